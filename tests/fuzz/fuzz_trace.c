/*
 * Fuzz harness: label-map tracing (thx_image_trace, thorax/image/trace.h). The bytes are a small
 * label map: byte 0-2 its size (1..16 per axis), byte 3 the options (plane spacing: every plane or
 * 1.5 voxels; holes filled or kept; min_size 0 or 3; a mirrored or oblique direction), then one
 * label per voxel (the byte mod 4; missing bytes are 0). Tissues: every non-zero value as "outer",
 * 1 and 2 as "lungs", 3 as "heart". Properties: the trace either succeeds or refuses with
 * THX_EINPUT (never another status, never a crash); what it returns passes thx_contours_validate
 * (no loop crossing itself, consecutive layers), every loop has >= 3 finite points, and the traced
 * layers lie within the image's planes.
 */
#include <math.h>

#include "fuzz.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/image/trace.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 4) return 0;
    thx_ctx *ctx = fuzz_ctx();
    size_t n[3] = {1 + data[0] % 16, 1 + data[1] % 16, 1 + data[2] % 16};
    uint8_t opt = data[3];
    thx_image img;
    FUZZ_ASSERT(thx_image_alloc(ctx, n, &img) == THX_OK);
    img.integral = 1;
    size_t count = thx_image_count(&img);
    for (size_t q = 0; q < count; q++) img.v[q] = 4 + q < size ? (float)(data[4 + q] % 4) : 0.0f;
    img.spacing[0] = 1.0 + (opt >> 5 & 1);
    if (opt & 4) { /* i -> -y, j -> -x, k -> -z */
        double d[9] = {0, -1, 0, -1, 0, 0, 0, 0, -1};
        memcpy(img.dir, d, sizeof d);
    } else if (opt & 8) { /* 30 degrees about x */
        double c = cos(M_PI / 6), s = sin(M_PI / 6), d[9] = {1, 0, 0, 0, c, -s, 0, s, c};
        memcpy(img.dir, d, sizeof d);
    }
    long v12[2] = {1, 2}, v3 = 3;
    thx_trace_tissue t[3] = {{NULL, 0, 1, "torso", THX_ROLE_OUTER},
                             {v12, 2, 0, "lungs", THX_ROLE_LUNG},
                             {&v3, 1, 0, "heart", THX_ROLE_HEART}};
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = t;
    o.n_tissues = 1 + (opt >> 6);
    if (o.n_tissues > 3) o.n_tissues = 3;
    o.spacing = (opt & 1) ? 1.5 : 0;
    o.holes = (opt & 2) ? THX_TRACE_HOLES_KEEP : THX_TRACE_HOLES_FILL;
    o.min_size = (opt & 16) ? 3 : 0;
    thx_contours *c = NULL;
    thx_trace_report rep;
    thx_status st = thx_image_trace(ctx, &img, &o, &c, &rep);
    FUZZ_ASSERT(st == THX_OK || st == THX_EINPUT);
    FUZZ_ASSERT((st == THX_OK) == (c != NULL));
    if (c) {
        FUZZ_ASSERT(thx_contours_validate(ctx, c) == THX_OK);
        FUZZ_ASSERT(c->n_surfaces >= o.n_tissues && c->n_surfaces == rep.n_tissues); /* organs split by component */
        for (size_t s = 0; s < c->n_surfaces; s++) {
            const thx_contour_surface *cs = &c->surf[s];
            FUZZ_ASSERT(cs->n_layers >= 2);
            for (size_t l = 0; l < cs->n_layers; l++) {
                double z = cs->layers[l].z;
                FUZZ_ASSERT(z >= rep.z_first - 1e-9 && z <= rep.z_first + rep.plane_spacing * (double)(rep.n_planes - 1) + 1e-9);
                for (size_t k = 0; k < cs->layers[l].n_loops; k++) {
                    const thx_loop *lp = &cs->layers[l].loops[k];
                    FUZZ_ASSERT(lp->n >= 3);
                    for (size_t i = 0; i < lp->n; i++) FUZZ_ASSERT(isfinite(lp->p[i].x) && isfinite(lp->p[i].y));
                }
            }
        }
        thx_trace_report_free(&rep);
    }
    thx_contours_destroy(&c);
    thx_image_free(&img);
    thx_ctx_destroy(&ctx);
    return 0;
}
