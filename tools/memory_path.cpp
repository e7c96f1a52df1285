#include "tools/memory_path.h"

#include "core/system/memory.h"
#include "core/system/memory_budget.h"
#include "io/json.h"

namespace seamvox::cli {

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
  return out + "; peak memory " + formatByteSize(peakResidentBytes());
}

void writeMemoryPathJson(JsonWriter& j, const MemoryPath& path) {
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
  j.key("peakResidentBytes").value(peakResidentBytes());
}

}  // namespace seamvox::cli
