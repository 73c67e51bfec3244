/*
 * Which side of a closed surface a point is on, for the volume check (see check_volume.c): ray
 * parity with exact orient3d signs, sped up by a voxel grid whose free voxels are classified once
 * by flood fill; and from it, which of a model's surfaces nests in which.
 */
#include "check_volume_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"

/* Ray-parity inside test against one surface (exact orient3d signs). */

enum { VOX_UNKNOWN = 0, VOX_INSIDE = 1, VOX_OUTSIDE = 2, VOX_SURFACE = 3 };

typedef struct {
    const inside_surface *is;
    const double *p, *q;
    int crossings;
    int ambiguous;
} parity_state;

static int parity_visit(void *user, size_t t)
{
    parity_state *ps = user;
    const inside_surface *is = ps->is;
    if (is->degen[t]) return 0;
    const int32_t *v = is->s->tri + 3 * t;
    const double *a = is->s->xyz + 3 * (size_t)v[0], *b = is->s->xyz + 3 * (size_t)v[1];
    const double *c = is->s->xyz + 3 * (size_t)v[2];
    int s1 = sgn(thx_orient3d(a, b, c, ps->p)), s2 = sgn(thx_orient3d(a, b, c, ps->q));
    if (s1 * s2 > 0) return 0; /* both ends on one side */
    int w1 = sgn(thx_orient3d(ps->p, ps->q, a, b)), w2 = sgn(thx_orient3d(ps->p, ps->q, b, c));
    int w3 = sgn(thx_orient3d(ps->p, ps->q, c, a));
    int strict = (w1 > 0 && w2 > 0 && w3 > 0) || (w1 < 0 && w2 < 0 && w3 < 0);
    int closed = (w1 >= 0 && w2 >= 0 && w3 >= 0) || (w1 <= 0 && w2 <= 0 && w3 <= 0);
    if (!closed) return 0;
    if (strict && s1 != 0 && s2 != 0) {
        ps->crossings++;
        return 0;
    }
    /* through an edge or vertex, along the plane, or an end on the triangle */
    ps->ambiguous = 1;
    return 1;
}

/* Fixed small perturbations of the axis directions: rays along an axis would
 * run through the edges of grid-built surfaces. */
static const double ray_tilt[8][2] = {{0.0123456789, 0.0271828183}, {-0.0314159265, 0.0141421356},
                                      {0.0173205081, -0.0223606798}, {-0.0264575131, -0.0316227766},
                                      {0.1180339887, 0.0577350269}, {-0.0707106781, 0.1309016994},
                                      {0.0916515139, -0.1054092553}, {-0.1224744871, -0.0866025404}};

/* 1 inside, 0 outside, 2 decided by the solid-angle fallback (*inside set). */
static int classify_ray(const inside_surface *is, thx_vec3 pt, int *inside)
{
    double p[3] = {pt.x, pt.y, pt.z};
    /* the nearest side of the box first, then the others in a fixed order */
    double dist[6];
    for (int a = 0; a < 3; a++) {
        dist[2 * a] = is->hi[a] - p[a];
        dist[2 * a + 1] = p[a] - is->lo[a];
    }
    int best = 0;
    for (int k = 1; k < 6; k++)
        if (dist[k] < dist[best]) best = k;
    for (int attempt = 0; attempt < 8; attempt++) {
        int side = (best + attempt) % 6, ax = side / 2;
        double sign = (side & 1) ? -1.0 : 1.0;
        double d[3];
        d[ax] = sign;
        d[(ax + 1) % 3] = ray_tilt[attempt][0];
        d[(ax + 2) % 3] = ray_tilt[attempt][1];
        /* long enough to leave the box: the axis component alone must cover the distance */
        double len = dist[side] + 0.01 * is->diag + 1.0;
        double q[3] = {p[0] + len * d[0], p[1] + len * d[1], p[2] + len * d[2]};
        parity_state ps = {is, p, q, 0, 0};
        thx_bvh_query_segment(is->bvh, p, q, parity_visit, &ps);
        if (ps.ambiguous) continue;
        *inside = ps.crossings & 1;
        return *inside;
    }
    thx_inside w = thx_surface_inside(is->s, pt, 0.0);
    *inside = w == THX_INSIDE;
    return 2;
}

static size_t vox_index(const inside_surface *is, const double *p)
{
    size_t i[3];
    for (int a = 0; a < 3; a++) {
        double f = is->h[a] > 0.0 ? (p[a] - is->lo[a]) / is->h[a] : 0.0;
        long k = (long)floor(f);
        if (k < 0) k = 0;
        if (k >= is->n[a]) k = is->n[a] - 1;
        i[a] = (size_t)k;
    }
    return i[0] + (size_t)is->n[0] * (i[1] + (size_t)is->n[1] * i[2]);
}

/* A point p of a surface voxel (voxel coordinates v): the side of a free
 * voxel nearby (up to 3 voxels away), flipped by the parity of the exact
 * crossings of the short segment from p to a point inside it. Every point of
 * a free voxel is on that voxel's side, so this is the ray-parity test with a
 * ray of a few voxels instead of one across the surface's box. 0 if no free
 * voxel is near or every segment tried grazes an edge (the caller casts a
 * full ray). */
static int classify_near(const inside_surface *is, const double *p, const size_t v[3], int *inside)
{
    static const double frac[4][3] = {{0.5, 0.5, 0.5}, {0.31, 0.62, 0.43}, {0.67, 0.36, 0.58}, {0.42, 0.71, 0.29}};
    for (int rad = 1; rad <= 3; rad++)
        for (int dz = -rad; dz <= rad; dz++)
            for (int dy = -rad; dy <= rad; dy++)
                for (int dx = -rad; dx <= rad; dx++) {
                    if (abs(dx) != rad && abs(dy) != rad && abs(dz) != rad) continue; /* the shell only */
                    long w[3] = {(long)v[0] + dx, (long)v[1] + dy, (long)v[2] + dz};
                    int in_grid = 1;
                    for (int a = 0; a < 3; a++) in_grid &= w[a] >= 0 && w[a] < is->n[a];
                    if (!in_grid) continue;
                    unsigned char c =
                        is->vox[(size_t)w[0] + (size_t)is->n[0] * ((size_t)w[1] + (size_t)is->n[1] * (size_t)w[2])];
                    if (c != VOX_INSIDE && c != VOX_OUTSIDE) continue;
                    for (int t = 0; t < 4; t++) {
                        double q[3];
                        for (int a = 0; a < 3; a++) q[a] = is->lo[a] + ((double)w[a] + frac[t][a]) * is->h[a];
                        parity_state ps = {is, p, q, 0, 0};
                        thx_bvh_query_segment(is->bvh, p, q, parity_visit, &ps);
                        if (ps.ambiguous) continue;
                        *inside = (c == VOX_INSIDE) ^ (ps.crossings & 1);
                        return 1;
                    }
                }
    return 0;
}

/* As classify_ray, through the voxel grid where it can. */
int cv_classify_point(const inside_surface *is, thx_vec3 pt, int *inside)
{
    double p[3] = {pt.x, pt.y, pt.z};
    for (int a = 0; a < 3; a++)
        if (!(p[a] >= is->lo[a] && p[a] <= is->hi[a])) {
            *inside = 0;
            return 0;
        }
    if (is->vox) {
        size_t k = vox_index(is, p);
        unsigned char c = is->vox[k];
        if (c == VOX_INSIDE || c == VOX_OUTSIDE) {
            *inside = c == VOX_INSIDE;
            return *inside;
        }
        size_t vv[3] = {k % (size_t)is->n[0], (k / (size_t)is->n[0]) % (size_t)is->n[1],
                        k / ((size_t)is->n[0] * (size_t)is->n[1])};
        if (classify_near(is, p, vv, inside)) return *inside;
    }
    return classify_ray(is, pt, inside);
}

/* Builds the voxel grid: about 64 voxels per triangle, at most 256 a side (16 were measured 1.5x
 * slower for the cells of the high-resolution phantom: more centroids fell in surface voxels and
 * needed a ray; 256 saved nothing more and cost more to build). */
static thx_status build_voxels(thx_ctx *ctx, inside_surface *is)
{
    const thx_surface *s = is->s;
    double ext[3], vol = 1.0;
    int flat = 0;
    for (int a = 0; a < 3; a++) {
        ext[a] = is->hi[a] - is->lo[a];
        if (ext[a] > 0.0) vol *= ext[a];
        else flat = 1;
    }
    if (flat) return THX_OK; /* no grid: rays only */
    double target = fmin(64.0 * (double)s->n_tris, 256.0 * 256.0 * 256.0);
    double h = cbrt(vol / target);
    size_t total = 1;
    for (int a = 0; a < 3; a++) {
        double na = ceil(ext[a] / h);
        is->n[a] = (int)fmax(1.0, fmin(256.0, na));
        is->h[a] = ext[a] / is->n[a];
        total *= (size_t)is->n[a];
    }
    is->vox = thx_calloc(ctx, total, 1);
    if (!is->vox) return THX_ENOMEM;
    /* voxels touched by a triangle's box, widened by a millionth of a voxel */
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        int i0[3], i1[3];
        for (int a = 0; a < 3; a++) {
            double x0 = s->xyz[3 * (size_t)v[0] + a], x1 = s->xyz[3 * (size_t)v[1] + a];
            double x2 = s->xyz[3 * (size_t)v[2] + a];
            double lo = fmin(x0, fmin(x1, x2)), hi = fmax(x0, fmax(x1, x2));
            double f0 = (lo - is->lo[a]) / is->h[a] - 1e-6, f1 = (hi - is->lo[a]) / is->h[a] + 1e-6;
            i0[a] = (int)fmax(0.0, floor(f0));
            i1[a] = (int)fmin((double)is->n[a] - 1, floor(f1));
        }
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++)
                    is->vox[(size_t)x + (size_t)is->n[0] * ((size_t)y + (size_t)is->n[1] * (size_t)z)] = VOX_SURFACE;
    }
    /* flood fill of the free voxels, one ray from the centre of the first of each set */
    size_t *queue = thx_malloc(ctx, total * sizeof *queue);
    if (!queue) return THX_ENOMEM;
    size_t nx = (size_t)is->n[0], ny = (size_t)is->n[1], nz = (size_t)is->n[2];
    for (size_t start = 0; start < total; start++) {
        if (is->vox[start] != VOX_UNKNOWN) continue;
        size_t x = start % nx, y = (start / nx) % ny, z = start / (nx * ny);
        thx_vec3 c = thx_v3(is->lo[0] + ((double)x + 0.5) * is->h[0], is->lo[1] + ((double)y + 0.5) * is->h[1],
                            is->lo[2] + ((double)z + 0.5) * is->h[2]);
        int inside = 0;
        classify_ray(is, c, &inside);
        unsigned char label = inside ? VOX_INSIDE : VOX_OUTSIDE;
        size_t qh = 0, qt = 0;
        is->vox[start] = label;
        queue[qt++] = start;
        while (qh < qt) {
            size_t k = queue[qh++];
            size_t kx = k % nx, ky = (k / nx) % ny, kz = k / (nx * ny);
            size_t nb[6];
            int m = 0;
            if (kx > 0) nb[m++] = k - 1;
            if (kx + 1 < nx) nb[m++] = k + 1;
            if (ky > 0) nb[m++] = k - nx;
            if (ky + 1 < ny) nb[m++] = k + nx;
            if (kz > 0) nb[m++] = k - nx * ny;
            if (kz + 1 < nz) nb[m++] = k + nx * ny;
            for (int j = 0; j < m; j++)
                if (is->vox[nb[j]] == VOX_UNKNOWN) {
                    is->vox[nb[j]] = label;
                    queue[qt++] = nb[j];
                }
        }
    }
    free(queue);
    return THX_OK;
}

void cv_inside_surface_free(inside_surface *is)
{
    thx_bvh_destroy(&is->bvh);
    free(is->degen);
    free(is->vox);
    is->degen = NULL;
    is->vox = NULL;
}

/* Prepares a surface for cv_classify_point; returns THX_EINPUT (without a
 * message kept in ctx) for a surface that cannot be used. */
thx_status cv_inside_surface_init(thx_ctx *ctx, const thx_surface *s, inside_surface *is)
{
    memset(is, 0, sizeof *is);
    is->s = s;
    if (s->n_tris == 0 || s->n_nodes == 0) return THX_EINPUT;
    for (size_t k = 0; k < 3 * s->n_tris; k++)
        if (s->tri[k] < 0 || (size_t)s->tri[k] >= s->n_nodes) return THX_EINPUT;
    is->degen = thx_calloc(ctx, s->n_tris, 1);
    if (!is->degen) return THX_ENOMEM;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 a = node3(s->xyz, v[0]);
        thx_vec3 n = thx_v3_cross(thx_v3_sub(node3(s->xyz, v[1]), a), thx_v3_sub(node3(s->xyz, v[2]), a));
        is->degen[t] = v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || (n.x == 0.0 && n.y == 0.0 && n.z == 0.0);
    }
    for (int a = 0; a < 3; a++) {
        is->lo[a] = INFINITY;
        is->hi[a] = -INFINITY;
    }
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int a = 0; a < 3; a++) {
            is->lo[a] = fmin(is->lo[a], s->xyz[3 * i + a]);
            is->hi[a] = fmax(is->hi[a], s->xyz[3 * i + a]);
        }
    is->diag = sqrt((is->hi[0] - is->lo[0]) * (is->hi[0] - is->lo[0]) +
                    (is->hi[1] - is->lo[1]) * (is->hi[1] - is->lo[1]) +
                    (is->hi[2] - is->lo[2]) * (is->hi[2] - is->lo[2]));
    if (!isfinite(is->diag)) return THX_EINPUT;
    thx_status st = thx_bvh_create_triangles(ctx, s->xyz, s->n_nodes, s->tri, s->n_tris, &is->bvh);
    if (st == THX_EINPUT) thx_ctx_clear(ctx);
    if (st != THX_OK) return st;
    return build_voxels(ctx, is);
}

/* The parent of each usable surface: the smallest-volume usable surface of
 * larger volume that holds most of (up to 256 spread) nodes of it; -1 none.
 * order: the surfaces by increasing |volume|. */
void cv_nesting(const thx_model *m, const inside_surface *isf, const unsigned char *usable, const size_t *order,
                thx_volume_surface_report *sr)
{
    size_t ns = m->n_surfaces;
    for (size_t a = 0; a < ns; a++) {
        sr[a].parent = -1;
        if (!usable[a]) continue;
        const thx_surface *A = m->surf[a];
        size_t nsample = A->n_nodes < 256 ? A->n_nodes : 256;
        for (size_t k = 0; k < ns; k++) {
            size_t b = order[k];
            if (b == a || !usable[b] || !(fabs(sr[b].volume) > fabs(sr[a].volume))) continue;
            size_t in = 0;
            for (size_t j = 0; j < nsample; j++) {
                int inside = 0;
                cv_classify_point(&isf[b], node3(A->xyz, (int32_t)(j * A->n_nodes / nsample)), &inside);
                in += inside != 0;
            }
            if (2 * in > nsample) {
                sr[a].parent = (int)b;
                break;
            }
        }
    }
}
