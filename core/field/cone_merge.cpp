#include "core/field/cone_merge.h"

#include "core/field/detail_cone_merge.h"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <queue>
#include <string>
#include <unordered_map>

#include "core/system/errors.h"
#include "core/quality/metrics.h"

namespace seamvox {
namespace {

/// The in-memory singularities for detail::mergeCloseConesWith and detail::moveIndex.
struct MemorySingularities {
  FieldSingularities& s;
  std::int32_t index(VertexId v) const { return s.index4[v]; }
  void setIndex(VertexId v, std::int32_t k) { s.index4[v] = k; }
  std::uint8_t matching(CornerId c) const { return s.matching[c]; }
  void setMatching(CornerId c, std::uint8_t m) { s.matching[c] = m; }
};

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
                                     options.maxDistance, true);
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
  if (cornerUV.size() != std::size_t(topology.numCorners())) {
    throw InputError("coincidentCones: the map has " + std::to_string(cornerUV.size()) + " corners, the mesh " +
                     std::to_string(topology.numCorners()));
  }
  std::vector<VertexId> sorted = cones;
  std::sort(sorted.begin(), sorted.end());
  return detail::coincidentConesWith([&](VertexId v) { return mesh.position(v); }, topology,
                                     [&](CornerId c) { return cornerUV[c]; }, sorted, maxDistance);
}

std::vector<std::pair<VertexId, VertexId>> closeCones(const TriangleMesh& mesh, const Topology& topology,
                                                      const std::vector<VertexId>& cones, double maxDistance) {
  std::vector<VertexId> sorted = cones;
  std::sort(sorted.begin(), sorted.end());
  return detail::closeConesWith([&](VertexId v) { return mesh.position(v); }, topology, sorted, maxDistance);
}

std::vector<std::pair<VertexId, VertexId>> foldedCloseCones(const TriangleMesh& mesh, const Topology& topology,
                                                            const std::vector<VertexId>& cones,
                                                            const std::vector<std::int32_t>& index4,
                                                            const WedgeMap& cornerUV, double h, double maxDistance) {
  if (index4.size() != cones.size() || cornerUV.size() != std::size_t(topology.numCorners())) {
    throw InputError("foldedCloseCones: " + std::to_string(index4.size()) + " indices for " +
                     std::to_string(cones.size()) + " cones, a map of " + std::to_string(cornerUV.size()) +
                     " corners for " + std::to_string(topology.numCorners()));
  }
  std::vector<std::pair<VertexId, std::int32_t>> byVertex;
  for (std::size_t k = 0; k < cones.size(); ++k) byVertex.push_back({cones[k], index4[k]});
  std::sort(byVertex.begin(), byVertex.end());
  std::vector<VertexId> sorted;
  for (const auto& [v, k] : byVertex) sorted.push_back(v);
  const auto indexOf = [&](VertexId v) {
    return std::lower_bound(byVertex.begin(), byVertex.end(), std::make_pair(v, INT32_MIN))->second;
  };
  const auto fanFlipped = [&](VertexId v) {
    bool flipped = false;
    topology.forEachCornerAround(
        v, [&](CornerId c) { flipped |= isFlippedRatio(parameterAreaRatio(mesh, cornerUV, cornerFace(c), h)); });
    return flipped;
  };
  return detail::foldedCloseConesWith([&](VertexId v) { return mesh.position(v); }, topology, sorted, indexOf,
                                      fanFlipped, maxDistance);
}

ConeMergeResult mergeCoincidentCones(const TriangleMesh& mesh, const Topology& topology,
                                     FieldSingularities& singularities,
                                     const std::vector<std::pair<VertexId, VertexId>>& pairs,
                                     double maxDistance) {
  for (const auto& [a, b] : pairs) {
    if (a >= singularities.index4.size() || b >= singularities.index4.size()) {
      throw InputError("mergeCoincidentCones: vertex out of range");
    }
  }
  MemorySingularities s{singularities};
  return detail::mergeCoincidentConesWith([&](VertexId v) { return mesh.position(v); }, topology, s,
                                          singularities.cones, pairs, maxDistance);
}

}  // namespace seamvox
