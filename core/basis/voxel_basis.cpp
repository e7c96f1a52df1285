#include "core/basis/voxel_basis.h"


#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <tuple>

#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

using detail::UnionFind;

// Dense labels 0.. of the union-find classes, in order of first appearance.
std::uint32_t denseLabels(UnionFind& uf, std::vector<std::uint32_t>& label) {
  const std::size_t n = uf.parent.size();
  std::vector<std::uint32_t> rootLabel(n, kInvalidId);
  label.resize(n);
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t r = uf.find(static_cast<std::uint32_t>(i));
    if (rootLabel[r] == kInvalidId) rootLabel[r] = count++;
    label[i] = rootLabel[r];
  }
  return count;
}

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

Vec3d combedDirection(const TriangleMesh& mesh, const CrossField& field, const CutResult& cut,
                      FaceId f, Vec3d& normal) {
  normal = faceNormal(mesh, f);
  Vec3d u = field.at(f);
  for (int k = 0; k < cut.faceRotation[f] % 4; ++k) u = normal.cross(u);
  return u;
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
  const std::uint32_t nfrag = static_cast<std::uint32_t>(fragments.size());
  reportProgress(options.progress, "voxel basis", 0.0);

  // Fragments per face (they arrive ordered by face) and per voxel (stable: ordered by face).
  faceFragmentStart_.assign(nf + 1, 0);
  for (std::uint32_t i = 0; i < nfrag; ++i) {
    const VoxelFragment& fr = fragments[i];
    if (fr.face >= nf || fr.voxel >= nv || (i > 0 && fr.face < fragments[i - 1].face)) {
      throw InputError("voxel basis: fragment " + std::to_string(i) +
                       " is out of range or not ordered by face");
    }
    ++faceFragmentStart_[fr.face + 1];
  }
  std::partial_sum(faceFragmentStart_.begin(), faceFragmentStart_.end(),
                   faceFragmentStart_.begin());
  std::vector<std::uint32_t> voxelFragmentStart(nv + 1, 0), voxelFragments(nfrag);
  for (const VoxelFragment& fr : fragments) ++voxelFragmentStart[fr.voxel + 1];
  std::partial_sum(voxelFragmentStart.begin(), voxelFragmentStart.end(),
                   voxelFragmentStart.begin());
  {
    std::vector<std::uint32_t> fill(voxelFragmentStart.begin(), voxelFragmentStart.end() - 1);
    for (std::uint32_t i = 0; i < nfrag; ++i) voxelFragments[fill[fragments[i].voxel]++] = i;
  }

  // Elements: per voxel, fragments joined through shared non-cut edges (union-find).
  fragmentElement_.assign(nfrag, 0);
  voxelElementStart_.assign(nv + 1, 0);
  parallelFor(nv, 64, [&](const IndexRange& range) {
    std::vector<FaceId> faces;
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      const std::uint32_t begin = voxelFragmentStart[v], m = voxelFragmentStart[v + 1] - begin;
      faces.resize(m);
      for (std::uint32_t i = 0; i < m; ++i) faces[i] = fragments[voxelFragments[begin + i]].face;
      UnionFind uf(m);
      for (std::uint32_t i = 0; i < m; ++i) {
        const VoxelFragment& fr = fragments[voxelFragments[begin + i]];
        for (int j = 0; j < 3; ++j) {
          const CornerId c = 3 * fr.face + j;
          if (!(fr.edgeMask >> j & 1) || cut.corners.isCut(c)) continue;
          const CornerId o = topology.opposite(c);
          if (o == kInvalidId) continue;
          const auto it = std::lower_bound(faces.begin(), faces.end(), cornerFace(o));
          if (it == faces.end() || *it != cornerFace(o)) continue;
          const std::uint32_t i2 = static_cast<std::uint32_t>(it - faces.begin());
          if (fragments[voxelFragments[begin + i2]].edgeMask >> (o % 3) & 1) uf.unite(i, i2);
        }
      }
      std::vector<std::uint32_t> label;
      voxelElementStart_[v + 1] = denseLabels(uf, label);
      for (std::uint32_t i = 0; i < m; ++i) fragmentElement_[voxelFragments[begin + i]] = label[i];
    }
  });
  std::partial_sum(voxelElementStart_.begin(), voxelElementStart_.end(),
                   voxelElementStart_.begin());
  const std::uint32_t ne = voxelElementStart_[nv];
  if (std::uint64_t(ne) * 8 >= kInvalidId) {
    throw InputError("voxel basis: too many elements (" + std::to_string(ne) +
                     "); use a coarser grid");
  }
  for (std::uint32_t i = 0; i < nfrag; ++i) {
    fragmentElement_[i] += voxelElementStart_[fragments[i].voxel];
  }
  elementVoxel_.resize(ne);
  for (std::uint32_t v = 0; v < nv; ++v) {
    for (std::uint32_t e = voxelElementStart_[v]; e < voxelElementStart_[v + 1]; ++e) {
      elementVoxel_[e] = v;
    }
  }
  reportProgress(options.progress, "voxel basis", 0.2);

  // Integrals: re-clip each fragment against its voxel (no polygons are stored).
  records_.assign(ne, VoxelIntegrals{});
  normalStiffness_.assign(ne, std::array<double, 36>{});
  setRegularization(options.regularization);
  parallelFor(nv, 16, [&](const IndexRange& range) {
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      for (std::uint32_t k = voxelFragmentStart[v]; k < voxelFragmentStart[v + 1]; ++k) {
        const std::uint32_t i = voxelFragments[k];
        const FaceId f = fragments[i].face;
        Vec3d n;
        const Vec3d u = combedDirection(mesh, field, cut, f, n);
        if (n.squaredNorm() == 0.0) continue;  // zero-area face: nothing to integrate
        const ClipPolygon piece = clipTriangleToVoxel(faceGridCoords(mesh, grid_, f), voxelCoords_[v]);
        const std::uint32_t e = fragmentElement_[i];
        addFragmentIntegrals(piece, voxelCoords_[v], grid_.voxelSize, n, u, options.edgeLength,
                             records_[e], 0.0, normalStiffness_[e].data());
      }
    }
  });
  voxelFragmentStart = {};
  voxelFragments = {};
  reportProgress(options.progress, "voxel basis", 0.5);

  // Domains: element functions (nodes 8 e + k) of one grid corner joined inside its support.
  const SeamIndex seamIndex(topology, cut.seams);
  UnionFind functions(std::size_t(ne) * 8);
  std::vector<SeamLink> seamLinks;
  std::vector<std::pair<VoxelCoord, std::uint32_t>> sorted;  // (voxel, element) of one face
  for (FaceId f = 0; f < nf; ++f) {
    const std::uint32_t begin = faceFragmentStart_[f], end = faceFragmentStart_[f + 1];
    // (a) One triangle meets a support (a convex box) in a convex, connected piece: its
    // fragments in any two voxels of the support belong to the same domain.
    if (end - begin >= 2) {
      sorted.clear();
      for (std::uint32_t i = begin; i < end; ++i) {
        sorted.emplace_back(voxelCoords_[fragments[i].voxel], fragmentElement_[i]);
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
    // (b) Two triangles across an edge meet in the support along the edge's piece: non-cut
    // edges join their domains, seam edges make a seam adjacency.
    for (std::uint32_t i = begin; i < end; ++i) {
      const VoxelFragment& fr = fragments[i];
      const VoxelCoord& a = voxelCoords_[fr.voxel];
      const std::array<Vec3d, 3> g = faceGridCoords(mesh, grid_, f);
      for (int j = 0; j < 3; ++j) {
        const CornerId c = 3 * f + j;
        const CornerId o = topology.opposite(c);
        if (!(fr.edgeMask >> j & 1) || o == kInvalidId || cornerFace(o) < f) continue;
        const bool isCut = cut.corners.isCut(c);
        const SeamIndex::Side side = isCut ? seamIndex.find(c) : SeamIndex::Side{};
        if (isCut && side.seam == kInvalidId) continue;
        const FaceId h = cornerFace(o);
        const Vec3d& p = g[(j + 1) % 3];
        const Vec3d& q = g[(j + 2) % 3];
        for (std::uint32_t i2 = faceFragmentStart_[h]; i2 < faceFragmentStart_[h + 1]; ++i2) {
          const VoxelFragment& other = fragments[i2];
          if (!(other.edgeMask >> (o % 3) & 1)) continue;
          const VoxelCoord& b = voxelCoords_[other.voxel];
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
          const std::uint32_t ea = fragmentElement_[i], eb = fragmentElement_[i2];
          forSharedCorners(d, [&](int k, int k2) {
            if (!isCut) {
              functions.unite(8 * ea + k, 8 * eb + k2);
            } else if (side.left) {
              seamLinks.push_back({8 * ea + k, 8 * eb + k2, side.seam});
            } else {
              seamLinks.push_back({8 * eb + k2, 8 * ea + k, side.seam});
            }
          });
        }
      }
    }
  }
  reportProgress(options.progress, "voxel basis", 0.8);

  std::vector<std::uint8_t> joinedNode;
  {
    // Weight of a node: int |grad phi|^2 over its element in grid units (tangential + normal).
    std::vector<double> nodeWeight(std::size_t(ne) * 8);
    for (std::uint32_t e = 0; e < ne; ++e) {
      for (int k = 0; k < 8; ++k) {
        const int kk = packedIndex(k, k);
        nodeWeight[8 * e + k] = records_[e].stiffness[kk] + normalStiffness_[e][kk];
      }
    }
    joinedDomains_ = joinNegligibleDomains(functions, nodeWeight, options.minDomainWeight, joinedNode);
  }
  const std::uint32_t nd = denseLabels(functions, elementDomain_);
  functions = UnionFind(0);
  // Basis functions: domains of one corner joined across seams (parts of a support that are
  // disconnected on the uncut surface are separate functions).
  UnionFind domains(nd);
  for (const SeamLink& link : seamLinks) {
    domains.unite(elementDomain_[link.left], elementDomain_[link.right]);
  }
  numBasisFunctions_ = denseLabels(domains, domainBasis_);
  basisCorner_.resize(numBasisFunctions_);
  for (std::uint8_t pass : {1, 0}) {  // a joined function keeps the corner of its larger part
    for (std::uint32_t e = 0; e < ne; ++e) {
      const VoxelCoord& v = voxelCoords_[elementVoxel_[e]];
      for (int k = 0; k < 8; ++k) {
        if (joinedNode[8 * e + k] != pass) continue;
        basisCorner_[domainBasis_[elementDomain_[8 * e + k]]] = {
            v[0] + (k & 1), v[1] + (k >> 1 & 1), v[2] + (k >> 2 & 1)};
      }
    }
  }
  for (const SeamLink& link : seamLinks) {
    adjacencies_.push_back({elementDomain_[link.left], elementDomain_[link.right], link.seam});
  }
  auto key = [](const DomainAdjacency& x) { return std::make_tuple(x.left, x.right, x.seam); };
  std::sort(adjacencies_.begin(), adjacencies_.end(),
            [&](const auto& x, const auto& y) { return key(x) < key(y); });
  adjacencies_.erase(std::unique(adjacencies_.begin(), adjacencies_.end(),
                                 [&](const auto& x, const auto& y) { return key(x) == key(y); }),
                     adjacencies_.end());
  seamRotation_.resize(cut.seams.size());
  for (std::size_t s = 0; s < cut.seams.size(); ++s) {
    seamRotation_[s] = static_cast<std::uint8_t>((4 - cut.seams[s].matching % 4) % 4);  // i^-k
  }
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
