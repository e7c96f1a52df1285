#pragma once
/// Small holes capped for the solve: a cross field is free to turn at a hole's boundary, so it
/// puts singularities inside small holes (a full turn, index -4, leaves the map wound twice around
/// the hole), and the rounding leaves translations around them. Solved on a copy with those holes
/// capped by fans (PipelineOptions::closeHoles; the caps are dropped from the output), the field
/// turns only where the surface's shape asks it to and the map closes over every capped hole,
/// also two holes that touched at a vertex (split by cleaning).
#include <cstdint>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct CappedHoles {
  TriangleMesh mesh;      ///< the positions, then one centre per cap; the faces, then the caps' fans
  Topology topology;      ///< of mesh
  std::uint32_t holes = 0;
};

/// Caps every boundary loop through distinct vertices (at most 64 edges) whose vertices fit in a
/// box of diagonal maxExtent, in a component more than four times that size across (not an
/// island's own outline), with a fan from a new vertex at its centroid when no fan face is
/// degenerate; the original faces and vertices keep their ids. With no such hole, holes is 0 and
/// mesh is left empty. Linear.
CappedHoles capSmallHoles(const TriangleMesh& mesh, const Topology& topology, double maxExtent);

}  // namespace seamvox
