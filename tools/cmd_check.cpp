// seamvox check: is a parameterized mesh seamless? Seams are reconstructed from the UVs alone.
#include <cmath>
#include <cstdio>

#include "core/mesh/clean.h"
#include "core/system/errors.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "io/field_io.h"
#include "io/json.h"
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
  if (!raw.hasUV()) throw InputError(path + ": the mesh has no per-corner texture coordinates");
  const std::uint32_t inputFaces = raw.numFaces();
  CleanResult clean = cleanMeshOf(path, std::move(raw));
  const TriangleMesh& mesh = clean.mesh;
  CrossField field;
  if (fieldPath) {
    const std::vector<Vec3d> vectors = readFieldVectors(*fieldPath, inputFaces);
    std::vector<Vec3d> perFace(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) perFace[f] = vectors[clean.faceOrigin[f]];
    field = projectToTangent(mesh, std::move(perFace));
  }
  const SeamQuality seams = measureSeamsFromUV(mesh, clean.topology, mesh.cornerUV);
  const MapQuality map = measureMap(mesh, mesh.cornerUV, fieldPath ? &field : nullptr, edgeLength);
  const bool seamless = seams.isSeamless(tolerance);

  if (json) {
    JsonWriter j;
    j.beginObject();
    j.key("mesh").value(path);
    j.key("faces").value(static_cast<std::uint64_t>(mesh.numFaces()));
    j.key("seamless").value(seamless).key("tolerance").value(tolerance);
    j.key("seamEdges").value(seams.seamEdges).key("seamLength").value(seams.seamLength);
    j.key("maxSeamResidual").value(seams.maxResidual);
    j.key("maxIntegerDistance").value(seams.maxIntegerDistance);
    j.key("flipped").value(map.flipped).key("flippedFraction").value(map.flippedFraction);
    j.key("collapsed").value(map.collapsed);
    j.key("edgeLength").value(map.edgeLength);
    j.key("relativeGradientError");
    if (fieldPath) {
      j.value(map.relativeGradientError);
    } else {
      j.null();
    }
    j.endObject();
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("%s: %u faces, %llu seam edges (length %.6g)\n", path.c_str(), mesh.numFaces(),
                static_cast<unsigned long long>(seams.seamEdges), seams.seamLength);
    std::printf("seam residual %.3g, integer distance %.3g (tolerance %.3g)\n", seams.maxResidual,
                seams.maxIntegerDistance, tolerance);
    std::printf("flipped %llu (%.4f%%), collapsed %llu, h %.6g\n",
                static_cast<unsigned long long>(map.flipped), 100.0 * map.flippedFraction,
                static_cast<unsigned long long>(map.collapsed), map.edgeLength);
    if (fieldPath) std::printf("relative gradient error %.6f\n", map.relativeGradientError);
    std::printf("%s\n", seamless ? "seamless" : "NOT seamless");
  }
  return seamless ? 0 : kNotSeamless;
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
