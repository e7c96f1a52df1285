#pragma once
/// Reduction of a basis to one that satisfies every seam constraint by construction
/// (DESIGN section 7): per basis function a BFS over its domains gives c_j = R_j c_0 + T_j . t;
/// cycles give translation constraints or determine c_0 (at cones); the translation constraints
/// are eliminated over Z[i] (t = U s); the result is the sparse complex map P from reduced
/// unknowns (free positional c_0's, then s) to domain (element-function) coefficients.
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/basis.h"
#include "core/basis/gaussian_int.h"
#include "core/system/progress.h"

namespace seamvox {

struct ReduceOptions {
  /// Translation constraints (rows over seams) to use instead of the basis' own cycle
  /// constraints (DESIGN section 7: the voxel basis takes the hat basis' set). The basis' own
  /// cycles are then checked against them; violating basis functions are marked inconsistent.
  const std::vector<GaussVector>* translationConstraints = nullptr;
  /// Further constraints on t kept in either case, e.g. the loops of small holes
  /// (smallHoleConstraints, hole_loops.h); the basis' own cycles are checked against them too.
  const std::vector<GaussVector>* extraConstraints = nullptr;
  /// #basis functions or null: a flagged function whose c_0 its seams determine (a cone) is put on
  /// a Gaussian integer, an integer point of the map, through one more translational unknown
  /// (alpha g = beta . t with g in Z[i]): feature curves meeting at a cone stay on integer lines.
  const std::vector<std::uint8_t>* integerPoints = nullptr;
  ProgressFn progress;
};

/// P as compressed rows: coefficient of domain d = sum over k in [rowStart[d], rowStart[d+1])
/// of value[k] * x[column[k]] + offset[d] (offset empty = zero; locked coefficients).
struct ReducedMap {
  std::vector<std::uint64_t> rowStart;  ///< #domains + 1
  std::vector<std::uint32_t> column;
  std::vector<std::complex<double>> value;
  std::vector<std::complex<double>> offset;  ///< #domains or empty
};

struct Reduction {
  std::uint32_t numPositional = 0;     ///< unknowns 0 .. numPositional-1: free c_0's
  std::uint32_t numTranslational = 0;  ///< unknowns numPositional ..: the free s
  std::uint32_t numUnknowns() const { return numPositional + numTranslational; }
  ReducedMap map;
  /// Per basis function: its positional unknown, or kInvalidId when c_0 is determined.
  std::vector<std::uint32_t> basisPositional;
  /// Per seam: t_seam = sum value * s_column (t = U s; columns count from 0 among the s).
  std::vector<GaussVector> seamTranslation;
  /// The translation constraints found from the basis' own cycles (rows over seams).
  std::vector<GaussVector> cycleConstraints;
  /// Basis functions whose c_0 is fixed by the seams around them (cones).
  std::vector<std::uint32_t> determinedBasis;
  /// Basis functions whose own cycle constraints are not implied (only with given constraints).
  std::vector<std::uint32_t> inconsistentBasis;
  std::uint32_t nonUnitConstraints = 0;  ///< constraints needing Euclid steps
  /// Free translations fixed at s = 0 because their column of P is parallel to another's: they
  /// only move seams no basis adjacency crosses, so the energy cannot see them (voxel bases).
  std::uint32_t invisibleTranslations = 0;
  /// Connected components of the surface (through elements), per unknown and per seam.
  std::uint32_t numComponents = 0;
  std::vector<std::uint32_t> unknownComponent;  ///< #unknowns
  /// Per component: some seam has r != 1 (then fixed translations pin the global shift).
  std::vector<std::uint8_t> componentHasRotation;
};

/// Builds the reduction of a basis. Linear in the number of domains plus the cost of the
/// elimination (small: one constraint per seam node). Deterministic.
Reduction reduceBasis(const Basis& basis, const ReduceOptions& options = {});

/// Coefficients of every domain for the reduced unknowns x (P x + offset).
std::vector<std::complex<double>> expandCoefficients(const Reduction& reduction,
                                                     const std::vector<std::complex<double>>& x);

/// Translation t of every seam for the given s values (numTranslational entries).
std::vector<std::complex<double>> seamTranslations(const Reduction& reduction,
                                                   const std::vector<std::complex<double>>& s);

}  // namespace seamvox
