// Rough spots of the field's surface: noise on a part tessellated far below the grid's scale.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/field/field.h"
#include "core/field/detail_rough_spots.h"
#include "core/field/field_proxy.h"
#include "core/field/rough_spots.h"
#include "core/system/errors.h"
#include "test_meshes.h"

namespace seamvox {
namespace {

using testing::denseSpotPlane;
using testing::makeSurface;
using testing::Surface;

constexpr int kOuter = 12, kInner = 2, kDense = 16;
constexpr double kGrid = 2.0;  // h: the fine cells are 1 / 32 of it, the coarse ones 1 / 2

std::size_t coneCount(const Surface& s, double roughSpotGrid) {
  FieldGeometryOptions geometry;
  geometry.roughSpotGrid = roughSpotGrid;
  const CrossField field = computeCrossField(s.mesh, s.topology, FieldMethod::Direct, {}, {}, geometry);
  return computeSingularities(s.mesh, s.topology, field).cones.size();
}

TEST(RoughSpots, FoundOnlyWhereTheSurfaceIsCrumpledBelowTheGridsScale) {
  // Without noise: nothing is rough, nothing moves.
  {
    const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.0, 1));
    std::vector<Vec3f> positions = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
    const std::vector<Vec3f> before = positions;
    const RoughSpotResult r = smoothRoughSpots(s.topology, positions, kGrid);
    EXPECT_EQ(r.roughVertices, 0u);
    EXPECT_TRUE(r.moved.empty());
    EXPECT_EQ(positions, before);
  }
  // The same noise on a plane of coarse cells only: the spacing keeps it (a coarse mesh's own
  // features are not smoothed away).
  {
    const Surface s = makeSurface(denseSpotPlane(kOuter, 0, kDense, 0.3, 1));
    std::vector<Vec3f> positions = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
    EXPECT_EQ(smoothRoughSpots(s.topology, positions, kGrid).roughVertices, 0u);
  }
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 1));
  std::vector<Vec3f> positions = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  const std::vector<Vec3f> before = positions;
  const auto roughInCentre = [&](const std::vector<Vec3f>& p) {
    std::size_t count = 0;
    for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
      count += std::abs(angleDefect(s.topology, p, v)) > kRoughSpotDefect;
    }
    return count;
  };
  const std::size_t roughBefore = roughInCentre(before);
  const RoughSpotResult r = smoothRoughSpots(s.topology, positions, kGrid);
  ASSERT_GT(r.roughVertices, 100u) << "the crumpled centre has rough vertices";
  EXPECT_GE(roughBefore, r.roughVertices);
  EXPECT_GE(r.rounds, 1u);
  EXPECT_LE(r.rounds, kRoughSpotRounds);
  // Moved: sorted, within h / 2 of the fine square (a rough vertex is in it), never on the
  // boundary; every other vertex keeps its floats.
  ASSERT_FALSE(r.moved.empty());
  std::vector<std::uint8_t> moved(s.topology.numVertices(), 0);
  const double reach = kInner + kRoughSpotRadius * kGrid + 1e-5;
  for (std::size_t i = 0; i < r.moved.size(); ++i) {
    const auto [v, p] = r.moved[i];
    if (i > 0) ASSERT_LT(r.moved[i - 1].first, v);
    moved[v] = 1;
    EXPECT_EQ(positions[v], p) << "vertex " << v;
    EXPECT_LE(std::abs(before[v].x()), reach) << "vertex " << v;
    EXPECT_LE(std::abs(before[v].y()), reach) << "vertex " << v;
    EXPECT_FALSE(s.topology.isBoundaryVertex(v)) << "vertex " << v;
  }
  std::size_t changed = 0;
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    if (!moved[v]) {
      EXPECT_EQ(positions[v], before[v]) << "vertex " << v;
    } else {
      changed += positions[v] != before[v];
    }
  }
  EXPECT_GT(changed, r.roughVertices);
  // The centre is smooth afterwards: at most a tenth of the rough vertices are left.
  EXPECT_LE(10 * roughInCentre(positions), roughBefore);
}

TEST(RoughSpots, ASharpTipOfTheShapeIsNotRough) {
  // The fine centre raised into a pyramid, no noise: its apex has a large defect on the smoothed
  // surface, but the defects around it do not cancel, so the shape stays as it is.
  TriangleMesh mesh = denseSpotPlane(kOuter, kInner, kDense, 0.0, 1);
  VertexId apex = 0;
  for (VertexId v = 0; v < mesh.positions.size(); ++v) {
    Vec3f& p = mesh.positions[v];
    p.z() = std::max(0.0f, 1.5f - 1.5f * std::max(std::abs(p.x()), std::abs(p.y())));
    if (p.z() > mesh.positions[apex].z()) apex = v;
  }
  const Surface s = makeSurface(std::move(mesh));
  std::vector<Vec3f> positions = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  ASSERT_GT(std::abs(angleDefect(s.topology, positions, apex)), kRoughSpotDefect);
  const std::vector<Vec3f> before = positions;
  const RoughSpotResult r = smoothRoughSpots(s.topology, positions, kGrid);
  EXPECT_EQ(r.roughVertices, 0u);
  EXPECT_EQ(positions, before);
  // The same pyramid crumpled by noise is rough.
  TriangleMesh noisy = s.mesh;
  const TriangleMesh noise = denseSpotPlane(kOuter, kInner, kDense, 0.3, 2);
  for (VertexId v = 0; v < noisy.positions.size(); ++v) noisy.positions[v].z() += noise.positions[v].z();
  const Surface n = makeSurface(std::move(noisy));
  std::vector<Vec3f> noisyPositions = smoothPositions(n.mesh, n.topology, kFieldSmoothingIterations);
  EXPECT_GT(smoothRoughSpots(n.topology, noisyPositions, kGrid).roughVertices, 100u);
}

TEST(RoughSpots, TheCrumpledSpotsConesGoAndASmoothMeshKeepsItsField) {
  // The plane without noise has no cone either way, and the same field.
  {
    const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.0, 1));
    EXPECT_EQ(coneCount(s, 0.0), 0u);
    EXPECT_EQ(coneCount(s, kGrid), 0u);
  }
  // A smooth closed mesh (no rough vertex): the same field, bit for bit.
  {
    const Surface sphere = makeSurface(testing::icosphereMesh(4));
    FieldGeometryOptions geometry;
    geometry.roughSpotGrid = 0.01;
    const CrossField plain = computeCrossField(sphere.mesh, sphere.topology, FieldMethod::Direct);
    const CrossField rough = computeCrossField(sphere.mesh, sphere.topology, FieldMethod::Direct, {}, {}, geometry);
    EXPECT_EQ(plain.direction, rough.direction);
    EXPECT_EQ(plain.framePositions, rough.framePositions);
    EXPECT_TRUE(rough.frameOverrides.empty());
  }
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, seed));
    const std::size_t without = coneCount(s, 0.0);
    const std::size_t with = coneCount(s, kGrid);
    // The noise crumples the fine square into many cones; smoothed at the grid's scale it has a
    // few at most.
    EXPECT_GE(without, 20u) << "seed " << seed;
    EXPECT_LE(5 * with, without) << "seed " << seed;
  }
}

TEST(RoughSpots, ReleasedFramePositionsComeBackExactly) {
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 4));
  FieldGeometryOptions geometry;
  geometry.roughSpotGrid = kGrid;
  FieldSolveStats stats;
  ProxyFieldOptions proxy;
  proxy.stats = &stats;
  CrossField field = computeCrossField(s.mesh, s.topology, FieldMethod::Proxy, {}, proxy, geometry);
  ASSERT_FALSE(field.frameOverrides.empty());
  EXPECT_EQ(stats.roughSpotVertices, field.frameOverrides.size());
  EXPECT_GT(stats.roughVertices, 0u);
  const std::vector<Vec3f> held = field.framePositions;
  // The overrides are exactly where the surface differs from the global smoothing.
  const std::vector<Vec3f> global = smoothPositions(s.mesh, s.topology, field.frameSmoothing);
  std::size_t differ = 0;
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) differ += held[v] != global[v];
  EXPECT_GT(differ, 0u);
  EXPECT_EQ(differ, field.frameOverrides.size());
  for (const auto& [v, p] : field.frameOverrides) EXPECT_EQ(held[v], p) << "vertex " << v;

  std::vector<VertexId> some;
  for (VertexId v = 0; v < s.topology.numVertices(); v += 7) some.push_back(v);
  for (const auto& [v, p] : field.frameOverrides) some.push_back(v);
  const auto expectHeld = [&](const std::vector<Vec3f>& got, const char* what) {
    ASSERT_EQ(got.size(), some.size()) << what;
    for (std::size_t i = 0; i < some.size(); ++i) ASSERT_EQ(got[i], held[some[i]]) << what << ", vertex " << some[i];
  };
  expectHeld(framePositionsAt(s.mesh, s.topology, field, some), "held");
  releaseFramePositions(field);
  ASSERT_TRUE(field.framePositions.empty());
  expectHeld(framePositionsAt(s.mesh, s.topology, field, some), "released");
  restoreFramePositions(s.mesh, s.topology, field);
  EXPECT_EQ(field.framePositions, held);
}

TEST(RoughSpots, AClosedComponentWithinTheRegionKeepsItsShape) {
  // A crumb far below the grid's scale: every vertex of it is rough, but smoothing the whole of it
  // would shrink it to a point. The crumpled plane next to it is smoothed as before.
  TriangleMesh crumb = testing::icosphereMesh(3);
  std::mt19937 random(3);
  std::uniform_real_distribution<float> jitter(0.6f, 1.4f);  // crumpled: defects of both signs
  for (Vec3f& p : crumb.positions) p = 0.2f * jitter(random) * p + Vec3f(30.0f, 0.0f, 0.0f);
  const std::uint32_t crumbVertices = static_cast<std::uint32_t>(crumb.positions.size());
  {
    // Next to the plane without noise (whose mean spacing makes the crumb's small): the crumb's
    // vertices alone are rough, and none moves.
    const Surface alone = makeSurface(testing::concatMeshes({denseSpotPlane(kOuter, kInner, kDense, 0.0, 6), crumb}));
    std::vector<Vec3f> p = smoothPositions(alone.mesh, alone.topology, kFieldSmoothingIterations);
    const std::vector<Vec3f> q = p;
    const RoughSpotResult r = smoothRoughSpots(alone.topology, p, kGrid);
    ASSERT_GT(r.roughVertices, 0u) << "the crumb is rough";
    EXPECT_TRUE(r.moved.empty());
    EXPECT_EQ(p, q);
  }
  const Surface s = makeSurface(testing::concatMeshes({denseSpotPlane(kOuter, kInner, kDense, 0.3, 6), crumb}));
  std::vector<Vec3f> positions = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  const std::vector<Vec3f> before = positions;
  const VertexId firstCrumb = s.topology.numVertices() - crumbVertices;
  const RoughSpotResult r = smoothRoughSpots(s.topology, positions, kGrid);
  ASSERT_FALSE(r.moved.empty());
  EXPECT_LT(r.moved.back().first, firstCrumb) << "the crumb moved";
  for (VertexId v = firstCrumb; v < s.topology.numVertices(); ++v) EXPECT_EQ(positions[v], before[v]) << "vertex " << v;
}

TEST(RoughSpots, SameForOneAndTwoThreads) {
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 5));
  const std::vector<Vec3f> smoothed = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  std::vector<Vec3f> serial = smoothed;
  RoughSpotResult one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = smoothRoughSpots(s.topology, serial, kGrid);
  }
  std::vector<Vec3f> parallel = smoothed;
  const RoughSpotResult two = smoothRoughSpots(s.topology, parallel, kGrid);
  ASSERT_FALSE(one.moved.empty());
  EXPECT_EQ(serial, parallel);
  EXPECT_EQ(one.moved, two.moved);
  EXPECT_EQ(one.roughVertices, two.roughVertices);
  EXPECT_EQ(one.rounds, two.rounds);
}

TEST(RoughSpots, ARegionAboveItsBoundSmoothsNothingAndSaysSo) {
  // The rounds' memory bound (out of core: roughRegionBound): a region that would hold more
  // vertices stops the rounds before any step, nothing moves and `capped` is set; a bound above the
  // region changes nothing.
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 8));
  const std::vector<Vec3f> surface = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  const auto at = [&](VertexId w) -> Vec3d { return surface[w].cast<double>(); };
  const double spacing = 1e30;  // every crumpled vertex is rough
  std::vector<VertexId> seeds;
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    if (detail::isRoughVertex(s.topology, v, at, spacing)) seeds.push_back(v);
  }
  ASSERT_GT(seeds.size(), 100u);
  const auto base = [&](VertexId v) { return surface[v]; };
  std::uint32_t rounds = 0;
  const auto free = detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, rounds);
  ASSERT_GT(free.size(), seeds.size());
  ASSERT_GE(rounds, 1u);
  bool capped = false;
  std::uint32_t boundedRounds = 0;
  EXPECT_EQ(detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, boundedRounds,
                                      s.topology.numVertices() + 1, &capped),
            free);
  EXPECT_FALSE(capped);
  EXPECT_EQ(boundedRounds, rounds);
  EXPECT_TRUE(detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, boundedRounds, free.size() / 2, &capped)
                  .empty());
  EXPECT_TRUE(capped);
  EXPECT_EQ(boundedRounds, 0u);
}

// The rounds in memory (local ids per vertex in an array, the re-test on both cores) or as out of
// core (hashed, one thread): the same moves over two rounds, and the same cap at the same bound.
TEST(RoughSpots, InMemoryAndOutOfCoreRoundsGiveTheSameMoves) {
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 9));
  const std::vector<Vec3f> surface = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  const auto at = [&](VertexId w) -> Vec3d { return surface[w].cast<double>(); };
  const double spacing = 1e30;
  std::vector<VertexId> seeds;
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    if (detail::isRoughVertex(s.topology, v, at, spacing)) seeds.push_back(v);
  }
  ASSERT_GT(seeds.size(), 100u);
  const auto base = [&](VertexId v) { return surface[v]; };
  const std::uint32_t n = s.topology.numVertices();
  std::uint32_t hashedRounds = 0, denseRounds = 0;
  const auto hashed = detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, hashedRounds);
  const auto dense =
      detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, denseRounds, ~std::uint64_t(0), nullptr, n);
  ASSERT_GT(hashed.size(), seeds.size());
  EXPECT_EQ(hashedRounds, 2u) << "a second round reads the first's moves";
  EXPECT_EQ(denseRounds, hashedRounds);
  EXPECT_EQ(dense, hashed);
  for (const std::uint64_t bound : {std::uint64_t(hashed.size() / 2), std::uint64_t(n) + 1}) {
    bool hashedCapped = false, denseCapped = false;
    const auto a = detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, hashedRounds, bound, &hashedCapped);
    const auto b =
        detail::smoothRoughRounds(s.topology, base, seeds, kGrid, spacing, denseRounds, bound, &denseCapped, n);
    EXPECT_EQ(a, b) << "bound " << bound;
    EXPECT_EQ(hashedCapped, denseCapped) << "bound " << bound;
    EXPECT_EQ(hashedRounds, denseRounds) << "bound " << bound;
  }
}

// A round's region found in waves on both cores (in memory) is the one Dijkstra finds (out of
// core): the same vertices, distances' shares, fans and positions, and the same cap at the bound
// the region just fits and one below it; from rough seeds and from seeds on the plane's rim.
TEST(RoughSpots, TheRegionFoundInWavesIsTheOneDijkstraFinds) {
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 10));
  const std::vector<Vec3f> surface = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  const auto at = [&](VertexId w) -> Vec3d { return surface[w].cast<double>(); };
  const auto current = [&](VertexId w) { return surface[w]; };
  const std::uint32_t n = s.topology.numVertices();
  std::vector<VertexId> rough, spread;
  for (VertexId v = 0; v < n; ++v) {
    if (detail::isRoughVertex(s.topology, v, at, 1e30)) rough.push_back(v);
    if (v % 97 == 0) spread.push_back(v);
  }
  ASSERT_GT(rough.size(), 100u);
  std::size_t rims = 0;
  for (VertexId v : spread) rims += s.topology.isBoundaryVertex(v);
  ASSERT_GT(rims, 0u);
  for (const auto& [seeds, limit] : {std::pair{rough, float(kGrid)}, std::pair{spread, 1.5f}}) {
    const detail::RoughRegion dijkstra = detail::searchRoughRegion(s.topology, current, seeds, limit, ~std::uint64_t(0));
    ASSERT_FALSE(dijkstra.over);
    const std::size_t size = dijkstra.value.size();
    ASSERT_GT(dijkstra.active.size(), 2 * seeds.size());
    ASSERT_GT(size, dijkstra.active.size());
    for (const std::size_t block : {std::size_t(1024), std::size_t(7)}) {
      const detail::RoughRegion waves =
          detail::searchRoughRegionInMemory(s.topology, current, seeds, limit, ~std::uint64_t(0), n, block);
      EXPECT_FALSE(waves.over);
      EXPECT_EQ(waves.active, dijkstra.active) << "block " << block;
      EXPECT_EQ(waves.share, dijkstra.share) << "block " << block;
      EXPECT_EQ(waves.fanStart, dijkstra.fanStart) << "block " << block;
      EXPECT_EQ(waves.fan, dijkstra.fan) << "block " << block;
      EXPECT_EQ(waves.value, dijkstra.value) << "block " << block;
    }
    for (const std::uint64_t bound : {std::uint64_t(size - 1), std::uint64_t(size)}) {
      EXPECT_EQ(detail::searchRoughRegion(s.topology, current, seeds, limit, bound).over, bound < size);
      EXPECT_EQ(detail::searchRoughRegionInMemory(s.topology, current, seeds, limit, bound, n, 7).over, bound < size);
    }
  }
}

TEST(RoughSpots, InMemoryARegionAboveTheBoundSmoothsNothingAndTheStatsSayIt) {
  // The bound's arithmetic: a quarter of the vertices plus the headroom at kRoughRegionBytes a
  // vertex, at least kRoughRegionMinVertices, no overflow with an unlimited headroom.
  EXPECT_EQ(roughRegionBoundInMemory(1000, 0), kRoughRegionMinVertices);
  EXPECT_EQ(roughRegionBoundInMemory(4000000, 0), 1000000u);
  EXPECT_EQ(roughRegionBoundInMemory(4000000, 100 * kRoughRegionBytes + 5), 1000100u);
  EXPECT_GT(roughRegionBoundInMemory(4000000, ~std::uint64_t(0)), ~std::uint64_t(0) / kRoughRegionBytes);
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 5));
  const std::vector<Vec3f> surface = smoothPositions(s.mesh, s.topology, kFieldSmoothingIterations);
  std::vector<Vec3f> unbounded = surface, above = surface, below = surface;
  const RoughSpotResult free = smoothRoughSpots(s.topology, unbounded, kGrid);
  ASSERT_GT(free.moved.size(), 100u);
  EXPECT_FALSE(free.capped);
  // A bound above every region: the same floats; one below the first region: nothing moves.
  const RoughSpotResult bounded = smoothRoughSpots(s.topology, above, kGrid, s.topology.numVertices() + 1);
  EXPECT_FALSE(bounded.capped);
  EXPECT_EQ(bounded.moved, free.moved);
  EXPECT_EQ(above, unbounded);
  const RoughSpotResult capped = smoothRoughSpots(s.topology, below, kGrid, free.moved.size() / 2);
  EXPECT_TRUE(capped.capped);
  EXPECT_EQ(capped.roughVertices, free.roughVertices);
  EXPECT_TRUE(capped.moved.empty());
  EXPECT_EQ(below, surface);
  // Through the field: the stats say capped and nothing moved, and the field is the one without
  // rough spots.
  FieldGeometryOptions geometry;
  geometry.roughSpotGrid = kGrid;
  geometry.roughSpotMaxRegion = free.moved.size() / 2;
  FieldSolveStats stats;
  SmoothFieldOptions smooth;
  smooth.stats = &stats;
  const CrossField field = computeCrossField(s.mesh, s.topology, FieldMethod::Direct, smooth, {}, geometry);
  EXPECT_TRUE(stats.roughSpotsCapped);
  EXPECT_EQ(stats.roughVertices, free.roughVertices);
  EXPECT_EQ(stats.roughSpotVertices, 0u);
  FieldGeometryOptions plain;
  const CrossField withoutRoughSpots = computeCrossField(s.mesh, s.topology, FieldMethod::Direct, {}, {}, plain);
  EXPECT_EQ(computeSingularities(s.mesh, s.topology, field).cones.size(),
            computeSingularities(s.mesh, s.topology, withoutRoughSpots).cones.size());
}

TEST(RoughSpots, SetAsideTheMovesAlongTheNormalAreReadAndPutBackTheRoughOnes) {
  // The map's stages after the cut read the plain smoothed surface with the rough spots' moves
  // along the rough surface's normal only: with the moves set aside, framePositions (held or
  // recomputed) are smoothPositions' floats elsewhere; put back, the field's own.
  const Surface s = makeSurface(denseSpotPlane(kOuter, kInner, kDense, 0.3, 3));
  FieldGeometryOptions geometry;
  geometry.roughSpotGrid = kGrid;
  CrossField field = computeCrossField(s.mesh, s.topology, FieldMethod::Direct, {}, {}, geometry);
  ASSERT_GT(field.frameOverrides.size(), 100u);
  const std::vector<Vec3f> plain = smoothPositions(s.mesh, s.topology, field.frameSmoothing);
  const std::vector<Vec3f> rough = field.framePositions;
  const auto overrides = field.frameOverrides;
  ASSERT_NE(rough, plain);
  std::vector<VertexId> all(s.topology.numVertices());
  for (VertexId v = 0; v < all.size(); ++v) all[v] = v;
  std::vector<std::pair<VertexId, Vec3f>> aside = {{0, Vec3f::Zero()}};  // emptied first
  setFrameOverridesAside(s.mesh, s.topology, field, aside);
  EXPECT_EQ(aside, overrides);
  ASSERT_EQ(field.frameOverrides.size(), overrides.size());
  // Bit for bit the vertex-after-vertex computation (the out-of-core one) on the whole plain surface.
  EXPECT_EQ(field.frameOverrides, detail::normalPartOfMoves(s.topology, overrides, [&](VertexId w) { return plain[w]; }));
  const std::vector<Vec3f> map = field.framePositions;
  std::size_t alongTheNormal = 0;
  for (std::size_t i = 0; i < overrides.size(); ++i) {
    const VertexId v = overrides[i].first;
    EXPECT_EQ(field.frameOverrides[i].first, v);
    EXPECT_EQ(map[v], field.frameOverrides[i].second);
    // The map's position: the plain one moved along the rough fan's normal by the rough move's
    // part along it.
    Vec3d n = Vec3d::Zero();
    const Vec3d p = rough[v].cast<double>();
    s.topology.forEachCornerAround(v, [&](CornerId c) {
      n += (rough[s.topology.vertex(nextCorner(c))].cast<double>() - p)
               .cross(rough[s.topology.vertex(prevCorner(c))].cast<double>() - p);
    });
    n.normalize();
    const Vec3d moveOnMap = (map[v] - plain[v]).cast<double>(), move = (rough[v] - plain[v]).cast<double>();
    EXPECT_LT((moveOnMap - n * n.dot(moveOnMap)).norm(), 1e-5 * (1.0 + move.norm())) << v;
    EXPECT_NEAR(n.dot(moveOnMap), n.dot(move), 1e-5 * (1.0 + move.norm())) << v;
    alongTheNormal += (moveOnMap - move).norm() > 1e-3 * move.norm();
  }
  EXPECT_GT(alongTheNormal, overrides.size() / 10) << "the steps drifted few vertices along the surface";
  std::vector<bool> isMoved(all.size(), false);
  for (const auto& [v, p] : overrides) isMoved[v] = true;
  for (VertexId v = 0; v < all.size(); ++v) {
    if (!isMoved[v]) EXPECT_EQ(map[v], plain[v]) << v;
  }
  releaseFramePositions(field);
  EXPECT_EQ(framePositionsAt(s.mesh, s.topology, field, all), map);
  restoreFramePositions(s.mesh, s.topology, field);
  EXPECT_EQ(field.framePositions, map);
  putFrameOverridesBack(field, aside);
  EXPECT_TRUE(aside.empty());
  EXPECT_EQ(field.frameOverrides, overrides);
  EXPECT_EQ(field.framePositions, rough);
  // Released while set aside, put back, then recomputed: the rough surface again.
  setFrameOverridesAside(s.mesh, s.topology, field, aside);
  releaseFramePositions(field);
  putFrameOverridesBack(field, aside);
  EXPECT_EQ(framePositionsAt(s.mesh, s.topology, field, all), rough);
  restoreFramePositions(s.mesh, s.topology, field);
  EXPECT_EQ(field.framePositions, rough);
  // Nothing to set aside on a field without rough spots.
  CrossField smooth = computeCrossField(s.mesh, s.topology, FieldMethod::Direct);
  const std::vector<Vec3f> held = smooth.framePositions;
  setFrameOverridesAside(s.mesh, s.topology, smooth, aside);
  EXPECT_TRUE(aside.empty());
  EXPECT_EQ(smooth.framePositions, held);
}

TEST(RoughSpots, BadArgumentsThrow) {
  const Surface s = makeSurface(testing::gridMesh(4, 4));
  std::vector<Vec3f> positions = s.mesh.positions;
  for (const double h : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(smoothRoughSpots(s.topology, positions, h), InputError) << h;
  }
  positions.pop_back();
  EXPECT_THROW(smoothRoughSpots(s.topology, positions, 1.0), InputError);
}

}  // namespace
}  // namespace seamvox
