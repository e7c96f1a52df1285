// The library pipeline: one call gives what `seamvox param` gives, validates h in one place,
// reports through the stage meter, cancels, and names the input in errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>

#include <tbb/global_control.h>

#include "core/mesh/topology.h"
#include "core/pipeline/grid_spacing.h"
#include "core/pipeline/parameterize.h"
#include "core/solve/cholmod_solver.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "io/param_report.h"
#include "stream/scratch_direction_store.h"
#include "stream/scratch_folder.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

TriangleMesh sphere(std::uint64_t faces) { return testing::generatedMesh(MeshKind::Sphere, faces); }

std::int64_t eulerCharacteristic(const Topology& topology) {
  std::int64_t chi = 0;
  for (const ComponentInfo& c : computeComponents(topology).components) chi += c.eulerCharacteristic;
  return chi;
}

class PipelineSolvers : public ::testing::TestWithParam<ParamSolver> {};

TEST_P(PipelineSolvers, SeamlessWithConesSummingToEulerCharacteristic) {
  PipelineOptions options;
  options.solver.solver = GetParam();
  options.solver.gridResolution = 32;
  options.spacing.cells = 20;
  StageMeter meter;
  options.meter = &meter;
  const PipelineResult r = parameterize(testing::concatMeshes({sphere(3000), testing::torusMesh(24, 12)}), options);
  EXPECT_TRUE(r.isSeamless()) << r.seamQuality.maxResidual << " " << r.seamQuality.maxIntegerDistance;
  EXPECT_EQ(r.mesh.cornerUV.size(), 3u * r.mesh.numFaces());
  std::int64_t indexSum4 = 0;
  for (std::int32_t k : r.coneIndex4) {
    EXPECT_NE(k, 0);
    indexSum4 += k;
  }
  EXPECT_EQ(r.cones.size(), r.coneIndex4.size());
  EXPECT_EQ(indexSum4, 4 * eulerCharacteristic(r.topology));  // Poincare-Hopf: 2 (sphere) + 0
  EXPECT_GE(r.conePasses, 1u);
  EXPECT_LT(r.mapQuality.relativeGradientError, 0.5);
  // The stages the pipeline closes, in order, on the caller's meter.
  std::vector<std::string> names;
  for (const StageFigures& s : meter.stages()) names.push_back(s.name);
  ASSERT_GE(names.size(), 5u);
  EXPECT_EQ(names[0], "clean");
  EXPECT_EQ(names[1], "field");
  EXPECT_EQ(names[2], "cut");
  EXPECT_EQ(names.back(), "metrics");
  EXPECT_GT(meter.peakBytes(), 0u);
}

// The same input gives the same map, bit for bit, with one thread or two: the assembly sums in
// a fixed order whatever the scheduling (the voxel system, the local hat solves of the
// refinement and of the foldover repair, whose groups run in parallel).
TEST_P(PipelineSolvers, MapDoesNotDependOnTheThreadCount) {
  ScanNoiseOptions noise;
  noise.amplitude = 0.4;
  noise.seed = 11;
  TriangleMesh raw = testing::generatedMesh(MeshKind::Scan, 40000);
  addScanNoise(raw, noise);
  PipelineOptions options;
  options.solver.solver = GetParam();
  options.solver.gridResolution = 64;
  std::vector<PipelineResult> runs;
  for (std::size_t threads : {1u, 2u}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    runs.push_back(parameterize(TriangleMesh(raw), options));
  }
  ASSERT_TRUE(runs[0].isSeamless());
  // voxloc's refinement, solved on the smoothed surface, leaves this scan no flip to repair: its
  // own groups are compared (the repair's are, with hat and vox).
  if (GetParam() == ParamSolver::VoxLoc) {
    EXPECT_GT(runs[0].solved.refine.solves, 1u) << "no refinement in groups: they are not compared";
  } else {
    EXPECT_GT(runs[0].untangle.flippedBefore, 0u) << "no repair ran: its groups are not compared";
  }
  ASSERT_EQ(runs[0].mesh.cornerUV.size(), runs[1].mesh.cornerUV.size());
  std::size_t differ = 0;
  for (CornerId c = 0; c < runs[0].mesh.cornerUV.size(); ++c) differ += runs[0].mesh.cornerUV[c] != runs[1].mesh.cornerUV[c];
  EXPECT_EQ(differ, 0u) << "corners whose (u, v) differ between one and two threads";
  EXPECT_EQ(runs[0].mapQuality.flipped, runs[1].mapQuality.flipped);
}

// The map keeps its wedge ids per vertex over the result's own triangles (WedgeMap::
// viewTriangles): a moved result keeps them, a copied mesh holds ids of its own and outlives
// the result it came from.
TEST_P(PipelineSolvers, TheMapViewsTheResultsTrianglesAndACopyOwnsItsIds) {
  PipelineOptions options;
  options.solver.solver = GetParam();
  options.solver.gridResolution = 32;
  auto owner = std::make_unique<PipelineResult>(parameterize(sphere(6000), options));
  ASSERT_TRUE(owner->isSeamless());
  EXPECT_TRUE(owner->mesh.cornerUV.viewsTriangles());
  const std::vector<Vec2d> values = testing::cornerValues(owner->mesh.cornerUV);
  PipelineResult moved = std::move(*owner);
  EXPECT_TRUE(moved.mesh.cornerUV.viewsTriangles());
  EXPECT_EQ(testing::cornerValues(moved.mesh.cornerUV), values);
  TriangleMesh copy = moved.mesh;
  owner.reset();
  moved = PipelineResult();
  EXPECT_FALSE(copy.cornerUV.viewsTriangles());
  EXPECT_EQ(testing::cornerValues(copy.cornerUV), values);
}

INSTANTIATE_TEST_SUITE_P(Solvers, PipelineSolvers,
                         ::testing::Values(ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc));

TEST(Pipeline, GivesWhatTheCommandWrites) {
  testing::TempDir dir;
  const std::string input = dir.path("s.obj"), output = dir.path("s_uv.obj"), report = dir.path("r.json");
  writeMesh(input, sphere(4000));
  std::string log;
  ASSERT_EQ(testing::runSeamvox("param " + input + " -o " + output + " --solver hat --quiet --report " + report, &log), 0) << log;
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  const PipelineResult r = parameterize(readMesh(input), options);
  const JsonValue j = parseJson(testing::readFile(report), report);
  EXPECT_EQ(j.numberAt("faces"), r.mesh.numFaces());
  EXPECT_EQ(j.numberAt("cones"), static_cast<double>(r.cones.size()));
  EXPECT_EQ(j.numberAt("seams"), r.seams);
  EXPECT_EQ(j.numberAt("quality.seamless"), 1.0);
  EXPECT_TRUE(r.isSeamless());
  EXPECT_EQ(j.numberAt("quality.flipped"), static_cast<double>(r.mapQuality.flipped));
  EXPECT_NEAR(j.numberAt("quality.relativeGradientError"), r.mapQuality.relativeGradientError, 1e-9);
  // The library's report has the same keys as the command's.
  ParamReportContext context;
  const JsonValue mine = parseJson(paramReportJson(r, context));
  for (const auto& [key, value] : flattenJson(j)) {
    if (key.rfind("stages.", 0) == 0) continue;  // the command adds read and write stages
    if (key == "path" || key == "memoryBudget" || key == "estimatedBytes" || key == "fieldBytesOnDisk") {
      continue;  // and its budget
    }
    EXPECT_NE(mine.find(key), nullptr) << key;
  }
}

TEST(Pipeline, AMeshAboveTheMemoryBudgetGoesOutOfCoreOrIsRefusedBeforeItIsRead) {
  // An estimate (from the header's counts) above the budget takes the out-of-core path, which
  // needs the grid-sized system in memory: below that the error names the file, the minimum and
  // the budget, and nothing is written; within the budget the run says which path ran, and the
  // estimate errs high.
  testing::TempDir dir;
  const std::string input = dir.path("s.ply");
  const TriangleMesh mesh = sphere(20000);
  writeMesh(input, mesh);
  const std::string common = "param " + input + " -o " + dir.path("o.ply") + " --report " + dir.path("r.json");
  std::string out;
  EXPECT_EQ(testing::runSeamvox(common + " --quiet --memory-budget 40M", &out), 1) << out;
  EXPECT_NE(out.find(input + ": param out of core needs a --memory-budget of at least 632.0 MiB at --grid 128"),
            std::string::npos) << out;
  EXPECT_NE(out.find("got 40.0 MiB"), std::string::npos) << out;
  EXPECT_FALSE(std::ifstream(dir.path("o.ply")).good());
  EXPECT_FALSE(std::ifstream(dir.path("r.json")).good());
  const std::uint64_t estimate = estimateParamPeakBytes(mesh.numFaces(), ParamSolver::Auto, kDefaultGridResolution);
  ASSERT_EQ(testing::runSeamvox(common + " --memory-budget " + std::to_string(estimate), &out), 0) << out;
  EXPECT_NE(out.find("path in memory: estimate"), std::string::npos) << out;
  const JsonValue report = parseJson(testing::readFile(dir.path("r.json")));
  EXPECT_EQ(report["path"].text, "in-memory");
  EXPECT_EQ(report.numberAt("memoryBudget"), double(estimate));
  EXPECT_EQ(report.numberAt("estimatedBytes"), double(estimate));
  EXPECT_GE(report.numberAt("estimatedBytes"), report.numberAt("peakResidentBytes"));
  EXPECT_EQ(testing::runSeamvox(common + " --memory-budget " + std::to_string(estimate - 1), &out), 1) << out;
  // An OBJ declares no counts: guessed from its size, the estimate is shown, not enforced.
  writeMesh(dir.path("s.obj"), mesh);
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("s.obj") + " -o " + dir.path("o.obj") + " --quiet --memory-budget 40M",
                                &out), 0) << out;
  EXPECT_NE(out.find("(faces guessed from the file size) above the budget 40.0 MiB"), std::string::npos) << out;
}

// Maps `mesh` by voxloc in memory and with the field's directions in a scratch file between the
// basis and the refinement (no singularities kept between cone passes either): the same map,
// corner by corner, and the file gone afterwards. Returns the cone passes.
std::uint32_t expectSameMapWithTheFieldOnDisk(const TriangleMesh& mesh) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::VoxLoc;
  options.solver.gridResolution = 32;
  options.spacing.cells = 20;
  const PipelineResult inMemory = parameterize(mesh, options);
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  ScratchDirectionStore store(folder);
  options.directionStore = &store;
  const PipelineResult onDisk = parameterize(mesh, options);
  const std::uint64_t perPass = 12 * std::uint64_t(onDisk.mesh.numFaces());
  EXPECT_GE(store.bytesStored(), perPass);
  EXPECT_EQ(store.bytesStored() % perPass, 0u);  // once per cone pass
  EXPECT_EQ(folder.bytesOnDisk(), folder.bytesKeptForReuse());
  EXPECT_EQ(onDisk.conePasses, inMemory.conePasses);
  EXPECT_EQ(onDisk.mesh.numFaces(), inMemory.mesh.numFaces());
  if (onDisk.mesh.numFaces() != inMemory.mesh.numFaces()) return 0;
  EXPECT_EQ(onDisk.cones, inMemory.cones);
  EXPECT_EQ(onDisk.solved.param.translations, inMemory.solved.param.translations);
  const WedgeMap& a = inMemory.mesh.cornerUV;
  const WedgeMap& b = onDisk.mesh.cornerUV;
  EXPECT_EQ(a.size(), b.size());
  std::size_t different = 0;
  for (CornerId c = 0; c < std::min(a.size(), b.size()); ++c) different += a[c] != b[c];
  EXPECT_EQ(different, 0u);
  EXPECT_TRUE(onDisk.seamQuality.isSeamless());
  return inMemory.conePasses;
}

TEST(Pipeline, TheFieldWaitsOnDiskWhileTheMapIsBuiltAndTheMapIsTheSame) {
  // A scan with holes, islands and bad faces.
  expectSameMapWithTheFieldOnDisk(testing::generatedMesh(MeshKind::Scan, 30000));
}

TEST(Pipeline, LaterConePassesReuseTheFieldsSingularitiesAndGiveTheSameMap) {
  // A scan whose solves put close cones on one point: later passes restore the singularities the
  // first pass kept (in memory) instead of recomputing them on the smoothed surface (on disk).
  GenerateOptions scan;
  scan.kind = MeshKind::Scan;
  scan.faces = 20000;
  scan.seed = 3;  // 3 passes (seed 2 had 2 until its islands left the voxel basis)
  EXPECT_GE(expectSameMapWithTheFieldOnDisk(generateMesh(scan).mesh), 2u);
}

TEST(Pipeline, AFullDiskWhileTheFieldGoesToDiskIsAnErrorNamingTheFolder) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir(), 1234567);
  folder.setWriteLimit(4096);
  ScratchDirectionStore store(folder);
  PipelineOptions options;
  options.solver.solver = ParamSolver::VoxLoc;
  options.solver.gridResolution = 32;
  options.spacing.cells = 20;
  options.directionStore = &store;
  try {
    parameterize(sphere(20000), options);
    FAIL() << "a full scratch disk must stop the run";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(folder.path()), std::string::npos) << e.what();
  }
}

TEST(Pipeline, AboveTheBudgetParamKeepsTheFieldOnDiskWhenThatFits) {
  // A budget between the in-memory estimate and the one with the field on disk: param runs, says
  // so, reports the bytes it kept on disk, leaves no scratch behind and writes the same file as
  // within the budget.
  testing::TempDir dir;
  const std::string input = dir.path("s.ply");
  const TriangleMesh mesh = testing::generatedMesh(MeshKind::Scan, 20000);
  writeMesh(input, mesh);
  ASSERT_TRUE(std::filesystem::create_directory(dir.path("scratch")));
  const auto estimate = [&](bool onDisk) {
    return estimateParamPeakBytes(mesh.numFaces(), ParamSolver::VoxLoc, 32, onDisk);
  };
  ASSERT_LT(estimate(true), estimate(false));
  const std::string common = "param " + input + " --solver voxloc --grid 32 --quiet --scratch " + dir.path("scratch");
  std::string out;
  ASSERT_EQ(testing::runSeamvox(common + " -o " + dir.path("m.ply") + " --memory-budget " +
                                    std::to_string(estimate(false)), &out), 0) << out;
  EXPECT_NE(out.find("path in memory: estimate"), std::string::npos) << out;
  const std::uint64_t between = (estimate(true) + estimate(false)) / 2;
  ASSERT_EQ(testing::runSeamvox(common + " -o " + dir.path("d.ply") + " --report " + dir.path("r.json") +
                                    " --memory-budget " + std::to_string(between), &out), 0) << out;
  EXPECT_NE(out.find("path in memory (the field's directions on disk while the map is built)"), std::string::npos) << out;
  const JsonValue report = parseJson(testing::readFile(dir.path("r.json")));
  EXPECT_EQ(report.numberAt("estimatedBytes"), double(estimate(true)));
  EXPECT_GE(report.numberAt("fieldBytesOnDisk"), 12.0 * report.numberAt("faces"));
  EXPECT_EQ(testing::readFile(dir.path("d.ply")), testing::readFile(dir.path("m.ply")));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path("scratch"))) << "scratch left behind";
  // Below both estimates it is still refused.
  EXPECT_EQ(testing::runSeamvox(common + " -o " + dir.path("x.ply") + " --memory-budget " +
                                    std::to_string(estimate(true) - 1), &out), 1) << out;
}

TEST(Pipeline, CancelsThroughProgress) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  int calls = 0;
  options.progress = [&](const char*, double) { return ++calls < 3; };
  EXPECT_THROW(parameterize(sphere(3000), options), CancelledError);
  EXPECT_GE(calls, 3);
}

TEST(Pipeline, ImportedFieldOfTheWrongSizeIsAnInputError) {
  PipelineOptions options;
  options.field.importedPerInputFace.assign(10, Vec3d(1, 0, 0));
  EXPECT_THROW(parameterize(sphere(3000), options), InputError);
}

TEST(Pipeline, ImportedFieldFollowsCleanedFaces) {
  // A mesh with a duplicate face: cleaning drops it, the field is still one vector per input face.
  TriangleMesh mesh = sphere(3000);
  mesh.triangles.push_back(mesh.triangles[5]);
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.field.importedPerInputFace.assign(mesh.numFaces(), Vec3d(1, 0.3, 0.2));
  const PipelineResult r = parameterize(std::move(mesh), options);
  EXPECT_EQ(r.fieldMethod, "file");
  EXPECT_TRUE(r.isSeamless());
}

TEST(Pipeline, ScatteredInputIsSolvedInSpatialOrderWithTheFieldFollowingItsFaces) {
  // A shuffled sphere put in spatial order by cleaning: an imported per-input-face field (a
  // function of each face's centroid) must follow the faces, so the cones are those of the same
  // field on the mesh in its own order.
  const auto fieldOf = [](const TriangleMesh& mesh) {
    std::vector<Vec3d> v(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const Vec3d c = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
      v[f] = Vec3d(std::cos(7.0 * c.x()), std::sin(5.0 * c.y()), 0.3 + c.z());
    }
    return v;
  };
  const TriangleMesh ordered = sphere(12000);
  const TriangleMesh scattered = testing::shuffledMesh(ordered, 11);
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.clean.reorderMinFaces = 1000;
  options.field.importedPerInputFace = fieldOf(ordered);
  const PipelineResult a = parameterize(ordered, options);
  options.field.importedPerInputFace = fieldOf(scattered);
  const PipelineResult b = parameterize(scattered, options);
  EXPECT_FALSE(a.cleanReport.reordered);
  EXPECT_TRUE(b.cleanReport.reordered);
  EXPECT_TRUE(a.isSeamless());
  EXPECT_TRUE(b.isSeamless());
  EXPECT_GT(a.conesBeforeMerge, 8u) << "a field with cones of its own";
  EXPECT_EQ(a.conesBeforeMerge, b.conesBeforeMerge);
  EXPECT_NEAR(a.mapQuality.relativeGradientError, b.mapQuality.relativeGradientError,
              0.05 * a.mapQuality.relativeGradientError);
}

// The real 2n x 2n form [Re -Im; Im Re] solves the same Hermitian systems: with every
// factorization forced into it (field, seamless solves, refinement) the pipeline reports the
// fallback and gives the same cones and, up to rounding, the same map.
TEST_P(PipelineSolvers, RealFormFallbackGivesTheSameMap) {
  PipelineOptions options;
  options.solver.solver = GetParam();
  options.solver.gridResolution = 32;
  options.spacing.cells = 20;
  const TriangleMesh mesh = testing::concatMeshes({sphere(3000), testing::torusMesh(24, 12)});
  const PipelineResult complex = parameterize(mesh, options);
  EXPECT_FALSE(complex.solved.param.stats.realFallback);
  EXPECT_FALSE(complex.fieldSolve.realFallback);
  PipelineResult real;
  {
    ScopedRealFormOnly realFormOnly;
    real = parameterize(mesh, options);
  }
  EXPECT_TRUE(real.solved.param.stats.realFallback);
  EXPECT_TRUE(real.fieldSolve.realFallback);
  EXPECT_GT(real.fieldSolve.factorBytes, complex.fieldSolve.factorBytes) << "2n unknowns";
  EXPECT_TRUE(complex.isSeamless()) << complex.seamQuality.maxResidual;
  EXPECT_TRUE(real.isSeamless()) << real.seamQuality.maxResidual;
  EXPECT_EQ(real.cones, complex.cones);
  const std::vector<Vec2d> a = testing::cornerValues(complex.mesh.cornerUV);
  const std::vector<Vec2d> b = testing::cornerValues(real.mesh.cornerUV);
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  EXPECT_LT(worst, 1e-6) << "grid units";
}

TEST(GridSpacing, ValidatesInOnePlace) {
  GridSpacing g;
  EXPECT_DOUBLE_EQ(g.spacing(10.0), 10.0 / GridSpacing::kDefaultCells);
  g.cells = 50;
  EXPECT_DOUBLE_EQ(g.spacing(10.0), 0.2);
  g.edgeLength = 0.5;
  EXPECT_THROW(g.validate(), InputError);  // both
  g.cells = 0;
  EXPECT_DOUBLE_EQ(g.spacing(10.0), 0.5);
  EXPECT_THROW(g.spacing(0.0), InputError);
  EXPECT_THROW(g.spacing(std::nan("")), InputError);
  g.edgeLength = 1e-300;
  EXPECT_THROW(g.spacing(10.0), InputError);  // more than kMaxCells cells
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    GridSpacing e;
    e.edgeLength = bad;
    EXPECT_THROW(e.validate(), InputError) << bad;
    GridSpacing c;
    c.cells = bad;
    EXPECT_THROW(c.validate(), InputError) << bad;
  }
  GridSpacing huge;
  huge.cells = 1e308;
  EXPECT_THROW(huge.validate(), InputError);
}

TEST(Errors, RethrowWithContextKeepsTheTypeAndPrefixesOnce) {
  auto rethrown = [](auto error, const std::string& context) -> std::string {
    try {
      try {
        throw error;
      } catch (...) {
        rethrowWithContext(context);
      }
    } catch (const decltype(error)& e) {
      return e.what();
    }
    return "wrong type";
  };
  EXPECT_EQ(rethrown(SolverError("cannot factor"), "a.ply"), "a.ply: cannot factor");
  EXPECT_EQ(rethrown(InputError("a.ply: line 3: bad"), "a.ply"), "a.ply: line 3: bad");
  EXPECT_EQ(rethrown(TopologyError("x"), "m.obj"), "m.obj: x");
  EXPECT_EQ(rethrown(IoError("x"), "m.obj"), "m.obj: x");
  EXPECT_EQ(rethrown(CancelledError("cancelled"), "m.obj"), "cancelled");
  EXPECT_THROW(
      {
        try {
          throw std::runtime_error("other");
        } catch (...) {
          rethrowWithContext("m.obj");
        }
      },
      std::runtime_error);
}

// Holonomy of the written map around a boundary loop, read off the corner coordinates alone:
// each interior edge crossed gives q -> r q + t (r a quarter turn from the edge's two images).
struct LoopHolonomy {
  std::complex<double> r{1.0, 0.0}, t{0.0, 0.0};
  std::uint32_t seamCrossings = 0;  ///< edges whose two images differ
};

std::vector<LoopHolonomy> holeHolonomies(const PipelineResult& r, double maxExtent) {
  const Topology& topology = r.topology;
  const std::vector<Vec2d> uv = testing::cornerValues(r.mesh.cornerUV);
  const auto q = [&](CornerId c) { return std::complex<double>(uv[c].x(), uv[c].y()); };
  std::vector<LoopHolonomy> out;
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (!topology.isBoundaryEdge(start) || seen[start]) continue;
    LoopHolonomy h;
    BoundingBox box;
    CornerId c = start;
    do {
      seen[c] = 1;
      const Vec3d p = r.mesh.position(topology.vertex(prevCorner(c)));
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
      std::vector<CornerId> crossed;
      c = nextBoundaryCorner(topology, c, &crossed);
      for (CornerId edge : crossed) {
        const CornerId o = topology.opposite(edge);
        // Edge of `edge` runs next(edge) -> prev(edge); in face(o) the same points are prev(o), next(o).
        const std::complex<double> a = q(nextCorner(edge)), b = q(prevCorner(edge));
        const std::complex<double> a2 = q(prevCorner(o)), b2 = q(nextCorner(o));
        const std::complex<double> rot = std::abs(b - a) > 1e-12 ? (b2 - a2) / (b - a) : 1.0;
        const std::complex<double> unit(std::round(rot.real()), std::round(rot.imag()));
        const std::complex<double> shift = a2 - unit * a;
        if (std::abs(unit - 1.0) > 0.5 || std::abs(shift) > 1e-9) ++h.seamCrossings;
        h.r = unit * h.r;
        h.t = unit * h.t + shift;
      }
    } while (c != start);
    if ((box.max - box.min).norm() <= maxExtent) out.push_back(h);
  }
  return out;
}

// A hole smaller than a few grid cells carries no seam translation in the written map (it can be
// closed by a quad mesh); without closeHoles the rounding leaves some of them a translation. The
// holes are capped for the solve (then dropped), with the direct field and the proxy (larger
// meshes); loops no cap closes have their translations held at zero as constraints (here all of
// them, with the caps off).
TEST(Pipeline, SmallHolesCarryNoTranslationInTheWrittenMap) {
  struct Case {
    ParamSolver solver;
    double cells;
    FieldMethod field;
    bool capped;
  };
  for (const Case& c : {Case{ParamSolver::Hat, 0.0, FieldMethod::Auto, false},
                        Case{ParamSolver::Hat, kCloseHoleCells, FieldMethod::Auto, true},
                        Case{ParamSolver::VoxLoc, kCloseHoleCells, FieldMethod::Auto, true},
                        Case{ParamSolver::VoxLoc, kCloseHoleCells, FieldMethod::Proxy, true},
                        Case{ParamSolver::Hat, kCloseHoleCells, FieldMethod::Proxy, false},
                        Case{ParamSolver::VoxLoc, kCloseHoleCells, FieldMethod::Auto, false}}) {
    SCOPED_TRACE(std::string(paramSolverName(c.solver)) + " " + std::to_string(c.cells) + " " +
                 fieldMethodName(c.field) + (c.capped ? " capped" : ""));
    PipelineOptions options;
    options.solver.solver = c.solver;
    options.solver.gridResolution = 32;
    options.spacing.cells = 25;
    options.closeHoles = c.cells;
    options.capHoles = c.capped;
    options.field.method = c.field;
    const TriangleMesh input = testing::withOneTriangleHoles(sphere(6000), 37);
    const PipelineResult r = parameterize(input, options);
    ASSERT_TRUE(r.isSeamless());
    EXPECT_EQ(r.mesh.numFaces(), input.numFaces());  // the caps are gone from the output
    EXPECT_EQ(r.mesh.numVertices(), input.numVertices());
    EXPECT_EQ(r.mesh.cornerUV.size(), 3u * input.numFaces());
    const std::vector<LoopHolonomy> holes = holeHolonomies(r, kCloseHoleCells * r.edgeLength);
    ASSERT_GE(holes.size(), 100u);
    std::uint32_t crossing = 0, translated = 0;
    for (const LoopHolonomy& h : holes) {
      if (h.seamCrossings > 0) ++crossing;
      if (std::abs(h.r - 1.0) < 1e-9 && std::abs(h.t) > 1e-6) ++translated;
    }
    EXPECT_GT(crossing, 0u) << "no hole touches a seam: the test proves nothing";
    const bool capped = c.cells > 0.0 && c.capped;
    EXPECT_EQ(r.fieldCappedHoles, capped ? holes.size() : 0u);
    EXPECT_EQ(r.solved.param.smallHoles, c.cells > 0.0 && !capped ? holes.size() : 0u);
    if (c.cells > 0.0) {
      EXPECT_EQ(translated, 0u);
    } else {
      EXPECT_GT(translated, 0u) << "no hole kept a translation without closeHoles: the test proves nothing";
    }
  }
}

}  // namespace
}  // namespace seamvox
