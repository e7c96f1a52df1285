#include "stream/cut_stream.h"

#include <algorithm>
#include <vector>

#include "core/basis/islands.h"
#include "core/cut/detail_cut.h"
#include "core/system/errors.h"
#include "core/system/stopwatch.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

namespace {

const char* const kStage = "cut";

/// Per face r | kVisited once the tree reached it (zeros: none visited).
template <class Bytes>
struct CutRotation {
  static constexpr std::uint8_t kVisited = 4;
  Bytes& bytes;
  bool visited(FaceId f) { return (bytes[f] & kVisited) != 0; }
  std::uint8_t operator[](FaceId f) { return bytes[f] & 3; }
  void set(FaceId f, std::uint8_t r) { bytes.set(f, static_cast<std::uint8_t>(r | kVisited)); }
};

/// Per corner while cutting: kUncut once the tree crosses or pruning removes its edge (zeros:
/// every edge cut), kTraced once a seam took it.
constexpr std::uint8_t kUncut = 1, kTraced = 2;
template <class Bytes>
struct CutWorkCorners {
  Bytes& bytes;
  bool isCut(CornerId c) { return (bytes[c] & kUncut) == 0; }
  void setCut(CornerId c, bool cut) {
    const std::uint8_t b = bytes[c];
    bytes.set(c, static_cast<std::uint8_t>(cut ? b & ~kUncut : b | kUncut));
  }
};

template <class Bytes>
struct CutTraced {
  Bytes& bytes;
  bool operator[](CornerId c) { return (bytes[c] & kTraced) != 0; }
  void set(CornerId c, bool traced) {
    const std::uint8_t b = bytes[c];
    bytes.set(c, static_cast<std::uint8_t>(traced ? b | kTraced : b & ~kTraced));
  }
};


// The tree's front and the seams' walks move over the whole surface: larger caches than a
// parallel pass's, one thread holding them.
std::size_t cutCacheBytes(std::uint64_t memoryBytes) {
  return static_cast<std::size_t>(std::clamp<std::uint64_t>(memoryBytes / 32, std::uint64_t(1) << 15, std::uint64_t(1) << 28));
}

/// The cut's state arrays in memory (zeros at first), seen as the steps see them.
struct HeldCutState {
  HeldCutState(std::uint64_t numFaces, std::uint64_t numVertices)
      : rotationValues(numFaces), workValues(3 * numFaces), componentValues(numFaces), degreeValues(numVertices),
        edgeXorValues(numVertices) {}
  HeldCutState(const HeldCutState&) = delete;
  HeldCutState& operator=(const HeldCutState&) = delete;
  std::uint64_t bytesRead() const { return 0; }
  std::vector<std::uint8_t> rotationValues, workValues;
  std::vector<std::uint32_t> componentValues, degreeValues;
  std::vector<CornerId> edgeXorValues;
  detail::VectorArray<std::uint8_t> rotation{rotationValues}, work{workValues};
  detail::VectorArray<std::uint32_t> component{componentValues}, degree{degreeValues};
  detail::VectorArray<CornerId> edgeXor{edgeXorValues};
};

/// The cut's state arrays on sparse scratch files (zeros) through page caches; the files go
/// with the state.
struct PagedCutState {
  PagedCutState(ScratchFolder& f, std::uint64_t numFaces, std::uint64_t numVertices, std::size_t cacheBytes)
      : folder(f),
        files{f.zeroFile(numFaces), f.zeroFile(3 * numFaces), f.zeroFile(4 * numFaces), f.zeroFile(4 * numVertices),
              f.zeroFile(4 * numVertices)},
        rotation(f, files[0], kStage, cacheBytes), work(f, files[1], kStage, cacheBytes),
        component(f, files[2], kStage, cacheBytes), degree(f, files[3], kStage, cacheBytes),
        edgeXor(f, files[4], kStage, cacheBytes) {}
  ~PagedCutState() {
    for (const ScratchFile& file : files) folder.remove(file);
  }
  PagedCutState(const PagedCutState&) = delete;
  PagedCutState& operator=(const PagedCutState&) = delete;
  std::uint64_t bytesRead() const {
    return rotation.bytesRead() + work.bytesRead() + component.bytesRead() + degree.bytesRead() + edgeXor.bytesRead();
  }
  ScratchFolder& folder;
  ScratchFile files[5];
  PagedArray<std::uint8_t> rotation, work;
  PagedArray<std::uint32_t> component, degree;
  PagedArray<CornerId> edgeXor;
};

/// cutScratchToDisk's passes on the state arrays given (HeldCutState or PagedCutState).
template <class State>
void cutWithState(ScratchFolder& folder, const CleanScratch& scratch, const ScratchSingularities& singularities,
                  const TreeIslands* islands, std::size_t cacheBytes, PagedCornerTable& table,
                  PagedReader<std::uint8_t>& matchingReader, State& state, ScratchCut& cut) {
  const std::uint64_t numFaces = scratch.numFaces, numVertices = scratch.numVertices, numCorners = 3 * numFaces;
  const auto isCone = [&](VertexId v) { return std::binary_search(cut.cones.begin(), cut.cones.end(), v); };
  const auto matching = [&](CornerId c) { return matchingReader[c]; };
  using Bytes = decltype(state.rotation);
  CutRotation<Bytes> rotation{state.rotation};
  CutWorkCorners<Bytes> work{state.work};
  auto& component = state.component;
  auto& degree = state.degree;

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
    detail::CutEdgeXor<decltype(state.edgeXor)> edgeXor{state.edgeXor};
    std::vector<std::uint64_t> remaining =
        detail::countCutDegrees(table, numCorners, work, component, cut.components, degree, edgeXor);
    clock.finish("degrees");
    detail::pruneCut(table, numVertices, isCone, component, remaining, work, degree, edgeXor);
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
    CutTraced<Bytes> traced{state.work};
    const auto isNode = [&](VertexId v) { return degree[v] != 2 || isCone(v) || table.isBoundaryVertex(v); };
    detail::traceSeams(table, numVertices, numCorners, isNode, degree, traced, cutCorners, cut.seams);
    folder.countRead(kStage, cutCorners.bytesRead());
  }
  clock.finish("seams");

  folder.countRead(kStage, table.bytesRead() + matchingReader.bytesRead() + state.bytesRead());
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
  const std::size_t cacheBytes = cutCacheBytes(pass.memoryBytes);
  PagedCornerTable table(scratch, cacheBytes);
  PagedReader<std::uint8_t> matchingReader(singularities.matching, cacheBytes);

  // The state arrays held in memory when they fit a third of the memory (8 B per face and per
  // vertex), else on sparse scratch files through page caches.
  if (8 * (numFaces + numVertices) <= pass.memoryBytes / 3) {
    HeldCutState state(numFaces, numVertices);
    cutWithState(folder, scratch, singularities, islands, cacheBytes, table, matchingReader, state, cut);
  } else {
    PagedCutState state(folder, numFaces, numVertices, cacheBytes);
    cutWithState(folder, scratch, singularities, islands, cacheBytes, table, matchingReader, state, cut);
  }
  return cut;
}

}  // namespace seamvox
