#pragma once
/// Quality figures of a parameterization (DESIGN section 11).
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// Seam figures. A map is seamless when both maxima are below the tolerance (1e-6).
struct SeamQuality {
  std::uint64_t seamEdges = 0;
  std::uint32_t seams = 0;           ///< seam curves (0 when reconstructed from UVs)
  double seamLength = 0.0;           ///< 3D length of the seam edges
  double maxResidual = 0.0;          ///< max |q' - (r q + t)| over seam corners
  double maxIntegerDistance = 0.0;   ///< max distance of a seam's t from Z + iZ
  std::uint64_t worstEdgeCorner = kInvalidId;  ///< corner of the edge with the largest residual
  bool isSeamless(double tolerance = 1e-6) const {
    return maxResidual <= tolerance && maxIntegerDistance <= tolerance;
  }
};

/// Seams of a known cut: per seam, t is read at its first corner with r = i^(-matching) (cut.h)
/// and q_right = r q_left + t is checked at both ends of every edge.
SeamQuality measureSeams(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                         const WedgeMap& cornerUV);
/// The same from accessors (a mesh out of core): value(c) the map at corner c, opposite(c), and
/// edgeLength(c) the 3D length of corner c's edge.
using SeamCornerValue = std::function<Vec2d(CornerId)>;
SeamQuality measureSeams(const std::vector<SeamCurve>& seams, const SeamCornerValue& value,
                         const std::function<CornerId(CornerId)>& opposite,
                         const std::function<double(CornerId)>& edgeLength);

/// The fit of one seam edge from its two sides' UVs at its ends A and B (q' on the right side):
/// the r in {1, i, -1, -i} with the smallest residual |q'_B - (r q_B + t)| for t = q'_A - r q_A
/// (ties: the t nearest to Z + iZ), that residual and t's distance from Z + iZ.
struct SeamEdgeFit {
  double residual = 0.0, integerDistance = 0.0;
};
SeamEdgeFit fitSeamEdge(const Vec2d& leftA, const Vec2d& rightA, const Vec2d& leftB, const Vec2d& rightB);

/// Seams reconstructed from per-corner UVs alone: every interior edge whose two sides differ is a
/// seam edge; r in {1, i, -1, -i} and t come from one endpoint (the r fitting best at the other),
/// the residual from the other endpoint.
SeamQuality measureSeamsFromUV(const TriangleMesh& mesh, const Topology& topology,
                               const WedgeMap& cornerUV);

/// A face whose |parameter area| is below this fraction of its expected area A_T / h^2 is collapsed.
constexpr double kCollapsedAreaFraction = 1e-6;
/// A flipped face by its parameterAreaRatio: negative, and not collapsed.
inline bool isFlippedRatio(double ratio) { return ratio < 0.0 && std::abs(ratio) >= kCollapsedAreaFraction; }

/// |grad u|^2 + |grad v|^2 of the linear map of a triangle with corners p and values q (NaN for a
/// zero-area triangle).
double gradientNormSquared(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q);
/// A face is stretched when h^2 (|grad u|^2 + |grad v|^2) / 2 (1 for |grad q| = 1/h) is above
/// this: the map stretches it over ten times on average, a smear no flip or collapse count sees.
constexpr double kStretchedFaceStretch = 100.0;
inline bool isStretched(double gradientNormSquared, double h) {
  return std::isfinite(gradientNormSquared) && 0.5 * h * h * gradientNormSquared > kStretchedFaceStretch;
}

/// Signed parameter-space area of face f (corners 3 f .. 3 f + 2 of cornerUV) over its expected
/// area A_T / h^2: 1 for a map with |grad q| = 1/h and no shear, negative when flipped, +-inf or
/// NaN for a face of zero 3D area.
double parameterAreaRatio(const TriangleMesh& mesh, const WedgeMap& cornerUV, FaceId f,
                          double edgeLength);
/// The same with face f's corner values given (q[k] at corner 3 f + k).
double parameterAreaRatio(const TriangleMesh& mesh, FaceId f, const std::array<Vec2d, 3>& q, double edgeLength);
/// The same from the face's corner positions p and values q.
double parameterAreaRatio(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q, double edgeLength);

/// Two cones whose corners are this close in (u, v) (grid units) coincide.
constexpr double kCoincidentConeDistance = 1e-9;

/// True when face f has an edge between two cones (isCone per vertex) whose corners have the same
/// (u, v) within kCoincidentConeDistance. In a seamless map a cone sits where the rotations of
/// its seams fix it (DESIGN section 7: c_0 = beta . t / alpha), on the half-integer lattice once
/// the translations are rounded, whatever the other vertices do. Two cones closer than about h/2 (cone pairs of a
/// noisy field, often one edge apart) then land on the same point and their shared triangles
/// collapse in every solver (hat included): only other translations could separate them, at the
/// price of a large distortion. This collapse belongs to the field and the rounding, not to the
/// basis, so it is counted apart (MapQuality::collapsedAtCones).
bool collapsesBetweenCones(const TriangleMesh& mesh, const WedgeMap& cornerUV, FaceId f,
                           const std::vector<std::uint8_t>& isCone);
/// The same with face f's corner values given (q[k] at corner 3 f + k).
bool collapsesBetweenCones(const TriangleMesh& mesh, FaceId f, const std::array<Vec2d, 3>& q,
                           const std::vector<std::uint8_t>& isCone);

/// True when face f's normal points away from the same face's normal on a smoothed copy of the
/// surface (same triangles, positions `smooth`, e.g. CrossField::framePositions): the face is
/// folded in 3D, and a map that follows the smooth surface flips it.
bool faceFoldedIn3D(const TriangleMesh& mesh, const std::vector<Vec3f>& smooth, FaceId f);
/// The same from the face's corner positions p and its corners on the smoothed surface.
bool faceFoldedIn3D(const std::array<Vec3d, 3>& p, const Vec3f& sa, const Vec3f& sb, const Vec3f& sc);

/// faceFoldedIn3D for each of `faces` against the field's smoothed surface: its framePositions,
/// or when they were released (releaseFramePositions) the same positions recomputed around these
/// faces (framePositionsAt; needs the topology, else InputError). All 0 without a smoothed
/// surface (no field, or a field made on the mesh itself).
std::vector<std::uint8_t> facesFoldedIn3D(const TriangleMesh& mesh, const Topology* topology,
                                          const CrossField* field, const std::vector<FaceId>& faces);

struct MapQuality {
  std::uint64_t faces = 0;
  std::uint64_t flipped = 0;    ///< negative parameter-space area (not collapsed)
  /// Of the flipped faces, those folded in 3D: normal opposite to the same face on the field's
  /// smoothed surface (CrossField::framePositions; 0 without one).
  std::uint64_t flippedFolded = 0;
  /// |parameter area| < kCollapsedAreaFraction of the expected area A / h^2
  std::uint64_t collapsed = 0;
  /// Of the collapsed faces, those between two coincident cones (collapsesBetweenCones); 0 when
  /// measureMap was given no cones.
  std::uint64_t collapsedAtCones = 0;
  /// Neither flipped nor collapsed, stretched (isStretched) by the map.
  std::uint64_t stretched = 0;
  /// Interior vertices the map winds around twice or more (woundVertices): a fold that no flipped
  /// face shows. Counted when measureMap has the topology (woundCounted), else 0.
  std::uint64_t wound = 0;
  bool woundCounted = false;
  double flippedFraction = 0.0;
  /// sqrt(sum A |grad q - w/h|^2 / sum A |w/h|^2), w the nearest of the 4 cross directions;
  /// NaN without a field.
  double relativeGradientError = 0.0;
  double edgeLength = 0.0;  ///< h used (given, or fitted by least squares when given <= 0)
};

/// The signed (u, v) angles of the corners at interior vertex v summed, each in its own face's
/// chart: 2 pi w at a regular vertex the map winds around w times (the fan's triangles all
/// positive: w >= 1), 2 pi - k pi / 2 at a cone of index k / 4 wound once; each angle within
/// 2e-6 rad. A corner with an edge of zero length in (u, v) (a collapsed face) adds nothing.
double cornerAngleSum(const Topology& topology, const WedgeMap& cornerUV, VertexId v);
/// One corner's signed (u, v) angle as cornerAngleSum sums it: at q, from the edge to next to
/// the edge to prev; 0 when either edge has zero length.
double cornerUVAngle(const Vec2d& q, const Vec2d& next, const Vec2d& prev);
/// An interior vertex whose corner angles sum to at least this (3.75 pi) is wound: the map covers
/// the plane around it twice or more. A foldover repair that counts only flipped faces can end
/// there: moving a vertex into the kernel of a fan that winds twice unflips every face and
/// leaves a branch point (next to a cone, whose own angle drops by 2 pi). A cone of index -1 or
/// below (angle 4 pi or more) counts too: a file alone cannot tell it from a fold.
constexpr double kWoundAngleSum = 3.75 * 3.14159265358979323846;
/// Interior vertices wound by the map (kWoundAngleSum), increasing. Linear, parallel.
std::vector<VertexId> woundVertices(const Topology& topology, const WedgeMap& cornerUV);

/// Flips, collapses and the gradient error against a field (may be null) for target spacing h
/// (<= 0: fitted); with the cones (vertex ids, e.g. CutResult::cones) also collapsedAtCones.
/// Linear, parallel.
/// With the topology also the wound vertices (woundVertices); the field's folds need it when its
/// framePositions were released (facesFoldedIn3D).
/// flippedFaces (when given) receives the flipped faces, increasing.
MapQuality measureMap(const TriangleMesh& mesh, const WedgeMap& cornerUV,
                      const CrossField* field, double edgeLength,
                      const std::vector<VertexId>* cones = nullptr, const Topology* topology = nullptr,
                      std::vector<FaceId>* flippedFaces = nullptr);

/// measureMap with a given h for a mesh read face by face (out of core): the same per-face terms,
/// summed in the order given. The caller counts collapsedAtCones and flippedFolded by the kind
/// add() returns.
class MapQualitySums {
 public:
  enum class Kind { Fine, Collapsed, Flipped };
  explicit MapQualitySums(double edgeLength) : h_(edgeLength) {}
  /// A face's corner positions and values and its field direction (null: no field).
  Kind add(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q, const Vec3d* direction);
  void countCollapsedAtCones() { ++out_.collapsedAtCones; }
  void countFolded() { ++out_.flippedFolded; }
  /// Adds the sums of other faces (of the same h).
  void merge(const MapQualitySums& other);
  MapQuality finish() const;

 private:
  double h_;
  double error_ = 0.0, target_ = 0.0;
  bool hasField_ = false;
  MapQuality out_;
};

}  // namespace seamvox
