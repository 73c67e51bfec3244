/* The image module's core and its NIfTI reader/writer: round trips (plain and gzip, every voxel type,
 * an oblique and a left-handed grid), geometry (index <-> RAS, the superior axis), the writer's refusal
 * of values its type cannot hold and of files it did not write, and the validation of bad images. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/image/image.h"

static void fill(thx_image *img, int integral)
{
    size_t count = thx_image_count(img);
    for (size_t q = 0; q < count; q++) img->v[q] = integral ? (float)((q * 7) % 300) - 20 : 0.25f * (float)q - 3.5f;
    img->integral = integral;
}

static int same_image(const thx_image *a, const thx_image *b)
{
    for (int c = 0; c < 3; c++) {
        if (a->n[c] != b->n[c]) return 0;
        if (fabs(a->spacing[c] - b->spacing[c]) > 1e-5 * a->spacing[c]) return 0;
        if (fabs(a->origin[c] - b->origin[c]) > 1e-4) return 0;
    }
    for (int k = 0; k < 9; k++)
        if (fabs(a->dir[k] - b->dir[k]) > 1e-5) return 0;
    size_t count = thx_image_count(a);
    for (size_t q = 0; q < count; q++)
        if (a->v[q] != b->v[q]) return 0;
    return 1;
}

int main(void)
{
    if (tl_scratch_make("test_image_nifti") != 0) return 1;
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);

    /* an oblique grid: rotation by 30 degrees about x, spacing 0.8 x 1.1 x 2.5, odd sizes */
    size_t n[3] = {7, 5, 4};
    thx_image img;
    CHECK_OK(ctx, thx_image_alloc(ctx, n, &img));
    double c30 = cos(M_PI / 6), s30 = sin(M_PI / 6);
    double rot[9] = {1, 0, 0, 0, c30, -s30, 0, s30, c30};
    memcpy(img.dir, rot, sizeof rot);
    img.spacing[0] = 0.8, img.spacing[1] = 1.1, img.spacing[2] = 2.5;
    img.origin[0] = -12.5, img.origin[1] = 30, img.origin[2] = 101.25;
    fill(&img, 1);

    /* index <-> RAS are inverse, and the superior axis of this grid is k (cos 30 with +z) */
    double ijk[3] = {2.5, 1, 3}, ras[3], back[3];
    thx_image_index_to_ras(&img, ijk, ras);
    CHECK_NEAR(ras[0], -12.5 + 2.5 * 0.8, 1e-12);
    CHECK_NEAR(ras[2], 101.25 + s30 * 1.1 + c30 * 3 * 2.5, 1e-12);
    thx_image_ras_to_index(&img, ras, back);
    for (int c = 0; c < 3; c++) CHECK_NEAR(back[c], ijk[c], 1e-12);
    int sa, ss, aa, as;
    double cosine;
    thx_image_axes(&img, &sa, &ss, &aa, &as, &cosine);
    CHECK(sa == 2 && ss == 1 && aa == 1 && as == 1);
    CHECK_NEAR(cosine, c30, 1e-12);
    CHECK(!thx_image_axis_aligned(&img));

    /* every type, plain and gzip: the same voxels and geometry back */
    const char *types[] = {"int16", "int32", "float32"};
    for (int t = 0; t < 3; t++)
        for (int gz = 0; gz < 2; gz++) {
            char name[64];
            snprintf(name, sizeof name, "rt_%s.nii%s", types[t], gz ? ".gz" : "");
            const char *p = tl_path(name);
            CHECK_OK(ctx, thx_image_write(ctx, &img, p, types[t]));
            thx_image in;
            CHECK_OK(ctx, thx_image_read(ctx, p, NULL, &in));
            CHECK(same_image(&img, &in));
            CHECK(strcmp(in.format, "nifti1") == 0);
            CHECK(strcmp(in.stored_type, types[t]) == 0);
            CHECK(in.integral == (t < 2));
            CHECK(strlen(in.sha256) == 64);
            CHECK(strstr(in.source_frame, "sform") != NULL);
            /* written again over itself (its own output): allowed */
            CHECK_OK(ctx, thx_image_write(ctx, &img, p, types[t]));
            thx_image_free(&in);
        }

    /* the type chosen from the range: -20..279 needs int16 */
    const char *pa = tl_path("auto.nii.gz");
    CHECK_OK(ctx, thx_image_write(ctx, &img, pa, NULL));
    thx_image in;
    CHECK_OK(ctx, thx_image_read(ctx, pa, NULL, &in));
    CHECK(strcmp(in.stored_type, "int16") == 0);
    thx_image_free(&in);

    /* a value the type cannot hold is refused, naming the voxel; nothing written */
    CHECK(thx_image_write(ctx, &img, tl_path("bad.nii"), "uint8") == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "cannot be stored exactly as uint8"));
    CHECK(!tl_exists(tl_path("bad.nii")));
    fill(&img, 0);
    CHECK(thx_image_write(ctx, &img, tl_path("bad2.nii"), "int16") == THX_EINPUT);
    CHECK(!tl_exists(tl_path("bad2.nii")));

    /* a left-handed grid (i reversed) and float values */
    img.dir[0] = -1;
    const char *pl = tl_path("left.nii");
    CHECK_OK(ctx, thx_image_write(ctx, &img, pl, NULL));
    CHECK_OK(ctx, thx_image_read(ctx, pl, NULL, &in));
    CHECK(same_image(&img, &in));
    CHECK(!in.integral);
    thx_image_free(&in);

    /* a file thorax did not write is not replaced */
    const char *foreign = tl_path("foreign.nii");
    tl_write_text(foreign, "someone else's data\n");
    CHECK(thx_image_write(ctx, &img, foreign, NULL) == THX_EIO);
    char *kept = tl_slurp(ctx, foreign, NULL);
    CHECK(kept && strcmp(kept, "someone else's data\n") == 0);
    free(kept);

    /* bad images: truncated, not NIfTI, NaN, zero spacing, skewed directions */
    size_t len = 0;
    char *whole = tl_slurp(ctx, pl, &len);
    tl_write_bytes(tl_path("trunc.nii"), whole, len - 10);
    CHECK(thx_image_read(ctx, tl_path("trunc.nii"), NULL, &in) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "truncated"));
    CHECK(in.v == NULL);
    tl_write_bytes(tl_path("junk.nii"), whole + 352, 400);
    CHECK(thx_image_read(ctx, tl_path("junk.nii"), NULL, &in) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "not a NIfTI"));
    free(whole);

    img.v[17] = NAN;
    CHECK(thx_image_validate(ctx, &img, "x.nii") == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "voxel (3, 2, 0) is NaN"));
    CHECK(thx_image_write(ctx, &img, tl_path("nan.nii"), NULL) == THX_EINPUT);
    img.v[17] = 0;
    img.spacing[1] = 0;
    CHECK(thx_image_validate(ctx, &img, "x.nii") == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "spacing along axis 2 is 0"));
    img.spacing[1] = 1.1;
    img.dir[1] = 0.3; /* column 2 tilted toward x: not orthogonal to column 1 */
    CHECK(thx_image_validate(ctx, &img, "x.nii") == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "not orthonormal"));
    CHECK(!tl_leftover_tmp(""));

    thx_image_free(&img);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_image_nifti");
}
