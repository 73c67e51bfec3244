/*
 * Colour bars and orientation letters of a picture (thorax/picture/picture.h), by pixel facts on
 * small offscreen renders:
 *  - two flat plates facing the camera, each with its own colour scale (+-10 and +-40): the
 *    colour of a plate's pixel, found on the strip of the bar drawn for that plate, reads the
 *    value the plate holds there (-5, 20); on the other bar it would read something else, so a
 *    shared bar would lie; a picture too small for both bars is refused, naming both scales;
 *  - an activation map's bar spans its earliest to latest time (not a symmetric range);
 *  - the letters at the edges: for the anterior view of a RAS model 'R' on the viewer's left
 *    (where a point toward the subject's right projects), 'L' on the right, 'S' above, 'I' below,
 *    drawn as those glyphs; the other standard views, another model frame, any camera.
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

/* A series over a plate: every node `v`, but the first corner `lo` and the last `hi`. */
static thx_series *plate_data(double v, double lo, double hi)
{
    thx_series *x = NULL;
    if (thx_series_create(ctx, 25, 1, &x) != THX_OK) return NULL;
    for (int i = 0; i < 25; i++) x->v[i] = v;
    x->v[0] = lo;
    x->v[24] = hi;
    snprintf(x->unit, sizeof x->unit, "mV");
    return x;
}

static void setup(thx_picture_data *d)
{
    memset(d, 0, sizeof *d);
    CHECK_OK(ctx, thx_model_create(ctx, &d->m));
    d->m->frame = thx_frame_ras();
    thx_surface *a = shape_plate(ctx, "left", -60), *b = shape_plate(ctx, "right", 10);
    CHECK_OK(ctx, thx_model_add_surface(ctx, d->m, &a));
    CHECK_OK(ctx, thx_model_add_surface(ctx, d->m, &b));
    /* plate "left" (x < 0: the subject's left, the viewer's right in the anterior view) -5 within
       +-10; "right" 20 within +-40 */
    d->sets[0][0] = d->series[0] = plate_data(-5, -10, 10);
    d->sets[1][0] = d->series[1] = plate_data(20, -40, 40);
    d->n_sets[0] = d->n_sets[1] = 1;
}

static const unsigned char *px(const thx_raster *img, int x, int y) { return img->rgba + 4 * ((size_t)y * img->w + x); }

static int dist(const unsigned char *a, const unsigned char *b)
{
    return abs(a[0] - b[0]) + abs(a[1] - b[1]) + abs(a[2] - b[2]);
}

/* The value colour c reads on the bar whose strip is box, spanning lo (bottom) .. hi (top); the
 * colour distance of the best row in *best. */
static double read_bar(const thx_raster *img, const int box[4], double lo, double hi, const unsigned char *c, int *best)
{
    int x = box[0] + box[2] / 2, brow = -1;
    *best = 1 << 30;
    for (int row = box[1]; row < box[1] + box[3]; row++) {
        int e = dist(px(img, x, row), c);
        if (e < *best) { *best = e; brow = row; }
    }
    double t = (box[1] + box[3] - 1 - brow + 0.5) / box[3];
    return lo + t * (hi - lo);
}

/* Whether text is drawn in img with its left end at x and its baseline within y0..y1: the pixels of
 * the glyphs' box (and one around it) exactly as the font draws text on the background. */
static int text_at(const thx_raster *img, thx_font *font, int x, int y0, int y1, const char *text)
{
    thx_raster *ref = NULL;
    if (thx_raster_create(ctx, img->w, img->h, &ref) != THX_OK) return 0;
    static const unsigned char bg[4] = {24, 24, 28, 255}, ink[4] = {255, 255, 255, 255};
    int found = 0;
    for (int y = y0; y <= y1 && !found; y++) {
        thx_raster_fill(ref, bg);
        thx_draw_text(ref, font, x, y, text, ink);
        int bx0 = img->w, by0 = img->h, bx1 = -1, by1 = -1;
        for (int j = 0; j < img->h; j++)
            for (int i = 0; i < img->w; i++)
                if (dist(px(ref, i, j), bg)) {
                    if (i < bx0) bx0 = i;
                    if (i > bx1) bx1 = i;
                    if (j < by0) by0 = j;
                    if (j > by1) by1 = j;
                }
        if (bx1 < 0) break;
        int same = 1;
        for (int j = by0 - 1; j <= by1 + 1 && same; j++)
            for (int i = bx0 - 1; i <= bx1 + 1 && same; i++)
                if (i >= 0 && j >= 0 && i < img->w && j < img->h) same = dist(px(ref, i, j), px(img, i, j)) == 0;
        found = same;
    }
    thx_raster_destroy(&ref);
    return found;
}

/* The pixel of the picture where model point p lands (single panel). */
static void where(const thx_picture_opts *o, const thx_picture_data *d, thx_font *font, const double p[3], int *x, int *y)
{
    int vp[4];
    thx_picture_viewport(o, font, o->w, o->h, vp);
    thx_camera cam;
    thx_picture_camera(o, d, (double)vp[2] / vp[3], &cam);
    double fx = 0, fy = 0, depth = 0;
    CHECK(thx_camera_project(&cam, vp[2], vp[3], p, &fx, &fy, &depth) == 0);
    *x = vp[0] + (int)fx;
    *y = vp[1] + (int)fy;
}

static void test_bars(thx_renderer *r, thx_font *font)
{
    thx_picture_data d;
    setup(&d);
    thx_picture_opts o;
    thx_picture_opts_default(&o);
    o.w = 600;
    o.h = 400;
    o.mode = THX_DRAW_FLAT; /* flat, facing an orthographic camera: the colour map's colour itself */
    o.colorbar = 1;
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &img));
    CHECK_OK(ctx, thx_picture_draw(ctx, &o, &d, r, font, 0, img, NULL));
    int box[THX_PICTURE_BARS][4];
    CHECK(thx_picture_bar_layout(&o, font, o.w, o.h, 2, box) == 2);
    /* the bars in order: the first surface's (no body surface here), then the other */
    double range[2] = {10, 40}, want[2] = {-5, 20};
    double centre[2][3] = {{-35, 0, 0}, {35, 0, 0}};
    for (int s = 0; s < 2; s++) {
        int x, y, e;
        where(&o, &d, font, centre[s], &x, &y);
        unsigned char c[4];
        memcpy(c, px(img, x, y), 4);
        double v = read_bar(img, box[s], -range[s], range[s], c, &e);
        printf("plate %d: pixel (%d, %d) rgb %d %d %d reads %.2f on its bar (colour distance %d)\n", s, x, y, c[0], c[1],
               c[2], v, e);
        CHECK(e <= 6);
        CHECK_NEAR(v, want[s], 2 * range[s] / box[s][3] + 1e-9); /* within a row of the strip */
        /* on the other bar the same colour reads the other scale's value: a shared bar would lie */
        double w = read_bar(img, box[1 - s], -range[s], range[s], c, &e);
        double other = read_bar(img, box[1 - s], -range[1 - s], range[1 - s], c, &e);
        CHECK_NEAR(w, want[s], 2 * range[s] / box[1 - s][3] + 1e-9);
        CHECK(fabs(other - want[s]) > 4);
    }
    /* the strip's end rows are the colour map's ends (where its end labels are): the row centres
       at t = 0.5 / h and 1 - 0.5 / h */
    for (int k = 0; k < 2; k++) {
        unsigned char top[3], bottom[3];
        thx_colormap_eval((thx_colormap)o.cmap, 1 - 0.5 / box[k][3], top);
        thx_colormap_eval((thx_colormap)o.cmap, 0.5 / box[k][3], bottom);
        CHECK(dist(px(img, box[k][0] + box[k][2] / 2, box[k][1]), top) <= 3);
        CHECK(dist(px(img, box[k][0] + box[k][2] / 2, box[k][1] + box[k][3] - 1), bottom) <= 3);
    }
    /* the end labels read each bar's own scale: "10" and "-10" beside the first, "40" and "-40"
       beside the second (the label's left end 7 pixels right of the strip, its baseline about half
       a digit below the end row), and not the other bar's */
    int fh = thx_font_height(font);
    for (int k = 0; k < 2; k++) {
        char hi[16], lo[16], ohi[16];
        snprintf(hi, sizeof hi, "%g", range[k]);
        snprintf(lo, sizeof lo, "%g", -range[k]);
        snprintf(ohi, sizeof ohi, "%g", range[1 - k]);
        int lx = box[k][0] + box[k][2] + 7, top_row = box[k][1], bottom_row = box[k][1] + box[k][3] - 1;
        CHECK(text_at(img, font, lx, top_row, top_row + fh, hi));
        CHECK(text_at(img, font, lx, bottom_row, bottom_row + fh, lo));
        CHECK(!text_at(img, font, lx, top_row, top_row + fh, ohi));
    }
    /* one scale for both (--scope all): one bar, +-40, and the plates' pixels read their values on it */
    o.scope = THX_SCOPE_ALL;
    CHECK_OK(ctx, thx_picture_draw(ctx, &o, &d, r, font, 0, img, NULL));
    CHECK(thx_picture_bar_layout(&o, font, o.w, o.h, 1, box) == 1);
    for (int s = 0; s < 2; s++) {
        int x, y, e;
        where(&o, &d, font, centre[s], &x, &y);
        double v = read_bar(img, box[0], -40, 40, px(img, x, y), &e);
        CHECK(e <= 6);
        CHECK_NEAR(v, want[s], 80.0 / box[0][3] + 1e-9);
    }
    /* too small for two bars: refused, naming both scales */
    o.scope = THX_SCOPE_SERIES;
    thx_raster *small = NULL;
    thx_renderer *rs = NULL;
    o.h = 100;
    CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &small));
    CHECK_OK(ctx, thx_renderer_create(ctx, o.w, o.h, &rs));
    CHECK(thx_picture_draw(ctx, &o, &d, rs, font, 0, small, NULL) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "2 different scales") && tl_msg_has(ctx, "-10..10 mV") && tl_msg_has(ctx, "-40..40 mV"));
    CHECK(tl_msg_has(ctx, "--scope all"));
    /* more titles than bars: refused; one title: every bar's; the k-th: the k-th bar's */
    o.h = 400;
    o.bar_title[0] = "A";
    o.bar_title[1] = "B";
    o.bar_title[2] = "C";
    o.n_bar_title = 3;
    CHECK(thx_picture_draw(ctx, &o, &d, r, font, 0, img, NULL) == THX_EINPUT && tl_msg_has(ctx, "--bar-title"));
    thx_picture_bars bars;
    memset(&bars, 0, sizeof bars);
    bars.n = 2;
    snprintf(bars.title[0], sizeof bars.title[0], "potential");
    snprintf(bars.title[1], sizeof bars.title[1], "activation");
    snprintf(bars.unit[1], sizeof bars.unit[1], "ms");
    char head[64], unit[32];
    o.n_bar_title = 0;
    thx_picture_bar_title(&o, &bars, 1, head, sizeof head, unit, sizeof unit);
    CHECK(!strcmp(head, "activation") && !strcmp(unit, "ms"));
    o.n_bar_title = 1;
    o.bar_unit[0] = "uV";
    o.n_bar_unit = 1;
    thx_picture_bar_title(&o, &bars, 1, head, sizeof head, unit, sizeof unit);
    CHECK(!strcmp(head, "A") && !strcmp(unit, "uV"));
    o.n_bar_title = 2;
    thx_picture_bar_title(&o, &bars, 1, head, sizeof head, unit, sizeof unit);
    CHECK(!strcmp(head, "B"));
    thx_raster_destroy(&small);
    thx_renderer_destroy(&rs);
    thx_raster_destroy(&img);
    thx_picture_data_free(&d);
}

/*
 * An activation map's colour bar runs from the earliest to the latest activation time (issue 24's
 * missed mutant: the symmetric range of potentials, -latest..latest, would pass unseen): a plate
 * whose columns activate at 20, 30, 40, 50, 60 ms (a downstroke -10 tanh((t - t_a) / 2) mV, 1 ms
 * samples), so its map is linear in x and each pixel's colour, read on the bar as spanning the
 * map's earliest (bottom) to latest (top) time, gives the time of its column.
 */
static void test_activation_bar(thx_renderer *r, thx_font *font)
{
    thx_picture_data d;
    memset(&d, 0, sizeof d);
    CHECK_OK(ctx, thx_model_create(ctx, &d.m));
    d.m->frame = thx_frame_ras();
    thx_surface *a = shape_plate(ctx, "sock", -25);
    CHECK_OK(ctx, thx_model_add_surface(ctx, d.m, &a));
    thx_series *x = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 25, 100, &x));
    snprintf(x->unit, sizeof x->unit, "mV");
    for (int f = 0; f < 100; f++) {
        x->time[f] = f;
        for (int i = 0; i < 25; i++) x->v[(size_t)f * 25 + i] = -10 * tanh((f - (20 + 10 * (i % 5))) / 2.0);
    }
    d.sets[0][0] = d.series[0] = x;
    d.n_sets[0] = 1;
    CHECK_OK(ctx, thx_picture_add_activation(ctx, &d, 0, NAN, NAN));
    const thx_series *map = d.series[0];
    CHECK(map != x && d.map[0][d.active[0]]);
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 25; i++) {
        lo = fmin(lo, map->v[i]);
        hi = fmax(hi, map->v[i]);
    }
    printf("activation map: %.3f to %.3f ms\n", lo, hi);
    CHECK_NEAR(lo, 20, 0.1);
    CHECK_NEAR(hi, 60, 0.1);
    thx_picture_opts o;
    thx_picture_opts_default(&o);
    o.w = 600;
    o.h = 400;
    o.mode = THX_DRAW_FLAT;
    o.colorbar = 1;
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &img));
    CHECK_OK(ctx, thx_picture_draw(ctx, &o, &d, r, font, 0, img, NULL));
    int box[THX_PICTURE_BARS][4];
    CHECK(thx_picture_bar_layout(&o, font, o.w, o.h, 1, box) == 1);
    for (int col = 1; col <= 3; col++) {
        double p[3] = {-25 + 12.5 * col, 0, 6.25}, want = map->v[5 + col];
        int px_x, px_y, e;
        where(&o, &d, font, p, &px_x, &px_y);
        double v = read_bar(img, box[0], lo, hi, px(img, px_x, px_y), &e);
        printf("activation column %d: pixel (%d, %d) reads %.2f ms on the bar (map %.2f; colour distance %d)\n", col, px_x,
               px_y, v, want, e);
        CHECK(e <= 6);
        CHECK_NEAR(v, want, (hi - lo) / box[0][3] + 0.5);
    }
    thx_raster_destroy(&img);
    thx_picture_data_free(&d);
}

/* The letters of o's camera (have_camera or the view) for the plates' model. */
static void letters(const thx_picture_opts *o, const thx_picture_data *d, char out[4][4])
{
    thx_camera cam;
    thx_picture_camera(o, d, 1.5, &cam);
    thx_picture_letter L[4];
    thx_picture_orientation_text(o, &cam, L);
    for (int k = 0; k < 4; k++) memcpy(out[k], L[k].text, 4);
}

static int is(char got[4][4], const char *l, const char *r, const char *t, const char *b)
{
    int ok = !strcmp(got[0], l) && !strcmp(got[1], r) && !strcmp(got[2], t) && !strcmp(got[3], b);
    if (!ok) printf("letters %s %s %s %s, expected %s %s %s %s\n", got[0], got[1], got[2], got[3], l, r, t, b);
    return ok;
}

static void test_orientation(thx_renderer *r, thx_font *font)
{
    thx_picture_data d;
    setup(&d);
    thx_picture_opts o;
    thx_picture_opts_default(&o);
    o.w = 600;
    o.h = 400;
    o.orientation = 1;
    char got[4][4];
    /* RAS, the standard views (left, right, top, bottom of the picture) */
    o.view = THX_VIEW_ANTERIOR;
    letters(&o, &d, got);
    CHECK(is(got, "R", "L", "S", "I"));
    o.view = THX_VIEW_POSTERIOR;
    letters(&o, &d, got);
    CHECK(is(got, "L", "R", "S", "I"));
    o.view = THX_VIEW_LEFT; /* from the subject's left, head up: the front on the viewer's left */
    letters(&o, &d, got);
    CHECK(is(got, "A", "P", "S", "I"));
    o.view = THX_VIEW_RIGHT;
    letters(&o, &d, got);
    CHECK(is(got, "P", "A", "S", "I"));
    o.view = THX_VIEW_SUPERIOR; /* from above, the front up */
    letters(&o, &d, got);
    CHECK(is(got, "L", "R", "A", "P"));
    o.view = THX_VIEW_INFERIOR;
    letters(&o, &d, got);
    CHECK(is(got, "R", "L", "A", "P"));
    /* the letters follow the projection: a point toward the subject's right lands on the 'R' side */
    o.view = THX_VIEW_ANTERIOR;
    {
        int x0, y0, x1, y1, x2, y2;
        double c[3] = {0, 0, 0}, rt[3] = {-40, 0, 0}, up[3] = {0, 0, 20};
        where(&o, &d, font, c, &x0, &y0);
        where(&o, &d, font, rt, &x1, &y1);
        where(&o, &d, font, up, &x2, &y2);
        CHECK(x1 > x0); /* -x (the subject's left) to the viewer's right */
        CHECK(y2 < y0); /* superior up */
    }
    /* another frame: the model's superior axis +y, anterior -z (as the Dalhousie torso's files):
       canonical right = +x, anterior = -z, cranial = +y */
    o.ax[0] = 0; o.sg[0] = 1;
    o.ax[1] = 2; o.sg[1] = -1;
    o.ax[2] = 1; o.sg[2] = 1;
    letters(&o, &d, got);
    CHECK(is(got, "R", "L", "S", "I"));
    o.view = THX_VIEW_LEFT;
    letters(&o, &d, got);
    CHECK(is(got, "A", "P", "S", "I"));
    for (int k = 0; k < 3; k++) { o.ax[k] = k; o.sg[k] = 1; }
    /* any camera: from the subject's right (+x), head up; then from the front-right, obliquely */
    o.have_camera = 1;
    memset(&o.cam, 0, sizeof o.cam);
    o.cam.eye[0] = 500;
    o.cam.up[2] = 1;
    o.cam.height = 200;
    letters(&o, &d, got);
    CHECK(is(got, "P", "A", "S", "I"));
    o.cam.eye[0] = o.cam.eye[1] = 400;
    letters(&o, &d, got);
    CHECK(is(got, "RP", "LA", "S", "I"));
    o.cam.up[0] = 1; /* tilted: the top is mostly superior, partly toward the subject's right */
    letters(&o, &d, got);
    CHECK(got[2][0] == 'S' && strlen(got[2]) >= 2);
    o.have_camera = 0;

    /* pixel facts: the anterior picture has an 'R' glyph at the left edge, 'L' at the right, 'S'
       at the top, 'I' at the bottom, exactly as the font draws them on the background */
    o.view = THX_VIEW_ANTERIOR;
    thx_raster *img = NULL, *ref = NULL;
    CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &img));
    CHECK_OK(ctx, thx_raster_create(ctx, o.w, o.h, &ref));
    CHECK_OK(ctx, thx_picture_draw(ctx, &o, &d, r, font, 0, img, NULL));
    thx_picture_letter L[8];
    CHECK(thx_picture_orientation(&o, &d, font, o.w, o.h, L, 8) == 4);
    const char *expect[4] = {"R", "L", "S", "I"}, *wrong[4] = {"L", "R", "I", "S"};
    static const unsigned char FG[4] = {235, 235, 235, 255};
    int fh = thx_font_height(font);
    for (int k = 0; k < 4; k++) {
        CHECK(!strcmp(L[k].text, expect[k]));
        int x0 = L[k].x - 2, y0 = L[k].y - fh, x1 = L[k].x + thx_text_width(font, expect[k]) + 2, y1 = L[k].y + 4;
        CHECK(x0 >= 0 && y0 >= 0 && x1 <= o.w && y1 <= o.h);
        int differ_right = 0, differ_wrong = 0, lit = 0;
        for (int pass = 0; pass < 2; pass++) {
            thx_raster_fill(ref, img->rgba); /* the background: the picture's top-left pixel */
            thx_draw_text(ref, font, L[k].x, L[k].y, pass ? wrong[k] : expect[k], FG);
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++) {
                    int e = dist(px(img, x, y), px(ref, x, y));
                    if (pass) differ_wrong += e > 0;
                    else { differ_right += e > 0; lit += dist(px(img, x, y), img->rgba) > 100; }
                }
        }
        printf("letter %s at (%d, %d): %d pixels lit, %d differ from the glyph, %d from '%s'\n", expect[k], L[k].x, L[k].y, lit,
               differ_right, differ_wrong, wrong[k]);
        CHECK(lit > 5);
        CHECK(differ_right == 0);
        CHECK(differ_wrong > 5);
    }
    /* --panels: four letters in each panel */
    o.panels = 1;
    thx_picture_letter P[16];
    CHECK(thx_picture_orientation(&o, &d, font, o.w, o.h, P, 16) == 8);
    CHECK(!strcmp(P[4].text, "R") && P[4].x > P[1].x);
    thx_raster_destroy(&img);
    thx_raster_destroy(&ref);
    thx_picture_data_free(&d);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_renderer *r = NULL;
    thx_font *font = NULL;
    thx_status st = thx_renderer_create(ctx, 600, 400, &r);
    if (st != THX_OK) {
        fprintf(stderr, "test_bars: no renderer: %s\n", thx_ctx_message(ctx));
        CHECK(st == THX_OK);
        thx_ctx_destroy(&ctx);
        return tl_finish();
    }
    CHECK_OK(ctx, thx_font_open(ctx, NULL, 14, &font));
    if (font) {
        test_bars(r, font);
        test_activation_bar(r, font);
        test_orientation(r, font);
    }
    thx_font_close(&font);
    thx_renderer_destroy(&r);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
