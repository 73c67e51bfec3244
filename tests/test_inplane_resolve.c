/*
 * Step 3c of the surface build (src/geom/inplane_resolve.c): a layer's plane whose in-plane triangles
 * overlap or double an edge gets one triangulation of the region its laced ("wall") triangles bound.
 *  1. Two boxes stacked, with the shared layer's square covered twice by in-plane triangles (the slices
 *     below and above both cut it), or once (its edges in three triangles, nothing overlapping): those
 *     triangles are removed, nothing replaces them, and the surface is the 2 x 2 x 2 box: closed,
 *     manifold, 4 pi, volume 8.
 *  2. A bow-tie: the walls below and above bound edges in the plane that cross (two cut pockets' chords:
 *     the bench map's lungs, issue 25). Both edges and their wall triangles are split at the crossing
 *     point, and the region is its two lobes, area 1 each: every edge in the plane in exactly two
 *     triangles.
 *  3. A well-formed plane is left as it is (the same triangles, byte for byte).
 *  4. thx_surface_drop_unused renumbers the nodes in order.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "geom/inplane.h"
#include "thorax/check/check.h"

static thx_ctx *ctx;

static thx_surface *make(const double *xyz, size_t nn, const int32_t *tri, size_t nt, size_t *node_cap, size_t *tri_cap)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "s", THX_ROLE_OTHER, &s) != THX_OK) exit(1);
    *node_cap = nn + 8;
    *tri_cap = nt + 8;
    s->xyz = malloc(*node_cap * 3 * sizeof *s->xyz);
    s->tri = malloc(*tri_cap * 3 * sizeof *s->tri);
    if (!s->xyz || !s->tri) exit(1);
    memcpy(s->xyz, xyz, nn * 3 * sizeof *xyz);
    memcpy(s->tri, tri, nt * 3 * sizeof *tri);
    s->n_nodes = nn;
    s->n_tris = nt;
    return s;
}

/* the in-plane triangles at height z: their count and area */
static size_t flat_at(const thx_surface *s, double z, double *area)
{
    size_t n = 0;
    *area = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const double *a = s->xyz + 3 * s->tri[3 * t], *b = s->xyz + 3 * s->tri[3 * t + 1], *c = s->xyz + 3 * s->tri[3 * t + 2];
        if (a[2] != z || b[2] != z || c[2] != z) continue;
        n++;
        *area += 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    }
    return n;
}

/* every edge with both nodes at height z in exactly two triangles? */
static int plane_manifold(const thx_surface *s, double z)
{
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            if (s->xyz[3 * a + 2] != z || s->xyz[3 * b + 2] != z) continue;
            int uses = 0;
            for (size_t u = 0; u < s->n_tris; u++)
                for (int q = 0; q < 3; q++) {
                    int32_t c = s->tri[3 * u + q], d = s->tri[3 * u + (q + 1) % 3];
                    uses += (c == a && d == b) || (c == b && d == a);
                }
            if (uses != 2) return 0;
        }
    return 1;
}

/* The 8 outward walls between a square's corners first .. first + 3 (counterclockwise) and the corners
 * 4 above them, appended to tri after nt triangles; the new count. */
static size_t square_walls(int32_t *tri, size_t nt, int32_t first)
{
    for (int32_t k = 0; k < 4; k++) {
        int32_t a = first + k, b = first + (k + 1) % 4, c = a + 4, d = b + 4;
        int32_t w[6] = {a, b, d, a, d, c};
        memcpy(tri + 3 * nt, w, sizeof w);
        nt += 2;
    }
    return nt;
}

/* twice: the shared layer covered twice (from below and from above) or once (an edge in three
 * triangles, no overlap) */
static void test_doubled_square(int twice_covered)
{
    /* layers z = 0, 1, 2: the square [0,2]^2, corners counterclockwise */
    double xyz[12 * 3];
    const double sq[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
    for (int l = 0; l < 3; l++)
        for (int k = 0; k < 4; k++) {
            xyz[3 * (4 * l + k)] = sq[k][0];
            xyz[3 * (4 * l + k) + 1] = sq[k][1];
            xyz[3 * (4 * l + k) + 2] = l;
        }
    int32_t tri[3 * 24];
    size_t nt = 0;
    for (int l = 0; l < 2; l++) nt = square_walls(tri, nt, 4 * l);
    int32_t caps[12] = {0, 2, 1, 0, 3, 2, 8, 9, 10, 8, 10, 11};
    memcpy(tri + 3 * nt, caps, sizeof caps);
    nt += 4;
    /* the shared layer covered twice: from below (facing up) and from above (facing down) */
    int32_t twice[12] = {4, 5, 6, 4, 6, 7, 4, 6, 5, 4, 7, 6};
    size_t extra = twice_covered ? 4 : 2;
    memcpy(tri + 3 * nt, twice, extra * 3 * sizeof *twice);
    nt += extra;
    size_t ncap, tcap, nres = 0, nnew = 0, nd = 0;
    thx_surface *s = make(xyz, 12, tri, nt, &ncap, &tcap);
    thx_check_opts o;
    thx_check_opts_default(&o);
    thx_surface_report rep;
    CHECK(thx_surface_check(ctx, s, NULL, &o, &rep) == THX_ECHECK); /* non-manifold as laced */
    CHECK(thx_inplane_resolve(ctx, s, 1.0, 1.0, &ncap, &tcap, &nres, &nnew) == THX_OK);
    CHECK(nres == 1 && nnew == 0);
    CHECK(s->n_tris == nt - extra);
    CHECK(thx_surface_drop_unused(ctx, s, &nd) == THX_OK && nd == 0);
    thx_status cs = thx_surface_check(ctx, s, NULL, &o, &rep);
    printf("square covered %s: %zu plane resolved, %zu triangles left; check %s, volume %g, 4 pi error %.1e\n",
           twice_covered ? "twice" : "once", nres, s->n_tris,
           cs == THX_OK ? "passed" : "failed", rep.volume, rep.solid_angle_rel_err);
    CHECK(cs == THX_OK);
    CHECK_NEAR(rep.volume, 8.0, 1e-12);
    thx_surface_destroy(&s);
}

static void test_bow_tie(void)
{
    /* plane z = 0: p0 (0,0), p1 (2,2), q0 (2,0), q1 (0,2); the boundary p0-p1, p1-q0, q0-q1, q1-p0 crosses
       itself at (1,1); apexes of the walls: 4 below, 5 above */
    double xyz[6 * 3] = {0, 0, 0, 2, 2, 0, 2, 0, 0, 0, 2, 0, 1, 1, -1, 1, 1, 1};
    int32_t tri[3 * 7] = {
        0, 1, 4, /* wall below on p0-p1 */
        1, 2, 4, /* wall below on p1-q0 */
        2, 3, 5, /* wall above on q0-q1 */
        3, 0, 5, /* wall above on q1-p0 */
        0, 2, 1, /* in-plane triangles covering the square, one twice */
        0, 1, 3, 0, 2, 1,
    };
    size_t ncap, tcap, nres = 0, nnew = 0;
    thx_surface *s = make(xyz, 6, tri, 7, &ncap, &tcap);
    CHECK(thx_inplane_resolve(ctx, s, 1.0, 1.0, &ncap, &tcap, &nres, &nnew) == THX_OK);
    double area = 0;
    size_t nf = flat_at(s, 0.0, &area);
    int found = 0;
    for (size_t i = 6; i < s->n_nodes; i++) found |= s->xyz[3 * i] == 1 && s->xyz[3 * i + 1] == 1 && s->xyz[3 * i + 2] == 0;
    printf("bow-tie: %zu plane resolved, %zu in-plane triangles of area %g (two lobes of 1), %zu walls after the split\n",
           nres, nf, area, s->n_tris - nf);
    CHECK(nres == 1);
    CHECK(nnew == nf);
    CHECK(found);                 /* the crossing point, a node */
    CHECK(s->n_tris - nf == 6);   /* the two crossing walls each split in two */
    CHECK_NEAR(area, 2.0, 1e-12);
    CHECK(plane_manifold(s, 0.0));
    thx_surface_destroy(&s);
}

static void test_left_alone(void)
{
    /* one box: nothing to resolve */
    double xyz[8 * 3] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0, 0, 0, 1, 2, 0, 1, 2, 2, 1, 0, 2, 1};
    int32_t tri[3 * 12];
    size_t nt = 0;
    nt = square_walls(tri, nt, 0);
    int32_t caps[12] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7};
    memcpy(tri + 3 * nt, caps, sizeof caps);
    nt += 4;
    size_t ncap, tcap, nres = 7, nnew = 7;
    thx_surface *s = make(xyz, 8, tri, nt, &ncap, &tcap);
    CHECK(thx_inplane_resolve(ctx, s, 1.0, 1.0, &ncap, &tcap, &nres, &nnew) == THX_OK);
    CHECK(nres == 0 && nnew == 0 && s->n_tris == nt && s->n_nodes == 8);
    CHECK(memcmp(s->tri, tri, sizeof tri) == 0);
    thx_surface_destroy(&s);
}

static void test_drop_unused(void)
{
    double xyz[5 * 3] = {0, 0, 0, 9, 9, 9, 1, 0, 0, 8, 8, 8, 0, 1, 0};
    int32_t tri[3] = {4, 0, 2};
    size_t ncap, tcap, nd = 0;
    thx_surface *s = make(xyz, 5, tri, 1, &ncap, &tcap);
    CHECK(thx_surface_drop_unused(ctx, s, &nd) == THX_OK);
    CHECK(nd == 2 && s->n_nodes == 3);
    CHECK(s->tri[0] == 2 && s->tri[1] == 0 && s->tri[2] == 1);
    CHECK(s->xyz[3] == 1 && s->xyz[7] == 1);
    thx_surface_destroy(&s);
}

int main(void)
{
    thx_ctx_create(&ctx);
    test_doubled_square(1);
    test_doubled_square(0);
    test_bow_tie();
    test_left_alone();
    test_drop_unused();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
