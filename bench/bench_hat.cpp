// Hat-solver benchmark: the library pipeline (parameterize, as `seamvox param --solver hat`) with
// per-stage time and peak memory, relative L2 gradient error and flipped fraction on armadillo and
// on fertility subdivided 1-to-4 (36K, 144K, 576K, 2.3M faces).
//   bench_hat [DATA_DIR] [--levels L] [--cells N] [--mesh NAME]...
// The field of a subdivided mesh is its parent face's field (children are coplanar with it).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "core/pipeline/parameterize.h"
#include "core/system/blas_threads.h"
#include "core/system/memory.h"
#include "io/mesh_io.h"

using namespace seamvox;

namespace {

/// One case through the library pipeline (core/pipeline/parameterize.h) with the hat solver, as
/// `seamvox param --solver hat` runs it (cones merged, cone passes); an inherited field is passed
/// as an imported one. Stages from the pipeline's meter, the solve's parts from its figures.
void runCase(const std::string& label, const TriangleMesh& inputMesh, const CrossField* inherited,
             double cells) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.spacing.cells = cells;
  if (inherited) {
    options.field.importedPerInputFace.resize(inherited->direction.size());
    for (FaceId f = 0; f < inherited->direction.size(); ++f) options.field.importedPerInputFace[f] = inherited->at(f);
  }
  StageMeter meter;
  options.meter = &meter;
  const PipelineResult r = parameterize(inputMesh, options);
  const ParamResult& p = r.solved.param;
  const SeamlessStats& st = p.stats;
  std::printf("\n== %s: %u faces, %u vertices, %zu cones, %u seams, h = diag/%.0f (field %s)\n", label.c_str(),
              r.mesh.numFaces(), r.mesh.numVertices(), r.cones.size(), r.seams, cells, r.fieldMethod.c_str());
  for (const StageFigures& s : meter.stages()) {
    std::printf("  %-28s %8.2f s  peak %8.1f MB\n", s.name.c_str(), s.seconds, s.peakBytes / 1048576.0);
  }
  std::printf("  solve detail: basis %.2f s, reduce %.2f s, assemble %.2f s, first solve %.2f s, round %.2f s, "
              "second solve %.2f s, evaluate %.2f s\n",
              p.secondsBasis, p.secondsReduce, st.secondsAssemble, st.secondsFirstSolve, st.secondsRound,
              st.secondsSecondSolve, p.secondsEvaluate);
  std::printf("  field: %llu unknowns, factor %.1f MB\n", static_cast<unsigned long long>(r.fieldSolve.unknowns),
              r.fieldSolve.factorBytes / 1048576.0);
  std::printf("  unknowns %u (translational %u), K nonzeros %llu, factor nonzeros %llu, factor %.1f MB "
              "(CHOLMOD peak %.1f MB)%s\n",
              st.unknowns, st.translational, static_cast<unsigned long long>(st.systemNonzeros),
              static_cast<unsigned long long>(st.factorNonzeros), st.factorBytes / 1048576.0,
              st.factorPeakBytes / 1048576.0, st.realFallback ? " [real fallback]" : "");
  std::printf("  relative L2 error %.5f, flipped %llu (%.5f%%), collapsed %llu, seam residual %.2e, "
              "integer distance %.2e\n",
              r.mapQuality.relativeGradientError, static_cast<unsigned long long>(r.mapQuality.flipped),
              100.0 * r.mapQuality.flippedFraction, static_cast<unsigned long long>(r.mapQuality.collapsed),
              r.seamQuality.maxResidual, r.seamQuality.maxIntegerDistance);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  seamvox::limitBlasThreads(1);
  std::string dir = "../shared/data";
  int levels = 4;
  double cells = 100;
  std::vector<std::string> only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--levels") && i + 1 < argc) {
      levels = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--cells") && i + 1 < argc) {
      cells = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--mesh") && i + 1 < argc) {
      only.push_back(argv[++i]);
    } else {
      dir = argv[i];
    }
  }
  auto wanted = [&](const std::string& name) {
    if (only.empty()) return true;
    for (const auto& o : only) {
      if (o == name) return true;
    }
    return false;
  };
  try {
    if (wanted("armadillo")) runCase("armadillo", readMesh(dir + "/armadillo.obj"), nullptr, cells);
    if (wanted("fertility")) {
      bench::forEachSubdividedFertility(dir, levels, [&](const std::string& name, const TriangleMesh& mesh,
                                                         const CrossField& field) {
        runCase(name, mesh, &field, cells);
      });
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_hat: %s\n", e.what());
    return 1;
  }
  return 0;
}
