// Corner table and components: invariants on meshes built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <unordered_map>

#include "core/mesh/clean.h"
#include "core/mesh/detail_id_map.h"
#include "core/system/errors.h"
#include "core/mesh/hole_caps.h"
#include "core/mesh/topology.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::concatMeshes;
using testing::cylinderMesh;
using testing::gridMesh;
using testing::icosphereMesh;
using testing::shuffledMesh;
using testing::torusWithIslands;
using testing::torusMesh;

Topology buildOf(const TriangleMesh& mesh) { return Topology::build(mesh.triangles, mesh.numVertices()); }

/// Checks the corner-table conventions of topology.h on every corner and vertex.
void expectConventions(const Topology& t) {
  ASSERT_NO_THROW(t.validate());
  for (CornerId c = 0; c < t.numCorners(); ++c) {
    const CornerId o = t.opposite(c);
    if (o == kInvalidId) continue;
    EXPECT_EQ(t.opposite(o), c);
    EXPECT_EQ(t.vertex(nextCorner(c)), t.vertex(prevCorner(o)));
    const CornerId around = t.ccw(prevCorner(c));
    if (around != kInvalidId) EXPECT_EQ(t.vertex(around), t.vertex(prevCorner(c)));
  }
  for (VertexId v = 0; v < t.numVertices(); ++v) {
    if (t.isIsolatedVertex(v)) continue;
    std::uint32_t n = 0;
    t.forEachCornerAround(v, [&](CornerId c) {
      EXPECT_EQ(t.vertex(c), v);
      ++n;
    });
    EXPECT_EQ(n, t.valence(v));
    if (t.isBoundaryVertex(v)) EXPECT_EQ(t.cw(t.vertexCorner(v)), kInvalidId);
  }
}

TEST(Topology, GridIsADisk) {
  const TriangleMesh mesh = gridMesh(5, 4);
  const Topology t = buildOf(mesh);
  expectConventions(t);
  const ComponentsResult comps = computeComponents(t);
  ASSERT_EQ(comps.components.size(), 1u);
  EXPECT_EQ(comps.components[0].boundaryLoops, 1u);
  EXPECT_EQ(comps.components[0].eulerCharacteristic, 1);
  EXPECT_EQ(comps.components[0].genus, 0);
  // Interior vertex of a regular grid split this way has valence 6, a corner valence 1 or 2.
  EXPECT_EQ(t.valence(1 * 6 + 1), 6u);
  EXPECT_TRUE(t.isBoundaryVertex(0));
  EXPECT_FALSE(t.isBoundaryVertex(1 * 6 + 1));
}

TEST(Topology, ClosedSurfacesHaveTheirGenus) {
  const Topology sphere = buildOf(icosphereMesh(2));
  expectConventions(sphere);
  auto c = computeComponents(sphere).components.at(0);
  EXPECT_EQ(c.eulerCharacteristic, 2);
  EXPECT_EQ(c.boundaryLoops, 0u);
  EXPECT_EQ(c.genus, 0);

  const Topology torus = buildOf(torusMesh(12, 8));
  expectConventions(torus);
  c = computeComponents(torus).components.at(0);
  EXPECT_EQ(c.eulerCharacteristic, 0);
  EXPECT_EQ(c.genus, 1);
}

TEST(Topology, CylinderHasTwoBoundaryLoops) {
  const Topology t = buildOf(cylinderMesh(10, 3));
  expectConventions(t);
  const auto c = computeComponents(t).components.at(0);
  EXPECT_EQ(c.boundaryLoops, 2u);
  EXPECT_EQ(c.eulerCharacteristic, 0);
  EXPECT_EQ(c.genus, 0);
}

// Walking a loop by nextBoundaryCorner: each boundary edge once, consecutive edges share their
// vertex, and the interior edges crossed are those at the loop's vertices (grid n x m: every
// interior edge with one end on the boundary, each crossed once).
TEST(Topology, NextBoundaryCornerWalksEachLoopOnce) {
  const int n = 5, m = 4;
  const Topology t = buildOf(gridMesh(n, m));
  CornerId start = kInvalidId;
  std::uint32_t boundaryEdges = 0;
  for (CornerId c = 0; c < t.numCorners(); ++c) {
    if (!t.isBoundaryEdge(c)) continue;
    ++boundaryEdges;
    if (start == kInvalidId) start = c;
  }
  ASSERT_NE(start, kInvalidId);
  std::vector<CornerId> crossed;
  std::uint32_t steps = 0;
  CornerId c = start;
  do {
    const CornerId next = nextBoundaryCorner(t, c, &crossed);
    ASSERT_TRUE(t.isBoundaryEdge(next));
    EXPECT_EQ(t.vertex(prevCorner(c)), t.vertex(nextCorner(next)));  // the edges chain head to tail
    c = next;
    ASSERT_LE(++steps, boundaryEdges);
  } while (c != start);
  EXPECT_EQ(steps, boundaryEdges);
  EXPECT_EQ(boundaryEdges, 2u * (n + m));
  std::uint32_t interiorAtBoundary = 0;  // interior edges with at least one boundary end
  for (CornerId e = 0; e < t.numCorners(); ++e) {
    if (t.isBoundaryEdge(e) || t.opposite(e) < e) continue;
    if (t.isBoundaryVertex(t.vertex(nextCorner(e))) || t.isBoundaryVertex(t.vertex(prevCorner(e)))) ++interiorAtBoundary;
  }
  for (CornerId e : crossed) EXPECT_FALSE(t.isBoundaryEdge(e));
  // An edge with both ends on the boundary is crossed from each end.
  std::uint32_t bothEnds = 0;
  for (CornerId e = 0; e < t.numCorners(); ++e) {
    if (t.isBoundaryEdge(e) || t.opposite(e) < e) continue;
    if (t.isBoundaryVertex(t.vertex(nextCorner(e))) && t.isBoundaryVertex(t.vertex(prevCorner(e)))) ++bothEnds;
  }
  EXPECT_EQ(crossed.size(), interiorAtBoundary + bothEnds);
}

// Capping small holes in place: a sphere with one-triangle holes becomes closed again (Euler
// characteristic 2; its corner table equals the one built from scratch), the original faces and
// vertices keep their ids, uncapping gives the table back as it was, and holes larger than the
// extent stay open. On a table that views the triangles and on one that owns them.
TEST(Topology, CapSmallHolesClosesEachSmallLoop) {
  const TriangleMesh holed = testing::withOneTriangleHoles(icosphereMesh(3), 17);
  const Topology original = buildOf(holed);
  const std::uint32_t loops = computeComponents(original).boundaryLoops;
  ASSERT_GE(loops, 10u);
  for (const bool view : {true, false}) {
    SCOPED_TRACE(view ? "viewing" : "owning");
    TriangleMesh mesh = holed;
    Topology t = original;  // owns a copy of the faces
    if (view) {
      std::vector<CornerId> opposite, starts;
      for (CornerId c = 0; c < original.numCorners(); ++c) opposite.push_back(original.opposite(c));
      for (VertexId v = 0; v < original.numVertices(); ++v) starts.push_back(original.vertexCorner(v));
      t = Topology::viewParts(mesh.triangles, std::move(opposite), std::move(starts));
    }
    const CappedHoles caps = capSmallHoles(mesh, t, 1.0);  // the unit sphere's holes are small
    EXPECT_EQ(caps.holes, loops);
    EXPECT_EQ(mesh.numVertices(), holed.numVertices() + loops);
    EXPECT_EQ(mesh.numFaces(), holed.numFaces() + 3 * loops);
    for (FaceId f = 0; f < holed.numFaces(); ++f) ASSERT_EQ(mesh.triangles[f], holed.triangles[f]);
    t.validate();
    const Topology built = buildOf(mesh);
    for (CornerId c = 0; c < t.numCorners(); ++c) ASSERT_EQ(t.opposite(c), built.opposite(c)) << c;
    for (VertexId v = 0; v < t.numVertices(); ++v) ASSERT_EQ(t.vertexCorner(v), built.vertexCorner(v)) << v;
    const ComponentsResult capped = computeComponents(t);
    ASSERT_EQ(capped.components.size(), 1u);
    EXPECT_EQ(capped.boundaryLoops, 0u);
    EXPECT_EQ(capped.components[0].eulerCharacteristic, 2);
    uncapHoles(mesh, t, caps);
    ASSERT_EQ(mesh.triangles, holed.triangles);
    ASSERT_EQ(mesh.positions, holed.positions);
    ASSERT_EQ(t.numFaces(), original.numFaces());
    ASSERT_EQ(t.numVertices(), original.numVertices());
    for (CornerId c = 0; c < t.numCorners(); ++c) ASSERT_EQ(t.opposite(c), original.opposite(c)) << c;
    for (VertexId v = 0; v < t.numVertices(); ++v) ASSERT_EQ(t.vertexCorner(v), original.vertexCorner(v)) << v;
    for (FaceId f = 0; f < t.numFaces(); ++f) ASSERT_EQ(t.triangles()[f], holed.triangles[f]);
    EXPECT_EQ(capSmallHoles(mesh, t, 1e-6).holes, 0u);  // smaller than any hole
    EXPECT_EQ(mesh.numFaces(), holed.numFaces());
  }
  // An island's own outline and a hole whose cap would be flat are not capped.
  TriangleMesh island;
  island.positions = {Vec3f(3.0f, 0.0f, 0.0f), Vec3f(3.01f, 0.0f, 0.0f), Vec3f(3.0f, 0.01f, 0.0f)};
  island.triangles = {{0, 1, 2}};
  TriangleMesh withIsland = testing::concatMeshes({holed, island});
  Topology t2 = buildOf(withIsland);
  EXPECT_EQ(computeComponents(t2).boundaryLoops, loops + 1);
  EXPECT_EQ(capSmallHoles(withIsland, t2, 1.0).holes, loops);
}

TEST(Topology, ComponentsAreSortedBySize) {
  const TriangleMesh mesh = concatMeshes({gridMesh(2, 2), torusMesh(10, 6), icosphereMesh(1)});
  const Topology t = buildOf(mesh);
  const ComponentsResult r = computeComponents(t);
  ASSERT_EQ(r.components.size(), 3u);
  EXPECT_EQ(r.components[0].faces, 120u);  // torus
  EXPECT_EQ(r.components[0].genus, 1);
  EXPECT_EQ(r.components[1].faces, 80u);   // icosphere
  EXPECT_EQ(r.components[2].faces, 8u);    // grid
  EXPECT_EQ(r.boundaryLoops, 1u);
  EXPECT_EQ(r.faceComponent[0], 2u);
}

// computeComponents against a breadth-first search seeded at the first face not reached yet:
// components numbered in that order, then stably sorted by size. Many islands of equal sizes
// (ties) with faces shuffled, so that every component's faces and smallest face are scattered
// over the blocks of both cores.
TEST(Topology, ComponentsAsASearchFromTheFirstFaceNotReached) {
  const TriangleMesh mesh = shuffledMesh(torusWithIslands(60, 20, 300, 0.05, 2, 0.3f, 4), 9);
  const Topology t = buildOf(mesh);
  const std::uint32_t nf = t.numFaces();
  std::vector<std::uint32_t> order(nf, kInvalidId), sizes;
  std::vector<FaceId> queue;
  for (FaceId seed = 0; seed < nf; ++seed) {
    if (order[seed] != kInvalidId) continue;
    const auto id = static_cast<std::uint32_t>(sizes.size());
    queue.assign(1, seed);
    order[seed] = id;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      for (int k = 0; k < 3; ++k) {
        const CornerId o = t.opposite(3 * queue[head] + k);
        if (o != kInvalidId && order[o / 3] == kInvalidId) order[o / 3] = id, queue.push_back(o / 3);
      }
    }
    sizes.push_back(static_cast<std::uint32_t>(queue.size()));
  }
  std::vector<std::uint32_t> byId(sizes.size()), rank(sizes.size());
  std::iota(byId.begin(), byId.end(), 0u);
  std::stable_sort(byId.begin(), byId.end(), [&](std::uint32_t a, std::uint32_t b) { return sizes[a] > sizes[b]; });
  for (std::uint32_t i = 0; i < byId.size(); ++i) rank[byId[i]] = i;
  for (std::uint32_t& id : order) id = rank[id];
  ASSERT_GT(sizes.size(), 250u);
  std::map<std::uint32_t, int> ofSize;
  for (std::uint32_t n : sizes) ++ofSize[n];
  ASSERT_GT(ofSize.begin()->second, 50) << "the test needs ties";
  const ComponentsResult r = computeComponents(t);
  ASSERT_EQ(r.components.size(), sizes.size());
  EXPECT_EQ(r.faceComponent, order);
  // Vertices and edges per component; the specks (at most 8 faces) are disks, the torus (the
  // largest) has genus 1, the ball genus 0.
  std::vector<std::uint32_t> vertices(sizes.size(), 0);
  std::vector<std::uint64_t> edges(sizes.size(), 0);
  for (VertexId v = 0; v < t.numVertices(); ++v) {
    if (!t.isIsolatedVertex(v)) ++vertices[order[t.vertexCorner(v) / 3]];
  }
  for (CornerId c = 0; c < t.numCorners(); ++c) edges[order[c / 3]] += t.opposite(c) == kInvalidId || c < t.opposite(c);
  std::uint32_t loops = 0;
  for (std::uint32_t i = 0; i < byId.size(); ++i) {
    const ComponentInfo& info = r.components[i];
    EXPECT_EQ(info.faces, sizes[byId[i]]);
    EXPECT_EQ(info.vertices, vertices[i]);
    EXPECT_EQ(info.edges, edges[i]);
    EXPECT_EQ(info.boundaryLoops, info.faces <= 8 ? 1u : 0u) << i;
    EXPECT_EQ(info.genus, i == 0 ? 1 : 0) << i;
    loops += info.faces <= 8;
  }
  EXPECT_EQ(r.boundaryLoops, loops);
}

TEST(Topology, BuildRejectsNonManifoldInput) {
  TriangleMesh fin;  // three faces on edge 0-1
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  EXPECT_THROW(buildOf(fin), TopologyError);

  TriangleMesh bowtie;  // two faces touching at vertex 0 only
  bowtie.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  bowtie.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_THROW(buildOf(bowtie), TopologyError);

  TriangleMesh clash;  // both faces traverse 0 -> 1
  clash.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  clash.triangles = {{0, 1, 2}, {0, 1, 3}};
  EXPECT_THROW(buildOf(clash), TopologyError);

  TriangleMesh outOfRange = gridMesh(1, 1);
  outOfRange.triangles[1][2] = 99;
  try {
    buildOf(outOfRange);
    FAIL() << "expected TopologyError";
  } catch (const TopologyError& e) {
    EXPECT_NE(std::string(e.what()).find("face 1"), std::string::npos) << e.what();
  }
}

struct SharedTopology {
  const char* file;
  std::uint32_t components, boundaryLoops;
  std::int64_t genus;
};

class SharedMeshTopology : public ::testing::TestWithParam<SharedTopology> {};

TEST_P(SharedMeshTopology, HasTheExpectedComponentsLoopsAndGenus) {
  const SharedTopology expected = GetParam();
  const std::string path = testing::sharedMesh(expected.file);
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage(expected.file);
  CleanResult r = cleanMesh(readMesh(path));
  expectConventions(r.topology);
  const ComponentsResult comps = computeComponents(r.topology);
  ASSERT_EQ(comps.components.size(), expected.components) << expected.file;
  EXPECT_EQ(comps.boundaryLoops, expected.boundaryLoops) << expected.file;
  EXPECT_EQ(comps.components[0].genus, expected.genus) << expected.file;
  EXPECT_EQ(r.report.nonManifoldEdges + r.report.nonManifoldVertices, 0u) << expected.file;
  if (std::string(expected.file) == "fertility.off") {
    EXPECT_EQ(r.mesh.numVertices(), 4494u);
    EXPECT_EQ(r.mesh.numFaces(), 9000u);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Shared, SharedMeshTopology,
    ::testing::Values(SharedTopology{"fertility.off", 1, 0, 4}, SharedTopology{"3holes.off", 1, 0, 3},
                      SharedTopology{"bunny.off", 1, 0, 0}, SharedTopology{"camelhead.off", 1, 1, 0},
                      SharedTopology{"lilium.obj", 1, 1, 0}, SharedTopology{"rocker-arm.obj", 1, 0, 1},
                      SharedTopology{"cheburashka.off", 1, 0, 0}, SharedTopology{"bumpy.off", 1, 0, 0},
                      SharedTopology{"spot.obj", 1, 0, 0}, SharedTopology{"armadillo.obj", 1, 0, 0}),
    [](const ::testing::TestParamInfo<SharedTopology>& info) {
      std::string name = info.param.file;
      for (char& ch : name) {
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      }
      return name;
    });

// IdMap against std::unordered_map: clustered and scattered keys through several growths,
// missing keys, overwrites, and every entry visited once.
TEST(IdMap, AgreesWithAStandardMap) {
  detail::IdMap map;
  std::unordered_map<std::uint32_t, std::uint32_t> reference;
  std::uint64_t state = 12345;
  for (std::uint32_t n = 0; n < 50000; ++n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    // Half the keys in a run of ids (as a region's vertices are), half anywhere below kEmpty.
    const std::uint32_t key = n % 2 ? 1000000 + n / 2 : static_cast<std::uint32_t>(state >> 33) % 0xfffffff0u;
    const auto [value, added] = map.emplace(key, n);
    const auto [it, refAdded] = reference.emplace(key, n);
    ASSERT_EQ(added, refAdded) << key;
    ASSERT_EQ(value, it->second) << key;
    if (n % 7 == 0) {
      map.set(key, n + 1);
      it->second = n + 1;
    }
  }
  EXPECT_EQ(map.size(), reference.size());
  for (const auto& [key, value] : reference) EXPECT_EQ(map.find(key), value);
  EXPECT_EQ(map.find(999999), detail::IdMap::kEmpty);
  EXPECT_EQ(map.find(0xfffffff5u), detail::IdMap::kEmpty);
  std::size_t visited = 0;
  map.forEach([&](std::uint32_t key, std::uint32_t value) {
    ++visited;
    EXPECT_EQ(reference.at(key), value);
  });
  EXPECT_EQ(visited, reference.size());
  ASSERT_EQ(reference.count(17), 0u);
  map.set(17, 3);  // set inserts a new key
  EXPECT_EQ(map.find(17), 3u);
  EXPECT_EQ(map.size(), reference.size() + 1);
}

}  // namespace
}  // namespace seamvox
