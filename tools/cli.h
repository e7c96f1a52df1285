#pragma once
/// Shared pieces of the `seamvox` command line: argument parsing, command registry, progress.
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/mesh/clean.h"
#include "core/pipeline/grid_spacing.h"
#include "core/quads/checked.h"
#include "core/synth/generate.h"
#include "core/system/progress.h"

namespace seamvox::cli {

/// Wrong usage of a command: printed with the command's usage, exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Arguments of one command: positionals and "--name value" / "--flag" options.
/// Every option a command reads is marked used; finish() rejects the ones nobody read.
class Args {
 public:
  Args(std::vector<std::string> tokens, std::vector<std::string> flagNames);
  const std::vector<std::string>& positionals() const { return positionals_; }
  /// The i-th positional or a UsageError naming `what`.
  const std::string& positional(std::size_t i, const char* what) const;
  bool flag(const std::string& name);
  std::optional<std::string> value(const std::string& name);
  std::string value(const std::string& name, const std::string& fallback);
  double number(const std::string& name, double fallback);
  std::int64_t integer(const std::string& name, std::int64_t fallback);
  /// Validated options: when given, the value must be finite and in [min, max] (a UsageError
  /// says the valid range, e.g. "--threads must be a whole number from 1 to 4096, got '0'");
  /// when absent, fallback is returned as it is.
  double number(const std::string& name, double fallback, double min, double max);
  std::int64_t integer(const std::string& name, std::int64_t fallback, std::int64_t min, std::int64_t max);
  /// A finite number above 0 and at most max.
  double positiveNumber(const std::string& name, double fallback,
                        double max = std::numeric_limits<double>::max());
  /// Throws UsageError for options given but never read and for extra positionals.
  void finish(std::size_t maxPositionals);

 private:
  std::vector<std::string> positionals_;
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> used_;
};

struct Command {
  const char* name;
  const char* summary;  ///< one line for `seamvox --help`
  const char* usage;    ///< full usage text for `seamvox NAME --help`
  /// Names of the options that take no value (everything else "--x" takes one).
  std::vector<std::string> flags;
  int (*run)(Args& args);
};
/// Adds a command to the registry (used by SEAMVOX_COMMAND at static initialization).
bool registerCommand(Command command);
const std::vector<Command>& commands();

/// The grid spacing h of param and field: --edge-length H, or --cells N for H = bounding-box
/// diagonal / N (default GridSpacing::kDefaultCells); validated when parsed (UsageError).
GridSpacing parseGridSpacing(Args& args);
/// --grid N of param and jobs: voxels per axis, a power of two in [4, 1024]
/// (default kDefaultGridResolution).
std::int32_t parseGridResolution(Args& args);
/// --merge-cones F (param, field): cones closer than F * h are merged; default kConeMergeFraction.
double parseMergeCones(Args& args);
/// --field-smoothing N (param, field): smoothing steps of the field's surface, 1..64; default
/// kFieldSmoothingIterations. Refused with an imported field (`imported`), which has no such surface.
std::uint32_t parseFieldSmoothing(Args& args, bool imported);

/// cleanMesh on a mesh read from path: its errors ("the mesh has no valid faces", a NaN) name
/// the file.
CleanResult cleanMeshOf(const std::string& path, TriangleMesh mesh, const CleanOptions& options = {});
/// --noise A, --spikes N, --folds N (gen, subdivide) into ScanNoiseOptions (seed left as is);
/// validated (UsageError). Returns whether any defect was asked for.
bool parseScanNoise(Args& args, ScanNoiseOptions& options);
/// One line on stdout: what addScanNoise did.
void printScanNoise(const ScanNoiseOptions& options, const ScanNoiseResult& result);
/// Help lines of those options, spliced into the commands' usage texts.
#define SEAMVOX_SCAN_NOISE_HELP                                                              \
  "  --noise A   scan noise: every vertex moves up to A mean edge lengths along its normal\n" \
  "              and up to A tangentially (deterministic for a seed)\n"                       \
  "  --noise-tangential F  the tangential part up to F A instead (0 to 1, default 1; 0: along\n" \
  "              the normal only, as a range scanner's depth noise)\n"                        \
  "  --noise-scale mean|local  A in the whole mesh's mean edge length (default) or in each\n"   \
  "              vertex's own (the edges at it: noise at the scale of uneven triangles)\n"    \
  "  --spikes N  N outlier vertices pushed 2-6 edge lengths along their normal\n"            \
  "  --folds N   N small fold-overs (a vertex and its ring slid over their neighbours)\n"

/// --memory-budget SIZE and --scratch DIR (every command that reads or writes meshes).
struct MemoryOptions {
  std::uint64_t budget = 0;  ///< bytes: the option's value or defaultMemoryBudget()
  bool budgetGiven = false;
  std::string scratch;  ///< folder for scratch files: --scratch, else $TMPDIR, else fallback
};
/// Parses both options (a SIZE as parseByteSize reads it; anything else is a UsageError naming
/// the option and the accepted forms). scratchFallback: the folder used without --scratch and
/// TMPDIR (e.g. the output's folder).
MemoryOptions parseMemoryOptions(Args& args, const std::string& scratchFallback = "/tmp");
/// A SIZE option as parseMemoryOptions reads --memory-budget (UsageError when malformed).
std::optional<std::uint64_t> parseSizeOption(Args& args, const std::string& name);
#define SEAMVOX_MEMORY_HELP                                                                       \
  "  --memory-budget SIZE  memory the command may use (2G, 1500M, 800K or bytes; G = 2^30;\n"    \
  "                        default 3/4 of the available memory)\n"                             \
  "  --scratch DIR         folder for scratch files (default $TMPDIR, else /tmp)\n"
/// Lines on stdout: the quad mesh's figures, what extraction could not do, the validation.
void printQuadSummary(const std::string& output, const QuadRun& run);

/// Progress reporting on stderr: a one-line percentage per stage when stderr is a terminal and
/// quiet is false; nothing otherwise.
ProgressFn makeProgress(bool quiet);
/// Writes text to path atomically, or to stdout when path is "-".
void writeTextOutput(const std::string& path, const std::string& text);

/// A path given on the command line and the option or argument that gave it ("-o", "MESH").
struct NamedPath {
  std::string name, path;  ///< an empty path (option not given) and "-" (stdout) are skipped
};
/// Checked before any work: an output naming the same file as an input or another output of the
/// run (same inode, or the same canonical path) is a UsageError naming both.
void checkOutputPaths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);
/// The message of an exception for the user: a std::filesystem error as "PATH: reason" (not the
/// library's "filesystem error: ..." wording), anything else as what().
std::string errorMessage(const std::exception& error);

/// Whether this process runs OpenMP parallel regions inline (tools/openmp_regions.cpp): the
/// thread limit is 1, SEAMVOX_OPENMP_INLINE is not 0, and the command's GOMP_parallel is the one
/// the dynamic linker binds.
bool openmpRegionsRunInline();

/// A UsageError unless path ends in .png (case-insensitive): option names it in the message.
void requirePngPath(const std::string& option, const std::string& path);

}  // namespace seamvox::cli

#define SEAMVOX_COMMAND_CAT2(a, b) a##b
#define SEAMVOX_COMMAND_CAT(a, b) SEAMVOX_COMMAND_CAT2(a, b)
/// Registers a command: SEAMVOX_COMMAND({"info", "summary", "usage", {"json"}, &runInfo});
#define SEAMVOX_COMMAND(...)                                                          \
  static const bool SEAMVOX_COMMAND_CAT(seamvoxCommandRegistered_, __LINE__) =       \
      ::seamvox::cli::registerCommand(::seamvox::cli::Command __VA_ARGS__)
