/*
 * OpenBLAS's kernels on processors it does not know.
 *
 * Debian 12's OpenBLAS (0.3.21, built for every x86-64 processor and choosing at
 * start-up) does not recognise recent Intel Xeons (family 6, model 207 among
 * them) and falls back to its SSE3 "Prescott" kernels: dgemm at 11-17 GF/s on a
 * core that does 50-65 with the AVX-512 ("SkylakeX") ones. The choice is made
 * when the library is loaded, from the environment variable OPENBLAS_CORETYPE,
 * so a program that wants the right kernels must have it set before it starts.
 *
 * thx_startup_heavy (thorax/core/startup.h) does that for a program's main(): when OpenBLAS is the
 * BLAS in the process, says "Prescott", OPENBLAS_CORETYPE is not set, and the
 * processor (and the operating system) support AVX-512 (F, CD, BW, DQ, VL:
 * SkylakeX's kernels) or AVX2 and FMA (Haswell's), it sets OPENBLAS_CORETYPE and
 * executes the program again with the same arguments. It returns (doing
 * nothing) in every other case, and when the new execution fails. Not under
 * valgrind, whose child would run outside it. A user's OPENBLAS_CORETYPE is
 * never changed; setting it (to any core) turns this off.
 */
#ifndef THORAX_CORE_BLAS_KERNELS_H
#define THORAX_CORE_BLAS_KERNELS_H

/* The core OpenBLAS would be given for this processor, or NULL when nothing is to
 * be done (see above); `loaded` is the core OpenBLAS chose, as it reports it. */
const char *thx_blas_better_core(const char *loaded);


#endif
