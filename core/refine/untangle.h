#pragma once
/// Foldover repair of a seamless map by stiffening re-solves in the hat basis. A least-squares
/// map that follows a cross field flips triangles where the field cannot be followed: around
/// cones (on the shared meshes nearly every flip lies within a few rings of one) and on scan noise.
/// Patches of rings around the flipped faces are re-solved with everything around them locked
/// and the seam translations kept (seams lying wholly inside a patch re-round theirs, as in
/// refine), so the map stays exactly seamless; each re-solve multiplies the energy of the faces
/// still flipped by a stiffening factor, which pulls their gradients towards the field's
/// orientation-preserving target and spreads the distortion over the unflipped neighbours.
/// Faces folded in 3D (their normal opposite to the field's smoothed surface) flip under any map
/// that follows the smooth surface: the stiffening and relocation steps leave them; only the
/// joint patches, which measure each face against its own 3D shape, unfold them.
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/basis.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/system/progress.h"

namespace seamvox {

struct UntangleOptions {
  double edgeLength = 1.0;  ///< h of the map (> 0)
  /// Patch radius around the flipped faces in the first round, in grid spacings h (as vertex
  /// rings at the seeds' mean edge length, at least 2); each further round doubles it.
  double patchRadius = 0.5;
  std::uint32_t maxRounds = 3;    ///< patch rounds (0: only the relocation step below)
  /// After the rounds: cones the map leaves a full turn short (a valence-5 cone at pi / 2, the
  /// map folded next to it) are re-solved in patches of this radius (grid spacings h), then twice
  /// and four times it (at most 64 rings each), outside the rounds' budget; 0: off. Without
  /// them the later steps unfold such a fold only by winding a neighbour twice (fertility x5:
  /// 31 such cones, 15 left wound and one fold of 871 faces left flipped).
  double coneRepairRadius = 1.0;
  std::uint32_t maxSolves = 6;    ///< stiffening re-solves per round (>= 1)
  /// A round's patches hold at most max(minPatchFaces, maxPatchFraction * #F) faces: the radius
  /// shrinks to fit. Unbounded, a 22M-face scan with 9154 flips re-solved 1.7M faces 24 times
  /// (103 s, twice the rest of the run).
  double maxPatchFraction = 0.005;
  std::uint64_t minPatchFaces = 20000;
  double stiffening = 2.0;        ///< energy factor per re-solve of a face still flipped (> 1)
  double coneWeightRadius = kConeWeightRadius;  ///< of the local hat solves (HatBasisOptions)
  /// The global solve's ParamOptions::closeHolesWithin (mesh units; 0: no hole held, solveRegion).
  double closeHolesWithin = 0.0;
  /// Gauss-Seidel passes of the last step: an interior vertex of a face still flipped, not a cone
  /// and next to no face folded in 3D, moves into the kernel of its fan (every fan triangle
  /// positive) when it has one, else a step toward a larger worst margin; neighbours make room
  /// when nothing moves; no move collapses a triangle, and all are undone if flips did not drop.
  /// A seam vertex moves all its wedges by one displacement turned through the seams' rotations.
  std::uint32_t relocationPasses = 32;
  /// Last: around each face still flipped (folded in 3D or not), the vertices within 2, 3, 4, 6,
  /// 9, 12, 18, 27, then 36 rings (up to this many; below 2: off) move jointly by minimising an
  /// untangling energy (regularised |J|^2/det plus an area term against the faces' 3D shapes,
  /// Garanzha et al. 2021), seam vertices through the seams' rotations, cones and the patch
  /// border fixed; a patch is kept only when its flips drop and no face flips or collapses that
  /// did not before. The wide patches matter on fine meshes: at 36 edges per h, a cone's
  /// distorted neighbourhood spans more than 12 rings.
  std::uint32_t jointRings = 36;
  /// After the repair, the pipelines re-solve the flips it left in the hat basis within this many
  /// h of them (one round from the repaired map, leftoverRefineOptions) and repair again: a fold
  /// next to a cone that the voxel or spline map put there and no patch opens with the cone fixed.
  /// Voxel maps only (a hat map re-solved locally is itself again); 0: off.
  double leftoverRadius = 1.0;
  /// When given (one flag per face): only the flipped faces marked here are repaired (the specks
  /// among them collapsed) and counted, the others are taken as fine (a repair near a few cones,
  /// before deciding on another pass).
  const std::vector<std::uint8_t>* onlyFaces = nullptr;
  /// When given (one flag per vertex): vertices never moved, by any step (the border of a window
  /// cut out of a larger mesh, whose faces outside keep their values).
  const std::vector<std::uint8_t>* pinnedVertices = nullptr;
  /// When given (increasing face ids): the only faces that may be flipped; every other face is
  /// known fine and not measured (a caller that re-solved a few regions of a map whose flips it
  /// knows). Not with onlyFaces.
  const std::vector<FaceId>* candidateFaces = nullptr;
  /// When given (increasing): cones an earlier repair of this map re-solved through its last cone
  /// round and left a full turn short (UntangleStats::conesLeftShort); the cone step skips them
  /// rather than solving the same patches again (the repair after the one near close cones, and
  /// the one after the leftovers' re-solve).
  const std::vector<VertexId>* conesNotRetried = nullptr;
  ProgressFn progress;
};

struct UntangleStats {
  std::uint64_t flippedBefore = 0, flippedAfter = 0;  ///< whole map, collapsed faces excluded
  /// Faces measured for flips at the start: every face, or UntangleOptions::candidateFaces (with
  /// a re-solve of the leftovers, the first repair's).
  std::uint64_t measuredFaces = 0;
  /// Of flippedAfter: folded in 3D against the field's smoothed surface (0 without one).
  std::uint64_t foldedIn3D = 0;
  std::uint32_t rounds = 0;  ///< patch re-solves, the cones' included
  /// Cones the map left a full turn short after the rounds (the most any of the combined repairs
  /// found), and after the cones' own re-solves (the last repair's). Out of core: those of the
  /// repair's window (the cones near flips), not the whole map's.
  std::uint32_t miswoundCones = 0, miswoundConesAfter = 0;
  std::uint32_t solves = 0;  ///< stiffening re-solves, summed over the groups of components of each round
  std::uint64_t patchFaces = 0;     ///< faces re-solved, summed over rounds
  std::uint32_t freeVertices = 0;   ///< vertices moved in some round (counted once per round)
  std::uint32_t largestUnknowns = 0;
  std::uint32_t relocatedVertices = 0;  ///< moves of the relocation step (a vertex counted per move)
  std::uint32_t jointVertices = 0;      ///< vertices of the kept joint patches (summed over patches)
  /// Closed components smaller than a cell left with flips, mapped to one point (collapseSpecks);
  /// their faces are collapsed, not counted in flippedAfter.
  std::uint32_t specks = 0;
  std::uint64_t speckFaces = 0;
  /// The hat re-solve of the flips the repair left (UntangleOptions::leftoverRadius): the flips it
  /// started from, its region's faces and free vertices, and the flips right after it (before the
  /// repair that follows; flippedAfter is that repair's).
  std::uint64_t leftoverFlips = 0, leftoverRegionFaces = 0, leftoverAfterResolve = 0;
  std::uint32_t leftoverFreeVertices = 0;
  double seconds = 0.0;
  /// Of seconds: the patch rounds, the cones' re-solves, the relocation, the joint patches and
  /// the leftovers' hat re-solve (summed over the combined repairs).
  double roundSeconds = 0.0, coneSeconds = 0.0, relocationSeconds = 0.0, jointSeconds = 0.0, leftoverSeconds = 0.0;
  /// The faces still flipped (folded in 3D or not) at the end, increasing: the whole map's, or
  /// empty with UntangleOptions::onlyFaces.
  std::vector<FaceId> leftFaces;
  /// The cones the cone step re-solved and left a full turn short, increasing (with those of the
  /// repairs combined into these figures).
  std::vector<VertexId> conesLeftShort;
};

/// stats of a repair that followed an earlier one restricted to some faces (onlyFaces: the faces
/// near close cones, repaired first when a pass may follow): the flips the earlier one repaired
/// count as found before, its work and seconds are added.
void addEarlierRepair(UntangleStats& stats, const UntangleStats& earlier);

/// stats of the repair after the hat re-solve of what an earlier repair left (`earlier`, whose
/// flippedAfter the re-solve started from): the leftover figures set from the re-solve's refine
/// stats, the work and seconds of both repairs added, flippedBefore the earlier one's.
void addLeftoverRepair(UntangleStats& stats, const UntangleStats& earlier, std::uint64_t regionFaces,
                       std::uint32_t freeVertices, double seconds);

/// Closed components whose bounding box diagonal is below h and whose map still has flipped
/// faces are mapped to the point (0, 0), every corner and the translations of their seams: a
/// closed surface other than a torus needs cones, which a seamless map puts on lattice points at
/// least half a unit apart, so a speck far smaller than a cell (a scan's floating crumb) is blown
/// up to a cell and folded, and no repair with its cones fixed unfolds it. On one point it stays
/// seamless (its seams' translations 0), its faces are collapsed (`check` counts them so, the
/// component report says "point") and the quad mesh reports it as an island smaller than a cell.
/// Returns the faces of each component mapped so (in the order of their first flipped face).
/// flipped: the map's flipped faces, increasing, when the caller has them (else one pass finds
/// them).
std::vector<std::uint32_t> collapseSpecks(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                                          WedgeMap& cornerUV, std::vector<std::complex<double>>& seamT, double h,
                                          const std::vector<FaceId>* flipped = nullptr);

/// Repairs flips of cornerUV (3 #F, on the wedges of cut) in place; seamT (per seam of cut,
/// Gaussian integers) is updated where a seam inside a patch re-rounded its translation. A round
/// is kept only where it lowers the flips of its patch; last, collapseSpecks. Throws InputError on
/// mismatched sizes.
UntangleStats untangleFlips(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                            const CutResult& cut, WedgeMap& cornerUV,
                            std::vector<std::complex<double>>& seamT, const UntangleOptions& options);

}  // namespace seamvox
