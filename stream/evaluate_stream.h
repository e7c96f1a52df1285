#pragma once
/// The map of an out-of-core voxel basis evaluated at the corners of the cut mesh: the wedges of
/// buildCutWedges (vertex by vertex) and VoxelBasis::evaluateCorners, from the scratch files of
/// the cleaned mesh, the cut and the basis' per-face fragments.
#include <array>
#include <complex>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/basis/smoothed_evaluation.h"
#include "core/system/parallel.h"
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

/// One face of an out-of-core map: its corners' vertices, positions (in double) and map values.
struct MapFace {
  FaceId f = 0;
  Triangle t{};
  std::array<Vec3d, 3> p;
  std::array<Vec2d, 3> q;
};

/// The faces of the cleaned mesh in order with their corners' positions (in double) and map
/// values, a block at a time: the faces and the corners' wedges read in order, positions and
/// values through pooled page caches in parallel. The passes that measure or seed from the whole
/// out-of-core map read it so.
class ScratchMapFaces {
 public:
  static constexpr std::uint64_t kBlockFaces = std::uint64_t(1) << 16;
  /// blockFaces: forEach's and nextBlock's faces at a time (tests set a few).
  ScratchMapFaces(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map, const std::string& stage,
                  std::size_t cacheBytes, std::uint64_t blockFaces = kBlockFaces);
  /// The next block of the remaining faces in order (at most blockFaces), their positions and
  /// values looked up in parallel; nullptr after the last (IoError when a file ends first). Valid
  /// until the next call.
  const std::vector<MapFace>* nextBlock();
  /// The remaining faces: measure(face) in parallel, then visit(face, measured) one face after
  /// another in face order, so what visit gathers is what a serial loop would gather.
  template <class Measure, class Visit>
  void forEach(Measure&& measure, Visit&& visit) {
    using Result = decltype(measure(std::declval<const MapFace&>()));
    using Stored = std::conditional_t<std::is_same<Result, bool>::value, std::uint8_t, Result>;
    std::vector<Stored> measured;
    while (const std::vector<MapFace>* block = nextBlock()) {
      measured.resize(block->size());
      parallelFor(block->size(), kLookupGrain, [&](const IndexRange& range) {
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) measured[i] = measure((*block)[i]);
      });
      for (std::size_t i = 0; i < block->size(); ++i) visit((*block)[i], static_cast<Result>(measured[i]));
    }
  }
  /// Bytes the page caches read (the sequential reads count themselves).
  std::uint64_t cacheBytesRead();

 private:
  static constexpr std::uint64_t kLookupGrain = 2048;
  struct Lookups {
    PagedFacePoints points;
    PagedReader<Vec2d> values;
  };
  /// The next block's faces and corners' wedges, read in order into block_ (false: none left).
  bool readBlock();

  const CleanScratch& scratch_;
  const ScratchMap& map_;
  std::size_t cacheBytes_;
  std::uint64_t blockFaces_;
  ScratchReader faces_, wedges_;
  FaceId next_ = 0;
  std::vector<MapFace> block_;
  std::vector<CleanFace> faceRecords_;
  std::vector<std::uint32_t> blockWedges_;
  ReaderPool<Lookups> lookups_;
};

/// buildCutWedges and basis.evaluateCorners(coefficients) out of core: the wedges of a block of
/// vertices walked (page caches), each evaluated once at its smallest corner, in parallel; the
/// wedge values written in order, the corners' wedges through a write-back cache. Equal, bit for
/// bit, to the in-memory map. coefficients: one per domain of the basis.
ScratchMap evaluateScratchVoxelMap(ScratchFolder& folder, const CleanScratch& scratch, const ScratchCut& cut,
                                   const ScratchVoxelBasis& basis, const std::vector<std::complex<double>>& coefficients,
                                   const StreamPassOptions& pass);

enum class RefineSeed : std::uint8_t;

/// The refinement's seeds read off the map by the smoothed evaluation's pass over the faces, so
/// that selectScratchRefineRegion need not pass over them again: every face whose
/// classifyRefineSeed of its parameterAreaRatio at edgeLength is not None, at the values the
/// pass leaves (the faces around the vertices it moved measured again).
struct ScratchMapSeeds {
  double edgeLength = 0.0, collapseThreshold = 0.0;  ///< set by the caller
  bool known = false;                                ///< set once faces and kinds are filled
  std::vector<FaceId> faces;                         ///< increasing
  std::vector<RefineSeed> kinds;                     ///< per face, never None
};

/// evaluateFoldsAtSmoothedSurface out of core on the map evaluateScratchVoxelMap wrote (its
/// wedge values changed in place): the faces measured in order, then around the vertices moved
/// through page caches; the smoothed surface is field.framePositions (nothing moves without it).
/// Equal, bit for bit, to the in-memory pass with the same field. With seeds, its pass also fills
/// them (nothing when there is no smoothed surface: seeds->known stays false). Memory: the folded
/// faces' vertices, the seeds and the caches.
SmoothedEvaluationStats evaluateScratchFoldsAtSmoothedSurface(ScratchFolder& folder, const CleanScratch& scratch,
                                                              const ScratchField& field,
                                                              const ScratchVoxelBasis& basis,
                                                              const std::vector<std::complex<double>>& coefficients,
                                                              double h, ScratchMap& map,
                                                              const StreamPassOptions& pass,
                                                              ScratchMapSeeds* seeds = nullptr);

}  // namespace seamvox
