#pragma once
/// `seamvox render` out of core: a parameterized mesh is read once as a stream; its faces go to a
/// scratch folder (their corner positions joined by external sorts when the positions do not fit
/// in memory), the camera is framed from every position, and the faces are rasterized chunk by
/// chunk with the in-memory renderer's code (core/synth/render_canvas), so the picture is the
/// same; seams (sides of an edge whose (u, v) differ, the sides glued as cleanMesh glues them) and
/// cones (interior vertices whose (u, v) angles do not sum to 2 pi) come from external sorts of
/// the edges and corners. Memory: the canvas (11 bytes per sample) plus the given limit.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/synth/render.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

struct MapRenderOptions {
  RenderOptions render;  ///< lines (a quad mesh's edges) are drawn from memory as given
  /// Memory of the sorts and of the positions when they fit half of it (the canvas comes on top).
  std::uint64_t memoryBytes = std::uint64_t(256) << 20;
  std::string scratchParent = "/tmp";  ///< the scratch folder is created in it
  /// Vertices at exactly equal positions are one vertex for the seams and cones (cleanMesh's weld
  /// with tolerance 0; a map whose vertices are split along its seams): 4 bytes per vertex.
  bool weld = false;
  /// Called with the scratch folder once created (tests set a write limit through it).
  std::function<void(ScratchFolder&)> onScratch;
};

struct MapRenderResult {
  RenderResult render;
  std::uint64_t faces = 0;  ///< drawn: without repeated vertices and duplicates, as cleanMesh keeps them
  std::vector<ScratchTraffic> traffic;  ///< scratch bytes read and written per stage
  /// Wall seconds of the passes: read, duplicates, faces (rasterized), edges, cones.
  std::vector<std::pair<std::string, double>> stageSeconds;
  std::uint64_t scratchPeakBytes = 0;
  bool positionsInMemory = false;  ///< the vertex positions fitted half of memoryBytes
};

/// Scratch bytes renderMapStream needs at most (what a disk-full error quotes).
std::uint64_t mapRenderScratchBytes(std::uint64_t vertices, std::uint64_t faces, bool seamsOrCones);

/// Renders the map of a stream read with texture coordinates. The faces' pixels equal
/// renderCheckerboard's on the cleaned mesh with its faceOrigin as face ids; seams and cones too
/// on meshes without non-manifold vertices and orientation clashes (out of core a clashing edge
/// is glued as it is, without reorienting faces, and the fans of a non-manifold vertex are summed
/// as one vertex; with weld, faces that become duplicates when welded are kept for the seams and
/// cones). Throws InputError (no UVs, indices out of range, non-finite coordinates, no
/// valid faces), IoError (scratch).
MapRenderResult renderMapStream(MeshStream& stream, const MapRenderOptions& options);

}  // namespace seamvox
