/*
 * Three shapes of a traced label map that the surface build laced with triangles under 1 degree
 * (issue 25, item 6), each mended where it arises:
 *  - a dome's top (tests/data/lace/dome_and_wedge.txt, the left lung): the diaphragm's dome cuts an
 *    oval pocket into one layer's loop from the crescent's concave side, the next layer up is the
 *    crescent without it. The pocket is no bay of the loop's hull; found as a run of nodes inside
 *    the other layer's curve (lace.c, run_pocket), it is cut in its plane, and its 27 mm chord gets
 *    nodes at the spacing (thx_lace_nodes) so that the other layer's run along it is not fanned to
 *    the chord's two ends;
 *  - a wedge's tip one voxel wide (the same file, the right lung beside the mediastinum), 14 mm
 *    further on each layer up: its tail is cut in its plane as a tongue found as a run of nodes
 *    outside the other layer's curve (run_tongue), not fanned side by side to the other tip;
 *  - a loop not much larger than the spline's smoothing bandwidth (a lung's tip of 2 x 0.7 mm),
 *    which the smoothing shrank to a 0.03 mm triangle: fitted again with less smoothing
 *    (spline.c, SMOOTH_KEEP_AREA).
 * The built surfaces must pass thorax check (closed, 4 pi, no intersection, every angle above 1
 * degree); both mechanisms must have acted; a large loop's smoothing is left as it was.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/check/contours.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/surfaces.h"
#include "thorax/model/model.h"

static thx_ctx *ctx;

static double area(const thx_vec2 *p, size_t n) { return thx_loop_area(p, n); }

/* the two lung pieces built, checked, and the mechanisms seen in the statistics and the nodes */
static void dome_and_wedge(void)
{
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_contours_read(ctx, tl_src_path(__FILE__, "data/lace/dome_and_wedge.txt"), &c));
    if (!c) return;
    CHECK(c->n_surfaces == 2);
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    thx_surfaces_stats st[2];
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_surfaces_build(ctx, c, &o, &m, st, NULL));
    if (!m) { thx_contours_destroy(&c); return; }
    for (size_t s = 0; s < m->n_surfaces; s++) {
        thx_surface_report rep;
        memset(&rep, 0, sizeof rep);
        thx_status r = thx_surface_check(ctx, m->surf[s], m->has_interior[s] ? &m->interior[s] : NULL, NULL, &rep);
        printf("%-12s %zu nodes %zu triangles: check %s, smallest angle %.2f deg; tongues %zu, filled pockets %zu, "
               "laced again for an angle %zu\n",
               m->surf[s]->name, m->surf[s]->n_nodes, m->surf[s]->n_tris, r == THX_OK ? "passes" : thx_ctx_message(ctx),
               rep.min_angle, st[s].lace.tongues, st[s].lace.filled_pockets, st[s].lace.relaced_quality);
        CHECK(r == THX_OK);
        CHECK(rep.min_angle >= 1.0);
        thx_surface_report_free(&rep);
    }
    /* the wedge (lungs_right): its tail cut as a tongue by a lacing laced again for its angle */
    CHECK(strcmp(m->surf[0]->name, "lungs_right") == 0);
    CHECK(st[0].lace.tongues >= 1 && st[0].lace.relaced_quality >= 1);
    /* the dome (lungs_left): the pocket cut, and nodes on its chord from (-60.14, 4.19) to (-75.36, 26.76)
       at z = 125.5: inner points of the chord, at the spacing (1 mm: about 26 of them) */
    CHECK(strcmp(m->surf[1]->name, "lungs_left") == 0);
    CHECK(st[1].lace.filled_pockets >= 1);
    const thx_surface *d = m->surf[1];
    double ax = -60.1355, ay = 4.18769, bx = -75.363, by = 26.7598, L = hypot(bx - ax, by - ay);
    size_t on_chord = 0;
    for (size_t i = 0; i < d->n_nodes; i++) {
        const double *p = d->xyz + 3 * i;
        if (fabs(p[2] - 125.5) > 1e-9) continue;
        double t = ((p[0] - ax) * (bx - ax) + (p[1] - ay) * (by - ay)) / (L * L);
        double off = fabs((p[0] - ax) * (by - ay) - (p[1] - ay) * (bx - ax)) / L;
        if (t > 0.01 && t < 0.99 && off < 1e-3) on_chord++; /* (the ends given to 6 digits) */
    }
    printf("dome: %zu nodes on the pocket's %.1f mm chord\n", on_chord, L);
    CHECK(on_chord >= 20 && on_chord <= 30);
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
}

/* a lung's tip traced from the map (a diamond 0.67 x 2.1 mm, 8 points) keeps half its area or more
   at the default smoothing; a 40 mm circle's smoothing is not lessened (its nodes as with the
   smoothing given, not as without) */
static void small_loop(void)
{
    const thx_vec2 tip[8] = {{-121.999993, -23.862004}, {-121.73317, -23.599991}, {-121.663221, -22.799991},
                             {-121.73317, -21.999991},  {-121.999993, -21.737978}, {-122.266815, -21.999991},
                             {-122.336765, -22.799991}, {-122.266815, -23.599991}};
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    thx_vec2 *r = NULL;
    size_t n = 0;
    CHECK_OK(ctx, thx_loop_resample(ctx, tip, 8, 1.0, o.smoothing, o.start, &r, &n));
    double a0 = fabs(area(tip, 8)), a1 = r ? fabs(area(r, n)) : 0;
    printf("a lung's tip: %.3f mm^2 digitized, %.3f mm^2 resampled (%zu nodes) at smoothing %g mm\n", a0, a1, n, o.smoothing);
    CHECK(a1 >= 0.5 * a0 && a1 <= 1.5 * a0);
    free(r);
    enum { NC = 64 };
    thx_vec2 circ[NC];
    for (int k = 0; k < NC; k++) circ[k] = (thx_vec2){20 * cos(2 * M_PI * k / NC) + 0.3 * (k % 2), 20 * sin(2 * M_PI * k / NC)};
    thx_vec2 *sm[3] = {NULL, NULL, NULL}; /* at the smoothing given, half of it, none */
    size_t nm[3] = {0, 0, 0};
    double spread[3] = {0, 0, 0}; /* the zig-zag's spread of radii, which the smoothing evens out */
    for (int w = 0; w < 3; w++) {
        CHECK_OK(ctx, thx_loop_resample(ctx, circ, NC, 1.0, o.smoothing * (w == 0 ? 1.0 : w == 1 ? 0.5 : 0.0), o.start,
                                        &sm[w], &nm[w]));
        double lo = INFINITY, hi = 0;
        for (size_t k = 0; k < nm[w]; k++)
            lo = fmin(lo, hypot(sm[w][k].x, sm[w][k].y)), hi = fmax(hi, hypot(sm[w][k].x, sm[w][k].y));
        spread[w] = hi - lo;
        free(sm[w]);
    }
    printf("a 40 mm zig-zag circle: radii spread %.3f mm at smoothing %g mm, %.3f at half, %.3f at none\n", spread[0],
           o.smoothing, spread[1], spread[2]);
    CHECK(spread[0] < spread[1] - 0.02 && spread[1] < spread[2] - 0.02);
}

int main(void)
{
    thx_ctx_create(&ctx);
    dome_and_wedge();
    small_loop();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
