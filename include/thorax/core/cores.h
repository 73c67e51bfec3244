/*
 * thorax/core/cores.h — how many of this process's cores are free now, for a library that would
 * start threads which must meet (OpenBLAS inside CHOLMOD's factorization).
 *
 * Threads that meet at every call of a parallel BLAS wait for the slowest; on a shared machine,
 * where another process holds a core, the thread on that core runs a slice at a time and its
 * partner spins. Measured (docs/design/parallel.md, "CHOLMOD's BLAS threads under load"): the high
 * phantom's factorization 27 s with two OpenBLAS threads at load 3.5 against 6 s with one; the
 * Utah tank's 2.2 s against 0.5 s.
 */
#ifndef THORAX_CORE_CORES_H
#define THORAX_CORE_CORES_H

/* The cores this process may run on (its affinity) minus the tasks of other processes running or
 * waiting to run now (Linux: /proc/loadavg's runnable count less this process's own runnable
 * threads, the median of a few looks over a few milliseconds), at least 1. Without /proc: the
 * affinity's count. */
int thx_cores_free(void);

/* The cores this process may run on (its affinity), at least 1. */
int thx_cores_allowed(void);

#endif
