#pragma once
/// The figures of `seamvox check` computed out of core: a parameterized mesh is read once as a
/// stream and measured by external sorts in a scratch folder (faces cleaned as cleanMesh cleans
/// them: degenerate and duplicate faces dropped, edges of more than two faces paired flattest
/// first), so memory stays within a limit whatever the mesh size. Same figures as
/// measureSeamsFromUV and measureMap (no field, with the topology: wound vertices counted) on
/// the cleaned mesh in memory.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/quality/metrics.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// Each sort gets at least this much, whatever memoryBytes says (smaller buffers only cost time).
constexpr std::uint64_t kMinimumSortBytes = std::uint64_t(1) << 20;

struct MapCheckOptions {
  double edgeLength = 0.0;  ///< grid spacing h; <= 0: fitted by least squares as measureMap fits it
  /// Memory of the sorts (the records buffered and merged at once); each of the up to five
  /// sorts alive at a time gets a fifth.
  std::uint64_t memoryBytes = std::uint64_t(256) << 20;
  std::string scratchParent = "/tmp";  ///< the scratch folder is created in it
  /// Called with the scratch folder once created (tests set a write limit through it).
  std::function<void(ScratchFolder&)> onScratch;
};

struct MapCheckResult {
  std::uint64_t faces = 0;  ///< after cleaning
  SeamQuality seams;
  MapQuality map;  ///< relativeGradientError NaN: no field
  std::vector<ScratchTraffic> traffic;  ///< scratch bytes read and written per stage
  /// Wall seconds of the passes: read (with the join when positions are not in memory),
  /// duplicates, faces, edges, flips.
  std::vector<std::pair<std::string, double>> stageSeconds;
  std::uint64_t scratchPeakBytes = 0;
  /// The vertex positions were held in memory (the header declared a count whose positions fit
  /// half of memoryBytes) rather than joined with the corners through external sorts.
  bool positionsInMemory = false;
};

/// Scratch bytes checkMapStream needs for faces and vertices (what a disk-full error quotes).
std::uint64_t mapCheckScratchBytes(std::uint64_t vertices, std::uint64_t faces);

/// Measures the map of a stream read with texture coordinates. Throws InputError (no UVs,
/// indices out of range, non-finite coordinates, no valid faces, faces whose orientation
/// clashes: those need the in-memory check, which reorients them), IoError (scratch).
MapCheckResult checkMapStream(MeshStream& stream, const MapCheckOptions& options);

}  // namespace seamvox
