#include "stream/cut_stream.h"

#include <algorithm>

#include "core/basis/islands.h"
#include "core/cut/detail_cut.h"
#include "core/system/errors.h"
#include "core/system/stopwatch.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

const char* const kStage = "cut";

/// Per face r | kVisited once the tree reached it (a zero file: none visited).
struct PagedRotation {
  static constexpr std::uint8_t kVisited = 4;
  PagedArray<std::uint8_t>& bytes;
  bool visited(FaceId f) { return (bytes[f] & kVisited) != 0; }
  std::uint8_t operator[](FaceId f) { return bytes[f] & 3; }
  void set(FaceId f, std::uint8_t r) { bytes.set(f, static_cast<std::uint8_t>(r | kVisited)); }
};

/// Per corner while cutting: kUncut once the tree crosses or pruning removes its edge (a zero
/// file: every edge cut), kTraced once a seam took it.
struct PagedWorkCorners {
  static constexpr std::uint8_t kUncut = 1, kTraced = 2;
  PagedArray<std::uint8_t>& bytes;
  bool isCut(CornerId c) { return (bytes[c] & kUncut) == 0; }
  void setCut(CornerId c, bool cut) {
    const std::uint8_t b = bytes[c];
    bytes.set(c, static_cast<std::uint8_t>(cut ? b & ~kUncut : b | kUncut));
  }
};

struct PagedTraced {
  PagedArray<std::uint8_t>& bytes;
  bool operator[](CornerId c) { return (bytes[c] & PagedWorkCorners::kTraced) != 0; }
  void set(CornerId c, bool traced) {
    const std::uint8_t b = bytes[c];
    bytes.set(c, static_cast<std::uint8_t>(traced ? b | PagedWorkCorners::kTraced : b & ~PagedWorkCorners::kTraced));
  }
};


// The tree's front and the seams' walks move over the whole surface: larger caches than a
// parallel pass's, one thread holding them.
std::size_t cutCacheBytes(std::uint64_t memoryBytes) {
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(memoryBytes / 32, std::uint64_t(1) << 15, std::uint64_t(1) << 28));
}

}  // namespace

ScratchCut cutScratchToDisk(ScratchFolder& folder, const CleanScratch& scratch, const ScratchSingularities& singularities,
                            const StreamPassOptions& pass, const TreeIslands* islands) {
  const std::uint64_t numFaces = scratch.numFaces, numCorners = 3 * numFaces, numVertices = scratch.numVertices;
  if (singularities.matching.bytes != numCorners) {
    throw InputError("cutToDisk: the singularities' matchings (" + std::to_string(singularities.matching.bytes) +
                     " corners) do not match the mesh (" + std::to_string(numFaces) + " faces)");
  }
  ScratchCut cut;
  cut.cones = singularities.cones;
  for (VertexId v : cut.cones) {
    if (v >= numVertices) throw InputError("cutToDisk: cone vertex " + std::to_string(v) + " out of range");
  }
  const auto isCone = [&](VertexId v) { return std::binary_search(cut.cones.begin(), cut.cones.end(), v); };
  const std::size_t cacheBytes = cutCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedReader<std::uint8_t> matchingReader(singularities.matching, cacheBytes);
  const auto matching = [&](CornerId c) { return matchingReader[c]; };

  const ScratchFile rotationFile = folder.zeroFile(numFaces), componentFile = folder.zeroFile(4 * numFaces);
  const ScratchFile workFile = folder.zeroFile(numCorners), degreeFile = folder.zeroFile(4 * numVertices);
  const ScratchFile edgeXorFile = folder.zeroFile(4 * numVertices);
  PagedArray<std::uint8_t> rotationBytes(folder, rotationFile, kStage, cacheBytes), workBytes(folder, workFile, kStage, cacheBytes);
  PagedArray<std::uint32_t> component(folder, componentFile, kStage, cacheBytes), degree(folder, degreeFile, kStage, cacheBytes);
  PagedRotation rotation{rotationBytes};
  PagedWorkCorners work{workBytes};

  StageClock clock(cut.stageSeconds);
  if (islands) {
    detail::IslandsInOrder found(islands->maxFaces);
    cut.components = detail::buildDualTree(table, numFaces, matching, rotation, component, work,
                                           [&](FaceId f, std::uint32_t k) { found.add(f, k); });
    islands->found(found.faces());
  } else {
    cut.components = detail::buildDualTree(table, numFaces, matching, rotation, component, work);
  }
  clock.finish("tree");

  {
    // The pruning's chains find a vertex's last cut edge from the XOR of its edges' corners
    // rather than by a walk around its fan through the page caches.
    PagedArray<CornerId> edgeXorValues(folder, edgeXorFile, kStage, cacheBytes);
    detail::CutEdgeXor<PagedArray<CornerId>> edgeXor{edgeXorValues};
    std::vector<std::uint64_t> remaining =
        detail::countCutDegrees(table, numCorners, work, component, cut.components, degree, edgeXor);
    clock.finish("degrees");
    detail::pruneCut(table, numVertices, isCone, component, remaining, work, degree, edgeXor);
    folder.countRead(kStage, edgeXorValues.bytesRead());
  }
  clock.finish("prune");

  {
    ScratchWriter corners(folder, kStage), rotations(folder, kStage);
    detail::combCorners(table, numCorners, matching, rotation, work, [&](CornerId c, bool isCut, std::uint8_t k) {
      const std::uint8_t byte = CutCorners::byteOf(isCut, k);
      corners.write(&byte, 1);
      if (c % 3 == 0) {
        const std::uint8_t r = rotation[cornerFace(c)];
        rotations.write(&r, 1);
      }
    });
    cut.corners = corners.finish();
    cut.faceRotation = rotations.finish();
  }
  clock.finish("comb");

  {
    PagedCutCorners cutCorners(cut.corners, cacheBytes);
    PagedTraced traced{workBytes};
    const auto isNode = [&](VertexId v) { return degree[v] != 2 || isCone(v) || table.isBoundaryVertex(v); };
    detail::traceSeams(table, numVertices, numCorners, isNode, degree, traced, cutCorners, cut.seams);
    folder.countRead(kStage, cutCorners.bytesRead());
  }
  clock.finish("seams");

  folder.countRead(kStage, table.bytesRead() + matchingReader.bytesRead() + rotationBytes.bytesRead() +
                               workBytes.bytesRead() + component.bytesRead() + degree.bytesRead());
  for (const ScratchFile& file : {rotationFile, componentFile, workFile, degreeFile, edgeXorFile}) folder.remove(file);
  return cut;
}

}  // namespace seamvox
