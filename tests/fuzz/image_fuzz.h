/*
 * Shared property checks of the image fuzz harnesses (fuzz_image_nrrd.c, fuzz_image_metaimage.c,
 * fuzz_image_nifti.c): the bytes are written as one file named with the reader's extension and read
 * by thx_image_read. An accepted image must hold what a file of that size can hold (a deflate stream
 * inflates at most about 1032:1; a raw or text voxel takes at least one byte), pass the image
 * invariants (thx_image_validate: finite values, spacing > 0, orthonormal directions), and come back
 * the same through thorax's own writer and reader (`out`: .nrrd, .mha or .nii) when small.
 */
#ifndef THORAX_TESTS_IMAGE_FUZZ_H
#define THORAX_TESTS_IMAGE_FUZZ_H

#include <math.h>

#include "fuzz.h"
#include "thorax/image/image.h"

static inline void image_fuzz_one(const uint8_t *data, size_t size, const char *name, const char *out)
{
    thx_ctx *ctx = fuzz_ctx();
    const char *path = fuzz_file(name, data, size);
    thx_image img;
    if (thx_image_read(ctx, path, NULL, &img) == THX_OK) {
        size_t count = thx_image_count(&img);
        FUZZ_ASSERT(img.v != NULL);
        FUZZ_ASSERT((double)count <= 1100.0 * (double)size + 4096.0);
        FUZZ_ASSERT(thx_image_validate(ctx, &img, "fuzz") == THX_OK);
        FUZZ_ASSERT(strlen(img.sha256) == 64 && img.format[0] && img.stored_type[0]);
        if (count <= 4096) {
            char dst[1100];
            snprintf(dst, sizeof dst, "%s/back%s", fuzz_dir(), out);
            /* float32 holds every value read exactly; thorax's own file is replaced each time */
            if (thx_image_write(ctx, &img, dst, "float32") == THX_OK) {
                thx_image back;
                FUZZ_ASSERT(thx_image_read(ctx, dst, NULL, &back) == THX_OK);
                for (int c = 0; c < 3; c++) {
                    FUZZ_ASSERT(back.n[c] == img.n[c]);
                    FUZZ_ASSERT(fabs(back.spacing[c] - img.spacing[c]) <= 1e-5 * img.spacing[c]);
                }
                for (size_t q = 0; q < count; q++) FUZZ_ASSERT(back.v[q] == img.v[q]);
                thx_image_free(&back);
            }
        }
        thx_image_free(&img);
    }
    thx_ctx_destroy(&ctx);
}

#endif
