#include "tools/cli.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>

#include "core/field/cone_merge.h"
#include "core/field/field_proxy.h"
#include "core/solve/param_solver.h"
#include "core/system/errors.h"
#include "core/system/memory_budget.h"
#include "io/atomic_file.h"
#include "io/output_set.h"

namespace seamvox::cli {

Args::Args(std::vector<std::string> tokens, std::vector<std::string> flagNames) {
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const std::string& tok = tokens[i];
    if (tok.size() > 2 && tok.compare(0, 2, "--") == 0) {
      std::string name = tok.substr(2), val;
      const auto eq = name.find('=');
      if (eq != std::string::npos) {
        val = name.substr(eq + 1);
        name = name.substr(0, eq);
      } else if (std::find(flagNames.begin(), flagNames.end(), name) != flagNames.end()) {
        val = "1";
      } else {
        if (i + 1 >= tokens.size()) throw UsageError("option --" + name + " needs a value");
        val = tokens[++i];
      }
      values_[name] = val;
    } else if (tok.size() == 2 && tok[0] == '-' && tok[1] == 'o') {
      if (i + 1 >= tokens.size()) throw UsageError("option -o needs a value");
      values_["output"] = tokens[++i];
    } else {
      positionals_.push_back(tok);
    }
  }
}

const std::string& Args::positional(std::size_t i, const char* what) const {
  if (i >= positionals_.size()) throw UsageError(std::string("missing ") + what);
  return positionals_[i];
}

bool Args::flag(const std::string& name) {
  used_[name] = true;
  auto it = values_.find(name);
  return it != values_.end() && it->second != "0" && it->second != "false";
}

std::optional<std::string> Args::value(const std::string& name) {
  used_[name] = true;
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::value(const std::string& name, const std::string& fallback) {
  return value(name).value_or(fallback);
}

double Args::number(const std::string& name, double fallback) {
  auto v = value(name);
  if (!v) return fallback;
  try {
    std::size_t pos = 0;
    const double x = std::stod(*v, &pos);
    if (pos == v->size()) return x;
  } catch (const std::exception&) {
  }
  throw UsageError("option --" + name + " expects a number, got '" + *v + "'");
}

std::int64_t Args::integer(const std::string& name, std::int64_t fallback) {
  auto v = value(name);
  if (!v) return fallback;
  try {
    std::size_t pos = 0;
    const long long x = std::stoll(*v, &pos);
    if (pos == v->size()) return x;
  } catch (const std::exception&) {
  }
  throw UsageError("option --" + name + " expects an integer, got '" + *v + "'");
}

namespace {

std::string formatNumber(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

}  // namespace

double Args::number(const std::string& name, double fallback, double min, double max) {
  const double x = number(name, fallback);
  if (!value(name) || (std::isfinite(x) && x >= min && x <= max)) return x;
  throw UsageError("--" + name + " must be " +
                   (max >= std::numeric_limits<double>::max() ? "a finite number >= " + formatNumber(min)
                                                             : "a number from " + formatNumber(min) + " to " +
                                                                   formatNumber(max)) +
                   ", got '" + *value(name) + "'");
}

double Args::positiveNumber(const std::string& name, double fallback, double max) {
  const double x = number(name, fallback);
  if (!value(name) || (std::isfinite(x) && x > 0.0 && x <= max)) return x;
  throw UsageError("--" + name + " must be " +
                   (max >= std::numeric_limits<double>::max() ? std::string("a positive finite number")
                                                             : "a number above 0 and at most " + formatNumber(max)) +
                   ", got '" + *value(name) + "'");
}

std::int64_t Args::integer(const std::string& name, std::int64_t fallback, std::int64_t min, std::int64_t max) {
  const std::int64_t x = integer(name, fallback);
  if (!value(name) || (x >= min && x <= max)) return x;
  throw UsageError("--" + name + " must be a whole number from " + std::to_string(min) + " to " +
                   std::to_string(max) + ", got '" + *value(name) + "'");
}

void Args::finish(std::size_t maxPositionals) {
  for (const auto& [name, val] : values_) {
    if (!used_.count(name)) {
      throw UsageError(name == "output" ? "this command takes no -o" : "unknown option --" + name);
    }
  }
  if (positionals_.size() > maxPositionals) {
    throw UsageError("unexpected argument '" + positionals_[maxPositionals] + "'");
  }
}

static std::vector<Command>& registry() {
  static std::vector<Command> all;
  return all;
}

bool registerCommand(Command command) {
  registry().push_back(std::move(command));
  std::sort(registry().begin(), registry().end(),
            [](const Command& a, const Command& b) { return std::string(a.name) < b.name; });
  return true;
}

const std::vector<Command>& commands() { return registry(); }

GridSpacing parseGridSpacing(Args& args) {
  GridSpacing g;
  g.edgeLength = args.positiveNumber("edge-length", 0.0);
  g.cells = args.positiveNumber("cells", 0.0, GridSpacing::kMaxCells);
  try {
    g.validate();  // both given
  } catch (const InputError& e) {
    throw UsageError(std::string("--edge-length/--cells: ") + e.what());
  }
  return g;
}

std::int32_t parseGridResolution(Args& args) {
  const std::int64_t grid = args.integer("grid", kDefaultGridResolution, 4, 1024);
  if ((grid & (grid - 1)) != 0) throw UsageError("--grid must be a power of two between 4 and 1024");
  return static_cast<std::int32_t>(grid);
}

double parseMergeCones(Args& args) {
  return args.number("merge-cones", kConeMergeFraction, 0.0, 10.0);
}

std::uint32_t parseFieldSmoothing(Args& args, bool imported) {
  if (imported && args.value("field-smoothing")) {
    throw UsageError("--field-smoothing has no effect with an imported field (it smooths the surface a computed field is solved on)");
  }
  return static_cast<std::uint32_t>(args.integer("field-smoothing", kFieldSmoothingIterations, 1, 64));
}

CleanResult cleanMeshOf(const std::string& path, TriangleMesh mesh, const CleanOptions& options) {
  try {
    return cleanMesh(std::move(mesh), options);
  } catch (const Error&) {
    rethrowWithContext(path);
  }
}

std::optional<std::uint64_t> parseSizeOption(Args& args, const std::string& name) {
  const auto text = args.value(name);
  if (!text) return std::nullopt;
  const auto bytes = parseByteSize(*text);
  if (!bytes) {
    throw UsageError("--" + name + " must be a size such as 2G, 1500M, 800K or a number of bytes (K, M, G = 2^10, 2^20, 2^30), got '" + *text + "'");
  }
  return bytes;
}

MemoryOptions parseMemoryOptions(Args& args, const std::string& scratchFallback) {
  MemoryOptions options;
  const auto budget = parseSizeOption(args, "memory-budget");
  options.budgetGiven = budget.has_value();
  options.budget = budget.value_or(defaultMemoryBudget());
  const char* tmp = std::getenv("TMPDIR");
  options.scratch = args.value("scratch", tmp && *tmp ? std::string(tmp) : scratchFallback);
  if (options.scratch.empty()) throw UsageError("--scratch needs a folder");
  return options;
}

bool parseScanNoise(Args& args, ScanNoiseOptions& options) {
  options.amplitude = args.number("noise", 0.0);
  if (!(options.amplitude >= 0.0 && options.amplitude <= 10.0)) {
    throw UsageError("--noise must be between 0 and 10 (mean edge lengths)");
  }
  const std::int64_t spikes = args.integer("spikes", 0), folds = args.integer("folds", 0);
  if (spikes < 0 || spikes > (1 << 30) || folds < 0 || folds > (1 << 30)) {
    throw UsageError("--spikes and --folds must be between 0 and 2^30");
  }
  options.spikes = static_cast<std::uint32_t>(spikes);
  options.folds = static_cast<std::uint32_t>(folds);
  options.tangential = args.number("noise-tangential", 1.0, 0.0, 1.0);
  const std::string scale = args.value("noise-scale", "mean");
  if (scale != "mean" && scale != "local") {
    throw UsageError("--noise-scale must be mean (the whole mesh's mean edge length) or local (each vertex's own "
                     "edges), not " + scale);
  }
  options.localScale = scale == "local";
  return options.amplitude > 0.0 || spikes > 0 || folds > 0;
}

void printScanNoise(const ScanNoiseOptions& options, const ScanNoiseResult& result) {
  std::printf("scan noise %.3g %s edge lengths (tangential share %.3g; edge %.4g, largest move %.4g), %u spikes, "
              "%u folds\n",
              options.amplitude, options.localScale ? "local" : "mean", options.tangential, result.meanEdgeLength, result.maxDisplacement, result.spikes,
              result.folds);
}

ProgressFn makeProgress(bool quiet) {
  if (quiet || !isatty(STDERR_FILENO)) return {};
  struct State {
    std::mutex mutex;
    std::string stage;
    int percent = -1;
    std::chrono::steady_clock::time_point last;
  };
  auto state = std::make_shared<State>();
  return [state](const char* stage, double fraction) {
    std::lock_guard<std::mutex> lock(state->mutex);
    const int percent = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 100.0);
    const auto now = std::chrono::steady_clock::now();
    const bool newStage = state->stage != stage;
    if (!newStage && percent == state->percent) return true;
    if (!newStage && percent < 100 && now - state->last < std::chrono::milliseconds(100)) return true;
    state->last = now;
    if (newStage && !state->stage.empty() && state->percent < 100) std::fprintf(stderr, "\n");
    state->stage = stage;
    state->percent = percent;
    std::fprintf(stderr, "\r%-24s %3d%%%s", stage, percent, percent >= 100 ? "\n" : "");
    std::fflush(stderr);
    return true;
  };
}

void writeTextOutput(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text << std::flush;
    return;
  }
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

void checkOutputPaths(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
  auto given = [](const NamedPath& p) { return !p.path.empty() && p.path != "-"; };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (!given(out)) continue;
    for (const NamedPath& in : inputs) {
      if (given(in) && isSameFile(in.path, out.path)) {
        throw UsageError(out.name + " " + out.path + " would overwrite the input " + in.name +
                         (in.path == out.path ? "" : " " + in.path) + "; write to another file");
      }
    }
    for (std::size_t k = 0; k < i; ++k) {
      if (given(outputs[k]) && isSameFile(outputs[k].path, out.path)) {
        throw UsageError(outputs[k].name + " and " + out.name + " name the same file " + out.path +
                         "; give each output its own file");
      }
    }
  }
}

std::string errorMessage(const std::exception& error) {
  const auto* fsError = dynamic_cast<const std::filesystem::filesystem_error*>(&error);
  if (!fsError) return error.what();
  const std::string path = fsError->path1().empty() ? "" : fsError->path1().string() + ": ";
  return path + fsError->code().message();
}

void requirePngPath(const std::string& option, const std::string& path) {
  std::string tail = path.size() >= 4 ? path.substr(path.size() - 4) : path;
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (tail != ".png") throw UsageError(option + " must be a .png file (the picture is PNG): " + path);
}

}  // namespace seamvox::cli
