// Reduction over Z[i]: BFS maps, cycle constraints, cones, unimodular elimination.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <complex>
#include <random>

#include "core/system/errors.h"
#include "core/basis/gaussian_int.h"
#include "core/basis/reduce.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

// A basis given directly by its domains and seam adjacency (no elements): the reduction's input.
class GraphBasis final : public Basis {
 public:
  GraphBasis(std::vector<std::uint32_t> domainBasis, std::vector<DomainAdjacency> adjacency,
             std::vector<std::uint8_t> seamRotation) {
    domainBasis_ = std::move(domainBasis);
    numBasisFunctions_ = 0;
    for (auto b : domainBasis_) numBasisFunctions_ = std::max(numBasisFunctions_, b + 1);
    adjacencies_ = std::move(adjacency);
    seamRotation_ = std::move(seamRotation);
  }
  std::uint64_t numElements() const override { return 0; }
  std::uint32_t elementDomains(std::uint64_t, std::uint32_t*) const override { return 0; }
  void elementIntegrals(std::uint64_t, ElementIntegrals& out) const override { out.count = 0; }
  void evaluateCorners(const std::vector<Complex>&, WedgeMap&) const override {}
};

std::vector<Complex> randomIntegerUnknowns(const Reduction& red, std::mt19937& rng) {
  std::uniform_int_distribution<int> pick(-5, 5);
  std::uniform_real_distribution<double> real(-3.0, 3.0);
  std::vector<Complex> x(red.numUnknowns());
  for (std::uint32_t j = 0; j < red.numUnknowns(); ++j) {
    x[j] = j < red.numPositional ? Complex(real(rng), real(rng)) : Complex(pick(rng), pick(rng));
  }
  return x;
}

// Every adjacency holds as c_right = r c_left + t and every t is a Gaussian integer.
void expectSeamless(const GraphBasis& basis, const Reduction& red, std::uint64_t seed) {
  std::mt19937 rng(static_cast<std::uint32_t>(seed));
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<Complex> x = randomIntegerUnknowns(red, rng);
    const std::vector<Complex> c = expandCoefficients(red, x);
    const std::vector<Complex> s(x.begin() + red.numPositional, x.end());
    const std::vector<Complex> t = seamTranslations(red, s);
    for (const Complex& ti : t) EXPECT_LT(gaussianIntegerDistance(ti), 1e-12);
    for (const DomainAdjacency& e : basis.adjacencies()) {
      const Complex r = unitPower(basis.seamRotation()[e.seam]).toComplex();
      EXPECT_LT(std::abs(c[e.right] - (r * c[e.left] + t[e.seam])), 1e-9)
          << "adjacency " << e.left << " -> " << e.right << " across seam " << e.seam;
    }
  }
}

TEST(GaussInt, ArithmeticAndRoundedDivision) {
  EXPECT_EQ(GaussInt(1, 1) * GaussInt(1, -1), GaussInt(2));
  EXPECT_EQ(unitPower(-1), GaussInt(0, -1));
  EXPECT_EQ(unitPower(6), GaussInt(-1));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(-40, 40);
  for (int k = 0; k < 2000; ++k) {
    const GaussInt a(pick(rng), pick(rng)), b(pick(rng), pick(rng));
    if (b.isZero()) continue;
    const GaussInt q = divideRounded(a, b);
    EXPECT_LE(2 * (a - q * b).norm(), b.norm()) << a.re << "+" << a.im << "i / " << b.re << "+" << b.im << "i";
  }
  EXPECT_NEAR(gaussianIntegerDistance({2.25, -0.75}), std::hypot(0.25, 0.25), 1e-15);
}

TEST(Reduce, VertexInsideSeamHasNoConstraint) {
  // Two wedges on either side of one seam, joined by both seam edges at the vertex.
  const GraphBasis basis({0, 0}, {{0, 1, 0}, {0, 1, 0}}, {1});
  const Reduction red = reduceBasis(basis);
  EXPECT_TRUE(red.cycleConstraints.empty());
  EXPECT_TRUE(red.determinedBasis.empty());
  EXPECT_EQ(red.numPositional, 1u);
  EXPECT_EQ(red.numTranslational, 1u);
  expectSeamless(basis, red, 1);
}

TEST(Reduce, ConeAtSeamTipIsDetermined) {
  for (std::uint8_t k : {1, 2, 3}) {  // r = i^k != 1
    // One wedge touching the seam from both sides: c0 = r c0 + t, so c0 = t / (1 - r).
    const GraphBasis basis({0}, {{0, 0, 0}}, {k});
    const Reduction red = reduceBasis(basis);
    ASSERT_EQ(red.determinedBasis.size(), 1u);
    EXPECT_EQ(red.numPositional, 0u);
    ASSERT_EQ(red.numTranslational, 1u);
    const Complex r = unitPower(k).toComplex();
    for (Complex s : {Complex(1, 0), Complex(2, -3)}) {
      const std::vector<Complex> c = expandCoefficients(red, {s});
      const Complex t = seamTranslations(red, {s})[0];
      EXPECT_LT(std::abs(c[0] - t / (1.0 - r)), 1e-12);
    }
    expectSeamless(basis, red, k);
  }
}

TEST(Reduce, RegularNodeOfThreeSeamsGivesOneUnitConstraint) {
  // Rotations i, i, -1 compose to 1: a regular (non-cone) node.
  const GraphBasis basis({0, 0, 0}, {{0, 1, 0}, {1, 2, 1}, {2, 0, 2}}, {1, 1, 2});
  const Reduction red = reduceBasis(basis);
  ASSERT_EQ(red.cycleConstraints.size(), 1u);
  EXPECT_EQ(red.cycleConstraints[0].size(), 3u);
  for (const auto& [seam, coefficient] : red.cycleConstraints[0]) EXPECT_TRUE(coefficient.isUnit());
  EXPECT_EQ(red.nonUnitConstraints, 0u);
  EXPECT_TRUE(red.determinedBasis.empty());
  EXPECT_EQ(red.numPositional, 1u);
  EXPECT_EQ(red.numTranslational, 2u);
  expectSeamless(basis, red, 7);
}

TEST(Reduce, ConeOfThreeSeamsIsDeterminedNotConstrained) {
  // Rotations i, i, i compose to -i: a cone; its position is fixed by the translations.
  const GraphBasis basis({0, 0, 0}, {{0, 1, 0}, {1, 2, 1}, {2, 0, 2}}, {1, 1, 1});
  const Reduction red = reduceBasis(basis);
  EXPECT_TRUE(red.cycleConstraints.empty());
  EXPECT_EQ(red.determinedBasis.size(), 1u);
  EXPECT_EQ(red.numTranslational, 3u);
  expectSeamless(basis, red, 11);
}

// Integer solutions of the constraints in a box are exactly the t = U s with s integer.
void expectLatticeExact(const std::vector<GaussVector>& constraints, std::uint32_t n,
                        const LatticeEliminator& lattice) {
  const std::uint32_t k = lattice.numFree();
  Eigen::MatrixXcd U = Eigen::MatrixXcd::Zero(n, k);
  for (std::uint32_t i = 0; i < n; ++i) {
    for (const auto& [j, x] : lattice.row(i)) U(i, j) = x.toComplex();
  }
  auto satisfies = [&](const Eigen::VectorXcd& t) {
    for (const GaussVector& row : constraints) {
      Complex sum = 0.0;
      for (const auto& [i, c] : row) sum += c.toComplex() * t[i];
      if (std::abs(sum) > 1e-9) return false;
    }
    return true;
  };
  // (a) every integer s gives an integer solution.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> pick(-4, 4);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::VectorXcd s(k);
    for (std::uint32_t j = 0; j < k; ++j) s[j] = Complex(pick(rng), pick(rng));
    EXPECT_TRUE(satisfies(U * s));
  }
  // (b) every integer solution in a box has an integer s.
  const int range = 2, side = 2 * range + 1, values = side * side;
  std::uint64_t total = 1, found = 0;
  for (std::uint32_t i = 0; i < n; ++i) total *= values;
  const auto solver = U.colPivHouseholderQr();
  for (std::uint64_t code = 0; code < total; ++code) {
    Eigen::VectorXcd t(n);
    std::uint64_t rest = code;
    for (std::uint32_t i = 0; i < n; ++i) {
      const int v = static_cast<int>(rest % values);
      rest /= values;
      t[i] = Complex(v % side - range, v / side - range);
    }
    if (!satisfies(t)) continue;
    ++found;
    const Eigen::VectorXcd s = solver.solve(t);
    ASSERT_LT((U * s - t).norm(), 1e-9) << "solution not in the span of U";
    for (std::uint32_t j = 0; j < k; ++j) ASSERT_LT(gaussianIntegerDistance(s[j]), 1e-9) << "lost integrality";
  }
  EXPECT_GT(found, 1u);
}

TEST(Reduce, NonUnitConstraintKeepsIntegrality) {
  const std::vector<std::vector<GaussVector>> cases = {
      {{{0, GaussInt(2)}, {1, GaussInt(1)}}},                       // 2 t0 + t1 = 0
      {{{0, GaussInt(2)}, {1, GaussInt(1, 1)}}},                    // 2 t0 + (1+i) t1 = 0
      {{{0, GaussInt(2)}, {1, GaussInt(1, 1)}, {2, GaussInt(3)}}},  // three terms, gcd 1
      {{{0, GaussInt(2)}, {1, GaussInt(-2)}}},                      // 2 t0 = 2 t1
      {{{0, GaussInt(1, 1)}, {1, GaussInt(2)}}, {{1, GaussInt(1)}, {2, GaussInt(-1, 1)}}},
  };
  for (const auto& constraints : cases) {
    const std::uint32_t n = 3;
    LatticeEliminator lattice(n);
    for (const GaussVector& row : constraints) EXPECT_TRUE(lattice.addConstraint(row));
    bool anyUnit = false;  // a row with a unit coefficient reduces in one step
    for (const auto& [i, c] : constraints[0]) anyUnit = anyUnit || c.isUnit();
    if (!anyUnit) EXPECT_GT(lattice.nonUnitConstraints(), 0u);
    lattice.finish();
    EXPECT_EQ(lattice.numFree(), n - constraints.size());
    expectLatticeExact(constraints, n, lattice);
  }
}

TEST(Reduce, RedundantConstraintRemovesNothing) {
  LatticeEliminator lattice(3);
  EXPECT_TRUE(lattice.addConstraint({{0, GaussInt(1)}, {1, GaussInt(-1)}}));
  EXPECT_TRUE(lattice.addConstraint({{1, GaussInt(1)}, {2, GaussInt(0, 1)}}));
  EXPECT_FALSE(lattice.addConstraint({{0, GaussInt(1)}, {2, GaussInt(0, 1)}}));
  lattice.finish();
  EXPECT_EQ(lattice.numFree(), 1u);
}

TEST(Reduce, TwoConesSharingSeamsGiveNonUnitConstraint) {
  // One wedge closing on seam 0 with r = i and on seam 1 with r = -1:
  // (1 - i) c0 = t0 and 2 c0 = t1, so t1 = (1 + i) t0: a constraint with coefficients 2, 1 - i.
  const GraphBasis basis({0}, {{0, 0, 0}, {0, 0, 1}}, {1, 2});
  const Reduction red = reduceBasis(basis);
  ASSERT_EQ(red.cycleConstraints.size(), 1u);
  EXPECT_EQ(red.nonUnitConstraints, 1u);
  EXPECT_EQ(red.numTranslational, 1u);
  expectSeamless(basis, red, 13);
  // t0 = 1 must be reachable with integer s (nothing lost): t1 = 1 + i then.
  const std::vector<Complex> t = seamTranslations(red, {Complex(1, 0)});
  EXPECT_NEAR(std::abs(t[0]), 1.0, 1e-12);
  EXPECT_LT(std::abs(t[1] - (1.0 + Complex(0, 1)) * t[0]), 1e-12);
}

TEST(Reduce, RejectsAdjacencyAcrossBasisFunctions) {
  const GraphBasis basis({0, 1}, {{0, 1, 0}}, {0});
  EXPECT_THROW(reduceBasis(basis), InputError);
}

}  // namespace
}  // namespace seamvox
