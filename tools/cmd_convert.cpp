// seamvox convert: rewrites a mesh in another format, keeping per-corner UVs and vertex
// properties where the output format can hold them.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

std::uint64_t fileBytes(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0 : static_cast<std::uint64_t>(size);
}

int runConvert(Args& args) {
  const std::string input = args.positional(0, "the input mesh (seamvox convert IN OUT)");
  const std::string output = args.positional(1, "the output mesh (seamvox convert IN OUT)");
  if (formatFromPath(output) == MeshFormat::Unknown) {
    throw UsageError("unknown output format (use .ply, .obj, .off or .drc): " + output);
  }
  WriteOptions options;
  const std::int64_t uvBits = args.integer("uv-bits", options.dracoUVBits, 0, 23);  // 0: lossless
  const std::int64_t positionBits = args.integer("position-bits", options.dracoPositionBits, 0, 30);
  options.dracoUVBits = static_cast<int>(uvBits);
  options.dracoPositionBits = static_cast<int>(positionBits);
  options.binary = !args.flag("ascii");
  options.writeUV = !args.flag("no-uv");
  const bool ratio = args.flag("ratio");
  parseMemoryOptions(args);  // validated; this command runs in memory (out of core: issue 17)
  args.finish(2);
  checkOutputPaths({{"IN", input}}, {{"OUT", output}});

  const auto start = std::chrono::steady_clock::now();
  ReadOptions readOptions;
  readOptions.readUV = options.writeUV;
  const TriangleMesh mesh = readMesh(input, readOptions);
  const auto read = std::chrono::steady_clock::now();
  writeMesh(output, mesh, options);
  const auto written = std::chrono::steady_clock::now();
  const std::uint64_t bytes = fileBytes(output);

  const std::string properties =
      mesh.attributes.empty() ? "" : ", vertex properties " + mesh.attributes.describe();
  std::printf("%s -> %s: %u faces, %u vertices, %s%s, %llu bytes (read %.2f s, write %.2f s)\n",
              input.c_str(), output.c_str(), mesh.numFaces(), mesh.numVertices(),
              mesh.hasUV() ? "per-corner UVs" : "no UVs", properties.c_str(), static_cast<unsigned long long>(bytes),
              std::chrono::duration<double>(read - start).count(),
              std::chrono::duration<double>(written - read).count());
  if (mesh.hasUV() && options.writeUV && formatFromPath(output) == MeshFormat::Off) {
    std::fprintf(stderr, "seamvox convert: warning: OFF has no texture coordinates; UVs dropped\n");
  }
  if (formatFromPath(output) == MeshFormat::Draco) {
    const int bits = dracoUVBitsFor(mesh, options);
    if (mesh.hasUV() && options.writeUV) {
      if (bits > 0) {
        std::printf("UVs on a lattice of step 2^-%d grid units (max corner shift %.3g)\n", bits,
                    std::ldexp(1.0, -bits) * 0.7071068);
      } else {
        std::printf("UVs lossless (float64)%s\n",
                    options.dracoUVBits > 0 ? ": their range is too large for an exact lattice" : "");
      }
    }
    std::printf("positions %s\n", options.dracoPositionBits > 0
                                      ? (std::to_string(options.dracoPositionBits) + "-bit quantized").c_str()
                                      : "lossless (float32)");
  }
  if (ratio) {
    // Same folder as the output: the probe is written and removed on the same file system.
    const std::string probe = output + ".ratio-" + std::to_string(::getpid()) + ".ply";
    WriteOptions plyOptions;
    plyOptions.writeUV = options.writeUV;
    writeMesh(probe, mesh, plyOptions);
    const std::uint64_t plyBytes = fileBytes(probe);
    std::filesystem::remove(probe);
    std::printf("binary PLY %llu bytes: compression ratio %.2f\n",
                static_cast<unsigned long long>(plyBytes),
                bytes ? static_cast<double>(plyBytes) / static_cast<double>(bytes) : 0.0);
  }
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"convert", "convert a mesh between PLY, OBJ, OFF and Draco (UVs kept)",
                 "usage: seamvox convert IN OUT [--uv-bits K] [--position-bits B] [--no-uv]\n"
                 "                       [--ascii] [--ratio]\n"
                 "\n"
                 "Reads IN and writes OUT; the extensions pick the formats (.ply .obj .off .drc).\n"
                 "Per-corner texture coordinates are kept (OFF cannot hold them: a warning says so),\n"
                 "and so are vertex properties (colors, normals, scalars) where OUT can hold them:\n"
                 "PLY and Draco all, OBJ red green blue (v x y z r g b), OFF none; a warning names\n"
                 "what is dropped.\n"
                 "\n"
                 "  --uv-bits K        Draco: round UVs to steps of 2^-K grid units on a lattice with an\n"
                 "                     integer origin, so seam translations stay integers and a\n"
                 "                     seamless map stays seamless (default 14: corners move by at most\n"
                 "                     4.4e-5). 0 = lossless float64, also used when the UV range is\n"
                 "                     too large for an exact lattice\n"
                 "  --position-bits B  Draco: quantize positions to B bits over the bounding box\n"
                 "                     (default 0 = lossless float32)\n"
                 "  --no-uv            drop texture coordinates\n"
                 "  --ascii            PLY: write ascii instead of binary little endian\n"
                 "  --ratio            also report the compression ratio against binary PLY\n"
                 SEAMVOX_MEMORY_HELP,
                 {"ascii", "no-uv", "ratio"},
                 &runConvert});

}  // namespace seamvox::cli
