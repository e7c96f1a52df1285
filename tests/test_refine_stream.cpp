// The local refinement out of core (stream/refine_stream) equals refineNearCones on the cleaned
// mesh read back from the scratch, with the same field, cut and Vox map: the same rounds and
// figures, the same solved corners bit for bit, the same translations; applied to the map, the
// same wedges and values, also where a wedge is split. Tiny page caches, small solve groups.
#include <gtest/gtest.h>

#include <algorithm>
#include <complex>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "core/mesh/wedge_map.h"
#include "core/refine/refine.h"
#include "core/basis/voxel_grid.h"
#include "core/system/errors.h"
#include "stream/refine_stream.h"
#include "stream/voxel_solve_stream.h"
#include "stream/voxel_stream.h"
#include "stream_testing.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::forEachCleaned;
using testing::NamedMeshes;
using testing::readRecords;

const StreamPassOptions kTinyPass{1, 300};

void expectSameStats(const RefineStats& got, const RefineStats& want) {
  EXPECT_EQ(std::make_tuple(got.markedFaces, got.collapsedFaces, got.flippedFaces, got.regionFaces),
            std::make_tuple(want.markedFaces, want.collapsedFaces, want.flippedFaces, want.regionFaces));
  EXPECT_EQ(std::make_tuple(got.freeVertices, got.lockedVertices, got.solves, got.totalUnknowns, got.unknowns),
            std::make_tuple(want.freeVertices, want.lockedVertices, want.solves, want.totalUnknowns, want.unknowns));
  EXPECT_EQ(std::make_tuple(got.collapsedAfter, got.collapsedAtConesAfter, got.flippedAfter, got.unresolvedFaces),
            std::make_tuple(want.collapsedAfter, want.collapsedAtConesAfter, want.flippedAfter, want.unresolvedFaces));
  EXPECT_EQ(std::make_tuple(got.failedSolves, got.failedSolveReason), std::make_tuple(want.failedSolves, want.failedSolveReason));
  EXPECT_EQ(got.refinedVertexFraction, want.refinedVertexFraction);
  EXPECT_EQ(std::make_tuple(got.splineVertices, got.splineVertexFraction),
            std::make_tuple(want.splineVertices, want.splineVertexFraction));
  ASSERT_EQ(got.rounds.size(), want.rounds.size());
  for (std::size_t k = 0; k < want.rounds.size(); ++k) {
    const RefineRound &a = got.rounds[k], &b = want.rounds[k];
    EXPECT_EQ(a.spline, b.spline) << "round " << k;
    EXPECT_EQ(std::make_tuple(a.seedFaces, a.regionFaces, a.freeVertices, a.unknowns, a.collapsed, a.flipped, a.borderFaces),
              std::make_tuple(b.seedFaces, b.regionFaces, b.freeVertices, b.unknowns, b.collapsed, b.flipped, b.borderFaces))
        << "round " << k;
  }
}

// The out-of-core result's corners are in its map already (compared by expectSameMap).
void expectSameResult(const RefineResult& got, const RefineResult& want) {
  EXPECT_TRUE(got.corners.empty());
  EXPECT_EQ(got.seams, want.seams);
  EXPECT_EQ(got.seamT, want.seamT);
  expectSameStats(got.stats, want.stats);
}

// The out-of-core map and the one in memory: the same wedge per corner and the same values.
void expectSameMap(ScratchFolder& folder, const ScratchMap& got, const WedgeMap& want) {
  ASSERT_EQ(got.numWedges, want.numWedges());
  const std::vector<std::uint32_t> cornerWedge = readRecords<std::uint32_t>(folder, got.cornerWedge);
  const std::vector<Vec2d> values = readRecords<Vec2d>(folder, got.wedgeValues);
  ASSERT_EQ(cornerWedge.size(), want.size());
  ASSERT_EQ(values.size(), want.numWedges());
  std::size_t wrongWedge = 0, wrongValue = 0;
  for (CornerId c = 0; c < want.size(); ++c) wrongWedge += cornerWedge[c] != want.wedge(c);
  for (std::uint32_t w = 0; w < want.numWedges(); ++w) wrongValue += values[w] != want.wedgeValue(w);
  EXPECT_EQ(wrongWedge, 0u);
  EXPECT_EQ(wrongValue, 0u);
}

struct Case {
  const char* name;
  bool voxLoc;
  double collapseThreshold;
  std::uint32_t rings;
  bool damaged = false;
  bool failSome = false;  // every third group's solve fails: it keeps its input map
  bool spline = false;    // the first round in B-splines, half a voxel apart
};

// Moves the values of every corner of some vertices far off in both maps (as the refinement's
// results are applied), so that their faces flip.
void damageMaps(ScratchFolder& folder, const Topology& topology, WedgeMap& map, ScratchMap& streamed) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  RefineResult edits;
  for (int k = 0; k < 30; ++k) {
    const VertexId v = std::uniform_int_distribution<VertexId>(0, topology.numVertices() - 1)(random);
    const Vec2d offset(uniform(random), uniform(random));
    topology.forEachCornerAround(v, [&](CornerId c) { edits.corners.push_back({map[c] + offset, c, true}); });
  }
  std::sort(edits.corners.begin(), edits.corners.end(),
            [](const RefinedCorner& x, const RefinedCorner& y) { return x.corner < y.corner; });
  edits.corners.erase(std::unique(edits.corners.begin(), edits.corners.end(),
                                  [](const RefinedCorner& x, const RefinedCorner& y) { return x.corner == y.corner; }),
                      edits.corners.end());
  applyRefinement(edits, map);
  applyScratchRefinement(folder, edits, streamed, nullptr, kTinyPass);
}

// Every corner's value in a scratch map.
std::vector<Vec2d> cornerValues(ScratchFolder& folder, const ScratchMap& map) {
  const std::vector<std::uint32_t> wedge = testing::readRecords<std::uint32_t>(folder, map.cornerWedge);
  const std::vector<Vec2d> values = testing::readRecords<Vec2d>(folder, map.wedgeValues);
  std::vector<Vec2d> out(wedge.size());
  for (std::size_t c = 0; c < wedge.size(); ++c) out[c] = values.at(wedge[c]);
  return out;
}

// voxloc (marked faces and the map's bad faces seed, rounds), vox (the inconsistent functions'
// faces only, one round: the faces outside are counted by a pass over the files) and voxloc with
// collapses not seeded (the pass counts the faces outside too); voxloc without rings, so that bad
// faces stay at the region's border and later rounds grow patches around them.
TEST(RefineStream, RefinementEqualsTheInMemoryOne) {
  const NamedMeshes meshes = testing::stageTestMeshes(31);
  std::uint64_t solves = 0, laterRounds = 0, outsideCounted = 0, batched = 0, failedSolves = 0, splineMoved = 0,
                changedCorners = 0;
  forEachCleaned(meshes, [&](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const testing::StageInputs in = testing::prepareStageInputs(folder, scratch, cleaned, 32, kTinyPass);
    ParamOptions param;
    param.edgeLength = in.options.edgeLength;
    param.smoothedEvaluation = false;  // the Vox map as solveScratchVoxelMap gives it
    const VoxelParamResult expected =
        parameterizeMeshVoxel(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut, param, 32);
    ScratchVoxelBasis basis = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    for (const Case& c : {Case{"voxloc", true, 0.1, 1}, Case{"vox", false, 0.1, 1}, Case{"voxloc, no collapses", true, 0.0, 1},
                         Case{"voxloc, no rings", true, 0.1, 0}, Case{"voxloc, damaged map", true, 0.1, 0, true},
                         Case{"voxloc, failed solves", true, 0.1, 1, false, true},
                         Case{"voxloc, spline round", true, 0.1, 1, false, false, true}}) {
      SCOPED_TRACE(c.name);
      // A fresh Vox map each time: applying changes it.
      ScratchVoxelSolution solved = solveScratchVoxelMap(folder, scratch, in.cut, basis, RoundOptions{}, kTinyPass);
      ASSERT_EQ(solved.translations, expected.param.translations);
      WedgeMap inMemoryMap = expected.param.cornerUV;
      if (c.damaged) damageMaps(folder, cleaned.topology, inMemoryMap, solved.map);
      RefineOptions options;
      options.edgeLength = param.edgeLength;
      options.markedFaces = c.voxLoc ? expected.markedFaces : expected.inconsistentFaces;
      if (c.damaged) options.markedFaces.clear();
      options.seedFromMap = c.voxLoc;
      options.collapseThreshold = c.collapseThreshold;
      options.maxRounds = c.voxLoc ? 6 : 1;
      options.rings = c.rings;
      options.groupFaces = 200;  // several groups solved in parallel, each with its own page caches
      if (c.failSome) options.groupFails = [](FaceId first) { return first % 3 == 0; };
      if (c.spline) {
        options.splineSpacing = basis.basis->grid().voxelSize / 2;
        options.splineMaxFraction = 1.0;  // B-splines wherever they are fewer than the vertices
      }
      const RefineResult want = refineNearCones(cleaned.mesh, cleaned.topology, in.inMemoryField, in.inMemoryCut,
                                                inMemoryMap, expected.param.translations, options);
      const std::vector<Vec2d> valuesBefore = cornerValues(folder, solved.map);
      std::vector<FaceId> changed;
      const RefineResult got = refineScratchNearCones(folder, scratch, in.field, in.cut, solved.map,
                                                      solved.translations, options, kTinyPass, nullptr, &changed);
      expectSameResult(got, want);
      // The faces it says it changed: increasing, and every corner with a new value on one.
      EXPECT_TRUE(std::is_sorted(changed.begin(), changed.end()) &&
                  std::adjacent_find(changed.begin(), changed.end()) == changed.end());
      const std::vector<Vec2d> valuesAfter = cornerValues(folder, solved.map);
      ASSERT_EQ(valuesAfter.size(), valuesBefore.size());
      std::size_t unlisted = 0;
      for (CornerId k = 0; k < valuesAfter.size(); ++k) {
        if (valuesAfter[k] == valuesBefore[k]) continue;
        ++changedCorners;
        unlisted += !std::binary_search(changed.begin(), changed.end(), cornerFace(k));
      }
      EXPECT_EQ(unlisted, 0u);
      failedSolves += want.stats.failedSolves;
      splineMoved += want.stats.splineVertices;
      if (c.failSome) EXPECT_NE(want.stats.failedSolveReason.find("test hook"), std::string::npos);
      EXPECT_EQ(want.stats.batches, want.stats.rounds.size());
      batched += got.stats.batches > want.stats.batches;  // several batches a round, each applied at once
      solves += want.stats.solves;
      laterRounds += want.stats.rounds.size() > 1;
      outsideCounted += !options.seedFromMap || options.collapseThreshold == 0.0;
      // Applied: the same wedges, values and translations (the out-of-core corners went into
      // solved.map while the rounds ran).
      WedgeMap map = inMemoryMap;
      std::vector<std::complex<double>> translations = expected.param.translations;
      applyRefinement(want, map, &translations);
      applyScratchRefinement(folder, got, solved.map, &solved.translations, kTinyPass);
      expectSameMap(folder, solved.map, map);
      EXPECT_EQ(solved.translations, translations);
    }
  });
  EXPECT_GT(solves, 3u);
  EXPECT_GT(laterRounds, 0u);  // a border that needed another round somewhere
  EXPECT_GT(batched, 0u);
  EXPECT_GT(failedSolves, 0u);
  EXPECT_GT(outsideCounted, 0u);
  EXPECT_GT(splineMoved, 0u);
  EXPECT_GT(changedCorners, 0u);
}

// Corners given values that split their wedges (part of a wedge, or two values in one wedge):
// the out-of-core map splits them as WedgeMap::assign does, the new wedges appended.
TEST(RefineStream, SplitWedgesAsInMemory) {
  const NamedMeshes meshes = testing::stageTestMeshes(37);
  std::uint64_t grown = 0;
  forEachCleaned(meshes, [&](ScratchFolder& folder, const CleanScratch& scratch, const CleanResult& cleaned) {
    const testing::StageInputs in = testing::prepareStageInputs(folder, scratch, cleaned, 16, kTinyPass);
    ScratchVoxelBasis basis = buildScratchVoxelBasis(folder, scratch, in.field, in.cut, in.options, kTinyPass);
    ScratchVoxelSolution solved = solveScratchVoxelMap(folder, scratch, in.cut, basis, RoundOptions{}, kTinyPass);
    WedgeMap map(readRecords<std::uint32_t>(folder, solved.map.cornerWedge), readRecords<Vec2d>(folder, solved.map.wedgeValues));
    std::mt19937 random(3);
    std::uniform_real_distribution<double> uniform(-5.0, 5.0);
    const Topology& topology = cleaned.topology;
    RefineResult edits;
    for (int trial = 0; trial < 40; ++trial) {
      const VertexId v = std::uniform_int_distribution<VertexId>(0, topology.numVertices() - 1)(random);
      std::vector<CornerId> fan;
      topology.forEachCornerAround(v, [&](CornerId c) { fan.push_back(c); });
      const Vec2d a(uniform(random), uniform(random)), b(uniform(random), uniform(random));
      for (std::size_t k = 0; k < fan.size(); ++k) {
        if (trial % 3 == 0 && k == 0) continue;  // part of a wedge keeps its value
        edits.corners.push_back({trial % 3 == 1 && k % 2 ? b : a, fan[k], true});
      }
    }
    std::sort(edits.corners.begin(), edits.corners.end(),
              [](const RefinedCorner& x, const RefinedCorner& y) { return x.corner < y.corner; });
    edits.corners.erase(std::unique(edits.corners.begin(), edits.corners.end(),
                                    [](const RefinedCorner& x, const RefinedCorner& y) { return x.corner == y.corner; }),
                        edits.corners.end());
    const std::uint32_t before = map.numWedges();
    applyRefinement(edits, map);
    applyScratchRefinement(folder, edits, solved.map, nullptr, kTinyPass);
    expectSameMap(folder, solved.map, map);
    grown += map.numWedges() - before;
    // Bad ids are refused before anything changes.
    RefineResult bad;
    bad.corners.push_back({Vec2d(1.0, 2.0), CornerId(3 * scratch.numFaces), true});
    EXPECT_THROW(applyScratchRefinement(folder, bad, solved.map, nullptr, kTinyPass), InputError);
    bad.corners.clear();
    bad.seams.push_back(static_cast<std::uint32_t>(solved.translations.size()));
    bad.seamT.push_back({1.0, 0.0});
    EXPECT_THROW(applyScratchRefinement(folder, bad, solved.map, &solved.translations, kTinyPass), InputError);
    expectSameMap(folder, solved.map, map);
  });
  EXPECT_GT(grown, 0u);
}

}  // namespace
}  // namespace seamvox
