/*
 * Blocked solves with a factored matrix, PETSc alone on a system thorax
 * assembled (thorax forward --dump-system): factors K_ff with the package of
 * -pc_factor_mat_solver_type (cholmod, mumps, petsc, ...), then solves -nrhs
 * right-hand sides (the dumped one, scaled and shifted column by column so
 * they differ): one MatSolve per column, then MatMatSolve on dense blocks
 * of each of the -blocks sizes (e.g. -blocks 1,16,64). Prints the factorization time, both solve times
 * and the largest relative difference between the two answers.
 * bench/forward.sh runs it to choose the package (docs/decisions.md).
 */
#include <petscksp.h>

int main(int argc, char **argv)
{
    PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
    char path[PETSC_MAX_PATH_LEN] = "";
    PetscBool have = PETSC_FALSE;
    PetscInt nrhs = 300, blocks[16] = {64}, n_blocks = 16;
    PetscCall(PetscOptionsGetString(NULL, NULL, "-system", path, sizeof path, &have));
    if (!have) SETERRQ(PETSC_COMM_WORLD, PETSC_ERR_USER, "give -system FILE");
    PetscCall(PetscOptionsGetInt(NULL, NULL, "-nrhs", &nrhs, NULL));
    PetscCall(PetscOptionsGetIntArray(NULL, NULL, "-blocks", blocks, &n_blocks, &have));
    if (!have) n_blocks = 1;
    PetscViewer vw;
    Mat A, F;
    Vec b, x;
    PetscCall(PetscViewerBinaryOpen(PETSC_COMM_WORLD, path, FILE_MODE_READ, &vw));
    PetscCall(MatCreate(PETSC_COMM_WORLD, &A));
    PetscCall(MatSetType(A, MATAIJ));
    PetscCall(MatLoad(A, vw));
    PetscCall(VecCreate(PETSC_COMM_WORLD, &b));
    PetscCall(VecLoad(b, vw));
    PetscCall(PetscViewerDestroy(&vw));
    PetscCall(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
    PetscCall(MatSetOption(A, MAT_SPD, PETSC_TRUE));
    PetscCall(VecDuplicate(b, &x));
    KSP ksp;
    PC pc;
    PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
    PetscCall(KSPSetOperators(ksp, A, A));
    PetscCall(KSPSetType(ksp, KSPPREONLY));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, PCCHOLESKY));
    PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERCHOLMOD));
    PetscCall(KSPSetFromOptions(ksp));
    PetscLogDouble t0, t1, t2;
    PetscCall(PetscTime(&t0));
    PetscCall(KSPSetUp(ksp));
    PetscCall(PetscTime(&t1));
    double t_factor = (double)(t1 - t0);
    PetscCall(PCFactorGetMatrix(pc, &F));
    MatSolverType pkg;
    PetscCall(PCFactorGetMatSolverType(pc, &pkg));
    PetscInt n, m;
    PetscCall(MatGetSize(A, &n, NULL));
    PetscCall(MatGetLocalSize(A, &m, NULL));
    /* column j of the right-hand sides: (1 + j / nrhs) b + j / nrhs */
    Mat X1; /* the column-by-column answers */
    PetscCall(MatCreateDense(PETSC_COMM_WORLD, m, PETSC_DECIDE, n, nrhs, NULL, &X1));
    PetscScalar *x1;
    PetscCall(MatDenseGetArray(X1, &x1));
    PetscCall(PetscTime(&t1));
    for (PetscInt j = 0; j < nrhs; j++) {
        PetscCall(VecCopy(b, x));
        PetscCall(VecScale(x, 1.0 + (double)j / (double)nrhs));
        PetscCall(VecShift(x, (double)j / (double)nrhs));
        Vec y;
        PetscCall(VecCreateMPIWithArray(PETSC_COMM_WORLD, 1, m, n, x1 + (size_t)j * (size_t)m, &y));
        PetscCall(MatSolve(F, x, y));
        PetscCall(VecDestroy(&y));
    }
    PetscCall(PetscTime(&t2));
    PetscCall(MatDenseRestoreArray(X1, &x1));
    for (PetscInt q = 0; q < n_blocks; q++) {
    PetscInt nb = blocks[q] < 1 ? 1 : blocks[q];
    double maxrel = 0, t_block = 0;
    const PetscScalar *bb;
    PetscCall(VecGetArrayRead(b, &bb));
    PetscCall(MatDenseGetArray(X1, &x1));
    for (PetscInt j0 = 0; j0 < nrhs; j0 += nb) {
        PetscInt k = PetscMin(nb, nrhs - j0);
        Mat B, X;
        PetscScalar *pb, *px;
        PetscCall(MatCreateDense(PETSC_COMM_WORLD, m, PETSC_DECIDE, n, k, NULL, &B));
        PetscCall(MatCreateDense(PETSC_COMM_WORLD, m, PETSC_DECIDE, n, k, NULL, &X));
        PetscCall(MatDenseGetArray(B, &pb));
        for (PetscInt j = 0; j < k; j++) {
            double s = (double)(j0 + j) / (double)nrhs;
            for (PetscInt i = 0; i < m; i++) pb[(size_t)j * (size_t)m + (size_t)i] = (1.0 + s) * bb[i] + s;
        }
        PetscCall(MatDenseRestoreArray(B, &pb));
        PetscLogDouble s0, s1;
        PetscCall(PetscTime(&s0));
        PetscCall(MatMatSolve(F, B, X));
        PetscCall(PetscTime(&s1));
        t_block += (double)(s1 - s0);
        PetscCall(MatDenseGetArray(X, &px));
        for (PetscInt j = 0; j < k; j++) {
            double dn = 0, nn = 0;
            for (PetscInt i = 0; i < m; i++) {
                double a = px[(size_t)j * (size_t)m + (size_t)i], c = x1[(size_t)(j0 + j) * (size_t)m + (size_t)i];
                dn = PetscMax(dn, PetscAbs(a - c));
                nn = PetscMax(nn, PetscAbs(c));
            }
            if (nn > 0) maxrel = PetscMax(maxrel, dn / nn);
        }
        PetscCall(MatDenseRestoreArray(X, &px));
        PetscCall(MatDestroy(&B));
        PetscCall(MatDestroy(&X));
    }
    PetscCall(MatDenseRestoreArray(X1, &x1));
    PetscCall(VecRestoreArrayRead(b, &bb));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &maxrel, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "%s: %d unknowns, factor %.3f s; %d right-hand sides: column by column %.3f s (%.1f ms each), "
                          "blocks of %d %.3f s (%.2f ms each), max relative difference %.1e\n",
                          pkg, (int)n, t_factor, (int)nrhs, (double)(t2 - t1), 1e3 * (double)(t2 - t1) / (double)nrhs,
                          (int)nb, t_block, 1e3 * t_block / (double)nrhs, maxrel));
    }
    PetscCall(MatDestroy(&X1));
    PetscCall(KSPDestroy(&ksp));
    PetscCall(MatDestroy(&A));
    PetscCall(VecDestroy(&b));
    PetscCall(VecDestroy(&x));
    PetscCall(PetscFinalize());
    return 0;
}
