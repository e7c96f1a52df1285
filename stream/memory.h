#pragma once
/// Resident memory of this process, for reports (Linux /proc/self/status; 0 elsewhere).
#include <cstdint>

namespace seamvox {

/// Peak resident set size so far (VmHWM), in bytes.
std::uint64_t peakResidentBytes();
/// Current resident set size (VmRSS), in bytes.
std::uint64_t currentResidentBytes();

}  // namespace seamvox
