#include "tools/memory_path.h"

#include <sys/stat.h>

#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "io/json.h"
#include "io/mesh_io.h"

namespace seamvox::cli {

MeshCounts guessMeshCounts(const std::string& path, const MeshStream& stream) {
  MeshCounts counts;
  counts.faces = stream.declaredFaces() ? stream.declaredFaces() : stream.expectedTriangles();
  // STL declares its facets' corners; about half as many vertices as faces stay once welded.
  counts.vertices = stream.cornerVertices() ? 0 : stream.declaredVertices();
  struct stat info {};
  if (counts.faces == 0 && ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode)) {
    counts.faces = static_cast<std::uint64_t>(info.st_size) / (formatFromPath(path) == MeshFormat::Draco ? 1 : 20);
  }
  if (counts.vertices == 0) counts.vertices = counts.faces / 2;
  return counts;
}

void refuseDracoInputAboveBudget(const std::string& path, std::uint64_t budget, std::uint64_t programBytes,
                                 std::uint64_t bytesPerFace, const std::string& alternative) {
  if (formatFromPath(path) != MeshFormat::Draco) return;
  struct stat info {};
  const std::uint64_t estimate =
      programBytes + (::stat(path.c_str(), &info) == 0 ? static_cast<std::uint64_t>(info.st_size) : 0) * bytesPerFace;
  if (estimate > budget) {
    throw InputError(path + ": a Draco file is decoded whole, about " + formatByteSize(estimate) +
                     " in memory, above the --memory-budget of " + formatByteSize(budget) + "; " + alternative);
  }
}

void MemoryPath::recordScratch(const ScratchFolder& scratch) {
  traffic = scratch.traffic();
  scratchPeakBytes = scratch.peakBytesOnDisk();
}

std::string describeMemoryPath(const MemoryPath& path) {
  std::string out = path.outOfCore ? "path out of core: estimate " + formatByteSize(path.estimate) + " above the budget "
                                   : "path in memory: estimate " + formatByteSize(path.estimate) + " within the budget ";
  out += formatByteSize(path.budget);
  if (path.outOfCore && !path.traffic.empty()) {
    out += "; scratch peak " + formatByteSize(path.scratchPeakBytes);
    for (const ScratchTraffic& t : path.traffic) {
      out += ", " + t.stage + " " + formatByteSize(t.bytesWritten) + " written / " + formatByteSize(t.bytesRead) + " read";
    }
  }
  return out + "; peak memory " + formatByteSize(path.peakBytes ? path.peakBytes : peakResidentBytes());
}

void writeMemoryPathJson(JsonWriter& j, const MemoryPath& path, bool withPeak) {
  j.key("path").value(std::string(path.outOfCore ? "out-of-core" : "in-memory"));
  j.key("memoryBudget").value(path.budget).key("estimatedBytes").value(path.estimate);
  if (path.outOfCore) {
    j.key("scratch").beginObject();
    j.key("peakBytes").value(path.scratchPeakBytes);
    j.key("stages").beginArray();
    for (const ScratchTraffic& t : path.traffic) {
      j.beginObject().key("stage").value(t.stage).key("bytesWritten").value(t.bytesWritten);
      j.key("bytesRead").value(t.bytesRead).endObject();
    }
    j.endArray().endObject();
  }
  if (withPeak) j.key("peakResidentBytes").value(peakResidentBytes());
}

}  // namespace seamvox::cli
