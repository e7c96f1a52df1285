#include "stream/evaluate_stream.h"

#include <algorithm>
#include <memory>

#include "core/refine/refine.h"
#include "core/solve/detail_wedges.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

const char* const kStage = "evaluate";

/// The readers a block of vertices takes: the fans and their cut, the corners' positions and
/// faces' fragments.
struct WedgeReaders {
  PagedCornerTable table;
  PagedCutCorners cut;
  PagedReader<Vec3f> position;
  PagedReader<std::uint32_t> faceStart, element;
  std::uint64_t bytesRead() const {
    return table.bytesRead() + cut.bytesRead() + position.bytesRead() + faceStart.bytesRead() + element.bytesRead();
  }
};

/// Wedges of a block of vertices [first, first + count), walked once, in chunks of kChunk
/// vertices each gathered on its own: per vertex its wedges and corners (prefix sums over the
/// block), per chunk its wedges' smallest corners and its corners with their chunk-local wedge.
struct WedgeBlock {
  static constexpr std::uint32_t kChunk = 4096;
  struct Chunk {
    std::vector<CornerId> smallest;                               // per wedge
    std::vector<std::pair<CornerId, std::uint32_t>> cornerWedge;  // chunk-local wedge
    std::uint32_t firstWedge = 0;                                 // in the block
  };
  std::vector<std::uint32_t> wedgeStart;  // count + 1, block-local
  std::vector<Chunk> chunks;
  std::vector<Vec2d> values;  // per wedge of the block
  std::uint32_t numWedges() const { return wedgeStart.back(); }
};

void walkBlock(VertexId first, std::uint32_t count, ReaderPool<WedgeReaders>& pool, WedgeBlock& block) {
  block.wedgeStart.assign(count + 1, 0);
  block.chunks.resize((count + WedgeBlock::kChunk - 1) / WedgeBlock::kChunk);
  parallelFor(block.chunks.size(), 1, [&](const IndexRange& range) {
    auto r = pool.take();
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      WedgeBlock::Chunk& chunk = block.chunks[k];
      chunk.smallest.clear();
      chunk.cornerWedge.clear();
      const std::uint32_t begin = static_cast<std::uint32_t>(k) * WedgeBlock::kChunk;
      for (std::uint32_t i = begin; i < std::min(count, begin + WedgeBlock::kChunk); ++i) {
        const std::size_t wedgesBefore = chunk.smallest.size();
        bool open = false;
        detail::walkWedges(r->table, r->cut, first + i, [&](CornerId c) {
          if (c == kInvalidId) {
            open = false;
            return;
          }
          if (!open) {
            open = true;
            chunk.smallest.push_back(c);
          } else {
            chunk.smallest.back() = std::min(chunk.smallest.back(), c);
          }
          chunk.cornerWedge.emplace_back(c, static_cast<std::uint32_t>(chunk.smallest.size() - 1));
        });
        block.wedgeStart[i + 1] = static_cast<std::uint32_t>(chunk.smallest.size() - wedgesBefore);
      }
    }
  });
  for (std::uint32_t i = 0; i < count; ++i) block.wedgeStart[i + 1] += block.wedgeStart[i];
  for (std::size_t k = 0; k < block.chunks.size(); ++k) {
    block.chunks[k].firstWedge = block.wedgeStart[k * WedgeBlock::kChunk];
  }
}

}  // namespace

ScratchMap evaluateScratchVoxelMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchCut& cut,
                                   const ScratchVoxelBasis& basis, const std::vector<std::complex<double>>& coefficients,
                                   const StreamPassOptions& pass) {
  const VoxelBasis& voxels = *basis.basis;
  if (coefficients.size() != voxels.numDomains()) {
    throw InputError("voxel map: " + std::to_string(coefficients.size()) + " coefficients for " +
                     std::to_string(voxels.numDomains()) + " domains");
  }
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const VoxelGridGeometry& grid = voxels.grid();
  ReaderPool<WedgeReaders> pool([&] {
    return std::unique_ptr<WedgeReaders>(new WedgeReaders{
        PagedCornerTable(scratch, cacheBytes), PagedCutCorners(cut.corners, cacheBytes),
        PagedReader<Vec3f>(scratch.positions, cacheBytes), PagedReader<std::uint32_t>(basis.faceFragmentStart, cacheBytes),
        PagedReader<std::uint32_t>(basis.fragmentElement, cacheBytes)});
  });
  ScratchMap out;
  const ScratchFile cornerWedgeFile = folder.zeroFile(3 * scratch.numFaces * sizeof(std::uint32_t));
  PagedArray<std::uint32_t> cornerWedge(folder, cornerWedgeFile, kStage, cacheBytes);
  ScratchWriter starts(folder, kStage), values(folder, kStage);
  const std::uint64_t blockVertices = std::max<std::uint64_t>(1, pass.blockRecords);
  WedgeBlock block;
  for (std::uint64_t first = 0; first < scratch.numVertices; first += blockVertices) {
    const std::uint32_t count = static_cast<std::uint32_t>(std::min(blockVertices, scratch.numVertices - first));
    walkBlock(static_cast<VertexId>(first), count, pool, block);
    if (out.numWedges + block.numWedges() >= kInvalidId) {
      throw InputError("voxel map: more than 2^32 wedges");
    }
    // Each wedge evaluated at its smallest corner, as VoxelBasis::evaluateCorners does.
    block.values.assign(block.numWedges(), Vec2d::Zero());
    parallelFor(block.chunks.size(), 1, [&](const IndexRange& range) {
      auto r = pool.take();
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        const WedgeBlock::Chunk& chunk = block.chunks[k];
        for (std::size_t j = 0; j < chunk.smallest.size(); ++j) {
          const CornerId c = chunk.smallest[j];
          const FaceId f = cornerFace(c);
          const Vec3d x = grid.toGrid(r->position[r->table.vertex(c)].cast<double>());
          const std::uint32_t begin = r->faceStart[f], end = r->faceStart[std::uint64_t(f) + 1];
          const std::uint32_t e =
              voxels.nearestElement(x, end - begin, [&](std::uint32_t i) { return r->element[begin + i]; });
          if (e == kInvalidId) continue;
          const std::complex<double> q = voxels.evaluateAt(e, x, coefficients);
          block.values[chunk.firstWedge + j] = Vec2d(q.real(), q.imag());
        }
      }
    });
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint32_t start = static_cast<std::uint32_t>(out.numWedges + block.wedgeStart[i]);
      starts.write(&start, sizeof(start));
    }
    for (const WedgeBlock::Chunk& chunk : block.chunks) {
      const std::uint32_t base = static_cast<std::uint32_t>(out.numWedges + chunk.firstWedge);
      for (const auto& [c, w] : chunk.cornerWedge) cornerWedge.set(c, base + w);
    }
    values.write(block.values.data(), block.values.size() * sizeof(Vec2d));
    out.numWedges += block.numWedges();
  }
  const std::uint32_t end = static_cast<std::uint32_t>(out.numWedges);
  starts.write(&end, sizeof(end));
  cornerWedge.flush();
  pool.forEach([&](WedgeReaders& r) { folder.countRead(kStage, r.bytesRead()); });
  folder.countRead(kStage, cornerWedge.bytesRead());
  out.vertexWedgeStart = starts.finish();
  out.wedgeValues = values.finish();
  out.cornerWedge = cornerWedgeFile;
  return out;
}

ScratchMapFaces::ScratchMapFaces(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                                 const std::string& stage, std::size_t cacheBytes, std::uint64_t blockFaces)
    : scratch_(scratch), map_(map), cacheBytes_(cacheBytes), blockFaces_(std::max<std::uint64_t>(1, blockFaces)),
      faces_(folder, scratch.faces, stage), wedges_(folder, map.cornerWedge, stage),
      lookups_([this] {
        return std::unique_ptr<Lookups>(new Lookups{PagedFacePoints(scratch_, scratch_.positions, cacheBytes_),
                                                    PagedReader<Vec2d>(map_.wedgeValues, cacheBytes_)});
      }) {}

bool ScratchMapFaces::readBlock() {
  const std::uint64_t left = scratch_.numFaces - std::min<std::uint64_t>(next_, scratch_.numFaces);
  const std::uint64_t count = std::min(blockFaces_, left);
  block_.clear();
  if (count == 0) return false;
  faceRecords_.resize(count);
  blockWedges_.resize(3 * count);
  if (!faces_.read(faceRecords_.data(), count * sizeof(CleanFace))) {
    throw IoError(scratch_.faces.path + ": scratch file ends early");
  }
  if (!wedges_.read(blockWedges_.data(), blockWedges_.size() * sizeof(std::uint32_t))) {
    throw IoError(map_.cornerWedge.path + ": scratch file ends early");
  }
  block_.resize(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    block_[i].f = next_++;
    block_[i].t = faceRecords_[i].triangle;
  }
  return true;
}

const std::vector<MapFace>* ScratchMapFaces::nextBlock() {
  if (!readBlock()) return nullptr;
  parallelFor(block_.size(), kLookupGrain, [&](const IndexRange& range) {
    auto r = lookups_.take();
    for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
      MapFace& face = block_[i];
      face.p = r->points.points(face.t);
      const std::uint32_t* w = &blockWedges_[3 * i];
      face.q = {r->values[w[0]], r->values[w[1]], r->values[w[2]]};
    }
  });
  return &block_;
}

std::uint64_t ScratchMapFaces::cacheBytesRead() {
  std::uint64_t bytes = 0;
  lookups_.forEach([&](Lookups& r) { bytes += r.points.bytesRead() + r.values.bytesRead(); });
  return bytes;
}

SmoothedEvaluationStats evaluateScratchFoldsAtSmoothedSurface(ScratchFolder& folder, const CleanScratch& scratch,
                                                              const ScratchField& field,
                                                              const ScratchVoxelBasis& basis,
                                                              const std::vector<std::complex<double>>& coefficients,
                                                              double h, ScratchMap& map,
                                                              const StreamPassOptions& pass, ScratchMapSeeds* seeds) {
  const char* const stage = "smoothed evaluation";
  SmoothedEvaluationStats stats;
  if (field.framePositions.bytes == 0) return stats;
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const auto seedOf = [&](const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q) {
    return classifyRefineSeed(parameterAreaRatio(p, q, seeds->edgeLength), seeds->collapseThreshold);
  };
  std::vector<FaceId> faces;
  {
    ScratchMapFaces all(folder, scratch, map, stage, cacheBytes);
    if (seeds) {
      seeds->faces.clear();
      seeds->kinds.clear();
      // Bit 0: folded; the bits above: the seed.
      all.forEach(
          [&](const MapFace& x) {
            return static_cast<std::uint8_t>(foldedForSmoothedEvaluation(x.p, x.q, h) |
                                              static_cast<unsigned>(seedOf(x.p, x.q)) << 1);
          },
          [&](const MapFace& x, std::uint8_t measured) {
            if (measured & 1) faces.push_back(x.f);
            if (measured >> 1) seeds->faces.push_back(x.f), seeds->kinds.push_back(static_cast<RefineSeed>(measured >> 1));
          });
    } else {
      all.forEach([&](const MapFace& x) { return foldedForSmoothedEvaluation(x.p, x.q, h); },
                  [&](const MapFace& x, bool folded) {
                    if (folded) faces.push_back(x.f);
                  });
    }
    folder.countRead(stage, all.cacheBytesRead());
  }
  stats.foldedBefore = faces.size();
  if (seeds) seeds->known = true;
  if (faces.empty()) return stats;
  const VoxelBasis& voxels = *basis.basis;
  const VoxelGridGeometry& grid = voxels.grid();
  PagedCornerTable table(scratch, cacheBytes);
  PagedFacePoints points(scratch, scratch.positions, cacheBytes);
  PagedReader<Vec3f> smooth(field.framePositions, cacheBytes);
  PagedReader<std::uint32_t> wedgeStart(map.vertexWedgeStart, cacheBytes), cornerWedge(map.cornerWedge, cacheBytes);
  PagedReader<std::uint32_t> faceStart(basis.faceFragmentStart, cacheBytes), element(basis.fragmentElement, cacheBytes);
  PagedArray<Vec2d> values(folder, map.wedgeValues, stage, cacheBytes);
  const auto faceValues = [&](FaceId f) {
    return std::array<Vec2d, 3>{values[cornerWedge[3 * f]], values[cornerWedge[3 * f + 1]],
                                values[cornerWedge[3 * f + 2]]};
  };
  const auto folded = [&](FaceId f) { return foldedForSmoothedEvaluation(points.points(f), faceValues(f), h); };
  std::vector<VertexId> tried;  // sorted
  std::vector<VertexId> moved;  // the vertices whose value changed
  for (std::uint32_t round = 0; round < kSmoothedEvaluationRounds && !faces.empty(); ++round) {
    std::vector<VertexId> vertices =
        detail::smoothedCandidates(faces, tried, folded, [&](FaceId f) { return points.triangle(f); });
    // One wedge (none: an isolated vertex; more: a seam through it).
    vertices.erase(std::remove_if(vertices.begin(), vertices.end(),
                                  [&](VertexId v) { return wedgeStart[std::uint64_t(v) + 1] - wedgeStart[v] != 1; }),
                   vertices.end());
    if (vertices.empty()) break;
    // Vertex by vertex in increasing order, each value set unless it stretches a face of its fan
    // at the values so far (as the in-memory pass goes).
    for (VertexId v : vertices) {
      // The element of the wedge's smallest corner, found from the vertex's own position as
      // evaluateScratchVoxelMap found it.
      CornerId smallest = kInvalidId;
      table.forEachCornerAround(v, [&](CornerId c) { smallest = std::min(smallest, c); });
      const FaceId f = cornerFace(smallest);
      const Vec3d x = grid.toGrid(points.points(f)[smallest % 3]);
      const std::uint32_t begin = faceStart[f], end = faceStart[std::uint64_t(f) + 1];
      const std::uint32_t e = voxels.nearestElement(x, end - begin, [&](std::uint32_t i) { return element[begin + i]; });
      bool keep = e == kInvalidId;
      if (!keep) {
        const std::complex<double> q = voxels.evaluateAt(e, grid.toGrid(smooth[v].cast<double>()), coefficients);
        const Vec2d value(q.real(), q.imag());
        table.forEachCornerAround(v, [&](CornerId c) {
          const FaceId g = cornerFace(c);
          keep = keep || movingStretches(points.points(g), faceValues(g), c % 3, value, h);
        });
        if (!keep) values.set(wedgeStart[v], value), moved.push_back(v);
      }
      stats.keptForStretch += keep;
    }
    detail::finishSmoothedRound(table, vertices, tried, faces, stats);
  }
  if (seeds && !moved.empty()) {
    // The faces around the moved vertices measured again at the values left.
    std::vector<FaceId> around;
    for (VertexId v : moved) table.forEachCornerAround(v, [&](CornerId c) { around.push_back(cornerFace(c)); });
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    ScratchMapSeeds merged;
    std::size_t i = 0;
    const auto keepOld = [&] { merged.faces.push_back(seeds->faces[i]), merged.kinds.push_back(seeds->kinds[i]), ++i; };
    for (FaceId f : around) {
      while (i < seeds->faces.size() && seeds->faces[i] < f) keepOld();
      if (i < seeds->faces.size() && seeds->faces[i] == f) ++i;
      const RefineSeed seed = seedOf(points.points(f), faceValues(f));
      if (seed != RefineSeed::None) merged.faces.push_back(f), merged.kinds.push_back(seed);
    }
    while (i < seeds->faces.size()) keepOld();
    seeds->faces = std::move(merged.faces);
    seeds->kinds = std::move(merged.kinds);
  }
  values.flush();
  folder.countRead(stage, table.bytesRead() + points.bytesRead() + smooth.bytesRead() + wedgeStart.bytesRead() +
                              cornerWedge.bytesRead() + faceStart.bytesRead() + element.bytesRead() +
                              values.bytesRead());
  return stats;
}

}  // namespace seamvox
