#pragma once
/// The map (u, v) at the corners of a mesh, stored once per wedge: a set of corners of one vertex
/// that share one value (interior vertices away from seams have a single wedge). A 32-bit wedge
/// id per corner plus one double pair per wedge: about 20 bytes per face instead of 48; or, over
/// the mesh's own triangles (viewTriangles), one wedge id per vertex and the few corners of
/// another wedge listed: about 10 bytes per face.
#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/mesh/mesh_types.h"

namespace seamvox {

class Topology;

class WedgeMap {
 public:
  WedgeMap() = default;
  /// Adopts a wedge structure: cornerWedge[c] < wedgeValues.size() for every corner (checked,
  /// InputError otherwise).
  WedgeMap(std::vector<std::uint32_t> cornerWedge, std::vector<Vec2d> wedgeValues);
  /// A copy holds its wedge ids per corner (a copied mesh has triangles of its own to view).
  WedgeMap(const WedgeMap& other);
  WedgeMap& operator=(const WedgeMap& other);
  WedgeMap(WedgeMap&&) noexcept = default;
  WedgeMap& operator=(WedgeMap&&) noexcept = default;
  /// A map over triangles[0 .. #corners / 3): per vertex the wedge of its corners, except the
  /// corners listed in `other` (corner, wedge; a vertex with several wedges). Views the triangles
  /// as Topology::viewParts does: their buffer must outlive the map and keep its faces (moving
  /// the vector keeps the buffer); copies and corner-table edits go back to ids per corner.
  /// Throws InputError on an id out of range.
  static WedgeMap overTriangles(const Triangle* triangles, std::size_t corners, std::vector<std::uint32_t> vertexWedge,
                                const std::vector<std::pair<CornerId, std::uint32_t>>& other,
                                std::vector<Vec2d> wedgeValues);
  /// Keeps the wedge ids per vertex over `triangles` (the faces of this map's corners) instead of
  /// per corner, as overTriangles, when that holds fewer bytes; returns whether it does.
  bool viewTriangles(const Triangle* triangles, std::uint32_t numVertices);
  bool viewsTriangles() const { return tris_ != nullptr; }
  /// Per-corner values (3 #F, corner c = 3 f + k at triangles[f][k]); corners of one vertex with
  /// exactly equal values share a wedge. Throws InputError on mismatched sizes or a bad vertex.
  static WedgeMap fromCorners(const std::vector<Triangle>& triangles, const std::vector<Vec2d>& values);

  std::size_t size() const { return tris_ ? corners_ : wedge_.size(); }  ///< number of corners
  bool empty() const { return size() == 0; }
  std::uint32_t numWedges() const { return static_cast<std::uint32_t>(value_.size()); }
  /// Value of corner c (by value: corners do not own storage).
  Vec2d operator[](CornerId c) const { return value_[wedge(c)]; }
  std::uint32_t wedge(CornerId c) const {
    if (!tris_) return wedge_[c];
    const std::uint32_t w = vertexWedge_[tris_[c]];
    return (w & kListed) ? listedWedge(c, w & ~kListed) : w;
  }
  const Vec2d& wedgeValue(std::uint32_t w) const { return value_[w]; }
  /// Sets the value of every corner of wedge w.
  void setWedgeValue(std::uint32_t w, const Vec2d& q) { value_[w] = q; }
  /// The smallest corner of each wedge in [begin, end) (kInvalidId for a wedge without corners),
  /// indexed from begin. One pass over the corners: a caller short of memory takes a range at a time.
  std::vector<CornerId> wedgeCorners(std::uint32_t begin = 0, std::uint32_t end = UINT32_MAX) const;

  /// Sets one corner: a no-op when the value is unchanged, else c moves to a new wedge of its own
  /// (its old wedge may be left without corners). For many corners use assign().
  void set(CornerId c, const Vec2d& q);
  /// Sets corners[k] to values[k]. A wedge whose corners all get one value keeps its id and only
  /// changes value; a wedge only part of whose corners change is split (one new wedge per new
  /// value). One pass over the wedge ids of all corners. Throws InputError on a bad corner or sizes.
  void assign(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values);
  /// The same, counting each touched wedge's corners around its vertex in `topology` (the map's
  /// mesh: a wedge's corners share one vertex) instead of over all corners: for many small
  /// assignments on a large map. Throws InputError when the topology's corners are not the map's.
  void assign(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values, const Topology& topology);

  /// Corner-table edits (cleaning): corner `to` takes the wedge of corner `from`; swap two corners'
  /// wedges; keep the first n corners.
  void copyCorner(CornerId to, CornerId from) {
    perCorner();
    wedge_[to] = wedge_[from];
  }
  void swapCorners(CornerId a, CornerId b) {
    perCorner();
    std::swap(wedge_[a], wedge_[b]);
  }
  void resizeCorners(std::size_t n);
  /// Keeps the first n corners (no copy of the array) and drops the wedges left without corners.
  void keepCorners(std::size_t n);
  void clear();
  /// Bytes held (for memory reports).
  std::size_t memoryBytes() const;

 private:
  friend class WedgeMapBuilder;
  static constexpr std::uint32_t kListed = 0x80000000u;  // in vertexWedge_: some corner is in listed_
  // A listed corner holds about ten times a corner's id: worth it only while few corners are.
  static std::size_t maxListed(std::size_t corners) { return corners / 16 + 1024; }
  std::uint32_t listedWedge(CornerId c, std::uint32_t vertexWedge) const {
    const auto it = listed_.find(c);
    return it == listed_.end() ? vertexWedge : it->second;
  }
  void setCornerWedge(CornerId c, std::uint32_t w);
  /// assign(), counting the touched wedges' corners around their vertices in topology when given,
  /// else over all corners.
  void assignCounted(const std::vector<CornerId>& corners, const std::vector<Vec2d>& values, const Topology* topology);
  /// Back to one wedge id per corner (the triangles viewed are read once more).
  void perCorner();
  std::vector<std::uint32_t> wedge_;  // #corners (empty when viewing triangles)
  std::vector<Vec2d> value_;          // #wedges
  // Viewing triangles: corners_ corners over tris_, the wedge of a corner that of its vertex
  // (vertexWedge_, kListed set when some corner of the vertex is listed) unless listed_ has it.
  // The triangles' vertex ids corner after corner (a triangle is three ids, no padding): one load
  // per corner instead of a division by 3.
  static_assert(sizeof(Triangle) == 3 * sizeof(VertexId), "triangles read as corner after corner");
  const VertexId* tris_ = nullptr;
  std::size_t corners_ = 0;
  std::vector<std::uint32_t> vertexWedge_;
  std::unordered_map<CornerId, std::uint32_t> listed_;
};

/// Throws InputError saying `what` needs `corners` corners unless the map has exactly that many.
void checkCorners(const WedgeMap& map, std::size_t corners, const std::string& what);

/// Builds a WedgeMap corner after corner (readers, streams): a corner joins a wedge of its vertex
/// with exactly the same value (searched among the vertex's first kMaxSearch wedges), else starts
/// one. Holds 4 bytes per vertex and per wedge besides the map until finish().
class WedgeMapBuilder {
 public:
  static constexpr int kMaxSearch = 64;
  void reserve(std::size_t corners);
  /// Appends the next corner (id = corners added so far), at vertex v with value q; v = kInvalidId
  /// (vertex not known yet) gives the corner a wedge of its own.
  void add(VertexId v, const Vec2d& q);
  std::size_t size() const { return map_.wedge_.size(); }
  /// The map; the builder is empty afterwards.
  WedgeMap finish();

 private:
  WedgeMap map_;
  std::vector<std::uint32_t> vertexWedge_;  // latest wedge of each vertex
  std::vector<std::uint32_t> nextWedge_;    // earlier wedge of the same vertex
};

}  // namespace seamvox
