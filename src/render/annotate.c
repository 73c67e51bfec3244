/*
 * 2D annotation on a thx_raster (thorax/image.h): text, lines, rectangles,
 * the colour bar and the signal trace.
 *
 * Geometry: pixel (i, j) is the unit square [i, i + 1) x [j, j + 1), its centre
 * at (i + 0.5, j + 0.5); y grows downwards. Lines are capsules (segments with
 * round ends) whose coverage of a pixel is estimated from the distance d of
 * its centre to the segment: clamp(w / 2 + 0.5 - d, 0, 1) — a one-pixel
 * ramp at the edge, which is what makes them antialiased. Polylines take the
 * largest coverage of their segments per pixel, so joints are not blended twice.
 *
 * Blending is "over" on non-premultiplied 8-bit RGBA, in sRGB values (as
 * every 2D library does): on an opaque destination, dst = src a + dst (1 - a).
 *
 * Text: FreeType renders each glyph as an 8-bit coverage bitmap (antialiased,
 * hinted), placed at the pen rounded to whole pixels. The default face is the
 * one fontconfig chooses for "sans-serif" (DejaVu Sans on Debian with
 * fonts-dejavu-core). Each thx_font holds its own FreeType library, so fonts
 * may be used in different threads, but one font by one thread at a time.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include "thorax/render/image.h"
struct thx_font {
    FT_Library lib;
    FT_Face face;
    int px;
    int ascender;  /* pixels above the baseline */
    int descender; /* pixels below the baseline (>= 0) */
    int digit_h;   /* height of the digit '0' above the baseline (centres labels on ticks) */
    char path[1024];
};

/* ------------------------------------------------------------- pixels */

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

/* Blends rgba over the pixel d with the given coverage in [0, 1]. */
static void blend(unsigned char *d, const unsigned char rgba[4], double cov)
{
    double a = rgba[3] / 255.0 * cov;
    if (!(a > 0)) return;
    double da = d[3] / 255.0, oa = a + da * (1 - a);
    for (int k = 0; k < 3; k++) d[k] = (unsigned char)lround((rgba[k] * a + d[k] * da * (1 - a)) / oa);
    d[3] = (unsigned char)lround(255 * oa);
}

/* A clip rectangle [x0, x1) x [y0, y1), always within the image. */
typedef struct {
    int x0, y0, x1, y1;
} clip_rect;

/* The box (x, y, w, h) clipped to the image (empty when they do not meet). */
static clip_rect clip_box(const thx_raster *img, long x, long y, long w, long h)
{
    clip_rect c = {0, 0, 0, 0};
    long x1 = x + w, y1 = y + h;
    c.x0 = (int)(x < 0 ? 0 : x > img->w ? img->w : x);
    c.y0 = (int)(y < 0 ? 0 : y > img->h ? img->h : y);
    c.x1 = (int)(x1 < c.x0 ? c.x0 : x1 > img->w ? img->w : x1);
    c.y1 = (int)(y1 < c.y0 ? c.y0 : y1 > img->h ? img->h : y1);
    return c;
}

static clip_rect whole(const thx_raster *img) { return clip_box(img, 0, 0, img->w, img->h); }

static void blend_at(thx_raster *img, const clip_rect *c, int i, int j, const unsigned char rgba[4], double cov)
{
    if (i < c->x0 || j < c->y0 || i >= c->x1 || j >= c->y1) return;
    blend(img->rgba + 4 * ((size_t)j * img->w + i), rgba, cov);
}

void thx_draw_rect(thx_raster *img, int x, int y, int w, int h, const unsigned char rgba[4])
{
    if (!img || w <= 0 || h <= 0) return;
    clip_rect c = clip_box(img, x, y, w, h);
    for (int j = c.y0; j < c.y1; j++)
        for (int i = c.x0; i < c.x1; i++) blend(img->rgba + 4 * ((size_t)j * img->w + i), rgba, 1);
}

/* ------------------------------------------------------------- lines */

/* Distance from (px, py) to the segment (x0, y0)-(x1, y1). */
static double seg_dist(double px, double py, double x0, double y0, double x1, double y1)
{
    double dx = x1 - x0, dy = y1 - y0, l2 = dx * dx + dy * dy;
    double s = l2 > 0 ? clamp01(((px - x0) * dx + (py - y0) * dy) / l2) : 0;
    double ex = px - (x0 + s * dx), ey = py - (y0 + s * dy);
    return sqrt(ex * ex + ey * ey);
}

/* Coverage of a pixel centre at distance d from the spine of a line of the given width. */
static double line_cov(double d, double width)
{
    return width >= 1 ? clamp01(width / 2 + 0.5 - d) : width * clamp01(1 - d);
}

/* The pixel range [*a, *b) touched by [lo, hi], within [n0, n1). Returns 0 if empty. */
static int pixel_span(double lo, double hi, int n0, int n1, int *a, int *b)
{
    if (!(hi >= n0) || !(lo < n1)) return 0;
    *a = lo < n0 ? n0 : (int)floor(lo);
    *b = hi >= n1 ? n1 : (int)floor(hi) + 1;
    return *a < *b;
}

/* Where a capsule's coverage goes: the pixels of the clip rectangle, blended at once (m NULL) or
   kept in m (one float per pixel of the rectangle, row by row) as the largest so far. */
typedef struct {
    clip_rect c;
    float *m;
} cov_sink;

static void capsule(thx_raster *img, cov_sink *sink, double x0, double y0, double x1, double y1, double width,
                    const unsigned char rgba[4])
{
    if (!isfinite(x0) || !isfinite(y0) || !isfinite(x1) || !isfinite(y1) || !(width > 0)) return;
    double r = (width >= 1 ? width / 2 : 0.5) + 1;
    const clip_rect *c = &sink->c;
    int i0, i1, j0, j1;
    if (!pixel_span(fmin(x0, x1) - r, fmax(x0, x1) + r, c->x0, c->x1, &i0, &i1)) return;
    if (!pixel_span(fmin(y0, y1) - r, fmax(y0, y1) + r, c->y0, c->y1, &j0, &j1)) return;
    for (int j = j0; j < j1; j++)
        for (int i = i0; i < i1; i++) {
            double cov = line_cov(seg_dist(i + 0.5, j + 0.5, x0, y0, x1, y1), width);
            if (cov <= 0) continue;
            if (!sink->m) {
                blend(img->rgba + 4 * ((size_t)j * img->w + i), rgba, cov);
            } else {
                float *p = sink->m + (size_t)(j - c->y0) * (size_t)(c->x1 - c->x0) + (size_t)(i - c->x0);
                if (cov > *p) *p = (float)cov;
            }
        }
}

void thx_draw_line(thx_raster *img, double x0, double y0, double x1, double y1, double width,
                   const unsigned char rgba[4])
{
    if (!img) return;
    cov_sink sink = {whole(img), NULL};
    capsule(img, &sink, x0, y0, x1, y1, width, rgba);
}

/* A line drawn only inside the clip rectangle. */
static void line_in(thx_raster *img, const clip_rect *c, double x0, double y0, double x1, double y1, double width,
                    const unsigned char rgba[4])
{
    cov_sink sink = {*c, NULL};
    capsule(img, &sink, x0, y0, x1, y1, width, rgba);
}

/* A polyline through (x[i], y[i]) drawn inside the clip rectangle. A non-finite point breaks the
   line; a finite point with no finite neighbour is drawn as a dot. */
static void polyline(thx_raster *img, const clip_rect *c, const double *x, const double *y, size_t n, double width,
                     const unsigned char rgba[4])
{
    int bw = c->x1 - c->x0, bh = c->y1 - c->y0;
    if (bw <= 0 || bh <= 0 || n == 0) return;
    cov_sink sink = {*c, calloc((size_t)bw * (size_t)bh, sizeof(float))};
    if (!sink.m) return; /* nothing to report from a drawing call; the picture lacks the trace */
    for (size_t i = 0; i < n; i++) {
        int ok = isfinite(x[i]) && isfinite(y[i]);
        int next = i + 1 < n && isfinite(x[i + 1]) && isfinite(y[i + 1]);
        int prev = i > 0 && isfinite(x[i - 1]) && isfinite(y[i - 1]);
        if (ok && next) capsule(img, &sink, x[i], y[i], x[i + 1], y[i + 1], width, rgba);
        else if (ok && !prev) capsule(img, &sink, x[i], y[i], x[i], y[i], width, rgba);
    }
    for (int j = 0; j < bh; j++)
        for (int i = 0; i < bw; i++) {
            float cov = sink.m[(size_t)j * bw + i];
            if (cov > 0) blend(img->rgba + 4 * ((size_t)(c->y0 + j) * img->w + (c->x0 + i)), rgba, cov);
        }
    free(sink.m);
}

/* ------------------------------------------------------------- fonts */

/* The file of the sans-serif face fontconfig prefers (scalable), in a private configuration so no
   fontconfig state outlives the call. */
static thx_status find_sans(thx_ctx *ctx, char *file, size_t size, int *index)
{
    FcConfig *cfg = FcInitLoadConfigAndFonts();
    if (!cfg) return thx_error(ctx, THX_EIO, "fontconfig: cannot load its configuration");
    thx_status st = THX_OK;
    FcPattern *pat = FcNameParse((const FcChar8 *)"sans-serif");
    FcPattern *match = NULL;
    FcChar8 *f = NULL;
    if (!pat) {
        st = thx_error(ctx, THX_ENOMEM, "fontconfig: out of memory");
        goto done;
    }
    FcPatternAddBool(pat, FC_SCALABLE, FcTrue);
    FcConfigSubstitute(cfg, pat, FcMatchPattern);
    FcDefaultSubstitute(pat);
    FcResult res;
    match = FcFontMatch(cfg, pat, &res);
    if (!match || FcPatternGetString(match, FC_FILE, 0, &f) != FcResultMatch || !f || !f[0]) {
        st = thx_error(ctx, THX_EIO,
                       "no sans-serif font found through fontconfig: install one (Debian: fonts-dejavu-core) "
                       "or give a font file");
        goto done;
    }
    if (strlen((const char *)f) >= size) {
        st = thx_error(ctx, THX_EIO, "%s: font path too long", (const char *)f);
        goto done;
    }
    snprintf(file, size, "%s", (const char *)f);
    if (FcPatternGetInteger(match, FC_INDEX, 0, index) != FcResultMatch) *index = 0;
done:
    if (match) FcPatternDestroy(match);
    if (pat) FcPatternDestroy(pat);
    FcConfigDestroy(cfg);
    return st;
}

thx_status thx_font_open(thx_ctx *ctx, const char *path, int px, thx_font **out)
{
    *out = NULL;
    if (px < 1 || px > 2048) return thx_error(ctx, THX_EINPUT, "font size %d pixels: must be 1 to 2048", px);
    thx_font *f = thx_calloc(ctx, 1, sizeof *f);
    if (!f) return THX_ENOMEM;
    thx_status st = THX_OK;
    int index = 0;
    if (path) {
        struct stat sb;
        if (stat(path, &sb) != 0) {
            st = thx_error(ctx, THX_EIO, "%s: cannot open font: %s", path, strerror(errno));
            goto fail;
        }
        if (strlen(path) >= sizeof f->path) {
            st = thx_error(ctx, THX_EIO, "%s: font path too long", path);
            goto fail;
        }
        snprintf(f->path, sizeof f->path, "%s", path);
    } else {
        st = find_sans(ctx, f->path, sizeof f->path, &index);
        if (st != THX_OK) goto fail;
    }
    FT_Error e = FT_Init_FreeType(&f->lib);
    if (e) {
        st = thx_error(ctx, THX_EINTERNAL, "FreeType cannot start (error 0x%02x)", (unsigned)e);
        goto fail;
    }
    e = FT_New_Face(f->lib, f->path, index, &f->face);
    if (e) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a font FreeType can read (error 0x%02x)", f->path, (unsigned)e);
        goto fail;
    }
    e = FT_Set_Pixel_Sizes(f->face, 0, (FT_UInt)px);
    if (e) {
        st = thx_error(ctx, THX_EINPUT, "%s: no %d-pixel size in this font (error 0x%02x)", f->path, px, (unsigned)e);
        goto fail;
    }
    f->px = px;
    const FT_Size_Metrics *m = &f->face->size->metrics;
    f->ascender = (int)((m->ascender + 63) >> 6);
    f->descender = (int)((-m->descender + 63) >> 6);
    if (f->descender < 0) f->descender = 0;
    f->digit_h = (f->ascender * 3) / 4;
    if (FT_Load_Char(f->face, '0', FT_LOAD_DEFAULT) == 0)
        f->digit_h = (int)((f->face->glyph->metrics.horiBearingY + 32) >> 6);
    *out = f;
    return THX_OK;
fail:
    thx_font_close(&f);
    return st;
}

void thx_font_close(thx_font **f)
{
    if (!f || !*f) return;
    if ((*f)->face) FT_Done_Face((*f)->face);
    if ((*f)->lib) FT_Done_FreeType((*f)->lib);
    free(*f);
    *f = NULL;
}

int thx_font_height(const thx_font *f) { return f ? f->ascender + f->descender : 0; }

/* The next code point of a UTF-8 string (advancing *s); U+FFFD for a malformed sequence. */
static uint32_t utf8_next(const char **s)
{
    const unsigned char *p = (const unsigned char *)*s;
    uint32_t c = p[0];
    int n = c < 0x80 ? 0 : (c >> 5) == 6 ? 1 : (c >> 4) == 14 ? 2 : (c >> 3) == 30 ? 3 : -1;
    if (n < 0) {
        *s += 1;
        return 0xFFFD;
    }
    c &= n == 0 ? 0x7F : (0x3F >> n);
    for (int i = 1; i <= n; i++) {
        if ((p[i] & 0xC0) != 0x80) {
            *s += i;
            return 0xFFFD;
        }
        c = (c << 6) | (p[i] & 0x3F);
    }
    *s += n + 1;
    static const uint32_t min[4] = {0, 0x80, 0x800, 0x10000};
    if (c < min[n] || c > 0x10FFFF || (c >= 0xD800 && c <= 0xDFFF)) return 0xFFFD;
    return c;
}

/* Copies a glyph's coverage bitmap, its top-left at (x, y), blended in rgba. */
static void blit_glyph(thx_raster *img, const clip_rect *clip, const FT_Bitmap *bm, int x, int y,
                       const unsigned char rgba[4])
{
    if (bm->pixel_mode != FT_PIXEL_MODE_GRAY && bm->pixel_mode != FT_PIXEL_MODE_MONO) return;
    const unsigned char *top = bm->pitch < 0 ? bm->buffer - (ptrdiff_t)(bm->rows - 1) * bm->pitch : bm->buffer;
    double scale = bm->num_grays > 1 ? 1.0 / (bm->num_grays - 1) : 1.0;
    for (unsigned r = 0; r < bm->rows; r++) {
        const unsigned char *row = top + (ptrdiff_t)r * bm->pitch;
        for (unsigned c = 0; c < bm->width; c++) {
            double cov = bm->pixel_mode == FT_PIXEL_MODE_MONO ? ((row[c >> 3] >> (7 - (c & 7))) & 1)
                                                              : row[c] * scale;
            if (cov > 0) blend_at(img, clip, x + (int)c, y + (int)r, rgba, cov);
        }
    }
}

/* Lays out a string from pen position x on baseline y: draws it inside the clip rectangle when img
   is given, and returns its advance width in pixels. Missing glyphs come out as the font's .notdef
   box. */
static int layout(thx_font *f, const char *s, thx_raster *img, const clip_rect *clip, int x, int y,
                  const unsigned char rgba[4])
{
    if (!f || !s) return 0;
    FT_Face face = f->face;
    FT_Pos pen = 0; /* 26.6 */
    FT_UInt prev = 0;
    int kern = FT_HAS_KERNING(face);
    while (*s) {
        uint32_t cp = utf8_next(&s);
        FT_UInt gi = FT_Get_Char_Index(face, cp);
        if (kern && prev && gi) {
            FT_Vector d;
            if (FT_Get_Kerning(face, prev, gi, FT_KERNING_DEFAULT, &d) == 0) pen += d.x;
        }
        if (FT_Load_Glyph(face, gi, img ? FT_LOAD_RENDER : FT_LOAD_DEFAULT) != 0) {
            prev = 0;
            continue;
        }
        FT_GlyphSlot g = face->glyph;
        if (img) {
            int gx = x + (int)((pen + 32) >> 6) + g->bitmap_left;
            blit_glyph(img, clip, &g->bitmap, gx, y - g->bitmap_top, rgba);
        }
        pen += g->advance.x;
        prev = gi;
    }
    return (int)((pen + 32) >> 6);
}

int thx_text_width(thx_font *f, const char *utf8) { return layout(f, utf8, NULL, NULL, 0, 0, NULL); }

void thx_draw_text(thx_raster *img, thx_font *f, int x, int y, const char *utf8, const unsigned char rgba[4])
{
    if (!img) return;
    clip_rect c = whole(img);
    layout(f, utf8, img, &c, x, y, rgba);
}

/* ------------------------------------------------------------- colour bar */

/* Mean luminance in [0, 1] of the image in a box (transparent pixels count as white: an image with
   a transparent background will most likely be put on a page). 1 when the box is outside. */
static double mean_luminance(const thx_raster *img, int x, int y, int w, int h)
{
    double sum = 0;
    long n = 0;
    for (int j = y < 0 ? 0 : y; j < y + h && j < img->h; j++)
        for (int i = x < 0 ? 0 : x; i < x + w && i < img->w; i++) {
            const unsigned char *p = img->rgba + 4 * ((size_t)j * img->w + i);
            double a = p[3] / 255.0, l = (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) / 255.0;
            sum += a * l + (1 - a);
            n++;
        }
    return n ? sum / n : 1;
}

/* Black on a light background, white on a dark one. */
static void ink_for(const thx_raster *img, int x, int y, int w, int h, unsigned char ink[4])
{
    unsigned char v = mean_luminance(img, x, y, w, h) > 0.5 ? 0 : 255;
    ink[0] = ink[1] = ink[2] = v;
    ink[3] = 255;
}

/* A value for a label: "%.3g", with rounding noise around zero shown as 0 (never "-0"). */
static void format_value(char *buf, size_t size, double v, double range)
{
    if (fabs(v) < 1e-9 * range) v = 0;
    double a = fabs(v);
    if (a >= 1e3 && a < 1e6) { /* 12600 rather than 1.26e+04: three significant digits, no exponent */
        double q = pow(10, floor(log10(a)) - 2);
        snprintf(buf, size, "%.0f", round(v / q) * q + 0.0);
        return;
    }
    snprintf(buf, size, "%.3g", v + 0.0);
}

/* The tick of the value at t beside the strip, and its label (text NULL: the tick alone). */
static void bar_label(thx_raster *img, thx_font *f, int vertical, int x, int y, int w, int h, double t,
                      const char *text, const unsigned char ink[4])
{
    if (vertical) {
        int row = y + h - (int)lround(t * h);
        if (row > y + h - 1) row = y + h - 1;
        thx_draw_rect(img, x + w + 1, row, 4, 1, ink);
        if (f && text) thx_draw_text(img, f, x + w + 7, row + f->digit_h / 2, text, ink);
    } else {
        int col = x + (int)lround(t * w);
        if (col > x + w - 1) col = x + w - 1;
        thx_draw_rect(img, col, y + h + 1, 1, 4, ink);
        if (f && text) thx_draw_text(img, f, col - thx_text_width(f, text) / 2, y + h + 7 + f->digit_h, text, ink);
    }
}

/* What a colour bar labels: n values at t = i / (n - 1), or a lab scale's levels at t = (j + 1) /
   (n_lev + 1); and whether a SEPARATE mapping's zero needs a label of its own. */
typedef struct {
    int lab, n_lev;
    double lev[2 * 13 + 1];
    int zero_extra;
} bar_marks;

static void bar_marks_of(const thx_scale *s, int n_labels, bar_marks *m)
{
    m->lab = s->model == THX_SCALE_LAB7 || s->model == THX_SCALE_LAB13;
    m->n_lev = m->lab ? thx_scale_levels(s, 0, m->lev, 2 * 13 + 1) : 0;
    if (m->n_lev > 2 * 13 + 1) m->n_lev = 2 * 13 + 1;
    int has_middle = m->lab || (n_labels == 1 || (n_labels > 1 && (n_labels - 1) % 2 == 0));
    m->zero_extra = s->mapping == THX_MAPPING_SEPARATE && !has_middle;
}

/*
 * Layout: (x, y, w, h) is the strip of colour itself. Along its length t runs linearly from 0 (the
 * bottom of a vertical bar, the left of a horizontal one) to 1; the label at t reads the value
 * thx_scale_invert(s, t), so under a log or exp model the labels are unevenly spaced values. Labels
 * are at t = i / (n_labels - 1) with a 4-pixel tick, to the right of a vertical bar or below a
 * horizontal one; a lab scale ticks each of its levels (at t = j / n, the band boundaries) and
 * labels every k-th of them counted from the middle one, k the least that keeps the labels apart.
 * A SEPARATE mapping's zero (t = 0.5, where the two sides' scales meet) gets a line of ink across
 * the strip and a label "0". The title, followed by the unit in parentheses, is above the strip.
 * Text and the frame are black or white, whichever contrasts with the image where the labels go.
 * With no font only the strip, its frame and the ticks are drawn.
 */
void thx_draw_colorbar(thx_raster *img, thx_font *f, int x, int y, int w, int h, thx_colormap c, const thx_scale *s,
                       int n_shades, int n_labels, const char *title, const char *unit)
{
    if (!img || !s || w <= 0 || h <= 0) return;
    int vertical = h > w;
    int len = vertical ? h : w;
    int fh = thx_font_height(f);
    double range = fmax(fabs(s->lo), fabs(s->hi));
    bar_marks mk;
    bar_marks_of(s, n_labels, &mk);
    int widest = 0;
    if (f) {
        char text[64];
        if (mk.lab) {
            for (int j = 0; j < mk.n_lev; j++) {
                format_value(text, sizeof text, mk.lev[j], range);
                int tw = thx_text_width(f, text);
                widest = tw > widest ? tw : widest;
            }
        } else if (vertical) {
            for (int i = 0; i < n_labels; i++) {
                format_value(text, sizeof text, thx_scale_invert(s, n_labels > 1 ? (double)i / (n_labels - 1) : 0.5),
                             range);
                int tw = thx_text_width(f, text);
                widest = tw > widest ? tw : widest;
            }
        }
        if (mk.zero_extra && thx_text_width(f, "0") > widest) widest = thx_text_width(f, "0");
    }
    if (vertical && f) {
        /* labels that would run off the right edge move the whole bar left */
        int over = x + w + 7 + widest - (img->w - 2);
        if (over > 0) x = x - over > 1 ? x - over : 1;
    }

    /* Choose the ink before drawing anything, from where the labels and title will go. */
    unsigned char ink[4];
    if (vertical) ink_for(img, x + w, y - fh, 6 * fh + 8, h + 2 * fh, ink);
    else ink_for(img, x, y - fh - 4, w, h + 2 * fh + 12, ink);

    int n_bands = n_shades > 0 ? thx_scale_bands(s, n_shades) : 0;
    for (int p = 0; p < len; p++) {
        double t = (p + 0.5) / len;
        if (n_bands > 0) t = thx_scale_band(t, n_bands);
        unsigned char col[4] = {0, 0, 0, 255};
        thx_colormap_eval(c, t, col);
        if (vertical) thx_draw_rect(img, x, y + h - 1 - p, w, 1, col);
        else thx_draw_rect(img, x + p, y, 1, h, col);
    }
    /* frame just outside the strip */
    thx_draw_rect(img, x - 1, y - 1, w + 2, 1, ink);
    thx_draw_rect(img, x - 1, y + h, w + 2, 1, ink);
    thx_draw_rect(img, x - 1, y, 1, h, ink);
    thx_draw_rect(img, x + w, y, 1, h, ink);
    if (s->mapping == THX_MAPPING_SEPARATE) { /* the zero, where the two sides' scales meet */
        if (vertical) {
            int row = y + h - (int)lround(0.5 * h);
            thx_draw_rect(img, x, row > y + h - 1 ? y + h - 1 : row, w, 1, ink);
        } else {
            int col = x + (int)lround(0.5 * w);
            thx_draw_rect(img, col > x + w - 1 ? x + w - 1 : col, y, 1, h, ink);
        }
    }

    char text[64];
    if (mk.lab) {
        int n = mk.n_lev + 1, stride = 1;
        if (f) {
            double room = (double)len / n, need = vertical ? f->digit_h + 4 : widest + 8;
            while (stride < n && stride * room < need) stride++;
        }
        for (int j = 0; j < mk.n_lev; j++) {
            int shown = (j - mk.n_lev / 2) % stride == 0;
            format_value(text, sizeof text, mk.lev[j], range);
            bar_label(img, f, vertical, x, y, w, h, thx_scale_apply(s, mk.lev[j]), shown ? text : NULL, ink);
        }
    } else {
        for (int i = 0; i < n_labels; i++) {
            double t = n_labels > 1 ? (double)i / (n_labels - 1) : 0.5;
            format_value(text, sizeof text, thx_scale_invert(s, t), range);
            bar_label(img, f, vertical, x, y, w, h, t, text, ink);
        }
    }
    if (mk.zero_extra) bar_label(img, f, vertical, x, y, w, h, 0.5, "0", ink);

    if (!f) return;
    char head[512];
    int has_title = title && title[0], has_unit = unit && unit[0];
    if (has_title && has_unit) snprintf(head, sizeof head, "%s (%s)", title, unit);
    else snprintf(head, sizeof head, "%s", has_title ? title : has_unit ? unit : "");
    if (!head[0]) return;
    /* The title is above the strip and kept inside the image: beside a vertical strip it is split
     * into two lines (the title, then the unit) when one line would run off the right edge; a line
     * still too long is moved left. */
    /* (beside a vertical strip the top value's label reaches half a digit above it) */
    int base = y - 4 - f->descender - (vertical ? f->digit_h / 2 : 0), width = thx_text_width(f, head);
    if (vertical && has_title && has_unit && x + width > img->w - 2) {
        char u[64];
        snprintf(u, sizeof u, "(%s)", unit);
        int wt = thx_text_width(f, title), wu = thx_text_width(f, u);
        int tt = x + wt > img->w - 2 ? img->w - 2 - wt : x, tu = x + wu > img->w - 2 ? img->w - 2 - wu : x;
        thx_draw_text(img, f, tt < 0 ? 0 : tt, base - thx_font_height(f), title, ink);
        thx_draw_text(img, f, tu < 0 ? 0 : tu, base, u, ink);
        return;
    }
    int tx = vertical ? x : x + (w - width) / 2;
    if (tx + width > img->w - 2) tx = img->w - 2 - width;
    if (tx < 0) tx = 0;
    thx_draw_text(img, f, tx, base, head, ink);
}

/* ------------------------------------------------------------- signal trace */

/*
 * Layout in the box (x, y, w, h), inset by 2 pixels: a header row (the label at the left, the
 * range of the finite values and the unit at the right) and a footer row (the first and last times)
 * when a font is given and the box has room, the plot between them. The plot's vertical range
 * holds zero and every finite value, with 5% to spare above and below (-1.05 to 1.05 when there
 * is nothing but zero). Sample i sits at x = px + 0.5 + i (pw - 1) / (n - 1), value v at
 * y = py + 0.5 + (hi - v) / (hi - lo) (ph - 1), with (px, py, pw, ph) the plot. The zero line and
 * the left axis are drawn at half the trace's opacity, the marker line at 60% (these three one
 * pixel wide, on the pixel centres nearest their place), the trace 1.5 pixels wide, the marker's
 * dot 6 pixels across, on the trace. Everything, text included, is clipped to the box.
 */
void thx_draw_trace(thx_raster *img, thx_font *f, int x, int y, int w, int h, const double *v, size_t n, double t0,
                    double dt, size_t marker, const char *label, const char *unit, const unsigned char rgba[4])
{
    if (!img || w <= 0 || h <= 0) return;
    const int pad = 2;
    int fh = thx_font_height(f);
    int head = f ? fh + 2 : 0, foot = f && n > 0 ? fh + 2 : 0;
    if (h - 2 * pad - head - foot < 8) head = foot = 0; /* too small for text */
    int px = x + pad, py = y + pad + head, pw = w - 2 * pad, ph = h - 2 * pad - head - foot;
    if (pw < 2 || ph < 2) return;
    clip_rect box = clip_box(img, x, y, w, h);

    double vmin = INFINITY, vmax = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (isfinite(v[i])) vmin = fmin(vmin, v[i]), vmax = fmax(vmax, v[i]);
    double lo = fmin(0, vmin), hi = fmax(0, vmax);
    if (!(hi > lo)) lo = -1, hi = 1;
    double spare = 0.05 * (hi - lo);
    lo -= spare, hi += spare;
#define TRACE_X(i) (px + 0.5 + (n > 1 ? (double)(i) * (pw - 1) / (double)(n - 1) : (pw - 1) / 2.0))
#define TRACE_Y(val) (py + 0.5 + (hi - (val)) / (hi - lo) * (ph - 1))

    unsigned char faint[4] = {rgba[0], rgba[1], rgba[2], (unsigned char)(rgba[3] / 2)};
    /* Axis and marker lines sit on pixel centres so they come out crisp, one pixel wide. */
    double y0 = floor(TRACE_Y(0.0)) + 0.5;
    line_in(img, &box, px, y0, px + pw, y0, 1, faint);             /* zero line: the time axis */
    line_in(img, &box, px + 0.5, py, px + 0.5, py + ph, 1, faint); /* the value axis */

    if (n > 0) {
        double *xy = malloc(2 * n * sizeof *xy);
        if (xy) {
            for (size_t i = 0; i < n; i++) {
                xy[i] = TRACE_X(i);
                xy[n + i] = isfinite(v[i]) ? TRACE_Y(v[i]) : NAN;
            }
            polyline(img, &box, xy, xy + n, n, 1.5, rgba);
            free(xy);
        }
    }
    if (marker < n) {
        unsigned char mk[4] = {rgba[0], rgba[1], rgba[2], (unsigned char)(rgba[3] * 3 / 5)};
        double mx = floor(TRACE_X(marker)) + 0.5;
        line_in(img, &box, mx, py, mx, py + ph, 1, mk);
        double dx = TRACE_X(marker), dy = TRACE_Y(v[marker]);
        if (isfinite(v[marker])) line_in(img, &box, dx, dy, dx, dy, 6, rgba);
    }
#undef TRACE_X
#undef TRACE_Y

    if (!f || head == 0) return;
    int base = y + pad + f->ascender;
    if (label && label[0]) layout(f, label, img, &box, px, base, rgba);
    char text[160], a[32], b[32];
    if (vmin <= vmax) {
        double range = fmax(fabs(vmin), fabs(vmax));
        format_value(a, sizeof a, vmin, range);
        format_value(b, sizeof b, vmax, range);
        snprintf(text, sizeof text, "%s to %s%s%s", a, b, unit && unit[0] ? " " : "", unit ? unit : "");
    } else {
        snprintf(text, sizeof text, "%s", unit ? unit : "");
    }
    if (text[0]) layout(f, text, img, &box, px + pw - thx_text_width(f, text), base, rgba);
    if (foot) {
        double t1 = t0 + (double)(n - 1) * dt, range = fmax(fabs(t0), fabs(t1));
        format_value(a, sizeof a, t0, range);
        format_value(b, sizeof b, t1, range);
        int fb = y + h - pad - f->descender;
        layout(f, a, img, &box, px, fb, rgba);
        if (n > 1) layout(f, b, img, &box, px + pw - thx_text_width(f, b), fb, rgba);
    }
}
