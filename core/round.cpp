#include "core/round.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <numeric>

#include <Eigen/Cholesky>

#include "core/errors.h"
#include "core/solve.h"

namespace seamvox {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void checkFinite(const std::complex<double>& v, std::uint32_t unknown) {
  if (!std::isfinite(v.real()) || !std::isfinite(v.imag())) {
    throw SolverError("seamless solve: non-finite value for unknown " + std::to_string(unknown));
  }
}

// Solves the system with the given unknowns fixed; writes the free ones into x.
void solveWithFixed(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                    std::vector<std::complex<double>>& x, SeamlessStats& stats) {
  const RestrictedSystem restricted = restrictSystem(system, fixed, x);
  CholmodFactor factor;
  factor.factor(restricted.lower);
  const ComplexVector y = factor.solve(restricted.rhs);
  for (std::size_t k = 0; k < restricted.freeUnknowns.size(); ++k) {
    checkFinite(y[k], restricted.freeUnknowns[k]);
    x[restricted.freeUnknowns[k]] = y[k];
  }
  stats.factorNonzeros = std::max(stats.factorNonzeros, factor.factorNonzeros());
  stats.factorBytes = std::max(stats.factorBytes, factor.factorBytes());
  stats.factorPeakBytes = std::max(stats.factorPeakBytes, factor.peakBytes());
  stats.realFallback = stats.realFallback || factor.usedRealFallback();
}

// Right-hand sides per blocked solve A X = B (bounds X to #positional x 64 entries).
constexpr Eigen::Index kSchurBlock = 64;

// The seamless system split as K = [[A, B], [B*, C]] (positional c_0's, then the free s), with
// only A factored (CHOLMOD, once) and s handled densely through the Schur complement
// S = C - B* A^-1 B. A fixes the untouched unknowns and the shift of components without rotation
// (the pins of both solves). Gauge of the first solve: the positional unknowns `gaugePins` (one per
// component whose shift the free translations absorb) are held at 0 by multipliers mu, exactly as
// the pins of a direct solve: [[A, B, E], [B*, C, 0], [E*, 0, 0]] with E their unit columns.
// Eliminating A leaves M = [[S, -B* A^-1 E], [-E* A^-1 B, -G]], G = E* A^-1 E positive definite;
// eliminating mu leaves H = S + M12 G^-1 M21, positive definite: fixing some s (greedy rounding)
// is a principal submatrix of H, so no refactorization.
class SchurSolver {
 public:
  // Factors A (the whole system of the second solve); keeps the right-hand side and [B, E].
  void factorPositional(const LinearSystem& system, std::uint32_t numPositional,
                        const std::vector<std::uint8_t>& fixed,
                        const std::vector<std::uint32_t>& gaugePins, SeamlessStats& stats) {
    const std::vector<std::complex<double>> zeros(system.rhs.size(), 0.0);
    const RestrictedSystem r = restrictSystem(system, fixed, zeros);
    const auto& free = r.freeUnknowns;
    const Eigen::Index na = std::lower_bound(free.begin(), free.end(), numPositional) - free.begin();
    const Eigen::Index k = static_cast<Eigen::Index>(free.size()) - na;
    const Eigen::Index m = static_cast<Eigen::Index>(gaugePins.size());
    positional_.assign(free.begin(), free.begin() + na);
    translational_.assign(free.begin() + na, free.end());
    gaugeRow_.clear();
    for (std::uint32_t pin : gaugePins) {
      gaugeRow_.push_back(std::lower_bound(free.begin(), free.begin() + na, pin) - free.begin());
    }
    factor_.factor(r.lower.topLeftCorner(na, na));
    rhsP_ = r.rhs.head(na);
    rhsS_ = r.rhs.tail(k);
    cLower_ = r.lower.bottomRightCorner(k, k);
    // bext = [B, E]: B from the lower triangle's block (s rows, positional columns), conjugated.
    std::vector<Eigen::Triplet<std::complex<double>>> triplets;
    for (Eigen::Index j = 0; j < na; ++j) {
      for (ComplexSparse::InnerIterator it(r.lower, j); it; ++it) {
        if (it.row() >= na) triplets.emplace_back(j, it.row() - na, std::conj(it.value()));
      }
    }
    for (Eigen::Index t = 0; t < m; ++t) triplets.emplace_back(gaugeRow_[t], k + t, 1.0);
    bext_.resize(na, k + m);
    bext_.setFromTriplets(triplets.begin(), triplets.end());
    stats.factorNonzeros = std::max(stats.factorNonzeros, factor_.factorNonzeros());
    stats.factorBytes = std::max(stats.factorBytes, factor_.factorBytes());
    stats.factorPeakBytes = std::max(stats.factorPeakBytes, factor_.peakBytes());
    stats.realFallback = stats.realFallback || factor_.usedRealFallback();
  }

  // Whether the dense Schur complement (k + m solves with A) is predicted cheaper than factoring
  // the first-solve system: a rough model in seconds on one core (complex factor at ~10 GFlop/s
  // plus ~3 us per unknown for ordering and symbolic analysis; blocked solves at ~5 GFlop/s).
  bool isSchurCheaper() const {
    const double na = static_cast<double>(positional_.size()), d = static_cast<double>(bext_.cols());
    const double factorSeconds = 4.0 * factor_.factorFlops() / 1e10 + 3e-6 * na;
    return d * solveFlopsPerColumn() / 5e9 < factorSeconds;
  }

  // Forms H; false when H (or G) is not positive definite (then the first solve goes direct).
  bool formSchur(SeamlessStats& stats) {
    const Eigen::Index na = static_cast<Eigen::Index>(positional_.size());
    const Eigen::Index k = static_cast<Eigen::Index>(translational_.size());
    const Eigen::Index m = static_cast<Eigen::Index>(gaugeRow_.size());
    const ComplexSparse bextAdjoint = bext_.adjoint();
    const ComplexVector z = factor_.solve(rhsP_);
    ComplexMatrix mFull = ComplexMatrix::Zero(k + m, k + m);
    mFull.topLeftCorner(k, k) = ComplexMatrix(cLower_).selfadjointView<Eigen::Lower>();
    // [B, E]* A^-1 [B, E] = W* W with W = L^-1 P [B, E] (forward solves, then one rank update), or
    // full solves by blocks (see isForwardCheaper).
    const Eigen::Index d = k + m;
    const bool forward = isForwardCheaper();
    ComplexMatrix w = forward ? ComplexMatrix(na, d) : ComplexMatrix();
    for (Eigen::Index j0 = 0; j0 < d; j0 += kSchurBlock) {
      const Eigen::Index b = std::min(kSchurBlock, d - j0);
      const ComplexMatrix rhs(bext_.middleCols(j0, b));
      if (forward) {
        w.middleCols(j0, b) = factor_.solveForward(rhs);
      } else {
        mFull.middleCols(j0, b) -= bextAdjoint * factor_.solve(rhs);
      }
    }
    if (forward) {
      mFull.selfadjointView<Eigen::Lower>().rankUpdate(w.adjoint(), -1.0);
      w = ComplexMatrix();
      mFull = ComplexMatrix(mFull.selfadjointView<Eigen::Lower>());
    } else {
      mFull = 0.5 * (mFull + mFull.adjoint()).eval();
    }
    ComplexVector rd = ComplexVector::Zero(k + m);
    rd.head(k) = rhsS_;
    rd -= bextAdjoint * z;

    m12_ = mFull.topRightCorner(k, m);
    r2_ = rd.tail(m);
    gauge_.compute(-mFull.bottomRightCorner(m, m));
    if (m > 0 && gauge_.info() != Eigen::Success) return false;
    h_ = mFull.topLeftCorner(k, k);
    g_ = rd.head(k);
    if (m > 0) {
      h_ += m12_ * gauge_.solve(m12_.adjoint());
      g_ += m12_ * gauge_.solve(r2_);
    }
    mFull = ComplexMatrix();
    if (Eigen::LLT<ComplexMatrix>(h_).info() != Eigen::Success) return false;

    stats.schurOrder = static_cast<std::uint32_t>(k + m);
    // The dense part held beside the sparse factor: H and its Cholesky factor.
    const std::uint64_t denseBytes = 2 * static_cast<std::uint64_t>(k * k) * sizeof(std::complex<double>);
    stats.factorBytes = factor_.factorBytes() + denseBytes;
    const std::uint64_t forwardBytes =
        forward ? static_cast<std::uint64_t>(na * d) * sizeof(std::complex<double>) : 0;
    stats.factorPeakBytes = factor_.peakBytes() + denseBytes + forwardBytes;
    return true;
  }

  // First solve (and greedy re-solves): the s not in `fixed` free, the gauge pins at 0.
  void solveFree(const std::vector<std::uint8_t>& fixed, std::vector<std::complex<double>>& x) const {
    const Eigen::Index k = static_cast<Eigen::Index>(translational_.size());
    std::vector<Eigen::Index> freeS, fixedS;
    for (Eigen::Index i = 0; i < k; ++i) (fixed[translational_[i]] ? fixedS : freeS).push_back(i);
    ComplexVector s(k);
    for (Eigen::Index i = 0; i < k; ++i) s[i] = x[translational_[i]];
    const Eigen::Index nf = static_cast<Eigen::Index>(freeS.size());
    if (nf > 0) {
      ComplexMatrix hff(nf, nf);
      ComplexVector rhs(nf);
      for (Eigen::Index a = 0; a < nf; ++a) {
        rhs[a] = g_[freeS[a]];
        for (Eigen::Index b = 0; b < nf; ++b) hff(a, b) = h_(freeS[a], freeS[b]);
        for (Eigen::Index f : fixedS) rhs[a] -= h_(freeS[a], f) * s[f];
      }
      const ComplexVector sf = Eigen::LLT<ComplexMatrix>(hff).solve(rhs);
      for (Eigen::Index a = 0; a < nf; ++a) s[freeS[a]] = sf[a];
    }
    ComplexVector dense(k + static_cast<Eigen::Index>(gaugeRow_.size()));
    dense.head(k) = s;
    if (!gaugeRow_.empty()) dense.tail(gaugeRow_.size()) = -gauge_.solve(r2_ - m12_.adjoint() * s);
    writeSolution(dense, x);
  }

  // Second solve: every s fixed at its value in x, no gauge pin.
  void solveFixed(std::vector<std::complex<double>>& x) const {
    ComplexVector dense = ComplexVector::Zero(bext_.cols());
    for (std::size_t i = 0; i < translational_.size(); ++i) dense[i] = x[translational_[i]];
    writeSolution(dense, x);
  }

 private:
  // Forward solves plus the rank update W* W (na d^2 / 2 complex multiply-adds) beat full solves
  // (twice the forward ones) when d < 2 lnz / na, and W (na x d) must fit in the factor's memory.
  bool isForwardCheaper() const {
    const double na = static_cast<double>(positional_.size()), d = static_cast<double>(bext_.cols());
    return factor_.isSupernodal() && !factor_.usedRealFallback() &&
           na * d < 2.0 * static_cast<double>(factor_.factorNonzeros()) &&
           na * d * sizeof(std::complex<double>) <= static_cast<double>(factor_.factorBytes());
  }
  // Real flops per column of [B, E] to form the Schur complement.
  double solveFlopsPerColumn() const {
    const double na = static_cast<double>(positional_.size()), d = static_cast<double>(bext_.cols());
    const double lnz = static_cast<double>(factor_.factorNonzeros());
    return isForwardCheaper() ? 8.0 * lnz + 4.0 * na * d : 16.0 * lnz;
  }

  // c = A^-1 (rhs_p - [B, E] [s; mu]) into x, with s.
  void writeSolution(const ComplexVector& dense, std::vector<std::complex<double>>& x) const {
    const ComplexVector c = factor_.solve(ComplexVector(rhsP_ - bext_ * dense));
    for (std::size_t i = 0; i < positional_.size(); ++i) {
      checkFinite(c[i], positional_[i]);
      x[positional_[i]] = c[i];
    }
    for (std::size_t i = 0; i < translational_.size(); ++i) {
      checkFinite(dense[i], translational_[i]);
      x[translational_[i]] = dense[i];
    }
  }

  CholmodFactor factor_;
  std::vector<std::uint32_t> positional_, translational_;  // global unknown of each row of A, of s
  std::vector<Eigen::Index> gaugeRow_;                     // row in A of each gauge pin
  ComplexSparse bext_;                                     // [B, E], #positional x (k + m)
  ComplexVector rhsP_, rhsS_, g_, r2_;
  ComplexSparse cLower_;  // C, lower triangle
  ComplexMatrix h_, m12_;
  Eigen::LLT<ComplexMatrix> gauge_;
};

// Greedy rounding: rounds the s nearest to an integer first, in batches, calling resolve() (with
// the rounded s fixed) in between.
void roundGreedy(const Reduction& reduction, const RoundOptions& options,
                 std::vector<std::complex<double>>& x, std::vector<std::uint8_t>& fixed,
                 SeamlessStats& stats, const std::function<void()>& resolve) {
  std::vector<std::uint32_t> pending(reduction.numTranslational);
  std::iota(pending.begin(), pending.end(), reduction.numPositional);
  const std::size_t batch =
      std::max<std::size_t>(1, (pending.size() + options.greedyRounds - 1) / options.greedyRounds);
  while (pending.size() > batch) {
    std::sort(pending.begin(), pending.end(), [&](std::uint32_t a, std::uint32_t b) {
      return gaussianIntegerDistance(x[a]) < gaussianIntegerDistance(x[b]);
    });
    for (std::size_t k = 0; k < batch; ++k) {
      const std::uint32_t j = pending[k];
      stats.maxRoundingShift = std::max(stats.maxRoundingShift, gaussianIntegerDistance(x[j]));
      x[j] = roundGaussian(x[j]);
      fixed[j] = 1;
    }
    pending.erase(pending.begin(), pending.begin() + batch);
    resolve();
  }
}

}  // namespace

double roundTranslations(const Reduction& reduction, std::vector<std::complex<double>>& x) {
  double shift = 0.0;
  for (std::uint32_t j = reduction.numPositional; j < reduction.numUnknowns(); ++j) {
    const std::complex<double> r = roundGaussian(x[j]);
    shift = std::max(shift, std::abs(x[j] - r));
    x[j] = r;
  }
  return shift;
}

SeamlessSolution solveSeamless(const Basis& basis, const Reduction& reduction,
                               const RoundOptions& options) {
  SeamlessSolution out;
  SeamlessStats& stats = out.stats;
  const std::uint32_t n = reduction.numUnknowns();
  stats.unknowns = n;
  stats.positional = reduction.numPositional;
  stats.translational = reduction.numTranslational;
  stats.determinedPositions = static_cast<std::uint32_t>(reduction.determinedBasis.size());
  stats.nonUnitConstraints = reduction.nonUnitConstraints;
  stats.components = reduction.numComponents;

  auto start = std::chrono::steady_clock::now();
  AssembleOptions assembleOptions;
  assembleOptions.progress = options.progress;
  const LinearSystem system = assembleSystem(basis, reduction, assembleOptions);
  stats.systemNonzeros = static_cast<std::uint64_t>(system.lower.nonZeros());
  stats.secondsAssemble = secondsSince(start);

  // Unknowns no element touches (zero diagonal) are fixed at 0: they do not affect the map.
  std::vector<std::uint8_t> untouched(n, 1);
  for (int j = 0; j < system.lower.outerSize(); ++j) {
    for (ComplexSparse::InnerIterator it(system.lower, j); it; ++it) {
      if (it.row() == j && it.value().real() > 0.0) untouched[j] = 0;
    }
  }
  // The global shift of a component is free when its translations are free (or it has no
  // rotation at all): first solve pins one positional unknown there. Second solve (s fixed):
  // only components whose seams all have r = 1. Pinned unknowns stay at 0.
  const std::uint32_t nc = reduction.numComponents;
  std::vector<std::uint8_t> hasFreeTranslation(nc, 0);
  std::vector<std::uint32_t> firstPositional(nc, kInvalidId);
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t c = reduction.unknownComponent[j];
    if (c == kInvalidId || untouched[j]) continue;
    if (j >= reduction.numPositional) hasFreeTranslation[c] = 1;
    if (j < reduction.numPositional && firstPositional[c] == kInvalidId) firstPositional[c] = j;
  }
  std::vector<std::uint8_t> pinnedBoth = untouched;  // untouched, and no-rotation shifts
  std::vector<std::uint32_t> gaugePins;               // pinned in the first solve only
  for (std::uint32_t c = 0; c < nc; ++c) {
    if (firstPositional[c] == kInvalidId) continue;
    if (!reduction.componentHasRotation[c]) {
      pinnedBoth[firstPositional[c]] = 1;
      ++stats.pinnedSecond;
    } else if (hasFreeTranslation[c]) {
      gaugePins.push_back(firstPositional[c]);
    }
  }
  stats.pinnedFirst = stats.pinnedSecond + static_cast<std::uint32_t>(gaugePins.size());
  if (reduction.numTranslational == 0) stats.pinnedSecond = stats.pinnedFirst;
  std::uint32_t denseOrder = static_cast<std::uint32_t>(gaugePins.size());
  for (std::uint32_t j = reduction.numPositional; j < n; ++j) denseOrder += untouched[j] ? 0 : 1;

  std::vector<std::complex<double>>& x = out.unknowns;
  x.assign(n, 0.0);
  reportProgress(options.progress, "solve", 0.0);
  start = std::chrono::steady_clock::now();
  // The positional block A (the second-solve system) is factored once. First solve: through the
  // Schur complement over s when it is small and predicted cheaper, else a direct factorization.
  // Above maxSchurOrder the order is that of two direct solves (one factor alive at a time).
  SchurSolver schur;
  const bool positionalFirst = denseOrder <= options.maxSchurOrder;
  if (positionalFirst) {
    schur.factorPositional(system, reduction.numPositional, pinnedBoth, gaugePins, stats);
  }
  const bool useSchur = positionalFirst && (denseOrder == 0 || schur.isSchurCheaper()) &&
                        schur.formSchur(stats);
  std::vector<std::uint8_t> fixed = pinnedBoth;
  for (std::uint32_t pin : gaugePins) fixed[pin] = 1;
  const auto solveFirst = [&] {
    if (useSchur) {
      schur.solveFree(fixed, x);
    } else {
      solveWithFixed(system, fixed, x, stats);
    }
  };
  solveFirst();
  stats.secondsFirstSolve = secondsSince(start);
  if (reduction.numTranslational > 0) {
    start = std::chrono::steady_clock::now();
    if (options.greedy && options.greedyRounds > 1) {
      roundGreedy(reduction, options, x, fixed, stats, solveFirst);
    }
    stats.maxRoundingShift = std::max(stats.maxRoundingShift, roundTranslations(reduction, x));
    stats.secondsRound = secondsSince(start);

    start = std::chrono::steady_clock::now();
    reportProgress(options.progress, "solve", 0.5);
    if (!positionalFirst) {
      schur.factorPositional(system, reduction.numPositional, pinnedBoth, gaugePins, stats);
    }
    schur.solveFixed(x);
    stats.secondsSecondSolve = secondsSince(start);
  }
  reportProgress(options.progress, "solve", 1.0);
  std::vector<std::complex<double>> s(x.begin() + reduction.numPositional, x.end());
  out.translations = seamTranslations(reduction, s);
  return out;
}

}  // namespace seamvox
