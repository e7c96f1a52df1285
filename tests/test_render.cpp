// Checkerboard renderer and PNG output: colours at known (u, v), seams, cones, framing, files.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>

#include "core/system/errors.h"
#include "core/synth/render.h"
#include "core/mesh/topology.h"
#include "io/mesh_io.h"
#include "io/png_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::gridMesh;
using testing::TempDir;

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// A small independent PNG reader (chunk walk, bitwise CRC-32, zlib uncompress, unfiltering).

std::uint32_t crc32Bitwise(const unsigned char* data, std::size_t size) {
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::uint32_t bigEndian(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}

/// Decodes an 8-bit RGB PNG; throws std::runtime_error saying what is malformed.
RgbImage decodePng(const std::string& file) {
  auto fail = [](const std::string& what) { throw std::runtime_error("PNG: " + what); };
  const auto* bytes = reinterpret_cast<const unsigned char*>(file.data());
  if (file.size() < 8 || file.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
    fail("bad signature");
  }
  RgbImage image;
  std::string compressed;
  bool sawHeader = false, sawEnd = false;
  std::size_t at = 8;
  while (at < file.size()) {
    if (sawEnd) fail("bytes after IEND");
    if (at + 12 > file.size()) fail("truncated chunk");
    const std::uint32_t length = bigEndian(bytes + at);
    if (at + 12 + std::size_t(length) > file.size()) fail("chunk longer than the file");
    const std::string type = file.substr(at + 4, 4);
    const unsigned char* data = bytes + at + 8;
    if (crc32Bitwise(bytes + at + 4, length + 4) != bigEndian(data + length)) fail(type + " CRC");
    if (!sawHeader && type != "IHDR") fail("first chunk is " + type);
    if (type == "IHDR") {
      if (length != 13) fail("IHDR length");
      image.width = bigEndian(data);
      image.height = bigEndian(data + 4);
      if (data[8] != 8 || data[9] != 2 || data[10] != 0 || data[11] != 0 || data[12] != 0) {
        fail("not 8-bit RGB, deflate, adaptive filter, no interlace");
      }
      sawHeader = true;
    } else if (type == "IDAT") {
      compressed.append(reinterpret_cast<const char*>(data), length);
    } else if (type == "IEND") {
      if (length != 0) fail("IEND with data");
      sawEnd = true;
    }
    at += 12 + std::size_t(length);
  }
  if (!sawEnd) fail("no IEND");
  const std::size_t rowBytes = 3 * std::size_t(image.width);
  std::vector<unsigned char> raw(image.height * (rowBytes + 1) + 1);
  uLongf rawSize = static_cast<uLongf>(raw.size());
  if (uncompress(raw.data(), &rawSize, reinterpret_cast<const Bytef*>(compressed.data()),
                 static_cast<uLong>(compressed.size())) != Z_OK) {
    fail("zlib stream does not decode");
  }
  if (rawSize != image.height * (rowBytes + 1)) fail("wrong amount of image data");
  image.pixels.resize(rowBytes * image.height);
  for (std::size_t y = 0; y < image.height; ++y) {
    const unsigned char type = raw[y * (rowBytes + 1)];
    const unsigned char* in = &raw[y * (rowBytes + 1) + 1];
    std::uint8_t* row = &image.pixels[y * rowBytes];
    for (std::size_t i = 0; i < rowBytes; ++i) {
      const int a = i >= 3 ? row[i - 3] : 0, b = y ? row[i - rowBytes] : 0;
      const int c = (i >= 3 && y) ? row[i - rowBytes - 3] : 0;
      int predictor = 0;
      if (type == 1) predictor = a;
      else if (type == 2) predictor = b;
      else if (type == 3) predictor = (a + b) / 2;
      else if (type == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        predictor = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
      } else if (type != 0) {
        fail("filter type " + std::to_string(type));
      }
      row[i] = static_cast<std::uint8_t>(in[i] + predictor);
    }
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// Helpers.

/// Per-corner (u, v) = (x, y) * scale of the corner's position.
void setPlanarUV(TriangleMesh& mesh, double scale = 1.0) {
  std::vector<Vec2d> values;
  for (const Triangle& t : mesh.triangles) {
    for (const VertexId v : t) values.emplace_back(scale * mesh.positions[v].x(), scale * mesh.positions[v].y());
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
}

Topology topologyOf(const TriangleMesh& mesh) { return Topology::build(mesh.triangles, mesh.numVertices()); }

/// Straight down the z axis: image right = +x, image up = +y.
RenderOptions topView(std::uint32_t width, std::uint32_t height) {
  RenderOptions options;
  options.width = width;
  options.height = height;
  options.upAxis = 2;
  options.azimuth = 0.0;
  options.elevation = 90.0;
  options.supersample = 1;
  return options;
}

Rgb pixelAt(const RenderResult& r, const Vec3d& p) {
  const Vec2d q = r.camera.project(p);
  const auto x = static_cast<std::uint32_t>(std::floor(q.x())), y = static_cast<std::uint32_t>(std::floor(q.y()));
  EXPECT_LT(x, r.image.width);
  EXPECT_LT(y, r.image.height);
  if (x >= r.image.width || y >= r.image.height) return {0, 0, 0};
  const std::uint8_t* c = r.image.pixel(x, y);
  return {c[0], c[1], c[2]};
}

bool isSeamColored(const Rgb& c) { return c[0] < 40 && c[1] > 200 && c[2] < 40; }

/// Closed fan of n triangles around vertex 0 (flat), each with a (u, v) corner angle of 90
/// degrees at the centre: angle sum n pi / 2, so a cone of 4 - n quarter turns when n != 4.
TriangleMesh quarterFan(int n) {
  TriangleMesh mesh;
  mesh.positions.emplace_back(0.f, 0.f, 0.f);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    mesh.positions.emplace_back(float(std::cos(a)), float(std::sin(a)), 0.f);
  }
  std::vector<Vec2d> values;
  for (int k = 0; k < n; ++k) {
    mesh.triangles.push_back({0, VertexId(1 + k), VertexId(1 + (k + 1) % n)});
    values.insert(values.end(), {Vec2d(0, 0), Vec2d(1, 0), Vec2d(0, 1)});
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
  return mesh;
}

/// concatMeshes, carrying the per-corner (u, v) along.
TriangleMesh concatWithUV(const std::vector<TriangleMesh>& parts) {
  TriangleMesh out = testing::concatMeshes(parts);
  std::vector<Vec2d> values;
  for (const TriangleMesh& p : parts) {
    const std::vector<Vec2d> part = testing::cornerValues(p.cornerUV);
    values.insert(values.end(), part.begin(), part.end());
  }
  out.cornerUV = WedgeMap::fromCorners(out.triangles, values);
  return out;
}

/// Torus with the periodic map u = 8 i / n, v = 4 j / m: two translation seams, no cones.
TriangleMesh torusWithUV(int n, int m) {
  TriangleMesh mesh = testing::torusMesh(n, m);
  std::vector<Vec2d> values;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < m; ++j) {
      auto uv = [&](int ii, int jj) { return Vec2d(8.0 * ii / n, 4.0 * jj / m); };
      values.insert(values.end(), {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
      values.insert(values.end(), {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
    }
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
  return mesh;
}

// ---------------------------------------------------------------------------------------------

TEST(Render, ImageHasTheRequestedSizeAndFramesTheWholeMesh) {
  const TriangleMesh mesh = torusWithUV(24, 12);
  const Topology topology = topologyOf(mesh);
  for (const auto& [w, h, az, el] : {std::make_tuple(64u, 48u, 30.0, 20.0),
                                      std::make_tuple(33u, 97u, -120.0, 60.0),
                                      std::make_tuple(200u, 10u, 0.0, -90.0)}) {
    RenderOptions options;
    options.width = w, options.height = h, options.azimuth = az, options.elevation = el;
    const RenderResult r = renderCheckerboard(mesh, topology, options);
    EXPECT_EQ(r.image.width, w);
    EXPECT_EQ(r.image.height, h);
    EXPECT_EQ(r.image.pixels.size(), 3u * w * h);
    EXPECT_GT(r.coveredPixels, 0u);
    // Every vertex lands inside the picture, and the mesh touches the margin on some side.
    double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
    for (VertexId v = 0; v < mesh.numVertices(); ++v) {
      const Vec2d q = r.camera.project(mesh.position(v));
      EXPECT_TRUE(q.x() >= 0 && q.x() <= w && q.y() >= 0 && q.y() <= h) << "vertex " << v;
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
    }
    const double fill = std::max((hi[0] - lo[0]) / w, (hi[1] - lo[1]) / h);
    EXPECT_NEAR(fill, 1.0 - 2.0 * options.margin, 1e-6);
  }
}

TEST(Render, PlanarMapSeenFromAboveShowsTheExpectedCheckerCells) {
  TriangleMesh mesh = gridMesh(6, 4);
  setPlanarUV(mesh);  // u = x, v = y
  const Topology topology = topologyOf(mesh);
  for (const double checker : {1.0, 2.0}) {
    RenderOptions options = topView(180, 130);
    options.checker = checker;
    options.light = {200, 200, 200};
    options.dark = {200, 0, 0};  // dark cells have no green
    const RenderResult r = renderCheckerboard(mesh, topology, options);
    // Image axes: +x to the right, +y up.
    EXPECT_GT(r.camera.project(Vec3d(1, 0, 0)).x(), r.camera.project(Vec3d(0, 0, 0)).x());
    EXPECT_LT(r.camera.project(Vec3d(0, 1, 0)).y(), r.camera.project(Vec3d(0, 0, 0)).y());
    const double cell = 1.0 / checker;
    int darkCells = 0, lightCells = 0;
    for (int i = 0; i < int(6 * checker); ++i) {
      for (int j = 0; j < int(4 * checker); ++j) {
        // Cell centre and a point a quarter cell off it: both well inside the cell.
        for (const Vec2d offset : {Vec2d(0.5, 0.5), Vec2d(0.3, 0.7)}) {
          const Vec3d p((i + offset.x()) * cell, (j + offset.y()) * cell, 0.0);
          const Rgb c = pixelAt(r, p);
          const bool expectDark = ((i + j) & 1) != 0;
          EXPECT_EQ(c[1] == 0 && c[0] > 0, expectDark) << "checker " << checker << " cell " << i << "," << j;
          EXPECT_EQ(c[1] > 0 && c[1] == c[0] && c[2] == c[0], !expectDark);
          (expectDark ? darkCells : lightCells)++;
        }
      }
    }
    EXPECT_GT(darkCells, 0);
    EXPECT_GT(lightCells, 0);
    // No cracks: every pixel whose centre lies on the grid shows the mesh.
    const Vec2d lo = r.camera.project(Vec3d(0, 4, 0)), hi = r.camera.project(Vec3d(6, 0, 0));
    for (std::uint32_t y = 0; y < r.image.height; ++y) {
      for (std::uint32_t x = 0; x < r.image.width; ++x) {
        if (x + 0.5 <= lo.x() || x + 0.5 >= hi.x() || y + 0.5 <= lo.y() || y + 0.5 >= hi.y()) continue;
        const std::uint8_t* c = r.image.pixel(x, y);
        ASSERT_NE((Rgb{c[0], c[1], c[2]}), options.background) << "crack at " << x << "," << y;
      }
    }
    // Outside the mesh: background.
    const Rgb corner = {r.image.pixel(0, 0)[0], r.image.pixel(0, 0)[1], r.image.pixel(0, 0)[2]};
    EXPECT_EQ(corner, options.background);
  }
}

TEST(Render, NearerSurfaceHidesFartherOne) {
  // Two stacked planes seen from above: the upper one (one dark cell) hides the lower one,
  // whichever comes first in the face order.
  TriangleMesh lower = gridMesh(2, 2), upper = gridMesh(2, 2);
  for (Vec3f& p : upper.positions) p.z() = 1.0f;
  setPlanarUV(lower);
  upper.cornerUV = WedgeMap::fromCorners(upper.triangles, std::vector<Vec2d>(3 * upper.numFaces(), Vec2d(0.5, 1.5)));
  for (const TriangleMesh& mesh : {concatWithUV({lower, upper}), concatWithUV({upper, lower})}) {
    RenderOptions options = topView(60, 60);
    options.dark = {200, 0, 0};
    options.light = {200, 200, 200};
    const RenderResult r = renderCheckerboard(mesh, topologyOf(mesh), options);
    for (const Vec3d p : {Vec3d(0.5, 0.5, 0), Vec3d(1.5, 1.5, 0), Vec3d(0.5, 1.5, 0)}) {
      EXPECT_EQ(pixelAt(r, p)[1], 0) << "lower plane shows through at " << p.transpose();
    }
  }
}

/// 4 x 4 grid whose right half (x > 2) is shifted by half a unit in u: a seam along x = 2.
TriangleMesh gridWithSeam() {
  TriangleMesh mesh = gridMesh(4, 4);
  setPlanarUV(mesh);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    double cx = 0;
    for (const VertexId v : mesh.triangles[f]) cx += mesh.positions[v].x() / 3.0;
    if (cx > 2.0) {
      for (int k = 0; k < 3; ++k) mesh.cornerUV.set(3 * f + k, mesh.cornerUV[3 * f + k] + Vec2d(0.5, 0.0));
    }
  }
  return mesh;
}

TEST(Render, SeamEdgesAreExactlyTheUVDiscontinuities) {
  const TriangleMesh mesh = gridWithSeam();
  const Topology topology = topologyOf(mesh);
  const std::vector<CornerId> seams = findSeamEdges(mesh, topology);
  ASSERT_EQ(seams.size(), 4u);
  for (const CornerId c : seams) {
    EXPECT_FALSE(topology.isBoundaryEdge(c));
    EXPECT_EQ(mesh.positions[topology.vertex(nextCorner(c))].x(), 2.0f);
    EXPECT_EQ(mesh.positions[topology.vertex(prevCorner(c))].x(), 2.0f);
  }
  TriangleMesh seamless = gridMesh(4, 4);
  setPlanarUV(seamless);
  EXPECT_TRUE(findSeamEdges(seamless, topologyOf(seamless)).empty());

  // A torus with a periodic map: seams along the two wrap-around loops, nothing else.
  const TriangleMesh torus = torusWithUV(20, 10);
  EXPECT_EQ(findSeamEdges(torus, topologyOf(torus)).size(), 20u + 10u);
}

TEST(Render, SeamLinesAppearOnTheSeamAndNowhereElse) {
  const TriangleMesh mesh = gridWithSeam();
  const Topology topology = topologyOf(mesh);
  RenderOptions options = topView(200, 200);
  options.drawSeams = true;
  options.seamColor = {0, 255, 0};
  options.seamWidth = 2.0;
  const RenderResult r = renderCheckerboard(mesh, topology, options);
  EXPECT_EQ(r.seamEdges, 4u);
  for (double y = 0.25; y < 4.0; y += 0.5) {
    EXPECT_TRUE(isSeamColored(pixelAt(r, Vec3d(2.0, y, 0)))) << "no seam at y " << y;
    EXPECT_FALSE(isSeamColored(pixelAt(r, Vec3d(1.0, y, 0)))) << "seam on a seamless edge";
    EXPECT_FALSE(isSeamColored(pixelAt(r, Vec3d(3.0, y, 0)))) << "seam on a seamless edge";
  }
  // Every seam-coloured pixel is within the line's half width (plus a pixel) of x = 2.
  const double seamX = r.camera.project(Vec3d(2, 0, 0)).x();
  std::uint64_t seamPixels = 0;
  for (std::uint32_t y = 0; y < r.image.height; ++y) {
    for (std::uint32_t x = 0; x < r.image.width; ++x) {
      const std::uint8_t* c = r.image.pixel(x, y);
      if (!isSeamColored({c[0], c[1], c[2]})) continue;
      ++seamPixels;
      EXPECT_LE(std::fabs(x + 0.5 - seamX), 0.5 * options.seamWidth + 1.0) << x << "," << y;
    }
  }
  EXPECT_GT(seamPixels, 0u);
  // Without --seams: no seam colour at all.
  options.drawSeams = false;
  const RenderResult plain = renderCheckerboard(mesh, topology, options);
  EXPECT_FALSE(isSeamColored(pixelAt(plain, Vec3d(2.0, 1.25, 0))));
}

TEST(Render, HiddenSeamsAreNotDrawn) {
  // The seamed grid at z = 0 under a seamless plane at z = 1, seen from above.
  TriangleMesh lower = gridWithSeam();
  TriangleMesh upper = gridMesh(4, 4);
  for (Vec3f& p : upper.positions) p.z() = 1.0f;
  setPlanarUV(upper);
  const TriangleMesh mesh = concatWithUV({lower, upper});
  RenderOptions options = topView(120, 120);
  options.drawSeams = true;
  options.seamColor = {0, 255, 0};
  const RenderResult r = renderCheckerboard(mesh, topologyOf(mesh), options);
  EXPECT_EQ(r.seamEdges, 4u);
  for (double y = 0.25; y < 4.0; y += 0.5) EXPECT_FALSE(isSeamColored(pixelAt(r, Vec3d(2.0, y, 0))));
}

TEST(Render, LinesAppearWhereDrawnAndHideUnderNearerSurfaces) {
  // A seamless grid at z = 0 seen from above, a line across it at y = 1.5 (drawn) and one under
  // it at z = -1 (hidden, deeper than the line tolerance).
  TriangleMesh mesh = gridMesh(4, 4);
  setPlanarUV(mesh);
  RenderOptions options = topView(200, 200);
  options.lineColor = {0, 255, 0};
  options.lineWidth = 2.0;
  options.lines.push_back({Vec3d(0.0, 1.5, 0.0), Vec3d(4.0, 1.5, 0.0)});
  options.lines.push_back({Vec3d(0.0, 2.5, -1.0), Vec3d(4.0, 2.5, -1.0)});
  const RenderResult r = renderCheckerboard(mesh, topologyOf(mesh), options);
  for (double x = 0.25; x < 4.0; x += 0.5) {
    EXPECT_TRUE(isSeamColored(pixelAt(r, Vec3d(x, 1.5, 0)))) << "no line at x " << x;
    EXPECT_FALSE(isSeamColored(pixelAt(r, Vec3d(x, 2.5, 0)))) << "hidden line drawn at x " << x;
    EXPECT_FALSE(isSeamColored(pixelAt(r, Vec3d(x, 0.75, 0)))) << "line colour away from lines";
  }
}

TEST(Render, ConesAreSingularAngleSumsColouredBySign) {
  for (const int n : {3, 4, 5, 6}) {
    const TriangleMesh mesh = quarterFan(n);
    const Topology topology = topologyOf(mesh);
    const std::vector<RenderCone> cones = findMapCones(mesh, topology).cones;
    if (n == 4) {
      EXPECT_TRUE(cones.empty());
    } else {
      ASSERT_EQ(cones.size(), 1u) << n;  // ring vertices are on the boundary
      EXPECT_EQ(cones[0].vertex, 0u);
      EXPECT_EQ(cones[0].quarterTurns, 4 - n);
    }
    RenderOptions options = topView(100, 100);
    options.drawCones = true;
    options.coneRadius = 4.0;
    const RenderResult r = renderCheckerboard(mesh, topology, options);
    const Rgb centre = pixelAt(r, Vec3d(0, 0, 0));
    const Rgb expected = n < 4 ? options.positiveCone : options.negativeCone;
    EXPECT_EQ(centre == expected, n != 4) << n;
  }
  // Flat planar map and periodic torus map: no cones.
  TriangleMesh grid = gridMesh(5, 5);
  setPlanarUV(grid, 0.37);
  const MapCones flat = findMapCones(grid, topologyOf(grid));
  EXPECT_TRUE(flat.cones.empty());
  EXPECT_EQ(flat.irregularVertices, 0u);
  const TriangleMesh torus = torusWithUV(20, 10);
  const MapCones periodic = findMapCones(torus, topologyOf(torus));
  EXPECT_TRUE(periodic.cones.empty());
  EXPECT_EQ(periodic.irregularVertices, 0u);
  // A fan whose centre angles sum to 2 pi - 0.3: not seamless, so no cone but irregular.
  TriangleMesh bent = quarterFan(4);
  const double a = 0.5 * kPi - 0.3;
  bent.cornerUV.set(3 * 3 + 2, Vec2d(std::cos(a), std::sin(a)));
  const MapCones odd = findMapCones(bent, topologyOf(bent));
  EXPECT_TRUE(odd.cones.empty());
  EXPECT_EQ(odd.irregularVertices, 1u);
}

TEST(Render, MeshWithoutUVIsAClearError) {
  const TriangleMesh mesh = gridMesh(2, 2);
  try {
    renderCheckerboard(mesh, topologyOf(mesh));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no texture coordinates"), std::string::npos) << e.what();
  }
  TempDir dir;
  const std::string path = dir.path("plain.off");
  writeMesh(path, mesh);
  std::string output;
  EXPECT_EQ(testing::runSeamvox("render " + path + " -o " + dir.path("out.png"), &output), 1) << output;
  EXPECT_NE(output.find(path + ": has no texture coordinates; run seamvox param first"),
            std::string::npos)
      << output;
  EXPECT_FALSE(std::ifstream(dir.path("out.png")).good());
}

TEST(Render, BadOptionsAreRejected) {
  TriangleMesh mesh = gridMesh(2, 2);
  setPlanarUV(mesh);
  const Topology topology = topologyOf(mesh);
  RenderOptions zero;
  zero.width = 0;
  EXPECT_THROW(renderCheckerboard(mesh, topology, zero), InputError);
  RenderOptions checker;
  checker.checker = -1.0;
  EXPECT_THROW(renderCheckerboard(mesh, topology, checker), InputError);
  RenderOptions huge;
  huge.width = 9000;
  EXPECT_THROW(renderCheckerboard(mesh, topology, huge), InputError);
  TriangleMesh shortUV = mesh;
  shortUV.cornerUV.resizeCorners(shortUV.cornerUV.size() - 1);
  EXPECT_THROW(renderCheckerboard(shortUV, topology), InputError);
}

TEST(Png, EncodedImagesDecodeBackExactly) {
  // A noisy image exercises every filter; a render has flat areas and edges.
  RgbImage noise;
  noise.width = 37, noise.height = 23;
  std::mt19937 random(7);
  for (std::size_t i = 0; i < 3u * noise.width * noise.height; ++i) {
    noise.pixels.push_back(static_cast<std::uint8_t>(i % 3 == 0 ? random() : (i / 3) % 251));
  }
  TriangleMesh mesh = gridWithSeam();
  RenderOptions options;
  options.width = 91, options.height = 57, options.drawSeams = true;
  const RgbImage render = renderCheckerboard(mesh, topologyOf(mesh), options).image;
  for (const RgbImage& image : {noise, render}) {
    const RgbImage decoded = decodePng(encodePng(image));
    EXPECT_EQ(decoded.width, image.width);
    EXPECT_EQ(decoded.height, image.height);
    EXPECT_EQ(decoded.pixels, image.pixels);
  }
  // A large flat image spans several IDAT chunks and stays small.
  RgbImage flat;
  flat.width = 1500, flat.height = 1500;
  flat.pixels.assign(3u * flat.width * flat.height, 77);
  for (std::size_t i = 0; i < flat.pixels.size(); i += 3 * 4099) flat.pixels[i] = std::uint8_t(i);
  const std::string bytes = encodePng(flat);
  EXPECT_LT(bytes.size(), flat.pixels.size() / 20);
  EXPECT_EQ(decodePng(bytes).pixels, flat.pixels);
  // A corrupted byte is caught by the CRC (checks the reader can fail).
  std::string corrupt = encodePng(noise);
  corrupt[40] ^= 0x10;
  EXPECT_THROW(decodePng(corrupt), std::runtime_error);
  EXPECT_THROW(encodePng(RgbImage{}), InputError);
}

TEST(Png, RenderCommandWritesAValidPicture) {
  TempDir dir;
  const std::string meshPath = dir.path("torus.obj"), png = dir.path("torus.png");
  writeMesh(meshPath, torusWithUV(32, 16));
  std::string output;
  ASSERT_EQ(testing::runSeamvox("render " + meshPath + " -o " + png +
                                    " --size 80x60 --view 20,35 --up z --checker 2 --seams --cones",
                                &output),
            0)
      << output;
  EXPECT_NE(output.find("48 seam edges"), std::string::npos) << output;
  EXPECT_NE(output.find("0 cones"), std::string::npos) << output;
  const RgbImage image = decodePng(testing::readFile(png));
  EXPECT_EQ(image.width, 80u);
  EXPECT_EQ(image.height, 60u);
  const RenderOptions defaults;
  const std::uint8_t* corner = image.pixel(0, 0);
  EXPECT_EQ((Rgb{corner[0], corner[1], corner[2]}), defaults.background);
  std::uint64_t covered = 0;
  for (std::uint32_t y = 0; y < image.height; ++y) {
    for (std::uint32_t x = 0; x < image.width; ++x) {
      const std::uint8_t* c = image.pixel(x, y);
      covered += Rgb{c[0], c[1], c[2]} != defaults.background;
    }
  }
  EXPECT_GT(covered, image.width * image.height / 5);  // the torus is there
  // Usage errors: exit code 2 and no output.
  for (const char* bad : {" --size 0x10", " --size 12", " --size 9000x10", " --view 10", " --checker 0", " --up w"}) {
    EXPECT_EQ(testing::runSeamvox("render " + meshPath + " -o " + dir.path("bad.png") + bad, &output), 2)
        << bad << "\n" << output;
  }
  EXPECT_FALSE(std::ifstream(dir.path("bad.png")).good());
}

TEST(Png, ParamRendersItsResult) {
  TempDir dir;
  const std::string meshPath = dir.path("sphere.obj"), png = dir.path("sphere.png");
  writeMesh(meshPath, testing::icosphereMesh(3));
  std::string output;
  ASSERT_EQ(testing::runSeamvox("param " + meshPath + " -o " + dir.path("uv.ply") + " --solver hat --cells 20 --render " +
                                    png + " --quiet",
                                &output),
            0)
      << output;
  const RgbImage image = decodePng(testing::readFile(png));
  EXPECT_EQ(image.width, 1024u);
  EXPECT_EQ(image.height, 1024u);
  const RenderOptions defaults;
  std::uint64_t seamPixels = 0, checkerPixels = 0;
  for (std::uint32_t y = 0; y < image.height; ++y) {
    for (std::uint32_t x = 0; x < image.width; ++x) {
      const std::uint8_t* c = image.pixel(x, y);
      const Rgb rgb{c[0], c[1], c[2]};
      seamPixels += rgb == defaults.seamColor;
      checkerPixels += rgb != defaults.background && rgb != defaults.seamColor;
    }
  }
  EXPECT_GT(checkerPixels, image.width * image.height / 5);  // the sphere is there
  EXPECT_GT(seamPixels, 0u);                                  // a sphere map has seams to draw
}

TEST(Png, RenderCommandWeldsFilesSplitAlongSeams) {
  // The seamed grid with its right half on vertices of its own: the seam is an open boundary
  // until --weld joins the two halves.
  TriangleMesh mesh = gridWithSeam();
  const VertexId base = mesh.numVertices();
  mesh.positions.insert(mesh.positions.end(), mesh.positions.begin(), mesh.positions.begin() + base);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (mesh.cornerUV[3 * f].x() != mesh.positions[mesh.triangles[f][0]].x()) {
      for (VertexId& v : mesh.triangles[f]) v += base;  // a right-half face
    }
  }
  TempDir dir;
  const std::string path = dir.path("split.obj");
  writeMesh(path, mesh);
  std::string output;
  ASSERT_EQ(testing::runSeamvox("render " + path + " -o " + dir.path("a.png") + " --seams", &output), 0)
      << output;
  EXPECT_NE(output.find(" 0 seam edges"), std::string::npos) << output;
  ASSERT_EQ(testing::runSeamvox("render " + path + " -o " + dir.path("b.png") + " --seams --weld", &output),
            0)
      << output;
  EXPECT_NE(output.find(" 4 seam edges"), std::string::npos) << output;
}

}  // namespace
}  // namespace seamvox
