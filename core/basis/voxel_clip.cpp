#include "core/basis/voxel_clip.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/system/errors.h"

namespace seamvox {

namespace {

double polygonArea(const ClipPolygon& poly) {
  if (poly.size < 3) return 0.0;
  Vec3d sum = Vec3d::Zero();
  for (int i = 1; i + 1 < poly.size; ++i) {
    sum += (poly.point[i] - poly.point[0]).cross(poly.point[i + 1] - poly.point[0]);
  }
  return 0.5 * sum.norm();
}

void push(ClipPolygon& poly, const Vec3d& p) {
  if (poly.size < ClipPolygon::kCapacity) poly.point[poly.size++] = p;
}

// Splits poly by the plane g[axis] = c into the parts below (g < c) and above (g > c); points on
// the plane go to both. A polygon lying in the plane goes above only (half-open voxels).
void splitPolygon(const ClipPolygon& poly, int axis, double c, ClipPolygon& below,
                  ClipPolygon& above) {
  below.size = above.size = 0;
  double d[ClipPolygon::kCapacity];
  bool anyBelow = false, anyAbove = false;
  for (int i = 0; i < poly.size; ++i) {
    d[i] = poly.point[i][axis] - c;
    anyBelow |= d[i] < 0.0;
    anyAbove |= d[i] > 0.0;
  }
  if (!anyBelow) {
    above = poly;
    return;
  }
  if (!anyAbove) {
    below = poly;
    return;
  }
  for (int i = 0; i < poly.size; ++i) {
    const int j = (i + 1) % poly.size;
    const Vec3d& p = poly.point[i];
    if (d[i] <= 0.0) push(below, p);
    if (d[i] >= 0.0) push(above, p);
    if ((d[i] < 0.0 && d[j] > 0.0) || (d[i] > 0.0 && d[j] < 0.0)) {
      Vec3d x = p + (poly.point[j] - p) * (d[i] / (d[i] - d[j]));
      x[axis] = c;
      push(below, x);
      push(above, x);
    }
  }
}

// Keeps the part of poly with sign * (g[axis] - c) >= 0.
void keepSide(ClipPolygon& poly, int axis, double c, double sign) {
  ClipPolygon below, above;
  splitPolygon(poly, axis, c, below, above);
  if (sign > 0) {
    poly = above;
  } else {
    // A polygon lying in the plane belongs to the closed box on either side.
    poly = below.size == 0 && above.size > 0 &&
                   std::all_of(above.point.begin(), above.point.begin() + above.size,
                               [&](const Vec3d& p) { return p[axis] == c; })
               ? above
               : below;
  }
}

void sliceAxis(const ClipPolygon& poly, int axis, VoxelCoord& voxel, std::int32_t resolution,
               std::vector<VoxelPiece>& out) {
  if (axis == 3) {
    const double area = polygonArea(poly);
    if (area > 0.0) {
      out.emplace_back();
      out.back().voxel = voxel;
      out.back().polygon = poly;
      out.back().area = area;
    }
    return;
  }
  double lowest = poly.point[0][axis], highest = lowest;
  for (int i = 1; i < poly.size; ++i) {
    lowest = std::min(lowest, poly.point[i][axis]);
    highest = std::max(highest, poly.point[i][axis]);
  }
  auto cell = [&](double x) {
    return static_cast<std::int32_t>(std::clamp(std::floor(x), 0.0, double(resolution - 1)));
  };
  const std::int32_t lo = cell(lowest), hi = cell(highest);
  ClipPolygon rest = poly, below, above;
  for (std::int32_t i = lo; i < hi; ++i) {
    splitPolygon(rest, axis, double(i + 1), below, above);
    if (below.size >= 3) {
      voxel[axis] = i;
      sliceAxis(below, axis + 1, voxel, resolution, out);
    }
    rest = above;
    if (rest.size < 3) return;
  }
  voxel[axis] = hi;
  sliceAxis(rest, axis + 1, voxel, resolution, out);
}

// Degree-4 exact rule on a triangle (barycentric points, weights summing to 1).
struct TrianglePoint {
  double a, b, c, w;
};
constexpr double kW1 = 0.223381589678011, kA1 = 0.445948490915965, kB1 = 0.108103018168070;
constexpr double kW2 = 0.109951743655322, kA2 = 0.091576213509771, kB2 = 0.816847572980459;
constexpr TrianglePoint kRule[6] = {{kA1, kA1, kB1, kW1}, {kA1, kB1, kA1, kW1},
                                    {kB1, kA1, kA1, kW1}, {kA2, kA2, kB2, kW2},
                                    {kA2, kB2, kA2, kW2}, {kB2, kA2, kA2, kW2}};
// Degree-2 exact rule, for pieces much smaller than a voxel (accumulateFragment).
constexpr double kA3 = 2.0 / 3.0, kB3 = 1.0 / 6.0, kW3 = 1.0 / 3.0;
constexpr TrianglePoint kSmallRule[3] = {{kA3, kB3, kB3, kW3}, {kB3, kA3, kB3, kW3}, {kB3, kB3, kA3, kW3}};
/// Squared diameter (voxel units) below which a piece takes kSmallRule: the integrands are
/// quartics with O(1) derivatives in a unit voxel, so the rule's error is O(d^3) of the piece's
/// own integral (d < 1/4: below 1e-4 of the largest entry, tests/test_voxel.cpp). Positive weights keep
/// constants and linear maps exact, as every rule does.
constexpr double kSmallPieceDiameter2 = 0.0625;

}  // namespace

VoxelCoord VoxelGridGeometry::voxelOf(const Vec3d& g) const {
  VoxelCoord v;
  for (int a = 0; a < 3; ++a) {
    v[a] = static_cast<std::int32_t>(std::clamp(std::floor(g[a]), 0.0, double(resolution - 1)));
  }
  return v;
}

std::array<Vec3d, 3> faceGridCoords(const TriangleMesh& mesh, const VoxelGridGeometry& grid,
                                    FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return {grid.toGrid(mesh.position(t[0])), grid.toGrid(mesh.position(t[1])),
          grid.toGrid(mesh.position(t[2]))};
}

VoxelGridGeometry makeVoxelGrid(const BoundingBox& box, std::int32_t resolution) {
  if (resolution < 4 || resolution > 1024 || (resolution & (resolution - 1)) != 0) {
    throw InputError("voxel grid: resolution " + std::to_string(resolution) +
                     " is not a power of two in 4..1024");
  }
  VoxelGridGeometry grid;
  grid.resolution = resolution;
  const Vec3d extent = box.extent();
  const double largest = extent.maxCoeff();
  grid.voxelSize = largest > 0.0 && std::isfinite(largest) ? largest / (resolution - 2) : 1.0;
  const Vec3d center = box.isEmpty() ? Vec3d::Zero() : Vec3d(0.5 * (box.min + box.max));
  // Centred, shifted by an irregular fraction of a voxel: at least 0.87 voxels of padding.
  grid.origin = center - Vec3d::Constant((0.5 * resolution - 0.1234567) * grid.voxelSize);
  return grid;
}

void clipTriangleToVoxels(const std::array<Vec3d, 3>& g, std::int32_t resolution,
                          std::vector<VoxelPiece>& out) {
  out.clear();
  ClipPolygon poly;
  for (const Vec3d& p : g) push(poly, p);
  VoxelCoord voxel{0, 0, 0};
  sliceAxis(poly, 0, voxel, resolution, out);
}

ClipPolygon clipTriangleToVoxel(const std::array<Vec3d, 3>& g, const VoxelCoord& voxel) {
  ClipPolygon poly;
  for (const Vec3d& p : g) push(poly, p);
  const Vec3d lo(voxel[0], voxel[1], voxel[2]);
  const Vec3d hi = lo + Vec3d::Ones();
  if (std::all_of(g.begin(), g.end(), [&](const Vec3d& p) {
        return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
      })) {
    return poly;  // the common case on fine meshes: the whole triangle
  }
  for (int a = 0; a < 3 && poly.size >= 3; ++a) {
    keepSide(poly, a, double(voxel[a]), +1.0);
    if (poly.size >= 3) keepSide(poly, a, double(voxel[a] + 1), -1.0);
  }
  if (poly.size < 3) poly.size = 0;
  return poly;
}

bool segmentOverlapsBox(const Vec3d& a, const Vec3d& b, const Vec3d& lo, const Vec3d& hi) {
  if (a == b) return false;
  double t0 = 0.0, t1 = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double d = b[k] - a[k];
    if (d == 0.0) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - a[k]) / d, tb = (hi[k] - a[k]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (!(t1 > t0)) return false;
  }
  return t1 > t0;
}

std::uint8_t voxelEdgeMask(const std::array<Vec3d, 3>& g, const VoxelCoord& voxel) {
  const Vec3d lo(voxel[0], voxel[1], voxel[2]);
  const Vec3d hi = lo + Vec3d::Ones();
  std::uint8_t mask = 0;
  for (int j = 0; j < 3; ++j) {
    if (segmentOverlapsBox(g[(j + 1) % 3], g[(j + 2) % 3], lo, hi)) mask |= 1u << j;
  }
  return mask;
}

void trilinearWeights(const Vec3d& t, double weights[8]) {
  for (int k = 0; k < 8; ++k) {
    weights[k] = ((k & 1) ? t[0] : 1.0 - t[0]) * ((k & 2) ? t[1] : 1.0 - t[1]) *
                 ((k & 4) ? t[2] : 1.0 - t[2]);
  }
}

namespace {

// Index of (a, b), a <= b < 4, in the 10 packed pairs of FragmentSums::yz/xz/xy.
constexpr int packed4(int a, int b) { return a * 4 - a * (a - 1) / 2 + (b - a); }

// The 36 pairs (a, b) of B-splines as the three bilinear-weight pairs (one per axis, into
// FragmentSums::yz, xz and xy) and the sign s_a s_b of each axis: a table built once.
struct PairTable {
  int yz[36], xz[36], xy[36];
  double syz[36], sxz[36], sxy[36];
  constexpr PairTable() : yz(), xz(), xy(), syz(), sxz(), sxy() {
    int idx = 0;
    for (int a = 0; a < 8; ++a) {
      const int ia = a & 1, ja = a >> 1 & 1, la = a >> 2 & 1;
      for (int b = a; b < 8; ++b, ++idx) {
        const int ib = b & 1, jb = b >> 1 & 1, lb = b >> 2 & 1;
        const int p = ja + 2 * la, q = jb + 2 * lb, r = ia + 2 * la, t = ib + 2 * lb;
        const int x = ia + 2 * ja, y = ib + 2 * jb;
        yz[idx] = p <= q ? packed4(p, q) : packed4(q, p);
        xz[idx] = r <= t ? packed4(r, t) : packed4(t, r);
        xy[idx] = x <= y ? packed4(x, y) : packed4(y, x);
        syz[idx] = ia == ib ? 1.0 : -1.0;
        sxz[idx] = ja == jb ? 1.0 : -1.0;
        sxy[idx] = la == lb ? 1.0 : -1.0;
      }
    }
  }
};
constexpr PairTable kPairs;

}  // namespace

void accumulateFragment(const ClipPolygon& fragment, const VoxelCoord& voxel, double voxelSize,
                        const Vec3d& n, const Vec3d& u, double edgeLength, FragmentSums& sums) {
  if (fragment.size < 3) return;
  // B-spline k = (i, j, l) (bits 0, 1, 2 of k) has the 3D gradient
  //   g_k = (s_i Y_j Z_l, X_i s_j Z_l, X_i Y_j s_l),  X_0 = 1 - x, X_1 = x, s_0 = -1, s_1 = +1,
  // so <g_a, g_b> needs only the integrals of the 10 distinct products of each axis pair's
  // bilinear weights (30 in all), and the integral of g_k only those of the 12 weights. The
  // normal part (n . g_a)(n . g_b) has no such structure and is integrated pair by pair.
  double weights[12] = {};  // integrals of byz, bxz, bxy (this fragment: its field is its own)
  // Local sums (no aliasing with the inputs: they stay in registers and cache lines of the stack).
  double yz[10] = {}, xz[10] = {}, xy[10] = {}, normal[36] = {};
  const Vec3d base(voxel[0], voxel[1], voxel[2]);
  const Vec3d p0 = fragment.point[0] - base;
  bool any = false;
  // One quadrature point t (voxel coordinates) of weight w.
  const auto addPoint = [&](const Vec3d& t, double w) {
    const double X[2] = {1.0 - t[0], t[0]}, Y[2] = {1.0 - t[1], t[1]}, Z[2] = {1.0 - t[2], t[2]};
    // Bilinear weights indexed by (bit of the first axis) + 2 (bit of the second).
    const double byz[4] = {Y[0] * Z[0], Y[1] * Z[0], Y[0] * Z[1], Y[1] * Z[1]};
    const double bxz[4] = {X[0] * Z[0], X[1] * Z[0], X[0] * Z[1], X[1] * Z[1]};
    const double bxy[4] = {X[0] * Y[0], X[1] * Y[0], X[0] * Y[1], X[1] * Y[1]};
    int idx = 0;
    for (int a = 0; a < 4; ++a) {
      const double wyz = w * byz[a], wxz = w * bxz[a], wxy = w * bxy[a];
      weights[a] += wyz;
      weights[4 + a] += wxz;
      weights[8 + a] += wxy;
      for (int b = a; b < 4; ++b, ++idx) {
        yz[idx] += wyz * byz[b];
        xz[idx] += wxz * bxz[b];
        xy[idx] += wxy * bxy[b];
      }
    }
    // n . g_k = s_i n_x byz[j + 2l] + s_j n_y bxz[i + 2l] + s_l n_z bxy[i + 2j].
    double nyz[4], nxz[4], nxy[4], nk[8];
    for (int a = 0; a < 4; ++a) nyz[a] = n[0] * byz[a], nxz[a] = n[1] * bxz[a], nxy[a] = n[2] * bxy[a];
    for (int k = 0; k < 8; ++k) {
      const int i = k & 1, j = k >> 1 & 1, l = k >> 2 & 1;
      nk[k] = (i ? nyz[j + 2 * l] : -nyz[j + 2 * l]) + (j ? nxz[i + 2 * l] : -nxz[i + 2 * l]) +
              (l ? nxy[i + 2 * j] : -nxy[i + 2 * j]);
    }
    idx = 0;
    for (int a = 0; a < 8; ++a) {
      const double wa = w * nk[a];
      for (int b = a; b < 8; ++b, ++idx) normal[idx] += wa * nk[b];
    }
  };
  for (int i = 1; i + 1 < fragment.size; ++i) {
    const Vec3d p1 = fragment.point[i] - base, p2 = fragment.point[i + 1] - base;
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if (!(area > 0.0)) continue;
    any = true;
    sums.area += area * voxelSize * voxelSize;
    const double diameter2 =
        std::max({(p1 - p0).squaredNorm(), (p2 - p0).squaredNorm(), (p2 - p1).squaredNorm()});
    if (diameter2 < kSmallPieceDiameter2) {
      for (const TrianglePoint& q : kSmallRule) addPoint(q.a * p0 + q.b * p1 + q.c * p2, q.w * area);
    } else {
      for (const TrianglePoint& q : kRule) addPoint(q.a * p0 + q.b * p1 + q.c * p2, q.w * area);
    }
  }
  if (!any) return;
  sums.any = true;
  for (int i = 0; i < 10; ++i) sums.yz[i] += yz[i], sums.xz[i] += xz[i], sums.xy[i] += xy[i];
  for (int i = 0; i < 36; ++i) sums.normal[i] += normal[i];
  // <grad_M g_k, u> = <g_k, u - (n . u) n>, the same with v = n x u; the integrals are linear in g.
  const Vec3d v = n.cross(u);
  const Vec3d ut = u - n.dot(u) * n, vt = v - n.dot(v) * n;
  const double rhsScale = voxelSize / edgeLength;
  for (int k = 0; k < 8; ++k) {
    const int i = k & 1, j = k >> 1 & 1, l = k >> 2 & 1;
    const Vec3d g((i ? 1.0 : -1.0) * weights[j + 2 * l], (j ? 1.0 : -1.0) * weights[4 + i + 2 * l],
                  (l ? 1.0 : -1.0) * weights[8 + i + 2 * j]);
    sums.rhs[k] += rhsScale * std::complex<double>(g.dot(ut), g.dot(vt));
  }
}

void finishElement(const FragmentSums& sums, VoxelIntegrals& acc, double normalWeight, double* normalAcc) {
  if (!sums.any) return;
  acc.area += sums.area;
  for (int k = 0; k < 8; ++k) acc.rhs[k] += sums.rhs[k];
  for (int idx = 0; idx < 36; ++idx) {
    const double full = kPairs.syz[idx] * sums.yz[kPairs.yz[idx]] + kPairs.sxz[idx] * sums.xz[kPairs.xz[idx]] +
                        kPairs.sxy[idx] * sums.xy[kPairs.xy[idx]];
    // Tangential gradients: <g_a, g_b> - (n . g_a)(n . g_b).
    acc.stiffness[idx] += full + (normalWeight - 1.0) * sums.normal[idx];
    if (normalAcc) normalAcc[idx] += sums.normal[idx];
  }
}

void addFragmentIntegrals(const ClipPolygon& fragment, const VoxelCoord& voxel, double voxelSize,
                          const Vec3d& n, const Vec3d& u, double edgeLength, VoxelIntegrals& acc,
                          double normalWeight, double* normalAcc) {
  FragmentSums sums;
  accumulateFragment(fragment, voxel, voxelSize, n, u, edgeLength, sums);
  finishElement(sums, acc, normalWeight, normalAcc);
}

}  // namespace seamvox
