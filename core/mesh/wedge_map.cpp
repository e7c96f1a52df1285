#include "core/mesh/wedge_map.h"

#include <algorithm>
#include <atomic>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/mesh/topology.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

WedgeMap::WedgeMap(std::vector<std::uint32_t> cornerWedge, std::vector<Vec2d> wedgeValues)
    : wedge_(std::move(cornerWedge)), value_(std::move(wedgeValues)) {
  for (std::size_t c = 0; c < wedge_.size(); ++c) {
    if (wedge_[c] >= value_.size()) {
      throw InputError("wedge map: corner " + std::to_string(c) + " has wedge " +
                       std::to_string(wedge_[c]) + " but there are " + std::to_string(value_.size()) +
                       " wedges");
    }
  }
}

namespace {

/// The wedge id of every corner of the map, in corner order.
std::vector<std::uint32_t> idsPerCorner(const WedgeMap& map) {
  std::vector<std::uint32_t> ids(map.size());
  for (std::size_t c = 0; c < ids.size(); ++c) ids[c] = map.wedge(static_cast<CornerId>(c));
  return ids;
}

}  // namespace

WedgeMap::WedgeMap(const WedgeMap& other)
    : wedge_(other.tris_ ? idsPerCorner(other) : other.wedge_), value_(other.value_) {}

WedgeMap& WedgeMap::operator=(const WedgeMap& other) {
  if (this != &other) *this = WedgeMap(other);
  return *this;
}

WedgeMap WedgeMap::overTriangles(const Triangle* triangles, std::size_t corners, std::vector<std::uint32_t> vertexWedge,
                                 const std::vector<std::pair<CornerId, std::uint32_t>>& other,
                                 std::vector<Vec2d> wedgeValues) {
  if (wedgeValues.size() >= kListed) {
    throw InputError("wedge map: " + std::to_string(wedgeValues.size()) + " wedges, too many to keep per vertex");
  }
  // Every corner's vertex and its wedge in range (the first bad corner named), and the listed ones.
  std::atomic<std::uint64_t> bad{corners};
  parallelFor(corners, 1u << 16, [&](const IndexRange& range) {
    for (std::uint64_t c = range.begin(); c != range.end(); ++c) {
      const VertexId v = triangles[c / 3][c % 3];
      if (v < vertexWedge.size() && vertexWedge[v] < wedgeValues.size()) continue;
      std::uint64_t seen = bad.load();
      while (c < seen && !bad.compare_exchange_weak(seen, c)) {
      }
      break;
    }
  });
  if (bad.load() < corners) {
    const std::uint64_t c = bad.load();
    throw InputError("wedge map: corner " + std::to_string(c) + " has vertex " +
                     std::to_string(triangles[c / 3][c % 3]) + " without a wedge among " +
                     std::to_string(wedgeValues.size()));
  }
  for (const auto& [c, w] : other) {
    if (c >= corners || w >= wedgeValues.size()) {
      throw InputError("wedge map: listed corner " + std::to_string(c) + " with wedge " + std::to_string(w) +
                       " out of range (" + std::to_string(corners) + " corners, " +
                       std::to_string(wedgeValues.size()) + " wedges)");
    }
  }
  WedgeMap map;
  map.value_ = std::move(wedgeValues);
  if (other.size() > maxListed(corners)) {
    map.wedge_.resize(corners);
    parallelFor(corners, 1u << 16, [&](const IndexRange& range) {
      for (std::uint64_t c = range.begin(); c != range.end(); ++c) map.wedge_[c] = vertexWedge[triangles[c / 3][c % 3]];
    });
    for (const auto& [c, w] : other) map.wedge_[c] = w;
    return map;
  }
  map.tris_ = reinterpret_cast<const VertexId*>(triangles);
  map.corners_ = corners;
  map.vertexWedge_ = std::move(vertexWedge);
  map.listed_.reserve(other.size());
  for (const auto& [c, w] : other) map.setCornerWedge(c, w);
  return map;
}

bool WedgeMap::viewTriangles(const Triangle* triangles, std::uint32_t numVertices) {
  if (tris_) return true;
  if (value_.size() >= kListed) return false;
  std::vector<std::uint32_t> vertexWedge(numVertices, kInvalidId);
  for (std::size_t c = 0; c < wedge_.size(); ++c) {
    const VertexId v = triangles[c / 3][c % 3];
    if (v >= numVertices) return false;
    if (vertexWedge[v] == kInvalidId) vertexWedge[v] = wedge_[c];
  }
  std::vector<std::pair<CornerId, std::uint32_t>> other;
  for (std::size_t c = 0; c < wedge_.size(); ++c) {
    if (wedge_[c] != vertexWedge[triangles[c / 3][c % 3]]) other.emplace_back(static_cast<CornerId>(c), wedge_[c]);
  }
  if (other.size() > maxListed(wedge_.size())) return false;
  for (std::uint32_t& w : vertexWedge) w = w == kInvalidId ? 0 : w;
  const std::size_t corners = wedge_.size();
  std::vector<std::uint32_t>().swap(wedge_);
  *this = overTriangles(triangles, corners, std::move(vertexWedge), other, std::move(value_));
  return true;
}

void WedgeMap::setCornerWedge(CornerId c, std::uint32_t w) {
  if (!tris_) {
    wedge_[c] = w;
    return;
  }
  std::uint32_t& own = vertexWedge_[tris_[c]];
  if (w == (own & ~kListed)) {
    if (own & kListed) listed_.erase(c);
    return;
  }
  listed_[c] = w;
  own |= kListed;
  // Many corners split off their vertex's wedge (a map no longer seamless there): ids per corner
  // hold less.
  if (listed_.size() > maxListed(corners_)) perCorner();
}

void WedgeMap::perCorner() {
  if (!tris_) return;
  std::vector<std::uint32_t> wedges = idsPerCorner(*this);
  tris_ = nullptr;
  corners_ = 0;
  std::vector<std::uint32_t>().swap(vertexWedge_);
  std::unordered_map<CornerId, std::uint32_t>().swap(listed_);
  wedge_ = std::move(wedges);
}

WedgeMap WedgeMap::fromCorners(const std::vector<Triangle>& triangles, const std::vector<Vec2d>& values) {
  if (values.size() != 3 * triangles.size()) {
    throw InputError("wedge map: " + std::to_string(values.size()) + " corner values for " +
                     std::to_string(triangles.size()) + " faces (expected 3 per face)");
  }
  WedgeMapBuilder builder;
  builder.reserve(values.size());
  for (std::size_t c = 0; c < values.size(); ++c) builder.add(triangles[c / 3][c % 3], values[c]);
  return builder.finish();
}

std::vector<CornerId> WedgeMap::wedgeCorners(std::uint32_t begin, std::uint32_t end) const {
  end = std::min(end, numWedges());
  begin = std::min(begin, end);
  std::vector<CornerId> first(end - begin, kInvalidId);
  // Both cores, each block in increasing order; a block's corner replaces a smaller-numbered
  // block's only when smaller (a compare-and-swap minimum), so the result is the least corner.
  parallelFor(size(), 1u << 16, [&](const IndexRange& range) {
    for (std::uint64_t c = range.begin(); c != range.end(); ++c) {
      const std::uint32_t w = wedge(static_cast<CornerId>(c));
      if (w < begin || w >= end) continue;
      CornerId* slot = &first[w - begin];
      CornerId seen = __atomic_load_n(slot, __ATOMIC_RELAXED);
      while (c < seen && !__atomic_compare_exchange_n(slot, &seen, static_cast<CornerId>(c), true, __ATOMIC_RELAXED,
                                                      __ATOMIC_RELAXED)) {
      }
    }
  });
  return first;
}

void WedgeMap::set(CornerId c, const Vec2d& q) {
  if (value_[wedge(c)] == q) return;
  const std::uint32_t w = numWedges();
  value_.push_back(q);
  setCornerWedge(c, w);
}

void WedgeMap::assign(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values) {
  assignCounted(corners, values, nullptr);
}

void WedgeMap::assign(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values,
                      const Topology& topology) {
  if (3u * static_cast<std::size_t>(topology.numFaces()) != size()) {
    throw InputError("wedge map: " + std::to_string(size()) + " corners but the topology has " +
                     std::to_string(topology.numFaces()) + " faces");
  }
  assignCounted(corners, values, &topology);
}

void WedgeMap::assignCounted(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values,
                             const Topology* topology) {
  if (corners.size() != values.size()) {
    throw InputError("wedge map: " + std::to_string(corners.size()) + " corners but " +
                     std::to_string(values.size()) + " values");
  }
  for (CornerId c : corners) {
    if (c >= size()) {
      throw InputError("wedge map: corner " + std::to_string(c) + " out of range (" +
                       std::to_string(size()) + " corners)");
    }
  }
  if (corners.empty()) return;
  // The last value given for each corner, in corner order.
  std::vector<std::pair<CornerId, Vec2d>> last;
  {
    std::vector<std::pair<CornerId, std::uint32_t>> order(corners.size());
    for (std::size_t k = 0; k < corners.size(); ++k) order[k] = {corners[k], static_cast<std::uint32_t>(k)};
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    last.reserve(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      if (k + 1 < order.size() && order[k + 1].first == order[k].first) continue;
      last.emplace_back(order[k].first, values[order[k].second]);
    }
  }
  // The touched wedges (sorted) with, per wedge, its corners given and all its corners (one pass
  // over the map, counting only the touched wedges): flat arrays, a few bytes per wedge.
  std::vector<std::uint32_t> touched(last.size());
  for (std::size_t k = 0; k < last.size(); ++k) touched[k] = wedge(last[k].first);
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  const auto slot = [&](std::uint32_t w) {
    return static_cast<std::size_t>(std::lower_bound(touched.begin(), touched.end(), w) - touched.begin());
  };
  std::vector<std::uint32_t> given(touched.size(), 0), all(touched.size(), 0);
  std::vector<CornerId> some(touched.size());  // a given corner of each touched wedge
  for (const auto& [c, q] : last) {
    const std::size_t i = slot(wedge(c));
    ++given[i];
    some[i] = c;
  }
  if (topology) {
    // A wedge's corners are corners of one vertex: its fan holds them all.
    for (std::size_t i = 0; i < touched.size(); ++i) {
      topology->forEachCornerAround(topology->vertex(some[i]), [&](CornerId c) { all[i] += wedge(c) == touched[i]; });
    }
  } else {
    // The pass over the map in parallel: the touched wedges' corners are few, so their counts
    // are atomic adds that rarely meet.
    std::vector<std::uint8_t> isTouched(value_.size(), 0);
    for (std::uint32_t w : touched) isTouched[w] = 1;
    std::vector<std::atomic<std::uint32_t>> count(touched.size());
    for (auto& n : count) n.store(0, std::memory_order_relaxed);
    parallelFor(size(), 1u << 16, [&](const IndexRange& range) {
      for (std::uint64_t c = range.begin(); c != range.end(); ++c) {
        const std::uint32_t w = wedge(static_cast<CornerId>(c));
        if (isTouched[w]) count[slot(w)].fetch_add(1, std::memory_order_relaxed);
      }
    });
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = count[i].load(std::memory_order_relaxed);
  }
  // Per wedge, in corner order: the first new value reuses the wedge when all its corners are
  // given; any other new value gets a wedge of its own (shared by the corners of that wedge
  // given that value). A wedge's first value is kept flat, further ones (rare) in a map; the new
  // wedges are counted first, so the values grow once by exactly that many (a reallocation
  // would hold them twice: 16 bytes per vertex).
  struct Option {
    Vec2d q;
    std::uint32_t target = 0;
    bool set = false;
  };
  std::vector<Option> first(touched.size());
  std::unordered_map<std::size_t, std::vector<std::pair<Vec2d, std::uint32_t>>> more;
  std::vector<Vec2d> fresh;
  const std::uint32_t numOld = numWedges();
  for (const auto& [c, q] : last) {
    const std::uint32_t w = wedge(c);
    const std::size_t i = slot(w);
    Option& head = first[i];
    if (head.set && head.q == q) {
      setCornerWedge(c, head.target);
      continue;
    }
    if (head.set) {
      auto& rest = more[i];
      const auto found = std::find_if(rest.begin(), rest.end(), [&](const auto& o) { return o.first == q; });
      if (found != rest.end()) {
        setCornerWedge(c, found->second);
        continue;
      }
    }
    std::uint32_t target;
    if (!head.set && given[i] == all[i]) {
      target = w;
      value_[w] = q;
    } else if (value_[w] == q && given[i] != all[i]) {
      target = w;  // unchanged value on a partly assigned wedge: stays
    } else {
      target = numOld + static_cast<std::uint32_t>(fresh.size());
      fresh.push_back(q);
    }
    if (!head.set) {
      head = {q, target, true};
    } else {
      more[i].emplace_back(q, target);
    }
    setCornerWedge(c, target);
  }
  if (value_.capacity() < value_.size() + fresh.size()) {
    std::vector<Vec2d> grown;
    grown.reserve(value_.size() + fresh.size() + value_.size() / 8);
    grown.assign(value_.begin(), value_.end());
    value_.swap(grown);
  }
  value_.insert(value_.end(), fresh.begin(), fresh.end());
}

void checkCorners(const WedgeMap& map, std::size_t corners, const std::string& what) {
  if (map.size() != corners) {
    throw InputError(what + ": the map has " + std::to_string(map.size()) + " corners, expected " +
                     std::to_string(corners) + " (3 per face)");
  }
}

void WedgeMap::resizeCorners(std::size_t n) {
  perCorner();
  wedge_.resize(n);
  wedge_.shrink_to_fit();
}

void WedgeMap::keepCorners(std::size_t n) {
  if (n >= size()) return;
  perCorner();
  wedge_.resize(n);
  std::vector<std::uint32_t> renumber(value_.size(), kInvalidId);
  for (const std::uint32_t w : wedge_) renumber[w] = 0;
  std::uint32_t kept = 0;
  for (std::uint32_t w = 0; w < value_.size(); ++w) {
    if (renumber[w] == kInvalidId) continue;
    renumber[w] = kept;
    value_[kept++] = value_[w];
  }
  value_.resize(kept);
  for (std::uint32_t& w : wedge_) w = renumber[w];
}

void WedgeMap::clear() {
  std::vector<std::uint32_t>().swap(wedge_);
  std::vector<Vec2d>().swap(value_);
  tris_ = nullptr;
  corners_ = 0;
  std::vector<std::uint32_t>().swap(vertexWedge_);
  std::unordered_map<CornerId, std::uint32_t>().swap(listed_);
}

std::size_t WedgeMap::memoryBytes() const {
  // A listed corner: its node (key, value, next pointer, cached hash) and a bucket pointer.
  const std::size_t listed = listed_.size() * (sizeof(std::pair<CornerId, std::uint32_t>) + 2 * sizeof(void*)) +
                             listed_.bucket_count() * sizeof(void*);
  return (wedge_.capacity() + vertexWedge_.capacity()) * sizeof(std::uint32_t) + value_.capacity() * sizeof(Vec2d) +
         listed;
}

void WedgeMapBuilder::reserve(std::size_t corners) { map_.wedge_.reserve(corners); }

void WedgeMapBuilder::add(VertexId v, const Vec2d& q) {
  if (v == kInvalidId) {
    map_.wedge_.push_back(map_.numWedges());
    map_.value_.push_back(q);
    nextWedge_.push_back(kInvalidId);
    return;
  }
  if (v >= vertexWedge_.size()) {
    vertexWedge_.resize(std::max<std::size_t>(v + std::size_t(1), 2 * vertexWedge_.size()), kInvalidId);
  }
  std::uint32_t w = vertexWedge_[v];
  for (int searched = 0; w != kInvalidId && searched < kMaxSearch; ++searched, w = nextWedge_[w]) {
    if (map_.value_[w] == q) {
      map_.wedge_.push_back(w);
      return;
    }
  }
  w = map_.numWedges();
  map_.value_.push_back(q);
  nextWedge_.push_back(vertexWedge_[v]);
  vertexWedge_[v] = w;
  map_.wedge_.push_back(w);
}

WedgeMap WedgeMapBuilder::finish() {
  WedgeMap out = std::move(map_);
  out.value_.shrink_to_fit();
  map_ = WedgeMap();
  std::vector<std::uint32_t>().swap(vertexWedge_);
  std::vector<std::uint32_t>().swap(nextWedge_);
  return out;
}

}  // namespace seamvox
