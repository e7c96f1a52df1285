#pragma once
/// The map of an out-of-core voxel basis evaluated at the corners of the cut mesh: the wedges of
/// buildCutWedges (vertex by vertex) and VoxelBasis::evaluateCorners, from the scratch files of
/// the cleaned mesh, the cut and the basis' per-face fragments.
#include <array>
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

#include "core/basis/smoothed_evaluation.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/field_stream.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"
#include "stream/scratch_folder.h"
#include "stream/voxel_stream.h"

namespace seamvox {

/// A map in the scratch folder, wedges numbered as buildCutWedges numbers them.
struct ScratchMap {
  ScratchFile vertexWedgeStart;  ///< std::uint32_t per vertex and one more: its first wedge
  ScratchFile cornerWedge;       ///< std::uint32_t per corner
  ScratchFile wedgeValues;       ///< Vec2d per wedge: (u, v) in grid units
  std::uint64_t numWedges = 0;
};

/// The faces of the cleaned mesh in order with their corners' positions (in double) and map
/// values: the faces and the corners' wedges read in order, positions and values through page
/// caches. The passes that measure or seed from the whole out-of-core map read it so.
class ScratchMapFaces {
 public:
  ScratchMapFaces(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map, const std::string& stage,
                  std::size_t cacheBytes);
  /// The next face; false after the last (IoError when the map's file ends first).
  bool next(FaceId& f, Triangle& t, std::array<Vec3d, 3>& p, std::array<Vec2d, 3>& q);
  /// Bytes the page caches read (the sequential reads count themselves).
  std::uint64_t cacheBytesRead() const { return points_.bytesRead() + values_.bytesRead(); }

 private:
  const ScratchMap& map_;
  PagedFacePoints points_;
  PagedReader<Vec2d> values_;
  ScratchReader faces_, wedges_;
  FaceId next_ = 0;
};

/// buildCutWedges and basis.evaluateCorners(coefficients) out of core: the wedges of a block of
/// vertices walked (page caches), each evaluated once at its smallest corner, in parallel; the
/// wedge values written in order, the corners' wedges through a write-back cache. Equal, bit for
/// bit, to the in-memory map. coefficients: one per domain of the basis.
ScratchMap evaluateScratchVoxelMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchCut& cut,
                                   const ScratchVoxelBasis& basis, const std::vector<std::complex<double>>& coefficients,
                                   const StreamPassOptions& pass);

/// evaluateFoldsAtSmoothedSurface out of core on the map evaluateScratchVoxelMap wrote (its
/// wedge values changed in place): the faces measured in order, then around the vertices moved
/// through page caches; the smoothed surface is field.framePositions (nothing moves without it).
/// Equal, bit for bit, to the in-memory pass with the same field. Memory: the folded faces'
/// vertices and the caches.
SmoothedEvaluationStats evaluateScratchFoldsAtSmoothedSurface(ScratchFolder& folder, const CleanScratch& scratch,
                                                              const ScratchField& field,
                                                              const ScratchVoxelBasis& basis,
                                                              const std::vector<std::complex<double>>& coefficients,
                                                              double h, ScratchMap& map,
                                                              const StreamPassOptions& pass);

}  // namespace seamvox
