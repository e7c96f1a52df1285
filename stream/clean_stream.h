#pragma once
/// The cleaning stage of the out-of-core param, after the weld pass (welded_scratch): the
/// unreferenced vertices dropped, each component's faces oriented, the edges glued as cleanMesh
/// glues them (edges of more than two faces paired, orientation clashes left open) and every
/// fan of a vertex beyond its first given a copy of it; the cleaned faces, their corner table
/// and the vertices written to the scratch folder by external sorts of edge and corner records.
/// Equal to cleanMesh on the weld pass's faces in the weld pass's (Morton) order, their vertices numbered
/// in the order the faces first name them (a vertex near its faces in the files). Memory: the
/// sorts' limit, 4 bytes per welded vertex while ids are renumbered, 4 per boundary vertex (open
/// fans), and only when the input needs them, the union-finds of the orientation and of the
/// pieces of edges shared by more than two faces (4 bytes per face) and 1 byte per face for the
/// flips, each on disk beyond its share. The spike count walks the fans through page caches.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "stream/scratch_folder.h"
#include "stream/welded_scratch.h"

namespace seamvox {

/// A face of the cleaned mesh (16 bytes).
struct CleanFace {
  Triangle triangle{};         ///< cleaned vertex ids, oriented
  std::uint32_t inputFace = 0;  ///< in the input stream
};

/// The cleaned mesh in the scratch folder, faces in the weld pass's order.
struct CleanScratch {
  ScratchFile faces;         ///< CleanFace per face
  ScratchFile opposite;      ///< CornerId per corner (kInvalidId on a boundary)
  ScratchFile vertexCorner;  ///< CornerId per vertex: the start of its fan, as Topology::build picks it
  ScratchFile positions;     ///< Vec3f per vertex; the copies of split vertices after the others
  ScratchFile vertexOrigin;  ///< input vertex id per vertex
  std::uint64_t numFaces = 0, numVertices = 0;
  Vec3d origin = Vec3d::Zero();  ///< TriangleMesh::origin of the positions
  /// cleanMesh's counts: welded, degenerate, duplicate and unreferenced from the weld pass, then
  /// non-manifold edges and vertices and flipped faces (the others 0 for now).
  CleanReport report;
  bool setsOnDisk = false;  ///< a per-face union-find or the flips did not fit its share of the memory
  /// How the edges were glued: "front", or "sorts" and why the front pass did not run or stopped.
  std::string gluing;
  std::uint64_t largestFront = 0;  ///< the front pass's open vertices at most
  std::uint64_t frontLateValues = 0;  ///< its values patched in place (set after their window was written)
  /// The islands (core/basis/islands.h) of at most CleanStreamOptions::islandFaces faces, found
  /// beside the front pass when it split no fan; else none (scratchIslandFaces finds them).
  std::optional<std::vector<FaceId>> islands;
  /// Wall seconds of the passes: vertices, faces, front, glue, fans, write, measure.
  std::vector<std::pair<std::string, double>> stageSeconds;
};

struct CleanStreamOptions {
  std::uint64_t memoryBytes = std::uint64_t(1) << 30;
  bool renumberBySorts = false;  ///< vertex ids renumbered by four sorts even when they fit (tests)
  bool setsOnDisk = false;       ///< the per-face union-finds and flips on disk always (tests)
  bool gluingBySorts = false;    ///< the gluing and fans by sorts, without the front pass (tests)
  std::size_t frontWindow = std::size_t(1) << 20;  ///< the front pass's in-order window (tests: small)
  std::uint64_t frontBytes = 0;  ///< the front pass's open front (0: a quarter of memoryBytes; tests: small)
  std::uint32_t islandFaces = 0;  ///< > 0: the islands of at most this many faces beside the front pass
  std::uint64_t spikeBlock = std::uint64_t(1) << 16;  ///< vertices per block of the spikes' walk (tests: small)
};

/// Cleans the weld pass's output (kept in folder) into folder within options.memoryBytes. The
/// vertices are renumbered in memory (4 B per welded vertex) while that fits a quarter of the
/// memory, else by four sorts. The edges are glued and the fans split in one pass along the faces'
/// front (stream/clean_front: 8 B per vertex while that fits a quarter of the memory) when the
/// mesh has no edge of more than two faces and no orientation clash, else by sorts of edge sides
/// and corners. The per-face union-finds and flips go on disk beyond their shares. Throws IoError
/// (scratch, a full disk) naming the folder.
CleanScratch cleanWeldedMesh(ScratchFolder& folder, const WeldedScratch& welded, const WeldCensus& census,
                             const CleanStreamOptions& options);

/// The cleaned mesh's components as computeComponents gives them (joined through glued edges, by
/// decreasing face count, ties in the order of their first faces; faceComponent left empty),
/// streamed from the scratch. Memory: the union-finds of the faces and of the boundary vertices
/// (4 bytes each) within half and a quarter of memoryBytes, on disk beyond; about 40 bytes per
/// component.
ComponentsResult cleanedComponents(ScratchFolder& folder, const CleanScratch& scratch, std::uint64_t memoryBytes);

/// islandFaces (core/basis/islands.h) of the cleaned mesh: one pass over the glued edges into a
/// union-find of the faces (within half of memoryBytes, on disk beyond) and counts at the roots
/// (a quarter). Memory: those and 4 bytes per island face.
std::vector<FaceId> scratchIslandFaces(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t maxFaces,
                                       std::uint64_t memoryBytes);

/// The bounding box of a file of Vec3f positions (a cleaned mesh's, or its smoothed surface),
/// read in order; its bytes counted under stage. IoError when the file ends inside a record.
BoundingBox scratchBoundingBox(ScratchFolder& folder, const ScratchFile& positions, const std::string& stage);

/// The scratch read back whole, as cleanMesh returns its result (faceOrigin: input faces).
CleanResult readCleanScratch(ScratchFolder& folder, const CleanScratch& scratch);

}  // namespace seamvox
