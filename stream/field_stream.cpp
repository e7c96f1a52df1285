#include "stream/field_stream.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <future>
#include <memory>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/field/detail_cone_merge.h"
#include "core/field/detail_proxy.h"
#include "core/field/detail_rough_spots.h"
#include "core/field/detail_singularities.h"
#include "core/field/detail_smoothing.h"
#include "core/field/field_numerics.h"
#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"
#include "stream/scratch_union_find.h"

namespace seamvox {

ScratchFile smoothScratchPositions(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t iterations,
                                   const StreamPassOptions& pass) {
  const char* stage = "field: smooth";
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const std::uint64_t blockRecords = std::max<std::uint64_t>(1, pass.blockRecords);
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
    for (std::uint64_t first = 0; first < scratch.numVertices; first += blockRecords) {
      const std::uint64_t count = std::min(blockRecords, scratch.numVertices - first);
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

std::uint64_t roughRegionBound(std::uint64_t memoryBytes) {
  return std::max<std::uint64_t>(kRoughRegionMinVertices, memoryBytes / 2 / kRoughRegionBytes);
}

ScratchFile smoothScratchRoughSpots(ScratchFolder& folder, const CleanScratch& scratch, const ScratchFile& surface,
                                    double gridLength, const StreamPassOptions& pass, ScratchField& counts) {
  const char* stage = "field: rough spots";
  detail::checkRoughSpotGrid(gridLength);
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const std::uint64_t blockRecords = std::max<std::uint64_t>(1, pass.blockRecords);
  // The mesh's mean spacing, then the rough vertices: two passes over the vertices, as
  // smoothRoughSpots finds them (the spacings summed by the same chunks, in vertex order).
  std::vector<VertexId> seeds;
  double spacing = 0.0;
  {
    struct Readers {
      PagedCornerTable table;
      PagedReader<Vec3f> positions;
    };
    ReaderPool<Readers> pool([&] {
      return std::unique_ptr<Readers>(new Readers{PagedCornerTable(scratch, cacheBytes), PagedReader<Vec3f>(surface, cacheBytes)});
    });
    // value(readers, v) for every vertex, a block at a time in parallel, then use(v, value) in
    // vertex order.
    const auto eachVertex = [&](auto value, auto use) {
      std::vector<decltype(value(std::declval<Readers&>(), VertexId(0)))> block;
      for (std::uint64_t first = 0; first < scratch.numVertices; first += blockRecords) {
        const std::uint64_t count = std::min(blockRecords, scratch.numVertices - first);
        block.resize(count);
        parallelFor(count, 4096, [&](const IndexRange& range) {
          auto readers = pool.take();
          for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
            block[i] = value(*readers, static_cast<VertexId>(first + i));
          }
        });
        for (std::uint64_t i = 0; i < count; ++i) use(static_cast<VertexId>(first + i), block[i]);
      }
    };
    const auto atOf = [](Readers& r) { return [&r](VertexId w) -> Vec3d { return r.positions[w].cast<double>(); }; };
    std::vector<std::pair<std::uint64_t, double>> chunks((scratch.numVertices + detail::kSpacingChunk - 1) / detail::kSpacingChunk);
    eachVertex([&](Readers& r, VertexId v) { return detail::vertexSpacing(r.table, v, atOf(r)); },
               [&](VertexId v, float spacing) {
                 auto& chunk = chunks[v / detail::kSpacingChunk];
                 if (spacing > 0.0f) chunk.first += 1, chunk.second += spacing;
               });
    spacing = detail::roughSpacingLimit(gridLength, detail::meanSpacingOf(chunks));
    eachVertex([&](Readers& r, VertexId v) { return std::uint8_t(detail::isRoughVertex(r.table, v, atOf(r), spacing)); },
               [&](VertexId v, std::uint8_t rough) {
                 if (rough) seeds.push_back(v);
               });
    pool.forEach([&](Readers& r) { folder.countRead(stage, r.table.bytesRead() + r.positions.bytesRead()); });
  }
  counts.roughVertices = seeds.size();
  if (seeds.empty()) return surface;
  std::vector<std::pair<VertexId, Vec3f>> moved, normal;
  {
    PagedCornerTable table(scratch, windowCacheBytes(pass.memoryBytes), kWindowPageBytes);
    PagedReader<Vec3f> positions(surface, windowCacheBytes(pass.memoryBytes), kWindowPageBytes);
    std::uint32_t rounds = 0;
    bool capped = false;
    const auto plainAt = [&](VertexId v) { return positions[v]; };
    moved = detail::smoothRoughRounds(table, plainAt, std::move(seeds), gridLength, spacing, rounds,
                                      roughRegionBound(pass.memoryBytes), &capped);
    counts.roughSpotsCapped = capped;
    normal = detail::normalPartOfMoves(table, moved, plainAt);
    folder.countRead(stage, table.bytesRead() + positions.bytesRead());
  }
  counts.roughSpotVertices = moved.size();
  if (moved.empty()) return surface;
  // Copies of the surface with the moved vertices in place: the rough one (returned) and the
  // map's (counts.mapPositions); `surface` stays.
  const auto copyWith = [&](const std::vector<std::pair<VertexId, Vec3f>>& in) {
    ScratchWriter writer(folder, stage);
    ScratchRandomReader reader(folder, surface, stage);
    std::vector<Vec3f> block;
    auto next = in.begin();
    for (std::uint64_t first = 0; first < scratch.numVertices; first += blockRecords) {
      const std::uint64_t count = std::min(blockRecords, scratch.numVertices - first);
      block.resize(count);
      reader.readAt(first * sizeof(Vec3f), block.data(), count * sizeof(Vec3f));
      for (; next != in.end() && next->first < first + count; ++next) block[next->first - first] = next->second;
      writer.write(block.data(), count * sizeof(Vec3f));
    }
    return writer.finish();
  };
  counts.mapPositions = copyWith(normal);
  return copyWith(moved);
}

namespace {

/// Records [first, first + count) of a per-face scratch file, read at once (pread): a pass over a
/// block of faces reads them there instead of through a page cache per face.
template <class T>
void readFaceBlock(ScratchRandomReader& in, std::uint64_t first, std::uint64_t count, std::vector<T>& out) {
  out.resize(count);
  in.readAt(first * sizeof(T), out.data(), count * sizeof(T));
}

/// Calls fill(block, first, count) for blocks of faces in order, each filling `count` records of
/// T in parallel, and writes them to a new file.
template <class T, class Fill>
ScratchFile writeFaceBlocks(ScratchFolder& folder, const char* stage, std::uint64_t numFaces, std::uint64_t blockFaces,
                            Fill&& fill) {
  ScratchWriter writer(folder, stage);
  std::vector<T> block;
  for (std::uint64_t first = 0; first < numFaces; first += blockFaces) {
    const std::uint64_t count = std::min(blockFaces, numFaces - first);
    block.resize(count);
    fill(block, first, count);
    writer.write(block.data(), count * sizeof(T));
  }
  return writer.finish();
}

/// The sweeps' greedy colouring of the faces (one byte each, to a file) and the colours used.
/// Greedy in face order: a face's earlier neighbours are in this block or, read back, in the
/// blocks written before. Serial; the corner table alone.
std::pair<ScratchFile, std::uint32_t> colourFaces(ScratchFolder& folder, const CleanScratch& scratch,
                                                  std::uint64_t blockFaces, std::size_t cacheBytes) {
  const std::uint64_t nf = scratch.numFaces;
  ScratchWriter colourWriter(folder, "field: colour");
  std::uint32_t used = 0;
  {
    PagedReader<CornerId> opposite(scratch.opposite, cacheBytes);
    std::vector<std::uint8_t> block;
    for (std::uint64_t first = 0; first < nf; first += blockFaces) {
      const std::uint64_t count = std::min(blockFaces, nf - first);
      block.assign(count, 0xff);
      std::unique_ptr<PagedReader<std::uint8_t>> earlier;
      if (first > 0) earlier = std::make_unique<PagedReader<std::uint8_t>>(colourWriter.written(), cacheBytes);
      for (std::uint64_t i = 0; i < count; ++i) {
        const FaceId f = static_cast<FaceId>(first + i);
        unsigned taken = 0;
        for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
          const CornerId o = opposite[c];
          if (o == kInvalidId || cornerFace(o) >= f) continue;  // not coloured yet
          const FaceId g = cornerFace(o);
          taken |= 1u << (g >= first ? block[g - first] : (*earlier)[g]);
        }
        block[i] = detail::firstFreeColour(taken);
        used = std::max<std::uint32_t>(used, block[i] + 1u);
      }
      if (earlier) folder.countRead("field: colour", earlier->bytesRead());
      colourWriter.write(block.data(), count);
    }
    folder.countRead("field: colour", opposite.bytesRead());
  }
  return {colourWriter.finish(), used};
}

}  // namespace

ScratchField computeScratchField(ScratchFolder& folder, const CleanScratch& scratch, const ProxyFieldOptions& proxy,
                                 const FieldGeometryOptions& geometry, const StreamPassOptions& pass, bool withAngles) {
  ScratchField out;
  StageClock clock(out.stageSeconds);
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const std::uint64_t blockFaces = std::max<std::uint64_t>(1, pass.blockRecords);
  const std::uint64_t nf = scratch.numFaces;
  const bool smoothed = geometry.smoothingIterations > 0;
  ScratchFile surface = smoothed ? smoothScratchPositions(folder, scratch, geometry.smoothingIterations, pass)
                                 : scratch.positions;
  clock.finish("smooth");
  if (smoothed && geometry.roughSpotGrid > 0.0) {
    const ScratchFile rough = smoothScratchRoughSpots(folder, scratch, surface, geometry.roughSpotGrid, pass, out);
    if (rough.path != surface.path) {
      folder.remove(surface);
      surface = rough;
    }
    clock.finish("rough spots");
  }
  if (smoothed) out.framePositions = surface;
  if (nf == 0) return out;

  // Each face's cell: the cell of its centroid on the surface.
  const BoundingBox box = scratchBoundingBox(folder, surface, "field: cells");
  const detail::ProxyCells cells = detail::proxyCells(box, proxy.gridResolution);
  ScratchFile faceCell;
  {
    ReaderPool<PagedFacePoints> pool([&] { return std::make_unique<PagedFacePoints>(scratch, surface, cacheBytes); });
    ScratchRandomReader facesIn(folder, scratch.faces, "field: cells");
    std::vector<CleanFace> faces;
    faceCell = writeFaceBlocks<std::uint32_t>(folder, "field: cells", nf, blockFaces, [&](std::vector<std::uint32_t>& block, std::uint64_t first, std::uint64_t count) {
      readFaceBlock(facesIn, first, count, faces);
      parallelFor(count, 4096, [&](const IndexRange& range) {
        auto points = pool.take();
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
          const std::array<Vec3d, 3> p = points->points(faces[i].triangle);
          block[i] = cells.cellOf((p[0] + p[1] + p[2]) / 3.0);
        }
      });
    });
    pool.forEach([&](PagedFacePoints& points) { folder.countRead("field: cells", points.bytesRead()); });
  }
  clock.finish("cells");

  // Elements as buildElements makes them: the faces of one cell joined through their shared edges
  // (a union-find of the faces whose roots are the smallest, its links in memory within a quarter
  // of the pass's memory, else on disk), numbered by their smallest faces.
  ScratchFile faceElement;
  std::uint32_t numElements = 0;
  {
    const char* stage = "field: elements";
    ScratchLinks links(folder, nf, pass.memoryBytes / 4, stage, false);
    {
      // A block's joins found in parallel (the neighbour's cell in the block or through a page
      // cache), then united in face order.
      ReaderPool<PagedReader<std::uint32_t>> pool([&] { return std::make_unique<PagedReader<std::uint32_t>>(faceCell, cacheBytes); });
      ScratchRandomReader oppositeIn(folder, scratch.opposite, stage), cellIn(folder, faceCell, stage);
      std::vector<std::array<CornerId, 3>> opposite;
      std::vector<std::uint32_t> cell;
      std::vector<std::array<FaceId, 3>> join;
      for (std::uint64_t first = 0; first < nf; first += blockFaces) {
        const std::uint64_t count = std::min(blockFaces, nf - first);
        readFaceBlock(oppositeIn, first, count, opposite);
        readFaceBlock(cellIn, first, count, cell);
        join.resize(count);
        parallelFor(count, 4096, [&](const IndexRange& range) {
          auto cellOf = pool.take();
          for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
            for (unsigned k = 0; k < 3; ++k) {
              const CornerId c = static_cast<CornerId>(3 * (first + i) + k), o = opposite[i][k];
              join[i][k] = kInvalidId;
              if (o == kInvalidId || o < c) continue;
              const FaceId g = cornerFace(o);
              if ((g >= first && g < first + count ? cell[g - first] : (*cellOf)[g]) == cell[i]) join[i][k] = g;
            }
          }
        });
        for (std::uint64_t i = 0; i < count; ++i) {
          for (const FaceId g : join[i]) {
            if (g != kInvalidId) detail::uniteRoots(links, static_cast<FaceId>(first + i), g);
          }
        }
      }
      pool.forEach([&](PagedReader<std::uint32_t>& r) { folder.countRead(stage, r.bytesRead()); });
    }
    folder.remove(faceCell);
    // Parents are smaller faces, so one increasing pass turns roots into element ids and every
    // other face into its parent's id (kept as the face's link from then on).
    faceElement = writeFaceBlocks<std::uint32_t>(folder, stage, nf, blockFaces, [&](std::vector<std::uint32_t>& block, std::uint64_t first, std::uint64_t count) {
      for (std::uint64_t i = 0; i < count; ++i) {
        const FaceId f = static_cast<FaceId>(first + i);
        const std::uint32_t up = links.parentOf(f);
        block[i] = up == f ? numElements++ : links.parentOf(up);
        links.setParent(f, block[i]);
      }
    });
  }
  // Per element its sums over its faces in increasing order: a block's face geometry and edges to
  // other elements in parallel, then added in face order.
  detail::ProxyElements elements;
  elements.cellSize = cells.cellSize;
  elements.normal.resize(numElements);
  elements.centroid.resize(numElements);
  elements.area.resize(numElements);
  {
    const char* stage = "field: elements";
    struct Readers {
      PagedFacePoints points;
      PagedReader<std::uint32_t> elementOf;
    };
    ReaderPool<Readers> pool([&] {
      return std::unique_ptr<Readers>(
          new Readers{PagedFacePoints(scratch, surface, cacheBytes), PagedReader<std::uint32_t>(faceElement, cacheBytes)});
    });
    ScratchRandomReader facesIn(folder, scratch.faces, stage), oppositeIn(folder, scratch.opposite, stage),
        elementIn(folder, faceElement, stage);
    std::vector<detail::ElementSums> sums(numElements);
    std::vector<CleanFace> faces;
    std::vector<std::array<CornerId, 3>> opposite;
    std::vector<std::uint32_t> element;
    std::vector<detail::FaceGeometry> geometry;
    std::vector<std::array<std::pair<std::uint32_t, double>, 3>> across;  // other element (or kInvalidId), edge length
    const std::uint64_t sumFaces = std::min<std::uint64_t>(blockFaces, std::uint64_t(1) << 16);
    for (std::uint64_t first = 0; first < nf; first += sumFaces) {
      const std::uint64_t count = std::min(sumFaces, nf - first);
      readFaceBlock(facesIn, first, count, faces);
      readFaceBlock(oppositeIn, first, count, opposite);
      readFaceBlock(elementIn, first, count, element);
      geometry.resize(count);
      across.resize(count);
      parallelFor(count, 2048, [&](const IndexRange& range) {
        auto r = pool.take();
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
          const std::array<Vec3d, 3> p = r->points.points(faces[i].triangle);
          geometry[i] = detail::faceGeometry(p);
          for (unsigned k = 0; k < 3; ++k) {
            across[i][k] = {kInvalidId, 0.0};
            const CornerId o = opposite[i][k];
            if (o == kInvalidId) continue;
            const FaceId g = cornerFace(o);
            const std::uint32_t other = g >= first && g < first + count ? element[g - first] : r->elementOf[g];
            if (other != element[i]) across[i][k] = {other, (p[(k + 1) % 3] - p[(k + 2) % 3]).norm()};
          }
        }
      });
      for (std::uint64_t i = 0; i < count; ++i) {
        detail::ElementSums& sum = sums[element[i]];
        sum.addFace(geometry[i]);
        for (const auto& [other, length] : across[i]) {
          if (other != kInvalidId) sum.addNeighbour(other, length);
        }
      }
    }
    pool.forEach([&](Readers& r) { folder.countRead(stage, r.points.bytesRead() + r.elementOf.bytesRead()); });
    std::vector<std::vector<std::pair<std::uint32_t, double>>> lists(numElements);
    for (std::uint32_t e = 0; e < numElements; ++e) lists[e] = sums[e].finish(elements, e);
    detail::storeNeighbours(lists, elements);
  }
  out.elements = numElements;
  out.elementEdges = elements.neighbours.size() / 2;
  clock.finish("elements");

  // The colouring reads the corner table alone: on a thread of its own beside the solve and the
  // transfer (a page cache and a block of bytes).
  const bool sweeps = proxy.smoothingSweeps > 0;
  std::future<std::pair<ScratchFile, std::uint32_t>> coloured;
  if (sweeps) coloured = std::async(std::launch::async, [&] { return colourFaces(folder, scratch, blockFaces, cacheBytes); });
  const Eigen::VectorXcd z = detail::solveElementField(elements, proxy.progress, proxy.stats);
  const detail::ElementDirections directions = detail::elementDirections(elements, z);
  clock.finish("solve");

  // Transfer: directions and the sweeps' float normals.
  struct TransferReaders {
    PagedFacePoints points;
  };
  ReaderPool<TransferReaders> transferPool([&] {
    return std::unique_ptr<TransferReaders>(new TransferReaders{PagedFacePoints(scratch, surface, cacheBytes)});
  });
  ScratchWriter normalWriter(folder, "field: transfer");
  std::vector<Vec3f> normalBlock;
  std::vector<CleanFace> transferFaces;
  std::vector<std::uint32_t> transferElements;
  std::optional<ScratchRandomReader> transferFacesIn, transferElementsIn;  // closed before faceElement goes
  transferFacesIn.emplace(folder, scratch.faces, "field: transfer");
  transferElementsIn.emplace(folder, faceElement, "field: transfer");
  const ScratchFile direction = writeFaceBlocks<Vec3f>(folder, "field: transfer", nf, blockFaces, [&](std::vector<Vec3f>& block, std::uint64_t first, std::uint64_t count) {
    normalBlock.resize(count);
    readFaceBlock(*transferFacesIn, first, count, transferFaces);
    readFaceBlock(*transferElementsIn, first, count, transferElements);
    parallelFor(count, 2048, [&](const IndexRange& range) {
      auto readers = transferPool.take();
      detail::TransferBatch batch(elements, directions);  // runs of faces of one element
      const auto store = [&](std::uint64_t i, const Vec3d& d) { block[i] = d.cast<float>(); };
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
        const detail::FaceGeometry g = detail::faceGeometry(readers->points.points(transferFaces[i].triangle));
        batch.add(i, g, transferElements[i], store);
        normalBlock[i] = g.degenerate ? Vec3f(Vec3f::Zero()) : Vec3f(g.n.cast<float>());
      }
      batch.flush(store);
    });
    if (sweeps) normalWriter.write(normalBlock.data(), count * sizeof(Vec3f));
  });
  const ScratchFile sweepNormal = normalWriter.finish();
  transferPool.forEach([&](TransferReaders& r) { folder.countRead("field: transfer", r.points.bytesRead()); });
  transferFacesIn.reset();
  transferElementsIn.reset();
  folder.remove(faceElement);
  clock.finish("transfer");

  if (sweeps) {
    const auto [colour, used] = coloured.get();
    out.colours = used;
    clock.finish("colour");

    // One pass per sweep, in place, in the in-memory sweep's order: blocks of faces, one colour
    // after another within a block (proxy.sweepBlockFaces). A colour's faces read only faces of
    // other colours, so they update in parallel. The directions are held in memory when they fit
    // three quarters of the pass's memory; else a block's are read, changed and written back, its
    // neighbours' read through page caches that forget a block once it is written back.
    const bool held = nf * sizeof(Vec3f) <= pass.memoryBytes / 4 * 3;
    std::vector<Vec3f> all;
    if (held) all = readWholeScratch<Vec3f>(folder, direction, nf, "field: sweeps");
    struct SweepReaders {
      PagedReader<Vec3f> normal;  // of the neighbours outside the block
      std::unique_ptr<PagedReader<Vec3f>> direction;
    };
    // I/O blocks of whole sweep blocks: the order does not depend on the pass's block size.
    const std::uint64_t sweepBlock = std::max<std::uint64_t>(1, proxy.sweepBlockFaces);
    const std::uint64_t ioFaces = (blockFaces + sweepBlock - 1) / sweepBlock * sweepBlock;
    std::vector<Vec3f> block, blockNormal;
    std::vector<std::array<CornerId, 3>> blockOpposite;
    std::vector<std::uint8_t> colours;
    ScratchRandomReader oppositeIn(folder, scratch.opposite, "field: sweeps"), normalIn(folder, sweepNormal, "field: sweeps");
    for (std::int32_t sweep = 0; sweep < proxy.smoothingSweeps; ++sweep) {
      ReaderPool<SweepReaders> pool([&] {
        auto r = std::unique_ptr<SweepReaders>(new SweepReaders{PagedReader<Vec3f>(sweepNormal, cacheBytes), nullptr});
        if (!held) r->direction = std::make_unique<PagedReader<Vec3f>>(direction, cacheBytes);
        return r;
      });
      std::unique_ptr<ScratchUpdater> directions;
      if (!held) directions = std::make_unique<ScratchUpdater>(folder, direction, "field: sweeps");
      ScratchReader colourReader(folder, colour, "field: sweeps");
      for (std::uint64_t first = 0; first < nf; first += ioFaces) {
        const std::uint64_t count = std::min(ioFaces, nf - first);
        colours.resize(count);
        if (!colourReader.read(colours.data(), count)) throw IoError(colour.path + ": scratch colours end early");
        // The block's own corner table and normals, read once for all its colours' passes.
        readFaceBlock(oppositeIn, first, count, blockOpposite);
        readFaceBlock(normalIn, first, count, blockNormal);
        Vec3f* own = all.data() + first;
        if (!held) {
          block.resize(count);
          directions->readAt(first * sizeof(Vec3f), block.data(), count * sizeof(Vec3f));
          own = block.data();
        }
        // A neighbour's direction: this I/O block's from `own`, the others' from memory or the file.
        const auto neighbourDirection = [&](SweepReaders& r, FaceId g) -> Vec3f {
          if (held) return all[g];
          return g >= first && g < first + count ? own[g - first] : (*r.direction)[g];
        };
        for (std::uint64_t sub = 0; sub < count; sub += sweepBlock) {
          const std::uint64_t subCount = std::min(sweepBlock, count - sub);
          for (std::uint32_t k = 0; k < out.colours; ++k) {
            parallelFor(subCount, 4096, [&](const IndexRange& range) {
              auto r = pool.take();
              detail::SweepBatch batch;  // faces of one colour: written after their batch is swept
              const auto store = [&](std::uint64_t i, const Vec3d& swept) { own[i] = swept.cast<float>(); };
              for (std::uint64_t i = sub + range.begin(); i != sub + range.end(); ++i) {
                if (colours[i] != k) continue;
                const Vec3f faceNormal = blockNormal[i];
                if (detail::isZero(faceNormal)) continue;
                Vec3f neighbourNormal[3];
                Vec3d neighbourDirections[3];
                int n = 0;
                for (const CornerId o : blockOpposite[i]) {
                  if (o == kInvalidId) continue;
                  const FaceId g = cornerFace(o);
                  const Vec3f normal = g >= first && g < first + count ? blockNormal[g - first] : r->normal[g];
                  if (detail::isZero(normal)) continue;
                  neighbourNormal[n] = normal;
                  neighbourDirections[n++] = neighbourDirection(*r, cornerFace(o)).cast<double>();
                }
                if (batch.add(i, faceNormal, own[i].cast<double>(), neighbourNormal, neighbourDirections, n)) {
                  batch.flush(store);
                }
              }
              batch.flush(store);
            });
          }
        }
        if (!held) {
          directions->writeAt(first * sizeof(Vec3f), block.data(), count * sizeof(Vec3f));
          pool.forEach([&](SweepReaders& r) { r.direction->forget(first, count); });
        }
      }
      pool.forEach([&](SweepReaders& r) {
        folder.countRead("field: sweeps", r.normal.bytesRead() +
                                              (r.direction ? r.direction->bytesRead() : 0));
      });
    }
    if (held) {
      ScratchUpdater(folder, direction, "field: sweeps").writeAt(0, all.data(), all.size() * sizeof(Vec3f));
      std::vector<Vec3f>().swap(all);
    }
    folder.remove(colour);
    clock.finish("sweeps");
  }

  // The exact tangent planes of the surface (after sweeps), then onto the mesh's own faces.
  struct FinishReaders {
    PagedFacePoints surface, own;
  };
  ReaderPool<FinishReaders> finishPool([&] {
    return std::unique_ptr<FinishReaders>(new FinishReaders{PagedFacePoints(scratch, surface, cacheBytes),
                                                            PagedFacePoints(scratch, scratch.positions, cacheBytes)});
  });
  // The block's faces, directions and sweep normals read at once.
  std::vector<CleanFace> finishFaces;
  std::vector<Vec3f> finishNormals;
  auto finishFacesIn = std::make_unique<ScratchRandomReader>(folder, scratch.faces, "field: finish");
  auto directionIn = std::make_unique<ScratchRandomReader>(folder, direction, "field: finish");
  std::unique_ptr<ScratchRandomReader> normalIn;
  if (sweeps) normalIn = std::make_unique<ScratchRandomReader>(folder, sweepNormal, "field: finish");
  // With angles: the singularities' per-face angles of the final directions in the same pass.
  ScratchWriter anglesOut(folder, "field: finish");
  std::vector<detail::FaceAngleData> angles;
  out.directions = writeFaceBlocks<Vec3f>(folder, "field: finish", nf, blockFaces, [&](std::vector<Vec3f>& block, std::uint64_t first, std::uint64_t count) {
    readFaceBlock(*finishFacesIn, first, count, finishFaces);
    readFaceBlock(*directionIn, first, count, block);
    if (sweeps) readFaceBlock(*normalIn, first, count, finishNormals);
    if (withAngles) angles.resize(count);
    parallelFor(count, 4096, [&](const IndexRange& range) {
      auto r = finishPool.take();
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
        const Triangle t = finishFaces[i].triangle;
        const std::array<Vec3d, 3> p = r->surface.points(t);
        if (sweeps && !detail::isZero(finishNormals[i])) {
          Vec3d tangent;
          if (detail::tangentOf(faceNormal(p[0], p[1], p[2]), block[i].cast<double>(), tangent)) {
            block[i] = tangent.cast<float>();
          }
        }
        Vec3d ownNormal = Vec3d::Zero();
        if (smoothed) {
          ownNormal = detail::faceFrameNormal(r->own.points(t));
          block[i] = rotateBetween(detail::faceFrameNormal(p), ownNormal, block[i].cast<double>()).cast<float>();
        }
        if (withAngles) angles[i] = detail::faceAngleData(p, smoothed ? &ownNormal : nullptr, block[i].cast<double>());
      }
    });
    if (withAngles) anglesOut.write(angles.data(), count * sizeof(detail::FaceAngleData));
  });
  const ScratchFile anglesFile = anglesOut.finish();
  if (withAngles) {
    out.angles = anglesFile;
  } else {
    folder.remove(anglesFile);
  }
  finishPool.forEach([&](FinishReaders& r) { folder.countRead("field: finish", r.surface.bytesRead() + r.own.bytesRead()); });
  finishFacesIn.reset(), directionIn.reset(), normalIn.reset();  // closed before their files go
  folder.remove(direction);
  folder.remove(sweepNormal);  // empty without sweeps
  clock.finish("finish");
  return out;
}

ScratchSingularities computeScratchSingularities(ScratchFolder& folder, const CleanScratch& scratch,
                                                 const ScratchField& field, const StreamPassOptions& pass) {
  ScratchSingularities out;
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const std::uint64_t block = std::max<std::uint64_t>(1, pass.blockRecords);
  const std::uint64_t nf = scratch.numFaces, nv = scratch.numVertices;
  const bool smoothed = !field.framePositions.path.empty();
  const ScratchFile& surface = smoothed ? field.framePositions : scratch.positions;

  // Per face its angles on the surface.
  // The block's faces and directions read at once; the corners' positions through page caches.
  struct AngleReaders {
    PagedFacePoints surface, own;
  };
  ReaderPool<AngleReaders> anglePool([&] {
    return std::unique_ptr<AngleReaders>(new AngleReaders{PagedFacePoints(scratch, surface, cacheBytes),
                                                          PagedFacePoints(scratch, scratch.positions, cacheBytes)});
  });
  std::vector<CleanFace> blockFaces;
  std::vector<Vec3f> blockDirections;
  ScratchFile angles = field.angles;
  if (angles.path.empty()) {
    ScratchRandomReader facesIn(folder, scratch.faces, "singularities: angles"),
        directionsIn(folder, field.directions, "singularities: angles");
    angles = writeFaceBlocks<detail::FaceAngleData>(
        folder, "singularities: angles", nf, block, [&](std::vector<detail::FaceAngleData>& data, std::uint64_t first, std::uint64_t count) {
          readFaceBlock(facesIn, first, count, blockFaces);
          readFaceBlock(directionsIn, first, count, blockDirections);
          parallelFor(count, 4096, [&](const IndexRange& range) {
            auto r = anglePool.take();
            for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
              const Triangle t = blockFaces[i].triangle;
              const Vec3d ownNormal = smoothed ? detail::faceFrameNormal(r->own.points(t)) : Vec3d::Zero();
              data[i] = detail::faceAngleData(r->surface.points(t), smoothed ? &ownNormal : nullptr,
                                              blockDirections[i].cast<double>());
            }
          });
        });
  }
  anglePool.forEach([&](AngleReaders& r) {
    folder.countRead("singularities: angles", r.surface.bytesRead() + r.own.bytesRead());
  });

  // Per corner the matching, read from the smaller corner of its edge as in memory.
  struct CrossingReaders {
    PagedReader<CornerId> opposite;
    PagedReader<detail::FaceAngleData> angles;
    float residual(CornerId c) {
      const CornerId o = opposite[c];
      if (o == kInvalidId) return 0.0f;
      return c < o ? crossing(c, o).eps : -crossing(o, c).eps;
    }
    detail::Crossing crossing(CornerId c, CornerId o) {
      return detail::crossingOf(angles[cornerFace(c)], c % 3, angles[cornerFace(o)], o % 3);
    }
  };
  ReaderPool<CrossingReaders> crossingPool([&] {
    return std::unique_ptr<CrossingReaders>(new CrossingReaders{PagedReader<CornerId>(scratch.opposite, cacheBytes),
                                                                PagedReader<detail::FaceAngleData>(angles, cacheBytes)});
  });
  // The block's corner table and angles read once (pread); a neighbour outside the block through
  // the page cache. The same pass sums each interior vertex's index terms (vertexIndices': per
  // corner the residual across the next corner's edge less the corner's angle), in face order,
  // within a quarter of the pass's memory (on disk beyond it).
  ScratchArray<double> indexSum(folder, nv, pass.memoryBytes / 4, "singularities: matching");
  std::vector<std::array<CornerId, 3>> blockOpposite;
  std::vector<detail::FaceAngleData> blockAngles;
  std::vector<std::array<double, 3>> blockTerms;
  ScratchRandomReader oppositeIn(folder, scratch.opposite, "singularities: matching"),
      anglesIn(folder, angles, "singularities: matching"), facesIn(folder, scratch.faces, "singularities: matching");
  out.matching = writeFaceBlocks<std::array<std::uint8_t, 3>>(
      folder, "singularities: matching", nf, block, [&](std::vector<std::array<std::uint8_t, 3>>& data, std::uint64_t first, std::uint64_t count) {
        readFaceBlock(oppositeIn, first, count, blockOpposite);
        readFaceBlock(anglesIn, first, count, blockAngles);
        readFaceBlock(facesIn, first, count, blockFaces);
        blockTerms.resize(count);
        parallelFor(count, 4096, [&](const IndexRange& range) {
          auto r = crossingPool.take();
          const auto anglesOf = [&](FaceId g) { return g >= first && g < first + count ? blockAngles[g - first] : r->angles[g]; };
          for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
            float residual[3];
            for (unsigned k = 0; k < 3; ++k) {
              const CornerId c = static_cast<CornerId>(3 * (first + i) + k);
              const CornerId o = blockOpposite[i][k];
              std::uint8_t m = 0;
              residual[k] = 0.0f;
              if (o != kInvalidId) {
                const detail::FaceAngleData& own = blockAngles[i];
                const detail::FaceAngleData other = anglesOf(cornerFace(o));
                if (c < o) {
                  const detail::Crossing x = detail::crossingOf(own, k, other, o % 3);
                  m = x.matching;
                  residual[k] = x.eps;
                } else {
                  const detail::Crossing x = detail::crossingOf(other, o % 3, own, k);
                  m = static_cast<std::uint8_t>((4 - x.matching) % 4);
                  residual[k] = -x.eps;
                }
              }
              data[i][k] = m;
            }
            double corner[3];
            detail::cornerAngles(blockAngles[i].edge, corner);
            for (unsigned k = 0; k < 3; ++k) blockTerms[i][k] = residual[(k + 1) % 3] - corner[k];
          }
        });
        for (std::uint64_t i = 0; i < count; ++i) {
          for (unsigned k = 0; k < 3; ++k) {
            const VertexId v = blockFaces[i].triangle[k];
            indexSum.set(v, indexSum.get(v) + blockTerms[i][k]);
          }
        }
      });

  // Per vertex the index: an interior vertex's from its sum, a boundary vertex's by the walk
  // around its fan (its first and last corners count).
  struct IndexReaders {
    PagedCornerTable table;
    CrossingReaders crossings;
  };
  ReaderPool<IndexReaders> indexPool([&] {
    return std::unique_ptr<IndexReaders>(new IndexReaders{
        PagedCornerTable(scratch, cacheBytes),
        CrossingReaders{PagedReader<CornerId>(scratch.opposite, cacheBytes), PagedReader<detail::FaceAngleData>(angles, cacheBytes)}});
  });
  std::vector<std::int32_t> index(block), boundaryIndex(block);
  std::vector<double> sums(block);
  for (std::uint64_t first = 0; first < nv; first += block) {
    const std::uint64_t count = std::min(block, nv - first);
    std::fill(index.begin(), index.begin() + count, 0);
    std::fill(boundaryIndex.begin(), boundaryIndex.begin() + count, 0);
    for (std::uint64_t i = 0; i < count; ++i) sums[i] = indexSum.get(first + i);
    parallelFor(count, 4096, [&](const IndexRange& range) {
      auto r = indexPool.take();
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
        const VertexId v = static_cast<VertexId>(first + i);
        if (r->table.isIsolatedVertex(v)) continue;
        if (!r->table.isBoundaryVertex(v)) {
          index[i] = detail::quarterTurns(2.0 * M_PI + sums[i]);
          continue;
        }
        detail::vertexIndices(
            r->table, v, [&](FaceId f) { return r->crossings.angles[f]; },
            [&](CornerId c) { return r->crossings.residual(c); }, index[i], boundaryIndex[i]);
      }
    });
    for (std::uint64_t i = 0; i < count; ++i) {
      const VertexId v = static_cast<VertexId>(first + i);
      if (index[i] != 0) out.index4.emplace_back(v, index[i]), out.cones.push_back(v);
      if (boundaryIndex[i] != 0) out.boundaryIndex4.emplace_back(v, boundaryIndex[i]);
    }
  }
  crossingPool.forEach([&](CrossingReaders& r) {
    folder.countRead("singularities: matching", r.opposite.bytesRead() + r.angles.bytesRead());
  });
  indexPool.forEach([&](IndexReaders& r) {
    folder.countRead("singularities: index", r.table.bytesRead() + r.crossings.opposite.bytesRead() + r.crossings.angles.bytesRead());
  });
  folder.remove(angles);
  return out;
}

namespace {

/// The out-of-core singularities for detail::mergeCloseConesWith: the nonzero indices in a map,
/// the matchings read from their file unless changed.
class ScratchSingularityEdits {
 public:
  ScratchSingularityEdits(const ScratchSingularities& s, std::size_t cacheBytes) : file_(s.matching, cacheBytes) {
    for (const auto& [v, k] : s.index4) index_[v] = k;
  }
  std::int32_t index(VertexId v) const {
    const auto it = index_.find(v);
    return it == index_.end() ? 0 : it->second;
  }
  void setIndex(VertexId v, std::int32_t k) {
    if (k == 0) {
      index_.erase(v);
    } else {
      index_[v] = k;
    }
  }
  std::uint8_t matching(CornerId c) {
    const auto it = changed_.find(c);
    return it != changed_.end() ? it->second : file_[c];
  }
  void setMatching(CornerId c, std::uint8_t m) { changed_[c] = m; }
  const std::unordered_map<CornerId, std::uint8_t>& changed() const { return changed_; }
  std::uint64_t bytesRead() const { return file_.bytesRead(); }

 private:
  PagedReader<std::uint8_t> file_;
  std::unordered_map<VertexId, std::int32_t> index_;
  std::unordered_map<CornerId, std::uint8_t> changed_;
};

}  // namespace

namespace {

/// A merge on the out-of-core singularities: merge(positionOf, table, edits) changes them through
/// edits; the changed matchings are written back in place, index4 follows the cones.
template <class Merge>
ConeMergeResult editScratchSingularities(ScratchFolder& folder, const CleanScratch& scratch,
                                         ScratchSingularities& singularities, const StreamPassOptions& pass,
                                         Merge&& merge) {
  const char* stage = "singularities: merge";
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedReader<Vec3f> positions(scratch.positions, cacheBytes);
  ScratchSingularityEdits edits(singularities, cacheBytes);
  const ConeMergeResult out = merge([&](VertexId v) -> Vec3d { return positions[v].cast<double>(); }, table, edits);
  folder.countRead(stage, table.bytesRead() + positions.bytesRead() + edits.bytesRead());
  std::vector<std::pair<CornerId, std::uint8_t>> changed(edits.changed().begin(), edits.changed().end());
  std::sort(changed.begin(), changed.end());
  ScratchUpdater matching(folder, singularities.matching, stage);
  for (const auto& [c, m] : changed) matching.writeAt(c, &m, 1);
  singularities.index4.clear();
  for (VertexId v : singularities.cones) singularities.index4.emplace_back(v, edits.index(v));
  return out;
}

}  // namespace

ConeMergeResult mergeScratchCones(ScratchFolder& folder, const CleanScratch& scratch, ScratchSingularities& singularities,
                                  const ConeMergeOptions& options, const StreamPassOptions& pass) {
  return editScratchSingularities(folder, scratch, singularities, pass, [&](auto&& positionOf, auto& table, auto& edits) {
    return detail::mergeCloseConesWith(positionOf, table, edits, singularities.cones, options.maxDistance);
  });
}

ConeMergeResult mergeScratchCoincidentCones(ScratchFolder& folder, const CleanScratch& scratch,
                                            ScratchSingularities& singularities,
                                            const std::vector<std::pair<VertexId, VertexId>>& pairs, double maxDistance,
                                            const StreamPassOptions& pass) {
  for (const auto& [a, b] : pairs) {
    if (a >= scratch.numVertices || b >= scratch.numVertices) throw InputError("mergeCoincidentCones: vertex out of range");
  }
  return editScratchSingularities(folder, scratch, singularities, pass, [&](auto&& positionOf, auto& table, auto& edits) {
    return detail::mergeCoincidentConesWith(positionOf, table, edits, singularities.cones, pairs, maxDistance);
  });
}

}  // namespace seamvox
