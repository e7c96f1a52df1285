// Assembly of the reduced system (core/solve/assemble): K = P* L P is Hermitian and equals a
// directly assembled cotangent Laplacian taken through P; x* K x - 2 Re(x* rhs) is the energy
// sum_T A_T |grad q - w_T / h|^2 up to a constant; constants are in the kernel without seams;
// restrictSystem moves fixed unknowns to the right-hand side.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <complex>
#include <random>
#include <vector>

#include "core/basis/basis.h"
#include "core/basis/reduce.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/solve/assemble.h"
#include "tests/test_meshes.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

Eigen::MatrixXcd denseP(const Reduction& reduction, std::uint32_t numDomains) {
  Eigen::MatrixXcd P = Eigen::MatrixXcd::Zero(numDomains, reduction.numUnknowns());
  for (std::uint32_t d = 0; d < numDomains; ++d) {
    for (std::uint64_t k = reduction.map.rowStart[d]; k < reduction.map.rowStart[d + 1]; ++k) {
      P(d, reduction.map.column[k]) += reduction.map.value[k];
    }
  }
  return P;
}

// The full Hermitian matrix from its stored lower triangle.
Eigen::MatrixXcd denseFull(const ComplexSparse& lower) {
  const Eigen::MatrixXcd L = Eigen::MatrixXcd(lower);
  Eigen::MatrixXcd K = L + L.adjoint();
  K.diagonal() -= L.diagonal();
  return K;
}

// Cotangent Laplacian over the hat basis' domains, written out from the angles of each face.
Eigen::MatrixXd cotangentLaplacian(const TriangleMesh& mesh, const HatBasis& basis) {
  const std::uint32_t nd = basis.numDomains();
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(nd, nd);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = mesh.position(mesh.triangles[f][k]);
      const Vec3d a = mesh.position(mesh.triangles[f][(k + 1) % 3]) - p;
      const Vec3d b = mesh.position(mesh.triangles[f][(k + 2) % 3]) - p;
      const double w = 0.5 * a.dot(b) / a.cross(b).norm();  // half the cotangent at corner k
      const std::uint32_t i = basis.cornerDomain()[3 * f + (k + 1) % 3];
      const std::uint32_t j = basis.cornerDomain()[3 * f + (k + 2) % 3];
      L(i, i) += w, L(j, j) += w, L(i, j) -= w, L(j, i) -= w;
    }
  }
  return L;
}

// sum_T A_T |grad q - w_T / h|^2 for domain coefficients c, from the hat gradients
// n x (opposite edge) / 2A and the combed direction u (v = n x u).
double directEnergy(const TriangleMesh& mesh, const HatBasis& basis, const CrossField& field,
                    const CutResult& cut, double h, const std::vector<Complex>& c) {
  double energy = 0.0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    Vec3d p[3];
    for (int k = 0; k < 3; ++k) p[k] = mesh.position(mesh.triangles[f][k]);
    const Vec3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
    const double area = 0.5 * cross.norm();
    const Vec3d n = cross.normalized();
    Vec3d u = field.at(f);
    for (int k = 0; k < cut.faceRotation[f] % 4; ++k) u = n.cross(u);
    const Vec3d v = n.cross(u);
    Vec3d gradRe = Vec3d::Zero(), gradIm = Vec3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vec3d g = n.cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / (2.0 * area);
      const Complex ck = c[basis.cornerDomain()[3 * f + k]];
      gradRe += ck.real() * g;
      gradIm += ck.imag() * g;
    }
    energy += area * ((gradRe - u / h).squaredNorm() + (gradIm - v / h).squaredNorm());
  }
  return energy;
}

// A torus with a random field: many cones, seams with every rotation, determined positions.
struct SeamedTorus : testing::CutSurface {
  SeamedTorus() : CutSurface(testing::makeCutSurface(testing::torusMesh(10, 6), 3)) {}
};

TEST(Assemble, HermitianAndEqualToCotangentLaplacianThroughP) {
  const SeamedTorus t;
  ASSERT_FALSE(t.cut.seams.empty());
  HatBasisOptions options;
  options.edgeLength = 0.3;
  const HatBasis basis(t.s.mesh, t.s.topology, t.field, t.cut, options);
  const Reduction reduction = reduceBasis(basis);
  ASSERT_GT(reduction.numTranslational, 0u);
  const LinearSystem system = assembleSystem(basis, reduction);
  // Only the lower triangle is stored; its diagonal is real.
  for (int j = 0; j < system.lower.outerSize(); ++j) {
    for (ComplexSparse::InnerIterator it(system.lower, j); it; ++it) {
      ASSERT_GE(it.row(), j);
      if (it.row() == j) EXPECT_NEAR(it.value().imag(), 0.0, 1e-12);
    }
  }
  const Eigen::MatrixXcd K = denseFull(system.lower);
  const Eigen::MatrixXcd P = denseP(reduction, basis.numDomains());
  const Eigen::MatrixXcd expected =
      P.adjoint() * cotangentLaplacian(t.s.mesh, basis).cast<Complex>() * P;
  EXPECT_LT((K - expected).cwiseAbs().maxCoeff(), 1e-10 * expected.cwiseAbs().maxCoeff());
  EXPECT_LT((K - K.adjoint()).cwiseAbs().maxCoeff(), 1e-12);
  // Positive semidefinite: no eigenvalue below rounding.
  const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(K).eigenvalues();
  EXPECT_GT(eigenvalues.minCoeff(), -1e-9 * eigenvalues.maxCoeff());
  double area = 0.0;
  for (FaceId f = 0; f < t.s.mesh.numFaces(); ++f) area += faceArea(t.s.mesh, f);
  EXPECT_NEAR(system.totalArea, area, 1e-9 * area);
}

TEST(Assemble, RhsMatchesTheEnergyItMinimises) {
  const SeamedTorus t;
  const double h = 0.3;
  HatBasisOptions options;
  options.edgeLength = h;
  const HatBasis basis(t.s.mesh, t.s.topology, t.field, t.cut, options);
  const Reduction reduction = reduceBasis(basis);
  const LinearSystem system = assembleSystem(basis, reduction);
  const Eigen::MatrixXcd K = denseFull(system.lower);
  const std::uint32_t n = reduction.numUnknowns();
  const double e0 = directEnergy(t.s.mesh, basis, t.field, t.cut, h,
                                 expandCoefficients(reduction, std::vector<Complex>(n, 0.0)));
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> value(-2.0, 2.0);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<Complex> x(n);
    for (Complex& xi : x) xi = Complex(value(rng), value(rng));
    const Eigen::VectorXcd xv = Eigen::Map<const Eigen::VectorXcd>(x.data(), n);
    const double quadratic = (xv.adjoint() * K * xv)(0).real() - 2.0 * xv.dot(system.rhs).real();
    const double direct =
        directEnergy(t.s.mesh, basis, t.field, t.cut, h, expandCoefficients(reduction, x)) - e0;
    EXPECT_NEAR(quadratic, direct, 1e-9 * std::max(1.0, std::abs(direct)));
  }
  // And rhs = P* (b - L offset) with b and L summed per domain from the element integrals.
  const std::uint32_t nd = basis.numDomains();
  Eigen::MatrixXcd L = Eigen::MatrixXcd::Zero(nd, nd);
  Eigen::VectorXcd b = Eigen::VectorXcd::Zero(nd), offset = Eigen::VectorXcd::Zero(nd);
  ElementIntegrals el;
  for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
    basis.elementIntegrals(e, el);
    for (std::uint32_t a = 0; a < el.count; ++a) {
      b[el.domain[a]] += el.rhs[a];
      for (std::uint32_t c = 0; c < el.count; ++c) L(el.domain[a], el.domain[c]) += el.stiffness[el.count * a + c];
    }
  }
  for (std::uint32_t d = 0; d < nd && !reduction.map.offset.empty(); ++d) offset[d] = reduction.map.offset[d];
  const Eigen::MatrixXcd P = denseP(reduction, nd);
  const Eigen::VectorXcd expectedRhs = P.adjoint() * (b - L * offset);
  EXPECT_LT((system.rhs - expectedRhs).cwiseAbs().maxCoeff(), 1e-10 * expectedRhs.cwiseAbs().maxCoeff());
}

TEST(Assemble, ConstantsAreInTheKernelWithoutRotations) {
  // Flat grid cut along its boundary; cylinder with the axis field (one seam, r = 1).
  std::vector<std::pair<testing::Surface, CrossField>> cases;
  {
    testing::Surface grid = testing::makeSurface(testing::gridMesh(6, 5));
    CrossField field = testing::constantField(grid.mesh, Vec3d(1, 2, 0));
    cases.emplace_back(std::move(grid), std::move(field));
    testing::Surface cylinder = testing::makeSurface(testing::cylinderMesh(10, 4));
    CrossField axis = testing::constantField(cylinder.mesh, Vec3d::UnitZ());
    cases.emplace_back(std::move(cylinder), std::move(axis));
  }
  for (const auto& [s, field] : cases) {
    const CutResult cut = cutToDisk(s.mesh, s.topology, field, computeSingularities(s.mesh, s.topology, field));
    const HatBasis basis(s.mesh, s.topology, field, cut, {});
    for (std::uint8_t r : basis.seamRotation()) ASSERT_EQ(r % 4, 0);
    const Reduction reduction = reduceBasis(basis);
    ASSERT_TRUE(reduction.map.offset.empty());
    const LinearSystem system = assembleSystem(basis, reduction);
    const Eigen::MatrixXcd K = denseFull(system.lower);
    Eigen::VectorXcd constant = Eigen::VectorXcd::Zero(reduction.numUnknowns());
    constant.head(reduction.numPositional).setConstant(Complex(0.7, -1.3));
    for (const Complex& c : expandCoefficients(reduction, std::vector<Complex>(constant.data(), constant.data() + constant.size()))) {
      EXPECT_NEAR(std::abs(c - Complex(0.7, -1.3)), 0.0, 1e-12) << "x is a constant map";
    }
    EXPECT_LT((K * constant).norm(), 1e-10 * K.norm());
    // The rhs is orthogonal to the constants too (the target has no average to fit).
    EXPECT_LT(std::abs(constant.dot(system.rhs)), 1e-9 * system.rhs.norm() * constant.norm());
  }
}

TEST(Assemble, RestrictedSystemMovesFixedUnknownsToTheRhs) {
  const SeamedTorus t;
  const HatBasis basis(t.s.mesh, t.s.topology, t.field, t.cut, {});
  const Reduction reduction = reduceBasis(basis);
  const LinearSystem system = assembleSystem(basis, reduction);
  const std::uint32_t n = reduction.numUnknowns();
  std::mt19937 rng(5);
  std::bernoulli_distribution pick(0.3);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<std::uint8_t> fixed(n);
  std::vector<Complex> values(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    fixed[i] = pick(rng);
    values[i] = fixed[i] ? Complex(value(rng), value(rng)) : Complex(0.0);
  }
  const RestrictedSystem restricted = restrictSystem(system, fixed, values);
  const Eigen::MatrixXcd K = denseFull(system.lower);
  const Eigen::VectorXcd x = Eigen::Map<const Eigen::VectorXcd>(values.data(), n);
  const Eigen::VectorXcd fullRhs = system.rhs - K * x;  // free rows: rhs_f - K_fx x_x
  ASSERT_EQ(restricted.freeUnknowns.size(), static_cast<std::size_t>(std::count(fixed.begin(), fixed.end(), 0)));
  const Eigen::MatrixXcd Kf = denseFull(restricted.lower);
  for (std::size_t a = 0; a < restricted.freeUnknowns.size(); ++a) {
    const std::uint32_t i = restricted.freeUnknowns[a];
    ASSERT_FALSE(fixed[i]);
    EXPECT_LT(std::abs(restricted.rhs[a] - fullRhs[i]), 1e-10);
    for (std::size_t b = 0; b < restricted.freeUnknowns.size(); ++b) {
      EXPECT_EQ(Kf(a, b), K(i, restricted.freeUnknowns[b]));
    }
  }
}

// The elements are summed in chunks merged in a fixed tree: the same system, up to rounding,
// whatever the number of chunks, and bit for bit the same on every run.
TEST(Assemble, FewerChunksGiveTheSameSystem) {
  const testing::CutSurface c = testing::makeCutSurface(testing::torusMesh(96, 48));
  HatBasisOptions options;
  options.edgeLength = 0.3;
  const HatBasis basis(c.s.mesh, c.s.topology, c.field, c.cut, options);
  const Reduction reduction = reduceBasis(basis);
  ASSERT_GT(basis.numElements(), 2u * 4096u);  // three ranges of elements: three chunks by default
  AssembleOptions few;
  few.fewChunksAbove = 0;
  const LinearSystem a = assembleSystem(basis, reduction), b = assembleSystem(basis, reduction, few);
  const LinearSystem again = assembleSystem(basis, reduction, few);
  const auto largest = [](const ComplexSparse& m) {
    double x = 0.0;
    for (int k = 0; k < m.nonZeros(); ++k) x = std::max(x, std::abs(m.valuePtr()[k]));
    return x;
  };
  const ComplexSparse difference = a.lower - b.lower;
  EXPECT_LT(largest(difference), 1e-12 * largest(a.lower));
  EXPECT_LT((a.rhs - b.rhs).cwiseAbs().maxCoeff(), 1e-12 * a.rhs.cwiseAbs().maxCoeff());
  EXPECT_EQ(largest(again.lower - b.lower), 0.0);
  EXPECT_EQ(again.rhs, b.rhs);
  EXPECT_GT(largest(difference) + (a.rhs - b.rhs).cwiseAbs().maxCoeff(), 0.0)
      << "the chunks did not change the summation order: the test checks nothing";
}

}  // namespace
}  // namespace seamvox
