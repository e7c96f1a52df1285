#pragma once
/// Quality figures of a parameterization (DESIGN section 11).
#include <cstdint>
#include <vector>

#include "cut.h"
#include "field.h"
#include "mesh.h"
#include "topology.h"

namespace seamvox {

/// Seam figures. A map is seamless when both maxima are below the tolerance (1e-6).
struct SeamQuality {
  std::uint64_t seamEdges = 0;
  std::uint32_t seams = 0;           ///< seam curves (0 when reconstructed from UVs)
  double seamLength = 0.0;           ///< 3D length of the seam edges
  double maxResidual = 0.0;          ///< max |q' - (r q + t)| over seam corners
  double maxIntegerDistance = 0.0;   ///< max distance of a seam's t from Z + iZ
  std::uint64_t worstEdgeCorner = kInvalidId;  ///< corner of the edge with the largest residual
  bool isSeamless(double tolerance = 1e-6) const {
    return maxResidual <= tolerance && maxIntegerDistance <= tolerance;
  }
};

/// Seams of a known cut: per seam, t is read at its first corner with r = i^(-matching) (cut.h)
/// and q_right = r q_left + t is checked at both ends of every edge.
SeamQuality measureSeams(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                         const std::vector<Vec2d>& cornerUV);

/// Seams reconstructed from per-corner UVs alone: every interior edge whose two sides differ is a
/// seam edge; r in {1, i, -1, -i} and t come from one endpoint (the r fitting best at the other),
/// the residual from the other endpoint.
SeamQuality measureSeamsFromUV(const TriangleMesh& mesh, const Topology& topology,
                               const std::vector<Vec2d>& cornerUV);

struct MapQuality {
  std::uint64_t faces = 0;
  std::uint64_t flipped = 0;    ///< negative parameter-space area (not collapsed)
  std::uint64_t collapsed = 0;  ///< |parameter area| < 1e-6 of the expected area A / h^2
  double flippedFraction = 0.0;
  /// sqrt(sum A |grad q - w/h|^2 / sum A |w/h|^2), w the nearest of the 4 cross directions;
  /// NaN without a field.
  double relativeGradientError = 0.0;
  double edgeLength = 0.0;  ///< h used (given, or fitted by least squares when given <= 0)
};

/// Flips, collapses and the gradient error against a field (may be null) for target spacing h
/// (<= 0: fitted). Linear, parallel.
MapQuality measureMap(const TriangleMesh& mesh, const std::vector<Vec2d>& cornerUV,
                      const CrossField* field, double edgeLength);

}  // namespace seamvox
