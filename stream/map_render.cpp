#include "stream/map_render.h"

#include <algorithm>
#include <memory>
#include <tuple>

#include "core/synth/render_canvas.h"
#include "core/system/errors.h"
#include "core/system/stopwatch.h"
#include "stream/corner_positions.h"
#include "stream/external_sort.h"
#include "stream/map_passes.h"
#include "stream/wound_count.h"

namespace seamvox {
namespace {

using namespace map_pass;
using namespace render_detail;

/// Faces handed to the rasterizer at once.
constexpr std::size_t kRasterChunk = std::size_t(1) << 14;

struct DrawnFace {  // a face drawn: corners, (u, v), input index
  float corner[3][3];
  double uv[3][2];
  std::uint32_t inputFace;
  Vec3d position(int j) const { return Vec3f(corner[j][0], corner[j][1], corner[j][2]).cast<double>(); }
  /// The normal cleanMesh glues the sides of an edge by.
  Vec3d normal() const { return gluingNormal(position(0), position(1), position(2)); }
};

/// The drawn faces, read back for the few corners that need them (seam edges, edges of more
/// than two sides, cones).
using DrawnFaces = RecordsByFace<DrawnFace>;

/// (u, v) of a side at the smaller and at the larger vertex of its edge.
std::pair<Vec2d, Vec2d> uvAtEnds(const EdgeRecord& side) {
  const Vec2d start = vec2(side.uvStart), end = vec2(side.uvEnd);
  return side.forward() ? std::make_pair(start, end) : std::make_pair(end, start);
}

}  // namespace

std::uint64_t mapRenderScratchBytes(std::uint64_t vertices, std::uint64_t faces, bool seamsOrCones) {
  // Faces and duplicate keys, the corner join (positions not in memory), and with seams or cones
  // the edge and corner runs and the geometry file: an upper bound of the peak.
  std::uint64_t perFace = sizeof(WeldKey) / 2 + sizeof(FaceRecord) + sizeof(DuplicateKey) +
                          3 * (sizeof(corner_detail::CornerRequest) + sizeof(corner_detail::CornerPosition));
  perFace += sizeof(DrawnFace);
  if (seamsOrCones) perFace += 3 * sizeof(EdgeRecord) + 3 * FanAngleSums<double>::kBytesPerSide;
  return vertices * sizeof(Vec3f) + faces * perFace;
}

MapRenderResult renderMapStream(MeshStream& stream, const MapRenderOptions& options) {
  const RenderOptions& render = options.render;
  checkOptions(render);
  const std::string& name = stream.name();
  const bool seamsOrCones = render.drawSeams || render.drawCones;
  ScratchFolder scratch(options.scratchParent,
                        mapRenderScratchBytes(stream.declaredVertices(), stream.expectedTriangles(), seamsOrCones));
  if (options.onScratch) options.onScratch(scratch);
  std::uint64_t sortMemory = options.memoryBytes / 4;  // up to four sorts alive at a time
  auto sortOptions = [&](const char* stage) {
    return ExternalSortOptions{std::max<std::uint64_t>(sortMemory, std::uint64_t(1) << 20), stage};
  };
  MapRenderResult result;
  SteadyClock::time_point start = SteadyClock::now();
  const SteadyClock::time_point begin = start;
  auto finishStage = [&](const char* stage) {
    result.stageSeconds.push_back({stage, secondsSince(start)});
    start = SteadyClock::now();
  };

  // Read: positions (in memory when they fit half the memory), faces, duplicate keys.
  CornerPositions positions(name, scratch, stream.declaredVertices(), options.memoryBytes / 2, sortOptions("corners"));
  if (positions.inMemory()) sortMemory -= std::min(sortMemory / 2, stream.declaredVertices() * sizeof(Vec3f) / 4);
  auto duplicateKeys = std::make_unique<ExternalSorter<DuplicateKey>>(scratch, sortOptions("duplicates"));
  std::unique_ptr<ExternalSorter<WeldKey>> weldKeys;
  if (options.weld && seamsOrCones) weldKeys = std::make_unique<ExternalSorter<WeldKey>>(scratch, sortOptions("weld"));
  const ReadPass read = readStream(stream, scratch, *duplicateKeys, positions, weldKeys.get());
  finishStage("read");
  // Welded ids for the edges and corners (faces keep theirs for the corner positions).
  std::vector<std::uint32_t> welded;
  if (weldKeys) {
    welded = weldMap(*weldKeys, read.vertices);
    weldKeys.reset();
    finishStage("weld");
  }
  const auto vertexId = [&](std::uint32_t v) { return welded.empty() ? v : welded[v]; };
  Duplicates duplicates = findDuplicateFaces(name, read, *duplicateKeys, scratch, sortOptions("duplicates"));
  duplicateKeys.reset();
  finishStage("duplicates");

  // Faces: the drawn ones (duplicates left out) with their corner positions, framed; their edges
  // and corners sorted for the seams and cones.
  FrameBuilder frame(render);
  std::unique_ptr<ExternalSorter<EdgeRecord>> edges;
  std::unique_ptr<FanAngleSums<double>> fans;  // the cones: each closed fan's angles, as cleaning splits fans
  if (seamsOrCones) edges = std::make_unique<ExternalSorter<EdgeRecord>>(scratch, sortOptions("edges"));
  if (render.drawCones) fans = std::make_unique<FanAngleSums<double>>(scratch, read.vertices, read.kept, sortOptions("cones"));
  ScratchFile drawnFile;
  {
    ScratchWriter drawn(scratch, "faces");
    forEachKeptFace(scratch, read, duplicates, positions, [&](const FaceRecord& face, const Vec3d (&p)[3]) {
      const std::uint64_t f = result.faces++;
      DrawnFace out{};
      for (int j = 0; j < 3; ++j) {
        const Vec3f q = p[j].cast<float>();
        frame.add(q);
        for (int k3 = 0; k3 < 3; ++k3) out.corner[j][k3] = q[k3];
        out.uv[j][0] = face.uv[j][0], out.uv[j][1] = face.uv[j][1];
      }
      out.inputFace = face.inputFace;
      drawn.write(&out, sizeof out);
      const std::uint32_t v[3] = {vertexId(face.v[0]), vertexId(face.v[1]), vertexId(face.v[2])};
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return;  // welded into a segment: not in the mesh
      for (int j = 0; edges && j < 3; ++j) {
        const int s = (j + 1) % 3, e = (j + 2) % 3;
        EdgeRecord edge(v[s], v[e], 3 * f + j);
        for (int k2 = 0; k2 < 2; ++k2) edge.uvStart[k2] = face.uv[s][k2], edge.uvEnd[k2] = face.uv[e][k2];
        if (fans) edge.startAngle = cornerAngle(vec2(face.uv[s]), vec2(face.uv[e]), vec2(face.uv[j]));
        edges->add(edge);
      }
    });
    drawnFile = drawn.finish();
  }
  duplicates.ranks.reset();
  scratch.remove(read.faces);
  const RenderCamera camera = frame.camera();
  result.render.camera = camera;
  finishStage("faces");

  // Rasterize chunk by chunk.
  const std::uint32_t ss = samplesPerPixel(render);
  SampleCanvas canvas(render.width * ss, render.height * ss, render.background);
  {
    ScratchReader faces(scratch, drawnFile, "raster");
    std::vector<ScreenFace> chunk;
    chunk.reserve(kRasterChunk);
    DrawnFace face;
    for (std::uint64_t f = 0; f < result.faces; ++f) {
      if (!faces.read(&face, sizeof face)) throw IoError(drawnFile.path + ": scratch faces end early");
      ScreenFace s;
      const Vec3d p[3] = {face.position(0), face.position(1), face.position(2)};
      for (int j = 0; j < 3; ++j) {
        s.corner[j] = toScreen(camera, ss, p[j]);
        s.uv[j] = vec2(face.uv[j]);
      }
      s.shade = faceShade(camera, p[0], p[1], p[2]);
      s.id = face.inputFace;
      chunk.push_back(s);
      if (chunk.size() == kRasterChunk || f + 1 == result.faces) {
        rasterizeFaces(chunk, render, canvas);
        chunk.clear();
        reportProgress(render.progress, "render", 0.1 + 0.6 * double(f + 1) / result.faces);
      }
    }
  }
  finishStage("raster");

  // Seams: the glued sides of every edge whose (u, v) differ, drawn from the smaller corner's
  // next vertex to its previous one (as in memory); every side goes to the fans.
  const double tolerance = lineTolerance(camera, ss);
  if (edges) {
    DrawnFaces drawn(scratch, drawnFile, "edges");
    edges->finish();
    std::vector<EdgeRecord> sides;
    std::vector<std::uint8_t> used;
    EdgeRecord edge;
    auto flush = [&] {
      bool clash = false;
      auto glued = glueSides(
          sides, [&](std::size_t i) { return drawn.at(sides[i].corner()).normal(); }, clash);
      if (fans) addSidesToFans(*fans, sides, glued, used);  // a clash's sides open their fans
      if (clash) glued.push_back({0, 1});  // in memory the faces are reoriented, then glued
      for (const auto& [x, y] : glued) {
        const auto [xLow, xHigh] = uvAtEnds(sides[x]);
        const auto [yLow, yHigh] = uvAtEnds(sides[y]);
        if (!render.drawSeams ||
            !(uvDiffer(xLow, yLow, render.seamTolerance) || uvDiffer(xHigh, yHigh, render.seamTolerance))) {
          continue;
        }
        ++result.render.seamEdges;
        const std::uint64_t c = sides[x].corner();
        const DrawnFace& face = drawn.at(c);
        const int j = static_cast<int>(c % 3);
        drawSegment(toScreen(camera, ss, face.position((j + 1) % 3)), toScreen(camera, ss, face.position((j + 2) % 3)),
                    0.5 * render.seamWidth * ss, tolerance, render.seamColor, canvas);
      }
      sides.clear();
    };
    while (edges->next(edge)) {
      if (!sides.empty() && sides[0].edge != edge.edge) flush();
      sides.push_back(edge);
    }
    if (!sides.empty()) flush();
    edges.reset();
  }
  finishStage("edges");
  drawLines(render, camera, ss, canvas);

  // Cones: closed fans whose corners' angles sum to 2 pi - k pi / 2, k != 0 (a bowtie vertex's
  // fans apart, as cleaning splits them).
  if (fans) {
    DrawnFaces drawn(scratch, drawnFile, "cones");
    std::vector<Vec3d> screen;
    fans->forEachClosedFan([&](const ClosedFan& fan) {
      const int turns = coneTurns(fan.angleSum);
      if (turns == kIrregularAngleSum) {
        ++result.render.irregularVertices;
      } else if (turns != 0) {
        result.render.cones.push_back({fan.vertex, turns});
        screen.push_back(toScreen(camera, ss, drawn.at(fan.corner).position(int(fan.corner % 3))));
      }
    });
    drawCones(result.render.cones, screen, render, ss, tolerance, canvas);
    fans.reset();
  }
  finishStage("cones");
  scratch.remove(drawnFile);
  downsample(canvas, ss, render, result.render);
  reportProgress(render.progress, "render", 1.0);
  result.render.seconds = secondsSince(begin);
  result.positionsInMemory = positions.inMemory();
  result.traffic = scratch.traffic();
  result.scratchPeakBytes = scratch.peakBytesOnDisk();
  return result;
}

}  // namespace seamvox
