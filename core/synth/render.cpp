#include "core/synth/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint32_t kMaxSide = 8192;
/// Sample buffers stay within this many samples (8 bytes of depth + id and 3 of colour each).
constexpr std::uint64_t kMaxSamples = 4096ull * 4096ull;
constexpr std::uint64_t kEmpty = ~std::uint64_t(0);

struct ViewAxes {
  Vec3d right, up, forward;
};

/// Screen axes for the options' up axis, azimuth and elevation (see RenderOptions).
ViewAxes viewAxes(const RenderOptions& options) {
  const int k = options.upAxis;
  const Vec3d worldUp = Vec3d::Unit(k);
  const Vec3d right0 = Vec3d::Unit(k == 0 ? 1 : 0);
  const Vec3d eye0 = right0.cross(worldUp);
  const double az = options.azimuth * kPi / 180.0, el = options.elevation * kPi / 180.0;
  const Vec3d eyeAz = std::cos(az) * eye0 + std::sin(az) * right0;
  ViewAxes axes;
  axes.right = std::cos(az) * right0 - std::sin(az) * eye0;
  axes.forward = -(std::cos(el) * eyeAz + std::sin(el) * worldUp);
  axes.up = axes.right.cross(axes.forward);
  return axes;
}

void checkOptions(const RenderOptions& options) {
  auto fail = [](const std::string& what) { throw InputError("render options: " + what); };
  if (options.width < 1 || options.height < 1 || options.width > kMaxSide ||
      options.height > kMaxSide) {
    fail("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
         " is outside 1..8192");
  }
  if (!(options.checker > 0.0) || !std::isfinite(options.checker)) {
    fail("checker cells per unit must be a positive number");
  }
  if (!std::isfinite(options.azimuth) || !std::isfinite(options.elevation)) {
    fail("azimuth and elevation must be finite");
  }
  if (options.upAxis < 0 || options.upAxis > 2) fail("up axis must be 0 (x), 1 (y) or 2 (z)");
  if (!(options.margin >= 0.0 && options.margin < 0.5)) fail("margin must be in [0, 0.5)");
}

/// Float depth to an unsigned key with the same order (negative depths included).
std::uint32_t depthKey(float depth) {
  std::uint32_t bits;
  std::memcpy(&bits, &depth, sizeof bits);
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}
float keyDepth(std::uint32_t key) {
  const std::uint32_t bits = (key & 0x80000000u) ? (key & 0x7fffffffu) : ~key;
  float depth;
  std::memcpy(&depth, &bits, sizeof depth);
  return depth;
}

/// Parity of the checker cell containing x (0 for values too large to tell).
int cellParity(double x) {
  const double f = std::floor(x);
  if (!(std::fabs(f) < 9e15)) return 0;
  return static_cast<int>(static_cast<std::int64_t>(f) & 1);
}

/// The supersampled picture: per sample the nearest (depth, face) key and a colour.
class SampleCanvas {
 public:
  SampleCanvas(std::uint32_t width, std::uint32_t height)
      : width_(width), height_(height), keys_(new std::atomic<std::uint64_t>[count()]),
        colors_(3 * count()) {
    parallelForEach(count(), 1 << 16, [&](std::uint64_t i) {
      keys_[i].store(kEmpty, std::memory_order_relaxed);
    });
  }
  std::uint64_t count() const { return std::uint64_t(width_) * height_; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  std::uint64_t index(std::uint32_t x, std::uint32_t y) const { return std::uint64_t(y) * width_ + x; }

  /// Keeps the nearer of the stored and the given fragment (ties: smaller face id).
  void testAndSet(std::uint64_t i, float depth, FaceId face) {
    const std::uint64_t key = (std::uint64_t(depthKey(depth)) << 32) | face;
    std::uint64_t old = keys_[i].load(std::memory_order_relaxed);
    while (key < old && !keys_[i].compare_exchange_weak(old, key, std::memory_order_relaxed)) {
    }
  }
  std::uint64_t key(std::uint64_t i) const { return keys_[i].load(std::memory_order_relaxed); }
  FaceId face(std::uint64_t i) const {
    const std::uint64_t k = key(i);
    return k == kEmpty ? kInvalidId : static_cast<FaceId>(k & 0xffffffffu);
  }
  /// Depth of the nearest fragment, +infinity for an empty sample.
  double depth(std::uint64_t i) const {
    const std::uint64_t k = key(i);
    return k == kEmpty ? std::numeric_limits<double>::infinity() : keyDepth(std::uint32_t(k >> 32));
  }
  std::uint8_t* color(std::uint64_t i) { return &colors_[3 * i]; }

  /// Whether a point at sample position p and depth d is in front of (or on) the surface: its
  /// depth is at most the farthest of the 3 x 3 samples around it, plus tolerance.
  bool isVisible(const Vec2d& p, double d, double tolerance) const {
    const long cx = static_cast<long>(std::floor(p.x())), cy = static_cast<long>(std::floor(p.y()));
    double farthest = -std::numeric_limits<double>::infinity();
    bool inside = false;
    for (long y = cy - 1; y <= cy + 1; ++y) {
      for (long x = cx - 1; x <= cx + 1; ++x) {
        if (x < 0 || y < 0 || x >= long(width_) || y >= long(height_)) continue;
        inside = true;
        farthest = std::max(farthest, depth(index(std::uint32_t(x), std::uint32_t(y))));
      }
    }
    return inside && d <= farthest + tolerance;
  }

  /// Paints the samples whose centres lie within radius of p (sample units).
  void stampDisk(const Vec2d& p, double radius, const Rgb& rgb) {
    const long x0 = std::max(0L, static_cast<long>(std::floor(p.x() - radius)));
    const long y0 = std::max(0L, static_cast<long>(std::floor(p.y() - radius)));
    const long x1 = std::min(long(width_) - 1, static_cast<long>(std::ceil(p.x() + radius)));
    const long y1 = std::min(long(height_) - 1, static_cast<long>(std::ceil(p.y() + radius)));
    for (long y = y0; y <= y1; ++y) {
      for (long x = x0; x <= x1; ++x) {
        const Vec2d d(x + 0.5 - p.x(), y + 0.5 - p.y());
        if (d.squaredNorm() > radius * radius) continue;
        std::uint8_t* c = color(index(std::uint32_t(x), std::uint32_t(y)));
        c[0] = rgb[0], c[1] = rgb[1], c[2] = rgb[2];
      }
    }
  }

 private:
  std::uint32_t width_, height_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> keys_;
  std::vector<std::uint8_t> colors_;
};

/// Screen position of every vertex in sample units (x, y) and its depth (z).
std::vector<Vec3d> projectVertices(const TriangleMesh& mesh, const RenderCamera& camera,
                                   double samplesPerPixel) {
  std::vector<Vec3d> screen(mesh.numVertices());
  parallelForEach(screen.size(), 1 << 14, [&](std::uint64_t v) {
    const Vec3d p = mesh.position(static_cast<VertexId>(v));
    const Vec2d s = camera.project(p) * samplesPerPixel;
    screen[v] = Vec3d(s.x(), s.y(), camera.depth(p));
  });
  return screen;
}

double edgeFunction(const Vec3d& a, const Vec3d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

/// Z-buffers every face (both sides) into the canvas, in parallel over faces.
void rasterizeFaces(const TriangleMesh& mesh, const std::vector<Vec3d>& screen, SampleCanvas& canvas) {
  const double maxX = canvas.width(), maxY = canvas.height();
  parallelForEach(mesh.numFaces(), 4096, [&](std::uint64_t fi) {
    const FaceId f = static_cast<FaceId>(fi);
    const Triangle& t = mesh.triangles[f];
    const Vec3d& a = screen[t[0]];
    Vec3d b = screen[t[1]], c = screen[t[2]];
    double area = edgeFunction(a, b, c.x(), c.y());
    if (!(std::fabs(area) > 1e-12)) return;  // seen edge-on (or not finite)
    if (area < 0.0) std::swap(b, c), area = -area;
    const double lo[2] = {std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()})};
    const double hi[2] = {std::max({a.x(), b.x(), c.x()}), std::max({a.y(), b.y(), c.y()})};
    if (hi[0] < 0.0 || hi[1] < 0.0 || lo[0] >= maxX || lo[1] >= maxY) return;
    // Sample centres x + 0.5 inside [lo, hi].
    const long x0 = std::max(0L, static_cast<long>(std::ceil(lo[0] - 0.5)));
    const long y0 = std::max(0L, static_cast<long>(std::ceil(lo[1] - 0.5)));
    const long x1 = std::min(long(maxX) - 1, static_cast<long>(std::floor(hi[0] - 0.5)));
    const long y1 = std::min(long(maxY) - 1, static_cast<long>(std::floor(hi[1] - 0.5)));
    // Barycentric weights (times area) of a and b step linearly along a row; depth too.
    constexpr double kSlack = 1e-6;  // squared samples
    const double inv = 1.0 / area;
    const double stepA = -(c.y() - b.y()), stepB = -(a.y() - c.y());
    const double depthStep = (stepA * (a.z() - c.z()) + stepB * (b.z() - c.z())) * inv;
    for (long y = y0; y <= y1; ++y) {
      const double py = y + 0.5, px = x0 + 0.5;
      double wa = edgeFunction(b, c, px, py), wb = edgeFunction(c, a, px, py);
      double depth = (wa * a.z() + wb * b.z() + (area - wa - wb) * c.z()) * inv;
      const std::uint64_t row = canvas.index(0, std::uint32_t(y));
      for (long x = x0; x <= x1; ++x, wa += stepA, wb += stepB, depth += depthStep) {
        // Inclusive, with a little slack for the stepping error: shared edges leave no cracks.
        if (wa < -kSlack || wb < -kSlack || area - wa - wb < -kSlack) continue;
        canvas.testAndSet(row + std::uint64_t(x), float(depth), f);
      }
    }
  });
}

/// Colours every covered sample: checker of the interpolated (u, v), Lambert + ambient.
void shadeSamples(const TriangleMesh& mesh, const std::vector<Vec3d>& screen, const ViewAxes& axes,
                  const RenderOptions& options, SampleCanvas& canvas) {
  // Brightness per face from a light above-left of the eye, both sides lit.
  const Vec3d light = (-axes.forward + 0.5 * axes.up - 0.3 * axes.right).normalized();
  constexpr double kAmbient = 0.3, kDiffuse = 0.7;
  std::vector<float> faceShade(mesh.numFaces());
  parallelForEach(faceShade.size(), 1 << 14, [&](std::uint64_t f) {
    faceShade[f] = float(kAmbient + kDiffuse * std::fabs(faceNormal(mesh, FaceId(f)).dot(light)));
  });
  parallelForEach(canvas.height(), 8, [&](std::uint64_t y) {
    for (std::uint32_t x = 0; x < canvas.width(); ++x) {
      const std::uint64_t i = canvas.index(x, std::uint32_t(y));
      std::uint8_t* out = canvas.color(i);
      const FaceId f = canvas.face(i);
      if (f == kInvalidId) {
        out[0] = options.background[0], out[1] = options.background[1], out[2] = options.background[2];
        continue;
      }
      const Triangle& t = mesh.triangles[f];
      const Vec3d &a = screen[t[0]], &b = screen[t[1]], &c = screen[t[2]];
      const double px = x + 0.5, py = y + 0.5;
      const double area = edgeFunction(a, b, c.x(), c.y());
      const double wa = edgeFunction(b, c, px, py) / area, wb = edgeFunction(c, a, px, py) / area;
      const double wc = 1.0 - wa - wb;
      const Vec2d uv = wa * mesh.cornerUV[3 * std::size_t(f)] +
                       wb * mesh.cornerUV[3 * std::size_t(f) + 1] +
                       wc * mesh.cornerUV[3 * std::size_t(f) + 2];
      const bool isDark =
          (cellParity(uv.x() * options.checker) ^ cellParity(uv.y() * options.checker)) != 0;
      const Rgb& base = isDark ? options.dark : options.light;
      const double shade = faceShade[f];
      for (int k = 0; k < 3; ++k) {
        out[k] = static_cast<std::uint8_t>(std::min(255.0, base[k] * shade + 0.5));
      }
    }
  });
}

/// A thick line between two screen points (x, y, depth), drawn where not hidden behind other
/// surfaces.
void drawSegment(const Vec3d& a, const Vec3d& b, double radius, double tolerance, const Rgb& rgb,
                 SampleCanvas& canvas) {
  const double length = Vec2d(b.x() - a.x(), b.y() - a.y()).norm();
  if (!std::isfinite(length)) return;
  const int steps = 1 + static_cast<int>(std::ceil(2.0 * length));
  for (int s = 0; s <= steps; ++s) {
    const Vec3d p = a + (b - a) * (double(s) / steps);
    const Vec2d q(p.x(), p.y());
    if (canvas.isVisible(q, p.z(), tolerance)) canvas.stampDisk(q, radius, rgb);
  }
}

/// Thick seam lines, drawn where the edge is not hidden behind other surfaces.
void drawSeams(const Topology& topology, const std::vector<CornerId>& seams,
               const std::vector<Vec3d>& screen, double radius, double tolerance, const Rgb& rgb,
               SampleCanvas& canvas) {
  for (const CornerId c : seams) {
    drawSegment(screen[topology.vertex(nextCorner(c))], screen[topology.vertex(prevCorner(c))], radius,
                tolerance, rgb, canvas);
  }
}

}  // namespace

Vec2d RenderCamera::project(const Vec3d& p) const {
  const Vec3d d = p - center;
  return {0.5 * width + d.dot(right) * pixelsPerUnit, 0.5 * height - d.dot(up) * pixelsPerUnit};
}

RenderCamera frameMesh(const TriangleMesh& mesh, const RenderOptions& options) {
  checkOptions(options);
  const ViewAxes axes = viewAxes(options);
  const BoundingBox box = computeBoundingBox(mesh.positions);
  const Vec3d boxCenter = box.isEmpty() ? Vec3d::Zero() : Vec3d(0.5 * (box.min + box.max));
  // Extent of the positions along the screen axes, relative to the box centre.
  using Extent = std::array<double, 4>;  // min right, max right, min up, max up
  const double inf = std::numeric_limits<double>::infinity();
  const Extent extent = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 1 << 14), Extent{inf, -inf, inf, -inf},
      [&](const tbb::blocked_range<std::size_t>& r, Extent e) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
          const Vec3d d = mesh.positions[v].cast<double>() - boxCenter;
          const double x = d.dot(axes.right), y = d.dot(axes.up);
          e = {std::min(e[0], x), std::max(e[1], x), std::min(e[2], y), std::max(e[3], y)};
        }
        return e;
      },
      [](const Extent& p, const Extent& q) {
        return Extent{std::min(p[0], q[0]), std::max(p[1], q[1]), std::min(p[2], q[2]),
                      std::max(p[3], q[3])};
      });
  RenderCamera camera;
  camera.right = axes.right;
  camera.up = axes.up;
  camera.forward = axes.forward;
  camera.width = options.width;
  camera.height = options.height;
  camera.center = boxCenter;
  if (!(extent[0] <= extent[1])) return camera;  // no positions
  camera.center += 0.5 * (extent[0] + extent[1]) * axes.right + 0.5 * (extent[2] + extent[3]) * axes.up;
  const double spanX = extent[1] - extent[0], spanY = extent[3] - extent[2];
  const double usable = 1.0 - 2.0 * options.margin;
  const double fitX = spanX > 0.0 ? usable * options.width / spanX : inf;
  const double fitY = spanY > 0.0 ? usable * options.height / spanY : inf;
  const double fit = std::min(fitX, fitY);
  camera.pixelsPerUnit = std::isfinite(fit) && fit > 0.0 ? fit : 1.0;
  return camera;
}

std::vector<CornerId> findSeamEdges(const TriangleMesh& mesh, const Topology& topology,
                                    double tolerance) {
  const std::uint64_t numCorners = topology.numCorners();
  std::vector<std::uint8_t> isSeam(numCorners, 0);
  auto differ = [&](CornerId p, CornerId q) {
    const Vec2d a = mesh.cornerUV[p];
    const Vec2d b = mesh.cornerUV[q];
    const double scale = std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
    return !((a - b).cwiseAbs().maxCoeff() <= tolerance * scale);
  };
  parallelForEach(numCorners, 1 << 14, [&](std::uint64_t ci) {
    const CornerId c = static_cast<CornerId>(ci);
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId || o < c) return;
    // The edge of c runs vertex(next c) -> vertex(prev c); o traverses it the other way.
    isSeam[c] = differ(nextCorner(c), prevCorner(o)) || differ(prevCorner(c), nextCorner(o));
  });
  std::vector<CornerId> seams;
  for (CornerId c = 0; c < numCorners; ++c) {
    if (isSeam[c]) seams.push_back(c);
  }
  return seams;
}

MapCones findMapCones(const TriangleMesh& mesh, const Topology& topology, double angleTolerance) {
  constexpr std::int8_t kIrregular = std::numeric_limits<std::int8_t>::min();
  std::vector<std::int8_t> turns(topology.numVertices(), 0);
  parallelForEach(turns.size(), 1 << 13, [&](std::uint64_t vi) {
    const VertexId v = static_cast<VertexId>(vi);
    if (topology.isIsolatedVertex(v) || topology.isBoundaryVertex(v)) return;
    double angleSum = 0.0;
    topology.forEachCornerAround(v, [&](CornerId c) {
      const Vec2d e1 = mesh.cornerUV[nextCorner(c)] - mesh.cornerUV[c];
      const Vec2d e2 = mesh.cornerUV[prevCorner(c)] - mesh.cornerUV[c];
      angleSum += std::atan2(e1.x() * e2.y() - e1.y() * e2.x(), e1.dot(e2));
    });
    const double quarters = (2.0 * kPi - angleSum) / (0.5 * kPi);
    const double k = std::round(quarters);
    if (!(std::fabs(quarters - k) * 0.5 * kPi <= angleTolerance)) {
      turns[v] = kIrregular;
    } else if (k != 0.0) {
      turns[v] = static_cast<std::int8_t>(std::clamp(k, -127.0, 127.0));
    }
  });
  MapCones result;
  for (VertexId v = 0; v < turns.size(); ++v) {
    if (turns[v] == kIrregular) {
      ++result.irregularVertices;
    } else if (turns[v] != 0) {
      result.cones.push_back({v, turns[v]});
    }
  }
  return result;
}

RenderResult renderCheckerboard(const TriangleMesh& mesh, const Topology& topology,
                                const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  checkOptions(options);
  if (!mesh.hasUV()) {
    throw InputError("mesh has no texture coordinates; run seamvox param first");
  }
  if (mesh.cornerUV.size() != 3 * std::size_t(mesh.numFaces())) {
    throw InputError("mesh has " + std::to_string(mesh.cornerUV.size()) +
                     " corner (u, v) entries for " + std::to_string(mesh.numFaces()) +
                     " faces (expected 3 per face)");
  }
  if ((options.drawSeams || options.drawCones) && topology.numFaces() != mesh.numFaces()) {
    throw InputError("render: the topology has " + std::to_string(topology.numFaces()) +
                     " faces, the mesh " + std::to_string(mesh.numFaces()));
  }
  RenderResult result;
  result.camera = frameMesh(mesh, options);
  const ViewAxes axes{result.camera.right, result.camera.up, result.camera.forward};

  std::uint32_t ss = std::max<std::uint32_t>(1, options.supersample);
  while (ss > 1 && std::uint64_t(options.width) * ss * options.height * ss > kMaxSamples) --ss;
  SampleCanvas canvas(options.width * ss, options.height * ss);
  const std::vector<Vec3d> screen = projectVertices(mesh, result.camera, ss);
  reportProgress(options.progress, "render", 0.1);
  rasterizeFaces(mesh, screen, canvas);
  reportProgress(options.progress, "render", 0.6);
  shadeSamples(mesh, screen, axes, options, canvas);
  reportProgress(options.progress, "render", 0.8);

  // Depth tolerance for lines and dots: two samples' worth of mesh units.
  const double tolerance = 2.0 / (result.camera.pixelsPerUnit * ss);
  if (options.drawSeams) {
    const std::vector<CornerId> seams = findSeamEdges(mesh, topology, options.seamTolerance);
    result.seamEdges = seams.size();
    drawSeams(topology, seams, screen, 0.5 * options.seamWidth * ss, tolerance, options.seamColor,
              canvas);
  }
  for (const auto& [from, to] : options.lines) {
    auto toScreen = [&](const Vec3d& p) {
      const Vec2d xy = result.camera.project(p) * double(ss);
      return Vec3d(xy.x(), xy.y(), result.camera.depth(p));
    };
    drawSegment(toScreen(from), toScreen(to), 0.5 * options.lineWidth * ss,
                options.lineDepthTolerance / result.camera.pixelsPerUnit, options.lineColor, canvas);
  }
  if (options.drawCones) {
    MapCones found = findMapCones(mesh, topology);
    result.cones = std::move(found.cones);
    result.irregularVertices = found.irregularVertices;
    const double radius =
        (options.coneRadius > 0.0 ? options.coneRadius
                                  : std::max(3.0, std::min(options.width, options.height) / 160.0)) *
        ss;
    const Rgb outline{20, 20, 20};
    for (const RenderCone& cone : result.cones) {
      const Vec3d& p = screen[cone.vertex];
      const Vec2d q(p.x(), p.y());
      if (!canvas.isVisible(q, p.z(), tolerance)) continue;
      canvas.stampDisk(q, radius + ss, outline);
      canvas.stampDisk(q, radius, cone.quarterTurns > 0 ? options.positiveCone : options.negativeCone);
    }
  }

  // Box filter down to the output size.
  RgbImage& image = result.image;
  image.width = options.width;
  image.height = options.height;
  image.pixels.assign(3 * std::size_t(image.width) * image.height, 0);
  std::vector<std::uint32_t> coveredRows(image.height, 0);
  parallelForEach(image.height, 4, [&](std::uint64_t y) {
    for (std::uint32_t x = 0; x < image.width; ++x) {
      std::uint32_t sum[3] = {0, 0, 0};
      bool covered = false;
      for (std::uint32_t sy = 0; sy < ss; ++sy) {
        for (std::uint32_t sx = 0; sx < ss; ++sx) {
          const std::uint64_t i = canvas.index(x * ss + sx, std::uint32_t(y) * ss + sy);
          covered |= canvas.face(i) != kInvalidId;
          const std::uint8_t* c = canvas.color(i);
          for (int k = 0; k < 3; ++k) sum[k] += c[k];
        }
      }
      std::uint8_t* out = &image.pixels[3 * (y * image.width + x)];
      for (int k = 0; k < 3; ++k) out[k] = static_cast<std::uint8_t>((sum[k] + ss * ss / 2) / (ss * ss));
      coveredRows[y] += covered;
    }
  });
  for (const std::uint32_t n : coveredRows) result.coveredPixels += n;
  reportProgress(options.progress, "render", 1.0);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace seamvox
