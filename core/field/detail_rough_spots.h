#pragma once
/// smoothRoughSpots written once for the in-memory corner table and the out-of-core one
/// (stream/field_stream), so that both move the same vertices to the same floats. Internal.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/field/detail_smoothing.h"
#include "core/field/rough_spots.h"
#include "core/mesh/detail_id_map.h"
#include "core/mesh/detail_union_find.h"
#include "core/mesh/topology.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox::detail {

/// InputError unless the grid's edge length is positive and finite.
inline void checkRoughSpotGrid(double gridLength) {
  if (!(gridLength > 0.0) || !std::isfinite(gridLength)) {
    throw InputError("smoothRoughSpots: grid edge length " + std::to_string(gridLength) + " is not positive");
  }
}

/// Angle defect at v (0 at boundary and isolated vertices); at(w): position of w in double.
template <class Table, class At>
double angleDefectOf(Table& table, VertexId v, At&& at) {
  if (table.isIsolatedVertex(v) || table.isBoundaryVertex(v)) return 0.0;
  const Vec3d p = at(v);
  double sum = 0.0;
  table.forEachCornerAround(v, [&](CornerId c) {
    const Vec3d a = at(table.vertex(nextCorner(c))) - p;
    const Vec3d b = at(table.vertex(prevCorner(c))) - p;
    sum += std::atan2(a.cross(b).norm(), a.dot(b));
  });
  return 2.0 * M_PI - sum;
}

/// Mean length of the edges of interior vertex v (-1 at boundary and isolated vertices).
template <class Table, class At>
float vertexSpacing(Table& table, VertexId v, At&& at) {
  if (table.isIsolatedVertex(v) || table.isBoundaryVertex(v)) return -1.0f;
  const Vec3d p = at(v);
  double length = 0.0;
  std::uint32_t count = 0;
  table.forEachCornerAround(v, [&](CornerId c) {
    length += (at(table.vertex(nextCorner(c))) - p).norm();
    ++count;
  });
  return static_cast<float>(length / count);
}

/// Vertices per chunk of the mean spacing's sum: each chunk summed in vertex order, the chunks in
/// order, so that the sum is the same for any thread count and any pass's blocks.
constexpr std::uint32_t kSpacingChunk = 1u << 16;

/// The mean spacing of the interior vertices from their chunks' sums (count, sum of spacings).
inline double meanSpacingOf(const std::vector<std::pair<std::uint64_t, double>>& chunks) {
  std::uint64_t count = 0;
  double sum = 0.0;
  for (const auto& [n, s] : chunks) count += n, sum += s;
  return count ? sum / count : 0.0;
}

/// The spacing below which a vertex may be rough: kRoughSpotSpacing of the grid's edge length,
/// and kRoughSpotRelative of the mesh's mean spacing.
inline double roughSpacingLimit(double gridLength, double meanSpacing) {
  return std::min(kRoughSpotSpacing * gridLength, kRoughSpotRelative * meanSpacing);
}

/// Rough: interior (`own`, its vertexSpacing, not negative), its edges shorter than `spacing` on
/// average (roughSpacingLimit), angle defect above kRoughSpotDefect, and the defects within two
/// rings cancel (kRoughSpotCancel).
template <class Table, class At>
bool isRoughVertex(Table& table, VertexId v, At&& at, double spacing, float own) {
  if (!(own >= 0.0f) || !(own < spacing)) return false;
  if (!(std::abs(angleDefectOf(table, v, at)) > kRoughSpotDefect)) return false;
  // Crumpled: the defects of the vertices within two rings cancel (a tip's all have one sign).
  double absSum = 0.0, sum = 0.0;
  std::vector<VertexId> ring = {v};
  table.forEachCornerAround(v, [&](CornerId c) { ring.push_back(table.vertex(nextCorner(c))); });
  const std::size_t first = ring.size();
  for (std::size_t i = 1; i < first; ++i) {
    if (table.isIsolatedVertex(ring[i])) continue;
    table.forEachCornerAround(ring[i], [&](CornerId c) { ring.push_back(table.vertex(nextCorner(c))); });
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  for (VertexId w : ring) {
    const double k = angleDefectOf(table, w, at);
    absSum += std::abs(k), sum += k;
  }
  return std::abs(sum) < kRoughSpotCancel * absSum;
}

/// isRoughVertex with v's spacing computed here.
template <class Table, class At>
bool isRoughVertex(Table& table, VertexId v, At&& at, double spacing) {
  return isRoughVertex(table, v, at, spacing, vertexSpacing(table, v, at));
}

/// Empties the fans of the pieces of the region (active vertices 0..numActive-1 joined along their
/// fans) that hold no vertex: no neighbour outside the region, no boundary or isolated vertex.
/// Such a piece is a whole closed component smaller than the region (a scan's crumb, a tiny
/// tetrahedron), and Laplacian steps would shrink it to a point.
inline void holdWholeComponents(std::size_t numActive, std::vector<std::uint64_t>& fanStart,
                                std::vector<std::uint32_t>& fan) {
  UnionFind pieces(numActive);
  std::vector<std::uint8_t> held(numActive, 0);
  for (std::size_t i = 0; i < numActive; ++i) {
    if (fanStart[i] == fanStart[i + 1]) held[i] = 1;
    for (std::uint64_t k = fanStart[i]; k < fanStart[i + 1]; ++k) {
      if (fan[k] < numActive) {
        pieces.unite(static_cast<std::uint32_t>(i), fan[k]);
      } else {
        held[i] = 1;
      }
    }
  }
  for (std::size_t i = 0; i < numActive; ++i) {
    if (held[i]) held[pieces.find(static_cast<std::uint32_t>(i))] = 1;
  }
  std::vector<std::uint64_t> start(numActive + 1, 0);
  std::size_t out = 0;
  for (std::size_t i = 0; i < numActive; ++i) {
    const bool keep = held[pieces.find(static_cast<std::uint32_t>(i))];
    for (std::uint64_t k = fanStart[i]; keep && k < fanStart[i + 1]; ++k) fan[out++] = fan[k];
    start[i + 1] = out;
  }
  fan.resize(out);
  fanStart.swap(start);
}

/// The share of a smoothing step a vertex of a rough region takes at `t` = its distance from the
/// seeds over the radius: 1 up to 1/2, then a cosine down to 0 at 1, so that the smoothed region
/// joins the held surface without a crease (a crease there would put new cones on the rim).
inline float roughSpotShare(float t) {
  if (!(t > 0.5f)) return 1.0f;
  if (!(t < 1.0f)) return 0.0f;
  return static_cast<float>(0.5 + 0.5 * std::cos(2.0 * M_PI * (double(t) - 0.5)));
}

/// A round's region of smoothRoughRounds: the vertices within the radius of the seeds (active)
/// and their neighbours beyond it (held), numbered active first, then held, each by vertex id.
struct RoughRegion {
  std::vector<VertexId> active;        ///< increasing
  std::vector<float> share;            ///< per active vertex: roughSpotShare of its distance
  std::vector<std::uint64_t> fanStart;  ///< per active vertex + 1: its fan in `fan`
  std::vector<std::uint32_t> fan;      ///< an interior vertex's neighbours in fan order (local ids)
  std::vector<Vec3f> value;            ///< positions, active then held
  bool over = false;                   ///< the region and its held vertices exceed the bound
};

/// The edge's length from a vertex at distance d and position p to one at q, as every search of
/// a rough region adds it (in float, so that both searches give the same bits).
inline float roughStep(float d, const Vec3d& p, const Vec3f& q) {
  return d + static_cast<float>((q.cast<double>() - p).norm());
}

/// A region vertex's neighbours in fan order: its corners' next vertices, and at a boundary vertex
/// their previous ones too (the rim's last vertex is no corner's next). Whether v is a boundary one
/// (it has no fan to smooth).
template <class Table, class Visit>
bool forEachRegionNeighbour(Table& table, VertexId v, Visit&& visit) {
  const bool boundary = table.isBoundaryVertex(v);
  table.forEachCornerAround(v, [&](CornerId c) {
    visit(table.vertex(nextCorner(c)));
    if (boundary) visit(table.vertex(prevCorner(c)));
  });
  return boundary;
}

/// The region one thread finds (the out-of-core table, read by one thread): Dijkstra from the
/// seeds along edges in float, each vertex reached given a local id once (hashed), so that an
/// edge costs one lookup; a vertex within the radius gathers its fan (local ids in fan order, as
/// smoothingStep walks it) when it is settled, its neighbours beyond the radius becoming held ones.
/// A vertex's distance is the least over its paths from the seeds (each prefix within `limit`) of
/// the path's lengths added in order: it does not depend on the order of ties, nor on the search.
/// Stops as soon as the region holds more than maxRegion vertices (over).
template <class Table, class Current>
RoughRegion searchRoughRegion(Table& table, Current&& current, const std::vector<VertexId>& seeds, float limit,
                              std::uint64_t maxRegion) {
  RoughRegion region;
  IdMap local;
  std::vector<VertexId> ids;   // local id -> vertex
  std::vector<float> dist;     // local id -> distance (infinite: beyond the radius)
  std::vector<Vec3f> value;    // local id -> position
  std::vector<std::uint64_t> fanAt;  // local id -> first entry in fans + 1 (0: no fan gathered)
  std::vector<std::uint32_t> fans;   // per settled vertex: its fan's size, then its fan
  const auto localId = [&](VertexId v) {
    const auto [id, added] = local.emplace(v, static_cast<std::uint32_t>(ids.size()));
    if (added) {
      ids.push_back(v);
      dist.push_back(std::numeric_limits<float>::infinity());
      value.push_back(current(v));
      fanAt.push_back(0);
      region.over = region.over || ids.size() > maxRegion;
    }
    return id;
  };
  using Entry = std::pair<float, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (VertexId v : seeds) {
    const std::uint32_t i = localId(v);
    dist[i] = 0.0f;
    queue.emplace(0.0f, i);
  }
  std::vector<std::uint32_t> around;
  while (!queue.empty() && !region.over) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > dist[i] || fanAt[i] != 0) continue;
    const VertexId v = ids[i];
    fanAt[i] = fans.size() + 1;
    fans.push_back(0);
    if (table.isIsolatedVertex(v)) continue;
    // An interior vertex's neighbours are its corners' next vertices, its fan; a boundary
    // vertex's are those and the last corner's previous vertex, and it has no fan (it stays).
    around.clear();
    const bool boundary = forEachRegionNeighbour(table, v, [&](VertexId w) { around.push_back(localId(w)); });
    const Vec3d p = value[i].template cast<double>();
    for (std::uint32_t j : around) {
      const float dj = roughStep(d, p, value[j]);
      if (!(dj <= limit) || !(dj < dist[j])) continue;
      dist[j] = dj;
      queue.emplace(dj, j);
    }
    if (!boundary) {
      fans[fanAt[i] - 1] = static_cast<std::uint32_t>(around.size());
      fans.insert(fans.end(), around.begin(), around.end());
    }
  }
  if (region.over) return region;
  local = IdMap();
  // Renumbered: the vertices within the radius first, by vertex id, then the held ones.
  // Sorted as keys (held bit, vertex) with the local id alongside: a sort of contiguous pairs.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(ids.size());
  for (std::uint32_t i = 0; i < keyed.size(); ++i) {
    keyed[i] = {(std::uint64_t(fanAt[i] == 0) << 32) | ids[i], i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(ids.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = keyed[k].second;
  std::vector<std::pair<std::uint64_t, std::uint32_t>>().swap(keyed);
  std::vector<std::uint32_t> renumbered(ids.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) renumbered[order[k]] = k;
  std::size_t numActive = 0;
  while (numActive < order.size() && fanAt[order[numActive]] != 0) ++numActive;
  region.active.resize(numActive);
  region.share.resize(numActive);
  region.fanStart.assign(numActive + 1, 0);
  region.fan.reserve(fans.size() - numActive);
  for (std::size_t k = 0; k < numActive; ++k) {
    const std::uint32_t i = order[k];
    region.active[k] = ids[i];
    region.share[k] = roughSpotShare(dist[i] / limit);
    const std::uint64_t at = fanAt[i] - 1;
    for (std::uint32_t n = 0; n < fans[at]; ++n) region.fan.push_back(renumbered[fans[at + 1 + n]]);
    region.fanStart[k + 1] = region.fan.size();
  }
  region.value.resize(order.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) region.value[k] = value[order[k]];
  return region;
}

/// A distance as a key whose larger values are the nearer distances, 0 for none (a distance is
/// finite and not negative, so its bits are at most 0x7F7FFFFF): a relaxation is an atomic maximum.
inline std::uint32_t nearKey(float d) {
  std::uint32_t bits;
  std::memcpy(&bits, &d, sizeof bits);
  return ~bits;
}
inline float keyDistance(std::uint32_t key) {
  const std::uint32_t bits = ~key;
  float d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}

/// searchRoughRegion's region on both cores (the in-memory table of numVertices vertices): the
/// same distances, found in waves (each vertex whose distance fell in one wave relaxes its
/// neighbours in the next, by atomic maxima of nearKey in a per-vertex array), so the same
/// region, fans and numbering. The wave in which the region exceeds maxRegion ends the search.
/// Per-vertex arrays from calloc: only the region's pages are touched. block: vertices a task
/// takes (the tests' small blocks put small regions on both cores).
template <class Table, class Current>
RoughRegion searchRoughRegionInMemory(Table& table, Current&& current, const std::vector<VertexId>& seeds, float limit,
                                      std::uint64_t maxRegion, std::uint32_t numVertices,
                                      std::size_t block = 1024) {
  constexpr std::uint32_t kHeld = 1;  // below any distance's key
  RoughRegion region;
  const auto blocksOf = [&](std::size_t n) { return (n + block - 1) / block; };
  const auto joined = [](std::vector<std::vector<VertexId>>& parts, std::vector<VertexId>& out) {
    for (std::vector<VertexId>& part : parts) out.insert(out.end(), part.begin(), part.end()), part = {};
  };
  const ZeroedIds key = zeroedIds(numVertices);     // nearKey of the distance, later local id + 1
  const ZeroedIds queued = zeroedIds(numVertices);  // the last wave that queued the vertex
  std::vector<VertexId> frontier = seeds, reached = seeds;
  for (VertexId v : seeds) key[v] = nearKey(0.0f);
  for (std::uint32_t wave = 1; !frontier.empty(); ++wave) {
    std::vector<std::vector<VertexId>> next(blocksOf(frontier.size())), fresh(next.size());
    parallelForEach(next.size(), 1, [&](std::uint64_t b) {
      const std::size_t end = std::min(frontier.size(), (b + 1) * block);
      for (std::size_t i = b * block; i < end; ++i) {
        const VertexId v = frontier[i];
        if (table.isIsolatedVertex(v)) continue;
        const float d = keyDistance(__atomic_load_n(&key[v], __ATOMIC_RELAXED));
        const Vec3d p = current(v).template cast<double>();
        const auto relax = [&](VertexId w) {
          const float dw = roughStep(d, p, current(w));
          if (!(dw <= limit)) return;
          const std::uint32_t k = nearKey(dw);
          std::uint32_t old = __atomic_load_n(&key[w], __ATOMIC_RELAXED);
          while (old < k) {
            if (__atomic_compare_exchange_n(&key[w], &old, k, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
              if (old == 0) fresh[b].push_back(w);
              if (__atomic_exchange_n(&queued[w], wave, __ATOMIC_RELAXED) != wave) next[b].push_back(w);
              return;
            }
          }
        };
        forEachRegionNeighbour(table, v, relax);
      }
    });
    frontier.clear();
    joined(next, frontier);
    joined(fresh, reached);
    if (reached.size() > maxRegion) {
      region.over = true;
      return region;
    }
  }
  sortUniqueIds(reached);
  region.active.swap(reached);
  const std::vector<VertexId>& active = region.active;
  const std::size_t numActive = active.size();
  // Shares from the distances; then the held vertices, each claimed once by its slot.
  region.share.resize(numActive);
  std::vector<std::vector<VertexId>> heldParts(blocksOf(numActive));
  parallelForEach(heldParts.size(), 1, [&](std::uint64_t b) {
    const std::size_t end = std::min(numActive, (b + 1) * block);
    for (std::size_t k = b * block; k < end; ++k) {
      region.share[k] = roughSpotShare(keyDistance(key[active[k]]) / limit);
      const VertexId v = active[k];
      if (table.isIsolatedVertex(v)) continue;
      const auto hold = [&](VertexId w) {
        std::uint32_t expected = 0;
        if (__atomic_load_n(&key[w], __ATOMIC_RELAXED) == 0 &&
            __atomic_compare_exchange_n(&key[w], &expected, kHeld, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
          heldParts[b].push_back(w);
        }
      };
      forEachRegionNeighbour(table, v, hold);
    }
  });
  std::vector<VertexId> held;
  joined(heldParts, held);
  sortUniqueIds(held);
  if (numActive + held.size() > maxRegion) {
    region = RoughRegion();
    region.over = true;
    return region;
  }
  const std::size_t total = numActive + held.size();
  const auto vertexAt = [&](std::size_t k) { return k < numActive ? active[k] : held[k - numActive]; };
  region.value.resize(total);
  parallelFor(total, 4096, [&](const IndexRange& range) {
    for (std::uint64_t k = range.begin(); k != range.end(); ++k) {
      const VertexId v = vertexAt(k);
      key[v] = static_cast<std::uint32_t>(k) + 1;
      region.value[k] = current(v);
    }
  });
  // Fans by blocks of active vertices, then laid end to end.
  std::vector<std::vector<std::uint32_t>> fanParts(blocksOf(numActive));
  region.fanStart.assign(numActive + 1, 0);
  parallelForEach(fanParts.size(), 1, [&](std::uint64_t b) {
    const std::size_t end = std::min(numActive, (b + 1) * block);
    for (std::size_t k = b * block; k < end; ++k) {
      const VertexId v = active[k];
      const std::size_t before = fanParts[b].size();
      if (!table.isIsolatedVertex(v) && !table.isBoundaryVertex(v)) {
        table.forEachCornerAround(v, [&](CornerId c) { fanParts[b].push_back(key[table.vertex(nextCorner(c))] - 1); });
      }
      region.fanStart[k + 1] = fanParts[b].size() - before;
    }
  });
  std::vector<std::uint64_t> partStart(fanParts.size() + 1, 0);
  for (std::size_t b = 0; b < fanParts.size(); ++b) partStart[b + 1] = partStart[b] + fanParts[b].size();
  for (std::size_t k = 0; k < numActive; ++k) region.fanStart[k + 1] += region.fanStart[k];
  region.fan.resize(partStart.back());
  parallelForEach(fanParts.size(), 1, [&](std::uint64_t b) {
    std::copy(fanParts[b].begin(), fanParts[b].end(), region.fan.begin() + partStart[b]);
    fanParts[b] = {};
  });
  return region;
}

/// The rounds of smoothRoughSpots from the rough vertices `seeds` (increasing): base(v) gives the
/// surface's position of v (Vec3f), spacing the roughSpacingLimit. Returns the vertices moved (their floats changed) and their
/// positions, sorted.
/// A round whose region (with its held neighbours) would exceed maxRegion vertices smooths
/// nothing and ends the rounds, *capped set (the out-of-core pass's memory bound).
/// inMemoryVertices: the in-memory table's vertex count (0 out of core, where the table is paged
/// and read by one thread): the region found on both cores (searchRoughRegionInMemory) and its
/// re-test on both cores; the same moves either way.
/// Each round: the vertices within kRoughSpotRadius * gridLength of the seeds along edges
/// (searchRoughRegion), kRoughSpotSteps Jacobi steps on them, each vertex taking roughSpotShare
/// of a step (in parallel, the same floats for any thread count), then the seeds still rough.
template <class Table, class Base>
std::vector<std::pair<VertexId, Vec3f>> smoothRoughRounds(Table& table, Base&& base, std::vector<VertexId> seeds,
                                                          double gridLength, double spacing, std::uint32_t& rounds,
                                                          std::uint64_t maxRegion = ~std::uint64_t(0),
                                                          bool* capped = nullptr, std::uint32_t inMemoryVertices = 0) {
  IdMap moved;                   // vertex -> index in movedIds and movedValues
  std::vector<VertexId> movedIds;
  std::vector<Vec3f> movedValues;
  const auto current = [&](VertexId v) -> Vec3f {
    const std::uint32_t k = moved.find(v);
    return k == IdMap::kEmpty ? Vec3f(base(v)) : movedValues[k];
  };
  const auto at = [&](VertexId v) -> Vec3d { return current(v).template cast<double>(); };
  const float limit = static_cast<float>(kRoughSpotRadius * gridLength);
  for (rounds = 0; rounds < kRoughSpotRounds && !seeds.empty(); ++rounds) {
    RoughRegion region = inMemoryVertices
                             ? searchRoughRegionInMemory(table, current, seeds, limit, maxRegion, inMemoryVertices)
                             : searchRoughRegion(table, current, seeds, limit, maxRegion);
    if (region.over) {  // a region above the bound: this round smooths nothing, and the rounds stop
      if (capped) *capped = true;
      break;
    }
    const std::vector<VertexId>& active = region.active;
    const std::vector<float>& share = region.share;
    std::vector<std::uint64_t>& fanStart = region.fanStart;
    std::vector<std::uint32_t>& fan = region.fan;
    std::vector<Vec3f>& value = region.value;
    holdWholeComponents(active.size(), fanStart, fan);
    // Both buffers hold the held vertices after the active ones, so that a step swaps them.
    std::vector<Vec3f> next(value);
    for (std::uint32_t step = 0; step < kRoughSpotSteps; ++step) {
      parallelFor(active.size(), 1024, [&](const IndexRange& range) {
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
          const Vec3d here = value[i].cast<double>();
          if (fanStart[i] == fanStart[i + 1]) {
            next[i] = value[i];
            continue;
          }
          Vec3d sum = Vec3d::Zero();
          for (std::uint64_t k = fanStart[i]; k < fanStart[i + 1]; ++k) sum += value[fan[k]].cast<double>();
          const Vec3d target =
              smoothingTarget(here, sum, static_cast<std::uint32_t>(fanStart[i + 1] - fanStart[i])).cast<double>();
          next[i] = (here + double(share[i]) * (target - here)).cast<float>();
        }
      });
      value.swap(next);
    }
    for (std::size_t i = 0; i < active.size(); ++i) {
      const auto [k, added] = moved.emplace(active[i], static_cast<std::uint32_t>(movedIds.size()));
      if (added) {
        movedIds.push_back(active[i]);
        movedValues.push_back(value[i]);
      } else {
        movedValues[k] = value[i];
      }
    }
    seeds.clear();
    if (inMemoryVertices) {  // the in-memory table may be read by both cores at once
      std::vector<std::uint8_t> still(active.size());
      parallelFor(active.size(), 1024, [&](const IndexRange& range) {
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) still[i] = isRoughVertex(table, active[i], at, spacing);
      });
      for (std::size_t i = 0; i < active.size(); ++i) {
        if (still[i]) seeds.push_back(active[i]);
      }
    } else {
      for (VertexId v : active) {
        if (isRoughVertex(table, v, at, spacing)) seeds.push_back(v);
      }
    }
  }
  std::vector<std::pair<VertexId, Vec3f>> out;
  for (std::size_t k = 0; k < movedIds.size(); ++k) {
    const VertexId v = movedIds[k];
    if (movedValues[k] != Vec3f(base(v))) out.emplace_back(v, movedValues[k]);  // held ones and boundary vertices stay
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

/// The rough spots' moves along the rough surface's normal only: for each moved vertex v (`moved`
/// sorted by vertex, its rough positions), plain(v) + n n.(rough(v) - plain(v)), n the normal of
/// v's fan on the rough surface (sum of its faces' cross products); plain(v) where that is zero.
/// plainAt(w): the plain smoothed surface's position of w (Vec3f). The map's stages after the cut
/// read this surface: the crumpling stays smoothed out of its shape, but not the steps' drift along
/// it, which folds noisy faces under a map evaluated or solved there (bench/RESULTS.md, session 60).
/// One moved vertex v at its rough position p: roughAt(w) is the rough surface's position of w (its
/// move, or plainAt(w) when it has none).
template <class Table, class RoughAt, class PlainAt>
Vec3f normalPartOfMove(Table& table, VertexId v, const Vec3f& rough, RoughAt&& roughAt, PlainAt&& plainAt) {
  const Vec3d p = rough.template cast<double>();
  Vec3d n = Vec3d::Zero();
  table.forEachCornerAround(v, [&](CornerId c) {
    n += (Vec3f(roughAt(table.vertex(nextCorner(c)))).template cast<double>() - p)
             .cross(Vec3f(roughAt(table.vertex(prevCorner(c)))).template cast<double>() - p);
  });
  const Vec3f plain = plainAt(v);
  const double squared = n.squaredNorm();
  const Vec3d q = plain.template cast<double>();
  return squared > 0.0 && std::isfinite(squared) ? Vec3f((q + n * (n.dot(p - q) / squared)).template cast<float>())
                                                 : plain;
}

/// Every move's normal part, one vertex after the other (a table and plainAt read by one thread).
template <class Table, class PlainAt>
std::vector<std::pair<VertexId, Vec3f>> normalPartOfMoves(Table& table, const std::vector<std::pair<VertexId, Vec3f>>& moved,
                                                          PlainAt&& plainAt) {
  const auto roughAt = [&](VertexId w) -> Vec3f {
    const auto it = std::lower_bound(moved.begin(), moved.end(), w,
                                     [](const std::pair<VertexId, Vec3f>& a, VertexId v) { return a.first < v; });
    return it != moved.end() && it->first == w ? it->second : Vec3f(plainAt(w));
  };
  std::vector<std::pair<VertexId, Vec3f>> out(moved.size());
  for (std::size_t i = 0; i < moved.size(); ++i) {
    out[i] = {moved[i].first, normalPartOfMove(table, moved[i].first, moved[i].second, roughAt, plainAt)};
  }
  return out;
}

}  // namespace seamvox::detail
