// Wound vertices out of core (stream/wound_count): on meshes of power-map fans (z^s winds its
// centre s times; some fans open, vertex ids shuffled so fans straddle the counters' ranges),
// both counters give woundVertices' count: the manifold one summed in memory and in many
// vertex ranges through scratch files, the fan one from the sides of the edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/mesh/topology.h"
#include "core/mesh/wedge_map.h"
#include "core/quality/metrics.h"
#include "stream/wound_count.h"
#include "testing.h"

namespace seamvox {
namespace {

struct FanMesh {
  std::vector<Triangle> triangles;
  std::vector<Vec2d> uv;  // per corner
  std::uint32_t vertices = 0;
};

// `fans` fans of 7 to 12 faces, powers among 0.75, 1, 1.75, 2 and 2.5 (the last two wound when
// closed), every fifth with a face missing; vertex ids shuffled.
FanMesh powerFans(int fans, std::uint32_t seed) {
  std::mt19937 random(seed);
  FanMesh m;
  const double powers[] = {0.75, 1.0, 1.75, 2.0, 2.5};
  for (int k = 0; k < fans; ++k) {
    const int n = 7 + static_cast<int>(random() % 6);
    const double s = powers[random() % 5];
    const VertexId centre = m.vertices++, rim = m.vertices;
    m.vertices += n;
    for (int j = 0; j < n - (k % 5 == 4); ++j) {
      m.triangles.push_back({centre, rim + j, rim + (j + 1) % n});
      m.uv.push_back(Vec2d::Zero());
      for (int i : {j, j + 1}) m.uv.push_back(Vec2d(std::cos(s * 2.0 * M_PI * i / n), std::sin(s * 2.0 * M_PI * i / n)));
    }
  }
  std::vector<VertexId> id(m.vertices);
  std::iota(id.begin(), id.end(), 0u);
  std::shuffle(id.begin(), id.end(), random);
  for (Triangle& t : m.triangles) {
    for (VertexId& v : t) v = id[v];
  }
  return m;
}

std::uint64_t countManifold(const FanMesh& m, const Topology& topology, std::uint64_t memoryBytes, bool expectRanges) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  ManifoldWoundCounter counter(scratch, m.vertices, memoryBytes, "wound");
  EXPECT_EQ(counter.inRanges(), expectRanges);
  for (CornerId c = 0; c < 3 * m.triangles.size(); ++c) {
    const bool onBoundary = topology.opposite(nextCorner(c)) == kInvalidId || topology.opposite(prevCorner(c)) == kInvalidId;
    counter.add(topology.vertex(c), woundCornerAngle(m.uv[c], m.uv[nextCorner(c)], m.uv[prevCorner(c)], onBoundary));
  }
  return counter.count();
}

TEST(WoundCount, BothCountersMatchTheInMemoryCount) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const FanMesh m = powerFans(200, seed);
    const Topology topology = Topology::build(m.triangles, m.vertices);
    const std::size_t expected = woundVertices(topology, WedgeMap::fromCorners(m.triangles, m.uv)).size();
    EXPECT_GT(expected, 20u);
    EXPECT_LT(expected, 200u);
    EXPECT_EQ(countManifold(m, topology, std::uint64_t(1) << 30, false), expected) << seed;
    EXPECT_EQ(countManifold(m, topology, 64, true), expected) << seed;  // ranges of 8 vertices

    testing::TempDir dir;
    ScratchFolder scratch(dir.dir());
    FanAngleSums<float> fans(scratch, m.vertices, m.triangles.size(), ExternalSortOptions{1 << 12, "wound"});  // many partitions
    const auto angleAt = [&](CornerId c) {
      return static_cast<float>(cornerUVAngle(m.uv[c], m.uv[nextCorner(c)], m.uv[prevCorner(c)]));
    };
    for (CornerId c = 0; c < 3 * m.triangles.size(); ++c) {
      const CornerId o = topology.opposite(c);
      if (o == kInvalidId) {
        fans.addSide(topology.vertex(nextCorner(c)), c, angleAt(nextCorner(c)));
      } else if (c < o) {
        fans.addGluedSides(topology.vertex(nextCorner(c)), topology.vertex(prevCorner(c)), c, o, angleAt(nextCorner(c)),
                           angleAt(nextCorner(o)));
      }
    }
    EXPECT_EQ(countWoundFans(fans), expected) << seed;
  }
}

}  // namespace
}  // namespace seamvox
