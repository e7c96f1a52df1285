#pragma once
/// Gaussian integers Z[i], sparse vectors over them, and the unimodular elimination that turns
/// integer constraints C t = 0 into a free parametrization t = U s (DESIGN section 7).
#include <complex>
#include <cstdint>
#include <utility>
#include <vector>

namespace seamvox {

/// a + b i with 64-bit parts.
struct GaussInt {
  std::int64_t re = 0, im = 0;
  GaussInt() = default;
  constexpr GaussInt(std::int64_t r, std::int64_t i = 0) : re(r), im(i) {}
  bool isZero() const { return re == 0 && im == 0; }
  bool isUnit() const { return norm() == 1; }
  std::int64_t norm() const { return re * re + im * im; }
  GaussInt conj() const { return {re, -im}; }
  std::complex<double> toComplex() const {
    return {static_cast<double>(re), static_cast<double>(im)};
  }
};
inline GaussInt operator+(GaussInt a, GaussInt b) { return {a.re + b.re, a.im + b.im}; }
inline GaussInt operator-(GaussInt a, GaussInt b) { return {a.re - b.re, a.im - b.im}; }
inline GaussInt operator-(GaussInt a) { return {-a.re, -a.im}; }
inline GaussInt operator*(GaussInt a, GaussInt b) {
  return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
}
inline bool operator==(GaussInt a, GaussInt b) { return a.re == b.re && a.im == b.im; }
inline bool operator!=(GaussInt a, GaussInt b) { return !(a == b); }

/// i^k for any integer k (the seam rotations).
GaussInt unitPower(int k);
/// The Gaussian integer nearest to a / b (b != 0); the remainder a - q b has norm <= norm(b) / 2.
GaussInt divideRounded(GaussInt a, GaussInt b);
/// The Gaussian integer nearest to z (ties away from zero per component).
std::complex<double> roundGaussian(std::complex<double> z);
/// Distance of z from the nearest Gaussian integer.
double gaussianIntegerDistance(std::complex<double> z);

/// Sparse vector over Z[i]: (index, value) pairs, indices increasing, no zero values.
using GaussVector = std::vector<std::pair<std::uint32_t, GaussInt>>;
/// a += q * b.
void addScaled(GaussVector& a, GaussInt q, const GaussVector& b);
/// q * a.
GaussVector scaled(const GaussVector& a, GaussInt q);

/// Integer-preserving elimination of constraints C t = 0 over Z[i] (t has n entries).
/// Keeps t = U s where U is unimodular on the columns still free; each constraint is reduced by
/// Euclid's algorithm among the free columns (unimodular column operations) until one column
/// carries it, which is then fixed to zero. Integer solutions t are exactly U s, s in Z[i]^k.
class LatticeEliminator {
 public:
  explicit LatticeEliminator(std::uint32_t numVariables);
  /// Adds the constraint row . t = 0. Returns false when it already held (no column removed).
  bool addConstraint(const GaussVector& row);
  /// row . U: the constraint expressed in the current free columns (column ids not compacted).
  GaussVector express(const GaussVector& row) const;
  /// Compacts the free columns to 0..numFree()-1. Call once, after the last constraint.
  void finish();
  std::uint32_t numFree() const { return numFree_; }
  /// Row i of U (t_i in terms of s); valid after finish().
  const GaussVector& row(std::uint32_t i) const { return rows_[i]; }
  /// Constraints whose reduction needed a non-unit step (a coefficient like 2 or 1 + i).
  std::uint32_t nonUnitConstraints() const { return nonUnit_; }

 private:
  void addToColumn(std::uint32_t target, GaussInt q, std::uint32_t source);
  std::vector<GaussVector> rows_;                 // n rows of U
  std::vector<std::vector<std::uint32_t>> colRows_;  // rows that may hold each column
  std::vector<std::uint8_t> alive_;
  std::uint32_t numFree_ = 0;
  std::uint32_t nonUnit_ = 0;
  bool finished_ = false;
};

}  // namespace seamvox
