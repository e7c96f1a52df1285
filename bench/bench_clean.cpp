// Read + clean + corner table benchmark on a large mesh file: wall time per step (and per
// cleaning sub-step, from the progress callback) and peak resident memory of the whole run.
//   seamvox gen scan --faces 20000000 -o /tmp/seamvox_bench_20M.ply
//   bench_clean [MESH=/tmp/seamvox_bench_20M.ply] [THREADS=2] [weld]
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/topology.h"
#include "bench/bench_common.h"
#include "io/mesh_io.h"
#include "core/system/memory.h"

namespace {

using namespace seamvox;
using bench::Clock;
using bench::mib;
using bench::seconds;

/// Processor time of the whole process (all threads), user + system: unlike wall time it
/// hardly depends on what else runs on the machine.
double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "/tmp/seamvox_bench_20M.ply";
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  const bool weld = argc > 3 && !std::strcmp(argv[3], "weld");
  if (!std::filesystem::exists(path)) {
    std::fprintf(stderr, "bench_clean: %s does not exist; make it with\n"
                         "  seamvox gen scan --faces 20000000 -o %s\n", path.c_str(), path.c_str());
    return 2;
  }
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
  std::printf("bench_clean %s, %d threads%s\n", path.c_str(), threads, weld ? ", weld" : "");

  std::printf("%-34s %7s   %7s\n", "step", "wall", "cpu");
  const double c0 = cpuSeconds();
  const auto t0 = Clock::now();
  TriangleMesh mesh = readMesh(path);
  const auto t1 = Clock::now();
  const double c1 = cpuSeconds();
  std::printf("%-34s %7.2f s %7.2f s   RSS %7.1f MiB, peak %7.1f MiB   (%u faces, %u vertices)\n", "read",
              seconds(t0, t1), c1 - c0, mib(currentResidentBytes()), mib(peakResidentBytes()),
              mesh.numFaces(), mesh.numVertices());

  // Cleaning sub-steps: the time between successive progress reports.
  struct Mark {
    double fraction;
    Clock::time_point at;
    double cpu;
    std::uint64_t peak;
  };
  std::vector<Mark> marks;
  CleanOptions options;
  options.weldVertices = weld;
  options.progress = [&](const char*, double fraction) {
    marks.push_back({fraction, Clock::now(), cpuSeconds(), peakResidentBytes()});
    return true;
  };
  const double c2 = cpuSeconds();
  const auto t2 = Clock::now();
  CleanResult cleaned = cleanMesh(std::move(mesh), options);
  const auto t3 = Clock::now();
  const double c3 = cpuSeconds();
  std::printf("%-34s %7.2f s %7.2f s   RSS %7.1f MiB, peak %7.1f MiB   (%llu faces, topology %.1f MiB)\n",
              "clean + corner table", seconds(t2, t3), c3 - c2, mib(currentResidentBytes()),
              mib(peakResidentBytes()), static_cast<unsigned long long>(cleaned.report.outputFaces),
              mib(cleaned.topology.memoryBytes()));
  Mark previous{0.0, t2, c2, 0};
  for (const Mark& m : marks) {
    if (m.fraction == previous.fraction) continue;
    char label[64];
    std::snprintf(label, sizeof label, "  cleaning %.2f -> %.2f", previous.fraction, m.fraction);
    std::printf("%-34s %7.2f s %7.2f s   peak %7.1f MiB\n", label, seconds(previous.at, m.at),
                m.cpu - previous.cpu, mib(m.peak));
    previous = m;
  }
  std::printf("%-34s %7.2f s %7.2f s\n", "  after the last report", seconds(previous.at, t3),
              c3 - previous.cpu);

  const double c4 = cpuSeconds();
  const auto t4 = Clock::now();
  const ComponentsResult components = computeComponents(cleaned.topology);
  const auto t5 = Clock::now();
  const double c5 = cpuSeconds();
  std::printf("%-34s %7.2f s %7.2f s   RSS %7.1f MiB, peak %7.1f MiB   (%zu components, %u boundary loops)\n",
              "components", seconds(t4, t5), c5 - c4, mib(currentResidentBytes()), mib(peakResidentBytes()),
              components.components.size(), components.boundaryLoops);
  std::printf("%-34s %7.2f s %7.2f s   peak RSS %7.1f MiB\n", "total read + clean + corner table",
              seconds(t0, t3), c3 - c0, mib(peakResidentBytes()));
  return 0;
}
