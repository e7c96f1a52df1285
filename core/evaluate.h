#pragma once
/// Evaluation of the map at the corners of the cut mesh (DESIGN section 9, step 4).
#include <complex>
#include <vector>

#include "basis.h"
#include "reduce.h"

namespace seamvox {

/// (u, v) in grid units at every corner (3 #F) for the reduced unknowns x: coefficients
/// P x + offset, then the basis evaluated at each corner. Corners outside the basis keep the
/// values already in cornerUV (pass an empty vector to start from zeros).
void evaluateMap(const Basis& basis, const Reduction& reduction,
                 const std::vector<std::complex<double>>& unknowns, std::vector<Vec2d>& cornerUV);

}  // namespace seamvox
