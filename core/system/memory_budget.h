#pragma once
/// The memory budget of a command (`--memory-budget SIZE`): how sizes are written and the
/// default, a share of the memory the system can give without swapping.
#include <cstdint>
#include <optional>
#include <string>

namespace seamvox {

/// "2G", "1500M", "800K", "1.5G", "4096" (bytes): a positive number with an optional suffix
/// K, M, G or T (powers of 1024, case-insensitive, an optional trailing "B" or "iB"). Nothing
/// when the text is not such a size or rounds to 0 bytes.
std::optional<std::uint64_t> parseByteSize(const std::string& text);

/// "1.50 GiB", "800 MiB", "12 KiB", "512 B": a size for messages.
std::string formatByteSize(std::uint64_t bytes);

/// The default budget: three quarters of MemAvailable (the rest left to the other programs of
/// the machine), at least kMinimumDefaultBudget; that minimum when MemAvailable is unknown.
std::uint64_t defaultMemoryBudget();
constexpr std::uint64_t kMinimumDefaultBudget = std::uint64_t(256) << 20;

}  // namespace seamvox
