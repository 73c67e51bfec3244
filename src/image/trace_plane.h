/*
 * One plane of a label map traced into loops (src/image/trace_plane.c), for the tracer's driver
 * (src/image/trace.c): the smoothed indicator of a tissue's mask on the plane, marching squares,
 * holes filled or kept, beads dropped, loops resampled at the node spacing without crossing. Private
 * to src/image (not installed); docs/design/image.md, "Tracing label maps".
 */
#ifndef THORAX_IMAGE_TRACE_PLANE_H
#define THORAX_IMAGE_TRACE_PLANE_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/image/trace.h"

#define ISO 0.5
#define PAD 3 /* zero cells around a plane's box: the smoothed field is below 0.5 on the buffer's rim */
#define KR 2  /* Gaussian kernel radius, cells (sigma 0.5: the weight at 3 is 1e-8) */

/* The geometry of the cut: the image's planes across its superior index axis, in model coordinates. */
typedef struct {
    const thx_image *img;
    int s, a0, a1;        /* superior index axis; the in-plane axes (a0 < a1) */
    size_t ns, n0, n1;    /* planes, and the plane's size along a0, a1 */
    size_t st[3];         /* stride of each index axis in the voxel array */
    double P0[2], A0[2], A1[2]; /* model (x, y) = P0 + A0 u + A1 v for in-plane indices (u, v) */
    double z0, dz;        /* model z of image plane k = z0 + dz k (dz = +-spacing) */
    double Q[9];          /* RAS = Q model, row-major */
} cut;

/* The voxel index of plane k, in-plane indices (u, v). */
static inline size_t vox(const cut *g, size_t k, size_t u, size_t v)
{
    return k * g->st[g->s] + u * g->st[g->a0] + v * g->st[g->a1];
}

/* A plane's smoothed field, on a buffer over the tissue's box. */
typedef struct {
    size_t W, H;          /* buffer size (cells) */
    long u0, v0;          /* in-plane index of buffer cell (0, 0) */
    float *f, *tmp;
    size_t cap;
} plane;

/* A loop (closed polygon, model coordinates) and a set of them. */
typedef struct {
    size_t n, cap;
    thx_vec2 *p;
} poly;
typedef struct {
    size_t n, cap;
    poly *l;
} polyset;

/* Per-thread scratch of the plane loop. */
typedef struct {
    plane pl;
    uint32_t *nxt;
    size_t nxt_cap;
    polyset raw, fin;
} plane_scratch;

/* The Gaussian's weights at sigma (voxels), 2 KR + 1 of them, summing to 1. */
void tp_gauss_weights(double sigma, double w[2 * KR + 1]);
void tp_polyset_clear(polyset *s);
void tp_polyset_free(polyset *s);
/* A new empty loop at the end of s, in *out. */
thx_status tp_polyset_new(thx_ctx *ctx, polyset *s, poly **out);
/* The signed area (counterclockwise positive). */
double tp_poly_area(const thx_vec2 *p, size_t n);
/* Is q inside the polygon (even-odd)? */
int tp_point_in(const thx_vec2 *p, size_t n, thx_vec2 q);
/* A point just to the left of edge i of P (inside a counterclockwise loop). */
thx_vec2 tp_inward(const poly *P, size_t i);
/* The bounding box x0 x1 y0 y1. */
void tp_bbox(const thx_vec2 *p, size_t n, double b[4]);
void tp_scratch_free(plane_scratch *sc);
/* One output plane of a tissue (continuous image plane index tk) traced into *out: trace_plane.c. */
thx_status tp_trace_plane(thx_ctx *ctx, const cut *g, const unsigned char *mask, const long *pb, double tk,
                          int resampled, const double w[2 * KR + 1], thx_trace_holes holes, double h, double amin,
                          plane_scratch *sc, polyset *out, size_t *n_holes, size_t *n_islands, size_t *n_tiny,
                          thx_vec2 *probe);

#endif
