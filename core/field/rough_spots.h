#pragma once
/// Rough spots of the field's smoothed surface: scan noise on parts tessellated far below the
/// grid's scale. The noise of a scan is in world units, so where its triangles are much smaller
/// than elsewhere each vertex moves several of its own edges and the surface crumples there. The
/// few global smoothing steps of the field's surface (kFieldSmoothingIterations) reach only a few
/// of those tiny edges, and every crumpled vertex turns the connection enough to put a pair of
/// cones there. smoothRoughSpots smooths such spots further, within a grid cell.
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// A vertex is rough where its angle defect on the smoothed surface exceeds this (radians; a
/// vertex of a smooth surface sampled finely has a defect far below it, one whose defect nears a
/// quarter turn is a cone by itself) ...
constexpr double kRoughSpotDefect = 0.1;
/// ... and the mean length of its edges there is below this fraction of the grid's edge length
/// (a spot far below the scale the map can follow; coarse meshes keep their features).
constexpr double kRoughSpotSpacing = 1.0 / 16.0;
/// ... and below this fraction of the mean over the mesh (a part tessellated finer than the rest:
/// a uniformly sampled scan, whose noise the global steps handle, keeps its shape) ...
constexpr double kRoughSpotRelative = 0.5;
/// ... and the defects of the vertices within two rings of it cancel: their sum's magnitude below
/// this fraction of the sum of their magnitudes. Crumpled noise turns the surface both ways; a
/// sharp tip of the shape (a subdivided mesh's claw or ear) turns it one way and keeps its shape.
constexpr double kRoughSpotCancel = 0.3;
/// Vertices within this many grid edge lengths of a rough vertex (along edges) are smoothed ...
constexpr double kRoughSpotRadius = 1.0;
/// ... by this many Laplacian steps (each halfway to the mean of the neighbours, as
/// smoothPositions; beyond half the radius a share of it tapering to none at the rim, so that the
/// region joins the held surface around it without a crease), about 8 of their own edges of
/// smoothing: 32 steps (4 edges) left clusters of cone pairs at camelhead x5's eyes with noise, and
/// a held rim without the taper put new cones there (bench/RESULTS.md, session 59) ...
constexpr std::uint32_t kRoughSpotSteps = 128;
/// ... for at most this many rounds, each on the vertices still rough after the one before.
constexpr std::uint32_t kRoughSpotRounds = 2;

/// Bytes a vertex of a rough spot's region holds at most while the rounds run (id maps, fans,
/// positions, distances, the renumbering; about 200).
constexpr std::uint64_t kRoughRegionBytes = 256;
/// A region of this many vertices is smoothed within any budget (16 MiB).
constexpr std::uint64_t kRoughRegionMinVertices = std::uint64_t(1) << 16;

/// The most vertices a round's region may hold in memory: a quarter of the mesh's vertices (the
/// field stage stays below param's estimate by more than that: noisy armadillo x4's field stage
/// peaked at 1.5 GB against an estimate of 2.3 GB), plus what headroomBytes (the budget less the
/// estimate) holds at kRoughRegionBytes a vertex, and at least kRoughRegionMinVertices.
std::uint64_t roughRegionBoundInMemory(std::uint64_t numVertices, std::uint64_t headroomBytes);

struct RoughSpotResult {
  /// The vertices moved and their new positions, sorted by vertex.
  std::vector<std::pair<VertexId, Vec3f>> moved;
  std::uint32_t roughVertices = 0;  ///< rough vertices found before the first round
  std::uint32_t rounds = 0;         ///< rounds run
  bool capped = false;              ///< a round's region exceeded maxRegion: that round moved nothing
};

/// Smooths the rough spots of `positions` (a smoothed surface of the topology's mesh, changed in
/// place) for a grid of edge length gridLength (> 0). Interior vertices only; boundary and
/// isolated vertices stay. Deterministic for any thread count. A round whose region (with its
/// held neighbours) would exceed maxRegion vertices smooths nothing and ends the rounds (capped).
/// Memory: 5 bytes per vertex (4 during a round's search), and up to kRoughRegionBytes per vertex
/// of a round's region.
RoughSpotResult smoothRoughSpots(const Topology& topology, std::vector<Vec3f>& positions, double gridLength,
                                 std::uint64_t maxRegion = ~std::uint64_t(0));

/// Angle defect at interior vertex v (2 pi minus its corner angles; 0 at boundary and isolated
/// vertices).
double angleDefect(const Topology& topology, const std::vector<Vec3f>& positions, VertexId v);

}  // namespace seamvox
