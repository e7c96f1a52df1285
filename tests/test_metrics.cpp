// Quality figures: seam residuals (from a cut and reconstructed from UVs), flips, collapses and
// the relative gradient error.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "core/system/errors.h"
#include "core/basis/gaussian_int.h"
#include "core/quality/metrics.h"
#include "core/mesh/topology.h"
#include "tests/test_meshes.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

struct SplitGrid {
  TriangleMesh mesh;
  Topology topology;
  CutResult cut;  // seam along x = n/2, left side = faces with x < n/2
};

// An n x n grid cut along its middle column line; q = position (x + i y) / h on the left half
// and r q + t on the right half.
SplitGrid splitGrid(int n, Complex r, Complex t, std::uint8_t matching) {
  SplitGrid g;
  g.mesh = testing::gridMesh(n, n, 1.0);
  g.topology = Topology::build(g.mesh.triangles, g.mesh.numVertices());
  const double middle = n / 2;
  auto faceCenterX = [&](FaceId f) {
    double x = 0;
    for (VertexId v : g.mesh.triangles[f]) x += g.mesh.positions[v].x();
    return x / 3;
  };
  g.cut.corners = CutCorners(g.topology.numCorners(), false);
  g.cut.faceRotation = FaceRotations(g.topology.numFaces());
  SeamCurve seam;
  seam.matching = matching;
  for (CornerId c = 0; c < g.topology.numCorners(); ++c) {
    const CornerId o = g.topology.opposite(c);
    if (o == kInvalidId) {
      g.cut.corners.setCut(c, true);
      continue;
    }
    const bool leftHere = faceCenterX(c / 3) < middle, leftThere = faceCenterX(o / 3) < middle;
    if (leftHere && !leftThere) seam.corners.push_back(c);
    if (leftHere != leftThere) g.cut.corners.setCut(c, true);
  }
  g.cut.seams.push_back(seam);
  std::vector<Vec2d> values(g.topology.numCorners());
  for (CornerId c = 0; c < g.topology.numCorners(); ++c) {
    const Vec3f& p = g.mesh.positions[g.topology.vertex(c)];
    Complex q(p.x(), p.y());
    if (faceCenterX(c / 3) > middle) q = r * q + t;
    values[c] = Vec2d(q.real(), q.imag());
  }
  g.mesh.cornerUV = WedgeMap::fromCorners(g.mesh.triangles, values);
  return g;
}

TEST(SeamMetrics, ExactSeamHasZeroResidual) {
  // r = i = i^(-3): matching 3.
  const SplitGrid g = splitGrid(6, Complex(0, 1), Complex(3, -2), 3);
  const SeamQuality fromCut = measureSeams(g.mesh, g.topology, g.cut, g.mesh.cornerUV);
  EXPECT_EQ(fromCut.seamEdges, 6u);
  EXPECT_LT(fromCut.maxResidual, 1e-12);
  EXPECT_LT(fromCut.maxIntegerDistance, 1e-12);
  EXPECT_TRUE(fromCut.isSeamless());
  const SeamQuality rebuilt = measureSeamsFromUV(g.mesh, g.topology, g.mesh.cornerUV);
  EXPECT_EQ(rebuilt.seamEdges, 6u);
  EXPECT_LT(rebuilt.maxResidual, 1e-12);
  EXPECT_LT(rebuilt.maxIntegerDistance, 1e-12);
  EXPECT_NEAR(rebuilt.seamLength, 6.0, 1e-12);
}

TEST(SeamMetrics, FractionalTranslationIsNotSeamless) {
  const SplitGrid g = splitGrid(6, Complex(-1, 0), Complex(2.5, 0.25), 2);
  const SeamQuality fromCut = measureSeams(g.mesh, g.topology, g.cut, g.mesh.cornerUV);
  EXPECT_NEAR(fromCut.maxIntegerDistance, std::hypot(0.5, 0.25), 1e-12);
  EXPECT_LT(fromCut.maxResidual, 1e-12);
  const SeamQuality rebuilt = measureSeamsFromUV(g.mesh, g.topology, g.mesh.cornerUV);
  EXPECT_NEAR(rebuilt.maxIntegerDistance, std::hypot(0.5, 0.25), 1e-12);
  EXPECT_FALSE(rebuilt.isSeamless());
}

TEST(SeamMetrics, PerturbedCornerShowsAsResidual) {
  SplitGrid g = splitGrid(6, Complex(0, -1), Complex(1, 1), 1);
  const CornerId c = g.cut.seams[0].corners[2];
  const CornerId moved = g.topology.opposite(c);  // a right-side corner on the seam
  const CornerId corner = nextCorner(moved);
  g.mesh.cornerUV.set(corner, g.mesh.cornerUV[corner] + Vec2d(0.0, 1e-3));
  const SeamQuality fromCut = measureSeams(g.mesh, g.topology, g.cut, g.mesh.cornerUV);
  EXPECT_NEAR(fromCut.maxResidual, 1e-3, 1e-9);
  EXPECT_FALSE(fromCut.isSeamless());
  const SeamQuality rebuilt = measureSeamsFromUV(g.mesh, g.topology, g.mesh.cornerUV);
  EXPECT_GT(rebuilt.maxResidual + rebuilt.maxIntegerDistance, 5e-4);
  EXPECT_FALSE(rebuilt.isSeamless());
}

TEST(SeamMetrics, ContinuousMapHasNoSeamEdges) {
  SplitGrid g = splitGrid(4, Complex(1, 0), Complex(0, 0), 0);
  EXPECT_EQ(measureSeamsFromUV(g.mesh, g.topology, g.mesh.cornerUV).seamEdges, 0u);
  const WedgeMap wrongSize({0, 0, 0}, {Vec2d::Zero()});
  EXPECT_THROW(measureSeamsFromUV(g.mesh, g.topology, wrongSize), InputError);
}

/// Per-corner values of mesh as a map.
WedgeMap wedges(const TriangleMesh& mesh, const std::vector<Vec2d>& uv) {
  return WedgeMap::fromCorners(mesh.triangles, uv);
}

std::vector<Vec2d> linearUV(const TriangleMesh& mesh, Complex scale) {
  std::vector<Vec2d> uv(3 * mesh.numFaces());
  for (CornerId c = 0; c < uv.size(); ++c) {
    const Vec3f& p = mesh.positions[mesh.triangles[c / 3][c % 3]];
    const Complex q = scale * Complex(p.x(), p.y());
    uv[c] = Vec2d(q.real(), q.imag());
  }
  return uv;
}

TEST(MapMetrics, GradientErrorFlipsAndCollapses) {
  const TriangleMesh mesh = testing::gridMesh(5, 5, 0.5);
  CrossField field;
  field.direction.assign(mesh.numFaces(), Vec3f(1, 0, 0));
  const double h = 0.25;
  // q = (x + i y) / h follows w = u + i n x u exactly; so does i q (the cross is symmetric).
  for (Complex rotation : {Complex(1, 0), Complex(0, 1), Complex(-1, 0)}) {
    const MapQuality exact = measureMap(mesh, wedges(mesh, linearUV(mesh, rotation / h)), &field, h);
    EXPECT_LT(exact.relativeGradientError, 1e-12);
    EXPECT_EQ(exact.flipped, 0u);
    EXPECT_EQ(exact.collapsed, 0u);
  }
  // Twice the target gradient: error |2w - w| / |w| = 1; a fitted h finds the scale.
  const MapQuality doubled = measureMap(mesh, wedges(mesh, linearUV(mesh, 2.0 / h)), &field, h);
  EXPECT_NEAR(doubled.relativeGradientError, 1.0, 1e-12);
  const MapQuality fitted = measureMap(mesh, wedges(mesh, linearUV(mesh, 2.0 / h)), &field, 0.0);
  EXPECT_NEAR(fitted.edgeLength, h / 2, 1e-12);
  EXPECT_LT(fitted.relativeGradientError, 1e-12);
  // Mirrored: every triangle flipped. Without a field the error is NaN.
  std::vector<Vec2d> mirrored = linearUV(mesh, 1.0 / h);
  for (Vec2d& q : mirrored) q.y() = -q.y();
  const MapQuality flipped = measureMap(mesh, wedges(mesh, mirrored), nullptr, h);
  EXPECT_EQ(flipped.flipped, mesh.numFaces());
  EXPECT_DOUBLE_EQ(flipped.flippedFraction, 1.0);
  EXPECT_TRUE(std::isnan(flipped.relativeGradientError));
  // One triangle squashed to a point.
  std::vector<Vec2d> squashed = linearUV(mesh, 1.0 / h);
  squashed[4] = squashed[3], squashed[5] = squashed[3];
  EXPECT_EQ(measureMap(mesh, wedges(mesh, squashed), &field, h).collapsed, 1u);
}

// A face the map stretches over ten times (root mean square of its gradient against 1/h) is
// counted as stretched, in memory and face by face alike; five times is not; a flipped or
// collapsed face counts as that only.
TEST(MapMetrics, FacesStretchedTenfoldAreCounted) {
  const TriangleMesh mesh = testing::gridMesh(5, 5, 0.5);
  const double h = 0.25;
  std::vector<Vec2d> uv = linearUV(mesh, 1.0 / h);
  auto scaleFace = [&](FaceId f, double s) {
    for (int k = 1; k < 3; ++k) uv[3 * f + k] = uv[3 * f] + s * (uv[3 * f + k] - uv[3 * f]);
  };
  scaleFace(1, 12.0);   // stretch 144
  scaleFace(2, 5.0);    // 25
  for (int k = 1; k < 3; ++k) uv[9 + k].y() = 2.0 * uv[9].y() - uv[9 + k].y();  // face 3 mirrored: flipped
  scaleFace(4, 1e-4);   // collapsed
  std::vector<FaceId> flippedFaces = {7, 8};  // replaced
  const MapQuality inMemory = measureMap(mesh, wedges(mesh, uv), nullptr, h, nullptr, nullptr, &flippedFaces);
  EXPECT_EQ(inMemory.stretched, 1u);
  EXPECT_EQ(inMemory.flipped, 1u);
  EXPECT_EQ(inMemory.collapsed, 1u);
  EXPECT_EQ(flippedFaces, std::vector<FaceId>{3});
  MapQualitySums sums(h);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const Triangle& t = mesh.triangles[f];
    sums.add({mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])}, {uv[3 * f], uv[3 * f + 1], uv[3 * f + 2]},
             nullptr);
  }
  EXPECT_EQ(sums.finish().stretched, 1u);
  // The threshold itself: 10 times along both directions is 100, not above it.
  const std::array<Vec3d, 3> p = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0)};
  EXPECT_NEAR(gradientNormSquared(p, {Vec2d(0, 0), Vec2d(10, 0), Vec2d(0, 10)}), 200.0, 1e-9);
  EXPECT_FALSE(isStretched(200.0, 1.0));
  EXPECT_TRUE(isStretched(200.5, 1.0));
  EXPECT_TRUE(std::isnan(gradientNormSquared({p[0], p[1], p[1]}, {Vec2d(0, 0), Vec2d(1, 0), Vec2d(0, 1)})));
}

// Two unit right triangles sharing the edge 1-2: (0, 1, 2) and (2, 1, 3).
TEST(MapMetrics, CollapsesBetweenCoincidentConesAreCountedApart) {
  TriangleMesh mesh;
  mesh.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(1, 1, 0)};
  mesh.triangles = {Triangle{0, 1, 2}, Triangle{2, 1, 3}};
  const double h = 0.5;
  std::vector<Vec2d> uv(6);
  for (CornerId c = 0; c < 6; ++c) {
    const Vec3d p = mesh.position(mesh.triangles[c / 3][c % 3]);
    uv[c] = Vec2d(p.x(), p.y()) / h;
  }
  EXPECT_NEAR(parameterAreaRatio(mesh, wedges(mesh, uv), 0, h), 1.0, 1e-12);
  EXPECT_NEAR(parameterAreaRatio(mesh, wedges(mesh, uv), 1, h), 1.0, 1e-12);
  const std::vector<VertexId> edgeCones = {1, 2}, oneCone = {1}, farCones = {0, 3};
  EXPECT_EQ(measureMap(mesh, wedges(mesh, uv), nullptr, h, &edgeCones).collapsed, 0u);
  // Vertex 2 moved onto vertex 1: both triangles collapse along the edge between the two cones.
  std::vector<Vec2d> merged = uv;
  merged[2] = merged[1], merged[3] = merged[4];
  EXPECT_NEAR(parameterAreaRatio(mesh, wedges(mesh, merged), 0, h), 0.0, 1e-12);
  const MapQuality atCones = measureMap(mesh, wedges(mesh, merged), nullptr, h, &edgeCones);
  EXPECT_EQ(atCones.collapsed, 2u);
  EXPECT_EQ(atCones.collapsedAtCones, 2u);
  EXPECT_EQ(measureMap(mesh, wedges(mesh, merged), nullptr, h, &oneCone).collapsedAtCones, 0u);
  EXPECT_EQ(measureMap(mesh, wedges(mesh, merged), nullptr, h, &farCones).collapsedAtCones, 0u);
  EXPECT_EQ(measureMap(mesh, wedges(mesh, merged), nullptr, h).collapsedAtCones, 0u);
  EXPECT_EQ(measureMap(mesh, wedges(mesh, merged), nullptr, h).collapsed, 2u);
  // Vertex 0 on the segment between the cones, which stay apart: collapsed, not at cones.
  std::vector<Vec2d> collinear = uv;
  collinear[0] = 0.5 * (uv[1] + uv[2]);
  const MapQuality line = measureMap(mesh, wedges(mesh, collinear), nullptr, h, &edgeCones);
  EXPECT_EQ(line.collapsed, 1u);
  EXPECT_EQ(line.collapsedAtCones, 0u);
  // Mirrored: ratio -1; a zero-area triangle has no ratio.
  std::vector<Vec2d> mirrored = uv;
  for (Vec2d& q : mirrored) q.y() = -q.y();
  EXPECT_NEAR(parameterAreaRatio(mesh, wedges(mesh, mirrored), 1, h), -1.0, 1e-12);
  TriangleMesh flat = mesh;
  flat.positions[2] = Vec3f(0.5f, 0, 0);
  EXPECT_TRUE(std::isnan(parameterAreaRatio(flat, wedges(flat, std::vector<Vec2d>(6, Vec2d::Zero())), 0, h)));
  const std::vector<VertexId> badCones = {7};
  EXPECT_THROW(measureMap(mesh, wedges(mesh, uv), nullptr, h, &badCones), InputError);
}

// A planar fan of n triangles around vertex 0 mapped by z -> z^s (ring vertex j at angle
// s 2 pi j / n): every triangle positive, the angles at the centre summing to 2 pi s. With
// `seam`, the second half of the triangles has its values in another chart (i q + t), as across
// a seam: the angles do not change.
struct Fan {
  TriangleMesh mesh;
  Topology topology;
  WedgeMap uv;
};
Fan powerFan(int n, double s, bool seam) {
  Fan fan;
  fan.mesh.positions.push_back(Vec3f(0, 0, 0));
  for (int j = 0; j < n; ++j) {
    const double a = 2.0 * M_PI * j / n;
    fan.mesh.positions.push_back(Vec3f(float(std::cos(a)), float(std::sin(a)), 0));
  }
  std::vector<Vec2d> values;
  for (int j = 0; j < n; ++j) {
    const VertexId a = 1 + j, b = 1 + (j + 1) % n;
    fan.mesh.triangles.push_back(Triangle{0, a, b});
    for (VertexId v : {VertexId(0), a, b}) {
      const double turn = v == 0 ? 0.0 : s * 2.0 * M_PI * (v == b && j + 1 == n ? n : v - 1) / n;
      Complex q = v == 0 ? Complex(0, 0) : std::polar(1.0, turn);
      if (seam && 2 * j >= n) q = Complex(0, 1) * q + Complex(3, 5);
      values.emplace_back(q.real(), q.imag());
    }
  }
  fan.topology = Topology::build(fan.mesh.triangles, fan.mesh.numVertices());
  fan.uv = WedgeMap::fromCorners(fan.mesh.triangles, values);
  return fan;
}

// The angle sum is 2 pi at a regular vertex, 2 pi - k pi / 2 at a cone and 4 pi where the map
// winds twice with no face flipped: only that counts as wound, and only at interior vertices.
TEST(MapMetrics, VerticesTheMapWindsAroundTwiceAreCounted) {
  for (bool seam : {false, true}) {
    for (const auto& [s, wound] : {std::pair{1.0, false}, {0.25, false}, {0.75, false}, {1.75, false},
                                   {2.0, true}, {2.5, true}}) {
      const Fan fan = powerFan(12, s, seam);
      EXPECT_NEAR(cornerAngleSum(fan.topology, fan.uv, 0), 2.0 * M_PI * s, 1e-4) << s;
      EXPECT_EQ(woundVertices(fan.topology, fan.uv), wound ? std::vector<VertexId>{0} : std::vector<VertexId>{})
          << "power " << s << (seam ? " across a seam" : "");
      const MapQuality q = measureMap(fan.mesh, fan.uv, nullptr, 1.0, nullptr, &fan.topology);
      EXPECT_EQ(q.flipped, 0u) << s;
      EXPECT_TRUE(q.woundCounted);
      EXPECT_EQ(q.wound, wound ? 1u : 0u) << s;
      EXPECT_FALSE(measureMap(fan.mesh, fan.uv, nullptr, 1.0).woundCounted);
    }
  }
  // A linear map of a grid: 2 pi at every interior vertex, none wound.
  const TriangleMesh grid = testing::gridMesh(6, 6, 1.0);
  const Topology topology = Topology::build(grid.triangles, grid.numVertices());
  const WedgeMap uv = wedges(grid, linearUV(grid, Complex(0.3, 2.0)));
  std::uint32_t interior = 0;
  for (VertexId v = 0; v < grid.numVertices(); ++v) {
    if (topology.isBoundaryVertex(v)) continue;
    ++interior;
    EXPECT_NEAR(cornerAngleSum(topology, uv, v), 2.0 * M_PI, 1e-4) << v;
  }
  EXPECT_EQ(interior, 25u);
  EXPECT_TRUE(woundVertices(topology, uv).empty());
  // Every neighbour of an interior vertex on its value (collapsed faces): no angle, not wound
  // (atan2 of the zero edges' signed zeros would add +-pi per corner).
  std::vector<Vec2d> collapsed = linearUV(grid, Complex(1, 0));
  const VertexId centre = 3 * 7 + 3;
  for (CornerId c = 0; c < collapsed.size(); ++c) {
    for (VertexId w : grid.triangles[c / 3]) {
      if (w == centre) collapsed[c] = Vec2d(-0.0, 0.0);
    }
  }
  const WedgeMap point = wedges(grid, collapsed);
  EXPECT_EQ(cornerAngleSum(topology, point, centre), 0.0);
  EXPECT_TRUE(woundVertices(topology, point).empty());
  EXPECT_THROW(woundVertices(topology, WedgeMap({0, 0, 0}, {Vec2d::Zero()})), InputError);
}

// woundVertices decides most vertices by bounds on the corners' angles: its list must be the
// plain test's (the angle sum against kWoundAngleSum at interior vertices) on maps that put
// corners in every direction, and on fans whose sums lie just below and above the threshold.
TEST(MapMetrics, WoundVerticesAsThePlainAngleSumTest) {
  const TriangleMesh torus = testing::torusMesh(24, 12);
  const Topology topology = Topology::build(torus.triangles, torus.numVertices());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const double jitter : {0.0, 0.02, 0.2, 1.0, 5.0}) {
    std::vector<Vec2d> values;
    for (CornerId c = 0; c < topology.numCorners(); ++c) {
      const Vec3f& p = torus.positions[torus.triangles[c / 3][c % 3]];
      // A smooth map of the torus' angles, each corner moved on its own by up to `jitter`.
      values.emplace_back(4.0 * std::atan2(p.y(), p.x()) + jitter * unit(random), 3.0 * p.z() + jitter * unit(random));
    }
    const WedgeMap uv = WedgeMap::fromCorners(torus.triangles, values);
    std::vector<VertexId> expected;
    for (VertexId v = 0; v < topology.numVertices(); ++v) {
      if (!topology.isBoundaryVertex(v) && cornerAngleSum(topology, uv, v) >= kWoundAngleSum) expected.push_back(v);
    }
    EXPECT_EQ(woundVertices(topology, uv), expected) << jitter;
  }
  // Fans of random powers (sums of 1 to 6 pi) and valences, their corners jittered.
  std::vector<TriangleMesh> parts;
  std::vector<Vec2d> values;
  for (int k = 0; k < 200; ++k) {
    const Fan fan = powerFan(4 + int(random() % 30), 1.5 + 1.25 * (1.0 + unit(random)), k % 3 == 0);
    parts.push_back(fan.mesh);
    for (CornerId c = 0; c < fan.topology.numCorners(); ++c) {
      values.push_back(fan.uv[c] + Vec2d(unit(random), unit(random)) * 0.05 * (k % 4));
    }
  }
  const TriangleMesh fans = testing::concatMeshes(parts);
  const Topology fanTopology = Topology::build(fans.triangles, fans.numVertices());
  const WedgeMap fanUV = WedgeMap::fromCorners(fans.triangles, values);
  std::vector<VertexId> expected;
  for (VertexId v = 0; v < fanTopology.numVertices(); ++v) {
    if (!fanTopology.isBoundaryVertex(v) && cornerAngleSum(fanTopology, fanUV, v) >= kWoundAngleSum) expected.push_back(v);
  }
  EXPECT_GT(expected.size(), 50u);
  EXPECT_LT(expected.size(), 180u);
  EXPECT_EQ(woundVertices(fanTopology, fanUV), expected);
  for (const double s : {1.870, 1.874, 1.876, 1.88}) {
    for (const int n : {5, 12, 40}) {
      const Fan fan = powerFan(n, s, false);
      EXPECT_EQ(woundVertices(fan.topology, fan.uv).size(), s > 1.875 ? 1u : 0u) << n << " " << s;
    }
  }
}

}  // namespace
}  // namespace seamvox
