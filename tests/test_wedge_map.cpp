// The per-wedge map: compression of per-corner values, corner edits against a plain per-corner
// model, and the cut's wedges against the hat basis' domains.
#include <gtest/gtest.h>

#include <algorithm>
#include <complex>
#include <random>
#include <vector>

#include "core/basis/basis.h"
#include "core/cut/cut.h"
#include "core/system/errors.h"
#include "core/solve/evaluate.h"
#include "core/field/field.h"
#include "core/mesh/topology.h"
#include "core/mesh/wedge_map.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::cornerValues;

/// (x, y) of each corner's vertex, plus `shift` in u on the faces right of x = seamX.
std::vector<Vec2d> planarValues(const TriangleMesh& mesh, double seamX, double shift) {
  std::vector<Vec2d> values(3 * mesh.triangles.size());
  for (std::size_t c = 0; c < values.size(); ++c) {
    const Triangle& t = mesh.triangles[c / 3];
    double cx = 0.0;
    for (VertexId v : t) cx += mesh.positions[v].x() / 3.0;
    const Vec3d p = mesh.position(t[c % 3]);
    values[c] = Vec2d(p.x() + (cx > seamX ? shift : 0.0), p.y());
  }
  return values;
}

TEST(WedgeMap, PerCornerValuesShareOneWedgePerVertexAndValue) {
  const TriangleMesh mesh = testing::gridMesh(6, 4);
  const std::vector<Vec2d> continuous = planarValues(mesh, 1e9, 0.0);
  const WedgeMap one = WedgeMap::fromCorners(mesh.triangles, continuous);
  EXPECT_EQ(one.size(), continuous.size());
  EXPECT_EQ(one.numWedges(), mesh.numVertices());
  EXPECT_EQ(cornerValues(one), continuous);
  // A seam along x = 3: the 5 vertices on it get a second wedge.
  const std::vector<Vec2d> seam = planarValues(mesh, 3.0, 7.0);
  const WedgeMap two = WedgeMap::fromCorners(mesh.triangles, seam);
  EXPECT_EQ(two.numWedges(), mesh.numVertices() + 5);
  EXPECT_EQ(cornerValues(two), seam);
  for (CornerId c = 0; c < two.size(); ++c) {
    EXPECT_EQ(two[c], two.wedgeValue(two.wedge(c)));
  }
  EXPECT_LT(two.memoryBytes(), seam.size() * sizeof(Vec2d));
  EXPECT_THROW(WedgeMap::fromCorners(mesh.triangles, std::vector<Vec2d>(5)), InputError);
  EXPECT_THROW(WedgeMap({0, 2}, {Vec2d::Zero()}), InputError);
}

TEST(WedgeMap, BuilderKeepsCornersOfUnknownVerticesApart) {
  WedgeMapBuilder builder;
  builder.add(3, Vec2d(1, 2));
  builder.add(kInvalidId, Vec2d(1, 2));
  builder.add(3, Vec2d(1, 2));
  builder.add(0, Vec2d(1, 2));  // another vertex: another wedge, whatever the value
  const WedgeMap map = builder.finish();
  EXPECT_EQ(map.size(), 4u);
  EXPECT_EQ(map.numWedges(), 3u);
  EXPECT_EQ(map.wedge(0), map.wedge(2));
  EXPECT_NE(map.wedge(0), map.wedge(1));
  EXPECT_NE(map.wedge(0), map.wedge(3));
  EXPECT_EQ(builder.size(), 0u);
}

TEST(WedgeMap, WholeWedgesChangeInPlaceAndPartlyChangedWedgesSplit) {
  const TriangleMesh mesh = testing::gridMesh(4, 4);
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  WedgeMap map = WedgeMap::fromCorners(mesh.triangles, planarValues(mesh, 1e9, 0.0));
  const std::uint32_t wedges = map.numWedges();
  // Every corner of the interior vertex 6 gets one new value: the wedge keeps its id.
  std::vector<CornerId> corners;
  topology.forEachCornerAround(6, [&](CornerId c) { corners.push_back(c); });
  ASSERT_GT(corners.size(), 2u);
  const std::uint32_t w = map.wedge(corners[0]);
  map.assign(corners, std::vector<Vec2d>(corners.size(), Vec2d(-5, 5)));
  EXPECT_EQ(map.numWedges(), wedges);
  for (CornerId c : corners) {
    EXPECT_EQ(map.wedge(c), w);
    EXPECT_EQ(map[c], Vec2d(-5, 5));
  }
  // Two of its corners get another value: one new wedge for both, the rest keep theirs.
  map.assign({corners[0], corners[1]}, {Vec2d(8, 8), Vec2d(8, 8)});
  EXPECT_EQ(map.numWedges(), wedges + 1);
  EXPECT_EQ(map.wedge(corners[0]), map.wedge(corners[1]));
  EXPECT_EQ(map[corners[0]], Vec2d(8, 8));
  EXPECT_EQ(map[corners[2]], Vec2d(-5, 5));
  EXPECT_EQ(map.wedge(corners[2]), w);
  // set: unchanged value keeps the wedge; a new one moves the corner alone.
  map.set(corners[2], Vec2d(-5, 5));
  EXPECT_EQ(map.wedge(corners[2]), w);
  map.set(corners[2], Vec2d(1, 1));
  EXPECT_NE(map.wedge(corners[2]), w);
  EXPECT_EQ(map[corners[2]], Vec2d(1, 1));
  EXPECT_EQ(map[corners.back()], Vec2d(-5, 5));
  EXPECT_THROW(map.assign({CornerId(map.size())}, {Vec2d::Zero()}), InputError);
  EXPECT_THROW(map.assign({0, 1}, {Vec2d::Zero()}), InputError);
}

// Also the assignment that counts wedges' corners around their vertices: the same wedges.
TEST(WedgeMap, RandomEditsMatchAPerCornerModel) {
  const TriangleMesh mesh = testing::torusMesh(10, 6);
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  std::vector<Vec2d> model = planarValues(mesh, 0.0, 3.0);
  WedgeMap map = WedgeMap::fromCorners(mesh.triangles, model);
  WedgeMap counted = map;
  std::mt19937 rng(7);
  std::uniform_int_distribution<CornerId> corner(0, CornerId(model.size() - 1));
  std::uniform_int_distribution<int> value(0, 3), count(1, 40);
  for (int round = 0; round < 200; ++round) {
    std::vector<CornerId> corners;
    std::vector<Vec2d> values;
    const int n = count(rng);
    for (int k = 0; k < n; ++k) {
      // Whole fans of one vertex now and then (the refinement's case), single corners otherwise.
      const CornerId c = corner(rng);
      const Vec2d q(value(rng), 0.5);
      const VertexId v = mesh.triangles[c / 3][c % 3];
      for (CornerId d = 0; d < model.size(); ++d) {
        if (d == c || (round % 3 == 0 && mesh.triangles[d / 3][d % 3] == v)) {
          corners.push_back(d);
          values.push_back(q);
        }
      }
    }
    if (round % 5 == 4) {
      map.set(corners[0], values[0]);
      counted.set(corners[0], values[0]);
      model[corners[0]] = values[0];
      continue;
    }
    map.assign(corners, values);
    counted.assign(corners, values, topology);
    for (std::size_t k = 0; k < corners.size(); ++k) model[corners[k]] = values[k];  // last wins
    ASSERT_EQ(cornerValues(map), model) << "round " << round;
    ASSERT_EQ(counted.numWedges(), map.numWedges()) << "round " << round;
    for (CornerId c = 0; c < map.size(); ++c) ASSERT_EQ(counted.wedge(c), map.wedge(c)) << "round " << round;
  }
  EXPECT_EQ(cornerValues(map), model);
  const Topology other = Topology::build(testing::torusMesh(8, 6).triangles, 48);
  EXPECT_THROW(counted.assign({0}, {Vec2d::Zero()}, other), InputError);
}

// The smallest corner of each wedge, over both cores: a plain scan's, on a shuffled mesh whose
// vertices have corners in many blocks, in ranges of wedges and whole, per corner and viewing.
TEST(WedgeMap, WedgeCornersAreTheSmallestCorners) {
  const TriangleMesh mesh = testing::shuffledMesh(testing::gridMesh(300, 200), 4);
  std::vector<Vec2d> values(3 * mesh.numFaces());
  for (CornerId c = 0; c < values.size(); ++c) {
    const VertexId v = mesh.triangles[c / 3][c % 3];
    values[c] = Vec2d(v % 97, (c % 5 == 0 && v % 29 == 0) ? 1.0 : 0.0);  // some vertices split in two
  }
  WedgeMap perCorner = WedgeMap::fromCorners(mesh.triangles, values);
  WedgeMap viewing = perCorner;
  ASSERT_TRUE(viewing.viewTriangles(mesh.triangles.data(), mesh.numVertices()));
  std::vector<CornerId> expected(perCorner.numWedges(), kInvalidId);
  for (CornerId c = 0; c < perCorner.size(); ++c) expected[perCorner.wedge(c)] = std::min(expected[perCorner.wedge(c)], c);
  ASSERT_GT(perCorner.size(), 5u << 16) << "the test needs many blocks";
  ASSERT_GT(perCorner.numWedges(), mesh.numVertices());
  for (const WedgeMap* map : {&perCorner, &viewing}) {
    EXPECT_EQ(map->wedgeCorners(), expected);
    const std::uint32_t step = 7919;
    for (std::uint32_t begin = 0; begin < map->numWedges(); begin += step) {
      const std::vector<CornerId> part = map->wedgeCorners(begin, begin + step);
      ASSERT_EQ(part, std::vector<CornerId>(expected.begin() + begin,
                                            expected.begin() + std::min<std::size_t>(expected.size(), begin + step)));
    }
  }
}

// Wedge ids kept per vertex over the mesh's triangles: the same values under the same edits as
// ids per corner, copies and corner-table edits back per corner, and many split corners too.
TEST(WedgeMap, OverTrianglesMatchesIdsPerCorner) {
  const TriangleMesh mesh = testing::gridMesh(60, 40);
  const std::vector<Vec2d> start = planarValues(mesh, 30.0, 7.0);
  WedgeMap perCorner = WedgeMap::fromCorners(mesh.triangles, start);
  WedgeMap viewing = perCorner;
  ASSERT_TRUE(viewing.viewTriangles(mesh.triangles.data(), mesh.numVertices()));
  ASSERT_TRUE(viewing.viewsTriangles());
  EXPECT_FALSE(perCorner.viewsTriangles());
  EXPECT_EQ(viewing.size(), perCorner.size());
  EXPECT_LT(2 * viewing.memoryBytes(), perCorner.memoryBytes() + 16 * perCorner.numWedges());
  for (CornerId c = 0; c < perCorner.size(); ++c) ASSERT_EQ(viewing.wedge(c), perCorner.wedge(c)) << "corner " << c;
  EXPECT_EQ(viewing.wedgeCorners(), perCorner.wedgeCorners());
  std::mt19937 rng(11);
  std::uniform_int_distribution<CornerId> corner(0, CornerId(start.size() - 1));
  std::uniform_int_distribution<int> value(0, 3), count(1, 30);
  for (int round = 0; round < 60; ++round) {
    std::vector<CornerId> corners;
    std::vector<Vec2d> values;
    for (int k = count(rng); k > 0; --k) {
      corners.push_back(corner(rng));
      values.push_back(Vec2d(value(rng), 0.25));
    }
    if (round % 4 == 3) {
      perCorner.set(corners[0], values[0]);
      viewing.set(corners[0], values[0]);
    } else {
      perCorner.assign(corners, values);
      viewing.assign(corners, values);
    }
    ASSERT_EQ(cornerValues(viewing), cornerValues(perCorner)) << "round " << round;
    ASSERT_EQ(viewing.numWedges(), perCorner.numWedges()) << "round " << round;
  }
  EXPECT_TRUE(viewing.viewsTriangles());
  // A copy holds ids per corner; so does the map after a corner-table edit.
  const WedgeMap copy = viewing;
  EXPECT_FALSE(copy.viewsTriangles());
  EXPECT_EQ(cornerValues(copy), cornerValues(perCorner));
  WedgeMap edited = viewing;
  ASSERT_TRUE(edited.viewTriangles(mesh.triangles.data(), mesh.numVertices()));
  edited.keepCorners(300);
  perCorner.keepCorners(300);
  EXPECT_FALSE(edited.viewsTriangles());
  EXPECT_EQ(cornerValues(edited), cornerValues(perCorner));
  EXPECT_EQ(edited.numWedges(), perCorner.numWedges());
  // Most corners split from their vertex's wedge: back to ids per corner, the same values.
  std::vector<CornerId> all(viewing.size());
  std::vector<Vec2d> distinct(viewing.size());
  for (CornerId c = 0; c < all.size(); ++c) all[c] = c, distinct[c] = Vec2d(c, -1.0);
  viewing.assign(all, distinct);
  EXPECT_FALSE(viewing.viewsTriangles());
  EXPECT_EQ(cornerValues(viewing), distinct);
  // Ids out of range are refused.
  EXPECT_THROW(WedgeMap::overTriangles(mesh.triangles.data(), 3, {0, 5, 0, 0, 0, 0, 0, 0}, {}, {Vec2d::Zero()}),
               InputError);
  EXPECT_THROW(WedgeMap::overTriangles(mesh.triangles.data(), 3, std::vector<std::uint32_t>(mesh.numVertices(), 0),
                                       {{1, 4}}, {Vec2d::Zero()}),
               InputError);
}

TEST(WedgeMap, CutWedgesAreTheHatDomains) {
  const testing::Surface s = testing::makeSurface(testing::icosphereMesh(2));
  const CrossField field = testing::randomField(s.mesh, 3);
  const CutResult cut = cutToDisk(s.mesh, s.topology, field, computeSingularities(s.mesh, s.topology, field));
  ASSERT_FALSE(cut.seams.empty());
  const WedgeMap wedges = buildCutWedges(s.topology, cut);
  ASSERT_EQ(wedges.size(), s.topology.numCorners());
  EXPECT_GT(wedges.numWedges(), s.topology.numVertices());
  // Around each vertex: the same wedge across a non-cut edge, another one across a cut edge
  // unless the vertex has a single cut edge; wedges are numbered vertex by vertex.
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    std::uint32_t cuts = 0;
    s.topology.forEachCornerAround(v, [&](CornerId c) {
      const CornerId next = s.topology.ccw(c);
      cuts += cut.corners.isCut(nextCorner(c));
      if (next == kInvalidId) return;
      if (!cut.corners.isCut(nextCorner(c))) EXPECT_EQ(wedges.wedge(c), wedges.wedge(next)) << "vertex " << v;
    });
    std::vector<std::uint32_t> seen;
    s.topology.forEachCornerAround(v, [&](CornerId c) {
      if (std::find(seen.begin(), seen.end(), wedges.wedge(c)) == seen.end()) seen.push_back(wedges.wedge(c));
    });
    EXPECT_EQ(seen.size(), std::max(1u, cuts)) << "vertex " << v;
  }
  // One to one with the hat basis' domains, and its evaluation gives each corner its domain's
  // coefficient.
  const HatBasis basis(s.mesh, s.topology, field, cut);
  ASSERT_EQ(basis.numDomains(), wedges.numWedges());
  std::vector<std::uint32_t> domainOf(wedges.numWedges(), kInvalidId);
  for (CornerId c = 0; c < wedges.size(); ++c) {
    std::uint32_t& d = domainOf[wedges.wedge(c)];
    if (d == kInvalidId) d = basis.cornerDomain()[c];
    ASSERT_EQ(d, basis.cornerDomain()[c]) << "corner " << c;
  }
  std::vector<std::complex<double>> coefficients(basis.numDomains());
  for (std::uint32_t d = 0; d < coefficients.size(); ++d) coefficients[d] = {double(d), -0.5 * d};
  WedgeMap map = wedges;
  basis.evaluateCorners(coefficients, map);
  for (CornerId c = 0; c < map.size(); ++c) {
    const std::complex<double> q = coefficients[basis.cornerDomain()[c]];
    ASSERT_EQ(map[c], Vec2d(q.real(), q.imag())) << "corner " << c;
  }
  WedgeMap wrong;
  EXPECT_THROW(basis.evaluateCorners(coefficients, wrong), InputError);
}

}  // namespace
}  // namespace seamvox
