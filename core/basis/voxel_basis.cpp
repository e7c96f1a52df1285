#include "core/basis/voxel_basis.h"


#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/basis/detail_voxel_elements.h"
#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

using detail::denseLabels;
using detail::UnionFind;

VoxelCoord difference(const VoxelCoord& b, const VoxelCoord& a) {
  return {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
}
bool isNeighbourOffset(const VoxelCoord& d) {
  return std::abs(d[0]) <= 1 && std::abs(d[1]) <= 1 && std::abs(d[2]) <= 1;
}

// Calls f(k, k2) for every grid corner shared by voxels A and B = A + d: local index k in A,
// k2 in B (corner A + k == B + k2).
template <class F>
void forSharedCorners(const VoxelCoord& d, F&& f) {
  for (int k = 0; k < 8; ++k) {
    const int kx = (k & 1) - d[0], ky = ((k >> 1) & 1) - d[1], kz = ((k >> 2) & 1) - d[2];
    if (kx < 0 || kx > 1 || ky < 0 || ky > 1 || kz < 0 || kz > 1) continue;
    f(k, kx + 2 * ky + 4 * kz);
  }
}

// Joins every domain (a class of element-function nodes 8 e + k) whose weight (sum of its nodes'
// nodeWeight) is below minWeight to the heaviest other domain of the element holding most of its
// weight. Such a domain is a B-spline that barely touches the surface (a sliver where a vertex
// lies a hair across a grid plane, or a strip along the far edges of its support): there it is
// almost a combination of the element's other functions, and the system would be singular to
// working precision. Flags the joined nodes; returns how many domains were joined.
std::uint32_t joinNegligibleDomains(UnionFind& functions, const std::vector<double>& nodeWeight,
                                    double minWeight, std::vector<std::uint8_t>& joinedNode) {
  const std::uint32_t nn = static_cast<std::uint32_t>(functions.parent.size());
  joinedNode.assign(nn, 0);
  if (!(minWeight > 0.0)) return 0;
  std::vector<std::uint32_t> root(nn);
  std::vector<double> weight(nn, 0.0);  // per root
  for (std::uint32_t i = 0; i < nn; ++i) {
    root[i] = functions.find(i);
    weight[root[i]] += nodeWeight[i];
  }
  std::vector<std::uint32_t> heaviest(nn, kInvalidId);  // per light root: its heaviest node
  for (std::uint32_t i = 0; i < nn; ++i) {
    const std::uint32_t r = root[i];
    if (weight[r] >= minWeight) continue;
    joinedNode[i] = 1;
    if (heaviest[r] == kInvalidId || nodeWeight[i] > nodeWeight[heaviest[r]]) heaviest[r] = i;
  }
  std::uint32_t joined = 0;
  for (std::uint32_t r = 0; r < nn; ++r) {
    if (heaviest[r] == kInvalidId) continue;
    const std::uint32_t e = heaviest[r] / 8;
    std::uint32_t target = kInvalidId;
    for (std::uint32_t k = 0; k < 8; ++k) {
      const std::uint32_t other = root[8 * e + k];
      if (other != r && (target == kInvalidId || weight[other] > weight[root[target]])) {
        target = 8 * e + k;
      }
    }
    if (target == kInvalidId) continue;  // the element's functions are all one domain already
    functions.unite(r, target);
    ++joined;
  }
  return joined;
}

struct SeamLink {
  std::uint32_t left, right, seam;  // element-function nodes 8 e + k
};

// Fragments per voxel (stable: ordered by face), as CSR.
struct VoxelFragmentIndex {
  std::vector<std::uint32_t> start;      // #voxels + 1
  std::vector<std::uint32_t> fragments;  // fragment ids
};

// The constructor's inputs every phase reads.
struct BasisInput {
  const TriangleMesh& mesh;
  const Topology& topology;
  const CrossField& field;
  const CutResult& cut;
  const VoxelGridGeometry& grid;
  const std::vector<VoxelCoord>& voxelCoords;
  const std::vector<VoxelFragment>& fragments;
};

// Fragment starts per face (they arrive ordered by face); InputError on a fragment out of range
// or out of order.
std::vector<std::uint32_t> indexFragmentsByFace(const std::vector<VoxelFragment>& fragments,
                                                std::uint32_t nf, std::uint32_t nv) {
  std::vector<std::uint32_t> faceStart(nf + 1, 0);
  for (std::uint32_t i = 0; i < fragments.size(); ++i) {
    const VoxelFragment& fr = fragments[i];
    if (fr.face >= nf || fr.voxel >= nv || (i > 0 && fr.face < fragments[i - 1].face)) {
      throw InputError("voxel basis: fragment " + std::to_string(i) +
                       " is out of range or not ordered by face");
    }
    ++faceStart[fr.face + 1];
  }
  std::partial_sum(faceStart.begin(), faceStart.end(), faceStart.begin());
  return faceStart;
}

VoxelFragmentIndex indexFragmentsByVoxel(const std::vector<VoxelFragment>& fragments,
                                         std::uint32_t nv) {
  VoxelFragmentIndex out;
  out.start.assign(nv + 1, 0);
  out.fragments.resize(fragments.size());
  for (const VoxelFragment& fr : fragments) ++out.start[fr.voxel + 1];
  std::partial_sum(out.start.begin(), out.start.end(), out.start.begin());
  std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::uint32_t i = 0; i < fragments.size(); ++i) out.fragments[fill[fragments[i].voxel]++] = i;
  return out;
}

// Elements of voxel v (labelVoxelFragments): each fragment's element label local to v; returns
// the number of elements of v.
std::uint32_t labelVoxelElements(const BasisInput& in, const VoxelFragmentIndex& byVoxel, std::uint32_t v,
                                 std::vector<FaceId>& faces, std::vector<std::uint8_t>& masks,
                                 std::vector<std::uint32_t>& label, std::vector<std::uint32_t>& fragmentElement) {
  const std::uint32_t begin = byVoxel.start[v], m = byVoxel.start[v + 1] - begin;
  faces.resize(m);
  masks.resize(m);
  for (std::uint32_t i = 0; i < m; ++i) {
    const VoxelFragment& fr = in.fragments[byVoxel.fragments[begin + i]];
    faces[i] = fr.face;
    masks[i] = static_cast<std::uint8_t>(fr.edgeMask);
  }
  const std::uint32_t count = detail::labelVoxelFragments(
      faces, masks, [&](CornerId c) { return in.topology.opposite(c); },
      [&](CornerId c) { return in.cut.corners.isCut(c); }, label);
  for (std::uint32_t i = 0; i < m; ++i) fragmentElement[byVoxel.fragments[begin + i]] = label[i];
  return count;
}

// Elements numbered in voxel order, and where each fragment and element lies.
struct Elements {
  std::vector<std::uint32_t> fragmentElement;    // #fragments
  std::vector<std::uint32_t> voxelElementStart;  // #voxels + 1
  std::vector<std::uint32_t> elementVoxel;       // #elements
};

// Elements: per voxel (in parallel), fragments joined through shared non-cut edges; then
// numbered globally. InputError when 8 #elements would not fit in 32 bits.
Elements buildElements(const BasisInput& in, const VoxelFragmentIndex& byVoxel) {
  const std::uint32_t nv = static_cast<std::uint32_t>(in.voxelCoords.size());
  const std::uint32_t nfrag = static_cast<std::uint32_t>(in.fragments.size());
  Elements out;
  out.fragmentElement.assign(nfrag, 0);
  out.voxelElementStart.assign(nv + 1, 0);
  parallelFor(nv, 64, [&](const IndexRange& range) {
    std::vector<FaceId> faces;
    std::vector<std::uint8_t> masks;
    std::vector<std::uint32_t> label;
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      out.voxelElementStart[v + 1] = labelVoxelElements(in, byVoxel, v, faces, masks, label, out.fragmentElement);
    }
  });
  std::partial_sum(out.voxelElementStart.begin(), out.voxelElementStart.end(),
                   out.voxelElementStart.begin());
  const std::uint32_t ne = out.voxelElementStart[nv];
  if (std::uint64_t(ne) * 8 >= kInvalidId) {
    throw InputError("voxel basis: too many elements (" + std::to_string(ne) +
                     "); use a coarser grid");
  }
  for (std::uint32_t i = 0; i < nfrag; ++i) {
    out.fragmentElement[i] += out.voxelElementStart[in.fragments[i].voxel];
  }
  out.elementVoxel.resize(ne);
  for (std::uint32_t v = 0; v < nv; ++v) {
    for (std::uint32_t e = out.voxelElementStart[v]; e < out.voxelElementStart[v + 1]; ++e) {
      out.elementVoxel[e] = v;
    }
  }
  return out;
}

// Integrals of every element: re-clip each fragment against its voxel (no polygons are stored),
// in parallel over voxels.
void integrateFragments(const BasisInput& in, const VoxelFragmentIndex& byVoxel,
                        const std::vector<std::uint32_t>& fragmentElement, double edgeLength,
                        std::vector<VoxelIntegrals>& records,
                        std::vector<std::array<double, 36>>& normalStiffness) {
  const std::uint32_t nv = static_cast<std::uint32_t>(in.voxelCoords.size());
  parallelFor(nv, 16, [&](const IndexRange& range) {
    // A voxel's elements are numbered contiguously: their sums are kept while its fragments are
    // added, and assembled once per element.
    std::vector<FragmentSums> sums;
    std::vector<FaceId> faces;
    std::vector<std::uint32_t> element;
    const auto integrand = [&](FaceId f) {
      detail::FaceIntegrand out;
      out.grid = faceGridCoords(in.mesh, in.grid, f);
      out.normal = faceNormal(in.mesh, f);
      out.direction = detail::combedDirection(in.field.at(f), out.normal, in.cut.faceRotation[f]);
      return out;
    };
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      std::uint32_t first = kInvalidId, last = 0;
      faces.clear();
      element.clear();
      for (std::uint32_t k = byVoxel.start[v]; k < byVoxel.start[v + 1]; ++k) {
        const std::uint32_t i = byVoxel.fragments[k];
        faces.push_back(in.fragments[i].face);
        element.push_back(fragmentElement[i]);
        first = std::min(first, element.back()), last = std::max(last, element.back());
      }
      if (first == kInvalidId) continue;
      detail::integrateVoxel(in.voxelCoords[v], in.grid.voxelSize, edgeLength, faces, element, first, last, integrand,
                             sums, records.data() + first, normalStiffness.data() + first);
    }
  });
}

// The element functions (nodes 8 e + k) of one grid corner, their domains being built, and the
// seam links between them.
struct DomainLinks {
  UnionFind functions;
  std::vector<SeamLink> seamLinks;
};

// (a) One triangle meets a support (a convex box) in a convex, connected piece: its fragments in
// any two voxels of the support belong to the same domain. `sorted` is scratch space.
void joinFacePieces(const BasisInput& in, const std::vector<std::uint32_t>& fragmentElement,
                    std::uint32_t begin, std::uint32_t end,
                    std::vector<std::pair<VoxelCoord, std::uint32_t>>& sorted,
                    UnionFind& functions) {
  sorted.clear();
  for (std::uint32_t i = begin; i < end; ++i) {
    sorted.emplace_back(in.voxelCoords[in.fragments[i].voxel], fragmentElement[i]);
  }
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [a, ea] : sorted) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const VoxelCoord b{a[0] + dx, a[1] + dy, a[2] + dz};
          if (b <= a) continue;
          const auto it = std::lower_bound(sorted.begin(), sorted.end(),
                                           std::make_pair(b, std::uint32_t(0)));
          if (it == sorted.end() || it->first != b) continue;
          const std::uint32_t eb = it->second;
          forSharedCorners({dx, dy, dz},
                           [&](int k, int k2) { functions.unite(8 * ea + k, 8 * eb + k2); });
        }
  }
}

// (b) Two triangles across an edge meet in the support along the edge's piece: non-cut edges of
// face f's fragment i join their domains, seam edges make a seam link.
void linkFragmentEdges(const BasisInput& in, const SeamIndex& seamIndex,
                       const std::vector<std::uint32_t>& faceFragmentStart,
                       const std::vector<std::uint32_t>& fragmentElement, FaceId f,
                       std::uint32_t i, DomainLinks& links) {
  const std::vector<VoxelFragment>& fragments = in.fragments;
  const VoxelFragment& fr = fragments[i];
  const VoxelCoord& a = in.voxelCoords[fr.voxel];
  const std::array<Vec3d, 3> g = faceGridCoords(in.mesh, in.grid, f);
  for (int j = 0; j < 3; ++j) {
    const CornerId c = 3 * f + j;
    const CornerId o = in.topology.opposite(c);
    if (!(fr.edgeMask >> j & 1) || o == kInvalidId || cornerFace(o) < f) continue;
    const bool isCut = in.cut.corners.isCut(c);
    const SeamIndex::Side side = isCut ? seamIndex.find(c) : SeamIndex::Side{};
    if (isCut && side.seam == kInvalidId) continue;
    const FaceId h = cornerFace(o);
    const Vec3d& p = g[(j + 1) % 3];
    const Vec3d& q = g[(j + 2) % 3];
    for (std::uint32_t i2 = faceFragmentStart[h]; i2 < faceFragmentStart[h + 1]; ++i2) {
      const VoxelFragment& other = fragments[i2];
      if (!(other.edgeMask >> (o % 3) & 1)) continue;
      const VoxelCoord& b = in.voxelCoords[other.voxel];
      const VoxelCoord d = difference(b, a);
      if (!isNeighbourOffset(d)) continue;
      if (d != VoxelCoord{0, 0, 0}) {
        // The edge must run inside the shared face or line of the two voxels.
        Vec3d lo, hi;
        for (int x = 0; x < 3; ++x) {
          lo[x] = std::max(a[x], b[x]);
          hi[x] = std::min(a[x], b[x]) + 1;
        }
        if (!segmentOverlapsBox(p, q, lo, hi)) continue;
      } else if (!isCut) {
        continue;  // same voxel, joined into one element already
      }
      const std::uint32_t ea = fragmentElement[i], eb = fragmentElement[i2];
      forSharedCorners(d, [&](int k, int k2) {
        if (!isCut) {
          links.functions.unite(8 * ea + k, 8 * eb + k2);
        } else if (side.left) {
          links.seamLinks.push_back({8 * ea + k, 8 * eb + k2, side.seam});
        } else {
          links.seamLinks.push_back({8 * eb + k2, 8 * ea + k, side.seam});
        }
      });
    }
  }
}

// Domains: element functions of one grid corner joined inside its support, face by face; and
// the seam links between domains.
DomainLinks linkElementFunctions(const BasisInput& in,
                                 const std::vector<std::uint32_t>& faceFragmentStart,
                                 const std::vector<std::uint32_t>& fragmentElement,
                                 std::uint32_t ne) {
  const SeamIndex seamIndex(in.topology, in.cut.seams);
  DomainLinks links{UnionFind(std::size_t(ne) * 8), {}};
  std::vector<std::pair<VoxelCoord, std::uint32_t>> sorted;  // (voxel, element) of one face
  const std::uint32_t nf = in.topology.numFaces();
  for (FaceId f = 0; f < nf; ++f) {
    const std::uint32_t begin = faceFragmentStart[f], end = faceFragmentStart[f + 1];
    if (end - begin >= 2) joinFacePieces(in, fragmentElement, begin, end, sorted, links.functions);
    for (std::uint32_t i = begin; i < end; ++i) {
      linkFragmentEdges(in, seamIndex, faceFragmentStart, fragmentElement, f, i, links);
    }
  }
  return links;
}

// Weight of a node: int |grad phi|^2 over its element in grid units (tangential + normal).
std::vector<double> weighNodes(const std::vector<VoxelIntegrals>& records,
                               const std::vector<std::array<double, 36>>& normalStiffness) {
  std::vector<double> nodeWeight(records.size() * 8);
  for (std::uint32_t e = 0; e < records.size(); ++e) {
    for (int k = 0; k < 8; ++k) {
      const int kk = packedIndex(k, k);
      nodeWeight[8 * e + k] = records[e].stiffness[kk] + normalStiffness[e][kk];
    }
  }
  return nodeWeight;
}

// Basis functions: domains of one corner joined across seams (parts of a support that are
// disconnected on the uncut surface are separate functions). Returns their number.
std::uint32_t joinDomainsAcrossSeams(std::uint32_t nd, const std::vector<SeamLink>& seamLinks,
                                     const std::vector<std::uint32_t>& elementDomain,
                                     std::vector<std::uint32_t>& domainBasis) {
  UnionFind domains(nd);
  for (const SeamLink& link : seamLinks) {
    domains.unite(elementDomain[link.left], elementDomain[link.right]);
  }
  return denseLabels(domains, domainBasis);
}

// Grid corner of each basis function; a joined function keeps the corner of its larger part
// (nodes not flagged in joinedNode are written last).
std::vector<VoxelCoord> cornersOfBasisFunctions(std::uint32_t numBasisFunctions,
                                                const std::vector<std::uint32_t>& elementDomain,
                                                const std::vector<std::uint32_t>& domainBasis,
                                                const std::vector<VoxelCoord>& voxelCoords,
                                                const std::vector<std::uint32_t>& elementVoxel,
                                                const std::vector<std::uint8_t>& joinedNode) {
  std::vector<VoxelCoord> corner(numBasisFunctions);
  for (std::uint8_t pass : {1, 0}) {
    for (std::uint32_t e = 0; e < elementVoxel.size(); ++e) {
      const VoxelCoord& v = voxelCoords[elementVoxel[e]];
      for (int k = 0; k < 8; ++k) {
        if (joinedNode[8 * e + k] != pass) continue;
        corner[domainBasis[elementDomain[8 * e + k]]] = {
            v[0] + (k & 1), v[1] + (k >> 1 & 1), v[2] + (k >> 2 & 1)};
      }
    }
  }
  return corner;
}

}  // namespace

VoxelBasis::VoxelBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                       const CutResult& cut, const VoxelGridGeometry& grid,
                       std::vector<VoxelCoord> voxelCoords, std::vector<VoxelFragment> fragments,
                       const VoxelBasisOptions& options)
    : mesh_(mesh), grid_(grid), voxelCoords_(std::move(voxelCoords)) {
  const std::uint32_t nf = topology.numFaces();
  const std::uint32_t nv = static_cast<std::uint32_t>(voxelCoords_.size());
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength)) {
    throw InputError("voxel basis: edge length must be positive and finite");
  }
  if (mesh.numFaces() != nf || field.direction.size() != nf || cut.corners.size() != 3u * nf ||
      cut.faceRotation.size() != nf) {
    throw InputError("voxel basis: mesh, field or cut sizes do not match the topology (" +
                     std::to_string(nf) + " faces)");
  }
  if (fragments.size() >= kInvalidId) {
    throw InputError("voxel basis: more than 2^32 fragments; use a coarser grid");
  }
  const BasisInput in{mesh, topology, field, cut, grid_, voxelCoords_, fragments};
  reportProgress(options.progress, "voxel basis", 0.0);
  faceFragmentStart_ = indexFragmentsByFace(fragments, nf, nv);
  VoxelFragmentIndex byVoxel = indexFragmentsByVoxel(fragments, nv);
  Elements elements = buildElements(in, byVoxel);
  fragmentElement_ = std::move(elements.fragmentElement);
  voxelElementStart_ = std::move(elements.voxelElementStart);
  elementVoxel_ = std::move(elements.elementVoxel);
  reportProgress(options.progress, "voxel basis", 0.2);

  records_.assign(numElements(), VoxelIntegrals{});
  normalStiffness_.assign(numElements(), std::array<double, 36>{});
  setRegularization(options.regularization);
  integrateFragments(in, byVoxel, fragmentElement_, options.edgeLength, records_, normalStiffness_);
  byVoxel = {};
  reportProgress(options.progress, "voxel basis", 0.5);

  DomainLinks links = linkElementFunctions(in, faceFragmentStart_, fragmentElement_,
                                           static_cast<std::uint32_t>(numElements()));
  reportProgress(options.progress, "voxel basis", 0.8);
  std::vector<std::uint8_t> joinedNode;
  joinedDomains_ = joinNegligibleDomains(links.functions, weighNodes(records_, normalStiffness_),
                                         options.minDomainWeight, joinedNode);
  const std::uint32_t nd = denseLabels(links.functions, elementDomain_);
  links.functions = UnionFind(0);
  numBasisFunctions_ = joinDomainsAcrossSeams(nd, links.seamLinks, elementDomain_, domainBasis_);
  basisCorner_ = cornersOfBasisFunctions(numBasisFunctions_, elementDomain_, domainBasis_,
                                         voxelCoords_, elementVoxel_, joinedNode);
  std::vector<DomainAdjacency> adjacencies;
  for (const SeamLink& link : links.seamLinks) {
    adjacencies.push_back({elementDomain_[link.left], elementDomain_[link.right], link.seam});
  }
  setSeamAdjacencies(cut.seams, std::move(adjacencies));
  reportProgress(options.progress, "voxel basis", 1.0);
}

std::uint32_t VoxelBasis::elementDomains(std::uint64_t e, std::uint32_t* out) const {
  std::copy_n(elementDomain_.begin() + 8 * e, 8, out);
  return 8;
}

void VoxelBasis::setVoxelBlocks(const std::vector<std::uint32_t>& voxelBlockStart) {
  const std::size_t numVoxels = voxelCoords_.size();
  if (voxelBlockStart.empty() || voxelBlockStart.front() != 0 || voxelBlockStart.back() != numVoxels ||
      !std::is_sorted(voxelBlockStart.begin(), voxelBlockStart.end())) {
    throw InputError("voxel basis: block starts must rise from 0 to " + std::to_string(numVoxels));
  }
  elementBlockStart_.clear();
  for (std::uint32_t v : voxelBlockStart) elementBlockStart_.push_back(voxelElementStart_[v]);
}

void VoxelBasis::setRegularization(double weight) {
  if (!(weight >= 0.0) || !std::isfinite(weight)) {
    throw InputError("voxel basis: regularization must be finite and >= 0");
  }
  regularization_ = weight;
}

void VoxelBasis::elementIntegrals(std::uint64_t e, ElementIntegrals& out) const {
  const VoxelIntegrals& r = records_[e];
  const std::array<double, 36>& normal = normalStiffness_[e];
  out.count = 8;
  for (int a = 0; a < 8; ++a) {
    out.domain[a] = elementDomain_[8 * e + a];
    out.rhs[a] = r.rhs[a];
    for (int b = 0; b < 8; ++b) {
      const int k = packedIndex(a, b);
      out.stiffness[8 * a + b] = r.stiffness[k] + regularization_ * normal[k];
    }
  }
  out.area = r.area;
}

std::vector<std::uint32_t> VoxelBasis::faceElements(FaceId f) const {
  return {fragmentElement_.begin() + faceFragmentStart_[f],
          fragmentElement_.begin() + faceFragmentStart_[f + 1]};
}

std::uint32_t VoxelBasis::cornerElement(CornerId c) const {
  const FaceId f = cornerFace(c);
  const std::uint32_t begin = faceFragmentStart_[f], end = faceFragmentStart_[f + 1];
  if (begin == end) return kInvalidId;
  const Vec3d x = grid_.toGrid(mesh_.position(mesh_.triangles[f][c % 3]));
  const VoxelCoord home = grid_.voxelOf(x);
  // The fragment in the vertex's own voxel, else the one whose voxel is nearest (a vertex on a
  // grid plane whose triangle lies on the lower side); ties go to the first, so the choice is
  // consistent.
  std::uint32_t best = kInvalidId;
  double bestDistance = 1e300;
  for (std::uint32_t i = begin; i < end; ++i) {
    const VoxelCoord& v = voxelCoords_[elementVoxel_[fragmentElement_[i]]];
    if (v == home) return fragmentElement_[i];
    double distance = 0.0;
    for (int a = 0; a < 3; ++a) {
      distance += std::pow(std::max({0.0, v[a] - x[a], x[a] - (v[a] + 1)}), 2);
    }
    if (distance < bestDistance) bestDistance = distance, best = fragmentElement_[i];
  }
  return best;
}

void VoxelBasis::evaluateCorners(const std::vector<std::complex<double>>& coefficients,
                                 WedgeMap& cornerUV) const {
  const std::uint32_t nf = static_cast<std::uint32_t>(faceFragmentStart_.size() - 1);
  checkCorners(cornerUV, 3u * std::size_t(nf), "voxel basis evaluation");
  // One evaluation per wedge, at its smallest corner: the basis is continuous across the
  // non-cut edges inside a wedge.
  const std::vector<CornerId> wedgeCorner = cornerUV.wedgeCorners();
  parallelFor(cornerUV.numWedges(), 4096, [&](const IndexRange& range) {
    for (std::uint32_t wedge = range.begin(); wedge != range.end(); ++wedge) {
      const CornerId c = wedgeCorner[wedge];
      if (c == kInvalidId) continue;
      const std::uint32_t e = cornerElement(c);
      if (e == kInvalidId) continue;
      const VoxelCoord& v = voxelCoords_[elementVoxel_[e]];
      const Vec3d x = grid_.toGrid(mesh_.position(mesh_.triangles[cornerFace(c)][c % 3]));
      const Vec3d t = (x - Vec3d(v[0], v[1], v[2])).cwiseMax(0.0).cwiseMin(1.0);
      double w[8];
      trilinearWeights(t, w);
      std::complex<double> q = 0.0;
      for (int k = 0; k < 8; ++k) q += w[k] * coefficients[elementDomain_[8 * e + k]];
      cornerUV.setWedgeValue(wedge, Vec2d(q.real(), q.imag()));
    }
  });
}

std::vector<FaceId> VoxelBasis::supportFaces(const std::vector<std::uint32_t>& basisFunctions) const {
  std::vector<std::uint8_t> marked(numBasisFunctions_, 0);
  for (std::uint32_t b : basisFunctions) {
    if (b < marked.size()) marked[b] = 1;
  }
  std::vector<std::uint8_t> elementMarked(elementVoxel_.size(), 0);
  for (std::size_t e = 0; e < elementVoxel_.size(); ++e) {
    for (int k = 0; k < 8; ++k) elementMarked[e] |= marked[domainBasis_[elementDomain_[8 * e + k]]];
  }
  std::vector<FaceId> faces;
  const std::uint32_t nf = static_cast<std::uint32_t>(faceFragmentStart_.size() - 1);
  for (FaceId f = 0; f < nf; ++f) {
    for (std::uint32_t i = faceFragmentStart_[f]; i < faceFragmentStart_[f + 1]; ++i) {
      if (elementMarked[fragmentElement_[i]]) {
        faces.push_back(f);
        break;
      }
    }
  }
  return faces;
}

std::vector<FaceId> VoxelBasis::markedFaces(const Reduction& reduction) const {
  std::vector<std::uint32_t> basis = reduction.determinedBasis;
  basis.insert(basis.end(), reduction.inconsistentBasis.begin(), reduction.inconsistentBasis.end());
  return supportFaces(basis);
}

VoxelBasisStats VoxelBasis::stats() const {
  VoxelBasisStats s;
  s.voxels = voxelCoords_.size();
  s.fragments = fragmentElement_.size();
  s.elements = elementVoxel_.size();
  s.joinedDomains = joinedDomains_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  s.bytes = bytes(voxelCoords_) + bytes(voxelElementStart_) + bytes(elementVoxel_) +
            bytes(records_) + bytes(normalStiffness_) + bytes(elementDomain_) + bytes(faceFragmentStart_) +
            bytes(fragmentElement_) + bytes(basisCorner_) + bytes(domainBasis_) +
            bytes(adjacencies_) + bytes(seamRotation_);
  return s;
}

}  // namespace seamvox
