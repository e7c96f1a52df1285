#include "stream_testing.h"

#include <gtest/gtest.h>

#include <memory>

#include "core/basis/islands.h"
#include "core/cut/cut.h"
#include "core/field/field_proxy.h"
#include "core/synth/generate.h"
#include "stream/clean_stream.h"
#include "stream/mesh_stream.h"
#include "stream/welded_scratch.h"
#include "test_meshes.h"

namespace seamvox::testing {

CleanScratch cleanIntoScratch(ScratchFolder& folder, const TriangleMesh& mesh, std::uint64_t memoryBytes) {
  const std::unique_ptr<MeshStream> stream = makeMemoryStream("mesh", std::make_shared<const TriangleMesh>(mesh), 997);
  WeldStreamOptions weld;
  weld.memoryBytes = memoryBytes;
  const WeldStreamResult welded = weldMeshStream(*stream, folder, weld);
  CleanStreamOptions clean;
  clean.memoryBytes = memoryBytes;
  return cleanWeldedMesh(folder, welded.scratch, welded.census, clean);
}

std::vector<Vec3f> readPositions(ScratchFolder& folder, const ScratchFile& file) {
  std::vector<Vec3f> out(file.bytes / sizeof(Vec3f));
  ScratchReader reader(folder, file, "test");
  if (!out.empty()) EXPECT_TRUE(reader.read(out.data(), file.bytes));
  return out;
}

std::vector<std::uint8_t> readBytes(ScratchFolder& folder, const ScratchFile& file) {
  std::vector<std::uint8_t> out(file.bytes);
  ScratchReader reader(folder, file, "test");
  if (!out.empty()) EXPECT_TRUE(reader.read(out.data(), out.size()));
  return out;
}

FieldSingularities inMemorySingularities(ScratchFolder& folder, const ScratchSingularities& streamed,
                                         std::uint32_t numVertices) {
  FieldSingularities out;
  out.matching = readBytes(folder, streamed.matching);
  out.index4.assign(numVertices, 0);
  out.boundaryIndex4.assign(numVertices, 0);
  for (const auto& [v, index] : streamed.index4) out.index4[v] = index;
  for (const auto& [v, index] : streamed.boundaryIndex4) out.boundaryIndex4[v] = index;
  out.cones = streamed.cones;
  return out;
}

TriangleMesh noisyScan(std::uint64_t faces) {
  TriangleMesh mesh = generatedMesh(MeshKind::Scan, faces);
  ScanNoiseOptions noise;
  noise.amplitude = 0.25;
  noise.spikes = 5;
  noise.folds = 5;
  addScanNoise(mesh, noise);
  return mesh;
}

NamedMeshes stageTestMeshes(std::uint32_t damageSeed) {
  return {{"noisy scan with holes", withOneTriangleHoles(noisyScan(30000), 41)},
          {"damaged", damagedMesh(damageSeed)},
          {"torus and islands", concatMeshes({torusMesh(60, 40), icosphereMesh(2),
                                              moebiusStrip(16, Vec3f(4.0f, 0.0f, 0.0f))})}};
}

StageInputs prepareStageInputs(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                               std::int32_t resolution, const StreamPassOptions& pass) {
  StageInputs in;
  in.field = computeScratchField(folder, scratch, {}, {}, pass);
  const ScratchSingularities singularities = computeScratchSingularities(folder, scratch, in.field, pass);
  in.cut = cutScratchToDisk(folder, scratch, singularities, pass);
  in.inMemoryField.direction = readPositions(folder, in.field.directions);
  // The smoothed surface the field was computed on, as the pipeline's field holds it.
  if (in.field.framePositions.bytes > 0) {
    in.inMemoryField.framePositions = readPositions(folder, in.field.framePositions);
    in.inMemoryField.frameSmoothing = kFieldSmoothingIterations;
  }
  in.inMemoryCut = cutToDisk(cleaned.mesh, cleaned.topology, in.inMemoryField,
                             inMemorySingularities(folder, singularities, cleaned.topology.numVertices()));
  in.options.gridResolution = resolution;
  in.options.edgeLength = 0.02 * computeBoundingBox(cleaned.mesh.positions).extent().norm();
  // The islands, left out of the voxel basis as parameterizeMeshVoxel leaves them out.
  in.options.leftOut = scratchIslandFaces(folder, scratch, kVoxelIslandFaces, pass.memoryBytes);
  EXPECT_EQ(in.options.leftOut, islandFaces(cleaned.topology));
  return in;
}

}  // namespace seamvox::testing
