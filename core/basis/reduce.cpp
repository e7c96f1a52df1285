#include "core/basis/reduce.h"

#include <algorithm>
#include <deque>
#include <numeric>
#include <unordered_map>

#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"

namespace seamvox {

namespace {

using detail::UnionFind;

// One BFS-connected group of domains of a basis function: its own c_0.
struct Group {
  std::uint32_t basis = 0;
  std::uint32_t root = 0;
  bool determined = false;
  GaussInt alpha;     // alpha c_0 = beta . t when determined
  GaussVector beta;
};

GaussVector unitVector(std::uint32_t s) { return {{s, GaussInt(1)}}; }

}  // namespace

/// Two free translations whose columns of P are parallel (every domain sees them in the same
/// ratio) move only seams that no basis adjacency crosses: the energy cannot see that direction
/// and K is singular along it. The later one is fixed at s = 0 (still an integer solution).
void dropInvisibleTranslations(Reduction& out) {
  const ReducedMap& P = out.map;
  const std::uint32_t np = out.numPositional, nt = out.numTranslational;
  if (nt < 2) return;
  std::vector<double> norm2(nt, 0.0);
  std::unordered_map<std::uint64_t, std::complex<double>> gram;  // (i, j), i < j
  std::vector<std::pair<std::uint32_t, std::complex<double>>> entries;
  for (std::size_t d = 0; d + 1 < P.rowStart.size(); ++d) {
    entries.clear();
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      if (P.column[k] >= np) entries.emplace_back(P.column[k] - np, P.value[k]);
    }
    for (std::size_t a = 0; a < entries.size(); ++a) {
      norm2[entries[a].first] += std::norm(entries[a].second);
      for (std::size_t b = a + 1; b < entries.size(); ++b) {
        auto [i, x] = entries[a];
        auto [j, y] = entries[b];
        if (i > j) std::swap(i, j), std::swap(x, y);
        gram[(std::uint64_t(i) << 32) | j] += std::conj(x) * y;
      }
    }
  }
  std::vector<std::uint8_t> dropped(nt, 0);
  std::vector<std::uint64_t> keys;
  for (const auto& entry : gram) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());  // deterministic
  for (std::uint64_t key : keys) {
    const std::uint32_t i = std::uint32_t(key >> 32), j = std::uint32_t(key);
    if (dropped[i] || dropped[j] || norm2[i] == 0.0 || norm2[j] == 0.0) continue;
    if (std::norm(gram[key]) >= (1.0 - 1e-9) * norm2[i] * norm2[j]) dropped[j] = 1;
  }
  std::vector<std::uint32_t> newIndex(nt, kInvalidId);
  std::uint32_t kept = 0;
  for (std::uint32_t j = 0; j < nt; ++j) {
    if (!dropped[j]) newIndex[j] = kept++;
  }
  if (kept == nt) return;
  out.invisibleTranslations = nt - kept;
  ReducedMap map;
  map.rowStart.assign(P.rowStart.size(), 0);
  map.offset = P.offset;
  for (std::size_t d = 0; d + 1 < P.rowStart.size(); ++d) {
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      std::uint32_t c = P.column[k];
      if (c >= np) {
        if (dropped[c - np]) continue;
        c = np + newIndex[c - np];
      }
      map.column.push_back(c);
      map.value.push_back(P.value[k]);
    }
    map.rowStart[d + 1] = map.column.size();
  }
  out.map = std::move(map);
  for (GaussVector& t : out.seamTranslation) {
    GaussVector kept;
    for (const auto& [j, x] : t) {
      if (!dropped[j]) kept.emplace_back(newIndex[j], x);
    }
    t = std::move(kept);
  }
  std::vector<std::uint32_t> component(out.unknownComponent.begin(), out.unknownComponent.begin() + np);
  for (std::uint32_t j = 0; j < nt; ++j) {
    if (!dropped[j]) component.push_back(out.unknownComponent[np + j]);
  }
  out.unknownComponent = std::move(component);
  out.numTranslational = kept;
}


namespace {

// Domains per basis function and adjacencies per domain (CSR).
struct DomainIndex {
  std::vector<std::uint32_t> basisStart, basisDomains;  // #basis + 1, #domains
  std::vector<std::uint32_t> adjStart, adjList;         // #domains + 1, adjacency ids
};

// InputError on an adjacency out of range or across basis functions.
DomainIndex indexDomains(const Basis& basis) {
  const std::uint32_t nd = basis.numDomains(), nb = basis.numBasisFunctions(), ns = basis.numSeams();
  const auto& domainBasis = basis.domainBasis();
  const auto& adjacency = basis.adjacencies();
  DomainIndex out;
  out.basisStart.assign(nb + 1, 0);
  out.basisDomains.resize(nd);
  for (std::uint32_t d = 0; d < nd; ++d) ++out.basisStart[domainBasis[d] + 1];
  std::partial_sum(out.basisStart.begin(), out.basisStart.end(), out.basisStart.begin());
  {
    std::vector<std::uint32_t> fill(out.basisStart.begin(), out.basisStart.end() - 1);
    for (std::uint32_t d = 0; d < nd; ++d) out.basisDomains[fill[domainBasis[d]]++] = d;
  }
  out.adjStart.assign(nd + 1, 0);
  for (std::uint32_t a = 0; a < adjacency.size(); ++a) {
    const DomainAdjacency& e = adjacency[a];
    if (e.left >= nd || e.right >= nd || e.seam >= ns ||
        domainBasis[e.left] != domainBasis[e.right]) {
      throw InputError("reduce: adjacency " + std::to_string(a) +
                       " joins domains of different basis functions or is out of range");
    }
    ++out.adjStart[e.left + 1];
    if (e.right != e.left) ++out.adjStart[e.right + 1];
  }
  std::partial_sum(out.adjStart.begin(), out.adjStart.end(), out.adjStart.begin());
  out.adjList.resize(out.adjStart[nd]);
  std::vector<std::uint32_t> fill(out.adjStart.begin(), out.adjStart.end() - 1);
  for (std::uint32_t a = 0; a < adjacency.size(); ++a) {
    out.adjList[fill[adjacency[a].left]++] = a;
    if (adjacency[a].right != adjacency[a].left) out.adjList[fill[adjacency[a].right]++] = a;
  }
  return out;
}

// Spanning trees of the domains of each basis function: c_d = i^R[d] c_0 + T[d] . t.
struct DomainTrees {
  std::vector<std::uint8_t> R;
  std::vector<GaussVector> T;
  std::vector<std::uint32_t> domainGroup;
  std::vector<std::uint8_t> isTree;  // per adjacency
  std::vector<Group> groups;
};

// BFS per basis function from each domain not reached yet (one group per BFS).
DomainTrees spanDomainTrees(const Basis& basis, const DomainIndex& index) {
  const std::uint32_t nd = basis.numDomains(), nb = basis.numBasisFunctions();
  const auto& adjacency = basis.adjacencies();
  const auto& rotation = basis.seamRotation();
  DomainTrees out;
  std::vector<std::uint8_t>& R = out.R;
  std::vector<GaussVector>& T = out.T;
  std::vector<std::uint32_t>& domainGroup = out.domainGroup;
  R.assign(nd, 0);
  T.resize(nd);
  domainGroup.assign(nd, kInvalidId);
  out.isTree.assign(adjacency.size(), 0);
  std::deque<std::uint32_t> queue;
  for (std::uint32_t b = 0; b < nb; ++b) {
    for (std::uint32_t k = index.basisStart[b]; k < index.basisStart[b + 1]; ++k) {
      const std::uint32_t root = index.basisDomains[k];
      if (domainGroup[root] != kInvalidId) continue;
      const std::uint32_t g = static_cast<std::uint32_t>(out.groups.size());
      out.groups.push_back({b, root, false, {}, {}});
      domainGroup[root] = g;
      queue.push_back(root);
      while (!queue.empty()) {
        const std::uint32_t d = queue.front();
        queue.pop_front();
        for (std::uint32_t k2 = index.adjStart[d]; k2 < index.adjStart[d + 1]; ++k2) {
          const std::uint32_t a = index.adjList[k2];
          const DomainAdjacency& e = adjacency[a];
          const GaussInt r = unitPower(rotation[e.seam]);
          if (e.left == d && domainGroup[e.right] == kInvalidId) {
            // c_right = r c_left + t
            R[e.right] = static_cast<std::uint8_t>((R[d] + rotation[e.seam]) % 4);
            T[e.right] = scaled(T[d], r);
            addScaled(T[e.right], GaussInt(1), unitVector(e.seam));
            domainGroup[e.right] = g;
            out.isTree[a] = 1;
            queue.push_back(e.right);
          } else if (e.right == d && domainGroup[e.left] == kInvalidId) {
            // c_left = r^-1 c_right - r^-1 t
            const GaussInt rInv = r.conj();
            R[e.left] = static_cast<std::uint8_t>((R[d] + 4 - rotation[e.seam]) % 4);
            T[e.left] = scaled(T[d], rInv);
            addScaled(T[e.left], -rInv, unitVector(e.seam));
            domainGroup[e.left] = g;
            out.isTree[a] = 1;
            queue.push_back(e.left);
          }
        }
      }
    }
  }
  return out;
}

// Cycles: (R_b - r R_a) c_0 = (r T_a + e_seam - T_b) . t for every non-tree adjacency. The first
// with alpha != 0 determines its group's c_0; the others become (basis, row) constraints on t.
// A cone flagged in integerPoints gets a point unknown g (numbered after the seams, recorded in
// pointRoot by its group's root domain): alpha c_0 = beta . t becomes c_0 = g with the constraint
// alpha g - beta . t = 0.
std::vector<std::pair<std::uint32_t, GaussVector>> closeCycles(const Basis& basis,
                                                               DomainTrees& trees,
                                                               const std::vector<std::uint8_t>* integerPoints,
                                                               std::vector<std::uint32_t>& pointRoot) {
  const auto& adjacency = basis.adjacencies();
  const auto& rotation = basis.seamRotation();
  std::vector<std::pair<std::uint32_t, GaussVector>> ownConstraints;
  for (std::uint32_t a = 0; a < adjacency.size(); ++a) {
    if (trees.isTree[a]) continue;
    const DomainAdjacency& e = adjacency[a];
    const GaussInt r = unitPower(rotation[e.seam]);
    const GaussInt alpha = unitPower(trees.R[e.right]) - r * unitPower(trees.R[e.left]);
    GaussVector beta = scaled(trees.T[e.left], r);
    addScaled(beta, GaussInt(1), unitVector(e.seam));
    addScaled(beta, GaussInt(-1), trees.T[e.right]);
    Group& group = trees.groups[trees.domainGroup[e.left]];
    if (alpha.isZero()) {
      if (!beta.empty()) ownConstraints.emplace_back(group.basis, std::move(beta));
    } else if (!group.determined) {
      group.determined = true;
      group.alpha = alpha;
      group.beta = std::move(beta);
      if (integerPoints && (*integerPoints)[group.basis]) {
        const std::uint32_t point = basis.numSeams() + static_cast<std::uint32_t>(pointRoot.size());
        pointRoot.push_back(group.root);
        GaussVector row = scaled(unitVector(point), group.alpha);
        addScaled(row, GaussInt(-1), group.beta);
        ownConstraints.emplace_back(group.basis, std::move(row));
        group.alpha = GaussInt(1);
        group.beta = unitVector(point);
      }
    } else {
      // alpha1 c0 = beta1 t and alpha c0 = beta t: alpha1 beta - alpha beta1 = 0.
      GaussVector row = scaled(beta, group.alpha);
      addScaled(row, -alpha, group.beta);
      if (!row.empty()) ownConstraints.emplace_back(group.basis, std::move(row));
    }
  }
  return ownConstraints;
}

// Integer-preserving elimination of the translation constraints: t = U s. With given
// constraints, the basis functions whose own constraints they do not imply are inconsistent.
void eliminateTranslations(std::uint32_t ns, const ReduceOptions& options,
                           std::vector<std::pair<std::uint32_t, GaussVector>> ownConstraints,
                           Reduction& out) {
  LatticeEliminator lattice(ns);
  const auto addExtra = [&] {
    if (!options.extraConstraints) return;
    for (const GaussVector& row : *options.extraConstraints) lattice.addConstraint(row);
  };
  if (options.translationConstraints) {
    for (const GaussVector& row : *options.translationConstraints) lattice.addConstraint(row);
    addExtra();
    for (const auto& [b, row] : ownConstraints) {
      if (!lattice.express(row).empty()) out.inconsistentBasis.push_back(b);
    }
    std::sort(out.inconsistentBasis.begin(), out.inconsistentBasis.end());
    out.inconsistentBasis.erase(
        std::unique(out.inconsistentBasis.begin(), out.inconsistentBasis.end()),
        out.inconsistentBasis.end());
  } else {
    for (const auto& [b, row] : ownConstraints) lattice.addConstraint(row);
    addExtra();
  }
  for (auto& entry : ownConstraints) out.cycleConstraints.push_back(std::move(entry.second));
  lattice.finish();
  out.nonUnitConstraints = lattice.nonUnitConstraints();
  out.numTranslational = lattice.numFree();
  out.seamTranslation.resize(ns);
  for (std::uint32_t s = 0; s < ns; ++s) out.seamTranslation[s] = lattice.row(s);
}

// Positional unknowns: one per group whose c_0 is free (returned per group); lists the basis
// functions whose root group is determined.
std::vector<std::uint32_t> numberPositionalUnknowns(const std::vector<Group>& groups,
                                                    const DomainIndex& index, std::uint32_t nb,
                                                    Reduction& out) {
  std::vector<std::uint32_t> groupPositional(groups.size(), kInvalidId);
  out.basisPositional.assign(nb, kInvalidId);
  for (std::uint32_t g = 0; g < groups.size(); ++g) {
    if (groups[g].determined) {
      if (groups[g].root == index.basisDomains[index.basisStart[groups[g].basis]]) {
        out.determinedBasis.push_back(groups[g].basis);
      }
      continue;
    }
    groupPositional[g] = out.numPositional++;
    if (out.basisPositional[groups[g].basis] == kInvalidId) {
      out.basisPositional[groups[g].basis] = groupPositional[g];
    }
  }
  return groupPositional;
}

// P: coefficient of domain d = i^R_d c_0 + (T_d U) s, with c_0 = (beta U) s / alpha if determined.
void buildReducedMap(const DomainTrees& trees, const std::vector<std::uint32_t>& groupPositional,
                     Reduction& out) {
  const std::vector<Group>& groups = trees.groups;
  const std::uint32_t nd = static_cast<std::uint32_t>(trees.R.size());
  auto translationalTerms = [&](const GaussVector& v) {  // v . t in terms of s
    GaussVector terms;
    for (const auto& [s, x] : v) addScaled(terms, x, out.seamTranslation[s]);
    return terms;
  };
  std::vector<std::complex<double>> groupScale(groups.size());
  std::vector<GaussVector> groupBetaU(groups.size());
  for (std::uint32_t g = 0; g < groups.size(); ++g) {
    if (!groups[g].determined) continue;
    groupBetaU[g] = translationalTerms(groups[g].beta);
    groupScale[g] = 1.0 / groups[g].alpha.toComplex();
  }
  ReducedMap& P = out.map;
  P.rowStart.assign(nd + 1, 0);
  std::vector<std::pair<std::uint32_t, std::complex<double>>> row;
  for (std::uint32_t d = 0; d < nd; ++d) {
    const std::uint32_t g = trees.domainGroup[d];
    const std::complex<double> unit = unitPower(trees.R[d]).toComplex();
    row.clear();
    if (groupPositional[g] != kInvalidId) row.emplace_back(groupPositional[g], unit);
    for (const auto& [j, x] : translationalTerms(trees.T[d])) {
      row.emplace_back(out.numPositional + j, x.toComplex());
    }
    if (groups[g].determined) {
      for (const auto& [j, x] : groupBetaU[g]) {
        row.emplace_back(out.numPositional + j, unit * groupScale[g] * x.toComplex());
      }
    }
    std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (!P.column.empty() && P.rowStart[d] < P.column.size() && P.column.back() == row[k].first) {
        P.value.back() += row[k].second;
      } else {
        P.column.push_back(row[k].first);
        P.value.push_back(row[k].second);
      }
    }
    P.rowStart[d + 1] = P.column.size();
  }
}

// Components through elements and seams: the component of every unknown and whether a
// component has a seam with a rotation.
void assignComponents(const Basis& basis, const DomainTrees& trees,
                      const std::vector<std::uint32_t>& groupPositional,
                      const std::vector<std::uint32_t>& pointRoot, Reduction& out) {
  const std::uint32_t nd = basis.numDomains(), ns = basis.numSeams();
  const std::vector<Group>& groups = trees.groups;
  UnionFind uf(nd);
  {
    std::uint32_t domains[kMaxElementFunctions];
    for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
      const std::uint32_t n = basis.elementDomains(e, domains);
      for (std::uint32_t k = 1; k < n; ++k) {
        if (domains[0] != kInvalidId && domains[k] != kInvalidId) uf.unite(domains[0], domains[k]);
      }
    }
    for (std::uint32_t d = 0; d < nd; ++d) uf.unite(d, groups[trees.domainGroup[d]].root);
  }
  std::vector<std::uint32_t> componentOf(nd, kInvalidId);
  for (std::uint32_t d = 0; d < nd; ++d) {
    const std::uint32_t root = uf.find(d);
    if (componentOf[root] == kInvalidId) componentOf[root] = out.numComponents++;
    componentOf[d] = componentOf[root];
  }
  out.componentHasRotation.assign(out.numComponents, 0);
  out.unknownComponent.assign(out.numUnknowns(), kInvalidId);
  for (std::uint32_t g = 0; g < groups.size(); ++g) {
    if (groupPositional[g] != kInvalidId) {
      out.unknownComponent[groupPositional[g]] = componentOf[groups[g].root];
    }
  }
  std::vector<std::uint32_t> seamComponent(ns, kInvalidId);
  for (const DomainAdjacency& e : basis.adjacencies()) {
    seamComponent[e.seam] = componentOf[e.left];
    if (basis.seamRotation()[e.seam] % 4 != 0) out.componentHasRotation[componentOf[e.left]] = 1;
  }
  for (std::uint32_t s = 0; s < ns; ++s) {
    if (seamComponent[s] == kInvalidId) continue;
    for (const auto& [j, x] : out.seamTranslation[s]) {
      out.unknownComponent[out.numPositional + j] = seamComponent[s];
    }
  }
  for (std::uint32_t p = 0; p < pointRoot.size(); ++p) {  // a cone's point unknown: its component
    for (const auto& [j, x] : out.seamTranslation[ns + p]) {
      out.unknownComponent[out.numPositional + j] = componentOf[pointRoot[p]];
    }
  }
}

}  // namespace

Reduction reduceBasis(const Basis& basis, const ReduceOptions& options) {
  reportProgress(options.progress, "reduce", 0.0);
  const DomainIndex index = indexDomains(basis);
  DomainTrees trees = spanDomainTrees(basis, index);
  reportProgress(options.progress, "reduce", 0.3);
  if (options.integerPoints && options.integerPoints->size() != basis.numBasisFunctions()) {
    throw InputError("reduceBasis: " + std::to_string(options.integerPoints->size()) +
                     " integer-point flags for " + std::to_string(basis.numBasisFunctions()) + " basis functions");
  }
  std::vector<std::uint32_t> pointRoot;
  std::vector<std::pair<std::uint32_t, GaussVector>> ownConstraints =
      closeCycles(basis, trees, options.integerPoints, pointRoot);
  Reduction out;
  eliminateTranslations(basis.numSeams() + static_cast<std::uint32_t>(pointRoot.size()), options,
                        std::move(ownConstraints), out);
  reportProgress(options.progress, "reduce", 0.6);
  const std::vector<std::uint32_t> groupPositional =
      numberPositionalUnknowns(trees.groups, index, basis.numBasisFunctions(), out);
  buildReducedMap(trees, groupPositional, out);
  reportProgress(options.progress, "reduce", 0.8);
  assignComponents(basis, trees, groupPositional, pointRoot, out);
  out.seamTranslation.resize(basis.numSeams());  // the point unknowns are no seams
  dropInvisibleTranslations(out);
  reportProgress(options.progress, "reduce", 1.0);
  return out;
}

std::vector<std::complex<double>> expandCoefficients(const Reduction& reduction,
                                                     const std::vector<std::complex<double>>& x) {
  const ReducedMap& P = reduction.map;
  const std::size_t nd = P.rowStart.size() - 1;
  std::vector<std::complex<double>> c(nd);
  for (std::size_t d = 0; d < nd; ++d) {
    std::complex<double> sum = P.offset.empty() ? 0.0 : P.offset[d];
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) sum += P.value[k] * x[P.column[k]];
    c[d] = sum;
  }
  return c;
}

std::vector<std::complex<double>> seamTranslations(const Reduction& reduction,
                                                   const std::vector<std::complex<double>>& s) {
  std::vector<std::complex<double>> t(reduction.seamTranslation.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    for (const auto& [j, x] : reduction.seamTranslation[i]) t[i] += x.toComplex() * s[j];
  }
  return t;
}

}  // namespace seamvox
