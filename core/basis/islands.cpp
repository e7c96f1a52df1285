#include "core/basis/islands.h"

#include <algorithm>

#include "core/mesh/detail_union_find.h"
#include "core/mesh/topology.h"

namespace seamvox {

std::vector<FaceId> islandFaces(const Topology& topology, std::uint32_t maxFaces) {
  const std::uint32_t nf = topology.numFaces();
  detail::UnionFind sets(nf);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (o != kInvalidId && c < o) sets.unite(c / 3, o / 3);
  }
  struct Counts {
    std::vector<std::uint32_t> n;
    std::uint32_t get(std::uint32_t i) const { return n[i]; }
    void set(std::uint32_t i, std::uint32_t value) { n[i] = value; }
  } counts{std::vector<std::uint32_t>(nf, 0)};
  return detail::islandFacesOf(nf, sets, counts, maxFaces);
}

}  // namespace seamvox
