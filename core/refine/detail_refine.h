#pragma once
/// The rounds of refineNearCones written once for the mesh in memory and for the out-of-core map
/// (stream/refine_stream): templates over a source of the whole mesh and its map. A source gives,
/// on the calling thread, table() (vertex, forEachCornerAround), numVertices(), triangle(f),
/// points(f) (corner positions in double) and countOutside(touched, cones, h) (FaceCounts of the
/// faces not in `touched`, input map); groupReaders(), an object for one thread with
/// extract(faces) (a RegionMesh as extractRegion cuts it) and value(c) (the map at corner c).
/// The solved corners live in the source: latest(readers, c) (corner c as solved so far, else the
/// input map; read by the threads of a batch), batchCorners() (the most solved corners held at
/// once), record(fresh) (a batch's corners, sorted by corner: they replace older values, a corner
/// stays free once freed), countTouched(touched, cones, h) (FaceCounts of the solved faces with
/// their latest values) and collect(touched, out) (the result's corners and vertex counts).
/// Whole-mesh state stays out: the faces ever solved are a sorted list.
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <limits>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <iterator>
#include <string>
#include <type_traits>
#include <vector>

#include "core/mesh/detail_union_find.h"
#include "core/quality/metrics.h"
#include "core/refine/refine.h"
#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"

namespace seamvox::detail {

using SolvedCorner = RefinedCorner;  // a whole-mesh corner solved by some round

/// Collapsed and flipped faces by MapQuality's criteria.
struct FaceCounts {
  std::uint64_t collapsed = 0, collapsedAtCones = 0, flipped = 0;
  /// betweenCones() (collapsesBetweenCones) is asked only of a collapsed face.
  template <class BetweenCones>
  void add(double ratio, BetweenCones&& betweenCones) {
    if (std::abs(ratio) < kCollapsedAreaFraction) {
      ++collapsed;
      collapsedAtCones += betweenCones();
    } else if (ratio < 0.0) {
      ++flipped;
    }
  }
  FaceCounts& operator+=(const FaceCounts& b) {
    collapsed += b.collapsed, collapsedAtCones += b.collapsedAtCones, flipped += b.flipped;
    return *this;
  }
};

/// collapsesBetweenCones with the cones as an increasing list of vertex ids.
inline bool collapsesBetweenListedCones(const Triangle& t, const std::array<Vec2d, 3>& q,
                                        const std::vector<VertexId>& cones) {
  const auto isCone = [&](VertexId v) { return std::binary_search(cones.begin(), cones.end(), v); };
  for (int k = 0; k < 3; ++k) {
    const int l = (k + 1) % 3;
    if (isCone(t[k]) && isCone(t[l]) && (q[k] - q[l]).norm() <= kCoincidentConeDistance) return true;
  }
  return false;
}

inline bool isSortedUnique(const std::vector<FaceId>& faces) {
  return std::adjacent_find(faces.begin(), faces.end(), [](FaceId a, FaceId b) { return a >= b; }) == faces.end();
}

/// Membership of ids below no known bound, by a bit each once a set is large enough to pay for
/// the words (up to the largest id / 8 bytes); below that, a sorted list's binary search.
class GrowingIdSet {
 public:
  explicit GrowingIdSet(const std::vector<std::uint32_t>& sorted) : sorted_(sorted) {}
  bool contains(std::uint32_t id) const {
    if (words_.empty()) return std::binary_search(sorted_.begin(), sorted_.end(), id);
    return id / 64 < words_.size() && (words_[id / 64] >> (id % 64) & 1);
  }
  /// By bits: the list need not stay sorted (nor be read again).
  bool dense() const { return !words_.empty(); }
  /// To call after `added` joined the list; switches to bits past kDense ids.
  void update(const std::vector<std::uint32_t>& added) {
    if (words_.empty() && sorted_.size() < kDense) return;
    for (std::uint32_t id : words_.empty() ? sorted_ : added) {
      if (id / 64 >= words_.size()) words_.resize(id / 64 + 1, 0);
      words_[id / 64] |= std::uint64_t(1) << (id % 64);
    }
  }

 private:
  static constexpr std::size_t kDense = std::size_t(1) << 14;
  const std::vector<std::uint32_t>& sorted_;
  std::vector<std::uint64_t> words_;
};

/// `added` (sorted, disjoint from `list`) joins `list`: merged while the list is searched, appended
/// once it is held by bits (sorted at the end).
inline void joinIds(std::vector<std::uint32_t>& list, GrowingIdSet& set, const std::vector<std::uint32_t>& added) {
  if (set.dense()) {
    list.insert(list.end(), added.begin(), added.end());
  } else {
    std::vector<std::uint32_t> merged;
    merged.reserve(list.size() + added.size());
    std::merge(list.begin(), list.end(), added.begin(), added.end(), std::back_inserter(merged));
    list = std::move(merged);
  }
  set.update(added);
}

/// growFaces over any corner table. It stops early, with more than maxFaces faces, once a ring
/// takes it past maxFaces (a caller that would refuse so large a patch need not grow it whole).
/// Over the in-memory table a wide ring's fans are walked on both cores.
template <class Table>
std::vector<FaceId> growFacesIn(Table& topology, std::vector<FaceId> frontier, std::uint32_t rings,
                                std::size_t maxFaces = std::numeric_limits<std::size_t>::max()) {
  constexpr bool kShared = std::is_same_v<std::remove_const_t<Table>, Topology>;  // read by threads
  std::vector<FaceId> patch = frontier;
  sortUniqueIds(patch);
  std::vector<VertexId> seen;  // vertices expanded
  GrowingIdSet inPatch(patch), wasSeen(seen);
  inPatch.update({});
  // The ids each of `from`'s items gives, sorted and unique (blocks of items on both cores when
  // shared and many).
  const auto collect = [&](const std::vector<std::uint32_t>& from, auto&& each) {
    std::vector<std::uint32_t> out;
    constexpr std::size_t kBlock = 4096;
    if (kShared && from.size() > 4 * kBlock) {
      std::vector<std::vector<std::uint32_t>> parts((from.size() + kBlock - 1) / kBlock);
      parallelForEach(parts.size(), 1, [&](std::uint64_t b) {
        for (std::size_t i = b * kBlock; i < std::min(from.size(), (b + 1) * kBlock); ++i) each(from[i], parts[b]);
      });
      for (const std::vector<std::uint32_t>& part : parts) out.insert(out.end(), part.begin(), part.end());
    } else {
      for (std::uint32_t x : from) each(x, out);
    }
    sortUniqueIds(out);
    return out;
  };
  for (std::uint32_t ring = 0; ring < rings && !frontier.empty() && patch.size() <= maxFaces; ++ring) {
    // The frontier's vertices not expanded yet, each once (a vertex has about six frontier faces).
    const std::vector<VertexId> unseen = collect(frontier, [&](FaceId f, std::vector<std::uint32_t>& out) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = topology.vertex(3 * f + k);
        if (!wasSeen.contains(v)) out.push_back(v);
      }
    });
    std::vector<FaceId> added = collect(unseen, [&](VertexId v, std::vector<std::uint32_t>& out) {
      topology.forEachCornerAround(v, [&](CornerId c) {
        const FaceId g = cornerFace(c);
        if (!inPatch.contains(g)) out.push_back(g);
      });
    });
    joinIds(seen, wasSeen, unseen);
    joinIds(patch, inPatch, added);
    frontier = std::move(added);
  }
  if (inPatch.dense()) sortUniqueIds(patch);
  return patch;
}

/// splitRegion over any corner table (faces sorted and unique: the caller checks).
template <class Table>
std::vector<std::vector<FaceId>> splitRegionIn(Table& topology, const std::vector<FaceId>& faces,
                                               std::size_t groupFaces) {
  const std::uint32_t n = static_cast<std::uint32_t>(faces.size());
  std::vector<std::pair<VertexId, std::uint32_t>> byVertex;
  byVertex.reserve(3u * static_cast<std::size_t>(n));
  for (std::uint32_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) byVertex.push_back({topology.vertex(3 * faces[i] + k), i});
  }
  std::sort(byVertex.begin(), byVertex.end());
  UnionFind sets(n);
  for (std::size_t j = 1; j < byVertex.size(); ++j) {
    if (byVertex[j].first == byVertex[j - 1].first) sets.unite(byVertex[j - 1].second, byVertex[j].second);
  }
  // A component's root is its first face (unite keeps the smaller id): groups in face order.
  std::vector<std::uint32_t> size(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) ++size[sets.find(i)];
  std::vector<std::uint32_t> groupOf(n, 0);
  std::size_t filled = 0;
  std::uint32_t groups = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (sets.find(i) != i) continue;
    if (groups == 0 || filled >= groupFaces) ++groups, filled = 0;
    groupOf[i] = groups - 1;
    filled += size[i];
  }
  std::vector<std::vector<FaceId>> out(groups);
  for (std::uint32_t i = 0; i < n; ++i) out[groupOf[sets.find(i)]].push_back(faces[i]);
  return out;
}

/// The input of a region solve: the corners as solved so far, else the map (source.latest).
template <class Source, class Readers>
WedgeMap regionInput(const RegionMesh& region, Source& source, Readers& readers) {
  const std::uint32_t rf = region.topology.numFaces();
  std::vector<Vec2d> values(3u * rf);
  for (std::uint32_t i = 0; i < rf; ++i) {
    for (int k = 0; k < 3; ++k) values[3 * i + k] = source.latest(readers, 3 * region.faceOrigin[i] + k);
  }
  return WedgeMap::fromCorners(region.mesh.triangles, values);
}

/// The value of corner c in `current` (sorted by corner) if solved, else value(c).
template <class Value>
Vec2d solvedOr(const std::vector<SolvedCorner>& current, CornerId c, Value&& value) {
  const auto it = std::lower_bound(current.begin(), current.end(), c,
                                   [](const SolvedCorner& s, CornerId x) { return s.corner < x; });
  return it != current.end() && it->corner == c ? it->uv : value(c);
}

/// Consecutive runs of groups (sizes in faces) holding at most maxCorners corners each (a larger
/// group alone): the first group of every run, then groups.size().
inline std::vector<std::size_t> groupBatches(const std::vector<std::vector<FaceId>>& groups, std::size_t maxCorners) {
  std::vector<std::size_t> start{0};
  std::size_t corners = 0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const std::size_t n = 3 * groups[g].size();
    if (g > start.back() && corners + n > maxCorners) start.push_back(g), corners = 0;
    corners += n;
  }
  start.push_back(groups.size());
  return start;
}

/// A region's solved corners under whole-mesh ids, in increasing corner order, from `out` on.
/// ownUnknown (solved in B-splines; per region vertex): a free vertex without its own unknown is
/// marked spline.
void writeSolvedCorners(const RegionMesh& region, const RegionSolution& solved, SolvedCorner* out,
                        const std::vector<std::uint8_t>* ownUnknown);
/// Records solved corners (sorted by corner) in `current` (sorted; these values replace older
/// ones, a corner stays free once freed), merging within its spare capacity where it suffices.
void mergeSolved(std::vector<SolvedCorner> fresh, std::vector<SolvedCorner>& current);
/// Measures a solved region into figures; returns its bad faces touching a locked vertex (whole-
/// mesh ids: they seed the next round). collapsedAtBorder: one of them is below the threshold
/// but not flipped. everyBadFace (solved in B-splines): every bad face seeds, locked vertex or not;
/// with collapsedOnly, only those collapsed by MapQuality's measure (flips are left to the repair).
std::vector<FaceId> measureSolvedRegion(const RegionMesh& region, const RegionSolution& solved, double h,
                                        double collapseThreshold, RefineRound& figures, bool& collapsedAtBorder,
                                        bool everyBadFace = false, bool collapsedOnly = false);
/// stats takes the system figures of the largest solve.
void keepLargestSolve(const RefineStats& largest, RefineStats& stats);
/// The seams whose translation changed (currentT against seamT) into out.
void collectChangedSeams(const std::vector<std::complex<double>>& currentT,
                         const std::vector<std::complex<double>>& seamT, RefineResult& out);

/// One round: the region's groups of components extracted, solved and measured on their own, in
/// parallel, a batch of groups at a time (source.batchCorners()); each batch's corners recorded in
/// the source and the round's translations in currentT. Groups are disjoint in faces, corners,
/// vertices and (seams among free vertices) translations, so a batch never reads another batch's
/// corners: batch by batch gives the map that one batch of all the groups gives. Returns the bad faces touching a
/// locked vertex (the next round's seeds), sorted. `largest` keeps the system figures of the
/// largest group solved so far; figures sums the groups.
/// figures.spline: the round solves in the B-splines of options.splineSpacing (with own unknowns
/// near cones), and returns every bad face (measureSolvedRegion); a group whose solve failed
/// returns all its faces.
template <class Source>
std::vector<FaceId> solveRound(Source& source, const std::vector<FaceId>& faces, const RefineOptions& options,
                               std::vector<std::complex<double>>& currentT, RefineRound& figures,
                               bool& collapsedAtBorder, RefineStats& largest, RefineStats& stats) {
  const bool spline = figures.spline;
  using Complex = std::complex<double>;
  struct GroupResult {
    std::vector<std::pair<std::uint32_t, Complex>> seams;
    std::vector<FaceId> border;
    RefineRound figures;
    RefineStats system;
    bool collapsedAtBorder = false;
    double secondsExtract = 0.0, secondsSolve = 0.0;
    std::string failure;  // the solve's SolverError: the group keeps its input map
    std::uint64_t unknowns = 0;  // over the group's solves (several when solved again by parts)
    std::uint32_t solves = 0;
  };
  const std::vector<std::vector<FaceId>> groups =
      splitRegionIn(source.table(), faces, std::max<std::size_t>(1, options.groupFaces));
  std::vector<GroupResult> results(groups.size());
  const double h = options.edgeLength;
  // One group's region extracted, solved from the map as refined so far and measured; its
  // corners written to out (3 per face, in face order). A solve that cannot be factored leaves
  // the group's input values, recorded as locked (nothing of it changes), and its message.
  const auto solveGroup = [&](const std::vector<FaceId>& groupFaces, SolvedCorner* out, GroupResult& r) {
    auto lap = std::chrono::steady_clock::now();
    auto readers = source.groupReaders();
    const RegionMesh region = readers->extract(groupFaces);
    WedgeMap regionUV = regionInput(region, source, *readers);
    std::vector<Complex> regionT(region.seamOrigin.size());
    for (std::size_t j = 0; j < regionT.size(); ++j) regionT[j] = currentT[region.seamOrigin[j]];
    const std::uint32_t numFree = static_cast<std::uint32_t>(
        std::count(region.vertexFree.begin(), region.vertexFree.end(), std::uint8_t(1)));
    r.figures.freeVertices = numFree;
    r.secondsExtract = secondsSince(lap);
    lap = std::chrono::steady_clock::now();
    RegionSolution solved;
    std::vector<std::uint8_t> ownUnknown;
    if (numFree > 0) {
      try {
        if (options.groupFails && options.groupFails(groupFaces.front())) {
          throw SolverError("refine: group of face " + std::to_string(groupFaces.front()) + " failed (test hook)");
        }
        solved = spline ? solveRegionInSplines(region, regionUV, regionT, h, options.splineSpacing,
                                               options.coneWeightRadius, ownUnknown, &r.system,
                                               options.splineMaxFraction, options.closeHolesWithin)
                        : solveRegion(region, regionUV, regionT, h, &r.system, {}, options.coneWeightRadius, false,
                                      options.closeHolesWithin);
      } catch (const SolverError& e) {
        r.failure = e.what();
        r.system = RefineStats();
      }
    }
    if (numFree == 0 || !r.failure.empty()) {
      solved.cornerUV = std::move(regionUV);
      solved.seamT = std::move(regionT);
    }
    r.secondsSolve = secondsSince(lap);
    r.unknowns = r.system.unknowns;
    r.solves = r.system.unknowns > 0;
    const bool inSplines = spline && solved.inSplines;
    writeSolvedCorners(region, solved, out, inSplines ? &ownUnknown : nullptr);
    if (!r.failure.empty()) {
      for (std::size_t k = 0; k < 3 * groupFaces.size(); ++k) out[k].free = false;
      r.figures.freeVertices = 0;
    }
    for (std::size_t j = 0; j < region.seamOrigin.size(); ++j) r.seams.push_back({region.seamOrigin[j], solved.seamT[j]});
    const bool collapsedOnly = inSplines && options.flipsToRepair;  // the flips are the repair's
    r.border = measureSolvedRegion(region, solved, h, options.collapseThreshold, r.figures, r.collapsedAtBorder,
                                   inSplines, collapsedOnly);
    if (spline && !r.failure.empty()) r.border = groupFaces;  // the hat rounds take the group whole
  };
  const std::vector<std::size_t> batches = groupBatches(groups, std::max<std::size_t>(1, source.batchCorners()));
  for (std::size_t b = 0; b + 1 < batches.size(); ++b) {
    // The batch's corners go straight into one array (group after group, 3 per face), with room
    // for a quarter more: in memory, the later rounds' patches merge their new corners into that
    // spare capacity, which is not resident until written.
    const std::size_t first = batches[b], count = batches[b + 1] - first;
    std::vector<std::size_t> offset(count + 1, 0);
    for (std::size_t i = 0; i < count; ++i) offset[i + 1] = offset[i] + 3 * groups[first + i].size();
    std::vector<SolvedCorner> fresh;
    fresh.reserve(offset.back() + offset.back() / 4);
    fresh.resize(offset.back());
    parallelForEach(count, 1, [&](std::uint64_t i) {
      solveGroup(groups[first + i], fresh.data() + offset[i], results[first + i]);
    });
    // A group whose solve failed is solved again component by component: only the components
    // that fail alone keep their input map (a zero-area sliver split off by the cleaning made a
    // whole group of cone neighbourhoods fail).
    for (std::size_t i = 0; i < count; ++i) {
      GroupResult& r = results[first + i];
      const std::vector<FaceId>& group = groups[first + i];
      if (r.failure.empty()) continue;
      const std::vector<std::vector<FaceId>> parts = splitRegionIn(source.table(), group, 1);
      if (parts.size() < 2) continue;
      std::vector<GroupResult> sub(parts.size());
      std::vector<std::vector<SolvedCorner>> corners(parts.size());
      parallelForEach(parts.size(), 1, [&](std::uint64_t k) {
        corners[k].resize(3 * parts[k].size());
        solveGroup(parts[k], corners[k].data(), sub[k]);
      });
      r = GroupResult();
      for (std::size_t k = 0; k < parts.size(); ++k) {
        for (std::size_t j = 0; j < parts[k].size(); ++j) {
          const std::size_t rank = std::lower_bound(group.begin(), group.end(), parts[k][j]) - group.begin();
          std::copy_n(corners[k].data() + 3 * j, 3, fresh.data() + offset[i] + 3 * rank);
        }
        GroupResult& p = sub[k];
        r.seams.insert(r.seams.end(), p.seams.begin(), p.seams.end());
        r.border.insert(r.border.end(), p.border.begin(), p.border.end());
        r.figures.freeVertices += p.figures.freeVertices;
        r.figures.collapsed += p.figures.collapsed;
        r.figures.collapsedAtCones += p.figures.collapsedAtCones;
        r.figures.flipped += p.figures.flipped;
        if (p.system.unknowns >= r.system.unknowns) r.system = p.system;
        r.unknowns += p.unknowns;
        r.solves += p.solves;
        r.collapsedAtBorder = r.collapsedAtBorder || p.collapsedAtBorder;
        r.secondsExtract += p.secondsExtract;
        r.secondsSolve += p.secondsSolve;
        if (r.failure.empty()) r.failure = p.failure;
      }
    }
    tbb::parallel_sort(fresh.begin(), fresh.end(), [](const SolvedCorner& x, const SolvedCorner& y) { return x.corner < y.corner; });
    source.record(std::move(fresh));
    ++stats.batches;
  }
  // Merging the groups' translations and figures in any order gives the same result.
  std::vector<FaceId> border;
  for (GroupResult& r : results) {
    for (const auto& [seam, t] : r.seams) currentT[seam] = t;
    border.insert(border.end(), r.border.begin(), r.border.end());
    figures.freeVertices += r.figures.freeVertices;
    figures.unknowns += r.unknowns;
    figures.collapsed += r.figures.collapsed;
    figures.collapsedAtCones += r.figures.collapsedAtCones;
    figures.flipped += r.figures.flipped;
    collapsedAtBorder = collapsedAtBorder || r.collapsedAtBorder;
    stats.secondsExtract += r.secondsExtract;
    stats.secondsSolve += r.secondsSolve;
    if (r.system.unknowns > 0 && r.system.unknowns >= largest.unknowns) largest = r.system;
    stats.solves += r.solves;
    if (!r.failure.empty() && stats.failedSolves++ == 0) stats.failedSolveReason = r.failure;
  }
  std::sort(border.begin(), border.end());
  figures.borderFaces = border.size();
  return border;
}

/// Whole-map counts into stats: every face ever solved (`touched`, sorted) with the refined
/// values, every other face as in the input.
template <class Source>
void measureRefinedMap(Source& source, const std::vector<FaceId>& touched, const std::vector<VertexId>& cones,
                       const RefineOptions& options, RefineStats& stats) {
  const double h = options.edgeLength;
  stats.regionFaces = touched.size();
  const FaceCounts inside = source.countTouched(touched, cones, h);
  // Faces never solved keep the input map. With the map's own faces seeded (voxloc), the first
  // region held every face below the collapse threshold: none outside is collapsed or flipped.
  FaceCounts outside;
  if (!options.regionOnly && !regionHoldsEveryFlip(options)) {
    outside = source.countOutside(touched, cones, h);
  }
  stats.collapsedAfter = outside.collapsed + inside.collapsed;
  stats.collapsedAtConesAfter = outside.collapsedAtCones + inside.collapsedAtCones;
  stats.flippedAfter = outside.flipped + inside.flipped;
}

/// FaceCounts of the faces in `touched` (sorted), their corners' values from valueOf(c), asked in
/// increasing corner order.
template <class Source, class ValueOf>
FaceCounts countFaces(Source& source, const std::vector<FaceId>& touched, const std::vector<VertexId>& cones,
                      double h, ValueOf&& valueOf) {
  FaceCounts counts;
  for (FaceId f : touched) {
    const std::array<Vec2d, 3> q{valueOf(3 * f), valueOf(3 * f + 1), valueOf(3 * f + 2)};
    const Triangle t = source.triangle(f);
    counts.add(parameterAreaRatio(source.points(f), q, h), [&] { return collapsesBetweenListedCones(t, q, cones); });
  }
  return counts;
}

/// countFaces with the values of `current` (sorted by corner, holding every corner of those faces:
/// a solve records all its region's corners), else the source's: one walk pairs them.
template <class Source>
FaceCounts countSolvedFaces(Source& source, const std::vector<FaceId>& touched,
                            const std::vector<SolvedCorner>& current, const std::vector<VertexId>& cones, double h) {
  auto it = current.begin();
  return countFaces(source, touched, cones, h, [&](CornerId c) {
    while (it != current.end() && it->corner < c) ++it;
    return it != current.end() && it->corner == c ? it->uv : source.value(c);
  });
}

/// The vertex counts of a source that writes its solved corners into the map (no corner list to
/// count them from): one flag byte per vertex in a store with get(v) and set(v, flag).
template <class Flags>
class VertexTally {
 public:
  explicit VertexTally(Flags& flags) : flags_(flags) {}
  /// The vertices of a batch's free corners.
  template <class Table>
  void addFreed(Table& table, const std::vector<SolvedCorner>& fresh) {
    for (const SolvedCorner& s : fresh) {
      if (!s.free) continue;
      const VertexId v = table.vertex(s.corner);
      const std::uint8_t flag = flags_.get(v);
      const std::uint8_t bit = s.spline ? kSpline : kFreed;
      if (!(flag & bit)) flags_.set(v, flag | bit), ++(s.spline ? spline_ : freed_);
    }
  }
  /// The freed and locked counts (locked: the other vertices of the solved faces) into out.stats.
  template <class Table>
  void collect(Table& table, const std::vector<FaceId>& touched, std::uint64_t numVertices, RefineResult& out) {
    std::uint64_t around = 0;
    spline_ = 0;
    for (FaceId f : touched) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = table.vertex(3 * f + k);
        const std::uint8_t flag = flags_.get(v);
        if (flag & kSeen) continue;
        flags_.set(v, flag | kSeen), ++around;
        spline_ += (flag & kSpline) && !(flag & kFreed);
      }
    }
    out.stats.freeVertices = static_cast<std::uint32_t>(freed_);
    out.stats.lockedVertices = static_cast<std::uint32_t>(around - freed_ - spline_);
    out.stats.refinedVertexFraction = numVertices ? double(freed_) / double(numVertices) : 0.0;
    out.stats.splineVertices = static_cast<std::uint32_t>(spline_);
    out.stats.splineVertexFraction = numVertices ? double(spline_) / double(numVertices) : 0.0;
  }

 private:
  static constexpr std::uint8_t kFreed = 1, kSeen = 2, kSpline = 4;
  Flags& flags_;
  std::uint64_t freed_ = 0, spline_ = 0;
};

/// The result: the corners of every vertex freed in some solve with their latest values, and the
/// freed and locked vertex counts.
template <class Table>
void collectRefinement(Table& topology, std::uint32_t numVertices, std::vector<SolvedCorner> current,
                       const std::vector<FaceId>& touched, RefineResult& out) {
  RefineStats& stats = out.stats;
  // The free corners, kept in place: the result takes the array itself.
  current.erase(std::remove_if(current.begin(), current.end(), [](const SolvedCorner& s) { return !s.free; }),
                current.end());
  out.corners = std::move(current);
  std::vector<VertexId> freed, spline;
  freed.reserve(out.corners.size());
  for (const SolvedCorner& s : out.corners) (s.spline ? spline : freed).push_back(topology.vertex(s.corner));
  for (std::vector<VertexId>* list : {&freed, &spline}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  stats.freeVertices = static_cast<std::uint32_t>(freed.size());
  stats.splineVertices = static_cast<std::uint32_t>(spline.size());
  stats.splineVertexFraction = numVertices ? double(spline.size()) / numVertices : 0.0;
  std::vector<VertexId> around;  // vertices of every refined face
  around.reserve(3 * touched.size());
  for (FaceId f : touched) {
    for (int k = 0; k < 3; ++k) around.push_back(topology.vertex(3 * f + k));
  }
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  stats.lockedVertices = static_cast<std::uint32_t>(around.size() - freed.size() - spline.size());
  stats.refinedVertexFraction = numVertices ? double(freed.size()) / numVertices : 0.0;
}

/// The distinct vertices of the islands' faces, and the free vertices off them as a fraction.
/// (After the free vertices and their fraction are counted.)
template <class Table>
void countIslandVertices(Table& table, const std::vector<FaceId>& islandFaces, RefineStats& stats) {
  std::vector<VertexId> vertices;
  vertices.reserve(3 * islandFaces.size());
  for (FaceId f : islandFaces) {
    for (int k = 0; k < 3; ++k) vertices.push_back(table.vertex(3 * f + k));
  }
  std::sort(vertices.begin(), vertices.end());
  stats.islandVertices = static_cast<std::uint32_t>(std::unique(vertices.begin(), vertices.end()) - vertices.begin());
  const std::uint32_t off = stats.freeVertices > stats.islandVertices ? stats.freeVertices - stats.islandVertices : 0;
  stats.refinedFractionOffIslands =
      stats.freeVertices ? stats.refinedVertexFraction * double(off) / double(stats.freeVertices) : 0.0;
}

/// refineNearCones after the first region is selected (`faces`, with its counts in out.stats):
/// the rounds, the measures and the result. cones: the cut's, increasing.
template <class Source>
void refineRounds(Source& source, const std::vector<VertexId>& cones, const std::vector<std::complex<double>>& seamT,
                  const RefineOptions& options, std::vector<FaceId> faces, RefineResult& out) {
  RefineStats& stats = out.stats;
  // Rounds: solve the region from the input map; then, while faces stay bad at the locked border,
  // solve a patch around them (rings doubling) from the map as refined so far. The source holds
  // every corner solved so far (the latest solve wins), currentT the seams, `touched` every face
  // solved so far (sorted).
  const std::uint32_t maxRounds = std::max(1u, options.maxRounds);
  const bool splineFirst = options.splineSpacing > 0.0 && maxRounds >= 2 && options.seedFromMap;
  std::uint64_t seeds = stats.markedFaces + stats.collapsedFaces + stats.flippedFaces;
  std::vector<std::complex<double>> currentT = seamT;
  std::vector<FaceId> touched = faces;
  RefineStats largest;  // system figures of the largest solve
  for (std::uint32_t round = 0; !faces.empty(); ++round) {
    const auto roundStart = std::chrono::steady_clock::now();
    RefineRound figures;
    figures.spline = splineFirst && round == 0;
    figures.seedFaces = seeds;
    figures.regionFaces = faces.size();
    bool collapsedAtBorder = false;  // a border face below the threshold but not flipped
    std::vector<FaceId> border =
        solveRound(source, faces, options, currentT, figures, collapsedAtBorder, largest, stats);
    figures.seconds = secondsSince(roundStart);
    stats.totalUnknowns = std::max<std::uint64_t>(stats.totalUnknowns, figures.unknowns);
    stats.rounds.push_back(figures);
    reportProgress(options.progress, "refine", double(round + 1) / maxRounds);
    if (figures.spline) {
      // The islands are mapped whole in the hat basis (the voxel map left them at 0).
      std::vector<FaceId> withIslands;
      std::set_union(border.begin(), border.end(), options.islandFaces.begin(), options.islandFaces.end(),
                     std::back_inserter(withIslands));
      border = std::move(withIslands);
    }
    if (border.empty() || round + 1 >= maxRounds) break;
    // Another solve pays while it removes collapses, or while the border shrinks fast. Flipped
    // faces that stay at the border round after round are the map's own flips near cones (hat has
    // them too); chasing them cost 3 extra solves and 27% of the time of a 22M-face run for 32 of
    // 8174 flips. After the spline round, the hat round always runs on what it left.
    if (!figures.spline && !collapsedAtBorder && 2 * border.size() > seeds) break;
    // After the spline round and the hat round on what it left, only collapsed faces (by the
    // map's measure, not the seeding threshold) justify another solve: the flips left are the hat
    // map's own near cones (the foldover repair's work), and chasing them grew the hat rounds to
    // 1.4% of a 22M-face scan's vertices against 0.8%.
    if (splineFirst && !figures.spline && figures.collapsed == figures.collapsedAtCones) break;
    seeds = border.size();
    // Rings double each round: damage that outlasts a round usually spreads further out. The
    // patch is solved on its own, the rest of the map (refined or not) locked around it.
    faces = growFacesIn(source.table(), std::move(border), std::max(1u, options.rings) << std::min(round, 4u));
    std::vector<FaceId> merged;
    merged.reserve(touched.size() + faces.size());
    std::set_union(touched.begin(), touched.end(), faces.begin(), faces.end(), std::back_inserter(merged));
    touched = std::move(merged);
  }
  releaseFreedMemory();  // the groups' regions and factors, before the results are gathered
  if (!stats.rounds.empty()) stats.unresolvedFaces = stats.rounds.back().borderFaces;
  if (largest.unknowns > 0) keepLargestSolve(largest, stats);
  measureRefinedMap(source, touched, cones, options, stats);
  source.collect(touched, out);
  if (options.regionOnly || options.listRegionFaces) out.regionFaces = std::move(touched);
  countIslandVertices(source.table(), options.islandFaces, out.stats);
  collectChangedSeams(currentT, seamT, out);
}

}  // namespace seamvox::detail
