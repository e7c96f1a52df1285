// Proxy cross field: Poincare-Hopf, the cut of a proxy field is a disk, constant on a plane, two
// sheets in one cell stay apart, deterministic across thread counts, cones and smoothness close
// to the direct field on the shared meshes; method selection.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/cut/cut.h"
#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"
#include "core/field/detail_proxy.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/synth/generate.h"
#include "core/mesh/subdivide.h"
#include "core/mesh/topology.h"
#include "core/mesh/clean.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::loadShared;
using testing::makeSurface;
using testing::Surface;

ProxyFieldResult proxyField(const Surface& s, std::int32_t grid = 32, std::int32_t sweeps = 4) {
  ProxyFieldOptions options;
  options.gridResolution = grid;
  options.smoothingSweeps = sweeps;
  return computeProxyField(s.mesh, s.topology, options);
}

/// Euler characteristic of the cut surface of each component, counted independently of
/// cutToDisk: a vertex with k > 0 cut edges around it splits into k copies (k + 1 on the
/// boundary, where boundary edges are not counted in k), a cut interior edge into two. Also
/// checks that the faces of each component stay connected through uncut edges. Then
/// chi == 1 per component means a disk (connected, orientable, with boundary).
void expectCutIsDisk(const Surface& s, const CutResult& cut, const std::string& what) {
  const Topology& t = s.topology;
  const ComponentsResult comps = computeComponents(t);
  std::vector<std::int64_t> chi(comps.components.size(), 0);
  detail::UnionFind pieces(t.numFaces());
  for (CornerId c = 0; c < t.numCorners(); ++c) {
    const std::uint32_t k = comps.faceComponent[cornerFace(c)];
    if (c % 3 == 0) chi[k] += 1;
    const CornerId o = t.opposite(c);
    if (o == kInvalidId || cut.corners.isCut(c)) {
      chi[k] -= 1;  // each side of a cut edge, and a boundary edge, once
    } else if (c < o) {
      chi[k] -= 1;
      pieces.unite(cornerFace(c), cornerFace(o));
    }
  }
  for (VertexId v = 0; v < t.numVertices(); ++v) {
    if (t.isIsolatedVertex(v)) continue;
    std::int64_t cutEdges = 0;
    t.forEachCornerAround(v, [&](CornerId c) {
      const CornerId e = nextCorner(c);  // edge from v to the next vertex of the fan
      if (t.opposite(e) != kInvalidId && cut.corners.isCut(e)) ++cutEdges;
    });
    const bool boundary = t.isBoundaryVertex(v);
    chi[comps.faceComponent[cornerFace(t.vertexCorner(v))]] +=
        boundary ? cutEdges + 1 : std::max<std::int64_t>(cutEdges, 1);
  }
  std::vector<std::uint32_t> rootOfComponent(comps.components.size(), kInvalidId);
  for (FaceId f = 0; f < t.numFaces(); ++f) {
    std::uint32_t& root = rootOfComponent[comps.faceComponent[f]];
    if (root == kInvalidId) root = pieces.find(f);
    ASSERT_EQ(pieces.find(f), root) << what << ": face " << f << " cut off from its component";
  }
  for (std::size_t k = 0; k < chi.size(); ++k) EXPECT_EQ(chi[k], 1) << what << ": component " << k;
}

std::int64_t eulerCharacteristic(const Topology& topology) {
  std::int64_t chi = 0;
  for (const ComponentInfo& c : computeComponents(topology).components) chi += c.eulerCharacteristic;
  return chi;
}

/// Poincare-Hopf on a closed surface, and the cut through the field's cones is a disk.
void expectValidField(const Surface& s, const CrossField& field, const std::string& what) {
  ASSERT_EQ(field.direction.size(), s.mesh.numFaces()) << what;
  for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
    ASSERT_TRUE(field.direction[f].allFinite()) << what << ": face " << f;
    ASSERT_NEAR(field.at(f).norm(), 1.0, 1e-6) << what << ": face " << f;
    const Vec3d n = faceNormal(s.mesh, f);
    ASSERT_LT(std::abs(n.dot(field.at(f))), 1e-6) << what << ": face " << f << " not tangent";
  }
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  if (computeComponents(s.topology).boundaryLoops == 0) {
    EXPECT_EQ(sing.indexSum4(), 4 * eulerCharacteristic(s.topology)) << what;
  }
  expectCutIsDisk(s, cutToDisk(s.mesh, s.topology, field, sing), what);
}

TEST(ProxyField, PoincareHopfAndDiskCutOnGeneratedClosedMeshes) {
  GenerateOptions genus2;
  genus2.kind = MeshKind::Genus2;
  genus2.faces = 20000;
  const std::vector<std::pair<std::string, TriangleMesh>> meshes = {
      {"icosphere", testing::icosphereMesh(4)},
      {"torus", testing::torusMesh(60, 24)},
      {"genus2", generateMesh(genus2).mesh},
      {"torus+sphere", testing::concatMeshes({testing::torusMesh(40, 16), testing::icosphereMesh(3)})}};
  for (const auto& [name, mesh] : meshes) {
    const Surface s = makeSurface(mesh);
    for (std::int32_t grid : {8, 32, 128}) {
      const ProxyFieldResult proxy = proxyField(s, grid);
      EXPECT_GT(proxy.elements, 0u);
      EXPECT_LE(proxy.colours, 4u);
      expectValidField(s, proxy.field, name + " grid " + std::to_string(grid));
    }
  }
}

Surface cleanSurface(TriangleMesh mesh) {
  CleanResult cleaned = cleanMesh(std::move(mesh));
  return {std::move(cleaned.mesh), std::move(cleaned.topology)};
}

// Scan noise (every vertex moved up to A edge lengths along its normal and across) folds faces
// over, and the field on the mesh itself gets a cone pair at each fold (several times the clean
// count). computeCrossField works on the smoothed surface: within 1.5x of the clean cones, for
// both methods, several amplitudes and seeds, with Poincare-Hopf and a disk cut.
TEST(ProxyField, NoisyScansKeepTheCleanConeCount) {
  struct Case {
    std::string name;
    TriangleMesh mesh;
    FieldMethod method;
  };
  std::vector<Case> cases;
  for (const MeshKind kind : {MeshKind::Genus2, MeshKind::Scan}) {
    GenerateOptions options;
    options.kind = kind;
    options.faces = 30000;
    cases.push_back({meshKindName(kind), generateMesh(options).mesh, FieldMethod::Direct});
  }
  const std::string fertility = testing::sharedMesh("fertility.off");
  if (!fertility.empty()) {
    const Surface base = testing::loadShared(fertility);
    SubdivideOptions twice;
    twice.levels = 2;
    cases.push_back({"fertility x16", subdivideMesh(base.mesh, base.topology, twice).mesh, FieldMethod::Proxy});
  }
  const auto coneCount = [](const Surface& s, FieldMethod method, const std::string& what) {
    const CrossField field = computeCrossField(s.mesh, s.topology, method);
    expectValidField(s, field, what);
    return computeSingularities(s.mesh, s.topology, field).cones.size();
  };
  for (const Case& c : cases) {
    const std::size_t clean = coneCount(cleanSurface(c.mesh), c.method, c.name);
    for (const auto& [amplitude, seed] : {std::pair{0.25, 1u}, {0.25, 2u}, {0.5, 3u}}) {
      TriangleMesh mesh = c.mesh;
      ScanNoiseOptions noise;
      noise.amplitude = amplitude;
      noise.seed = seed;
      addScanNoise(mesh, noise);
      const std::string what = c.name + " noise " + std::to_string(amplitude) + " seed " + std::to_string(seed);
      const std::size_t noisy = coneCount(cleanSurface(mesh), c.method, what);
      EXPECT_LE(noisy, 1.5 * clean) << what << " (clean: " << clean << " cones)";
    }
  }
  if (fertility.empty()) GTEST_SKIP() << testing::missingSharedMessage("fertility.off");
}

TEST(ProxyField, SmoothingKeepsBoundaryAndPlanesAndRotationsInvert) {
  const Surface s = makeSurface(testing::gridMesh(6, 5));
  const std::vector<Vec3f> smoothed = smoothPositions(s.mesh, s.topology, 3);
  for (VertexId v = 0; v < s.topology.numVertices(); ++v) {
    EXPECT_EQ(smoothed[v].z(), 0.0f);
    if (s.topology.isBoundaryVertex(v)) EXPECT_EQ(smoothed[v], s.mesh.positions[v]);
  }
  const Vec3d a = Vec3d(1, 2, 3).normalized(), b = Vec3d(-2, 0.5, 1).normalized();
  for (const Vec3d& to : {b, Vec3d(-a)}) {
    const Vec3d u = a.unitOrthogonal();
    const Vec3d there = rotateBetween(a, to, u);
    EXPECT_NEAR(there.dot(to), 0.0, 1e-12);
    EXPECT_NEAR((rotateBetween(to, a, there) - u).norm(), 0.0, 1e-12);
  }
}

TEST(ProxyField, SmoothSphereHasEightQuarterCones) {
  const Surface s = makeSurface(testing::icosphereMesh(5));
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, proxyField(s, 32).field);
  EXPECT_EQ(sing.indexSum4(), 8);
  EXPECT_EQ(sing.cones.size(), 8u);
  for (VertexId v : sing.cones) EXPECT_EQ(sing.index4[v], 1) << "vertex " << v;
}

TEST(ProxyField, ConstantOnAPlane) {
  const Surface s = makeSurface(testing::gridMesh(60, 40, 0.5));
  for (std::int32_t grid : {4, 16, 64}) {
    const ProxyFieldResult proxy = proxyField(s, grid);
    // A constant cross: the same 4th power on every face (all frames share the plane's axes
    // up to the face's first-edge angle, so compare angles in world coordinates).
    auto fourth = [](const Vec3d& u) {
      std::complex<double> z(u.x(), u.y());
      z *= z;
      return z * z;
    };
    const std::complex<double> z0 = fourth(proxy.field.at(0));
    double worst = 0.0;
    for (const Vec3f& u : proxy.field.direction) worst = std::max(worst, std::abs(fourth(u.cast<double>()) - z0));
    EXPECT_LT(worst, 1e-6) << "grid " << grid;
    EXPECT_LT(measureFieldEnergy(s.mesh, s.topology, proxy.field), 1e-9) << "grid " << grid;
    EXPECT_TRUE(computeSingularities(s.mesh, s.topology, proxy.field).cones.empty()) << "grid " << grid;
    expectValidField(s, proxy.field, "plane grid " + std::to_string(grid));
  }
}

TEST(ProxyField, TwoSheetsInOneCellAreSeparateElements) {
  // Two parallel squares 0.01 apart; 5 cells of 0.2 centred on them: every cell that holds
  // faces holds both sheets.
  TriangleMesh lower = testing::gridMesh(8, 8, 0.125);
  TriangleMesh upper = lower;
  for (Vec3f& p : upper.positions) p.z() = 0.01f;
  const Surface s = makeSurface(testing::concatMeshes({lower, upper}));
  const ProxyFieldResult one = proxyField(makeSurface(lower), 5);
  const ProxyFieldResult two = proxyField(s, 5);
  EXPECT_EQ(two.elements, 2 * one.elements);
  expectValidField(s, two.field, "two sheets");
}

TEST(ProxyField, SameResultForOneAndTwoThreads) {
  GenerateOptions options;
  options.kind = MeshKind::Torus;
  options.faces = 30000;
  const Surface s = makeSurface(generateMesh(options).mesh);
  CrossField serial;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    serial = proxyField(s, 32).field;
  }
  const CrossField parallel = proxyField(s, 32).field;
  for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
    ASSERT_EQ(serial.direction[f], parallel.direction[f]) << "face " << f;
  }
}

// The elements' sets, joined on both cores (a union-find by compare-and-swap), against the serial
// union-find: the same smallest face per face, at one thread and at two, for faces joined by cells
// of several sizes (many small sets, a few large ones, one set per component).
TEST(ProxyField, ElementSetsOnBothCoresAreTheSerialOnes) {
  const Surface s = makeSurface(testing::generatedMesh(MeshKind::Genus2, 200000));
  const std::uint32_t nf = s.topology.numFaces();
  std::mt19937 random(3);
  for (const std::uint32_t cells : {1u << 16, 64u, 1u}) {
    std::vector<std::uint32_t> cell(nf);
    for (FaceId f = 0; f < nf; ++f) cell[f] = (f / 97 + random() % 3) % cells;  // runs and noise
    const auto joined = [&](FaceId f, FaceId g) { return cell[f] == cell[g]; };
    detail::UnionFind serial(nf);
    for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
      const CornerId o = s.topology.opposite(c);
      if (o != kInvalidId && o > c && joined(c / 3, o / 3)) serial.unite(c / 3, o / 3);
    }
    std::size_t sets = 0;
    for (FaceId f = 0; f < nf; ++f) sets += serial.find(f) == f;
    if (cells > 1) EXPECT_GT(sets, 1000u);  // cells = 1: one set per component
    for (const int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      const std::vector<std::uint32_t> roots = detail::smallestFaceOfSets(s.topology, joined);
      ASSERT_EQ(roots.size(), nf);
      for (FaceId f = 0; f < nf; ++f) ASSERT_EQ(roots[f], serial.find(f)) << "face " << f << ", " << threads << " threads";
    }
  }
}

TEST(ProxyField, SweepsLowerTheEnergy) {
  GenerateOptions options;
  options.kind = MeshKind::Sphere;
  options.faces = 40000;
  const Surface s = makeSurface(generateMesh(options).mesh);
  const double transferred = measureFieldEnergy(s.mesh, s.topology, proxyField(s, 32, 0).field);
  const double smoothed = measureFieldEnergy(s.mesh, s.topology, proxyField(s, 32, 4).field);
  EXPECT_GT(transferred, 0.0);
  EXPECT_LT(smoothed, transferred);
}

TEST(ProxyField, ZeroAreaFacesGiveNoNaN) {
  // A grid whose middle row of vertices is moved onto the row below: its faces have zero area.
  TriangleMesh mesh = testing::gridMesh(6, 6);
  for (Vec3f& p : mesh.positions) {
    if (p.y() == 3.0f) p.y() = 2.0f;
  }
  const Surface s = makeSurface(mesh);
  const CrossField field = proxyField(s, 8).field;
  for (const Vec3f& u : field.direction) EXPECT_TRUE(u.allFinite());
}

TEST(ProxyField, ComparableToTheDirectFieldOnSharedMeshes) {
  for (const char* name : {"bumpy.off", "bunny.off", "fertility.off", "3holes.off", "cheburashka.off",
                           "rocker-arm.obj", "camelhead.off", "armadillo.obj"}) {
    const std::string path = testing::sharedMesh(name);
    if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage(name);
    const Surface s = loadShared(path);
    const CrossField direct = computeSmoothestField(s.mesh, s.topology);
    const std::size_t directCones = computeSingularities(s.mesh, s.topology, direct).cones.size();
    const double directEnergy = measureFieldEnergy(s.mesh, s.topology, direct);
    // Grid 32: a few faces to a few dozen per element on these meshes; 128: about one.
    for (std::int32_t grid : {32, 128}) {
      const std::string what = std::string(name) + " grid " + std::to_string(grid);
      const ProxyFieldResult proxy = proxyField(s, grid);
      expectValidField(s, proxy.field, what);
      const std::size_t proxyCones = computeSingularities(s.mesh, s.topology, proxy.field).cones.size();
      const double proxyEnergy = measureFieldEnergy(s.mesh, s.topology, proxy.field);
      EXPECT_LE(proxyCones, 2 * directCones + 8) << what << ": direct " << directCones;
      EXPECT_LE(proxyEnergy, 2.0 * directEnergy) << what;
      std::printf("%-26s %6u faces %6u elements  cones direct %4zu proxy %4zu  energy direct %8.1f proxy %8.1f\n",
                  what.c_str(), s.mesh.numFaces(), proxy.elements, directCones, proxyCones, directEnergy,
                  proxyEnergy);
    }
  }
}

TEST(ProxyField, MethodSelection) {
  EXPECT_EQ(resolveFieldMethod(FieldMethod::Auto, 1000), FieldMethod::Direct);
  EXPECT_EQ(resolveFieldMethod(FieldMethod::Auto, kDirectFieldMaxFaces), FieldMethod::Direct);
  EXPECT_EQ(resolveFieldMethod(FieldMethod::Auto, kDirectFieldMaxFaces + 1), FieldMethod::Proxy);
  EXPECT_EQ(resolveFieldMethod(FieldMethod::Proxy, 10), FieldMethod::Proxy);
  EXPECT_EQ(resolveFieldMethod(FieldMethod::Direct, 1u << 30), FieldMethod::Direct);
  for (FieldMethod m : {FieldMethod::Auto, FieldMethod::Direct, FieldMethod::Proxy}) {
    EXPECT_EQ(parseFieldMethod(fieldMethodName(m)), m);
  }
  EXPECT_EQ(parseFieldMethod("smooth"), FieldMethod::Direct);
  EXPECT_THROW(parseFieldMethod("fast"), InputError);

  const Surface s = makeSurface(testing::icosphereMesh(2));
  SmoothFieldOptions curvature;
  curvature.curvatureWeight = 1.0;
  EXPECT_THROW(computeCrossField(s.mesh, s.topology, FieldMethod::Proxy, curvature), InputError);
  // Auto on a small mesh is the direct solve (on the smoothed frames), curvature alignment included.
  EXPECT_EQ(computeCrossField(s.mesh, s.topology, FieldMethod::Auto, curvature).direction,
            computeCrossField(s.mesh, s.topology, FieldMethod::Direct, curvature).direction);
  const CrossField proxy = computeCrossField(s.mesh, s.topology, FieldMethod::Proxy);
  expectValidField(s, proxy, "computeCrossField proxy");
  ProxyFieldOptions bad;
  bad.gridResolution = 2;
  EXPECT_THROW(computeProxyField(s.mesh, s.topology, bad), InputError);
  bad.gridResolution = 64;
  bad.smoothingSweeps = -1;
  EXPECT_THROW(computeProxyField(s.mesh, s.topology, bad), InputError);
}

// Angle in [0, 45] degrees between a cross field direction and a tangent line direction.
double crossAngleDegrees(const Vec3d& u, const Vec3d& d, const Vec3d& n) {
  const double a = std::atan2(n.dot(d.cross(u)), d.dot(u));
  const double quarter = std::remainder(a, M_PI / 2);  // in [-45, 45] degrees
  return std::abs(quarter) * 180.0 / M_PI;
}

TEST(ProxyField, CurvatureAlignedFieldFollowsPrincipalDirectionsOnAnEllipsoid) {
  // Ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1: the principal directions at p are the tangent
  // eigenvectors of P H P (H = diag(2/a^2, 2/b^2, 2/c^2), P the tangent projector).
  const Vec3d radii(1.6, 1.0, 0.6);
  TriangleMesh mesh = testing::icosphereMesh(4);
  for (Vec3f& p : mesh.positions) p = (p.cast<double>().cwiseProduct(radii)).cast<float>();
  const Surface s = makeSurface(std::move(mesh));
  SmoothFieldOptions curvature;
  curvature.curvatureWeight = 1.0;
  const CrossField aligned = computeCrossField(s.mesh, s.topology, FieldMethod::Auto, curvature);
  const CrossField smoothest = computeCrossField(s.mesh, s.topology, FieldMethod::Auto);
  const Eigen::Matrix3d H = Eigen::Vector3d(2 / (radii.x() * radii.x()), 2 / (radii.y() * radii.y()),
                                            2 / (radii.z() * radii.z())).asDiagonal();
  std::uint32_t within10Aligned = 0, within10Smoothest = 0, counted = 0;
  for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
    const Vec3d n = faceNormal(s.mesh, f);
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - n * n.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(P * H * P);
    // The largest eigenvalue's vector is a principal direction; skip near-umbilic faces, where
    // the two tangent eigenvalues (the largest two) nearly agree.
    const Eigen::Vector3d values = eigen.eigenvalues();
    if (values[2] - values[1] < 0.1 * values[2]) continue;
    const Vec3d d = eigen.eigenvectors().col(2);
    ++counted;
    within10Aligned += crossAngleDegrees(aligned.at(f), d, n) < 10.0;
    within10Smoothest += crossAngleDegrees(smoothest.at(f), d, n) < 10.0;
  }
  ASSERT_GT(counted, s.mesh.numFaces() / 2);
  EXPECT_GT(within10Aligned, 0.9 * counted) << "of " << counted << " faces";
  // The smoothest field alone does not follow curvature (the alignment above is the weight's).
  EXPECT_LT(within10Smoothest, within10Aligned);
  std::printf("ellipsoid: %u of %u faces within 10 degrees of a principal direction (smoothest: %u)\n",
              within10Aligned, counted, within10Smoothest);
}

TEST(ProxyField, CommandsSelectTheMethodAndReportIt) {
  testing::TempDir dir;
  writeMesh(dir.path("t.obj"), testing::torusMesh(48, 20));
  std::string out;
  ASSERT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("t.field") +
                                    " --field proxy --json --quiet", &out), 0) << out;
  EXPECT_NE(out.find("\"fieldMethod\": \"proxy\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"indexSum4\": 0"), std::string::npos) << out;  // torus: chi = 0
  ASSERT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("t.field") + " --json --quiet",
                                &out), 0) << out;
  EXPECT_NE(out.find("\"fieldMethod\": \"direct\""), std::string::npos) << out;  // auto, small mesh
  EXPECT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("t.field") +
                                    " --field proxy --curvature 1", &out), 2) << out;
  EXPECT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("t.field") + " --field fast",
                                &out), 2) << out;
  // param: the proxy field gives a seamless map; the report names the method.
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("t.obj") + " -o " + dir.path("t_uv.obj") +
                                    " --field proxy --solver hat --quiet --report " + dir.path("r.json"), &out),
            0) << out;
  const std::string report = testing::readFile(dir.path("r.json"));
  EXPECT_NE(report.find("\"fieldMethod\": \"proxy\""), std::string::npos) << report;
  EXPECT_NE(report.find("\"seamless\": true"), std::string::npos) << report;
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("t.obj") + " -o " + dir.path("t_uv.obj") +
                                    " --solver hat --quiet --report " + dir.path("r.json"), &out), 0) << out;
  EXPECT_NE(testing::readFile(dir.path("r.json")).find("\"fieldMethod\": \"direct\""), std::string::npos);
}

TEST(ProxyField, EmptyAndTinyMeshes) {
  const Surface empty = makeSurface(TriangleMesh{});
  EXPECT_TRUE(computeProxyField(empty.mesh, empty.topology).field.direction.empty());
  TriangleMesh triangle;
  triangle.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  triangle.triangles = {{0, 1, 2}};
  TriangleMesh needle = triangle;  // zero area: collinear corners
  needle.positions[2] = Vec3f(2, 0, 0);
  const std::vector<std::pair<std::string, TriangleMesh>> meshes = {
      {"triangle", triangle},
      {"needle", needle},
      {"two triangles", testing::concatMeshes({triangle, needle})},
      {"triangle+torus", testing::concatMeshes({triangle, testing::torusMesh(20, 8)})}};
  for (const auto& [name, mesh] : meshes) {
    const Surface s = makeSurface(mesh);
    for (std::int32_t grid : {4, 128}) {
      const CrossField field = proxyField(s, grid).field;
      ASSERT_EQ(field.direction.size(), s.mesh.numFaces()) << name;
      for (const Vec3f& u : field.direction) EXPECT_NEAR(u.norm(), 1.0, 1e-6) << name << " grid " << grid;
    }
  }
}

// The sweep step by its definition: the unit 4th powers of the neighbours' directions carried into
// the face's plane (projected when the normals are within kProjectCosine, else rotated), summed,
// and the representative of the sum's 4th root in the frame (u, n x u). A batch of faces gives
// every face the bits it gets alone, whatever its lane and whatever the other lanes hold.
TEST(ProxySweep, BatchesMatchTheDefinitionAndEachFaceAlone) {
  using detail::SweepBatch;
  struct Face {
    Vec3f normal;
    Vec3d u;
    Vec3f neighbourNormal[3];
    Vec3d neighbourDirection[3];
    int count = 0;
  };
  std::mt19937 random(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto randomUnit = [&] {
    Vec3d v(unit(random), unit(random), unit(random));
    return Vec3d(v.normalized());
  };
  std::vector<Face> faces(403);
  int tilted = 0, cancelled = 0;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    Face& f = faces[i];
    const Vec3d n = randomUnit();
    f.normal = n.cast<float>();
    f.u = n.unitOrthogonal();
    f.count = static_cast<int>(i % 4);
    for (int k = 0; k < f.count; ++k) {
      // Mostly near the face's plane; every seventh neighbour folded well past kProjectCosine.
      const double tilt = (i + k) % 7 == 0 ? 1.2 : 0.05;
      const Vec3d m = (n + tilt * randomUnit()).normalized();
      f.neighbourNormal[k] = m.cast<float>();
      f.neighbourDirection[k] = m.cross(randomUnit()).normalized();
      tilted += m.dot(n) < detail::kProjectCosine;
    }
    if (i % 50 == 3) f.neighbourDirection[0] = Vec3d::Zero();  // no direction: adds nothing
    if (i % 50 == 6 && f.count == 2) {
      // Two neighbours an eighth of a turn apart in the plane: their 4th powers cancel (to rounding).
      f.neighbourNormal[0] = f.neighbourNormal[1] = f.normal;
      const Vec3d u = f.u, v = n.cross(u);
      f.neighbourDirection[0] = u;
      f.neighbourDirection[1] = (u + v).normalized();
      ++cancelled;
    }
  }
  ASSERT_GT(tilted, 20);
  ASSERT_GT(cancelled, 0);
  // The definition, written with Eigen.
  const auto reference = [](const Face& f, Vec3d& out) {
    const Vec3d n = f.normal.cast<double>(), v = n.cross(f.u);
    std::complex<double> sum = 0.0;
    for (int k = 0; k < f.count; ++k) {
      const Vec3d m = f.neighbourNormal[k].cast<double>();
      const Vec3d w = m.dot(n) >= detail::kProjectCosine ? f.neighbourDirection[k]
                                                          : rotateBetween(m, n, f.neighbourDirection[k]);
      const std::complex<double> z(w.dot(f.u), w.dot(v));
      if (std::norm(z) > 0.0) sum += std::pow(z / std::abs(z), 4);
    }
    if (!(std::abs(sum) > 1e-6)) return false;  // cancelled: no direction to compare
    const double angle = std::arg(sum) / 4.0;
    out = std::cos(angle) * f.u + std::sin(angle) * v;
    return true;
  };
  std::vector<Vec3d> alone(faces.size());
  std::vector<std::uint8_t> changed(faces.size(), 0);
  int compared = 0;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Face& f = faces[i];
    changed[i] = detail::sweptDirection(f.normal, f.u, f.neighbourNormal, f.neighbourDirection, f.count, alone[i]);
    Vec3d expected;
    const bool has = reference(f, expected);
    if (f.count == 0) EXPECT_FALSE(changed[i]) << "face " << i;
    if (!has || !changed[i]) continue;
    EXPECT_LT((alone[i] - expected).norm(), 1e-9) << "face " << i;
    ++compared;
  }
  EXPECT_GT(compared, 250);
  // In batches, faces in a shuffled order (so every face sits in several lanes over the runs).
  for (std::uint32_t run = 0; run < 3; ++run) {
    std::vector<std::size_t> order(faces.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), random);
    std::vector<Vec3d> got(faces.size());
    std::vector<std::uint8_t> seen(faces.size(), 0);
    SweepBatch batch;
    const auto store = [&](std::uint64_t i, const Vec3d& d) { got[i] = d, seen[i] = 1; };
    for (std::size_t i : order) {
      const Face& f = faces[i];
      if (batch.add(i, f.normal, f.u, f.neighbourNormal, f.neighbourDirection, f.count)) batch.flush(store);
    }
    batch.flush(store);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      ASSERT_EQ(seen[i], changed[i]) << "face " << i;
      if (changed[i]) ASSERT_EQ(got[i], alone[i]) << "face " << i;
    }
  }
}


// The transfer by its definition: per face, its element's and the neighbours' directions rotated
// onto the face's plane, their unit 4th powers weighted by confidence and a bump of the centroid
// distance (the own element at least 1e-3), and the 4th root of the sum nearest e1. Faces batched
// per element get the bits each gets alone, whatever the batch.
TEST(ProxyTransfer, BatchesMatchTheDefinitionAndEachFaceAlone) {
  std::mt19937 random(23);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto randomUnit = [&] { return Vec3d(Vec3d(unit(random), unit(random), unit(random)).normalized()); };
  // Six elements in a row of cells, each joined to the next; element 5's normal opposite to 4's.
  detail::ProxyElements elements;
  detail::ElementDirections directions;
  directions.radius = 2.0;
  for (std::uint32_t e = 0; e < 6; ++e) {
    const Vec3d n = e == 5 ? Vec3d(-elements.normal[4]) : Vec3d((Vec3d::UnitZ() + 0.3 * randomUnit()).normalized());
    elements.normal.push_back(n);
    elements.centroid.push_back(Vec3d(double(e), 0.2 * unit(random), 0.0));
    elements.area.push_back(1.0);
    directions.direction.push_back(n.cross(randomUnit()).normalized());
    directions.confidence.push_back(e == 2 ? 0.0 : 0.5 + 0.5 * std::abs(unit(random)));
  }
  elements.neighbourStart = {0};
  for (std::uint32_t e = 0; e < 6; ++e) {
    if (e > 0) elements.neighbours.push_back({e - 1, 1.0});
    if (e < 5) elements.neighbours.push_back({e + 1, 1.0});
    elements.neighbourStart.push_back(static_cast<std::uint32_t>(elements.neighbours.size()));
  }
  struct Face {
    detail::FaceGeometry g;
    std::uint32_t own;
  };
  std::vector<Face> faces;
  for (std::uint32_t i = 0; i < 300; ++i) {
    const std::uint32_t own = (i / 7) % 6;  // runs of one element, of several lengths
    const Vec3d c = elements.centroid[own] + Vec3d(0.5 * unit(random), 0.5 * unit(random), 0.1 * unit(random));
    const Vec3d a = randomUnit(), b = randomUnit();
    faces.push_back({detail::faceGeometry({c, Vec3d(c + 0.1 * a), Vec3d(c + 0.1 * b)}), own});
  }
  const auto reference = [&](const Face& f) {
    std::complex<double> sum = 0.0;
    const auto add = [&](std::uint32_t e) {
      const double d = (f.g.centroid - elements.centroid[e]).norm() / directions.radius;
      const double bump = d < 1.0 ? (1.0 - d * d) * (1.0 - d * d) : 0.0;
      const double w = directions.confidence[e] * (e == f.own ? std::max(bump, 1e-3) : bump);
      const Vec3d v = rotateBetween(elements.normal[e], f.g.n, directions.direction[e]);
      const std::complex<double> z(v.dot(f.g.e1), v.dot(f.g.e2));
      if (w > 0.0 && std::norm(z) > 0.0) sum += w * std::pow(z / std::abs(z), 4);
    };
    add(f.own);
    for (std::uint32_t i = elements.neighbourStart[f.own]; i < elements.neighbourStart[f.own + 1]; ++i) {
      add(elements.neighbours[i].first);
    }
    if (!(std::abs(sum) > 1e-9)) return f.g.e1;
    const double angle = std::arg(sum) / 4.0;
    return Vec3d(std::cos(angle) * f.g.e1 + std::sin(angle) * f.g.e2);
  };
  std::vector<Vec3d> alone(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    alone[i] = detail::transferredDirection(elements, directions, faces[i].g, faces[i].own);
    EXPECT_LT((alone[i] - reference(faces[i])).norm(), 1e-9) << "face " << i;
  }
  // Batched in face order (runs of one element) and in a shuffled order (runs of one face).
  for (const bool shuffled : {false, true}) {
    std::vector<std::size_t> order(faces.size());
    std::iota(order.begin(), order.end(), 0);
    if (shuffled) std::shuffle(order.begin(), order.end(), random);
    std::vector<Vec3d> got(faces.size(), Vec3d::Constant(7.0));
    detail::TransferBatch batch(elements, directions);
    const auto store = [&](std::uint64_t i, const Vec3d& d) { got[i] = d; };
    for (std::size_t i : order) batch.add(i, faces[i].g, faces[i].own, store);
    batch.flush(store);
    for (std::size_t i = 0; i < faces.size(); ++i) ASSERT_EQ(got[i], alone[i]) << "face " << i;
  }
}

}  // namespace
}  // namespace seamvox
