// Solver selection (core/solve/param_solver): names, and the vox -> hat fallback when the voxel
// system cannot be factored: the hat map, seamless, with the reason reported; other errors are
// not swallowed.
#include <gtest/gtest.h>

#include <string>

#include "core/basis/islands.h"
#include "core/basis/voxel_grid.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/solve/param_solver.h"
#include "core/system/errors.h"
#include "tests/test_meshes.h"

namespace seamvox {
namespace {

struct FieldTorus : testing::CutSurface {
  FieldTorus() : CutSurface(testing::makeCutSurface(testing::torusMesh(30, 12))) {}
  ParamOptions options() const {
    ParamOptions o;
    o.edgeLength = 0.3;
    return o;
  }
};

TEST(ParamSolver, NamesRoundTrip) {
  for (ParamSolver s : {ParamSolver::Auto, ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
    EXPECT_EQ(parseParamSolver(paramSolverName(s)), s);
  }
  try {
    parseParamSolver("voxel");
    FAIL() << "an unknown solver name was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("available: auto, hat, vox, voxloc"), std::string::npos) << e.what();
  }
}

TEST(ParamSolver, AutoPicksHatUpToItsLimitAndCountsTheSolvesOfAFeatureAlignedMap) {
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, kAutoHatMaxFacesGrid128, 128).solver, ParamSolver::Hat);
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, kAutoHatMaxFacesGrid128 + 1, 128).solver, ParamSolver::VoxLoc);
  // The voxel system grows as the grid's square.
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, 4 * kAutoHatMaxFacesGrid128, 256).solver, ParamSolver::Hat);
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, kAutoHatMaxFacesGrid128 / 4 + 1, 64).solver, ParamSolver::VoxLoc);
  // Feature curves to align: the hat limit divided by the solves an aligned map takes.
  const std::uint64_t featureLimit = kAutoHatMaxFacesGrid128 / kAutoFeatureSolves;
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, featureLimit, 128, true).solver, ParamSolver::Hat);
  const SolverChoice above = chooseParamSolver(ParamSolver::Auto, featureLimit + 1, 128, true);
  EXPECT_EQ(above.solver, ParamSolver::VoxLoc);
  EXPECT_NE(above.reason.find("feature curves"), std::string::npos) << above.reason;
  EXPECT_NE(above.reason.find("only --solver hat aligns the curves"), std::string::npos) << above.reason;
  EXPECT_EQ(chooseParamSolver(ParamSolver::Auto, featureLimit + 1, 128, false).solver, ParamSolver::Hat);
  // An asked-for solver is kept whatever the size.
  const SolverChoice asked = chooseParamSolver(ParamSolver::Hat, 100 * kAutoHatMaxFacesGrid128, 128, true);
  EXPECT_EQ(asked.solver, ParamSolver::Hat);
  EXPECT_EQ(asked.reason, "asked for");
}

TEST(ParamSolver, AutoSeesTheFeatureCurvesOfTheSolve) {
  // 2880 faces at grid 16: below the hat limit (400K / 64), above it with curves to align (/ 5).
  const testing::CutSurface t = testing::makeCutSurface(testing::torusMesh(60, 24));
  const std::uint64_t limit = kAutoHatMaxFacesGrid128 / 64;
  ASSERT_GT(t.s.mesh.numFaces(), limit / kAutoFeatureSolves);
  ASSERT_LE(t.s.mesh.numFaces(), limit);
  ParamOptions options;
  options.edgeLength = 0.3;
  SolverOptions solverOptions;
  solverOptions.gridResolution = 16;
  EXPECT_EQ(parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, options, solverOptions).solver,
            ParamSolver::Hat);
  const std::vector<CornerId> featureCorners{0, 1};
  options.featureCorners = &featureCorners;
  const SolverResult aligned = parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, options, solverOptions);
  EXPECT_EQ(aligned.solver, ParamSolver::VoxLoc) << aligned.solverReason;
  EXPECT_NE(aligned.solverReason.find("feature curves"), std::string::npos) << aligned.solverReason;
}

TEST(ParamSolver, UnfactorableVoxelSystemFallsBackToTheHatSolver) {
  const FieldTorus t;
  const ParamResult hat = parameterizeMesh(t.s.mesh, t.s.topology, t.field, t.cut, t.options());
  for (ParamSolver chosen : {ParamSolver::Vox, ParamSolver::VoxLoc}) {
    SCOPED_TRACE(paramSolverName(chosen));
    SolverOptions solverOptions;
    solverOptions.solver = chosen;
    solverOptions.gridResolution = 16;
    StageMeter meter;
    solverOptions.meter = &meter;
    int attempts = 0;
    solverOptions.beforeVoxelSolve = [&] {
      throw SolverError("CHOLMOD: not positive definite at column " + std::to_string(7 + attempts++) + " (injected)");
    };
    const SolverResult result =
        parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions);
    EXPECT_EQ(attempts, 2) << "the first solve and the one with more B-splines joined";
    EXPECT_EQ(result.solver, ParamSolver::Hat);
    EXPECT_NE(result.fallbackReason.find("not positive definite at column 8 (injected)"), std::string::npos)
        << result.fallbackReason;
    EXPECT_FALSE(result.refined) << "the hat map is not refined";
    // The voxel basis was built once, then the hat solve ran.
    ASSERT_EQ(meter.stages().size(), 2u);
    EXPECT_EQ(meter.stages()[0].name, "basis");
    EXPECT_EQ(meter.stages()[1].name, "solve");
    // The map is the hat solver's, corner for corner, and seamless.
    ASSERT_EQ(result.param.cornerUV.size(), hat.cornerUV.size());
    for (CornerId c = 0; c < hat.cornerUV.size(); ++c) {
      ASSERT_EQ(result.param.cornerUV[c], hat.cornerUV[c]) << "corner " << c;
    }
    EXPECT_TRUE(measureSeams(t.s.mesh, t.s.topology, t.cut, result.param.cornerUV).isSeamless(1e-8));
  }
}

TEST(ParamSolver, AVoxelSystemThatFailsOnceIsSolvedAgainWithMoreSplinesJoined) {
  // The first voxel solve fails (injected); the second, with the negligible B-splines joined up to
  // kRetryMinDomainWeight, factors. The basis is built once (its faces are not clipped again,
  // the field is not read again), and the map is the one a basis built with that weight gives,
  // seamless, with the first failure reported.
  const FieldTorus t;
  ParamOptions joinedOptions = t.options();
  joinedOptions.smoothedEvaluation = SolverOptions{}.smoothedEvaluation;
  const VoxelParamResult joined =
      parameterizeMeshVoxel(t.s.mesh, t.s.topology, t.field, t.cut, joinedOptions, 16, kRetryMinDomainWeight);
  ASSERT_TRUE(joined.retryReason.empty());
  for (ParamSolver chosen : {ParamSolver::Vox, ParamSolver::VoxLoc}) {
    SCOPED_TRACE(paramSolverName(chosen));
    SolverOptions solverOptions;
    solverOptions.solver = chosen;
    solverOptions.gridResolution = 16;
    int attempts = 0, idle = 0, needed = 0;
    solverOptions.beforeVoxelSolve = [&] {
      if (attempts++ == 0) throw SolverError("CHOLMOD: not positive definite at column 7 (injected)");
    };
    solverOptions.fieldIdle = [&] { ++idle; };
    solverOptions.fieldNeeded = [&] { ++needed; };
    const SolverResult result =
        parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions);
    EXPECT_EQ(attempts, 2);
    EXPECT_EQ(idle, 1) << "one basis built";
    EXPECT_EQ(needed, 1);
    EXPECT_EQ(result.solver, chosen);
    EXPECT_TRUE(result.fallbackReason.empty()) << result.fallbackReason;
    EXPECT_NE(result.voxelRetryReason.find("(injected)"), std::string::npos) << result.voxelRetryReason;
    EXPECT_TRUE(measureSeams(t.s.mesh, t.s.topology, t.cut, result.param.cornerUV).isSeamless(1e-6));
    if (chosen == ParamSolver::Vox) {
      ASSERT_EQ(result.param.cornerUV.size(), joined.param.cornerUV.size());
      for (CornerId c = 0; c < joined.param.cornerUV.size(); ++c) {
        ASSERT_EQ(result.param.cornerUV[c], joined.param.cornerUV[c]) << "corner " << c;
      }
      EXPECT_EQ(result.param.translations, joined.param.translations);
    }
  }
}

TEST(ParamSolver, OtherErrorsOfTheVoxelSolveAreNotSwallowed) {
  const FieldTorus t;
  SolverOptions solverOptions;
  solverOptions.solver = ParamSolver::Vox;
  solverOptions.beforeVoxelSolve = [] { throw InputError("bad input (injected)"); };
  EXPECT_THROW(parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions),
               InputError);
}

TEST(ParamSolver, VoxelSolveRunsWhenItCanBeFactored) {
  const FieldTorus t;
  SolverOptions solverOptions;
  solverOptions.solver = ParamSolver::Vox;
  solverOptions.gridResolution = 16;
  bool called = false;
  solverOptions.beforeVoxelSolve = [&called] { called = true; };
  const SolverResult result =
      parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions);
  EXPECT_TRUE(called);
  EXPECT_EQ(result.solver, ParamSolver::Vox) << result.fallbackReason;
  EXPECT_TRUE(result.fallbackReason.empty());
  EXPECT_TRUE(measureSeams(t.s.mesh, t.s.topology, t.cut, result.param.cornerUV).isSeamless(1e-6));
}

TEST(ParamSolver, VoxelSolversCloseABasisStageBeforeTheSolve) {
  const FieldTorus t;
  for (ParamSolver chosen : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
    SolverOptions solverOptions;
    solverOptions.solver = chosen;
    solverOptions.gridResolution = 16;
    StageMeter meter;
    solverOptions.meter = &meter;
    const SolverResult result =
        parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions);
    std::vector<std::string> names;
    for (const StageFigures& stage : meter.stages()) names.push_back(stage.name);
    std::vector<std::string> expected{"solve"};
    if (chosen != ParamSolver::Hat) expected.insert(expected.begin(), "basis");
    if (result.refined) expected.push_back("refine");
    EXPECT_EQ(names, expected) << paramSolverName(chosen);
    EXPECT_EQ(result.refined, chosen == ParamSolver::VoxLoc) << paramSolverName(chosen);
  }
}

TEST(ParamSolver, IslandsAreLeftOutOfTheVoxelBasisAndMappedByTheLocalHatSolve) {
  const testing::CutSurface t = testing::makeCutSurface(testing::torusWithIslands(30, 12, 6, 0.08, 2, 0.3f, 7));
  const std::uint32_t torusFaces = 2 * 30 * 12;
  const std::vector<FaceId> islands = islandFaces(t.s.topology);
  ASSERT_EQ(islands.size(), t.s.mesh.numFaces() - torusFaces);  // all but the largest component
  EXPECT_EQ(islands.front(), torusFaces);
  EXPECT_TRUE(islandFaces(t.s.topology, 3).empty());  // no component that small
  ParamOptions options;
  options.edgeLength = 0.1;
  const ParamResult hat = parameterizeMesh(t.s.mesh, t.s.topology, t.field, t.cut, options);
  for (ParamSolver chosen : {ParamSolver::Vox, ParamSolver::VoxLoc}) {
    SCOPED_TRACE(paramSolverName(chosen));
    SolverOptions solverOptions;
    solverOptions.solver = chosen;
    solverOptions.gridResolution = 16;
    const SolverResult result =
        parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, options, solverOptions);
    EXPECT_EQ(result.solver, chosen);
    EXPECT_EQ(result.islandFaces, islands.size());
    EXPECT_TRUE(result.refined);
    EXPECT_GE(result.markedFaces, islands.size());
    // The refinement counts the islands' vertices apart: all of them, and all of them free.
    std::vector<VertexId> islandVertices;
    for (FaceId f : islands) islandVertices.insert(islandVertices.end(), t.s.mesh.triangles[f].begin(), t.s.mesh.triangles[f].end());
    std::sort(islandVertices.begin(), islandVertices.end());
    islandVertices.erase(std::unique(islandVertices.begin(), islandVertices.end()), islandVertices.end());
    EXPECT_EQ(result.refine.islandVertices, islandVertices.size());
    EXPECT_GE(result.refine.freeVertices, islandVertices.size());
    EXPECT_NEAR(result.refine.refinedFractionOffIslands,
                double(result.refine.freeVertices - islandVertices.size()) / t.s.mesh.numVertices(), 1e-12);
    const WedgeMap& uv = result.param.cornerUV;
    EXPECT_TRUE(measureSeams(t.s.mesh, t.s.topology, t.cut, uv).isSeamless(1e-8));
    // The islands are mapped whole by the local hat solve: none of their triangles collapsed or
    // flipped, and the specks (no cones: one linear solve) have the hat solver's triangles up to
    // a shift. The ball's cones and translations are placed by the local solve's own rounding.
    const FaceId ballFaces = 320, specks = t.s.mesh.numFaces() - ballFaces;
    double largest = 0.0;
    std::size_t bad = 0;
    for (FaceId f : islands) {
      bad += parameterAreaRatio(t.s.mesh, uv, f, options.edgeLength) < 0.1;
      for (int k = 1; k < 3 && f < specks; ++k) {
        const Vec2d got = uv[3 * f + k] - uv[3 * f], want = hat.cornerUV[3 * f + k] - hat.cornerUV[3 * f];
        largest = std::max(largest, (got - want).norm());
      }
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_LT(largest, 1e-9);
  }
}

// A local solve that cannot be factored keeps the voxel map there: kept when the map is still
// seamless (voxloc here: its voxel map is), else the hat solver maps the mesh (vox: the
// refinement re-solves only where the voxel map is not seamless).
TEST(ParamSolver, ALocalSolveThatCannotBeFactoredFallsBackToTheHatSolver) {
  const FieldTorus t;
  const ParamResult hat = parameterizeMesh(t.s.mesh, t.s.topology, t.field, t.cut, t.options());
  std::size_t fellBack = 0, kept = 0;
  for (ParamSolver chosen : {ParamSolver::Vox, ParamSolver::VoxLoc}) {
    for (std::int32_t grid : {8, 16}) {
      SCOPED_TRACE(std::string(paramSolverName(chosen)) + " grid " + std::to_string(grid));
      SolverOptions solverOptions;
      solverOptions.solver = chosen;
      solverOptions.gridResolution = grid;
      solverOptions.refine.groupFails = [](FaceId) { return true; };
      const SolverResult result =
          parameterizeMeshWithSolver(t.s.mesh, t.s.topology, t.field, t.cut, t.options(), solverOptions);
      EXPECT_TRUE(measureSeams(t.s.mesh, t.s.topology, t.cut, result.param.cornerUV).isSeamless(1e-6));
      if (result.solver == ParamSolver::Hat) {
        ++fellBack;
        EXPECT_NE(result.fallbackReason.find("local refinement"), std::string::npos) << result.fallbackReason;
        EXPECT_NE(result.fallbackReason.find("test hook"), std::string::npos) << result.fallbackReason;
        EXPECT_FALSE(result.refined);
        std::size_t different = 0;
        for (CornerId c = 0; c < hat.cornerUV.size(); ++c) different += result.param.cornerUV[c] != hat.cornerUV[c];
        EXPECT_EQ(different, 0u);
      } else {
        ++kept;
        EXPECT_EQ(result.solver, chosen);
        EXPECT_TRUE(result.fallbackReason.empty());
      }
      if (result.refined) EXPECT_GT(result.refine.failedSolves, 0u);
    }
  }
  EXPECT_GT(fellBack, 0u);
  EXPECT_GT(kept, 0u);
}

}  // namespace
}  // namespace seamvox
