/* The L-curve as a PNG (thorax/picture/lcurve_plot.h), through the plots' pen (plot_pen.h). */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "picture/plot_pen.h"
#include "thorax/picture/lcurve_plot.h"

void thx_lcurve_plot_opts_default(thx_lcurve_plot_opts *o)
{
    memset(o, 0, sizeof *o);
    o->width = 800;
    o->height = 600;
}

/* the bold curve: the series' or the representative frame's (n points) */
static void bold_curve(const thx_inverse_report *r, const double **res, const double **sem)
{
    *res = r->curve_residual;
    *sem = r->curve_seminorm;
    if (r->mark_frame < 0) return;
    for (size_t j = 0; j < r->n_frame_curves; j++)
        if (r->frame_curve_frame[j] == (size_t)r->mark_frame) {
            *res = r->frame_curve_residual + j * r->n_curve;
            *sem = r->frame_curve_seminorm + j * r->n_curve;
        }
}

static void extend(double rho, double eta, double *b)
{
    double x = log10(rho), y = log10(eta);
    if (!isfinite(x) || !isfinite(y)) return;
    b[0] = fmin(b[0], x);
    b[1] = fmax(b[1], x);
    b[2] = fmin(b[2], y);
    b[3] = fmax(b[3], y);
}

thx_status thx_lcurve_plot_axes(thx_ctx *ctx, const thx_inverse_report *r, const thx_lcurve_plot_opts *o,
                                thx_lcurve_axes *ax)
{
    thx_lcurve_plot_opts def;
    if (!o) {
        thx_lcurve_plot_opts_default(&def);
        o = &def;
    }
    if (!r->n_curve || !r->curve_residual) return thx_error(ctx, THX_EINPUT, "L-curve picture: the report has no curve");
    double b[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    const double *res, *sem;
    bold_curve(r, &res, &sem);
    for (size_t i = 0; i < r->n_curve; i++) extend(res[i], sem[i], b);
    for (size_t i = 0; i < r->n_frame_curves * r->n_curve; i++)
        extend(r->frame_curve_residual[i], r->frame_curve_seminorm[i], b);
    extend(r->mark_residual, r->mark_seminorm, b);
    extend(r->mark_corner_residual, r->mark_corner_seminorm, b);
    if (!(b[1] >= b[0]) || !(b[3] >= b[2]))
        return thx_error(ctx, THX_EINPUT, "L-curve picture: the curve has no point with a finite, positive residual "
                                          "and norm");
    ax->lx0 = floor(b[0]);
    ax->lx1 = ceil(b[1]);
    ax->ly0 = floor(b[2]);
    ax->ly1 = ceil(b[3]);
    if (ax->lx1 == ax->lx0) ax->lx0 -= 1, ax->lx1 += 1;
    if (ax->ly1 == ax->ly0) ax->ly0 -= 1, ax->ly1 += 1;
    ax->left = 95;
    ax->right = o->width - 30;
    ax->top = 80;
    ax->bottom = o->height - 75;
    return THX_OK;
}

static double px(const thx_lcurve_axes *a, double rho)
{
    return a->left + (log10(rho) - a->lx0) / (a->lx1 - a->lx0) * (a->right - a->left);
}

static double py(const thx_lcurve_axes *a, double eta)
{
    return a->bottom - (log10(eta) - a->ly0) / (a->ly1 - a->ly0) * (a->bottom - a->top);
}

static const plot_rgb INK = {0, 0, 0}, TEXT = {0x30, 0x30, 0x30}, GRID = {0xdd, 0xdd, 0xdd},
                      FAINT = {0xc6, 0xd4, 0xea}, BOLD = {0x1f, 0x4e, 0x9c}, MARK = {0xd6, 0x27, 0x28},
                      CORNER = {0xff, 0x7f, 0x0e};

static void polyline(plot_pen *p, const thx_lcurve_axes *a, const double *res, const double *sem, size_t n, double w,
                     plot_rgb c)
{
    int have = 0;
    double x0 = 0, y0 = 0;
    for (size_t i = 0; i < n; i++) {
        if (!(res[i] > 0) || !(sem[i] > 0) || !isfinite(res[i]) || !isfinite(sem[i])) {
            have = 0;
            continue;
        }
        double x = px(a, res[i]), y = py(a, sem[i]);
        if (have) plot_line(p, x0, y0, x, y, w, c);
        x0 = x, y0 = y, have = 1;
    }
}

static void decade_label(char *buf, size_t n, double e)
{
    snprintf(buf, n, "1e%d", (int)e);
}

static void draw(plot_pen *p, const thx_inverse_report *r, const thx_lcurve_plot_opts *o, const thx_lcurve_axes *a)
{
    char buf[320];
    /* the grid: a line and a label per decade (or per few decades) */
    int sx = (int)ceil((a->lx1 - a->lx0) / 10.0), sy = (int)ceil((a->ly1 - a->ly0) / 10.0);
    for (double e = a->lx0; e <= a->lx1 + 1e-9; e += 1) {
        double x = a->left + (e - a->lx0) / (a->lx1 - a->lx0) * (a->right - a->left);
        plot_line(p, x, a->top, x, a->bottom, 1, GRID);
        if ((int)lround(e - a->lx0) % sx == 0) {
            decade_label(buf, sizeof buf, e);
            plot_text(p, x, a->bottom + 20, 0, 1, buf, TEXT, 15, 13);
        }
    }
    for (double e = a->ly0; e <= a->ly1 + 1e-9; e += 1) {
        double y = a->bottom - (e - a->ly0) / (a->ly1 - a->ly0) * (a->bottom - a->top);
        plot_line(p, a->left, y, a->right, y, 1, GRID);
        if ((int)lround(e - a->ly0) % sy == 0) {
            decade_label(buf, sizeof buf, e);
            plot_text(p, a->left - 8, y + 5, 0, 2, buf, TEXT, 15, 13);
        }
    }
    /* the curves: the frames' faint, the bold one over them */
    for (size_t j = 0; j < r->n_frame_curves; j++)
        if (r->frame_curve_frame[j] != (size_t)r->mark_frame)
            polyline(p, a, r->frame_curve_residual + j * r->n_curve, r->frame_curve_seminorm + j * r->n_curve,
                     r->n_curve, 1, FAINT);
    const double *res, *sem;
    bold_curve(r, &res, &sem);
    polyline(p, a, res, sem, r->n_curve, 2.5, BOLD);
    /* the box */
    plot_line(p, a->left, a->top, a->right, a->top, 1, INK);
    plot_line(p, a->left, a->bottom, a->right, a->bottom, 1, INK);
    plot_line(p, a->left, a->top, a->left, a->bottom, 1, INK);
    plot_line(p, a->right, a->top, a->right, a->bottom, 1, INK);
    /* the corner and the λ used */
    int corner = r->mark_corner_residual > 0 && r->mark_corner_seminorm > 0 && isfinite(r->mark_corner_residual) &&
                 isfinite(r->mark_corner_seminorm);
    int mark = r->mark_residual > 0 && r->mark_seminorm > 0 && isfinite(r->mark_residual) && isfinite(r->mark_seminorm);
    if (corner) {
        double x = px(a, r->mark_corner_residual), y = py(a, r->mark_corner_seminorm);
        plot_ring(p, x, y, 10, 2, CORNER);
        snprintf(buf, sizeof buf, "corner \xce\xbb = %.3g", r->mark_corner_lambda);
        plot_text(p, x - 14, y + 24, 0, 2, buf, TEXT, 15, 13);
    }
    if (mark) {
        double x = px(a, r->mark_residual), y = py(a, r->mark_seminorm);
        plot_disc(p, x, y, 6, MARK);
        snprintf(buf, sizeof buf, "\xce\xbb = %.3g", r->mark_lambda);
        plot_text(p, x + 12, y - 10, 1, 0, buf, TEXT, 15, 13);
    }
    /* titles and axis names */
    plot_text(p, o->width / 2.0, 26, 1, 1, o->title && o->title[0] ? o->title : "L-curve", INK, 15, 13);
    const char *rule = o->rule && o->rule[0] ? o->rule : "the rule";
    if (r->mark_frame >= 0) {
        int comp = r->n_components > 0;
        snprintf(buf, sizeof buf, "bold: %s %ld of %zu (largest ||b||), \xce\xbb by %s; faint: %zu %s spread evenly",
                 comp ? "temporal component" : "frame", r->mark_frame + 1, comp ? r->n_components : r->n_frames, rule,
                 r->n_frame_curves - 1, comp ? "other components" : "other frames");
    } else if (r->n_components > 0)
        snprintf(buf, sizeof buf, "the curve of the %zu temporal components summed, one \xce\xbb by %s",
                 r->n_components, rule);
    else
        snprintf(buf, sizeof buf, "the series' curve (%zu frames summed), one \xce\xbb by %s", r->n_frames, rule);
    plot_text(p, o->width / 2.0, 50, 0, 1, buf, TEXT, 15, 13);
    plot_text(p, (a->left + a->right) / 2, o->height - 22, 0, 1, "residual norm ||A x - b||", INK, 15, 13);
    plot_text(p, a->left - 8, a->top - 10, 0, 0, "solution (semi)norm ||L x||", INK, 15, 13);
    /* the legend, bottom left inside the box */
    double lx = a->left + 14, ly = a->bottom - 16;
    plot_disc(p, lx, ly - 5, 5, MARK);
    plot_text(p, lx + 12, ly, 0, 0, "the \xce\xbb used", TEXT, 15, 13);
    plot_ring(p, lx + 110, ly - 5, 7, 2, CORNER);
    plot_text(p, lx + 122, ly, 0, 0, "maximum curvature", TEXT, 15, 13);
}

static int ends_with_png(const char *s)
{
    size_t n = strlen(s);
    return n >= 4 && s[n - 4] == '.' && tolower((unsigned char)s[n - 3]) == 'p' &&
           tolower((unsigned char)s[n - 2]) == 'n' && tolower((unsigned char)s[n - 1]) == 'g';
}

thx_status thx_lcurve_plot_write(thx_ctx *ctx, const thx_inverse_report *r, const thx_lcurve_plot_opts *o,
                                 const char *path)
{
    thx_lcurve_plot_opts def;
    if (!o) {
        thx_lcurve_plot_opts_default(&def);
        o = &def;
    }
    if (!ends_with_png(path)) return thx_error(ctx, THX_EINPUT, "L-curve picture %s: give a file ending in .png", path);
    if (o->width < 320 || o->height < 240 || o->width > 8000 || o->height > 8000)
        return thx_error(ctx, THX_EINPUT, "L-curve picture %s: %d x %d pixels is outside 320 x 240 .. 8000 x 8000", path,
                         o->width, o->height);
    thx_lcurve_axes a;
    THX_CHECK(thx_lcurve_plot_axes(ctx, r, o, &a));
    thx_raster *img = NULL;
    thx_font *fb = NULL, *fs = NULL;
    THX_CHECK(thx_raster_create(ctx, o->width, o->height, &img));
    static const unsigned char white[4] = {255, 255, 255, 255};
    thx_raster_fill(img, white);
    thx_status st = thx_font_open(ctx, o->font, 16, &fb);
    if (st == THX_OK) st = thx_font_open(ctx, o->font, 14, &fs);
    if (st == THX_OK) {
        plot_pen p = {.img = img, .fbig = fb, .fsmall = fs, .s = 1};
        draw(&p, r, o, &a);
        st = thx_raster_write_png(ctx, img, path);
    }
    thx_font_close(&fb);
    thx_font_close(&fs);
    thx_raster_destroy(&img);
    return st;
}
