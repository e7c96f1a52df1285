// `seamvox render` out of core (stream/map_render): the streamed picture must equal the in-memory
// renderer's pixel for pixel (faces, seams, cones) on closed maps, holes and islands, non-manifold
// maps with duplicate and degenerate faces, with the positions in memory or joined by sorts and
// any chunking; the command gives the same PNG bytes on both paths and says which ran; a full
// scratch disk is an error naming the folder, and nothing is left behind.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/synth/render.h"
#include "io/mesh_io.h"
#include "stream/map_render.h"
#include "testing.h"

namespace seamvox {
namespace {

namespace fs = std::filesystem;

class OocRender : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir;
    std::string log;
    for (const auto& [kind, faces] : {std::pair<std::string, int>{"sphere", 3000}, {"scan", 6000}}) {
      ASSERT_EQ(testing::runSeamvox("gen " + kind + " --faces " + std::to_string(faces) + " -o " + path(kind + ".ply") + " --quiet", &log), 0) << log;
      ASSERT_EQ(testing::runSeamvox("param " + path(kind + ".ply") + " -o " + path(kind + "-map.ply") + " --quiet", &log), 0) << log;
    }
    // A fin (three faces on one edge), a duplicate face and a face with a repeated vertex.
    ReadOptions options;
    options.readUV = true;
    TriangleMesh mesh = readMesh(path("scan-map.ply"), options);
    std::vector<Vec2d> uv = testing::cornerValues(mesh.cornerUV);
    const Triangle t = mesh.triangles[10];
    mesh.positions.push_back(mesh.positions[t[0]] + Vec3f(0.0f, 0.0f, 0.05f));
    mesh.attributes = mesh.attributes.emptyCopy();
    const VertexId tip = mesh.numVertices() - 1;
    mesh.triangles.push_back({t[0], t[1], tip});
    for (const Vec2d& q : {uv[30], uv[31], Vec2d(uv[30] + Vec2d(0.3, 0.7))}) uv.push_back(q);
    mesh.triangles.push_back(mesh.triangles[20]);
    for (int j = 0; j < 3; ++j) uv.push_back(uv[60 + j] + Vec2d(0.5, 0.25));  // other UVs: must lose the tie
    mesh.triangles.push_back({t[0], t[0], t[2]});
    for (int j = 0; j < 3; ++j) uv.push_back(uv[30 + j]);
    mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
    writeMesh(path("fin-map.ply"), mesh);
    // The sphere's map as a triangle soup: three vertices of its own per face.
    TriangleMesh sphere = readMesh(path("sphere-map.ply"), options);
    TriangleMesh soup;
    soup.cornerUV = sphere.cornerUV;
    for (const Triangle& t : sphere.triangles) {
      const VertexId first = soup.numVertices();
      for (const VertexId v : t) soup.positions.push_back(sphere.positions[v]);
      soup.triangles.push_back({first, first + 1, first + 2});
    }
    writeMesh(path("soup-map.ply"), soup);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path(name); }

  static RenderOptions options() {
    RenderOptions o;
    o.width = 320;
    o.height = 240;
    o.checker = 2.0;
    o.drawSeams = true;
    o.drawCones = true;
    o.azimuth = 40.0;
    o.elevation = 25.0;
    return o;
  }

  // The in-memory picture of the cleaned map, input face ids breaking depth ties.
  static RenderResult inMemory(const std::string& file, const RenderOptions& o) {
    ReadOptions read;
    read.readUV = true;
    const CleanResult clean = cleanMesh(readMesh(file, read));
    return renderCheckerboard(clean.mesh, clean.topology, o, clean.faceOrigin);
  }

  static MapRenderResult outOfCore(const std::string& file, const RenderOptions& o, bool declared,
                                   std::uint64_t memoryBytes) {
    ReadOptions read;
    read.readUV = true;
    read.chunkTriangles = 700;  // several chunks
    std::unique_ptr<MeshStream> stream = openMeshStream(file, read);
    if (!declared) stream = std::make_unique<testing::UndeclaredStream>(std::move(stream));
    testing::TempDir scratch;
    MapRenderOptions ooc;
    ooc.render = o;
    ooc.memoryBytes = memoryBytes;
    ooc.scratchParent = scratch.dir();
    MapRenderResult result = renderMapStream(*stream, ooc);
    EXPECT_TRUE(fs::is_empty(scratch.dir())) << "scratch left behind rendering " << file;
    return result;
  }

  static void expectSamePicture(const std::string& file) {
    const RenderOptions o = options();
    const RenderResult expected = inMemory(file, o);
    ASSERT_GT(expected.coveredPixels, 1000u);
    for (const bool declared : {true, false}) {
      const MapRenderResult got = outOfCore(file, o, declared, declared ? 64 << 20 : 4 << 20);
      EXPECT_EQ(got.positionsInMemory, declared);
      EXPECT_EQ(got.render.image.width, expected.image.width);
      EXPECT_EQ(got.render.image.height, expected.image.height);
      std::size_t differ = 0;
      for (std::size_t i = 0; i < expected.image.pixels.size(); ++i) differ += got.render.image.pixels[i] != expected.image.pixels[i];
      EXPECT_EQ(differ, 0u) << file << (declared ? " (positions in memory)" : " (positions joined)");
      EXPECT_EQ(got.render.coveredPixels, expected.coveredPixels);
      EXPECT_EQ(got.render.seamEdges, expected.seamEdges) << file;
      EXPECT_EQ(got.render.cones.size(), expected.cones.size()) << file;
      EXPECT_EQ(got.render.irregularVertices, expected.irregularVertices) << file;
      EXPECT_EQ(got.render.camera.pixelsPerUnit, expected.camera.pixelsPerUnit);
    }
  }



  static testing::TempDir* dir_;
};
testing::TempDir* OocRender::dir_ = nullptr;

TEST_F(OocRender, ClosedMapSamePicture) {
  expectSamePicture(path("sphere-map.ply"));
  const RenderResult r = inMemory(path("sphere-map.ply"), options());
  EXPECT_GT(r.seamEdges, 0u);
  int turns = 0;
  for (const RenderCone& cone : r.cones) turns += cone.quarterTurns;
  EXPECT_EQ(turns, 8);  // Poincare-Hopf: a sphere's cones sum to 2, in quarter turns 8
}

TEST_F(OocRender, WeldedSoupSamePicture) {
  RenderOptions o = options();
  ReadOptions read;
  read.readUV = true;
  CleanOptions weld;
  weld.weldVertices = true;
  const CleanResult clean = cleanMesh(readMesh(path("soup-map.ply"), read), weld);
  const RenderResult expected = renderCheckerboard(clean.mesh, clean.topology, o, clean.faceOrigin);
  ReadOptions chunked = read;
  chunked.chunkTriangles = 500;
  const auto stream = openMeshStream(path("soup-map.ply"), chunked);
  testing::TempDir scratch;
  MapRenderOptions ooc;
  ooc.render = o;
  ooc.weld = true;
  ooc.scratchParent = scratch.dir();
  const MapRenderResult got = renderMapStream(*stream, ooc);
  EXPECT_EQ(got.render.image.pixels, expected.image.pixels);
  EXPECT_EQ(got.render.seamEdges, expected.seamEdges);
  EXPECT_GT(expected.seamEdges, 0u);
  EXPECT_EQ(got.render.irregularVertices, expected.irregularVertices);
  int turns = 0;
  for (const RenderCone& cone : got.render.cones) turns += cone.quarterTurns;
  EXPECT_EQ(turns, 8);
  EXPECT_EQ(got.render.cones.size(), expected.cones.size());
  // Not welded, every edge is a boundary: no seam, no cone.
  ooc.weld = false;
  const auto again = openMeshStream(path("soup-map.ply"), chunked);
  const MapRenderResult unwelded = renderMapStream(*again, ooc);
  EXPECT_EQ(unwelded.render.seamEdges, 0u);
  EXPECT_TRUE(unwelded.render.cones.empty());
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
}

// Maps of real scans (a closed one, one with holes, one with a sharp crease) and a noisy variant.
TEST_F(OocRender, SharedMeshesSamePicture) {
  int rendered = 0;
  for (const char* name : {"bunny.off", "camelhead.off", "spot.obj"}) {
    const std::string mesh = testing::sharedMesh(name);
    if (mesh.empty()) GTEST_SKIP() << "../shared/data is absent: shared meshes not rendered";
    const std::string map = path(std::string(name) + "-map.ply"), noisy = path(std::string(name) + "-noisy.ply");
    std::string log;
    ASSERT_EQ(testing::runSeamvox("param " + mesh + " -o " + map + " --quiet", &log), 0) << log;
    expectSamePicture(map);
    ASSERT_EQ(testing::runSeamvox("subdivide " + mesh + " --levels 1 --noise 0.25 --seed 3 -o " + noisy, &log), 0) << log;
    ASSERT_EQ(testing::runSeamvox("param " + noisy + " -o " + map + " --quiet", &log), 0) << log;
    expectSamePicture(map);
    ++rendered;
  }
  EXPECT_EQ(rendered, 3);
}

TEST_F(OocRender, HolesAndIslandsSamePicture) { expectSamePicture(path("scan-map.ply")); }

TEST_F(OocRender, NonManifoldWithDuplicateAndDegenerateFacesSamePicture) {
  std::string log;
  ASSERT_EQ(testing::runSeamvox("info " + path("fin-map.ply"), &log), 0) << log;
  EXPECT_NE(log.find("non-manifold edges 1 (split)"), std::string::npos) << log;
  expectSamePicture(path("fin-map.ply"));
}

// Cones at bowtie vertices: two fans mapped by z^0.75 on one vertex (a cone of a quarter turn
// each; their angles together would read as one cone of -2), one such fan with one by z^1.25
// (+1 and -1; together a vertex wound twice), and a lone z^1.25 fan: found per fan, as cleaning
// splits the vertex, so both paths draw the same five cones.
TEST_F(OocRender, ConesAtBowtieVerticesSamePicture) {
  TriangleMesh mesh;
  std::vector<Vec2d> uv;
  testing::addPowerFan(mesh, uv, 0.75, 1.0f, 10, testing::addPowerFan(mesh, uv, 0.75, 2.0f, 10));
  testing::addPowerFan(mesh, uv, 1.25, 3.0f, 10, testing::addPowerFan(mesh, uv, 0.75, 4.0f, 10));
  testing::addPowerFan(mesh, uv, 1.25, 5.0f, 10);
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(path("bowtie-cones-map.ply"), mesh);
  const RenderResult expected = inMemory(path("bowtie-cones-map.ply"), options());
  EXPECT_EQ(expected.cones.size(), 5u);
  expectSamePicture(path("bowtie-cones-map.ply"));
}

// Several views and sizes: the framing and the bands of rows agree at any shape of picture.
TEST_F(OocRender, OtherViewsAndSizesSamePicture) {
  for (const auto& [w, h, az, el, up] : {std::tuple{97, 301, 0.0, 90.0, 2}, std::tuple{512, 64, -120.0, -35.0, 0}}) {
    RenderOptions o = options();
    o.width = w, o.height = h, o.azimuth = az, o.elevation = el, o.upAxis = up, o.supersample = 3;
    const RenderResult expected = inMemory(path("scan-map.ply"), o);
    const MapRenderResult got = outOfCore(path("scan-map.ply"), o, true, 64 << 20);
    EXPECT_EQ(got.render.image.pixels, expected.image.pixels) << w << "x" << h;
  }
}

TEST_F(OocRender, CommandGivesTheSamePngOnBothPaths) {
  testing::TempDir scratch;
  std::string inMemory, outOfCore;
  const std::string base = "render " + path("sphere-map.ply") + " --seams --cones --size 300x200 --quiet --scratch " + scratch.dir();
  ASSERT_EQ(testing::runSeamvox(base + " -o " + path("a.png") + " --memory-budget 64G", &inMemory), 0) << inMemory;
  ASSERT_EQ(testing::runSeamvox(base + " -o " + path("b.png") + " --memory-budget 1K", &outOfCore), 0) << outOfCore;
  EXPECT_NE(inMemory.find("path in memory"), std::string::npos) << inMemory;
  EXPECT_NE(outOfCore.find("path out of core"), std::string::npos) << outOfCore;
  EXPECT_NE(outOfCore.find("running with that minimum"), std::string::npos) << outOfCore;
  EXPECT_EQ(testing::readFile(path("a.png")), testing::readFile(path("b.png")));
  // The same figures but for the lines naming the path and the times.
  const auto figures = [](const std::string& text) { return text.substr(text.find("wrote"), text.find('\n', text.find("wrote")) - text.find("wrote")); };
  EXPECT_EQ(figures(inMemory).substr(figures(inMemory).find(':')), figures(outOfCore).substr(figures(outOfCore).find(':')));
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
  // A map whose vertices are split at every corner, welded back on both paths.
  std::string log;
  ASSERT_EQ(testing::runSeamvox(base + " -o " + path("c.png") + " --memory-budget 64G --weld " + path("soup-map.ply"), &log), 2)
      << "two meshes are a usage error: " << log;
  const std::string soup = "render " + path("soup-map.ply") + " --seams --cones --size 300x200 --quiet --weld --scratch " + scratch.dir();
  ASSERT_EQ(testing::runSeamvox(soup + " -o " + path("c.png") + " --memory-budget 64G", &inMemory), 0) << inMemory;
  ASSERT_EQ(testing::runSeamvox(soup + " -o " + path("d.png") + " --memory-budget 1K", &outOfCore), 0) << outOfCore;
  EXPECT_EQ(testing::readFile(path("c.png")), testing::readFile(path("d.png")));
  EXPECT_EQ(figures(inMemory).substr(figures(inMemory).find(':')), figures(outOfCore).substr(figures(outOfCore).find(':')));
  EXPECT_EQ(inMemory.find(", 0 seam edges"), std::string::npos) << "welded: seams, not boundaries: " << inMemory;
  EXPECT_EQ(inMemory.find(", 0 cones"), std::string::npos) << inMemory;
}

TEST_F(OocRender, FullScratchDiskNamesTheFolderAndLeavesNothing) {
  testing::TempDir scratch;
  ReadOptions read;
  read.readUV = true;
  const auto stream = openMeshStream(path("scan-map.ply"), read);
  MapRenderOptions ooc;
  ooc.render = options();
  ooc.memoryBytes = 16384;
  ooc.scratchParent = scratch.dir();
  std::string folder;
  ooc.onScratch = [&](ScratchFolder& s) {
    folder = s.path();
    s.setWriteLimit(100000);
  };
  try {
    renderMapStream(*stream, ooc);
    FAIL() << "the scratch limit was never reached";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(folder), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs about"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
}

TEST_F(OocRender, MapsWithoutUVAndTruncatedMapsAreClearErrors) {
  testing::TempDir scratch;
  std::string log;
  EXPECT_EQ(testing::runSeamvox("render " + path("sphere.ply") + " -o " + path("e.png") + " --memory-budget 1K --scratch " + scratch.dir(), &log), 1) << log;
  EXPECT_NE(log.find("texture coordinates"), std::string::npos) << log;
  const std::string whole = testing::readFile(path("sphere-map.ply"));
  testing::writeFile(path("cut.ply"), whole.substr(0, whole.size() / 2 + 5));
  EXPECT_EQ(testing::runSeamvox("render " + path("cut.ply") + " -o " + path("e.png") + " --memory-budget 1K --scratch " + scratch.dir(), &log), 1) << log;
  EXPECT_NE(log.find(path("cut.ply")), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(path("e.png")));
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
}

}  // namespace
}  // namespace seamvox
