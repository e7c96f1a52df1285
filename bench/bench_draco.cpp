// Draco archive benchmark: sizes, write and read times of a parameterized mesh in binary PLY, OBJ
// and Draco (lossless, UV lattice, UV lattice + quantized positions), and the seam figures of the
// decoded maps.
//   bench_draco [N=200000 faces of a generated sphere, hat solver] [MESH_WITH_UV instead]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/synth/generate.h"
#include "core/quality/metrics.h"
#include "core/solve/hat_solver.h"
#include "io/mesh_io.h"

namespace {

using namespace seamvox;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// A generated sphere with a seamless hat map of 100 cells on the diagonal.
TriangleMesh parameterizedSphere(std::uint64_t faces) {
  GenerateOptions generate;
  generate.faces = faces;
  CleanResult clean = cleanMesh(generateMesh(generate).mesh);
  const CrossField field = computeSmoothestField(clean.mesh, clean.topology);
  const FieldSingularities singularities = computeSingularities(clean.mesh, clean.topology, field);
  const CutResult cut = cutToDisk(clean.mesh, clean.topology, field, singularities);
  ParamOptions options;
  options.edgeLength = computeBoundingBox(clean.mesh.positions).diagonal() / 100.0;
  ParamResult result = parameterizeMesh(clean.mesh, clean.topology, field, cut, options);
  clean.mesh.cornerUV = std::move(result.cornerUV);
  return std::move(clean.mesh);
}

}  // namespace

int main(int argc, char** argv) {
  const std::uint64_t faces = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 200000;
  auto start = Clock::now();
  TriangleMesh mesh;
  if (argc > 2) {
    ReadOptions options;
    options.readUV = true;
    mesh = readMesh(argv[2], options);
  } else {
    mesh = parameterizedSphere(faces);
  }
  std::printf("mesh: %u faces, %u vertices, UVs %s (%.2f s)\n", mesh.numFaces(), mesh.numVertices(),
              mesh.hasUV() ? "yes" : "no", since(start));
  const std::string dir = std::filesystem::temp_directory_path() / "seamvox_bench_draco";
  std::filesystem::create_directories(dir);

  struct Variant {
    const char* name;
    const char* file;
    int uvBits, positionBits;
  };
  const Variant variants[] = {
      {"binary PLY", "m.ply", 0, 0},          {"OBJ", "m.obj", 0, 0},
      {"Draco lossless", "lossless.drc", 0, 0}, {"Draco uv 2^-14", "uv14.drc", 14, 0},
      {"Draco uv 2^-10", "uv10.drc", 10, 0},  {"Draco uv 2^-14 pos 20", "uv14p20.drc", 14, 20},
      {"Draco uv 2^-14 pos 16", "uv14p16.drc", 14, 16},
  };
  std::uintmax_t plyBytes = 0;
  std::printf("%-24s %12s %7s %8s %8s %12s %12s\n", "format", "bytes", "ratio", "write s", "read s",
              "residual", "integer");
  for (const Variant& v : variants) {
    const std::string path = dir + "/" + v.file;
    WriteOptions options;
    options.dracoUVBits = v.uvBits;
    options.dracoPositionBits = v.positionBits;
    start = Clock::now();
    writeMesh(path, mesh, options);
    const double write = since(start);
    const std::uintmax_t bytes = std::filesystem::file_size(path);
    if (!plyBytes) plyBytes = bytes;
    ReadOptions readOptions;
    readOptions.readUV = true;
    start = Clock::now();
    TriangleMesh back = readMesh(path, readOptions);
    const double read = since(start);
    const CleanResult clean = cleanMesh(std::move(back));
    const SeamQuality seams = measureSeamsFromUV(clean.mesh, clean.topology, clean.mesh.cornerUV);
    std::printf("%-24s %12ju %7.2f %8.2f %8.2f %12.3g %12.3g\n", v.name, bytes,
                static_cast<double>(plyBytes) / static_cast<double>(bytes), write, read, seams.maxResidual,
                seams.maxIntegerDistance);
    std::filesystem::remove(path);
  }
  std::filesystem::remove_all(dir);
  return 0;
}
