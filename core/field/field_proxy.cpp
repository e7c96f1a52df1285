// The proxy cross field: grid-cell elements, the connection Laplacian on the element graph
// solved by inverse iteration (CHOLMOD), transfer to faces and coloured smoothing sweeps.
// Conventions: core/field/field.h; the method: DESIGN section 4.
#include "core/field/field_proxy.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "core/field/detail_proxy.h"
#include "core/field/rough_spots.h"
#include "core/field/field_numerics.h"
#include "core/mesh/detail_union_find.h"
#include "core/solve/cholmod_solver.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace detail {

using Complex = std::complex<double>;
using VectorC = Eigen::VectorXcd;

namespace {

/// Unit 4th power of the tangent vector v written in the frame (e1, e2); 0 for a zero vector.
/// (x + iy)^4 / (x^2 + y^2)^2: no trigonometry, no square root.
Complex fourthPower(const Vec3d& v, const Vec3d& e1, const Vec3d& e2) {
  const double x = v.dot(e1), y = v.dot(e2);
  const double r2 = x * x + y * y;
  if (!(r2 > 0.0) || !std::isfinite(r2)) return 0.0;
  const double inverse = 1.0 / r2;
  const double a = (x * x - y * y) * inverse, b = 2.0 * x * y * inverse;  // unit square
  return {a * a - b * b, 2.0 * a * b};
}

/// Principal square root of a unit complex number (half the angle, in (-pi/2, pi/2]).
Complex unitSqrt(Complex w) {
  const double c = std::sqrt(std::max(0.0, 0.5 * (1.0 + w.real())));
  const double s = std::sqrt(std::max(0.0, 0.5 * (1.0 - w.real())));
  return {c, std::signbit(w.imag()) ? -s : s};
}

/// The direction whose 4th power has the argument of z, in the frame (e1, e2): the quarter-turn
/// representative closest to e1 (angle arg(z) / 4). e1 itself when z is 0.
Vec3d directionOf(Complex z, const Vec3d& e1, const Vec3d& e2) {
  const double len = std::sqrt(std::norm(z));
  if (!(len > 0.0) || !std::isfinite(len)) return e1;
  const double inverse = 1.0 / len;
  const Complex r = unitSqrt(unitSqrt(Complex(z.real() * inverse, z.imag() * inverse)));
  return r.real() * e1 + r.imag() * e2;
}

/// Tangent frame of an element: e1 any unit vector perpendicular to its normal.
void elementFrame(const Vec3d& n, Vec3d& e1, Vec3d& e2) {
  e1 = n.unitOrthogonal();
  e2 = n.cross(e1);
}

/// directionOf's root for the batches, branch-free: (re, im) = the principal 4th root of the
/// unit complex along (sumRe, sumIm), by two half-angle steps (unitSqrt written out); false when
/// the sum has no direction (zero or not finite).
inline bool quarterRoot(double sumRe, double sumIm, double& re, double& im) {
  const double len = std::sqrt(sumRe * sumRe + sumIm * sumIm);
  const double inverse = 1.0 / len;
  const double re0 = sumRe * inverse, im0 = sumIm * inverse;
  const double h0 = 0.5 * (1.0 + re0), g0 = 0.5 * (1.0 - re0);
  const double re1 = std::sqrt(0.0 < h0 ? h0 : 0.0), im1 = std::copysign(std::sqrt(0.0 < g0 ? g0 : 0.0), im0);
  const double h1 = 0.5 * (1.0 + re1), g1 = 0.5 * (1.0 - re1);
  re = std::sqrt(0.0 < h1 ? h1 : 0.0);
  im = std::copysign(std::sqrt(0.0 < g1 ? g1 : 0.0), im1);
  return (len > 0.0) & (len <= std::numeric_limits<double>::max());
}

}  // namespace

FaceGeometry faceGeometry(const std::array<Vec3d, 3>& p) {
  const FaceFrame frame = faceFrame(p);
  FaceGeometry g;
  g.n = frame.n;
  g.e1 = frame.e1;
  g.e2 = frame.e2;
  g.centroid = (p[0] + p[1] + p[2]) / 3.0;
  g.area = frame.degenerate ? 0.0 : faceArea(p[0], p[1], p[2]);
  g.degenerate = frame.degenerate;
  return g;
}

ProxyCells proxyCells(const BoundingBox& box, std::int32_t resolution) {
  ProxyCells cells;
  const Vec3d extent = box.extent();
  const double longest = std::max(extent.maxCoeff(), 1e-300);
  // Cubic cells, the grid centred on the box and padded by a few percent of a cell.
  cells.cellSize = longest * (1.0 + 1e-3) / resolution;
  if (!(cells.cellSize > 0.0) || !std::isfinite(cells.cellSize)) cells.cellSize = 1.0;
  cells.origin = 0.5 * (box.min + box.max) - Vec3d::Constant(0.5 * resolution * cells.cellSize);
  cells.resolution = static_cast<std::uint32_t>(resolution);
  return cells;
}

std::uint32_t ProxyCells::cellOf(const Vec3d& b) const {
  std::uint32_t key = 0;
  for (int axis = 2; axis >= 0; --axis) {
    const double x = (b[axis] - origin[axis]) / cellSize;
    const std::uint32_t i = x >= 0.0 ? std::min(static_cast<std::uint32_t>(std::min(x, 1e9)), resolution - 1) : 0;
    key = key * resolution + i;  // NaN centroids land in cell 0
  }
  return key;
}

void ElementSums::addFace(const FaceGeometry& g) {
  normal_ += g.area * g.n;
  weighted_ += g.area * g.centroid;
  plain_ += g.centroid;
  area_ += g.area;
  ++count_;
}

void ElementSums::addNeighbour(std::uint32_t other, double len) {
  auto it = std::find_if(list_.begin(), list_.end(), [&](const auto& p) { return p.first == other; });
  if (it == list_.end()) {
    list_.emplace_back(other, std::isfinite(len) ? len : 0.0);
  } else {
    it->second += std::isfinite(len) ? len : 0.0;
  }
}

std::vector<std::pair<std::uint32_t, double>> ElementSums::finish(ProxyElements& elements, std::uint32_t e) {
  std::sort(list_.begin(), list_.end());
  const double len = normal_.norm();
  elements.normal[e] = len > 0.0 && std::isfinite(len) ? Vec3d(normal_ / len) : Vec3d::UnitZ();
  elements.centroid[e] = area_ > 0.0 && std::isfinite(area_) ? Vec3d(weighted_ / area_) : Vec3d(plain_ / count_);
  elements.area[e] = std::isfinite(area_) ? area_ : 0.0;
  return std::move(list_);
}

void storeNeighbours(std::vector<std::vector<std::pair<std::uint32_t, double>>>& lists, ProxyElements& elements) {
  const std::uint32_t numElements = static_cast<std::uint32_t>(lists.size());
  elements.neighbourStart.assign(numElements + 1, 0);
  for (std::uint32_t e = 0; e < numElements; ++e) {
    elements.neighbourStart[e + 1] = elements.neighbourStart[e] + static_cast<std::uint32_t>(lists[e].size());
  }
  elements.neighbours.reserve(elements.neighbourStart[numElements]);
  for (auto& list : lists) {
    elements.neighbours.insert(elements.neighbours.end(), list.begin(), list.end());
    std::vector<std::pair<std::uint32_t, double>>().swap(list);
  }
}

using SparseMatrixC = Eigen::SparseMatrix<Complex, Eigen::ColMajor, int>;

VectorC solveElementField(const ProxyElements& proxy, const ProgressFn& progress, FieldSolveStats* stats) {
  const std::uint32_t numElements = proxy.numElements();
  std::vector<Vec3d> e1(numElements), e2(numElements);
  for (std::uint32_t e = 0; e < numElements; ++e) elementFrame(proxy.normal[e], e1[e], e2[e]);

  // Lower triangle, one column per element: diagonal first, then the neighbours b > a.
  SparseMatrixC a(numElements, numElements);
  std::vector<int> start(numElements + 1, 0);
  for (std::uint32_t e = 0; e < numElements; ++e) {
    int n = 1;
    for (std::uint32_t i = proxy.neighbourStart[e]; i < proxy.neighbourStart[e + 1]; ++i) n += proxy.neighbours[i].first > e;
    start[e + 1] = start[e] + n;
  }
  a.resizeNonZeros(start[numElements]);
  std::copy(start.begin(), start.end(), a.outerIndexPtr());
  Eigen::VectorXd mass = Eigen::Map<const Eigen::VectorXd>(proxy.area.data(), numElements);
  detail::floorMasses(mass);
  double trace = 0.0;
  detail::UnionFind components(numElements);
  for (std::uint32_t e = 0; e < numElements; ++e) {
    int p = start[e];
    double diagonal = 0.0;
    for (std::uint32_t i = proxy.neighbourStart[e]; i < proxy.neighbourStart[e + 1]; ++i) {
      const auto [b, length] = proxy.neighbours[i];
      const double w = dualWeight(length, proxy.centroid[e], proxy.centroid[b]);
      diagonal += w;
      if (b < e) continue;
      components.unite(e, b);
      // Angle of e1[e], transported to b, in b's frame: z_b ~ exp(4 i kappa) z_e.
      const Vec3d moved = rotateBetween(proxy.normal[e], proxy.normal[b], e1[e]);
      const Complex transport = fourthPower(moved, e1[b], e2[b]);
      ++p;
      a.innerIndexPtr()[p] = static_cast<int>(b);
      a.valuePtr()[p] = -w * (std::abs(transport) > 0.0 ? transport : Complex(1.0));
    }
    a.innerIndexPtr()[start[e]] = static_cast<int>(e);
    a.valuePtr()[start[e]] = diagonal;
    trace += diagonal;
  }
  // A tiny shift keeps the matrix definite for fields without holonomy (flat pieces).
  const double sigma = detail::flatModeShift(trace, mass.sum());
  for (std::uint32_t e = 0; e < numElements; ++e) {
    a.valuePtr()[start[e]] += detail::rowShift(sigma, a.valuePtr()[start[e]].real(), mass[e]) * mass[e];
  }

  std::vector<std::uint32_t> comp(numElements);
  std::uint32_t numComponents = 0;
  for (std::uint32_t e = 0; e < numElements; ++e) {
    comp[e] = components.find(e) == e ? numComponents++ : comp[components.find(e)];
  }
  reportProgress(progress, "proxy field: factor", 0.3);
  CholmodFactor factor;
  detail::factorFieldMatrix(factor, a, "proxy field", "elements", stats);
  detail::InverseIterationOptions iteration;
  iteration.maxIterations = 40;
  iteration.start = detail::StartHash::Elements;
  iteration.solver = "proxy field";
  iteration.progress = progress;
  iteration.stage = "proxy field: eigenvector";
  iteration.progressFrom = 0.3;
  iteration.progressSpan = 0.2;
  return detail::smallestEigenvectors(factor, mass, comp, numComponents, iteration);
}

ElementDirections elementDirections(const ProxyElements& proxy, const VectorC& z) {
  ElementDirections out;
  const std::uint32_t numElements = proxy.numElements();
  out.direction.resize(numElements);
  out.confidence.resize(numElements);
  for (std::uint32_t e = 0; e < numElements; ++e) {
    Vec3d e1, e2;
    elementFrame(proxy.normal[e], e1, e2);
    out.direction[e] = directionOf(z[e], e1, e2);
    out.confidence[e] = std::isfinite(std::abs(z[e])) ? std::abs(z[e]) : 0.0;
  }
  out.radius = 2.0 * proxy.cellSize;
  return out;
}

void TransferBatch::compute() {
  constexpr int L = kLanes;
  constexpr double kMax = std::numeric_limits<double>::max();
  for (int l = size_; l < L; ++l) {  // idle lanes repeat the first face
    for (int i = 0; i < 3; ++i) n_[i][l] = n_[i][0], e1_[i][l] = e1_[i][0], e2_[i][l] = e2_[i][0], centroid_[i][l] = centroid_[i][0];
  }
  // Each face averages the unit 4th powers of its element's and the neighbours' directions,
  // carried onto its plane, weighted by confidence and a bump of the centroid distance.
  double sumRe[L], sumIm[L];
  for (int l = 0; l < L; ++l) sumRe[l] = 0.0, sumIm[l] = 0.0;
  const auto add = [&](std::uint32_t e) {
    const Vec3d& ce = elements_.centroid[e];
    const Vec3d& ne = elements_.normal[e];
    const Vec3d& de = directions_.direction[e];
    const double confidence = directions_.confidence[e], radius = directions_.radius;
    const bool own = e == own_;
    double w[L], r[3][L], c[L];
    for (int l = 0; l < L; ++l) {
      const double dx = centroid_[0][l] - ce[0], dy = centroid_[1][l] - ce[1], dz = centroid_[2][l] - ce[2];
      const double d = std::sqrt(dx * dx + dy * dy + dz * dz) / radius;
      const double bump = d < 1.0 ? (1.0 - d * d) * (1.0 - d * d) : 0.0;
      // The own element always counts a little, so no face is left without a value.
      w[l] = confidence * (own ? (bump < 1e-3 ? 1e-3 : bump) : bump);
      // rotateBetween(ne, n, de): about k = ne x n by the angle whose cosine is c.
      const double nx = n_[0][l], ny = n_[1][l], nz = n_[2][l];
      c[l] = ne[0] * nx + ne[1] * ny + ne[2] * nz;
      const double kx = ne[1] * nz - ne[2] * ny, ky = ne[2] * nx - ne[0] * nz, kz = ne[0] * ny - ne[1] * nx;
      const double t = (kx * de[0] + ky * de[1] + kz * de[2]) / (1.0 + c[l]);
      r[0][l] = c[l] * de[0] + (ky * de[2] - kz * de[1]) + t * kx;
      r[1][l] = c[l] * de[1] + (kz * de[0] - kx * de[2]) + t * ky;
      r[2][l] = c[l] * de[2] + (kx * de[1] - ky * de[0]) + t * kz;
    }
    for (int l = 0; l < L; ++l) {
      if (c[l] > -1.0 + 1e-9 || !(w[l] > 0.0)) continue;  // opposite normals: rotateBetween's half turn
      const Vec3d v = rotateBetween(ne, Vec3d(n_[0][l], n_[1][l], n_[2][l]), de);
      for (int i = 0; i < 3; ++i) r[i][l] = v[i];
    }
    for (int l = 0; l < L; ++l) {
      // fourthPower in the face's frame: (x + iy)^4 / r^4, 0 for a zero vector.
      const double x = r[0][l] * e1_[0][l] + r[1][l] * e1_[1][l] + r[2][l] * e1_[2][l];
      const double y = r[0][l] * e2_[0][l] + r[1][l] * e2_[1][l] + r[2][l] * e2_[2][l];
      const double r2 = x * x + y * y;
      const bool adds = (w[l] > 0.0) & (r2 > 0.0) & (r2 <= kMax);
      const double inverse = 1.0 / r2;
      const double a = (x * x - y * y) * inverse, b = 2.0 * x * y * inverse;  // unit square
      sumRe[l] = adds ? sumRe[l] + w[l] * (a * a - b * b) : sumRe[l];
      sumIm[l] = adds ? sumIm[l] + w[l] * (2.0 * a * b) : sumIm[l];
    }
  };
  add(own_);
  for (std::uint32_t i = elements_.neighbourStart[own_]; i < elements_.neighbourStart[own_ + 1]; ++i) {
    add(elements_.neighbours[i].first);
  }
  // directionOf: the quarter-turn representative nearest e1 of the sum's 4th root (e1 for 0).
  for (int l = 0; l < L; ++l) {
    double re, im;
    const bool turns = quarterRoot(sumRe[l], sumIm[l], re, im);
    for (int i = 0; i < 3; ++i) out_[i][l] = turns ? re * e1_[i][l] + im * e2_[i][l] : e1_[i][l];
  }
}

Vec3d transferredDirection(const ProxyElements& proxy, const ElementDirections& directions, const FaceGeometry& g,
                           std::uint32_t own) {
  TransferBatch batch(proxy, directions);
  Vec3d out;
  const auto done = [&](std::uint64_t, const Vec3d& direction) { out = direction; };
  batch.add(0, g, own, done);
  batch.flush(done);
  return out;
}

bool SweepBatch::add(std::uint64_t id, const Vec3f& normal, const Vec3d& u, const Vec3f* neighbourNormal,
                     const Vec3d* neighbourDirection, int count) {
  const int l = size_++;
  id_[l] = id;
  for (int i = 0; i < 3; ++i) n_[i][l] = normal[i], u_[i][l] = u[i];
  for (int k = 0; k < 3; ++k) {
    weight_[k][l] = k < count ? 1.0 : 0.0;
    for (int i = 0; i < 3; ++i) {
      m_[k][i][l] = k < count ? double(neighbourNormal[k][i]) : 0.0;
      d_[k][i][l] = k < count ? neighbourDirection[k][i] : 0.0;
    }
  }
  return size_ == kLanes;
}

void SweepBatch::compute() {
  constexpr int L = kLanes;
  for (int l = size_; l < L; ++l) {  // idle lanes: no neighbour, so no direction
    for (int i = 0; i < 3; ++i) n_[i][l] = u_[i][l] = 0.0;
    for (int k = 0; k < 3; ++k) weight_[k][l] = 0.0;
  }
  // Frame (u, v = n x u): the new direction is the representative nearest the current one.
  double v[3][L], c[3][L], x[3][L], y[3][L], sumRe[L], sumIm[L];
  for (int l = 0; l < L; ++l) {
    v[0][l] = n_[1][l] * u_[2][l] - n_[2][l] * u_[1][l];
    v[1][l] = n_[2][l] * u_[0][l] - n_[0][l] * u_[2][l];
    v[2][l] = n_[0][l] * u_[1][l] - n_[1][l] * u_[0][l];
  }
  // A neighbour's direction in this face's plane. Nearly coplanar (c >= kProjectCosine): its
  // projection, (x, y) = (d.u, d.v), whose angle differs from the rotated direction's by at most
  // 1.5 degrees there. Tilted further (a fold of the surface): the rotation between the normals.
  for (int k = 0; k < 3; ++k) {
    const double(&m)[3][L] = m_[k];
    const double(&d)[3][L] = d_[k];
    for (int l = 0; l < L; ++l) {
      c[k][l] = m[0][l] * n_[0][l] + m[1][l] * n_[1][l] + m[2][l] * n_[2][l];
      x[k][l] = d[0][l] * u_[0][l] + d[1][l] * u_[1][l] + d[2][l] * u_[2][l];
      y[k][l] = d[0][l] * v[0][l] + d[1][l] * v[1][l] + d[2][l] * v[2][l];
    }
  }
  for (int k = 0; k < 3; ++k) {
    for (int l = 0; l < L; ++l) {
      if (!(weight_[k][l] > 0.0) || c[k][l] >= kProjectCosine) continue;
      const Vec3d w = rotateBetween(Vec3d(m_[k][0][l], m_[k][1][l], m_[k][2][l]), Vec3d(n_[0][l], n_[1][l], n_[2][l]),
                                    Vec3d(d_[k][0][l], d_[k][1][l], d_[k][2][l]));
      x[k][l] = w[0] * u_[0][l] + w[1] * u_[1][l] + w[2] * u_[2][l];
      y[k][l] = w[0] * v[0][l] + w[1] * v[1][l] + w[2] * v[2][l];
    }
  }
  // Their unit 4th powers, (x + iy)^4 / r^4, summed in neighbour order where they have one
  // (masks with &: no branches).
  for (int l = 0; l < L; ++l) {
    double re = 0.0, im = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double r2 = x[k][l] * x[k][l] + y[k][l] * y[k][l];
      const bool adds = (weight_[k][l] > 0.0) & (r2 > 0.0) & (r2 <= std::numeric_limits<double>::max());
      const double inverse = 1.0 / r2;
      const double a = (x[k][l] * x[k][l] - y[k][l] * y[k][l]) * inverse, b = 2.0 * x[k][l] * y[k][l] * inverse;
      re = adds ? re + (a * a - b * b) : re;
      im = adds ? im + 2.0 * a * b : im;
    }
    sumRe[l] = re;
    sumIm[l] = im;
  }
  // The 4th root of the sum's direction.
  for (int l = 0; l < L; ++l) {
    double re, im;
    const bool turns = quarterRoot(sumRe[l], sumIm[l], re, im);
    // Unit and tangent up to float rounding (u's, and |n| in v): a few 1e-7 after the sweeps,
    // whose last step projects onto the exact planes and normalizes.
    const double o0 = re * u_[0][l] + im * v[0][l], o1 = re * u_[1][l] + im * v[1][l],
                 o2 = re * u_[2][l] + im * v[2][l];
    out_[0][l] = o0, out_[1][l] = o1, out_[2][l] = o2;
    constexpr double kMax = std::numeric_limits<double>::max();
    ok_[l] = turns & (std::abs(o0) <= kMax) & (std::abs(o1) <= kMax) & (std::abs(o2) <= kMax) ? 1.0 : 0.0;
  }
}

bool sweptDirection(const Vec3f& normal, const Vec3d& u, const Vec3f* neighbourNormal, const Vec3d* neighbourDirection,
                    int count, Vec3d& out) {
  SweepBatch batch;
  batch.add(0, normal, u, neighbourNormal, neighbourDirection, count);
  bool changed = false;
  batch.flush([&](std::uint64_t, const Vec3d& direction) { out = direction, changed = true; });
  return changed;
}

bool tangentOf(const Vec3d& n, const Vec3d& u, Vec3d& out) {
  const Vec3d tangent = u - u.dot(n) * n;
  const double len = tangent.norm();
  if (!(len > 0.0 && std::isfinite(len))) return false;
  out = tangent * (1.0 / len);
  return true;
}

}  // namespace detail

namespace {

using Complex = std::complex<double>;
using VectorC = Eigen::VectorXcd;
using detail::dualWeight;
using detail::edgeLength;
using detail::FaceGeometry;
using detail::isZero;
using detail::fourthPower;

FaceGeometry faceGeometry(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return detail::faceGeometry({mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])});
}

/// The proxy: elements (connected pieces of the mesh inside one grid cell) and their graph.
struct Proxy : detail::ProxyElements {
  std::vector<std::uint32_t> faceElement;     ///< #F
  std::vector<std::uint32_t> elementStart;    ///< #E + 1, offsets into elementFaces
  std::vector<std::uint32_t> elementFaces;    ///< faces grouped by element, increasing in each
};

/// Cell of every face's centroid, then faces of one cell joined through their shared edges.
void buildElements(const TriangleMesh& mesh, const Topology& topology, std::int32_t resolution,
                   Proxy& proxy) {
  const std::uint32_t numFaces = topology.numFaces();
  const detail::ProxyCells cells = detail::proxyCells(computeBoundingBox(mesh.positions), resolution);
  proxy.cellSize = cells.cellSize;
  std::vector<std::uint32_t> cell(numFaces);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Triangle& t = mesh.triangles[f];
      cell[f] = cells.cellOf((mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0);
    }
  });
  // Every face points at the smallest face of its element, so one increasing pass numbers the
  // elements by their smallest face and gives every other face its root's id.
  std::vector<std::uint32_t> element =
      detail::smallestFaceOfSets(topology, [&](FaceId f, FaceId g) { return cell[f] == cell[g]; });
  std::vector<std::uint32_t>().swap(cell);
  std::uint32_t numElements = 0;
  for (FaceId f = 0; f < numFaces; ++f) element[f] = element[f] == f ? numElements++ : element[element[f]];
  proxy.faceElement = std::move(element);

  proxy.elementStart.assign(numElements + 1, 0);
  for (FaceId f = 0; f < numFaces; ++f) ++proxy.elementStart[proxy.faceElement[f] + 1];
  for (std::uint32_t e = 0; e < numElements; ++e) proxy.elementStart[e + 1] += proxy.elementStart[e];
  proxy.elementFaces.resize(numFaces);
  {
    std::vector<std::uint32_t> fill(proxy.elementStart.begin(), proxy.elementStart.end() - 1);
    for (FaceId f = 0; f < numFaces; ++f) proxy.elementFaces[fill[proxy.faceElement[f]]++] = f;
  }
}

/// Area, normal and centroid per element; neighbours with the summed length of shared edges.
/// Parallel over elements, each summing its faces in increasing order (deterministic).
void accumulateElements(const TriangleMesh& mesh, const Topology& topology, Proxy& proxy) {
  const std::uint32_t numElements = static_cast<std::uint32_t>(proxy.elementStart.size() - 1);
  proxy.normal.resize(numElements);
  proxy.centroid.resize(numElements);
  proxy.area.resize(numElements);
  std::vector<std::vector<std::pair<std::uint32_t, double>>> adjacent(numElements);
  parallelFor(numElements, 64, [&](const IndexRange& range) {
    for (std::uint32_t e = range.begin(); e != range.end(); ++e) {
      detail::ElementSums sums;
      for (std::uint32_t i = proxy.elementStart[e]; i < proxy.elementStart[e + 1]; ++i) {
        const FaceId f = proxy.elementFaces[i];
        sums.addFace(faceGeometry(mesh, f));
        for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
          const CornerId o = topology.opposite(c);
          if (o == kInvalidId) continue;
          const std::uint32_t other = proxy.faceElement[cornerFace(o)];
          if (other != e) sums.addNeighbour(other, edgeLength(mesh, topology, c));
        }
      }
      adjacent[e] = sums.finish(proxy, e);
    }
  });
  detail::storeNeighbours(adjacent, proxy);
}

/// Greedy colouring of the face graph (faces adjacent through edges), in face order: at most 4
/// colours since a face has at most 3 neighbours.
std::uint32_t colourFaces(const Topology& topology, std::vector<std::uint8_t>& colour) {
  const std::uint32_t numFaces = topology.numFaces();
  colour.assign(numFaces, 0xff);
  std::uint32_t used = 0;
  for (FaceId f = 0; f < numFaces; ++f) {
    unsigned taken = 0;
    for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
      const CornerId o = topology.opposite(c);
      if (o != kInvalidId && colour[cornerFace(o)] != 0xff) taken |= 1u << colour[cornerFace(o)];
    }
    colour[f] = detail::firstFreeColour(taken);
    used = std::max<std::uint32_t>(used, colour[f] + 1u);
  }
  return used;
}

void checkProxyFieldInput(const TriangleMesh& mesh, const Topology& topology, const ProxyFieldOptions& options) {
  const std::uint32_t numFaces = topology.numFaces();
  if (mesh.triangles.size() != numFaces) {
    throw InputError("computeProxyField: mesh has " + std::to_string(mesh.triangles.size()) +
                     " faces, topology " + std::to_string(numFaces));
  }
  if (options.gridResolution < 4 || options.gridResolution > 1024) {
    throw InputError("computeProxyField: grid resolution " + std::to_string(options.gridResolution) +
                     " outside 4..1024");
  }
  if (options.smoothingSweeps < 0) {
    throw InputError("computeProxyField: negative number of smoothing sweeps");
  }
  if (options.sweepBlockFaces == 0) throw InputError("computeProxyField: sweep blocks of 0 faces");
}

/// Transfer: each face averages the 4th powers of its element and the element's neighbours,
/// transported to the face's plane, weighted by confidence (|z|) and a bump of the centroid
/// distance. Fills sweepNormal (when not empty) with the faces' unit normals as floats, zero for a
/// zero-area face.
void transferToFaces(const TriangleMesh& mesh, const Proxy& proxy, const VectorC& z, CrossField& field,
                     std::vector<Vec3f>& sweepNormal) {
  const std::uint32_t numFaces = static_cast<std::uint32_t>(mesh.triangles.size());
  const detail::ElementDirections directions = detail::elementDirections(proxy, z);
  field.direction.resize(numFaces);
  parallelFor(numFaces, 2048, [&](const IndexRange& range) {
    detail::TransferBatch batch(proxy, directions);  // runs of faces of one element
    const auto store = [&](std::uint64_t f, const Vec3d& direction) { field.set(static_cast<FaceId>(f), direction); };
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const FaceGeometry g = faceGeometry(mesh, f);
      batch.add(f, g, proxy.faceElement[f], store);
      if (!sweepNormal.empty()) sweepNormal[f] = g.degenerate ? Vec3f(Vec3f::Zero()) : Vec3f(g.n.cast<float>());
    }
    batch.flush(store);
  });
}

/// One Gauss-Seidel sweep, by blocks of blockFaces faces and by colour within a block; faces of one colour share no edge, so each colour of a block is a
/// race-free parallel loop and the result does not depend on the thread count. A sweep reads only
/// the corner table, the float normals and the directions (unit weights): memory traffic, not
/// geometry.
void smoothSweep(const Topology& topology, const std::vector<std::uint8_t>& colour, std::uint32_t colours,
                 std::uint32_t blockFaces, const std::vector<Vec3f>& sweepNormal, CrossField& field) {
  const std::uint32_t numFaces = topology.numFaces();
  for (std::uint64_t first = 0; first < numFaces; first += blockFaces) {
    const std::uint64_t count = std::min<std::uint64_t>(blockFaces, numFaces - first);
    for (std::uint32_t k = 0; k < colours; ++k) {
      parallelFor(count, 4096, [&](const IndexRange& range) {
        detail::SweepBatch batch;
        const auto store = [&](std::uint64_t f, const Vec3d& next) { field.set(static_cast<FaceId>(f), next); };
        for (FaceId f = static_cast<FaceId>(first + range.begin()); f != first + range.end(); ++f) {
          if (colour[f] != k || isZero(sweepNormal[f])) continue;
          Vec3f normals[3];
          Vec3d directions[3];
          int n = 0;
          for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
            const CornerId o = topology.opposite(c);
            if (o == kInvalidId || isZero(sweepNormal[cornerFace(o)])) continue;
            normals[n] = sweepNormal[cornerFace(o)];
            directions[n++] = field.at(cornerFace(o));
          }
          if (batch.add(f, sweepNormal[f], field.at(f), normals, directions, n)) batch.flush(store);
        }
        batch.flush(store);
      });
    }
  }
}

/// After the sweeps: every direction projected onto its face's exact (double) tangent plane.
void restoreTangentPlanes(const TriangleMesh& mesh, const std::vector<Vec3f>& sweepNormal, CrossField& field) {
  parallelFor(mesh.numFaces(), 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      if (isZero(sweepNormal[f])) continue;
      Vec3d tangent;
      if (detail::tangentOf(faceNormal(mesh, f), field.at(f), tangent)) field.set(f, tangent);
    }
  });
}

}  // namespace

ProxyFieldResult computeProxyField(const TriangleMesh& mesh, const Topology& topology,
                                   const ProxyFieldOptions& options) {
  checkProxyFieldInput(mesh, topology, options);
  const std::uint32_t numFaces = topology.numFaces();
  ProxyFieldResult result;
  if (numFaces == 0) return result;

  reportProgress(options.progress, "proxy field: elements", 0.0);
  Proxy proxy;
  buildElements(mesh, topology, options.gridResolution, proxy);
  accumulateElements(mesh, topology, proxy);
  std::vector<std::uint32_t>().swap(proxy.elementFaces);
  std::vector<std::uint32_t>().swap(proxy.elementStart);
  result.elements = proxy.numElements();
  result.elementEdges = proxy.neighbours.size() / 2;

  const VectorC z = detail::solveElementField(proxy, options.progress, options.stats);
  reportProgress(options.progress, "proxy field: transfer", 0.5);
  // Unit normals as floats for the sweeps (zero for a zero-area face): 12 bytes per face, read
  // 4 times per face and sweep without decoding.
  std::vector<Vec3f> sweepNormal(options.smoothingSweeps > 0 ? numFaces : 0);
  transferToFaces(mesh, proxy, z, result.field, sweepNormal);
  std::vector<std::uint32_t>().swap(proxy.faceElement);  // freed before the sweeps

  std::vector<std::uint8_t> colour;
  result.colours = options.smoothingSweeps > 0 ? colourFaces(topology, colour) : 0;
  for (std::int32_t sweep = 0; sweep < options.smoothingSweeps; ++sweep) {
    reportProgress(options.progress, "proxy field: smooth", 0.6 + 0.4 * sweep / options.smoothingSweeps);
    smoothSweep(topology, colour, result.colours, options.sweepBlockFaces, sweepNormal, result.field);
  }
  // The exact tangent planes are restored once at the end.
  if (options.smoothingSweeps > 0) restoreTangentPlanes(mesh, sweepNormal, result.field);
  reportProgress(options.progress, "proxy field: smooth", 1.0);
  return result;
}

FieldMethod resolveFieldMethod(FieldMethod method, std::uint32_t numFaces) {
  if (method != FieldMethod::Auto) return method;
  return numFaces <= kDirectFieldMaxFaces ? FieldMethod::Direct : FieldMethod::Proxy;
}

const char* fieldMethodName(FieldMethod method) {
  switch (method) {
    case FieldMethod::Auto: return "auto";
    case FieldMethod::Direct: return "direct";
    case FieldMethod::Proxy: return "proxy";
  }
  return "unknown";
}

FieldMethod parseFieldMethod(const std::string& name) {
  if (name == "auto") return FieldMethod::Auto;
  if (name == "direct" || name == "smooth") return FieldMethod::Direct;
  if (name == "proxy") return FieldMethod::Proxy;
  throw InputError("unknown field method '" + name + "' (known: auto, direct or smooth, proxy)");
}

CrossField computeCrossField(TriangleMesh& mesh, const Topology& topology, FieldMethod method,
                             const SmoothFieldOptions& smooth, const ProxyFieldOptions& proxy,
                             const FieldGeometryOptions& geometry) {
  const bool direct = resolveFieldMethod(method, topology.numFaces()) == FieldMethod::Direct;
  if (!direct && smooth.curvatureWeight > 0.0) {
    throw InputError("curvature alignment needs the direct field: the proxy field (used above " +
                     std::to_string(kDirectFieldMaxFaces) + " faces) is the smoothest field only");
  }
  if (!direct && !smooth.alignCorners.empty()) {
    throw InputError("feature alignment needs the direct field: the proxy field (used above " +
                     std::to_string(kDirectFieldMaxFaces) + " faces) cannot follow feature curves");
  }
  const auto compute = [&](const TriangleMesh& surface) {
    return direct ? computeSmoothestField(surface, topology, smooth)
                  : computeProxyField(surface, topology, proxy).field;
  };
  // The direct solve aligns the field with smooth.alignCorners on the surface it solves on; the
  // directions are then turned exactly onto those edges of the mesh's own faces.
  const auto snap = [&](CrossField field) {
    if (direct && !smooth.alignCorners.empty()) snapToFeatureEdges(mesh, smooth.alignCorners, field);
    return field;
  };
  if (geometry.smoothingIterations == 0) return snap(compute(mesh));
  // The mesh itself, with the smoothed positions in place of its own while the field is solved
  // (restored on every exit): the smoothed surface needs no copy of the triangles.
  std::vector<Vec3f> own = smoothPositions(mesh, topology, geometry.smoothingIterations);
  RoughSpotResult rough;
  if (geometry.roughSpotGrid > 0.0) {
    rough = smoothRoughSpots(topology, own, geometry.roughSpotGrid, geometry.roughSpotMaxRegion);
    FieldSolveStats* stats = smooth.stats ? smooth.stats : proxy.stats;
    if (stats) {
      stats->roughVertices = rough.roughVertices;
      stats->roughSpotVertices = rough.moved.size();
      stats->roughSpotsCapped = rough.capped;
    }
  }
  struct Restore {
    std::vector<Vec3f>& a;
    std::vector<Vec3f>& b;
    ~Restore() { a.swap(b); }
  };
  CrossField field;
  {
    mesh.positions.swap(own);
    Restore restore{mesh.positions, own};
    field = compute(mesh);
  }
  const std::vector<Vec3f>& flat = own;  // now the smoothed positions
  // Onto the mesh's own faces by the rotation between the two normals, which computeSingularities
  // undoes exactly (a projection would not: on a tilted face it turns the direction).
  parallelFor(topology.numFaces(), 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Triangle& t = mesh.triangles[f];
      field.set(f, rotateBetween(detail::faceFrameNormal(flat, t), detail::faceFrameNormal(mesh.positions, t), field.at(f)));
    }
  });
  field = snap(std::move(field));
  field.framePositions = std::move(own);
  field.frameSmoothing = geometry.smoothingIterations;
  field.frameOverrides = std::move(rough.moved);
  return field;
}

CrossField computeCrossField(const TriangleMesh& mesh, const Topology& topology, FieldMethod method,
                             const SmoothFieldOptions& smooth, const ProxyFieldOptions& proxy,
                             const FieldGeometryOptions& geometry) {
  TriangleMesh copy = mesh;
  return computeCrossField(copy, topology, method, smooth, proxy, geometry);
}

double measureFieldEnergy(const TriangleMesh& mesh, const Topology& topology, const CrossField& field) {
  const std::uint32_t numFaces = topology.numFaces();
  if (field.direction.size() != numFaces) {
    throw InputError("measureFieldEnergy: field has " + std::to_string(field.direction.size()) +
                     " directions for " + std::to_string(numFaces) + " faces");
  }
  std::vector<double> perFace(numFaces, 0.0);
  parallelFor(numFaces, 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const FaceGeometry g = faceGeometry(mesh, f);
      const Complex zf = fourthPower(field.at(f), g.e1, g.e2);
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        const CornerId o = topology.opposite(c);
        if (o == kInvalidId || o < c) continue;
        const FaceGeometry h = faceGeometry(mesh, cornerFace(o));
        const Complex zg = fourthPower(rotateBetween(h.n, g.n, field.at(cornerFace(o))), g.e1, g.e2);
        perFace[f] += dualWeight(edgeLength(mesh, topology, c), g.centroid, h.centroid) * std::norm(zf - zg);
      }
    }
  });
  double sum = 0.0;
  for (double e : perFace) sum += e;
  return sum;
}

}  // namespace seamvox
