#include "core/solve/cholmod_solver.h"

#include <cholmod.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

#include "core/system/errors.h"
#include "core/system/huge_pages.h"

namespace seamvox {
namespace {

// CHOLMOD allocates through SuiteSparse_config: its large blocks (the factor, the workspace) get
// the same huge-page advice as the command's own arrays (core/system/huge_pages.h).
void* adviseCalloc(std::size_t count, std::size_t size) {
  void* p = std::calloc(count, size);
  if (p && size != 0 && count <= ~std::size_t(0) / size) adviseHugePages(p, count * size);
  return p;
}
void* adviseRealloc(void* old, std::size_t size) {
  void* p = std::realloc(old, size);
  adviseHugePages(p, size);
  return p;
}
void useAdvisedAllocation() {
  static std::once_flag once;
  std::call_once(once, [] {
    SuiteSparse_config.malloc_func = [](std::size_t size) { return mallocAdvised(size); };
    SuiteSparse_config.calloc_func = adviseCalloc;
    SuiteSparse_config.realloc_func = adviseRealloc;
    SuiteSparse_config.free_func = std::free;
  });
}

std::atomic<int> realFormOnlyScopes{0};  // ScopedRealFormOnly instances alive

}  // namespace

struct CholmodFactor::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  bool realForm = false;
  bool realMatrix = false;    // every entry real: factored as a real n x n matrix
  bool realFormOnly = false;  // test hook (setRealFormOnly)
  std::int64_t n = 0;
  std::int64_t failedColumn = -1;  // of the complex form, in the input numbering
  std::uint64_t factorBytes = 0, peakBytes = 0, nonzeros = 0;
  Impl() {
    useAdvisedAllocation();
    cholmod_l_start(&common);
    common.print = 0;  // core never prints; failures become exceptions
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Impl() {
    clear();
    cholmod_l_finish(&common);
  }
  void clear() {
    if (L) cholmod_l_free_factor(&L, &common);
    L = nullptr;
  }
  // Factors A (in the given order when not null); returns false (and frees the factor) when it
  // is not positive definite.
  bool tryFactor(cholmod_sparse* A, std::string* why, const std::vector<std::int64_t>* order = nullptr) {
    clear();
    if (order) {
      const int methods = common.nmethods, ordering = common.method[0].ordering;
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;
      std::vector<SuiteSparse_long> perm(order->begin(), order->end());
      L = cholmod_l_analyze_p(A, perm.data(), nullptr, 0, &common);
      common.nmethods = methods;
      common.method[0].ordering = ordering;
    } else {
      L = cholmod_l_analyze(A, &common);
    }
    if (!L || common.status < CHOLMOD_OK) {
      *why = "analysis failed (status " + std::to_string(common.status) + ")";
      clear();
      return false;
    }
    const int ok = cholmod_l_factorize(A, L, &common);
    if (!ok || common.status < CHOLMOD_OK || L->minor < L->n) {
      *why = L && L->minor < L->n ? "not positive definite at column " + std::to_string(L->minor)
                                  : "factorization failed (status " +
                                        std::to_string(common.status) + ")";
      if (L && L->minor < L->n && failedColumn < 0) {
        // minor counts in the fill-reducing order; the real form's columns n.. are imaginary parts.
        const auto* perm = static_cast<const SuiteSparse_long*>(L->Perm);
        const std::int64_t column = perm ? perm[L->minor] : static_cast<std::int64_t>(L->minor);
        failedColumn = column % n;
      }
      clear();
      return false;
    }
    nonzeros = static_cast<std::uint64_t>(common.lnz);
    return true;
  }
};

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;
CholmodFactor::CholmodFactor(CholmodFactor&&) noexcept = default;
CholmodFactor& CholmodFactor::operator=(CholmodFactor&&) noexcept = default;

void CholmodFactor::factor(const ComplexSparse& lowerIn) { factor(lowerIn, {}); }

std::vector<std::int64_t> CholmodFactor::permutation() const {
  const Impl& m = *impl_;
  if (!m.L || m.realForm || !m.L->Perm) return {};
  const auto* perm = static_cast<const SuiteSparse_long*>(m.L->Perm);
  return std::vector<std::int64_t>(perm, perm + m.n);
}

void CholmodFactor::factor(const ComplexSparse& lowerIn, const std::vector<std::int64_t>& order) {
  ComplexSparse lower = lowerIn;
  lower.makeCompressed();
  Impl& m = *impl_;
  m.n = lower.rows();
  m.realForm = false;
  m.failedColumn = -1;
  const std::int64_t n = m.n, nnz = lower.nonZeros();
  if (n == 0) {
    m.clear();
    return;
  }
  std::string why = "skipped";
  // A real matrix (e.g. the real form of feature-line systems, built by the caller) is factored
  // in real arithmetic: a quarter of the complex flops, half the memory.
  m.realMatrix = std::all_of(lower.valuePtr(), lower.valuePtr() + nnz,
                             [](const std::complex<double>& v) { return v.imag() == 0.0; });
  if (!m.realFormOnly && realFormOnlyScopes.load() == 0) {
    cholmod_sparse* A =
        cholmod_l_allocate_sparse(n, n, nnz, 1, 1, -1, m.realMatrix ? CHOLMOD_REAL : CHOLMOD_COMPLEX, &m.common);
    if (!A) throw SolverError("CHOLMOD: out of memory allocating a " + std::to_string(n) + " matrix");
    auto* p = static_cast<SuiteSparse_long*>(A->p);
    auto* i = static_cast<SuiteSparse_long*>(A->i);
    auto* x = static_cast<double*>(A->x);
    for (std::int64_t j = 0; j <= n; ++j) p[j] = lower.outerIndexPtr()[j];
    for (std::int64_t k = 0; k < nnz; ++k) {
      i[k] = lower.innerIndexPtr()[k];
      if (m.realMatrix) {
        x[k] = lower.valuePtr()[k].real();
      } else {
        x[2 * k] = lower.valuePtr()[k].real();
        x[2 * k + 1] = lower.valuePtr()[k].imag();
      }
    }
    if (!order.empty() && static_cast<std::int64_t>(order.size()) != n) {
      cholmod_l_free_sparse(&A, &m.common);
      throw SolverError("CHOLMOD: a given order of " + std::to_string(order.size()) + " entries for " +
                        std::to_string(n) + " unknowns");
    }
    const bool ok = m.tryFactor(A, &why, order.empty() ? nullptr : &order);
    cholmod_l_free_sparse(&A, &m.common);
    if (ok) {
      m.factorBytes = m.common.memory_inuse;
      m.peakBytes = m.common.memory_usage;
      return;
    }
    // Not positive definite: the real form has the same eigenvalues (each twice), so it would fail
    // as well, after an analysis and factorization of twice the size (10 s and 250 MB more on a
    // 111K-unknown voxel system whose regularization was then raised).
    if (m.failedColumn >= 0) {
      throw SolverError("CHOLMOD: cannot factor the " + std::to_string(n) + "-unknown Hermitian system: " + why +
                        " (a component without a pinned unknown, or a degenerate mesh region)");
    }
  }
  m.realMatrix = false;
  // Real form [Re -Im; Im Re], lower triangle: blocks (1,1) and (2,2) = lower(Re K), block (2,1) =
  // Im K in full (Im K is antisymmetric: entry (i, j) from the lower triangle, (j, i) negated).
  std::string whyReal;
  {
    const std::int64_t n2 = 2 * n;
    std::vector<std::vector<std::pair<std::int64_t, double>>> cols(n2);
    for (std::int64_t j = 0; j < n; ++j) {
      for (ComplexSparse::InnerIterator it(lower, j); it; ++it) {
        const std::int64_t r = it.row();
        cols[j].emplace_back(r, it.value().real());
        cols[n + j].emplace_back(n + r, it.value().real());
        cols[j].emplace_back(n + r, it.value().imag());
        if (r != j) cols[r].emplace_back(n + j, -it.value().imag());
      }
    }
    std::int64_t total = 0;
    for (auto& c : cols) {
      std::sort(c.begin(), c.end());
      total += static_cast<std::int64_t>(c.size());
    }
    cholmod_sparse* A = cholmod_l_allocate_sparse(n2, n2, total, 1, 1, -1, CHOLMOD_REAL, &m.common);
    if (!A) throw SolverError("CHOLMOD: out of memory allocating the real form");
    auto* p = static_cast<SuiteSparse_long*>(A->p);
    auto* i = static_cast<SuiteSparse_long*>(A->i);
    auto* x = static_cast<double*>(A->x);
    std::int64_t k = 0;
    for (std::int64_t j = 0; j < n2; ++j) {
      p[j] = k;
      for (const auto& [r, v] : cols[j]) i[k] = r, x[k] = v, ++k;
    }
    p[n2] = k;
    cols.clear();
    const bool ok = m.tryFactor(A, &whyReal);
    cholmod_l_free_sparse(&A, &m.common);
    if (ok) {
      m.realForm = true;
      m.factorBytes = m.common.memory_inuse;
      m.peakBytes = m.common.memory_usage;
      return;
    }
  }
  throw SolverError("CHOLMOD: cannot factor the " + std::to_string(n) +
                    "-unknown Hermitian system: " + why + "; real form: " + whyReal +
                    " (a component without a pinned unknown, or a degenerate mesh region)");
}

ComplexVector CholmodFactor::solve(const ComplexVector& rhs) const {
  const Impl& m = *impl_;
  if (m.n == 0) return ComplexVector();
  if (!m.L) throw SolverError("CHOLMOD: solve called without a factor");
  auto& common = const_cast<cholmod_common&>(m.common);
  // The real form stacks (Re, Im) in one column; a real matrix takes them as two columns.
  const std::int64_t rows = m.realForm ? 2 * m.n : m.n;
  const bool real = m.realForm || m.realMatrix;
  cholmod_dense* B = cholmod_l_allocate_dense(rows, m.realMatrix ? 2 : 1, rows, real ? CHOLMOD_REAL : CHOLMOD_COMPLEX,
                                              &common);
  if (!B) throw SolverError("CHOLMOD: out of memory allocating the right-hand side");
  auto* b = static_cast<double*>(B->x);
  for (std::int64_t k = 0; k < m.n; ++k) {
    if (real) {
      b[k] = rhs[k].real();
      b[m.n + k] = rhs[k].imag();
    } else {
      b[2 * k] = rhs[k].real();
      b[2 * k + 1] = rhs[k].imag();
    }
  }
  cholmod_dense* X = cholmod_l_solve(CHOLMOD_A, m.L, B, &common);
  cholmod_l_free_dense(&B, &common);
  if (!X) throw SolverError("CHOLMOD: solve failed (status " + std::to_string(common.status) + ")");
  ComplexVector out(m.n);
  const auto* xv = static_cast<const double*>(X->x);
  for (std::int64_t k = 0; k < m.n; ++k) {
    out[k] = m.realForm || m.realMatrix ? std::complex<double>(xv[k], xv[m.n + k])
                                        : std::complex<double>(xv[2 * k], xv[2 * k + 1]);
  }
  cholmod_l_free_dense(&X, &common);
  return out;
}

std::uint64_t CholmodFactor::factorNonzeros() const { return impl_->nonzeros; }
std::uint64_t CholmodFactor::factorBytes() const { return impl_->factorBytes; }
std::uint64_t CholmodFactor::peakBytes() const { return impl_->peakBytes; }
bool CholmodFactor::usedRealFallback() const { return impl_->realForm; }
void CholmodFactor::setRealFormOnly(bool realFormOnly) { impl_->realFormOnly = realFormOnly; }
bool CholmodFactor::isSupernodal() const { return impl_->L && impl_->L->is_super; }
std::int64_t CholmodFactor::failedColumn() const { return impl_->failedColumn; }

ScopedRealFormOnly::ScopedRealFormOnly() { ++realFormOnlyScopes; }
ScopedRealFormOnly::~ScopedRealFormOnly() { --realFormOnlyScopes; }

}  // namespace seamvox
