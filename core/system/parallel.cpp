// parallelFor over TBB with a serial path for loops of one block.
#include "core/system/parallel.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace seamvox {

void parallelFor(std::uint64_t n, std::uint64_t grain, const std::function<void(const IndexRange&)>& body) {
  grain = std::max<std::uint64_t>(grain, 1);
  if (n == 0) return;
  if (n <= grain) {
    body(IndexRange{0, n});
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::uint64_t>& r) { body(IndexRange{r.begin(), r.end()}); });
}

void sortUniqueIds(std::vector<std::uint32_t>& ids) {
  if (ids.size() > (std::size_t(1) << 16)) {
    tbb::parallel_sort(ids.begin(), ids.end());
  } else {
    std::sort(ids.begin(), ids.end());
  }
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
}

}  // namespace seamvox
