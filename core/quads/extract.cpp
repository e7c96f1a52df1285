#include "core/quads/extract.h"

#include <algorithm>
#include <map>
#include <atomic>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "core/quads/lattice.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

using namespace quads;

// Where a grid vertex lies on the map. Edge points are named by their edge's smaller corner and
// their parameter t = num / den (reduced, den > 0) from vertex(next e) to vertex(prev e).
enum class Where : std::uint8_t { Vertex, Edge, Face };

struct PointKey {
  std::uint64_t head;  // where << 62 | id
  std::int64_t a, b;   // Face: lattice point; Edge: t = a / b; Vertex: 0, 0
  bool operator==(const PointKey& o) const { return head == o.head && a == o.a && b == o.b; }
};
struct PointKeyHash {
  static std::uint64_t mix(std::uint64_t x) {  // splitmix64's finalizer
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  }
  std::size_t operator()(const PointKey& k) const {
    return static_cast<std::size_t>(
        mix(k.head ^ mix(static_cast<std::uint64_t>(k.a) ^ mix(static_cast<std::uint64_t>(k.b)))));
  }
};
PointKey vertexKey(VertexId v) { return {(std::uint64_t(Where::Vertex) << 62) | v, 0, 0}; }
PointKey faceKey(FaceId f, Point p) { return {(std::uint64_t(Where::Face) << 62) | f, p.x, p.y}; }
PointKey edgeKey(CornerId e, std::int64_t num, std::int64_t den) {
  const std::int64_t g = std::gcd(num, den);
  return {(std::uint64_t(Where::Edge) << 62) | e, num / g, den / g};
}

struct GridVertex {
  Where where;
  bool xOnGrid, yOnGrid;  // in the chart of the owner (Edge: face of the edge's corner)
  std::uint32_t id;       // vertex, edge corner or face
  std::int64_t a, b;      // as in PointKey
};

// An iso-line direction leaving a grid vertex into a face (dir 0..3 in that face's chart), or
// the boundary: kOut along the boundary with the surface on the left, kIn back along it.
constexpr std::uint8_t kOut = 4, kIn = 5;
struct Port {
  FaceId face;
  std::uint8_t dir;
  std::int32_t turn = 0;  // at a mesh vertex: direction in quarter turns around its unfolded fan
};

// Signed angle from a to b.
double angleBetween(Point a, Point b) { return std::atan2(double(cross(a, b)), double(dot(a, b))); }
// Whether axis direction v lies in the half-open sector [a, b) turning counter-clockwise (< pi).
bool inSector(Point a, Point b, Point v) {
  const __int128 ca = cross(a, v);
  return (ca > 0 || (ca == 0 && dot(a, v) > 0)) && cross(v, b) > 0;
}

constexpr std::uint32_t kNone = 0xFFFFFFFFu;
// A port whose iso-line ends at a cone of index 2 halfway to the next integer point: past the
// cone the line comes back onto itself (the point one step ahead is the start turned by pi about
// the cone), so the port has no edge, and the cell around the cone is a triangle.
constexpr std::uint32_t kDeadEnd = 0xFFFFFFFEu;
constexpr int kMaxTraceSteps = 1 << 16;
constexpr std::uint32_t kMaxFaceDegree = 1024;

class Extractor {
 public:
  Extractor(const TriangleMesh& mesh, const Topology& topology, const QuadOptions& options)
      : mesh_(mesh), topo_(topology), options_(options), map_(mesh, topology, options.scale) {
    G_ = map_.gridStep();
  }

  QuadResult run() {
    QuadResult out;
    out.stats = map_.stats();
    findPoints();
    reportProgress(options_.progress, "quads", 0.3);
    makePorts();
    traceAll(out.stats);
    reportProgress(options_.progress, "quads", 0.7);
    linkBoundaries(out.stats);
    buildFaces(out);
    reportProgress(options_.progress, "quads", 1.0);
    return out;
  }

 private:
  // ---- grid vertices ----

  std::uint32_t addPoint(const PointKey& key, const GridVertex& v) {
    const auto [it, inserted] = index_.emplace(key, static_cast<std::uint32_t>(points_.size()));
    if (inserted) points_.push_back(v);
    return it->second;
  }

  bool onGrid(std::int64_t x) const { return x % G_ == 0; }

  // Integer points on mesh vertices (both coordinates on the grid), boundary vertices where one
  // iso-line meets the boundary, and cones of negative index halfway between two integer points
  // on an iso-line: rounding puts a cone of index -2 at t / 2, and the lines through it fan out
  // to 3 integer points, so the cone is a vertex of valence (4 - k) / 2 between pentagons.
  void findVertexPoints() {
    for (VertexId v = 0; v < topo_.numVertices(); ++v) {
      const CornerId c = topo_.vertexCorner(v);
      if (c == kInvalidId) continue;
      const Point q = map_.at(c);
      const bool x = onGrid(q.x), y = onGrid(q.y);
      if ((x && y) || ((x || y) && (topo_.isBoundaryVertex(v) || map_.coneIndex(v) < 0))) {
        addPoint(vertexKey(v), {Where::Vertex, x, y, v, 0, 0});
      }
    }
  }

  // Points strictly inside edge e (from A to B) whose coordinate `axis` is on the grid: the
  // parameters t = num / den along the edge.
  void gridCrossings(Point A, Point B, int axis, std::vector<std::pair<std::int64_t, std::int64_t>>& out) const {
    const std::int64_t a = axis == 0 ? A.x : A.y, b = axis == 0 ? B.x : B.y;
    if (a == b) return;
    const std::int64_t lo = std::min(a, b), hi = std::max(a, b);
    for (std::int64_t k = floorDiv(lo, G_) + 1; k * G_ < hi; ++k) {
      std::int64_t num = k * G_ - a, den = b - a;
      if (den < 0) num = -num, den = -den;
      out.emplace_back(num, den);
    }
  }

  void findEdgePoints() {
    std::vector<std::pair<std::int64_t, std::int64_t>> ts;
    for (CornerId e = 0; e < topo_.numCorners(); ++e) {
      const CornerId o = topo_.opposite(e);
      if (o != kInvalidId && o < e) continue;
      const Point A = map_.at(nextCorner(e)), B = map_.at(prevCorner(e));
      ts.clear();
      gridCrossings(A, B, 0, ts);
      gridCrossings(A, B, 1, ts);
      for (const auto& [num, den] : ts) {
        // The point A + (B - A) t, exact when its coordinate is on the grid.
        const __int128 px = __int128(A.x) * den + __int128(B.x - A.x) * num;
        const __int128 py = __int128(A.y) * den + __int128(B.y - A.y) * num;
        const bool x = px % (__int128(G_) * den) == 0, y = py % (__int128(G_) * den) == 0;
        if (o != kInvalidId && !(x && y)) continue;  // inside: integer points only
        addPoint(edgeKey(e, num, den), {Where::Edge, x, y, e, 0, 0});
      }
    }
  }

  void findFacePoints() {
    for (FaceId f = 0; f < topo_.numFaces(); ++f) {
      const Point q0 = map_.at(3 * f), q1 = map_.at(3 * f + 1), q2 = map_.at(3 * f + 2);
      const __int128 area = orient(q0, q1, q2);
      const std::int64_t x0 = floorDiv(std::min({q0.x, q1.x, q2.x}), G_) + 1;
      const std::int64_t x1 = floorDiv(std::max({q0.x, q1.x, q2.x}) - 1, G_);
      const std::int64_t y0 = floorDiv(std::min({q0.y, q1.y, q2.y}), G_) + 1;
      const std::int64_t y1 = floorDiv(std::max({q0.y, q1.y, q2.y}) - 1, G_);
      for (std::int64_t i = x0; i <= x1; ++i) {
        for (std::int64_t j = y0; j <= y1; ++j) {
          const Point p{i * G_, j * G_};
          const int s = sign(orient(q0, q1, p)), t = sign(orient(q1, q2, p)), u = sign(orient(q2, q0, p));
          if (area > 0 && s > 0 && t > 0 && u > 0) {
            addPoint(faceKey(f, p), {Where::Face, true, true, f, p.x, p.y});
          } else if (area < 0 && s < 0 && t < 0 && u < 0) {
            ++pointsInFlipped_;
          }
        }
      }
    }
  }

  void findPoints() {
    // About one integer point per unit of parameter area, plus those on the boundary.
    double area = 0.0;
    for (FaceId f = 0; f < topo_.numFaces(); ++f) {
      area += std::abs(double(orient(map_.at(3 * f), map_.at(3 * f + 1), map_.at(3 * f + 2))));
    }
    const double cells = 0.5 * area / (double(G_) * double(G_));
    index_.reserve(static_cast<std::size_t>(1.1 * cells) + topo_.numFaces() / 64 + 16);
    points_.reserve(index_.bucket_count());
    findVertexPoints();
    findEdgePoints();
    findFacePoints();
    for (const auto& [key, i] : index_) {
      if (points_[i].where == Where::Edge) points_[i].a = key.a, points_[i].b = key.b;
    }
  }

  // ---- ports ----

  // Directions of corner c's sector [a, b) (c's face counter-clockwise) through a point whose
  // coordinates are on the grid as told, in counter-clockwise order; `openStart` excludes a.
  void sectorDirections(Point a, Point b, bool halfPlane, bool openStart, bool xOn, bool yOn,
                        FaceId f, std::vector<Port>& out) const {
    std::uint8_t found[4];
    int n = 0;
    for (std::uint8_t d = 0; d < 4; ++d) {
      if (!(d % 2 == 0 ? yOn : xOn)) continue;  // the iso-line along d must be on the grid
      const Point v = direction(d);
      const __int128 ca = cross(a, v);
      const bool startOk = ca > 0 || (!openStart && ca == 0 && dot(a, v) > 0);
      const bool endOk = halfPlane ? true : cross(v, b) > 0;
      if (halfPlane && ca == 0 && dot(a, v) < 0) continue;
      if (startOk && endOk) found[n++] = d;
    }
    std::sort(found, found + n, [](std::uint8_t p, std::uint8_t q) {
      return cross(direction(p), direction(q)) > 0;
    });
    for (int k = 0; k < n; ++k) out.push_back({f, found[k]});
  }

  bool isPositive(FaceId f) const {
    return orient(map_.at(3 * f), map_.at(3 * f + 1), map_.at(3 * f + 2)) > 0;
  }

  bool isPositiveFan(VertexId w) const {
    bool positive = true;
    topo_.forEachCornerAround(w, [&](CornerId c) { positive = positive && isPositive(cornerFace(c)); });
    return positive;
  }

  void portsOf(const GridVertex& v, std::vector<Port>& out) const {
    if (v.where == Where::Face) {
      for (std::uint8_t d = 0; d < 4; ++d) out.push_back({v.id, d});
      return;
    }
    if (v.where == Where::Edge) {
      const CornerId e = v.id, o = topo_.opposite(e);
      const bool boundary = o == kInvalidId;
      if (boundary) out.push_back({cornerFace(e), kOut});
      for (const CornerId s : {e, o}) {
        if (s == kInvalidId || !isPositive(cornerFace(s))) continue;
        const Point a = map_.at(prevCorner(s)) - map_.at(nextCorner(s));
        bool xOn = v.xOnGrid, yOn = v.yOnGrid;
        if (s != e && map_.transition(e).r % 2 == 1) std::swap(xOn, yOn);
        sectorDirections(a, Point{-a.x, -a.y}, true, boundary, xOn, yOn, cornerFace(s), out);
      }
      if (boundary) out.push_back({cornerFace(e), kIn});
      return;
    }
    vertexPorts(v.id, out);
  }

  // The fan of vertex w unfolded into one plane (transitions composed, angles added from the
  // first corner): visit(c, a, b, turned) for every corner c with its two edges a, b in its own
  // chart and the unfolded angle of a. Returns the fan's total angle.
  template <class F>
  double walkUnfoldedFan(VertexId w, F&& visit) const {
    double turned = 0.0, start = 0.0;
    bool firstCorner = true;
    topo_.forEachCornerAround(w, [&](CornerId c) {
      const Point q = map_.at(c), a = map_.at(nextCorner(c)) - q, b = map_.at(prevCorner(c)) - q;
      if (firstCorner) start = turned = std::atan2(double(a.y), double(a.x));
      visit(c, a, b, turned);
      turned += angleBetween(a, b);
      firstCorner = false;
    });
    return turned - start;
  }
  static std::int32_t quarterTurns(double angle) {
    return static_cast<std::int32_t>(std::lround(angle / (0.5 * M_PI)));
  }

  // The directions out of a mesh vertex, by their unfolded angle in quarter turns. Every corner's
  // sector covers the quarter turns from its first edge to its second, counted negatively in a
  // flipped triangle, so each direction out of the vertex is covered once net, folds or not, and
  // a cone of index k has 4 - k of them (QEx's approach).
  template <class F>
  void forEachSectorDirection(VertexId w, F&& visit) const {
    const bool boundary = topo_.isBoundaryVertex(w);
    const CornerId first = topo_.vertexCorner(w);
    walkUnfoldedFan(w, [&](CornerId c, Point a, Point b, double turned) {
      const Point q = map_.at(c);
      const int orientation = sign(cross(a, b));
      for (std::uint8_t d = 0; d < 4; ++d) {
        const Point v = direction(d);
        if (!(d % 2 == 0 ? onGrid(q.y) : onGrid(q.x))) continue;  // its iso-line is off the grid
        int weight = 0;
        if (orientation > 0 && inSector(a, b, v)) weight = 1;
        if (orientation < 0 && inSector(b, a, v)) weight = -1;
        if (weight == 0 || (boundary && c == first && cross(a, v) == 0)) continue;
        visit(c, d, quarterTurns(turned + angleBetween(a, v)), weight);
      }
    });
  }

  void vertexPorts(VertexId w, std::vector<Port>& out) const {
    const bool boundary = topo_.isBoundaryVertex(w);
    CornerId last = topo_.vertexCorner(w);
    if (boundary) out.push_back({cornerFace(last), kOut});
    const std::size_t begin = out.size();
    std::vector<std::pair<std::int32_t, int>> net;  // (turn, weight)
    forEachSectorDirection(w, [&](CornerId c, std::uint8_t d, std::int32_t turn, int weight) {
      net.emplace_back(turn, weight);
      if (weight > 0) out.push_back({cornerFace(c), d, turn});
    });
    topo_.forEachCornerAround(w, [&](CornerId c) { last = c; });
    // Keep the first positive occurrence of each direction covered net once.
    std::sort(out.begin() + begin, out.end(), [](const Port& p, const Port& q) { return p.turn < q.turn; });
    auto netOf = [&](std::int32_t turn) {
      int sum = 0;
      for (const auto& [t, w] : net) sum += t == turn ? w : 0;
      return sum;
    };
    std::size_t kept = begin;
    for (std::size_t i = begin; i < out.size(); ++i) {
      if (kept > begin && out[kept - 1].turn == out[i].turn) continue;
      if (netOf(out[i].turn) > 0) out[kept++] = out[i];
    }
    out.resize(kept);
    if (boundary) out.push_back({cornerFace(last), kIn});
  }

  void makePorts() {
    portStart_.assign(points_.size() + 1, 0);
    std::vector<Port> local;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      local.clear();
      portsOf(points_[i], local);
      portStart_[i + 1] = portStart_[i] + static_cast<std::uint32_t>(local.size());
      ports_.insert(ports_.end(), local.begin(), local.end());
      portVertex_.insert(portVertex_.end(), local.size(), static_cast<std::uint32_t>(i));
    }
    portTarget_.assign(ports_.size(), kNone);
  }

  std::uint32_t findPort(std::uint32_t v, FaceId f, std::uint8_t d) const {
    for (std::uint32_t p = portStart_[v]; p < portStart_[v + 1]; ++p) {
      if (ports_[p].face == f && ports_[p].dir == d) return p;
    }
    return kNone;
  }

  CornerId cornerAt(FaceId f, VertexId w) const {
    for (int k = 0; k < 3; ++k) {
      if (topo_.vertex(3 * f + k) == w) return 3 * f + k;
    }
    return kInvalidId;
  }

  // The port of grid vertex v that leaves into face f along direction d, where (f, d) may name a
  // direction on the border of two sectors, which belongs to the neighbouring face.
  std::uint32_t arrivalPort(std::uint32_t v, FaceId f, std::uint8_t d) const {
    std::uint32_t p = findPort(v, f, d);
    if (p != kNone) return p;
    const GridVertex& g = points_[v];
    if (g.where == Where::Edge) {
      const CornerId e = g.id, o = topo_.opposite(e);
      if (o == kInvalidId) return kNone;
      const CornerId s = cornerFace(e) == f ? e : o;
      return findPort(v, cornerFace(topo_.opposite(s)), rotateDir(d, map_.transition(s).r));
    }
    if (g.where != Where::Vertex) return kNone;
    // Any corner's direction: the port of the same unfolded direction.
    std::int32_t turn = 0, period = 0;  // around an interior vertex, turns repeat after the fan's
    bool found = false;
    unfoldedTurn(g.id, f, d, turn, period, found);
    if (!found) return kNone;
    for (std::uint32_t q = portStart_[v]; q < portStart_[v + 1]; ++q) {
      if (ports_[q].dir >= 4) continue;
      const std::int32_t diff = ports_[q].turn - turn;
      if (diff == 0 || (period > 0 && diff % period == 0)) return q;
    }
    return kNone;
  }

  // The unfolded direction (forEachSectorDirection) of direction d in face f at vertex w, whether
  // or not f's sector holds it; period: the fan's quarter turns around an interior vertex, or 0.
  void unfoldedTurn(VertexId w, FaceId f, std::uint8_t d, std::int32_t& turn, std::int32_t& period,
                    bool& found) const {
    found = false;
    const double total = walkUnfoldedFan(w, [&](CornerId c, Point a, Point, double turned) {
      if (cornerFace(c) != f || found) return;
      found = true;
      turn = quarterTurns(turned + angleBetween(a, direction(d)));
    });
    period = topo_.isBoundaryVertex(w) ? 0 : quarterTurns(total);
  }

  // ---- tracing ----

  // Where point p of face f's chart lies (p in the closed, positive triangle).
  PointKey locate(FaceId f, Point p) const {
    for (int k = 0; k < 3; ++k) {
      if (map_.at(3 * f + k) == p) return vertexKey(topo_.vertex(3 * f + k));
    }
    for (int k = 0; k < 3; ++k) {
      CornerId c = 3 * f + k;
      if (orient(map_.at(nextCorner(c)), map_.at(prevCorner(c)), p) != 0) continue;
      const CornerId o = topo_.opposite(c);
      if (o != kInvalidId && o < c) p = map_.transition(c).apply(p), c = o;
      const Point A = map_.at(nextCorner(c)), B = map_.at(prevCorner(c));
      std::int64_t num, den;
      if (A.x != B.x) num = p.x - A.x, den = B.x - A.x;
      else num = p.y - A.y, den = B.y - A.y;
      if (den < 0) num = -num, den = -den;
      return edgeKey(c, num, den);
    }
    return faceKey(f, p);
  }

  // Start of the iso-line of port p: its face, the target point one grid step ahead (the next
  // grid value along the line) in that face's chart.
  bool startOf(std::uint32_t v, const Port& port, Point& target) const {
    const GridVertex& g = points_[v];
    const std::uint8_t d = port.dir;
    const bool alongX = d % 2 == 0;
    const int sgn = d < 2 ? 1 : -1;
    __int128 sNum, sDen = 1;  // coordinate along the line, rational
    std::int64_t perp;
    if (g.where == Where::Face) {
      sNum = alongX ? g.a : g.b;
      perp = alongX ? g.b : g.a;
    } else if (g.where == Where::Vertex) {
      const Point q = map_.at(cornerAt(port.face, g.id));
      sNum = alongX ? q.x : q.y;
      perp = alongX ? q.y : q.x;
    } else {
      CornerId e = g.id;
      const Point A = map_.at(nextCorner(e)), B = map_.at(prevCorner(e));
      __int128 px = __int128(A.x) * g.b + __int128(B.x - A.x) * g.a;
      __int128 py = __int128(A.y) * g.b + __int128(B.y - A.y) * g.a;
      sDen = g.b;
      if (cornerFace(e) != port.face) {  // an interior edge's point: integer, moved to the other side
        const Point p = map_.transition(e).apply(Point{std::int64_t(px / g.b), std::int64_t(py / g.b)});
        px = p.x, py = p.y, sDen = 1;
      }
      sNum = alongX ? px : py;
      const __int128 pp = alongX ? py : px;
      if (pp % sDen != 0) return false;
      perp = static_cast<std::int64_t>(pp / sDen);
    }
    if (perp % G_ != 0) return false;
    // next multiple of G strictly ahead of sNum / sDen
    const __int128 step = __int128(G_) * sDen;
    __int128 k = floorDiv128(sNum, step);
    const std::int64_t next = static_cast<std::int64_t>(sgn > 0 ? (k + 1) * G_
                                                                : ((sNum % step == 0 ? k : k + 1) - 1) * G_);
    target = alongX ? Point{next, perp} : Point{perp, next};
    return true;
  }

  // Left of the line through e along d: > 0 left, < 0 right.
  static std::int64_t leftOf(std::uint8_t d, Point p, Point e) {
    switch (d) {
      case 0: return p.y - e.y;
      case 1: return e.x - p.x;
      case 2: return e.y - p.y;
      default: return p.x - e.x;
    }
  }

  // Moves (f, d, target) across the edge of corner c into the opposite face.
  void crossEdge(CornerId c, FaceId& f, std::uint8_t& d, Point& target) const {
    const Transition t = map_.transition(c);
    target = t.apply(target);
    d = rotateDir(d, t.r);
    f = cornerFace(topo_.opposite(c));
  }

  // Continues a line through vertex corner c straight on: the face around the vertex whose sector
  // holds d. False when none does (boundary) or the vertex is a cone.
  bool passVertex(CornerId c, FaceId& f, std::uint8_t& d, Point& target) const {
    for (int way = 0; way < 2; ++way) {
      CornerId cur = c;
      FaceId g = f;
      std::uint8_t dd = d;
      Point tt = target;
      for (std::uint32_t n = 0; n < kMaxFaceDegree; ++n) {
        const CornerId edge = way == 0 ? nextCorner(cur) : prevCorner(cur);
        if (topo_.opposite(edge) == kInvalidId) break;
        crossEdge(edge, g, dd, tt);
        cur = way == 0 ? nextCorner(topo_.opposite(edge)) : prevCorner(topo_.opposite(edge));
        if (cur == c) return false;
        if (!isPositive(g)) continue;
        const Point q = map_.at(cur), a = map_.at(nextCorner(cur)) - q, b = map_.at(prevCorner(cur)) - q;
        const Point v = direction(dd);
        const __int128 ca = cross(a, v);
        if ((ca > 0 || (ca == 0 && dot(a, v) > 0)) && cross(v, b) > 0) {
          f = g, d = dd, target = tt;
          return true;
        }
      }
    }
    return false;
  }

  // Traces port p to the grid vertex one step along its iso-line (or to the boundary); the port
  // it arrives by, or kNone.
  std::uint32_t trace(std::uint32_t v, std::uint32_t p) const {
    const Port& port = ports_[p];
    if (port.dir >= 4) return kNone;
    Point target;
    if (!startOf(v, port, target)) return kNone;
    FaceId f = port.face;
    std::uint8_t d = port.dir;
    int entry = -1;  // local corner of the edge the line came in by (-1: unknown)
    for (int step = 0; step < kMaxTraceSteps; ++step) {
      const Point q[3] = {map_.at(3 * f), map_.at(3 * f + 1), map_.at(3 * f + 2)};
      const int orientation = sign(orient(q[0], q[1], q[2]));
      if (orientation == 0 && entry < 0) return kNone;  // zero area: crossed like a fold, below
      if (orientation > 0 && orient(q[0], q[1], target) >= 0 && orient(q[1], q[2], target) >= 0 &&
          orient(q[2], q[0], target) >= 0) {
        const auto it = index_.find(locate(f, target));
        if (it == index_.end()) return kNone;
        return arrivalPort(it->second, f, rotateDir(d, 2));
      }
      const std::int64_t s[3] = {leftOf(d, q[0], target), leftOf(d, q[1], target), leftOf(d, q[2], target)};
      int zeros = 0, zero = -1, nonzero = -1;
      for (int k = 0; k < 3; ++k) (s[k] == 0 ? (++zeros, zero = k) : nonzero = k);
      int exitEdge = -1, exitVertex = -1;  // local corner naming the exit edge, or the vertex
      if (orientation <= 0 || (entry >= 0 && zeros == 0)) {
        // A flipped or zero-area triangle (a fold), or one entered by an edge: out by the other edge
        // the line crosses, which keeps the walk going through folds (QEx's local tracing).
        if (entry < 0 || zeros > 0) return kNone;
        for (int k = 0; k < 3; ++k) {
          if (k != entry && (s[(k + 1) % 3] < 0) != (s[(k + 2) % 3] < 0)) exitEdge = k;
        }
      } else if (zeros == 0) {
        for (int k = 0; k < 3; ++k) {
          if (s[k] < 0 && s[(k + 1) % 3] > 0) exitEdge = (k + 2) % 3;
        }
      } else if (zeros == 1) {
        const std::int64_t s1 = s[(zero + 1) % 3], s2 = s[(zero + 2) % 3];
        if (s1 < 0 && s2 > 0) exitEdge = zero;
        else if (s1 > 0 && s2 < 0) exitVertex = zero;
      } else if (zeros == 2) {  // along an edge: out through its far end
        const int k1 = (nonzero + 1) % 3, k2 = (nonzero + 2) % 3;
        const Point dv = direction(d);
        exitVertex = dot(dv, q[k1]) > dot(dv, q[k2]) ? k1 : k2;
      }
      entry = -1;
      if (exitEdge >= 0) {
        const CornerId c = 3 * f + exitEdge;
        if (topo_.opposite(c) == kInvalidId) {
          return boundaryArrival(c, f, d, target);
        }
        crossEdge(c, f, d, target);
        entry = static_cast<int>(topo_.opposite(c) % 3);
      } else if (exitVertex >= 0) {
        const CornerId c = 3 * f + exitVertex;
        const VertexId w = topo_.vertex(c);
        // A vertex on the line that is a grid vertex itself (a boundary vertex, or a cone between
        // integer points) ends the edge there: its own ports carry the line on. Not through a
        // fold: directions into a fan with flipped triangles do not name one port.
        if (const auto it = index_.find(vertexKey(w)); it != index_.end() && isPositiveFan(w)) {
          return arrivalPort(it->second, f, rotateDir(d, 2));
        }
        if (map_.coneIndex(w) == 2) {
          const Point half = target - map_.at(c);
          if (std::abs(half.x) + std::abs(half.y) == G_ / 2) return kDeadEnd;
        }
        if (map_.coneIndex(w) != 0) return kNone;  // through another cone: not followed
        if (!passVertex(c, f, d, target)) {
          if (!topo_.isBoundaryVertex(w)) return kNone;
          const auto it = index_.find(vertexKey(w));
          if (it == index_.end()) return kNone;
          return arrivalPort(it->second, f, rotateDir(d, 2));
        }
      } else {
        return kNone;
      }
    }
    return kNone;
  }

  // The point where the line (target, d) leaves face f through boundary edge c.
  std::uint32_t boundaryArrival(CornerId c, FaceId f, std::uint8_t d, Point target) const {
    const Point A = map_.at(nextCorner(c)), B = map_.at(prevCorner(c));
    const bool alongX = d % 2 == 0;  // the line is y = target.y (alongX) or x = target.x
    std::int64_t num = alongX ? target.y - A.y : target.x - A.x;
    std::int64_t den = alongX ? B.y - A.y : B.x - A.x;
    if (den == 0) return kNone;
    if (den < 0) num = -num, den = -den;
    const auto it = index_.find(edgeKey(c, num, den));
    if (it == index_.end()) return kNone;
    return arrivalPort(it->second, f, rotateDir(d, 2));
  }

  void traceAll(QuadStats& stats) {
    const std::uint64_t n = points_.size();
    std::atomic<std::uint64_t> untraced{0};
    parallelFor(n, 256, [&](const IndexRange& r) {
      std::uint64_t failed = 0;
      for (std::uint64_t v = r.begin(); v < r.end(); ++v) {
        for (std::uint32_t p = portStart_[v]; p < portStart_[v + 1]; ++p) {
          if (ports_[p].dir >= 4) continue;
          portTarget_[p] = trace(static_cast<std::uint32_t>(v), p);
          failed += portTarget_[p] == kNone;
        }
      }
      untraced += failed;
    });
    stats.untracedEdges = untraced;
    for (std::uint32_t p = 0; p < ports_.size(); ++p) {
      if (ports_[p].dir < 4 && portTarget_[p] == kDeadEnd) ++stats.deadEnds;
      if (ports_[p].dir >= 4 || portTarget_[p] >= kDeadEnd) continue;
      ++stats.tracedEdges;
      const std::uint32_t back = portTarget_[p];
      if (ports_[back].dir >= 4 || portTarget_[back] != p) ++stats.unpairedEdges;
    }
    stats.pointsInFlippedFaces = pointsInFlipped_;
    for (const GridVertex& g : points_) {
      if (g.xOnGrid && g.yOnGrid) ++stats.gridVertices;
      else if (g.where == Where::Vertex && !topo_.isBoundaryVertex(g.id)) ++stats.halfwayCones;
      else ++stats.boundaryVertices;
    }
  }

  // ---- boundary ----

  // Boundary half-edges: along every boundary loop, from each point on it to the next.
  void linkBoundaries(QuadStats& stats) {
    // Points on boundary edges, by edge, in order along the edge.
    std::vector<std::uint32_t> onEdges;
    for (std::uint32_t i = 0; i < points_.size(); ++i) {
      if (points_[i].where == Where::Edge && topo_.opposite(points_[i].id) == kInvalidId) onEdges.push_back(i);
    }
    std::sort(onEdges.begin(), onEdges.end(), [&](std::uint32_t i, std::uint32_t j) {
      const GridVertex &a = points_[i], &b = points_[j];
      if (a.id != b.id) return a.id < b.id;
      return __int128(a.a) * b.b < __int128(b.a) * a.b;
    });
    std::vector<std::uint8_t> done(topo_.numCorners(), 0);
    std::vector<std::uint32_t> loop;
    for (CornerId start = 0; start < topo_.numCorners(); ++start) {
      if (topo_.opposite(start) != kInvalidId || done[start]) continue;
      loop.clear();
      CornerId c = start;
      do {
        done[c] = 1;
        const auto it = index_.find(vertexKey(topo_.vertex(nextCorner(c))));
        if (it != index_.end()) loop.push_back(it->second);
        auto lo = std::lower_bound(onEdges.begin(), onEdges.end(), c,
                                   [&](std::uint32_t i, CornerId e) { return points_[i].id < e; });
        for (; lo != onEdges.end() && points_[*lo].id == c; ++lo) loop.push_back(*lo);
        c = prevCorner(topo_.vertexCorner(topo_.vertex(prevCorner(c))));
      } while (c != start && !done[c]);
      if (loop.empty()) {
        ++stats.holesWithoutVertex;
        continue;
      }
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const std::uint32_t from = loop[k], to = loop[(k + 1) % loop.size()];
        portTarget_[portStart_[from]] = portStart_[to + 1] - 1;  // kOut -> kIn
        ++stats.boundaryEdges;
      }
    }
  }

  // ---- faces ----

  Vec3d positionOf(const GridVertex& g) const {
    if (g.where == Where::Vertex) return mesh_.position(g.id);
    if (g.where == Where::Edge) {
      const double t = double(g.a) / double(g.b);
      return (1.0 - t) * mesh_.position(topo_.vertex(nextCorner(g.id))) +
             t * mesh_.position(topo_.vertex(prevCorner(g.id)));
    }
    const FaceId f = g.id;
    const Point p{g.a, g.b}, q0 = map_.at(3 * f), q1 = map_.at(3 * f + 1), q2 = map_.at(3 * f + 2);
    const double area = double(orient(q0, q1, q2));
    const double w0 = double(orient(q1, q2, p)) / area, w1 = double(orient(q2, q0, p)) / area;
    const Triangle& t = mesh_.triangles[f];
    return w0 * mesh_.position(t[0]) + w1 * mesh_.position(t[1]) + (1.0 - w0 - w1) * mesh_.position(t[2]);
  }

  FaceId ownerFace(const GridVertex& g) const {
    if (g.where == Where::Vertex) return cornerFace(topo_.vertexCorner(g.id));
    return g.where == Where::Edge ? cornerFace(g.id) : g.id;
  }

  // Drops edges a -> b -> a that a face walk takes out and back to a vertex b with no other way
  // on: an integer point whose other lines all end at cones of index 2 halfway (a cluster of them
  // around it) or fold back in flipped triangles. Both ends lose the edge (QuadStats::spikes);
  // b, when in no other face, is left out.
  void removeSpikes(std::vector<std::uint32_t>& face, std::vector<std::uint32_t>& facePorts,
                    std::vector<std::uint8_t>& lostAt, QuadStats& stats) const {
    for (std::size_t k = 0; face.size() > 2 && k < face.size();) {
      const std::size_t n = face.size(), before = (k + n - 1) % n, after = (k + 1) % n;
      if (face[before] != face[after]) {
        ++k;
        continue;
      }
      ++lostAt[face[k]];
      ++lostAt[face[after]];
      ++stats.spikes;
      // Keep `before`, drop k and `after` (the same vertex as `before`).
      const std::size_t first = std::min(k, after);
      for (std::size_t i : {std::max(k, after), first}) {
        face.erase(face.begin() + i);
        facePorts.erase(facePorts.begin() + i);
      }
      k = first > 0 ? first - 1 : 0;
    }
  }

  // Drops the loop edges of a face walk (the same vertex twice in a row, cyclically): an
  // iso-line from an integer point back to itself around a cone of index 1 in a cell. The inside
  // of the loop is a one-edge face, left out as a digon; the face outside closes without the loop.
  // The point loses both ends of the loop (QuadStats::loops).
  static void removeLoops(std::vector<std::uint32_t>& face, std::vector<std::uint32_t>& facePorts,
                          std::vector<std::uint8_t>& lostAt, QuadStats& stats) {
    for (std::size_t k = 0; face.size() > 1 && k < face.size();) {
      const std::size_t after = (k + 1) % face.size();
      if (face[k] != face[after]) {
        ++k;
        continue;
      }
      lostAt[face[k]] += 2;
      ++stats.loops;
      face.erase(face.begin() + after);
      facePorts.erase(facePorts.begin() + after);
      if (after < k) k = k - 1;
    }
  }

  // Removes pairs of faces on the same cycle of vertices in opposite orders (QuadStats::pillows)
  // and the vertices only they used; a remaining vertex loses each map edge of a pillow's vertex
  // pairs that the kept faces no longer account for (below).
  // Faces are given by their point ids (face vertices of pm map back through pointOf).
  static void removePillows(PolygonMesh& pm, std::vector<std::uint32_t>& pointOf, std::vector<std::uint8_t>& lostAt,
                            QuadResult& out) {
    const std::uint32_t nf = pm.numFaces();
    // A face's cycle from its smallest vertex, forwards; its reverse likewise.
    const auto canonical = [&](std::uint32_t f, bool reversed) {
      std::vector<std::uint32_t> cycle(pm.faceVertices.begin() + pm.faceStart[f], pm.faceVertices.begin() + pm.faceStart[f + 1]);
      if (reversed) std::reverse(cycle.begin(), cycle.end());
      std::rotate(cycle.begin(), std::min_element(cycle.begin(), cycle.end()), cycle.end());
      return cycle;
    };
    std::map<std::vector<std::uint32_t>, std::uint32_t> open;  // cycles not yet paired
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::uint32_t f = 0; f < nf; ++f) {
      const auto twin = open.find(canonical(f, true));
      if (twin != open.end()) {
        pairs.push_back({twin->second, f});
        open.erase(twin);
      } else {
        open.emplace(canonical(f, false), f);
      }
    }
    if (pairs.empty()) return;
    // A pair is a fold only when it hangs on the rest of the mesh (an edge of it in a third face);
    // a pair alone is a whole closed component of two faces, and stays.
    // The edge from face f's vertex at i to the next one, as a sorted pair.
    const auto edgeOf = [&](std::uint32_t f, std::uint32_t i) {
      const std::uint32_t a = pm.faceVertices[i];
      const std::uint32_t b = pm.faceVertices[i + 1 < pm.faceStart[f + 1] ? i + 1 : pm.faceStart[f]];
      return std::make_pair(std::min(a, b), std::max(a, b));
    };
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> uses;
    for (const auto& [f, g] : pairs) {
      for (std::uint32_t i = pm.faceStart[f]; i < pm.faceStart[f + 1]; ++i) {
        uses[edgeOf(f, i)] = 0;
      }
    }
    for (std::uint32_t f = 0; f < nf; ++f) {
      for (std::uint32_t i = pm.faceStart[f]; i < pm.faceStart[f + 1]; ++i) {
        const auto it = uses.find(edgeOf(f, i));
        if (it != uses.end()) ++it->second;
      }
    }
    std::vector<std::uint8_t> removed(nf, 0);
    for (const auto& [f, g] : pairs) {
      bool attached = false;
      for (std::uint32_t i = pm.faceStart[f]; i < pm.faceStart[f + 1] && !attached; ++i) {
        attached = uses[edgeOf(f, i)] > 2;
      }
      if (!attached) continue;
      removed[f] = removed[g] = 1;
      ++out.stats.pillows;
    }
    if (out.stats.pillows == 0) return;
    // Sides per vertex pair, of all faces and of the kept ones: a pair with 2 k sides stands for k
    // edges of the map. A pillow pair's side whose edge another face keeps may be an edge of its own
    // (a tube two quads around, zipped: two rim edges become one), so an end loses every edge of the
    // pair that the kept faces no longer account for.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::uint32_t, std::uint32_t>> sides;  // all, kept
    PolygonMesh faces;
    faces.faceStart = {0};
    for (std::uint32_t f = 0; f < nf; ++f) {
      const std::uint32_t b = pm.faceStart[f], e = pm.faceStart[f + 1];
      for (std::uint32_t i = b; i < e; ++i) {
        auto& count = sides[edgeOf(f, i)];
        ++count.first;
        count.second += !removed[f];
      }
      if (removed[f]) continue;
      faces.faceVertices.insert(faces.faceVertices.end(), pm.faceVertices.begin() + b, pm.faceVertices.begin() + e);
      faces.faceStart.push_back(static_cast<std::uint32_t>(faces.faceVertices.size()));
    }
    // Vertices still used, renumbered in order.
    std::vector<std::uint32_t> renumber(pm.numVertices(), kNone);
    for (std::uint32_t v : faces.faceVertices) renumber[v] = 0;
    std::uint32_t next = 0;
    for (std::uint32_t v = 0; v < pm.numVertices(); ++v) {
      if (renumber[v] == kNone) continue;
      renumber[v] = next++;
      pm.positions[renumber[v]] = pm.positions[v];
      out.vertexComponent[renumber[v]] = out.vertexComponent[v];
      out.vertexConeIndex[renumber[v]] = out.vertexConeIndex[v];
      pointOf[renumber[v]] = pointOf[v];
    }
    for (const auto& [pair, count] : sides) {
      const auto [all, keptSides] = count;
      if (all == keptSides) continue;  // no pillow side
      const auto [a, b] = pair;
      const std::uint32_t gone = (all + 1) / 2 - (keptSides + 1) / 2;
      for (std::uint32_t v : {a, b}) {
        if (renumber[v] != kNone) lostAt[pointOf[v]] = static_cast<std::uint8_t>(std::min(255u, lostAt[pointOf[v]] + gone));
      }
    }
    pm.positions.resize(next);
    out.vertexComponent.resize(next);
    out.vertexConeIndex.resize(next);
    pointOf.resize(next);
    for (std::uint32_t& v : faces.faceVertices) v = renumber[v];
    pm.faceVertices = std::move(faces.faceVertices);
    pm.faceStart = std::move(faces.faceStart);
  }

  bool leaves(std::uint32_t p) const { return ports_[p].dir != kIn && portTarget_[p] < kDeadEnd; }

  void buildFaces(QuadResult& out) {
    std::vector<std::uint8_t> visited(ports_.size(), 0);
    std::vector<std::uint32_t> newIndex(points_.size(), kNone), face, facePorts;
    std::vector<std::uint8_t> lostAt(points_.size(), 0);
    for (std::uint32_t p = 0; p < ports_.size(); ++p) lostAt[portVertex_[p]] += portTarget_[p] == kDeadEnd;
    for (std::uint32_t v = 0; v < points_.size(); ++v) {  // a cone between integer points
      const GridVertex& g = points_[v];
      if (g.where != Where::Vertex || (g.xOnGrid && g.yOnGrid) || topo_.isBoundaryVertex(g.id)) continue;
      const int directions = 4 - map_.coneIndex(g.id), ports = int(portStart_[v + 1] - portStart_[v]);
      lostAt[v] = static_cast<std::uint8_t>(std::clamp(directions - ports, 0, 255));
    }
    PolygonMesh& pm = out.mesh;
    for (std::uint32_t h = 0; h < ports_.size(); ++h) {
      if (visited[h] || !leaves(h)) continue;
      face.clear();
      facePorts.clear();
      std::uint32_t cur = h;
      bool closed = false;
      while (true) {
        visited[cur] = 1;
        face.push_back(portVertex_[cur]);
        facePorts.push_back(cur);
        const std::uint32_t arrive = portTarget_[cur], v = portVertex_[arrive];
        const std::uint32_t first = portStart_[v], count = portStart_[v + 1] - first;
        if (ports_[first].dir == kOut && arrive == first) break;  // arrived from outside
        std::uint32_t next = arrive;  // the port before, skipping iso-lines that end at cones
        do {
          next = first + (next - first + count - 1) % count;
        } while (portTarget_[next] == kDeadEnd && next != arrive);
        if (next == h) {
          closed = true;
          break;
        }
        if (visited[next] || !leaves(next) || face.size() >= kMaxFaceDegree) break;
        cur = next;
      }
      if (!closed) {
        ++out.stats.openFaces;
        continue;
      }
      if (face.size() > 1) removeLoops(face, facePorts, lostAt, out.stats);
      removeSpikes(face, facePorts, lostAt, out.stats);
      if (face.size() <= 2) {  // two edges between the same points: one edge once this goes
        ++out.stats.digons;
        if (face.size() == 2 && ports_[h].dir < 4 &&
            facePorts.size() == 2 && ports_[facePorts[1]].dir < 4) {
          // Between two iso-lines: a cone of index 2 in a cell. Its two corners lose an edge.
          ++lostAt[face[0]];
          ++lostAt[face[1]];
        }
        continue;
      }
      for (const std::uint32_t v : face) {
        if (newIndex[v] == kNone) {
          newIndex[v] = pm.numVertices();
          pm.positions.push_back(positionOf(points_[v]));
          const GridVertex& g = points_[v];
          out.vertexComponent.push_back(ownerFace(g));  // a face for now; components below
          const int cone = g.where == Where::Vertex ? map_.coneIndex(g.id) : 0;
          out.vertexConeIndex.push_back(static_cast<std::int8_t>(cone));
          out.conesOnGridVertices += cone != 0 && g.xOnGrid && g.yOnGrid;
        }
        pm.faceVertices.push_back(newIndex[v]);
      }
      pm.faceStart.push_back(static_cast<std::uint32_t>(pm.faceVertices.size()));
    }
    std::vector<std::uint32_t> pointOf(pm.numVertices());
    for (std::uint32_t v = 0; v < points_.size(); ++v) {
      if (newIndex[v] != kNone) pointOf[newIndex[v]] = v;
    }
    removePillows(pm, pointOf, lostAt, out);
    out.vertexLostEdges.assign(pm.numVertices(), 0);
    for (std::uint32_t v = 0; v < pm.numVertices(); ++v) out.vertexLostEdges[v] = lostAt[pointOf[v]];
    // Components of the map: per vertex, and those that got no face (islands).
    const ComponentsResult comps = computeComponents(topo_);
    std::vector<std::uint8_t> hasFace(comps.components.size(), 0);
    for (std::uint32_t& c : out.vertexComponent) {
      c = comps.faceComponent[c];
      hasFace[c] = 1;
    }
    for (std::size_t c = 0; c < comps.components.size(); ++c) {
      if (hasFace[c]) continue;
      ++out.stats.islands;
      out.stats.islandFaces += comps.components[c].faces;
    }
    out.cones = map_.numCones();
  }

  const TriangleMesh& mesh_;
  const Topology& topo_;
  const QuadOptions& options_;
  LatticeMap map_;
  std::int64_t G_ = 0;
  std::vector<GridVertex> points_;
  std::unordered_map<PointKey, std::uint32_t, PointKeyHash> index_;
  std::uint64_t pointsInFlipped_ = 0;
  std::vector<std::uint32_t> portStart_, portVertex_, portTarget_;
  std::vector<Port> ports_;
};

}  // namespace

QuadResult extractQuads(const TriangleMesh& mesh, const Topology& topology, const QuadOptions& options) {
  if (!mesh.hasUV()) throw InputError("the mesh has no texture coordinates (u, v); run seamvox param first");
  checkCorners(mesh.cornerUV, 3 * std::size_t(mesh.numFaces()), "quad extraction");
  if (topology.numFaces() != mesh.numFaces()) {
    throw InputError("quad extraction: the topology has " + std::to_string(topology.numFaces()) +
                     " faces, the mesh " + std::to_string(mesh.numFaces()));
  }
  if (options.scale < 1 || options.scale > (1 << 20)) {
    throw InputError("quad extraction: the scale must be from 1 to 2^20, got " + std::to_string(options.scale));
  }
  return Extractor(mesh, topology, options).run();
}

}  // namespace seamvox
