// The hat-basis seamless solver: exactness on developable meshes with hand-built cuts, and
// seamlessness of the whole pipeline (field, cut, reduce, solve, round) on test meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <sstream>

#include <Eigen/Dense>

#include "core/basis/basis.h"
#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/synth/generate.h"
#include "core/quality/metrics.h"
#include "core/solve/hat_solver.h"
#include "core/basis/reduce.h"
#include "core/mesh/topology.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

using testing::boundaryCut;
using testing::constantField;

// Cylinder of testing::cylinderMesh(n, m) cut along the generator through vertices j * n
// (vertex index 0 mod n): one seam with matching 0 from the bottom to the top boundary.
CutResult cylinderCut(const Topology& topology, int n, int m) {
  CutResult cut = boundaryCut(topology);
  SeamCurve seam;
  std::vector<std::pair<VertexId, CornerId>> upward;  // (lower vertex, left corner)
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const VertexId a = topology.vertex(nextCorner(c)), b = topology.vertex(prevCorner(c));
    if (topology.isBoundaryEdge(c) || a % n != 0 || b % n != 0 || b < a) continue;
    upward.emplace_back(a, c);
  }
  std::sort(upward.begin(), upward.end());
  EXPECT_EQ(upward.size(), static_cast<std::size_t>(m));
  for (const auto& [v, c] : upward) {
    seam.corners.push_back(c);
    for (CornerId side : {c, topology.opposite(c)}) cut.corners.setCut(side, true);
  }
  seam.start = upward.front().first;
  seam.end = static_cast<VertexId>(m * n);
  seam.matching = 0;
  cut.seams.push_back(seam);
  return cut;
}

// Perimeter of the bottom ring of cylinderMesh(n, ...) (float positions): the exact period of
// the cylinder's development.
double ringPerimeter(const TriangleMesh& mesh, int n) {
  double length = 0.0;
  for (int i = 0; i < n; ++i) length += (mesh.position((i + 1) % n) - mesh.position(i)).norm();
  return length;
}

Complex uvAt(const ParamResult& result, CornerId c) {
  const Vec2d q = result.cornerUV[c];
  return {q.x(), q.y()};
}

TEST(HatBasis, WedgesAndIntegrals) {
  const TriangleMesh mesh = testing::cylinderMesh(6, 3);
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  const CutResult cut = cylinderCut(topology, 6, 3);
  const CrossField field = constantField(mesh, Vec3d(0, 0, 1));
  const HatBasis basis(mesh, topology, field, cut, {});
  EXPECT_EQ(basis.numBasisFunctions(), mesh.numVertices());
  EXPECT_EQ(basis.numDomains(), mesh.numVertices() + 4u);  // 4 seam vertices have two wedges
  EXPECT_EQ(basis.adjacencies().size(), 4u);
  ElementIntegrals el;
  for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
    basis.elementIntegrals(e, el);
    ASSERT_EQ(el.count, 3u);
    Complex rhsSum = 0.0;
    for (int a = 0; a < 3; ++a) {
      double rowSum = 0.0;
      for (int b = 0; b < 3; ++b) {
        rowSum += el.stiffness[3 * a + b];
        EXPECT_DOUBLE_EQ(el.stiffness[3 * a + b], el.stiffness[3 * b + a]);
      }
      EXPECT_NEAR(rowSum, 0.0, 1e-12);  // constants are in the kernel
      rhsSum += el.rhs[a];
    }
    EXPECT_NEAR(std::abs(rhsSum), 0.0, 1e-12);
  }
}

TEST(HatBasis, DegenerateTriangleGivesBoundedIntegrals) {
  double L[9];
  Complex b[3];
  // Zero area: all zero. Needle: finite and bounded by the cotangent clamp.
  hatTriangleIntegrals(Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(2, 0, 0), Vec3d(1, 0, 0), 1.0, L, b);
  for (double x : L) EXPECT_EQ(x, 0.0);
  hatTriangleIntegrals(Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0.5, 1e-13, 0), Vec3d(1, 0, 0), 1.0, L, b);
  for (double x : L) {
    EXPECT_TRUE(std::isfinite(x));
    EXPECT_LE(std::abs(x), kMaxCotangent);
  }
  for (const Complex& x : b) EXPECT_TRUE(std::isfinite(std::abs(x)));
}

TEST(HatSolver, FlatSquareWithConstantFieldIsExactlyLinear) {
  const TriangleMesh mesh = testing::gridMesh(8, 8, 1.0);
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  const double angle = 0.3, h = 0.5;
  const CrossField field = constantField(mesh, Vec3d(std::cos(angle), std::sin(angle), 0.0));
  // The map follows the stored (float) direction exactly.
  const Vec3d u = field.at(0), v = Vec3d::UnitZ().cross(u);
  const CutResult cut = boundaryCut(topology);
  ParamOptions options;
  options.edgeLength = h;
  const ParamResult result = parameterizeMesh(mesh, topology, field, cut, options);
  const Complex q0 = uvAt(result, 0);
  const Vec3d p0 = mesh.position(mesh.triangles[0][0]);
  for (CornerId c = 0; c < 3 * mesh.numFaces(); ++c) {
    const Vec3d d = mesh.position(mesh.triangles[c / 3][c % 3]) - p0;
    EXPECT_LT(std::abs(uvAt(result, c) - q0 - Complex(d.dot(u), d.dot(v)) / h), 1e-9);
  }
  const MapQuality quality = measureMap(mesh, result.cornerUV, &field, h);
  EXPECT_LT(quality.relativeGradientError, 1e-7);  // measureMap normalizes u; |u| is 1 to float precision
  EXPECT_EQ(quality.flipped, 0u);
  EXPECT_EQ(result.stats.pinnedFirst, 1u);
  EXPECT_EQ(result.stats.translational, 0u);
}

// A 12 x 5 cylinder cut along one generator, with the field along its axis.
class HatCylinder : public ::testing::Test {
 protected:
  const int n = 12, m = 5;
  const TriangleMesh mesh = testing::cylinderMesh(n, m, 1.0, 2.0);
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  const CutResult cut = cylinderCut(topology, n, m);
  const CrossField field = constantField(mesh, Vec3d(0, 0, 1));
  const double circumference = ringPerimeter(mesh, n);
};

TEST_F(HatCylinder, AxisFieldGivesExactMapWithIntegerPeriod) {
  const int period = 8;
  ParamOptions options;
  options.edgeLength = circumference / period;
  const ParamResult result = parameterizeMesh(mesh, topology, field, cut, options);
  ASSERT_EQ(result.translations.size(), 1u);
  EXPECT_NEAR(std::abs(result.translations[0]), period, 1e-12);
  EXPECT_LT(gaussianIntegerDistance(result.translations[0]), 1e-12);
  const SeamQuality seams = measureSeams(mesh, topology, cut, result.cornerUV);
  EXPECT_LT(seams.maxResidual, 1e-9);
  EXPECT_LT(seams.maxIntegerDistance, 1e-9);
  EXPECT_EQ(seams.seamEdges, static_cast<std::uint64_t>(m));
  const MapQuality quality = measureMap(mesh, result.cornerUV, &field, options.edgeLength);
  EXPECT_LT(quality.relativeGradientError, 1e-9);
  EXPECT_EQ(quality.flipped, 0u);
  // r = 1 everywhere: the shift stays pinned in the second solve too.
  EXPECT_EQ(result.stats.pinnedSecond, 1u);
}

TEST_F(HatCylinder, OffPeriodRoundsToNearestInteger) {
  ParamOptions options;
  options.edgeLength = circumference / 7.3;  // continuous period 7.3 -> rounded to 7
  const ParamResult result = parameterizeMesh(mesh, topology, field, cut, options);
  EXPECT_NEAR(std::abs(result.translations[0]), 7.0, 1e-12);
  const SeamQuality seams = measureSeams(mesh, topology, cut, result.cornerUV);
  EXPECT_TRUE(seams.isSeamless(1e-9));
  const MapQuality quality = measureMap(mesh, result.cornerUV, &field, options.edgeLength);
  EXPECT_GT(quality.relativeGradientError, 1e-3);  // the map had to stretch to close up
  EXPECT_LT(quality.relativeGradientError, 0.1);
}

TEST(HatSolver, SeveralComponentsEachPinned) {
  const TriangleMesh a = testing::gridMesh(4, 4, 1.0);
  const TriangleMesh b = testing::cylinderMesh(12, 5, 1.0, 2.0);
  const TriangleMesh mesh = testing::concatMeshes({a, b});
  const Topology topology = Topology::build(mesh.triangles, mesh.numVertices());
  // Cylinder part: its vertices are offset by the grid's 25 vertices; cut along i = 0 there.
  CutResult cut = boundaryCut(topology);
  {
    const Topology tb = Topology::build(b.triangles, b.numVertices());
    const CutResult cb = cylinderCut(tb, 12, 5);
    SeamCurve seam = cb.seams[0];
    const CornerId offset = 3 * a.numFaces();
    for (CornerId& c : seam.corners) {
      c += offset;
      for (CornerId side : {c, topology.opposite(c)}) cut.corners.setCut(side, true);
    }
    cut.seams.push_back(seam);
  }
  const double circumference = ringPerimeter(b, 12);
  const CrossField field = constantField(mesh, Vec3d(0, 0, 1));  // tangent on the cylinder only
  CrossField mixed = field;
  for (FaceId f = 0; f < a.numFaces(); ++f) mixed.direction[f] = Vec3f(1, 0, 0);
  ParamOptions options;
  options.edgeLength = circumference / 6;
  const ParamResult result = parameterizeMesh(mesh, topology, mixed, cut, options);
  EXPECT_EQ(result.stats.components, 2u);
  EXPECT_EQ(result.stats.pinnedFirst, 2u);
  EXPECT_EQ(result.stats.pinnedSecond, 2u);
  EXPECT_LT(measureMap(mesh, result.cornerUV, &mixed, options.edgeLength).relativeGradientError, 1e-9);
  EXPECT_TRUE(measureSeams(mesh, topology, cut, result.cornerUV).isSeamless(1e-9));
}

// --- the whole pipeline on test meshes ------------------------------------------------------------

struct PipelineFigures {
  SeamQuality seams, rebuilt;
  MapQuality map;
  std::size_t cones = 0;
};

PipelineFigures runPipeline(TriangleMesh input, const std::string& fieldPath = "") {
  CleanResult clean = cleanMesh(std::move(input));
  const TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  const CrossField field = fieldPath.empty() ? computeSmoothestField(mesh, topology)
                                             : importField(fieldPath, mesh);
  const FieldSingularities singularities = computeSingularities(mesh, topology, field);
  const CutResult cut = cutToDisk(mesh, topology, field, singularities);
  ParamOptions options;
  options.edgeLength = computeBoundingBox(mesh.positions).diagonal() / 40.0;
  const ParamResult result = parameterizeMesh(mesh, topology, field, cut, options);
  PipelineFigures out;
  out.seams = measureSeams(mesh, topology, cut, result.cornerUV);
  out.rebuilt = measureSeamsFromUV(mesh, topology, result.cornerUV);
  out.map = measureMap(mesh, result.cornerUV, &field, options.edgeLength);
  out.cones = cut.cones.size();
  for (const Complex& t : result.translations) EXPECT_LT(gaussianIntegerDistance(t), 1e-9);
  return out;
}

void expectSeamless(const PipelineFigures& f, const std::string& name) {
  EXPECT_LT(f.seams.maxResidual, 1e-6) << name;
  EXPECT_LT(f.seams.maxIntegerDistance, 1e-6) << name;
  EXPECT_LT(f.rebuilt.maxResidual, 1e-6) << name;
  EXPECT_LT(f.rebuilt.maxIntegerDistance, 1e-6) << name;
  EXPECT_TRUE(std::isfinite(f.map.relativeGradientError)) << name;
  EXPECT_LT(f.map.relativeGradientError, 1.0) << name;
}

class SharedMeshSeamless : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedMeshSeamless, IsSeamless) {
  const std::string name = GetParam();
  const std::string path = testing::sharedMesh(name);
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage(name);
  std::string fieldPath;
  if (name == "lilium.obj") {
    fieldPath = testing::sharedMesh("lilium.crossfield");
    if (fieldPath.empty()) GTEST_SKIP() << testing::missingSharedMessage("lilium.crossfield");
  }
  const PipelineFigures f = runPipeline(readMesh(path), fieldPath);
  expectSeamless(f, name);
  if (name != "lilium.obj") EXPECT_GT(f.cones, 0u) << name;
}

INSTANTIATE_TEST_SUITE_P(Meshes, SharedMeshSeamless,
                         ::testing::Values("fertility.off", "3holes.off", "bunny.off",
                                           "camelhead.off", "lilium.obj", "rocker-arm.obj"),
                         [](const auto& info) {
                           std::string s = info.param;
                           s = s.substr(0, s.find('.'));
                           s.erase(std::remove(s.begin(), s.end(), '-'), s.end());
                           return s;
                         });

TEST(HatPipeline, GeneratedMeshesAreSeamless) {
  for (MeshKind kind : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    GenerateOptions options;
    options.kind = kind;
    options.faces = std::max<std::uint64_t>(6000, minimumFaces(kind));
    expectSeamless(runPipeline(generateMesh(options).mesh), meshKindName(kind));
  }
}

TEST(HatPipeline, SeveralComponentsAreSeamless) {
  const TriangleMesh mesh = testing::concatMeshes(
      {testing::torusMesh(40, 16), testing::icosphereMesh(3), testing::gridMesh(6, 6, 0.2)});
  expectSeamless(runPipeline(mesh), "torus+sphere+square");
}

TEST(HatCommand, ParamThenCheck) {
  const std::string bunny = testing::sharedMesh("bunny.off");
  if (bunny.empty()) GTEST_SKIP() << testing::missingSharedMessage("bunny.off");
  testing::TempDir dir;
  std::string log;
  ASSERT_EQ(testing::runSeamvox("param '" + bunny + "' -o '" + dir.path("uv.obj") + "' --solver hat --cells 60 --report '" +
                                    dir.path("r.json") + "' --quiet",
                                &log),
            0)
      << log;
  const std::string report = testing::readFile(dir.path("r.json"));
  for (const char* key : {"\"seamless\": true", "\"relativeGradientError\"", "\"factorBytes\"",
                          "\"peakResidentBytes\"", "\"secondSolve\""}) {
    EXPECT_NE(report.find(key), std::string::npos) << key << " missing in " << report;
  }
  // One record per stage, in pipeline order.
  std::size_t at = report.find("\"stages\"");
  ASSERT_NE(at, std::string::npos) << report;
  for (const char* stage : {"read", "clean", "field", "cut", "solve", "metrics", "write"}) {
    at = report.find("\"name\": \"" + std::string(stage) + "\"", at);
    ASSERT_NE(at, std::string::npos) << "stage " << stage << " missing or out of order in " << report;
  }
  EXPECT_NE(report.find("\"peakBytes\"", report.find("\"stages\"")), std::string::npos) << report;
  EXPECT_EQ(testing::runSeamvox("check '" + dir.path("uv.obj") + "' --json", &log), 0) << log;
  EXPECT_NE(log.find("\"seamless\": true"), std::string::npos) << log;
  // Shifting every u by 1/2 keeps r = 1 seams but makes t non-integer across r != 1 seams.
  std::istringstream in(testing::readFile(dir.path("uv.obj")));
  std::string line, shifted;
  while (std::getline(in, line)) {
    if (line.rfind("vt ", 0) == 0) {
      double u = 0, v = 0;
      std::istringstream(line.substr(3)) >> u >> v;
      char buffer[96];
      std::snprintf(buffer, sizeof buffer, "vt %.17g %.17g", u + 0.5, v);
      line = buffer;
    }
    shifted += line + "\n";
  }
  testing::writeFile(dir.path("bad.obj"), shifted);
  EXPECT_EQ(testing::runSeamvox("check '" + dir.path("bad.obj") + "'", &log), 5) << log;
  EXPECT_NE(log.find("NOT seamless"), std::string::npos) << log;
  EXPECT_EQ(testing::runSeamvox("param '" + bunny + "' -o x.off", &log), 2) << log;
}

}  // namespace
}  // namespace seamvox

namespace seamvox {
namespace {

/// Rank over the reals of constraint rows on numSeams translations (each seam: real, imag).
Eigen::Index constraintRank(const std::vector<const std::vector<GaussVector>*>& sets,
                            std::uint32_t numSeams) {
  std::size_t rows = 0;
  for (const auto* set : sets) rows += set->size();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(rows), 2 * numSeams);
  Eigen::Index row = 0;
  for (const auto* set : sets) {
    for (const GaussVector& constraint : *set) {
      // (x + iy)(s + i t) = (xs - yt) + i(xt + ys): two real rows over (s, t) per seam.
      for (const auto& [seam, q] : constraint) {
        a(row, 2 * seam) += double(q.re), a(row, 2 * seam + 1) -= double(q.im);
        a(row + 1, 2 * seam) += double(q.im), a(row + 1, 2 * seam + 1) += double(q.re);
      }
      row += 2;
    }
  }
  return rows == 0 ? 0 : Eigen::FullPivLU<Eigen::MatrixXd>(a).rank();
}

void expectSameConstraints(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                           const char* what) {
  const CutResult cut = cutToDisk(mesh, topology, field, computeSingularities(mesh, topology, field));
  HatBasisOptions options;
  options.edgeLength = 0.1;
  const std::vector<GaussVector> whole = reduceBasis(HatBasis(mesh, topology, field, cut, options)).cycleConstraints;
  const std::vector<GaussVector> local = seamCycleConstraints(mesh, topology, field, cut, 0.1);
  const auto n = static_cast<std::uint32_t>(cut.seams.size());
  const Eigen::Index rankWhole = constraintRank({&whole}, n), rankLocal = constraintRank({&local}, n);
  EXPECT_GT(rankWhole, 0) << what << ": no constraint to compare";
  EXPECT_EQ(rankLocal, rankWhole) << what;
  EXPECT_EQ(constraintRank({&whole, &local}, n), rankWhole) << what << ": the spans differ";
}

TEST(HatReduction, SeamCycleConstraintsSpanTheWholeMeshConstraints) {
  {
    const testing::Surface s = testing::makeSurface(testing::torusMesh(40, 20));
    expectSameConstraints(s.mesh, s.topology, testing::randomField(s.mesh, 3), "torus, random field");
  }
  {
    TriangleMesh bumpy = testing::icosphereMesh(3);
    for (Vec3f& p : bumpy.positions) p *= 1.0f + 0.2f * std::sin(3.0f * p.x()) * std::cos(2.0f * p.y());
    const testing::Surface s = testing::makeSurface(std::move(bumpy));
    expectSameConstraints(s.mesh, s.topology, computeSmoothestField(s.mesh, s.topology), "bumpy sphere");
  }
  {
    const testing::Surface s = testing::makeSurface(
        testing::concatMeshes({testing::gridMesh(30, 30), testing::torusMesh(30, 16)}));
    expectSameConstraints(s.mesh, s.topology, testing::randomField(s.mesh, 5), "square and torus");
  }
}

}  // namespace
}  // namespace seamvox
