/* Invariant checks of tetrahedral volume meshes (see thorax/check_volume.h; paper 3.3). */
#include "thorax/check/check_volume.h"
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include "thorax/geom/spatial.h"
#include "thorax/core/union_find.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* OpenMP pragmas that vanish when the library is built without OpenMP. */
#ifdef _OPENMP
#define THX_OMP(x) _Pragma(#x)
#else
#define THX_OMP(x)
#endif

const double thx_vcheck_dihedral_edges[THX_VCHECK_DIHEDRAL_BINS + 1] = {0, 5, 10, 15, 20, 30, 40, 50, 60, INFINITY};
const double thx_vcheck_radius_edge_edges[THX_VCHECK_RADIUS_EDGE_BINS + 1] = {
    0.61237243569579452, 0.8, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 100.0, INFINITY};

/* Outward faces of a right-handed tetrahedron (volume.h): face k is opposite
 * vertex k, counterclockwise seen from outside. */
static const int vface[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

void thx_volume_check_opts_default(thx_volume_check_opts *o)
{
    o->volume_tol = 0.01;
    o->region_volume_tol = 0.005;
    o->node_tol = 1e-5;
    o->coverage_tol = 1e-6;
    o->expected_cavities = -1;
    o->check_intersections = 1;
    o->min_dihedral_deg = 1.0;
    o->max_radius_edge = 0.0;
}

const char *thx_volume_check_failure_name(thx_volume_check_failure f)
{
    switch (f) {
    case THX_VCHECKF_EMPTY: return "empty";
    case THX_VCHECKF_BAD_INDEX: return "bad_index";
    case THX_VCHECKF_BAD_REGION: return "bad_region";
    case THX_VCHECKF_REPEATED_NODE: return "repeated_node";
    case THX_VCHECKF_INVERTED: return "inverted";
    case THX_VCHECKF_FLAT: return "flat";
    case THX_VCHECKF_UNUSED: return "unused_nodes";
    case THX_VCHECKF_DUPLICATE_NODE: return "duplicate_nodes";
    case THX_VCHECKF_DUPLICATE_TET: return "duplicate_tetrahedra";
    case THX_VCHECKF_NONCONFORMING: return "nonconforming";
    case THX_VCHECKF_BOUNDARY: return "boundary";
    case THX_VCHECKF_COMPONENTS: return "components";
    case THX_VCHECKF_CONTAINMENT: return "containment";
    case THX_VCHECKF_VOLUME: return "volume";
    case THX_VCHECKF_REGION_VOLUME: return "region_volume";
    case THX_VCHECKF_NODE_TABLE: return "node_table";
    case THX_VCHECKF_QUALITY: return "quality";
    case THX_VCHECKF_COVERAGE: return "coverage";
    case THX_VCHECKF_REGION_CELLS: return "region_cells";
    }
    return "?";
}

static void add_reason(thx_volume_report *r, thx_volume_check_failure f, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void add_reason(thx_volume_report *r, thx_volume_check_failure f, const char *fmt, ...)
{
    r->failures |= (unsigned)f;
    if (r->n_reasons >= THX_VCHECK_MAX_REASONS) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->reasons[r->n_reasons++], sizeof r->reasons[0], fmt, ap);
    va_end(ap);
}

static thx_vec3 node3(const double *xyz, int32_t i)
{
    return thx_v3(xyz[3 * (size_t)i], xyz[3 * (size_t)i + 1], xyz[3 * (size_t)i + 2]);
}

/* ------------------------------------------------------------------ */
/* Quality of one tetrahedron. */

void thx_tet_quality(const double *a, const double *b, const double *c, const double *d, double *min_dihedral,
                     double *max_dihedral, double *radius_edge, double *radius_ratio)
{
    double mn = 0.0, mx = 180.0, re = INFINITY, rr = 0.0;
    if (thx_orient3d(a, b, c, d) != 0.0) {
        thx_vec3 p[4] = {thx_v3(a[0], a[1], a[2]), thx_v3(b[0], b[1], b[2]), thx_v3(c[0], c[1], c[2]),
                         thx_v3(d[0], d[1], d[2])};
        /* face normals, all outward for a right-handed tetrahedron (all inward
         * otherwise: the angles between them are the same) */
        thx_vec3 n[4];
        double nn[4], area2 = 0.0;
        for (int k = 0; k < 4; k++) {
            thx_vec3 o = p[vface[k][0]];
            n[k] = thx_v3_cross(thx_v3_sub(p[vface[k][1]], o), thx_v3_sub(p[vface[k][2]], o));
            nn[k] = thx_v3_norm(n[k]);
            area2 += nn[k];
        }
        mn = INFINITY;
        mx = -INFINITY;
        for (int k = 0; k < 4; k++)
            for (int l = k + 1; l < 4; l++) {
                /* interior angle at the shared edge = pi - angle between the outward normals */
                double ang = atan2(thx_v3_norm(thx_v3_cross(n[k], n[l])), -thx_v3_dot(n[k], n[l])) * (180.0 / M_PI);
                mn = fmin(mn, ang);
                mx = fmax(mx, ang);
            }
        thx_vec3 e1 = thx_v3_sub(p[1], p[0]), e2 = thx_v3_sub(p[2], p[0]), e3 = thx_v3_sub(p[3], p[0]);
        double det = fabs(thx_v3_dot(e1, thx_v3_cross(e2, e3))); /* 6 V */
        double lmin = INFINITY;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) lmin = fmin(lmin, thx_v3_norm(thx_v3_sub(p[j], p[i])));
        /* circumcentre - p0 = (|e1|^2 (e2 x e3) + |e2|^2 (e3 x e1) + |e3|^2 (e1 x e2)) / (2 det) */
        thx_vec3 num = thx_v3_add(thx_v3_scale(thx_v3_cross(e2, e3), thx_v3_dot(e1, e1)),
                                  thx_v3_add(thx_v3_scale(thx_v3_cross(e3, e1), thx_v3_dot(e2, e2)),
                                             thx_v3_scale(thx_v3_cross(e1, e2), thx_v3_dot(e3, e3))));
        double R = det > 0.0 ? thx_v3_norm(num) / (2.0 * det) : INFINITY;
        double rin = area2 > 0.0 ? det / area2 : 0.0; /* 3 V / total area */
        re = lmin > 0.0 ? R / lmin : INFINITY;
        rr = isfinite(R) && R > 0.0 ? 3.0 * rin / R : 0.0;
        if (det == 0.0) { /* exactly non-flat but underflowed: treat as flat */
            mn = 0.0;
            mx = 180.0;
        }
    }
    if (min_dihedral) *min_dihedral = mn;
    if (max_dihedral) *max_dihedral = mx;
    if (radius_edge) *radius_edge = re;
    if (radius_ratio) *radius_ratio = rr;
}

/* ------------------------------------------------------------------ */
/* Ray-parity inside test against one surface (exact orient3d signs). */

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

enum { VOX_UNKNOWN = 0, VOX_INSIDE = 1, VOX_OUTSIDE = 2, VOX_SURFACE = 3 };

typedef struct {
    const inside_surface *is;
    const double *p, *q;
    int crossings;
    int ambiguous;
} parity_state;

static int sgn(double x) { return (x > 0) - (x < 0); }

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
static int classify_point(const inside_surface *is, thx_vec3 pt, int *inside)
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

static void inside_surface_free(inside_surface *is)
{
    thx_bvh_destroy(&is->bvh);
    free(is->degen);
    free(is->vox);
    is->degen = NULL;
    is->vox = NULL;
}

/* Prepares a surface for classify_point; returns THX_EINPUT (without a
 * message kept in ctx) for a surface that cannot be used. */
static thx_status inside_surface_init(thx_ctx *ctx, const thx_surface *s, inside_surface *is)
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

/* ------------------------------------------------------------------ */
/* Sorting helpers. */

typedef struct {
    int32_t b, c;  /* the two larger nodes of the face (the smallest is the bucket) */
    uint32_t tet;
    int8_t lf;     /* local face (opposite vertex lf) */
    int8_t par;    /* +1 if the outward face is an even permutation of (a, b, c), -1 if odd */
} face_rec;

static int cmp_face(const void *x, const void *y)
{
    const face_rec *a = x, *b = y;
    if (a->b != b->b) return a->b < b->b ? -1 : 1;
    if (a->c != b->c) return a->c < b->c ? -1 : 1;
    if (a->tet != b->tet) return a->tet < b->tet ? -1 : 1;
    return (a->lf > b->lf) - (a->lf < b->lf);
}

typedef struct {
    int32_t k[4];
    size_t t;
} tet_key;

static int cmp_tet_key(const void *x, const void *y)
{
    const tet_key *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a->k[i] != b->k[i]) return a->k[i] < b->k[i] ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

typedef struct {
    double x[3];
    int32_t i;
} node_key;

static int cmp_node_key(const void *x, const void *y)
{
    const node_key *a = x, *b = y;
    for (int k = 0; k < 3; k++)
        if (a->x[k] != b->x[k]) return a->x[k] < b->x[k] ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

/* Sorts three ints ascending; returns +1 for an even permutation, -1 for odd. */
static int sort3(int32_t *x)
{
    int par = 1;
    int32_t t;
    if (x[0] > x[1]) { t = x[0]; x[0] = x[1]; x[1] = t; par = -par; }
    if (x[1] > x[2]) { t = x[1]; x[1] = x[2]; x[2] = t; par = -par; }
    if (x[0] > x[1]) { t = x[0]; x[0] = x[1]; x[1] = t; par = -par; }
    return par;
}

/* Inserts (t, val) into a list kept sorted by val (ascending if !desc), ties
 * by smaller t first; at most THX_VCHECK_MAX_WORST entries. */
static void worst_add(thx_volume_worst *l, size_t *n, size_t t, double val, int desc)
{
    size_t k = *n < THX_VCHECK_MAX_WORST ? (*n)++ : THX_VCHECK_MAX_WORST;
#define WORSE(va, ta, vb, tb) ((desc ? (va) > (vb) : (va) < (vb)) || ((va) == (vb) && (ta) < (tb)))
    if (k == THX_VCHECK_MAX_WORST) {
        const thx_volume_worst *last = &l[THX_VCHECK_MAX_WORST - 1];
        if (!WORSE(val, t, last->value, last->tet)) return;
        k = THX_VCHECK_MAX_WORST - 1;
    }
    while (k > 0 && WORSE(val, t, l[k - 1].value, l[k - 1].tet)) {
        l[k] = l[k - 1];
        k--;
    }
#undef WORSE
    l[k].tet = t;
    l[k].value = val;
}

static void append_name(char *buf, size_t size, const char *sep, const char *name)
{
    size_t n = strlen(buf);
    if (n + 1 < size) snprintf(buf + n, size - n, "%s%s", n ? sep : "", name);
}

/* ------------------------------------------------------------------ */
/* Region expectations (mapping by name, documented in the header). */

/* The surfaces region `name` belongs to (the inside of each, less the
 * surfaces nested directly in it): flags in base[]; 0 if the name maps to none. */
static int region_base(const thx_model *m, const char *name, unsigned char *base)
{
    size_t ns = m->n_surfaces;
    memset(base, 0, ns);
    for (size_t s = 0; s < ns; s++) {
        thx_role ro = m->surf[s]->role;
        if ((ro == THX_ROLE_LUNG || ro == THX_ROLE_HEART || ro == THX_ROLE_OTHER) && !strcmp(m->surf[s]->name, name)) {
            base[s] = 1;
            return 1;
        }
    }
    size_t has[THX_ROLE_COUNT] = {0};
    for (size_t s = 0; s < ns; s++)
        if ((int)m->surf[s]->role >= 0 && m->surf[s]->role < THX_ROLE_COUNT) has[m->surf[s]->role]++;
    thx_role want;
    if (!strcmp(name, "heart")) want = THX_ROLE_HEART;
    else if (!strcmp(name, "lung") || !strcmp(name, "lungs")) want = THX_ROLE_LUNG;
    else if (!strcmp(name, "fat")) {
        if (!has[THX_ROLE_FAT]) return 0;
        want = THX_ROLE_OUTER;
    } else if (!strcmp(name, "muscle")) {
        if (!has[THX_ROLE_MUSCLE]) return 0;
        want = has[THX_ROLE_FAT] ? THX_ROLE_FAT : THX_ROLE_OUTER;
    } else if (!strcmp(name, "mean_thorax") || !strcmp(name, "thorax") || !strcmp(name, "torso")) {
        want = has[THX_ROLE_MUSCLE] ? THX_ROLE_MUSCLE : has[THX_ROLE_FAT] ? THX_ROLE_FAT : THX_ROLE_OUTER;
    } else {
        return 0;
    }
    if (!has[want]) return 0;
    for (size_t s = 0; s < ns; s++) base[s] = m->surf[s]->role == want;
    return 1;
}

/* Expected volume of region `name`: over its base surfaces S, V(S) minus the
 * volumes of the surfaces whose parent is S; NaN if the name maps to none.
 * def gets e.g. "muscle - lung_r - lung_l - heart". base: scratch, n_surfaces. */
static double region_expectation(const thx_model *m, const thx_volume_surface_report *sr, const char *name,
                                 unsigned char *base, char *def, size_t size)
{
    def[0] = '\0';
    if (!region_base(m, name, base)) return NAN;
    double v = 0.0;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        if (!base[s]) continue;
        append_name(def, size, " + ", m->surf[s]->name);
        v += sr[s].volume;
        for (size_t c = 0; c < m->n_surfaces; c++)
            if (sr[c].parent == (int)s) {
                v -= sr[c].volume;
                size_t n = strlen(def);
                if (n + 1 < size) snprintf(def + n, size - n, " - %s", m->surf[c]->name);
            }
    }
    return v;
}

/* ------------------------------------------------------------------ */
/* Surface coverage: interface faces mapped onto surface triangles. */

typedef struct {
    const thx_model *m;
    const int32_t *gsurf, *gtri; /* BVH box -> surface, triangle */
    thx_bvh *bvh;
    double tol;
} cover_set;

typedef struct {
    const cover_set *cs;
    const double *p[3];
    double cen[3];
    int n;
    int32_t g[2], s[2];
    double score[2];
} cover_query;

/* Whether the three points p lie on triangle (a, b, c): within tol of its
 * plane and inside it within tol. *score: how deep inside the face's
 * centroid is (the smallest of its distances to the edges, negative if out). */
static int on_triangle(const double *a, const double *b, const double *c, const double *const p[3], const double *cen,
                       double tol, double *score)
{
    thx_vec3 A = thx_v3(a[0], a[1], a[2]), B = thx_v3(b[0], b[1], b[2]), C = thx_v3(c[0], c[1], c[2]);
    thx_vec3 n = thx_v3_cross(thx_v3_sub(B, A), thx_v3_sub(C, A));
    double nn = thx_v3_norm(n);
    if (!(nn > 0.0)) return 0;
    thx_vec3 u = thx_v3_scale(n, 1.0 / nn);
    thx_vec3 P[3];
    for (int k = 0; k < 3; k++) {
        P[k] = thx_v3(p[k][0], p[k][1], p[k][2]);
        if (!(fabs(thx_v3_dot(u, thx_v3_sub(P[k], A))) <= tol)) return 0;
    }
    thx_vec3 V[3] = {A, B, C}, X = thx_v3(cen[0], cen[1], cen[2]);
    double sc = INFINITY;
    for (int e = 0; e < 3; e++) {
        thx_vec3 d = thx_v3_sub(V[(e + 1) % 3], V[e]);
        double len = thx_v3_norm(d);
        if (!(len > 0.0)) return 0;
        thx_vec3 w = thx_v3_scale(thx_v3_cross(u, d), 1.0 / len); /* in the plane, towards the inside */
        for (int k = 0; k < 3; k++)
            if (!(thx_v3_dot(w, thx_v3_sub(P[k], V[e])) >= -tol)) return 0;
        sc = fmin(sc, thx_v3_dot(w, thx_v3_sub(X, V[e])));
    }
    *score = sc;
    return 1;
}

static int cover_visit(void *user, size_t box)
{
    cover_query *q = user;
    const cover_set *cs = q->cs;
    int32_t s = cs->gsurf[box], t = cs->gtri[box];
    const thx_surface *su = cs->m->surf[s];
    const int32_t *c = su->tri + 3 * (size_t)t;
    double sc;
    if (!on_triangle(su->xyz + 3 * (size_t)c[0], su->xyz + 3 * (size_t)c[1], su->xyz + 3 * (size_t)c[2], q->p, q->cen,
                     cs->tol, &sc))
        return 0;
    for (int k = 0; k < q->n; k++)
        if (q->s[k] == s) {
            /* best per surface; equal scores: the lower triangle number (the visiting order is fixed anyway) */
            if (sc > q->score[k] || (sc == q->score[k] && t < cs->gtri[q->g[k]])) {
                q->g[k] = (int32_t)box;
                q->score[k] = sc;
            }
            return 0;
        }
    if (q->n < 2) {
        q->g[q->n] = (int32_t)box;
        q->s[q->n] = s;
        q->score[q->n] = sc;
        q->n++;
    }
    return 0;
}

static double tri_area3(const double *a, const double *b, const double *c, double *perimeter)
{
    thx_vec3 A = thx_v3(a[0], a[1], a[2]), B = thx_v3(b[0], b[1], b[2]), C = thx_v3(c[0], c[1], c[2]);
    if (perimeter)
        *perimeter = thx_v3_norm(thx_v3_sub(B, A)) + thx_v3_norm(thx_v3_sub(C, B)) + thx_v3_norm(thx_v3_sub(A, C));
    return 0.5 * thx_v3_norm(thx_v3_cross(thx_v3_sub(B, A), thx_v3_sub(C, A)));
}

/* Fills the coverage part of r (r->surfaces allocated by the caller). */
static thx_status coverage(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const size_t *iface, size_t n_iface,
                           const thx_volume_check_opts *o, thx_volume_report *r)
{
    thx_status st = THX_OK;
    size_t ns = m->n_surfaces, ng = 0;
    for (size_t s = 0; s < ns; s++) ng += m->surf[s]->n_tris;
    int32_t *gsurf = thx_malloc(ctx, (ng + 1) * sizeof *gsurf), *gtri = thx_malloc(ctx, (ng + 1) * sizeof *gtri);
    double *lo = thx_malloc(ctx, (3 * ng + 1) * sizeof *lo), *hi = thx_malloc(ctx, (3 * ng + 1) * sizeof *hi);
    double *cov = thx_calloc(ctx, ng + 1, sizeof *cov);
    size_t *gfirst = thx_calloc(ctx, ns + 1, sizeof *gfirst); /* surface s's triangle t is global gfirst[s] + t */
    int32_t *match = thx_malloc(ctx, (2 * n_iface + 1) * sizeof *match);
    int32_t *gbox = thx_malloc(ctx, (ng + 1) * sizeof *gbox); /* global triangle -> BVH box, -1 degenerate */
    cover_set cs = {m, gsurf, gtri, NULL, o->node_tol};
    if (!gsurf || !gtri || !lo || !hi || !cov || !gfirst || !match || !gbox) {
        st = THX_ENOMEM;
        goto done;
    }
    /* boxes of the non-degenerate triangles (corners in range), widened by the tolerance */
    size_t nb = 0, g = 0;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *su = m->surf[s];
        gfirst[s] = g;
        for (size_t t = 0; t < su->n_tris; t++, g++) {
            gbox[g] = -1;
            const int32_t *c = su->tri + 3 * t;
            int ok = 1;
            for (int k = 0; k < 3; k++) ok &= c[k] >= 0 && (size_t)c[k] < su->n_nodes;
            if (!ok) continue;
            const double *a = su->xyz + 3 * (size_t)c[0], *b = su->xyz + 3 * (size_t)c[1];
            const double *d = su->xyz + 3 * (size_t)c[2];
            if (!(tri_area3(a, b, d, NULL) > 0.0)) continue;
            for (int k = 0; k < 3; k++) {
                lo[3 * nb + k] = fmin(a[k], fmin(b[k], d[k])) - 2.0 * o->node_tol;
                hi[3 * nb + k] = fmax(a[k], fmax(b[k], d[k])) + 2.0 * o->node_tol;
            }
            gsurf[nb] = (int32_t)s;
            gtri[nb] = (int32_t)t;
            gbox[g] = (int32_t)nb++;
        }
    }
    gfirst[ns] = g;
    st = thx_bvh_create(ctx, lo, hi, nb, &cs.bvh);
    if (st == THX_EINPUT) { /* non-finite coordinates: the surface checks say so */
        thx_ctx_clear(ctx);
        st = THX_OK;
        goto done;
    }
    if (st != THX_OK) goto done;
    long long nf_ll = (long long)n_iface;
THX_OMP(omp parallel for schedule(dynamic, 1024))
    for (long long i = 0; i < nf_ll; i++) {
        size_t t = iface[i] / 4;
        int lf = (int)(iface[i] % 4);
        cover_query q;
        memset(&q, 0, sizeof q);
        q.cs = &cs;
        double flo[3], fhi[3];
        for (int k = 0; k < 3; k++) q.p[k] = v->xyz + 3 * (size_t)v->tet[4 * t + vface[lf][k]];
        for (int a = 0; a < 3; a++) {
            q.cen[a] = (q.p[0][a] + q.p[1][a] + q.p[2][a]) / 3.0;
            flo[a] = fmin(q.p[0][a], fmin(q.p[1][a], q.p[2][a]));
            fhi[a] = fmax(q.p[0][a], fmax(q.p[1][a], q.p[2][a]));
        }
        thx_bvh_query_box(cs.bvh, flo, fhi, cover_visit, &q);
        match[2 * i] = q.n > 0 ? q.g[0] : -1;
        match[2 * i + 1] = q.n > 1 ? q.g[1] : -1;
    }
    /* serial sums in face order (deterministic) */
    for (size_t i = 0; i < n_iface; i++) {
        size_t t = iface[i] / 4;
        int lf = (int)(iface[i] % 4);
        const int32_t *q = v->tet + 4 * t;
        const double *p0 = v->xyz + 3 * (size_t)q[vface[lf][0]], *p1 = v->xyz + 3 * (size_t)q[vface[lf][1]];
        const double *p2 = v->xyz + 3 * (size_t)q[vface[lf][2]];
        double area = tri_area3(p0, p1, p2, NULL);
        if (match[2 * i] < 0) {
            if (!r->n_faces_off_surfaces) {
                int32_t k3[3] = {q[vface[lf][0]], q[vface[lf][1]], q[vface[lf][2]]};
                sort3(k3);
                memcpy(r->ex_off_face, k3, sizeof k3);
                for (int a = 0; a < 3; a++) r->ex_off_centroid[a] = (p0[a] + p1[a] + p2[a]) / 3.0;
            }
            r->n_faces_off_surfaces++;
            continue;
        }
        for (int k = 0; k < 2; k++) {
            int32_t b = match[2 * i + k];
            if (b < 0) continue;
            cov[gfirst[gsurf[b]] + (size_t)gtri[b]] += area;
            r->surfaces[gsurf[b]].covered_area += area;
        }
    }
    r->n_interface_faces = n_iface;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *su = m->surf[s];
        thx_volume_surface_report *sr = &r->surfaces[s];
        sr->n_tris = su->n_tris;
        int have_ex = 0;
        for (size_t t = 0; t < su->n_tris; t++) {
            size_t gi = gfirst[s] + t;
            if (gbox[gi] < 0) { /* degenerate or bad: nothing to cover */
                sr->n_covered++;
                continue;
            }
            const int32_t *c = su->tri + 3 * t;
            const double *a = su->xyz + 3 * (size_t)c[0], *b = su->xyz + 3 * (size_t)c[1];
            const double *d = su->xyz + 3 * (size_t)c[2];
            double per, A = tri_area3(a, b, d, &per);
            sr->area += A;
            /* relative tolerance, plus the 6-decimal rounding of nodes on the edges */
            if (fabs(cov[gi] - A) <= o->coverage_tol * A + 1e-6 * per) {
                sr->n_covered++;
                continue;
            }
            if (!have_ex) { /* the first triangle of this surface not covered */
                have_ex = 1;
                sr->ex_uncovered = t;
                for (int k = 0; k < 3; k++) sr->ex_centroid[k] = (a[k] + b[k] + d[k]) / 3.0;
                sr->ex_covered_share = cov[gi] / A;
            }
            r->n_uncovered_tris++;
        }
        sr->share = sr->n_tris ? (double)sr->n_covered / (double)sr->n_tris : 1.0;
    }
    r->coverage_checked = 1;
done:
    thx_bvh_destroy(&cs.bvh);
    free(gsurf);
    free(gtri);
    free(lo);
    free(hi);
    free(cov);
    free(gfirst);
    free(match);
    free(gbox);
    return st;
}

/* ------------------------------------------------------------------ */

typedef struct {
    double vol;        /* signed volume */
    double mind, maxd; /* dihedral angles, deg */
    double re, rr;     /* radius-edge, radius ratio */
    double lmin, lmax; /* edges */
    int8_t orient;     /* -1 right-handed (good), +1 inverted, 0 flat */
    int8_t repeated;   /* a node twice */
} tet_fig;

/* Counts the faces, marks the boundary faces in bmask (bit lf of tetrahedron
 * t) and, if iface is not NULL, lists the interface faces (boundary faces and
 * faces between two regions) as 4 t + lf, in the order of their sorted node
 * numbers. */
static thx_status faces_and_boundary(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, unsigned char *bmask,
                                     thx_volume_report *r, size_t **iface, size_t *n_iface)
{
    size_t cap_if = 0;
    if (iface) {
        *iface = NULL;
        *n_iface = 0;
    }
    thx_status st = THX_OK;
    size_t nv = v->n_nodes, nt = v->n_tets;
    size_t *start = thx_calloc(ctx, nv + 1, sizeof *start);
    size_t *fill = thx_malloc(ctx, (nv + 1) * sizeof *fill);
    face_rec *fr = thx_malloc(ctx, (4 * nt + 1) * sizeof *fr);
    if (!start || !fill || !fr) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        for (int f = 0; f < 4; f++) {
            int32_t k[3] = {v->tet[4 * t + vface[f][0]], v->tet[4 * t + vface[f][1]], v->tet[4 * t + vface[f][2]]};
            sort3(k);
            start[(size_t)k[0] + 1]++;
        }
    }
    for (size_t i = 0; i < nv; i++) start[i + 1] += start[i];
    memcpy(fill, start, nv * sizeof *fill);
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        for (int f = 0; f < 4; f++) {
            int32_t k[3] = {v->tet[4 * t + vface[f][0]], v->tet[4 * t + vface[f][1]], v->tet[4 * t + vface[f][2]]};
            int par = sort3(k);
            face_rec x = {k[1], k[2], (uint32_t)t, (int8_t)f, (int8_t)par};
            fr[fill[(size_t)k[0]]++] = x;
        }
    }
    for (size_t a = 0; a < nv; a++) {
        size_t b = start[a], e = start[a + 1];
        if (e - b > 1) qsort(fr + b, e - b, sizeof *fr, cmp_face);
        for (size_t g = b; g < e;) {
            size_t h = g;
            while (h < e && fr[h].b == fr[g].b && fr[h].c == fr[g].c) h++;
            size_t cnt = h - g;
            r->n_faces++;
            int inter = 0;
            if (cnt == 1) {
                r->n_boundary_faces++;
                bmask[fr[g].tet] |= (unsigned char)(1u << fr[g].lf);
                inter = 1;
            } else if (cnt == 2) {
                r->n_interior_faces++;
                inter = v->region && v->region[fr[g].tet] != v->region[fr[g + 1].tet];
                if (fr[g].par == fr[g + 1].par) {
                    if (!r->n_overlapping_faces) {
                        r->ex_overlapping_face[0] = (int32_t)a;
                        r->ex_overlapping_face[1] = fr[g].b;
                        r->ex_overlapping_face[2] = fr[g].c;
                    }
                    r->n_overlapping_faces++;
                }
            } else {
                if (!r->n_nonconforming_faces) {
                    r->ex_nonconforming_face[0] = (int32_t)a;
                    r->ex_nonconforming_face[1] = fr[g].b;
                    r->ex_nonconforming_face[2] = fr[g].c;
                }
                r->n_nonconforming_faces++;
            }
            if (inter && iface) {
                if (*n_iface + 1 > cap_if &&
                    (st = thx_grow(ctx, (void **)iface, &cap_if, *n_iface + 1, sizeof **iface)) != THX_OK)
                    goto done;
                (*iface)[(*n_iface)++] = 4 * (size_t)fr[g].tet + (size_t)fr[g].lf;
            }
            g = h;
        }
    }
done:
    free(start);
    free(fill);
    free(fr);
    return st;
}

static thx_status duplicates(thx_ctx *ctx, const thx_volume *v, const tet_fig *fig, thx_volume_report *r)
{
    size_t nt = v->n_tets, nv = v->n_nodes;
    tet_key *keys = thx_malloc(ctx, (nt + 1) * sizeof *keys);
    node_key *nk = thx_malloc(ctx, (nv + 1) * sizeof *nk);
    size_t *start = thx_calloc(ctx, nv + 2, sizeof *start);
    if (!keys || !nk || !start) {
        free(keys);
        free(nk);
        free(start);
        return THX_ENOMEM;
    }
    /* sorted node quadruples, bucketed by the smallest node (counting sort
     * keeps tetrahedron order), then sorted inside each small bucket */
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        const int32_t *q = v->tet + 4 * t;
        int32_t mn = q[0];
        for (int i = 1; i < 4; i++) mn = q[i] < mn ? q[i] : mn;
        start[(size_t)mn + 1]++;
    }
    for (size_t i = 0; i < nv; i++) start[i + 1] += start[i];
    for (size_t t = 0; t < nt; t++) {
        if (fig[t].repeated) continue;
        int32_t k[4];
        memcpy(k, v->tet + 4 * t, sizeof k);
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
                int32_t x = k[j];
                k[j] = k[j - 1];
                k[j - 1] = x;
            }
        tet_key *dst = &keys[start[(size_t)k[0]]++];
        memcpy(dst->k, k, sizeof k);
        dst->t = t;
    }
    /* start[a] now ends bucket a; bucket a begins at start[a - 1] (0 for a = 0) */
    for (size_t a = 0; a < nv; a++) {
        size_t b = a ? start[a - 1] : 0, e = start[a];
        if (e - b > 1) qsort(keys + b, e - b, sizeof *keys, cmp_tet_key);
        for (size_t i = b + 1; i < e; i++)
            if (!memcmp(keys[i].k, keys[i - 1].k, sizeof keys[i].k)) {
                if (!r->n_duplicate_tets || keys[i].t < r->ex_duplicate_tet[1]) {
                    /* the earliest pair by the later tetrahedron's index */
                    size_t g = i - 1;
                    while (g > b && !memcmp(keys[g - 1].k, keys[i].k, sizeof keys[i].k)) g--;
                    r->ex_duplicate_tet[0] = keys[g].t;
                    r->ex_duplicate_tet[1] = keys[i].t;
                }
                r->n_duplicate_tets++;
            }
    }
    free(start);
    for (size_t i = 0; i < nv; i++) {
        memcpy(nk[i].x, v->xyz + 3 * i, 3 * sizeof(double));
        nk[i].i = (int32_t)i;
    }
    qsort(nk, nv, sizeof *nk, cmp_node_key);
    for (size_t i = 1; i < nv; i++)
        if (nk[i].x[0] == nk[i - 1].x[0] && nk[i].x[1] == nk[i - 1].x[1] && nk[i].x[2] == nk[i - 1].x[2]) {
            if (!r->n_duplicate_nodes) {
                size_t g = i - 1;
                while (g > 0 && nk[g - 1].x[0] == nk[i].x[0] && nk[g - 1].x[1] == nk[i].x[1] &&
                       nk[g - 1].x[2] == nk[i].x[2])
                    g--;
                r->ex_duplicate_node[0] = nk[g].i;
                r->ex_duplicate_node[1] = nk[i].i;
            }
            r->n_duplicate_nodes++;
        }
    free(keys);
    free(nk);
    return THX_OK;
}

/* Builds the boundary as a surface (faces in tet order), checks it, counts
 * shells and cavities. */
static thx_status boundary(thx_ctx *ctx, const thx_volume *v, const unsigned char *bmask,
                           const thx_volume_check_opts *o, thx_volume_report *r, int32_t **bnode_out,
                           size_t *n_bnodes)
{
    thx_status st = THX_OK;
    size_t nv = v->n_nodes, nt = v->n_tets, nf = r->n_boundary_faces;
    int32_t *map = thx_malloc(ctx, (nv + 1) * sizeof *map);
    int32_t *back = thx_malloc(ctx, (nv + 1) * sizeof *back);
    size_t *parent = thx_malloc(ctx, (nv + 1) * sizeof *parent);
    thx_surface *s = NULL;
    double *cvol = NULL;
    if (!map || !back || !parent) {
        st = THX_ENOMEM;
        goto done;
    }
    THX_TRY(thx_surface_create(ctx, "boundary", THX_ROLE_OTHER, &s));
    s->tri = thx_malloc(ctx, (3 * nf + 1) * sizeof *s->tri);
    if (!s->tri) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < nv; i++) {
        map[i] = -1;
        parent[i] = i;
    }
    size_t nb = 0, k = 0;
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++) {
            if (!(bmask[t] & (1u << f))) continue;
            for (int j = 0; j < 3; j++) {
                int32_t g = v->tet[4 * t + vface[f][j]];
                if (map[g] < 0) {
                    back[nb] = g;
                    map[g] = (int32_t)nb++;
                }
                s->tri[k++] = map[g];
            }
            uf_union(parent, (size_t)v->tet[4 * t + vface[f][0]], (size_t)v->tet[4 * t + vface[f][1]]);
            uf_union(parent, (size_t)v->tet[4 * t + vface[f][0]], (size_t)v->tet[4 * t + vface[f][2]]);
        }
    s->n_tris = nf;
    s->n_nodes = nb;
    s->xyz = thx_malloc(ctx, (3 * nb + 1) * sizeof *s->xyz);
    if (!s->xyz) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < nb; i++) memcpy(s->xyz + 3 * i, v->xyz + 3 * (size_t)back[i], 3 * sizeof(double));

    thx_check_opts so;
    thx_check_opts_default(&so);
    so.check_intersections = o->check_intersections;
    st = thx_surface_check(ctx, s, NULL, &so, &r->boundary);
    if (st == THX_ECHECK) {
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    if (st != THX_OK) goto done;
    r->boundary_checked = 1;
    /* node numbers back to volume nodes */
    thx_surface_report *b = &r->boundary;
#define BACK(x) ((x) = ((x) >= 0 && (size_t)(x) < nb) ? back[(x)] : (x))
    if (b->n_boundary_edges) { BACK(b->ex_boundary_edge[0]); BACK(b->ex_boundary_edge[1]); }
    if (b->n_nonmanifold_edges) { BACK(b->ex_nonmanifold_edge[0]); BACK(b->ex_nonmanifold_edge[1]); }
    if (b->n_inconsistent_edges) { BACK(b->ex_inconsistent_edge[0]); BACK(b->ex_inconsistent_edge[1]); }
    if (b->n_nonmanifold_vertices) BACK(b->ex_nonmanifold_vertex);
    if (b->n_unused_nodes) BACK(b->ex_unused_node);
#undef BACK

    /* components: node-connected; signed volume about the centre of the node box */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nb; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], s->xyz[3 * i + a]);
            hi[a] = fmax(hi[a], s->xyz[3 * i + a]);
        }
    thx_vec3 c0 = thx_v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    /* component index per root, in order of first appearance */
    for (size_t i = 0; i < nb; i++) map[back[i]] = -1;
    size_t nc = 0;
    for (size_t i = 0; i < nb; i++) {
        size_t root = uf_find(parent, (size_t)back[i]);
        if (map[root] < 0) map[root] = (int32_t)nc++;
    }
    cvol = thx_calloc(ctx, nc + 1, sizeof *cvol);
    if (!cvol) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t f = 0; f < nf; f++) {
        int32_t g0 = back[s->tri[3 * f]];
        size_t cidx = (size_t)map[uf_find(parent, (size_t)g0)];
        thx_vec3 a = thx_v3_sub(node3(s->xyz, s->tri[3 * f]), c0);
        thx_vec3 bb = thx_v3_sub(node3(s->xyz, s->tri[3 * f + 1]), c0);
        thx_vec3 cc = thx_v3_sub(node3(s->xyz, s->tri[3 * f + 2]), c0);
        cvol[cidx] += thx_v3_dot(a, thx_v3_cross(bb, cc)) / 6.0;
    }
    r->n_boundary_components = nc;
    for (size_t c = 0; c < nc; c++) {
        if (cvol[c] > 0.0) r->n_shells++;
        else r->n_cavities++;
    }
    *bnode_out = back;
    *n_bnodes = nb;
    back = NULL;
done:
    free(map);
    free(back);
    free(parent);
    free(cvol);
    thx_surface_destroy(&s);
    return st;
}

/* Node tables (paper 3.3). */
static void node_tables(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r)
{
    int has = v->surf_node || v->node_surf || v->node_snode || v->n_surfaces;
    if (!has && !(m && m->n_surfaces)) return;
    r->node_tables_checked = 1;
    r->n_table_surfaces = v->n_surfaces;
    r->table_max_distance = NAN;
    size_t ns = v->n_surfaces;
    int first_bad = 1;
#define NOTE_BAD(s_, i_)                \
    do {                                \
        if (first_bad) {                \
            r->ex_table_surface = (s_); \
            r->ex_table_node = (i_);    \
            first_bad = 0;              \
        }                               \
    } while (0)
    if (m && m->n_surfaces != ns)
        r->n_table_size_errors += m->n_surfaces > ns ? m->n_surfaces - ns : ns - m->n_surfaces;
    if (!v->node_surf || !v->node_snode) r->n_table_size_errors++;
    if (ns && (!v->surf_node || !v->surf_n_nodes)) {
        r->n_table_size_errors += ns;
        return;
    }
    double maxd = -1.0, tol2 = o->node_tol * o->node_tol;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *ms = (m && s < m->n_surfaces) ? m->surf[s] : NULL;
        if (!v->surf_node[s] || (ms && v->surf_n_nodes[s] != ms->n_nodes)) {
            r->n_table_size_errors++;
            continue;
        }
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            int32_t g = v->surf_node[s][i];
            if (g < 0 || (size_t)g >= v->n_nodes) {
                NOTE_BAD(s, i);
                r->n_table_bad_entries++;
                continue;
            }
            if (ms) {
                double d2 = 0.0;
                for (int a = 0; a < 3; a++) {
                    double dd = v->xyz[3 * (size_t)g + a] - ms->xyz[3 * i + a];
                    d2 += dd * dd;
                }
                if (d2 > maxd) maxd = d2;
                if (!(d2 <= tol2)) {
                    NOTE_BAD(s, i);
                    r->n_table_mismatches++;
                }
            }
            if (v->node_surf && v->node_snode &&
                (v->node_surf[g] < 0 || ((size_t)v->node_surf[g] == s && (size_t)v->node_snode[g] != i))) {
                if (!r->n_table_backlink_errors) r->ex_backlink_node = g;
                r->n_table_backlink_errors++;
            }
        }
    }
    if (maxd >= 0.0) r->table_max_distance = sqrt(maxd);
    if (v->node_surf && v->node_snode)
        for (size_t g = 0; g < v->n_nodes; g++) {
            int32_t s = v->node_surf[g];
            if (s < 0) continue;
            int32_t i = v->node_snode[g];
            int ok = (size_t)s < ns && v->surf_node && v->surf_node[s] && v->surf_n_nodes && i >= 0 &&
                     (size_t)i < v->surf_n_nodes[s] && v->surf_node[s][i] == (int32_t)g;
            if (!ok) {
                if (!r->n_table_backlink_errors) r->ex_backlink_node = (int32_t)g;
                r->n_table_backlink_errors++;
            }
        }
#undef NOTE_BAD
}

/* Steiner records (with a model): in range, not on a surface node, and on
 * the point their barycentric coordinates give. */
static void steiner_table(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r)
{
    r->n_steiner = v->n_steiner;
    r->steiner_max_distance = NAN;
    if (!v->n_steiner || !m) return;
    if (!v->steiner) {
        r->n_steiner_bad = v->n_steiner;
        r->ex_steiner = 0;
        return;
    }
    double maxd = -1.0, tol2 = o->node_tol * o->node_tol;
    int first = 1;
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *sr = &v->steiner[k];
        const thx_surface *su = (sr->surf >= 0 && (size_t)sr->surf < m->n_surfaces) ? m->surf[sr->surf] : NULL;
        int ok = su && sr->node >= 0 && (size_t)sr->node < v->n_nodes && sr->tri >= 0 && (size_t)sr->tri < su->n_tris &&
                 (!v->node_surf || v->node_surf[sr->node] < 0);
        for (int c = 0; c < 3 && ok; c++) {
            int32_t i = su->tri[3 * (size_t)sr->tri + c];
            ok = i >= 0 && (size_t)i < su->n_nodes && isfinite(sr->bary[c]);
        }
        if (!ok) {
            if (first) r->ex_steiner = k;
            first = 0;
            r->n_steiner_bad++;
            continue;
        }
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double x = 0.0;
            for (int c = 0; c < 3; c++) x += sr->bary[c] * su->xyz[3 * (size_t)su->tri[3 * (size_t)sr->tri + c] + a];
            double dd = v->xyz[3 * (size_t)sr->node + a] - x;
            d2 += dd * dd;
        }
        if (d2 > maxd) maxd = d2;
        if (!(d2 <= tol2)) {
            if (first) r->ex_steiner = k;
            first = 0;
            r->n_steiner_mismatches++;
        }
    }
    if (maxd >= 0.0) r->steiner_max_distance = sqrt(maxd);
}

/* The parent of each usable surface: the smallest-volume usable surface of
 * larger volume that holds most of (up to 256 spread) nodes of it; -1 none.
 * order: the surfaces by increasing |volume|. */
static void nesting(const thx_model *m, const inside_surface *isf, const unsigned char *usable, const size_t *order,
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
                classify_point(&isf[b], node3(A->xyz, (int32_t)(j * A->n_nodes / nsample)), &inside);
                in += inside != 0;
            }
            if (2 * in > nsample) {
                sr[a].parent = (int)b;
                break;
            }
        }
    }
}

/* "inside NAME" / "outside every surface" for a cell. */
static void cell_name(const thx_model *m, int cell, char *buf, size_t size)
{
    if (cell >= 0) snprintf(buf, size, "inside %s", m->surf[cell]->name);
    else snprintf(buf, size, "outside every surface");
}

/* ------------------------------------------------------------------ */

thx_status thx_volume_check(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const thx_volume_check_opts *opts_in,
                            thx_volume_report *r)
{
    thx_volume_check_opts o;
    if (opts_in) o = *opts_in;
    else thx_volume_check_opts_default(&o);
    memset(r, 0, sizeof *r);
    r->n_nodes = v->n_nodes;
    r->n_tets = v->n_tets;
    r->n_table_regions = v->n_regions;
    r->volume_tol = o.volume_tol;
    r->region_volume_tol = o.region_volume_tol;
    r->node_tol = o.node_tol;
    r->coverage_tol = o.coverage_tol;
    r->min_dihedral_opt = o.min_dihedral_deg;
    r->max_radius_edge_opt = o.max_radius_edge;
    r->tet_volume = r->enclosed_volume = r->volume_rel_diff = NAN;
    r->min_tet_volume = r->max_tet_volume = NAN;
    r->table_max_distance = r->steiner_max_distance = NAN;
    r->min_dihedral = r->max_dihedral = r->max_radius_edge = r->mean_radius_edge = NAN;
    r->min_radius_ratio = r->mean_radius_ratio = r->min_edge = r->max_edge = NAN;

    thx_status st = THX_OK;
    size_t nt = v->n_tets, nv = v->n_nodes;
    tet_fig *fig = NULL;
    unsigned char *bmask = NULL, *used = NULL, *cls = NULL, *excluded = NULL, *usable = NULL, *base = NULL;
    int32_t *bnodes = NULL, *cell = NULL, *cell_region = NULL, *steiner_surf = NULL;
    size_t n_bnodes = 0, *iface = NULL, n_iface = 0, *order = NULL, *cell_count = NULL;
    inside_surface *isf = NULL;
    size_t n_isf = 0;

    /* regions table first: reported even when the mesh is unusable */
    if (v->n_regions) {
        r->regions = thx_calloc(ctx, v->n_regions, sizeof *r->regions);
        if (!r->regions) return THX_ENOMEM;
        r->n_regions = v->n_regions;
        for (size_t k = 0; k < v->n_regions; k++) {
            snprintf(r->regions[k].name, sizeof r->regions[k].name, "%s", v->regions[k].name);
            r->regions[k].expected = r->regions[k].rel_diff = NAN;
            r->regions[k].ok = 1;
            r->regions[k].cell = -2;
        }
    }
    if (nt == 0) {
        add_reason(r, THX_VCHECKF_EMPTY, "empty: the volume has no tetrahedra");
        goto verdict;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            int32_t g = v->tet[4 * t + k];
            if (g < 0 || (size_t)g >= nv) {
                if (!r->n_bad_index_tets) r->ex_bad_index_tet = t;
                r->n_bad_index_tets++;
                break;
            }
        }
    if (r->n_bad_index_tets) {
        add_reason(r, THX_VCHECKF_BAD_INDEX,
                   "bad index: %zu tetrahedra refer to nodes outside 1..%zu (first: tetrahedron %zu); nothing else "
                   "checked",
                   r->n_bad_index_tets, nv, r->ex_bad_index_tet + 1);
        goto verdict;
    }

    /* phase times for -v (THX_LOG_DEBUG) */
    double tp = thx_wtime(), t_tets = 0, t_faces = 0, t_bound = 0, t_surf = 0, t_cover = 0, t_cells = 0;
    /* per tetrahedron, in parallel: orientation (exact), volume, quality */
    fig = thx_malloc(ctx, nt * sizeof *fig);
    bmask = thx_calloc(ctx, nt, 1);
    used = thx_calloc(ctx, nv + 1, 1);
    if (!fig || !bmask || !used) {
        st = THX_ENOMEM;
        goto done;
    }
    long long nt_ll = (long long)nt;
THX_OMP(omp parallel for schedule(dynamic, 4096))
    for (long long t = 0; t < nt_ll; t++) {
        const int32_t *q = v->tet + 4 * t;
        tet_fig *f = &fig[t];
        f->repeated = q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] || q[2] == q[3];
        const double *p[4];
        for (int k = 0; k < 4; k++) p[k] = v->xyz + 3 * (size_t)q[k];
        double o3 = thx_orient3d(p[0], p[1], p[2], p[3]);
        f->orient = (int8_t)sgn(o3);
        f->vol = thx_volume_tet_volume(v, (size_t)t);
        thx_tet_quality(p[0], p[1], p[2], p[3], &f->mind, &f->maxd, &f->re, &f->rr);
        f->lmin = INFINITY;
        f->lmax = 0.0;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) {
                double l = thx_v3_norm(thx_v3_sub(node3(v->xyz, q[j]), node3(v->xyz, q[i])));
                f->lmin = fmin(f->lmin, l);
                f->lmax = fmax(f->lmax, l);
            }
    }

    /* serial pass: counts, sums and lists in tetrahedron order (deterministic) */
    double vsum = 0.0, re_sum = 0.0, rr_sum = 0.0;
    size_t n_re = 0, n_q = 0;
    r->min_tet_volume = INFINITY;
    r->max_tet_volume = -INFINITY;
    r->min_dihedral = r->min_radius_ratio = r->min_edge = INFINITY;
    r->max_dihedral = r->max_radius_edge = r->max_edge = -INFINITY;
    for (size_t t = 0; t < nt; t++) {
        const tet_fig *f = &fig[t];
        for (int k = 0; k < 4; k++) used[v->tet[4 * t + k]] = 1;
        int32_t reg = v->region ? v->region[t] : -1;
        if (!v->region || reg < 0 || (size_t)reg >= v->n_regions) {
            if (!r->n_bad_region_tets) r->ex_bad_region_tet = t;
            r->n_bad_region_tets++;
        } else {
            r->regions[reg].n_tets++;
            r->regions[reg].volume += f->vol;
        }
        vsum += f->vol;
        r->min_tet_volume = fmin(r->min_tet_volume, f->vol);
        r->max_tet_volume = fmax(r->max_tet_volume, f->vol);
        if (f->repeated) {
            if (!r->n_repeated_node_tets) r->ex_repeated_node_tet = t;
            r->n_repeated_node_tets++;
            continue;
        }
        if (f->orient > 0) {
            if (!r->n_inverted_tets) r->ex_inverted_tet = t;
            r->n_inverted_tets++;
        } else if (f->orient == 0) {
            if (!r->n_flat_tets) r->ex_flat_tet = t;
            r->n_flat_tets++;
        }
        /* quality */
        n_q++;
        if (f->mind < r->min_dihedral) { r->min_dihedral = f->mind; r->min_dihedral_tet = t; }
        if (f->maxd > r->max_dihedral) { r->max_dihedral = f->maxd; r->max_dihedral_tet = t; }
        if (f->re > r->max_radius_edge) { r->max_radius_edge = f->re; r->max_radius_edge_tet = t; }
        if (f->rr < r->min_radius_ratio) { r->min_radius_ratio = f->rr; r->min_radius_ratio_tet = t; }
        if (isfinite(f->re)) {
            re_sum += f->re;
            n_re++;
        }
        rr_sum += f->rr;
        r->min_edge = fmin(r->min_edge, f->lmin);
        r->max_edge = fmax(r->max_edge, f->lmax);
        int bin = 0;
        while (bin < THX_VCHECK_DIHEDRAL_BINS - 1 && !(f->mind < thx_vcheck_dihedral_edges[bin + 1])) bin++;
        r->dihedral_hist[bin]++;
        bin = 0;
        while (bin < THX_VCHECK_RADIUS_EDGE_BINS - 1 && !(f->re < thx_vcheck_radius_edge_edges[bin + 1])) bin++;
        r->radius_edge_hist[bin]++;
        worst_add(r->worst_dihedral, &r->n_worst_dihedral, t, f->mind, 0);
        worst_add(r->worst_radius_edge, &r->n_worst_radius_edge, t, f->re, 1);
    }
    r->tet_volume = vsum;
    r->mean_radius_edge = n_re ? re_sum / (double)n_re : NAN;
    r->mean_radius_ratio = n_q ? rr_sum / (double)n_q : NAN;
    if (!n_q) {
        r->min_dihedral = r->max_dihedral = r->max_radius_edge = r->min_radius_ratio = NAN;
        r->min_edge = r->max_edge = NAN;
    }
    for (size_t g = 0; g < nv; g++)
        if (!used[g]) {
            if (!r->n_unused_nodes) r->ex_unused_node = (int32_t)g;
            r->n_unused_nodes++;
        }

    t_tets = thx_wtime() - tp;
    tp = thx_wtime();
    THX_TRY(duplicates(ctx, v, fig, r));
    THX_TRY(faces_and_boundary(ctx, v, fig, bmask, r, m ? &iface : NULL, &n_iface));
    t_faces = thx_wtime() - tp;

    /* surfaces of the model that bound the mesh: outer ones and excluded hearts */
    size_t n_outer = 0, n_excl = 0;
    if (m) {
        excluded = thx_calloc(ctx, m->n_surfaces + 1, 1);
        if (!excluded) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t s = 0; s < m->n_surfaces; s++) {
            const thx_surface *ms = m->surf[s];
            if (ms->role == THX_ROLE_OUTER) {
                n_outer++;
                append_name(r->outer_names, sizeof r->outer_names, ", ", ms->name);
            } else if (ms->role == THX_ROLE_HEART) {
                int mapped = 0;
                for (size_t k = 0; k < v->n_regions && !mapped; k++)
                    mapped = !strcmp(v->regions[k].name, ms->name) || !strcmp(v->regions[k].name, "heart");
                if (!mapped) {
                    excluded[s] = 1;
                    n_excl++;
                    append_name(r->excluded_names, sizeof r->excluded_names, ", ", ms->name);
                }
            }
        }
    }
    r->n_outer_surfaces = n_outer;
    r->n_excluded_hearts = n_excl;
    r->expected_shells = (m && n_outer) ? n_outer : 1;
    r->expected_cavities = o.expected_cavities >= 0 ? (size_t)o.expected_cavities : n_excl;

    tp = thx_wtime();
    if (r->n_boundary_faces) THX_TRY(boundary(ctx, v, bmask, &o, r, &bnodes, &n_bnodes));
    t_bound = thx_wtime() - tp;
    tp = thx_wtime();
    if (r->n_cavities > r->expected_cavities) r->n_voids = r->n_cavities - r->expected_cavities;

    /* the model's surfaces: coverage, containment, cells, nesting, volumes */
    if (m && m->n_surfaces) {
        size_t ns = m->n_surfaces;
        isf = thx_calloc(ctx, ns, sizeof *isf);
        usable = thx_calloc(ctx, ns, 1);
        base = thx_calloc(ctx, ns, 1);
        order = thx_malloc(ctx, ns * sizeof *order);
        r->surfaces = thx_calloc(ctx, ns, sizeof *r->surfaces);
        cls = thx_calloc(ctx, nt, 1);
        cell = thx_malloc(ctx, nt * sizeof *cell);
        if (!isf || !usable || !base || !order || !r->surfaces || !cls || !cell) {
            st = THX_ENOMEM;
            goto done;
        }
        r->n_surface_reports = ns;
        n_isf = ns;
        int all_usable = 1, bound_usable = 1;
        for (size_t s = 0; s < ns; s++) {
            thx_volume_surface_report *sr = &r->surfaces[s];
            snprintf(sr->name, sizeof sr->name, "%s", m->surf[s]->name);
            sr->n_tris = m->surf[s]->n_tris;
            sr->parent = -1;
            sr->ex_covered_share = NAN;
            sr->volume = NAN; /* unusable surfaces: no volume, no nesting */
            thx_status s2 = inside_surface_init(ctx, m->surf[s], &isf[s]);
            if (s2 == THX_EINPUT) {
                all_usable = 0;
                if (m->surf[s]->role == THX_ROLE_OUTER || excluded[s]) bound_usable = 0;
            } else if (s2 != THX_OK) {
                st = s2;
                goto done;
            } else {
                usable[s] = 1;
                sr->volume = thx_surface_volume(m->surf[s]);
            }
        }
        for (size_t k = 0; k < v->n_steiner && v->steiner; k++)
            if (v->steiner[k].surf >= 0 && (size_t)v->steiner[k].surf < ns) r->surfaces[v->steiner[k].surf].n_steiner++;
        /* increasing |volume|, ties by index: the first surface holding a point is its innermost */
        for (size_t s = 0; s < ns; s++) {
            size_t j = s;
            while (j > 0 && fabs(r->surfaces[order[j - 1]].volume) > fabs(r->surfaces[s].volume)) {
                order[j] = order[j - 1];
                j--;
            }
            order[j] = s;
        }
        nesting(m, isf, usable, order, r->surfaces);
        t_surf = thx_wtime() - tp;
        tp = thx_wtime();
        THX_TRY(coverage(ctx, v, m, iface, n_iface, &o, r));
        t_cover = thx_wtime() - tp;
        tp = thx_wtime();

        int do_cont = bound_usable && (n_outer || n_excl);
        if (do_cont || all_usable) {
            /* cls bits: 1 outside every outer surface, 2 inside an excluded heart, 4 fallback used */
THX_OMP(omp parallel for schedule(dynamic, 1024))
            for (long long t = 0; t < nt_ll; t++) {
                const int32_t *q = v->tet + 4 * t;
                thx_vec3 c = thx_v3(0, 0, 0);
                for (int k = 0; k < 4; k++) c = thx_v3_add(c, node3(v->xyz, q[k]));
                c = thx_v3_scale(c, 0.25);
                unsigned char bits = 0;
                int in_outer = 0;
                int32_t ce = -1;
                for (size_t k = 0; k < ns; k++) {
                    size_t s = order[k];
                    if (!usable[s]) continue;
                    int is_outer = m->surf[s]->role == THX_ROLE_OUTER, is_excl = excluded[s];
                    /* past the innermost surface only the outer and excluded ones matter */
                    int need = (all_usable && ce < 0) || (is_outer && !in_outer) || is_excl;
                    if (!need) continue;
                    int inside = 0;
                    if (classify_point(&isf[s], c, &inside) == 2) bits |= 4;
                    if (inside && ce < 0) ce = (int32_t)s;
                    if (is_outer) in_outer |= inside;
                    else if (is_excl && inside) bits |= 2;
                }
                if (n_outer && !in_outer) bits |= 1;
                cls[t] = bits;
                cell[t] = ce;
            }
        }
        t_cells = thx_wtime() - tp;
        if (do_cont) {
            r->containment_checked = 1;
            for (size_t t = 0; t < nt; t++) {
                if (cls[t] & 1) {
                    if (!r->n_outside_tets) r->ex_outside_tet = t;
                    r->n_outside_tets++;
                }
                if (cls[t] & 2) {
                    if (!r->n_in_cavity_tets) r->ex_in_cavity_tet = t;
                    r->n_in_cavity_tets++;
                }
            }
        }
        if (do_cont || all_usable)
            for (size_t t = 0; t < nt; t++) r->n_undecided_tets += (cls[t] & 4) != 0;
        /* each cell holds one region: the one most of its tetrahedra have */
        size_t nreg = v->n_regions, nc = ns + 1;
        if (all_usable && v->region && nreg) {
            r->cells_checked = 1;
            cell_count = thx_calloc(ctx, nc * nreg, sizeof *cell_count);
            cell_region = thx_malloc(ctx, nc * sizeof *cell_region);
            if (!cell_count || !cell_region) {
                st = THX_ENOMEM;
                goto done;
            }
            for (size_t t = 0; t < nt; t++) {
                int32_t g = v->region[t];
                if (g >= 0 && (size_t)g < nreg) cell_count[(size_t)(cell[t] + 1) * nreg + (size_t)g]++;
            }
            for (size_t c = 0; c < nc; c++) {
                size_t best = 0;
                cell_region[c] = -1;
                for (size_t g = 0; g < nreg; g++)
                    if (cell_count[c * nreg + g] > best) {
                        best = cell_count[c * nreg + g];
                        cell_region[c] = (int32_t)g;
                    }
            }
            for (size_t g = 0; g < nreg; g++) {
                size_t best = 0;
                for (size_t c = 0; c < nc; c++)
                    if (cell_count[c * nreg + g] > best) {
                        best = cell_count[c * nreg + g];
                        r->regions[g].cell = (int)c - 1;
                    }
            }
            for (size_t t = 0; t < nt; t++) {
                int32_t g = v->region[t];
                if (g < 0 || (size_t)g >= nreg || cell_region[cell[t] + 1] == g) continue;
                thx_volume_region_report *rg = &r->regions[g];
                if (!rg->n_outside) {
                    rg->ex_outside = t;
                    rg->ex_outside_cell = cell[t];
                }
                rg->n_outside++;
                if (!r->n_outside_region_tets) r->ex_outside_region_tet = t;
                r->n_outside_region_tets++;
            }
        }
    }
    if (m && n_outer) {
        double ve = 0.0;
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (m->surf[s]->role == THX_ROLE_OUTER) {
                ve += thx_surface_volume(m->surf[s]);
                append_name(r->volume_definition, sizeof r->volume_definition, " + ", m->surf[s]->name);
            }
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (excluded[s]) {
                ve -= thx_surface_volume(m->surf[s]);
                append_name(r->volume_definition, sizeof r->volume_definition, " - ", m->surf[s]->name);
            }
        r->enclosed_volume = ve;
        r->volume_rel_diff = (r->tet_volume - ve) / ve;
    }
    if (m && r->surfaces)
        for (size_t k = 0; k < r->n_regions; k++) {
            thx_volume_region_report *rg = &r->regions[k];
            rg->expected = region_expectation(m, r->surfaces, rg->name, base, rg->definition, sizeof rg->definition);
            if (rg->expected == rg->expected) rg->rel_diff = (rg->volume - rg->expected) / rg->expected;
            if (o.region_volume_tol > 0.0 && rg->expected == rg->expected && !(fabs(rg->rel_diff) <= o.region_volume_tol))
                rg->ok = 0;
        }

    thx_log(ctx, THX_LOG_DEBUG,
            "volume check: tetrahedra %.3f s, faces %.3f s, boundary %.3f s, surfaces %.3f s, coverage %.3f s "
            "(%zu interface faces), cells %.3f s",
            t_tets, t_faces, t_bound, t_surf, t_cover, n_iface, t_cells);
    node_tables(v, m, &o, r);
    steiner_table(v, m, &o, r);
    if (m && r->node_tables_checked && v->node_surf && bnodes) {
        steiner_surf = thx_malloc(ctx, (nv + 1) * sizeof *steiner_surf);
        if (!steiner_surf) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t g = 0; g < nv; g++) steiner_surf[g] = -1;
        for (size_t k = 0; k < v->n_steiner && v->steiner; k++) {
            const thx_steiner *sr = &v->steiner[k];
            if (sr->node >= 0 && (size_t)sr->node < nv && sr->surf >= 0 && (size_t)sr->surf < m->n_surfaces)
                steiner_surf[sr->node] = sr->surf;
        }
        for (size_t i = 0; i < n_bnodes; i++) {
            int32_t s = v->node_surf[bnodes[i]], s2 = steiner_surf[bnodes[i]];
            int on = (s >= 0 && (size_t)s < m->n_surfaces && (m->surf[s]->role == THX_ROLE_OUTER || excluded[s])) ||
                     (s2 >= 0 && (m->surf[s2]->role == THX_ROLE_OUTER || excluded[s2]));
            r->n_boundary_nodes_off_surfaces += !on;
        }
    }

    /* reasons, in a fixed order (numbers 1-based, as in volume.tet) */
    if (r->n_bad_region_tets) {
        if (!v->region)
            add_reason(r, THX_VCHECKF_BAD_REGION, "bad region: the volume has no region per tetrahedron");
        else
            add_reason(r, THX_VCHECKF_BAD_REGION,
                       "bad region: %zu tetrahedra have a region outside 1..%zu (first: tetrahedron %zu)",
                       r->n_bad_region_tets, v->n_regions, r->ex_bad_region_tet + 1);
    }
    if (r->n_repeated_node_tets)
        add_reason(r, THX_VCHECKF_REPEATED_NODE, "repeated node: %zu tetrahedra use a node twice (first: tetrahedron %zu)",
                   r->n_repeated_node_tets, r->ex_repeated_node_tet + 1);
    if (r->n_inverted_tets)
        add_reason(r, THX_VCHECKF_INVERTED,
                   "inverted: %zu tetrahedra have negative volume (left-handed; first: tetrahedron %zu, %.6g mm^3)",
                   r->n_inverted_tets, r->ex_inverted_tet + 1, fig[r->ex_inverted_tet].vol);
    if (r->n_flat_tets)
        add_reason(r, THX_VCHECKF_FLAT, "flat: %zu tetrahedra have zero volume (first: tetrahedron %zu)", r->n_flat_tets,
                   r->ex_flat_tet + 1);
    if (r->n_unused_nodes)
        add_reason(r, THX_VCHECKF_UNUSED, "unused nodes: %zu nodes in no tetrahedron (first: node %ld)",
                   r->n_unused_nodes, (long)r->ex_unused_node + 1);
    if (r->n_duplicate_nodes)
        add_reason(r, THX_VCHECKF_DUPLICATE_NODE,
                   "duplicate nodes: %zu nodes coincide with another (first: nodes %ld and %ld)", r->n_duplicate_nodes,
                   (long)r->ex_duplicate_node[0] + 1, (long)r->ex_duplicate_node[1] + 1);
    if (r->n_duplicate_tets)
        add_reason(r, THX_VCHECKF_DUPLICATE_TET,
                   "duplicate tetrahedra: %zu repeat the nodes of another (first: tetrahedra %zu and %zu)",
                   r->n_duplicate_tets, r->ex_duplicate_tet[0] + 1, r->ex_duplicate_tet[1] + 1);
    if (r->n_nonconforming_faces)
        add_reason(r, THX_VCHECKF_NONCONFORMING,
                   "nonconforming: %zu faces in three or more tetrahedra (first: nodes %ld %ld %ld)",
                   r->n_nonconforming_faces, (long)r->ex_nonconforming_face[0] + 1,
                   (long)r->ex_nonconforming_face[1] + 1, (long)r->ex_nonconforming_face[2] + 1);
    if (r->n_overlapping_faces)
        add_reason(r, THX_VCHECKF_NONCONFORMING,
                   "nonconforming: %zu faces have both tetrahedra on the same side (overlap; first: nodes %ld %ld %ld)",
                   r->n_overlapping_faces, (long)r->ex_overlapping_face[0] + 1, (long)r->ex_overlapping_face[1] + 1,
                   (long)r->ex_overlapping_face[2] + 1);
    if (r->boundary_checked && !r->boundary.ok)
        add_reason(r, THX_VCHECKF_BOUNDARY, "boundary surface (%zu faces): %s%s", r->n_boundary_faces,
                   r->boundary.reasons[0], r->boundary.n_reasons > 1 ? " (and more)" : "");
    else if (!r->n_boundary_faces)
        add_reason(r, THX_VCHECKF_BOUNDARY, "boundary: no face lies in exactly one tetrahedron");
    if (r->n_boundary_faces && (r->n_shells != r->expected_shells || r->n_cavities != r->expected_cavities)) {
        char voids[96] = "";
        if (r->n_voids)
            snprintf(voids, sizeof voids, "; %zu void%s: tetrahedra missing inside the mesh", r->n_voids,
                     r->n_voids == 1 ? "" : "s");
        add_reason(r, THX_VCHECKF_COMPONENTS,
                   "components: the boundary has %zu shell%s and %zu cavit%s, expected %zu and %zu%s", r->n_shells,
                   r->n_shells == 1 ? "" : "s", r->n_cavities, r->n_cavities == 1 ? "y" : "ies", r->expected_shells,
                   r->expected_cavities, voids);
    }
    if (r->n_outside_tets)
        add_reason(r, THX_VCHECKF_CONTAINMENT,
                   "containment: %zu tetrahedra have their centroid outside %s (first: tetrahedron %zu)",
                   r->n_outside_tets, r->outer_names, r->ex_outside_tet + 1);
    if (r->n_in_cavity_tets)
        add_reason(r, THX_VCHECKF_CONTAINMENT,
                   "containment: %zu tetrahedra have their centroid inside the excluded %s (first: tetrahedron %zu)",
                   r->n_in_cavity_tets, r->excluded_names, r->ex_in_cavity_tet + 1);
    if (r->coverage_checked) {
        for (size_t s = 0; s < r->n_surface_reports; s++) {
            const thx_volume_surface_report *sr = &r->surfaces[s];
            if (sr->n_covered == sr->n_tris) continue;
            add_reason(r, THX_VCHECKF_COVERAGE,
                       "coverage: surface \"%s\": %zu of %zu triangles not covered by mesh faces (first: triangle %zu, "
                       "centroid (%.6g, %.6g, %.6g), %.4g%% of its area covered)",
                       sr->name, sr->n_tris - sr->n_covered, sr->n_tris, sr->ex_uncovered + 1, sr->ex_centroid[0],
                       sr->ex_centroid[1], sr->ex_centroid[2], 100.0 * sr->ex_covered_share);
        }
        if (r->n_faces_off_surfaces)
            add_reason(r, THX_VCHECKF_COVERAGE,
                       "coverage: %zu faces between regions or on the boundary lie on no surface triangle (region "
                       "boundary off the surfaces; first: nodes %ld %ld %ld, centroid (%.6g, %.6g, %.6g))",
                       r->n_faces_off_surfaces, (long)r->ex_off_face[0] + 1, (long)r->ex_off_face[1] + 1,
                       (long)r->ex_off_face[2] + 1, r->ex_off_centroid[0], r->ex_off_centroid[1], r->ex_off_centroid[2]);
    }
    if (r->n_outside_region_tets)
        for (size_t k = 0; k < r->n_regions; k++) {
            const thx_volume_region_report *rg = &r->regions[k];
            if (!rg->n_outside) continue;
            char where[96];
            cell_name(m, rg->ex_outside_cell, where, sizeof where);
            int32_t holder = cell_region[rg->ex_outside_cell + 1];
            add_reason(r, THX_VCHECKF_REGION_CELLS,
                       "tetrahedra outside their region: region \"%s\": %zu of %zu tetrahedra lie %s, which holds "
                       "region \"%s\" (first: tetrahedron %zu)",
                       rg->name, rg->n_outside, rg->n_tets, where, holder >= 0 ? r->regions[holder].name : "?",
                       rg->ex_outside + 1);
        }
    if (o.volume_tol > 0.0 && r->volume_rel_diff == r->volume_rel_diff && !(fabs(r->volume_rel_diff) <= o.volume_tol))
        add_reason(r, THX_VCHECKF_VOLUME,
                   "volume: tetrahedra %.6g mm^3, enclosed by the surfaces (%s) %.6g mm^3: relative difference %+.3g%% "
                   "(tolerance %.3g%%)",
                   r->tet_volume, r->volume_definition, r->enclosed_volume, 100.0 * r->volume_rel_diff,
                   100.0 * o.volume_tol);
    for (size_t k = 0; k < r->n_regions; k++)
        if (!r->regions[k].ok)
            add_reason(r, THX_VCHECKF_REGION_VOLUME,
                       "region \"%s\": tetrahedra %.6g mm^3, surfaces (%s) %.6g mm^3: relative difference %+.3g%% "
                       "(tolerance %.3g%%)",
                       r->regions[k].name, r->regions[k].volume, r->regions[k].definition, r->regions[k].expected,
                       100.0 * r->regions[k].rel_diff, 100.0 * o.region_volume_tol);
    if (r->node_tables_checked) {
        if (r->n_table_size_errors)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu missing or of the wrong size (volume tables for %zu surfaces, model has %zu)",
                       r->n_table_size_errors, v->n_surfaces, m ? m->n_surfaces : v->n_surfaces);
        if (r->n_table_bad_entries || r->n_table_mismatches)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu surface nodes map to no volume node, %zu to a volume node elsewhere (> %.3g mm; "
                       "first: surface %zu node %zu)",
                       r->n_table_bad_entries, r->n_table_mismatches, o.node_tol, r->ex_table_surface + 1,
                       r->ex_table_node + 1);
        if (r->n_table_backlink_errors)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu volume/surface entries do not point back to each other (first: volume node %ld)",
                       r->n_table_backlink_errors, (long)r->ex_backlink_node + 1);
    }
    if (r->n_steiner_bad || r->n_steiner_mismatches) {
        const thx_steiner *sr = v->steiner ? &v->steiner[r->ex_steiner] : NULL;
        add_reason(r, THX_VCHECKF_NODE_TABLE,
                   "Steiner nodes: %zu records out of range or on a surface node, %zu nodes farther than %.3g mm from "
                   "the point of their barycentric coordinates (first: record %zu, volume node %ld)",
                   r->n_steiner_bad, r->n_steiner_mismatches, o.node_tol, r->ex_steiner + 1,
                   sr ? (long)sr->node + 1 : 0L);
    }
    if (o.min_dihedral_deg > 0.0 && !(r->min_dihedral >= o.min_dihedral_deg))
        add_reason(r, THX_VCHECKF_QUALITY, "quality: smallest dihedral angle %.3g deg < %.3g deg (tetrahedron %zu)",
                   r->min_dihedral, o.min_dihedral_deg, r->min_dihedral_tet + 1);
    if (o.max_radius_edge > 0.0 && !(r->max_radius_edge <= o.max_radius_edge))
        add_reason(r, THX_VCHECKF_QUALITY, "quality: radius-edge ratio %.4g > %.4g (tetrahedron %zu)",
                   r->max_radius_edge, o.max_radius_edge, r->max_radius_edge_tet + 1);

verdict:
    r->ok = r->failures == 0;
    if (!r->ok) st = thx_error(ctx, THX_ECHECK, "volume: %s", r->reasons[0]);
done:
    if (st != THX_OK && st != THX_ECHECK) {
        /* an allocation failed: the report is incomplete */
        r->ok = 0;
    }
    for (size_t k = 0; k < n_isf; k++) inside_surface_free(&isf[k]);
    free(isf);
    free(usable);
    free(base);
    free(order);
    free(cell);
    free(cell_region);
    free(cell_count);
    free(steiner_surf);
    free(iface);
    free(fig);
    free(bmask);
    free(used);
    free(cls);
    free(excluded);
    free(bnodes);
    return st;
}

void thx_volume_report_free(thx_volume_report *r)
{
    if (!r) return;
    free(r->regions);
    free(r->surfaces);
    memset(r, 0, sizeof *r);
}

/* ------------------------------------------------------------------ */
/* JSON. Non-finite numbers become null. */

static cJSON *num(double x) { return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull(); }

static void add_num(cJSON *o, const char *k, double x) { cJSON_AddItemToObject(o, k, num(x)); }

static void add_count(cJSON *o, const char *k, size_t n) { cJSON_AddNumberToObject(o, k, (double)n); }

static void add_nodes1(cJSON *o, const char *k, const int32_t *x, int n)
{
    cJSON *arr = cJSON_CreateArray();
    for (int i = 0; i < n; i++) cJSON_AddItemToArray(arr, cJSON_CreateNumber((double)x[i] + 1));
    cJSON_AddItemToObject(o, k, arr);
}

static void add_names(cJSON *o, const char *k, const char *list)
{
    cJSON *arr = cJSON_AddArrayToObject(o, k);
    char buf[160];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ", ", &save); tok; tok = strtok_r(NULL, ", ", &save))
        cJSON_AddItemToArray(arr, cJSON_CreateString(tok));
}

static void add_hist(cJSON *o, const double *edges, const size_t *counts, int nb)
{
    cJSON *h = cJSON_AddObjectToObject(o, "histogram");
    cJSON *he = cJSON_AddArrayToObject(h, "edges");
    for (int b = 0; b <= nb; b++) cJSON_AddItemToArray(he, num(edges[b]));
    cJSON *hc = cJSON_AddArrayToObject(h, "counts");
    for (int b = 0; b < nb; b++) cJSON_AddItemToArray(hc, cJSON_CreateNumber((double)counts[b]));
}

static void add_worst(cJSON *o, const thx_volume_worst *l, size_t n)
{
    cJSON *arr = cJSON_AddArrayToObject(o, "worst");
    for (size_t k = 0; k < n; k++) {
        cJSON *pr = cJSON_CreateArray();
        cJSON_AddItemToArray(pr, cJSON_CreateNumber((double)l[k].tet + 1));
        cJSON_AddItemToArray(pr, num(l[k].value));
        cJSON_AddItemToArray(arr, pr);
    }
}

cJSON *thx_volume_report_json(thx_ctx *ctx, const thx_volume_report *r)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) goto nomem;
    int indexed = !(r->failures & (THX_VCHECKF_EMPTY | THX_VCHECKF_BAD_INDEX));
    cJSON_AddBoolToObject(o, "ok", r->ok);
    cJSON_AddNumberToObject(o, "index_base", 1);
    cJSON *fl = cJSON_AddArrayToObject(o, "failures");
    for (unsigned b = 0; b < THX_VCHECK_N_FAILURES; b++)
        if (r->failures & (1u << b))
            cJSON_AddItemToArray(fl, cJSON_CreateString(thx_volume_check_failure_name((thx_volume_check_failure)(1u << b))));
    cJSON *rs = cJSON_AddArrayToObject(o, "reasons");
    for (size_t i = 0; i < r->n_reasons; i++) cJSON_AddItemToArray(rs, cJSON_CreateString(r->reasons[i]));
    add_count(o, "nodes", r->n_nodes);
    add_count(o, "tetrahedra", r->n_tets);
    add_count(o, "region_table_size", r->n_table_regions);
    cJSON_AddBoolToObject(o, "conforming", indexed && !r->n_nonconforming_faces && !r->n_overlapping_faces &&
                                               !r->n_duplicate_tets);
    cJSON_AddBoolToObject(o, "boundary_closed", indexed && r->boundary_checked && !r->boundary.n_boundary_edges &&
                                                    !r->boundary.n_nonmanifold_edges);
    cJSON_AddBoolToObject(o, "positive", indexed && !r->n_inverted_tets && !r->n_flat_tets && !r->n_repeated_node_tets);

    cJSON *va = cJSON_AddObjectToObject(o, "validity");
    add_count(va, "bad_index_tetrahedra", r->n_bad_index_tets);
    add_count(va, "bad_region_tetrahedra", r->n_bad_region_tets);
    add_count(va, "repeated_node_tetrahedra", r->n_repeated_node_tets);
    add_count(va, "inverted_tetrahedra", r->n_inverted_tets);
    add_count(va, "flat_tetrahedra", r->n_flat_tets);
    add_count(va, "unused_nodes", r->n_unused_nodes);
    add_count(va, "duplicate_nodes", r->n_duplicate_nodes);
    add_count(va, "duplicate_tetrahedra", r->n_duplicate_tets);
    cJSON *vf = cJSON_AddObjectToObject(va, "first");
    if (r->n_bad_index_tets) add_count(vf, "bad_index_tetrahedron", r->ex_bad_index_tet + 1);
    if (r->n_bad_region_tets) add_count(vf, "bad_region_tetrahedron", r->ex_bad_region_tet + 1);
    if (r->n_repeated_node_tets) add_count(vf, "repeated_node_tetrahedron", r->ex_repeated_node_tet + 1);
    if (r->n_inverted_tets) add_count(vf, "inverted_tetrahedron", r->ex_inverted_tet + 1);
    if (r->n_flat_tets) add_count(vf, "flat_tetrahedron", r->ex_flat_tet + 1);
    if (r->n_unused_nodes) add_count(vf, "unused_node", (size_t)r->ex_unused_node + 1);
    if (r->n_duplicate_nodes) add_nodes1(vf, "duplicate_nodes", r->ex_duplicate_node, 2);
    if (r->n_duplicate_tets) {
        int32_t d[2] = {(int32_t)r->ex_duplicate_tet[0], (int32_t)r->ex_duplicate_tet[1]};
        add_nodes1(vf, "duplicate_tetrahedra", d, 2);
    }

    cJSON *co = cJSON_AddObjectToObject(o, "conformity");
    add_count(co, "faces", r->n_faces);
    add_count(co, "interior_faces", r->n_interior_faces);
    add_count(co, "boundary_faces", r->n_boundary_faces);
    add_count(co, "faces_in_3_or_more", r->n_nonconforming_faces);
    add_count(co, "overlapping_faces", r->n_overlapping_faces);
    add_count(co, "boundary_components", r->n_boundary_components);
    add_count(co, "shells", r->n_shells);
    add_count(co, "cavities", r->n_cavities);
    add_count(co, "expected_shells", r->expected_shells);
    add_count(co, "expected_cavities", r->expected_cavities);
    add_count(co, "voids", r->n_voids);
    add_count(co, "boundary_nodes_off_surfaces", r->n_boundary_nodes_off_surfaces);
    cJSON *cf = cJSON_AddObjectToObject(co, "first");
    if (r->n_nonconforming_faces) add_nodes1(cf, "face_in_3_or_more", r->ex_nonconforming_face, 3);
    if (r->n_overlapping_faces) add_nodes1(cf, "overlapping_face", r->ex_overlapping_face, 3);
    if (r->boundary_checked) {
        cJSON *bj = thx_surface_report_json(ctx, &r->boundary, NULL);
        if (!bj) {
            cJSON_Delete(o);
            return NULL;
        }
        cJSON_AddItemToObject(co, "boundary", bj);
    } else {
        cJSON_AddNullToObject(co, "boundary");
    }

    cJSON *ct = cJSON_AddObjectToObject(o, "containment");
    cJSON_AddBoolToObject(ct, "checked", r->containment_checked);
    add_names(ct, "outer_surfaces", r->outer_names);
    add_names(ct, "excluded_surfaces", r->excluded_names);
    add_count(ct, "outside", r->n_outside_tets);
    add_count(ct, "in_excluded", r->n_in_cavity_tets);
    add_count(ct, "undecided", r->n_undecided_tets);
    cJSON *tf = cJSON_AddObjectToObject(ct, "first");
    if (r->n_outside_tets) add_count(tf, "outside_tetrahedron", r->ex_outside_tet + 1);
    if (r->n_in_cavity_tets) add_count(tf, "in_excluded_tetrahedron", r->ex_in_cavity_tet + 1);

    cJSON *cv = cJSON_AddObjectToObject(o, "coverage");
    cJSON_AddBoolToObject(cv, "checked", r->coverage_checked);
    add_count(cv, "interface_faces", r->n_interface_faces);
    add_count(cv, "uncovered_triangles", r->n_uncovered_tris);
    add_count(cv, "faces_off_surfaces", r->n_faces_off_surfaces);
    add_num(cv, "tolerance", r->coverage_tol);
    cJSON *csf = cJSON_AddArrayToObject(cv, "surfaces");
    for (size_t s = 0; s < r->n_surface_reports && csf; s++) {
        const thx_volume_surface_report *sr = &r->surfaces[s];
        cJSON *so = cJSON_CreateObject();
        cJSON_AddStringToObject(so, "name", sr->name);
        add_count(so, "triangles", sr->n_tris);
        add_count(so, "covered", sr->n_covered);
        add_num(so, "share", sr->share);
        add_num(so, "area", sr->area);
        add_num(so, "covered_area", sr->covered_area);
        add_count(so, "steiner_nodes", sr->n_steiner);
        if (sr->parent >= 0 && (size_t)sr->parent < r->n_surface_reports)
            cJSON_AddStringToObject(so, "inside", r->surfaces[sr->parent].name);
        else
            cJSON_AddNullToObject(so, "inside");
        if (sr->n_covered < sr->n_tris) {
            cJSON *fu = cJSON_AddObjectToObject(so, "first_uncovered");
            add_count(fu, "triangle", sr->ex_uncovered + 1);
            cJSON *ce = cJSON_AddArrayToObject(fu, "centroid");
            for (int k = 0; k < 3; k++) cJSON_AddItemToArray(ce, num(sr->ex_centroid[k]));
            add_num(fu, "covered_share", sr->ex_covered_share);
        }
        cJSON_AddItemToArray(csf, so);
    }
    if (r->n_faces_off_surfaces) {
        cJSON *fo = cJSON_AddObjectToObject(cv, "first_off_surface");
        add_nodes1(fo, "nodes", r->ex_off_face, 3);
        cJSON *ce = cJSON_AddArrayToObject(fo, "centroid");
        for (int k = 0; k < 3; k++) cJSON_AddItemToArray(ce, num(r->ex_off_centroid[k]));
    }

    cJSON *rcl = cJSON_AddObjectToObject(o, "region_cells");
    cJSON_AddBoolToObject(rcl, "checked", r->cells_checked);
    add_count(rcl, "outside_region", r->n_outside_region_tets);
    if (r->n_outside_region_tets) add_count(rcl, "first_tetrahedron", r->ex_outside_region_tet + 1);

    cJSON *vo = cJSON_AddObjectToObject(o, "volume");
    add_num(vo, "tetrahedra", r->tet_volume);
    add_num(vo, "enclosed", r->enclosed_volume);
    cJSON_AddStringToObject(vo, "definition", r->volume_definition);
    add_num(vo, "rel_diff", r->volume_rel_diff);
    add_num(vo, "tolerance", r->volume_tol);
    add_num(vo, "min_tet", r->min_tet_volume);
    add_num(vo, "max_tet", r->max_tet_volume);
    cJSON_AddBoolToObject(vo, "ok", !(r->failures & THX_VCHECKF_VOLUME));

    cJSON *rg = cJSON_AddArrayToObject(o, "regions");
    for (size_t k = 0; k < r->n_regions; k++) {
        const thx_volume_region_report *g = &r->regions[k];
        cJSON *go = cJSON_CreateObject();
        cJSON_AddStringToObject(go, "name", g->name);
        add_count(go, "tetrahedra", g->n_tets);
        add_num(go, "volume", g->volume);
        add_num(go, "expected", g->expected);
        cJSON_AddStringToObject(go, "definition", g->definition);
        add_num(go, "rel_diff", g->rel_diff);
        cJSON_AddBoolToObject(go, "ok", g->ok);
        if (g->cell >= -1) {
            char cn[96];
            if (g->cell >= 0 && (size_t)g->cell < r->n_surface_reports)
                snprintf(cn, sizeof cn, "inside %s", r->surfaces[g->cell].name);
            else
                snprintf(cn, sizeof cn, "outside every surface");
            cJSON_AddStringToObject(go, "cell", cn);
        } else {
            cJSON_AddNullToObject(go, "cell");
        }
        add_count(go, "outside_region", g->n_outside);
        if (g->n_outside) add_count(go, "first_outside_tetrahedron", g->ex_outside + 1);
        cJSON_AddItemToArray(rg, go);
    }
    add_num(o, "region_tolerance", r->region_volume_tol);

    cJSON *nt = cJSON_AddObjectToObject(o, "node_tables");
    cJSON_AddBoolToObject(nt, "checked", r->node_tables_checked);
    add_count(nt, "surfaces", r->n_table_surfaces);
    add_count(nt, "size_errors", r->n_table_size_errors);
    add_count(nt, "bad_entries", r->n_table_bad_entries);
    add_count(nt, "coordinate_mismatches", r->n_table_mismatches);
    add_count(nt, "backlink_errors", r->n_table_backlink_errors);
    add_num(nt, "max_distance", r->table_max_distance);
    add_num(nt, "tolerance", r->node_tol);
    cJSON *nf = cJSON_AddObjectToObject(nt, "first");
    if (r->n_table_bad_entries || r->n_table_mismatches) {
        add_count(nf, "surface", r->ex_table_surface + 1);
        add_count(nf, "surface_node", r->ex_table_node + 1);
    }
    if (r->n_table_backlink_errors) add_count(nf, "backlink_volume_node", (size_t)r->ex_backlink_node + 1);
    add_count(nt, "steiner_nodes", r->n_steiner);
    add_count(nt, "steiner_bad", r->n_steiner_bad);
    add_count(nt, "steiner_mismatches", r->n_steiner_mismatches);
    add_num(nt, "steiner_max_distance", r->steiner_max_distance);
    if (r->n_steiner_bad || r->n_steiner_mismatches) add_count(nf, "steiner_record", r->ex_steiner + 1);

    cJSON *q = cJSON_AddObjectToObject(o, "quality");
    add_num(q, "min_dihedral_deg", r->min_dihedral);
    if (isfinite(r->min_dihedral)) add_count(q, "min_dihedral_tetrahedron", r->min_dihedral_tet + 1);
    add_num(q, "max_dihedral_deg", r->max_dihedral);
    if (isfinite(r->max_dihedral)) add_count(q, "max_dihedral_tetrahedron", r->max_dihedral_tet + 1);
    add_num(q, "min_edge", r->min_edge);
    add_num(q, "max_edge", r->max_edge);
    cJSON *dj = cJSON_AddObjectToObject(q, "dihedral");
    cJSON_AddStringToObject(dj, "definition",
                            "smallest dihedral angle of each tetrahedron, degrees; regular 70.53; flat 0");
    add_hist(dj, thx_vcheck_dihedral_edges, r->dihedral_hist, THX_VCHECK_DIHEDRAL_BINS);
    add_worst(dj, r->worst_dihedral, r->n_worst_dihedral);
    cJSON *rj = cJSON_AddObjectToObject(q, "radius_edge");
    cJSON_AddStringToObject(rj, "definition",
                            "circumradius / shortest edge; regular sqrt(6)/4 = 0.612; null = infinite (flat)");
    add_num(rj, "max", r->max_radius_edge);
    if (r->max_radius_edge == r->max_radius_edge) add_count(rj, "max_tetrahedron", r->max_radius_edge_tet + 1);
    add_num(rj, "mean", r->mean_radius_edge);
    add_hist(rj, thx_vcheck_radius_edge_edges, r->radius_edge_hist, THX_VCHECK_RADIUS_EDGE_BINS);
    add_worst(rj, r->worst_radius_edge, r->n_worst_radius_edge);
    cJSON *rr = cJSON_AddObjectToObject(q, "radius_ratio");
    cJSON_AddStringToObject(rr, "definition", "3 inradius / circumradius; regular 1; flat 0");
    add_num(rr, "min", r->min_radius_ratio);
    if (r->min_radius_ratio == r->min_radius_ratio) add_count(rr, "min_tetrahedron", r->min_radius_ratio_tet + 1);
    add_num(rr, "mean", r->mean_radius_ratio);
    add_num(q, "min_dihedral_limit", r->min_dihedral_opt);
    add_num(q, "max_radius_edge_limit", r->max_radius_edge_opt);

    if (!fl || !rs || !va || !vf || !co || !cf || !ct || !tf || !cv || !csf || !rcl || !vo || !rg || !nt || !nf || !q ||
        !dj || !rj || !rr) {
        cJSON_Delete(o);
        goto nomem;
    }
    return o;
nomem:
    thx_error(ctx, THX_ENOMEM, "out of memory building the volume check report");
    return NULL;
}
