/*
 * OpenBLAS's kernels: on processors it does not know, and the ones thorax's own work runs fastest with.
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
 *
 * Where OpenBLAS does know the processor, the kernels it picks are not always the fastest for thorax's
 * shapes: on this project's machines (AMD EPYC, Zen 4: family 25, model 17, whose AVX-512 OpenBLAS 0.3.21
 * takes for a Cooper Lake's) its AVX-512 kernels ("Cooperlake", "SkylakeX") run dgemm with a thread's 150
 * columns at 37 GF/s and the triangular solves at 29-33, where its AVX2 ones ("Haswell") run them at
 * 44-48, and the high phantom's 300 frames take 0.90 of the time with them
 * (docs/design/parallel.md, "The margin under 8 s"). So thx_blas_chosen_core measures, once per machine:
 * the program is run again as a probe (THORAX_BLAS_PROBE set: main's thx_startup_heavy calls
 * thx_blas_probe_run, which times a fixed workload of thorax's own shapes, one BLAS thread, twice, and
 * prints the shorter) with each core the processor can run (the one OpenBLAS chose, SkylakeX's,
 * Haswell's), in two rounds taken in turn, each core's shorter time kept; another core than OpenBLAS's is
 * taken only when it is at least 5 % faster. The answer is kept in the cache directory
 * (thorax/core/cache.h: blas-KEY.bin, KEY the SHA-256 of OpenBLAS's configuration, its core, and the
 * processor's name and features; the file says the core and each candidate's seconds), under a lock, so
 * that commands started together (mpirun's ranks) wait for one measure and all take the same kernels.
 * About 2 s, the first time only.
 */
#ifndef THORAX_CORE_BLAS_KERNELS_H
#define THORAX_CORE_BLAS_KERNELS_H

/* The core OpenBLAS would be given for this processor, or NULL when nothing is to
 * be done (see above); `loaded` is the core OpenBLAS chose, as it reports it. */
const char *thx_blas_better_core(const char *loaded);

/* The core OpenBLAS runs in this process, as it names it; NULL when the BLAS is not OpenBLAS. */
const char *thx_blas_loaded_core(void);

/* The core to give OpenBLAS for thorax's work, or NULL to keep `loaded` (the core it chose): for
 * "Prescott", thx_blas_better_core's; else the machine's kept choice, measured first when there is none
 * (argv: the program's own, run again for each probe). NULL too when no cache directory can be had. */
const char *thx_blas_chosen_core(const char *loaded, char **argv);

/* The probe's side: times the workload with the kernels OpenBLAS loaded, prints the seconds on standard
 * output; 0, or 1 when out of memory. */
int thx_blas_probe_run(void);

#endif
