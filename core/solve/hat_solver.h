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
  /// Test hook (vox): run before each voxel seamless solve (the first, and the second with more
  /// B-splines joined); a SolverError it throws takes the path of a system that cannot be factored.
  std::function<void()> beforeVoxelSolve;
  /// Called by the voxel solver once its basis is built (the pipeline closes a "basis" stage).
  std::function<void()> basisBuilt;
  /// When set: corners on either side of feature edges (featureSideCorners, features.h) whose
  /// normal coordinate the map holds on an integer (featureLineConstraints).
  const std::vector<CornerId>* featureCorners = nullptr;
  /// Boundary loops within this extent (mesh units; 0: none) carry no seam translation, so the
  /// map extends over the hole (smallHoleConstraints, hole_loops.h). The pipeline passes h.
  double closeHolesWithin = 0.0;
  /// Voxel solvers: the map re-evaluated at the smoothed surface at the vertices of the faces it
  /// folds (smoothed_evaluation.h).
  bool smoothedEvaluation = true;
  /// Vertices smoothed and evaluated at once by that pass (0: kSmoothedBatchVertices). The map
  /// does not depend on it; tests set a few to cover the batches.
  std::size_t smoothedBatchVertices = 0;
  /// The map keeps its wedge ids per vertex over the topology's triangles (buildCutWedges'
  /// viewTriangles: 8 bytes per face less), which must then outlive it unchanged (the pipeline's
  /// mesh and topology do).
  bool mapViewsTriangles = false;
};

struct ParamResult {
  WedgeMap cornerUV;  ///< 3 #F corners on the cut's wedges, (u, v) in grid units
  std::vector<std::complex<double>> translations;  ///< t per seam
  SeamlessStats stats;
  std::uint32_t basisFunctions = 0, domains = 0, seamAdjacencies = 0;
  std::uint32_t translationConstraints = 0;  ///< cycle constraints found
  /// Boundary loops within ParamOptions::closeHolesWithin, and of them those closed (no net
  /// translation: the constraint held or was added) and those left open by a net rotation.
  std::uint32_t smallHoles = 0, smallHolesRotated = 0;
  /// Faces (sorted) of the components the solve left unsolved (mapped to the point 0) and of
  /// those it anchored through a translation (SeamlessSolution).
  std::vector<FaceId> unsolvedFaces, anchoredFaces;
  double secondsBasis = 0.0, secondsReduce = 0.0, secondsEvaluate = 0.0;
  LineConstraintStats lines;  ///< the feature constraints (ParamOptions::featureCorners)
};

/// Seamless map of a mesh cut to a disk per component (cutToDisk), following the combed field.
/// Throws InputError for mismatched sizes, SolverError when a factorization fails.
ParamResult parameterizeMesh(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const ParamOptions& options = {});

/// Largest angle (degrees) between a feature edge and the nearest combed axis of its face for
/// which the map holds the edge on an iso-line (the aligned field is within float precision).
constexpr double kFeatureAxisDegrees = 10.0;

/// The line constraints of feature edges in the hat basis: per side corner s (group = its index),
/// at both ends of its edge in face(s), the coordinate normal to the edge (v when the edge runs
/// along the combed direction, u when along its quarter turn). Edges farther than
/// kFeatureAxisDegrees from both axes are left out.
std::vector<LineConstraint> featureLineConstraints(const TriangleMesh& mesh, const CrossField& field,
                                                   const CutResult& cut, const HatBasis& basis,
                                                   const std::vector<CornerId>& sideCorners);

/// Per basis function of a hat basis: whether its vertex is a cone on a feature edge (sideCorners),
/// which the map puts on an integer point (ReduceOptions::integerPoints): else the curves through
/// it could only pass where its seams put it, a half-integer point for many cones.
std::vector<std::uint8_t> conesOnFeatures(const Topology& topology, const CutResult& cut, const HatBasis& basis,
                                          const std::vector<CornerId>& sideCorners);

/// Stores a solved seamless system in out: its stats and translations, and the map evaluated
/// once per wedge of the cut (timed as secondsEvaluate; viewTriangles as buildCutWedges'). Shared
/// by the hat and voxel solvers.
void storeSeamlessSolution(const Basis& basis, const Reduction& reduction, SeamlessSolution solution,
                           const Topology& topology, const CutResult& cut, ParamResult& out,
                           bool viewTriangles = false);

/// The small-hole constraints of ParamOptions::closeHolesWithin (empty when 0), their counts
/// stored in out.
std::vector<GaussVector> closeSmallHoles(const TriangleMesh& mesh, const Topology& topology,
                                         const CutResult& cut, const ParamOptions& options,
                                         ParamResult& out);

/// The translation constraints of the hat basis (Reduction::cycleConstraints, DESIGN section 7)
/// from a hat basis built only on the faces around seam vertices: cycles of seam crossings only
/// close around those vertices, so the constraints span the same lattice as a whole-mesh
/// reduction at a cost that follows the seams, not the mesh. Empty when there are no seams.
std::vector<GaussVector> seamCycleConstraints(const TriangleMesh& mesh, const Topology& topology,
                                              const CrossField& field, const CutResult& cut,
                                              double edgeLength);

}  // namespace seamvox
