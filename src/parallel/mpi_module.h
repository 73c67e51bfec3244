/*
 * MPI's table in the solver module (thorax/core/module.h): the few calls sort-first rendering needs
 * (thorax/parallel/parallel.h), made by src/parallel/mpi_module.c inside libthorax-petsc.so, which
 * links MPI; the library reaches them through thx_par_mpi_get. Every function returns 0 on success,
 * else MPI's error code.
 */
#ifndef THORAX_PARALLEL_MPI_MODULE_H
#define THORAX_PARALLEL_MPI_MODULE_H

#include <stddef.h>

#define THX_PAR_MPI_ABI 2

/* thx_par_mpi.composite's modes */
#define THX_PAR_COMPOSITE_DEPTH 0 /* the nearer fragment (depth), RGBA bytes */
#define THX_PAR_COMPOSITE_BLEND 1 /* premultiplied RGBA floats blended over in an order */

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
    int (*max_dbl)(double *v, int n);
    /* every rank's n into counts[size] on root (counts may be NULL elsewhere) */
    int (*gather_size)(size_t n, size_t *counts, int root);
    /* every rank's n bytes of send into recv on root, rank after rank (counts from gather_size) */
    int (*gatherv)(const void *send, size_t n, void *recv, const size_t *counts, int root);
    /* MPI's message for an error code, into buf */
    void (*error_string)(int code, char *buf, size_t size);
    /* Sort-last compositing by IceT (src/parallel/icet_module.c), collective: every rank's w x h
       image (rows from the bottom or the top, as long as every rank's are alike) into rank 0's.
       DEPTH: color RGBA bytes, depth floats in [0, 1] (1: nothing drawn); rank 0's color ends with
       the nearest fragment of every pixel, and its depth with that fragment's depth. BLEND: color
       premultiplied RGBA floats, depth NULL; order[size] the ranks front to back; rank 0's color
       ends with every rank's blended over the ones behind it. A pixel no rank drew ends transparent
       (alpha 0; depth 1). color NULL: IceT made ready alone (loaded, its context made), so that the
       ranks can agree it is before they composite. 0, or -1 with the reason in why (IceT not built
       in or not loadable, IceT's error). */
    int (*composite)(int mode, int w, int h, void *color, float *depth, const int *order, char *why, size_t why_size);
} thx_par_mpi;

const thx_par_mpi *thx_par_mpi_get(void);

#endif
