/* Private to src/inverse: LAPACK/BLAS prototypes (Fortran interface, OpenBLAS) and shared helpers. */
#ifndef THORAX_INVERSE_IMPL_H
#define THORAX_INVERSE_IMPL_H
#include <stddef.h>

#include "thorax/inverse/inverse.h"

/* LAPACK and BLAS through their Fortran symbols (liblapack3 / OpenBLAS): no LAPACKE needed. */
void dgesdd_(const char *jobz, const int *m, const int *n, double *a, const int *lda, double *s, double *u,
             const int *ldu, double *vt, const int *ldvt, double *work, const int *lwork, int *iwork, int *info);
void dsyevd_(const char *jobz, const char *uplo, const int *n, double *a, const int *lda, double *w, double *work,
             const int *lwork, int *iwork, const int *liwork, int *info);
void dposv_(const char *uplo, const int *n, const int *nrhs, double *a, const int *lda, double *b, const int *ldb,
            int *info);
void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha,
            const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c,
            const int *ldc);

/* C = op(A) op(B) (column-major, alpha 1, beta 0 or 1) */
void thx_inv_gemm(char ta, char tb, size_t m, size_t n, size_t k, const double *a, size_t lda, const double *b,
                  size_t ldb, double beta, double *c, size_t ldc);
void thx_inv_norms(const double *s, const double *beta2, size_t k, double perp2, double lambda, double *rho2,
                   double *eta2);
size_t thx_inv_grid(const double *s, size_t k, int n_grid, double *grid);
/* per-triangle gradient rows of the heart's piecewise-linear potential, scaled by sqrt(area):
 * G (3 n_tris x n, column-major, new array) */
thx_status thx_inv_gradient(thx_ctx *ctx, const thx_surface *heart, double **G);
#endif
