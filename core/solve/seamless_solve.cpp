#include "core/solve/assemble.h"
#include "core/solve/seamless_solve.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "core/system/errors.h"
#include "core/solve/cholmod_solver.h"
#include "core/system/stopwatch.h"

namespace seamvox {

namespace {


// Solves the system with the given unknowns fixed; writes the free ones into x.
void solveWithFixed(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                    std::vector<std::complex<double>>& x, SeamlessStats& stats) {
  const RestrictedSystem restricted = restrictSystem(system, fixed, x);
  CholmodFactor factor;
  factor.factor(restricted.lower);
  const ComplexVector y = factor.solve(restricted.rhs);
  for (std::size_t k = 0; k < restricted.freeUnknowns.size(); ++k) {
    if (!std::isfinite(y[k].real()) || !std::isfinite(y[k].imag())) {
      throw SolverError("seamless solve: non-finite value for unknown " +
                        std::to_string(restricted.freeUnknowns[k]));
    }
    x[restricted.freeUnknowns[k]] = y[k];
  }
  stats.factorNonzeros = std::max(stats.factorNonzeros, factor.factorNonzeros());
  stats.factorBytes = std::max(stats.factorBytes, factor.factorBytes());
  stats.factorPeakBytes = std::max(stats.factorPeakBytes, factor.peakBytes());
  stats.realFallback = stats.realFallback || factor.usedRealFallback();
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
  // only components whose seams all have r = 1.
  const std::uint32_t nc = reduction.numComponents;
  std::vector<std::uint8_t> hasFreeTranslation(nc, 0);
  std::vector<std::uint32_t> firstPositional(nc, kInvalidId);
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t c = reduction.unknownComponent[j];
    if (c == kInvalidId || untouched[j]) continue;
    if (j >= reduction.numPositional) hasFreeTranslation[c] = 1;
    if (j < reduction.numPositional && firstPositional[c] == kInvalidId) firstPositional[c] = j;
  }
  std::vector<std::complex<double>>& x = out.unknowns;
  x.assign(n, 0.0);
  std::vector<std::uint8_t> fixed = untouched;
  for (std::uint32_t c = 0; c < nc; ++c) {
    const bool shiftFree = hasFreeTranslation[c] || !reduction.componentHasRotation[c];
    if (shiftFree && firstPositional[c] != kInvalidId) {
      fixed[firstPositional[c]] = 1;
      ++stats.pinnedFirst;
    }
  }
  reportProgress(options.progress, "solve", 0.0);
  start = std::chrono::steady_clock::now();
  solveWithFixed(system, fixed, x, stats);
  stats.secondsFirstSolve = secondsSince(start);
  if (reduction.numTranslational == 0) {
    stats.pinnedSecond = stats.pinnedFirst;
  } else {
    start = std::chrono::steady_clock::now();
    if (options.greedy && options.greedyRounds > 1) {
      // Round the s nearest to an integer first, re-solving the rest in between.
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
        solveWithFixed(system, fixed, x, stats);
      }
    }
    stats.maxRoundingShift = std::max(stats.maxRoundingShift, roundTranslations(reduction, x));
    stats.secondsRound = secondsSince(start);

    start = std::chrono::steady_clock::now();
    fixed = untouched;
    for (std::uint32_t j = reduction.numPositional; j < n; ++j) fixed[j] = 1;
    for (std::uint32_t c = 0; c < nc; ++c) {
      if (!reduction.componentHasRotation[c] && firstPositional[c] != kInvalidId) {
        fixed[firstPositional[c]] = 1;
        ++stats.pinnedSecond;
      }
    }
    // Keep the pinned values of the first solve (0) for the pinned unknowns.
    for (std::uint32_t c = 0; c < nc; ++c) {
      if (firstPositional[c] != kInvalidId && fixed[firstPositional[c]]) x[firstPositional[c]] = 0.0;
    }
    reportProgress(options.progress, "solve", 0.5);
    solveWithFixed(system, fixed, x, stats);
    stats.secondsSecondSolve = secondsSince(start);
  }
  reportProgress(options.progress, "solve", 1.0);
  std::vector<std::complex<double>> s(x.begin() + reduction.numPositional, x.end());
  out.translations = seamTranslations(reduction, s);
  return out;
}

}  // namespace seamvox
