// Corner table, components and cleaning: invariants on meshes built in code.
#include <gtest/gtest.h>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
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

TEST(Clean, RemovesDegenerateDuplicateAndUnreferenced) {
  TriangleMesh mesh = gridMesh(3, 3);
  const std::uint32_t faces = mesh.numFaces();
  mesh.triangles.push_back(mesh.triangles[4]);                       // exact duplicate
  const Triangle t = mesh.triangles[7];
  mesh.triangles.push_back({t[0], t[2], t[1]});                      // reversed duplicate
  mesh.triangles.push_back({t[0], t[0], t[1]});                      // degenerate
  mesh.positions.emplace_back(9.f, 9.f, 9.f);                        // unreferenced
  const CleanResult r = cleanMesh(std::move(mesh));
  EXPECT_EQ(r.report.duplicateFaces, 2u);
  EXPECT_EQ(r.report.degenerateFaces, 1u);
  EXPECT_EQ(r.report.unreferencedVertices, 1u);
  EXPECT_EQ(r.mesh.numFaces(), faces);
  EXPECT_EQ(r.mesh.numVertices(), 16u);
  ASSERT_EQ(r.faceOrigin.size(), faces);
  for (FaceId f = 0; f < faces; ++f) EXPECT_EQ(r.faceOrigin[f], f);
  expectConventions(r.topology);
}

TEST(Clean, WeldsCoincidentVertices) {
  // Two halves of a grid with their shared column duplicated: two components until welded.
  TriangleMesh left = gridMesh(2, 3), right = gridMesh(2, 3);
  for (Vec3f& p : right.positions) p.x() += 2.f;
  const TriangleMesh soup = concatMeshes({left, right});
  EXPECT_EQ(computeComponents(buildOf(soup)).components.size(), 2u);

  CleanOptions weld;
  weld.weldVertices = true;
  CleanResult r = cleanMesh(soup, weld);
  EXPECT_EQ(r.report.weldedVertices, 4u);
  EXPECT_EQ(r.mesh.numVertices(), 5u * 4u);
  const ComponentsResult comps = computeComponents(r.topology);
  ASSERT_EQ(comps.components.size(), 1u);
  EXPECT_EQ(comps.components[0].boundaryLoops, 1u);
  expectConventions(r.topology);

  // With noise below the tolerance, welding needs the tolerance.
  TriangleMesh noisy = soup;
  for (VertexId v = right.numVertices() - 0; v < noisy.numVertices(); ++v) noisy.positions[v].y() += 1e-6f;
  EXPECT_EQ(cleanMesh(noisy, weld).report.weldedVertices, 0u);
  weld.weldTolerance = 1e-4;
  r = cleanMesh(noisy, weld);
  EXPECT_EQ(r.report.weldedVertices, 4u);
  EXPECT_EQ(computeComponents(r.topology).components.size(), 1u);
}

TEST(Clean, SplitsNonManifoldEdgesAndVertices) {
  TriangleMesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  CleanResult r = cleanMesh(fin);
  EXPECT_EQ(r.report.nonManifoldEdges, 1u);
  expectConventions(r.topology);
  EXPECT_EQ(r.mesh.numFaces(), 3u);

  TriangleMesh bowtie;
  bowtie.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  bowtie.triangles = {{0, 1, 2}, {0, 3, 4}};
  r = cleanMesh(bowtie);
  EXPECT_EQ(r.report.nonManifoldVertices, 1u);
  EXPECT_EQ(r.mesh.numVertices(), 6u);
  EXPECT_EQ(r.vertexOrigin[5], 0u);
  EXPECT_EQ(r.mesh.positions[5], r.mesh.positions[0]);
  expectConventions(r.topology);
  EXPECT_EQ(computeComponents(r.topology).components.size(), 2u);
}

TEST(Clean, OrientsFacesConsistently) {
  TriangleMesh torus = torusMesh(12, 8);
  std::vector<Vec2d> values(3 * torus.numFaces());
  for (CornerId c = 0; c < values.size(); ++c) values[c] = Vec2d(torus.triangles[c / 3][c % 3], 0.5);
  torus.cornerUV = WedgeMap::fromCorners(torus.triangles, values);
  EXPECT_EQ(torus.cornerUV.numWedges(), torus.numVertices());
  for (FaceId f : {3u, 40u, 41u, 100u}) {
    std::swap(torus.triangles[f][1], torus.triangles[f][2]);
    torus.cornerUV.swapCorners(3 * f + 1, 3 * f + 2);
  }
  const CleanResult r = cleanMesh(torus);
  EXPECT_EQ(r.report.flippedFaces, 4u);
  EXPECT_EQ(r.report.nonManifoldEdges, 0u);
  expectConventions(r.topology);
  EXPECT_EQ(computeComponents(r.topology).components.at(0).genus, 1);
  // The UV of each corner still belongs to its vertex.
  for (CornerId c = 0; c < r.topology.numCorners(); ++c) {
    EXPECT_EQ(r.mesh.cornerUV[c].x(), double(r.vertexOrigin[r.topology.vertex(c)]));
  }
}

TEST(Clean, NonOrientableStripBecomesValidTopology) {
  // Moebius strip: a 6 x 1 grid whose last column is glued to the first with a twist.
  TriangleMesh m = gridMesh(6, 1);
  for (Triangle& t : m.triangles)
    for (VertexId& v : t) {
      if (v == 6) v = 7;        // top-right of row 0 -> bottom-left of row 1 (twist)
      else if (v == 13) v = 0;  // top-right -> bottom-left
    }
  const CleanResult r = cleanMesh(m);
  expectConventions(r.topology);
  EXPECT_GE(r.report.nonManifoldEdges, 1u);
}

TEST(Clean, RejectsBadInput) {
  TriangleMesh nan = gridMesh(1, 1);
  nan.positions[2].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(cleanMesh(nan), InputError);

  TriangleMesh onlyDegenerate;
  onlyDegenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  onlyDegenerate.triangles = {{0, 1, 1}};
  EXPECT_THROW(cleanMesh(onlyDegenerate), InputError);

  TriangleMesh bad = gridMesh(1, 1);
  bad.triangles[0][0] = 17;
  EXPECT_THROW(cleanMesh(bad), InputError);
}

TEST(Clean, CountsZeroAreaFacesAndKeepsThem) {
  TriangleMesh m = gridMesh(2, 1);
  m.positions[1] = Vec3f(0.f, 0.f, 0.f) * 0.5f + Vec3f(1.f, 0.f, 0.f);  // unchanged
  // Collapse face 0 to a segment by moving vertex 4 (1,1) onto the line through 0 and 1? Use a sliver:
  m.positions.push_back({0.5f, 0.f, 0.f});
  m.triangles.push_back({0, 1, m.numVertices() - 1});
  const CleanResult r = cleanMesh(m);
  EXPECT_EQ(r.report.zeroAreaFaces, 1u);
  EXPECT_EQ(r.mesh.numFaces(), 5u);
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

}  // namespace
}  // namespace seamvox
