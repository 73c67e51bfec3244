/* The transfer matrix under mpirun: each rank assembles a block of rows (thx_bem_transfer_rows,
 * the serial code), PETSc's MATSCALAPACK holds the dense system block-cyclically over the ranks,
 * ScaLAPACK's LU (MatLUFactor with MATSOLVERSCALAPACK) and MatMatSolve solve all heart columns at
 * once; rank 0 gathers the outer surface's rows (thorax/bem/bem.h). */
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
    Mat A = NULL, Rm = NULL, X = NULL, F = NULL, Xd = NULL;
    double *M = NULL, *R = NULL, *loc = NULL, *all = NULL;
    int *counts = NULL, *displs = NULL;
    PetscInt *cols = NULL;
    PetscMPIInt rank = 0, size = 1;
    MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &size);
    double t0 = thx_wtime();
    /* the rows this rank assembles: an even split */
    size_t i0 = N * (size_t)rank / (size_t)size, i1 = N * ((size_t)rank + 1) / (size_t)size, nl = i1 - i0;
    M = thx_malloc(ctx, (nl ? nl : 1) * N * sizeof *M);
    R = thx_malloc(ctx, (nl ? nl : 1) * nh * sizeof *R);
    cols = thx_malloc(ctx, (N > nh ? N : nh) * sizeof *cols);
    if (!M || !R || !cols) { st = THX_ENOMEM; goto done; }
    if (nl) THX_TRY(thx_bem_transfer_rows(ctx, b, h, i0, i1, M, R, nl));
    for (size_t j = 0; j < N; j++) cols[j] = (PetscInt)j;
    PTRY(MatCreate(PETSC_COMM_WORLD, &A));
    PTRY(MatSetSizes(A, PETSC_DECIDE, PETSC_DECIDE, (PetscInt)N, (PetscInt)N));
    PTRY(MatSetType(A, MATSCALAPACK));
    PTRY(MatSetUp(A));
    PTRY(MatCreate(PETSC_COMM_WORLD, &Rm));
    PTRY(MatSetSizes(Rm, PETSC_DECIDE, PETSC_DECIDE, (PetscInt)N, (PetscInt)nh));
    PTRY(MatSetType(Rm, MATSCALAPACK));
    PTRY(MatSetUp(Rm));
    /* row by row (values given column-major: one row is strided; copy it) */
    {
        double *row = thx_malloc(ctx, (N > nh ? N : nh) * sizeof *row);
        if (!row) { st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < nl && st == THX_OK; i++) {
            PetscInt gi = (PetscInt)(i0 + i);
            for (size_t j = 0; j < N; j++) row[j] = M[j * nl + i];
            if (MatSetValues(A, 1, &gi, (PetscInt)N, cols, row, INSERT_VALUES)) st = thx_error(ctx, THX_ESOLVER, "PETSc: MatSetValues");
            for (size_t j = 0; j < nh && st == THX_OK; j++) row[j] = R[j * nl + i];
            if (st == THX_OK && MatSetValues(Rm, 1, &gi, (PetscInt)nh, cols, row, INSERT_VALUES)) st = thx_error(ctx, THX_ESOLVER, "PETSc: MatSetValues");
        }
        free(row);
        if (st != THX_OK) goto done;
    }
    free(M);
    M = NULL;
    free(R);
    R = NULL;
    PTRY(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyBegin(Rm, MAT_FINAL_ASSEMBLY));
    PTRY(MatAssemblyEnd(Rm, MAT_FINAL_ASSEMBLY));
    inf.t_assemble = thx_wtime() - t0;
    t0 = thx_wtime();
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
    /* rank 0 gathers the outer surface's rows */
    {
        PetscInt rs, re, lda;
        PTRY(MatGetOwnershipRange(Xd, &rs, &re));
        const PetscScalar *x;
        PTRY(MatDenseGetLDA(Xd, &lda));
        PTRY(MatDenseGetArrayRead(Xd, &x));
        size_t a = (size_t)rs > oo ? (size_t)rs : oo, z = (size_t)re < oo + on ? (size_t)re : oo + on;
        size_t cnt = z > a ? z - a : 0;
        loc = thx_malloc(ctx, (cnt ? cnt : 1) * nh * sizeof *loc);
        if (!loc) { MatDenseRestoreArrayRead(Xd, &x); st = THX_ENOMEM; goto done; }
        for (size_t r = 0; r < cnt; r++)
            for (size_t j = 0; j < nh; j++) loc[r * nh + j] = x[j * (size_t)lda + (a + r - (size_t)rs)];
        PTRY(MatDenseRestoreArrayRead(Xd, &x));
        int c = (int)(cnt * nh);
        counts = thx_malloc(ctx, (size_t)size * sizeof *counts);
        displs = thx_malloc(ctx, (size_t)size * sizeof *displs);
        if (!counts || !displs) { st = THX_ENOMEM; goto done; }
        MPI_Gather(&c, 1, MPI_INT, counts, 1, MPI_INT, 0, PETSC_COMM_WORLD);
        if (rank == 0) {
            all = thx_malloc(ctx, (on ? on : 1) * nh * sizeof *all);
            if (!all) { st = THX_ENOMEM; goto done; }
            for (int r = 0, d = 0; r < size; r++) { displs[r] = d; d += counts[r]; }
        }
        /* ranks own increasing row ranges: the gathered rows are in order */
        MPI_Gatherv(loc, c, MPI_DOUBLE, all, counts, displs, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
        if (rank == 0)
            for (size_t r = 0; r < on; r++)
                for (size_t j = 0; j < nh; j++) T[j * on + r] = all[r * nh + j];
    }
    inf.t_solve = thx_wtime() - t0;
    inf.n_unknowns = N;
    inf.matrix_bytes = ((double)N * (double)N + 2.0 * (double)N * (double)nh) * sizeof(double) / size;
done:
    MatDestroy(&A);
    MatDestroy(&Rm);
    MatDestroy(&X);
    MatDestroy(&F);
    MatDestroy(&Xd);
    free(M);
    free(R);
    free(cols);
    free(loc);
    free(all);
    free(counts);
    free(displs);
    if (info) *info = inf;
    return st;
}
