// Synthetic meshes (core/synth/generate): kinds, genus, scan defects, face counts, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/synth/generate.h"
#include "core/mesh/topology.h"
#include "io/mesh_io.h"
#include "testing.h"

namespace seamvox {
namespace {

TriangleMesh generate(MeshKind kind, std::uint64_t faces, std::uint64_t seed = 1) {
  GenerateOptions options;
  options.kind = kind;
  options.faces = faces;
  options.seed = seed;
  return generateMesh(options).mesh;
}

double signedVolume(const TriangleMesh& mesh) {
  double volume = 0.0;
  for (const Triangle& t : mesh.triangles) {
    volume += mesh.position(t[0]).dot(mesh.position(t[1]).cross(mesh.position(t[2]))) / 6.0;
  }
  return volume;
}

bool sameMesh(const TriangleMesh& a, const TriangleMesh& b) {
  return a.positions.size() == b.positions.size() && a.triangles.size() == b.triangles.size() &&
         std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3f)) == 0 &&
         std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * sizeof(Triangle)) == 0;
}

void expectNothingToFix(const CleanReport& r) {
  EXPECT_EQ(r.weldedVertices, 0u);
  EXPECT_EQ(r.degenerateFaces, 0u);
  EXPECT_EQ(r.duplicateFaces, 0u);
  EXPECT_EQ(r.zeroAreaFaces, 0u);
  EXPECT_EQ(r.unreferencedVertices, 0u);
  EXPECT_EQ(r.nonManifoldEdges, 0u);
  EXPECT_EQ(r.nonManifoldVertices, 0u);
  EXPECT_EQ(r.flippedFaces, 0u);
  EXPECT_EQ(r.outputFaces, r.inputFaces);
  EXPECT_EQ(r.outputVertices, r.inputVertices);
}

struct ClosedCase {
  MeshKind kind;
  std::int64_t genus;
};

class ClosedKinds : public ::testing::TestWithParam<std::tuple<ClosedCase, std::uint64_t>> {};

TEST_P(ClosedKinds, CleanClosedManifoldOfTheExpectedGenus) {
  const auto [c, faces] = GetParam();
  TriangleMesh mesh = generate(c.kind, faces, 7);
  EXPECT_NEAR(static_cast<double>(mesh.numFaces()), static_cast<double>(faces), 0.04 * faces)
      << meshKindName(c.kind);
  EXPECT_GT(signedVolume(mesh), 0.0) << "faces must be oriented outward";
  const CleanResult cleaned = cleanMesh(std::move(mesh));
  expectNothingToFix(cleaned.report);
  cleaned.topology.validate();
  const ComponentsResult comps = computeComponents(cleaned.topology);
  ASSERT_EQ(comps.components.size(), 1u);
  EXPECT_EQ(comps.boundaryLoops, 0u);
  EXPECT_EQ(comps.components[0].genus, c.genus);
  EXPECT_EQ(comps.components[0].eulerCharacteristic, 2 - 2 * c.genus);
}

INSTANTIATE_TEST_SUITE_P(
    Generate, ClosedKinds,
    ::testing::Combine(::testing::Values(ClosedCase{MeshKind::Sphere, 0}, ClosedCase{MeshKind::Torus, 1},
                                         ClosedCase{MeshKind::Genus2, 2}),
                       ::testing::Values(std::uint64_t{300}, std::uint64_t{4321}, std::uint64_t{40000})));

TEST(Generate, ScanHasHolesIslandsAndDefectsThatCleaningFinds) {
  for (std::uint64_t faces : {700u, 30000u}) {
    GenerateOptions options;
    options.kind = MeshKind::Scan;
    options.faces = faces;
    const GenerateResult generated = generateMesh(options);
    const ScanDefects& d = generated.defects;
    EXPECT_NEAR(static_cast<double>(generated.mesh.numFaces()), static_cast<double>(faces), 0.04 * faces);
    EXPECT_GE(d.holes, 3u);
    EXPECT_GE(d.openIslands + d.closedIslands, 3u);
    EXPECT_GT(d.seamDuplicates, 0u);
    EXPECT_GT(d.degenerateFaces, 0u);
    EXPECT_GT(d.duplicateFaces, 0u);

    // Without welding the seam stays open: one more boundary loop on the main surface.
    {
      const CleanResult cleaned = cleanMesh(generated.mesh);
      EXPECT_EQ(cleaned.report.degenerateFaces, d.degenerateFaces);
      EXPECT_EQ(cleaned.report.duplicateFaces, d.duplicateFaces);
      EXPECT_EQ(cleaned.report.weldedVertices, 0u);
      EXPECT_EQ(cleaned.report.flippedFaces, 0u);
      EXPECT_EQ(cleaned.report.nonManifoldEdges, 0u);
      const ComponentsResult comps = computeComponents(cleaned.topology);
      EXPECT_EQ(comps.components.size(), 1u + d.openIslands + d.closedIslands);
      EXPECT_EQ(comps.boundaryLoops, d.holes + 1 + d.openIslands);
      EXPECT_EQ(comps.components[0].boundaryLoops, d.holes + 1);
      EXPECT_EQ(comps.components[0].genus, 0);
    }
    // Welding closes the seam.
    {
      CleanOptions weld;
      weld.weldVertices = true;
      const CleanResult cleaned = cleanMesh(generated.mesh, weld);
      EXPECT_EQ(cleaned.report.weldedVertices, d.seamDuplicates);
      const ComponentsResult comps = computeComponents(cleaned.topology);
      EXPECT_EQ(comps.boundaryLoops, d.holes + d.openIslands);
      EXPECT_EQ(comps.components[0].boundaryLoops, d.holes);
      EXPECT_EQ(comps.components[0].genus, 0);
      for (std::size_t k = 1; k < comps.components.size(); ++k) {
        EXPECT_EQ(comps.components[k].genus, 0);
        EXPECT_LE(comps.components[k].boundaryLoops, 1u);
      }
    }
  }
}

TriangleMesh noisy(TriangleMesh mesh, double amplitude, std::uint64_t seed, std::uint32_t spikes = 0,
                   std::uint32_t folds = 0, ScanNoiseResult* result = nullptr) {
  ScanNoiseOptions options;
  options.amplitude = amplitude;
  options.seed = seed;
  options.spikes = spikes;
  options.folds = folds;
  const ScanNoiseResult r = addScanNoise(mesh, options);
  if (result) *result = r;
  return mesh;
}

std::vector<double> moves(const TriangleMesh& before, const TriangleMesh& after) {
  std::vector<double> out(before.numVertices());
  for (VertexId v = 0; v < before.numVertices(); ++v) out[v] = (after.position(v) - before.position(v)).norm();
  return out;
}

TEST(ScanNoise, SameSeedSameBytesOtherSeedOtherMesh) {
  const TriangleMesh scan = generate(MeshKind::Scan, 5000);
  const TriangleMesh a = noisy(scan, 0.25, 4, 3, 2), b = noisy(scan, 0.25, 4, 3, 2);
  EXPECT_TRUE(sameMesh(a, b));
  EXPECT_FALSE(sameMesh(a, noisy(scan, 0.25, 5, 3, 2)));
  EXPECT_FALSE(sameMesh(a, scan));
  EXPECT_TRUE(sameMesh(noisy(scan, 0.0, 4), scan));
}

TEST(ScanNoise, MovesStayWithinTheAmplitudeAlongTheNormalAndAcross) {
  const TriangleMesh sphere = generate(MeshKind::Sphere, 8000);
  for (const double amplitude : {0.1, 0.25, 0.5}) {
    ScanNoiseResult result;
    const TriangleMesh moved = noisy(sphere, amplitude, 2, 0, 0, &result);
    ASSERT_GT(result.meanEdgeLength, 0.0);
    const double bound = amplitude * result.meanEdgeLength * (1.0 + 1e-4) + 1e-6;
    // The same normals as the noise: area-weighted sums of the face normals.
    std::vector<Vec3d> normal(sphere.numVertices(), Vec3d::Zero());
    for (const Triangle& t : sphere.triangles) {
      const Vec3d n = (sphere.position(t[1]) - sphere.position(t[0])).cross(sphere.position(t[2]) - sphere.position(t[0]));
      for (VertexId v : t) normal[v] += n;
    }
    double largestAlong = 0.0, largestAcross = 0.0;
    for (VertexId v = 0; v < sphere.numVertices(); ++v) {
      const Vec3d d = moved.position(v) - sphere.position(v), n = normal[v].normalized();
      const double along = std::abs(d.dot(n)), across = (d - d.dot(n) * n).norm();
      EXPECT_LE(along, bound) << "vertex " << v;
      EXPECT_LE(across, bound) << "vertex " << v;
      largestAlong = std::max(largestAlong, along);
      largestAcross = std::max(largestAcross, across);
    }
    // Uniform noise reaches near its bound somewhere among thousands of vertices.
    EXPECT_GT(largestAlong, 0.9 * amplitude * result.meanEdgeLength);
    EXPECT_GT(largestAcross, 0.9 * amplitude * result.meanEdgeLength);
    EXPECT_LE(result.maxDisplacement, std::sqrt(2.0) * bound);
  }
  EXPECT_THROW(noisy(sphere, -0.1, 1), InputError);
  EXPECT_THROW(noisy(sphere, std::nan(""), 1), InputError);
  EXPECT_THROW(noisy(generate(MeshKind::Sphere, 12), 0.1, 1, 5, 5), InputError);
}

// With localScale every vertex moves the same draw as with the mean edge length L, scaled by its
// own mean edge length over L: on a mesh of two spheres whose triangles differ tenfold in size,
// the small one's vertices move about a tenth as far, where L moves them as far as the large one's.
TEST(ScanNoise, LocalScaleMovesEachVertexInUnitsOfItsOwnEdges) {
  TriangleMesh mesh = generate(MeshKind::Sphere, 4000);
  const TriangleMesh large = mesh;
  const VertexId offset = large.numVertices();
  for (const Vec3f& p : large.positions) mesh.positions.push_back(0.1f * p + Vec3f(5.f, 0.f, 0.f));
  for (const Triangle& t : large.triangles) mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  std::vector<double> edgeSum(mesh.numVertices(), 0.0), edgeCount(mesh.numVertices(), 0.0);
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const double len = (mesh.position(t[(k + 1) % 3]) - mesh.position(t[k])).norm();
      for (const VertexId v : {t[k], t[(k + 1) % 3]}) edgeSum[v] += len, edgeCount[v] += 1.0;
    }
  }
  ScanNoiseOptions options;
  options.amplitude = 0.3;
  options.seed = 2;
  TriangleMesh byMean = mesh, byLocal = mesh;
  const ScanNoiseResult mean = addScanNoise(byMean, options);
  options.localScale = true;
  const ScanNoiseResult local = addScanNoise(byLocal, options);
  EXPECT_EQ(local.meanEdgeLength, mean.meanEdgeLength);
  double largest[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // [small sphere][local scale]
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    const double own = edgeSum[v] / edgeCount[v];
    const Vec3d dMean = byMean.position(v) - mesh.position(v), dLocal = byLocal.position(v) - mesh.position(v);
    const double position = mesh.position(v).norm();
    EXPECT_LE((dLocal - dMean * (own / mean.meanEdgeLength)).norm(), 1e-4 * dLocal.norm() + 4e-7 * position)
        << "vertex " << v;
    EXPECT_LE(dLocal.norm(), std::sqrt(2.0) * 0.3 * own * (1.0 + 1e-4) + 4e-7 * position) << "vertex " << v;
    const int small = v >= offset;
    largest[small][0] = std::max(largest[small][0], dMean.norm());
    largest[small][1] = std::max(largest[small][1], dLocal.norm());
  }
  EXPECT_GT(largest[1][0], 0.7 * largest[0][0]);  // L: the small sphere moves as far
  EXPECT_LT(largest[1][1], 0.15 * largest[0][1]);  // its own edges: about a tenth as far
  EXPECT_GT(largest[1][1], 0.05 * largest[0][1]);
}

// The tangential share scales the move across the normal only: 0 moves along the normals alone
// (a range scanner's depth noise), 0.5 at most half the amplitude across; the normal part is the
// same draw either way.
TEST(ScanNoise, TheTangentialShareScalesOnlyTheMoveAcrossTheNormal) {
  const TriangleMesh sphere = generate(MeshKind::Sphere, 8000);
  std::vector<Vec3d> normal(sphere.numVertices(), Vec3d::Zero());
  for (const Triangle& t : sphere.triangles) {
    const Vec3d n = (sphere.position(t[1]) - sphere.position(t[0])).cross(sphere.position(t[2]) - sphere.position(t[0]));
    for (VertexId v : t) normal[v] += n;
  }
  const auto moved = [&](double tangential, ScanNoiseResult& result) {
    TriangleMesh mesh = sphere;
    ScanNoiseOptions options;
    options.amplitude = 0.4;
    options.seed = 3;
    options.tangential = tangential;
    result = addScanNoise(mesh, options);
    return mesh;
  };
  ScanNoiseResult full, half, none;
  const TriangleMesh a = moved(1.0, full), b = moved(0.5, half), c = moved(0.0, none);
  const double bound = 0.4 * full.meanEdgeLength;
  double acrossHalf = 0.0, acrossNone = 0.0, alongNone = 0.0;
  for (VertexId v = 0; v < sphere.numVertices(); ++v) {
    const Vec3d n = normal[v].normalized();
    const Vec3d da = a.position(v) - sphere.position(v), db = b.position(v) - sphere.position(v),
                dc = c.position(v) - sphere.position(v);
    const auto across = [&](const Vec3d& d) { return (d - d.dot(n) * n).norm(); };
    // Float positions: the same normal part within their rounding.
    EXPECT_NEAR(dc.dot(n), da.dot(n), 1e-6 * (1.0 + sphere.position(v).norm())) << "vertex " << v;
    EXPECT_NEAR(across(db), 0.5 * across(da), 1e-6 * (1.0 + sphere.position(v).norm())) << "vertex " << v;
    acrossHalf = std::max(acrossHalf, across(db));
    acrossNone = std::max(acrossNone, across(dc));
    alongNone = std::max(alongNone, std::abs(dc.dot(n)));
  }
  EXPECT_LT(acrossNone, 1e-5 * bound + 1e-6);
  EXPECT_GT(alongNone, 0.9 * bound);
  EXPECT_LE(acrossHalf, 0.5 * bound * (1.0 + 1e-4) + 1e-6);
  EXPECT_GT(acrossHalf, 0.45 * bound);
  TriangleMesh mesh = sphere;
  ScanNoiseOptions bad;
  bad.amplitude = 0.1;
  for (const double share : {-0.1, 1.5, std::nan("")}) {
    bad.tangential = share;
    EXPECT_THROW(addScanNoise(mesh, bad), InputError) << share;
  }
}

TEST(ScanNoise, KeepsTheTopologyAndTheUnweldedSeam) {
  GenerateOptions options;
  options.kind = MeshKind::Scan;
  options.faces = 20000;
  const GenerateResult generated = generateMesh(options);
  const TriangleMesh moved = noisy(generated.mesh, 0.5, 9, 10, 10);
  ASSERT_EQ(moved.triangles.size(), generated.mesh.triangles.size());
  EXPECT_EQ(std::memcmp(moved.triangles.data(), generated.mesh.triangles.data(),
                        moved.triangles.size() * sizeof(Triangle)), 0);
  for (const bool weld : {false, true}) {
    CleanOptions clean;
    clean.weldVertices = weld;
    const CleanResult a = cleanMesh(generated.mesh, clean), b = cleanMesh(moved, clean);
    EXPECT_EQ(a.report.weldedVertices, b.report.weldedVertices) << "the seam copies move alike";
    EXPECT_EQ(a.mesh.numFaces(), b.mesh.numFaces());
    const ComponentsResult ca = computeComponents(a.topology), cb = computeComponents(b.topology);
    ASSERT_EQ(ca.components.size(), cb.components.size());
    EXPECT_EQ(ca.boundaryLoops, cb.boundaryLoops);
    for (std::size_t k = 0; k < ca.components.size(); ++k) {
      EXPECT_EQ(ca.components[k].eulerCharacteristic, cb.components[k].eulerCharacteristic);
    }
  }
}

TEST(ScanNoise, SpikesAndFoldsMoveTheAskedVertices) {
  const TriangleMesh sphere = generate(MeshKind::Sphere, 20000);
  ScanNoiseResult result;
  const TriangleMesh spiked = noisy(sphere, 0.0, 3, 7, 0, &result);
  EXPECT_EQ(result.spikes, 7u);
  std::size_t far = 0;
  for (double d : moves(sphere, spiked)) far += d >= 1.99 * result.meanEdgeLength;
  EXPECT_EQ(far, 7u);
  const TriangleMesh folded = noisy(sphere, 0.0, 3, 0, 5, &result);
  EXPECT_EQ(result.folds, 5u);
  std::size_t centres = 0, ring = 0;
  for (double d : moves(sphere, folded)) {
    centres += d >= 1.99 * result.meanEdgeLength;
    ring += d > 0.99 * result.meanEdgeLength && d < 1.01 * result.meanEdgeLength;
  }
  EXPECT_EQ(centres, 5u);
  EXPECT_GE(ring, 5u * 3u);  // a ring has 3 or more vertices
  // A fold turns faces over.
  std::size_t flipped = 0;
  for (FaceId f = 0; f < sphere.numFaces(); ++f) flipped += faceNormal(sphere, f).dot(faceNormal(folded, f)) < 0.0;
  EXPECT_GE(flipped, 5u);
}

TEST(Generate, FaceCountFollowsTheTarget) {
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    for (std::uint64_t faces : {1000u, 2500u, 9999u, 47000u}) {
      const TriangleMesh mesh = generate(kind, faces);
      EXPECT_NEAR(static_cast<double>(mesh.numFaces()), static_cast<double>(faces), 0.03 * faces)
          << meshKindName(kind) << " " << faces;
    }
  }
}

TEST(Generate, SameSeedSameBytesOtherSeedOtherMesh) {
  testing::TempDir dir;
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    const TriangleMesh a = generate(kind, 5000, 42), b = generate(kind, 5000, 42);
    EXPECT_TRUE(sameMesh(a, b)) << meshKindName(kind);
    const TriangleMesh c = generate(kind, 5000, 43);
    EXPECT_FALSE(sameMesh(a, c)) << meshKindName(kind);
    const std::string pa = dir.path("a.ply"), pb = dir.path("b.ply");
    writeMesh(pa, a);
    writeMesh(pb, b);
    const std::string bytes = testing::readFile(pa);
    EXPECT_GT(bytes.size(), 5000u * 13);
    EXPECT_EQ(bytes, testing::readFile(pb)) << meshKindName(kind);
  }
}

/// The mesh a MeshGenerator hands out in chunks of `chunk` vertices and triangles.
TriangleMesh drainGenerator(MeshGenerator& generator, std::size_t chunk) {
  TriangleMesh mesh;
  while (generator.nextPositions(chunk, mesh.positions)) {
  }
  while (generator.nextTriangles(chunk, mesh.triangles)) {
  }
  return mesh;
}

TEST(Generate, PieceByPieceGivesTheSameBitsAsTheWholeMesh) {
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    for (std::uint64_t faces : {minimumFaces(kind), std::uint64_t(2500), std::uint64_t(47000)}) {
      for (std::uint64_t seed : {1u, 7u}) {
        GenerateOptions options;
        options.kind = kind;
        options.faces = faces;
        options.seed = seed;
        const GenerateResult whole = generateMesh(options);
        for (std::size_t chunk : {std::size_t(1), std::size_t(777), std::size_t(1) << 20}) {
          if (chunk == 1 && faces > 2500) continue;
          MeshGenerator generator(options);
          EXPECT_EQ(generator.numVertices(), whole.mesh.numVertices());
          EXPECT_EQ(generator.numFaces(), whole.mesh.numFaces());
          const TriangleMesh pieces = drainGenerator(generator, chunk);
          EXPECT_TRUE(sameMesh(pieces, whole.mesh)) << meshKindName(kind) << " " << faces << " seed " << seed
                                                    << " chunk " << chunk;
          const ScanDefects& a = generator.defects();
          const ScanDefects& b = whole.defects;
          EXPECT_EQ(std::tie(a.holes, a.openIslands, a.closedIslands, a.seamDuplicates, a.degenerateFaces,
                             a.duplicateFaces),
                    std::tie(b.holes, b.openIslands, b.closedIslands, b.seamDuplicates, b.degenerateFaces,
                             b.duplicateFaces));
        }
      }
    }
  }
}

TEST(Generate, KindNamesAndLimits) {
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    EXPECT_EQ(parseMeshKind(meshKindName(kind)), kind);
    // The smallest allowed mesh is already a surface of its kind (the scan's main part: a disk
    // with holes, genus 0).
    const TriangleMesh smallest = generate(kind, minimumFaces(kind));
    EXPECT_GE(smallest.numFaces(), minimumFaces(kind) * 9 / 10) << meshKindName(kind);
    const CleanResult cleaned = cleanMesh(smallest);
    const std::int64_t genus = kind == MeshKind::Torus ? 1 : kind == MeshKind::Genus2 ? 2 : 0;
    EXPECT_EQ(computeComponents(cleaned.topology).components.at(0).genus, genus) << meshKindName(kind);
    EXPECT_THROW(generate(kind, minimumFaces(kind) - 1), InputError);
  }
  EXPECT_THROW(parseMeshKind("cube"), InputError);
}

}  // namespace
}  // namespace seamvox
