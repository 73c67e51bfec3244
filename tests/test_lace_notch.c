/*
 * Lacing a loop with a deep, narrow notch against a loop without it (issue 25, 5(c)).
 *
 * On the Cranium CT (InVesalius' example) the skull's loop on the planes through the frontal
 * sinus runs around the outside of the skull, in through the sinus's notch (a slit a few voxels
 * wide), around the whole cranial cavity and out again; on the next plane up the bone ring is
 * closed, the cavity filled, and the loop is the outside only. Laced as one pair of chains, the
 * cavity's side of the notched loop was fanned to a few nodes of the full one across the skull:
 * triangles whose centroids lie inside the full loop pass the outside test, and they cut the rest
 * of the slice (1,658 crossing pairs, the check failed).
 *
 * Here the same case is built from analytic loops (a ring of bone 12 mm thick with a 3 mm slit,
 * two layers, against two layers of a full disc shifted sideways), in both orders (the notch below
 * and the notch above), and each surface must be a closed, outward, non-self-intersecting
 * manifold whose volume is the layers' areas times their heights: the cavity closed by a ceiling
 * (or a floor) in the plane of the last notched layer, as the surface of the solid is.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/surfaces.h"

#define R_OUT 80.0
#define R_IN 68.0
#define SLIT 1.5 /* half-width of the notch, mm */

/* Appends the point to p (n points so far, room for cap). */
static void push(thx_vec2 *p, int *n, int cap, double x, double y)
{
    if (*n < cap) p[(*n)++] = (thx_vec2){x, y};
}

/* The notched ring (counterclockwise, the bone on the left): the outside circle from the slit's
 * left edge around to its right edge, down the right edge, clockwise around the cavity (centre
 * (cx, cy), radius R_IN), up the left edge. Points about 1 mm apart. Returns the count. */
static int notched_ring(thx_vec2 *p, int cap, double cx, double cy)
{
    int n = 0;
    double ao = asin(SLIT / R_OUT);
    int m = (int)(2 * M_PI * R_OUT);
    for (int k = 0; k <= m; k++) {
        double a = M_PI / 2 + ao + (2 * M_PI - 2 * ao) * k / m;
        push(p, &n, cap, R_OUT * cos(a), R_OUT * sin(a));
    }
    /* the slit's right wall, from the outside circle down to the cavity */
    double yo = sqrt(R_OUT * R_OUT - SLIT * SLIT), yi = cy + sqrt(R_IN * R_IN - (SLIT - cx) * (SLIT - cx));
    for (double y = yo - 1; y > yi + 0.5; y -= 1) push(p, &n, cap, SLIT, y);
    double ai_r = atan2(yi - cy, SLIT - cx), ai_l = atan2(yi - cy, -SLIT - cx);
    int mi = (int)(2 * M_PI * R_IN);
    for (int k = 0; k <= mi; k++) { /* clockwise from the right wall to the left one, the long way */
        double a = ai_r - (2 * M_PI - (ai_l - ai_r)) * k / mi;
        push(p, &n, cap, cx + R_IN * cos(a), cy + R_IN * sin(a));
    }
    for (double y = yi + 1; y < yo - 0.5; y += 1) push(p, &n, cap, -SLIT, y);
    return n;
}

static double shoelace(const thx_vec2 *p, int n)
{
    double a = 0;
    for (int k = 0; k < n; k++) a += p[k].x * p[(k + 1) % n].y - p[(k + 1) % n].x * p[k].y;
    return 0.5 * a;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    enum { CAP = 4096 };
    thx_vec2 *ring = malloc(CAP * sizeof *ring), *disc = malloc(CAP * sizeof *disc), *q = malloc(CAP * sizeof *q);
    /* the cavity off centre (the skull is thicker at the back), the full disc shifted by 2 mm */
    int nr = notched_ring(ring, CAP, 0, 4);
    int nd = (int)(2 * M_PI * R_OUT);
    for (int k = 0; k < nd; k++) {
        double a = 2 * M_PI * k / nd;
        disc[k] = (thx_vec2){2 + R_OUT * cos(a), 1 + R_OUT * sin(a)};
    }
    double a_ring = shoelace(ring, nr), a_disc = shoelace(disc, nd);
    CHECK(a_ring > 0 && a_disc > 0);
    /* surface 0: the notch on the two lower layers; surface 1: on the two upper ones (x + 300) */
    size_t s[2];
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "notch_below", THX_ROLE_OTHER, THX_CAP_GRID, 0, &s[0]));
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "notch_above", THX_ROLE_OTHER, THX_CAP_GRID, 0, &s[1]));
    double dz = 1.5;
    for (int sf = 0; sf < 2; sf++)
        for (int l = 0; l < 4; l++) {
            int notched = sf == 0 ? l < 2 : l >= 2;
            const thx_vec2 *src = notched ? ring : disc;
            int n = notched ? nr : nd;
            for (int k = 0; k < n; k++) q[k] = (thx_vec2){src[k].x + 300.0 * sf, src[k].y};
            CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s[sf], dz * l, q, (size_t)n));
        }
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    o.spacing = 1.5;
    thx_model *m = NULL;
    thx_surfaces_stats st[2];
    thx_status r = thx_surfaces_build(ctx, c, &o, &m, st, NULL);
    CHECK_OK(ctx, r);
    /* the solid: two slabs of the notched ring and two of the disc (the slab between them is the
       disc's: the cavity is closed in the plane of the last notched layer) */
    double exact = dz * a_ring + 2 * dz * a_disc;
    for (size_t k = 0; r == THX_OK && k < m->n_surfaces; k++) {
        thx_surface_report rep;
        thx_check_opts co;
        thx_check_opts_default(&co);
        /* the whole check, the 1-degree floor included: the cavity's cut in its plane, triangulated by
           the lacing from its ~300 boundary nodes (0.63 and 0.23 degrees), is triangulated again with
           grid nodes, its chord (10.7 mm among 1.5 mm edges) split with the triangle beyond it (build
           step 3b, src/geom/inplane.c) */
        CHECK_OK(ctx, thx_surface_check(ctx, m->surf[k], &m->interior[k], &co, &rep));
        CHECK(rep.ok);
        for (size_t e = 0; !rep.ok && e < rep.n_reasons; e++) fprintf(stderr, "  %s: %s\n", m->surf[k]->name, rep.reasons[e]);
        thx_surface_report_free(&rep);
        CHECK_NEAR(thx_surface_solid_angle(m->surf[k], m->interior[k]) / (4 * M_PI), 1.0, 1e-6);
        double v = thx_surface_volume(m->surf[k]);
        printf("%s: volume %.1f mm^3, layers' areas x heights %.1f (%.3f%%); %zu crossing groups, %zu re-laced "
               "after crossing, %zu filled pockets, %zu in-plane triangles, largest fan %d\n",
               m->surf[k]->name, v, exact, 100 * (v - exact) / exact, st[k].lace.crossing, st[k].lace.relaced_crossing,
               st[k].lace.filled_pockets, st[k].lace.inplane_tris, st[k].lace.max_fan);
        /* the cavity left open or filled would be off by 1.5 * pi * 68^2 = 21,800 mm^3 (32%) */
        CHECK(fabs(v - exact) < 0.01 * exact);
        CHECK(st[k].lace.crossing == 0);
        CHECK(st[k].lace.filled_pockets == 1);
    }
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    free(ring);
    free(disc);
    free(q);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
