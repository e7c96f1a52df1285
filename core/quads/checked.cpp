#include "core/quads/checked.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/system/errors.h"

namespace seamvox {

namespace {

/// q -> R^r q + t, R a quarter turn: how a chart's (u, v) read in another chart.
struct Rigid {
  int r = 0;
  Vec2d t = Vec2d::Zero();
  static Vec2d turn(const Vec2d& q, int r) {
    switch (r & 3) {
      case 0: return q;
      case 1: return {-q.y(), q.x()};
      case 2: return -q;
      default: return {q.y(), -q.x()};
    }
  }
  Vec2d apply(const Vec2d& q) const { return turn(q, r) + t; }
  Vec2d inverse(const Vec2d& p) const { return turn(p - t, -r); }
  Rigid after(const Rigid& m) const { return {(r + m.r) & 3, turn(m.t, r) + t}; }  // this o m
};

/// A hole to close: its boundary corners in order, each face's chart read in the first's.
struct Hole {
  std::vector<CornerId> corners;
  std::vector<Rigid> chart;
  Vec2d centre = Vec2d::Zero();  // in the first corner's chart
  /// Empty: a fan from the centre. Else triangles over the loop's points (indices into corners,
  /// counter-clockwise in the first chart), for a loop not star-shaped around its centre.
  std::vector<std::array<std::uint32_t, 3>> ears;
};

double cross2(const Vec2d& a, const Vec2d& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Ear clipping of the simple polygon `polygon` (counter-clockwise; at most a few dozen points):
/// triangles of indices, counter-clockwise, or empty when it is not simple enough to clip (no
/// ear left: self-touching or clockwise).
std::vector<std::array<std::uint32_t, 3>> clipEars(const std::vector<Vec2d>& polygon) {
  std::vector<std::uint32_t> left(polygon.size());
  for (std::uint32_t k = 0; k < left.size(); ++k) left[k] = k;
  std::vector<std::array<std::uint32_t, 3>> out;
  while (left.size() > 3) {
    bool clipped = false;
    for (std::size_t k = 0; k < left.size() && !clipped; ++k) {
      const std::uint32_t a = left[(k + left.size() - 1) % left.size()], b = left[k], c = left[(k + 1) % left.size()];
      const Vec2d &pa = polygon[a], &pb = polygon[b], &pc = polygon[c];
      if (!(cross2(pb - pa, pc - pb) > 0.0)) continue;  // reflex or flat
      bool empty = true;
      for (const std::uint32_t q : left) {
        if (q == a || q == b || q == c) continue;
        const Vec2d& x = polygon[q];
        if (cross2(pb - pa, x - pa) >= 0.0 && cross2(pc - pb, x - pb) >= 0.0 && cross2(pa - pc, x - pc) >= 0.0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.push_back({a, b, c});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
    }
    if (!clipped) return {};
  }
  if (!(cross2(polygon[left[1]] - polygon[left[0]], polygon[left[2]] - polygon[left[1]]) > 0.0)) return {};
  out.push_back({left[0], left[1], left[2]});
  return out;
}

/// Points where the lines u = k s or v = k s (s = span) meet the closed polygon `rim`: its
/// vertices on a line (once each) and its edges' crossings between their ends.
std::size_t rimGridPoints(const std::vector<Vec2d>& rim, double span) {
  constexpr double kOnLine = 1e-6;
  const auto onLine = [&](double x) { return std::abs(x / span - std::round(x / span)) < kOnLine; };
  const auto crossings = [&](double a, double b) -> std::size_t {
    const double lo = std::min(a, b) / span, hi = std::max(a, b) / span;
    const double first = std::floor(lo + kOnLine) + 1.0, last = std::ceil(hi - kOnLine) - 1.0;
    return last >= first ? static_cast<std::size_t>(last - first + 1.0) : 0;
  };
  std::size_t points = 0;
  for (std::size_t k = 0; k < rim.size(); ++k) {
    const Vec2d& a = rim[k];
    const Vec2d& b = rim[(k + 1) % rim.size()];
    points += (onLine(a.x()) || onLine(a.y())) + crossings(a.x(), b.x()) + crossings(a.y(), b.y());
  }
  return points;
}

}  // namespace

std::uint64_t fillSmallHoles(const TriangleMesh& mesh, const Topology& topology, std::int64_t scale,
                             TriangleMesh& out, std::uint64_t* translated) {
  constexpr std::size_t kMaxLoop = 32;
  const double span = static_cast<double>(std::max<std::int64_t>(scale, 1));
  const WedgeMap& uv = mesh.cornerUV;
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  std::vector<Hole> holes;
  // A component hardly larger than its loop is an island, not a surface with a hole: left open.
  std::vector<std::uint32_t> component;
  std::vector<BoundingBox> extent;
  auto componentExtent = [&](FaceId f) -> const BoundingBox& {
    if (component.empty()) {
      component = computeComponents(topology).faceComponent;
      for (FaceId g = 0; g < mesh.numFaces(); ++g) {
        if (component[g] >= extent.size()) extent.resize(component[g] + 1);
        for (const VertexId v : mesh.triangles[g]) {
          extent[component[g]].min = extent[component[g]].min.cwiseMin(mesh.position(v));
          extent[component[g]].max = extent[component[g]].max.cwiseMax(mesh.position(v));
        }
      }
    }
    return extent[component[f]];
  };
  Hole hole;
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (topology.opposite(start) != kInvalidId || seen[start]) continue;
    // Walk the loop: the edge of boundary corner c runs vertex(next c) -> vertex(prev c); the next
    // boundary edge leaves vertex(prev c), found by turning around it through interior edges, each
    // crossing read as the rigid map between the two faces' charts (identity off seams).
    hole.corners.clear();
    hole.chart.clear();
    bool closed = false;
    Rigid chart;  // the current face's chart read in the first face's
    CornerId c = start;
    for (std::size_t steps = 0; steps < kMaxLoop + 1; ++steps) {
      seen[c] = 1;
      hole.corners.push_back(c);
      hole.chart.push_back(chart);
      CornerId d = prevCorner(c), e = prevCorner(d);  // d: the corner at the far end vertex
      for (std::size_t turns = 0; topology.opposite(e) != kInvalidId && turns < 4096; ++turns) {
        const CornerId o = topology.opposite(e), d2 = prevCorner(o);
        // Across the edge B -> X of corner e: B at d and d2, X at next(d) and next(o).
        const Vec2d here = uv[nextCorner(d)] - uv[d], there = uv[nextCorner(o)] - uv[d2];
        if (!(here != Vec2d::Zero()) || !(there != Vec2d::Zero())) {
          chart.r = -1;  // a zero-length edge in (u, v): no direction to read the turn from
          break;
        }
        const double angle = std::atan2(there.x() * here.y() - there.y() * here.x(), there.dot(here));
        Rigid m;
        m.r = static_cast<int>(std::lround(angle / (0.5 * M_PI))) & 3;
        m.t = uv[d] - Rigid::turn(uv[d2], m.r);
        chart = chart.after(m);
        d = d2;
        e = prevCorner(d);
      }
      if (chart.r < 0 || topology.opposite(e) != kInvalidId) break;  // not a plain hole
      c = e;
      if (c == start) {
        // The charts come back (no cone inside), or turned (a cone inside or on the loop); back
        // with a translation only (a dislocation), nothing can close the hole.
        closed = chart.r != 0 || chart.t.norm() <= 1e-6;
        if (translated && chart.r == 0 && !closed && hole.corners.size() <= kMaxLoop) ++*translated;
        break;
      }
      if (seen[c]) break;
    }
    if (!closed || hole.corners.size() > kMaxLoop) continue;
    // The loop's points in the first chart: a span below a quad, in a component four times larger.
    std::vector<Vec2d> point, end;  // each rim edge's start and end
    BoundingBox around;
    for (std::size_t k = 0; k < hole.corners.size(); ++k) {
      point.push_back(hole.chart[k].apply(uv[nextCorner(hole.corners[k])]));
      end.push_back(hole.chart[k].apply(uv[prevCorner(hole.corners[k])]));
      around.min = around.min.cwiseMin(mesh.position(topology.vertex(nextCorner(hole.corners[k]))));
      around.max = around.max.cwiseMax(mesh.position(topology.vertex(nextCorner(hole.corners[k]))));
    }
    // Turned: a cone inside, at the turn's fixed point q = R q + t (first chart), or on the rim.
    bool turned = chart.r != 0;
    Vec2d cone = Vec2d::Zero();
    if (turned) {
      const Vec2d x = Rigid::turn(Vec2d(1.0, 0.0), chart.r), y = Rigid::turn(Vec2d(0.0, 1.0), chart.r);
      const double a = 1.0 - x.x(), b = -y.x(), c2 = -x.y(), d = 1.0 - y.y(), det = a * d - b * c2;
      cone = Vec2d(d * chart.t.x() - b * chart.t.y(), a * chart.t.y() - c2 * chart.t.x()) / det;
      // A cone on the rim: read the points before it after the turn, and the loop, from the cone
      // round to it, closes in the first chart (the fill's faces at the cone widen its fan).
      for (std::size_t j = 0; j < point.size() && turned; ++j) {
        if ((point[j] - cone).norm() > 1e-6) continue;
        for (std::size_t k = 0; k < j; ++k) {
          hole.chart[k] = chart.after(hole.chart[k]);
          point[k] = chart.apply(point[k]);
          end[k] = chart.apply(end[k]);
        }
        turned = false;
      }
    }
    Vec2d lo = end.back(), hi = end.back();
    hole.centre = Vec2d::Zero();
    for (const Vec2d& q : point) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q), hole.centre += q;
    hole.centre /= double(point.size());
    if (turned) {
      hole.centre = cone;
      lo = lo.cwiseMin(cone), hi = hi.cwiseMax(cone);
    }
    // Or a hole whose rim the iso-lines meet at two points or none, whatever its span (at most one
    // line crosses it, so it is under two units one way and one the other): a quad mesh cannot
    // leave it open (two points give one edge that the faces on both sides share).
    if (!((hi - lo).maxCoeff() < span) && (turned || rimGridPoints(point, span) > 2)) continue;
    if (!(componentExtent(cornerFace(start)).diagonal() > 4.0 * around.diagonal())) continue;
    // Every face of the fan must turn the way the map's faces do (a star-shaped hole in (u, v)).
    bool starShaped = true;
    for (std::size_t k = 0; k < point.size(); ++k) {
      const Vec2d p = end[k], q = point[k];  // the edge's end B and start A
      starShaped = starShaped && cross2(q - p, hole.centre - p) > 0.0;
    }
    hole.ears.clear();
    if (!starShaped && turned) continue;  // a fan around the cone or nothing
    if (!starShaped) {
      // Else the loop's own points triangulated: the fill runs against the loop's direction, so the
      // polygon is the points in reverse; a loop through a vertex twice is left open.
      std::vector<VertexId> rim;
      for (const CornerId b : hole.corners) rim.push_back(topology.vertex(nextCorner(b)));
      std::sort(rim.begin(), rim.end());
      if (std::adjacent_find(rim.begin(), rim.end()) != rim.end()) continue;
      const std::vector<Vec2d> reversed(point.rbegin(), point.rend());
      hole.ears = clipEars(reversed);
      if (hole.ears.empty()) continue;
      const std::uint32_t last = static_cast<std::uint32_t>(point.size()) - 1;
      for (auto& ear : hole.ears) {
        for (std::uint32_t& k : ear) k = last - k;
      }
    }
    holes.push_back(hole);
  }
  if (holes.empty()) return 0;
  // The copy keeps the map's wedges (4 bytes per corner) and adds the fans' corners to them: the
  // edge a -> b of the surface closed by the face b -> a -> centre, in that face's chart (the fan's
  // own edges to the centre become seams where the loop crosses one).
  out.positions = mesh.positions;
  out.triangles = mesh.triangles;
  out.origin = mesh.origin;
  std::vector<std::uint32_t> wedge(uv.size());
  for (CornerId k = 0; k < wedge.size(); ++k) wedge[k] = uv.wedge(k);
  std::vector<Vec2d> value(uv.numWedges());
  for (std::uint32_t w = 0; w < value.size(); ++w) value[w] = uv.wedgeValue(w);
  for (const Hole& h : holes) {
    if (!h.ears.empty()) {
      // One chart for the whole fill (the first corner's): the loop's edges become seams where
      // the loop crossed one.
      const std::uint32_t first = static_cast<std::uint32_t>(value.size());
      for (std::size_t k = 0; k < h.corners.size(); ++k) {
        value.push_back(h.chart[k].apply(uv[nextCorner(h.corners[k])]));
      }
      for (const auto& ear : h.ears) {
        Triangle t;
        for (int j = 0; j < 3; ++j) {
          t[j] = topology.vertex(nextCorner(h.corners[ear[j]]));
          wedge.push_back(first + ear[j]);
        }
        out.triangles.push_back(t);
      }
      continue;
    }
    Vec3d centre = Vec3d::Zero();
    for (const CornerId b : h.corners) centre += mesh.position(topology.vertex(nextCorner(b)));
    const VertexId middle = static_cast<VertexId>(out.positions.size());
    out.positions.push_back((centre / double(h.corners.size())).cast<float>());
    std::vector<std::pair<Vec2d, std::uint32_t>> centreWedges;
    for (std::size_t k = 0; k < h.corners.size(); ++k) {
      const CornerId b = h.corners[k];
      const Vec2d q = h.chart[k].inverse(h.centre);
      auto it = std::find_if(centreWedges.begin(), centreWedges.end(), [&](const auto& w) { return w.first == q; });
      if (it == centreWedges.end()) {
        centreWedges.push_back({q, static_cast<std::uint32_t>(value.size())});
        value.push_back(q);
        it = centreWedges.end() - 1;
      }
      out.triangles.push_back({topology.vertex(prevCorner(b)), topology.vertex(nextCorner(b)), middle});
      wedge.push_back(uv.wedge(prevCorner(b)));
      wedge.push_back(uv.wedge(nextCorner(b)));
      wedge.push_back(it->second);
    }
  }
  out.cornerUV = WedgeMap(std::move(wedge), std::move(value));
  return holes.size();
}

QuadRun extractCheckedQuads(const std::string& name, const TriangleMesh& mesh, const Topology& topology,
                            std::int64_t scale, const ProgressFn& progress) {
  if (!mesh.hasUV()) throw InputError(name + ": has no texture coordinates; run seamvox param first");
  QuadRun run;
  run.seams = measureSeamsFromUV(mesh, topology, mesh.cornerUV);
  const SeamQuality& seams = run.seams;
  if (!seams.isSeamless(kQuadSeamTolerance)) {
    throw InputError(name + ": the map is not seamless (seam residual " + std::to_string(seams.maxResidual) +
                     ", translations " + std::to_string(seams.maxIntegerDistance) +
                     " from integers, at the edge of corner " + std::to_string(seams.worstEdgeCorner) +
                     "); quads needs the integer-grid map of seamvox param");
  }
  QuadOptions options;
  options.scale = scale;
  options.progress = progress;
  TriangleMesh filled;
  run.filledHoles = fillSmallHoles(mesh, topology, scale, filled, &run.translatedHoles);
  const Topology filledTopology =
      run.filledHoles ? Topology::build(filled.triangles, filled.numVertices()) : Topology();
  const TriangleMesh& map = run.filledHoles ? filled : mesh;
  const Topology& mapTopology = run.filledHoles ? filledTopology : topology;
  try {
    run.quads = extractQuads(map, mapTopology, options);
  } catch (...) {
    rethrowWithContext(name);
  }
  if (run.quads.stats.seamEdgesOffScale > 0) {
    // A seam maps u = K m onto u' = +-K m + t: the coarse lines continue only when K divides t.
    // Rounding makes t any integer, so this holds only for maps rounded to multiples of K.
    throw InputError(name + ": " + std::to_string(run.quads.stats.seamEdgesOffScale) +
                     " seam translations are no multiples of --scale " + std::to_string(scale) +
                     " (seam edges), so iso-lines every " + std::to_string(scale) +
                     " units would not continue across the seams: seamvox param rounds translations to "
                     "any integers; for a coarser quad mesh, map with an edge length " + std::to_string(scale) +
                     " times larger (--edge-length, --cells) and extract without --scale");
  }
  run.check = validateQuads(run.quads, computeComponents(mapTopology));
  // The quad mesh in the file's coordinates (TriangleMesh::origin), in double precision.
  if (!mesh.origin.isZero(0.0)) {
    for (Vec3d& p : run.quads.mesh.positions) p += mesh.origin;
  }
  return run;
}

}  // namespace seamvox
