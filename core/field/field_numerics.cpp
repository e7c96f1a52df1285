// Numerics shared by the direct and the proxy smoothest field (field_numerics.h).
#include "core/field/field_numerics.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>

#include "core/system/errors.h"

namespace seamvox::detail {

using Complex = std::complex<double>;

FaceFrame faceFrame(const std::vector<Vec3f>& positions, const Triangle& t) {
  return faceFrame({positions[t[0]].cast<double>(), positions[t[1]].cast<double>(), positions[t[2]].cast<double>()});
}

FaceFrame faceFrame(const std::array<Vec3d, 3>& p) {
  FaceFrame frame;
  const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double area2 = n.norm();
  const double len01 = (p[1] - p[0]).norm();
  if (area2 > 0.0 && len01 > 0.0 && std::isfinite(area2)) {
    frame.n = n / area2;
    frame.e1 = (p[1] - p[0]) / len01;
    frame.e2 = frame.n.cross(frame.e1);
    frame.degenerate = false;
    return frame;
  }
  // Zero-area face: its longest edge (if any) as e1, any perpendicular as e2.
  Vec3d longest = Vec3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const Vec3d e = p[(k + 1) % 3] - p[k];
    if (e.squaredNorm() > longest.squaredNorm()) longest = e;
  }
  const double len = longest.norm();
  frame.e1 = len > 0.0 && std::isfinite(len) ? Vec3d(longest / len) : Vec3d::UnitX();
  frame.e2 = frame.e1.unitOrthogonal();
  frame.n = frame.e1.cross(frame.e2);
  frame.degenerate = true;
  return frame;
}

FaceFrame faceFrame(const TriangleMesh& mesh, FaceId f) { return faceFrame(mesh.positions, mesh.triangles[f]); }

Vec3d faceFrameNormal(const std::array<Vec3d, 3>& p) {
  const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double area2 = n.norm();
  if (area2 > 0.0 && (p[1] - p[0]).squaredNorm() > 0.0 && std::isfinite(area2)) return n / area2;
  return faceFrame(p).n;  // zero-area face: the fallback frame's normal
}

Vec3d faceFrameNormal(const std::vector<Vec3f>& positions, const Triangle& t) {
  return faceFrameNormal({positions[t[0]].cast<double>(), positions[t[1]].cast<double>(), positions[t[2]].cast<double>()});
}

Vec3d faceCentroid(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
}

double edgeLength(const TriangleMesh& mesh, const Topology& topology, CornerId c) {
  return (mesh.position(topology.vertex(nextCorner(c))) - mesh.position(topology.vertex(prevCorner(c))))
      .norm();
}

double dualWeight(double edgeLength, const Vec3d& bf, const Vec3d& bg) {
  constexpr double kMaxWeight = 1e3, kMinWeight = 1e-3;
  if (!(edgeLength > 0.0) || !std::isfinite(edgeLength)) return kMinWeight;
  return std::clamp(edgeLength / std::max((bf - bg).norm(), edgeLength / kMaxWeight), kMinWeight,
                    kMaxWeight);
}

void floorMasses(Eigen::VectorXd& mass) {
  const Eigen::Index n = mass.size();
  double total = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) total += std::isfinite(mass[i]) ? mass[i] : 0.0;
  const double minMass = n ? std::max(1e-6 * total / n, 1e-300) : 1.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(mass[i] >= minMass)) mass[i] = minMass;  // also catches NaN
  }
}

double flatModeShift(double diagonalTrace, double massSum) {
  return diagonalTrace > 0.0 ? 1e-9 * diagonalTrace / massSum : 1.0;
}

double rowShift(double sigma, double diagonal, double mass) {
  constexpr double kRelativeRowShift = 1e-10;
  return mass > 0.0 ? std::max(sigma, kRelativeRowShift * diagonal / mass) : sigma;
}

Eigen::VectorXcd startVector(std::uint32_t n, StartHash hash) {
  Eigen::VectorXcd x(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    std::uint64_t h;
    if (hash == StartHash::Faces) {
      h = (i + 1) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 31;
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 29;
    } else {
      h = (std::uint64_t(i) + 7) * 0x9E3779B97F4A7C15ull;
      h ^= h >> 29;
      h *= 0xBF58476D1CE4E5B9ull;
    }
    x[i] = std::polar(1.0, (h >> 11) * (2.0 * M_PI / 9007199254740992.0));
  }
  return x;
}

std::vector<double> componentNorms(const Eigen::VectorXcd& x, const Eigen::VectorXd& mass,
                                   const std::vector<std::uint32_t>& comp, std::size_t numComp) {
  std::vector<double> sum(numComp, 0.0);
  for (Eigen::Index i = 0; i < x.size(); ++i) sum[comp[i]] += mass[i] * std::norm(x[i]);
  for (double& s : sum) s = std::sqrt(s);
  return sum;
}

Eigen::VectorXcd smallestEigenvectors(const CholmodFactor& factor, const Eigen::VectorXd& mass,
                                      const std::vector<std::uint32_t>& comp, std::size_t numComp,
                                      const InverseIterationOptions& options) {
  const std::uint32_t n = static_cast<std::uint32_t>(mass.size());
  Eigen::VectorXcd x = startVector(n, options.start);
  {
    const std::vector<double> norms = componentNorms(x, mass, comp, numComp);
    for (std::uint32_t i = 0; i < n; ++i) x[i] /= norms[comp[i]];
  }
  for (int it = 0; it < options.maxIterations; ++it) {
    reportProgress(options.progress, options.stage,
                   options.progressFrom + options.progressSpan * it / options.maxIterations);
    Eigen::VectorXcd y = factor.solve(Eigen::VectorXcd(mass.cast<Complex>().cwiseProduct(x)));
    if (!y.allFinite()) throw SolverError(std::string(options.solver) + ": inverse iteration produced NaN");
    const std::vector<double> norms = componentNorms(y, mass, comp, numComp);
    std::vector<Complex> overlap(numComp, 0.0);
    for (std::uint32_t i = 0; i < n; ++i) {
      y[i] /= norms[comp[i]] > 0.0 ? norms[comp[i]] : 1.0;
      overlap[comp[i]] += mass[i] * std::conj(x[i]) * y[i];
    }
    x.swap(y);
    double change = 0.0;
    for (const Complex& o : overlap) change = std::max(change, 1.0 - std::abs(o));
    if (change < 1e-10) break;
  }
  return x;
}

void factorFieldMatrix(CholmodFactor& factor, const ComplexSparse& lower, const char* solver,
                       const char* what, FieldSolveStats* stats) {
  try {
    factor.factor(lower);
  } catch (const SolverError& e) {
    throw SolverError(std::string(solver) + ": cannot factor the connection Laplacian of the " + what +
                      " (" + std::to_string(lower.rows()) + " unknowns; not positive definite or out of memory): " +
                      e.what());
  }
  if (!stats) return;
  stats->unknowns = std::max<std::uint64_t>(stats->unknowns, lower.rows());
  stats->matrixNonzeros = std::max<std::uint64_t>(stats->matrixNonzeros, lower.nonZeros());
  stats->factorNonzeros = std::max(stats->factorNonzeros, factor.factorNonzeros());
  stats->factorBytes = std::max(stats->factorBytes, factor.factorBytes());
  stats->factorPeakBytes = std::max(stats->factorPeakBytes, factor.peakBytes());
  stats->realFallback = stats->realFallback || factor.usedRealFallback();
}

}  // namespace seamvox::detail
