#pragma once
/// The BLAS behind CHOLMOD's supernodal factorization: its thread count and its kernels.
#include <string>

namespace seamvox {

/// Sets the number of BLAS threads when the BLAS in use offers it (OpenBLAS), unless the user
/// chose one with OPENBLAS_NUM_THREADS or OMP_NUM_THREADS. Returns false when it could not.
/// seamvox's own loops already run in parallel (TBB); a second pool of spinning BLAS threads
/// on the same cores made factorizations up to 2x slower on a loaded 2-core machine.
bool limitBlasThreads(int threads);

/// The kernels OpenBLAS chose for this processor (its core name, e.g. "Haswell"), or "" when
/// the BLAS is not OpenBLAS.
std::string blasCoreName();

/// The kernels to ask OpenBLAS for (through OPENBLAS_CORETYPE, read when it loads), or "" to
/// keep its choice. An OpenBLAS older than the processor (Debian 12's 0.3.21 on an Emerald
/// Rapids Xeon) falls back to its SSE3 "Prescott" kernels, about 1.4x slower in the complex
/// factorizations; this names the newest family of kernels the processor and the system
/// support instead: "SkylakeX" (AVX-512 F, BW, DQ, VL), "Haswell" (AVX2, FMA) or
/// "Sandybridge" (AVX). "" when OPENBLAS_CORETYPE is set, the BLAS is not OpenBLAS or its
/// choice is not one of the generic fallbacks.
std::string preferredBlasCore();

/// For a program's main, first thing: when preferredBlasCore() names kernels, sets
/// OPENBLAS_CORETYPE to them and runs the program again in this process (execv of
/// /proc/self/exe with argv), as OpenBLAS reads the setting only as it loads. Returns when there
/// is nothing to choose or the new run could not start (the program then goes on with
/// OpenBLAS's own choice).
void rerunWithPreferredBlas(char** argv);

}  // namespace seamvox
