#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/field/cone_merge.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/solve/hat_solver.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using testing::Surface;

/// A flat n x n grid of unit cells whose field turns by (sa arg(x - a) + sb arg(x - b)) / 4:
/// cones of index4 sa at a and sb at b.
struct PairCase {
  Surface s;
  CrossField field;
  VertexId a, b;
};

PairCase pairCase(int n, int ai, int aj, int bi, int bj, double sa, double sb) {
  PairCase out{testing::makeSurface(testing::gridMesh(n, n)), {}, VertexId(aj * (n + 1) + ai),
               VertexId(bj * (n + 1) + bi)};
  const Vec3d pa = out.s.mesh.position(out.a), pb = out.s.mesh.position(out.b);
  for (FaceId f = 0; f < out.s.mesh.numFaces(); ++f) {
    const Triangle& t = out.s.mesh.triangles[f];
    const Vec3d x = (out.s.mesh.position(t[0]) + out.s.mesh.position(t[1]) + out.s.mesh.position(t[2])) / 3.0;
    const double theta = (sa * std::atan2(x.y() - pa.y(), x.x() - pa.x()) +
                          sb * std::atan2(x.y() - pb.y(), x.x() - pb.x())) / 4.0;
    out.field.direction.push_back(Vec3f(float(std::cos(theta)), float(std::sin(theta)), 0.f));
  }
  return out;
}

std::int64_t indexSum(const FieldSingularities& sing) {
  return std::accumulate(sing.index4.begin(), sing.index4.end(), std::int64_t(0));
}

/// The cut goes through exactly the remaining cones, and the hat map on it is seamless with no
/// collapsed face.
void expectSeamlessWithoutCollapse(const Surface& s, const CrossField& field,
                                   const FieldSingularities& sing, double h, const std::string& what) {
  const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);  // throws on inconsistency
  EXPECT_EQ(cut.cones, sing.cones) << what;
  ParamOptions options;
  options.edgeLength = h;
  const ParamResult param = parameterizeMesh(s.mesh, s.topology, field, cut, options);
  EXPECT_TRUE(measureSeams(s.mesh, s.topology, cut, param.cornerUV).isSeamless()) << what;
  EXPECT_EQ(measureMap(s.mesh, param.cornerUV, &field, h).collapsed, 0u) << what;
}

TEST(ConeMerge, OppositeConesTwoEdgesApartCancel) {
  PairCase c = pairCase(20, 9, 10, 11, 10, 1.0, -1.0);
  FieldSingularities sing = computeSingularities(c.s.mesh, c.s.topology, c.field);
  ASSERT_EQ(sing.cones.size(), 2u);
  ASSERT_EQ(sing.index4[c.a], 1);
  ASSERT_EQ(sing.index4[c.b], -1);
  const FieldSingularities before = sing;

  // Farther apart than the merge distance: nothing changes.
  EXPECT_EQ(mergeCloseCones(c.s.mesh, c.s.topology, sing, {1.5}).cancelledPairs, 0u);
  EXPECT_EQ(sing.matching, before.matching);
  EXPECT_EQ(sing.cones, before.cones);

  const ConeMergeResult merged = mergeCloseCones(c.s.mesh, c.s.topology, sing, {2.5});
  EXPECT_EQ(merged.cancelledPairs, 1u);
  EXPECT_EQ(merged.mergedPairs, 0u);
  EXPECT_EQ(merged.changedEdges, 2u);  // the straight path of two edges
  EXPECT_NEAR(merged.longestPath, 2.0, 1e-6);
  EXPECT_TRUE(sing.cones.empty());
  EXPECT_EQ(indexSum(sing), indexSum(before));
  for (CornerId k = 0; k < c.s.topology.numCorners(); ++k) {
    const CornerId o = c.s.topology.opposite(k);
    if (o != kInvalidId) EXPECT_EQ((sing.matching[k] + sing.matching[o]) % 4, 0) << k;
  }
  expectSeamlessWithoutCollapse(c.s, c.field, sing, 2.0, "cancelled dipole");
}

TEST(ConeMerge, EqualConesBecomeOneConeOfTwiceTheIndex) {
  for (const double sign : {1.0, -1.0}) {
    PairCase c = pairCase(20, 9, 10, 11, 10, sign, sign);
    FieldSingularities sing = computeSingularities(c.s.mesh, c.s.topology, c.field);
    ASSERT_EQ(sing.cones.size(), 2u);
    ASSERT_EQ(sing.index4[c.a], int(sign));
    ASSERT_EQ(sing.index4[c.b], int(sign));
    const ConeMergeResult merged = mergeCloseCones(c.s.mesh, c.s.topology, sing, {2.5});
    EXPECT_EQ(merged.mergedPairs, 1u);
    EXPECT_EQ(merged.cancelledPairs, 0u);
    ASSERT_EQ(sing.cones.size(), 1u);
    EXPECT_EQ(sing.cones[0], std::min(c.a, c.b));  // equal |index|: the smaller id stays
    EXPECT_EQ(sing.index4[sing.cones[0]], 2 * int(sign));
    expectSeamlessWithoutCollapse(c.s, c.field, sing, 2.0, sign > 0 ? "+2 cone" : "-2 cone");
  }
}

TEST(ConeMerge, KeepsPoincareHopfAndBoundsTheMergedIndex) {
  const std::vector<std::pair<std::string, Surface>> cases = {
      {"icosphere", testing::makeSurface(testing::icosphereMesh(3))},
      {"torus", testing::makeSurface(testing::torusMesh(40, 16))}};
  for (const auto& [name, s] : cases) {
    for (const std::uint32_t seed : {1u, 2u}) {
      const CrossField field = name == "icosphere" && seed == 1
                                   ? computeSmoothestField(s.mesh, s.topology)
                                   : testing::randomField(s.mesh, seed);
      FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
      const std::int64_t sum = indexSum(sing);
      const std::size_t cones = sing.cones.size();
      const double diagonal = computeBoundingBox(s.mesh.positions).diagonal();
      const ConeMergeResult merged = mergeCloseCones(s.mesh, s.topology, sing, {0.3 * diagonal});
      const std::string what = name + " seed " + std::to_string(seed);
      EXPECT_GT(merged.cancelledPairs + merged.mergedPairs, 0u) << what;
      EXPECT_EQ(indexSum(sing), sum) << what;
      EXPECT_EQ(sing.cones.size(), cones - merged.mergedPairs - 2 * merged.cancelledPairs) << what;
      for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
        EXPECT_LE(std::abs(sing.index4[v]), std::max(kMaxMergedIndex4, 0)) << what << " vertex " << v;
        EXPECT_EQ(sing.index4[v] != 0, std::binary_search(sing.cones.begin(), sing.cones.end(), v));
      }
      const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);  // matchings agree with cones
      EXPECT_EQ(cut.cones, sing.cones) << what;
    }
  }
}

// A field that turns a full turn or more around one vertex (index4 4, 5, 8 at a vertex of
// valence 32: a cone of angle <= 0 that no map holds) is split into cones of at most +2, within
// the merge distance, or farther when no vertex is that close; the index sum stays, the cut goes
// through the new cones and the map is seamless without collapsed faces.
TEST(ConeMerge, FullTurnConesAreSplitIntoConesAMapHolds) {
  for (const double turns : {4.0, 5.0, 8.0}) {
    for (const double distance : {3.5, 0.5}) {
      const std::string what = "index4 " + std::to_string(int(turns)) + ", distance " + std::to_string(distance);
      PairCase c{testing::makeSurface(testing::fanDiskMesh(32, 12)), {}, 0, 0};
      c.field = testing::turningField(c.s.mesh, turns);
      FieldSingularities sing = computeSingularities(c.s.mesh, c.s.topology, c.field);
      ASSERT_EQ(sing.cones, std::vector<VertexId>{c.a}) << what;
      ASSERT_EQ(sing.index4[c.a], int(turns)) << what;
      const std::int64_t sum = indexSum(sing);
      const ConeMergeResult merged = mergeCloseCones(c.s.mesh, c.s.topology, sing, {distance});
      EXPECT_EQ(merged.splitCones, static_cast<std::uint32_t>((int(turns) - 1) / 2)) << what;
      EXPECT_EQ(indexSum(sing), sum) << what;
      EXPECT_TRUE(std::is_sorted(sing.cones.begin(), sing.cones.end())) << what;
      for (VertexId v = 0; v < c.s.topology.numVertices(); ++v) {
        EXPECT_LE(sing.index4[v], kMaxMergedIndex4) << what << " vertex " << v;
        EXPECT_EQ(sing.index4[v] != 0, std::binary_search(sing.cones.begin(), sing.cones.end(), v)) << what;
        if (sing.index4[v] != 0) EXPECT_FALSE(c.s.topology.isBoundaryVertex(v)) << what << " vertex " << v;
      }
      // The new cones are spread: no two closer than the rings' spacing.
      for (VertexId a : sing.cones) {
        for (VertexId b : sing.cones) {
          if (a < b) EXPECT_GE((c.s.mesh.position(a) - c.s.mesh.position(b)).norm(), 1.0 - 1e-6) << what;
        }
      }
      expectSeamlessWithoutCollapse(c.s, c.field, sing, 0.5, what);
    }
  }
}

// Many close cone pairs (a random field on a flat grid: a cone at about every other vertex):
// the work of the merge grows like the number of cones, four times the grid gives about four
// times the work (the pairwise scan it replaced gave sixteen).
TEST(ConeMerge, WorkGrowsLinearlyWithTheNumberOfCones) {
  std::size_t cones[2];
  std::uint64_t work[2];
  for (int k = 0; k < 2; ++k) {
    const int n = 60 << k;
    const Surface s = testing::makeSurface(testing::gridMesh(n, n));
    FieldSingularities sing = computeSingularities(s.mesh, s.topology, testing::randomField(s.mesh, 3));
    cones[k] = sing.cones.size();
    const std::int64_t sum = indexSum(sing);
    const ConeMergeResult merged = mergeCloseCones(s.mesh, s.topology, sing, {2.0});
    work[k] = merged.searchedVertices;
    EXPECT_EQ(indexSum(sing), sum);
    EXPECT_GT(merged.cancelledPairs, cones[k] / 8) << "n " << n;
    EXPECT_LT(sing.cones.size(), cones[k] / 2) << "n " << n;
  }
  ASSERT_GT(cones[0], 1000u);
  EXPECT_GT(double(cones[1]) / cones[0], 3.5);
  const double perCone[2] = {double(work[0]) / cones[0], double(work[1]) / cones[1]};
  EXPECT_LT(perCone[1], 1.2 * perCone[0]) << work[0] << " and " << work[1] << " vertices searched";
  EXPECT_LT(perCone[0], 60.0);  // a ball of radius 2 on the unit grid holds about 20 vertices
}

TEST(ConeMerge, CoincidentConeEdgesAreFoundAndMerged) {
  const Surface s = testing::makeSurface(testing::torusMesh(30, 12));
  const CrossField field = testing::randomField(s.mesh, 7);
  FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  std::vector<std::uint8_t> isCone(s.topology.numVertices(), 0);
  for (VertexId v : sing.cones) isCone[v] = 1;
  // A map putting every corner on one point: every edge between two cones is coincident.
  const std::vector<Vec2d> flat(s.topology.numCorners(), Vec2d::Zero());
  std::uint32_t coneEdges = 0;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const VertexId x = s.topology.vertex(nextCorner(c)), y = s.topology.vertex(prevCorner(c));
    if (isCone[x] && isCone[y] && (s.topology.opposite(c) == kInvalidId || c < s.topology.opposite(c))) {
      ++coneEdges;
    }
  }
  ASSERT_GT(coneEdges, 3u) << "the random field should have adjacent cones";
  const auto pairs = coincidentConeEdges(s.topology, sing.cones, WedgeMap::fromCorners(s.mesh.triangles, flat));
  EXPECT_EQ(pairs.size(), coneEdges);
  for (const auto& [a, b] : pairs) EXPECT_TRUE(isCone[a] && isCone[b]);

  // A map with distinct corner values has none.
  std::vector<Vec2d> spread(s.topology.numCorners());
  for (CornerId c = 0; c < spread.size(); ++c) {
    spread[c] = s.mesh.position(s.topology.vertex(c)).head<2>();
  }
  EXPECT_TRUE(coincidentConeEdges(s.topology, sing.cones, WedgeMap::fromCorners(s.mesh.triangles, spread)).empty());

  const std::int64_t sum = indexSum(sing);
  const ConeMergeResult merged = mergeCoincidentCones(s.mesh, s.topology, sing, pairs, 0.0);
  EXPECT_GT(merged.mergedPairs + merged.cancelledPairs, 0u);
  EXPECT_EQ(indexSum(sing), sum);
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    EXPECT_LE(std::abs(sing.index4[v]), kMaxCoincidentIndex4) << v;
  }
  const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);
  EXPECT_EQ(cut.cones, sing.cones);

  // Pairs that are not adjacent are left alone with no distance to reach them.
  FieldSingularities again = computeSingularities(s.mesh, s.topology, field);
  ASSERT_GE(again.cones.size(), 2u);
  const VertexId far = again.cones.back();
  VertexId other = kInvalidId;
  for (VertexId v : again.cones) {
    bool adjacent = false;
    s.topology.forEachCornerAround(far, [&](CornerId c) { adjacent |= s.topology.vertex(nextCorner(c)) == v; });
    if (v != far && !adjacent) other = v;
  }
  ASSERT_NE(other, kInvalidId);
  const ConeMergeResult none = mergeCoincidentCones(s.mesh, s.topology, again, {{far, other}}, 0.0);
  EXPECT_EQ(none.mergedPairs + none.cancelledPairs, 0u);
}

TEST(ConeMerge, CloseConesOnOnePointAreFoundAndMergedAlongAPath) {
  // Cones a few edges apart that the map put on one point (a rounding can do that to a +1 and a
  // +2 cone half a spacing apart) fold the faces between them: they are found within the
  // distance, and merged along a path of interior edges.
  const Surface s = testing::makeSurface(testing::torusMesh(30, 12));
  const CrossField field = testing::randomField(s.mesh, 7);
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  const WedgeMap flat = WedgeMap::fromCorners(s.mesh.triangles, std::vector<Vec2d>(s.topology.numCorners(), Vec2d::Zero()));
  const auto adjacent = coincidentConeEdges(s.topology, sing.cones, flat);
  const auto none = coincidentCones(s.mesh, s.topology, sing.cones, flat, 0.0);
  EXPECT_EQ(none.size(), adjacent.size()) << "with no distance only the adjacent pairs";
  // Within 3 edge lengths (the torus's edges are at most about 0.35 long), pairs that do not
  // share an edge as well.
  double longest = 0.0;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const VertexId x = s.topology.vertex(nextCorner(c)), y = s.topology.vertex(prevCorner(c));
    longest = std::max(longest, (s.mesh.position(x) - s.mesh.position(y)).norm());
  }
  const double reach = 3.0 * longest;
  const auto pairs = coincidentCones(s.mesh, s.topology, sing.cones, flat, reach);
  ASSERT_GT(pairs.size(), adjacent.size());
  std::vector<std::uint8_t> isCone(s.topology.numVertices(), 0);
  for (VertexId v : sing.cones) isCone[v] = 1;
  std::pair<VertexId, VertexId> apart{kInvalidId, kInvalidId};
  for (const auto& [a, b] : pairs) {
    EXPECT_TRUE(isCone[a] && isCone[b] && a < b);
    EXPECT_LE((s.mesh.position(a) - s.mesh.position(b)).norm(), reach + 1e-12);
    bool shareEdge = false;
    s.topology.forEachCornerAround(a, [&](CornerId c) { shareEdge |= s.topology.vertex(nextCorner(c)) == b; });
    if (!shareEdge && canMergeCoincident(sing.index4[a], sing.index4[b])) apart = {a, b};
  }
  ASSERT_NE(apart.first, kInvalidId) << "a mergeable pair that shares no edge";
  // A map that puts every vertex on its own point has none.
  std::vector<Vec2d> spread(s.topology.numCorners());
  for (CornerId c = 0; c < spread.size(); ++c) spread[c] = Vec2d(s.topology.vertex(c), 0.5);
  EXPECT_TRUE(coincidentCones(s.mesh, s.topology, sing.cones, WedgeMap::fromCorners(s.mesh.triangles, spread), reach).empty());

  // The non-adjacent pair merges along a path; the index sum and the cut's disk are kept.
  FieldSingularities merged = sing;
  const std::int32_t sum = sing.index4[apart.first] + sing.index4[apart.second];
  const ConeMergeResult result = mergeCoincidentCones(s.mesh, s.topology, merged, {apart}, reach);
  EXPECT_EQ(result.mergedPairs + result.cancelledPairs, 1u);
  EXPECT_GE(result.changedEdges, 2u) << "a path of more than one edge";
  EXPECT_EQ(indexSum(merged), indexSum(sing));
  EXPECT_EQ(merged.index4[apart.first] + merged.index4[apart.second], sum);
  EXPECT_TRUE(merged.index4[apart.first] == 0 || merged.index4[apart.second] == 0);
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    if (v != apart.first && v != apart.second) EXPECT_EQ(merged.index4[v], sing.index4[v]) << v;
  }
  EXPECT_EQ(merged.cones.size() + (sum == 0 ? 2 : 1), sing.cones.size());
  const CutResult cut = cutToDisk(s.mesh, s.topology, field, merged);
  EXPECT_EQ(cut.cones, merged.cones);
  // Out of reach: left alone.
  FieldSingularities untouched = sing;
  const ConeMergeResult far = mergeCoincidentCones(s.mesh, s.topology, untouched, {apart}, 0.0);
  EXPECT_EQ(far.mergedPairs + far.cancelledPairs, 0u);
  EXPECT_EQ(untouched.index4, sing.index4);
}

TEST(ConeMerge, CloseConesAreThePairsWithinReachAlongEdges) {
  // Close cones whatever the map (the repair's check for cones on two points with flips left
  // between them): every pair whose shortest path of edges is within reach, found by a search
  // written here, and on a map that puts everything on one point the same pairs as coincidentCones.
  const Surface s = testing::makeSurface(testing::torusMesh(30, 12));
  const CrossField field = testing::randomField(s.mesh, 7);
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  ASSERT_GT(sing.cones.size(), 4u);
  double longest = 0.0;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const VertexId x = s.topology.vertex(nextCorner(c)), y = s.topology.vertex(prevCorner(c));
    longest = std::max(longest, (s.mesh.position(x) - s.mesh.position(y)).norm());
  }
  for (const double reach : {0.0, 1.5 * longest, 4.0 * longest}) {
    SCOPED_TRACE(reach);
    std::vector<std::pair<VertexId, VertexId>> expected;
    for (VertexId a : sing.cones) {
      // Plain Dijkstra over every vertex (the torus is closed: every edge is interior).
      std::vector<double> d(s.topology.numVertices(), 1e300);
      std::vector<std::uint8_t> done(s.topology.numVertices(), 0);
      d[a] = 0.0;
      for (;;) {
        VertexId x = kInvalidId;
        for (VertexId v = 0; v < d.size(); ++v) {
          if (!done[v] && d[v] <= reach && (x == kInvalidId || d[v] < d[x])) x = v;
        }
        if (x == kInvalidId) break;
        done[x] = 1;
        s.topology.forEachCornerAround(x, [&](CornerId c) {
          const VertexId y = s.topology.vertex(nextCorner(c));
          d[y] = std::min(d[y], d[x] + (s.mesh.position(y) - s.mesh.position(x)).norm());
        });
      }
      for (VertexId b : sing.cones) {
        if (b > a && done[b]) expected.push_back({a, b});
      }
    }
    std::sort(expected.begin(), expected.end());
    const auto close = closeCones(s.mesh, s.topology, sing.cones, reach);
    EXPECT_EQ(close, expected);
    if (reach > longest) {
      EXPECT_FALSE(close.empty());
      const WedgeMap flat =
          WedgeMap::fromCorners(s.mesh.triangles, std::vector<Vec2d>(s.topology.numCorners(), Vec2d::Zero()));
      EXPECT_EQ(close, coincidentCones(s.mesh, s.topology, sing.cones, flat, reach));
    }
  }
}

TEST(ConeMerge, FoldedCloseConesAreClosePairsWithFlipsAtBothCones) {
  // Two cones two edges apart on a flat grid, the map the grid itself (unit cells): the pair is
  // reported only when a face at each cone is flipped, they are within reach and their indices
  // may merge.
  // A +1 and a +2 cone may merge (a +3 cone); two +2 cones may not.
  for (const double first : {1.0, 2.0}) {
    SCOPED_TRACE(first);
    const PairCase c = pairCase(12, 5, 6, 7, 6, first, 2.0);
    const FieldSingularities sing = computeSingularities(c.s.mesh, c.s.topology, c.field);
    ASSERT_EQ(sing.index4[c.a], std::int32_t(first));
    ASSERT_EQ(sing.index4[c.b], 2);
    const std::vector<VertexId> cones{std::min(c.a, c.b), std::max(c.a, c.b)};
    const std::vector<std::int32_t> index4{sing.index4[cones[0]], sing.index4[cones[1]]};
    const bool mergeable = canMergeCoincident(index4[0], index4[1]);
    EXPECT_EQ(mergeable, first == 1.0);
    std::vector<Vec2d> values(c.s.topology.numCorners());
    for (CornerId k = 0; k < values.size(); ++k) {
      const Vec3d p = c.s.mesh.position(c.s.topology.vertex(k));
      values[k] = Vec2d(p.x(), p.y());
    }
    // Flips one face at v: two of its corners' values swapped.
    const auto flipAt = [&](std::vector<Vec2d>& q, VertexId v) {
      const FaceId f = cornerFace(c.s.topology.vertexCorner(v));
      std::swap(q[3 * f + 1], q[3 * f + 2]);
    };
    const auto folded = [&](const std::vector<Vec2d>& q, double reach) {
      return foldedCloseCones(c.s.mesh, c.s.topology, cones, index4, WedgeMap::fromCorners(c.s.mesh.triangles, q),
                              1.0, reach);
    };
    EXPECT_TRUE(folded(values, 3.0).empty()) << "no flips";
    std::vector<Vec2d> one = values;
    flipAt(one, c.a);
    EXPECT_TRUE(folded(one, 3.0).empty()) << "flips at one cone only";
    std::vector<Vec2d> both = one;
    flipAt(both, c.b);
    const std::pair<VertexId, VertexId> pair{cones[0], cones[1]};
    using Pairs = std::vector<std::pair<VertexId, VertexId>>;
    const Pairs expected = mergeable ? Pairs{pair} : Pairs{};
    EXPECT_EQ(folded(both, 3.0), expected);
    EXPECT_TRUE(folded(both, 1.5).empty()) << "farther apart than the reach";
  }
}

TEST(ConeMerge, ParamLeavesNoCollapsedFacesOnSharedMeshes) {
  // #6: without merging, the hat map of cheburashka collapses faces between coincident cones;
  // with it, neither hat nor voxloc (after refinement) leaves a collapsed face.
  const std::string path = testing::sharedMesh("cheburashka.off");
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage("cheburashka.off");
  testing::TempDir dir;
  const auto collapsed = [&](const std::string& extra) {
    std::string output;
    const int code = testing::runSeamvox("param " + path + " -o " + dir.path("o.ply") +
                                             " --quiet --report " + dir.path("r.json") +
                                             " " + extra,
                                         &output);
    EXPECT_EQ(code, 0) << output;
    const std::string report = testing::readFile(dir.path("r.json"));
    EXPECT_NE(report.find("\"seamless\": true"), std::string::npos) << extra << report;
    const std::size_t at = report.find("\"collapsed\": ");
    EXPECT_NE(at, std::string::npos) << report;
    return at == std::string::npos ? -1 : std::stol(report.substr(at + 13));
  };
  EXPECT_GT(collapsed("--solver hat --merge-cones 0"), 0) << "the case no longer exercises coincident cones";
  EXPECT_EQ(collapsed("--solver hat"), 0);
  EXPECT_EQ(collapsed("--solver voxloc --grid 128"), 0);
}

}  // namespace
}  // namespace seamvox
