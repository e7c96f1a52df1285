#pragma once
/// The in-memory triangle mesh: plain arrays indexed by 32-bit ids.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "core/mesh/mesh_types.h"
#include "core/mesh/vertex_attributes.h"
#include "core/mesh/wedge_map.h"

namespace seamvox {

/// A triangle soup or indexed mesh. Positions are float (scans; 12 bytes per vertex), all
/// geometric computation is done in double. Triangles are counter-clockwise seen from outside.
struct TriangleMesh {
  std::vector<Vec3f> positions;     ///< #V
  std::vector<Triangle> triangles;  ///< #F
  /// Optional texture coordinates (u, v) in grid units per corner (3 * #F corners) or empty,
  /// stored per wedge. Double: seam checks need 1e-6 absolute accuracy on coordinates of
  /// several thousand.
  WedgeMap cornerUV;
  /// Per-vertex properties read with the mesh (colors, normals, scalars), #V values each or none;
  /// they follow every vertex edit and are written where the output format can hold them.
  VertexAttributes attributes;
  /// Vertices of the file joined while it was read (STL's per-facet corners at equal positions):
  /// cleanMesh counts them as input vertices welded, as the out-of-core weld pass does.
  std::uint64_t weldedAtRead = 0;
  /// Where position zero lies in the file's coordinates: a vertex is at origin + positions[v].
  /// Zero unless the file's coordinates lie far from zero (a georeferenced scan at 5e5, 4e6),
  /// where floats would lose the mesh's detail: the readers then keep positions relative to the
  /// first vertex rounded to whole units, every stage works on those (the map does not depend on a
  /// translation), and the writers add it back in double precision.
  Vec3d origin = Vec3d::Zero();

  std::uint32_t numVertices() const { return static_cast<std::uint32_t>(positions.size()); }
  std::uint32_t numFaces() const { return static_cast<std::uint32_t>(triangles.size()); }
  bool hasUV() const { return !cornerUV.empty(); }
  Vec3d position(VertexId v) const { return positions[v].cast<double>(); }
};

/// TriangleMesh::origin for a mesh whose first vertex lies at p (in the file's coordinates): zero
/// unless a coordinate lies beyond kOriginBeyond (float spacing 0.002 there), then p rounded to
/// whole units.
constexpr double kOriginBeyond = 16384.0;
Vec3d originFor(const Vec3d& p);

/// Axis-aligned bounding box of the positions (empty mesh: min > max).
struct BoundingBox {
  Vec3d min{Vec3d::Constant(1e300)};
  Vec3d max{Vec3d::Constant(-1e300)};
  bool isEmpty() const { return (min.array() > max.array()).any(); }
  Vec3d extent() const { return isEmpty() ? Vec3d::Zero() : Vec3d(max - min); }
  double diagonal() const { return extent().norm(); }
};
BoundingBox computeBoundingBox(const std::vector<Vec3f>& positions);

/// Unit normal of a face (zero vector for a zero-area face).
Vec3d faceNormal(const TriangleMesh& mesh, FaceId f);
/// The same for the corners a, b, c.
Vec3d faceNormal(const Vec3d& a, const Vec3d& b, const Vec3d& c);
/// Area of a face.
double faceArea(const TriangleMesh& mesh, FaceId f);
/// The same for the corners a, b, c.
double faceArea(const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// The unit normal cleanMesh glues the sides of an edge of more than two faces by (the best
/// aligned pairs first): zero for a sliver (height below 1e-4 of its longest edge: its normal is
/// rounding noise) and for a non-finite triangle.
Vec3d gluingNormal(const Vec3d& a, const Vec3d& b, const Vec3d& c);
/// Alignment of two faces by their gluing normals: their dot product; -3 when either is a sliver
/// (a scan's collinear faces on an edge are glued last); -2 when not finite.
double gluingAlignment(const Vec3d& n0, const Vec3d& n1);

}  // namespace seamvox
