/* Boundary elements under mpirun (thorax/bem/bem.h): each rank assembles a block of rows (the
 * transfer matrix: thx_bem_transfer_rows, the serial code; the symmetric dipole system:
 * thx_bem_symmetric_rows, each row from the pair integrals alone), PETSc's MATSCALAPACK holds the
 * dense system block-cyclically over the ranks, ScaLAPACK's LU (MatLUFactor with
 * MATSOLVERSCALAPACK) and MatMatSolve solve every right-hand side at once; rank 0 gathers the rows
 * it writes. */
#include <petscmat.h>
#include <stdlib.h>
#include <string.h>

#include "bem/bem_impl.h"

#define PTRY(call)                                                                             \
    do {                                                                                       \
        PetscErrorCode e_ = (call);                                                            \
        if (e_) {                                                                              \
            const char *txt_ = NULL;                                                           \
            PetscErrorMessage(e_, &txt_, NULL);                                                \
            st = thx_error(ctx, THX_ESOLVER, "PETSc: %s: %s", #call, txt_ ? txt_ : "error");   \
            goto done;                                                                         \
        }                                                                                      \
    } while (0)

/* The distributed dense solve shared by the transfer matrix and the symmetric dipoles: this rank's
 * rows i0..i1-1 of the n x n matrix (M) and of the nrhs right-hand sides (R), column-major with
 * ld i1 - i0, set into MATSCALAPACK matrices; ScaLAPACK's LU and MatMatSolve; rank 0 gets rows
 * g0..g1-1 of the solution in out ((g1 - g0) x nrhs, column-major). Collective. */
static thx_status scalapack_solve(thx_ctx *ctx, size_t n, size_t i0, size_t i1, const double *M, const double *R,
                                  size_t nrhs, size_t g0, size_t g1, double *out)
{
    thx_status st = THX_OK;
    Mat A = NULL, Rm = NULL, X = NULL, F = NULL, Xd = NULL;
    double *row = NULL, *loc = NULL, *all = NULL;
    int *counts = NULL, *displs = NULL;
    PetscInt *cols = NULL;
    PetscMPIInt rank = 0, size = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    size_t nl = i1 - i0, gn = g1 - g0, w = n > nrhs ? n : nrhs;
    cols = thx_malloc(ctx, (w ? w : 1) * sizeof *cols);
    row = thx_malloc(ctx, (w ? w : 1) * sizeof *row);
    if (!cols || !row) { st = THX_ENOMEM; goto done; }
    for (size_t j = 0; j < w; j++) cols[j] = (PetscInt)j;
    PTRY(MatCreate(PETSC_COMM_WORLD, &A));
    PTRY(MatSetSizes(A, PETSC_DECIDE, PETSC_DECIDE, (PetscInt)n, (PetscInt)n));
    PTRY(MatSetType(A, MATSCALAPACK));
    PTRY(MatSetUp(A));
    PTRY(MatCreate(PETSC_COMM_WORLD, &Rm));
    PTRY(MatSetSizes(Rm, PETSC_DECIDE, PETSC_DECIDE, (PetscInt)n, (PetscInt)nrhs));
    PTRY(MatSetType(Rm, MATSCALAPACK));
    PTRY(MatSetUp(Rm));
    /* row by row (values given column-major: one row is strided; copy it) */
    for (size_t i = 0; i < nl; i++) {
        PetscInt gi = (PetscInt)(i0 + i);
        for (size_t j = 0; j < n; j++) row[j] = M[j * nl + i];
        PTRY(MatSetValues(A, 1, &gi, (PetscInt)n, cols, row, INSERT_VALUES));
        for (size_t j = 0; j < nrhs; j++) row[j] = R[j * nl + i];
        PTRY(MatSetValues(Rm, 1, &gi, (PetscInt)nrhs, cols, row, INSERT_VALUES));
    }
    PTRY(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyBegin(Rm, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyEnd(Rm, MAT_FINAL_ASSEMBLY));
    PTRY(MatDuplicate(Rm, MAT_DO_NOT_COPY_VALUES, &X));
    PTRY(MatGetFactor(A, MATSOLVERSCALAPACK, MAT_FACTOR_LU, &F));
    {
        MatFactorInfo fi;
        PTRY(MatFactorInfoInitialize(&fi));
        PTRY(MatLUFactorSymbolic(F, A, NULL, NULL, &fi));
        PTRY(MatLUFactorNumeric(F, A, &fi));
    }
    PTRY(MatMatSolve(F, Rm, X));
    PTRY(MatConvert(X, MATDENSE, MAT_INITIAL_MATRIX, &Xd));
    /* rank 0 gathers rows g0..g1-1 */
    {
        PetscInt rs, re, lda;
        PTRY(MatGetOwnershipRange(Xd, &rs, &re));
        const PetscScalar *x;
        PTRY(MatDenseGetLDA(Xd, &lda));
        PTRY(MatDenseGetArrayRead(Xd, &x));
        size_t a = (size_t)rs > g0 ? (size_t)rs : g0, z = (size_t)re < g1 ? (size_t)re : g1;
        size_t cnt = z > a ? z - a : 0;
        loc = thx_malloc(ctx, (cnt ? cnt : 1) * (nrhs ? nrhs : 1) * sizeof *loc);
        if (!loc) { MatDenseRestoreArrayRead(Xd, &x); st = THX_ENOMEM; goto done; }
        for (size_t r = 0; r < cnt; r++)
            for (size_t j = 0; j < nrhs; j++) loc[r * nrhs + j] = x[j * (size_t)lda + (a + r - (size_t)rs)];
        PTRY(MatDenseRestoreArrayRead(Xd, &x));
        int c = (int)(cnt * nrhs);
        counts = thx_malloc(ctx, (size_t)size * sizeof *counts);
        displs = thx_malloc(ctx, (size_t)size * sizeof *displs);
        if (!counts || !displs) { st = THX_ENOMEM; goto done; }
        MPI_Gather(&c, 1, MPI_INT, counts, 1, MPI_INT, 0, PETSC_COMM_WORLD);
        if (rank == 0) {
            all = thx_malloc(ctx, (gn ? gn : 1) * (nrhs ? nrhs : 1) * sizeof *all);
            if (!all) { st = THX_ENOMEM; goto done; }
            for (int r = 0, d = 0; r < size; r++) { displs[r] = d; d += counts[r]; }
        }
        /* ranks own increasing row ranges: the gathered rows are in order */
        MPI_Gatherv(loc, c, MPI_DOUBLE, all, counts, displs, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
        if (rank == 0)
            for (size_t r = 0; r < gn; r++)
                for (size_t j = 0; j < nrhs; j++) out[j * gn + r] = all[r * nrhs + j];
    }
done:
    MatDestroy(&A);
    MatDestroy(&Rm);
    MatDestroy(&X);
    MatDestroy(&F);
    MatDestroy(&Xd);
    free(row);
    free(cols);
    free(loc);
    free(all);
    free(counts);
    free(displs);
    return st;
}

thx_status thx_bem_transfer_parallel(thx_ctx *ctx, const thx_bem *b, size_t h, double *T, thx_bem_info *info)
{
    thx_bem_info inf;
    memset(&inf, 0, sizeof inf);
    inf.ipa_surface = -1;
    THX_CHECK(thx_bem_transfer_check(ctx, b, h));
    PetscBool up = PETSC_FALSE;
    PetscInitialized(&up);
    if (!up) return thx_error(ctx, THX_EINTERNAL, "bem: PETSc is not initialized");
    thx_status st = THX_OK;
    size_t N = b->off[b->n], nh = b->off[h + 1] - b->off[h];
    size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
    double *M = NULL, *R = NULL;
    PetscMPIInt rank = 0, size = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    double t0 = thx_wtime();
    /* the rows this rank assembles: an even split */
    size_t i0 = N * (size_t)rank / (size_t)size, i1 = N * ((size_t)rank + 1) / (size_t)size, nl = i1 - i0;
    M = thx_malloc(ctx, (nl ? nl : 1) * N * sizeof *M);
    R = thx_malloc(ctx, (nl ? nl : 1) * nh * sizeof *R);
    if (!M || !R) { st = THX_ENOMEM; goto done; }
    if (nl) THX_TRY(thx_bem_transfer_rows(ctx, b, h, i0, i1, M, R, nl));
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
    THX_TRY(scalapack_solve(ctx, N, i0, i1, M, R, nh, oo, oo + on, T));
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = N;
    inf.matrix_bytes = ((double)N * (double)N + 2.0 * (double)N * (double)nh) * sizeof(double) / size;
done:
    free(M);
    free(R);
    if (info) *info = inf;
    return st;
}

thx_status thx_bem_dipoles_parallel(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                                    double *phi, thx_bem_info *info)
{
    thx_bem_info inf;
    memset(&inf, 0, sizeof inf);
    inf.ipa_surface = -1;
    PetscBool up = PETSC_FALSE;
    PetscInitialized(&up);
    if (!up) return thx_error(ctx, THX_EINTERNAL, "bem: PETSc is not initialized");
    thx_status st = THX_OK;
    size_t N = b->off[b->n], n = 0;
    double *M = NULL, *R = NULL, *V = NULL;
    int *comp = thx_malloc(ctx, (nd ? nd : 1) * sizeof *comp);
    PetscMPIInt rank = 0, size = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    if (!comp) return THX_ENOMEM;
    THX_TRY(thx_bem_dipole_compartments(ctx, b, pos, mom, nd, comp));
    THX_TRY(thx_bem_symmetric_rows(ctx, b, 0, 0, NULL, NULL, 0, comp, NULL, NULL, &n));
    double t0 = thx_wtime();
    size_t i0 = n * (size_t)rank / (size_t)size, i1 = n * ((size_t)rank + 1) / (size_t)size, nl = i1 - i0;
    M = thx_malloc(ctx, (nl ? nl : 1) * n * sizeof *M);
    R = thx_malloc(ctx, (nl ? nl : 1) * (nd ? nd : 1) * sizeof *R);
    V = rank == 0 ? thx_malloc(ctx, (N ? N : 1) * (nd ? nd : 1) * sizeof *V) : NULL;
    if (!M || !R || (rank == 0 && !V)) { st = THX_ENOMEM; goto done; }
    if (nl) THX_TRY(thx_bem_symmetric_rows(ctx, b, i0, i1, pos, mom, nd, comp, M, R, NULL));
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
    THX_TRY(scalapack_solve(ctx, n, i0, i1, M, R, nd, 0, N, V));
    /* potentials referenced to the outer surface's area-weighted mean (rank 0) */
    if (rank == 0) {
        size_t oo = b->off[b->outer], on = b->off[b->outer + 1] - oo;
        for (size_t d = 0; d < nd; d++) {
            double m = 0, w = 0;
            for (size_t a = oo; a < oo + on; a++) m += b->area[a] * V[d * N + a], w += b->area[a];
            for (size_t a = 0; a < N; a++) phi[d * N + a] = V[d * N + a] - m / w;
        }
    }
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = n;
    inf.matrix_bytes = ((double)n * (double)n + 2.0 * (double)n * (double)nd) * sizeof(double) / size;
done:
    free(M);
    free(R);
    free(V);
    free(comp);
    if (info) *info = inf;
    return st;
}
