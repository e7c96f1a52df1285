// seamvox jobs: runs a manifest of parameterization jobs (resumable, memory-budgeted, tiles,
// optionally over MPI ranks); also the weld and split steps of tiled jobs.
#include <glob.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "io/output_set.h"
#include "core/batch/jobs.h"
#include "core/system/memory_budget.h"
#include "tools/cli.h"
#include "tools/jobs.h"

namespace seamvox::cli {
namespace {
namespace fs = std::filesystem;

/// Exit code when at least one job failed.
constexpr int kJobsFailed = 6;

std::vector<std::string> expandPattern(const std::string& pattern) {
  if (pattern.find_first_of("*?[") == std::string::npos) return {pattern};
  glob_t matches{};
  std::vector<std::string> files;
  if (glob(pattern.c_str(), 0, nullptr, &matches) == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) files.emplace_back(matches.gl_pathv[i]);
  }
  globfree(&matches);
  return files;  // glob sorts
}

std::string selfExecutable() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) throw IoError("cannot find the seamvox binary (/proc/self/exe): " + error.message());
  return self.string();
}

/// Creates a folder and its parents; IoError naming it (read-only place, a file in the way, a
/// name too long) otherwise.
void createFolder(const std::string& folder, const char* what) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw IoError(folder + ": cannot create the " + what + ": " + error.message());
}

/// The tiles with their positions about one origin (given, or the first tile's): positions equal
/// in the files stay equal.
std::vector<TriangleMesh> readTiles(const std::vector<std::string>& paths, std::optional<Vec3d> origin = {}) {
  std::vector<TriangleMesh> tiles;
  ReadOptions options;
  options.origin = origin;
  for (const std::string& path : paths) {
    tiles.push_back(readMesh(path, options));
    options.origin = tiles.front().origin;
  }
  return tiles;
}

int weldTileFiles(const std::string& output, const std::vector<std::string>& paths) {
  if (paths.empty()) throw UsageError("--weld-tiles OUT needs the tile files");
  const WeldedTiles welded = weldTiles(readTiles(paths));
  writeMesh(output, welded.mesh);
  std::printf("%zu tiles -> %s: %u faces, %u vertices, %llu border vertices welded\n", paths.size(),
              output.c_str(), welded.mesh.numFaces(), welded.mesh.numVertices(),
              static_cast<unsigned long long>(welded.weldedVertices));
  return 0;
}

int splitTileFiles(const std::string& mapped, const std::string& folder, const std::string& format,
                   const std::vector<std::string>& paths) {
  if (paths.empty()) throw UsageError("--split-tiles MESH needs the tile files");
  ReadOptions readOptions;
  readOptions.readUV = true;
  const TriangleMesh mesh = readMesh(mapped, readOptions);
  if (!mesh.hasUV()) throw InputError(mapped + ": the parameterized mesh has no texture coordinates");
  SplitTiles split = splitTiles(mesh, readTiles(paths, mesh.origin));
  createFolder(folder, "tiles output folder");
  OutputSet outputs;  // every tile or none
  for (std::size_t t = 0; t < paths.size(); ++t) {
    AtomicFile& out = outputs.add(folder + "/" + fs::path(paths[t]).stem().string() + "." + format);
    writeMesh(out, split.tiles[t]);
    out.close();  // one open file at a time, whatever the number of tiles
  }
  outputs.commit();
  for (std::size_t t = 0; t < paths.size(); ++t) {
    std::printf("%s/%s.%s: %u faces\n", folder.c_str(), fs::path(paths[t]).stem().c_str(), format.c_str(),
                split.tiles[t].numFaces());
  }
  if (split.missingFaces) {
    std::printf("%llu tile faces dropped by cleaning (degenerate or duplicate)\n",
                static_cast<unsigned long long>(split.missingFaces));
  }
  return 0;
}

int runJobs(Args& args) {
  const auto weld = args.value("weld-tiles");
  const auto split = args.value("split-tiles");
  if (weld || split) {
    const std::string folder = args.value("tiles-output", "");
    const std::string format = args.value("format", "drc");
    args.finish(SIZE_MAX);
    if (weld) return weldTileFiles(*weld, args.positionals());
    if (folder.empty()) throw UsageError("--split-tiles needs --tiles-output DIR");
    return splitTileFiles(*split, folder, format, args.positionals());
  }

  const std::string manifestPath = args.positional(0, "the manifest (seamvox jobs MANIFEST)");
  const std::int64_t workers = args.integer("workers", 1);
  if (workers < 1 || workers > 256) throw UsageError("--workers must be between 1 and 256");
  // The budget rule of every command (2G, 1500M, bytes; default defaultMemoryBudget()), but a
  // plain number here still counts GB as it always did.
  std::optional<std::uint64_t> budgetGiven;
  if (const auto text = args.value("memory-budget"); text && !text->empty() && std::isdigit(static_cast<unsigned char>(text->back()))) {
    const double gb = args.number("memory-budget", 0.0);
    if (!(gb > 0.0 && std::isfinite(gb))) throw UsageError("--memory-budget must be a positive number of GB or a size such as 1500M");
    budgetGiven = static_cast<std::uint64_t>(gb * 1073741824.0);
  } else {
    budgetGiven = parseSizeOption(args, "memory-budget");
  }
  const bool force = args.flag("force");
  const bool mpi = args.flag("mpi") || isStartedByMpirun();
  const auto summaryPath = args.value("summary");
  RunnerOptions options;
  options.quiet = args.flag("quiet");
  const std::int64_t threads = args.integer("threads", 0);
  args.finish(1);

  if (fs::is_directory(manifestPath)) {
    throw UsageError(manifestPath + " is a folder; give the manifest file (seamvox jobs MANIFEST)");
  }
  checkOutputPaths({{"MANIFEST", manifestPath}}, {{"--summary", summaryPath.value_or("")}});
  std::ifstream in(manifestPath, std::ios::binary);
  if (!in) throw IoError(manifestPath + ": cannot open the manifest");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string baseDir = fs::absolute(manifestPath).parent_path().string();
  const Manifest manifest = parseManifest(text.str(), manifestPath, baseDir, expandPattern);
  const std::uint64_t budget = budgetGiven.value_or(defaultMemoryBudget());
  options.executable = selfExecutable();
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  options.threadsPerJob = threads > 0 ? static_cast<std::uint32_t>(threads)
                                      : std::max<std::uint32_t>(1, cores / static_cast<unsigned>(mpi ? 1 : workers));
  createFolder(manifest.outputDir, "output folder");
  // Staged before any job runs, so a summary that cannot be written fails at once.
  const std::string summaryTarget = summaryPath.value_or(manifest.outputDir + "/summary.csv");
  OutputSet summaryOutput;
  AtomicFile* summary = summaryTarget == "-" ? nullptr : &summaryOutput.add(summaryTarget);

  std::vector<JobOutcome> outcomes;
  if (mpi) {
    bool isRoot = true;
    outcomes = runJobsWithMpi(manifest.jobs, manifest.outputDir, force, budget, options, isRoot);
    if (!isRoot) return 0;
  } else {
    std::vector<PreparedJob> toRun;
    std::vector<std::size_t> runIndex;
    outcomes.resize(manifest.jobs.size());
    for (std::size_t i = 0; i < manifest.jobs.size(); ++i) {
      PreparedJob job = prepareJob(manifest.jobs[i], manifest.outputDir);
      if (job.upToDate && !force) {
        outcomes[i] = skippedOutcome(job);
      } else {
        toRun.push_back(std::move(job));
        runIndex.push_back(i);
      }
    }
    const std::vector<JobOutcome> ran =
        runJobsLocally(toRun, static_cast<std::uint32_t>(workers), budget, options);
    for (std::size_t k = 0; k < ran.size(); ++k) outcomes[runIndex[k]] = ran[k];
  }
  std::printf("%s", formatSummaryText(outcomes).c_str());
  if (summary) {
    summary->write(formatSummaryCsv(outcomes));
    summaryOutput.commit();
  } else {
    writeTextOutput("-", formatSummaryCsv(outcomes));
  }
  for (const JobOutcome& o : outcomes) {
    if (o.status == JobStatus::Failed) return kJobsFailed;
  }
  return 0;
}

}  // namespace

SEAMVOX_COMMAND({"jobs", "run a manifest of parameterization jobs (resumable, budgeted, MPI)",
                 "usage: seamvox jobs MANIFEST [--workers N] [--memory-budget SIZE] [--force]\n"
                 "                    [--summary FILE.csv] [--mpi]\n"
                 "       mpirun -np K seamvox jobs MANIFEST ...\n"
                 "\n"
                 "Runs `seamvox param` on every job of MANIFEST, each in its own process, and writes\n"
                 "its output and a JSON report (inputs, options, quality, time, peak memory, and the\n"
                 "param report) atomically; then prints a summary and writes it as CSV. A rerun skips\n"
                 "jobs whose report and outputs exist and whose inputs (size and content hash),\n"
                 "options and format are unchanged. A failing job is recorded with its error and the\n"
                 "others go on. Exit code 0 when every job succeeded, 6 when some failed.\n"
                 "\n"
                 "Manifest (text; '#' starts a comment; relative paths are relative to MANIFEST):\n"
                 "  output DIR                   output folder (default: out next to MANIFEST)\n"
                 "  format drc|obj|ply           output format of the jobs below (default drc)\n"
                 "  param OPTIONS...             default param options of the jobs below\n"
                 "  mesh PATH|GLOB... [: OPTIONS...]        one job per file\n"
                 "  tiles NAME PATH|GLOB... [: OPTIONS...]  one job: tiles of one surface, welded at\n"
                 "                               coincident border vertices, parameterized as one\n"
                 "                               mesh and written back as DIR/NAME/<tile>.<format>\n"
                 "Example:\n"
                 "  output results\n"
                 "  param --solver hat --cells 80\n"
                 "  mesh scans/*.ply\n"
                 "  tiles site site/tile_*.ply : --cells 200\n"
                 "\n"
                 "  --workers N          jobs at once on this machine (default 1)\n"
                 "  --memory-budget SIZE start a job only while the memory the running jobs hold\n"
                 "                       fits (2G, 1500M, 800K; a plain number is GB, as before;\n"
                 "                       default 3/4 of the available memory). A job holds its\n"
                 "                       estimated peak, which param gets as its --memory-budget;\n"
                 "                       a job above the whole budget holds all of it and param\n"
                 "                       runs out of core; one whose grid's system does not fit\n"
                 "                       fails without running\n"
                 "  --force              redo up-to-date jobs\n"
                 "  --summary FILE       CSV summary (default DIR/summary.csv)\n"
                 "  --mpi                distribute over MPI ranks (implied under mpirun): rank 0\n"
                 "                       hands out jobs as ranks become free and gathers the summary;\n"
                 "                       the output folder must be shared by all ranks\n"
                 "  --threads T          threads per job (default: cores / workers)\n"
                 "\n"
                 "Steps of tiled jobs (run by the runner itself):\n"
                 "  seamvox jobs --weld-tiles MERGED TILE...\n"
                 "  seamvox jobs --split-tiles MAPPED --tiles-output DIR [--format EXT] TILE...\n",
                 {"force", "mpi"},
                 &runJobs});

}  // namespace seamvox::cli
