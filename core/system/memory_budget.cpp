#include "core/system/memory_budget.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/system/memory.h"

namespace seamvox {

std::optional<std::uint64_t> parseByteSize(const std::string& text) {
  if (text.empty() || !(std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '.')) return std::nullopt;
  char* end = nullptr;
  const double number = std::strtod(text.c_str(), &end);
  std::string suffix(end);
  for (char& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (suffix.size() > 1 && (suffix.substr(1) == "B" || suffix.substr(1) == "IB")) suffix.resize(1);
  double scale = 1.0;
  if (suffix == "K") scale = 1024.0;
  else if (suffix == "M") scale = 1048576.0;
  else if (suffix == "G") scale = 1073741824.0;
  else if (suffix == "T") scale = 1099511627776.0;
  else if (!suffix.empty() && suffix != "B") return std::nullopt;
  const double bytes = std::round(number * scale);
  if (!std::isfinite(bytes) || bytes < 1.0 || bytes > 9.0e18) return std::nullopt;
  return static_cast<std::uint64_t>(bytes);
}

std::string formatByteSize(std::uint64_t bytes) {
  char text[32];
  if (bytes >= (std::uint64_t(1) << 30)) {
    std::snprintf(text, sizeof text, "%.2f GiB", bytes / 1073741824.0);
  } else if (bytes >= (std::uint64_t(1) << 20)) {
    std::snprintf(text, sizeof text, "%.1f MiB", bytes / 1048576.0);
  } else if (bytes >= 1024) {
    std::snprintf(text, sizeof text, "%.1f KiB", bytes / 1024.0);
  } else {
    std::snprintf(text, sizeof text, "%llu B", static_cast<unsigned long long>(bytes));
  }
  return text;
}

std::uint64_t defaultMemoryBudget() {
  const std::uint64_t available = availableMemoryBytes();
  const std::uint64_t share = available / 4 * 3;
  return share > kMinimumDefaultBudget ? share : kMinimumDefaultBudget;
}

}  // namespace seamvox
