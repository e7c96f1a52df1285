#include "stream/voxel_solve_stream.h"

#include "core/basis/detail_hat_wedges.h"
#include "core/basis/reduce.h"
#include "core/basis/voxel_grid.h"
#include "core/system/errors.h"
#include "stream/paged_corner_table.h"

namespace seamvox {

std::vector<GaussVector> scratchSeamCycleConstraints(const CleanScratch& scratch, const ScratchCut& cut,
                                                     const StreamPassOptions& pass) {
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedCutCorners corners(cut.corners, cacheBytes);
  const std::vector<FaceId> faces = detail::facesAroundSeams(table, cut.seams);
  if (faces.empty()) return {};
  const HatDomains domains(detail::buildSubsetWedges(table, corners, faces, cut.seams), cut.seams);
  return reduceBasis(domains).cycleConstraints;
}

ScratchVoxelSolution solveScratchVoxelMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchCut& cut,
                                          ScratchVoxelBasis& basis, const RoundOptions& options,
                                          const StreamPassOptions& pass) {
  ScratchVoxelSolution out;
  const std::vector<GaussVector> constraints = scratchSeamCycleConstraints(scratch, cut, pass);
  out.translationConstraints = static_cast<std::uint32_t>(constraints.size());
  ReduceOptions reduceOptions;
  reduceOptions.translationConstraints = &constraints;
  reduceOptions.progress = options.progress;
  const Reduction reduction = reduceBasis(*basis.basis, reduceOptions);
  out.determinedBasis = static_cast<std::uint32_t>(reduction.determinedBasis.size());
  out.inconsistentBasis = static_cast<std::uint32_t>(reduction.inconsistentBasis.size());
  out.markedBasis = markedBasisFunctions(reduction);
  out.inconsistentBasisFunctions = reduction.inconsistentBasis;
  SeamlessSolution solution = solveVoxelSeamless(*basis.basis, reduction, options, out.failedAttempts);
  out.regularization = basis.basis->regularization();
  out.stats = solution.stats;
  out.translations = std::move(solution.translations);
  out.coefficients = expandCoefficients(reduction, solution.unknowns);
  out.map = evaluateScratchVoxelMap(folder, scratch, cut, basis, out.coefficients, pass);
  return out;
}

std::vector<FaceId> scratchSupportFaces(ScratchFolder& folder, const ScratchVoxelBasis& basis,
                                        const std::vector<std::uint32_t>& basisFunctions) {
  const std::vector<std::uint8_t> elementMarked = basis.basis->elementsTouching(basisFunctions);
  std::vector<FaceId> faces;
  ScratchReader fragments(folder, basis.fragments, "support faces"), elements(folder, basis.fragmentElement, "support faces");
  VoxelFragment fragment;
  std::uint32_t element = 0;
  while (fragments.read(&fragment, sizeof(fragment))) {
    if (!elements.read(&element, sizeof(element))) throw IoError(basis.fragmentElement.path + ": scratch file ends early");
    if (elementMarked[element] && (faces.empty() || faces.back() != fragment.face)) faces.push_back(fragment.face);
  }
  return faces;
}

}  // namespace seamvox
