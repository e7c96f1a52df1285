// seamvox info: what a mesh file holds after cleaning (components, genus, boundary loops, fixes).
#include <chrono>
#include <cstdio>

#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "core/system/stopwatch.h"
#include "io/mesh_io.h"
#include "stream/welded_scratch.h"
#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

// Measured peak of the in-memory path: 153 MB for a 2M-face scan, about 54 B per face over the
// program (cleaning's corner table, fans and origins on top of the mesh); rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 64, kBytesPerVertex = 16;
/// Scratch of the weld pass at its peak, per face (the Morton sort's runs and output).
constexpr std::uint64_t kScratchBytesPerFace = 192;

/// The weld pass in a scratch folder, its census as the summary.
MeshSummary summarizeOutOfCore(const std::string& path, MeshStream& stream, const SummarizeOptions& options,
                               const MemoryOptions& memory, MemoryPath& memoryPath, std::uint64_t faces) {
  if (options.weld && options.weldTolerance > 0.0) {
    throw UsageError("--weld-tolerance: out of core only vertices at exactly equal positions are welded; the mesh "
                     "(about " + formatByteSize(memoryPath.estimate) + " in memory) is above the --memory-budget of " +
                     formatByteSize(memory.budget) + ": drop --weld-tolerance or raise --memory-budget");
  }
  ScratchFolder scratch(memory.scratch, faces * kScratchBytesPerFace);
  WeldStreamOptions weld;
  weld.weld = options.weld;
  const std::uint64_t program = currentResidentBytes();
  weld.memoryBytes = memory.budget > program ? memory.budget - program : 0;
  const auto start = std::chrono::steady_clock::now();
  const WeldStreamResult result = weldMeshStream(stream, scratch, weld);
  MeshSummary summary = summarizeCensus(path, result.census, secondsSince(start));
  memoryPath.recordScratch(scratch);
  return summary;
}

int runInfo(Args& args) {
  const std::string path = args.positional(0, "the mesh file (seamvox info MESH)");
  SummarizeOptions options;
  options.weld = args.flag("weld");
  options.weldTolerance = args.number("weld-tolerance", 0.0, 0.0, std::numeric_limits<double>::max());
  if (options.weldTolerance > 0.0 && !options.weld) {
    throw UsageError("--weld-tolerance needs --weld");
  }
  const bool json = args.flag("json");
  const auto report = args.value("report");
  options.progress = makeProgress(args.flag("quiet"));
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(1);
  checkOutputPaths({{"MESH", path}}, {{"--report", report.value_or("")}});

  MemoryPath memoryPath;
  memoryPath.budget = memory.budget;
  refuseDracoInputAboveBudget(path, memory.budget, kProgramBytes, kBytesPerFace + kBytesPerVertex,
                              "convert it to PLY (seamvox convert " + path + " OUT.ply) or raise --memory-budget");
  const auto start = std::chrono::steady_clock::now();
  const std::unique_ptr<MeshStream> stream = openMeshStream(path);
  const MeshCounts counts = guessMeshCounts(path, *stream);
  memoryPath.estimate = kProgramBytes + counts.faces * kBytesPerFace + counts.vertices * kBytesPerVertex;
  memoryPath.outOfCore = memoryPath.estimate > memory.budget;
  MeshSummary summary = memoryPath.outOfCore
                            ? summarizeOutOfCore(path, *stream, options, memory, memoryPath, counts.faces)
                            : summarizeMeshStream(path, *stream, options, start);
  summary.memoryPath = memoryPath;
  if (report) writeTextOutput(*report, formatSummaryJson(summary));
  std::printf("%s", json ? formatSummaryJson(summary).c_str() : formatSummaryText(summary).c_str());
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"info", "read and clean a mesh; print its components, genus and fixes",
                 "usage: seamvox info MESH [--json] [--report FILE] [--weld [--weld-tolerance D]]\n"
                 "\n"
                 "Reads MESH (.ply .obj .off .drc), cleans it as every seamvox stage does and prints\n"
                 "vertices, faces, connected components (the largest with faces, vertices, boundary\n"
                 "loops, Euler characteristic and genus), boundary loops, what cleaning fixed, the\n"
                 "bounding box, read/clean time and peak memory.\n"
                 "\n"
                 "  --json               print a JSON document instead of text\n"
                 "  --report FILE        also write the JSON document to FILE\n"
                 "  --weld               weld coincident vertices before cleaning\n"
                 "  --weld-tolerance D   weld vertices closer than D (mesh units; default 0: equal)\n"
                 "  --quiet              no progress on stderr\n"
                 "\n"
                 "Above the memory budget (the in-memory path needs about 48 MiB + 64 B per face,\n"
                 "counted from the header, or the file size for OBJ) the mesh is streamed once and\n"
                 "measured by external sorts in the scratch folder (about 140 B per face at the peak):\n"
                 "welding of equal positions (no --weld-tolerance), degenerate and duplicate faces,\n"
                 "edges by their faces, components by union-find over the vertices (4 B per vertex in\n"
                 "memory), boundary loops, bounding box, zero-area faces; the same figures as in memory\n"
                 "on meshes without non-manifold vertices or edges and orientation clashes (out of core\n"
                 "nothing is split or reoriented; non-manifold vertices and spikes are not counted).\n"
                 SEAMVOX_MEMORY_HELP,
                 {"json", "weld"},
                 &runInfo});

}  // namespace seamvox::cli
