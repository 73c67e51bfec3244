/*
 * PETSc alone on a system thorax assembled (thorax forward --dump-system):
 * loads the matrix and right-hand side, solves with the options on the
 * command line (same defaults as thorax: -ksp_type cg -pc_type gamg
 * -ksp_rtol 1e-10), prints setup and solve times. bench/forward.sh runs it
 * beside thorax so our overhead is a ratio.
 */
#include <petscksp.h>

int main(int argc, char **argv)
{
    PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
    char path[PETSC_MAX_PATH_LEN] = "";
    PetscBool have = PETSC_FALSE;
    PetscCall(PetscOptionsGetString(NULL, NULL, "-system", path, sizeof path, &have));
    if (!have) SETERRQ(PETSC_COMM_WORLD, PETSC_ERR_USER, "give -system FILE");
    PetscViewer vw;
    Mat A;
    Vec b, x;
    PetscLogDouble tl0, tl1;
    PetscCall(PetscTime(&tl0));
    PetscCall(PetscViewerBinaryOpen(PETSC_COMM_WORLD, path, FILE_MODE_READ, &vw));
    PetscCall(MatCreate(PETSC_COMM_WORLD, &A));
    PetscCall(MatSetType(A, MATAIJ));
    PetscCall(MatLoad(A, vw));
    PetscCall(VecCreate(PETSC_COMM_WORLD, &b));
    PetscCall(VecLoad(b, vw));
    PetscCall(PetscViewerDestroy(&vw));
    PetscCall(PetscTime(&tl1));
    PetscCall(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
    PetscCall(MatSetOption(A, MAT_SPD, PETSC_TRUE));
    PetscCall(VecDuplicate(b, &x));
    KSP ksp;
    PC pc;
    PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
    PetscCall(KSPSetOperators(ksp, A, A));
    PetscCall(KSPSetType(ksp, KSPCG));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, PCGAMG));
    PetscCall(KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, 10000));
    PetscCall(KSPSetFromOptions(ksp));
    PetscLogDouble t0, t1, t2;
    PetscCall(PetscTime(&t0));
    PetscCall(KSPSetUp(ksp));
    PetscCall(PetscTime(&t1));
    PetscCall(KSPSolve(ksp, b, x));
    PetscCall(PetscTime(&t2));
    PetscInt its;
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscInt n;
    PetscCall(MatGetSize(A, &n, NULL));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "petsc alone: %d unknowns, load %.3f s, setup %.3f s, solve %.3f s (setup + solve %.3f s), %d iterations\n",
                          (int)n, (double)(tl1 - tl0), (double)(t1 - t0), (double)(t2 - t1), (double)(t2 - t0), (int)its));
    PetscCall(KSPDestroy(&ksp));
    PetscCall(MatDestroy(&A));
    PetscCall(VecDestroy(&b));
    PetscCall(VecDestroy(&x));
    PetscCall(PetscFinalize());
    return 0;
}
