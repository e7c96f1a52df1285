#pragma once
/// The cut stage of the out-of-core param: cutToDisk on the cleaned mesh in the scratch folder and
/// the out-of-core field's singularities (field_stream), the same steps (core/cut/detail_cut.h)
/// over page caches of scratch files. Conventions: core/cut/cut.h.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/cut/cut.h"
#include "stream/clean_stream.h"
#include "stream/field_stream.h"
#include "stream/paged_reader.h"
#include "stream/scratch_folder.h"

namespace seamvox {

struct ScratchCut {
  ScratchFile corners;       ///< per corner CutCorners' byte: cut flag and combed matching
  ScratchFile faceRotation;  ///< per face the quarter turns combing applied (0..3)
  std::vector<SeamCurve> seams;
  std::vector<VertexId> cones;
  std::uint32_t components = 0;
  /// Wall seconds of the passes: tree, prune, comb, seams.
  std::vector<std::pair<std::string, double>> stageSeconds;
};

/// The cut file (ScratchCut::corners) read through a page cache as CutCorners is read.
class PagedCutCorners {
 public:
  PagedCutCorners(const ScratchFile& corners, std::size_t cacheBytes, std::size_t pageBytes = kScratchPageBytes)
      : bytes_(corners, cacheBytes, pageBytes) {}
  bool isCut(CornerId c) { return CutCorners::isCutByte(bytes_[c]); }
  std::uint8_t matching(CornerId c) { return CutCorners::matchingOfByte(bytes_[c]); }
  std::uint64_t bytesRead() const { return bytes_.bytesRead(); }

 private:
  PagedReader<std::uint8_t> bytes_;
};

/// The islands (core/basis/islands.h) read off the first cut's dual tree, which meets the
/// components one after another: found(faces) is called once the tree is built, while the cut
/// goes on (the voxel clip, which leaves them out, can start beside it).
struct TreeIslands {
  std::uint32_t maxFaces = 0;
  std::function<void(std::vector<FaceId>)> found;
};

/// Equal to cutToDisk on readCleanScratch's mesh with the singularities' matchings and cones:
/// the same cut, rotations and seam curves. Working state in scratch files (1 byte per face for
/// the rotations, 4 for the components, 1 per corner, 4 per vertex), removed at the end; in
/// memory the page caches, the tree's front and the seams. TopologyError as cutToDisk's; IoError
/// naming the folder on a full disk.
ScratchCut cutScratchToDisk(ScratchFolder& folder, const CleanScratch& scratch, const ScratchSingularities& singularities,
                            const StreamPassOptions& pass, const TreeIslands* islands = nullptr);

}  // namespace seamvox
