// Foldover repair: patches around flipped faces re-solved in the hat basis with stiffening.
#include "core/refine/untangle.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include <Eigen/LU>

#include "core/quality/metrics.h"
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
std::uint8_t stateOf(double ratio) {
  return ratio < 0.0 && std::abs(ratio) >= kCollapsedAreaFraction ? kFlipped : kFine;
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
  for (std::uint32_t solve = 0; solve < std::max(1u, options.maxSolves); ++solve) {
    RefineStats stats;
    RegionSolution solved = solveRegion(region, regionUV, regionT, h, &stats, weight, options.coneWeightRadius);
    ++out.solves;
    out.unknowns = std::max(out.unknowns, stats.unknowns);
    const std::vector<std::uint8_t> state = regionStates(region, solved.cornerUV, h, mesh, topology, field);
    const std::vector<std::uint32_t> flips = flipsPerComponent(state, components);
    // Keep, per component, the corners of the best solve so far.
    if (out.solution.cornerUV.empty()) {
      out.solution = solved;
      for (std::size_t c = 0; c < flips.size(); ++c) out.componentImproved[c] = flips[c] < before[c];
      best = flips;
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
      for (std::size_t c = 0; c < flips.size(); ++c) {
        if (flips[c] < best[c]) best[c] = flips[c], out.componentImproved[c] = 1;
      }
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

// The point of the fan kernel farthest inside: p maximizing min_i (n_i . p + c_i) / |n_i| over
// the half-planes n_i . p + c_i > 0 (2D linear programme, solved by its vertices: the fans are
// small). Returns that margin (<= 0: empty kernel).
double kernelCentre(const std::vector<Vec2d>& normal, const std::vector<double>& offset, Vec2d& centre) {
  const std::size_t n = normal.size();
  double best = -1e300;
  // Each candidate is where three constraints (n_i . p + c_i = t |n_i|) meet: the optimum of a
  // bounded region is one of them (callers pass closed fans, whose kernel lies in the fan).
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      for (std::size_t c = b + 1; c < n; ++c) {
        Eigen::Matrix3d m;
        Eigen::Vector3d r;
        for (int k = 0; k < 3; ++k) {
          const std::size_t i = k == 0 ? a : (k == 1 ? b : c);
          m.row(k) << normal[i].x(), normal[i].y(), -normal[i].norm();
          r[k] = -offset[i];
        }
        if (std::abs(m.determinant()) < 1e-300) continue;
        const Eigen::Vector3d x = m.partialPivLu().solve(r);
        if (!x.allFinite() || x[2] <= best) continue;
        bool feasible = true;
        for (std::size_t i = 0; i < n && feasible; ++i) {
          feasible = normal[i].dot(x.head<2>()) + offset[i] >= x[2] * normal[i].norm() * (1.0 - 1e-9) - 1e-300;
        }
        if (feasible) best = x[2], centre = x.head<2>();
      }
    }
  }
  return best;
}

// One vertex: moves its single wedge toward the kernel centre of its fan, just far enough that
// every fan triangle keeps a quarter of the best margin. Only interior vertices whose fan has no
// face folded in 3D: their kernel lies inside the fan's polygon, so a move stays local (an open
// or partly unconstrained fan could send the vertex far away). False when it cannot move.
bool relocateVertex(const Topology& topology, WedgeMap& cornerUV, VertexId v, const std::vector<std::uint8_t>& folded) {
  if (topology.isBoundaryVertex(v) || topology.isIsolatedVertex(v)) return false;
  std::vector<Vec2d> normal;
  std::vector<double> offset;
  std::uint32_t wedge = kInvalidId;
  bool single = true, anyFolded = false;
  topology.forEachCornerAround(v, [&](CornerId c) {
    if (wedge == kInvalidId) wedge = cornerUV.wedge(c);
    single = single && cornerUV.wedge(c) == wedge;
    anyFolded = anyFolded || folded[c / 3];
    // Triangle (p, a, b) positive: (b - a) x p + a x b > 0.
    const Vec2d a = cornerUV[nextCorner(c)], b = cornerUV[prevCorner(c)];
    const Vec2d d = b - a;
    normal.emplace_back(-d.y(), d.x());
    offset.push_back(a.x() * b.y() - a.y() * b.x());
  });
  if (!single || anyFolded || wedge == kInvalidId || normal.size() < 3) return false;
  Vec2d centre;
  const double margin = kernelCentre(normal, offset, centre);
  if (!(margin > 0.0)) return false;
  // Along the segment from the current point to the centre, the first point where every
  // constraint has a quarter of the margin (each is linear along it; all hold at the centre).
  const Vec2d p0 = cornerUV.wedgeValue(wedge);
  double s = 0.0;
  for (std::size_t i = 0; i < normal.size(); ++i) {
    const double need = 0.25 * margin * normal[i].norm();
    const double d0 = normal[i].dot(p0) + offset[i], d1 = normal[i].dot(centre) + offset[i];
    if (d0 < need) s = std::max(s, d1 > d0 ? (need - d0) / (d1 - d0) : 1.0);
  }
  if (s <= 0.0) return false;
  cornerUV.setWedgeValue(wedge, p0 + std::min(1.0, s) * (centre - p0));
  return true;
}

// The last step: interior vertices of faces still flipped that have one wedge, lie on no seam,
// are not cones and touch no face folded in 3D move into their fan's kernel, pass after pass.
// Moving one vertex leaves every triangle outside its fan as it was and makes every fan
// triangle positive, so flips never increase and seams never change.
std::uint32_t relocateFlippedVertices(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                                      WedgeMap& cornerUV, std::vector<std::uint8_t>& state, double h,
                                      std::uint32_t passes) {
  std::vector<std::uint8_t> fixed(topology.numVertices(), 0);
  for (VertexId c : cut.cones) fixed[c] = 1;
  for (const SeamCurve& seam : cut.seams) {
    for (CornerId c : seam.corners) fixed[topology.vertex(nextCorner(c))] = fixed[topology.vertex(prevCorner(c))] = 1;
  }
  std::vector<std::uint8_t> folded(state.size(), 0);
  for (std::size_t f = 0; f < state.size(); ++f) folded[f] = state[f] == kFolded;
  std::uint32_t moves = 0;
  for (std::uint32_t pass = 0; pass < passes; ++pass) {
    std::vector<VertexId> candidates;
    for (FaceId f = 0; f < state.size(); ++f) {
      if (state[f] != kFlipped) continue;
      for (VertexId v : mesh.triangles[f]) {
        if (!fixed[v]) candidates.push_back(v);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::uint32_t moved = 0;
    for (VertexId v : candidates) moved += relocateVertex(topology, cornerUV, v, folded);
    moves += moved;
    if (moved == 0) break;
    for (FaceId f = 0; f < state.size(); ++f) {
      if (state[f] == kFlipped) state[f] = stateOf(parameterAreaRatio(mesh, cornerUV, f, h));
    }
  }
  return moves;
}

}  // namespace

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
  auto classifyAll = [&] {
    parallelFor(nf, 1u << 14, [&](const IndexRange& range) {
      for (FaceId f = range.begin(); f != range.end(); ++f) state[f] = stateOf(parameterAreaRatio(mesh, cornerUV, f, h));
    });
    markFolded(mesh, topology, field, state, [](FaceId f) { return f; });
  };
  classifyAll();
  UntangleStats stats;
  for (FaceId f = 0; f < nf; ++f) stats.flippedBefore += state[f] != kFine;

  std::vector<VertexId> moved;
  for (std::uint32_t round = 0; round < options.maxRounds; ++round) {
    std::vector<FaceId> seeds;
    for (FaceId f = 0; f < nf; ++f) {
      if (state[f] == kFlipped) seeds.push_back(f);
    }
    if (seeds.empty()) break;
    // The patch radius halves until the round's faces fit the budget (at least 2 rings).
    const std::uint64_t budget = std::max<std::uint64_t>(
        options.minPatchFaces, static_cast<std::uint64_t>(options.maxPatchFraction * nf));
    std::uint32_t rings = patchRings(mesh, seeds, h, options.patchRadius * double(1u << round));
    std::vector<FaceId> patch = growFaces(topology, seeds, rings);
    while (patch.size() > budget && rings > 2) {
      rings = std::max(2u, rings / 2);
      patch = growFaces(topology, seeds, rings);
    }
    const RegionMesh region = extractRegion(mesh, topology, field, cut, patch);
    std::vector<Vec2d> values(3 * patch.size());
    for (std::size_t i = 0; i < patch.size(); ++i) {
      for (int k = 0; k < 3; ++k) values[3 * i + k] = cornerUV[3 * patch[i] + k];
    }
    const WedgeMap regionUV = WedgeMap::fromCorners(region.mesh.triangles, values);
    std::vector<Complex> regionT(region.seamOrigin.size());
    for (std::size_t j = 0; j < regionT.size(); ++j) regionT[j] = seamT[region.seamOrigin[j]];
    ++stats.rounds;
    stats.patchFaces += patch.size();
    const RoundSolution solved = stiffenRegion(region, regionUV, regionT, mesh, topology, field, options);
    stats.solves += solved.solves;
    stats.largestUnknowns = std::max(stats.largestUnknowns, solved.unknowns);

    // Free corners of the improved components go back into the whole map.
    const ComponentsResult& components = solved.components;
    std::vector<CornerId> corners;
    std::vector<Vec2d> uv;
    for (std::uint32_t c = 0; c < 3 * region.topology.numFaces(); ++c) {
      const VertexId v = region.mesh.triangles[c / 3][c % 3];
      if (!region.vertexFree[v] || !solved.componentImproved[components.faceComponent[c / 3]]) continue;
      corners.push_back(3 * region.faceOrigin[c / 3] + c % 3);
      uv.push_back(solved.solution.cornerUV[c]);
      moved.push_back(region.vertexOrigin[v]);
    }
    cornerUV.assign(corners, uv);
    for (std::size_t j = 0; j < region.seamOrigin.size(); ++j) {
      const std::uint32_t c = components.faceComponent[region.cut.seams[j].corners.front() / 3];
      if (solved.componentImproved[c]) seamT[region.seamOrigin[j]] = solved.solution.seamT[j];
    }
    classifyAll();
    reportProgress(options.progress, "untangle", double(round + 1) / options.maxRounds);
  }
  if (options.relocationPasses > 0) {
    stats.relocatedVertices =
        relocateFlippedVertices(mesh, topology, cut, cornerUV, state, h, options.relocationPasses);
  }
  std::sort(moved.begin(), moved.end());
  stats.freeVertices = static_cast<std::uint32_t>(std::unique(moved.begin(), moved.end()) - moved.begin());
  for (FaceId f = 0; f < nf; ++f) {
    stats.flippedAfter += state[f] != kFine;
    stats.foldedIn3D += state[f] == kFolded;
  }
  stats.seconds = secondsSince(start);
  return stats;
}

}  // namespace seamvox
