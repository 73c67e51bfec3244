/*
 * thorax/geom/verify.h — geometry and analytic solutions for verifying the
 * volume-conductor solvers (docs/validation.md).
 *
 * Concentric spherical shells: radii a < b < c, conductivity s1 in a < r < b
 * and s2 in b < r < c. With the potential P_l(cos theta) prescribed on the
 * inner sphere r = a and no normal current through r = c, the solution is
 * (A_k r^l + B_k r^-(l+1)) P_l(cos theta) in shell k, the four constants from
 * phi(a) = 1, continuity of phi and of s dphi/dr at r = b, and dphi/dr = 0 at
 * r = c. (One shell: s1 = s2.)
 */
#ifndef THORAX_VERIFY_H
#define THORAX_VERIFY_H

#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

/* The analytic potential at radius r (a <= r <= c) and cos(theta) = ct. */
double thx_shells_potential(int l, double a, double b, double c, double s1, double s2, double r, double ct);
/* Legendre polynomial P_l(x). */
double thx_legendre(int l, double x);

/*
 * A tetrahedral mesh of the shells a <= r <= c (a "cubed sphere": each face
 * of a cube split into n x n cells, projected onto the spheres, with nr1
 * layers of cells between a and b and nr2 between b and c; each hexahedral
 * cell split into 6 right-handed tetrahedra, consistently across neighbours
 * so the mesh is conforming). Nodes on r = a, r = b and r = c lie exactly on
 * those spheres (to rounding). Region 0 is the inner shell (sigma s1,
 * isotropic), region 1 the outer one (s2); the interface r = b is a set of
 * faces of the mesh. inner/outer: the nodes on r = a and on r = c (0-based,
 * malloc'ed). The mesh's surfaces and node tables are left empty.
 */
thx_status thx_shells_mesh(thx_ctx *ctx, double a, double b, double c, double s1, double s2, int n, int nr1, int nr2,
                           thx_volume **out, int32_t **inner, size_t *n_inner, int32_t **outer, size_t *n_outer);

/*
 * A box [0,L] x [0,W] x [0,H] split into nx x ny x nz cells of 6 tetrahedra,
 * one region with the conductivity tensor sigma (row-major, symmetric
 * positive definite). The closed form used against it: the potential
 * phi(x) = g . x with g = sigma^-1 e_x / (sigma^-1)_xx (so that phi goes from
 * 0 to L along x and the current -sigma g is parallel to x: no current
 * through the faces y = 0, W and z = 0, H). ends: the nodes on x = 0 and
 * x = L (malloc'ed), where phi is prescribed.
 */
thx_status thx_slab_mesh(thx_ctx *ctx, double L, double W, double H, int nx, int ny, int nz, const double sigma[9],
                         thx_volume **out, int32_t **ends, size_t *n_ends);
/* The slab's closed-form potential at p. */
double thx_slab_potential(const double sigma[9], const double p[3]);

/*
 * An icosphere: the regular icosahedron with `level` rounds of midpoint
 * subdivision (each triangle into four, new nodes projected onto the
 * sphere), scaled to radius r about the origin: 10 4^level + 2 nodes
 * (level 2: 162, 3: 642, 4: 2562, 5: 10242), 20 4^level triangles
 * counterclockwise seen from outside, every node on the sphere (to
 * rounding). level 0 to 8. Caller destroys *out.
 */
thx_status thx_icosphere(thx_ctx *ctx, int level, double r, const char *name, thx_role role, thx_surface **out);

/* Error measures between a computed and a reference vector over n values:
 * RDM = || u/|u| - v/|v| || (0..2), MAG = |u| / |v| (1 = right magnitude). */
double thx_rdm(const double *u, const double *v, size_t n);
double thx_mag(const double *u, const double *v, size_t n);

#ifdef __cplusplus
}
#endif
#endif
