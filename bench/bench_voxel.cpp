// Voxel basis build (clipping + OpenVDB index, elements, integrals, domains, seam adjacency) on a
// generated mesh at grids 64, 128 and 256: wall time, memory held by the basis, resident-memory
// growth, and the element / basis / domain counts.
//   bench_voxel [FACES=2000000] [THREADS=2] [KIND=sphere] [GRIDS=64,128,256]
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/synth/generate.h"
#include "core/mesh/topology.h"
#include "core/system/memory.h"
#include "core/basis/voxel_grid.h"
#include "core/system/blas_threads.h"

namespace {

using namespace seamvox;
using bench::Clock;
using bench::mib;
using bench::seconds;

}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  seamvox::limitBlasThreads(1);
  const std::uint64_t faces = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 2000000;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  const std::string kind = argc > 3 ? argv[3] : "sphere";
  std::vector<int> grids = {64, 128, 256};
  if (argc > 4) {
    grids.clear();
    std::stringstream list(argv[4]);
    for (std::string item; std::getline(list, item, ',');) grids.push_back(std::atoi(item.c_str()));
  }
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);

  auto t0 = Clock::now();
  GenerateOptions gen;
  gen.kind = parseMeshKind(kind);
  gen.faces = faces;
  const TriangleMesh mesh = generateMesh(gen).mesh;
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  // Field quality does not matter for the build: a fixed direction projected on each face.
  const CrossField field =
      projectToTangent(mesh, std::vector<Vec3d>(mesh.numFaces(), Vec3d(0.3, 0.5, 0.8)));
  const FieldSingularities singularities = computeSingularities(mesh, topology, field);
  const CutResult cut = cutToDisk(mesh, topology, field, singularities);
  auto t1 = Clock::now();
  std::printf("mesh %s: %u faces, %u vertices, %zu cones, %zu seams; setup %.2f s, RSS %.0f MiB\n",
              kind.c_str(), mesh.numFaces(), mesh.numVertices(), cut.cones.size(),
              cut.seams.size(), seconds(t0, t1), mib(currentResidentBytes()));
  std::printf("%6s %9s %10s %10s %9s %9s %8s %8s %8s %9s %9s %9s\n", "grid", "voxels", "fragments",
              "elements", "basis", "domains", "adjac", "clip_s", "basis_s", "basis_MiB", "vdb_MiB",
              "dRSS_MiB");
  for (int resolution : grids) {
    const std::uint64_t before = currentResidentBytes();
    VoxelBasisOptions options;
    options.gridResolution = resolution;
    // Per-phase times of the basis build (elements, integrals, domains, basis functions).
    std::string phases;
    auto last = Clock::now();
    options.progress = [&](const char* stage, double fraction) {
      if (std::string(stage) == "voxel basis" && fraction > 0.0) {
        const auto now = Clock::now();
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, " %.2f", seconds(last, now));
        phases += buffer;
        last = now;
      } else if (std::string(stage) == "voxel basis") {
        last = Clock::now();
      }
      return true;
    };
    const VoxelBuildResult built = buildVoxelBasis(mesh, topology, field, cut, options);
    const VoxelBasisStats stats = built.basis->stats();
    const std::uint64_t after = currentResidentBytes();
    std::printf("%6d %9llu %10llu %10llu %9u %9u %8zu %8.2f %8.2f %9.1f %9.1f %9.1f\n", resolution,
                (unsigned long long)stats.voxels, (unsigned long long)stats.fragments,
                (unsigned long long)stats.elements, built.basis->numBasisFunctions(),
                built.basis->numDomains(), built.basis->adjacencies().size(), built.secondsClip,
                built.secondsBasis, mib(stats.bytes), mib(built.grid.treeBytes()),
                (after > before ? mib(after - before) : 0.0));
    std::printf("       basis phases (elements, integrals, domains, functions): %s s\n",
                phases.c_str());
  }
  std::printf("peak RSS %.0f MiB\n", mib(peakResidentBytes()));
  return 0;
}
