// seamvox field: cross field (smoothest, curvature-aligned or imported), cones, cut and seams.
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>

#include "core/pipeline/parameterize.h"
#include "core/system/errors.h"
#include "io/field_io.h"
#include "io/json.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "io/param_report.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

/// Cones as OBJ points: a comment with vertex id and index, `v x y z r g b` (red for positive,
/// blue for negative index), then one `p` element per cone.
void writeConesObj(AtomicFile& file, const TriangleMesh& mesh, const FieldSingularities& sing) {
  std::string text = "# seamvox cones: " + std::to_string(sing.cones.size()) +
                     " vertices with nonzero index (in quarter turns)\n";
  char buf[200];
  for (VertexId v : sing.cones) {
    const Vec3d p = mesh.origin + mesh.position(v);  // in the file's coordinates
    const int k = sing.index4[v];
    std::snprintf(buf, sizeof buf,
                  mesh.origin.isZero(0.0) ? "# cone vertex %u index4 %+d (index %+g)\nv %.9g %.9g %.9g %s\n"
                                          : "# cone vertex %u index4 %+d (index %+g)\nv %.17g %.17g %.17g %s\n",
                  v, k,
                  k / 4.0, p.x(), p.y(), p.z(), k > 0 ? "1 0 0" : "0 0 1");
    text += buf;
  }
  for (std::size_t i = 0; i < sing.cones.size(); ++i) text += "p " + std::to_string(i + 1) + "\n";
  file.write(text);
}

/// Seams as OBJ polylines: the seam vertices once each, then one `l` element per seam.
void writeSeamsObj(AtomicFile& file, const TriangleMesh& mesh, const Topology& topology,
                   const CutResult& cut) {
  std::map<VertexId, std::size_t> objIndex;
  std::string vertices, lines;
  char buf[128];
  auto index = [&](VertexId v) {
    auto [it, added] = objIndex.emplace(v, objIndex.size() + 1);
    if (added) {
      const Vec3d p = mesh.origin + mesh.position(v);
      std::snprintf(buf, sizeof buf, mesh.origin.isZero(0.0) ? "v %.9g %.9g %.9g\n" : "v %.17g %.17g %.17g\n", p.x(),
                    p.y(), p.z());
      vertices += buf;
    }
    return it->second;
  };
  for (std::size_t s = 0; s < cut.seams.size(); ++s) {
    const SeamCurve& seam = cut.seams[s];
    lines += "# seam " + std::to_string(s) + " rotation " + std::to_string(seam.matching) +
             " quarter turns, " + std::to_string(seam.corners.size()) + " edges\nl " +
             std::to_string(index(seam.start));
    for (CornerId c : seam.corners) lines += " " + std::to_string(index(topology.vertex(prevCorner(c))));
    lines += "\n";
  }
  file.write("# seamvox seams: " + std::to_string(cut.seams.size()) + " curves\n" + vertices + lines);
}

/// The field command's arguments, checked.
struct FieldCommand {
  std::string input;
  std::optional<std::string> output, importPath, conesPath, seamsPath;
  double curvature = 0.0;
  FieldMethod method = FieldMethod::Auto;
  double mergeCones = 0.0;
  std::uint32_t fieldSmoothing = kFieldSmoothingIterations;  ///< steps of the field's surface (--field-smoothing)
  bool roughSpots = true;  ///< its rough spots smoothed within h (--no-rough-spots)
  GridSpacing spacing;
  bool json = false, weld = false;
  FeatureOptions features;  ///< the curves the field follows, as in param
  ProgressFn progress;
};

FieldCommand parseFieldArgs(Args& args) {
  FieldCommand c;
  c.input = args.positional(0, "the input mesh (seamvox field MESH -o FIELD)");
  c.output = args.value("output");
  if (!c.output) throw UsageError("missing -o FIELD (the field file to write)");
  c.importPath = args.value("import");
  c.curvature = args.number("curvature", 0.0, 0.0, std::numeric_limits<double>::max());
  if (c.importPath && args.value("curvature")) throw UsageError("--curvature has no effect with --import");
  if (c.importPath && args.value("field")) throw UsageError("--field has no effect with --import");
  try {
    c.method = parseFieldMethod(args.value("field", "auto"));
  } catch (const InputError& e) {
    throw UsageError(std::string("--field: ") + e.what());
  }
  if (c.curvature > 0.0 && c.method == FieldMethod::Proxy) throw UsageError("--curvature needs --field smooth or auto");
  c.mergeCones = parseMergeCones(args);
  c.fieldSmoothing = parseFieldSmoothing(args, c.importPath.has_value());
  c.roughSpots = !args.flag("no-rough-spots");
  c.spacing = parseGridSpacing(args);
  c.conesPath = args.value("cones");
  c.seamsPath = args.value("seams");
  c.json = args.flag("json");
  c.weld = args.flag("weld");
  c.features.alignBoundary = args.flag("align-boundary");
  c.features.featureAngle = args.number("feature-angle", 0.0, 0.0, 179.0);
  c.progress = makeProgress(args.flag("quiet"));
  args.finish(1);
  checkOutputPaths({{"MESH", c.input}, {"--import", c.importPath.value_or("")}},
                   {{"-o", *c.output}, {"--cones", c.conesPath.value_or("")}, {"--seams", c.seamsPath.value_or("")}});
  return c;
}

/// What the command computes: the cleaned mesh, its field and the cut through its cones.
struct FieldRun {
  CleanResult clean;
  std::uint32_t inputFaces = 0;
  FieldMethod method = FieldMethod::Auto;  ///< resolved
  CrossField field;
  FieldSolveStats fieldSolve;
  double edgeLength = 0.0;
  ConeCut coneCut;
};

/// Read, clean, field, cut: each a stage of the meter.
FieldRun computeField(const FieldCommand& c, StageMeter& meter) {
  FieldRun run;
  TriangleMesh raw = readMesh(c.input);
  run.inputFaces = raw.numFaces();
  raw.cornerUV.clear();
  FieldSource source;
  source.method = c.method;
  source.curvatureWeight = c.curvature;
  source.smoothingSteps = c.fieldSmoothing;
  if (c.importPath) source.importedPerInputFace = readFieldVectors(*c.importPath, run.inputFaces);
  meter.finish("read");
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = c.weld;
  cleanOptions.progress = c.progress;
  run.clean = cleanMeshOf(c.input, std::move(raw), cleanOptions);
  const TriangleMesh& mesh = run.clean.mesh;
  const Topology& topology = run.clean.topology;
  meter.finish("clean");

  run.method = resolveFieldMethod(c.method, mesh.numFaces());
  if (c.curvature > 0.0 && run.method == FieldMethod::Proxy) {
    throw UsageError("--curvature needs the direct field (--field smooth): the proxy field is the smoothest field only");
  }
  // h as param takes it (the diagonal without spikes), so both merge the same cones.
  run.edgeLength = c.spacing.spacing(run.clean.report.diagonalWithoutSpikes);
  source.roughSpots = c.roughSpots;
  source.gridLength = run.edgeLength;  // as parameterize sets it
  try {
    const std::optional<FieldSource> aligned =
        alignedFieldSource(topology, findFeatures(mesh, topology, c.features), source, mesh.numFaces());
    run.field = computeFieldFromSource(run.clean.mesh, topology, run.clean.faceOrigin, run.inputFaces,
                                       aligned ? *aligned : source, c.progress, &run.fieldSolve);
  } catch (...) {
    rethrowWithContext(c.importPath ? *c.importPath : c.input);
  }
  meter.finish("field");
  // The cones param cuts through: those closer than the merge distance are merged, as param does
  // before its first cut (param may merge a few more pairs that a solve puts on one point).
  run.coneCut = cutThroughCones(mesh, topology, run.field, c.mergeCones * run.edgeLength, {}, 0.0, c.progress);
  meter.finish("cut");
  return run;
}

/// The field per input face (faces cleaning dropped get a zero vector: "no preference"), the
/// cones and the seams, committed together.
void writeFieldOutputs(const FieldCommand& c, const FieldRun& run, OutputSet& outputs, AtomicFile& fieldFile,
                       AtomicFile* conesFile, AtomicFile* seamsFile) {
  const TriangleMesh& mesh = run.clean.mesh;
  std::vector<Vec3d> perInputFace(run.inputFaces, Vec3d::Zero());
  for (FaceId f = 0; f < mesh.numFaces(); ++f) perInputFace[run.clean.faceOrigin[f]] = run.field.at(f);
  writeField(fieldFile, perInputFace);
  if (conesFile) writeConesObj(*conesFile, mesh, run.coneCut.singularities);
  if (seamsFile) writeSeamsObj(*seamsFile, mesh, run.clean.topology, run.coneCut.cut);
  outputs.commit();
}

/// Counts for the summary: Euler characteristic, cones per index, cut and seam edges.
struct FieldFigures {
  std::int64_t chi = 0;
  std::uint32_t closedComponents = 0;
  std::map<int, std::uint64_t> conesByIndex;
  std::uint64_t cutEdges = 0, seamEdges = 0;
};

FieldFigures countFieldFigures(const Topology& topology, const FieldSingularities& sing, const CutResult& cut) {
  FieldFigures figures;
  for (const ComponentInfo& c : computeComponents(topology).components) {
    figures.chi += c.eulerCharacteristic;
    figures.closedComponents += c.boundaryLoops == 0;
  }
  for (VertexId v : sing.cones) ++figures.conesByIndex[sing.index4[v]];
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (cut.corners.isCut(c) && (o == kInvalidId || c < o)) ++figures.cutEdges;
  }
  for (const SeamCurve& s : cut.seams) figures.seamEdges += s.corners.size();
  return figures;
}

void printFieldJson(const FieldCommand& c, const FieldRun& run, const FieldFigures& figures,
                    const StageMeter& meter, double total, std::uint64_t peak) {
  const TriangleMesh& mesh = run.clean.mesh;
  const FieldSingularities& sing = run.coneCut.singularities;
  const ConeMergeResult& merged = run.coneCut.merged;
  JsonWriter j;
  j.beginObject();
  j.key("input").value(c.input).key("output").value(*c.output);
  j.key("field").value(c.importPath ? "import" : c.curvature > 0.0 ? "curvature" : "smoothest");
  j.key("fieldMethod").value(c.importPath ? "import" : fieldMethodName(run.method));
  j.key("fieldSmoothing").value(c.importPath ? 0u : c.fieldSmoothing);
  j.key("roughSpots").value(!c.importPath && c.roughSpots);
  j.key("roughVertices").value(run.fieldSolve.roughVertices);
  j.key("roughSpotVertices").value(run.fieldSolve.roughSpotVertices);
  j.key("faces").value(std::uint64_t{mesh.numFaces()}).key("vertices").value(std::uint64_t{mesh.numVertices()});
  j.key("eulerCharacteristic").value(figures.chi);
  j.key("cones").value(std::uint64_t{sing.cones.size()});
  j.key("conesBeforeMerge").value(std::uint64_t{run.coneCut.conesBeforeMerge});
  j.key("conesCancelled").value(std::uint64_t{2 * merged.cancelledPairs});
  j.key("conesMerged").value(std::uint64_t{merged.mergedPairs});
  j.key("conesSplit").value(std::uint64_t{merged.splitCones});
  j.key("edgeLength").value(run.edgeLength).key("mergeCones").value(c.mergeCones);
  j.key("conesByIndex4").beginObject();
  for (const auto& [k, n] : figures.conesByIndex) j.key(std::to_string(k)).value(n);
  j.endObject();
  j.key("indexSum4").value(sing.indexSum4());
  j.key("seams").value(std::uint64_t{run.coneCut.cut.seams.size()});
  j.key("seamEdges").value(figures.seamEdges).key("cutEdges").value(figures.cutEdges);
  writeFieldSolve(j, run.fieldSolve);
  j.key("seconds").beginObject();
  for (const StageFigures& stage : meter.stages()) j.key(stage.name).value(stage.seconds);
  j.key("total").value(total).endObject();
  j.key("peakResidentBytes").value(peak);
  j.endObject();
  std::printf("%s\n", j.str().c_str());
}

void printFieldText(const FieldCommand& c, const FieldRun& run, const FieldFigures& figures,
                    const StageMeter& meter, std::uint64_t peak) {
  const TriangleMesh& mesh = run.clean.mesh;
  const FieldSingularities& sing = run.coneCut.singularities;
  const ConeMergeResult& merged = run.coneCut.merged;
  const std::size_t conesBeforeMerge = run.coneCut.conesBeforeMerge;
  std::printf("%s -> %s: %u faces, %u vertices, chi %lld\n", c.input.c_str(), c.output->c_str(),
              mesh.numFaces(), mesh.numVertices(), static_cast<long long>(figures.chi));
  std::printf("field: %s%s; %zu cones (", c.importPath ? "imported" : c.curvature > 0.0 ? "curvature-aligned" : "smoothest",
              c.importPath ? "" : run.method == FieldMethod::Proxy ? " (proxy)" : " (direct)", sing.cones.size());
  bool first = true;
  for (const auto& [k, n] : figures.conesByIndex) {
    std::printf("%s%llu of index %+g", first ? "" : ", ", static_cast<unsigned long long>(n), k / 4.0);
    first = false;
  }
  std::printf("), index sum %+g%s\n", sing.indexSum4() / 4.0,
              figures.closedComponents ? " (Poincare-Hopf: chi on closed components)" : "");
  if (conesBeforeMerge != sing.cones.size()) {
    std::printf("merged cones closer than %g h (h = %.6g): %zu before, %u pairs cancelled, %u merged\n",
                c.mergeCones, run.edgeLength, conesBeforeMerge, merged.cancelledPairs, merged.mergedPairs);
  }
  std::printf("cut: %llu edges, %zu seams with %llu edges\n", static_cast<unsigned long long>(figures.cutEdges),
              run.coneCut.cut.seams.size(), static_cast<unsigned long long>(figures.seamEdges));
  std::printf("time:");
  for (const StageFigures& stage : meter.stages()) std::printf(" %s %.2fs", stage.name.c_str(), stage.seconds);
  std::printf("\n");
  std::printf("peak memory: %.1f MB\n", peak / 1048576.0);
}

int runField(Args& args) {
  const FieldCommand c = parseFieldArgs(args);
  // Every output is staged now (a missing folder fails before the work) and committed together.
  OutputSet outputs;
  AtomicFile& fieldFile = outputs.add(*c.output);
  AtomicFile* conesFile = c.conesPath ? &outputs.add(*c.conesPath) : nullptr;
  AtomicFile* seamsFile = c.seamsPath ? &outputs.add(*c.seamsPath) : nullptr;

  StageMeter meter;
  const FieldRun run = computeField(c, meter);
  writeFieldOutputs(c, run, outputs, fieldFile, conesFile, seamsFile);
  meter.finish("write");

  const FieldFigures figures = countFieldFigures(run.clean.topology, run.coneCut.singularities, run.coneCut.cut);
  const double total = meter.totalSeconds();
  const std::uint64_t peak = meter.peakBytes();
  if (c.json) {
    printFieldJson(c, run, figures, meter, total, peak);
  } else {
    printFieldText(c, run, figures, meter, peak);
  }
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"field", "cross field, cones, cut graph and seams of a mesh",
                 "usage: seamvox field MESH -o FIELD [--field auto|smooth|proxy] [--import FILE]\n"
                 "                     [--curvature W] [--field-smoothing N] [--no-rough-spots]\n"
                 "                     [--cones OUT.obj]\n"
                 "                     [--merge-cones F] [--edge-length H | --cells N]\n"
                 "                     [--seams OUT.obj] [--json] [--weld]\n"
                 "                     [--align-boundary] [--feature-angle DEG]\n"
                 "\n"
                 "Cleans MESH, computes the smoothest cross field (or imports one), its cones and the\n"
                 "cut to a disk per component, and writes the field in the plain per-face format\n"
                 "(header `1 F`, one `x y z` line per input face; see io/field_io.h), which\n"
                 "`seamvox param --field FIELD` reads back.\n"
                 "\n"
                 "  --field auto      smooth up to 400K faces, proxy above (default)\n"
                 "  --field smooth    one solve over all faces (exact; up to a few million faces)\n"
                 "  --field proxy     solved on a coarse grid proxy, then smoothed on the faces\n"
                 "                    (linear time and memory; massive meshes; no --curvature)\n"
                 "  --import FILE     use the field in FILE (.crossfield `2 F` or plain) instead\n"
                 "  --curvature W     align with principal curvature, weight W > 0 (0: smoothest)\n"
                 "  --field-smoothing N  smoothing steps of the surface the field and its cones are\n"
                 "                    read on (1..64, default 3), as in param\n"
                 "  --no-rough-spots  leave that surface's crumpled spots as they are (param's\n"
                 "                    default smooths them further within H)\n"
                 "  --merge-cones F   merge cones at most F * H apart along edges, as param does\n"
                 "                    (default 1; 0 shows every cone of the field)\n"
                 "  --edge-length H   grid spacing for --merge-cones (as in param)\n"
                 "  --cells N         H = bounding-box diagonal / N (default N = 100)\n"
                 "  --cones OUT.obj   cones as OBJ points (red: positive index, blue: negative)\n"
                 "  --seams OUT.obj   seam curves as OBJ polylines\n"
                 "  --json            print a JSON report (cones, index sum, seams, times, memory)\n"
                 "  --align-boundary, --feature-angle DEG  the curves the field follows, as in\n"
                 "                    param (boundaries; creases above DEG degrees; default none)\n"
                 "  --weld            weld coincident vertices before cleaning\n"
                 "  --quiet           no progress on stderr\n",
                 {"json", "weld", "align-boundary", "no-rough-spots"},
                 &runField});

}  // namespace seamvox::cli
