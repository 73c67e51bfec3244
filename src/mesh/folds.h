/*
 * The sharp folds of a surface of given potentials, and the graded mesh size
 * around them (internal to src/mesh; docs/design/mesh.md, "Folds").
 *
 * With the heart left out of the domain (thorax mesh --no-heart) its surface
 * is a boundary of given potentials, and an edge where that surface folds
 * sharply (the thin rim where an endocardium meets the epicardium: an
 * interior dihedral angle of a few degrees) is a re-entrant edge of the
 * domain, of angle close to 360 degrees. The potential there behaves like
 * r^(pi/alpha), nearly a square root: linear elements of the grid's size
 * lose most of what flows around the rim, and every column of the transfer
 * matrix whose node sits in a cavity behind it (Babuska's graded meshes are
 * the classical answer). A fold is an edge whose interior dihedral angle is
 * below a bound; the size field is h0 + grade * (distance to the nearest
 * fold), with no bound where that reaches hmax.
 */
#ifndef THORAX_MESH_FOLDS_H
#define THORAX_MESH_FOLDS_H

#include "thorax/geom/spatial.h"
#include "thorax/model/surface.h"

typedef struct {
    double *seg;   /* n segments, 6 doubles each (the two ends) */
    size_t n;
    thx_bvh *bvh;  /* over the segments' boxes */
    double h0, grade, hmax;
} mesh_folds;

/*
 * The edges of closed, outward-oriented surface s whose interior dihedral angle (the angle inside
 * the surface between its two triangles, 0..360 degrees) is below max_deg. An edge that is not
 * in exactly two triangles is not a fold. f->n may be 0 (then mesh_folds_size is INFINITY
 * everywhere).
 */
thx_status mesh_folds_find(thx_ctx *ctx, const thx_surface *s, double max_deg, double h0, double grade, double hmax,
                           mesh_folds *f);
/* The interior dihedral angle (degrees, 0..360) of edge (a, b) between triangle (a, b, c) and the
 * triangle on its other side whose third corner is d, for a surface oriented counterclockwise seen
 * from outside. */
double mesh_interior_dihedral(const double a[3], const double b[3], const double c[3], const double d[3]);
/* The bound on a tetrahedron's circumradius at p: h0 + grade * (distance to the nearest fold), or
 * INFINITY where that is at least hmax. Thread-safe. */
double mesh_folds_size(const mesh_folds *f, const double p[3]);
void mesh_folds_free(mesh_folds *f);

#endif
