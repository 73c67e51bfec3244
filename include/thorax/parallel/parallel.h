/*
 * thorax/parallel/parallel.h — the ranks of a run under mpirun, for the commands that share their
 * work among processes without PETSc (render, trace, animate: sort-first and sort-last rendering;
 * field: the cuts of a solution in parts; paper 4.3).
 *
 * The library never links MPI. A run started by a launcher with more than one rank (Open MPI's
 * OMPI_COMM_WORLD_SIZE, or PMI_SIZE / PMIX_SIZE of the others) starts MPI through the solver module
 * (thorax/core/module.h), which holds the MPI calls; a single process never loads it, and every
 * call below is then a no-op on rank 0 of 1.
 *
 * Every call marked "collective" must be made by every rank, in the same order; a rank that has
 * failed still makes them (thx_par_agree lets the ranks learn of one another's failures before the
 * next collective, so that no rank waits for one that has given up).
 */
#ifndef THORAX_PARALLEL_H
#define THORAX_PARALLEL_H

#include <stddef.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The ranks the launcher started (its environment), 1 when none; 0 when the launcher's count is
 * not a positive number (the caller refuses to run: two processes might write the same file). */
int thx_par_launched(void);

/* This process's rank as the launcher numbered it (OMPI_COMM_WORLD_RANK, PMI_RANK or PMIX_RANK), 0
 * when none is set: who speaks for a run that will not start MPI. */
int thx_par_launched_rank(void);

/* Starts MPI when the launcher started more than one rank (collective), else nothing: *rank and
 * *size (either may be NULL) are this process's. Fails with THX_ESOLVER when MPI is needed but the
 * solver module (MPI) cannot be loaded or started. Called once, before any other call below. */
thx_status thx_par_start(thx_ctx *ctx, int *rank, int *size);

/* This process's rank and the number of ranks (0 and 1 before thx_par_start, or without MPI). */
int thx_par_rank(void);
int thx_par_size(void);

/* Ends MPI if thx_par_start started it (collective). */
void thx_par_end(void);

/* Collective: every rank's st. Returns st on a rank that failed; on the others THX_OK when every
 * rank succeeded, else the first failed rank's status with a message naming that rank in ctx.
 * *failed_rank (when not NULL): the lowest failed rank, or -1. */
thx_status thx_par_agree(thx_ctx *ctx, thx_status st, int *failed_rank);

/* The lowest rank that had failed when an agreement (thx_par_agree, and the calls made of it) first
 * met a failure: the rank whose own message tells what went wrong, where later agreements see every
 * rank failed (the others carrying "rank K failed" on). -1 when no agreement has met a failure. */
int thx_par_failed_first(void);

/* Collective: n bytes of buf from rank root to every rank. */
thx_status thx_par_bcast(thx_ctx *ctx, void *buf, size_t n, int root);

/* Collective: v[0..n) summed over the ranks, on every rank. */
thx_status thx_par_sum(thx_ctx *ctx, long long *v, int n);

/* Collective: every rank's st agreed as thx_par_agree does, and, when every rank succeeded, v[0..n)
 * replaced by its largest over the ranks (a least as the largest of -v; NaN on a rank is lost to
 * any number). On failure v is left as it was. At most 64 values. */
thx_status thx_par_max(thx_ctx *ctx, thx_status st, double *v, int n);

/* Collective: every rank's st agreed as thx_par_agree does, then, when every rank succeeded, every
 * rank's n bytes of send into *all on rank 0, rank after rank, with (*counts)[r] the bytes of rank r
 * (*all and *counts the caller's to free on rank 0; NULL elsewhere, and on failure). With one rank,
 * *all is a copy of send. */
thx_status thx_par_gather(thx_ctx *ctx, thx_status st, const void *send, size_t n, void **all, size_t **counts);

/* Collective: waits for every rank. */
thx_status thx_par_barrier(thx_ctx *ctx);

/* Collective, sort-first's gather: every rank's pixels of a w x h RGBA image (rgba, 4 bytes a pixel)
 * where its own[] (a byte a pixel) is not 0, into rank 0's rgba; rank 0 keeps its own pixels and
 * those no rank owns. On rank 0, a pixel owned by two ranks, or a run outside the image, is refused
 * (THX_EINTERNAL: the ranks disagreed on the picture's shares). own is left as it was on every
 * rank but 0, where it ends with every gathered pixel marked. */
thx_status thx_par_gather_pixels(thx_ctx *ctx, unsigned char *rgba, unsigned char *own, int w, int h);

/* Collective, sort-last's compositing (IceT, through the solver module): every rank's w x h layer
 * (rows in any order alike on every rank) into rank 0's. Depth: rgba bytes and depth floats in
 * [0, 1] (1: nothing drawn there); rank 0's rgba and depth end with the nearest fragment of each
 * pixel over all ranks (a pixel no rank drew: rgba 0, depth 1). Blend: premultiplied RGBA floats;
 * order[thx_par_size()] the ranks front to back; rank 0's rgba ends with the ranks' layers blended
 * "over" in that order (a pixel no rank drew: 0). With one rank, nothing is done. THX_ESOLVER when
 * this thorax was built without IceT or its library cannot be loaded (the message names the package),
 * or when IceT fails. */
thx_status thx_par_composite_depth(thx_ctx *ctx, unsigned char *rgba, float *depth, int w, int h);
thx_status thx_par_composite_blend(thx_ctx *ctx, float *rgba, int w, int h, const int *order);

#ifdef __cplusplus
}
#endif
#endif
