// `seamvox gen` and `seamvox convert` above the memory budget (chunk by chunk, io/chunked_mesh_writer):
// a tiny --memory-budget forces the streamed path, whose output must be the in-memory path's byte
// for byte (every kind; PLY binary and ascii, OBJ, OFF; UVs and vertex properties), and the bad
// situations: Draco and options that need the whole mesh refused, a truncated input, a bad index,
// a full scratch disk. No output, temporary or scratch file is left behind by a failure.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>


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
