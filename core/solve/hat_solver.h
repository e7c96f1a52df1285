#pragma once
/// The hat-basis seamless parameterization of a cut mesh: basis, reduction, assembly, solves,
/// rounding and evaluation in one call (DESIGN sections 6-9).
#include <functional>
#include <vector>

#include "core/basis/gaussian_int.h"

#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/basis/basis.h"
#include "core/system/progress.h"
#include "core/solve/seamless_solve.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct ParamOptions {
  double edgeLength = 1.0;  ///< h, target grid spacing in mesh units (> 0)
  bool greedyRounding = false;
  /// HatBasisOptions::coneWeightRadius of the hat solves (global, and local in refinement).
  double coneWeightRadius = kConeWeightRadius;
  ProgressFn progress;
  std::function<bool(std::uint32_t unknowns)> failsToFactor;  ///< test hook (RoundOptions)
  /// Called by the voxel solver once its basis is built (the pipeline closes a "basis" stage).
  std::function<void()> basisBuilt;
};

struct ParamResult {
  WedgeMap cornerUV;  ///< 3 #F corners on the cut's wedges, (u, v) in grid units
  std::vector<std::complex<double>> translations;  ///< t per seam
  SeamlessStats stats;
  std::uint32_t basisFunctions = 0, domains = 0, seamAdjacencies = 0;
  std::uint32_t translationConstraints = 0;  ///< cycle constraints found
  /// Faces (sorted) of the components the solve left unsolved (mapped to the point 0) and of
  /// those it anchored through a translation (SeamlessSolution).
  std::vector<FaceId> unsolvedFaces, anchoredFaces;
  double secondsBasis = 0.0, secondsReduce = 0.0, secondsEvaluate = 0.0;
};

/// Seamless map of a mesh cut to a disk per component (cutToDisk), following the combed field.
/// Throws InputError for mismatched sizes, SolverError when a factorization fails.
ParamResult parameterizeMesh(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const ParamOptions& options = {});

/// Stores a solved seamless system in out: its stats and translations, and the map evaluated
/// once per wedge of the cut (timed as secondsEvaluate). Shared by the hat and voxel solvers.
void storeSeamlessSolution(const Basis& basis, const Reduction& reduction, SeamlessSolution solution,
                           const Topology& topology, const CutResult& cut, ParamResult& out);

/// The translation constraints of the hat basis (Reduction::cycleConstraints, DESIGN section 7)
/// from a hat basis built only on the faces around seam vertices: cycles of seam crossings only
/// close around those vertices, so the constraints span the same lattice as a whole-mesh
/// reduction at a cost that follows the seams, not the mesh. Empty when there are no seams.
std::vector<GaussVector> seamCycleConstraints(const TriangleMesh& mesh, const Topology& topology,
                                              const CrossField& field, const CutResult& cut,
                                              double edgeLength);

}  // namespace seamvox
