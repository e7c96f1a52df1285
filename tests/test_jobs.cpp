// The job runner: manifest parsing, the scheduling rule, tile welding and splitting, and
// `seamvox jobs` end to end (failures recorded, resume, --force, tiles, MPI).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/mesh/clean.h"
#include "core/mesh/vertex_attributes.h"
#include "core/system/errors.h"
#include "core/synth/generate.h"
#include "core/quality/metrics.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "core/batch/jobs.h"
#include "core/solve/param_solver.h"
#include "core/solve/param_solver.h"
#include "testing.h"

namespace seamvox {
namespace {

using ::testing::HasSubstr;
using testing::readFile;
using testing::runSeamvox;
using testing::TempDir;
using testing::writeFile;
namespace fs = std::filesystem;

std::vector<std::string> fakeGlob(const std::string& pattern) {
  if (pattern == "/data/scans/*.ply") return {"/data/scans/a.ply", "/data/scans/b.ply"};
  if (pattern == "/data/site/t*.ply") return {"/data/site/t0.ply", "/data/site/t1.ply"};
  if (pattern.find('*') != std::string::npos) return {};
  return {pattern};
}

using testing::messageOf;

TEST(JobManifest, DirectivesDefaultsGlobsAndTiles) {
  const std::string text =
      "# nightly batch\n"
      "output results\n"
      "param --solver hat --cells 80\n"
      "mesh scans/*.ply\n"
      "format obj\n"
      "mesh /abs/c.off : --greedy   # per-job option\n"
      "param --solver vox\n"
      "tiles site site/t*.ply : --grid 64\n";
  const Manifest m = parseManifest(text, "m.txt", "/data", fakeGlob);
  EXPECT_EQ(m.outputDir, "/data/results");
  ASSERT_EQ(m.jobs.size(), 4u);
  EXPECT_EQ(m.jobs[0].name, "a");
  EXPECT_EQ(m.jobs[1].inputs, std::vector<std::string>{"/data/scans/b.ply"});
  EXPECT_EQ(m.jobs[1].format, "drc");
  EXPECT_EQ(m.jobs[1].paramArgs, (std::vector<std::string>{"--solver", "hat", "--cells", "80"}));
  EXPECT_EQ(m.jobs[2].name, "c");
  EXPECT_EQ(m.jobs[2].format, "obj");
  EXPECT_EQ(m.jobs[2].paramArgs, (std::vector<std::string>{"--solver", "hat", "--cells", "80", "--greedy"}));
  EXPECT_EQ(m.jobs[2].line, 6u);
  EXPECT_TRUE(m.jobs[3].tiled);
  EXPECT_EQ(m.jobs[3].name, "site");
  EXPECT_EQ(m.jobs[3].inputs, (std::vector<std::string>{"/data/site/t0.ply", "/data/site/t1.ply"}));
  EXPECT_EQ(m.jobs[3].paramArgs, (std::vector<std::string>{"--solver", "vox", "--grid", "64"}));
  EXPECT_EQ(parseManifest("mesh x.ply\n", "m", "/d", fakeGlob).outputDir, "/d/out");
}

TEST(JobManifest, ErrorsNameTheLine) {
  auto parse = [](const std::string& text) { return parseManifest(text, "m.txt", "/d", fakeGlob); };
  EXPECT_THAT(messageOf<InputError>([&] { parse("mesh a.ply\nbake x\n"); }), HasSubstr("m.txt:2: unknown directive 'bake'"));
  EXPECT_THAT(messageOf<InputError>([&] { parse("mesh nothing/*.ply\n"); }), HasSubstr("m.txt:1: no file matches"));
  EXPECT_THAT(messageOf<InputError>([&] { parse("mesh a.ply : -o x.obj\n"); }), HasSubstr("set by the job runner"));
  EXPECT_THAT(messageOf<InputError>([&] { parse("format stl\n"); }), HasSubstr("unknown format"));
  EXPECT_THAT(messageOf<InputError>([&] { parse("mesh a.ply\nmesh other/a.off\n"); }),
              HasSubstr("m.txt:2: two jobs named 'a'"));
  EXPECT_THAT(messageOf<InputError>([&] { parse("tiles site\n"); }), HasSubstr("needs a name and at least one tile"));
}

TEST(JobSchedule, FirstPendingJobThatFitsTheBudget) {
  EXPECT_EQ(pickNextJob({5, 3}, 0, 10), 0);
  EXPECT_EQ(pickNextJob({5, 3}, 6, 10), 1);  // the first does not fit next to the running 6
  EXPECT_EQ(pickNextJob({5, 5}, 6, 10), -1);
  EXPECT_EQ(pickNextJob({}, 0, 10), -1);
  EXPECT_EQ(pickNextJob({4}, 12, 10), -1);  // over budget already (no underflow)
  // Estimates grow with faces and, for the voxel solvers, with the grid.
  const std::vector<std::string> hat = {"--solver", "hat"}, voxloc = {"--solver", "voxloc"},
                                 vox256 = {"--solver", "voxloc", "--grid", "256"};
  EXPECT_LT(estimateJobPeakBytes(1000, hat), estimateJobPeakBytes(1000000, hat));
  EXPECT_LT(estimateJobPeakBytes(1000, hat), estimateJobPeakBytes(1000, voxloc));
  EXPECT_LT(estimateJobPeakBytes(1000, voxloc), estimateJobPeakBytes(1000, vox256));
  // The default solver is param's: auto, hat on small meshes, voxloc on large ones; the same
  // rule param checks against its own budget.
  EXPECT_EQ(estimateJobPeakBytes(1000, {}), estimateJobPeakBytes(1000, hat));
  EXPECT_EQ(estimateJobPeakBytes(20000000, {}), estimateJobPeakBytes(20000000, voxloc));
  EXPECT_EQ(estimateJobPeakBytes(20000000, {}), estimateParamPeakBytes(20000000, ParamSolver::Auto, 128));
  // Vertex properties count three times (read, gathered by cleaning, written).
  EXPECT_EQ(estimateJobPeakBytes(1000, hat, 4000000), estimateJobPeakBytes(1000, hat) + 12000000);
  // What a job holds: its estimate when that fits the budget; else the whole budget, where param
  // runs out of core, when it holds that path's grid-sized system; else nothing (it fails).
  EXPECT_EQ(jobOutOfCoreMinimumBytes(vox256), outOfCoreMinimumBytes(256));
  EXPECT_EQ(jobOutOfCoreMinimumBytes({}), outOfCoreMinimumBytes(kDefaultGridResolution));
  EXPECT_LT(outOfCoreMinimumBytes(64), outOfCoreMinimumBytes(128));
  EXPECT_EQ(reserveJobMemory(300, 500, 1000), 300u);
  EXPECT_EQ(reserveJobMemory(3000, 500, 1000), 1000u);
  EXPECT_EQ(reserveJobMemory(3000, 1500, 1000), 0u);
  EXPECT_EQ(reserveJobMemory(1000, 1500, 1000), 1000u);
}

/// A generated sphere cut into three tiles by face centroid x, each tile with its own vertices.
std::vector<TriangleMesh> cutIntoTiles(const TriangleMesh& mesh) {
  std::vector<TriangleMesh> tiles(3);
  std::vector<std::vector<VertexId>> map(3, std::vector<VertexId>(mesh.numVertices(), kInvalidId));
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    double x = 0.0;
    for (const VertexId v : mesh.triangles[f]) x += mesh.positions[v][0] / 3.0;
    const int t = x < -0.3 ? 0 : x < 0.3 ? 1 : 2;
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      VertexId& m = map[t][mesh.triangles[f][k]];
      if (m == kInvalidId) {
        m = tiles[t].numVertices();
        tiles[t].positions.push_back(mesh.positions[mesh.triangles[f][k]]);
      }
      tri[k] = m;
    }
    tiles[t].triangles.push_back(tri);
  }
  return tiles;
}

TriangleMesh generatedSphere(std::uint64_t faces) {
  GenerateOptions options;
  options.faces = faces;
  return generateMesh(options).mesh;
}

TEST(JobTiles, WeldThenSplitRestoresEveryTile) {
  const TriangleMesh mesh = generatedSphere(3000);
  const std::vector<TriangleMesh> tiles = cutIntoTiles(mesh);
  for (const TriangleMesh& t : tiles) ASSERT_GT(t.numFaces(), 100u);
  const WeldedTiles welded = weldTiles(tiles);
  EXPECT_EQ(welded.mesh.numFaces(), mesh.numFaces());
  EXPECT_EQ(welded.mesh.numVertices(), mesh.numVertices()) << "every border vertex welded once";
  EXPECT_GT(welded.weldedVertices, 0u);
  // A closed surface again: cleaning finds no boundary.
  const CleanResult clean = cleanMesh(welded.mesh);
  EXPECT_EQ(clean.report.outputFaces, mesh.numFaces());

  TriangleMesh withUV = welded.mesh;
  std::vector<Vec2d> values;
  for (FaceId f = 0; f < withUV.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) values.emplace_back(f, k);
  }
  withUV.cornerUV = WedgeMap::fromCorners(withUV.triangles, values);
  std::swap(withUV.triangles.front(), withUV.triangles.back());  // order and rotation do not matter
  withUV.cornerUV.swapCorners(0, 3 * (withUV.numFaces() - 1));
  const SplitTiles split = splitTiles(withUV, tiles);
  EXPECT_EQ(split.missingFaces, 0u);
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    EXPECT_EQ(split.tiles[t].numFaces(), tiles[t].numFaces());
    EXPECT_EQ(split.tiles[t].numVertices(), tiles[t].numVertices());
    EXPECT_EQ(split.tiles[t].cornerUV.size(), 3u * tiles[t].numFaces());
  }
  TriangleMesh stranger = withUV;
  stranger.positions[stranger.triangles[7][0]] += Vec3f(0.5f, 0.0f, 0.0f);
  EXPECT_THROW(splitTiles(stranger, tiles), InputError);
}

TEST(JobTiles, VertexPropertiesFollowTheWeldAndTheSplit) {
  std::vector<TriangleMesh> tiles = cutIntoTiles(generatedSphere(3000));
  auto valueAt = [](const Vec3f& p) { return std::round(1000.0 * (p.x() + 2.0 * p.y() + 4.0 * p.z())); };
  auto expectValuesOfPositions = [&](const TriangleMesh& mesh, const std::string& what) {
    const VertexProperty* q = mesh.attributes.find("quality");
    ASSERT_NE(q, nullptr) << what;
    ASSERT_EQ(q->size(), mesh.numVertices()) << what;
    for (VertexId v = 0; v < mesh.numVertices(); ++v) ASSERT_EQ(q->value(v), valueAt(mesh.positions[v])) << what;
  };
  for (TriangleMesh& tile : tiles) {
    VertexProperty& q = tile.attributes.add("quality", ScalarType::Int32, tile.numVertices());
    for (VertexId v = 0; v < tile.numVertices(); ++v) q.setValue(v, valueAt(tile.positions[v]));
  }
  const WeldedTiles welded = weldTiles(tiles);
  expectValuesOfPositions(welded.mesh, "welded");
  const SplitTiles split = splitTiles(welded.mesh, tiles);
  for (std::size_t t = 0; t < tiles.size(); ++t) expectValuesOfPositions(split.tiles[t], "tile " + std::to_string(t));
  tiles[1].attributes.properties[0].name = "confidence";
  EXPECT_THROW(weldTiles(tiles), InputError);  // different properties: named, not dropped
}

/// A folder with three generated meshes, one corrupt file and a manifest over them.
struct Batch {
  TempDir dir;
  Batch() {
    fs::create_directories(dir.path("in"));
    std::string log;
    const char* kinds[] = {"sphere", "torus", "sphere"};
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(runSeamvox(std::string("gen ") + kinds[i] + " --faces 3000 --seed " + std::to_string(i + 1) +
                               " -o " + dir.path("in/m" + std::to_string(i) + ".ply"), &log), 0) << log;
    }
    writeFile(dir.path("in/broken.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n");
    writeFile(dir.path("jobs.txt"), "output out\nparam --solver hat --cells 30\nmesh in/*.ply\n");
  }
  int run(const std::string& extra, std::string* log) {
    return runSeamvox("jobs " + dir.path("jobs.txt") + " --quiet --workers 2 " + extra, log);
  }
  /// Replaces the manifest, then runs it.
  int runManifest(const std::string& manifest, std::string* log) {
    writeFile(dir.path("jobs.txt"), manifest);
    return run("", log);
  }
};

fs::file_time_type mtime(const std::string& path) { return fs::last_write_time(path); }

TEST(JobsCommand, FailuresAreRecordedRerunsSkipAndForceRedoes) {
  Batch batch;
  std::string log, first;
  EXPECT_EQ(batch.run("", &first), 6) << first;
  EXPECT_THAT(first, HasSubstr("4 jobs: 1 failed"));
  const std::string csv = readFile(batch.dir.path("out/summary.csv"));
  EXPECT_THAT(csv, HasSubstr("\"broken\",failed"));
  EXPECT_THAT(csv, HasSubstr("broken.ply"));  // the reader's message names the file
  for (const char* name : {"m0", "m1", "m2"}) {
    EXPECT_THAT(csv, HasSubstr(std::string("\"") + name + "\",done")) << csv;
    const std::string output = batch.dir.path(std::string("out/") + name + ".drc");
    ASSERT_TRUE(fs::exists(output));
    const std::string report = readFile(batch.dir.path(std::string("out/") + name + ".json"));
    EXPECT_THAT(report, HasSubstr("\"seamless\": true"));
    EXPECT_THAT(report, HasSubstr("\"param\": {"));
    EXPECT_EQ(runSeamvox("check " + output + " --tolerance 1e-4", &log), 0) << log;
  }
  EXPECT_FALSE(fs::exists(batch.dir.path("out/broken.json")));

  const auto before = mtime(batch.dir.path("out/m1.drc"));
  EXPECT_EQ(batch.run("", &log), 6) << log;
  const std::string again = readFile(batch.dir.path("out/summary.csv"));
  for (const char* name : {"m0", "m1", "m2"}) EXPECT_THAT(again, HasSubstr(std::string("\"") + name + "\",skipped"));
  EXPECT_EQ(mtime(batch.dir.path("out/m1.drc")), before);

  // A changed input is redone; the others stay skipped.
  EXPECT_EQ(runSeamvox("gen sphere --faces 3000 --seed 9 -o " + batch.dir.path("in/m2.ply"), &log), 0);
  EXPECT_EQ(batch.run("", &log), 6) << log;
  EXPECT_THAT(readFile(batch.dir.path("out/summary.csv")), HasSubstr("\"m2\",done"));
  EXPECT_THAT(readFile(batch.dir.path("out/summary.csv")), HasSubstr("\"m1\",skipped"));

  fs::remove(batch.dir.path("in/broken.ply"));
  EXPECT_EQ(batch.run("--force", &log), 0) << log;
  for (const char* name : {"m0", "m1", "m2"}) {
    EXPECT_THAT(readFile(batch.dir.path("out/summary.csv")), HasSubstr(std::string("\"") + name + "\",done"));
  }
  EXPECT_NE(mtime(batch.dir.path("out/m1.drc")), before);
}

TEST(JobsCommand, JobsOverTheBudgetFailWithoutRunning) {
  Batch batch;
  std::string log;
  EXPECT_EQ(batch.run("--memory-budget 0.001", &log), 6) << log;
  const std::string csv = readFile(batch.dir.path("out/summary.csv"));
  EXPECT_THAT(csv, HasSubstr("exceeds the memory budget"));
  EXPECT_THAT(csv, HasSubstr("param's out-of-core path needs at least"));
  EXPECT_FALSE(fs::exists(batch.dir.path("out/m0.drc")));
}

// Each job's param gets what the job holds of the budget as its own --memory-budget (its estimate
// here), so param's choice of path and the runner's schedule follow one rule.
TEST(JobsCommand, ParamGetsTheJobsShareOfTheBudget) {
  Batch batch;
  std::string log;
  fs::remove(batch.dir.path("in/broken.ply"));
  EXPECT_EQ(batch.run("--memory-budget 4G", &log), 0) << log;
  for (const char* name : {"m0", "m1", "m2"}) {
    const JsonValue report = parseJson(readFile(batch.dir.path(std::string("out/") + name + ".json")));
    EXPECT_EQ(report.textAt("param.path"), "in-memory") << name;
    EXPECT_EQ(report.numberAt("param.memoryBudget"), report.numberAt("estimatedPeakBytes")) << name;
  }
}

// The estimate counts an input's vertex properties: the same mesh with ten double properties per
// vertex is estimated 3 x 80 bytes per vertex higher (read, gathered by cleaning, written).
TEST(JobsCommand, EstimatesCountVertexProperties) {
  TempDir dir;
  fs::create_directories(dir.path("in"));
  GenerateOptions options;
  options.kind = MeshKind::Sphere;
  options.faces = 200000;
  TriangleMesh mesh = generateMesh(options).mesh;
  writeMesh(dir.path("in/plain.ply"), mesh);
  for (int k = 0; k < 10; ++k) {
    VertexProperty& p = mesh.attributes.add("q" + std::to_string(k), ScalarType::Float64, mesh.numVertices());
    for (VertexId v = 0; v < mesh.numVertices(); ++v) p.setValue(v, k + 0.5 * v);
  }
  writeMesh(dir.path("in/props.ply"), mesh);
  writeFile(dir.path("jobs.txt"), "output out\nparam --solver hat\nmesh in/*.ply\n");
  std::string log;
  EXPECT_EQ(runSeamvox("jobs " + dir.path("jobs.txt") + " --quiet --memory-budget 0.001", &log), 6) << log;
  const std::string csv = readFile(dir.path("out/summary.csv"));
  // summary.csv: "name",status,faces,seconds,peak_bytes,estimated_peak_bytes,...
  auto estimateBytes = [&](const std::string& job) {
    const std::size_t line = csv.find("\"" + job + "\",");
    EXPECT_NE(line, std::string::npos) << csv;
    std::size_t at = line;
    for (int comma = 0; comma < 5; ++comma) at = csv.find(',', at) + 1;
    return std::stod(csv.substr(at));
  };
  const double expected = 3.0 * 80.0 * mesh.numVertices();
  EXPECT_NEAR(estimateBytes("props") - estimateBytes("plain"), expected, 2.0) << csv;
}

// Near zero, and far from it as a georeferenced site is (its tiles then keep one origin).
class TiledJobs : public ::testing::TestWithParam<bool> {};

TEST_P(TiledJobs, TilesAreParameterizedAsOneSeamlessSurface) {
  TempDir dir;
  const TriangleMesh mesh = generatedSphere(3000);
  std::vector<TriangleMesh> tiles = cutIntoTiles(mesh);
  const Vec3d offset = GetParam() ? Vec3d(512000.0, 4123000.0, 100.0) : Vec3d::Zero();
  for (TriangleMesh& tile : tiles) tile.origin = offset;
  fs::create_directories(dir.path("site"));
  for (std::size_t t = 0; t < tiles.size(); ++t) writeMesh(dir.path("site/tile" + std::to_string(t) + ".ply"), tiles[t]);
  writeFile(dir.path("jobs.txt"), "tiles site site/tile*.ply : --solver hat --cells 30\n");
  std::string log;
  ASSERT_EQ(runSeamvox("jobs " + dir.path("jobs.txt") + " --quiet", &log), 0) << log;

  // Reassemble the three Draco outputs: the map must be seamless across the tile borders too.
  ReadOptions options;
  options.readUV = true;
  options.origin = offset;
  TriangleMesh whole;
  std::vector<Vec2d> wholeUV;
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    const TriangleMesh part = readMesh(dir.path("out/site/tile" + std::to_string(t) + ".drc"), options);
    EXPECT_EQ(part.numFaces(), tiles[t].numFaces());
    // Far from zero, the output keeps the tiles' coordinates (its own origin is its first vertex's).
    EXPECT_EQ(readMesh(dir.path("out/site/tile" + std::to_string(t) + ".drc")).origin.isZero(0.0), !GetParam());
    const VertexId offset = whole.numVertices();
    whole.positions.insert(whole.positions.end(), part.positions.begin(), part.positions.end());
    for (Triangle tri : part.triangles) {
      for (VertexId& v : tri) v += offset;
      whole.triangles.push_back(tri);
    }
    const std::vector<Vec2d> partUV = testing::cornerValues(part.cornerUV);
    wholeUV.insert(wholeUV.end(), partUV.begin(), partUV.end());
  }
  whole.cornerUV = WedgeMap::fromCorners(whole.triangles, wholeUV);
  CleanOptions weld;
  weld.weldVertices = true;
  const CleanResult clean = cleanMesh(std::move(whole), weld);
  EXPECT_EQ(clean.mesh.numFaces(), mesh.numFaces());
  EXPECT_EQ(clean.mesh.numVertices(), mesh.numVertices());
  const SeamQuality seams = measureSeamsFromUV(clean.mesh, clean.topology, clean.mesh.cornerUV);
  EXPECT_LE(seams.maxResidual, 1e-4);
  EXPECT_LE(seams.maxIntegerDistance, 1e-4);
  EXPECT_THAT(readFile(dir.path("out/site.json")), HasSubstr("\"kind\": \"tiles\""));
}

INSTANTIATE_TEST_SUITE_P(NearAndFar, TiledJobs, ::testing::Bool());

TEST(JobsCommand, MpiRanksShareTheJobs) {
  Batch batch;
  fs::remove(batch.dir.path("in/broken.ply"));
  std::string log;
  // Started without mpirun, --mpi either explains that MPI is missing or that it needs 2 ranks.
  EXPECT_NE(batch.run("--mpi", &log), 0);
  if (log.find("built without MPI") != std::string::npos) GTEST_SKIP() << "seamvox was built without MPI";
  EXPECT_THAT(log, HasSubstr("at least 2 ranks"));
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0) GTEST_SKIP() << "mpirun is not installed";
  // Root may run mpirun in containers only when asked to.
  const std::string mpirun =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe -np 3 ";
  const std::string command = mpirun + testing::seamvoxBinary() + " jobs " + batch.dir.path("jobs.txt") +
                              " --quiet 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[4096];
  std::string output;
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = pclose(pipe);
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_THAT(output, HasSubstr("3 jobs: 0 failed"));
  const std::string csv = readFile(batch.dir.path("out/summary.csv"));
  for (const char* name : {"m0", "m1", "m2"}) EXPECT_THAT(csv, HasSubstr(std::string("\"") + name + "\",done")) << csv;
}

TEST(JobsCommand, FolderErrorsNameThePathBeforeAnyJobRuns) {
  Batch batch;
  writeFile(batch.dir.path("a_file"), "not a folder");
  const std::string longName(300, 'x');
  const std::pair<std::string, std::string> cases[] = {
      {"output /sys/seamvox-jobs-test\n", "/sys/seamvox-jobs-test"},  // read-only, even for root
      {"output a_file\n", "a_file"},
      {"output " + longName + "\n", longName},
  };
  std::string log;
  for (const auto& [outputLine, named] : cases) {
    writeFile(batch.dir.path("bad.txt"), outputLine + "mesh in/m0.ply\n");
    EXPECT_EQ(runSeamvox("jobs " + batch.dir.path("bad.txt") + " --quiet", &log), 1) << log;
    EXPECT_THAT(log, HasSubstr(named));
    EXPECT_THAT(log, ::testing::Not(HasSubstr("internal error")));
    EXPECT_THAT(log, ::testing::Not(HasSubstr("filesystem error")));
  }
  // A summary that cannot be written fails before the jobs run.
  EXPECT_EQ(batch.run("--summary " + batch.dir.path("missing/s.csv"), &log), 1) << log;
  EXPECT_THAT(log, HasSubstr("missing/s.csv"));
  EXPECT_FALSE(fs::exists(batch.dir.path("out/m0.drc")));
  EXPECT_EQ(batch.run("--summary " + batch.dir.path("jobs.txt"), &log), 2) << log;
  // A folder is not a manifest.
  EXPECT_EQ(runSeamvox("jobs " + batch.dir.path("in") + " --quiet", &log), 2) << log;
  EXPECT_THAT(log, HasSubstr("is a folder"));
  EXPECT_TRUE(testing::temporaryFilesIn(batch.dir.dir()).empty());
}

TEST(JobsCommand, AJobsUsageErrorIsRecordedWithItsReason) {
  Batch batch;
  std::string log;
  EXPECT_EQ(batch.runManifest("output out\nmesh in/m0.ply : --solver bogus\n", &log), 6) << log;
  const std::string csv = readFile(batch.dir.path("out/summary.csv"));
  EXPECT_THAT(csv, HasSubstr("unknown solver 'bogus'"));
  EXPECT_THAT(csv, ::testing::Not(HasSubstr("--quiet")));  // the last line of the usage text
}

TEST(JobsCommand, PeakMemoryAndFlipsAreParamsOwnFigures) {
  Batch batch;
  std::string log;
  ASSERT_EQ(batch.runManifest("output out\nparam --cells 30 --grid 64\nmesh in/m1.ply\n", &log), 0) << log;
  const JsonValue report = parseJson(readFile(batch.dir.path("out/m1.json")), "m1.json");
  // param's stage meter resets the kernel's peak, so wait4 alone sees less than param's peak
  // (on this job about 98 against 158 MB).
  EXPECT_GT(report.numberAt("param.peakResidentBytes"), 0.0);
  EXPECT_GE(report.numberAt("peakResidentBytes"), report.numberAt("param.peakResidentBytes"));
  EXPECT_EQ(report.numberAt("flipped"), report.numberAt("param.quality.flipped"));
  EXPECT_EQ(report.numberAt("seamless"), report.numberAt("param.quality.seamless"));
  EXPECT_THAT(readFile(batch.dir.path("out/summary.csv")),
              HasSubstr(",done,"));
}

TEST(JobsCommand, SigtermStopsTheRunnerAndItsJobsWithoutTemporaries) {
  Batch batch;
  EXPECT_EQ(runSeamvox("gen sphere --faces 60000 -o " + batch.dir.path("in/big.ply")), 0);
  writeFile(batch.dir.path("jobs.txt"), "output out\nmesh in/big.ply\n");
  std::string log;
  // The shell starts the runner, waits for the job's first temporary, then sends SIGTERM.
  const std::string script =
      testing::seamvoxBinary() + " jobs " + batch.dir.path("jobs.txt") + " --quiet > /dev/null 2>&1 & pid=$!; "
      "for i in $(seq 300); do ls " + batch.dir.path("out") + "/*.tmp-* > /dev/null 2>&1 && break; sleep 0.1; done; "
      "sleep 0.5; kill -TERM $pid; wait $pid; echo exit=$?";
  FILE* pipe = popen(("bash -c '" + script + "'").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[256];
  while (fgets(buffer, sizeof buffer, pipe)) log += buffer;
  pclose(pipe);
  EXPECT_THAT(log, HasSubstr("exit=143"));
  EXPECT_TRUE(testing::temporaryFilesIn(batch.dir.dir()).empty());
  EXPECT_FALSE(fs::exists(batch.dir.path("out/big.drc")));
  EXPECT_FALSE(fs::exists(batch.dir.path("out/summary.csv")));
}

}  // namespace
}  // namespace seamvox
