#pragma once
/// Quad mesh of a seamless integer-grid map (the approach of QEx, Ebke et al. 2013): grid vertices
/// at the integer points of the map (on its vertices, edges and faces), grid edges traced along the
/// integer iso-lines through triangles and across seams, faces by walking the traced half-edges.
/// Every predicate is exact: the map is first snapped to a fixed-point lattice (2^-20 grid units)
/// and made exactly seamless there, so each integer point is found once.
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/system/progress.h"

namespace seamvox {

/// A polygon mesh: face f is faceVertices[faceStart[f] .. faceStart[f + 1]), counter-clockwise
/// like the triangles it comes from.
struct PolygonMesh {
  std::vector<Vec3d> positions;
  std::vector<std::uint32_t> faceStart{0};
  std::vector<std::uint32_t> faceVertices;
  std::uint32_t numVertices() const { return static_cast<std::uint32_t>(positions.size()); }
  std::uint32_t numFaces() const { return static_cast<std::uint32_t>(faceStart.size() - 1); }
  std::uint32_t degree(std::uint32_t f) const { return faceStart[f + 1] - faceStart[f]; }
};

/// Seam residual and distance of translations from integers (grid units) up to which a map counts
/// as seamless for extraction (files may hold UVs rounded to float); snapping moves it that much.
constexpr double kQuadSeamTolerance = 1e-4;

struct QuadOptions {
  /// Iso-lines every `scale` units of u and v (>= 1). Needs seam translations that are multiples
  /// of scale (QuadStats::seamEdgesOffScale counts the others): a seam maps u = K m onto
  /// +-K m + t, so the coarse lines continue only where K divides t. A map rounded to any
  /// integers (seamvox param's) has them only at scale 1; map with a K times larger edge instead.
  std::int64_t scale = 1;
  ProgressFn progress;  ///< stage "quads"
};

/// What extraction found, and what it could not do (all zero on a clean seamless map).
struct QuadStats {
  std::uint64_t gridVertices = 0;      ///< integer points of the map
  std::uint64_t boundaryVertices = 0;  ///< points where iso-lines meet the boundary
  std::uint64_t tracedEdges = 0;       ///< half-edges traced along iso-lines
  std::uint64_t boundaryEdges = 0;     ///< half-edges along the boundary
  std::uint64_t untracedEdges = 0;     ///< iso-line directions whose trace failed (flips, cones)
  std::uint64_t deadEnds = 0;          ///< iso-line directions that end at a cone of index 2
  /// Cones of negative index halfway between integer points on an iso-line: vertices of the quad
  /// mesh with (4 - k) / 2 edges (the lines through them), between pentagons.
  std::uint64_t halfwayCones = 0;
  /// Edges a face walk took out and back to an integer point whose other lines all end at cones
  /// of index 2 or fold back in flipped triangles (left out, with the point when it has no other
  /// edge; both ends lose the edge in QuadResult::vertexLostEdges).
  std::uint64_t spikes = 0;
  /// Iso-lines from an integer point back to itself (around a cone of index 1 in a cell, whose
  /// rotation identifies the cell's corners): zipped out of the face beside them, the point loses
  /// both ends of the loop.
  std::uint64_t loops = 0;
  /// Pairs of faces on the same cycle of points in opposite orders (a cell the map covers twice,
  /// folded over itself where a triangle is folded in 3D): both left out, they enclose nothing.
  std::uint64_t pillows = 0;
  std::uint64_t unpairedEdges = 0;     ///< traced half-edges whose reverse trace went elsewhere
  std::uint64_t openFaces = 0;         ///< face walks that met a missing edge (no face made)
  /// Faces of two edges (an iso-line and a boundary piece or another iso-line between the same two
  /// points, around no integer point): left out, which joins their two edges into one.
  std::uint64_t digons = 0;
  std::uint64_t flippedFaces = 0;      ///< triangles of negative area in (u, v)
  std::uint64_t degenerateFaces = 0;   ///< triangles of zero area in (u, v)
  std::uint64_t pointsInFlippedFaces = 0;  ///< integer points inside flipped triangles (unused)
  std::uint64_t openVertexFans = 0;    ///< vertices whose seam transitions do not close
  std::uint64_t seamEdgesOffScale = 0;  ///< seam translations that are no multiple of the scale
  std::uint64_t holesWithoutVertex = 0;  ///< boundary loops that no iso-line meets
  std::uint64_t islands = 0;           ///< components that got no face (smaller than a cell)
  std::uint64_t islandFaces = 0;       ///< triangles of those components
  double maxSnap = 0.0;  ///< largest move of a corner by snapping and closing seams (grid units)
};

struct QuadResult {
  PolygonMesh mesh;
  std::vector<std::uint32_t> vertexComponent;  ///< #V: component of the map (computeComponents)
  std::vector<std::int8_t> vertexConeIndex;    ///< #V: index of the cone there (quarter turns), or 0
  /// #V: edges the vertex loses to cones of index 2: two-edge faces left out between two iso-lines
  /// (QuadStats::digons; one from each corner) and iso-lines that end at a cone halfway to the
  /// next integer point (QuadStats::deadEnds); at a cone halfway between integer points
  /// (QuadStats::halfwayCones), the (4 - k) / 2 directions whose iso-lines are off the grid.
  std::vector<std::uint8_t> vertexLostEdges;
  std::uint32_t cones = 0;                     ///< cones of the map
  std::uint32_t conesOnGridVertices = 0;       ///< of them, those at an integer point
  QuadStats stats;
};

/// The quad mesh of mesh.cornerUV (grid units), which must be seamless: across every interior
/// edge the sides differ by a quarter-turn rotation and an integer translation. Throws InputError
/// without UVs or with coordinates beyond 2^30 grid units. Memory: about 30 bytes per face of the
/// map plus 150 per grid vertex; parallel.
QuadResult extractQuads(const TriangleMesh& mesh, const Topology& topology,
                        const QuadOptions& options = {});

}  // namespace seamvox
