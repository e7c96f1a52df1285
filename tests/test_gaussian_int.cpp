// Gaussian integers and the unimodular elimination (core/basis/gaussian_int): Euclid's algorithm
// on random Gaussian integers; C U = 0, U primitive, and integer solutions exactly t = U s,
// checked against brute-force enumeration on small systems.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <complex>
#include <cstdlib>
#include <random>
#include <vector>

#include "core/basis/gaussian_int.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

GaussInt randomGauss(std::mt19937& rng, int range) {
  std::uniform_int_distribution<int> pick(-range, range);
  return {pick(rng), pick(rng)};
}

// Whether b divides a exactly in Z[i].
bool divides(GaussInt b, GaussInt a) {
  if (b.isZero()) return a.isZero();
  return a - divideRounded(a, b) * b == GaussInt(0);
}

// Euclid's algorithm through divideRounded; returns g and Bezout factors x, y with a x + b y = g.
GaussInt gcdBezout(GaussInt a, GaussInt b, GaussInt* x, GaussInt* y) {
  GaussInt x0 = 1, y0 = 0, x1 = 0, y1 = 1;
  while (!b.isZero()) {
    const GaussInt q = divideRounded(a, b);
    const GaussInt r = a - q * b;
    EXPECT_LE(2 * r.norm(), b.norm()) << "remainder not below half the divisor's norm";
    a = b, b = r;
    const GaussInt x2 = x0 - q * x1, y2 = y0 - q * y1;
    x0 = x1, y0 = y1, x1 = x2, y1 = y2;
  }
  *x = x0, *y = y0;
  return a;
}

TEST(GaussianInt, UnitPowersCycle) {
  for (int k = -9; k <= 9; ++k) {
    EXPECT_TRUE(unitPower(k).isUnit());
    EXPECT_EQ(unitPower(k) * unitPower(1), unitPower(k + 1));
    EXPECT_EQ(unitPower(k), unitPower(k + 4));
  }
  EXPECT_EQ(unitPower(1), GaussInt(0, 1));
}

TEST(GaussianInt, RoundedDivisionLeavesSmallRemainder) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20000; ++trial) {
    const GaussInt a = randomGauss(rng, 1000), b = randomGauss(rng, 40);
    if (b.isZero()) continue;
    const GaussInt q = divideRounded(a, b);
    const GaussInt r = a - q * b;
    ASSERT_LE(2 * r.norm(), b.norm()) << a.re << "+" << a.im << "i / " << b.re << "+" << b.im << "i";
    // q is the Gaussian integer nearest to the complex quotient (ties aside).
    const Complex exact = a.toComplex() / b.toComplex();
    EXPECT_LE(std::abs(exact - q.toComplex()), std::sqrt(0.5) + 1e-12);
  }
}

TEST(GaussianInt, EuclidGivesACommonDivisorWithBezoutFactors) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 3000; ++trial) {
    // A common factor c makes the gcd non-trivial.
    const GaussInt c = randomGauss(rng, 6);
    const GaussInt a = c * randomGauss(rng, 50), b = c * randomGauss(rng, 50);
    GaussInt x, y;
    const GaussInt g = gcdBezout(a, b, &x, &y);
    EXPECT_EQ(a * x + b * y, g);
    EXPECT_TRUE(divides(g, a));
    EXPECT_TRUE(divides(g, b));
    if (!a.isZero() || !b.isZero()) EXPECT_TRUE(divides(c, g)) << "the gcd is the greatest";
    // Unit multiples of each other, and exact division leaves nothing.
    if (!c.isZero() && !g.isZero()) EXPECT_EQ((g * divideRounded(a, g)), a);
  }
}

TEST(GaussianInt, RoundingToNearestGaussianInteger) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> real(-50.0, 50.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const Complex z(real(rng), real(rng));
    const Complex r = roundGaussian(z);
    EXPECT_EQ(r.real(), std::round(r.real()));
    EXPECT_EQ(r.imag(), std::round(r.imag()));
    EXPECT_LE(std::abs(z.real() - r.real()), 0.5);
    EXPECT_LE(std::abs(z.imag() - r.imag()), 0.5);
    EXPECT_DOUBLE_EQ(gaussianIntegerDistance(z), std::abs(z - r));
  }
}

TEST(GaussianInt, SparseVectorsStayCompact) {
  GaussVector a{{0, GaussInt(1, 1)}, {3, GaussInt(2)}};
  const GaussVector b{{1, GaussInt(5)}, {3, GaussInt(0, -1)}};
  addScaled(a, GaussInt(0, -2), b);  // entry 3: 2 + (-2i)(-i) = 0, dropped
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].first, 0u);
  EXPECT_EQ(a[1].first, 1u);
  EXPECT_EQ(a[1].second, GaussInt(0, -10));
  EXPECT_TRUE(scaled(b, GaussInt(0)).empty());
  EXPECT_EQ(scaled(b, GaussInt(0, 1))[0].second, GaussInt(0, 5));
}

// --- Elimination ---

using GaussMatrix = std::vector<std::vector<GaussInt>>;

GaussInt dot(const GaussVector& row, const std::vector<GaussInt>& t) {
  GaussInt sum = 0;
  for (const auto& [i, c] : row) sum = sum + c * t[i];
  return sum;
}

GaussInt determinant(const GaussMatrix& m) {
  const std::size_t k = m.size();
  if (k == 0) return 1;
  if (k == 1) return m[0][0];
  GaussInt sum = 0;
  for (std::size_t j = 0; j < k; ++j) {
    GaussMatrix minor;
    for (std::size_t r = 1; r < k; ++r) {
      std::vector<GaussInt> row;
      for (std::size_t c = 0; c < k; ++c) {
        if (c != j) row.push_back(m[r][c]);
      }
      minor.push_back(row);
    }
    const GaussInt term = m[0][j] * determinant(minor);
    sum = j % 2 == 0 ? sum + term : sum - term;
  }
  return sum;
}

// Calls f for every k-subset of 0..n-1 (increasing indices).
template <typename F>
void forEachSubset(std::size_t n, std::size_t k, F&& f, std::vector<std::size_t> prefix = {}) {
  if (prefix.size() == k) return f(prefix);
  const std::size_t first = prefix.empty() ? 0 : prefix.back() + 1;
  for (std::size_t i = first; i < n; ++i) {
    prefix.push_back(i);
    forEachSubset(n, k, f, prefix);
    prefix.pop_back();
  }
}

struct Elimination {
  GaussMatrix U;  // n x k
  std::uint32_t k = 0;
};

Elimination eliminate(std::uint32_t n, const std::vector<GaussVector>& constraints) {
  LatticeEliminator lattice(n);
  for (const GaussVector& row : constraints) {
    lattice.addConstraint(row);
    EXPECT_TRUE(lattice.express(row).empty()) << "an added constraint holds for every s";
  }
  for (const GaussVector& row : constraints) EXPECT_TRUE(lattice.express(row).empty());
  lattice.finish();
  Elimination out;
  out.k = lattice.numFree();
  out.U.assign(n, std::vector<GaussInt>(out.k, GaussInt(0)));
  for (std::uint32_t i = 0; i < n; ++i) {
    for (const auto& [j, x] : lattice.row(i)) {
      EXPECT_LT(j, out.k);
      out.U[i][j] = x;
    }
  }
  return out;
}

GaussVector randomRow(std::mt19937& rng, std::uint32_t n, int range) {
  GaussVector row;
  std::bernoulli_distribution present(0.75);
  for (std::uint32_t i = 0; i < n; ++i) {
    const GaussInt x = randomGauss(rng, range);
    if (present(rng) && !x.isZero()) row.emplace_back(i, x);
  }
  return row;
}

// Checks C U = 0 and that the gcd of U's k x k minors is a unit (U extends to a unimodular
// matrix, so U Z[i]^k is saturated). Returns k rows of U with a non-zero minor.
std::vector<std::size_t> checkLattice(const Elimination& e, std::uint32_t n,
                                      const std::vector<GaussVector>& constraints) {
  for (std::uint32_t j = 0; j < e.k; ++j) {
    std::vector<GaussInt> column(n);
    for (std::uint32_t i = 0; i < n; ++i) column[i] = e.U[i][j];
    for (const GaussVector& row : constraints) EXPECT_EQ(dot(row, column), GaussInt(0)) << "C U != 0";
  }
  GaussInt minorGcd = 0;
  std::vector<std::size_t> pivotRows;
  forEachSubset(n, e.k, [&](const std::vector<std::size_t>& rows) {
    GaussMatrix m;
    for (std::size_t r : rows) m.push_back(e.U[r]);
    const GaussInt d = determinant(m);
    if (!d.isZero() && pivotRows.empty()) pivotRows = rows;
    GaussInt x, y;
    minorGcd = gcdBezout(minorGcd, d, &x, &y);
  });
  EXPECT_TRUE(minorGcd.isUnit()) << "gcd of the maximal minors of U has norm " << minorGcd.norm();
  if (e.k > 0 && pivotRows.empty()) ADD_FAILURE() << "U has no non-zero maximal minor";
  return pivotRows;
}

// checkLattice, then brute force: every integer t in [-box, box]^2n with C t = 0 is U s for an
// integer s. Returns the number of box solutions found.
int checkElimination(std::uint32_t n, const std::vector<GaussVector>& constraints, int box) {
  const Elimination e = eliminate(n, constraints);
  const std::vector<std::size_t> pivotRows = checkLattice(e, n, constraints);
  if (e.k > 0 && pivotRows.empty()) return 0;
  // Enumerate t in [-box, box]^2n.
  const int side = 2 * box + 1;
  std::int64_t total = 1;
  for (std::uint32_t i = 0; i < 2 * n; ++i) total *= side;
  int found = 0;
  std::vector<GaussInt> t(n);
  for (std::int64_t code = 0; code < total; ++code) {
    std::int64_t rest = code;
    for (std::uint32_t i = 0; i < n; ++i) {
      t[i].re = rest % side - box, rest /= side;
      t[i].im = rest % side - box, rest /= side;
    }
    bool solves = true;
    for (const GaussVector& row : constraints) solves = solves && dot(row, t).isZero();
    if (!solves) continue;
    ++found;
    // Solve U s = t on the pivot rows, round, and check every row exactly.
    std::vector<GaussInt> s(e.k);
    if (e.k > 0) {
      Eigen::MatrixXcd A(e.k, e.k);
      Eigen::VectorXcd b(e.k);
      for (std::uint32_t a = 0; a < e.k; ++a) {
        for (std::uint32_t c = 0; c < e.k; ++c) A(a, c) = e.U[pivotRows[a]][c].toComplex();
        b[a] = t[pivotRows[a]].toComplex();
      }
      const Eigen::VectorXcd x = A.fullPivLu().solve(b);
      for (std::uint32_t c = 0; c < e.k; ++c) {
        EXPECT_LT(gaussianIntegerDistance(x[c]), 1e-9) << "s is not integral for an integer solution";
        const Complex r = roundGaussian(x[c]);
        s[c] = GaussInt(std::llround(r.real()), std::llround(r.imag()));
      }
    }
    for (std::uint32_t i = 0; i < n; ++i) {
      GaussInt ui = 0;
      for (std::uint32_t c = 0; c < e.k; ++c) ui = ui + e.U[i][c] * s[c];
      if (ui != t[i]) {
        ADD_FAILURE() << "integer solution not of the form U s (row " << i << ")";
        return found;
      }
    }
  }
  return found;
}

TEST(LatticeEliminator, UnitConstraintFreesTheOtherVariables) {
  // t0 + i t1 - t2 = 0: two free parameters, every solution reachable.
  EXPECT_GT(checkElimination(3, {{{0, GaussInt(1)}, {1, GaussInt(0, 1)}, {2, GaussInt(-1)}}}, 1), 9);
}

TEST(LatticeEliminator, NonUnitConstraintNeedsEuclid) {
  // (1 + i) t0 + 2 t1 = 0: one free parameter, t0 = (1 - i) s... every solution reachable.
  LatticeEliminator lattice(2);
  EXPECT_TRUE(lattice.addConstraint({{0, GaussInt(1, 1)}, {1, GaussInt(2)}}));
  EXPECT_EQ(lattice.nonUnitConstraints(), 1u);
  EXPECT_GT(checkElimination(2, {{{0, GaussInt(1, 1)}, {1, GaussInt(2)}}}, 2), 1);
  // 3 t0 + (2 + i) t1: gcd 1 but no unit coefficient.
  EXPECT_GT(checkElimination(2, {{{0, GaussInt(3)}, {1, GaussInt(2, 1)}}}, 3), 1);
}

TEST(LatticeEliminator, RedundantAndContradictoryRowsRemoveWhatTheyMust) {
  LatticeEliminator lattice(3);
  const GaussVector a{{0, GaussInt(2)}, {1, GaussInt(0, 1)}};
  EXPECT_TRUE(lattice.addConstraint(a));
  EXPECT_FALSE(lattice.addConstraint(scaled(a, GaussInt(1, -3)))) << "a multiple adds nothing";
  EXPECT_EQ(lattice.numFree(), 2u);
  // A single-variable constraint g t2 = 0 forces t2 = 0.
  EXPECT_TRUE(lattice.addConstraint({{2, GaussInt(3, 1)}}));
  lattice.finish();
  EXPECT_EQ(lattice.numFree(), 1u);
  EXPECT_TRUE(lattice.row(2).empty());
}

TEST(LatticeEliminator, RandomSmallSystemsMatchBruteForce) {
  std::mt19937 rng(14);
  int systems = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::uint32_t n = trial % 2 == 0 ? 2 : 3;
    const std::uint32_t rows = 1 + trial % 2;  // 1 row on 2 variables, 2 rows on 3
    std::vector<GaussVector> constraints;
    for (std::uint32_t r = 0; r < rows; ++r) constraints.push_back(randomRow(rng, n, 3));
    // Boxes: 2 variables [-4, 4]^4, 3 variables [-2, 2]^6 (thousands of candidates each).
    checkElimination(n, constraints, n == 2 ? 4 : 2);
    ++systems;
  }
  EXPECT_EQ(systems, 40);
}

TEST(LatticeEliminator, LargerRandomSystemsKeepCUZeroAndUPrimitive) {
  std::mt19937 rng(15);
  for (int trial = 0; trial < 30; ++trial) {
    const std::uint32_t n = 6;
    std::vector<GaussVector> constraints;
    for (int r = 0; r < 3; ++r) constraints.push_back(randomRow(rng, n, 4));
    const Elimination e = eliminate(n, constraints);
    EXPECT_GE(e.k, n - 3);
    checkLattice(e, n, constraints);
  }
}

}  // namespace
}  // namespace seamvox
