#pragma once
/// Transparent huge pages for large blocks. Where the kernel's THP mode is "madvise" (Debian's
/// default), every 4 KB page of a fresh block faults on first touch; on a virtual machine a page
/// fault costs microseconds, and the multi-gigabyte arrays of a 10M-face run touch millions of
/// pages. Advising the block's 2 MB-aligned interior as huge pages cuts those faults 512-fold.
#include <cstddef>

namespace seamvox {

/// Blocks at least this large are advised (2 huge pages: smaller ones gain little).
constexpr std::size_t kHugePageAdviceBytes = std::size_t(4) << 20;

/// Advises the 2 MB-aligned pages inside [p, p + bytes) as huge pages (MADV_HUGEPAGE) when bytes
/// >= kHugePageAdviceBytes; a no-op elsewhere and where unsupported. Call before first touch.
void adviseHugePages(void* p, std::size_t bytes) noexcept;

/// std::malloc (at least 1 byte) with the advice above; null when out of memory.
void* mallocAdvised(std::size_t bytes) noexcept;

}  // namespace seamvox
