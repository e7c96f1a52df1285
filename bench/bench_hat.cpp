// Hat-solver benchmark: per-stage time and peak memory, relative L2 gradient error and flipped
// fraction on armadillo and on fertility subdivided 1-to-4 (36K, 144K, 576K, 2.3M faces).
//   bench_hat [DATA_DIR] [--levels L] [--cells N] [--mesh NAME]...
// The field of a subdivided mesh is its parent face's field (children are coplanar with it).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "core/basis/basis.h"
#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/solve/evaluate.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/basis/reduce.h"
#include "core/solve/assemble.h"
#include "core/solve/seamless_solve.h"
#include "core/mesh/subdivide.h"
#include "bench/bench_common.h"
#include "io/mesh_io.h"
#include "core/system/memory.h"
#include "core/system/blas_threads.h"

using namespace seamvox;

namespace {

// Resets the peak-RSS mark (Linux: writing 5 to clear_refs), so each stage reports its own peak.
void resetPeak() {
  std::ofstream clear("/proc/self/clear_refs");
  if (clear) clear << "5";
}

struct Stage {
  std::string name;
  double seconds = 0;
  double peakMB = 0;
};

template <class F>
void timeStage(std::vector<Stage>& stages, const char* name, F&& f) {
  resetPeak();
  const auto start = std::chrono::steady_clock::now();
  f();
  stages.push_back({name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                    peakResidentBytes() / 1048576.0});
}

void runCase(const std::string& label, const TriangleMesh& inputMesh, const CrossField* inherited,
             double cells) {
  std::vector<Stage> stages;
  CleanResult clean;
  timeStage(stages, "clean", [&] { clean = cleanMesh(inputMesh); });
  const TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  CrossField field;
  FieldSingularities sing;
  timeStage(stages, "field", [&] {
    if (inherited) {
      std::vector<Vec3d> v(mesh.numFaces());
      for (FaceId f = 0; f < mesh.numFaces(); ++f) v[f] = inherited->at(clean.faceOrigin[f]);
      field = projectToTangent(mesh, std::move(v));
    } else {
      field = computeSmoothestField(mesh, topology);
    }
    sing = computeSingularities(mesh, topology, field);
  });
  CutResult cut;
  timeStage(stages, "cut", [&] { cut = cutToDisk(mesh, topology, field, sing); });
  const double h = computeBoundingBox(mesh.positions).diagonal() / cells;
  HatBasisOptions basisOptions;
  basisOptions.edgeLength = h;
  std::unique_ptr<HatBasis> basis;
  timeStage(stages, "basis", [&] { basis = std::make_unique<HatBasis>(mesh, topology, field, cut, basisOptions); });
  Reduction reduction;
  timeStage(stages, "reduce", [&] { reduction = reduceBasis(*basis); });
  SeamlessSolution solution;
  timeStage(stages, "assemble+solve+round+solve", [&] { solution = solveSeamless(*basis, reduction); });
  WedgeMap uv;
  timeStage(stages, "evaluate", [&] {
    uv = buildCutWedges(topology, cut);
    evaluateMap(*basis, reduction, solution.unknowns, uv);
  });
  SeamQuality seams;
  MapQuality quality;
  timeStage(stages, "metrics", [&] {
    seams = measureSeams(mesh, topology, cut, uv);
    quality = measureMap(mesh, uv, &field, h);
  });
  const SeamlessStats& st = solution.stats;
  std::printf("\n== %s: %u faces, %u vertices, %zu cones, %zu seams, h = diag/%.0f\n", label.c_str(),
              mesh.numFaces(), mesh.numVertices(), cut.cones.size(), cut.seams.size(), cells);
  for (const Stage& s : stages) {
    std::printf("  %-28s %8.2f s  peak %8.1f MB\n", s.name.c_str(), s.seconds, s.peakMB);
  }
  std::printf("  solve detail: assemble %.2f s, first solve %.2f s, round %.2f s, second solve %.2f s\n",
              st.secondsAssemble, st.secondsFirstSolve, st.secondsRound, st.secondsSecondSolve);
  std::printf("  unknowns %u (translational %u), K nonzeros %llu, factor nonzeros %llu, factor %.1f MB "
              "(CHOLMOD peak %.1f MB)%s\n",
              st.unknowns, st.translational, static_cast<unsigned long long>(st.systemNonzeros),
              static_cast<unsigned long long>(st.factorNonzeros), st.factorBytes / 1048576.0,
              st.factorPeakBytes / 1048576.0, st.realFallback ? " [real fallback]" : "");
  std::printf("  relative L2 error %.5f, flipped %llu (%.5f%%), collapsed %llu, seam residual %.2e, "
              "integer distance %.2e\n",
              quality.relativeGradientError, static_cast<unsigned long long>(quality.flipped),
              100.0 * quality.flippedFraction, static_cast<unsigned long long>(quality.collapsed),
              seams.maxResidual, seams.maxIntegerDistance);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
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
