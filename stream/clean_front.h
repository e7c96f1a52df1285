#pragma once
/// The out-of-core cleaning's gluing and fan splitting in one pass over the faces, for faces in an
/// order where each vertex's faces lie close together (the weld pass's Morton order) and vertices
/// numbered in the order the faces first name them. An edge is complete once the first of its two
/// vertices has met its last face, a vertex's fans once the vertex has: only the open front of
/// vertices and edges is held, not a sort of every edge side and corner. Meshes it does not cover
/// (an edge of more than two faces, two faces meeting in one direction, a front over its memory)
/// are left to the sorts (stream/clean_stream), which give the same result on every mesh.
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "stream/scratch_folder.h"

namespace seamvox::detail {

/// A corner at its vertex with the corner clockwise of it around the vertex (kInvalidId across a
/// boundary edge).
struct CornerAround {
  VertexId vertex;
  CornerId corner, clockwise;
};

/// A fan's start as Topology::build picks it (the most clockwise corner of an open fan, else the
/// largest corner of a vertex's only fan or the smallest of one of several) and whether it is open.
struct FanStart {
  CornerId start;
  bool open;
};

/// The fans of one vertex's corners (group, sorted by corner): fanOf[i] is group[i]'s fan, the fans
/// numbered in the order of their smallest corners, starts[k] fan k's start. root: room reused.
void findFans(const std::vector<CornerAround>& group, std::vector<std::uint32_t>& root,
              std::vector<std::uint32_t>& fanOf, std::vector<FanStart>& starts);

struct FrontGlueOptions {
  std::uint64_t memoryBytes = std::uint64_t(64) << 20;  ///< the open front and the late values
  std::size_t windowValues = std::size_t(1) << 20;       ///< values held for in-order writing (tests: small)
};

/// A fan of a vertex beyond its first: it becomes a copy of the vertex.
struct FanCopy {
  VertexId vertex;
  std::uint32_t fan;  ///< of the vertex's fans, in the order of their smallest corners (1, 2, ...)
  FanStart start;
  std::vector<CornerId> corners;
};

struct FrontGlueResult {
  bool glued = false;  ///< false: nothing kept, why says what the pass met
  std::string why;
  ScratchFile opposite;                ///< CornerId per corner (kInvalidId on a boundary)
  ScratchFile vertexCorner;            ///< the first fan's start per vertex (the copies' not yet)
  std::vector<VertexId> boundary;      ///< vertices whose first fan is open, increasing
  std::vector<FanCopy> copies;         ///< by vertex, then fan
  std::uint64_t nonManifoldVertices = 0;
  std::uint64_t largestFront = 0;      ///< open vertices at most
  std::uint64_t lateValues = 0;        ///< values set after their window was written (patched in place)
};

/// One pass over faces (CleanFace records, numFaces of them, on numVertices vertices, none
/// degenerate; lastFace[v]: the last face naming v). Edges of one side are boundary, of two
/// opposite sides glued. Memory: 4 bytes per vertex, the windows and the front within
/// options.memoryBytes. Throws IoError on scratch failures, as the sorts do.
FrontGlueResult glueAlongFront(ScratchFolder& folder, const ScratchFile& faces, std::uint64_t numFaces,
                               std::uint64_t numVertices, const std::vector<FaceId>& lastFace,
                               const FrontGlueOptions& options);

}  // namespace seamvox::detail
