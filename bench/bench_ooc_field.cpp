// The out-of-core field, cut, voxel basis and Vox solve stages against the in-memory ones: wall time and peak resident
// memory per step, scratch traffic, and with in-memory the directions, cones and cut that differ
// (none expected). Steps run on the weld pass's faces (Morton order), as param's out-of-core path
// will; cones merged within one default grid spacing (the diagonal over 100).
//   seamvox gen scan --faces 20000000 -o /tmp/s20.ply
//   bench_ooc_field MESH [BUDGET_MIB=1024] [SCRATCH=/tmp] [in-memory]
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bench/bench_common.h"
#include "core/field/field.h"
#include "core/basis/islands.h"
#include "core/basis/voxel_grid.h"
#include "core/cut/cut.h"
#include "core/field/cone_merge.h"
#include "core/field/field_proxy.h"
#include "core/pipeline/grid_spacing.h"
#include "core/system/blas_threads.h"
#include "core/system/memory.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/voxel_solve_stream.h"
#include "stream/voxel_stream.h"
#include "stream/field_stream.h"
#include "stream/mesh_stream.h"
#include "stream/welded_scratch.h"

using namespace seamvox;
using bench::Clock;
using bench::mib;
using bench::seconds;

namespace {
void line(const char* step, Clock::time_point a, Clock::time_point b) {
  std::printf("%-28s %8.2f s   RSS %8.1f MiB   peak %8.1f MiB\n", step, seconds(a, b), mib(currentResidentBytes()),
              mib(peakResidentBytes()));
  std::fflush(stdout);
}
}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_ooc_field MESH [BUDGET_MIB=1024] [SCRATCH=/tmp] [in-memory]\n");
    return 2;
  }
  const std::string path = argv[1];
  const std::uint64_t budget = (argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1024) << 20;
  const std::string scratchParent = argc > 3 ? argv[3] : "/tmp";
  const bool inMemory = argc > 4 && !std::strcmp(argv[4], "in-memory");
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, 2);
  limitBlasThreads(1);  // as the seamvox command: the factorization is then repeatable
  ScratchFolder folder(scratchParent);
  const std::unique_ptr<MeshStream> stream = openMeshStream(path);
  auto t0 = Clock::now();
  WeldStreamOptions weld;
  weld.memoryBytes = budget;
  const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
  auto t1 = Clock::now();
  line("weld pass", t0, t1);
  for (const auto& [name, s] : welded.census.stageSeconds) std::printf("  weld: %-21s %8.2f s\n", name.c_str(), s);
  CleanStreamOptions clean;
  clean.memoryBytes = budget;
  const CleanScratch scratch = cleanWeldedMesh(folder, welded.scratch, welded.census, clean);
  auto t2 = Clock::now();
  line("clean", t1, t2);
  std::printf("  clean: gluing %s, largest front %llu vertices, %llu values patched\n", scratch.gluing.c_str(),
              static_cast<unsigned long long>(scratch.largestFront), static_cast<unsigned long long>(scratch.frontLateValues));
  for (const auto& [name, s] : scratch.stageSeconds) std::printf("  clean: %-20s %8.2f s\n", name.c_str(), s);
  std::fflush(stdout);
  const ScratchField field = computeScratchField(folder, scratch, ProxyFieldOptions(), FieldGeometryOptions(), StreamPassOptions{budget});
  auto t3 = Clock::now();
  line("field (proxy)", t2, t3);
  for (const auto& [name, s] : field.stageSeconds) std::printf("  field: %-20s %8.2f s\n", name.c_str(), s);
  std::printf("  elements %u, colours %u\n", field.elements, field.colours);
  ScratchSingularities singularities = computeScratchSingularities(folder, scratch, field, StreamPassOptions{budget});
  auto t3b = Clock::now();
  line("singularities", t3, t3b);
  std::printf("  cones %zu, boundary vertices with an index %zu\n", singularities.cones.size(),
              singularities.boundaryIndex4.size());
  const std::vector<VertexId> fieldCones = singularities.cones;
  ConeMergeOptions merge;
  {
    Vec3f lo(1e30f, 1e30f, 1e30f), hi = -lo;
    ScratchReader reader(folder, scratch.positions, "bench");
    Vec3f p;
    while (reader.read(&p, sizeof(p))) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    merge.maxDistance = GridSpacing{}.spacing((hi - lo).cast<double>().norm());
  }
  const ConeMergeResult merged = mergeScratchCones(folder, scratch, singularities, merge, StreamPassOptions{budget});
  auto t3c = Clock::now();
  line("merge cones", t3b, t3c);
  std::printf("  cones %zu after merging (%zu pairs cancelled, %zu merged)\n", singularities.cones.size(),
              std::size_t(merged.cancelledPairs), std::size_t(merged.mergedPairs));
  const ScratchCut cut = cutScratchToDisk(folder, scratch, singularities, StreamPassOptions{budget});
  auto t3d = Clock::now();
  line("cut", t3c, t3d);
  for (const auto& [name, s] : cut.stageSeconds) std::printf("  cut: %-22s %8.2f s\n", name.c_str(), s);
  std::size_t seamEdges = 0;
  for (const SeamCurve& seam : cut.seams) seamEdges += seam.corners.size();
  std::printf("  components %u, seams %zu, seam edges %zu\n", cut.components, cut.seams.size(), seamEdges);
  VoxelBasisOptions voxelOptions;
  voxelOptions.edgeLength = merge.maxDistance;
  // As param builds it: the islands left to the local hat solve.
  voxelOptions.leftOut = scratchIslandFaces(folder, scratch, kVoxelIslandFaces, budget);
  ScratchVoxelBasis voxels = buildScratchVoxelBasis(folder, scratch, field, cut, voxelOptions, StreamPassOptions{budget});
  auto t3e = Clock::now();
  line("voxel basis (grid 128)", t3d, t3e);
  for (const auto& [name, s] : voxels.stageSeconds) std::printf("  voxel: %-20s %8.2f s\n", name.c_str(), s);
  std::printf("  voxels %u, fragments %llu, elements %llu, domains %u, basis functions %u, seam adjacencies %zu\n",
              voxels.grid.size(), (unsigned long long)voxels.numFragments,
              (unsigned long long)voxels.basis->numElements(), voxels.basis->numDomains(),
              voxels.basis->numBasisFunctions(), voxels.basis->adjacencies().size());
  const ScratchVoxelSolution solved =
      solveScratchVoxelMap(folder, scratch, cut, voxels, RoundOptions{}, StreamPassOptions{budget});
  auto t3f = Clock::now();
  line("vox solve and evaluation", t3e, t3f);
  std::printf("  constraints %u, determined %u, inconsistent %u, wedges %llu, factorizations failed %u\n",
              solved.translationConstraints, solved.determinedBasis, solved.inconsistentBasis,
              (unsigned long long)solved.map.numWedges, solved.failedAttempts);
  t3 = t3f;
  for (const ScratchTraffic& t : folder.traffic()) {
    std::printf("  traffic %-24s read %9.1f MiB  written %9.1f MiB\n", t.stage.c_str(), mib(t.bytesRead),
                mib(t.bytesWritten));
  }
  std::printf("  scratch peak %.1f MiB, faces %llu, vertices %llu\n", mib(folder.peakBytesOnDisk()),
              (unsigned long long)scratch.numFaces, (unsigned long long)scratch.numVertices);
  if (inMemory) {
    const CleanResult cleaned = readCleanScratch(folder, scratch);
    auto t4 = Clock::now();
    line("in memory: read scratch", t3, t4);
    const CrossField inMemory = computeCrossField(cleaned.mesh, cleaned.topology, FieldMethod::Proxy);
    auto t5 = Clock::now();
    line("in memory: field (proxy)", t4, t5);
    std::vector<Vec3f> streamed(scratch.numFaces);
    ScratchReader reader(folder, field.directions, "bench");
    if (!streamed.empty() && !reader.read(streamed.data(), streamed.size() * sizeof(Vec3f))) return 1;
    std::size_t differ = 0, far = 0;
    double largest = 0.0;
    for (std::size_t f = 0; f < streamed.size(); ++f) {
      const double d = (streamed[f] - inMemory.direction[f]).norm();
      differ += d > 0.0;
      far += d > 1e-3;
      largest = std::max(largest, d);
    }
    std::printf("  directions differing from the in-memory field: %zu of %zu (%zu by more than 1e-3; largest %.3g)\n",
                differ, streamed.size(), far, largest);
    auto t6 = Clock::now();
    const FieldSingularities expected = computeSingularities(cleaned.mesh, cleaned.topology, inMemory);
    auto t7 = Clock::now();
    line("in memory: singularities", t6, t7);
    std::printf("  cones equal to the in-memory ones: %s (%zu)\n", expected.cones == fieldCones ? "yes" : "NO",
                expected.cones.size());
    FieldSingularities mergedExpected = expected;
    mergeCloseCones(cleaned.mesh, cleaned.topology, mergedExpected, merge);
    auto t8 = Clock::now();
    line("in memory: merge cones", t7, t8);
    std::printf("  merged cones equal to the in-memory ones: %s (%zu)\n",
                mergedExpected.cones == singularities.cones ? "yes" : "NO", mergedExpected.cones.size());
    const CutResult cutExpected = cutToDisk(cleaned.mesh, cleaned.topology, inMemory, mergedExpected);
    auto t9 = Clock::now();
    line("in memory: cut", t8, t9);
    std::vector<std::uint8_t> corners(cut.corners.bytes);
    ScratchReader cutReader(folder, cut.corners, "bench");
    if (!corners.empty() && !cutReader.read(corners.data(), corners.size())) return 1;
    bool sameSeams = cut.seams.size() == cutExpected.seams.size();
    for (std::size_t i = 0; sameSeams && i < cut.seams.size(); ++i) {
      sameSeams = cut.seams[i].corners == cutExpected.seams[i].corners && cut.seams[i].matching == cutExpected.seams[i].matching;
    }
    std::printf("  cut corners equal to the in-memory cut: %s; seams equal: %s (%zu)\n",
                corners == cutExpected.corners.cornerBytes() ? "yes" : "NO", sameSeams ? "yes" : "NO", cutExpected.seams.size());
    const VoxelBuildResult built = buildVoxelBasis(cleaned.mesh, cleaned.topology, inMemory, cutExpected, voxelOptions);
    auto t10 = Clock::now();
    line("in memory: voxel basis", t9, t10);
    std::printf("  clip %.2f s, basis %.2f s\n", built.secondsClip, built.secondsBasis);
    const VoxelBasis &got = *voxels.basis, &want = *built.basis;
    std::size_t wrong = 0;
    for (std::uint64_t e = 0; e < want.numElements() && e < got.numElements(); ++e) {
      ElementIntegrals a, b;
      got.elementIntegrals(e, a);
      want.elementIntegrals(e, b);
      wrong += a.domain != b.domain || a.stiffness != b.stiffness || a.rhs != b.rhs;
    }
    bool sameAdjacency = got.adjacencies().size() == want.adjacencies().size();
    for (std::size_t i = 0; sameAdjacency && i < want.adjacencies().size(); ++i) {
      sameAdjacency = got.adjacencies()[i].left == want.adjacencies()[i].left &&
                      got.adjacencies()[i].right == want.adjacencies()[i].right &&
                      got.adjacencies()[i].seam == want.adjacencies()[i].seam;
    }
    std::printf("  basis equal to the in-memory one: %s (%llu elements, %zu differ; domains %s; adjacency %s)\n",
                got.numElements() == want.numElements() && wrong == 0 ? "yes" : "NO",
                (unsigned long long)want.numElements(), wrong, got.domainBasis() == want.domainBasis() ? "equal" : "DIFFER",
                sameAdjacency ? "equal" : "DIFFERS");
    ParamOptions param;
    param.edgeLength = voxelOptions.edgeLength;
    param.smoothedEvaluation = false;  // out of core, a later pass of its own
    const VoxelParamResult vox = parameterizeMeshVoxel(cleaned.mesh, cleaned.topology, inMemory, cutExpected, param, 128);
    auto t11 = Clock::now();
    line("in memory: vox solve (whole)", t10, t11);
    std::vector<Vec2d> values(solved.map.numWedges);
    ScratchReader valueReader(folder, solved.map.wedgeValues, "bench");
    if (!values.empty() && !valueReader.read(values.data(), values.size() * sizeof(Vec2d))) return 1;
    double largestMap = 0.0;
    for (std::uint32_t w = 0; w < vox.param.cornerUV.numWedges() && w < values.size(); ++w) {
      largestMap = std::max(largestMap, (values[w] - vox.param.cornerUV.wedgeValue(w)).norm());
    }
    std::printf("  vox map: wedges %s, translations %s, largest difference %.3g\n",
                vox.param.cornerUV.numWedges() == values.size() ? "equal" : "DIFFER",
                vox.param.translations == solved.translations ? "equal" : "DIFFER", largestMap);
  }
  return 0;
}
