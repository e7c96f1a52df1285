#pragma once
/// Numerics shared by the two smoothest-field solvers (the direct one on the faces, field.cpp, and
/// the proxy one on grid elements, field_proxy.cpp): face frames, dual-edge weights, the mass
/// floor and flat-mode shift, and the inverse iteration for the smallest eigenvector of
/// A z = lambda M z through the project's CHOLMOD wrapper. Internal to core/field.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/solve/cholmod_solver.h"
#include "core/system/progress.h"

namespace seamvox::detail {

/// Orthonormal frame of a face: e1 along its first edge, e2 = n x e1. A zero-area face gets e1
/// along its longest edge (x when it has none), e2 = e1.unitOrthogonal(), n = e1 x e2.
struct FaceFrame {
  Vec3d e1, e2, n;
  bool degenerate = false;  ///< zero-area face: fallback frame
};
FaceFrame faceFrame(const std::array<Vec3d, 3>& p);
FaceFrame faceFrame(const std::vector<Vec3f>& positions, const Triangle& t);
FaceFrame faceFrame(const TriangleMesh& mesh, FaceId f);
/// faceFrame(p).n, bit for bit, without the frame's other axes.
Vec3d faceFrameNormal(const std::array<Vec3d, 3>& p);
Vec3d faceFrameNormal(const std::vector<Vec3f>& positions, const Triangle& t);

/// Barycentre of a face.
Vec3d faceCentroid(const TriangleMesh& mesh, FaceId f);
/// Length of the edge of corner c (from vertex next(c) to prev(c), topology.h).
double edgeLength(const TriangleMesh& mesh, const Topology& topology, CornerId c);
/// Dual-edge weight |e| / |b_f - b_g| (barycentres), bounded to [1e-3, 1e3] for needles and
/// zero-length edges.
double dualWeight(double edgeLength, const Vec3d& bf, const Vec3d& bg);

/// Raises every mass below 1e-6 of the mean (or not finite) to that floor, so M stays definite.
void floorMasses(Eigen::VectorXd& mass);
/// The shift sigma of A + sigma M that keeps the factorization definite for a field without
/// holonomy (a flat piece) and leaves the smallest eigenvector unchanged: 1e-9 of the mean
/// diagonal per unit mass (1 when A has no edge at all).
double flatModeShift(double diagonalTrace, double massSum);
/// The shift per unit mass of one row: sigma, or more where the row's own diagonal needs it. Two
/// near-degenerate slivers glued with coincident centroids (a scan's collinear faces) are joined by
/// the largest weight, and their flat pair loses far more than sigma times a floored mass to
/// rounding in the factorization: each row keeps at least 1e-10 of its own diagonal.
double rowShift(double sigma, double diagonal, double mass);

/// Which fixed hash startVector uses. The two solvers keep the start they always had: 30 or 40
/// iterations do not converge fully where the two smallest eigenvalues are close (bumpy: a change
/// of 1.5e-5 after 30, 6e-7 after 40), so the result, and even its cones, depend on the start.
enum class StartHash { Faces, Elements };
/// Deterministic pseudo-random unit start vector (a fixed hash per index).
Eigen::VectorXcd startVector(std::uint32_t n, StartHash hash);
/// Per-component M-norms of x (component of entry i: comp[i]).
std::vector<double> componentNorms(const Eigen::VectorXcd& x, const Eigen::VectorXd& mass,
                                   const std::vector<std::uint32_t>& comp, std::size_t numComp);

struct InverseIterationOptions {
  int maxIterations = 30;
  StartHash start = StartHash::Faces;
  const char* solver = "smoothest field";  ///< names the solver in errors
  ProgressFn progress;
  const char* stage = "field: eigenvector";  ///< progress stage, from progressFrom by progressSpan
  double progressFrom = 0.0, progressSpan = 1.0;
};
/// Smallest eigenvector of A z = lambda M z per component (A block diagonal by component, given
/// factored, with its shift), normalized to unit M-norm per component: inverse iteration from
/// startVector until every component turns by less than 1e-10 (or maxIterations). Throws SolverError on NaN.
Eigen::VectorXcd smallestEigenvectors(const CholmodFactor& factor, const Eigen::VectorXd& mass,
                                      const std::vector<std::uint32_t>& comp, std::size_t numComp,
                                      const InverseIterationOptions& options);

/// Factors the lower triangle of a field's connection matrix and records its figures in stats
/// when set (the larger of repeated factorizations). SolverError names `solver` and `what`.
void factorFieldMatrix(CholmodFactor& factor, const ComplexSparse& lower, const char* solver,
                       const char* what, FieldSolveStats* stats);

}  // namespace seamvox::detail
