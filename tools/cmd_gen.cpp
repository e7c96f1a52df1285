// seamvox gen: deterministic synthetic scan-like meshes (test and benchmark inputs).
#include <chrono>
#include <cstdio>

#include "core/system/errors.h"
#include "core/system/memory_budget.h"
#include "core/synth/generate.h"
#include "io/atomic_file.h"
#include "io/chunked_mesh_writer.h"
#include "io/mesh_io.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

// Measured peak of the in-memory path: 120 MB for a 4M-face scan (about 26 B per face over the
// program), 175 MB with --noise; rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 28, kNoiseBytesPerFace = 16;
// --noise-scale local: a float and a count per vertex, about two vertices per face.
constexpr std::uint64_t kLocalNoiseBytesPerFace = 4;
constexpr std::size_t kChunk = std::size_t(1) << 18;

/// Writes the generated mesh chunk by chunk (no scratch: the counts are known up front).
void writeGenerated(MeshGenerator& generator, const std::string& output, const WriteOptions& options) {
  ChunkedMeshLayout layout;
  layout.countsKnown = true;
  layout.vertices = generator.numVertices();
  layout.faces = generator.numFaces();
  AtomicFile file(output);
  ChunkedMeshWriter writer(file, layout, options, nullptr);
  MeshChunk chunk;
  while (generator.nextPositions(kChunk, chunk.positions)) {
    writer.write(chunk);
    chunk.firstVertex += static_cast<std::uint32_t>(chunk.positions.size());
    chunk.positions.clear();
  }
  while (generator.nextTriangles(kChunk, chunk.triangles)) {
    writer.write(chunk);
    chunk.triangles.clear();
  }
  writer.finish();
  file.commit();
}

int runGen(Args& args) {
  const std::string kindName = args.positional(0, "the kind (sphere, torus, genus2, scan)");
  GenerateOptions options;
  try {
    options.kind = parseMeshKind(kindName);
  } catch (const InputError& e) {
    throw UsageError(e.what());
  }
  const std::int64_t faces = args.integer("faces", 100000);
  if (faces <= 0) throw UsageError("--faces must be positive");
  options.faces = static_cast<std::uint64_t>(faces);
  const std::int64_t seed = args.integer("seed", 1);
  if (seed < 0) throw UsageError("--seed must be >= 0");
  options.seed = static_cast<std::uint64_t>(seed);
  ScanNoiseOptions noise;
  noise.seed = options.seed;
  const bool noisy = parseScanNoise(args, noise);
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT (.ply .obj .off .drc)");
  WriteOptions writeOptions;
  writeOptions.binary = !args.flag("ascii");
  options.progress = makeProgress(args.flag("quiet"));
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(1);
  if (!isWritableFormat(formatFromPath(*output))) {
    throw UsageError("cannot write '" + *output + "' (use .ply .obj .off .drc; STL is read only)");
  }

  MemoryPath path;
  path.budget = memory.budget;
  path.estimate = kProgramBytes + options.faces * (kBytesPerFace + (noisy ? kNoiseBytesPerFace + (noise.localScale ? kLocalNoiseBytesPerFace : 0) : 0));
  path.outOfCore = path.estimate > memory.budget;
  if (path.outOfCore && noisy) {
    throw UsageError("--noise, --spikes and --folds move vertices by normals summed over the whole mesh: about " +
                     formatByteSize(path.estimate) + " in memory, above the --memory-budget of " +
                     formatByteSize(memory.budget) + "; raise --memory-budget or generate without them");
  }
  if (path.outOfCore && formatFromPath(*output) == MeshFormat::Draco) {
    throw UsageError(*output + ": Draco encodes a whole mesh at once: about " + formatByteSize(path.estimate) +
                     " in memory, above the --memory-budget of " + formatByteSize(memory.budget) +
                     "; write .ply, .obj or .off (then convert pieces), or raise --memory-budget");
  }

  const auto start = std::chrono::steady_clock::now();
  std::uint64_t numFaces = 0, numVertices = 0;
  double generateSeconds = 0.0;
  ScanNoiseResult noiseAdded;
  if (path.outOfCore) {
    MeshGenerator generator(options);
    numFaces = generator.numFaces();
    numVertices = generator.numVertices();
    writeGenerated(generator, *output, writeOptions);
  } else {
    GenerateResult generated = generateMesh(options);
    if (noisy) noiseAdded = addScanNoise(generated.mesh, noise);
    generateSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    writeMesh(*output, generated.mesh, writeOptions);
    numFaces = generated.mesh.numFaces();
    numVertices = generated.mesh.numVertices();
  }
  const double totalSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("wrote %s: %s, seed %llu, %llu faces, %llu vertices (", output->c_str(), meshKindName(options.kind),
              static_cast<unsigned long long>(options.seed), static_cast<unsigned long long>(numFaces),
              static_cast<unsigned long long>(numVertices));
  if (path.outOfCore) {
    std::printf("generated and written chunk by chunk in %.2f s)\n", totalSeconds);
  } else {
    std::printf("generate %.2f s, write %.2f s)\n", generateSeconds, totalSeconds - generateSeconds);
  }
  if (noisy) printScanNoise(noise, noiseAdded);
  std::printf("%s\n", describeMemoryPath(path).c_str());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"gen", "generate a synthetic scan-like mesh (sphere, torus, genus2, scan)",
                 "usage: seamvox gen KIND --faces N -o OUT [--seed S] [--ascii]\n"
                 "                      [--noise A [--noise-tangential F] [--noise-scale mean|local]]\n"
                 "                      [--spikes N] [--folds N]\n"
                 "\n"
                 "Writes a deterministic synthetic mesh with about N faces (within a few percent):\n"
                 "the same KIND, N and seed give a byte-identical file on every machine.\n"
                 "  sphere   bumpy sphere: closed, genus 0\n"
                 "  torus    bumpy torus: closed, genus 1\n"
                 "  genus2   two bumpy tori joined by a tube: closed, genus 2\n"
                 "  scan     bumpy sphere with holes, floating islands, an unwelded seam and a few\n"
                 "           degenerate and duplicate faces, like raw scanner output\n"
                 "\n"
                 "  --faces N   target face count (default 100000)\n"
                 "  -o OUT      output mesh; the extension picks the format (.ply is binary PLY)\n"
                 "  --seed S    random seed (default 1)\n"
                 "  --ascii     ascii PLY instead of binary\n"
                 SEAMVOX_SCAN_NOISE_HELP
                 "  --quiet     no progress on stderr\n"
                 "\n"
                 "Above the memory budget (the in-memory path needs about 48 MiB + 28 B per face) the\n"
                 "mesh is generated and written chunk by chunk, the same bytes, in a few MiB; --noise,\n"
                 "--spikes, --folds and .drc need the whole mesh and are refused there.\n"
                 SEAMVOX_MEMORY_HELP,
                 {"ascii"},
                 &runGen});

}  // namespace seamvox::cli
