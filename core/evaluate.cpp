#include "core/evaluate.h"

namespace seamvox {

void evaluateMap(const Basis& basis, const Reduction& reduction,
                 const std::vector<std::complex<double>>& unknowns, std::vector<Vec2d>& cornerUV) {
  basis.evaluateCorners(expandCoefficients(reduction, unknowns), cornerUV);
}

}  // namespace seamvox
