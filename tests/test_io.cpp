// Mesh readers and writers: round trips, every PLY encoding and element kind, OBJ and OFF
// syntaxes, BOMs and line ends, devices and pipes, malformed input (mutants: test_fuzz), atomic
// writes, the shared meshes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <future>
#include <limits>
#include <random>
#include <set>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "stream/mesh_stream.h"
#include "testing.h"

namespace seamvox {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;
using testing::writeFile;

/// A rows x cols grid of quads split into triangles, with awkward float positions and per-corner
/// UVs that are not representable in short decimal form.
TriangleMesh makeGrid(int rows, int cols, bool withUV) {
  TriangleMesh mesh;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  for (int i = 0; i <= rows; ++i) {
    for (int j = 0; j <= cols; ++j) {
      mesh.positions.emplace_back(j + jitter(rng), i * 1.1f + jitter(rng), std::sin(0.37f * i * j));
    }
  }
  auto id = [&](int i, int j) { return static_cast<VertexId>(i * (cols + 1) + j); };
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      mesh.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  }
  if (withUV) {
    std::uniform_real_distribution<double> uv(-3000.0, 3000.0);
    std::vector<Vec2d> values;
    for (std::size_t c = 0; c < 3 * mesh.triangles.size(); ++c) values.emplace_back(uv(rng), uv(rng) / 3.0);
    mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
  }
  return mesh;
}

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b, bool compareUV) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t v = 0; v < a.positions.size(); ++v) {
    // Bitwise: float positions must round-trip exactly.
    ASSERT_EQ(0, std::memcmp(a.positions[v].data(), b.positions[v].data(), sizeof(Vec3f))) << "vertex " << v;
  }
  EXPECT_EQ(a.triangles, b.triangles);
  if (compareUV) {
    ASSERT_EQ(a.cornerUV.size(), b.cornerUV.size());
    for (std::size_t c = 0; c < a.cornerUV.size(); ++c) {
      ASSERT_EQ(a.cornerUV[c][0], b.cornerUV[c][0]) << "corner " << c;
      ASSERT_EQ(a.cornerUV[c][1], b.cornerUV[c][1]) << "corner " << c;
    }
  }
}

using testing::messageOf;

// --- round trips --------------------------------------------------------------------------------

TEST(MeshIo, RoundTripsEveryFormatExactly) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(9, 13, true);
  ReadOptions withUV;
  withUV.readUV = true;
  for (const char* name : {"a.ply", "b.obj", "c.off", "D.PLY"}) {
    const std::string path = dir.path(name);
    writeMesh(path, mesh);
    const bool hasUV = formatFromPath(path) != MeshFormat::Off;
    const TriangleMesh back = readMesh(path, withUV);
    expectSameMesh(mesh, back, hasUV);
    EXPECT_EQ(back.hasUV(), hasUV) << name;
    // Without readUV the coordinates are ignored.
    EXPECT_FALSE(readMesh(path).hasUV()) << name;
  }
  WriteOptions ascii;
  ascii.binary = false;
  writeMesh(dir.path("ascii.ply"), mesh, ascii);
  expectSameMesh(mesh, readMesh(dir.path("ascii.ply"), withUV), true);
  EXPECT_THAT(testing::readFile(dir.path("ascii.ply")), HasSubstr("format ascii 1.0"));

  WriteOptions noUV;
  noUV.writeUV = false;
  writeMesh(dir.path("plain.obj"), mesh, noUV);
  EXPECT_FALSE(readMesh(dir.path("plain.obj"), withUV).hasUV());
}

TEST(MeshIo, WrittenPlyHasTheDocumentedLayout) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(2, 2, true);
  writeMesh(dir.path("m.ply"), mesh);
  const std::string bytes = testing::readFile(dir.path("m.ply"));
  EXPECT_THAT(bytes, HasSubstr("format binary_little_endian 1.0"));
  EXPECT_THAT(bytes, HasSubstr("property float x\nproperty float y\nproperty float z\n"));
  EXPECT_THAT(bytes, HasSubstr("property list uchar int vertex_indices\nproperty list uchar double texcoord\n"));
  const std::size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(bytes.size() - body, mesh.positions.size() * 12 + mesh.triangles.size() * (1 + 12 + 1 + 48));
  const std::string obj = (writeMesh(dir.path("m.obj"), mesh), testing::readFile(dir.path("m.obj")));
  EXPECT_THAT(obj, HasSubstr("\nf 1/1 2/2 5/3\n"));
}

TEST(MeshIo, ObjSharesTexcoordsWithinAVertexAndKeepsSeamsApart) {
  TempDir dir;
  TriangleMesh mesh = makeGrid(6, 5, false);
  // A map continuous at every vertex except along column j = 2, where the corners of faces to the
  // right of it get u + 7 (a seam): those vertices need a second texture coordinate.
  const int cols = 5;
  std::size_t seamVertices = 0, seamCorners = 0;
  for (VertexId v = 0; v < mesh.positions.size(); ++v) seamVertices += (v % (cols + 1) == 2);
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) seamCorners += (v % (cols + 1) == 2);
  }
  std::vector<Vec2d> values;
  for (std::size_t c = 0; c < 3 * mesh.triangles.size(); ++c) {
    const Triangle& t = mesh.triangles[c / 3];
    const VertexId v = t[c % 3];
    const bool right = std::min({t[0] % (cols + 1), t[1] % (cols + 1), t[2] % (cols + 1)}) >= 2;
    const Vec3d p = mesh.position(v);
    values.emplace_back(0.37 * p.x() + (right ? 7.0 : 0.0), 1.0 / 3.0 * p.y());
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
  // Two wedges at each seam vertex, one at every other vertex.
  EXPECT_EQ(mesh.cornerUV.numWedges(), mesh.positions.size() + seamVertices);
  writeMesh(dir.path("shared.obj"), mesh);
  const std::string text = testing::readFile(dir.path("shared.obj"));
  std::size_t vtLines = 0;
  for (std::size_t at = text.find("\nvt "); at != std::string::npos; at = text.find("\nvt ", at + 1)) ++vtLines;
  // One per vertex, plus at most one per corner at the seam (each vertex's first value is shared).
  EXPECT_GE(vtLines, mesh.positions.size() + seamVertices);
  EXPECT_LE(vtLines, mesh.positions.size() + seamCorners - seamVertices);
  ReadOptions withUV;
  withUV.readUV = true;
  const TriangleMesh back = readMesh(dir.path("shared.obj"), withUV);
  ASSERT_EQ(back.cornerUV.size(), mesh.cornerUV.size());
  for (std::size_t c = 0; c < mesh.cornerUV.size(); ++c) {
    ASSERT_EQ(back.cornerUV[c], mesh.cornerUV[c]) << "corner " << c;  // shortest round-trip text
  }
}

TEST(MeshIo, StreamsInChunksOfTheRequestedSize) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(10, 10, true);  // 121 vertices, 200 triangles
  for (const char* name : {"s.ply", "s.obj", "s.off"}) {
    writeMesh(dir.path(name), mesh);
    ReadOptions options;
    options.chunkTriangles = 17;
    options.readUV = true;
    auto stream = openMeshStream(dir.path(name), options);
    MeshChunk chunk;
    std::size_t vertices = 0, triangles = 0, chunks = 0;
    while (stream->next(chunk)) {
      ++chunks;
      EXPECT_EQ(chunk.firstVertex, vertices);
      EXPECT_LE(chunk.triangles.size(), 17u);
      EXPECT_LE(chunk.positions.size(), 17u);
      EXPECT_TRUE(chunk.cornerUV.empty() || chunk.cornerUV.size() == 3 * chunk.triangles.size());
      vertices += chunk.positions.size();
      triangles += chunk.triangles.size();
    }
    EXPECT_EQ(vertices, mesh.positions.size()) << name;
    EXPECT_EQ(triangles, mesh.triangles.size()) << name;
    EXPECT_GE(chunks, (121 + 200) / 17u) << name;
    EXPECT_FALSE(stream->next(chunk));
    expectSameMesh(mesh, readMesh(dir.path(name), options), formatFromPath(name) != MeshFormat::Off);
  }
}

// A file rewritten in place (same size, new time) or grown while a stream reads it: an IoError
// naming it, in every format (the reader checks after each read from the file; files larger than
// its 4 MiB buffer are read in several).
TEST(MeshIo, AFileThatChangesWhileItIsReadIsAnError) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(500, 500, true);  // 251K vertices, 500K triangles
  for (const char* name : {"big.ply", "big.obj", "big.off"}) {
    for (const bool grow : {false, true}) {
      writeMesh(dir.path(name), mesh);
      ASSERT_GT(std::filesystem::file_size(dir.path(name)), std::uintmax_t(9) << 20) << name;
      ReadOptions options;
      options.chunkTriangles = 1000;
      auto stream = openMeshStream(dir.path(name), options);
      MeshChunk chunk;
      ASSERT_TRUE(stream->next(chunk));
      if (grow) {
        std::FILE* f = std::fopen(dir.path(name).c_str(), "ab");
        std::fputs("# more\n", f);
        std::fclose(f);
      } else {
        const timespec later[2] = {{0, UTIME_OMIT}, {std::time(nullptr) + 100, 0}};
        ASSERT_EQ(::utimensat(AT_FDCWD, dir.path(name).c_str(), later, 0), 0);
      }
      try {
        while (stream->next(chunk)) {
        }
        ADD_FAILURE() << name << ": the change went unnoticed";
      } catch (const IoError& e) {
        EXPECT_THAT(e.what(), ::testing::HasSubstr(dir.path(name)));
        EXPECT_THAT(e.what(), ::testing::HasSubstr("changed while it was read"));
        if (grow) EXPECT_THAT(e.what(), ::testing::HasSubstr("its size went from"));
      }
    }
    // Unchanged, the same file reads whole.
    EXPECT_EQ(readMesh(dir.path(name)).numFaces(), mesh.numFaces()) << name;
  }
}

TEST(MeshIo, MemoryStreamFeedsCollectMesh) {
  auto mesh = std::make_shared<const TriangleMesh>(makeGrid(4, 5, true));
  auto stream = makeMemoryStream("memory", mesh, 3);
  expectSameMesh(*mesh, collectMesh(*stream), true);
}

/// The triangles as sorted lists of corner (position, UV) values, each rotated to start at its
/// smallest corner: equal for meshes that differ only in vertex and face order.
std::vector<std::array<std::array<double, 5>, 3>> canonicalTriangles(const TriangleMesh& m) {
  std::vector<std::array<std::array<double, 5>, 3>> result;
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    std::array<std::array<double, 5>, 3> corners;
    for (int k = 0; k < 3; ++k) {
      const Vec3f& p = m.positions[m.triangles[f][k]];
      const Vec2d uv = m.hasUV() ? m.cornerUV[3 * f + k] : Vec2d::Zero();
      corners[k] = {p[0], p[1], p[2], uv[0], uv[1]};
    }
    const int first = static_cast<int>(std::min_element(corners.begin(), corners.end()) - corners.begin());
    std::rotate(corners.begin(), corners.begin() + first, corners.end());
    result.push_back(corners);
  }
  std::sort(result.begin(), result.end());
  return result;
}

TEST(DracoIo, RoundTripKeepsGeometryAndUVsExactly) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(12, 9, true);
  WriteOptions lossless;
  lossless.dracoUVBits = 0;  // the UV lattice is tested in test_draco
  writeMesh(dir.path("m.drc"), mesh, lossless);
  ReadOptions options;
  options.readUV = true;
  const TriangleMesh back = readMesh(dir.path("m.drc"), options);
  EXPECT_EQ(back.numVertices(), mesh.numVertices());
  ASSERT_TRUE(back.hasUV());
  EXPECT_EQ(canonicalTriangles(back), canonicalTriangles(mesh));
  EXPECT_FALSE(readMesh(dir.path("m.drc")).hasUV());
  // Chunked like every other format.
  options.chunkTriangles = 10;
  EXPECT_EQ(canonicalTriangles(readMesh(dir.path("m.drc"), options)), canonicalTriangles(mesh));

  writeFile(dir.path("bad.drc"), "DRACO not really");
  EXPECT_THAT(messageOf<InputError>([&] { readMesh(dir.path("bad.drc")); }), HasSubstr(dir.path("bad.drc")));
  EXPECT_THAT(messageOf<IoError>([&] { readMesh(dir.path("missing.drc")); }), HasSubstr("cannot open"));
}

// --- PLY bodies written by hand -----------------------------------------------------------------

enum class Enc { Ascii, Little, Big };

const char* encodingName(Enc e) {
  return e == Enc::Ascii ? "ascii" : e == Enc::Little ? "binary_little_endian" : "binary_big_endian";
}

/// Appends values in one of the three PLY encodings.
struct Body {
  Enc enc;
  std::string bytes;
  template <class T>
  Body& operator()(T value) {
    if (enc == Enc::Ascii) {
      char text[64];
      char* end;
      if constexpr (sizeof(T) == 1) end = std::to_chars(text, text + 64, static_cast<int>(value)).ptr;
      else end = std::to_chars(text, text + 64, value).ptr;
      bytes.append(text, end);
      bytes += ' ';
      return *this;
    }
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    const bool hostBig = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
    if ((enc == Enc::Big) != hostBig) std::reverse(raw, raw + sizeof(T));
    bytes.append(raw, sizeof(T));
    return *this;
  }
  Body& end() {
    if (enc == Enc::Ascii) bytes += '\n';
    return *this;
  }
};

std::string plyFile(Enc enc, const std::string& headerBody, const std::string& body) {
  return std::string("ply\nformat ") + encodingName(enc) + " 1.0\n" + headerBody + "end_header\n" + body;
}

const char* kEveryTypeHeader =
    "comment made by hand\n"
    "obj_info every type and list\n"
    "element material 2\n"
    "property list uchar char names\n"
    "property list ushort short s\n"
    "property list uint ushort us\n"
    "property list char int i\n"
    "property list short uint u\n"
    "property list int float f\n"
    "property list uint8 double d\n"
    "property uchar tag\n"
    "element vertex 5\n"
    "property char a\n"
    "property uchar b\n"
    "property short c\n"
    "property ushort d\n"
    "property int e\n"
    "property uint f\n"
    "property float x\n"
    "property double y\n"
    "property int8 g\n"
    "property float32 z\n"
    "property list uchar int neighbours\n"
    "property float64 nx\n"
    "element face 2\n"
    "property uchar flags\n"
    "property list ushort uint vertex_indices\n"
    "property list int float other\n"
    "property list uchar double texcoord\n"
    "property int16 id\n"
    "element edge 1\n"
    "property int vertex1\n"
    "property int vertex2\n"
    "property list uint uint8 more\n";

const float kX[5] = {0.1f, 1.7f, -2.25f, 3.0e-5f, 1234.5f};
const double kY[5] = {0.25, -1.5, 7.0, 2.0, -0.125};
const float kZ[5] = {1.0f / 3.0f, 0.0f, -7.75f, 5.5f, 0.2f};
const double kUV[14] = {0.1, 0.2, 1.0 / 3.0, -5.5, 1e-9, 2999.999, 4.0, 5.0, 6.25, 7.5, -8.0, 9.0, 10.5, 11.0};

std::string everyTypeBody(Enc enc) {
  Body b{enc, {}};
  for (int m = 0; m < 2; ++m) {
    b(std::uint8_t(2))(std::int8_t(-3))(std::int8_t(4));
    b(std::uint16_t(1))(std::int16_t(-300));
    b(std::uint32_t(0));
    b(std::int8_t(2))(std::int32_t(-70000))(std::int32_t(5));
    b(std::int16_t(1))(std::uint32_t(4000000000u));
    b(std::int32_t(2))(1.5f)(-2.5f);
    b(std::uint8_t(1))(0.125);
    b(std::uint8_t(9)).end();
  }
  for (int v = 0; v < 5; ++v) {
    b(std::int8_t(-1))(std::uint8_t(200))(std::int16_t(-2))(std::uint16_t(60000))(std::int32_t(-5))(
        std::uint32_t(7));
    b(kX[v])(kY[v])(std::int8_t(3))(kZ[v]);
    b(std::uint8_t(v % 3));
    for (int k = 0; k < v % 3; ++k) b(std::int32_t(k));
    b(0.5).end();
  }
  // A triangle and a quad, each with other values around the index list.
  b(std::uint8_t(1))(std::uint16_t(3))(std::uint32_t(0))(std::uint32_t(1))(std::uint32_t(2));
  b(std::int32_t(2))(9.5f)(8.5f)(std::uint8_t(6));
  for (int k = 0; k < 6; ++k) b(kUV[k]);
  b(std::int16_t(-1)).end();
  b(std::uint8_t(0))(std::uint16_t(4))(std::uint32_t(1))(std::uint32_t(3))(std::uint32_t(4))(std::uint32_t(2));
  b(std::int32_t(0))(std::uint8_t(8));
  for (int k = 6; k < 14; ++k) b(kUV[k]);
  b(std::int16_t(2)).end();
  b(std::int32_t(0))(std::int32_t(1))(std::uint32_t(3))(std::uint8_t(1))(std::uint8_t(2))(std::uint8_t(3)).end();
  return b.bytes;
}

TEST(PlyRead, EveryTypeAndListInAllThreeEncodings) {
  TempDir dir;
  ReadOptions withUV;
  withUV.readUV = true;
  for (const Enc enc : {Enc::Ascii, Enc::Little, Enc::Big}) {
    SCOPED_TRACE(encodingName(enc));
    const std::string path = dir.path(std::string(encodingName(enc)) + ".ply");
    writeFile(path, plyFile(enc, kEveryTypeHeader, everyTypeBody(enc)));
    const TriangleMesh mesh = readMesh(path, withUV);
    ASSERT_EQ(mesh.numVertices(), 5u);
    for (int v = 0; v < 5; ++v) {
      EXPECT_EQ(mesh.positions[v][0], kX[v]);
      EXPECT_EQ(mesh.positions[v][1], static_cast<float>(kY[v]));
      EXPECT_EQ(mesh.positions[v][2], kZ[v]);
    }
    // The quad (1 3 4 2) is fan-triangulated from its first corner.
    const std::vector<Triangle> expected = {{0, 1, 2}, {1, 3, 4}, {1, 4, 2}};
    EXPECT_EQ(mesh.triangles, expected);
    ASSERT_EQ(mesh.cornerUV.size(), 9u);
    const int uvOfCorner[9] = {0, 1, 2, 3, 4, 5, 3, 5, 6};  // indices into the (u, v) pairs
    for (int c = 0; c < 9; ++c) {
      EXPECT_EQ(mesh.cornerUV[c][0], kUV[2 * uvOfCorner[c]]) << c;
      EXPECT_EQ(mesh.cornerUV[c][1], kUV[2 * uvOfCorner[c] + 1]) << c;
    }
    EXPECT_FALSE(readMesh(path).hasUV());
    // Every scalar vertex property besides x, y, z is kept with its type; the list is not.
    EXPECT_EQ(mesh.attributes.describe(), "char a, uchar b, short c, ushort d, int e, uint f, char g, double nx");
    const double values[8] = {-1, 200, -2, 60000, -5, 7, 3, 0.5};
    for (std::size_t k = 0; k < 8; ++k) {
      for (VertexId v = 0; v < 5; ++v) EXPECT_EQ(mesh.attributes.properties[k].value(v), values[k]) << k;
    }
  }
}

TEST(PlyRead, VertexIndexNameSmallTypesAndCrlfHeader) {
  TempDir dir;
  for (const Enc enc : {Enc::Ascii, Enc::Little, Enc::Big}) {
    Body b{enc, {}};
    b(std::int16_t(0))(std::int16_t(0))(std::int16_t(0)).end();
    b(std::int16_t(1))(std::int16_t(0))(std::int16_t(0)).end();
    b(std::int16_t(0))(std::int16_t(1))(std::int16_t(0)).end();
    b(std::uint8_t(3))(std::uint8_t(0))(std::uint8_t(1))(std::uint8_t(2)).end();
    std::string header = std::string("ply\r\nformat ") + encodingName(enc) +
                         " 1.0\r\nelement vertex 3\r\nproperty short x\r\nproperty short y\r\n"
                         "property short z\r\nelement face 1\r\nproperty list uchar uchar vertex_index\r\n"
                         "end_header\n";
    const std::string path = dir.path("small.ply");
    writeFile(path, header + b.bytes);
    const TriangleMesh mesh = readMesh(path);
    ASSERT_EQ(mesh.numFaces(), 1u);
    EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
    EXPECT_EQ(mesh.positions[1], Vec3f(1, 0, 0));
  }
}

/// Signed doubled area of a triangle in the xy plane.
double orientation(const TriangleMesh& m, const Triangle& t) {
  const Vec3f a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

TEST(PlyRead, TristripsKeepOneOrientationAndSkipDegenerates) {
  TempDir dir;
  // A zigzag of 8 vertices: bottom row at y=0, top row at y=1.
  const int strip[] = {0, 4, 1, 5, 2, 6, 3, 7, -1, 0, 4, 1, 1, 1, 5, 2, 6};
  for (const Enc enc : {Enc::Ascii, Enc::Little, Enc::Big}) {
    SCOPED_TRACE(encodingName(enc));
    Body b{enc, {}};
    for (int i = 0; i < 4; ++i) b(float(i))(0.0f)(0.0f).end();
    for (int i = 0; i < 4; ++i) b(float(i))(1.0f)(0.0f).end();
    b(std::int32_t(17));
    for (const int s : strip) b(std::int32_t(s));
    b.end();
    const std::string path = dir.path("strips.ply");
    writeFile(path, plyFile(enc,
                            "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                            "element tristrips 1\nproperty list int int vertex_indices\n",
                            b.bytes));
    const TriangleMesh mesh = readMesh(path);
    // First strip: 6 triangles. Second: (0 4 1), three degenerate ones (the doubled repeat keeps
    // the parity), then (1 5 2) and (5 2 6) flipped.
    ASSERT_EQ(mesh.numFaces(), 6u + 3u);
    const double first = orientation(mesh, mesh.triangles[0]);
    EXPECT_NE(first, 0.0);
    for (const Triangle& t : mesh.triangles) {
      EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
      EXPECT_GT(orientation(mesh, t) * first, 0.0) << t[0] << " " << t[1] << " " << t[2];
    }
    // The first strip covers the 3 x 1 band, the second 3 half cells of it again.
    double area = 0;
    for (const Triangle& t : mesh.triangles) area += std::abs(orientation(mesh, t)) / 2;
    EXPECT_DOUBLE_EQ(area, 3.0 + 1.5);
  }
}

// --- OBJ and OFF syntaxes -----------------------------------------------------------------------

TEST(ObjRead, AllFaceSyntaxesNegativeIndicesPolygonsAndCrlf) {
  TempDir dir;
  const std::string path = dir.path("syntax.obj");
  writeFile(path,
            "# comment\r\n"
            "mtllib x.mtl\r\n"
            "o object\r\ng group\r\ns 1\r\nusemtl red\r\n"
            "f 1 2 3\r\n"  // forward reference
            "v 0 0 0\r\n"
            "v 1 0 0 1.0\r\n"         // w ignored
            "v 1 1 0 0.5 0.5 0.5\r\n"  // colour ignored
            "v 0 1 0\r\n"
            "vt 0.5 0.25\r\nvt 0.75 0.125\r\nvt 0.1 0.2\r\nvt 0.3 0.4\r\n"
            "vn 0 0 1\r\n"
            "f 1/1 2/2 3/3\r\n"
            "f 1//1 3//1 4//1\r\n"
            "f -4/-4/1 -3/-3/1 -2/-2/1 -1/-1/1\r\n"
            "l 1 2\r\np 3\r\n"
            "f 1 2 3 4 # trailing comment\r\n");
  const TriangleMesh mesh = readMesh(path);
  ASSERT_EQ(mesh.numVertices(), 4u);
  EXPECT_EQ(mesh.positions[1], Vec3f(1, 0, 0));
  const std::vector<Triangle> expected = {{0, 1, 2}, {0, 1, 2}, {0, 2, 3}, {0, 1, 2},
                                          {0, 2, 3}, {0, 1, 2}, {0, 2, 3}};
  EXPECT_EQ(mesh.triangles, expected);
  EXPECT_FALSE(mesh.hasUV());
}

TEST(ObjRead, TexcoordsPerCornerWhenAsked) {
  TempDir dir;
  const std::string path = dir.path("uv.obj");
  writeFile(path,
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
            "vt 0.5 0.25\nvt 0.75 0.125\nvt 0.1 0.2\nvt 0.3 0.4 0.0\n"
            "f 1/4 2/3 3/2\n"
            "f -4/-4/1 -3/-3/1 -2/-2/1 -1/-1/1\n");
  ReadOptions options;
  options.readUV = true;
  const TriangleMesh mesh = readMesh(path, options);
  ASSERT_EQ(mesh.numFaces(), 3u);
  ASSERT_EQ(mesh.cornerUV.size(), 9u);
  EXPECT_EQ(mesh.cornerUV[0], Vec2d(0.3, 0.4));
  EXPECT_EQ(mesh.cornerUV[1], Vec2d(0.1, 0.2));
  EXPECT_EQ(mesh.cornerUV[2], Vec2d(0.75, 0.125));
  // The quad with relative indices: vt 1..4 on vertices 1..4, fan (1 2 3), (1 3 4).
  EXPECT_EQ(mesh.cornerUV[3], Vec2d(0.5, 0.25));
  EXPECT_EQ(mesh.cornerUV[7], Vec2d(0.1, 0.2));
  EXPECT_EQ(mesh.cornerUV[8], Vec2d(0.3, 0.4));
}

TEST(OffRead, HeaderVariantsCommentsAndColours) {
  TempDir dir;
  const std::string faces = "3 0 1 2\n4 0 2 3 1 255 0 0\n";
  const std::vector<std::pair<const char*, std::string>> files = {
      {"plain.off", "OFF\n# a comment\n\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n" + faces},
      {"oneline.off", "OFF 4 2 0\n0 0 0\n1 0 0 # comment\n1 1 0\n0 1 0\n" + faces},
      {"colour.off", "COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n" + faces},
      {"normal.off", "NOFF\r\n4 2 0\r\n0 0 0 0 0 1\r\n1 0 0 0 0 1\r\n1 1 0 0 0 1\r\n0 1 0 0 0 1\r\n3 0 1 2\r\n4 0 2 3 1\r\n"},
      {"texture.off", "STCOFF\n4 2 0\n0 0 0 0 0 1 1 1 1\n1 0 0 1 0 1 1 1 1\n1 1 0 1 1 1 1 1 1\n0 1 0 0 1 1 1 1 1\n" + faces},
      {"four.off", "4OFF\n4 2 0\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n" + faces},
  };
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    writeFile(dir.path(name), text);
    const TriangleMesh mesh = readMesh(dir.path(name));
    ASSERT_EQ(mesh.numVertices(), 4u);
    EXPECT_EQ(mesh.positions[2], Vec3f(1, 1, 0));
    const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}};
    EXPECT_EQ(mesh.triangles, expected);
  }
}

// --- text encodings, tiny numbers, strip restarts ----------------------------------------------

/// The same unit square (4 vertices, 2 triangles) in every text format, lines ending in "\n".
std::vector<std::pair<const char*, std::string>> squareTexts() {
  const std::string plyHeader =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string points = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
  return {{"square.obj", "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"},
          {"square.off", "OFF\n4 2 0\n" + points + "3 0 1 2\n3 0 2 3\n"},
          {"square.ply", plyHeader + points + "3 0 1 2\n3 0 2 3\n"}};
}

std::string withLineEnds(const std::string& text, const std::string& end) {
  std::string out;
  for (const char c : text) out += c == '\n' ? end : std::string(1, c);
  return out;
}

TEST(TextRead, ByteOrderMarkAndEveryLineEnd) {
  TempDir dir;
  const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}};
  for (const auto& [name, text] : squareTexts()) {
    for (const char* end : {"\n", "\r\n", "\r"}) {
      for (const bool bom : {false, true}) {
        SCOPED_TRACE(std::string(name) + (bom ? " with BOM, " : ", ") + (end[0] == '\n' ? "LF" : end[1] ? "CRLF" : "CR"));
        const std::string path = dir.path(name);
        writeFile(path, (bom ? "\xEF\xBB\xBF" : "") + withLineEnds(text, end));
        const TriangleMesh mesh = readMesh(path);
        ASSERT_EQ(mesh.numVertices(), 4u);
        EXPECT_EQ(mesh.positions[2], Vec3f(1, 1, 0));
        EXPECT_EQ(mesh.triangles, expected);
      }
    }
  }
  // A CR file's errors count lines like any other.
  writeFile(dir.path("cr.obj"), "v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 9\r");
  EXPECT_THAT(messageOf<InputError>([&] { readMesh(dir.path("cr.obj")); }), HasSubstr("line 4"));
}

TEST(TextRead, DenormalCoordinatesAreNumbersAndHugeOnesAreNot) {
  TempDir dir;
  for (const auto& [name, text] : squareTexts()) {
    SCOPED_TRACE(name);
    // "1 0 0" is the second vertex in every format: make its y tiny (a float denormal, then below
    // every float, which reads as 0).
    for (const auto& [tiny, value] : {std::pair<const char*, float>{"1e-40", 1e-40f}, {"1e-320", 0.0f},
                                      {"-4.9e-324", -0.0f}}) {
      std::string bytes = text;
      bytes.replace(bytes.find("\n1 0 0\n") != std::string::npos ? bytes.find("\n1 0 0\n") + 3
                                                                 : bytes.find("v 1 0 0") + 4,
                    1, tiny);
      writeFile(dir.path(name), bytes);
      const TriangleMesh mesh = readMesh(dir.path(name));
      EXPECT_EQ(mesh.positions[1][1], value) << tiny;
      EXPECT_TRUE(std::isfinite(mesh.positions[1][1]));
    }
    std::string huge = text;
    huge.replace(huge.find("\n1 0 0\n") != std::string::npos ? huge.find("\n1 0 0\n") + 3 : huge.find("v 1 0 0") + 4,
                 1, "1e39");
    writeFile(dir.path(name), huge);
    const std::string message = messageOf<InputError>([&] { readMesh(dir.path(name)); });
    EXPECT_THAT(message, HasSubstr(dir.path(name)));
    EXPECT_THAT(message, HasSubstr("infinite"));
  }
}

TEST(PlyRead, TristripRestartsInSignedAndUnsignedIndexTypes) {
  TempDir dir;
  const int strip[] = {0, 4, 1, 5, -1, 1, 5, 2, 6, 3, 7};  // 2 + 4 triangles
  for (const Enc enc : {Enc::Ascii, Enc::Little, Enc::Big}) {
    for (const char* type : {"int", "uint", "short", "ushort"}) {
      SCOPED_TRACE(std::string(encodingName(enc)) + " " + type);
      Body b{enc, {}};
      for (int i = 0; i < 4; ++i) b(float(i))(0.0f)(0.0f).end();
      for (int i = 0; i < 4; ++i) b(float(i))(1.0f)(0.0f).end();
      b(std::uint8_t(sizeof strip / sizeof strip[0]));
      for (const int s : strip) {
        if (!std::strcmp(type, "int")) b(std::int32_t(s));
        else if (!std::strcmp(type, "uint")) b(static_cast<std::uint32_t>(s));  // -1: 0xFFFFFFFF
        else if (!std::strcmp(type, "short")) b(std::int16_t(s));
        else b(static_cast<std::uint16_t>(s));
      }
      b.end();
      const std::string path = dir.path("strips.ply");
      writeFile(path, plyFile(enc,
                              "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                              "element tristrips 1\nproperty list uchar " + std::string(type) + " vertex_indices\n",
                              b.bytes));
      const TriangleMesh mesh = readMesh(path);
      ASSERT_EQ(mesh.numFaces(), 6u);
      double area = 0;
      for (const Triangle& t : mesh.triangles) {
        EXPECT_GT(orientation(mesh, t) * orientation(mesh, mesh.triangles[0]), 0.0);
        area += std::abs(orientation(mesh, t)) / 2;
      }
      EXPECT_DOUBLE_EQ(area, 1.0 + 2.0);
    }
  }
}

// --- devices and pipes ----------------------------------------------------------------------------

/// Runs read (which opens fifo) and fails the test when it takes more than 10 s; a reader stuck
/// in open() is released by opening the write end, so the test ends either way.
void expectReturnsQuickly(const std::string& fifo, const std::function<void()>& read) {
  auto done = std::async(std::launch::async, read);
  if (done.wait_for(std::chrono::seconds(10)) == std::future_status::timeout) {
    ADD_FAILURE() << fifo << ": reading a pipe without a writer hangs";
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
  }
  done.get();
}

TEST(MeshIo, DevicesAreRefusedAtOnce) {
  TempDir dir;
  for (const char* name : {"zero.obj", "zero.ply", "zero.off", "zero.drc"}) {
    const std::string link = dir.path(name);
    std::filesystem::create_symlink("/dev/zero", link);
    const std::string message = messageOf<IoError>([&] { readMesh(link); });
    EXPECT_THAT(message, HasSubstr(link));
    EXPECT_THAT(message, HasSubstr("character device"));
  }
}

TEST(MeshIo, PipeWithoutWriterFailsAfterTheWait) {
  TempDir dir;
  ::signal(SIGPIPE, SIG_IGN);
  for (const char* name : {"nowriter.obj", "nowriter.drc"}) {
    const std::string fifo = dir.path(name);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    ReadOptions options;
    options.pipeWaitSeconds = 0.2;
    const auto start = std::chrono::steady_clock::now();
    expectReturnsQuickly(fifo, [&] {
      const std::string message = messageOf<IoError>([&] { readMesh(fifo, options); });
      EXPECT_THAT(message, HasSubstr(fifo));
      EXPECT_THAT(message, HasSubstr("nothing was written"));
    });
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  }
}

/// Writes bytes into a FIFO from another thread (it opens when the reader does).
class PipeWriter {
 public:
  PipeWriter(std::string fifo, std::string bytes)
      : thread_([fifo = std::move(fifo), bytes = std::move(bytes)] {
          const int fd = ::open(fifo.c_str(), O_WRONLY);
          if (fd < 0) return;
          for (std::size_t at = 0; at < bytes.size();) {
            const ssize_t n = ::write(fd, bytes.data() + at, std::min<std::size_t>(bytes.size() - at, 1000));
            if (n <= 0) break;  // the reader stopped early
            at += static_cast<std::size_t>(n);
          }
          ::close(fd);
        }) {}
  ~PipeWriter() { thread_.join(); }

 private:
  std::thread thread_;
};

TEST(MeshIo, PipesAreReadAsStreams) {
  TempDir dir;
  ::signal(SIGPIPE, SIG_IGN);
  const TriangleMesh mesh = makeGrid(30, 30, true);
  WriteOptions lossless;
  lossless.dracoUVBits = 0;
  WriteOptions ascii;
  ascii.binary = false;
  ReadOptions options;
  options.readUV = true;
  for (const auto& [name, write] : {std::pair<const char*, WriteOptions>{"p.obj", {}}, {"p.off", {}},
                                    {"p.ply", {}}, {"q.ply", ascii}, {"p.drc", lossless}}) {
    SCOPED_TRACE(name);
    const std::string file = dir.path(std::string("file_") + name), fifo = dir.path(name);
    writeMesh(file, mesh, write);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    TriangleMesh fromPipe;
    {
      PipeWriter writer(fifo, testing::readFile(file));
      expectReturnsQuickly(fifo, [&] { fromPipe = readMesh(fifo, options); });
    }
    const TriangleMesh fromFile = readMesh(file, options);
    expectSameMesh(fromFile, fromPipe, formatFromPath(name) != MeshFormat::Off);
  }
  // A pipe cannot seek: the binary PLY reader skips an unused element by reading through it.
  const std::string fifo = dir.path("skip.ply");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  Body b{Enc::Little, {}};
  for (int i = 0; i < 3; ++i) b(std::int32_t(i))(0.5 * i);
  b(0.0f)(0.0f)(0.0f)(1.0f)(0.0f)(0.0f)(0.0f)(1.0f)(0.0f)(std::uint8_t(3))(std::int32_t(0))(std::int32_t(1))(std::int32_t(2));
  const std::string bytes = plyFile(Enc::Little,
                                    "element block 3\nproperty int a\nproperty double b\n"
                                    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                    "element face 1\nproperty list uchar int vertex_indices\n",
                                    b.bytes);
  TriangleMesh fromPipe;
  {
    PipeWriter writer(fifo, bytes);
    expectReturnsQuickly(fifo, [&] { fromPipe = readMesh(fifo); });
  }
  EXPECT_EQ(fromPipe.numFaces(), 1u);
  EXPECT_EQ(fromPipe.positions[2], Vec3f(0, 1, 0));
}

// --- malformed input ----------------------------------------------------------------------------

struct BadCase {
  const char* file;
  std::string content;
  bool isIoError;
  std::vector<std::string> mustContain;  ///< besides the file name
};

TEST(MeshIo, MalformedInputNamesFileLocationAndProblem) {
  TempDir dir;
  const std::string v3 = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
  auto binaryTriangle = [](int index, float x) {
    Body b{Enc::Little, {}};
    b(0.0f)(0.0f)(0.0f)(1.0f)(0.0f)(0.0f)(x)(1.0f)(0.0f);
    b(std::uint8_t(3))(std::int32_t(0))(std::int32_t(1))(std::int32_t(index));
    return b.bytes;
  };
  const std::vector<BadCase> cases = {
      {"unknown.ply", plyFile(Enc::Ascii, "element vertex 3\nproperty int64 x\n", ""), false,
       {"line 4", "unsupported PLY type 'int64'"}},
      {"format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", false, {"line 2", "unknown PLY format"}},
      {"keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n", false, {"line 3", "unknown PLY header keyword"}},
      {"noend.ply", "ply\nformat ascii 1.0\n" + v3, false, {"no end_header"}},
      {"notply.ply", "solid cube\nfacet normal 0 0 1\n", false, {"not a PLY file"}},
      {"novertex.ply", plyFile(Enc::Ascii, "element vertex 1\nproperty float x\n", "1\n"), false, {"x, y and z"}},
      {"range.ply", plyFile(Enc::Little, v3 + face, binaryTriangle(3, 1.0f)), false,
       {"element 'face' 0", "vertex index 3 is out of range"}},
      {"range_ascii.ply", plyFile(Enc::Ascii, v3 + face, "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"), false,
       {"line 13", "vertex index -1 is out of range"}},
      {"nan.ply", plyFile(Enc::Little, v3 + face, binaryTriangle(2, std::nanf(""))), false,
       {"element 'vertex' 2", "NaN or infinite"}},
      {"inf.ply", plyFile(Enc::Ascii, v3 + face, "0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"), false,
       {"line 11", "NaN or infinite"}},
      {"twoface.ply", plyFile(Enc::Ascii, v3 + face, "0 0 0\n1 0 0\n0 1 0\n2 0 1\n"), false,
       {"line 13", "at least 3"}},
      {"badnumber.ply", plyFile(Enc::Ascii, v3 + face, "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"), false,
       {"line 11", "bad number 'x'"}},
      {"empty.ply", plyFile(Enc::Ascii, v3, "0 0 0\n1 0 0\n0 1 0\n"), false, {"no faces"}},
      {"huge.ply", plyFile(Enc::Little, "element vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\n", "abc"),
       true, {"1000000000000", "truncated or its header is wrong"}},
      {"huge_ascii.ply", plyFile(Enc::Ascii, "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                              "element face 1000000000000\nproperty list uchar int vertex_indices\n",
                                 "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
       true, {"'face'", "truncated or its header is wrong"}},
      {"hugelist.ply", plyFile(Enc::Little, v3 + "element face 1\nproperty list uint int vertex_indices\n",
                               binaryTriangle(2, 1.0f).substr(0, 36) + std::string("\xff\xff\xff\x7f", 4) + "12345678"),
       true, {"element 'face' 0", "truncated"}},
      {"short.ply", plyFile(Enc::Ascii, v3 + face, "0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), true, {"line 13", "ends early"}},
      {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 1 2\n", false, {"line 6", "at least 3"}},
      {"b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\nv 1 1 1\n", false,
       {"line 5", "vertex 7 but the file has only 4"}},
      {"c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", false, {"line 4", "reaches before the first"}},
      {"d.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", false, {"line 2", "NaN or infinite"}},
      {"e.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", false, {"line 2", "fewer than 3"}},
      {"f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", false, {"line 4", "index 0 is invalid"}},
      {"g.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", false, {"line 4", "bad vertex index"}},
      {"h.obj", "# nothing\nv 0 0 0\n", false, {"no faces"}},
      {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", false, {"line 6", "vertex index 3 is out of range"}},
      {"b.off", "PLY\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", false, {"line 1", "not an OFF file"}},
      {"c.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1 # padding\n", false, {"line 6", "at least 3"}},
      {"d.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n", false, {"line 4", "NaN or infinite"}},
      {"e.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n# padding padding padding padding\n", true, {"truncated", "2 of 3 vertices"}},
      {"f.off", "OFF\n3000000000000 1 0\n0 0 0\n", true, {"line 2", "truncated or its header is wrong"}},
      {"g.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", false, {"no faces"}},
      {"h.off", "", false, {"not an OFF file"}},
      {"mesh.stp", "solid\n", true, {"unknown mesh format"}},
  };
  for (const BadCase& bad : cases) {
    SCOPED_TRACE(bad.file);
    const std::string path = dir.path(bad.file);
    writeFile(path, bad.content);
    const std::string message = bad.isIoError ? messageOf<IoError>([&] { readMesh(path); })
                                              : messageOf<InputError>([&] { readMesh(path); });
    EXPECT_THAT(message, HasSubstr(path));
    for (const std::string& part : bad.mustContain) EXPECT_THAT(message, HasSubstr(part));
  }
}

TEST(MeshIo, MissingFilesAndFoldersAreIoErrors) {
  TempDir dir;
  EXPECT_THAT(messageOf<IoError>([&] { readMesh(dir.path("missing.ply")); }),
              HasSubstr(dir.path("missing.ply") + ": cannot open"));
  std::filesystem::create_directory(dir.path("folder.obj"));
  EXPECT_THAT(messageOf<IoError>([&] { readMesh(dir.path("folder.obj")); }), HasSubstr("is a folder"));
  EXPECT_THAT(messageOf<IoError>([&] { readMesh(dir.path("noextension")); }), HasSubstr("unknown mesh format"));
}

TEST(PlyRead, TruncatedBinaryFailsCleanlyAtEveryCut) {
  TempDir dir;
  const std::string whole = dir.path("whole.ply");
  TriangleMesh grid = makeGrid(5, 5, true);
  grid.attributes.add("red", ScalarType::UInt8, grid.numVertices());  // cuts fall inside them too
  grid.attributes.add("quality", ScalarType::Float64, grid.numVertices());
  writeMesh(whole, grid);
  const std::string bytes = testing::readFile(whole);
  const std::size_t body = bytes.find("end_header\n") + 11;
  ReadOptions options;
  options.readUV = true;
  std::size_t cuts = 0;
  for (std::size_t cut = body; cut < bytes.size(); cut += 37, ++cuts) {
    const std::string path = dir.path("cut.ply");
    writeFile(path, bytes.substr(0, cut));
    const std::string message = messageOf<IoError>([&] { readMesh(path, options); });
    EXPECT_THAT(message, HasSubstr(path)) << cut;
    EXPECT_THAT(message, HasSubstr("truncated")) << cut;
  }
  EXPECT_GT(cuts, 50u);
  // Cuts inside the header are header errors.
  writeFile(dir.path("header.ply"), bytes.substr(0, body - 11));
  EXPECT_THAT(messageOf<InputError>([&] { readMesh(dir.path("header.ply")); }), HasSubstr("end_header"));
}

// Binary faces of a one-byte count and 32-bit indices are read in runs: the same triangles as
// the general path (ASCII, and big-endian on this machine) with the index types and counts a
// scan's files use, a quad and a bad index in the middle of a run, runs across chunks, and files
// cut inside the faces.
TEST(PlyRead, RunsOfTrianglesAsTheGeneralPath) {
  TempDir dir;
  constexpr int kFaces = 9000, kVertices = 40;
  const auto file = [&](Enc enc, const std::string& list, int quadAt, int badAt, int nanAt = -1) {
    Body b{enc, {}};
    for (int v = 0; v < kVertices; ++v) {
      b(float(v) * 0.37f)(v == nanAt ? std::numeric_limits<float>::quiet_NaN() : float(v % 7))(float(v % 3) - 1e-3f).end();
    }
    for (int f = 0; f < kFaces; ++f) {
      const int n = f == quadAt ? 4 : 3;
      b(std::uint8_t(n));
      for (int k = 0; k < n; ++k) {
        const std::uint32_t v = f == badAt && k == 1 ? kVertices : (f * 7 + k * 13) % kVertices;
        if (list == "int") b(std::int32_t(v));
        else b(std::uint32_t(v));
      }
      b.end();
    }
    return plyFile(enc, "element vertex " + std::to_string(kVertices) +
                            "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                            std::to_string(kFaces) + "\nproperty list uchar " + list + " vertex_indices\n",
                   b.bytes);
  };
  ReadOptions chunks;
  chunks.chunkTriangles = 1000;  // runs end at chunk limits too
  for (const std::string list : {"int", "uint"}) {
    for (const int quadAt : {-1, 0, 4095, 4096, 8999}) {
      SCOPED_TRACE(list + " quad at " + std::to_string(quadAt));
      writeFile(dir.path("a.ply"), file(Enc::Ascii, list, quadAt, -1));
      writeFile(dir.path("b.ply"), file(Enc::Big, list, quadAt, -1));
      writeFile(dir.path("l.ply"), file(Enc::Little, list, quadAt, -1));
      const TriangleMesh expected = readMesh(dir.path("a.ply"));
      ASSERT_EQ(expected.numFaces(), std::size_t(kFaces) + (quadAt >= 0));
      for (const TriangleMesh& mesh :
           {readMesh(dir.path("b.ply")), readMesh(dir.path("l.ply")), readMesh(dir.path("l.ply"), chunks)}) {
        EXPECT_EQ(mesh.triangles, expected.triangles);
        EXPECT_EQ(mesh.positions, expected.positions);
      }
    }
    // Vertices are read in runs too: a coordinate that is not finite is named by its vertex.
    for (const int nanAt : {1, 20, kVertices - 1}) {
      writeFile(dir.path("nan.ply"), file(Enc::Little, list, -1, -1, nanAt));
      const std::string message = messageOf<InputError>([&] { readMesh(dir.path("nan.ply")); });
      EXPECT_THAT(message, HasSubstr("element 'vertex' " + std::to_string(nanAt))) << list;
      EXPECT_THAT(message, HasSubstr("NaN or infinite")) << list;
    }
    for (const int badAt : {0, 2100, 8999}) {
      writeFile(dir.path("bad.ply"), file(Enc::Little, list, -1, badAt));
      const std::string message = messageOf<InputError>([&] { readMesh(dir.path("bad.ply")); });
      EXPECT_THAT(message, HasSubstr("element 'face' " + std::to_string(badAt))) << list;
      EXPECT_THAT(message, HasSubstr("out of range")) << list;
    }
    const std::string whole = file(Enc::Little, list, -1, -1);
    for (const std::size_t cut : {whole.size() - 1, whole.size() - 13 * 3000 - 5, whole.size() - 13 * 8999}) {
      writeFile(dir.path("cut.ply"), whole.substr(0, cut));
      EXPECT_THAT(messageOf<IoError>([&] { readMesh(dir.path("cut.ply")); }), HasSubstr("truncated")) << cut;
    }
  }
}

// --- writing ------------------------------------------------------------------------------------

TEST(MeshIo, FailedWritesLeaveNoFile) {
  TempDir dir;
  const TriangleMesh mesh = makeGrid(2, 2, false);
  EXPECT_THAT(messageOf<IoError>([&] { writeMesh(dir.path("missing/out.ply"), mesh); }),
              HasSubstr(dir.path("missing/out.ply")));
  EXPECT_FALSE(std::filesystem::exists(dir.path("missing")));

  TriangleMesh broken = mesh;
  broken.triangles[1][2] = 99;
  EXPECT_THAT(messageOf<InputError>([&] { writeMesh(dir.path("broken.obj"), broken); }), HasSubstr("face 1"));
  TriangleMesh badUV = mesh;
  badUV.cornerUV.resizeCorners(5);
  EXPECT_THAT(messageOf<InputError>([&] { writeMesh(dir.path("baduv.ply"), badUV); }), HasSubstr("corner UVs"));
  EXPECT_THAT(messageOf<IoError>([&] { writeMesh(dir.path("x.unknown"), mesh); }), HasSubstr("unknown mesh format"));
  EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));

  // Overwriting replaces the old content completely.
  writeMesh(dir.path("m.off"), makeGrid(6, 6, false));
  writeMesh(dir.path("m.off"), mesh);
  expectSameMesh(mesh, readMesh(dir.path("m.off")), false);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.dir()), {}), 1);
}

// --- shared meshes ------------------------------------------------------------------------------

TEST(SharedMeshes, FertilityCounts) {
  const std::string path = testing::sharedMesh("fertility.off");
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage("fertility.off");
  const TriangleMesh mesh = readMesh(path);
  EXPECT_EQ(mesh.numVertices(), 4494u);
  EXPECT_EQ(mesh.numFaces(), 9000u);
}

TEST(SharedMeshes, EveryMeshReadsAndRoundTrips) {
  const std::string readme = testing::sharedMesh("README.md");
  if (readme.empty()) GTEST_SKIP() << testing::missingSharedMessage("README.md");
  const std::filesystem::path folder = std::filesystem::path(readme).parent_path();
  TempDir dir;
  int read = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string path = entry.path().string();
    if (formatFromPath(path) == MeshFormat::Unknown) continue;
    SCOPED_TRACE(path);
    ReadOptions options;
    options.readUV = true;
    const TriangleMesh mesh = readMesh(path, options);
    EXPECT_GT(mesh.numFaces(), 1000u);
    EXPECT_TRUE(mesh.cornerUV.empty() || mesh.cornerUV.size() == 3 * mesh.triangles.size());
    ++read;
    const std::string copy = dir.path("copy.ply");
    writeMesh(copy, mesh);
    expectSameMesh(mesh, readMesh(copy, options), true);
  }
  EXPECT_GE(read, 10);
  const std::string spot = testing::sharedMesh("spot.obj");
  if (!spot.empty()) {
    ReadOptions options;
    options.readUV = true;
    EXPECT_TRUE(readMesh(spot, options).hasUV());
    EXPECT_FALSE(readMesh(spot).hasUV());
  }
}

}  // namespace
}  // namespace seamvox
