#pragma once
/// Translation constraints that close small holes: walking around a boundary loop through the
/// faces at its vertices crosses seams; with no net rotation the crossings compose to
/// q -> q + T . t. T . t = 0 makes the map extendable over the hole (a hole smaller than a grid
/// cell can then be filled by the quad extraction); without it the rounding may leave T = (1, 1)
/// around a one-triangle hole, which no quad face can span.
#include <cstdint>
#include <vector>

#include "core/basis/gaussian_int.h"
#include "core/cut/cut.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct HoleLoopConstraints {
  std::vector<GaussVector> rows;  ///< T per closed loop (over seam ids), empty T left out
  std::uint32_t smallLoops = 0;   ///< boundary loops within the extent
  std::uint32_t rotatedLoops = 0; ///< of them, loops whose crossings compose to a rotation (left as they are)
};

/// Rows T . t = 0 for every boundary loop whose vertices fit in a box of diagonal at most
/// maxExtent (mesh units) and whose seam crossings compose to no rotation (cut.h conventions).
/// Linear in the boundary's corners plus the faces around it.
/// loopVertices (#V or null): only loops whose every vertex is flagged (e.g. the holes a
/// refinement region holds whole, not its border).
HoleLoopConstraints smallHoleConstraints(const TriangleMesh& mesh, const Topology& topology,
                                         const CutResult& cut, double maxExtent,
                                         const std::vector<std::uint8_t>* loopVertices = nullptr);

}  // namespace seamvox
