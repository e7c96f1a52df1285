#pragma once
/// The map of quad extraction on a fixed-point lattice (2^-20 grid units): exact integer
/// predicates on its points, and a copy of the map snapped to the lattice and made exactly
/// seamless there (every seam transition maps one side's corners onto the other's, cones sit on
/// the fixed points of their fans' rotations), so that each integer point is found once.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/quads/extract.h"

namespace seamvox::quads {

constexpr int kFractionBits = 20;
constexpr std::int64_t kUnit = std::int64_t(1) << kFractionBits;  ///< one grid unit
/// Coordinates beyond this many grid units are refused (products then fit 128 bits).
constexpr double kMaxCoordinate = double(std::int64_t(1) << 30);

struct Point {
  std::int64_t x = 0, y = 0;
  bool operator==(const Point& o) const { return x == o.x && y == o.y; }
  bool operator!=(const Point& o) const { return !(*this == o); }
  Point operator-(const Point& o) const { return {x - o.x, y - o.y}; }
  Point operator+(const Point& o) const { return {x + o.x, y + o.y}; }
};

inline __int128 cross(Point a, Point b) { return __int128(a.x) * b.y - __int128(a.y) * b.x; }
inline __int128 dot(Point a, Point b) { return __int128(a.x) * b.x + __int128(a.y) * b.y; }
/// Twice the signed area of (a, b, c): > 0 counter-clockwise.
inline __int128 orient(Point a, Point b, Point c) { return cross(b - a, c - a); }
inline int sign(__int128 x) { return (x > 0) - (x < 0); }
inline std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
inline __int128 floorDiv128(__int128 a, __int128 b) {
  const __int128 q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
/// p turned by k quarter turns counter-clockwise (multiplied by i^k).
inline Point rotate(Point p, int k) {
  switch (k & 3) {
    case 0: return p;
    case 1: return {-p.y, p.x};
    case 2: return {-p.x, -p.y};
    default: return {p.y, -p.x};
  }
}
/// Axis directions, counter-clockwise: 0 = +u, 1 = +v, 2 = -u, 3 = -v.
inline Point direction(std::uint8_t d) { return rotate(Point{1, 0}, d); }
inline std::uint8_t rotateDir(std::uint8_t d, int k) { return static_cast<std::uint8_t>((d + k) & 3); }

/// q -> i^r q + t: from one face's chart to its neighbour's across an edge.
struct Transition {
  int r = 0;
  Point t;
  Point apply(Point p) const { return rotate(p, r) + t; }
  Transition inverse() const { return {(4 - r) & 3, rotate(Point{-t.x, -t.y}, (4 - r) & 3)}; }
  /// this after first: q -> this(first(q))
  Transition after(const Transition& first) const { return {(r + first.r) & 3, apply(first.t)}; }
};

/// The snapped, exactly seamless map. About 1 byte per corner and 16 per wedge.
class LatticeMap {
 public:
  /// Throws InputError for coordinates beyond kMaxCoordinate or that are not finite.
  LatticeMap(const TriangleMesh& mesh, const Topology& topology, std::int64_t scale);
  Point at(CornerId c) const { return value_[map_.wedge(c)]; }
  /// From the chart of c's face to the opposite face's across c's edge (c not on the boundary).
  Transition transition(CornerId c) const;
  /// Index of the cone at v in quarter turns (0: no cone).
  int coneIndex(VertexId v) const { return cone_[v]; }
  std::uint32_t numCones() const { return cones_; }
  /// Lattice units between iso-lines (scale * kUnit).
  std::int64_t gridStep() const { return step_; }
  /// Snap, open fans, flips, translations off the scale (the other fields are left 0).
  const QuadStats& stats() const { return stats_; }

 private:
  /// Whether the two sides of c's (interior) edge have different wedges.
  bool isSeam(CornerId c) const;
  Transition seedTransition(CornerId c) const;
  void closeFan(VertexId v, std::uint64_t& open);

  const TriangleMesh& mesh_;
  const Topology& topo_;
  const WedgeMap& map_;
  std::int64_t step_;
  std::vector<Point> value_;          // per wedge
  std::vector<std::uint8_t> rot_;     // per corner: quarter turns across its edge
  std::vector<std::int8_t> cone_;     // per vertex
  std::uint32_t cones_ = 0;
  QuadStats stats_;
};

}  // namespace seamvox::quads
