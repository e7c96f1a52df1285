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
  /// Holes of the map smaller than a quad (fillSmallHoles) closed for the extraction.
  std::uint64_t filledHoles = 0;
  /// Holes of at most 32 edges left open because their loop carries a seam translation (a map
  /// made without `param --close-holes`): fillSmallHoles' `translated`.
  std::uint64_t translatedHoles = 0;
};

/// A copy of a map with its holes smaller than a quad closed: every boundary loop of at most 32
/// edges around which the charts come back (no cone inside; seams may cross it) or come back
/// turned by a cone on the loop (the loop is then read from that cone round to it, in one chart)
/// or inside it (closed only by a fan around the turn's fixed point, the cone's point, when the
/// loop and that point span less than `scale` units each way and the fan is star-shaped), whose (u, v), read
/// in one chart, span less than `scale` units each way or meet the iso-lines at two points or none,
/// in a component more than four times its size across, gets a fan of triangles from a new vertex
/// at its centroid (mean position and (u, v); in each fan face's own chart, so a seam crossing the
/// loop continues through the fan to the centre) when it is star-shaped around its mean (u, v) (no
/// face of the fan flipped), else its own points triangulated by ear clipping in the first
/// chart (a simple polygon in (u, v) through distinct vertices; otherwise left open). A hole that small cannot show in the quad mesh; left
/// open, iso-lines crossing it end on its boundary and the quads around it carry extra boundary
/// vertices (a scan's missing triangles). Returns the number of holes filled; when 0, `out` is
/// left empty and the map itself is to be used.
/// translated (optional) counts the loops of at most 32 edges left open because the charts come
/// back with a translation and no rotation.
std::uint64_t fillSmallHoles(const TriangleMesh& mesh, const Topology& topology, std::int64_t scale,
                             TriangleMesh& out, std::uint64_t* translated = nullptr);

/// Extracts and validates the quad mesh of a cleaned map read from (or made for) `name`. Throws
/// InputError naming it when the map has no UVs or is not seamless (kQuadSeamTolerance), or when
/// `scale` does not divide its seam translations.
QuadRun extractCheckedQuads(const std::string& name, const TriangleMesh& mesh, const Topology& topology,
                            std::int64_t scale, const ProgressFn& progress);

}  // namespace seamvox
