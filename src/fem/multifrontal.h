/*
 * thorax's numeric supernodal Cholesky factorization (docs/design/parallel.md, "The factorization of
 * our own"): multifrontal, on a symbolic factor computed elsewhere (CHOLMOD's analysis, which gives the
 * supernodes, their rows and where their values go), with the elimination tree's independent subtrees
 * shared among threads that each call BLAS alone, and the separators at the top of the tree factored
 * after them with BLAS's own threads. Built into the solver module beside src/fem/cholesky.c.
 *
 * The values are laid out as CHOLMOD lays out a supernodal factor: supernode s holds columns
 * super[s] .. super[s + 1] - 1 of L; its rows are s_rows[pi[s] .. pi[s + 1] - 1] (ascending, the first
 * nscol of them its own columns); its values are an nsrow x nscol column-major block at Lx + px[s].
 */
#ifndef THORAX_FEM_MULTIFRONTAL_H
#define THORAX_FEM_MULTIFRONTAL_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"
#include "thorax/core/pages.h"

typedef struct {
    int64_t n;             /* the matrix's order */
    int64_t nsuper;        /* supernodes */
    const int64_t *super;  /* nsuper + 1: each supernode's first column */
    const int64_t *pi;     /* nsuper + 1: where its rows start in rows */
    const int64_t *px;     /* nsuper + 1: where its values start in Lx */
    const int64_t *rows;   /* the supernodes' row indices */
} thx_mf_symbolic;

typedef struct {
    int threads;           /* threads used for the subtrees */
    size_t subtrees;       /* independent subtrees shared among them */
    size_t top;            /* supernodes above them, factored one after the other with BLAS's threads */
    double top_share;      /* the top's share of the flops */
    double flops;          /* the flops done, explicit zeros of amalgamated supernodes included */
    double top_flops;      /* the top's share of them */
    double t_subtrees;     /* seconds: the subtrees, then the top */
    double t_top;
    int beside;            /* 1: the top was factored beside the first solve's start (thx_chol_factor_top) */
    size_t stack_bytes;    /* the update matrices' space, all threads */
    int64_t not_posdef;    /* -1, or the first column (the factor's order) with a zero or negative pivot */
} thx_mf_info;

/* Factors P A P^T = L L^T into Lx (px[nsuper] values, written here). A is the symmetric matrix of order
 * S->n given as a full CSR (both triangles) in its own numbering; row i of P A P^T is row perm[i] of A,
 * iperm the inverse. threads: how many threads share the subtrees (each calling BLAS with one thread
 * through set_blas_threads, when it is given); the top is factored with set_blas_threads(top_threads).
 * The subtrees' threads never wait for one another until the last subtree is done, so on a loaded
 * machine they may be more than the free cores; BLAS's threads meet at every call, and should not.
 * A matrix that is not positive definite returns THX_ESOLVER with info->not_posdef set and no
 * message (the caller names the row); a symbolic factor that does not hold the matrix's pattern (a row of
 * A, or of a child's update matrix, missing from a supernode) is THX_EINTERNAL, found as the fronts are
 * assembled, before any value lands in a wrong place. Lx must hold zeros (thx_pages_zeroed, thorax/core/pages.h:
 * its pages present already): the fronts' columns are assembled into it as they are. */
thx_status thx_mf_factor(thx_ctx *ctx, const thx_mf_symbolic *S, const int64_t *rowp, const int32_t *col,
                         const double *val, const int64_t *perm, const int64_t *iperm, int threads, int top_threads,
                         void (*set_blas_threads)(int), double *Lx, thx_mf_info *info);

/* The same in two steps, so that other work may run beside the top: thx_mf_begin factors the subtrees (and
 * checks the top's fronts' structure, so that the second step can fail on a pivot alone) and returns the
 * state in *out (NULL on failure); thx_mf_top factors the supernodes above them, one after the other, BLAS
 * with top_threads. Until then the top's columns of Lx are not the factor's (thx_mf_top_mask: the top's
 * supernodes, 1 each; NULL once done); the others' are. info: filled by each step. */
typedef struct thx_mf thx_mf;
thx_status thx_mf_begin(thx_ctx *ctx, const thx_mf_symbolic *S, const int64_t *rowp, const int32_t *col,
                        const double *val, const int64_t *perm, const int64_t *iperm, int threads,
                        void (*set_blas_threads)(int), double *Lx, thx_mf **out, thx_mf_info *info);
thx_status thx_mf_top(thx_mf *m, int top_threads, void (*set_blas_threads)(int), thx_mf_info *info);
const unsigned char *thx_mf_top_mask(const thx_mf *m);
/* The working memory no longer needed, given to the caller (its pages present; contents undefined): the
 * threads' stacks once thx_mf_begin has returned, the roots' and the top's arena once thx_mf_top has. The
 * larger first; out->p NULL when none is left. Not thread-safe (the caller serializes). */
void thx_mf_take_spare(thx_mf *m, thx_pages *out);
void thx_mf_free(thx_mf **m);

#endif
