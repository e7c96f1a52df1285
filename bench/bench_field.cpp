// Field + cut benchmark: time and peak memory of the smoothest field (direct CHOLMOD solve or the
// proxy field), singularities and the cut on a mesh file or a generated mesh; cones and the
// smoothness energy (measureFieldEnergy) of the result, and the factorization's size. One method
// per run, so the peak memory is that method's.
//   bench_field MESH [--method direct|proxy] [--grid N] [--sweeps K] [--curvature W]
//   bench_field --generate sphere|torus|genus2 FACES [same options]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/system/errors.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/synth/generate.h"
#include "io/mesh_io.h"
#include "core/system/memory.h"
#include "core/system/blas_threads.h"

namespace {

using Clock = std::chrono::steady_clock;

std::clock_t cpuMark = std::clock();  // process CPU time (all threads) at the last report

/// Wall time, process CPU time and peak memory since the last mark.
void report(const char* stage, Clock::time_point& mark) {
  const Clock::time_point now = Clock::now();
  const std::clock_t cpu = std::clock();
  std::printf("%-14s %8.2f s  cpu %8.2f s   peak %8.1f MB\n", stage,
              std::chrono::duration<double>(now - mark).count(), double(cpu - cpuMark) / CLOCKS_PER_SEC,
              seamvox::peakResidentBytes() / 1048576.0);
  std::fflush(stdout);
  mark = now;
  cpuMark = cpu;
}

}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  seamvox::limitBlasThreads(1);
  using namespace seamvox;
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: bench_field MESH | --generate KIND FACES  [--method direct|proxy] [--grid N]\n"
                 "                   [--sweeps K] [--curvature W]\n");
    return 2;
  }
  try {
    SmoothFieldOptions fieldOptions;
    // Sub-stage times of the field solve (assemble, factor, eigenvector iterations, curvature).
    std::string stage;
    int steps = 0;
    Clock::time_point stageStart = Clock::now();
    fieldOptions.progress = [&](const char* name, double) {
      if (stage != name) {
        if (!stage.empty()) {
          std::printf("  %-24s %8.2f s  (%d calls)\n", stage.c_str(),
                      std::chrono::duration<double>(Clock::now() - stageStart).count(), steps);
        }
        stage = name;
        steps = 0;
        stageStart = Clock::now();
      }
      ++steps;
      return true;
    };
    FieldMethod method = FieldMethod::Direct;
    ProxyFieldOptions proxyOptions;
    proxyOptions.progress = fieldOptions.progress;
    FieldSolveStats solve;  // the factorization of either method
    fieldOptions.stats = &solve;
    proxyOptions.stats = &solve;
    for (int i = 1; i + 1 < argc; ++i) {
      if (!std::strcmp(argv[i], "--curvature")) fieldOptions.curvatureWeight = std::atof(argv[i + 1]);
      if (!std::strcmp(argv[i], "--method")) method = parseFieldMethod(argv[i + 1]);
      if (!std::strcmp(argv[i], "--grid")) proxyOptions.gridResolution = std::atoi(argv[i + 1]);
      if (!std::strcmp(argv[i], "--sweeps")) proxyOptions.smoothingSweeps = std::atoi(argv[i + 1]);
    }
    Clock::time_point mark = Clock::now();
    TriangleMesh raw;
    if (!std::strcmp(argv[1], "--generate") && argc >= 4) {
      GenerateOptions options;
      options.kind = parseMeshKind(argv[2]);
      options.faces = std::strtoull(argv[3], nullptr, 10);
      raw = generateMesh(options).mesh;
      report("generate", mark);
    } else {
      raw = readMesh(argv[1]);
      report("read", mark);
    }
    const CleanResult clean = cleanMesh(std::move(raw));
    std::printf("faces %u vertices %u\n", clean.mesh.numFaces(), clean.mesh.numVertices());
    report("clean", mark);
    method = resolveFieldMethod(method, clean.mesh.numFaces());
    CrossField field;
    if (method == FieldMethod::Proxy) {
      ProxyFieldResult proxy = computeProxyField(clean.mesh, clean.topology, proxyOptions);
      fieldOptions.progress("done", 1.0);
      std::printf("proxy: grid %d, %u elements, %llu element pairs, %u colours, %d sweeps\n",
                  proxyOptions.gridResolution, proxy.elements,
                  static_cast<unsigned long long>(proxy.elementEdges), proxy.colours,
                  proxyOptions.smoothingSweeps);
      field = std::move(proxy.field);
    } else {
      field = computeSmoothestField(clean.mesh, clean.topology, fieldOptions);
      fieldOptions.progress("done", 1.0);
    }
    report(method == FieldMethod::Proxy ? "proxy field" : "direct field", mark);
    std::printf("factor: %llu unknowns, %llu nonzeros, %.1f MB (CHOLMOD peak %.1f MB)\n",
                static_cast<unsigned long long>(solve.unknowns), static_cast<unsigned long long>(solve.factorNonzeros),
                solve.factorBytes / 1048576.0, solve.factorPeakBytes / 1048576.0);
    const FieldSingularities sing = computeSingularities(clean.mesh, clean.topology, field);
    report("singularities", mark);
    const CutResult cut = cutToDisk(clean.mesh, clean.topology, field, sing);
    report("cut", mark);
    std::printf("cones %zu (index sum %lld/4), seams %zu\n", sing.cones.size(),
                static_cast<long long>(sing.indexSum4()), cut.seams.size());
    std::printf("energy %.6g\n", measureFieldEnergy(clean.mesh, clean.topology, field));
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_field: %s\n", e.what());
    return 1;
  }
  return 0;
}
