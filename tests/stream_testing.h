#pragma once
// Fixtures of the out-of-core stage tests: a mesh welded and cleaned into a scratch folder as
// param's out-of-core path starts, and the scratch files read back.
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/mesh.h"
#include "core/basis/voxel_basis.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "stream/cut_stream.h"
#include "stream/clean_stream.h"
#include "stream/field_stream.h"
#include "stream/scratch_folder.h"
#include "testing.h"

namespace seamvox::testing {

/// A scratch file's records.
template <class T>
std::vector<T> readRecords(ScratchFolder& folder, const ScratchFile& file) {
  std::vector<T> out(file.bytes / sizeof(T));
  ScratchReader reader(folder, file, "test");
  if (!out.empty()) EXPECT_TRUE(reader.read(out.data(), out.size() * sizeof(T)));
  return out;
}

/// The field and cut out of core and the same in memory; the voxel options of a grid.
struct StageInputs {
  ScratchField field;
  ScratchCut cut;
  CrossField inMemoryField;
  CutResult inMemoryCut;
  VoxelBasisOptions options;
};

/// The field, singularities and cut out of core with `pass`, the cut in memory from the same
/// singularities, and an edge length of 2% of the diagonal.
StageInputs prepareStageInputs(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                               std::int32_t resolution, const StreamPassOptions& pass);

/// The mesh welded (memory stream, blocks of 997 faces) and cleaned into the folder.
CleanScratch cleanIntoScratch(ScratchFolder& folder, const TriangleMesh& mesh, std::uint64_t memoryBytes);

/// A file of Vec3f records (positions or directions).
std::vector<Vec3f> readPositions(ScratchFolder& folder, const ScratchFile& file);
/// A file's bytes.
std::vector<std::uint8_t> readBytes(ScratchFolder& folder, const ScratchFile& file);

/// The in-memory singularities of out-of-core ones (what cutToDisk reads of them).
FieldSingularities inMemorySingularities(ScratchFolder& folder, const ScratchSingularities& streamed,
                                         std::uint32_t numVertices);

/// A generated scan with scanner noise (a quarter of an edge), spikes and folds.
TriangleMesh noisyScan(std::uint64_t faces);

using NamedMeshes = std::vector<std::pair<const char*, TriangleMesh>>;

/// The stages' usual cases: a noisy generated scan with one-triangle holes, the damaged mesh of
/// a seed, and a torus with two islands (a sphere and a Moebius strip).
NamedMeshes stageTestMeshes(std::uint32_t damageSeed);

/// f(folder, scratch, cleaned) for each mesh cleaned (smallest sort memory) into a folder of its
/// own and read back.
template <class F>
void forEachCleaned(const NamedMeshes& meshes, F&& f) {
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    TempDir dir;
    ScratchFolder folder(dir.dir());
    const CleanScratch scratch = cleanIntoScratch(folder, mesh, 1);
    const CleanResult cleaned = readCleanScratch(folder, scratch);
    f(folder, scratch, cleaned);
  }
}

}  // namespace seamvox::testing
