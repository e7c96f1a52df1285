#include "stream/memory.h"

#include <cstdio>
#include <cstring>

namespace seamvox {
namespace {

/// Value of a "Name:   123 kB" line of /proc/self/status, in bytes (0 when unavailable).
std::uint64_t statusBytes(const char* field) {
  std::FILE* file = std::fopen("/proc/self/status", "r");
  if (!file) return 0;
  char line[256];
  std::uint64_t bytes = 0;
  const std::size_t length = std::strlen(field);
  while (std::fgets(line, sizeof line, file)) {
    if (std::strncmp(line, field, length) == 0 && line[length] == ':') {
      unsigned long long kb = 0;
      if (std::sscanf(line + length + 1, "%llu", &kb) == 1) bytes = kb * 1024ull;
      break;
    }
  }
  std::fclose(file);
  return bytes;
}

}  // namespace

std::uint64_t peakResidentBytes() { return statusBytes("VmHWM"); }
std::uint64_t currentResidentBytes() { return statusBytes("VmRSS"); }

}  // namespace seamvox
