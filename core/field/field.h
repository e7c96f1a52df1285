#pragma once
/// Cross fields: per-face unit tangent direction u_T (the cross is {u, n x u, -u, -n x u}),
/// per-edge matchings and per-vertex singularity indices. DESIGN section 4.
///
/// CONVENTIONS (written once; see also topology.h):
/// * Angles are measured counter-clockwise about the face normal; rot(x) = n x x is a quarter
///   turn. Each face has a reference frame: its first edge (vertex 0 -> vertex 1) is angle 0.
/// * matching[c] = k for the edge of corner c, going from face f = face(c) to g = face(opposite c):
///   the cross direction rot^k(u_f), parallel-transported across the edge, is the one closest to
///   u_g. Hence matching[opposite(c)] == (4 - matching[c]) % 4. Boundary corners hold 0.
/// * singularity index of a vertex in quarter turns: index4(v) = round(4 (K_v + sum eps) / 2 pi)
///   walking counter-clockwise around v (DESIGN section 4); a flat fan whose field turns by +phi/4
///   around the vertex has index4 = +1. On a closed mesh sum index4 = 4 chi (Poincare-Hopf).
///   Boundary vertices get index 0 (the boundary is free); their turning relative to the
///   boundary is boundaryIndex4 (below).
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct CrossField {
  /// #F unit tangent vectors u_T (world coordinates), stored in float to halve their memory
  /// (12 bytes per face); computations read them in double through at().
  std::vector<Vec3f> direction;
  /// Empty, or #V positions of a smoothed copy of the mesh (same triangles) whose discrete
  /// connection defines the matchings and indices (computeSingularities turns each direction onto
  /// the smoothed face by rotateBetween their normals, the inverse of what computeCrossField did). On a noisy scan every fold-over of the mesh's own faces turns the
  /// connection by up to half a turn and puts a pair of cones there; the smoothed surface has
  /// the scan's shape without them. The directions stay tangent to the mesh's own faces.
  std::vector<Vec3f> framePositions;
  /// smoothPositions steps framePositions were made with (0: none). With it, a caller may release
  /// them for the memory (12 bytes per vertex) and recompute them, all or only where needed.
  std::uint32_t frameSmoothing = 0;
  /// Vertices whose framePositions differ from smoothPositions with frameSmoothing steps (rough
  /// spots smoothed further, smoothRoughSpots), sorted by vertex; kept when framePositions are
  /// released, so that they are recomputed exactly (framePositionsAt, restoreFramePositions).
  std::vector<std::pair<VertexId, Vec3f>> frameOverrides;
  Vec3d at(FaceId f) const { return direction[f].cast<double>(); }
  void set(FaceId f, const Vec3d& u) { direction[f] = u.cast<float>(); }
};

struct FieldSingularities {
  std::vector<std::uint8_t> matching;  ///< 3 #F, per corner, in {0,1,2,3}
  std::vector<std::int32_t> index4;    ///< #V, singularity index in quarter turns
  std::vector<VertexId> cones;         ///< vertices with index4 != 0, increasing
  /// #V, 0 at interior vertices. At a boundary vertex, in quarter turns, the rotation of the field
  /// walking counter-clockwise from the first boundary edge to the last, against the boundary's
  /// own turn: round(4 (pi - sum of angles + sum eps + delta_first - delta_last) / 2 pi), delta the
  /// field's angle from its boundary edge modulo quarter turns (0 when aligned). The deltas cancel
  /// along each boundary edge, so sum index4 + sum boundaryIndex4 = 4 chi on every component;
  /// with the field aligned to the boundary a 90-degree corner has +1, a straight vertex 0.
  std::vector<std::int32_t> boundaryIndex4;
  std::int64_t indexSum4() const;      ///< sum of index4 (== 4 chi on closed meshes)
};

/// FieldSingularities in about 0.75 byte per face: matchings packed four to a byte, indices
/// listed where they are not 0. What a later cone pass restores instead of recomputing them on
/// the smoothed surface.
struct PackedSingularities {
  std::vector<std::uint8_t> matching;  ///< 2 bits per corner
  std::size_t corners = 0, vertices = 0, boundaryVertices = 0;  ///< the unpacked vectors' sizes
  std::vector<std::pair<VertexId, std::int32_t>> index4, boundaryIndex4;  ///< the nonzero entries
  std::vector<VertexId> cones;
  bool empty() const { return corners == 0; }
};
PackedSingularities packSingularities(const FieldSingularities& singularities);
FieldSingularities unpackSingularities(const PackedSingularities& packed);

/// Matchings, indices and cones of a field, on the surface of field.framePositions when set (the
/// mesh's own otherwise). Linear, parallel. Zero-area faces are handled without NaN (their frame
/// falls back to any tangent direction).
FieldSingularities computeSingularities(const TriangleMesh& mesh, const Topology& topology,
                                        const CrossField& field);
/// The same, with field.framePositions released (releaseFramePositions) as soon as the faces'
/// angles are read: 12 bytes per vertex less while the matchings and indices are computed.
FieldSingularities computeSingularitiesReleasingFrames(const TriangleMesh& mesh, const Topology& topology,
                                                       CrossField& field);

/// Figures of a field's CHOLMOD factorization (the largest when it factors more than once), as
/// SeamlessStats has them for the seamless solve.
struct FieldSolveStats {
  std::uint64_t unknowns = 0, matrixNonzeros = 0, factorNonzeros = 0;
  std::uint64_t factorBytes = 0, factorPeakBytes = 0;
  bool realFallback = false;  ///< the complex factorization failed, the real 2n x 2n form was used
  /// Rough spots of the field's surface (smoothRoughSpots): rough vertices found, vertices moved.
  std::uint64_t roughVertices = 0, roughSpotVertices = 0;
  /// A region exceeded its memory bound and the rounds stopped there (in memory
  /// roughRegionBoundInMemory, out of core stream/field_stream.h roughRegionBound).
  bool roughSpotsCapped = false;
};

struct SmoothFieldOptions {
  /// 0 = smoothest field only; larger values align more strongly with principal curvature.
  /// (w > 0 solves (A - lambda M) z = M q per component, q the principal directions as 4th
  /// powers, lambda = lambda_1 / 2 - w 4 pi^2 / area: w = 1 already follows curvature closely.)
  double curvatureWeight = 0.0;
  /// Corners whose face's field is fixed along the corner's edge (feature curves, features.h):
  /// a hard constraint, the other faces of their components solve A z = 0 around them (one more
  /// factorization). A face whose constrained edges disagree takes the mean of their 4th powers.
  std::vector<CornerId> alignCorners;
  ProgressFn progress;
  FieldSolveStats* stats = nullptr;  ///< filled when set
};
/// Smoothest 4-direction field (Knoppel et al. 2013): per-face z^4, discrete connection across
/// edges, one sparse Hermitian CHOLMOD solve. Exact; practical up to a few million faces.
CrossField computeSmoothestField(const TriangleMesh& mesh, const Topology& topology,
                                 const SmoothFieldOptions& options = {});

/// Turns the direction of every face whose corners in `corners` (sorted) name edges that agree
/// (parallel or perpendicular) onto the nearest of those edges' four directions, exactly on the
/// mesh's own face. Other faces are left unchanged.
void snapToFeatureEdges(const TriangleMesh& mesh, const std::vector<CornerId>& corners, CrossField& field);

/// v rotated by the smallest rotation taking unit vector `from` to unit vector `to` (for two faces
/// of an edge: the rotation about the edge, the discrete parallel transport). Opposite vectors: a
/// half turn about from.unitOrthogonal(). Rotating back (to, from) restores v.
Vec3d rotateBetween(const Vec3d& from, const Vec3d& to, const Vec3d& v);

/// Positions after `iterations` steps of uniform Laplacian smoothing (each interior vertex moves
/// halfway to the mean of its neighbours; boundary and isolated vertices stay). Each step damps
/// edge-scale noise by half or more and moves features larger than a few edges very little.
/// Linear, parallel, deterministic.
std::vector<Vec3f> smoothPositions(const TriangleMesh& mesh, const Topology& topology,
                                   std::uint32_t iterations);

/// smoothPositions' values at the given vertices only (the same floats), computed on the
/// `iterations`-ring neighbourhood of those vertices: cost proportional to that neighbourhood.
std::vector<Vec3f> smoothPositionsAt(const TriangleMesh& mesh, const Topology& topology,
                                     std::uint32_t iterations, const std::vector<VertexId>& vertices);

/// field.framePositions at the given vertices: read when held, else recomputed there
/// (smoothPositionsAt with frameSmoothing steps, then frameOverrides). Empty when the field has no
/// smoothed surface.
std::vector<Vec3f> framePositionsAt(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                    const std::vector<VertexId>& vertices);

/// Frees field.framePositions when they can be recomputed (frameSmoothing > 0).
void releaseFramePositions(CrossField& field);
/// Recomputes released framePositions (smoothPositions with frameSmoothing steps, then
/// frameOverrides).
void restoreFramePositions(const TriangleMesh& mesh, const Topology& topology, CrossField& field);

/// Sets the rough spots' moves (frameOverrides) aside into `aside` (emptied first) and puts their
/// parts along the rough surface's normal in their place (detail::normalPartOfMoves): framePositions,
/// when held, and framePositionsAt then give the plain smoothed surface (smoothPositions with
/// frameSmoothing steps) with those. The map's stages after the cut read that one: the rough
/// spots' steps also drift vertices along the surface, and a map evaluated or solved there folds
/// noisy faces (bench/RESULTS.md, session 60). putFrameOverridesBack undoes it.
void setFrameOverridesAside(const TriangleMesh& mesh, const Topology& topology, CrossField& field,
                            std::vector<std::pair<VertexId, Vec3f>>& aside);
/// The moves setFrameOverridesAside set aside back in the field (and in framePositions when held);
/// `aside` is left empty. Nothing happens when it is empty.
void putFrameOverridesBack(CrossField& field, std::vector<std::pair<VertexId, Vec3f>>& aside);

/// Projects arbitrary per-face 3D vectors onto each face's tangent plane and normalizes them.
/// Vectors parallel to the normal (or zero) get the face's first edge direction.
CrossField projectToTangent(const TriangleMesh& mesh, const std::vector<Vec3d>& vectors);

}  // namespace seamvox
