#include "tools/mesh_report.h"

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>

#include "core/system/errors.h"
#include "io/json.h"
#include "io/mesh_io.h"
#include "core/system/memory.h"
#include "core/system/stopwatch.h"
#include "stream/welded_scratch.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

std::string format(const char* pattern, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* pattern, ...) {
  char buffer[512];
  va_list args;
  va_start(args, pattern);
  std::vsnprintf(buffer, sizeof buffer, pattern, args);
  va_end(args);
  return buffer;
}

unsigned long long ull(std::uint64_t x) { return static_cast<unsigned long long>(x); }

}  // namespace

MeshSummary summarizeMeshFile(const std::string& path, const SummarizeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<MeshStream> stream = openMeshStream(path);
  return summarizeMeshStream(path, *stream, options, start);
}

MeshSummary summarizeMeshStream(const std::string& path, MeshStream& stream, const SummarizeOptions& options,
                                std::chrono::steady_clock::time_point start) {
  MeshSummary summary;
  summary.path = path;
  TriangleMesh mesh = collectMesh(stream);
  if (mesh.triangles.empty()) throw InputError(path + ": the mesh has no faces");
  summary.readSeconds = secondsSince(start);

  start = std::chrono::steady_clock::now();
  CleanOptions cleanOptions;
  cleanOptions.weldVertices = options.weld;
  cleanOptions.weldTolerance = options.weldTolerance;
  cleanOptions.progress = options.progress;
  CleanResult cleaned = cleanMeshOf(path, std::move(mesh), cleanOptions);
  summary.cleanSeconds = secondsSince(start);
  summary.clean = cleaned.report;
  summary.properties = cleaned.mesh.attributes.emptyCopy();
  summary.propertyBytes = cleaned.mesh.attributes.memoryBytes();
  summary.vertices = cleaned.mesh.numVertices();
  summary.faces = cleaned.mesh.numFaces();

  start = std::chrono::steady_clock::now();
  ComponentsResult components = computeComponents(cleaned.topology);
  summary.componentsSeconds = secondsSince(start);
  summary.components = std::move(components.components);
  summary.boundaryLoops = components.boundaryLoops;
  summary.box = computeBoundingBox(cleaned.mesh.positions);
  if (!summary.box.isEmpty()) summary.box.min += cleaned.mesh.origin, summary.box.max += cleaned.mesh.origin;
  summary.peakResidentBytes = peakResidentBytes();
  return summary;
}

MeshSummary summarizeCensus(const std::string& path, const WeldCensus& census, const CleanReport& cleaned,
                            ComponentsResult components, double seconds) {
  MeshSummary s;
  s.path = path;
  s.outOfCore = true;
  s.vertices = cleaned.outputVertices;
  s.faces = cleaned.outputFaces;
  s.clean = cleaned;
  s.properties = census.properties.emptyCopy();
  s.components = std::move(components.components);
  s.boundaryLoops = components.boundaryLoops;
  s.box = census.box;
  if (!s.box.isEmpty()) s.box.min += census.origin, s.box.max += census.origin;
  s.readSeconds = seconds;
  s.edges = census.edges;
  s.boundaryEdges = census.boundaryEdges;
  s.manifoldEdges = census.manifoldEdges;
  s.clashEdges = census.clashEdges;
  s.edgesOfMoreFaces = census.nonManifoldEdges;
  s.stageSeconds = census.stageSeconds;
  s.peakResidentBytes = peakResidentBytes();
  return s;
}

std::string formatSummaryText(const MeshSummary& s, std::size_t largest) {
  const CleanReport& c = s.clean;
  std::string out;
  out += format("mesh            %s\n", s.path.c_str());
  out += format("vertices        %llu (input %llu)\n", ull(s.vertices), ull(c.inputVertices));
  out += format("faces           %llu (input %llu)\n", ull(s.faces), ull(c.inputFaces));
  out += "vertex props    " + (s.properties.empty() ? std::string("none") : s.properties.describe()) + "\n";
  if (!s.properties.empty()) out += format("                %.1f MiB\n", s.propertyBytes / 1048576.0);
  out += format("components      %zu\n", s.components.size());
  const std::size_t shown = std::min(largest, s.components.size());
  if (shown > 0) {
    out += "                    faces   vertices  boundary loops  euler  genus\n";
    for (std::size_t i = 0; i < shown; ++i) {
      const ComponentInfo& k = s.components[i];
      out += format("  #%-12zu %9u  %9u  %14u  %5lld  %5lld\n", i, k.faces, k.vertices,
                    k.boundaryLoops, static_cast<long long>(k.eulerCharacteristic),
                    static_cast<long long>(k.genus));
    }
    if (shown < s.components.size()) {
      out += format("  (%zu smaller components not listed)\n", s.components.size() - shown);
    }
  }
  out += format("boundary loops  %u\n", s.boundaryLoops);
  if (s.outOfCore) {
    out += format("edges           %llu: boundary %llu, two faces %llu, two faces in one direction %llu,\n"
                  "                more than two faces %llu (before cleaning)\n",
                  ull(s.edges), ull(s.boundaryEdges), ull(s.manifoldEdges), ull(s.clashEdges), ull(s.edgesOfMoreFaces));
  }
  out += format("cleaning        welded vertices %llu, degenerate faces %llu, duplicate faces %llu,\n"
                "                zero-area faces %llu (kept), unreferenced vertices %llu,\n"
                "                non-manifold edges %llu (split), non-manifold vertices %llu (split),\n"
                "                flipped faces %llu, spike vertices %llu (kept),\n"
                "                boundary vertices on another one %llu (kept: an unwelded crack%s)%s\n",
                ull(c.weldedVertices), ull(c.degenerateFaces), ull(c.duplicateFaces),
                ull(c.zeroAreaFaces), ull(c.unreferencedVertices), ull(c.nonManifoldEdges),
                ull(c.nonManifoldVertices), ull(c.flippedFaces), ull(c.spikeVertices),
                ull(c.unweldedBoundaryVertices), c.unweldedBoundaryVertices ? "; --weld joins it" : "",
                c.reordered ? ";\n                vertices and faces put in spatial order (the input's was scattered)"
                : c.verticesRenumbered ? ";\n                vertices renumbered in the order the faces use them (their ids were scattered)"
                                       : "");
  if (!s.box.isEmpty()) {
    out += format("bounding box    (%.10g, %.10g, %.10g) - (%.10g, %.10g, %.10g), diagonal %g\n", s.box.min.x(),
                  s.box.min.y(), s.box.min.z(), s.box.max.x(), s.box.max.y(), s.box.max.z(),
                  s.box.diagonal());
  }
  if (s.outOfCore) {
    out += format("time            %.3f s:", s.readSeconds);
    for (const auto& [stage, seconds] : s.stageSeconds) out += format(" %s %.2f", stage.c_str(), seconds);
    out += "\n";
  } else {
    out += format("time            read %.3f s, clean %.3f s, components %.3f s\n", s.readSeconds,
                  s.cleanSeconds, s.componentsSeconds);
  }
  out += format("peak memory     %.1f MiB\n", s.peakResidentBytes / 1048576.0);
  if (s.memoryPath.budget > 0) out += describeMemoryPath(s.memoryPath) + "\n";
  return out;
}

std::string formatSummaryJson(const MeshSummary& s, std::size_t largest) {
  const CleanReport& c = s.clean;
  JsonWriter j;
  j.beginObject();
  j.key("file").value(s.path);
  j.key("vertices").value(s.vertices);
  j.key("faces").value(s.faces);
  j.key("input").beginObject();
  j.key("vertices").value(c.inputVertices);
  j.key("faces").value(c.inputFaces);
  j.endObject();
  j.key("vertexProperties").beginArray();
  for (const VertexProperty& p : s.properties.properties) {
    j.beginObject().key("name").value(p.name).key("type").value(std::string(scalarTypeName(p.type))).endObject();
  }
  j.endArray();
  j.key("vertexPropertyBytes").value(s.propertyBytes);
  j.key("components").beginObject();
  j.key("count").value(static_cast<std::uint64_t>(s.components.size()));
  j.key("largest").beginArray();
  for (std::size_t i = 0; i < std::min(largest, s.components.size()); ++i) {
    const ComponentInfo& k = s.components[i];
    j.beginObject();
    j.key("faces").value(k.faces);
    j.key("vertices").value(k.vertices);
    j.key("edges").value(k.edges);
    j.key("boundaryLoops").value(k.boundaryLoops);
    j.key("eulerCharacteristic").value(k.eulerCharacteristic);
    j.key("genus").value(k.genus);
    j.endObject();
  }
  j.endArray();
  j.endObject();
  j.key("boundaryLoops").value(s.boundaryLoops);
  j.key("clean").beginObject();
  j.key("weldedVertices").value(c.weldedVertices);
  j.key("degenerateFaces").value(c.degenerateFaces);
  j.key("duplicateFaces").value(c.duplicateFaces);
  j.key("zeroAreaFaces").value(c.zeroAreaFaces);
  j.key("unreferencedVertices").value(c.unreferencedVertices);
  j.key("nonManifoldEdges").value(c.nonManifoldEdges);
  j.key("nonManifoldVertices").value(c.nonManifoldVertices);
  j.key("flippedFaces").value(c.flippedFaces);
  j.key("spikeVertices").value(c.spikeVertices);
  j.key("unweldedBoundaryVertices").value(c.unweldedBoundaryVertices);
  j.key("reorderedForLocality").value(c.reordered);
  j.key("verticesRenumberedForLocality").value(c.verticesRenumbered);
  j.endObject();
  if (s.outOfCore) {
    j.key("edges").beginObject();
    j.key("count").value(s.edges).key("boundary").value(s.boundaryEdges).key("twoFaces").value(s.manifoldEdges);
    j.key("orientationClashes").value(s.clashEdges).key("moreThanTwoFaces").value(s.edgesOfMoreFaces);
    j.endObject();
  }
  j.key("boundingBox").beginObject();
  j.key("min").beginArray().value(s.box.min.x()).value(s.box.min.y()).value(s.box.min.z()).endArray();
  j.key("max").beginArray().value(s.box.max.x()).value(s.box.max.y()).value(s.box.max.z()).endArray();
  j.key("diagonal").value(s.box.diagonal());
  j.endObject();
  j.key("timings").beginObject();
  if (s.outOfCore) {
    j.key("passSeconds").beginObject();
    for (const auto& [stage, seconds] : s.stageSeconds) j.key(stage).value(seconds);
    j.endObject();
  }
  j.key("readSeconds").value(s.readSeconds);
  j.key("cleanSeconds").value(s.cleanSeconds);
  j.key("componentsSeconds").value(s.componentsSeconds);
  j.endObject();
  if (s.memoryPath.budget > 0) {
    writeMemoryPathJson(j, s.memoryPath);
  } else {
    j.key("peakResidentBytes").value(s.peakResidentBytes);
  }
  j.endObject();
  return j.str() + "\n";
}

}  // namespace seamvox::cli
