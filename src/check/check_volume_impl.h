/*
 * Private to the volume checker (src/check/check_volume*.c): what its files share. Not installed,
 * not public; the entry points are in thorax/check/check_volume.h.
 *
 *   check_volume.c           options, failure names and reasons, the regions' expected volumes,
 *                            thx_volume_check (the checks in order, the verdict), report_free
 *   check_volume_tets.c      thx_tet_quality and the pass over the tetrahedra (cv_tets)
 *   check_volume_topology.c  faces, duplicates, the boundary surface, node tables, Steiner records
 *   check_volume_inside.c    point in a closed surface (ray parity and voxels); surface nesting
 *   check_volume_coverage.c  the surfaces' coverage by the interface faces
 *   check_volume_json.c      thx_volume_report_json
 *
 * Functions shared between these files are named cv_; each is described above its definition.
 */
#ifndef THORAX_CHECK_VOLUME_IMPL_H
#define THORAX_CHECK_VOLUME_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/check/check_volume.h"
#include "thorax/geom/spatial.h"

/* OpenMP pragmas that vanish when the library is built without OpenMP. */
#ifdef _OPENMP
#define THX_OMP(x) _Pragma(#x)
#else
#define THX_OMP(x)
#endif

/* Outward faces of a right-handed tetrahedron (volume.h): face k is opposite
 * vertex k, counterclockwise seen from outside. */
static const int vface[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

static inline thx_vec3 node3(const double *xyz, int32_t i)
{
    return thx_v3(xyz[3 * (size_t)i], xyz[3 * (size_t)i + 1], xyz[3 * (size_t)i + 2]);
}

static inline int sgn(double x) { return (x > 0) - (x < 0); }

/* Sorts three ints ascending; returns +1 for an even permutation, -1 for odd. */
static inline int sort3(int32_t *x)
{
    int par = 1;
    int32_t t;
    if (x[0] > x[1]) { t = x[0]; x[0] = x[1]; x[1] = t; par = -par; }
    if (x[1] > x[2]) { t = x[1]; x[1] = x[2]; x[2] = t; par = -par; }
    if (x[0] > x[1]) { t = x[0]; x[0] = x[1]; x[1] = t; par = -par; }
    return par;
}

/* What the pass over the tetrahedra finds of each. */
typedef struct {
    double vol;        /* signed volume */
    double mind, maxd; /* dihedral angles, deg */
    double re, rr;     /* radius-edge, radius ratio */
    double lmin, lmax; /* edges */
    int8_t orient;     /* -1 right-handed (good), +1 inverted, 0 flat */
    int8_t repeated;   /* a node twice */
} tet_fig;

/* A closed surface prepared for the inside test (check_volume_inside.c). */
typedef struct {
    const thx_surface *s;
    thx_bvh *bvh;
    unsigned char *degen; /* per triangle: repeated node or zero cross product: skipped */
    double lo[3], hi[3];
    double diag;
    /* voxel grid over [lo, hi]: voxels no triangle's (slightly widened) box
     * touches hold no surface point, so every point of one is on one side,
     * shared by its face-neighbours of the same kind (flood fill, one ray per
     * connected set). VOX_SURFACE voxels need a ray per point. */
    int n[3];
    double h[3];
    unsigned char *vox;
} inside_surface;

/* check_volume_tets.c */
void cv_tets(const thx_volume *v, tet_fig *fig, unsigned char *used, thx_volume_report *r);

/* check_volume_topology.c */
thx_status cv_faces_and_boundary(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, unsigned char *bmask,
                                 thx_volume_report *r, size_t **iface, size_t *n_iface);
thx_status cv_duplicates(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, thx_volume_report *r);
thx_status cv_boundary(thx_ctx *ctx, const thx_volume *v, const unsigned char *bmask, const thx_volume_check_opts *o,
                       thx_volume_report *r, int32_t **bnode_out, size_t *n_bnodes);
void cv_node_tables(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r);
void cv_steiner_table(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r);

/* check_volume_inside.c */
thx_status cv_inside_surface_init(thx_ctx *ctx, const thx_surface *s, inside_surface *is);
void cv_inside_surface_free(inside_surface *is);
int cv_classify_point(const inside_surface *is, thx_vec3 pt, int *inside);
void cv_nesting(const thx_model *m, const inside_surface *isf, const unsigned char *usable, const size_t *order,
                thx_volume_surface_report *sr);

/* check_volume_coverage.c */
thx_status cv_coverage(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const size_t *iface, size_t n_iface,
                       const thx_volume_check_opts *o, thx_volume_report *r);

#endif
