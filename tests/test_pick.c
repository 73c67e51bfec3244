/*
 * Tests of picking (thorax/geom/pick.h, src/geom/pick.c):
 *  - an axis-aligned box: hit point, distance, face and nearest node known exactly; from outside,
 *    from inside, behind, beside, t_max; a direction of any length;
 *  - watertightness: rays exactly through the box's vertices, edges and face diagonals (integer
 *    directions: the projections are exact, the edge functions exactly zero, the perturbation
 *    decides), each line meeting the closed box exactly twice when it passes through the inside
 *    and 0 or 2 times when it only touches it; rays aimed at an icosphere's vertices and edge
 *    points from random origins (near-zero edge functions, the exact predicate decides): exactly
 *    twice; on the phantom, lines through vertices and edge midpoints meet every closed surface an
 *    even number of times, rays from a surface's interior point an odd number;
 *  - the icosphere: rays along a vertex's radius hit that vertex (t = 2 from 3 v); rays from the
 *    centre hit the facet whose plane is nearest along the ray;
 *  - clip planes (hits in the clipped part skipped, the ray going on behind; a plane parallel to
 *    the ray), hidden surfaces, nested surfaces (the outer first from outside, whatever the order);
 *  - the phantom (medium, built in memory): random rays from outside and inside, with and without
 *    clip planes and hidden surfaces: the index answers bit for bit as the brute force over every
 *    triangle, and as an independent Moeller-Trumbore test written here (same surface, t within
 *    1e-9 mm, same triangle unless the hit is within 1e-7 of an edge);
 *  - node picks (points): tolerance in mm and per mm of depth, the nearest to the ray chosen, clip
 *    and hidden surfaces honoured;
 *  - bad input: zero or non-finite direction, non-finite clip plane, negative tolerance, a triangle
 *    naming a node out of range (the message names the surface and the triangle).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/pick.h"
#include "thorax/geom/surfaces.h"
#include "thorax/phantom/phantom.h"

static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

static uint64_t rng_state = 12345;
static double urand(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* Orients every triangle of a surface star-shaped about c so that its normal points away from c. */
static void orient_out(thx_surface *s, const double c[3])
{
    for (size_t t = 0; t < s->n_tris; t++) {
        int32_t *v = s->tri + 3 * t;
        const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1], *cc = s->xyz + 3 * v[2];
        double e1[3], e2[3], n[3], g[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = b[k] - a[k];
            e2[k] = cc[k] - a[k];
            g[k] = (a[k] + b[k] + cc[k]) / 3 - c[k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        if (n[0] * g[0] + n[1] * g[1] + n[2] * g[2] < 0) {
            int32_t x = v[1];
            v[1] = v[2];
            v[2] = x;
        }
    }
}

/* The box [-h, h]^3: node i = corner (x, y, z) with bit 0 = x, bit 1 = y, bit 2 = z; each face split
 * along the diagonal through its lowest-numbered corner. */
static thx_surface *box(double h)
{
    thx_surface *s = NULL;
    CHECK_OK(ctx, thx_surface_create(ctx, "box", THX_ROLE_OTHER, &s));
    s->n_nodes = 8;
    s->n_tris = 12;
    s->xyz = malloc(24 * sizeof(double));
    s->tri = malloc(36 * sizeof(int32_t));
    for (int i = 0; i < 8; i++) {
        s->xyz[3 * i] = (i & 1) ? h : -h;
        s->xyz[3 * i + 1] = (i & 2) ? h : -h;
        s->xyz[3 * i + 2] = (i & 4) ? h : -h;
    }
    /* faces as 4 corners in cyclic order */
    static const int face[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    for (int f = 0; f < 6; f++) {
        int32_t *t = s->tri + 6 * f;
        t[0] = face[f][0], t[1] = face[f][1], t[2] = face[f][2];
        t[3] = face[f][0], t[4] = face[f][2], t[5] = face[f][3];
    }
    orient_out(s, (double[3]){0, 0, 0});
    return s;
}

/* An icosphere of the given radius: the icosahedron, each triangle split in 4 `level` times,
 * the new nodes pushed onto the sphere. */
static thx_surface *icosphere(int level, double radius)
{
    const double p = (1 + sqrt(5.0)) / 2;
    double v0[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                        {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
    int f0[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    size_t nv = 12, nt = 20, cap_v = 12, cap_t = 20;
    for (int l = 0; l < level; l++) cap_v += (cap_t * 3) / 2, cap_t *= 4;
    double *xyz = malloc(3 * cap_v * sizeof(double));
    int32_t *tri = malloc(3 * cap_t * sizeof(int32_t));
    for (int i = 0; i < 12; i++) {
        double n = sqrt(v0[i][0] * v0[i][0] + v0[i][1] * v0[i][1] + v0[i][2] * v0[i][2]);
        for (int k = 0; k < 3; k++) xyz[3 * i + k] = v0[i][k] / n;
    }
    for (int t = 0; t < 20; t++)
        for (int k = 0; k < 3; k++) tri[3 * t + k] = f0[t][k];
    for (int l = 0; l < level; l++) {
        /* edge midpoints through a table (a, b) -> node, a < b */
        size_t ne = 0, cap_e = 3 * nt;
        int32_t(*edge)[3] = malloc(cap_e * sizeof *edge);
        int32_t *nt_tri = malloc(12 * nt * sizeof(int32_t));
        for (size_t t = 0; t < nt; t++) {
            int32_t m[3];
            for (int k = 0; k < 3; k++) {
                int32_t a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3], lo = a < b ? a : b, hi = a < b ? b : a;
                size_t e = 0;
                while (e < ne && !(edge[e][0] == lo && edge[e][1] == hi)) e++;
                if (e == ne) {
                    edge[ne][0] = lo, edge[ne][1] = hi, edge[ne][2] = (int32_t)nv;
                    double q[3], n = 0;
                    for (int c = 0; c < 3; c++) q[c] = xyz[3 * a + c] + xyz[3 * b + c], n += q[c] * q[c];
                    for (int c = 0; c < 3; c++) xyz[3 * nv + c] = q[c] / sqrt(n);
                    nv++, ne++;
                }
                m[k] = edge[e][2];
            }
            int32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
            int32_t q[12] = {a, m[0], m[2], m[0], b, m[1], m[2], m[1], c, m[0], m[1], m[2]};
            memcpy(nt_tri + 12 * t, q, sizeof q);
        }
        memcpy(tri, nt_tri, 12 * nt * sizeof(int32_t));
        nt *= 4;
        free(edge);
        free(nt_tri);
    }
    for (size_t i = 0; i < 3 * nv; i++) xyz[i] *= radius;
    thx_surface *s = NULL;
    CHECK_OK(ctx, thx_surface_create(ctx, "sphere", THX_ROLE_OTHER, &s));
    s->n_nodes = nv;
    s->n_tris = nt;
    s->xyz = xyz;
    s->tri = tri;
    orient_out(s, (double[3]){0, 0, 0});
    return s;
}

/* Number of triangles of s the ray's whole line meets (t of any sign), and of those at t > 0. */
static int line_hits(const thx_surface *s, const double o[3], const double d[3], int *ahead)
{
    thx_ray r;
    if (thx_pick_ray_prepare(&r, o, d)) return -1;
    int n = 0, na = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        double tt;
        if (thx_pick_triangle(&r, s->xyz + 3 * v[0], s->xyz + 3 * v[1], s->xyz + 3 * v[2], &tt, NULL)) {
            n++;
            if (tt > 0) na++;
        }
    }
    if (ahead) *ahead = na;
    return n;
}

/* The textbook Moeller-Trumbore test (1997), written independently of the library: 1 and t, u, v
 * (weights of b and c) if the ray meets the triangle at t >= 0. Two-sided. */
static int mt(const double o[3], const double d[3], const double *a, const double *b, const double *c, double *t,
              double *u, double *v)
{
    double e1[3], e2[3], p[3], s[3], q[3];
    for (int k = 0; k < 3; k++) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], s[k] = o[k] - a[k];
    p[0] = d[1] * e2[2] - d[2] * e2[1], p[1] = d[2] * e2[0] - d[0] * e2[2], p[2] = d[0] * e2[1] - d[1] * e2[0];
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (fabs(det) < 1e-300) return 0;
    double inv = 1 / det;
    *u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
    if (*u < 0 || *u > 1) return 0;
    q[0] = s[1] * e1[2] - s[2] * e1[1], q[1] = s[2] * e1[0] - s[0] * e1[2], q[2] = s[0] * e1[1] - s[1] * e1[0];
    *v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if (*v < 0 || *u + *v > 1) return 0;
    *t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    return *t >= 0;
}

/* The reference pick: nearest MT hit over all surfaces not skipped, inside the clip planes. */
static int mt_pick(const thx_surface *const *surf, size_t n, const double o[3], const double d0[3],
                   const thx_pick_plane *clip, size_t n_clip, const unsigned char *skip, int *si, size_t *ti,
                   double *tbest, double *wmin)
{
    double len = sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]), d[3] = {d0[0] / len, d0[1] / len, d0[2] / len};
    *si = -1;
    *tbest = INFINITY;
    for (size_t s = 0; s < n; s++) {
        if (skip && skip[s]) continue;
        for (size_t t = 0; t < surf[s]->n_tris; t++) {
            const int32_t *v = surf[s]->tri + 3 * t;
            const double *a = surf[s]->xyz + 3 * v[0], *b = surf[s]->xyz + 3 * v[1], *c = surf[s]->xyz + 3 * v[2];
            double tt, u, w;
            if (!mt(o, d, a, b, c, &tt, &u, &w) || tt >= *tbest) continue;
            int kept = 1;
            for (size_t k = 0; k < n_clip; k++) {
                double g = clip[k].d;
                for (int j = 0; j < 3; j++) g += clip[k].n[j] * (o[j] + tt * d[j]);
                if (g < 0) kept = 0;
            }
            if (!kept) continue;
            *tbest = tt, *si = (int)s, *ti = t;
            *wmin = fmin(1 - u - w, fmin(u, w));
        }
    }
    return *si >= 0;
}

/* A ray pick that must succeed. */
static thx_pick_hit pick(const thx_pick_index *x, double ox, double oy, double oz, double dx, double dy, double dz,
                         const thx_pick_opts *o)
{
    thx_pick_hit h;
    CHECK_OK(ctx, thx_pick_ray(ctx, x, (double[3]){ox, oy, oz}, (double[3]){dx, dy, dz}, o, &h));
    return h;
}

/* The hit's own invariants: weights in [0, 1] summing to 1, the point their combination and on the
 * ray at distance t, the node one of the triangle's and the nearest of them. */
static void check_hit(const thx_surface *const *surf, const thx_pick_hit *h, const double o[3], const double d0[3])
{
    if (h->surface < 0) return;
    const thx_surface *s = surf[h->surface];
    const int32_t *v = s->tri + 3 * h->tri;
    double len = sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]), sum = 0, scale = 1;
    for (int k = 0; k < 3; k++) {
        CHECK(h->bary[k] >= 0 && h->bary[k] <= 1);
        sum += h->bary[k];
        scale = fmax(scale, fabs(o[k]) + h->t);
    }
    CHECK_NEAR(sum, 1, 1e-12);
    for (int k = 0; k < 3; k++) {
        double p = 0;
        for (int j = 0; j < 3; j++) p += h->bary[j] * s->xyz[3 * v[j] + k];
        CHECK_NEAR(h->point[k], p, 1e-12 * scale);
        CHECK_NEAR(h->point[k], o[k] + h->t * d0[k] / len, 1e-9 * scale);
    }
    int is_node = 0;
    double dn = 0;
    for (int j = 0; j < 3; j++) {
        double dd = 0;
        for (int k = 0; k < 3; k++) dd += pow(s->xyz[3 * v[j] + k] - h->point[k], 2);
        if ((size_t)v[j] == h->node) is_node = 1, dn = dd;
    }
    CHECK(is_node);
    for (int j = 0; j < 3; j++) {
        double dd = 0;
        for (int k = 0; k < 3; k++) dd += pow(s->xyz[3 * v[j] + k] - h->point[k], 2);
        CHECK(dn <= dd);
    }
}

/* ------------------------------------------------------------- the box */

static void test_box(void)
{
    thx_surface *b = box(1);
    const thx_surface *surf[1] = {b};
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 1, &x));
    if (!x) return;

    /* from outside, through the face x = -1 */
    thx_pick_hit h = pick(x, -5, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 0);
    CHECK_NEAR(h.t, 4, 1e-14);
    CHECK_NEAR(h.point[0], -1, 1e-14);
    CHECK_NEAR(h.point[1], 0.2, 1e-14);
    CHECK_NEAR(h.point[2], 0.3, 1e-14);
    CHECK(h.front == 1);
    CHECK(h.node == 7 - 1); /* the nearest corner (-1, 1, 1): node 6, in either triangle of the face */
    check_hit(surf, &h, (double[3]){-5, 0.2, 0.3}, (double[3]){1, 0, 0});
    /* the same with a longer direction: t is a distance */
    thx_pick_hit h2 = pick(x, -5, 0.2, 0.3, 7.5, 0, 0, NULL);
    CHECK(h2.surface == 0 && h2.tri == h.tri && h2.t == h.t);
    /* oblique, through the top face z = 1 at (0.25, -0.5, 1) */
    h = pick(x, 0.25 - 3, -0.5 + 4, 1 + 12, 3, -4, -12, NULL);
    CHECK(h.surface == 0);
    CHECK_NEAR(h.t, 13, 1e-12);
    CHECK_NEAR(h.point[0], 0.25, 1e-13);
    CHECK_NEAR(h.point[1], -0.5, 1e-13);
    CHECK_NEAR(h.point[2], 1, 1e-13);
    CHECK(h.front == 1);
    check_hit(surf, &h, (double[3]){-2.75, 3.5, 13}, (double[3]){3, -4, -12});
    /* from inside: the far face, its inside */
    h = pick(x, 0, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 0 && h.front == 0);
    CHECK_NEAR(h.t, 1, 1e-14);
    CHECK_NEAR(h.point[0], 1, 1e-14);
    /* behind the origin, beside the box: nothing */
    h = pick(x, 5, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == -1 && h.tri == (size_t)-1);
    h = pick(x, -5, 1.5, 0, 1, 0, 0, NULL);
    CHECK(h.surface == -1);
    /* t_max */
    thx_pick_opts o;
    thx_pick_opts_default(&o);
    o.t_max = 3.999;
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == -1);
    o.t_max = 4;
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == 0);
    /* from a point on the surface: t = 0 */
    h = pick(x, -1, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 0 && h.t == 0);
    /* agreement with the brute force */
    thx_pick_hit hb;
    CHECK_OK(ctx, thx_pick_ray_brute(ctx, surf, 1, (double[3]){-5, 0.2, 0.3}, (double[3]){1, 0, 0}, NULL, &hb));
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(hb.surface == h.surface && hb.tri == h.tri && hb.t == h.t && hb.node == h.node);
    thx_pick_index_destroy(&x);
    CHECK(x == NULL);
    thx_pick_index_destroy(&x);
    thx_surface_destroy(&b);
}

/* Does the line o + t d pass through the open box (-1, 1)^3? (exact for the small rationals used) */
static int line_through_open_box(const double o[3], const double d[3])
{
    double t0 = -INFINITY, t1 = INFINITY;
    for (int k = 0; k < 3; k++) {
        if (d[k] == 0) {
            if (!(o[k] > -1 && o[k] < 1)) return 0;
            continue;
        }
        double a = (-1 - o[k]) / d[k], b = (1 - o[k]) / d[k];
        if (a > b) {
            double t = a;
            a = b;
            b = t;
        }
        t0 = fmax(t0, a);
        t1 = fmin(t1, b);
    }
    return t0 < t1;
}

static void test_box_watertight(void)
{
    thx_surface *b = box(1);
    /* points on the boundary: the 8 corners, points k/4 along the 12 edges, points on the face
     * diagonals (the shared edges of the face's two triangles) and face centres */
    double pts[400][3];
    int np = 0;
    for (int i = 0; i < 8; i++) memcpy(pts[np++], b->xyz + 3 * i, sizeof pts[0]);
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++) {
            int diff = i ^ j;
            int is_edge = diff == 1 || diff == 2 || diff == 4;
            int same_face = (diff & (diff - 1)) && !(diff == 7); /* two bits differ: a face diagonal */
            if (!is_edge && !same_face) continue;
            for (int k = 1; k < 4; k++, np++)
                for (int c = 0; c < 3; c++)
                    pts[np][c] = b->xyz[3 * i + c] + (b->xyz[3 * j + c] - b->xyz[3 * i + c]) * k / 4;
        }
    int lines = 0, bad = 0, through = 0;
    for (int p = 0; p < np; p++)
        for (int dx = -2; dx <= 2; dx++)
            for (int dy = -2; dy <= 2; dy++)
                for (int dz = -2; dz <= 2; dz++) {
                    if (!dx && !dy && !dz) continue;
                    double d[3] = {dx, dy, dz}, o[3];
                    for (int k = 0; k < 3; k++) o[k] = pts[p][k] - 8 * d[k];
                    int n = line_hits(b, o, d, NULL);
                    int in = line_through_open_box(o, d);
                    lines++;
                    through += in;
                    if (in ? n != 2 : (n != 0 && n != 2)) {
                        if (bad++ < 5)
                            fprintf(stderr, "box: line through (%g, %g, %g) along (%d, %d, %d): %d hits (%s)\n",
                                    pts[p][0], pts[p][1], pts[p][2], dx, dy, dz, n, in ? "through" : "touching");
                    }
                }
    CHECK(bad == 0);
    CHECK(through > 1000);
    printf("box: %d lines through vertices, edges and face diagonals (%d through the inside): %d wrong counts\n",
           lines, through, bad);
    /* the corner ray (1, 1, 1): the pick itself */
    const thx_surface *surf[1] = {b};
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 1, &x));
    thx_pick_hit h = pick(x, -5, -5, -5, 1, 1, 1, NULL);
    CHECK(h.surface == 0);
    CHECK_NEAR(h.t, 4 * sqrt(3.0), 1e-13);
    CHECK(h.node == 0);
    CHECK_NEAR(h.bary[0] + h.bary[1] + h.bary[2], 1, 1e-15);
    thx_pick_index_destroy(&x);
    thx_surface_destroy(&b);
}

/* ------------------------------------------------------------- the icosphere */

static void test_icosphere(void)
{
    thx_surface *s = icosphere(3, 1);
    const thx_surface *surf[1] = {s};
    CHECK(s->n_nodes == 642 && s->n_tris == 1280);
    CHECK_NEAR(thx_surface_solid_angle(s, thx_v3(0.1, 0.2, 0.05)), 4 * M_PI, 1e-9);
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 1, &x));
    if (!x) return;
    /* along a vertex's radius from 3 v: the vertex, at t = 2 */
    int bad_vertex = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        const double *v = s->xyz + 3 * i;
        thx_pick_hit h = pick(x, 3 * v[0], 3 * v[1], 3 * v[2], -v[0], -v[1], -v[2], NULL);
        if (h.surface != 0 || h.node != i || fabs(h.t - 2) > 1e-12 || !h.front) bad_vertex++;
        check_hit(surf, &h, (double[3]){3 * v[0], 3 * v[1], 3 * v[2]}, (double[3]){-v[0], -v[1], -v[2]});
    }
    CHECK(bad_vertex == 0);
    /* from the centre: the exit through the facet along the ray, t = (n . a) / (n . d) for its plane, and
     * no facet plane nearer along the ray (convex) */
    int bad_centre = 0;
    for (int k = 0; k < 500; k++) {
        double d[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
        thx_pick_hit h = pick(x, 0, 0, 0, d[0], d[1], d[2], NULL);
        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), tmin = INFINITY;
        for (size_t t = 0; t < s->n_tris; t++) {
            const int32_t *v = s->tri + 3 * t;
            const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
            double e1[3], e2[3], n[3];
            for (int j = 0; j < 3; j++) e1[j] = b[j] - a[j], e2[j] = c[j] - a[j];
            n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double nd = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / len;
            if (nd > 0) tmin = fmin(tmin, (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / nd);
        }
        if (h.surface != 0 || h.front || fabs(h.t - tmin) > 1e-12) bad_centre++;
        check_hit(surf, &h, (double[3]){0, 0, 0}, d);
    }
    CHECK(bad_centre == 0);
    /* watertight: lines through vertices and through points on edges (the midpoint and 1/3 along),
     * from random origins, through a random point inside: exactly two hits on the line */
    int bad = 0, lines = 0;
    for (int k = 0; k < 3000; k++) {
        double P[3];
        size_t t = (size_t)(urand() * s->n_tris);
        const int32_t *v = s->tri + 3 * t;
        int kind = k % 3;
        for (int j = 0; j < 3; j++) {
            const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1];
            P[j] = kind == 0 ? a[j] : kind == 1 ? 0.5 * (a[j] + b[j]) : a[j] + (b[j] - a[j]) / 3;
        }
        double Q[3] = {0.6 * (urand() - 0.5), 0.6 * (urand() - 0.5), 0.6 * (urand() - 0.5)}, o[3], d[3];
        double sc = 1 + 3 * urand();
        for (int j = 0; j < 3; j++) o[j] = P[j] + sc * (P[j] - Q[j]), d[j] = P[j] - o[j];
        int ahead = 0, n = line_hits(s, o, d, &ahead);
        lines++;
        if (n != 2 || ahead != 2) {
            if (bad++ < 5) fprintf(stderr, "icosphere: line %d (kind %d): %d hits, %d ahead\n", k, kind, n, ahead);
        }
    }
    CHECK(bad == 0);
    printf("icosphere: %d lines through vertices and edge points: %d wrong counts\n", lines, bad);
    thx_pick_index_destroy(&x);
    thx_surface_destroy(&s);
}

/* ------------------------------------------------------------- clip planes, nesting, hiding */

static void test_clip_nested(void)
{
    thx_surface *inner = box(1), *outer = box(2);
    const thx_surface *surf[2] = {inner, outer}; /* the inner one first: order must not matter */
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 2, &x));
    if (!x) return;
    /* from outside: the outer box first */
    thx_pick_hit h = pick(x, -5, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 1 && h.front);
    CHECK_NEAR(h.t, 3, 1e-14);
    /* the outer hidden: the inner one */
    unsigned char skip[2] = {0, 1};
    thx_pick_opts o;
    thx_pick_opts_default(&o);
    o.skip = skip;
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 0);
    CHECK_NEAR(h.t, 4, 1e-14);
    skip[0] = 1;
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == -1);
    /* from between the boxes: the inner one; from inside the inner: its far face, then the outer */
    h = pick(x, -1.5, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 0);
    CHECK_NEAR(h.t, 0.5, 1e-14);
    h = pick(x, 0, 0.2, 0.3, 1, 0, 0, NULL);
    CHECK(h.surface == 0 && !h.front);
    CHECK_NEAR(h.t, 1, 1e-14);

    /* clip planes */
    thx_pick_plane pl[2];
    thx_pick_opts_default(&o);
    o.clip = pl;
    o.n_clip = 1;
    pl[0] = (thx_pick_plane){{-1, 0, 0}, 0}; /* keeps x <= 0: the front faces stay */
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 1);
    CHECK_NEAR(h.t, 3, 1e-14);
    pl[0] = (thx_pick_plane){{1, 0, 0}, 0}; /* keeps x >= 0: on through both front faces to the inner's back */
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 0 && !h.front);
    CHECK_NEAR(h.t, 6, 1e-14);
    CHECK_NEAR(h.point[0], 1, 1e-14);
    pl[0] = (thx_pick_plane){{1, 0, 0}, -1.5}; /* keeps x >= 1.5: the outer's back face */
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 1 && !h.front);
    CHECK_NEAR(h.t, 7, 1e-14);
    pl[0] = (thx_pick_plane){{1, 0, 0}, -2.5}; /* keeps x >= 2.5: nothing there */
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == -1);
    pl[0] = (thx_pick_plane){{1, 0, 0}, 1}; /* keeps x >= -1 exactly: the inner's front face (on the plane) */
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 0 && h.front);
    CHECK_NEAR(h.t, 4, 1e-14);
    /* a plane parallel to the ray: all or nothing */
    pl[0] = (thx_pick_plane){{0, 1, 0}, -0.5}; /* keeps y >= 0.5 */
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == -1);
    h = pick(x, -5, 0.7, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 1);
    CHECK_NEAR(h.t, 3, 1e-14);
    /* two planes: a slab 0.5 <= x <= 1.5 leaves the inner's back face */
    pl[0] = (thx_pick_plane){{1, 0, 0}, -0.5};
    pl[1] = (thx_pick_plane){{-1, 0, 0}, 1.5};
    o.n_clip = 2;
    h = pick(x, -5, 0.2, 0.3, 1, 0, 0, &o);
    CHECK(h.surface == 0 && !h.front);
    CHECK_NEAR(h.t, 6, 1e-14);
    /* clipped and hidden together: the slab with the inner hidden leaves nothing */
    skip[0] = 1, skip[1] = 0;
    o.skip = skip;
    CHECK(pick(x, -5, 0.2, 0.3, 1, 0, 0, &o).surface == -1);
    thx_pick_index_destroy(&x);
    thx_surface_destroy(&inner);
    thx_surface_destroy(&outer);
}

/* ------------------------------------------------------------- node picks */

static void test_nodes(void)
{
    thx_surface *inner = box(1), *outer = box(2);
    const thx_surface *surf[2] = {inner, outer};
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 2, &x));
    if (!x) return;
    thx_pick_hit h;
    /* a ray along z passing 0.05 from the corner (-1, -1, *) of the inner box: nodes 0 and 4 both at
     * 0.05; the nearer in depth (node 4, z = +1, from above) wins */
    double o[3] = {-1.03, -1.04, 10}, d[3] = {0, 0, -1};
    CHECK_OK(ctx, thx_pick_node(ctx, x, o, d, 0.1, 0, NULL, &h));
    CHECK(h.surface == 0 && h.node == 4 && h.tri == (size_t)-1);
    CHECK_NEAR(h.dist, 0.05, 1e-12);
    CHECK_NEAR(h.t, 9, 1e-12);
    CHECK(h.point[0] == -1 && h.point[1] == -1 && h.point[2] == 1);
    /* tolerance too small: nothing */
    CHECK_OK(ctx, thx_pick_node(ctx, x, o, d, 0.04, 0, NULL, &h));
    CHECK(h.surface == -1);
    /* a tolerance growing with depth (perspective): node 0, 0.05 off the ray at depth 11, is nearer
     * on the screen than node 4, 0.05 off at depth 9 */
    CHECK_OK(ctx, thx_pick_node(ctx, x, o, d, 0, 1, NULL, &h));
    CHECK(h.surface == 0 && h.node == 0);
    CHECK_NEAR(h.t, 11, 1e-12);
    CHECK_OK(ctx, thx_pick_node(ctx, x, o, d, 0, 0.05 / 11 * 1.001, NULL, &h));
    CHECK(h.surface == 0 && h.node == 0);
    CHECK_OK(ctx, thx_pick_node(ctx, x, o, d, 0, 0.05 / 11 * 0.999, NULL, &h));
    CHECK(h.surface == -1);
    /* the nearest to the ray wins over the nearest in depth: a ray 0.02 from the inner's corner
     * (-1, -1, 1) and 1.4 from the outer's (-2, -2, 2), nearer in depth */
    double o2[3] = {-1.02, -1, 10};
    CHECK_OK(ctx, thx_pick_node(ctx, x, o2, d, 1.5, 0, NULL, &h));
    CHECK(h.surface == 0 && h.node == 4);
    CHECK_NEAR(h.dist, 0.02, 1e-12);
    /* the inner hidden: none of the outer's nodes is within 0.5; within 1.5, its corner (-2, -2, 2) */
    unsigned char skip[2] = {1, 0};
    thx_pick_opts op;
    thx_pick_opts_default(&op);
    op.skip = skip;
    CHECK_OK(ctx, thx_pick_node(ctx, x, o2, d, 0.5, 0, &op, &h));
    CHECK(h.surface == -1);
    CHECK_OK(ctx, thx_pick_node(ctx, x, o2, d, 1.5, 0, &op, &h));
    CHECK(h.surface == 1 && h.node == 4);
    /* clipped: keep z <= 0 — the inner's node 0 (z = -1) */
    thx_pick_plane pl = {{0, 0, -1}, 0};
    thx_pick_opts_default(&op);
    op.clip = &pl;
    op.n_clip = 1;
    CHECK_OK(ctx, thx_pick_node(ctx, x, o2, d, 1.5, 0, &op, &h));
    CHECK(h.surface == 0 && h.node == 0);
    CHECK_NEAR(h.t, 11, 1e-12);
    /* behind the origin: not picked */
    double o3[3] = {-1.02, -1, 0};
    CHECK_OK(ctx, thx_pick_node(ctx, x, o3, d, 0.1, 0, NULL, &h));
    CHECK(h.surface == 0 && h.node == 0);
    thx_pick_index_destroy(&x);
    thx_surface_destroy(&inner);
    thx_surface_destroy(&outer);
}

/* ------------------------------------------------------------- bad input */

static void test_bad(void)
{
    thx_surface *b = box(1);
    const thx_surface *surf[1] = {b};
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, 1, &x));
    thx_pick_hit h;
    CHECK(thx_pick_ray(ctx, x, (double[3]){0, 0, 0}, (double[3]){0, 0, 0}, NULL, &h) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "zero direction"));
    CHECK(h.surface == -1);
    CHECK(thx_pick_ray(ctx, x, (double[3]){NAN, 0, 0}, (double[3]){1, 0, 0}, NULL, &h) == THX_EINPUT);
    CHECK(thx_pick_ray_brute(ctx, surf, 1, (double[3]){0, 0, 0}, (double[3]){INFINITY, 0, 0}, NULL, &h) ==
          THX_EINPUT);
    thx_pick_plane pl = {{NAN, 0, 0}, 0};
    thx_pick_opts o;
    thx_pick_opts_default(&o);
    o.clip = &pl;
    o.n_clip = 1;
    CHECK(thx_pick_ray(ctx, x, (double[3]){-5, 0, 0}, (double[3]){1, 0, 0}, &o, &h) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "clip plane 1"));
    CHECK(thx_pick_node(ctx, x, (double[3]){-5, 0, 0}, (double[3]){1, 0, 0}, -1, 0, NULL, &h) == THX_EINPUT);
    CHECK(thx_pick_node(ctx, x, (double[3]){-5, 0, 0}, (double[3]){1, 0, 0}, 0, NAN, NULL, &h) == THX_EINPUT);
    thx_pick_index_destroy(&x);
    b->tri[7] = 8; /* triangle 3 names node 9 of 8 */
    CHECK(thx_pick_index_create(ctx, surf, 1, &x) == THX_EINPUT);
    CHECK(x == NULL);
    CHECK(tl_msg_has(ctx, "box"));
    b->tri[7] = 1;
    b->xyz[5] = NAN;
    CHECK(thx_pick_index_create(ctx, surf, 1, &x) == THX_EINPUT);
    CHECK(x == NULL);
    thx_surface_destroy(&b);
    /* no surfaces at all: nothing is hit */
    CHECK_OK(ctx, thx_pick_index_create(ctx, NULL, 0, &x));
    h = pick(x, 0, 0, 0, 1, 0, 0, NULL);
    CHECK(h.surface == -1);
    thx_pick_index_destroy(&x);
}

/* ------------------------------------------------------------- the phantom */

static void test_phantom(void)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    if (!m) return;
    const thx_surface *const *surf = (const thx_surface *const *)m->surf;
    size_t ns = m->n_surfaces, ntri = 0;
    for (size_t s = 0; s < ns; s++) ntri += surf[s]->n_tris;
    double t0 = thx_wtime();
    thx_pick_index *x = NULL;
    CHECK_OK(ctx, thx_pick_index_create(ctx, surf, ns, &x));
    if (!x) return;
    double t_build = thx_wtime() - t0;
    /* the torso's box */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, ctr[3];
    for (size_t i = 0; i < surf[0]->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], surf[0]->xyz[3 * i + k]);
            hi[k] = fmax(hi[k], surf[0]->xyz[3 * i + k]);
        }
    for (int k = 0; k < 3; k++) ctr[k] = 0.5 * (lo[k] + hi[k]);

    int n_rays = 1500, hits = 0, bad_brute = 0, bad_ref = 0, same_tri = 0, edge_hits = 0;
    double t_idx = 0, t_brute = 0;
    thx_pick_plane pl[2];
    unsigned char skip[THX_PHANTOM_N_SURFACES + 1];
    for (int k = 0; k < n_rays; k++) {
        double o[3], target[3], d[3];
        for (int j = 0; j < 3; j++) target[j] = lo[j] + urand() * (hi[j] - lo[j]);
        if (k % 3 == 2) { /* from inside the torso's box */
            for (int j = 0; j < 3; j++) o[j] = lo[j] + urand() * (hi[j] - lo[j]);
        } else { /* from a sphere of radius 600 mm around it */
            double u[3], n = 0;
            for (int j = 0; j < 3; j++) u[j] = urand() - 0.5, n += u[j] * u[j];
            for (int j = 0; j < 3; j++) o[j] = ctr[j] + 600 * u[j] / sqrt(n);
        }
        for (int j = 0; j < 3; j++) d[j] = target[j] - o[j];
        thx_pick_opts opt;
        thx_pick_opts_default(&opt);
        if (k % 4 == 1) { /* a random clip plane through the middle, and another */
            for (int p = 0; p < 2; p++) {
                double n[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
                pl[p] = (thx_pick_plane){{n[0], n[1], n[2]}, -(n[0] * ctr[0] + n[1] * ctr[1] + n[2] * ctr[2]) +
                                                               40 * (urand() - 0.5)};
            }
            opt.clip = pl;
            opt.n_clip = 1 + (size_t)(k % 8 == 1);
        }
        if (k % 5 == 3) { /* some surfaces hidden */
            for (size_t s = 0; s < ns; s++) skip[s] = urand() < 0.4;
            opt.skip = skip;
        }
        thx_pick_hit h, hb;
        double ta = thx_wtime();
        CHECK_OK(ctx, thx_pick_ray(ctx, x, o, d, &opt, &h));
        double tb = thx_wtime();
        CHECK_OK(ctx, thx_pick_ray_brute(ctx, surf, ns, o, d, &opt, &hb));
        t_brute += thx_wtime() - tb;
        t_idx += tb - ta;
        if (h.surface != hb.surface || h.tri != hb.tri || h.t != hb.t || h.node != hb.node || h.front != hb.front ||
            memcmp(h.point, hb.point, sizeof h.point))
            bad_brute++;
        check_hit(surf, &h, o, d);
        int rs;
        size_t rt = 0;
        double rtb, wmin = 1;
        mt_pick(surf, ns, o, d, opt.clip, opt.n_clip, opt.skip, &rs, &rt, &rtb, &wmin);
        if (h.surface >= 0) hits++;
        if (rs != h.surface || (rs >= 0 && fabs(rtb - h.t) > 1e-9)) {
            if (bad_ref++ < 5)
                fprintf(stderr, "phantom ray %d: pick surface %d t %.17g, reference surface %d t %.17g\n", k,
                        h.surface, h.t, rs, rtb);
        } else if (rs >= 0) {
            if (rt == h.tri) same_tri++;
            else if (wmin < 1e-7) edge_hits++;
            else if (bad_ref++ < 5)
                fprintf(stderr, "phantom ray %d: triangle %zu, reference %zu (min weight %g)\n", k, h.tri, rt, wmin);
        }
    }
    CHECK(bad_brute == 0);
    CHECK(bad_ref == 0);
    CHECK(hits > n_rays / 2);
    printf("phantom (medium, %zu triangles): index %.3f s; %d rays, %d hits: index = brute force for all, the "
           "reference's triangle for %d (%d on a shared edge); %.1f us a pick with the index, %.0f us brute force\n",
           ntri, t_build, n_rays, hits, same_tri, edge_hits, 1e6 * t_idx / n_rays, 1e6 * t_brute / n_rays);

    /* watertight on the phantom: a line through a vertex or an edge midpoint from far outside meets
     * each closed surface an even number of times; a ray from a surface's interior point an odd number */
    int bad_even = 0, bad_odd = 0, n_even = 0, n_odd = 0;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *sf = surf[s];
        for (int k = 0; k < 60; k++) {
            size_t t = (size_t)(urand() * sf->n_tris);
            const double *a = sf->xyz + 3 * sf->tri[3 * t], *b = sf->xyz + 3 * sf->tri[3 * t + 1];
            double P[3], o[3], d[3], u[3], n = 0;
            for (int j = 0; j < 3; j++) P[j] = (k & 1) ? a[j] : 0.5 * (a[j] + b[j]);
            for (int j = 0; j < 3; j++) u[j] = urand() - 0.5, n += u[j] * u[j];
            for (int j = 0; j < 3; j++) o[j] = ctr[j] + 700 * u[j] / sqrt(n), d[j] = P[j] - o[j];
            int cnt = line_hits(sf, o, d, NULL);
            n_even++;
            if (cnt % 2) bad_even++;
            if (m->has_interior && m->has_interior[s]) {
                double I[3] = {m->interior[s].x, m->interior[s].y, m->interior[s].z};
                CHECK(thx_surface_inside(sf, m->interior[s], 0) == THX_INSIDE);
                for (int j = 0; j < 3; j++) d[j] = P[j] - I[j];
                int ahead = 0;
                line_hits(sf, I, d, &ahead);
                n_odd++;
                if (ahead % 2 == 0) bad_odd++;
            }
        }
    }
    CHECK(bad_even == 0);
    CHECK(bad_odd == 0);
    CHECK(n_odd > 0);
    printf("phantom: %d lines through vertices and edge midpoints (even counts), %d rays from interior points "
           "(odd counts): %d and %d wrong\n", n_even, n_odd, bad_even, bad_odd);
    thx_pick_index_destroy(&x);
    thx_model_destroy(&m);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_box();
    test_box_watertight();
    test_icosphere();
    test_clip_nested();
    test_nodes();
    test_bad();
    test_phantom();
    int rc = tl_finish();
    thx_ctx_destroy(&ctx);
    return rc;
}
