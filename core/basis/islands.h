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

/// islandFacesOf's faces from a walk that meets the components one after another (a component's
/// faces before the next one's, as detail::buildDualTree reaches them): add(f, component) for
/// every face, then faces().
class IslandsInOrder {
 public:
  explicit IslandsInOrder(std::uint32_t maxFaces) : maxFaces_(maxFaces) {}
  void add(FaceId f, std::uint32_t component) {
    if (component != current_) {
      close();
      current_ = component;
    }
    if (++count_ <= maxFaces_) faces_.push_back(f);
  }
  /// The faces of the components of at most maxFaces faces and fewer than the largest, increasing.
  std::vector<FaceId> faces() {
    close();
    std::vector<FaceId> out;
    std::size_t at = 0;
    for (const std::uint32_t n : small_) {
      if (n < largest_) out.insert(out.end(), faces_.begin() + at, faces_.begin() + at + n);
      at += n;
    }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  void close() {
    if (count_ == 0) return;
    largest_ = std::max(largest_, static_cast<std::uint32_t>(std::min<std::uint64_t>(count_, maxFaces_ + std::uint64_t(1))));
    if (count_ <= maxFaces_) {
      small_.push_back(static_cast<std::uint32_t>(count_));
    } else {
      faces_.resize(faces_.size() - maxFaces_);  // too large: its first faces dropped
    }
    count_ = 0;
  }
  std::uint32_t maxFaces_ = 0, largest_ = 0;
  std::uint32_t current_ = ~std::uint32_t(0);
  std::uint64_t count_ = 0;
  std::vector<FaceId> faces_;         // the small components' faces, in order
  std::vector<std::uint32_t> small_;  // per small component its faces
};

}  // namespace detail
}  // namespace seamvox
