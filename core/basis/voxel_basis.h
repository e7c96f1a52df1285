#pragma once
/// The volumetric basis (DESIGN section 6): trilinear B-splines of the corners of a 2^D grid,
/// restricted to the cut surface. Elements are the connected pieces of "cut surface inside one
/// voxel"; the domains of a corner's B-spline are the connected pieces of its support (the 8
/// voxels around it) on the cut surface; seam adjacency joins the domains on either side of a
/// seam inside the support. core/basis/voxel_grid.h builds it (buildVoxelBasis) from a triangle
/// stream through the sparse OpenVDB grid; this class holds only flat per-element arrays.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/basis.h"
#include "core/system/progress.h"
#include "core/basis/reduce.h"
#include "core/basis/voxel_clip.h"

namespace seamvox {

namespace detail {
struct VoxelBasisParts;
}

/// VoxelBasisOptions::minDomainWeight of the voxel solver's second attempt, when the first could
/// not factor its system even at kMaxVoxelRegularization: on a noisy 50M-face scan B-splines that
/// barely touch the surface (diagonal entries down to 1e-17 against a median 0.17) were nearly
/// dependent, which a stronger normal regularization does not change.
constexpr double kRetryMinDomainWeight = 1e-6;

struct VoxelBasisOptions {
  std::int32_t gridResolution = 128;  ///< voxels per axis: 64, 128, 256 or 512 (any 2^D, 4..1024)
  double edgeLength = 1.0;            ///< h: one unit of (u, v) is h on the surface
  std::uint32_t chunkFaces = 1u << 14;  ///< triangles per parallel clipping task
  /// Weight of the normal-derivative term int (n . grad phi_a)(n . grad phi_b) added to each
  /// element's stiffness. Restricted B-splines are linearly dependent on planes (and nearly so on
  /// flat regions, e.g. big triangles that fill a scan's holes); this term makes the system
  /// definite. It vanishes on maps whose gradient is tangent (linear maps on planes, maps along a
  /// cylinder's axis stay exact). 0 = off (pure surface integrals). Rows still sum to zero.
  double regularization = 1e-5;
  /// A domain whose B-spline has less energy int |grad phi|^2 (3D gradient, grid units: about
  /// the area in squared voxels it covers with a unit gradient) joins the heaviest domain of its
  /// heaviest element. B-splines that barely touch the surface (a sliver where a vertex lies a
  /// hair across a grid plane) would make the system singular to working precision; joined, they
  /// lose their own coefficient only where they are almost zero. 0 = off.
  double minDomainWeight = 1e-9;
  /// Faces given no fragments (increasing): the islands (islands.h), mapped by the local hat
  /// solve instead; the basis, its system and the voxel map leave them out (their corners 0).
  std::vector<FaceId> leftOut;
  ProgressFn progress;
};

/// One positive-area piece of face `face` in voxel `voxel` (a dense voxel id); edgeMask bit j:
/// the edge of corner 3 face + j has a piece of positive length in the closed voxel. 8 bytes:
/// there are about 1.2 fragments per face while the basis is built.
struct VoxelFragment {
  static constexpr std::uint32_t kMaxVoxels = std::uint32_t(1) << 29;
  FaceId face = 0;
  std::uint32_t voxel : 29;  ///< below kMaxVoxels
  std::uint32_t edgeMask : 3;
};

/// The basis functions whose support the local refinement re-solves: the determined ones (their
/// supports overlap cones) and the inconsistent ones (DESIGN sections 7 and 10).
std::vector<std::uint32_t> markedBasisFunctions(const Reduction& reduction);

/// Sizes of a built voxel basis (for reports and benchmarks).
struct VoxelBasisStats {
  std::uint64_t voxels = 0, fragments = 0, elements = 0;
  std::uint64_t joinedDomains = 0;  ///< negligible domains joined to a neighbour (minDomainWeight)
  std::uint64_t bytes = 0;  ///< memory held by the basis
};

/// Per face, the range of its fragments in an array ordered by face, in about 1.25 bytes per face
/// instead of 4: a count per face (kLarge: listed apart) and the first fragment of every 16th face.
class FragmentRanges {
 public:
  FragmentRanges() = default;
  /// From #F + 1 increasing offsets (empty: no faces).
  explicit FragmentRanges(const std::vector<std::uint32_t>& start);
  std::uint32_t numFaces() const { return static_cast<std::uint32_t>(count_.size()); }
  std::uint32_t begin(FaceId f) const {
    std::uint32_t first = blockStart_[f >> kBlockBits];
    for (FaceId g = f & ~kBlockMask; g < f; ++g) first += count(g);
    return first;
  }
  std::uint32_t count(FaceId f) const { return count_[f] == kLarge ? largeCount(f) : count_[f]; }
  std::size_t bytes() const;

 private:
  static constexpr std::uint32_t kBlockBits = 4, kBlockMask = (1u << kBlockBits) - 1;
  static constexpr std::uint8_t kLarge = 255;
  std::uint32_t largeCount(FaceId f) const;
  std::vector<std::uint8_t> count_;                       // #F
  std::vector<std::uint32_t> blockStart_;                 // #F / 16, rounded up
  std::vector<std::pair<FaceId, std::uint32_t>> large_;  // faces of kLarge or more fragments, by face
};

/// Restricted trilinear B-splines on the cut surface. Element functions of element e are its
/// voxel's 8 corners, numbered k = kx + 2 ky + 4 kz (voxel_clip.h). Holds a reference to the
/// mesh (evaluation): it must outlive the basis.
class VoxelBasis final : public Basis {
 public:
  /// Builds elements, integrals, domains and seam adjacency from the fragments of every face
  /// (ordered by face; every face with positive area has at least one) over the given voxels.
  /// Linear in the fragments; parallel over voxels. Throws InputError on mismatched sizes.
  VoxelBasis(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
             const CutResult& cut, const VoxelGridGeometry& grid,
             std::vector<VoxelCoord> voxelCoords, std::vector<VoxelFragment> fragments,
             const VoxelBasisOptions& options = {});

  /// From parts built elsewhere (detail/voxel_elements.h; the out-of-core build): mesh null when
  /// the faces are not in memory (then evaluation, faceElements, cornerElement and the support
  /// faces throw InputError: the caller evaluates from its own per-face files).
  VoxelBasis(const TriangleMesh* mesh, detail::VoxelBasisParts parts, const std::vector<SeamCurve>& seams,
             const VoxelBasisOptions& options);

  std::uint64_t numElements() const override { return elementVoxel_.size(); }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override;
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override;
  void evaluateCorners(const std::vector<std::complex<double>>& domainCoefficients,
                       WedgeMap& cornerUV) const override;

  const VoxelGridGeometry& grid() const { return grid_; }
  /// Voxel of element e (grid coordinates of its lowest corner).
  const VoxelCoord& elementVoxel(std::uint64_t e) const { return voxelCoords_[elementVoxel_[e]]; }
  /// Dense id of every active voxel's coordinate (elements are ordered by voxel id).
  const std::vector<VoxelCoord>& voxelCoords() const { return voxelCoords_; }
  /// Elements of voxel id v: [voxelElementStart[v], voxelElementStart[v + 1]).
  const std::vector<std::uint32_t>& voxelElementStart() const { return voxelElementStart_; }
  /// Groups voxels into assembly blocks: voxel ids [voxelBlockStart[b], voxelBlockStart[b + 1])
  /// form block b (ids 0 .. #voxels, increasing). elementBlocks() then lists their elements.
  void setVoxelBlocks(const std::vector<std::uint32_t>& voxelBlockStart);
  std::vector<std::uint64_t> elementBlocks() const override { return elementBlockStart_; }
  /// Integrals of element e in compact form (upper triangle of the stiffness), without the
  /// normal-derivative term.
  const VoxelIntegrals& elementRecord(std::uint64_t e) const { return records_[e]; }
  /// The unweighted normal-derivative stiffness of element e (packed as VoxelIntegrals::stiffness).
  const std::array<double, 36>& elementNormalStiffness(std::uint64_t e) const { return normalStiffness_[e]; }
  /// Weight of the normal-derivative term in elementIntegrals (VoxelBasisOptions::regularization).
  /// Its integrals are kept per element, so changing the weight costs no re-clipping.
  double regularization() const { return regularization_; }
  void setRegularization(double weight);
  /// Elements holding a piece of face f (the face's fragments), and the element that holds the
  /// corner c (used for evaluation: the fragment of c's face whose voxel contains c's vertex).
  std::vector<std::uint32_t> faceElements(FaceId f) const;
  std::uint32_t cornerElement(CornerId c) const;
  /// Of the elements of a face's fragments (count of them, element(i)), the one that holds grid
  /// point x (a corner of the face): in x's own voxel, else the nearest voxel (a vertex on a grid
  /// plane whose triangle lies on the lower side); ties go to the first. kInvalidId when none.
  template <class Element>
  std::uint32_t nearestElement(const Vec3d& x, std::uint32_t count, Element&& element) const {
    const VoxelCoord home = grid_.voxelOf(x);
    std::uint32_t best = kInvalidId;
    double bestDistance = 1e300;
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint32_t e = element(i);
      const VoxelCoord& v = voxelCoords_[elementVoxel_[e]];
      if (v == home) return e;
      double distance = 0.0;
      for (int a = 0; a < 3; ++a) {
        distance += std::pow(std::max({0.0, v[a] - x[a], x[a] - (v[a] + 1)}), 2);
      }
      if (distance < bestDistance) bestDistance = distance, best = e;
    }
    return best;
  }
  /// The map at grid point x in element e from the domains' coefficients.
  std::complex<double> evaluateAt(std::uint32_t e, const Vec3d& x, const std::vector<std::complex<double>>& coefficients) const;
  /// Grid corner of each basis function (of its larger part when negligible domains joined it).
  const std::vector<VoxelCoord>& basisCorner() const { return basisCorner_; }

  /// Faces in the support of the basis functions the reduction marked for local refinement
  /// (determined, i.e. cone-overlapping, and inconsistent ones; DESIGN sections 7 and 10).
  /// Sorted, unique.
  std::vector<FaceId> markedFaces(const Reduction& reduction) const;
  /// Faces in the support of the given basis functions. Sorted, unique.
  std::vector<FaceId> supportFaces(const std::vector<std::uint32_t>& basisFunctions) const;
  /// Per element: 1 when one of its functions is one of the given basis functions.
  std::vector<std::uint8_t> elementsTouching(const std::vector<std::uint32_t>& basisFunctions) const;

  VoxelBasisStats stats() const;

  /// Joins the domains again as a basis built with this VoxelBasisOptions::minDomainWeight (and
  /// its regularization) would: the same functions, adjacencies and integrals, without clipping
  /// the faces again. For a second attempt when the first system could not be factored.
  void joinDomains(double minDomainWeight);

 private:
  const TriangleMesh& mesh() const;
  const TriangleMesh* mesh_ = nullptr;
  VoxelGridGeometry grid_;
  std::vector<VoxelCoord> voxelCoords_;           // per voxel id
  std::vector<std::uint32_t> voxelElementStart_;  // #voxels + 1
  std::vector<std::uint32_t> elementVoxel_;       // #elements
  std::vector<std::uint64_t> elementBlockStart_;  // #blocks + 1, or empty
  std::vector<VoxelIntegrals> records_;           // #elements, tangential stiffness
  std::vector<std::array<double, 36>> normalStiffness_;  // #elements, unweighted
  double regularization_ = 0.0;
  double builtRegularization_ = 0.0;                  // VoxelBasisOptions::regularization
  std::uint32_t joinedDomains_ = 0;
  std::vector<std::uint32_t> functionLinks_;      // 8 #elements: the nodes' union-find before joining
  std::vector<DomainAdjacency> nodeSeamLinks_;    // seam links between nodes (8 e + k), not domains
  std::vector<std::uint32_t> elementDomain_;      // 8 #elements
  FragmentRanges faceFragments_;                  // #F (empty out of core)
  std::vector<std::uint32_t> fragmentElement_;    // #fragments, ordered by face
  std::vector<VoxelCoord> basisCorner_;           // #basis functions
};

}  // namespace seamvox
