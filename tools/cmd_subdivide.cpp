// seamvox subdivide: 1-to-4 midpoint subdivision of the cleaned mesh (the scaling series).
#include <chrono>
#include <cstdio>

#include "core/mesh/clean.h"
#include "core/mesh/subdivide.h"
#include "core/system/errors.h"
#include "core/system/memory_budget.h"
#include "io/chunked_mesh_writer.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "stream/subdivision_stream.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

// Measured peaks of the in-memory path (armadillo, 86K faces, 3 and 4 levels: 219 and 739 MiB
// for 5.5M and 22.1M faces, about 33 B per output face over the program; 834 MiB with --noise).
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 36, kNoiseBytesPerFace = 8;
// --noise-scale local: a float and a count per vertex, about two vertices per face.
constexpr std::uint64_t kLocalNoiseBytesPerFace = 4;
// The streamed path holds the cleaned input with its corner table and edge numbers, and a chunk
// of vertices or faces (about 48 bytes per item with the writer's buffers).
constexpr std::size_t kChunk = std::size_t(1) << 16;
constexpr std::uint64_t kInputBytesPerFace = 200, kChunkBytes = 48 * kChunk;

/// Writes the subdivision chunk by chunk (counts known: no scratch) and, when fieldFile is given,
/// cleanedField carried to the fine faces in face order. Returns the vertex count.
std::uint64_t writeStreamed(const CleanResult& cleaned, std::uint32_t levels, AtomicFile& meshFile,
                            const WriteOptions& options, const std::vector<Vec3d>& cleanedField, AtomicFile* fieldFile) {
  SubdivisionStream stream(cleaned.mesh, cleaned.topology, levels);
  ChunkedMeshLayout layout;
  layout.countsKnown = true;
  layout.vertices = stream.numVertices();
  layout.faces = stream.numFaces();
  layout.attributes = cleaned.mesh.attributes.emptyCopy();
  layout.origin = cleaned.mesh.origin;
  ChunkedMeshWriter writer(meshFile, layout, options, nullptr);
  MeshChunk chunk;
  while (stream.nextVertices(kChunk, chunk)) writer.write(chunk);
  chunk.positions.clear();
  chunk.attributes.clearValues();
  chunk.firstVertex = static_cast<std::uint32_t>(stream.numVertices());  // triangles only from here
  while (stream.nextTriangles(kChunk, chunk)) writer.write(chunk);
  writer.finish();
  if (!fieldFile) return stream.numVertices();
  writeFieldHeader(*fieldFile, stream.numFaces());
  std::vector<Vec3d> children;
  const std::uint64_t perFace = std::uint64_t(1) << (2 * levels);
  for (const Vec3d& v : cleanedField) {
    for (std::uint64_t done = 0; done < perFace;) {
      const std::uint64_t n = std::min<std::uint64_t>(perFace - done, kChunk);
      children.assign(n, v);
      appendFieldVectors(*fieldFile, children.data(), children.size());
      done += n;
    }
  }
  return stream.numVertices();
}

int runSubdivide(Args& args) {
  const std::string path = args.positional(0, "the mesh file (seamvox subdivide MESH)");
  const std::int64_t levels = args.integer("levels", 1, 0, 10);
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT (.ply .obj .off .drc)");
  const auto fieldIn = args.value("field");
  const auto fieldOut = args.value("field-out");
  if (fieldIn.has_value() != fieldOut.has_value()) {
    throw UsageError("--field and --field-out go together");
  }
  ScanNoiseOptions noise;
  const bool noisy = parseScanNoise(args, noise);
  const std::int64_t seed = args.integer("seed", 1);
  if (seed < 0) throw UsageError("--seed must be >= 0");
  noise.seed = static_cast<std::uint64_t>(seed);
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = args.flag("weld");
  WriteOptions writeOptions;
  writeOptions.binary = !args.flag("ascii");
  const ProgressFn progress = makeProgress(args.flag("quiet"));
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(1);
  if (!isWritableFormat(formatFromPath(*output))) {
    throw UsageError("cannot write '" + *output + "' (use .ply .obj .off .drc; STL is read only)");
  }
  checkOutputPaths({{"MESH", path}, {"--field", fieldIn.value_or("")}},
                   {{"-o", *output}, {"--field-out", fieldOut.value_or("")}});
  OutputSet outputs;  // staged now, committed together
  AtomicFile& meshFile = outputs.add(*output);
  AtomicFile* fieldFile = fieldOut ? &outputs.add(*fieldOut) : nullptr;

  const auto start = std::chrono::steady_clock::now();
  MemoryPath memoryPath;
  memoryPath.budget = memory.budget;
  // The input is read whole on either path.
  const std::unique_ptr<MeshStream> stream = openMeshStream(path);
  const MeshCounts counts = guessMeshCounts(path, *stream);
  const std::uint64_t inputBytes = kProgramBytes + kChunkBytes + counts.faces * kInputBytesPerFace;
  if (inputBytes > memory.budget) {
    throw InputError(path + ": about " + std::to_string(counts.faces) + " faces; subdivide reads its input whole (about " +
                     formatByteSize(inputBytes) + "), above the --memory-budget of " + formatByteSize(memory.budget) +
                     "; raise --memory-budget or subdivide parts of the mesh");
  }
  TriangleMesh input = readMesh(*stream);
  const std::uint32_t inputFaces = input.numFaces();
  // Read the field before cleaning so a mismatch is reported before any long work.
  std::vector<Vec3d> field;
  if (fieldIn) field = readFieldVectors(*fieldIn, inputFaces);
  cleanOptions.progress = progress;
  CleanResult cleaned = cleanMeshOf(path, std::move(input), cleanOptions);

  const std::uint64_t outputFaces = std::uint64_t(cleaned.mesh.numFaces()) << (2 * levels);
  memoryPath.estimate = kProgramBytes + outputFaces * (kBytesPerFace + (noisy ? kNoiseBytesPerFace + (noise.localScale ? kLocalNoiseBytesPerFace : 0) : 0));
  memoryPath.outOfCore = memoryPath.estimate > memory.budget;
  // Input face -> cleaned face (faceOrigin) -> children (parentFace, or 4^levels in a row).
  std::vector<Vec3d> cleanedField;
  if (fieldIn) {
    cleanedField.resize(cleaned.faceOrigin.size());
    for (std::size_t f = 0; f < cleanedField.size(); ++f) cleanedField[f] = field[cleaned.faceOrigin[f]];
  }
  std::uint64_t outputVertices = 0;
  ScanNoiseResult noiseAdded;
  if (memoryPath.outOfCore) {
    if (noisy) {
      throw UsageError("--noise, --spikes and --folds move vertices by normals summed over the whole mesh: about " +
                       formatByteSize(memoryPath.estimate) + " in memory for " + std::to_string(outputFaces) +
                       " faces, above the --memory-budget of " + formatByteSize(memory.budget) +
                       "; raise --memory-budget or subdivide without them");
    }
    if (formatFromPath(*output) == MeshFormat::Draco) {
      throw UsageError(*output + ": Draco encodes a whole mesh at once: about " + formatByteSize(memoryPath.estimate) +
                       " in memory for " + std::to_string(outputFaces) + " faces, above the --memory-budget of " +
                       formatByteSize(memory.budget) + "; write .ply, .obj or .off, or raise --memory-budget");
    }
    outputVertices = writeStreamed(cleaned, static_cast<std::uint32_t>(levels), meshFile, writeOptions,
                                   cleanedField, fieldFile);
  } else {
    SubdivideOptions options;
    options.levels = static_cast<std::uint32_t>(levels);
    options.progress = progress;
    SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology, options);
    if (noisy) noiseAdded = addScanNoise(result.mesh, noise);
    writeMesh(meshFile, result.mesh, writeOptions);
    outputVertices = result.mesh.numVertices();
    if (fieldIn) writeField(*fieldFile, inheritFaceVectors(cleanedField, result.parentFace));
  }
  outputs.commit();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("wrote %s: %llu faces, %llu vertices (%lld level%s from %u cleaned faces, %u input%s) "
              "in %.2f s\n",
              output->c_str(), static_cast<unsigned long long>(outputFaces),
              static_cast<unsigned long long>(outputVertices), static_cast<long long>(levels),
              levels == 1 ? "" : "s", cleaned.mesh.numFaces(), inputFaces,
              memoryPath.outOfCore ? ", written chunk by chunk" : "", seconds);
  if (noisy) printScanNoise(noise, noiseAdded);
  if (fieldOut) {
    std::printf("wrote %s: field on %llu faces\n", fieldOut->c_str(), static_cast<unsigned long long>(outputFaces));
  }
  std::printf("%s\n", describeMemoryPath(memoryPath).c_str());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"subdivide", "1-to-4 midpoint subdivision (the scaling series), carrying a field",
                 "usage: seamvox subdivide MESH --levels K -o OUT [--field IN --field-out OUT]\n"
                 "                        [--noise A [--seed S] [--noise-tangential F]\n"
                 "                        [--noise-scale mean|local]] [--spikes N]\n"
                 "                        [--folds N]\n"
                 "\n"
                 "Cleans MESH, then splits every triangle into four at its edge midpoints, K times\n"
                 "(faces x 4^K; old vertices keep their positions). Vertex properties (colors,\n"
                 "normals, scalars) of a new vertex are the mean of its edge's ends, integers rounded.\n"
                 "\n"
                 "Above the memory budget (the output needs about 48 MiB + 36 B per face in memory)\n"
                 "the input is still read whole, and the output is written chunk by chunk: the same\n"
                 "faces in the same order with the same positions and properties, the vertices\n"
                 "numbered by input vertex, then edge, then face. Not with --noise, --spikes, --folds\n"
                 "or a .drc output (they need the whole mesh).\n"
                 "\n"
                 "  --levels K        number of subdivisions (default 1)\n"
                 "  -o OUT            output mesh (.ply binary by default, .obj, .off, .drc)\n"
                 "  --field IN        per-face field of MESH (plain x y z per face, or .crossfield)\n"
                 "  --field-out OUT   the field carried to the fine faces (children keep their\n"
                 "                    parent's direction), plain format\n"
                 "  --weld            weld coincident vertices while cleaning\n"
                 "  --seed S          seed of the scan defects below (default 1), added after the\n"
                 "                    subdivision\n"
                 SEAMVOX_SCAN_NOISE_HELP
                 "  --ascii           ascii PLY instead of binary\n"
                 "  --quiet           no progress on stderr\n"
                 SEAMVOX_MEMORY_HELP,
                 {"weld", "ascii"},
                 &runSubdivide});

}  // namespace seamvox::cli
