// seamvox subdivide: 1-to-4 midpoint subdivision of the cleaned mesh (the scaling series).
#include <chrono>
#include <cstdio>

#include "core/mesh/clean.h"
#include "core/mesh/subdivide.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

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
  parseMemoryOptions(args);  // validated; this command runs in memory (out of core: issue 17)
  args.finish(1);
  if (formatFromPath(*output) == MeshFormat::Unknown) {
    throw UsageError("cannot tell the format of '" + *output + "' (use .ply .obj .off .drc)");
  }
  checkOutputPaths({{"MESH", path}, {"--field", fieldIn.value_or("")}},
                   {{"-o", *output}, {"--field-out", fieldOut.value_or("")}});
  OutputSet outputs;  // staged now, committed together
  AtomicFile& meshFile = outputs.add(*output);
  AtomicFile* fieldFile = fieldOut ? &outputs.add(*fieldOut) : nullptr;

  const auto start = std::chrono::steady_clock::now();
  TriangleMesh input = readMesh(path);
  const std::uint32_t inputFaces = input.numFaces();
  // Read the field before cleaning so a mismatch is reported before any long work.
  std::vector<Vec3d> field;
  if (fieldIn) field = readFieldVectors(*fieldIn, inputFaces);
  cleanOptions.progress = progress;
  CleanResult cleaned = cleanMeshOf(path, std::move(input), cleanOptions);

  SubdivideOptions options;
  options.levels = static_cast<std::uint32_t>(levels);
  options.progress = progress;
  SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology, options);
  ScanNoiseResult noiseAdded;
  if (noisy) noiseAdded = addScanNoise(result.mesh, noise);
  writeMesh(meshFile, result.mesh, writeOptions);
  if (fieldIn) {
    // Input face -> cleaned face (faceOrigin) -> children (parentFace).
    std::vector<Vec3d> cleanedField(cleaned.faceOrigin.size());
    for (std::size_t f = 0; f < cleanedField.size(); ++f) cleanedField[f] = field[cleaned.faceOrigin[f]];
    writeField(*fieldFile, inheritFaceVectors(cleanedField, result.parentFace));
  }
  outputs.commit();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("wrote %s: %u faces, %u vertices (%lld level%s from %u cleaned faces, %u input) "
              "in %.2f s\n",
              output->c_str(), result.mesh.numFaces(), result.mesh.numVertices(),
              static_cast<long long>(levels), levels == 1 ? "" : "s", cleaned.mesh.numFaces(),
              inputFaces, seconds);
  if (noisy) printScanNoise(noise, noiseAdded);
  if (fieldOut) std::printf("wrote %s: field on %u faces\n", fieldOut->c_str(), result.mesh.numFaces());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"subdivide", "1-to-4 midpoint subdivision (the scaling series), carrying a field",
                 "usage: seamvox subdivide MESH --levels K -o OUT [--field IN --field-out OUT]\n"
                 "                        [--noise A [--seed S]] [--spikes N] [--folds N]\n"
                 "\n"
                 "Cleans MESH, then splits every triangle into four at its edge midpoints, K times\n"
                 "(faces x 4^K; old vertices keep their positions). Vertex properties (colors,\n"
                 "normals, scalars) of a new vertex are the mean of its edge's ends, integers rounded.\n"
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
