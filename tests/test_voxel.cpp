// The volumetric basis: exact fragment integrals, partition of unity and linear reproduction on
// elements, area, separation of thin sheets and of cut sides, domain counts along a seam, and
// the Vox solver's exactness on developable meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include "core/solve/assemble.h"
#include "core/cut/cut.h"
#include "core/system/errors.h"
#include "core/solve/evaluate.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/mesh/topology.h"
#include "core/solve/hat_solver.h"
#include "core/basis/reduce.h"
#include "core/solve/seamless_solve.h"
#include "core/basis/voxel_basis.h"
#include "core/basis/voxel_clip.h"
#include "core/basis/detail_voxel_elements.h"
#include "core/basis/voxel_grid.h"
#include "core/field/field_proxy.h"
#include "core/mesh/clean.h"
#include "core/synth/generate.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

// Everything a basis needs, for a mesh whose cut is the boundary plus an optional seam.
struct CutMesh {
  TriangleMesh mesh;
  Topology topology;
  CrossField field;
  CutResult cut;
};

CutMesh makeSetup(TriangleMesh mesh, const Vec3d& direction) {
  CutMesh s;
  s.mesh = std::move(mesh);
  s.topology = Topology::build(s.mesh.triangles, s.mesh.numVertices());
  std::vector<Vec3d> vectors(s.mesh.numFaces(), direction);
  s.field = projectToTangent(s.mesh, vectors);
  const std::uint32_t nc = s.topology.numCorners();
  s.cut.corners = CutCorners(nc, false);
  s.cut.faceRotation = FaceRotations(s.mesh.numFaces());
  for (CornerId c = 0; c < nc; ++c) s.cut.corners.setCut(c, s.topology.isBoundaryEdge(c));
  return s;
}

// Adds one seam (matching 0) along the chain of edges a -> b for which isSeamEdge(a, b) holds,
// oriented so that its left corners traverse a -> b.
template <class F>
void addSeam(CutMesh& s, F isSeamEdge) {
  SeamCurve seam;
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const VertexId a = s.topology.vertex(nextCorner(c)), b = s.topology.vertex(prevCorner(c));
    if (s.topology.isBoundaryEdge(c) || !isSeamEdge(a, b)) continue;
    seam.corners.push_back(c);
    for (CornerId side : {c, s.topology.opposite(c)}) s.cut.corners.setCut(side, true);
  }
  ASSERT_FALSE(seam.corners.empty());
  s.cut.seams.push_back(seam);
}

// A level-4 icosphere with its smoothest field, cut through the cones.
CutMesh smoothSphere() {
  CutMesh s;
  s.mesh = testing::icosphereMesh(4);
  s.topology = Topology::build(s.mesh.triangles, s.mesh.numVertices());
  s.field = computeSmoothestField(s.mesh, s.topology);
  s.cut = cutToDisk(s.mesh, s.topology, s.field, computeSingularities(s.mesh, s.topology, s.field));
  return s;
}

// Pure surface integrals (no regularization) unless asked.
VoxelBuildResult build(const CutMesh& s, int resolution, double edgeLength = 1.0,
                       double regularization = 0.0) {
  VoxelBasisOptions options;
  options.regularization = regularization;
  options.gridResolution = resolution;
  options.edgeLength = edgeLength;
  options.chunkFaces = 7;  // several chunks even on small meshes
  return buildVoxelBasis(s.mesh, s.topology, s.field, s.cut, options);
}

Vec3d cornerPosition(const VoxelGridGeometry& grid, const VoxelCoord& v, int k) {
  return grid.origin +
         grid.voxelSize * Vec3d(v[0] + (k & 1), v[1] + (k >> 1 & 1), v[2] + (k >> 2 & 1));
}

TriangleMesh rotated(TriangleMesh mesh, const Eigen::Matrix3d& rotation, const Vec3d& shift) {
  for (Vec3f& p : mesh.positions) p = (rotation * p.cast<double>() + shift).cast<float>();
  return mesh;
}

Eigen::Matrix3d tilt() {
  return (Eigen::AngleAxisd(0.7, Vec3d(1, 2, 3).normalized()) *
          Eigen::AngleAxisd(0.3, Vec3d::UnitX()))
      .toRotationMatrix();
}

double meshArea(const TriangleMesh& mesh) {
  double area = 0.0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) area += faceArea(mesh, f);
  return area;
}

// --- kernels ------------------------------------------------------------------------------------

TEST(VoxelClip, PiecesPartitionTheTriangleAndStayInTheirVoxels) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(0.2, 15.8);
  std::vector<VoxelPiece> pieces;
  for (int trial = 0; trial < 50; ++trial) {
    std::array<Vec3d, 3> g;
    for (auto& p : g) p = Vec3d(coord(rng), coord(rng), coord(rng));
    if (trial % 5 == 0) g[2][2] = g[1][2] = g[0][2] = 7.0;  // lying in a grid plane
    const double area = 0.5 * (g[1] - g[0]).cross(g[2] - g[0]).norm();
    clipTriangleToVoxels(g, 16, pieces);
    double sum = 0.0;
    std::set<VoxelCoord> seen;
    for (const VoxelPiece& piece : pieces) {
      sum += piece.area;
      EXPECT_TRUE(seen.insert(piece.voxel).second);
      for (int i = 0; i < piece.polygon.size; ++i) {
        for (int a = 0; a < 3; ++a) {
          EXPECT_GE(piece.polygon.point[i][a], piece.voxel[a] - 1e-12);
          EXPECT_LE(piece.polygon.point[i][a], piece.voxel[a] + 1 + 1e-12);
        }
      }
      // The single-voxel clip finds the same piece.
      double single = 0.0;
      VoxelIntegrals a, b;
      addFragmentIntegrals(piece.polygon, piece.voxel, 1.0, Vec3d::UnitZ(), Vec3d::UnitX(), 1.0, a);
      addFragmentIntegrals(clipTriangleToVoxel(g, piece.voxel), piece.voxel, 1.0, Vec3d::UnitZ(),
                           Vec3d::UnitX(), 1.0, b);
      single = b.area;
      EXPECT_NEAR(single, a.area, 1e-12 * std::max(1.0, a.area));
    }
    EXPECT_NEAR(sum, area, 1e-10 * area);
  }
}

/// The integrals addFragmentIntegrals computes, from their definition: projected gradients of
/// the 8 B-splines at the points of a degree-4 rule (exact for the quartic integrands), pair by pair.
struct ReferenceIntegrals {
  std::array<double, 36> stiffness{}, normal{};
  std::array<std::complex<double>, 8> rhs{};
  double scale() const {
    double m = 0.0;
    for (double x : stiffness) m = std::max(m, std::abs(x));
    return m;
  }
};

ReferenceIntegrals referenceIntegrals(const ClipPolygon& poly, const VoxelCoord& voxel, double voxelSize,
                                      const Vec3d& n, const Vec3d& u, double h, double normalWeight) {
  const double w1 = 0.223381589678011, a1 = 0.445948490915965, b1 = 0.108103018168070;
  const double w2 = 0.109951743655322, a2 = 0.091576213509771, b2 = 0.816847572980459;
  const double rule[6][4] = {{a1, a1, b1, w1}, {a1, b1, a1, w1}, {b1, a1, a1, w1},
                             {a2, a2, b2, w2}, {a2, b2, a2, w2}, {b2, a2, a2, w2}};
  const Vec3d v = n.cross(u);
  ReferenceIntegrals out;
  const Vec3d base(voxel[0], voxel[1], voxel[2]);
  for (int i = 1; i + 1 < poly.size; ++i) {
    const Vec3d p0 = poly.point[0] - base, p1 = poly.point[i] - base, p2 = poly.point[i + 1] - base;
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    for (const auto& q : rule) {
      const Vec3d t = q[0] * p0 + q[1] * p1 + q[2] * p2;
      Vec3d grad[8];
      double dn[8];
      for (int k = 0; k < 8; ++k) {
        const double f[3] = {k & 1 ? t[0] : 1 - t[0], k & 2 ? t[1] : 1 - t[1], k & 4 ? t[2] : 1 - t[2]};
        const double d[3] = {k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0};
        const Vec3d g(d[0] * f[1] * f[2], f[0] * d[1] * f[2], f[0] * f[1] * d[2]);
        dn[k] = n.dot(g);
        grad[k] = g - dn[k] * n;
      }
      for (int a = 0; a < 8; ++a) {
        for (int b = a; b < 8; ++b) {
          const int idx = packedIndex(a, b);
          out.stiffness[idx] += q[3] * area * (grad[a].dot(grad[b]) + normalWeight * dn[a] * dn[b]);
          out.normal[idx] += q[3] * area * dn[a] * dn[b];
        }
        out.rhs[a] += q[3] * area * voxelSize / h * std::complex<double>(grad[a].dot(u), grad[a].dot(v));
      }
    }
  }
  return out;
}

TEST(VoxelClip, FragmentIntegralsMatchTheTangentialGradientsPairByPair) {
  // The kernel integrates products of bilinear weights per axis; compare with the definition.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3d n = Vec3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
    const Vec3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const double angle = 6.2831853 * unit(rng);
    const Vec3d u = std::cos(angle) * e1 + std::sin(angle) * e2;
    const VoxelCoord voxel{5, 6, 7};
    const Vec3d centre = Vec3d(5.2, 6.2, 7.2) + 0.6 * Vec3d(unit(rng), unit(rng), unit(rng));
    ClipPolygon poly;
    poly.size = 3 + trial % 6;
    for (int i = 0; i < poly.size; ++i) {
      const double a = 6.2831853 * i / poly.size;
      poly.point[i] = centre + 0.2 * (std::cos(a) * e1 + std::sin(a) * e2);
    }
    const double normalWeight = trial % 2 ? 0.0 : unit(rng), voxelSize = 0.25, h = 0.8;
    VoxelIntegrals acc;
    double normalAcc[36] = {};
    addFragmentIntegrals(poly, voxel, voxelSize, n, u, h, acc, normalWeight, normalAcc);
    const ReferenceIntegrals ref = referenceIntegrals(poly, voxel, voxelSize, n, u, h, normalWeight);
    const double scale = ref.scale();
    for (int i = 0; i < 36; ++i) {
      ASSERT_NEAR(acc.stiffness[i], ref.stiffness[i], 1e-12 * scale) << "trial " << trial << " entry " << i;
      ASSERT_NEAR(normalAcc[i], ref.normal[i], 1e-12 * scale) << "trial " << trial << " entry " << i;
    }
    for (int a = 0; a < 8; ++a) ASSERT_NEAR(std::abs(acc.rhs[a] - ref.rhs[a]), 0.0, 1e-12 * (1.0 + scale));
  }
}

// The compact per-face fragment ranges give back every face's offsets: counts of 0, 1, just below,
// at and far above the one-byte limit, across the 16-face blocks.
TEST(VoxelBasis, FragmentRangesGiveBackTheOffsets) {
  std::mt19937 rng(3);
  const std::uint32_t special[] = {0, 1, 254, 255, 256, 300, 70000};
  std::vector<std::uint32_t> start{0};
  for (int f = 0; f < 1000; ++f) {
    const std::uint32_t n = f % 37 == 5 ? special[(f / 37) % 7] : std::uniform_int_distribution<std::uint32_t>(0, 4)(rng);
    start.push_back(start.back() + n);
  }
  const FragmentRanges ranges(start);
  ASSERT_EQ(ranges.numFaces(), 1000u);
  std::set<std::uint32_t> counts;
  for (FaceId f = 0; f < 1000; ++f) {
    ASSERT_EQ(ranges.begin(f), start[f]) << "face " << f;
    ASSERT_EQ(ranges.count(f), start[f + 1] - start[f]) << "face " << f;
    counts.insert(ranges.count(f));
  }
  for (std::uint32_t n : special) EXPECT_TRUE(counts.count(n)) << n;  // every special count was used
  EXPECT_LT(ranges.bytes(), 1000u * 2);
  EXPECT_EQ(FragmentRanges(std::vector<std::uint32_t>{}).numFaces(), 0u);
}

TEST(VoxelClip, SmallPiecesAreIntegratedWithinATenThousandth) {
  // Triangles under a quarter of a voxel across take the degree-2 rule: every integral within 1e-4
  // of the exact one (relative to the largest entry), anywhere in the voxel, and no longer exact
  // (else the cheaper rule would not be in use).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const VoxelCoord voxel{1, 2, 3};
    const Vec3d corner = Vec3d(1, 2, 3) + 0.85 * Vec3d(unit(rng), unit(rng), unit(rng));
    ClipPolygon poly;
    poly.size = 3;
    for (int i = 0; i < 3; ++i) poly.point[i] = corner + 0.144 * Vec3d(unit(rng), unit(rng), unit(rng));
    const Vec3d n = (poly.point[1] - poly.point[0]).cross(poly.point[2] - poly.point[0]).normalized();
    const Vec3d u = n.cross(Vec3d(0.3, -0.2, 0.9)).normalized();
    VoxelIntegrals acc;
    double normalAcc[36] = {};
    addFragmentIntegrals(poly, voxel, 0.5, n, u, 2.0, acc, 0.0, normalAcc);
    const ReferenceIntegrals ref = referenceIntegrals(poly, voxel, 0.5, n, u, 2.0, 0.0);
    const double scale = ref.scale();
    for (int i = 0; i < 36; ++i) {
      ASSERT_NEAR(acc.stiffness[i], ref.stiffness[i], 1e-4 * scale) << "trial " << trial << " entry " << i;
      ASSERT_NEAR(normalAcc[i], ref.normal[i], 1e-4 * scale) << "trial " << trial << " entry " << i;
      worst = std::max(worst, std::abs(acc.stiffness[i] - ref.stiffness[i]) / scale);
    }
    for (int a = 0; a < 8; ++a) ASSERT_NEAR(std::abs(acc.rhs[a] - ref.rhs[a]), 0.0, 1e-4 * (1.0 + scale));
  }
  EXPECT_GT(worst, 1e-12);
  std::printf("worst relative error of the small-piece rule: %.2e\n", worst);
}

TEST(VoxelClip, FragmentIntegralsAreExactUnderSubdivision) {
  // The degree-4 exact rule (pieces a quarter of a voxel across or more) gives the same integrals
  // on a triangle and on its 4 sub-triangles.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::array<Vec3d, 3> t;
    do {  // edges of 0.6 voxel or more, so that the halves stay above a quarter
      for (auto& p : t) p = Vec3d(unit(rng), unit(rng), unit(rng)) + Vec3d(2, 3, 4);
    } while (std::min({(t[1] - t[0]).norm(), (t[2] - t[1]).norm(), (t[0] - t[2]).norm()}) < 0.6);
    const Vec3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    const Vec3d u = n.cross(Vec3d(0.3, -0.2, 0.9)).normalized();
    const VoxelCoord voxel{2, 3, 4};
    auto integrate = [&](const std::vector<std::array<Vec3d, 3>>& tris) {
      VoxelIntegrals acc;
      for (const auto& tri : tris) {
        ClipPolygon poly;
        for (const Vec3d& p : tri) poly.point[poly.size++] = p;
        addFragmentIntegrals(poly, voxel, 0.5, n, u, 2.0, acc);
      }
      return acc;
    };
    std::vector<std::array<Vec3d, 3>> tris{t};
    const VoxelIntegrals coarse = integrate(tris);
    for (int level = 0; level < 1; ++level) {
      std::vector<std::array<Vec3d, 3>> finer;
      for (const auto& x : tris) {
        const Vec3d m01 = 0.5 * (x[0] + x[1]), m12 = 0.5 * (x[1] + x[2]), m20 = 0.5 * (x[2] + x[0]);
        finer.push_back({x[0], m01, m20});
        finer.push_back({m01, x[1], m12});
        finer.push_back({m20, m12, x[2]});
        finer.push_back({m01, m12, m20});
      }
      tris = finer;
    }
    const VoxelIntegrals fine = integrate(tris);
    double scale = 0.0;
    for (double x : coarse.stiffness) scale = std::max(scale, std::abs(x));
    for (int i = 0; i < 36; ++i) EXPECT_NEAR(coarse.stiffness[i], fine.stiffness[i], 1e-12 * scale);
    for (int a = 0; a < 8; ++a) EXPECT_NEAR(std::abs(coarse.rhs[a] - fine.rhs[a]), 0.0, 1e-12);
    EXPECT_NEAR(coarse.area, fine.area, 1e-14);
  }
}

// --- elements ------------------------------------------------------------------------------------

// Partition of unity (stiffness rows sum to zero, rhs sums to zero) and exact reproduction of a
// linear function f = g.x: c^T L c = int |P g|^2 and c . rhs = int <P g, u> + i <P g, n x u> / h.
void expectLinearReproduction(const CutMesh& s, int resolution, bool perElementPlane) {
  const double h = 0.37;
  VoxelBuildResult built = build(s, resolution, h);
  const VoxelBasis& basis = *built.basis;
  const VoxelGridGeometry& grid = basis.grid();
  const Vec3d g(0.8, -1.3, 0.45);
  double energy = 0.0, totalArea = 0.0;
  Complex rhs = 0.0;
  ElementIntegrals el;
  for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
    basis.elementIntegrals(e, el);
    ASSERT_EQ(el.count, 8u);
    double scale = 0.0;
    for (double x : el.stiffness) scale = std::max(scale, std::abs(x));
    Complex rhsSum = 0.0;
    for (int a = 0; a < 8; ++a) {
      double row = 0.0;
      for (int b = 0; b < 8; ++b) {
        row += el.stiffness[8 * a + b];
        EXPECT_EQ(el.stiffness[8 * a + b], el.stiffness[8 * b + a]);
      }
      EXPECT_NEAR(row, 0.0, 1e-12 * std::max(scale, 1e-300));
      rhsSum += el.rhs[a];
    }
    EXPECT_LE(std::abs(rhsSum), 1e-12 * (1.0 + el.area / (h * grid.voxelSize)));
    double c[8];
    for (int k = 0; k < 8; ++k) c[k] = g.dot(cornerPosition(grid, basis.elementVoxel(e), k));
    double quad = 0.0;
    for (int a = 0; a < 8; ++a) {
      for (int b = 0; b < 8; ++b) quad += c[a] * el.stiffness[8 * a + b] * c[b];
      rhs += c[a] * el.rhs[a];
    }
    if (perElementPlane) {
      const Vec3d n = faceNormal(s.mesh, 0);
      const double expected = (g - n * n.dot(g)).squaredNorm() * el.area;
      EXPECT_NEAR(quad, expected, 1e-9 * std::max(expected, 1e-12 * g.squaredNorm()));
    }
    energy += quad;
    totalArea += el.area;
  }
  double expectedEnergy = 0.0;
  Complex expectedRhs = 0.0;
  for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
    const Vec3d n = faceNormal(s.mesh, f);
    const Vec3d pg = g - n * n.dot(g);
    const double area = faceArea(s.mesh, f);
    expectedEnergy += pg.squaredNorm() * area;
    const Vec3d u = s.field.at(f);
    expectedRhs += area * Complex(pg.dot(u), pg.dot(n.cross(u))) / h;
  }
  EXPECT_NEAR(energy, expectedEnergy, 1e-9 * expectedEnergy);
  EXPECT_NEAR(std::abs(rhs - expectedRhs), 0.0, 1e-9 * std::abs(expectedRhs));
  EXPECT_NEAR(totalArea, meshArea(s.mesh), 1e-9 * totalArea);
}

TEST(VoxelBasis, ReproducesLinearFunctionsOnATiltedPlane) {
  // z = x / 2 + y / 4 on a grid of quarters: exactly planar in float positions.
  TriangleMesh mesh = testing::gridMesh(6, 5, 0.25);
  for (Vec3f& p : mesh.positions) p[2] = 0.5f * p[0] + 0.25f * p[1];
  const CutMesh s = makeSetup(std::move(mesh), Vec3d(1, 0.2, 0.1));
  for (int resolution : {8, 16, 64}) expectLinearReproduction(s, resolution, true);
}

TEST(VoxelBasis, ReproducesLinearFunctionsOnCurvedMeshes) {
  expectLinearReproduction(makeSetup(testing::icosphereMesh(2), Vec3d(0.3, 1, 0.2)), 16, false);
  expectLinearReproduction(makeSetup(rotated(testing::torusMesh(24, 12), tilt(), Vec3d::Zero()),
                                     Vec3d(0, 0.2, 1)),
                           32, false);
}

// Two sheets closer than a voxel, joined by a fold at x = 1: away from the fold every voxel they
// cross holds one element per sheet, and the corners there get one basis function per sheet.
TEST(VoxelBasis, ThinFoldedSheetGetsSeparateElementsPerSheet) {
  const int n = 40, m = 6;
  const double gap = 0.01;
  TriangleMesh mesh;
  std::vector<double> path;  // arc length along the fold: bottom 0..1, side, top back to 0
  for (int i = 0; i <= n; ++i) path.push_back(double(i) / n);
  path.push_back(1.0 + gap);
  for (int i = n - 1; i >= 0; --i) path.push_back(1.0 + gap + double(n - i) / n);
  auto lift = [&](double t, double y) {
    if (t <= 1.0) return Vec3d(t, y, 0.0);
    if (t <= 1.0 + gap) return Vec3d(1.0, y, t - 1.0);
    return Vec3d(1.0 - (t - 1.0 - gap), y, gap);
  };
  const int columns = static_cast<int>(path.size());
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < columns; ++i) mesh.positions.push_back(lift(path[i], 0.5 * j / m).cast<float>());
  for (int j = 0; j < m; ++j)
    for (int i = 0; i + 1 < columns; ++i) {
      const VertexId a = j * columns + i, b = a + 1, c = a + columns, d = c + 1;
      mesh.triangles.push_back({a, b, d});
      mesh.triangles.push_back({a, d, c});
    }
  const CutMesh s = makeSetup(std::move(mesh), Vec3d::UnitX());
  VoxelBuildResult built = build(s, 16);
  const VoxelBasis& basis = *built.basis;
  ASSERT_LT(gap, 0.5 * basis.grid().voxelSize);
  // Which sheet each element's faces lie on: z < gap / 2 is the bottom.
  std::map<std::uint32_t, std::set<int>> elementSheets;
  for (FaceId f = 0; f < s.mesh.numFaces(); ++f) {
    const Triangle& t = s.mesh.triangles[f];
    const double z = (s.mesh.position(t[0]) + s.mesh.position(t[1]) + s.mesh.position(t[2]))[2] / 3;
    const int sheet = z < 0.25 * gap ? 0 : z > 0.75 * gap ? 1 : 2;
    for (std::uint32_t e : basis.faceElements(f)) elementSheets[e].insert(sheet);
  }
  int voxelsWithBoth = 0;
  for (std::uint32_t v = 0; v < basis.voxelCoords().size(); ++v) {
    std::set<int> sheets;
    for (std::uint32_t e = basis.voxelElementStart()[v]; e < basis.voxelElementStart()[v + 1]; ++e) {
      const auto& es = elementSheets[e];
      if (es.count(2)) continue;  // the fold joins both sheets
      EXPECT_EQ(es.size(), 1u) << "element " << e << " mixes the sheets";
      sheets.insert(es.begin(), es.end());
    }
    if (sheets.size() == 2) {
      ++voxelsWithBoth;
      EXPECT_EQ(basis.voxelElementStart()[v + 1] - basis.voxelElementStart()[v], 2u);
    }
  }
  EXPECT_GT(voxelsWithBoth, 10);
  // Corners far from the fold (x < 0.5) whose support holds both sheets carry two basis
  // functions, one per sheet; the others one.
  std::map<VoxelCoord, int> perCorner;
  for (const VoxelCoord& c : basis.basisCorner()) ++perCorner[c];
  const double z0 = basis.grid().toGrid(Vec3d::Zero())[2];
  const double z1 = basis.grid().toGrid(Vec3d(0, 0, gap))[2];
  int doubled = 0;
  for (const auto& [corner, count] : perCorner) {
    const double x = basis.grid().origin[0] + basis.grid().voxelSize * corner[0];
    if (x >= 0.5) continue;
    const bool both = std::abs(z0 - corner[2]) < 1 && std::abs(z1 - corner[2]) < 1;
    EXPECT_EQ(count, both ? 2 : 1) << corner[0] << " " << corner[1] << " " << corner[2];
    doubled += both;
  }
  EXPECT_GT(doubled, 0);
  EXPECT_EQ(basis.numDomains(), basis.numBasisFunctions());  // no seams
}

// Counts grid corners whose open support (the 8 voxels around it) meets segment a-b, sampling.
int cornersMeetingSegment(const VoxelGridGeometry& grid, const Vec3d& a, const Vec3d& b) {
  std::set<VoxelCoord> corners;
  for (int i = 0; i <= 20000; ++i) {
    const Vec3d g = grid.toGrid(a + (b - a) * (i / 20000.0));
    for (int dz = 0; dz <= 1; ++dz)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          const VoxelCoord c{int(std::floor(g[0])) + dx, int(std::floor(g[1])) + dy,
                             int(std::floor(g[2])) + dz};
          if (std::abs(g[0] - c[0]) < 1 && std::abs(g[1] - c[1]) < 1 && std::abs(g[2] - c[2]) < 1) {
            corners.insert(c);
          }
        }
  }
  return static_cast<int>(corners.size());
}

CutMesh cutCylinder(int n, int m) {
  CutMesh s = makeSetup(testing::cylinderMesh(n, m, 1.0, 2.0), Vec3d::UnitZ());
  addSeam(s, [&](VertexId a, VertexId b) { return a % n == 0 && b == a + VertexId(n); });
  return s;
}

TEST(VoxelBasis, SeamSplitsSupportsIntoTwoAdjacentDomains) {
  const int n = 48, m = 12;
  const CutMesh s = cutCylinder(n, m);
  for (int resolution : {16, 32}) {
    VoxelBuildResult built = build(s, resolution);
    const VoxelBasis& basis = *built.basis;
    // Every support is one connected piece of the uncut cylinder: one function per corner.
    std::set<VoxelCoord> corners(basis.basisCorner().begin(), basis.basisCorner().end());
    EXPECT_EQ(corners.size(), basis.numBasisFunctions());
    const int split = cornersMeetingSegment(basis.grid(), Vec3d(1, 0, 0), Vec3d(1, 0, 2));
    EXPECT_GT(split, 0);
    EXPECT_EQ(basis.numDomains(), basis.numBasisFunctions() + split) << "grid " << resolution;
    // Each split function's two domains are adjacent across the seam, left to right, and the
    // left domain is the one on the side of the seam's left faces (y < 0 near angle 0).
    std::vector<int> domainsOf(basis.numBasisFunctions(), 0);
    for (std::uint32_t d = 0; d < basis.numDomains(); ++d) ++domainsOf[basis.domainBasis()[d]];
    std::set<std::uint32_t> adjacent;
    for (const DomainAdjacency& a : basis.adjacencies()) {
      EXPECT_EQ(a.seam, 0u);
      EXPECT_NE(a.left, a.right);
      EXPECT_EQ(basis.domainBasis()[a.left], basis.domainBasis()[a.right]);
      adjacent.insert(basis.domainBasis()[a.left]);
    }
    for (std::uint32_t b = 0; b < basis.numBasisFunctions(); ++b) {
      EXPECT_LE(domainsOf[b], 2);
      EXPECT_EQ(domainsOf[b] == 2, adjacent.count(b) == 1) << "basis " << b;
    }
    // No element holds faces of both sides next to the seam.
    for (const CornerId c : s.cut.seams[0].corners) {
      const auto left = basis.faceElements(cornerFace(c));
      const auto right = basis.faceElements(cornerFace(s.topology.opposite(c)));
      for (std::uint32_t e : left) EXPECT_EQ(std::count(right.begin(), right.end(), e), 0);
    }
  }
}

TEST(VoxelBasis, UncutSurfacesHaveOneDomainPerFunction) {
  const CutMesh s = makeSetup(testing::torusMesh(30, 16), Vec3d::UnitZ());
  VoxelBuildResult built = build(s, 16);
  EXPECT_EQ(built.basis->numDomains(), built.basis->numBasisFunctions());
  EXPECT_TRUE(built.basis->adjacencies().empty());
  // The OpenVDB grid finds every voxel's id, and nothing elsewhere.
  for (std::uint32_t v = 0; v < built.grid.size(); ++v) {
    EXPECT_EQ(built.grid.find(built.basis->voxelCoords()[v]), v);
  }
  EXPECT_EQ(built.grid.find({-5, 0, 0}), kInvalidId);
}

// A flat square with one vertex lifted a hair across the grid plane z = 8 (and one lowered as
// much, so the bounding box stays centred): the lifted tip puts a sliver of ~1e-9 squared voxels
// into the layer above, whose upper corners' B-splines see nothing else.
CutMesh sliverSquare(int resolution) {
  TriangleMesh mesh = testing::gridMesh(8, 8, 1.0 / 8);
  const double voxelSize = 1.0 / (resolution - 2);  // makeVoxelGrid on a unit square
  const double planeZ = 0.5 * resolution - 0.1234567;  // grid z of the square's plane
  const float lift = static_cast<float>((resolution / 2 + 2e-6 - planeZ) * voxelSize);
  mesh.positions[3 * 9 + 3][2] = lift;    // vertex (3, 3)
  mesh.positions[6 * 9 + 5][2] = -lift;  // vertex (5, 6)
  return makeSetup(std::move(mesh), Vec3d(1, 0, 0));
}

// Weight of every domain: int |grad phi|^2 (3D gradient, grid units) over its support.
std::vector<double> domainWeights(VoxelBasis& basis) {
  const double regularization = basis.regularization();
  basis.setRegularization(1.0);  // tangential + normal = 3D gradient
  std::vector<double> weight(basis.numDomains(), 0.0);
  ElementIntegrals el;
  for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
    basis.elementIntegrals(e, el);
    for (std::uint32_t k = 0; k < el.count; ++k) weight[el.domain[k]] += el.stiffness[9 * k];
  }
  basis.setRegularization(regularization);
  return weight;
}

TEST(VoxelBasis, SliverSupportsJoinAHeavierDomain) {
  const int resolution = 16;
  const CutMesh s = sliverSquare(resolution);
  const VoxelGridGeometry grid = makeVoxelGrid(computeBoundingBox(s.mesh.positions), resolution);
  const double tip = grid.toGrid(s.mesh.position(3 * 9 + 3))[2] - resolution / 2;
  ASSERT_GT(tip, 0.0);
  ASSERT_LT(tip, 1e-5);
  const double minWeight = VoxelBasisOptions{}.minDomainWeight;
  VoxelBasisOptions options;
  options.gridResolution = resolution;
  options.minDomainWeight = 0.0;
  {
    // Without joining, the sliver's upper corners are domains of almost no weight.
    const VoxelBuildResult raw = buildVoxelBasis(s.mesh, s.topology, s.field, s.cut, options);
    const std::vector<double> weight = domainWeights(*raw.basis);
    EXPECT_LT(*std::min_element(weight.begin(), weight.end()), 1e-3 * minWeight);
    EXPECT_EQ(raw.basis->stats().joinedDomains, 0u);
  }
  options.minDomainWeight = minWeight;
  const VoxelBuildResult built = buildVoxelBasis(s.mesh, s.topology, s.field, s.cut, options);
  VoxelBasis& basis = *built.basis;
  EXPECT_GT(basis.stats().joinedDomains, 0u);
  for (double weight : domainWeights(basis)) EXPECT_GE(weight, minWeight);
  // Still a partition of unity: equal coefficients give that value at every corner.
  const Complex value(3.0, -2.0);
  WedgeMap uv = buildCutWedges(s.topology, s.cut);
  basis.evaluateCorners(std::vector<Complex>(basis.numDomains(), value), uv);
  for (const Vec2d& q : testing::cornerValues(uv)) EXPECT_LT(std::abs(Complex(q[0], q[1]) - value), 1e-12);
  // And the Vox solver factors its system at the first try.
  ParamOptions param;
  param.edgeLength = 0.05;
  const VoxelParamResult result =
      parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, param, resolution);
  EXPECT_EQ(result.failedAttempts, 0u);
  EXPECT_EQ(result.regularization, VoxelBasisOptions{}.regularization);
}

TEST(VoxelBasis, JoiningAgainGivesTheBasisBuiltWithThatWeight) {
  // joinDomains(w) on a basis built with another weight: the domains, functions, adjacencies,
  // corners and regularization of a basis built with w, either way round.
  const int resolution = 16;
  const CutMesh s = sliverSquare(resolution);
  const auto build = [&](double weight) {
    VoxelBasisOptions options;
    options.gridResolution = resolution;
    options.minDomainWeight = weight;
    return buildVoxelBasis(s.mesh, s.topology, s.field, s.cut, options);
  };
  const auto expectSame = [](const VoxelBasis& a, const VoxelBasis& b) {
    ASSERT_EQ(a.numElements(), b.numElements());
    EXPECT_EQ(a.numBasisFunctions(), b.numBasisFunctions());
    EXPECT_EQ(a.domainBasis(), b.domainBasis());
    EXPECT_EQ(a.basisCorner(), b.basisCorner());
    EXPECT_EQ(a.stats().joinedDomains, b.stats().joinedDomains);
    EXPECT_EQ(a.regularization(), b.regularization());
    ASSERT_EQ(a.adjacencies().size(), b.adjacencies().size());
    for (std::size_t i = 0; i < a.adjacencies().size(); ++i) {
      EXPECT_EQ(a.adjacencies()[i].left, b.adjacencies()[i].left);
      EXPECT_EQ(a.adjacencies()[i].right, b.adjacencies()[i].right);
      EXPECT_EQ(a.adjacencies()[i].seam, b.adjacencies()[i].seam);
    }
    EXPECT_EQ(a.seamRotation(), b.seamRotation());
    std::uint32_t da[8], db[8];
    for (std::uint64_t e = 0; e < a.numElements(); ++e) {
      ASSERT_EQ(a.elementDomains(e, da), b.elementDomains(e, db));
      ASSERT_TRUE(std::equal(da, da + 8, db)) << "element " << e;
    }
  };
  const double weight = VoxelBasisOptions{}.minDomainWeight;
  const VoxelBuildResult raw = build(0.0), joined = build(weight);
  ASSERT_GT(joined.basis->stats().joinedDomains, 0u);
  ASSERT_NE(raw.basis->numBasisFunctions(), joined.basis->numBasisFunctions());
  VoxelBuildResult rejoined = build(0.0);
  rejoined.basis->setRegularization(1e-3);  // as a failed solve leaves it
  rejoined.basis->joinDomains(weight);
  expectSame(*rejoined.basis, *joined.basis);
  rejoined.basis->joinDomains(0.0);
  expectSame(*rejoined.basis, *raw.basis);
}

// The links of one face as every fragment pair across each edge gives them (the plain scan the
// search by voxel must equal, links in the same order).
template <class Neighbour>
void linkByPlainScan(FaceId f, const std::vector<detail::FaceFragment>& mine, const std::array<Vec3d, 3>& g,
                     const Topology& topology, const std::vector<std::uint8_t>& cut, Neighbour&& neighbour,
                     detail::RecordedLinks& links) {
  std::vector<std::pair<VoxelCoord, std::uint32_t>> sorted;
  if (mine.size() >= 2) detail::joinFacePieces(mine, sorted, links.functions);
  std::vector<detail::FaceFragment> theirs;
  for (const detail::FaceFragment& fr : mine) {
    for (int j = 0; j < 3; ++j) {
      const CornerId c = 3 * f + j, o = topology.opposite(c);
      if (!(fr.edgeMask >> j & 1) || o == kInvalidId || cornerFace(o) < f) continue;
      neighbour(cornerFace(o), theirs);
      for (const detail::FaceFragment& other : theirs) {
        const VoxelCoord d = detail::voxelDifference(other.voxel, fr.voxel);
        if (!(other.edgeMask >> (o % 3) & 1) || !detail::isNeighbourOffset(d)) continue;
        if (d == VoxelCoord{0, 0, 0} && !cut[c]) continue;
        if (d != VoxelCoord{0, 0, 0}) {
          Vec3d lo, hi;
          for (int x = 0; x < 3; ++x) {
            lo[x] = std::max(fr.voxel[x], other.voxel[x]);
            hi[x] = std::min(fr.voxel[x], other.voxel[x]) + 1;
          }
          if (!segmentOverlapsBox(g[(j + 1) % 3], g[(j + 2) % 3], lo, hi)) continue;
        }
        detail::forSharedCorners(d, [&](int k, int k2) {
          const std::uint32_t a = 8 * fr.element + k, b = 8 * other.element + k2;
          if (!cut[c]) {
            links.functions.unite(a, b);
          } else if (c < o) {
            links.seamLinks.push_back({a, b, c % 5});
          } else {
            links.seamLinks.push_back({b, a, o % 5});
          }
        });
      }
    }
  }
}

TEST(VoxelBasis, LongSliversAreLinkedByVoxelAsByAPlainScan) {
  // A double cone of long slivers in grid coordinates (two poles of 300 faces each), its poles on
  // a grid line and one spoke along it (neighbours whose fragments meet along a voxel edge link in
  // several voxels); some spokes are seams. Every fragment is an element of its own, the
  // fragments of a face in a random order (the links follow it).
  const int n = 300, resolution = 64;
  const Vec3d top(10.0, 32.0, 60.3), bottom(10.0, 32.0, 0.3), centre(30.0, 32.0, 30.3);
  std::vector<Vec3d> points{top, bottom};
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    points.push_back(i == n / 2 ? Vec3d(10.0, 32.0, 30.3) : centre + 20.0 * Vec3d(std::cos(t), std::sin(t), 0.1));
  }
  std::vector<Triangle> triangles;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t a = 2 + i, b = 2 + (i + 1) % n;
    triangles.push_back({0, a, b});
    triangles.push_back({1, b, a});
  }
  const Topology topology = Topology::build(triangles, static_cast<std::uint32_t>(points.size()));
  std::vector<std::uint8_t> cut(3 * triangles.size(), 0);
  for (CornerId c = 0; c < cut.size(); ++c) {
    const CornerId o = topology.opposite(c);
    if (std::min(c, o) % 7 == 0 || std::min(c, o) % 7 == 3) cut[c] = 1;
  }
  const auto gridCoords = [&](FaceId f) {
    return std::array<Vec3d, 3>{points[triangles[f][0]], points[triangles[f][1]], points[triangles[f][2]]};
  };
  std::vector<std::vector<detail::FaceFragment>> fragments(triangles.size());
  std::vector<VoxelPiece> pieces;
  std::uint32_t element = 0, longest = 0;
  std::mt19937 random(7);
  for (FaceId f = 0; f < triangles.size(); ++f) {
    const std::array<Vec3d, 3> g = gridCoords(f);
    clipTriangleToVoxels(g, resolution, pieces);
    std::array<std::uint32_t, 3> onEdge{};
    for (const VoxelPiece& piece : pieces) {
      const std::uint8_t mask = voxelEdgeMask(g, piece.voxel);
      fragments[f].push_back({piece.voxel, element++, mask});
      for (int j = 0; j < 3; ++j) onEdge[j] += mask >> j & 1;
    }
    longest = std::max(longest, *std::max_element(onEdge.begin(), onEdge.end()));
    std::shuffle(fragments[f].begin(), fragments[f].end(), random);
  }
  ASSERT_GT(longest, 20u);  // the search by voxel is taken (a plain scan up to 8)
  const auto neighbour = [&](FaceId h, std::vector<detail::FaceFragment>& out) { out = fragments[h]; };
  detail::RecordedLinks searched, scanned;
  detail::LinkScratch scratch;
  for (FaceId f = 0; f < triangles.size(); ++f) {
    const std::array<Vec3d, 3> g = gridCoords(f);
    detail::linkFaceFragments(
        f, fragments[f], g, [&](CornerId c) { return topology.opposite(c); }, [&](CornerId c) { return cut[c] != 0; },
        [&](CornerId c) {
          const CornerId o = topology.opposite(c);
          return SeamIndex::Side{std::min(c, o) % 5, c < o};
        },
        neighbour, scratch, searched);
    linkByPlainScan(f, fragments[f], g, topology, cut, neighbour, scanned);
  }
  EXPECT_GT(searched.seamLinks.size(), 100u);
  EXPECT_GT(searched.functions.pairs.size(), 1000u);
  EXPECT_EQ(searched.functions.pairs, scanned.functions.pairs);
  ASSERT_EQ(searched.seamLinks.size(), scanned.seamLinks.size());
  for (std::size_t i = 0; i < searched.seamLinks.size(); ++i) {
    const detail::SeamLink &a = searched.seamLinks[i], &b = scanned.seamLinks[i];
    ASSERT_TRUE(a.left == b.left && a.right == b.right && a.seam == b.seam) << "seam link " << i;
  }
}

TEST(VoxelBasis, RegularizationChangesWithoutRebuilding) {
  // The normal-derivative integrals are kept apart: a basis built with weight w and one built
  // without it and then given w have the same element integrals.
  const CutMesh s = makeSetup(rotated(testing::icosphereMesh(2), tilt(), Vec3d::Zero()),
                              Vec3d(0.3, 1, 0.2));
  const double weight = 1e-3;
  VoxelBuildResult withWeight = build(s, 8, 1.0, weight);
  VoxelBuildResult without = build(s, 8, 1.0, 0.0);
  ASSERT_EQ(withWeight.basis->numElements(), without.basis->numElements());
  EXPECT_EQ(withWeight.basis->regularization(), weight);
  without.basis->setRegularization(weight);
  EXPECT_THROW(without.basis->setRegularization(-1.0), InputError);
  ElementIntegrals a, b, plain;
  double normalPart = 0.0;
  for (std::uint64_t e = 0; e < without.basis->numElements(); ++e) {
    withWeight.basis->elementIntegrals(e, a);
    without.basis->elementIntegrals(e, b);
    const VoxelIntegrals& record = without.basis->elementRecord(e);
    for (int k = 0; k < 64; ++k) {
      EXPECT_NEAR(a.stiffness[k], b.stiffness[k], 1e-12);
      normalPart = std::max(normalPart, std::abs(b.stiffness[k] - record.stiffness[packedIndex(k / 8, k % 8)]));
    }
    for (int k = 0; k < 8; ++k) EXPECT_EQ(a.rhs[k], b.rhs[k]);
  }
  EXPECT_GT(normalPart, 1e-6 * weight);  // the weight does reach the stiffness
  without.basis->setRegularization(0.0);
  without.basis->elementIntegrals(0, plain);
  for (int k = 0; k < 64; ++k) {
    EXPECT_EQ(plain.stiffness[k], without.basis->elementRecord(0).stiffness[packedIndex(k / 8, k % 8)]);
  }
}

// --- the Vox solver ----------------------------------------------------------------------------

TEST(VoxelSolver, FlatSquareWithConstantFieldIsExact) {
  const double h = 0.05;
  const CutMesh s = makeSetup(testing::gridMesh(12, 12, 1.0 / 12), Vec3d(1, 0, 0));
  ParamOptions options;
  options.edgeLength = h;
  const VoxelParamResult result = parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, options, 16);
  const auto& uv = result.param.cornerUV;
  ASSERT_EQ(uv.size(), 3u * s.mesh.numFaces());
  const Vec3d x0 = s.mesh.position(s.mesh.triangles[0][0]);
  for (CornerId c = 0; c < uv.size(); ++c) {
    const Vec3d x = s.mesh.position(s.mesh.triangles[cornerFace(c)][c % 3]);
    EXPECT_NEAR(uv[c][0] - uv[0][0], (x[0] - x0[0]) / h, 1e-7);
    EXPECT_NEAR(uv[c][1] - uv[0][1], (x[1] - x0[1]) / h, 1e-7);
  }
  EXPECT_TRUE(result.markedFaces.empty());
}

TEST(VoxelSolver, CylinderFollowsTheAxisExactlyAndIsSeamless) {
  const int n = 32, m = 8;
  const CutMesh s = cutCylinder(n, m);
  ParamOptions options;
  options.edgeLength = 0.25;
  const VoxelParamResult result = parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, options, 16);
  const auto& uv = result.param.cornerUV;
  // The field is the axis: u = z / h exactly (linear), v goes around.
  for (CornerId c = 0; c < uv.size(); ++c) {
    const Vec3d x = s.mesh.position(s.mesh.triangles[cornerFace(c)][c % 3]);
    EXPECT_NEAR(uv[c][0] - uv[0][0], (x[2] - s.mesh.position(s.mesh.triangles[0][0])[2]) / 0.25,
                1e-7);
  }
  const SeamQuality seams = measureSeams(s.mesh, s.topology, s.cut, uv);
  EXPECT_TRUE(seams.isSeamless()) << seams.maxResidual << " " << seams.maxIntegerDistance;
  // Going once around is a whole number of grid cells near the perimeter / h.
  ASSERT_EQ(result.param.translations.size(), 1u);
  EXPECT_NEAR(std::abs(result.param.translations[0]), 2 * M_PI / 0.25, 1.5);
  EXPECT_EQ(result.determinedBasis, 0u);
}

// DESIGN section 7: only marked (inconsistent or cone-overlapping) basis functions may break
// the seam relation, so seam edges whose faces lie outside their supports are seamless, and every
// translation is a Gaussian integer.
TEST(VoxelSolver, SeamlessAwayFromMarkedFunctions) {
  CutMesh s;
  s.mesh = testing::icosphereMesh(4);
  for (Vec3f& p : s.mesh.positions) p *= 1.0f + 0.15f * std::sin(3.0f * p.x()) * std::cos(2.0f * p.y());
  s.topology = Topology::build(s.mesh.triangles, s.mesh.numVertices());
  s.field = computeSmoothestField(s.mesh, s.topology);
  s.cut = cutToDisk(s.mesh, s.topology, s.field, computeSingularities(s.mesh, s.topology, s.field));
  ASSERT_FALSE(s.cut.seams.empty());
  ParamOptions options;
  options.edgeLength = 0.08;
  const VoxelParamResult result = parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, options, 32);
  const WedgeMap& uv = result.param.cornerUV;
  std::set<FaceId> marked(result.markedFaces.begin(), result.markedFaces.end());
  ASSERT_EQ(result.param.translations.size(), s.cut.seams.size());
  std::size_t checked = 0;
  for (std::size_t i = 0; i < s.cut.seams.size(); ++i) {
    const SeamCurve& seam = s.cut.seams[i];
    const std::complex<double> t = result.param.translations[i];
    EXPECT_NEAR(t.real(), std::round(t.real()), 1e-9);
    EXPECT_NEAR(t.imag(), std::round(t.imag()), 1e-9);
    std::complex<double> r(1.0, 0.0);
    for (int k = 0; k < seam.matching % 4; ++k) r *= std::complex<double>(0.0, -1.0);  // i^(-k)
    for (CornerId c : seam.corners) {
      const CornerId o = s.topology.opposite(c);
      if (marked.count(cornerFace(c)) || marked.count(cornerFace(o))) continue;
      // The edge runs vertex(next c) -> vertex(prev c) on the left, prev o -> next o on the right.
      for (const auto& [left, right] : {std::pair{nextCorner(c), prevCorner(o)}, std::pair{prevCorner(c), nextCorner(o)}}) {
        const std::complex<double> ql(uv[left].x(), uv[left].y()), qr(uv[right].x(), uv[right].y());
        EXPECT_LT(std::abs(qr - (r * ql + t)), 1e-6) << "seam " << i << " corner " << c;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 20u) << "too few unmarked seam edges to show anything";
  EXPECT_LT(marked.size(), s.mesh.numFaces());
}

// Relative L2 difference of the gradients of two per-corner maps.
double relativeGradientDifference(const TriangleMesh& mesh, const WedgeMap& a, const WedgeMap& b,
                                  const std::set<FaceId>& skip = {}) {
  double diff = 0.0, norm = 0.0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (skip.count(f)) continue;
    const Vec3d p[3] = {mesh.position(mesh.triangles[f][0]), mesh.position(mesh.triangles[f][1]),
                        mesh.position(mesh.triangles[f][2])};
    const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    const double area2 = n.norm();
    if (area2 == 0.0) continue;
    Vec3d ga_u = Vec3d::Zero(), ga_v = Vec3d::Zero(), gb_u = Vec3d::Zero(), gb_v = Vec3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vec3d grad = (n / area2).cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / area2;  // grad of hat k
      ga_u += a[3 * f + k].x() * grad, ga_v += a[3 * f + k].y() * grad;
      gb_u += b[3 * f + k].x() * grad, gb_v += b[3 * f + k].y() * grad;
    }
    const double w = 0.5 * area2;
    diff += w * ((ga_u - gb_u).squaredNorm() + (ga_v - gb_v).squaredNorm());
    norm += w * (gb_u.squaredNorm() + gb_v.squaredNorm());
  }
  return std::sqrt(diff / norm);
}

TEST(VoxelSolver, AgreesWithTheHatSolverOnASmoothMesh) {
  const CutMesh s = smoothSphere();
  ParamOptions options;
  options.edgeLength = 0.08;
  const ParamResult hat = parameterizeMesh(s.mesh, s.topology, s.field, s.cut, options);
  double previous = 1.0;
  for (int grid : {32, 64}) {
    const VoxelParamResult vox = parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, options, grid);
    const std::set<FaceId> marked(vox.markedFaces.begin(), vox.markedFaces.end());
    const double all = relativeGradientDifference(s.mesh, vox.param.cornerUV, hat.cornerUV);
    const double unmarked = relativeGradientDifference(s.mesh, vox.param.cornerUV, hat.cornerUV, marked);
    std::printf("grid %d: vox vs hat relative L2 gradient difference %.4f (%.4f off the %zu marked faces)\n",
                grid, all, unmarked, marked.size());
    EXPECT_LT(all, 0.2);
    EXPECT_LT(unmarked, 0.1);
    EXPECT_LT(all, 0.5 * previous) << "a finer grid must come closer to the hat map";
    previous = all;
  }
  // Sanity of the measure: a map and itself differ by 0, a map and its double by 1.
  EXPECT_EQ(relativeGradientDifference(s.mesh, hat.cornerUV, hat.cornerUV), 0.0);
  WedgeMap doubled = hat.cornerUV;
  for (std::uint32_t w = 0; w < doubled.numWedges(); ++w) doubled.setWedgeValue(w, 2.0 * doubled.wedgeValue(w));
  EXPECT_NEAR(relativeGradientDifference(s.mesh, doubled, hat.cornerUV), 1.0, 1e-12);
}

TEST(VoxelSolver, ConesAreMarkedForLocalRefinement) {
  const TriangleMesh mesh = testing::icosphereMesh(3);
  CutMesh s;
  s.mesh = mesh;
  s.topology = Topology::build(s.mesh.triangles, s.mesh.numVertices());
  s.field = computeSmoothestField(s.mesh, s.topology);
  const FieldSingularities singularities = computeSingularities(s.mesh, s.topology, s.field);
  s.cut = cutToDisk(s.mesh, s.topology, s.field, singularities);
  ASSERT_FALSE(s.cut.cones.empty());
  ParamOptions options;
  options.edgeLength = 0.1;
  const VoxelParamResult result = parameterizeMeshVoxel(s.mesh, s.topology, s.field, s.cut, options, 16);
  EXPECT_GT(result.determinedBasis, 0u);
  std::set<FaceId> marked(result.markedFaces.begin(), result.markedFaces.end());
  for (VertexId cone : s.cut.cones) {
    s.topology.forEachCornerAround(cone, [&](CornerId c) {
      EXPECT_TRUE(marked.count(cornerFace(c))) << "face around cone " << cone;
    });
  }
  EXPECT_LT(marked.size(), s.mesh.numFaces());
}

TEST(VoxelGrid, OrderByBlocksGivesEachLeafConsecutiveIds) {
  VoxelGrid grid;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coordinate(-40, 40);
  std::vector<VoxelCoord> inserted;
  for (int i = 0; i < 3000; ++i) {
    const VoxelCoord v{coordinate(rng), coordinate(rng), coordinate(rng)};
    if (grid.insert(v) == inserted.size()) inserted.push_back(v);
  }
  const std::vector<std::uint32_t> remap = grid.orderByBlocks();
  ASSERT_EQ(remap.size(), inserted.size());
  std::vector<std::uint32_t> sorted = remap;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i) << "not a permutation";
  for (std::uint32_t old = 0; old < inserted.size(); ++old) {
    EXPECT_EQ(grid.coords()[remap[old]], inserted[old]);
    EXPECT_EQ(grid.find(inserted[old]), remap[old]);
  }
  const std::vector<std::uint32_t>& starts = grid.blockStarts();
  ASSERT_GE(starts.size(), 2u);
  EXPECT_EQ(starts.front(), 0u);
  EXPECT_EQ(starts.back(), inserted.size());
  auto leaf = [](const VoxelCoord& v) { return std::array<int, 3>{v[0] >> 3, v[1] >> 3, v[2] >> 3}; };
  std::set<std::array<int, 3>> leaves;
  for (std::size_t b = 0; b + 1 < starts.size(); ++b) {
    ASSERT_LT(starts[b], starts[b + 1]) << "empty block " << b;
    const auto key = leaf(grid.coords()[starts[b]]);
    EXPECT_TRUE(leaves.insert(key).second) << "two blocks in one leaf";
    for (std::uint32_t id = starts[b]; id < starts[b + 1]; ++id) EXPECT_EQ(leaf(grid.coords()[id]), key);
  }
}

/// Forwards a basis' elements without its blocks: the assembly then takes fixed-size ranges.
class WithoutBlocks final : public Basis {
 public:
  explicit WithoutBlocks(const Basis& basis) : basis_(basis) {}
  std::uint64_t numElements() const override { return basis_.numElements(); }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override {
    return basis_.elementDomains(e, out);
  }
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override { basis_.elementIntegrals(e, out); }
  void evaluateCorners(const std::vector<std::complex<double>>& c, WedgeMap& uv) const override {
    basis_.evaluateCorners(c, uv);
  }

 private:
  const Basis& basis_;
};

TEST(VoxelSolver, BlockByBlockAssemblyEqualsElementRanges) {
  const CutMesh s = smoothSphere();
  const VoxelBuildResult built = build(s, 32, 0.1, 1e-5);
  const std::vector<std::uint64_t> blocks = built.basis->elementBlocks();
  ASSERT_GE(blocks.size(), 3u) << "the grid should have several leaf blocks";
  EXPECT_EQ(blocks.back(), built.basis->numElements());
  for (std::size_t b = 0; b + 1 < blocks.size(); ++b) {
    const VoxelCoord first = built.basis->elementVoxel(blocks[b]);
    for (std::uint64_t e = blocks[b]; e < blocks[b + 1]; ++e) {
      const VoxelCoord v = built.basis->elementVoxel(e);
      ASSERT_TRUE(v[0] >> 3 == first[0] >> 3 && v[1] >> 3 == first[1] >> 3 && v[2] >> 3 == first[2] >> 3)
          << "element " << e << " of block " << b << " lies in another leaf";
    }
  }
  const Reduction reduction = reduceBasis(*built.basis);
  const LinearSystem byBlocks = assembleSystem(*built.basis, reduction);
  const LinearSystem byRanges = assembleSystem(WithoutBlocks(*built.basis), reduction);
  auto largest = [](const ComplexSparse& m) {
    double most = 0.0;
    for (int j = 0; j < m.outerSize(); ++j) {
      for (ComplexSparse::InnerIterator it(m, j); it; ++it) most = std::max(most, std::abs(it.value()));
    }
    return most;
  };
  const double scale = largest(byRanges.lower);
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(largest(byBlocks.lower - byRanges.lower), 1e-12 * scale);
  EXPECT_LT((byBlocks.rhs - byRanges.rhs).cwiseAbs().maxCoeff(), 1e-12 * byRanges.rhs.cwiseAbs().maxCoeff());
  EXPECT_NEAR(byBlocks.totalArea, byRanges.totalArea, 1e-12 * byRanges.totalArea);
}

TEST(VoxelSolver, OneEvaluationPerWedgeEqualsOnePerCorner) {
  // The solved coefficients evaluated once per wedge of the cut, and at every corner on its own
  // (a map with one wedge per corner): the same map to rounding, with far fewer wedges.
  const CutMesh s = smoothSphere();
  const VoxelBuildResult built = build(s, 32, 0.1, 1e-5);
  const Reduction reduction = reduceBasis(*built.basis);
  const SeamlessSolution solution = solveSeamless(*built.basis, reduction);
  WedgeMap perWedge = buildCutWedges(s.topology, s.cut);
  evaluateMap(*built.basis, reduction, solution.unknowns, perWedge);
  std::vector<std::uint32_t> own(s.topology.numCorners());
  for (CornerId c = 0; c < own.size(); ++c) own[c] = c;
  WedgeMap perCorner(std::move(own), std::vector<Vec2d>(s.topology.numCorners(), Vec2d::Zero()));
  evaluateMap(*built.basis, reduction, solution.unknowns, perCorner);
  EXPECT_LT(perWedge.numWedges(), perCorner.numWedges() / 5);
  double largest = 0.0, difference = 0.0;
  for (CornerId c = 0; c < perCorner.size(); ++c) {
    largest = std::max(largest, perCorner[c].norm());
    difference = std::max(difference, (perWedge[c] - perCorner[c]).norm());
  }
  EXPECT_GT(largest, 1.0);
  EXPECT_LT(difference, 1e-9 * largest);
}

// The voxel map of a noisy scan (scanner noise of half an edge) re-evaluated at the
// field's smoothed surface where it folds: fewer folded faces, still seamless, and only vertices
// without a seam through them, near the faces first folded, move (smoothed_evaluation.h).
TEST(SmoothedEvaluation, NoiseFoldsFewerFacesAndOnlyOneWedgeVerticesMove) {
  TriangleMesh noisy = testing::generatedMesh(MeshKind::Scan, 30000);
  ScanNoiseOptions noise;
  noise.amplitude = 0.5;  // a quarter of an edge folds only the generated scan's cone and border faces
  addScanNoise(noisy, noise);
  CleanResult clean = cleanMesh(std::move(noisy));
  const TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  const CrossField field = computeCrossField(mesh, topology, FieldMethod::Proxy);
  ASSERT_GT(field.frameSmoothing, 0u);
  const CutResult cut = cutToDisk(mesh, topology, field, computeSingularities(mesh, topology, field));
  ParamOptions options;
  options.edgeLength = computeBoundingBox(mesh.positions).diagonal() / 25.0;
  const double h = options.edgeLength;
  options.smoothedEvaluation = false;
  const VoxelParamResult raw = parameterizeMeshVoxel(mesh, topology, field, cut, options, 32);
  options.smoothedEvaluation = true;
  const VoxelParamResult smoothed = parameterizeMeshVoxel(mesh, topology, field, cut, options, 32);
  const auto foldedFaces = [&](const WedgeMap& uv) {
    std::vector<FaceId> out;
    for (FaceId f = 0; f < mesh.numFaces(); ++f) {
      const Triangle& t = mesh.triangles[f];
      if (foldedForSmoothedEvaluation({mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])},
                                      {uv[3 * f], uv[3 * f + 1], uv[3 * f + 2]}, h)) {
        out.push_back(f);
      }
    }
    return out;
  };
  const std::vector<FaceId> before = foldedFaces(raw.param.cornerUV), after = foldedFaces(smoothed.param.cornerUV);
  EXPECT_EQ(raw.smoothedEvaluation.vertices, 0u);
  EXPECT_EQ(smoothed.smoothedEvaluation.foldedBefore, before.size());
  ASSERT_GT(before.size(), 100u) << "the noise folds too few faces: the test proves nothing";
  EXPECT_LT(2 * after.size(), before.size());  // measured 1,150 -> 305
  EXPECT_TRUE(measureSeams(mesh, topology, cut, raw.param.cornerUV).isSeamless());
  EXPECT_TRUE(measureSeams(mesh, topology, cut, smoothed.param.cornerUV).isSeamless());
  // The vertices within kSmoothedEvaluationRounds - 1 rings of the faces first folded.
  std::vector<std::uint8_t> near(topology.numVertices(), 0);
  std::vector<VertexId> frontier;
  for (FaceId f : before) {
    for (VertexId v : mesh.triangles[f]) near[v] = 1, frontier.push_back(v);
  }
  for (std::uint32_t ring = 1; ring < kSmoothedEvaluationRounds; ++ring) {
    std::vector<VertexId> next;
    for (VertexId v : frontier) {
      topology.forEachCornerAround(v, [&](CornerId c) {
        for (VertexId w : mesh.triangles[cornerFace(c)]) {
          if (!near[w]) near[w] = 1, next.push_back(w);
        }
      });
    }
    frontier = std::move(next);
  }
  std::vector<std::uint8_t> changed(topology.numVertices(), 0);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    if (raw.param.cornerUV[c] != smoothed.param.cornerUV[c]) changed[topology.vertex(c)] = 1;
  }
  std::uint64_t moved = 0;
  for (VertexId v = 0; v < topology.numVertices(); ++v) {
    if (!changed[v]) continue;
    ++moved;
    EXPECT_TRUE(near[v]) << "vertex " << v;
    std::set<std::uint32_t> wedges;
    topology.forEachCornerAround(v, [&](CornerId c) { wedges.insert(smoothed.param.cornerUV.wedge(c)); });
    EXPECT_EQ(wedges.size(), 1u) << "vertex " << v;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_LE(moved, smoothed.smoothedEvaluation.vertices);
  // A few vertices at a time (a noisy scan's millions go in batches): the same map, bit for bit.
  options.smoothedBatchVertices = 7;
  const VoxelParamResult batched = parameterizeMeshVoxel(mesh, topology, field, cut, options, 32);
  ASSERT_GT(smoothed.smoothedEvaluation.vertices, 10u * options.smoothedBatchVertices);
  EXPECT_EQ(batched.smoothedEvaluation.vertices, smoothed.smoothedEvaluation.vertices);
  EXPECT_EQ(batched.smoothedEvaluation.keptForStretch, smoothed.smoothedEvaluation.keptForStretch);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    ASSERT_EQ(batched.param.cornerUV[c], smoothed.param.cornerUV[c]) << "corner " << c;
  }
}

}  // namespace
}  // namespace seamvox
