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
using detail::DomainLinks;
using detail::FaceFragment;
using detail::SeamLink;
using detail::UnionFind;

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

// Domains: element functions of one grid corner joined inside its support, face by face; and
// the seam links between domains.
DomainLinks linkElementFunctions(const BasisInput& in, const std::vector<std::uint32_t>& faceFragmentStart,
                                 const std::vector<std::uint32_t>& fragmentElement, std::uint32_t ne) {
  const SeamIndex seamIndex(in.topology, in.cut.seams);
  DomainLinks links{UnionFind(std::size_t(ne) * 8), {}};
  const auto fragmentsOf = [&](FaceId f, std::vector<FaceFragment>& out) {
    out.clear();
    for (std::uint32_t i = faceFragmentStart[f]; i < faceFragmentStart[f + 1]; ++i) {
      const VoxelFragment& fr = in.fragments[i];
      out.push_back({in.voxelCoords[fr.voxel], fragmentElement[i], static_cast<std::uint8_t>(fr.edgeMask)});
    }
  };
  // The links of a chunk of faces are found in parallel and applied in face order.
  const auto work = [&](detail::LinkChunk& chunk) {
    std::vector<FaceFragment> mine;
    detail::LinkScratch scratch;
    for (FaceId f = chunk.begin; f < chunk.end; ++f) {
      fragmentsOf(f, mine);
      if (mine.empty()) continue;
      detail::linkFaceFragments(
          f, mine, faceGridCoords(in.mesh, in.grid, f), [&](CornerId c) { return in.topology.opposite(c); },
          [&](CornerId c) { return in.cut.corners.isCut(c); }, [&](CornerId c) { return seamIndex.find(c); },
          fragmentsOf, scratch, chunk.links);
    }
  };
  detail::facesInOrder<detail::LinkChunk>(in.topology.numFaces(), 1u << 14, work,
                                          [&](detail::LinkChunk& chunk) { chunk.links.applyTo(links); });
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
// seamLinks: between nodes 8 e + k.
std::uint32_t joinDomainsAcrossSeams(std::uint32_t nd, const std::vector<DomainAdjacency>& seamLinks,
                                     const std::vector<std::uint32_t>& elementDomain,
                                     std::vector<std::uint32_t>& domainBasis) {
  UnionFind domains(nd);
  for (const DomainAdjacency& link : seamLinks) {
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

// Elements, integrals and domain links of the fragments (ordered by face) over the voxels.
detail::VoxelBasisParts buildParts(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                   const CutResult& cut, const VoxelGridGeometry& grid,
                                   std::vector<VoxelCoord> voxelCoords, const std::vector<VoxelFragment>& fragments,
                                   const VoxelBasisOptions& options) {
  const std::uint32_t nf = topology.numFaces();
  const std::uint32_t nv = static_cast<std::uint32_t>(voxelCoords.size());
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
  detail::VoxelBasisParts parts;
  parts.grid = grid;
  parts.voxelCoords = std::move(voxelCoords);
  const BasisInput in{mesh, topology, field, cut, parts.grid, parts.voxelCoords, fragments};
  reportProgress(options.progress, "voxel basis", 0.0);
  parts.faceFragmentStart = indexFragmentsByFace(fragments, nf, nv);
  VoxelFragmentIndex byVoxel = indexFragmentsByVoxel(fragments, nv);
  Elements elements = buildElements(in, byVoxel);
  parts.fragmentElement = std::move(elements.fragmentElement);
  parts.voxelElementStart = std::move(elements.voxelElementStart);
  parts.elementVoxel = std::move(elements.elementVoxel);
  reportProgress(options.progress, "voxel basis", 0.2);

  const std::size_t ne = parts.elementVoxel.size();
  parts.records.assign(ne, VoxelIntegrals{});
  parts.normalStiffness.assign(ne, std::array<double, 36>{});
  integrateFragments(in, byVoxel, parts.fragmentElement, options.edgeLength, parts.records, parts.normalStiffness);
  byVoxel = {};
  reportProgress(options.progress, "voxel basis", 0.5);

  parts.links = linkElementFunctions(in, parts.faceFragmentStart, parts.fragmentElement, static_cast<std::uint32_t>(ne));
  reportProgress(options.progress, "voxel basis", 0.8);
  return parts;
}

}  // namespace

VoxelBasis::VoxelBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                       const CutResult& cut, const VoxelGridGeometry& grid,
                       std::vector<VoxelCoord> voxelCoords, std::vector<VoxelFragment> fragments,
                       const VoxelBasisOptions& options)
    : VoxelBasis(&mesh, buildParts(mesh, topology, field, cut, grid, std::move(voxelCoords), fragments, options),
                 cut.seams, options) {}

VoxelBasis::VoxelBasis(const TriangleMesh* mesh, detail::VoxelBasisParts parts, const std::vector<SeamCurve>& seams,
                       const VoxelBasisOptions& options)
    : mesh_(mesh), grid_(parts.grid), voxelCoords_(std::move(parts.voxelCoords)),
      voxelElementStart_(std::move(parts.voxelElementStart)), elementVoxel_(std::move(parts.elementVoxel)),
      records_(std::move(parts.records)), normalStiffness_(std::move(parts.normalStiffness)),
      faceFragments_(parts.faceFragmentStart), fragmentElement_(std::move(parts.fragmentElement)) {
  std::vector<std::uint32_t>().swap(parts.faceFragmentStart);
  if (voxelElementStart_.size() != voxelCoords_.size() + 1 || voxelElementStart_.back() != elementVoxel_.size() ||
      records_.size() != elementVoxel_.size() || normalStiffness_.size() != elementVoxel_.size() ||
      parts.links.functions.parent.size() != 8 * elementVoxel_.size()) {
    throw InputError("voxel basis: element parts of mismatched sizes");
  }
  setSeamAdjacencies(seams, {});  // the rotations; the adjacencies come with the domains
  builtRegularization_ = options.regularization;
  functionLinks_ = std::move(parts.links.functions.parent);
  for (const SeamLink& link : parts.links.seamLinks) nodeSeamLinks_.push_back({link.left, link.right, link.seam});
  parts.links = DomainLinks();
  joinDomains(options.minDomainWeight);
  reportProgress(options.progress, "voxel basis", 1.0);
}

void VoxelBasis::joinDomains(double minDomainWeight) {
  setRegularization(builtRegularization_);
  UnionFind functions(0);
  functions.parent = functionLinks_;
  std::vector<std::uint8_t> joinedNode;
  joinedDomains_ = joinNegligibleDomains(functions, weighNodes(records_, normalStiffness_), minDomainWeight, joinedNode);
  const std::uint32_t nd = denseLabels(functions, elementDomain_);
  functions = UnionFind(0);
  numBasisFunctions_ = joinDomainsAcrossSeams(nd, nodeSeamLinks_, elementDomain_, domainBasis_);
  basisCorner_ = cornersOfBasisFunctions(numBasisFunctions_, elementDomain_, domainBasis_,
                                         voxelCoords_, elementVoxel_, joinedNode);
  std::vector<DomainAdjacency> adjacencies;
  adjacencies.reserve(nodeSeamLinks_.size());
  for (const DomainAdjacency& link : nodeSeamLinks_) {
    adjacencies.push_back({elementDomain_[link.left], elementDomain_[link.right], link.seam});
  }
  setDomainAdjacencies(std::move(adjacencies));
}

const TriangleMesh& VoxelBasis::mesh() const {
  if (!mesh_) {
    throw InputError("voxel basis: built out of core, its faces are in the scratch folder (evaluate it there)");
  }
  return *mesh_;
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

FragmentRanges::FragmentRanges(const std::vector<std::uint32_t>& start) {
  if (start.empty()) return;
  const std::uint32_t nf = static_cast<std::uint32_t>(start.size() - 1);
  count_.resize(nf);
  blockStart_.resize((std::uint64_t(nf) + kBlockMask) >> kBlockBits);
  for (FaceId f = 0; f < nf; ++f) {
    if ((f & kBlockMask) == 0) blockStart_[f >> kBlockBits] = start[f];
    const std::uint32_t n = start[f + 1] - start[f];
    count_[f] = static_cast<std::uint8_t>(std::min<std::uint32_t>(n, kLarge));
    if (n >= kLarge) large_.push_back({f, n});
  }
}

std::uint32_t FragmentRanges::largeCount(FaceId f) const {
  return std::lower_bound(large_.begin(), large_.end(), std::make_pair(f, std::uint32_t(0)))->second;
}

std::size_t FragmentRanges::bytes() const {
  return count_.capacity() + blockStart_.capacity() * sizeof(std::uint32_t) + large_.capacity() * sizeof(large_[0]);
}

std::vector<std::uint32_t> VoxelBasis::faceElements(FaceId f) const {
  (void)mesh();  // the per-face index is kept only with the mesh
  const std::uint32_t begin = faceFragments_.begin(f);
  return {fragmentElement_.begin() + begin, fragmentElement_.begin() + begin + faceFragments_.count(f)};
}

std::uint32_t VoxelBasis::cornerElement(CornerId c) const {
  const TriangleMesh& mesh = this->mesh();
  const FaceId f = cornerFace(c);
  const Vec3d x = grid_.toGrid(mesh.position(mesh.triangles[f][c % 3]));
  const std::uint32_t begin = faceFragments_.begin(f);
  return nearestElement(x, faceFragments_.count(f), [&](std::uint32_t i) { return fragmentElement_[begin + i]; });
}

std::complex<double> VoxelBasis::evaluateAt(std::uint32_t e, const Vec3d& x,
                                            const std::vector<std::complex<double>>& coefficients) const {
  const VoxelCoord& v = voxelCoords_[elementVoxel_[e]];
  const Vec3d t = (x - Vec3d(v[0], v[1], v[2])).cwiseMax(0.0).cwiseMin(1.0);
  double w[8];
  trilinearWeights(t, w);
  std::complex<double> q = 0.0;
  for (int k = 0; k < 8; ++k) q += w[k] * coefficients[elementDomain_[8 * e + k]];
  return q;
}

void VoxelBasis::evaluateCorners(const std::vector<std::complex<double>>& coefficients,
                                 WedgeMap& cornerUV) const {
  const TriangleMesh& mesh = this->mesh();
  const std::uint32_t nf = mesh.numFaces();
  checkCorners(cornerUV, 3u * std::size_t(nf), "voxel basis evaluation");
  // One evaluation per wedge, at its smallest corner: the basis is continuous across the
  // non-cut edges inside a wedge. The smallest corners a range of wedges at a time: this runs
  // at the pipeline's peak, next to the basis and the new map (a table for all wedges: 4 bytes
  // each, 44 MiB at 23M faces; 16 MiB at once, each range a pass over the corners).
  constexpr std::uint32_t kWedgesAtOnce = 1u << 22;
  for (std::uint32_t begin = 0; begin < cornerUV.numWedges(); begin += kWedgesAtOnce) {
    const std::vector<CornerId> wedgeCorner = cornerUV.wedgeCorners(begin, begin + kWedgesAtOnce);
    parallelFor(wedgeCorner.size(), 4096, [&](const IndexRange& range) {
      for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
        const CornerId c = wedgeCorner[i];
        if (c == kInvalidId) continue;
        const std::uint32_t e = cornerElement(c);
        if (e == kInvalidId) continue;
        const Vec3d x = grid_.toGrid(mesh.position(mesh.triangles[cornerFace(c)][c % 3]));
        const std::complex<double> q = evaluateAt(e, x, coefficients);
        cornerUV.setWedgeValue(static_cast<std::uint32_t>(begin + i), Vec2d(q.real(), q.imag()));
      }
    });
  }
}

std::vector<std::uint8_t> VoxelBasis::elementsTouching(const std::vector<std::uint32_t>& basisFunctions) const {
  std::vector<std::uint8_t> marked(numBasisFunctions_, 0);
  for (std::uint32_t b : basisFunctions) {
    if (b < marked.size()) marked[b] = 1;
  }
  std::vector<std::uint8_t> elementMarked(elementVoxel_.size(), 0);
  for (std::size_t e = 0; e < elementVoxel_.size(); ++e) {
    for (int k = 0; k < 8; ++k) elementMarked[e] |= marked[domainBasis_[elementDomain_[8 * e + k]]];
  }
  return elementMarked;
}

std::vector<FaceId> VoxelBasis::supportFaces(const std::vector<std::uint32_t>& basisFunctions) const {
  (void)mesh();  // the per-face index is kept only with the mesh
  const std::vector<std::uint8_t> elementMarked = elementsTouching(basisFunctions);
  std::vector<FaceId> faces;
  const std::uint32_t nf = faceFragments_.numFaces();
  std::uint32_t end = 0;
  for (FaceId f = 0; f < nf; ++f) {
    const std::uint32_t begin = end;
    end += faceFragments_.count(f);
    for (std::uint32_t i = begin; i < end; ++i) {
      if (elementMarked[fragmentElement_[i]]) {
        faces.push_back(f);
        break;
      }
    }
  }
  return faces;
}

std::vector<std::uint32_t> markedBasisFunctions(const Reduction& reduction) {
  std::vector<std::uint32_t> basis = reduction.determinedBasis;
  basis.insert(basis.end(), reduction.inconsistentBasis.begin(), reduction.inconsistentBasis.end());
  return basis;
}

std::vector<FaceId> VoxelBasis::markedFaces(const Reduction& reduction) const {
  return supportFaces(markedBasisFunctions(reduction));
}

VoxelBasisStats VoxelBasis::stats() const {
  VoxelBasisStats s;
  s.voxels = voxelCoords_.size();
  s.fragments = fragmentElement_.size();  // 0 when built out of core
  s.elements = elementVoxel_.size();
  s.joinedDomains = joinedDomains_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  s.bytes = bytes(voxelCoords_) + bytes(voxelElementStart_) + bytes(elementVoxel_) +
            bytes(records_) + bytes(normalStiffness_) + bytes(elementDomain_) + bytes(functionLinks_) +
            bytes(nodeSeamLinks_) + faceFragments_.bytes() +
            bytes(fragmentElement_) + bytes(basisCorner_) + bytes(domainBasis_) +
            bytes(adjacencies_) + bytes(seamRotation_);
  return s;
}

}  // namespace seamvox
