#include "stream/param_stream.h"

#include "core/basis/islands.h"
#include "core/basis/voxel_grid.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <complex>
#include <future>
#include <iterator>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "core/basis/voxel_basis.h"
#include "core/field/field_proxy.h"
#include "core/solve/param_solver.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"
#include "stream/cone_pass_stream.h"
#include "stream/cut_stream.h"
#include "stream/field_stream.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"
#include "stream/refine_stream.h"
#include "stream/untangle_stream.h"
#include "stream/voxel_solve_stream.h"
#include "stream/voxel_stream.h"
#include "stream/wound_count.h"
#include "stream/welded_scratch.h"

namespace seamvox {

namespace {

/// The voxel basis and its Vox solve; when the system cannot be factored, built again with the
/// B-splines that barely touch the surface joined to a neighbour (as the in-memory voxel solvers).
struct VoxStage {
  ScratchVoxelBasis basis;
  ScratchVoxelSolution solved;
};

/// The voxel basis' options of a pass (islands: the faces left out).
VoxelBasisOptions voxelBasisOptions(const StreamParamOptions& options, double h, const std::vector<FaceId>& islands) {
  VoxelBasisOptions basis;
  basis.gridResolution = options.gridResolution;
  basis.edgeLength = h;
  basis.progress = options.progress;
  basis.leftOut = islands;
  return basis;
}

VoxStage solveVox(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                  VoxelBasisOptions basisOptions, const RoundOptions& round, const StreamPassOptions& pass,
                  StageMeter& meter, std::string& retryReason, ScratchVoxelClip* clip,
                  const std::function<void()>& beforeSolve) {
  VoxStage out;
  try {
    out.basis = buildScratchVoxelBasis(folder, scratch, field, cut, basisOptions, pass, clip);
    meter.finish("basis");
    if (beforeSolve) beforeSolve();
    out.solved = solveScratchVoxelMap(folder, scratch, cut, out.basis, round, pass);
  } catch (const SolverError& first) {
    // Nearly dependent B-splines that barely touch the surface: joined to a neighbour and solved
    // again, the fragments and integrals kept (parameterizeMeshVoxel's second attempt).
    if (!out.basis.basis || !(basisOptions.minDomainWeight < kRetryMinDomainWeight)) throw;
    retryReason = first.what();
    out.basis.basis->joinDomains(kRetryMinDomainWeight);
    if (beforeSolve) beforeSolve();
    out.solved = solveScratchVoxelMap(folder, scratch, cut, out.basis, round, pass);
  }
  meter.finish("solve");
  return out;
}

/// measureSeams and measureMap (with the field, h given, no cones) of the out-of-core map: the
/// seams' edges through page caches, the faces in order with their corners' wedges and
/// directions read alongside; a flipped face is tested against the smoothed surface.
void measureScratchMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                       const ScratchCut& cut, const ScratchMap& map, double h, const StreamPassOptions& pass,
                       StreamParamResult& r) {
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  {
    PagedFacePoints points(scratch, scratch.positions, cacheBytes);
    PagedReader<Vec2d> values(map.wedgeValues, cacheBytes);
    PagedReader<std::uint32_t> cornerWedge(map.cornerWedge, cacheBytes);
    PagedReader<CornerId> opposite(scratch.opposite, cacheBytes);
    r.seamQuality = measureSeams(
        cut.seams, [&](CornerId c) { return values[cornerWedge[c]]; }, [&](CornerId c) { return opposite[c]; },
        [&](CornerId c) {
          const Triangle t = points.triangle(cornerFace(c));
          const std::array<Vec3d, 3> p = points.points(t);
          return (p[(c + 1) % 3] - p[(c + 2) % 3]).norm();
        });
    folder.countRead("metrics", points.bytesRead() + values.bytesRead() + cornerWedge.bytesRead() + opposite.bytesRead());
  }
  std::optional<PagedReader<Vec3f>> smooth;
  if (field.framePositions.bytes > 0) smooth.emplace(field.framePositions, cacheBytes);
  MapQualitySums sums(h);
  ScratchMapFaces faces(folder, scratch, map, "metrics", cacheBytes);
  // Wound vertices: the corners' angles summed per vertex, a corner on an edge without another
  // side marking its vertex as boundary.
  ManifoldWoundCounter wound(folder, scratch.numVertices, pass.memoryBytes / 2, "metrics: wound");
  ReaderPool<PagedReader<CornerId>> opposites(
      [&] { return std::make_unique<PagedReader<CornerId>>(scratch.opposite, cacheBytes); });
  ScratchReader directions(folder, field.directions, "metrics");
  // Faces a block at a time in order (looked up in parallel), measured in parallel in fixed
  // chunks whose sums are added in order (the same figures at any thread count); flipped faces
  // tested after, the corners' angles added to their vertices in order.
  constexpr std::size_t kChunkFaces = 4096;
  std::vector<Vec3f> blockDirections;
  std::vector<std::array<float, 3>> angles;  // woundCornerAngle per corner
  std::vector<MapQualitySums> chunkSums;
  std::vector<std::vector<std::uint32_t>> chunkFlipped;
  while (const std::vector<MapFace>* faceBlock = faces.nextBlock()) {
    const std::vector<MapFace>& block = *faceBlock;
    blockDirections.resize(block.size());
    angles.resize(block.size());
    if (!directions.read(blockDirections.data(), block.size() * sizeof(Vec3f))) {
      throw IoError(field.directions.path + ": scratch file ends early");
    }
    const std::size_t chunks = (block.size() + kChunkFaces - 1) / kChunkFaces;
    chunkSums.assign(chunks, MapQualitySums(h));
    chunkFlipped.assign(chunks, {});
    parallelForEach(chunks, 1, [&](std::uint64_t c) {
      auto opposite = opposites.take();
      for (std::size_t i = c * kChunkFaces; i < std::min(block.size(), (c + 1) * kChunkFaces); ++i) {
        const MapFace& x = block[i];
        const Vec3d u = blockDirections[i].cast<double>();
        if (chunkSums[c].add(x.p, x.q, &u) == MapQualitySums::Kind::Flipped) {
          chunkFlipped[c].push_back(static_cast<std::uint32_t>(i));
        }
        for (std::uint32_t j = 0; j < 3; ++j) {
          const CornerId corner = 3 * x.f + j;
          const bool onBoundary =
              (*opposite)[nextCorner(corner)] == kInvalidId || (*opposite)[prevCorner(corner)] == kInvalidId;
          angles[i][j] = woundCornerAngle(x.q[j], x.q[(j + 1) % 3], x.q[(j + 2) % 3], onBoundary);
        }
      }
    });
    for (std::size_t i = 0; i < block.size(); ++i) {
      for (int j = 0; j < 3; ++j) wound.add(block[i].t[j], angles[i][j]);
    }
    for (std::size_t c = 0; c < chunks; ++c) {
      sums.merge(chunkSums[c]);
      for (const std::uint32_t i : chunkFlipped[c]) {
        const Triangle& t = block[i].t;
        if (smooth && faceFoldedIn3D(block[i].p, (*smooth)[t[0]], (*smooth)[t[1]], (*smooth)[t[2]])) sums.countFolded();
      }
    }
  }
  r.mapQuality = sums.finish();
  r.mapQuality.wound = wound.count();
  r.mapQuality.woundCounted = true;
  std::uint64_t oppositeBytes = 0;
  opposites.forEach([&](PagedReader<CornerId>& opposite) { oppositeBytes += opposite.bytesRead(); });
  folder.countRead("metrics", faces.cacheBytesRead() + oppositeBytes + (smooth ? smooth->bytesRead() : 0));
}

/// One cone pass's solve through the cut: voxel basis and Vox solve, then the local refinement;
/// the map and the seams' translations out.
void solveScratchPass(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                      const StreamParamOptions& options, const StreamPassOptions& pass, StageMeter& meter,
                      const std::vector<FaceId>& islands, ScratchVoxelClip* clip, StreamParamResult& r, ScratchMap& map,
                      std::vector<std::complex<double>>& translations, std::optional<std::vector<FaceId>>& flipCandidates) {
  const double h = r.edgeLength;
  const VoxelBasisOptions basisOptions = voxelBasisOptions(options, h, islands);
  r.islandFaces = basisOptions.leftOut.size();
  RoundOptions round;
  round.progress = options.progress;
  VoxStage vox = solveVox(folder, scratch, field, cut, basisOptions, round, pass, meter, r.voxelRetryReason, clip,
                          options.beforeVoxelSolve);
  ScratchVoxelSolution& solved = vox.solved;
  r.solve = solved.stats;
  r.translationConstraints = solved.translationConstraints;
  r.determinedBasis = solved.determinedBasis;
  r.inconsistentBasis = solved.inconsistentBasis;
  r.failedAttempts = solved.failedAttempts;
  r.domains = vox.basis.basis->numDomains();
  r.basisFunctions = vox.basis.basis->numBasisFunctions();
  r.elements = vox.basis.basis->numElements();
  r.fragments = vox.basis.numFragments;
  // voxloc's refinement seeds from the map: read off by the smoothed evaluation's pass.
  ScratchMapSeeds mapSeeds;
  mapSeeds.edgeLength = h;
  mapSeeds.collapseThreshold = options.refine.collapseThreshold;
  if (options.smoothedEvaluation) {
    r.smoothedEvaluation = evaluateScratchFoldsAtSmoothedSurface(folder, scratch, field, vox.basis, solved.coefficients,
                                                                 h, solved.map, pass, options.voxLoc ? &mapSeeds : nullptr);
  }
  std::vector<std::complex<double>>().swap(solved.coefficients);

  // voxloc refines near cones and wherever the map collapses or flips; vox only where its
  // reduction left basis functions inconsistent (as parameterizeMeshWithSolver).
  // The islands are mapped by the local hat solve: every face of theirs seeds it.
  std::vector<FaceId> seeds = withFaces(
      scratchSupportFaces(folder, vox.basis, options.voxLoc ? solved.markedBasis : solved.inconsistentBasisFunctions),
      basisOptions.leftOut);
  const double voxelSize = vox.basis.basis->grid().voxelSize;
  for (const ScratchFile* file : {&vox.basis.fragments, &vox.basis.fragmentElement, &vox.basis.faceFragmentStart}) {
    if (!file->path.empty()) folder.remove(*file);
  }
  vox.basis = ScratchVoxelBasis();  // the grid-sized basis, before the local solves
  r.markedFaces = seeds.size();
  std::vector<FaceId> changed;  // by the refinement
  if (options.voxLoc || !seeds.empty()) {
    RefineOptions refine = options.refine;
    refine.edgeLength = h;
    refine.markedFaces = std::move(seeds);
    refine.islandFaces = basisOptions.leftOut;
    refine.seedFromMap = options.voxLoc;
    refine.flipsToRepair = options.untangle;
    if (!options.voxLoc) refine.maxRounds = 1;
    if (options.voxLoc && refine.splineCells > 0) refine.splineSpacing = voxelSize / refine.splineCells;
    if (!refine.progress) refine.progress = options.progress;
    const RefineResult refinement =
        refineScratchNearCones(folder, scratch, field, cut, solved.map, solved.translations, refine, pass, &mapSeeds,
                               &changed);
    applyScratchRefinement(folder, refinement, solved.map, &solved.translations, pass);
    r.refined = true;
    r.refine = refinement.stats;
    meter.finish("refine");
  }
  map = solved.map;
  translations = std::move(solved.translations);
  // The faces the map may flip now, for the repair to read instead of every face: the seeds'
  // flipped faces and the faces the refinement changed (below a positive threshold every
  // flipped face is a flipped seed).
  flipCandidates.reset();
  if (mapSeeds.known && mapSeeds.collapseThreshold > 0.0) {
    std::vector<FaceId> flipped, candidates;
    for (std::size_t i = 0; i < mapSeeds.faces.size(); ++i) {
      if (mapSeeds.kinds[i] == RefineSeed::Flipped) flipped.push_back(mapSeeds.faces[i]);
    }
    std::set_union(flipped.begin(), flipped.end(), changed.begin(), changed.end(), std::back_inserter(candidates));
    flipCandidates = std::move(candidates);
  }
}

}  // namespace

StreamParamResult parameterizeOutOfCore(MeshStream& stream, ScratchFolder& folder, const StreamParamOptions& options) {
  if (!options.writeMap) throw InputError("param out of core: no writer for the map");
  std::unique_ptr<StageMeter> ownMeter;
  if (!options.meter) ownMeter = std::make_unique<StageMeter>();
  StageMeter& meter = options.meter ? *options.meter : *ownMeter;
  const StreamPassOptions pass{options.memoryBytes};
  const StreamPassOptions early{std::max(options.memoryBytes, options.earlyMemoryBytes)};
  StreamParamResult r;

  WeldStreamOptions weld;
  weld.weld = options.weld;
  weld.memoryBytes = early.memoryBytes;
  weld.census = false;  // what `info` prints; param uses none of it
  const CleanScratch scratch = [&] {
    const WeldStreamResult welded = weldMeshStream(stream, folder, weld);
    r.inputFaces = welded.census.inputFaces;
    meter.finish("weld");
    for (const auto& [name, seconds] : welded.census.stageSeconds) r.passSeconds.emplace_back("weld: " + name, seconds);
    CleanStreamOptions clean;
    clean.memoryBytes = early.memoryBytes;
    clean.islandFaces = kVoxelIslandFaces;
    CleanScratch cleaned = cleanWeldedMesh(folder, welded.scratch, welded.census, clean);
    for (const auto& [name, seconds] : cleaned.stageSeconds) r.passSeconds.emplace_back("clean: " + name, seconds);
    r.cleanGluing = cleaned.gluing;
    folder.remove(welded.scratch.faces);
    folder.remove(welded.scratch.positions);
    return cleaned;
  }();
  r.cleanReport = scratch.report;
  r.faces = scratch.numFaces;
  r.vertices = scratch.numVertices;
  meter.finish("clean");
  reportProgress(options.progress, "clean", 1.0);

  // h from the diagonal without spikes, as the in-memory pipeline takes it.
  r.diagonal = scratch.report.diagonalWithoutSpikes;
  r.edgeLength = options.spacing.spacing(r.diagonal);
  const double h = r.edgeLength;
  // The field's surface as the in-memory pipeline's (its rough spots smoothed within h).
  FieldGeometryOptions geometry;
  geometry.smoothingIterations = options.fieldSmoothing;
  geometry.roughSpotGrid = options.roughSpots ? h : 0.0;
  ScratchField field = computeScratchField(folder, scratch, ProxyFieldOptions(), geometry, early, true);
  r.roughVertices = field.roughVertices;
  r.roughSpotVertices = field.roughSpotVertices;
  r.roughSpotsCapped = field.roughSpotsCapped;
  r.fieldElements = field.elements;
  for (const auto& [name, seconds] : field.stageSeconds) r.passSeconds.emplace_back("field: " + name, seconds);
  meter.finish("field");
  reportProgress(options.progress, "field", 1.0);

  std::vector<std::pair<std::string, double>> cutSeconds;
  StageClock cutClock(cutSeconds);
  ScratchSingularities singularities = computeScratchSingularities(folder, scratch, field, early);
  // The cones were read with the rough spots smoothed; the stages after them read the smoothed
  // surface with their moves along the normal only, as in memory (setFrameOverridesAside).
  if (!field.mapPositions.path.empty()) {
    folder.remove(field.framePositions);
    field.framePositions = std::exchange(field.mapPositions, ScratchFile());
  }
  r.conesBeforeMerge = static_cast<std::uint32_t>(singularities.cones.size());
  cutClock.finish("cut: singularities");
  ConeMergeOptions merge;
  merge.maxDistance = options.mergeCones * h;
  r.merged = mergeScratchCones(folder, scratch, singularities, merge, early);
  cutClock.finish("cut: merge");
  for (auto& entry : cutSeconds) r.passSeconds.push_back(std::move(entry));
  const double coincidentDistance = kCoincidentSearchFraction * h;
  // The cone passes (parameterize's solveConePasses): cut, solve, refine and repair; again with
  // the cone pairs the map put on one point, or close cones with flips left at them after the
  // repair, merged. Each pass's merges go onto the singularities the last pass cut through.
  ScratchCut cut;
  ScratchMap map;
  std::vector<std::complex<double>> translations;
  const auto removePass = [&](const ScratchCut& c, const ScratchMap& m) {
    for (const ScratchFile* file : {&c.corners, &c.faceRotation, &m.vertexWedgeStart, &m.cornerWedge, &m.wedgeValues}) {
      if (!file->path.empty()) folder.remove(*file);
    }
  };
  // The best pass that started another after its repair (parameterize's KeptPass).
  struct KeptPass {
    StreamParamResult r;
    ScratchCut cut;
    ScratchMap map;
    std::vector<std::complex<double>> translations;
  };
  std::optional<KeptPass> kept;
  // The islands (components too small for the voxel basis) and the first pass's voxel clip
  // depend on the mesh alone. The islands come from the cleaning (found beside its front pass) or
  // else are read off the first cut's dual tree; then the clip runs on a thread of its own while
  // the cut walks on one core, with a quarter of the pass's memory beside the cut's page caches (a
  // quarter of the early passes'). The clip then waits for the first pass's basis.
  struct Ahead {
    std::vector<FaceId> islands;
    ScratchVoxelClip clip;
    double clipSeconds = 0.0;
  };
  std::future<Ahead> ahead;
  const auto clipAhead = [&](std::vector<FaceId> faces) {
    ahead = std::async(std::launch::async, [&, faces = std::move(faces)]() mutable {
      Ahead a;
      a.islands = std::move(faces);
      const auto start = std::chrono::steady_clock::now();
      a.clip = clipScratchFaces(folder, scratch, voxelBasisOptions(options, h, a.islands), pass);
      a.clipSeconds = secondsSince(start);
      return a;
    });
  };
  const TreeIslands treeIslands{kVoxelIslandFaces, clipAhead};
  if (scratch.islands) clipAhead(*scratch.islands);
  std::optional<std::vector<FaceId>> islands;
  std::optional<ScratchVoxelClip> firstClip;
  std::optional<std::vector<FaceId>> flipCandidates;  // see solveScratchPass
  for (;;) {
    ++r.conePasses;
    cut = cutScratchToDisk(folder, scratch, singularities, early, islands || scratch.islands ? nullptr : &treeIslands);
    for (const auto& [name, seconds] : cut.stageSeconds) r.passSeconds.emplace_back("cut: " + name, seconds);
    r.cones = cut.cones;
    std::sort(r.cones.begin(), r.cones.end());
    r.coneIndex4.clear();
    for (VertexId v : r.cones) r.coneIndex4.push_back(coneIndexOf(singularities, v));
    r.seams = static_cast<std::uint32_t>(cut.seams.size());
    r.components = cut.components;
    meter.finish("cut");
    reportProgress(options.progress, "cut", 1.0);
    ScratchVoxelClip* clip = nullptr;
    if (!islands) {
      Ahead a = ahead.get();
      islands = std::move(a.islands);
      firstClip = std::move(a.clip);
      clip = &*firstClip;
      r.passSeconds.emplace_back("basis: voxel clip (beside the cut)", a.clipSeconds);
    }
    solveScratchPass(folder, scratch, field, cut, options, pass, meter, *islands, clip, r, map, translations,
                     flipCandidates);
    firstClip.reset();

    const bool passesLeft = options.mergeCones > 0.0 && r.conePasses < options.maxConePasses;
    // Another pass with these pairs merged: this pass's cut and map go, or are kept (afterRepair:
    // the best such pass so far, in case the next ends with more flips).
    const auto nextPass = [&](const std::vector<std::pair<VertexId, VertexId>>& pairs, bool afterRepair = false) {
      if (pairs.empty()) return false;
      if (afterRepair) {
        if (kept) removePass(kept->cut, kept->map);
        kept = KeptPass{r, std::move(cut), map, std::move(translations)};
        cut = ScratchCut();
      } else {
        removePass(cut, map);
      }
      map = ScratchMap();
      r.merged.add(mergeScratchCoincidentCones(folder, scratch, singularities, pairs, coincidentDistance, early));
      r.refined = false;
      r.refine = RefineStats();
      r.untangled = false;
      r.untangle = UntangleStats();
      r.untangleWindowFaces = 0;
      return true;
    };
    // Adjacent cones on one point: another pass before any repair (the faces between them collapse).
    if (passesLeft && nextPass(scratchMergeableCoincidentCones(folder, scratch, singularities, map, 0.0, pass))) continue;
    if (options.untangle) {
      UntangleOptions untangle = options.untangleOptions;
      untangle.edgeLength = h;
      if (!untangle.progress) untangle.progress = options.progress;
      // Close cones on one point with flips next to them: repaired first alone; when flips stay
      // next to them another pass starts before the whole map is repaired.
      UntangleStats nearCones;
      if (passesLeft) {
        const auto suspects = scratchFoldedCoincidentCones(folder, scratch, singularities, map, h, coincidentDistance, pass);
        if (!suspects.empty()) {
          const FacesNearPoints near = facesNearConePairs(scratch, suspects, coincidentDistance, pass);
          nearCones = untangleScratchFlips(folder, scratch, field, cut, map, translations, untangle, pass, &near).untangle;
          flipCandidates.reset();  // that repair changed faces beyond them
          if (nextPass(scratchFoldedCoincidentCones(folder, scratch, singularities, map, h, coincidentDistance, pass))) {
            meter.finish("untangle");  // the repair next to the cones, this pass's last step
            continue;
          }
        }
      }
      UntangleOptions whole = untangle;
      whole.conesNotRetried = &nearCones.conesLeftShort;
      ScratchUntangleStats repaired = untangleScratchFlips(folder, scratch, field, cut, map, translations, whole,
                                                           pass, nullptr, flipCandidates ? &*flipCandidates : nullptr);
      addEarlierRepair(repaired.untangle, nearCones);
      resolveScratchLeftoverFlips(folder, scratch, field, cut, map, translations, options.refine, untangle, pass, repaired);
      r.untangled = true;
      r.untangle = repaired.untangle;
      r.untangleWindowFaces = repaired.windowFaces;
      meter.finish("untangle");
      r.conePassFlips.push_back(r.untangle.flippedAfter);
      // Close cones with flips left at them: merging them can move the flips away, the repair
      // with the cones fixed cannot; not again after a pass that did not leave fewer.
      if (passesLeft && r.untangle.flippedAfter > 0 && (!kept || r.untangle.flippedAfter < kept->r.untangle.flippedAfter) &&
          nextPass(scratchFoldedConesAfterRepair(folder, scratch, singularities, map, h, coincidentDistance, pass),
                   true)) {
        continue;
      }
    }
    break;
  }
  r.conePassKept = r.conePasses;
  if (kept && kept->r.untangle.flippedAfter <= r.untangle.flippedAfter) {
    removePass(cut, map);
    const std::uint32_t passes = r.conePasses;
    std::vector<std::pair<std::string, double>> passSeconds = std::move(r.passSeconds);
    std::vector<std::uint64_t> passFlips = std::move(r.conePassFlips);
    r = std::move(kept->r);
    r.conePassKept = r.conePasses;
    r.conePasses = passes;
    r.passSeconds = std::move(passSeconds);
    r.conePassFlips = std::move(passFlips);
    cut = std::move(kept->cut);
    map = kept->map;
    translations = std::move(kept->translations);
  } else if (kept) {
    removePass(kept->cut, kept->map);
  }
  kept.reset();
  folder.remove(singularities.matching);
  r.wedges = map.numWedges;

  options.writeMap(scratch, map);
  meter.finish("write");
  measureScratchMap(folder, scratch, field, cut, map, h, pass, r);
  meter.finish("metrics");
  return r;
}

}  // namespace seamvox
