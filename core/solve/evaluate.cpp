#include "core/solve/evaluate.h"

#include <algorithm>

#include "core/solve/detail_wedges.h"
#include "core/system/parallel.h"


namespace seamvox {

using detail::walkWedges;

WedgeMap buildCutWedges(const Topology& topology, const CutResult& cut, bool viewTriangles) {
  const std::uint32_t nv = topology.numVertices();
  const CutCorners& corners = cut.corners;
  // Wedges are numbered in vertex order, a fan's in walk order (a fan with k > 0 cut edges has k
  // wedges, unless it is a boundary fan, whose last edge is a boundary edge). One walk per vertex
  // numbers them within its block of vertices; then every wedge id adds its block's offset.
  // Per corner, or (viewTriangles) per vertex its first wedge and the corners of its later ones.
  constexpr std::uint32_t kBlock = 1u << 14;
  const std::uint32_t blocks = (nv + kBlock - 1) / kBlock;
  std::vector<std::uint32_t> first(blocks + std::size_t(1), 0);
  std::vector<std::uint32_t> cornerWedge(viewTriangles ? 0 : topology.numCorners(), kInvalidId);
  std::vector<std::uint32_t> vertexWedge(viewTriangles ? nv : 0, 0);
  std::vector<std::vector<std::pair<CornerId, std::uint32_t>>> later(viewTriangles ? blocks : 0);
  parallelForEach(blocks, 1, [&](std::uint64_t b) {
    std::uint32_t w = 0;
    const VertexId end = static_cast<VertexId>(std::min<std::uint64_t>(nv, (b + 1) * std::uint64_t(kBlock)));
    for (VertexId v = static_cast<VertexId>(b * kBlock); v < end; ++v) {
      bool open = false;
      const std::uint32_t own = w;
      walkWedges(topology, corners, v, [&](CornerId c) {
        if (c == kInvalidId) {
          if (open) ++w;
          open = false;
        } else {
          open = true;
          if (!viewTriangles) {
            cornerWedge[c] = w;
          } else if (w != own) {
            later[b].emplace_back(c, w);
          }
        }
      });
      if (viewTriangles) vertexWedge[v] = own;
      if (open) ++w;
    }
    first[b + 1] = w;
  });
  for (std::uint32_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  const std::uint32_t numWedges = first[blocks];
  // Room for the wedges the refinement and the repair add (WedgeMap::assign): an untouched
  // reserve is not resident, a reallocation would hold the values twice.
  std::vector<Vec2d> values;
  values.reserve(numWedges + numWedges / 8);
  values.resize(numWedges, Vec2d::Zero());
  if (viewTriangles) {
    std::vector<std::pair<CornerId, std::uint32_t>> other;
    for (std::uint32_t b = 0; b < blocks; ++b) {
      for (const auto& [c, w] : later[b]) other.emplace_back(c, w + first[b]);
      std::vector<std::pair<CornerId, std::uint32_t>>().swap(later[b]);
    }
    parallelFor(vertexWedge.size(), 1u << 16, [&](const IndexRange& range) {
      for (VertexId v = range.begin(); v != range.end(); ++v) vertexWedge[v] += first[v / kBlock];
    });
    return WedgeMap::overTriangles(topology.triangles().data(), topology.numCorners(), std::move(vertexWedge), other,
                                   std::move(values));
  }
  parallelFor(cornerWedge.size(), 1u << 16, [&](const IndexRange& range) {
    for (CornerId c = range.begin(); c != range.end(); ++c) {
      std::uint32_t& w = cornerWedge[c];
      w = w == kInvalidId ? 0 : w + first[topology.vertex(c) / kBlock];
    }
  });
  std::vector<std::uint32_t>().swap(first);
  return WedgeMap(std::move(cornerWedge), std::move(values));
}

void evaluateMap(const Basis& basis, const Reduction& reduction,
                 const std::vector<std::complex<double>>& unknowns, WedgeMap& cornerUV) {
  basis.evaluateCorners(expandCoefficients(reduction, unknowns), cornerUV);
}

}  // namespace seamvox
