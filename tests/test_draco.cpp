// Draco archives of parameterized meshes: the UV lattice keeps seamless maps seamless, positions
// and faces survive, the lossless fallback is exact, and `seamvox convert` moves maps between
// every format.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/quality/metrics.h"
#include "io/atomic_file.h"
#include "io/mesh_io.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::runSeamvox;
using testing::TempDir;
using testing::cornerValues;

/// A seamless map of a generated 3000-face sphere, made by the command line (hat solver).
TriangleMesh parameterizedSphere(const TempDir& dir, double cells = 40.0) {
  std::string log;
  EXPECT_EQ(runSeamvox("gen sphere --faces 3000 -o " + dir.path("s.ply"), &log), 0) << log;
  EXPECT_EQ(runSeamvox("param " + dir.path("s.ply") + " -o " + dir.path("s_uv.ply") +
                           " --solver hat --quiet --cells " + std::to_string(cells), &log), 0) << log;
  ReadOptions options;
  options.readUV = true;
  return readMesh(dir.path("s_uv.ply"), options);
}

SeamQuality seamsOf(TriangleMesh mesh) {
  const CleanResult clean = cleanMesh(std::move(mesh));
  return measureSeamsFromUV(clean.mesh, clean.topology, clean.mesh.cornerUV);
}

using FaceKey = std::array<float, 9>;
/// Corner positions of a face, rotated to start at the smallest: the same key after any
/// re-indexing that keeps orientation. Also returns the rotation.
FaceKey faceKey(const TriangleMesh& mesh, FaceId f, int& rotation) {
  std::array<std::array<float, 3>, 3> corners;
  for (int k = 0; k < 3; ++k) {
    const Vec3f& p = mesh.positions[mesh.triangles[f][k]];
    corners[k] = {p[0], p[1], p[2]};
  }
  rotation = static_cast<int>(std::min_element(corners.begin(), corners.end()) - corners.begin());
  FaceKey key;
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) key[3 * k + c] = corners[(rotation + k) % 3][c];
  }
  return key;
}

/// Largest per-component UV change between two meshes with the same faces (matched by position);
/// -1 when some face of b has no counterpart in a.
double maxUVChange(const TriangleMesh& a, const TriangleMesh& b) {
  std::map<FaceKey, std::pair<FaceId, int>> index;
  for (FaceId f = 0; f < a.numFaces(); ++f) {
    int r = 0;
    const FaceKey key = faceKey(a, f, r);
    index[key] = {f, r};
  }
  double worst = 0.0;
  for (FaceId f = 0; f < b.numFaces(); ++f) {
    int r = 0;
    const auto found = index.find(faceKey(b, f, r));
    if (found == index.end()) return -1.0;
    const auto [g, s] = found->second;
    for (int k = 0; k < 3; ++k) {
      const Vec2d d = b.cornerUV[3 * f + (r + k) % 3] - a.cornerUV[3 * g + (s + k) % 3];
      worst = std::max(worst, d.cwiseAbs().maxCoeff());
    }
  }
  return worst;
}

TEST(DracoArchive, DefaultLatticeKeepsFacesPositionsAndSeamlessness) {
  TempDir dir;
  const TriangleMesh mesh = parameterizedSphere(dir);
  ASSERT_TRUE(mesh.hasUV());
  ASSERT_TRUE(seamsOf(mesh).isSeamless(1e-6));
  const WriteOptions options;
  ASSERT_EQ(dracoUVBitsFor(mesh, options), 14);
  writeMesh(dir.path("m.drc"), mesh, options);
  ReadOptions readOptions;
  readOptions.readUV = true;
  const TriangleMesh back = readMesh(dir.path("m.drc"), readOptions);
  ASSERT_EQ(back.numFaces(), mesh.numFaces());
  ASSERT_TRUE(back.hasUV());
  // Every decoded UV is a lattice point of step 2^-14, within half a step of the original
  // (positions are lossless by default, so faces match exactly by position).
  const double step = std::ldexp(1.0, -14);
  for (const Vec2d& uv : cornerValues(back.cornerUV)) {
    for (int c = 0; c < 2; ++c) EXPECT_EQ(uv[c] / step, std::nearbyint(uv[c] / step));
  }
  const double change = maxUVChange(mesh, back);
  ASSERT_GE(change, 0.0) << "a decoded face has no counterpart";
  EXPECT_LE(change, 0.5 * step + 1e-12);
  EXPECT_GT(change, 0.0);  // it did quantize
  const SeamQuality seams = seamsOf(back);
  EXPECT_GT(seams.seamEdges, 0u);
  EXPECT_LE(seams.maxResidual, 1e-4);
  EXPECT_LE(seams.maxIntegerDistance, 1e-4);
  // The lattice is smaller than the lossless float64 archive.
  WriteOptions lossless;
  lossless.dracoUVBits = 0;
  writeMesh(dir.path("lossless.drc"), mesh, lossless);
  EXPECT_LT(std::filesystem::file_size(dir.path("m.drc")), std::filesystem::file_size(dir.path("lossless.drc")));
  EXPECT_EQ(maxUVChange(mesh, readMesh(dir.path("lossless.drc"), readOptions)), 0.0);
}

TEST(DracoArchive, LargeUVsFallBackToLosslessOrACoarserLattice) {
  TempDir dir;
  TriangleMesh mesh = parameterizedSphere(dir);
  // q -> 64 q + (1000 - 3000 i) keeps the map seamless (integer translations stay integers).
  for (std::uint32_t w = 0; w < mesh.cornerUV.numWedges(); ++w) {
    mesh.cornerUV.setWedgeValue(w, 64.0 * mesh.cornerUV.wedgeValue(w) + Vec2d(1000.0, -3000.0));
  }
  ASSERT_TRUE(seamsOf(mesh).isSeamless(1e-6));
  WriteOptions options;
  EXPECT_EQ(dracoUVBitsFor(mesh, options), 0) << "2^14 steps of thousands of cells overflow float32";
  writeMesh(dir.path("big.drc"), mesh, options);
  ReadOptions readOptions;
  readOptions.readUV = true;
  EXPECT_EQ(maxUVChange(mesh, readMesh(dir.path("big.drc"), readOptions)), 0.0);

  options.dracoUVBits = 8;
  ASSERT_EQ(dracoUVBitsFor(mesh, options), 8);
  writeMesh(dir.path("coarse.drc"), mesh, options);
  const TriangleMesh coarse = readMesh(dir.path("coarse.drc"), readOptions);
  EXPECT_LE(maxUVChange(mesh, coarse), 0.5 / 256 + 1e-9);
  const SeamQuality seams = seamsOf(coarse);
  EXPECT_LE(seams.maxResidual, 1e-4) << "rounding commutes with quarter turns and integer shifts";
  EXPECT_LE(seams.maxIntegerDistance, 1e-4);
}

TEST(DracoArchive, AWideUVRangeDecodesWithinHalfAStep) {
  // A range of 2^23 to 2^24 steps of 2^-14 (a spike's chart spans hundreds of cells): Draco's
  // encoder rounds indices >= 2^23 in float32, one step off, unless the writer avoids them.
  TempDir dir;
  TriangleMesh mesh = parameterizedSphere(dir);
  double lo = 1e300, hi = -1e300;
  for (std::uint32_t w = 0; w < mesh.cornerUV.numWedges(); ++w) {
    lo = std::min(lo, mesh.cornerUV.wedgeValue(w).minCoeff());
    hi = std::max(hi, mesh.cornerUV.wedgeValue(w).maxCoeff());
  }
  const double scale = std::ceil(700.0 / (hi - lo));  // an integer: the map stays seamless
  const double shift = -std::floor(scale * lo) - 500.0;
  for (std::uint32_t w = 0; w < mesh.cornerUV.numWedges(); ++w) {
    mesh.cornerUV.setWedgeValue(w, scale * mesh.cornerUV.wedgeValue(w) + Vec2d(shift, shift));
  }
  ASSERT_TRUE(seamsOf(mesh).isSeamless(1e-6));
  writeMesh(dir.path("wide.drc"), mesh);
  ReadOptions readOptions;
  readOptions.readUV = true;
  const TriangleMesh back = readMesh(dir.path("wide.drc"), readOptions);
  const double change = maxUVChange(mesh, back);
  ASSERT_GE(change, 0.0);
  EXPECT_LE(change, 0.5 * std::ldexp(1.0, -14) + 1e-12);
  EXPECT_TRUE(seamsOf(back).isSeamless(1e-6));
}

TEST(DracoArchive, AConsumingWriteGivesTheSameArchiveAndFreesTheMesh) {
  TempDir dir;
  TriangleMesh mesh = parameterizedSphere(dir);
  writeMesh(dir.path("kept.drc"), mesh);
  for (const char* ext : {".drc", ".ply"}) {
    TriangleMesh consumed = mesh;
    AtomicFile file(dir.path(std::string("consumed") + ext));
    writeMesh(file, std::move(consumed));
    file.commit();
    EXPECT_EQ(consumed.numFaces(), 0u) << ext;
    EXPECT_EQ(consumed.numVertices(), 0u) << ext;
    EXPECT_FALSE(consumed.hasUV()) << ext;
  }
  EXPECT_EQ(testing::readFile(dir.path("consumed.drc")), testing::readFile(dir.path("kept.drc")));
  ReadOptions readOptions;
  readOptions.readUV = true;
  EXPECT_EQ(maxUVChange(readMesh(dir.path("consumed.ply"), readOptions), mesh), 0.0);
}

TEST(DracoArchive, QuantizedPositionsStayWithinTheirStep) {
  TempDir dir;
  const TriangleMesh mesh = parameterizedSphere(dir);
  WriteOptions options;
  options.dracoPositionBits = 16;
  writeMesh(dir.path("q.drc"), mesh, options);
  const TriangleMesh back = readMesh(dir.path("q.drc"));
  ASSERT_EQ(back.numFaces(), mesh.numFaces());
  const BoundingBox a = computeBoundingBox(mesh.positions), b = computeBoundingBox(back.positions);
  const double step = a.extent().maxCoeff() / 65535.0;
  EXPECT_LE((a.min - b.min).cwiseAbs().maxCoeff(), step);
  EXPECT_LE((a.max - b.max).cwiseAbs().maxCoeff(), step);
  EXPECT_GT((a.min - b.min).cwiseAbs().maxCoeff() + (a.max - b.max).cwiseAbs().maxCoeff(), 0.0);
  options.dracoPositionBits = 31;
  EXPECT_THROW(writeMesh(dir.path("bad.drc"), mesh, options), Error);
}

TEST(ConvertCommand, MovesAMapThroughEveryFormat) {
  TempDir dir;
  const TriangleMesh mesh = parameterizedSphere(dir);
  std::string log;
  // ply -> drc -> obj -> ply keeps the (lattice) map; off drops UVs with a warning.
  ASSERT_EQ(runSeamvox("convert " + dir.path("s_uv.ply") + " " + dir.path("a.drc") + " --ratio", &log), 0) << log;
  EXPECT_NE(log.find("compression ratio"), std::string::npos) << log;
  EXPECT_NE(log.find("step 2^-14"), std::string::npos) << log;
  ASSERT_EQ(runSeamvox("convert " + dir.path("a.drc") + " " + dir.path("b.obj"), &log), 0) << log;
  ASSERT_EQ(runSeamvox("convert " + dir.path("b.obj") + " " + dir.path("c.ply") + " --ascii", &log), 0) << log;
  ReadOptions readOptions;
  readOptions.readUV = true;
  const TriangleMesh back = readMesh(dir.path("c.ply"), readOptions);
  EXPECT_EQ(back.numFaces(), mesh.numFaces());
  EXPECT_LE(maxUVChange(mesh, back), 0.5 * std::ldexp(1.0, -14) + 1e-12);
  EXPECT_EQ(runSeamvox("check " + dir.path("c.ply") + " --tolerance 1e-4", &log), 0) << log;
  ASSERT_EQ(runSeamvox("convert " + dir.path("c.ply") + " " + dir.path("d.off"), &log), 0) << log;
  EXPECT_NE(log.find("UVs dropped"), std::string::npos) << log;
  EXPECT_EQ(readMesh(dir.path("d.off")).numFaces(), mesh.numFaces());
  EXPECT_NE(runSeamvox("convert " + dir.path("c.ply") + " " + dir.path("e.xyz"), &log), 0);
  EXPECT_NE(runSeamvox("convert " + dir.path("missing.ply") + " " + dir.path("f.drc"), &log), 0);
  EXPECT_NE(log.find("missing.ply"), std::string::npos) << log;
}

}  // namespace
}  // namespace seamvox
