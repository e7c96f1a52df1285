// 1-to-4 midpoint subdivision (core/mesh/subdivide): faces x4, components, Euler characteristic,
// genus and boundary loops kept, old vertices unchanged, exact midpoints, children inside their
// parent, per-face vectors carried to the children.
#include <gtest/gtest.h>

#include <cstring>
#include <map>

#include "core/field/field.h"
#include "core/mesh/clean.h"
#include "core/mesh/subdivide.h"
#include "core/mesh/topology.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "stream/subdivision_stream.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

TriangleMesh generate(MeshKind kind, std::uint64_t faces) { return testing::generatedMesh(kind, faces); }

/// Checks the invariants of one subdivision of `cleaned` into `result` over `levels` levels.
void expectSubdivisionInvariants(const CleanResult& cleaned, const SubdivideResult& result,
                                 std::uint32_t levels) {
  const TriangleMesh& coarse = cleaned.mesh;
  const TriangleMesh& fine = result.mesh;
  ASSERT_EQ(std::uint64_t(fine.numFaces()), std::uint64_t(coarse.numFaces()) << (2 * levels));
  const ComponentsResult before = computeComponents(cleaned.topology);
  std::uint64_t edges = 0;
  for (const ComponentInfo& k : before.components) edges += k.edges;
  EXPECT_EQ(result.edges, edges);
  if (levels == 1) EXPECT_EQ(fine.numVertices(), coarse.numVertices() + edges);

  // Same topology: manifold, same components, Euler characteristic, genus, boundary loops.
  const Topology topology = Topology::build(fine.triangles, fine.numVertices());
  topology.validate();
  const ComponentsResult after = computeComponents(topology);
  ASSERT_EQ(after.components.size(), before.components.size());
  EXPECT_EQ(after.boundaryLoops, before.boundaryLoops);
  for (std::size_t k = 0; k < before.components.size(); ++k) {
    EXPECT_EQ(after.components[k].eulerCharacteristic, before.components[k].eulerCharacteristic);
    EXPECT_EQ(after.components[k].genus, before.components[k].genus);
    EXPECT_EQ(after.components[k].boundaryLoops, before.components[k].boundaryLoops);
  }
  // Old vertices keep their positions bit for bit.
  ASSERT_GE(fine.numVertices(), coarse.numVertices());
  EXPECT_EQ(std::memcmp(fine.positions.data(), coarse.positions.data(),
                        coarse.positions.size() * sizeof(Vec3f)), 0);
  // Every fine face lies in its parent: same plane, orientation kept, centroid inside.
  ASSERT_EQ(result.parentFace.size(), fine.triangles.size());
  for (FaceId f = 0; f < fine.numFaces(); ++f) {
    const FaceId p = result.parentFace[f];
    ASSERT_LT(p, coarse.numFaces());
    const Triangle& pt = coarse.triangles[p];
    const Vec3d a = coarse.position(pt[0]), b = coarse.position(pt[1]), c = coarse.position(pt[2]);
    const Vec3d n = (b - a).cross(c - a);
    const Triangle& t = fine.triangles[f];
    const Vec3d x = (fine.position(t[0]) + fine.position(t[1]) + fine.position(t[2])) / 3.0;
    const Vec3d m = (fine.position(t[1]) - fine.position(t[0])).cross(fine.position(t[2]) - fine.position(t[0]));
    ASSERT_GT(m.dot(n), 0.0) << "face " << f << " flipped or degenerate";
    const double area2 = n.squaredNorm();
    const double wa = (c - b).cross(x - b).dot(n) / area2, wb = (a - c).cross(x - c).dot(n) / area2;
    ASSERT_GT(wa, 0.0);
    ASSERT_GT(wb, 0.0);
    ASSERT_GT(1.0 - wa - wb, 0.0);
  }
}

/// For one level: the middle child's vertices are the exact midpoints of the parent's edges.
void expectExactMidpoints(const TriangleMesh& coarse, const SubdivideResult& result) {
  for (FaceId p = 0; p < coarse.numFaces(); ++p) {
    std::vector<FaceId> children;
    for (FaceId f = 4 * p; f < 4 * p + 4; ++f) children.push_back(f);
    const Triangle& pt = coarse.triangles[p];
    // The child that uses no parent vertex is the middle one.
    int middles = 0;
    for (FaceId f : children) {
      ASSERT_EQ(result.parentFace[f], p);
      const Triangle& t = result.mesh.triangles[f];
      bool usesParentVertex = false;
      for (VertexId v : t) usesParentVertex |= v < coarse.numVertices();
      if (usesParentVertex) continue;
      ++middles;
      for (int k = 0; k < 3; ++k) {
        // The middle child's vertex k is the midpoint of the parent's edge opposite corner k.
        const Vec3f expected =
            ((coarse.position(pt[(k + 1) % 3]) + coarse.position(pt[(k + 2) % 3])) * 0.5).cast<float>();
        ASSERT_EQ(result.mesh.positions[t[k]], expected) << "face " << p << " edge " << k;
      }
    }
    ASSERT_EQ(middles, 1);
  }
}

TEST(Subdivide, OneLevelKeepsTopologyAndPlacesExactMidpoints) {
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Genus2, MeshKind::Scan}) {
    SCOPED_TRACE(meshKindName(kind));
    const CleanResult cleaned = cleanMesh(generate(kind, 2000));
    const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology);
    expectSubdivisionInvariants(cleaned, result, 1);
    expectExactMidpoints(cleaned.mesh, result);
  }
}

TEST(Subdivide, TwoLevelsMultiplyFacesBySixteen) {
  const CleanResult cleaned = cleanMesh(generate(MeshKind::Torus, 1000));
  SubdivideOptions options;
  options.levels = 2;
  const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology, options);
  expectSubdivisionInvariants(cleaned, result, 2);
  // V2 = V1 + E1 with E1 = 2 E + 3 F (each edge splits, each face adds three inner edges).
  const std::uint64_t v = cleaned.mesh.numVertices(), f = cleaned.mesh.numFaces();
  const std::uint64_t e = result.edges, v1 = v + e, e1 = 2 * e + 3 * f;
  EXPECT_EQ(result.mesh.numVertices(), v1 + e1);
}

TEST(Subdivide, ZeroLevelsIsACopyAndMismatchedTopologyIsRejected) {
  const CleanResult cleaned = cleanMesh(generate(MeshKind::Sphere, 500));
  SubdivideOptions options;
  options.levels = 0;
  const SubdivideResult same = subdivideMesh(cleaned.mesh, cleaned.topology, options);
  EXPECT_EQ(same.mesh.positions, cleaned.mesh.positions);
  EXPECT_EQ(same.mesh.triangles, cleaned.mesh.triangles);
  const CleanResult other = cleanMesh(generate(MeshKind::Torus, 500));
  EXPECT_THROW(subdivideMesh(cleaned.mesh, other.topology), TopologyError);
}

TEST(Subdivide, ChildrenInheritTheParentsVector) {
  const CleanResult cleaned = cleanMesh(generate(MeshKind::Torus, 400));
  const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology);
  std::vector<Vec3d> field(cleaned.mesh.numFaces());
  for (FaceId f = 0; f < field.size(); ++f) field[f] = Vec3d(f, 1.0, -1.0);
  const std::vector<Vec3d> fine = inheritFaceVectors(field, result.parentFace);
  ASSERT_EQ(fine.size(), result.mesh.numFaces());
  std::map<double, int> count;
  for (FaceId f = 0; f < fine.size(); ++f) {
    EXPECT_EQ(fine[f], field[result.parentFace[f]]);
    ++count[fine[f].x()];
  }
  EXPECT_EQ(count.size(), field.size());
  for (const auto& [x, n] : count) EXPECT_EQ(n, 4);
}

TEST(Subdivide, FertilityOnce) {
  const std::string path = testing::sharedMesh("fertility.off");
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage("fertility.off");
  const CleanResult cleaned = cleanMesh(readMesh(path));
  const ComponentsResult comps = computeComponents(cleaned.topology);
  ASSERT_EQ(comps.components.size(), 1u);
  EXPECT_EQ(comps.components[0].genus, 4);
  const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology);
  expectSubdivisionInvariants(cleaned, result, 1);
  expectExactMidpoints(cleaned.mesh, result);
}

TEST(Subdivide, BoundariesAndSeveralComponentsAreKept) {
  // A disk, a cylinder (two loops) and a torus in one mesh, twice subdivided.
  const TriangleMesh parts = testing::concatMeshes(
      {testing::gridMesh(5, 3), testing::cylinderMesh(9, 2), testing::torusMesh(8, 5)});
  const CleanResult cleaned = cleanMesh(parts);
  ASSERT_EQ(computeComponents(cleaned.topology).boundaryLoops, 3u);
  for (std::uint32_t levels : {1u, 2u}) {
    SubdivideOptions options;
    options.levels = levels;
    const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology, options);
    expectSubdivisionInvariants(cleaned, result, levels);
    // Each boundary edge splits in two per level.
    const Topology fine = Topology::build(result.mesh.triangles, result.mesh.numVertices());
    std::uint64_t coarseBoundary = 0, fineBoundary = 0;
    for (CornerId c = 0; c < cleaned.topology.numCorners(); ++c) coarseBoundary += cleaned.topology.isBoundaryEdge(c);
    for (CornerId c = 0; c < fine.numCorners(); ++c) fineBoundary += fine.isBoundaryEdge(c);
    EXPECT_EQ(fineBoundary, coarseBoundary << levels);
  }
}

// The streamed subdivision (for outputs above the memory budget) gives subdivideMesh's faces in
// its order with the same corner positions and properties bit for bit, numbered its own way:
// every id used once per position, as many vertices, and the same corner table.
TEST(Subdivide, TheStreamGivesTheSameFacesNumberedByEdgeAndFace) {
  TriangleMesh parts = testing::concatMeshes(
      {testing::gridMesh(5, 3), testing::cylinderMesh(9, 2), testing::torusMesh(8, 5)});
  VertexProperty& red = parts.attributes.add("red", ScalarType::UInt8, parts.numVertices());
  VertexProperty& q = parts.attributes.add("quality", ScalarType::Float32, parts.numVertices());
  for (VertexId v = 0; v < parts.numVertices(); ++v) red.setValue(v, (v * 37) % 256), q.setValue(v, 0.1 * v);
  const CleanResult cleaned = cleanMesh(parts);
  for (std::uint32_t levels : {0u, 1u, 2u, 3u}) {
    SCOPED_TRACE(levels);
    SubdivideOptions options;
    options.levels = levels;
    const SubdivideResult memory = subdivideMesh(cleaned.mesh, cleaned.topology, options);
    SubdivisionStream stream(cleaned.mesh, cleaned.topology, levels);
    ASSERT_EQ(stream.numFaces(), memory.mesh.numFaces());
    ASSERT_EQ(stream.numVertices(), memory.mesh.numVertices());
    TriangleMesh streamed;
    streamed.attributes = cleaned.mesh.attributes.emptyCopy();
    MeshChunk chunk;
    while (stream.nextVertices(7, chunk)) {  // small chunks: items split across calls
      ASSERT_EQ(chunk.firstVertex, streamed.numVertices());
      streamed.positions.insert(streamed.positions.end(), chunk.positions.begin(), chunk.positions.end());
      streamed.attributes.append(chunk.attributes);
    }
    while (stream.nextTriangles(5, chunk)) {
      streamed.triangles.insert(streamed.triangles.end(), chunk.triangles.begin(), chunk.triangles.end());
    }
    ASSERT_EQ(streamed.numVertices(), memory.mesh.numVertices());
    ASSERT_EQ(streamed.numFaces(), memory.mesh.numFaces());
    streamed.attributes.checkSize(streamed.numVertices());
    // One streamed id per in-memory id (a renumbering), positions and properties equal.
    std::vector<VertexId> memoryId(streamed.numVertices(), kInvalidId), streamedId(streamed.numVertices(), kInvalidId);
    for (FaceId f = 0; f < streamed.numFaces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const VertexId a = streamed.triangles[f][k], b = memory.mesh.triangles[f][k];
        ASSERT_LT(a, streamed.numVertices());
        ASSERT_TRUE(memoryId[a] == kInvalidId || memoryId[a] == b) << "face " << f << " corner " << k;
        ASSERT_TRUE(streamedId[b] == kInvalidId || streamedId[b] == a) << "face " << f << " corner " << k;
        memoryId[a] = b;
        streamedId[b] = a;
        ASSERT_EQ(streamed.positions[a], memory.mesh.positions[b]) << "face " << f << " corner " << k;
        for (std::size_t p = 0; p < streamed.attributes.properties.size(); ++p) {
          ASSERT_EQ(streamed.attributes.properties[p].value(a), memory.mesh.attributes.properties[p].value(b));
        }
      }
    }
    for (VertexId v = 0; v < streamed.numVertices(); ++v) ASSERT_NE(memoryId[v], kInvalidId) << v;
    const Topology topology = Topology::build(streamed.triangles, streamed.numVertices());
    topology.validate();
    EXPECT_EQ(computeComponents(topology).boundaryLoops, 3u);
  }
}

TEST(Subdivide, ATangentFieldStaysTangentOnTheChildren) {
  const CleanResult cleaned = cleanMesh(testing::icosphereMesh(1));
  const CrossField field = testing::randomField(cleaned.mesh, 9);
  std::vector<Vec3d> vectors(field.direction.size());
  for (FaceId f = 0; f < vectors.size(); ++f) vectors[f] = field.at(f);
  SubdivideOptions options;
  options.levels = 2;
  const SubdivideResult result = subdivideMesh(cleaned.mesh, cleaned.topology, options);
  const std::vector<Vec3d> fine = inheritFaceVectors(vectors, result.parentFace);
  for (FaceId f = 0; f < result.mesh.numFaces(); ++f) {
    // Children are coplanar with their parent: the inherited direction is tangent to them.
    EXPECT_LT(std::abs(fine[f].dot(faceNormal(result.mesh, f))), 1e-5) << "face " << f;
  }
}

}  // namespace
}  // namespace seamvox
