#pragma once
/// Bases for the seamless solve (DESIGN section 6): elements, element functions, integrals and
/// the seam adjacency between the domains of one basis function. The reduction, assembly, solve,
/// rounding and evaluation stages see a basis only through this interface.
#include <array>
#include <complex>
#include <cstdint>
#include <vector>

#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

namespace detail {
struct SubsetWedges;
}

/// Domain a crosses seam `seam` into domain b: the coefficients map as c_b = r_seam c_a + t_seam
/// (left to right as in cut.h). a and b are domains of the same basis function (a == b allowed:
/// a wedge touching both sides of a seam, e.g. at a seam tip).
struct DomainAdjacency {
  std::uint32_t left = 0;
  std::uint32_t right = 0;
  std::uint32_t seam = 0;
};

/// Largest number of element functions per element (8: the corners of a voxel).
constexpr std::uint32_t kMaxElementFunctions = 8;

/// Everything the assembly needs of one element. stiffness is row-major count x count:
/// L_ab = int <grad phi_a, grad phi_b>; rhs_a = int <grad phi_a, u_T> + i <grad phi_a, v_T>,
/// with w = u + i v scaled by 1/h (DESIGN section 6). domain[a] identifies the element function.
struct ElementIntegrals {
  std::uint32_t count = 0;
  std::array<std::uint32_t, kMaxElementFunctions> domain{};
  std::array<double, kMaxElementFunctions * kMaxElementFunctions> stiffness{};
  std::array<std::complex<double>, kMaxElementFunctions> rhs{};
  double area = 0.0;
};

/// A basis of continuous, partition-of-unity functions restricted to the cut surface.
/// Domains are numbered globally; each belongs to one basis function.
class Basis {
 public:
  virtual ~Basis() = default;
  virtual std::uint64_t numElements() const = 0;
  /// The domains of element e's functions (count entries written to out); cheap.
  virtual std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const = 0;
  /// Integrals of element e. Thread-safe.
  virtual void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const = 0;
  /// Writes q = u + i v once per wedge of cornerUV that the basis covers (wedges it does not
  /// cover are left unchanged) from the coefficient of every domain. cornerUV must hold the
  /// cut's wedges on 3 #F corners (buildCutWedges, evaluate.h); InputError otherwise.
  virtual void evaluateCorners(const std::vector<std::complex<double>>& domainCoefficients,
                               WedgeMap& cornerUV) const = 0;
  /// Element ranges the assembly takes as one task each: starts, then numElements() (e.g. the
  /// voxel basis' OpenVDB leaf blocks, whose elements are contiguous). Empty: fixed-size ranges.
  virtual std::vector<std::uint64_t> elementBlocks() const { return {}; }

  std::uint32_t numBasisFunctions() const { return numBasisFunctions_; }
  std::uint32_t numDomains() const { return static_cast<std::uint32_t>(domainBasis_.size()); }
  /// Basis function of each domain (#domains).
  const std::vector<std::uint32_t>& domainBasis() const { return domainBasis_; }
  const std::vector<DomainAdjacency>& adjacencies() const { return adjacencies_; }
  /// Rotation r of each seam (#seams), a unit of Z[i] stored as the power of i: r = i^rotation.
  const std::vector<std::uint8_t>& seamRotation() const { return seamRotation_; }
  std::uint32_t numSeams() const { return static_cast<std::uint32_t>(seamRotation_.size()); }

 protected:
  /// Stores the seam rotations r = i^(-matching) of the cut's seams and the adjacencies, sorted
  /// by (left, right, seam) without repeats (one convention for every basis).
  void setSeamAdjacencies(const std::vector<SeamCurve>& seams,
                          std::vector<DomainAdjacency> adjacencies);
  /// The adjacencies alone (the seams' rotations kept), sorted as setSeamAdjacencies does.
  void setDomainAdjacencies(std::vector<DomainAdjacency> adjacencies);

  std::uint32_t numBasisFunctions_ = 0;
  std::vector<std::uint32_t> domainBasis_;
  std::vector<DomainAdjacency> adjacencies_;
  std::vector<std::uint8_t> seamRotation_;
};

/// Bound on |cot| in the hat stiffness (near-degenerate scan triangles stay finite).
constexpr double kMaxCotangent = 1e4;

struct HatBasisOptions {
  double edgeLength = 1.0;  ///< h: one unit of (u, v) is h on the surface
  /// Optional subset of faces (local refinement); empty = all faces. Vertices not touched by the
  /// subset get no domain.
  std::vector<FaceId> faces;
  /// Optional per-face multiplier of the energy (stiffness and right-hand side), #F of the mesh
  /// or empty (all 1): stiffening re-solves weight faces that a solve flipped (core/refine/untangle).
  std::vector<double> faceWeight;
  /// Faces closer than this many h to a cone of the cut get their energy multiplied by
  /// sqrt(R / r), r the distance from the face's centroid to the cone (0: off). A cone's value is
  /// fixed by its seams' rotation (DESIGN section 7), but the Dirichlet energy barely feels a
  /// single vertex on a fine mesh: without the weight the map around a cone ignores where the
  /// rounding put it, and the cone's fan folds over (bench/RESULTS.md, flips near cones).
  double coneWeightRadius = 0.0;
};

/// Recommended HatBasisOptions::coneWeightRadius for the solves of a map (global and local).
constexpr double kConeWeightRadius = 4.0;

/// The per-face factors of HatBasisOptions::coneWeightRadius (radius in mesh units): 1 beyond
/// the radius. Cones hashed on a grid of the radius: linear in the faces.
std::vector<double> coneNeighbourhoodWeights(const TriangleMesh& mesh, const std::vector<VertexId>& cones,
                                             double radius);

/// Per-vertex hat functions; elements = triangles; domains = wedges (sectors of a vertex's
/// one-ring between cut edges). The target direction of face f is the combed field
/// rot^faceRotation[f](field.direction[f]) (cut.h). Holds references: inputs must outlive it.
class HatBasis final : public Basis {
 public:
  HatBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
           const CutResult& cut, const HatBasisOptions& options = {});
  std::uint64_t numElements() const override { return faces_.size(); }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override;
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override;
  void evaluateCorners(const std::vector<std::complex<double>>& domainCoefficients,
                       WedgeMap& cornerUV) const override;

  /// Wedge (domain) of each corner; kInvalidId for corners outside the face subset.
  const std::vector<std::uint32_t>& cornerDomain() const { return cornerDomain_; }
  /// Vertex of each basis function.
  const std::vector<VertexId>& basisVertex() const { return basisVertex_; }
  /// Face of element e.
  FaceId elementFace(std::uint64_t e) const { return faces_[e]; }

 private:
  const TriangleMesh& mesh_;
  const CrossField& field_;
  const CutResult& cut_;
  double edgeLength_;
  std::vector<double> faceWeight_;
  std::vector<FaceId> faces_;
  std::vector<std::uint32_t> cornerDomain_;
  std::vector<VertexId> basisVertex_;
};

/// Stiffness (3x3 row-major) and right-hand side of one triangle with combed direction u (unit,
/// tangent) for target w / h: the cotangent formulas with |cot| <= kMaxCotangent. Zero-area
/// triangles give zeros.
void hatTriangleIntegrals(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& u,
                          double edgeLength, double stiffness[9], std::complex<double> rhs[3]);

/// The hat basis' domains and seam adjacency on a face subset (detail::buildSubsetWedges, over
/// any corner table: in memory or out of core), without integrals or evaluation (they throw
/// InputError): what reduceBasis reads for the seam cycle constraints. Elements: the subset's
/// faces in increasing order.
class HatDomains final : public Basis {
 public:
  HatDomains(detail::SubsetWedges wedges, const std::vector<SeamCurve>& seams);
  std::uint64_t numElements() const override { return faceDomains_.size(); }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override;
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override;
  void evaluateCorners(const std::vector<std::complex<double>>& domainCoefficients, WedgeMap& cornerUV) const override;

 private:
  std::vector<std::array<std::uint32_t, 3>> faceDomains_;
};

}  // namespace seamvox
