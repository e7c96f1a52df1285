// Meshes far from zero (georeferenced scans): the readers keep positions relative to an origin
// (TriangleMesh::origin), every writer puts them back in double precision, and param maps such a
// mesh exactly as the same mesh near zero, in memory and out of core.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "io/mesh_io.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using testing::TempDir;
using ::testing::HasSubstr;

/// A world offset like a UTM coordinate in metres: floats have 0.25-0.5 units of spacing there.
const Vec3d kOffset(512000.0, 4123000.0, 100.0);

/// The torus with coordinates on a 2^-10 lattice, moved so that its first vertex rounds to zero:
/// near zero (origin 0) and far (origin kOffset) it has the very same float positions.
TriangleMesh latticeTorus(bool far) {
  TriangleMesh mesh = testing::torusMesh(32, 16);
  // Vertex 0, the first a reader sees, rounds to zero: far, the origin is kOffset itself.
  Vec3f shift;
  for (int k = 0; k < 3; ++k) shift[k] = std::round(std::round(mesh.positions[0][k] * 1024.0f) / 1024.0f);
  for (Vec3f& p : mesh.positions) {
    for (int k = 0; k < 3; ++k) p[k] = std::round(p[k] * 1024.0f) / 1024.0f - shift[k];
  }
  if (far) mesh.origin = kOffset;
  return mesh;
}

TEST(Origin, OnlyFarMeshesGetOne) {
  EXPECT_TRUE(originFor(Vec3d(1000.0, -2000.0, 16000.0)).isZero(0.0));
  EXPECT_EQ(originFor(Vec3d(512000.4, 4123000.6, 99.5)), Vec3d(512000.0, 4123001.0, 100.0));
  EXPECT_EQ(originFor(Vec3d(-20000.5, 0.0, 0.0)), Vec3d(-20001.0, 0.0, 0.0));
  EXPECT_TRUE(originFor(Vec3d(std::nan(""), 1e9, 0.0)).isZero(0.0));
}

TEST(Origin, EveryFormatKeepsFarPositionsExactly) {
  TempDir dir;
  const TriangleMesh far = latticeTorus(true);
  ASSERT_FALSE(far.origin.isZero(0.0));
  WriteOptions ascii;
  ascii.binary = false;
  for (const auto& [name, options] : {std::pair<const char*, WriteOptions>{"f.ply", {}}, {"a.ply", ascii}, {"f.obj", {}},
                                      {"f.off", {}}, {"f.drc", {}}}) {
    SCOPED_TRACE(name);
    writeMesh(dir.path(name), far, options);
    const TriangleMesh read = readMesh(dir.path(name));
    ASSERT_EQ(read.numVertices(), far.numVertices());
    // The origin is the first vertex's: Draco orders vertices its own way.
    if (formatFromPath(name) != MeshFormat::Draco) EXPECT_EQ(read.origin, far.origin);
    // Draco orders vertices its own way: compare the sets of world positions.
    std::vector<std::array<double, 3>> expected, got;
    for (VertexId v = 0; v < far.numVertices(); ++v) {
      const Vec3d a = far.origin + far.positions[v].cast<double>(), b = read.origin + read.positions[v].cast<double>();
      expected.push_back({a[0], a[1], a[2]});
      got.push_back({b[0], b[1], b[2]});
    }
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(expected, got);
  }
  // Written as doubles in the file's coordinates: a float PLY could not hold them.
  const auto has = [&](const std::string& name, const std::string& part) {
    return testing::readFile(dir.path(name)).find(part) != std::string::npos;
  };
  EXPECT_TRUE(has("a.ply", "property double x"));
  EXPECT_TRUE(has("f.obj", "\nv 511999.7001953125 4123000 100\n"));
  // A mesh near zero keeps its float layout.
  writeMesh(dir.path("near.ply"), latticeTorus(false), ascii);
  EXPECT_TRUE(has("near.ply", "property float x"));
  // Tiles of one site: a forced origin.
  ReadOptions forced;
  forced.origin = Vec3d(512000.0, 4123000.0, 0.0);
  const TriangleMesh tile = readMesh(dir.path("f.ply"), forced);
  EXPECT_EQ(tile.origin, *forced.origin);
  EXPECT_EQ((tile.origin + tile.positions[5].cast<double>()), (far.origin + far.positions[5].cast<double>()));
}

// Far and near, param computes the same map (the same float positions), writes the far one in the
// file's coordinates, and check calls both seamless; in memory and out of core.
TEST(Origin, ParamMapsAFarMeshAsTheSameMeshNearZero) {
  TempDir dir;
  const TriangleMesh far = latticeTorus(true), near = latticeTorus(false);
  writeMesh(dir.path("far.ply"), far);
  writeMesh(dir.path("near.ply"), near);
  const std::string options = " --cells 12 --solver voxloc --grid 32 --quiet";
  for (const std::string path : {std::string(), " --out-of-core --memory-budget 700M --scratch " + dir.dir()}) {
    SCOPED_TRACE(path);
    std::string output;
    for (const char* name : {"far", "near"}) {
      const std::string out = dir.path(std::string(name) + ".map.ply");
      ASSERT_EQ(testing::runSeamvox("param " + dir.path(std::string(name) + ".ply") + " -o " + out + options + path, &output), 0)
          << output;
      EXPECT_THAT(output, HasSubstr(": seamless"));
      ASSERT_EQ(testing::runSeamvox("check " + out, &output), 0) << output;
    }
    ReadOptions uv;
    uv.readUV = true;
    const TriangleMesh a = readMesh(dir.path("far.map.ply"), uv), b = readMesh(dir.path("near.map.ply"), uv);
    EXPECT_FALSE(a.origin.isZero(0.0));
    EXPECT_TRUE(b.origin.isZero(0.0));
    ASSERT_EQ(a.numVertices(), b.numVertices());
    EXPECT_EQ(a.triangles, b.triangles);
    // Exactly the near map's positions moved by the offset (lattice values: no rounding).
    for (VertexId v = 0; v < a.numVertices(); ++v) {
      ASSERT_EQ(Vec3d(a.origin + a.positions[v].cast<double>()), Vec3d(kOffset + b.positions[v].cast<double>())) << "vertex " << v;
    }
    ASSERT_EQ(a.cornerUV.size(), b.cornerUV.size());
    for (std::size_t c = 0; c < a.cornerUV.size(); ++c) ASSERT_EQ(a.cornerUV[c], b.cornerUV[c]) << "corner " << c;
  }
  // The quad meshes: the near one's moved by the offset (double interpolation: to 1e-6).
  for (const char* quads : {"q.obj", "q.ply"}) {
    SCOPED_TRACE(quads);
    std::vector<TriangleMesh> meshes;
    for (const char* name : {"far", "near"}) {
      const std::string out = dir.path(std::string(name) + "." + quads);
      ASSERT_EQ(testing::runSeamvox("param " + dir.path(std::string(name) + ".ply") + " -o " + dir.path("q.map.ply") +
                                        " --quads " + out + options,
                                    nullptr),
                0);
      meshes.push_back(readMesh(out));
    }
    ASSERT_EQ(meshes[0].numVertices(), meshes[1].numVertices());
    ASSERT_GT(meshes[0].numVertices(), 0u);
    EXPECT_FALSE(meshes[0].origin.isZero(0.0));
    double worst = 0.0;
    for (VertexId v = 0; v < meshes[0].numVertices(); ++v) {
      const Vec3d a = meshes[0].origin + meshes[0].positions[v].cast<double>();
      const Vec3d b = kOffset + meshes[1].positions[v].cast<double>();
      worst = std::max(worst, (a - b).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-6);
  }
  // convert chunk by chunk (above its budget) writes what it writes in memory.
  std::string output;
  ASSERT_EQ(testing::runSeamvox("convert " + dir.path("far.ply") + " " + dir.path("in.obj"), &output), 0) << output;
  ASSERT_EQ(testing::runSeamvox("convert " + dir.path("far.ply") + " " + dir.path("ooc.obj") + " --memory-budget 40M --scratch " +
                                    dir.dir(),
                                &output),
            0)
      << output;
  EXPECT_THAT(output, HasSubstr("chunk by chunk"));
  EXPECT_EQ(testing::readFile(dir.path("in.obj")), testing::readFile(dir.path("ooc.obj")));
  EXPECT_NE(testing::readFile(dir.path("in.obj")).find("\nv 511999.7001953125 4123000 100\n"), std::string::npos);
  // info reports the far bounding box.
  ASSERT_EQ(testing::runSeamvox("info " + dir.path("far.ply"), &output), 0) << output;
  EXPECT_THAT(output, HasSubstr("bounding box    (5119"));
}

}  // namespace
}  // namespace seamvox
