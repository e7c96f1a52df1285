#include "stream/cone_pass_stream.h"

#include <algorithm>
#include <array>

#include "core/field/detail_cone_merge.h"
#include "core/quality/metrics.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

std::vector<std::pair<VertexId, VertexId>> scratchMergeableCoincidentCones(ScratchFolder& folder,
                                                                           const CleanScratch& scratch,
                                                                           const ScratchSingularities& singularities,
                                                                           const ScratchMap& map, double maxDistance,
                                                                           const StreamPassOptions& pass) {
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedReader<Vec3f> positions(scratch.positions, cacheBytes);
  PagedReader<std::uint32_t> cornerWedge(map.cornerWedge, cacheBytes);
  PagedReader<Vec2d> values(map.wedgeValues, cacheBytes);
  const auto pairs = detail::coincidentConesWith([&](VertexId v) -> Vec3d { return positions[v].cast<double>(); },
                                                 table, [&](CornerId c) { return values[cornerWedge[c]]; },
                                                 singularities.cones, maxDistance);
  folder.countRead("cone passes", table.bytesRead() + positions.bytesRead() + cornerWedge.bytesRead() + values.bytesRead());
  std::vector<std::pair<VertexId, VertexId>> out;
  for (const auto& [a, b] : pairs) {
    if (canMergeCoincident(coneIndexOf(singularities, a), coneIndexOf(singularities, b))) out.push_back({a, b});
  }
  return out;
}

FacesNearPoints facesNearConePairs(const CleanScratch& scratch, const std::vector<std::pair<VertexId, VertexId>>& pairs,
                                   double distance, const StreamPassOptions& pass) {
  PagedReader<Vec3f> positions(scratch.positions, pageCacheBytes(pass.memoryBytes));
  FacesNearPoints near;
  near.distance = distance;
  for (const auto& [a, b] : pairs) {
    near.points.push_back(positions[a].cast<double>());
    near.points.push_back(positions[b].cast<double>());
  }
  return near;
}

std::vector<std::pair<VertexId, VertexId>> scratchFoldedCoincidentCones(ScratchFolder& folder, const CleanScratch& scratch,
                                                                        const ScratchSingularities& singularities,
                                                                        const ScratchMap& map, double h,
                                                                        double maxDistance, const StreamPassOptions& pass) {
  const auto candidates = scratchMergeableCoincidentCones(folder, scratch, singularities, map, maxDistance, pass);
  if (candidates.empty()) return {};
  const FacesNearPoints near = facesNearConePairs(scratch, candidates, maxDistance, pass);
  // The flipped faces' centroids among the faces near the candidates, by one pass over the faces.
  std::vector<Vec3d> centroids;
  {
    ScratchMapFaces faces(folder, scratch, map, "cone passes", pageCacheBytes(pass.memoryBytes));
    faces.forEach([&](const MapFace& x) { return near.holds(x.p) && isFlippedRatio(parameterAreaRatio(x.p, x.q, h)); },
                  [&](const MapFace& x, bool nearFlip) {
                    if (nearFlip) centroids.push_back((x.p[0] + x.p[1] + x.p[2]) / 3.0);
                  });
    folder.countRead("cone passes", faces.cacheBytesRead());
  }
  const auto nearFlip = [&](const Vec3d& p) {
    return std::any_of(centroids.begin(), centroids.end(), [&](const Vec3d& c) { return (c - p).norm() <= maxDistance; });
  };
  std::vector<std::pair<VertexId, VertexId>> pairs;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    if (nearFlip(near.points[2 * k]) || nearFlip(near.points[2 * k + 1])) pairs.push_back(candidates[k]);
  }
  return pairs;
}

std::vector<std::pair<VertexId, VertexId>> scratchFoldedConesAfterRepair(ScratchFolder& folder,
                                                                         const CleanScratch& scratch,
                                                                         const ScratchSingularities& singularities,
                                                                         const ScratchMap& map, double h,
                                                                         double maxDistance,
                                                                         const StreamPassOptions& pass) {
  std::vector<std::pair<VertexId, VertexId>> pairs =
      scratchFoldedCoincidentCones(folder, scratch, singularities, map, h, maxDistance, pass);
  {
    const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
    PagedCornerTable table(scratch, cacheBytes);
    PagedFacePoints points(scratch, scratch.positions, cacheBytes);
    PagedReader<Vec3f> positions(scratch.positions, cacheBytes);
    PagedReader<std::uint32_t> cornerWedge(map.cornerWedge, cacheBytes);
    PagedReader<Vec2d> values(map.wedgeValues, cacheBytes);
    const auto fanFlipped = [&](VertexId v) {
      bool flipped = false;
      table.forEachCornerAround(v, [&](CornerId c) {
        const FaceId f = cornerFace(c);
        const std::array<Vec2d, 3> q{values[cornerWedge[3 * f]], values[cornerWedge[3 * f + 1]], values[cornerWedge[3 * f + 2]]};
        flipped |= isFlippedRatio(parameterAreaRatio(points.points(f), q, h));
      });
      return flipped;
    };
    for (const auto& pair : detail::foldedCloseConesWith(
             [&](VertexId v) -> Vec3d { return positions[v].cast<double>(); }, table, singularities.cones,
             [&](VertexId v) { return coneIndexOf(singularities, v); }, fanFlipped, maxDistance)) {
      pairs.push_back(pair);
    }
    folder.countRead("cone passes", table.bytesRead() + points.bytesRead() + positions.bytesRead() +
                                        cornerWedge.bytesRead() + values.bytesRead());
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace seamvox
