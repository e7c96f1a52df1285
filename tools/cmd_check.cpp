// seamvox check: is a parameterized mesh seamless? Seams are reconstructed from the UVs alone.
#include <cmath>
#include <cstdio>

#include "core/quality/check.h"
#include "core/system/errors.h"
#include "io/check_report.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "tools/cli.h"

namespace seamvox::cli {
namespace {

/// Exit code when the map is readable but not seamless.
constexpr int kNotSeamless = 5;

int runCheck(Args& args) {
  const std::string path = args.positional(0, "the parameterized mesh (seamvox check MESH)");
  const auto fieldPath = args.value("field");
  const double edgeLength = args.positiveNumber("edge-length", 0.0);
  const double tolerance = args.number("tolerance", 1e-6, 0.0, std::numeric_limits<double>::max());
  const bool json = args.flag("json");
  args.finish(1);

  ReadOptions readOptions;
  readOptions.readUV = true;
  TriangleMesh raw = readMesh(path, readOptions);
  CheckOptions options;
  options.edgeLength = edgeLength;
  options.tolerance = tolerance;
  if (fieldPath) options.fieldPerInputFace = readFieldVectors(*fieldPath, raw.numFaces());
  CheckResult r;
  try {
    r = checkParameterization(std::move(raw), options);
  } catch (...) {
    rethrowWithContext(path);
  }
  const SeamQuality& seams = r.seams;
  const MapQuality& map = r.map;

  if (json) {
    std::printf("%s\n", checkReportJson(path, r).c_str());
  } else {
    std::printf("%s: %u faces, %llu seam edges (length %.6g)\n", path.c_str(), r.faces,
                static_cast<unsigned long long>(seams.seamEdges), seams.seamLength);
    std::printf("seam residual %.3g, integer distance %.3g (tolerance %.3g)\n", seams.maxResidual,
                seams.maxIntegerDistance, tolerance);
    std::printf("flipped %llu (%.4f%%), collapsed %llu, h %.6g\n",
                static_cast<unsigned long long>(map.flipped), 100.0 * map.flippedFraction,
                static_cast<unsigned long long>(map.collapsed), map.edgeLength);
    if (r.hasField) std::printf("relative gradient error %.6f\n", map.relativeGradientError);
    std::printf("%s\n", r.isSeamless ? "seamless" : "NOT seamless");
  }
  return r.isSeamless ? 0 : kNotSeamless;
}

}  // namespace

SEAMVOX_COMMAND({"check", "check that a parameterized mesh is seamless; print its quality",
                 "usage: seamvox check MESH [--field FILE] [--edge-length H] [--tolerance T] [--json]\n"
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
                 "  --json            print a JSON document\n",
                 {"json"},
                 &runCheck});

}  // namespace seamvox::cli
