/*
 * thorax's own direct path (src/fem/cholesky.h): the ordering and CHOLMOD's supernodal analysis (both
 * kept in the cache, src/fem/chol_cache.h), our numeric factorization (or CHOLMOD's), and blocked
 * triangular solves on row-major right-hand sides.
 */
#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <suitesparse/cholmod.h>

#include "fem/chol_cache.h"
#include "thorax/core/cache.h"
#include "thorax/core/pages.h"
#include "fem/cholesky.h"
#include "fem/multifrontal.h"

/* BLAS, Fortran calling convention (OpenBLAS behind libblas.so.3) */
void dtrsm_(const char *side, const char *uplo, const char *transa, const char *diag, const int *m, const int *n,
            const double *alpha, const double *a, const int *lda, double *b, const int *ldb);
void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha,
            const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c,
            const int *ldc);

struct thx_chol {
    cholmod_common c;
    cholmod_factor *L;     /* CHOLMOD's factor: with its numeric factorization alone */
    thx_chol_symbolic y;   /* the symbolic factor (the cache's, or a copy of CHOLMOD's analysis) */
    double *Lx;            /* the factor's values: our own (multifrontal.h), or CHOLMOD's L->x */
    thx_pages own;         /* ours, when we computed them: zeros made present at once (thorax/core/pages.h) */
    int64_t n;
    int64_t *perm, *iperm;
    size_t max_below;      /* the most rows below a supernode's diagonal block */
    thx_mf_symbolic S;     /* ours: the symbolic factor as the multifrontal code takes it */
    thx_mf *mf;            /* ours with the top still to factor (thx_chol_factor_top), or NULL */
    thx_pages spare[2];    /* the factorization's working memory once mf is gone (thx_chol_take_spare) */
    pthread_mutex_t lock;  /* over mf's and spare's hand-outs */
};

/* mf's spare blocks into f->spare (mf about to be freed) */
static void keep_spare(thx_chol *f)
{
    for (int i = 0; i < 2 && f->mf; i++)
        if (!f->spare[i].p) thx_mf_take_spare(f->mf, &f->spare[i]);
}

void thx_chol_take_spare(thx_chol *f, thx_pages *out)
{
    pthread_mutex_lock(&f->lock);
    out->p = NULL;
    out->bytes = 0;
    if (f->mf) thx_mf_take_spare(f->mf, out);
    int k = f->spare[0].bytes >= f->spare[1].bytes ? 0 : 1;
    if (!out->p && f->spare[k].p) {
        *out = f->spare[k];
        f->spare[k] = (thx_pages){NULL, 0};
    }
    pthread_mutex_unlock(&f->lock);
}

void thx_chol_drop_spare(thx_chol *f)
{
    pthread_mutex_lock(&f->lock);
    thx_pages pg;
    while (f->mf && (thx_mf_take_spare(f->mf, &pg), pg.p)) thx_pages_free(&pg);
    thx_pages_free(&f->spare[0]);
    thx_pages_free(&f->spare[1]);
    pthread_mutex_unlock(&f->lock);
}

void thx_chol_free(thx_chol **fp)
{
    if (!fp || !*fp) return;
    thx_chol *f = *fp;
    thx_mf_free(&f->mf);
    thx_pages_free(&f->spare[0]);
    thx_pages_free(&f->spare[1]);
    pthread_mutex_destroy(&f->lock);
    if (f->L) cholmod_l_free_factor(&f->L, &f->c);
    cholmod_l_finish(&f->c);
    thx_chol_symbolic_free(&f->y);
    thx_pages_free(&f->own);
    free(f->perm);
    free(f->iperm);
    free(f);
    *fp = NULL;
}

_Static_assert(sizeof(SuiteSparse_long) == sizeof(int64_t), "CHOLMOD's long integers are 64 bits");

/* CHOLMOD's upper triangle of the CSR's matrix (CSR row i is column i of the symmetric matrix), or NULL. */
static cholmod_sparse *upper(thx_chol *f, int64_t n, const int64_t *rowp, const int32_t *col, const double *val)
{
    size_t nz = 0;
    for (int64_t i = 0; i < n; i++)
        for (int64_t k = rowp[i]; k < rowp[i + 1]; k++) nz += col[k] <= i;
    cholmod_sparse *A = cholmod_l_allocate_sparse((size_t)n, (size_t)n, nz, 1, 1, 1, CHOLMOD_REAL, &f->c);
    if (!A) return NULL;
    SuiteSparse_long *Ap = A->p, *Ai = A->i;
    double *Ax = A->x;
    size_t w = 0;
    for (int64_t i = 0; i < n; i++) {
        Ap[i] = (SuiteSparse_long)w;
        for (int64_t k = rowp[i]; k < rowp[i + 1]; k++)
            if (col[k] <= i) { Ai[w] = col[k]; Ax[w] = val[k]; w++; }
    }
    Ap[n] = (SuiteSparse_long)w;
    return A;
}

/* A factorization refused at column bad (the factor's order). */
static thx_status not_posdef(thx_ctx *ctx, const thx_chol *f, int64_t bad)
{
    const int64_t n = f->n;
    return thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization failed: zero or negative "
                     "pivot at row %lld of %lld: the matrix is singular, e.g. currents into a part of the mesh with no "
                     "prescribed potential)", (long long)(bad >= 0 && bad < n ? f->perm[bad] + 1 : bad + 1), (long long)n);
}

thx_status thx_chol_factor(thx_ctx *ctx, int64_t n, const int64_t *rowp, const int32_t *col, const double *val,
                           const thx_chol_opts *opts, thx_chol **out, thx_chol_info *info)
{
    *out = NULL;
    thx_chol_info inf;
    memset(&inf, 0, sizeof inf);
    thx_status st = THX_OK;
    cholmod_sparse *A = NULL;
    int64_t *order = NULL;
    const int cholmod_numeric = opts && opts->cholmod_numeric;
    thx_chol *f = thx_calloc(ctx, 1, sizeof *f);
    if (!f) return THX_ENOMEM;
    pthread_mutex_init(&f->lock, NULL);
    cholmod_l_start(&f->c);
    f->c.print = 0;
    f->c.error_handler = NULL;
    f->c.supernodal = CHOLMOD_SUPERNODAL;
    /* CHOLMOD's own relaxed amalgamation (4, 16, 48 columns). With CHOLMOD's numeric factorization the
       coarser 16/64/192 ran faster (3.0 s against 4.8 s); with ours the default is as fast and its factor
       smaller: 695 against 801 MB for the high phantom, 0.96 of the time in paired runs
       (docs/design/parallel.md, "The factorization of our own") */
    f->n = n;
    f->perm = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *f->perm);
    f->iperm = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *f->iperm);
    order = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *order);
    if (!f->perm || !f->iperm || !order) { st = THX_ENOMEM; goto done; }
    /* the ordering: the cache, else METIS (stored for the next run) */
    double t0 = thx_wtime();
    unsigned char key[32], skey[32];
    thx_chol_graph_key(n, rowp, col, key);
    char dir[4096];
    const char *cd = thx_cache_dir(dir, sizeof dir);
    inf.ordering_cached = cd && thx_chol_order_cached(cd, n, key, order);
    if (!inf.ordering_cached) {
        if (!(A = upper(f, n, rowp, col, val))) { st = THX_ENOMEM; goto done; }
        if (!cholmod_l_metis(A, NULL, 0, 0, (SuiteSparse_long *)order, &f->c) || f->c.status < 0) {
            st = thx_error(ctx, f->c.status == CHOLMOD_OUT_OF_MEMORY ? THX_ENOMEM : THX_ESOLVER,
                           "fem: the fill-reducing ordering (METIS through CHOLMOD) failed (CHOLMOD status %d)", f->c.status);
            goto done;
        }
        if (cd) thx_chol_order_keep(cd, n, key, order, inf.cache_note, sizeof inf.cache_note);
        else snprintf(inf.cache_note, sizeof inf.cache_note, "no cache directory (HOME, XDG_CACHE_HOME and THORAX_CACHE_DIR unset)");
    }
    inf.t_order = thx_wtime() - t0;
    /* the symbolic analysis with exactly that ordering, postordered: the cache's (our factorization needs
       nothing more), else CHOLMOD's (the same for a cached and a fresh ordering), kept for the next run */
    t0 = thx_wtime();
    thx_chol_symbolic_key(key, n, order, skey);
    int use_cache = !cholmod_numeric && cd;
analyse:
    inf.symbolic_cached = use_cache && thx_chol_symbolic_cached(cd, n, skey, &f->y);
    if (!inf.symbolic_cached) {
        if (!A && !(A = upper(f, n, rowp, col, val))) { st = THX_ENOMEM; goto done; }
        f->c.nmethods = 1;
        f->c.method[0].ordering = CHOLMOD_GIVEN;
        f->c.postorder = 1;
        f->L = cholmod_l_analyze_p(A, (SuiteSparse_long *)order, NULL, 0, &f->c);
        if (!f->L || f->c.status < 0) {
            st = thx_error(ctx, f->c.status == CHOLMOD_OUT_OF_MEMORY ? THX_ENOMEM : THX_ESOLVER,
                           "fem: the symbolic factorization (CHOLMOD) failed (status %d)", f->c.status);
            goto done;
        }
        if (!f->L->is_super || !f->L->super || !f->L->pi || !f->L->px || !f->L->s) {
            st = thx_error(ctx, THX_ESOLVER, "fem: CHOLMOD's analysis gave no supernodal symbolic factor");
            goto done;
        }
        if (!thx_chol_symbolic_copy(&f->y, n, (int64_t)f->L->nsuper, (const int64_t *)f->L->Perm,
                                    (const int64_t *)f->L->super, (const int64_t *)f->L->pi, (const int64_t *)f->L->px,
                                    (const int64_t *)f->L->s, f->L->ssize, f->L->xsize)) {
            st = THX_ENOMEM;
            goto done;
        }
        f->y.flops = f->c.fl; /* the analysis's count, explicit zeros of amalgamated supernodes left out */
        f->y.lnz = f->c.lnz;
        if (cd && !inf.cache_note[0]) thx_chol_symbolic_keep(cd, n, skey, &f->y, inf.cache_note, sizeof inf.cache_note);
    }
    inf.t_analyze = thx_wtime() - t0;
    inf.flops = f->y.flops;
    inf.lnz = f->y.lnz;
    inf.n_super = (size_t)f->y.nsuper;
    for (int64_t i = 0; i < n; i++) {
        f->perm[i] = f->y.perm[i];
        f->iperm[f->y.perm[i]] = i;
    }
    for (int64_t s = 0; s < f->y.nsuper; s++) {
        size_t below = (size_t)((f->y.pi[s + 1] - f->y.pi[s]) - (f->y.super[s + 1] - f->y.super[s]));
        if (below > f->max_below) f->max_below = below;
    }
    t0 = thx_wtime();
    if (cholmod_numeric) {
        int ok = cholmod_l_factorize(A, f->L, &f->c);
        inf.t_factor = thx_wtime() - t0;
        if (f->c.status == CHOLMOD_NOT_POSDEF) {
            inf.not_posdef = 1;
            inf.bad_column = (int64_t)f->L->minor;
        } else if (!ok || f->c.status < 0 || !f->L->is_super) {
            st = thx_error(ctx, f->c.status == CHOLMOD_OUT_OF_MEMORY ? THX_ENOMEM : THX_ESOLVER,
                           "fem: the numeric factorization (CHOLMOD) failed (status %d)", f->c.status);
            goto done;
        }
        f->Lx = f->L->x;
        inf.numeric = "CHOLMOD (supernodal, left-looking)";
    } else {
        /* our own multifrontal factorization on the symbolic factor (fem/multifrontal.h); CHOLMOD's factor
           is not needed any more */
        if (A) cholmod_l_free_sparse(&A, &f->c);
        if (f->L) cholmod_l_free_factor(&f->L, &f->c);
        if (thx_pages_zeroed(&f->own, (f->y.xsize ? f->y.xsize : 1) * sizeof(double), opts ? opts->threads : 1)) {
            st = THX_ENOMEM;
            goto done;
        }
        f->S = (thx_mf_symbolic){n, f->y.nsuper, f->y.super, f->y.pi, f->y.px, f->y.rows};
        const int threads = opts ? opts->threads : 1;
        void (*set_blas)(int) = opts ? opts->set_blas_threads : NULL;
        thx_status e = thx_mf_begin(ctx, &f->S, rowp, col, val, f->perm, f->iperm, threads, set_blas, f->own.p, &f->mf,
                                    &inf.mf);
        /* the top now, or beside the caller's first solve (opts->defer_top: thx_chol_factor_top) */
        if (e == THX_OK && !(opts && opts->defer_top && threads > 1 && inf.mf.top > 0)) {
            e = thx_mf_top(f->mf, opts ? opts->top_threads : 1, set_blas, &inf.mf);
            keep_spare(f);
            thx_mf_free(&f->mf);
        }
        inf.t_factor = thx_wtime() - t0;
        if (e == THX_EINTERNAL && inf.symbolic_cached) {
            /* the cache's symbolic factor, though whole, is not this matrix's: analysed again, kept again */
            thx_ctx_clear(ctx);
            thx_mf_free(&f->mf);
            thx_pages_free(&f->own);
            thx_chol_symbolic_free(&f->y);
            f->max_below = 0;
            use_cache = 0;
            t0 = thx_wtime();
            goto analyse;
        }
        if (e == THX_ESOLVER && inf.mf.not_posdef >= 0) {
            inf.not_posdef = 1;
            inf.bad_column = inf.mf.not_posdef;
        } else if (e != THX_OK) {
            st = e;
            goto done;
        }
        f->Lx = f->own.p;
        inf.numeric = "thorax (multifrontal, subtrees in parallel)";
    }
    if (inf.not_posdef) {
        st = not_posdef(ctx, f, inf.bad_column);
        goto done;
    }
    inf.factor_bytes = (f->y.xsize + f->y.ssize) * sizeof(double);
    *out = f;
    f = NULL;
done:
    if (A) cholmod_l_free_sparse(&A, f ? &f->c : &(*out)->c);
    free(order);
    thx_chol_free(&f);
    if (info) *info = inf;
    return st;
}

const unsigned char *thx_chol_top_left(const thx_chol *f) { return f->mf ? thx_mf_top_mask(f->mf) : NULL; }

thx_status thx_chol_factor_top(thx_ctx *ctx, thx_chol *f, void (*set_blas_threads)(int), thx_chol_info *info)
{
    if (!f->mf || !thx_mf_top_mask(f->mf)) return THX_OK;
    double t0 = thx_wtime();
    thx_status e = thx_mf_top(f->mf, 1, set_blas_threads, &info->mf);
    info->t_factor += thx_wtime() - t0;
    info->mf.beside = 1;
    if (e == THX_ESOLVER && info->mf.not_posdef >= 0) {
        info->not_posdef = 1;
        info->bad_column = info->mf.not_posdef;
        return not_posdef(ctx, f, info->bad_column);
    }
    return e;
}

void thx_chol_top_release(thx_chol *f)
{
    pthread_mutex_lock(&f->lock);
    keep_spare(f);
    thx_mf_free(&f->mf);
    pthread_mutex_unlock(&f->lock);
}

const int64_t *thx_chol_perm(const thx_chol *f) { return f->perm; }
const int64_t *thx_chol_iperm(const thx_chol *f) { return f->iperm; }

size_t thx_chol_work_bytes(const thx_chol *f, size_t r) { return (f->max_below ? f->max_below : 1) * r * sizeof(double); }

size_t thx_chol_nsuper(const thx_chol *f) { return (size_t)f->y.nsuper; }

/* Supernode s's share of one column's sweep (either): nscol (nscol + 2 nb), the flops of its triangle and its
   rectangle. */
static double sweep_share(const thx_chol *f, size_t s)
{
    const double k = (double)(f->y.super[s + 1] - f->y.super[s]), r = (double)(f->y.pi[s + 1] - f->y.pi[s]);
    return k * (k + 2.0 * (r - k));
}

double thx_chol_sweep_flops(const thx_chol *f, const unsigned char *reach, const unsigned char *need)
{
    double fl = 0;
    for (size_t s = 0; s < (size_t)f->y.nsuper; s++) {
        double w = sweep_share(f, s);
        fl += (!reach || reach[s] ? w : 0) + (!need || need[s] ? w : 0);
    }
    return fl;
}

double thx_chol_needed(const thx_chol *f, const int64_t *want, size_t m, unsigned char *need)
{
    const int64_t *super = f->y.super, *pi = f->y.pi, *Ls = f->y.rows;
    const size_t ns = (size_t)f->y.nsuper;
    memset(need, 0, ns);
    for (size_t i = 0; i < m; i++) {
        /* the supernode holding factor row want[i]: the last s with super[s] <= row */
        size_t lo = 0, hi = ns;
        while (hi - lo > 1) {
            size_t mid = lo + (hi - lo) / 2;
            if (super[mid] <= want[i]) lo = mid;
            else hi = mid;
        }
        need[lo] = 1;
    }
    /* a parent (the supernode of the first row below the diagonal block) comes after its children */
    double all = 0, kept = 0;
    for (size_t s = 0; s < ns; s++) {
        int64_t nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
        double w = sweep_share(f, s);
        all += w;
        if (!need[s]) continue;
        kept += w;
        if (nsrow > nscol) {
            int64_t row = Ls[pi[s] + nscol];
            size_t lo = s + 1, hi = ns;
            while (hi - lo > 1) {
                size_t mid = lo + (hi - lo) / 2;
                if (super[mid] <= row) lo = mid;
                else hi = mid;
            }
            need[lo] = 1;
        }
    }
    return all > 0 ? kept / all : 1;
}

void thx_chol_prepare_rows(const thx_chol *f, double *X, size_t r, const unsigned char *need, const unsigned char *reach,
                           const double *fresh)
{
    const int64_t *super = f->y.super;
    const size_t ns = (size_t)f->y.nsuper;
    for (size_t s = 0; s < ns;) {
        if (!((need && need[s]) || (reach && reach[s]))) {
            s++;
            continue;
        }
        size_t e = s + 1; /* the run of marked supernodes s .. e - 1: their rows are one range */
        while (e < ns && ((need && need[e]) || (reach && reach[e]))) e++;
        double *a = X + (size_t)super[s] * r, *b = X + (size_t)super[e] * r;
        double *mid = fresh <= a ? a : fresh >= b ? b : (double *)fresh;
        if (mid > a) memset(a, 0, (size_t)(mid - a) * sizeof *X); /* rows that held something */
        if (b > mid && thx_pages_present(mid, (size_t)(b - mid) * sizeof *X))
            memset(mid, 0, (size_t)(b - mid) * sizeof *X); /* zeros already: written to be present */
        s = e;
    }
}

double thx_chol_solve_rows(const thx_chol *f, double *X, size_t r, double *E)
{
    return thx_chol_solve_rows_with(f, X, r, 0, NULL, E, NULL, NULL);
}

double thx_chol_solve_rows_needed(const thx_chol *f, double *X, size_t r, double *E, const unsigned char *need,
                                  const unsigned char *reach)
{
    return thx_chol_solve_rows_with(f, X, r, 0, NULL, E, need, reach);
}

/* Supernode s's step of the forward sweep on the r columns of X (row-major, ld r): L11 Y = B, then the rows below
   updated. A supernode whose rows are all zero is skipped (they stay zero and update nothing). Returns the flops. */
static double forward_step(const thx_chol *f, size_t s, double *X, size_t r, double *E)
{
    const int64_t *super = f->y.super, *pi = f->y.pi;
    const int ir = (int)r;
    const double one = 1, zero = 0;
    int nscol = (int)(super[s + 1] - super[s]), nsrow = (int)(pi[s + 1] - pi[s]), nb = nsrow - nscol;
    const double *L1 = f->Lx + f->y.px[s];
    double *Xs = X + (size_t)super[s] * r;
    size_t z = 0, nz = (size_t)nscol * r;
    while (z < nz && Xs[z] == 0) z++;
    if (z == nz) return 0;
    dtrsm_("R", "L", "T", "N", &ir, &nscol, &one, L1, &nsrow, Xs, &ir);
    if (nb > 0) {
        dgemm_("N", "T", &ir, &nb, &nscol, &one, Xs, &ir, L1 + nscol, &nsrow, &zero, E, &ir);
        const int64_t *rows = f->y.rows + pi[s] + nscol;
        for (int t = 0; t < nb; t++) {
            double *xr = X + (size_t)rows[t] * r;
            const double *e = E + (size_t)t * r;
            for (size_t j = 0; j < r; j++) xr[j] -= e[j];
        }
    }
    return (double)r * nscol * ((double)nscol + 2.0 * nb);
}

/* Supernode s's step of the backward sweep: L11^T X_s = Y_s - L21^T X_below. Returns the flops. */
static double backward_step(const thx_chol *f, size_t s, double *X, size_t r, double *E)
{
    const int64_t *super = f->y.super, *pi = f->y.pi;
    const int ir = (int)r;
    const double one = 1, minus = -1;
    int nscol = (int)(super[s + 1] - super[s]), nsrow = (int)(pi[s + 1] - pi[s]), nb = nsrow - nscol;
    const double *L1 = f->Lx + f->y.px[s];
    double *Xs = X + (size_t)super[s] * r;
    if (nb > 0) {
        const int64_t *rows = f->y.rows + pi[s] + nscol;
        for (int t = 0; t < nb; t++) memcpy(E + (size_t)t * r, X + (size_t)rows[t] * r, r * sizeof *E);
        dgemm_("N", "N", &ir, &nscol, &nb, &minus, E, &ir, L1 + nscol, &nsrow, &one, Xs, &ir);
    }
    dtrsm_("R", "L", "N", "N", &ir, &nscol, &one, L1, &nsrow, Xs, &ir);
    return (double)r * nscol * ((double)nscol + 2.0 * nb);
}

double thx_chol_solve_rows_with(const thx_chol *f, double *X, size_t r, size_t q, double *Z, double *E,
                                const unsigned char *need, const unsigned char *reach)
{
    return thx_chol_solve_rows_part(f, X, r, q, Z, E, need, reach, NULL, 0);
}

double thx_chol_solve_rows_part(const thx_chol *f, double *X, size_t r, size_t q, double *Z, double *E,
                                const unsigned char *need, const unsigned char *reach, const unsigned char *top, int part)
{
    double flops = 0;
    const int64_t *super = f->y.super;
    const size_t ns = (size_t)f->y.nsuper, w = r + q;
    if (part == 0) top = NULL;
    /* forward: L Y = B. In column-major terms a supernode's rows of X are X_s^T (w x nscol, ld w). The forward
       problem's b lives at the nodes next to the heart: the supernodes it cannot reach are skipped unread.
       Part 1: those below the top (a supernode's descendants are never in the top when it is not); part 2: the
       top's, after them. */
    if (part != 2)
        for (size_t s = 0; s < ns; s++)
            if ((!reach || reach[s]) && !(top && top[s])) flops += forward_step(f, s, X, w, E);
    if (part == 1) return flops;
    if (top)
        for (size_t s = 0; s < ns; s++)
            if ((!reach || reach[s]) && top[s]) flops += forward_step(f, s, X, w, E);
    /* the last q columns go on in Z, where the rows of the supernodes the forward sweep never reached are zero */
    if (q) {
        memset(Z, 0, (size_t)f->n * q * sizeof *Z);
        for (size_t s = 0; s < ns; s++)
            if (!reach || reach[s])
                for (int64_t i = super[s]; i < super[s + 1]; i++) memcpy(Z + (size_t)i * q, X + (size_t)i * w + r, q * sizeof *Z);
    }
    /* backward: L^T X = Y. A supernode in need: all w columns in X, its last q then copied to Z (its ancestors are
       in need too, so the rows it reads in X are done); any other: Z's q columns alone, reading Z. */
    for (size_t s = ns; s-- > 0;) {
        if (!need || need[s]) {
            flops += backward_step(f, s, X, w, E);
            if (q)
                for (int64_t i = super[s]; i < super[s + 1]; i++) memcpy(Z + (size_t)i * q, X + (size_t)i * w + r, q * sizeof *Z);
        } else if (q)
            flops += backward_step(f, s, Z, q, E);
    }
    return flops;
}
