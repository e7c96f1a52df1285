#pragma once
/// Cleaning a raw scan into a manifold, consistently oriented mesh ready for Topology::build.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// Smallest mesh cleanMesh puts in spatial order by default: below it the arrays mostly stay in
/// cache anyway.
constexpr std::uint32_t kReorderMinFaces = 1u << 19;

struct CleanOptions {
  /// Weld vertices whose positions coincide within this distance (0 = exactly equal positions).
  bool weldVertices = false;
  double weldTolerance = 0.0;
  /// A mesh of at least this many faces whose order is scattered is put in spatial order
  /// (CleanReport::reordered), or its vertices alone renumbered when only their ids are scattered
  /// (CleanReport::verticesRenumbered); UINT32_MAX keeps every input's order.
  std::uint32_t reorderMinFaces = kReorderMinFaces;
  ProgressFn progress;
};

/// What cleanMesh changed, in counts of input elements.
struct CleanReport {
  std::uint64_t inputVertices = 0, inputFaces = 0;
  std::uint64_t weldedVertices = 0;        ///< vertices merged into another
  std::uint64_t degenerateFaces = 0;       ///< removed: a repeated vertex
  std::uint64_t duplicateFaces = 0;        ///< removed: same vertex set as an earlier face
  std::uint64_t zeroAreaFaces = 0;         ///< kept (removing them would open holes), counted
  std::uint64_t unreferencedVertices = 0;  ///< removed
  std::uint64_t nonManifoldEdges = 0;      ///< edges split apart (> 2 faces, or orientation clash)
  std::uint64_t nonManifoldVertices = 0;   ///< vertices duplicated, one copy per extra fan
  std::uint64_t flippedFaces = 0;          ///< faces reoriented to agree with their component
  /// Kept, counted: boundary vertices at exactly the position of another boundary vertex that
  /// does not come from the same input vertex (a crack left unwelded; welding joins them).
  std::uint64_t unweldedBoundaryVertices = 0;
  /// Kept, counted: vertices whose every edge is over kSpikeRatio times longer than the typical
  /// edge around their neighbours (an outlier pulled far out of the surface: needle faces).
  std::uint64_t spikeVertices = 0;
  /// Bounding-box diagonal of the output without its spike vertices (the mesh's own extent).
  double diagonalWithoutSpikes = 0.0;
  std::uint64_t outputVertices = 0, outputFaces = 0;
  /// Vertices and faces were put in spatial order (the input's was scattered): the output's order
  /// differs from the input's (vertexOrigin and faceOrigin map back).
  bool reordered = false;
  /// Only the vertices were renumbered, in the order the faces first use them (the faces were in
  /// order, the vertex ids scattered, as in a subdivided mesh): vertexOrigin maps back.
  bool verticesRenumbered = false;
};


/// A vertex is a spike when its shortest edge is this many times the median, over its
/// neighbours, of their median edge length.
constexpr double kSpikeRatio = 10.0;

/// Move-only: topology views mesh.triangles (no second copy of the faces).
struct CleanResult {
  CleanResult() = default;
  CleanResult(CleanResult&&) = default;
  CleanResult& operator=(CleanResult&&) = default;
  CleanResult(const CleanResult&) = delete;
  CleanResult& operator=(const CleanResult&) = delete;

  /// Cleaned positions and triangles; cornerUV and vertex attributes carried along (a welded
  /// vertex keeps the attribute values of the lowest-numbered vertex of its cluster, whose
  /// position it keeps; the copies of a split vertex keep its values).
  TriangleMesh mesh;
  Topology topology;  ///< corner table of mesh.triangles
  CleanReport report;
  std::vector<FaceId> faceOrigin;      ///< #F out: the input face each output face comes from
  std::vector<VertexId> vertexOrigin;  ///< #V out: the input vertex each output vertex comes from
  std::vector<VertexId> spikes;        ///< output vertices counted in report.spikeVertices
};

/// Spike vertices of a mesh (CleanReport::spikeVertices), increasing. Linear, parallel.
std::vector<VertexId> findSpikeVertices(const TriangleMesh& mesh, const Topology& topology);

/// Welds (optional), drops degenerate and duplicate faces and unreferenced vertices, orients
/// each component consistently where possible, splits non-manifold edges and vertices, and
/// builds the corner table. Consumes the input mesh. Linear memory; parallel where it pays.
CleanResult cleanMesh(TriangleMesh mesh, const CleanOptions& options = {});

}  // namespace seamvox
