#include "core/basis/basis.h"

#include <algorithm>
#include <cmath>

#include "core/system/errors.h"

namespace seamvox {

void hatTriangleIntegrals(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& u,
                          double edgeLength, double stiffness[9], std::complex<double> rhs[3]) {
  std::fill(stiffness, stiffness + 9, 0.0);
  std::fill(rhs, rhs + 3, std::complex<double>(0.0));
  const Vec3d p[3] = {p0, p1, p2};
  const Vec3d normal = (p1 - p0).cross(p2 - p0);
  const double twiceArea = normal.norm();
  const double longest = std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(),
                                   (p0 - p2).squaredNorm()});
  if (!(twiceArea > 1e-14 * longest) || !std::isfinite(twiceArea)) return;  // zero area
  const Vec3d n = normal / twiceArea;
  const Vec3d v = n.cross(u);
  // A needle or cap has a huge |cot|: the whole triangle's weight is scaled down so that none
  // exceeds kMaxCotangent. Clamping single cotangents instead breaks cot_a cot_b + cot_b cot_c +
  // cot_c cot_a = 1, which keeps the 3x3 stiffness semi-definite (a spike made K indefinite).
  double cot[3], largest = 0.0;
  for (int k = 0; k < 3; ++k) {
    // cot of the angle at vertex k weights the edge opposite it.
    cot[k] = (p[(k + 1) % 3] - p[k]).dot(p[(k + 2) % 3] - p[k]) / twiceArea;
    largest = std::max(largest, std::abs(cot[k]));
  }
  const double weight = largest > kMaxCotangent ? kMaxCotangent / largest : 1.0;
  for (int k = 0; k < 3; ++k) {
    const Vec3d& b = p[(k + 1) % 3];
    const Vec3d& c = p[(k + 2) % 3];
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    stiffness[3 * i + j] = stiffness[3 * j + i] = -0.5 * weight * cot[k];
    // grad phi_k = n x e_k / (2A) with e_k = c - b; times the area A (and the weight).
    const Vec3d g = n.cross(c - b) * (0.5 * weight);
    rhs[k] = std::complex<double>(g.dot(u), g.dot(v)) / edgeLength;
  }
  for (int i = 0; i < 3; ++i) {
    stiffness[3 * i + i] = -(stiffness[3 * i + (i + 1) % 3] + stiffness[3 * i + (i + 2) % 3]);
  }
}

HatBasis::HatBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                   const CutResult& cut, const HatBasisOptions& options)
    : mesh_(mesh), field_(field), cut_(cut), edgeLength_(options.edgeLength) {
  const std::uint32_t nf = topology.numFaces();
  if (!(edgeLength_ > 0.0) || !std::isfinite(edgeLength_)) {
    throw InputError("hat basis: edge length must be positive and finite");
  }
  if (field.direction.size() != nf || cut.corners.size() != 3u * nf || cut.faceRotation.size() != nf) {
    throw InputError("hat basis: field or cut sizes do not match the mesh (" +
                     std::to_string(nf) + " faces)");
  }
  std::vector<std::uint8_t> inSubset(nf, options.faces.empty() ? 1 : 0);
  if (options.faces.empty()) {
    faces_.resize(nf);
    for (FaceId f = 0; f < nf; ++f) faces_[f] = f;
  } else {
    faces_ = options.faces;
    for (FaceId f : faces_) {
      if (f >= nf) throw InputError("hat basis: face " + std::to_string(f) + " out of range");
      inSubset[f] = 1;
    }
  }

  // Wedges: walk each fan counter-clockwise; a cut edge (or the subset's border) starts a new one.
  cornerDomain_.assign(3u * nf, kInvalidId);
  // With a face subset only its vertices can get a wedge: walk those (in increasing order, as the
  // whole-mesh walk would), not every fan of a large mesh.
  std::vector<VertexId> subsetVertices;
  if (!options.faces.empty()) {
    subsetVertices.reserve(3 * faces_.size());
    for (FaceId f : faces_) {
      for (VertexId v : topology.triangles()[f]) subsetVertices.push_back(v);
    }
    std::sort(subsetVertices.begin(), subsetVertices.end());
    subsetVertices.erase(std::unique(subsetVertices.begin(), subsetVertices.end()), subsetVertices.end());
  }
  const std::size_t numWalked = options.faces.empty() ? topology.numVertices() : subsetVertices.size();
  std::vector<CornerId> fan;
  for (std::size_t i = 0; i < numWalked; ++i) {
    const VertexId v = options.faces.empty() ? static_cast<VertexId>(i) : subsetVertices[i];
    fan.clear();
    topology.forEachCornerAround(v, [&](CornerId c) { fan.push_back(c); });
    if (fan.empty()) continue;
    const std::size_t m = fan.size();
    const bool closed = topology.ccw(fan.back()) == fan.front();
    auto separated = [&](std::size_t j) {  // is there a wedge border just before fan[j]?
      const CornerId before = j > 0 ? fan[j - 1] : fan[m - 1];
      if (j == 0 && !closed) return true;
      return cut.corners.isCut(nextCorner(before)) || !inSubset[cornerFace(before)] ||
             !inSubset[cornerFace(fan[j])];
    };
    std::size_t start = 0;
    for (std::size_t j = 0; j < m; ++j) {
      if (separated(j)) {
        start = j;
        break;
      }
    }
    bool anyDomain = false;
    std::uint32_t current = kInvalidId;
    for (std::size_t step = 0; step < m; ++step) {
      const std::size_t j = (start + step) % m;
      const CornerId c = fan[j];
      if (!inSubset[cornerFace(c)]) {
        current = kInvalidId;
        continue;
      }
      if (current == kInvalidId || separated(j)) {
        if (!anyDomain) {
          basisVertex_.push_back(v);
          anyDomain = true;
        }
        current = static_cast<std::uint32_t>(domainBasis_.size());
        domainBasis_.push_back(static_cast<std::uint32_t>(basisVertex_.size() - 1));
      }
      cornerDomain_[c] = current;
    }
  }
  numBasisFunctions_ = static_cast<std::uint32_t>(basisVertex_.size());

  // Seam adjacency: the wedges on either side of every seam edge, at both of its endpoints.
  seamRotation_.resize(cut.seams.size());
  for (std::uint32_t s = 0; s < cut.seams.size(); ++s) {
    const SeamCurve& seam = cut.seams[s];
    seamRotation_[s] = static_cast<std::uint8_t>((4 - seam.matching % 4) % 4);  // r = i^(-k)
    for (CornerId c : seam.corners) {
      const CornerId o = topology.opposite(c);
      if (o == kInvalidId) {
        throw InputError("hat basis: seam " + std::to_string(s) + " has boundary edge of corner " +
                         std::to_string(c));
      }
      if (!inSubset[cornerFace(c)] || !inSubset[cornerFace(o)]) continue;
      adjacencies_.push_back({cornerDomain_[nextCorner(c)], cornerDomain_[prevCorner(o)], s});
      adjacencies_.push_back({cornerDomain_[prevCorner(c)], cornerDomain_[nextCorner(o)], s});
    }
  }
  auto key = [](const DomainAdjacency& a) { return std::make_tuple(a.left, a.right, a.seam); };
  std::sort(adjacencies_.begin(), adjacencies_.end(),
            [&](const auto& a, const auto& b) { return key(a) < key(b); });
  adjacencies_.erase(std::unique(adjacencies_.begin(), adjacencies_.end(),
                                 [&](const auto& a, const auto& b) { return key(a) == key(b); }),
                     adjacencies_.end());
}

std::uint32_t HatBasis::elementDomains(std::uint64_t e, std::uint32_t* out) const {
  const FaceId f = faces_[e];
  for (int k = 0; k < 3; ++k) out[k] = cornerDomain_[3 * f + k];
  return 3;
}

void HatBasis::elementIntegrals(std::uint64_t e, ElementIntegrals& out) const {
  const FaceId f = faces_[e];
  const Triangle& t = mesh_.triangles[f];
  const Vec3d p0 = mesh_.position(t[0]), p1 = mesh_.position(t[1]), p2 = mesh_.position(t[2]);
  // Combed direction: rot^faceRotation[f](direction[f]), rot = n x (cut.h).
  const Vec3d n = faceNormal(mesh_, f);
  Vec3d u = field_.at(f);
  for (int k = 0; k < cut_.faceRotation[f] % 4; ++k) u = n.cross(u);
  double stiffness[9];
  std::complex<double> rhs[3];
  hatTriangleIntegrals(p0, p1, p2, u, edgeLength_, stiffness, rhs);
  out.count = 3;
  for (int a = 0; a < 3; ++a) {
    out.domain[a] = cornerDomain_[3 * f + a];
    out.rhs[a] = rhs[a];
    for (int b = 0; b < 3; ++b) out.stiffness[3 * a + b] = stiffness[3 * a + b];
  }
  out.area = faceArea(mesh_, f);
}

}  // namespace seamvox

namespace seamvox {

void HatBasis::evaluateCorners(const std::vector<std::complex<double>>& coefficients,
                               WedgeMap& cornerUV) const {
  checkCorners(cornerUV, cornerDomain_.size(), "hat basis evaluation");
  // Domains are the cut's wedges (restricted to the face subset): each wedge gets its domain's
  // coefficient, written once per corner of the subset.
  for (FaceId f : faces_) {
    for (int k = 0; k < 3; ++k) {
      const std::complex<double> q = coefficients[cornerDomain_[3 * f + k]];
      cornerUV.setWedgeValue(cornerUV.wedge(3 * f + k), Vec2d(q.real(), q.imag()));
    }
  }
}

}  // namespace seamvox
