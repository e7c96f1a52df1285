#pragma once
/// The one parallel loop of the project: TBB stays in parallel.cpp, and a loop whose work fits
/// in one block runs on the calling thread, without task overhead. Thread counts are set once,
/// by the caller (tools/: tbb::global_control).
#include <cstdint>
#include <functional>
#include <vector>

namespace seamvox {

/// A block [begin, end) of a parallel loop.
struct IndexRange {
  std::uint64_t first = 0, last = 0;
  std::uint64_t begin() const { return first; }
  std::uint64_t end() const { return last; }
};

/// Calls body on disjoint blocks covering [0, n), possibly concurrently; `grain` is the smallest
/// block worth a task (blocks hold at least grain / 2 items); n <= grain runs as one call on
/// this thread. Exceptions from body propagate
/// (TBB cancels the other blocks).
void parallelFor(std::uint64_t n, std::uint64_t grain, const std::function<void(const IndexRange&)>& body);

/// Calls f(i) for every i in [0, n), in parallelFor's blocks (one indirect call per block).
template <class F>
void parallelForEach(std::uint64_t n, std::uint64_t grain, F&& f) {
  parallelFor(n, grain, [&](const IndexRange& r) {
    for (std::uint64_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

/// Sorts ids and drops repeats, on several threads when they are many (the same list either way).
void sortUniqueIds(std::vector<std::uint32_t>& ids);

}  // namespace seamvox
