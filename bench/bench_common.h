#pragma once
// Helpers shared by the bench drivers (header only: each bench_*.cpp is its own program).
#include <chrono>
#include <cstdint>
#include <string>

#include "core/mesh/clean.h"
#include "core/field/field.h"
#include "core/mesh/subdivide.h"
#include "io/mesh_io.h"

namespace seamvox::bench {

using Clock = std::chrono::steady_clock;

inline double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
inline double mib(std::uint64_t bytes) { return bytes / 1048576.0; }

/// The fertility scaling series: fertility.off in dataDir subdivided 1 to `levels` times, each
/// with the base mesh's smoothest field inherited by the subdivided faces (the same problem at
/// every size). Calls run(name, mesh, field) per level.
template <class Run>
void forEachSubdividedFertility(const std::string& dataDir, int levels, Run&& run) {
  const CleanResult base = cleanMesh(readMesh(dataDir + "/fertility.off"));
  const CrossField baseField = computeSmoothestField(base.mesh, base.topology);
  for (int level = 1; level <= levels; ++level) {
    SubdivideOptions options;
    options.levels = static_cast<std::uint32_t>(level);
    const SubdivideResult sub = subdivideMesh(base.mesh, base.topology, options);
    CrossField field;
    field.direction.resize(sub.parentFace.size());
    for (std::size_t f = 0; f < sub.parentFace.size(); ++f) field.direction[f] = baseField.direction[sub.parentFace[f]];
    run("fertility x4^" + std::to_string(level), sub.mesh, field);
  }
}

}  // namespace seamvox::bench
