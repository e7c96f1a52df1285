#pragma once
/// Thread count of the BLAS behind CHOLMOD's supernodal factorization.

namespace seamvox {

/// Sets the number of BLAS threads when the BLAS in use offers it (OpenBLAS), unless the user
/// chose one with OPENBLAS_NUM_THREADS or OMP_NUM_THREADS. Returns false when it could not.
/// seamvox's own loops already run in parallel (TBB); a second pool of spinning BLAS threads
/// on the same cores made factorizations up to 2x slower on a loaded 2-core machine.
bool limitBlasThreads(int threads);

}  // namespace seamvox
