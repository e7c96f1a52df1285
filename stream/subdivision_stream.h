#pragma once
/// The 1-to-4 midpoint subdivision of core/mesh/subdivide handed out in chunks, for outputs
/// larger than memory (`seamvox subdivide` above its budget): the same faces in the same order
/// (face g of the result lies in input face g >> (2 levels)), each with the same corner positions
/// and vertex properties, but the vertices numbered differently: the input's vertices, then per
/// input edge (in subdivideMesh's edge order) its 2^levels - 1 inner points from the start of its
/// owning corner's edge, then per input face its inner points. Every point is computed as
/// subdivideMesh computes it (level by level, each a midpoint rounded once to float, properties
/// by VertexAttributes::withMidpoints), inside its edge or face alone, so the two faces of an edge
/// agree. Memory: the input, and one face's (2^levels + 1) (2^levels + 2) / 2 points at a time.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "stream/mesh_stream.h"

namespace seamvox {

class SubdivisionStream {
 public:
  /// Throws TopologyError when topology does not belong to mesh or the result needs 32-bit ids
  /// beyond range (as subdivideMesh). Keeps references to mesh and topology.
  SubdivisionStream(const TriangleMesh& mesh, const Topology& topology, std::uint32_t levels);
  ~SubdivisionStream();
  std::uint64_t numVertices() const { return numVertices_; }
  std::uint64_t numFaces() const { return std::uint64_t(topology_.numFaces()) << (2 * levels_); }
  std::uint64_t numInputEdges() const { return numEdges_; }
  /// The next vertices (whole input vertices, edges or faces, about count of them) into
  /// chunk.positions and chunk.attributes (cleared first), chunk.firstVertex set; false when all
  /// were handed out.
  bool nextVertices(std::size_t count, MeshChunk& chunk);
  /// The next faces (whole input faces, about count of them) into chunk.triangles (cleared
  /// first), in subdivideMesh's order; false at the end.
  bool nextTriangles(std::size_t count, MeshChunk& chunk);

 private:
  struct Points;
  void subdivideFace(FaceId f, Points& points) const;
  void subdivideEdge(CornerId owner, Points& points) const;

  const TriangleMesh& mesh_;
  const Topology& topology_;
  std::uint32_t levels_ = 0, n_ = 1;
  std::vector<std::uint32_t> edgeOf_;  ///< per corner, subdivideMesh's edge number
  std::vector<CornerId> edgeOwner_;    ///< per edge, its owning corner (the smaller of the pair)
  std::uint64_t numEdges_ = 0, numVertices_ = 0, edgeBase_ = 0, faceBase_ = 0;
  std::uint64_t nextItem_ = 0;  ///< input vertices, then edges, then faces
  FaceId nextFace_ = 0;
};

}  // namespace seamvox
