#include "core/quads/lattice.h"

#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox::quads {

namespace {

Point snap(const Vec2d& q) {
  return {std::llround(q.x() * double(kUnit)), std::llround(q.y() * double(kUnit))};
}

// Quarter turns r for the edge of corner c (opposite o) that best map its left side onto its
// right side as q_right = i^r q_left + t (ties: the t nearest to an integer).
int fitRotation(const WedgeMap& uv, CornerId c, CornerId o) {
  const Vec2d a = uv[nextCorner(c)], b = uv[prevCorner(c)], a2 = uv[prevCorner(o)], b2 = uv[nextCorner(o)];
  int best = 0;
  double bestResidual = std::numeric_limits<double>::infinity(), bestDistance = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double cs[4] = {1, 0, -1, 0}, sn[4] = {0, 1, 0, -1};
    auto turn = [&](const Vec2d& p) { return Vec2d(cs[k] * p.x() - sn[k] * p.y(), sn[k] * p.x() + cs[k] * p.y()); };
    const Vec2d t = a2 - turn(a);
    const double residual = (b2 - (turn(b) + t)).norm();
    const double distance = (t - Vec2d(std::round(t.x()), std::round(t.y()))).norm();
    if (residual < bestResidual - 1e-9 || (residual <= bestResidual + 1e-9 && distance < bestDistance)) {
      best = k;
      bestResidual = std::min(residual, bestResidual);
      bestDistance = distance;
    }
  }
  return best;
}

}  // namespace

LatticeMap::LatticeMap(const TriangleMesh& mesh, const Topology& topology, std::int64_t scale)
    : mesh_(mesh), topo_(topology), map_(mesh.cornerUV), step_(scale * kUnit) {
  value_.resize(map_.numWedges());
  for (std::uint32_t w = 0; w < map_.numWedges(); ++w) {
    const Vec2d& q = map_.wedgeValue(w);
    if (!(std::abs(q.x()) < kMaxCoordinate && std::abs(q.y()) < kMaxCoordinate)) {
      throw InputError("texture coordinate (" + std::to_string(q.x()) + ", " + std::to_string(q.y()) +
                       ") is not finite or beyond 2^30 grid units");
    }
    value_[w] = snap(q);
  }
  rot_.assign(topo_.numCorners(), 0);
  parallelFor(topo_.numCorners(), 1 << 14, [&](const IndexRange& r) {
    for (std::uint64_t c = r.begin(); c < r.end(); ++c) {
      const CornerId o = topo_.opposite(CornerId(c));
      if (o == kInvalidId || o < c) continue;
      if (!isSeam(CornerId(c))) continue;  // the same wedges on both sides
      const int k = fitRotation(map_, CornerId(c), o);
      rot_[c] = static_cast<std::uint8_t>(k);
      rot_[o] = static_cast<std::uint8_t>((4 - k) & 3);
    }
  });
  cone_.assign(topo_.numVertices(), 0);
  std::atomic<std::uint64_t> open{0};
  parallelFor(topo_.numVertices(), 1 << 12, [&](const IndexRange& r) {
    std::uint64_t local = 0;
    for (std::uint64_t v = r.begin(); v < r.end(); ++v) closeFan(VertexId(v), local);
    open += local;
  });
  stats_.openVertexFans = open;
  for (std::uint32_t w = 0; w < map_.numWedges(); ++w) {
    const Vec2d moved = Vec2d(double(value_[w].x), double(value_[w].y)) / double(kUnit) - map_.wedgeValue(w);
    stats_.maxSnap = std::max(stats_.maxSnap, moved.norm());
  }
  for (VertexId v = 0; v < topo_.numVertices(); ++v) cones_ += cone_[v] != 0;
  for (FaceId f = 0; f < topo_.numFaces(); ++f) {
    const int s = sign(orient(at(3 * f), at(3 * f + 1), at(3 * f + 2)));
    stats_.flippedFaces += s < 0;
    stats_.degenerateFaces += s == 0;
  }
  for (CornerId c = 0; c < topo_.numCorners(); ++c) {
    const CornerId o = topo_.opposite(c);
    if (o == kInvalidId || o < c) continue;
    const Transition t = transition(c);
    if (t.t.x % step_ != 0 || t.t.y % step_ != 0) ++stats_.seamEdgesOffScale;
  }
}

bool LatticeMap::isSeam(CornerId c) const {
  const CornerId o = topo_.opposite(c);
  return map_.wedge(nextCorner(c)) != map_.wedge(prevCorner(o)) ||
         map_.wedge(prevCorner(c)) != map_.wedge(nextCorner(o));
}

Transition LatticeMap::seedTransition(CornerId c) const {
  const CornerId o = topo_.opposite(c);
  const CornerId e = std::min(c, o), f = std::max(c, o);
  Transition t;
  if (!isSeam(e)) return t;  // the identity
  t.r = rot_[e];
  const Vec2d a = map_[nextCorner(e)], a2 = map_[prevCorner(f)];
  const Point turned = rotate(snap(a), t.r);
  const Vec2d diff = a2 - Vec2d(double(turned.x), double(turned.y)) / double(kUnit);
  t.t = {std::llround(diff.x()) * kUnit, std::llround(diff.y()) * kUnit};
  return c == e ? t : t.inverse();
}

Transition LatticeMap::transition(CornerId c) const {
  const CornerId o = topo_.opposite(c);
  Transition t;
  t.r = rot_[c];
  t.t = at(prevCorner(o)) - rotate(at(nextCorner(c)), t.r);
  return t;
}

// Gives the corners of v's fan values that the seed transitions carry exactly from the first;
// around an interior vertex whose transitions turn (a cone), the first value is the fixed point
// of their composition, so the fan closes.
void LatticeMap::closeFan(VertexId v, std::uint64_t& open) {
  const CornerId first = topo_.vertexCorner(v);
  if (first == kInvalidId) return;
  bool seams = false;  // no seam at v: nothing to close
  topo_.forEachCornerAround(v, [&](CornerId c) {
    seams |= topo_.opposite(nextCorner(c)) != kInvalidId && isSeam(nextCorner(c));
  });
  if (!seams) return;
  const bool interior = !topo_.isBoundaryVertex(v);
  auto propagate = [&](Point start, bool write) {
    Transition total;  // chart of `first` -> chart of the current corner
    CornerId c = first;
    Point value = start;
    while (true) {
      if (write) value_[map_.wedge(c)] = value;
      const CornerId next = topo_.ccw(c);
      if (next == kInvalidId) break;
      const Transition step = seedTransition(nextCorner(c));
      total = step.after(total);
      value = step.apply(value);
      if (next == first) break;
      c = next;
    }
    return total;
  };
  Point start = value_[map_.wedge(first)];
  if (interior) {
    const Transition h = propagate(start, false);
    if (h.r == 0 && h.t != Point{}) ++open;
    if (h.r != 0) {  // the fixed point of q -> i^r q + t: t / (1 - i^r)
      const Point t = h.t;
      if (h.r == 1) start = {(t.x - t.y) / 2, (t.x + t.y) / 2};
      else if (h.r == 2) start = {t.x / 2, t.y / 2};
      else start = {(t.x + t.y) / 2, (t.y - t.x) / 2};
    }
  }
  propagate(start, true);
  if (!interior) return;
  // A corner whose wedge got two values (wedges shared across a seam) leaves the fan open.
  double angle = 0.0;
  bool consistent = true;
  CornerId c = first;
  do {
    const Point q = at(c), a = at(nextCorner(c)) - q, b = at(prevCorner(c)) - q;
    angle += std::atan2(double(cross(a, b)), double(dot(a, b)));
    const CornerId next = topo_.ccw(c);
    if (seedTransition(nextCorner(c)).apply(q) != at(next)) consistent = false;
    c = next;
  } while (c != first);
  if (!consistent) ++open;
  const long turns = std::lround((2.0 * M_PI - angle) / (0.5 * M_PI));
  if (turns != 0 && std::abs(2.0 * M_PI - angle - 0.5 * M_PI * double(turns)) < 0.25) {
    cone_[v] = static_cast<std::int8_t>(std::max(-127L, std::min(127L, turns)));
  }
}

}  // namespace seamvox::quads
