#pragma once
/// The voxel basis' elements out of core (DESIGN sections 6 and 12): the cleaned mesh's faces
/// (clean_stream) clipped into voxel fragments by a TBB pipeline whose last stage registers the
/// voxels in the sparse OpenVDB grid and writes the fragments to the scratch folder; the fragments
/// sorted by voxel give each voxel's elements and their integrals, which stay in memory (grid-sized);
/// the element of each fragment goes back to face order in a file. Equal, bit for bit, to
/// buildVoxelBasis's elements and integrals on readCleanScratch's mesh with the same field and cut.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/basis/voxel_basis.h"
#include "core/basis/voxel_grid.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/field_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

struct ScratchVoxelElements {
  VoxelGridGeometry geometry;
  VoxelGrid grid;                ///< voxel -> id, ids in the order of the tree's leaf blocks
  ScratchFile fragments;         ///< VoxelFragment per fragment, by face (as buildVoxelBasis orders them)
  ScratchFile fragmentElement;   ///< std::uint32_t per fragment: its element
  ScratchFile faceFragmentStart;  ///< std::uint32_t per face and one more: its first fragment
  std::uint64_t numFragments = 0;
  std::vector<std::uint32_t> voxelElementStart;  ///< #voxels + 1: elements of voxel id v
  std::vector<std::uint32_t> elementVoxel;       ///< #elements
  std::vector<VoxelIntegrals> records;           ///< #elements, tangential (VoxelBasis::elementRecord)
  std::vector<std::array<double, 36>> normalStiffness;  ///< #elements, the normal-derivative term, unweighted
  /// Wall seconds of the passes: bounds, clip, sort, elements, order.
  std::vector<std::pair<std::string, double>> stageSeconds;
};

/// The voxel basis' first passes, which depend on the mesh and the faces left out alone (not on the
/// field or the cut): the grid's geometry and voxels, the faces clipped into fragments (in face
/// order, with each face's first fragment) and the fragments' sort by voxel, its records written
/// but not yet read back. Memory while it waits: the grid and the sort's write buffers (all its
/// records while they fit its share, a quarter of the pass's memory).
struct ScratchVoxelClip {
  ScratchVoxelClip();
  ScratchVoxelClip(ScratchVoxelClip&&) noexcept;
  ScratchVoxelClip& operator=(ScratchVoxelClip&&) noexcept;
  ~ScratchVoxelClip();
  VoxelGridGeometry geometry;
  VoxelGrid grid;
  ScratchFile fragments, faceFragmentStart;
  std::uint64_t numFragments = 0;
  struct ByVoxel;
  std::unique_ptr<ByVoxel> byVoxel;
  /// Wall seconds of the passes: bounds, clip, sort.
  std::vector<std::pair<std::string, double>> stageSeconds;
};
/// The clip of buildScratchVoxelElements (options: grid resolution, clip chunks, faces left out).
ScratchVoxelClip clipScratchFaces(ScratchFolder& folder, const CleanScratch& scratch, const VoxelBasisOptions& options,
                                  const StreamPassOptions& pass);

/// Clips, sorts and integrates out of core (options: grid resolution and edge length; the
/// clip chunks). Memory: the grid, the elements' records (about 600 bytes each), the sorts'
/// and page caches' share, a block of fragments. InputError when the grid has more voxels or
/// elements than the basis indexes (a coarser grid then); IoError naming the folder on a full disk.
/// clip: clipScratchFaces' result for these options, made ahead (taken over), else clipped here.
ScratchVoxelElements buildScratchVoxelElements(ScratchFolder& folder, const CleanScratch& scratch,
                                               const ScratchField& field, const ScratchCut& cut,
                                               const VoxelBasisOptions& options, const StreamPassOptions& pass,
                                               ScratchVoxelClip* clip = nullptr);

/// The whole voxel basis out of core: the elements (buildScratchVoxelElements), then the domains
/// and seam links face by face (each face's fragments read in order, its neighbours' through page
/// caches), then the grid-sized rest as VoxelBasis builds it. Equal to buildVoxelBasis's basis
/// (domains, basis functions, seam adjacency, integrals); the basis holds no mesh: its per-face
/// index stays in the files here.
struct ScratchVoxelBasis {
  std::unique_ptr<VoxelBasis> basis;
  VoxelGrid grid;
  ScratchFile fragments, fragmentElement, faceFragmentStart;
  std::uint64_t numFragments = 0;
  /// Wall seconds of the passes: those of the elements, then link and domains.
  std::vector<std::pair<std::string, double>> stageSeconds;
};
ScratchVoxelBasis buildScratchVoxelBasis(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                         const ScratchCut& cut, const VoxelBasisOptions& options,
                                         const StreamPassOptions& pass, ScratchVoxelClip* clip = nullptr);

}  // namespace seamvox
