/*
 * thorax's own direct path in the solver module (src/fem/solver_internal.h; docs/design/parallel.md,
 * "thorax's own direct path" and "The outer surface's rows alone, checked by combinations"): on one rank
 * with many right-hand sides, K_ff factored once (src/fem/cholesky.h) and blocks of columns solved by the
 * threads, each calling BLAS alone; every column's residual checked, or, for some rows alone, the backward
 * sweep pruned and each block checked by two combinations of its columns.
 */
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <petscksp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem/solver_internal.h"
#include "thorax/core/cores.h"
#include "thorax/core/hash.h"
#ifdef _OPENMP
#include <omp.h>
#endif

static void *big_alloc(size_t bytes)
{
    void *p = NULL;
    size_t align = 64;
    bytes = (bytes + align - 1) / align * align;
    return posix_memalign(&p, align, bytes ? bytes : align) ? NULL : p;
}

void fem_own_top_drop(thx_fem_system *s)
{
    if (s->chol) thx_chol_top_release(s->chol);
    free(s->top_rowp);
    free(s->top_col);
    s->top_rowp = NULL;
    s->top_col = NULL;
}

void fem_own_work_free(own_work *w)
{
    if (w->Xpg.p) thx_pages_free(&w->Xpg);
    else free(w->X);
    free(w->P);
    free(w->E);
    free(w->acc);
    free(w->Z);
    free(w->Pz);
    memset(w, 0, sizeof *w);
}

static int blas_threads(int set);
static void set_blas_threads(int n);
static thx_status factor_threads(thx_ctx *ctx, int was, int *use);
static int own_threads_max(void);

/* The own path's factorization, once (timed as the setup, as PETSc's is). defer_top: the top may be left to the
   first block of rows (own_solve factors it beside that block's start); A's pattern is then kept for it. */
thx_status fem_own_factor(thx_ctx *ctx, thx_fem_system *s, int defer_top)
{
    if (s->chol) return THX_OK;
    double t0 = thx_wtime();
    thx_status st = THX_OK;
    size_t n = (size_t)s->nf, nz = (size_t)s->ii[n];
    int64_t *rowp = thx_malloc(ctx, (n + 1) * sizeof *rowp);
    int32_t *col = thx_malloc(ctx, (nz ? nz : 1) * sizeof *col);
    if (!rowp || !col) { st = THX_ENOMEM; goto done; }
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i <= n; i++) rowp[i] = (int64_t)s->ii[i];
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < nz; k++) col[k] = (int32_t)s->jj[k];
    int was = blas_threads(0), use = -1;
    st = factor_threads(ctx, was, &use);
    if (st != THX_OK) goto done;
    if (use > 0 && use != was) blas_threads(use);
    /* the factor's values: ours (src/fem/multifrontal.h), or CHOLMOD's with -thorax_factor cholmod */
    char how[16] = "thorax";
    PetscOptionsGetString(NULL, NULL, "-thorax_factor", how, sizeof how, NULL);
    if (strcmp(how, "thorax") && strcmp(how, "cholmod")) {
        st = thx_error(ctx, THX_EINPUT, "-thorax_factor %s: thorax (the default: our multifrontal factorization) or "
                       "cholmod (CHOLMOD's)", how);
        goto done;
    }
    /* BLAS's threads (CHOLMOD's factorization; the top of ours): the free cores (factor_threads). Our subtrees'
       threads: the cores this process may use, even on a loaded machine (they wait for none but the last:
       beside three busy loops the high phantom's factorization took 5.8 s on one, 3.5 s for the subtrees on
       two, docs/design/parallel.md), unless THORAX_FACTOR_THREADS or OPENBLAS_NUM_THREADS says. */
    int tree = use;
    if (!getenv("THORAX_FACTOR_THREADS") && !getenv("OPENBLAS_NUM_THREADS")) {
        tree = thx_cores_allowed();
#ifdef _OPENMP
        tree = tree < omp_get_max_threads() ? tree : omp_get_max_threads();
#else
        tree = 1;
#endif
    }
    thx_chol_opts co = {tree > 0 ? tree : 1, use > 0 ? use : 1, was > 0 ? set_blas_threads : NULL, !strcmp(how, "cholmod"),
                        defer_top && own_threads_max() > 1};
    st = thx_chol_factor(ctx, (int64_t)n, rowp, col, s->aa, &co, &s->chol, &s->chol_info);
    if (st == THX_OK && thx_chol_top_left(s->chol)) { /* the top's fronts read A's pattern: kept until it is done */
        s->top_rowp = rowp;
        s->top_col = col;
        rowp = NULL;
        col = NULL;
    }
    if (was > 0) blas_threads(was);
    s->chol_info.blas_threads = use > 0 ? use : 0;
    if (st == THX_ESOLVER && s->chol_info.not_posdef) {
        /* a singular system (a piece of the mesh with no prescribed potential): PETSc's interface to the
           same package decides, as before the own path existed (a consistent system may still solve) */
        s->own = 0;
        st = THX_OK;
    }
    s->pc_ready = st == THX_OK && s->own;
done:
    free(rowp);
    free(col);
    s->t_setup += thx_wtime() - t0;
    return st;
}

static void set_blas_threads(int n) { blas_threads(n); }

/* OpenBLAS's thread count, where OpenBLAS is the BLAS (else -1): our threads each call BLAS alone. */
static int blas_threads(int set)
{
    static void (*setn)(int);
    static int (*getn)(void);
    static int looked;
    if (!looked) {
        setn = (void (*)(int))dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
        getn = (int (*)(void))dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
        looked = 1;
    }
    if (!setn || !getn) return -1;
    int was = getn();
    if (set > 0) setn(set);
    return was;
}

/* The OpenBLAS threads for CHOLMOD's factorization into *use (was: OpenBLAS's count, -1 when it is not
 * the BLAS; *use -1 then): $THORAX_FACTOR_THREADS when set (1 to 1024, else refused); OpenBLAS's own when the user set OPENBLAS_NUM_THREADS; else as
 * many as the cores free now, at most was. Its threads meet at every BLAS call, and a thread whose
 * core another process holds makes its partner spin: 27 s against 6 s for the high phantom's factor
 * at load 3.5 (docs/design/parallel.md, "CHOLMOD's BLAS threads under load"). */
static thx_status factor_threads(thx_ctx *ctx, int was, int *use)
{
    *use = -1;
    if (was < 1) return THX_OK;
    const char *e = getenv("THORAX_FACTOR_THREADS");
    if (e && *e) {
        char *end;
        errno = 0;
        long n = strtol(e, &end, 10);
        if (end == e || *end || errno || n < 1 || n > 1024)
            return thx_error(ctx, THX_EINPUT, "THORAX_FACTOR_THREADS=%s: the factorization's BLAS threads, a count from 1 to 1024",
                             e);
        *use = (int)n;
        return THX_OK;
    }
    int free_cores = getenv("OPENBLAS_NUM_THREADS") ? was : thx_cores_free();
    *use = free_cores < was ? free_cores : was;
    return THX_OK;
}

/* b = load_f - K_fd phi_d for columns c0 .. c0 + r - 1, row-major in the factor's order (rows ld apart, ld >= r).
   B_zero: B's rows where b lives hold zeros already (a buffer fresh from calloc, whose pages are not touched: a
   row the solve never writes then costs no page); else all of B is zeroed first. */
static void own_rhs(const thx_fem_system *s, const double *P, const double *load, size_t c0, size_t r,
                    double *restrict B, size_t ld, int B_zero)
{
    const size_t n = (size_t)s->n, nf = (size_t)s->nf;
    const int64_t *iperm = thx_chol_iperm(s->chol);
    if (!B_zero) memset(B, 0, nf * ld * sizeof *B);
    for (size_t q = 0; q < nf; q++) {
        double *restrict bq = B + (size_t)iperm[q] * ld;
        for (int64_t e = s->kfd.row[q]; e < s->kfd.row[q + 1]; e++) {
            const double a = s->kfd.val[e], *pd = P + (size_t)s->kfd.col[e] * r;
            for (size_t j = 0; j < r; j++) bq[j] -= a * pd[j];
        }
    }
    if (load)
        for (size_t j = 0; j < r; j++) {
            const double *lj = load + (c0 + j) * n;
            for (size_t q = 0; q < nf; q++) B[(size_t)iperm[q] * ld + j] += lj[s->free_node[q]];
        }
}

/* Rows of phi, tiled: T[i * r + j] = phi[(c0 + j) * n + node[i]] for m nodes (a block of rows at a time,
   so that each column's reads stay near each other). */
static void own_gather_rows(const double *phi, size_t n, size_t c0, size_t r, const int32_t *node, size_t m,
                            double *restrict T)
{
    const size_t tile = 256;
    for (size_t i0 = 0; i0 < m; i0 += tile) {
        size_t i1 = i0 + tile < m ? i0 + tile : m;
        for (size_t j = 0; j < r; j++) {
            const double *pj = phi + (c0 + j) * n;
            for (size_t i = i0; i < i1; i++) T[i * r + j] = pj[node[i]];
        }
    }
}

/* Row q of b (original free numbering) for the r columns into out: load_f - K_fd phi_d, as own_rhs puts it
   (P: the prescribed values, row-major, own_gather_rows). */
static inline __attribute__((always_inline)) void own_rhs_row(const thx_fem_system *s, const double *P, const double *load, size_t c0, size_t r,
                               size_t q, double *restrict out)
{
    const size_t n = (size_t)s->n;
    for (size_t j = 0; j < r; j++) out[j] = 0;
    for (int64_t e = s->kfd.row[q]; e < s->kfd.row[q + 1]; e++) {
        const double a = s->kfd.val[e], *pd = P + (size_t)s->kfd.col[e] * r;
        for (size_t j = 0; j < r; j++) out[j] -= a * pd[j];
    }
    if (load) {
        const double *lq = load + c0 * n + (size_t)s->free_node[q];
        for (size_t j = 0; j < r; j++) out[j] += lq[j * n];
    }
}

/* rn[j] = ||b - K_ff x||^2 and bn[j] = ||b||^2 for the r columns, rows visited in the factor's order (their
   neighbours are near them there); b rebuilt row by row from the prescribed values P and the loads (not
   kept: a block of it is as large as x). */
static inline __attribute__((always_inline)) void
own_residual_body(const thx_fem_system *s, const double *P, const double *load, size_t c0, const double *restrict X,
                  size_t r, double *restrict acc, double *restrict rn, double *restrict bn)
{
    const size_t nf = (size_t)s->nf;
    const int64_t *perm = thx_chol_perm(s->chol), *iperm = thx_chol_iperm(s->chol);
    double *restrict bq = acc + r;
    for (size_t j = 0; j < r; j++) rn[j] = bn[j] = 0;
    for (size_t p = 0; p < nf; p++) {
        const size_t q = (size_t)perm[p];
        own_rhs_row(s, P, load, c0, r, q, bq);
#pragma omp simd
        for (size_t j = 0; j < r; j++) acc[j] = bq[j];
        for (PetscInt e = s->ii[q]; e < s->ii[q + 1]; e++) {
            const double a = s->aa[e];
            const double *restrict xc = X + (size_t)iperm[s->jj[e]] * r;
#pragma omp simd
            for (size_t j = 0; j < r; j++) acc[j] -= a * xc[j];
        }
#pragma omp simd
        for (size_t j = 0; j < r; j++) {
            rn[j] += acc[j] * acc[j];
            bn[j] += bq[j] * bq[j];
        }
    }
}

/* The same compiled twice: for AVX2 with FMA (four products a step instead of SSE2's two; chosen at run time)
   and for any x86-64. The residual is a check: its last bits may differ between the two. */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2,fma"))) static void
own_residual_avx2(const thx_fem_system *s, const double *P, const double *load, size_t c0, const double *restrict X,
                  size_t r, double *restrict acc, double *restrict rn, double *restrict bn)
{
    own_residual_body(s, P, load, c0, X, r, acc, rn, bn);
}
#define THX_HAVE_AVX2_RESIDUAL 1
#endif

static void own_residual(const thx_fem_system *s, const double *P, const double *load, size_t c0,
                         const double *restrict X, size_t r, double *restrict acc, double *restrict rn,
                         double *restrict bn)
{
#ifdef THX_HAVE_AVX2_RESIDUAL
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        own_residual_avx2(s, P, load, c0, X, r, acc, rn, bn);
        return;
    }
#endif
    own_residual_body(s, P, load, c0, X, r, acc, rn, bn);
}

/* Where a block's right-hand sides come from and its answers go: phi's columns (n values each, the prescribed
   values in, every node's value out), or the caller's prescribed values (pres: np values a column, value c for
   the system's prescribed node whose from-index is c; from[d] = -2: the pinned node, 0) in and the values at
   rows[0 .. m - 1] out (out: m values a column). */
typedef struct {
    double *phi;
    const double *load;
    const double *pres;
    const int32_t *from;
    size_t np;
    const int32_t *rows;
    size_t m;
    double *out;
    /* rows out: the backward sweep kept to the supernodes the rows need (thx_chol_needed), and each thread's
       check of its columns (own_check_finish): per combination its relative residual, the largest difference
       between the combined rows and its own answer, and the scale of that difference */
    const unsigned char *need, *reach;
    double *part; /* T x THX_FEM_CHECK_COMBOS x 3 */
    size_t spoil;    /* the check's test: column spoil (1-based, 0: none) written times 1 + spoil_by */
    int fail_top;    /* the hand-over's test: the top beside the solves reported as failed on a pivot */
    double spoil_by;
} own_io;

/* The check of a block whose answers are kept at some rows alone (the backward sweep pruned): each thread's
   columns in two fixed combinations, column j weighted by w = u_j / ||b_j|| (u_j in [-1, 1) from the column's
   number alone), solved in full beside them (thx_chol_solve_rows_with); their residual must be a
   factorization's, and the rows' answers combined with the same weights must equal theirs. */
#define THX_FEM_CHECK_COMBOS 2
/* The combined rows against the combination's own answer: within this of sum_j |w_j| max_i |x_ij| (the
   two solves differ by rounding alone, about 1e-15 of it; a column off by 1e-6 of itself shows in a block
   of 512) */
#define THX_FEM_CHECK_RTOL 1e-9

/* A number in [-1, 1) from i alone: the same weights whatever the threads. */
static double check_weight(uint64_t i) { return thx_hash_signed_unit(i); }

/* ||b_j||^2 of the r columns of B (row-major, rows ld apart, the factor's order) where b can be nonzero: the free
   rows coupled to a prescribed node (no loads on this path). */
static void own_rhs_norms(const thx_fem_system *s, const double *B, size_t r, size_t ld, double *restrict bn)
{
    const int64_t *iperm = thx_chol_iperm(s->chol);
    for (size_t j = 0; j < r; j++) bn[j] = 0;
    for (size_t q = 0; q < (size_t)s->nf; q++) {
        if (s->kfd.row[q + 1] == s->kfd.row[q]) continue;
        const double *bq = B + (size_t)iperm[q] * ld;
        for (size_t j = 0; j < r; j++) bn[j] += bq[j] * bq[j];
    }
}

/* T[i * r + j] = pres[(c0 + j) * np + from[i]] for the nd prescribed nodes, a tile of rows at a time. */
static void own_gather_pres(const own_io *io, size_t nd, size_t c0, size_t r, double *restrict T)
{
    const size_t tile = 256;
    for (size_t i0 = 0; i0 < nd; i0 += tile) {
        size_t i1 = i0 + tile < nd ? i0 + tile : nd;
        for (size_t j = 0; j < r; j++) {
            const double *pj = io->pres + (c0 + j) * io->np;
            for (size_t i = i0; i < i1; i++) T[i * r + j] = io->from[i] >= 0 ? pj[io->from[i]] : 0;
        }
    }
}

/* This thread's check, before its solve (see THX_FEM_CHECK_COMBOS): its columns' weights into w->acc (C x r), the
   combinations' prescribed values into w->Pz (nd x C) and their right-hand sides into X's last C columns (X: rows
   of r + C, the r columns' b there already, the last C zero where b lives). bn: ||b_j||^2. */
static void own_check_prepare(const thx_fem_system *s, own_work *w, size_t c0, size_t r, const double *bn)
{
    const size_t nd = (size_t)s->nd, C = THX_FEM_CHECK_COMBOS;
    double *wt = w->acc; /* acc holds 4 r */
    for (size_t c = 0; c < C; c++)
        for (size_t j = 0; j < r; j++) {
            double u = check_weight(C * (c0 + j) + c);
            wt[c * r + j] = bn[j] > 0 ? u / sqrt(bn[j]) : 0;
        }
    for (size_t d = 0; d < nd; d++)
        for (size_t c = 0; c < C; c++) {
            double a = 0;
            for (size_t j = 0; j < r; j++) a += wt[c * r + j] * w->P[d * r + j];
            w->Pz[d * C + c] = a;
        }
    own_rhs(s, w->Pz, NULL, 0, C, w->X + r, r + C, 1);
}

/* ... and after it, the rows written to io->out: per combination, its relative residual (a factorization's
   verdict, as own_verdict gives it column by column on the other path), and its answers at the rows against
   the rows' answers combined with the same weights, into io->part (thread t). */
static void own_check_finish(const thx_fem_system *s, const own_io *io, own_work *w, int t, size_t c0, size_t r)
{
    const size_t m = io->m, C = THX_FEM_CHECK_COMBOS;
    const int64_t *iperm = thx_chol_iperm(s->chol);
    const double *wt = w->acc;
    double acc[4 * THX_FEM_CHECK_COMBOS], *rn = acc + 2 * C, *bn = acc + 3 * C;
    own_residual(s, w->Pz, NULL, 0, w->Z, C, acc, rn, bn);
    for (size_t c = 0; c < C; c++) {
        double scale = 0, diff = 0;
        for (size_t j = 0; j < r; j++) {
            double mx = 0;
            for (size_t i = 0; i < m; i++) mx = fmax(mx, fabs(io->out[(c0 + j) * m + i]));
            scale += fabs(wt[c * r + j]) * mx;
        }
        for (size_t i = 0; i < m; i++) {
            double y = 0;
            for (size_t j = 0; j < r; j++) y += wt[c * r + j] * io->out[(c0 + j) * m + i];
            int32_t node = io->rows[i], f = s->fidx[node], d = s->didx[node];
            double x = f >= 0 ? w->Z[(size_t)iperm[f] * C + c] : d >= 0 ? w->Pz[(size_t)d * C + c] : 0;
            diff = fmax(diff, fabs(y - x));
        }
        double *pt = io->part + ((size_t)t * C + c) * 3;
        pt[0] = bn[c] > 0 ? sqrt(rn[c] / bn[c]) : sqrt(rn[c]);
        pt[1] = diff;
        pt[2] = scale;
    }
}

/* k columns through the own factor: dealt to the threads in contiguous groups, each group row-major in the
   factor's order (src/fem/cholesky.h), its residuals ||b - A x|| from the kept CSR. rel[j]: column j's
   relative residual. */
/* The threads own_solve may use, and those it deals k columns to. */
static int own_threads_max(void)
{
    int T = 1;
#ifdef _OPENMP
    T = omp_get_max_threads();
#endif
    return T > THX_FEM_OWN_THREADS ? THX_FEM_OWN_THREADS : T;
}

static int own_threads(size_t k)
{
    int T = own_threads_max();
    if ((size_t)T > k) T = (int)k;
    return T < 1 ? 1 : T;
}

/* The top of the factorization left by fem_own_factor (defer_top), factored by thread 0 while the others start
   their blocks: until it is done they run the forward sweep below it (thx_chol_solve_rows_part, part 1), then
   wait here for it. */
typedef struct {
    pthread_mutex_t lock;
    pthread_cond_t done_cv;
    int done; /* 1: factored; -1: failed (the others stop) */
} own_top;

static void own_top_set(own_top *tp, int v)
{
    pthread_mutex_lock(&tp->lock);
    tp->done = v;
    pthread_cond_broadcast(&tp->done_cv);
    pthread_mutex_unlock(&tp->lock);
}

static int own_top_wait(own_top *tp)
{
    pthread_mutex_lock(&tp->lock);
    while (!tp->done) pthread_cond_wait(&tp->done_cv, &tp->lock);
    int v = tp->done;
    pthread_mutex_unlock(&tp->lock);
    return v;
}

/* The first column of each thread's group (cut[0 .. T]). Evenly, or, with the top to factor by thread 0, thread 0
   given fewer columns by the top's work in columns' worth: its flops over those of a column's sweeps (forward
   where b reaches, backward where the rows need), the top's dense fronts counted at OWN_TOP_SPEED times the
   sweeps' rate per flop. From the factor's counts alone: the same columns whatever the load. */
#define OWN_TOP_SPEED 1.5
static void own_cut(const thx_fem_system *s, const own_io *io, size_t k, int T, int top, size_t *cut)
{
    double c_top = 0;
    if (top && T > 1) {
        double per_col = thx_chol_sweep_flops(s->chol, io->reach, io->need);
        c_top = per_col > 0 ? s->chol_info.mf.top_flops / OWN_TOP_SPEED / per_col : 0;
    }
    cut[0] = 0;
    if (!top || T < 2) {
        for (int t = 0; t < T; t++) cut[t + 1] = k * (size_t)(t + 1) / (size_t)T;
        return;
    }
    double first = ((double)k + c_top) / T - c_top;
    size_t c0 = first <= 0 ? 0 : first >= (double)k ? k : (size_t)first;
    for (int t = 0; t < T; t++) cut[t + 1] = c0 + (k - c0) * (size_t)t / (size_t)(T - 1);
}

static thx_status own_solve(thx_ctx *ctx, thx_fem_system *s, const own_io *io, size_t k, double *rel)
{
    const size_t n = (size_t)s->n, nf = (size_t)s->nf;
    double *phi = io->phi;
    const double *load = io->load;
    const int T = own_threads(k);
    const int64_t *iperm = thx_chol_iperm(s->chol);
    if (!s->work && !(s->work = thx_calloc(ctx, THX_FEM_OWN_THREADS, sizeof *s->work))) return THX_ENOMEM;
    int failed = 0;
    int was = T > 1 ? blas_threads(1) : -1;
    /* the top left by fem_own_factor: beside this block when its rows alone are asked for on threads, else now */
    const unsigned char *top = thx_chol_top_left(s->chol);
    thx_status top_st = THX_OK;
    if (top && (T < 2 || !io->need)) {
        top_st = thx_chol_factor_top(ctx, s->chol, was > 0 ? set_blas_threads : NULL, &s->chol_info);
        top = NULL;
    }
    own_top tw = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, top ? 0 : 1};
    size_t cut[THX_FEM_OWN_THREADS + 1];
    own_cut(s, io, k, T, top != NULL, cut);
    if (top_st == THX_OK)
#pragma omp parallel for num_threads(T) schedule(static, 1) reduction(| : failed)
    for (int t = 0; t < T; t++) {
        if (top && t == 0) {
            /* thread 0 factors the top (BLAS on this thread alone) while the others start */
            top_st = thx_chol_factor_top(ctx, s->chol, NULL, &s->chol_info);
            if (top_st == THX_OK && io->fail_top) { /* the hand-over's own test (tests/test_fem_block.c) */
                s->chol_info.not_posdef = 1;
                top_st = thx_error(ctx, THX_ESOLVER, "fem: the top's pivot made to fail (-thorax_test_fail_top)");
            }
            own_top_set(&tw, top_st == THX_OK ? 1 : -1);
            if (top_st != THX_OK) continue;
        }
        size_t c0 = cut[t], c1 = cut[t + 1], r = c1 - c0;
        if (!r) continue;
        own_work *w = &s->work[t];
        if (w->r < r) {
            double done = w->flops;
            fem_own_work_free(w);
            w->flops = done;
            const size_t C = THX_FEM_CHECK_COMBOS, nd = (size_t)s->nd ? (size_t)s->nd : 1;
            /* r + C: the rows out carry the check's C combinations. X on the factorization's working memory
               where it is spare (its pages present: about 1 microsecond a page not spent again), the rest fresh */
            const size_t xn = nf * (r + C);
            thx_chol_take_spare(s->chol, &w->Xpg);
            size_t kept = w->Xpg.bytes / sizeof *w->X;
            if (w->Xpg.p && thx_pages_grow(&w->Xpg, (xn ? xn : 1) * sizeof *w->X) == 0) {
                w->X = w->Xpg.p;
                w->fresh = w->X + (kept < xn ? kept : xn);
            } else {
                thx_pages_free(&w->Xpg);
                w->X = calloc(xn ? xn : 1, sizeof *w->X);
                w->fresh = w->X;
            }
            w->E = big_alloc(thx_chol_work_bytes(s->chol, r + C));
            w->acc = malloc(4 * (r > C ? r : C) * sizeof *w->acc);
            w->P = malloc(nd * r * sizeof *w->P);
            w->Z = malloc((nf ? nf : 1) * C * sizeof *w->Z);
            w->Pz = malloc(nd * C * sizeof *w->Pz);
            w->r = w->X && w->E && w->acc && w->P && w->Z && w->Pz ? r : 0;
        }
        if (!w->r) failed = 1;
        else {
            double *rn = w->acc + 2 * r, *bn = w->acc + 3 * r;
            /* rows of ld values: the rows out carry the check's combinations after the r columns */
            const size_t C = io->need ? THX_FEM_CHECK_COMBOS : 0, ld = r + C;
            if (phi) own_gather_rows(phi, n, c0, r, s->pres_node, (size_t)s->nd, w->P);
            else own_gather_pres(io, (size_t)s->nd, c0, r, w->P);
            /* the rows the sweeps use made zero (the rest never touched), or all of them */
            if (w->fresh && io->need) thx_chol_prepare_rows(s->chol, w->X, ld, io->need, io->reach, w->fresh);
            own_rhs(s, w->P, load, c0, r, w->X, ld, w->fresh && io->need);
            w->fresh = NULL;
            if (io->need) {
                own_rhs_norms(s, w->X, r, ld, bn);
                own_check_prepare(s, w, c0, r, bn);
            }
            if (top) { /* below the top, then (once it is factored) the rest */
                w->flops += thx_chol_solve_rows_part(s->chol, w->X, r, C, w->Z, w->E, io->need, io->reach, top, 1);
                if (own_top_wait(&tw) < 0) continue;
                w->flops += thx_chol_solve_rows_part(s->chol, w->X, r, C, w->Z, w->E, io->need, io->reach, top, 2);
            } else
                w->flops += thx_chol_solve_rows_with(s->chol, w->X, r, C, w->Z, w->E, io->need, io->reach);
            if (!io->need) {
                own_residual(s, w->P, load, c0, w->X, r, w->acc, rn, bn);
                for (size_t j = 0; j < r; j++) rel[c0 + j] = bn[j] > 0 ? sqrt(rn[j] / bn[j]) : sqrt(rn[j]);
            }
            if (phi) {
                /* the free values into phi, a block of rows at a time (each column's writes near each other);
                   nodes neither free nor prescribed are 0 */
                for (size_t q0 = 0; q0 < nf; q0 += 256) {
                    size_t q1 = q0 + 256 < nf ? q0 + 256 : nf;
                    for (size_t j = 0; j < r; j++) {
                        double *pj = phi + (c0 + j) * n;
                        for (size_t q = q0; q < q1; q++) pj[s->free_node[q]] = w->X[(size_t)iperm[q] * r + j];
                    }
                }
                for (size_t j = 0; j < r; j++)
                    for (int32_t i = 0; i < s->n; i++)
                        if (s->fidx[i] < 0 && s->didx[i] < 0) phi[(c0 + j) * n + (size_t)i] = 0;
            } else {
                /* the rows asked for: a free node's answer, a prescribed node's value, else 0; 256 rows at a
                   time, so that each frame's writes are near each other */
                for (size_t i0 = 0; i0 < io->m; i0 += 256) {
                    const size_t i1 = i0 + 256 < io->m ? i0 + 256 : io->m;
                    const double *src[256];
                    for (size_t i = i0; i < i1; i++) {
                        int32_t node = io->rows[i], f = s->fidx[node], d = s->didx[node];
                        src[i - i0] = f >= 0 ? w->X + (size_t)iperm[f] * ld : d >= 0 ? w->P + (size_t)d * r : NULL;
                    }
                    for (size_t j = 0; j < r; j++) {
                        double *o = io->out + (c0 + j) * io->m;
                        for (size_t i = i0; i < i1; i++) o[i] = src[i - i0] ? src[i - i0][j] : 0;
                    }
                }
                if (io->spoil > c0 && io->spoil <= c0 + r)
                    for (size_t i = 0; i < io->m; i++) io->out[(io->spoil - 1) * io->m + i] *= 1 + io->spoil_by;
                if (io->need) own_check_finish(s, io, w, t, c0, r);
            }
        }
    }
    if (was > 0) blas_threads(was);
    if (!thx_chol_top_left(s->chol)) fem_own_top_drop(s); /* the top done: what it needed given back */
    thx_chol_drop_spare(s->chol);                          /* and the working memory no block took */
    if (top_st != THX_OK) return top_st;
    return failed ? thx_error(ctx, THX_ENOMEM, "fem: out of memory for a block of %zu right-hand sides", k) : THX_OK;
}

static thx_status own_verdict(thx_ctx *ctx, const double *rel, size_t k, thx_status st, thx_fem_solve_stats *out);

/* The verdict on a block solved for some rows alone (THX_FEM_CHECK_COMBOS): every thread's combinations, in the
   threads' order. */
static thx_status own_check(thx_ctx *ctx, const own_io *io, size_t k, thx_fem_solve_stats *out)
{
    const size_t C = THX_FEM_CHECK_COMBOS;
    const int T = own_threads(k);
    for (int t = 0; t < T; t++)
        for (size_t c = 0; c < C; c++) {
            const double *pt = io->part + ((size_t)t * C + c) * 3, rel = pt[0], diff = pt[1], scale = pt[2];
            if (out) out->residual = fmax(out->residual, rel);
            if (!(rel <= THX_FEM_DIRECT_RTOL))
                return thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization's answer "
                                 "leaves a relative residual of %g for a combination of the right-hand sides of a block "
                                 "of %zu: the system is singular, e.g. currents into a part of the mesh with no prescribed "
                                 "potential)", rel, k);
            if (out) out->check = fmax(out->check, scale > 0 ? diff / scale : diff);
            if (!(diff <= THX_FEM_CHECK_RTOL * scale))
                return thx_error(ctx, THX_EINTERNAL, "fem: a block of %zu right-hand sides solved for %zu rows disagrees "
                                 "with a combination of its columns solved in full (%g of its scale, above %g)", k, io->m,
                                 scale > 0 ? diff / scale : diff, THX_FEM_CHECK_RTOL);
        }
    return THX_OK;
}

/* The own path for k columns: factor once, solve, refuse a singular system as the PETSc path does. */
thx_status fem_own_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k,
                               thx_fem_solve_stats *out)
{
    double t0 = thx_wtime();
    if (s->pinned >= 0)
        for (size_t j = 0; j < k; j++) phi[j * (size_t)s->n + (size_t)s->pinned] = 0;
    double *rel = thx_malloc(ctx, (k ? k : 1) * sizeof *rel);
    if (!rel) return THX_ENOMEM;
    own_io io = {.phi = phi, .load = load};
    thx_status st = own_solve(ctx, s, &io, k, rel);
    st = own_verdict(ctx, rel, k, st, out);
    free(rel);
    if (out) out->seconds += thx_wtime() - t0;
    return st;
}

/* The residuals' verdict: a block whose relative residual is above THX_FEM_DIRECT_RTOL anywhere is refused. */
static thx_status own_verdict(thx_ctx *ctx, const double *rel, size_t k, thx_status st, thx_fem_solve_stats *out)
{
    for (size_t j = 0; j < k && st == THX_OK; j++) {
        if (!(rel[j] <= THX_FEM_DIRECT_RTOL))
            st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization's answer leaves a "
                           "relative residual of %g at right-hand side %zu of a block of %zu: the system is singular, e.g. "
                           "currents into a part of the mesh with no prescribed potential)", rel[j], j + 1, k);
        if (out) out->residual = fmax(out->residual, rel[j]);
    }
    return st;
}

thx_status fem_own_solve_rows(thx_ctx *ctx, thx_fem_system *s, const int32_t *from, size_t np, const double *pres,
                              size_t k, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *sum)
{
    thx_status st = THX_OK;
    unsigned char *need = NULL, *reach = NULL;
    double *part = NULL;
    /* blocks of x alone (no column of every node is made) */
    size_t nb = s->block;
    if (!nb) {
        PetscInt want = 0;
        PetscBool set = PETSC_FALSE;
        PetscOptionsGetInt(NULL, NULL, "-thorax_block_size", &want, &set);
        nb = set && want >= 1 ? (size_t)want : THX_FEM_OWN_BYTES / (sizeof(double) * (size_t)(s->nf > 0 ? s->nf : 1));
        nb = nb < 1 ? 1 : nb > THX_FEM_OWN_ROWS_MAX ? THX_FEM_OWN_ROWS_MAX : nb;
    }
    /* the backward sweep kept to the supernodes the rows need, each block checked by two combinations of
       its columns solved in full (own_check) instead of every column's residual, which needs every row */
    size_t nbk = nb < k ? nb : k;
    int T = own_threads(nbk);
    const int64_t *iperm = thx_chol_iperm(s->chol);
    int64_t *frow = thx_malloc(ctx, (m ? m : 1) * sizeof *frow);
    need = thx_malloc(ctx, thx_chol_nsuper(s->chol) + 1);
    part = thx_calloc(ctx, (size_t)T * THX_FEM_CHECK_COMBOS * 3, sizeof *part);
    if (!frow || !need || !part) { free(frow); st = THX_ENOMEM; goto done; }
    size_t mf = 0;
    for (size_t i = 0; i < m; i++)
        if (s->fidx[rows[i]] >= 0) frow[mf++] = iperm[s->fidx[rows[i]]];
    sum->backward_share = thx_chol_needed(s->chol, frow, mf, need);
    /* the supernodes the forward sweep can reach: those of the rows b lives on (coupled to a prescribed
       node) and their ancestors */
    reach = thx_malloc(ctx, thx_chol_nsuper(s->chol) + 1);
    int64_t *brow = reach ? thx_malloc(ctx, ((size_t)s->nf ? (size_t)s->nf : 1) * sizeof *brow) : NULL;
    if (!brow) { free(frow); st = THX_ENOMEM; goto done; }
    size_t mb = 0;
    for (size_t q = 0; q < (size_t)s->nf; q++)
        if (s->kfd.row[q + 1] > s->kfd.row[q]) brow[mb++] = iperm[q];
    thx_chol_needed(s->chol, brow, mb, reach);
    free(brow);
    free(frow);
    for (size_t j0 = 0; j0 < k && st == THX_OK; j0 += nb) {
        size_t kk = k - j0 < nb ? k - j0 : nb;
        double t0 = thx_wtime();
        own_io io = {.pres = pres + j0 * np, .from = from, .np = np, .rows = rows, .m = m, .out = out + j0 * m,
                     .need = need, .reach = reach, .part = part};
        {
            /* the check's own test (tests/test_fem_block.c): column J of the whole call (1-based) made wrong by
               a relative EPS as the solve writes it, before the check */
            PetscInt J = 0;
            PetscReal eps = 1e-6;
            PetscBool set = PETSC_FALSE;
            PetscOptionsGetInt(NULL, NULL, "-thorax_test_spoil_column", &J, &set);
            PetscOptionsGetReal(NULL, NULL, "-thorax_test_spoil_by", &eps, NULL);
            if (set && J >= 1 && (size_t)J > j0 && (size_t)J <= j0 + kk) {
                io.spoil = (size_t)J - j0;
                io.spoil_by = (double)eps;
            }
            PetscBool fail_top = PETSC_FALSE;
            PetscOptionsHasName(NULL, NULL, "-thorax_test_fail_top", &fail_top);
            io.fail_top = fail_top == PETSC_TRUE;
        }
        st = own_solve(ctx, s, &io, kk, NULL);
        if (st == THX_OK) st = own_check(ctx, &io, kk, sum);
        sum->seconds += thx_wtime() - t0;
    }
    sum->iterations = sum->iterations_min = 1;
    sum->iterations_total = (long)k;
    sum->block = nb < k ? nb : k;
done:
    free(need);
    free(reach);
    free(part);
    return st;
}
