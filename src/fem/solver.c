/*
 * The PETSc side of thorax/fem/fem.h: the free-node system K_ff, its KSP, and
 * solves. Every rank holds the whole assembled matrix (thx_csr) and hands
 * PETSc its own block of rows; results are gathered to every rank.
 */
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <petscksp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "fem/cholesky.h"
#include "thorax/core/hash.h"
#include "thorax/core/cores.h"
#include "thorax/fem/fem.h"
#ifdef _OPENMP
#include <omp.h>
#endif
static int g_inited = 0, g_we_inited = 0;

thx_status thx_fem_init(int argc, char **argv, int *rank, int *size)
{
    if (!g_inited) {
        PetscBool already = PETSC_FALSE;
        PetscInitialized(&already);
        if (!already) {
            /* PETSc reads its options from this argv; it keeps the pointer */
            static int s_argc;
            static char **s_argv;
            s_argc = argc;
            s_argv = argv;
            /* A process no launcher started is an MPI singleton: Open MPI would start its daemon (orted) for
               it, 0.3-1.0 s of every solve on this machine, to serve features thorax never uses (spawning
               processes, connecting jobs). Isolated, it starts alone. Nor has it a peer to send to, so its
               point-to-point layer is Open MPI's own (ob1) rather than the search through UCX, PSM and OFI
               for network hardware: MPI_Init 0.23 s -> 0.03 s here. A user's settings are kept; under mpirun
               neither is touched. */
            if (!getenv("OMPI_COMM_WORLD_SIZE")) {
                setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
                setenv("OMPI_MCA_pml", "ob1", 0);
            }
            if (PetscInitialize(&s_argc, &s_argv, NULL, NULL) != 0) return THX_ESOLVER;
            g_we_inited = 1;
        }
        PetscPushErrorHandler(PetscReturnErrorHandler, NULL);
        g_inited = 1;
    }
    PetscMPIInt r = 0, s = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &r);
    MPI_Comm_size(PETSC_COMM_WORLD, &s);
    if (rank) *rank = r;
    if (size) *size = s;
    return THX_OK;
}

void thx_fem_finalize(void)
{
    if (g_inited && g_we_inited) {
        PetscPopErrorHandler();
        PetscFinalize();
    }
    g_inited = g_we_inited = 0;
}

int thx_fem_options_unused(int list)
{
    if (!g_inited) return 0;
    PetscInt left = 0;
    PetscOptionsAllUsed(NULL, &left);
    if (left > 0 && list) {
        PetscMPIInt r = 0;
        MPI_Comm_rank(PETSC_COMM_WORLD, &r);
        if (r == 0) PetscOptionsLeft(NULL);
    }
    return (int)left;
}

/* A thread's buffers for the own path: x (b before the solve) of up to r columns (row-major, the factor's order), the
   solve's work space, the residual's sums. Kept across blocks (fresh pages cost a fault each, and faults
   are dear on virtual machines). */
#define THX_FEM_OWN_THREADS 64
typedef struct own_work_s {
    double *X, *E, *acc, *P; /* P: the prescribed values of the r columns, row-major */
    int zero;                /* X is all zeros (fresh from calloc: its pages not yet touched) */
    size_t r;
    double flops; /* the solves' flops so far (thx_chol_solve_rows) */
} own_work;

static void *big_alloc(size_t bytes)
{
    void *p = NULL;
    size_t align = 64;
    bytes = (bytes + align - 1) / align * align;
    return posix_memalign(&p, align, bytes ? bytes : align) ? NULL : p;
}

static void own_work_free(own_work *w)
{
    free(w->X);
    free(w->P);
    free(w->E);
    free(w->acc);
    memset(w, 0, sizeof *w);
}

struct thx_fem_system {
    int32_t n;           /* nodes */
    int32_t nf, nd;      /* free, prescribed */
    int32_t *fidx;       /* node -> free index or -1 */
    int32_t *didx;       /* node -> prescribed index or -1 */
    int32_t *free_node;  /* free index -> node */
    int32_t *pres_node;  /* prescribed index -> node */
    int32_t pinned;      /* node pinned to 0 (pure Neumann), or -1 */
    PetscInt rstart, rend;
    thx_csr kfd;         /* own free rows x prescribed columns */
    Mat A;
    KSP ksp;
    Vec x, b, xall;
    Vec r;               /* work vector for the true residual of a direct solve */
    VecScatter toall;
    double t_setup;      /* the matrix (creation) and the preconditioner (KSPSetUp) */
    double t_matrix;     /* the matrix alone */
    int pc_ready;
    size_t block;        /* columns per dense block (thx_fem_system_set_block), 0 = automatic */
    /* thorax's own direct path (src/fem/cholesky.h), one rank: K_ff's CSR kept, and its factor */
    PetscInt *ii, *jj;
    PetscScalar *aa;
    int own;             /* 1: many right-hand sides on one rank, no solver chosen on the command line */
    thx_chol *chol;
    thx_chol_info chol_info;
    own_work *work;          /* THX_FEM_OWN_THREADS of them */
};

/* A PETSc call inside a thx function: on failure record the message and jump to done. */
#define PCALL(ctx, call)                                                                      \
    do {                                                                                      \
        PetscErrorCode e_ = (call);                                                           \
        if (e_) {                                                                             \
            const char *txt_ = NULL;                                                          \
            PetscErrorMessage(e_, &txt_, NULL);                                               \
            st = thx_error(ctx, THX_ESOLVER, "PETSc: %s: %s", #call, txt_ ? txt_ : "error"); \
            goto done;                                                                        \
        }                                                                                     \
    } while (0)

thx_status thx_fem_system_create(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                 thx_fem_system **out)
{
    return thx_fem_system_create_parts(ctx, K, kind, pin_one, NULL, out);
}

/* Sorts row r's columns (and values) of a CSR: insertion sort, the rows are short. */
static void sort_row(PetscInt *jj, PetscScalar *aa, PetscInt n)
{
    for (PetscInt x = 1; x < n; x++) {
        PetscInt key = jj[x], y = x - 1;
        PetscScalar v = aa[x];
        while (y >= 0 && jj[y] > key) { jj[y + 1] = jj[y]; aa[y + 1] = aa[y]; y--; }
        jj[y + 1] = key;
        aa[y + 1] = v;
    }
}

thx_status thx_fem_system_create_parts(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                       const int32_t *part, thx_fem_system **out)
{
    *out = NULL;
    if (!g_inited) return thx_error(ctx, THX_EINTERNAL, "fem: thx_fem_init was not called");
    double t0 = thx_wtime();
    thx_status st = THX_OK;
    PetscInt *ii = NULL, *jj = NULL;
    PetscScalar *aa = NULL;
    thx_fem_system *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    int32_t n = K->n_rows;
    s->n = n;
    s->pinned = -1;
    s->fidx = thx_malloc(ctx, (n ? n : 1) * sizeof *s->fidx);
    s->didx = thx_malloc(ctx, (n ? n : 1) * sizeof *s->didx);
    s->free_node = thx_malloc(ctx, (n ? n : 1) * sizeof *s->free_node);
    s->pres_node = thx_malloc(ctx, (n + 1) * sizeof *s->pres_node);
    if (!s->fidx || !s->didx || !s->free_node || !s->pres_node) { st = THX_ENOMEM; goto done; }
    int32_t first_free = -1;
    for (int32_t i = 0; i < n; i++) {
        s->fidx[i] = s->didx[i] = -1;
        if (kind[i] == 2) { s->didx[i] = s->nd; s->pres_node[s->nd++] = i; }
        else if (kind[i] == 1 && first_free < 0) first_free = i;
    }
    if (s->nd == 0) {
        if (!pin_one || first_free < 0)
            { st = thx_error(ctx, THX_EINPUT, "fem: no prescribed potential anywhere: the problem has no unique solution"); goto done; }
        s->pinned = first_free;
        s->didx[first_free] = s->nd;
        s->pres_node[s->nd++] = first_free;
    }
    PetscMPIInt my_rank = 0, n_ranks = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &my_rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &n_ranks);
    PetscInt m = PETSC_DECIDE;
    if (!part) { /* the free nodes in the nodes' order, split in equal ranges */
        for (int32_t i = 0; i < n; i++)
            if (kind[i] == 1 && i != s->pinned) { s->fidx[i] = s->nf; s->free_node[s->nf++] = i; }
    } else { /* a partition: each rank's free nodes together, ranks in order, the nodes' order within */
        for (int32_t i = 0; i < n; i++)
            if (kind[i] == 1 && i != s->pinned && (part[i] < 0 || part[i] >= n_ranks))
                { st = thx_error(ctx, THX_EINTERNAL, "fem: free node %d in part %d of %d ranks", i + 1, part[i], n_ranks); goto done; }
        m = 0;
        for (PetscMPIInt r = 0; r < n_ranks; r++)
            for (int32_t i = 0; i < n; i++)
                if (kind[i] == 1 && i != s->pinned && part[i] == r) {
                    s->fidx[i] = s->nf;
                    s->free_node[s->nf++] = i;
                    m += r == my_rank;
                }
    }
    if (s->nf == 0) { st = thx_error(ctx, THX_EINPUT, "fem: every node is prescribed: nothing to solve"); goto done; }
    /* own rows */
    PetscInt N = s->nf;
    PCALL(ctx, PetscSplitOwnership(PETSC_COMM_WORLD, &m, &N));
    PetscInt rend = 0;
    MPI_Scan(&m, &rend, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD);
    s->rstart = rend - m;
    s->rend = rend;
    /* local CSR of K_ff (global free columns) and K_fd */
    {
        int64_t nnz_ff = 0, nnz_fd = 0;
        for (PetscInt r = s->rstart; r < s->rend; r++) {
            int32_t i = s->free_node[r];
            for (int64_t k = K->row[i]; k < K->row[i + 1]; k++) {
                int32_t j = K->col[k];
                if (s->fidx[j] >= 0) nnz_ff++;
                else if (s->didx[j] >= 0) nnz_fd++;
            }
        }
        ii = thx_malloc(ctx, (size_t)(m + 1) * sizeof *ii);
        jj = thx_malloc(ctx, (size_t)(nnz_ff ? nnz_ff : 1) * sizeof *jj);
        aa = thx_malloc(ctx, (size_t)(nnz_ff ? nnz_ff : 1) * sizeof *aa);
        s->kfd.n_rows = (int32_t)m;
        s->kfd.n_cols = s->nd;
        s->kfd.row = thx_malloc(ctx, (size_t)(m + 1) * sizeof *s->kfd.row);
        s->kfd.col = thx_malloc(ctx, (size_t)(nnz_fd ? nnz_fd : 1) * sizeof *s->kfd.col);
        s->kfd.val = thx_malloc(ctx, (size_t)(nnz_fd ? nnz_fd : 1) * sizeof *s->kfd.val);
        if (!ii || !jj || !aa || !s->kfd.row || !s->kfd.col || !s->kfd.val) { st = THX_ENOMEM; goto done; }
        int64_t a = 0, d = 0;
        ii[0] = 0;
        s->kfd.row[0] = 0;
        for (PetscInt r = s->rstart; r < s->rend; r++) {
            int32_t i = s->free_node[r];
            for (int64_t k = K->row[i]; k < K->row[i + 1]; k++) {
                int32_t j = K->col[k];
                if (s->fidx[j] >= 0) { jj[a] = s->fidx[j]; aa[a] = K->val[k]; a++; }
                else if (s->didx[j] >= 0) { s->kfd.col[d] = s->didx[j]; s->kfd.val[d] = K->val[k]; d++; }
            }
            ii[r - s->rstart + 1] = (PetscInt)a;
            s->kfd.row[r - s->rstart + 1] = d;
            if (i >= 0 && K->row[i] == K->row[i + 1])
                { st = thx_error(ctx, THX_EINTERNAL, "fem: rank %d owns node %d's row, which was not assembled", my_rank, i + 1); goto done; }
        }
        /* columns of K are sorted: without a partition the free numbering keeps the node order and
           rows stay sorted; with one, each row is sorted again */
        if (part)
            for (PetscInt r = 0; r < m; r++) sort_row(jj + ii[r], aa + ii[r], ii[r + 1] - ii[r]);
    }
    PCALL(ctx, MatCreate(PETSC_COMM_WORLD, &s->A));
    PCALL(ctx, MatSetSizes(s->A, m, m, s->nf, s->nf));
    PCALL(ctx, MatSetType(s->A, MATAIJ));
    PCALL(ctx, MatSetOption(s->A, MAT_SYMMETRIC, PETSC_TRUE));
    PCALL(ctx, MatSetOption(s->A, MAT_SPD, PETSC_TRUE));
    PCALL(ctx, MatSetFromOptions(s->A));
    PCALL(ctx, MatSeqAIJSetPreallocationCSR(s->A, ii, jj, aa));
    PCALL(ctx, MatMPIAIJSetPreallocationCSR(s->A, ii, jj, aa));
    PCALL(ctx, MatAssemblyBegin(s->A, MAT_FINAL_ASSEMBLY));
    PCALL(ctx, MatAssemblyEnd(s->A, MAT_FINAL_ASSEMBLY));
    PCALL(ctx, MatCreateVecs(s->A, &s->x, &s->b));
    PCALL(ctx, VecScatterCreateToAll(s->x, &s->toall, &s->xall));
    PCALL(ctx, KSPCreate(PETSC_COMM_WORLD, &s->ksp));
    PCALL(ctx, KSPSetOperators(s->ksp, s->A, s->A));
    PCALL(ctx, KSPSetType(s->ksp, KSPCG));
    {
        PC pc;
        PCALL(ctx, KSPGetPC(s->ksp, &pc));
        PCALL(ctx, PCSetType(pc, PCGAMG));
    }
    PCALL(ctx, KSPSetTolerances(s->ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, 10000));
    PCALL(ctx, KSPSetFromOptions(s->ksp));
    {
        PetscMPIInt size = 1;
        MPI_Comm_size(PETSC_COMM_WORLD, &size);
        if (size == 1) { /* the whole K_ff: kept for thorax's own direct path */
            s->ii = ii;
            s->jj = jj;
            s->aa = aa;
            ii = jj = NULL;
            aa = NULL;
        }
    }
    s->t_setup = s->t_matrix = thx_wtime() - t0;
    *out = s;
    s = NULL;
done:
    free(ii);
    free(jj);
    free(aa);
    thx_fem_system_destroy(&s);
    return st;
}

void thx_fem_system_destroy(thx_fem_system **sp)
{
    if (!sp || !*sp) return;
    thx_fem_system *s = *sp;
    if (s->ksp) KSPDestroy(&s->ksp);
    if (s->A) MatDestroy(&s->A);
    if (s->x) VecDestroy(&s->x);
    if (s->b) VecDestroy(&s->b);
    if (s->xall) VecDestroy(&s->xall);
    if (s->r) VecDestroy(&s->r);
    if (s->toall) VecScatterDestroy(&s->toall);
    thx_csr_free(&s->kfd);
    thx_chol_free(&s->chol);
    if (s->work)
        for (int t = 0; t < THX_FEM_OWN_THREADS; t++) own_work_free(&s->work[t]);
    free(s->work);
    free(s->ii);
    free(s->jj);
    free(s->aa);
    free(s->fidx);
    free(s->didx);
    free(s->free_node);
    free(s->pres_node);
    free(s);
    *sp = NULL;
}

void thx_fem_system_info(const thx_fem_system *s, size_t *n_free, size_t *n_prescribed, double *setup_seconds)
{
    if (n_free) *n_free = (size_t)s->nf;
    if (n_prescribed) *n_prescribed = (size_t)s->nd;
    if (setup_seconds) *setup_seconds = s->t_setup;
}

double thx_fem_system_matrix_seconds(const thx_fem_system *s) { return s->t_matrix; }

void thx_fem_system_factor_info(const thx_fem_system *s, thx_fem_factor_info *out)
{
    memset(out, 0, sizeof *out);
    if (!s->chol) return;
    const thx_chol_info *c = &s->chol_info;
    out->used = 1;
    out->ordering_cached = c->ordering_cached;
    out->symbolic_cached = c->symbolic_cached;
    out->t_ordering = c->t_order;
    out->t_analysis = c->t_analyze;
    out->t_factor = c->t_factor;
    out->flops = c->flops;
    out->nonzeros = c->lnz;
    for (int t = 0; s->work && t < THX_FEM_OWN_THREADS; t++) out->solve_flops += s->work[t].flops;
    out->factor_bytes = c->factor_bytes;
    snprintf(out->cache_note, sizeof out->cache_note, "%s", c->cache_note);
    out->blas_threads = c->blas_threads;
    snprintf(out->numeric, sizeof out->numeric, "%s", c->numeric ? c->numeric : "");
    out->threads = c->mf.threads;
    out->subtrees = c->mf.subtrees;
    out->top = c->mf.top;
    out->top_share = c->mf.top_share;
    out->t_subtrees = c->mf.t_subtrees;
    out->t_top = c->mf.t_top;
}

void thx_fem_system_describe(const thx_fem_system *s, char ksp[32], char pc[32], int *ranks)
{
    KSPType kt = NULL;
    PCType pt = NULL;
    PC p = NULL;
    KSPGetType(s->ksp, &kt);
    KSPGetPC(s->ksp, &p);
    if (p) PCGetType(p, &pt);
    snprintf(ksp, 32, "%s", kt ? kt : "?");
    snprintf(pc, 32, "%s", pt ? pt : "?");
    PetscMPIInt n = 1;
    MPI_Comm_size(PETSC_COMM_WORLD, &n);
    if (ranks) *ranks = n;
}

/* The memory-bounded block (thx_fem_system_block): bytes for the dense blocks, and the most columns. */
#define THX_FEM_BLOCK_BYTES ((size_t)512 << 20)
#define THX_FEM_BLOCK_MAX 64
/* The same for thorax's own path: its blocks are split among the threads, and wider ones keep BLAS busier. */
#define THX_FEM_OWN_BYTES ((size_t)768 << 20)
#define THX_FEM_OWN_MAX 256
/* ... and for thx_fem_solve_rows, whose blocks need no column of every node: x alone within THX_FEM_OWN_BYTES */
#define THX_FEM_OWN_ROWS_MAX 512
/* A factorization's answer whose relative residual ||b - A x|| / ||b|| is above this is refused: a
 * backward-stable Cholesky or LU leaves 1e-15 on these matrices; 1e-3 .. 1e+0 is a singular system
 * (currents into a piece of the mesh with no prescribed potential) whose tiny pivot the package took. */
#define THX_FEM_DIRECT_RTOL 1e-6

/* A factorization in use: -ksp_type preonly with -pc_type cholesky or lu (thx_fem_system_hint_rhs's choice for
 * many right-hand sides, or the command line's). Only then does a dense block of right-hand sides go to the
 * factor at once. */
static int is_direct(const thx_fem_system *s)
{
    KSPType kt = NULL;
    PCType pt = NULL;
    PC pc = NULL;
    KSPGetType(s->ksp, &kt);
    KSPGetPC(s->ksp, &pc);
    if (pc) PCGetType(pc, &pt);
    return kt && pt && !strcmp(kt, KSPPREONLY) && (!strcmp(pt, PCCHOLESKY) || !strcmp(pt, PCLU));
}

/* The own rows of one right-hand side, b = load_f - K_fd phi_d, and of the guess (x may be NULL). */
static void rhs_rows(const thx_fem_system *s, const double *phi, const double *load, int warm, PetscScalar *b,
                     PetscScalar *x)
{
    PetscInt m = s->rend - s->rstart;
    for (PetscInt r = 0; r < m; r++) {
        int32_t i = s->free_node[s->rstart + r];
        double v = load ? load[i] : 0;
        for (int64_t k = s->kfd.row[r]; k < s->kfd.row[r + 1]; k++) v -= s->kfd.val[k] * phi[s->pres_node[s->kfd.col[k]]];
        b[r] = v;
        if (x) x[r] = warm ? phi[i] : 0;
    }
}

static thx_status fill_rhs(thx_ctx *ctx, thx_fem_system *s, const double *phi, const double *load, int warm)
{
    thx_status st = THX_OK;
    PetscScalar *b, *x;
    PCALL(ctx, VecGetArray(s->b, &b));
    PCALL(ctx, VecGetArray(s->x, &x));
    rhs_rows(s, phi, load, warm, b, x);
    PCALL(ctx, VecRestoreArray(s->b, &b));
    PCALL(ctx, VecRestoreArray(s->x, &x));
done:
    return st;
}

thx_status thx_fem_system_dump(thx_ctx *ctx, thx_fem_system *s, const double *phi, const double *load, const char *path)
{
    thx_status st = fill_rhs(ctx, s, phi, load, 0);
    PetscViewer vw = NULL;
    if (st != THX_OK) return st;
    PCALL(ctx, PetscViewerBinaryOpen(PETSC_COMM_WORLD, path, FILE_MODE_WRITE, &vw));
    PCALL(ctx, MatView(s->A, vw));
    PCALL(ctx, VecView(s->b, vw));
done:
    if (vw) PetscViewerDestroy(&vw);
    return st;
}

void thx_fem_system_hint_rhs(thx_fem_system *s, size_t n_rhs)
{
    if (s->pc_ready || n_rhs < 12) return;
    PetscBool k = PETSC_FALSE, p = PETSC_FALSE;
    PetscOptionsHasName(NULL, NULL, "-ksp_type", &k);
    PetscOptionsHasName(NULL, NULL, "-pc_type", &p);
    if (k || p) return;
    PetscMPIInt size = 1;
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    PC pc;
    KSPSetType(s->ksp, KSPPREONLY);
    KSPGetPC(s->ksp, &pc);
    PCSetType(pc, PCCHOLESKY);
    PCFactorSetMatSolverType(pc, size == 1 ? MATSOLVERCHOLMOD : MATSOLVERMUMPS);
    /* one rank: CHOLMOD's factor driven by thorax (src/fem/cholesky.h), unless -thorax_direct petsc asks for
       PETSc's interface to it (the path before; bench/forward.sh compares the two) */
    char how[16] = "thorax";
    PetscOptionsGetString(NULL, NULL, "-thorax_direct", how, sizeof how, NULL);
    s->own = size == 1 && s->ii && strcmp(how, "petsc") != 0;
}

static int blas_threads(int set);
static void set_blas_threads(int n);
static thx_status factor_threads(thx_ctx *ctx, int was, int *use);

/* The own path's factorization, once (timed as the setup, as PETSc's is). */
static thx_status own_factor(thx_ctx *ctx, thx_fem_system *s)
{
    if (s->chol) return THX_OK;
    double t0 = thx_wtime();
    thx_status st = THX_OK;
    size_t n = (size_t)s->nf, nz = (size_t)s->ii[n];
    int64_t *rowp = thx_malloc(ctx, (n + 1) * sizeof *rowp);
    int32_t *col = thx_malloc(ctx, (nz ? nz : 1) * sizeof *col);
    if (!rowp || !col) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i <= n; i++) rowp[i] = (int64_t)s->ii[i];
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
    thx_chol_opts co = {tree > 0 ? tree : 1, use > 0 ? use : 1, was > 0 ? set_blas_threads : NULL, !strcmp(how, "cholmod")};
    st = thx_chol_factor(ctx, (int64_t)n, rowp, col, s->aa, &co, &s->chol, &s->chol_info);
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

/* b = load_f - K_fd phi_d for columns c0 .. c0 + r - 1, row-major in the factor's order. B_zero: B holds
   zeros already (a buffer fresh from calloc, whose pages are not touched: a row the solve never writes then
   costs no page). */
static void own_rhs(const thx_fem_system *s, const double *P, const double *load, size_t c0, size_t r,
                    double *restrict B, int B_zero)
{
    const size_t n = (size_t)s->n, nf = (size_t)s->nf;
    const int64_t *iperm = thx_chol_iperm(s->chol);
    if (!B_zero) memset(B, 0, nf * r * sizeof *B);
    for (size_t q = 0; q < nf; q++) {
        double *restrict bq = B + (size_t)iperm[q] * r;
        for (int64_t e = s->kfd.row[q]; e < s->kfd.row[q + 1]; e++) {
            const double a = s->kfd.val[e], *pd = P + (size_t)s->kfd.col[e] * r;
            for (size_t j = 0; j < r; j++) bq[j] -= a * pd[j];
        }
    }
    if (load)
        for (size_t j = 0; j < r; j++) {
            const double *lj = load + (c0 + j) * n;
            for (size_t q = 0; q < nf; q++) B[(size_t)iperm[q] * r + j] += lj[s->free_node[q]];
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
    /* rows out: the backward sweep kept to the supernodes the rows need (thx_chol_needed), and the check's
       partial sums per thread (own_check): the prescribed values and the answers at the rows of two fixed
       combinations of the columns, and their scales */
    const unsigned char *need, *reach;
    double *part_p, *part_y, *part_s; /* T x nd x 2, T x m x 2, T x 2 */
    size_t spoil;    /* the check's test: column spoil (1-based, 0: none) written times 1 + spoil_by */
    double spoil_by;
} own_io;

/* The check of a block whose answers are kept at some rows alone (the backward sweep pruned): two fixed
   combinations of its columns, column j weighted by w = u_j / ||b_j|| (u_j in [-1, 1) from the column's
   number alone), solved again in full; their residual must be a factorization's, and the rows' answers
   combined with the same weights must equal theirs. */
#define THX_FEM_CHECK_COMBOS 2
/* The combined rows against the combination's own answer: within this of sum_j |w_j| max_i |x_ij| (the
   two solves differ by rounding alone, about 1e-15 of it; a column off by 1e-6 of itself shows in a block
   of 512) */
#define THX_FEM_CHECK_RTOL 1e-9

/* A number in [-1, 1) from i alone: the same weights whatever the threads. */
static double check_weight(uint64_t i) { return thx_hash_signed_unit(i); }

/* ||b_j||^2 of the r columns of B (row-major, the factor's order) where b can be nonzero: the free rows
   coupled to a prescribed node (no loads on this path). */
static void own_rhs_norms(const thx_fem_system *s, const double *B, size_t r, double *restrict bn)
{
    const int64_t *iperm = thx_chol_iperm(s->chol);
    for (size_t j = 0; j < r; j++) bn[j] = 0;
    for (size_t q = 0; q < (size_t)s->nf; q++) {
        if (s->kfd.row[q + 1] == s->kfd.row[q]) continue;
        const double *bq = B + (size_t)iperm[q] * r;
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

/* This thread's share of the check (see THX_FEM_CHECK_COMBOS): its columns' weights, and the prescribed
   values, the answers at the rows and the scale of each combination, summed over its columns. */
static void own_check_part(const thx_fem_system *s, const own_io *io, own_work *w, int t, size_t c0, size_t r,
                           const double *bn)
{
    const size_t nd = (size_t)s->nd, m = io->m, C = THX_FEM_CHECK_COMBOS;
    double *pp = io->part_p + (size_t)t * nd * C, *py = io->part_y + (size_t)t * m * C, *ps = io->part_s + (size_t)t * C;
    double *wt = w->acc; /* C x r weights (acc holds 4 r) */
    for (size_t c = 0; c < C; c++) {
        ps[c] = 0;
        for (size_t j = 0; j < r; j++) {
            double u = check_weight(C * (c0 + j) + c);
            wt[c * r + j] = bn[j] > 0 ? u / sqrt(bn[j]) : 0;
            double mx = 0;
            for (size_t i = 0; i < m; i++) mx = fmax(mx, fabs(io->out[(c0 + j) * m + i]));
            ps[c] += fabs(wt[c * r + j]) * mx;
        }
    }
    for (size_t d = 0; d < nd; d++)
        for (size_t c = 0; c < C; c++) {
            double a = 0;
            for (size_t j = 0; j < r; j++) a += wt[c * r + j] * w->P[d * r + j];
            pp[d * C + c] = a;
        }
    for (size_t i = 0; i < m; i++)
        for (size_t c = 0; c < C; c++) {
            double a = 0;
            for (size_t j = 0; j < r; j++) a += wt[c * r + j] * io->out[(c0 + j) * m + i];
            py[i * C + c] = a;
        }
}

/* k columns through the own factor: dealt to the threads in contiguous groups, each group row-major in the
   factor's order (src/fem/cholesky.h), its residuals ||b - A x|| from the kept CSR. rel[j]: column j's
   relative residual. */
/* The threads own_solve deals k columns to. */
static int own_threads(size_t k)
{
    int T = 1;
#ifdef _OPENMP
    T = omp_get_max_threads();
#endif
    if (T > THX_FEM_OWN_THREADS) T = THX_FEM_OWN_THREADS;
    if ((size_t)T > k) T = (int)k;
    return T < 1 ? 1 : T;
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
#pragma omp parallel for num_threads(T) schedule(static, 1) reduction(| : failed)
    for (int t = 0; t < T; t++) {
        size_t c0 = k * (size_t)t / (size_t)T, c1 = k * (size_t)(t + 1) / (size_t)T, r = c1 - c0;
        own_work *w = &s->work[t];
        if (w->r < r) {
            double done = w->flops;
            own_work_free(w);
            w->flops = done;
            w->X = calloc(nf * r, sizeof *w->X);
            w->zero = 1;
            w->E = big_alloc(thx_chol_work_bytes(s->chol, r));
            w->acc = malloc(4 * r * sizeof *w->acc);
            w->P = malloc(((size_t)s->nd ? (size_t)s->nd : 1) * r * sizeof *w->P);
            w->r = w->X && w->E && w->acc && w->P ? r : 0;
        }
        if (!w->r) failed = 1;
        else {
            double *rn = w->acc + 2 * r, *bn = w->acc + 3 * r;
            if (phi) own_gather_rows(phi, n, c0, r, s->pres_node, (size_t)s->nd, w->P);
            else own_gather_pres(io, (size_t)s->nd, c0, r, w->P);
            if (w->zero && io->need) thx_chol_zero_rows(s->chol, w->X, r, io->need, io->reach);
            own_rhs(s, w->P, load, c0, r, w->X, w->zero && io->need);
            w->zero = 0;
            if (io->need) own_rhs_norms(s, w->X, r, bn);
            w->flops += thx_chol_solve_rows_needed(s->chol, w->X, r, w->E, io->need, io->reach);
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
                /* the rows asked for: a free node's answer, a prescribed node's value, else 0 */
                for (size_t i = 0; i < io->m; i++) {
                    int32_t node = io->rows[i], f = s->fidx[node], d = s->didx[node];
                    const double *src = f >= 0 ? w->X + (size_t)iperm[f] * r : d >= 0 ? w->P + (size_t)d * r : NULL;
                    for (size_t j = 0; j < r; j++) io->out[(c0 + j) * io->m + i] = src ? src[j] : 0;
                }
                if (io->spoil > c0 && io->spoil <= c0 + r)
                    for (size_t i = 0; i < io->m; i++) io->out[(io->spoil - 1) * io->m + i] *= 1 + io->spoil_by;
                if (io->need) own_check_part(s, io, w, t, c0, r, bn);
            }
        }
    }
    if (was > 0) blas_threads(was);
    return failed ? thx_error(ctx, THX_ENOMEM, "fem: out of memory for a block of %zu right-hand sides", k) : THX_OK;
}

static thx_status own_verdict(thx_ctx *ctx, const double *rel, size_t k, thx_status st, thx_fem_solve_stats *out);

/* The check of a block solved for some rows alone (THX_FEM_CHECK_COMBOS): the threads' partial sums added
   in their order, the two combinations solved in full, their residuals (the factorization's verdict, as
   own_verdict gives it column by column on the other path) and their answers at the rows against the rows'
   combined answers. */
static thx_status own_check(thx_ctx *ctx, thx_fem_system *s, const own_io *io, size_t k, thx_fem_solve_stats *out)
{
    const size_t nd = (size_t)s->nd, nf = (size_t)s->nf, m = io->m, C = THX_FEM_CHECK_COMBOS;
    const int T = own_threads(k);
    const int64_t *iperm = thx_chol_iperm(s->chol);
    double *P = calloc((nd ? nd : 1) * C, sizeof *P), *Y = calloc((m ? m : 1) * C, sizeof *Y);
    double *X = big_alloc(nf * C * sizeof *X), *E = big_alloc(thx_chol_work_bytes(s->chol, C));
    double acc[4 * THX_FEM_CHECK_COMBOS], S[THX_FEM_CHECK_COMBOS] = {0};
    thx_status st = THX_OK;
    if (!P || !Y || !X || !E) { st = THX_ENOMEM; goto done; }
    for (int t = 0; t < T; t++) {
        for (size_t q = 0; q < nd * C; q++) P[q] += io->part_p[(size_t)t * nd * C + q];
        for (size_t q = 0; q < m * C; q++) Y[q] += io->part_y[(size_t)t * m * C + q];
        for (size_t c = 0; c < C; c++) S[c] += io->part_s[(size_t)t * C + c];
    }
    own_rhs(s, P, NULL, 0, C, X, 0);
    int was = blas_threads(1); /* two columns: calls too small to share */
    s->work[0].flops += thx_chol_solve_rows(s->chol, X, C, E);
    if (was > 0) blas_threads(was);
    double *rn = acc + 2 * C, *bn = acc + 3 * C;
    own_residual(s, P, NULL, 0, X, C, acc, rn, bn);
    for (size_t c = 0; c < C && st == THX_OK; c++) {
        double rel = bn[c] > 0 ? sqrt(rn[c] / bn[c]) : sqrt(rn[c]);
        if (out) out->residual = fmax(out->residual, rel);
        if (!(rel <= THX_FEM_DIRECT_RTOL)) {
            st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization's answer leaves a "
                           "relative residual of %g for a combination of the %zu right-hand sides of a block: the system "
                           "is singular, e.g. currents into a part of the mesh with no prescribed potential)", rel, k);
            break;
        }
        double diff = 0;
        for (size_t i = 0; i < m; i++) {
            int32_t node = io->rows[i], f = s->fidx[node], d = s->didx[node];
            double x = f >= 0 ? X[(size_t)iperm[f] * C + c] : d >= 0 ? P[(size_t)d * C + c] : 0;
            diff = fmax(diff, fabs(Y[i * C + c] - x));
        }
        if (out) out->check = fmax(out->check, S[c] > 0 ? diff / S[c] : diff);
        if (!(diff <= THX_FEM_CHECK_RTOL * S[c]))
            st = thx_error(ctx, THX_EINTERNAL, "fem: a block of %zu right-hand sides solved for %zu rows disagrees with a "
                           "combination of its columns solved alone (%g of its scale, above %g)", k, m,
                           S[c] > 0 ? diff / S[c] : diff, THX_FEM_CHECK_RTOL);
    }
done:
    free(P);
    free(Y);
    free(X);
    free(E);
    return st;
}

/* The own path for k columns: factor once, solve, refuse a singular system as the PETSc path does. */
static thx_status own_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k,
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

thx_status thx_fem_solve(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, int warm,
                         thx_fem_solve_stats *out)
{
    thx_status st = THX_OK;
    double t0 = thx_wtime();
    if (s->own) THX_CHECK(own_factor(ctx, s)); /* may hand the system back to PETSc */
    if (s->own) {
        thx_fem_solve_stats one;
        memset(&one, 0, sizeof one);
        st = own_solve_block(ctx, s, phi, load, 1, &one);
        one.iterations = one.iterations_min = 1;
        one.iterations_total = 1;
        one.converged = st == THX_OK;
        if (out) *out = one;
        return st;
    }
    if (s->pinned >= 0) phi[s->pinned] = 0;
    /* b = load_f - K_fd phi_d over the own rows; x = the guess */
    st = fill_rhs(ctx, s, phi, load, warm);
    if (st != THX_OK) goto done;
    {
        KSPType kt;
        PCALL(ctx, KSPGetType(s->ksp, &kt));
        if (kt && !strcmp(kt, KSPPREONLY)) warm = 0; /* a direct solve takes no initial guess */
    }
    PCALL(ctx, KSPSetInitialGuessNonzero(s->ksp, warm ? PETSC_TRUE : PETSC_FALSE));
    if (!s->pc_ready) {
        double t1 = thx_wtime();
        PCALL(ctx, KSPSetUp(s->ksp));
        s->t_setup += thx_wtime() - t1;
        s->pc_ready = 1;
        t0 = thx_wtime();
    }
    PCALL(ctx, KSPSolve(s->ksp, s->b, s->x));
    KSPConvergedReason reason;
    PetscInt its;
    PetscReal rnorm;
    PCALL(ctx, KSPGetConvergedReason(s->ksp, &reason));
    PCALL(ctx, KSPGetIterationNumber(s->ksp, &its));
    PCALL(ctx, KSPGetResidualNorm(s->ksp, &rnorm));
    {
        /* a direct solve (preonly) reports no residual: compute ||b - A x|| */
        KSPType kt;
        PCALL(ctx, KSPGetType(s->ksp, &kt));
        if (kt && !strcmp(kt, KSPPREONLY)) {
            if (!s->r) PCALL(ctx, VecDuplicate(s->b, &s->r));
            PCALL(ctx, MatMult(s->A, s->x, s->r));
            PCALL(ctx, VecAYPX(s->r, -1.0, s->b));
            PCALL(ctx, VecNorm(s->r, NORM_2, &rnorm));
        }
    }
    PetscReal bn = 0;
    PCALL(ctx, VecNorm(s->b, NORM_2, &bn));
    double rel = bn > 0 ? rnorm / bn : rnorm;
    if (out) {
        out->iterations = out->iterations_min = (int)its;
        out->iterations_total = (long)its;
        out->residual = rel;
        out->converged = reason > 0;
    }
    if (reason <= 0) {
        st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (%s after %d iterations, residual %g)",
                       KSPConvergedReasons[reason], (int)its, (double)rnorm);
        goto done;
    }
    if (is_direct(s) && !(rel <= THX_FEM_DIRECT_RTOL)) {
        st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization's answer leaves a "
                       "relative residual of %g: the system is singular, e.g. currents into a part of the mesh with no "
                       "prescribed potential)", rel);
        goto done;
    }
    /* to every rank */
    PCALL(ctx, VecScatterBegin(s->toall, s->x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
    PCALL(ctx, VecScatterEnd(s->toall, s->x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
    {
        const PetscScalar *xa;
        PCALL(ctx, VecGetArrayRead(s->xall, &xa));
        for (int32_t k = 0; k < s->nf; k++) phi[s->free_node[k]] = xa[k];
        PCALL(ctx, VecRestoreArrayRead(s->xall, &xa));
    }
    for (int32_t i = 0; i < s->n; i++)
        if (s->fidx[i] < 0 && s->didx[i] < 0) phi[i] = 0;
    if (out) out->seconds = thx_wtime() - t0;
done:
    return st;
}

void thx_fem_system_set_block(thx_fem_system *s, size_t k) { s->block = k; }

size_t thx_fem_system_block(const thx_fem_system *s)
{
    if (!is_direct(s)) return 1;
    if (s->block) return s->block;
    PetscInt want = 0;
    PetscBool set = PETSC_FALSE;
    PetscOptionsGetInt(NULL, NULL, "-thorax_block_size", &want, &set);
    if (set && want >= 1) return (size_t)want;
    if (s->own) {
        /* per right-hand side: the caller's column of every node, and one of the free nodes in the solve (x,
           row-major); the factor itself is on top */
        size_t k = THX_FEM_OWN_BYTES / (sizeof(double) * ((size_t)(s->n > 0 ? s->n : 1) + (size_t)s->nf));
        return k < 1 ? 1 : k > THX_FEM_OWN_MAX ? THX_FEM_OWN_MAX : k;
    }
    /* five columns of every node's value per right-hand side live at once: the caller's block, PETSc's
       dense B and X, CHOLMOD's workspace and the residual's block (docs/decisions.md) */
    size_t k = THX_FEM_BLOCK_BYTES / (5 * sizeof(double) * (size_t)(s->n > 0 ? s->n : 1));
    return k < 1 ? 1 : k > THX_FEM_BLOCK_MAX ? THX_FEM_BLOCK_MAX : k;
}

/* Columns j0 .. j0 + k - 1 in one MatMatSolve with the factor; phi, load point at column j0. */
static thx_status solve_dense_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k,
                                    thx_fem_solve_stats *out)
{
    thx_status st = THX_OK;
    Mat B = NULL, X = NULL, R = NULL, F = NULL;
    PetscReal *rn = NULL, *bn = NULL;
    PetscScalar *pb = NULL, *px = NULL;
    size_t n = (size_t)s->n;
    PetscInt m = s->rend - s->rstart, kk = (PetscInt)k, ldb = 0, ldx = 0;
    PetscMPIInt size = 1;
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    PC pc;
    PCALL(ctx, KSPGetPC(s->ksp, &pc));
    PCALL(ctx, PCFactorGetMatrix(pc, &F));
    PCALL(ctx, MatCreateDense(PETSC_COMM_WORLD, m, PETSC_DECIDE, s->nf, kk, NULL, &B));
    PCALL(ctx, MatCreateDense(PETSC_COMM_WORLD, m, PETSC_DECIDE, s->nf, kk, NULL, &X));
    PCALL(ctx, MatDenseGetLDA(B, &ldb));
    PCALL(ctx, MatDenseGetArrayWrite(B, &pb));
    for (size_t j = 0; j < k; j++)
        rhs_rows(s, phi + j * n, load ? load + j * n : NULL, 0, pb + j * (size_t)ldb, NULL);
    PCALL(ctx, MatDenseRestoreArrayWrite(B, &pb));
    PCALL(ctx, MatMatSolve(F, B, X));
    {
        MatFactorError fe = MAT_FACTOR_NOERROR;
        PCALL(ctx, MatFactorGetError(F, &fe));
        if (fe != MAT_FACTOR_NOERROR) {
            st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization failed: %s)",
                           fe == MAT_FACTOR_STRUCT_ZEROPIVOT    ? "structurally zero pivot"
                           : fe == MAT_FACTOR_NUMERIC_ZEROPIVOT ? "zero pivot: the matrix is singular"
                           : fe == MAT_FACTOR_OUTMEMORY         ? "out of memory"
                                                                : "the package's error");
            goto done;
        }
    }
    /* the true residuals, as a direct thx_fem_solve reports them: ||B - A X|| column by column */
    rn = thx_malloc(ctx, 2 * k * sizeof *rn);
    if (!rn) { st = THX_ENOMEM; goto done; }
    bn = rn + k;
    PCALL(ctx, MatMatMult(s->A, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &R));
    PCALL(ctx, MatAXPY(R, -1.0, B, SAME_NONZERO_PATTERN));
    PCALL(ctx, MatGetColumnNorms(R, NORM_2, rn));
    PCALL(ctx, MatGetColumnNorms(B, NORM_2, bn));
    for (size_t j = 0; j < k; j++) {
        double rel = bn[j] > 0 ? rn[j] / bn[j] : rn[j];
        if (!(rel <= THX_FEM_DIRECT_RTOL)) {
            st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization's answer leaves a "
                           "relative residual of %g at right-hand side %zu of a block of %zu: the system is singular, e.g. "
                           "currents into a part of the mesh with no prescribed potential)", rel, j + 1, k);
            goto done;
        }
        if (out) out->residual = fmax(out->residual, rel);
    }
    /* the free values to every rank: on one rank straight from X, else a column at a time through the scatter */
    PCALL(ctx, MatDenseGetLDA(X, &ldx));
    PCALL(ctx, MatDenseGetArray(X, &px));
    for (size_t j = 0; j < k; j++) {
        double *pj = phi + j * n;
        const PetscScalar *xa = px + j * (size_t)ldx;
        if (size > 1) {
            PCALL(ctx, VecPlaceArray(s->x, xa));
            PCALL(ctx, VecScatterBegin(s->toall, s->x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
            PCALL(ctx, VecScatterEnd(s->toall, s->x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
            PCALL(ctx, VecResetArray(s->x));
            PCALL(ctx, VecGetArrayRead(s->xall, &xa));
        }
        for (int32_t q = 0; q < s->nf; q++) pj[s->free_node[q]] = xa[q];
        if (size > 1) PCALL(ctx, VecRestoreArrayRead(s->xall, &xa));
        for (int32_t i = 0; i < s->n; i++)
            if (s->fidx[i] < 0 && s->didx[i] < 0) pj[i] = 0;
    }
    PCALL(ctx, MatDenseRestoreArray(X, &px));
    px = NULL;
done:
    if (px) MatDenseRestoreArray(X, &px);
    free(rn);
    if (R) MatDestroy(&R);
    if (B) MatDestroy(&B);
    if (X) MatDestroy(&X);
    return st;
}

thx_status thx_fem_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k, int warm,
                               thx_fem_solve_stats *out)
{
    thx_status st = THX_OK;
    size_t n = (size_t)s->n;
    thx_fem_solve_stats sum;
    memset(&sum, 0, sizeof sum);
    sum.iterations_min = 1 << 30;
    sum.converged = 1;
    if (!k) { sum.iterations_min = 0; goto done; }
    if (s->own) THX_TRY(own_factor(ctx, s)); /* may hand the system back to PETSc */
    if (s->own) {
        size_t nb = thx_fem_system_block(s);
        for (size_t j0 = 0; j0 < k; j0 += nb)
            THX_TRY(own_solve_block(ctx, s, phi + j0 * n, load ? load + j0 * n : NULL, k - j0 < nb ? k - j0 : nb, &sum));
        sum.iterations = sum.iterations_min = 1;
        sum.iterations_total = (long)k;
        goto done;
    }
    if (k == 1 || !is_direct(s)) {
        /* column by column: exactly thx_fem_solve, column j > 0 warm-started from column j - 1's solution */
        for (size_t j = 0; j < k; j++) {
            double *pj = phi + j * n;
            if (warm && j > 0)
                for (int32_t q = 0; q < s->nf; q++) pj[s->free_node[q]] = pj[(ptrdiff_t)s->free_node[q] - (ptrdiff_t)n];
            thx_fem_solve_stats ss;
            THX_TRY(thx_fem_solve(ctx, s, pj, load ? load + j * n : NULL, warm, &ss));
            sum.iterations = ss.iterations > sum.iterations ? ss.iterations : sum.iterations;
            sum.iterations_min = ss.iterations < sum.iterations_min ? ss.iterations : sum.iterations_min;
            sum.iterations_total += ss.iterations;
            sum.residual = fmax(sum.residual, ss.residual);
            sum.seconds += ss.seconds;
        }
        goto done;
    }
    /* the factorization once (timed as the setup, as in thx_fem_solve), then dense blocks */
    if (!s->pc_ready) {
        double t1 = thx_wtime();
        PCALL(ctx, KSPSetUp(s->ksp));
        s->t_setup += thx_wtime() - t1;
        s->pc_ready = 1;
        PC pc;
        PCFailedReason why = PC_NOERROR;
        PCALL(ctx, KSPGetPC(s->ksp, &pc));
        PCALL(ctx, PCGetFailedReason(pc, &why));
        if (why != PC_NOERROR) {
            st = thx_error(ctx, THX_ESOLVER, "fem: the linear solve did not converge (the factorization failed: %s)",
                           PCFailedReasons[why]);
            goto done;
        }
    }
    {
        double t0 = thx_wtime();
        size_t nb = thx_fem_system_block(s);
        if (s->pinned >= 0)
            for (size_t j = 0; j < k; j++) phi[j * n + (size_t)s->pinned] = 0;
        for (size_t j0 = 0; j0 < k; j0 += nb) {
            size_t kk = k - j0 < nb ? k - j0 : nb;
            THX_TRY(solve_dense_block(ctx, s, phi + j0 * n, load ? load + j0 * n : NULL, kk, &sum));
        }
        sum.iterations = sum.iterations_min = 1;
        sum.iterations_total = (long)k;
        sum.seconds = thx_wtime() - t0;
    }
done:
    if (out) *out = sum;
    return st;
}

thx_status thx_fem_solve_rows(thx_ctx *ctx, thx_fem_system *s, const int32_t *pnode, size_t np, const double *pres,
                              size_t k, int warm, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *stats)
{
    thx_status st = THX_OK;
    const size_t n = (size_t)s->n, nd = (size_t)s->nd;
    thx_fem_solve_stats sum;
    memset(&sum, 0, sizeof sum);
    sum.iterations_min = 1 << 30;
    sum.converged = 1;
    int32_t *from = thx_malloc(ctx, (nd ? nd : 1) * sizeof *from);
    double *phi = NULL, *part_p = NULL, *part_y = NULL, *part_s = NULL;
    unsigned char *need = NULL, *reach = NULL;
    if (!from) return THX_ENOMEM;
    /* every prescribed node's value from the caller's list (the pinned node of a pure Neumann problem: 0) */
    for (size_t d = 0; d < nd; d++) from[d] = -1;
    if (s->pinned >= 0) from[s->didx[s->pinned]] = -2;
    for (size_t c = 0; c < np; c++) {
        int32_t node = pnode[c];
        if (node < 0 || (size_t)node >= n || s->didx[node] < 0 || node == s->pinned) {
            st = thx_error(ctx, THX_EINTERNAL, "fem: prescribed value %zu is for node %d, which the system does not prescribe",
                           c + 1, node + 1);
            goto done;
        }
        from[s->didx[node]] = (int32_t)c;
    }
    for (size_t d = 0; d < nd; d++)
        if (from[d] == -1) {
            st = thx_error(ctx, THX_EINTERNAL, "fem: prescribed node %d has no value", s->pres_node[d] + 1);
            goto done;
        }
    for (size_t i = 0; i < m; i++)
        if (rows[i] < 0 || (size_t)rows[i] >= n) {
            st = thx_error(ctx, THX_EINTERNAL, "fem: row %zu asks for node %d of %zu", i + 1, rows[i] + 1, n);
            goto done;
        }
    if (!k) { sum.iterations_min = 0; goto done; }
    if (s->own) THX_TRY(own_factor(ctx, s)); /* may hand the system back to PETSc */
    if (s->own) {
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
        part_p = thx_malloc(ctx, (size_t)T * (nd ? nd : 1) * THX_FEM_CHECK_COMBOS * sizeof *part_p);
        part_y = thx_malloc(ctx, (size_t)T * (m ? m : 1) * THX_FEM_CHECK_COMBOS * sizeof *part_y);
        part_s = thx_malloc(ctx, (size_t)T * THX_FEM_CHECK_COMBOS * sizeof *part_s);
        if (!frow || !need || !part_p || !part_y || !part_s) { free(frow); st = THX_ENOMEM; goto done; }
        size_t mf = 0;
        for (size_t i = 0; i < m; i++)
            if (s->fidx[rows[i]] >= 0) frow[mf++] = iperm[s->fidx[rows[i]]];
        sum.backward_share = thx_chol_needed(s->chol, frow, mf, need);
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
                         .need = need, .reach = reach, .part_p = part_p, .part_y = part_y, .part_s = part_s};
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
            }
            st = own_solve(ctx, s, &io, kk, NULL);
            if (st == THX_OK) st = own_check(ctx, s, &io, kk, &sum);
            sum.seconds += thx_wtime() - t0;
        }
        sum.iterations = sum.iterations_min = 1;
        sum.iterations_total = (long)k;
        sum.block = nb < k ? nb : k;
        goto done;
    }
    /* any other solver: columns of every node, as thx_fem_solve_block takes them, a block at a time (the last
       column of a block starts the next one's first when warm) */
    size_t nb = thx_fem_system_block(s);
    nb = nb < k ? nb : k;
    phi = thx_calloc(ctx, n * nb, sizeof *phi);
    if (!phi) { st = THX_ENOMEM; goto done; }
    sum.block = nb;
    for (size_t j0 = 0; j0 < k; j0 += nb) {
        size_t kk = k - j0 < nb ? k - j0 : nb;
        if (j0 > 0 && nb > 1) memcpy(phi, phi + (nb - 1) * n, n * sizeof *phi);
        for (size_t j = 0; j < kk; j++) {
            const double *pj = pres + (j0 + j) * np;
            for (size_t c = 0; c < np; c++) phi[j * n + (size_t)pnode[c]] = pj[c];
        }
        thx_fem_solve_stats ss;
        THX_TRY(thx_fem_solve_block(ctx, s, phi, NULL, kk, warm, &ss));
        sum.iterations = ss.iterations > sum.iterations ? ss.iterations : sum.iterations;
        sum.iterations_min = ss.iterations_min < sum.iterations_min ? ss.iterations_min : sum.iterations_min;
        sum.iterations_total += ss.iterations_total;
        sum.residual = fmax(sum.residual, ss.residual);
        sum.seconds += ss.seconds;
        for (size_t j = 0; j < kk; j++)
            for (size_t i = 0; i < m; i++) out[(j0 + j) * m + i] = phi[j * n + (size_t)rows[i]];
    }
done:
    free(from);
    free(phi);
    free(need);
    free(reach);
    free(part_p);
    free(part_y);
    free(part_s);
    if (stats) *stats = sum;
    return st;
}
