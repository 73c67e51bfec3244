/*
 * MPI's table in the solver module (thorax/core/module.h): the few calls sort-first rendering needs
 * (thorax/parallel/parallel.h), made by src/parallel/mpi_module.c inside libthorax-petsc.so, which
 * links MPI; the library reaches them through thx_par_mpi_get. Every function returns 0 on success,
 * else MPI's error code.
 */
#ifndef THORAX_PARALLEL_MPI_MODULE_H
#define THORAX_PARALLEL_MPI_MODULE_H

#include <stddef.h>

#define THX_PAR_MPI_ABI 1

typedef struct {
    int abi; /* THX_PAR_MPI_ABI */
    /* MPI_Init_thread (MPI_THREAD_FUNNELED) unless MPI is running already; this rank and the size of
       MPI_COMM_WORLD. *started: 1 when this call started MPI (finalize ends it then). */
    int (*init)(int *rank, int *size, int *started);
    /* MPI_Finalize, unless MPI has ended already (PETSc's finalize may have ended it). */
    void (*finalize)(void);
    int (*barrier)(void);
    int (*bcast)(void *buf, size_t n, int root);
    int (*max_int)(int *v, int n);          /* in place, over MPI_COMM_WORLD */
    int (*min_int)(int *v, int n);
    int (*sum_ll)(long long *v, int n);
    /* every rank's n into counts[size] on root (counts may be NULL elsewhere) */
    int (*gather_size)(size_t n, size_t *counts, int root);
    /* every rank's n bytes of send into recv on root, rank after rank (counts from gather_size) */
    int (*gatherv)(const void *send, size_t n, void *recv, const size_t *counts, int root);
    /* MPI's message for an error code, into buf */
    void (*error_string)(int code, char *buf, size_t size);
} thx_par_mpi;

const thx_par_mpi *thx_par_mpi_get(void);

#endif
