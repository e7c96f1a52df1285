#pragma once
/// The BLAS and OpenMP behind CHOLMOD's supernodal factorization: their thread counts and the
/// BLAS kernels.
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

/// The OpenMP thread limit to ask for (through OMP_THREAD_LIMIT, read as libgomp loads): "1",
/// or "" when the user set OMP_THREAD_LIMIT or OMP_NUM_THREADS. Debian's CHOLMOD opens a team of
/// 4 OpenMP threads for each large supernode of a supernodal factorization, whatever
/// OMP_NUM_THREADS says. seamvox factors several repair regions at once on its own (TBB)
/// threads, each then starting and waking teams on the same cores (futex calls and spinning, not
/// work). The results do not change.
std::string preferredOpenMPLimit();

/// Whether the program runs OpenMP parallel regions inline under a thread limit of 1 (the seamvox
/// command does, tools/openmp_regions.cpp: libgomp's team per region cost more than CHOLMOD's
/// small supernode updates); what reports say. false unless the program sets it.
void setOpenMPRegionsInline(bool inlined);
bool openmpRegionsInline();

/// For a program's main, first thing: when preferredBlasCore() names kernels or
/// preferredOpenMPLimit() a limit, sets OPENBLAS_CORETYPE and OMP_THREAD_LIMIT to them and runs
/// the program again in this process (execv of /proc/self/exe with argv), as both libraries
/// read their settings only as they load. Returns when there is nothing to set or the new run
/// could not start (the program then goes on with the libraries' own choices).
void rerunWithPreferredRuntime(char** argv);

}  // namespace seamvox
