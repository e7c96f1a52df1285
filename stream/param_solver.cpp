#include "stream/param_solver.h"

#include "core/errors.h"
#include "stream/voxel_grid.h"

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
    vox = parameterizeMeshVoxel(mesh, topology, field, cut, options, solverOptions.gridResolution);
  } catch (const SolverError& e) {
    // The voxel system could not be factored: the hat solver gives the same kind of map.
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
