// STL input (io/stl_io.cpp): binary and ASCII read into the same welded mesh as an indexed file,
// in memory and by the out-of-core weld pass; malformed files named with what is wrong; STL
// refused as an output; param maps an STL as it maps the same mesh from PLY, in and out of core.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <thread>

#include <signal.h>
#include <sys/stat.h>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "stream/welded_scratch.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using testing::TempDir;
using ::testing::HasSubstr;

using testing::messageOf;

/// The mesh with its vertices numbered by first appearance in its faces, unreferenced ones
/// dropped: what reading its STL gives (no two of its vertices share a position).
TriangleMesh inFirstAppearanceOrder(const TriangleMesh& mesh) {
  TriangleMesh out;
  std::vector<VertexId> id(mesh.numVertices(), kInvalidId);
  for (const Triangle& t : mesh.triangles) {
    Triangle u;
    for (int k = 0; k < 3; ++k) {
      if (id[t[k]] == kInvalidId) {
        id[t[k]] = out.numVertices();
        out.positions.push_back(mesh.positions[t[k]]);
      }
      u[k] = id[t[k]];
    }
    out.triangles.push_back(u);
  }
  return out;
}

std::string binaryStl(const TriangleMesh& mesh, const std::string& header, const std::function<void(std::string&, std::size_t)>& edit = {}) {
  std::string bytes = header;
  bytes.resize(80, ' ');
  const std::uint32_t n = mesh.numFaces();
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const float normal[3] = {0.0f, 0.0f, 1.0f};
    bytes.append(reinterpret_cast<const char*>(normal), 12);
    for (VertexId v : mesh.triangles[f]) bytes.append(reinterpret_cast<const char*>(mesh.positions[v].data()), 12);
    bytes.append(2, '\0');
    if (edit) edit(bytes, f);
  }
  return bytes;
}

/// ASCII STL in the spellings writers use: upper and lower case, CRLF, the mesh split in two
/// solids, blank lines; coordinates in shortest round-trip form.
std::string asciiStl(const TriangleMesh& mesh) {
  std::string text = "solid part one\r\n";
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (f == mesh.triangles.size() / 2) text += "endsolid part one\r\n\r\nSOLID two\r\n";
    text += f % 2 ? "  facet normal 0 0 1\r\n    outer loop\r\n" : "FACET NORMAL 0.0 0.0 1.0\r\nOUTER LOOP\r\n";
    for (VertexId v : mesh.triangles[f]) {
      text += f % 2 ? "      vertex" : "VERTEX";
      for (int k = 0; k < 3; ++k) {
        char buffer[32];
        const auto r = std::to_chars(buffer, buffer + sizeof buffer, mesh.positions[v][k]);
        text += " " + std::string(buffer, r.ptr);
      }
      text += "\r\n";
    }
    text += f % 2 ? "    endloop\r\n  endfacet\r\n" : "ENDLOOP\r\nENDFACET\r\n";
  }
  return text + "endsolid two\r\n";
}

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t v = 0; v < a.positions.size(); ++v) {
    ASSERT_EQ(0, std::memcmp(a.positions[v].data(), b.positions[v].data(), sizeof(Vec3f))) << "vertex " << v;
  }
  EXPECT_EQ(a.triangles, b.triangles);
}

TriangleMesh twoComponents() {
  TriangleMesh sphere = testing::icosphereMesh(2);
  for (Vec3f& p : sphere.positions) p += Vec3f(5.0f, 0.0f, 0.0f);
  return inFirstAppearanceOrder(testing::concatMeshes({testing::torusMesh(24, 12), sphere}));
}

TEST(StlRead, BinaryAndAsciiGiveTheIndexedMeshWelded) {
  TempDir dir;
  const TriangleMesh mesh = twoComponents();
  // A binary header may start with "solid" too: the size decides.
  testing::writeFile(dir.path("b.stl"), binaryStl(mesh, "solid but binary"));
  testing::writeFile(dir.path("a.STL"), asciiStl(mesh));
  for (const char* name : {"b.stl", "a.STL"}) {
    SCOPED_TRACE(name);
    const TriangleMesh read = readMesh(dir.path(name));
    expectSameMesh(mesh, read);
    EXPECT_EQ(read.weldedAtRead, 3 * mesh.triangles.size() - mesh.positions.size());
    // Cleaning counts STL's corners as input vertices, welded, as the out-of-core weld pass does.
    const CleanResult cleaned = cleanMesh(read, CleanOptions{});
    EXPECT_EQ(cleaned.report.inputVertices, 3 * mesh.triangles.size());
    EXPECT_EQ(cleaned.report.weldedVertices, 3 * mesh.triangles.size() - mesh.positions.size());
    EXPECT_EQ(cleaned.report.unreferencedVertices, 0u);
    EXPECT_EQ(cleaned.mesh.numVertices(), mesh.numVertices());
    EXPECT_EQ(cleaned.mesh.weldedAtRead, 0u);

    // Out of core: the stream hands out corners; the weld pass joins them whatever its options.
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = openMeshStream(dir.path(name));
    EXPECT_TRUE(stream->cornerVertices());
    const WeldStreamResult welded = weldMeshStream(*stream, folder, WeldStreamOptions{});
    EXPECT_EQ(welded.census.inputVertices, 3 * mesh.triangles.size());
    EXPECT_EQ(welded.census.weldedVertices, cleaned.report.weldedVertices);
    EXPECT_EQ(welded.census.vertices, mesh.positions.size());
    EXPECT_EQ(welded.census.faces, mesh.triangles.size());
    EXPECT_EQ(welded.census.components.size(), 2u);
  }
  // Chunks of any size, and a stream whose counts are not declared (a pipe's).
  ReadOptions small;
  small.chunkTriangles = 7;
  expectSameMesh(mesh, readMesh(dir.path("b.stl"), small));
  testing::UndeclaredStream undeclared(openMeshStream(dir.path("a.STL"), small));
  expectSameMesh(mesh, readMesh(undeclared));
}

TEST(StlRead, EqualPositionsWeldWhateverTheirZeroSignAndPolygonsAreFans) {
  TempDir dir;
  testing::writeFile(dir.path("z.stl"),
                     "solid z\n"
                     "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n"
                     "facet normal 0 0 1\n outer loop\n  vertex -0 1e0 0\n  vertex 1 -0.0 0\n  vertex 1 1 0\n  vertex 0.5 2 0\n"
                     " endloop\nendfacet\nendsolid z\n");
  const TriangleMesh read = readMesh(dir.path("z.stl"));
  ASSERT_EQ(read.numVertices(), 5u);
  ASSERT_EQ(read.numFaces(), 3u);
  EXPECT_EQ(read.triangles[1], (Triangle{2, 1, 3}));
  EXPECT_EQ(read.triangles[2], (Triangle{2, 3, 4}));
  EXPECT_EQ(read.weldedAtRead, 4u);
}

TEST(StlRead, PipesAreReadAsStreams) {
  TempDir dir;
  ::signal(SIGPIPE, SIG_IGN);
  const TriangleMesh mesh = twoComponents();
  for (const auto& [name, bytes] : {std::pair<const char*, std::string>{"b.stl", binaryStl(mesh, "solid binary")},
                                    {"a.stl", asciiStl(mesh)}}) {
    SCOPED_TRACE(name);
    const std::string fifo = dir.path(name);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::thread writer([&, data = bytes] {
      FILE* f = std::fopen(fifo.c_str(), "wb");
      if (!f) return;
      std::fwrite(data.data(), 1, data.size(), f);
      std::fclose(f);
    });
    const TriangleMesh read = readMesh(fifo);
    writer.join();
    expectSameMesh(mesh, read);
  }
}

TEST(StlRead, MalformedFilesNameTheFileAndTheProblem) {
  TempDir dir;
  const TriangleMesh tri = testing::gridMesh(1, 1);
  const std::string good = binaryStl(tri, "bin");
  struct Case {
    const char* file;
    std::string content;
    bool isIoError;
    std::vector<std::string> mustContain;
  };
  const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
  const std::vector<Case> cases = {
      {"short.stl", good.substr(0, good.size() - 10), false, {"not an STL file", "84 + 50 x 2 = 184 bytes", "174", "truncated?"}},
      {"long.stl", good + "xx", false, {"not an STL file"}},
      {"header.stl", "solid", false, {"not an STL file"}},
      {"binsolid.stl", binaryStl(tri, "solid x").substr(0, 150), false, {"not an STL file"}},
      {"nanbinary.stl", binaryStl(tri, "b", [](std::string& b, std::size_t f) {
         if (f == 1) {
           const float nan = std::nanf("");
           std::memcpy(&b[b.size() - 2 - 4], &nan, 4);
         }
       }),
       false, {"facet 1", "NaN or infinite"}},
      {"empty.stl", binaryStl(TriangleMesh{}, "b"), false, {"no faces"}},
      {"emptyascii.stl", "solid e\nendsolid e\n", false, {"no faces"}},
      {"noend.stl", "solid a\n" + facet, true, {"ends early", "no 'endsolid' after 1 facets"}},
      {"cut.stl", "solid a\n" + facet + "facet normal 0 0 1\nouter loop\nvertex 0 0 0\n", true, {"ends early", "facet 1"}},
      {"badnumber.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 x 0\n", false, {"line 4", "bad vertex coordinate 'x'"}},
      {"nan.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 nan 0\n", false, {"line 4", "NaN or infinite"}},
      {"huge.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1e99 0\nendloop\nendfacet\n",
       false, {"line 8", "beyond float range"}},
      {"two.stl", "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n", false,
       {"line 7", "2 vertices (at least 3"}},
      {"keyword.stl", "solid a\nfacet normal 0 0 1\nouterloop\n", false, {"line 3", "expected 'outer loop'"}},
      {"garbage.stl", "solid a\n" + facet + "endsolid a\nthis is not STL\n", false, {"line 10", "expected 'solid'"}},
  };
  for (const Case& bad : cases) {
    SCOPED_TRACE(bad.file);
    const std::string path = dir.path(bad.file);
    testing::writeFile(path, bad.content);
    const std::string message = bad.isIoError ? messageOf<IoError>([&] { readMesh(path); })
                                              : messageOf<InputError>([&] { readMesh(path); });
    EXPECT_THAT(message, HasSubstr(path));
    for (const std::string& part : bad.mustContain) EXPECT_THAT(message, HasSubstr(part));
  }
}

TEST(StlWrite, IsRefusedBeforeAnyFileIsMade) {
  TempDir dir;
  const std::string path = dir.path("out.stl");
  EXPECT_THAT(messageOf<IoError>([&] { writeMesh(path, testing::gridMesh(2, 2)); }), HasSubstr("STL is read, not written"));
  struct stat info;
  EXPECT_NE(::stat(path.c_str(), &info), 0);
  std::string output;
  const std::string input = dir.path("in.ply");
  writeMesh(input, testing::gridMesh(2, 2));
  for (const std::string command : {"convert " + input + " " + path, "param " + input + " -o " + path}) {
    EXPECT_EQ(testing::runSeamvox(command, &output), 2) << output;
    EXPECT_THAT(output, HasSubstr("STL"));
  }
  EXPECT_NE(::stat(path.c_str(), &info), 0);
}

// The same mesh as PLY (vertices in first-appearance order) and as binary and ASCII STL: param
// writes the same bytes from each, in memory and out of core, and check calls them seamless.
TEST(StlParam, MapsAnStlAsTheSameMeshFromPly) {
  TempDir dir;
  const TriangleMesh mesh = twoComponents();
  writeMesh(dir.path("m.ply"), mesh);
  testing::writeFile(dir.path("m.stl"), binaryStl(mesh, "solid m"));
  testing::writeFile(dir.path("a.stl"), asciiStl(mesh));
  const std::string options = " --cells 12 --solver voxloc --grid 32 --quiet";
  for (const std::string path : {std::string(), " --out-of-core --memory-budget 700M --scratch " + dir.dir()}) {
    SCOPED_TRACE(path);
    std::string output;
    for (const char* input : {"m.ply", "m.stl", "a.stl"}) {
      const std::string out = dir.path(std::string(input) + (path.empty() ? ".in.ply" : ".ooc.ply"));
      ASSERT_EQ(testing::runSeamvox("param " + dir.path(input) + " -o " + out + options + path, &output), 0) << output;
      EXPECT_THAT(output, HasSubstr(": seamless"));
      ASSERT_EQ(testing::runSeamvox("check " + out, &output), 0) << output;
    }
    const std::string suffix = path.empty() ? ".in.ply" : ".ooc.ply";
    const std::string fromPly = testing::readFile(dir.path("m.ply" + suffix));
    EXPECT_EQ(fromPly, testing::readFile(dir.path("m.stl" + suffix)));
    EXPECT_EQ(fromPly, testing::readFile(dir.path("a.stl" + suffix)));
  }
}

// The memory estimate counts STL's welded vertices (about half the faces), not its corners.
TEST(StlParam, TheMemoryEstimateCountsWeldedVertices) {
  TempDir dir;
  // Large enough for the vertices to weigh in the estimate (corners counted: 9% more).
  const TriangleMesh mesh = testing::torusMesh(400, 200);
  writeMesh(dir.path("m.ply"), mesh);
  testing::writeFile(dir.path("m.stl"), binaryStl(mesh, "b"));
  const auto estimate = [&](const std::string& name) {
    std::string output;
    EXPECT_EQ(testing::runSeamvox("info " + dir.path(name) + " --json", &output), 0) << output;
    const std::size_t at = output.find("\"estimatedBytes\":");
    EXPECT_NE(at, std::string::npos) << output;
    return at == std::string::npos ? 0.0 : std::stod(output.substr(at + 17));
  };
  const double ply = estimate("m.ply"), stl = estimate("m.stl");
  EXPECT_GT(ply, 0.0);
  EXPECT_NEAR(stl / ply, 1.0, 0.01);
}

}  // namespace
}  // namespace seamvox
