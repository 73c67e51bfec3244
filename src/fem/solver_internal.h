/*
 * The solver module's own shared parts (src/fem/solver.c: PETSc's systems and solves; src/fem/solver_own.c:
 * thorax's own direct path on its factor, docs/design/parallel.md): the system's structure, the own path's
 * per-thread buffers, the block sizes and tolerances, and the calls solver.c makes into the own path.
 * Built into the solver module alone.
 */
#ifndef THORAX_FEM_SOLVER_INTERNAL_H
#define THORAX_FEM_SOLVER_INTERNAL_H

#include <petscksp.h>
#include <stdlib.h>
#include <string.h>

#include "fem/cholesky.h"
#include "thorax/fem/fem.h"

/* A thread's buffers for the own path: x (b before the solve) of up to r columns (row-major, the factor's order), the
   solve's work space, the residual's sums. Kept across blocks (fresh pages cost a fault each, and faults
   are dear on virtual machines). */
#define THX_FEM_OWN_THREADS 64
typedef struct own_work_s {
    double *X, *E, *acc, *P; /* P: the prescribed values of the r columns, row-major */
    double *Z, *Pz;          /* the check's combinations of the r columns (src/fem/solver_own.c): x, prescribed values */
    double *fresh;           /* X from here on is zeros, its pages not yet touched; NULL: X holds anything */
    thx_pages Xpg;           /* X's pages when X is made of the factorization's spare memory (else X from calloc) */
    size_t r;
    double flops; /* the solves' flops so far (thx_chol_solve_rows) */
} own_work;

/* The top's state and A's pattern kept for it (fem_own_factor's defer_top) given back; nothing when none. */
void fem_own_top_drop(thx_fem_system *s);

/* A thread's buffers freed (the system's destruction). */
void fem_own_work_free(own_work *w);

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
    int64_t *top_rowp;       /* A's pattern in the factor's terms while its top is left (fem_own_factor's defer_top) */
    int32_t *top_col;
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

/* The own path (src/fem/solver_own.c). The factorization, once, when s->own; on a singular system it hands
 * the system back to PETSc (s->own = 0) and returns THX_OK. */
thx_status fem_own_factor(thx_ctx *ctx, thx_fem_system *s, int defer_top);
/* k columns of every node (phi, load: as thx_fem_solve_block takes them) through the factor, each column's
 * residual checked. */
thx_status fem_own_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k,
                               thx_fem_solve_stats *out);
/* thx_fem_solve_rows on the factor: the prescribed values (from[d]: prescribed node d's column in pres, np a
 * frame; -2 the pinned node) in, the m rows asked for out, in blocks; the backward sweep kept to the
 * supernodes the rows need and each block checked by two combinations of its columns. sum: the stats. */
thx_status fem_own_solve_rows(thx_ctx *ctx, thx_fem_system *s, const int32_t *from, size_t np, const double *pres,
                              size_t k, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *sum);

#endif
