/* The livewire on the phantom's simulated MR (thorax/phantom/voxelize.h, as `thorax phantom --image OUT
 * --modality mr --voxel 2` makes it, here with Rician noise): 12 clicks on the torso's analytic outline
 * in an axial plane give a loop within 1 mm of that outline (issue 26 item 7), both ways round (every
 * loop point near the outline, every outline point near the loop). Also the threshold tool on a lung. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/digitizer/livewire.h"
#include "thorax/digitizer/region.h"
#include "thorax/digitizer/snap.h"
#include "thorax/geom/inside.h"
#include "thorax/image/sample.h"
#include "thorax/phantom/phantom.h"
#include "thorax/phantom/voxelize.h"

/* distances both ways between the loop xyz[0..n-1] (RAS, on z) and the outline pts[0..m-1] */
static void hausdorff(const double *xyz, size_t n, const thx_vec2 *pts, size_t m, double *to_outline, double *to_loop,
                      double *mean)
{
    thx_vec2 *l = malloc(n * sizeof *l);
    *to_outline = *to_loop = *mean = 0;
    for (size_t i = 0; i < n; i++) {
        l[i].x = xyz[3 * i];
        l[i].y = xyz[3 * i + 1];
        double d = thx_loop_distance(pts, m, l[i]);
        *to_outline = fmax(*to_outline, d);
        *mean += d / (double)n;
    }
    for (size_t i = 0; i < m; i++) *to_loop = fmax(*to_loop, thx_loop_distance(l, n, pts[i]));
    free(l);
}

int main(void)
{
    thx_ctx *ctx;
    thx_ctx_create(&ctx);
    thx_phantom_field *fld = NULL;
    CHECK_OK(ctx, thx_phantom_field_create(ctx, &fld));
    const double z0 = 135, z1 = 171, DZ = 10; /* voxel centres of the 2 mm grid (faces on even millimetres) */
    double lo[3], hi[3];
    thx_phantom_bounds(fld, lo, hi);
    lo[2] = z0 - 3;
    hi[2] = z1 + 3;
    if (hi[2] < z0 + DZ + 3) hi[2] = z0 + DZ + 3;
    thx_image lab, mix;
    memset(&mix, 0, sizeof mix);
    CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 2.0, 2, &lab));
    CHECK_OK(ctx, thx_image_alloc(ctx, lab.n, &mix));
    memcpy(mix.spacing, lab.spacing, sizeof mix.spacing);
    memcpy(mix.origin, lab.origin, sizeof mix.origin);
    memcpy(mix.dir, lab.dir, sizeof mix.dir);
    static const thx_role ROLE[] = {THX_ROLE_OUTER, THX_ROLE_FAT, THX_ROLE_MUSCLE, THX_ROLE_LUNG, THX_ROLE_LUNG,
                                    THX_ROLE_HEART};
    double values[7];
    values[0] = thx_tissue_value(THX_MODALITY_MR, THX_TISSUE_AIR);
    for (int r = 1; r < 7; r++) values[r] = thx_tissue_value(THX_MODALITY_MR, thx_tissue_of_role(ROLE[r - 1], 1));
    thx_voxelize_opts vo;
    thx_voxelize_opts_default(&vo);
    vo.values = values;
    CHECK_OK(ctx, thx_phantom_voxelize(ctx, &vo, &lab, &mix, NULL));
    CHECK_OK(ctx, thx_scan_degrade(ctx, &mix, THX_MODALITY_MR, 0.1, 20.0, THX_NOISE_RICIAN, 7));

    for (int pl = 0; pl < 2; pl++) {
        double z = pl ? z1 : z0;
        thx_image_plane_spec spec = {'z', z};
        thx_image_slice s;
        CHECK_OK(ctx, thx_image_sample_plane(ctx, &mix, &spec, 0, &s));
        thx_vec2 *pts = NULL;
        size_t m = 0;
        CHECK_OK(ctx, thx_phantom_section(ctx, fld, 0, z, &pts, &m));
        CHECK(m >= 12);
        /* 12 clicks on the outline, evenly by index */
        double clicks[36];
        for (int k = 0; k < 12; k++) {
            clicks[3 * k] = pts[k * m / 12].x;
            clicks[3 * k + 1] = pts[k * m / 12].y;
            clicks[3 * k + 2] = z;
        }
        thx_livewire *lw = NULL;
        double *xyz = NULL, d1, d2, dm;
        size_t n = 0;
        CHECK_OK(ctx, thx_livewire_create(ctx, &s, NULL, &lw));
        CHECK_OK(ctx, thx_livewire_loop(ctx, lw, clicks, 12, &xyz, &n));
        hausdorff(xyz, n, pts, m, &d1, &d2, &dm);
        printf("phantom MR (2 mm voxels, Rician noise 20), z = %g: livewire loop of %zu points through 12 clicks: "
               "loop -> outline max %.3f mean %.3f mm, outline -> loop max %.3f mm\n", z, n, d1, dm, d2);
        CHECK(d1 <= 1.0);
        CHECK(d2 <= 1.0);
        /* copy the loop to the plane 2 mm up and snap it there (issue 26 item 7: within 1.5 mm) */
        if (pl == 0) {
            thx_image_plane_spec s2 = {'z', z + DZ};
            thx_image_slice t;
            CHECK_OK(ctx, thx_image_sample_plane(ctx, &mix, &s2, 0, &t));
            double *sn = malloc(3 * n * sizeof *sn);
            CHECK_OK(ctx, thx_snap_loop(ctx, &t, NULL, xyz, n, sn));
            thx_vec2 *p2 = NULL;
            size_t m2 = 0;
            CHECK_OK(ctx, thx_phantom_section(ctx, fld, 0, z + DZ, &p2, &m2));
            double b1, b2, bm;
            hausdorff(xyz, n, p2, m2, &b1, &b2, &bm);
            hausdorff(sn, n, p2, m2, &d1, &d2, &dm);
            printf("  before the snap: loop -> outline max %.3f mean %.3f mm\n", b1, bm);
            printf("  copied to z = %g and snapped: loop -> outline max %.3f mean %.3f mm, outline -> loop max %.3f mm\n",
                   z + DZ, d1, dm, d2);
            CHECK(d1 <= 1.0 && d1 < b1);
            CHECK(d2 <= 1.0);
            free(sn);
            free(p2);
            thx_image_slice_free(&t);
        }
        free(xyz);
        thx_livewire_destroy(&lw);
        /* the threshold tool on each lung: MR lung 40, its neighbours 300 (soft tissue) and up; the window
         * [-1000, 170] (its bound halfway), the seed at the outline's centroid */
        for (int lung = 3; lung <= 4; lung++) {
            thx_vec2 *lp = NULL;
            size_t lm = 0;
            CHECK_OK(ctx, thx_phantom_section(ctx, fld, lung, z, &lp, &lm));
            if (lm == 0) continue;
            double seed[3] = {0, 0, z};
            for (size_t i = 0; i < lm; i++) {
                seed[0] += lp[i].x / (double)lm;
                seed[1] += lp[i].y / (double)lm;
            }
            thx_region_info info;
            CHECK_OK(ctx, thx_region_loop(ctx, &s, -1000, 170, seed, 1, &xyz, &n, &info));
            hausdorff(xyz, n, lp, lm, &d1, &d2, &dm);
            printf("  threshold [-1000, 170] + seed in lung %d: %zu pixels, loop -> outline max %.3f mean %.3f mm, "
                   "outline -> loop max %.3f mm\n", lung - 2, info.n_pixels, d1, dm, d2);
            CHECK(d1 <= 2.0); /* within a voxel */
            CHECK(d2 <= 2.0);
            free(xyz);
            free(lp);
        }
        free(pts);
        thx_image_slice_free(&s);
    }
    thx_image_free(&lab);
    thx_image_free(&mix);
    thx_phantom_field_destroy(&fld);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
