/*
 * thorax/render/image.h — images, colour maps, scaling models, and 2D annotation
 * (text, colour bars, signal traces) for the renderer (paper 4.2,
 * "Standards"). Everything here is CPU-side and needs no OpenGL: the 3D
 * renderer (thorax/render/render.h) draws into a thx_image, the annotations are
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
} thx_image;

thx_status thx_image_create(thx_ctx *ctx, int w, int h, thx_image **out);
void thx_image_destroy(thx_image **img);
void thx_image_fill(thx_image *img, const unsigned char rgba[4]);
/* The tEXt chunk thorax writes in every PNG ("Software" = "thorax"): an existing file is replaced
 * only when it has it (thorax/core/fileio.h, thx_atomic_open_output). */
#define THX_PNG_MARKER "Software\0thorax"
/* PNG through libpng, 8-bit RGBA (or RGB when every alpha is 255); atomic; an existing file is
 * replaced only when thorax's own (above), never through a link. */
thx_status thx_image_write_png(thx_ctx *ctx, const thx_image *img, const char *path);
thx_status thx_image_read_png(thx_ctx *ctx, const char *path, thx_image **out);

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

/* ---- scaling models (paper 4.2: linear, exponential, logarithmic) ----
 * With c = (lo + hi) / 2, h = (hi - lo) / 2 and u = (v - c) / h clamped to [-1, 1]:
 *   linear: u' = u
 *   log:    u' = sign(u) log(1 + k |u|) / log(1 + k)     (expands small values)
 *   exp:    u' = sign(u) (exp(k |u|) - 1) / (exp(k) - 1) (expands large values)
 * and t = (u' + 1) / 2. A symmetric mapping has lo = -hi (zero at t = 0.5). */
typedef enum { THX_SCALE_LINEAR = 0, THX_SCALE_LOG, THX_SCALE_EXP } thx_scale_model;

typedef struct {
    thx_scale_model model;
    double lo, hi;   /* the values mapped to t = 0 and t = 1 */
    double k;        /* strength of log/exp (default 10 for log, 3 for exp) */
} thx_scale;

/* Limits from data: lo/hi the min/max of the finite values in v (n), or -M/M with M the largest
 * magnitude when symmetric. All-NaN or empty data: -1/1. */
void thx_scale_from_data(thx_scale *s, thx_scale_model model, const double *v, size_t n, int symmetric);
/* t in [0, 1] for a value (NaN stays NaN). */
double thx_scale_apply(const thx_scale *s, double v);
/* The value whose t is t (the inverse; for labels). */
double thx_scale_invert(const thx_scale *s, double t);
/* Quantized to n bands: (floor(t n) + 0.5) / n, the last band closed. */
double thx_scale_band(double t, int n);

/* ---- 2D annotation ---- */
typedef struct thx_font thx_font;

/* A font through FreeType; path NULL = the default sans-serif face found by fontconfig. Error
 * naming what is missing. px: the pixel height. */
thx_status thx_font_open(thx_ctx *ctx, const char *path, int px, thx_font **out);
void thx_font_close(thx_font **f);
int thx_font_height(const thx_font *f);
int thx_text_width(thx_font *f, const char *utf8);
/* Text with its baseline at y, alpha-blended. */
void thx_draw_text(thx_image *img, thx_font *f, int x, int y, const char *utf8, const unsigned char rgba[4]);
/* Antialiased line of the given width (pixels), alpha-blended. */
void thx_draw_line(thx_image *img, double x0, double y0, double x1, double y1, double width, const unsigned char rgba[4]);
/* Filled rectangle, alpha-blended. */
void thx_draw_rect(thx_image *img, int x, int y, int w, int h, const unsigned char rgba[4]);

/* A colour bar in the box (x, y, w, h): the map under the scale (n_shades > 0: that many discrete
 * bands, 0: continuous), n_labels labelled values (printf "%.3g") with the unit, a title above;
 * vertical when h > w (low values at the bottom), else horizontal. The box is the colour strip
 * itself: labels go to its right (vertical) or below it (horizontal), "title (unit)" above it, in
 * black or white, whichever contrasts with the image there. f NULL: no text. */
void thx_draw_colorbar(thx_image *img, thx_font *f, int x, int y, int w, int h, thx_colormap c, const thx_scale *s,
                       int n_shades, int n_labels, const char *title, const char *unit);

/* A signal trace in the box (x, y, w, h): values v[0..n) against time t0 + i dt, axes with a zero
 * line, a label (e.g. "II") and the unit, and a marker (vertical line and dot) at sample `marker`
 * (none when marker >= n). Non-finite samples leave gaps. Nothing is drawn outside the box;
 * f NULL: no text. */
void thx_draw_trace(thx_image *img, thx_font *f, int x, int y, int w, int h, const double *v, size_t n, double t0,
                    double dt, size_t marker, const char *label, const char *unit, const unsigned char rgba[4]);

#ifdef __cplusplus
}
#endif
#endif
