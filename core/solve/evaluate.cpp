#include "core/solve/evaluate.h"
#include "core/solve/detail_wedges.h"
#include "core/system/parallel.h"


namespace seamvox {

using detail::walkWedges;

WedgeMap buildCutWedges(const Topology& topology, const CutResult& cut) {
  const std::uint32_t nv = topology.numVertices();
  const CutCorners& corners = cut.corners;
  // Wedges per vertex (a fan with k > 0 cut edges has k wedges, unless it is a boundary fan,
  // whose last edge is a boundary edge), then one prefix sum, then the numbering.
  std::vector<std::uint32_t> first(nv + std::size_t(1), 0);
  parallelFor(nv, 1u << 14, [&](const IndexRange& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      std::uint32_t wedges = 0;
      bool open = false;
      walkWedges(topology, corners, v, [&](CornerId c) {
        if (c == kInvalidId) {
          open = false;
        } else if (!open) {
          open = true;
          ++wedges;
        }
      });
      first[v + 1] = wedges;
    }
  });
  for (VertexId v = 0; v < nv; ++v) first[v + 1] += first[v];
  std::vector<std::uint32_t> cornerWedge(topology.numCorners(), 0);
  parallelFor(nv, 1u << 14, [&](const IndexRange& range) {
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      std::uint32_t w = first[v];
      bool open = false;
      walkWedges(topology, corners, v, [&](CornerId c) {
        if (c == kInvalidId) {
          if (open) ++w;
          open = false;
        } else {
          open = true;
          cornerWedge[c] = w;
        }
      });
    }
  });
  const std::uint32_t numWedges = first[nv];
  std::vector<std::uint32_t>().swap(first);
  // Room for the wedges the refinement and the repair add (WedgeMap::assign): an untouched
  // reserve is not resident, a reallocation would hold the values twice.
  std::vector<Vec2d> values;
  values.reserve(numWedges + numWedges / 8);
  values.resize(numWedges, Vec2d::Zero());
  return WedgeMap(std::move(cornerWedge), std::move(values));
}

void evaluateMap(const Basis& basis, const Reduction& reduction,
                 const std::vector<std::complex<double>>& unknowns, WedgeMap& cornerUV) {
  basis.evaluateCorners(expandCoefficients(reduction, unknowns), cornerUV);
}

}  // namespace seamvox
