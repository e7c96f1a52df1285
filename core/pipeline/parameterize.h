#pragma once
/// The whole pipeline as one library call (DESIGN section 2): clean, cross field, cones merged
/// where the grid cannot separate them, cut, seamless solve (hat, vox or voxloc with its fallback
/// and local refinement), repeated while a solve still puts adjacent cones on one point, and the
/// quality figures. No file I/O: the caller reads the mesh (and an imported field) and writes what
/// it gets back. `seamvox param`, `seamvox field` and the benchmarks call these stages.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/cut/cut.h"
#include "core/field/cone_merge.h"
#include "core/field/features.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/mesh/clean.h"
#include "core/pipeline/components.h"
#include "core/pipeline/grid_spacing.h"
#include "core/quality/metrics.h"
#include "core/solve/param_solver.h"
#include "core/system/memory.h"
#include "core/refine/untangle.h"
#include "core/system/progress.h"

namespace seamvox {

/// Where the field comes from.
struct FieldSource {
  FieldMethod method = FieldMethod::Auto;
  double curvatureWeight = 0.0;  ///< > 0: curvature-aligned (direct field only)
  /// When not empty: an imported field, one vector per input face (before cleaning), projected
  /// on the cleaned faces; method and curvatureWeight are then unused.
  std::vector<Vec3d> importedPerInputFace;
  /// Corners of the cleaned mesh whose faces the direct field is held along (featureSideCorners);
  /// unused by the proxy field and an imported one.
  std::vector<CornerId> alignCorners;
  /// The map's edge length h (parameterize and `seamvox field` set it): with roughSpots, the
  /// computed field's surface is smoothed further at its rough spots within h
  /// (FieldGeometryOptions::roughSpotGrid). 0: no h, no rough spots.
  double gridLength = 0.0;
  /// The most vertices a rough spot's region may hold (FieldGeometryOptions::roughSpotMaxRegion):
  /// parameterize sets roughRegionBoundInMemory with its passHeadroomBytes. Unbounded by default.
  std::uint64_t roughSpotMaxRegion = ~std::uint64_t(0);
  /// Whether parameterize (and param out of core, and `seamvox field`) smooths the rough spots
  /// of the field's surface within h: the crumpled spots of a noisy scan otherwise put clusters
  /// of cone pairs into the field (camelhead x5 with noise: 333 cones before merging against
  /// the clean 31; bench/RESULTS.md, sessions 54-59). `--no-rough-spots` turns it off.
  bool roughSpots = true;
  /// Uniform Laplacian steps of the surface the computed field and its cones are read on
  /// (FieldGeometryOptions::smoothingIterations; 0: the mesh itself). More steps take the cone
  /// pairs of stronger noise off the field, at some cost in gradient error and map changes
  /// (`--field-smoothing`; bench/RESULTS.md, session 57).
  std::uint32_t smoothingSteps = kFieldSmoothingIterations;
};

/// The cross field of a cleaned mesh from its source; faceOrigin maps cleaned faces to input
/// faces (CleanResult::faceOrigin) for an imported field. Throws InputError for a field whose
/// size does not match inputFaces. The field solve's factor figures go to stats when set. The
/// mesh is unchanged on return (computeCrossField lends its positions array to the smoothed surface).
CrossField computeFieldFromSource(TriangleMesh& mesh, const Topology& topology,
                                  const std::vector<FaceId>& faceOrigin, std::uint32_t inputFaces,
                                  const FieldSource& source, const ProgressFn& progress = {},
                                  FieldSolveStats* stats = nullptr);

/// The source of a field that follows the feature curves: `source` with their side corners to align
/// to, when its field can (the direct field, not the proxy nor an imported one, and some curve).
std::optional<FieldSource> alignedFieldSource(const Topology& topology, const FeatureSet& features,
                                              const FieldSource& source, std::uint32_t numFaces);

/// Singularities of a field with close cones merged, and the cut through them.
struct ConeCut {
  FieldSingularities singularities;  ///< after merging
  CutResult cut;
  std::uint32_t conesBeforeMerge = 0;
  ConeMergeResult merged;  ///< both kinds of merges added up
};

/// computeSingularities, mergeCloseCones (cones at most mergeDistance apart, mesh units; <= 0
/// merges nothing), mergeCoincidentCones on `coincident` (pairs a previous solve put on one
/// point, joined along paths up to coincidentDistance), then cutToDisk. The field's smoothed
/// positions are released once read (computeSingularitiesReleasingFrames; restoreFramePositions
/// brings them back). With `reuse`: when it holds singularities they are taken instead of
/// computed (the smoothed positions are not read), when empty it is given the computed ones
/// (before merging).
ConeCut cutThroughCones(const TriangleMesh& mesh, const Topology& topology, CrossField& field,
                        double mergeDistance,
                        const std::vector<std::pair<VertexId, VertexId>>& coincident = {},
                        double coincidentDistance = 0.0, const ProgressFn& progress = {},
                        PackedSingularities* reuse = nullptr);

/// Somewhere the field's directions can wait while nothing reads them (a scratch file:
/// stream/scratch_direction_store.h).
class DirectionStore {
 public:
  virtual ~DirectionStore() = default;
  /// Takes the directions away (the vector is left empty, its memory freed).
  virtual void store(std::vector<Vec3f>& directions) = 0;
  /// Gives the stored directions back.
  virtual void load(std::vector<Vec3f>& directions) = 0;
};

/// PipelineOptions::closeHoles for a quad mesh: one-triangle holes of coarse scans span up to
/// about 2 spacings (the shared meshes' "split" damage, bench/RESULTS.md).
constexpr double kCloseHoleCells = 2.0;

struct PipelineOptions {
  CleanOptions clean;  ///< weld, tolerance (progress is set from below)
  FieldSource field;
  GridSpacing spacing;
  /// Cones closer than this many grid spacings are merged (kConeMergeFraction); 0 keeps them all
  /// and runs a single cone pass.
  double mergeCones = kConeMergeFraction;
  /// Holes whose boundary fits in a box of this many grid spacings (diagonal) carry no seam
  /// translation: the map extends over them and a quad mesh can close them (kCloseHoleCells for
  /// quads). They are capped in place for the field and the solve (capSmallHoles,
  /// fieldCappedHoles; without an imported field), and the loops no cap closes (through a vertex
  /// twice, flat caps) are held by constraints (ParamOptions::closeHolesWithin). 0: none closed,
  /// the default: the field turns freely at holes, and translations there let the map follow it
  /// more closely.
  double closeHoles = 0.0;
  /// With closeHoles: caps for the solve (false: constraints alone; tests).
  bool capHoles = true;
  /// Called with the solved map on the surface the solve saw (mesh.cornerUV set; small holes
  /// still capped) before the caps are taken off: `param --quads` extracts there, where the
  /// caps close the holes a quad mesh cannot keep open, with no copy of the map to fill them.
  std::function<void(const TriangleMesh& map, const Topology& topology)> withSolvedMap;
  /// Called once with the final mesh and map (PipelineResult::mesh as returned): on a thread of
  /// its own while the map's figures are measured when nothing after them changes the mesh (no
  /// unsolved component to drop) and the run may use more than one thread, else after them;
  /// parameterize waits for it and rethrows what it throws. `param` writes its output there, the
  /// file's copy overlapping the figures.
  std::function<void(const TriangleMesh& map)> withFinalMap;
  /// Cut-and-solve passes at most: another pass while a solve puts mergeable adjacent cones on
  /// one point, or leaves flipped faces at both of two close cones after the repair.
  std::uint32_t maxConePasses = 3;
  /// Cone pairs a solve put on one point, one of them ending a single seam, are merged in that
  /// pass's map (mergeConesInMap: a neighbourhood solved again) instead of starting another pass;
  /// other pairs still start one. In memory only. Off by default: faster, but on noisy armadillo
  /// x4 it left 352 flips next to the merged cone where the second pass left none
  /// (bench/RESULTS.md, session 56).
  bool mergeInMap = false;
  /// Memory a pass started after the repair may hold beyond the run's estimate: the earlier
  /// pass's map and cut wait meanwhile (about 24 bytes per face). Such a pass is not started when
  /// they would not fit (`param`: the budget less the estimate); unlimited by default.
  std::uint64_t passHeadroomBytes = ~std::uint64_t(0);
  /// Feature curves at faces the map collapses are released and the map solved again: the
  /// shortest curve per cluster of collapsed faces, at most this many times, then every curve at
  /// one once more (0: the constraints are kept whatever they collapse).
  std::uint32_t maxFeatureReleaseRounds = 8;
  /// Feature curves (boundaries; creases above featureAngle) the field follows and the map holds
  /// on integer iso-lines. Only the direct field follows them and only the hat solves hold them:
  /// with the proxy field no curve is aligned, with vox and voxloc those the map keeps by chance
  /// (PipelineResult::featureCurves counts them in the map either way).
  FeatureOptions features;
  SolverOptions solver;  ///< solver, grid resolution, refinement (its meter is set from below)
  bool greedyRounding = false;
  /// Foldover repair after the solve (core/refine/untangle): stiffening re-solves of patches
  /// around flipped faces, seams and integer translations kept. Stage "untangle".
  bool untangle = true;
  /// HatBasisOptions::coneWeightRadius of every hat solve (global, refinement, repair); 0: off.
  double coneWeightRadius = kConeWeightRadius;
  UntangleOptions untangleOptions;  ///< edgeLength and progress are set from below
  ProgressFn progress;  ///< every stage reports and may cancel (CancelledError) through it
  /// Stages are closed on this meter when given ("clean", "field", "cut", "basis" for the voxel
  /// solvers, "solve", "refine", "untangle", "metrics"), so a caller can add its own ("read", "write") on the same one.
  StageMeter* meter = nullptr;
  /// Components listed one by one in PipelineResult::components (the largest; the rest summed).
  std::uint32_t listComponents = 1000;
  /// Components the solve could not map are removed from the result's mesh instead of being
  /// kept at (u, v) = 0; their ids are in components.droppedIds.
  bool dropUnsolved = false;
  /// Test hook (RoundOptions::failsToFactor): components it names are left unsolved.
  std::function<bool(std::uint32_t unknowns)> failsToFactor;
  /// When set, the field's directions (12 bytes per face) wait in it while the voxel solvers
  /// build the map next to the basis (SolverOptions::fieldIdle), the stage of the largest peak.
  DirectionStore* directionStore = nullptr;
};

/// Sizes of a result's mesh and map, kept apart so they can be reported after the mesh was
/// handed to a consuming writer (writeMesh(AtomicFile&, TriangleMesh&&)).
struct MeshSize {
  std::uint32_t faces = 0, vertices = 0, wedges = 0;
  std::uint64_t mapBytes = 0;
  std::string attributes;           ///< VertexAttributes::describe() of the vertex properties
  std::uint64_t attributeBytes = 0;
};

struct PipelineResult {
  /// The cleaned mesh with the map in mesh.cornerUV (grid units, per wedge of the cut).
  TriangleMesh mesh;
  /// PipelineOptions::withFinalMap ran beside the map's figures (the "metrics" stage holds it).
  bool finalMapBesideMetrics = false;
  MeshSize size;            ///< of mesh as parameterize returned it
  Topology topology;        ///< of mesh
  CleanReport cleanReport;  ///< what cleaning changed
  std::uint32_t inputFaces = 0;
  std::string fieldMethod;  ///< "direct", "proxy" or "file"
  FieldSolveStats fieldSolve;  ///< the field's factorization (zero for an imported field)
  double edgeLength = 0.0, diagonal = 0.0;
  std::vector<VertexId> cones;   ///< of the kept pass's cut, sorted
  std::vector<std::int32_t> coneIndex4;  ///< index of each cone, quarter turns
  std::uint32_t seams = 0;       ///< seam curves of the kept pass's cut
  std::uint32_t conesBeforeMerge = 0;  ///< of the first pass
  ConeMergeResult merged;        ///< of the kept pass (each merges the field's cones afresh)
  std::uint32_t conePasses = 0;
  /// The pass whose map is the result (1-based): a pass started after the repair because flips
  /// stayed at close cones is kept only when it ends with fewer flips; else the earlier one.
  std::uint32_t conePassKept = 0;
  /// Per pass that ran the whole repair, the faces it left flipped (UntangleStats::flippedAfter).
  std::vector<std::uint64_t> conePassFlips;
  /// A pass after the repair was due but not started: the earlier pass's map and cut would not
  /// fit PipelineOptions::passHeadroomBytes.
  bool conePassSkippedForMemory = false;
  /// Cone pairs a solve put on one point that were merged in its pass's map (mergeConesInMap,
  /// PipelineOptions::mergeInMap), summed over the passes.
  std::uint32_t conesMergedInMap = 0;
  /// Small holes capped for the field and the solve (PipelineOptions::closeHoles), not in the
  /// output.
  std::uint32_t fieldCappedHoles = 0;
  SolverResult solved;           ///< figures of the last solve (its map moved to mesh.cornerUV)
  bool untangled = false;        ///< the foldover repair ran
  UntangleStats untangle;
  FeatureSet features;              ///< of the cleaned mesh (before any drop)
  double featureAngle = 0.0;         ///< the crease angle used (0: none)
  bool featureAngleAuto = false;     ///< chosen by FeatureOptions::autoFeatureAngle (a CAD-like mesh)
  bool featureFieldAligned = false;  ///< the field was held along them (direct field)
  LineConstraintStats featureLines;  ///< the map's constraints (last hat solve; zero otherwise)
  FeatureAlignment featureCurves;    ///< curves the final map keeps on integer iso-lines
  /// Curves left out of the map's constraints because the map collapsed triangles next to them
  /// (two curves rounded onto one iso-line squeeze the faces between them); counted in notAligned.
  std::uint32_t featureCurvesReleased = 0;
  SeamQuality seamQuality;
  MapQuality mapQuality;
  ComponentSummary components;  ///< per component, of the mesh before any drop
  bool isSeamless() const { return seamQuality.isSeamless(); }
};

/// Runs the whole pipeline on a raw mesh (consumed). Throws InputError (an empty or flat mesh,
/// a field of the wrong size), TopologyError, SolverError, CancelledError. Memory: about 80
/// bytes per face at the peak (bench/RESULTS.md).
PipelineResult parameterize(TriangleMesh raw, const PipelineOptions& options);

}  // namespace seamvox
