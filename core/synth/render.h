#pragma once
/// Checkerboard pictures of a parameterization: a headless software rasterizer (z-buffer,
/// Lambert + ambient shading, (u, v) checkerboard, seam lines, cone dots) into an RGB image.
#include <array>
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// 8-bit RGB image, rows top to bottom, 3 bytes per pixel.
struct RgbImage {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  ///< 3 * width * height
  const std::uint8_t* pixel(std::uint32_t x, std::uint32_t y) const {
    return &pixels[3 * (std::size_t(y) * width + x)];
  }
};

using Rgb = std::array<std::uint8_t, 3>;

/// Orthographic camera. The eye looks at `center` from azimuth/elevation; image x grows to the
/// right, y downwards; pixel (x, y) covers [x, x+1) x [y, y+1) (its centre is x + 0.5).
struct RenderCamera {
  Vec3d center = Vec3d::Zero();
  Vec3d right = Vec3d::UnitX(), up = Vec3d::UnitY(), forward = -Vec3d::UnitZ();
  double pixelsPerUnit = 1.0;  ///< output pixels per mesh unit
  double width = 1.0, height = 1.0;  ///< output image size in pixels
  /// Image position (x right, y down, in output pixels) of a point.
  Vec2d project(const Vec3d& p) const;
  /// Distance of a point along the viewing direction from the centre (smaller is nearer).
  double depth(const Vec3d& p) const { return (p - center).dot(forward); }
};

struct RenderOptions {
  /// Output size in pixels, each in [1, 8192] (8192 x 8192 needs about 1.2 GB).
  std::uint32_t width = 1024, height = 1024;
  /// View in degrees around the bounding-box centre. Azimuth 0, elevation 0: image right is +x
  /// (+y when up = x) and the eye lies on right x up (up = y: eye on +z; up = z: eye on -y).
  /// Azimuth turns the eye counter-clockwise about the up axis; elevation raises it towards up
  /// (90: looking straight down, the azimuth-0 eye side at the image bottom).
  double azimuth = 30.0, elevation = 20.0;
  int upAxis = 1;            ///< 0 = x, 1 = y, 2 = z is "up" in the picture
  double checker = 1.0;      ///< checker cells per unit of u and v (> 0)
  bool drawSeams = false;    ///< edges whose two sides have different (u, v)
  bool drawCones = false;    ///< vertices where the map turns by a multiple of 90 degrees
  double seamTolerance = 1e-6;  ///< (u, v) difference (relative to max(1, |uv|)) that is a seam
  /// Samples per pixel along each axis (anti-aliasing); lowered automatically so that the
  /// sample buffer stays within 4096 x 4096 samples.
  std::uint32_t supersample = 2;
  double margin = 0.04;      ///< free border around the mesh, as a fraction of the image size
  Rgb light{236, 236, 228}, dark{86, 110, 160};  ///< the two checker colours
  Rgb seamColor{255, 170, 0}, background{255, 255, 255};
  Rgb positiveCone{220, 30, 30}, negativeCone{30, 70, 235};
  double seamWidth = 1.5;    ///< output pixels
  /// Segments drawn over the surface where not hidden (e.g. a quad mesh's edges; its vertices lie
  /// on the surface), in lineColor, lineWidth output pixels wide.
  std::vector<std::array<Vec3d, 2>> lines;
  Rgb lineColor{25, 25, 25};
  double lineWidth = 1.2;
  /// Depth (output pixels) a line may lie behind the surface and still show: a straight edge
  /// between two surface points cuts under a curved surface.
  double lineDepthTolerance = 8.0;
  double coneRadius = 0.0;   ///< output pixels; 0 = from the image size
  ProgressFn progress;
};

/// A vertex where the map is singular: parameter-space angle sum 2 pi (1 - index).
struct RenderCone {
  VertexId vertex = kInvalidId;
  int quarterTurns = 0;  ///< 4 * index: +1 for a cone of index +1/4 (angle sum 3 pi / 2)
};

struct RenderResult {
  RgbImage image;
  RenderCamera camera;
  std::uint64_t coveredPixels = 0;  ///< output pixels that show the mesh
  std::uint64_t seamEdges = 0;      ///< interior edges with a (u, v) discontinuity
  std::vector<RenderCone> cones;    ///< interior vertices with a singular angle sum (drawCones)
  std::uint64_t irregularVertices = 0;  ///< see MapCones (drawCones)
  double seconds = 0.0;
};

/// Camera that frames the whole mesh (all of its positions) for the options' view and size.
RenderCamera frameMesh(const TriangleMesh& mesh, const RenderOptions& options);

/// Interior edges (named by their smaller corner, topology.h) whose two sides disagree in (u, v).
std::vector<CornerId> findSeamEdges(const TriangleMesh& mesh, const Topology& topology,
                                    double tolerance = 1e-6);

struct MapCones {
  std::vector<RenderCone> cones;
  /// Interior vertices whose angle sum is no multiple of pi / 2 (the map is not seamless there).
  std::uint64_t irregularVertices = 0;
};
/// Interior vertices whose signed (u, v) corner angles sum to 2 pi - k pi / 2 with k != 0
/// (within angleTolerance radians).
MapCones findMapCones(const TriangleMesh& mesh, const Topology& topology,
                      double angleTolerance = 1e-2);

/// Renders the mesh with its per-corner (u, v) as a shaded checkerboard, both sides lit.
/// Requires mesh.cornerUV (InputError otherwise) and a topology of mesh.triangles when seams or
/// cones are drawn. faceIds (one per face, or empty: the face index) break exact depth ties, the
/// nearest smaller id winning: a cleaned mesh's faceOrigin gives the pixels the out-of-core
/// renderer (stream/map_render) gives for the input. Parallel; memory about 11 bytes per sample
/// plus 3 bytes per output pixel.
RenderResult renderCheckerboard(const TriangleMesh& mesh, const Topology& topology,
                                const RenderOptions& options = {}, const std::vector<FaceId>& faceIds = {});

}  // namespace seamvox
