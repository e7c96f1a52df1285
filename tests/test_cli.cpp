// The `seamvox` command: gen, info, subdivide and demo run as a user would run them; outputs are
// all-or-nothing, never clobber an input, and an interrupted run leaves no temporary behind.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <functional>
#include <thread>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "io/json_reader.h"
#include "test_meshes.h"
#include "io/mesh_io.h"
#include "testing.h"

extern char** environ;

namespace seamvox {
namespace {

using testing::runSeamvox;
using testing::TempDir;

using Json = JsonValue;

/// Runs seamvox, expects exit code `code`, returns the combined output.
std::string run(const std::string& arguments, int code) {
  std::string output;
  EXPECT_EQ(runSeamvox(arguments, &output), code) << "seamvox " << arguments << "\n" << output;
  return output;
}

/// Runs `seamvox info --json` and parses stdout (--quiet keeps stderr empty).
Json infoJson(const std::string& arguments) {
  return parseJson(run("info --quiet --json " + arguments, 0));
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Cli, GenThenInfoReportsTheTopology) {
  TempDir dir;
  const std::string sphere = dir.path("sphere.ply"), genus2 = dir.path("g2.ply");
  EXPECT_TRUE(contains(run("gen sphere --faces 3000 -o " + sphere, 0), "wrote"));
  run("gen genus2 --faces 3000 --seed 5 -o " + genus2, 0);
  const Json a = infoJson(sphere);
  for (const char* key : {"file", "vertices", "faces", "input", "components", "boundaryLoops",
                          "clean", "boundingBox", "timings", "peakResidentBytes"}) {
    EXPECT_TRUE(a.has(key)) << key;
  }
  EXPECT_NEAR(a["faces"].number, 3000, 120);
  EXPECT_EQ(a["components"]["count"].number, 1);
  ASSERT_EQ(a["components"]["largest"].items.size(), 1u);
  const Json& c = a["components"]["largest"].items[0];
  for (const char* key : {"faces", "vertices", "boundaryLoops", "eulerCharacteristic", "genus"}) {
    EXPECT_TRUE(c.has(key)) << key;
  }
  EXPECT_EQ(c["genus"].number, 0);
  EXPECT_EQ(c["faces"].number, a["faces"].number);
  EXPECT_EQ(a["boundingBox"]["min"].items.size(), 3u);
  EXPECT_GT(a["peakResidentBytes"].number, 0);
  EXPECT_EQ(infoJson(genus2)["components"]["largest"].items[0]["genus"].number, 2);

  const std::string text = run("info " + genus2, 0);
  for (const char* part : {"vertices", "faces", "components", "genus", "boundary loops", "cleaning",
                           "bounding box", "peak memory"}) {
    EXPECT_TRUE(contains(text, part)) << part << "\n" << text;
  }
}

TEST(Cli, InfoOnAScanShowsWhatCleaningFixed) {
  TempDir dir;
  const std::string scan = dir.path("scan.obj"), report = dir.path("report.json");
  run("gen scan --faces 4000 -o " + scan, 0);
  const Json raw = infoJson(scan);
  EXPECT_GT(raw["components"]["count"].number, 1);
  EXPECT_GT(raw["boundaryLoops"].number, 1);
  EXPECT_GT(raw["clean"]["degenerateFaces"].number, 0);
  EXPECT_GT(raw["clean"]["duplicateFaces"].number, 0);
  EXPECT_EQ(raw["clean"]["weldedVertices"].number, 0);
  run("info --quiet --weld --report " + report + " " + scan, 0);
  const Json welded = parseJson(testing::readFile(report));
  EXPECT_GT(welded["clean"]["weldedVertices"].number, 0);
  EXPECT_EQ(welded["boundaryLoops"].number, raw["boundaryLoops"].number - 1);
}

TEST(Cli, ParamPutsAScatteredInputInSpatialOrderUnlessToldToKeepIt) {
  // 600K faces (above the reorder threshold) in a shuffled order.
  TempDir dir;
  const std::string input = dir.path("shuffled.ply");
  writeMesh(input, testing::shuffledMesh(testing::generatedMesh(MeshKind::Sphere, 600000), 5));
  std::string out;
  for (const bool keep : {false, true}) {
    SCOPED_TRACE(keep ? "--keep-order" : "default");
    const std::string report = dir.path(keep ? "keep.json" : "spatial.json");
    ASSERT_EQ(runSeamvox("param " + input + " -o " + dir.path(keep ? "keep.ply" : "spatial.ply") + " --cells 10 --field proxy --solver vox --grid 32 --no-untangle --quiet" +
                             (keep ? " --keep-order" : "") + " --report " + report,
                         &out),
              0)
        << out;
    EXPECT_EQ(out.find("put in spatial order") != std::string::npos, !keep) << out;
    const Json r = parseJson(testing::readFile(report));
    EXPECT_EQ(r.numberAt("reorderedForLocality"), keep ? 0.0 : 1.0);
    EXPECT_NE(out.find(": seamless"), std::string::npos) << out;
  }
}

// Small holes are closed (no seam translation around them) for a quad mesh, not for a plain map,
// and --close-holes says otherwise either way.
TEST(Cli, ParamClosesSmallHolesForQuads) {
  TempDir dir;
  const std::string input = dir.path("holes.ply");
  writeMesh(input, testing::withOneTriangleHoles(testing::generatedMesh(MeshKind::Sphere, 6000), 37));
  for (const auto& [flags, closed] : {std::pair<std::string, bool>{"", false}, {" --quads " + dir.path("q.obj"), true},
                                      {" --quads " + dir.path("q.obj") + " --close-holes 0", false},
                                      {" --close-holes 2", true}}) {
    SCOPED_TRACE(flags);
    const std::string report = dir.path("r.json");
    const std::string out = run("param " + input + " -o " + dir.path("o.ply") + " --cells 25 --solver hat --quiet --report " +
                                    report + flags, 0);
    EXPECT_TRUE(contains(out, ": seamless")) << out;
    const Json r = parseJson(testing::readFile(report));
    // Up to 1M faces the small holes are capped for the solve; the output has the input's faces.
    EXPECT_EQ(r.numberAt("system.holesCappedForField"), closed ? 160.0 : 0.0);
    EXPECT_EQ(r.numberAt("system.smallHoles"), 0.0);
    EXPECT_EQ(r.numberAt("faces"), parseJson(run("info --quiet --json " + input, 0)).numberAt("faces"));
  }
  run("param " + input + " -o " + dir.path("o.ply") + " --close-holes -1", 2);
}

// --spline-cells reaches the voxloc refinement: its first round is the spline round, the report
// says so and counts the vertices only it moved; the written map is seamless for check too.
TEST(Cli, ParamSplineCellsRunsTheSplineRound) {
  TempDir dir;
  const std::string input = dir.path("sphere.ply");
  writeMesh(input, testing::generatedMesh(MeshKind::Sphere, 6000));
  for (const std::string cells : {"0", "4"}) {
    SCOPED_TRACE(cells);
    const std::string report = dir.path("r.json"), output = dir.path("o.ply");
    const std::string out = run("param " + input + " -o " + output + " --cells 25 --solver voxloc --grid 16 --quiet" +
                                    " --spline-cells " + cells + " --report " + report, 0);
    EXPECT_TRUE(contains(out, ": seamless")) << out;
    const std::string check = run("check " + output, 0);
    EXPECT_TRUE(contains(check, "\nseamless\n") && !contains(check, "NOT seamless")) << check;
    const Json r = parseJson(testing::readFile(report));
    EXPECT_EQ(r.numberAt("refine.rounds.0.spline"), cells == "4" ? 1.0 : 0.0);
    EXPECT_GE(r.numberAt("refine.splineVertices"), 0.0);
  }
  run("param " + input + " -o " + dir.path("o.ply") + " --spline-cells -1", 2);
}

// A noisy scan whose first repair leaves a flipped face at two close cones on two points: the
// next pass merges them; a pass started so is kept only with fewer flips, and the written map is
// the pass with the fewest (the report lists each pass's flips after its repair). The voxel map
// as solved (--no-smoothed-evaluation): re-evaluated at the smoothed surface, this scan's first
// repair leaves no flip.
TEST(Cli, ParamRetriesAPassWhoseRepairLeavesFlipsAtCloseCones) {
  const std::string scan = testing::sharedMesh("cheburashka.off");
  if (scan.empty()) GTEST_SKIP() << testing::missingSharedMessage("cheburashka.off");
  TempDir dir;
  const std::string noisy = dir.path("noisy.ply"), output = dir.path("o.ply"), report = dir.path("r.json");
  run("subdivide " + scan + " --levels 1 --noise 0.5 -o " + noisy + " --quiet", 0);
  // Without the smoothed evaluation, the hat re-solve of the repair's leftovers and the cones'
  // own re-solves, which all remove the flips at close cones on this scan before a retry would
  // be needed.
  const std::string common =
      " --solver voxloc --merge-cones 0.25 --cells 100 --no-smoothed-evaluation --no-leftover-resolve"
      " --no-cone-resolve --quiet";
  const std::string out = run("param " + noisy + " -o " + output + common + " --report " + report, 0);
  EXPECT_TRUE(contains(out, ": seamless")) << out;
  const std::string check = run("check " + output, 0);
  EXPECT_TRUE(contains(check, "\nseamless\n") && !contains(check, "NOT seamless")) << check;
  const Json r = parseJson(testing::readFile(report));
  const Json* flips = r.find("conePassFlips");
  ASSERT_TRUE(flips);
  ASSERT_GE(flips->items.size(), 2u) << "a pass after a repair that left flips";
  EXPECT_GT(flips->items.front().number, 0.0);
  double fewest = flips->items.front().number;
  for (const Json& f : flips->items) fewest = std::min(fewest, f.number);
  EXPECT_EQ(r.numberAt("untangle.flippedAfter"), fewest);
  const double kept = r.numberAt("conePassKept");
  ASSERT_GE(kept, 1.0);
  ASSERT_LE(kept, r.numberAt("conePasses"));
  EXPECT_EQ(r.numberAt("conePassSkippedForMemory"), 0.0);
  EXPECT_EQ(r.numberAt("conePairsMergedInMap"), 0.0);

  // --merge-in-map: pairs on one point merged in the first pass's map (here all of them, three
  // cones on one point among them), seamless by param's verdict and check's.
  const std::string inMap =
      run("param " + noisy + " -o " + output + common + " --merge-in-map --report " + report, 0);
  EXPECT_TRUE(contains(inMap, ": seamless")) << inMap;
  const std::string checkInMap = run("check " + output, 0);
  EXPECT_TRUE(contains(checkInMap, "\nseamless\n") && !contains(checkInMap, "NOT seamless")) << checkInMap;
  EXPECT_GE(parseJson(testing::readFile(report)).numberAt("conePairsMergedInMap"), 4.0);

  // A budget that holds the run's estimate but not the first map besides: no such pass, and the
  // report says why.
  const std::uint64_t estimate = static_cast<std::uint64_t>(r.numberAt("estimatedBytes"));
  run("param " + noisy + " -o " + output + common + " --memory-budget " + std::to_string(estimate + 1024) +
          " --report " + report, 0);
  const Json tight = parseJson(testing::readFile(report));
  EXPECT_EQ(tight["path"].text, "in-memory");
  EXPECT_EQ(tight.numberAt("conePassSkippedForMemory"), 1.0);
  ASSERT_EQ(tight.find("conePassFlips")->items.size(), 1u);
  EXPECT_EQ(tight.numberAt("untangle.flippedAfter"), flips->items.front().number);
  const std::string tightCheck = run("check " + output, 0);
  EXPECT_TRUE(contains(tightCheck, "\nseamless\n") && !contains(tightCheck, "NOT seamless")) << tightCheck;
}

// param --quads extracts from the map as solved, its small holes still capped: also the pinched
// ones (two missing faces touching at one vertex, split apart by cleaning), which no fill of the
// written map closes, so a sphere with such holes gives a closed quad mesh.
TEST(Cli, ParamQuadsOfASphereWithPinchedHolesIsClosed) {
  TempDir dir;
  TriangleMesh mesh = testing::generatedMesh(MeshKind::Sphere, 6000);
  std::vector<std::vector<FaceId>> facesAt(mesh.numVertices());
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    for (const VertexId v : mesh.triangles[f]) facesAt[v].push_back(f);
  }
  std::vector<std::uint8_t> used(mesh.numVertices(), 0), drop(mesh.numFaces(), 0);
  int pinched = 0;
  for (VertexId v = 0; v < mesh.numVertices() && pinched < 20; v += 97) {
    const auto shared = [&](FaceId a, FaceId b) {
      int n = 0;
      for (const VertexId x : mesh.triangles[a]) n += std::count(mesh.triangles[b].begin(), mesh.triangles[b].end(), x);
      return n;
    };
    bool clear = true;
    for (const FaceId f : facesAt[v]) {
      for (const VertexId x : mesh.triangles[f]) clear = clear && !used[x];
    }
    if (!clear) continue;
    for (std::size_t i = 0; i < facesAt[v].size(); ++i) {
      for (std::size_t j = i + 1; j < facesAt[v].size(); ++j) {
        const FaceId a = facesAt[v][i], b = facesAt[v][j];
        if (shared(a, b) != 1 || drop[a] || drop[b] || pinched >= 20) continue;
        drop[a] = drop[b] = 1;
        ++pinched;
        for (const FaceId f : facesAt[v]) {
          for (const VertexId x : mesh.triangles[f]) used[x] = 1;
        }
        i = j = facesAt[v].size();
      }
    }
  }
  ASSERT_EQ(pinched, 20);
  TriangleMesh holed;
  holed.positions = mesh.positions;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (!drop[f]) holed.triangles.push_back(mesh.triangles[f]);
  }
  const std::string input = dir.path("pinched.ply");
  writeMesh(input, holed);
  const std::string out = run("param " + input + " -o " + dir.path("o.ply") + " --cells 25 --quads " + dir.path("q.obj") +
                                  " --report " + dir.path("r.json"),
                              0);
  EXPECT_TRUE(contains(out, ", 0 boundary loops")) << out;
  EXPECT_TRUE(contains(out, "validation: valid")) << out;
  EXPECT_EQ(parseJson(testing::readFile(dir.path("r.json"))).numberAt("system.holesCappedForField"), 20.0);
}

TEST(Cli, GenIsByteIdenticalForTheSameSeed) {
  TempDir dir;
  run("gen scan --faces 30000 --seed 9 -o " + dir.path("a.ply"), 0);
  run("gen scan --faces 30000 --seed 9 -o " + dir.path("b.ply"), 0);
  run("gen scan --faces 3000 --seed 10 -o " + dir.path("c.ply"), 0);
  run("gen scan --faces 30000 --seed 9 --threads 1 -o " + dir.path("d.ply"), 0);
  const std::string a = testing::readFile(dir.path("a.ply"));
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, testing::readFile(dir.path("b.ply")));
  EXPECT_NE(a, testing::readFile(dir.path("c.ply")));
  EXPECT_EQ(a, testing::readFile(dir.path("d.ply"))) << "the thread count must not matter";
}

// --noise-scale local: a noisy mesh other than the mean scale's, said on the noise line; any other
// scale is refused naming the two.
TEST(Cli, GenNoiseInEachVertexsOwnEdgeLengths) {
  TempDir dir;
  const std::string mean = run("gen scan --faces 3000 --noise 0.3 -o " + dir.path("m.ply"), 0);
  const std::string local = run("gen scan --faces 3000 --noise 0.3 --noise-scale local -o " + dir.path("l.ply"), 0);
  EXPECT_TRUE(contains(mean, "scan noise 0.3 mean edge lengths")) << mean;
  EXPECT_TRUE(contains(local, "scan noise 0.3 local edge lengths")) << local;
  EXPECT_NE(testing::readFile(dir.path("m.ply")), testing::readFile(dir.path("l.ply")));
  const std::string bad = run("gen scan --faces 3000 --noise 0.3 --noise-scale median -o " + dir.path("b.ply"), 2);
  EXPECT_TRUE(contains(bad, "--noise-scale must be mean") && contains(bad, "median")) << bad;
  EXPECT_FALSE(std::filesystem::exists(dir.path("b.ply")));
}

TEST(Cli, SubdivideMultipliesFacesAndCarriesTheField) {
  TempDir dir;
  const std::string torus = dir.path("torus.off"), fine = dir.path("fine.ply");
  const std::string field = dir.path("torus.field"), fineField = dir.path("fine.field");
  run("gen torus --faces 1000 -o " + torus, 0);
  const Json coarse = infoJson(torus);
  const int faces = static_cast<int>(coarse["faces"].number);
  {
    std::ofstream out(field);
    for (int f = 0; f < faces; ++f) out << f << " 1 0\n";
  }
  run("subdivide " + torus + " --levels 2 -o " + fine + " --field " + field + " --field-out " + fineField, 0);
  const Json after = infoJson(fine);
  EXPECT_EQ(after["faces"].number, 16.0 * faces);
  EXPECT_EQ(after["components"]["largest"].items[0]["genus"].number, 1);
  // Each coarse vector appears on exactly 16 fine faces.
  std::ifstream in(fineField);
  std::map<long, int> count;
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double x, y, z;
    if (!(ss >> x >> y >> z) || !ss.eof()) continue;  // the "1 F" header has two numbers
    ++lines;
    ++count[std::lround(x)];
  }
  EXPECT_EQ(lines, 16 * faces);
  EXPECT_EQ(count.size(), static_cast<std::size_t>(faces));
  for (const auto& [x, n] : count) EXPECT_EQ(n, 16) << x;
}

// Above --memory-budget the subdivision is written chunk by chunk: the same faces in the same order
// with the same corner positions and colours (the vertices numbered otherwise), the same field
// file byte for byte, in every format but Draco; noise and Draco are refused naming the budget.
TEST(Cli, SubdivideAboveTheBudgetWritesTheSameFacesChunkByChunk) {
  TempDir dir;
  const std::string scan = dir.path("scan.ply"), colored = dir.path("colored.ply"), field = dir.path("scan.field");
  run("gen scan --faces 1000 -o " + scan, 0);  // holes, islands, an unwelded seam, duplicates
  TriangleMesh mesh = readMesh(scan);
  VertexProperty& red = mesh.attributes.add("red", ScalarType::UInt8, mesh.numVertices());
  for (VertexId v = 0; v < mesh.numVertices(); ++v) red.setValue(v, (v * 53) % 256);
  writeMesh(colored, mesh);
  {
    std::ofstream out(field);
    for (FaceId f = 0; f < mesh.numFaces(); ++f) out << f << " 1 0\n";
  }
  for (const std::string ext : {"ply", "obj", "off"}) {
    SCOPED_TRACE(ext);
    const std::string a = dir.path("memory." + ext), b = dir.path("streamed." + ext);
    const std::string fieldA = dir.path("memory-" + ext + ".field"), fieldB = dir.path("streamed-" + ext + ".field");
    // 4 levels: the output's estimate (48 MiB + 36 B per face) is above 54M, the input's is not.
    const std::string common = "subdivide " + colored + " --levels 4 --field " + field;
    const std::string outA = run(common + " -o " + a + " --field-out " + fieldA, 0);
    EXPECT_TRUE(contains(outA, "path in memory")) << outA;
    const std::string outB = run(common + " -o " + b + " --field-out " + fieldB + " --memory-budget 54M", 0);
    EXPECT_TRUE(contains(outB, "path out of core")) << outB;
    EXPECT_TRUE(contains(outB, "written chunk by chunk")) << outB;
    EXPECT_TRUE(testing::readFile(fieldA) == testing::readFile(fieldB));
    const TriangleMesh x = readMesh(a), y = readMesh(b);
    ASSERT_EQ(x.numFaces(), y.numFaces());
    ASSERT_EQ(x.numVertices(), y.numVertices());
    const VertexProperty* rx = x.attributes.find("red");
    const VertexProperty* ry = y.attributes.find("red");
    ASSERT_EQ(rx != nullptr, ext == "ply");
    ASSERT_EQ(ry != nullptr, ext == "ply");
    for (FaceId f = 0; f < x.numFaces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(x.positions[x.triangles[f][k]], y.positions[y.triangles[f][k]]) << f;
        if (rx) ASSERT_EQ(rx->value(x.triangles[f][k]), ry->value(y.triangles[f][k])) << f;
      }
    }
  }
  std::string out = run("subdivide " + scan + " --levels 4 -o " + dir.path("n.ply") + " --noise 0.2 --memory-budget 54M", 2);
  EXPECT_TRUE(contains(out, "--memory-budget")) << out;
  out = run("subdivide " + scan + " --levels 4 -o " + dir.path("n.drc") + " --memory-budget 54M", 2);
  EXPECT_TRUE(contains(out, "Draco")) << out;
  out = run("subdivide " + scan + " --levels 4 -o " + dir.path("n.ply") + " --memory-budget 49M", 1);
  EXPECT_TRUE(contains(out, scan)) << out;
  EXPECT_TRUE(contains(out, "reads its input whole")) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path("n.ply")));
  EXPECT_FALSE(std::filesystem::exists(dir.path("n.drc")));
}

TEST(Cli, BadInputGivesAClearMessageAndNonZeroExit) {
  TempDir dir;
  const std::string missing = dir.path("missing.ply");
  std::string out = run("info " + missing, 1);
  EXPECT_TRUE(contains(out, missing)) << out;

  const std::string corrupt = dir.path("corrupt.ply");
  testing::writeFile(corrupt, "ply\nformat binary_little_endian 1.0\nelement vertex 10\n"
                              "property float x\nend_header\n\x01\x02");
  out = run("info " + corrupt, 1);
  EXPECT_TRUE(contains(out, corrupt)) << out;

  const std::string mesh = dir.path("m.ply");
  run("gen sphere --faces 200 -o " + mesh, 0);
  out = run("info " + mesh + " --bogus 3", 2);
  EXPECT_TRUE(contains(out, "unknown option --bogus")) << out;
  out = run("gen cube --faces 100 -o " + mesh, 2);
  EXPECT_TRUE(contains(out, "unknown mesh kind 'cube'")) << out;
  out = run("gen sphere --faces 100", 2);
  EXPECT_TRUE(contains(out, "-o")) << out;
  out = run("gen genus2 --faces 10 -o " + mesh, 1);
  EXPECT_TRUE(contains(out, "at least")) << out;
  out = run("subdivide " + mesh + " --levels 1 -o " + dir.path("f.ply") + " --field x.field", 2);
  EXPECT_TRUE(contains(out, "--field-out")) << out;
  const std::string shortField = dir.path("short.field");
  testing::writeFile(shortField, "1 0 0\n");
  out = run("subdivide " + mesh + " -o " + dir.path("f.ply") + " --field " + shortField +
                " --field-out " + dir.path("g.field"), 1);
  EXPECT_TRUE(contains(out, shortField)) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path("f.ply")));
}

TEST(Cli, OptionValuesOutsideTheirRangeAreUsageErrorsSayingIt) {
  TempDir dir;
  const std::string mesh = dir.path("m.ply"), out = dir.path("out.obj");
  run("gen sphere --faces 200 -o " + mesh, 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"check " + mesh + " --edge-length -1", "--edge-length must be a positive finite number, got '-1'"},
      {"check " + mesh + " --edge-length nan", "--edge-length must be a positive finite number"},
      {"check " + mesh + " --edge-length 0", "--edge-length must be a positive finite number"},
      {"check " + mesh + " --tolerance inf", "--tolerance must be a finite number >= 0"},
      {"info " + mesh + " --weld --weld-tolerance nan", "--weld-tolerance must be a finite number >= 0"},
      {"info " + mesh + " --threads 0", "--threads must be a whole number from 1 to 4096, got '0'"},
      {"param " + mesh + " -o " + out + " --cells 1e308", "--cells must be a number above 0 and at most 1e+06, got '1e308'"},
      {"param " + mesh + " -o " + out + " --cells nan", "--cells must be a number above 0 and at most 1e+06"},
      {"param " + mesh + " -o " + out + " --cells 5 --edge-length 1", "not both"},
      {"param " + mesh + " -o " + out + " --edge-length inf", "--edge-length must be a positive finite number"},
      {"param " + mesh + " -o " + out + " --merge-cones nan", "--merge-cones must be a number from 0 to 10"},
      {"param " + mesh + " -o " + out + " --grid 2048", "--grid must be a whole number from 4 to 1024"},
      {"render " + mesh + " -o " + dir.path("p.png") + " --checker -inf", "--checker must be a positive finite number"},
  };
  for (const auto& [arguments, message] : cases) {
    const std::string output = run(arguments, 2);
    EXPECT_TRUE(contains(output, message)) << arguments << "\n" << output;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(Cli, ErrorsAfterReadingNameTheFile) {
  TempDir dir;
  // Every face repeats a vertex: cleaning leaves nothing.
  const std::string degenerate = dir.path("degenerate.obj");
  testing::writeFile(degenerate, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 2 3 3\n");
  for (const std::string& command : {std::string("info "), "param -o " + dir.path("o.obj") + " ",
                                     "subdivide -o " + dir.path("o.ply") + " ",
                                     "field -o " + dir.path("o.field") + " "}) {
    const std::string output = run(command + degenerate, 1);
    EXPECT_TRUE(contains(output, degenerate + ": the mesh has no valid faces")) << output;
  }
}

TEST(Cli, DracoThroughAPipeIsRead) {
  TempDir dir;
  const std::string mesh = dir.path("m.drc"), link = dir.path("stdin.drc");
  run("gen sphere --faces 500 -o " + mesh, 0);
  std::filesystem::create_symlink("/dev/stdin", link);
  const std::string command = "cat " + mesh + " | " + testing::seamvoxBinary() + " info --json --quiet " + link + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) text.append(buffer, n);
  EXPECT_EQ(pclose(pipe), 0) << text;
  EXPECT_EQ(parseJson(text)["faces"].number, infoJson(mesh)["faces"].number) << text;
}

TEST(Cli, DemoRunsTheMainJobOnAGeneratedScan) {
  TempDir dir;
  const std::string out = run("demo --quiet --faces 5000 --keep " + dir.path("demo"), 0);
  for (const char* part : {"generated", "components", "genus", "boundary loops", "cleaning"}) {
    EXPECT_TRUE(contains(out, part)) << part << "\n" << out;
  }
  EXPECT_TRUE(contains(out, "welded vertices ")) << out;
  EXPECT_FALSE(contains(out, "welded vertices 0,")) << "the demo welds the scan's seam\n" << out;
  EXPECT_TRUE(std::filesystem::exists(dir.path("demo/scan.ply")));
  EXPECT_TRUE(contains(run("demo --faces 10", 2), "--faces"));
}

// OpenBLAS falls back to SSE3 kernels on a processor newer than it knows (Debian 12's on an
// Emerald Rapids Xeon): the command then runs itself again asking for kernels that fit, and a
// kernel the user named stays.
TEST(Cli, ParamFactorsWithBlasKernelsThatFitTheProcessor) {
  TempDir dir;
  const std::string mesh = dir.path("s.ply"), report = dir.path("r.json");
  run("gen sphere --faces 2000 -o " + mesh + " --quiet", 0);
  const auto blasCore = [&] {
    run("param " + mesh + " -o " + dir.path("s_uv.obj") + " --report " + report + " --quiet", 0);
    const Json r = parseJson(testing::readFile(report));
    return r.has("blasCore") ? r.textAt("blasCore") : std::string();
  };
  const char* chosen = std::getenv("OPENBLAS_CORETYPE");
  const std::string userChoice = chosen ? chosen : "";
  unsetenv("OPENBLAS_CORETYPE");
  const std::string core = blasCore();
  setenv("OPENBLAS_CORETYPE", "Prescott", 1);
  const std::string named = blasCore();
  if (userChoice.empty()) unsetenv("OPENBLAS_CORETYPE");
  else setenv("OPENBLAS_CORETYPE", userChoice.c_str(), 1);
  if (core.empty()) GTEST_SKIP() << "the BLAS is not OpenBLAS: no kernels to choose";
  EXPECT_EQ(named, "Prescott");
  std::string lower = core;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    for (const char* generic : {"prescott", "core2", "penryn", "nehalem", "atom"}) EXPECT_NE(lower, generic) << core;
  }
}

/// Unsets the named environment variables for its lifetime and restores what they held after.
class UnsetEnvironment {
 public:
  UnsetEnvironment(std::initializer_list<const char*> names) {
    for (const char* name : names) {
      const char* value = std::getenv(name);
      saved_.emplace_back(name, value ? std::optional<std::string>(value) : std::nullopt);
      unsetenv(name);
    }
  }
  ~UnsetEnvironment() {
    for (const auto& [name, value] : saved_) {
      if (value) setenv(name.c_str(), value->c_str(), 1);
      else unsetenv(name.c_str());
    }
  }

 private:
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

// CHOLMOD opens OpenMP teams of 4 threads per large supernode whatever OMP_NUM_THREADS says: the
// command runs itself again with OMP_THREAD_LIMIT=1 unless the user chose a limit or a count, and
// under that limit runs CHOLMOD's one-thread regions inline (tools/openmp_regions.cpp; not with
// SEAMVOX_OPENMP_INLINE=0). The map depends on neither (OMP_NUM_THREADS, which OpenBLAS reads
// too, may change it).
TEST(Cli, ParamLimitsOpenMPTeamsAndRunsOneThreadRegionsInline) {
  TempDir dir;
  const std::string mesh = dir.path("s.ply"), report = dir.path("r.json");
  run("gen genus2 --faces 30000 --seed 3 -o " + mesh + " --quiet", 0);
  struct Run {
    std::string limit;
    bool inlined = false;
    std::string map;
  };
  const auto runParam = [&](const std::string& tag) {
    const std::string map = dir.path("s_" + tag + ".ply");
    run("param " + mesh + " -o " + map + " --solver hat --report " + report + " --quiet", 0);
    const Json r = parseJson(testing::readFile(report));
    return Run{r.textAt("openmpThreadLimit"), r.numberAt("openmpRegionsInline") == 1.0, testing::readFile(map)};
  };
  const UnsetEnvironment unset{"OMP_THREAD_LIMIT", "OMP_NUM_THREADS", "SEAMVOX_OPENMP_INLINE"};
  const Run chosen = runParam("default");
  setenv("SEAMVOX_OPENMP_INLINE", "0", 1);
  const Run teams = runParam("teams");
  unsetenv("SEAMVOX_OPENMP_INLINE");
  setenv("OMP_THREAD_LIMIT", "3", 1);
  const Run user = runParam("user");
  unsetenv("OMP_THREAD_LIMIT");
  setenv("OMP_NUM_THREADS", "2", 1);
  const Run count = runParam("count");
  unsetenv("OMP_NUM_THREADS");
  EXPECT_EQ(chosen.limit, "1");
  EXPECT_TRUE(chosen.inlined);
  EXPECT_EQ(teams.limit, "1");
  EXPECT_FALSE(teams.inlined);
  EXPECT_EQ(user.limit, "3");
  EXPECT_FALSE(user.inlined);
  EXPECT_EQ(count.limit, "unset");
  EXPECT_FALSE(count.inlined);
  EXPECT_FALSE(chosen.map.empty());
  EXPECT_EQ(chosen.map, teams.map);
  EXPECT_EQ(chosen.map, user.map);
}

TEST(Cli, OutputsOfOneRunAreAllOrNothing) {
  TempDir dir;
  const std::string mesh = dir.path("m.ply"), out = dir.path("m_uv.obj");
  run("gen sphere --faces 1500 -o " + mesh, 0);
  // The report cannot be written: the map is not written either, and an older map stays.
  const std::string missing = dir.path("missing/r.json");
  std::string log = run("param --quiet --solver hat --cells 20 " + mesh + " -o " + out + " --report " + missing, 1);
  EXPECT_TRUE(contains(log, missing)) << log;
  EXPECT_FALSE(std::filesystem::exists(out));
  testing::writeFile(out, "older map");
  run("param --quiet --solver hat --cells 20 " + mesh + " -o " + out + " --render " + dir.path("no/p.png"), 1);
  EXPECT_EQ(testing::readFile(out), "older map");
  log = run("field --quiet " + mesh + " -o " + dir.path("f.field") + " --cones " + dir.path("c.obj") +
                " --seams " + dir.path("missing/s.obj"), 1);
  EXPECT_TRUE(contains(log, "missing/s.obj")) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.path("f.field")));
  EXPECT_FALSE(std::filesystem::exists(dir.path("c.obj")));
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  // All of them when everything can be written.
  run("param --quiet --solver hat --cells 20 " + mesh + " -o " + out + " --report " + dir.path("r.json") +
          " --render " + dir.path("p.png"), 0);
  EXPECT_NE(testing::readFile(out), "older map");
  const JsonValue report = parseJson(testing::readFile(dir.path("r.json")));
  EXPECT_GT(report["peakResidentBytes"].number, 0);
  EXPECT_TRUE(report["writtenBesideMetrics"].flag) << "the map is written while its figures are measured";
  EXPECT_TRUE(testing::runSeamvox("check --quiet " + out, &log) == 0) << log;
  EXPECT_EQ(testing::readFile(dir.path("p.png")).substr(1, 3), "PNG");
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
}

TEST(Cli, AnOutputThatWouldOverwriteAnInputOrAnotherOutputIsAUsageError) {
  TempDir dir;
  const std::string mesh = dir.path("m.obj"), uv = dir.path("uv.obj");
  run("gen sphere --faces 800 -o " + mesh, 0);
  run("param --quiet --solver hat --cells 10 " + mesh + " -o " + uv, 0);
  const std::string meshBytes = testing::readFile(mesh), uvBytes = testing::readFile(uv);
  std::filesystem::create_directory(dir.path("sub"));
  std::filesystem::create_symlink(mesh, dir.path("link.obj"));
  const std::string sameAsMesh[] = {mesh, dir.path("sub/../m.obj"), dir.path("link.obj")};
  for (const std::string& target : sameAsMesh) {
    std::string log = run("param --quiet " + mesh + " -o " + target, 2);
    EXPECT_TRUE(contains(log, "overwrite the input")) << log;
    run("field --quiet " + mesh + " -o " + target, 2);
    run("convert " + mesh + " " + target, 2);
    run("info " + mesh + " --report " + target, 2);
  }
  std::string log = run("param --quiet " + mesh + " -o " + dir.path("a.obj") + " --report " + dir.path("a.obj"), 2);
  EXPECT_TRUE(contains(log, "same file")) << log;
  run("param --quiet " + mesh + " -o " + dir.path("a.obj") + " --report " + dir.path("sub/../a.obj"), 2);
  run("field --quiet " + mesh + " -o " + dir.path("f") + " --cones " + dir.path("s.obj") + " --seams " +
          dir.path("s.obj"), 2);
  run("subdivide " + mesh + " -o " + dir.path("f.obj") + " --field " + dir.path("x.field") +
          " --field-out " + dir.path("x.field"), 2);
  log = run("render " + uv + " -o " + uv, 2);
  EXPECT_TRUE(contains(log, ".png")) << log;
  run("render " + uv + " -o " + dir.path("p.jpg"), 2);
  run("param --quiet " + mesh + " -o " + dir.path("b.obj") + " --render " + dir.path("p.jpg"), 2);
  EXPECT_EQ(testing::readFile(mesh), meshBytes);
  EXPECT_EQ(testing::readFile(uv), uvBytes);
  for (const char* name : {"a.obj", "b.obj", "f", "s.obj", "f.obj", "p.jpg"}) {
    EXPECT_FALSE(std::filesystem::exists(dir.path(name))) << name;
  }
}

/// Starts seamvox with these arguments (output discarded), sends `signal` once `ready` holds
/// (by default: its first temporary output exists in dir) and it has run `after` more, and
/// returns its exit code. A point reached by the run itself, not a time, keeps this independent
/// of the machine's speed.
int interruptedExitCode(const std::vector<std::string>& arguments, const TempDir& dir, int signal,
                        std::chrono::milliseconds after, std::function<bool()> ready = {}) {
  if (!ready) ready = [&dir] { return !testing::temporaryFilesIn(dir.dir()).empty(); };
  std::vector<std::string> argv = {testing::seamvoxBinary()};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  std::vector<char*> pointers;
  for (std::string& a : argv) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, pointers.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!ready() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(after);
  int status = 0;
  EXPECT_EQ(waitpid(pid, &status, WNOHANG), 0) << "the run ended before the signal: use a larger mesh";
  kill(pid, signal);
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

TEST(Cli, SigtermAndSigintRemoveUnfinishedOutputs) {
  TempDir dir;
  const std::string mesh = dir.path("big.ply");
  run("gen sphere --faces 200000 -o " + mesh, 0);  // about 3 s of param, 1.5 s of field: the signals land mid-run
  const std::string out = dir.path("big_uv.obj"), report = dir.path("big.json"), picture = dir.path("big.png");
  const std::vector<std::string> param = {"param", mesh, "-o", out, "--report", report, "--render", picture, "--quiet"};
  EXPECT_EQ(interruptedExitCode(param, dir, SIGTERM, std::chrono::milliseconds(500)), 143);
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  for (const std::string& path : {out, report, picture}) EXPECT_FALSE(std::filesystem::exists(path)) << path;
  EXPECT_EQ(interruptedExitCode(param, dir, SIGINT, std::chrono::milliseconds(200)), 130);
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  const std::vector<std::string> field = {"field", mesh, "-o", dir.path("f.field"), "--seams", dir.path("s.obj"), "--quiet"};
  EXPECT_EQ(interruptedExitCode(field, dir, SIGTERM, std::chrono::milliseconds(100)), 143);
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  EXPECT_FALSE(std::filesystem::exists(dir.path("f.field")));
}

/// Every file and folder under dir (recursively), relative to it, sorted.
std::vector<std::string> listTree(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    out.push_back(std::filesystem::relative(entry.path(), dir).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Cli, DemoOutputsAreAllOrNothing) {
  TempDir dir;
  const std::string work = dir.path("demo");
  // Success: the four outputs and nothing else (no staging folder, no temporaries).
  run("demo --quiet --faces 5000 --keep " + work, 0);
  EXPECT_EQ(listTree(work), (std::vector<std::string>{"scan.ply", "scan_uv.json", "scan_uv.ply", "scan_uv.png"}));

  // A target that cannot be written (a folder): refused before any work, nothing else created.
  const std::string blocked = dir.path("blocked");
  std::filesystem::create_directories(blocked + "/scan_uv.png");
  const std::string message = run("demo --quiet --faces 5000 --keep " + blocked, 1);
  EXPECT_TRUE(contains(message, "scan_uv.png")) << message;
  EXPECT_EQ(listTree(blocked), std::vector<std::string>{"scan_uv.png"});

  // Interrupted at several points: the earlier outputs stay as they were, nothing is added.
  const std::vector<std::string> names = {"scan.ply", "scan_uv.json", "scan_uv.ply", "scan_uv.png"};
  std::vector<std::string> before;
  for (const std::string& name : names) before.push_back(testing::readFile(work + "/" + name));
  // Early: 50 ms into the first step. Late: once param's map and report are staged (check and
  // render still to run), so some outputs are complete but not yet moved into place.
  const std::vector<std::string> demo = {"demo", "--quiet", "--faces", "100000", "--keep", work};
  const auto mapStaged = [&work] {
    std::error_code error;  // the staging folder may vanish while it is listed
    for (std::filesystem::recursive_directory_iterator it(work, error), end; !error && it != end; it.increment(error)) {
      if (it->path().filename() == "scan_uv.json" && it->path().parent_path() != work) return true;
    }
    return false;
  };
  const std::vector<std::pair<std::string, std::function<bool()>>> points = {{"early", {}}, {"late", mapStaged}};
  for (const auto& [point, ready] : points) {
    const auto after = std::chrono::milliseconds(point == "early" ? 50 : 0);
    EXPECT_EQ(interruptedExitCode(demo, dir, SIGTERM, after, ready), 143) << point;
    EXPECT_EQ(listTree(work), names) << point;
    for (std::size_t i = 0; i < names.size(); ++i) {
      EXPECT_TRUE(testing::readFile(work + "/" + names[i]) == before[i]) << names[i] << " changed by a run stopped " << point;
    }
  }
  // A folder the demo created is removed again.
  const std::vector<std::string> fresh = {"demo", "--quiet", "--faces", "100000", "--keep", dir.path("fresh")};
  EXPECT_EQ(interruptedExitCode(fresh, dir, SIGTERM, std::chrono::milliseconds(300)), 143);
  EXPECT_FALSE(std::filesystem::exists(dir.path("fresh")));
}

}  // namespace
}  // namespace seamvox
