// Foldover repair: patches around flipped faces re-solved in the hat basis with stiffening.
#include "core/refine/untangle.h"

#include <algorithm>
#include <iterator>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/LU>

#include "core/quality/metrics.h"
#include "core/refine/detail_untangle.h"
#include "core/refine/refine.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;

enum FaceState : std::uint8_t { kFine = 0, kFlipped = 1, kFolded = 2 };

/// kFlipped for a face with negative parameter area ratio (collapsed and zero-area faces
/// excluded); markFolded then turns those folded in 3D into kFolded.
FaceState stateOf(double ratio) {
  return isFlippedRatio(ratio) ? kFlipped : kFine;
}

/// kFlipped faces (state[i], mesh face origin(i)) whose whole face is folded in 3D against the
/// field's smoothed surface become kFolded.
template <class Origin>
void markFolded(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                std::vector<std::uint8_t>& state, const Origin& origin) {
  std::vector<std::uint32_t> at;
  std::vector<FaceId> faces;
  for (std::uint32_t i = 0; i < state.size(); ++i) {
    if (state[i] == kFlipped) at.push_back(i), faces.push_back(origin(i));
  }
  const std::vector<std::uint8_t> folded = facesFoldedIn3D(mesh, &topology, &field, faces);
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (folded[k]) state[at[k]] = kFolded;
  }
}

/// Per region face: its state under the region's map uv (the 3D fold is the whole face's).
std::vector<std::uint8_t> regionStates(const RegionMesh& region, const WedgeMap& uv, double h,
                                       const TriangleMesh& mesh, const Topology& topology,
                                       const CrossField& field) {
  const std::uint32_t rf = region.topology.numFaces();
  std::vector<std::uint8_t> state(rf, kFine);
  for (std::uint32_t i = 0; i < rf; ++i) state[i] = stateOf(parameterAreaRatio(region.mesh, uv, i, h));
  markFolded(mesh, topology, field, state, [&](std::uint32_t i) { return region.faceOrigin[i]; });
  return state;
}

/// Flipped (not folded) faces per region component.
std::vector<std::uint32_t> flipsPerComponent(const std::vector<std::uint8_t>& state,
                                             const ComponentsResult& components) {
  std::vector<std::uint32_t> count(components.components.size(), 0);
  for (std::size_t i = 0; i < state.size(); ++i) count[components.faceComponent[i]] += state[i] == kFlipped;
  return count;
}

/// Per region face, whether map uv collapses it (|parameter area ratio| < kCollapsedAreaFraction).
std::vector<std::uint8_t> collapsedFaces(const RegionMesh& region, const WedgeMap& uv, double h) {
  std::vector<std::uint8_t> collapsed(region.topology.numFaces());
  for (std::uint32_t i = 0; i < collapsed.size(); ++i) {
    collapsed[i] = std::abs(parameterAreaRatio(region.mesh, uv, i, h)) < kCollapsedAreaFraction;
  }
  return collapsed;
}

/// The best stiffened solution of one round's region: re-solves while faces stay flipped, each
/// time multiplying their energy by options.stiffening; per component the solve with the fewest
/// flips wins (components are independent: everything around them is locked).
struct RoundSolution {
  RegionSolution solution;
  ComponentsResult components;  ///< of the region
  std::vector<std::uint8_t> componentImproved;
  std::uint32_t solves = 0, unknowns = 0;
};

RoundSolution stiffenRegion(const RegionMesh& region, const WedgeMap& regionUV,
                            const std::vector<Complex>& regionT, const TriangleMesh& mesh,
                            const Topology& topology, const CrossField& field, const UntangleOptions& options) {
  const double h = options.edgeLength;
  RoundSolution out;
  out.components = computeComponents(region.topology);
  const ComponentsResult& components = out.components;
  const std::vector<std::uint32_t> before =
      flipsPerComponent(regionStates(region, regionUV, h, mesh, topology, field), components);
  std::vector<std::uint32_t> best = before;
  out.componentImproved.assign(before.size(), 0);
  std::vector<double> weight(region.topology.numFaces(), 1.0);
  const std::vector<std::uint8_t> collapsedBefore = collapsedFaces(region, regionUV, h);
  // The re-solves change only weights: the basis, the systems at weight 1 and each kind's
  // elimination order (seams re-rounded, or their translations kept) serve them all.
  RegionStiffener stiffener(region, regionUV, regionT, h, options.coneWeightRadius, options.closeHolesWithin);
  for (std::uint32_t solve = 0; solve < std::max(1u, options.maxSolves); ++solve) {
    RefineStats stats;
    RegionSolution solved = stiffener.solve(weight, false, &stats);
    // Seams whose edges all lie in the patch are re-rounded, which can move two cones onto one
    // point (their faces collapse): then solved again with every translation kept.
    const std::vector<std::uint8_t> collapsed = collapsedFaces(region, solved.cornerUV, h);
    bool collapsesMore = false;
    for (std::size_t i = 0; i < collapsed.size() && !collapsesMore; ++i) collapsesMore = collapsed[i] > collapsedBefore[i];
    if (collapsesMore) {
      solved = stiffener.solve(weight, true, &stats);
      ++out.solves;
    }
    ++out.solves;
    out.unknowns = std::max(out.unknowns, stats.unknowns);
    const std::vector<std::uint8_t> state = regionStates(region, solved.cornerUV, h, mesh, topology, field);
    const std::vector<std::uint32_t> flips = flipsPerComponent(state, components);
    // Keep, per component, the corners of the best solve so far; a component counts as improved
    // only below the flips it came in with (a later solve better than a worse first one is not).
    if (out.solution.cornerUV.empty()) {
      out.solution = solved;
    } else {
      for (std::uint32_t i = 0; i < region.topology.numFaces(); ++i) {
        const std::uint32_t c = components.faceComponent[i];
        if (flips[c] >= best[c]) continue;
        for (int k = 0; k < 3; ++k) out.solution.cornerUV.set(3 * i + k, solved.cornerUV[3 * i + k]);
      }
      for (std::size_t j = 0; j < region.seamOrigin.size(); ++j) {
        const std::uint32_t c = components.faceComponent[region.cut.seams[j].corners.front() / 3];
        if (flips[c] < best[c]) out.solution.seamT[j] = solved.seamT[j];
      }
    }
    for (std::size_t c = 0; c < flips.size(); ++c) {
      if (flips[c] < best[c]) best[c] = flips[c], out.componentImproved[c] = 1;
    }
    bool anyFlipped = false;
    for (std::uint32_t i = 0; i < state.size(); ++i) {
      if (state[i] != kFlipped) continue;
      weight[i] *= options.stiffening;
      anyFlipped = true;
    }
    if (!anyFlipped) break;
  }
  return out;
}

/// Vertex rings that reach `radius` (world units) at the mean edge length of the seed faces (at
/// least 2): the patch must reach as far as the map's damage, which scales with h, not the edges.
std::uint32_t patchRings(const TriangleMesh& mesh, const std::vector<FaceId>& seeds, double h, double radius) {
  double sum = 0.0;
  for (FaceId f : seeds) {
    const Triangle& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) sum += (mesh.position(t[(k + 1) % 3]) - mesh.position(t[k])).norm();
  }
  const double edge = sum / (3.0 * seeds.size());
  const double rings = edge > 0.0 ? std::ceil(radius * h / edge) : 2.0;
  return static_cast<std::uint32_t>(std::clamp(rings, 2.0, 64.0));
}

constexpr double kMaxRelocation = 0.25;

Vec2d quarterTurns(const Vec2d& p, int k) {
  switch (k & 3) {
    case 0: return p;
    case 1: return {-p.y(), p.x()};
    case 2: return {-p.x(), -p.y()};
    default: return {p.y(), -p.x()};
  }
}

// The fan of interior vertex v with, per corner, the quarter turns from the chart of the first
// corner into the corner's own (composed across the seams, from the edge both faces share). False
// for a cone (the turns do not close), an edge too short in (u, v) to tell the turn, or a wedge
// whose corners disagree. A closed fan starts at its smallest corner, whatever corner the table
// starts it at: the moves' arithmetic follows this order, and the out-of-core repair's window
// (faces in mesh order) then computes what the whole mesh in memory does.
bool fanTurns(const Topology& topology, const WedgeMap& uv, VertexId v, std::vector<CornerId>& corners,
              std::vector<int>& turns) {
  corners.clear();
  turns.clear();
  topology.forEachCornerAround(v, [&](CornerId c) { corners.push_back(c); });
  if (!topology.isBoundaryVertex(v)) std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
  int turn = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    turns.push_back(turn);
    // The edge (v, vertex(prev c)) in both charts: i^k e = e' (a cone's corners may share one
    // value across its seams, so the wedges of v alone do not tell a seam).
    const CornerId c = corners[i], next = topology.ccw(c);
    const Vec2d e = uv[prevCorner(c)] - uv[c], e2 = uv[nextCorner(next)] - uv[next];
    if (e == e2) continue;
    int k = 0;
    double residual = std::numeric_limits<double>::infinity();
    for (int j = 0; j < 4; ++j) {
      const double r = (quarterTurns(e, j) - e2).norm();
      if (r < residual) residual = r, k = j;
    }
    if (!(residual <= 1e-6 * e.norm())) return false;
    turn = (turn + k) & 3;
  }
  if (turn != 0) return false;  // around a cone the seams' turns add up
  for (std::size_t i = 0; i < corners.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (uv.wedge(corners[j]) == uv.wedge(corners[i]) && turns[j] != turns[i]) return false;
    }
  }
  return true;
}

// One interior vertex, on a seam or not: its wedges move together by one displacement d in the
// chart of its first corner, turned into each wedge's chart, so every seam transition keeps its
// rotation and integer translation. d goes toward the kernel centre of the fan, just far enough
// that every fan triangle keeps `share` of the best margin. When the kernel is empty, d goes
// toward the point that most raises the worst negative fan triangle while every positive one
// keeps half its distance to its edge (so a neighbour may find a kernel next). d stays inside the
// box of the neighbours and within kMaxRelocation grid units. Only vertices whose fan has no face
// folded in 3D. False when it cannot move.
using MoveLog = std::vector<std::pair<std::uint32_t, Vec2d>>;  // wedge, value before the move

// Moves every wedge of a vertex's fan (corners with their quarter turns, fanTurns) by d turned
// into the wedge's chart, so the seams keep their transitions; logs the values before.
void moveFanWedges(WedgeMap& uv, const std::vector<CornerId>& corners, const std::vector<int>& turns,
                   const Vec2d& d, MoveLog* log) {
  std::vector<std::uint32_t> done;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const std::uint32_t w = uv.wedge(corners[i]);
    if (std::find(done.begin(), done.end(), w) != done.end()) continue;
    done.push_back(w);
    if (log) log->emplace_back(w, uv.wedgeValue(w));
    uv.setWedgeValue(w, uv.wedgeValue(w) + quarterTurns(d, turns[i]));
  }
}

// How a vertex may move: into its fan's kernel to a quarter of the margin (any distance), toward
// a larger worst margin when the kernel is empty, or (a neighbour making room) halfway into it.
enum class Move { Kernel, Gain, Room };

bool relocateVertex(const Topology& topology, WedgeMap& cornerUV, VertexId v, const std::vector<std::uint8_t>& state,
                    MoveLog& log, Move mode) {
  if (topology.isBoundaryVertex(v) || topology.isIsolatedVertex(v)) return false;
  std::vector<CornerId> corners;
  std::vector<int> turns;
  if (!fanTurns(topology, cornerUV, v, corners, turns) || corners.size() < 3) return false;
  std::vector<Vec2d> normal;
  std::vector<double> offset, weight;
  Vec2d lo = Vec2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const CornerId c = corners[i];
    if (state[c / 3] == kFolded) return false;
    // Triangle (p + i^k d, a, b) positive: (b - a) x (p + i^k d) + a x b > 0.
    const Vec2d p = cornerUV[c], a = cornerUV[nextCorner(c)], b = cornerUV[prevCorner(c)];
    const Vec2d n(a.y() - b.y(), b.x() - a.x());
    normal.push_back(quarterTurns(n, -turns[i]));
    offset.push_back(n.dot(p) + a.x() * b.y() - a.y() * b.x());
    weight.push_back(n.norm());
    for (const Vec2d& q : {a, b}) {
      const Vec2d d = quarterTurns(q - p, -turns[i]);
      lo = lo.cwiseMin(d), hi = hi.cwiseMax(d);
    }
  }
  const std::size_t fan = normal.size();
  for (int axis = 0; axis < 2; ++axis) {  // d inside the neighbours' box
    for (const double sign : {1.0, -1.0}) {
      normal.push_back(axis == 0 ? Vec2d(sign, 0.0) : Vec2d(0.0, sign));
      offset.push_back(sign > 0 ? -lo[axis] : hi[axis]);
      weight.push_back(0.0);
    }
  }
  Vec2d centre;
  const double margin = detail::kernelCentre(normal, offset, weight, centre);
  if (!std::isfinite(margin)) return false;
  double s = 1.0;
  if ((margin > 0.0) != (mode != Move::Gain)) return false;
  const double share = mode == Move::Room ? 0.5 : 0.25;
  if (margin > 0.0) {
    // Along the segment from d = 0 to the centre, the first point where every fan constraint
    // has a quarter of the margin (each is linear along it; all hold at the centre).
    s = 0.0;
    for (std::size_t i = 0; i < fan; ++i) {
      const double need = share * margin * weight[i];
      const double d0 = offset[i], d1 = normal[i].dot(centre) + offset[i];
      if (d0 < need) s = std::max(s, d1 > d0 ? (need - d0) / (d1 - d0) : 1.0);
    }
    if (s <= 0.0) return false;
  } else {
    // No kernel: the point where the worst negative fan triangle gains most while every positive
    // one keeps half its distance (positives as unweighted half-planes), kept when it gains.
    double worst = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < fan; ++i) {
      if (offset[i] > 0.0) {
        offset[i] *= 0.5;
        weight[i] = 0.0;
      } else {
        worst = std::min(worst, offset[i] / weight[i]);
      }
    }
    const double gained = detail::kernelCentre(normal, offset, weight, centre);
    if (!std::isfinite(gained) || !(gained > worst + 1e-3 * (hi - lo).norm())) return false;
  }
  // Steps toward a kernel that is not there yet, or that only makes room, take at most
  // kMaxRelocation grid units: far moves cost gradient error on coarse meshes.
  const double length = std::min(1.0, s) * centre.norm();
  if (!(length > 0.0)) return false;
  const double cap = mode == Move::Kernel ? length : kMaxRelocation;
  const Vec2d d = std::min(length, cap) / centre.norm() * centre;
  moveFanWedges(cornerUV, corners, turns, d, &log);
  return true;
}

// A face as 0 fine, 1 flipped, 2 collapsed (|parameter area ratio| below kCollapsedAreaFraction),
// and its change under a move: worse when a fine face flips or collapses, a flipped one
// collapses or a collapsed one flips (a collapsed face's state says fine: its flip would go
// unseen).
int faceBadness(const TriangleMesh& mesh, const WedgeMap& uv, FaceId f, double h) {
  const double ratio = parameterAreaRatio(mesh, uv, f, h);
  return std::abs(ratio) < kCollapsedAreaFraction ? 2 : (ratio < 0.0 ? 1 : 0);
}
bool becameWorse(int before, int now) {
  return (now != 0 && before == 0) || (now == 2 && before != 2) || (now == 1 && before == 2);
}

// A cone the map leaves a full turn short or over: its (u, v) angle sum outside [pi, 3 pi] by
// about a full turn (at most 0.75 pi or at least 3.25 pi; the cut's cones have indices -2..2
// quarter turns, angles pi to 3 pi). The least-squares map, hat or voxel, leaves many valence-5
// cones at pi / 2 instead of 5 pi / 2 with the map folded next to them (half of them on fertility
// x3 in the hat basis, 47 of 107 on armadillo x4); the relocation and joint steps, which move
// vertices with the cone fixed, unflip such a fold only by winding a neighbour twice
// (metrics.h woundVertices), and the fold they leave may span a thousand faces.
// A cone with a corner on a zero-length (u, v) edge (on one point with another cone, its faces
// collapsed) is not judged: its angle sum misses those corners.
bool coneMiswound(const Topology& topology, const WedgeMap& uv, VertexId cone) {
  constexpr double kPi = 3.14159265358979323846;
  if (topology.isIsolatedVertex(cone) || topology.isBoundaryVertex(cone)) return false;
  bool degenerate = false;
  topology.forEachCornerAround(cone, [&](CornerId c) {
    degenerate = degenerate || uv[nextCorner(c)] == uv[c] || uv[prevCorner(c)] == uv[c];
  });
  if (degenerate) return false;
  const double sum = cornerAngleSum(topology, uv, cone);
  return sum <= 0.75 * kPi || sum >= 3.25 * kPi;
}

// The last step: interior vertices of faces still flipped that are not cones and touch no face
// folded in 3D move toward their fan's kernel (seam vertices with all their wedges), pass after
// pass; when none can, their neighbours move halfway into their own kernels to make room. A move
// changes only the moved vertex's fan and turns none of its positive triangles negative, so
// flips never increase, and the seams keep their rotations and translations; a move that
// collapses a fan triangle is undone. All moves are undone when they leave as many flips as
// before (they would only cost gradient error).
std::uint32_t relocateFlippedVertices(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                                      WedgeMap& cornerUV, std::vector<std::uint8_t>& state, double h,
                                      std::uint32_t passes, const std::vector<std::uint8_t>* pinned,
                                      std::vector<FaceId>& touched) {
  std::vector<std::uint8_t> fixed = pinned ? *pinned : std::vector<std::uint8_t>(topology.numVertices(), 0);
  for (VertexId c : cut.cones) fixed[c] = 1;
  // Only faces flipped at the start change state here (folded ones stay kFolded): no copies of
  // the states (a byte per face each).
  std::uint32_t moves = 0;
  MoveLog log;
  const auto flips = [&] { return std::count(state.begin(), state.end(), std::uint8_t(kFlipped)); };
  const auto flipsBefore = flips();
  // A move is undone when it collapses a fan triangle (parameter area below the collapse
  // fraction) that was not collapsed before, or flips one that was positive (the steps are
  // built not to, but a step at the edge of a kernel can, by rounding).
  const auto badness = [&](FaceId f) { return faceBadness(mesh, cornerUV, f, h); };
  std::vector<int> was;
  const auto tryMove = [&](VertexId v, Move mode) {
    was.clear();
    topology.forEachCornerAround(v, [&](CornerId c) { was.push_back(badness(c / 3)); });
    const std::size_t mark = log.size();
    if (!relocateVertex(topology, cornerUV, v, state, log, mode)) return false;
    std::size_t i = 0;
    bool worse = false;
    topology.forEachCornerAround(v, [&](CornerId c) {
      const int now = badness(c / 3), before = was[i++];
      worse = worse || becameWorse(before, now);
    });
    if (!worse) {
      topology.forEachCornerAround(v, [&](CornerId c) { touched.push_back(c / 3); });
      return true;
    }
    while (log.size() > mark) cornerUV.setWedgeValue(log.back().first, log.back().second), log.pop_back();
    return false;
  };
  // Only the faces flipped at the start are re-measured (as before), so a pass walks them alone,
  // not every face of the mesh.
  std::vector<FaceId> flippedFaces;
  for (FaceId f = 0; f < state.size(); ++f) {
    if (state[f] == kFlipped) flippedFaces.push_back(f);
  }
  for (std::uint32_t pass = 0; pass < passes; ++pass) {
    std::vector<VertexId> candidates;
    for (FaceId f : flippedFaces) {
      if (state[f] != kFlipped) continue;
      for (VertexId v : mesh.triangles[f]) {
        if (!fixed[v]) candidates.push_back(v);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    // Kernel moves first; steps toward a better worst margin only when none is possible.
    std::uint32_t moved = 0;
    for (VertexId v : candidates) moved += tryMove(v, Move::Kernel);
    if (moved == 0) {
      for (VertexId v : candidates) moved += tryMove(v, Move::Gain);
    }
    if (moved == 0) {  // stalled: neighbours of the flipped faces' vertices make room
      std::vector<VertexId> ring;
      for (VertexId v : candidates) {
        topology.forEachCornerAround(v, [&](CornerId c) {
          for (VertexId w : mesh.triangles[c / 3]) {
            if (!fixed[w]) ring.push_back(w);
          }
        });
      }
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      for (VertexId v : ring) {
        if (std::binary_search(candidates.begin(), candidates.end(), v)) continue;
        moved += tryMove(v, Move::Room);
      }
    }
    moves += moved;
    if (moved == 0) break;
    for (FaceId f : flippedFaces) {
      if (state[f] == kFlipped) state[f] = stateOf(parameterAreaRatio(mesh, cornerUV, f, h));
    }
  }
  if (moves > 0 && flips() >= flipsBefore) {  // no gain: the moves would only cost gradient error
    for (auto it = log.rbegin(); it != log.rend(); ++it) cornerUV.setWedgeValue(it->first, it->second);
    for (FaceId f : flippedFaces) state[f] = kFlipped;
    touched.clear();
    return 0;
  }
  return moves;
}

// ---- Joint untangling: whole patches of vertices move together ----

// The regularised denominator of the untangling energy: chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2,
// positive for every D, written without cancellation for D < 0.
double regularisedDet(double det, double eps) {
  const double root = std::sqrt(eps * eps + det * det);
  return det >= 0.0 ? 0.5 * (det + root) : 0.5 * eps * eps / (root - det);
}

}  // namespace

namespace detail {

// Each candidate is where three constraints (n_i . p + c_i = t w_i) meet: the optimum of a
// bounded region is one of them (the box bounds it). A candidate's t comes first: most fall at
// or below the best so far and need neither the other coordinates nor the feasibility test. The
// test starts at the constraint that refused the last candidate (it often refuses the next) and
// reads each constraint's norm once: the same conjunction, in a cheaper order.
double kernelCentre(const std::vector<Vec2d>& normal, const std::vector<double>& offset,
                    const std::vector<double>& weight, Vec2d& centre) {
  const std::size_t n = normal.size();
  std::vector<double> length(n);
  for (std::size_t i = 0; i < n; ++i) length[i] = normal[i].norm();
  const auto holds = [&](std::size_t i, const Vec2d& p, double t) {
    const double need = t * weight[i];
    return normal[i].dot(p) + offset[i] >= need - 1e-9 * (std::abs(need) + length[i]) - 1e-300;
  };
  double best = -std::numeric_limits<double>::infinity();
  std::size_t refused = 0;
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      for (std::size_t c = b + 1; c < n; ++c) {
        Eigen::Matrix3d m;
        Eigen::Vector3d r;
        for (int k = 0; k < 3; ++k) {
          const std::size_t i = k == 0 ? a : (k == 1 ? b : c);
          m.row(k) << normal[i].x(), normal[i].y(), -weight[i];
          r[k] = -offset[i];
        }
        // Cramer's rule: the columns' cross products give the determinant and the inverse's rows.
        const Eigen::Vector3d c01 = m.col(1).cross(m.col(2)), c20 = m.col(0).cross(m.col(1));
        const double det = m.col(0).dot(c01);
        if (std::abs(det) < 1e-300) continue;
        const double t = c20.dot(r) / det;
        if (!(t > best) || !std::isfinite(t)) continue;
        const Eigen::Vector3d c12 = m.col(2).cross(m.col(0));
        const Vec2d p(c01.dot(r) / det, c12.dot(r) / det);
        if (!p.allFinite() || !holds(refused, p, t)) continue;
        bool feasible = true;
        for (std::size_t i = 0; i < n && feasible; ++i) {
          if (i != refused && !holds(i, p, t)) feasible = false, refused = i;
        }
        if (feasible) best = t, centre = p;
      }
    }
  }
  return best;
}

ReferenceShape referenceShape(const TriangleMesh& mesh, FaceId f, double h) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d a = mesh.position(t[0]);
  const Vec3d e1 = (mesh.position(t[1]) - a) / h, e2 = (mesh.position(t[2]) - a) / h;
  ReferenceShape shape;
  const double l1 = e1.norm(), y2 = l1 > 0.0 ? e1.cross(e2).norm() / l1 : 0.0;
  shape.area = 0.5 * l1 * y2;
  if (!(shape.area > 0.0)) return shape;
  Eigen::Matrix2d edges;
  edges << l1, e1.dot(e2) / l1, 0.0, y2;
  shape.inverse = edges.inverse();
  return shape;
}

// As eps falls, a fold costs ever more, so minimising under a falling eps unfolds where it can.
double untanglingEnergy(const ReferenceShape& shape, const Vec2d& q0, const Vec2d& q1, const Vec2d& q2, double eps) {
  Eigen::Matrix2d edges;
  edges.col(0) = q1 - q0;
  edges.col(1) = q2 - q0;
  const Eigen::Matrix2d j = edges * shape.inverse;
  const double det = j.determinant(), chi = regularisedDet(det, eps);
  return shape.area * (j.squaredNorm() + det * det + 1.0) / chi;
}

// With J = [q1 - q0, q2 - q0] S, moving corner k by d adds d w^T to J (w = S^T c_k, c_0 = (-1, -1),
// c_1 = (1, 0), c_2 = (0, 1)): det J grows by g.d (g = cof(J) w), |J|^2 by 2 a.d + |w|^2 |d|^2
// (a = J w). So f = |J|^2 + det^2 + 1 has gradient 2 a + 2 det g and Hessian 2 |w|^2 I + 2 g g^T,
// chi has chi' g and chi'' g g^T, and E = A f / chi follows by the quotient rule.
UntanglingTerms untanglingTerms(const ReferenceShape& shape, const Vec2d& q0, const Vec2d& q1, const Vec2d& q2, int k,
                                double eps) {
  Eigen::Matrix2d edges;
  edges.col(0) = q1 - q0;
  edges.col(1) = q2 - q0;
  const Eigen::Matrix2d j = edges * shape.inverse;
  const double det = j.determinant(), root = std::sqrt(eps * eps + det * det);
  const double chi = regularisedDet(det, eps), dchi = 0.5 * (1.0 + det / root);
  const double ddchi = 0.5 * eps * eps / (root * root * root);
  const double f = j.squaredNorm() + det * det + 1.0;
  Eigen::Matrix2d cof;
  cof << j(1, 1), -j(1, 0), -j(0, 1), j(0, 0);
  const Vec2d c = k == 0 ? Vec2d(-1.0, -1.0) : (k == 1 ? Vec2d(1.0, 0.0) : Vec2d(0.0, 1.0));
  const Vec2d w = shape.inverse.transpose() * c;
  const Vec2d g = cof * w, a = j * w;
  const Vec2d df = 2.0 * a + 2.0 * det * g;
  const Eigen::Matrix2d ggT = g * g.transpose();
  const Eigen::Matrix2d ddf = 2.0 * w.squaredNorm() * Eigen::Matrix2d::Identity() + 2.0 * ggT;
  const Eigen::Matrix2d cross = df * g.transpose() + g * df.transpose();
  UntanglingTerms out;
  out.energy = shape.area * f / chi;
  out.gradient = shape.area * (df / chi - f * dchi / (chi * chi) * g);
  out.hessian = shape.area * (ddf / chi - dchi / (chi * chi) * cross +
                              (2.0 * f * dchi * dchi / (chi * chi * chi) - f * ddchi / (chi * chi)) * ggT);
  return out;
}

}  // namespace detail

namespace {

using detail::ReferenceShape;
using detail::referenceShape;
using detail::untanglingEnergy;

// A vertex that moves in a joint patch: its fan's corners with their quarter turns (fanTurns).
struct JointVertex {
  VertexId v = kInvalidId;
  std::vector<CornerId> corners;
  std::vector<int> turns;
  std::vector<const ReferenceShape*> shapes;  // per corner: its face's
  std::vector<std::uint32_t> neighbours;      // patch vertices sharing a fan face (indices)
};

class JointPatch {
 public:
  JointPatch(const TriangleMesh& mesh, const Topology& topology, WedgeMap& uv, double h)
      : mesh_(mesh), topology_(topology), uv_(uv), h_(h) {}

  // v joins when it can move: interior, not fixed (cones), a fan whose turns close, no fan face
  // degenerate in 3D. A face folded in 3D may join: its energy is against its own 3D shape.
  bool add(VertexId v, const std::vector<std::uint8_t>& fixed) {
    if (fixed[v] || topology_.isBoundaryVertex(v) || topology_.isIsolatedVertex(v)) return false;
    JointVertex jv;
    jv.v = v;
    if (!fanTurns(topology_, uv_, v, jv.corners, jv.turns) || jv.corners.size() < 3) return false;
    for (CornerId c : jv.corners) {
      const ReferenceShape& shape = shapeOf(c / 3);  // unordered_map: stable references
      if (!(shape.area > 0.0)) return false;
      jv.shapes.push_back(&shape);
    }
    vertices_.push_back(std::move(jv));
    return true;
  }
  std::size_t size() const { return vertices_.size(); }

  // Faces whose map the patch changes.
  std::vector<FaceId> faces() const {
    std::vector<FaceId> out;
    for (const JointVertex& jv : vertices_) {
      for (CornerId c : jv.corners) out.push_back(c / 3);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // Sweeps of per-vertex Newton steps on the untangling energy under a falling eps, until the
  // patch's faces are all positive, the count of folded faces stops falling for three eps
  // stages, or the schedule ends. A sweep visits only the vertices that moved in the one before
  // and their neighbours (all of them at each new eps): in a wide patch most vertices settle at
  // once. Returns the fan energies evaluated (the work done).
  std::uint64_t minimise(const std::vector<FaceId>& faces) {
    evaluations_ = 0;
    linkNeighbours();
    auto [worst, folded] = foldedFaces(faces);
    double eps = std::max(0.1, -worst);
    std::size_t fewest = folded;
    std::vector<std::uint8_t> active(vertices_.size()), next(vertices_.size());
    for (int stage = 0, stalled = 0; stage < 10 && stalled < 3; ++stage) {
      std::fill(active.begin(), active.end(), 1);
      for (int sweep = 0; sweep < 20; ++sweep) {
        double total = 0.0, gained = 0.0;
        std::fill(next.begin(), next.end(), 0);
        for (std::size_t i = 0; i < vertices_.size(); ++i) {
          if (!active[i] || !newtonStep(vertices_[i], eps, total, gained)) continue;
          next[i] = 1;
          for (std::uint32_t n : vertices_[i].neighbours) next[n] = 1;
        }
        active.swap(next);
        if (!(gained > 1e-4 * total)) break;
      }
      std::tie(worst, folded) = foldedFaces(faces);
      if (folded == 0 && stage > 0) break;
      stalled = folded < fewest ? 0 : stalled + 1;
      fewest = std::min(fewest, folded);
      eps = worst > 0.0 ? 0.5 * eps : std::max(1e-9, 0.2 * eps);
    }
    return evaluations_;
  }

 private:
  // JointVertex::neighbours: the patch vertices of each fan's faces.
  void linkNeighbours() {
    std::unordered_map<VertexId, std::uint32_t> index;
    for (std::uint32_t i = 0; i < vertices_.size(); ++i) index.emplace(vertices_[i].v, i);
    for (JointVertex& jv : vertices_) {
      jv.neighbours.clear();
      for (CornerId c : jv.corners) {
        for (VertexId w : mesh_.triangles[c / 3]) {
          const auto it = index.find(w);
          if (it != index.end() && w != jv.v) jv.neighbours.push_back(it->second);
        }
      }
      std::sort(jv.neighbours.begin(), jv.neighbours.end());
      jv.neighbours.erase(std::unique(jv.neighbours.begin(), jv.neighbours.end()), jv.neighbours.end());
    }
  }

  const ReferenceShape& shapeOf(FaceId f) {
    auto it = shapes_.find(f);
    if (it == shapes_.end()) it = shapes_.emplace(f, referenceShape(mesh_, f, h_)).first;
    return it->second;
  }

  // The least Jacobian determinant over the faces, and how many are not positive.
  std::pair<double, std::size_t> foldedFaces(const std::vector<FaceId>& faces) {
    double worst = std::numeric_limits<double>::infinity();
    std::size_t folded = 0;
    for (FaceId f : faces) {
      Eigen::Matrix2d edges;
      edges.col(0) = uv_[3 * f + 1] - uv_[3 * f];
      edges.col(1) = uv_[3 * f + 2] - uv_[3 * f];
      const double det = (edges * shapeOf(f).inverse).determinant();
      worst = std::min(worst, det);
      folded += !(det > 0.0);
    }
    return {worst, folded};
  }

  // Energy of jv's fan with jv moved by d (turned into each corner's chart).
  double fanEnergy(const JointVertex& jv, const Vec2d& d, double eps) {
    ++evaluations_;
    double e = 0.0;
    for (std::size_t i = 0; i < jv.corners.size(); ++i) {
      const CornerId c = jv.corners[i];
      const FaceId f = c / 3;
      Vec2d q[3] = {uv_[3 * f], uv_[3 * f + 1], uv_[3 * f + 2]};
      q[c % 3] += quarterTurns(d, jv.turns[i]);
      e += untanglingEnergy(*jv.shapes[i], q[0], q[1], q[2], eps);
    }
    return e;
  }

  // Energy, gradient and Hessian of jv's fan where it is (the gradient and Hessian in jv's first
  // corner's chart: each corner's terms turned back from its own). Counted as the energy and three
  // gradients a step took when the Hessian was differenced, so the work budget buys as many steps.
  detail::UntanglingTerms fanTerms(const JointVertex& jv, double eps) {
    evaluations_ += 4;
    detail::UntanglingTerms sum;
    for (std::size_t i = 0; i < jv.corners.size(); ++i) {
      const CornerId c = jv.corners[i];
      const FaceId f = c / 3;
      const detail::UntanglingTerms t =
          detail::untanglingTerms(*jv.shapes[i], uv_[3 * f], uv_[3 * f + 1], uv_[3 * f + 2], int(c % 3), eps);
      // A move d in jv's chart is R d in the corner's (R: turns quarter turns), so the terms come
      // back as R^T g and R^T H R: an odd turn swaps H's diagonal and negates its off-diagonal,
      // an even one keeps H (entries moved and negated, exactly).
      sum.energy += t.energy;
      sum.gradient += quarterTurns(t.gradient, -jv.turns[i]);
      if (jv.turns[i] & 1) {
        Eigen::Matrix2d turned;
        turned << t.hessian(1, 1), -t.hessian(1, 0), -t.hessian(0, 1), t.hessian(0, 0);
        sum.hessian += turned;
      } else {
        sum.hessian += t.hessian;
      }
    }
    return sum;
  }

  // One damped Newton step (analytic gradient and Hessian) that lowers the fan's energy; adds the
  // fan's energy to total and what the step gained to gained. False when the vertex did not move.
  bool newtonStep(const JointVertex& jv, double eps, double& total, double& gained) {
    double scale = 0.0;
    for (CornerId c : jv.corners) scale += (uv_[nextCorner(c)] - uv_[c]).norm();
    scale /= jv.corners.size();
    if (!(scale > 0.0)) return false;
    const detail::UntanglingTerms terms = fanTerms(jv, eps);
    const double e0 = terms.energy;
    total += e0;
    const Vec2d& g = terms.gradient;
    const Eigen::Matrix2d& hessian = terms.hessian;
    if (!g.allFinite() || !(g.norm() > 0.0)) return false;
    Vec2d step = -g.normalized() * (0.25 * scale);
    if (hessian.allFinite() && hessian(0, 0) > 0.0 && hessian.determinant() > 0.0) {
      step = -hessian.ldlt().solve(g);
      if (step.norm() > scale) step *= scale / step.norm();
    }
    for (int halving = 0; halving < 30; ++halving, step *= 0.5) {
      const double e = fanEnergy(jv, step, eps);
      if (!(e < e0)) continue;
      moveFanWedges(uv_, jv.corners, jv.turns, step, nullptr);
      gained += e0 - e;
      return true;
    }
    return false;
  }

  const TriangleMesh& mesh_;
  const Topology& topology_;
  WedgeMap& uv_;
  double h_;
  std::vector<JointVertex> vertices_;
  std::unordered_map<FaceId, ReferenceShape> shapes_;
  std::uint64_t evaluations_ = 0;
};

// Vertices within `rings` vertex rings of the seeds (the seeds are ring 0).
std::vector<VertexId> vertexRings(const TriangleMesh& mesh, const Topology& topology,
                                  std::vector<VertexId> seeds, std::uint32_t rings) {
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  std::vector<VertexId> all = seeds, front = seeds;
  for (std::uint32_t r = 0; r < rings && !front.empty(); ++r) {
    std::vector<VertexId> next;
    for (VertexId v : front) {
      topology.forEachCornerAround(v, [&](CornerId c) {
        for (VertexId w : mesh.triangles[c / 3]) {
          if (!std::binary_search(all.begin(), all.end(), w)) next.push_back(w);
        }
      });
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    std::vector<VertexId> merged;
    std::merge(all.begin(), all.end(), next.begin(), next.end(), std::back_inserter(merged));
    all.swap(merged);
    front.swap(next);
  }
  return all;
}

// Fan energies the joint patches may evaluate in one run, about 5 s of work: clusters of folds
// that no patch unfolds (a 22M-face map had hundreds around its cones) must not cost minutes.
constexpr std::uint64_t kJointEvaluations = 100'000'000;

// After the relocation: around each face still flipped (folded in 3D too), the vertices within
// k rings (k = 2, 3, 4, 6, 9, 12, 18, 27, 36 until it unfolds) move jointly, seam vertices with
// all their wedges through the seams' turns (seams and translations exact), cones and the
// patch's border fixed. A patch is kept only when it has fewer flipped faces, no face that was
// fine flips and none collapses; else its wedges are restored. Returns the vertices of kept
// patches.
//
// The seeds are taken in face order, in waves: a seed joins a wave when the faces its rings can
// reach meet none that an earlier seed of the wave, or a deferred one, may reach; so the patches
// of a wave share no face and run in parallel. A seed inside such faces waits for the next wave
// (often its face is then in a tried patch). The same map at any thread count; the work budget
// is checked between waves.
std::uint32_t untangleJointly(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                              WedgeMap& cornerUV, std::vector<std::uint8_t>& state, double h,
                              std::uint32_t maxRings, const std::vector<std::uint8_t>* pinned,
                              std::vector<FaceId>& touched) {
  std::vector<std::uint8_t> fixed = pinned ? *pinned : std::vector<std::uint8_t>(topology.numVertices(), 0);
  for (VertexId c : cut.cones) fixed[c] = 1;
  const auto badness = [&](FaceId f) { return faceBadness(mesh, cornerUV, f, h); };
  // One seed's patch: built (serially, from the map between waves), then minimised on its own.
  struct Candidate {
    std::unique_ptr<JointPatch> patch;
    std::vector<FaceId> faces;
    std::uint64_t work = 0;
    bool kept = false;
  };
  std::uint32_t movedVertices = 0;
  std::uint64_t work = 0;
  std::vector<std::uint8_t> claimed(state.size(), 0);  // faces a seed of the wave (or deferred) may reach
  for (const std::uint32_t rings : {2u, 3u, 4u, 6u, 9u, 12u, 18u, 27u, 36u}) {
    if (rings > maxRings) break;
    std::vector<FaceId> pending;
    for (FaceId f = 0; f < state.size(); ++f) {
      if (state[f] != kFine) pending.push_back(f);
    }
    std::vector<std::uint8_t> tried(state.size(), 0);  // in a patch of this many rings already
    // A deferred seed's rings and reach (topology only), kept for its next wave.
    std::unordered_map<FaceId, std::pair<std::vector<VertexId>, std::vector<FaceId>>> known;
    while (!pending.empty()) {
      if (work > kJointEvaluations) return movedVertices;
      std::vector<Candidate> wave;
      std::vector<FaceId> deferred, claims;
      for (FaceId seed : pending) {
        if (state[seed] == kFine || tried[seed]) {
          known.erase(seed);
          continue;
        }
        if (claimed[seed]) {
          deferred.push_back(seed);
          continue;
        }
        auto it = known.find(seed);
        if (it == known.end()) {
          const Triangle& t = mesh.triangles[seed];
          std::vector<VertexId> ring = vertexRings(mesh, topology, {t[0], t[1], t[2]}, rings - 1);
          std::vector<FaceId> reach;
          for (VertexId v : ring) topology.forEachCornerAround(v, [&](CornerId c) { reach.push_back(cornerFace(c)); });
          std::sort(reach.begin(), reach.end());
          reach.erase(std::unique(reach.begin(), reach.end()), reach.end());
          it = known.emplace(seed, std::make_pair(std::move(ring), std::move(reach))).first;
        }
        const std::vector<FaceId>& reach = it->second.second;
        const bool free = std::none_of(reach.begin(), reach.end(), [&](FaceId f) { return claimed[f] != 0; });
        for (FaceId f : reach) {
          if (!claimed[f]) claimed[f] = 1, claims.push_back(f);
        }
        if (!free) {
          deferred.push_back(seed);
          continue;
        }
        Candidate cand;
        cand.patch = std::make_unique<JointPatch>(mesh, topology, cornerUV, h);
        for (VertexId v : it->second.first) cand.patch->add(v, fixed);
        known.erase(it);
        if (cand.patch->size() == 0) continue;
        cand.faces = cand.patch->faces();
        wave.push_back(std::move(cand));
      }
      for (FaceId f : claims) claimed[f] = 0;
      parallelForEach(wave.size(), 1, [&](std::uint64_t i) {
        Candidate& cand = wave[i];
        const std::vector<FaceId>& faces = cand.faces;
        std::vector<std::pair<CornerId, Vec2d>> saved;
        std::vector<int> before;
        std::uint32_t flipsBefore = 0;
        for (FaceId f : faces) {
          before.push_back(badness(f));
          flipsBefore += before.back() == 1;
          for (int k = 0; k < 3; ++k) saved.emplace_back(3 * f + k, cornerUV[3 * f + k]);
        }
        cand.work = cand.patch->minimise(faces);
        std::uint32_t flipsAfter = 0;
        bool worse = false;
        for (std::size_t j = 0; j < faces.size(); ++j) {
          const int now = badness(faces[j]);
          flipsAfter += now == 1;
          worse = worse || becameWorse(before[j], now);
        }
        if (worse || flipsAfter >= flipsBefore) {
          for (const auto& [c, q] : saved) cornerUV.setWedgeValue(cornerUV.wedge(c), q);
          return;
        }
        cand.kept = true;
        for (FaceId f : faces) {
          const std::uint8_t now = stateOf(parameterAreaRatio(mesh, cornerUV, f, h));
          state[f] = now == kFlipped && state[f] == kFolded ? std::uint8_t(kFolded) : now;
        }
      });
      for (Candidate& cand : wave) {
        work += cand.work;
        for (FaceId f : cand.faces) tried[f] = 1;
        if (!cand.kept) continue;
        touched.insert(touched.end(), cand.faces.begin(), cand.faces.end());
        movedVertices += static_cast<std::uint32_t>(cand.patch->size());
      }
      pending.swap(deferred);
    }
  }
  return movedVertices;
}

}  // namespace

namespace {

/// Smallest group of a round's patch solved on its own (splitRegion).
constexpr std::size_t kMinGroupFaces = 8192;

/// What one group of a round's patch changes: the free corners of its improved components, their
/// vertices, and the translations of seams inside them.
struct GroupRepair {
  std::vector<CornerId> corners;
  std::vector<Vec2d> uv;
  std::vector<VertexId> moved;
  std::vector<std::pair<std::uint32_t, Complex>> seams;
  std::uint32_t solves = 0, unknowns = 0;
};

/// Cuts a group out of the map (read only) and stiffens it (stiffenRegion).
GroupRepair repairGroup(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                        const CutResult& cut, const WedgeMap& cornerUV, const std::vector<Complex>& seamT,
                        const std::vector<FaceId>& faces, const UntangleOptions& options) {
  RegionMesh region = extractRegionOnFieldSurface(mesh, topology, field, cut, faces);
  if (options.pinnedVertices) {
    for (VertexId v = 0; v < region.vertexOrigin.size(); ++v) {
      if ((*options.pinnedVertices)[region.vertexOrigin[v]]) region.vertexFree[v] = 0;
    }
  }
  const WedgeMap regionUV = regionCornerValues(region, cornerUV);
  const std::vector<Complex> regionT = regionTranslations(region, seamT);
  const RoundSolution solved = stiffenRegion(region, regionUV, regionT, mesh, topology, field, options);
  GroupRepair out;
  out.solves = solved.solves;
  out.unknowns = solved.unknowns;
  // Free corners of the improved components go back into the whole map.
  const ComponentsResult& components = solved.components;
  for (std::uint32_t c = 0; c < 3 * region.topology.numFaces(); ++c) {
    const VertexId v = region.mesh.triangles[c / 3][c % 3];
    if (!region.vertexFree[v] || !solved.componentImproved[components.faceComponent[c / 3]]) continue;
    out.corners.push_back(3 * region.faceOrigin[c / 3] + c % 3);
    out.uv.push_back(solved.solution.cornerUV[c]);
    out.moved.push_back(region.vertexOrigin[v]);
  }
  for (std::size_t j = 0; j < region.seamOrigin.size(); ++j) {
    const std::uint32_t c = components.faceComponent[region.cut.seams[j].corners.front() / 3];
    if (solved.componentImproved[c]) out.seams.push_back({region.seamOrigin[j], solved.solution.seamT[j]});
  }
  return out;
}

}  // namespace

namespace {

/// The work of an earlier repair added to a later one's figures.
void addRepairWork(UntangleStats& stats, const UntangleStats& earlier) {
  stats.miswoundCones = std::max(stats.miswoundCones, earlier.miswoundCones);
  stats.solves += earlier.solves;
  stats.patchFaces += earlier.patchFaces;
  stats.freeVertices += earlier.freeVertices;
  stats.largestUnknowns = std::max(stats.largestUnknowns, earlier.largestUnknowns);
  stats.relocatedVertices += earlier.relocatedVertices;
  stats.jointVertices += earlier.jointVertices;
  stats.seconds += earlier.seconds;
  stats.roundSeconds += earlier.roundSeconds;
  stats.coneSeconds += earlier.coneSeconds;
  stats.relocationSeconds += earlier.relocationSeconds;
  stats.jointSeconds += earlier.jointSeconds;
  stats.leftoverSeconds += earlier.leftoverSeconds;
  std::vector<VertexId> cones;
  std::set_union(stats.conesLeftShort.begin(), stats.conesLeftShort.end(), earlier.conesLeftShort.begin(),
                 earlier.conesLeftShort.end(), std::back_inserter(cones));
  stats.conesLeftShort = std::move(cones);
}

}  // namespace

void addEarlierRepair(UntangleStats& stats, const UntangleStats& earlier) {
  stats.flippedBefore += earlier.flippedBefore - earlier.flippedAfter;
  addRepairWork(stats, earlier);
}

void addLeftoverRepair(UntangleStats& stats, const UntangleStats& earlier, std::uint64_t regionFaces,
                       std::uint32_t freeVertices, double seconds) {
  stats.leftoverFlips = earlier.flippedAfter;
  stats.measuredFaces = earlier.measuredFaces;
  stats.leftoverAfterResolve = stats.flippedBefore;
  stats.leftoverRegionFaces = regionFaces;
  stats.leftoverFreeVertices = freeVertices;
  stats.flippedBefore = earlier.flippedBefore;
  stats.rounds = std::max(stats.rounds, earlier.rounds);
  addRepairWork(stats, earlier);
  stats.specks += earlier.specks;
  stats.speckFaces += earlier.speckFaces;
  stats.seconds += seconds;
  stats.leftoverSeconds += seconds;
}

std::vector<std::uint32_t> collapseSpecks(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                                          WedgeMap& cornerUV, std::vector<std::complex<double>>& seamT, double h,
                                          const std::vector<FaceId>* flipped) {
  // Only the components of flipped faces are walked, each walk given up once its box reaches h:
  // the cost follows the flips, and nothing is kept per face of the mesh. A walk that meets a face
  // of an earlier walk is in that walk's component, which was given up (a speck is walked whole):
  // it is not a speck either, though the faces left to it may look closed and small.
  std::vector<std::uint32_t> collapsed;
  std::unordered_set<FaceId> walked, speckFaces, current;
  std::vector<CornerId> corners;
  const auto walk = [&](FaceId seed) {
    std::vector<FaceId> faces{seed};
    walked.insert(seed);
    current = {seed};
    BoundingBox box;
    bool closed = true, small = true;
    for (std::size_t i = 0; i < faces.size() && small; ++i) {
      for (CornerId c = 3 * faces[i]; c < 3 * faces[i] + 3; ++c) {
        const Vec3d p = mesh.position(topology.vertex(c));
        box.min = box.min.cwiseMin(p);
        box.max = box.max.cwiseMax(p);
        const CornerId o = topology.opposite(c);
        if (o == kInvalidId) {
          closed = false;
        } else if (walked.insert(cornerFace(o)).second) {
          faces.push_back(cornerFace(o));
          current.insert(cornerFace(o));
        } else if (!current.count(cornerFace(o))) {
          small = false;  // an earlier walk's component
        }
      }
      small = small && box.diagonal() < h;
    }
    if (!small || !closed) return;
    // Closed: E = 3F / 2; a torus (chi 0) needs no cone and is left to the repair.
    std::vector<VertexId> vertices;
    for (FaceId f : faces) vertices.insert(vertices.end(), mesh.triangles[f].begin(), mesh.triangles[f].end());
    std::sort(vertices.begin(), vertices.end());
    const std::int64_t v = std::unique(vertices.begin(), vertices.end()) - vertices.begin();
    const std::int64_t chi = v - 3 * std::int64_t(faces.size()) / 2 + std::int64_t(faces.size());
    if (chi == 0) return;
    collapsed.push_back(static_cast<std::uint32_t>(faces.size()));
    for (FaceId f : faces) {
      speckFaces.insert(f);
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) corners.push_back(c);
    }
  };
  if (flipped) {
    for (FaceId seed : *flipped) {
      if (!walked.count(seed)) walk(seed);
    }
  } else {
    for (FaceId seed = 0; seed < topology.numFaces(); ++seed) {
      if (!walked.count(seed) && isFlippedRatio(parameterAreaRatio(mesh, cornerUV, seed, h))) walk(seed);
    }
  }
  if (corners.empty()) return collapsed;
  std::sort(corners.begin(), corners.end());
  cornerUV.assign(corners, std::vector<Vec2d>(corners.size(), Vec2d::Zero()));
  for (std::size_t s = 0; s < cut.seams.size() && s < seamT.size(); ++s) {
    const SeamCurve& seam = cut.seams[s];
    if (!seam.corners.empty() && speckFaces.count(cornerFace(seam.corners.front()))) seamT[s] = 0.0;
  }
  return collapsed;
}

UntangleStats untangleFlips(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                            const CutResult& cut, WedgeMap& cornerUV, std::vector<Complex>& seamT,
                            const UntangleOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const FaceId nf = topology.numFaces();
  if (cornerUV.size() != 3u * static_cast<std::size_t>(nf) || seamT.size() != cut.seams.size()) {
    throw InputError("untangle: " + std::to_string(cornerUV.size()) + " corner UVs and " +
                     std::to_string(seamT.size()) + " translations for " + std::to_string(nf) +
                     " faces and " + std::to_string(cut.seams.size()) + " seams");
  }
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength) || !(options.stiffening > 1.0)) {
    throw InputError("untangle: edge length must be positive and stiffening above 1");
  }
  const double h = options.edgeLength;
  std::vector<std::uint8_t> state(nf, kFine);
  const std::vector<std::uint8_t>* only = options.onlyFaces;
  auto classify = [&](FaceId f) {
    return only && !(*only)[f] ? kFine : stateOf(parameterAreaRatio(mesh, cornerUV, f, h));
  };
  const std::vector<FaceId>* candidates = options.candidateFaces;
  auto classifyAll = [&] {
    if (candidates) {
      parallelFor(candidates->size(), 1u << 12, [&](const IndexRange& range) {
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) state[(*candidates)[i]] = classify((*candidates)[i]);
      });
    } else {
      parallelFor(nf, 1u << 14, [&](const IndexRange& range) {
        for (FaceId f = range.begin(); f != range.end(); ++f) state[f] = classify(f);
      });
    }
    markFolded(mesh, topology, field, state, [](FaceId f) { return f; });
  };
  // After a round only the patch's faces can change: every corner it assigns belongs to a free
  // vertex, whose whole fan is in the patch.
  auto classifyPatch = [&](const std::vector<FaceId>& patch) {
    parallelFor(patch.size(), 1u << 12, [&](const IndexRange& range) {
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) state[patch[i]] = classify(patch[i]);
    });
    std::vector<FaceId> flipped;
    for (FaceId f : patch) {
      if (state[f] == kFlipped) flipped.push_back(f);
    }
    const std::vector<std::uint8_t> folded = facesFoldedIn3D(mesh, &topology, &field, flipped);
    for (std::size_t k = 0; k < flipped.size(); ++k) {
      if (folded[k]) state[flipped[k]] = kFolded;
    }
  };
  if (only && only->size() != nf) {
    throw InputError("untangle: " + std::to_string(only->size()) + " face flags for " +
                     std::to_string(nf) + " faces");
  }
  if (candidates && (only || !std::is_sorted(candidates->begin(), candidates->end()) ||
                     (!candidates->empty() && candidates->back() >= nf))) {
    throw InputError("untangle: candidate faces must be increasing ids below " + std::to_string(nf) +
                     ", without face flags");
  }
  if (options.pinnedVertices && options.pinnedVertices->size() != mesh.numVertices()) {
    throw InputError("untangle: " + std::to_string(options.pinnedVertices->size()) + " vertex flags for " +
                     std::to_string(mesh.numVertices()) + " vertices");
  }
  classifyAll();
  UntangleStats stats;
  stats.measuredFaces = candidates ? candidates->size()
                                  : only ? std::uint64_t(std::count_if(only->begin(), only->end(), [](std::uint8_t x) { return x != 0; })) : nf;
  for (FaceId f = 0; f < nf; ++f) stats.flippedBefore += state[f] != kFine;

  std::vector<VertexId> moved;
  // Re-solves a patch: its components are independent (everything around them is locked), so
  // groups of them are solved in parallel, and a group's factor stays small.
  const auto solvePatch = [&](const std::vector<FaceId>& patch) {
    ++stats.rounds;
    stats.patchFaces += patch.size();
    const std::vector<std::vector<FaceId>> groups =
        splitRegion(topology, patch, std::max<std::size_t>(kMinGroupFaces, patch.size() / 8));
    std::vector<GroupRepair> repairs(groups.size());
    parallelForEach(groups.size(), 1, [&](std::uint64_t g) {
      repairs[g] = repairGroup(mesh, topology, field, cut, cornerUV, seamT, groups[g], options);
    });
    // One assignment per patch, counting wedges' corners around their vertices.
    std::vector<CornerId> corners;
    std::vector<Vec2d> uv;
    for (GroupRepair& repair : repairs) {
      stats.solves += repair.solves;
      stats.largestUnknowns = std::max(stats.largestUnknowns, repair.unknowns);
      corners.insert(corners.end(), repair.corners.begin(), repair.corners.end());
      uv.insert(uv.end(), repair.uv.begin(), repair.uv.end());
      moved.insert(moved.end(), repair.moved.begin(), repair.moved.end());
      for (const auto& [seam, t] : repair.seams) seamT[seam] = t;
      repair = GroupRepair();
    }
    cornerUV.assign(corners, uv, topology);
    classifyPatch(patch);
  };
  auto stepStart = SteadyClock::now();
  const auto stepDone = [&](double& seconds) {
    seconds += secondsSince(stepStart);
    stepStart = SteadyClock::now();
  };
  for (std::uint32_t round = 0; round < options.maxRounds; ++round) {
    std::vector<FaceId> seeds;
    for (FaceId f = 0; f < nf; ++f) {
      if (state[f] == kFlipped) seeds.push_back(f);
    }
    if (seeds.empty()) break;
    // The patch radius halves until the round's faces fit the budget (at least 2 rings).
    const std::uint64_t budget = std::max<std::uint64_t>(
        options.minPatchFaces, static_cast<std::uint64_t>(options.maxPatchFraction * nf));
    // A growth stops at the first ring past the budget: that patch would be refused anyway.
    std::uint32_t rings = patchRings(mesh, seeds, h, options.patchRadius * double(1u << round));
    const auto grow = [&] {
      return growFaces(topology, seeds, rings, rings > 2 ? budget : std::numeric_limits<std::size_t>::max());
    };
    std::vector<FaceId> patch = grow();
    while (patch.size() > budget && rings > 2) {
      rings = std::max(2u, rings / 2);
      patch = grow();
    }
    solvePatch(patch);
    reportProgress(options.progress, "untangle", double(round + 1) / options.maxRounds);
  }
  stepDone(stats.roundSeconds);
  // Cones the rounds leave a full turn short (coneMiswound) with a flip within coneRepairRadius h
  // get re-solves of their own, at that radius, twice and four times it, outside the rounds'
  // budget (a few cones): the budget shrinks a round's patches to a few rings when flips are
  // many, and only a patch wide enough to spread the cone's rounded position opens the fold. A
  // patch grows from the cone's fan, then again from it and the flips that growth reached (a fold
  // may lie off to one side). Only cones near flips: the out-of-core window holds those.
  const auto coneFan = [&](VertexId c) {
    std::vector<FaceId> fan;
    topology.forEachCornerAround(c, [&](CornerId k) {
      if (!only || (*only)[cornerFace(k)]) fan.push_back(cornerFace(k));
    });
    return fan;
  };
  const auto judged = [&](VertexId c) {
    return !(options.pinnedVertices && (*options.pinnedVertices)[c]) && coneMiswound(topology, cornerUV, c);
  };
  std::vector<VertexId> targets;
  const auto notRetried = [&](VertexId c) {
    return options.conesNotRetried &&
           std::binary_search(options.conesNotRetried->begin(), options.conesNotRetried->end(), c);
  };
  if (options.coneRepairRadius > 0.0) {
    for (VertexId c : cut.cones) {
      if (!judged(c)) continue;
      ++stats.miswoundCones;
      if (notRetried(c)) continue;
      const std::vector<FaceId> fan = coneFan(c);
      if (fan.empty()) continue;
      const std::vector<FaceId> near = growFaces(topology, fan, patchRings(mesh, fan, h, options.coneRepairRadius));
      if (std::any_of(near.begin(), near.end(), [&](FaceId f) { return state[f] == kFlipped; })) targets.push_back(c);
    }
  }
  // A round whose rings the clamps of patchRings keep at the last round's would solve that patch
  // again: skipped (noisy armadillo x4: 2h and 4h both 64 rings, the third round gained nothing).
  std::uint32_t lastRings = 0;
  const std::vector<VertexId> tried = targets;
  for (std::uint32_t round = 0; round < 3 && !targets.empty(); ++round) {
    std::vector<FaceId> seeds;
    std::vector<VertexId> still;
    for (VertexId c : targets) {
      if (!judged(c)) continue;
      still.push_back(c);
      for (FaceId f : coneFan(c)) seeds.push_back(f);
    }
    targets.swap(still);
    if (seeds.empty()) break;
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    const std::uint32_t rings = patchRings(mesh, seeds, h, options.coneRepairRadius * double(1u << round));
    if (rings == lastRings) continue;
    lastRings = rings;
    for (FaceId f : growFaces(topology, seeds, rings)) {
      if (state[f] == kFlipped) seeds.push_back(f);
    }
    std::sort(seeds.begin(), seeds.end());
    seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
    solvePatch(growFaces(topology, seeds, rings));
  }
  for (VertexId c : cut.cones) stats.miswoundConesAfter += judged(c);
  for (VertexId c : tried) {
    if (judged(c)) stats.conesLeftShort.push_back(c);
  }
  std::sort(stats.conesLeftShort.begin(), stats.conesLeftShort.end());
  stepDone(stats.coneSeconds);
  // The faces whose map the last steps changed: the fans of relocated vertices, the joint
  // patches kept.
  std::vector<FaceId> touched;
  if (options.relocationPasses > 0) {
    stats.relocatedVertices = relocateFlippedVertices(mesh, topology, cut, cornerUV, state, h,
                                                      options.relocationPasses, options.pinnedVertices, touched);
  }
  stepDone(stats.relocationSeconds);
  if (options.jointRings >= 2) {
    stats.jointVertices =
        untangleJointly(mesh, topology, cut, cornerUV, state, h, options.jointRings, options.pinnedVertices, touched);
  }
  stepDone(stats.jointSeconds);
  // The last steps re-measure only the faces they watch: every face they changed is measured
  // again, so the figures are the whole map's, as the quality measure's are.
  if (!touched.empty()) {
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    classifyPatch(touched);
  }
  if (std::any_of(state.begin(), state.end(), [](std::uint8_t s) { return s != kFine; })) {
    // The states are the map's (every change re-measured), outside onlyFaces fine: a repair
    // restricted to them collapses the specks among them (walking from every flipped face of an
    // unrepaired map, as it did, took 6 s at 22M faces), the whole map's repair the others.
    std::vector<FaceId> flipped;
    for (FaceId f = 0; f < nf; ++f) {
      if (state[f] != kFine) flipped.push_back(f);
    }
    for (std::uint32_t faces : collapseSpecks(mesh, topology, cut, cornerUV, seamT, h, &flipped)) {
      stats.specks += faces > 0;
      stats.speckFaces += faces;
    }
    if (stats.specks > 0) classifyAll();
  }
  std::sort(moved.begin(), moved.end());
  stats.freeVertices = static_cast<std::uint32_t>(std::unique(moved.begin(), moved.end()) - moved.begin());
  for (FaceId f = 0; f < nf; ++f) {
    if (state[f] == kFine) continue;
    ++stats.flippedAfter;
    stats.foldedIn3D += state[f] == kFolded;
    if (!only) stats.leftFaces.push_back(f);
  }
  stats.seconds = secondsSince(start);
  return stats;
}

}  // namespace seamvox
