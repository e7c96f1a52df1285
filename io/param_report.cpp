// The JSON report of a parameterization: counts, system sizes, refinement, quality, stages.
#include "io/param_report.h"

#include "core/pipeline/parameterize.h"
#include "core/system/blas_threads.h"
#include "io/json.h"

namespace seamvox {

namespace {

using U64 = std::uint64_t;

void writeSystem(JsonWriter& j, const PipelineResult& r) {
  const ParamResult& p = r.solved.param;
  const SeamlessStats& st = p.stats;
  j.key("system").beginObject();
  j.key("basisFunctions").value(U64{p.basisFunctions});
  j.key("domains").value(U64{p.domains});
  j.key("unknowns").value(U64{st.unknowns});
  j.key("positional").value(U64{st.positional});
  j.key("translational").value(U64{st.translational});
  j.key("conePositions").value(U64{st.determinedPositions});
  j.key("translationConstraints").value(U64{p.translationConstraints});
  j.key("smallHoles").value(U64{p.smallHoles});
  j.key("smallHolesRotated").value(U64{p.smallHolesRotated});
  j.key("holesCappedForField").value(U64{r.fieldCappedHoles});
  j.key("nonUnitConstraints").value(U64{st.nonUnitConstraints});
  j.key("pinnedFirstSolve").value(U64{st.pinnedFirst});
  j.key("pinnedSecondSolve").value(U64{st.pinnedSecond});
  j.key("componentsSolvedApart").value(U64{st.componentsApart});
  j.key("matrixNonzeros").value(st.systemNonzeros);
  j.key("factorNonzeros").value(st.factorNonzeros);
  j.key("factorBytes").value(st.factorBytes);
  j.key("factorPeakBytes").value(st.factorPeakBytes);
  j.key("realFallback").value(st.realFallback);
  j.key("maxRoundingShift").value(st.maxRoundingShift);
  j.endObject();
}

void writeVoxel(JsonWriter& j, const SolverResult& s, std::int32_t grid) {
  j.key("voxel").beginObject();
  j.key("grid").value(static_cast<U64>(grid));
  j.key("regularization").value(s.regularization);
  j.key("failedFactorizations").value(U64{s.failedAttempts});
  j.key("invisibleTranslations").value(U64{s.invisibleTranslations});
  j.key("voxels").value(s.basisStats.voxels);
  j.key("elements").value(s.basisStats.elements);
  j.key("basisBytes").value(s.basisStats.bytes);
  j.key("conePositions").value(U64{s.determinedBasis});
  j.key("inconsistentBasis").value(U64{s.inconsistentBasis});
  j.key("markedFaces").value(s.markedFaces);
  j.key("islandFaces").value(s.islandFaces);
  j.key("smoothedEvaluation").beginObject();
  j.key("foldedBefore").value(s.smoothedEvaluation.foldedBefore);
  j.key("vertices").value(s.smoothedEvaluation.vertices);
  j.key("keptForStretch").value(s.smoothedEvaluation.keptForStretch);
  j.key("rounds").value(U64{s.smoothedEvaluation.rounds});
  j.endObject();
  j.endObject();
}

void writeRefineRounds(JsonWriter& j, const RefineStats& refine) {
  j.key("rounds").beginArray();
  for (const RefineRound& round : refine.rounds) {
    j.beginObject();
    j.key("spline").value(round.spline);
    j.key("seedFaces").value(round.seedFaces).key("regionFaces").value(round.regionFaces);
    j.key("freeVertices").value(U64{round.freeVertices});
    j.key("unknowns").value(U64{round.unknowns});
    j.key("collapsed").value(round.collapsed).key("collapsedAtCones").value(round.collapsedAtCones);
    j.key("flipped").value(round.flipped).key("borderFaces").value(round.borderFaces);
    j.key("seconds").value(round.seconds);
    j.endObject();
  }
  j.endArray();
}

void writeRefine(JsonWriter& j, const RefineStats& refine, const ParamReportContext& c) {
  j.key("refine").beginObject();
  j.key("refinedVertexFraction").value(refine.refinedVertexFraction);
  j.key("refinedFractionOffIslands").value(refine.refinedFractionOffIslands);
  j.key("islandVertices").value(U64{refine.islandVertices});
  j.key("freeVertices").value(U64{refine.freeVertices});
  j.key("splineVertices").value(U64{refine.splineVertices});
  j.key("splineVertexFraction").value(refine.splineVertexFraction);
  j.key("lockedVertices").value(U64{refine.lockedVertices});
  j.key("regionFaces").value(refine.regionFaces);
  j.key("markedFaces").value(refine.markedFaces);
  j.key("collapsedFaces").value(refine.collapsedFaces);
  j.key("flippedFaces").value(refine.flippedFaces);
  j.key("rings").value(U64{c.rings});
  j.key("localSolves").value(U64{refine.solves});
  j.key("localUnknownsTotal").value(refine.totalUnknowns);
  j.key("localUnknowns").value(U64{refine.unknowns});
  j.key("localTranslations").value(U64{refine.freeTranslations});
  j.key("localNonzeros").value(refine.systemNonzeros);
  j.key("factorNonzeros").value(refine.factorNonzeros);
  j.key("factorBytes").value(refine.factorBytes);
  j.key("factorPeakBytes").value(refine.factorPeakBytes);
  j.key("seconds").value(refine.secondsTotal);
  // Whole refined map (metrics.h criteria); collapsedAtCones: between coincident cones.
  j.key("collapsedAfter").value(refine.collapsedAfter);
  j.key("collapsedAtConesAfter").value(refine.collapsedAtConesAfter);
  j.key("collapsedBeyondConesAfter").value(refine.collapsedAfter - refine.collapsedAtConesAfter);
  j.key("flippedAfter").value(refine.flippedAfter);
  j.key("unresolvedFaces").value(refine.unresolvedFaces);
  j.key("failedSolves").value(U64{refine.failedSolves});
  j.key("failedSolveReason").value(refine.failedSolveReason);
  j.key("maxRounds").value(U64{c.maxRounds});
  writeRefineRounds(j, refine);
  j.endObject();
}

void writeUntangle(JsonWriter& j, const UntangleStats& u) {
  j.key("untangle").beginObject();
  j.key("flippedBefore").value(u.flippedBefore).key("flippedAfter").value(u.flippedAfter);
  j.key("measuredFaces").value(u.measuredFaces);
  j.key("foldedIn3D").value(u.foldedIn3D);
  j.key("rounds").value(U64{u.rounds}).key("solves").value(U64{u.solves});
  j.key("patchFaces").value(u.patchFaces).key("freeVertices").value(U64{u.freeVertices});
  j.key("largestUnknowns").value(U64{u.largestUnknowns});
  j.key("relocatedVertices").value(U64{u.relocatedVertices}).key("jointVertices").value(U64{u.jointVertices});
  j.key("miswoundCones").value(U64{u.miswoundCones}).key("miswoundConesAfter").value(U64{u.miswoundConesAfter});
  j.key("specks").value(U64{u.specks}).key("speckFaces").value(u.speckFaces);
  j.key("leftover").beginObject();
  j.key("flips").value(u.leftoverFlips).key("regionFaces").value(u.leftoverRegionFaces);
  j.key("freeVertices").value(U64{u.leftoverFreeVertices}).key("flipsAfterResolve").value(u.leftoverAfterResolve);
  j.endObject();
  j.key("seconds").value(u.seconds);
  j.key("stepSeconds").beginObject();
  j.key("rounds").value(u.roundSeconds).key("cones").value(u.coneSeconds);
  j.key("relocation").value(u.relocationSeconds).key("joint").value(u.jointSeconds);
  j.key("leftover").value(u.leftoverSeconds);
  j.endObject();
  j.endObject();
}

void writeFeatures(JsonWriter& j, const PipelineResult& r) {
  j.key("featureCurves").beginObject();
  j.key("total").value(U64{r.featureCurves.total});
  j.key("aligned").value(U64{r.featureCurves.aligned});
  j.key("notAligned").value(U64{r.featureCurves.notAligned});
  j.key("released").value(U64{r.featureCurvesReleased});
  j.key("boundaryEdges").value(U64{r.features.boundaryEdges});
  j.key("creaseEdges").value(U64{r.features.creaseEdges});
  j.key("featureAngle").value(r.featureAngle);
  j.key("featureAngleAuto").value(r.featureAngleAuto);
  j.key("fieldAligned").value(r.featureFieldAligned);
  j.key("constraints").value(U64{r.featureLines.constraints});
  j.key("constraintsApplied").value(U64{r.featureLines.applied});
  j.key("constraintsConflicting").value(U64{r.featureLines.conflicting});
  j.key("constraintsUnsupported").value(U64{r.featureLines.unsupported});
  j.key("largestResidual").value(r.featureCurves.largestResidual);
  j.endObject();
}

void writeQuality(JsonWriter& j, const PipelineResult& r) {
  j.key("quality").beginObject();
  j.key("seamless").value(r.isSeamless());
  j.key("maxSeamResidual").value(r.seamQuality.maxResidual);
  j.key("maxIntegerDistance").value(r.seamQuality.maxIntegerDistance);
  j.key("relativeGradientError").value(r.mapQuality.relativeGradientError);
  j.key("flipped").value(r.mapQuality.flipped).key("flippedFraction").value(r.mapQuality.flippedFraction);
  j.key("flippedFolded").value(r.mapQuality.flippedFolded);
  j.key("collapsed").value(r.mapQuality.collapsed);
  j.key("stretched").value(r.mapQuality.stretched);
  j.key("wound");
  if (r.mapQuality.woundCounted) {
    j.value(r.mapQuality.wound);
  } else {
    j.null();  // out of core: not counted
  }
  j.endObject();
}

void writeSeconds(JsonWriter& j, const PipelineResult& r, const ParamReportContext& c) {
  const ParamResult& p = r.solved.param;
  const SeamlessStats& st = p.stats;
  j.key("seconds").beginObject();
  j.key("read").value(stageSeconds(c.stages, "read")).key("clean").value(stageSeconds(c.stages, "clean"));
  j.key("field").value(stageSeconds(c.stages, "field")).key("cut").value(stageSeconds(c.stages, "cut"));
  j.key("basis").value(p.secondsBasis).key("reduce").value(p.secondsReduce);
  j.key("assemble").value(st.secondsAssemble).key("firstSolve").value(st.secondsFirstSolve);
  j.key("round").value(st.secondsRound).key("secondSolve").value(st.secondsSecondSolve);
  j.key("evaluate").value(p.secondsEvaluate).key("refine").value(r.solved.refine.secondsTotal);
  j.key("metrics").value(stageSeconds(c.stages, "metrics"));
  j.key("write").value(stageSeconds(c.stages, "write")).key("total").value(c.totalSeconds);
  j.endObject();
  j.key("peakResidentBytes").value(c.peakBytes);
  // The BLAS kernels of the factorizations (blas_threads.h): they set much of the solves' time.
  const std::string blasCore = blasCoreName();
  if (!blasCore.empty()) j.key("blasCore").value(blasCore);
  // The OpenMP thread limit the run had (CHOLMOD's teams; rerunWithPreferredRuntime sets it), or
  // "unset" (a library caller's process left it to OpenMP).
  const char* limit = std::getenv("OMP_THREAD_LIMIT");
  j.key("openmpThreadLimit").value(std::string(limit ? limit : "unset"));
  j.key("openmpRegionsInline").value(openmpRegionsInline());
  if (c.memoryPathJson) {
    c.memoryPathJson(j);
  } else if (c.memoryBudget > 0) {
    j.key("path").value(std::string("in-memory"));
    j.key("memoryBudget").value(c.memoryBudget).key("estimatedBytes").value(c.estimatedBytes);
    j.key("fieldBytesOnDisk").value(c.fieldBytesOnDisk);
  }
  // The output written beside the map's figures (its time in "metrics", "write" only commits).
  j.key("writtenBesideMetrics").value(r.finalMapBesideMetrics);
  // Wall time, peak and end resident size of each stage, in order.
  j.key("stages").beginArray();
  for (const StageFigures& stage : c.stages) {
    j.beginObject().key("name").value(stage.name).key("seconds").value(stage.seconds);
    j.key("peakBytes").value(stage.peakBytes).key("endBytes").value(stage.endBytes).endObject();
  }
  j.endArray();
}

void writeCounts(JsonWriter& j, const PipelineResult& r, const ParamReportContext& c) {
  j.key("input").value(c.input).key("output").value(c.output).key("solver").value(c.solverAsked);
  j.key("solverUsed").value(paramSolverName(r.solved.solver));
  j.key("solverReason").value(r.solved.solverReason);
  if (!r.solved.fallbackReason.empty()) j.key("fallbackReason").value(r.solved.fallbackReason);
  if (!r.solved.voxelRetryReason.empty()) j.key("voxelRetryReason").value(r.solved.voxelRetryReason);
  j.key("field").value(c.fieldSource).key("fieldMethod").value(r.fieldMethod);
  j.key("fieldSmoothing").value(U64{c.fieldSmoothing});
  j.key("roughSpots").value(c.roughSpots);
  j.key("faces").value(U64{r.size.faces});
  j.key("vertices").value(U64{r.size.vertices});
  j.key("components").value(U64{r.solved.param.stats.components});
  j.key("anchoredComponents").value(U64{r.solved.param.stats.anchoredComponents});
  j.key("unsolvedComponents").value(U64{r.solved.param.stats.unsolvedComponents});
  j.key("nonManifoldEdgesSplit").value(r.cleanReport.nonManifoldEdges);
  j.key("nonManifoldVerticesSplit").value(r.cleanReport.nonManifoldVertices);
  j.key("spikeVertices").value(r.cleanReport.spikeVertices);
  j.key("unweldedBoundaryVertices").value(r.cleanReport.unweldedBoundaryVertices);
  j.key("reorderedForLocality").value(r.cleanReport.reordered);
  j.key("verticesRenumberedForLocality").value(r.cleanReport.verticesRenumbered);
  j.key("cones").value(static_cast<U64>(r.cones.size()));
  j.key("conesBeforeMerge").value(U64{r.conesBeforeMerge});
  j.key("conesCancelled").value(U64{2 * r.merged.cancelledPairs});
  j.key("conesMerged").value(U64{r.merged.mergedPairs});
  j.key("conesSplit").value(U64{r.merged.splitCones});
  j.key("conePasses").value(U64{r.conePasses});
  j.key("conePassKept").value(U64{r.conePassKept});
  j.key("conePassSkippedForMemory").value(r.conePassSkippedForMemory);
  j.key("conePairsMergedInMap").value(U64{r.conesMergedInMap});
  j.key("conePassFlips").beginArray();
  for (const std::uint64_t flips : r.conePassFlips) j.value(U64{flips});
  j.endArray();
  j.key("seams").value(U64{r.seams});
  j.key("seamEdges").value(r.seamQuality.seamEdges).key("seamLength").value(r.seamQuality.seamLength);
  j.key("wedges").value(U64{r.size.wedges}).key("mapBytes").value(r.size.mapBytes);
  j.key("vertexProperties").value(r.size.attributes).key("vertexPropertyBytes").value(r.size.attributeBytes);
  j.key("edgeLength").value(r.edgeLength);
  j.key("cellsOnDiagonal").value(r.diagonal / r.edgeLength);
}

void writeIds(JsonWriter& j, const char* key, const std::vector<std::uint32_t>& ids) {
  j.key(key).beginArray();
  for (std::uint32_t id : ids) j.value(U64{id});
  j.endArray();
}

// Components of the solved mesh (ids: order of their lowest face), the largest listed one by
// one, the rest summed, so the report stays bounded on a scan with 100K islands.
void writeComponents(JsonWriter& j, const ComponentSummary& s) {
  j.key("componentList").beginObject();
  j.key("count").value(U64{s.count});
  j.key("mapped").beginObject();
  for (ComponentMapping m : {ComponentMapping::Solved, ComponentMapping::Point, ComponentMapping::Anchored,
                             ComponentMapping::Unsolved}) {
    j.key(componentMappingName(m)).value(U64{s.mapped[static_cast<int>(m)]});
  }
  j.endObject();
  j.key("limit").value(U64{s.limit}).key("listed").value(static_cast<U64>(s.listed.size()));
  j.key("unlisted").value(U64{s.unlisted}).key("unlistedFaces").value(s.unlistedFaces);
  if (s.unlisted) {
    j.key("note").value("the " + std::to_string(s.listed.size()) +
                        " largest components are listed; the others are counted in unlisted");
  }
  writeIds(j, "unsolvedIds", s.unsolvedIds);
  writeIds(j, "droppedIds", s.droppedIds);
  j.key("droppedFaces").value(s.droppedFaces);
  j.key("components").beginArray();
  for (const ComponentFigures& c : s.listed) {
    j.beginObject().key("id").value(U64{c.id}).key("faces").value(U64{c.faces});
    j.key("vertices").value(U64{c.vertices}).key("boundaryLoops").value(U64{c.boundaryLoops});
    j.key("eulerCharacteristic").value(c.eulerCharacteristic).key("genus").value(c.genus);
    j.key("area").value(c.area).key("mapping").value(componentMappingName(c.mapping));
    j.key("cones").value(U64{c.cones}).key("flippedFaces").value(c.flippedFaces);
    j.endObject();
  }
  j.endArray();
  j.endObject();
}

}  // namespace

void writeFieldSolve(JsonWriter& j, const FieldSolveStats& stats) {
  j.key("fieldSolve").beginObject();
  j.key("unknowns").value(stats.unknowns).key("matrixNonzeros").value(stats.matrixNonzeros);
  j.key("factorNonzeros").value(stats.factorNonzeros).key("factorBytes").value(stats.factorBytes);
  j.key("factorPeakBytes").value(stats.factorPeakBytes).key("realFallback").value(stats.realFallback);
  j.key("roughVertices").value(stats.roughVertices).key("roughSpotVertices").value(stats.roughSpotVertices);
  j.key("roughSpotsCapped").value(stats.roughSpotsCapped);
  j.endObject();
}

double stageSeconds(const std::vector<StageFigures>& stages, const std::string& name) {
  double seconds = 0.0;
  for (const StageFigures& stage : stages) {
    if (stage.name == name) seconds += stage.seconds;
  }
  return seconds;
}

ParamReportContext paramReportContext(const PipelineOptions& options, const StageMeter& meter,
                                      std::string input, std::string output,
                                      std::string solverAsked, std::string fieldSource) {
  ParamReportContext c;
  c.input = std::move(input);
  c.output = std::move(output);
  c.solverAsked = std::move(solverAsked);
  c.fieldSource = std::move(fieldSource);
  c.gridResolution = options.solver.gridResolution;
  c.rings = options.solver.refine.rings;
  c.fieldSmoothing = options.field.importedPerInputFace.empty() ? options.field.smoothingSteps : 0;
  c.roughSpots = options.field.importedPerInputFace.empty() && options.field.roughSpots;
  c.maxRounds = options.solver.refine.maxRounds;
  c.stages = meter.stages();
  c.totalSeconds = meter.totalSeconds();
  c.peakBytes = meter.peakBytes();
  return c;
}

std::string paramReportJson(const PipelineResult& r, const ParamReportContext& c) {
  JsonWriter j;
  j.beginObject();
  writeCounts(j, r, c);
  writeFieldSolve(j, r.fieldSolve);
  writeSystem(j, r);
  if (r.solved.solver != ParamSolver::Hat) writeVoxel(j, r.solved, c.gridResolution);
  if (r.solved.refined) writeRefine(j, r.solved.refine, c);
  if (r.untangled) writeUntangle(j, r.untangle);
  writeFeatures(j, r);
  writeQuality(j, r);
  writeComponents(j, r.components);
  writeSeconds(j, r, c);
  j.endObject();
  return j.str();
}

}  // namespace seamvox
