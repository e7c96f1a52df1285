#pragma once
/// mergeCloseCones (cone_merge.cpp) written once for the in-memory mesh and the out-of-core one
/// (stream/field_stream): positions, corner table and singularities come through small
/// interfaces. Internal.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <queue>
#include <unordered_map>
#include <vector>

#include "core/field/cone_merge.h"
#include "core/quality/metrics.h"
#include "core/system/parallel.h"

namespace seamvox::detail {

/// Shortest-path tree of interior edges from one vertex, cut off at a radius. pred holds the
/// corner naming the directed edge X -> Y that reached Y (topology.h: the edge of corner d runs
/// from vertex(next d) to vertex(prev d)).
struct Ball {
  std::unordered_map<VertexId, double> distance;
  std::unordered_map<VertexId, CornerId> pred;
};

/// positionOf(v): Vec3d; table: forEachCornerAround, opposite, vertex.
template <class PositionOf, class Table>
Ball searchBall(PositionOf&& positionOf, Table& table, VertexId source, double radius, VertexId stopAt = kInvalidId) {
  Ball ball;
  using Item = std::pair<double, VertexId>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  ball.distance[source] = 0.0;
  queue.push({0.0, source});
  while (!queue.empty()) {
    const auto [d, x] = queue.top();
    queue.pop();
    if (d > ball.distance[x]) continue;
    if (x == stopAt) break;
    const Vec3d px = positionOf(x);
    table.forEachCornerAround(x, [&](CornerId c) {
      const CornerId edge = prevCorner(c);  // runs from x to vertex(next c), face(c) on its left
      if (table.opposite(edge) == kInvalidId) return;
      const VertexId y = table.vertex(nextCorner(c));
      const double dy = d + (positionOf(y) - px).norm();
      if (dy > radius) return;
      const auto it = ball.distance.find(y);
      if (it != ball.distance.end() && it->second <= dy) return;
      ball.distance[y] = dy;
      ball.pred[y] = edge;
      queue.push({dy, y});
    });
  }
  return ball;
}

/// Adds delta to the matching of every directed edge X -> Y of path (and -delta to its opposite):
/// each adds delta to index4(X) and takes it from index4(Y). Singularities: matching, setMatching.
template <class Table, class Singularities>
void shiftMatchings(Table& table, Singularities& s, const std::vector<CornerId>& path, std::int32_t delta,
                    ConeMergeResult& out) {
  for (CornerId edge : path) {
    const auto moved = static_cast<std::uint8_t>(((s.matching(edge) + delta) % 4 + 4) % 4);
    s.setMatching(edge, moved);
    s.setMatching(table.opposite(edge), static_cast<std::uint8_t>((4 - moved) % 4));
    ++out.changedEdges;
  }
}

/// Moves the whole index of `gone` onto `keep` along path (directed edges from keep to gone, in
/// any order). A matching change of delta on the directed edge X -> Y adds delta to index4(X) and
/// takes it from index4(Y) (field.cpp's index sums the eps of the edges ending at the vertex), so
/// delta = index4(gone) on every path edge empties gone into keep and leaves inner vertices as
/// they were. Singularities: index, setIndex, matching, setMatching.
template <class Table, class Singularities>
void moveIndex(Table& table, Singularities& s, VertexId keep, VertexId gone, const std::vector<CornerId>& path,
               ConeMergeResult& out) {
  const std::int32_t delta = s.index(gone);
  shiftMatchings(table, s, path, delta, out);
  s.setIndex(keep, s.index(keep) + delta);
  s.setIndex(gone, 0);
  ++(s.index(keep) == 0 ? out.cancelledPairs : out.mergedPairs);
}

/// How far (in merge distances) a split looks for a vertex to take index.
constexpr double kSplitReach = 1024.0;

/// The cone split of mergeCloseCones (cone_merge.h) on these interfaces; new cones are appended to
/// cones (unsorted).
template <class PositionOf, class Table, class Singularities>
void splitFullTurnConesWith(PositionOf&& positionOf, Table& table, Singularities& s, std::vector<VertexId>& cones,
                            double distance, ConeMergeResult& out) {
  const std::size_t original = cones.size();
  for (std::size_t i = 0; i < original; ++i) {
    const VertexId v = cones[i];
    if (s.index(v) < kFullTurnIndex4) continue;
    // The ball grows until it holds a vertex that can take index (a fan of long faces has none
    // within the merge distance).
    const auto free = [&](VertexId y) { return y != v && s.index(y) == 0 && !table.isBoundaryVertex(y); };
    Ball ball;
    for (double radius = distance; radius <= kSplitReach * distance; radius *= 2.0) {
      ball = searchBall(positionOf, table, v, radius);
      if (std::any_of(ball.distance.begin(), ball.distance.end(), [&](const auto& yd) { return free(yd.first); })) break;
    }
    // The free vertices, walked and read once: a vertex taken below is at gap 0 from itself.
    std::vector<std::pair<VertexId, Vec3d>> candidates;
    for (const auto& [y, d] : ball.distance) {
      if (free(y)) candidates.emplace_back(y, positionOf(y));
    }
    std::vector<Vec3d> taken{positionOf(v)};
    std::vector<CornerId> path;
    while (s.index(v) > kMaxMergedIndex4) {
      // The candidate farthest (in space) from the cone and its new cones; ties to the smaller id.
      VertexId best = kInvalidId;
      double bestGap = -1.0;
      for (const auto& [y, p] : candidates) {
        double gap = HUGE_VAL;
        for (const Vec3d& t : taken) gap = std::min(gap, (p - t).norm());
        if (gap > bestGap || (gap == bestGap && y < best)) best = y, bestGap = gap;
      }
      if (best == kInvalidId || !(bestGap > 0.0)) break;  // no room: the cone stays as it is
      path.clear();
      for (VertexId y = best; y != v; y = table.vertex(nextCorner(path.back()))) path.push_back(ball.pred.at(y));
      // The edges run from v outwards: v gives `moved`, best gets it.
      const std::int32_t moved = std::min(kMaxMergedIndex4, s.index(v) - kMaxMergedIndex4);
      shiftMatchings(table, s, path, -moved, out);
      s.setIndex(v, s.index(v) - moved);
      s.setIndex(best, moved);
      cones.push_back(best);
      taken.push_back(positionOf(best));
      ++out.splitCones;
    }
  }
}

/// mergeCloseCones on these interfaces; cones: the cones, increasing, updated. parallel: the
/// searches around the cones run in parallel (a table that several threads may read).
template <class PositionOf, class Table, class Singularities>
ConeMergeResult mergeCloseConesWith(PositionOf&& positionOf, Table& table, Singularities& s,
                                    std::vector<VertexId>& cones, double maxDistance, bool parallel = false) {
  ConeMergeResult out;
  if (!(maxDistance > 0.0)) return out;
  splitFullTurnConesWith(positionOf, table, s, cones, maxDistance, out);
  std::sort(cones.begin(), cones.end());
  if (cones.size() < 2) return out;
  const auto mergeable = [&](VertexId a, VertexId b) {
    const std::int32_t ia = s.index(a), ib = s.index(b);
    return ia != 0 && ib != 0 && std::abs(ia + ib) <= kMaxMergedIndex4;
  };
  // A pair within reach and the shortest path from a to b its search found: directed edges,
  // paths[pathBegin, pathEnd). The searches depend on the mesh alone, not on the indices the
  // merges change, so a merge takes its pair's path instead of searching again.
  struct Candidate {
    double distance;
    VertexId a, b;
    std::size_t pathBegin, pathEnd;
  };
  struct Found {
    std::vector<Candidate> candidates;
    std::vector<CornerId> paths;
    std::uint64_t searched = 0;
  };
  // Pairs within reach: the cones each ball settles (the index tells a cone in O(1)), so the work
  // is the balls' size, linear in the number of cones, not quadratic.
  std::vector<Found> found(cones.size());
  const auto search = [&](std::uint64_t i) {
    const VertexId a = cones[i];
    Found& f = found[i];
    const Ball ball = searchBall(positionOf, table, a, maxDistance);
    f.searched = ball.distance.size();
    for (const auto& [b, distance] : ball.distance) {
      if (!(b > a && mergeable(a, b))) continue;
      const std::size_t begin = f.paths.size();
      for (VertexId y = b; y != a; y = table.vertex(nextCorner(f.paths.back()))) f.paths.push_back(ball.pred.at(y));
      f.candidates.push_back({distance, a, b, begin, f.paths.size()});
    }
  };
  if (parallel) {
    parallelForEach(cones.size(), 1, search);
  } else {
    for (std::uint64_t i = 0; i < cones.size(); ++i) search(i);
  }
  std::vector<Candidate> candidates;
  std::vector<CornerId> paths;
  for (Found& f : found) {
    out.searchedVertices += f.searched;
    for (Candidate c : f.candidates) {
      c.pathBegin += paths.size(), c.pathEnd += paths.size();
      candidates.push_back(c);
    }
    paths.insert(paths.end(), f.paths.begin(), f.paths.end());
    f = Found();
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return x.distance != y.distance ? x.distance < y.distance : (x.a != y.a ? x.a < y.a : x.b < y.b);
  });
  std::vector<CornerId> path;
  for (const Candidate& pair : candidates) {
    if (!mergeable(pair.a, pair.b)) continue;  // an earlier merge changed one of them
    // keep = the cone that stays (larger |index4|, then smaller id); gone = the one moved onto it.
    const bool keepA = std::abs(s.index(pair.a)) >= std::abs(s.index(pair.b));
    const VertexId keep = keepA ? pair.a : pair.b, gone = keepA ? pair.b : pair.a;
    // The path from a to b, or the same edges the other way (their opposite corners).
    path.assign(paths.begin() + pair.pathBegin, paths.begin() + pair.pathEnd);
    if (!keepA) {
      for (CornerId& edge : path) edge = table.opposite(edge);
    }
    moveIndex(table, s, keep, gone, path, out);
    out.longestPath = std::max(out.longestPath, pair.distance);
  }
  cones.erase(std::remove_if(cones.begin(), cones.end(), [&](VertexId v) { return s.index(v) == 0; }), cones.end());
  return out;
}

/// coincidentCones on these interfaces; uvOf(c): Vec2d, the map at corner c; cones increasing.
template <class PositionOf, class Table, class UvOf>
std::vector<std::pair<VertexId, VertexId>> coincidentConesWith(PositionOf&& positionOf, Table& table, UvOf&& uvOf,
                                                               const std::vector<VertexId>& cones, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> out;
  const auto isCone = [&](VertexId v) { return std::binary_search(cones.begin(), cones.end(), v); };
  // Adjacent pairs: the edge v -> w of face(c), named by prev(c); each undirected edge once (from
  // its smaller vertex, or from v when the other side is the boundary).
  for (VertexId v : cones) {
    table.forEachCornerAround(v, [&](CornerId c) {
      const CornerId edge = prevCorner(c);
      const CornerId n = nextCorner(c);
      const VertexId w = table.vertex(n);
      if (!isCone(w) || (w < v && table.opposite(edge) != kInvalidId)) return;
      if ((uvOf(c) - uvOf(n)).norm() <= kCoincidentConeDistance) out.push_back({v, w});
    });
  }
  if (maxDistance > 0.0) {
    // Cones grouped by the points their wedges map to (the map puts cones on lattice points, far
    // from the 1e-6 keys' borders), then one bounded search per cone that shares a point: the
    // work is the cones' wedges plus a ball per such cone, even when a whole unsolved component's
    // cones sit at (0, 0).
    struct Image {
      std::int64_t u, v;
      VertexId cone;
      Vec2d q;
    };
    std::vector<Image> images;
    constexpr double kKeyCell = 1e-6;
    for (VertexId v : cones) {
      table.forEachCornerAround(v, [&](CornerId c) {
        const Vec2d q = uvOf(c);
        images.push_back({std::llround(q.x() / kKeyCell), std::llround(q.y() / kKeyCell), v, q});
      });
    }
    std::sort(images.begin(), images.end(), [](const Image& x, const Image& y) {
      return x.u != y.u ? x.u < y.u : (x.v != y.v ? x.v < y.v : x.cone < y.cone);
    });
    for (std::size_t begin = 0, end = 0; begin < images.size(); begin = end) {
      while (end < images.size() && images[end].u == images[begin].u && images[end].v == images[begin].v) ++end;
      if (images[begin].cone == images[end - 1].cone) continue;  // one cone's wedges only
      for (std::size_t i = begin; i < end; ++i) {
        if (i > begin && images[i].cone == images[i - 1].cone) continue;
        const Ball ball = searchBall(positionOf, table, images[i].cone, maxDistance);
        for (std::size_t j = begin; j < end; ++j) {
          if (images[j].cone > images[i].cone && ball.distance.count(images[j].cone) &&
              (images[j].q - images[i].q).norm() <= kCoincidentConeDistance) {
            out.push_back({images[i].cone, images[j].cone});
          }
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// mergeCoincidentCones on these interfaces; cones: the cones, increasing, updated. Vertex ids
/// are checked by the caller.
template <class PositionOf, class Table, class Singularities>
ConeMergeResult mergeCoincidentConesWith(PositionOf&& positionOf, Table& table, Singularities& s,
                                         std::vector<VertexId>& cones,
                                         const std::vector<std::pair<VertexId, VertexId>>& pairs, double maxDistance) {
  ConeMergeResult out;
  for (const auto& [a, b] : pairs) {
    if (!canMergeCoincident(s.index(a), s.index(b))) continue;
    const bool keepA = std::abs(s.index(a)) >= std::abs(s.index(b));
    const VertexId keep = keepA ? a : b, gone = keepA ? b : a;
    // An adjacent pair is reached whatever maxDistance: through its own edge at worst.
    double reach = maxDistance;
    table.forEachCornerAround(keep, [&](CornerId c) {
      if (table.vertex(nextCorner(c)) == gone && table.opposite(prevCorner(c)) != kInvalidId) {
        reach = std::max(reach, (positionOf(gone) - positionOf(keep)).norm());
      }
    });
    if (!(reach > 0.0)) continue;
    const Ball ball = searchBall(positionOf, table, keep, reach, gone);
    if (!ball.pred.count(gone)) continue;  // farther than reach along interior edges
    std::vector<CornerId> path;
    for (VertexId y = gone; y != keep; y = table.vertex(nextCorner(path.back()))) path.push_back(ball.pred.at(y));
    moveIndex(table, s, keep, gone, path, out);
    out.longestPath = std::max(out.longestPath, ball.distance.at(gone));
  }
  cones.erase(std::remove_if(cones.begin(), cones.end(), [&](VertexId v) { return s.index(v) == 0; }), cones.end());
  return out;
}

/// Cone pairs (a < b) no farther apart than maxDistance along interior edges, sorted; cones
/// increasing. One bounded search per cone.
template <class PositionOf, class Table>
std::vector<std::pair<VertexId, VertexId>> closeConesWith(PositionOf&& positionOf, Table& table,
                                                          const std::vector<VertexId>& cones, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> out;
  if (!(maxDistance > 0.0)) return out;
  for (VertexId a : cones) {
    const Ball ball = searchBall(positionOf, table, a, maxDistance);
    for (const auto& [b, distance] : ball.distance) {
      if (b > a && std::binary_search(cones.begin(), cones.end(), b)) out.push_back({a, b});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// foldedCloseCones on these interfaces: indexOf(v) the cone's index4, fanFlipped(v) whether a
/// face around v is flipped; cones increasing.
template <class PositionOf, class Table, class IndexOf, class FanFlipped>
std::vector<std::pair<VertexId, VertexId>> foldedCloseConesWith(PositionOf&& positionOf, Table& table,
                                                                const std::vector<VertexId>& cones, IndexOf&& indexOf,
                                                                FanFlipped&& fanFlipped, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> out;
  for (const auto& [a, b] : closeConesWith(positionOf, table, cones, maxDistance)) {
    if (canMergeCoincident(indexOf(a), indexOf(b)) && fanFlipped(a) && fanFlipped(b)) out.push_back({a, b});
  }
  return out;
}

}  // namespace seamvox::detail
