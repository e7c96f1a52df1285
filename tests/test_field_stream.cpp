// The out-of-core field stage (stream/field_stream) gives what the in-memory field gives on the
// cleaned mesh read back from the scratch, bit for bit, with page caches small enough that most
// lookups miss.
#include <gtest/gtest.h>

#include <memory>

#include "core/field/field.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "stream/clean_stream.h"
#include "stream/field_stream.h"
#include "stream/mesh_stream.h"
#include "stream/paged_reader.h"
#include "stream/welded_scratch.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

// The mesh welded and cleaned into the folder, as param's out-of-core path starts.
CleanScratch cleanIntoScratch(ScratchFolder& folder, const TriangleMesh& mesh, std::uint64_t memoryBytes) {
  const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", std::make_shared<const TriangleMesh>(mesh), 997);
  WeldStreamOptions weld;
  weld.memoryBytes = memoryBytes;
  const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
  return cleanWeldedMesh(folder, welded.scratch, welded.census, memoryBytes);
}

std::vector<Vec3f> readPositions(ScratchFolder& folder, const ScratchFile& file) {
  std::vector<Vec3f> out(file.bytes / sizeof(Vec3f));
  ScratchReader reader(folder, file, "test");
  if (!out.empty()) EXPECT_TRUE(reader.read(out.data(), file.bytes));
  return out;
}

TEST(PagedReader, ReadsEveryRecordInAnyOrderThroughTwoPages) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  std::vector<Vec3f> values(100000);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = Vec3f(float(i), float(2 * i), float(3 * i));
  ScratchWriter writer(folder, "test");
  writer.write(values.data(), values.size() * sizeof(Vec3f));
  const ScratchFile file = writer.finish();
  PagedReader<Vec3f> reader(file, 1);  // two pages
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    const std::size_t i = (k * 7919) % values.size();  // jumps across pages
    wrong += reader[i] != values[i];
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(reader.bytesRead(), file.bytes);  // pages read again: the cache holds two
  EXPECT_THROW(reader[values.size()], IoError);
}

TEST(FieldStream, SmoothedPositionsEqualSmoothPositions) {
  const std::vector<std::pair<const char*, TriangleMesh>> meshes = {
      {"scan with holes", testing::withOneTriangleHoles(testing::generatedMesh(MeshKind::Scan, 40000), 53)},
      {"damaged", testing::damagedMesh(7)},
      {"torus", testing::torusMesh(60, 40)}};
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    testing::TempDir dir;
    ScratchFolder folder(dir.dir());
    const CleanScratch scratch = cleanIntoScratch(folder, mesh, 1);
    const CleanResult cleaned = readCleanScratch(folder, scratch);
    for (const std::uint32_t iterations : {0u, 1u, 3u}) {
      const std::vector<Vec3f> expected = smoothPositions(cleaned.mesh, cleaned.topology, iterations);
      // 1 byte of memory: every cache holds two 64 KB pages, far less than the files.
      const ScratchFile smoothed = smoothScratchPositions(folder, scratch, iterations, 1);
      const std::vector<Vec3f> streamed = readPositions(folder, smoothed);
      ASSERT_EQ(streamed.size(), expected.size());
      std::size_t wrong = 0;
      for (std::size_t v = 0; v < expected.size(); ++v) wrong += streamed[v] != expected[v];
      EXPECT_EQ(wrong, 0u) << iterations << " iterations";
      if (iterations > 0) EXPECT_NE(streamed, cleaned.mesh.positions);  // the smoothing did move them
    }
  }
}

}  // namespace
}  // namespace seamvox
