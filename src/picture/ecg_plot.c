/*
 * The 12-lead ECG on ECG paper (thorax/picture/ecg_plot.h): one layout in millimetres, drawn by
 * one set of calls into either an SVG file (text, one user unit = 1 mm) or an image (pixels =
 * mm x px_per_mm) written as PNG.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/picture/ecg_plot.h"
#include "thorax/render/image.h"
#include "picture/plot_pen.h"

#define SVG_MARKER "thorax-ecg-plot"

static const char *const LEAD[12] = {"I", "II", "III", "aVR", "aVL", "aVF", "V1", "V2", "V3", "V4", "V5", "V6"};

/* margins and strips, mm */
#define M_LEFT 10.0  /* the calibration pulses */
#define M_RIGHT 5.0
#define GAP 5.0      /* between columns */
#define PAD 3.0      /* above and below the traces in a row */
#define AXIS 12.0    /* the time axis and the scale line under the bottom row */

void thx_ecg_plot_opts_default(thx_ecg_plot_opts *o)
{
    memset(o, 0, sizeof *o);
    o->mm_per_mv = 10.0;
    o->mm_per_s = 25.0;
    o->px_per_mm = 8.0;
}

typedef struct {
    double gain, speed;     /* mm/mV, mm/s */
    double vk, tk;          /* the series' units to mV and ms */
    double t0, dur;         /* ms */
    double cell_w;          /* mm */
    double x0[4];           /* each column's left edge (time t0) */
    double base[3];         /* each row's baseline (0 mV), on a mm line */
    double rtop[3];         /* each row's top edge */
    double top, W, H;       /* the title strip's height; the paper's size */
    double tstep;           /* ms between time labels */
} layout;

static double ceil_to(double v, double step) { return step * ceil(v / step - 1e-9); }

static thx_status make_layout(thx_ctx *ctx, const thx_series *s, const thx_ecg_plot_opts *o, layout *L)
{
    const char *what = s->label[0] ? s->label : "(no label)";
    if (s->n_rows != 12)
        return thx_error(ctx, THX_EINPUT,
                         "ECG plot: series \"%s\" has %zu rows; a 12-lead ECG has 12 (I, II, III, aVR, aVL, aVF, "
                         "V1..V6, as thorax leads writes ecg12)",
                         what, s->n_rows);
    if (!strcmp(s->unit, "mV")) L->vk = 1.0;
    else if (!strcmp(s->unit, "uV") || !strcmp(s->unit, "\xc2\xb5V")) L->vk = 1e-3;
    else if (!strcmp(s->unit, "V")) L->vk = 1e3;
    else
        return thx_error(ctx, THX_EINPUT, "ECG plot: series \"%s\" has unit \"%s\"; the plot needs mV, uV or V", what,
                         s->unit);
    if (!strcmp(s->time_unit, "ms")) L->tk = 1.0;
    else if (!strcmp(s->time_unit, "s")) L->tk = 1e3;
    else
        return thx_error(ctx, THX_EINPUT, "ECG plot: series \"%s\" has time unit \"%s\"; the plot needs ms or s", what,
                         s->time_unit);
    if (!(o->mm_per_mv > 0) || !(o->mm_per_s > 0) || !isfinite(o->mm_per_mv) || !isfinite(o->mm_per_s))
        return thx_error(ctx, THX_EINPUT, "ECG plot: gain %g mm/mV and speed %g mm/s must be positive", o->mm_per_mv,
                         o->mm_per_s);
    L->gain = o->mm_per_mv;
    L->speed = o->mm_per_s;
    L->t0 = s->time[0] * L->tk;
    L->dur = (s->time[s->n_frames - 1] - s->time[0]) * L->tk;
    L->cell_w = ceil_to(fmax(L->dur * L->speed / 1000.0, 10.0), 5.0);
    if (L->cell_w > 1e5)
        return thx_error(ctx, THX_EINPUT, "ECG plot: series \"%s\" lasts %g ms: %g mm of paper a column is too long",
                         what, L->dur, L->cell_w);
    for (int c = 0; c < 4; c++) L->x0[c] = M_LEFT + c * (L->cell_w + GAP);
    L->top = o->title && o->title[0] ? 10.0 : 5.0;
    double y = L->top;
    for (int r = 0; r < 3; r++) {
        double hi = 0, lo = 0;
        for (int c = 0; c < 4; c++) {
            size_t row = (size_t)(3 * c + r);
            for (size_t f = 0; f < s->n_frames; f++) {
                double v = s->v[f * s->n_rows + row] * L->vk;
                if (isfinite(v)) {
                    hi = fmax(hi, v);
                    lo = fmin(lo, v);
                }
            }
        }
        double up = ceil(fmax(hi * L->gain, 10.0) - 1e-9); /* room for the 1 mV pulse */
        double down = -lo * L->gain;
        if (up + down > 1e5)
            return thx_error(ctx, THX_EINPUT, "ECG plot: series \"%s\": %g mV is too large to plot at %g mm/mV", what,
                             fmax(hi, -lo), L->gain);
        L->rtop[r] = y;
        L->base[r] = y + PAD + up;
        y += ceil_to(2 * PAD + up + down, 5.0);
    }
    L->W = L->x0[3] + L->cell_w + M_RIGHT;
    L->H = y + AXIS;
    /* time labels at least 5 mm apart: 100, 200, 500, 1000 ... ms */
    static const double steps[] = {1, 2, 5};
    L->tstep = 100;
    for (double dec = 100;; dec *= 10) {
        int found = 0;
        for (int k = 0; k < 3 && !found; k++)
            if (steps[k] * dec * L->speed / 1000.0 >= 5.0) {
                L->tstep = steps[k] * dec;
                found = 1;
            }
        if (found || dec > 1e9) break;
    }
    return THX_OK;
}

/* ------------------------------------------------------------------ the two pens */

static const plot_rgb GRID_MINOR = {0xf4, 0xc4, 0xc4}, GRID_MAJOR = {0xe0, 0x7c, 0x7c}, INK = {0, 0, 0},
                      TEXT = {0x30, 0x30, 0x30};

static void line(plot_pen *p, double x0, double y0, double x1, double y1, double w, plot_rgb c)
{
    plot_line(p, x0, y0, x1, y1, w, c);
}

/* Text with its baseline at y (mm); anchor 0 start, 1 middle, 2 end (SVG: 3.2 and 2.4 mm fonts). */
static void text(plot_pen *p, double x, double y, int big, int anchor, const char *t)
{
    plot_text(p, x, y, big, anchor, t, p->svg ? (plot_rgb){0, 0, 0} : TEXT, 3.2, 2.4);
}

/* One lead: its samples from (x0, base), a break at every non-finite one. */
static void trace(plot_pen *p, const layout *L, const thx_series *s, size_t row, double x0, double base)
{
    size_t n = s->n_frames;
    if (p->svg) {
        fprintf(p->svg, "<g class=\"lead\" id=\"lead-%s\" data-x0=\"%.3f\" data-baseline=\"%.3f\">\n", LEAD[row], x0,
                base);
        int open = 0;
        for (size_t f = 0; f < n; f++) {
            double v = s->v[f * s->n_rows + row] * L->vk;
            if (!isfinite(v)) {
                if (open) fputs("\"/>\n", p->svg);
                open = 0;
                continue;
            }
            double x = x0 + (s->time[f] * L->tk - L->t0) * L->speed / 1000.0, y = base - v * L->gain;
            if (!open)
                fprintf(p->svg, "<polyline class=\"trace\" fill=\"none\" stroke=\"#000000\" stroke-width=\"0.3\" "
                                "stroke-linejoin=\"round\" points=\"");
            fprintf(p->svg, "%s%.3f,%.3f", open ? " " : "", x, y);
            open = 1;
        }
        if (open) fputs("\"/>\n", p->svg);
        fputs("</g>\n", p->svg);
        return;
    }
    double px = 0, py = 0;
    int have = 0;
    for (size_t f = 0; f < n; f++) {
        double v = s->v[f * s->n_rows + row] * L->vk;
        if (!isfinite(v)) {
            have = 0;
            continue;
        }
        double x = x0 + (s->time[f] * L->tk - L->t0) * L->speed / 1000.0, y = base - v * L->gain;
        if (have) line(p, px, py, x, y, 0.3, INK);
        else if (n == 1) line(p, x, y, x + 0.2, y, 0.3, INK);
        px = x;
        py = y;
        have = 1;
    }
}

static void draw(plot_pen *p, const layout *L, const thx_series *s, const char *title)
{
    double bottom = L->H - AXIS;
    /* the grid over the whole sheet: 1 mm, every fifth line heavier */
    int nx = (int)floor(L->W + 1e-9), ny = (int)floor(L->H + 1e-9);
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i <= nx; i++)
            if ((i % 5 == 0) == pass) line(p, i, 0, i, L->H, pass ? 0.2 : 0.08, pass ? GRID_MAJOR : GRID_MINOR);
        for (int j = 0; j <= ny; j++)
            if ((j % 5 == 0) == pass) line(p, 0, j, L->W, j, pass ? 0.2 : 0.08, pass ? GRID_MAJOR : GRID_MINOR);
    }
    if (title && title[0]) text(p, M_LEFT, 6.5, 0, 0, title);
    char buf[160];
    for (int r = 0; r < 3; r++) {
        /* the calibration pulse: 1 mV for 200 ms, at the row's start */
        double b = L->base[r], x = 2.0, w = 0.2 * L->speed, h = L->gain;
        line(p, x - 1.0, b, x, b, 0.3, INK);
        line(p, x, b, x, b - h, 0.3, INK);
        line(p, x, b - h, x + w, b - h, 0.3, INK);
        line(p, x + w, b - h, x + w, b, 0.3, INK);
        line(p, x + w, b, x + w + 1.0, b, 0.3, INK);
        for (int c = 0; c < 4; c++) {
            size_t row = (size_t)(3 * c + r);
            trace(p, L, s, row, L->x0[c], b);
            text(p, L->x0[c] + 0.5, L->rtop[r] + 3.2, 1, 0, LEAD[row]);
        }
    }
    /* the time axis under each column, ms from the series' first sample */
    for (int c = 0; c < 4; c++)
        for (double t = 0; t <= L->dur + 1e-9; t += L->tstep) {
            double x = L->x0[c] + t * L->speed / 1000.0;
            line(p, x, bottom, x, bottom + 1.2, 0.2, INK);
            snprintf(buf, sizeof buf, "%g", t + L->t0);
            text(p, x, bottom + 4.0, 0, 1, buf);
        }
    snprintf(buf, sizeof buf, "time (ms)   %g mm/s, %g mm/mV; small squares %g ms x %g mV", L->speed, L->gain,
             1000.0 / L->speed, 1.0 / L->gain);
    text(p, M_LEFT, bottom + 8.5, 0, 0, buf);
}

/* ------------------------------------------------------------------ writers */

static thx_status write_svg(thx_ctx *ctx, const layout *L, const thx_series *s, const char *title, const char *path,
                            const char *const *inputs, size_t n_inputs)
{
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(ctx, path, SVG_MARKER, sizeof SVG_MARKER - 1, inputs, n_inputs, &af));
    FILE *f = af.f;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- " SVG_MARKER
               ": the 12-lead ECG, 1 user unit = 1 mm -->\n");
    fprintf(f,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.1fmm\" height=\"%.1fmm\" viewBox=\"0 0 %.1f %.1f\" "
            "font-family=\"sans-serif\" data-mm-per-mv=\"%g\" data-mm-per-s=\"%g\" data-t0=\"%g\">\n",
            L->W, L->H, L->W, L->H, L->gain, L->speed, L->t0);
    fprintf(f, "<rect x=\"0\" y=\"0\" width=\"%.1f\" height=\"%.1f\" fill=\"#ffffff\"/>\n", L->W, L->H);
    plot_pen p = {.svg = f};
    draw(&p, L, s, title);
    fputs("</svg>\n", f);
    return thx_atomic_commit(ctx, &af);
}

static thx_status write_png(thx_ctx *ctx, const layout *L, const thx_series *s, const thx_ecg_plot_opts *o,
                            const char *path)
{
    double k = o->px_per_mm;
    if (!(k >= 1 && k <= 50))
        return thx_error(ctx, THX_EINPUT, "ECG plot %s: %g pixels per mm is outside 1..50", path, k);
    int w = (int)ceil(L->W * k), h = (int)ceil(L->H * k);
    if ((double)w * h > 1e8)
        return thx_error(ctx, THX_EINPUT, "ECG plot %s: %d x %d pixels is too large; give fewer pixels per mm", path, w,
                         h);
    thx_raster *img = NULL;
    thx_font *fb = NULL, *fs = NULL;
    THX_CHECK(thx_raster_create(ctx, w, h, &img));
    static const unsigned char white[4] = {255, 255, 255, 255};
    thx_raster_fill(img, white);
    thx_status st = thx_font_open(ctx, o->font, (int)lround(3.2 * k), &fb);
    if (st == THX_OK) st = thx_font_open(ctx, o->font, (int)lround(2.4 * k), &fs);
    if (st == THX_OK) {
        plot_pen p = {.img = img, .fbig = fb, .fsmall = fs, .s = k};
        draw(&p, L, s, o->title);
        st = thx_raster_write_png(ctx, img, path);
    }
    thx_font_close(&fb);
    thx_font_close(&fs);
    thx_raster_destroy(&img);
    return st;
}

static int ends_with(const char *s, const char *ext)
{
    size_t n = strlen(s), m = strlen(ext);
    if (n < m) return 0;
    for (size_t i = 0; i < m; i++)
        if (tolower((unsigned char)s[n - m + i]) != ext[i]) return 0;
    return 1;
}

thx_status thx_ecg_plot_write(thx_ctx *ctx, const thx_series *ecg, const thx_ecg_plot_opts *o, const char *path,
                              const char *const *inputs, size_t n_inputs)
{
    thx_ecg_plot_opts def;
    if (!o) {
        thx_ecg_plot_opts_default(&def);
        o = &def;
    }
    int svg = ends_with(path, ".svg"), png = ends_with(path, ".png");
    if (!svg && !png)
        return thx_error(ctx, THX_EINPUT, "ECG plot %s: give a file ending in .svg or .png", path);
    THX_CHECK(thx_series_validate(ctx, ecg, path));
    layout L;
    memset(&L, 0, sizeof L);
    THX_CHECK(make_layout(ctx, ecg, o, &L));
    return svg ? write_svg(ctx, &L, ecg, o->title, path, inputs, n_inputs) : write_png(ctx, &L, ecg, o, path);
}
