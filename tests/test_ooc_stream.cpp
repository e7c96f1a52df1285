// `seamvox gen`, `seamvox convert` and `seamvox info` above the memory budget (chunk by chunk, io/chunked_mesh_writer):
// a tiny --memory-budget forces the streamed path, whose output must be the in-memory path's byte
// for byte (every kind; PLY binary and ascii, OBJ, OFF; UVs and vertex properties), and the bad
// situations: Draco and options that need the whole mesh refused, a truncated input, a bad index,
// a full scratch disk. `info` out of core (stream/welded_scratch) gives the in-memory figures on
// closed meshes and on holes and islands, and a simple model's on a non-manifold one; its welded,
// Morton-ordered faces are checked against cleanMesh. No output, temporary or scratch file is left behind by a failure.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include "core/mesh/clean.h"
#include "core/mesh/detail_union_find.h"
#include "core/mesh/morton.h"
#include "io/json_reader.h"
#include "stream/welded_scratch.h"

#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/chunked_mesh_writer.h"
#include "io/mesh_io.h"
#include "stream/scratch_folder.h"
#include "testing.h"

namespace seamvox {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

class OocStream : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir;
    std::string log;
    ASSERT_EQ(testing::runSeamvox("gen scan --faces 6000 -o " + path("scan.ply") + " --quiet", &log), 0) << log;
    ASSERT_EQ(testing::runSeamvox("param " + path("scan.ply") + " -o " + path("map.ply") + " --quiet", &log), 0) << log;
    ASSERT_EQ(testing::runSeamvox("convert " + path("map.ply") + " " + path("map.obj"), &log), 0) << log;
    // Vertex properties of several types (PLY keeps them all, OBJ the colors, OFF none).
    TriangleMesh mesh = readMesh(path("scan.ply"));
    const std::size_t n = mesh.numVertices();
    for (const char* name : {"red", "green", "blue"}) {
      VertexProperty& p = mesh.attributes.add(name, ScalarType::UInt8, n);
      for (std::size_t v = 0; v < n; ++v) p.bytes[v] = static_cast<std::uint8_t>(v * 7 + name[0]);
    }
    VertexProperty& q = mesh.attributes.add("quality", ScalarType::Float32, n);
    for (std::size_t v = 0; v < n; ++v) {
      const float x = 0.25f * static_cast<float>(v);
      std::memcpy(q.bytes.data() + 4 * v, &x, 4);
    }
    writeMesh(path("colored.ply"), mesh);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path(name); }

  /// Runs a command with a budget and its own scratch folder, which must end empty.
  static int run(const std::string& command, const std::string& budget, std::string* out) {
    testing::TempDir scratch;
    const int code = testing::runSeamvox(command + " --memory-budget " + budget + " --scratch " + scratch.dir(), out);
    EXPECT_TRUE(fs::is_empty(scratch.dir())) << "scratch left behind by " << command;
    return code;
  }

  /// The command writing OUT in memory and out of core: same exit code 0, same bytes, each
  /// saying which path ran.
  static void expectSameOutput(const std::string& command, const std::string& out) {
    std::string inMemory, outOfCore;
    ASSERT_EQ(run(command + " " + path("a-" + out), "64G", &inMemory), 0) << inMemory;
    ASSERT_EQ(run(command + " " + path("b-" + out), "1K", &outOfCore), 0) << outOfCore;
    EXPECT_TRUE(contains(inMemory, "path in memory")) << inMemory;
    EXPECT_TRUE(contains(outOfCore, "path out of core")) << outOfCore;
    const std::string a = testing::readFile(path("a-" + out)), b = testing::readFile(path("b-" + out));
    EXPECT_GT(a.size(), 1000u) << command;
    EXPECT_TRUE(a == b) << command << " -> " << out << ": " << a.size() << " bytes in memory, " << b.size()
                        << " out of core";
    EXPECT_TRUE(testing::temporaryFilesIn(dir_->dir()).empty());
  }

  static testing::TempDir* dir_;
};
testing::TempDir* OocStream::dir_ = nullptr;

TEST_F(OocStream, GenWritesTheSameBytesChunkByChunk) {
  for (const char* kind : {"sphere", "torus", "genus2", "scan"}) {
    for (const char* format : {"ply", "obj", "off"}) {
      expectSameOutput(std::string("gen ") + kind + " --faces 5000 --seed 3 --quiet -o", std::string(kind) + "." + format);
    }
    expectSameOutput(std::string("gen ") + kind + " --faces 5000 --ascii --quiet -o", std::string(kind) + "-ascii.ply");
  }
}

TEST_F(OocStream, GenRefusesWhatNeedsTheWholeMeshAboveTheBudget) {
  std::string log;
  EXPECT_EQ(run("gen scan --faces 5000 --noise 0.2 -o " + path("noisy.ply"), "1K", &log), 2) << log;
  EXPECT_TRUE(contains(log, "--noise") && contains(log, "--memory-budget")) << log;
  EXPECT_EQ(run("gen scan --faces 5000 -o " + path("scan.drc"), "1K", &log), 2) << log;
  EXPECT_TRUE(contains(log, "Draco") && contains(log, ".ply")) << log;
  EXPECT_FALSE(fs::exists(path("noisy.ply")));
  EXPECT_FALSE(fs::exists(path("scan.drc")));
  EXPECT_EQ(run("gen scan --faces 5000 --noise 0.2 --quiet -o " + path("noisy.ply"), "64G", &log), 0) << log;
}

TEST_F(OocStream, ConvertWritesTheSameBytesChunkByChunk) {
  // No UVs, UVs from PLY and OBJ, vertex properties; every output format, ascii PLY too.
  for (const char* input : {"scan.ply", "map.ply", "map.obj", "colored.ply"}) {
    for (const char* out : {"ply", "obj", "off"}) {
      const std::string name = std::string(input) + "." + out;
      expectSameOutput("convert " + path(input), name);
    }
    expectSameOutput("convert " + path(input) + " --ascii", std::string(input) + "-ascii.ply");
    expectSameOutput("convert " + path(input) + " --no-uv", std::string(input) + "-no-uv.obj");
  }
}

TEST_F(OocStream, ConvertRefusesDracoAboveTheBudgetNamingTheAlternatives) {
  std::string log;
  EXPECT_EQ(run("convert " + path("map.ply") + " " + path("map.drc"), "1K", &log), 2) << log;
  EXPECT_TRUE(contains(log, "Draco") && contains(log, ".ply") && contains(log, "--memory-budget")) << log;
  EXPECT_FALSE(fs::exists(path("map.drc")));
  ASSERT_EQ(run("convert " + path("map.ply") + " " + path("map.drc"), "64G", &log), 0) << log;
  EXPECT_EQ(run("convert " + path("map.drc") + " " + path("back.ply"), "1K", &log), 1) << log;
  EXPECT_TRUE(contains(log, "decoded whole")) << log;
  EXPECT_FALSE(fs::exists(path("back.ply")));
}

TEST_F(OocStream, ConvertOfATruncatedInputFailsCleanlyOutOfCore) {
  const std::string bytes = testing::readFile(path("map.ply"));
  const std::string text = testing::readFile(path("map.obj"));
  for (const double fraction : {0.001, 0.1, 0.5, 0.9, 0.9999}) {
    testing::writeFile(path("cut.ply"), bytes.substr(0, static_cast<std::size_t>(fraction * bytes.size())));
    std::string log;
    EXPECT_EQ(run("convert " + path("cut.ply") + " " + path("cut-out.ply"), "1K", &log), 1) << fraction << ": " << log;
    EXPECT_TRUE(contains(log, path("cut.ply"))) << log;
    EXPECT_FALSE(fs::exists(path("cut-out.ply"))) << fraction;
    // An OBJ cut inside a face line refers to vertices that exist: cut before the faces instead
    // (a little before the last texture coordinate: its last digits alone may leave a valid file).
    if (fraction > 0.99) continue;
    const std::size_t firstFace = text.find("\nf ");
    testing::writeFile(path("cut.obj"), text.substr(0, static_cast<std::size_t>(fraction * firstFace)) + text.substr(firstFace));
    EXPECT_EQ(run("convert " + path("cut.obj") + " " + path("cut-out.off"), "1K", &log), 1) << fraction << ": " << log;
    EXPECT_TRUE(contains(log, path("cut.obj"))) << log;
    EXPECT_FALSE(fs::exists(path("cut-out.off"))) << fraction;
  }
  EXPECT_TRUE(testing::temporaryFilesIn(dir_->dir()).empty());
}

TEST_F(OocStream, ConvertNamesABadIndexAsTheInMemoryPathDoes) {
  testing::writeFile(path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\nf 1 2 3\n");
  testing::writeFile(path("bad.off"), "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n");
  for (const char* input : {"bad.obj", "bad.off"}) {
    std::string inMemory, outOfCore;
    EXPECT_EQ(run("convert " + path(input) + " " + path("bad.ply"), "64G", &inMemory), 1);
    EXPECT_EQ(run("convert " + path(input) + " " + path("bad.ply"), "1K", &outOfCore), 1);
    EXPECT_TRUE(contains(inMemory, path(input)) && contains(inMemory, "vertex")) << inMemory;
    EXPECT_EQ(inMemory, outOfCore);
    EXPECT_FALSE(fs::exists(path("bad.ply")));
  }
}

TEST(StreamChecker, NamesTheFirstFaceWithAVertexThatNeverCame) {
  StreamChecker checker("mesh");
  MeshChunk chunk;
  chunk.triangles = {{0, 1, 2}, {0, 5, 1}, {12, 1, 2}, {0, 4, 1}};
  checker.check(chunk);
  chunk.triangles.clear();
  chunk.positions.assign(5, Vec3f::Zero());
  checker.check(chunk);
  try {
    checker.finish();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mesh: face 1 refers to vertex 5 but there are only 5 vertices");
  }
  chunk.firstVertex = 5;
  chunk.positions.assign(5, Vec3f::Zero());
  checker.check(chunk);
  try {
    checker.finish();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mesh: face 2 refers to vertex 12 but there are only 10 vertices") << e.what();
  }
}

/// info --json of a file with a budget.
JsonValue info(const std::string& file, const std::string& budget, const std::string& extra) {
  testing::TempDir scratch;
  std::string out;
  EXPECT_EQ(testing::runSeamvox("info " + file + " --json --quiet " + extra + " --memory-budget " + budget +
                                    " --scratch " + scratch.dir(),
                                &out),
            0)
      << out;
  EXPECT_TRUE(fs::is_empty(scratch.dir()));
  return parseJson(out, file);
}

/// The figures both paths give: every count of the cleaning and the cleaned components.
void expectSameInfo(const std::string& file, const std::string& extra) {
  const JsonValue a = info(file, "64G", extra), b = info(file, "1K", extra);
  EXPECT_EQ(a.textAt("path"), "in-memory");
  EXPECT_EQ(b.textAt("path"), "out-of-core");
  EXPECT_GT(b.numberAt("scratch.peakBytes"), 0.0);
  for (const char* key : {"vertices", "faces", "input.vertices", "input.faces", "components.count", "boundaryLoops",
                          "clean.weldedVertices", "clean.degenerateFaces", "clean.duplicateFaces", "clean.zeroAreaFaces",
                          "clean.unreferencedVertices", "clean.nonManifoldEdges", "clean.nonManifoldVertices",
                          "clean.flippedFaces", "clean.spikeVertices", "clean.unweldedBoundaryVertices", "boundingBox.min.0",
                          "boundingBox.min.1", "boundingBox.min.2", "boundingBox.max.0", "boundingBox.max.1",
                          "boundingBox.max.2"}) {
    EXPECT_EQ(a.numberAt(key), b.numberAt(key)) << key << " of " << file << " " << extra;
  }
  const JsonValue& x = a["components"]["largest"];
  const JsonValue& y = b["components"]["largest"];
  ASSERT_EQ(x.items.size(), y.items.size());
  for (std::size_t i = 0; i < x.items.size(); ++i) {
    for (const char* key : {"faces", "vertices", "edges", "boundaryLoops", "eulerCharacteristic", "genus"}) {
      EXPECT_EQ(x.items[i].numberAt(key), y.items[i].numberAt(key)) << key << " of component " << i << " of " << file;
    }
  }
}

TEST_F(OocStream, InfoOutOfCoreGivesTheInMemoryFiguresOnClosedAndScanMeshes) {
  std::string log;
  ASSERT_EQ(testing::runSeamvox("gen genus2 --faces 4000 --quiet -o " + path("genus2.ply"), &log), 0) << log;
  expectSameInfo(path("genus2.ply"), "");
  // Holes, islands, an unwelded seam, degenerate and duplicate faces: without and with welding.
  expectSameInfo(path("scan.ply"), "");
  expectSameInfo(path("scan.ply"), "--weld");
  expectSameInfo(path("map.obj"), "--weld");
  const JsonValue welded = info(path("scan.ply"), "1K", "--weld");
  EXPECT_GT(welded.numberAt("clean.weldedVertices"), 0.0);
  EXPECT_EQ(welded.numberAt("edges.moreThanTwoFaces"), 0.0);
}

TEST_F(OocStream, InfoOutOfCoreGivesTheInMemoryFiguresOnNonManifoldMeshes) {
  TriangleMesh mesh = readMesh(path("scan.ply"));
  // Fins on the edges of a few faces (three faces on each such edge), a face sharing only a vertex
  // with the surface, faces turned over, and a spike.
  for (const std::uint32_t f : {10u, 500u, 2000u}) {
    const Triangle t = mesh.triangles[f];
    mesh.positions.push_back(mesh.positions[t[0]] + Vec3f(0.0f, 0.0f, 0.05f));
    mesh.triangles.push_back({t[0], t[1], mesh.numVertices() - 1});
  }
  const VertexId pin = mesh.triangles[3000][0];
  mesh.positions.push_back(mesh.positions[pin] + Vec3f(0.1f, 0.0f, 0.0f));
  mesh.positions.push_back(mesh.positions[pin] + Vec3f(0.0f, 0.1f, 0.0f));
  mesh.triangles.push_back({pin, mesh.numVertices() - 2, mesh.numVertices() - 1});
  for (std::uint32_t f = 100; f < mesh.numFaces(); f += 97) std::swap(mesh.triangles[f][1], mesh.triangles[f][2]);
  mesh.positions[mesh.triangles[1234][0]] += Vec3f(0.0f, 0.0f, 5.0f);
  writeMesh(path("fins.ply"), mesh);
  expectSameInfo(path("fins.ply"), "");
  const JsonValue b = info(path("fins.ply"), "1K", "");
  EXPECT_EQ(b.numberAt("clean.nonManifoldEdges"), 3.0);
  EXPECT_GE(b.numberAt("clean.nonManifoldVertices"), 1.0);
  EXPECT_GT(b.numberAt("clean.flippedFaces"), 0.0);
  EXPECT_GT(b.numberAt("clean.spikeVertices"), 0.0);
  // The edges as the input has them, before cleaning: the three fins' edges have three faces.
  EXPECT_EQ(b.numberAt("edges.moreThanTwoFaces"), 3.0);
  EXPECT_GT(b.numberAt("edges.orientationClashes"), 0.0);
}

TEST(WeldedScratch, FacesInMortonOrderAreTheFacesCleanMeshKeepsOnWeldedVertices) {
  GenerateOptions options;
  options.kind = MeshKind::Scan;
  options.faces = 60000;  // 1.4 MB of Morton records: several runs at 1 MiB per sort
  const auto mesh = std::make_shared<const TriangleMesh>(generateMesh(options).mesh);
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = true;
  const CleanResult cleaned = cleanMesh(*mesh, cleanOptions);

  // Positions joined with the corners by sorts (the smallest sorts), and read whole (8 MiB); the
  // latter without the census too, when the Morton sort finds the duplicates.
  for (const int mode : {0, 1, 2}) {
  const bool join = mode == 0;
  SCOPED_TRACE(join ? "positions joined" : mode == 1 ? "positions in memory" : "duplicates in the Morton sort");
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const std::unique_ptr<MeshStream> stream = makeMemoryStream("scan", mesh, 5000);
  WeldStreamOptions weld;
  weld.weld = true;
  weld.memoryBytes = join ? 1 : std::uint64_t(8) << 20;
  weld.joinPositions = join;
  weld.census = mode != 2;
  const WeldStreamResult result = weldMeshStream(*stream, folder, weld);
  EXPECT_EQ(result.census.weldedVertices, cleaned.report.weldedVertices);
  EXPECT_EQ(result.census.faces, cleaned.mesh.numFaces());
  EXPECT_EQ(result.census.setsOnDisk, join) << "the weld map and sets on disk exactly with the smallest memory";
  EXPECT_EQ(result.scratch.numVertices, mesh->numVertices() - cleaned.report.weldedVertices);
  bool spilled = false;
  // Runs written and the sorted faces written: twice the records (once without a spill).
  for (const ScratchTraffic& t : folder.traffic()) spilled |= t.stage == "morton" && t.bytesWritten >= 2 * sizeof(WeldedFace) * result.census.faces;
  EXPECT_TRUE(spilled) << "the Morton sort was meant to merge runs from disk";

  // Welded positions by id: the lowest input vertex of each cluster, in input order.
  std::vector<Vec3f> positions(result.scratch.numVertices);
  {
    ScratchReader in(folder, result.scratch.positions, "test");
    for (Vec3f& p : positions) ASSERT_TRUE(in.read(&p, sizeof p));
  }
  std::set<FaceId> faces;
  std::uint64_t previous = 0, count = 0;
  WeldedFaceReader reader(folder, result.scratch);
  std::vector<WeldedFace> chunk;
  while (reader.next(chunk, 777)) {
    for (const WeldedFace& f : chunk) {
      EXPECT_GE(f.morton, previous);
      previous = f.morton;
      EXPECT_TRUE(faces.insert(f.face).second);
      ++count;
      for (int k = 0; k < 3; ++k) {
        ASSERT_LT(f.triangle[k], positions.size());
        EXPECT_EQ(positions[f.triangle[k]], mesh->positions[mesh->triangles[f.face][k]]);
      }
      // The code is the centroid's (summed in vertex id order: the same for every face on a
      // vertex set) on the box of the positions.
      std::array<VertexId, 3> ids = f.triangle;
      std::sort(ids.begin(), ids.end());
      const Vec3d a = positions[ids[0]].cast<double>(), b = positions[ids[1]].cast<double>(),
                  d = positions[ids[2]].cast<double>();
      EXPECT_EQ(f.morton, mortonCode((a + b + d) / 3.0, result.census.box));
    }
  }
  EXPECT_EQ(count, cleaned.mesh.numFaces());
  std::set<FaceId> expected(cleaned.faceOrigin.begin(), cleaned.faceOrigin.end());
  EXPECT_TRUE(faces == expected);
}
}

TEST(WeldedScratch, AFullScratchDiskIsAnErrorNamingTheFolder) {
  GenerateOptions options;
  options.faces = 20000;
  const auto mesh = std::make_shared<const TriangleMesh>(generateMesh(options).mesh);
  testing::TempDir dir;
  // Limits early in the read, midway and just short of everything the weld writes.
  std::uint64_t total = 0;
  {
    ScratchFolder folder(dir.dir());
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", mesh, 5000);
    weldMeshStream(*stream, folder, {});
    for (const ScratchTraffic& t : folder.traffic()) total += t.bytesWritten;
  }
  ASSERT_GT(total, 400000u);
  for (const std::uint64_t limit : {std::uint64_t(1000), total / 2, total - 1}) {
    ScratchFolder folder(dir.dir());
    folder.setWriteLimit(limit);
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", mesh, 5000);
    try {
      weldMeshStream(*stream, folder, {});
      FAIL() << "no disk-full error at " << limit;
    } catch (const IoError& e) {
      EXPECT_TRUE(contains(e.what(), folder.path()) && contains(e.what(), "full")) << e.what();
    }
  }
  EXPECT_TRUE(fs::is_empty(dir.dir()));
}

TEST(ChunkedMeshWriter, AFullScratchDiskIsAnErrorNamingTheFolderAndLeavesNoOutput) {
  testing::TempDir dir;
  GenerateOptions options;
  options.faces = 20000;
  const TriangleMesh mesh = generateMesh(options).mesh;
  const std::string out = dir.path("out.ply");
  try {
    ScratchFolder scratch(dir.dir());
    scratch.setWriteLimit(100000);
    AtomicFile file(out);
    ChunkedMeshWriter writer(file, {}, {}, &scratch);
    const std::shared_ptr<const TriangleMesh> shared(&mesh, [](const TriangleMesh*) {});
    const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", shared, 1000);
    MeshChunk chunk;
    while (stream->next(chunk)) writer.write(chunk);
    writer.finish();
    file.commit();
    FAIL() << "no disk-full error";
  } catch (const IoError& e) {
    EXPECT_TRUE(contains(e.what(), dir.dir())) << e.what();
    EXPECT_TRUE(contains(e.what(), "full")) << e.what();
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(fs::is_empty(dir.dir()));
}

TEST(ChunkedMeshWriter, CountsAnnouncedAndNotWrittenAreAnError) {
  testing::TempDir dir;
  ChunkedMeshLayout layout;
  layout.countsKnown = true;
  layout.vertices = 3;
  layout.faces = 2;
  AtomicFile file(dir.path("out.ply"));
  ChunkedMeshWriter writer(file, layout, {}, nullptr);
  MeshChunk chunk;
  chunk.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  chunk.triangles = {{0, 1, 2}};
  writer.write(chunk);
  EXPECT_THROW(writer.finish(), InputError);
}

}  // namespace
}  // namespace seamvox
