// OpenMP parallel regions of one thread run inline in the `seamvox` command.
//
// Debian's CHOLMOD (SuiteSparse 5.12, built with OpenMP) enters an OpenMP parallel region for
// each descendant update of a supernodal factorization, with an `if` clause that keeps most of
// them to one thread. libgomp still builds a team for each (an allocation, and a futex wake at
// its closing barrier even for one thread): about 1.3 us per region here, millions per large
// factorization. With the thread limit the command sets (OMP_THREAD_LIMIT=1,
// rerunWithPreferredRuntime) every region has exactly one thread, and calling its body directly
// is the same computation: the command exports this GOMP_parallel, which the dynamic linker
// binds CHOLMOD's calls to ahead of libgomp's, and it runs the body inline under that limit
// (the results are the same bits; only libgomp's bookkeeping goes). Under any other limit, or
// with SEAMVOX_OPENMP_INLINE=0, it hands the region to libgomp unchanged.
#include <dlfcn.h>

#include <cstdlib>
#include <cstring>

#include "tools/cli.h"

extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned numThreads, unsigned flags);

namespace {

using RegionEntry = void (*)(void (*)(void*), void*, unsigned, unsigned);

bool inlineUnderThisLimit() {
  const char* limit = std::getenv("OMP_THREAD_LIMIT");
  const char* choice = std::getenv("SEAMVOX_OPENMP_INLINE");
  return limit && std::strcmp(limit, "1") == 0 && !(choice && std::strcmp(choice, "0") == 0);
}

// libgomp's entry, for regions that keep their team (nullptr when no OpenMP runtime is loaded:
// then nothing else could run the region either, and it runs inline).
RegionEntry libgompEntry() {
  static const RegionEntry entry = reinterpret_cast<RegionEntry>(dlsym(RTLD_NEXT, "GOMP_parallel"));
  return entry;
}

}  // namespace

extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned numThreads, unsigned flags) {
  static const bool inlined = inlineUnderThisLimit();
  const RegionEntry entry = inlined ? nullptr : libgompEntry();
  if (!entry) {
    fn(data);
    return;
  }
  entry(fn, data, numThreads, flags);
}

namespace seamvox::cli {

/// Whether this process's OpenMP regions run inline: the limit allows it and the dynamic linker
/// resolves GOMP_parallel to the command's own (as it does CHOLMOD's calls).
bool openmpRegionsRunInline() {
  const void* bound = dlsym(RTLD_DEFAULT, "GOMP_parallel");
  return inlineUnderThisLimit() && bound == reinterpret_cast<const void*>(&GOMP_parallel);
}

}  // namespace seamvox::cli
