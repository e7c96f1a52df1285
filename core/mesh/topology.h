#pragma once
/// Corner table of a manifold triangle mesh.
///
/// CONVENTIONS (the one place they are written; everything else refers here):
/// * Corner c = 3 f + k lies in face f = c / 3 at vertex triangles[f][k].
///   next(c) = the following corner of the same face (counter-clockwise), prev(c) the preceding.
/// * Corner c names the edge opposite to it, directed as its face traverses it:
///   from vertex(next(c)) to vertex(prev(c)). The face of c lies on the LEFT of that directed
///   edge (faces are counter-clockwise seen from the side their normal points to).
/// * opposite(c) is the corner of the neighbouring face across that edge (which traverses it in
///   the other direction), or kInvalidId when the edge is on the boundary.
///   An undirected edge is named by its smaller corner: edgeCorner = min(c, opposite(c)).
/// * Around a vertex, ccw(c) = next(opposite(next(c))) is the corner at the same vertex in the
///   next face counter-clockwise; cw(c) = prev(opposite(prev(c))). Either is kInvalidId when it
///   would cross the boundary. vertexCorner(v) is the most clockwise corner at v (its cw() is
///   invalid) for boundary vertices, any corner for interior ones, so walking ccw() from it
///   visits the whole fan of v exactly once.
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"

namespace seamvox {

inline CornerId nextCorner(CornerId c) { return c % 3 == 2 ? c - 2 : c + 1; }
inline CornerId prevCorner(CornerId c) { return c % 3 == 0 ? c + 2 : c - 1; }

/// Calls f(corner) from start (none when kInvalidId) counter-clockwise through table.ccw until
/// the fan closes or ends: the fan walk of Topology and of the out-of-core corner table.
template <class Table, class F>
void walkCornersAround(Table& table, CornerId start, F&& f) {
  if (start == kInvalidId) return;
  CornerId c = start;
  do {
    f(c);
    c = table.ccw(c);
  } while (c != kInvalidId && c != start);
}

inline FaceId cornerFace(CornerId c) { return c / 3; }

/// Read-only view of a triangle array (what Topology::triangles() returns).
class TriangleSpan {
 public:
  TriangleSpan(const Triangle* data, std::size_t size) : data_(data), size_(size) {}
  const Triangle& operator[](std::size_t f) const { return data_[f]; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const Triangle* begin() const { return data_; }
  const Triangle* end() const { return data_ + size_; }
  const Triangle* data() const { return data_; }

 private:
  const Triangle* data_;
  std::size_t size_;
};

/// Immutable corner table. Requires an edge- and vertex-manifold, consistently oriented mesh
/// without degenerate faces (cleanMesh produces one). About 16 bytes per face plus the triangles.
class Topology {
 public:
  Topology() = default;
  /// Builds the table in parallel. Throws TopologyError naming the face when the input is not
  /// manifold (an edge shared by more than two faces or twice in the same direction, a vertex
  /// whose faces form more than one fan) or has an index >= numVertices.
  static Topology build(std::vector<Triangle> triangles, std::uint32_t numVertices);
  /// Adopts an already computed table (as cleanMesh produces). Trusted: no checks beyond sizes;
  /// call validate() when unsure.
  static Topology fromParts(std::vector<Triangle> triangles, std::vector<CornerId> opposite,
                            std::vector<CornerId> vertexCorner);
  /// Like fromParts, but views the triangles instead of owning a copy (saves 12 bytes per face on
  /// massive meshes). The vector's buffer must outlive the Topology and must not be resized;
  /// moving the vector keeps the buffer (cleanMesh uses this for CleanResult::mesh.triangles).
  static Topology viewParts(const std::vector<Triangle>& triangles, std::vector<CornerId> opposite,
                            std::vector<CornerId> vertexCorner);
  Topology(const Topology& other);
  Topology& operator=(const Topology& other);
  Topology(Topology&&) = default;
  Topology& operator=(Topology&&) = default;

  std::uint32_t numVertices() const { return static_cast<std::uint32_t>(vertexCorner_.size()); }
  std::uint32_t numFaces() const { return numFaces_; }
  std::uint32_t numCorners() const { return 3 * numFaces(); }
  TriangleSpan triangles() const { return {tris_, numFaces_}; }

  VertexId vertex(CornerId c) const { return tris_[c / 3][c % 3]; }
  CornerId opposite(CornerId c) const { return opposite_[c]; }
  bool isBoundaryEdge(CornerId c) const { return opposite_[c] == kInvalidId; }
  /// Start corner of the fan of v (see conventions); kInvalidId for an isolated vertex.
  CornerId vertexCorner(VertexId v) const { return vertexCorner_[v]; }
  bool isBoundaryVertex(VertexId v) const {
    const CornerId c = vertexCorner_[v];
    return c != kInvalidId && cw(c) == kInvalidId;
  }
  bool isIsolatedVertex(VertexId v) const { return vertexCorner_[v] == kInvalidId; }
  CornerId ccw(CornerId c) const {
    CornerId o = opposite_[nextCorner(c)];
    return o == kInvalidId ? kInvalidId : nextCorner(o);
  }
  CornerId cw(CornerId c) const {
    CornerId o = opposite_[prevCorner(c)];
    return o == kInvalidId ? kInvalidId : prevCorner(o);
  }
  /// Calls f(corner) for every corner at v, counter-clockwise starting at vertexCorner(v).
  template <class F>
  void forEachCornerAround(VertexId v, F&& f) const {
    walkCornersAround(*this, vertexCorner_[v], f);
  }
  /// Number of faces incident to v.
  std::uint32_t valence(VertexId v) const;

  /// Faces appended in place: `triangles` holds this table's faces unchanged, then new ones (the
  /// table views it, or owns a copy when it owned its faces), `numVertices` counts new vertices
  /// too, and each pair in `glued` joins two corners' edges (one of them at least new). The fan
  /// starts of the vertices of the new faces are found as build() finds them. Returns the old
  /// fan starts of the old vertices among them, for shrink().
  std::vector<std::pair<VertexId, CornerId>> extend(const std::vector<Triangle>& triangles, std::uint32_t numVertices,
                                                    const std::vector<std::pair<CornerId, CornerId>>& glued);
  /// Undoes extend(): keeps the first `faces` faces of `triangles` (its first faces unchanged) and
  /// the first `vertices` vertices, opens the edges glued to dropped corners and gives `starts`
  /// back. The table then equals the one before extend().
  void shrink(const std::vector<Triangle>& triangles, std::uint32_t faces, std::uint32_t vertices,
              const std::vector<std::pair<VertexId, CornerId>>& starts);

  /// Checks every invariant (opposite is an involution between corners of different faces that
  /// share the edge reversed, fans, vertexCorner). Throws TopologyError with the first failure.
  void validate() const;

  /// Bytes held by the table (for memory reports).
  std::size_t memoryBytes() const;

 private:
  std::vector<Triangle> owned_;  // empty when viewing another array
  const Triangle* tris_ = nullptr;
  std::uint32_t numFaces_ = 0;
  std::vector<CornerId> opposite_;      // 3 #F
  std::vector<CornerId> vertexCorner_;  // #V
};

/// The boundary corner after boundary corner c along its loop (c's edge runs vertex(next c) ->
/// vertex(prev c) with the face on the left): turns clockwise around vertex(prev c), appending
/// the corner of every interior edge it crosses (in the face it leaves) to crossed when given.
CornerId nextBoundaryCorner(const Topology& topology, CornerId c, std::vector<CornerId>* crossed = nullptr);

/// Connected components (through shared edges) with their topological figures.
struct ComponentInfo {
  std::uint32_t faces = 0;
  std::uint32_t vertices = 0;
  std::uint64_t edges = 0;
  std::uint32_t boundaryLoops = 0;
  std::int64_t eulerCharacteristic = 0;  ///< V - E + F
  /// (2 - chi - b) / 2 for an orientable surface with b boundary loops.
  std::int64_t genus = 0;
};
struct ComponentsResult {
  std::vector<std::uint32_t> faceComponent;  ///< #F, component id per face
  std::vector<ComponentInfo> components;      ///< sorted by decreasing face count
  std::uint32_t boundaryLoops = 0;            ///< over all components
};
/// Components, boundary loops, Euler characteristic and genus. Linear time.
ComponentsResult computeComponents(const Topology& topology);

}  // namespace seamvox
