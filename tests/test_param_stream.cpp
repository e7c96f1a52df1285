// param out of core (stream/param_stream, `param --out-of-core` or above the budget): the file it
// writes is the one the in-memory pipeline writes with the same stages (proxy field, voxloc, its
// cone passes, foldover repair) on the mesh as the out-of-core path cleans it; `seamvox check` agrees with its
// verdict; the report says which path ran; what the path lacks and budgets below the grid-sized
// system are refused by name; a full scratch disk is an error that leaves nothing behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "core/system/errors.h"
#include "core/basis/gaussian_int.h"
#include "core/pipeline/parameterize.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "stream/mesh_stream.h"
#include "stream/param_stream.h"
#include "stream_testing.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string run(const std::string& arguments, int code) {
  std::string output;
  EXPECT_EQ(testing::runSeamvox(arguments, &output), code) << "seamvox " << arguments << "\n" << output;
  return output;
}

// The written maps: byte for byte, or (tolerance > 0) the same mesh and wedges with values within
// the tolerance (the repair near coincident cones, in a window out of core, differs in rounding).
void expectSameMap(const std::string& outOfCore, const std::string& inMemory, double tolerance) {
  if (tolerance == 0.0) {
    EXPECT_TRUE(testing::readFile(outOfCore) == testing::readFile(inMemory)) << outOfCore << " differs";
    return;
  }
  const TriangleMesh a = readMesh(outOfCore), b = readMesh(inMemory);
  ASSERT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.positions, b.positions);
  ASSERT_EQ(a.cornerUV.size(), b.cornerUV.size());
  double largest = 0.0;
  for (CornerId c = 0; c < a.cornerUV.size(); ++c) {
    ASSERT_EQ(a.cornerUV.wedge(c), b.cornerUV.wedge(c)) << "corner " << c;
    largest = std::max(largest, (a.cornerUV[c] - b.cornerUV[c]).norm());
  }
  EXPECT_EQ(a.cornerUV.numWedges(), b.cornerUV.numWedges());
  EXPECT_LE(largest, tolerance);
}

struct PathRun {
  double conePasses = 0.0, conePassKept = 0.0;
  std::vector<double> conePassFlips;  ///< flips left by each pass's repair
  double flipped = 0.0;               ///< left by the repair in the written map
  bool repaired = false;              ///< the repair had flips to repair
  double smoothedVertices = 0.0;      ///< the voxel map re-evaluated at the smoothed surface there
  double wound = 0.0;                 ///< wound vertices in the written map
};

// param on `mesh` out of core and in memory (on the mesh as the out-of-core path cleans it, in its
// order), with each of the settings: the same map (byte for byte; within 1e-9 where the repair
// near coincident cones may run, merging and repair on), the same figures and cone passes, and
// the same verdict from param and from check on the written file.
std::vector<PathRun> expectPathsAgree(const TriangleMesh& mesh, const std::vector<std::string>& settingsList,
                                      const std::string& budget = "150M") {
  std::vector<PathRun> runs;
  testing::TempDir dir;
  EXPECT_TRUE(std::filesystem::create_directory(dir.path("scratch")));
  writeMesh(dir.path("in.ply"), mesh);
  {
    ScratchFolder folder(dir.dir());
    const CleanScratch scratch = testing::cleanIntoScratch(folder, mesh, std::uint64_t(1) << 20);
    writeMesh(dir.path("clean.ply"), readCleanScratch(folder, scratch).mesh);
  }
  for (const std::string& settings : settingsList) {
    SCOPED_TRACE(settings);
    const bool repair = !contains(settings, "--no-untangle");
    const bool laterPasses = repair && !contains(settings, "--merge-cones 0");
    const std::string inMemory = run("param " + dir.path("clean.ply") + " -o " + dir.path("mem.ply") +
                                         " --solver voxloc --field proxy" + settings + " --report " + dir.path("m.json"),
                                     0);
    const std::string outOfCore =
        run("param " + dir.path("in.ply") + " -o " + dir.path("ooc.ply") + " --out-of-core --memory-budget " + budget +
                settings + " --scratch " + dir.path("scratch") + " --report " + dir.path("r.json"),
            0);
    expectSameMap(dir.path("ooc.ply"), dir.path("mem.ply"), laterPasses ? 1e-9 : 0.0);
    EXPECT_TRUE(contains(outOfCore, "path out of core")) << outOfCore;
    EXPECT_TRUE(contains(inMemory, "path in memory")) << inMemory;
    EXPECT_EQ(contains(outOfCore, "foldover repair: flipped"), repair) << outOfCore;
    const bool seamless = contains(outOfCore, ": seamless");
    EXPECT_TRUE(seamless || contains(outOfCore, "NOT seamless")) << outOfCore;
    const std::string checked = run("check " + dir.path("ooc.ply"), seamless ? 0 : 1);
    EXPECT_EQ(contains(checked, "NOT seamless"), !seamless) << checked;
    const JsonValue report = parseJson(testing::readFile(dir.path("r.json")));
    EXPECT_EQ(report["path"].text, "out-of-core");
    EXPECT_GT(report.numberAt("scratch.peakBytes"), 0.0);
    for (const char* pass : {"passSeconds.weld: read", "passSeconds.clean: faces", "passSeconds.field: sweeps"}) {
      EXPECT_GE(report.numberAt(pass), 0.0) << pass;
    }
    // The map's figures as measured in memory (the sums in another order: the error to rounding).
    const JsonValue memoryReport = parseJson(testing::readFile(dir.path("m.json")));
    for (const char* count : {"quality.flipped", "quality.collapsed", "quality.flippedFolded", "quality.stretched", "quality.wound",
                              "conePasses", "conePassKept", "cones", "conesCancelled", "conesMerged", "seams",
                              "voxel.smoothedEvaluation.foldedBefore", "voxel.smoothedEvaluation.vertices"}) {
      EXPECT_EQ(report.numberAt(count), memoryReport.numberAt(count)) << count;
    }
    EXPECT_NEAR(report.numberAt("quality.relativeGradientError"), memoryReport.numberAt("quality.relativeGradientError"),
                (laterPasses ? 1e-9 : 1e-12) * memoryReport.numberAt("quality.relativeGradientError"));
    // The repair's steps' seconds are parts of its seconds, on both paths.
    for (const JsonValue* x : {&report, &memoryReport}) {
      if (!repair) continue;
      double steps = 0.0;
      for (const char* step : {"rounds", "cones", "relocation", "joint", "leftover"}) {
        const double seconds = x->numberAt(std::string("untangle.stepSeconds.") + step);
        EXPECT_GE(seconds, 0.0) << step;
        steps += seconds;
      }
      EXPECT_LE(steps, x->numberAt("untangle.seconds") + 1e-9);
      if (x->numberAt("untangle.flippedBefore") > 0.0) EXPECT_GT(steps, 0.0);
    }
    PathRun r{memoryReport.numberAt("conePasses"), memoryReport.numberAt("conePassKept"), {},
              report.numberAt("untangle.flippedAfter"), report.numberAt("untangle.flippedBefore") > 0.0,
              report.numberAt("voxel.smoothedEvaluation.vertices"), report.numberAt("quality.wound")};
    const JsonValue& flips = report["conePassFlips"];
    const JsonValue& memoryFlips = memoryReport["conePassFlips"];
    EXPECT_EQ(flips.items.size(), memoryFlips.items.size());
    for (std::size_t k = 0; k < std::min(flips.items.size(), memoryFlips.items.size()); ++k) {
      EXPECT_EQ(flips.items[k].number, memoryFlips.items[k].number) << "pass " << k + 1;
      r.conePassFlips.push_back(flips.items[k].number);
    }
    runs.push_back(r);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path("scratch"))) << "scratch left behind";
  return runs;
}

// A closed noisy scan with holes, the damaged mesh (non-manifold edges and vertices, duplicate
// and flipped faces) and a torus with islands (a sphere and a Moebius strip): without and with
// the foldover repair (out of core: in a window around the flips, its border pinned), and the
// repair without later cone passes (no merging).
TEST(ParamStream, EqualsTheInMemoryPipelineAndCheckAgrees) {
  std::size_t repairs = 0;
  double smoothed = 0.0, wound = 0.0;
  for (const auto& [name, mesh] : testing::stageTestMeshes(43)) {
    SCOPED_TRACE(name);
    for (const PathRun& r : expectPathsAgree(mesh, {" --grid 32 --cells 20 --quiet --no-untangle",
                                                    " --grid 32 --cells 20 --quiet",
                                                    " --grid 32 --cells 20 --quiet --merge-cones 0"})) {
      repairs += r.repaired;
      smoothed += r.smoothedVertices;
      wound += r.wound;
    }
  }
  EXPECT_GT(wound, 0.0);  // some map wound, counted alike on both paths
  EXPECT_GT(repairs, 0u);  // some map had flips to repair
  EXPECT_GT(smoothed, 0.0);  // and some voxel map folds that the smoothed surface re-evaluated
}

// --field-smoothing reaches the out-of-core field: with the field's surface smoothed by 1 and by 8
// steps, the same map and figures on both paths; and out of core the steps change the map (each
// written file differs from the default's), the report saying which.
TEST(ParamStream, FieldSmoothingStepsAsInMemory) {
  const TriangleMesh scan = testing::stageTestMeshes(43).at(0).second;
  for (const char* steps : {"1", "8"}) {
    expectPathsAgree(scan, {std::string(" --grid 32 --cells 20 --quiet --no-untangle --field-smoothing ") + steps});
  }
  testing::TempDir dir;
  writeMesh(dir.path("in.ply"), scan);
  std::vector<std::string> maps;
  for (const char* steps : {"3", "1", "8"}) {
    run("param " + dir.path("in.ply") + " -o " + dir.path("o.ply") + " --out-of-core --memory-budget 150M --scratch " +
            dir.dir() + " --grid 32 --cells 20 --quiet --no-untangle --field-smoothing " + steps + " --report " +
            dir.path("r.json"),
        0);
    EXPECT_EQ(parseJson(testing::readFile(dir.path("r.json"))).numberAt("fieldSmoothing"), std::stod(steps));
    maps.push_back(testing::readFile(dir.path("o.ply")));
  }
  EXPECT_NE(maps[1], maps[0]) << "1 step gives the default's map";
  EXPECT_NE(maps[2], maps[0]) << "8 steps give the default's map";
}

// A real scan whose solve puts two close cones on one point: the second cone pass merges them,
// out of core as in memory (at two spacings where it happens); and a noisy scan at the
// default grid, with the repair and the checks after it (the retry of a pass whose repair leaves
// flips at close cones: test_cli, in memory, where a small scan needs it).
TEST(ParamStream, LaterConePassesAsInMemory) {
  const std::string scan = testing::sharedMesh("cheburashka.off");
  if (scan.empty()) GTEST_SKIP() << testing::missingSharedMessage("cheburashka.off");
  {
    testing::TempDir dir;
    std::string out;
    ASSERT_EQ(testing::runSeamvox("subdivide " + scan + " --levels 2 --noise 0.25 -o " + dir.path("noisy.ply") +
                                      " --quiet", &out), 0) << out;
    const PathRun r = expectPathsAgree(readMesh(dir.path("noisy.ply")), {" --quiet"}, "700M").at(0);
    EXPECT_TRUE(r.repaired);
    EXPECT_GT(r.smoothedVertices, 0.0);
    ASSERT_FALSE(r.conePassFlips.empty());
    EXPECT_EQ(r.flipped, *std::min_element(r.conePassFlips.begin(), r.conePassFlips.end()));
  }
  for (const char* cells : {"40", "60"}) {
    EXPECT_GE(expectPathsAgree(readMesh(scan), {std::string(" --grid 32 --cells ") + cells + " --quiet"}).at(0).conePasses,
              2.0);
  }
}

// The flips a repair leaves are re-solved in the hat basis within a radius of them, then repaired
// again: with a repair that moves nothing (no patch rounds, relocation or joint patches) on the
// voxel map, what the re-solve fixes is all that changes. Fewer flips than without it, seamless,
// the figures reported; out of core the same counts and map figures as in memory.
TEST(ParamStream, FlipsTheRepairLeavesAreResolvedInTheHatBasisAsInMemory) {
  const auto mesh = std::make_shared<const TriangleMesh>(testing::generatedMesh(MeshKind::Scan, 30000));
  UntangleOptions still;
  still.maxRounds = 0;
  still.relocationPasses = 0;
  still.jointRings = 0;
  still.coneRepairRadius = 0.0;
  testing::TempDir dir;
  TriangleMesh cleaned;
  {
    ScratchFolder folder(dir.dir());
    cleaned = readCleanScratch(folder, testing::cleanIntoScratch(folder, *mesh, std::uint64_t(1) << 20)).mesh;
  }
  const auto inMemory = [&](double radius) {
    PipelineOptions options;
    options.field.method = FieldMethod::Proxy;
    options.solver.solver = ParamSolver::Vox;
    options.solver.gridResolution = 32;
    options.spacing.cells = 30;
    options.mergeCones = 0.0;
    options.untangleOptions = still;
    options.untangleOptions.leftoverRadius = radius;
    return parameterize(TriangleMesh(cleaned), options);
  };
  const PipelineResult off = inMemory(0.0);
  ASSERT_GT(off.untangle.flippedAfter, 0u) << "the test needs a map with flips left";
  EXPECT_EQ(off.untangle.flippedAfter, off.untangle.flippedBefore);  // the repair moved nothing
  EXPECT_EQ(off.untangle.leftoverFlips, 0u);
  const PipelineResult on = inMemory(1.0);
  EXPECT_TRUE(on.isSeamless());
  EXPECT_EQ(on.untangle.flippedBefore, off.untangle.flippedBefore);
  EXPECT_EQ(on.untangle.leftoverFlips, off.untangle.flippedAfter);
  EXPECT_GE(on.untangle.leftoverRegionFaces, on.untangle.leftoverFlips);
  EXPECT_GT(on.untangle.leftoverFreeVertices, 0u);
  EXPECT_EQ(on.untangle.flippedAfter, on.untangle.leftoverAfterResolve);  // the second repair moved nothing
  EXPECT_EQ(on.mapQuality.flipped, on.untangle.flippedAfter);
  EXPECT_LT(on.mapQuality.flipped, off.mapQuality.flipped);
  for (const auto& t : on.solved.param.translations) EXPECT_LT(gaussianIntegerDistance(t), 1e-9);

  StreamParamOptions options;
  options.memoryBytes = std::uint64_t(8) << 20;
  options.gridResolution = 32;
  options.spacing.cells = 30;
  options.voxLoc = false;
  options.mergeCones = 0.0;
  options.untangleOptions = still;
  options.writeMap = [](const CleanScratch&, const ScratchMap&) {};
  ScratchFolder folder(dir.dir());
  const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 997);
  const StreamParamResult r = parameterizeOutOfCore(*stream, folder, options);
  EXPECT_TRUE(r.isSeamless());
  EXPECT_EQ(r.untangle.leftoverFlips, on.untangle.leftoverFlips);
  EXPECT_EQ(r.untangle.leftoverRegionFaces, on.untangle.leftoverRegionFaces);
  EXPECT_EQ(r.untangle.leftoverFreeVertices, on.untangle.leftoverFreeVertices);
  EXPECT_EQ(r.untangle.leftoverAfterResolve, on.untangle.leftoverAfterResolve);
  EXPECT_EQ(r.untangle.flippedAfter, on.untangle.flippedAfter);
  EXPECT_EQ(r.mapQuality.flipped, on.mapQuality.flipped);
  EXPECT_NEAR(r.mapQuality.relativeGradientError, on.mapQuality.relativeGradientError,
              1e-12 * on.mapQuality.relativeGradientError);
}

TEST(ParamStream, WhatThePathLacksAndTooSmallBudgetsAreRefusedByName) {
  testing::TempDir dir;
  writeMesh(dir.path("in.ply"), testing::generatedMesh(MeshKind::Scan, 3000));
  const std::string common = "param " + dir.path("in.ply") + " --out-of-core --quiet";
  const struct {
    std::string options, named;
  } lacking[] = {{"--solver hat", "--solver hat"},
                 {"--quads " + dir.path("q.obj"), "--quads"},
                 {"--render " + dir.path("r.png"), "--render"},
                 {"--field smooth", "--field smooth"},
                 {"--close-holes 2", "--close-holes"},
                 {"--keep-order", "--keep-order"}};
  for (const auto& c : lacking) {
    const std::string out = run(common + " -o " + dir.path("o.ply") + " " + c.options, 1);
    EXPECT_TRUE(contains(out, "that path has no") && contains(out, c.named)) << out;
    EXPECT_TRUE(contains(out, dir.path("in.ply"))) << out;
  }
  EXPECT_TRUE(contains(run(common + " -o " + dir.path("o.drc"), 1), ".drc output"));
  // The grid-sized system stays in memory: the minimum budget, and the grid that fits.
  std::string out = run(common + " -o " + dir.path("o.ply") + " --memory-budget 300M", 1);
  EXPECT_TRUE(contains(out, "at least 632.0 MiB at --grid 128")) << out;
  EXPECT_TRUE(contains(out, "--grid 64 fits within it")) << out;
  out = run(common + " -o " + dir.path("o.ply") + " --memory-budget 100M", 1);
  EXPECT_TRUE(contains(out, "no grid of 32 or more voxels per axis fits")) << out;
  for (const char* name : {"o.ply", "o.drc", "q.obj", "r.png"}) EXPECT_FALSE(std::filesystem::exists(dir.path(name))) << name;
}

// A small scan's run: an 8 MiB budget, grid 16, 20 cells on the diagonal.
StreamParamOptions smallRunOptions() {
  StreamParamOptions options;
  options.memoryBytes = std::uint64_t(8) << 20;
  options.gridResolution = 16;
  options.spacing.cells = 20;
  return options;
}

// A voxel system that cannot be factored (injected) is solved again with more B-splines joined,
// from the same basis: the map is seamless and the reason reported; failing twice is an error.
TEST(ParamStream, AVoxelSystemThatFailsOnceIsSolvedAgainWithMoreSplinesJoined) {
  const auto mesh = std::make_shared<const TriangleMesh>(testing::generatedMesh(MeshKind::Scan, 6000));
  testing::TempDir dir;
  StreamParamOptions options = smallRunOptions();
  options.writeMap = [](const CleanScratch&, const ScratchMap&) {};
  StageMeter meter;
  options.meter = &meter;
  int attempts = 0, failures = 1;
  options.beforeVoxelSolve = [&] {
    if (attempts++ < failures) throw SolverError("CHOLMOD: not positive definite at column 7 (injected)");
  };
  {
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 997);
    const StreamParamResult r = parameterizeOutOfCore(*stream, folder, options);
    EXPECT_EQ(attempts, 2);
    EXPECT_TRUE(r.isSeamless());
    EXPECT_TRUE(contains(r.voxelRetryReason, "(injected)")) << r.voxelRetryReason;
    std::size_t bases = 0;
    for (const auto& stage : meter.stages()) bases += stage.name == "basis";
    EXPECT_EQ(bases, 1u) << "the basis is built once";
  }
  attempts = 0, failures = 2;
  {
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 997);
    EXPECT_THROW(parameterizeOutOfCore(*stream, folder, options), SolverError);
    EXPECT_EQ(attempts, 2);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
}

// A scratch disk that fills at any point of the run is an IoError naming the folder; the map is
// not written and the folder is empty afterwards.
TEST(ParamStream, AFullScratchDiskIsAnErrorAndNothingIsWritten) {
  const auto mesh = std::make_shared<const TriangleMesh>(testing::generatedMesh(MeshKind::Scan, 6000));
  testing::TempDir dir;
  StreamParamOptions options = smallRunOptions();
  bool written = false;
  options.writeMap = [&](const CleanScratch&, const ScratchMap&) { written = true; };
  std::uint64_t total = 0;
  {
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 997);
    const StreamParamResult r = parameterizeOutOfCore(*stream, folder, options);
    total = folder.bytesWritten();
    EXPECT_TRUE(written);
    EXPECT_TRUE(r.isSeamless());
    EXPECT_GT(r.refine.rounds.size(), 0u);
  }
  ASSERT_GT(total, 0u);
  for (const double share : {0.01, 0.3, 0.6, 0.95}) {
    SCOPED_TRACE(share);
    written = false;
    {
      ScratchFolder folder(dir.dir());
      folder.setWriteLimit(static_cast<std::uint64_t>(share * total));
      const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 997);
      testing::expectScratchFull(folder, [&] { parameterizeOutOfCore(*stream, folder, options); });
    }
    EXPECT_FALSE(written);
    EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
  }
}

}  // namespace
}  // namespace seamvox
