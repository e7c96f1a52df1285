// The verdict on a parameterized mesh: clean, reconstruct seams from the UVs, measure the map.
#include "core/quality/check.h"

#include <string>

#include "core/field/field.h"
#include "core/mesh/clean.h"
#include "core/system/errors.h"

namespace seamvox {

CheckResult checkParameterization(TriangleMesh raw, const CheckOptions& options) {
  if (!raw.hasUV()) throw InputError("the mesh has no per-corner texture coordinates");
  const std::uint32_t inputFaces = raw.numFaces();
  const bool hasField = !options.fieldPerInputFace.empty();
  if (hasField && options.fieldPerInputFace.size() != inputFaces) {
    throw InputError("the field has " + std::to_string(options.fieldPerInputFace.size()) +
                     " vectors for a mesh of " + std::to_string(inputFaces) + " faces");
  }
  CleanResult clean = cleanMesh(std::move(raw));
  const TriangleMesh& mesh = clean.mesh;
  CrossField field;
  if (hasField) {
    std::vector<Vec3d> perFace(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) perFace[f] = options.fieldPerInputFace[clean.faceOrigin[f]];
    field = projectToTangent(mesh, perFace);
  }
  CheckResult r;
  r.faces = mesh.numFaces();
  r.seams = measureSeamsFromUV(mesh, clean.topology, mesh.cornerUV);
  r.map = measureMap(mesh, mesh.cornerUV, hasField ? &field : nullptr, options.edgeLength, nullptr, &clean.topology);
  r.hasField = hasField;
  r.tolerance = options.tolerance;
  r.isSeamless = r.seams.isSeamless(options.tolerance);
  return r;
}

}  // namespace seamvox
