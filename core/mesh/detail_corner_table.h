#pragma once
/// Internal pieces shared by Topology::build and cleanMesh (not part of the public API).
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"

namespace seamvox::detail {

/// Corners grouped by vertex (CSR): corners of v are corners[offsets[v] .. offsets[v+1]).
struct VertexCorners {
  std::vector<std::uint32_t> offsets;  // #V + 1
  std::vector<CornerId> corners;       // 3 #F
  static VertexCorners build(const std::vector<Triangle>& triangles, std::uint32_t numVertices);
};

/// How many faces share each undirected edge, as seen from one corner.
struct EdgeMatch {
  std::uint32_t sameDirection = 0;      ///< faces traversing the edge like c's face (incl. it)
  std::uint32_t reverseDirection = 0;   ///< faces traversing it the other way
  CornerId reverseCorner = kInvalidId;  ///< the opposite corner in the last reverse face
  CornerId sameCorner = kInvalidId;     ///< the opposite corner in another same-direction face
  CornerId smallestCorner = kInvalidId; ///< smallest corner naming this edge in any face
  bool isManifold() const { return sameDirection == 1 && reverseDirection == 1; }
};
/// Looks up the faces around the edge of corner c through the corners of its start vertex.
EdgeMatch matchEdge(const std::vector<Triangle>& triangles, const VertexCorners& vc, CornerId c);

/// Glues every edge shared by exactly two oppositely oriented faces; all other edges become
/// boundary. Returns the number of non-manifold edges (shared by more than two faces) and of
/// orientation clashes (two faces in the same direction).
struct GlueStats {
  std::uint64_t nonManifoldEdges = 0;
  std::uint64_t orientationClashes = 0;
  CornerId firstProblem = kInvalidId;  ///< smallest corner on a non-glued interior edge
};
GlueStats glueEdges(const std::vector<Triangle>& triangles, const VertexCorners& vc,
                    std::vector<CornerId>& opposite);

/// Fans (maximal edge-connected corner sequences) at every vertex: the fans of v have start
/// corners fanStart[fanOffsets[v] .. fanOffsets[v+1]); each start is the most clockwise corner of
/// its fan (or any corner of a closed fan). Isolated vertices have none.
struct FanTable {
  std::vector<std::uint32_t> fanOffsets;  // #V + 1
  std::vector<CornerId> fanStart;
};
/// Needs only the triangles and opposite (the vertex-corner table can be freed before): fans
/// are walked from one corner per vertex; only vertices whose fan misses some of their corners
/// (non-manifold, rare) get a second, slower look.
FanTable findFans(const std::vector<Triangle>& triangles, std::uint32_t numVertices,
                  const std::vector<CornerId>& opposite);

/// Walks the fan starting at corner start counter-clockwise and calls f(corner) for each.
template <class F>
void walkFan(const std::vector<CornerId>& opposite, CornerId start, F&& f) {
  CornerId c = start;
  do {
    f(c);
    const CornerId o = opposite[c % 3 == 2 ? c - 2 : c + 1];
    if (o == kInvalidId) return;
    c = o % 3 == 2 ? o - 2 : o + 1;
  } while (c != start);
}

}  // namespace seamvox::detail
