#pragma once
/// The Vox solve of the out-of-core param on the out-of-core voxel basis (voxel_stream): the seam
/// cycle constraints from the faces around the seams, paged in; the grid-sized reduction, solve and
/// rounding as in memory; the map evaluated into the scratch folder (evaluate_stream). Equal to
/// parameterizeMeshVoxel's map (before any local refinement) on readCleanScratch's mesh.
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/gaussian_int.h"
#include "core/solve/seamless_solve.h"
#include "stream/cut_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/voxel_stream.h"

namespace seamvox {

/// seamCycleConstraints out of core: the faces around the seams' vertices found by fan walks
/// through page caches, their hat wedges and seam adjacency (detail::buildSubsetWedges), reduced.
/// Memory: the seams' neighbourhood.
std::vector<GaussVector> scratchSeamCycleConstraints(const CleanScratch& scratch, const ScratchCut& cut,
                                                     const StreamPassOptions& pass);

struct ScratchVoxelSolution {
  ScratchMap map;
  std::vector<std::complex<double>> translations;  ///< t per seam (Gaussian integers)
  SeamlessStats stats;
  std::uint32_t translationConstraints = 0, determinedBasis = 0, inconsistentBasis = 0, failedAttempts = 0;
  double regularization = 0.0;  ///< the normal-derivative weight the solve succeeded with
  /// markedBasisFunctions of the reduction: whose support the local refinement re-solves.
  std::vector<std::uint32_t> markedBasis;
  std::vector<std::uint32_t> inconsistentBasisFunctions;
  std::vector<std::complex<double>> coefficients;  ///< per domain of the basis: what the map evaluates
};

/// VoxelBasis::supportFaces out of core: the faces holding a fragment of an element one of whose
/// functions is given, increasing (from the per-face fragment files, read once in order).
std::vector<FaceId> scratchSupportFaces(ScratchFolder& folder, const ScratchVoxelBasis& basis,
                                        const std::vector<std::uint32_t>& basisFunctions);

/// Constraints, reduction (no small-hole constraints), solveVoxelSeamless with options, and the
/// map evaluated out of core. SolverError as the in-memory Vox solver's.
ScratchVoxelSolution solveScratchVoxelMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchCut& cut,
                                          ScratchVoxelBasis& basis, const RoundOptions& options,
                                          const StreamPassOptions& pass);

}  // namespace seamvox
