#pragma once
/// A coarser space for a region's hat system near cones (DESIGN section 10): trilinear B-splines
/// of a fine grid (spacing s, a fraction of the voxel size) sampled at the region's vertices. The
/// correction x = x0 + P c moves the free vertices' positional unknowns by sum_g c_g rho_v phi_g(v);
/// the map stays piecewise linear on the mesh, so its energy is the hat energy of the written
/// map, and it stays continuous and seamless by construction:
///  - a function moves free vertices only: locked ones keep their values, which keeps the map
///    continuous at the region's border; a function reaching a vertex without positional unknown
///    (a cone's: its value is fixed by the rounded translations) is dropped;
///  - per function, the unit rho_v of each vertex follows the charts of the faces between its
///    vertices (the seam rotations); a function whose pieces cannot agree (its support winds
///    around a cone) is dropped.
/// Near cones, where the B-splines are dropped, each free vertex keeps its own unknown: one
/// system holds the B-splines and those vertices, so the map around a cone is solved vertex by
/// vertex together with the smooth map around it, with far fewer unknowns than one per vertex.
#include <complex>
#include <cstdint>
#include <vector>

#include "core/basis/reduce.h"
#include "core/mesh/mesh.h"

namespace seamvox::detail {

struct SplineSpace {
  /// Per positional unknown j: the columns (B-spline pieces) moving it, as compressed rows over
  /// the positional unknowns of the region system: x_j = x0_j + sum value[k] c[column[k]].
  std::vector<std::uint64_t> rowStart;
  std::vector<std::uint32_t> column;
  std::vector<std::complex<double>> value;
  std::uint32_t numColumns = 0;
  std::uint32_t numSplines = 0;  ///< columns 0 .. numSplines-1: B-spline pieces; then own unknowns
  /// Per vertex of the region mesh: 1 when it keeps an unknown of its own (a column after the
  /// B-splines, value 1): the free vertices of B-splines dropped at a cone (a vertex without
  /// positional unknown in their support, or rotations that cannot agree around it). The
  /// B-splines leave these vertices out.
  std::vector<std::uint8_t> ownUnknown;
  /// B-splines dropped at cones, and those cut off at locked vertices: a column may take any
  /// values on the free vertices (the map is linear per face and the locked ones do not move), so
  /// a B-spline that reaches the region's border keeps its free vertices.
  std::uint32_t droppedAtCones = 0, truncatedAtBorder = 0;
};

/// The space over a region's system (`system.map` rows per hat domain, positional unknowns
/// 0 .. numPositional-1 with at most one entry per row; cornerDomain per corner of `mesh`).
/// vertexLocked[v]: the region keeps vertex v at its input values. Grid planes at integer
/// multiples of spacing. Deterministic; cost: a sort of 8 entries per vertex, and per B-spline the
/// edges of its vertices (6 chart links per face in all).
SplineSpace buildSplineSpace(const TriangleMesh& mesh, const std::vector<std::uint32_t>& cornerDomain,
                             const Reduction& system, const std::vector<std::uint8_t>& vertexLocked, double spacing);

}  // namespace seamvox::detail
