/* Point location against a closed surface (see locate.h). */
#include "mesh/locate.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
typedef struct {
    const thx_surface *s;
    const double *p, *q;
    int crossings;
    int degenerate;
} ray_state;

static int ray_visit(void *user, size_t t)
{
    ray_state *r = user;
    const thx_surface *s = r->s;
    const double *a = s->xyz + 3 * (size_t)s->tri[3 * t], *b = s->xyz + 3 * (size_t)s->tri[3 * t + 1],
                 *c = s->xyz + 3 * (size_t)s->tri[3 * t + 2];
    double sp = thx_orient3d(a, b, c, r->p), sq = thx_orient3d(a, b, c, r->q);
    if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return 0;
    if (sq == 0) { r->degenerate = 1; return 1; } /* the far end never lies on a triangle; be safe */
    if (sp == 0) return 0;                          /* the point itself on the triangle's plane: not a crossing of the open ray */
    double e0 = thx_orient3d(r->p, r->q, a, b), e1 = thx_orient3d(r->p, r->q, b, c), e2 = thx_orient3d(r->p, r->q, c, a);
    if ((e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0)) { r->crossings++; return 0; }
    if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) { r->degenerate = 1; return 1; }
    return 0;
}

/* The long rays of the original test: 1 inside, 0 outside, -1 if all six
 * directions grazed an edge, a vertex or a plane. */
static int ray_parity(const locator *l, const double pp[3])
{
    /* Fixed, irrational-looking directions: grazing an edge is a measure-zero event; retry if it happens. */
    static const double dir[6][3] = {{0.1327, 0.2461, 0.9601},  {-0.5817, 0.3923, 0.7126}, {0.7713, -0.4172, 0.4806},
                                     {-0.2203, -0.8314, 0.5101}, {0.6151, 0.6612, -0.4295}, {-0.3391, 0.1783, -0.9237}};
    for (int k = 0; k < 6; k++) {
        double q[3] = {pp[0] + l->reach * dir[k][0], pp[1] + l->reach * dir[k][1], pp[2] + l->reach * dir[k][2]};
        ray_state r = {l->s, pp, q, 0, 0};
        thx_bvh_query_segment(l->bvh, pp, q, ray_visit, &r);
        if (!r.degenerate) return r.crossings & 1;
    }
    return -1;
}

/* Voxel of a point, per axis floor((x - lo) / h) clamped to the grid. Monotone
 * in each coordinate (rounding included), so a triangle's points all fall in
 * voxels between those of its bounding box's corners. */
static int vox_axis(const locator *l, int a, double x)
{
    double f = (x - l->lo[a]) * l->inv_h[a];
    if (!(f >= 0.0)) return 0;
    if (f >= (double)l->n[a]) return l->n[a] - 1;
    int k = (int)f;
    return k < l->n[a] ? k : l->n[a] - 1;
}

static size_t vox_of(const locator *l, const double p[3])
{
    return (size_t)vox_axis(l, 0, p[0]) +
           (size_t)l->n[0] * ((size_t)vox_axis(l, 1, p[1]) + (size_t)l->n[1] * (size_t)vox_axis(l, 2, p[2]));
}

static void vox_centre(const locator *l, size_t v, double c[3])
{
    size_t nx = (size_t)l->n[0], ny = (size_t)l->n[1];
    size_t i[3] = {v % nx, (v / nx) % ny, v / (nx * ny)};
    for (int a = 0; a < 3; a++) c[a] = l->lo[a] + ((double)i[a] + 0.5) * l->h[a];
}

/* p coplanar with abc: is it in the closed triangle? (1 also when abc is
 * degenerate: undecided, the caller falls back.) Exact: orient2d on a
 * projection where abc has non-zero area, which maps the plane one to one. */
static int point_in_coplanar_triangle(const double *p, const double *a, const double *b, const double *c)
{
    for (int ax = 0; ax < 3; ax++) {
        int u = (ax + 1) % 3, v = (ax + 2) % 3;
        double pa[2] = {a[u], a[v]}, pb[2] = {b[u], b[v]}, pc[2] = {c[u], c[v]}, pq[2] = {p[u], p[v]};
        double o = thx_orient2d(pa, pb, pc);
        if (o == 0) continue;
        double w0 = thx_orient2d(pa, pb, pq), w1 = thx_orient2d(pb, pc, pq), w2 = thx_orient2d(pc, pa, pq);
        if (o > 0) return w0 >= 0 && w1 >= 0 && w2 >= 0;
        return w0 <= 0 && w1 <= 0 && w2 <= 0;
    }
    return 1;
}

/* Segment p-q, q the centre of a labelled voxel (so on no triangle): counts
 * the crossings; the segment through an edge or a vertex, along a plane, or p
 * on a triangle makes it degenerate. An end merely on a triangle's plane (q
 * always outside the triangle) is no crossing. */
static int seg_visit(void *user, size_t t)
{
    ray_state *r = user;
    const thx_surface *s = r->s;
    const double *a = s->xyz + 3 * (size_t)s->tri[3 * t], *b = s->xyz + 3 * (size_t)s->tri[3 * t + 1],
                 *c = s->xyz + 3 * (size_t)s->tri[3 * t + 2];
    double sp = thx_orient3d(a, b, c, r->p), sq = thx_orient3d(a, b, c, r->q);
    if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return 0;
    if (sp == 0 && sq == 0) { r->degenerate = 1; return 1; } /* along the plane */
    if (sq == 0) return 0; /* meets the plane only at q, which is on no triangle */
    if (sp == 0) {
        /* meets the plane only at p: a crossing of nothing unless p is on the triangle (on the surface) */
        if (point_in_coplanar_triangle(r->p, a, b, c)) { r->degenerate = 1; return 1; }
        return 0;
    }
    double e0 = thx_orient3d(r->p, r->q, a, b), e1 = thx_orient3d(r->p, r->q, b, c), e2 = thx_orient3d(r->p, r->q, c, a);
    if ((e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0)) { r->crossings++; return 0; }
    if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) { r->degenerate = 1; return 1; }
    return 0;
}

int locator_inside(const locator *l, thx_vec3 p)
{
    double pp[3] = {p.x, p.y, p.z};
    if (l->vox) {
        /* outside the box of a closed surface: outside (also what every ray says) */
        for (int a = 0; a < 3; a++)
            if (!(pp[a] >= l->lo[a] && pp[a] <= l->hi[a])) return 0;
        size_t v = vox_of(l, pp);
        unsigned char lab = l->vox[v];
        if (lab) return lab == 1;
        int32_t rv = l->ref[v];
        if (rv >= 0) {
            double q[3];
            vox_centre(l, (size_t)rv, q);
            ray_state r = {l->s, pp, q, 0, 0};
            thx_bvh_query_segment(l->bvh, pp, q, seg_visit, &r);
            if (!r.degenerate) return (l->vox[rv] == 1) ^ (r.crossings & 1);
        }
    }
    int k = ray_parity(l, pp);
    return k < 0 ? 0 : k;
}

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

/* Every edge (node pair) in an even number of triangles: the surface is a
 * mod-2 cycle, so the parity of crossings of any generic path from a point to
 * far away is the same, and points joined by a path that meets no triangle
 * are on the same side. Otherwise the voxel cache is not used. */
static int closed_mod2(thx_ctx *ctx, const thx_surface *s, int *closed)
{
    *closed = 0;
    size_t ne = 3 * s->n_tris;
    uint64_t *e = thx_malloc(ctx, (ne ? ne : 1) * sizeof *e);
    if (!e) return THX_ENOMEM;
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            if (a < 0 || b < 0 || (size_t)a >= s->n_nodes || (size_t)b >= s->n_nodes) { free(e); return THX_OK; }
            uint32_t lo = (uint32_t)(a < b ? a : b), hi = (uint32_t)(a < b ? b : a);
            e[3 * t + k] = ((uint64_t)lo << 32) | hi;
        }
    qsort(e, ne, sizeof *e, cmp_u64);
    int ok = 1;
    for (size_t i = 0; i < ne && ok;) {
        size_t j = i;
        while (j < ne && e[j] == e[i]) j++;
        if ((j - i) & 1) ok = 0;
        i = j;
    }
    free(e);
    *closed = ok;
    return THX_OK;
}

static thx_status build_grid(thx_ctx *ctx, locator *l)
{
    const thx_surface *s = l->s;
    if (s->n_tris == 0) return THX_OK;
    double ext[3], vol = 1.0;
    for (int a = 0; a < 3; a++) {
        ext[a] = l->hi[a] - l->lo[a];
        if (!(ext[a] > 0.0) || !isfinite(ext[a])) return THX_OK; /* flat or odd: rays only */
        vol *= ext[a];
    }
    int closed;
    thx_status st = closed_mod2(ctx, s, &closed);
    if (st != THX_OK || !closed) return st;
    /* about 16 voxels per triangle, at most 128 a side */
    double target = fmin(16.0 * (double)s->n_tris, 128.0 * 128.0 * 128.0);
    double hh = cbrt(vol / target);
    size_t total = 1;
    for (int a = 0; a < 3; a++) {
        l->n[a] = (int)fmax(1.0, fmin(128.0, ceil(ext[a] / hh)));
        l->h[a] = ext[a] / l->n[a];
        l->inv_h[a] = (double)l->n[a] / ext[a];
        total *= (size_t)l->n[a];
    }
    unsigned char *vox = thx_calloc(ctx, total, 1);
    int32_t *ref = thx_malloc(ctx, total * sizeof *ref);
    size_t *queue = thx_malloc(ctx, total * sizeof *queue);
    if (!vox || !ref || !queue) {
        free(vox); free(ref); free(queue);
        return THX_ENOMEM;
    }
    enum { FREE = 0, IN = 1, OUT = 2, TOUCHED = 3, VISIT = 4 };
    size_t nx = (size_t)l->n[0], ny = (size_t)l->n[1], nz = (size_t)l->n[2];
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        double blo[3], bhi[3];
        for (int a = 0; a < 3; a++) {
            double x0 = s->xyz[3 * (size_t)v[0] + a], x1 = s->xyz[3 * (size_t)v[1] + a], x2 = s->xyz[3 * (size_t)v[2] + a];
            blo[a] = fmin(x0, fmin(x1, x2));
            bhi[a] = fmax(x0, fmax(x1, x2));
        }
        int i0[3], i1[3];
        for (int a = 0; a < 3; a++) {
            i0[a] = vox_axis(l, a, blo[a]);
            i1[a] = vox_axis(l, a, bhi[a]);
        }
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++) vox[(size_t)x + nx * ((size_t)y + ny * (size_t)z)] = TOUCHED;
    }
    /* connected sets of free voxels: one exact long ray from the centre of
     * one of them (a centre inside its own voxel, the ray grazing nothing) */
    for (size_t start = 0; start < total; start++) {
        if (vox[start] != FREE) continue;
        size_t qh = 0, qt = 0;
        vox[start] = VISIT;
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
                if (vox[nb[j]] == FREE) {
                    vox[nb[j]] = VISIT;
                    queue[qt++] = nb[j];
                }
        }
        int inside = -1;
        for (size_t i = 0, tries = 0; i < qt && tries < 16 && inside < 0; i++) {
            double c[3];
            vox_centre(l, queue[i], c);
            if (vox_of(l, c) != queue[i]) continue;
            tries++;
            inside = ray_parity(l, c);
        }
        /* undecided (never seen): treated as touched, rays per point */
        unsigned char lab = inside < 0 ? TOUCHED : inside ? IN : OUT;
        for (size_t i = 0; i < qt; i++) vox[queue[i]] = lab;
    }
    /* touched voxels: the nearest labelled voxel (breadth first, fixed order)
     * whose centre lies in itself, a short segment's end */
    size_t qh = 0, qt = 0;
    for (size_t k = 0; k < total; k++) {
        ref[k] = -1;
        if (vox[k] == IN || vox[k] == OUT) {
            double c[3];
            vox_centre(l, k, c);
            if (vox_of(l, c) == k) {
                ref[k] = (int32_t)k;
                queue[qt++] = k;
            }
        }
    }
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
            if (ref[nb[j]] < 0 && vox[nb[j]] == TOUCHED) {
                ref[nb[j]] = ref[k];
                queue[qt++] = nb[j];
            }
    }
    for (size_t k = 0; k < total; k++)
        if (vox[k] == TOUCHED) vox[k] = 0;
    free(queue);
    l->vox = vox;
    l->ref = ref;
    return THX_OK;
}

thx_status locator_init(thx_ctx *ctx, locator *l, const thx_surface *s)
{
    memset(l, 0, sizeof *l);
    l->s = s;
    l->bvh = NULL;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], s->xyz[3 * i + d]);
            hi[d] = fmax(hi[d], s->xyz[3 * i + d]);
        }
    l->reach = 2.0 * (fabs(hi[0] - lo[0]) + fabs(hi[1] - lo[1]) + fabs(hi[2] - lo[2])) + 1.0;
    thx_status st = thx_bvh_create_triangles(ctx, s->xyz, s->n_nodes, s->tri, s->n_tris, &l->bvh);
    if (st != THX_OK) return st;
    for (int d = 0; d < 3; d++) {
        l->lo[d] = lo[d];
        l->hi[d] = hi[d];
    }
    return build_grid(ctx, l);
}

void locator_free(locator *l)
{
    thx_bvh_destroy(&l->bvh);
    free(l->vox);
    free(l->ref);
    l->vox = NULL;
    l->ref = NULL;
}

typedef struct {
    const thx_surface *s;
    thx_vec3 p;
    double r2;
} near_state;

static int near_visit(void *user, size_t t)
{
    near_state *n = user;
    const thx_surface *s = n->s;
    thx_vec3 a = thx_surface_node(s, (size_t)s->tri[3 * t]), b = thx_surface_node(s, (size_t)s->tri[3 * t + 1]),
             c = thx_surface_node(s, (size_t)s->tri[3 * t + 2]);
    return thx_triangle_distance2(a, b, c, n->p) < n->r2;
}

int locator_near(const locator *l, thx_vec3 p, double r)
{
    double lo[3] = {p.x - r, p.y - r, p.z - r}, hi[3] = {p.x + r, p.y + r, p.z + r};
    if (l->vox) {
        /* every triangle's bounding box lies in touched voxels; none among
         * the voxels covering the query box: no triangle is even a candidate */
        int i0[3], i1[3];
        for (int a = 0; a < 3; a++) {
            i0[a] = vox_axis(l, a, lo[a]);
            i1[a] = vox_axis(l, a, hi[a]);
        }
        size_t nx = (size_t)l->n[0], ny = (size_t)l->n[1];
        int touched = 0;
        for (int z = i0[2]; z <= i1[2] && !touched; z++)
            for (int y = i0[1]; y <= i1[1] && !touched; y++)
                for (int x = i0[0]; x <= i1[0]; x++)
                    if (!l->vox[(size_t)x + nx * ((size_t)y + ny * (size_t)z)]) { touched = 1; break; }
        if (!touched) return 0;
    }
    near_state n = {l->s, p, r * r};
    return thx_bvh_query_box(l->bvh, lo, hi, near_visit, &n) != 0;
}
