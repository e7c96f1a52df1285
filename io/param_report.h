#pragma once
/// The JSON report of a parameterization (`seamvox param --report`, jobs, bench): one writer for
/// every key, so the command, the library user and the readers see the same figures.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/system/memory.h"

namespace seamvox {

class JsonWriter;
struct FieldSolveStats;
struct PipelineOptions;
struct PipelineResult;

/// What the report says beyond the pipeline's result: the caller's names and settings and the
/// stages it measured (the pipeline's own and the caller's "read" and "write").
struct ParamReportContext {
  std::string input, output;
  std::string solverAsked;  ///< as given: "hat", "vox", "voxloc"
  std::string fieldSource;  ///< "auto", "smooth", "proxy" or the field file
  std::int32_t gridResolution = 0;
  std::uint32_t rings = 0, maxRounds = 0;
  std::uint32_t fieldSmoothing = 0;  ///< steps of the computed field's surface (0 for an imported field)
  bool roughSpots = false;  ///< its rough spots smoothed within h (FieldSource::roughSpots; false when imported)
  std::vector<StageFigures> stages;
  double totalSeconds = 0.0;
  std::uint64_t peakBytes = 0;
  /// The command's memory budget and its estimate of the in-memory peak (0: not written).
  std::uint64_t memoryBudget = 0, estimatedBytes = 0;
  /// Bytes of the field's directions kept on disk while the map was built (0: none).
  std::uint64_t fieldBytesOnDisk = 0;
  /// When set, writes the memory path's keys (out of core: its scratch) instead of the in-memory ones.
  std::function<void(JsonWriter&)> memoryPathJson;
};

/// The context of a run with these options measured by meter (its stages so far): the settings,
/// stages, total time and peak filled in, the names as given.
ParamReportContext paramReportContext(const PipelineOptions& options, const StageMeter& meter,
                                      std::string input, std::string output,
                                      std::string solverAsked, std::string fieldSource);

/// The report as pretty-printed JSON.
std::string paramReportJson(const PipelineResult& result, const ParamReportContext& context);

/// The "fieldSolve" object: the field's factorization figures (param and field reports).
void writeFieldSolve(JsonWriter& j, const FieldSolveStats& stats);

/// Seconds of the named stage in a stage list (0 when absent; summed when repeated).
double stageSeconds(const std::vector<StageFigures>& stages, const std::string& name);

}  // namespace seamvox
