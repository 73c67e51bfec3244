/*
 * thorax/render/image.h — images, colour maps, scaling models, and 2D annotation
 * (text, colour bars, signal traces) for the renderer (paper 4.2,
 * "Standards"). Everything here is CPU-side and needs no OpenGL: the 3D
 * renderer (thorax/render/render.h) draws into a thx_raster, the annotations are
 * composited on top.
 */
#ifndef THORAX_IMAGE_H
#define THORAX_IMAGE_H

#include <stddef.h>

#include "thorax/core/core.h"
#ifdef __cplusplus
extern "C" {
#endif

/* RGBA, 8 bits per channel, rows top to bottom, not premultiplied. */
typedef struct {
    int w, h;
    unsigned char *rgba; /* 4 w h */
} thx_raster;

thx_status thx_raster_create(thx_ctx *ctx, int w, int h, thx_raster **out);
void thx_raster_destroy(thx_raster **img);
void thx_raster_fill(thx_raster *img, const unsigned char rgba[4]);
/* The tEXt chunk thorax writes in every PNG ("Software" = "thorax"): an existing file is replaced
 * only when it has it (thorax/core/fileio.h, thx_atomic_open_output). */
#define THX_PNG_MARKER "Software\0thorax"
/* PNG through libpng, 8-bit RGBA (or RGB when every alpha is 255); atomic; an existing file is
 * replaced only when thorax's own (above), never through a link. */
thx_status thx_raster_write_png(thx_ctx *ctx, const thx_raster *img, const char *path);
thx_status thx_raster_read_png(thx_ctx *ctx, const char *path, thx_raster **out);

/* ---- colour maps ----
 * ECG: the field's convention (default): negative blue, zero white, positive red.
 * ECG_GREEN: negative green, zero white, positive red (the paper's figures).
 * COOLWARM: Moreland's perceptually uniform diverging map (blue-grey-red).
 * VIRIDIS: perceptually uniform sequential. GRAY. JET: the rainbow, for comparison. */
typedef enum { THX_CMAP_ECG = 0, THX_CMAP_ECG_GREEN, THX_CMAP_COOLWARM, THX_CMAP_VIRIDIS, THX_CMAP_GRAY, THX_CMAP_JET } thx_colormap;

/* "ecg", "ecg-green", "coolwarm", "viridis", "gray", "jet"; -1 if unknown. */
int thx_colormap_parse(const char *name, thx_colormap *out);
const char *thx_colormap_name(thx_colormap c);
/* The colour at t in [0, 1] (clamped); t = 0.5 is the middle (zero for diverging maps). */
void thx_colormap_eval(thx_colormap c, double t, unsigned char rgb[3]);
/* n samples at t = i / (n - 1), 3 n bytes (for a 1D texture). */
void thx_colormap_table(thx_colormap c, int n, unsigned char *rgb);

/* ---- scaling (paper 4.2, "Standards": the scaling model, the mapping, the number of levels) ----
 * A scale maps a value v to t in [0, 1], where the colour map is looked up; the code is
 * src/render/scale.c. Two choices make a scale, as in map3d:
 *
 * The mapping says which range of values spans the colours:
 *   TRUE:      lo..hi as given.
 *   SYMMETRIC: -M..M about zero, M = max(|lo|, |hi|): zero in the middle, both signs alike.
 *   MIDPOINT:  symmetric about the midpoint c = (lo + hi) / 2 of lo..hi.
 *   SEPARATE:  zero in the middle whatever lo and hi: negative values scaled by |lo| onto
 *              t in [0, 0.5], positive values by hi onto [0.5, 1], so zero has the middle colour
 *              even when |lo| != |hi|. A side with no range (lo >= 0, or hi <= 0) takes the other
 *              side's; both empty (lo = hi = 0): a step at zero.
 *
 * The model says how values are spread over t within that range. With a centre c and half widths
 * h (h- below c, h+ above it for SEPARATE), u = (v - c) / h clamped to [-1, 1]:
 *   linear: u' = u
 *   log:    u' = sign(u) log(1 + k |u|) / log(1 + k)     (expands small values)
 *   exp:    u' = sign(u) (exp(k |u|) - 1) / (exp(k) - 1) (expands large values)
 * and t = (u' + 1) / 2; c = (lo + hi) / 2, h = (hi - lo) / 2 for TRUE and MIDPOINT (the same map:
 * these models are odd about the middle of the range), c = 0, h = M for SYMMETRIC, c = 0,
 * h- = |lo|, h+ = hi for SEPARATE. A range of zero or infinite width maps to a step at c.
 *   lab7, lab13: map3d's "lab standard" logarithmic coverage of one decade. The levels are the
 *   series 1, 1.5, 2.2, 3.3, 4.7, 6.8 (lab7) or 1, 1.2, 1.5, 1.8, 2.2, 2.7, 3.3, 3.9, 4.7, 5.6,
 *   6.8, 8.2 (lab13) times powers of ten; on each side of the centre m = 7 (13) of them, going
 *   down from the largest one strictly below that side's half width (data -37..52, lab7,
 *   SYMMETRIC: +-47, 33, 22, 15, 10, 6.8, 4.7, and 0). With the centre that is n - 1 = 2 m + 1
 *   levels and n = 2 m + 2 bands (16, 28), and t is piecewise linear in v with the levels at
 *   uniform steps of t:
 *       t(c - h-) = 0, t(level j, ascending, j = 1 .. n - 1) = j / n, t(c + h+) = 1.
 *   INVARIANT: every lab level falls exactly on a band boundary of thx_scale_band(t, n), so bands
 *   and contour lines drawn at uniform steps of t are the lab levels (tested). TRUE is SEPARATE
 *   when lo < 0 < hi (map3d's levels); over one sign only (0 <= lo < hi, or lo < hi <= 0) it is
 *   the up to m levels of the side of larger magnitude that lie strictly inside lo..hi, lo..hi at
 *   t = 0 and 1, n = levels + 1 bands. The levels are the decimal values (the doubles nearest
 *   to 4.7, 0.68, ...), without map3d's factor 1.0001.
 *   The number of bands is the scale's own (thx_scale_bands): a lab scale ignores the number asked
 *   for, as map3d's does.
 *
 * lo > hi reverses the scale (t -> 1 - t of the scale with lo and hi swapped: the colour map read
 * backwards), under every model and mapping.
 * The default, {model, lo, hi, k} with mapping 0 = TRUE, is the scale as it was before mappings:
 * the same t for the same value. */
typedef enum { THX_SCALE_LINEAR = 0, THX_SCALE_LOG, THX_SCALE_EXP, THX_SCALE_LAB7, THX_SCALE_LAB13 } thx_scale_model;
typedef enum { THX_MAPPING_TRUE = 0, THX_MAPPING_SYMMETRIC, THX_MAPPING_MIDPOINT, THX_MAPPING_SEPARATE } thx_scale_mapping;

typedef struct {
    thx_scale_model model;
    double lo, hi;   /* the range of values (TRUE: mapped to t = 0 and t = 1; see the mapping) */
    double k;        /* strength of log/exp (default 10 for log, 3 for exp; <= 0: the default) */
    thx_scale_mapping mapping;
} thx_scale;

/* "linear", "log", "exp", "lab7", "lab13"; 0, or -1 if unknown (out untouched). */
int thx_scale_model_parse(const char *name, thx_scale_model *out);
const char *thx_scale_model_name(thx_scale_model m); /* "unknown" if out of range */
/* "true", "symmetric", "midpoint", "separate"; 0, or -1 if unknown (out untouched). */
int thx_scale_mapping_parse(const char *name, thx_scale_mapping *out);
const char *thx_scale_mapping_name(thx_scale_mapping m); /* "unknown" if out of range */

/* The one range rule of the colour scales, for a range lo..hi of data (the least and greatest
 * finite values; `thorax render` takes them over the values its --scope covers): s gets the model,
 * the mapping, the model's default k and
 *   no finite value (lo > hi, or not finite): -1..1 (any mapping);
 *   SYMMETRIC: -M..M, M = max(|lo|, |hi|) (data -5..2 gives -5..5); all zeros: -1..1;
 *   SEPARATE: lo..hi as they are (their magnitudes are the two sides' scales); all zeros: -1..1;
 *   TRUE, MIDPOINT: lo..hi; constant data v: v - 1..v + 1 (the value maps to the middle). */
void thx_scale_from_range_mapped(thx_scale *s, thx_scale_model model, thx_scale_mapping mapping, double lo,
                                 double hi);
/* The same over the finite values of v[0..n). */
void thx_scale_from_data_mapped(thx_scale *s, thx_scale_model model, thx_scale_mapping mapping, const double *v,
                                size_t n);
/* The older forms: symmetric nonzero = SYMMETRIC, zero = TRUE. */
void thx_scale_from_range(thx_scale *s, thx_scale_model model, double lo, double hi, int symmetric);
void thx_scale_from_data(thx_scale *s, thx_scale_model model, const double *v, size_t n, int symmetric);

/* t in [0, 1] for a value: monotone in v (non-decreasing; non-increasing when lo > hi), clamped
 * outside the range; NaN stays NaN. */
double thx_scale_apply(const thx_scale *s, double v);
/* The same for n values into float t[0..n) (for vertex buffers): a lab scale's levels are found
 * once, not per value; t[i] = (float)thx_scale_apply(s, v[i]) exactly. */
void thx_scale_apply_n(const thx_scale *s, const double *v, size_t n, float *t);
/* The value whose t is t (t clamped to [0, 1]): the exact inverse of thx_scale_apply inside the
 * range (round trips to rounding); a step (degenerate range) gives its centre. NaN stays NaN. */
double thx_scale_invert(const thx_scale *s, double t);
/* Quantized to n bands: (floor(t n) + 0.5) / n, the last band closed. */
double thx_scale_band(double t, int n);
/* The number of bands to draw: n_requested for linear, log and exp; the lab scale's own for lab7
 * and lab13 (16 or 28 when the range has the centre level; n_requested is ignored). */
int thx_scale_bands(const thx_scale *s, int n_requested);
/* The band boundaries (contour levels) of the scale with thx_scale_bands(s, n_requested) bands,
 * ascending: the values at t = j / n, j = 1 .. n - 1 (lab scales: the lab levels). Writes
 * min(count, max) of them to out (out may be NULL when max is 0) and returns the count n - 1
 * (0 when n_requested < 1 for linear, log and exp). */
int thx_scale_levels(const thx_scale *s, int n_requested, double *out, int max);

/* ---- 2D annotation ---- */
typedef struct thx_font thx_font;

/* A font through FreeType; path NULL = the default sans-serif face found by fontconfig. Error
 * naming what is missing. px: the pixel height. */
thx_status thx_font_open(thx_ctx *ctx, const char *path, int px, thx_font **out);
void thx_font_close(thx_font **f);
int thx_font_height(const thx_font *f);
int thx_text_width(thx_font *f, const char *utf8);
/* Text with its baseline at y, alpha-blended. */
void thx_draw_text(thx_raster *img, thx_font *f, int x, int y, const char *utf8, const unsigned char rgba[4]);
/* Antialiased line of the given width (pixels), alpha-blended. */
void thx_draw_line(thx_raster *img, double x0, double y0, double x1, double y1, double width, const unsigned char rgba[4]);
/* Filled rectangle, alpha-blended. */
void thx_draw_rect(thx_raster *img, int x, int y, int w, int h, const unsigned char rgba[4]);

/* A colour bar in the box (x, y, w, h): the map under the scale (n_shades > 0: discrete bands,
 * thx_scale_bands(s, n_shades) of them; 0: continuous), n_labels labelled values (printf "%.3g") at
 * even steps of t with the unit, a title above; vertical when h > w (low values at the bottom),
 * else horizontal. A lab scale labels its levels instead (ticks at every level; labels on every
 * level, or every second, third ... counted from the middle one, as many as fit), and n_labels is
 * ignored. Under a SEPARATE mapping the zero (t = 0.5) is marked by a line across the strip and
 * labelled "0". The box is the colour strip
 * itself: labels go to its right (vertical) or below it (horizontal), "title (unit)" above it, in
 * black or white, whichever contrasts with the image there. f NULL: no text. */
void thx_draw_colorbar(thx_raster *img, thx_font *f, int x, int y, int w, int h, thx_colormap c, const thx_scale *s,
                       int n_shades, int n_labels, const char *title, const char *unit);

/* A signal trace in the box (x, y, w, h): values v[0..n) against time t0 + i dt, axes with a zero
 * line, a label (e.g. "II") and the unit, and a marker (vertical line and dot) at sample `marker`
 * (none when marker >= n). Non-finite samples leave gaps. Nothing is drawn outside the box;
 * f NULL: no text. */
void thx_draw_trace(thx_raster *img, thx_font *f, int x, int y, int w, int h, const double *v, size_t n, double t0,
                    double dt, size_t marker, const char *label, const char *unit, const unsigned char rgba[4]);

#ifdef __cplusplus
}
#endif
#endif
