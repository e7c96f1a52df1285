#include "stream/refine_stream.h"

#include <algorithm>
#include <string>

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

}  // namespace seamvox
