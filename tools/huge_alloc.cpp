// The seamvox command's global operator new: large blocks (the per-face and per-corner arrays of
// massive meshes) are advised as transparent huge pages before first touch (core/system/huge_pages.h).
// Measured on a 9.2M-face mesh: 29.4 -> 22 s wall, peak memory unchanged (bench/RESULTS.md).
// Only the executable replaces operator new; the library and its tests allocate as usual.
#include <cstdlib>
#include <new>

#include "core/system/huge_pages.h"

void* operator new(std::size_t size) {
  void* p = seamvox::mallocAdvised(size);
  if (!p) throw std::bad_alloc();
  return p;
}

void* operator new[](std::size_t size) { return ::operator new(size); }

void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return seamvox::mallocAdvised(size); }

void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return ::operator new(size, tag); }

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
