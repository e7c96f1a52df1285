// seamvox gen: deterministic synthetic scan-like meshes (test and benchmark inputs).
#include <chrono>
#include <cstdio>

#include "core/system/errors.h"
#include "core/synth/generate.h"
#include "io/mesh_io.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

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
  parseMemoryOptions(args);  // validated; this command runs in memory (out of core: issue 17)
  args.finish(1);
  if (formatFromPath(*output) == MeshFormat::Unknown) {
    throw UsageError("cannot tell the format of '" + *output + "' (use .ply .obj .off .drc)");
  }

  const auto start = std::chrono::steady_clock::now();
  GenerateResult generated = generateMesh(options);
  ScanNoiseResult noiseAdded;
  if (noisy) noiseAdded = addScanNoise(generated.mesh, noise);
  const auto generatedAt = std::chrono::steady_clock::now();
  writeMesh(*output, generated.mesh, writeOptions);
  const auto end = std::chrono::steady_clock::now();
  std::printf("wrote %s: %s, seed %llu, %u faces, %u vertices (generate %.2f s, write %.2f s)\n",
              output->c_str(), meshKindName(options.kind),
              static_cast<unsigned long long>(options.seed), generated.mesh.numFaces(),
              generated.mesh.numVertices(),
              std::chrono::duration<double>(generatedAt - start).count(),
              std::chrono::duration<double>(end - generatedAt).count());
  if (noisy) printScanNoise(noise, noiseAdded);
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"gen", "generate a synthetic scan-like mesh (sphere, torus, genus2, scan)",
                 "usage: seamvox gen KIND --faces N -o OUT [--seed S] [--ascii]\n"
                 "                      [--noise A] [--spikes N] [--folds N]\n"
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
                 SEAMVOX_MEMORY_HELP,
                 {"ascii"},
                 &runGen});

}  // namespace seamvox::cli
