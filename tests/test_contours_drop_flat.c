/* thx_contours_drop_flat (thorax/geom/surfaces.h): the loops the lacing would find with no partner once
 * resampled, dropped to a fixed point, as traced label maps need; the surface then builds where it
 * failed before. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/geom/surfaces.h"
#include "thorax/model/contours.h"
#include "thorax/model/model.h"

static thx_ctx *ctx;

static void ring(thx_contours *c, size_t s, double z, double cx, double cy, double r, int n)
{
    thx_vec2 p[64];
    for (int k = 0; k < n; k++) p[k] = (thx_vec2){cx + r * cos(2 * M_PI * k / n), cy + r * sin(2 * M_PI * k / n)};
    if (thx_contours_add_loop(ctx, c, s, z, p, (size_t)n) != THX_OK) {
        fprintf(stderr, "ring: %s\n", thx_ctx_message(ctx));
        exit(1);
    }
}

int main(void)
{
    thx_ctx_create(&ctx);
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    o.spacing = 2.0;

    /* a cylinder on five layers, a stray loop beside it on layer 2 only, and a small blob on layers 3 and 4
       far from the rest: the stray goes, the blob (two overlapping loops) stays */
    thx_contours *c = NULL;
    size_t s;
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    c->spacing = 2.0;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "body", THX_ROLE_OTHER, THX_CAP_POLYGON, 0, &s));
    for (int l = 0; l < 5; l++) { /* layers in increasing z */
        ring(c, s, 2.0 * l, 0, 0, 20, 40);
        if (l == 2) ring(c, s, 4.0, 60, 0, 6, 16);
        if (l == 3) ring(c, s, 6.0, -60, 0, 6, 16);
        if (l == 4) ring(c, s, 8.0, -61, 1, 6, 16);
    }
    thx_model *m = NULL;
    CHECK(thx_surfaces_build(ctx, c, &o, &m, NULL, NULL) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "overlaps no loop of the layers above and below"));
    size_t gone = 99;
    CHECK_OK(ctx, thx_contours_drop_flat(ctx, c, &o, &gone));
    CHECK(gone == 1);
    CHECK(c->surf[0].n_layers == 5 && c->surf[0].layers[2].n_loops == 1 && c->surf[0].layers[3].n_loops == 2);
    CHECK_OK(ctx, thx_surfaces_build(ctx, c, &o, &m, NULL, NULL));
    thx_model_destroy(&m);
    /* nothing more to drop: a second pass is the identity */
    CHECK_OK(ctx, thx_contours_drop_flat(ctx, c, &o, &gone));
    CHECK(gone == 0);
    thx_contours_destroy(&c);

    /* the end layers' loops with no partner go with their layers; a layer left empty inside is refused */
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    c->spacing = 2.0;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "tube", THX_ROLE_OTHER, THX_CAP_POLYGON, 0, &s));
    ring(c, s, 0, 100, 100, 6, 16);   /* far from the layer above's loops */
    ring(c, s, 2, 0, 0, 20, 40);
    ring(c, s, 2, 100, -100, 6, 16);  /* a second loop, so the single-loop pairing rule does not apply */
    ring(c, s, 4, 0, 0, 20, 40);
    ring(c, s, 6, 0, 0, 20, 40);
    CHECK_OK(ctx, thx_contours_drop_flat(ctx, c, &o, &gone));
    CHECK(gone == 2 && c->surf[0].n_layers == 3 && c->surf[0].layers[0].z == 2);
    CHECK_OK(ctx, thx_surfaces_build(ctx, c, &o, &m, NULL, NULL));
    thx_model_destroy(&m);
    thx_contours_destroy(&c);

    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    c->spacing = 2.0;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "broken", THX_ROLE_OTHER, THX_CAP_POLYGON, 0, &s));
    for (int l = 0; l < 5; l++) { /* two tubes, their middle layer replaced by two specks far away */
        ring(c, s, 2.0 * l, l == 2 ? 200 : 0, l == 2 ? 200 : 0, l == 2 ? 3 : 20, l == 2 ? 12 : 40);
        ring(c, s, 2.0 * l, l == 2 ? 300 : 100, l == 2 ? 300 : 0, l == 2 ? 3 : 20, l == 2 ? 12 : 40);
    }
    CHECK(thx_contours_drop_flat(ctx, c, &o, &gone) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "would break in two"));
    thx_contours_destroy(&c);

    /* single loops on neighbouring layers always pair, as the build pairs them, overlapping or not */
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    c->spacing = 2.0;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "slant", THX_ROLE_OTHER, THX_CAP_POLYGON, 0, &s));
    for (int l = 0; l < 3; l++) ring(c, s, 2.0 * l, 30.0 * l, 0, 5, 16);
    CHECK_OK(ctx, thx_contours_drop_flat(ctx, c, &o, &gone));
    CHECK(gone == 0 && c->surf[0].n_layers == 3);
    thx_contours_destroy(&c);

    /* specks: an end layer of one-voxel loops under a big body (a ray-voxelized torso's flat end on a
       plane of voxel centres) fans the body's nodes into needles that thorax check fails (< 1 degree);
       a loop that every overlapping partner exceeds 100 times in area is dropped; a small loop that
       is not that small (the body 56 times its area) is kept (laced 2 mm under a 150 mm loop it
       fans into thin triangles too, which the check then names: a shelf, not a speck) */
    for (int variant = 0; variant < 2; variant++) {
        CHECK_OK(ctx, thx_contours_create(ctx, &c));
        c->spacing = 2.0;
        CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "body", THX_ROLE_OUTER, THX_CAP_GRID, 0, &s));
        if (variant == 0) {
            ring(c, s, 0, 40, 10, 0.45, 8);
            ring(c, s, 0, -70, -30, 0.45, 8);
            ring(c, s, 0, 5, 60, 0.9, 8);
        } else
            ring(c, s, 0, 10, 10, 20, 40);
        for (int l = 1; l < 5; l++) ring(c, s, 2.0 * l, 0, 0, 150, 64);
        CHECK_OK(ctx, thx_contours_drop_flat(ctx, c, &o, &gone));
        CHECK(variant == 0 ? gone == 3 && c->surf[0].n_layers == 4 && c->surf[0].layers[0].z == 2
                           : gone == 0 && c->surf[0].n_layers == 5);
        if (variant == 0) { /* the body capped at its first big loop: no needle left */
            CHECK_OK(ctx, thx_surfaces_build(ctx, c, &o, &m, NULL, NULL));
            thx_model_report *rep = NULL;
            CHECK_OK(ctx, thx_model_check(ctx, m, NULL, &rep));
            thx_model_report_destroy(&rep);
            thx_model_destroy(&m);
        }
        thx_contours_destroy(&c);
    }
    /* the same specks built without the drop: the lacing's needles, failed by the check by name */
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    c->spacing = 2.0;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "body", THX_ROLE_OUTER, THX_CAP_GRID, 0, &s));
    ring(c, s, 0, 40, 10, 0.45, 8);
    ring(c, s, 0, -70, -30, 0.45, 8);
    for (int l = 1; l < 5; l++) ring(c, s, 2.0 * l, 0, 0, 150, 64);
    if (thx_surfaces_build(ctx, c, &o, &m, NULL, NULL) == THX_OK) {
        thx_model_report *rep = NULL;
        CHECK(thx_model_check(ctx, m, NULL, &rep) == THX_ECHECK);
        CHECK(tl_msg_has(ctx, "deg angle"));
        thx_model_report_destroy(&rep);
        thx_model_destroy(&m);
    }
    thx_contours_destroy(&c);

    thx_ctx_destroy(&ctx);
    return tl_finish();
}
