/*
 * thorax/bem/bem.h — boundary elements for nested closed surfaces with piecewise-constant
 * conductivity (paper 4.1: "forward solutions by both methods"; docs/decisions.md, "Boundary
 * elements" and "Symmetric boundary elements").
 *
 * Dipoles are solved by default with the symmetric Galerkin method (Kybic et al. 2005; src/bem/
 * symmetric.c: potentials linear on each triangle, normal currents constant on each triangle of
 * every surface but the outermost). The transfer matrix, and dipoles on request
 * (THX_BEM_COLLOCATION), by the method below.
 *
 * Collocation method: linear collocation (potentials linear on each triangle, one equation a node) with the
 * analytic double- and single-layer integrals over a flat triangle of de Munck (1992), the
 * isolated problem approach of Hämäläinen & Sarvas (1989) for a source compartment inside a poorly
 * conducting one, and the constant null space of the pure Neumann problem deflated with the outer
 * surface's area-weighted mean. Dense algebra by LAPACK (dgetrf/dgetrs) on OpenBLAS.
 *
 * The equation at a node r of surface k (Geselowitz 1967), with n the outward normal:
 *     (s_k- + s_k+)/2 phi(r) - sum_l (s_l- - s_l+)/(4 pi) int_{S_l} phi(r') dOmega_r(r') = V_inf(r)
 *     dOmega_r(r') = n(r').(r' - r) / |r' - r|^3 dS'      (+4 pi for r inside a closed surface)
 *     V_inf(r) = q.(r - r0) / (4 pi |r - r0|^3)            (a dipole q at r0, unit conductivity)
 * s_k- is the conductivity just inside surface k, s_k+ just outside (0 outside the outermost).
 *
 * Invariants of a thx_bem: every surface closed (each edge in exactly two triangles, in opposite
 * directions), triangles counterclockwise seen from outside (surfaces given inward are reversed),
 * no two surfaces crossing (every node of one on the same side of the other), exactly one
 * outermost surface that holds all the others. Node numbering of the unknowns: surface 0's nodes,
 * then surface 1's, ... (thx_bem_offset).
 */
#ifndef THORAX_BEM_BEM_H
#define THORAX_BEM_BEM_H

#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_bem thx_bem;

/*
 * The analytic integrals over the flat triangle (a, b, c) (counterclockwise about its normal n)
 * seen from x, for the three linear hat functions h_i (h_0 = 1 at a, ...):
 *   dl[i] = int_T h_i(r') n.(r' - x)/|r' - x|^3 dS'   (double layer; sum = the solid angle)
 *   sl[i] = int_T h_i(r') / |r' - x| dS'               (single layer; may be NULL)
 * Returns the signed solid angle of the triangle seen from x (van Oosterom & Strackee 1983;
 * positive when n points away from x). x may be a corner or on an edge (weakly singular: finite).
 */
double thx_bem_triangle(const double x[3], const double a[3], const double b[3], const double c[3], double dl[3],
                        double sl[3]);

/*
 * A boundary-element geometry from n surfaces (copied; the caller keeps its own) and sigma_in[k],
 * the conductivity (S/m) of the compartment just inside surface k (between k and the surfaces
 * directly inside it). The nesting is found here; the conductivity just outside a surface is
 * that of its parent, 0 outside the outermost. Refused with the surface named: an open or
 * non-manifold surface (the edge), a surface crossing another (a node on each side; up to 400
 * nodes of each surface are tested, evenly spread), two
 * outermost surfaces, a conductivity not finite or not positive (sigma_in of a surface used as
 * a hole, e.g. the heart in thx_bem_transfer, is not read and may be 0). Surfaces given inward
 * (negative enclosed volume) are reversed and logged. Caller destroys *out.
 */
thx_status thx_bem_create(thx_ctx *ctx, const thx_surface *const *surf, size_t n, const double *sigma_in,
                          thx_bem **out);
/* Frees b; accepts NULL; nulls *b. */
void thx_bem_destroy(thx_bem **b);

size_t thx_bem_n_surfaces(const thx_bem *b);
/* All nodes of all surfaces: the size of the dipole problem. */
size_t thx_bem_n_nodes(const thx_bem *b);
/* The first unknown of surface k. */
size_t thx_bem_offset(const thx_bem *b, size_t k);
/* The surface as used (oriented outward; borrowed). */
const thx_surface *thx_bem_surface(const thx_bem *b, size_t k);
/* The index of the surface directly outside surface k, -1 for the outermost. */
int thx_bem_parent(const thx_bem *b, size_t k);
/* The outermost surface's index. */
size_t thx_bem_outer(const thx_bem *b);
/* Conductivity just inside / just outside surface k. */
double thx_bem_sigma_in(const thx_bem *b, size_t k);
double thx_bem_sigma_out(const thx_bem *b, size_t k);

/*
 * The double-layer matrix B (N x N, column-major, B[j * N + i]): B_ij = sum over the triangles of
 * the surface of node j of int h_j dOmega_{r_i}, with no correction: the triangles at node i
 * contribute 0 to row i (flat), so the row of node i over its own surface sums to 4 pi minus the
 * solid angle of the surface's inside at i (thx_bem_vertex_angle), over a surface enclosing i to
 * 4 pi, over any other surface to 0. The system matrices replace the diagonal so that each row
 * over its own surface sums to 2 pi. OpenMP over rows; deterministic.
 */
thx_status thx_bem_double_layer(thx_ctx *ctx, const thx_bem *b, double *B);
/* The solid angle (sr) of the inside of surface k at its node i: the polyhedral cone of the
 * triangles at i, from their dihedral angles (sum of the interior dihedrals - (m - 2) pi). */
double thx_bem_vertex_angle(const thx_bem *b, size_t k, size_t i);

enum { THX_BEM_SYMMETRIC = 0, THX_BEM_COLLOCATION = 1 };

typedef struct {
    int method;        /* for dipoles: THX_BEM_SYMMETRIC (default; symmetric.c) or THX_BEM_COLLOCATION.
                          The transfer matrix is always by collocation. */
    int ipa;           /* 1 (default): the isolated problem approach where it applies: dipoles in the
                          compartment inside a surface with no surface inside it, conducting more
                          than the compartment outside; 0: never (collocation only) */
} thx_bem_opts;
void thx_bem_opts_default(thx_bem_opts *o);

typedef struct {
    size_t n_unknowns;     /* size of the dense system */
    double t_assemble;     /* seconds: the boundary integrals */
    double t_solve;        /* seconds: factorization and solves */
    int ipa_surface;       /* the surface the isolated problem approach used, -1 if none */
    double matrix_bytes;   /* dense matrices held at the peak */
} thx_bem_info;

/*
 * Potentials of n dipoles (positions pos[3d..3d+2], moments mom[3d..3d+2], in the units of the
 * geometry and a moment unit: phi = q.R/(4 pi sigma R^3) in an infinite medium) at every node:
 * phi[d * N + i], N = thx_bem_n_nodes, referenced to zero area-weighted mean over the outer
 * surface. A dipole outside the outermost surface, or within 1e-9 of the size of the model of a
 * surface, is refused (naming it, 1-based). info may be NULL.
 */
thx_status thx_bem_dipoles(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t n,
                           const thx_bem_opts *o, double *phi, thx_bem_info *info);

/*
 * The heart-surface-potential formulation (Barr et al. 1977): the surface `heart` is the
 * boundary of the source-free conductor (its inside is a hole, its potentials given); the
 * unknowns are the potentials on every other surface and the normal derivative on the heart
 * (linear, single layer). T (n_outer x n_heart, column-major T[j * n_outer + i]) maps the heart's
 * node potentials to the outer surface's: phi_outer = T phi_heart, the rows and columns of
 * `thorax forward --transfer-out`. heart must have no surface inside it and the outer surface
 * must be the outermost. info may be NULL.
 */
thx_status thx_bem_transfer(thx_ctx *ctx, const thx_bem *b, size_t heart, const thx_bem_opts *o, double *T,
                            thx_bem_info *info);

/* The most subdivisions of thx_bem_subdivide (each multiplies a surface's nodes by about 4 and the
 * dense system by up to 16). */
#define THX_BEM_REFINE_MAX 4

/* The linear interpolation from a surface's nodes (n_coarse) to those of its subdivision (n_fine):
 * fine node f = sum over k < 3 of w[3f + k] * coarse node node[3f + k] (a weight 0 means nothing;
 * the weights sum to 1). As a matrix W (n_fine x n_coarse), the coarse hat functions written in the
 * fine ones: a coarse hat function is exactly piecewise linear on the fine surface. */
typedef struct {
    size_t n_fine, n_coarse;
    size_t *node;
    double *w;
} thx_bem_refinement;
void thx_bem_refinement_free(thx_bem_refinement *W);
/* T (n_rows x n_coarse, column-major) = Tf (n_rows x n_fine) W: columns on the fine nodes combined
 * into columns on the coarse nodes' hat functions. */
void thx_bem_refinement_apply(const thx_bem_refinement *W, const double *Tf, size_t n_rows, double *T);
/* The node and triangle counts of a closed surface of n_nodes, n_tris subdivided `levels` times
 * (n + e nodes and 4 t triangles a level, e = 3 t / 2 edges); either output may be NULL. */
void thx_bem_refined_counts(size_t n_nodes, size_t n_tris, int levels, size_t *n_fine, size_t *t_fine);

/*
 * s subdivided `levels` times (0..THX_BEM_REFINE_MAX) by edge midpoints: one new node amid each
 * edge (shared by its two triangles; numbered after the old nodes, in the order of the edges'
 * sorted (lower, higher) node pairs), each triangle (a, b, c) into (a, ab, ca), (ab, b, bc),
 * (ca, bc, c), (ab, bc, ca): flat, so the geometry is the same, and the orientation kept. The old
 * nodes keep their numbers. *fine (caller destroys) and W (caller frees with
 * thx_bem_refinement_free) from s's nodes to *fine's.
 */
thx_status thx_bem_subdivide(thx_ctx *ctx, const thx_surface *s, int levels, thx_surface **fine,
                             thx_bem_refinement *W);
/* b with surface k subdivided `levels` times (thx_bem_subdivide; the same conductivities):
 * *out (caller destroys) and W from b's surface k to *out's. */
thx_status thx_bem_refine(thx_ctx *ctx, const thx_bem *b, size_t k, int levels, thx_bem **out, thx_bem_refinement *W);

/*
 * thx_bem_transfer with the heart subdivided `levels` times (thx_bem_refine): the system solved on
 * the fine heart, its right-hand sides (one a fine heart node) combined by W into one a coarse
 * node's hat function before the solve (T = T_fine W, without holding T_fine: the right-hand sides
 * are assembled a block of rows at a time). T as thx_bem_transfer's on b (n_outer x the heart's
 * nodes of b); levels 0 is thx_bem_transfer. info->n_unknowns: the fine system's.
 */
thx_status thx_bem_transfer_refined(thx_ctx *ctx, const thx_bem *b, size_t heart, int levels, const thx_bem_opts *o,
                                    double *T, thx_bem_info *info);
/* The dense memory (bytes) thx_bem_transfer_refined holds at its peak for b and these levels. */
double thx_bem_transfer_refined_bytes(const thx_bem *b, size_t heart, int levels);

/*
 * thx_bem_transfer under MPI (collective over PETSC_COMM_WORLD; PETSc initialized by the caller):
 * each rank assembles N/size rows, the system is a PETSc MATSCALAPACK matrix (block-cyclic over
 * the ranks, so no rank holds it whole) factored by ScaLAPACK's LU, every heart column solved at
 * once; T (as thx_bem_transfer's) is filled on rank 0 only. The same matrix as the serial path
 * to rounding (tests/e2e_bem.sh: 2 ranks against 1). info->matrix_bytes: per rank.
 */
thx_status thx_bem_transfer_parallel(thx_ctx *ctx, const thx_bem *b, size_t heart, double *T, thx_bem_info *info);

/*
 * thx_bem_dipoles by the symmetric method under MPI (collective over PETSC_COMM_WORLD; PETSc
 * initialized by the caller): each rank computes n/size rows of the symmetric system from the pair
 * integrals alone (no rank holds the matrix whole; the pairs near a row's node are integrated again
 * by each row that needs them: about three times the serial path's integrals in all), the system is
 * a MATSCALAPACK matrix factored by ScaLAPACK's LU, every dipole solved at once; phi (as
 * thx_bem_dipoles') is filled on rank 0 only. The same potentials as the serial path to rounding
 * (tests/e2e_bem.sh: 1 and 2 ranks against LAPACK).
 */
thx_status thx_bem_dipoles_parallel(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t n,
                                    double *phi, thx_bem_info *info);

/*
 * The conductivity just inside each surface of a meshed model (m->volume), sigma_in[k]: the
 * region of most of the tetrahedra at the surface's nodes on its inner side (by the node's normal).
 * A surface with no tetrahedron inside (a hole, e.g. a heart meshed with --no-heart) gets 0.
 * Refused: no volume, an anisotropic region at a surface. `where` names the model in messages.
 */
thx_status thx_bem_sigma_from_volume(thx_ctx *ctx, const thx_model *m, const char *where, double *sigma_in);

/*
 * OpenMEEG's geometry (.geom, "Domain Description 1.1": Interfaces with their .tri files relative
 * to the .geom, Domains "NAME: i -j" with -j inside interface j, +i outside it) and conductivity
 * (.cond, "NAME VALUE" lines) files: the surfaces as a model (roles: the outermost "outer",
 * others "other") and sigma_in per surface (caller frees with free()). Errors name file and line.
 */
thx_status thx_bem_read_openmeeg(thx_ctx *ctx, const char *geom, const char *cond, thx_model **m,
                                 double **sigma_in);

/*
 * Dipoles from a text file: one a line, "px py pz qx qy qz" (OpenMEEG's .dip layout), `#`
 * comments; *pos and *mom get 3n doubles (caller frees with free()). Errors name file and line.
 */
thx_status thx_bem_read_dipoles(thx_ctx *ctx, const char *path, double **pos, double **mom, size_t *n);

#ifdef __cplusplus
}
#endif
#endif
