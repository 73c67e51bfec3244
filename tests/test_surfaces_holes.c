/*
 * Surfaces with holes (src/geom/build.c: rloop.hole, mark_holes, hole_covered, enclosing_outer):
 * a lung's base over the diaphragm's dome, as the bench map has it (issue 25). Contours, 2 mm
 * apart, of a disc of radius 40 mm with a dome pushing up into it from below:
 *   z = 0     a horseshoe: the annulus 20 < r < 40 opened by a channel 4 mm wide along +x (the
 *             dome's section meets the outside at one saddle),
 *   z = 2, 4  annuli, the dome's section a hole of radius 18, 12 mm,
 *   z = 6, 8  full discs (above the dome's top).
 * The hole at z = 2 has no hole to lace to below: it is joined to its annulus (bridged, walked
 * clockwise) and laced to the horseshoe's pocket; the hole at z = 4 is capped under the disc above.
 * The surface must pass thorax check (closed, outward, 4 pi about an interior point outside the
 * dome, no intersection, angles), enclose the volume of the layers' areas (trapezoidal in z, within
 * 3%: the lacing interpolates), and have no node in the plane z = 0 inside the dome's section
 * (the failure before holes were taken: the surface closed flat over the dome there, counting it as
 * tissue). The same contours with the holes filled enclose the dome's volume too: the difference
 * is checked against the holes' areas.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/surfaces.h"
#include "thorax/model/contours.h"
#include "thorax/model/model.h"

static thx_ctx *ctx;

#define R_OUT 40.0
#define W_CH 4.0

static void add(thx_contours *c, size_t s, double z, const thx_vec2 *p, size_t n)
{
    if (thx_contours_add_loop(ctx, c, s, z, p, n) != THX_OK) {
        fprintf(stderr, "add loop: %s\n", thx_ctx_message(ctx));
        exit(1);
    }
}

/* a circle of radius r, counterclockwise (cw: clockwise), about 1 mm between points */
static size_t circle(thx_vec2 *p, double r, int cw)
{
    size_t n = (size_t)ceil(2 * M_PI * r / 1.0);
    for (size_t k = 0; k < n; k++) {
        double a = 2 * M_PI * (double)k / (double)n * (cw ? -1 : 1);
        p[k] = (thx_vec2){r * cos(a), r * sin(a)};
    }
    return n;
}

/* the horseshoe: the outer arc counterclockwise from the channel's upper side round to its lower side,
   in along y = -W/2, the inner arc clockwise, out along y = +W/2 */
static size_t horseshoe(thx_vec2 *p, double r_in)
{
    size_t n = 0;
    double a0 = asin(0.5 * W_CH / R_OUT), a1 = asin(0.5 * W_CH / r_in);
    int no = (int)ceil((2 * M_PI - 2 * a0) * R_OUT), ni = (int)ceil((2 * M_PI - 2 * a1) * r_in);
    for (int k = 0; k <= no; k++) {
        double a = a0 + (2 * M_PI - 2 * a0) * k / no;
        p[n++] = (thx_vec2){R_OUT * cos(a), R_OUT * sin(a)};
    }
    double x0 = R_OUT * cos(a0), x1 = r_in * cos(a1);
    for (int k = 1; k < (int)(x0 - x1); k++) p[n++] = (thx_vec2){x0 - k, -0.5 * W_CH};
    for (int k = 0; k <= ni; k++) {
        double a = -a1 - (2 * M_PI - 2 * a1) * k / ni;
        p[n++] = (thx_vec2){r_in * cos(a), r_in * sin(a)};
    }
    for (int k = 1; k < (int)(x0 - x1); k++) p[n++] = (thx_vec2){x1 + k, 0.5 * W_CH};
    return n;
}

static thx_vec2 pts[2][600];

static thx_contours *make(int filled)
{
    thx_contours *c = NULL;
    size_t s;
    if (thx_contours_create(ctx, &c) != THX_OK) exit(1);
    c->spacing = 1.0;
    if (thx_contours_add_surface(ctx, c, "lung", THX_ROLE_LUNG, THX_CAP_GRID, 0, &s) != THX_OK) exit(1);
    const double hole[3] = {20, 18, 12};
    for (int l = 0; l < 5; l++) {
        double z = 2.0 * l;
        size_t n = l == 0 && !filled ? horseshoe(pts[0], hole[0]) : circle(pts[0], R_OUT, 0);
        add(c, s, z, pts[0], n);
        if (l >= 1 && l <= 2 && !filled) add(c, s, z, pts[1], circle(pts[1], hole[l], 1));
    }
    return c;
}

static double loop_area(const thx_contour_layer *L)
{
    double a = 0;
    for (size_t k = 0; k < L->n_loops; k++) a += thx_loop_area(L->loops[k].p, L->loops[k].n);
    return a;
}

int main(void)
{
    thx_ctx_create(&ctx);
    double vol[2] = {0, 0}, want[2] = {0, 0};
    for (int filled = 0; filled < 2; filled++) {
        thx_contours *c = make(filled);
        const thx_contour_surface *cs = &c->surf[0];
        for (size_t l = 0; l + 1 < cs->n_layers; l++) /* trapezoidal in z over the signed areas (holes negative) */
            want[filled] += 0.5 * (loop_area(&cs->layers[l]) + loop_area(&cs->layers[l + 1])) * (cs->layers[l + 1].z - cs->layers[l].z);
        thx_surfaces_opts o;
        thx_surfaces_opts_default(&o);
        o.smoothing = 0.5;
        thx_model *m = NULL;
        thx_status r = thx_surfaces_build(ctx, c, &o, &m, NULL, NULL);
        CHECK_OK(ctx, r);
        if (r != THX_OK || !m) { thx_contours_destroy(&c); continue; }
        const thx_surface *sf = m->surf[0];
        thx_surface_report rep;
        memset(&rep, 0, sizeof rep);
        r = thx_surface_check(ctx, sf, m->has_interior[0] ? &m->interior[0] : NULL, NULL, &rep);
        vol[filled] = thx_surface_volume(sf);
        size_t in_dome = 0; /* nodes in the plane z = 0 more than 1 mm inside the dome's section */
        for (size_t i = 0; i < sf->n_nodes; i++) {
            const double *p = sf->xyz + 3 * i;
            if (fabs(p[2]) < 1e-9 && hypot(p[0], p[1]) < 19.0 && !(p[0] > 0 && fabs(p[1]) < 0.5 * W_CH + 1)) in_dome++;
        }
        printf("%s: %zu nodes, %zu triangles, check %s (smallest angle %.2f deg), volume %.0f mm^3 (layers' areas: "
               "%.0f, %+.2f%%), nodes in the plane z = 0 inside the dome: %zu\n",
               filled ? "holes filled" : "holes", sf->n_nodes, sf->n_tris, r == THX_OK ? "passes" : thx_ctx_message(ctx),
               rep.min_angle, vol[filled], want[filled], 100 * (vol[filled] / want[filled] - 1), in_dome);
        CHECK(r == THX_OK);
        CHECK(fabs(vol[filled] / want[filled] - 1) < 0.03);
        if (!filled) CHECK(in_dome == 0);
        thx_surface_report_free(&rep);
        thx_model_destroy(&m);
        thx_contours_destroy(&c);
    }
    /* the dome's volume, counted as tissue when the holes are filled: about the holes' areas over their layers */
    printf("the dome's volume: %.0f mm^3 between the two (the layers' areas give %.0f)\n", vol[1] - vol[0], want[1] - want[0]);
    CHECK(vol[1] - vol[0] > 0.8 * (want[1] - want[0]));
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
