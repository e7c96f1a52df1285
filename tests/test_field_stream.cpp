// The out-of-core field stage (stream/field_stream) gives what the in-memory field gives on the
// cleaned mesh read back from the scratch, bit for bit, with page caches small enough that most
// lookups miss.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>

#include "core/field/cone_merge.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "stream/clean_stream.h"
#include "stream/field_stream.h"
#include "stream/mesh_stream.h"
#include "stream/paged_reader.h"
#include "stream/welded_scratch.h"
#include "test_meshes.h"
#include "stream_testing.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::forEachCleaned;
using testing::NamedMeshes;
using testing::noisyScan;
using testing::cleanIntoScratch;
using testing::readPositions;

std::size_t countDiffering(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  EXPECT_EQ(a.size(), b.size());
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) wrong += a[i] != b[i];
  return wrong;
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

// Clusters of records far apart, read again and again (a window's rings around scattered flips):
// small pages read the same values and a small fraction of the bytes large pages read, since the
// cache then holds the clusters rather than their neighbours.
TEST(PagedReader, SmallPagesHoldScatteredClusters) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  std::vector<Vec3f> values(1 << 20);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = Vec3f(float(i), float(i % 7), float(i % 11));
  ScratchWriter writer(folder, "test");
  writer.write(values.data(), values.size() * sizeof(Vec3f));
  const ScratchFile file = writer.finish();
  const std::size_t cacheBytes = std::size_t(1) << 19;
  PagedReader<Vec3f> large(file, cacheBytes), small(file, cacheBytes, kWindowPageBytes);
  std::size_t wrong = 0;
  for (int pass = 0; pass < 10; ++pass) {
    for (std::size_t cluster = 0; cluster < 200; ++cluster) {
      const std::size_t start = cluster * 5209;  // 61 KiB apart: a large page each
      for (std::size_t i = start; i < start + 40; ++i) wrong += large[i] != values[i] || small[i] != values[i];
    }
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_LT(small.bytesRead(), 400u * kWindowPageBytes);  // each cluster's one or two pages, once
  EXPECT_GT(large.bytesRead(), 10 * small.bytesRead());
}

// A file changed behind a reader's back: its cached pages keep the old records until forget()
// drops the pages of the changed range; records outside it come from the cache as before.
TEST(PagedReader, ForgetReadsAChangedRangeAgain) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const std::uint32_t n = 100000, first = 30001, count = 9000;
  std::vector<std::uint32_t> values(n);
  for (std::uint32_t i = 0; i < n; ++i) values[i] = i;
  ScratchWriter writer(folder, "test");
  writer.write(values.data(), n * sizeof(std::uint32_t));
  const ScratchFile file = writer.finish();
  PagedReader<std::uint32_t> reader(file, std::size_t(1) << 20);  // holds every page
  for (std::uint32_t i = 0; i < n; ++i) ASSERT_EQ(reader[i], i);
  std::vector<std::uint32_t> changed(count);
  for (std::uint32_t i = 0; i < count; ++i) changed[i] = 7 * (first + i) + 1;
  ScratchUpdater(folder, file, "test").writeAt(std::uint64_t(first) * sizeof(std::uint32_t), changed.data(),
                                               count * sizeof(std::uint32_t));
  EXPECT_EQ(reader[first + 10], first + 10);  // still the cached page
  const std::uint64_t before = reader.bytesRead();
  reader.forget(first, count);
  std::size_t wrong = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    wrong += reader[i] != (i >= first && i < first + count ? 7 * i + 1 : i);
  }
  EXPECT_EQ(wrong, 0u);
  // Read again: the changed range's pages (and at most one page more at each end), not the file.
  EXPECT_GE(reader.bytesRead() - before, count * sizeof(std::uint32_t));
  EXPECT_LE(reader.bytesRead() - before, count * sizeof(std::uint32_t) + 2 * kScratchPageBytes);
  reader.forget(n - 5, 100);  // past the end: nothing to drop
  reader.forget(2 * n, 10);
  EXPECT_EQ(reader[n - 1], n - 1);
}

// Random reads and writes through a two-page writable cache agree with a vector; after flush()
// the file holds the vector, the rest of a zero file still zero.
TEST(PagedArray, ChangesThroughTwoPagesReachTheFile) {
  testing::TempDir dir;
  ScratchFolder folder(dir.dir());
  const std::size_t n = 50000;
  const ScratchFile file = folder.zeroFile(n * sizeof(std::uint32_t));
  std::vector<std::uint32_t> model(n, 0);
  {
    PagedArray<std::uint32_t> array(folder, file, "test", 1);
    std::size_t wrong = 0;
    for (std::size_t k = 0; k < 3 * n; ++k) {
      const std::size_t i = (k * 7919) % (n - n / 10);  // the last tenth never written
      wrong += array[i] != model[i];
      model[i] += static_cast<std::uint32_t>(k);
      array.set(i, array[i] + static_cast<std::uint32_t>(k));
    }
    EXPECT_EQ(wrong, 0u);
    array.flush();
    EXPECT_THROW(array.set(n, 1), IoError);
  }
  std::vector<std::uint32_t> stored(n);
  ScratchReader reader(folder, file, "test");
  ASSERT_TRUE(reader.read(stored.data(), n * sizeof(std::uint32_t)));
  EXPECT_EQ(stored, model);
  EXPECT_GT(folder.bytesWritten(), file.bytes);  // pages written back more than once
}

TEST(FieldStream, SmoothedPositionsEqualSmoothPositions) {
  const NamedMeshes meshes = {
      {"scan with holes", testing::withOneTriangleHoles(testing::generatedMesh(MeshKind::Scan, 40000), 53)},
      {"damaged", testing::damagedMesh(7)},
      {"torus", testing::torusMesh(60, 40)}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    for (const std::uint32_t iterations : {0u, 1u, 3u}) {
      const std::vector<Vec3f> expected = smoothPositions(cleaned.mesh, cleaned.topology, iterations);
      // 1 byte of memory: every cache holds two 64 KB pages, far less than the files; blocks
      // of 1000 vertices.
      const ScratchFile smoothed = smoothScratchPositions(folder, scratch, iterations, StreamPassOptions{1, 1000});
      const std::vector<Vec3f> streamed = readPositions(folder, smoothed);
      EXPECT_EQ(countDiffering(streamed, expected), 0u) << iterations << " iterations";
      if (iterations > 0) EXPECT_NE(streamed, cleaned.mesh.positions);  // the smoothing did move them
    }
  });
}

TEST(FieldStream, ProxyFieldEqualsTheInMemoryField) {
  const NamedMeshes meshes = {
      {"scan with holes", testing::withOneTriangleHoles(testing::generatedMesh(MeshKind::Scan, 40000), 53)},
      {"damaged", testing::damagedMesh(11)},
      {"torus and islands", testing::concatMeshes({testing::torusMesh(60, 40), testing::icosphereMesh(2),
                                                   testing::moebiusStrip(16, Vec3f(4.0f, 0.0f, 0.0f))})}};
  struct Variant {
    std::int32_t grid, sweeps;
    std::uint32_t smoothing, sweepBlock;
  };
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    // Grid 4: cells of more faces than a block (elements across blocks). Sweep blocks:
    // the whole mesh in one; 1024 faces, each I/O block of 1000 faces rounded up to one; 300
    // faces, four to an I/O block (neighbours in the block, before it and after it).
    for (const Variant v : {Variant{128, 4, 3, 1u << 16}, Variant{16, 4, 3, 1024}, Variant{32, 0, 3, 1u << 16},
                            Variant{64, 2, 0, 300}, Variant{4, 1, 0, 1u << 16}})
    for (const std::uint64_t memory : {std::uint64_t(1), std::uint64_t(1) << 30}) {
      SCOPED_TRACE("grid " + std::to_string(v.grid) + ", sweeps " + std::to_string(v.sweeps) + ", smoothing " +
                   std::to_string(v.smoothing) + ", sweep blocks " + std::to_string(v.sweepBlock) + ", memory " +
                   std::to_string(memory));
      ProxyFieldOptions proxy;
      proxy.gridResolution = v.grid;
      proxy.smoothingSweeps = v.sweeps;
      proxy.sweepBlockFaces = v.sweepBlock;
      FieldGeometryOptions geometry;
      geometry.smoothingIterations = v.smoothing;
      const CrossField expected = computeCrossField(cleaned.mesh, cleaned.topology, FieldMethod::Proxy, {}, proxy, geometry);
      // 1 byte: the elements' union-find on disk, every cache holds two pages and the sweeps go
      // through the file; 1 GiB: the links and the sweeps' directions held in memory. Blocks of
      // 1000 faces.
      const std::uint64_t filesBefore = folder.bytesInUse();
      const ScratchField streamed = computeScratchField(folder, scratch, proxy, geometry, StreamPassOptions{memory, 1000});
      EXPECT_EQ(countDiffering(readPositions(folder, streamed.directions), expected.direction), 0u)
          << "directions differ";
      if (v.smoothing > 0) {
        EXPECT_EQ(readPositions(folder, streamed.framePositions), expected.framePositions);
      } else {
        EXPECT_TRUE(streamed.framePositions.path.empty());
      }
      EXPECT_GT(streamed.elements, 0u);
      if (v.sweeps > 0) EXPECT_GE(streamed.colours, 2u);
      // Only the results stay: every intermediate file was removed.
      EXPECT_EQ(folder.bytesInUse() - filesBefore, streamed.directions.bytes + streamed.framePositions.bytes);
      folder.remove(streamed.directions);
      if (v.smoothing > 0) folder.remove(streamed.framePositions);
    }
  });
}

TEST(FieldStream, RoughSpotsAsInMemory) {
  // The plane's fine centre crumpled by noise (rough at the coarser grid), a noisy scan and the damaged
  // mesh.
  const NamedMeshes meshes = {{"crumpled fine spot", testing::denseSpotPlane(12, 2, 16, 0.3, 7)},
                              {"noisy scan with holes", testing::withOneTriangleHoles(noisyScan(30000), 41)},
                              {"damaged", testing::damagedMesh(19)}};
  std::uint64_t moved = 0;
  forEachCleaned(meshes, [&moved](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const double diagonal = computeBoundingBox(cleaned.mesh.positions).extent().norm();
    for (const double grid : {diagonal / 16, diagonal / 100})
    for (const std::uint64_t memory : {std::uint64_t(1), std::uint64_t(1) << 30}) {
      SCOPED_TRACE("grid " + std::to_string(grid) + ", memory " + std::to_string(memory));
      FieldGeometryOptions geometry;
      geometry.roughSpotGrid = grid;
      FieldSolveStats stats;
      ProxyFieldOptions proxy;
      proxy.stats = &stats;
      const CrossField expected = computeCrossField(cleaned.mesh, cleaned.topology, FieldMethod::Proxy, {}, proxy, geometry);
      const std::uint64_t filesBefore = folder.bytesInUse();
      const ScratchField streamed = computeScratchField(folder, scratch, {}, geometry, StreamPassOptions{memory, 1000});
      EXPECT_EQ(streamed.roughVertices, stats.roughVertices);
      EXPECT_EQ(streamed.roughSpotVertices, stats.roughSpotVertices);
      EXPECT_EQ(streamed.roughSpotVertices, expected.frameOverrides.size());
      EXPECT_EQ(readPositions(folder, streamed.framePositions), expected.framePositions);
      EXPECT_EQ(countDiffering(readPositions(folder, streamed.directions), expected.direction), 0u)
          << "directions differ";
      // Only the results stay (the surface before the rough spots were smoothed was removed), and
      // when they moved a vertex the surface param's later stages read, bit for bit the in-memory
      // one (setFrameOverridesAside).
      EXPECT_EQ(streamed.mapPositions.path.empty(), stats.roughSpotVertices == 0);
      if (!streamed.mapPositions.path.empty()) {
        CrossField aside = expected;
        std::vector<std::pair<VertexId, Vec3f>> moves;
        setFrameOverridesAside(cleaned.mesh, cleaned.topology, aside, moves);
        EXPECT_EQ(readPositions(folder, streamed.mapPositions), aside.framePositions);
      }
      EXPECT_EQ(folder.bytesInUse() - filesBefore,
                streamed.directions.bytes + streamed.framePositions.bytes + streamed.mapPositions.bytes);
      folder.remove(streamed.directions);
      folder.remove(streamed.framePositions);
      if (!streamed.mapPositions.path.empty()) folder.remove(streamed.mapPositions);
      moved += stats.roughSpotVertices;
    }
  });
  EXPECT_GT(moved, 1000u) << "too little rough to compare";
}

TEST(FieldStream, RoughRegionsBoundedByHalfThePassMemory) {
  // Half the pass's memory at kRoughRegionBytes a vertex, and never below the minimum region.
  EXPECT_EQ(roughRegionBound(1), kRoughRegionMinVertices);
  EXPECT_EQ(roughRegionBound(0), kRoughRegionMinVertices);
  EXPECT_EQ(roughRegionBound(std::uint64_t(1) << 30), (std::uint64_t(1) << 29) / kRoughRegionBytes);
  EXPECT_GT(roughRegionBound(std::uint64_t(1) << 30), kRoughRegionMinVertices);
}

TEST(FieldStream, SingularitiesEqualTheInMemoryOnes) {
  const NamedMeshes meshes = testing::stageTestMeshes(13);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    for (const std::uint32_t smoothing : {3u, 0u})
    for (const bool fieldAngles : {false, true}) {
      // The angles computed by the singularities, or by the field's last pass and read.
      SCOPED_TRACE("smoothing " + std::to_string(smoothing) + (fieldAngles ? ", the field's angles" : ""));
      FieldGeometryOptions geometry;
      geometry.smoothingIterations = smoothing;
      const CrossField field = computeCrossField(cleaned.mesh, cleaned.topology, FieldMethod::Proxy, {}, {}, geometry);
      const FieldSingularities expected = computeSingularities(cleaned.mesh, cleaned.topology, field);
      const StreamPassOptions pass{1, 1000};
      const ScratchField streamedField = computeScratchField(folder, scratch, {}, geometry, pass, fieldAngles);
      EXPECT_EQ(streamedField.angles.path.empty(), !fieldAngles);
      const std::uint64_t before = folder.bytesInUse();
      const ScratchSingularities streamed = computeScratchSingularities(folder, scratch, streamedField, pass);
      // Only the matchings stay (the field's angles were removed).
      EXPECT_EQ(folder.bytesInUse() + streamedField.angles.bytes, before + streamed.matching.bytes);
      std::vector<std::uint8_t> matching(streamed.matching.bytes);
      ScratchReader reader(folder, streamed.matching, "test");
      ASSERT_TRUE(reader.read(matching.data(), matching.size()));
      EXPECT_EQ(matching, expected.matching);
      std::vector<std::pair<VertexId, std::int32_t>> index4, boundaryIndex4;
      for (VertexId v = 0; v < expected.index4.size(); ++v) {
        if (expected.index4[v] != 0) index4.emplace_back(v, expected.index4[v]);
        if (expected.boundaryIndex4[v] != 0) boundaryIndex4.emplace_back(v, expected.boundaryIndex4[v]);
      }
      EXPECT_EQ(streamed.index4, index4);
      EXPECT_EQ(streamed.boundaryIndex4, boundaryIndex4);
      EXPECT_EQ(streamed.cones, expected.cones);
      EXPECT_FALSE(streamed.cones.empty());  // the torus has none, the scan and the sphere do
    }
  });
}

TEST(FieldStream, MergedConesEqualTheInMemoryMerge) {
  const NamedMeshes meshes = {{"noisy scan with holes", testing::withOneTriangleHoles(noisyScan(30000), 41)},
                              {"damaged", testing::damagedMesh(17)}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    // Without smoothing the noise puts pairs of cones everywhere: much to merge.
    FieldGeometryOptions geometry;
    geometry.smoothingIterations = 0;
    const CrossField field = computeCrossField(cleaned.mesh, cleaned.topology, FieldMethod::Proxy, {}, {}, geometry);
    FieldSingularities expected = computeSingularities(cleaned.mesh, cleaned.topology, field);
    ConeMergeOptions merge;
    merge.maxDistance = 0.05 * computeBoundingBox(cleaned.mesh.positions).extent().norm();
    const ConeMergeResult inMemory = mergeCloseCones(cleaned.mesh, cleaned.topology, expected, merge);
    const StreamPassOptions pass{1, 1000};
    ScratchSingularities streamed =
        computeScratchSingularities(folder, scratch, computeScratchField(folder, scratch, {}, geometry, pass), pass);
    const std::size_t before = streamed.cones.size();
    const ConeMergeResult merged = mergeScratchCones(folder, scratch, streamed, merge, pass);
    EXPECT_GT(inMemory.cancelledPairs + inMemory.mergedPairs, 0u);
    EXPECT_EQ(merged.cancelledPairs, inMemory.cancelledPairs);
    EXPECT_EQ(merged.mergedPairs, inMemory.mergedPairs);
    EXPECT_EQ(merged.changedEdges, inMemory.changedEdges);
    EXPECT_LT(streamed.cones.size(), before);
    EXPECT_EQ(streamed.cones, expected.cones);
    std::vector<std::uint8_t> matching(streamed.matching.bytes);
    ScratchReader reader(folder, streamed.matching, "test");
    ASSERT_TRUE(reader.read(matching.data(), matching.size()));
    EXPECT_EQ(matching, expected.matching);
    std::vector<std::pair<VertexId, std::int32_t>> index4;
    for (VertexId v : expected.cones) index4.emplace_back(v, expected.index4[v]);
    EXPECT_EQ(streamed.index4, index4);
  });
}

// A full-turn cone (index4 5 at the centre of a fan of 40 faces) is split out of core as in memory:
// the same new cones, matchings and indices.
TEST(FieldStream, FullTurnConesAreSplitAsInMemory) {
  const NamedMeshes meshes = {{"fan disk", testing::fanDiskMesh(40, 10)}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const CrossField field = testing::turningField(cleaned.mesh, 5.0);
    FieldSingularities expected = computeSingularities(cleaned.mesh, cleaned.topology, field);
    ASSERT_EQ(expected.cones.size(), 1u);
    ASSERT_EQ(expected.index4[expected.cones[0]], 5);
    ScratchSingularities streamed;
    ScratchWriter writer(folder, "test");
    writer.write(expected.matching.data(), expected.matching.size());
    streamed.matching = writer.finish();
    streamed.cones = expected.cones;
    streamed.index4 = {{expected.cones[0], 5}};
    for (const double distance : {2.5, 0.5}) {
      SCOPED_TRACE(distance);
      FieldSingularities inMemory = expected;
      ScratchSingularities outOfCore = streamed;
      ScratchWriter copy(folder, "test");
      copy.write(expected.matching.data(), expected.matching.size());
      outOfCore.matching = copy.finish();
      const ConeMergeResult a = mergeCloseCones(cleaned.mesh, cleaned.topology, inMemory, {distance});
      const ConeMergeResult b = mergeScratchCones(folder, scratch, outOfCore, {distance}, StreamPassOptions{1, 1000});
      EXPECT_EQ(a.splitCones, 2u);
      EXPECT_EQ(b.splitCones, a.splitCones);
      EXPECT_EQ(b.changedEdges, a.changedEdges);
      EXPECT_EQ(outOfCore.cones, inMemory.cones);
      std::vector<std::pair<VertexId, std::int32_t>> index4;
      for (VertexId v : inMemory.cones) index4.emplace_back(v, inMemory.index4[v]);
      EXPECT_EQ(outOfCore.index4, index4);
      std::vector<std::uint8_t> matching(outOfCore.matching.bytes);
      ScratchReader reader(folder, outOfCore.matching, "test");
      ASSERT_TRUE(reader.read(matching.data(), matching.size()));
      EXPECT_EQ(matching, inMemory.matching);
    }
  });
}

// A scratch disk that fills during the field stage (at its start, in the sweeps, at its end) is
// an IoError naming the folder, and nothing of the run stays on disk.
TEST(FieldStream, AFullScratchDiskIsAnErrorAndLeavesNothing) {
  const TriangleMesh mesh = testing::generatedMesh(MeshKind::Scan, 6000);
  testing::TempDir dir;
  std::uint64_t cleanBytes = 0, fieldBytes = 0;
  {
    ScratchFolder folder(dir.dir());
    const CleanScratch scratch = cleanIntoScratch(folder, mesh, 1 << 20);
    cleanBytes = folder.bytesWritten();
    computeScratchField(folder, scratch, {}, {}, StreamPassOptions{1, 1000});
    fieldBytes = folder.bytesWritten() - cleanBytes;
  }
  for (const double share : {0.0, 0.5, 0.95}) {
    SCOPED_TRACE(share);
    {
      ScratchFolder folder(dir.dir());
      const CleanScratch scratch = cleanIntoScratch(folder, mesh, 1 << 20);
      folder.setWriteLimit(folder.bytesWritten() + static_cast<std::uint64_t>(share * fieldBytes));
      testing::expectScratchFull(folder, [&] { computeScratchField(folder, scratch, {}, {}, StreamPassOptions{1, 1000}); });
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
  }
}

}  // namespace
}  // namespace seamvox
