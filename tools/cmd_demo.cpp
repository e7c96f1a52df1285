// seamvox demo: the main job on a built-in input (a generated scan-like mesh).
#include <stdlib.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "core/system/errors.h"
#include "core/synth/generate.h"
#include "io/interrupt_cleanup.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

/// A working folder: the one given (kept; created when missing, and removed again when the demo
/// fails and leaves it empty), or a fresh temporary one removed at the end.
class WorkFolder {
 public:
  explicit WorkFolder(const std::string& keep) {
    if (!keep.empty()) {
      path_ = keep;
      std::error_code ec;
      created_ = std::filesystem::create_directories(path_, ec);
      if (ec) throw IoError("cannot create folder '" + path_ + "': " + ec.message());
      if (created_) cleanupSlot_ = registerTemporary(path_.c_str());  // a signal removes it if empty
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
    if (temporary_) {
      std::filesystem::remove_all(path_, ec);
    } else if (created_ && !succeeded_) {
      std::filesystem::remove(path_, ec);  // only when empty
    }
    unregisterTemporary(cleanupSlot_);
  }
  const std::string& path() const { return path_; }
  bool isTemporary() const { return temporary_; }
  void markSucceeded() { succeeded_ = true; }

 private:
  std::string path_;
  bool temporary_ = false, created_ = false, succeeded_ = false;
  int cleanupSlot_ = -1;
};

/// The demo's outputs, all or nothing: every step writes into a hidden staging folder inside the
/// work folder (same filesystem), and the files are moved into place together (io/output_set.h)
/// only once every step succeeded. A failed step, an exception or a signal (the staged files and
/// the folder are registered with io/interrupt_cleanup.h) leaves the work folder as it was.
class StagedOutputs {
 public:
  StagedOutputs(const std::string& folder, std::vector<std::string> names) : names_(std::move(names)) {
    for (const std::string& name : names_) files_.push_back(&outputs_.add(folder + "/" + name));
    std::string pattern = folder + "/.seamvox-demo-XXXXXX";
    if (!mkdtemp(pattern.data())) {
      throw IoError(folder + ": cannot create the demo's staging folder: " + std::strerror(errno));
    }
    staging_ = pattern;
    slots_.push_back(registerTemporary(staging_.c_str()));
    for (const std::string& name : names_) slots_.push_back(registerTemporary(staged(name).c_str()));
  }
  ~StagedOutputs() {
    std::error_code ec;
    std::filesystem::remove_all(staging_, ec);
    for (int slot : slots_) unregisterTemporary(slot);
  }
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;

  /// Where the step that makes `name` writes it.
  std::string staged(const std::string& name) const { return staging_ + "/" + name; }
  /// Moves every staged file into place together; throws IoError (nothing moved) on failure.
  void commit() {
    for (std::size_t i = 0; i < names_.size(); ++i) files_[i]->adopt(staged(names_[i]));
    outputs_.commit();
  }

 private:
  std::vector<std::string> names_;
  OutputSet outputs_;
  std::vector<AtomicFile*> files_;
  std::string staging_;
  std::vector<int> slots_;
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
int runMainPipeline(const std::string& meshPath, const StagedOutputs& outputs, bool quiet) {
  SummarizeOptions options;
  options.weld = true;
  options.progress = makeProgress(quiet);
  std::printf("%s\n", formatSummaryText(summarizeMeshFile(meshPath, options)).c_str());
  const std::string map = outputs.staged("scan_uv.ply"), report = outputs.staged("scan_uv.json");
  const std::string picture = outputs.staged("scan_uv.png");
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

  WorkFolder folder(keep);
  StagedOutputs outputs(folder.path(), {"scan.ply", "scan_uv.ply", "scan_uv.json", "scan_uv.png"});
  const std::string meshPath = outputs.staged("scan.ply");
  const auto start = std::chrono::steady_clock::now();
  const GenerateResult generated = generateMesh(options);
  writeMesh(meshPath, generated.mesh);
  std::printf("demo: generated a scan-like mesh with %u faces (%u holes, %u floating islands, "
              "an unwelded seam, %u degenerate and %u duplicate faces) in %.2f s\n",
              generated.mesh.numFaces(), generated.defects.holes,
              generated.defects.openIslands + generated.defects.closedIslands,
              generated.defects.degenerateFaces, generated.defects.duplicateFaces,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  std::printf("demo: the steps write into %s; their files are moved into %s together once every "
              "step succeeded\n\n", meshPath.substr(0, meshPath.rfind('/')).c_str(), folder.path().c_str());
  if (const int rc = runMainPipeline(meshPath, outputs, args.flag("quiet"))) return rc;
  outputs.commit();
  folder.markSucceeded();
  std::printf("\ndemo: wrote scan.ply, scan_uv.ply, scan_uv.json and scan_uv.png in %s%s\n",
              folder.path().c_str(), folder.isTemporary() ? " (temporary; --keep DIR keeps them)" : "");
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"demo", "run the main job on a generated scan-like mesh",
                 "usage: seamvox demo [--faces N] [--seed S] [--keep DIR]\n"
                 "\n"
                 "Generates a scan-like mesh (holes, floating islands, an unwelded seam, bad\n"
                 "faces) and runs the main pipeline on it: today reading, cleaning (with welding)\n"
                 "exactly as a user runs it: `seamvox info --weld`, `seamvox param --weld` (default\n"
                 "solver), `seamvox check` and `seamvox render --seams --cones`. Exit code: that of\n"
                 "the first step that fails (5: the map is not seamless). The outputs are written\n"
                 "all or nothing: when a step fails or the demo is interrupted, DIR keeps what it\n"
                 "held before.\n"
                 "\n"
                 "  --faces N    size of the generated mesh (default 200000)\n"
                 "  --seed S     random seed (default 1)\n"
                 "  --keep DIR   folder for the mesh, map, report and picture (default\n"
                 "               ./seamvox-demo; --keep '' uses a temporary folder, removed after)\n"
                 "  --quiet      no progress on stderr\n",
                 {},
                 &runDemo});

}  // namespace seamvox::cli
