#pragma once
/// Feature curves of a mesh (boundary curves and sharp creases) that the cross field follows and
/// the map places on integer iso-lines: which edges are features, their chains split at corners,
/// and whether a map keeps each curve on an integer iso-line.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/mesh/wedge_map.h"

namespace seamvox {

/// Default turn of a curve (degrees) that splits it: a sharper turn is a corner.
constexpr double kFeatureCornerDegrees = 45.0;

struct FeatureOptions {
  /// Boundary edges are features. Off by default: on the shared meshes aligned boundaries raised
  /// the gradient error 1.19x (camelhead) and 1.84x (lilium, whose smooth outline gets four field
  /// corners) and quad extraction fails to trace some iso-lines that run along the boundary
  /// (bench/RESULTS.md, feature curves).
  bool alignBoundary = false;
  /// Interior edges whose faces' normals differ by more than this (degrees) are creases; 0: none.
  /// For CAD-like meshes: on a scan every noisy fold would become a crease.
  double featureAngle = 0.0;
  /// With featureAngle 0: creases at kAutoFeatureAngle when the mesh looks like a CAD model's
  /// (looksLikeCad), none on a scan. param's default; the library's is off. The pipeline decides
  /// only where the direct field follows creases (up to kDirectFieldMaxFaces, no imported field).
  bool autoFeatureAngle = false;
  double cornerAngle = kFeatureCornerDegrees;  ///< turn (degrees) that splits a curve
  bool any() const { return alignBoundary || featureAngle > 0.0; }
};

/// Feature edges chained into curves. An edge is named by one of its corners (the boundary corner,
/// or the smaller of a crease's two); a curve runs from corner to corner (a vertex with other than
/// two feature edges, or a turn above cornerAngle) or is a closed loop without a corner.
struct FeatureSet {
  std::vector<CornerId> curveEdges;       ///< edges of all curves, each curve in chain order
  std::vector<std::uint32_t> curveStart;  ///< #curves + 1 offsets into curveEdges
  std::uint32_t boundaryEdges = 0, creaseEdges = 0;
  std::uint32_t numCurves() const { return curveStart.empty() ? 0 : std::uint32_t(curveStart.size() - 1); }
  bool empty() const { return curveEdges.empty(); }
};

/// Feature edges and curves of a mesh. Linear. (autoFeatureAngle is the caller's: resolveFeatureAngle.)
FeatureSet findFeatures(const TriangleMesh& mesh, const Topology& topology, const FeatureOptions& options);

/// The crease angle used when FeatureOptions::autoFeatureAngle finds a CAD-like mesh.
constexpr double kAutoFeatureAngle = 30.0;
/// Whether a mesh's creases at kAutoFeatureAngle look like a CAD model's: at least 24 crease edges
/// in curves of at least 6 edges on average. A scan's folds give curves of one or two edges (the
/// shared scans: 1.4 to 2.5 edges per curve at 30 degrees), a box 8 per side at 8 edges a side.
bool looksLikeCad(const FeatureSet& creases);
/// The options with autoFeatureAngle resolved: featureAngle kAutoFeatureAngle on a CAD-like mesh
/// (`chosen` then true), else unchanged. Costs one findFeatures when it applies.
FeatureOptions resolveFeatureAngle(const TriangleMesh& mesh, const Topology& topology, FeatureOptions options,
                                   bool& chosen);

/// The corners on either side of every feature edge (a crease gives two, a boundary edge one):
/// the faces the field is aligned in (SmoothFieldOptions::alignCorners). Sorted.
std::vector<CornerId> featureSideCorners(const Topology& topology, const FeatureSet& features);

/// How many curves a map keeps on integer iso-lines.
struct FeatureAlignment {
  std::uint32_t total = 0, aligned = 0, notAligned = 0;
  double largestResidual = 0.0;  ///< of the aligned curves' edges: |q - round(q)| and |dq| (<= tolerance)
};

/// A curve is aligned when, in every face along it, one coordinate of the map (u or v, either may
/// be the normal one, a seam may swap them) is the same integer at both ends of each edge within
/// `tolerance`. Reads cornerUV only.
FeatureAlignment measureFeatureAlignment(const Topology& topology, const FeatureSet& features,
                                         const WedgeMap& cornerUV, double tolerance = 1e-9);

}  // namespace seamvox
