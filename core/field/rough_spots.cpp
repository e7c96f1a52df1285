#include "core/field/rough_spots.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/field/detail_rough_spots.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

double angleDefect(const Topology& topology, const std::vector<Vec3f>& positions, VertexId v) {
  return detail::angleDefectOf(topology, v, [&](VertexId w) -> Vec3d { return positions[w].cast<double>(); });
}

std::uint64_t roughRegionBoundInMemory(std::uint64_t numVertices, std::uint64_t headroomBytes) {
  const std::uint64_t spare = headroomBytes / kRoughRegionBytes;
  const std::uint64_t quarter = numVertices / 4;
  return std::max(kRoughRegionMinVertices, quarter + std::min(spare, ~std::uint64_t(0) - quarter));
}

RoughSpotResult smoothRoughSpots(const Topology& topology, std::vector<Vec3f>& positions, double gridLength,
                                 std::uint64_t maxRegion) {
  const std::uint32_t numVertices = topology.numVertices();
  detail::checkRoughSpotGrid(gridLength);
  if (positions.size() != numVertices) {
    throw InputError("smoothRoughSpots: " + std::to_string(positions.size()) + " positions for " +
                     std::to_string(numVertices) + " vertices");
  }
  const auto at = [&](VertexId w) -> Vec3d { return positions[w].cast<double>(); };
  // Each vertex's spacing once (4 B a vertex for the two passes), summed by chunks in vertex order.
  std::vector<float> own(numVertices);
  std::vector<std::pair<std::uint64_t, double>> chunks((numVertices + detail::kSpacingChunk - 1) / detail::kSpacingChunk);
  parallelForEach(chunks.size(), 1, [&](std::uint64_t k) {
    const VertexId end = static_cast<VertexId>(std::min<std::uint64_t>(numVertices, (k + 1) * detail::kSpacingChunk));
    for (VertexId v = static_cast<VertexId>(k * detail::kSpacingChunk); v < end; ++v) {
      own[v] = detail::vertexSpacing(topology, v, at);
      if (own[v] > 0.0f) chunks[k].first += 1, chunks[k].second += own[v];
    }
  });
  const double spacing = detail::roughSpacingLimit(gridLength, detail::meanSpacingOf(chunks));
  std::vector<std::uint8_t> rough(numVertices, 0);
  parallelFor(numVertices, 4096, [&](const IndexRange& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      rough[v] = detail::isRoughVertex(topology, v, at, spacing, own[v]);
    }
  });
  std::vector<float>().swap(own);
  std::vector<VertexId> seeds;
  for (VertexId v = 0; v < numVertices; ++v) {
    if (rough[v]) seeds.push_back(v);
  }
  std::vector<std::uint8_t>().swap(rough);
  RoughSpotResult result;
  result.roughVertices = static_cast<std::uint32_t>(seeds.size());
  if (seeds.empty()) return result;
  result.moved = detail::smoothRoughRounds(
      topology, [&](VertexId v) { return positions[v]; }, std::move(seeds), gridLength, spacing, result.rounds,
      maxRegion, &result.capped, numVertices);
  for (const auto& [v, p] : result.moved) positions[v] = p;
  return result;
}

}  // namespace seamvox
