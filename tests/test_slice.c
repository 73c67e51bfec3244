/* Cross-sections of closed surfaces by planes (thorax/geom/slice.h): areas, orientation, nodes on the plane, open surfaces. */
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/slice.h"
static thx_surface *make(thx_ctx *ctx, const double *xyz, size_t nn, const int32_t *tri, size_t nt, int reverse)
{
    thx_surface *s = NULL;
    thx_surface_create(ctx, "s", THX_ROLE_OTHER, &s);
    s->xyz = malloc(3 * nn * sizeof *s->xyz);
    s->tri = malloc(3 * nt * sizeof *s->tri);
    memcpy(s->xyz, xyz, 3 * nn * sizeof *xyz);
    for (size_t t = 0; t < nt; t++) {
        s->tri[3 * t] = tri[3 * t];
        s->tri[3 * t + 1] = tri[3 * t + (reverse ? 2 : 1)];
        s->tri[3 * t + 2] = tri[3 * t + (reverse ? 1 : 2)];
    }
    s->n_nodes = nn;
    s->n_tris = nt;
    return s;
}

/* Slices and returns the number of loops; *area = sum of signed areas. */
static size_t slice_area(thx_ctx *ctx, const thx_surface *s, double z, double *area, size_t *npts)
{
    thx_loop *loops = NULL;
    size_t n = 0;
    CHECK_OK(ctx, thx_surface_slice(ctx, s, z, &loops, &n));
    *area = 0;
    *npts = 0;
    for (size_t k = 0; k < n; k++) {
        *area += thx_loop_area(loops[k].p, loops[k].n);
        *npts += loops[k].n;
    }
    thx_slice_free(&loops, n);
    return n;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    /* unit cube, triangles counterclockwise seen from outside */
    static const double cube[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
    static const int32_t ctri[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                   1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
    thx_surface *c = make(ctx, cube, 8, ctri, 12, 0);
    double a;
    size_t np;
    CHECK(slice_area(ctx, c, 0.5, &a, &np) == 1);
    CHECK_NEAR(a, 1.0, 1e-12); /* counterclockwise seen from above */
    CHECK(np >= 4);
    CHECK(slice_area(ctx, c, 0.25, &a, &np) == 1);
    CHECK_NEAR(a, 1.0, 1e-12);
    /* nodes exactly on the plane count as above: z = 1 cuts along the top edges, z = 0 misses */
    CHECK(slice_area(ctx, c, 1.0, &a, &np) == 1);
    CHECK_NEAR(a, 1.0, 1e-12);
    CHECK(slice_area(ctx, c, 0.0, &a, &np) == 0);
    CHECK(slice_area(ctx, c, 2.0, &a, &np) == 0);
    thx_surface_destroy(&c);
    /* reversed triangles: the loop runs clockwise */
    c = make(ctx, cube, 8, ctri, 12, 1);
    CHECK(slice_area(ctx, c, 0.5, &a, &np) == 1);
    CHECK_NEAR(a, -1.0, 1e-12);
    thx_surface_destroy(&c);
    /* octahedron cut through its four equator nodes: the square of area 2 */
    static const double oct[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    static const int32_t otri[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    thx_surface *o = make(ctx, oct, 6, otri, 8, 0);
    CHECK(slice_area(ctx, o, 0.0, &a, &np) == 1);
    CHECK_NEAR(a, 2.0, 1e-12);
    CHECK(np == 4);
    CHECK(slice_area(ctx, o, 0.5, &a, &np) == 1);
    CHECK_NEAR(a, 0.5, 1e-12);
    thx_surface_destroy(&o);
    /* two disjoint cubes in one surface: two loops */
    double two[48];
    int32_t ttri[72];
    memcpy(two, cube, sizeof cube);
    for (int i = 0; i < 8; i++) { two[24 + 3 * i] = cube[3 * i] + 3; two[25 + 3 * i] = cube[3 * i + 1]; two[26 + 3 * i] = cube[3 * i + 2]; }
    for (int i = 0; i < 36; i++) { ttri[i] = ctri[i]; ttri[36 + i] = ctri[i] + 8; }
    thx_surface *t = make(ctx, two, 16, ttri, 24, 0);
    CHECK(slice_area(ctx, t, 0.5, &a, &np) == 2);
    CHECK_NEAR(a, 2.0, 1e-12);
    thx_surface_destroy(&t);
    /* an open surface (the cube without one side) cannot be cut where it is open */
    thx_surface *open = make(ctx, cube, 8, ctri, 10, 0);
    thx_loop *loops = NULL;
    size_t n = 0;
    CHECK(thx_surface_slice(ctx, open, 0.5, &loops, &n) == THX_EGEOM);
    CHECK(loops == NULL && n == 0);
    thx_surface_destroy(&open);
    /* the model's anatomical frame goes into the contours (written as their 'frame' line) */
    for (int framed = 0; framed < 2; framed++) {
        thx_model *m = NULL;
        CHECK_OK(ctx, thx_model_create(ctx, &m));
        thx_surface *cs = make(ctx, cube, 8, ctri, 12, 0);
        CHECK_OK(ctx, thx_model_add_surface(ctx, m, &cs));
        if (framed) CHECK_OK(ctx, thx_frame_from_names(ctx, "-y", "+z", "test", &m->frame));
        thx_slice_opts so;
        thx_slice_opts_default(&so);
        so.spacing = 0.25;
        thx_contours *k = NULL;
        CHECK_OK(ctx, thx_model_slice(ctx, m, &so, &k));
        if (k) {
            CHECK(k->frame.set == framed);
            if (framed) CHECK(k->frame.up.axis == 1 && k->frame.up.sign == -1 && k->frame.front.axis == 2 && k->frame.front.sign == 1);
        }
        thx_contours_destroy(&k);
        thx_model_destroy(&m);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
