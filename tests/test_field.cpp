// Cross fields: Poincare-Hopf, index sign, smoothest field, curvature alignment, degenerate
// faces, tangent projection and field files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/synth/generate.h"
#include "core/mesh/topology.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::loadShared;
using testing::makeSurface;
using testing::Surface;

std::int64_t eulerCharacteristic(const Topology& topology) {
  std::int64_t chi = 0;
  for (const ComponentInfo& c : computeComponents(topology).components) chi += c.eulerCharacteristic;
  return chi;
}

using testing::randomField;

/// Sum over interior edges of the squared residual rotation eps, recomputed from matchings:
/// a smoothness figure that is independent of the solver's energy.
double residualEnergy(const Surface& s, const CrossField& field) {
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  double sum = 0.0;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const CornerId o = s.topology.opposite(c);
    if (o == kInvalidId || o < c) continue;
    const FaceId f = cornerFace(c), g = cornerFace(o);
    // Angle between u_g and the transported rot^k(u_f), measured in g's tangent plane: for
    // nearly flat neighbours this is the residual eps up to the small dihedral correction.
    const Vec3d nf = faceNormal(s.mesh, f), ng = faceNormal(s.mesh, g);
    Vec3d u = field.at(f);
    for (int k = 0; k < sing.matching[c]; ++k) u = nf.cross(u);
    const Vec3d axis = nf.cross(ng);
    const double sinA = axis.norm(), cosA = nf.dot(ng);
    if (sinA > 1e-12) {  // rotate u about the shared edge onto g's plane
      const Vec3d k = axis / sinA;
      u = u * cosA + k.cross(u) * sinA + k * k.dot(u) * (1 - cosA);
    }
    const double e = std::atan2(ng.dot(u.cross(field.at(g))), u.dot(field.at(g)));
    sum += e * e;
  }
  return sum;
}

void expectPoincareHopf(const Surface& s, const CrossField& field, const std::string& what) {
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  EXPECT_EQ(sing.indexSum4(), 4 * eulerCharacteristic(s.topology)) << what;
  std::size_t nonZero = 0;
  for (std::int32_t i : sing.index4) nonZero += i != 0;
  EXPECT_EQ(nonZero, sing.cones.size()) << what;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const CornerId o = s.topology.opposite(c);
    if (o != kInvalidId) ASSERT_EQ((sing.matching[c] + sing.matching[o]) % 4, 0) << what;
  }
}

// What a later cone pass restores: every matching, index and boundary index as computed, in
// about a quarter of the matchings' bytes.
TEST(Field, PackedSingularitiesUnpackToTheSame) {
  const Surface s = makeSurface(testing::concatMeshes({testing::gridMesh(9, 7, 1.0), testing::torusMesh(20, 10)}));
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, randomField(s.mesh, 5));
  ASSERT_GT(sing.cones.size(), 4u);
  ASSERT_TRUE(std::any_of(sing.boundaryIndex4.begin(), sing.boundaryIndex4.end(), [](std::int32_t k) { return k != 0; }));
  const PackedSingularities packed = packSingularities(sing);
  EXPECT_LE(packed.matching.size(), sing.matching.size() / 4 + 1);
  const FieldSingularities back = unpackSingularities(packed);
  EXPECT_EQ(back.matching, sing.matching);
  EXPECT_EQ(back.index4, sing.index4);
  EXPECT_EQ(back.boundaryIndex4, sing.boundaryIndex4);
  EXPECT_EQ(back.cones, sing.cones);
  EXPECT_TRUE(PackedSingularities().empty());
  EXPECT_FALSE(packed.empty());
}

TEST(Field, PoincareHopfOnGeneratedClosedMeshes) {
  GenerateOptions genus2;
  genus2.kind = MeshKind::Genus2;
  genus2.faces = 6000;
  const Surface surfaces[] = {makeSurface(testing::icosphereMesh(3)),
                              makeSurface(testing::torusMesh(40, 16)),
                              makeSurface(generateMesh(genus2).mesh)};
  const std::int64_t expectedChi[] = {2, 0, -2};
  for (int i = 0; i < 3; ++i) {
    const Surface& s = surfaces[i];
    ASSERT_EQ(eulerCharacteristic(s.topology), expectedChi[i]);
    expectPoincareHopf(s, computeSmoothestField(s.mesh, s.topology), "smoothest #" + std::to_string(i));
    expectPoincareHopf(s, randomField(s.mesh, 7 + i), "random #" + std::to_string(i));
  }
}

// A scan's collinear faces, cleaned: two near-degenerate slivers glued along their long edge, their
// tips at one position (centroids equal: the largest dual weight), as an island of a closed mesh.
// Both field solvers factor it (its flat pair used to lose its shift to rounding: "not positive
// definite") and give every face a unit direction; the sphere keeps its eight quarter cones.
TEST(Field, GluedSliversOnOnePointStillFactor) {
  TriangleMesh island;
  island.positions = {Vec3f(3.0f, 0.0f, 0.0f), Vec3f(4.0f, 0.0f, 0.0f), Vec3f(3.5f, 1e-9f, 0.0f), Vec3f(3.5f, 1e-9f, 0.0f)};
  island.triangles = {{0, 2, 1}, {1, 3, 0}};
  const CleanResult clean = cleanMesh(testing::concatMeshes({testing::icosphereMesh(3), island}));
  ASSERT_EQ(clean.mesh.numFaces(), 1282u);
  ASSERT_GT(faceArea(clean.mesh, 1280), 0.0);
  ASSERT_LT(faceArea(clean.mesh, 1280), 1e-5);
  for (const FieldMethod method : {FieldMethod::Direct, FieldMethod::Proxy}) {
    const CrossField field = computeCrossField(clean.mesh, clean.topology, method);
    for (FaceId f = 0; f < clean.mesh.numFaces(); ++f) EXPECT_NEAR(field.at(f).norm(), 1.0, 1e-6) << f;
    const FieldSingularities sing = computeSingularities(clean.mesh, clean.topology, field);
    std::int32_t sphere = 0;
    for (const VertexId v : sing.cones) sphere += v < 642 ? sing.index4[v] : 0;
    EXPECT_EQ(sphere, 8) << fieldMethodName(method);
  }
}

TEST(Field, PoincareHopfOnSharedClosedMeshes) {
  const std::pair<const char*, std::int64_t> cases[] = {{"fertility.off", -6}, {"3holes.off", -4}, {"bumpy.off", 2}};
  for (const auto& [name, chi] : cases) {
    const std::string path = testing::sharedMesh(name);
    if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage(name);
    const Surface s = loadShared(path);
    ASSERT_EQ(eulerCharacteristic(s.topology), chi) << name;
    const CrossField field = computeSmoothestField(s.mesh, s.topology);
    expectPoincareHopf(s, field, name);
    const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
    std::printf("[ info ] %s: smoothest field has %zu cones, index sum %lld/4\n", name,
                sing.cones.size(), static_cast<long long>(sing.indexSum4()));
  }
}

/// Flat fan of n triangles around vertex 0 at the origin; field at polar angle phi * s / 4.
TEST(Field, IndexSignOnFlatFan) {
  const int n = 12;
  TriangleMesh mesh;
  mesh.positions.emplace_back(0.f, 0.f, 0.f);
  for (int j = 0; j < n; ++j) {
    const double a = 2 * M_PI * j / n;
    mesh.positions.emplace_back(float(std::cos(a)), float(std::sin(a)), 0.f);
  }
  for (int j = 0; j < n; ++j) mesh.triangles.push_back({0, VertexId(1 + j), VertexId(1 + (j + 1) % n)});
  const Surface s = makeSurface(mesh);
  for (const int sign : {+1, -1}) {
    for (const double rotation : {0.0, 0.3, 2.0}) {  // adding a constant angle changes nothing
      std::vector<Vec3d> dirs;
      for (int j = 0; j < n; ++j) {
        const double phi = 2 * M_PI * (j + 0.5) / n;
        const double theta = sign * phi / 4 + rotation;
        dirs.emplace_back(std::cos(theta), std::sin(theta), 0.0);
      }
      const FieldSingularities sing =
          computeSingularities(s.mesh, s.topology, projectToTangent(s.mesh, dirs));
      EXPECT_EQ(sing.index4[0], sign) << "sign " << sign << " rotation " << rotation;
      for (VertexId v = 1; v <= VertexId(n); ++v) EXPECT_EQ(sing.index4[v], 0);  // boundary
      ASSERT_EQ(sing.cones.size(), 1u);
      EXPECT_EQ(sing.cones[0], 0u);
    }
  }
  // Lifted into a cone (angle defect about 1.86): the index counts the field's turning against
  // the transport, so a field that is constant seen from above still has index 0 and the
  // quarter-turning one index +1.
  TriangleMesh lifted = mesh;
  lifted.positions[0].z() = 1.0f;
  const Surface t = makeSurface(lifted);
  for (const int turns : {0, 1}) {
    std::vector<Vec3d> dirs;
    for (int j = 0; j < n; ++j) {
      const double theta = turns * 2 * M_PI * (j + 0.5) / n / 4;
      dirs.emplace_back(std::cos(theta), std::sin(theta), 0.0);
    }
    const FieldSingularities sing = computeSingularities(t.mesh, t.topology, projectToTangent(t.mesh, dirs));
    EXPECT_EQ(sing.index4[0], turns);
  }
}

TEST(Field, SmoothestFieldOnBumpySphereAndTorus) {
  const std::string path = testing::sharedMesh("bumpy.off");
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage("bumpy.off");
  const Surface bumpy = loadShared(path);
  const CrossField field = computeSmoothestField(bumpy.mesh, bumpy.topology);
  const FieldSingularities sing = computeSingularities(bumpy.mesh, bumpy.topology, field);
  std::int64_t sum = 0;
  for (VertexId v : sing.cones) sum += sing.index4[v];
  EXPECT_EQ(sum, 8);  // cone indices sum to 2
  EXPECT_GE(sing.cones.size(), 2u);
  std::printf("[ info ] bumpy.off: %zu cones\n", sing.cones.size());
  // Smoothest means: every random perturbation is rougher.
  const double energy = residualEnergy(bumpy, field);
  std::vector<Vec3d> perturbed(field.direction.size());
  for (FaceId f = 0; f < perturbed.size(); ++f) {
    perturbed[f] = field.at(f);
    const Vec3d n = faceNormal(bumpy.mesh, f);
    const double a = 0.2 * std::sin(12.9898 * f);
    perturbed[f] = std::cos(a) * perturbed[f] + std::sin(a) * n.cross(perturbed[f]);
  }
  EXPECT_LT(energy, residualEnergy(bumpy, projectToTangent(bumpy.mesh, perturbed)));

  // A thin torus of revolution (tube radius / big radius = 1/6): cone-free at every resolution
  // (thicker tori have smoothest fields with 4 to 12 cones, still summing to 0).
  const Surface torus = makeSurface(testing::torusMesh(96, 16, 3.0, 0.5));
  const FieldSingularities torusSing =
      computeSingularities(torus.mesh, torus.topology, computeSmoothestField(torus.mesh, torus.topology));
  EXPECT_EQ(torusSing.cones.size(), 0u);
}

TEST(Field, CurvatureAlignmentOnCylinder) {
  // Flat cylinder: every constant-angle field is smoothest; curvature picks axis/circumference.
  const Surface s = makeSurface(testing::cylinderMesh(48, 16, 1.0, 2.0));
  auto alignment = [&](const CrossField& field) {
    double sum = 0.0;
    for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
      const Vec3d n = faceNormal(s.mesh, f);
      const Vec3d axis = (Vec3d::UnitZ() - n * n.z()).normalized();
      const double a = std::atan2(n.dot(axis.cross(field.at(f))), axis.dot(field.at(f)));
      sum += std::cos(4 * a);
    }
    return sum / s.mesh.numFaces();
  };
  SmoothFieldOptions options;
  options.curvatureWeight = 1.0;
  const CrossField aligned = computeSmoothestField(s.mesh, s.topology, options);
  EXPECT_GT(alignment(aligned), 0.98);
  EXPECT_TRUE(computeSingularities(s.mesh, s.topology, aligned).cones.empty());
  // The smoothest field alone is parallel (no cones) at whatever constant angle.
  const CrossField smooth = computeSmoothestField(s.mesh, s.topology);
  EXPECT_TRUE(computeSingularities(s.mesh, s.topology, smooth).cones.empty());
  // A flat component has no curvature target: it keeps its (parallel) smoothest field.
  const Surface two = makeSurface(testing::concatMeshes({testing::cylinderMesh(24, 8), testing::gridMesh(6, 5)}));
  const CrossField both = computeSmoothestField(two.mesh, two.topology, options);
  const FaceId gridStart = two.mesh.numFaces() - 60;
  for (FaceId f = 0; f < two.mesh.numFaces(); ++f) {
    ASSERT_TRUE(both.direction[f].allFinite());
    if (f > gridStart) {
      EXPECT_NEAR(std::cos(4 * std::acos(std::clamp(both.at(f).dot(both.at(gridStart)), -1.0, 1.0))), 1.0, 1e-6);
    }
  }
}

TEST(Field, SeveralComponentsEachGetAField) {
  const Surface s = makeSurface(testing::concatMeshes(
      {testing::icosphereMesh(2), testing::torusMesh(30, 12), testing::gridMesh(6, 5)}));
  const CrossField field = computeSmoothestField(s.mesh, s.topology);
  for (const Vec3f& d : field.direction) ASSERT_NEAR(d.norm(), 1.0, 1e-6);
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  EXPECT_EQ(sing.indexSum4(), 8);  // sphere 8, torus 0, disk: interior cones only
  // The flat grid's smoothest field is parallel: no cones and residuals ~0.
  const FaceId gridStart = s.mesh.numFaces() - 60;
  for (FaceId f = gridStart + 1; f < s.mesh.numFaces(); ++f) {
    EXPECT_NEAR(std::cos(4 * std::acos(std::clamp(field.at(f).dot(field.at(gridStart)), -1.0, 1.0))), 1.0, 1e-6);
  }
}

TEST(Field, ZeroAreaFacesGiveNoNaN) {
  TriangleMesh mesh = testing::torusMesh(20, 10);
  // Collapse one face onto a line (vertex on the midpoint of the opposite edge) and another to a
  // point pair (two coincident vertices).
  const Triangle a = mesh.triangles[10], b = mesh.triangles[101];
  mesh.positions[a[2]] = 0.5f * (mesh.positions[a[0]] + mesh.positions[a[1]]);
  mesh.positions[b[1]] = mesh.positions[b[0]];
  const Surface s = makeSurface(mesh);
  EXPECT_EQ(faceArea(s.mesh, 10), 0.0);
  for (const CrossField& field : {computeSmoothestField(s.mesh, s.topology), randomField(s.mesh, 3)}) {
    for (const Vec3f& d : field.direction) ASSERT_TRUE(d.allFinite());
    expectPoincareHopf(s, field, "degenerate torus");
  }
}

TEST(Field, ProjectToTangent) {
  const Surface s = makeSurface(testing::gridMesh(2, 1));
  const double nan = std::nan("");
  const CrossField f = projectToTangent(s.mesh, {Vec3d(3, 4, 5), Vec3d(0, 0, 2), Vec3d(nan, 0, 0), Vec3d(0, 0, 0)});
  EXPECT_NEAR((f.at(0) - Vec3d(0.6, 0.8, 0)).norm(), 0, 1e-7);  // stored in float
  for (FaceId x = 1; x < 4; ++x) {  // no tangent part: the first edge direction
    const Triangle& t = s.mesh.triangles[x];
    EXPECT_NEAR((f.at(x) - (s.mesh.position(t[1]) - s.mesh.position(t[0])).normalized()).norm(), 0, 1e-7);
  }
  EXPECT_THROW(projectToTangent(s.mesh, {Vec3d(1, 0, 0)}), InputError);
}

TEST(FieldIo, PlainRoundTripAndHeaderlessFiles) {
  testing::TempDir dir;
  const std::vector<Vec3d> v = {Vec3d(1, 0, 0), Vec3d(0.1, -0.25, 1e-7), Vec3d(0, 0, 0)};
  writeField(dir.path("a.field"), v);
  const std::vector<Vec3d> back = readFieldVectors(dir.path("a.field"), 3);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR((back[i] - v[i]).norm(), 0.0, 1e-9 * (1 + v[i].norm()));
  testing::writeFile(dir.path("b.field"), "# comment\n\n1 0 0\n0 1 0\r\n");
  EXPECT_EQ(readFieldVectors(dir.path("b.field"), 2)[1], Vec3d(0, 1, 0));
  // Signs, exponents and leading/trailing zeros as other tools write them.
  testing::writeFile(dir.path("c.field"), "+1.5 -0 2.5e-3\n-1E+2 .5 007\n");
  const std::vector<Vec3d> c = readFieldVectors(dir.path("c.field"), 2);
  EXPECT_EQ(c[0], Vec3d(1.5, 0.0, 2.5e-3));
  EXPECT_EQ(c[1], Vec3d(-100.0, 0.5, 7.0));
}

TEST(FieldIo, BadFilesNameFileAndLine) {
  testing::TempDir dir;
  const std::pair<const char*, const char*> cases[] = {
      {"1 3\n1 0 0\n0 1 0\n", ":3: file ends after 2"},
      {"1 2\n1 0 0\n0 1 0\n", ":1: header declares 2 faces"},
      {"1 0 0\n0 1 x\n0 0 1\n", ":2: 'x' is not a number"},
      {"1 0 0\n0 1 nan\n0 0 1\n", ":2: "},
      {"1 0 0\n0 1 1e999\n0 0 1\n", ":2: non-finite value '1e999'"},
      {"1 0 0\n0 +-1 0\n0 0 1\n", ":2: '+-1' is not a number"},
      {"1 0 0\n0 1.0.0 0\n0 0 1\n", ":2: '1.0.0' is not a number"},
      {"1 0 0\n0 1\n0 0 1\n", ":2: expected 3 numbers"},
      {"1 0 0\n0 1 0\n0 0 1\n1 1 1\n", ":4: more field lines"},
      {"2 3\n0 1 0 0 0 1 0\n0 1 0 0 0 1 0\n0 1 0 0 0 1\n", ":4: expected 7 values"},
      {"3 3\n", ":1: header"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string path = dir.path("bad.field");
    testing::writeFile(path, text);
    try {
      readFieldVectors(path, 3);
      ADD_FAILURE() << "no error for " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + expected), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(readFieldVectors(dir.path("missing.field"), 3), IoError);
}

TEST(FieldIo, ByteOrderMarkLineEndsTinyNumbersAndDevices) {
  testing::TempDir dir;
  for (const char* end : {"\n", "\r\n", "\r"}) {
    const std::string path = dir.path("e.field");
    testing::writeFile(path, std::string("\xEF\xBB\xBF# comment") + end + "1 2" + end + "1 0 1e-320" + end + "0 1 0" + end);
    const std::vector<Vec3d> v = readFieldVectors(path, 2);
    EXPECT_EQ(v[0], Vec3d(1, 0, 1e-320)) << "a denormal is a number";
    EXPECT_EQ(v[1], Vec3d(0, 1, 0));
  }
  const std::string zero = dir.path("zero.field");
  std::filesystem::create_symlink("/dev/zero", zero);
  try {
    readFieldVectors(zero, 3);
    ADD_FAILURE() << "/dev/zero was read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(zero + ": is a character device"), std::string::npos) << e.what();
  }
}

TEST(FieldIo, LiliumCrossfieldImport) {
  const std::string meshPath = testing::sharedMesh("lilium.obj");
  const std::string fieldPath = testing::sharedMesh("lilium.crossfield");
  if (meshPath.empty() || fieldPath.empty()) GTEST_SKIP() << testing::missingSharedMessage("lilium.*");
  const TriangleMesh mesh = readMesh(meshPath);
  const CrossField field = importField(fieldPath, mesh);
  ASSERT_EQ(field.direction.size(), mesh.numFaces());
  // Reference: parse both vectors of each face here and compare as crosses (4th powers).
  std::ifstream in(fieldPath);
  std::string header;
  std::getline(in, header);
  double worst = 0.0;
  int checked = 0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    int flag;
    Vec3d a, b;
    ASSERT_TRUE(in >> flag >> a.x() >> a.y() >> a.z() >> b.x() >> b.y() >> b.z());
    const Vec3d n = faceNormal(mesh, f);
    if (n.norm() == 0.0) continue;
    const Vec3d u = field.at(f);
    EXPECT_NEAR(u.norm(), 1.0, 1e-6);  // stored in float
    EXPECT_NEAR(u.dot(n), 0.0, 1e-6);
    // The cross of u contains the file's first vector (the second is a conjugate direction,
    // not always perpendicular in this file, and is not used).
    const Vec3d t = (a - a.dot(n) * n).normalized();
    const double angle = std::atan2(n.dot(u.cross(t)), u.dot(t));
    worst = std::max(worst, 1.0 - std::cos(4 * angle));
    ++checked;
  }
  EXPECT_GT(checked, 6500);
  EXPECT_LT(worst, 1e-9);
}

/// Count of `key` lines (e.g. "l ", "p ") in a text.
std::size_t countLines(const std::string& text, const std::string& key) {
  std::size_t n = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    if (text.compare(pos, key.size(), key) == 0) ++n;
    pos = text.find('\n', pos);
    if (pos == std::string::npos) break;
    ++pos;
  }
  return n;
}

/// The integer after "key": in a JSON document (-1 when absent).
long jsonInteger(const std::string& json, const std::string& key) {
  const std::size_t pos = json.find("\"" + key + "\": ");
  return pos == std::string::npos ? -1 : std::stol(json.substr(pos + key.size() + 4));
}

/// Writes a generated mesh of the given kind and size to path.
void writeGenerated(const std::string& path, MeshKind kind, std::uint64_t faces) {
  GenerateOptions options;
  options.kind = kind;
  options.faces = faces;
  writeMesh(path, generateMesh(options).mesh);
}

TEST(FieldCommand, WritesFieldConesSeamsAndReimportsTheSameField) {
  testing::TempDir dir;
  writeGenerated(dir.path("t.obj"), MeshKind::Torus, 3000);
  std::string out;
  ASSERT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("t.field") + " --cones " +
                                    dir.path("cones.obj") + " --seams " + dir.path("seams.obj") + " --json",
                                &out),
            0)
      << out;
  const long cones = jsonInteger(out, "cones"), seams = jsonInteger(out, "seams");
  EXPECT_EQ(jsonInteger(out, "indexSum4"), 0) << out;  // torus: chi = 0
  EXPECT_GT(jsonInteger(out, "peakResidentBytes"), 0) << out;
  EXPECT_EQ(long(countLines(testing::readFile(dir.path("cones.obj")), "p ")), cones);
  EXPECT_EQ(long(countLines(testing::readFile(dir.path("seams.obj")), "l ")), seams);
  EXPECT_EQ(countLines(testing::readFile(dir.path("t.field")), "1 "), 1u);  // the header
  // Importing the written field gives the same cones and seams.
  std::string again;
  ASSERT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("u.field") + " --import " +
                                    dir.path("t.field") + " --json",
                                &again),
            0)
      << again;
  EXPECT_EQ(jsonInteger(again, "cones"), cones);
  EXPECT_EQ(jsonInteger(again, "seams"), seams);
  // Bad input: exit code 1 and a message naming the file.
  testing::writeFile(dir.path("bad.field"), "1 5\n");
  EXPECT_EQ(testing::runSeamvox("field " + dir.path("t.obj") + " -o " + dir.path("v.field") + " --import " +
                                    dir.path("bad.field"),
                                &out),
            1);
  EXPECT_NE(out.find(dir.path("bad.field") + ":1:"), std::string::npos) << out;
  EXPECT_EQ(testing::runSeamvox("field " + dir.path("t.obj"), &out), 2) << out;  // no -o
}

TEST(FieldCommand, ShowsTheConesParamCutsThrough) {
  // Cones closer than --merge-cones F * h are merged by field as by param, so the cones shown are
  // the ones the map has (on a generated scan with a coarse grid: equal cones a few edges apart).
  testing::TempDir dir;
  writeGenerated(dir.path("s.ply"), MeshKind::Scan, 20000);
  const std::string common = "field " + dir.path("s.ply") + " -o " + dir.path("s.field") + " --json --quiet --cells 20";
  std::string all, merged;
  ASSERT_EQ(testing::runSeamvox(common + " --merge-cones 0", &all), 0) << all;
  ASSERT_EQ(testing::runSeamvox(common + " --cones " + dir.path("cones.obj"), &merged), 0) << merged;
  const long before = jsonInteger(all, "cones");
  EXPECT_EQ(jsonInteger(all, "conesBeforeMerge"), before);
  EXPECT_EQ(jsonInteger(merged, "conesBeforeMerge"), before);
  const long cancelled = jsonInteger(merged, "conesCancelled"), moved = jsonInteger(merged, "conesMerged");
  ASSERT_GT(cancelled + moved, 0) << "the case no longer exercises close cones\n" << merged;
  const long cones = jsonInteger(merged, "cones");
  EXPECT_EQ(cones, before - cancelled - moved);
  EXPECT_EQ(jsonInteger(merged, "indexSum4"), jsonInteger(all, "indexSum4"));  // Poincare-Hopf kept
  EXPECT_EQ(long(countLines(testing::readFile(dir.path("cones.obj")), "p ")), cones);
  // param with the same spacing cuts through the same cones (one pass: no coincident pair left).
  std::string out;
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("s.ply") + " -o " + dir.path("o.ply") +
                                    " --quiet --solver hat --cells 20 --report " + dir.path("r.json"),
                                &out),
            0)
      << out;
  const std::string report = testing::readFile(dir.path("r.json"));
  if (jsonInteger(report, "conePasses") == 1) EXPECT_EQ(jsonInteger(report, "cones"), cones) << report;
  EXPECT_EQ(testing::runSeamvox(common + " --merge-cones -1", &out), 2) << out;
  EXPECT_EQ(testing::runSeamvox(common + " --edge-length 1", &out), 2) << out;  // with --cells
}

// --field-smoothing N sets the steps of the surface the field and its cones are read on, in field
// and in param alike: on a closed genus-2 surface jittered by half an edge each number of steps
// gives its own field (Poincare-Hopf held), param reads the same cones as field with the same
// steps, both reports say the steps; a value out of range or one given with an imported field is
// refused and writes nothing.
TEST(FieldCommand, FieldSmoothingStepsReachFieldAndParam) {
  testing::TempDir dir;
  std::string out;
  ASSERT_EQ(testing::runSeamvox("gen genus2 --faces 20000 --noise 0.5 --seed 3 -o " + dir.path("s.ply") + " --quiet", &out), 0)
      << out;
  const std::string common = "field " + dir.path("s.ply") + " --json --quiet --merge-cones 0";
  std::string one, smoothed, more;
  ASSERT_EQ(testing::runSeamvox(common + " -o " + dir.path("1.field") + " --field-smoothing 1", &one), 0) << one;
  ASSERT_EQ(testing::runSeamvox(common + " -o " + dir.path("s.field"), &smoothed), 0) << smoothed;
  ASSERT_EQ(testing::runSeamvox(common + " -o " + dir.path("8.field") + " --field-smoothing 8", &more), 0) << more;
  EXPECT_EQ(jsonInteger(one, "fieldSmoothing"), 1);
  EXPECT_EQ(jsonInteger(smoothed, "fieldSmoothing"), 3);
  EXPECT_EQ(jsonInteger(more, "fieldSmoothing"), 8);
  EXPECT_NE(testing::readFile(dir.path("1.field")), testing::readFile(dir.path("s.field")));
  EXPECT_NE(testing::readFile(dir.path("8.field")), testing::readFile(dir.path("s.field")));
  for (const std::string* json : {&one, &smoothed, &more}) {
    EXPECT_EQ(jsonInteger(*json, "indexSum4"), 4 * jsonInteger(*json, "eulerCharacteristic")) << *json;
  }
  // param with the same steps reads the same cones off the same surface.
  for (const auto& [steps, json] : {std::pair<const char*, const std::string*>{"1", &one}, {"8", &more}}) {
    ASSERT_EQ(testing::runSeamvox("param " + dir.path("s.ply") + " -o " + dir.path("o.ply") + " --quiet --merge-cones 0 " +
                                      "--solver hat --field-smoothing " + steps + " --report " + dir.path("r.json"),
                                  &out),
              0)
        << out;
    const std::string report = testing::readFile(dir.path("r.json"));
    EXPECT_EQ(jsonInteger(report, "fieldSmoothing"), std::stol(steps));
    EXPECT_EQ(jsonInteger(report, "conesBeforeMerge"), jsonInteger(*json, "conesBeforeMerge")) << steps;
  }
  std::filesystem::remove(dir.path("o.ply"));
  for (const std::string& bad : std::vector<std::string>{" --field-smoothing 0", " --field-smoothing 65", " --field-smoothing x",
                                " --field-smoothing 3 --field " + dir.path("s.field")}) {
    EXPECT_EQ(testing::runSeamvox("param " + dir.path("s.ply") + " -o " + dir.path("o.ply") + " --quiet" + bad, &out), 2)
        << bad << "\n" << out;
    EXPECT_NE(out.find("--field-smoothing"), std::string::npos) << out;
    EXPECT_FALSE(std::filesystem::exists(dir.path("o.ply"))) << bad;
  }
  EXPECT_EQ(testing::runSeamvox("field " + dir.path("s.ply") + " -o " + dir.path("t.field") + " --import " +
                                    dir.path("s.field") + " --field-smoothing 2",
                                &out),
            2)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path("t.field")));
}

/// The JSON boolean after "key": (false when absent).
bool jsonTrue(const std::string& json, const std::string& key) {
  return json.find("\"" + key + "\": true") != std::string::npos;
}

// The rough spots of the field's surface are smoothed within h by default, in field and in param
// (in memory and out of core) alike: a plane whose finely tessellated centre is crumpled by noise
// (1/32 of h across) has many cones read off it as it is and a few once smoothed; each command
// and path reports the same rough vertices and reads the same cones, and --no-rough-spots moves
// none.
TEST(FieldCommand, RoughSpotsSmoothedByDefaultInFieldAndParam) {
  testing::TempDir dir;
  writeMesh(dir.path("p.ply"), testing::denseSpotPlane(12, 2, 16, 0.3, 1));
  const std::string field = "field " + dir.path("p.ply") + " -o " + dir.path("p.field") +
                            " --json --quiet --merge-cones 0 --edge-length 2";
  std::string smoothed, plain, out;
  ASSERT_EQ(testing::runSeamvox(field, &smoothed), 0) << smoothed;
  ASSERT_EQ(testing::runSeamvox(field + " --no-rough-spots", &plain), 0) << plain;
  EXPECT_TRUE(jsonTrue(smoothed, "roughSpots")) << smoothed;
  EXPECT_FALSE(jsonTrue(plain, "roughSpots")) << plain;
  EXPECT_GT(jsonInteger(smoothed, "roughVertices"), 100) << smoothed;
  EXPECT_GT(jsonInteger(smoothed, "roughSpotVertices"), jsonInteger(smoothed, "roughVertices"));
  EXPECT_EQ(jsonInteger(plain, "roughVertices"), 0) << plain;
  EXPECT_EQ(jsonInteger(plain, "roughSpotVertices"), 0) << plain;
  const long cones = jsonInteger(smoothed, "cones"), noisyCones = jsonInteger(plain, "cones");
  EXPECT_GE(noisyCones, 20) << plain;
  EXPECT_LE(5 * cones, noisyCones) << smoothed;
  // param reads the same cones off the same surface in memory (hat and voxloc); out of core (the
  // proxy field, faces in another order) it smooths the same vertices, and has fewer cones for it.
  long outOfCoreCones[2] = {0, 0};
  for (const std::string options : {"--solver hat", "--solver voxloc", "--out-of-core", "--solver hat --no-rough-spots",
                                    "--out-of-core --no-rough-spots"}) {
    const bool rough = options.find("--no-rough-spots") == std::string::npos;
    ASSERT_EQ(testing::runSeamvox("param " + dir.path("p.ply") + " -o " + dir.path("o.ply") + " --quiet --merge-cones 0 " +
                                      "--edge-length 2 " + options + " --report " + dir.path("r.json"),
                                  &out),
              0)
        << options << "\n" << out;
    const std::string report = testing::readFile(dir.path("r.json"));
    const std::string& json = rough ? smoothed : plain;
    EXPECT_EQ(jsonTrue(report, "roughSpots"), rough) << options;
    EXPECT_EQ(jsonInteger(report, "roughVertices"), jsonInteger(json, "roughVertices")) << options;
    EXPECT_EQ(jsonInteger(report, "roughSpotVertices"), jsonInteger(json, "roughSpotVertices")) << options;
    if (options.find("--out-of-core") == std::string::npos) {
      EXPECT_EQ(jsonInteger(report, "conesBeforeMerge"), rough ? cones : noisyCones) << options;
    } else {
      outOfCoreCones[rough] = jsonInteger(report, "conesBeforeMerge");
    }
    EXPECT_TRUE(jsonTrue(report, "seamless")) << options << "\n" << report;
  }
  EXPECT_LT(outOfCoreCones[1], outOfCoreCones[0]);
}

}  // namespace
}  // namespace seamvox
