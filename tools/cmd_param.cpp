// seamvox param: seamless parameterization of a mesh (hat, vox or vox + local hat refinement).
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "core/mesh/clean.h"
#include "core/field/cone_merge.h"
#include "core/cut/cut.h"
#include "core/system/errors.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/quality/metrics.h"
#include "core/solve/hat_solver.h"
#include "core/synth/render.h"
#include "io/field_io.h"
#include "io/json.h"
#include "io/mesh_io.h"
#include "io/png_io.h"
#include "core/system/memory.h"
#include "core/solve/param_solver.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

/// Cut-and-solve passes at most when coincident cones are merged after a solve.
constexpr std::uint32_t kMaxConePasses = 3;

int runParam(Args& args) {
  const std::string input = args.positional(0, "the input mesh (seamvox param MESH -o OUT)");
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT (.obj, .ply or .drc)");
  if (formatFromPath(*output) == MeshFormat::Unknown || formatFromPath(*output) == MeshFormat::Off) {
    throw UsageError("output must be .obj, .ply or .drc (OFF has no texture coordinates): " + *output);
  }
  const std::string solver = args.value("solver", "voxloc");
  SolverOptions solverOptions;
  try {
    solverOptions.solver = parseParamSolver(solver);
  } catch (const InputError& e) {
    throw UsageError(std::string("--solver: ") + e.what());
  }
  const std::int64_t grid = args.integer("grid", 128);
  if (grid < 4 || grid > 1024 || (grid & (grid - 1)) != 0) {
    throw UsageError("--grid must be a power of two between 4 and 1024");
  }
  solverOptions.gridResolution = static_cast<std::int32_t>(grid);
  const std::int64_t rings = args.integer("rings", solverOptions.refine.rings);
  if (rings < 0 || rings > 64) throw UsageError("--rings must be between 0 and 64");
  solverOptions.refine.rings = static_cast<std::uint32_t>(rings);
  const std::string fieldSource = args.value("field", "auto");
  const double mergeCones = parseMergeCones(args);
  const GridSpacing spacing = parseGridSpacing(args);
  const bool greedy = args.flag("greedy");
  const bool weld = args.flag("weld");
  const auto reportPath = args.value("report");
  const auto renderPath = args.value("render");
  const ProgressFn progress = makeProgress(args.flag("quiet"));
  args.finish(1);

  StageMeter meter;
  TriangleMesh raw = readMesh(input);
  const std::uint64_t inputFaces = raw.numFaces();
  const double secondsRead = meter.finish("read").seconds;
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = weld;
  cleanOptions.progress = progress;
  CleanResult clean = cleanMesh(std::move(raw), cleanOptions);
  std::vector<VertexId>().swap(clean.vertexOrigin);  // faceOrigin stays for a field file
  TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  const double secondsClean = meter.finish("clean").seconds;

  CrossField field;
  std::string fieldMethod = "file";
  if (fieldSource == "auto" || fieldSource == "smooth" || fieldSource == "proxy") {
    const FieldMethod method = resolveFieldMethod(parseFieldMethod(fieldSource), mesh.numFaces());
    fieldMethod = fieldMethodName(method);
    SmoothFieldOptions fieldOptions;
    fieldOptions.progress = progress;
    ProxyFieldOptions proxyOptions;
    proxyOptions.progress = progress;
    field = computeCrossField(mesh, topology, method, fieldOptions, proxyOptions);
  } else {
    // The file has one vector per input face; cleaning may have dropped or reordered faces.
    const std::vector<Vec3d> vectors = readFieldVectors(fieldSource, static_cast<std::uint32_t>(inputFaces));
    std::vector<Vec3d> perFace(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) perFace[f] = vectors[clean.faceOrigin[f]];
    field = projectToTangent(mesh, std::move(perFace));
  }
  std::vector<FaceId>().swap(clean.faceOrigin);  // only the field file needed it
  const double secondsField = meter.finish("field").seconds;
  const double diagonal = clean.report.diagonalWithoutSpikes;  // a spike would inflate h
  ParamOptions options;
  options.edgeLength = spacing.spacing(diagonal);
  if (!(options.edgeLength > 0.0)) throw InputError(input + ": the mesh has zero extent");

  options.greedyRounding = greedy;
  options.progress = progress;
  solverOptions.meter = &meter;  // closes the "solve" and "refine" stages

  // Cones closer than the grid resolves are merged before cutting; adjacent cones the solve still
  // puts on one point (collapsing the faces between them) are merged too and the cut and solve
  // redone, at most kMaxConePasses times in all.
  CutOptions cutOptions;
  cutOptions.progress = progress;
  ConeMergeResult merged;
  std::vector<std::pair<VertexId, VertexId>> coincident;
  std::unordered_map<VertexId, std::int32_t> coneIndex;  // of the last cut's cones
  CutResult cut;
  SolverResult solved;
  std::uint32_t conePasses = 0;
  double secondsCut = 0.0;
  for (;;) {
    ++conePasses;
    {
      // Matchings and indices are only needed to cut; the cut keeps the combed matchings and cones.
      FieldSingularities singularities = computeSingularities(mesh, topology, field);
      ConeMergeOptions mergeOptions;
      mergeOptions.maxDistance = mergeCones * options.edgeLength;
      merged = mergeCloseCones(mesh, topology, singularities, mergeOptions);
      const ConeMergeResult adjacent = mergeAdjacentCones(topology, singularities, coincident);
      merged.cancelledPairs += adjacent.cancelledPairs;
      merged.mergedPairs += adjacent.mergedPairs;
      cut = cutToDisk(mesh, topology, field, singularities, cutOptions);
      coneIndex.clear();
      for (VertexId v : singularities.cones) coneIndex[v] = singularities.index4[v];
    }
    secondsCut += meter.finish("cut").seconds;
    solved = parameterizeMeshWithSolver(mesh, topology, field, cut, options, solverOptions);
    if (!(mergeCones > 0.0) || conePasses == kMaxConePasses) break;
    std::size_t mergeable = 0;
    for (const auto& [a, b] : coincidentConeEdges(topology, cut.cones, solved.param.cornerUV)) {
      if (canMergeCoincident(coneIndex.at(a), coneIndex.at(b))) {
        coincident.push_back({a, b});
        ++mergeable;
      }
    }
    if (mergeable == 0) break;
    solved = SolverResult{};  // free the map and the cut before the next pass
    cut = CutResult{};
  }
  ParamResult& result = solved.param;
  const RefineStats& refine = solved.refine;
  double secondsParam = 0.0;
  for (const StageFigures& stage : meter.stages()) {
    if (stage.name == "solve" || stage.name == "refine") secondsParam += stage.seconds;
  }

  const SeamQuality seams = measureSeams(mesh, topology, cut, result.cornerUV);
  const MapQuality map = measureMap(mesh, result.cornerUV, &field, options.edgeLength);
  const double secondsMetrics = meter.finish("metrics").seconds;
  const std::uint64_t wedges = result.cornerUV.numWedges(), mapBytes = result.cornerUV.memoryBytes();
  // The writer needs the mesh and its map only (the render also the corner table): release the
  // field and the cut before the output is written.
  const std::size_t numCones = cut.cones.size(), numSeams = cut.seams.size();
  field = CrossField();
  cut = CutResult();
  if (!renderPath) clean.topology = Topology();
  mesh.cornerUV = std::move(result.cornerUV);
  writeMesh(*output, mesh);
  const double secondsWrite = meter.finish("write").seconds;
  if (renderPath) {
    RenderOptions renderOptions;
    renderOptions.drawSeams = renderOptions.drawCones = true;
    renderOptions.progress = progress;
    writePng(*renderPath, renderCheckerboard(mesh, topology, renderOptions).image);
    meter.finish("render");
  }
  const double secondsTotal = meter.totalSeconds();
  const std::uint64_t peak = meter.peakBytes();
  const bool seamless = seams.isSeamless();
  const SeamlessStats& st = result.stats;

  std::printf("%s -> %s: %u faces, %zu cones, %zu seams, h = %.6g (%.1f cells on the diagonal)\n",
              input.c_str(), output->c_str(), mesh.numFaces(), numCones, numSeams,
              options.edgeLength, diagonal / options.edgeLength);
  std::printf("unknowns %u (positional %u, translational %u), factor %.1f MB, peak %.1f MB\n",
              st.unknowns, st.positional, st.translational, st.factorBytes / 1048576.0,
              peak / 1048576.0);
  std::printf("map: %llu wedges (%.3f per vertex), %.1f MB\n", static_cast<unsigned long long>(wedges),
              mesh.numVertices() ? double(wedges) / mesh.numVertices() : 0.0, mapBytes / 1048576.0);
  std::printf("seam residual %.3g, integer distance %.3g, gradient error %.4f, flipped %llu, "
              "collapsed %llu: %s\n",
              seams.maxResidual, seams.maxIntegerDistance, map.relativeGradientError,
              static_cast<unsigned long long>(map.flipped),
              static_cast<unsigned long long>(map.collapsed), seamless ? "seamless" : "NOT seamless");
  if (solved.refined) {
    std::printf("refined %u vertices (%.3f%%) in %llu faces: %u local unknowns (%u translations), "
                "factor %.1f MB, %.2f s\n",
                refine.freeVertices, 100.0 * refine.refinedVertexFraction,
                static_cast<unsigned long long>(refine.regionFaces), refine.unknowns,
                refine.freeTranslations, refine.factorBytes / 1048576.0, refine.secondsTotal);
  }
  if (st.unsolvedComponents) {
    std::printf("WARNING: %u components could not be solved and map to the point 0\n", st.unsolvedComponents);
  }
  if (!solved.fallbackReason.empty()) {
    std::printf("WARNING: the %s system could not be factored (%s); the hat solver ran instead\n",
                solver.c_str(), solved.fallbackReason.c_str());
  }
  std::printf("time %.2f s (field %.2f, cut %.2f, solve %.2f)\n", secondsTotal, secondsField,
              secondsCut, secondsParam);
  std::printf("stages (s / peak MB):");
  for (const StageFigures& stage : meter.stages()) {
    std::printf(" %s %.1f / %.0f;", stage.name.c_str(), stage.seconds, stage.peakBytes / 1048576.0);
  }
  std::printf("\n");

  if (reportPath) {
    JsonWriter j;
    j.beginObject();
    j.key("input").value(input).key("output").value(*output).key("solver").value(solver);
    j.key("solverUsed").value(paramSolverName(solved.solver));
    if (!solved.fallbackReason.empty()) j.key("fallbackReason").value(solved.fallbackReason);
    j.key("field").value(fieldSource).key("fieldMethod").value(fieldMethod);
    j.key("faces").value(static_cast<std::uint64_t>(mesh.numFaces()));
    j.key("vertices").value(static_cast<std::uint64_t>(mesh.numVertices()));
    j.key("components").value(static_cast<std::uint64_t>(st.components));
    j.key("anchoredComponents").value(static_cast<std::uint64_t>(st.anchoredComponents));
    j.key("unsolvedComponents").value(static_cast<std::uint64_t>(st.unsolvedComponents));
    j.key("nonManifoldEdgesSplit").value(clean.report.nonManifoldEdges);
    j.key("nonManifoldVerticesSplit").value(clean.report.nonManifoldVertices);
    j.key("spikeVertices").value(clean.report.spikeVertices);
    j.key("cones").value(static_cast<std::uint64_t>(numCones));
    j.key("conesCancelled").value(static_cast<std::uint64_t>(2 * merged.cancelledPairs));
    j.key("conesMerged").value(static_cast<std::uint64_t>(merged.mergedPairs));
    j.key("conePasses").value(static_cast<std::uint64_t>(conePasses));
    j.key("seams").value(static_cast<std::uint64_t>(numSeams));
    j.key("seamEdges").value(seams.seamEdges).key("seamLength").value(seams.seamLength);
    j.key("wedges").value(wedges).key("mapBytes").value(mapBytes);
    j.key("edgeLength").value(options.edgeLength);
    j.key("cellsOnDiagonal").value(diagonal / options.edgeLength);
    j.key("system").beginObject();
    j.key("basisFunctions").value(static_cast<std::uint64_t>(result.basisFunctions));
    j.key("domains").value(static_cast<std::uint64_t>(result.domains));
    j.key("unknowns").value(static_cast<std::uint64_t>(st.unknowns));
    j.key("positional").value(static_cast<std::uint64_t>(st.positional));
    j.key("translational").value(static_cast<std::uint64_t>(st.translational));
    j.key("conePositions").value(static_cast<std::uint64_t>(st.determinedPositions));
    j.key("translationConstraints").value(static_cast<std::uint64_t>(result.translationConstraints));
    j.key("nonUnitConstraints").value(static_cast<std::uint64_t>(st.nonUnitConstraints));
    j.key("pinnedFirstSolve").value(static_cast<std::uint64_t>(st.pinnedFirst));
    j.key("pinnedSecondSolve").value(static_cast<std::uint64_t>(st.pinnedSecond));
    j.key("matrixNonzeros").value(st.systemNonzeros);
    j.key("factorNonzeros").value(st.factorNonzeros);
    j.key("factorBytes").value(st.factorBytes);
    j.key("factorPeakBytes").value(st.factorPeakBytes);
    j.key("realFallback").value(st.realFallback);
    j.key("maxRoundingShift").value(st.maxRoundingShift);
    j.endObject();
    if (solved.solver != ParamSolver::Hat) {
      j.key("voxel").beginObject();
      j.key("grid").value(static_cast<std::uint64_t>(solverOptions.gridResolution));
      j.key("regularization").value(solved.regularization);
      j.key("failedFactorizations").value(static_cast<std::uint64_t>(solved.failedAttempts));
      j.key("invisibleTranslations").value(static_cast<std::uint64_t>(solved.invisibleTranslations));
      j.key("voxels").value(solved.basisStats.voxels);
      j.key("elements").value(solved.basisStats.elements);
      j.key("basisBytes").value(solved.basisStats.bytes);
      j.key("conePositions").value(static_cast<std::uint64_t>(solved.determinedBasis));
      j.key("inconsistentBasis").value(static_cast<std::uint64_t>(solved.inconsistentBasis));
      j.key("markedFaces").value(solved.markedFaces);
      j.endObject();
    }
    if (solved.refined) {
      j.key("refine").beginObject();
      j.key("refinedVertexFraction").value(refine.refinedVertexFraction);
      j.key("freeVertices").value(static_cast<std::uint64_t>(refine.freeVertices));
      j.key("lockedVertices").value(static_cast<std::uint64_t>(refine.lockedVertices));
      j.key("regionFaces").value(refine.regionFaces);
      j.key("markedFaces").value(refine.markedFaces);
      j.key("collapsedFaces").value(refine.collapsedFaces);
      j.key("flippedFaces").value(refine.flippedFaces);
      j.key("rings").value(static_cast<std::uint64_t>(solverOptions.refine.rings));
      j.key("localUnknowns").value(static_cast<std::uint64_t>(refine.unknowns));
      j.key("localTranslations").value(static_cast<std::uint64_t>(refine.freeTranslations));
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
      j.key("maxRounds").value(static_cast<std::uint64_t>(solverOptions.refine.maxRounds));
      j.key("rounds").beginArray();
      for (const RefineRound& round : refine.rounds) {
        j.beginObject();
        j.key("seedFaces").value(round.seedFaces).key("regionFaces").value(round.regionFaces);
        j.key("freeVertices").value(static_cast<std::uint64_t>(round.freeVertices));
        j.key("unknowns").value(static_cast<std::uint64_t>(round.unknowns));
        j.key("collapsed").value(round.collapsed).key("collapsedAtCones").value(round.collapsedAtCones);
        j.key("flipped").value(round.flipped).key("borderFaces").value(round.borderFaces);
        j.key("seconds").value(round.seconds);
        j.endObject();
      }
      j.endArray();
      j.endObject();
    }
    j.key("quality").beginObject();
    j.key("seamless").value(seamless);
    j.key("maxSeamResidual").value(seams.maxResidual);
    j.key("maxIntegerDistance").value(seams.maxIntegerDistance);
    j.key("relativeGradientError").value(map.relativeGradientError);
    j.key("flipped").value(map.flipped).key("flippedFraction").value(map.flippedFraction);
    j.key("collapsed").value(map.collapsed);
    j.endObject();
    j.key("seconds").beginObject();
    j.key("read").value(secondsRead).key("clean").value(secondsClean);
    j.key("field").value(secondsField).key("cut").value(secondsCut);
    j.key("basis").value(result.secondsBasis).key("reduce").value(result.secondsReduce);
    j.key("assemble").value(st.secondsAssemble).key("firstSolve").value(st.secondsFirstSolve);
    j.key("round").value(st.secondsRound).key("secondSolve").value(st.secondsSecondSolve);
    j.key("evaluate").value(result.secondsEvaluate).key("refine").value(refine.secondsTotal).key("metrics").value(secondsMetrics);
    j.key("write").value(secondsWrite).key("total").value(secondsTotal);
    j.endObject();
    j.key("peakResidentBytes").value(peak);
    // Wall time, peak and end resident size of each stage, in order.
    j.key("stages").beginArray();
    for (const StageFigures& stage : meter.stages()) {
      j.beginObject().key("name").value(stage.name).key("seconds").value(stage.seconds);
      j.key("peakBytes").value(stage.peakBytes).key("endBytes").value(stage.endBytes).endObject();
    }
    j.endArray();
    j.endObject();
    writeTextOutput(*reportPath, j.str());
  }
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"param", "compute a seamless parameterization (per-corner u, v)",
                 "usage: seamvox param MESH -o OUT.obj|.ply|.drc [--solver hat|vox|voxloc] [--grid N]\n"
                 "                     [--rings K] [--field auto|smooth|proxy|FILE]\n"
                 "                     [--edge-length H | --cells N] [--merge-cones F]\n"
                 "                     [--greedy] [--weld] [--report R.json] [--render OUT.png]\n"
                 "\n"
                 "Reads and cleans MESH, computes (or reads) a cross field, cuts through its cones and\n"
                 "writes per-corner (u, v) in grid units: across every seam q' = r q + t with r a\n"
                 "quarter turn and t an integer vector, and grad q follows the field with spacing H.\n"
                 "\n"
                 "  --solver voxloc     volumetric B-spline basis on an N^3 grid, then a local hat\n"
                 "                      solve near cones and on collapsed or flipped triangles (default)\n"
                 "  --solver vox        the volumetric basis alone\n"
                 "  --solver hat        the per-vertex hat basis (exact reference, one global solve)\n"
                 "  --grid N            voxels per axis for vox and voxloc: 64, 128 (default), 256, 512\n"
                 "  --rings K           rings of neighbours added around the voxloc region (default 1)\n"
                 "  --field auto        the smoothest cross field: smooth up to 1M faces, proxy above\n"
                 "                      (default)\n"
                 "  --field smooth      the smoothest cross field by one solve over all faces (exact)\n"
                 "  --field proxy       the smoothest cross field solved on a coarse grid proxy, then\n"
                 "                      smoothed on the faces (linear time and memory; massive meshes)\n"
                 "  --field FILE        per-face field (.crossfield or plain, one vector per input face)\n"
                 "  --edge-length H     grid spacing in mesh units\n"
                 "  --cells N           H = bounding-box diagonal / N (default N = 100)\n"
                 "  --merge-cones F     move the index of cones at most F * H apart (along edges) onto\n"
                 "                      one of them: closer than the grid resolves, they would collapse\n"
                 "                      the faces between them; default 0.5, 0 keeps every cone\n"
                 "  --greedy            round translations in batches, re-solving in between\n"
                 "  --weld              weld coincident vertices before cleaning\n"
                 "  --report FILE       JSON report: quality, counts, system sizes, factor memory,\n"
                 "                      stage timings, peak memory\n"
                 "  --render OUT.png    also render the result (checkerboard, seams, cones; 1024x1024,\n"
                 "                      default view of seamvox render)\n"
                 "  --quiet             no progress on stderr\n",
                 {"greedy", "weld"},
                 &runParam});

}  // namespace seamvox::cli
