// Hat vs Vox vs Vox+HatLoc (DESIGN sections 10-11): relative L2 gradient error, flips, collapsed
// triangles, seam residual, refined vertex fraction, local system size and times, on fertility
// subdivided 1-to-4 (36K faces at level 1) and armadillo. One cut from the pipeline's stages
// (field, cone merging) for the three solvers; the local refinement runs on the same Vox map for
// each number of rings, which is why this one calls the solvers itself rather than parameterize.
//   bench_refine [DATA_DIR] [--grid N] [--cells N] [--levels L] [--mesh NAME]... [--rings K]...
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/solve/hat_solver.h"
#include "core/refine/refine.h"
#include "core/mesh/subdivide.h"
#include "core/pipeline/parameterize.h"
#include "bench/bench_common.h"
#include "io/mesh_io.h"
#include "core/system/memory.h"
#include "core/basis/voxel_grid.h"
#include "core/system/blas_threads.h"
#include "core/system/stopwatch.h"

using namespace seamvox;

namespace {


struct Options {
  std::int32_t grid = 128;
  double cells = 100;
  std::vector<std::uint32_t> rings;
};

void printMap(const char* name, double seconds, const TriangleMesh& mesh, const Topology& topology,
              const CutResult& cut, const CrossField& field, const WedgeMap& uv,
              double h, double hatError) {
  const SeamQuality seams = measureSeams(mesh, topology, cut, uv);
  const MapQuality q = measureMap(mesh, uv, &field, h);
  std::printf("  %-16s L2 %.5f (%.3fx hat)  flipped %6llu  collapsed %6llu  seam residual %.1e  "
              "integer %.1e  %7.2f s\n",
              name, q.relativeGradientError, hatError > 0 ? q.relativeGradientError / hatError : 1.0,
              static_cast<unsigned long long>(q.flipped), static_cast<unsigned long long>(q.collapsed),
              seams.maxResidual, seams.maxIntegerDistance, seconds);
}

void runCase(const std::string& label, const TriangleMesh& input, const CrossField* inherited,
             const Options& options) {
  // The pipeline's first pass (core/pipeline/parameterize.h): clean, field (an inherited one as
  // imported), close cones merged, cut. The three maps below then share this cut.
  CleanResult clean = cleanMesh(input);
  const TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  FieldSource source;
  if (inherited) {
    source.importedPerInputFace.resize(inherited->direction.size());
    for (FaceId f = 0; f < inherited->direction.size(); ++f) source.importedPerInputFace[f] = inherited->at(f);
  }
  CrossField field = computeFieldFromSource(clean.mesh, topology, clean.faceOrigin, input.numFaces(), source);
  ParamOptions param;
  param.edgeLength = clean.report.diagonalWithoutSpikes / options.cells;
  const CutResult cut = cutThroughCones(mesh, topology, field, kConeMergeFraction * param.edgeLength).cut;
  std::printf("\n== %s: %u faces, %u vertices, %zu cones, %zu seams, h = diag/%.0f, grid %d\n",
              label.c_str(), mesh.numFaces(), mesh.numVertices(), cut.cones.size(), cut.seams.size(),
              options.cells, options.grid);

  auto start = std::chrono::steady_clock::now();
  const ParamResult hat = parameterizeMesh(mesh, topology, field, cut, param);
  const double hatSeconds = secondsSince(start);
  const double hatError = measureMap(mesh, hat.cornerUV, &field, param.edgeLength).relativeGradientError;
  printMap("hat", hatSeconds, mesh, topology, cut, field, hat.cornerUV, param.edgeLength, hatError);
  std::printf("  %-16s unknowns %u, factor %.1f MB\n", "", hat.stats.unknowns,
              hat.stats.factorBytes / 1048576.0);

  start = std::chrono::steady_clock::now();
  const VoxelParamResult vox = parameterizeMeshVoxel(mesh, topology, field, cut, param, options.grid);
  const double voxSeconds = secondsSince(start);
  printMap("vox", voxSeconds, mesh, topology, cut, field, vox.param.cornerUV, param.edgeLength,
           hatError);
  std::printf("  %-16s unknowns %u, factor %.1f MB, marked faces %zu (cone functions %u, "
              "inconsistent %u)\n",
              "", vox.param.stats.unknowns, vox.param.stats.factorBytes / 1048576.0,
              vox.markedFaces.size(), vox.determinedBasis, vox.inconsistentBasis);

  for (std::uint32_t rings : options.rings) {
    RefineOptions refine;
    refine.edgeLength = param.edgeLength;
    refine.markedFaces = vox.markedFaces;
    refine.rings = rings;
    const RefineResult r = refineNearCones(mesh, topology, field, cut, vox.param.cornerUV,
                                           vox.param.translations, refine);
    WedgeMap uv = vox.param.cornerUV;
    std::vector<std::complex<double>> translations = vox.param.translations;
    applyRefinement(r, uv, &translations);
    const std::string name = "voxloc rings " + std::to_string(rings);
    printMap(name.c_str(), voxSeconds + r.stats.secondsTotal, mesh, topology, cut, field, uv,
             param.edgeLength, hatError);
    const RefineStats& s = r.stats;
    std::printf("  %-16s refined %.2f%% of vertices (%u free, %u locked), region %llu faces "
                "(marked %llu, collapsed %llu, flipped %llu), local unknowns %u, nonzeros %llu, "
                "factor %.2f MB, refine %.3f s (region %.3f, extract %.3f, solve %.3f)\n",
                "", 100.0 * s.refinedVertexFraction, s.freeVertices, s.lockedVertices,
                static_cast<unsigned long long>(s.regionFaces),
                static_cast<unsigned long long>(s.markedFaces),
                static_cast<unsigned long long>(s.collapsedFaces),
                static_cast<unsigned long long>(s.flippedFaces), s.unknowns,
                static_cast<unsigned long long>(s.systemNonzeros), s.factorBytes / 1048576.0,
                s.secondsTotal, s.secondsRegion, s.secondsExtract, s.secondsSolve);
  }
  std::printf("  peak resident %.1f MB\n", peakResidentBytes() / 1048576.0);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  seamvox::limitBlasThreads(1);
  std::string dir = "../shared/data";
  Options options;
  int levels = 1;
  std::vector<std::string> only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) {
      options.grid = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--cells") && i + 1 < argc) {
      options.cells = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--levels") && i + 1 < argc) {
      levels = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--rings") && i + 1 < argc) {
      options.rings.push_back(static_cast<std::uint32_t>(std::atoi(argv[++i])));
    } else if (!std::strcmp(argv[i], "--mesh") && i + 1 < argc) {
      only.push_back(argv[++i]);
    } else {
      dir = argv[i];
    }
  }
  if (options.rings.empty()) options.rings = {0, 1, 2};
  auto wanted = [&](const std::string& name) {
    if (only.empty()) return true;
    for (const auto& o : only) {
      if (o == name) return true;
    }
    return false;
  };
  try {
    if (wanted("fertility")) {
      bench::forEachSubdividedFertility(dir, levels, [&](const std::string& name, const TriangleMesh& mesh,
                                                         const CrossField& field) {
        runCase(name, mesh, &field, options);
      });
    }
    if (wanted("armadillo")) runCase("armadillo", readMesh(dir + "/armadillo.obj"), nullptr, options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_refine: %s\n", e.what());
    return 1;
  }
  return 0;
}
