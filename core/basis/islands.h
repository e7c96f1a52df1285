#pragma once
/// Islands: components too small for the voxel basis. A component of a few faces inside one or
/// two cells gets its own copies of the B-splines around it (about 9 unknowns each, often nearly
/// dependent on it): a scan with a million specks would carry 10^7 unknowns in the "grid-sized"
/// system. Islands are left out of the voxel basis and mapped by the local hat solve instead (a
/// region holding the whole island: every vertex free), in memory and out of core alike.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/mesh/mesh_types.h"

namespace seamvox {

class Topology;

/// Components (faces joined through glued edges) of at most this many faces, other than those
/// with the most faces, are islands.
constexpr std::uint32_t kVoxelIslandFaces = 1024;

/// The faces of the islands of at most maxFaces faces, increasing.
std::vector<FaceId> islandFaces(const Topology& topology, std::uint32_t maxFaces = kVoxelIslandFaces);

namespace detail {

/// islandFaces over any union-find of the faces (find(f), joined already) and any per-face
/// counters (get(i), set(i, value); zero at first), for the in-memory and out-of-core paths.
template <class Sets, class Counts>
std::vector<FaceId> islandFacesOf(std::uint64_t numFaces, Sets& sets, Counts& counts, std::uint32_t maxFaces) {
  // Faces per component at its root, saturated at maxFaces + 1: only the small ones need counts.
  for (std::uint64_t f = 0; f < numFaces; ++f) {
    const std::uint32_t root = sets.find(static_cast<std::uint32_t>(f));
    const std::uint32_t n = counts.get(root);
    if (n <= maxFaces) counts.set(root, n + 1);
  }
  std::uint32_t largest = 0;
  for (std::uint64_t f = 0; f < numFaces; ++f) {
    if (sets.find(static_cast<std::uint32_t>(f)) == f) largest = std::max(largest, counts.get(static_cast<std::uint32_t>(f)));
  }
  std::vector<FaceId> out;
  for (std::uint64_t f = 0; f < numFaces; ++f) {
    const std::uint32_t n = counts.get(sets.find(static_cast<std::uint32_t>(f)));
    if (n <= maxFaces && n < largest) out.push_back(static_cast<FaceId>(f));
  }
  return out;
}

}  // namespace detail
}  // namespace seamvox
