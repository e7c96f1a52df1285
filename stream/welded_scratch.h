#pragma once
/// The weld pass of the out-of-core stages: a mesh stream is read once and, by external sorts in a
/// scratch folder, welded (optional: exactly equal positions, as cleanMesh welds with tolerance 0),
/// cleaned of degenerate and duplicate faces as cleanMesh cleans them, and measured (edges by
/// their two vertices, components by union-find, boundary loops, bounding box). Its output, the
/// welded triangles sorted by the Morton code of their centroid (a spatially coherent order; 24
/// bytes each, the positions apart) and the welded positions, stays in the scratch folder for the next
/// streamed stage (WeldedFaceReader). Memory: the sorts' limit, plus the weld map (4 bytes per
/// input vertex while faces are renumbered) and the union-finds of the components and boundary loops
/// (4 bytes per vertex, the loops' a map of the boundary vertices while it is small), each
/// within a quarter of the limit, beyond it on disk through page caches; about 110 bytes per
/// component; the welded positions (12 bytes per vertex) read whole when they fit, else joined
/// with the corners by sorts.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/morton.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// A face of the weld pass's output (64 bytes).
struct WeldedFace {
  std::uint64_t morton = 0;  ///< of the centroid on a 2^21 grid over the bounding box
  std::uint32_t face = 0;    ///< index in the input stream
  Triangle triangle{};       ///< welded vertex ids, the input's corner order
};
static_assert(sizeof(WeldedFace) == 24, "the Morton sort's records");

struct WeldStreamOptions {
  bool weld = false;  ///< join vertices at exactly equal positions (the lowest input id keeps its place first); always for a stream of corner vertices (STL)
  /// For the sorts (each of the up to three alive: a third) and the positions when they fit half.
  std::uint64_t memoryBytes = std::uint64_t(256) << 20;
  /// Tests: join the positions by sorts even when they fit.
  bool joinPositions = false;
  /// Tests: the weld map and the union-finds of the components and boundary loops on disk even
  /// when they fit.
  bool setsOnDisk = false;
  /// The census of edges, components and boundary loops (WeldCensus: edges to components,
  /// setsOnDisk), which `info` prints. Without it (param) the weld skips their edge sort, union-
  /// find and per-component counts; those fields stay 0 and empty.
  bool census = true;
};

/// What the weld pass found: the figures `seamvox info` prints, out of core.
struct WeldCensus {
  std::uint64_t inputVertices = 0, inputFaces = 0;
  std::uint64_t weldedVertices = 0, degenerateFaces = 0, duplicateFaces = 0, unreferencedVertices = 0;
  std::uint64_t zeroAreaFaces = 0;  ///< area <= 1e-14 diagonal^2, as cleanMesh counts them
  std::uint64_t vertices = 0, faces = 0;  ///< welded and referenced; kept
  /// Edges by their faces: one (boundary), two in opposite directions (manifold), two in the same
  /// direction (orientation clash), more than two (non-manifold).
  std::uint64_t edges = 0, boundaryEdges = 0, manifoldEdges = 0, clashEdges = 0, nonManifoldEdges = 0;
  std::uint32_t boundaryLoops = 0;
  bool setsOnDisk = false;  ///< the components' or the loops' union-find did not fit its share
  /// Connected through shared vertices (cleanMesh splits non-manifold vertices and edges first:
  /// equal on meshes without them); by decreasing face count, then vertices.
  std::vector<ComponentInfo> components;
  BoundingBox box;              ///< of the positions, about origin
  Vec3d origin = Vec3d::Zero();  ///< TriangleMesh::origin of the stream's positions
  VertexAttributes properties;  ///< names and types of the vertex properties read
  /// Wall seconds of the passes: read, weld, faces, duplicates, edges, positions, morton, components.
  std::vector<std::pair<std::string, double>> stageSeconds;
};

/// cleanMesh's counts the weld pass already knows (input, welded, degenerate, duplicate and
/// unreferenced); the others 0.
CleanReport weldCleanReport(const WeldCensus& census);

/// The weld pass's output files in the scratch folder.
struct WeldedScratch {
  ScratchFile faces;      ///< WeldedFace records in Morton order
  ScratchFile positions;  ///< Vec3f per welded vertex id
  std::uint64_t numFaces = 0, numVertices = 0;
};

struct WeldStreamResult {
  WeldCensus census;
  WeldedScratch scratch;
};

/// Runs the weld pass on a stream (scratch files in folder, kept there for the caller). Throws
/// InputError (indices out of range, non-finite coordinates, no valid faces) and IoError
/// (scratch, a full disk) naming the stream or the folder.
WeldStreamResult weldMeshStream(MeshStream& stream, ScratchFolder& folder, const WeldStreamOptions& options);

/// Hands out the faces of a WeldedScratch in Morton order, in chunks.
class WeldedFaceReader {
 public:
  WeldedFaceReader(ScratchFolder& folder, const WeldedScratch& scratch, std::string stage = "read welded");
  /// Fills chunk (cleared first) with at most count faces; false at the end.
  bool next(std::vector<WeldedFace>& chunk, std::size_t count);

 private:
  ScratchReader reader_;
};

}  // namespace seamvox
