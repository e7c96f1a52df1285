#pragma once
/// Small holes capped for the solve: a cross field is free to turn at a hole's boundary, so it
/// puts singularities inside small holes (a full turn, index -4, leaves the map wound twice around
/// the hole), and the rounding leaves translations around them. Solved on a copy with those holes
/// capped by fans (PipelineOptions::closeHoles; the caps are dropped from the output), the field
/// turns only where the surface's shape asks it to and the map closes over every capped hole,
/// also two holes that touched at a vertex (split by cleaning).
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// The caps appended to a mesh, and what uncapHoles needs to take them off again.
struct CappedHoles {
  std::uint32_t holes = 0;
  std::uint32_t faces = 0, vertices = 0;  ///< the mesh's own, before the caps
  std::vector<std::pair<VertexId, CornerId>> fanStarts;  ///< of the rim vertices, before the caps
};

/// Caps every boundary loop through distinct vertices (at most 64 edges) whose vertices fit in a
/// box of diagonal maxExtent, in a component more than four times that size across (not an
/// island's own outline), with a fan from a new vertex at its centroid when no fan face is
/// degenerate. In place: the centres are appended to the positions, the fans to the faces, and
/// the corner table is extended (no copy of the mesh; the original faces and vertices keep their
/// ids). Linear.
CappedHoles capSmallHoles(TriangleMesh& mesh, Topology& topology, double maxExtent);

/// Takes the caps off again: the mesh and its corner table as they were before capSmallHoles.
void uncapHoles(TriangleMesh& mesh, Topology& topology, const CappedHoles& caps);

}  // namespace seamvox
