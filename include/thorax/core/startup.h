/*
 * thorax/core/startup.h — the environment a heavy command starts in.
 *
 * OpenBLAS reads its kernel choice only when the process starts, so a program that wants it must
 * have it in its environment before main() runs: when OpenBLAS is the BLAS, names "Prescott" (its SSE3
 * fallback), the user has not set OPENBLAS_CORETYPE, and the processor has a better kernel set
 * (thorax/core/blas_kernels.h), thx_startup_heavy sets OPENBLAS_CORETYPE to it and executes the
 * program again, at most once (the guard variable THORAX_BLAS_REEXEC).
 * (It once also asked glibc for transparent huge pages on malloc's large blocks; on this class of
 * virtual machine a fresh huge page costs more to fault in than its 512 small pages, and the forward
 * problem ran 0.80 times as long without them: docs/design/parallel.md, "Huge pages, measured again".)
 * GNU OpenMP reads how long a thread waiting at a barrier spins before it sleeps (GOMP_SPINCOUNT, by
 * default 300,000 turns) the same way. Beside other busy processes a spinning thread burns the share of
 * the core its partner needs, so unless the user set GOMP_SPINCOUNT or OMP_WAIT_POLICY it is set to
 * THX_STARTUP_SPINCOUNT, in the same new execution: the high phantom's 300 frames beside three busy
 * loops 0.98 of the time and 0.977 of the CPU, quiet the same time and 0.985 of the CPU (paired,
 * docs/design/parallel.md, "Load 5 at the edge of 8 s").
 * Nothing is done under valgrind (its child would run outside it), nor when the new execution
 * fails (the program goes on as it is). A user's own OPENBLAS_CORETYPE is kept.
 */
#ifndef THORAX_CORE_STARTUP_H
#define THORAX_CORE_STARTUP_H

#define THX_STARTUP_SPINCOUNT "10000"

/* Call first in main(), before any thread is started; argv as main received it. */
void thx_startup_heavy(char **argv);

#endif
