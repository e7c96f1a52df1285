#include "core/solve/param_solver.h"

#include <cstdio>

#include "core/system/errors.h"
#include "core/basis/voxel_grid.h"

namespace seamvox {

const char* paramSolverName(ParamSolver solver) {
  switch (solver) {
    case ParamSolver::Hat: return "hat";
    case ParamSolver::Vox: return "vox";
    case ParamSolver::VoxLoc: return "voxloc";
  }
  return "?";
}

ParamSolver parseParamSolver(const std::string& name) {
  for (ParamSolver s : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
    if (name == paramSolverName(s)) return s;
  }
  throw InputError("unknown solver '" + name + "' (available: hat, vox, voxloc)");
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
  out.solver = solverOptions.solver;
  if (solverOptions.solver == ParamSolver::Hat) {
    out.param = parameterizeMesh(mesh, topology, field, cut, options);
    if (solverOptions.meter) solverOptions.meter->finish("solve");
    return out;
  }
  VoxelParamResult vox;
  try {
    if (solverOptions.beforeVoxelSolve) solverOptions.beforeVoxelSolve();
    vox = parameterizeMeshVoxel(mesh, topology, field, cut, options, solverOptions.gridResolution);
  } catch (const SolverError& e) {
    // The voxel system could not be factored: the hat solver gives the same kind of map, if it
    // fits in memory (on a massive mesh it would not, and swapping or being killed is worse
    // than an error).
    checkHatFallbackFits(mesh.numFaces(), availableMemoryBytes(), e.what());
    out.fallbackReason = e.what();
    out.solver = ParamSolver::Hat;
    out.param = parameterizeMesh(mesh, topology, field, cut, options);
    if (solverOptions.meter) solverOptions.meter->finish("solve");
    return out;
  }
  if (solverOptions.meter) solverOptions.meter->finish("solve");
  out.regularization = vox.regularization;
  out.failedAttempts = vox.failedAttempts;
  out.invisibleTranslations = vox.invisibleTranslations;
  out.param = std::move(vox.param);
  out.basisStats = vox.basisStats;
  out.determinedBasis = vox.determinedBasis;
  out.inconsistentBasis = vox.inconsistentBasis;
  out.markedFaces = vox.markedFaces.size();
  if (solverOptions.solver == ParamSolver::VoxLoc) {
    RefineOptions refineOptions = solverOptions.refine;
    refineOptions.edgeLength = options.edgeLength;
    refineOptions.markedFaces = std::move(vox.markedFaces);
    if (!refineOptions.progress) refineOptions.progress = options.progress;
    const RefineResult refinement = refineNearCones(mesh, topology, field, cut, out.param.cornerUV,
                                                    out.param.translations, refineOptions);
    applyRefinement(refinement, out.param.cornerUV, &out.param.translations);
    out.refined = true;
    out.refine = refinement.stats;
    if (solverOptions.meter) solverOptions.meter->finish("refine");
  }
  return out;
}

}  // namespace seamvox
