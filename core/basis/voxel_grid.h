#pragma once
/// The sparse voxel grid of the volumetric basis (DESIGN sections 6 and 12): an OpenVDB tree
/// mapping each voxel the surface touches to a dense voxel id, which indexes the flat element
/// records of VoxelBasis (elements are ordered by voxel id). buildVoxelBasis streams the
/// triangles through it in parallel chunks. OpenVDB's headers stay in voxel_grid.cpp.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/solve/hat_solver.h"
#include "core/basis/smoothed_evaluation.h"
#include "core/basis/voxel_basis.h"

namespace seamvox {

/// Sparse map voxel coordinate -> dense id (0, 1, ... in order of insertion). Move-only.
class VoxelGrid {
 public:
  VoxelGrid();
  ~VoxelGrid();
  VoxelGrid(VoxelGrid&&) noexcept;
  VoxelGrid& operator=(VoxelGrid&&) noexcept;
  VoxelGrid(const VoxelGrid&) = delete;
  VoxelGrid& operator=(const VoxelGrid&) = delete;

  /// Id of the voxel, adding it when new. Not thread-safe.
  std::uint32_t insert(const VoxelCoord& voxel);
  /// Id of the voxel, or kInvalidId when the surface does not touch it. Thread-safe.
  std::uint32_t find(const VoxelCoord& voxel) const;
  std::uint32_t size() const { return static_cast<std::uint32_t>(coords_.size()); }
  /// Coordinate of every id.
  const std::vector<VoxelCoord>& coords() const { return coords_; }
  std::vector<VoxelCoord> releaseCoords() { return std::move(coords_); }
  /// Bytes held by the OpenVDB tree.
  std::uint64_t treeBytes() const;
  /// Renumbers the ids in the order of the tree's leaf nodes (blocks of 8^3 voxels), so every
  /// block's voxels get consecutive ids; returns old id -> new id. blockStarts() then lists where
  /// each block begins (and the end).
  std::vector<std::uint32_t> orderByBlocks();
  const std::vector<std::uint32_t>& blockStarts() const { return blockStarts_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<VoxelCoord> coords_;
  std::vector<std::uint32_t> blockStarts_;
};

struct VoxelBuildResult {
  std::unique_ptr<VoxelBasis> basis;
  VoxelGrid grid;  ///< voxel -> voxel id; basis->voxelElementStart() gives its elements
  double secondsClip = 0.0, secondsBasis = 0.0;
};

/// Clips every triangle against the voxels of a 2^D grid over the mesh's padded bounding box
/// (parallel chunks of options.chunkFaces triangles; a serial in-order stage registers their
/// fragments in the OpenVDB grid) and builds the voxel basis: elements, integrals, domains and
/// seam adjacency. Memory: about 12 bytes per fragment while building, then per element a
/// 456-byte record; the basis keeps 4 bytes per face and per fragment for evaluation.
VoxelBuildResult buildVoxelBasis(const TriangleMesh& mesh, const Topology& topology,
                                 const CrossField& field, const CutResult& cut,
                                 const VoxelBasisOptions& options = {});

/// The Vox solver: voxel basis, reduced with the hat basis' translation constraints (DESIGN
/// section 7), assembled, solved, rounded and evaluated at every corner. markedFaces receives
/// the triangles of determined and inconsistent basis functions (input of the local refinement).
struct VoxelParamResult {
  ParamResult param;
  std::vector<FaceId> markedFaces;
  /// The triangles of inconsistent basis functions alone: where the voxel map is not seamless.
  std::vector<FaceId> inconsistentFaces;
  /// Faces of the islands (islands.h), left out of the basis; in both lists above.
  std::uint64_t islandFaces = 0;
  std::vector<FaceId> islands;  ///< those faces (increasing): marked, and counted apart by the refinement
  VoxelBasisStats basisStats;
  double voxelSize = 0.0;  ///< edge of a voxel in mesh units
  std::uint32_t determinedBasis = 0, inconsistentBasis = 0;
  /// Normal-derivative regularization the solve succeeded with (VoxelBasisOptions), and how many
  /// factorizations failed before (nearly dependent B-splines on coarse or thin regions).
  double regularization = 0.0;
  std::uint32_t failedAttempts = 0;
  std::uint32_t invisibleTranslations = 0;  ///< Reduction::invisibleTranslations
  SmoothedEvaluationStats smoothedEvaluation;  ///< ParamOptions::smoothedEvaluation
  /// Why the first system could not be factored, when its negligible B-splines were joined
  /// (kRetryMinDomainWeight) and solved again; empty otherwise.
  std::string retryReason;
};
/// Strongest normal-derivative regularization the Vox solver retries with.
constexpr double kMaxVoxelRegularization = 1e-3;

/// solveSeamless, the basis' normal-derivative regularization raised (x100 from at least 1e-7, up
/// to kMaxVoxelRegularization) while the factorization fails; failedAttempts counts the failures.
SeamlessSolution solveVoxelSeamless(VoxelBasis& basis, const Reduction& reduction, const RoundOptions& options,
                                    std::uint32_t& failedAttempts);
/// The Vox solver. When CHOLMOD finds the system indefinite, it re-assembles and refactors with a
/// 100x stronger regularization (up to kMaxVoxelRegularization; the basis is built once) before
/// giving up with the last SolverError. Then, once, with the B-splines of weight below
/// kRetryMinDomainWeight joined to a neighbour (VoxelBasis::joinDomains; not when minDomainWeight
/// is that already). minDomainWeight: VoxelBasisOptions's (< 0: its default).
/// The union of two increasing face lists.
std::vector<FaceId> withFaces(const std::vector<FaceId>& faces, const std::vector<FaceId>& more);

VoxelParamResult parameterizeMeshVoxel(const TriangleMesh& mesh, const Topology& topology,
                                       const CrossField& field, const CutResult& cut,
                                       const ParamOptions& options,
                                       std::int32_t gridResolution = 128, double minDomainWeight = -1.0);

}  // namespace seamvox
