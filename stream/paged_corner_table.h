#pragma once
/// The cleaned mesh's corner table and face corners (clean_stream) read through page caches, for
/// the out-of-core passes that walk it as Topology is walked.
#include <algorithm>
#include <array>
#include <cstdint>

#include "core/mesh/topology.h"
#include "stream/clean_stream.h"
#include "stream/paged_reader.h"

namespace seamvox {

/// The cleaned mesh's corner table through page caches: the same fan walk as Topology's.
class PagedCornerTable {
 public:
  PagedCornerTable(const CleanScratch& scratch, std::size_t cacheBytes, std::size_t pageBytes = kScratchPageBytes)
      : faces_(scratch.faces, cacheBytes, pageBytes), opposite_(scratch.opposite, cacheBytes, pageBytes),
        vertexCorner_(scratch.vertexCorner, cacheBytes, pageBytes) {}
  VertexId vertex(CornerId c) { return faces_[c / 3].triangle[c % 3]; }
  CornerId opposite(CornerId c) { return opposite_[c]; }
  CornerId vertexCorner(VertexId v) { return vertexCorner_[v]; }
  bool isIsolatedVertex(VertexId v) { return vertexCorner_[v] == kInvalidId; }
  bool isBoundaryVertex(VertexId v) {
    const CornerId c = vertexCorner_[v];
    return c != kInvalidId && cw(c) == kInvalidId;
  }
  CornerId ccw(CornerId c) {
    const CornerId o = opposite_[nextCorner(c)];
    return o == kInvalidId ? kInvalidId : nextCorner(o);
  }
  CornerId cw(CornerId c) {
    const CornerId o = opposite_[prevCorner(c)];
    return o == kInvalidId ? kInvalidId : prevCorner(o);
  }
  template <class F>
  void forEachCornerAround(VertexId v, F&& f) {
    walkCornersAround(*this, vertexCorner_[v], f);
  }
  std::uint64_t bytesRead() const { return faces_.bytesRead() + opposite_.bytesRead() + vertexCorner_.bytesRead(); }

 private:
  PagedReader<CleanFace> faces_;
  PagedReader<CornerId> opposite_;
  PagedReader<CornerId> vertexCorner_;
};

/// Per page cache: lookups in Morton order stay within a few megabytes of each file, and a
/// thread holds a handful of caches; a larger cache hardly saves reads.
inline std::size_t pageCacheBytes(std::uint64_t memoryBytes) {
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(memoryBytes / 32, std::uint64_t(1) << 17, std::uint64_t(1) << 23));
}

/// Per page cache of a window scattered over the mesh (small pages): what a window of about
/// memoryBytes / 1 KiB faces reads of one file, in clusters around far-apart seeds.
inline std::size_t windowCacheBytes(std::uint64_t memoryBytes) {
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(memoryBytes / 64, std::uint64_t(1) << 20, std::uint64_t(1) << 25));
}

/// A face's corner positions (in double, as TriangleMesh::position gives them) through caches.
class PagedFacePoints {
 public:
  PagedFacePoints(const CleanScratch& scratch, const ScratchFile& positions, std::size_t cacheBytes,
                  std::size_t pageBytes = kScratchPageBytes)
      : faces_(scratch.faces, cacheBytes, pageBytes), positions_(positions, cacheBytes, pageBytes) {}
  Triangle triangle(FaceId f) { return faces_[f].triangle; }
  std::array<Vec3d, 3> points(const Triangle& t) {
    return {positions_[t[0]].cast<double>(), positions_[t[1]].cast<double>(), positions_[t[2]].cast<double>()};
  }
  std::array<Vec3d, 3> points(FaceId f) { return points(triangle(f)); }
  std::uint64_t bytesRead() const { return faces_.bytesRead() + positions_.bytesRead(); }

 private:
  PagedReader<CleanFace> faces_;
  PagedReader<Vec3f> positions_;
};

}  // namespace seamvox
