#pragma once
/// The seamless solve (DESIGN sections 8-9): assemble, first solve with the translations s free
/// (one pinned positional unknown per component), rounding of s to Gaussian integers (direct or
/// greedy), second solve with s fixed (pinned only on components whose seams all have r = 1).
#include <complex>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/basis/basis.h"
#include "core/system/progress.h"
#include "core/basis/reduce.h"
#include "core/solve/line_constraints.h"

namespace seamvox {

struct RoundOptions {
  /// false: round every s at once. true: round in `greedyRounds` batches, those nearest to an
  /// integer first, re-solving in between.
  bool greedy = false;
  std::uint32_t greedyRounds = 4;
  /// A component whose system cannot be factored is left unsolved (its unknowns stay 0, see
  /// SeamlessSolution::unsolvedComponents) and the rest solved again, unless it is the component
  /// with the most unknowns (then, or when false, SolverError names the stage and component).
  bool dropUnsolvable = true;
  /// Test hook: a component (not the largest) for which it returns true, given its number of
  /// unknowns, is left unsolved as if it could not be factored (dropUnsolvable's path).
  std::function<bool(std::uint32_t unknowns)> failsToFactor;
  /// Components of at most 64 unknowns without translations are solved on their own, each its
  /// dense block, outside the global factorization (a scan's specks); false: all in it (tests).
  bool solveApart = true;
  /// Coordinates held on integer iso-lines in the last solve (line_constraints.h; feature curves),
  /// when set and not empty; their figures go to lineStats.
  const std::vector<LineConstraint>* lines = nullptr;
  LineConstraintStats* lineStats = nullptr;
  /// When set, in and out: the first solve's elimination order (unknown ids). A non-empty one is
  /// used instead of ordering again (a re-solve of a system with the same pattern, other
  /// values: the foldover repair's stiffened solves); the order used is written back. Unknowns it
  /// misses go last. Not used by a first solve with anchored components.
  std::vector<std::uint32_t>* firstOrder = nullptr;
  /// When the second solve fixes at most a few unknowns more than the first (a local re-solve's
  /// translations) and nothing the first fixed is freed, it is taken from the first factor (a
  /// solve per such unknown) instead of a second factorization: the same map up to rounding.
  /// false: always factor again (tests compare the two).
  bool reuseFirstFactor = true;
  ProgressFn progress;
};

struct SeamlessStats {
  std::uint32_t unknowns = 0, positional = 0, translational = 0;
  std::uint32_t determinedPositions = 0, nonUnitConstraints = 0, components = 0;
  std::uint32_t pinnedFirst = 0, pinnedSecond = 0;
  /// Components with a free shift but no free positional unknown (every vertex a cone, e.g. a
  /// tetrahedron): the first solve fixes their shift through a translation instead.
  std::uint32_t anchoredComponents = 0;
  /// Components left unsolved (SeamlessSolution::unsolvedComponents): mapped to the point 0.
  std::uint32_t unsolvedComponents = 0;
  /// Small components without translations solved on their own (dense), outside the global
  /// factorization; their pins are in pinnedFirst and pinnedSecond.
  std::uint32_t componentsApart = 0;
  std::uint64_t systemNonzeros = 0;      ///< lower triangle of K
  std::uint64_t factorNonzeros = 0;      ///< largest factor
  std::uint64_t factorBytes = 0;         ///< largest factor
  std::uint64_t factorPeakBytes = 0;     ///< CHOLMOD's peak
  bool realFallback = false;
  bool secondFromFirstFactor = false;    ///< RoundOptions::reuseFirstFactor took effect
  double maxRoundingShift = 0.0;         ///< max |s - round(s)| after the first solve
  double secondsAssemble = 0.0, secondsFirstSolve = 0.0, secondsRound = 0.0,
         secondsSecondSolve = 0.0;
};

struct SeamlessSolution {
  std::vector<std::complex<double>> unknowns;      ///< reduced unknowns (positional, then s)
  std::vector<std::complex<double>> translations;  ///< t per seam (Gaussian integers)
  SeamlessStats stats;
  /// Components (Reduction numbering) that could not be factored, with CHOLMOD's message: their
  /// unknowns are 0 (the component maps to the point 0 and has no seam).
  std::vector<std::uint32_t> unsolvedComponents;
  std::vector<std::string> unsolvedReasons;
  /// Components (Reduction numbering) whose shift the first solve anchored through a translation
  /// (SeamlessStats::anchoredComponents).
  std::vector<std::uint32_t> anchoredComponents;
};

/// Runs the whole solve for a reduced basis. Throws SolverError when a factorization fails and
/// the failure cannot be confined to a component (RoundOptions::dropUnsolvable).
SeamlessSolution solveSeamless(const Basis& basis, const Reduction& reduction,
                               const RoundOptions& options = {});

struct LinearSystem;  // core/solve/assemble.h

/// solveSeamless on a system already assembled from `reduction` (assembleSystem): a caller that
/// solves several systems of one basis and reduction assembles what they share once (the
/// foldover repair's stiffened solves). Leaves stats.secondsAssemble at 0.
SeamlessSolution solveSeamlessSystem(const LinearSystem& system, const Reduction& reduction,
                                     const RoundOptions& options = {});

/// Rounds s (the translational unknowns of x) to the nearest Gaussian integers in place and
/// returns the largest change.
double roundTranslations(const Reduction& reduction, std::vector<std::complex<double>>& unknowns);

}  // namespace seamvox
