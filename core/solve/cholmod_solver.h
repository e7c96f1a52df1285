#pragma once
/// Owning CHOLMOD factorization of a Hermitian positive definite complex matrix (DESIGN
/// section 8). CHOLMOD's headers stay in solve.cpp.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/solve/assemble.h"

namespace seamvox {

/// Supernodal complex Hermitian Cholesky (a matrix whose entries are all real: real symmetric,
/// in real arithmetic); falls back to the real 2n x 2n form [Re -Im; Im Re] only when the
/// complex factorization fails. Move-only.
class CholmodFactor {
 public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(CholmodFactor&&) noexcept;
  CholmodFactor& operator=(CholmodFactor&&) noexcept;
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// Analyses and factors the matrix given by its lower triangle. Throws SolverError (not
  /// positive definite, out of memory) naming the column where it failed.
  void factor(const ComplexSparse& lower);
  /// The same with a fill-reducing order given (a permutation of 0..n-1, e.g. a restriction of
  /// a similar system's permutation()): the analysis skips AMD and METIS, about half the time
  /// of factoring a grid-sized system. An empty order analyses as factor(lower) does.
  void factor(const ComplexSparse& lower, const std::vector<std::int64_t>& order);
  /// The fill-reducing order of the last complex factorization (empty for the real form).
  std::vector<std::int64_t> permutation() const;
  /// Solves K x = rhs with the last factor.
  ComplexVector solve(const ComplexVector& rhs) const;

  std::uint64_t factorNonzeros() const;  ///< entries of L (complex or real form)
  std::uint64_t factorBytes() const;     ///< memory held by the factor
  std::uint64_t peakBytes() const;       ///< CHOLMOD's peak memory during analyse + factor
  bool usedRealFallback() const;
  /// Test hook: factor() skips the complex factorization and goes to the real form directly.
  void setRealFormOnly(bool realFormOnly);
  bool isSupernodal() const;
  /// After factor() threw for a matrix that is not positive definite: a column (in the
  /// matrix's own numbering) of the block where the factorization stopped; -1 otherwise.
  std::int64_t failedColumn() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Test hook for whole pipelines: while one lives, every CholmodFactor::factor() in the process
/// goes to the real form directly, as setRealFormOnly does for one factor.
class ScopedRealFormOnly {
 public:
  ScopedRealFormOnly();
  ~ScopedRealFormOnly();
  ScopedRealFormOnly(const ScopedRealFormOnly&) = delete;
  ScopedRealFormOnly& operator=(const ScopedRealFormOnly&) = delete;
};

}  // namespace seamvox
