/*
 * Tests of the 12-lead ECG plot (thorax/picture/ecg_plot.h):
 *  - a made-up 12-lead series whose lead k peaks at a known value at a known time: in the SVG each
 *    lead's trace reaches baseline - peak * 10 mm at x0 + t * 25 mm/s, its lowest point is the
 *    series' minimum in the same units, it has one point per sample, and every baseline lies on
 *    a millimetre line of the grid; microvolts give the same picture as millivolts, seconds the
 *    same as milliseconds;
 *  - the gain and the speed: 20 mm/mV doubles the excursion, 50 mm/s the length;
 *  - the PNG: read back, its size is the SVG's in mm times the pixels per mm, and the trace's ink
 *    is where the SVG puts it;
 *  - refusals: 11 rows, an unknown unit or time unit, an extension that is neither .svg nor .png,
 *    a file thorax did not write, an input given as the output; nothing left behind.
 * The real-file case (the leads of a forward solution, read with python's xml.etree) is
 * tests/e2e_report.sh.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/picture/ecg_plot.h"
#include "thorax/render/image.h"

static thx_ctx *ctx;

/* Lead k: a Gaussian of height (k + 1) * 0.15 mV (negative for aVR) at 100 + 10 k ms, width 15 ms,
 * over 400 samples at 1 ms; a small negative dip of -0.05 (k + 1) mV at 300 ms. */
static thx_series *made_up(double vscale, const char *unit, double tscale, const char *tunit)
{
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 12, 400, &s));
    if (!s) return NULL;
    for (size_t f = 0; f < 400; f++) {
        s->time[f] = (double)f * tscale;
        for (size_t k = 0; k < 12; k++) {
            double t = (double)f, c = 100.0 + 10.0 * (double)k, a = (k == 3 ? -1 : 1) * 0.15 * (double)(k + 1);
            double v = a * exp(-0.5 * (t - c) * (t - c) / 225.0) - 0.05 * (double)(k + 1) * exp(-0.5 * (t - 300) * (t - 300) / 100.0);
            s->v[f * 12 + k] = v * vscale;
        }
    }
    snprintf(s->unit, sizeof s->unit, "%s", unit);
    snprintf(s->time_unit, sizeof s->time_unit, "%s", tunit);
    snprintf(s->label, sizeof s->label, "made-up ECG");
    return s;
}

static const char *const LEAD[12] = {"I", "II", "III", "aVR", "aVL", "aVF", "V1", "V2", "V3", "V4", "V5", "V6"};

/* The attribute NAME="..." after p, as a number. */
static double attr(const char *p, const char *name)
{
    char key[64];
    snprintf(key, sizeof key, " %s=\"", name);
    const char *q = strstr(p, key);
    return q ? atof(q + strlen(key)) : NAN;
}

typedef struct {
    double x0, base, ymin, ymax, x_at_ymin, x_at_ymax;
    size_t n;
} trace_info;

/* Reads lead NAME's group from the SVG text: its x0, baseline, and the extremes of its points. */
static int lead_trace(const char *svg, const char *name, trace_info *ti)
{
    char key[64];
    snprintf(key, sizeof key, "id=\"lead-%s\"", name);
    const char *g = strstr(svg, key);
    if (!g) return -1;
    ti->x0 = attr(g, "data-x0");
    ti->base = attr(g, "data-baseline");
    const char *pts = strstr(g, "points=\"");
    const char *end = strstr(g, "</g>");
    if (!pts || !end || pts > end) return -1;
    pts += 8;
    ti->ymin = INFINITY;
    ti->ymax = -INFINITY;
    ti->x_at_ymin = ti->x_at_ymax = NAN;
    ti->n = 0;
    while (*pts && *pts != '"') {
        char *e;
        double x = strtod(pts, &e);
        if (*e != ',') return -1;
        double y = strtod(e + 1, &e);
        if (y < ti->ymin) ti->ymin = y, ti->x_at_ymin = x;
        if (y > ti->ymax) ti->ymax = y, ti->x_at_ymax = x;
        ti->n++;
        pts = e;
        while (*pts == ' ') pts++;
    }
    return 0;
}

static void series_extremes(const thx_series *s, size_t row, double k, double *lo, size_t *flo, double *hi, size_t *fhi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t f = 0; f < s->n_frames; f++) {
        double v = s->v[f * s->n_rows + row] * k;
        if (v < *lo) *lo = v, *flo = f;
        if (v > *hi) *hi = v, *fhi = f;
    }
}

static void test_svg(void)
{
    thx_series *s = made_up(1, "mV", 1, "ms");
    if (!s) return;
    const char *p = tl_path("ecg.svg");
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, NULL, p, NULL, 0));
    size_t len = 0;
    char *svg = tl_slurp(ctx, p, &len);
    if (!svg) return;
    CHECK(strstr(svg, "<?xml") == svg && strstr(svg, "thorax-ecg-plot") != NULL);
    CHECK(strstr(svg, "data-mm-per-mv=\"10\"") && strstr(svg, "data-mm-per-s=\"25\""));
    for (int k = 0; k < 12; k++) {
        trace_info ti;
        CHECK(lead_trace(svg, LEAD[k], &ti) == 0);
        double lo, hi;
        size_t flo = 0, fhi = 0;
        series_extremes(s, (size_t)k, 1, &lo, &flo, &hi, &fhi);
        CHECK(ti.n == 400);
        /* 10 mm per mV, y downwards; 25 mm per second: 0.025 mm per ms */
        CHECK_NEAR((ti.base - ti.ymin) / 10.0, hi, 1e-3);
        CHECK_NEAR((ti.base - ti.ymax) / 10.0, lo, 1e-3);
        /* the main wave's place (the other extreme may be a flat tie near zero) */
        if (k == 3) CHECK_NEAR(ti.x_at_ymax, ti.x0 + 0.025 * (double)flo, 1e-3);
        else CHECK_NEAR(ti.x_at_ymin, ti.x0 + 0.025 * (double)fhi, 1e-3);
        CHECK_NEAR(k == 3 ? flo : fhi, 100 + 10 * k, 0.5);
        CHECK(fabs(ti.base - round(ti.base)) < 1e-9); /* on a millimetre line */
        CHECK(ti.ymin > 0);                          /* inside the sheet */
    }
    /* the standard layout: I, II, III down the first column, aVR.. the second, V1.. and V4.. */
    trace_info a, b, c;
    lead_trace(svg, "I", &a);
    lead_trace(svg, "II", &b);
    lead_trace(svg, "aVR", &c);
    CHECK(a.x0 == b.x0 && b.base > a.base && c.base == a.base && c.x0 > a.x0);
    lead_trace(svg, "V6", &c);
    lead_trace(svg, "III", &a);
    CHECK(c.base == a.base && c.x0 > b.x0);

    /* the same picture from microvolts and seconds */
    thx_series *u = made_up(1000, "uV", 1e-3, "s");
    const char *pu = tl_path("ecg_uv.svg");
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, u, NULL, pu, NULL, 0));
    char *svgu = tl_slurp(ctx, pu, &len);
    CHECK(svgu && !strcmp(svg, svgu));
    free(svgu);
    thx_series_destroy(&u);

    /* gain 20 mm/mV and 50 mm/s */
    thx_ecg_plot_opts o;
    thx_ecg_plot_opts_default(&o);
    CHECK(o.mm_per_mv == 10 && o.mm_per_s == 25);
    o.mm_per_mv = 20;
    o.mm_per_s = 50;
    const char *p2 = tl_path("ecg2.svg");
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, &o, p2, NULL, 0));
    char *svg2 = tl_slurp(ctx, p2, &len);
    if (svg2) {
        trace_info t1, t2;
        CHECK(lead_trace(svg, "V3", &t1) == 0 && lead_trace(svg2, "V3", &t2) == 0);
        CHECK_NEAR(t2.base - t2.ymin, 2 * (t1.base - t1.ymin), 2e-3);
        CHECK_NEAR(t2.x_at_ymin - t2.x0, 2 * (t1.x_at_ymin - t1.x0), 2e-3);
    }
    free(svg2);

    /* writing again over thorax's own plot is allowed */
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, NULL, p, NULL, 0));
    free(svg);
    thx_series_destroy(&s);
}

static void test_png(void)
{
    thx_series *s = made_up(1, "mV", 1, "ms");
    if (!s) return;
    thx_ecg_plot_opts o;
    thx_ecg_plot_opts_default(&o);
    o.title = "made-up";
    const char *ps = tl_path("p.svg"), *pp = tl_path("p.png");
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, &o, ps, NULL, 0));
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, &o, pp, NULL, 0));
    size_t len;
    char *svg = tl_slurp(ctx, ps, &len);
    thx_raster *img = NULL;
    CHECK_OK(ctx, thx_raster_read_png(ctx, pp, &img));
    if (svg && img) {
        const char *vb = strstr(svg, "viewBox=\"");
        double x = 0, y = 0, w = 0, h = 0;
        CHECK(vb && sscanf(vb + 9, "%lf %lf %lf %lf", &x, &y, &w, &h) == 4);
        CHECK(img->w == (int)ceil(w * o.px_per_mm) && img->h == (int)ceil(h * o.px_per_mm));
        /* lead II's peak: dark ink at its place in pixels, the paper's colours elsewhere */
        trace_info ti;
        CHECK(lead_trace(svg, "II", &ti) == 0);
        int px = (int)lround(ti.x_at_ymin * o.px_per_mm), py = (int)lround(ti.ymin * o.px_per_mm);
        int dark = 0;
        for (int dy = -2; dy <= 2; dy++)
            for (int dx = -2; dx <= 2; dx++) {
                const unsigned char *q = img->rgba + 4 * ((size_t)(py + dy) * (size_t)img->w + (size_t)(px + dx));
                dark |= q[0] < 80 && q[1] < 80 && q[2] < 80;
            }
        CHECK(dark);
        /* a corner of the sheet is paper: white or the grid's pink, never ink */
        const unsigned char *q = img->rgba + 4 * ((size_t)(img->h - 3) * (size_t)img->w + (size_t)(img->w - 3));
        CHECK(q[0] > 200);
    }
    free(svg);
    thx_raster_destroy(&img);
    thx_series_destroy(&s);
}

static void test_refusals(void)
{
    thx_series *s = made_up(1, "mV", 1, "ms");
    if (!s) return;
    const char *p = tl_path("bad.svg");
    s->n_rows = 11; /* the values are still 12 a frame; only the count is looked at before refusing */
    CHECK(thx_ecg_plot_write(ctx, s, NULL, p, NULL, 0) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "\"made-up ECG\" has 11 rows"));
    s->n_rows = 12;
    snprintf(s->unit, sizeof s->unit, "furlong");
    CHECK(thx_ecg_plot_write(ctx, s, NULL, p, NULL, 0) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "unit \"furlong\""));
    snprintf(s->unit, sizeof s->unit, "mV");
    snprintf(s->time_unit, sizeof s->time_unit, "beats");
    CHECK(thx_ecg_plot_write(ctx, s, NULL, p, NULL, 0) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "time unit \"beats\""));
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    CHECK(!tl_exists(p));
    CHECK(thx_ecg_plot_write(ctx, s, NULL, tl_path("ecg.pdf"), NULL, 0) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, ".svg or .png"));
    CHECK(!tl_exists(tl_path("ecg.pdf")));
    /* a file thorax did not write is left alone */
    const char *mine = tl_path("mine.svg");
    tl_write_text(mine, "<svg>my own drawing</svg>\n");
    CHECK(thx_ecg_plot_write(ctx, s, NULL, mine, NULL, 0) != THX_OK);
    size_t len;
    char *t = tl_slurp(ctx, mine, &len);
    CHECK(t && !strcmp(t, "<svg>my own drawing</svg>\n"));
    free(t);
    /* nor is an input, even one thorax wrote */
    const char *own = tl_path("own.svg");
    CHECK_OK(ctx, thx_ecg_plot_write(ctx, s, NULL, own, NULL, 0));
    const char *in[1] = {own};
    CHECK(thx_ecg_plot_write(ctx, s, NULL, own, in, 1) != THX_OK);
    CHECK(tl_leftover_tmp("bad") == 0 && tl_leftover_tmp("mine") == 0 && tl_leftover_tmp("own") == 0);
    thx_series_destroy(&s);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_ecg_plot")) return 1;
    test_svg();
    test_png();
    test_refusals();
    int rc = tl_scratch_finish("test_ecg_plot");
    thx_ctx_destroy(&ctx);
    return rc;
}
