#include "core/synth/render_canvas.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox::render_detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint32_t kMaxSide = 8192;
/// Sample buffers stay within this many samples (8 bytes of key and 3 of colour each).
constexpr std::uint64_t kMaxSamples = 4096ull * 4096ull;
/// Rows of samples per band of the rasterizer (one task each).
constexpr long kBandRows = 16;

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

double edgeFunction(const Vec3d& a, const Vec3d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

/// Sample rows [y0, y1] a face may cover (y0 > y1: none), as the rasterizer clips them.
struct RowRange {
  long y0 = 1, y1 = 0;
};

/// The samples of one face: x, y ranges, stepping of the barycentric weights and the depth.
struct FaceSetup {
  Vec3d a, b, c;  // b and c swapped when the face is seen clockwise
  double area = 0.0, inv = 0.0, stepA = 0.0, stepB = 0.0, depthStep = 0.0;
  long x0 = 0, x1 = -1, y0 = 0, y1 = -1;
};

bool setupFace(const ScreenFace& face, const SampleCanvas& canvas, FaceSetup& s) {
  s.a = face.corner[0], s.b = face.corner[1], s.c = face.corner[2];
  s.area = edgeFunction(s.a, s.b, s.c.x(), s.c.y());
  if (!(std::fabs(s.area) > 1e-12)) return false;  // seen edge-on (or not finite)
  if (s.area < 0.0) std::swap(s.b, s.c), s.area = -s.area;
  const double maxX = canvas.width(), maxY = canvas.height();
  const double lo[2] = {std::min({s.a.x(), s.b.x(), s.c.x()}), std::min({s.a.y(), s.b.y(), s.c.y()})};
  const double hi[2] = {std::max({s.a.x(), s.b.x(), s.c.x()}), std::max({s.a.y(), s.b.y(), s.c.y()})};
  if (hi[0] < 0.0 || hi[1] < 0.0 || lo[0] >= maxX || lo[1] >= maxY) return false;
  // Sample centres x + 0.5 inside [lo, hi].
  s.x0 = std::max(0L, static_cast<long>(std::ceil(lo[0] - 0.5)));
  s.y0 = std::max(0L, static_cast<long>(std::ceil(lo[1] - 0.5)));
  s.x1 = std::min(long(maxX) - 1, static_cast<long>(std::floor(hi[0] - 0.5)));
  s.y1 = std::min(long(maxY) - 1, static_cast<long>(std::floor(hi[1] - 0.5)));
  // Barycentric weights (times area) of a and b step linearly along a row; depth too.
  s.inv = 1.0 / s.area;
  s.stepA = -(s.c.y() - s.b.y());
  s.stepB = -(s.a.y() - s.c.y());
  s.depthStep = (s.stepA * (s.a.z() - s.c.z()) + s.stepB * (s.b.z() - s.c.z())) * s.inv;
  return s.x0 <= s.x1 && s.y0 <= s.y1;
}

/// The checker colour of a face at sample (x, y): the (u, v) interpolated in the face's own
/// corner order, Lambert + ambient.
void shadeSample(const ScreenFace& face, long x, long y, const RenderOptions& options, std::uint8_t* out) {
  const Vec3d &a = face.corner[0], &b = face.corner[1], &c = face.corner[2];
  const double px = x + 0.5, py = y + 0.5;
  const double area = edgeFunction(a, b, c.x(), c.y());
  const double wa = edgeFunction(b, c, px, py) / area, wb = edgeFunction(c, a, px, py) / area;
  const double wc = 1.0 - wa - wb;
  const Vec2d uv = wa * face.uv[0] + wb * face.uv[1] + wc * face.uv[2];
  const bool isDark = (cellParity(uv.x() * options.checker) ^ cellParity(uv.y() * options.checker)) != 0;
  const Rgb& base = isDark ? options.dark : options.light;
  const double shade = face.shade;
  for (int k = 0; k < 3; ++k) out[k] = static_cast<std::uint8_t>(std::min(255.0, base[k] * shade + 0.5));
}

/// Rows [from, to] of a set-up face.
void rasterizeRows(const ScreenFace& face, const FaceSetup& s, long from, long to, const RenderOptions& options,
                   SampleCanvas& canvas) {
  constexpr double kSlack = 1e-6;  // squared samples
  for (long y = std::max(from, s.y0); y <= std::min(to, s.y1); ++y) {
    const double py = y + 0.5, px = s.x0 + 0.5;
    double wa = edgeFunction(s.b, s.c, px, py), wb = edgeFunction(s.c, s.a, px, py);
    double depth = (wa * s.a.z() + wb * s.b.z() + (s.area - wa - wb) * s.c.z()) * s.inv;
    const std::uint64_t row = canvas.index(0, std::uint32_t(y));
    for (long x = s.x0; x <= s.x1; ++x, wa += s.stepA, wb += s.stepB, depth += s.depthStep) {
      // Inclusive, with a little slack for the stepping error: shared edges leave no cracks.
      if (wa < -kSlack || wb < -kSlack || s.area - wa - wb < -kSlack) continue;
      if (canvas.testAndSet(row + std::uint64_t(x), float(depth), face.id)) {
        shadeSample(face, x, y, options, canvas.color(row + std::uint64_t(x)));
      }
    }
  }
}

}  // namespace

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
  if (options.width < 1 || options.height < 1 || options.width > kMaxSide || options.height > kMaxSide) {
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

FrameBuilder::FrameBuilder(const RenderOptions& options)
    : options_(options), axes_(viewAxes(options)), extent_(empty()) {
  checkOptions(options);
}

FrameBuilder::Extent FrameBuilder::empty() {
  const float fi = std::numeric_limits<float>::infinity();
  const double di = std::numeric_limits<double>::infinity();
  return Extent{{fi, fi, fi}, {-fi, -fi, -fi}, {di, -di}, {di, -di}};
}

void FrameBuilder::grow(Extent& e, const Vec3f& p, const ViewAxes& axes) {
  for (int k = 0; k < 3; ++k) e.lo[k] = std::min(e.lo[k], p[k]), e.hi[k] = std::max(e.hi[k], p[k]);
  const Vec3d q = p.cast<double>();
  const double x = q.dot(axes.right), y = q.dot(axes.up);
  e.x[0] = std::min(e.x[0], x), e.x[1] = std::max(e.x[1], x);
  e.y[0] = std::min(e.y[0], y), e.y[1] = std::max(e.y[1], y);
}

FrameBuilder::Extent FrameBuilder::join(const Extent& a, const Extent& b) {
  Extent e = a;
  for (int k = 0; k < 3; ++k) e.lo[k] = std::min(a.lo[k], b.lo[k]), e.hi[k] = std::max(a.hi[k], b.hi[k]);
  e.x[0] = std::min(a.x[0], b.x[0]), e.x[1] = std::max(a.x[1], b.x[1]);
  e.y[0] = std::min(a.y[0], b.y[0]), e.y[1] = std::max(a.y[1], b.y[1]);
  return e;
}

void FrameBuilder::add(const Vec3f& p) { grow(extent_, p, axes_); }

void FrameBuilder::addAll(const std::vector<Vec3f>& positions) {
  const Extent part = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, positions.size(), 1 << 14), empty(),
      [&](const tbb::blocked_range<std::size_t>& r, Extent e) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) grow(e, positions[v], axes_);
        return e;
      },
      &FrameBuilder::join);
  extent_ = join(extent_, part);
}

RenderCamera FrameBuilder::camera() const {
  RenderCamera camera;
  camera.right = axes_.right;
  camera.up = axes_.up;
  camera.forward = axes_.forward;
  camera.width = options_.width;
  camera.height = options_.height;
  if (!(extent_.x[0] <= extent_.x[1])) return camera;  // no positions
  const Vec3d lo(extent_.lo[0], extent_.lo[1], extent_.lo[2]), hi(extent_.hi[0], extent_.hi[1], extent_.hi[2]);
  const Vec3d boxCenter = 0.5 * (lo + hi);
  // Extent along the screen axes relative to the box centre.
  const double x0 = extent_.x[0] - boxCenter.dot(axes_.right), x1 = extent_.x[1] - boxCenter.dot(axes_.right);
  const double y0 = extent_.y[0] - boxCenter.dot(axes_.up), y1 = extent_.y[1] - boxCenter.dot(axes_.up);
  camera.center = boxCenter + 0.5 * (x0 + x1) * axes_.right + 0.5 * (y0 + y1) * axes_.up;
  const double inf = std::numeric_limits<double>::infinity();
  const double spanX = extent_.x[1] - extent_.x[0], spanY = extent_.y[1] - extent_.y[0];
  const double usable = 1.0 - 2.0 * options_.margin;
  const double fitX = spanX > 0.0 ? usable * options_.width / spanX : inf;
  const double fitY = spanY > 0.0 ? usable * options_.height / spanY : inf;
  const double fit = std::min(fitX, fitY);
  camera.pixelsPerUnit = std::isfinite(fit) && fit > 0.0 ? fit : 1.0;
  return camera;
}

std::uint32_t samplesPerPixel(const RenderOptions& options) {
  std::uint32_t ss = std::max<std::uint32_t>(1, options.supersample);
  while (ss > 1 && std::uint64_t(options.width) * ss * options.height * ss > kMaxSamples) --ss;
  return ss;
}

SampleCanvas::SampleCanvas(std::uint32_t width, std::uint32_t height, const Rgb& background)
    : width_(width), height_(height), keys_(count(), kEmpty), colors_(3 * count()) {
  parallelForEach(count(), 1 << 16, [&](std::uint64_t i) {
    colors_[3 * i] = background[0], colors_[3 * i + 1] = background[1], colors_[3 * i + 2] = background[2];
  });
}

double SampleCanvas::depth(std::uint64_t i) const {
  const std::uint64_t k = keys_[i];
  return k == kEmpty ? std::numeric_limits<double>::infinity() : keyDepth(std::uint32_t(k >> 32));
}

bool SampleCanvas::testAndSet(std::uint64_t i, float depth, FaceId id) {
  const std::uint64_t key = (std::uint64_t(depthKey(depth)) << 32) | id;
  if (!(key < keys_[i])) return false;
  keys_[i] = key;
  return true;
}

bool SampleCanvas::isVisible(const Vec2d& p, double d, double tolerance) const {
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

void SampleCanvas::stampDisk(const Vec2d& p, double radius, const Rgb& rgb) {
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

Vec3d toScreen(const RenderCamera& camera, double samplesPerPixel, const Vec3d& p) {
  const Vec2d s = camera.project(p) * samplesPerPixel;
  return Vec3d(s.x(), s.y(), camera.depth(p));
}

float faceShade(const RenderCamera& camera, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d light = (-camera.forward + 0.5 * camera.up - 0.3 * camera.right).normalized();
  constexpr double kAmbient = 0.3, kDiffuse = 0.7;
  const Vec3d n = (b - a).cross(c - a);
  const double len = n.norm();
  const Vec3d normal = len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
  return float(kAmbient + kDiffuse * std::fabs(normal.dot(light)));
}

void rasterizeFaces(const std::vector<ScreenFace>& faces, const RenderOptions& options, SampleCanvas& canvas) {
  const long bands = (long(canvas.height()) + kBandRows - 1) / kBandRows;
  std::vector<FaceSetup> setup(faces.size());
  std::vector<std::uint8_t> visible(faces.size(), 0);
  parallelForEach(faces.size(), 1024, [&](std::uint64_t i) { visible[i] = setupFace(faces[i], canvas, setup[i]); });
  // The faces of each band in order (counting sort by band).
  std::vector<std::uint32_t> start(bands + 1, 0);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!visible[i]) continue;
    for (long b = setup[i].y0 / kBandRows; b <= setup[i].y1 / kBandRows; ++b) ++start[b + 1];
  }
  for (long b = 0; b < bands; ++b) start[b + 1] += start[b];
  std::vector<std::uint32_t> inBand(start[bands]);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (!visible[i]) continue;
      for (long b = setup[i].y0 / kBandRows; b <= setup[i].y1 / kBandRows; ++b) {
        inBand[fill[b]++] = static_cast<std::uint32_t>(i);
      }
    }
  }
  parallelForEach(static_cast<std::uint64_t>(bands), 1, [&](std::uint64_t b) {
    const long from = long(b) * kBandRows, to = from + kBandRows - 1;
    for (std::uint32_t k = start[b]; k < start[b + 1]; ++k) {
      rasterizeRows(faces[inBand[k]], setup[inBand[k]], from, to, options, canvas);
    }
  });
}

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

double lineTolerance(const RenderCamera& camera, std::uint32_t samplesPerPixel) {
  return 2.0 / (camera.pixelsPerUnit * samplesPerPixel);
}

void drawCones(const std::vector<RenderCone>& cones, const std::vector<Vec3d>& screen, const RenderOptions& options,
               std::uint32_t samplesPerPixel, double tolerance, SampleCanvas& canvas) {
  const double ss = samplesPerPixel;
  const double radius =
      (options.coneRadius > 0.0 ? options.coneRadius
                                : std::max(3.0, std::min(options.width, options.height) / 160.0)) * ss;
  const Rgb outline{20, 20, 20};
  for (std::size_t k = 0; k < cones.size(); ++k) {
    const Vec2d q(screen[k].x(), screen[k].y());
    if (!canvas.isVisible(q, screen[k].z(), tolerance)) continue;
    canvas.stampDisk(q, radius + ss, outline);
    canvas.stampDisk(q, radius, cones[k].quarterTurns > 0 ? options.positiveCone : options.negativeCone);
  }
}

void drawLines(const RenderOptions& options, const RenderCamera& camera, std::uint32_t samplesPerPixel,
               SampleCanvas& canvas) {
  for (const auto& [from, to] : options.lines) {
    drawSegment(toScreen(camera, samplesPerPixel, from), toScreen(camera, samplesPerPixel, to),
                0.5 * options.lineWidth * samplesPerPixel, options.lineDepthTolerance / camera.pixelsPerUnit,
                options.lineColor, canvas);
  }
}

void downsample(const SampleCanvas& canvas, std::uint32_t samplesPerPixel, const RenderOptions& options,
                RenderResult& result) {
  const std::uint32_t ss = samplesPerPixel;
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
          covered |= canvas.covered(i);
          const std::uint8_t* c = canvas.color(i);
          for (int k = 0; k < 3; ++k) sum[k] += c[k];
        }
      }
      std::uint8_t* out = &image.pixels[3 * (y * image.width + x)];
      for (int k = 0; k < 3; ++k) out[k] = static_cast<std::uint8_t>((sum[k] + ss * ss / 2) / (ss * ss));
      coveredRows[y] += covered;
    }
  });
  result.coveredPixels = 0;
  for (const std::uint32_t n : coveredRows) result.coveredPixels += n;
}

int coneTurns(double angleSum, double angleTolerance) {
  const double quarters = (2.0 * kPi - angleSum) / (0.5 * kPi);
  const double k = std::round(quarters);
  if (!(std::fabs(quarters - k) * 0.5 * kPi <= angleTolerance)) return kIrregularAngleSum;
  return static_cast<int>(std::clamp(k, -127.0, 127.0));
}

double cornerAngle(const Vec2d& p, const Vec2d& q, const Vec2d& r) {
  const Vec2d e1 = q - p, e2 = r - p;
  return std::atan2(e1.x() * e2.y() - e1.y() * e2.x(), e1.dot(e2));
}

bool uvDiffer(const Vec2d& a, const Vec2d& b, double tolerance) {
  const double scale = std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
  return !((a - b).cwiseAbs().maxCoeff() <= tolerance * scale);
}

}  // namespace seamvox::render_detail
