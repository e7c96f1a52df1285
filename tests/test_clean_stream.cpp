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
  std::uint64_t edgeSortWritten = 0, sortedEdgeBytes = 0;  // runs spilled: more than the sorted file
};

Cleaned cleanBothWays(const TriangleMesh& mesh, std::uint64_t memoryBytes) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const std::unique_ptr<MeshStream> stream =
      makeMemoryStream("mesh", std::make_shared<const TriangleMesh>(mesh), 997);
  WeldStreamOptions weld;
  weld.memoryBytes = memoryBytes;
  const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
  const CleanScratch scratch = cleanWeldedMesh(folder, welded.scratch, welded.census, memoryBytes);
  Cleaned out;
  out.streamed = readCleanScratch(folder, scratch);
  out.streamedComponents = cleanedComponents(folder, scratch);
  for (const ScratchTraffic& t : folder.traffic()) {
    if (t.stage == "clean: edges") out.edgeSortWritten = t.bytesWritten;
  }
  out.sortedEdgeBytes = 3 * sizeof(std::uint32_t[4]) * scratch.numFaces;
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
  CleanOptions options;
  options.reorderMinFaces = UINT32_MAX;
  out.inMemory = cleanMesh(std::move(ordered), options);
  for (FaceId& f : out.inMemory.faceOrigin) f = inputFace[f];
  return out;
}

void expectEqual(const Cleaned& c) {
  const CleanResult &a = c.streamed, &b = c.inMemory;
  ASSERT_EQ(a.mesh.numFaces(), b.mesh.numFaces());
  ASSERT_EQ(a.mesh.numVertices(), b.mesh.numVertices());
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.faceOrigin, b.faceOrigin);
  EXPECT_EQ(a.vertexOrigin, b.vertexOrigin);
  std::size_t wrong = 0;
  for (CornerId k = 0; k < a.topology.numCorners(); ++k) wrong += a.topology.opposite(k) != b.topology.opposite(k);
  EXPECT_EQ(wrong, 0u) << "corners glued otherwise";
  wrong = 0;
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

// A Moebius strip of n quads (two triangles each), its last quad glued to the first turned over.
TriangleMesh moebiusStrip(int n, const Vec3f& at) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    for (const double s : {-0.2, 0.2}) {
      m.positions.push_back(at + Vec3f(float((1.0 + s * std::cos(t / 2)) * std::cos(t)),
                                       float((1.0 + s * std::cos(t / 2)) * std::sin(t)), float(s * std::sin(t / 2))));
    }
  }
  for (int i = 0; i < n; ++i) {
    const VertexId a = 2 * i, b = 2 * i + 1;
    const bool last = i + 1 == n;
    const VertexId c = last ? 1 : 2 * (i + 1), d = last ? 0 : 2 * (i + 1) + 1;
    m.triangles.push_back({a, c, d});
    m.triangles.push_back({a, d, b});
  }
  return m;
}

// A scan-like mesh with every kind of damage cleaning repairs: fins (edges of three and four
// faces), bowties (a fan joined at one vertex), flipped patches, duplicate and reversed faces,
// a Moebius strip and a pair of faces meeting along an edge in the same direction.
TriangleMesh damagedMesh(std::uint32_t seed) {
  TriangleMesh m = testing::generatedMesh(MeshKind::Scan, 6000);
  std::mt19937 random(seed);
  const std::uint32_t nf = m.numFaces();
  for (int k = 0; k < 12; ++k) {  // fins: one or two extra faces on an edge
    const Triangle t = m.triangles[random() % nf];
    for (int j = 0; j <= k % 2; ++j) {
      const Vec3f tip = m.positions[t[0]] + 0.3f * (m.positions[t[1]] - m.positions[t[0]]).cross(Vec3f::UnitZ()) +
                        Vec3f(0.0f, 0.0f, 0.01f * float(j + 1));
      m.positions.push_back(tip);
      m.triangles.push_back({t[0], t[1], VertexId(m.positions.size() - 1)});
    }
  }
  for (int k = 0; k < 8; ++k) {  // bowties: a small fan sharing one vertex with the surface
    const VertexId v = m.triangles[random() % nf][0];
    const VertexId base = static_cast<VertexId>(m.positions.size());
    for (int j = 0; j < 3; ++j) {
      const double a = 2.0 * M_PI * j / 3;
      m.positions.push_back(m.positions[v] + Vec3f(0.01f * float(std::cos(a)), 0.01f * float(std::sin(a)), 0.02f));
    }
    for (int j = 0; j < 3; ++j) m.triangles.push_back({v, base + VertexId(j), base + VertexId((j + 1) % 3)});
  }
  for (int k = 0; k < 300; ++k) {  // flipped faces
    Triangle& t = m.triangles[random() % nf];
    std::swap(t[1], t[2]);
  }
  for (int k = 0; k < 20; ++k) {  // cracks: faces on copies of their vertices
    Triangle& t = m.triangles[random() % nf];
    for (VertexId& v : t) {
      m.positions.push_back(m.positions[v]);
      v = static_cast<VertexId>(m.positions.size() - 1);
    }
  }
  for (int k = 0; k < 3; ++k) m.positions[m.triangles[random() % nf][0]] += Vec3f(0.0f, 0.0f, 5.0f);  // spikes
  for (int k = 0; k < 5; ++k) {  // zero-area faces: a point on an edge's middle
    const Triangle t = m.triangles[random() % nf];
    m.positions.push_back(0.5f * (m.positions[t[0]] + m.positions[t[1]]));
    m.triangles.push_back({t[1], t[0], VertexId(m.positions.size() - 1)});
  }
  for (int k = 0; k < 40; ++k) {  // duplicates, some reversed
    Triangle t = m.triangles[random() % nf];
    if (k % 2) std::swap(t[1], t[2]);
    m.triangles.push_back(t);
  }
  // Books: single triangles around one edge, two each way, paired by how flat they meet.
  TriangleMesh books;
  for (int b = 0; b < 4; ++b) {
    const Vec3f p(8.0f + float(b), 0.0f, 0.0f), q(8.0f + float(b), 0.0f, 0.5f);
    const VertexId base = static_cast<VertexId>(books.positions.size());
    books.positions.push_back(p);
    books.positions.push_back(q);
    const double angles[4] = {0.0, 1.2 + 0.3 * b, 3.3, 4.0 + 0.2 * b};
    for (int j = 0; j < 4; ++j) {
      books.positions.push_back(p + Vec3f(0.3f * float(std::cos(angles[j])), 0.3f * float(std::sin(angles[j])), 0.2f));
      const VertexId tip = static_cast<VertexId>(books.positions.size() - 1);
      books.triangles.push_back(j % 2 ? Triangle{base + 1, base, tip} : Triangle{base, base + 1, tip});
    }
  }
  return testing::concatMeshes({m, moebiusStrip(24, Vec3f(5.0f, 0.0f, 0.0f)), books});
}

TEST(CleanStream, EqualsCleanMeshOnClosedAndHoledMeshes) {
  for (const MeshKind kind : {MeshKind::Sphere, MeshKind::Scan}) {
    SCOPED_TRACE(static_cast<int>(kind));
    const Cleaned c = cleanBothWays(testing::withOneTriangleHoles(testing::generatedMesh(kind, 40000), 53), 1);
    expectEqual(c);
    EXPECT_EQ(c.streamed.report.nonManifoldEdges, 0u);
    EXPECT_GT(c.edgeSortWritten, c.sortedEdgeBytes) << "the edge sort was meant to spill runs to disk";
  }
}

TEST(CleanStream, EqualsCleanMeshOnNonManifoldAndNonOrientableMeshes) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    for (const std::uint64_t memory : {std::uint64_t(1), std::uint64_t(64) << 20}) {
      const Cleaned c = cleanBothWays(damagedMesh(seed), memory);
      expectEqual(c);
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
  for (const std::uint64_t extra : {std::uint64_t(1000), std::uint64_t(2000000)}) {
    std::string message;
    {
      ScratchFolder folder(dir.dir());
      folder.setWriteLimit(weldBytes + extra);
      const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", mesh, 5000);
      const WeldStreamResult welded = weldMeshStream(*stream, folder, {});
      try {
        cleanWeldedMesh(folder, welded.scratch, welded.census, std::uint64_t(1) << 20);
      } catch (const IoError& e) {
        message = e.what();
      }
      EXPECT_NE(message.find(folder.path()), std::string::npos) << message;
      EXPECT_NE(message.find("full"), std::string::npos) << message;
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
  }
}

}  // namespace
}  // namespace seamvox
