#include "core/mesh/hole_caps.h"

#include <algorithm>

namespace seamvox {

CappedHoles capSmallHoles(TriangleMesh& mesh, Topology& topology, double maxExtent) {
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
  out.faces = mesh.numFaces();
  out.vertices = mesh.numVertices();
  // The caps' faces first (the corner table views the faces, whose array may move when it grows).
  std::vector<Triangle> added;
  std::vector<Vec3f> centres;
  std::vector<std::pair<CornerId, CornerId>> glued;
  for (const auto& [cap, centre] : caps) {
    const VertexId middle = static_cast<VertexId>(mesh.positions.size() + centres.size());
    centres.push_back(centre.cast<float>());
    // The boundary edge of corner c runs A = vertex(next c) -> B = vertex(prev c): the cap face
    // B, A, centre runs back along it (its centre corner faces c), and its edge centre -> B meets
    // the next cap face's B -> centre.
    const FaceId first = mesh.numFaces() + static_cast<FaceId>(added.size());
    for (std::size_t k = 0; k < cap.size(); ++k) {
      const CornerId c = cap[k];
      const FaceId g = first + static_cast<FaceId>(k), h = first + static_cast<FaceId>((k + 1) % cap.size());
      added.push_back({topology.vertex(prevCorner(c)), topology.vertex(nextCorner(c)), middle});
      glued.push_back({3 * g + 2, c});
      glued.push_back({3 * g + 1, 3 * h});
    }
  }
  // Exact allocations: a growing vector would double the mesh's arrays.
  mesh.positions.reserve(mesh.positions.size() + centres.size());
  mesh.positions.insert(mesh.positions.end(), centres.begin(), centres.end());
  mesh.triangles.reserve(mesh.triangles.size() + added.size());
  mesh.triangles.insert(mesh.triangles.end(), added.begin(), added.end());
  out.fanStarts = topology.extend(mesh.triangles, mesh.numVertices(), glued);
  return out;
}

void uncapHoles(TriangleMesh& mesh, Topology& topology, const CappedHoles& caps) {
  if (caps.holes == 0) return;
  mesh.triangles.resize(caps.faces);
  mesh.positions.resize(caps.vertices);
  topology.shrink(mesh.triangles, caps.faces, caps.vertices, caps.fanStarts);
}

}  // namespace seamvox
