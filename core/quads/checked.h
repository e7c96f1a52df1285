#pragma once
/// The quad mesh of a map as `seamvox quads`, `param --quads` and the Python module make it: the
/// map's seams are checked first, then the mesh is extracted and validated.
#include <cstdint>
#include <string>

#include "core/quads/extract.h"
#include "core/quads/validate.h"
#include "core/quality/metrics.h"

namespace seamvox {

struct QuadRun {
  QuadResult quads;
  QuadValidation check;
  SeamQuality seams;  ///< of the map, measured from its UVs (measureSeamsFromUV)
};

/// Extracts and validates the quad mesh of a cleaned map read from (or made for) `name`. Throws
/// InputError naming it when the map has no UVs or is not seamless (kQuadSeamTolerance), or when
/// `scale` does not divide its seam translations.
QuadRun extractCheckedQuads(const std::string& name, const TriangleMesh& mesh, const Topology& topology,
                            std::int64_t scale, const ProgressFn& progress);

}  // namespace seamvox
