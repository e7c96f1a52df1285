// Numerics shared by the direct and proxy fields: dual weights, mass floor, the inverse
// iteration through the CHOLMOD wrapper, and the factor figures both field solves report.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <vector>

#include "core/field/fast_atan2.h"
#include "core/field/detail_singularities.h"
#include "core/field/field_numerics.h"
#include "core/field/field_proxy.h"
#include "core/system/errors.h"
#include "test_meshes.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

TEST(FieldNumerics, DualWeightIsEdgeOverBarycentreDistanceWithinBounds) {
  const Vec3d o = Vec3d::Zero(), x = Vec3d::UnitX();
  EXPECT_DOUBLE_EQ(detail::dualWeight(2.0, o, x), 2.0);
  EXPECT_DOUBLE_EQ(detail::dualWeight(1e6, o, x), 1e3) << "needle: bounded above";
  EXPECT_DOUBLE_EQ(detail::dualWeight(1.0, o, o), 1e3) << "coincident barycentres";
  EXPECT_DOUBLE_EQ(detail::dualWeight(1e-9, o, x), 1e-3) << "bounded below";
  EXPECT_DOUBLE_EQ(detail::dualWeight(0.0, o, x), 1e-3) << "zero-length edge";
  EXPECT_DOUBLE_EQ(detail::dualWeight(std::nan(""), o, x), 1e-3);
}

// faceFrameNormal is faceFrame's normal bit for bit: random faces at many scales, and the
// zero-area ones (coincident first edge, collinear, a point, tiny, huge, not finite) whose
// fallback frame it takes.
TEST(FieldNumerics, FaceFrameNormalIsTheFramesNormalBitForBit) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  const auto same = [](const std::array<Vec3d, 3>& p) {
    const Vec3d a = detail::faceFrame(p).n, b = detail::faceFrameNormal(p);
    for (int i = 0; i < 3; ++i) {
      if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
    }
    return true;
  };
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::pow(10.0, (i % 13) * 25 - 150);
    std::array<Vec3d, 3> p;
    for (Vec3d& x : p) x = scale * Vec3d(coordinate(random), coordinate(random), coordinate(random));
    ASSERT_TRUE(same(p)) << i;
    const std::array<Vec3d, 3> collinear = {p[0], p[1], p[0] + 2.0 * (p[1] - p[0])};
    ASSERT_TRUE(same(collinear)) << i;
    ASSERT_TRUE(same({p[0], p[0], p[2]})) << i;
    ASSERT_TRUE(same({p[0], p[0], p[0]})) << i;
  }
  const double inf = std::numeric_limits<double>::infinity();
  ASSERT_TRUE(same({Vec3d::Zero(), Vec3d(inf, 0, 0), Vec3d(0, 1, 0)}));
  ASSERT_TRUE(same({Vec3d::Zero(), Vec3d(1e300, 0, 0), Vec3d(0, 1e300, 0)}));
  ASSERT_TRUE(same({Vec3d::Zero(), Vec3d(1e-170, 0, 0), Vec3d(0, 1e-170, 0)}));
  ASSERT_TRUE(same({Vec3d::Zero(), Vec3d(1, 0, 0), Vec3d(std::nan(""), 1, 0)}));
}

// roundHalfAway is std::lround: at and next to every half and integer within 4, at random, and
// beyond 4 (where it calls lround).
TEST(FieldNumerics, RoundHalfAwayIsLround) {
  std::vector<double> xs = {0.0, -0.0, 0.49999999999999994, -0.49999999999999994, 1e-300, -1e-300, 4.0, -4.0, 1e17};
  for (int k = -8; k <= 8; ++k) {
    const double x = 0.5 * k;
    xs.insert(xs.end(), {x, std::nextafter(x, 10.0), std::nextafter(x, -10.0)});
  }
  std::mt19937 random(3);
  std::uniform_real_distribution<double> any(-4.5, 4.5);
  for (int i = 0; i < 100000; ++i) xs.push_back(any(random));
  for (const double x : xs) ASSERT_EQ(detail::roundHalfAway(x), std::lround(x)) << x;
}

// The singularities and the wound-vertex count take their angles from fastAtan2: within 2e-6 rad
// of std::atan2 at every angle and length scale, exact at the axes, pi on the negative x axis.
TEST(FieldNumerics, FastAtan2IsWithinTwoMicroradiansOfAtan2) {
  double worst = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const double angle = -M_PI + 2.0 * M_PI * (i + 0.5) / 100000;
    for (const double r : {1e-30, 1e-3, 1.0, 7.5e4, 1e30}) {
      const double y = r * std::sin(angle), x = r * std::cos(angle);
      worst = std::max(worst, std::abs(detail::fastAtan2(y, x) - std::atan2(y, x)));
    }
  }
  EXPECT_LT(worst, 2e-6);
  EXPECT_GT(worst, 1e-9) << "a polynomial, not std::atan2 itself";
  EXPECT_EQ(detail::fastAtan2(0.0, 0.0), 0.0);
  EXPECT_EQ(detail::fastAtan2(0.0, 2.0), 0.0);
  EXPECT_NEAR(detail::fastAtan2(3.0, 0.0), 0.5 * M_PI, 1e-15);
  EXPECT_NEAR(detail::fastAtan2(-3.0, 0.0), -0.5 * M_PI, 1e-15);
  EXPECT_NEAR(detail::fastAtan2(0.0, -1.0), M_PI, 1e-15);
  EXPECT_NEAR(detail::fastAtan2(-0.0, -1.0), M_PI, 1e-15) << "a straight angle is pi for either zero";
}

TEST(FieldNumerics, FloorMassesRaisesTinyZeroAndNanToOneMillionthOfTheMean) {
  Eigen::VectorXd mass(5);
  mass << 1.0, 0.0, std::numeric_limits<double>::quiet_NaN(), 1e-12, 2.0;
  detail::floorMasses(mass);
  const double floor = 1e-6 * (3.0 + 1e-12) / 5.0;  // the NaN counts as 0 in the mean
  EXPECT_EQ(mass[0], 1.0);
  EXPECT_EQ(mass[4], 2.0);
  for (int i : {1, 2, 3}) EXPECT_DOUBLE_EQ(mass[i], floor) << i;
}

TEST(FieldNumerics, FlatModeShiftIsTinyAgainstTheDiagonalAndPositiveWithoutEdges) {
  EXPECT_DOUBLE_EQ(detail::flatModeShift(4.0, 2.0), 2e-9);
  EXPECT_GT(detail::flatModeShift(0.0, 2.0), 0.0);
}

/// Two components: a real and a Hermitian 2 x 2 block, each with smallest eigenvalue 1.
ComplexSparse twoComponentLower() {
  ComplexSparse a(4, 4);
  std::vector<Eigen::Triplet<Complex>> t = {{0, 0, 2.0}, {1, 0, -1.0}, {1, 1, 2.0},
                                            {2, 2, 2.0}, {3, 2, Complex(0.0, 1.0)}, {3, 3, 2.0}};
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

TEST(FieldNumerics, InverseIterationFindsTheSmallestEigenvectorOfEveryComponent) {
  const ComplexSparse lower = twoComponentLower();
  CholmodFactor factor;
  FieldSolveStats stats;
  detail::factorFieldMatrix(factor, lower, "test field", "unknowns", &stats);
  EXPECT_EQ(stats.unknowns, 4u);
  EXPECT_EQ(stats.matrixNonzeros, 6u);
  EXPECT_GT(stats.factorBytes, 0u);
  EXPECT_GE(stats.factorPeakBytes, stats.factorBytes);
  EXPECT_FALSE(stats.realFallback);

  const Eigen::VectorXd mass = Eigen::VectorXd::Ones(4);
  const std::vector<std::uint32_t> comp = {0, 0, 1, 1};
  detail::InverseIterationOptions options;
  options.maxIterations = 200;
  const Eigen::VectorXcd x = detail::smallestEigenvectors(factor, mass, comp, 2, options);
  const Eigen::MatrixXcd full = ComplexSparse(lower.selfadjointView<Eigen::Lower>());
  const Eigen::VectorXcd ax = full * x;
  // It stops when a step turns x by less than 1e-10 in 1 - |<x, y>|, i.e. ~1e-5 radians.
  for (int i = 0; i < 4; ++i) EXPECT_LT(std::abs(ax[i] - x[i]), 1e-4) << "A x = 1 x at " << i;
  const std::vector<double> norms = detail::componentNorms(x, mass, comp, 2);
  EXPECT_NEAR(norms[0], 1.0, 1e-12);
  EXPECT_NEAR(norms[1], 1.0, 1e-12);
}

TEST(FieldNumerics, FactoringAnIndefiniteMatrixNamesTheField) {
  ComplexSparse lower = twoComponentLower();
  lower.coeffRef(3, 3) = -5.0;
  CholmodFactor factor;
  try {
    detail::factorFieldMatrix(factor, lower, "test field", "unknowns", nullptr);
    FAIL() << "an indefinite matrix was factored";
  } catch (const SolverError& e) {
    EXPECT_NE(std::string(e.what()).find("test field"), std::string::npos) << e.what();
  }
}

TEST(FieldNumerics, BothFieldSolvesReportTheirFactorization) {
  const testing::Surface s = testing::makeSurface(testing::torusMesh(24, 12));
  FieldSolveStats direct;
  SmoothFieldOptions smooth;
  smooth.stats = &direct;
  computeSmoothestField(s.mesh, s.topology, smooth);
  EXPECT_EQ(direct.unknowns, s.mesh.numFaces());
  EXPECT_GT(direct.factorNonzeros, direct.unknowns);
  EXPECT_GT(direct.factorBytes, 0u);

  FieldSolveStats proxy;
  ProxyFieldOptions proxyOptions;
  proxyOptions.gridResolution = 8;
  proxyOptions.stats = &proxy;
  const ProxyFieldResult result = computeProxyField(s.mesh, s.topology, proxyOptions);
  EXPECT_EQ(proxy.unknowns, result.elements);
  EXPECT_LT(proxy.unknowns, direct.unknowns) << "the proxy solves on fewer elements than faces";
  EXPECT_GT(proxy.factorBytes, 0u);
}

}  // namespace
}  // namespace seamvox
