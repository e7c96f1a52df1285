// seamvox param: seamless parameterization of a mesh (hat, vox or vox + local hat refinement).
// Parses the options, reads, calls the library pipeline (core/pipeline), prints, writes.
#include <cstdio>
#include <exception>
#include <limits>

#include "core/pipeline/parameterize.h"
#include "core/solve/param_solver.h"
#include "core/synth/render.h"
#include "core/system/errors.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "io/param_report.h"
#include "io/png_io.h"
#include "io/polygon_io.h"
#include "core/system/memory_budget.h"
#include "io/json.h"
#include "io/scratch_map_writer.h"
#include "stream/param_stream.h"
#include "stream/scratch_direction_store.h"
#include "stream/scratch_folder.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

/// --field names a file rather than a method (auto, smooth, proxy).
bool isFieldFile(const std::string& fieldSource) {
  return fieldSource != "auto" && fieldSource != "smooth" && fieldSource != "proxy";
}

struct ParamCommand {
  std::string input, output;
  std::string solverName, fieldSource;
  std::optional<std::string> reportPath, renderPath, quadsPath;
  PipelineOptions options;
  MemoryOptions memory;
  bool outOfCore = false;  ///< --out-of-core: whatever the estimate
};

ParamCommand parseParamArgs(Args& args) {
  ParamCommand c;
  c.input = args.positional(0, "the input mesh (seamvox param MESH -o OUT)");
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT (.obj, .ply or .drc)");
  c.output = *output;
  const MeshFormat outputFormat = formatFromPath(c.output);
  if (outputFormat != MeshFormat::Obj && outputFormat != MeshFormat::Ply && outputFormat != MeshFormat::Draco) {
    throw UsageError("output must be .obj, .ply or .drc (OFF and STL have no texture coordinates): " + c.output);
  }
  PipelineOptions& o = c.options;
  c.solverName = args.value("solver", "auto");
  try {
    o.solver.solver = parseParamSolver(c.solverName);
  } catch (const InputError& e) {
    throw UsageError(std::string("--solver: ") + e.what());
  }
  o.solver.gridResolution = parseGridResolution(args);
  const std::int64_t rings = args.integer("rings", o.solver.refine.rings, 0, 64);
  o.solver.refine.rings = static_cast<std::uint32_t>(rings);
  o.solver.refine.splineCells = static_cast<std::uint32_t>(args.integer("spline-cells", 4, 0, 64));
  c.fieldSource = args.value("field", "auto");
  o.mergeCones = parseMergeCones(args);
  o.field.smoothingSteps = parseFieldSmoothing(args, isFieldFile(c.fieldSource));
  o.spacing = parseGridSpacing(args);
  o.greedyRounding = args.flag("greedy");
  o.untangle = !args.flag("no-untangle");
  if (args.flag("no-leftover-resolve")) o.untangleOptions.leftoverRadius = 0.0;
  if (args.flag("no-cone-resolve")) o.untangleOptions.coneRepairRadius = 0.0;
  o.mergeInMap = args.flag("merge-in-map");
  o.field.roughSpots = !args.flag("no-rough-spots");
  o.solver.smoothedEvaluation = !args.flag("no-smoothed-evaluation");
  o.features.alignBoundary = args.flag("align-boundary");
  o.features.featureAngle = args.number("feature-angle", 0.0, 0.0, 179.0);
  o.features.autoFeatureAngle = !args.value("feature-angle");  // given, even as 0: exactly that
  o.clean.weldVertices = args.flag("weld");
  if (args.flag("keep-order")) o.clean.reorderMinFaces = std::numeric_limits<std::uint32_t>::max();
  o.listComponents = static_cast<std::uint32_t>(args.integer("report-components", o.listComponents, 0, 100000000));
  o.dropUnsolved = args.flag("drop-unsolved");
  c.reportPath = args.value("report");
  c.renderPath = args.value("render");
  c.quadsPath = args.value("quads");
  // A quad mesh can close only holes without a translation; a plain map keeps the lower
  // distortion that translations at tiny holes allow (bench/RESULTS.md, session 17).
  o.closeHoles = args.number("close-holes", c.quadsPath ? kCloseHoleCells : 0.0, 0.0, 1000.0);
  o.progress = makeProgress(args.flag("quiet"));
  c.memory = parseMemoryOptions(args);
  c.outOfCore = args.flag("out-of-core");
  args.finish(1);
  if (c.renderPath) requirePngPath("--render", *c.renderPath);
  if (c.quadsPath && formatFromPath(*c.quadsPath) != MeshFormat::Obj && formatFromPath(*c.quadsPath) != MeshFormat::Ply) {
    throw UsageError("--quads: the quad mesh is written as .obj or .ply: " + *c.quadsPath);
  }
  const bool fieldFile = isFieldFile(c.fieldSource);
  checkOutputPaths({{"MESH", c.input}, {"--field", fieldFile ? c.fieldSource : ""}},
                   {{"-o", c.output}, {"--report", c.reportPath.value_or("")}, {"--render", c.renderPath.value_or("")},
                    {"--quads", c.quadsPath.value_or("")}});
  return c;
}

void printSummary(const ParamCommand& c, const PipelineResult& r, const StageMeter& meter) {
  const SeamlessStats& st = r.solved.param.stats;
  const std::uint64_t wedges = r.size.wedges;
  std::printf("%s -> %s: %u faces, %zu cones, %u seams, h = %.6g (%.1f cells on the diagonal)\n",
              c.input.c_str(), c.output.c_str(), r.size.faces, r.cones.size(), r.seams,
              r.edgeLength, r.diagonal / r.edgeLength);
  if (r.cleanReport.unweldedBoundaryVertices) {
    std::printf("%llu boundary vertices lie exactly on another boundary vertex: cracks left open "
                "(--weld joins them)\n", static_cast<unsigned long long>(r.cleanReport.unweldedBoundaryVertices));
  }
  if (r.cleanReport.reordered) {
    std::printf("the input's order was scattered: vertices and faces were put in spatial order (so are the output's)\n");
  }
  if (r.cleanReport.verticesRenumbered) {
    std::printf("the input's vertex ids were scattered: vertices were renumbered in the order the faces use them (so are the output's)\n");
  }
  std::printf("unknowns %u (positional %u, translational %u), factor %.1f MB, peak %.1f MB\n",
              st.unknowns, st.positional, st.translational, st.factorBytes / 1048576.0,
              meter.peakBytes() / 1048576.0);
  std::printf("map: %llu wedges (%.3f per vertex), %.1f MB\n", static_cast<unsigned long long>(wedges),
              r.size.vertices ? double(wedges) / r.size.vertices : 0.0, r.size.mapBytes / 1048576.0);
  if (r.size.attributeBytes > 0) {
    std::printf("vertex properties: %s, %.1f MB\n", r.size.attributes.c_str(), r.size.attributeBytes / 1048576.0);
  }
  char wound[48] = "";
  if (r.mapQuality.woundCounted) {
    std::snprintf(wound, sizeof wound, ", wound %llu", static_cast<unsigned long long>(r.mapQuality.wound));
  }
  std::printf("seam residual %.3g, integer distance %.3g, gradient error %.4f, flipped %llu, "
              "collapsed %llu, stretched %llu%s: %s\n",
              r.seamQuality.maxResidual, r.seamQuality.maxIntegerDistance,
              r.mapQuality.relativeGradientError, static_cast<unsigned long long>(r.mapQuality.flipped),
              static_cast<unsigned long long>(r.mapQuality.collapsed),
              static_cast<unsigned long long>(r.mapQuality.stretched), wound,
              r.isSeamless() ? "seamless" : "NOT seamless");
  const RefineStats& refine = r.solved.refine;
  if (r.solved.refined) {
    char islands[96] = "";
    if (refine.islandVertices > 0) {
      std::snprintf(islands, sizeof islands, "; %u of them on islands mapped whole, %.3f%% off them",
                    refine.islandVertices, 100.0 * refine.refinedFractionOffIslands);
    }
    std::printf("refined %u vertices (%.3f%%%s) in %llu faces: %llu local unknowns in %u solves "
                "(largest %u unknowns, %u translations, factor %.1f MB), %.2f s\n",
                refine.freeVertices, 100.0 * refine.refinedVertexFraction, islands,
                static_cast<unsigned long long>(refine.regionFaces),
                static_cast<unsigned long long>(refine.totalUnknowns), refine.solves, refine.unknowns,
                refine.freeTranslations, refine.factorBytes / 1048576.0, refine.secondsTotal);
    if (refine.splineVertices > 0) {
      std::printf("refined: %u more vertices (%.3f%%) moved only by the first round's B-splines (%llu unknowns)\n",
                  refine.splineVertices, 100.0 * refine.splineVertexFraction,
                  static_cast<unsigned long long>(refine.rounds.empty() ? 0 : refine.rounds.front().unknowns));
    }
    if (refine.failedSolves > 0) {
      std::printf("refined: %u local solves could not be factored and kept the voxel map there (first: %s)\n",
                  refine.failedSolves, refine.failedSolveReason.c_str());
    }
  }
  if (r.untangled) {
    std::printf("foldover repair: flipped %llu -> %llu (%llu folded in 3D), %llu patch faces, %u solves, "
                "%u vertices moved into their fan's kernel, %u moved jointly, %.2f s\n",
                static_cast<unsigned long long>(r.untangle.flippedBefore),
                static_cast<unsigned long long>(r.untangle.flippedAfter),
                static_cast<unsigned long long>(r.untangle.foldedIn3D),
                static_cast<unsigned long long>(r.untangle.patchFaces), r.untangle.solves,
                r.untangle.relocatedVertices, r.untangle.jointVertices, r.untangle.seconds);
    if (r.untangle.miswoundCones > 0) {
      std::printf("foldover repair: %u cones a full turn short after its rounds, %u after their own re-solves\n",
                  r.untangle.miswoundCones, r.untangle.miswoundConesAfter);
    }
    if (r.untangle.leftoverFlips > 0) {
      std::printf("foldover repair: %llu flips left re-solved in the hat basis (%llu faces, %u vertices), "
                  "%llu flipped after that, then repaired again\n",
                  static_cast<unsigned long long>(r.untangle.leftoverFlips),
                  static_cast<unsigned long long>(r.untangle.leftoverRegionFaces), r.untangle.leftoverFreeVertices,
                  static_cast<unsigned long long>(r.untangle.leftoverAfterResolve));
    }
    if (r.untangle.specks > 0) {
      std::printf("foldover repair: %u closed components smaller than a cell (%llu faces) were still folded: "
                  "mapped to one point, their faces collapsed\n",
                  r.untangle.specks, static_cast<unsigned long long>(r.untangle.speckFaces));
    }
  }
  if (r.featureCurves.total > 0) {
    std::printf("feature curves: %u (%u boundary, %u crease edges; feature angle %g%s): %u aligned on integer "
                "iso-lines, %u not aligned (%u released: the map collapsed faces next to them)%s\n",
                r.featureCurves.total, r.features.boundaryEdges, r.features.creaseEdges, r.featureAngle,
                r.featureAngleAuto ? ", chosen: the creases look like a CAD model's" : "",
                r.featureCurves.aligned, r.featureCurves.notAligned, r.featureCurvesReleased,
                !r.featureFieldAligned ? " (the proxy or an imported field does not follow them)"
                : r.solved.solver != ParamSolver::Hat ? " (only the hat solver holds them)" : "");
  }
  const ComponentSummary& parts = r.components;
  if (!parts.droppedIds.empty()) {
    std::printf("WARNING: %zu components (%llu faces) could not be solved and were dropped from the "
                "output (ids in the report)\n", parts.droppedIds.size(),
                static_cast<unsigned long long>(parts.droppedFaces));
  } else if (!parts.unsolvedIds.empty()) {
    std::printf("WARNING: %zu components could not be solved and are written unmapped at (u, v) = 0 "
                "(ids in the report; --drop-unsolved removes them)\n", parts.unsolvedIds.size());
  }
  if (!r.solved.fallbackReason.empty()) {
    std::printf("WARNING: the %s system could not be factored (%s); the hat solver ran instead\n",
                c.solverName.c_str(), r.solved.fallbackReason.c_str());
  }
  if (!r.solved.voxelRetryReason.empty()) {
    std::printf("the first voxel system could not be factored (%s); solved with the B-splines that barely touch "
                "the surface (weight below %g) joined to a neighbour\n",
                r.solved.voxelRetryReason.c_str(), kRetryMinDomainWeight);
  }
  std::printf("solver %s: %s\n", paramSolverName(r.solved.solver), r.solved.solverReason.c_str());
  const auto& stages = meter.stages();
  std::printf("time %.2f s (field %.2f, cut %.2f, solve %.2f)\n", meter.totalSeconds(),
              stageSeconds(stages, "field"), stageSeconds(stages, "cut"),
              stageSeconds(stages, "basis") + stageSeconds(stages, "solve") + stageSeconds(stages, "refine"));
  std::printf("stages (s / peak MB):");
  for (const StageFigures& stage : stages) {
    std::printf(" %s %.1f / %.0f;", stage.name.c_str(), stage.seconds, stage.peakBytes / 1048576.0);
  }
  std::printf("\n");
}

/// The options the out-of-core path does not have yet, as the user gave them.
std::vector<std::string> optionsWithoutOutOfCorePath(const ParamCommand& c) {
  std::vector<std::string> out;
  const PipelineOptions& o = c.options;
  if (o.solver.solver == ParamSolver::Hat) out.push_back("--solver hat (one global solve over every vertex)");
  if (c.fieldSource != "auto" && c.fieldSource != "proxy") out.push_back("--field " + c.fieldSource);
  if (o.features.alignBoundary) out.push_back("--align-boundary");
  if (!o.features.autoFeatureAngle && o.features.featureAngle > 0.0) out.push_back("--feature-angle");
  if (o.closeHoles > 0.0 && !c.quadsPath) out.push_back("--close-holes");
  if (c.quadsPath) out.push_back("--quads (run seamvox quads on the output)");
  if (c.renderPath) out.push_back("--render (run seamvox render on the output)");
  if (o.dropUnsolved) out.push_back("--drop-unsolved");
  if (o.greedyRounding) out.push_back("--greedy");
  if (o.clean.reorderMinFaces == std::numeric_limits<std::uint32_t>::max()) {
    out.push_back("--keep-order (the output is in spatial order)");
  }
  if (formatFromPath(c.output) == MeshFormat::Draco) out.push_back("a .drc output (Draco encodes whole meshes: write .ply or .obj)");
  return out;
}

/// The out-of-core run's figures as the in-memory pipeline reports them (its mesh empty).
PipelineResult figuresOfOutOfCoreRun(const StreamParamResult& s, ParamSolver solver) {
  PipelineResult r;
  r.size.faces = static_cast<std::uint32_t>(s.faces);
  r.size.vertices = static_cast<std::uint32_t>(s.vertices);
  r.size.wedges = static_cast<std::uint32_t>(s.wedges);
  r.size.mapBytes = 3 * s.faces * sizeof(std::uint32_t) + s.wedges * sizeof(Vec2d);  // its scratch files
  r.cleanReport = s.cleanReport;
  r.inputFaces = static_cast<std::uint32_t>(s.inputFaces);
  r.fieldMethod = "proxy";
  r.edgeLength = s.edgeLength;
  r.diagonal = s.diagonal;
  r.cones = s.cones;
  r.coneIndex4 = s.coneIndex4;
  r.seams = s.seams;
  r.conesBeforeMerge = s.conesBeforeMerge;
  r.fieldSolve.roughVertices = s.roughVertices;
  r.fieldSolve.roughSpotVertices = s.roughSpotVertices;
  r.fieldSolve.roughSpotsCapped = s.roughSpotsCapped;
  r.merged = s.merged;
  r.conePasses = s.conePasses;
  r.conePassKept = s.conePassKept;
  r.conePassFlips = s.conePassFlips;
  SolverResult& solved = r.solved;
  solved.solver = solver;
  solved.solverReason = "out of core, the voxel basis (the hat basis needs the whole mesh in memory)";
  solved.param.stats = s.solve;
  solved.param.translationConstraints = s.translationConstraints;
  solved.param.basisFunctions = static_cast<std::uint32_t>(s.basisFunctions);
  solved.param.domains = static_cast<std::uint32_t>(s.domains);
  solved.basisStats.elements = s.elements;
  solved.basisStats.fragments = s.fragments;
  solved.determinedBasis = s.determinedBasis;
  solved.inconsistentBasis = s.inconsistentBasis;
  solved.failedAttempts = s.failedAttempts;
  solved.voxelRetryReason = s.voxelRetryReason;
  solved.markedFaces = s.markedFaces;
  solved.smoothedEvaluation = s.smoothedEvaluation;
  solved.islandFaces = s.islandFaces;
  solved.refined = s.refined;
  solved.refine = s.refine;
  r.untangled = s.untangled;
  r.untangle = s.untangle;
  r.seamQuality = s.seamQuality;
  r.mapQuality = s.mapQuality;
  r.components.count = s.components;  // the cut's; no per-component figures out of core
  return r;
}

/// param above the memory budget (or with --out-of-core): every stage streams through the
/// scratch folder (stream/param_stream); the grid-sized system and the passes' buffers stay
/// within the budget.
int runParamOutOfCore(ParamCommand& c, MeshStream& stream, OutputSet& outputs, AtomicFile& meshFile,
                      AtomicFile* reportFile, MemoryPath& memoryPath, std::uint64_t faces) {
  const std::vector<std::string> missing = optionsWithoutOutOfCorePath(c);
  if (!missing.empty()) {
    std::string list;
    for (const std::string& option : missing) list += (list.empty() ? "" : ", ") + option;
    throw InputError(c.input + ": param runs out of core here (" +
                     (c.outOfCore ? std::string("--out-of-core") : "its estimate " + formatByteSize(memoryPath.estimate) +
                                                                       " is above the --memory-budget of " +
                                                                       formatByteSize(memoryPath.budget)) +
                     "), and that path has no " + list + " yet; leave them out, or give a larger --memory-budget if "
                     "the machine has it");
  }
  const std::int32_t grid = c.options.solver.gridResolution;
  const auto fixedBytes = [](std::int32_t g) { return estimateParamPeakBytes(0, ParamSolver::VoxLoc, g); };
  if (memoryPath.budget < outOfCoreMinimumBytes(grid)) {
    std::string fits = "no grid of 32 or more voxels per axis fits within it";
    for (const std::int32_t g : {256, 128, 64, 32}) {
      if (g < grid && outOfCoreMinimumBytes(g) <= memoryPath.budget) {
        fits = "--grid " + std::to_string(g) + " fits within it";
        break;
      }
    }
    throw InputError(c.input + ": param out of core needs a --memory-budget of at least " +
                     formatByteSize(outOfCoreMinimumBytes(grid)) + " at --grid " + std::to_string(grid) +
                     " (the grid-sized system stays in memory), got " + formatByteSize(memoryPath.budget) + "; " + fits);
  }
  memoryPath.outOfCore = true;
  // The scratch peak measured 192 B per face at 20M and 100M faces (bench/RESULTS.md, session 21).
  ScratchFolder folder(c.memory.scratch, 200 * faces);
  StageMeter meter;
  StreamParamOptions options;
  options.memoryBytes = memoryPath.budget - fixedBytes(grid);
  options.earlyMemoryBytes = memoryPath.budget - outOfCoreProgramBytes();
  options.weld = c.options.clean.weldVertices;
  options.spacing = c.options.spacing;
  options.mergeCones = c.options.mergeCones;
  options.fieldSmoothing = c.options.field.smoothingSteps;
  options.roughSpots = c.options.field.roughSpots;
  options.maxConePasses = c.options.maxConePasses;
  options.gridResolution = grid;
  const ParamSolver solver = c.options.solver.solver == ParamSolver::Vox ? ParamSolver::Vox : ParamSolver::VoxLoc;
  options.voxLoc = solver == ParamSolver::VoxLoc;
  options.refine = c.options.solver.refine;
  options.smoothedEvaluation = c.options.solver.smoothedEvaluation;
  options.refine.coneWeightRadius = c.options.coneWeightRadius;
  options.untangle = c.options.untangle;
  options.untangleOptions = c.options.untangleOptions;
  options.untangleOptions.coneWeightRadius = c.options.coneWeightRadius;
  options.progress = c.options.progress;
  options.meter = &meter;
  options.writeMap = [&](const CleanScratch& scratch, const ScratchMap& map) {
    writeScratchMap(meshFile, folder, scratch, map, WriteOptions{}, StreamPassOptions{options.memoryBytes});
  };
  StreamParamResult streamed;
  try {
    streamed = parameterizeOutOfCore(stream, folder, options);
  } catch (...) {
    rethrowWithContext(c.input);
  }
  memoryPath.recordScratch(folder);
  memoryPath.peakBytes = meter.peakBytes();
  const PipelineResult r = figuresOfOutOfCoreRun(streamed, solver);
  printSummary(c, r, meter);
  if (streamed.untangled) {
    std::printf("foldover repair out of core: %llu faces paged in around the flips\n",
                static_cast<unsigned long long>(streamed.untangleWindowFaces));
  }
  std::printf("cleaning out of core: edges glued by %s\n",
              streamed.cleanGluing == "front" ? "one pass along the faces' front" : streamed.cleanGluing.c_str());
  std::printf("%s\n", describeMemoryPath(memoryPath).c_str());
  if (c.reportPath) {
    ParamReportContext context = paramReportContext(c.options, meter, c.input, c.output, c.solverName, c.fieldSource);
    context.memoryPathJson = [&](JsonWriter& j) {
      writeMemoryPathJson(j, memoryPath, false);
      j.key("untangleWindowFaces").value(streamed.untangleWindowFaces);
      j.key("cleanGluing").value(streamed.cleanGluing);
      j.key("passSeconds").beginObject();
      for (const auto& [name, seconds] : streamed.passSeconds) j.key(name).value(seconds);
      j.endObject();
    };
    const std::string json = paramReportJson(r, context);
    if (reportFile) {
      reportFile->write(json);
    } else {
      writeTextOutput("-", json);
    }
  }
  outputs.commit();
  return 0;
}

int runParam(Args& args) {
  ParamCommand c = parseParamArgs(args);
  // Every output is staged now (a missing folder fails before the work) and committed together.
  OutputSet outputs;
  AtomicFile& meshFile = outputs.add(c.output);
  AtomicFile* reportFile = c.reportPath && *c.reportPath != "-" ? &outputs.add(*c.reportPath) : nullptr;
  AtomicFile* renderFile = c.renderPath ? &outputs.add(*c.renderPath) : nullptr;
  AtomicFile* quadsFile = c.quadsPath ? &outputs.add(*c.quadsPath) : nullptr;
  // The estimate from the header's counts, before anything is read: a mesh that would not fit
  // the budget in memory goes out of core. One stream for both (a pipe is read once).
  MemoryPath memoryPath;
  memoryPath.budget = c.memory.budget;
  const std::unique_ptr<MeshStream> stream = openMeshStream(c.input);
  bool declared = false;
  // Above the budget the field's directions wait in a scratch file while the map is built, when
  // that brings the estimate within it.
  std::unique_ptr<ScratchFolder> scratch;
  std::unique_ptr<ScratchDirectionStore> directionStore;
  {
    const MeshCounts counts = guessMeshCounts(c.input, *stream);
    const auto estimate = [&](bool fieldOnDisk) {
      return estimateParamPeakBytes(counts.faces, c.options.solver.solver, c.options.solver.gridResolution, fieldOnDisk);
    };
    memoryPath.estimate = estimate(false);
    // Only a count the header declares is trusted: OBJ's is guessed from the file size (up to
    // twice too high) and a pipe's is unknown, so those stay in memory.
    declared = stream->declaredFaces() > 0 || stream->expectedTriangles() > 0;
    const bool fieldOnDiskFits = estimate(true) <= memoryPath.budget;
    if (c.outOfCore || (declared && memoryPath.estimate > memoryPath.budget && !fieldOnDiskFits)) {
      return runParamOutOfCore(c, *stream, outputs, meshFile, reportFile, memoryPath, counts.faces);
    }
    if (memoryPath.estimate > memoryPath.budget && estimate(true) < memoryPath.estimate) {
      memoryPath.estimate = estimate(true);
      scratch = std::make_unique<ScratchFolder>(c.memory.scratch, 12 * counts.faces);
      directionStore = std::make_unique<ScratchDirectionStore>(*scratch);
      c.options.directionStore = directionStore.get();
    }
  }
  c.options.passHeadroomBytes = memoryPath.budget - std::min(memoryPath.budget, memoryPath.estimate);
  StageMeter meter;
  c.options.meter = &meter;
  TriangleMesh raw = readMesh(*stream);
  if (isFieldFile(c.fieldSource)) {
    // The file has one vector per input face; cleaning may drop or reorder faces.
    c.options.field.importedPerInputFace = readFieldVectors(c.fieldSource, raw.numFaces());
  } else {
    c.options.field.method = parseFieldMethod(c.fieldSource);
  }
  meter.finish("read");
  // The quad mesh of the map as solved, small holes still capped (PipelineOptions::withSolvedMap).
  std::optional<QuadRun> quads;
  if (quadsFile) {
    c.options.withSolvedMap = [&](const TriangleMesh& map, const Topology& topology) {
      quads = extractCheckedQuads(c.input, map, topology, 1, c.options.progress);
      writePolygonMesh(*quadsFile, quads->quads.mesh);
      quads->quads.mesh = PolygonMesh();
      meter.finish("quads");
    };
  }
  // The output is written from the final map while its figures are measured (a Draco file
  // after them: its encoder takes a copy of the mesh, the figures' memory would add to it).
  // A failed write is reported as the output's, after the pipeline (not in the input's name).
  bool written = false;
  std::exception_ptr writeError;
  if (formatFromPath(c.output) != MeshFormat::Draco) {
    c.options.withFinalMap = [&](const TriangleMesh& map) {
      try {
        writeMesh(meshFile, map);
        written = true;
      } catch (...) {
        writeError = std::current_exception();
      }
    };
  }
  PipelineResult r;
  try {
    r = parameterize(std::move(raw), c.options);
  } catch (...) {
    rethrowWithContext(c.input);
  }
  if (writeError) std::rethrow_exception(writeError);
  if (c.renderPath) {
    RenderOptions renderOptions;
    renderOptions.drawSeams = renderOptions.drawCones = true;
    renderOptions.progress = c.options.progress;
    writePng(*renderFile, renderCheckerboard(r.mesh, r.topology, renderOptions).image);
    meter.finish("render");
  }
  // The writer takes the mesh and its map (r.size keeps their figures): the corner table goes
  // first, and a Draco write frees the mesh as its own copy takes it.
  r.topology = Topology();
  if (!written) writeMesh(meshFile, std::move(r.mesh));
  meter.finish("write");
  printSummary(c, r, meter);
  // The meter's peak: the stages reset the high-water mark as they close.
  std::printf("path in memory%s: estimate %s%s %s the budget %s; peak memory %s\n",
              directionStore ? " (the field's directions on disk while the map is built)" : "",
              formatByteSize(memoryPath.estimate).c_str(), declared ? "" : " (faces guessed from the file size)",
              memoryPath.estimate <= memoryPath.budget ? "within" : "above", formatByteSize(memoryPath.budget).c_str(),
              formatByteSize(meter.peakBytes()).c_str());
  if (quads) printQuadSummary(*c.quadsPath, *quads);
  if (c.reportPath) {
    ParamReportContext context =
        paramReportContext(c.options, meter, c.input, c.output, c.solverName, c.fieldSource);
    context.memoryBudget = memoryPath.budget;
    context.estimatedBytes = memoryPath.estimate;
    context.fieldBytesOnDisk = directionStore ? directionStore->bytesStored() : 0;
    if (reportFile) {
      reportFile->write(paramReportJson(r, context));
    } else {
      writeTextOutput("-", paramReportJson(r, context));
    }
  }
  outputs.commit();
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"param", "compute a seamless parameterization (per-corner u, v)",
                 "usage: seamvox param MESH -o OUT.obj|.ply|.drc [--solver auto|hat|vox|voxloc] [--grid N]\n"
                 "                     [--rings K] [--spline-cells N] [--field auto|smooth|proxy|FILE]\n"
                 "                     [--field-smoothing N] [--no-rough-spots]\n"
                 "                     [--edge-length H | --cells N] [--merge-cones F] [--merge-in-map]\n"
                 "                     [--greedy] [--no-untangle] [--no-leftover-resolve] [--no-cone-resolve]\n"
                 "                     [--no-smoothed-evaluation] [--weld]\n"
                 "                     [--keep-order] [--report R.json]\n"
                 "                     [--render OUT.png] [--report-components N] [--drop-unsolved]\n"
                 "                     [--quads Q.obj|.ply] [--close-holes C] [--align-boundary]\n"
                 "                     [--feature-angle DEG]\n"
                 "\n"
                 "Reads and cleans MESH (.ply .obj .off .drc, or .stl, binary or ASCII, its facets'\n"
                 "corners welded at equal positions), computes (or reads) a cross field, cuts through\n"
                 "its cones and\n"
                 "writes per-corner (u, v) in grid units: across every seam q' = r q + t with r a\n"
                 "quarter turn and t an integer vector, and grad q follows the field with spacing H.\n"
                 "\n"
                 "  --solver auto       hat up to 400K faces (x (N/128)^2; 80K with feature curves to\n"
                 "                      align, which only hat aligns), voxloc above (default)\n"
                 "  --solver voxloc     volumetric B-spline basis on an N^3 grid, then a local hat\n"
                 "                      solve near cones and on collapsed or flipped triangles\n"
                 "  --solver vox        the volumetric basis alone\n"
                 "  --solver hat        the per-vertex hat basis (exact reference, one global solve)\n"
                 "  --grid N            voxels per axis for vox and voxloc: 64, 128 (default), 256, 512\n"
                 "  --rings K           rings of neighbours added around the voxloc region (default 1)\n"
                 "  --spline-cells N    voxloc: solve the region first in trilinear B-splines N per\n"
                 "                      voxel edge (one unknown per vertex only next to cones), then\n"
                 "                      per vertex only where that leaves faces collapsed or flipped\n"
                 "                      (default 4; a 22M-face scan: 0.8% of its vertices solved per\n"
                 "                      vertex against 6.2% with 0, which solves every round per vertex)\n"
                 "  --field auto        the smoothest cross field: smooth up to 400K faces, proxy above\n"
                 "                      (default)\n"
                 "  --field smooth      the smoothest cross field by one solve over all faces (exact)\n"
                 "  --field proxy       the smoothest cross field solved on a coarse grid proxy, then\n"
                 "                      smoothed on the faces (linear time and memory; massive meshes)\n"
                 "  --field FILE        per-face field (.crossfield or plain, one vector per input face)\n"
                 "  --field-smoothing N smoothing steps of the surface a computed field and its cones\n"
                 "                      are read on (1..64, default 3). On strong scan noise 8 takes\n"
                 "                      most noise cone pairs off the field (bench/RESULTS.md)\n"
                 "  --no-rough-spots    read the field and its cones on that surface as it is: by\n"
                 "                      default its crumpled spots (scan noise on parts tessellated\n"
                 "                      finer than the rest) are smoothed further within H, where\n"
                 "                      they would put clusters of cone pairs into the field\n"
                 "  --edge-length H     grid spacing in mesh units\n"
                 "  --cells N           H = bounding-box diagonal / N (default N = 100)\n"
                 "  --merge-cones F     move the index of cones at most F * H apart (along edges) onto\n"
                 "                      one of them: closer than the grid resolves, they would collapse\n"
                 "                      the faces between them; default 1, 0 keeps every cone. With\n"
                 "                      merging on, close cones a solve puts on one point, or whose\n"
                 "                      faces stay flipped after the repair, are merged and the map\n"
                 "                      solved again (up to 3 passes; a pass retried for flips is kept\n"
                 "                      only when it leaves fewer, and in memory it starts only when\n"
                 "                      the earlier map fits the budget beside the estimate). With\n"
                 "                      F > 0, a cone of a full turn (angle 0: the field may turn so\n"
                 "                      around a pole of many thin faces) is split into cones of at\n"
                 "                      most +2 quarter turns nearby (report conesSplit)\n"
                 "  --merge-in-map      a pair of cones a solve puts on one point, one of them ending a\n"
                 "                      single seam, is merged in the map itself (a neighbourhood\n"
                 "                      solved again) instead of in another pass: faster, may leave\n"
                 "                      flips next to the merged cone (in memory only; report\n"
                 "                      conePairsMergedInMap)\n"
                 "  --greedy            round translations in batches, re-solving in between\n"
                 "  --no-untangle       skip the foldover repair (patches around flipped triangles\n"
                 "                      re-solved with stiffening; seams and translations kept)\n"
                 "  --no-leftover-resolve\n"
                 "                      vox, voxloc: no hat re-solve within 1 H of the flips the\n"
                 "                      repair leaves, and no second repair after it (by default\n"
                 "                      both run, before any further cone pass; report\n"
                 "                      untangle.leftover)\n"
                 "  --no-cone-resolve   no re-solves of their own, within 1, 2 and 4 H, for cones the\n"
                 "                      map leaves a full turn short next to a flip (a valence-5\n"
                 "                      cone at 90 degrees, the map folded beside it, which the\n"
                 "                      later steps unfold only by winding a neighbour twice;\n"
                 "                      report untangle.miswoundCones, miswoundConesAfter)\n"
                 "  --no-smoothed-evaluation\n"
                 "                      vox, voxloc: keep the voxel map at the vertices of the faces\n"
                 "                      it folds (by default re-evaluated at the field's smoothed\n"
                 "                      surface, where scan noise does not fold it)\n"
                 "  --align-boundary    the field follows boundary curves and the map puts them on\n"
                 "                      integer iso-lines, so quads end cleanly there (direct field\n"
                 "                      and hat solver only; the report counts curves aligned and\n"
                 "                      not); off by default: it costs gradient error on smooth outlines\n"
                 "  --feature-angle DEG also align interior edges whose faces turn by more than DEG\n"
                 "                      degrees (creases); 0: none. Default: 30 on a CAD-like mesh\n"
                 "                      (its creases at 30 degrees form curves of 6+ edges on\n"
                 "                      average; where the direct field follows them and the hat\n"
                 "                      solver holds them: --solver hat, or auto up to 80K faces),\n"
                 "                      none on a scan, whose noisy folds would all be creases\n"
                 "  --weld              weld coincident vertices before cleaning\n"
                 "  --keep-order        keep the input's vertex and face order in the output even when\n"
                 "                      it is scattered (by default an input of 512K+ faces in a\n"
                 "                      scattered order is put in spatial order: several times faster)\n"
                 "  --report FILE       JSON report: quality, counts, system sizes, factor memory,\n"
                 "                      stage timings, peak memory, components\n"
                 "  --report-components N  components listed one by one in the report, the largest\n"
                 "                      (default 1000); the rest are counted together\n"
                 "  --drop-unsolved     remove the components whose system cannot be factored from\n"
                 "                      the output instead of writing them unmapped at (u, v) = 0\n"
                 "  --render OUT.png    also render the result (checkerboard, seams, cones; 1024x1024,\n"
                 "                      default view of seamvox render)\n"
                 "  --quads Q.obj|.ply  also write the map's quad mesh (seamvox quads) and print its\n"
                 "                      validation\n"
                 "  --close-holes C     holes whose boundary fits in a box of C * H carry no seam\n"
                 "                      translation, so the map extends over them and a quad mesh\n"
                 "                      can close them (default 2 with --quads, else 0: translations\n"
                 "                      at tiny holes let the map follow the field more closely)\n"
                 "  --quiet             no progress on stderr\n"
                 SEAMVOX_MEMORY_HELP
                 "                        a mesh whose estimated in-memory peak (from the header's\n"
                 "                        counts) exceeds the budget runs out of core: every stage\n"
                 "                        streams through the scratch folder, the grid-sized system\n"
                 "                        and the passes' buffers stay within the budget (at least\n"
                 "                        632M at --grid 128). That path writes the mesh in spatial\n"
                 "                        order with its map (.ply or .obj) and has no further cone\n"
                 "                        passes, --quads, --render, --close-holes, features or hat\n"
                 "                        solver yet\n"
                 "  --out-of-core         take the out-of-core path whatever the estimate\n",
                 {"greedy", "merge-in-map", "no-rough-spots", "no-untangle", "no-leftover-resolve", "no-cone-resolve", "no-smoothed-evaluation", "weld", "keep-order", "drop-unsolved", "align-boundary", "out-of-core"},
                 &runParam});

}  // namespace seamvox::cli
