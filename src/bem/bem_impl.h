/* Private to src/bem: the geometry of a boundary-element problem. */
#ifndef THORAX_BEM_IMPL_H
#define THORAX_BEM_IMPL_H
#include "thorax/bem/bem.h"

struct thx_bem {
    size_t n;            /* surfaces */
    thx_surface **surf;  /* owned copies, outward */
    size_t *off;         /* n + 1: first unknown of each surface, off[n] = total nodes */
    int *parent;         /* surface directly outside, -1 for the outermost */
    double *sig_in, *sig_out;
    size_t outer;
    double *area;        /* per node (all surfaces): a third of its triangles' areas */
    double scale;        /* the model's size (bounding-box diagonal) */
};

/* Adds the double-layer rows i0..i1-1 (of all nodes) into B, the columns of surfaces in use
 * (use[l] != 0; others left untouched), and the single layer of surface `sl_surf` (-1: none)
 * into S (its columns those of sl_surf's nodes). B and S column-major, leading dimension ld >=
 * i1 - i0: row i is B[col * ld + i - i0]. */
void thx_bem_assemble_rows(const thx_bem *b, size_t i0, size_t i1, const unsigned char *use, int sl_surf, double *B,
                           double *S, size_t ld);
/* The transfer system's rows i0..i1-1 (thx_bem_transfer): M (ld x N) and the right-hand sides R
 * (ld x n_heart), column-major, zeroed here. Identical whatever the row blocks. */
thx_status thx_bem_transfer_rows(thx_ctx *ctx, const thx_bem *b, size_t h, size_t i0, size_t i1, double *M, double *R,
                                 size_t ld);
/* Signed solid angle of surface k seen from p (4 pi inside, 0 outside). */
double thx_bem_surface_angle(const thx_bem *b, size_t k, const double p[3]);

/* The checks of thx_bem_transfer (heart not outermost, nothing inside it, conductivities). */
thx_status thx_bem_transfer_check(thx_ctx *ctx, const thx_bem *b, size_t h);

/* Each dipole's compartment (the innermost surface holding it), with the checks of
 * thx_bem_dipoles (conducting compartments, finite values, not on a surface, inside the outer). */
thx_status thx_bem_dipole_compartments(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                                       int *comp);

/* The symmetric (Galerkin) method for thx_bem_dipoles (symmetric.c): comp[d] is dipole d's
 * compartment (the innermost surface holding it), checked by the caller; phi as thx_bem_dipoles'. */
thx_status thx_bem_dipoles_symmetric(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t nd,
                                     const int *comp, double *phi, thx_bem_info *info);

/* Rows i0..i1-1 of the symmetric method's matrix (M, ld i1 - i0, column-major: row i is
 * M[col * (i1 - i0) + i - i0]) and of its right-hand sides (R, the same layout, nd columns; may
 * be NULL), each computed alone from the pair integrals (the serial path's numbers, so that the
 * distributed solve gives the same answer). M NULL: *n_out (the number of unknowns: every node,
 * then every current triangle) only. comp as thx_bem_dipoles_symmetric's. */
thx_status thx_bem_symmetric_rows(thx_ctx *ctx, const thx_bem *b, size_t i0, size_t i1, const double *pos,
                                  const double *mom, size_t nd, const int *comp, double *M, double *R, size_t *n_out);

/* The triangle quadrature rules of src/bem: point i at barycentric (r[i][0], r[i][1], r[i][2]),
 * weight r[i][3] (the weights sum to 1: times the area), exact for every polynomial of degree
 * `degree` (tests/test_bem_quadrature.c). The table ends with name NULL. */
typedef struct {
    const char *name;
    int n, degree;
    const double (*r)[4];
} thx_bem_quad_rule;
extern const thx_bem_quad_rule thx_bem_quad_rules[];
/* The edge-midpoint rule of the isolated problem's right-hand side (solve.c). */
extern const double thx_bem_edge_midpoints[3][4];

/* LAPACK / BLAS (Fortran interfaces of OpenBLAS) */
void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info);
void dsytrf_(const char *uplo, const int *n, double *a, const int *lda, int *ipiv, double *work, const int *lwork,
             int *info);
void dsytrs_(const char *uplo, const int *n, const int *nrhs, const double *a, const int *lda, const int *ipiv,
             double *b, const int *ldb, int *info);
void dpotrf_(const char *uplo, const int *n, double *a, const int *lda, int *info);
void dtrsm_(const char *side, const char *uplo, const char *transa, const char *diag, const int *m, const int *n,
            const double *alpha, const double *a, const int *lda, double *b, const int *ldb);
void dsyrk_(const char *uplo, const char *trans, const int *n, const int *k, const double *alpha, const double *a,
            const int *lda, const double *beta, double *c, const int *ldc);
void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha,
            const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c,
            const int *ldc);
void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a, const int *lda, const int *ipiv,
             double *b, const int *ldb, int *info);
#endif
