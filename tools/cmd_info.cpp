// seamvox info: what a mesh file holds after cleaning (components, genus, boundary loops, fixes).
#include <chrono>
#include <cstdio>

#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "core/system/stopwatch.h"
#include "io/mesh_io.h"
#include "stream/clean_stream.h"
#include "stream/welded_scratch.h"
#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

// Measured peak of the in-memory path: 153 MB for a 2M-face scan, about 54 B per face over the
// program (cleaning's corner table, fans and origins on top of the mesh); rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 64, kBytesPerVertex = 16;
/// Scratch at its peak, per face (measured: 192 B per face on a 20M-face scan, the cleaning's
/// measuring sorts next to the weld pass's output).
constexpr std::uint64_t kScratchBytesPerFace = 200;

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
  // The cleaning as in memory (splits, orientation, spikes), then the cleaned components.
  const auto cleanStart = std::chrono::steady_clock::now();
  CleanStreamOptions clean;
  clean.memoryBytes = weld.memoryBytes;
  const CleanScratch cleaned = cleanWeldedMesh(scratch, result.scratch, result.census, clean);
  const double cleanSeconds = secondsSince(cleanStart);
  const auto componentsStart = std::chrono::steady_clock::now();
  ComponentsResult components = cleanedComponents(scratch, cleaned, weld.memoryBytes);
  const double componentsSeconds = secondsSince(componentsStart);
  MeshSummary summary = summarizeCensus(path, result.census, cleaned.report, std::move(components), secondsSince(start));
  summary.stageSeconds.emplace_back("clean", cleanSeconds);
  for (const auto& [pass, seconds] : cleaned.stageSeconds) summary.stageSeconds.emplace_back("clean: " + pass, seconds);
  summary.stageSeconds.emplace_back("cleaned components", componentsSeconds);
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
                 "Reads MESH (.ply .obj .off .drc .stl), cleans it as every seamvox stage does and prints\n"
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
                 "cleaned by external sorts in the scratch folder (about 200 B per face at the peak):\n"
                 "welding of equal positions (no --weld-tolerance), degenerate and duplicate faces,\n"
                 "orientation, edges of more than two faces paired and non-manifold vertices split as\n"
                 "in memory, spikes, then the components (union-finds of 4 B per face or vertex,\n"
                 "held in memory within shares of the budget and on disk beyond them): the same\n"
                 "figures as in memory, and the input's edges by their faces.\n"
                 SEAMVOX_MEMORY_HELP,
                 {"json", "weld"},
                 &runInfo});

}  // namespace seamvox::cli
