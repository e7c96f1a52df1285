#include "core/solve/assemble.h"
#include "core/system/parallel.h"

#include <algorithm>
#include <atomic>
#include <mutex>

namespace seamvox {

namespace {

using Triplet = Eigen::Triplet<std::complex<double>, int>;

// Per-chunk accumulation: triplets, compressed into a sparse matrix when the buffer fills.
struct Accumulator {
  std::vector<Triplet> triplets;
  ComplexSparse sum;
  ComplexVector rhs;
  double area = 0.0, target = 0.0;
  void flush(int n) {
    if (triplets.empty()) return;
    ComplexSparse part(n, n);
    part.setFromTriplets(triplets.begin(), triplets.end());
    if (sum.rows() == 0) {
      sum = std::move(part);
    } else {
      sum += part;
    }
    triplets.clear();
  }
  // Adds other (flushed) into this (flushed).
  void merge(Accumulator&& other) {
    if (other.sum.rows() != 0) {
      if (sum.rows() == 0) {
        sum = std::move(other.sum);
      } else {
        sum += other.sum;
      }
    }
    rhs += other.rhs;
    area += other.area;
    target += other.target;
    other = Accumulator();
  }
};

constexpr std::size_t kFlushTriplets = 1u << 21;
/// Elements per range when the basis has no blocks of its own.
constexpr std::uint64_t kRangeElements = 4096;
/// Chunks the assembly is split into, whatever the thread count: each level of their merge is a
/// pass over all nonzeros, so few, enough for a few cores; kFewChunks above
/// AssembleOptions::fewChunksAbove unknowns.
constexpr std::uint64_t kChunks = 8, kFewChunks = 2;

}  // namespace

LinearSystem assembleSystem(const Basis& basis, const Reduction& reduction,
                            const AssembleOptions& options) {
  const int n = static_cast<int>(reduction.numUnknowns());
  const ReducedMap& P = reduction.map;
  const bool hasOffset = !P.offset.empty();
  const std::uint64_t ne = basis.numElements();
  std::atomic<std::uint64_t> done{0};
  std::mutex progressMutex;
  reportProgress(options.progress, "assemble", 0.0);
  // The elements are split at the basis' own blocks (e.g. OpenVDB leaf nodes) when it has them,
  // else into fixed-size ranges, and the ranges into kChunks chunks of consecutive ranges. Each
  // chunk sums into its own accumulator and the chunks are merged in a fixed tree: the sums do
  // not depend on how the threads were scheduled, so the system (and the map) is the same every
  // run and for any thread count.
  std::vector<std::uint64_t> blocks = basis.elementBlocks();
  if (!(blocks.size() >= 2 && blocks.front() == 0 && blocks.back() == ne)) {
    blocks.clear();
    for (std::uint64_t e = 0; e < ne; e += kRangeElements) blocks.push_back(e);
    blocks.push_back(ne);
  }
  const std::uint64_t ranges = blocks.size() - 1;
  const std::uint64_t chunks = std::min<std::uint64_t>(std::uint64_t(n) > options.fewChunksAbove ? kFewChunks : kChunks, ranges);
  std::vector<Accumulator> parts(chunks);
  const auto assembleRange = [&](Accumulator& acc, std::uint64_t begin, std::uint64_t end) {
    ElementIntegrals el;
    for (std::uint64_t e = begin; e != end; ++e) {
      basis.elementIntegrals(e, el);
      const std::uint32_t m = el.count;
      acc.area += el.area;
      std::complex<double> local[kMaxElementFunctions];
      for (std::uint32_t a = 0; a < m; ++a) {
        local[a] = el.rhs[a];
        if (hasOffset) {
          for (std::uint32_t b = 0; b < m; ++b) {
            if (el.domain[b] != kInvalidId) local[a] -= el.stiffness[m * a + b] * P.offset[el.domain[b]];
          }
        }
      }
      for (std::uint32_t a = 0; a < m; ++a) {
        const std::uint32_t da = el.domain[a];
        if (da == kInvalidId) continue;
        for (std::uint64_t ka = P.rowStart[da]; ka < P.rowStart[da + 1]; ++ka) {
          const int i = static_cast<int>(P.column[ka]);
          const std::complex<double> pa = std::conj(P.value[ka]);
          acc.rhs[i] += pa * local[a];
          for (std::uint32_t b = 0; b < m; ++b) {
            const std::uint32_t db = el.domain[b];
            const double l = el.stiffness[m * a + b];
            if (db == kInvalidId || l == 0.0) continue;
            for (std::uint64_t kb = P.rowStart[db]; kb < P.rowStart[db + 1]; ++kb) {
              const int j = static_cast<int>(P.column[kb]);
              if (i >= j) acc.triplets.emplace_back(i, j, pa * l * P.value[kb]);
            }
          }
        }
      }
      if (acc.triplets.size() > kFlushTriplets) acc.flush(n);
    }
    const std::uint64_t total = done += end - begin;
    if (options.progress) {
      std::lock_guard<std::mutex> lock(progressMutex);
      reportProgress(options.progress, "assemble", static_cast<double>(total) / ne);
    }
  };
  parallelForEach(chunks, 1, [&](std::uint64_t k) {
    Accumulator& acc = parts[k];
    acc.rhs = ComplexVector::Zero(n);
    const std::uint64_t first = ranges * k / chunks, last = ranges * (k + 1) / chunks;
    for (std::uint64_t r = first; r < last; ++r) assembleRange(acc, blocks[r], blocks[r + 1]);
    acc.flush(n);
  });
  // Pairwise merges in a fixed tree (each level in parallel): log2(chunks) passes over the
  // nonzeros instead of one per chunk.
  for (std::size_t step = 1; step < parts.size(); step *= 2) {
    parallelForEach((parts.size() + 2 * step - 1) / (2 * step), 1, [&](std::uint64_t i) {
      const std::size_t a = 2 * step * i, b = a + step;
      if (b < parts.size()) parts[a].merge(std::move(parts[b]));
    });
  }
  LinearSystem out;
  if (!parts.empty()) {
    out.lower = std::move(parts.front().sum);
    out.rhs = std::move(parts.front().rhs);
    out.totalArea = parts.front().area;
  }
  if (out.lower.rows() == 0) out.lower.resize(n, n);
  if (out.rhs.size() == 0) out.rhs = ComplexVector::Zero(n);
  out.lower.makeCompressed();
  return out;
}

RestrictedSystem restrictSystem(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                                const std::vector<std::complex<double>>& values,
                                const std::vector<ComplexTriplet>& extraLower) {
  const int n = static_cast<int>(system.lower.rows());
  RestrictedSystem out;
  std::vector<int> index(n, -1);
  for (int i = 0; i < n; ++i) {
    if (!fixed[i]) {
      index[i] = static_cast<int>(out.freeUnknowns.size());
      out.freeUnknowns.push_back(static_cast<std::uint32_t>(i));
    }
  }
  const int nf = static_cast<int>(out.freeUnknowns.size());
  out.rhs.resize(nf);
  for (int k = 0; k < nf; ++k) out.rhs[k] = system.rhs[out.freeUnknowns[k]];
  std::vector<Triplet> triplets;
  triplets.reserve(system.lower.nonZeros() + extraLower.size());
  const auto add = [&](int i, int j, std::complex<double> value) {  // i >= j; K_ji = conj(K_ij)
    if (index[i] >= 0 && index[j] >= 0) {
      triplets.emplace_back(index[i], index[j], value);
    } else if (index[i] >= 0) {
      out.rhs[index[i]] -= value * values[j];
    } else if (index[j] >= 0) {
      out.rhs[index[j]] -= std::conj(value) * values[i];
    }
  };
  for (int j = 0; j < n; ++j) {
    for (ComplexSparse::InnerIterator it(system.lower, j); it; ++it) add(it.row(), j, it.value());
  }
  for (const ComplexTriplet& t : extraLower) add(t.row(), t.col(), t.value());
  out.lower.resize(nf, nf);
  out.lower.setFromTriplets(triplets.begin(), triplets.end());
  return out;
}

std::vector<std::int64_t> restrictOrder(const std::vector<std::uint32_t>& order,
                                        const std::vector<std::uint32_t>& freeUnknowns, std::uint32_t numUnknowns) {
  if (order.empty()) return {};
  std::vector<std::int64_t> position(numUnknowns, -1);
  for (std::size_t k = 0; k < freeUnknowns.size(); ++k) position[freeUnknowns[k]] = std::int64_t(k);
  std::vector<std::int64_t> out;
  out.reserve(freeUnknowns.size());
  for (std::uint32_t j : order) {
    if (j < numUnknowns && position[j] >= 0) out.push_back(position[j]), position[j] = -1;
  }
  for (std::size_t k = 0; k < freeUnknowns.size(); ++k) {
    if (position[freeUnknowns[k]] >= 0) out.push_back(std::int64_t(k));
  }
  return out;
}

}  // namespace seamvox
