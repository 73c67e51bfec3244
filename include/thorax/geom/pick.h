/*
 * thorax/geom/pick.h — picking: which surface, triangle and node lies under the mouse
 * (paper 4.2, the viewer's pick; the viewer un-projects the mouse position into a ray).
 *
 * Rays are in model coordinates (mm): origin + t dir, t >= 0, dir any non-zero vector (it is
 * normalized, so t is a distance in mm).
 *
 * Robustness: the ray-triangle test is watertight (Woop, Benthin and Wald 2013, "Watertight
 * ray/triangle intersection"): the triangle's vertices are moved into a frame where the ray is the
 * z axis, and the ray hits the triangle when the origin of that frame's (x, y) plane lies on the
 * same side of the three edges. A shared edge is evaluated from the same two projected points in
 * both triangles, its sign by the exact predicate thx_orient2d, and a zero (the ray through the
 * edge or a vertex) is resolved by a fixed symbolic perturbation of the ray (a shift by (e, e^2)
 * in that plane), so a ray through an edge or a vertex of a closed, consistently oriented surface
 * hits exactly one of the triangles there: never none (no crack), never two. A ray lying in a
 * triangle's plane does not hit it. Both faces are hit (a ray from inside a surface hits it).
 *
 * Clip planes: half spaces n . x + d >= 0 are kept, as thx_clip_plane of thorax/render/render.h
 * (same layout). A hit in the clipped-away part is skipped and the ray goes on to the next hit
 * behind it. A surface whose skip flag is set (hidden) is never hit.
 *
 * The index borrows the surfaces: they must outlive it and must not change (coordinates or
 * triangles) while it is used. After an edit, destroy it and create it again (no refit).
 * A built index is read-only: picks from several threads are safe, each with its own context.
 */
#ifndef THORAX_GEOM_PICK_H
#define THORAX_GEOM_PICK_H

#include <stddef.h>

#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Keeps the half space n . x + d >= 0 (the layout of thx_clip_plane). */
typedef struct {
    double n[3], d;
} thx_pick_plane;

typedef struct {
    const thx_pick_plane *clip; /* n_clip planes, or NULL: a hit must lie in every kept half space */
    size_t n_clip;
    const unsigned char *skip;  /* one flag per surface, or NULL: non-zero = hidden, never hit */
    double t_max;               /* hits farther along the ray than this (mm) are ignored (default INFINITY) */
} thx_pick_opts;

/* No clip planes, no hidden surface, no limit along the ray. */
void thx_pick_opts_default(thx_pick_opts *o);

/* What a pick found. */
typedef struct {
    int surface;      /* index of the surface hit, in the order given; -1 when nothing was hit */
    size_t tri;       /* triangle of that surface (ray picks; (size_t)-1 for node picks) */
    double bary[3];   /* weights of the triangle's nodes tri[3t], tri[3t+1], tri[3t+2] at the hit:
                         each in [0, 1], summing to 1 (node picks: 0) */
    double point[3];  /* the hit point: bary-weighted nodes (node picks: the node) */
    double t;         /* distance from the origin along the ray, mm */
    size_t node;      /* the triangle's node nearest the hit point (ties: first in the triangle);
                         node picks: the node picked. Index into the surface's nodes. */
    int front;        /* 1 if the ray met the triangle's outside face (it runs against the normal
                         (b - a) x (c - a)), 0 its inside face (node picks: 0) */
    double dist;      /* node picks: the node's distance from the ray, mm (ray picks: 0) */
} thx_pick_hit;

/* A ray prepared for the watertight test: direction normalized, the axis it runs along most
 * (kz), and the shear that takes it to the z axis. Filled by thx_pick_ray_prepare. */
typedef struct {
    double o[3], d[3];
    int kx, ky, kz;
    double sx, sy, sz;
} thx_ray;

/* Prepares a ray; 0, or -1 if origin or dir is not finite or dir is zero (r is then unusable). */
int thx_pick_ray_prepare(thx_ray *r, const double origin[3], const double dir[3]);

/* The watertight ray-triangle test (above) for triangle a, b, c. 1 if the ray's line meets the
 * triangle, with the signed distance along the ray in *t (negative: behind the origin) and the
 * barycentric weights of a, b, c in bary[3] (either may be NULL); 0 if not. Pure. */
int thx_pick_triangle(const thx_ray *r, const double a[3], const double b[3], const double c[3], double *t,
                      double bary[3]);

typedef struct thx_pick_index thx_pick_index;

/* An index over n surfaces (borrowed, see above): one bounding-volume hierarchy per surface
 * (thorax/geom/spatial.h) over its triangles' boxes. Errors: THX_EINPUT naming the surface and the
 * triangle when a triangle refers to a node out of range or a coordinate is not finite. Caller
 * destroys *out. */
thx_status thx_pick_index_create(thx_ctx *ctx, const thx_surface *const *surf, size_t n, thx_pick_index **out);
/* Frees the index (not the surfaces); accepts NULL; nulls *idx. */
void thx_pick_index_destroy(thx_pick_index **idx);

/* The nearest hit of the ray (t >= 0) on the surfaces of the index, with the options o (NULL:
 * defaults); ties at the same t go to the lower surface index, then the lower triangle index.
 * hit->surface = -1 when nothing is hit. THX_EINPUT for a ray thx_pick_ray_prepare refuses. */
thx_status thx_pick_ray(thx_ctx *ctx, const thx_pick_index *idx, const double origin[3], const double dir[3],
                        const thx_pick_opts *o, thx_pick_hit *hit);

/* The same answer as thx_pick_ray (bit for bit) by testing every triangle: no index. The
 * reference for tests and benchmarks; the surfaces must be valid (thx_surface_validate: it is not
 * run here). */
thx_status thx_pick_ray_brute(thx_ctx *ctx, const thx_surface *const *surf, size_t n, const double origin[3],
                              const double dir[3], const thx_pick_opts *o, thx_pick_hit *hit);

/*
 * Pick by screen distance, for surfaces drawn as points: the node nearest the ray (smallest
 * distance r from the ray's line relative to the tolerance at its depth) among the nodes at
 * depth t >= 0 (and <= o->t_max) with r <= tol + slope * t, inside the clip planes, of surfaces
 * not skipped. A caller with an orthographic camera passes tol = the pixel tolerance times the
 * size of a pixel (mm) and slope = 0; with a perspective camera tol = 0 and slope = the pixel
 * tolerance times 2 tan(fov / 2) / image height (r / t is then the tangent of the angle off the
 * ray). Ties: the smaller t, then the lower surface, then the lower node. hit->surface = -1 when
 * no node is near enough. THX_EINPUT for a bad ray or a negative or non-finite tol or slope.
 */
thx_status thx_pick_node(thx_ctx *ctx, const thx_pick_index *idx, const double origin[3], const double dir[3],
                         double tol, double slope, const thx_pick_opts *o, thx_pick_hit *hit);

#ifdef __cplusplus
}
#endif
#endif
