#include "stream/refine_stream.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>

#include "core/quality/metrics.h"
#include "core/refine/detail_region.h"
#include "core/system/errors.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

RegionMesh extractScratchRegion(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                                const std::vector<FaceId>& regionFaces, const StreamPassOptions& pass) {
  const bool sorted = std::adjacent_find(regionFaces.begin(), regionFaces.end(),
                                         [](FaceId a, FaceId b) { return a >= b; }) == regionFaces.end();
  if (!sorted || (!regionFaces.empty() && regionFaces.back() >= scratch.numFaces)) {
    throw InputError("refine: region faces must be increasing face ids below " + std::to_string(scratch.numFaces));
  }
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedReader<Vec3f> positions(scratch.positions, cacheBytes), directions(field.directions, cacheBytes);
  PagedReader<std::uint8_t> rotations(cut.faceRotation, cacheBytes);
  PagedCutCorners corners(cut.corners, cacheBytes);
  return detail::extractRegionFrom(
      table, [&](VertexId v) { return positions[v]; }, [&](FaceId f) { return directions[f]; },
      [&](FaceId f) { return rotations[f]; }, corners, cut.seams, cut.cones, regionFaces);
}

std::vector<FaceId> selectScratchRefineRegion(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                                              const RefineOptions& options, const StreamPassOptions& pass,
                                              RefineStats* stats) {
  const std::uint64_t nf = scratch.numFaces;
  if (map.cornerWedge.bytes != 3 * nf * sizeof(std::uint32_t)) {
    throw InputError("refine: the map has " + std::to_string(map.cornerWedge.bytes / sizeof(std::uint32_t)) +
                     " corners for " + std::to_string(nf) + " faces (need 3 per face)");
  }
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength)) {
    throw InputError("refine: edge length must be positive and finite");
  }
  for (FaceId f : options.markedFaces) {
    if (f >= nf) {
      throw InputError("refine: marked face " + std::to_string(f) + " out of range (" + std::to_string(nf) + " faces)");
    }
  }
  std::vector<FaceId> marked = options.markedFaces;
  std::sort(marked.begin(), marked.end());
  marked.erase(std::unique(marked.begin(), marked.end()), marked.end());
  RefineStats counts;
  counts.markedFaces = marked.size();
  std::vector<FaceId> seeds;
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  if (options.seedFromMap) {
    PagedReader<Vec3f> positions(scratch.positions, cacheBytes);
    PagedReader<Vec2d> values(map.wedgeValues, cacheBytes);
    ScratchReader faces(folder, scratch.faces, "refine region"), wedges(folder, map.cornerWedge, "refine region");
    CleanFace face;
    std::uint32_t w[3];
    std::size_t nextMarked = 0;
    for (FaceId f = 0; faces.read(&face, sizeof face); ++f) {
      if (!wedges.read(w, sizeof w)) throw IoError(map.cornerWedge.path + ": scratch file ends early");
      if (nextMarked < marked.size() && marked[nextMarked] == f) {
        seeds.push_back(marked[nextMarked++]);
        continue;
      }
      const Triangle& t = face.triangle;
      const RefineSeed seed = classifyRefineSeed(
          parameterAreaRatio({positions[t[0]].cast<double>(), positions[t[1]].cast<double>(), positions[t[2]].cast<double>()},
                             {values[w[0]], values[w[1]], values[w[2]]}, options.edgeLength),
          options.collapseThreshold);
      if (seed == RefineSeed::None) continue;
      seeds.push_back(f);
      counts.collapsedFaces += seed == RefineSeed::Collapsed;
      counts.flippedFaces += seed == RefineSeed::Flipped;
    }
    folder.countRead("refine region", positions.bytesRead() + values.bytesRead());
  } else {
    seeds = marked;
  }
  // Rings: every face sharing a vertex with the frontier, options.rings times.
  std::unordered_set<FaceId> inRegion(seeds.begin(), seeds.end());
  std::unordered_set<VertexId> vertexSeen;
  std::vector<FaceId> region = seeds, frontier = seeds;
  for (std::uint32_t ring = 0; ring < options.rings && !frontier.empty(); ++ring) {
    std::vector<FaceId> added;
    for (FaceId f : frontier) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = table.vertex(3 * f + k);
        if (!vertexSeen.insert(v).second) continue;
        table.forEachCornerAround(v, [&](CornerId c) {
          if (inRegion.insert(cornerFace(c)).second) added.push_back(cornerFace(c));
        });
      }
    }
    region.insert(region.end(), added.begin(), added.end());
    frontier = std::move(added);
  }
  folder.countRead("refine region", table.bytesRead());
  std::sort(region.begin(), region.end());
  counts.regionFaces = region.size();
  copyRegionCounts(counts, stats);
  return region;
}

}  // namespace seamvox
