#include "stream/field_stream.h"

#include <algorithm>
#include <memory>
#include <vector>

#include "core/field/detail_smoothing.h"
#include "core/system/parallel.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

/// The cleaned mesh's corner table through page caches: the same fan walk as Topology's.
class PagedCornerTable {
 public:
  PagedCornerTable(const CleanScratch& scratch, std::size_t cacheBytes)
      : faces_(scratch.faces, cacheBytes), opposite_(scratch.opposite, cacheBytes),
        vertexCorner_(scratch.vertexCorner, cacheBytes) {}
  VertexId vertex(CornerId c) { return faces_[c / 3].triangle[c % 3]; }
  CornerId opposite(CornerId c) { return opposite_[c]; }
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

// Per page cache: lookups in Morton order stay within a few megabytes of each file, and a
// thread holds a handful of caches; a larger cache hardly saves reads.
std::size_t pageCacheBytes(std::uint64_t memoryBytes) {
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(memoryBytes / 32, std::uint64_t(1) << 17, std::uint64_t(1) << 23));
}

// Records per block written at once: 12 MB of positions.
constexpr std::uint64_t kBlockVertices = std::uint64_t(1) << 20;

}  // namespace

ScratchFile smoothScratchPositions(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t iterations,
                                   std::uint64_t memoryBytes) {
  const char* stage = "field: smooth";
  const std::size_t cacheBytes = pageCacheBytes(memoryBytes);
  ScratchFile current = scratch.positions;
  for (std::uint32_t it = 0; it < iterations; ++it) {
    struct Readers {
      PagedCornerTable table;
      PagedReader<Vec3f> positions;
    };
    ReaderPool<Readers> pool([&] {
      return std::unique_ptr<Readers>(new Readers{PagedCornerTable(scratch, cacheBytes), PagedReader<Vec3f>(current, cacheBytes)});
    });
    ScratchWriter writer(folder, stage);
    std::vector<Vec3f> next;
    for (std::uint64_t first = 0; first < scratch.numVertices; first += kBlockVertices) {
      const std::uint64_t count = std::min(kBlockVertices, scratch.numVertices - first);
      next.resize(count);
      parallelFor(count, 4096, [&](const IndexRange& range) {
        auto readers = pool.take();
        auto valueOf = [&](VertexId w) -> Vec3d { return readers->positions[w].cast<double>(); };
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
          next[i] = detail::smoothingStep(readers->table, static_cast<VertexId>(first + i), valueOf);
        }
      });
      writer.write(next.data(), count * sizeof(Vec3f));
    }
    pool.forEach([&](Readers& r) { folder.countRead(stage, r.table.bytesRead() + r.positions.bytesRead()); });
    const ScratchFile written = writer.finish();
    if (it > 0) folder.remove(current);
    current = written;
  }
  return current;
}

}  // namespace seamvox
