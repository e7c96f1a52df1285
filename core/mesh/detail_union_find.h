#pragma once
/// Union-find over 32-bit ids with path halving; unite keeps the smaller id as the root, so
/// results do not depend on the order of unions.
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace seamvox::detail {

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace seamvox::detail
