#pragma once
/// Merging cones closer than the grid can resolve (DESIGN sections 4 and 8).
///
/// Once the seam translations are integers, a cone of index +-1 lies on the lattice (1 + i)/2 Z[i]
/// and one of index +-2 on Z[i]/2 (grid units): distinct cones are at least 1/2 apart. Two cones
/// much closer than that on the surface are rounded onto the same point, and the faces between
/// them collapse, with any solver. Moving the index of one onto the other removes the collapse:
/// changing the matching on every edge of a short path between them by the same quarter turns
/// moves index from one end to the other (each inner path vertex gains and loses the same amount).
/// Opposite cones cancel; two +1 (or -1) cones become one +2 (-2) cone, what the coincident pair
/// was in the map anyway. The field's directions stay as they are: across the path's few edges it
/// turns by a quarter more than its nearest rotation, a distortion confined to the path's length.
///
/// Conventions: field.h (matching, index4), topology.h (corners).
#include <cstdint>
#include <utility>
#include <vector>

#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/mesh/wedge_map.h"

namespace seamvox {

/// Default merge distance in units of the grid spacing h. Cones of index +-1 sit on the lattice
/// (1 + i)/2 Z[i], at least 0.71 apart: a pair about one unit apart is pushed around by rounding
/// and folds the faces between them. 1.0 rather than 0.5 halved the flips on armadillo
/// subdivided 2 and 3 times (500 -> 296, 1958 -> 969) at +0-1.6% gradient error, and changed
/// nothing on meshes without close pairs (bench/RESULTS.md).
constexpr double kConeMergeFraction = 1.0;
/// Cones merged by distance keep |index4| <= this (a cone of angle pi at most).
constexpr std::int32_t kMaxMergedIndex4 = 2;
/// Cones the map already put on one point may merge up to |index4| 3 (what the map has there
/// anyway); 4 would be a cone of angle 0.
constexpr std::int32_t kMaxCoincidentIndex4 = 3;
/// Cones the map put on one point are looked for this many grid spacings apart along edges: a +1
/// and a +2 cone half a spacing apart can be rounded onto one point, and merging by distance must
/// not join them in advance (most such pairs end 0.5 apart, and a +3 cone is a strong distortion).
constexpr double kCoincidentSearchFraction = 2.0;
/// Whether two cones of these indices that the map put on one point may be merged
/// (mergeCoincidentCones). Two +2 cones on one point (e.g. a closed component smaller than the
/// grid) cannot: the map must collapse there.
inline bool canMergeCoincident(std::int32_t a, std::int32_t b) {
  return a != 0 && b != 0 && (a + b <= kMaxCoincidentIndex4 && a + b >= -kMaxCoincidentIndex4);
}

struct ConeMergeOptions {
  /// Cones whose shortest path of interior edges is at most this long (mesh units) are merged;
  /// <= 0 merges nothing. param uses kConeMergeFraction * h.
  double maxDistance = 0.0;
};

struct ConeMergeResult {
  std::uint32_t cancelledPairs = 0;  ///< opposite cones that both vanished
  std::uint32_t mergedPairs = 0;     ///< cones moved onto another one that stays a cone
  /// Cones of a full turn or more split: +2 moved onto new cones nearby (splitFullTurnCones).
  std::uint32_t splitCones = 0;
  double longestPath = 0.0;          ///< longest path used (mesh units)
  std::uint32_t changedEdges = 0;
  /// Vertices reached by the bounded searches (mergeCloseCones): the work done, about the
  /// number of cones times the vertices within maxDistance of one.
  std::uint64_t searchedVertices = 0;
  /// Adds another merge's figures (the longest path the longer of the two).
  void add(const ConeMergeResult& other) {
    cancelledPairs += other.cancelledPairs;
    mergedPairs += other.mergedPairs;
    splitCones += other.splitCones;
    longestPath = longestPath > other.longestPath ? longestPath : other.longestPath;
    changedEdges += other.changedEdges;
    searchedVertices += other.searchedVertices;
  }
};

/// A cone of index4 >= this has an angle <= 0: no map holds it (the field turns a full turn
/// around one vertex, as the direct field may around a high-valence vertex of thin faces).
constexpr std::int32_t kFullTurnIndex4 = 4;

/// First, every cone of index4 >= kFullTurnIndex4 is split: up to +2 at a time moves along
/// interior edges onto a new cone (an interior vertex without index within options.maxDistance,
/// or twice that and so on when there is none, the farthest from the cone and its earlier new
/// cones) until it keeps +2 (a +2 pair is not merged back). Then greedily, closest pair first,
/// moves the whole index of one cone onto another no farther than options.maxDistance along
/// interior edges, when the sum keeps |index4| <= kMaxMergedIndex4 (the cone with the larger
/// |index4|, or the smaller id, stays). Changes matchings, index4 and cones in place; the index
/// sum (Poincare-Hopf) is unchanged. Cost: one bounded search per cone
/// (ConeMergeResult::searchedVertices; in parallel), whose shortest paths the merges then take,
/// independent of how many cones there are.
ConeMergeResult mergeCloseCones(const TriangleMesh& mesh, const Topology& topology,
                                FieldSingularities& singularities, const ConeMergeOptions& options);

}  // namespace seamvox

namespace seamvox {

/// Edges between two cones that the map put on the same point (metrics.h collapsesBetweenCones:
/// the faces on them collapse), as (vertex, vertex) pairs, each edge once.
std::vector<std::pair<VertexId, VertexId>> coincidentConeEdges(const Topology& topology,
                                                               const std::vector<VertexId>& cones,
                                                               const WedgeMap& cornerUV);

/// Cone pairs the map put on one point (a wedge of each within kCoincidentConeDistance of the
/// other's) no farther apart than maxDistance along interior edges, adjacent pairs included
/// whatever maxDistance (coincidentConeEdges): the faces between them collapse or fold, and no
/// repair with the cones fixed unfolds them. Sorted, each pair once with a < b.
std::vector<std::pair<VertexId, VertexId>> coincidentCones(const TriangleMesh& mesh, const Topology& topology,
                                                           const std::vector<VertexId>& cones,
                                                           const WedgeMap& cornerUV, double maxDistance);

/// Cone pairs no farther apart than maxDistance along interior edges, whatever the map. Sorted,
/// each pair once with a < b.
std::vector<std::pair<VertexId, VertexId>> closeCones(const TriangleMesh& mesh, const Topology& topology,
                                                      const std::vector<VertexId>& cones, double maxDistance);

/// Close cones on two points that a repair holding the cones cannot unfold: pairs no farther
/// apart than maxDistance along interior edges whose indices may merge (canMergeCoincident) and
/// whose fans both hold a face the map flips (isFlippedRatio, h the grid spacing). Rounding puts
/// close cones on lattice points that may lie the wrong way round (a +1 and a +2 cone, which
/// merging by distance keeps apart, half a unit apart with the faces between them folded);
/// merged, they are one cone. index4: per cone, in the order of `cones`. Sorted, a < b.
std::vector<std::pair<VertexId, VertexId>> foldedCloseCones(const TriangleMesh& mesh, const Topology& topology,
                                                            const std::vector<VertexId>& cones,
                                                            const std::vector<std::int32_t>& index4,
                                                            const WedgeMap& cornerUV, double h, double maxDistance);

/// Merges the given pairs like mergeCloseCones, along a shortest path of interior edges no longer
/// than maxDistance (an adjacent pair at least along its edge); skips pairs that are no longer
/// both cones, are farther apart, or whose sum would exceed kMaxCoincidentIndex4.
ConeMergeResult mergeCoincidentCones(const TriangleMesh& mesh, const Topology& topology,
                                     FieldSingularities& singularities,
                                     const std::vector<std::pair<VertexId, VertexId>>& pairs,
                                     double maxDistance);

}  // namespace seamvox
