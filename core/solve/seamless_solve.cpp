#include "core/solve/assemble.h"
#include "core/solve/seamless_solve.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "core/system/errors.h"
#include "core/solve/cholmod_solver.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;

/// A factorization that failed inside one solve: the stage, an unknown (full numbering) of the
/// block where CHOLMOD stopped (kInvalidId when not known) and CHOLMOD's message.
struct FactorFailure {
  const char* stage;
  std::uint32_t unknown;
  std::string message;
};

/// The restricted system of one solve, factored. Throws FactorFailure.
struct FactoredSystem {
  RestrictedSystem restricted;
  CholmodFactor factor;
};

/// An elimination order in the full numbering (FillOrder::unknowns; empty: none).
struct FillOrder {
  std::vector<std::uint32_t> unknowns;
};

/// The restricted system's order from a full-numbering order: its free unknowns in that order,
/// those the order does not hold last. Empty when order is empty.
void factorSystem(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                  const std::vector<Complex>& x, const std::vector<ComplexTriplet>& extraLower,
                  const char* stage, FactoredSystem& out, SeamlessStats& stats,
                  const FillOrder& givenOrder = {}, FillOrder* usedOrder = nullptr) {
  out.restricted = restrictSystem(system, fixed, x, extraLower);
  try {
    out.factor.factor(out.restricted.lower,
                      restrictOrder(givenOrder.unknowns, out.restricted.freeUnknowns, static_cast<std::uint32_t>(x.size())));
  } catch (const SolverError& e) {
    const std::int64_t column = out.factor.failedColumn();
    throw FactorFailure{stage, column >= 0 ? out.restricted.freeUnknowns[column] : kInvalidId, e.what()};
  }
  stats.factorNonzeros = std::max(stats.factorNonzeros, out.factor.factorNonzeros());
  stats.factorBytes = std::max(stats.factorBytes, out.factor.factorBytes());
  stats.factorPeakBytes = std::max(stats.factorPeakBytes, out.factor.peakBytes());
  stats.realFallback = stats.realFallback || out.factor.usedRealFallback();
  if (usedOrder) {
    usedOrder->unknowns.clear();
    for (std::int64_t k : out.factor.permutation()) usedOrder->unknowns.push_back(out.restricted.freeUnknowns[k]);
  }
}

/// Solves the factored system and writes the free unknowns into x.
void solveInto(const FactoredSystem& factored, std::vector<Complex>& x) {
  const RestrictedSystem& restricted = factored.restricted;
  const ComplexVector y = factored.factor.solve(restricted.rhs);
  for (std::size_t k = 0; k < restricted.freeUnknowns.size(); ++k) {
    if (!std::isfinite(y[k].real()) || !std::isfinite(y[k].imag())) {
      throw SolverError("seamless solve: non-finite value for unknown " +
                        std::to_string(restricted.freeUnknowns[k]));
    }
    x[restricted.freeUnknowns[k]] = y[k];
  }
}

// Solves the system with the given unknowns fixed; writes the free ones into x. givenOrder and
// usedOrder as in factorSystem.
void solveWithFixed(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                    std::vector<Complex>& x, const char* stage, SeamlessStats& stats,
                    const FillOrder& givenOrder = {}, FillOrder* usedOrder = nullptr) {
  FactoredSystem factored;
  factorSystem(system, fixed, x, {}, stage, factored, stats, givenOrder, usedOrder);
  solveInto(factored, x);
}

/// A component whose global shift is free while none of its positional unknowns is (every
/// vertex a cone): anchored through the row of one of its domains (P row, translations only).
struct ShiftAnchor {
  std::uint32_t component = 0;
  std::vector<std::pair<std::uint32_t, Complex>> row;
  double weight = 0.0;
};

/// The anchors' penalty weight |a x|^2 (lower triangle, full numbering). The shift of such a
/// component moves every domain coefficient by the same c, so a.v = 1 along the kernel v of K:
/// K + w a* a is definite and its minimiser has a x = 0 and the energy of K's minimisers.
std::vector<ComplexTriplet> anchorPenalty(const std::vector<ShiftAnchor>& anchors) {
  std::vector<ComplexTriplet> out;
  for (const ShiftAnchor& anchor : anchors) {
    for (const auto& [i, ai] : anchor.row) {
      for (const auto& [j, aj] : anchor.row) {
        if (i >= j) out.emplace_back(int(i), int(j), anchor.weight * std::conj(ai) * aj);
      }
    }
  }
  return out;
}

/// Which components need an anchor and the domain row each takes (the first one in P).
std::vector<ShiftAnchor> findShiftAnchors(const Reduction& reduction, const LinearSystem& system,
                                          const std::vector<std::uint8_t>& needsAnchor,
                                          const std::vector<std::uint8_t>& fixed) {
  std::vector<ShiftAnchor> anchors;
  std::vector<std::uint8_t> done(needsAnchor.size(), 0);
  const ReducedMap& P = reduction.map;
  for (std::size_t d = 0; d + 1 < P.rowStart.size(); ++d) {
    if (P.rowStart[d] == P.rowStart[d + 1]) continue;
    const std::uint32_t c = reduction.unknownComponent[P.column[P.rowStart[d]]];
    if (c == kInvalidId || !needsAnchor[c] || done[c]) continue;
    ShiftAnchor anchor;
    anchor.component = c;
    double diagonal = 0.0, norm2 = 0.0;
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (fixed[j]) continue;
      anchor.row.emplace_back(j, P.value[k]);
      diagonal = std::max(diagonal, system.lower.coeff(int(j), int(j)).real());
      norm2 += std::norm(P.value[k]);
    }
    if (anchor.row.empty() || !(norm2 > 0.0)) continue;
    anchor.weight = (diagonal > 0.0 ? diagonal : 1.0) / norm2;
    done[c] = 1;
    anchors.push_back(std::move(anchor));
  }
  return anchors;
}

/// First solve with anchored components: solves with the anchors' penalty, then moves each
/// anchored component along its shift (the kernel v of K, from one more solve with the same
/// factor) until one of its translations is an integer, and fixes that translation: the later
/// solves see a plain pin, as for components pinned through a positional unknown.
void solveAnchored(const LinearSystem& system, const Reduction& reduction,
                   const std::vector<ShiftAnchor>& anchors, std::vector<std::uint8_t>& fixed,
                   std::vector<Complex>& x, SeamlessStats& stats, FillOrder* usedOrder) {
  FactoredSystem factored;
  factorSystem(system, fixed, x, anchorPenalty(anchors), "first solve", factored, stats, {}, usedOrder);
  solveInto(factored, x);
  const std::vector<std::uint32_t>& free = factored.restricted.freeUnknowns;
  // (K + w a* a) v = w a*: v is the shift by 1 of every anchored component (a v = 1, K v = 0).
  ComplexVector rhs = ComplexVector::Zero(static_cast<Eigen::Index>(free.size()));
  std::vector<std::int64_t> restrictedIndex(reduction.numUnknowns(), -1);
  for (std::size_t k = 0; k < free.size(); ++k) restrictedIndex[free[k]] = std::int64_t(k);
  for (const ShiftAnchor& anchor : anchors) {
    for (const auto& [j, a] : anchor.row) rhs[restrictedIndex[j]] += anchor.weight * std::conj(a);
  }
  const ComplexVector v = factored.factor.solve(rhs);
  std::vector<std::int64_t> anchorOf(reduction.numComponents, -1);
  for (std::size_t i = 0; i < anchors.size(); ++i) anchorOf[anchors[i].component] = std::int64_t(i);
  std::vector<std::int64_t> pin(anchors.size(), -1);  // restricted index of the largest |v|
  for (std::size_t k = 0; k < free.size(); ++k) {
    const std::uint32_t c = reduction.unknownComponent[free[k]];
    if (c == kInvalidId || anchorOf[c] < 0 || free[k] < reduction.numPositional) continue;
    std::int64_t& p = pin[anchorOf[c]];
    if (p < 0 || std::abs(v[k]) > std::abs(v[p])) p = std::int64_t(k);
  }
  std::vector<Complex> shift(anchors.size(), 0.0);
  for (std::size_t i = 0; i < anchors.size(); ++i) {
    if (pin[i] < 0 || !(std::abs(v[pin[i]]) > 1e-9)) {
      throw FactorFailure{"first solve", anchors[i].row.front().first,
                          "the shift of the component does not move its translations"};
    }
    const std::uint32_t j = free[pin[i]];
    shift[i] = (roundGaussian(x[j]) - x[j]) / v[pin[i]];
  }
  for (std::size_t k = 0; k < free.size(); ++k) {
    const std::uint32_t c = reduction.unknownComponent[free[k]];
    if (c != kInvalidId && anchorOf[c] >= 0) x[free[k]] += shift[anchorOf[c]] * v[k];
  }
  for (std::size_t i = 0; i < anchors.size(); ++i) {
    const std::uint32_t j = free[pin[i]];
    x[j] = roundGaussian(x[j]);
    fixed[j] = 1;
  }
}

/// Per component: its first positional unknown that is not fixed and whether a translation is
/// free; from them the pins of the first solve.
struct ComponentPins {
  std::vector<std::uint8_t> hasFreeTranslation;
  std::vector<std::uint32_t> firstPositional;
};

ComponentPins findPins(const Reduction& reduction, const std::vector<std::uint8_t>& excluded) {
  const std::uint32_t nc = reduction.numComponents;
  ComponentPins pins;
  pins.hasFreeTranslation.assign(nc, 0);
  pins.firstPositional.assign(nc, kInvalidId);
  for (std::uint32_t j = 0; j < reduction.numUnknowns(); ++j) {
    const std::uint32_t c = reduction.unknownComponent[j];
    if (c == kInvalidId || excluded[j]) continue;
    if (j >= reduction.numPositional) pins.hasFreeTranslation[c] = 1;
    if (j < reduction.numPositional && pins.firstPositional[c] == kInvalidId) pins.firstPositional[c] = j;
  }
  return pins;
}

/// The second solve taken from the first one's factor when it fixes at most this many unknowns
/// more: one solve with the factor per such unknown, against a factorization.
constexpr std::size_t kSecondFromFirstUnknowns = 24;

/// The second solve's fixed unknowns (excluded, every translation, and the pins of components
/// whose seams all have r = 1).
std::vector<std::uint8_t> secondSolveFixed(const Reduction& reduction, const std::vector<std::uint8_t>& excluded,
                                           const ComponentPins& pins) {
  std::vector<std::uint8_t> fixed = excluded;
  for (std::uint32_t j = reduction.numPositional; j < reduction.numUnknowns(); ++j) fixed[j] = 1;
  for (std::uint32_t c = 0; c < reduction.numComponents; ++c) {
    const std::uint32_t first = pins.firstPositional[c];
    if (!reduction.componentHasRotation[c] && first != kInvalidId) fixed[first] = 1;
  }
  return fixed;
}

/// The second solve from the first one's factor A (free unknowns F): the minimiser with the
/// unknowns D of F that the second solve fixes held at their values t in x is
/// y = y1 + Z mu, Z = A^-1 E (E: the columns of D), (E^T Z) mu = t - y1_D, y1 the first solution
/// (firstX on F). Exact up to rounding; |D| solves with the factor instead of a factorization.
/// Writes the free unknowns of the second solve into x; false (x unchanged) when E^T Z is not
/// invertible in floating point.
bool secondFromFirst(const FactoredSystem& first, const std::vector<std::uint8_t>& fixedSecond,
                     const std::vector<Complex>& firstX, std::vector<Complex>& x) {
  const std::vector<std::uint32_t>& free = first.restricted.freeUnknowns;
  const Eigen::Index nf = static_cast<Eigen::Index>(free.size());
  std::vector<Eigen::Index> held;  // positions in F of D
  for (Eigen::Index k = 0; k < nf; ++k) {
    if (fixedSecond[free[k]]) held.push_back(k);
  }
  const Eigen::Index m = static_cast<Eigen::Index>(held.size());
  Eigen::MatrixXcd Z(nf, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    ComplexVector e = ComplexVector::Zero(nf);
    e[held[i]] = 1.0;
    Z.col(i) = first.factor.solve(e);
  }
  Eigen::MatrixXcd S(m, m);
  Eigen::VectorXcd gap(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    S.row(i) = Z.row(held[i]);
    gap[i] = x[free[held[i]]] - firstX[free[held[i]]];
  }
  const Eigen::FullPivLU<Eigen::MatrixXcd> lu(S);
  if (m > 0 && !lu.isInvertible()) return false;
  const Eigen::VectorXcd mu = m > 0 ? Eigen::VectorXcd(lu.solve(gap)) : Eigen::VectorXcd();
  const Eigen::VectorXcd y = m > 0 ? Eigen::VectorXcd(Z * mu) : Eigen::VectorXcd::Zero(nf);
  for (Eigen::Index k = 0; k < nf; ++k) {
    if (!std::isfinite(y[k].real()) || !std::isfinite(y[k].imag())) return false;
  }
  for (Eigen::Index k = 0; k < nf; ++k) {
    if (!fixedSecond[free[k]]) x[free[k]] = firstX[free[k]] + y[k];
  }
  return true;
}

/// First solve, rounding and second solve with the unknowns in `excluded` fixed at their values
/// in `initial` (0, or solved apart). Throws FactorFailure.
void solveRounded(const LinearSystem& system, const Reduction& reduction,
                  const std::vector<std::uint8_t>& excluded, const std::vector<Complex>& initial,
                  const RoundOptions& options, SeamlessSolution& out) {
  SeamlessStats& stats = out.stats;
  const std::uint32_t n = reduction.numUnknowns(), nc = reduction.numComponents;
  stats.pinnedFirst = stats.pinnedSecond = stats.anchoredComponents = 0;
  out.anchoredComponents.clear();
  stats.maxRoundingShift = 0.0;
  // The global shift of a component is free when its translations are free (or it has no
  // rotation at all): the first solve pins one positional unknown there, or anchors the shift
  // through a translation when every positional unknown is determined (solveAnchored). Second
  // solve (s fixed): pins only on components whose seams all have r = 1.
  const ComponentPins pins = findPins(reduction, excluded);
  std::vector<Complex>& x = out.unknowns;
  x = initial;
  std::vector<std::uint8_t> fixed = excluded;
  std::vector<std::uint8_t> needsAnchor(nc, 0);
  for (std::uint32_t c = 0; c < nc; ++c) {
    const bool shiftFree = pins.hasFreeTranslation[c] || !reduction.componentHasRotation[c];
    if (!shiftFree) continue;
    if (pins.firstPositional[c] != kInvalidId) {
      fixed[pins.firstPositional[c]] = 1;
      ++stats.pinnedFirst;
    } else if (pins.hasFreeTranslation[c]) {
      needsAnchor[c] = 1;
    }
  }
  reportProgress(options.progress, "solve", 0.0);
  auto start = std::chrono::steady_clock::now();
  const std::vector<ShiftAnchor> anchors = findShiftAnchors(reduction, system, needsAnchor, fixed);
  // The first solve's fill-reducing order serves the later ones: their systems are its system
  // with a few unknowns fixed or freed, and the ordering is half the cost of a factorization.
  FillOrder order;
  // When the second solve only fixes a few unknowns more than the first (its translations, in a
  // local re-solve), the first factor is kept and serves it (secondFromFirst).
  const bool lines = options.lines && !options.lines->empty();
  const std::vector<std::uint8_t> fixedSecond = secondSolveFixed(reduction, excluded, pins);
  bool keepFirst = options.reuseFirstFactor && anchors.empty() && !lines && reduction.numTranslational > 0 &&
                   !(options.greedy && options.greedyRounds > 1);
  std::size_t moreFixed = 0;
  for (std::uint32_t j = 0; j < n && keepFirst; ++j) {
    if (fixed[j] && !fixedSecond[j]) keepFirst = false;
    moreFixed += fixedSecond[j] && !fixed[j];
  }
  keepFirst = keepFirst && moreFixed <= kSecondFromFirstUnknowns;
  FactoredSystem first;
  std::vector<Complex> firstX;
  if (anchors.empty()) {
    FillOrder given;
    if (options.firstOrder) given.unknowns = *options.firstOrder;
    if (keepFirst) {
      factorSystem(system, fixed, x, {}, "first solve", first, stats, given, &order);
      solveInto(first, x);
      firstX = x;
    } else {
      solveWithFixed(system, fixed, x, "first solve", stats, given, &order);
    }
    if (options.firstOrder) *options.firstOrder = order.unknowns;
  } else {
    solveAnchored(system, reduction, anchors, fixed, x, stats, &order);
    stats.anchoredComponents = static_cast<std::uint32_t>(anchors.size());
    for (const ShiftAnchor& anchor : anchors) out.anchoredComponents.push_back(anchor.component);
    stats.pinnedFirst += stats.anchoredComponents;
  }
  stats.secondsFirstSolve = secondsSince(start);
  LineConstraintStats ownLineStats;
  LineConstraintStats& lineStats = options.lineStats ? *options.lineStats : ownLineStats;
  if (reduction.numTranslational == 0) {
    stats.pinnedSecond = stats.pinnedFirst;
    if (lines) solveWithLineConstraints(system, reduction, fixed, x, *options.lines, lineStats);
    return;
  }
  start = std::chrono::steady_clock::now();
  if (options.greedy && options.greedyRounds > 1) {
    // Round the s nearest to an integer first, re-solving the rest in between.
    std::vector<std::uint32_t> pending;
    for (std::uint32_t j = reduction.numPositional; j < n; ++j) {
      if (!fixed[j]) pending.push_back(j);
    }
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
      solveWithFixed(system, fixed, x, "greedy rounding", stats, order);
    }
  }
  stats.maxRoundingShift = std::max(stats.maxRoundingShift, roundTranslations(reduction, x));
  stats.secondsRound = secondsSince(start);

  start = std::chrono::steady_clock::now();
  fixed = fixedSecond;
  for (std::uint32_t c = 0; c < nc; ++c) {
    const std::uint32_t pin = pins.firstPositional[c];
    if (reduction.componentHasRotation[c] || pin == kInvalidId) continue;
    // Keep the pinned value of the first solve (0).
    if (keepFirst && x[pin] != Complex(0.0)) keepFirst = false;
    x[pin] = 0.0;
    ++stats.pinnedSecond;
  }
  reportProgress(options.progress, "solve", 0.5);
  if (lines) {
    solveWithLineConstraints(system, reduction, fixed, x, *options.lines, lineStats);
  } else if (keepFirst && secondFromFirst(first, fixed, firstX, x)) {
    stats.secondFromFirstFactor = true;
  } else {
    first = FactoredSystem();  // freed before the second factorization
    solveWithFixed(system, fixed, x, "second solve", stats, order);
  }
  stats.secondsSecondSolve = secondsSince(start);
}

/// Components solved apart: at most this many unknowns, none of them a translation.
constexpr std::uint32_t kApartUnknowns = 64;
/// A pivot below this fraction of its diagonal entry: the block is singular in floating point
/// (a function that is a combination of the others on the component), not solved.
constexpr double kApartPivotTolerance = 1e-12;

/// Components solved apart from the global factorization, and those left unsolved there.
struct ApartResult {
  std::uint32_t solved = 0, pins = 0;
  std::vector<std::uint32_t> unsolved;
  std::vector<std::string> reasons;
};

/// The components with at most kApartUnknowns unknowns and no translation (islands a few cells
/// across: a scan carries thousands to millions of specks), other than `largest`, each solved on
/// its own: no entry of the system couples two components, so its block is its whole system
/// (dense Cholesky, pinned as solveRounded pins a component without translations). Their
/// unknowns join `excluded` with the values in x. A block that is not positive definite (or has
/// a pivot below kApartPivotTolerance) leaves its component unsolved (at 0) at the cost of its
/// block, not of a global factorization per such component (100K specks of two triangles: 84
/// of them, 85 factorizations of 1M unknowns).
ApartResult solveComponentsApart(const LinearSystem& system, const Reduction& reduction, std::uint32_t largest,
                                 std::vector<std::uint8_t>& excluded, std::vector<Complex>& x) {
  const std::uint32_t n = reduction.numUnknowns(), nc = reduction.numComponents;
  std::vector<std::uint32_t> count(nc + 1, 0);
  std::vector<std::uint8_t> apart(nc, 1);
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t c = reduction.unknownComponent[j];
    if (c == kInvalidId || excluded[j]) continue;
    ++count[c];
    if (j >= reduction.numPositional) apart[c] = 0;
  }
  for (std::uint32_t c = 0; c < nc; ++c) apart[c] = apart[c] && c != largest && count[c] > 0 && count[c] <= kApartUnknowns;
  // Each apart component's unknowns, increasing (component c from start[c]).
  std::vector<std::uint32_t> start(nc + 1, 0);
  for (std::uint32_t c = 0; c < nc; ++c) start[c + 1] = start[c] + (apart[c] ? count[c] : 0);
  std::vector<std::uint32_t> unknowns(start[nc]), filled(start.begin(), start.end() - 1);
  std::vector<std::uint32_t> local(n, kInvalidId);  // an apart unknown's rank in its component
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t c = reduction.unknownComponent[j];
    if (c == kInvalidId || excluded[j] || !apart[c]) continue;
    local[j] = filled[c] - start[c];
    unknowns[filled[c]++] = j;
  }
  std::vector<std::uint32_t> apartList;
  for (std::uint32_t c = 0; c < nc; ++c) {
    if (apart[c]) apartList.push_back(c);
  }
  std::vector<std::uint8_t> failed(apartList.size(), 0);
  parallelForEach(apartList.size(), 256, [&](std::uint64_t k) {
    const std::uint32_t c = apartList[k];
    const std::uint32_t* own = unknowns.data() + start[c];
    const int m = static_cast<int>(count[c]);
    // A component without rotation has a free shift: its first unknown stays at 0.
    const int pin = reduction.componentHasRotation[c] ? -1 : 0;
    const auto row = [&](int i) { return pin < 0 ? i : i - (i > pin); };
    const int size = m - (pin >= 0);
    if (size == 0) return;
    Eigen::MatrixXcd block = Eigen::MatrixXcd::Zero(size, size);
    Eigen::VectorXcd rhs(size);
    for (int i = 0; i < m; ++i) {
      if (i == pin) continue;
      rhs[row(i)] = system.rhs[own[i]];
      for (ComplexSparse::InnerIterator it(system.lower, own[i]); it; ++it) {
        const std::uint32_t r = local[it.row()];
        if (r == kInvalidId || static_cast<int>(r) == pin) continue;
        block(row(static_cast<int>(r)), row(i)) = it.value();  // lower: r >= i
      }
    }
    const Eigen::LLT<Eigen::MatrixXcd, Eigen::Lower> llt(block);
    bool definite = llt.info() == Eigen::Success;
    for (int i = 0; definite && i < size; ++i) {
      definite = std::norm(llt.matrixLLT()(i, i)) >= kApartPivotTolerance * block(i, i).real();
    }
    const Eigen::VectorXcd y = definite ? Eigen::VectorXcd(llt.solve(rhs)) : Eigen::VectorXcd();
    if (!definite || !y.allFinite()) {
      failed[k] = 1;
      return;
    }
    for (int i = 0; i < m; ++i) x[own[i]] = i == pin ? Complex(0.0) : y[row(i)];
  });
  ApartResult out;
  for (std::size_t k = 0; k < apartList.size(); ++k) {
    const std::uint32_t c = apartList[k];
    for (std::uint32_t i = start[c]; i < start[c + 1]; ++i) {
      excluded[unknowns[i]] = 1;
      if (failed[k]) x[unknowns[i]] = 0.0;
    }
    if (failed[k]) {
      out.unsolved.push_back(c);
      out.reasons.push_back("seamless solve, component " + std::to_string(c) + " of " + std::to_string(nc) + " (" +
                            std::to_string(count[c]) + " unknowns, solved apart): not positive definite");
    } else {
      ++out.solved;
      out.pins += !reduction.componentHasRotation[c];
    }
  }
  return out;
}

/// The message of a failure that is not confined to a component.
std::string failureMessage(const FactorFailure& failure, const Reduction& reduction,
                           const std::vector<std::uint32_t>& componentUnknowns) {
  std::string where = std::string("seamless solve, ") + failure.stage;
  const std::uint32_t c =
      failure.unknown != kInvalidId ? reduction.unknownComponent[failure.unknown] : kInvalidId;
  if (c != kInvalidId) {
    where += ", component " + std::to_string(c) + " of " + std::to_string(reduction.numComponents) +
             " (" + std::to_string(componentUnknowns[c]) + " unknowns)";
  }
  return where + ": " + failure.message;
}

}  // namespace

double roundTranslations(const Reduction& reduction, std::vector<Complex>& x) {
  double shift = 0.0;
  for (std::uint32_t j = reduction.numPositional; j < reduction.numUnknowns(); ++j) {
    const Complex r = roundGaussian(x[j]);
    shift = std::max(shift, std::abs(x[j] - r));
    x[j] = r;
  }
  return shift;
}

SeamlessSolution solveSeamless(const Basis& basis, const Reduction& reduction,
                               const RoundOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  AssembleOptions assembleOptions;
  assembleOptions.progress = options.progress;
  const LinearSystem system = assembleSystem(basis, reduction, assembleOptions);
  const double seconds = secondsSince(start);
  SeamlessSolution out = solveSeamlessSystem(system, reduction, options);
  out.stats.secondsAssemble = seconds;
  return out;
}

SeamlessSolution solveSeamlessSystem(const LinearSystem& system, const Reduction& reduction,
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
  if (system.lower.rows() != static_cast<Eigen::Index>(n) || system.rhs.size() != static_cast<Eigen::Index>(n)) {
    throw InputError("seamless solve: a system of " + std::to_string(system.lower.rows()) + " unknowns for a reduction of " +
                     std::to_string(n));
  }
  stats.systemNonzeros = static_cast<std::uint64_t>(system.lower.nonZeros());

  // Unknowns no element touches (zero diagonal) are fixed at 0: they do not affect the map.
  std::vector<std::uint8_t> excluded(n, 1);
  for (int j = 0; j < system.lower.outerSize(); ++j) {
    for (ComplexSparse::InnerIterator it(system.lower, j); it; ++it) {
      if (it.row() == j && it.value().real() > 0.0) excluded[j] = 0;
    }
  }
  std::vector<std::uint32_t> componentUnknowns(reduction.numComponents, 0);
  for (std::uint32_t j = 0; j < n; ++j) {
    if (reduction.unknownComponent[j] != kInvalidId) ++componentUnknowns[reduction.unknownComponent[j]];
  }
  const std::uint32_t largest = static_cast<std::uint32_t>(
      std::max_element(componentUnknowns.begin(), componentUnknowns.end()) - componentUnknowns.begin());
  auto leaveUnsolved = [&](std::uint32_t c, std::string reason) {
    out.unsolvedComponents.push_back(c);
    out.unsolvedReasons.push_back(std::move(reason));
    for (std::uint32_t j = 0; j < n; ++j) {
      if (reduction.unknownComponent[j] == c) excluded[j] = 1;
    }
  };
  if (options.failsToFactor) {
    for (std::uint32_t c = 0; c < reduction.numComponents; ++c) {
      if (c != largest && options.failsToFactor(componentUnknowns[c])) {
        leaveUnsolved(c, "component " + std::to_string(c) + ": failed by the test hook");
      }
    }
  }
  std::vector<Complex> initial(n, 0.0);
  const ApartResult apart =
      options.solveApart ? solveComponentsApart(system, reduction, largest, excluded, initial) : ApartResult();
  if (!options.dropUnsolvable && !apart.unsolved.empty()) throw SolverError(apart.reasons.front());
  out.unsolvedComponents.insert(out.unsolvedComponents.end(), apart.unsolved.begin(), apart.unsolved.end());
  out.unsolvedReasons.insert(out.unsolvedReasons.end(), apart.reasons.begin(), apart.reasons.end());
  stats.componentsApart = apart.solved;
  // A component that cannot be factored is excluded (left at 0) and the rest solved again.
  for (;;) {
    try {
      solveRounded(system, reduction, excluded, initial, options, out);
      stats.pinnedFirst += apart.pins;
      stats.pinnedSecond += apart.pins;
      break;
    } catch (const FactorFailure& failure) {
      const std::uint32_t c =
          failure.unknown != kInvalidId ? reduction.unknownComponent[failure.unknown] : kInvalidId;
      if (!options.dropUnsolvable || c == kInvalidId || c == largest ||
          std::count(out.unsolvedComponents.begin(), out.unsolvedComponents.end(), c) != 0) {
        throw SolverError(failureMessage(failure, reduction, componentUnknowns));
      }
      leaveUnsolved(c, failureMessage(failure, reduction, componentUnknowns));
    }
  }
  stats.unsolvedComponents = static_cast<std::uint32_t>(out.unsolvedComponents.size());
  reportProgress(options.progress, "solve", 1.0);
  std::vector<Complex> s(out.unknowns.begin() + reduction.numPositional, out.unknowns.end());
  out.translations = seamTranslations(reduction, s);
  return out;
}

}  // namespace seamvox
