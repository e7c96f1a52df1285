// The seamless solve with coordinates held on integer iso-lines (line_constraints.h).
#include "core/solve/line_constraints.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/solve/cholmod_solver.h"
#include "core/system/errors.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;

double coordinate(const Complex& z, int axis) { return axis == 0 ? z.real() : z.imag(); }

/// Affine links between real values: node = sign * parent + offset. Nodes are the real parts of
/// the unknowns (2 j: Re x_j, 2 j + 1: Im x_j), then one integer per group, then the constant 0.
/// A class's root is the constant when it has one, else a group: its members are +-root + offset.
class AffineLinks {
 public:
  AffineLinks(std::uint32_t unknowns, std::uint32_t groups)
      : numVars_(2 * unknowns), constant_(2 * unknowns + groups), parent_(constant_ + 1), sign_(constant_ + 1, 1.0),
        offset_(constant_ + 1, 0.0) {
    for (std::uint32_t i = 0; i <= constant_; ++i) parent_[i] = i;
  }
  std::uint32_t var(std::uint32_t unknown, int part) const { return 2 * unknown + part; }
  std::uint32_t group(std::uint32_t g) const { return numVars_ + g; }
  std::uint32_t constant() const { return constant_; }
  bool isGroup(std::uint32_t node) const { return node >= numVars_ && node < constant_; }

  struct Root {
    std::uint32_t node;
    double sign, offset;
  };
  Root find(std::uint32_t a) {
    std::uint32_t root = a;
    path_.clear();
    while (parent_[root] != root) {
      path_.push_back(root);
      root = parent_[root];
    }
    // From the node below the root down to a: each parent already points at the root.
    for (std::size_t k = path_.size(); k-- > 0;) {
      const std::uint32_t node = path_[k], up = parent_[node];
      if (up == root) continue;
      offset_[node] = sign_[node] * offset_[up] + offset_[node];
      sign_[node] *= sign_[up];
      parent_[node] = root;
    }
    return root == a ? Root{a, 1.0, 0.0} : Root{root, sign_[a], offset_[a]};
  }
  std::uint32_t numNodes() const { return constant_ + 1; }
  /// Adds a = sign * b + offset; false (nothing added) when it contradicts the links before.
  bool link(std::uint32_t a, std::uint32_t b, double sign, double offset) {
    const Root ra = find(a), rb = find(b);
    // root(a) = s * root(b) + o.
    const double s = ra.sign * sign * rb.sign;
    const double o = ra.sign * (sign * rb.offset + offset - ra.offset);
    if (ra.node == rb.node) {
      const bool constant = ra.node == constant_;  // 0 = s 0 + o
      return std::abs(o) <= 1e-9 * std::max(1.0, std::abs(offset)) && (constant || s == 1.0);
    }
    if (priority(ra.node) <= priority(rb.node)) {
      attach(ra.node, rb.node, s, o);
    } else {
      attach(rb.node, ra.node, s, -s * o);  // root(b) = s root(a) - s o
    }
    return true;
  }

 private:
  int priority(std::uint32_t node) const { return node == constant_ ? 2 : node >= numVars_ ? 1 : 0; }
  void attach(std::uint32_t child, std::uint32_t root, double sign, double offset) {
    parent_[child] = root;
    sign_[child] = sign;
    offset_[child] = offset;
  }
  std::uint32_t numVars_, constant_;
  std::vector<std::uint32_t> parent_;
  std::vector<double> sign_, offset_;
  std::vector<std::uint32_t> path_;
};

/// Links each constraint's coordinate to its group's integer. A constraint whose domain row has
/// no free unknown fixes the group; one free unknown times a unit i^q ties one real part of it.
void linkConstraints(const Reduction& reduction, const std::vector<std::uint8_t>& fixed,
                     const std::vector<Complex>& x, const std::vector<LineConstraint>& lines,
                     AffineLinks& links, LineConstraintStats& stats) {
  const ReducedMap& P = reduction.map;
  for (const LineConstraint& line : lines) {
    if (line.domain + 1 >= P.rowStart.size() || line.axis > 1) {
      throw InputError("line constraint on domain " + std::to_string(line.domain) + " axis " +
                       std::to_string(line.axis) + ": out of range");
    }
    Complex known = P.offset.empty() ? Complex(0.0) : P.offset[line.domain];
    std::uint32_t freeUnknown = kInvalidId, freeCount = 0;
    Complex unit = 0.0;
    for (std::uint64_t k = P.rowStart[line.domain]; k < P.rowStart[line.domain + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (fixed[j]) {
        known += P.value[k] * x[j];
      } else {
        freeUnknown = j;
        unit = P.value[k];
        ++freeCount;
      }
    }
    const bool isUnit = (std::abs(unit.real()) == 1.0 && unit.imag() == 0.0) ||
                        (unit.real() == 0.0 && std::abs(unit.imag()) == 1.0);
    const std::uint32_t group = links.group(line.group);
    bool held;
    if (freeCount == 0) {
      held = links.link(group, links.constant(), 1.0, coordinate(known, line.axis));
    } else if (freeCount == 1 && isUnit) {
      // coordinate(unit * x_j) = sign * (Re or Im of x_j).
      const int part = coordinate(unit, line.axis) != 0.0 ? 0 : 1;
      const double sign = coordinate(unit * (part == 0 ? Complex(1.0) : Complex(0.0, 1.0)), line.axis);
      // sign var + known = c  =>  var = sign c - sign known.
      held = links.link(links.var(freeUnknown, part), group, sign, -sign * coordinate(known, line.axis));
    } else {
      ++stats.unsupported;
      continue;
    }
    ++(held ? stats.applied : stats.conflicting);
  }
}

/// Where each real part of the unknowns goes: reduced column (or kInvalidId when known),
/// sign and constant: value = sign * z[column] + constant.
struct RealMap {
  std::vector<std::uint32_t> column;
  std::vector<double> sign, constant;
  std::vector<std::uint8_t> integer;  ///< per reduced column: a group's integer
  std::uint32_t columns = 0;
};

RealMap mapRealParts(const std::vector<std::uint8_t>& fixed, const std::vector<Complex>& x, AffineLinks& links) {
  const std::uint32_t n = static_cast<std::uint32_t>(fixed.size());
  RealMap map;
  map.column.assign(2 * n, kInvalidId);
  map.sign.assign(2 * n, 1.0);
  map.constant.assign(2 * n, 0.0);
  std::vector<std::uint32_t> columnOfRoot(links.numNodes(), kInvalidId);  // groups' integers
  for (std::uint32_t j = 0; j < n; ++j) {
    for (int part = 0; part < 2; ++part) {
      const std::uint32_t v = links.var(j, part);
      if (fixed[j]) {
        map.constant[v] = coordinate(x[j], part);
        continue;
      }
      const AffineLinks::Root root = links.find(v);
      if (root.node == links.constant()) {
        map.constant[v] = root.offset;
      } else if (root.node == v) {
        map.column[v] = map.columns++;
        map.integer.push_back(0);
      } else {
        std::uint32_t& column = columnOfRoot[root.node];
        if (column == kInvalidId) {
          column = map.columns++;
          map.integer.push_back(1);
        }
        map.column[v] = column;
        map.sign[v] = root.sign;
        map.constant[v] = root.offset;
      }
    }
  }
  return map;
}

/// The real system on the reduced columns: T^T K_R T and T^T (rhs_R - K_R c), T and c from map.
LinearSystem reducedRealSystem(const LinearSystem& system, const RealMap& map) {
  std::vector<ComplexTriplet> triplets;
  ComplexVector rhs = ComplexVector::Zero(map.columns);
  const auto add = [&](std::uint32_t p, std::uint32_t q, double value) {  // full entry (p, q)
    const std::uint32_t P = map.column[p];
    if (P == kInvalidId || value == 0.0) return;
    rhs[P] -= map.sign[p] * value * map.constant[q];
    const std::uint32_t Q = map.column[q];
    if (Q != kInvalidId && P >= Q) triplets.emplace_back(int(P), int(Q), map.sign[p] * map.sign[q] * value);
  };
  for (int j = 0; j < system.lower.outerSize(); ++j) {
    for (ComplexSparse::InnerIterator it(system.lower, j); it; ++it) {
      const std::uint32_t i = static_cast<std::uint32_t>(it.row());
      const double a = it.value().real(), b = it.value().imag();
      // Block (i, j) of [Re K -Im K; Im K Re K] and, off the diagonal, its transpose at (j, i).
      const double block[2][2] = {{a, -b}, {b, a}};
      for (int pi = 0; pi < 2; ++pi) {
        for (int pj = 0; pj < 2; ++pj) {
          add(2 * i + pi, 2 * std::uint32_t(j) + pj, block[pi][pj]);
          if (i != std::uint32_t(j)) add(2 * std::uint32_t(j) + pj, 2 * i + pi, block[pi][pj]);
        }
      }
    }
  }
  for (std::uint32_t j = 0; j < system.rhs.size(); ++j) {
    for (int part = 0; part < 2; ++part) {
      const std::uint32_t p = 2 * j + part;
      if (map.column[p] != kInvalidId) rhs[map.column[p]] += map.sign[p] * coordinate(system.rhs[j], part);
    }
  }
  LinearSystem out;
  out.lower.resize(map.columns, map.columns);
  out.lower.setFromTriplets(triplets.begin(), triplets.end());
  out.rhs = std::move(rhs);
  return out;
}

/// Solves the restricted system into z (free columns only). order: empty, the elimination order
/// to use (full numbering), filled with the one used; the second solve reuses the first's.
void solveRestricted(const LinearSystem& system, const std::vector<std::uint8_t>& fixed,
                     std::vector<Complex>& z, const char* stage, std::vector<std::uint32_t>& order) {
  const RestrictedSystem restricted = restrictSystem(system, fixed, z);
  if (restricted.freeUnknowns.empty()) return;
  CholmodFactor factor;
  try {
    factor.factor(restricted.lower, restrictOrder(order, restricted.freeUnknowns, static_cast<std::uint32_t>(z.size())));
    order.clear();
    for (std::int64_t k : factor.permutation()) order.push_back(restricted.freeUnknowns[k]);
  } catch (const SolverError& e) {
    throw SolverError(std::string("seamless solve with feature lines, ") + stage + ": " + e.what());
  }
  const ComplexVector y = factor.solve(restricted.rhs);
  if (!y.allFinite()) throw SolverError(std::string("seamless solve with feature lines, ") + stage + ": NaN");
  for (std::size_t k = 0; k < restricted.freeUnknowns.size(); ++k) z[restricted.freeUnknowns[k]] = y[k].real();
}

}  // namespace

void solveWithLineConstraints(const LinearSystem& system, const Reduction& reduction,
                              const std::vector<std::uint8_t>& fixed, std::vector<Complex>& x,
                              const std::vector<LineConstraint>& lines, LineConstraintStats& stats) {
  const std::uint32_t n = reduction.numUnknowns();
  if (fixed.size() != n || x.size() != n) {
    throw InputError("line constraints: " + std::to_string(fixed.size()) + " flags and " +
                     std::to_string(x.size()) + " values for " + std::to_string(n) + " unknowns");
  }
  std::uint32_t groups = 0;
  for (const LineConstraint& line : lines) groups = std::max(groups, line.group + 1);
  stats = LineConstraintStats();
  stats.constraints = static_cast<std::uint32_t>(lines.size());
  AffineLinks links(n, groups);
  linkConstraints(reduction, fixed, x, lines, links, stats);
  const RealMap map = mapRealParts(fixed, x, links);
  const LinearSystem real = reducedRealSystem(system, map);
  // First with the integers free, then with them rounded and fixed.
  std::vector<Complex> z(map.columns, 0.0);
  std::vector<std::uint8_t> none(map.columns, 0), integers(map.integer.begin(), map.integer.end());
  std::vector<std::uint32_t> order;
  solveRestricted(real, none, z, "first solve", order);
  for (std::uint32_t k = 0; k < map.columns; ++k) {
    if (!integers[k]) continue;
    ++stats.integerUnknowns;
    const double rounded = std::round(z[k].real());
    stats.maxRoundingShift = std::max(stats.maxRoundingShift, std::abs(z[k].real() - rounded));
    z[k] = rounded;
  }
  if (stats.integerUnknowns > 0) solveRestricted(real, integers, z, "second solve", order);
  for (std::uint32_t j = 0; j < n; ++j) {
    if (fixed[j]) continue;
    double part[2];
    for (int p = 0; p < 2; ++p) {
      const std::uint32_t v = 2 * j + p;
      part[p] = map.constant[v] + (map.column[v] == kInvalidId ? 0.0 : map.sign[v] * z[map.column[v]].real());
    }
    x[j] = Complex(part[0], part[1]);
  }
}

}  // namespace seamvox
