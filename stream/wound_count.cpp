#include "stream/wound_count.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "core/mesh/detail_union_find.h"
#include "core/quality/metrics.h"
#include "stream/keyed_sort.h"

namespace seamvox {
namespace {

struct VertexAngle {  // a corner's angle at its vertex, in a range's scratch file
  std::uint32_t vertex;
  float angle;
};

template <class Angle>
struct FanCorner {  // a corner at a vertex and the corner it is joined to there (none: kNoCorner)
  std::uint64_t corner, joined;
  std::uint32_t vertex;
  Angle angle;
};
template <class Angle>
struct FanCornerLess {
  bool operator()(const FanCorner<Angle>& x, const FanCorner<Angle>& y) const {
    return std::tie(x.vertex, x.corner) < std::tie(y.vertex, y.corner);
  }
};
struct VertexOf {
  template <class Record>
  std::uint64_t operator()(const Record& x) const { return x.vertex; }
};
constexpr std::uint64_t kNoCorner = ~std::uint64_t(0);

std::uint64_t nextOf(std::uint64_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
std::uint64_t prevOf(std::uint64_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

}  // namespace

float woundCornerAngle(const Vec2d& q, const Vec2d& next, const Vec2d& prev, bool onBoundary) {
  return onBoundary ? -std::numeric_limits<float>::infinity() : static_cast<float>(cornerUVAngle(q, next, prev));
}

struct ManifoldWoundCounter::Impl {
  ScratchFolder& scratch;
  std::string stage;
  std::uint64_t vertices, perRange;
  std::vector<float> sums;  // the vertices of one range
  std::vector<std::unique_ptr<ScratchWriter>> writers;  // a file per range beyond one
  std::vector<VertexAngle> buffer;
};

ManifoldWoundCounter::ManifoldWoundCounter(ScratchFolder& scratch, std::uint64_t vertices, std::uint64_t memoryBytes,
                                           const char* stage)
    : impl_(std::make_unique<Impl>(Impl{scratch, stage, vertices, 0, {}, {}, {}})) {
  Impl& m = *impl_;
  // A range's sums take the memory less the write buffers (64 KiB per range).
  const std::uint64_t fit = std::max<std::uint64_t>(memoryBytes / 2 / sizeof(float), 1);
  const std::uint64_t ranges = std::max<std::uint64_t>(1, (vertices + fit - 1) / fit);
  m.perRange = std::max<std::uint64_t>(1, (vertices + ranges - 1) / ranges);
  if (ranges == 1) {
    m.sums.assign(vertices, 0.0f);
  } else {
    for (std::uint64_t r = 0; r < ranges; ++r) m.writers.push_back(std::make_unique<ScratchWriter>(scratch, stage, 1 << 16));
  }
}
ManifoldWoundCounter::~ManifoldWoundCounter() = default;

bool ManifoldWoundCounter::inRanges() const { return !impl_->writers.empty(); }

void ManifoldWoundCounter::add(std::uint32_t v, float angle) {
  Impl& m = *impl_;
  if (m.writers.empty()) {
    m.sums[v] += angle;
  } else {
    const VertexAngle record{v, angle};
    m.writers[v / m.perRange]->write(&record, sizeof record);
  }
}

std::uint64_t ManifoldWoundCounter::count() {
  Impl& m = *impl_;
  std::uint64_t wound = 0;
  const auto countSums = [&] {
    for (const float sum : m.sums) wound += sum >= kWoundAngleSum;
  };
  if (m.writers.empty()) {
    countSums();
    std::vector<float>().swap(m.sums);
    return wound;
  }
  for (std::size_t r = 0; r < m.writers.size(); ++r) {
    const ScratchFile file = m.writers[r]->finish();
    m.writers[r].reset();
    const std::uint64_t first = r * m.perRange;
    m.sums.assign(static_cast<std::size_t>(std::min(m.perRange, m.vertices - first)), 0.0f);
    {
      ScratchReader reader(m.scratch, file, m.stage);
      VertexAngle corner;
      while (reader.read(&corner, sizeof corner)) m.sums[corner.vertex - first] += corner.angle;
    }
    m.scratch.remove(file);
    countSums();
  }
  std::vector<float>().swap(m.sums);
  return wound;
}

template <class Angle>
struct FanAngleSums<Angle>::Impl {
  KeyedSorter<FanCorner<Angle>, FanCornerLess<Angle>, VertexOf> corners;
  Impl(ScratchFolder& scratch, std::uint64_t vertices, std::uint64_t faces, const ExternalSortOptions& options)
      : corners(scratch, vertices, 3 * faces, options) {}
};

template <class Angle>
FanAngleSums<Angle>::FanAngleSums(ScratchFolder& scratch, std::uint64_t vertices, std::uint64_t faces,
                                  const ExternalSortOptions& options)
    : impl_(std::make_unique<Impl>(scratch, vertices, faces, options)) {
  static_assert(sizeof(FanCorner<Angle>) == kBytesPerSide, "the record's bytes");
}
template <class Angle>
FanAngleSums<Angle>::~FanAngleSums() = default;

template <class Angle>
void FanAngleSums<Angle>::addSide(std::uint32_t a, std::uint64_t c, Angle angle) {
  impl_->corners.add({nextOf(c), kNoCorner, a, angle});
}

template <class Angle>
void FanAngleSums<Angle>::addGluedSides(std::uint32_t a, std::uint32_t b, std::uint64_t c, std::uint64_t o,
                                        Angle angleC, Angle angleO) {
  impl_->corners.add({nextOf(c), prevOf(o), a, angleC});
  impl_->corners.add({nextOf(o), prevOf(c), b, angleO});
}

template <class Angle>
void FanAngleSums<Angle>::forEachClosedFan(const std::function<void(const ClosedFan&)>& visit) {
  impl_->corners.finish();
  FanCorner<Angle> corner;
  bool have = impl_->corners.next(corner);
  std::vector<FanCorner<Angle>> around;
  std::vector<double> sums;
  std::vector<std::uint32_t> cornerCount, joinedCount;
  detail::UnionFind fans(0);
  // A vertex at a time: its corners (by corner id) joined into fans. A fan's root is its smallest
  // index, so its smallest corner, and the roots in increasing order give the fans in that order.
  while (have) {
    const std::uint32_t v = corner.vertex;
    around.clear();
    for (; have && corner.vertex == v; have = impl_->corners.next(corner)) around.push_back(corner);
    const std::uint32_t n = static_cast<std::uint32_t>(around.size());
    fans.parent.resize(n);
    std::iota(fans.parent.begin(), fans.parent.end(), 0u);
    for (std::uint32_t i = 0; i < n; ++i) {
      if (around[i].joined == kNoCorner) continue;
      const auto it = std::lower_bound(around.begin(), around.end(), around[i].joined,
                                       [](const FanCorner<Angle>& x, std::uint64_t c) { return x.corner < c; });
      if (it != around.end() && it->corner == around[i].joined) {
        fans.unite(i, static_cast<std::uint32_t>(it - around.begin()));
      } else {
        around[i].joined = kNoCorner;  // not a corner at v (cannot happen for glued sides)
      }
    }
    sums.assign(n, 0.0);
    cornerCount.assign(n, 0);
    joinedCount.assign(n, 0);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t root = fans.find(i);
      sums[root] += around[i].angle;
      ++cornerCount[root];
      joinedCount[root] += around[i].joined != kNoCorner;
    }
    for (std::uint32_t i = 0; i < n; ++i) {
      if (fans.parent[i] == i && joinedCount[i] == cornerCount[i]) visit(ClosedFan{v, sums[i], around[i].corner});
    }
  }
}

template class FanAngleSums<float>;
template class FanAngleSums<double>;

std::uint64_t countWoundFans(FanAngleSums<float>& sums) {
  std::uint64_t wound = 0;
  sums.forEachClosedFan([&](const ClosedFan& fan) { wound += fan.angleSum >= kWoundAngleSum; });
  return wound;
}

}  // namespace seamvox
