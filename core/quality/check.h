#pragma once
/// The verdict on a parameterized mesh (`seamvox check`, the Python module's check): seams
/// reconstructed from the per-corner UVs alone, flips, collapses and, against a field, the
/// gradient error.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/quality/metrics.h"

namespace seamvox {

struct CheckOptions {
  double edgeLength = 0.0;  ///< grid spacing of the map; <= 0: fitted by least squares
  double tolerance = 1e-6;  ///< seamless when the residual and the integer distance are <= this
  /// Empty, or one vector per input face (before cleaning) for the gradient error.
  std::vector<Vec3d> fieldPerInputFace;
};

struct CheckResult {
  std::uint32_t faces = 0;  ///< of the cleaned mesh
  SeamQuality seams;
  MapQuality map;           ///< relativeGradientError is NaN without a field
  bool hasField = false;
  double tolerance = 0.0;
  bool isSeamless = false;  ///< seams.isSeamless(tolerance)
};

/// Cleans the mesh (consumed; it must have per-corner UVs) and measures its map. Throws
/// InputError for a mesh without UVs or a field whose size is not the input's face count.
CheckResult checkParameterization(TriangleMesh raw, const CheckOptions& options = {});

}  // namespace seamvox
