#pragma once
/// Evaluation of the map at the corners of the cut mesh (DESIGN section 9, step 4).
#include <complex>
#include <vector>

#include "core/basis/basis.h"
#include "core/basis/reduce.h"
#include "core/mesh/wedge_map.h"

namespace seamvox {

/// The wedges of the cut mesh, values zero: the corners of a vertex between consecutive cut
/// edges (cut.h CutCorners::isCut, boundary included) form one wedge; a vertex without cut
/// edges has one.
/// Wedges are numbered vertex by vertex. Linear time, parallel; 4 bytes per vertex besides the map.
/// viewTriangles: the map keeps its wedge ids per vertex over the topology's triangles
/// (WedgeMap::overTriangles, 4 bytes per vertex instead of 12 per face), which must then outlive it
/// unchanged; the same wedges and ids either way.
WedgeMap buildCutWedges(const Topology& topology, const CutResult& cut, bool viewTriangles = false);

/// (u, v) in grid units for the reduced unknowns x: coefficients P x + offset, then the basis
/// evaluated once per wedge of cornerUV, which must hold the cut's wedges (buildCutWedges) on all
/// 3 #F corners; wedges the basis does not cover keep their values.
void evaluateMap(const Basis& basis, const Reduction& reduction,
                 const std::vector<std::complex<double>>& unknowns, WedgeMap& cornerUV);

}  // namespace seamvox
