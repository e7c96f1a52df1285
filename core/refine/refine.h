#pragma once
/// Local refinement of a seamless map in the hat basis near cones: the "HatLoc" half of the
/// Vox+HatLoc solver (DESIGN section 10). A region of triangles (marked faces, triangles the input
/// map collapsed or flipped, plus rings of neighbours) is cut out as a mesh of its own; vertices
/// whose triangles all lie in the region are re-solved with the seam translations fixed, every
/// other vertex keeps the input map's values (per wedge) and enters the right-hand side.
///
/// Rounds: the locked border keeps the input map, which may itself be damaged just outside the
/// first region. After each solve the region's faces are measured again; a face still collapsed
/// (below collapseThreshold) or flipped that touches a locked vertex seeds a patch: those faces
/// and rings around them (rings double each round), solved on their own with everything around
/// locked to the map as refined so far, up to maxRounds solves. (Re-solving the whole grown region
/// instead cost as much as the first solve per round: 26 of a 54 s run on 9.2M faces.)
/// A further solve runs only while it pays: while a border face is collapsed but not flipped, or
/// while the border at least halves from one round to the next (flips that persist at the border
/// are the map's own near cones; a 22M-face armadillo spent 3 extra solves on 32 of 8174 flips).
/// Faces whose vertices are all free are not grown around: the local hat solve is exact for its
/// border, and what remains there is the hat map's own damage (on the shared meshes: flips of
/// triangles touching a cone, as many as the hat solver's up to how the translations round).
/// Faces between two coincident cones (metrics.h collapsesBetweenCones) are not grown around
/// either: the cones' positions follow from the rounded translations, no free vertex moves them.
/// On the shared meshes these are the only collapsed faces left, in the hat map as well.
#include <complex>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/basis/basis.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct RefineOptions {
  double edgeLength = 1.0;  ///< h, as in the map being refined (> 0)
  /// Faces to refine whatever the map looks like there (e.g. VoxelParamResult::markedFaces).
  std::vector<FaceId> markedFaces;
  /// Those of them that are islands mapped whole (islands.h; increasing): their vertices are
  /// counted apart (RefineStats::islandVertices), not as refinement near cones.
  std::vector<FaceId> islandFaces;
  /// A face whose signed parameter-space area is below this fraction of its expected area
  /// A_T / h^2 is added to the region (collapsed; negative area = flipped is always added).
  double collapseThreshold = 0.1;
  /// Collapsed and flipped faces of the map seed the region too (voxloc). false: markedFaces
  /// alone (vox repairs only where its basis could not keep the seams).
  bool seedFromMap = true;
  /// Rings of neighbouring faces (sharing a vertex) added around the region, and around the
  /// faces that grow it in later rounds (at least one ring there).
  std::uint32_t rings = 1;
  /// Solves at most (>= 1; 1: no re-detection).
  std::uint32_t maxRounds = 6;
  double coneWeightRadius = kConeWeightRadius;  ///< of the local hat solves (HatBasisOptions)
  /// The global solve's ParamOptions::closeHolesWithin (mesh units; 0: no hole held, solveRegion).
  double closeHolesWithin = 0.0;
  /// > 0 (mesh units): the first round solves its region in trilinear B-splines of this spacing
  /// (spline_space.h), with an unknown per vertex only next to cones, instead of one unknown per
  /// vertex; the next rounds re-solve in the hat basis the faces it leaves collapsed or flipped
  /// (collapsed only with flipsToRepair), with rings around them. 0: every round in the hat
  /// basis. Needs maxRounds >= 2 and seedFromMap.
  double splineSpacing = 0.0;
  /// B-splines per voxel edge for the voxloc solvers, which set splineSpacing to the voxel size
  /// divided by it; 0: off. The default 4 refines 0.5% of armadillo x4's vertices in the hat
  /// basis against 6.2% without it (bench/RESULTS.md, sessions 28, 32 and 36).
  std::uint32_t splineCells = 4;
  /// A group of the spline round is solved in the hat basis instead when the B-splines and own
  /// unknowns are not fewer than this fraction of its free vertices (solveRegionInSplines). At a
  /// quarter, most groups of noisy fertility x5 (9.2M faces) went to the hat basis: 2.85% of the
  /// vertices refined there against 0.25% at a half, in the same time (bench/RESULTS.md, session 36).
  double splineMaxFraction = 0.5;
  /// The foldover repair runs after the refinement (ParamOptions::untangle): the faces the spline
  /// round leaves flipped in its groups solved in B-splines go to it, and only collapsed ones (and
  /// islands) seed the hat rounds there; a group solved per vertex seeds as before. A
  /// local hat solve turns a collapse near a cone into a proper map; a flip of a triangle that
  /// noise folded stays flipped under any smooth map, and the repair unfolds it with fewer free
  /// vertices (noisy armadillo x4: 1.24% -> 0.68% of the vertices in hat rounds, same repair time).
  bool flipsToRepair = false;
  /// A round's region is solved in groups of whole components of at least this many faces
  /// (splitRegion), in parallel: a group's factor stays near 40 MB at the default.
  std::size_t groupFaces = std::size_t(1) << 15;
  /// Test hook: a group whose first face it returns true for fails its solve as an indefinite
  /// system would (RefineStats::failedSolves).
  std::function<bool(FaceId firstFace)> groupFails;
  /// RefineResult::regionFaces lists the faces solved, and the after-figures (collapsedAfter,
  /// flippedAfter) count only them: for a caller that knows the rest of the map's faces.
  bool regionOnly = false;
  /// RefineResult::regionFaces lists the faces solved also without regionOnly (the figures still
  /// the whole map's): with seedFromMap, a caller learns which faces may be flipped
  /// (SolverResult::flipCandidates).
  bool listRegionFaces = false;
  ProgressFn progress;
};

/// Whether the first region holds every face the map flips or collapses: seeded from the whole
/// map at a threshold at or above the collapse fraction. After the rounds no other face is
/// flipped (the faces outside keep their values), so the figures skip them and a caller may
/// take the faces solved as the only ones to repair (RefineOptions::listRegionFaces).
bool regionHoldsEveryFlip(const RefineOptions& options);

/// One solve of the (grown) region.
struct RefineRound {
  /// Solved in the B-splines of RefineOptions::splineSpacing (unknowns: their coefficients).
  bool spline = false;
  /// Faces the region grew around: round 0 the input's marked, collapsed and flipped faces; later
  /// rounds the previous round's borderFaces.
  std::uint64_t seedFaces = 0;
  std::uint64_t regionFaces = 0;
  std::uint32_t freeVertices = 0;
  std::uint32_t unknowns = 0;
  /// The region's faces after this solve, by MapQuality's criteria (metrics.h).
  std::uint64_t collapsed = 0, collapsedAtCones = 0, flipped = 0;
  /// Region faces after this solve below collapseThreshold or flipped, touching a locked vertex
  /// and not between coincident cones: the next round's seeds.
  std::uint64_t borderFaces = 0;
  double seconds = 0.0;
};

/// Figures over all rounds unless said otherwise.
struct RefineStats {
  std::uint64_t markedFaces = 0, collapsedFaces = 0, flippedFaces = 0;  ///< found in the input
  std::uint64_t regionFaces = 0;   ///< faces solved in some round
  std::uint32_t freeVertices = 0;  ///< vertices re-solved in some round (all their faces in it)
  std::uint32_t lockedVertices = 0;  ///< other vertices of those faces, kept at the input values
  double refinedVertexFraction = 0.0;  ///< freeVertices / #V
  /// Vertices of RefineOptions::islandFaces (all of them free: an island is solved whole), and
  /// the free vertices off the islands / #V: the refinement near cones and folds.
  std::uint32_t islandVertices = 0;
  double refinedFractionOffIslands = 0.0;
  /// Vertices only the spline round moved (free there, in no hat round: not in freeVertices),
  /// and their fraction of #V.
  std::uint32_t splineVertices = 0;
  double splineVertexFraction = 0.0;
  /// Each round solves its region in groups of whole components (splitRegion), each on its own.
  std::uint32_t solves = 0;          ///< group solves over all rounds
  /// Batches of groups solved and recorded at once, over all rounds (one per round in memory;
  /// out of core a batch holds at most a share of the memory in solved corners).
  std::uint32_t batches = 0;
  std::uint64_t totalUnknowns = 0;   ///< unknowns summed over the groups of the largest round
  /// System figures (unknowns to factorPeakBytes) of the largest group solve.
  std::uint32_t unknowns = 0;  ///< size of the local system
  /// Translation unknowns solved locally: seams among free vertices only, e.g. between two cones
  /// (their input t is not trusted; rounded to Gaussian integers and solved again).
  std::uint32_t freeTranslations = 0;
  std::uint32_t pinned = 0;    ///< region components without any locked vertex or rotation
  std::uint64_t systemNonzeros = 0, factorNonzeros = 0, factorBytes = 0, factorPeakBytes = 0;
  double secondsRegion = 0.0, secondsExtract = 0.0, secondsSolve = 0.0, secondsTotal = 0.0;  ///< all rounds
  std::vector<RefineRound> rounds;  ///< empty when the region is empty
  /// The whole refined map by MapQuality's criteria (metrics.h), cones from the cut: what
  /// measureMap(mesh, refined, field, h, &cut.cones) counts.
  std::uint64_t collapsedAfter = 0, collapsedAtConesAfter = 0, flippedAfter = 0;
  /// Last round's borderFaces: 0 unless maxRounds ran out or the rounds stopped paying (only
  /// flipped faces left at the border, and no fewer than half as many as the round before).
  std::uint64_t unresolvedFaces = 0;
  /// Group solves whose system could not be factored (zero-area and needle faces can make a
  /// region's hat system indefinite): the group keeps its input map; the first one's message.
  std::uint32_t failedSolves = 0;
  std::string failedSolveReason;
};

/// How a face's parameterAreaRatio seeds the refinement region: collapsed below the threshold,
/// flipped when negative; a NaN ratio (a zero-area face, no energy) does not.
enum class RefineSeed : std::uint8_t { None, Collapsed, Flipped };
RefineSeed classifyRefineSeed(double ratio, double threshold);
/// selectRefineRegion's counts (marked, collapsed, flipped and region faces) into stats, when given.
void copyRegionCounts(const RefineStats& counts, RefineStats* stats);

/// A corner a refinement solved: its whole-mesh id and value; free when its vertex was free in
/// some solve (a RefineResult holds only those).
struct RefinedCorner {
  Vec2d uv = Vec2d::Zero();
  CornerId corner = 0;
  bool free = false;  // 24 bytes with the value first
  bool spline = false;  ///< free only in the spline round (not a hat-refined vertex)
};

/// New (u, v) of the corners of the free vertices, sorted by corner. Every other corner keeps the
/// input value exactly. Seams whose translation was re-solved (all their edges among free
/// vertices) get seamT[k] for seam seams[k].
struct RefineResult {
  std::vector<RefinedCorner> corners;
  std::vector<std::uint32_t> seams;
  std::vector<std::complex<double>> seamT;
  RefineStats stats;
  /// Faces solved in some round, increasing (RefineOptions::regionOnly, listRegionFaces).
  std::vector<FaceId> regionFaces;
};

/// The region's triangles as a mesh of their own, with index maps back to the whole mesh. Sub
/// face i is whole face faceOrigin[i] with its corners in the same order (sub corner 3 i + k is
/// whole corner 3 faceOrigin[i] + k). A locked vertex whose region faces form several fans gets
/// one sub vertex per fan, so the sub mesh is manifold; a free vertex keeps its whole fan. The
/// cut keeps the seam edges with both faces in the region (local seam ids, seamOrigin maps back);
/// region-border edges are boundary edges.
struct RegionMesh {
  TriangleMesh mesh;
  Topology topology;
  CrossField field;
  CutResult cut;
  std::vector<FaceId> faceOrigin;          ///< #sub faces, increasing
  std::vector<VertexId> vertexOrigin;      ///< #sub vertices
  std::vector<std::uint8_t> vertexFree;    ///< #sub vertices: all its whole-mesh faces are here
  std::vector<std::uint32_t> seamOrigin;   ///< #local seams
};

/// Faces within `rings` vertex rings of the seeds (the seeds included). Sorted, unique. Cost: the
/// patch's size times the valence. It stops early, with more than maxFaces faces, at the first
/// ring that takes it past maxFaces (for a caller that refuses so large a patch).
std::vector<FaceId> growFaces(const Topology& topology, std::vector<FaceId> seeds, std::uint32_t rings,
                              std::size_t maxFaces = std::numeric_limits<std::size_t>::max());

/// The faces (sorted, unique) as groups of whole components (faces sharing a vertex belong to one
/// component): a group closes once it holds groupFaces faces, so each is solved on its own with
/// bounded memory and the groups run in parallel. Groups in the order of their first face, each
/// sorted. Cost: a sort of 3 ids per face.
std::vector<std::vector<FaceId>> splitRegion(const Topology& topology, const std::vector<FaceId>& faces,
                                             std::size_t groupFaces);

/// Faces to refine: marked faces, faces whose input parameter area is below the collapse
/// threshold or negative, then options.rings rings of neighbours. Sorted, unique. Linear in #F
/// (one pass over the map) plus the region's size times the valence.
std::vector<FaceId> selectRefineRegion(const TriangleMesh& mesh, const Topology& topology,
                                       const WedgeMap& cornerUV,
                                       const RefineOptions& options, RefineStats* stats = nullptr);

/// Cuts the given faces (sorted, unique) out of the mesh. Cost: the region's size times the
/// valence; no per-face array of the whole mesh. Throws InputError on bad sizes or ids.
RegionMesh extractRegion(const TriangleMesh& mesh, const Topology& topology,
                         const CrossField& field, const CutResult& cut,
                         const std::vector<FaceId>& regionFaces);
/// extractRegion, then on the surface the field was computed on (placeRegionOnSurface) when it
/// was a smoothed one: framePositionsAt the region's vertices. What the refinement's and the
/// repair's local solves work on.
RegionMesh extractRegionOnFieldSurface(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                       const CutResult& cut, const std::vector<FaceId>& regionFaces);

/// The whole map's corner values on a region's faces (their own corners, region face order) and
/// the translations of the region's seams (seamOrigin): what a local solve of the region starts
/// from.
WedgeMap regionCornerValues(const RegionMesh& region, const WedgeMap& cornerUV);
std::vector<std::complex<double>> regionTranslations(const RegionMesh& region,
                                                     const std::vector<std::complex<double>>& seamT);

/// Moves a region onto the surface its field was computed on: positions become `surface` (one
/// per sub vertex, vertexOrigin order) and each face's direction is turned onto the face there
/// by rotateBetween their normals, as computeSingularities reads the field (a face of zero area
/// on either surface keeps its direction). A local solve then measures the map on the smooth
/// surface: on a noisy scan the faces the noise folds in 3D are not folded there, so the solve
/// does not flip them as it would following their own frames. The written mesh keeps its own
/// positions; only the region's solve sees these.
void placeRegionOnSurface(RegionMesh& region, std::vector<Vec3f> surface);

/// The region's corner values (3 #sub faces) and translations (per local seam) after the solve.
struct RegionSolution {
  WedgeMap cornerUV;  ///< on the region's cut wedges
  std::vector<std::complex<double>> seamT;
  /// solveRegionInSplines solved in the B-splines (false: they were too many, and it solved in
  /// the hat basis instead).
  bool inSplines = false;
};

/// Re-solves the free vertices of a region in the hat basis (DESIGN section 10): locked wedges
/// fixed to the given corner values (3 #sub faces, the input map on the region) and moved to the
/// right-hand side; translations fixed to seamT (per local seam) except on seams among free
/// vertices only, which are solved, rounded to Gaussian integers and solved again (solveSeamless).
/// Locked corners keep their input values exactly. faceWeight (#sub faces or empty) scales each
/// face's energy, and so does HatBasisOptions::coneWeightRadius around the region's cones.
/// keepTranslations fixes every seam's translation (the foldover repair: re-rounding a seam between
/// two cones in the region can put them on one point). closeHolesWithin > 0: the loop translations
/// of the holes within it that the region holds whole stay as the input has them, as
/// ParamOptions::closeHolesWithin holds them closed in the global solve (pass the global solve's
/// value; 0: solved with the seams). firstOrder (in and out, RoundOptions::firstOrder): the
/// elimination order of an earlier solve of the same region with the same flags, other weights
/// (the same pattern), so this one skips the ordering. Throws SolverError when a factorization
/// fails.
RegionSolution solveRegion(const RegionMesh& region, const WedgeMap& cornerUV,
                           const std::vector<std::complex<double>>& seamT, double edgeLength,
                           RefineStats* stats = nullptr,
                           const std::vector<double>& faceWeight = {}, double coneWeightRadius = 0.0,
                           bool keepTranslations = false, double closeHolesWithin = 0.0,
                           std::vector<std::uint32_t>* firstOrder = nullptr);

/// solveRegion repeated on one region with other face weights (the foldover repair's stiffened
/// solves): the hat basis, its reduction, each kind of local system (translations solved or kept)
/// and its assembly at weight 1 are built once; a solve assembles only the faces whose weight is
/// not 1, scaled by weight - 1, adds them, and factors in the elimination order of the kind's
/// first solve. The same map as solveRegion with those weights, up to rounding. Holds
/// references: the region and cornerUV must outlive it. Throws as solveRegion does.
class RegionStiffener {
 public:
  RegionStiffener(const RegionMesh& region, const WedgeMap& cornerUV, const std::vector<std::complex<double>>& seamT,
                  double edgeLength, double coneWeightRadius = 0.0, double closeHolesWithin = 0.0);
  ~RegionStiffener();
  RegionStiffener(const RegionStiffener&) = delete;
  RegionStiffener& operator=(const RegionStiffener&) = delete;
  /// faceWeight: #sub faces, or empty for all 1.
  RegionSolution solve(const std::vector<double>& faceWeight, bool keepTranslations, RefineStats* stats = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// solveRegion with its translations kept, in the trilinear B-splines of the given spacing (mesh
/// units) sampled at the region's vertices (core/refine/spline_space.h) instead of one unknown per
/// free vertex: a few coefficients per cell, and near cones, where the B-splines would not keep
/// the seams, an unknown per vertex (ownUnknown gets those vertices, per region vertex). When its
/// unknowns are not fewer than maxColumnFraction of the free vertices (cells too fine for the
/// mesh, or cones too close together), solves as solveRegion does (inSplines false). Throws
/// SolverError when the factorization fails.
RegionSolution solveRegionInSplines(const RegionMesh& region, const WedgeMap& cornerUV,
                                    const std::vector<std::complex<double>>& seamT, double edgeLength,
                                    double spacing, double coneWeightRadius, std::vector<std::uint8_t>& ownUnknown,
                                    RefineStats* stats = nullptr, double maxColumnFraction = 0.25,
                                    double closeHolesWithin = 0.0);

/// The cut's cones as an increasing list (duplicates dropped). InputError for a cone at or above
/// numVertices.
std::vector<VertexId> listedCones(const std::vector<VertexId>& cones, std::uint64_t numVertices);

/// The whole stage: select, extract, solve, re-detect and grow (rounds, above). cornerUV is the
/// input map (3 #F), seamT its rounded translation per seam of cut (Gaussian integers). Holds the
/// region and, while it selects the first region, one byte per face. Throws InputError on bad
/// sizes.
RefineResult refineNearCones(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const WedgeMap& cornerUV,
                             const std::vector<std::complex<double>>& seamT,
                             const RefineOptions& options = {});

/// refineNearCones then applyRefinement, with the solved corners written into cornerUV a batch
/// at a time (at most batchCorners, 24 bytes each, held at once with a quarter more reserved; 30 MB
/// by default: this runs at the pipeline's peak) instead of held until the end:
/// later batches and rounds read the map itself, as the out-of-core refinement does. The same
/// map and translations; the result's corners are left empty.
RefineResult refineNearConesInPlace(const TriangleMesh& mesh, const Topology& topology,
                                    const CrossField& field, const CutResult& cut, WedgeMap& cornerUV,
                                    std::vector<std::complex<double>>& seamT, const RefineOptions& options = {},
                                    std::size_t batchCorners = std::size_t(1) << 20);

/// The hat re-solve of flips a foldover repair left (UntangleOptions::leftoverRadius): `flipped`
/// as the marked faces with the rings that reach radius h at their mean edge length meanEdge (1 to
/// 256 rings), one round in the hat basis, not seeded from the map. base: the pipeline's refine
/// options (edge length, cone weights, holes held).
RefineOptions leftoverRefineOptions(const RefineOptions& base, std::vector<FaceId> flipped, double meanEdge,
                                    double radius);

/// Writes a refinement's corner values into a whole-mesh map (3 #F; a free vertex's wedges
/// change whole and keep their ids) and, when given, its re-solved translations into the per-seam
/// translations.
void applyRefinement(const RefineResult& refinement, WedgeMap& cornerUV,
                     std::vector<std::complex<double>>* translations = nullptr);

}  // namespace seamvox
