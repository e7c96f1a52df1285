// The JSON report of a quad extraction.
#include "io/quad_report.h"

#include <utility>

#include "io/json.h"

namespace seamvox {

QuadReportContext quadReportContext(const QuadRun& run, std::uint32_t mapFaces, std::int64_t scale,
                                    const StageMeter& meter, std::string input, std::string output) {
  QuadReportContext context;
  context.input = std::move(input);
  context.output = std::move(output);
  context.scale = scale;
  context.mapFaces = mapFaces;
  context.seamResidual = run.seams.maxResidual;
  context.integerDistance = run.seams.maxIntegerDistance;
  context.filledHoles = run.filledHoles;
  context.translatedHoles = run.translatedHoles;
  context.stages = meter.stages();
  context.totalSeconds = meter.totalSeconds();
  context.peakBytes = meter.peakBytes();
  return context;
}

std::string quadReportJson(const QuadResult& quads, const QuadValidation& v, const QuadReportContext& context) {
  using U64 = std::uint64_t;
  const QuadStats& s = quads.stats;
  JsonWriter j;
  j.beginObject();
  j.key("input").value(context.input).key("output").value(context.output);
  j.key("scale").value(context.scale);
  j.key("map").beginObject();
  j.key("faces").value(U64{context.mapFaces});
  j.key("seamResidual").value(context.seamResidual).key("integerDistance").value(context.integerDistance);
  j.key("cones").value(U64{quads.cones}).key("conesOnGridVertices").value(U64{quads.conesOnGridVertices});
  j.key("flippedFaces").value(s.flippedFaces).key("degenerateFaces").value(s.degenerateFaces);
  j.key("maxSnap").value(s.maxSnap).key("openVertexFans").value(s.openVertexFans);
  j.key("seamEdgesOffScale").value(s.seamEdgesOffScale);
  j.endObject();
  j.key("extraction").beginObject();
  j.key("gridVertices").value(s.gridVertices).key("boundaryVertices").value(s.boundaryVertices);
  j.key("tracedEdges").value(s.tracedEdges).key("boundaryEdges").value(s.boundaryEdges);
  j.key("untracedEdges").value(s.untracedEdges).key("unpairedEdges").value(s.unpairedEdges);
  j.key("openFaces").value(s.openFaces).key("digons").value(s.digons).key("deadEnds").value(s.deadEnds);
  j.key("halfwayCones").value(s.halfwayCones).key("spikes").value(s.spikes).key("loops").value(s.loops).key("pillows").value(s.pillows);
  j.key("pointsInFlippedFaces").value(s.pointsInFlippedFaces);
  j.key("holesWithoutVertex").value(s.holesWithoutVertex).key("smallHolesClosed").value(context.filledHoles);
  j.key("smallHolesWithTranslation").value(context.translatedHoles);
  j.key("islands").value(s.islands).key("islandFaces").value(s.islandFaces);
  j.endObject();
  j.key("quadMesh").beginObject();
  j.key("vertices").value(v.vertices).key("edges").value(v.edges).key("faces").value(v.faces);
  j.key("quads").value(v.quads).key("triangles").value(v.triangles).key("pentagons").value(v.pentagons);
  j.key("otherFaces").value(v.otherFaces).key("quadFraction").value(v.quadFraction);
  j.key("boundaryEdges").value(v.boundaryEdges).key("boundaryLoops").value(v.boundaryLoops);
  j.endObject();
  j.key("validation").beginObject();
  j.key("valid").value(v.isValid());
  j.key("nonManifoldEdges").value(v.nonManifoldEdges).key("nonManifoldVertices").value(v.nonManifoldVertices);
  j.key("degenerateFaces").value(v.degenerateFaces);
  j.key("irregularVertices").value(v.irregularVertices);
  j.key("conesOnVertices").value(v.conesOnVertices).key("conesWithWrongValence").value(v.conesWithWrongValence);
  j.key("interiorNonQuads").value(v.interiorNonQuads);
  j.key("componentsChecked").value(U64{v.components.size()});
  j.key("componentsDiffering").value(v.componentsDiffering);
  j.key("components").beginArray();
  for (const QuadComponentCheck& c : v.components) {
    if (c.matches() && v.components.size() > 100) continue;  // many: only the differing ones
    j.beginObject();
    j.key("component").value(U64{c.component}).key("matches").value(c.matches());
    j.key("vertices").value(c.vertices).key("edges").value(c.edges).key("faces").value(c.faces);
    j.key("eulerCharacteristic").value(c.eulerCharacteristic).key("mapEulerCharacteristic").value(c.mapEulerCharacteristic);
    j.key("genus").value(c.genus).key("mapGenus").value(c.mapGenus);
    j.key("boundaryLoops").value(U64{c.boundaryLoops}).key("mapBoundaryLoops").value(U64{c.mapBoundaryLoops});
    j.endObject();
  }
  j.endArray();
  j.endObject();
  j.key("stages").beginArray();
  for (const StageFigures& st : context.stages) {
    j.beginObject().key("name").value(st.name).key("seconds").value(st.seconds);
    j.key("peakBytes").value(st.peakBytes).endObject();
  }
  j.endArray();
  j.key("totalSeconds").value(context.totalSeconds).key("peakBytes").value(context.peakBytes);
  j.endObject();
  return j.str();
}

}  // namespace seamvox
