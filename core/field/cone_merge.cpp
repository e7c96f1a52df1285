#include "core/field/cone_merge.h"

#include "core/field/detail_cone_merge.h"

#include <algorithm>
#include <cstdlib>
#include <queue>
#include <string>
#include <unordered_map>

#include "core/system/errors.h"
#include "core/quality/metrics.h"

namespace seamvox {
namespace {

using detail::Ball;

/// The in-memory singularities for detail::mergeCloseConesWith and detail::moveIndex.
struct MemorySingularities {
  FieldSingularities& s;
  std::int32_t index(VertexId v) const { return s.index4[v]; }
  void setIndex(VertexId v, std::int32_t k) { s.index4[v] = k; }
  std::uint8_t matching(CornerId c) const { return s.matching[c]; }
  void setMatching(CornerId c, std::uint8_t m) { s.matching[c] = m; }
};

Ball searchBall(const TriangleMesh& mesh, const Topology& topology, VertexId source, double radius,
                        VertexId stopAt = kInvalidId) {
  return detail::searchBall([&](VertexId v) { return mesh.position(v); }, topology, source, radius, stopAt);
}

void moveIndex(const Topology& topology, FieldSingularities& singularities, VertexId keep, VertexId gone,
               const std::vector<CornerId>& path, ConeMergeResult& out) {
  MemorySingularities s{singularities};
  detail::moveIndex(topology, s, keep, gone, path, out);
}

void dropVanishedCones(FieldSingularities& singularities) {
  std::vector<VertexId> cones;
  for (VertexId v : singularities.cones) {
    if (singularities.index4[v] != 0) cones.push_back(v);
  }
  singularities.cones = std::move(cones);
}

}  // namespace

ConeMergeResult mergeCloseCones(const TriangleMesh& mesh, const Topology& topology,
                                FieldSingularities& singularities, const ConeMergeOptions& options) {
  const std::size_t nc = std::size_t(topology.numCorners());
  if (singularities.matching.size() != nc || singularities.index4.size() != topology.numVertices()) {
    throw InputError("mergeCloseCones: singularities do not match the mesh (" +
                     std::to_string(singularities.matching.size()) + " matchings for " +
                     std::to_string(nc) + " corners)");
  }
  MemorySingularities s{singularities};
  return detail::mergeCloseConesWith([&](VertexId v) { return mesh.position(v); }, topology, s, singularities.cones,
                                     options.maxDistance);
}

std::vector<std::pair<VertexId, VertexId>> coincidentConeEdges(const Topology& topology,
                                                               const std::vector<VertexId>& cones,
                                                               const WedgeMap& cornerUV) {
  std::vector<std::pair<VertexId, VertexId>> out;
  if (cornerUV.size() != std::size_t(topology.numCorners())) {
    throw InputError("coincidentConeEdges: the map has " + std::to_string(cornerUV.size()) +
                     " corners, the mesh " + std::to_string(topology.numCorners()));
  }
  std::vector<std::uint8_t> isCone(topology.numVertices(), 0);
  for (VertexId v : cones) isCone[v] = 1;
  for (VertexId v : cones) {
    topology.forEachCornerAround(v, [&](CornerId c) {
      // The edge v -> w of face(c), named by prev(c); each undirected edge once (from its smaller
      // vertex, or from v when the other side is the boundary).
      const CornerId edge = prevCorner(c);
      const CornerId n = nextCorner(c);
      const VertexId w = topology.vertex(n);
      if (!isCone[w] || (w < v && !topology.isBoundaryEdge(edge))) return;
      if ((cornerUV[c] - cornerUV[n]).norm() <= kCoincidentConeDistance) out.push_back({v, w});
    });
  }
  return out;
}

std::vector<std::pair<VertexId, VertexId>> coincidentCones(const TriangleMesh& mesh, const Topology& topology,
                                                           const std::vector<VertexId>& cones,
                                                           const WedgeMap& cornerUV, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> out = coincidentConeEdges(topology, cones, cornerUV);
  if (!(maxDistance > 0.0)) return out;
  // Cones grouped by the points their wedges map to (the map puts cones on lattice points, far
  // from the 1e-6 keys' borders), then one bounded search per cone that shares a point: the work
  // is the cones' wedges plus a ball per such cone, even when a whole unsolved component's cones
  // sit at (0, 0).
  struct Image {
    std::int64_t u, v;
    VertexId cone;
    Vec2d q;
  };
  std::vector<Image> images;
  constexpr double kKeyCell = 1e-6;
  for (VertexId v : cones) {
    topology.forEachCornerAround(v, [&](CornerId c) {
      const Vec2d q = cornerUV[c];
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
      const Ball ball = searchBall(mesh, topology, images[i].cone, maxDistance);
      for (std::size_t j = begin; j < end; ++j) {
        if (images[j].cone > images[i].cone && ball.distance.count(images[j].cone) &&
            (images[j].q - images[i].q).norm() <= kCoincidentConeDistance) {
          out.push_back({images[i].cone, images[j].cone});
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

ConeMergeResult mergeCoincidentCones(const TriangleMesh& mesh, const Topology& topology,
                                     FieldSingularities& singularities,
                                     const std::vector<std::pair<VertexId, VertexId>>& pairs,
                                     double maxDistance) {
  ConeMergeResult out;
  std::vector<std::int32_t>& index4 = singularities.index4;
  for (const auto& [a, b] : pairs) {
    if (a >= index4.size() || b >= index4.size()) {
      throw InputError("mergeCoincidentCones: vertex out of range");
    }
    if (!canMergeCoincident(index4[a], index4[b])) continue;
    const bool keepA = std::abs(index4[a]) >= std::abs(index4[b]);
    const VertexId keep = keepA ? a : b, gone = keepA ? b : a;
    // An adjacent pair is reached whatever maxDistance: through its own edge at worst.
    double reach = maxDistance;
    topology.forEachCornerAround(keep, [&](CornerId c) {
      if (topology.vertex(nextCorner(c)) == gone && !topology.isBoundaryEdge(prevCorner(c))) {
        reach = std::max(reach, (mesh.position(gone) - mesh.position(keep)).norm());
      }
    });
    if (!(reach > 0.0)) continue;
    const Ball ball = searchBall(mesh, topology, keep, reach, gone);
    if (!ball.pred.count(gone)) continue;  // farther than reach along interior edges
    std::vector<CornerId> path;
    for (VertexId y = gone; y != keep; y = topology.vertex(nextCorner(path.back()))) {
      path.push_back(ball.pred.at(y));
    }
    moveIndex(topology, singularities, keep, gone, path, out);
    out.longestPath = std::max(out.longestPath, ball.distance.at(gone));
  }
  dropVanishedCones(singularities);
  return out;
}

}  // namespace seamvox
