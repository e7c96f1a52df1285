#include "core/synth/generate.h"

#include <tbb/combinable.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace {

// ---- deterministic randomness ------------------------------------------------------------------
// Only integer arithmetic and IEEE +, -, *, /, sqrt below, so results are identical everywhere.

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// Uniform in [0, 1) from 53 random bits.
double unitFromBits(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

/// A small sequential generator (splitmix64) for placing holes and islands.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(mix64(seed ^ 0x5eed5eed5eedull)) {}
  std::uint64_t next() {
    state_ += 0x9e3779b97f4a7c15ull;
    return mix64(state_);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unitFromBits(next()); }
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(next() % n); }

 private:
  std::uint64_t state_;
};

/// Value in [-1, 1] attached to an integer lattice point.
double latticeValue(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  const std::uint64_t h = mix64(seed ^ (static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ull) ^
                                (static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4full) ^
                                (static_cast<std::uint64_t>(z) * 0x165667b19e3779f9ull));
  return 2.0 * unitFromBits(h) - 1.0;
}

double smoothStep(double t) { return t * t * (3.0 - 2.0 * t); }

/// Trilinear value noise with smooth-step weights; C1, in [-1, 1].
double valueNoise(const Vec3d& p, std::uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto x = static_cast<std::int64_t>(fx), y = static_cast<std::int64_t>(fy),
             z = static_cast<std::int64_t>(fz);
  const double tx = smoothStep(p.x() - fx), ty = smoothStep(p.y() - fy), tz = smoothStep(p.z() - fz);
  double layer[2];
  for (int k = 0; k < 2; ++k) {
    const double v00 = latticeValue(x, y, z + k, seed), v10 = latticeValue(x + 1, y, z + k, seed);
    const double v01 = latticeValue(x, y + 1, z + k, seed);
    const double v11 = latticeValue(x + 1, y + 1, z + k, seed);
    const double a = v00 + tx * (v10 - v00), b = v01 + tx * (v11 - v01);
    layer[k] = a + ty * (b - a);
  }
  return layer[0] + tz * (layer[1] - layer[0]);
}

/// Smooth multi-octave bumps: sum of value noise at doubling frequencies, halving weights,
/// normalized to [-1, 1].
struct Bumps {
  double amplitude = 0.0;  ///< displacement scale (absolute units)
  double frequency = 2.0;  ///< of the first octave, per unit length
  int octaves = 4;
  std::uint64_t seed = 1;

  double operator()(const Vec3d& p) const {
    if (amplitude == 0.0) return 0.0;
    double sum = 0.0, weight = 1.0, total = 0.0, freq = frequency;
    for (int o = 0; o < octaves; ++o) {
      sum += weight * valueNoise(p * freq, seed + 0x1000u * static_cast<std::uint64_t>(o));
      total += weight;
      weight *= 0.5;
      freq *= 2.0;
    }
    return amplitude * sum / total;
  }
};

/// sin and cos of an angle given in turns (1 turn = 2 pi), by range reduction to
/// [-pi/4, pi/4] and fixed polynomials (|error| < 1e-16), so no libm difference can creep in.
void sinCosTurns(double turns, double& sine, double& cosine) {
  const double q = std::floor(4.0 * turns + 0.5);
  const double x = (turns - 0.25 * q) * 6.283185307179586476925;
  const double x2 = x * x;
  const double s =
      x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880 +
          x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800.0 + x2 * (-1.0 / 1307674368000.0))))))));
  const double c =
      1.0 + x2 * (-1.0 / 2 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 +
          x2 * (-1.0 / 3628800 + x2 * (1.0 / 479001600 + x2 * (-1.0 / 87178291200.0 +
          x2 * (1.0 / 20922789888000.0))))))));
  switch (static_cast<std::int64_t>(q) & 3) {
    case 0: sine = s; cosine = c; break;
    case 1: sine = c; cosine = -s; break;
    case 2: sine = -s; cosine = -c; break;
    default: sine = -c; cosine = s; break;
  }
}

template <class F>
void parallelRange(std::uint64_t n, F&& body) {
  if (n < 20000) {
    body(std::uint64_t{0}, n);
    return;
  }
  parallelFor(n, 8192, [&](const IndexRange& r) { body(r.begin(), r.end()); });
}

Vec3f toFloat(const Vec3d& p) { return p.cast<float>(); }

// ---- the surface of a box of a x b x c cells, as a lattice of vertices ---------------------------

/// Vertices: the lattice points (i, j, k), 0 <= i <= a etc., on the box surface, numbered layer
/// by layer: the full bottom layer k = 0, one ring per middle layer, the full top layer k = c.
/// Faces: each of the 6 sides is a grid of quads, two triangles each, outward oriented.
struct BoxLattice {
  std::uint32_t n[3] = {1, 1, 1};

  std::uint64_t layerSize() const { return std::uint64_t(n[0] + 1) * (n[1] + 1); }
  std::uint64_t ringSize() const { return 2 * std::uint64_t(n[0] + n[1]); }
  std::uint64_t numVertices() const { return 2 * layerSize() + (n[2] - 1) * ringSize(); }
  std::uint64_t numFaces() const {
    return 4 * (std::uint64_t(n[0]) * n[1] + std::uint64_t(n[1]) * n[2] + std::uint64_t(n[2]) * n[0]);
  }

  std::uint64_t id(std::uint32_t i, std::uint32_t j, std::uint32_t k) const {
    const std::uint32_t a = n[0], b = n[1];
    if (k == 0) return std::uint64_t(i) * (b + 1) + j;
    if (k == n[2]) return layerSize() + (n[2] - 1) * ringSize() + std::uint64_t(i) * (b + 1) + j;
    std::uint64_t r;
    if (j == 0 && i < a) r = i;
    else if (i == a && j < b) r = a + j;
    else if (j == b && i > 0) r = a + b + (a - i);
    else r = 2 * a + b + (b - j);
    return layerSize() + (k - 1) * ringSize() + r;
  }

  void point(std::uint64_t id, std::uint32_t& i, std::uint32_t& j, std::uint32_t& k) const {
    const std::uint32_t a = n[0], b = n[1];
    const std::uint64_t middle = (n[2] - 1) * ringSize();
    if (id < layerSize() || id >= layerSize() + middle) {
      const bool top = id >= layerSize();
      const std::uint64_t local = top ? id - layerSize() - middle : id;
      i = static_cast<std::uint32_t>(local / (b + 1));
      j = static_cast<std::uint32_t>(local % (b + 1));
      k = top ? n[2] : 0;
      return;
    }
    const std::uint64_t local = id - layerSize();
    k = static_cast<std::uint32_t>(1 + local / ringSize());
    const auto r = static_cast<std::uint32_t>(local % ringSize());
    if (r < a) { i = r; j = 0; }
    else if (r < a + b) { i = a; j = r - a; }
    else if (r < 2 * a + b) { i = a - (r - a - b); j = b; }
    else { i = 0; j = b - (r - 2 * a - b); }
  }

  /// Side s in 0..5: axis d = s / 2, on the low (s even) or high (s odd) face. The side's grid
  /// runs over axes u = (d + 1) % 3 and v = (d + 2) % 3 (e_u x e_v = e_d).
  std::uint32_t sideWidth(int s) const { return n[(s / 2 + 1) % 3]; }
  std::uint32_t sideHeight(int s) const { return n[(s / 2 + 2) % 3]; }
  std::uint64_t sideFaces(int s) const { return 2 * std::uint64_t(sideWidth(s)) * sideHeight(s); }
  std::uint64_t sideOffset(int s) const {
    std::uint64_t o = 0;
    for (int t = 0; t < s; ++t) o += sideFaces(t);
    return o;
  }
  std::uint64_t sideVertex(int s, std::uint32_t x, std::uint32_t y) const {
    const int d = s / 2;
    std::uint32_t c[3];
    c[d] = (s & 1) ? n[d] : 0;
    c[(d + 1) % 3] = x;
    c[(d + 2) % 3] = y;
    return id(c[0], c[1], c[2]);
  }
  /// First of the two triangles of quad (x, y) of side s.
  std::uint64_t quadFace(int s, std::uint32_t x, std::uint32_t y) const {
    return sideOffset(s) + 2 * (std::uint64_t(y) * sideWidth(s) + x);
  }
};

/// Box dimensions a <= b <= c near a cube with 4 (ab + bc + ca) as close as possible to faces
/// (ties: the first found, i.e. the smallest a).
BoxLattice chooseBox(std::uint64_t faces) {
  const auto n0 = static_cast<std::int64_t>(std::sqrt(static_cast<double>(faces) / 12.0));
  BoxLattice best;
  std::uint64_t bestError = std::numeric_limits<std::uint64_t>::max();
  // Sides may differ by up to 4 cells (a nearly cubic box), which gives fine steps in 4 (ab+bc+ca).
  for (std::int64_t a = std::max<std::int64_t>(1, n0 - 3); a <= n0 + 2; ++a) {
    for (std::int64_t b = a; b <= a + 4; ++b) {
      for (std::int64_t c = b; c <= a + 4; ++c) {
        BoxLattice box;
        box.n[0] = static_cast<std::uint32_t>(a);
        box.n[1] = static_cast<std::uint32_t>(b);
        box.n[2] = static_cast<std::uint32_t>(c);
        const std::uint64_t f = box.numFaces();
        const std::uint64_t error = f > faces ? f - faces : faces - f;
        if (error < bestError) {
          bestError = error;
          best = box;
        }
      }
    }
  }
  return best;
}

/// A bumpy sphere made from the box lattice projected radially (with an equal-angle warp).
/// jitter adds per-vertex radial noise of that relative size (scan noise).
struct BoxSphere {
  BoxLattice box;
  Vec3d center = Vec3d::Zero();
  double radius = 1.0;
  Bumps bumps;
  double jitter = 0.0;
  std::uint64_t seed = 0;
  std::vector<double> warp[3];  ///< per axis: lattice i -> tan(pi/4 (2 i / n - 1))

  BoxSphere(const BoxLattice& lattice, const Vec3d& c, double r, const Bumps& b, double j, std::uint64_t s)
      : box(lattice), center(c), radius(r), bumps(b), jitter(j), seed(s) {
    for (int axis = 0; axis < 3; ++axis) {
      for (std::uint32_t i = 0; i <= box.n[axis]; ++i) {
        double sine, cosine;
        sinCosTurns((2.0 * i / box.n[axis] - 1.0) / 8.0, sine, cosine);
        warp[axis].push_back(sine / cosine);
      }
    }
  }

  /// Position of lattice vertex v.
  Vec3f position(std::uint64_t v) const {
    std::uint32_t ijk[3];
    box.point(v, ijk[0], ijk[1], ijk[2]);
    Vec3d d(warp[0][ijk[0]], warp[1][ijk[1]], warp[2][ijk[2]]);
    d /= d.norm();
    double r = radius * (1.0 + bumps(d));
    if (jitter != 0.0) r *= 1.0 + jitter * (2.0 * unitFromBits(mix64(seed ^ mix64(v))) - 1.0);
    return toFloat(center + r * d);
  }

  /// The two triangles of quad (x, y) of side s, outward oriented, vertex ids offset by v0.
  void quad(std::uint64_t v0, int s, std::uint32_t x, std::uint32_t y, Triangle& t0, Triangle& t1) const {
    const auto p00 = static_cast<VertexId>(v0 + box.sideVertex(s, x, y));
    const auto p10 = static_cast<VertexId>(v0 + box.sideVertex(s, x + 1, y));
    const auto p11 = static_cast<VertexId>(v0 + box.sideVertex(s, x + 1, y + 1));
    const auto p01 = static_cast<VertexId>(v0 + box.sideVertex(s, x, y + 1));
    if ((x + y) & 1) {
      t0 = {p00, p10, p01};
      t1 = {p10, p11, p01};
    } else {
      t0 = {p00, p10, p11};
      t1 = {p00, p11, p01};
    }
    if (!(s & 1)) {
      std::swap(t0[1], t0[2]);
      std::swap(t1[1], t1[2]);
    }
  }
};

/// Appends a box sphere's vertices and faces.
void appendBoxSphere(TriangleMesh& mesh, const BoxLattice& box, const Vec3d& center, double radius,
                     const Bumps& bumps, double jitter, std::uint64_t seed) {
  const BoxSphere sphere(box, center, radius, bumps, jitter, seed);
  const std::uint64_t v0 = mesh.positions.size(), f0 = mesh.triangles.size();
  mesh.positions.resize(v0 + box.numVertices());
  mesh.triangles.resize(f0 + box.numFaces());
  parallelRange(box.numVertices(), [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t v = begin; v < end; ++v) mesh.positions[v0 + v] = sphere.position(v);
  });
  for (int s = 0; s < 6; ++s) {
    const std::uint32_t w = box.sideWidth(s), h = box.sideHeight(s);
    parallelRange(h, [&](std::uint64_t yBegin, std::uint64_t yEnd) {
      for (auto y = static_cast<std::uint32_t>(yBegin); y < yEnd; ++y) {
        for (std::uint32_t x = 0; x < w; ++x) {
          const std::uint64_t f = f0 + box.quadFace(s, x, y);
          sphere.quad(v0, s, x, y, mesh.triangles[f], mesh.triangles[f + 1]);
        }
      }
    });
  }
}

// ---- tori ------------------------------------------------------------------------------------

/// An m x n torus grid: major angle i / m turns, tube angle j / n turns; vertex id i * n + j.
struct TorusGrid {
  std::uint32_t m = 3, n = 3;
  double major = 1.0, minor = 0.4;
  double centerX = 0.0;
  bool mirrored = false;  ///< reflected through the plane x = 0 (faces reversed to stay outward)

  VertexId id(std::int64_t i, std::int64_t j) const {
    const std::int64_t im = ((i % m) + m) % m, jm = ((j % n) + n) % n;
    return static_cast<VertexId>(im * n + jm);
  }
  void point(std::int64_t i, std::int64_t j, Vec3d& position, Vec3d& normal) const {
    double su, cu, sv, cv;
    sinCosTurns(static_cast<double>(i) / m, su, cu);
    sinCosTurns(static_cast<double>(j) / n, sv, cv);
    normal = Vec3d(cv * cu, cv * su, sv);
    position = Vec3d(centerX + major * cu, major * su, 0.0) + minor * normal;
    if (mirrored) {
      position.x() = -position.x();
      normal.x() = -normal.x();
    }
  }
};

/// Position of torus vertex (i, j) displaced by the bumps along the normal.
Vec3f torusPosition(const TorusGrid& torus, const Bumps& bumps, std::int64_t i, std::int64_t j) {
  Vec3d p, nrm;
  torus.point(i, j, p, nrm);
  return toFloat(p + bumps(p) * nrm);
}

/// The two triangles of torus quad (i, j), outward oriented, vertex ids offset by v0.
void torusQuad(const TorusGrid& torus, std::uint64_t v0, std::int64_t i, std::int64_t j, Triangle& t0, Triangle& t1) {
  const auto p00 = static_cast<VertexId>(v0 + torus.id(i, j));
  const auto p10 = static_cast<VertexId>(v0 + torus.id(i + 1, j));
  const auto p11 = static_cast<VertexId>(v0 + torus.id(i + 1, j + 1));
  const auto p01 = static_cast<VertexId>(v0 + torus.id(i, j + 1));
  t0 = {p00, p10, p11};
  t1 = {p00, p11, p01};
  if (torus.mirrored) {
    std::swap(t0[1], t0[2]);
    std::swap(t1[1], t1[2]);
  }
}

/// Appends a bumpy torus; quads with skip(i, j) are left out (their vertices stay, unreferenced).
template <class Skip>
void appendTorus(TriangleMesh& mesh, const TorusGrid& torus, const Bumps& bumps, Skip&& skip) {
  const std::uint64_t v0 = mesh.positions.size();
  mesh.positions.resize(v0 + std::uint64_t(torus.m) * torus.n);
  parallelRange(torus.m, [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t i = begin; i < end; ++i) {
      for (std::uint32_t j = 0; j < torus.n; ++j) {
        mesh.positions[v0 + torus.id(static_cast<std::int64_t>(i), j)] =
            torusPosition(torus, bumps, static_cast<std::int64_t>(i), j);
      }
    }
  });
  // Count kept quads per row so rows can be filled in parallel.
  std::vector<std::uint64_t> rowStart(torus.m + 1, 0);
  for (std::uint32_t i = 0; i < torus.m; ++i) {
    std::uint64_t kept = 0;
    for (std::uint32_t j = 0; j < torus.n; ++j) kept += skip(i, j) ? 0 : 1;
    rowStart[i + 1] = rowStart[i] + 2 * kept;
  }
  const std::uint64_t f0 = mesh.triangles.size();
  mesh.triangles.resize(f0 + rowStart[torus.m]);
  parallelRange(torus.m, [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t i = begin; i < end; ++i) {
      std::uint64_t f = f0 + rowStart[i];
      for (std::uint32_t j = 0; j < torus.n; ++j) {
        if (skip(static_cast<std::uint32_t>(i), j)) continue;
        torusQuad(torus, v0, static_cast<std::int64_t>(i), j, mesh.triangles[f], mesh.triangles[f + 1]);
        f += 2;
      }
    }
  });
}

/// Drops vertices no triangle uses, keeping the order of the others.
void compactVertices(TriangleMesh& mesh) {
  std::vector<VertexId> newId(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) newId[v] = 1;
  }
  VertexId next = 0;
  for (std::size_t v = 0; v < newId.size(); ++v) {
    if (newId[v]) {
      mesh.positions[next] = mesh.positions[v];
      newId[v] = next++;
    } else {
      newId[v] = kInvalidId;
    }
  }
  mesh.positions.resize(next);  // keeps the capacity: no second copy of the positions
  parallelRange(mesh.triangles.size(), [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t f = begin; f < end; ++f) {
      for (VertexId& v : mesh.triangles[f]) v = newId[v];
    }
  });
}

// ---- the kinds -------------------------------------------------------------------------------

const Bumps kSphereBumps{0.08, 1.5, 5, 0};

GenerateResult generateSphere(const GenerateOptions& options) {
  GenerateResult result;
  Bumps bumps = kSphereBumps;
  bumps.seed = options.seed;
  appendBoxSphere(result.mesh, chooseBox(options.faces), Vec3d::Zero(), 1.0, bumps, 0.0, 0);
  return result;
}

/// Torus m x n with m / n near ratio and 2 m n close to faces.
TorusGrid chooseTorus(std::uint64_t faces, double ratio) {
  const auto n0 = static_cast<std::int64_t>(std::sqrt(static_cast<double>(faces) / (2.0 * ratio)));
  TorusGrid best;
  std::uint64_t bestError = std::numeric_limits<std::uint64_t>::max();
  for (std::int64_t n = std::max<std::int64_t>(3, n0 - 2); n <= std::max<std::int64_t>(3, n0 + 2); ++n) {
    for (std::int64_t m = std::max<std::int64_t>(3, 2 * n); m <= 3 * n; ++m) {
      const std::uint64_t f = 2 * std::uint64_t(m) * std::uint64_t(n);
      const std::uint64_t error = f > faces ? f - faces : faces - f;
      if (error < bestError) {
        bestError = error;
        best.m = static_cast<std::uint32_t>(m);
        best.n = static_cast<std::uint32_t>(n);
      }
    }
  }
  return best;
}

GenerateResult generateTorus(const GenerateOptions& options) {
  GenerateResult result;
  TorusGrid torus = chooseTorus(options.faces, 2.5);
  const Bumps bumps{0.04, 2.5, 4, options.seed};
  appendTorus(result.mesh, torus, bumps, [](std::uint32_t, std::uint32_t) { return false; });
  return result;
}

/// Layout of the genus-2 shape: two m x n tori (the second mirrored through x = 0), each with a
/// hole of 2ha x 2hb quads around its outer equator point facing the other, joined by a tube
/// of `rings` quad rings.
struct Genus2Layout {
  TorusGrid torus;
  std::int64_t ha = 1, hb = 1;
  std::uint32_t rings = 1;
  std::uint64_t faces() const {
    const std::uint64_t mn = std::uint64_t(torus.m) * torus.n;
    return 4 * (mn - 4 * std::uint64_t(ha * hb)) + 8 * std::uint64_t(ha + hb) * rings;
  }
};

constexpr double kGenus2Gap = 0.4;  // between the two tori, along x

Genus2Layout chooseGenus2(std::uint64_t faces) {
  const auto n0 = static_cast<std::int64_t>(std::sqrt(static_cast<double>(faces) / 10.0));
  Genus2Layout best;
  std::uint64_t bestError = std::numeric_limits<std::uint64_t>::max();
  for (std::int64_t n = std::max<std::int64_t>(4, n0 - 2); n <= std::max<std::int64_t>(4, n0 + 2); ++n) {
    for (std::int64_t m = 2 * n; m <= 3 * n; ++m) {
      Genus2Layout g;
      g.torus.m = static_cast<std::uint32_t>(m);
      g.torus.n = static_cast<std::uint32_t>(n);
      g.ha = std::max<std::int64_t>(1, std::llround(0.3 * m / 6.283185307179586));
      g.hb = std::max<std::int64_t>(1, std::llround(0.8 * n / 6.283185307179586));
      g.hb = std::min<std::int64_t>(g.hb, (n - 2) / 2);
      const double edge = 6.283185307179586 * g.torus.major / m;
      g.rings = static_cast<std::uint32_t>(std::max<std::int64_t>(1, std::llround((kGenus2Gap + 0.1) / edge)));
      const std::uint64_t f = g.faces();
      const std::uint64_t error = f > faces ? f - faces : faces - f;
      if (error < bestError) {
        bestError = error;
        best = g;
      }
    }
  }
  return best;
}

/// The genus-2 shape before its unreferenced vertices (inside the tori's holes) are dropped:
/// the left torus's m n vertices, the right torus's, then the tube's inner rings.
struct Genus2Shape {
  Genus2Layout layout;
  TorusGrid left, right;
  Bumps bumps;
  std::vector<std::pair<std::int64_t, std::int64_t>> loop;  ///< the hole's boundary in (i, j)
  std::uint64_t torusVertices = 0;

  explicit Genus2Shape(const GenerateOptions& options)
      : layout(chooseGenus2(options.faces)), bumps{0.03, 2.5, 4, options.seed} {
    const std::int64_t ha = layout.ha, hb = layout.hb;
    left = layout.torus;
    left.centerX = -(left.major + left.minor + 0.5 * kGenus2Gap);
    right = left;
    right.mirrored = true;
    torusVertices = std::uint64_t(left.m) * left.n;
    // Counter-clockwise in the (i, j) grid. The left torus's faces run it clockwise, the mirrored
    // right torus's counter-clockwise; the tube's faces run it the other way.
    for (std::int64_t i = -ha; i < ha; ++i) loop.emplace_back(i, -hb);
    for (std::int64_t j = -hb; j < hb; ++j) loop.emplace_back(ha, j);
    for (std::int64_t i = ha; i > -ha; --i) loop.emplace_back(i, hb);
    for (std::int64_t j = hb; j > -hb; --j) loop.emplace_back(-ha, j);
  }
  std::uint32_t loopSize() const { return static_cast<std::uint32_t>(loop.size()); }
  std::uint64_t numVertices() const { return 2 * torusVertices + std::uint64_t(layout.rings - 1) * loopSize(); }
  bool inHole(std::int64_t i, std::int64_t j) const {
    return (i + layout.ha) % left.m < 2 * layout.ha && (j + layout.hb) % left.n < 2 * layout.hb;
  }
  VertexId ringVertex(std::uint32_t s, std::uint32_t l) const {
    const std::uint32_t L = loopSize();
    const auto& [i, j] = loop[l % L];
    if (s == 0) return left.id(i, j);
    if (s == layout.rings) return static_cast<VertexId>(torusVertices + right.id(i, j));
    return static_cast<VertexId>(2 * torusVertices + std::uint64_t(s - 1) * L + l % L);
  }
  Vec3f position(std::uint64_t v) const {
    if (v < 2 * torusVertices) {
      const TorusGrid& torus = v < torusVertices ? left : right;
      const std::uint64_t local = v % torusVertices;
      return torusPosition(torus, bumps, static_cast<std::int64_t>(local / torus.n),
                           static_cast<std::int64_t>(local % torus.n));
    }
    const std::uint64_t k = v - 2 * torusVertices;
    const auto s = static_cast<std::uint32_t>(k / loopSize() + 1), l = static_cast<std::uint32_t>(k % loopSize());
    const double t = static_cast<double>(s) / layout.rings;
    Vec3d pl, nl, pr, nr;
    left.point(loop[l].first, loop[l].second, pl, nl);
    right.point(loop[l].first, loop[l].second, pr, nr);
    const Vec3d a = position(ringVertex(0, l)).cast<double>();
    const Vec3d b = position(ringVertex(layout.rings, l)).cast<double>();
    const Vec3d p = a + t * (b - a);
    Vec3d nrm = nl + t * (nr - nl);
    nrm /= nrm.norm();
    return toFloat(p + (4.0 * t * (1.0 - t)) * bumps(p) * nrm);
  }
  /// The two triangles of tube quad (s, l).
  void tubeQuad(std::uint32_t s, std::uint32_t l, Triangle& t0, Triangle& t1) const {
    const VertexId a = ringVertex(s, l), b = ringVertex(s, l + 1);
    const VertexId c = ringVertex(s + 1, l + 1), d = ringVertex(s + 1, l);
    t0 = {a, b, c};
    t1 = {a, c, d};
  }
  /// The vertices inside the holes (no quad left around them), increasing.
  std::vector<std::uint32_t> unreferenced() const {
    std::vector<std::uint32_t> out;
    for (std::uint64_t offset : {std::uint64_t(0), torusVertices}) {
      for (std::int64_t i = 1 - layout.ha; i < layout.ha; ++i) {
        for (std::int64_t j = 1 - layout.hb; j < layout.hb; ++j) {
          out.push_back(static_cast<std::uint32_t>(offset + left.id(i, j)));
        }
      }
    }
    std::sort(out.begin(), out.end());
    return out;
  }
};

GenerateResult generateGenus2(const GenerateOptions& options) {
  GenerateResult result;
  TriangleMesh& mesh = result.mesh;
  const Genus2Shape shape(options);
  const auto inHole = [&](std::int64_t i, std::int64_t j) { return shape.inHole(i, j); };
  mesh.positions.reserve(shape.numVertices());
  mesh.triangles.reserve(shape.layout.faces());
  appendTorus(mesh, shape.left, shape.bumps, inHole);
  appendTorus(mesh, shape.right, shape.bumps, inHole);
  for (std::uint64_t v = mesh.positions.size(); v < shape.numVertices(); ++v) {
    mesh.positions.push_back(shape.position(v));
  }
  for (std::uint32_t s = 0; s < shape.layout.rings; ++s) {
    for (std::uint32_t l = 0; l < shape.loopSize(); ++l) {
      Triangle t0, t1;
      shape.tubeQuad(s, l, t0, t1);
      mesh.triangles.push_back(t0);
      mesh.triangles.push_back(t1);
    }
  }
  compactVertices(mesh);
  return result;
}

/// A uniformly random unit vector (rejection sampling in the unit ball).
Vec3d randomDirection(Rng& rng) {
  for (;;) {
    const Vec3d d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double len = d.norm();
    if (len > 0.2 && len <= 1.0) return d / len;
  }
}

/// A floating p x q quad patch facing away from the origin at `center` (one boundary loop).
void appendPatch(TriangleMesh& mesh, const Vec3d& center, std::uint32_t p, std::uint32_t q,
                 double spacing, const Bumps& bumps) {
  const Vec3d d = center.normalized();
  Vec3d e1 = d.unitOrthogonal();
  const Vec3d e2 = d.cross(e1);  // e1 x e2 = d: quads counter-clockwise seen from outside
  const VertexId v0 = mesh.numVertices();
  for (std::uint32_t t = 0; t <= q; ++t) {
    for (std::uint32_t s = 0; s <= p; ++s) {
      const Vec3d x = center + (s - 0.5 * p) * spacing * e1 + (t - 0.5 * q) * spacing * e2;
      mesh.positions.push_back(toFloat(x + bumps(x) * d));
    }
  }
  for (std::uint32_t t = 0; t < q; ++t) {
    for (std::uint32_t s = 0; s < p; ++s) {
      const VertexId a = v0 + t * (p + 1) + s, b = a + 1, c = b + p + 1, e = a + p + 1;
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, e});
    }
  }
}

/// Where the scan kind puts its holes and islands; depends only on the box and the seed.
struct ScanPlan {
  struct Hole {
    int side;
    double cx, cy, radius;  // in grid cells of the side
  };
  struct Island {
    Vec3d center;
    std::uint32_t p, q;  // patch size in quads; 0 x 0 for a closed blob
  };
  std::vector<Hole> holes;
  std::vector<Island> islands;
  std::uint32_t blobCells = 1;
  std::uint64_t removedFaces = 0, islandFaces = 0;

  static bool inHole(const Hole& h, std::uint32_t x, std::uint32_t y) {
    const double dx = x + 0.5 - h.cx, dy = y + 0.5 - h.cy;
    return dx * dx + dy * dy <= h.radius * h.radius;
  }
  /// Calls f(x, y) for the quads of hole h.
  template <class F>
  static void forEachQuad(const Hole& h, F&& f) {
    const auto y0 = static_cast<std::uint32_t>(std::max(0.0, std::floor(h.cy - h.radius)));
    const auto x0 = static_cast<std::uint32_t>(std::max(0.0, std::floor(h.cx - h.radius)));
    for (std::uint32_t y = y0; y <= h.cy + h.radius; ++y) {
      for (std::uint32_t x = x0; x <= h.cx + h.radius; ++x) {
        if (inHole(h, x, y)) f(x, y);
      }
    }
  }
};

constexpr double kScanHoleFraction = 0.03;  // of the sphere's area, over 5 holes
constexpr std::uint32_t kScanDegenerateFaces = 3, kScanDuplicateFaces = 5;
constexpr std::uint64_t kScanBadFaces = kScanDegenerateFaces + kScanDuplicateFaces;

ScanPlan planScan(const BoxLattice& box, std::uint64_t seed) {
  ScanPlan plan;
  Rng rng(seed);
  const std::uint32_t w = box.n[0];  // smallest side length in cells
  // Holes: one round hole (in grid cells) inside each of sides 0..4, away from the side's edges.
  const double targetRadius = std::sqrt(kScanHoleFraction * 6.0 / (5.0 * 3.141592653589793)) * w;
  for (int s = 0; s < 5; ++s) {
    const double sw = box.sideWidth(s), sh = box.sideHeight(s);
    ScanPlan::Hole h;
    h.side = s;
    h.radius = std::max(1.0, targetRadius * rng.uniform(0.75, 1.25));
    h.cx = rng.uniform(h.radius + 1.0, sw - h.radius - 1.0);
    h.cy = rng.uniform(h.radius + 1.0, sh - h.radius - 1.0);
    ScanPlan::forEachQuad(h, [&](std::uint32_t, std::uint32_t) { plan.removedFaces += 2; });
    plan.holes.push_back(h);
  }
  // Islands: three open patches and two closed blobs floating just above the surface.
  const std::uint32_t maxPatch = 2 + std::min<std::uint32_t>(3, w / 8);
  for (int k = 0; k < 3; ++k) {
    ScanPlan::Island island;
    island.p = 2 + rng.below(maxPatch - 1);
    island.q = 2 + rng.below(maxPatch - 1);
    island.center = rng.uniform(1.15, 1.3) * randomDirection(rng);
    plan.islandFaces += 2 * island.p * island.q;
    plan.islands.push_back(island);
  }
  plan.blobCells = w >= 16 ? 2 : 1;
  for (int k = 0; k < 2; ++k) {
    ScanPlan::Island island;
    island.p = island.q = 0;
    island.center = rng.uniform(1.15, 1.3) * randomDirection(rng);
    plan.islandFaces += 12 * plan.blobCells * plan.blobCells;
    plan.islands.push_back(island);
  }
  return plan;
}

/// The sphere lattice and the defect plan whose face count comes closest to the target (the plan
/// predicts the count exactly; a few rounds of correction, keep the best).
std::pair<BoxLattice, ScanPlan> chooseScanBox(const GenerateOptions& options) {
  const auto predicted = [](const BoxLattice& b, const ScanPlan& p) {
    return static_cast<std::int64_t>(b.numFaces() - p.removedFaces + p.islandFaces + kScanBadFaces);
  };
  const auto target = static_cast<std::int64_t>(options.faces);
  BoxLattice box = chooseBox(static_cast<std::uint64_t>(options.faces / (1.0 - kScanHoleFraction)));
  ScanPlan plan = planScan(box, options.seed);
  BoxLattice candidate = box;
  for (int round = 0; round < 4; ++round) {
    const ScanPlan candidatePlan = planScan(candidate, options.seed);
    if (std::llabs(predicted(candidate, candidatePlan) - target) < std::llabs(predicted(box, plan) - target)) {
      box = candidate;
      plan = candidatePlan;
    }
    const std::int64_t sphereFaces = target + static_cast<std::int64_t>(candidatePlan.removedFaces) -
                                     static_cast<std::int64_t>(candidatePlan.islandFaces + kScanBadFaces);
    candidate = chooseBox(static_cast<std::uint64_t>(std::max<std::int64_t>(sphereFaces, 12)));
  }
  return {box, plan};
}

/// The unwelded seam on side 5: the quads just above grid line y0 use copies of the line's inner
/// vertices x0 < x < x1 (same positions), as when a scanner stitches two sweeps.
struct SeamLine {
  std::uint32_t y0 = 0, x0 = 0, x1 = 0;
  explicit SeamLine(const BoxLattice& box)
      : y0(box.sideHeight(5) / 2), x0(box.sideWidth(5) / 4), x1(box.sideWidth(5) - box.sideWidth(5) / 4) {}
  std::uint32_t copies() const { return x1 - x0 - 1; }
};

void addUnweldedSeam(TriangleMesh& mesh, const BoxLattice& box, ScanDefects& defects) {
  const int s = 5;
  const SeamLine seam(box);
  for (std::uint32_t x = seam.x0 + 1; x < seam.x1; ++x) {
    const auto original = static_cast<VertexId>(box.sideVertex(s, x, seam.y0));
    const VertexId copy = mesh.numVertices();
    mesh.positions.push_back(mesh.positions[original]);
    ++defects.seamDuplicates;
    for (std::uint32_t qx = x - 1; qx <= x; ++qx) {
      const std::uint64_t f = box.quadFace(s, qx, seam.y0);
      for (std::uint64_t g = f; g < f + 2; ++g) {
        for (VertexId& v : mesh.triangles[g]) v = v == original ? copy : v;
      }
    }
  }
}

/// Removes the faces of the planned holes (their inner vertices go with compactVertices later).
void removeHoleFaces(TriangleMesh& mesh, const BoxLattice& box, const ScanPlan& plan, ScanDefects& defects) {
  std::vector<std::uint8_t> removed(mesh.triangles.size(), 0);
  for (const ScanPlan::Hole& h : plan.holes) {
    ScanPlan::forEachQuad(h, [&](std::uint32_t x, std::uint32_t y) {
      const std::uint64_t f = box.quadFace(h.side, x, y);
      removed[f] = removed[f + 1] = 1;
    });
    ++defects.holes;
  }
  std::uint64_t kept = 0;
  for (std::uint64_t f = 0; f < mesh.triangles.size(); ++f) {
    if (!removed[f]) mesh.triangles[kept++] = mesh.triangles[f];
  }
  mesh.triangles.resize(kept);
}

/// The planned islands: open bumpy patches and closed blobs floating above the surface.
void appendIslands(TriangleMesh& mesh, const ScanPlan& plan, double spacing, std::uint64_t seed,
                   ScanDefects& defects) {
  std::uint64_t islandSeed = seed;
  for (const ScanPlan::Island& island : plan.islands) {
    islandSeed = mix64(islandSeed);
    if (island.p > 0) {
      const Bumps islandBumps{0.2 * spacing, 1.0 / spacing, 2, islandSeed};
      appendPatch(mesh, island.center, island.p, island.q, 1.5 * spacing, islandBumps);
      ++defects.openIslands;
    } else {
      BoxLattice blob;
      blob.n[0] = blob.n[1] = blob.n[2] = plan.blobCells;
      const Bumps blobBumps{0.15, 1.0, 2, islandSeed};
      appendBoxSphere(mesh, blob, island.center, 2.0 * spacing, blobBumps, 0.0, 0);
      ++defects.closedIslands;
    }
  }
}

/// Bad faces, as scanners and converters leave them: repeated vertices and duplicates, copied
/// from faces spread over the main surface. badFaceSources: the faces copied, as indices into
/// the first sphereFaces faces (all main surface once the holes are cut), in order.
std::vector<std::uint64_t> badFaceSources(std::uint32_t sphereFaces, std::uint64_t seed) {
  Rng rng(mix64(seed));
  std::vector<std::uint64_t> sources;
  for (const std::uint32_t count : {kScanDegenerateFaces, kScanDuplicateFaces}) {
    const std::uint32_t stride = sphereFaces / count;
    for (std::uint32_t k = 0; k < count; ++k) sources.push_back(k * stride + rng.below(stride));
  }
  return sources;
}

/// Bad face k made from its source face t: degenerate ones first, then duplicates (the last one
/// reversed).
Triangle badFace(std::size_t k, const Triangle& t) {
  if (k < kScanDegenerateFaces) return {t[0], t[1], t[1]};
  if (k + 1 == kScanBadFaces) return {t[0], t[2], t[1]};
  return {t[1], t[2], t[0]};
}

void appendBadFaces(TriangleMesh& mesh, std::uint32_t sphereFaces, std::uint64_t seed, ScanDefects& defects) {
  const std::vector<std::uint64_t> sources = badFaceSources(sphereFaces, seed);
  for (std::size_t k = 0; k < sources.size(); ++k) mesh.triangles.push_back(badFace(k, mesh.triangles[sources[k]]));
  defects.degenerateFaces += kScanDegenerateFaces;
  defects.duplicateFaces += kScanDuplicateFaces;
}

GenerateResult generateScan(const GenerateOptions& options) {
  GenerateResult result;
  TriangleMesh& mesh = result.mesh;
  const auto [box, plan] = chooseScanBox(options);
  const std::uint32_t w = box.n[0];
  const double spacing = 1.5707963267948966 / w;  // about one edge length on the unit sphere
  Bumps bumps = kSphereBumps;
  bumps.seed = options.seed;
  // Room for the seam copies, islands and bad faces, so that nothing is reallocated later.
  mesh.positions.reserve(box.numVertices() + box.sideWidth(5) + 4096);
  mesh.triangles.reserve(box.numFaces() + plan.islandFaces + 64);
  appendBoxSphere(mesh, box, Vec3d::Zero(), 1.0, bumps, 0.1 * spacing, options.seed);
  reportProgress(options.progress, "generate", 0.5);

  // The seam edits vertices of faces by lattice index, the holes remove faces by lattice index:
  // the seam first, while the indices still hold.
  addUnweldedSeam(mesh, box, result.defects);
  removeHoleFaces(mesh, box, plan, result.defects);
  appendIslands(mesh, plan, spacing, options.seed, result.defects);
  compactVertices(mesh);
  const auto sphereFaces = static_cast<std::uint32_t>(box.numFaces() / 2);  // all still main surface
  appendBadFaces(mesh, sphereFaces, options.seed, result.defects);
  return result;
}

}  // namespace

const char* meshKindName(MeshKind kind) {
  switch (kind) {
    case MeshKind::Sphere: return "sphere";
    case MeshKind::Torus: return "torus";
    case MeshKind::Genus2: return "genus2";
    case MeshKind::Scan: return "scan";
  }
  return "?";
}

MeshKind parseMeshKind(const std::string& name) {
  for (MeshKind k : {MeshKind::Sphere, MeshKind::Torus, MeshKind::Genus2, MeshKind::Scan}) {
    if (name == meshKindName(k)) return k;
  }
  throw InputError("unknown mesh kind '" + name + "' (known: sphere, torus, genus2, scan)");
}

std::uint64_t minimumFaces(MeshKind kind) {
  switch (kind) {
    case MeshKind::Sphere: return 12;
    case MeshKind::Torus: return 36;
    case MeshKind::Genus2: return 200;
    case MeshKind::Scan: return 600;
  }
  return 0;
}

namespace {

std::array<std::uint32_t, 3> positionBits(const Vec3f& p) {
  std::array<std::uint32_t, 3> bits;
  std::memcpy(bits.data(), p.data(), sizeof bits);
  return bits;
}

/// Per vertex, the smallest id of the vertices at exactly its position.
std::vector<VertexId> coincidentRepresentatives(const std::vector<Vec3f>& positions) {
  std::vector<VertexId> order(positions.size());
  std::iota(order.begin(), order.end(), VertexId{0});
  tbb::parallel_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) {
    const auto pa = positionBits(positions[a]), pb = positionBits(positions[b]);
    return pa != pb ? pa < pb : a < b;
  });
  std::vector<VertexId> rep(positions.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const bool same = i > 0 && positionBits(positions[order[i]]) == positionBits(positions[order[i - 1]]);
    rep[order[i]] = same ? rep[order[i - 1]] : order[i];
  }
  return rep;
}

/// A unit tangent at angle `turns` (in turns) in a frame perpendicular to the unit normal n.
Vec3d tangentAt(const Vec3d& n, double turns) {
  const Vec3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  double s, c;
  sinCosTurns(turns, s, c);
  return c * e1 + s * e2;
}

/// Distinct representative vertices picked at random (at most count, fewer only on tiny meshes).
std::vector<VertexId> pickVertices(Rng& rng, const std::vector<VertexId>& rep, std::uint32_t count,
                                   std::unordered_map<VertexId, Vec3d>& taken) {
  std::vector<VertexId> picked;
  const auto n = static_cast<std::uint32_t>(rep.size());
  for (std::uint64_t tries = 0; picked.size() < count && tries < 64ull * count; ++tries) {
    const VertexId v = rep[rng.below(n)];
    if (taken.emplace(v, Vec3d::Zero()).second) picked.push_back(v);
  }
  return picked;
}

void checkScanNoiseInput(const TriangleMesh& mesh, const ScanNoiseOptions& options) {
  if (!(options.amplitude >= 0.0) || !std::isfinite(options.amplitude)) {
    throw InputError("scan noise: the amplitude must be a finite number >= 0, not " +
                     std::to_string(options.amplitude));
  }
  if (!(options.tangential >= 0.0 && options.tangential <= 1.0)) {
    throw InputError("scan noise: the tangential share must be between 0 and 1, not " +
                     std::to_string(options.tangential));
  }
  const std::uint64_t numVertices = mesh.positions.size();
  if (std::uint64_t(options.spikes) + options.folds > numVertices) {
    throw InputError("scan noise: " + std::to_string(options.spikes) + " spikes and " +
                     std::to_string(options.folds) + " folds asked of a mesh with " +
                     std::to_string(numVertices) + " vertices");
  }
  if (numVertices == 0) return;  // nothing to move: addScanNoise returns at once
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) {
      if (v >= numVertices) throw InputError("scan noise: a triangle names vertex " + std::to_string(v) +
                                             " of " + std::to_string(numVertices));
    }
  }
}

/// Area-weighted unit normals per representative (rep) and the mean edge length, summed in face
/// order. With localEdge, also each representative's mean length of the face edges at it (an
/// interior edge counted once per face), meanEdgeLength where it has none.
std::vector<Vec3d> representativeNormals(const TriangleMesh& mesh, const std::vector<VertexId>& rep,
                                         double& meanEdgeLength, std::vector<float>* localEdge = nullptr) {
  const std::uint64_t numVertices = mesh.positions.size();
  std::vector<Vec3d> normal(numVertices, Vec3d::Zero());
  std::vector<std::uint32_t> localCount;
  if (localEdge) localEdge->assign(numVertices, 0.f), localCount.assign(numVertices, 0);
  double edgeSum = 0.0;
  std::uint64_t edgeCount = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3d p[3] = {mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])};
    const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    for (int k = 0; k < 3; ++k) {
      if (n.allFinite()) normal[rep[t[k]]] += n;
      const double len = (p[(k + 1) % 3] - p[k]).norm();
      if (std::isfinite(len)) {
        edgeSum += len;
        ++edgeCount;
        if (localEdge) {
          for (const VertexId end : {rep[t[k]], rep[t[(k + 1) % 3]]}) {
            (*localEdge)[end] += static_cast<float>(len);
            ++localCount[end];
          }
        }
      }
    }
  }
  meanEdgeLength = edgeCount ? edgeSum / edgeCount : 0.0;
  if (localEdge) {
    for (std::uint64_t v = 0; v < numVertices; ++v) {
      float& e = (*localEdge)[v];
      e = localCount[v] ? e / static_cast<float>(localCount[v]) : static_cast<float>(meanEdgeLength);
    }
  }
  parallelRange(numVertices, [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t v = begin; v < end; ++v) {
      if (rep[v] != v) continue;
      const double len = normal[v].norm();
      normal[v] = len > 0.0 && std::isfinite(len) ? Vec3d(normal[v] / len) : Vec3d::UnitZ();
    }
  });
  return normal;
}

/// Spikes and folds: extra moves per representative, decided before any position changes.
std::unordered_map<VertexId, Vec3d> spikeAndFoldMoves(const TriangleMesh& mesh, const std::vector<VertexId>& rep,
                                                      const std::vector<Vec3d>& normal, double edge,
                                                      const ScanNoiseOptions& options, ScanNoiseResult& result) {
  Rng rng(mix64(options.seed ^ 0x5ca7ull));
  std::unordered_map<VertexId, Vec3d> extra;
  for (VertexId v : pickVertices(rng, rep, options.spikes, extra)) {
    const double sign = rng.below(2) ? 1.0 : -1.0;
    extra[v] = sign * rng.uniform(2.0, 6.0) * edge * normal[v];
    ++result.spikes;
  }
  std::unordered_map<VertexId, Vec3d> foldMove;  // centre -> its tangent move
  for (VertexId v : pickVertices(rng, rep, options.folds, extra)) {
    foldMove[v] = 2.0 * edge * tangentAt(normal[v], rng.uniform(0.0, 1.0));
    ++result.folds;
  }
  if (!foldMove.empty()) {
    // The ring of each fold centre moves half as far in the same direction (first fold wins).
    for (const Triangle& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const auto centre = foldMove.find(rep[t[k]]);
        if (centre == foldMove.end()) continue;
        for (int j = 1; j < 3; ++j) {
          const VertexId w = rep[t[(k + j) % 3]];
          if (!foldMove.count(w)) extra.emplace(w, 0.5 * centre->second);
        }
      }
    }
    for (const auto& [v, move] : foldMove) extra[v] = move;
  }
  return extra;
}

}  // namespace

ScanNoiseResult addScanNoise(TriangleMesh& mesh, const ScanNoiseOptions& options) {
  checkScanNoiseInput(mesh, options);
  const std::uint64_t numVertices = mesh.positions.size();
  ScanNoiseResult result;
  if (numVertices == 0 || mesh.triangles.empty()) return result;
  const std::vector<VertexId> rep = coincidentRepresentatives(mesh.positions);
  double edge = 0.0;
  std::vector<float> localEdge;  // per representative, with localScale
  const std::vector<Vec3d> normal =
      representativeNormals(mesh, rep, edge, options.localScale && options.amplitude > 0.0 ? &localEdge : nullptr);
  result.meanEdgeLength = edge;
  const std::unordered_map<VertexId, Vec3d> extra = spikeAndFoldMoves(mesh, rep, normal, edge, options, result);

  // Per-vertex noise from a hash of the seed and the position: coincident copies move alike.
  // Copies move first, reading their representative's position before it moves itself.
  const double meanAmplitude = options.amplitude * edge;
  tbb::combinable<double> largest([] { return 0.0; });
  for (const bool representatives : {false, true}) {
    parallelRange(numVertices, [&](std::uint64_t begin, std::uint64_t end) {
      double& local = largest.local();
      for (std::uint64_t v = begin; v < end; ++v) {
        const VertexId r = rep[v];
        if ((r == v) != representatives) continue;
        Vec3d move = Vec3d::Zero();
        const double amplitude = localEdge.empty() ? meanAmplitude : options.amplitude * localEdge[r];
        if (amplitude > 0.0) {
          const auto bits = positionBits(mesh.positions[r]);
          const std::uint64_t h0 = mix64(options.seed ^ mix64(bits[0] ^ (std::uint64_t(bits[1]) << 32)) ^
                                         mix64(std::uint64_t(bits[2]) + 0x7a11ull));
          const std::uint64_t h1 = mix64(h0), h2 = mix64(h1);
          const double along = amplitude * (2.0 * unitFromBits(h0) - 1.0);
          const double across = options.tangential * amplitude * std::sqrt(unitFromBits(h1));
          move = along * normal[r] + across * tangentAt(normal[r], unitFromBits(h2));
          local = std::max(local, move.norm());
        }
        if (!extra.empty()) {
          const auto it = extra.find(r);
          if (it != extra.end()) move += it->second;
        }
        mesh.positions[v] = toFloat(mesh.position(static_cast<VertexId>(v)) + move);
      }
    });
  }
  result.maxDisplacement = largest.combine([](double a, double b) { return std::max(a, b); });
  return result;
}

namespace {

void checkGenerateOptions(const GenerateOptions& options) {
  if (options.faces < minimumFaces(options.kind)) {
    throw InputError(std::string("cannot generate a ") + meshKindName(options.kind) + " with " +
                     std::to_string(options.faces) + " faces: use at least " +
                     std::to_string(minimumFaces(options.kind)));
  }
  if (options.faces >= (1ull << 31)) {
    throw InputError("cannot generate " + std::to_string(options.faces) +
                     " faces: 32-bit indices allow fewer than 2^31");
  }
}

}  // namespace

GenerateResult generateMesh(const GenerateOptions& options) {
  checkGenerateOptions(options);
  reportProgress(options.progress, "generate", 0.0);
  GenerateResult result;
  switch (options.kind) {
    case MeshKind::Sphere: result = generateSphere(options); break;
    case MeshKind::Torus: result = generateTorus(options); break;
    case MeshKind::Genus2: result = generateGenus2(options); break;
    case MeshKind::Scan: result = generateScan(options); break;
  }
  reportProgress(options.progress, "generate", 1.0);
  return result;
}

// ---- the same meshes piece by piece -------------------------------------------------------------

namespace detail {

/// A generated mesh as a sequence of vertices (by their id before the unreferenced ones are
/// dropped, "pre" ids) and of face units (a quad: two triangles, or one triangle) in segments.
struct GeneratedSequence {
  struct Segment {
    std::uint64_t units = 0;
    /// Appends the triangles of unit u (pre ids, or final ids when finalIds).
    std::function<void(std::uint64_t u, std::vector<Triangle>& out)> emit;
    bool finalIds = false;
  };

  std::uint64_t preVertices = 0, faces = 0;
  std::vector<std::uint32_t> dropped;  ///< pre ids no face uses, increasing
  std::function<Vec3f(std::uint64_t pre)> position;
  std::vector<Segment> segments;
  ScanDefects defects;
  // The scan's bad faces copy faces of its first segment, at these output indices.
  std::vector<std::uint64_t> badSources;
  std::vector<Triangle> badCopied;

  std::uint64_t nextPre = 0, positionsGiven = 0, facesGiven = 0;
  std::size_t droppedSeen = 0, segment = 0;
  std::uint64_t unit = 0;
  std::vector<std::uint64_t> preIds;
  std::vector<Triangle> pending;

  VertexId finalId(VertexId pre) const {
    return pre - static_cast<VertexId>(std::lower_bound(dropped.begin(), dropped.end(), pre) - dropped.begin());
  }
};

}  // namespace detail

using detail::GeneratedSequence;

namespace {

/// Quad q of a box lattice in face order: side, then row, then column.
void boxQuadAt(const BoxLattice& box, std::uint64_t q, int& s, std::uint32_t& x, std::uint32_t& y) {
  for (s = 0; s < 5; ++s) {
    const std::uint64_t quads = std::uint64_t(box.sideWidth(s)) * box.sideHeight(s);
    if (q < quads) break;
    q -= quads;
  }
  x = static_cast<std::uint32_t>(q % box.sideWidth(s));
  y = static_cast<std::uint32_t>(q / box.sideWidth(s));
}

std::uint64_t boxQuads(const BoxLattice& box) { return box.numFaces() / 2; }

void sequenceSphere(GeneratedSequence& g, const GenerateOptions& options) {
  Bumps bumps = kSphereBumps;
  bumps.seed = options.seed;
  auto sphere = std::make_shared<BoxSphere>(chooseBox(options.faces), Vec3d::Zero(), 1.0, bumps, 0.0, 0);
  g.preVertices = sphere->box.numVertices();
  g.faces = sphere->box.numFaces();
  g.position = [sphere](std::uint64_t v) { return sphere->position(v); };
  g.segments.push_back({boxQuads(sphere->box), [sphere](std::uint64_t q, std::vector<Triangle>& out) {
                          int s;
                          std::uint32_t x, y;
                          boxQuadAt(sphere->box, q, s, x, y);
                          Triangle t0, t1;
                          sphere->quad(0, s, x, y, t0, t1);
                          out.push_back(t0);
                          out.push_back(t1);
                        }});
}

/// Quads of a torus grid row by row, those with skip(i, j) left out; vertex ids offset by v0.
template <class Skip>
GeneratedSequence::Segment torusSegment(const TorusGrid& torus, std::uint64_t v0, Skip skip) {
  return {std::uint64_t(torus.m) * torus.n, [torus, v0, skip](std::uint64_t q, std::vector<Triangle>& out) {
            const auto i = static_cast<std::int64_t>(q / torus.n), j = static_cast<std::int64_t>(q % torus.n);
            if (skip(i, j)) return;
            Triangle t0, t1;
            torusQuad(torus, v0, i, j, t0, t1);
            out.push_back(t0);
            out.push_back(t1);
          }};
}

void sequenceTorus(GeneratedSequence& g, const GenerateOptions& options) {
  const TorusGrid torus = chooseTorus(options.faces, 2.5);
  const Bumps bumps{0.04, 2.5, 4, options.seed};
  g.preVertices = std::uint64_t(torus.m) * torus.n;
  g.faces = 2 * g.preVertices;
  g.position = [torus, bumps](std::uint64_t v) {
    return torusPosition(torus, bumps, static_cast<std::int64_t>(v / torus.n), static_cast<std::int64_t>(v % torus.n));
  };
  g.segments.push_back(torusSegment(torus, 0, [](std::int64_t, std::int64_t) { return false; }));
}

void sequenceGenus2(GeneratedSequence& g, const GenerateOptions& options) {
  auto shape = std::make_shared<const Genus2Shape>(options);
  g.preVertices = shape->numVertices();
  g.dropped = shape->unreferenced();
  g.faces = shape->layout.faces();
  g.position = [shape](std::uint64_t v) { return shape->position(v); };
  const auto inHole = [shape](std::int64_t i, std::int64_t j) { return shape->inHole(i, j); };
  g.segments.push_back(torusSegment(shape->left, 0, inHole));
  g.segments.push_back(torusSegment(shape->right, shape->torusVertices, inHole));
  g.segments.push_back({std::uint64_t(shape->layout.rings) * shape->loopSize(),
                        [shape](std::uint64_t q, std::vector<Triangle>& out) {
                          Triangle t0, t1;
                          shape->tubeQuad(static_cast<std::uint32_t>(q / shape->loopSize()),
                                          static_cast<std::uint32_t>(q % shape->loopSize()), t0, t1);
                          out.push_back(t0);
                          out.push_back(t1);
                        }});
}

/// The scan: the box sphere with the seam's copies and without the holes' faces, the islands,
/// then the bad faces (copies of first-segment faces taken as they pass).
void sequenceScan(GeneratedSequence& g, const GenerateOptions& options) {
  const std::pair<BoxLattice, ScanPlan> chosen = chooseScanBox(options);
  const BoxLattice& box = chosen.first;
  const ScanPlan& plan = chosen.second;
  const double spacing = 1.5707963267948966 / box.n[0];
  Bumps bumps = kSphereBumps;
  bumps.seed = options.seed;
  auto sphere = std::make_shared<BoxSphere>(box, Vec3d::Zero(), 1.0, bumps, 0.1 * spacing, options.seed);
  auto islands = std::make_shared<TriangleMesh>();
  appendIslands(*islands, plan, spacing, options.seed, g.defects);
  const SeamLine seam(box);
  const std::uint64_t seamBase = box.numVertices(), islandBase = seamBase + seam.copies();
  g.defects.seamDuplicates = seam.copies();
  g.defects.holes = static_cast<std::uint32_t>(plan.holes.size());
  g.defects.degenerateFaces = kScanDegenerateFaces;
  g.defects.duplicateFaces = kScanDuplicateFaces;
  g.preVertices = islandBase + islands->positions.size();
  g.position = [sphere, islands, seam, seamBase, islandBase](std::uint64_t v) {
    if (v < seamBase) return sphere->position(v);
    if (v < islandBase) return sphere->position(sphere->box.sideVertex(5, seam.x0 + 1 + static_cast<std::uint32_t>(v - seamBase), seam.y0));
    return islands->positions[v - islandBase];
  };
  // A vertex inside a hole has all four quads around it removed.
  for (const ScanPlan::Hole& h : plan.holes) {
    ScanPlan::forEachQuad(h, [&](std::uint32_t x, std::uint32_t y) {
      if (ScanPlan::inHole(h, x + 1, y) && ScanPlan::inHole(h, x, y + 1) && ScanPlan::inHole(h, x + 1, y + 1)) {
        g.dropped.push_back(static_cast<std::uint32_t>(box.sideVertex(h.side, x + 1, y + 1)));
      }
    });
  }
  std::sort(g.dropped.begin(), g.dropped.end());
  auto holes = std::make_shared<const std::vector<ScanPlan::Hole>>(plan.holes);
  g.segments.push_back({boxQuads(box), [sphere, holes, seam, seamBase](std::uint64_t q, std::vector<Triangle>& out) {
                          int s;
                          std::uint32_t x, y;
                          boxQuadAt(sphere->box, q, s, x, y);
                          for (const ScanPlan::Hole& h : *holes) {
                            if (h.side == s && ScanPlan::inHole(h, x, y)) return;
                          }
                          Triangle t[2];
                          sphere->quad(0, s, x, y, t[0], t[1]);
                          if (s == 5 && y == seam.y0) {
                            for (std::uint32_t lx = x; lx <= x + 1; ++lx) {
                              if (lx <= seam.x0 || lx >= seam.x1) continue;
                              const auto original = static_cast<VertexId>(sphere->box.sideVertex(5, lx, seam.y0));
                              const auto copy = static_cast<VertexId>(seamBase + (lx - seam.x0 - 1));
                              for (Triangle& tri : t) {
                                for (VertexId& v : tri) v = v == original ? copy : v;
                              }
                            }
                          }
                          out.push_back(t[0]);
                          out.push_back(t[1]);
                        }});
  g.segments.push_back({islands->triangles.size(), [islands, islandBase](std::uint64_t f, std::vector<Triangle>& out) {
                          Triangle t = islands->triangles[f];
                          for (VertexId& v : t) v += static_cast<VertexId>(islandBase);
                          out.push_back(t);
                        }});
  g.badSources = badFaceSources(static_cast<std::uint32_t>(box.numFaces() / 2), options.seed);
  g.badCopied.resize(g.badSources.size());
  GeneratedSequence* self = &g;
  g.segments.push_back({kScanBadFaces, [self](std::uint64_t k, std::vector<Triangle>& out) {
                          out.push_back(badFace(k, self->badCopied[k]));
                        }, true});
  g.faces = box.numFaces() - plan.removedFaces + plan.islandFaces + kScanBadFaces;
}

}  // namespace

MeshGenerator::MeshGenerator(const GenerateOptions& options) : impl_(std::make_unique<detail::GeneratedSequence>()) {
  checkGenerateOptions(options);
  GeneratedSequence& g = *impl_;
  switch (options.kind) {
    case MeshKind::Sphere: sequenceSphere(g, options); break;
    case MeshKind::Torus: sequenceTorus(g, options); break;
    case MeshKind::Genus2: sequenceGenus2(g, options); break;
    case MeshKind::Scan: sequenceScan(g, options); break;
  }
}

MeshGenerator::~MeshGenerator() = default;

std::uint64_t MeshGenerator::numVertices() const { return impl_->preVertices - impl_->dropped.size(); }
std::uint64_t MeshGenerator::numFaces() const { return impl_->faces; }
const ScanDefects& MeshGenerator::defects() const { return impl_->defects; }

bool MeshGenerator::nextPositions(std::size_t count, std::vector<Vec3f>& out) {
  GeneratedSequence& g = *impl_;
  g.preIds.clear();
  while (g.preIds.size() < count && g.nextPre < g.preVertices) {
    if (g.droppedSeen < g.dropped.size() && g.dropped[g.droppedSeen] == g.nextPre) {
      ++g.droppedSeen;
    } else {
      g.preIds.push_back(g.nextPre);
    }
    ++g.nextPre;
  }
  if (g.preIds.empty()) return false;
  const std::size_t first = out.size();
  out.resize(first + g.preIds.size());
  parallelRange(g.preIds.size(), [&](std::uint64_t begin, std::uint64_t end) {
    for (std::uint64_t i = begin; i < end; ++i) out[first + i] = g.position(g.preIds[i]);
  });
  g.positionsGiven += g.preIds.size();
  return true;
}

bool MeshGenerator::nextTriangles(std::size_t count, std::vector<Triangle>& out) {
  GeneratedSequence& g = *impl_;
  const std::size_t first = out.size();
  while (out.size() - first < count && g.segment < g.segments.size()) {
    const GeneratedSequence::Segment& s = g.segments[g.segment];
    if (g.unit == s.units) {
      ++g.segment;
      g.unit = 0;
      continue;
    }
    const std::size_t before = out.size();
    s.emit(g.unit++, out);
    for (std::size_t i = before; i < out.size(); ++i) {
      if (!s.finalIds) {
        for (VertexId& v : out[i]) v = g.finalId(v);
      }
      if (g.segment == 0) {
        // The scan's bad faces copy first-segment faces (at most a few per index).
        const std::uint64_t index = g.facesGiven + (i - first);
        for (std::size_t k = 0; k < g.badSources.size(); ++k) {
          if (g.badSources[k] == index) g.badCopied[k] = out[i];
        }
      }
    }
  }
  g.facesGiven += out.size() - first;
  return out.size() > first;
}

}  // namespace seamvox
