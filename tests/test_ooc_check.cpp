// `seamvox check` out of core (stream/map_check): a tiny --memory-budget forces the streamed
// path, whose figures must equal the in-memory path's on the same file (closed maps, holes and
// islands, non-manifold with duplicate and degenerate faces, not seamless; PLY and OBJ), and
// the bad situations: sizes that are not sizes, Draco above the budget, orientation clashes,
// a full scratch disk. Nothing is left in the scratch folder's parent.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "stream/map_check.h"
#include "testing.h"

namespace seamvox {
namespace {

namespace fs = std::filesystem;

class OocCheck : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir;
    std::string log;
    for (const auto& [kind, faces] : {std::pair<std::string, int>{"sphere", 3000}, {"scan", 6000}}) {
      ASSERT_EQ(testing::runSeamvox("gen " + kind + " --faces " + std::to_string(faces) + " -o " + path(kind + ".ply") + " --quiet", &log), 0) << log;
      ASSERT_EQ(testing::runSeamvox("param " + path(kind + ".ply") + " -o " + path(kind + "-map.ply") + " --quiet", &log), 0) << log;
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path(name); }
  static TriangleMesh readMap(const std::string& name) {
    ReadOptions options;
    options.readUV = true;
    return readMesh(path(name), options);
  }

  // Runs check on a file with a budget, scratch in a fresh folder that must end empty.
  static int check(const std::string& file, const std::string& budget, const std::string& extra, std::string* out) {
    testing::TempDir scratch;
    const int code = testing::runSeamvox("check " + file + " --memory-budget " + budget + " --scratch " +
                                             scratch.dir() + " " + extra,
                                         out);
    // A budget below the program's own memory is said on stderr (merged into out): set apart.
    const std::string warning = "seamvox check: the budget";
    if (out->rfind(warning, 0) == 0) {
      EXPECT_NE(out->find("running with that minimum"), std::string::npos) << *out;
      out->erase(0, out->find('\n') + 1);
    }
    EXPECT_TRUE(fs::is_empty(scratch.dir())) << "scratch left behind by check " << file;
    return code;
  }

  // Both paths on one file: same exit code, same figures, each saying which path ran.
  static void expectSamePaths(const std::string& file, bool seamless) {
    std::string inMemory, outOfCore;
    const int a = check(file, "64G", "--json", &inMemory), b = check(file, "1K", "--json", &outOfCore);
    EXPECT_EQ(a, seamless ? 0 : 5) << inMemory;
    EXPECT_EQ(b, a) << outOfCore;
    const JsonValue x = parseJson(inMemory, "in memory"), y = parseJson(outOfCore, "out of core");
    EXPECT_EQ(x.textAt("path"), "in-memory");
    EXPECT_EQ(y.textAt("path"), "out-of-core");
    EXPECT_GT(y.numberAt("scratch.peakBytes"), 0.0);
    for (const char* key : {"faces", "seamless", "seamEdges", "seamLength", "maxSeamResidual", "maxIntegerDistance",
                            "flipped", "flippedFraction", "collapsed", "stretched"}) {
      EXPECT_EQ(x.numberAt(key), y.numberAt(key)) << key << " of " << file;
    }
    // h is a least-squares fit summed in parallel in memory: equal up to rounding.
    EXPECT_NEAR(x.numberAt("edgeLength"), y.numberAt("edgeLength"), 1e-12 * x.numberAt("edgeLength")) << file;
    EXPECT_TRUE(y.find("relativeGradientError") && y["relativeGradientError"].type == JsonValue::Type::Null);
    // Wound vertices: counted on both paths (out of core by a sort of the corners' angles).
    EXPECT_TRUE(x.find("wound") && x["wound"].type == JsonValue::Type::Number) << inMemory;
    EXPECT_TRUE(y.find("wound") && y["wound"].type == JsonValue::Type::Number) << outOfCore;
    EXPECT_EQ(x.numberAt("wound"), y.numberAt("wound")) << file;

    // The text report too, but for the line naming the path.
    auto withoutPath = [](const std::string& text) {
      std::string out;
      std::size_t begin = 0;
      while (begin < text.size()) {
        const std::size_t end = text.find('\n', begin);
        const std::string line = text.substr(begin, end == std::string::npos ? std::string::npos : end + 1 - begin);
        if (line.rfind("path ", 0) != 0) out += line;
        if (end == std::string::npos) break;
        begin = end + 1;
      }
      return out;
    };
    std::string textIn, textOut;
    EXPECT_EQ(check(file, "64G", "", &textIn), a);
    EXPECT_EQ(check(file, "1K", "", &textOut), a);
    EXPECT_NE(textIn.find("path in memory"), std::string::npos) << textIn;
    EXPECT_NE(textOut.find("path out of core"), std::string::npos) << textOut;
    EXPECT_EQ(withoutPath(textIn), withoutPath(textOut));
  }

  static testing::TempDir* dir_;
};
testing::TempDir* OocCheck::dir_ = nullptr;

TEST_F(OocCheck, ClosedMapSamePathsPlyAndObj) {
  expectSamePaths(path("sphere-map.ply"), true);
  std::string log;
  ASSERT_EQ(testing::runSeamvox("convert " + path("sphere-map.ply") + " " + path("sphere-map.obj"), &log), 0) << log;
  expectSamePaths(path("sphere-map.obj"), true);
}

TEST_F(OocCheck, HolesAndIslandsSamePaths) {
  const TriangleMesh map = readMap("scan-map.ply");
  ASSERT_TRUE(map.hasUV());
  expectSamePaths(path("scan-map.ply"), true);
}

TEST_F(OocCheck, NonManifoldWithDuplicateAndDegenerateFacesSamePaths) {
  TriangleMesh mesh = readMap("scan-map.ply");
  std::vector<Vec2d> uv = testing::cornerValues(mesh.cornerUV);
  // A fin on the edge of face 10's first two corners (three faces on that edge), a copy of
  // face 20 (dropped as a duplicate) and a face with a repeated vertex (dropped as degenerate).
  const Triangle t = mesh.triangles[10];
  mesh.positions.push_back(mesh.positions[t[0]] + Vec3f(0.0f, 0.0f, 0.05f));
  mesh.attributes = mesh.attributes.emptyCopy();
  const VertexId tip = mesh.numVertices() - 1;
  mesh.triangles.push_back({t[0], t[1], tip});
  for (const Vec2d& q : {uv[30], uv[31], Vec2d(uv[30] + Vec2d(0.3, 0.7))}) uv.push_back(q);
  mesh.triangles.push_back(mesh.triangles[20]);
  for (int j = 0; j < 3; ++j) uv.push_back(uv[60 + j]);
  mesh.triangles.push_back({t[0], t[0], t[2]});
  for (int j = 0; j < 3; ++j) uv.push_back(uv[30 + j]);
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(path("fin-map.ply"), mesh);
  std::string log;
  ASSERT_EQ(testing::runSeamvox("info " + path("fin-map.ply") + " --json", &log), 0) << log;
  const JsonValue info = parseJson(log);
  EXPECT_EQ(info.numberAt("clean.nonManifoldEdges"), 1.0) << log;
  EXPECT_EQ(info.numberAt("clean.duplicateFaces"), 1.0) << log;
  EXPECT_EQ(info.numberAt("clean.degenerateFaces"), 1.0) << log;
  check(path("fin-map.ply"), "64G", "", &log);
  expectSamePaths(path("fin-map.ply"), log.find("NOT seamless") == std::string::npos);
}

TEST_F(OocCheck, NotSeamlessSamePaths) {
  TriangleMesh mesh = readMap("scan-map.ply");
  std::vector<Vec2d> uv = testing::cornerValues(mesh.cornerUV);
  for (std::size_t f = 100; f < 140; ++f) uv[3 * f] += Vec2d(0.01 * f, -0.003);  // corners moved on one side
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(path("broken-map.ply"), mesh);
  expectSamePaths(path("broken-map.ply"), false);
}

// Faces the map stretches twentyfold: the same count on both paths.
TEST_F(OocCheck, StretchedFacesSamePaths) {
  TriangleMesh mesh = readMap("scan-map.ply");
  std::vector<Vec2d> uv = testing::cornerValues(mesh.cornerUV);
  for (std::size_t f = 200; f < 210; ++f) {
    for (int k = 1; k < 3; ++k) uv[3 * f + k] = uv[3 * f] + 20.0 * (uv[3 * f + k] - uv[3 * f]);
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(path("stretched-map.ply"), mesh);
  expectSamePaths(path("stretched-map.ply"), false);
  std::string text;
  check(path("stretched-map.ply"), "1K", "--json", &text);
  EXPECT_EQ(parseJson(text, "out of core").numberAt("stretched"), 10.0) << text;
}

// Fans whose centre the map winds around twice (power maps z^2), as their own vertex and at a
// bowtie vertex (two fans, which cleanMesh splits: the angles of both together would read 4 pi),
// and with a face missing (a boundary vertex): the same wound count on both paths, 2.
TEST_F(OocCheck, WoundVerticesAtFansAndBowtiesSamePaths) {
  TriangleMesh mesh;
  std::vector<Vec2d> uv;
  const auto addFan = [&](double power, float z, int faces, VertexId centre) {
    return testing::addPowerFan(mesh, uv, power, z, faces, centre);
  };
  addFan(2.0, 0.0f, 10, kInvalidId);                         // wound
  addFan(1.0, 1.0f, 10, addFan(1.0, 2.0f, 10, kInvalidId));  // bowtie, 2 pi each: not wound
  addFan(2.0, 3.0f, 10, addFan(1.0, 4.0f, 10, kInvalidId));  // bowtie, one fan wound
  addFan(2.4, 5.0f, 9, kInvalidId);                          // 4.3 pi on a boundary vertex: not wound
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(path("fans-map.ply"), mesh);
  std::string log;
  const int code = check(path("fans-map.ply"), "64G", "--json", &log);
  EXPECT_EQ(parseJson(log, "in memory").numberAt("wound"), 2.0) << log;
  expectSamePaths(path("fans-map.ply"), code == 0);
}

TEST_F(OocCheck, SizesThatAreNotSizesAreUsageErrors) {
  for (const char* bad : {"0", "abc", "-1G", "5X", "1.5.2G", "G", ""}) {
    std::string log;
    EXPECT_EQ(testing::runSeamvox("check " + path("sphere-map.ply") + " --memory-budget '" + bad + "'", &log), 2) << bad;
    EXPECT_NE(log.find("--memory-budget"), std::string::npos) << log;
  }
  std::string log;
  EXPECT_EQ(testing::runSeamvox("check " + path("sphere-map.ply") + " --memory-budget 1500M --json", &log), 0) << log;
  EXPECT_EQ(parseJson(log).numberAt("memoryBudget"), 1500.0 * 1048576.0);
}

TEST_F(OocCheck, EveryMeshCommandTakesTheBudgetAndScratch) {
  const std::string map = path("sphere-map.ply"), out = path("out.ply");
  const std::vector<std::string> commands = {
      "param " + map + " -o " + out, "info " + map, "convert " + map + " " + out,
      "render " + map + " -o " + path("out.png"), "subdivide " + map + " --levels 1 -o " + out,
      "gen sphere --faces 100 -o " + out};
  for (const std::string& command : commands) {
    std::string log;
    EXPECT_EQ(testing::runSeamvox(command + " --memory-budget 12Q", &log), 2) << command << "\n" << log;
    EXPECT_NE(log.find("--memory-budget must be a size"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(out)) << command;
  }
  std::string log;
  EXPECT_EQ(testing::runSeamvox("gen sphere --faces 100 -o " + out + " --memory-budget 1500M --scratch " + dir_->dir(), &log), 0) << log;
  // jobs: the same sizes, and a plain number still counts GB.
  testing::writeFile(path("jobs.txt"), "output " + path("jobs-out") + "\nmesh " + path("sphere.ply") + "\n");
  EXPECT_EQ(testing::runSeamvox("jobs " + path("jobs.txt") + " --memory-budget 12Q", &log), 2) << log;
  EXPECT_EQ(testing::runSeamvox("jobs " + path("jobs.txt") + " --memory-budget -3", &log), 2) << log;
  EXPECT_EQ(testing::runSeamvox("jobs " + path("jobs.txt") + " --quiet --memory-budget 1M", &log), 6) << log;
  EXPECT_NE(log.find("exceeds the memory budget of 1 MiB"), std::string::npos) << log;
  EXPECT_EQ(testing::runSeamvox("jobs " + path("jobs.txt") + " --quiet --memory-budget 0.001 --force", &log), 6) << log;
  EXPECT_NE(log.find("exceeds the memory budget of 1 MiB"), std::string::npos) << "0.001 GB: " << log;
}

TEST_F(OocCheck, DracoAboveTheBudgetIsRefusedWithTheAlternatives) {
  std::string log;
  ASSERT_EQ(testing::runSeamvox("convert " + path("sphere-map.ply") + " " + path("sphere-map.drc"), &log), 0) << log;
  EXPECT_EQ(testing::runSeamvox("check " + path("sphere-map.drc") + " --memory-budget 1K", &log), 1);
  EXPECT_NE(log.find("decoded whole"), std::string::npos) << log;
  EXPECT_NE(log.find("seamvox convert"), std::string::npos) << log;
  EXPECT_EQ(testing::runSeamvox("check " + path("sphere-map.drc") + " --memory-budget 64G", &log), 0) << log;
}

TEST_F(OocCheck, OrientationClashIsAClearErrorOutOfCore) {
  TriangleMesh mesh = readMap("sphere-map.ply");
  std::swap(mesh.triangles[0][1], mesh.triangles[0][2]);  // face 0 against its three neighbours
  writeMesh(path("clash-map.ply"), mesh);
  std::string log;
  EXPECT_EQ(check(path("clash-map.ply"), "1K", "", &log), 1);
  EXPECT_NE(log.find("same orientation"), std::string::npos) << log;
  EXPECT_NE(log.find("--memory-budget"), std::string::npos) << log;
}


// The library call on its own: positions held in memory (declared count) or joined by sorts
// (none declared), against measureSeamsFromUV and measureMap on the cleaned mesh.
TEST_F(OocCheck, BothPositionModesMatchTheInMemoryFigures) {
  CleanResult clean = cleanMesh(readMap("scan-map.ply"));
  const SeamQuality seams = measureSeamsFromUV(clean.mesh, clean.topology, clean.mesh.cornerUV);
  const MapQuality map = measureMap(clean.mesh, clean.mesh.cornerUV, nullptr, 0.0);
  ASSERT_GT(seams.seamEdges, 0u);
  for (const bool declared : {true, false}) {
    ReadOptions options;
    options.readUV = true;
    options.chunkTriangles = 1000;  // several chunks
    std::unique_ptr<MeshStream> stream = openMeshStream(path("scan-map.ply"), options);
    if (!declared) stream = std::make_unique<testing::UndeclaredStream>(std::move(stream));
    testing::TempDir scratch;
    MapCheckOptions check;
    check.memoryBytes = 64 << 20;
    check.scratchParent = scratch.dir();
    const MapCheckResult result = checkMapStream(*stream, check);
    EXPECT_EQ(result.positionsInMemory, declared);
    EXPECT_EQ(result.faces, clean.mesh.numFaces());
    EXPECT_EQ(result.seams.seamEdges, seams.seamEdges);
    EXPECT_EQ(result.seams.seamLength, seams.seamLength);
    EXPECT_EQ(result.seams.maxResidual, seams.maxResidual);
    EXPECT_EQ(result.seams.maxIntegerDistance, seams.maxIntegerDistance);
    EXPECT_EQ(result.seams.worstEdgeCorner, seams.worstEdgeCorner);
    EXPECT_EQ(result.map.flipped, map.flipped);
    EXPECT_EQ(result.map.collapsed, map.collapsed);
    EXPECT_NEAR(result.map.edgeLength, map.edgeLength, 1e-12 * map.edgeLength);
    EXPECT_TRUE(std::isnan(result.map.relativeGradientError));
    EXPECT_TRUE(fs::is_empty(scratch.dir()));
  }
}

TEST_F(OocCheck, FullScratchDiskNamesTheFolderAndLeavesNothing) {
  testing::TempDir scratch;
  ReadOptions options;
  options.readUV = true;
  const auto stream = openMeshStream(path("scan-map.ply"), options);
  MapCheckOptions check;
  check.memoryBytes = 16384;
  check.scratchParent = scratch.dir();
  std::string folder;
  check.onScratch = [&](ScratchFolder& s) {
    folder = s.path();
    s.setWriteLimit(100000);
  };
  try {
    checkMapStream(*stream, check);
    FAIL() << "the scratch limit was never reached";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(folder), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs about"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
}

TEST_F(OocCheck, TruncatedMapsFailCleanlyOnBothPaths) {
  const std::string whole = testing::readFile(path("sphere-map.ply"));
  const std::size_t header = whole.find("end_header\n") + 11;
  for (int i = 0; i < 8; ++i) {
    const std::size_t size = header + (whole.size() - header) * i / 8 + 7;  // inside a record
    testing::writeFile(path("cut.ply"), whole.substr(0, size));
    for (const char* budget : {"64G", "1K"}) {
      std::string log;
      EXPECT_EQ(check(path("cut.ply"), budget, "", &log), 1) << size << " bytes, budget " << budget << ": " << log;
      EXPECT_NE(log.find(path("cut.ply")), std::string::npos) << log;
    }
  }
}

// SIGTERM while the check waits for the rest of a map from a pipe: exit 143, scratch removed.
TEST_F(OocCheck, TerminatedCheckRemovesItsScratch) {
  testing::TempDir dir;
  // A map larger than the reader's buffer (UV = x, y): the first 3 MB are sent, then a signal.
  std::string log;
  ASSERT_EQ(testing::runSeamvox("gen sphere --faces 100000 -o " + dir.path("big.ply") + " --quiet", &log), 0) << log;
  TriangleMesh mesh = readMesh(dir.path("big.ply"));
  std::vector<Vec2d> uv;
  for (const Triangle& t : mesh.triangles) {
    for (const VertexId v : t) uv.emplace_back(mesh.positions[v].x(), mesh.positions[v].y());
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  writeMesh(dir.path("big-map.ply"), mesh);
  ASSERT_GT(fs::file_size(dir.path("big-map.ply")), 4000000u);
  fs::create_directory(dir.path("scratch"));
  const std::string script =
      "mkfifo " + dir.path("in.ply") + "\n" + testing::seamvoxBinary() + " check " + dir.path("in.ply") +
      " --memory-budget 1K --scratch " + dir.path("scratch") + " > " + dir.path("log") + " 2>&1 & pid=$!\n" +
      "exec 3>" + dir.path("in.ply") + "\n" + "(head -c 3000000 " + dir.path("big-map.ply") + " >&3 &)\n" +
      "for i in $(seq 200); do [ -e " + dir.path("scratch") + "/seamvox-scratch-*/0 ] && break; sleep 0.05; done\n" +
      "ls " + dir.path("scratch") + "/seamvox-scratch-*/ | wc -l > " + dir.path("files") + "\n" +
      "sleep 0.2; kill -TERM $pid; wait $pid; echo $? > " + dir.path("code") + "\n";
  testing::writeFile(dir.path("run.sh"), script);
  ASSERT_EQ(std::system(("sh " + dir.path("run.sh")).c_str()), 0);
  EXPECT_EQ(testing::readFile(dir.path("code")), "143\n") << testing::readFile(dir.path("log"));
  EXPECT_GE(std::stoi(testing::readFile(dir.path("files"))), 1) << "scratch files were written before the signal";
  EXPECT_TRUE(fs::is_empty(dir.path("scratch")));
}

TEST_F(OocCheck, ScratchDefaultsToTmpdir) {
  testing::TempDir tmp;
  const std::string command = "TMPDIR=" + tmp.dir() + " " + testing::seamvoxBinary() + " check " +
                              path("sphere-map.ply") + " --memory-budget 1K > /dev/null";
  // TMPDIR is read by the command: a folder that does not exist is named in the error.
  EXPECT_EQ(std::system(("TMPDIR=" + tmp.path("missing") + " " + testing::seamvoxBinary() + " check " +
                         path("sphere-map.ply") + " --memory-budget 1K > /dev/null 2>&1").c_str()) >> 8, 1);
  EXPECT_EQ(std::system(command.c_str()) >> 8, 0);
  EXPECT_TRUE(fs::is_empty(tmp.dir()));
}

}  // namespace
}  // namespace seamvox
