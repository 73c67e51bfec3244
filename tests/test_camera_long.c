/* A long smooth camera flight (issue 24): 10,000 keys on a slow helix round the z axis are a
 * path (the orientation solve's convergence is judged per key, in radians, not by the 2-norm of
 * 30,000 residuals, which grows with the number of keys), and every key is reached at its frame. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/render/camera_path.h"

#define N_KEYS 10000

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    size_t cap = (size_t)N_KEYS * 160, len = 0;
    char *text = malloc(cap);
    CHECK(text != NULL);
    if (!text) return tl_finish();
    /* 0.25 degrees a key round the axis, rising 0.05 mm a key, radius 600 mm, a slow roll and a
       breathing field of view: refused before (residual 2e-12 rad, the 2-norm over every key) */
    for (int f = 1; f <= N_KEYS; f++) {
        double a = 0.25 * (f - 1) * M_PI / 180;
        len += (size_t)snprintf(text + len, cap - len, "%d eye %.17g,%.17g,%.17g target 0,0,%.17g up %.17g,0,1 fov %.17g\n",
                                f, 600 * sin(a), -600 * cos(a), 0.05 * (f - 1), 0.05 * (f - 1), 0.3 * sin(0.37 * a),
                                30 + 5 * sin(0.2 * a));
    }
    thx_camera_keys k;
    thx_camera_path *p = NULL;
    thx_status st = thx_camera_keys_parse(ctx, "long.keys", text, &k);
    CHECK(st == THX_OK);
    if (st == THX_OK) st = thx_camera_keys_resolve(ctx, &k, NULL);
    CHECK(st == THX_OK);
    if (st == THX_OK) {
        st = thx_camera_path_create(ctx, &k, &p);
        if (st != THX_OK) fprintf(stderr, "refused: %s\n", thx_ctx_message(ctx));
        CHECK(st == THX_OK);
    }
    if (p) {
        double worst = 0;
        for (size_t i = 0; i < k.n; i += 97) {
            thx_camera c;
            thx_camera_path_camera(p, k.keys[i].frame, &c);
            for (int e = 0; e < 3; e++) worst = fmax(worst, fabs(c.eye[e] - k.keys[i].cam.eye[e]));
        }
        printf("%zu keys: a path; largest eye error at the keys %.3g mm\n", k.n, worst);
        CHECK(worst < 1e-9);
    }
    thx_camera_path_destroy(&p);
    thx_camera_keys_free(&k);
    free(text);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
