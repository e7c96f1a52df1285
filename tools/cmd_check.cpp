// seamvox check: is a parameterized mesh seamless? Seams are reconstructed from the UVs alone.
#include <cmath>
#include <cstdio>

#include "core/quality/check.h"
#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "io/check_report.h"
#include "io/json.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "stream/map_check.h"
#include "tools/cli.h"
#include "tools/memory_path.h"

namespace seamvox::cli {
namespace {

/// Exit code when the map is readable but not seamless.
constexpr int kNotSeamless = 5;

// Measured peak of the in-memory check: 43 MB for the program, 81 B per face of a 1M-face map
// (124 MB); rounded up.
constexpr std::uint64_t kProgramBytes = std::uint64_t(48) << 20, kBytesPerFace = 96, kBytesPerVertex = 16;

/// What a check measured and how.
struct CheckFigures {
  CheckResult result;  ///< the verdict and figures, whichever path measured them
  bool outOfCore = false;
  std::uint64_t budget = 0, estimate = 0;
  MapCheckResult scratch;  ///< traffic and peak of the out-of-core path
};

std::uint64_t estimateInMemoryBytes(const std::string& path, const MeshStream& stream) {
  const MeshCounts counts = guessMeshCounts(path, stream);
  return kProgramBytes + counts.faces * kBytesPerFace + counts.vertices * kBytesPerVertex;
}

CheckResult checkInMemory(const std::string& path, MeshStream& stream, const std::optional<std::string>& fieldPath,
                          double edgeLength, double tolerance) {
  TriangleMesh raw = collectMesh(stream);
  if (raw.triangles.empty()) throw InputError(path + ": the mesh has no faces");
  if (!raw.hasUV()) throw InputError(path + ": the mesh has no per-corner texture coordinates");
  CheckOptions options;
  options.edgeLength = edgeLength;
  options.tolerance = tolerance;
  if (fieldPath) options.fieldPerInputFace = readFieldVectors(*fieldPath, raw.numFaces());
  try {
    return checkParameterization(std::move(raw), options);
  } catch (...) {
    rethrowWithContext(path);
  }
}

std::string formatTraffic(const MapCheckResult& r) {
  std::string out;
  for (const auto& [stage, seconds] : r.stageSeconds) {
    char text[64];
    std::snprintf(text, sizeof text, "%s%s %.1f s", out.empty() ? "" : ", ", stage.c_str(), seconds);
    out += text;
  }
  out += "; scratch: ";
  const std::size_t scratchStart = out.size();
  for (const ScratchTraffic& t : r.traffic) {
    out += (out.size() == scratchStart ? "" : ", ") + t.stage + " " + formatByteSize(t.bytesWritten) + " written / " +
           formatByteSize(t.bytesRead) + " read";
  }
  return out;
}

void printJson(const std::string& path, const CheckFigures& c) {
  const std::string json = checkReportJson(path, c.result, [&](JsonWriter& j) {
    j.key("path").value(std::string(c.outOfCore ? "out-of-core" : "in-memory"));
    j.key("memoryBudget").value(c.budget).key("estimatedBytes").value(c.estimate);
    if (c.outOfCore) {
      j.key("scratch").beginObject();
      j.key("peakBytes").value(c.scratch.scratchPeakBytes);
      j.key("positionsInMemory").value(c.scratch.positionsInMemory);
      j.key("seconds").beginObject();
      for (const auto& [stage, seconds] : c.scratch.stageSeconds) j.key(stage).value(seconds);
      j.endObject();
      j.key("stages").beginArray();
      for (const ScratchTraffic& t : c.scratch.traffic) {
        j.beginObject().key("stage").value(t.stage).key("bytesWritten").value(t.bytesWritten);
        j.key("bytesRead").value(t.bytesRead).endObject();
      }
      j.endArray().endObject();
    }
    j.key("peakResidentBytes").value(peakResidentBytes());
  });
  std::printf("%s\n", json.c_str());
}

void printText(const std::string& path, const CheckFigures& c) {
  const SeamQuality& seams = c.result.seams;
  const MapQuality& map = c.result.map;
  const double tolerance = c.result.tolerance;
  std::printf("%s: %llu faces, %llu seam edges (length %.6g)\n", path.c_str(),
              static_cast<unsigned long long>(c.result.faces), static_cast<unsigned long long>(seams.seamEdges),
              seams.seamLength);
  std::printf("seam residual %.3g, integer distance %.3g (tolerance %.3g)\n", seams.maxResidual,
              seams.maxIntegerDistance, tolerance);
  std::printf("flipped %llu (%.4f%%), collapsed %llu, stretched %llu, h %.6g\n",
              static_cast<unsigned long long>(map.flipped), 100.0 * map.flippedFraction,
              static_cast<unsigned long long>(map.collapsed), static_cast<unsigned long long>(map.stretched),
              map.edgeLength);
  if (map.woundCounted) {
    std::printf("wound %llu (interior vertices the map winds around twice or more)\n",
                static_cast<unsigned long long>(map.wound));
  }
  if (c.result.hasField) std::printf("relative gradient error %.6f\n", map.relativeGradientError);
  if (c.outOfCore) {
    std::printf("path out of core: estimate %s above the budget %s; positions %s; scratch peak %s; %s; peak memory %s\n",
                formatByteSize(c.estimate).c_str(), formatByteSize(c.budget).c_str(),
                c.scratch.positionsInMemory ? "in memory" : "joined by external sorts",
                formatByteSize(c.scratch.scratchPeakBytes).c_str(), formatTraffic(c.scratch).c_str(),
                formatByteSize(peakResidentBytes()).c_str());
  } else {
    std::printf("path in memory: estimate %s within the budget %s; peak memory %s\n",
                formatByteSize(c.estimate).c_str(), formatByteSize(c.budget).c_str(),
                formatByteSize(peakResidentBytes()).c_str());
  }
  std::printf("%s\n", c.result.isSeamless ? "seamless" : "NOT seamless");
}

int runCheck(Args& args) {
  const std::string path = args.positional(0, "the parameterized mesh (seamvox check MESH)");
  const auto fieldPath = args.value("field");
  const double edgeLength = args.positiveNumber("edge-length", 0.0);
  const double tolerance = args.number("tolerance", 1e-6, 0.0, std::numeric_limits<double>::max());
  const bool json = args.flag("json");
  const MemoryOptions memory = parseMemoryOptions(args);
  args.finish(1);

  ReadOptions readOptions;
  readOptions.readUV = true;
  CheckFigures figures;
  figures.budget = memory.budget;
  // Draco decodes a whole mesh at once: no stream to check out of core.
  refuseDracoInputAboveBudget(path, memory.budget, kProgramBytes, kBytesPerFace + kBytesPerVertex,
                              "convert it to PLY (seamvox convert " + path + " OUT.ply) or raise --memory-budget");
  const std::unique_ptr<MeshStream> stream = openMeshStream(path, readOptions);
  figures.estimate = estimateInMemoryBytes(path, *stream);
  if (figures.estimate <= memory.budget) {
    figures.result = checkInMemory(path, *stream, fieldPath, edgeLength, tolerance);
  } else {
    if (fieldPath) {
      throw UsageError("--field: the gradient error reads the field whole; the map (about " +
                       formatByteSize(figures.estimate) + " in memory) is above the --memory-budget of " +
                       formatByteSize(memory.budget) + ": check without --field or raise --memory-budget");
    }
    MapCheckOptions options;
    options.edgeLength = edgeLength;
    const std::uint64_t program = currentResidentBytes();
    options.memoryBytes = memory.budget > program ? memory.budget - program : 0;
    if (options.memoryBytes < 5 * kMinimumSortBytes) {
      std::fprintf(stderr, "seamvox check: the budget %s is below what the program holds (%s) and 5 MiB for the sorts: running with that minimum\n",
                   formatByteSize(memory.budget).c_str(), formatByteSize(program).c_str());
    }
    options.scratchParent = memory.scratch;
    figures.scratch = checkMapStream(*stream, options);
    figures.outOfCore = true;
    CheckResult& r = figures.result;
    r.faces = static_cast<std::uint32_t>(figures.scratch.faces);
    r.seams = figures.scratch.seams;
    r.map = figures.scratch.map;
    r.tolerance = tolerance;
    r.isSeamless = r.seams.isSeamless(tolerance);
  }
  if (json) {
    printJson(path, figures);
  } else {
    printText(path, figures);
  }
  return figures.result.isSeamless ? 0 : kNotSeamless;
}

}  // namespace

SEAMVOX_COMMAND({"check", "check that a parameterized mesh is seamless; print its quality",
                 "usage: seamvox check MESH [--field FILE] [--edge-length H] [--tolerance T] [--json]\n"
                 "                     [--memory-budget SIZE] [--scratch DIR]\n"
                 "\n"
                 "Reads MESH with its per-corner (u, v), finds the seam edges (interior edges whose two\n"
                 "sides have different UVs), fits q' = r q + t on each (r a quarter turn) and reports\n"
                 "the largest residual, the largest distance of a t from integers, flipped and\n"
                 "collapsed triangles and, with a field, the relative L2 gradient error.\n"
                 "Exit code 0 when seamless (both figures <= T), 5 when not, 1 on errors.\n"
                 "\n"
                 "  --field FILE      per-face field (one vector per face of MESH) for the gradient error\n"
                 "  --edge-length H   grid spacing of the map (default: fitted by least squares)\n"
                 "  --tolerance T     seamless tolerance (default 1e-6)\n"
                 "  --json            print a JSON document\n"
                 "\n"
                 "A map whose in-memory check would exceed the budget (estimated from the header's\n"
                 "counts) is checked out of core: streamed once and measured by external sorts in a\n"
                 "scratch folder, same figures; the output says which path ran. Draco files are decoded\n"
                 "whole and refused above the budget.\n"
                 SEAMVOX_MEMORY_HELP,
                 {"json"},
                 &runCheck});

}  // namespace seamvox::cli
