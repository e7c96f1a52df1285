#pragma once
/// Map coordinates held on integer iso-lines (feature curves, core/field/features.h): a
/// constraint "coordinate u (or v) of one domain's coefficient equals an integer shared by a
/// group" is real-linear, not complex-linear, so the seamless system is solved in its real form
/// [Re K -Im K; Im K Re K] with the constrained coordinates eliminated: each is +-(one integer
/// unknown per class of linked groups) + a constant of the fixed unknowns. Solved with the integers
/// free, rounded, solved again with them fixed.
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/reduce.h"
#include "core/solve/assemble.h"

namespace seamvox {

/// Coordinate `axis` (0: u = Re, 1: v = Im) of domain `domain`'s coefficient equals the integer
/// unknown of `group` (numbered from 0; constraints sharing a vertex link their groups).
struct LineConstraint {
  std::uint32_t domain = 0;
  std::uint8_t axis = 0;
  std::uint32_t group = 0;
};

struct LineConstraintStats {
  std::uint32_t constraints = 0;  ///< given
  std::uint32_t applied = 0;      ///< held exactly by the solve
  /// Left out: their domain's coefficient is not one unknown times a unit of Z[i] plus fixed
  /// unknowns (e.g. a voxel basis), or they contradict the constraints before them (a curve
  /// through a cone at a half-integer point, a loop whose seams shift it by an integer).
  std::uint32_t unsupported = 0, conflicting = 0;
  std::uint32_t integerUnknowns = 0;  ///< free integers after linking
  double maxRoundingShift = 0.0;      ///< largest |c - round(c)| of the integers after the first solve
};

/// Minimises x* K x - 2 Re(x* rhs) over the unknowns not in `fixed` (x holds the fixed values and
/// receives the others) with the line constraints held exactly. Throws SolverError when the real
/// system cannot be factored.
void solveWithLineConstraints(const LinearSystem& system, const Reduction& reduction,
                              const std::vector<std::uint8_t>& fixed, std::vector<std::complex<double>>& x,
                              const std::vector<LineConstraint>& lines, LineConstraintStats& stats);

}  // namespace seamvox
