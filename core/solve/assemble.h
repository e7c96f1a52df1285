#pragma once
/// Assembly of the reduced system K = P* L P, rhs = P* (b - L offset) (DESIGN section 8).
#include <Eigen/SparseCore>
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/basis.h"
#include "core/system/progress.h"
#include "core/basis/reduce.h"

namespace seamvox {

using ComplexSparse = Eigen::SparseMatrix<std::complex<double>, Eigen::ColMajor, int>;
using ComplexVector = Eigen::VectorXcd;
using ComplexTriplet = Eigen::Triplet<std::complex<double>, int>;

/// Hermitian system over all reduced unknowns; K holds the lower triangle (row >= column).
/// Minimising x* K x - 2 Re(x* rhs) minimises sum_T A_T |grad q - w_T / h|^2.
struct LinearSystem {
  ComplexSparse lower;
  ComplexVector rhs;
  double totalArea = 0.0;
};

struct AssembleOptions {
  ProgressFn progress;
  /// Above this many unknowns the elements are summed in 2 chunks instead of 8: each chunk holds
  /// a right-hand side and column starts of every unknown (a scan with a million specks has 10^7
  /// of them; a grid-sized system about 10^5). Tests lower it.
  std::uint64_t fewChunksAbove = std::uint64_t(1) << 21;
};

/// Sums the element integrals through the map P in parallel (TBB; thread-local accumulation,
/// one merge). Memory: the nonzeros of K plus a bounded buffer per thread.
LinearSystem assembleSystem(const Basis& basis, const Reduction& reduction,
                            const AssembleOptions& options = {});

/// The system on the free unknowns: fixed[i] != 0 moves unknown i (value values[i]) to the
/// right-hand side. Returns the lower triangle of K_ff, rhs_f - K_fx x_x and the free indices.
/// extraLower (row >= column, full numbering) is added to K first (e.g. a penalty term).
struct RestrictedSystem {
  ComplexSparse lower;
  ComplexVector rhs;
  std::vector<std::uint32_t> freeUnknowns;
};
RestrictedSystem restrictSystem(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                                const std::vector<std::complex<double>>& values,
                                const std::vector<ComplexTriplet>& extraLower = {});

/// A fill-reducing order given in a system's full numbering (`order`: unknowns, the first
/// eliminated first; empty: none), for its restriction to freeUnknowns: positions among them, in
/// that order, then those the order missed (CholmodFactor::factor with an order).
std::vector<std::int64_t> restrictOrder(const std::vector<std::uint32_t>& order,
                                        const std::vector<std::uint32_t>& freeUnknowns, std::uint32_t numUnknowns);

}  // namespace seamvox
