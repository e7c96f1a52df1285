// seamvox quads: the quad mesh of a seamless map (its integer points and iso-lines).
#include <cstdio>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/system/memory.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "io/polygon_io.h"
#include "io/quad_report.h"
#include "tools/cli.h"

namespace seamvox::cli {

void printQuadSummary(const std::string& output, const QuadRun& run) {
  using U = unsigned long long;
  const QuadValidation& v = run.check;
  const QuadStats& s = run.quads.stats;
  std::printf("quads -> %s: %llu faces (%.2f%% quads; %llu triangles, %llu pentagons, %llu other), "
              "%llu vertices, %llu edges, %llu boundary loops\n",
              output.c_str(), U(v.faces), 100.0 * v.quadFraction, U(v.triangles), U(v.pentagons),
              U(v.otherFaces), U(v.vertices), U(v.edges), U(v.boundaryLoops));
  std::printf("map: %u cones (%u on integer points), %llu flipped and %llu degenerate triangles, "
              "snapped by at most %.2g\n", run.quads.cones, run.quads.conesOnGridVertices,
              U(s.flippedFaces), U(s.degenerateFaces), s.maxSnap);
  std::printf("extraction: %llu integer points, %llu boundary points, %llu traced edges; untraced %llu, "
              "unpaired %llu, open faces %llu, two-edge faces %llu, ends at cones %llu, cones halfway %llu, spikes %llu, loops %llu, pillows %llu; islands %llu (%llu triangles), "
              "holes without a point %llu, holes smaller than a quad closed %llu\n",
              U(s.gridVertices), U(s.boundaryVertices), U(s.tracedEdges), U(s.untracedEdges),
              U(s.unpairedEdges), U(s.openFaces), U(s.digons), U(s.deadEnds), U(s.halfwayCones), U(s.spikes), U(s.loops), U(s.pillows), U(s.islands), U(s.islandFaces),
              U(s.holesWithoutVertex), U(run.filledHoles));
  if (run.translatedHoles > 0) {
    std::printf("note: %llu small holes were left open because the map carries a seam translation around "
                "them; a map from `seamvox param --close-holes 2` (the default with --quads) has none\n",
                U(run.translatedHoles));
  }
  std::printf("validation: %s; non-manifold edges %llu, vertices %llu; faces through a vertex twice %llu; "
              "%llu/%zu components with the map's Euler characteristic and boundary loops; irregular vertices "
              "off cones %llu, cones with valence != 4 - k %llu of %llu, interior non-quads %llu\n",
              v.isValid() ? "valid" : "NOT valid", U(v.nonManifoldEdges), U(v.nonManifoldVertices),
              U(v.degenerateFaces),
              U(v.components.size() - v.componentsDiffering), v.components.size(), U(v.irregularVertices),
              U(v.conesWithWrongValence), U(v.conesOnVertices), U(v.interiorNonQuads));
}

namespace {

int runQuads(Args& args) {
  const std::string input = args.positional(0, "the map (seamvox quads MAP -o OUT.obj|.ply)");
  const auto output = args.value("output");
  if (!output) throw UsageError("missing -o OUT (.obj or .ply)");
  const MeshFormat format = formatFromPath(*output);
  if (format != MeshFormat::Obj && format != MeshFormat::Ply) {
    throw UsageError("the quad mesh is written as .obj or .ply: " + *output);
  }
  const std::int64_t scale = args.integer("scale", 1, 1, 1 << 20);
  const auto reportPath = args.value("report");
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = args.flag("weld");
  const ProgressFn progress = makeProgress(args.flag("quiet"));
  args.finish(1);
  checkOutputPaths({{"MAP", input}}, {{"-o", *output}, {"--report", reportPath.value_or("")}});

  OutputSet outputs;
  AtomicFile& meshFile = outputs.add(*output);
  AtomicFile* reportFile = reportPath && *reportPath != "-" ? &outputs.add(*reportPath) : nullptr;
  StageMeter meter;
  ReadOptions readOptions;
  readOptions.readUV = true;
  TriangleMesh mesh = readMesh(input, readOptions);
  if (!mesh.hasUV()) throw InputError(input + ": has no texture coordinates; run seamvox param first");
  cleanOptions.progress = progress;
  const CleanResult cleaned = cleanMeshOf(input, std::move(mesh), cleanOptions);
  meter.finish("read");
  const QuadRun run = extractCheckedQuads(input, cleaned.mesh, cleaned.topology, scale, progress);
  meter.finish("quads");
  writePolygonMesh(meshFile, run.quads.mesh);
  meter.finish("write");
  std::printf("%s: %u triangles, scale %lld\n", input.c_str(), cleaned.mesh.numFaces(),
              static_cast<long long>(scale));
  printQuadSummary(*output, run);
  std::printf("time %.2f s (read %.2f, quads %.2f, write %.2f), peak %.1f MB\n", meter.totalSeconds(),
              meter.stages()[0].seconds, meter.stages()[1].seconds, meter.stages()[2].seconds,
              meter.peakBytes() / 1048576.0);
  if (reportPath) {
    const QuadReportContext context =
        quadReportContext(run, cleaned.mesh.numFaces(), scale, meter, input, *output);
    const std::string json = quadReportJson(run.quads, run.check, context);
    if (reportFile) reportFile->write(json);
    else writeTextOutput("-", json);
  }
  outputs.commit();
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"quads", "quad mesh of a seamless map (its integer points and iso-lines)",
                 "usage: seamvox quads MAP -o OUT.obj|.ply [--scale K] [--report R.json]\n"
                 "\n"
                 "Reads MAP (a mesh with per-corner texture coordinates in grid units, as written by\n"
                 "seamvox param), which must be seamless, and writes its quad mesh: a vertex at every\n"
                 "integer point of the map, edges along the integer iso-lines traced across seams,\n"
                 "quads everywhere except at cones (a cone of index k gives valence 4 - k) and where\n"
                 "iso-lines meet the boundary, which stays a boundary. Prints and reports the\n"
                 "validation: an oriented 2-manifold with the map's Euler characteristic and boundary\n"
                 "loops per component, valences, and what could not be traced (flipped triangles).\n"
                 "\n"
                 "  -o OUT             the quad mesh (.obj or binary .ply; polygons)\n"
                 "  --scale K          iso-lines every K units (K x K cells); only for maps whose seam\n"
                 "                     translations are all multiples of K, which param's maps (rounded\n"
                 "                     to any integers) are not: for a coarser mesh, map with a K times\n"
                 "                     larger --edge-length (or K times fewer --cells) instead\n"
                 "  --report FILE      JSON report (- for stdout)\n"
                 "  --weld             weld coincident vertices first (maps split along seams)\n"
                 "  --quiet            no progress on stderr\n",
                 {"weld"},
                 &runQuads});

}  // namespace seamvox::cli
