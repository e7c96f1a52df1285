#include "core/refine/merge_in_map.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include "core/basis/gaussian_int.h"
#include "core/field/cone_merge.h"
#include "core/refine/refine.h"
#include "core/system/errors.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;

/// Map values (grid units) closer than this are one point.
constexpr double kSamePointDistance = 1e-6;

/// The number of seam ends at v (a closed seam through v counts twice).
std::uint32_t seamEnds(const CutResult& cut, VertexId v) {
  std::uint32_t n = 0;
  for (const SeamCurve& s : cut.seams) n += (s.start == v) + (s.end == v);
  return n;
}

/// The corner of face f at vertex v (kInvalidId when v is not on f).
CornerId cornerAt(const Topology& topology, FaceId f, VertexId v) {
  for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
    if (topology.vertex(c) == v) return c;
  }
  return kInvalidId;
}

/// Shortest path of uncut edges from `from` to `to`, no longer than maxLength, whose inner
/// vertices have no cut edge: the corners of its edges in order, each edge's own face on the
/// path's left (the corner whose edge runs from the path's vertex to the next). Empty when none.
std::vector<CornerId> chordPath(const TriangleMesh& mesh, const Topology& topology, const CutCorners& corners,
                                VertexId from, VertexId to, double maxLength) {
  std::unordered_map<VertexId, bool> onCut;
  const auto touchesCut = [&](VertexId v) {
    const auto it = onCut.find(v);
    if (it != onCut.end()) return it->second;
    bool cut = false;
    topology.forEachCornerAround(v, [&](CornerId c) {
      cut = cut || corners.isCut(nextCorner(c)) || corners.isCut(prevCorner(c));
    });
    return onCut[v] = cut;
  };
  std::unordered_map<VertexId, double> distance{{from, 0.0}};
  std::unordered_map<VertexId, CornerId> via;  // the edge's corner reaching each vertex
  using Item = std::pair<double, VertexId>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  queue.push({0.0, from});
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    if (v == to) break;
    if (v != from && touchesCut(v)) continue;  // only the ends may lie on the cut
    topology.forEachCornerAround(v, [&](CornerId c) {
      const CornerId edge = prevCorner(c);  // runs from v to vertex(next c)
      if (corners.isCut(edge)) return;
      const VertexId w = topology.vertex(nextCorner(c));
      const double dw = d + (mesh.position(w) - mesh.position(v)).norm();
      if (dw > maxLength) return;
      const auto it = distance.find(w);
      if (it != distance.end() && it->second <= dw) return;
      distance[w] = dw;
      via[w] = edge;
      queue.push({dw, w});
    });
  }
  std::vector<CornerId> path;
  if (!via.count(to)) return path;
  for (VertexId v = to; v != from; v = topology.vertex(nextCorner(path.back()))) path.push_back(via.at(v));
  std::reverse(path.begin(), path.end());
  return path;
}

/// The faces reached from `seeds` across uncut edges that are not on the path; empty when more
/// than maxFaces.
std::unordered_set<FaceId> fillSide(const Topology& topology, const CutCorners& corners,
                                    const std::unordered_set<CornerId>& pathCorners, const std::vector<FaceId>& seeds,
                                    std::size_t maxFaces) {
  std::unordered_set<FaceId> side(seeds.begin(), seeds.end());
  std::vector<FaceId> stack(side.begin(), side.end());
  while (!stack.empty()) {
    const FaceId f = stack.back();
    stack.pop_back();
    for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
      if (corners.isCut(c) || pathCorners.count(c)) continue;
      const FaceId g = topology.opposite(c) / 3;
      if (!side.insert(g).second) continue;
      if (side.size() > maxFaces) return {};
      stack.push_back(g);
    }
  }
  return side;
}

}  // namespace

MergeInMapResult mergeConesInMap(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                 CutResult& cut, WedgeMap& cornerUV, std::vector<Complex>& seamT,
                                 VertexId a, std::int32_t ia, VertexId b, std::int32_t ib,
                                 const MergeInMapOptions& options) {
  if (seamT.size() != cut.seams.size()) {
    throw InputError("mergeConesInMap: " + std::to_string(seamT.size()) + " translations for " +
                     std::to_string(cut.seams.size()) + " seams");
  }
  if (!canMergeCoincident(ia, ib) || a == b) {
    throw InputError("mergeConesInMap: cones " + std::to_string(a) + " and " + std::to_string(b) + " of indices " +
                     std::to_string(ia) + " and " + std::to_string(ib) + " cannot merge");
  }
  MergeInMapResult out;
  if (seamEnds(cut, b) == 1) {
    out.gone = b, out.kept = a;
  } else if (seamEnds(cut, a) == 1) {
    out.gone = a, out.kept = b;
  } else {
    out.reason = "neither cone ends exactly one seam";
    return out;
  }
  out.keptIndex4 = ia + ib;
  const double h = options.edgeLength;

  // P and the side D it cuts off the cut surface.
  const std::vector<CornerId> path =
      chordPath(mesh, topology, cut.corners, out.gone, out.kept, options.pathLength > 0.0 ? options.pathLength : 4.0 * h);
  if (path.empty()) {
    out.reason = "no path of uncut edges joins them within reach";
    return out;
  }
  out.pathEdges = static_cast<std::uint32_t>(path.size());
  std::unordered_set<CornerId> pathCorners;
  std::vector<FaceId> leftSeeds, rightSeeds;
  double pathLength = 0.0;
  for (const CornerId e : path) {
    pathCorners.insert(e);
    pathCorners.insert(topology.opposite(e));
    leftSeeds.push_back(e / 3);
    rightSeeds.push_back(topology.opposite(e) / 3);
    pathLength += (mesh.position(topology.vertex(prevCorner(e))) - mesh.position(topology.vertex(nextCorner(e)))).norm();
  }
  const std::unordered_set<FaceId> left = fillSide(topology, cut.corners, pathCorners, leftSeeds, options.maxFaces);
  const std::unordered_set<FaceId> right = fillSide(topology, cut.corners, pathCorners, rightSeeds, options.maxFaces);
  if (left.empty() && right.empty()) {
    out.reason = "both sides of the path hold more than " + std::to_string(options.maxFaces) + " faces";
    return out;
  }
  const bool pieceOnLeft = right.empty() || (!left.empty() && left.size() <= right.size());
  const std::unordered_set<FaceId>& piece = pieceOnLeft ? left : right;
  const std::vector<FaceId>& otherSeeds = pieceOnLeft ? rightSeeds : leftSeeds;
  if (std::any_of(otherSeeds.begin(), otherSeeds.end(), [&](FaceId f) { return piece.count(f) > 0; })) {
    out.reason = "the path does not cut the surface in two";
    return out;
  }
  out.pieceFaces = piece.size();

  // The seam gone ends: its side in D fixes the quarter turns delta that make it the identity.
  std::uint32_t goneSeam = kInvalidId;
  for (std::uint32_t j = 0; j < cut.seams.size(); ++j) {
    if (cut.seams[j].start == out.gone || cut.seams[j].end == out.gone) goneSeam = j;
  }
  // Per seam: 1 when D is on its left only, 2 on its right only, 3 both, 0 neither; 4 mixed.
  std::vector<std::uint8_t> sideOf(cut.seams.size(), 0);
  for (std::uint32_t j = 0; j < cut.seams.size(); ++j) {
    std::uint8_t side = 0;
    bool first = true;
    for (const CornerId c : cut.seams[j].corners) {
      const std::uint8_t here = static_cast<std::uint8_t>((piece.count(c / 3) ? 1 : 0) |
                                                          (piece.count(topology.opposite(c) / 3) ? 2 : 0));
      if (first) side = here, first = false;
      if (here != side) side = 4;
    }
    sideOf[j] = side;
  }
  if (std::find(sideOf.begin(), sideOf.end(), 4) != sideOf.end() || sideOf[goneSeam] == 0 || sideOf[goneSeam] == 3) {
    out.reason = "the path's small side does not lie along the seams between the cones";
    return out;
  }
  const int k = cut.seams[goneSeam].matching;
  const int delta = sideOf[goneSeam] == 1 ? k : -k;  // new matching k - delta (D left) or k + delta
  if (delta % 4 == 0) {
    out.reason = "the seam gone ends has no rotation";
    return out;
  }

  // p: the cones' common point in D's chart.
  const CornerId first = path.front(), last = path.back();
  const FaceId atGone = pieceOnLeft ? first / 3 : topology.opposite(first) / 3;
  const FaceId atKept = pieceOnLeft ? last / 3 : topology.opposite(last) / 3;
  const Vec2d pg = cornerUV[cornerAt(topology, atGone, out.gone)], pk = cornerUV[cornerAt(topology, atKept, out.kept)];
  if ((pg - pk).norm() > kSamePointDistance) {
    out.reason = "not on one point";
    return out;
  }
  const Complex p(pg.x(), pg.y());

  // The region: D, P's faces and the faces of the seams bounding D, with rings around them.
  std::vector<FaceId> seeds(piece.begin(), piece.end());
  seeds.insert(seeds.end(), otherSeeds.begin(), otherSeeds.end());
  for (std::uint32_t j = 0; j < cut.seams.size(); ++j) {
    if (sideOf[j] == 0) continue;
    for (const CornerId c : cut.seams[j].corners) seeds.push_back(c / 3), seeds.push_back(topology.opposite(c) / 3);
  }
  const double meanEdge = pathLength / double(path.size());
  const double rings = meanEdge > 0.0 ? std::ceil(options.radius * h / meanEdge) : 2.0;
  const std::vector<FaceId> faces =
      growFaces(topology, std::move(seeds), static_cast<std::uint32_t>(std::clamp(rings, 2.0, 256.0)), options.maxFaces);
  if (faces.size() > options.maxFaces) {
    out.reason = "its region has more than " + std::to_string(options.maxFaces) + " faces";
    return out;
  }

  // D's combing turns by delta; a seam with D on one side composes with R(q) = i^-delta (q - p) + p
  // (T R^-1 with D on its left, R T on its right), one inside D is conjugated (R T R^-1).
  const Complex turn = unitPower(-delta).toComplex();
  struct SeamChange {
    std::uint32_t seam;
    std::uint8_t matching;
    Complex t;
  };
  std::vector<SeamChange> changes;
  for (std::uint32_t j = 0; j < cut.seams.size(); ++j) {
    if (sideOf[j] == 0) continue;
    const int m = cut.seams[j].matching;
    const Complex r = unitPower(-m).toComplex(), t = seamT[j];
    int m2 = m;
    Complex t2 = t;
    if (sideOf[j] == 1) {
      m2 = m - delta;
      t2 = t + r * p * (1.0 - std::conj(turn));
    } else if (sideOf[j] == 2) {
      m2 = m + delta;
      t2 = turn * (t - p) + p;
    } else {
      t2 = -r * p + turn * (r * p + t - p) + p;
    }
    const Complex rounded(std::round(t2.real()), std::round(t2.imag()));
    // p is a lattice point of the rounded map, so the new translations are Gaussian integers.
    if (std::abs(t2 - rounded) > 1e-4) {
      out.reason = "their point is not on the lattice";
      return out;
    }
    changes.push_back({j, static_cast<std::uint8_t>(((m2 % 4) + 4) % 4), rounded});
  }
  std::vector<SeamChange> saved;
  const auto setMatching = [&](std::uint32_t j, std::uint8_t m) {
    SeamCurve& seam = cut.seams[j];
    for (const CornerId c : seam.corners) {
      cut.corners.setMatching(c, m);
      if (topology.opposite(c) != kInvalidId) cut.corners.setMatching(topology.opposite(c), (4 - m) % 4);
    }
    seam.matching = m;
  };
  for (const SeamChange& change : changes) {
    saved.push_back({change.seam, cut.seams[change.seam].matching, seamT[change.seam]});
    setMatching(change.seam, change.matching);
    seamT[change.seam] = change.t;
  }
  out.changedSeams = static_cast<std::uint32_t>(saved.size());
  for (const FaceId f : piece) cut.faceRotation.set(f, static_cast<std::uint8_t>(((cut.faceRotation[f] + delta) % 4 + 4) % 4));
  const std::vector<VertexId> cones = cut.cones;
  cut.cones.erase(std::remove_if(cut.cones.begin(), cut.cones.end(),
                                 [&](VertexId v) { return v == out.gone || (v == out.kept && out.keptIndex4 == 0); }),
                  cut.cones.end());
  const auto restore = [&] {
    for (const SeamChange& change : saved) setMatching(change.seam, change.matching), seamT[change.seam] = change.t;
    for (const FaceId f : piece) cut.faceRotation.set(f, static_cast<std::uint8_t>(((cut.faceRotation[f] - delta) % 4 + 4) % 4));
    cut.cones = cones;
  };
  try {
    RegionMesh region = extractRegionOnFieldSurface(mesh, topology, field, cut, faces);
    RefineStats stats;
    const RegionSolution solved =
        solveRegion(region, regionCornerValues(region, cornerUV), regionTranslations(region, seamT), h, &stats, {},
                    options.coneWeightRadius, true, options.closeHolesWithin);
    std::vector<CornerId> corners;
    std::vector<Vec2d> uv;
    for (CornerId c = 0; c < 3 * region.topology.numFaces(); ++c) {
      if (!region.vertexFree[region.mesh.triangles[c / 3][c % 3]]) continue;
      corners.push_back(3 * region.faceOrigin[c / 3] + c % 3);
      uv.push_back(solved.cornerUV[c]);
    }
    cornerUV.assign(corners, uv, topology);
    out.regionFaces = faces.size();
    out.freeVertices = static_cast<std::uint64_t>(std::count(region.vertexFree.begin(), region.vertexFree.end(), 1));
  } catch (const CancelledError&) {
    restore();
    throw;
  } catch (const Error& e) {  // a failed factorization, or a region the local solve refuses
    restore();
    out.reason = std::string("its local solve failed: ") + e.what();
    return out;
  }
  out.merged = true;
  return out;
}

}  // namespace seamvox
