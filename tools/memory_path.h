#pragma once
/// How a mesh command chose between its in-memory and out-of-core paths, and the line (and JSON
/// keys) that say which ran: the estimate against the budget, the scratch traffic per stage and
/// its peak, and the peak resident memory.
#include <cstdint>
#include <string>
#include <vector>

#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {
class JsonWriter;
}

namespace seamvox::cli {

struct MemoryPath {
  bool outOfCore = false;
  std::uint64_t budget = 0, estimate = 0;
  std::vector<ScratchTraffic> traffic;  ///< scratch bytes per stage (out of core)
  std::uint64_t scratchPeakBytes = 0;
  /// The run's peak resident size when a StageMeter measured it (its stages reset the kernel's
  /// high-water mark); 0: read VmHWM.
  std::uint64_t peakBytes = 0;
  /// Takes the traffic and peak of a finished scratch folder.
  void recordScratch(const ScratchFolder& scratch);
};

/// Faces and vertices of an input as its header declares them, else guessed from the file size
/// (OBJ: a face line and its share of v and vt lines take at least 20 bytes; Draco: 1 byte).
struct MeshCounts {
  std::uint64_t faces = 0, vertices = 0;
};
MeshCounts guessMeshCounts(const std::string& path, const MeshStream& stream);

/// A Draco input is decoded whole when opened: refused (InputError ending with alternative) when
/// programBytes + bytesPerFace per byte of the file exceeds the budget.
void refuseDracoInputAboveBudget(const std::string& path, std::uint64_t budget, std::uint64_t programBytes,
                                 std::uint64_t bytesPerFace, const std::string& alternative);

/// "path in memory: estimate 1.2 GiB within the budget 2.00 GiB; peak memory 900 MiB" or
/// "path out of core: estimate ... above the budget ...; scratch peak ...; stage W written / R read, ...; peak memory ...".
std::string describeMemoryPath(const MemoryPath& path);
/// The same as JSON keys "path", "memoryBudget", "estimatedBytes", "scratch" (out of core),
/// and with withPeak "peakResidentBytes", of the object being written.
void writeMemoryPathJson(JsonWriter& json, const MemoryPath& path, bool withPeak = true);

}  // namespace seamvox::cli
