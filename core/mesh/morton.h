#pragma once
/// Morton (Z-order) codes of points in a box: sorting by them puts points that are close in space
/// close in memory (the spatial order of cleaning and of the out-of-core scratch).
#include <algorithm>
#include <cstdint>

#include "core/mesh/mesh.h"

namespace seamvox {

/// Bits per axis of a Morton code (63 bits in all).
constexpr int kMortonBits = 21;

/// The low 21 bits of x spread to every third bit.
inline std::uint64_t spreadBits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

/// Morton code of p on a 2^21 grid over the box (points outside are clamped to it).
inline std::uint64_t mortonCode(const Vec3d& p, const BoundingBox& box) {
  std::uint64_t code = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double extent = box.max[axis] - box.min[axis];
    const double t = extent > 0.0 ? (p[axis] - box.min[axis]) / extent : 0.0;
    const double cells = static_cast<double>(1u << kMortonBits);
    const auto q = static_cast<std::uint64_t>(std::clamp(t * cells, 0.0, cells - 1.0));
    code |= spreadBits(q) << axis;
  }
  return code;
}

}  // namespace seamvox
