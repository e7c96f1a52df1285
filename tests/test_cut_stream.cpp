// The out-of-core cut (stream/cut_stream) gives what cutToDisk gives on the cleaned mesh read back
// from the scratch and the same singularities: the same cut edges, combing rotations and seam
// curves, with page caches small enough that most lookups miss.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/basis/islands.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/system/errors.h"
#include "stream/cut_stream.h"
#include "stream/field_stream.h"
#include "stream_testing.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::forEachCleaned;
using testing::NamedMeshes;
using testing::readBytes;

const StreamPassOptions kTinyPass{1, 1000};

void expectSameCut(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                   const ScratchSingularities& singularities) {
  CrossField field;
  field.direction.assign(cleaned.topology.numFaces(), Vec3f(1.0f, 0.0f, 0.0f));  // cutToDisk reads its size only
  const CutResult expected =
      cutToDisk(cleaned.mesh, cleaned.topology, field, testing::inMemorySingularities(folder, singularities, cleaned.topology.numVertices()));
  // 1 byte of memory: the cut's state on sparse files through page caches; 64 MiB: held.
  for (const StreamPassOptions& pass : {kTinyPass, StreamPassOptions{std::uint64_t(64) << 20, 1000}}) {
    SCOPED_TRACE("memory " + std::to_string(pass.memoryBytes));
    const std::uint64_t onDisk = folder.bytesInUse();
    const ScratchCut cut = cutScratchToDisk(folder, scratch, singularities, pass);
    EXPECT_EQ(readBytes(folder, cut.corners), expected.corners.cornerBytes());
    EXPECT_EQ(readBytes(folder, cut.faceRotation), expected.faceRotation.faceBytes());
    ASSERT_EQ(cut.seams.size(), expected.seams.size());
    for (std::size_t i = 0; i < cut.seams.size(); ++i) {
      EXPECT_EQ(cut.seams[i].corners, expected.seams[i].corners) << "seam " << i;
      EXPECT_EQ(cut.seams[i].start, expected.seams[i].start) << "seam " << i;
      EXPECT_EQ(cut.seams[i].end, expected.seams[i].end) << "seam " << i;
      EXPECT_EQ(cut.seams[i].matching, expected.seams[i].matching) << "seam " << i;
    }
    EXPECT_EQ(cut.cones, expected.cones);
    // The working files are gone: the cut and the rotations are what it leaves.
    EXPECT_EQ(folder.bytesInUse(), onDisk + cut.corners.bytes + cut.faceRotation.bytes);
    folder.remove(cut.corners);
    folder.remove(cut.faceRotation);
  }
}

// Singularities of the proxy field computed out of core, with and without merging.
TEST(CutStream, CutEqualsTheInMemoryCut) {
  const NamedMeshes meshes = testing::stageTestMeshes(13);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const ScratchField field = computeScratchField(folder, scratch, {}, {}, kTinyPass);
    ScratchSingularities singularities = computeScratchSingularities(folder, scratch, field, kTinyPass);
    EXPECT_FALSE(singularities.cones.empty());
    {
      SCOPED_TRACE("field's cones");
      expectSameCut(folder, scratch, cleaned, singularities);
    }
    ConeMergeOptions merge;
    merge.maxDistance = 0.05 * computeBoundingBox(cleaned.mesh.positions).extent().norm();
    mergeScratchCones(folder, scratch, singularities, merge, kTinyPass);
    SCOPED_TRACE("merged cones");
    expectSameCut(folder, scratch, cleaned, singularities);
  });
}

// A closed genus-0 component with no cone or one keeps one cut edge: the branch cutToDisk takes
// when pruning would leave nothing; zero matchings are consistent with any such choice.
TEST(CutStream, SpheresWithAtMostOneConeKeepOneEdgeAsInMemory) {
  const NamedMeshes meshes = {{"two spheres", testing::concatMeshes({testing::icosphereMesh(3), testing::icosphereMesh(2)})}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    for (const bool withCone : {false, true}) {
      SCOPED_TRACE(withCone ? "one cone" : "no cone");
      ScratchSingularities singularities;
      ScratchWriter writer(folder, "test");
      const std::vector<std::uint8_t> zeros(3 * std::size_t(scratch.numFaces), 0);
      writer.write(zeros.data(), zeros.size());
      singularities.matching = writer.finish();
      if (withCone) {
        singularities.cones = {7};
        singularities.index4 = {{7, 1}};
      }
      expectSameCut(folder, scratch, cleaned, singularities);
      const ScratchCut cut = cutScratchToDisk(folder, scratch, singularities, kTinyPass);
      EXPECT_EQ(cut.components, 2u);
      EXPECT_EQ(cut.seams.size(), 2u);  // one edge each
    }
  });
}

// The islands read off the first cut's dual tree are islandFaces' on the cleaned mesh: a large
// piece with specks of 2-40 faces (some larger than maxFaces), and pieces that are all small (the
// largest then stays); the cut itself is the one without islands asked for.
TEST(CutStream, TheTreesIslandsAreIslandFaces) {
  std::vector<TriangleMesh> specks = {testing::icosphereMesh(3)};
  for (int k = 1; k <= 6; ++k) specks.push_back(testing::gridMesh(k, k % 3 + 1));
  specks.push_back(testing::icosphereMesh(0));
  const NamedMeshes meshes = {{"sphere and specks", testing::concatMeshes(specks)},
                              {"small pieces", testing::concatMeshes({testing::gridMesh(3, 2), testing::gridMesh(2, 2),
                                                                      testing::icosphereMesh(0), testing::gridMesh(3, 2)})},
                              {"one piece", testing::generatedMesh(MeshKind::Scan, 3000)}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    ScratchSingularities singularities;
    ScratchWriter writer(folder, "test");
    const std::vector<std::uint8_t> zeros(3 * std::size_t(scratch.numFaces), 0);
    writer.write(zeros.data(), zeros.size());
    singularities.matching = writer.finish();
    const ScratchCut plain = cutScratchToDisk(folder, scratch, singularities, kTinyPass);
    std::size_t nonEmpty = 0;
    for (const std::uint32_t maxFaces : {0u, 7u, 20u, 1024u}) {
      SCOPED_TRACE(maxFaces);
      std::vector<FaceId> found;
      int calls = 0;
      const TreeIslands islands{maxFaces, [&](std::vector<FaceId> faces) {
                                  found = std::move(faces);
                                  ++calls;
                                }};
      const ScratchCut cut = cutScratchToDisk(folder, scratch, singularities, kTinyPass, &islands);
      EXPECT_EQ(calls, 1);
      EXPECT_EQ(found, islandFaces(cleaned.topology, maxFaces));
      EXPECT_EQ(found, scratchIslandFaces(folder, scratch, maxFaces, 1 << 20));
      nonEmpty += !found.empty();
      EXPECT_EQ(readBytes(folder, cut.corners), readBytes(folder, plain.corners));
      EXPECT_EQ(readBytes(folder, cut.faceRotation), readBytes(folder, plain.faceRotation));
      folder.remove(cut.corners);
      folder.remove(cut.faceRotation);
    }
    if (cleaned.topology.numFaces() < 3000) EXPECT_GT(nonEmpty, 0u);
  });
}

// Matchings that disagree with the cones are the same TopologyError as in memory.
TEST(CutStream, AMissingConeIsATopologyError) {
  const NamedMeshes meshes = {{"scan", testing::generatedMesh(MeshKind::Scan, 6000)}};
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult&) {
    ScratchSingularities singularities =
        computeScratchSingularities(folder, scratch, computeScratchField(folder, scratch, {}, {}, kTinyPass), kTinyPass);
    ASSERT_FALSE(singularities.cones.empty());
    singularities.cones.erase(singularities.cones.begin());
    EXPECT_THROW(cutScratchToDisk(folder, scratch, singularities, kTinyPass), TopologyError);
  });
}

// A scratch disk that fills during the cut (at its start, in the comb, near its end) is an IoError
// naming the folder, and nothing of the run stays on disk.
TEST(CutStream, AFullScratchDiskIsAnErrorAndLeavesNothing) {
  const TriangleMesh mesh = testing::generatedMesh(MeshKind::Scan, 6000);
  testing::TempDir dir;
  std::uint64_t cutBytes = 0;
  {
    ScratchFolder folder(dir.dir());
    const CleanScratch scratch = testing::cleanIntoScratch(folder, mesh, 1 << 20);
    const ScratchSingularities singularities =
        computeScratchSingularities(folder, scratch, computeScratchField(folder, scratch, {}, {}, kTinyPass), kTinyPass);
    const std::uint64_t before = folder.bytesWritten();
    cutScratchToDisk(folder, scratch, singularities, kTinyPass);
    cutBytes = folder.bytesWritten() - before;
  }
  ASSERT_GT(cutBytes, 0u);
  for (const double share : {0.0, 0.5, 0.95}) {
    SCOPED_TRACE(share);
    {
      ScratchFolder folder(dir.dir());
      const CleanScratch scratch = testing::cleanIntoScratch(folder, mesh, 1 << 20);
      const ScratchSingularities singularities =
          computeScratchSingularities(folder, scratch, computeScratchField(folder, scratch, {}, {}, kTinyPass), kTinyPass);
      folder.setWriteLimit(folder.bytesWritten() + static_cast<std::uint64_t>(share * cutBytes));
      testing::expectScratchFull(folder, [&] { cutScratchToDisk(folder, scratch, singularities, kTinyPass); });
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
  }
}

}  // namespace
}  // namespace seamvox
