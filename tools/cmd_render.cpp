// seamvox render: checkerboard picture of a mesh's (u, v) map, with seams and cones.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "core/synth/render.h"
#include "core/synth/render_canvas.h"
#include "io/mesh_io.h"
#include "io/png_io.h"
#include "io/polygon_io.h"
#include "stream/map_render.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

// Measured peak of the in-memory render: 48 MiB for the program, about 70 B per face of a
// 1M-face and a 22M-face map (read, cleaned, its topology), plus the canvas; rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 80;

/// Bytes of the supersampled canvas (key and colour per sample) and the output image.
std::uint64_t canvasBytes(const RenderOptions& options) {
  const std::uint64_t ss = render_detail::samplesPerPixel(options);
  return std::uint64_t(options.width) * options.height * (ss * ss * 11 + 3);
}

std::string formatSeconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", seconds);
  return text;
}

/// Parses "A<sep>B" into two numbers, or throws UsageError naming the option.
std::pair<double, double> parsePair(const std::string& text, char separator, const char* option) {
  const auto at = text.find(separator);
  std::size_t used1 = 0, used2 = 0;
  try {
    if (at == std::string::npos) throw std::invalid_argument("no separator");
    const std::string first = text.substr(0, at), second = text.substr(at + 1);
    const double a = std::stod(first, &used1), b = std::stod(second, &used2);
    if (used1 != first.size() || used2 != second.size()) throw std::invalid_argument("trailing");
    return {a, b};
  } catch (const std::exception&) {
    throw UsageError(std::string("--") + option + " expects A" + separator + "B, got '" + text + "'");
  }
}

int runRender(Args& args) {
  const std::string path = args.positional(0, "the mesh file (seamvox render MESH -o OUT.png)");
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT.png");
  RenderOptions options;
  if (const auto size = args.value("size")) {
    const auto [w, h] = parsePair(*size, 'x', "size");
    if (!(w >= 1 && w <= 8192 && h >= 1 && h <= 8192) || w != std::floor(w) || h != std::floor(h)) {
      throw UsageError("--size must be WxH with whole numbers in 1..8192, got '" + *size + "'");
    }
    options.width = static_cast<std::uint32_t>(w);
    options.height = static_cast<std::uint32_t>(h);
  }
  if (const auto view = args.value("view")) {
    std::tie(options.azimuth, options.elevation) = parsePair(*view, ',', "view");
    if (!std::isfinite(options.azimuth) || !std::isfinite(options.elevation)) {
      throw UsageError("--view angles must be finite");
    }
  }
  const std::string up = args.value("up", "y");
  if (up != "x" && up != "y" && up != "z") throw UsageError("--up must be x, y or z");
  options.upAxis = up[0] - 'x';
  options.checker = args.positiveNumber("checker", 1.0);
  const std::int64_t supersample = args.integer("supersample", 2, 1, 4);
  options.supersample = static_cast<std::uint32_t>(supersample);
  options.drawSeams = args.flag("seams");
  options.drawCones = args.flag("cones");
  const auto quadsPath = args.value("quads");
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = args.flag("weld");
  const bool quiet = args.flag("quiet");
  const ProgressFn progress = makeProgress(quiet);
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(1);
  requirePngPath("-o", *output);
  checkOutputPaths({{"MESH_WITH_UV", path}, {"--quads", quadsPath.value_or("")}}, {{"-o", *output}});
  if (quadsPath && formatFromPath(*quadsPath) != MeshFormat::Obj) {
    throw UsageError("--quads reads an OBJ polygon mesh (seamvox quads MAP -o Q.obj): " + *quadsPath);
  }

  const auto start = std::chrono::steady_clock::now();
  if (quadsPath) {  // the quad mesh's edges over a plain surface
    const PolygonMesh quads = readPolygonObj(*quadsPath);
    for (std::uint32_t f = 0; f < quads.numFaces(); ++f) {
      for (std::uint32_t i = quads.faceStart[f]; i < quads.faceStart[f + 1]; ++i) {
        const std::uint32_t j = i + 1 < quads.faceStart[f + 1] ? i + 1 : quads.faceStart[f];
        options.lines.push_back({quads.positions[quads.faceVertices[i]], quads.positions[quads.faceVertices[j]]});
      }
    }
    options.dark = options.light;
  }
  MemoryPath memoryPath;
  memoryPath.budget = memory.budget;
  const std::uint64_t fixedBytes = kProgramBytes + canvasBytes(options);
  refuseDracoInputAboveBudget(path, memory.budget, fixedBytes, kBytesPerFace,
                              "convert it to PLY (seamvox convert " + path + " OUT.ply) or raise --memory-budget");
  ReadOptions readOptions;
  readOptions.readUV = true;
  const std::unique_ptr<MeshStream> stream = openMeshStream(path, readOptions);
  memoryPath.estimate = fixedBytes + guessMeshCounts(path, *stream).faces * kBytesPerFace;
  memoryPath.outOfCore = memoryPath.estimate > memory.budget;
  options.progress = progress;
  RenderResult result;
  std::uint64_t faces = 0;
  double secondsRead = 0.0;
  std::string stages;  // out of core: seconds per pass
  if (!memoryPath.outOfCore) {
    TriangleMesh mesh = collectMesh(*stream);
    if (!mesh.hasUV()) {
      throw InputError(path + ": has no texture coordinates; run seamvox param first");
    }
    cleanOptions.progress = progress;
    const CleanResult cleaned = cleanMeshOf(path, std::move(mesh), cleanOptions);
    secondsRead = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // Depth ties go to the smaller input face, as out of core.
    result = renderCheckerboard(cleaned.mesh, cleaned.topology, options, cleaned.faceOrigin);
    faces = cleaned.mesh.numFaces();
  } else {
    MapRenderOptions ooc;
    ooc.render = options;
    ooc.weld = cleanOptions.weldVertices;
    const std::uint64_t program = currentResidentBytes() + canvasBytes(options);
    ooc.memoryBytes = memory.budget > program ? memory.budget - program : 0;
    if (ooc.memoryBytes < (std::uint64_t(4) << 20)) {
      std::fprintf(stderr, "seamvox render: the budget %s is below what the program and the canvas hold (%s) and 4 MiB for the sorts: running with that minimum (a smaller --size or --supersample 1 needs less)\n",
                   formatByteSize(memory.budget).c_str(), formatByteSize(program).c_str());
    }
    ooc.scratchParent = memory.scratch;
    MapRenderResult rendered = renderMapStream(*stream, ooc);
    result = std::move(rendered.render);
    faces = rendered.faces;
    memoryPath.traffic = rendered.traffic;
    for (const auto& [stage, seconds] : rendered.stageSeconds) stages += (stages.empty() ? "" : ", ") + stage + " " + formatSeconds(seconds);
    memoryPath.scratchPeakBytes = rendered.scratchPeakBytes;
  }
  const auto writeStart = std::chrono::steady_clock::now();
  writePng(*output, result.image);
  const double secondsWrite =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - writeStart).count();

  std::printf("wrote %s: %ux%u, %llu faces, %.1f%% of the picture covered",
              output->c_str(), result.image.width, result.image.height, static_cast<unsigned long long>(faces),
              100.0 * double(result.coveredPixels) / (double(result.image.width) * result.image.height));
  if (quadsPath) std::printf(", %zu quad-mesh edges drawn", options.lines.size() / 2);
  if (options.drawSeams) std::printf(", %llu seam edges", static_cast<unsigned long long>(result.seamEdges));
  if (options.drawCones) {
    std::size_t positive = 0;
    for (const RenderCone& cone : result.cones) positive += cone.quarterTurns > 0;
    std::printf(", %zu cones (%zu positive, %zu negative)", result.cones.size(), positive,
                result.cones.size() - positive);
    if (result.irregularVertices) {
      std::printf(", %llu vertices where the map is not seamless (angle sum no multiple of 90 "
                  "degrees)", static_cast<unsigned long long>(result.irregularVertices));
    }
  }
  if (memoryPath.outOfCore) {
    std::printf("\n  read and render %.2f s (%s), png %.2f s\n", result.seconds, stages.c_str(), secondsWrite);
  } else {
    std::printf("\n  read+clean %.2f s, render %.2f s, png %.2f s\n", secondsRead, result.seconds, secondsWrite);
  }
  std::printf("%s\n", describeMemoryPath(memoryPath).c_str());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"render", "checkerboard picture (PNG) of a mesh's texture coordinates",
                 "usage: seamvox render MESH_WITH_UV -o OUT.png [--size WxH] [--view AZ,EL]\n"
                 "                      [--checker K] [--seams] [--cones] [--up x|y|z]\n"
                 "                      [--quads Q.obj]\n"
                 "\n"
                 "Reads MESH (.ply .obj .off .drc with per-corner texture coordinates, e.g. written\n"
                 "by seamvox param), cleans it and renders it headless: a shaded checkerboard in\n"
                 "(u, v), orthographic, framing the whole mesh.\n"
                 "\n"
                 "  -o OUT.png         the picture (8-bit RGB PNG)\n"
                 "  --size WxH         picture size in pixels (default 1024x1024, at most 8192)\n"
                 "  --view AZ,EL       azimuth and elevation in degrees around the bounding-box\n"
                 "                     centre (default 30,20; 0,90 looks straight down the up axis)\n"
                 "  --up x|y|z         the axis that points up in the picture (default y)\n"
                 "  --checker K        checker cells per unit of u and v (default 1)\n"
                 "  --seams            draw seams (edges whose sides have different (u, v)) in orange\n"
                 "  --cones            draw cones (vertices where the map turns by a multiple of 90\n"
                 "                     degrees): red positive index, blue negative\n"
                 "  --quads Q.obj      draw the edges of a quad mesh of the map (seamvox quads) over\n"
                 "                     the plain shaded surface instead of the checkerboard\n"
                 "  --supersample N    N x N samples per pixel (default 2; 1 = no anti-aliasing)\n"
                 "  --weld             weld coincident vertices (files whose vertices are split\n"
                 "                     along seams: otherwise those seams show as open boundary)\n"
                 "  --quiet            no progress on stderr\n"
                 "\n"
                 "A map whose in-memory render would exceed the budget (48 MiB + 80 B per face + the\n"
                 "canvas, from the header's counts) is rendered out of core: streamed once, its faces\n"
                 "kept in a scratch folder and rasterized in chunks, seams and cones found by external\n"
                 "sorts; the same picture. The last line says which path ran.\n"
                 SEAMVOX_MEMORY_HELP,
                 {"seams", "cones", "weld"},
                 &runRender});

}  // namespace seamvox::cli
