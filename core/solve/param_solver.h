#pragma once
/// Solver selection for the seamless parameterization (DESIGN sections 6-10): the hat solver
/// (core/solve/hat_solver.h), the Vox solver (voxel_grid.h) and Vox+HatLoc, the Vox map repaired near cones
/// by a local hat solve (core/refine/refine.h).
#include <cstdint>
#include <functional>
#include <string>

#include "core/solve/hat_solver.h"
#include "core/refine/refine.h"
#include "core/basis/smoothed_evaluation.h"
#include "core/basis/voxel_basis.h"
#include "core/system/memory.h"

namespace seamvox {

enum class ParamSolver {
  Hat,     ///< per-vertex hat basis, one global solve (exact reference)
  Vox,     ///< volumetric basis on a 2^D grid
  VoxLoc,  ///< Vox, then refineNearCones on its marked, collapsed and flipped faces
  Auto,    ///< Hat where its system is the cheaper one, VoxLoc above (chooseParamSolver; default)
};
/// "hat", "vox", "voxloc", "auto".
const char* paramSolverName(ParamSolver solver);
/// Parses a solver name; throws InputError listing the known names.
ParamSolver parseParamSolver(const std::string& name);

/// Largest mesh Auto solves with the hat basis at grid 128. The hat system has one unknown per
/// vertex, the voxel one about one per occupied grid corner (fixed by the grid); bench/RESULTS.md
/// (session 25) measured the two equal within 20% from 350K to 420K faces: hat faster on the
/// subdivided armadillo (346K) and a generated scan (399K), voxloc on the subdivided lilium (422K).
constexpr std::uint64_t kAutoHatMaxFacesGrid128 = 400000;
/// Hat solves a feature-aligned hat map costs (the first, then those that release the curves the
/// map collapsed; the field aligned too): 4-5 on the subdivided shared meshes, where voxloc was
/// already faster from 94K faces. Auto divides its hat limit by this when curves are to be aligned.
constexpr std::uint64_t kAutoFeatureSolves = 5;

struct SolverChoice {
  ParamSolver solver = ParamSolver::VoxLoc;  ///< never Auto
  std::string reason;                        ///< one sentence for reports
};
/// Resolves Auto by the face count against kAutoHatMaxFacesGrid128 scaled by (grid / 128)^2 (the
/// occupied corners of a surface grow as the square of the grid), divided by kAutoFeatureSolves
/// when feature curves are to be aligned (only the hat solver aligns them: the reason says so);
/// other solvers are kept, with "asked for" as the reason.
SolverChoice chooseParamSolver(ParamSolver requested, std::uint64_t numFaces,
                               std::int32_t gridResolution, bool alignsFeatures = false);

/// Memory the hat solve needs per face beyond the mesh, field and cut, rounded up from the scaling
/// study (bench/RESULTS.md: 0.99-1.15 KB per face of whole-process peak from 1.4M to 9.2M faces).
constexpr std::uint64_t kHatBytesPerFace = 1200;
/// The hat fallback is refused (SolverError naming both figures and `reason`) when it would need
/// more than availableBytes (kHatBytesPerFace per face); availableBytes 0 means unknown: allowed.
void checkHatFallbackFits(std::uint64_t faces, std::uint64_t availableBytes, const std::string& reason);

/// Whole-process peak of `seamvox param` in memory for a mesh of this many faces, rounded up
/// from bench/RESULTS.md: 48 MiB for the program, then with the hat solver (Auto up to
/// kAutoHatMaxFacesGrid128) 1400 bytes per face (measured 1.2-1.3 KB at 100K-300K faces), with
/// vox and voxloc the grid's system (520 MiB at grid 128, growing as the grid's square) and 78
/// bytes per face (measured: 1.58 GiB at 20.0M faces, 1.78 GiB at 22.1M with two cone passes,
/// 7.45 GiB at 100M, 74 bytes per face above the grid's system). fieldOnDisk: the field's
/// directions wait on disk while the map is built (PipelineOptions::directionStore), 70 bytes per
/// face (measured 16990 MiB at 250M faces, 69 bytes per face above the grid's system: the
/// estimate is 1.6% above it there).
std::uint64_t estimateParamPeakBytes(std::uint64_t faces, ParamSolver requested, std::int32_t gridResolution,
                                     bool fieldOnDisk = false);
/// The smallest budget of param's out-of-core path at a grid: the program and the grid-sized
/// system (as estimateParamPeakBytes counts them) and 64 MiB for the passes' sorts and caches.
std::uint64_t outOfCoreMinimumBytes(std::int32_t gridResolution);
/// Of estimateParamPeakBytes, the program's part and a margin of 64 MiB: what the out-of-core
/// passes before the grid-sized system may not use of the budget.
std::uint64_t outOfCoreProgramBytes();


/// Default voxels per axis of the voxel basis's grid (vox, voxloc).
constexpr std::int32_t kDefaultGridResolution = 128;

struct SolverOptions {
  ParamSolver solver = ParamSolver::Auto;
  std::int32_t gridResolution = kDefaultGridResolution;  ///< voxels per axis (vox, voxloc)
  /// Region and rings of the local refinement (voxloc); markedFaces and edgeLength are filled in.
  RefineOptions refine;
  /// When set, the solve closes its stages on it: for vox and voxloc "basis" (the voxel basis
  /// built), then "solve" (the hat or voxel solve, with the fallback if any) and, for voxloc,
  /// "refine".
  StageMeter* meter = nullptr;
  /// Test hook, run just before each voxel solve (the first, and the second with more B-splines
  /// joined): a SolverError it throws takes the path of a voxel system that cannot be factored.
  std::function<void()> beforeVoxelSolve;
  /// vox, voxloc: fieldIdle runs once the voxel basis is built, after which nothing reads the
  /// field's directions until fieldNeeded runs (before the refinement, or the hat fallback): a
  /// caller may keep them elsewhere meanwhile, while the map is built next to the basis.
  std::function<void()> fieldIdle, fieldNeeded;
  /// vox, voxloc: ParamOptions::smoothedEvaluation (out of core: StreamParamOptions's).
  bool smoothedEvaluation = true;
};

struct SolverResult {
  ParamResult param;  ///< the final map (refined for voxloc, and for vox where it was inconsistent)
  ParamSolver solver = ParamSolver::Hat;  ///< the solver that made the map (never Auto)
  std::string solverReason;              ///< why that one (chooseParamSolver, or the fallback)
  VoxelBasisStats basisStats;  ///< vox, voxloc
  std::uint32_t determinedBasis = 0, inconsistentBasis = 0;
  std::uint64_t markedFaces = 0;  ///< faces of marked voxel basis functions, and of the islands
  std::uint64_t islandFaces = 0;  ///< faces of the islands (islands.h), mapped by the local hat solve
  bool refined = false;  ///< the local refinement ran (voxloc; vox on inconsistent basis functions)
  RefineStats refine;
  /// voxloc (flipCandidatesKnown): the faces the refinement solved, increasing. Every other face
  /// keeps the voxel map's values, which the refinement's seeding measured at or above its collapse
  /// threshold (every face below it, flipped ones included, seeded the region): none is flipped,
  /// so a repair of this map may measure these faces only (UntangleOptions::candidateFaces).
  std::vector<FaceId> flipCandidates;
  bool flipCandidatesKnown = false;
  /// Once a step other than the solver moves the map's values, the candidates no longer hold.
  void forgetFlipCandidates() {
    std::vector<FaceId>().swap(flipCandidates);
    flipCandidatesKnown = false;
  }
  /// vox/voxloc: regularization the voxel solve succeeded with and failed factorizations before.
  double regularization = 0.0;
  std::uint32_t failedAttempts = 0;
  std::uint32_t invisibleTranslations = 0;  ///< Reduction::invisibleTranslations (vox, voxloc)
  SmoothedEvaluationStats smoothedEvaluation;  ///< vox, voxloc (SolverOptions::smoothedEvaluation)
  /// Set when the voxel system could not be factored and the hat solver ran instead (solver is
  /// then Hat): CHOLMOD's message. Reported, never silent.
  std::string fallbackReason;
  /// Set when the first voxel system could not be factored and the second, with the B-splines of
  /// weight below kRetryMinDomainWeight joined to a neighbour (the same basis), could: the first's
  /// message. Reported.
  std::string voxelRetryReason;
};

/// Runs the chosen solver (Auto resolved by chooseParamSolver) on a mesh cut to a disk per
/// component (cutToDisk). Throws like
/// parameterizeMesh and refineNearCones. vox and voxloc fall back to the hat solver when the
/// voxel system cannot be factored (see SolverResult::fallbackReason) and the hat solve fits in
/// memory (checkHatFallbackFits); otherwise they throw SolverError.
SolverResult parameterizeMeshWithSolver(const TriangleMesh& mesh, const Topology& topology,
                                        const CrossField& field, const CutResult& cut,
                                        const ParamOptions& options,
                                        const SolverOptions& solverOptions = {});

}  // namespace seamvox
