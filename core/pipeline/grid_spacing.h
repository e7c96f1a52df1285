#pragma once
/// The grid spacing h of the map (one unit of (u, v) is h on the surface): defaults and
/// validation in one place, for the pipeline and every command that takes --edge-length/--cells.

namespace seamvox {

/// The grid spacing h: an explicit edge length, or the bounding-box diagonal over a cell count.
/// The one place h is defaulted and validated.
struct GridSpacing {
  static constexpr double kDefaultCells = 100.0;
  /// Finer than this many cells on the diagonal, the map's integer grid says nothing useful.
  static constexpr double kMaxCells = 1.0e6;
  double edgeLength = 0.0;  ///< given h in mesh units, or 0
  double cells = 0.0;       ///< given cell count on the diagonal, or 0 (kDefaultCells)
  /// Throws InputError naming the option when a given value is not a usable number (both given,
  /// not positive, not finite, more than kMaxCells cells).
  void validate() const;
  /// h for a mesh with this bounding-box diagonal. Throws InputError when the mesh has no extent
  /// or h is not a positive finite number below the diagonal times a million.
  double spacing(double diagonal) const;
};

}  // namespace seamvox
