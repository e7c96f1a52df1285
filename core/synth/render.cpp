#include "core/synth/render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "core/synth/render_canvas.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

using namespace render_detail;

Vec2d RenderCamera::project(const Vec3d& p) const {
  const Vec3d d = p - center;
  return {0.5 * width + d.dot(right) * pixelsPerUnit, 0.5 * height - d.dot(up) * pixelsPerUnit};
}

RenderCamera frameMesh(const TriangleMesh& mesh, const RenderOptions& options) {
  FrameBuilder frame(options);
  frame.addAll(mesh.positions);
  return frame.camera();
}

std::vector<CornerId> findSeamEdges(const TriangleMesh& mesh, const Topology& topology,
                                    double tolerance) {
  const std::uint64_t numCorners = topology.numCorners();
  std::vector<std::uint8_t> isSeam(numCorners, 0);
  auto differ = [&](CornerId p, CornerId q) { return uvDiffer(mesh.cornerUV[p], mesh.cornerUV[q], tolerance); };
  parallelForEach(numCorners, 1 << 14, [&](std::uint64_t ci) {
    const CornerId c = static_cast<CornerId>(ci);
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId || o < c) return;
    // The edge of c runs vertex(next c) -> vertex(prev c); o traverses it the other way.
    isSeam[c] = differ(nextCorner(c), prevCorner(o)) || differ(prevCorner(c), nextCorner(o));
  });
  std::vector<CornerId> seams;
  for (CornerId c = 0; c < numCorners; ++c) {
    if (isSeam[c]) seams.push_back(c);
  }
  return seams;
}

MapCones findMapCones(const TriangleMesh& mesh, const Topology& topology, double angleTolerance) {
  std::vector<std::int8_t> turns(topology.numVertices(), 0);
  parallelForEach(turns.size(), 1 << 13, [&](std::uint64_t vi) {
    const VertexId v = static_cast<VertexId>(vi);
    if (topology.isIsolatedVertex(v) || topology.isBoundaryVertex(v)) return;
    double angleSum = 0.0;
    topology.forEachCornerAround(v, [&](CornerId c) {
      angleSum += cornerAngle(mesh.cornerUV[c], mesh.cornerUV[nextCorner(c)], mesh.cornerUV[prevCorner(c)]);
    });
    turns[v] = static_cast<std::int8_t>(coneTurns(angleSum, angleTolerance));
  });
  MapCones result;
  for (VertexId v = 0; v < turns.size(); ++v) {
    if (turns[v] == kIrregularAngleSum) {
      ++result.irregularVertices;
    } else if (turns[v] != 0) {
      result.cones.push_back({v, turns[v]});
    }
  }
  return result;
}

RenderResult renderCheckerboard(const TriangleMesh& mesh, const Topology& topology, const RenderOptions& options,
                                const std::vector<FaceId>& faceIds) {
  const auto start = std::chrono::steady_clock::now();
  checkOptions(options);
  if (!mesh.hasUV()) {
    throw InputError("mesh has no texture coordinates; run seamvox param first");
  }
  if (mesh.cornerUV.size() != 3 * std::size_t(mesh.numFaces())) {
    throw InputError("mesh has " + std::to_string(mesh.cornerUV.size()) +
                     " corner (u, v) entries for " + std::to_string(mesh.numFaces()) +
                     " faces (expected 3 per face)");
  }
  if ((options.drawSeams || options.drawCones) && topology.numFaces() != mesh.numFaces()) {
    throw InputError("render: the topology has " + std::to_string(topology.numFaces()) +
                     " faces, the mesh " + std::to_string(mesh.numFaces()));
  }
  if (!faceIds.empty() && faceIds.size() != mesh.numFaces()) {
    throw InputError("render: " + std::to_string(faceIds.size()) + " face ids for " +
                     std::to_string(mesh.numFaces()) + " faces");
  }
  RenderResult result;
  result.camera = frameMesh(mesh, options);
  const RenderCamera& camera = result.camera;
  const std::uint32_t ss = samplesPerPixel(options);
  SampleCanvas canvas(options.width * ss, options.height * ss, options.background);
  const auto screenOf = [&](VertexId v) { return toScreen(camera, ss, mesh.position(v)); };
  // Faces chunk by chunk, as the out-of-core renderer hands them over.
  constexpr FaceId kChunk = FaceId(1) << 16;
  std::vector<ScreenFace> chunk;
  for (FaceId begin = 0; begin < mesh.numFaces(); begin += std::min(kChunk, mesh.numFaces() - begin)) {
    chunk.resize(std::min(kChunk, mesh.numFaces() - begin));
    parallelForEach(chunk.size(), 4096, [&](std::uint64_t i) {
      const FaceId f = begin + FaceId(i);
      const Triangle& t = mesh.triangles[f];
      ScreenFace& face = chunk[i];
      for (int k = 0; k < 3; ++k) {
        face.corner[k] = screenOf(t[k]);
        face.uv[k] = mesh.cornerUV[3 * std::size_t(f) + k];
      }
      face.shade = faceShade(camera, mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2]));
      face.id = faceIds.empty() ? f : faceIds[f];
    });
    rasterizeFaces(chunk, options, canvas);
    reportProgress(options.progress, "render", 0.1 + 0.7 * double(begin + chunk.size()) / mesh.numFaces());
  }

  const double tolerance = lineTolerance(camera, ss);
  if (options.drawSeams) {
    const std::vector<CornerId> seams = findSeamEdges(mesh, topology, options.seamTolerance);
    result.seamEdges = seams.size();
    for (const CornerId c : seams) {
      drawSegment(screenOf(topology.vertex(nextCorner(c))), screenOf(topology.vertex(prevCorner(c))),
                  0.5 * options.seamWidth * ss, tolerance, options.seamColor, canvas);
    }
  }
  drawLines(options, camera, ss, canvas);
  if (options.drawCones) {
    MapCones found = findMapCones(mesh, topology);
    result.cones = std::move(found.cones);
    result.irregularVertices = found.irregularVertices;
    std::vector<Vec3d> screen;
    for (const RenderCone& cone : result.cones) screen.push_back(screenOf(cone.vertex));
    drawCones(result.cones, screen, options, ss, tolerance, canvas);
  }
  downsample(canvas, ss, options, result);
  reportProgress(options.progress, "render", 1.0);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace seamvox
