/*
 * Sort-last's layers (thx_render_layer, thorax/render/render.h): two spheres that pass through each
 * other, each drawn alone as a layer (premultiplied colour and depth, before FXAA) with the same camera
 * and depth box, put together pixel by pixel by the nearer depth (the first layer on a tie, as the
 * depth test keeps the first fragment drawn) and finished by thx_render_layer_finish, give
 * thx_render's picture of both: byte for byte, with a perspective and an orthographic camera, in the
 * whole image and in a viewport. Where the spheres cross, each layer wins some pixels (the depth
 * decides). A layer needs one sample a pixel, and a scene that clears its viewport.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shapes.h"
#include "testlib.h"
#include "thorax/model/surface.h"
#include "thorax/render/render.h"

static thx_ctx *ctx;

static void layers(thx_renderer *r, const thx_render_surface rs[2], const thx_camera *cam, const int vp[4], const char *what)
{
    int w = 181, h = 137;
    size_t n = (size_t)w * h;
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.camera = *cam;
    sc.clear = 1;
    sc.background[0] = 0.1f, sc.background[1] = 0.1f, sc.background[2] = 0.12f, sc.background[3] = 1;
    memcpy(sc.viewport, vp, sizeof sc.viewport);
    sc.have_box = 1;
    for (int k = 0; k < 3; k++) sc.box[0][k] = INFINITY, sc.box[1][k] = -INFINITY;
    for (int s = 0; s < 2; s++)
        for (size_t i = 0; i < rs[s].surf->n_nodes; i++)
            for (int k = 0; k < 3; k++) {
                sc.box[0][k] = fmin(sc.box[0][k], rs[s].surf->xyz[3 * i + k]);
                sc.box[1][k] = fmax(sc.box[1][k], rs[s].surf->xyz[3 * i + k]);
            }
    thx_raster *whole = NULL, *made = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, w, h, &whole));
    CHECK_OK(ctx, thx_raster_create(ctx, w, h, &made));
    unsigned char *c[2] = {calloc(4 * n, 1), calloc(4 * n, 1)};
    float *z[2] = {calloc(n, sizeof(float)), calloc(n, sizeof(float))};
    sc.surfaces = rs;
    sc.n_surfaces = 2;
    CHECK_OK(ctx, thx_render(ctx, r, &sc, whole, NULL));
    for (int s = 0; s < 2; s++) {
        sc.surfaces = rs + s;
        sc.n_surfaces = 1;
        CHECK_OK(ctx, thx_render_layer(ctx, r, &sc, c[s], z[s], NULL));
    }
    size_t won[2] = {0, 0};
    for (size_t i = 0; i < n; i++) { /* the nearer fragment; the first layer on a tie */
        int b = z[1][i] < z[0][i];
        won[b] += z[b][i] < 1;
        memcpy(c[0] + 4 * i, c[b] + 4 * i, 4);
    }
    memcpy(made->rgba, whole->rgba, 4 * n); /* (the pixels outside the viewport: the caller's) */
    CHECK_OK(ctx, thx_render_layer_finish(ctx, r, &sc, c[0], made));
    size_t differ = 0;
    for (size_t i = 0; i < 4 * n; i++) differ += made->rgba[i] != whole->rgba[i];
    printf("%s: %zu bytes differ from the whole scene's picture; pixels from layer 1 %zu, from layer 2 %zu\n", what,
           differ, won[0], won[1]);
    CHECK(differ == 0);
    CHECK(won[0] > 100 && won[1] > 100);
    for (int s = 0; s < 2; s++) {
        free(c[s]);
        free(z[s]);
    }
    thx_raster_destroy(&whole);
    thx_raster_destroy(&made);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_renderer *r = NULL;
    thx_status st = thx_renderer_create(ctx, 181, 137, &r);
    if (st != THX_OK) {
        fprintf(stderr, "test_render_layers: no renderer: %s\n", thx_ctx_message(ctx));
        CHECK(st == THX_OK);
        thx_ctx_destroy(&ctx);
        return tl_finish();
    }
    CHECK_OK(ctx, thx_renderer_set_samples(ctx, r, 1));
    const double c0[3] = {-0.35, 0, 0}, c1[3] = {0.3, 0.15, 0.1};
    thx_surface *s[2] = {shape_sphere(ctx, "ball", c0, 0.6, 32, 16), shape_sphere(ctx, "ball", c1, 0.55, 32, 16)};
    double *v[2];
    thx_render_surface rs[2];
    for (int k = 0; k < 2; k++) {
        v[k] = malloc(s[k]->n_nodes * sizeof *v[k]);
        for (size_t i = 0; i < s[k]->n_nodes; i++) v[k][i] = s[k]->xyz[3 * i] + 0.5 * s[k]->xyz[3 * i + 2];
        memset(&rs[k], 0, sizeof rs[k]);
        rs[k].surf = s[k];
        rs[k].mode = THX_DRAW_PHONG;
        rs[k].color[0] = rs[k].color[1] = rs[k].color[2] = 0.8f, rs[k].color[3] = 1;
        rs[k].values = v[k];
        rs[k].cmap = THX_CMAP_ECG;
        rs[k].scale.model = THX_SCALE_LINEAR;
        rs[k].scale.lo = -1, rs[k].scale.hi = 1;
    }
    thx_camera persp, ortho;
    memset(&persp, 0, sizeof persp);
    persp.eye[0] = 1.2, persp.eye[1] = -3.5, persp.eye[2] = 1.0;
    persp.up[2] = 1;
    persp.fov_deg = 35;
    ortho = persp;
    ortho.fov_deg = 0;
    ortho.height = 2.2;
    const int whole_image[4] = {0, 0, 0, 0}, part[4] = {13, 9, 150, 111};
    layers(r, rs, &persp, whole_image, "perspective, the whole image");
    layers(r, rs, &ortho, whole_image, "orthographic, the whole image");
    layers(r, rs, &persp, part, "perspective, a viewport");
    /* refused: more than one sample a pixel, a scene that does not clear */
    thx_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.camera = persp;
    sc.surfaces = rs;
    sc.n_surfaces = 1;
    unsigned char *rgba = calloc(4 * 181 * 137, 1);
    float *depth = calloc(181 * 137, sizeof *depth);
    CHECK(thx_render_layer(ctx, r, &sc, rgba, depth, NULL) == THX_EINPUT); /* clear = 0 */
    sc.clear = 1;
    if (thx_renderer_set_samples(ctx, r, 4) == THX_OK && thx_renderer_samples(r) == 4) {
        CHECK(thx_render_layer(ctx, r, &sc, rgba, depth, NULL) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "one sample") != NULL);
    }
    free(rgba);
    free(depth);
    for (int k = 0; k < 2; k++) {
        free(v[k]);
        thx_surface_destroy(&s[k]);
    }
    thx_renderer_destroy(&r);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
