/* Label maps from a scan (thorax/image/segment.h): the exact distance transform against brute force,
 * closing's reach, and a synthetic head CT (scalp, a skull shell round a brain, a sinus, a head holder,
 * speckle) segmented into skin and bone with the volumes of the analytic balls. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/image/segment.h"

/* distance of voxel q of the 64^3 test grid from its centre */
static double lab_ball_r(size_t q)
{
    double x = (double)(q % 64) - 31.5, y = (double)(q / 64 % 64) - 31.5, z = (double)(q / 4096) - 31.5;
    return sqrt(x * x + y * y + z * z);
}

static double frand(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return (double)((*s >> 8) & 0xffff) / 65536.0;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);

    /* 1. the distance transform is exact: brute force on a random sparse mask, anisotropic spacing */
    {
        size_t n[3] = {9, 7, 6};
        double sp[3] = {0.7, 1.3, 2.1};
        size_t count = n[0] * n[1] * n[2];
        unsigned char *m = calloc(count, 1);
        float *d = malloc(count * sizeof *d);
        unsigned seed = 7;
        for (size_t q = 0; q < count; q++) m[q] = frand(&seed) < 0.03;
        m[count / 2] = 1;
        CHECK_OK(ctx, thx_distance_squared(ctx, n, sp, m, d));
        double worst = 0;
        for (size_t q = 0; q < count; q++) {
            double best = INFINITY;
            for (size_t p = 0; p < count; p++) {
                if (!m[p]) continue;
                double dx = ((double)(q % 9) - (double)(p % 9)) * sp[0];
                double dy = ((double)(q / 9 % 7) - (double)(p / 9 % 7)) * sp[1];
                double dz = ((double)(q / 63) - (double)(p / 63)) * sp[2];
                double e = dx * dx + dy * dy + dz * dz;
                if (e < best) best = e;
            }
            double err = fabs(best - d[q]) / (1 + best);
            if (err > worst) worst = err;
        }
        CHECK(worst < 1e-6);
        memset(m, 0, count);
        CHECK_OK(ctx, thx_distance_squared(ctx, n, sp, m, d));
        CHECK(isinf(d[0]) && isinf(d[count - 1]));
        free(m), free(d);
    }

    /* 2. a synthetic head CT, 1 mm voxels */
    size_t n[3] = {64, 64, 64};
    thx_image ct;
    CHECK_OK(ctx, thx_image_alloc(ctx, n, &ct));
    unsigned seed = 11;
    const double c = 31.5;
    for (size_t k = 0; k < 64; k++)
        for (size_t j = 0; j < 64; j++)
            for (size_t i = 0; i < 64; i++) {
                double x = (double)i - c, y = (double)j - c, z = (double)k - c, r = sqrt(x * x + y * y + z * z);
                float v = -1000;                                  /* air */
                if (r <= 25) v = 40;                              /* scalp and brain */
                if (r <= 18 && r >= 14) v = 1200;                 /* skull shell */
                if (sqrt((x - 21) * (x - 21) + y * y + z * z) <= 2.5) v = -1000; /* a sinus in the scalp */
                if (fabs(sqrt(x * x + y * y) - 29.5) < 0.8 && z < -10) v = 800;  /* a head holder */
                if (r > 26 && frand(&seed) < 0.002) v = 500;      /* speckle */
                ct.v[thx_image_at(&ct, i, j, k)] = v;
            }
    thx_threshold tissues[2] = {{-400, 4000, 1, 0}, {226, 4000, 2, 0}};
    thx_segment_opts o = {tissues, 2, 1, 1};
    thx_image lab;
    thx_segment_report rep;
    CHECK_OK(ctx, thx_image_segment(ctx, &ct, &o, &lab, &rep));
    /* bone = the filled skull ball r <= 18; skin = the head ball r <= 25 minus the bone */
    double v_bone = 4.0 / 3.0 * M_PI * 18 * 18 * 18, v_head = 4.0 / 3.0 * M_PI * 25 * 25 * 25;
    CHECK(fabs((double)rep.voxels[1] - v_bone) < 0.02 * v_bone);
    CHECK(fabs((double)(rep.voxels[0] + rep.voxels[1]) - v_head) < 0.02 * v_head);
    CHECK(rep.dropped[0] > 0);   /* the holder and the speckle */
    CHECK(rep.filled[0] > 40);   /* the sinus (4/3 pi 2.5^3 = 65 voxels) joined the head */
    CHECK(rep.filled[1] > 0.9 * 4.0 / 3.0 * M_PI * 14 * 14 * 14); /* the brain inside the skull */
    CHECK(lab.v[thx_image_at(&lab, 32, 32, 32)] == 2);
    CHECK(lab.v[thx_image_at(&lab, 53, 32, 32)] == 1); /* the sinus's centre */
    CHECK(lab.v[thx_image_at(&lab, 61, 32, 5)] == 0);  /* on the holder */
    CHECK(lab.integral);
    /* the bone keeps a voxel of scalp round it: no bone voxel has an outside voxel among its 26 neighbours */
    size_t touching = 0; /* reused below */
    for (size_t k = 1; k + 1 < 64; k++)
        for (size_t j = 1; j + 1 < 64; j++)
            for (size_t i = 1; i + 1 < 64; i++) {
                if (lab.v[thx_image_at(&lab, i, j, k)] != 2) continue;
                for (int d = 0; d < 27; d++)
                    if (lab.v[thx_image_at(&lab, i + (size_t)(d % 3) - 1, j + (size_t)(d / 3 % 3) - 1,
                                           k + (size_t)(d / 9) - 1)] == 0)
                        touching++;
            }
    CHECK(touching == 0);
    thx_image_free(&lab);

    /* without the clean-up the holder stays and the brain is not bone */
    o.largest = 0, o.fill_planes = 0;
    CHECK_OK(ctx, thx_image_segment(ctx, &ct, &o, &lab, &rep));
    CHECK(lab.v[thx_image_at(&lab, 32, 32, 32)] == 1);
    CHECK(lab.v[thx_image_at(&lab, 53, 32, 32)] == 0);
    thx_image_free(&lab);

    /* bone out to the skin (no scalp in the scan): the map still keeps a voxel of label 1 round label 2 */
    for (size_t q = 0; q < thx_image_count(&ct); q++)
        if (ct.v[q] == 40 && lab_ball_r(q) >= 14) ct.v[q] = 1200;
    thx_segment_opts o2 = {tissues, 2, 1, 1};
    CHECK_OK(ctx, thx_image_segment(ctx, &ct, &o2, &lab, &rep));
    touching = 0;
    size_t scalp = 0;
    for (size_t k = 1; k + 1 < 64; k++)
        for (size_t j = 1; j + 1 < 64; j++)
            for (size_t i = 1; i + 1 < 64; i++) {
                float v = lab.v[thx_image_at(&lab, i, j, k)];
                scalp += v == 1;
                if (v != 2) continue;
                for (int d = 0; d < 27; d++)
                    if (lab.v[thx_image_at(&lab, i + (size_t)(d % 3) - 1, j + (size_t)(d / 3 % 3) - 1,
                                           k + (size_t)(d / 9) - 1)] == 0)
                        touching++;
            }
    CHECK(touching == 0 && scalp > 0);
    thx_image_free(&lab);

    /* 3. closing bridges a 1-voxel gap with a 1.5 mm ball, not a 5-voxel gap */
    for (int k = 0; k < 64; k++)
        for (int j = 0; j < 64; j++)
            for (int i = 0; i < 64; i++) {
                int in_a = i >= 10 && i < 30 && j >= 10 && j < 30 && k >= 10 && k < 30;
                int in_b = i >= 31 && i < 50 && j >= 10 && j < 30 && k >= 10 && k < 30;
                int in_c = i >= 10 && i < 50 && j >= 35 && j < 50 && k >= 10 && k < 30 && (i < 28 || i > 32);
                ct.v[thx_image_at(&ct, (size_t)i, (size_t)j, (size_t)k)] = (in_a || in_b || in_c) ? 100.0f : 0.0f;
            }
    thx_threshold one = {50, 200, 3, 1.5};
    thx_segment_opts oc = {&one, 1, 0, 0};
    CHECK_OK(ctx, thx_image_segment(ctx, &ct, &oc, &lab, NULL));
    CHECK(lab.v[thx_image_at(&lab, 30, 20, 20)] == 3);  /* bridged */
    CHECK(lab.v[thx_image_at(&lab, 30, 40, 20)] == 0);  /* not bridged */
    CHECK(lab.v[thx_image_at(&lab, 20, 20, 20)] == 3);  /* inside kept */
    CHECK(lab.v[thx_image_at(&lab, 20, 32, 20)] == 0);  /* the corridor between the bars stays open */
    thx_image_free(&lab);

    /* bad ranges */
    thx_threshold bad = {10, 5, 1, 0};
    thx_segment_opts ob = {&bad, 1, 0, 0};
    CHECK(thx_image_segment(ctx, &ct, &ob, &lab, NULL) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "is empty"));
    CHECK(lab.v == NULL);

    thx_image_free(&ct);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
