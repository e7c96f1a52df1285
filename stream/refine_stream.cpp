#include "stream/refine_stream.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>

#include "core/quality/metrics.h"
#include "core/refine/detail_refine.h"
#include "core/refine/detail_region.h"
#include "core/system/errors.h"
#include "core/system/stopwatch.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

/// What extractScratchRegion reads, through page caches: one set per thread. onFieldSurface: the
/// regions go onto the field's smoothed surface (extractRegionOnFieldSurface) when it has one.
struct RegionReaders {
  PagedCornerTable table;
  PagedReader<Vec3f> positions, directions;
  PagedReader<std::uint8_t> rotations;
  PagedCutCorners corners;
  std::optional<PagedReader<Vec3f>> surface;
  const ScratchCut& cut;
  RegionReaders(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& c, std::size_t cacheBytes,
                bool onFieldSurface, std::size_t pageBytes = kScratchPageBytes)
      : table(scratch, cacheBytes, pageBytes), positions(scratch.positions, cacheBytes, pageBytes),
        directions(field.directions, cacheBytes, pageBytes), rotations(c.faceRotation, cacheBytes, pageBytes),
        corners(c.corners, cacheBytes, pageBytes), cut(c) {
    if (onFieldSurface && field.framePositions.bytes > 0) surface.emplace(field.framePositions, cacheBytes, pageBytes);
  }
  RegionMesh extract(const std::vector<FaceId>& regionFaces) {
    RegionMesh out = detail::extractRegionFrom(
        table, [&](VertexId v) { return positions[v]; }, [&](FaceId f) { return directions[f]; },
        [&](FaceId f) { return rotations[f]; }, corners, cut.seams, cut.cones, regionFaces);
    if (surface) detail::placeRegionOnSurfaceOf(out, [&](VertexId v) { return (*surface)[v]; });
    return out;
  }
  std::uint64_t bytesRead() const {
    return table.bytesRead() + positions.bytesRead() + directions.bytesRead() + rotations.bytesRead() +
           corners.bytesRead() + (surface ? surface->bytesRead() : 0);
  }
};

/// The out-of-core map's value at a corner: its wedge, then the wedge's value.
struct MapValues {
  PagedReader<std::uint32_t> cornerWedge;
  PagedReader<Vec2d> values;
  MapValues(const ScratchMap& map, std::size_t cacheBytes)
      : cornerWedge(map.cornerWedge, cacheBytes), values(map.wedgeValues, cacheBytes) {}
  Vec2d value(CornerId c) { return values[cornerWedge[c]]; }
  std::uint64_t bytesRead() const { return cornerWedge.bytesRead() + values.bytesRead(); }
};

void checkRegionFaces(const std::vector<FaceId>& regionFaces, std::uint64_t numFaces) {
  if (!detail::isSortedUnique(regionFaces) || (!regionFaces.empty() && regionFaces.back() >= numFaces)) {
    throw InputError("refine: region faces must be increasing face ids below " + std::to_string(numFaces));
  }
}

}  // namespace

RegionMesh extractScratchRegion(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                                const std::vector<FaceId>& regionFaces, const StreamPassOptions& pass,
                                std::uint64_t* bytesRead, bool onFieldSurface) {
  checkRegionFaces(regionFaces, scratch.numFaces);
  // A region is faces scattered over the mesh: small pages, and room for what it reads.
  RegionReaders readers(scratch, field, cut, windowCacheBytes(pass.memoryBytes), onFieldSurface, kWindowPageBytes);
  RegionMesh out = readers.extract(regionFaces);
  if (bytesRead) *bytesRead += readers.bytesRead();
  return out;
}

std::vector<FaceId> selectScratchRefineRegion(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                                              const RefineOptions& options, const StreamPassOptions& pass,
                                              RefineStats* stats, const ScratchMapSeeds* known) {
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
  const bool seedsKnown = known && known->known && known->edgeLength == options.edgeLength &&
                          known->collapseThreshold == options.collapseThreshold;
  if (options.seedFromMap && seedsKnown) {
    // The marked faces and the known seeds merged, as the pass below merges them.
    std::size_t nextMarked = 0;
    for (std::size_t i = 0; i < known->faces.size(); ++i) {
      const FaceId f = known->faces[i];
      while (nextMarked < marked.size() && marked[nextMarked] < f) seeds.push_back(marked[nextMarked++]);
      if (nextMarked < marked.size() && marked[nextMarked] == f) {
        seeds.push_back(marked[nextMarked++]);
        continue;
      }
      seeds.push_back(f);
      counts.collapsedFaces += known->kinds[i] == RefineSeed::Collapsed;
      counts.flippedFaces += known->kinds[i] == RefineSeed::Flipped;
    }
    seeds.insert(seeds.end(), marked.begin() + static_cast<std::ptrdiff_t>(nextMarked), marked.end());
  } else if (options.seedFromMap) {
    ScratchMapFaces faces(folder, scratch, map, "refine region", cacheBytes);
    std::size_t nextMarked = 0;
    faces.forEach(
        [&](const MapFace& x) {
          return classifyRefineSeed(parameterAreaRatio(x.p, x.q, options.edgeLength), options.collapseThreshold);
        },
        [&](const MapFace& x, RefineSeed seed) {
          if (nextMarked < marked.size() && marked[nextMarked] == x.f) {
            seeds.push_back(marked[nextMarked++]);
            return;
          }
          if (seed == RefineSeed::None) return;
          seeds.push_back(x.f);
          counts.collapsedFaces += seed == RefineSeed::Collapsed;
          counts.flippedFaces += seed == RefineSeed::Flipped;
        });
    folder.countRead("refine region", faces.cacheBytesRead());
  } else {
    seeds = marked;
  }
  // Rings: every face sharing a vertex with the frontier, options.rings times (sorted lists, about
  // 8 B per region face: the region grows with the faces per cell at a fixed grid).
  const std::vector<FaceId> region = detail::growFacesIn(table, std::move(seeds), options.rings);
  folder.countRead("refine region", table.bytesRead());
  counts.regionFaces = region.size();
  copyRegionCounts(counts, stats);
  return region;
}

namespace {

void applyScratchCorners(ScratchFolder& folder, const std::vector<RefinedCorner>& corners, ScratchMap& map,
                         const StreamPassOptions& pass);

/// The out-of-core mesh and map as detail::refineRounds reads them: page caches on the calling
/// thread, and a pool of reader sets for the region solves that run in parallel. Each batch's
/// free corners go into the scratch map as soon as it is solved (the map is then the latest
/// values), so what a round holds is one batch of corners (a share of the memory), not the
/// region's; per vertex a freed/seen flag (ScratchArray within a share) for the counts.
class ScratchRefineSource {
 public:
  /// One thread's readers: a region's mesh and the map's values (rebuilt after every batch).
  struct GroupReaders : RegionReaders {
    MapValues map;
    GroupReaders(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut, const ScratchMap& m,
                 std::size_t cacheBytes)
        : RegionReaders(scratch, field, cut, cacheBytes, true), map(m, cacheBytes) {}
  };

  ScratchRefineSource(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                      const ScratchCut& cut, ScratchMap& map, const StreamPassOptions& pass,
                      std::vector<FaceId>* changedFaces)
      : folder_(folder), scratch_(scratch), field_(field), cut_(cut), map_(map), pass_(pass),
        cacheBytes_(pageCacheBytes(pass.memoryBytes)), table_(scratch, cacheBytes_),
        points_(scratch, scratch.positions, cacheBytes_),
        flags_(folder, scratch.numVertices, pass.memoryBytes / 16, "refine"), tally_(flags_), changed_(changedFaces) {
    openMap();
  }

  ReaderPool<GroupReaders>::Lease groupReaders() { return pool_->take(); }
  PagedCornerTable& table() { return table_; }
  std::uint32_t numVertices() const { return static_cast<std::uint32_t>(scratch_.numVertices); }
  Triangle triangle(FaceId f) { return points_.triangle(f); }
  std::array<Vec3d, 3> points(FaceId f) { return points_.points(f); }
  Vec2d value(CornerId c) { return values_->value(c); }

  Vec2d latest(GroupReaders& readers, CornerId c) { return readers.map.value(c); }
  /// An eighth of the memory in solved corners at once.
  std::size_t batchCorners() const {
    return static_cast<std::size_t>(std::max<std::uint64_t>(1, pass_.memoryBytes / 8 / sizeof(detail::SolvedCorner)));
  }
  void record(std::vector<detail::SolvedCorner> fresh) {
    fresh.erase(std::remove_if(fresh.begin(), fresh.end(), [](const detail::SolvedCorner& s) { return !s.free; }),
                fresh.end());
    tally_.addFreed(table_, fresh);
    if (changed_) {
      for (const detail::SolvedCorner& c : fresh) changed_->push_back(cornerFace(c.corner));
    }
    closeMap();  // the readers' cached pages of the map are stale once it changes
    applyScratchCorners(folder_, fresh, map_, pass_);
    openMap();
  }
  detail::FaceCounts countTouched(const std::vector<FaceId>& touched, const std::vector<VertexId>& cones, double h) {
    return detail::countFaces(*this, touched, cones, h, [this](CornerId c) { return value(c); });
  }
  /// The corners are in the map already: the result keeps the vertex counts only.
  void collect(const std::vector<FaceId>& touched, RefineResult& out) {
    tally_.collect(table_, touched, scratch_.numVertices, out);
  }

  /// One pass over the faces and their corners' wedges in order, skipping `touched`.
  detail::FaceCounts countOutside(const std::vector<FaceId>& touched, const std::vector<VertexId>& cones, double h) {
    detail::FaceCounts counts;
    ScratchMapFaces faces(folder_, scratch_, map_, "refine", cacheBytes_);
    auto next = touched.begin();
    faces.forEach([&](const MapFace& x) { return parameterAreaRatio(x.p, x.q, h); },
                  [&](const MapFace& x, double ratio) {
                    if (next != touched.end() && *next == x.f) {
                      ++next;
                      return;
                    }
                    counts.add(ratio, [&] { return detail::collapsesBetweenListedCones(x.t, x.q, cones); });
                  });
    folder_.countRead("refine", faces.cacheBytesRead());
    return counts;
  }

  std::uint64_t bytesRead() { return table_.bytesRead() + points_.bytesRead() + closedBytes_ + openBytes(); }

 private:
  std::uint64_t openBytes() {
    std::uint64_t bytes = values_ ? values_->bytesRead() : 0;
    if (pool_) {
      pool_->forEach([&](GroupReaders& r) { bytes += r.RegionReaders::bytesRead() + r.map.bytesRead(); });
    }
    return bytes;
  }
  void openMap() {
    values_.emplace(map_, cacheBytes_);
    pool_.emplace([this] { return std::make_unique<GroupReaders>(scratch_, field_, cut_, map_, cacheBytes_); });
  }
  void closeMap() {
    closedBytes_ += openBytes();
    pool_.reset();
    values_.reset();
  }

  ScratchFolder& folder_;
  const CleanScratch& scratch_;
  const ScratchField& field_;
  const ScratchCut& cut_;
  ScratchMap& map_;
  StreamPassOptions pass_;
  std::size_t cacheBytes_;
  PagedCornerTable table_;
  PagedFacePoints points_;
  ScratchArray<std::uint8_t> flags_;
  detail::VertexTally<ScratchArray<std::uint8_t>> tally_;
  std::uint64_t closedBytes_ = 0;
  std::optional<MapValues> values_;
  std::optional<ReaderPool<GroupReaders>> pool_;
  std::vector<FaceId>* changed_ = nullptr;  ///< the faces of the corners given new values, when wanted
};

}  // namespace

RefineResult refineScratchNearCones(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                    const ScratchCut& cut, ScratchMap& map,
                                    const std::vector<std::complex<double>>& seamT, const RefineOptions& options,
                                    const StreamPassOptions& pass, const ScratchMapSeeds* mapSeeds,
                                    std::vector<FaceId>* changedFaces) {
  const auto start = std::chrono::steady_clock::now();
  if (seamT.size() != cut.seams.size()) {
    throw InputError("refine: " + std::to_string(seamT.size()) + " translations for " +
                     std::to_string(cut.seams.size()) + " seams");
  }
  RefineResult out;
  std::vector<FaceId> faces = selectScratchRefineRegion(folder, scratch, map, options, pass, &out.stats, mapSeeds);
  out.stats.secondsRegion = secondsSince(start);
  const std::vector<VertexId> cones = listedCones(cut.cones, scratch.numVertices);
  ScratchRefineSource source(folder, scratch, field, cut, map, pass, changedFaces);
  detail::refineRounds(source, cones, seamT, options, std::move(faces), out);
  if (changedFaces) {
    std::sort(changedFaces->begin(), changedFaces->end());
    changedFaces->erase(std::unique(changedFaces->begin(), changedFaces->end()), changedFaces->end());
  }
  folder.countRead("refine", source.bytesRead());
  reportProgress(options.progress, "refine", 1.0);
  out.stats.secondsTotal = secondsSince(start);
  return out;
}

namespace {

/// WedgeMap::assign of refined corners (sorted, unique) on the out-of-core map, after their
/// wedges took the values in place: a wedge only part of whose corners changed is split, one new
/// wedge per new value, appended. The wedges' corner counts come from one pass over the corners'
/// wedges. Returns the appended values.
std::vector<Vec2d> splitScratchWedges(ScratchFolder& folder, const std::vector<RefinedCorner>& corners,
                                      const ScratchMap& map, PagedArray<std::uint32_t>& cornerWedge,
                                      PagedArray<Vec2d>& values) {
  // Per touched wedge: its corners in the refinement, and in the whole map.
  std::unordered_map<std::uint32_t, std::pair<std::uint64_t, std::uint64_t>> count;
  for (const RefinedCorner& r : corners) ++count[cornerWedge[r.corner]].first;
  {
    ScratchReader wedges(folder, map.cornerWedge, "refine");
    std::uint32_t w = 0;
    while (wedges.read(&w, sizeof w)) {
      const auto it = count.find(w);
      if (it != count.end()) ++it->second.second;
    }
  }
  std::unordered_map<std::uint32_t, std::vector<std::pair<Vec2d, std::uint32_t>>> made;
  std::vector<Vec2d> appended;
  for (const RefinedCorner& r : corners) {
    const std::uint32_t w = cornerWedge[r.corner];
    auto& options = made[w];
    const auto found = std::find_if(options.begin(), options.end(), [&](const auto& o) { return o.first == r.uv; });
    if (found != options.end()) {
      cornerWedge.set(r.corner, found->second);
      continue;
    }
    const auto& n = count[w];
    std::uint32_t target = w;
    if (options.empty() && n.first == n.second) {
      values.set(w, r.uv);
    } else if (!(values[w] == r.uv && n.first != n.second)) {  // else: unchanged on a partly given wedge
      target = static_cast<std::uint32_t>(map.numWedges + appended.size());
      appended.push_back(r.uv);
    }
    options.emplace_back(r.uv, target);
    cornerWedge.set(r.corner, target);
  }
  return appended;
}

/// The corners' values into the map (ids checked by the caller): wedges in place, split where
/// their corners disagree, the split wedges' values appended to a copy of the values file.
void applyScratchCorners(ScratchFolder& folder, const std::vector<RefinedCorner>& corners, ScratchMap& map,
                         const StreamPassOptions& pass) {
  if (corners.empty()) return;
  std::vector<Vec2d> appended;
  {
    const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
    PagedArray<std::uint32_t> cornerWedge(folder, map.cornerWedge, "refine", cacheBytes);
    PagedArray<Vec2d> values(folder, map.wedgeValues, "refine", cacheBytes);
    // A free vertex's wedges change whole and keep their ids (applyRefinement): values in place.
    for (const RefinedCorner& r : corners) values.set(cornerWedge[r.corner], r.uv);
    const bool whole = std::all_of(corners.begin(), corners.end(),
                                   [&](const RefinedCorner& r) { return values[cornerWedge[r.corner]] == r.uv; });
    if (!whole) appended = splitScratchWedges(folder, corners, map, cornerWedge, values);
    values.flush();
    cornerWedge.flush();
    folder.countRead("refine", cornerWedge.bytesRead() + values.bytesRead());
  }
  if (appended.empty()) return;
  // The split wedges' values after the others: the values file copied with them appended.
  ScratchWriter writer(folder, "refine");
  {
    ScratchReader old(folder, map.wedgeValues, "refine");
    std::vector<char> buffer(std::size_t(1) << 20);
    while (const std::size_t n = old.readUpTo(buffer.data(), buffer.size())) writer.write(buffer.data(), n);
  }
  writer.write(appended.data(), appended.size() * sizeof(Vec2d));
  const ScratchFile grown = writer.finish();
  folder.remove(map.wedgeValues);
  map.wedgeValues = grown;
  map.numWedges += appended.size();
}

}  // namespace

void applyScratchRefinement(ScratchFolder& folder, const RefineResult& refinement, ScratchMap& map,
                            std::vector<std::complex<double>>* translations, const StreamPassOptions& pass) {
  if (translations) {
    for (std::size_t k = 0; k < refinement.seams.size(); ++k) {
      if (refinement.seams[k] >= translations->size()) {
        throw InputError("refine: seam " + std::to_string(refinement.seams[k]) + " out of range (" +
                         std::to_string(translations->size()) + " seams)");
      }
    }
  }
  const std::uint64_t numCorners = map.cornerWedge.bytes / sizeof(std::uint32_t);
  for (const RefinedCorner& r : refinement.corners) {
    if (r.corner >= numCorners) {
      throw InputError("refine: corner " + std::to_string(r.corner) + " out of range (" + std::to_string(numCorners) +
                       " corners)");
    }
  }
  if (translations) {
    for (std::size_t k = 0; k < refinement.seams.size(); ++k) (*translations)[refinement.seams[k]] = refinement.seamT[k];
  }
  applyScratchCorners(folder, refinement.corners, map, pass);
}

}  // namespace seamvox
