// seamvox demo: the main job on a built-in input (a generated scan-like mesh).
#include <stdlib.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "core/errors.h"
#include "core/generate.h"
#include "io/mesh_io.h"
#include "tools/cli.h"
#include "tools/mesh_report.h"

namespace seamvox::cli {
namespace {

/// A working folder: the one given (kept), or a fresh temporary one removed at the end.
class WorkFolder {
 public:
  explicit WorkFolder(const std::optional<std::string>& keep) {
    if (keep) {
      path_ = *keep;
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

/// The main pipeline run on one mesh file. Today: read, clean (welding the scan's seam) and
/// report; later stages (field, cut, parameterization) plug in here.
void runMainPipeline(const std::string& meshPath, const ProgressFn& progress) {
  SummarizeOptions options;
  options.weld = true;
  options.progress = progress;
  std::printf("%s", formatSummaryText(summarizeMeshFile(meshPath, options)).c_str());
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
  const auto keep = args.value("keep");
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
  runMainPipeline(meshPath, progress);
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"demo", "run the main job on a generated scan-like mesh",
                 "usage: seamvox demo [--faces N] [--seed S] [--keep DIR]\n"
                 "\n"
                 "Generates a scan-like mesh (holes, floating islands, an unwelded seam, bad\n"
                 "faces) and runs the main pipeline on it: today reading, cleaning (with welding)\n"
                 "and the mesh report of `seamvox info --weld`.\n"
                 "\n"
                 "  --faces N    size of the generated mesh (default 200000)\n"
                 "  --seed S     random seed (default 1)\n"
                 "  --keep DIR   write the generated files to DIR and keep them (default: a\n"
                 "               temporary folder, removed afterwards)\n"
                 "  --quiet      no progress on stderr\n",
                 {},
                 &runDemo});

}  // namespace seamvox::cli
