/* Planes cut through an image (thorax/image/sample.h): trilinear sampling reproduces a linear
 * function of position exactly at every sample inside an oblique grid (and nowhere outside it,
 * where the samples are NaN); nearest sampling gives the value of the voxel whose centre is
 * nearest; an axial plane through voxel centres of an axis-aligned grid gives the voxels
 * themselves; a RAS plane's range is the voxels' outer faces; index planes; plane specs parsed and
 * refused; the default windows (label map, Hounsfield units, percentiles) against values computed
 * here. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/image/sample.h"

static double lin(const double p[3])
{
    return 3.0 + 0.5 * p[0] - 1.25 * p[1] + 2.0 * p[2];
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);

    /* plane specs */
    thx_image_plane_spec sp;
    CHECK(thx_image_plane_parse("z=-20.5", &sp) == 0 && sp.axis == 'z' && sp.pos == -20.5);
    CHECK(thx_image_plane_parse("k=12", &sp) == 0 && sp.axis == 'k' && sp.pos == 12);
    CHECK(thx_image_plane_parse("w=1", &sp) == -1);
    CHECK(thx_image_plane_parse("z=", &sp) == -1);
    CHECK(thx_image_plane_parse("z=1mm", &sp) == -1);
    CHECK(thx_image_plane_parse("z=nan", &sp) == -1);
    CHECK(thx_image_plane_parse("", &sp) == -1);
    CHECK(thx_image_plane_parse("z", &sp) == -1);

    /* an oblique grid (30 degrees about x, then 20 about z), anisotropic, values linear in RAS */
    size_t n[3] = {9, 7, 6};
    thx_image img;
    CHECK_OK(ctx, thx_image_alloc(ctx, n, &img));
    double a = M_PI / 6, b = M_PI / 9;
    double rx[9] = {1, 0, 0, 0, cos(a), -sin(a), 0, sin(a), cos(a)};
    double rz[9] = {cos(b), -sin(b), 0, sin(b), cos(b), 0, 0, 0, 1};
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double s = 0;
            for (int k = 0; k < 3; k++) s += rz[r * 3 + k] * rx[k * 3 + c];
            img.dir[r * 3 + c] = s;
        }
    img.spacing[0] = 1.5, img.spacing[1] = 2.0, img.spacing[2] = 3.0;
    img.origin[0] = -5, img.origin[1] = 8, img.origin[2] = -4;
    for (size_t k = 0; k < n[2]; k++)
        for (size_t j = 0; j < n[1]; j++)
            for (size_t i = 0; i < n[0]; i++) {
                double ijk[3] = {(double)i, (double)j, (double)k}, p[3];
                thx_image_index_to_ras(&img, ijk, p);
                img.v[thx_image_at(&img, i, j, k)] = (float)lin(p);
            }
    CHECK_OK(ctx, thx_image_validate(ctx, &img, "oblique"));

    /* an axial plane through the middle: inside samples = the linear function (float voxels), outside
       (beyond half a voxel from the outer centres) NaN; both kinds present */
    double lo, hi, step;
    thx_image_plane_range(&img, 'z', &lo, &hi, &step);
    thx_image_plane_spec mid = {'z', 0.5 * (lo + hi) + 0.3};
    thx_image_slice sl;
    CHECK_OK(ctx, thx_image_sample_plane(ctx, &img, &mid, 0, &sl));
    size_t inside = 0, outside = 0, bad = 0;
    double worst = 0;
    for (size_t q = 0; q < sl.w * sl.h; q++) {
        double p[3], x[3];
        for (int k = 0; k < 3; k++) p[k] = sl.origin[k] + (double)(q % sl.w) * sl.du[k] + (double)(q / sl.w) * sl.dv[k];
        CHECK_NEAR(p[2], mid.pos, 1e-9);
        thx_image_ras_to_index(&img, p, x);
        int in = 1;
        for (int k = 0; k < 3; k++) in &= x[k] >= -0.5 && x[k] <= (double)n[k] - 0.5;
        if (in) {
            inside++;
            /* clamped to the outer centres within the last half voxel: linear only inside the centres */
            int core = 1;
            for (int k = 0; k < 3; k++) core &= x[k] >= 0 && x[k] <= (double)n[k] - 1;
            if (core) worst = fmax(worst, fabs(sl.v[q] - lin(p)));
            bad += isnan(sl.v[q]);
        } else {
            outside++;
            bad += !isnan(sl.v[q]);
        }
    }
    CHECK(inside > 20 && outside > 20 && bad == 0);
    CHECK(worst < 1e-4 * 40);
    printf("oblique axial plane: %zu x %zu samples, %zu inside (max |trilinear - linear| %.2g), %zu outside\n", sl.w, sl.h,
           inside, worst, outside);
    thx_image_slice_free(&sl);

    /* nearest: the voxel whose centre is nearest, for random points inside */
    srand(7);
    int wrong = 0;
    for (int t = 0; t < 500; t++) {
        double x[3], p[3];
        for (int k = 0; k < 3; k++) x[k] = -0.49 + ((double)rand() / RAND_MAX) * ((double)n[k] - 0.02);
        thx_image_index_to_ras(&img, x, p);
        size_t q[3];
        for (int k = 0; k < 3; k++) q[k] = (size_t)floor(x[k] + 0.5);
        wrong += thx_image_sample_at(&img, p, 1) != img.v[thx_image_at(&img, q[0], q[1], q[2])];
    }
    CHECK(wrong == 0);

    /* an index plane j = 3: the voxels of that plane, exactly */
    thx_image_plane_spec jp = {'j', 3};
    CHECK_OK(ctx, thx_image_sample_plane(ctx, &img, &jp, 0, &sl));
    CHECK(sl.w == n[0] && sl.h == n[2] && sl.step == 1 && sl.lo == 0 && sl.hi == (double)n[1] - 1);
    int diff = 0;
    for (size_t k = 0; k < n[2]; k++)
        for (size_t i = 0; i < n[0]; i++) diff += fabs(sl.v[i + n[0] * k] - img.v[thx_image_at(&img, i, 3, k)]) > 1e-4;
    CHECK(diff == 0);
    for (int k = 0; k < 3; k++) CHECK_NEAR(sl.normal[k], img.dir[k * 3 + 1], 1e-12);
    thx_image_slice_free(&sl);

    /* outside the image: refused with the range */
    thx_image_plane_spec far = {'z', hi + 1};
    CHECK(thx_image_sample_plane(ctx, &img, &far, 0, &sl) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "is outside the image"));
    thx_image_plane_spec kfar = {'k', 6};
    CHECK(thx_image_sample_plane(ctx, &img, &kfar, 0, &sl) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "k from 0 to 5"));
    thx_image_free(&img);

    /* axis-aligned: an axial plane through voxel centres gives the voxels; the range is the faces */
    size_t m[3] = {4, 3, 5};
    CHECK_OK(ctx, thx_image_alloc(ctx, m, &img));
    img.spacing[0] = 2, img.spacing[1] = 2.5, img.spacing[2] = 4;
    img.origin[0] = -3, img.origin[1] = 1, img.origin[2] = 10;
    for (size_t q = 0; q < 60; q++) img.v[q] = (float)((q * 37) % 11);
    img.integral = 1;
    thx_image_plane_range(&img, 'z', &lo, &hi, &step);
    CHECK_NEAR(lo, 8, 1e-12);
    CHECK_NEAR(hi, 28, 1e-12);
    CHECK_NEAR(step, 4, 1e-12);
    thx_image_plane_range(&img, 'x', &lo, &hi, &step);
    CHECK_NEAR(lo, -4, 1e-12);
    CHECK_NEAR(hi, 4, 1e-12);
    thx_image_plane_spec z2 = {'z', 18};
    CHECK_OK(ctx, thx_image_sample_plane(ctx, &img, &z2, 0, &sl));
    CHECK(sl.w == 4 && sl.h == 3);
    diff = 0;
    for (size_t j = 0; j < 3; j++)
        for (size_t i = 0; i < 4; i++) diff += sl.v[i + 4 * j] != img.v[thx_image_at(&img, i, j, 2)];
    CHECK(diff == 0);
    CHECK_NEAR(sl.origin[0], -3, 1e-12);
    CHECK_NEAR(sl.du[0], 2, 1e-12);
    CHECK_NEAR(sl.dv[1], 2.5, 1e-12);
    thx_image_slice_free(&sl);
    /* halfway between planes k = 2 and 3: their mean (trilinear) */
    thx_image_plane_spec zh = {'z', 20};
    CHECK_OK(ctx, thx_image_sample_plane(ctx, &img, &zh, 0, &sl));
    diff = 0;
    for (size_t q = 0; q < 12; q++)
        diff += fabs(sl.v[q] - 0.5 * (img.v[thx_image_at(&img, q % 4, q / 4, 2)] + img.v[thx_image_at(&img, q % 4, q / 4, 3)])) > 1e-6;
    CHECK(diff == 0);
    thx_image_slice_free(&sl);

    /* default windows: a label map (few integers >= 0): its full range */
    double w, l;
    CHECK(thx_image_window_default(&img, &w, &l) == THX_WINDOW_LABELS);
    CHECK_NEAR(w, 10, 1e-12);
    CHECK_NEAR(l, 5, 1e-12);
    /* Hounsfield units: -1000 .. 1200 -> 400 / 40 */
    for (size_t q = 0; q < 60; q++) img.v[q] = q < 20 ? -1000.0f : q < 40 ? 40.0f : 1200.0f;
    CHECK(thx_image_window_default(&img, &w, &l) == THX_WINDOW_CT && w == 400 && l == 40);
    /* otherwise the 1st to 99th percentile: 1001 voxels 0..1000 (shuffled) -> 10 .. 990 */
    thx_image_free(&img);
    size_t p3[3] = {1001, 1, 1};
    CHECK_OK(ctx, thx_image_alloc(ctx, p3, &img));
    for (size_t q = 0; q < 1001; q++) img.v[q] = (float)((q * 389) % 1001) * 0.5f + 0.25f;
    CHECK(thx_image_window_default(&img, &w, &l) == THX_WINDOW_PERCENTILE);
    CHECK_NEAR(w, 0.5 * (990 - 10), 1e-9);
    CHECK_NEAR(l, 0.5 * (0.5 * (990 + 10)) + 0.25, 1e-9);
    /* a constant image: a window of 1 about its value */
    for (size_t q = 0; q < 1001; q++) img.v[q] = 7.5f;
    thx_image_window_default(&img, &w, &l);
    CHECK(w == 1 && l == 7.5);
    thx_image_free(&img);

    thx_ctx_destroy(&ctx);
    return tl_finish();
}
