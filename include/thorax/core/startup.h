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
 * Nothing is done under valgrind (its child would run outside it), nor when the new execution
 * fails (the program goes on as it is). A user's own OPENBLAS_CORETYPE is kept.
 */
#ifndef THORAX_CORE_STARTUP_H
#define THORAX_CORE_STARTUP_H

/* Call first in main(), before any thread is started; argv as main received it. */
void thx_startup_heavy(char **argv);

#endif
