/*
 * thorax's own direct path (src/fem/cholesky.h): CHOLMOD's supernodal factor with a cached METIS
 * ordering, and blocked triangular solves on row-major right-hand sides.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <suitesparse/cholmod.h>

#include "fem/cholesky.h"
#include "fem/multifrontal.h"
#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"

/* BLAS, Fortran calling convention (OpenBLAS behind libblas.so.3) */
void dtrsm_(const char *side, const char *uplo, const char *transa, const char *diag, const int *m, const int *n,
            const double *alpha, const double *a, const int *lda, double *b, const int *ldb);
void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha,
            const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c,
            const int *ldc);

struct thx_chol {
    cholmod_common c;
    cholmod_factor *L;
    double *Lx;    /* the factor's values: our own (multifrontal.h), or CHOLMOD's L->x */
    double *own_x; /* ours, when we computed them */
    int64_t n;
    int64_t *perm, *iperm;
    size_t max_below; /* the most rows below a supernode's diagonal block */
};

static const char k_magic[8] = {'T', 'H', 'X', 'O', 'R', 'D', '0', '1'};

const char *thx_chol_cache_dir(char *buf, size_t n)
{
    const char *d = getenv("THORAX_CACHE_DIR");
    if (d && *d) return snprintf(buf, n, "%s", d) < (int)n ? buf : NULL;
    d = getenv("XDG_CACHE_HOME");
    if (d && *d == '/') return snprintf(buf, n, "%s/thorax", d) < (int)n ? buf : NULL;
    d = getenv("HOME");
    if (d && *d == '/') return snprintf(buf, n, "%s/.cache/thorax", d) < (int)n ? buf : NULL;
    return NULL;
}


/* The graph's key: SHA-256 of a tag, n, rowp and col. */
static void graph_key(int64_t n, const int64_t *rowp, const int32_t *col, unsigned char key[32])
{
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    static const char tag[] = "thorax ordering: METIS nested dissection of a CSR graph, v1";
    thx_sha256_update(&h, tag, sizeof tag);
    thx_sha256_update(&h, &n, sizeof n);
    thx_sha256_update(&h, rowp, (size_t)(n + 1) * sizeof *rowp);
    thx_sha256_update(&h, col, (size_t)rowp[n] * sizeof *col);
    thx_sha256_final(&h, key);
}

static void cache_path(char *buf, size_t n, const char *dir, const unsigned char key[32])
{
    char hex[65];
    for (int i = 0; i < 32; i++) snprintf(hex + 2 * i, 3, "%02x", key[i]);
    snprintf(buf, n, "%s/ordering-%s.bin", dir, hex);
}

/* 1 when perm (n entries) is a permutation of 0..n-1 */
static int is_permutation(const int64_t *perm, int64_t n)
{
    unsigned char *seen = calloc((size_t)(n ? n : 1), 1);
    if (!seen) return 0;
    int ok = 1;
    for (int64_t i = 0; i < n && ok; i++) {
        if (perm[i] < 0 || perm[i] >= n || seen[perm[i]]) ok = 0;
        else seen[perm[i]] = 1;
    }
    free(seen);
    return ok;
}

/* The cached ordering, or 0 (missing, another graph, damaged: the caller computes it again). */
static int cache_read(const char *path, int64_t n, const unsigned char key[32], int64_t *perm)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char magic[8];
    uint64_t nn = 0;
    unsigned char k2[32], sum[32], sum2[32];
    int ok = fread(magic, 1, 8, f) == 8 && !memcmp(magic, k_magic, 8) && fread(&nn, sizeof nn, 1, f) == 1 &&
             nn == (uint64_t)n && fread(k2, 1, 32, f) == 32 && !memcmp(k2, key, 32) &&
             fread(perm, sizeof *perm, (size_t)n, f) == (size_t)n && fread(sum, 1, 32, f) == 32 && fgetc(f) == EOF;
    fclose(f);
    if (!ok) return 0;
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, perm, (size_t)n * sizeof *perm);
    thx_sha256_final(&h, sum2);
    return !memcmp(sum, sum2, 32) && is_permutation(perm, n);
}

/* Writes the ordering atomically (a temporary file renamed); a note on failure, none on success. */
static void cache_write(const char *dir, const char *path, int64_t n, const unsigned char key[32], const int64_t *perm,
                        char *note, size_t note_n)
{
    if (thx_make_dirs(dir)) { snprintf(note, note_n, "cannot create the cache directory %s", dir); return; }
    char tmp[4300];
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    if (!f) { snprintf(note, note_n, "cannot write in the cache directory %s", dir); return; }
    unsigned char sum[32];
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    thx_sha256_update(&h, perm, (size_t)n * sizeof *perm);
    thx_sha256_final(&h, sum);
    uint64_t nn = (uint64_t)n;
    int ok = fwrite(k_magic, 1, 8, f) == 8 && fwrite(&nn, sizeof nn, 1, f) == 1 && fwrite(key, 1, 32, f) == 32 &&
             fwrite(perm, sizeof *perm, (size_t)n, f) == (size_t)n && fwrite(sum, 1, 32, f) == 32;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path)) {
        unlink(tmp);
        snprintf(note, note_n, "cannot write the ordering into the cache directory %s", dir);
    }
}

void thx_chol_free(thx_chol **fp)
{
    if (!fp || !*fp) return;
    thx_chol *f = *fp;
    if (f->L) cholmod_l_free_factor(&f->L, &f->c);
    cholmod_l_finish(&f->c);
    free(f->own_x);
    free(f->perm);
    free(f->iperm);
    free(f);
    *fp = NULL;
}

_Static_assert(sizeof(SuiteSparse_long) == sizeof(int64_t), "CHOLMOD's long integers are 64 bits");

thx_status thx_chol_factor(thx_ctx *ctx, int64_t n, const int64_t *rowp, const int32_t *col, const double *val,
                           const thx_chol_opts *opts, thx_chol **out, thx_chol_info *info)
{
    *out = NULL;
    thx_chol_info inf;
    memset(&inf, 0, sizeof inf);
    thx_status st = THX_OK;
    cholmod_sparse *A = NULL;
    int64_t *order = NULL;
    thx_chol *f = thx_calloc(ctx, 1, sizeof *f);
    if (!f) return THX_ENOMEM;
    cholmod_l_start(&f->c);
    f->c.print = 0;
    f->c.error_handler = NULL;
    f->c.supernodal = CHOLMOD_SUPERNODAL;
    /* CHOLMOD's own relaxed amalgamation (4, 16, 48 columns). With CHOLMOD's numeric factorization the
       coarser 16/64/192 ran faster (3.0 s against 4.8 s); with ours the default is as fast and its factor
       smaller: 695 against 801 MB for the high phantom, 0.96 of the time in paired runs
       (docs/design/parallel.md, "The factorization of our own") */
    f->n = n;
    /* the upper triangle, column by column: CSR row i is column i of the symmetric matrix */
    size_t nz = 0;
    for (int64_t i = 0; i < n; i++)
        for (int64_t k = rowp[i]; k < rowp[i + 1]; k++) nz += col[k] <= i;
    A = cholmod_l_allocate_sparse((size_t)n, (size_t)n, nz, 1, 1, 1, CHOLMOD_REAL, &f->c);
    f->perm = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *f->perm);
    f->iperm = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *f->iperm);
    order = thx_malloc(ctx, (size_t)(n ? n : 1) * sizeof *order);
    if (!A || !f->perm || !f->iperm || !order) { st = THX_ENOMEM; goto done; }
    {
        SuiteSparse_long *Ap = A->p, *Ai = A->i;
        double *Ax = A->x;
        size_t w = 0;
        for (int64_t i = 0; i < n; i++) {
            Ap[i] = (SuiteSparse_long)w;
            for (int64_t k = rowp[i]; k < rowp[i + 1]; k++)
                if (col[k] <= i) { Ai[w] = col[k]; Ax[w] = val[k]; w++; }
        }
        Ap[n] = (SuiteSparse_long)w;
    }
    /* the ordering: the cache, else METIS (stored for the next run) */
    double t0 = thx_wtime();
    unsigned char key[32];
    graph_key(n, rowp, col, key);
    char dir[4096], path[4200];
    const char *cd = thx_chol_cache_dir(dir, sizeof dir);
    if (cd) cache_path(path, sizeof path, cd, key);
    inf.ordering_cached = cd && cache_read(path, n, key, order);
    if (!inf.ordering_cached) {
        if (!cholmod_l_metis(A, NULL, 0, 0, (SuiteSparse_long *)order, &f->c) || f->c.status < 0) {
            st = thx_error(ctx, f->c.status == CHOLMOD_OUT_OF_MEMORY ? THX_ENOMEM : THX_ESOLVER,
                           "fem: the fill-reducing ordering (METIS through CHOLMOD) failed (CHOLMOD status %d)", f->c.status);
            goto done;
        }
        if (cd) cache_write(cd, path, n, key, order, inf.cache_note, sizeof inf.cache_note);
        else snprintf(inf.cache_note, sizeof inf.cache_note, "no cache directory (HOME, XDG_CACHE_HOME and THORAX_CACHE_DIR unset)");
    }
    inf.t_order = thx_wtime() - t0;
    /* the symbolic analysis with exactly that ordering, postordered: the same for a cached and a fresh one */
    t0 = thx_wtime();
    f->c.nmethods = 1;
    f->c.method[0].ordering = CHOLMOD_GIVEN;
    f->c.postorder = 1;
    f->L = cholmod_l_analyze_p(A, (SuiteSparse_long *)order, NULL, 0, &f->c);
    if (!f->L || f->c.status < 0) {
        st = thx_error(ctx, f->c.status == CHOLMOD_OUT_OF_MEMORY ? THX_ENOMEM : THX_ESOLVER,
                       "fem: the symbolic factorization (CHOLMOD) failed (status %d)", f->c.status);
        goto done;
    }
    inf.t_analyze = thx_wtime() - t0;
    inf.flops = f->c.fl; /* the analysis's count, explicit zeros of amalgamated supernodes left out */
    inf.lnz = f->c.lnz;
    inf.n_super = f->L->nsuper;
    {
        const SuiteSparse_long *P = f->L->Perm, *super = f->L->super, *pi = f->L->pi;
        for (int64_t i = 0; i < n; i++) {
            f->perm[i] = P[i];
            f->iperm[P[i]] = i;
        }
        for (size_t s = 0; s < f->L->nsuper; s++) {
            size_t below = (size_t)((pi[s + 1] - pi[s]) - (super[s + 1] - super[s]));
            if (below > f->max_below) f->max_below = below;
        }
    }
    t0 = thx_wtime();
    if (opts && opts->cholmod_numeric) {
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
        /* our own multifrontal factorization on CHOLMOD's symbolic factor (fem/multifrontal.h) */
        if (!f->L->is_super || !f->L->super || !f->L->pi || !f->L->px || !f->L->s) {
            st = thx_error(ctx, THX_ESOLVER, "fem: CHOLMOD's analysis gave no supernodal symbolic factor");
            goto done;
        }
        f->own_x = malloc((f->L->xsize ? f->L->xsize : 1) * sizeof *f->own_x);
        if (!f->own_x) { st = THX_ENOMEM; goto done; }
        thx_mf_symbolic S = {n, (int64_t)f->L->nsuper, (const int64_t *)f->L->super, (const int64_t *)f->L->pi,
                             (const int64_t *)f->L->px, (const int64_t *)f->L->s};
        thx_status e = thx_mf_factor(ctx, &S, rowp, col, val, f->perm, f->iperm, opts ? opts->threads : 1,
                                     opts ? opts->set_blas_threads : NULL, f->own_x, &inf.mf);
        inf.t_factor = thx_wtime() - t0;
        if (e == THX_ESOLVER && inf.mf.not_posdef >= 0) {
            inf.not_posdef = 1;
            inf.bad_column = inf.mf.not_posdef;
        } else if (e != THX_OK) {
            st = e;
            goto done;
        }
        f->Lx = f->own_x;
        inf.numeric = "thorax (multifrontal, subtrees in parallel)";
    }
    if (inf.not_posdef) {
        int64_t bad = inf.bad_column;
        st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization failed: zero or negative "
                       "pivot at row %lld of %lld: the matrix is singular, e.g. currents into a part of the mesh with no "
                       "prescribed potential)", (long long)(bad >= 0 && bad < n ? f->perm[bad] + 1 : bad + 1), (long long)n);
        goto done;
    }
    inf.factor_bytes = f->L->xsize * sizeof(double) + f->L->ssize * sizeof(SuiteSparse_long);
    *out = f;
    f = NULL;
done:
    if (A) cholmod_l_free_sparse(&A, f ? &f->c : &(*out)->c);
    free(order);
    thx_chol_free(&f);
    if (info) *info = inf;
    return st;
}

const int64_t *thx_chol_perm(const thx_chol *f) { return f->perm; }
const int64_t *thx_chol_iperm(const thx_chol *f) { return f->iperm; }

size_t thx_chol_work_bytes(const thx_chol *f, size_t r) { return (f->max_below ? f->max_below : 1) * r * sizeof(double); }

double thx_chol_solve_rows(const thx_chol *f, double *X, size_t r, double *E)
{
    double flops = 0;
    const cholmod_factor *L = f->L;
    const SuiteSparse_long *super = L->super, *pi = L->pi, *px = L->px, *Ls = L->s;
    const double *Lx = f->Lx;
    const size_t ns = L->nsuper;
    const int ir = (int)r;
    const double one = 1, zero = 0, minus = -1;
    /* forward: L Y = B. In column-major terms a supernode's rows of X are X_s^T (r x nscol, ld r). A supernode
       whose rows are all zero (no right-hand side there, no update from below: the forward problem's b lives
       at the nodes next to the heart) is skipped: its rows stay zero and it updates nothing, exactly. */
    for (size_t s = 0; s < ns; s++) {
        int nscol = (int)(super[s + 1] - super[s]), nsrow = (int)(pi[s + 1] - pi[s]), nb = nsrow - nscol;
        const double *L1 = Lx + px[s];
        double *Xs = X + (size_t)super[s] * r;
        size_t z = 0, nz = (size_t)nscol * r;
        while (z < nz && Xs[z] == 0) z++;
        if (z == nz) continue;
        flops += (double)r * nscol * ((double)nscol + 2.0 * nb);
        dtrsm_("R", "L", "T", "N", &ir, &nscol, &one, L1, &nsrow, Xs, &ir);
        if (nb <= 0) continue;
        dgemm_("N", "T", &ir, &nb, &nscol, &one, Xs, &ir, L1 + nscol, &nsrow, &zero, E, &ir);
        const SuiteSparse_long *rows = Ls + pi[s] + nscol;
        for (int t = 0; t < nb; t++) {
            double *xr = X + (size_t)rows[t] * r;
            const double *e = E + (size_t)t * r;
            for (size_t j = 0; j < r; j++) xr[j] -= e[j];
        }
    }
    /* backward: L^T X = Y */
    for (size_t s = ns; s-- > 0;) {
        int nscol = (int)(super[s + 1] - super[s]), nsrow = (int)(pi[s + 1] - pi[s]), nb = nsrow - nscol;
        const double *L1 = Lx + px[s];
        double *Xs = X + (size_t)super[s] * r;
        if (nb > 0) {
            const SuiteSparse_long *rows = Ls + pi[s] + nscol;
            for (int t = 0; t < nb; t++) memcpy(E + (size_t)t * r, X + (size_t)rows[t] * r, r * sizeof *E);
            dgemm_("N", "N", &ir, &nscol, &nb, &minus, E, &ir, L1 + nscol, &nsrow, &one, Xs, &ir);
        }
        dtrsm_("R", "L", "N", "N", &ir, &nscol, &one, L1, &nsrow, Xs, &ir);
        flops += (double)r * nscol * ((double)nscol + 2.0 * nb);
    }
    return flops;
}
