#pragma once
/// The hat basis' wedges (domains) and seam adjacency written once for HatBasis, HatDomains and
/// the out-of-core seam constraints (stream/constraint_stream): templates over the corner table
/// (ccw, opposite, vertex, forEachCornerAround), the cut (isCut) and where corners' domains live.
#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/basis/basis.h"
#include "core/cut/cut.h"
#include "core/mesh/topology.h"
#include "core/system/errors.h"

namespace seamvox::detail {

/// Walks the fan of corners around v counter-clockwise; a cut edge (or the subset's border)
/// starts a new wedge. The first wedge of v makes v's basis function: basisVertex gets v,
/// domainBasis its function per new domain, setDomain(c, d) per corner of the subset.
template <class Table, class Cut, class InSubset, class SetDomain>
void addFanWedges(Table& table, Cut& cut, InSubset&& inSubset, VertexId v, const std::vector<CornerId>& fan,
                  std::vector<std::uint32_t>& domainBasis, std::vector<VertexId>& basisVertex, SetDomain&& setDomain) {
  const std::size_t m = fan.size();
  const bool closed = table.ccw(fan.back()) == fan.front();
  auto separated = [&](std::size_t j) {  // is there a wedge border just before fan[j]?
    const CornerId before = j > 0 ? fan[j - 1] : fan[m - 1];
    if (j == 0 && !closed) return true;
    return cut.isCut(nextCorner(before)) || !inSubset(cornerFace(before)) || !inSubset(cornerFace(fan[j]));
  };
  std::size_t start = 0;
  for (std::size_t j = 0; j < m; ++j) {
    if (separated(j)) {
      start = j;
      break;
    }
  }
  bool anyDomain = false;
  std::uint32_t current = kInvalidId;
  for (std::size_t step = 0; step < m; ++step) {
    const std::size_t j = (start + step) % m;
    const CornerId c = fan[j];
    if (!inSubset(cornerFace(c))) {
      current = kInvalidId;
      continue;
    }
    if (current == kInvalidId || separated(j)) {
      if (!anyDomain) {
        basisVertex.push_back(v);
        anyDomain = true;
      }
      current = static_cast<std::uint32_t>(domainBasis.size());
      domainBasis.push_back(static_cast<std::uint32_t>(basisVertex.size() - 1));
    }
    setDomain(c, current);
  }
}

/// Seam adjacency: the wedges on either side of every seam edge inside the subset, at both of
/// its endpoints (unsorted). InputError on a seam along a boundary edge.
template <class Opposite, class InSubset, class CornerDomain>
std::vector<DomainAdjacency> collectSeamAdjacencies(const std::vector<SeamCurve>& seams, Opposite&& opposite,
                                                    InSubset&& inSubset, CornerDomain&& cornerDomain) {
  std::vector<DomainAdjacency> adjacencies;
  for (std::uint32_t s = 0; s < seams.size(); ++s) {
    for (CornerId c : seams[s].corners) {
      const CornerId o = opposite(c);
      if (o == kInvalidId) {
        throw InputError("hat basis: seam " + std::to_string(s) + " has boundary edge of corner " + std::to_string(c));
      }
      if (!inSubset(cornerFace(c)) || !inSubset(cornerFace(o))) continue;
      adjacencies.push_back({cornerDomain(nextCorner(c)), cornerDomain(prevCorner(o)), s});
      adjacencies.push_back({cornerDomain(prevCorner(c)), cornerDomain(nextCorner(o)), s});
    }
  }
  return adjacencies;
}

/// The faces around the vertices of every seam edge, sorted, unique: where cycles of seam
/// crossings close (seamCycleConstraints).
template <class Table>
std::vector<FaceId> facesAroundSeams(Table& table, const std::vector<SeamCurve>& seams) {
  std::vector<FaceId> faces;
  for (const SeamCurve& seam : seams) {
    for (CornerId c : seam.corners) {
      for (CornerId end : {nextCorner(c), prevCorner(c)}) {
        table.forEachCornerAround(table.vertex(end), [&](CornerId around) { faces.push_back(cornerFace(around)); });
      }
    }
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

/// The hat basis' domains on a sorted face subset (as HatBasis with HatBasisOptions::faces
/// builds them): per subset face its three corners' domains, and the seam adjacency.
struct SubsetWedges {
  std::vector<std::array<std::uint32_t, 3>> faceDomains;  // per subset face
  std::vector<std::uint32_t> domainBasis;
  std::vector<VertexId> basisVertex;
  std::vector<DomainAdjacency> adjacencies;
};

template <class Table, class Cut>
SubsetWedges buildSubsetWedges(Table& table, Cut& cut, const std::vector<FaceId>& faces,
                               const std::vector<SeamCurve>& seams) {
  SubsetWedges out;
  out.faceDomains.assign(faces.size(), {kInvalidId, kInvalidId, kInvalidId});
  const auto indexOf = [&](FaceId f) {
    const auto it = std::lower_bound(faces.begin(), faces.end(), f);
    return it != faces.end() && *it == f ? static_cast<std::size_t>(it - faces.begin()) : faces.size();
  };
  const auto inSubset = [&](FaceId f) { return indexOf(f) != faces.size(); };
  std::vector<VertexId> vertices;
  for (FaceId f : faces) {
    for (int k = 0; k < 3; ++k) vertices.push_back(table.vertex(3 * f + k));
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  std::vector<CornerId> fan;
  for (VertexId v : vertices) {
    fan.clear();
    table.forEachCornerAround(v, [&](CornerId c) { fan.push_back(c); });
    if (fan.empty()) continue;
    addFanWedges(table, cut, inSubset, v, fan, out.domainBasis, out.basisVertex,
                 [&](CornerId c, std::uint32_t d) { out.faceDomains[indexOf(cornerFace(c))][c % 3] = d; });
  }
  out.adjacencies = collectSeamAdjacencies(
      seams, [&](CornerId c) { return table.opposite(c); }, inSubset,
      [&](CornerId c) {
        const std::size_t i = indexOf(cornerFace(c));
        return i == faces.size() ? kInvalidId : out.faceDomains[i][c % 3];
      });
  return out;
}

}  // namespace seamvox::detail
