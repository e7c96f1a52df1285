#include "core/mesh/hole_caps.h"

#include <algorithm>

namespace seamvox {

CappedHoles capSmallHoles(const TriangleMesh& mesh, const Topology& topology, double maxExtent) {
  constexpr std::size_t kMaxLoop = 64;
  CappedHoles out;
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  std::vector<CornerId> loop;
  std::vector<VertexId> rim;
  std::vector<std::vector<CornerId>> caps;
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (!topology.isBoundaryEdge(start) || seen[start]) continue;
    loop.clear();
    BoundingBox box;
    bool small = true;
    for (CornerId c = start; loop.empty() || c != start; c = nextBoundaryCorner(topology, c)) {
      seen[c] = 1;
      loop.push_back(c);
      if (!small) continue;
      const Vec3d p = mesh.position(topology.vertex(prevCorner(c)));
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
      small = loop.size() <= kMaxLoop && box.diagonal() <= maxExtent;
    }
    if (!small || loop.size() < 3) continue;
    rim.clear();
    for (CornerId c : loop) rim.push_back(topology.vertex(prevCorner(c)));
    std::sort(rim.begin(), rim.end());
    if (std::adjacent_find(rim.begin(), rim.end()) != rim.end()) continue;  // a pinched loop
    caps.push_back(loop);
  }
  if (caps.empty()) return out;
  out.holes = static_cast<std::uint32_t>(caps.size());
  out.mesh.positions = mesh.positions;
  out.mesh.triangles = mesh.triangles;
  for (const std::vector<CornerId>& cap : caps) {
    Vec3d centre = Vec3d::Zero();
    for (CornerId c : cap) centre += mesh.position(topology.vertex(prevCorner(c)));
    const VertexId middle = static_cast<VertexId>(out.mesh.positions.size());
    out.mesh.positions.push_back((centre / double(cap.size())).cast<float>());
    // The boundary edge of corner c runs vertex(next c) -> vertex(prev c): the cap face runs back.
    for (CornerId c : cap) out.mesh.triangles.push_back({topology.vertex(prevCorner(c)), topology.vertex(nextCorner(c)), middle});
  }
  out.topology = Topology::build(out.mesh.triangles, out.mesh.numVertices());
  return out;
}

}  // namespace seamvox
