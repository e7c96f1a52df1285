#pragma once
/// The JSON report of a quad extraction (`seamvox quads --report`): what was found, what could
/// not be traced, and the validation figures.
#include <cstdint>
#include <string>
#include <vector>

#include "core/quads/checked.h"
#include "core/system/memory.h"

namespace seamvox {

struct QuadReportContext {
  std::string input, output;
  std::int64_t scale = 1;
  std::uint32_t mapFaces = 0;
  double seamResidual = 0.0, integerDistance = 0.0;  ///< of the map (measureSeamsFromUV)
  std::uint64_t filledHoles = 0;                     ///< QuadRun::filledHoles
  std::uint64_t translatedHoles = 0;                 ///< QuadRun::translatedHoles
  std::vector<StageFigures> stages;
  double totalSeconds = 0.0;
  std::uint64_t peakBytes = 0;
};

/// The context of `run` (extractCheckedQuads at `scale` on a map of mapFaces faces) measured by
/// meter (its stages so far): the map's seam figures, stages, total time and peak filled in.
QuadReportContext quadReportContext(const QuadRun& run, std::uint32_t mapFaces, std::int64_t scale,
                                    const StageMeter& meter, std::string input, std::string output);

/// The report as pretty-printed JSON.
std::string quadReportJson(const QuadResult& quads, const QuadValidation& check,
                           const QuadReportContext& context);

}  // namespace seamvox
