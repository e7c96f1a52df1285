#include "core/basis/gaussian_int.h"

#include <algorithm>
#include <cmath>

namespace seamvox {

namespace {

// round(x / n) for n > 0, halves rounded up; exact in integers.
std::int64_t divideNearest(std::int64_t x, std::int64_t n) {
  const std::int64_t num = 2 * x + n, den = 2 * n;
  std::int64_t q = num / den;
  if ((num % den != 0) && (num < 0)) --q;  // floor division
  return q;
}

// Sums duplicate indices of an unsorted list and drops zeros.
GaussVector compact(GaussVector v) {
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  GaussVector out;
  for (const auto& [i, x] : v) {
    if (!out.empty() && out.back().first == i) {
      out.back().second = out.back().second + x;
    } else {
      out.emplace_back(i, x);
    }
    if (out.back().second.isZero()) out.pop_back();
  }
  return out;
}

// Adds x at index i of a sorted vector; returns true when the index was not present before.
bool addEntry(GaussVector& v, std::uint32_t i, GaussInt x) {
  auto it = std::lower_bound(v.begin(), v.end(), i,
                             [](const auto& e, std::uint32_t k) { return e.first < k; });
  if (it != v.end() && it->first == i) {
    it->second = it->second + x;
    if (it->second.isZero()) v.erase(it);
    return false;
  }
  if (!x.isZero()) v.insert(it, {i, x});
  return !x.isZero();
}

const GaussInt* findEntry(const GaussVector& v, std::uint32_t i) {
  auto it = std::lower_bound(v.begin(), v.end(), i,
                             [](const auto& e, std::uint32_t k) { return e.first < k; });
  return (it != v.end() && it->first == i) ? &it->second : nullptr;
}

}  // namespace

GaussInt unitPower(int k) {
  switch (((k % 4) + 4) % 4) {
    case 0: return {1, 0};
    case 1: return {0, 1};
    case 2: return {-1, 0};
    default: return {0, -1};
  }
}

GaussInt divideRounded(GaussInt a, GaussInt b) {
  const GaussInt num = a * b.conj();
  const std::int64_t n = b.norm();
  return {divideNearest(num.re, n), divideNearest(num.im, n)};
}

std::complex<double> roundGaussian(std::complex<double> z) {
  return {std::round(z.real()), std::round(z.imag())};
}

double gaussianIntegerDistance(std::complex<double> z) { return std::abs(z - roundGaussian(z)); }

void addScaled(GaussVector& a, GaussInt q, const GaussVector& b) {
  if (q.isZero() || b.empty()) return;
  GaussVector sum = a;
  for (const auto& [i, x] : b) sum.emplace_back(i, q * x);
  a = compact(std::move(sum));
}

GaussVector scaled(const GaussVector& a, GaussInt q) {
  GaussVector out;
  if (q.isZero()) return out;
  out.reserve(a.size());
  for (const auto& [i, x] : a) out.emplace_back(i, q * x);
  return out;
}

LatticeEliminator::LatticeEliminator(std::uint32_t n)
    : rows_(n), colRows_(n), alive_(n, 1), numFree_(n) {
  for (std::uint32_t i = 0; i < n; ++i) {
    rows_[i] = {{i, GaussInt(1)}};
    colRows_[i] = {i};
  }
}

GaussVector LatticeEliminator::express(const GaussVector& row) const {
  GaussVector terms;
  for (const auto& [i, c] : row) {
    for (const auto& [j, u] : rows_[i]) terms.emplace_back(j, c * u);
  }
  return compact(std::move(terms));
}

void LatticeEliminator::addToColumn(std::uint32_t target, GaussInt q, std::uint32_t source) {
  // column_target += q column_source, over every row holding the source column. A row is listed
  // twice when its entry cancelled and came back: update it once.
  std::vector<std::uint32_t> rows = colRows_[source];
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  for (std::uint32_t r : rows) {
    const GaussInt* x = findEntry(rows_[r], source);
    if (!x) continue;  // stale index entry
    if (addEntry(rows_[r], target, q * *x)) colRows_[target].push_back(r);
  }
}

bool LatticeEliminator::addConstraint(const GaussVector& row) {
  GaussVector a = express(row);
  if (a.empty()) return false;
  bool nonUnit = false;
  while (a.size() > 1) {
    std::size_t p = 0;
    for (std::size_t j = 1; j < a.size(); ++j) {
      const std::int64_t nj = a[j].second.norm(), np = a[p].second.norm();
      if (nj < np || (nj == np && colRows_[a[j].first].size() < colRows_[a[p].first].size())) p = j;
    }
    if (!a[p].second.isUnit()) nonUnit = true;
    const auto [pc, pv] = a[p];
    GaussVector next{{pc, pv}};
    for (std::size_t j = 0; j < a.size(); ++j) {
      if (j == p) continue;
      const GaussInt q = divideRounded(a[j].second, pv);
      const GaussInt rest = a[j].second - q * pv;
      if (!q.isZero()) addToColumn(a[j].first, -q, pc);  // column_j -= q column_p
      if (!rest.isZero()) next.emplace_back(a[j].first, rest);
    }
    std::sort(next.begin(), next.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    a = std::move(next);
  }
  // One column carries the constraint: g s_p = 0 with g != 0, so s_p = 0.
  const std::uint32_t p = a[0].first;
  for (std::uint32_t r : colRows_[p]) {
    auto& v = rows_[r];
    v.erase(std::remove_if(v.begin(), v.end(), [p](const auto& e) { return e.first == p; }), v.end());
  }
  colRows_[p].clear();
  colRows_[p].shrink_to_fit();
  alive_[p] = 0;
  --numFree_;
  if (nonUnit) ++nonUnit_;
  return true;
}

void LatticeEliminator::finish() {
  if (finished_) return;
  finished_ = true;
  std::vector<std::uint32_t> index(alive_.size(), 0);
  std::uint32_t k = 0;
  for (std::size_t j = 0; j < alive_.size(); ++j) {
    if (alive_[j]) index[j] = k++;
  }
  for (auto& row : rows_) {
    for (auto& e : row) e.first = index[e.first];  // monotone: order kept
  }
  colRows_.clear();
  colRows_.shrink_to_fit();
}

}  // namespace seamvox
