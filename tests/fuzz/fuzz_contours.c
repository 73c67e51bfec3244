/*
 * Fuzz harness: contour files (thx_contours_parse, thx_contours_parse_raw, thx_contours_repair,
 * thx_contours_write). Properties of an accepted input:
 *  - what the strict reader accepts, the raw reader accepts with the same counts;
 *  - counts within what the bytes can hold: a point takes at least 4 bytes ("0 0\n"), a loop
 *    header 7 ("loop a\n"), a surface line 13; every loop has >= 3 points, finite coordinates;
 *  - the repair either refuses or leaves contours that pass thx_contours_validate, with no
 *    more points than it was given;
 *  - written and read back (strict), the repaired contours keep their counts, frame and image line.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/model/contours.h"
#include "thorax/io/contours_file.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/check/contours.h"
#include "thorax/geom/repair.h"
static size_t count_points(const thx_contours *c, size_t *loops)
{
    size_t n = 0;
    *loops = 0;
    for (size_t s = 0; s < c->n_surfaces; s++)
        for (size_t l = 0; l < c->surf[s].n_layers; l++)
            for (size_t i = 0; i < c->surf[s].layers[l].n_loops; i++) {
                const thx_loop *lp = &c->surf[s].layers[l].loops[i];
                FUZZ_ASSERT(lp->n >= 3);
                for (size_t k = 0; k < lp->n; k++) FUZZ_ASSERT(isfinite(lp->p[k].x) && isfinite(lp->p[k].y));
                n += lp->n;
                (*loops)++;
            }
    return n;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    thx_ctx *ctx = fuzz_ctx();
    thx_contours *strict = NULL, *raw = NULL;
    int ok_strict = thx_contours_parse(ctx, "f.txt", (const char *)data, size, &strict) == THX_OK;
    int ok_raw = thx_contours_parse_raw(ctx, "f.txt", (const char *)data, size, &raw) == THX_OK;
    FUZZ_ASSERT(!ok_strict || ok_raw);
    FUZZ_ASSERT(ok_strict == (strict != NULL) && ok_raw == (raw != NULL));
    if (ok_raw) {
        size_t loops = 0, pts = count_points(raw, &loops);
        FUZZ_ASSERT(4 * pts + 7 * loops + 13 * raw->n_surfaces <= size + 1);
        if (ok_strict) {
            size_t l2 = 0;
            FUZZ_ASSERT(count_points(strict, &l2) == pts && l2 == loops);
        }
        thx_repair_opts o;
        thx_repair_opts_default(&o, raw->spacing > 0 ? raw->spacing : 5.0);
        thx_repair_log log = {0};
        if (thx_contours_repair(ctx, raw, &o, &log) == THX_OK) {
            size_t l3 = 0, p3 = count_points(raw, &l3);
            FUZZ_ASSERT(p3 <= pts && l3 <= loops);
            FUZZ_ASSERT(thx_contours_validate(ctx, raw) == THX_OK);
            char path[512];
            snprintf(path, sizeof path, "%s/w.txt", fuzz_dir());
            FUZZ_ASSERT(thx_contours_write(ctx, raw, path, "fuzz") == THX_OK);
            thx_contours *back = NULL;
            /* %.6f in the writer may join points closer than a micrometre: then the strict reader
               refuses a repeat, which is fine; what it accepts keeps the counts and the frame */
            if (thx_contours_read(ctx, path, &back) == THX_OK) {
                size_t l4 = 0;
                count_points(back, &l4);
                FUZZ_ASSERT(l4 == l3 && back->n_surfaces == raw->n_surfaces);
                FUZZ_ASSERT(back->frame.set == raw->frame.set);
                /* the image line (issue 25): path and SHA-256 back as read (the path escaped and decoded) */
                FUZZ_ASSERT(strcmp(back->image, raw->image) == 0 && strcmp(back->image_sha256, raw->image_sha256) == 0);
                if (raw->frame.set)
                    FUZZ_ASSERT(back->frame.up.axis == raw->frame.up.axis && back->frame.up.sign == raw->frame.up.sign &&
                                back->frame.front.axis == raw->frame.front.axis);
            }
            thx_contours_destroy(&back);
        }
        thx_repair_log_free(&log);
    }
    thx_contours_destroy(&strict);
    thx_contours_destroy(&raw);
    thx_ctx_destroy(&ctx);
    return 0;
}
