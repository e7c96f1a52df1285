// seamvox demo: the main job on a built-in input (a generated scan-like mesh).
#include <stdlib.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "core/system/errors.h"
#include "core/synth/generate.h"
#include "io/mesh_io.h"
#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

/// A working folder: the one given (kept), or a fresh temporary one removed at the end.
class WorkFolder {
 public:
  explicit WorkFolder(const std::string& keep) {
    if (!keep.empty()) {
      path_ = keep;
      std::error_code ec;
      std::filesystem::create_directories(path_, ec);
      if (ec) throw IoError("cannot create folder '" + path_ + "': " + ec.message());
      return;
    }
    std::string pattern = (std::filesystem::temp_directory_path() / "seamvox-demo-XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw IoError("cannot create a temporary folder in " +
                                                std::filesystem::temp_directory_path().string());
    path_ = pattern;
    temporary_ = true;
  }
  ~WorkFolder() {
    std::error_code ec;
    if (temporary_) std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  bool isTemporary() const { return temporary_; }

 private:
  std::string path_;
  bool temporary_ = false;
};

/// Runs a registered subcommand in-process with the given arguments (as the command line would).
int runSubcommand(const std::string& name, const std::vector<std::string>& tokens) {
  for (const Command& c : commands()) {
    if (name != c.name) continue;
    std::vector<std::string> flags = c.flags;
    flags.push_back("quiet");
    Args args(tokens, flags);
    return c.run(args);
  }
  throw std::logic_error("demo: no command " + name);
}

/// The main job on one mesh file, exactly as a user runs it: mesh report (welding the scan's
/// seam), parameterization with the default solver, quality check and a checkerboard picture.
/// Returns the exit code of the first step that fails (check: 5 when the map is not seamless).
int runMainPipeline(const std::string& meshPath, const WorkFolder& folder, bool quiet) {
  SummarizeOptions options;
  options.weld = true;
  options.progress = makeProgress(quiet);
  std::printf("%s\n", formatSummaryText(summarizeMeshFile(meshPath, options)).c_str());
  const std::string map = folder.file("scan_uv.ply"), report = folder.file("scan_uv.json");
  const std::string picture = folder.file("scan_uv.png");
  std::vector<std::string> q;
  if (quiet) q.push_back("--quiet");
  auto with = [&](std::vector<std::string> tokens) {
    tokens.insert(tokens.end(), q.begin(), q.end());
    return tokens;
  };
  std::printf("== seamvox param %s -o %s --weld --report %s\n", meshPath.c_str(), map.c_str(), report.c_str());
  if (int rc = runSubcommand("param", with({meshPath, "-o", map, "--weld", "--report", report}))) return rc;
  std::printf("\n== seamvox check %s\n", map.c_str());
  if (int rc = runSubcommand("check", {map})) return rc;
  std::printf("\n== seamvox render %s -o %s --seams --cones --weld\n", map.c_str(), picture.c_str());
  return runSubcommand("render", with({map, "-o", picture, "--seams", "--cones", "--weld", "--checker", "1"}));
}

int runDemo(Args& args) {
  GenerateOptions options;
  options.kind = MeshKind::Scan;
  const std::int64_t faces = args.integer("faces", 200000);
  if (faces < static_cast<std::int64_t>(minimumFaces(options.kind)) || faces >= (1ll << 31)) {
    throw UsageError("--faces must be between " + std::to_string(minimumFaces(options.kind)) +
                     " and 2^31");
  }
  options.faces = static_cast<std::uint64_t>(faces);
  const std::int64_t seed = args.integer("seed", 1);
  if (seed < 0) throw UsageError("--seed must be >= 0");
  options.seed = static_cast<std::uint64_t>(seed);
  const auto keep = args.value("keep", "seamvox-demo");
  const ProgressFn progress = makeProgress(args.flag("quiet"));
  options.progress = progress;
  args.finish(0);

  const WorkFolder folder(keep);
  const std::string meshPath = folder.file("scan.ply");
  const auto start = std::chrono::steady_clock::now();
  const GenerateResult generated = generateMesh(options);
  writeMesh(meshPath, generated.mesh);
  std::printf("demo: generated a scan-like mesh with %u faces (%u holes, %u floating islands, "
              "an unwelded seam, %u degenerate and %u duplicate faces) in %.2f s\n",
              generated.mesh.numFaces(), generated.defects.holes,
              generated.defects.openIslands + generated.defects.closedIslands,
              generated.defects.degenerateFaces, generated.defects.duplicateFaces,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  std::printf("demo: input %s%s\n\n", meshPath.c_str(),
              folder.isTemporary() ? " (temporary; --keep DIR keeps it)" : "");
  return runMainPipeline(meshPath, folder, args.flag("quiet"));
}

}  // namespace

SEAMVOX_COMMAND({"demo", "run the main job on a generated scan-like mesh",
                 "usage: seamvox demo [--faces N] [--seed S] [--keep DIR]\n"
                 "\n"
                 "Generates a scan-like mesh (holes, floating islands, an unwelded seam, bad\n"
                 "faces) and runs the main pipeline on it: today reading, cleaning (with welding)\n"
                 "exactly as a user runs it: `seamvox info --weld`, `seamvox param --weld` (default\n"
                 "solver), `seamvox check` and `seamvox render --seams --cones`. Exit code: that of\n"
                 "the first step that fails (5: the map is not seamless).\n"
                 "\n"
                 "  --faces N    size of the generated mesh (default 200000)\n"
                 "  --seed S     random seed (default 1)\n"
                 "  --keep DIR   folder for the mesh, map, report and picture (default\n"
                 "               ./seamvox-demo; --keep '' uses a temporary folder, removed after)\n"
                 "  --quiet      no progress on stderr\n",
                 {},
                 &runDemo});

}  // namespace seamvox::cli
