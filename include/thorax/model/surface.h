/*
 * thorax/model/surface.h — triangle surfaces and the tissue roles of the model (model layer).
 *
 * Coordinate convention (RAS): +x toward the subject's right, +y anterior,
 * +z cranial (superior). Millimetres throughout.
 * "Counterclockwise seen cranio-caudally" (looking from the head toward the
 * feet, i.e. along -z) is a positive signed area in the (x, y) plane.
 * Triangles of a thx_surface are stored counterclockwise seen from outside:
 * (b - a) x (c - a) points out of the enclosed volume.
 */
#ifndef THORAX_MODEL_SURFACE_H
#define THORAX_MODEL_SURFACE_H

#include "thorax/core/core.h"
#include "thorax/core/vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Tissue role of a surface (paper 3.1: the boundaries between tissues of
 * different conductivity). The text names are used in files and on the CLI. */
typedef enum {
    THX_ROLE_OUTER = 0,  /* "outer": outer boundary of the torso */
    THX_ROLE_FAT,        /* "fat": subcutaneous fat / skeletal muscle interface */
    THX_ROLE_MUSCLE,     /* "muscle": inner border of the skeletal muscle */
    THX_ROLE_LUNG,       /* "lung" */
    THX_ROLE_HEART,      /* "heart": epicardium */
    THX_ROLE_OTHER,      /* "other" */
    THX_ROLE_COUNT
} thx_role;

/* "outer", "fat", ... (static storage). */
const char *thx_role_name(thx_role r);
/* Parses a role name; returns 0 on success, -1 if unknown. */
int thx_role_parse(const char *s, thx_role *out);

/*
 * A closed triangle surface. Plain data: fields may be read and written
 * directly; thx_surface_destroy frees the arrays.
 *   xyz: 3 * n_nodes doubles.  tri: 3 * n_tris node indices, 0-based,
 *   counterclockwise seen from outside once the surface is built.
 */
typedef struct thx_surface {
    char name[64];
    thx_role role;
    size_t n_nodes;
    double *xyz;
    size_t n_tris;
    int32_t *tri;
} thx_surface;

/* New empty surface (arrays NULL). Caller destroys. */
thx_status thx_surface_create(thx_ctx *ctx, const char *name, thx_role role, thx_surface **out);
/* Frees the surface and its arrays; accepts NULL; nulls *s. */
void thx_surface_destroy(thx_surface **s);

/* The invariants every surface holds before it is written or used: arrays present for the counts,
 * finite coordinates, at most INT32_MAX nodes, node indices in range. Errors name the surface, the
 * node or the triangle (1-based). */
thx_status thx_surface_validate(thx_ctx *ctx, const thx_surface *s);

/* Signed enclosed volume (mm^3) by the divergence theorem, summed about the centre of the
 * bounding box (less cancellation far from the origin): > 0 iff the triangles of a closed
 * surface face outward. */
double thx_surface_volume(const thx_surface *s);

/* The area-weighted normal sums at the nodes, into out (3 n_nodes doubles, overwritten): at node i,
 * the sum over the triangles at i of (b - a) x (c - a), twice the triangle's area times its unit
 * normal, taken in the triangles' order. Unit normals are these divided by their length (zero at a
 * node of no triangle, or where the triangles cancel); the renderer, the ray tracer, the web page
 * and the tissue votes all use them. */
void thx_surface_normal_sums(const thx_surface *s, double *out);

/* The point of s's triangles nearest to p (src/model/surface_nearest.c): returns its distance,
 * sets *tri (0-based triangle; ties: the lowest number), w (barycentric weights of the triangle's
 * corners, >= 0, sum 1) and q (the point, mm). A brute-force scan of every triangle: O(n_tris) per
 * point, meant for electrode sets (hundreds of points), not for large queries. -1 if s has no
 * triangle. */
double thx_surface_nearest(const thx_surface *s, const double p[3], size_t *tri, double w[3], double q[3]);

static inline thx_vec3 thx_surface_node(const thx_surface *s, size_t i)
{
    return thx_v3(s->xyz[3 * i], s->xyz[3 * i + 1], s->xyz[3 * i + 2]);
}

#ifdef __cplusplus
}
#endif
#endif
