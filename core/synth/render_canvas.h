#pragma once
/// The pieces of a checkerboard picture that the in-memory renderer (renderCheckerboard) and the
/// out-of-core one (stream/map_render) share, so that both give the same pixels: the camera
/// framed from positions added in any order, faces rasterized chunk by chunk with their colour
/// decided as they win a sample, lines, cone dots and the box filter to the output size.
#include <cstdint>
#include <vector>

#include "core/synth/render.h"

namespace seamvox::render_detail {

struct ViewAxes {
  Vec3d right, up, forward;
};

/// Screen axes for the options' up axis, azimuth and elevation (see RenderOptions).
ViewAxes viewAxes(const RenderOptions& options);
/// Throws InputError for options outside their ranges.
void checkOptions(const RenderOptions& options);

/// The camera that frames every position added (frameMesh): bounding box and extents along the
/// screen axes, independent of the order and chunking of the positions.
class FrameBuilder {
 public:
  explicit FrameBuilder(const RenderOptions& options);
  void add(const Vec3f& p);
  void addAll(const std::vector<Vec3f>& positions);  ///< parallel; same result as add one by one
  RenderCamera camera() const;

 private:
  struct Extent {
    float lo[3], hi[3];  // bounding box
    double x[2], y[2];   // min and max of p . right, p . up
  };
  static Extent empty();
  static void grow(Extent& e, const Vec3f& p, const ViewAxes& axes);
  static Extent join(const Extent& a, const Extent& b);
  RenderOptions options_;
  ViewAxes axes_;
  Extent extent_;
};

/// Samples per pixel along each axis: options.supersample, lowered so that the canvas stays
/// within 4096 x 4096 samples.
std::uint32_t samplesPerPixel(const RenderOptions& options);

/// The supersampled picture: per sample the nearest (depth, face id) key and its colour.
class SampleCanvas {
 public:
  SampleCanvas(std::uint32_t width, std::uint32_t height, const Rgb& background);
  std::uint64_t count() const { return std::uint64_t(width_) * height_; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  std::uint64_t index(std::uint32_t x, std::uint32_t y) const { return std::uint64_t(y) * width_ + x; }
  bool covered(std::uint64_t i) const { return keys_[i] != kEmpty; }
  /// Depth of the nearest fragment, +infinity for an empty sample.
  double depth(std::uint64_t i) const;
  std::uint8_t* color(std::uint64_t i) { return &colors_[3 * i]; }
  const std::uint8_t* color(std::uint64_t i) const { return &colors_[3 * i]; }
  /// Whether the fragment (depth, id) is nearer than the stored one (ties: smaller id); if so it
  /// is stored and the caller writes its colour.
  bool testAndSet(std::uint64_t i, float depth, FaceId id);
  /// Whether a point at sample position p and depth d is in front of (or on) the surface: its
  /// depth is at most the farthest of the 3 x 3 samples around it, plus tolerance.
  bool isVisible(const Vec2d& p, double d, double tolerance) const;
  /// Paints the samples whose centres lie within radius of p (sample units).
  void stampDisk(const Vec2d& p, double radius, const Rgb& rgb);

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::uint32_t width_, height_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint8_t> colors_;
};

/// A face ready to rasterize: its corners on screen (x, y in samples, depth), their (u, v), the
/// face's brightness and the id that breaks depth ties (the input face index).
struct ScreenFace {
  Vec3d corner[3];
  Vec2d uv[3];
  float shade = 0.0f;
  FaceId id = 0;
};

/// Screen position (x, y in samples) and depth of a point.
Vec3d toScreen(const RenderCamera& camera, double samplesPerPixel, const Vec3d& p);
/// Brightness of a face (ambient + Lambert from a light above-left of the eye, both sides lit)
/// with corners a, b, c.
float faceShade(const RenderCamera& camera, const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Z-buffers the faces (both sides) into the canvas, each sample coloured by the checker of its
/// interpolated (u, v) as a face wins it: parallel over bands of rows, each band taking the faces
/// that reach it in order, so the result does not depend on the thread count or the chunking.
void rasterizeFaces(const std::vector<ScreenFace>& faces, const RenderOptions& options, SampleCanvas& canvas);

/// A thick line between two screen points (x, y, depth), drawn where not hidden.
void drawSegment(const Vec3d& a, const Vec3d& b, double radius, double tolerance, const Rgb& rgb,
                 SampleCanvas& canvas);
/// Depth tolerance of lines and dots: two samples' worth of mesh units.
double lineTolerance(const RenderCamera& camera, std::uint32_t samplesPerPixel);
/// The cone dots (screen position of each cone's vertex), where not hidden.
void drawCones(const std::vector<RenderCone>& cones, const std::vector<Vec3d>& screen, const RenderOptions& options,
               std::uint32_t samplesPerPixel, double tolerance, SampleCanvas& canvas);
/// The quad-mesh segments of options.lines.
void drawLines(const RenderOptions& options, const RenderCamera& camera, std::uint32_t samplesPerPixel,
               SampleCanvas& canvas);
/// Box filter down to the output size into result.image; counts result.coveredPixels.
void downsample(const SampleCanvas& canvas, std::uint32_t samplesPerPixel, const RenderOptions& options,
                RenderResult& result);

/// Cone of a vertex from the sum of its corners' signed (u, v) angles (findMapCones): quarter
/// turns k != 0, 0, or kIrregularAngleSum when the sum is no multiple of pi / 2.
constexpr int kIrregularAngleSum = -128;
int coneTurns(double angleSum, double angleTolerance = 1e-2);
/// Signed (u, v) angle at corner p between the edges to q and r.
double cornerAngle(const Vec2d& p, const Vec2d& q, const Vec2d& r);
/// Whether two (u, v) of one vertex differ beyond tolerance (relative to max(1, |uv|)).
bool uvDiffer(const Vec2d& a, const Vec2d& b, double tolerance);

}  // namespace seamvox::render_detail
