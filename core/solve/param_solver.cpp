#include "core/solve/param_solver.h"

#include "core/quality/metrics.h"

#include <cstdio>
#include <string>

#include "core/system/errors.h"
#include "core/basis/voxel_grid.h"

namespace seamvox {

const char* paramSolverName(ParamSolver solver) {
  switch (solver) {
    case ParamSolver::Hat: return "hat";
    case ParamSolver::Vox: return "vox";
    case ParamSolver::VoxLoc: return "voxloc";
    case ParamSolver::Auto: return "auto";
  }
  return "?";
}

ParamSolver parseParamSolver(const std::string& name) {
  for (ParamSolver s : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc, ParamSolver::Auto}) {
    if (name == paramSolverName(s)) return s;
  }
  throw InputError("unknown solver '" + name + "' (available: auto, hat, vox, voxloc)");
}

SolverChoice chooseParamSolver(ParamSolver requested, std::uint64_t numFaces,
                               std::int32_t gridResolution, bool alignsFeatures) {
  if (requested != ParamSolver::Auto) return {requested, "asked for"};
  const double scale = double(gridResolution) / 128.0;
  const double solves = alignsFeatures ? double(kAutoFeatureSolves) : 1.0;
  const auto limit = static_cast<std::uint64_t>(double(kAutoHatMaxFacesGrid128) * scale * scale / solves);
  const bool hat = numFaces <= limit;
  const std::string grid = "grid " + std::to_string(gridResolution);
  std::string reason = std::to_string(numFaces) + " faces" + (alignsFeatures ? " with feature curves" : "") +
                       (hat ? ", at most " : ", more than ") + std::to_string(limit) + ": the ";
  if (alignsFeatures) {
    reason += hat ? "feature-aligned hat map (about " + std::to_string(kAutoFeatureSolves) +
                        " hat solves) is cheaper than the voxel one (" + grid + ")"
                  : "voxel (" + grid + ") map is cheaper than a feature-aligned hat map (about " +
                        std::to_string(kAutoFeatureSolves) + " hat solves); only --solver hat aligns the curves";
  } else {
    reason += hat ? "hat (one unknown per vertex) system is smaller than the voxel one (" + grid + ")"
                  : "voxel (" + grid + ") system is smaller than the hat one (one unknown per vertex)";
  }
  return {hat ? ParamSolver::Hat : ParamSolver::VoxLoc, reason};
}

namespace {
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20;
constexpr std::uint64_t kOutOfCorePassBytes = std::uint64_t(64) << 20;  ///< the least the passes get
}

std::uint64_t estimateParamPeakBytes(std::uint64_t faces, ParamSolver requested, std::int32_t gridResolution,
                                     bool fieldOnDisk) {
  constexpr std::uint64_t kMiB = std::uint64_t(1) << 20;
  const std::uint64_t program = kProgramBytes;
  if (chooseParamSolver(requested, faces, gridResolution).solver == ParamSolver::Hat) return program + 1400 * faces;
  const double scale = double(gridResolution) / kDefaultGridResolution;
  return program + static_cast<std::uint64_t>(520.0 * kMiB * scale * scale) + (fieldOnDisk ? 70 : 78) * faces;
}

std::uint64_t outOfCoreProgramBytes() { return kProgramBytes + kOutOfCorePassBytes; }

std::uint64_t outOfCoreMinimumBytes(std::int32_t gridResolution) {
  return estimateParamPeakBytes(0, ParamSolver::VoxLoc, gridResolution) + kOutOfCorePassBytes;
}

void checkHatFallbackFits(std::uint64_t faces, std::uint64_t availableBytes, const std::string& reason) {
  const std::uint64_t needed = faces * kHatBytesPerFace;
  if (availableBytes == 0 || needed <= availableBytes) return;
  char figures[160];
  std::snprintf(figures, sizeof figures, "about %.1f GB for %llu faces, %.1f GB available",
                needed / 1e9, static_cast<unsigned long long>(faces), availableBytes / 1e9);
  throw SolverError("the voxel system could not be factored (" + reason +
                    ") and the hat solver it falls back to would need " + figures +
                    "; try another --grid (e.g. 256) or more memory");
}

SolverResult parameterizeMeshWithSolver(const TriangleMesh& mesh, const Topology& topology,
                                        const CrossField& field, const CutResult& cut,
                                        const ParamOptions& options,
                                        const SolverOptions& solverOptions) {
  SolverResult out;
  const SolverChoice choice =
      chooseParamSolver(solverOptions.solver, mesh.numFaces(), solverOptions.gridResolution,
                        options.featureCorners && !options.featureCorners->empty());
  out.solver = choice.solver;
  out.solverReason = choice.reason;
  if (choice.solver == ParamSolver::Hat) {
    out.param = parameterizeMesh(mesh, topology, field, cut, options);
    if (solverOptions.meter) solverOptions.meter->finish("solve");
    return out;
  }
  VoxelParamResult vox;
  try {
    ParamOptions voxOptions = options;
    voxOptions.smoothedEvaluation = solverOptions.smoothedEvaluation;
    voxOptions.basisBuilt = [&] {
      if (options.basisBuilt) options.basisBuilt();
      if (solverOptions.meter) solverOptions.meter->finish("basis");
      if (solverOptions.fieldIdle) solverOptions.fieldIdle();
    };
    if (solverOptions.beforeVoxelSolve) voxOptions.beforeVoxelSolve = solverOptions.beforeVoxelSolve;
    vox = parameterizeMeshVoxel(mesh, topology, field, cut, voxOptions, solverOptions.gridResolution);
    out.voxelRetryReason = vox.retryReason;
    if (solverOptions.fieldNeeded) solverOptions.fieldNeeded();
  } catch (const SolverError& e) {
    if (solverOptions.fieldNeeded) solverOptions.fieldNeeded();
    // The voxel system could not be factored: the hat solver gives the same kind of map, if it
    // fits in memory (on a massive mesh it would not, and swapping or being killed is worse
    // than an error).
    checkHatFallbackFits(mesh.numFaces(), availableMemoryBytes(), e.what());
    out.fallbackReason = e.what();
    out.solver = ParamSolver::Hat;
    out.solverReason = "the voxel system could not be factored";
    out.param = parameterizeMesh(mesh, topology, field, cut, options);
    if (solverOptions.meter) solverOptions.meter->finish("solve");
    return out;
  }
  if (solverOptions.meter) solverOptions.meter->finish("solve");
  out.regularization = vox.regularization;
  out.failedAttempts = vox.failedAttempts;
  out.invisibleTranslations = vox.invisibleTranslations;
  out.smoothedEvaluation = vox.smoothedEvaluation;
  out.param = std::move(vox.param);
  out.basisStats = vox.basisStats;
  out.determinedBasis = vox.determinedBasis;
  out.inconsistentBasis = vox.inconsistentBasis;
  out.markedFaces = vox.markedFaces.size();
  out.islandFaces = vox.islandFaces;
  // voxloc refines near cones and wherever the map collapses or flips; vox only where its
  // reduction left basis functions inconsistent, the one place the voxel map is not seamless.
  const bool voxLoc = choice.solver == ParamSolver::VoxLoc;
  if (voxLoc || !vox.inconsistentFaces.empty()) {
    RefineOptions refineOptions = solverOptions.refine;
    refineOptions.edgeLength = options.edgeLength;
    refineOptions.markedFaces = std::move(voxLoc ? vox.markedFaces : vox.inconsistentFaces);
    refineOptions.islandFaces = std::move(vox.islands);
    refineOptions.seedFromMap = voxLoc;
    if (!voxLoc) refineOptions.maxRounds = 1;
    if (voxLoc && refineOptions.splineCells > 0) refineOptions.splineSpacing = vox.voxelSize / refineOptions.splineCells;
    if (!refineOptions.progress) refineOptions.progress = options.progress;
    // Seeded from the whole map: the faces solved are the only ones that may be flipped after.
    const bool listCandidates = !refineOptions.regionOnly && regionHoldsEveryFlip(refineOptions);
    refineOptions.listRegionFaces = listCandidates;
    // The solved corners go into the map a batch at a time (at most 96 MB of them held).
    RefineResult refinement = refineNearConesInPlace(mesh, topology, field, cut, out.param.cornerUV,
                                                           out.param.translations, refineOptions);
    out.refined = true;
    out.refine = refinement.stats;
    out.flipCandidates = std::move(refinement.regionFaces);
    out.flipCandidatesKnown = listCandidates;
    if (solverOptions.meter) solverOptions.meter->finish("refine");
    // A local solve that could not be factored left its components as the voxel map made them
    // (not seamless where functions were inconsistent there): when the map is then not seamless,
    // the hat solver maps the whole mesh instead if it fits in memory; else the map stays, its
    // verdict measured and reported.
    const std::uint64_t available = availableMemoryBytes();
    if (out.refine.failedSolves > 0 && !measureSeams(mesh, topology, cut, out.param.cornerUV).isSeamless() &&
        (available == 0 || mesh.numFaces() * kHatBytesPerFace <= available)) {
      out.fallbackReason = "local refinement: " + out.refine.failedSolveReason;
      out.solver = ParamSolver::Hat;
      out.solverReason = "a local solve of the voxel map's refinement could not be factored";
      out.refined = false;
      out.forgetFlipCandidates();
      out.param = parameterizeMesh(mesh, topology, field, cut, options);
      if (solverOptions.meter) solverOptions.meter->finish("solve");
    }
  }
  return out;
}

}  // namespace seamvox
