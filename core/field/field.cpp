// Cross fields: face frames, discrete transport, matchings, singularity indices, the smoothest
// field (connection Laplacian solved with CHOLMOD) and tangent projection. Conventions:
// core/field/field.h.
#include "core/field/field.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <complex>
#include <cstdint>
#include <cstdlib>
#include <unordered_map>

#include "core/field/detail_rough_spots.h"
#include "core/field/detail_singularities.h"
#include "core/field/detail_smoothing.h"
#include "core/mesh/detail_id_map.h"
#include "core/field/fast_atan2.h"
#include "core/field/field_numerics.h"
#include "core/solve/assemble.h"
#include "core/solve/cholmod_solver.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

using detail::cornerAngles;
using detail::FaceFrame;
using detail::faceFrame;
using detail::faceFrameNormal;
using detail::wrapAngle;

/// A frame, the angles of the three corner edges in it and the three corner angles.
struct FaceAngles {
  FaceFrame frame;
  double edge[3];    ///< angle of the directed edge of corner k
  double corner[3];  ///< interior angle at corner k (they sum to pi)
};


Vec3d pointOf(const std::vector<Vec3f>& positions, VertexId v) { return positions[v].cast<double>(); }

/// The angle of v in the frame by atan2 (0 for a zero or non-finite v).
template <class Atan2>
double angleInFrame(const FaceFrame& frame, const Vec3d& v, Atan2&& atan2) {
  const double x = v.dot(frame.e1), y = v.dot(frame.e2);
  return (x == 0.0 && y == 0.0) || !std::isfinite(x) || !std::isfinite(y) ? 0.0 : atan2(y, x);
}

double frameAngle(const FaceFrame& frame, const Vec3d& v) {
  return angleInFrame(frame, v, [](double y, double x) { return std::atan2(y, x); });
}

/// frameAngle within 2e-6 rad (fastAtan2), for the singularities' face angles: kept as floats and
/// rounded to quarter turns, four per face, tens of millions in all.
double roundedFrameAngle(const FaceFrame& frame, const Vec3d& v) { return angleInFrame(frame, v, detail::fastAtan2); }

FaceAngles faceAngles(const std::array<Vec3d, 3>& p) {
  FaceAngles a;
  a.frame = faceFrame(p);
  // Corner k names the edge from vertex k+1 to vertex k+2 (topology.h).
  for (int k = 0; k < 3; ++k) a.edge[k] = frameAngle(a.frame, p[(k + 2) % 3] - p[(k + 1) % 3]);
  cornerAngles(a.edge, a.corner);
  return a;
}

FaceAngles faceAngles(const std::vector<Vec3f>& positions, const Triangle& t) {
  return faceAngles({pointOf(positions, t[0]), pointOf(positions, t[1]), pointOf(positions, t[2])});
}

FaceAngles faceAngles(const TriangleMesh& mesh, FaceId f) { return faceAngles(mesh.positions, mesh.triangles[f]); }

/// kappa: the angle of the edge of c in the frame of face(opposite c) minus its angle in face(c).
/// The edge as face(c) traverses it is traversed reversed by the other face: add pi.
double transportAngle(CornerId c, CornerId o, const FaceAngles& from, const FaceAngles& to) {
  return wrapAngle(to.edge[o % 3] + M_PI - from.edge[c % 3]);
}

}  // namespace

namespace detail {

FaceAngleData faceAngleData(const std::array<Vec3d, 3>& surface, const Vec3d* ownNormal, const Vec3d& direction) {
  const FaceFrame frame = faceFrame(surface);
  const Vec3d u = ownNormal ? rotateBetween(*ownNormal, frame.n, direction) : direction;
  FaceAngleData out{float(roundedFrameAngle(frame, u)), {}};
  // Corner k names the edge from vertex k+1 to vertex k+2 (topology.h), as in faceAngles.
  for (int k = 0; k < 3; ++k) out.edge[k] = float(roundedFrameAngle(frame, surface[(k + 2) % 3] - surface[(k + 1) % 3]));
  return out;
}

}  // namespace detail

PackedSingularities packSingularities(const FieldSingularities& singularities) {
  PackedSingularities packed;
  packed.corners = singularities.matching.size();
  packed.vertices = singularities.index4.size();
  packed.boundaryVertices = singularities.boundaryIndex4.size();
  packed.matching.assign((packed.corners + 3) / 4, 0);
  for (std::size_t c = 0; c < packed.corners; ++c) {
    packed.matching[c / 4] |= static_cast<std::uint8_t>((singularities.matching[c] & 3u) << (2 * (c % 4)));
  }
  for (VertexId v = 0; v < packed.vertices; ++v) {
    if (singularities.index4[v] != 0) packed.index4.push_back({v, singularities.index4[v]});
  }
  for (VertexId v = 0; v < singularities.boundaryIndex4.size(); ++v) {
    if (singularities.boundaryIndex4[v] != 0) packed.boundaryIndex4.push_back({v, singularities.boundaryIndex4[v]});
  }
  packed.cones = singularities.cones;
  return packed;
}

FieldSingularities unpackSingularities(const PackedSingularities& packed) {
  FieldSingularities s;
  s.matching.resize(packed.corners);
  for (std::size_t c = 0; c < packed.corners; ++c) s.matching[c] = (packed.matching[c / 4] >> (2 * (c % 4))) & 3u;
  s.index4.assign(packed.vertices, 0);
  for (const auto& [v, k] : packed.index4) s.index4[v] = k;
  s.boundaryIndex4.assign(packed.boundaryVertices, 0);
  for (const auto& [v, k] : packed.boundaryIndex4) s.boundaryIndex4[v] = k;
  s.cones = packed.cones;
  return s;
}

std::int64_t FieldSingularities::indexSum4() const {
  std::int64_t sum = 0;
  for (std::int32_t i : index4) sum += i;
  return sum;
}

namespace {

/// computeSingularities; afterFaceAngles (if set) runs once the faces' angles are read, before
/// anything else is allocated.
FieldSingularities singularitiesOf(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                   const std::function<void()>& afterFaceAngles) {
  const std::uint32_t numFaces = topology.numFaces();
  const std::uint32_t numVertices = topology.numVertices();
  if (field.direction.size() != numFaces || mesh.triangles.size() != numFaces) {
    throw InputError("computeSingularities: field has " + std::to_string(field.direction.size()) +
                     " directions, mesh " + std::to_string(mesh.triangles.size()) +
                     " faces, topology " + std::to_string(numFaces) + " faces");
  }
  if (!field.framePositions.empty() && field.framePositions.size() != mesh.positions.size()) {
    throw InputError("computeSingularities: field has " + std::to_string(field.framePositions.size()) +
                     " frame positions for " + std::to_string(mesh.positions.size()) + " vertices");
  }
  const std::vector<Vec3f>& positions = field.framePositions.empty() ? mesh.positions : field.framePositions;
  FieldSingularities out;
  // Per face, once: the field angle and the edge angles in the face frame (16 bytes per face;
  // float is ample for rounding to quarter turns).
  std::vector<detail::FaceAngleData> faceData(numFaces);
  const bool ownFrames = field.framePositions.empty();
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const Vec3d ownNormal = ownFrames ? Vec3d::Zero() : faceFrameNormal(mesh.positions, t);
      faceData[f] = detail::faceAngleData({pointOf(positions, t[0]), pointOf(positions, t[1]), pointOf(positions, t[2])},
                                          ownFrames ? nullptr : &ownNormal, field.at(f));
    }
  });
  if (afterFaceAngles) afterFaceAngles();
  out.matching.assign(3 * std::size_t(numFaces), 0);
  out.index4.assign(numVertices, 0);

  // Matching and residual rotation of an interior edge, from its smaller corner so that the two
  // sides are exactly opposite. The residuals are recomputed where the index needs them instead
  // of kept (12 bytes per face).
  const auto crossing = [&](CornerId c, CornerId o) {
    return detail::crossingOf(faceData[cornerFace(c)], c % 3, faceData[cornerFace(o)], o % 3);
  };
  const auto residual = [&](CornerId c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId) return 0.0f;
    return c < o ? crossing(c, o).eps : -crossing(o, c).eps;
  };
  parallelFor(3 * numFaces, 8192, [&](const IndexRange& range) {
    for (CornerId c = range.begin(); c != range.end(); ++c) {
      const CornerId o = topology.opposite(c);
      if (o == kInvalidId || o < c) continue;
      const std::uint8_t k = crossing(c, o).matching;
      out.matching[c] = k;
      out.matching[o] = static_cast<std::uint8_t>((4 - k) % 4);
    }
  });

  // Index: walk counter-clockwise around each vertex (detail::vertexIndices).
  out.boundaryIndex4.assign(numVertices, 0);
  parallelFor(numVertices, 4096, [&](const IndexRange& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      if (topology.isIsolatedVertex(v)) continue;
      detail::vertexIndices(topology, v, [&](FaceId f) { return faceData[f]; }, residual, out.index4[v],
                            out.boundaryIndex4[v]);
    }
  });
  for (VertexId v = 0; v < numVertices; ++v) {
    if (out.index4[v] != 0) out.cones.push_back(v);
  }
  return out;
}

}  // namespace

FieldSingularities computeSingularities(const TriangleMesh& mesh, const Topology& topology,
                                        const CrossField& field) {
  return singularitiesOf(mesh, topology, field, {});
}

FieldSingularities computeSingularitiesReleasingFrames(const TriangleMesh& mesh, const Topology& topology,
                                                       CrossField& field) {
  return singularitiesOf(mesh, topology, field, [&] { releaseFramePositions(field); });
}

namespace {

using Complex = std::complex<double>;
using SparseMatrixC = Eigen::SparseMatrix<Complex, Eigen::ColMajor, int>;
using VectorC = Eigen::VectorXcd;

/// The connection Laplacian of the 4-direction field (lower triangle, diagonal first in each
/// column) and the face areas: energy sum_e w_e |z_g - exp(4 i kappa_fg) z_f|^2.
struct ConnectionSystem {
  SparseMatrixC laplacian;
  Eigen::VectorXd mass;  ///< #F face areas, floored to stay positive
};

/// Dual-edge weight of the edge of corner c between faces f and g (detail::dualWeight).
double dualWeight(const TriangleMesh& mesh, const Topology& topology, CornerId c, FaceId f,
                  FaceId g) {
  return detail::dualWeight(detail::edgeLength(mesh, topology, c), detail::faceCentroid(mesh, f),
                            detail::faceCentroid(mesh, g));
}

ConnectionSystem buildConnectionSystem(const TriangleMesh& mesh, const Topology& topology) {
  const std::uint32_t numFaces = topology.numFaces();
  ConnectionSystem sys;
  sys.mass.resize(numFaces);
  // Column f holds the diagonal and the rows g > f of its neighbours (merged when two edges are
  // shared with the same face).
  std::vector<int> count(numFaces + 1, 0);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      sys.mass[f] = faceArea(mesh, f);
      FaceId seen[3];
      int n = 0;
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        const CornerId o = topology.opposite(c);
        if (o == kInvalidId || cornerFace(o) <= f) continue;
        if (std::find(seen, seen + n, cornerFace(o)) == seen + n) seen[n++] = cornerFace(o);
      }
      count[f + 1] = 1 + n;
    }
  });
  for (std::uint32_t f = 0; f < numFaces; ++f) count[f + 1] += count[f];
  detail::floorMasses(sys.mass);

  SparseMatrixC& a = sys.laplacian;
  a.resize(numFaces, numFaces);
  a.resizeNonZeros(count[numFaces]);
  std::copy(count.begin(), count.end(), a.outerIndexPtr());
  parallelFor(numFaces, 2048, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const FaceAngles af = faceAngles(mesh, f);
      std::pair<FaceId, Complex> entries[3];
      int n = 0;
      double diagonal = 0.0;
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        const CornerId o = topology.opposite(c);
        if (o == kInvalidId) continue;
        const FaceId g = cornerFace(o);
        const double w = dualWeight(mesh, topology, c, f, g);
        diagonal += w;
        if (g <= f) continue;
        const double kappa = transportAngle(c, o, af, faceAngles(mesh, g));
        // Entry (g, f): coefficient of conj(z_g) z_f, i.e. -w exp(4 i kappa_fg).
        const Complex value = -w * std::polar(1.0, 4.0 * kappa);
        auto it = std::find_if(entries, entries + n, [&](const auto& e) { return e.first == g; });
        if (it != entries + n) {
          it->second += value;
        } else {
          entries[n++] = {g, value};
        }
      }
      for (int j = 1; j < n; ++j) {  // insertion sort of at most three rows
        for (int i = j; i > 0 && entries[i].first < entries[i - 1].first; --i) {
          std::swap(entries[i], entries[i - 1]);
        }
      }
      int p = a.outerIndexPtr()[f];
      a.innerIndexPtr()[p] = static_cast<int>(f);
      a.valuePtr()[p] = diagonal;
      for (int j = 0; j < n; ++j) {
        a.innerIndexPtr()[p + 1 + j] = static_cast<int>(entries[j].first);
        a.valuePtr()[p + 1 + j] = entries[j].second;
      }
    }
  });
  return sys;
}

/// Principal-curvature target per face: |k1 - k2| exp(4 i theta) with theta the angle of a
/// principal direction in the face frame, from a least-squares shape operator fitted to the
/// change of the area-weighted vertex normals along the three edges.
VectorC curvatureTarget(const TriangleMesh& mesh, const Topology& topology) {
  const std::uint32_t numFaces = topology.numFaces(), numVertices = topology.numVertices();
  std::vector<Vec3d> normal(numVertices, Vec3d::Zero());
  parallelFor(numVertices, 4096, [&](const IndexRange& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      Vec3d sum = Vec3d::Zero();
      topology.forEachCornerAround(v, [&](CornerId c) {
        const FaceId f = cornerFace(c);
        sum += faceNormal(mesh, f) * faceArea(mesh, f);
      });
      const double len = sum.norm();
      normal[v] = len > 0.0 && std::isfinite(len) ? Vec3d(sum / len) : Vec3d::Zero();
    }
  });
  VectorC q(numFaces);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      q[f] = 0.0;
      const FaceFrame frame = faceFrame(mesh, f);
      if (frame.degenerate) continue;
      const Triangle& t = mesh.triangles[f];
      // Unknowns (a, b, c) of S = [a b; b c]; rows S e = dn for the three edges.
      Eigen::Matrix3d normalMatrix = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const VertexId i = t[k], j = t[(k + 1) % 3];
        const Vec3d e = mesh.position(j) - mesh.position(i), dn = normal[j] - normal[i];
        const double ex = e.dot(frame.e1), ey = e.dot(frame.e2);
        const double nx = dn.dot(frame.e1), ny = dn.dot(frame.e2);
        const Eigen::Vector3d r1(ex, ey, 0.0), r2(0.0, ex, ey);
        normalMatrix += r1 * r1.transpose() + r2 * r2.transpose();
        rhs += r1 * nx + r2 * ny;
      }
      const Eigen::Vector3d s = normalMatrix.ldlt().solve(rhs);
      if (!s.allFinite()) continue;
      const Complex z2(s[0] - s[2], 2.0 * s[1]);
      const double mag = std::abs(z2);
      if (mag > 0.0 && std::isfinite(mag)) q[f] = z2 * z2 / mag;
    }
  });
  return q;
}

/// Sets the diagonal of the lower-triangle matrix a to base diagonal + shift[f] * mass[f].
void shiftDiagonal(SparseMatrixC& a, const std::vector<double>& baseDiagonal,
                   const Eigen::VectorXd& mass, const std::vector<double>& shift) {
  for (Eigen::Index f = 0; f < a.cols(); ++f) {
    a.valuePtr()[a.outerIndexPtr()[f]] = baseDiagonal[f] + shift[f] * mass[f];
  }
}

/// Per face, the sum of exp(4 i angle) over its aligned edges (corners sorted), angles in the
/// face frame; 0 for faces without one.
std::vector<Complex> alignmentTargets(const TriangleMesh& mesh, const std::vector<CornerId>& corners) {
  std::vector<Complex> target(mesh.numFaces(), 0.0);
  for (CornerId c : corners) {
    if (cornerFace(c) >= mesh.numFaces()) {
      throw InputError("field alignment: corner " + std::to_string(c) + " out of range");
    }
    target[cornerFace(c)] += std::polar(1.0, 4.0 * faceAngles(mesh, cornerFace(c)).edge[c % 3]);
  }
  return target;
}

/// Whether the aligned edges of a face agree (their 4th powers sum to their count).
bool edgesAgree(const Complex& target, std::uint32_t count) { return std::abs(target) > count - 1e-6; }

/// The field x (4th powers) with the faces of `corners` fixed along their edges and the other faces
/// of their components solving A z = 0 (a harmonic extension: the smoothest field with the
/// constraint); components without a constrained face keep x. A face whose edges cancel (e.g. at
/// 45 degrees) is left free.
void constrainToEdges(const TriangleMesh& mesh, const SparseMatrixC& lower, const std::vector<CornerId>& corners,
                      const std::vector<std::uint32_t>& comp, std::size_t numComp, VectorC& x,
                      FieldSolveStats* stats) {
  const std::uint32_t numFaces = mesh.numFaces();
  const std::vector<Complex> target = alignmentTargets(mesh, corners);
  std::vector<std::uint8_t> constrained(numComp, 0), fixed(numFaces, 0);
  std::vector<Complex> values(x.data(), x.data() + x.size());
  for (FaceId f = 0; f < numFaces; ++f) {
    if (std::abs(target[f]) < 1e-6) continue;
    fixed[f] = 1;
    values[f] = target[f] / std::abs(target[f]);
    constrained[comp[f]] = 1;
  }
  for (FaceId f = 0; f < numFaces; ++f) {
    if (!constrained[comp[f]]) fixed[f] = 1;
  }
  LinearSystem system;
  system.lower = lower;
  system.rhs = VectorC::Zero(numFaces);
  const RestrictedSystem restricted = restrictSystem(system, fixed, values);
  if (!restricted.freeUnknowns.empty()) {
    CholmodFactor factor;
    detail::factorFieldMatrix(factor, restricted.lower, "aligned field", "faces", stats);
    const VectorC y = factor.solve(restricted.rhs);
    if (!y.allFinite()) throw SolverError("aligned field: the constrained solve produced NaN");
    for (std::size_t k = 0; k < restricted.freeUnknowns.size(); ++k) values[restricted.freeUnknowns[k]] = y[k];
  }
  for (FaceId f = 0; f < numFaces; ++f) x[f] = values[f];
}

}  // namespace

CrossField computeSmoothestField(const TriangleMesh& mesh, const Topology& topology,
                                 const SmoothFieldOptions& options) {
  const std::uint32_t numFaces = topology.numFaces();
  CrossField field;
  if (numFaces == 0) return field;
  if (mesh.triangles.size() != numFaces) {
    throw InputError("computeSmoothestField: mesh has " + std::to_string(mesh.triangles.size()) +
                     " faces, topology " + std::to_string(numFaces));
  }
  reportProgress(options.progress, "field: assemble", 0.0);
  const ComponentsResult components = computeComponents(topology);
  const std::vector<std::uint32_t>& comp = components.faceComponent;
  const std::size_t numComp = components.components.size();
  ConnectionSystem sys = buildConnectionSystem(mesh, topology);
  SparseMatrixC& a = sys.laplacian;
  std::vector<double> baseDiagonal(numFaces);
  double diagonalTrace = 0.0;
  for (std::uint32_t f = 0; f < numFaces; ++f) {
    baseDiagonal[f] = a.valuePtr()[a.outerIndexPtr()[f]].real();
    diagonalTrace += baseDiagonal[f];
  }
  // A face without an interior edge is a component of its own: its field is free and takes its
  // first edge (x = 1) without a solve. It gets a unit row so the factorization stays definite.
  std::vector<std::uint8_t> loneFace(numFaces, 0);
  for (std::uint32_t f = 0; f < numFaces; ++f) {
    if (baseDiagonal[f] > 0.0) continue;
    loneFace[f] = 1;
    baseDiagonal[f] = sys.mass[f];
  }
  // A tiny shift keeps A + sigma M definite when the field has a flat mode (trivial holonomy,
  // e.g. a flat torus) without changing the smallest eigenvector.
  const double sigma = detail::flatModeShift(diagonalTrace, sys.mass.sum());
  std::vector<double> shift(numFaces), rowSigma(numFaces);
  for (std::uint32_t f = 0; f < numFaces; ++f) shift[f] = rowSigma[f] = detail::rowShift(sigma, baseDiagonal[f], sys.mass[f]);
  shiftDiagonal(a, baseDiagonal, sys.mass, shift);

  // Smallest eigenvector of A x = lambda M x by inverse power iteration, normalized per
  // component (the matrix is block diagonal, so every component converges on its own).
  reportProgress(options.progress, "field: factor", 0.1);
  CholmodFactor factor;
  detail::factorFieldMatrix(factor, a, "smoothest field", "faces", options.stats);
  detail::InverseIterationOptions iteration;
  iteration.maxIterations = 30;
  iteration.solver = "smoothest field";
  iteration.progress = options.progress;
  iteration.stage = "field: eigenvector";
  iteration.progressFrom = 0.5;
  iteration.progressSpan = 0.4;
  VectorC x = detail::smallestEigenvectors(factor, sys.mass, comp, numComp, iteration);

  if (options.curvatureWeight > 0.0) {
    // Curvature alignment: (A - lambda M) z = M q per component with
    // lambda = lambda_1 / 2 - curvatureWeight * 4 pi^2 / area (below lambda_1: definite).
    reportProgress(options.progress, "field: curvature", 0.9);
    const VectorC ax = a.selfadjointView<Eigen::Lower>() * x;
    std::vector<double> lambda1(numComp, 0.0), area(numComp, 0.0);
    for (std::uint32_t f = 0; f < numFaces; ++f) {
      lambda1[comp[f]] += (std::conj(x[f]) * ax[f]).real();  // x has unit M-norm per component
      area[comp[f]] += sys.mass[f];
    }
    for (std::uint32_t f = 0; f < numFaces; ++f) {
      const std::uint32_t k = comp[f];
      const double lambda = 0.5 * std::max(lambda1[k] - sigma, 0.0) -
                            options.curvatureWeight * 4.0 * M_PI * M_PI / area[k];
      shift[f] = rowSigma[f] - lambda;
    }
    shiftDiagonal(a, baseDiagonal, sys.mass, shift);
    detail::factorFieldMatrix(factor, a, "curvature-aligned field", "faces", options.stats);
    const VectorC q = curvatureTarget(mesh, topology);
    VectorC z = factor.solve(VectorC(sys.mass.cast<Complex>().cwiseProduct(q)));
    const std::vector<double> qNorms = detail::componentNorms(q, sys.mass, comp, numComp);
    const std::vector<double> zNorms = detail::componentNorms(z, sys.mass, comp, numComp);
    for (std::uint32_t f = 0; f < numFaces; ++f) {
      const std::uint32_t k = comp[f];
      // A flat component has no curvature target: keep its smoothest field.
      if (qNorms[k] > 1e-12 * std::sqrt(area[k]) && zNorms[k] > 0.0 && std::isfinite(zNorms[k])) {
        x[f] = z[f];
      }
    }
  }

  if (!options.alignCorners.empty()) {
    reportProgress(options.progress, "field: align", 0.92);
    constrainToEdges(mesh, a, options.alignCorners, comp, numComp, x, options.stats);
  }
  for (std::uint32_t f = 0; f < numFaces; ++f) {
    if (loneFace[f]) x[f] = 1.0;
  }
  reportProgress(options.progress, "field: directions", 0.95);
  field.direction.resize(numFaces);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const FaceFrame frame = faceFrame(mesh, f);
      const double theta = std::abs(x[f]) > 0.0 ? 0.25 * std::arg(x[f]) : 0.0;
      field.set(f, std::cos(theta) * frame.e1 + std::sin(theta) * frame.e2);
    }
  });
  reportProgress(options.progress, "field: directions", 1.0);
  return field;
}

void snapToFeatureEdges(const TriangleMesh& mesh, const std::vector<CornerId>& corners, CrossField& field) {
  if (field.direction.size() != mesh.numFaces()) {
    throw InputError("snapToFeatureEdges: field has " + std::to_string(field.direction.size()) +
                     " directions for " + std::to_string(mesh.numFaces()) + " faces");
  }
  const std::vector<Complex> target = alignmentTargets(mesh, corners);
  std::vector<std::uint32_t> count(mesh.numFaces(), 0);
  for (CornerId c : corners) ++count[cornerFace(c)];
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const CornerId c = corners[i];
    const FaceId f = cornerFace(c);
    if (i > 0 && cornerFace(corners[i - 1]) == f) continue;  // once per face, along its first edge
    if (!edgesAgree(target[f], count[f])) continue;
    const FaceAngles a = faceAngles(mesh, f);
    const double theta = frameAngle(a.frame, field.at(f));
    const double edge = a.edge[c % 3];
    const double snapped = edge + std::round(wrapAngle(theta - edge) / (0.5 * M_PI)) * (0.5 * M_PI);
    field.set(f, std::cos(snapped) * a.frame.e1 + std::sin(snapped) * a.frame.e2);
  }
}

Vec3d rotateBetween(const Vec3d& from, const Vec3d& to, const Vec3d& v) {
  const double c = from.dot(to);
  if (c > -1.0 + 1e-9) {
    const Vec3d k = from.cross(to);
    return c * v + k.cross(v) + (k.dot(v) / (1.0 + c)) * k;
  }
  const Vec3d axis = from.unitOrthogonal();
  return 2.0 * axis.dot(v) * axis - v;
}


std::vector<Vec3f> smoothPositions(const TriangleMesh& mesh, const Topology& topology,
                                   std::uint32_t iterations) {
  const std::uint32_t numVertices = topology.numVertices();
  if (mesh.positions.size() != numVertices) {
    throw InputError("smoothPositions: mesh has " + std::to_string(mesh.positions.size()) +
                     " vertices, topology " + std::to_string(numVertices));
  }
  std::vector<Vec3f> current = mesh.positions;
  if (iterations == 0) return current;
  std::vector<Vec3f> next(numVertices);
  for (std::uint32_t it = 0; it < iterations; ++it) {
    parallelFor(numVertices, 4096, [&](const IndexRange& range) {
      for (VertexId v = range.begin(); v != range.end(); ++v) {
        next[v] = detail::smoothingStep(topology, v, [&](VertexId w) { return pointOf(current, w); });
      }
    });
    current.swap(next);
  }
  return current;
}

std::vector<Vec3f> smoothPositionsAt(const TriangleMesh& mesh, const Topology& topology,
                                     std::uint32_t iterations, const std::vector<VertexId>& vertices) {
  if (mesh.positions.size() != topology.numVertices()) {
    throw InputError("smoothPositionsAt: mesh has " + std::to_string(mesh.positions.size()) +
                     " vertices, topology " + std::to_string(topology.numVertices()));
  }
  // The ball of `iterations` rings around the vertices, local ids in BFS order. Outside it the
  // values stay the input positions: after step k, values are exact up to `iterations` - k + 1
  // rings deep, so the centre is exact after the last step. Local ids are hashed for a few
  // vertices, kept per vertex of the mesh for many (a noisy scan's folds: 4% of its vertices).
  // The per-vertex ids are local id + 1 in zeroed memory (calloc): only the pages the ball
  // touches are written, not the whole mesh's 4 B a vertex at every call (a noisy scan's map
  // calls this a hundred times).
  const bool dense = vertices.size() > topology.numVertices() / 1024;
  std::unordered_map<VertexId, std::uint32_t> hashed;
  const detail::ZeroedIds denseId = dense ? detail::zeroedIds(topology.numVertices()) : detail::ZeroedIds(nullptr, std::free);
  const auto localOf = [&](VertexId v) {
    if (dense) return denseId[v] - 1;  // 0 (none) wraps to kInvalidId
    const auto it = hashed.find(v);
    return it == hashed.end() ? kInvalidId : it->second;
  };
  std::vector<VertexId> ball;
  const auto enter = [&](VertexId v) {
    if (dense) {
      if (denseId[v] != 0) return;
      denseId[v] = static_cast<std::uint32_t>(ball.size()) + 1;
    } else if (!hashed.emplace(v, static_cast<std::uint32_t>(ball.size())).second) {
      return;
    }
    ball.push_back(v);
  };
  for (VertexId v : vertices) {
    if (v >= topology.numVertices()) throw InputError("smoothPositionsAt: vertex " + std::to_string(v) + " out of range");
    enter(v);
  }
  // ringEnd[r]: the ball's vertices within r rings come first, ball[0, ringEnd[r]). The ring
  // `iterations` deep is only read, at its input positions (what valueOf gives outside the
  // ball), so the ball stops a ring short of it. Only the corners' next vertices enter: they
  // are an interior vertex's neighbours (its closed fan), and a boundary vertex's other one (its
  // last corner's previous) is on the boundary, which keeps its input positions.
  std::vector<std::size_t> ringEnd = {ball.size()};
  std::size_t ringStart = 0;
  // A wide ring (per-vertex ids) grows on both cores: a vertex is claimed by a compare-and-swap
  // of its slot, listed by the block of the ring that claimed it, and numbered block by block.
  // The ball's order then depends on the threads; nothing below does (values by vertex).
  constexpr std::size_t kRingBlock = 4096;
  constexpr std::uint32_t kClaimed = ~std::uint32_t(0);
  for (std::uint32_t ring = 0; ring + 1 < iterations; ++ring) {
    const std::size_t end = ball.size();
    if (dense && end - ringStart > 4 * kRingBlock) {
      std::vector<std::vector<VertexId>> claimed((end - ringStart + kRingBlock - 1) / kRingBlock);
      parallelForEach(claimed.size(), 1, [&](std::uint64_t b) {
        const std::size_t last = std::min(end, ringStart + (b + 1) * kRingBlock);
        for (std::size_t i = ringStart + b * kRingBlock; i < last; ++i) {
          if (topology.isIsolatedVertex(ball[i])) continue;
          topology.forEachCornerAround(ball[i], [&](CornerId c) {
            const VertexId w = topology.vertex(nextCorner(c));
            std::uint32_t expected = 0;
            if (__atomic_load_n(&denseId[w], __ATOMIC_RELAXED) == 0 &&
                __atomic_compare_exchange_n(&denseId[w], &expected, kClaimed, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
              claimed[b].push_back(w);
            }
          });
        }
      });
      for (const std::vector<VertexId>& block : claimed) {
        for (VertexId w : block) {
          denseId[w] = static_cast<std::uint32_t>(ball.size()) + 1;
          ball.push_back(w);
        }
      }
    } else {
      for (std::size_t i = ringStart; i < end; ++i) {
        if (topology.isIsolatedVertex(ball[i])) continue;
        topology.forEachCornerAround(ball[i], [&](CornerId c) { enter(topology.vertex(nextCorner(c))); });
      }
    }
    ringStart = end;
    ringEnd.push_back(ball.size());
  }
  std::vector<Vec3f> current(ball.size()), next(ball.size());
  for (std::size_t i = 0; i < ball.size(); ++i) current[i] = mesh.positions[ball[i]];
  const auto valueOf = [&](VertexId w) {
    const std::uint32_t i = localOf(w);
    return i == kInvalidId ? pointOf(mesh.positions, w) : pointOf(current, i);
  };
  // Step it needs exact values only within iterations - it rings: the vertices it computes read
  // neighbours one ring further, all computed by the step before (or input positions at step 0).
  for (std::uint32_t it = 0; it < iterations; ++it) {
    parallelFor(ringEnd[iterations - 1 - it], 4096, [&](const IndexRange& range) {
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
        next[i] = detail::smoothingStep(topology, ball[i], valueOf);
      }
    });
    current.swap(next);
  }
  std::vector<Vec3f> out(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) out[i] = current[localOf(vertices[i])];
  return out;
}

void releaseFramePositions(CrossField& field) {
  if (field.frameSmoothing > 0) std::vector<Vec3f>().swap(field.framePositions);
}

void restoreFramePositions(const TriangleMesh& mesh, const Topology& topology, CrossField& field) {
  if (field.frameSmoothing > 0 && field.framePositions.empty()) {
    field.framePositions = smoothPositions(mesh, topology, field.frameSmoothing);
    for (const auto& [v, p] : field.frameOverrides) field.framePositions[v] = p;
  }
}

std::vector<Vec3f> framePositionsAt(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                    const std::vector<VertexId>& vertices) {
  if (field.framePositions.size() == mesh.numVertices()) {
    std::vector<Vec3f> out(vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) out[i] = field.framePositions[vertices[i]];
    return out;
  }
  if (field.frameSmoothing == 0) return {};
  std::vector<Vec3f> out = smoothPositionsAt(mesh, topology, field.frameSmoothing, vertices);
  if (field.frameOverrides.empty()) return out;
  const auto byVertex = [](const std::pair<VertexId, Vec3f>& a, VertexId v) { return a.first < v; };
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const auto it = std::lower_bound(field.frameOverrides.begin(), field.frameOverrides.end(), vertices[i], byVertex);
    if (it != field.frameOverrides.end() && it->first == vertices[i]) out[i] = it->second;
  }
  return out;
}

void setFrameOverridesAside(const TriangleMesh& mesh, const Topology& topology, CrossField& field,
                            std::vector<std::pair<VertexId, Vec3f>>& aside) {
  aside.clear();
  if (field.frameOverrides.empty()) return;
  // The plain surface at the moved vertices and their neighbours (marked in a per-vertex slot on
  // both cores, listed in vertex order), then the moves' normal parts, each vertex on its own.
  const std::vector<std::pair<VertexId, Vec3f>>& moves = field.frameOverrides;
  const std::uint32_t nv = topology.numVertices();
  detail::ZeroedIds slot = detail::zeroedIds(nv);  // 1 + the vertex's place in ring; 0 outside
  std::uint32_t* const slots = slot.get();
  const auto mark = [&](VertexId w) { __atomic_store_n(&slots[w], 1u, __ATOMIC_RELAXED); };
  parallelFor(moves.size(), 1u << 12, [&](const IndexRange& range) {
    for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
      mark(moves[i].first);
      topology.forEachCornerAround(moves[i].first, [&](CornerId c) {
        mark(topology.vertex(nextCorner(c)));
        mark(topology.vertex(prevCorner(c)));
      });
    }
  });
  constexpr std::uint32_t kBlock = 1u << 16;
  std::vector<std::uint32_t> before((nv + kBlock - 1) / kBlock + 1, 0);
  parallelFor(before.size() - 1, 1, [&](const IndexRange& range) {
    for (std::uint64_t b = range.begin(); b != range.end(); ++b) {
      for (VertexId w = b * kBlock; w < std::min<std::uint64_t>(nv, (b + 1) * kBlock); ++w) before[b + 1] += slots[w] != 0;
    }
  });
  for (std::size_t b = 1; b < before.size(); ++b) before[b] += before[b - 1];
  std::vector<VertexId> ring(before.back());
  parallelFor(before.size() - 1, 1, [&](const IndexRange& range) {
    for (std::uint64_t b = range.begin(); b != range.end(); ++b) {
      std::uint32_t at = before[b];
      for (VertexId w = b * kBlock; w < std::min<std::uint64_t>(nv, (b + 1) * kBlock); ++w) {
        if (slots[w]) ring[at] = w, slots[w] = ++at;
      }
    }
  });
  const std::vector<Vec3f> plain = smoothPositionsAt(mesh, topology, field.frameSmoothing, ring);
  std::vector<Vec3f> rough = plain;
  for (const auto& [v, p] : moves) rough[slots[v] - 1] = p;
  std::vector<std::pair<VertexId, Vec3f>> normal(moves.size());
  parallelFor(moves.size(), 1u << 12, [&](const IndexRange& range) {
    for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
      normal[i] = {moves[i].first, detail::normalPartOfMove(
                                       topology, moves[i].first, moves[i].second,
                                       [&](VertexId w) { return rough[slots[w] - 1]; },
                                       [&](VertexId w) { return plain[slots[w] - 1]; })};
    }
  });
  if (field.framePositions.size() == mesh.numVertices()) {
    for (const auto& [v, p] : normal) field.framePositions[v] = p;
  }
  aside.swap(field.frameOverrides);
  field.frameOverrides.swap(normal);
}

void putFrameOverridesBack(CrossField& field, std::vector<std::pair<VertexId, Vec3f>>& aside) {
  if (aside.empty()) return;
  if (!field.framePositions.empty()) {
    for (const auto& [v, p] : aside) field.framePositions[v] = p;
  }
  field.frameOverrides.swap(aside);
  aside.clear();
}

CrossField projectToTangent(const TriangleMesh& mesh, const std::vector<Vec3d>& vectors) {
  const std::uint32_t numFaces = mesh.numFaces();
  if (vectors.size() != numFaces) {
    throw InputError("projectToTangent: " + std::to_string(vectors.size()) + " vectors for " +
                     std::to_string(numFaces) + " faces");
  }
  CrossField field;
  field.direction.resize(numFaces);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const FaceFrame frame = faceFrame(mesh, f);
      const Vec3d& v = vectors[f];
      const Vec3d t = v.allFinite() ? Vec3d(v - v.dot(frame.n) * frame.n) : Vec3d::Zero();
      const double len = t.norm();
      // Parallel to the normal, zero or not finite: the frame's first direction.
      field.set(f, len > 1e-12 * std::max(1.0, v.norm()) ? Vec3d(t / len) : frame.e1);
    }
  });
  return field;
}

}  // namespace seamvox
