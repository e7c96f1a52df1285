// Per-vertex properties (colors, normals, scalars) follow their vertices through reading,
// cleaning (welds, removed vertices, non-manifold splits), subdivision, the pipeline and every
// writer: each test gives vertices values that are a function of their position, f(p), and checks
// that every output vertex still holds f(its position); what a format cannot hold is named in a
// warning.
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include "core/mesh/clean.h"
#include "core/mesh/subdivide.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing::TempDir;

std::uint32_t hashOf(const Vec3f& p) {
  std::uint32_t bits[3];
  std::memcpy(bits, p.data(), sizeof bits);
  return bits[0] * 73856093u ^ bits[1] * 19349663u ^ bits[2] * 83492791u ^ (bits[0] >> 13);
}

/// The value every property below must hold at a vertex at position p.
double expectedValue(const std::string& name, const Vec3f& p) {
  const std::uint32_t h = hashOf(p);
  if (name == "red") return h & 255u;
  if (name == "green") return (h >> 8) & 255u;
  if (name == "blue") return (h >> 16) & 255u;
  if (name == "nx") return static_cast<float>(p.x() * 0.5f);
  if (name == "ny") return static_cast<float>(p.y() - 1.0f);
  if (name == "nz") return static_cast<float>(-p.z());
  if (name == "quality") return 3.0 * p.x() + p.y() * 1e-3 + 1e-9;
  if (name == "label") return static_cast<std::int32_t>(h >> 4) - (1 << 26);
  ADD_FAILURE() << "unexpected property " << name;
  return 0.0;
}

/// uchar red green blue, float nx ny nz, double quality, int label: f(position).
void addPositionAttributes(TriangleMesh& mesh) {
  const std::pair<const char*, ScalarType> kProperties[] = {
      {"red", ScalarType::UInt8},    {"green", ScalarType::UInt8},    {"blue", ScalarType::UInt8},
      {"nx", ScalarType::Float32},   {"ny", ScalarType::Float32},     {"nz", ScalarType::Float32},
      {"quality", ScalarType::Float64}, {"label", ScalarType::Int32}};
  for (const auto& [name, type] : kProperties) {
    VertexProperty& p = mesh.attributes.add(name, type, mesh.numVertices());
    for (VertexId v = 0; v < mesh.numVertices(); ++v) p.setValue(v, expectedValue(name, mesh.positions[v]));
  }
}

/// Every vertex holds f(its position) in every property; `names` must all be present.
void expectAttributesFollowPositions(const TriangleMesh& mesh, const std::vector<std::string>& names,
                                     const std::string& what) {
  ASSERT_NO_THROW(mesh.attributes.checkSize(mesh.numVertices())) << what;
  for (const std::string& name : names) {
    const VertexProperty* p = mesh.attributes.find(name);
    ASSERT_NE(p, nullptr) << what << ": no property " << name << " in " << mesh.attributes.describe();
    for (VertexId v = 0; v < mesh.numVertices(); ++v) {
      const double expected = expectedValue(name, mesh.positions[v]);
      const double got = p->value(v);
      if (p->type == ScalarType::Float32) {
        ASSERT_EQ(static_cast<float>(got), static_cast<float>(expected)) << what << ": " << name << " at vertex " << v;
      } else {
        ASSERT_EQ(got, expected) << what << ": " << name << " at vertex " << v;
      }
    }
  }
}

const std::vector<std::string> kAllNames = {"red", "green", "blue", "nx", "ny", "nz", "quality", "label"};

/// A small scan: holes, islands, an unwelded seam, degenerate and duplicate faces.
TriangleMesh scanWithAttributes(std::uint64_t faces) {
  GenerateOptions options;
  options.kind = MeshKind::Scan;
  options.faces = faces;
  TriangleMesh mesh = generateMesh(options).mesh;
  addPositionAttributes(mesh);
  return mesh;
}

/// The binary little-endian PLY of writeMesh turned big-endian: per vertex x y z and the
/// properties, per face a uchar count and three ints.
std::string toBigEndian(std::string ply, const TriangleMesh& mesh) {
  const std::string le = "binary_little_endian", be = "binary_big_endian";
  ply.replace(ply.find(le), le.size(), be);
  std::size_t at = ply.find("end_header\n") + 11;
  auto swap = [&](std::size_t width) {
    std::reverse(ply.begin() + at, ply.begin() + at + width);
    at += width;
  };
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    for (int k = 0; k < 3; ++k) swap(4);
    for (const VertexProperty& p : mesh.attributes.properties) swap(scalarSize(p.type));
  }
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    ++at;
    for (int k = 0; k < 3; ++k) swap(4);
  }
  EXPECT_EQ(at, ply.size());
  return ply;
}

void expectSameAttributes(const VertexAttributes& a, const VertexAttributes& b, const std::string& what) {
  ASSERT_EQ(a.describe(), b.describe()) << what;
  for (std::size_t i = 0; i < a.properties.size(); ++i) {
    EXPECT_EQ(a.properties[i].bytes, b.properties[i].bytes) << what << ": " << a.properties[i].name;
  }
}

TEST(Attributes, PlyAsciiBinaryAndBigEndianKeepNamesTypesAndValues) {
  TempDir dir;
  TriangleMesh mesh = testing::gridMesh(6, 5, 0.37);
  addPositionAttributes(mesh);
  WriteOptions ascii;
  ascii.binary = false;
  writeMesh(dir.path("le.ply"), mesh);
  writeMesh(dir.path("ascii.ply"), mesh, ascii);
  testing::writeFile(dir.path("be.ply"), toBigEndian(testing::readFile(dir.path("le.ply")), mesh));
  EXPECT_THAT(testing::readFile(dir.path("ascii.ply")),
              HasSubstr("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float nx\n"
                        "property float ny\nproperty float nz\nproperty double quality\nproperty int label\n"));
  for (const char* name : {"le.ply", "ascii.ply", "be.ply"}) {
    for (const std::size_t chunk : {std::size_t(5), std::size_t(1) << 18}) {
      ReadOptions options;
      options.chunkTriangles = chunk;  // vertices arrive in several chunks and are concatenated
      const TriangleMesh back = readMesh(dir.path(name), options);
      ASSERT_EQ(back.positions, mesh.positions) << name;
      expectSameAttributes(back.attributes, mesh.attributes, name);
      expectAttributesFollowPositions(back, kAllNames, name);
    }
  }
}

TEST(Attributes, PlyReaderWarnsAboutWhatItDoesNotKeep) {
  TempDir dir;
  const std::string path = dir.path("extra.ply");
  testing::writeFile(path,
                     "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nproperty uchar red\nproperty list uchar float weights\n"
                     "element face 1\nproperty list uchar int vertex_indices\nproperty uchar flags\n"
                     "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
                     "0 0 0 10 2 0.5 0.5\n1 0 0 20 0\n0 1 0 30 1 1\n3 0 1 2 7\n0 1\n");
  std::vector<std::string> warnings;
  ReadOptions options;
  options.warn = [&](const std::string& message) { warnings.push_back(message); };
  const TriangleMesh mesh = readMesh(path, options);
  ASSERT_EQ(warnings.size(), 1u);
  for (const char* part : {"vertex property 'weights'", "face property 'flags'", "element 'edge'"}) {
    EXPECT_THAT(warnings[0], HasSubstr(part));
  }
  EXPECT_THAT(warnings[0], HasSubstr(path));
  EXPECT_EQ(mesh.attributes.describe(), "uchar red");
  EXPECT_EQ(mesh.attributes.properties[0].bytes, (std::vector<std::uint8_t>{10, 20, 30}));
}

TEST(Attributes, CleaningKeepsValuesThroughWeldsRemovalsAndSplits) {
  // A bowtie vertex (two fans), a fin (three faces on one edge), an unreferenced vertex and an
  // exact duplicate of a vertex to weld.
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0.1f}, {0, -1, 0.2f},   // bowtie at 0
                    {3, 0, 0},  {4, 0, 0}, {3.5f, 1, 0}, {3.5f, -1, 0}, {3.5f, 0, 1},  // fin on 5-6
                    {9, 9, 9},                                                         // unreferenced
                    {1, 0, 0}, {2, 0, 0}, {1.5f, -1, 0}};  // 11 = vertex 1: a second fan at 1
  mesh.triangles = {{0, 1, 2}, {0, 3, 4}, {5, 6, 7}, {6, 5, 8}, {5, 6, 9}, {11, 12, 13}};
  addPositionAttributes(mesh);
  CleanOptions options;
  options.weldVertices = true;
  const CleanResult cleaned = cleanMesh(mesh, options);
  EXPECT_GT(cleaned.report.nonManifoldVertices, 0u);
  EXPECT_GT(cleaned.report.nonManifoldEdges, 0u);
  EXPECT_EQ(cleaned.report.weldedVertices, 1u);
  EXPECT_EQ(cleaned.report.unreferencedVertices, 1u);
  EXPECT_GT(cleaned.mesh.numVertices(), mesh.numVertices() - 2);  // the split copies
  expectAttributesFollowPositions(cleaned.mesh, kAllNames, "cleaned");

  // The Draco writer maps points to vertices; the PLY writer writes the copies as they are.
  TempDir dir;
  for (const char* name : {"split.drc", "split.ply"}) {
    writeMesh(dir.path(name), cleaned.mesh);
    const TriangleMesh back = readMesh(dir.path(name));
    EXPECT_EQ(back.numVertices(), cleaned.mesh.numVertices()) << name;
    expectAttributesFollowPositions(back, kAllNames, name);
  }
}

TEST(Attributes, WeldingWithAToleranceKeepsTheValuesOfTheKeptPosition) {
  TriangleMesh mesh = testing::gridMesh(4, 4, 1.0);
  // Split the grid along x = 2 with copies moved by 1e-5: welded back with tolerance 1e-4.
  const std::uint32_t nv = mesh.numVertices();
  for (Triangle& t : mesh.triangles) {
    const bool right = mesh.positions[t[0]].x() + mesh.positions[t[1]].x() + mesh.positions[t[2]].x() > 6.0f;
    for (VertexId& v : t) {
      if (right && mesh.positions[v].x() == 2.0f) {
        mesh.positions.push_back(mesh.positions[v] + Vec3f(1e-5f, 0, 0));
        v = static_cast<VertexId>(mesh.positions.size() - 1);
      }
    }
  }
  ASSERT_GT(mesh.numVertices(), nv);
  addPositionAttributes(mesh);
  CleanOptions options;
  options.weldVertices = true;
  options.weldTolerance = 1e-4;
  const CleanResult cleaned = cleanMesh(mesh, options);
  EXPECT_EQ(cleaned.mesh.numVertices(), nv);
  expectAttributesFollowPositions(cleaned.mesh, kAllNames, "welded");
}

TEST(Attributes, SubdivisionAveragesTheEndsOfEachEdge) {
  TriangleMesh grid = testing::gridMesh(5, 4, 0.9);
  addPositionAttributes(grid);
  const CleanResult cleaned = cleanMesh(grid);
  const TriangleMesh& mesh = cleaned.mesh;
  const SubdivideResult fine = subdivideMesh(mesh, cleaned.topology, {});
  ASSERT_NO_THROW(fine.mesh.attributes.checkSize(fine.mesh.numVertices()));
  // Old vertices keep their values.
  for (const VertexProperty& p : mesh.attributes.properties) {
    const VertexProperty* q = fine.mesh.attributes.find(p.name);
    ASSERT_NE(q, nullptr);
    ASSERT_TRUE(std::equal(p.bytes.begin(), p.bytes.end(), q->bytes.begin())) << p.name;
  }
  // Child 4 f + 3 is (m0, m1, m2), m_k the midpoint of the edge opposite corner k of face f.
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const VertexId m = fine.mesh.triangles[4 * f + 3][k];
      const VertexId a = mesh.triangles[f][(k + 1) % 3], b = mesh.triangles[f][(k + 2) % 3];
      for (const VertexProperty& p : mesh.attributes.properties) {
        const double mean = 0.5 * (p.value(a) + p.value(b));
        const double got = fine.mesh.attributes.find(p.name)->value(m);
        if (p.type == ScalarType::UInt8 || p.type == ScalarType::Int32) {
          EXPECT_EQ(got, std::round(mean)) << p.name;  // colors round to nearest
        } else if (p.type == ScalarType::Float32) {
          EXPECT_EQ(got, static_cast<float>(mean)) << p.name;
        } else {
          EXPECT_EQ(got, mean) << p.name;
        }
      }
    }
  }
}

TEST(Attributes, DracoKeepsColorNormalAndGenericAttributes) {
  TempDir dir;
  TriangleMesh mesh = testing::torusMesh(12, 8);
  addPositionAttributes(mesh);
  mesh.attributes.add("alpha", ScalarType::UInt8, mesh.numVertices()).bytes.assign(mesh.numVertices(), 200);
  // Full-range 32-bit values (Draco's own integer coding would need tables of 2^32 entries).
  VertexProperty& id = mesh.attributes.add("id", ScalarType::UInt32, mesh.numVertices());
  for (VertexId v = 0; v < mesh.numVertices(); ++v) id.setValue(v, 4294967295.0 - hashOf(mesh.positions[v]));
  const std::string path = dir.path("torus.drc");
  writeMesh(path, mesh);
  const TriangleMesh back = readMesh(path);
  EXPECT_EQ(back.numVertices(), mesh.numVertices());
  EXPECT_EQ(back.numFaces(), mesh.numFaces());
  expectAttributesFollowPositions(back, kAllNames, "draco");
  // Types are kept; names come from the kinds (COLOR, NORMAL) or from the metadata (GENERIC).
  for (const VertexProperty& p : mesh.attributes.properties) {
    const VertexProperty* q = back.attributes.find(p.name);
    ASSERT_NE(q, nullptr) << p.name;
    EXPECT_EQ(q->type, p.type) << p.name;
  }
  EXPECT_EQ(back.attributes.properties.size(), mesh.attributes.properties.size());
  const VertexProperty& alpha = *back.attributes.find("alpha");
  EXPECT_TRUE(std::all_of(alpha.bytes.begin(), alpha.bytes.end(), [](std::uint8_t a) { return a == 200; }));
  for (VertexId v = 0; v < back.numVertices(); ++v) {
    EXPECT_EQ(back.attributes.find("id")->value(v), 4294967295.0 - hashOf(back.positions[v]));
  }
}

/// Two triangles sharing the edge 1-2 with one point per corner, the colors of the given
/// triangles, and a two-component GENERIC attribute without metadata.
std::string dracoTwoTriangles(const std::array<std::array<std::uint8_t, 3>, 2>& colors) {
  draco::Mesh mesh;
  mesh.set_num_points(6);
  mesh.SetNumFaces(2);
  mesh.SetFace(draco::FaceIndex(0), {draco::PointIndex(0), draco::PointIndex(1), draco::PointIndex(2)});
  mesh.SetFace(draco::FaceIndex(1), {draco::PointIndex(3), draco::PointIndex(4), draco::PointIndex(5)});
  auto add = [&](draco::GeometryAttribute::Type kind, int components, draco::DataType type, int values) {
    draco::GeometryAttribute a;
    a.Init(kind, nullptr, components, type, false, draco::DataTypeLength(type) * components, 0);
    return mesh.attribute(mesh.AddAttribute(a, values == 6, values));
  };
  draco::PointAttribute* position = add(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, 4);
  const float corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  for (std::uint32_t v = 0; v < 4; ++v) position->SetAttributeValue(draco::AttributeValueIndex(v), corners[v]);
  const std::uint32_t positionOfPoint[6] = {0, 1, 2, 2, 1, 3};
  position->SetExplicitMapping(6);
  for (std::uint32_t p = 0; p < 6; ++p) {
    position->SetPointMapEntry(draco::PointIndex(p), draco::AttributeValueIndex(positionOfPoint[p]));
  }
  draco::PointAttribute* color = add(draco::GeometryAttribute::COLOR, 3, draco::DT_UINT8, 6);
  draco::PointAttribute* generic = add(draco::GeometryAttribute::GENERIC, 2, draco::DT_INT16, 6);
  for (std::uint32_t p = 0; p < 6; ++p) {
    color->SetAttributeValue(draco::AttributeValueIndex(p), colors[p / 3].data());
    const std::int16_t g[2] = {static_cast<std::int16_t>(positionOfPoint[p]), -7};
    generic->SetAttributeValue(draco::AttributeValueIndex(p), g);
  }
  draco::Encoder encoder;
  draco::EncoderBuffer buffer;
  EXPECT_TRUE(encoder.EncodeMeshToBuffer(mesh, &buffer).ok());
  return std::string(buffer.data(), buffer.size());
}

TEST(Attributes, DracoReaderNamesUnnamedAttributesAndSplitsPointsOfDifferentValues) {
  TempDir dir;
  const std::string same = dir.path("same.drc"), different = dir.path("different.drc");
  testing::writeFile(same, dracoTwoTriangles({{{10, 20, 30}, {10, 20, 30}}}));
  testing::writeFile(different, dracoTwoTriangles({{{10, 20, 30}, {40, 50, 60}}}));
  const TriangleMesh joined = readMesh(same);
  EXPECT_EQ(joined.numVertices(), 4u);
  const TriangleMesh split = readMesh(different);
  EXPECT_EQ(split.numVertices(), 6u);  // the shared edge's two positions, once per color
  for (const TriangleMesh* mesh : {&joined, &split}) {
    ASSERT_NE(mesh->attributes.find("red"), nullptr) << mesh->attributes.describe();
    for (const char* name : {"red", "green", "blue"}) EXPECT_EQ(mesh->attributes.find(name)->type, ScalarType::UInt8);
    const VertexProperty* g0 = nullptr;
    const VertexProperty* g1 = nullptr;
    for (const VertexProperty& p : mesh->attributes.properties) {
      if (p.name.rfind("draco_generic_", 0) == 0 && p.name.size() > 2 && p.name.substr(p.name.size() - 2) == "_0") g0 = &p;
      if (p.name.rfind("draco_generic_", 0) == 0 && p.name.size() > 2 && p.name.substr(p.name.size() - 2) == "_1") g1 = &p;
    }
    ASSERT_NE(g0, nullptr) << mesh->attributes.describe();
    ASSERT_NE(g1, nullptr) << mesh->attributes.describe();
    for (FaceId f = 0; f < mesh->numFaces(); ++f) {
      const int color = static_cast<int>(mesh->attributes.find("red")->value(mesh->triangles[f][0]));
      for (const VertexId v : mesh->triangles[f]) {
        // Every corner of a face has its face's color, and the generic value of its position.
        EXPECT_EQ(mesh->attributes.find("red")->value(v), color);
        const Vec3f& p = mesh->positions[v];
        const int position = p.x() == 0 && p.y() == 0 ? 0 : p.x() == 1 && p.y() == 0 ? 1 : p.x() == 0 ? 2 : 3;
        EXPECT_EQ(g0->value(v), position);
        EXPECT_EQ(g1->value(v), -7);
      }
    }
  }
}

TEST(Attributes, ObjWritesColorsInUnitRangeAndWarnsAboutTheRest) {
  TempDir dir;
  TriangleMesh mesh = testing::gridMesh(3, 3, 0.5);
  addPositionAttributes(mesh);
  std::vector<std::string> warnings;
  WriteOptions options;
  options.warn = [&](const std::string& message) { warnings.push_back(message); };
  const std::string obj = dir.path("colors.obj"), off = dir.path("mesh.off");
  writeMesh(obj, mesh, options);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(obj));
  for (const char* name : {"nx", "ny", "nz", "quality", "label"}) EXPECT_THAT(warnings[0], HasSubstr(name));
  EXPECT_THAT(warnings[0], Not(HasSubstr("red")));
  const TriangleMesh back = readMesh(obj);
  EXPECT_EQ(back.attributes.describe(), "float red, float green, float blue");
  for (VertexId v = 0; v < back.numVertices(); ++v) {
    for (const char* name : {"red", "green", "blue"}) {
      EXPECT_EQ(back.attributes.find(name)->value(v),
                static_cast<float>(expectedValue(name, back.positions[v]) / 255.0)) << name;
    }
  }
  writeMesh(off, mesh, options);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_THAT(warnings[1], HasSubstr(off));
  for (const std::string& name : kAllNames) EXPECT_THAT(warnings[1], HasSubstr(name));
  writeMesh(dir.path("mesh.ply"), mesh, options);
  writeMesh(dir.path("mesh.drc"), mesh, options);
  EXPECT_EQ(warnings.size(), 2u);  // PLY and Draco hold everything
}

TEST(Attributes, ObjNormalsAreNamedInAWarning) {
  TempDir dir;
  const std::string path = dir.path("normals.obj");
  testing::writeFile(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//2\n");
  std::vector<std::string> warnings;
  ReadOptions options;
  options.warn = [&](const std::string& message) { warnings.push_back(message); };
  EXPECT_EQ(readMesh(path, options).numFaces(), 1u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(path + ": line 4: vn normals not kept"));
}

TEST(Attributes, ObjColorsOnSomeVerticesOnlyAreAnError) {
  TempDir dir;
  const std::string path = dir.path("partial.obj");
  testing::writeFile(path, "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
  try {
    readMesh(path);
    ADD_FAILURE() << "read a vertex without color after one with";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path + ": line 2"));
  }
}

/// The parameterized output in every format that holds colors: each vertex keeps f(position)
/// through welding, cleaning splits, the cut's wedges and Draco's per-point seams.
TEST(Attributes, ParamWeldCarriesAttributesToPlyDracoAndObj) {
  TempDir dir;
  const std::string input = dir.path("scan.ply");
  writeMesh(input, scanWithAttributes(3000));
  for (const char* name : {"out.ply", "out.drc", "out.obj"}) {
    std::string output;
    ASSERT_EQ(testing::runSeamvox("param --quiet --weld " + input + " -o " + dir.path(name), &output), 0) << output;
    ReadOptions options;
    options.readUV = true;
    const TriangleMesh out = readMesh(dir.path(name), options);
    ASSERT_TRUE(out.hasUV()) << name;
    if (std::string(name) == "out.obj") {
      EXPECT_THAT(output, HasSubstr("nx, ny, nz, quality, label"));
      for (const char* color : {"red", "green", "blue"}) {
        const VertexProperty* p = out.attributes.find(color);
        ASSERT_NE(p, nullptr);
        for (VertexId v = 0; v < out.numVertices(); ++v) {
          ASSERT_EQ(p->value(v), static_cast<float>(expectedValue(color, out.positions[v]) / 255.0));
        }
      }
    } else {
      EXPECT_THAT(output, Not(HasSubstr("warning")));
      expectAttributesFollowPositions(out, kAllNames, name);
    }
  }
  // The report names the properties the run carried and their memory (per cleaned vertex).
  const std::string report = dir.path("r.json");
  std::string output;
  ASSERT_EQ(testing::runSeamvox("param --quiet --weld " + input + " -o " + dir.path("r.ply") + " --report " + report, &output), 0) << output;
  const TriangleMesh written = readMesh(dir.path("r.ply"));
  const JsonValue j = parseJson(testing::readFile(report), report);
  EXPECT_EQ(j.textAt("vertexProperties"), written.attributes.describe());
  EXPECT_EQ(j.numberAt("vertexPropertyBytes"), static_cast<double>(written.attributes.memoryBytes()));
  EXPECT_GT(j.numberAt("vertexPropertyBytes"), 0.0);
}

TEST(Attributes, CommandsSubdivideConvertAndInfoKeepOrNameTheProperties) {
  TempDir dir;
  TriangleMesh grid = testing::gridMesh(4, 4, 1.0);
  addPositionAttributes(grid);
  const std::string input = dir.path("grid.ply");
  writeMesh(input, grid);
  std::string output;
  ASSERT_EQ(testing::runSeamvox("subdivide --quiet " + input + " --levels 2 -o " + dir.path("fine.ply"), &output), 0);
  const TriangleMesh fine = readMesh(dir.path("fine.ply"));
  EXPECT_EQ(fine.attributes.describe(), grid.attributes.describe());
  ASSERT_NO_THROW(fine.attributes.checkSize(fine.numVertices()));

  ASSERT_EQ(testing::runSeamvox("convert " + input + " " + dir.path("grid.off"), &output), 0);
  EXPECT_THAT(output, HasSubstr("warning: " + dir.path("grid.off")));
  EXPECT_THAT(output, HasSubstr("red, green, blue, nx, ny, nz, quality, label"));
  ASSERT_EQ(testing::runSeamvox("convert " + input + " " + dir.path("grid.drc"), &output), 0);
  EXPECT_THAT(output, Not(HasSubstr("warning")));
  expectAttributesFollowPositions(readMesh(dir.path("grid.drc")), kAllNames, "convert to drc");

  ASSERT_EQ(testing::runSeamvox("info " + input, &output), 0);
  EXPECT_THAT(output, HasSubstr("uchar red, uchar green, uchar blue, float nx"));
}

}  // namespace
}  // namespace seamvox
