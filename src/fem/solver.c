/*
 * The PETSc side of thorax/fem/fem.h: the free-node system K_ff, its KSP, and
 * solves. Every rank holds the whole assembled matrix (thx_csr) and hands
 * PETSc its own block of rows; results are gathered to every rank. thorax's own direct path (one rank,
 * many right-hand sides, its own factor) is src/fem/solver_own.c; what both share, src/fem/solver_internal.h.
 */
#include <math.h>
#include <petscksp.h>
#include <stddef.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem/solver_internal.h"
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

/* The own path's factor and blocks given back by a thread of their own (thx_fem_system_destroy), while the caller
   goes on (writes its answers): munmap of the high phantom's 1 GB took 0.05 s of a quiet machine, alone. One at a
   time; joined before the next, and by thx_fem_finalize. */
static struct {
    pthread_mutex_t lock;
    pthread_t thread;
    int running;
} g_reap = {PTHREAD_MUTEX_INITIALIZER, 0, 0};

typedef struct {
    thx_chol *chol;
    own_work *work;
} reap_job;

static void reap_free(thx_chol *chol, own_work *work)
{
    thx_chol_free(&chol);
    if (work)
        for (int t = 0; t < THX_FEM_OWN_THREADS; t++) fem_own_work_free(&work[t]);
    free(work);
}

static void *reap_main(void *arg)
{
    reap_job *j = arg;
    reap_free(j->chol, j->work);
    free(j);
    return NULL;
}

static void reap_join_locked(void)
{
    if (g_reap.running) pthread_join(g_reap.thread, NULL);
    g_reap.running = 0;
}

static void reap_later(thx_chol *chol, own_work *work)
{
    reap_job *j = malloc(sizeof *j);
    if (j) {
        j->chol = chol;
        j->work = work;
        pthread_mutex_lock(&g_reap.lock);
        reap_join_locked();
        g_reap.running = pthread_create(&g_reap.thread, NULL, reap_main, j) == 0;
        pthread_mutex_unlock(&g_reap.lock);
        if (g_reap.running) return;
        free(j);
    }
    reap_free(chol, work); /* no thread: now */
}

void thx_fem_finalize(void)
{
    pthread_mutex_lock(&g_reap.lock);
    reap_join_locked();
    pthread_mutex_unlock(&g_reap.lock);
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
    /* local CSR of K_ff (global free columns) and K_fd: each row's counts, their sums, then the rows filled, the
       rows shared by the threads */
    {
        ii = thx_calloc(ctx, (size_t)m + 1, sizeof *ii);
        s->kfd.n_rows = (int32_t)m;
        s->kfd.n_cols = s->nd;
        s->kfd.row = thx_calloc(ctx, (size_t)m + 1, sizeof *s->kfd.row);
        if (!ii || !s->kfd.row) { st = THX_ENOMEM; goto done; }
        PetscInt empty = PETSC_MAX_INT; /* the first own row that was not assembled */
#pragma omp parallel for schedule(static) reduction(min : empty)
        for (PetscInt r = s->rstart; r < s->rend; r++) {
            int32_t i = s->free_node[r];
            PetscInt a = 0;
            int64_t d = 0;
            for (int64_t k = K->row[i]; k < K->row[i + 1]; k++) {
                int32_t j = K->col[k];
                if (s->fidx[j] >= 0) a++;
                else if (s->didx[j] >= 0) d++;
            }
            ii[r - s->rstart + 1] = a;
            s->kfd.row[r - s->rstart + 1] = d;
            if (K->row[i] == K->row[i + 1] && r < empty) empty = r;
        }
        if (empty != PETSC_MAX_INT)
            { st = thx_error(ctx, THX_EINTERNAL, "fem: rank %d owns node %d's row, which was not assembled", my_rank, s->free_node[empty] + 1); goto done; }
        for (PetscInt r = 0; r < m; r++) {
            ii[r + 1] += ii[r];
            s->kfd.row[r + 1] += s->kfd.row[r];
        }
        int64_t nnz_ff = ii[m], nnz_fd = s->kfd.row[m];
        jj = thx_malloc(ctx, (size_t)(nnz_ff ? nnz_ff : 1) * sizeof *jj);
        aa = thx_malloc(ctx, (size_t)(nnz_ff ? nnz_ff : 1) * sizeof *aa);
        s->kfd.col = thx_malloc(ctx, (size_t)(nnz_fd ? nnz_fd : 1) * sizeof *s->kfd.col);
        s->kfd.val = thx_malloc(ctx, (size_t)(nnz_fd ? nnz_fd : 1) * sizeof *s->kfd.val);
        if (!jj || !aa || !s->kfd.col || !s->kfd.val) { st = THX_ENOMEM; goto done; }
#pragma omp parallel for schedule(static)
        for (PetscInt r = s->rstart; r < s->rend; r++) {
            int32_t i = s->free_node[r];
            PetscInt a = ii[r - s->rstart];
            int64_t d = s->kfd.row[r - s->rstart];
            for (int64_t k = K->row[i]; k < K->row[i + 1]; k++) {
                int32_t j = K->col[k];
                if (s->fidx[j] >= 0) { jj[a] = s->fidx[j]; aa[a] = K->val[k]; a++; }
                else if (s->didx[j] >= 0) { s->kfd.col[d] = s->didx[j]; s->kfd.val[d] = K->val[k]; d++; }
            }
        }
        /* columns of K are sorted: without a partition the free numbering keeps the node order and
           rows stay sorted; with one, each row is sorted again */
        if (part)
            for (PetscInt r = 0; r < m; r++) sort_row(jj + ii[r], aa + ii[r], ii[r + 1] - ii[r]);
    }
    PetscBool mat_type = PETSC_FALSE;
    PCALL(ctx, PetscOptionsHasName(NULL, NULL, "-mat_type", &mat_type));
    if (n_ranks == 1) { /* the whole K_ff: kept for thorax's own direct path, freed after the matrix */
        s->ii = ii;
        s->jj = jj;
        s->aa = aa;
        ii = jj = NULL;
        aa = NULL;
    }
    if (s->ii && !mat_type) {
        /* one rank: PETSc's matrix over that CSR itself (52 MB not copied on the high phantom); -mat_type asks
           for a matrix of PETSc's own, copied */
        PCALL(ctx, MatCreateSeqAIJWithArrays(PETSC_COMM_WORLD, m, m, s->ii, s->jj, s->aa, &s->A));
        PCALL(ctx, MatSetOption(s->A, MAT_SYMMETRIC, PETSC_TRUE));
        PCALL(ctx, MatSetOption(s->A, MAT_SPD, PETSC_TRUE));
    } else {
        PCALL(ctx, MatCreate(PETSC_COMM_WORLD, &s->A));
        PCALL(ctx, MatSetSizes(s->A, m, m, s->nf, s->nf));
        PCALL(ctx, MatSetType(s->A, MATAIJ));
        PCALL(ctx, MatSetOption(s->A, MAT_SYMMETRIC, PETSC_TRUE));
        PCALL(ctx, MatSetOption(s->A, MAT_SPD, PETSC_TRUE));
        PCALL(ctx, MatSetFromOptions(s->A));
        const PetscInt *ci = s->ii ? s->ii : ii, *cj = s->ii ? s->jj : jj;
        const PetscScalar *ca = s->ii ? s->aa : aa;
        PCALL(ctx, MatSeqAIJSetPreallocationCSR(s->A, ci, cj, ca));
        PCALL(ctx, MatMPIAIJSetPreallocationCSR(s->A, ci, cj, ca));
        PCALL(ctx, MatAssemblyBegin(s->A, MAT_FINAL_ASSEMBLY));
        PCALL(ctx, MatAssemblyEnd(s->A, MAT_FINAL_ASSEMBLY));
    }
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
    if (s->chol || s->work) reap_later(s->chol, s->work); /* the factor and the blocks: by a thread of their own */
    s->chol = NULL;
    s->work = NULL;
    fem_own_top_drop(s);
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
    out->top_beside = c->mf.beside;
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


thx_status thx_fem_solve(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, int warm,
                         thx_fem_solve_stats *out)
{
    thx_status st = THX_OK;
    double t0 = thx_wtime();
    if (s->own) THX_CHECK(fem_own_factor(ctx, s, 0)); /* may hand the system back to PETSc */
    if (s->own) {
        thx_fem_solve_stats one;
        memset(&one, 0, sizeof one);
        st = fem_own_solve_block(ctx, s, phi, load, 1, &one);
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
    if (s->own) THX_TRY(fem_own_factor(ctx, s, 0)); /* may hand the system back to PETSc */
    if (s->own) {
        size_t nb = thx_fem_system_block(s);
        for (size_t j0 = 0; j0 < k; j0 += nb)
            THX_TRY(fem_own_solve_block(ctx, s, phi + j0 * n, load ? load + j0 * n : NULL, k - j0 < nb ? k - j0 : nb, &sum));
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
    double *phi = NULL;
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
    /* the top of the factorization beside the first block's start (src/fem/solver_own.c) */
    if (s->own) THX_TRY(fem_own_factor(ctx, s, 1)); /* may hand the system back to PETSc */
    if (s->own) {
        /* blocks of x alone (no column of every node is made): src/fem/solver_own.c */
        st = fem_own_solve_rows(ctx, s, from, np, pres, k, rows, m, out, &sum);
        if (!(st == THX_ESOLVER && s->chol_info.not_posdef && s->chol_info.mf.beside)) goto done;
        /* the top, factored beside the first block, met a zero pivot: PETSc's interface to the same package
           decides, as fem_own_factor hands a singular system over when the subtrees meet one */
        thx_ctx_clear(ctx);
        fem_own_top_drop(s);
        thx_chol_free(&s->chol);
        s->own = 0;
        s->pc_ready = 0;
        st = THX_OK;
        memset(&sum, 0, sizeof sum);
        sum.iterations_min = 1 << 30;
        sum.converged = 1;
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
    if (stats) *stats = sum;
    return st;
}
