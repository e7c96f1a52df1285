// seamvox info: what a mesh file holds after cleaning (components, genus, boundary loops, fixes).
#include <cstdio>

#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

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
  parseMemoryOptions(args);  // validated; this command runs in memory (out of core: issue 17)
  args.finish(1);
  checkOutputPaths({{"MESH", path}}, {{"--report", report.value_or("")}});

  const MeshSummary summary = summarizeMeshFile(path, options);
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
                 SEAMVOX_MEMORY_HELP,
                 {"json", "weld"},
                 &runInfo});

}  // namespace seamvox::cli
