#include "core/mesh/hole_caps.h"

#include <algorithm>

namespace seamvox {

CappedHoles capSmallHoles(const TriangleMesh& mesh, const Topology& topology, double maxExtent) {
  constexpr std::size_t kMaxLoop = 64;
  CappedHoles out;
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  std::vector<CornerId> loop;
  std::vector<VertexId> rim;
  std::vector<std::pair<std::vector<CornerId>, Vec3d>> caps;  // loop and centroid
  // A loop that bounds most of its component is an island, not a hole: capping it would make a
  // closed pillow of zero volume.
  const ComponentsResult components = computeComponents(topology);
  std::vector<BoundingBox> componentBox(components.components.size());
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    BoundingBox& b = componentBox[components.faceComponent[f]];
    for (const VertexId v : mesh.triangles[f]) {
      b.min = b.min.cwiseMin(mesh.position(v));
      b.max = b.max.cwiseMax(mesh.position(v));
    }
  }
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
    if (!(componentBox[components.faceComponent[cornerFace(start)]].diagonal() > 4.0 * box.diagonal())) continue;
    rim.clear();
    for (CornerId c : loop) rim.push_back(topology.vertex(prevCorner(c)));
    std::sort(rim.begin(), rim.end());
    if (std::adjacent_find(rim.begin(), rim.end()) != rim.end()) continue;  // a pinched loop
    // No cap face may be degenerate (a crack whose two sides coincide, a sliver): it would make
    // the solve singular.
    Vec3d centre = Vec3d::Zero();
    for (CornerId c : loop) centre += mesh.position(topology.vertex(prevCorner(c)));
    centre /= double(loop.size());
    const double minArea = 1e-6 * box.diagonal() * box.diagonal();
    bool flat = false;
    for (CornerId c : loop) {
      const Vec3d a = mesh.position(topology.vertex(nextCorner(c))), b = mesh.position(topology.vertex(prevCorner(c)));
      flat = flat || !(0.5 * (a - centre).cross(b - centre).norm() > minArea);
    }
    if (!flat) caps.emplace_back(loop, centre);
  }
  if (caps.empty()) return out;
  out.holes = static_cast<std::uint32_t>(caps.size());
  out.mesh.positions = mesh.positions;
  out.mesh.triangles = mesh.triangles;
  for (const auto& [cap, centre] : caps) {
    const VertexId middle = static_cast<VertexId>(out.mesh.positions.size());
    out.mesh.positions.push_back(centre.cast<float>());
    // The boundary edge of corner c runs vertex(next c) -> vertex(prev c): the cap face runs back.
    for (CornerId c : cap) out.mesh.triangles.push_back({topology.vertex(prevCorner(c)), topology.vertex(nextCorner(c)), middle});
  }
  out.topology = Topology::build(out.mesh.triangles, out.mesh.numVertices());
  return out;
}

}  // namespace seamvox
