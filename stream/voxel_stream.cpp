#include "stream/voxel_stream.h"

#include <algorithm>
#include <memory>

#include "core/basis/detail_voxel_elements.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"
#include "stream/external_sort.h"
#include "stream/keyed_sort.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

const char* const kStage = "voxel elements";

/// A fragment on its way to its voxel: sorted by (voxel, fragment), i.e. by voxel and then by
/// face, as the in-memory build visits a voxel's fragments.
struct VoxelOrderRecord {
  std::uint64_t key = 0;  ///< voxel << 32 | fragment
  FaceId face = 0;
  std::uint32_t edgeMask = 0;
  bool operator<(const VoxelOrderRecord& o) const { return key < o.key; }
};

/// A fragment's element on its way back to face order.
struct FragmentElementRecord {
  std::uint32_t fragment = 0, element = 0;
  bool operator<(const FragmentElementRecord& o) const { return fragment < o.fragment; }
};

/// The keyed sorts' keys: a record's voxel, a record's fragment.
struct VoxelOfRecord {
  std::uint64_t operator()(const VoxelOrderRecord& r) const { return r.key >> 32; }
};
struct FragmentOfRecord {
  std::uint64_t operator()(const FragmentElementRecord& r) const { return r.fragment; }
};

/// The readers a block of voxels takes: the cut surface's neighbours and the faces' integrands.
struct VoxelReaders {
  PagedReader<CornerId> opposite;
  PagedReader<std::uint8_t> cut;
  PagedFacePoints points;
  PagedReader<Vec3f> direction;
  PagedReader<std::uint8_t> rotation;
  std::uint64_t bytesRead() const {
    return opposite.bytesRead() + cut.bytesRead() + points.bytesRead() + direction.bytesRead() + rotation.bytesRead();
  }
};

std::array<Vec3d, 3> toGrid(const VoxelGridGeometry& geometry, const std::array<Vec3d, 3>& p) {
  return {geometry.toGrid(p[0]), geometry.toGrid(p[1]), geometry.toGrid(p[2])};
}

/// Clips every face (a pipeline: chunks in order, clipped in parallel, their voxels registered in
/// order); writes the fragments with the voxels' ids of first appearance.
ScratchFile clipFaces(ScratchFolder& folder, const CleanScratch& scratch, const VoxelBasisOptions& options,
                      std::size_t cacheBytes, const VoxelGridGeometry& geometry, VoxelGrid& grid) {
  ReaderPool<PagedFacePoints> pool(
      [&] { return std::make_unique<PagedFacePoints>(scratch, scratch.positions, cacheBytes); });
  ScratchWriter writer(folder, kStage);
  detail::clipFacesInOrder(
      scratch.numFaces, options.chunkFaces,
      [&](detail::ClippedChunk& chunk) {
        auto readers = pool.take();
        detail::clipChunk(geometry, [&](FaceId f) { return toGrid(geometry, readers->points(f)); }, chunk,
                          options.leftOut);
      },
      grid, [&](const VoxelFragment& fragment) { writer.write(&fragment, sizeof(fragment)); },
      [](const detail::ClippedChunk&) {});
  pool.forEach([&](PagedFacePoints& r) { folder.countRead(kStage, r.bytesRead()); });
  return writer.finish();
}

/// One voxel's fragments in a block: [begin, end) of the block's arrays.
struct VoxelGroup {
  std::uint32_t voxel = 0;
  std::size_t begin = 0, end = 0;
};

/// A block of fragments sorted by voxel, whole voxels only.
struct FragmentBlock {
  std::vector<VoxelGroup> groups;
  std::vector<FaceId> face;
  std::vector<std::uint8_t> mask;
  std::vector<std::uint32_t> fragment, element;
  void clear() {
    groups.clear(), face.clear(), mask.clear(), fragment.clear(), element.clear();
  }
};

/// Elements and integrals of a block's voxels, numbered after the ones before.
void buildBlockElements(FragmentBlock& block, ReaderPool<VoxelReaders>& pool, const VoxelBasisOptions& options,
                        ScratchVoxelElements& out) {
  const std::size_t numGroups = block.groups.size();
  block.element.resize(block.face.size());
  std::vector<std::uint32_t> count(numGroups);
  parallelFor(numGroups, 64, [&](const IndexRange& range) {
    auto r = pool.take();
    std::vector<FaceId> faces;
    std::vector<std::uint8_t> masks;
    std::vector<std::uint32_t> label;
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const VoxelGroup& group = block.groups[g];
      faces.assign(block.face.begin() + group.begin, block.face.begin() + group.end);
      masks.assign(block.mask.begin() + group.begin, block.mask.begin() + group.end);
      count[g] = detail::labelVoxelFragments(
          faces, masks, [&](CornerId c) { return r->opposite[c]; },
          [&](CornerId c) { return CutCorners::isCutByte(r->cut[c]); }, label);
      std::copy(label.begin(), label.end(), block.element.begin() + group.begin);
    }
  });
  std::vector<std::uint32_t> base(numGroups);
  for (std::size_t g = 0; g < numGroups; ++g) {
    base[g] = static_cast<std::uint32_t>(out.elementVoxel.size());
    if ((std::uint64_t(base[g]) + count[g]) * 8 >= kInvalidId) {
      throw InputError("voxel basis: too many elements (more than " + std::to_string(base[g]) + "); use a coarser grid");
    }
    out.elementVoxel.insert(out.elementVoxel.end(), count[g], block.groups[g].voxel);
    out.voxelElementStart[block.groups[g].voxel + 1] = base[g] + count[g];
    for (std::size_t i = block.groups[g].begin; i < block.groups[g].end; ++i) block.element[i] += base[g];
  }
  out.records.resize(out.elementVoxel.size());
  out.normalStiffness.resize(out.elementVoxel.size());
  parallelFor(numGroups, 16, [&](const IndexRange& range) {
    auto r = pool.take();
    std::vector<FragmentSums> sums;
    std::vector<FaceId> faces;
    std::vector<std::uint32_t> element;
    const auto integrand = [&](FaceId f) {
      detail::FaceIntegrand face;
      const std::array<Vec3d, 3> p = r->points.points(f);
      face.grid = toGrid(out.geometry, p);
      face.normal = faceNormal(p[0], p[1], p[2]);
      face.direction = detail::combedDirection(r->direction[f].cast<double>(), face.normal, r->rotation[f]);
      return face;
    };
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const VoxelGroup& group = block.groups[g];
      if (count[g] == 0) continue;
      faces.assign(block.face.begin() + group.begin, block.face.begin() + group.end);
      element.assign(block.element.begin() + group.begin, block.element.begin() + group.end);
      const std::uint32_t first = base[g], last = base[g] + count[g] - 1;
      detail::integrateVoxel(out.grid.coords()[group.voxel], out.geometry.voxelSize, options.edgeLength, faces, element,
                             first, last, integrand, sums, out.records.data() + first,
                             out.normalStiffness.data() + first);
    }
  });
}

}  // namespace

struct ScratchVoxelClip::ByVoxel {
  KeyedSorter<VoxelOrderRecord, std::less<VoxelOrderRecord>, VoxelOfRecord> sorter;
};
ScratchVoxelClip::ScratchVoxelClip() = default;
ScratchVoxelClip::ScratchVoxelClip(ScratchVoxelClip&&) noexcept = default;
ScratchVoxelClip& ScratchVoxelClip::operator=(ScratchVoxelClip&&) noexcept = default;
ScratchVoxelClip::~ScratchVoxelClip() = default;

namespace {

/// The voxel passes' sorts: a quarter of the pass's memory each.
ExternalSortOptions voxelSortOptions(const StreamPassOptions& pass) {
  ExternalSortOptions sort;
  sort.memoryBytes = std::max<std::uint64_t>(pass.memoryBytes / 4, std::uint64_t(1) << 20);
  sort.stage = kStage;
  return sort;
}

}  // namespace

ScratchVoxelClip clipScratchFaces(ScratchFolder& folder, const CleanScratch& scratch, const VoxelBasisOptions& options,
                                  const StreamPassOptions& pass) {
  ScratchVoxelClip out;
  StageClock clock(out.stageSeconds);
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const ExternalSortOptions sort = voxelSortOptions(pass);
  out.geometry = makeVoxelGrid(scratchBoundingBox(folder, scratch.positions, kStage), options.gridResolution);
  clock.finish("bounds");
  const ScratchFile raw = clipFaces(folder, scratch, options, cacheBytes, out.geometry, out.grid);
  clock.finish("clip");

  // Ids in the tree's block order, as buildVoxelBasis numbers them; the fragments in face order
  // with those ids, and by voxel for the elements.
  const std::vector<std::uint32_t> remap = out.grid.orderByBlocks();
  out.byVoxel = std::unique_ptr<ScratchVoxelClip::ByVoxel>(
      new ScratchVoxelClip::ByVoxel{{folder, out.grid.size(), raw.bytes / sizeof(VoxelFragment), sort}});
  auto& byVoxel = out.byVoxel->sorter;
  {
    ScratchReader reader(folder, raw, kStage);
    ScratchWriter writer(folder, kStage), starts(folder, kStage);
    std::uint64_t nextFace = 0;  // faces before it have their start written
    const auto startFacesUpTo = [&](std::uint64_t end) {
      const std::uint32_t start = static_cast<std::uint32_t>(out.numFragments);
      for (; nextFace < end; ++nextFace) starts.write(&start, sizeof(start));
    };
    VoxelFragment fragment;
    while (reader.read(&fragment, sizeof(fragment))) {
      startFacesUpTo(std::uint64_t(fragment.face) + 1);
      if (out.numFragments + 1 >= kInvalidId) {
        throw InputError("voxel basis: more than 2^32 fragments; use a coarser grid");
      }
      fragment.voxel = remap[fragment.voxel];
      writer.write(&fragment, sizeof(fragment));
      byVoxel.add({std::uint64_t(fragment.voxel) << 32 | out.numFragments, fragment.face, fragment.edgeMask});
      ++out.numFragments;
    }
    startFacesUpTo(scratch.numFaces + 1);
    out.fragments = writer.finish();
    out.faceFragmentStart = starts.finish();
  }
  folder.remove(raw);
  byVoxel.close();
  clock.finish("sort");
  return out;
}

ScratchVoxelElements buildScratchVoxelElements(ScratchFolder& folder, const CleanScratch& scratch,
                                               const ScratchField& field, const ScratchCut& cut,
                                               const VoxelBasisOptions& options, const StreamPassOptions& pass,
                                               ScratchVoxelClip* ahead) {
  const std::uint64_t nf = scratch.numFaces;
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength)) {
    throw InputError("voxel basis: edge length must be positive and finite");
  }
  if (field.directions.bytes != nf * sizeof(Vec3f) || cut.corners.bytes != 3 * nf || cut.faceRotation.bytes != nf) {
    throw InputError("voxel basis: field or cut sizes do not match the mesh (" + std::to_string(nf) + " faces)");
  }
  ScratchVoxelClip clip = ahead ? std::move(*ahead) : clipScratchFaces(folder, scratch, options, pass);
  ScratchVoxelElements out;
  out.stageSeconds = std::move(clip.stageSeconds);
  StageClock clock(out.stageSeconds);
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const ExternalSortOptions sort = voxelSortOptions(pass);
  out.geometry = clip.geometry;
  out.grid = std::move(clip.grid);
  out.fragments = clip.fragments;
  out.faceFragmentStart = clip.faceFragmentStart;
  out.numFragments = clip.numFragments;
  auto& byVoxel = clip.byVoxel->sorter;
  byVoxel.finish();

  out.voxelElementStart.assign(std::size_t(out.grid.size()) + 1, 0);
  ReaderPool<VoxelReaders> pool([&] {
    return std::unique_ptr<VoxelReaders>(new VoxelReaders{
        PagedReader<CornerId>(scratch.opposite, cacheBytes), PagedReader<std::uint8_t>(cut.corners, cacheBytes),
        PagedFacePoints(scratch, scratch.positions, cacheBytes), PagedReader<Vec3f>(field.directions, cacheBytes),
        PagedReader<std::uint8_t>(cut.faceRotation, cacheBytes)});
  });
  KeyedSorter<FragmentElementRecord, std::less<FragmentElementRecord>, FragmentOfRecord> byFragment(
      folder, out.numFragments, out.numFragments, sort);
  const std::uint64_t blockRecords = std::max<std::uint64_t>(1, pass.blockRecords);
  FragmentBlock block;
  const auto flush = [&] {
    buildBlockElements(block, pool, options, out);
    for (std::size_t i = 0; i < block.face.size(); ++i) byFragment.add({block.fragment[i], block.element[i]});
    block.clear();
  };
  VoxelOrderRecord record;
  while (byVoxel.next(record)) {
    const std::uint32_t voxel = static_cast<std::uint32_t>(record.key >> 32);
    if (block.groups.empty() || block.groups.back().voxel != voxel) {
      if (block.face.size() >= blockRecords) flush();
      block.groups.push_back({voxel, block.face.size(), block.face.size()});
    }
    block.face.push_back(record.face);
    block.mask.push_back(static_cast<std::uint8_t>(record.edgeMask));
    block.fragment.push_back(static_cast<std::uint32_t>(record.key));
    ++block.groups.back().end;
  }
  flush();
  pool.forEach([&](VoxelReaders& r) { folder.countRead(kStage, r.bytesRead()); });
  byFragment.finish();
  clock.finish("elements");

  {
    ScratchWriter writer(folder, kStage);
    FragmentElementRecord r;
    while (byFragment.next(r)) writer.write(&r.element, sizeof(r.element));
    out.fragmentElement = writer.finish();
  }
  clock.finish("order");
  return out;
}

ScratchVoxelBasis buildScratchVoxelBasis(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                         const ScratchCut& cut, const VoxelBasisOptions& options,
                                         const StreamPassOptions& pass, ScratchVoxelClip* clip) {
  ScratchVoxelElements elements = buildScratchVoxelElements(folder, scratch, field, cut, options, pass, clip);
  ScratchVoxelBasis out;
  out.stageSeconds = std::move(elements.stageSeconds);
  StageClock clock(out.stageSeconds);
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  const std::uint64_t nf = scratch.numFaces;
  const std::vector<VoxelCoord>& voxelCoords = elements.grid.coords();
  detail::VoxelBasisParts parts;
  parts.links.functions = detail::UnionFind(8 * elements.elementVoxel.size());
  {
    // Chunks of faces linked in parallel, each through a pooled set of page caches, and their
    // links applied in face order (the same domains and seam links as one pass in order).
    struct LinkReaders {
      PagedReader<CornerId> opposite;
      PagedReader<std::uint8_t> cutBytes;
      PagedFacePoints points;
      PagedReader<std::uint32_t> faceStart, element;
      PagedReader<VoxelFragment> fragments;
      std::uint64_t bytesRead() const {
        return opposite.bytesRead() + cutBytes.bytesRead() + points.bytesRead() + faceStart.bytesRead() +
               element.bytesRead() + fragments.bytesRead();
      }
    };
    ReaderPool<LinkReaders> pool([&] {
      return std::unique_ptr<LinkReaders>(new LinkReaders{
          PagedReader<CornerId>(scratch.opposite, cacheBytes), PagedReader<std::uint8_t>(cut.corners, cacheBytes),
          PagedFacePoints(scratch, scratch.positions, cacheBytes),
          PagedReader<std::uint32_t>(elements.faceFragmentStart, cacheBytes),
          PagedReader<std::uint32_t>(elements.fragmentElement, cacheBytes),
          PagedReader<VoxelFragment>(elements.fragments, cacheBytes)});
    });
    const SeamIndex seamIndex = [&] {
      PagedReader<CornerId> opposite(scratch.opposite, cacheBytes);
      SeamIndex index(cut.seams, 3 * nf, [&](CornerId c) { return opposite[c]; });
      folder.countRead(kStage, opposite.bytesRead());
      return index;
    }();
    const auto work = [&](detail::LinkChunk& chunk) {
      auto r = pool.take();
      const auto fragmentsOf = [&](FaceId f, std::vector<detail::FaceFragment>& into) {
        into.clear();
        const std::uint32_t end = r->faceStart[std::uint64_t(f) + 1];
        for (std::uint32_t i = r->faceStart[f]; i < end; ++i) {
          const VoxelFragment fr = r->fragments[i];
          into.push_back({voxelCoords[fr.voxel], r->element[i], static_cast<std::uint8_t>(fr.edgeMask)});
        }
      };
      std::vector<detail::FaceFragment> mine;
      detail::LinkScratch scratch;
      for (FaceId f = chunk.begin; f < chunk.end; ++f) {
        fragmentsOf(f, mine);
        if (mine.empty()) continue;
        detail::linkFaceFragments(
            f, mine, toGrid(elements.geometry, r->points.points(f)), [&](CornerId c) { return r->opposite[c]; },
            [&](CornerId c) { return CutCorners::isCutByte(r->cutBytes[c]); },
            [&](CornerId c) { return seamIndex.find(c); }, fragmentsOf, scratch, chunk.links);
      }
    };
    detail::facesInOrder<detail::LinkChunk>(nf, 1u << 14, work,
                                            [&](detail::LinkChunk& chunk) { chunk.links.applyTo(parts.links); });
    pool.forEach([&](LinkReaders& r) { folder.countRead(kStage, r.bytesRead()); });
  }
  clock.finish("link");
  parts.grid = elements.geometry;
  parts.voxelCoords = voxelCoords;
  parts.voxelElementStart = std::move(elements.voxelElementStart);
  parts.elementVoxel = std::move(elements.elementVoxel);
  parts.records = std::move(elements.records);
  parts.normalStiffness = std::move(elements.normalStiffness);
  out.basis = std::make_unique<VoxelBasis>(nullptr, std::move(parts), cut.seams, options);
  out.basis->setVoxelBlocks(elements.grid.blockStarts());
  clock.finish("domains");
  out.grid = std::move(elements.grid);
  out.fragments = elements.fragments;
  out.fragmentElement = elements.fragmentElement;
  out.faceFragmentStart = elements.faceFragmentStart;
  out.numFragments = elements.numFragments;
  return out;
}

}  // namespace seamvox
