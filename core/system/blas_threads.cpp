#include "core/system/blas_threads.h"

#include <dlfcn.h>

#include <cstdlib>

namespace seamvox {

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

}  // namespace seamvox
