#include "core/basis/basis.h"

#include "core/basis/detail_hat_wedges.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "core/system/errors.h"
#include "core/system/parallel.h"

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

/// Cones up to which coneNeighbourhoodWeights tests each one instead of looking up cells.
constexpr std::size_t kDirectCones = 32;

std::vector<double> coneNeighbourhoodWeights(const TriangleMesh& mesh, const std::vector<VertexId>& cones,
                                             double radius) {
  std::vector<double> weight(mesh.numFaces(), 1.0);
  if (cones.empty() || !(radius > 0.0) || !std::isfinite(radius)) return weight;
  using Cell = std::array<std::int64_t, 3>;
  auto cellOf = [&](const Vec3d& x) {
    return Cell{static_cast<std::int64_t>(std::floor(x.x() / radius)),
                static_cast<std::int64_t>(std::floor(x.y() / radius)),
                static_cast<std::int64_t>(std::floor(x.z() / radius))};
  };
  // Few cones (a local solve's region has a handful): each is tested, cheaper than 27 cell
  // lookups; either way every cone within the radius is seen, so the weights are the same.
  const bool direct = cones.size() <= kDirectCones;
  std::vector<Vec3d> points;
  std::map<Cell, std::vector<Vec3d>> buckets;
  for (VertexId v : cones) {
    if (direct) {
      points.push_back(mesh.position(v));
    } else {
      buckets[cellOf(mesh.position(v))].push_back(mesh.position(v));
    }
  }
  // The squared distance from c to its nearest cone, at most radius^2.
  const auto nearestSquared = [&](const Vec3d& c) {
    double nearest = radius * radius;
    if (direct) {
      for (const Vec3d& p : points) nearest = std::min(nearest, (p - c).squaredNorm());
      return nearest;
    }
    const Cell cell = cellOf(c);
    for (int d = 0; d < 27; ++d) {
      const auto it = buckets.find({cell[0] + d % 3 - 1, cell[1] + d / 3 % 3 - 1, cell[2] + d / 9 - 1});
      if (it == buckets.end()) continue;
      for (const Vec3d& p : it->second) nearest = std::min(nearest, (p - c).squaredNorm());
    }
    return nearest;
  };
  parallelFor(mesh.numFaces(), 1u << 14, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const double nearest = nearestSquared((mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0);
      // sqrt(R / r) = (R^2 / r^2)^(1/4); capped where a centroid nearly meets its cone.
      // No cone within the radius: 1 (what the power gives there, without computing it).
      if (nearest < radius * radius) {
        weight[f] = std::pow(radius * radius / std::max(nearest, 1e-12 * radius * radius), 0.25);
      }
    }
  });
  return weight;
}

void Basis::setSeamAdjacencies(const std::vector<SeamCurve>& seams,
                               std::vector<DomainAdjacency> adjacencies) {
  seamRotation_.resize(seams.size());
  for (std::size_t s = 0; s < seams.size(); ++s) {
    seamRotation_[s] = static_cast<std::uint8_t>((4 - seams[s].matching % 4) % 4);  // r = i^(-k)
  }
  setDomainAdjacencies(std::move(adjacencies));
}

void Basis::setDomainAdjacencies(std::vector<DomainAdjacency> adjacencies) {
  auto key = [](const DomainAdjacency& a) { return std::make_tuple(a.left, a.right, a.seam); };
  std::sort(adjacencies.begin(), adjacencies.end(),
            [&](const auto& a, const auto& b) { return key(a) < key(b); });
  adjacencies.erase(std::unique(adjacencies.begin(), adjacencies.end(),
                                [&](const auto& a, const auto& b) { return key(a) == key(b); }),
                    adjacencies.end());
  adjacencies_ = std::move(adjacencies);
}

namespace {

// Faces of the basis (the subset, or all nf) and a per-face flag "in the subset"; InputError on
// a subset face out of range.
std::vector<std::uint8_t> selectFaces(std::uint32_t nf, const std::vector<FaceId>& subset,
                                      std::vector<FaceId>& faces) {
  std::vector<std::uint8_t> inSubset(nf, subset.empty() ? 1 : 0);
  if (subset.empty()) {
    faces.resize(nf);
    for (FaceId f = 0; f < nf; ++f) faces[f] = f;
  } else {
    faces = subset;
    for (FaceId f : faces) {
      if (f >= nf) throw InputError("hat basis: face " + std::to_string(f) + " out of range");
      inSubset[f] = 1;
    }
  }
  return inSubset;
}

// With a face subset only its vertices can get a wedge: those, in increasing order (as the
// whole-mesh walk would visit them), so a small subset does not walk every fan of a large mesh.
std::vector<VertexId> verticesOfFaces(const Topology& topology, const std::vector<FaceId>& faces) {
  std::vector<VertexId> vertices;
  vertices.reserve(3 * faces.size());
  for (FaceId f : faces) {
    for (VertexId v : topology.triangles()[f]) vertices.push_back(v);
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  return vertices;
}

// The wedges (domains) of the hat functions: per corner its domain, per domain its function,
// per function its vertex.
struct Wedges {
  std::vector<std::uint32_t> cornerDomain;
  std::vector<std::uint32_t> domainBasis;
  std::vector<VertexId> basisVertex;
};

Wedges buildWedges(const Topology& topology, const CutResult& cut,
                   const std::vector<std::uint8_t>& inSubset, bool wholeMesh,
                   const std::vector<VertexId>& subsetVertices) {
  Wedges out;
  out.cornerDomain.assign(3u * topology.numFaces(), kInvalidId);
  const std::size_t numWalked = wholeMesh ? topology.numVertices() : subsetVertices.size();
  std::vector<CornerId> fan;
  for (std::size_t i = 0; i < numWalked; ++i) {
    const VertexId v = wholeMesh ? static_cast<VertexId>(i) : subsetVertices[i];
    fan.clear();
    topology.forEachCornerAround(v, [&](CornerId c) { fan.push_back(c); });
    if (fan.empty()) continue;
    detail::addFanWedges(
        topology, cut.corners, [&](FaceId f) { return inSubset[f] != 0; }, v, fan, out.domainBasis, out.basisVertex,
        [&](CornerId c, std::uint32_t d) { out.cornerDomain[c] = d; });
  }
  return out;
}


}  // namespace

HatBasis::HatBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                   const CutResult& cut, const HatBasisOptions& options)
    : mesh_(mesh), field_(field), cut_(cut), edgeLength_(options.edgeLength), faceWeight_(options.faceWeight) {
  const std::uint32_t nf = topology.numFaces();
  if (!(edgeLength_ > 0.0) || !std::isfinite(edgeLength_)) {
    throw InputError("hat basis: edge length must be positive and finite");
  }
  if (!faceWeight_.empty() && faceWeight_.size() != nf) {
    throw InputError("hat basis: " + std::to_string(faceWeight_.size()) + " face weights for " +
                     std::to_string(nf) + " faces");
  }
  if (options.coneWeightRadius > 0.0 && !cut.cones.empty()) {
    const std::vector<double> near =
        coneNeighbourhoodWeights(mesh, cut.cones, options.coneWeightRadius * edgeLength_);
    if (faceWeight_.empty()) {
      faceWeight_ = near;
    } else {
      for (FaceId f = 0; f < nf; ++f) faceWeight_[f] *= near[f];
    }
  }
  if (field.direction.size() != nf || cut.corners.size() != 3u * nf || cut.faceRotation.size() != nf) {
    throw InputError("hat basis: field or cut sizes do not match the mesh (" +
                     std::to_string(nf) + " faces)");
  }
  const std::vector<std::uint8_t> inSubset = selectFaces(nf, options.faces, faces_);
  const bool wholeMesh = options.faces.empty();
  Wedges wedges = buildWedges(topology, cut, inSubset, wholeMesh,
                              wholeMesh ? std::vector<VertexId>{} : verticesOfFaces(topology, faces_));
  cornerDomain_ = std::move(wedges.cornerDomain);
  domainBasis_ = std::move(wedges.domainBasis);
  basisVertex_ = std::move(wedges.basisVertex);
  numBasisFunctions_ = static_cast<std::uint32_t>(basisVertex_.size());
  setSeamAdjacencies(cut.seams, detail::collectSeamAdjacencies(
                                    cut.seams, [&](CornerId c) { return topology.opposite(c); },
                                    [&](FaceId f) { return inSubset[f] != 0; },
                                    [&](CornerId c) { return cornerDomain_[c]; }));
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
  if (!faceWeight_.empty()) {
    for (double& s : stiffness) s *= faceWeight_[f];
    for (auto& r : rhs) r *= faceWeight_[f];
  }
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

HatDomains::HatDomains(detail::SubsetWedges wedges, const std::vector<SeamCurve>& seams)
    : faceDomains_(std::move(wedges.faceDomains)) {
  domainBasis_ = std::move(wedges.domainBasis);
  numBasisFunctions_ = static_cast<std::uint32_t>(wedges.basisVertex.size());
  setSeamAdjacencies(seams, std::move(wedges.adjacencies));
}

std::uint32_t HatDomains::elementDomains(std::uint64_t e, std::uint32_t* out) const {
  std::copy_n(faceDomains_[e].begin(), 3, out);
  return 3;
}

void HatDomains::elementIntegrals(std::uint64_t, ElementIntegrals&) const {
  throw InputError("hat domains: no integrals (the basis is built for its seam cycles only)");
}

void HatDomains::evaluateCorners(const std::vector<std::complex<double>>&, WedgeMap&) const {
  throw InputError("hat domains: no evaluation (the basis is built for its seam cycles only)");
}

}  // namespace seamvox
