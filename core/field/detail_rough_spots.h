#pragma once
/// smoothRoughSpots written once for the in-memory corner table and the out-of-core one
/// (stream/field_stream), so that both move the same vertices to the same floats. Internal.
#include <algorithm>
#include <cmath>
#include <cstdint>
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
/// seeds over the radius: 1 up to 1/2, then a cosine down to 0 at 1.
inline float roughSpotShare(float t) {
  if (!(t > 0.5f)) return 1.0f;
  if (!(t < 1.0f)) return 0.0f;
  return static_cast<float>(0.5 + 0.5 * std::cos(2.0 * M_PI * (double(t) - 0.5)));
}

/// The rounds of smoothRoughSpots from the rough vertices `seeds` (increasing): base(v) gives the
/// surface's position of v (Vec3f), spacing the roughSpacingLimit. Returns the vertices moved (their floats changed) and their
/// positions, sorted.
/// A round whose region (with its held neighbours) would exceed maxRegion vertices smooths
/// nothing and ends the rounds, *capped set (the out-of-core pass's memory bound).
/// inMemoryVertices: the in-memory table's vertex count (0 out of core, where the table is paged
/// and read by one thread): local ids per vertex in an array of 4 B a vertex instead of hashed,
/// and the re-test of the region on both cores; the same moves either way.
/// Each round: the vertices within kRoughSpotRadius * gridLength of the seeds along edges
/// (Dijkstra, in float), their fans gathered once, kRoughSpotSteps Jacobi steps on them, each
/// vertex taking roughSpotShare of a step (in parallel, the same floats for any thread count), then
/// the seeds still rough.
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
    // Dijkstra from the seeds along edges (in float). Each vertex reached gets a local id once,
    // so that an edge costs one hash lookup; a vertex within the radius gathers its fan (local ids
    // in fan order, as smoothingStep walks it) when it is settled, its neighbours beyond the
    // radius becoming held ones. The distances do not depend on the order of ties.
    IdMap local;
    std::vector<VertexId> ids;   // local id -> vertex
    std::vector<float> dist;     // local id -> distance (infinite: beyond the radius)
    std::vector<Vec3f> value;    // local id -> position
    std::vector<std::uint64_t> fanAt;  // local id -> first entry in fans + 1 (0: no fan gathered)
    std::vector<std::uint32_t> fans;   // per settled vertex: its fan's size, then its fan
    bool over = false;
    // In memory, local ids sit in a per-vertex array (zero: none, else id + 1), whose
    // entries for a region are as close together as the region's corner-table entries; the
    // hashed map scatters every lookup. Untouched pages of the array are never faulted in.
    ZeroedIds dense = inMemoryVertices ? zeroedIds(inMemoryVertices) : ZeroedIds(nullptr, std::free);
    const auto localId = [&](VertexId v) {
      std::uint32_t id = static_cast<std::uint32_t>(ids.size());
      bool added = true;
      if (dense) {
        std::uint32_t& slot = dense[v];
        added = slot == 0;
        if (added) slot = id + 1;
        else id = slot - 1;
      } else {
        std::tie(id, added) = local.emplace(v, id);
      }
      over = over || ids.size() >= maxRegion;
      if (added) {
        ids.push_back(v);
        dist.push_back(std::numeric_limits<float>::infinity());
        value.push_back(current(v));
        fanAt.push_back(0);
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
    while (!queue.empty() && !over) {
      const auto [d, i] = queue.top();
      queue.pop();
      if (d > dist[i] || fanAt[i] != 0) continue;
      const VertexId v = ids[i];
      fanAt[i] = fans.size() + 1;
      fans.push_back(0);
      if (table.isIsolatedVertex(v)) continue;
      // An interior vertex's neighbours are its corners' next vertices, its fan; a boundary
      // vertex's are those and the last corner's previous vertex, and it has no fan (it stays).
      const bool boundary = table.isBoundaryVertex(v);
      around.clear();
      table.forEachCornerAround(v, [&](CornerId c) {
        around.push_back(localId(table.vertex(nextCorner(c))));
        if (boundary) around.push_back(localId(table.vertex(prevCorner(c))));
      });
      const Vec3d p = value[i].template cast<double>();
      for (std::uint32_t j : around) {
        const float dj = d + static_cast<float>((value[j].template cast<double>() - p).norm());
        if (!(dj <= limit) || !(dj < dist[j])) continue;
        dist[j] = dj;
        queue.emplace(dj, j);
      }
      if (!boundary) {
        fans[fanAt[i] - 1] = static_cast<std::uint32_t>(around.size());
        fans.insert(fans.end(), around.begin(), around.end());
      }
    }
    local = IdMap();  // freed before the steps
    dense.reset();
    if (over) {  // a region above the bound: this round smooths nothing, and the rounds stop
      if (capped) *capped = true;
      break;
    }
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
    std::vector<VertexId> active(numActive);
    // Each vertex's share of a step: whole within half the radius, tapering to none at the rim,
    // so that the smoothed region joins the held surface without a crease (a crease there would
    // put new cones on the rim).
    std::vector<float> share(numActive);
    std::vector<std::uint64_t> fanStart(numActive + 1, 0);
    std::vector<std::uint32_t> fan;
    fan.reserve(fans.size() - numActive);
    for (std::size_t k = 0; k < numActive; ++k) {
      const std::uint32_t i = order[k];
      active[k] = ids[i];
      share[k] = roughSpotShare(dist[i] / limit);
      const std::uint64_t at = fanAt[i] - 1;
      for (std::uint32_t n = 0; n < fans[at]; ++n) fan.push_back(renumbered[fans[at + 1 + n]]);
      fanStart[k + 1] = fan.size();
    }
    {
      std::vector<Vec3f> sorted(order.size());
      for (std::uint32_t k = 0; k < order.size(); ++k) sorted[k] = value[order[k]];
      value.swap(sorted);
    }
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
