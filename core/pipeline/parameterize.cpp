// The whole pipeline as one call: clean, field, cone passes (merge, cut, solve), quality.
#include "core/pipeline/parameterize.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>

#include "core/field/rough_spots.h"
#include "core/mesh/hole_caps.h"
#include "core/refine/merge_in_map.h"
#include "core/refine/refine.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"

namespace seamvox {

CrossField computeFieldFromSource(TriangleMesh& mesh, const Topology& topology,
                                  const std::vector<FaceId>& faceOrigin, std::uint32_t inputFaces,
                                  const FieldSource& source, const ProgressFn& progress,
                                  FieldSolveStats* stats) {
  if (!source.importedPerInputFace.empty()) {
    if (source.importedPerInputFace.size() != inputFaces) {
      throw InputError("the field has " + std::to_string(source.importedPerInputFace.size()) +
                       " vectors for a mesh of " + std::to_string(inputFaces) + " faces");
    }
    std::vector<Vec3d> perFace(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) perFace[f] = source.importedPerInputFace[faceOrigin[f]];
    return projectToTangent(mesh, perFace);
  }
  SmoothFieldOptions smooth;
  smooth.curvatureWeight = source.curvatureWeight;
  smooth.alignCorners = source.alignCorners;
  smooth.progress = progress;
  smooth.stats = stats;
  ProxyFieldOptions proxy;
  proxy.progress = progress;
  proxy.stats = stats;
  FieldGeometryOptions geometry;
  geometry.roughSpotGrid = source.roughSpots ? source.gridLength : 0.0;
  geometry.roughSpotMaxRegion = source.roughSpotMaxRegion;
  geometry.smoothingIterations = source.smoothingSteps;
  return computeCrossField(mesh, topology, resolveFieldMethod(source.method, mesh.numFaces()), smooth, proxy, geometry);
}

std::optional<FieldSource> alignedFieldSource(const Topology& topology, const FeatureSet& features,
                                              const FieldSource& source, std::uint32_t numFaces) {
  if (features.empty() || !source.importedPerInputFace.empty() ||
      resolveFieldMethod(source.method, numFaces) != FieldMethod::Direct) {
    return std::nullopt;
  }
  FieldSource aligned;
  aligned.method = source.method;
  aligned.curvatureWeight = source.curvatureWeight;
  aligned.alignCorners = featureSideCorners(topology, features);
  aligned.gridLength = source.gridLength;
  aligned.roughSpotMaxRegion = source.roughSpotMaxRegion;
  aligned.roughSpots = source.roughSpots;
  aligned.smoothingSteps = source.smoothingSteps;
  return aligned;
}

ConeCut cutThroughCones(const TriangleMesh& mesh, const Topology& topology, CrossField& field,
                        double mergeDistance,
                        const std::vector<std::pair<VertexId, VertexId>>& coincident,
                        double coincidentDistance, const ProgressFn& progress, PackedSingularities* reuse) {
  ConeCut result;
  if (reuse && !reuse->empty()) {
    result.singularities = unpackSingularities(*reuse);
  } else {
    result.singularities = computeSingularitiesReleasingFrames(mesh, topology, field);
    if (reuse) *reuse = packSingularities(result.singularities);
  }
  result.conesBeforeMerge = static_cast<std::uint32_t>(result.singularities.cones.size());
  ConeMergeOptions mergeOptions;
  mergeOptions.maxDistance = mergeDistance;
  result.merged = mergeCloseCones(mesh, topology, result.singularities, mergeOptions);
  result.merged.add(mergeCoincidentCones(mesh, topology, result.singularities, coincident, coincidentDistance));
  CutOptions cutOptions;
  cutOptions.progress = progress;
  result.cut = cutToDisk(mesh, topology, field, result.singularities, cutOptions);
  return result;
}

namespace {

/// Cone pairs the map put on one point, adjacent or close (coincidentCones), that may still be
/// merged (canMergeCoincident).
std::vector<std::pair<VertexId, VertexId>> mergeableCoincidentCones(
    const TriangleMesh& mesh, const Topology& topology, const std::vector<VertexId>& cones,
    const std::unordered_map<VertexId, std::int32_t>& coneIndex, const WedgeMap& map, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> pairs;
  for (const auto& [a, b] : coincidentCones(mesh, topology, cones, map, maxDistance)) {
    if (canMergeCoincident(coneIndex.at(a), coneIndex.at(b))) pairs.push_back({a, b});
  }
  return pairs;
}

/// Per face: its centroid within maxDistance of a cone of `pairs`.
std::vector<std::uint8_t> facesNearCones(const TriangleMesh& mesh,
                                         const std::vector<std::pair<VertexId, VertexId>>& pairs, double maxDistance) {
  std::vector<Vec3d> cones;
  for (const auto& [a, b] : pairs) cones.push_back(mesh.position(a)), cones.push_back(mesh.position(b));
  std::vector<std::uint8_t> near(mesh.numFaces(), 0);
  if (cones.empty()) return near;
  // A centroid that near a cone lies in the cones' box grown by the distance (a little more, for
  // rounding): most faces are decided by the box alone.
  Vec3d low = cones.front(), high = cones.front();
  for (const Vec3d& p : cones) low = low.cwiseMin(p), high = high.cwiseMax(p);
  const double grow = maxDistance * (1.0 + 1e-6);
  low.array() -= grow;
  high.array() += grow;
  parallelFor(mesh.numFaces(), 1u << 14, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const Vec3d c = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
      if ((c.array() < low.array()).any() || (c.array() > high.array()).any()) continue;
      near[f] = std::any_of(cones.begin(), cones.end(), [&](const Vec3d& p) { return (c - p).norm() <= maxDistance; });
    }
  });
  return near;
}

/// Cone pairs the map put on one point within maxDistance of each other along edges
/// (coincidentCones), mergeable, with a face still flipped within maxDistance of one of them. The
/// pairs come first (a few cones' wedges): only faces whose centroid lies that close to one of
/// their cones are measured, and none when there is no pair.
std::vector<std::pair<VertexId, VertexId>> foldedCoincidentCones(
    const PipelineResult& r, const std::vector<VertexId>& cones,
    const std::unordered_map<VertexId, std::int32_t>& coneIndex, double maxDistance) {
  const auto candidates = mergeableCoincidentCones(r.mesh, r.topology, cones, coneIndex,
                                                   r.solved.param.cornerUV, maxDistance);
  if (candidates.empty()) return {};
  const std::vector<std::uint8_t> near = facesNearCones(r.mesh, candidates, maxDistance);
  const WedgeMap& map = r.solved.param.cornerUV;
  std::vector<std::uint8_t> flipped(r.mesh.numFaces(), 0);
  parallelFor(r.mesh.numFaces(), 1u << 14, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      flipped[f] = near[f] && isFlippedRatio(parameterAreaRatio(r.mesh, map, f, r.edgeLength));
    }
  });
  std::vector<Vec3d> centroids;
  for (FaceId f = 0; f < r.mesh.numFaces(); ++f) {
    if (!flipped[f]) continue;
    const Triangle& t = r.mesh.triangles[f];
    centroids.push_back((r.mesh.position(t[0]) + r.mesh.position(t[1]) + r.mesh.position(t[2])) / 3.0);
  }
  const auto nearFlip = [&](VertexId v) {
    const Vec3d p = r.mesh.position(v);
    return std::any_of(centroids.begin(), centroids.end(), [&](const Vec3d& q) { return (q - p).norm() <= maxDistance; });
  };
  std::vector<std::pair<VertexId, VertexId>> pairs;
  for (const auto& [a, b] : candidates) {
    if (nearFlip(a) || nearFlip(b)) pairs.push_back({a, b});
  }
  return pairs;
}

/// After the repair: the pairs of foldedCoincidentCones and of foldedCloseCones (flipped faces at
/// both cones, which the repair holds).
std::vector<std::pair<VertexId, VertexId>> foldedConesAfterRepair(
    const PipelineResult& r, const std::vector<VertexId>& cones,
    const std::unordered_map<VertexId, std::int32_t>& coneIndex, double maxDistance) {
  std::vector<std::pair<VertexId, VertexId>> pairs = foldedCoincidentCones(r, cones, coneIndex, maxDistance);
  std::vector<std::int32_t> index4;
  for (VertexId v : cones) index4.push_back(coneIndex.at(v));
  for (const auto& pair : foldedCloseCones(r.mesh, r.topology, cones, index4, r.solved.param.cornerUV, r.edgeLength,
                                           maxDistance)) {
    pairs.push_back(pair);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

/// Merges each of `pairs` in the pass's map (mergeConesInMap), updating coneIndex and
/// r.conesMergedInMap. False when one cannot be: the pass must start again with the pairs merged in
/// the field, and the map as it is is discarded.
bool mergePairsInMap(PipelineResult& r, const CrossField& field, CutResult& cut,
                     std::unordered_map<VertexId, std::int32_t>& coneIndex,
                     const std::vector<std::pair<VertexId, VertexId>>& pairs, const MergeInMapOptions& options) {
  r.solved.forgetFlipCandidates();  // the merges re-solve patches of the map
  // A cone merged away stands for the one that took its index (three cones on one point).
  std::unordered_map<VertexId, VertexId> mergedInto;
  const auto current = [&](VertexId v) {
    for (auto it = mergedInto.find(v); it != mergedInto.end(); it = mergedInto.find(v)) v = it->second;
    return v;
  };
  for (const auto& pair : pairs) {
    const VertexId a = current(pair.first), b = current(pair.second);
    if (a == b) continue;
    const auto ia = coneIndex.find(a), ib = coneIndex.find(b);
    if (ia == coneIndex.end() || ib == coneIndex.end() || !canMergeCoincident(ia->second, ib->second)) return false;
    const MergeInMapResult merged = mergeConesInMap(r.mesh, r.topology, field, cut, r.solved.param.cornerUV,
                                                    r.solved.param.translations, a, ia->second, b, ib->second, options);
    if (!merged.merged) return false;
    mergedInto[merged.gone] = merged.kept;
    coneIndex.erase(merged.gone);
    if (merged.keptIndex4 == 0) {
      coneIndex.erase(merged.kept);
    } else {
      coneIndex[merged.kept] = merged.keptIndex4;
    }
    ++r.conesMergedInMap;
  }
  return true;
}

/// Curves of `features` the map could not hold on integer iso-lines without squeezing faces (two
/// curves rounded onto one line, a curve forced through a cone's point): per cluster of collapsed
/// faces (|parameter area| below kCollapsedAreaFraction, not between coincident cones; faces
/// sharing a vertex cluster), the shortest curve with an edge at one of its vertices, or with
/// `all` every such curve. Returns the features without them; `released` counts them.
FeatureSet releaseCollapsingCurves(const TriangleMesh& mesh, const Topology& topology,
                                   const FeatureSet& features, const WedgeMap& cornerUV, double h,
                                   const std::vector<VertexId>& cones, bool all, std::uint32_t& released) {
  std::vector<std::uint8_t> isCone(mesh.numVertices(), 0);
  for (VertexId v : cones) isCone[v] = 1;
  std::vector<FaceId> squeezedFaces;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const double ratio = parameterAreaRatio(mesh, cornerUV, f, h);
    if (std::abs(ratio) < kCollapsedAreaFraction && !collapsesBetweenCones(mesh, cornerUV, f, isCone)) {
      squeezedFaces.push_back(f);
    }
  }
  // Clusters: components of the collapsed faces (groups of one component each), per vertex.
  const std::vector<std::vector<FaceId>> clusters = splitRegion(topology, squeezedFaces, 1);
  std::vector<std::pair<VertexId, std::uint32_t>> squeezed;
  for (std::uint32_t k = 0; k < clusters.size(); ++k) {
    for (FaceId f : clusters[k]) {
      for (VertexId v : mesh.triangles[f]) squeezed.push_back({v, k});
    }
  }
  std::sort(squeezed.begin(), squeezed.end());
  const auto clusterAt = [&](VertexId v) -> std::uint32_t {
    const auto it = std::lower_bound(squeezed.begin(), squeezed.end(), std::make_pair(v, 0u));
    return it != squeezed.end() && it->first == v ? it->second : kInvalidId;
  };
  // Per cluster the shortest curve touching it (or every one).
  std::vector<std::uint32_t> chosen(clusters.size(), kInvalidId);
  std::vector<std::uint8_t> release(features.numCurves(), 0);
  const auto length = [&](std::uint32_t k) { return features.curveStart[k + 1] - features.curveStart[k]; };
  for (std::uint32_t k = 0; k < features.numCurves(); ++k) {
    for (std::uint32_t i = features.curveStart[k]; i < features.curveStart[k + 1]; ++i) {
      const CornerId c = features.curveEdges[i];
      for (VertexId v : {topology.vertex(nextCorner(c)), topology.vertex(prevCorner(c))}) {
        const std::uint32_t cluster = clusterAt(v);
        if (cluster == kInvalidId) continue;
        if (all) release[k] = 1;
        std::uint32_t& best = chosen[cluster];
        if (best == kInvalidId || length(k) < length(best)) best = k;
      }
    }
  }
  for (std::uint32_t k : chosen) {
    if (k != kInvalidId) release[k] = 1;
  }
  FeatureSet kept;
  kept.boundaryEdges = features.boundaryEdges;
  kept.creaseEdges = features.creaseEdges;
  kept.curveStart.push_back(0);
  released = 0;
  for (std::uint32_t k = 0; k < features.numCurves(); ++k) {
    if (release[k]) {
      ++released;
      continue;
    }
    kept.curveEdges.insert(kept.curveEdges.end(), features.curveEdges.begin() + features.curveStart[k],
                           features.curveEdges.begin() + features.curveStart[k + 1]);
    kept.curveStart.push_back(static_cast<std::uint32_t>(kept.curveEdges.size()));
  }
  return kept;
}

/// With PipelineOptions::closeHoles (no imported field: it has no vectors for the caps): the small
/// holes capped in place by fans for the field and the whole solve (hole_caps.h), so the field does
/// not turn inside them and the map is closed over them; uncapForOutput takes the caps off again.
CappedHoles capForSolve(PipelineResult& r, const FieldSource& source, const PipelineOptions& options) {
  if (!(options.closeHoles > 0.0 && options.capHoles && source.importedPerInputFace.empty())) return {};
  CappedHoles caps = capSmallHoles(r.mesh, r.topology, options.closeHoles * r.edgeLength);
  r.fieldCappedHoles = caps.holes;
  return caps;
}

/// The mesh, field, map and cones without the caps: the map keeps its values on the mesh's own
/// corners (seamless there as on the capped surface); a cone at a cap's centre goes with it.
void uncapForOutput(PipelineResult& r, CrossField& field, CappedHoles& caps) {
  if (caps.holes == 0) return;
  r.solved.param.cornerUV.keepCorners(3 * std::size_t(caps.faces));
  uncapHoles(r.mesh, r.topology, caps);
  field.direction.resize(caps.faces);
  if (!field.framePositions.empty()) field.framePositions.resize(caps.vertices);
  auto& overrides = field.frameOverrides;  // sorted by vertex: the caps' centres come last
  overrides.erase(std::lower_bound(overrides.begin(), overrides.end(), std::make_pair(caps.vertices, Vec3f(Vec3f::Zero())),
                                   [](const auto& a, const auto& b) { return a.first < b.first; }),
                  overrides.end());
  std::vector<VertexId> cones;
  std::vector<std::int32_t> index4;
  for (std::size_t k = 0; k < r.cones.size(); ++k) {
    if (r.cones[k] >= caps.vertices) continue;
    cones.push_back(r.cones[k]);
    index4.push_back(r.coneIndex4[k]);
  }
  r.cones = std::move(cones);
  r.coneIndex4 = std::move(index4);
  for (std::vector<FaceId>* faces : {&r.solved.param.unsolvedFaces, &r.solved.param.anchoredFaces}) {
    faces->erase(std::remove_if(faces->begin(), faces->end(), [&](FaceId f) { return f >= caps.faces; }),
                 faces->end());
  }
  caps = CappedHoles();
}

/// The hat re-solve of the flips the repair left on a voxel map (UntangleOptions::leftoverRadius),
/// then the repair again from there; r.untangle becomes the figures of both repairs.
void resolveLeftoverFlips(PipelineResult& r, const CrossField& field, const CutResult& cut, RefineOptions refine,
                          const UntangleOptions& untangle) {
  if (r.untangle.flippedAfter == 0 || !(untangle.leftoverRadius > 0.0) || r.solved.solver == ParamSolver::Hat) return;
  const auto start = SteadyClock::now();
  // The whole map's repair lists every flip it leaves (UntangleStats::leftFaces); after the
  // re-solve only those and the re-solved faces are measured again.
  const std::vector<FaceId>& left = r.untangle.leftFaces;
  double edges = 0.0;
  for (FaceId f : left) {
    const Triangle& t = r.mesh.triangles[f];
    for (int k = 0; k < 3; ++k) edges += (r.mesh.position(t[(k + 1) % 3]) - r.mesh.position(t[k])).norm();
  }
  refine.edgeLength = r.edgeLength;
  const double meanEdge = edges / (3.0 * double(left.size()));
  RefineOptions local = leftoverRefineOptions(refine, left, meanEdge, untangle.leftoverRadius);
  local.regionOnly = true;
  const RefineResult resolved = refineNearConesInPlace(r.mesh, r.topology, field, cut, r.solved.param.cornerUV,
                                                       r.solved.param.translations, local);
  const double seconds = secondsSince(start);
  std::vector<FaceId> candidates;
  std::set_union(left.begin(), left.end(), resolved.regionFaces.begin(), resolved.regionFaces.end(),
                 std::back_inserter(candidates));
  UntangleOptions again = untangle;
  again.candidateFaces = &candidates;
  again.conesNotRetried = &r.untangle.conesLeftShort;
  UntangleStats repaired =
      untangleFlips(r.mesh, r.topology, field, cut, r.solved.param.cornerUV, r.solved.param.translations, again);
  addLeftoverRepair(repaired, r.untangle, resolved.stats.regionFaces, resolved.stats.freeVertices, seconds);
  r.untangle = std::move(repaired);
}

/// The cone passes: merge and cut, solve; again with the pairs a solve put on one point merged,
/// or close cones with flips left at them after the repair, while there are such pairs (at most
/// options.maxConePasses passes).
void solveConePasses(PipelineResult& r, CrossField& field, const PipelineOptions& options,
                     StageMeter& meter) {
  ParamOptions param;
  std::vector<CornerId> featureCorners = featureSideCorners(r.topology, r.features);
  if (r.featureFieldAligned) param.featureCorners = &featureCorners;
  FeatureSet held = r.features;  // the curves the solve holds on iso-lines
  param.edgeLength = r.edgeLength;
  param.closeHolesWithin = options.closeHoles * r.edgeLength;
  param.greedyRounding = options.greedyRounding;
  param.coneWeightRadius = options.coneWeightRadius;
  param.progress = options.progress;
  param.failsToFactor = options.failsToFactor;
  param.mapViewsTriangles = true;  // r.mesh and r.topology outlive the map unchanged (uncapForOutput edits per corner)
  SolverOptions solverOptions = options.solver;
  solverOptions.meter = &meter;  // closes "solve" and "refine"
  bool directionsStored = false;
  if (options.directionStore) {
    solverOptions.fieldIdle = [&] {
      options.directionStore->store(field.direction);
      directionsStored = true;
    };
    solverOptions.fieldNeeded = [&] {
      if (!directionsStored) return;
      options.directionStore->load(field.direction);
      directionsStored = false;
    };
  }
  solverOptions.refine.coneWeightRadius = options.coneWeightRadius;
  solverOptions.refine.closeHolesWithin = param.closeHolesWithin;
  solverOptions.refine.flipsToRepair = options.untangle;
  const double mergeDistance = options.mergeCones * r.edgeLength;
  const double coincidentDistance = kCoincidentSearchFraction * r.edgeLength;
  std::vector<std::pair<VertexId, VertexId>> coincident;
  // The field's singularities before merging, kept for a later pass (0.75 B per face) instead of
  // recomputing them on the smoothed surface (a quarter of a pass at 22M faces); not above the
  // memory budget (the field's directions on disk).
  const bool keepSingularities = !options.directionStore && options.mergeCones > 0.0 && options.maxConePasses > 1;
  PackedSingularities fieldSingularities;
  // The best pass that started another after its repair (flips left next to close cones): a
  // later pass replaces it only with fewer flips, since the new cut changes seams everywhere.
  struct KeptPass {
    SolverResult solved;
    CutResult cut;
    std::unordered_map<VertexId, std::int32_t> coneIndex;
    UntangleStats untangle;
    ConeMergeResult merged;
    std::uint32_t pass = 0;
  };
  std::optional<KeptPass> kept;
  // The cones are read on the field's surface with its rough spots smoothed; the stages after the
  // cut (smoothed evaluation, refinement, repair, the metrics' fold test) on the plain smoothed
  // surface with those moves along the normal only (setFrameOverridesAside).
  std::vector<std::pair<VertexId, Vec3f>> roughMoves;
  for (;;) {
    ++r.conePasses;
    putFrameOverridesBack(field, roughMoves);
    if (fieldSingularities.empty()) restoreFramePositions(r.mesh, r.topology, field);
    ConeCut coneCut = cutThroughCones(r.mesh, r.topology, field, mergeDistance, coincident, coincidentDistance,
                                      options.progress, keepSingularities ? &fieldSingularities : nullptr);
    setFrameOverridesAside(r.mesh, r.topology, field, roughMoves);
    // The cut released the smoothed surface: until the next pass's cones only the 3D-fold test of
    // a few flipped faces reads it, and recomputes it around them.
    if (r.conePasses == 1) r.conesBeforeMerge = coneCut.conesBeforeMerge;
    r.merged = coneCut.merged;  // each pass merges the field's cones afresh
    std::unordered_map<VertexId, std::int32_t> coneIndex;
    for (VertexId v : coneCut.singularities.cones) coneIndex[v] = coneCut.singularities.index4[v];
    coneCut.singularities = FieldSingularities();  // the cut keeps the combed matchings and cones
    meter.finish("cut");
    r.solved = parameterizeMeshWithSolver(r.mesh, r.topology, field, coneCut.cut, param, solverOptions);
    // Curves at faces the map collapsed are released (the shortest per cluster; from round
    // releaseRounds on, every one, at most releaseRounds more times: a release can make the solve
    // collapse faces next to another curve) and the map solved again.
    const std::uint32_t releaseRounds = options.maxFeatureReleaseRounds;
    for (std::uint32_t round = 0; releaseRounds > 0 && round <= 2 * releaseRounds && param.featureCorners &&
                                  r.solved.param.lines.applied > 0;
         ++round) {
      std::uint32_t released = 0;
      held = releaseCollapsingCurves(r.mesh, r.topology, held, r.solved.param.cornerUV, r.edgeLength,
                                     coneCut.cut.cones, round >= releaseRounds, released);
      if (released == 0) break;
      r.featureCurvesReleased += released;
      featureCorners = featureSideCorners(r.topology, held);
      r.solved = SolverResult{};
      r.solved = parameterizeMeshWithSolver(r.mesh, r.topology, field, coneCut.cut, param, solverOptions);
    }
    // Adjacent cones on one point: another pass before any repair (the faces between them collapse).
    const bool passesLeft = options.mergeCones > 0.0 && r.conePasses < options.maxConePasses;
    MergeInMapOptions inMap;
    inMap.edgeLength = r.edgeLength;
    inMap.radius = kCoincidentSearchFraction;
    inMap.coneWeightRadius = options.coneWeightRadius;
    inMap.closeHolesWithin = param.closeHolesWithin;
    if (passesLeft) {
      const auto pairs = mergeableCoincidentCones(r.mesh, r.topology, coneCut.cut.cones, coneIndex,
                                                  r.solved.param.cornerUV, 0.0);
      // Merged in the map or not, a later pass merges them in the field.
      coincident.insert(coincident.end(), pairs.begin(), pairs.end());
      if (!pairs.empty() && !(options.mergeInMap && mergePairsInMap(r, field, coneCut.cut, coneIndex, pairs, inMap))) {
        r.solved = SolverResult{};  // free the map before the next pass
        continue;
      }
    }
    if (options.untangle) {
      UntangleOptions untangle = options.untangleOptions;
      untangle.edgeLength = r.edgeLength;
      untangle.coneWeightRadius = options.coneWeightRadius;
      untangle.closeHolesWithin = param.closeHolesWithin;
      untangle.progress = options.progress;
      // Close cones on one point with flips next to them (below) start another pass, which
      // repairs its own map: they are repaired first alone, and when flips stay next to them the
      // pass starts before the whole map is repaired.
      UntangleStats nearCones;
      if (passesLeft) {
        const auto suspects = foldedCoincidentCones(r, coneCut.cut.cones, coneIndex, coincidentDistance);
        if (!suspects.empty()) {
          r.solved.forgetFlipCandidates();  // the repair next to the cones may move any face
          const std::vector<std::uint8_t> near = facesNearCones(r.mesh, suspects, coincidentDistance);
          UntangleOptions local = untangle;
          local.onlyFaces = &near;
          nearCones = untangleFlips(r.mesh, r.topology, field, coneCut.cut, r.solved.param.cornerUV,
                                    r.solved.param.translations, local);
          const auto pairs = foldedCoincidentCones(r, coneCut.cut.cones, coneIndex, coincidentDistance);
          coincident.insert(coincident.end(), pairs.begin(), pairs.end());
          if (!pairs.empty() &&
              !(options.mergeInMap && mergePairsInMap(r, field, coneCut.cut, coneIndex, pairs, inMap))) {
            r.solved = SolverResult{};
            meter.finish("untangle");  // the repair next to the cones, this pass's last step
            continue;
          }
        }
      }
      untangle.conesNotRetried = &nearCones.conesLeftShort;
      // The refinement's faces are the only ones a voxloc map may have flipped: only they are measured.
      if (r.solved.flipCandidatesKnown) untangle.candidateFaces = &r.solved.flipCandidates;
      r.untangle = untangleFlips(r.mesh, r.topology, field, coneCut.cut, r.solved.param.cornerUV,
                                 r.solved.param.translations, untangle);
      untangle.candidateFaces = nullptr;
      r.solved.forgetFlipCandidates();
      addEarlierRepair(r.untangle, nearCones);
      untangle.conesNotRetried = nullptr;
      resolveLeftoverFlips(r, field, coneCut.cut, solverOptions.refine, untangle);
      r.untangled = true;
      meter.finish("untangle");
      r.conePassFlips.push_back(r.untangle.flippedAfter);
      // Close cones with flips left at them: the repair cannot move them (their seams'
      // translations fix them), merging them can; on a noisy scan most such pairs are harmless
      // and merging them all costs flips elsewhere, so only these. Not again after a pass that
      // did not leave fewer flips than the best such pass.
      if (passesLeft && r.untangle.flippedAfter > 0 && (!kept || r.untangle.flippedAfter < kept->untangle.flippedAfter)) {
        const auto pairs = foldedConesAfterRepair(r, coneCut.cut.cones, coneIndex, coincidentDistance);
        const std::uint64_t keptBytes = r.solved.param.cornerUV.memoryBytes() + coneCut.cut.corners.memoryBytes() +
                                        coneCut.cut.faceRotation.memoryBytes();
        if (!pairs.empty() && keptBytes > options.passHeadroomBytes) r.conePassSkippedForMemory = true;
        if (!pairs.empty() && keptBytes <= options.passHeadroomBytes) {
          coincident.insert(coincident.end(), pairs.begin(), pairs.end());
          kept = KeptPass{std::move(r.solved), std::move(coneCut.cut), std::move(coneIndex), r.untangle, r.merged,
                          r.conePasses};
          r.solved = SolverResult{};
          r.untangle = UntangleStats{};
          r.untangled = false;
          continue;
        }
      }
    }
    r.solved.forgetFlipCandidates();  // without a repair, nothing reads them
    r.conePassKept = r.conePasses;
    if (kept && kept->untangle.flippedAfter <= r.untangle.flippedAfter) {
      r.solved = std::move(kept->solved);
      coneCut.cut = std::move(kept->cut);
      coneIndex = std::move(kept->coneIndex);
      r.untangle = kept->untangle;
      r.merged = kept->merged;
      r.conePassKept = kept->pass;
    }
    r.cones = coneCut.cut.cones;
    std::sort(r.cones.begin(), r.cones.end());
    r.coneIndex4.clear();
    for (VertexId v : r.cones) r.coneIndex4.push_back(coneIndex.at(v));
    r.seams = static_cast<std::uint32_t>(coneCut.cut.seams.size());
    r.seamQuality = measureSeams(r.mesh, r.topology, coneCut.cut, r.solved.param.cornerUV);
    r.featureLines = r.solved.param.lines;
    r.featureCurves = measureFeatureAlignment(r.topology, r.features, r.solved.param.cornerUV);
    return;
  }
}

/// Runs work (if any) on a thread of its own; join() waits and rethrows what it threw. An
/// exception leaving the scope first still waits for the thread (its own error is then lost).
class BesideThread {
 public:
  explicit BesideThread(std::function<void()> work) {
    if (!work) return;
    thread_ = std::thread([this, work = std::move(work)] {
      try {
        work();
      } catch (...) {
        error_ = std::current_exception();
      }
    });
  }
  BesideThread(const BesideThread&) = delete;
  BesideThread& operator=(const BesideThread&) = delete;
  ~BesideThread() {
    if (thread_.joinable()) thread_.join();
  }
  void join() {
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  std::thread thread_;
  std::exception_ptr error_;
};

/// Per-component figures, and with options.dropUnsolved the unsolved components removed (the
/// corner table rebuilt for the smaller mesh).
void summarizeMappedComponents(PipelineResult& r, const PipelineOptions& options,
                               const std::vector<FaceId>& flippedFaces) {
  std::vector<FaceId> unsolvedFaces;
  r.components = summarizeComponents(r.mesh, r.topology, r.cones, r.solved.param.unsolvedFaces,
                                     r.solved.param.anchoredFaces, r.edgeLength,
                                     options.listComponents, &unsolvedFaces, &flippedFaces);
  if (!options.dropUnsolved || unsolvedFaces.empty()) return;
  r.components.droppedIds = r.components.unsolvedIds;
  r.components.droppedFaces = unsolvedFaces.size();
  std::vector<VertexId> vertexMap;
  r.mesh = removeFaces(r.mesh, unsolvedFaces, &vertexMap);
  r.topology = Topology::build(r.mesh.triangles, r.mesh.numVertices());
  std::vector<VertexId> cones;
  std::vector<std::int32_t> index4;
  for (std::size_t k = 0; k < r.cones.size(); ++k) {
    if (vertexMap[r.cones[k]] == kInvalidId) continue;
    cones.push_back(vertexMap[r.cones[k]]);
    index4.push_back(r.coneIndex4[k]);
  }
  r.cones = std::move(cones);  // still sorted: the map keeps the vertex order
  r.coneIndex4 = std::move(index4);
}

}  // namespace

PipelineResult parameterize(TriangleMesh raw, const PipelineOptions& options) {
  options.spacing.validate();
  std::unique_ptr<StageMeter> ownMeter;
  if (!options.meter) ownMeter = std::make_unique<StageMeter>();
  StageMeter& meter = options.meter ? *options.meter : *ownMeter;

  PipelineResult r;
  r.inputFaces = raw.numFaces();
  CleanOptions cleanOptions = options.clean;
  cleanOptions.progress = options.progress;
  CleanResult clean = cleanMesh(std::move(raw), cleanOptions);
  std::vector<VertexId>().swap(clean.vertexOrigin);  // faceOrigin stays for an imported field
  r.mesh = std::move(clean.mesh);
  r.topology = std::move(clean.topology);
  r.cleanReport = clean.report;
  meter.finish("clean");

  // Only the direct field follows creases and only the hat solver holds them: the automatic
  // feature angle runs where both would (not above the direct field's size, with an imported
  // field, or where the solver, counting the feature-aligned map's solves, is not hat); otherwise
  // it would cost a pass over every edge and an aligned field for curves nothing aligns.
  FeatureOptions asked = options.features;
  asked.autoFeatureAngle = asked.autoFeatureAngle && options.field.importedPerInputFace.empty() &&
                           resolveFieldMethod(options.field.method, r.mesh.numFaces()) == FieldMethod::Direct &&
                           chooseParamSolver(options.solver.solver, r.mesh.numFaces(), options.solver.gridResolution,
                                             true).solver == ParamSolver::Hat;
  const FeatureOptions featureOptions = resolveFeatureAngle(r.mesh, r.topology, asked, r.featureAngleAuto);
  r.featureAngle = featureOptions.featureAngle;
  r.features = findFeatures(r.mesh, r.topology, featureOptions);
  std::optional<FieldSource> aligned = alignedFieldSource(r.topology, r.features, options.field, r.mesh.numFaces());
  r.featureFieldAligned = aligned.has_value();
  // Only an imported field reads the faces' input ids: otherwise they go now (4 bytes per face).
  if (options.field.importedPerInputFace.empty()) std::vector<FaceId>().swap(clean.faceOrigin);
  r.diagonal = r.cleanReport.diagonalWithoutSpikes;  // a spike would inflate h
  r.edgeLength = options.spacing.spacing(r.diagonal);
  r.fieldMethod = options.field.importedPerInputFace.empty()
                      ? fieldMethodName(resolveFieldMethod(options.field.method, r.mesh.numFaces()))
                      : "file";
  FieldSource source = aligned ? *aligned : options.field;
  aligned.reset();
  source.gridLength = r.edgeLength;
  source.roughSpotMaxRegion = roughRegionBoundInMemory(r.mesh.numVertices(), options.passHeadroomBytes);
  // The field's method as the mesh's own size picks it (the caps' faces do not count).
  source.method = resolveFieldMethod(source.method, r.mesh.numFaces());
  CappedHoles caps = capForSolve(r, source, options);
  CrossField field = computeFieldFromSource(r.mesh, r.topology, clean.faceOrigin, r.inputFaces, source,
                                            options.progress, &r.fieldSolve);
  std::vector<FaceId>().swap(clean.faceOrigin);
  meter.finish("field");

  solveConePasses(r, field, options, meter);
  if (options.withSolvedMap) {
    std::swap(r.mesh.cornerUV, r.solved.param.cornerUV);  // an input's own UVs wait meanwhile
    options.withSolvedMap(r.mesh, r.topology);
    std::swap(r.mesh.cornerUV, r.solved.param.cornerUV);
  }
  uncapForOutput(r, field, caps);
  r.mesh.cornerUV = std::move(r.solved.param.cornerUV);
  // The final map goes to withFinalMap beside the figures, which only read the mesh, unless
  // unsolved components are to be dropped from it after them, or the run has one thread.
  r.finalMapBesideMetrics = options.withFinalMap && (!options.dropUnsolved || r.solved.param.unsolvedFaces.empty()) &&
                            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
  {
    BesideThread finalMap(r.finalMapBesideMetrics ? [&] { options.withFinalMap(r.mesh); } : std::function<void()>());
    std::vector<FaceId> flippedFaces;
    r.mapQuality = measureMap(r.mesh, r.mesh.cornerUV, &field, r.edgeLength, nullptr, &r.topology, &flippedFaces);
    field = CrossField();  // before the per-component figures (10 bytes per face)
    summarizeMappedComponents(r, options, flippedFaces);
    finalMap.join();
  }
  if (options.withFinalMap && !r.finalMapBesideMetrics) options.withFinalMap(r.mesh);
  r.size = {r.mesh.numFaces(), r.mesh.numVertices(), r.mesh.cornerUV.numWedges(), r.mesh.cornerUV.memoryBytes(),
            r.mesh.attributes.describe(), r.mesh.attributes.memoryBytes()};
  meter.finish("metrics");
  return r;
}

}  // namespace seamvox
