// The out-of-core cleaning (stream/clean_stream) gives what cleanMesh gives on the weld pass's
// faces in the weld pass's order: the same triangles, positions, corner table, fan starts,
// origins and repair counts, on closed, holed, non-manifold and non-orientable meshes, with
// sorts small enough to spill to disk.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <tuple>

#include "core/mesh/clean.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "stream/clean_stream.h"
#include "stream/mesh_stream.h"
#include "stream/welded_scratch.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

struct Cleaned {
  CleanResult streamed, inMemory;
  ComponentsResult streamedComponents;
  std::uint64_t edgeSortWritten = 0, sortedEdgeBytes = 0;  // the edge sort's partitions; the sides' bytes
  bool weldSetsOnDisk = false, cleanSetsOnDisk = false;     // the union-finds beyond their shares
  std::string gluing;                                       // CleanScratch::gluing
  std::uint64_t frontLateValues = 0;
};

/// The cleaning within options.memoryBytes (also the weld's) and cleanMesh on the same faces.
Cleaned cleanBothWays(const TriangleMesh& mesh, const CleanStreamOptions& options) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const std::unique_ptr<MeshStream> stream =
      makeMemoryStream("mesh", std::make_shared<const TriangleMesh>(mesh), 997);
  WeldStreamOptions weld;
  weld.memoryBytes = options.memoryBytes;
  const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
  const CleanScratch scratch = cleanWeldedMesh(folder, welded.scratch, welded.census, options);
  Cleaned out;
  out.streamed = readCleanScratch(folder, scratch);
  out.streamedComponents = cleanedComponents(folder, scratch, options.memoryBytes);
  out.weldSetsOnDisk = welded.census.setsOnDisk;
  out.cleanSetsOnDisk = scratch.setsOnDisk;
  out.gluing = scratch.gluing;
  out.frontLateValues = scratch.frontLateValues;
  for (const ScratchTraffic& t : folder.traffic()) {
    if (t.stage == "clean: edges") out.edgeSortWritten = t.bytesWritten;
  }
  out.sortedEdgeBytes = 3 * sizeof(std::uint32_t[3]) * scratch.numFaces;  // 12-byte edge sides
  // In memory: the weld pass's faces in its order (input vertex ids: nothing welded).
  TriangleMesh ordered;
  ordered.positions = mesh.positions;
  std::vector<FaceId> inputFace;
  WeldedFaceReader reader(folder, welded.scratch);
  std::vector<WeldedFace> chunk;
  while (reader.next(chunk, 1000)) {
    for (const WeldedFace& f : chunk) {
      ordered.triangles.push_back(f.triangle);
      inputFace.push_back(f.face);
    }
  }
  // Vertices numbered in the order the faces first name them, as the streamed cleaning numbers them.
  std::vector<VertexId> newId(ordered.positions.size(), kInvalidId), oldId;
  for (Triangle& t : ordered.triangles) {
    for (VertexId& v : t) {
      if (newId[v] == kInvalidId) newId[v] = static_cast<VertexId>(oldId.size()), oldId.push_back(v);
      v = newId[v];
    }
  }
  std::vector<Vec3f> positions;
  for (VertexId v : oldId) positions.push_back(ordered.positions[v]);
  ordered.positions = std::move(positions);
  CleanOptions inMemory;
  inMemory.reorderMinFaces = UINT32_MAX;
  out.inMemory = cleanMesh(std::move(ordered), inMemory);
  for (FaceId& f : out.inMemory.faceOrigin) f = inputFace[f];
  for (VertexId& v : out.inMemory.vertexOrigin) v = oldId[v];
  return out;
}

/// The same faces, positions, origins and gluing.
void expectSameMesh(const CleanResult& a, const CleanResult& b) {
  ASSERT_EQ(a.mesh.numFaces(), b.mesh.numFaces());
  ASSERT_EQ(a.mesh.numVertices(), b.mesh.numVertices());
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.faceOrigin, b.faceOrigin);
  EXPECT_EQ(a.vertexOrigin, b.vertexOrigin);
  std::size_t wrong = 0;
  for (CornerId k = 0; k < a.topology.numCorners(); ++k) wrong += a.topology.opposite(k) != b.topology.opposite(k);
  EXPECT_EQ(wrong, 0u) << "corners glued otherwise";
}

void expectEqual(const Cleaned& c) {
  const CleanResult &a = c.streamed, &b = c.inMemory;
  expectSameMesh(a, b);
  std::size_t wrong = 0;
  for (VertexId v = 0; v < a.topology.numVertices(); ++v) wrong += a.topology.vertexCorner(v) != b.topology.vertexCorner(v);
  EXPECT_EQ(wrong, 0u) << "fan starts differ";
  EXPECT_EQ(a.report.nonManifoldEdges, b.report.nonManifoldEdges);
  EXPECT_EQ(a.report.nonManifoldVertices, b.report.nonManifoldVertices);
  EXPECT_EQ(a.report.flippedFaces, b.report.flippedFaces);
  EXPECT_EQ(a.report.outputFaces, b.report.outputFaces);
  EXPECT_EQ(a.report.zeroAreaFaces, b.report.zeroAreaFaces);
  EXPECT_EQ(a.report.unweldedBoundaryVertices, b.report.unweldedBoundaryVertices);
  EXPECT_EQ(a.report.spikeVertices, b.report.spikeVertices);
  EXPECT_EQ(a.report.diagonalWithoutSpikes, b.report.diagonalWithoutSpikes);
  EXPECT_EQ(a.report.outputVertices, b.report.outputVertices);
  a.topology.validate();
  // The components from the scratch are computeComponents' of the in-memory result.
  const ComponentsResult expected = computeComponents(b.topology);
  const ComponentsResult& got = c.streamedComponents;
  EXPECT_EQ(got.boundaryLoops, expected.boundaryLoops);
  ASSERT_EQ(got.components.size(), expected.components.size());
  for (std::size_t i = 0; i < got.components.size(); ++i) {
    const ComponentInfo &x = got.components[i], &y = expected.components[i];
    EXPECT_EQ(std::make_tuple(x.faces, x.vertices, x.edges, x.boundaryLoops, x.eulerCharacteristic, x.genus),
              std::make_tuple(y.faces, y.vertices, y.edges, y.boundaryLoops, y.eulerCharacteristic, y.genus))
        << "component " << i;
  }
}

CleanStreamOptions withinOneByte(bool renumberBySorts, bool gluingBySorts) {
  CleanStreamOptions options;
  options.memoryBytes = 1;
  options.renumberBySorts = renumberBySorts;
  options.gluingBySorts = gluingBySorts;
  return options;
}

TEST(CleanStream, EqualsCleanMeshOnClosedAndHoledMeshes) {
  for (const MeshKind kind : {MeshKind::Sphere, MeshKind::Scan}) {
    SCOPED_TRACE(static_cast<int>(kind));
    const TriangleMesh mesh = testing::withOneTriangleHoles(testing::generatedMesh(kind, 80000), 53);
    // The sphere's 40K vertices do not fit the smallest memory beside their new ids: their
    // positions go through a sort (the scan's: by the sorts of every step).
    const bool renumberBySorts = kind == MeshKind::Scan;
    {
      SCOPED_TRACE("glued by sorts");
      const Cleaned c = cleanBothWays(mesh, withinOneByte(renumberBySorts, true));
      expectEqual(c);
      EXPECT_EQ(c.gluing, "sorts");
      EXPECT_EQ(c.streamed.report.nonManifoldEdges, 0u);
      // The edge sort's partitions went to disk, each side written once.
      EXPECT_EQ(c.edgeSortWritten, c.sortedEdgeBytes);
    }
    // Along the front, with windows of 2^20 values and of 64 (values set after their window was
    // written are patched in place).
    for (const std::size_t window : {std::size_t(1) << 20, std::size_t(64)}) {
      SCOPED_TRACE(window);
      CleanStreamOptions options = withinOneByte(renumberBySorts, false);
      options.frontWindow = window;
      const Cleaned c = cleanBothWays(mesh, options);
      expectEqual(c);
      EXPECT_EQ(c.gluing, "front");
      EXPECT_EQ(c.edgeSortWritten, 0u);
      if (window == 64) EXPECT_GT(c.frontLateValues, 0u);
    }
  }
}

// Vertices of thousands of corners (the poles of a double cone, the centre of an open fan) are
// glued along the front as cleanMesh glues them, and by the sorts.
TEST(CleanStream, HighValenceVerticesEqualCleanMesh) {
  TriangleMesh mesh;
  const int n = 6000, m = 3000;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    mesh.positions.push_back(Vec3f(float(std::cos(a)), float(std::sin(a)), 0.0f));
  }
  const VertexId top = VertexId(mesh.positions.size()), bottom = top + 1;
  mesh.positions.push_back(Vec3f(0.0f, 0.0f, 1.0f));
  mesh.positions.push_back(Vec3f(0.0f, 0.0f, -1.0f));
  for (int i = 0; i < n; ++i) {
    const VertexId r = VertexId(i), s = VertexId((i + 1) % n);
    mesh.triangles.push_back({top, r, s});
    mesh.triangles.push_back({bottom, s, r});
  }
  const VertexId centre = VertexId(mesh.positions.size());
  mesh.positions.push_back(Vec3f(5.0f, 0.0f, 0.0f));
  for (int i = 0; i < m; ++i) {
    const double a = 1.5 * M_PI * i / (m - 1);
    mesh.positions.push_back(Vec3f(float(5.0 + std::cos(a)), float(std::sin(a)), 0.0f));
  }
  for (int i = 0; i + 1 < m; ++i) mesh.triangles.push_back({centre, centre + 1 + VertexId(i), centre + 2 + VertexId(i)});
  for (const bool gluingBySorts : {false, true}) {
    SCOPED_TRACE(gluingBySorts ? "sorts" : "front");
    CleanStreamOptions options;
    options.memoryBytes = std::uint64_t(64) << 20;
    options.gluingBySorts = gluingBySorts;
    // The spikes' walk in blocks of 100 vertices: the poles lie beyond most of their ring's blocks.
    options.spikeBlock = 100;
    const Cleaned c = cleanBothWays(mesh, options);
    expectEqual(c);
    EXPECT_EQ(c.gluing, gluingBySorts ? "sorts" : "front");
    EXPECT_EQ(c.inMemory.report.nonManifoldVertices, 0u);
  }
}

// Surfaces that share single vertices (two, three and four fans at one vertex) are glued along the
// front; the split vertices are cleanMesh's, and a front over its memory leaves it to the sorts.
TEST(CleanStream, SplitVerticesAlongTheFrontEqualCleanMesh) {
  TriangleMesh a = testing::withOneTriangleHoles(testing::generatedMesh(MeshKind::Sphere, 20000), 37);
  std::vector<TriangleMesh> parts{a, a, a, a};
  for (std::size_t i = 1; i < parts.size(); ++i) {
    for (Vec3f& p : parts[i].positions) p += Vec3f(2.5f * float(i), 0.0f, 0.0f);
  }
  TriangleMesh mesh = testing::concatMeshes(parts);
  // Vertex k of part i (i > 0) becomes vertex k of part 0 for k a multiple of 997 (parts 1 to 3 at a
  // third of them, parts 2 and 3 at another, part 3 at the last): two, three and four fans there.
  const VertexId n = static_cast<VertexId>(a.positions.size());
  for (Triangle& t : mesh.triangles) {
    for (VertexId& v : t) {
      const VertexId part = v / n, k = v % n;
      if (part > 0 && k % 997 == 0 && (k / 997) % 3 < part) v = k;
    }
  }
  for (const bool smallFront : {false, true}) {
    SCOPED_TRACE(smallFront ? "front over its memory" : "front");
    CleanStreamOptions options = withinOneByte(false, false);
    options.frontWindow = 256;
    if (smallFront) options.frontBytes = 2000;
    const Cleaned c = cleanBothWays(mesh, options);
    expectEqual(c);
    EXPECT_GE(c.inMemory.report.nonManifoldVertices, 8u);
    EXPECT_EQ(c.inMemory.report.nonManifoldEdges, 0u);
    EXPECT_EQ(c.gluing, smallFront ? "sorts: the front pass met the open front outgrew its memory" : "front");
  }
}

TEST(CleanStream, EqualsCleanMeshOnNonManifoldAndNonOrientableMeshes) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    // The vertices renumbered in memory and by sorts (as when their ids do not fit the budget).
    for (const auto& [memory, bySorts] : {std::make_pair(std::uint64_t(1), false), std::make_pair(std::uint64_t(1), true),
                                          std::make_pair(std::uint64_t(64) << 20, false)}) {
      SCOPED_TRACE(bySorts ? "renumbered by sorts" : "renumbered in memory");
      CleanStreamOptions options;
      options.memoryBytes = memory;
      options.renumberBySorts = bySorts;
      // The spikes' walk in blocks of 50 vertices: many blocks, neighbours beyond the three held.
      if (memory == 1) options.spikeBlock = 50;
      const Cleaned c = cleanBothWays(testing::damagedMesh(seed), options);
      expectEqual(c);
      // The front pass meets the first edge of more than two faces or orientation clash.
      EXPECT_EQ(c.gluing.rfind("sorts: the front pass met ", 0), 0u) << c.gluing;
      // The union-finds of the weld and cleaning (components, loops, orientation, pieces) and the
      // flips in memory within a budget, on disk through page caches beyond it.
      EXPECT_EQ(c.weldSetsOnDisk, memory == 1);
      EXPECT_EQ(c.cleanSetsOnDisk, memory == 1);
      // Every kind of repair happened.
      EXPECT_GT(c.inMemory.report.nonManifoldEdges, 12u);
      EXPECT_GE(c.inMemory.report.nonManifoldVertices, 8u);
      EXPECT_GT(c.inMemory.report.flippedFaces, 0u);
      EXPECT_GT(c.inMemory.report.unweldedBoundaryVertices, 0u);
      EXPECT_GT(c.inMemory.report.spikeVertices, 0u);
      EXPECT_GT(c.inMemory.report.zeroAreaFaces, 0u);
    }
  }
}

// param welds without the census `info` prints (edges, components, loops): the same cleaned mesh
// and repair counts, with the unreferenced vertices counted by the cleaning.
TEST(CleanStream, WithoutTheWeldCensusTheCleaningIsTheSame) {
  TriangleMesh mesh = testing::damagedMesh(5);
  for (int k = 0; k < 7; ++k) mesh.positions.push_back(Vec3f(float(k), 9.0f, 9.0f));  // no face uses them
  mesh.positions.push_back(mesh.positions[mesh.triangles[10][0]]);  // welded with the vertex it copies
  mesh.triangles[20][0] = VertexId(mesh.positions.size() - 1);
  const auto shared = std::make_shared<const TriangleMesh>(mesh);
  for (const std::uint64_t memory : {std::uint64_t(1), std::uint64_t(64) << 20}) {
    SCOPED_TRACE(memory);
    CleanResult cleaned[2];
    WeldCensus census[2];
    for (const bool withCensus : {true, false}) {
      testing::TempDir dir;
      ScratchFolder folder(dir.dir());
      const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", shared, 997);
      WeldStreamOptions weld;
      weld.weld = true;
      weld.memoryBytes = memory;
      weld.census = withCensus;
      const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
      CleanStreamOptions clean;
      clean.memoryBytes = memory;
      const CleanScratch scratch = cleanWeldedMesh(folder, welded.scratch, welded.census, clean);
      cleaned[withCensus] = readCleanScratch(folder, scratch);
      census[withCensus] = welded.census;
    }
    const CleanResult &a = cleaned[0], &b = cleaned[1];
    expectSameMesh(a, b);
    EXPECT_EQ(std::make_tuple(a.report.inputVertices, a.report.weldedVertices, a.report.degenerateFaces,
                              a.report.duplicateFaces, a.report.unreferencedVertices, a.report.nonManifoldEdges,
                              a.report.nonManifoldVertices, a.report.flippedFaces, a.report.outputVertices),
              std::make_tuple(b.report.inputVertices, b.report.weldedVertices, b.report.degenerateFaces,
                              b.report.duplicateFaces, b.report.unreferencedVertices, b.report.nonManifoldEdges,
                              b.report.nonManifoldVertices, b.report.flippedFaces, b.report.outputVertices));
    // The cleaning's count of unreferenced vertices is the census's.
    EXPECT_EQ(b.report.unreferencedVertices, census[1].unreferencedVertices);
    EXPECT_GE(b.report.unreferencedVertices, 7u);
    EXPECT_GE(b.report.weldedVertices, 1u);
    EXPECT_GT(b.report.duplicateFaces, 0u);
    EXPECT_GT(census[1].edges, 0u);
    EXPECT_FALSE(census[1].components.empty());
    EXPECT_EQ(census[0].edges, 0u);
    EXPECT_TRUE(census[0].components.empty());
  }
}

// A scratch disk that fills up during the cleaning (after the weld pass) is an error naming the
// folder, and the folder is removed with everything in it.
TEST(CleanStream, AFullScratchDiskIsAnErrorNamingTheFolder) {
  const auto mesh = std::make_shared<const TriangleMesh>(testing::generatedMesh(MeshKind::Scan, 20000));
  testing::TempDir dir;
  std::uint64_t weldBytes = 0;
  {
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", mesh, 5000);
    weldMeshStream(*stream, folder, {});
    weldBytes = folder.bytesWritten();
  }
  // Full at the cleaning's first bytes, and once the faces are written (while the edges are
  // glued along the front or sorted).
  for (const bool gluingBySorts : {false, true}) {
    for (const std::uint64_t extra : {std::uint64_t(1000), std::uint64_t(400000)}) {
      SCOPED_TRACE(gluingBySorts ? "sorts" : "front");
      {
        ScratchFolder folder(dir.dir());
        folder.setWriteLimit(weldBytes + extra);
        const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", mesh, 5000);
        const WeldStreamResult welded = weldMeshStream(*stream, folder, {});
        CleanStreamOptions clean;
        clean.memoryBytes = std::uint64_t(1) << 20;
        clean.gluingBySorts = gluingBySorts;
        testing::expectScratchFull(folder, [&] { cleanWeldedMesh(folder, welded.scratch, welded.census, clean); });
      }
      EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
    }
  }
}

}  // namespace
}  // namespace seamvox
