/*
 * thorax's own direct path for many right-hand sides on one rank (docs/design/parallel.md, "The
 * forward problem at the high resolution in seconds"): CHOLMOD's supernodal analysis of the free-node
 * system, with its fill-reducing ordering (METIS nested dissection) kept in the user's cache keyed
 * by the matrix's graph; the numeric factorization ours (src/fem/multifrontal.h: subtrees of the
 * elimination tree in parallel), or CHOLMOD's on request; and triangular solves of our own on
 * row-major blocks (a supernode's rows of every right-hand side contiguous), one block of columns per
 * thread. Built into the solver module beside src/fem/solver.c, which decides when to take this path.
 */
#ifndef THORAX_FEM_CHOLESKY_H
#define THORAX_FEM_CHOLESKY_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"
#include "fem/multifrontal.h"

typedef struct thx_chol thx_chol;

typedef struct {
    double t_order;     /* the ordering: computed (METIS) or read from the cache */
    double t_analyze;   /* CHOLMOD's symbolic analysis with that ordering */
    double t_factor;    /* the numeric factorization */
    double flops;       /* CHOLMOD's count for the factorization */
    double lnz;         /* nonzeros in L (CHOLMOD's count) */
    size_t factor_bytes;/* the factor's values and row indices */
    size_t n_super;     /* supernodes */
    int ordering_cached;/* 1: the ordering came from the cache */
    int symbolic_cached;/* 1: the symbolic factor came from the cache (no analysis ran) */
    int not_posdef;     /* 1: refused as not positive definite (a zero or negative pivot) */
    char cache_note[160];/* why the cache was not used or not written (empty when it was) */
    int blas_threads;   /* OpenBLAS's threads in the factorization (set by the caller; 0: not OpenBLAS) */
    int64_t bad_column; /* with not_posdef: the column (the factor's order) */
    const char *numeric;/* who computed the factor's values */
    thx_mf_info mf;     /* ours: threads, subtrees, the top's share, times */
} thx_chol_info;

typedef struct {
    int threads;                    /* threads for our factorization's subtrees */
    int top_threads;                /* BLAS's threads (ours: for the supernodes above the subtrees; CHOLMOD's: all) */
    void (*set_blas_threads)(int);  /* sets BLAS's threads, or NULL */
    int cholmod_numeric;            /* 1: CHOLMOD's numeric factorization instead of ours (-thorax_factor cholmod) */
    int defer_top;                  /* 1 (ours, threads > 1): the top left to thx_chol_factor_top, beside a solve */
} thx_chol_opts;

/* Factors the symmetric positive definite matrix of order n given as a full CSR (both triangles,
 * sorted columns). The ordering is looked up in the cache (thx_cache_dir, thorax/core/cache.h) by the SHA-256 of
 * (n, rowp, col); when missing it is computed and stored there. A matrix that is not positive
 * definite is THX_ESOLVER naming the column. */
thx_status thx_chol_factor(thx_ctx *ctx, int64_t n, const int64_t *rowp, const int32_t *col, const double *val,
                           const thx_chol_opts *opts, thx_chol **out, thx_chol_info *info);
void thx_chol_free(thx_chol **f);

/* With opts->defer_top, the supernodes above the subtrees (the top: the largest separators) are left out of
 * thx_chol_factor: thx_chol_top_left gives them (nsuper bytes, 1 each; NULL when nothing is left), and
 * thx_chol_factor_top factors them with one BLAS thread, while other threads may run the forward sweep below
 * them (thx_chol_solve_rows_part, part 1), which reads no column of the top. A pivot failing there is
 * THX_ESOLVER naming the row, as thx_chol_factor's. thx_chol_top_release frees what the top needed (the mask
 * included) once no thread reads the mask; thx_chol_free does it too. */
const unsigned char *thx_chol_top_left(const thx_chol *f);
thx_status thx_chol_factor_top(thx_ctx *ctx, thx_chol *f, void (*set_blas_threads)(int), thx_chol_info *info);
void thx_chol_top_release(thx_chol *f);

/* The factor's order: row i of the permuted system is row perm[i] of the matrix; iperm its inverse. */
const int64_t *thx_chol_perm(const thx_chol *f);
const int64_t *thx_chol_iperm(const thx_chol *f);

/* Bytes of work space one thread needs to solve r right-hand sides at once (beyond X itself). */
size_t thx_chol_work_bytes(const thx_chol *f, size_t r);
/* Solves A X = B in place for r right-hand sides held row-major in the factor's order: row i of X
 * (r values, contiguous) is row perm[i] of the system. work: thx_chol_work_bytes(f, r) bytes. Calls
 * BLAS from the calling thread alone; safe to run from several threads on the same factor. Supernodes
 * whose rows of B are all zero are skipped in the forward sweep (exactly: they would stay zero).
 * Returns the flops done (the triangular blocks' r nscol^2 and the rectangles' 2 r nscol nb, both
 * sweeps). */
double thx_chol_solve_rows(const thx_chol *f, double *X, size_t r, double *work);
/* The same with the backward sweep kept to the supernodes marked in need (nsuper bytes; NULL: all):
 * the rows of the other supernodes are left as the forward sweep made them. need from
 * thx_chol_needed: a row's answer depends on its supernode and that supernode's ancestors alone, so
 * the rows asked for come out the same to the bit as with every supernode. reach (NULL: every
 * supernode may hold a nonzero): thx_chol_needed of the rows where B may be nonzero, the supernodes
 * the forward sweep can reach; the others are skipped without reading their rows (they are zero), so
 * pages of X no sweep writes are never touched. */
double thx_chol_solve_rows_needed(const thx_chol *f, double *X, size_t r, double *work, const unsigned char *need,
                                  const unsigned char *reach);
/* The same on r + q columns (X row-major, ld r + q), the last q solved in full whatever need says and
 * returned in Z (n x q, ld q, the factor's order): the check's combinations of a block (src/fem/solver_own.c),
 * solved in the same BLAS calls as the block wherever the block itself is (the factor read once), alone on
 * the supernodes the block's backward sweep skips (their rows then in Z). X's last q columns are left as
 * the block's are: right on the supernodes in need. work: thx_chol_work_bytes(f, r + q). Returns the flops. */
double thx_chol_solve_rows_with(const thx_chol *f, double *X, size_t r, size_t q, double *Z, double *work,
                                const unsigned char *need, const unsigned char *reach);
/* thx_chol_solve_rows_with in two parts: part 1 the forward sweep on the supernodes not in top (nsuper bytes,
 * thx_chol_top_left's), part 2 the rest (the forward sweep on top's, then the backward sweep); part 0 both,
 * as thx_chol_solve_rows_with (top unused). Part 1 reads none of top's columns of the factor. The same answers
 * as part 0 but for the order in which the top's rows receive their updates (rounding). */
double thx_chol_solve_rows_part(const thx_chol *f, double *X, size_t r, size_t q, double *Z, double *work,
                                const unsigned char *need, const unsigned char *reach, const unsigned char *top, int part);
/* The factor's supernodes (thx_chol_nsuper of them) into need: 1 for those holding one of the m factor
 * rows given (in the factor's order) and their ancestors, else 0. Returns the share of the backward
 * sweep's flops they hold (0 .. 1). */
size_t thx_chol_nsuper(const thx_chol *f);
/* The flops of one column's sweeps: forward on the supernodes in reach, backward on those in need (NULL: all). */
double thx_chol_sweep_flops(const thx_chol *f, const unsigned char *reach, const unsigned char *need);
/* The factorization's working memory, once no longer needed, for the caller's own use (thorax/core/pages.h;
 * its pages present, its contents undefined): the larger block left, or out->p NULL. Thread-safe. What is
 * not taken stays until thx_chol_drop_spare or the factor's end. */
void thx_chol_take_spare(thx_chol *f, thx_pages *out);
void thx_chol_drop_spare(thx_chol *f);
/* The rows of X (r columns, as thx_chol_solve_rows_needed takes it) of the supernodes marked in need or
 * reach, the only rows the sweeps read or write, made zero: those before fresh by writing zeros, those
 * from fresh on (zeros already, their pages not yet touched: fresh from calloc or thx_pages_grow) by making
 * their pages present for writing (thorax/core/pages.h). X's other pages are never touched. A fresh page
 * written first costs one fault, where one read first (the sweeps' updates read before they write) costs
 * two and a TLB shootdown, and asked for a run of rows at once none (nor a pass of zeros). */
void thx_chol_prepare_rows(const thx_chol *f, double *X, size_t r, const unsigned char *need, const unsigned char *reach,
                           const double *fresh);
double thx_chol_needed(const thx_chol *f, const int64_t *rows, size_t m, unsigned char *need);


#endif
