#include "core/quads/checked.h"

#include <algorithm>

#include "core/system/errors.h"

namespace seamvox {

std::uint64_t fillSmallHoles(const TriangleMesh& mesh, const Topology& topology, std::int64_t scale,
                             TriangleMesh& out) {
  constexpr std::size_t kMaxLoop = 32;
  const double span = static_cast<double>(std::max<std::int64_t>(scale, 1));
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  std::vector<CornerId> loop;  // boundary corners, in order
  std::vector<std::vector<CornerId>> holes;
  // A component hardly larger than its loop is an island, not a surface with a hole: left open.
  std::vector<std::uint32_t> component;
  std::vector<BoundingBox> extent;
  auto componentExtent = [&](FaceId f) -> const BoundingBox& {
    if (component.empty()) {
      component = computeComponents(topology).faceComponent;
      for (FaceId g = 0; g < mesh.numFaces(); ++g) {
        if (component[g] >= extent.size()) extent.resize(component[g] + 1);
        for (const VertexId v : mesh.triangles[g]) {
          extent[component[g]].min = extent[component[g]].min.cwiseMin(mesh.position(v));
          extent[component[g]].max = extent[component[g]].max.cwiseMax(mesh.position(v));
        }
      }
    }
    return extent[component[f]];
  };
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (topology.opposite(start) != kInvalidId || seen[start]) continue;
    // Walk the loop: the edge of boundary corner c runs vertex(next c) -> vertex(prev c); the next
    // boundary edge leaves vertex(prev c), found by turning around it through interior edges.
    loop.clear();
    bool oneChart = true, closed = false;
    CornerId c = start;
    for (std::size_t steps = 0; steps < kMaxLoop + 1; ++steps) {
      seen[c] = 1;
      loop.push_back(c);
      const CornerId atEnd = prevCorner(c);  // the corner at vertex(prev c) in c's face
      CornerId d = atEnd, e = prevCorner(d);
      for (std::size_t turns = 0; topology.opposite(e) != kInvalidId && turns < 4096; ++turns) {
        d = prevCorner(topology.opposite(e));
        e = prevCorner(d);
      }
      if (topology.opposite(e) != kInvalidId) break;  // a fan that does not end: not a plain hole
      oneChart = oneChart && mesh.cornerUV[d] == mesh.cornerUV[atEnd];
      c = e;
      if (c == start) {
        closed = true;
        break;
      }
      if (seen[c]) break;
    }
    if (!closed || !oneChart || loop.size() > kMaxLoop) continue;
    Vec2d lo = mesh.cornerUV[nextCorner(loop[0])], hi = lo;
    BoundingBox around;
    for (const CornerId b : loop) {
      lo = lo.cwiseMin(mesh.cornerUV[nextCorner(b)]);
      hi = hi.cwiseMax(mesh.cornerUV[nextCorner(b)]);
      around.min = around.min.cwiseMin(mesh.position(topology.vertex(nextCorner(b))));
      around.max = around.max.cwiseMax(mesh.position(topology.vertex(nextCorner(b))));
    }
    if (!((hi - lo).maxCoeff() < span)) continue;
    if (!(componentExtent(cornerFace(start)).diagonal() > 4.0 * around.diagonal())) continue;
    // Every face of the fan must turn the way the map's faces do (a star-shaped hole in (u, v)).
    Vec2d centre = Vec2d::Zero();
    for (const CornerId b : loop) centre += mesh.cornerUV[nextCorner(b)];
    centre /= double(loop.size());
    const bool starShaped = std::all_of(loop.begin(), loop.end(), [&](CornerId b) {
      const Vec2d p = mesh.cornerUV[prevCorner(b)], q = mesh.cornerUV[nextCorner(b)];
      const Vec2d x = q - p, y = centre - p;
      return x.x() * y.y() - x.y() * y.x() > 0.0;
    });
    if (starShaped) holes.push_back(loop);
  }
  if (holes.empty()) return 0;
  // The copy keeps the map's wedges (4 bytes per corner) and adds the fans' corners to them.
  out.positions = mesh.positions;
  out.triangles = mesh.triangles;
  std::vector<std::uint32_t> wedge(mesh.cornerUV.size());
  for (CornerId k = 0; k < wedge.size(); ++k) wedge[k] = mesh.cornerUV.wedge(k);
  std::vector<Vec2d> value(mesh.cornerUV.numWedges());
  for (std::uint32_t w = 0; w < value.size(); ++w) value[w] = mesh.cornerUV.wedgeValue(w);
  for (const std::vector<CornerId>& hole : holes) {
    Vec3d centre = Vec3d::Zero();
    Vec2d centreUV = Vec2d::Zero();
    for (const CornerId b : hole) {
      centre += mesh.position(topology.vertex(nextCorner(b)));
      centreUV += mesh.cornerUV[nextCorner(b)];
    }
    const VertexId middle = static_cast<VertexId>(out.positions.size());
    out.positions.push_back((centre / double(hole.size())).cast<float>());
    const std::uint32_t middleWedge = static_cast<std::uint32_t>(value.size());
    value.push_back(centreUV / double(hole.size()));
    for (const CornerId b : hole) {  // the surface's edge a -> b closed by the face b -> a -> centre
      out.triangles.push_back({topology.vertex(prevCorner(b)), topology.vertex(nextCorner(b)), middle});
      wedge.push_back(mesh.cornerUV.wedge(prevCorner(b)));
      wedge.push_back(mesh.cornerUV.wedge(nextCorner(b)));
      wedge.push_back(middleWedge);
    }
  }
  out.cornerUV = WedgeMap(std::move(wedge), std::move(value));
  return holes.size();
}

QuadRun extractCheckedQuads(const std::string& name, const TriangleMesh& mesh, const Topology& topology,
                            std::int64_t scale, const ProgressFn& progress) {
  if (!mesh.hasUV()) throw InputError(name + ": has no texture coordinates; run seamvox param first");
  QuadRun run;
  run.seams = measureSeamsFromUV(mesh, topology, mesh.cornerUV);
  const SeamQuality& seams = run.seams;
  if (!seams.isSeamless(kQuadSeamTolerance)) {
    throw InputError(name + ": the map is not seamless (seam residual " + std::to_string(seams.maxResidual) +
                     ", translations " + std::to_string(seams.maxIntegerDistance) +
                     " from integers, at the edge of corner " + std::to_string(seams.worstEdgeCorner) +
                     "); quads needs the integer-grid map of seamvox param");
  }
  QuadOptions options;
  options.scale = scale;
  options.progress = progress;
  TriangleMesh filled;
  run.filledHoles = fillSmallHoles(mesh, topology, scale, filled);
  const Topology filledTopology =
      run.filledHoles ? Topology::build(filled.triangles, filled.numVertices()) : Topology();
  const TriangleMesh& map = run.filledHoles ? filled : mesh;
  const Topology& mapTopology = run.filledHoles ? filledTopology : topology;
  try {
    run.quads = extractQuads(map, mapTopology, options);
  } catch (...) {
    rethrowWithContext(name);
  }
  if (run.quads.stats.seamEdgesOffScale > 0) {
    // A seam maps u = K m onto u' = +-K m + t: the coarse lines continue only when K divides t.
    // Rounding makes t any integer, so this holds only for maps rounded to multiples of K.
    throw InputError(name + ": " + std::to_string(run.quads.stats.seamEdgesOffScale) +
                     " seam translations are no multiples of --scale " + std::to_string(scale) +
                     " (seam edges), so iso-lines every " + std::to_string(scale) +
                     " units would not continue across the seams: seamvox param rounds translations to "
                     "any integers; for a coarser quad mesh, map with an edge length " + std::to_string(scale) +
                     " times larger (--edge-length, --cells) and extract without --scale");
  }
  run.check = validateQuads(run.quads, computeComponents(mapTopology));
  return run;
}

}  // namespace seamvox
