/*
 * thorax/core/startup.h — the environment a heavy command starts in.
 *
 * Two settings are read only when the process starts, so a program that wants them must have
 * them in its environment before main() runs; thx_startup_heavy sets them and executes the
 * program again, at most once (the guard variable THORAX_BLAS_REEXEC), when either is missing:
 *  - OpenBLAS's kernels on processors it does not know (thorax/core/blas_kernels.h): when OpenBLAS
 *    is the BLAS, names "Prescott", the user has not set OPENBLAS_CORETYPE, and the processor has
 *    a better kernel set, OPENBLAS_CORETYPE is set to it;
 *  - transparent huge pages for the large blocks glibc's malloc hands out: when the kernel gives
 *    them on request (/sys/kernel/mm/transparent_hugepage/enabled is [always] or [madvise]) and
 *    GLIBC_TUNABLES does not already say glibc.malloc.hugetlb, glibc.malloc.hugetlb=1 is added to
 *    GLIBC_TUNABLES. A page fault costs the same for 2 MiB as for 4 KiB; on virtual machines each
 *    costs several microseconds. The forward problem at the high resolution touches 1.7 GB of fresh
 *    memory (the factor alone 0.8 GB): 426,000 faults and 14.7 s became 15,000 and 11.7 s
 *    (docs/design/parallel.md).
 * Nothing is done under valgrind (its child would run outside it), nor when the new execution
 * fails (the program goes on as it is). A user's own setting of either variable is kept.
 */
#ifndef THORAX_CORE_STARTUP_H
#define THORAX_CORE_STARTUP_H

/* Call first in main(), before any thread is started; argv as main received it. */
void thx_startup_heavy(char **argv);

#endif
