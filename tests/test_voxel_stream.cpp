// The out-of-core voxel elements (stream/voxel_stream) equal buildVoxelBasis's on the cleaned mesh
// read back from the scratch, with the same field and cut: the same voxels and ids, the same
// elements of every face's fragments, bit-equal integrals; with sorts that spill and blocks of a
// few hundred fragments.
#include <gtest/gtest.h>

#include <complex>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <tuple>
#include <filesystem>
#include <string>

#include "core/basis/voxel_grid.h"
#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/wedge_map.h"
#include "core/refine/refine.h"
#include "core/system/errors.h"
#include "core/solve/evaluate.h"
#include "stream/cut_stream.h"
#include "stream/evaluate_stream.h"
#include "io/atomic_file.h"
#include "io/mesh_io.h"
#include "io/scratch_map_writer.h"
#include "stream/refine_stream.h"
#include "stream/voxel_solve_stream.h"
#include "stream/field_stream.h"
#include "stream/voxel_stream.h"
#include "stream_testing.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::forEachCleaned;
using testing::NamedMeshes;

const StreamPassOptions kTinyPass{1, 300};

using testing::readRecords;
using Inputs = testing::StageInputs;

Inputs prepareInputs(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                     std::int32_t resolution) {
  return testing::prepareStageInputs(folder, scratch, cleaned, resolution, kTinyPass);
}

void expectSameElements(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                        std::int32_t resolution) {
  const Inputs in = prepareInputs(folder, scratch, cleaned, resolution);
  VoxelBasisOptions options = in.options;
  options.chunkFaces = 777;
  const VoxelBuildResult expected = buildVoxelBasis(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, options);
  const VoxelBasis& basis = *expected.basis;

  const ScratchVoxelElements built = buildScratchVoxelElements(folder, scratch, in.field, in.cut, options, kTinyPass);
  EXPECT_EQ(built.geometry.origin, basis.grid().origin);
  EXPECT_EQ(built.geometry.voxelSize, basis.grid().voxelSize);
  EXPECT_EQ(built.grid.coords(), basis.voxelCoords());
  EXPECT_EQ(built.grid.blockStarts(), expected.grid.blockStarts());
  EXPECT_EQ(built.voxelElementStart, basis.voxelElementStart());
  ASSERT_EQ(built.elementVoxel.size(), basis.numElements());
  std::size_t wrongVoxel = 0, wrongRecord = 0, wrongNormal = 0;
  for (std::uint64_t e = 0; e < basis.numElements(); ++e) {
    wrongVoxel += built.grid.coords()[built.elementVoxel[e]] != basis.elementVoxel(e);
    wrongRecord += std::memcmp(&built.records[e], &basis.elementRecord(e), sizeof(VoxelIntegrals)) != 0;
    wrongNormal += built.normalStiffness[e] != basis.elementNormalStiffness(e);
  }
  EXPECT_EQ(wrongVoxel, 0u);
  EXPECT_EQ(wrongRecord, 0u);
  EXPECT_EQ(wrongNormal, 0u);
  EXPECT_GT(basis.numElements(), 50u);

  const std::vector<VoxelFragment> fragments = readRecords<VoxelFragment>(folder, built.fragments);
  const std::vector<std::uint32_t> element = readRecords<std::uint32_t>(folder, built.fragmentElement);
  ASSERT_EQ(fragments.size(), built.numFragments);
  ASSERT_EQ(element.size(), built.numFragments);
  std::size_t next = 0, wrongFace = 0;
  for (FaceId f = 0; f < cleaned.topology.numFaces(); ++f) {
    std::vector<std::uint32_t> elements;
    for (; next < fragments.size() && fragments[next].face == f; ++next) elements.push_back(element[next]);
    wrongFace += elements != basis.faceElements(f);
  }
  EXPECT_EQ(next, fragments.size());
  EXPECT_EQ(wrongFace, 0u);
}

// The whole basis: domains, basis functions, seam adjacency, blocks and integrals as assembled.
void expectSameBasis(ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned,
                     std::int32_t resolution) {
  const Inputs in = prepareInputs(folder, scratch, cleaned, resolution);
  VoxelBasisOptions options = in.options;
  options.minDomainWeight = 1e-3;  // some domains joined
  const VoxelBuildResult expected = buildVoxelBasis(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, options);
  const VoxelBasis& want = *expected.basis;
  const ScratchVoxelBasis built = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, options, kTinyPass);
  const VoxelBasis& got = *built.basis;
  EXPECT_GT(want.stats().joinedDomains, 0u);
  EXPECT_EQ(got.stats().joinedDomains, want.stats().joinedDomains);
  EXPECT_EQ(got.numBasisFunctions(), want.numBasisFunctions());
  EXPECT_EQ(got.domainBasis(), want.domainBasis());
  EXPECT_EQ(got.seamRotation(), want.seamRotation());
  EXPECT_EQ(got.basisCorner(), want.basisCorner());
  EXPECT_EQ(got.elementBlocks(), want.elementBlocks());
  ASSERT_EQ(got.adjacencies().size(), want.adjacencies().size());
  EXPECT_GT(want.adjacencies().size(), 0u);
  std::size_t wrongAdjacency = 0, wrongElement = 0;
  for (std::size_t i = 0; i < want.adjacencies().size(); ++i) {
    const DomainAdjacency &a = got.adjacencies()[i], &b = want.adjacencies()[i];
    wrongAdjacency += a.left != b.left || a.right != b.right || a.seam != b.seam;
  }
  ASSERT_EQ(got.numElements(), want.numElements());
  for (std::uint64_t e = 0; e < want.numElements(); ++e) {
    ElementIntegrals a, b;
    got.elementIntegrals(e, a);
    want.elementIntegrals(e, b);
    wrongElement += a.count != b.count || a.domain != b.domain || a.stiffness != b.stiffness || a.rhs != b.rhs ||
                    a.area != b.area;
  }
  EXPECT_EQ(wrongAdjacency, 0u);
  EXPECT_EQ(wrongElement, 0u);
  // No mesh in memory: evaluation is the caller's, from the files.
  WedgeMap map;
  EXPECT_THROW(got.evaluateCorners(std::vector<std::complex<double>>(got.numDomains()), map), InputError);
  EXPECT_THROW(got.faceElements(0), InputError);
}

TEST(VoxelStream, BasisEqualsTheInMemoryBasis) {
  const NamedMeshes meshes = testing::stageTestMeshes(19);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    for (const std::int32_t resolution : {16, 64}) {
      SCOPED_TRACE("grid " + std::to_string(resolution));
      expectSameBasis(folder, scratch, cleaned, resolution);
    }
  });
}

// The map of random coefficients evaluated out of core: the same wedges (ids per corner) and
// bit-equal values as buildCutWedges and evaluateCorners in memory.
TEST(VoxelStream, MapEqualsTheInMemoryEvaluation) {
  const NamedMeshes meshes = testing::stageTestMeshes(23);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const Inputs in = prepareInputs(folder, scratch, cleaned, 32);
    const VoxelBuildResult expected =
        buildVoxelBasis(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, in.options);
    const ScratchVoxelBasis built = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    std::mt19937 random(5);
    std::uniform_real_distribution<double> uniform(-10.0, 10.0);
    std::vector<std::complex<double>> coefficients(expected.basis->numDomains());
    for (auto& q : coefficients) q = {uniform(random), uniform(random)};
    WedgeMap map = buildCutWedges(cleaned.topology, in.inMemoryCut);
    expected.basis->evaluateCorners(coefficients, map);
    const ScratchMap streamed = evaluateScratchVoxelMap(folder, scratch, in.cut, built, coefficients, kTinyPass);
    ASSERT_EQ(streamed.numWedges, map.numWedges());
    const std::vector<std::uint32_t> cornerWedge = readRecords<std::uint32_t>(folder, streamed.cornerWedge);
    const std::vector<Vec2d> values = readRecords<Vec2d>(folder, streamed.wedgeValues);
    const std::vector<std::uint32_t> starts = readRecords<std::uint32_t>(folder, streamed.vertexWedgeStart);
    ASSERT_EQ(cornerWedge.size(), map.size());
    ASSERT_EQ(values.size(), map.numWedges());
    ASSERT_EQ(starts.size(), std::size_t(cleaned.topology.numVertices()) + 1);
    std::size_t wrongWedge = 0, wrongValue = 0, wrongVertex = 0, nonZero = 0;
    for (CornerId c = 0; c < map.size(); ++c) {
      wrongWedge += cornerWedge[c] != map.wedge(c);
      const VertexId v = cleaned.topology.vertex(c);
      wrongVertex += cornerWedge[c] < starts[v] || cornerWedge[c] >= starts[v + 1];
    }
    // Every wedge is evaluated but the islands' (left out of the basis, mapped by the local
    // hat solve later: they stay 0).
    std::vector<std::uint8_t> island(map.numWedges(), 0);
    for (FaceId f : in.options.leftOut) {
      for (int k = 0; k < 3; ++k) island[map.wedge(3 * f + k)] = 1;
    }
    std::size_t islandWedges = 0;
    for (std::uint32_t w = 0; w < map.numWedges(); ++w) {
      wrongValue += values[w] != map.wedgeValue(w);
      nonZero += values[w] != Vec2d::Zero() && !island[w];
      islandWedges += island[w] && values[w] == Vec2d::Zero();
    }
    EXPECT_EQ(wrongWedge, 0u);
    EXPECT_EQ(wrongVertex, 0u);
    EXPECT_EQ(wrongValue, 0u);
    EXPECT_EQ(nonZero + islandWedges, values.size());
    EXPECT_GT(map.numWedges(), cleaned.topology.numVertices());  // seams split vertices
    // Written chunk by chunk from the files: the bytes writeMesh writes for the mesh in memory.
    TriangleMesh mesh;
    mesh.positions = cleaned.mesh.positions;
    mesh.triangles = cleaned.mesh.triangles;
    mesh.cornerUV = map;
    testing::TempDir dir;
    for (const char* name : {"map.ply", "map.obj", "map.off", "ascii.ply"}) {
      SCOPED_TRACE(name);
      WriteOptions options;
      options.binary = std::string(name) != "ascii.ply";
      const std::string want = dir.dir() + "/want-" + name, got = dir.dir() + "/got-" + name;
      writeMesh(want, mesh, options);
      AtomicFile file(got);
      writeScratchMap(file, folder, scratch, streamed, options, kTinyPass);
      file.commit();
      const std::string wantBytes = testing::readFile(want), gotBytes = testing::readFile(got);
      EXPECT_GT(wantBytes.size(), 1000u);
      EXPECT_TRUE(wantBytes == gotBytes) << wantBytes.size() << " against " << gotBytes.size() << " bytes";
    }
  });
}

void expectSameRegion(const RegionMesh& got, const RegionMesh& want) {
  EXPECT_EQ(got.faceOrigin, want.faceOrigin);
  EXPECT_EQ(got.vertexOrigin, want.vertexOrigin);
  EXPECT_EQ(got.vertexFree, want.vertexFree);
  EXPECT_EQ(got.seamOrigin, want.seamOrigin);
  EXPECT_EQ(got.mesh.positions, want.mesh.positions);
  EXPECT_EQ(got.mesh.triangles, want.mesh.triangles);
  EXPECT_EQ(got.field.direction, want.field.direction);
  EXPECT_EQ(got.cut.corners.cornerBytes(), want.cut.corners.cornerBytes());
  EXPECT_EQ(got.cut.faceRotation, want.cut.faceRotation);
  EXPECT_EQ(got.cut.cones, want.cut.cones);
  ASSERT_EQ(got.cut.seams.size(), want.cut.seams.size());
  for (std::size_t s = 0; s < want.cut.seams.size(); ++s) {
    EXPECT_EQ(got.cut.seams[s].corners, want.cut.seams[s].corners);
    EXPECT_EQ(got.cut.seams[s].start, want.cut.seams[s].start);
    EXPECT_EQ(got.cut.seams[s].end, want.cut.seams[s].end);
  }
  ASSERT_EQ(got.topology.numCorners(), want.topology.numCorners());
  std::size_t wrong = 0;
  for (CornerId c = 0; c < want.topology.numCorners(); ++c) wrong += got.topology.opposite(c) != want.topology.opposite(c);
  for (VertexId v = 0; v < want.topology.numVertices(); ++v) wrong += got.topology.vertexCorner(v) != want.topology.vertexCorner(v);
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(want.topology.numFaces(), 0u);
  EXPECT_LT(std::count(want.vertexFree.begin(), want.vertexFree.end(), 1), std::ptrdiff_t(want.vertexFree.size()));
}

// The Vox solve out of core: the same seam constraints, translations and map (before any local
// refinement) as parameterizeMeshVoxel on the cleaned mesh; the written map's seams are seamless.
// The passes over every face of an out-of-core map read it a block at a time and measure in
// parallel: forEach and nextBlock give every face in order, with the positions and values its
// corners have in the files, across blocks.
TEST(VoxelStream, MapFacesInBlocksAreTheFacesInOrder) {
  const NamedMeshes meshes = testing::stageTestMeshes(23);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const Inputs in = prepareInputs(folder, scratch, cleaned, 32);
    const ScratchVoxelBasis built = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-10.0, 10.0);
    std::vector<std::complex<double>> coefficients(built.basis->numDomains());
    for (auto& q : coefficients) q = {uniform(random), uniform(random)};
    const ScratchMap map = evaluateScratchVoxelMap(folder, scratch, in.cut, built, coefficients, kTinyPass);
    const std::vector<CleanFace> records = readRecords<CleanFace>(folder, scratch.faces);
    const std::vector<Vec3f> positions = readRecords<Vec3f>(folder, scratch.positions);
    const std::vector<std::uint32_t> cornerWedge = readRecords<std::uint32_t>(folder, map.cornerWedge);
    const std::vector<Vec2d> values = readRecords<Vec2d>(folder, map.wedgeValues);
    std::vector<MapFace> one(records.size());
    for (FaceId f = 0; f < records.size(); ++f) {
      one[f].f = f;
      one[f].t = records[f].triangle;
      for (int k = 0; k < 3; ++k) {
        one[f].p[k] = positions[one[f].t[k]].cast<double>();
        one[f].q[k] = values[cornerWedge[3 * f + k]];
      }
    }
    ASSERT_EQ(one.size(), scratch.numFaces);
    const auto same = [](const MapFace& a, const MapFace& b) {
      return a.f == b.f && a.t == b.t && a.p == b.p && a.q == b.q;
    };
    const std::uint64_t blockFaces = 97;  // several blocks, the last one short
    ASSERT_GT(one.size(), 3 * blockFaces);
    ScratchMapFaces faces(folder, scratch, map, "test", 4096, blockFaces);
    std::size_t visited = 0, wrong = 0, wrongMeasure = 0;
    faces.forEach([](const MapFace& x) { return x.p[0].x() + 3.0 * x.q[1].y() + x.t[2]; },
                  [&](const MapFace& x, double measured) {
                    wrong += visited >= one.size() || !same(x, one[visited]);
                    wrongMeasure += measured != x.p[0].x() + 3.0 * x.q[1].y() + x.t[2];
                    ++visited;
                  });
    EXPECT_EQ(visited, one.size());
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(wrongMeasure, 0u);
    ScratchMapFaces blocks(folder, scratch, map, "test", 4096, blockFaces);
    std::size_t at = 0, count = 0;
    wrong = 0;
    while (const std::vector<MapFace>* block = blocks.nextBlock()) {
      EXPECT_LE(block->size(), blockFaces);
      for (const MapFace& x : *block) wrong += at >= one.size() || !same(x, one[at++]);
      ++count;
    }
    EXPECT_EQ(at, one.size());
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(count, (one.size() + blockFaces - 1) / blockFaces);
  });
}

TEST(VoxelStream, VoxMapEqualsTheInMemorySolve) {
  const NamedMeshes meshes = testing::stageTestMeshes(29);
  std::size_t consistentMeshes = 0;
  std::uint64_t seededFromMap = 0, islandFacesSeen = 0;
  forEachCleaned(meshes, [&](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const Inputs in = prepareInputs(folder, scratch, cleaned, 32);
    ParamOptions param;
    param.edgeLength = in.options.edgeLength;
    param.smoothedEvaluation = false;  // the Vox map as solved (its re-evaluation: test_param_stream)
    const VoxelParamResult expected =
        parameterizeMeshVoxel(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, param, 32);
    EXPECT_EQ(scratchSeamCycleConstraints(scratch, in.cut, kTinyPass),
              seamCycleConstraints(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, param.edgeLength));
    ScratchVoxelBasis basis = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    const ScratchVoxelSolution solved = solveScratchVoxelMap(folder, scratch, in.cut, basis, RoundOptions{}, kTinyPass);
    EXPECT_EQ(solved.translationConstraints, expected.param.translationConstraints);
    EXPECT_EQ(solved.determinedBasis, expected.determinedBasis);
    EXPECT_EQ(solved.inconsistentBasis, expected.inconsistentBasis);
    EXPECT_EQ(solved.translations, expected.param.translations);
    // The refinement's faces, and those of the inconsistent functions alone.
    const std::vector<FaceId>& islands = in.options.leftOut;
    EXPECT_EQ(withFaces(scratchSupportFaces(folder, basis, solved.markedBasis), islands), expected.markedFaces);
    EXPECT_EQ(withFaces(scratchSupportFaces(folder, basis, solved.inconsistentBasisFunctions), islands),
              expected.inconsistentFaces);
    EXPECT_EQ(expected.islandFaces, islands.size());
    islandFacesSeen += islands.size();
    EXPECT_FALSE(expected.markedFaces.empty());
    // The refinement's region paged in equals the one cut out of the mesh in memory.
    // (a part of the marked faces and a ring: the region has a border of locked vertices).
    const std::vector<FaceId> seeds(expected.markedFaces.begin(), expected.markedFaces.begin() + expected.markedFaces.size() / 8);
    const std::vector<FaceId> region = growFaces(cleaned.topology, seeds, 1);
    const RegionMesh want = extractRegion(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, region);
    const RegionMesh got = extractScratchRegion(scratch, in.field, in.cut, region, kTinyPass);
    expectSameRegion(got, want);
    // On the field's smoothed surface: read from its file out of core, in memory from the field's
    // positions or, released, smoothed again at the region's vertices.
    ASSERT_GT(in.field.framePositions.bytes, 0u);
    CrossField released = in.inMemoryField;
    released.framePositions.clear();
    const RegionMesh onSurface = extractScratchRegion(scratch, in.field, in.cut, region, kTinyPass, nullptr, true);
    expectSameRegion(onSurface, extractRegionOnFieldSurface(cleaned.mesh, cleaned.topology, in.inMemoryField,
                                                            in.inMemoryCut, region));
    expectSameRegion(onSurface,
                     extractRegionOnFieldSurface(cleaned.mesh, cleaned.topology, released, in.inMemoryCut, region));
    EXPECT_NE(onSurface.mesh.positions, got.mesh.positions);
    // The refinement region selected from the map out of core: the same faces and counts.
    for (const bool fromMap : {true, false}) {
      for (const std::uint32_t rings : {1u, 3u}) {
        SCOPED_TRACE(std::string(fromMap ? "seeds from the map" : "marked only") + ", rings " + std::to_string(rings));
        RefineOptions refine;
        refine.edgeLength = param.edgeLength;
        refine.markedFaces = expected.markedFaces;
        refine.seedFromMap = fromMap;
        refine.rings = rings;
        RefineStats a, b;
        const std::vector<FaceId> inMemory = selectRefineRegion(cleaned.mesh, cleaned.topology, expected.param.cornerUV, refine, &a);
        EXPECT_EQ(selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass, &b), inMemory);
        EXPECT_EQ(std::make_tuple(b.markedFaces, b.collapsedFaces, b.flippedFaces, b.regionFaces),
                  std::make_tuple(a.markedFaces, a.collapsedFaces, a.flippedFaces, a.regionFaces));
        if (fromMap) seededFromMap += a.collapsedFaces + a.flippedFaces;
      }
    }
    EXPECT_FALSE(solved.translations.empty());
    const WedgeMap& map = expected.param.cornerUV;
    ASSERT_EQ(solved.map.numWedges, map.numWedges());
    const std::vector<std::uint32_t> cornerWedge = readRecords<std::uint32_t>(folder, solved.map.cornerWedge);
    const std::vector<Vec2d> values = readRecords<Vec2d>(folder, solved.map.wedgeValues);
    std::size_t wrongWedge = 0, far = 0;
    double largest = 0.0;
    for (CornerId c = 0; c < map.size(); ++c) wrongWedge += cornerWedge[c] != map.wedge(c);
    for (std::uint32_t w = 0; w < map.numWedges(); ++w) {
      const double d = (values[w] - map.wedgeValue(w)).norm();
      largest = std::max(largest, d);
      far += d > 1e-9;
    }
    EXPECT_EQ(wrongWedge, 0u);
    EXPECT_EQ(far, 0u) << "largest difference " << largest;
    // Seamless across the seams (q_right = r q_left + t) except where the voxel basis could not
    // keep them (inconsistent basis functions near cones, which the local refinement re-solves)
    std::size_t notSeamless = 0, pairs = 0;
    const auto valueAt = [&](CornerId c) { return values[cornerWedge[c]]; };
    for (std::uint32_t s = 0; s < in.inMemoryCut.seams.size(); ++s) {
      const SeamCurve& seam = in.inMemoryCut.seams[s];
      const std::complex<double> r = std::pow(std::complex<double>(0.0, -1.0), seam.matching % 4);
      for (CornerId c : seam.corners) {
        const CornerId o = cleaned.topology.opposite(c);
        for (const auto& [left, right] : {std::make_pair(nextCorner(c), prevCorner(o)), std::make_pair(prevCorner(c), nextCorner(o))}) {
          const Vec2d l = valueAt(left), rt = valueAt(right);
          const std::complex<double> mapped = r * std::complex<double>(l[0], l[1]) + solved.translations[s];
          notSeamless += std::abs(mapped - std::complex<double>(rt[0], rt[1])) > 1e-6;
          ++pairs;
        }
      }
    }
    // (by construction: exactly seamless where no basis function is inconsistent).
    EXPECT_GT(pairs, 0u);
    if (expected.inconsistentBasis == 0) {
      EXPECT_EQ(notSeamless, 0u);
      ++consistentMeshes;
    } else {
      EXPECT_LT(notSeamless, pairs) << notSeamless << " of " << pairs;
    }
  });
  EXPECT_GT(consistentMeshes, 0u);
  EXPECT_GT(seededFromMap, 0u);  // some faces collapsed or flipped
  EXPECT_GT(islandFacesSeen, 0u);  // the torus's islands
}

// The refinement's seeds read off the map by the smoothed evaluation's pass (the faces around the
// vertices it moved measured again) select the region that a pass over the re-evaluated map
// selects, marked faces first as there; seeds for another edge length are not taken.
TEST(VoxelStream, SeedsReadBySmoothedEvaluationEqualAPassAfterIt) {
  const NamedMeshes meshes = testing::stageTestMeshes(29);
  std::uint64_t moved = 0, seeded = 0, changedByMoves = 0;
  forEachCleaned(meshes, [&](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const Inputs in = prepareInputs(folder, scratch, cleaned, 32);
    ScratchVoxelBasis basis = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    ScratchVoxelSolution solved = solveScratchVoxelMap(folder, scratch, in.cut, basis, RoundOptions{}, kTinyPass);
    RefineOptions refine;
    refine.edgeLength = in.options.edgeLength;
    refine.seedFromMap = true;
    refine.rings = 0;
    const std::vector<FaceId> seedsBefore = selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass);
    ScratchMapSeeds seeds;
    seeds.edgeLength = refine.edgeLength;
    seeds.collapseThreshold = refine.collapseThreshold;
    const SmoothedEvaluationStats stats = evaluateScratchFoldsAtSmoothedSurface(
        folder, scratch, in.field, basis, solved.coefficients, refine.edgeLength, solved.map, kTinyPass, &seeds);
    ASSERT_TRUE(seeds.known);
    ASSERT_EQ(seeds.kinds.size(), seeds.faces.size());
    moved += stats.vertices - stats.keptForStretch;
    // Marked faces: every 13th, and some of the seeds.
    for (FaceId f = 0; f < scratch.numFaces; f += 13) refine.markedFaces.push_back(f);
    for (std::size_t i = 0; i < seeds.faces.size(); i += 3) refine.markedFaces.push_back(seeds.faces[i]);
    for (const std::uint32_t rings : {0u, 2u}) {
      SCOPED_TRACE("rings " + std::to_string(rings));
      refine.rings = rings;
      RefineStats a, b, c;
      const std::vector<FaceId> byPass = selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass, &a);
      EXPECT_EQ(selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass, &b, &seeds), byPass);
      EXPECT_EQ(std::make_tuple(b.markedFaces, b.collapsedFaces, b.flippedFaces, b.regionFaces),
                std::make_tuple(a.markedFaces, a.collapsedFaces, a.flippedFaces, a.regionFaces));
      ScratchMapSeeds other;
      other.edgeLength = 2.0 * refine.edgeLength;
      other.collapseThreshold = refine.collapseThreshold;
      other.known = true;  // and empty: taken, it would drop every seed
      EXPECT_EQ(selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass, &c, &other), byPass);
      if (rings == 0) seeded += a.collapsedFaces + a.flippedFaces;
    }
    refine.rings = 0;
    refine.markedFaces.clear();
    changedByMoves += selectScratchRefineRegion(folder, scratch, solved.map, refine, kTinyPass, nullptr, &seeds) != seedsBefore;
  });
  EXPECT_GT(moved, 0u);           // the smoothed evaluation moved vertices
  EXPECT_GT(seeded, 0u);          // faces collapsed or flipped
  EXPECT_GT(changedByMoves, 0u);  // and the moves changed the seeds (measured again around them)
}

TEST(VoxelStream, ElementsEqualTheInMemoryBasis) {
  const NamedMeshes meshes = testing::stageTestMeshes(13);
  forEachCleaned(meshes, [](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    for (const std::int32_t resolution : {16, 64}) {
      SCOPED_TRACE("grid " + std::to_string(resolution));
      expectSameElements(folder, scratch, cleaned, resolution);
    }
  });
}

// A scratch disk that fills while the elements are built (at the start, in the sorts, near the
// end) is an IoError naming the folder, and nothing of the run stays on disk.
TEST(VoxelStream, AFullScratchDiskIsAnErrorAndLeavesNothing) {
  const TriangleMesh mesh = testing::generatedMesh(MeshKind::Scan, 6000);
  testing::TempDir dir;
  VoxelBasisOptions options;
  options.gridResolution = 32;
  options.edgeLength = 0.05;
  std::uint64_t voxelBytes = 0;
  for (const double share : {-1.0, 0.0, 0.5, 0.95}) {
    SCOPED_TRACE(share);
    {
      ScratchFolder folder(dir.dir());
      const CleanScratch scratch = testing::cleanIntoScratch(folder, mesh, 1 << 20);
      const ScratchField field = computeScratchField(folder, scratch, {}, {}, kTinyPass);
      const ScratchCut cut =
          cutScratchToDisk(folder, scratch, computeScratchSingularities(folder, scratch, field, kTinyPass), kTinyPass);
      const std::uint64_t before = folder.bytesWritten();
      if (share < 0.0) {  // measure
        buildScratchVoxelElements(folder, scratch, field, cut, options, kTinyPass);
        voxelBytes = folder.bytesWritten() - before;
        ASSERT_GT(voxelBytes, 0u);
        continue;
      }
      folder.setWriteLimit(before + static_cast<std::uint64_t>(share * voxelBytes));
      testing::expectScratchFull(folder, [&] { buildScratchVoxelElements(folder, scratch, field, cut, options, kTinyPass); });
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir.dir()));
  }
}

}  // namespace
}  // namespace seamvox
