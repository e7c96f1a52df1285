// seamvox render: checkerboard picture of a mesh's (u, v) map, with seams and cones.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/synth/render.h"
#include "io/mesh_io.h"
#include "io/png_io.h"
#include "io/polygon_io.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

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
  parseMemoryOptions(args);  // validated; this command runs in memory (out of core: issue 17)
  args.finish(1);
  requirePngPath("-o", *output);
  checkOutputPaths({{"MESH_WITH_UV", path}, {"--quads", quadsPath.value_or("")}}, {{"-o", *output}});
  if (quadsPath && formatFromPath(*quadsPath) != MeshFormat::Obj) {
    throw UsageError("--quads reads an OBJ polygon mesh (seamvox quads MAP -o Q.obj): " + *quadsPath);
  }

  const auto start = std::chrono::steady_clock::now();
  ReadOptions readOptions;
  readOptions.readUV = true;
  TriangleMesh mesh = readMesh(path, readOptions);
  if (!mesh.hasUV()) {
    throw InputError(path + ": has no texture coordinates; run seamvox param first");
  }
  cleanOptions.progress = progress;
  const CleanResult cleaned = cleanMeshOf(path, std::move(mesh), cleanOptions);
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
  const double secondsRead =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  options.progress = progress;
  // Depth ties go to the smaller input face, as out of core.
  const RenderResult result = renderCheckerboard(cleaned.mesh, cleaned.topology, options, cleaned.faceOrigin);
  const auto writeStart = std::chrono::steady_clock::now();
  writePng(*output, result.image);
  const double secondsWrite =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - writeStart).count();

  std::printf("wrote %s: %ux%u, %u faces, %.1f%% of the picture covered",
              output->c_str(), result.image.width, result.image.height, cleaned.mesh.numFaces(),
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
  std::printf("\n  read+clean %.2f s, render %.2f s, png %.2f s\n", secondsRead, result.seconds,
              secondsWrite);
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
                 SEAMVOX_MEMORY_HELP,
                 {"seams", "cones", "weld"},
                 &runRender});

}  // namespace seamvox::cli
