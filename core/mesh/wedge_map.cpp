#include "core/mesh/wedge_map.h"

#include <algorithm>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/system/errors.h"

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
  for (std::size_t c = wedge_.size(); c-- > 0;) {
    const std::uint32_t w = wedge_[c];
    if (w >= begin && w < end) first[w - begin] = static_cast<CornerId>(c);
  }
  return first;
}

void WedgeMap::set(CornerId c, const Vec2d& q) {
  if (value_[wedge_[c]] == q) return;
  wedge_[c] = numWedges();
  value_.push_back(q);
}

void WedgeMap::assign(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values) {
  if (corners.size() != values.size()) {
    throw InputError("wedge map: " + std::to_string(corners.size()) + " corners but " +
                     std::to_string(values.size()) + " values");
  }
  for (CornerId c : corners) {
    if (c >= wedge_.size()) {
      throw InputError("wedge map: corner " + std::to_string(c) + " out of range (" +
                       std::to_string(wedge_.size()) + " corners)");
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
  for (std::size_t k = 0; k < last.size(); ++k) touched[k] = wedge_[last[k].first];
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  const auto slot = [&](std::uint32_t w) {
    return static_cast<std::size_t>(std::lower_bound(touched.begin(), touched.end(), w) - touched.begin());
  };
  std::vector<std::uint32_t> given(touched.size(), 0), all(touched.size(), 0);
  for (const auto& [c, q] : last) ++given[slot(wedge_[c])];
  {
    std::vector<bool> isTouched(value_.size(), false);
    for (std::uint32_t w : touched) isTouched[w] = true;
    for (std::uint32_t w : wedge_) {
      if (isTouched[w]) ++all[slot(w)];
    }
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
    const std::uint32_t w = wedge_[c];
    const std::size_t i = slot(w);
    Option& head = first[i];
    if (head.set && head.q == q) {
      wedge_[c] = head.target;
      continue;
    }
    if (head.set) {
      auto& rest = more[i];
      const auto found = std::find_if(rest.begin(), rest.end(), [&](const auto& o) { return o.first == q; });
      if (found != rest.end()) {
        wedge_[c] = found->second;
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
    wedge_[c] = target;
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
  wedge_.resize(n);
  wedge_.shrink_to_fit();
}

void WedgeMap::keepCorners(std::size_t n) {
  if (n >= wedge_.size()) return;
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
}

std::size_t WedgeMap::memoryBytes() const {
  return wedge_.capacity() * sizeof(std::uint32_t) + value_.capacity() * sizeof(Vec2d);
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
