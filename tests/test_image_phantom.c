/* Issue 25, 5(a): the phantom's label map at 5, 2 and 1 mm voxels (thx_phantom_voxelize), traced back
 * into contours (thx_image_trace), against the phantom's analytic anatomy: every loop node's distance, in
 * its plane, to the smooth outline of its surface on that plane (thx_phantom_section), and each surface's
 * volume from its loops against the analytic volume (thx_phantom_volumes). Under THORAX_QUICK the 1 mm map
 * is left out. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/image/trace.h"
#include "thorax/phantom/phantom.h"
#include "thorax/phantom/voxelize.h"

static thx_ctx *ctx;

static double seg_dist(thx_vec2 p, thx_vec2 a, thx_vec2 b)
{
    double ux = b.x - a.x, uy = b.y - a.y, l2 = ux * ux + uy * uy;
    double t = l2 > 0 ? ((p.x - a.x) * ux + (p.y - a.y) * uy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(p.x - a.x - t * ux, p.y - a.y - t * uy);
}

/* Whether the tissue's boundary by the phantom's point test passes within r of (x, y) on the plane: the
 * centre and 48 points on the circle of radius r are not all on one side. The smooth outline
 * (thx_phantom_section) is one loop a surface; where a lung's plane holds two (its tip cut across), the
 * point test is the reference for the other. */
static int member(int s, int region) { return s < 3 ? region >= s + 1 : region == s + 1; }

static int boundary_within(const thx_phantom_plane *pl, int s, double x, double y, double r)
{
    int in0 = member(s, thx_phantom_region(pl, x, y));
    for (int k = 0; k < 48; k++) {
        double a = 2 * M_PI * k / 48;
        int in = member(s, thx_phantom_region(pl, x + r * cos(a), y + r * sin(a)));
        if (in != in0) return 1;
    }
    return 0;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void run(double h)
{
    thx_phantom_field *f = NULL;
    CHECK_OK(ctx, thx_phantom_field_create(ctx, &f));
    double lo[3], hi[3];
    thx_phantom_bounds(f, lo, hi);
    thx_image lab;
    CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, h, 2, &lab));
    thx_voxelize_opts vo;
    thx_voxelize_opts_default(&vo);
    if (h < 2) vo.sub = 2; /* 8 sub-samples a boundary voxel at 1 mm (64 at 2 and 5 mm): the test's time */
    CHECK_OK(ctx, thx_phantom_voxelize(ctx, &vo, &lab, NULL, NULL));
    /* the phantom's surfaces: torso, fat, muscle, lung_r, lung_l, heart (regions 1 + index) */
    static const long all[] = {1, 2, 3, 4, 5, 6}, fat[] = {2, 3, 4, 5, 6}, mus[] = {3, 4, 5, 6}, lr[] = {4}, ll[] = {5},
                      hr[] = {6};
    static const char *const names[] = {"torso", "fat", "muscle", "lung_r", "lung_l", "heart"};
    thx_trace_tissue t[6] = {
        {all, 6, 0, names[0], THX_ROLE_OUTER}, {fat, 5, 0, names[1], THX_ROLE_FAT}, {mus, 4, 0, names[2], THX_ROLE_MUSCLE},
        {lr, 1, 0, names[3], THX_ROLE_LUNG},   {ll, 1, 0, names[4], THX_ROLE_LUNG}, {hr, 1, 0, names[5], THX_ROLE_HEART}};
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = t;
    o.n_tissues = 6;
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, thx_image_trace(ctx, &lab, &o, &c, &rep));
    if (!c) exit(1);
    double vol[THX_PHANTOM_N_SURFACES];
    CHECK_OK(ctx, thx_phantom_volumes(ctx, f, 0.25, vol));
    for (size_t s = 0; s < c->n_surfaces; s++) {
        const thx_contour_surface *cs = &c->surf[s];
        size_t nd = 0, cap = 0, n_second = 0;
        double *d = NULL, v = 0;
        for (size_t l = 0; l < cs->n_layers; l++) {
            const thx_contour_layer *L = &cs->layers[l];
            thx_vec2 *sec = NULL;
            size_t ns = 0;
            CHECK_OK(ctx, thx_phantom_section(ctx, f, (int)s, L->z, &sec, &ns));
            thx_phantom_plane *pl = NULL;
            CHECK_OK(ctx, thx_phantom_plane_create(ctx, f, L->z, &pl));
            for (size_t k = 0; k < L->n_loops; k++) {
                const thx_loop *lp = &L->loops[k];
                double a = 0;
                for (size_t i = 0, j = lp->n - 1; i < lp->n; j = i++) a += lp->p[j].x * lp->p[i].y - lp->p[i].x * lp->p[j].y;
                v += 0.5 * a * h;
                for (size_t i = 0; i < lp->n; i++) {
                    double best = INFINITY;
                    for (size_t q = 0; q < ns; q++) best = fmin(best, seg_dist(lp->p[i], sec[q], sec[(q + 1) % ns]));
                    /* beyond half a voxel from the one smooth outline: the point test's boundary within half a
                       voxel counts (a second loop of a lung's tip) */
                    if (best > 0.5 * h && boundary_within(pl, (int)s, lp->p[i].x, lp->p[i].y, 0.5 * h)) {
                        best = 0.5 * h;
                        n_second++;
                    }
                    if (nd == cap) {
                        cap = cap ? 2 * cap : 1024;
                        d = realloc(d, cap * sizeof *d);
                        if (!d) exit(1);
                    }
                    d[nd++] = ns ? best : INFINITY;
                }
            }
            free(sec);
            thx_phantom_plane_destroy(&pl);
        }
        qsort(d, nd, sizeof *d, cmp_d);
        double p50 = d[nd / 2], p99 = d[(size_t)(0.99 * (double)(nd - 1))], mx = d[nd - 1];
        double verr = v / vol[s] - 1;
        printf("phantom %g mm voxels: %-7s %3zu layers %6zu nodes: in-plane distance median %.3f, 99%% %.3f, max %.3f "
               "voxel (%zu by the point test); volume from the loops %+.2f%%\n",
               h, cs->name, cs->n_layers, nd, p50 / h, p99 / h, mx / h, n_second, 100 * verr);
        CHECK(p99 <= 0.5 * h);           /* all but the caps' rims: within half a voxel in the plane */
        CHECK(mx <= 1.5 * h);            /* the worst, where a rounded end meets its cap plane */
        CHECK(fabs(verr) < 0.01 || (h >= 5 && fabs(verr) < 0.03));
        free(d);
    }
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&lab);
    thx_phantom_field_destroy(&f);
}

int main(void)
{
    thx_ctx_create(&ctx);
    run(5.0);
    run(2.0);
    if (!getenv("THORAX_QUICK")) run(1.0);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
