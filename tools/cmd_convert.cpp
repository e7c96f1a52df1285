// seamvox convert: rewrites a mesh in another format, keeping per-corner UVs and vertex
// properties where the output format can hold them. Above the memory budget PLY, OBJ and OFF
// are streamed chunk by chunk (io/chunked_mesh_writer), the same bytes.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "core/system/errors.h"
#include "core/system/memory_budget.h"
#include "io/atomic_file.h"
#include "io/chunked_mesh_writer.h"
#include "io/mesh_io.h"
#include "stream/scratch_folder.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

// Measured peak of the in-memory path: 87 MB for a 2M-face PLY without UVs (about 20 B per face
// over the program); corner UVs take about 30 B per face more. Rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 56, kBytesPerVertex = 16;

std::uint64_t fileBytes(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0 : static_cast<std::uint64_t>(size);
}

/// What the conversion read and wrote, whichever path ran.
struct Converted {
  std::uint64_t faces = 0, vertices = 0;
  bool hasUV = false;
  VertexAttributes properties;  ///< names and types
  double readSeconds = 0, writeSeconds = 0;
  TriangleMesh mesh;  ///< in memory only (Draco figures, --ratio)
};

Converted convertInMemory(MeshStream& stream, const std::string& input, const std::string& output,
                          const WriteOptions& options) {
  Converted c;
  const auto start = std::chrono::steady_clock::now();
  c.mesh = collectMesh(stream);
  if (c.mesh.triangles.empty()) throw InputError(input + ": the mesh has no faces");
  const auto read = std::chrono::steady_clock::now();
  writeMesh(output, c.mesh, options);
  c.readSeconds = std::chrono::duration<double>(read - start).count();
  c.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - read).count();
  c.faces = c.mesh.numFaces();
  c.vertices = c.mesh.numVertices();
  c.hasUV = c.mesh.hasUV();
  c.properties = c.mesh.attributes.emptyCopy();
  return c;
}

/// Reads and writes chunk by chunk; bodies whose header needs the counts wait in scratch.
Converted convertStreamed(MeshStream& stream, const std::string& input, const std::string& output,
                          const WriteOptions& options, const MemoryOptions& memory, std::uint64_t expectedFaces,
                          MemoryPath& path) {
  Converted c;
  const auto start = std::chrono::steady_clock::now();
  ScratchFolder scratch(memory.scratch, expectedFaces * 64);
  AtomicFile file(output);
  std::unique_ptr<ChunkedMeshWriter> writer;
  StreamChecker checker(input);
  MeshChunk chunk;
  while (stream.next(chunk)) {
    checker.check(chunk);
    if (!writer) {
      ChunkedMeshLayout layout;
      layout.attributes = chunk.attributes.emptyCopy();
      c.properties = layout.attributes.emptyCopy();
      writer = std::make_unique<ChunkedMeshWriter>(file, std::move(layout), options, &scratch);
    }
    writer->write(chunk);
  }
  checker.finish();
  if (checker.faces() == 0) throw InputError(input + ": the mesh has no faces");
  writer->finish();
  file.commit();
  c.faces = checker.faces();
  c.vertices = checker.vertices();
  c.hasUV = checker.hasUV();
  c.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  path.recordScratch(scratch);
  return c;
}

void printDracoFigures(const TriangleMesh& mesh, const WriteOptions& options) {
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
  std::printf("positions %s\n", !mesh.origin.isZero(0.0) ? "lossless (float64: the mesh lies far from zero)"
                                : options.dracoPositionBits > 0
                                    ? (std::to_string(options.dracoPositionBits) + "-bit quantized").c_str()
                                    : "lossless (float32)");
}

void printRatio(const TriangleMesh& mesh, const std::string& output, std::uint64_t bytes, const WriteOptions& options) {
  // Same folder as the output: the probe is written and removed on the same file system.
  const std::string probe = output + ".ratio-" + std::to_string(::getpid()) + ".ply";
  WriteOptions plyOptions;
  plyOptions.writeUV = options.writeUV;
  writeMesh(probe, mesh, plyOptions);
  const std::uint64_t plyBytes = fileBytes(probe);
  std::filesystem::remove(probe);
  std::printf("binary PLY %llu bytes: compression ratio %.2f\n", static_cast<unsigned long long>(plyBytes),
              bytes ? static_cast<double>(plyBytes) / static_cast<double>(bytes) : 0.0);
}

int runConvert(Args& args) {
  const std::string input = args.positional(0, "the input mesh (seamvox convert IN OUT)");
  const std::string output = args.positional(1, "the output mesh (seamvox convert IN OUT)");
  if (!isWritableFormat(formatFromPath(output))) {
    throw UsageError("unknown output format (use .ply, .obj, .off or .drc; STL is read only): " + output);
  }
  WriteOptions options;
  const std::int64_t uvBits = args.integer("uv-bits", options.dracoUVBits, 0, 23);  // 0: lossless
  const std::int64_t positionBits = args.integer("position-bits", options.dracoPositionBits, 0, 30);
  options.dracoUVBits = static_cast<int>(uvBits);
  options.dracoPositionBits = static_cast<int>(positionBits);
  options.binary = !args.flag("ascii");
  options.writeUV = !args.flag("no-uv");
  const bool ratio = args.flag("ratio");
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(2);
  checkOutputPaths({{"IN", input}}, {{"OUT", output}});

  MemoryPath path;
  path.budget = memory.budget;
  refuseDracoInputAboveBudget(input, memory.budget, kProgramBytes, kBytesPerFace + kBytesPerVertex,
                              "raise --memory-budget (Draco cannot be decoded in pieces)");
  ReadOptions readOptions;
  readOptions.readUV = options.writeUV;
  const std::unique_ptr<MeshStream> stream = openMeshStream(input, readOptions);
  const MeshCounts counts = guessMeshCounts(input, *stream);
  path.estimate = kProgramBytes + counts.faces * kBytesPerFace + counts.vertices * kBytesPerVertex;
  path.outOfCore = path.estimate > memory.budget;
  if (path.outOfCore && formatFromPath(output) == MeshFormat::Draco) {
    throw UsageError(output + ": Draco encodes a whole mesh at once: about " + formatByteSize(path.estimate) +
                     " in memory, above the --memory-budget of " + formatByteSize(memory.budget) +
                     "; convert to .ply, .obj or .off (streamed within the budget), or raise --memory-budget");
  }
  if (path.outOfCore && stream->cornerVertices()) {
    throw UsageError(input + ": STL keeps every facet's corners apart; convert welds them in memory, about " +
                     formatByteSize(path.estimate) + ", above the --memory-budget of " + formatByteSize(memory.budget) +
                     "; raise --memory-budget (param and info weld STL out of core)");
  }
  if (path.outOfCore && ratio) {
    throw UsageError("--ratio writes the whole mesh a second time in memory: about " + formatByteSize(path.estimate) +
                     ", above the --memory-budget of " + formatByteSize(memory.budget));
  }

  const Converted c = path.outOfCore ? convertStreamed(*stream, input, output, options, memory, counts.faces, path)
                                     : convertInMemory(*stream, input, output, options);
  const std::uint64_t bytes = fileBytes(output);
  const std::string properties = c.properties.empty() ? "" : ", vertex properties " + c.properties.describe();
  std::printf("%s -> %s: %llu faces, %llu vertices, %s%s, %llu bytes (", input.c_str(), output.c_str(),
              static_cast<unsigned long long>(c.faces), static_cast<unsigned long long>(c.vertices),
              c.hasUV ? "per-corner UVs" : "no UVs", properties.c_str(), static_cast<unsigned long long>(bytes));
  if (path.outOfCore) {
    std::printf("read and written chunk by chunk in %.2f s)\n", c.writeSeconds);
  } else {
    std::printf("read %.2f s, write %.2f s)\n", c.readSeconds, c.writeSeconds);
  }
  if (c.hasUV && options.writeUV && formatFromPath(output) == MeshFormat::Off) {
    std::fprintf(stderr, "seamvox convert: warning: OFF has no texture coordinates; UVs dropped\n");
  }
  if (formatFromPath(output) == MeshFormat::Draco) printDracoFigures(c.mesh, options);
  if (ratio) printRatio(c.mesh, output, bytes, options);
  std::printf("%s\n", describeMemoryPath(path).c_str());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"convert", "convert a mesh between PLY, OBJ, OFF and Draco, or from STL (UVs kept)",
                 "usage: seamvox convert IN OUT [--uv-bits K] [--position-bits B] [--no-uv]\n"
                 "                       [--ascii] [--ratio]\n"
                 "\n"
                 "Reads IN and writes OUT; the extensions pick the formats (.ply .obj .off .drc; .stl,\n"
                 "binary or ASCII, is read, its facets' corners welded at equal positions).\n"
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
                 "\n"
                 "Above the memory budget (the in-memory path needs about 48 MiB + 56 B per face, counted\n"
                 "from the header, or the file size for OBJ) PLY, OBJ and OFF are read and written chunk\n"
                 "by chunk, the same bytes: bodies whose header needs the counts wait in the scratch\n"
                 "folder (about the output's size); OBJ with UVs keeps 20 B per vertex in memory. Draco\n"
                 "(encoded and decoded whole) and --ratio are refused there.\n"
                 SEAMVOX_MEMORY_HELP,
                 {"ascii", "no-uv", "ratio"},
                 &runConvert});

}  // namespace seamvox::cli
