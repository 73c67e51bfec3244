/*
 * Fuzz harness: camera key files (thx_camera_keys_read, thx_camera_keys_resolve,
 * thx_camera_path_create; docs/formats.md, "Camera key files"). Properties of an accepted input:
 *  - at least two keys, within what the bytes can hold (the shortest key line, "1 eye 0,0,0" or
 *    "1 view left", takes 11 bytes less the last line's newline);
 *  - frames from 1 up, strictly increasing; line numbers in the file, increasing; data frames 0
 *    (not given) or positive; an eye or a named view per key, every number given finite;
 *  - resolved against six standard views of a 100 mm box: every camera finite; and when the path
 *    is built, the camera at every key's frame is that key's (to 1e-6 of the scene), finite
 *    between them, and the data frames in range.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/render/camera_path.h"

static int finite3(const double *v) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

static void check_camera(const thx_camera *c)
{
    FUZZ_ASSERT(finite3(c->eye) && finite3(c->center) && finite3(c->up));
    FUZZ_ASSERT(isfinite(c->fov_deg) && isfinite(c->height));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file("in.keys", data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_camera_keys k;
    if (thx_camera_keys_read(ctx, path, &k) == THX_OK) {
        size_t lines = 1;
        for (size_t i = 0; i < size; i++) lines += data[i] == '\n';
        FUZZ_ASSERT(k.n >= 2 && 11 * k.n <= size + 1);
        for (size_t i = 0; i < k.n; i++) {
            const thx_camera_key *e = &k.keys[i];
            FUZZ_ASSERT(e->frame >= 1 && (i == 0 || e->frame > k.keys[i - 1].frame));
            FUZZ_ASSERT(e->line >= 1 && (size_t)e->line <= lines && (i == 0 || e->line > k.keys[i - 1].line));
            FUZZ_ASSERT(e->data_frame >= 0);
            FUZZ_ASSERT((e->view >= 0 && e->view < 6) || (e->view == -1 && (e->given & THX_KEY_EYE)));
            if (e->given & THX_KEY_EYE) FUZZ_ASSERT(finite3(e->cam.eye));
            if (e->given & THX_KEY_TARGET) FUZZ_ASSERT(finite3(e->cam.center));
            if (e->given & THX_KEY_UP) FUZZ_ASSERT(finite3(e->cam.up));
            if (e->given & THX_KEY_FOV) FUZZ_ASSERT(isfinite(e->cam.fov_deg));
            if (e->given & THX_KEY_HEIGHT) FUZZ_ASSERT(isfinite(e->cam.height));
            if (e->given & THX_KEY_DISTANCE) FUZZ_ASSERT(isfinite(e->distance) && e->distance > 0);
        }
        thx_camera views[6];
        const double lo[3] = {0, 0, 0}, hi[3] = {100, 100, 100};
        for (int v = 0; v < 6; v++) thx_camera_view(&views[v], (thx_view)v, lo, hi, 1.0);
        thx_camera_path *p = NULL;
        if (thx_camera_keys_resolve(ctx, &k, views) == THX_OK) {
            for (size_t i = 0; i < k.n; i++) check_camera(&k.keys[i].cam);
            if (thx_camera_path_create(ctx, &k, &p) == THX_OK) {
                FUZZ_ASSERT(thx_camera_path_first(p) == k.keys[0].frame && thx_camera_path_last(p) == k.keys[k.n - 1].frame);
                int max_data = 0;
                for (size_t i = 0; i < k.n; i++) max_data = k.keys[i].data_frame > max_data ? k.keys[i].data_frame : max_data;
                for (size_t i = 0; i < k.n; i++) {
                    thx_camera c;
                    thx_camera_path_camera(p, k.keys[i].frame, &c);
                    check_camera(&c);
                    double scale = 1;
                    for (int a = 0; a < 3; a++) scale = fmax(scale, fabs(k.keys[i].cam.eye[a]));
                    for (int a = 0; a < 3; a++) FUZZ_ASSERT(fabs(c.eye[a] - k.keys[i].cam.eye[a]) <= 1e-6 * scale);
                    if (i + 1 < k.n) { /* a point between this key and the next */
                        thx_camera_path_camera(p, 0.5 * (k.keys[i].frame + k.keys[i + 1].frame), &c);
                        check_camera(&c);
                    }
                    int df = thx_camera_path_data_frame(p, k.keys[i].frame);
                    FUZZ_ASSERT(df >= 0 && df <= max_data);
                }
                thx_camera_path_destroy(&p);
            }
        }
        thx_camera_keys_free(&k);
    }
    thx_ctx_destroy(&ctx);
    return 0;
}
