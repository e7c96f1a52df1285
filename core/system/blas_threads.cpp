#include "core/system/blas_threads.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>

namespace seamvox {

namespace {
std::atomic<bool> regionsInline{false};
}  // namespace

void setOpenMPRegionsInline(bool inlined) { regionsInline = inlined; }
bool openmpRegionsInline() { return regionsInline; }

bool limitBlasThreads(int threads) {
  if (std::getenv("OPENBLAS_NUM_THREADS") || std::getenv("OMP_NUM_THREADS")) return false;
  // Looked up at run time: the BLAS is chosen by the system (Debian alternatives), not linked
  // by name, and the reference BLAS has no thread control.
  using SetThreads = void (*)(int);
  auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (!set) return false;
  set(threads < 1 ? 1 : threads);
  return true;
}

std::string blasCoreName() {
  using CoreName = char* (*)();
  auto name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  const char* core = name ? name() : nullptr;
  return core ? std::string(core) : std::string();
}

std::string preferredBlasCore() {
  if (std::getenv("OPENBLAS_CORETYPE")) return {};
  std::string core = blasCoreName();
  std::transform(core.begin(), core.end(), core.begin(), [](unsigned char c) { return std::tolower(c); });
  // What OpenBLAS's DYNAMIC_ARCH picks for a processor model it does not know: kernels of
  // processors without AVX.
  static const char* const kGeneric[] = {"prescott", "core2", "penryn", "dunnington", "nehalem", "atom",
                                         "katmai", "coppermine", "northwood", "banias"};
  if (std::none_of(std::begin(kGeneric), std::end(kGeneric), [&](const char* g) { return core == g; })) return {};
#if defined(__x86_64__) || defined(__i386__)
  // __builtin_cpu_supports also checks that the system saves the wide registers (XCR0).
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl")) {
    return "SkylakeX";
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
  if (__builtin_cpu_supports("avx")) return "Sandybridge";
#endif
  return {};
}

std::string preferredOpenMPLimit() {
  if (std::getenv("OMP_THREAD_LIMIT") || std::getenv("OMP_NUM_THREADS")) return {};
  return "1";
}

void rerunWithPreferredRuntime(char** argv) {
  const std::string core = preferredBlasCore(), limit = preferredOpenMPLimit();
  if (core.empty() && limit.empty()) return;
  if (!core.empty() && setenv("OPENBLAS_CORETYPE", core.c_str(), 1) != 0) return;
  if (!limit.empty() && setenv("OMP_THREAD_LIMIT", limit.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
}

}  // namespace seamvox
