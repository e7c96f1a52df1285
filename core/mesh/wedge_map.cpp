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
  // Corners per touched wedge: in the assignment, and in the whole map (one pass, counting only
  // the touched wedges).
  std::vector<bool> touched(value_.size(), false);
  std::unordered_map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> count;  // given, all
  for (CornerId c : corners) {
    touched[wedge_[c]] = true;
    ++count[wedge_[c]].first;
  }
  for (std::uint32_t w : wedge_) {
    if (touched[w]) ++count[w].second;
  }
  // Repeated corners count once too many; a wedge is wholly assigned when every corner of it is
  // given, which then also holds with the repeats removed.
  std::vector<std::pair<CornerId, std::uint32_t>> order(corners.size());
  for (std::size_t k = 0; k < corners.size(); ++k) order[k] = {corners[k], static_cast<std::uint32_t>(k)};
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (order[k].first == order[k - 1].first) --count[wedge_[order[k].first]].first;
  }
  // The last value given for a corner wins.
  std::vector<std::pair<CornerId, Vec2d>> last;
  last.reserve(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k + 1 < order.size() && order[k + 1].first == order[k].first) continue;
    last.emplace_back(order[k].first, values[order[k].second]);
  }
  // Per wedge: the first new value reuses the wedge when all its corners are given; any other
  // new value gets a wedge of its own (shared by the corners of that wedge given that value).
  std::unordered_map<std::uint32_t, std::vector<std::pair<Vec2d, std::uint32_t>>> made;
  // At most one new wedge per corner given: grown by that much and 1/8 more, not doubled (a
  // map's values are 8 bytes per face; the untouched reserve is not resident).
  if (value_.capacity() < value_.size() + last.size()) {
    std::vector<Vec2d> grown;
    grown.reserve(value_.size() + last.size() + value_.size() / 8);
    grown.assign(value_.begin(), value_.end());
    value_.swap(grown);
  }
  for (const auto& [c, q] : last) {
    const std::uint32_t w = wedge_[c];
    auto& options = made[w];
    const auto found = std::find_if(options.begin(), options.end(),
                                    [&](const auto& o) { return o.first == q; });
    if (found != options.end()) {
      wedge_[c] = found->second;
      continue;
    }
    const auto& n = count[w];
    std::uint32_t target;
    if (options.empty() && n.first == n.second) {
      target = w;
      value_[w] = q;
    } else if (value_[w] == q && n.first != n.second) {
      target = w;  // unchanged value on a partly assigned wedge: stays
    } else {
      target = numWedges();
      value_.push_back(q);
    }
    options.emplace_back(q, target);
    wedge_[c] = target;
  }
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
