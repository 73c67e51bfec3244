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

/* The double-layer rows i0..i1-1 of B restricted to the columns of surfaces in use (use[l] != 0;
 * others left untouched), plus the single layer of surface `sl_surf` (-1: none) into S (same
 * layout as B, its columns those of sl_surf). B column-major with leading dimension ld. */
void thx_bem_assemble_rows(const thx_bem *b, const unsigned char *use, int sl_surf, double *B, double *S, size_t ld);
/* Signed solid angle of surface k seen from p (4 pi inside, 0 outside). */
double thx_bem_surface_angle(const thx_bem *b, size_t k, const double p[3]);

/* LAPACK / BLAS (Fortran interfaces of OpenBLAS) */
void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info);
void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a, const int *lda, const int *ipiv,
             double *b, const int *ldb, int *info);
#endif
