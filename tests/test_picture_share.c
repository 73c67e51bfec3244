/*
 * Sort-first shares of a picture (thx_picture_draw_share, thorax/picture/picture.h), without MPI: for
 * 1, 2 and 3 ranks, each rank's share drawn alone, the shares put together by their own masks as
 * rank 0 does (thx_par_gather_pixels) and annotated, must give thx_picture_draw's picture byte for
 * byte, with OpenGL (rows in bands; one sample smoothed by FXAA, whose search crosses the bands'
 * edges where the plates' sides and the sphere's outline run across them) and with the ray tracer
 * (tiles dealt round-robin), in one panel and in panels. And the shares are shares: no pixel
 * drawn by two ranks, each rank drawing some, together exactly the 3D part's viewport; a rank
 * outside 0..size-1 is refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shapes.h"
#include "testlib.h"
#include "thorax/model/model.h"
#include "thorax/picture/picture.h"

static thx_ctx *ctx;

/* A series over surface s: x + z / 2 at each node (a gradient across every band and tile). */
static thx_series *gradient(const thx_surface *s)
{
    thx_series *x = NULL;
    if (thx_series_create(ctx, s->n_nodes, 1, &x) != THX_OK) return NULL;
    for (size_t i = 0; i < s->n_nodes; i++) x->v[i] = s->xyz[3 * i] + 0.5 * s->xyz[3 * i + 2];
    snprintf(x->unit, sizeof x->unit, "mV");
    return x;
}

static void setup(thx_picture_data *d)
{
    memset(d, 0, sizeof *d);
    CHECK_OK(ctx, thx_model_create(ctx, &d->m));
    d->m->frame = thx_frame_ras();
    double c[3] = {0, -20, 10};
    thx_surface *s[3] = {shape_plate(ctx, "left", -60), shape_plate(ctx, "right", 10), shape_sphere(ctx, "ball", c, 22, 24, 12)};
    for (int k = 0; k < 3; k++) {
        d->sets[k][0] = d->series[k] = gradient(s[k]);
        d->n_sets[k] = 1;
        CHECK_OK(ctx, thx_model_add_surface(ctx, d->m, &s[k]));
    }
}

/* Every share of o's picture for size ranks put together as rank 0 does, against the whole. */
static void check_shares(thx_renderer *r, thx_font *font, thx_picture_data *d, const thx_picture_opts *o, int size,
                         const char *what)
{
    thx_raster *whole = NULL, *part = NULL, *sum = NULL;
    size_t n = (size_t)o->w * o->h;
    unsigned char *own = malloc(n), *any = calloc(n, 1);
    CHECK_OK(ctx, thx_raster_create(ctx, o->w, o->h, &whole));
    CHECK_OK(ctx, thx_raster_create(ctx, o->w, o->h, &part));
    CHECK_OK(ctx, thx_raster_create(ctx, o->w, o->h, &sum));
    if (!whole || !part || !sum || !own || !any) goto done;
    CHECK_OK(ctx, thx_picture_draw(ctx, o, d, r, font, 0, whole, NULL));
    thx_picture_bars bars;
    int overlap = 0, empty = 0;
    for (int rank = 0; rank < size; rank++) {
        CHECK_OK(ctx, thx_picture_draw_share(ctx, o, d, r, font, 0, rank, size, part, own, &bars, NULL));
        size_t mine = 0;
        for (size_t i = 0; i < n; i++) {
            if (rank == 0 || own[i]) memcpy(sum->rgba + 4 * i, part->rgba + 4 * i, 4); /* rank 0's image, then the others' pixels */
            if (!own[i]) continue;
            overlap += any[i];
            any[i] = 1;
            mine++;
        }
        empty += mine == 0;
    }
    CHECK_OK(ctx, thx_picture_annotate(ctx, o, d, font, 0, &bars, sum));
    size_t differ = 0;
    for (size_t i = 0; i < 4 * n; i++) differ += sum->rgba[i] != whole->rgba[i];
    /* the shares together: exactly the 3D part's viewport (one panel) */
    size_t outside = 0, missed = 0;
    if (!o->panels) {
        int vp[4];
        thx_picture_viewport(o, font, o->w, o->h, vp);
        for (int y = 0; y < o->h; y++)
            for (int x = 0; x < o->w; x++) {
                int in = x >= vp[0] && x < vp[0] + vp[2] && y >= vp[1] && y < vp[1] + vp[3];
                outside += !in && any[(size_t)y * o->w + x];
                missed += in && !any[(size_t)y * o->w + x];
            }
    }
    printf("%s, %d rank%s: %zu bytes differ from the whole picture; %d pixels drawn twice, %d ranks drew none, %zu "
           "pixels outside the viewport drawn, %zu inside it not\n",
           what, size, size > 1 ? "s" : "", differ, overlap, empty, outside, missed);
    CHECK(differ == 0);
    CHECK(overlap == 0);
    CHECK(empty == 0);
    CHECK(outside == 0 && missed == 0);
done:
    free(own);
    free(any);
    thx_raster_destroy(&whole);
    thx_raster_destroy(&part);
    thx_raster_destroy(&sum);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_font *font = NULL;
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 12, &font));
    thx_picture_data d;
    setup(&d);
    /* odd sizes: bands and tiles that do not divide the picture */
    const int sizes[2][2] = {{301, 217}, {250, 331}};
    for (int z = 0; z < 2; z++) {
        thx_renderer *r = NULL;
        thx_status st = thx_renderer_create(ctx, sizes[z][0], sizes[z][1], &r);
        if (st != THX_OK) {
            fprintf(stderr, "test_picture_share: no renderer: %s\n", thx_ctx_message(ctx));
            CHECK(st == THX_OK);
            break;
        }
        for (int panels = 0; panels < 2; panels++)
            for (int traced = 0; traced < 2; traced++) {
                thx_picture_opts o;
                thx_picture_opts_default(&o);
                o.w = sizes[z][0];
                o.h = sizes[z][1];
                o.colorbar = 1;
                o.scope = THX_SCOPE_ALL;
                o.panels = panels;
                o.view = 2; /* from the left, the plates seen at a slant behind the ball */
                o.renderer = traced;
                o.rt.samples = 1;
                o.rt.ao_samples = 0;
                char what[96];
                snprintf(what, sizeof what, "%dx%d, %s, %s", o.w, o.h, traced ? "traced" : "OpenGL", panels ? "panels" : "one panel");
                for (int size = 1; size <= 3; size++) check_shares(r, font, &d, &o, size, what);
            }
        /* a rank outside the ranks */
        thx_picture_opts o;
        thx_picture_opts_default(&o);
        o.w = sizes[z][0];
        o.h = sizes[z][1];
        thx_raster *img = NULL;
        unsigned char *own = malloc((size_t)o.w * o.h);
        thx_picture_bars bars;
        CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &img));
        CHECK(img && own && thx_picture_draw_share(ctx, &o, &d, r, font, 0, 3, 3, img, own, &bars, NULL) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "share 3 of 3") != NULL);
        free(own);
        thx_raster_destroy(&img);
        thx_renderer_destroy(&r);
    }
    thx_picture_data_free(&d);
    thx_font_close(&font);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
