/*
 * thorax/picture/lcurve_plot.h — the L-curve of an inverse solution as a PNG picture (paper 4.1,
 * the inverse problem; issue 15: "a picture of the L-curve"), drawn from the figures
 * thx_inverse_solve returns (thorax/inverse/inverse.h, thx_inverse_report) through the same pen
 * as the 12-lead ECG plot (src/picture/plot_pen.c).
 *
 * What it shows: log-log axes, the residual norm ||A x - b|| across, the solution's (semi)norm
 * ||L x|| up, a grid line and a label at every decade (every second, third ... decade when more
 * than ten). One λ for the series: the series' curve (summed over frames; Greensite: over the
 * temporal components), bold. A λ per frame:
 * the curves of up to THX_INVERSE_FRAME_CURVES frames spread over the series, faint, and the
 * representative frame's (the frame with the largest ||b||; report->mark_frame), bold. On the bold
 * curve: the λ used, a filled red disc at the solution's (||A x - b||, ||L x||), labelled
 * "λ = …"; the curve's maximum-curvature corner, an orange ring labelled "corner λ = …". Above the
 * plot: the title, and a line naming the rule, the λ and which curve is bold.
 *
 * The axis mapping (thx_lcurve_plot_axes; tests check a picture's marks against it): the plot box
 * is [left, right] x [top, bottom] in pixels (x to the right, y down, pixel (i, j) covering
 * [i, i+1) x [j, j+1)); its ends are whole decades, lx0 = floor(min log10 ρ) .. lx1 =
 * ceil(max log10 ρ) and likewise ly0 .. ly1 for η, over every finite point drawn (the curves, the
 * mark, the corner); a span of zero decades widens to one on each side. A point (ρ, η) is drawn at
 *   x = left + (log10 ρ - lx0) / (lx1 - lx0) (right - left),
 *   y = bottom - (log10 η - ly0) / (ly1 - ly0) (bottom - top).
 */
#ifndef THORAX_PICTURE_LCURVE_PLOT_H
#define THORAX_PICTURE_LCURVE_PLOT_H
#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/inverse/inverse.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int width, height;  /* pixels, default 800 x 600 (at least 320 x 240) */
    const char *title;  /* the first line (NULL: "L-curve") */
    const char *rule;   /* the λ rule's name for the second line (NULL: none) */
    const char *font;   /* a TrueType font (NULL: sans-serif through fontconfig) */
} thx_lcurve_plot_opts;

void thx_lcurve_plot_opts_default(thx_lcurve_plot_opts *o);

typedef struct {
    double left, right, top, bottom; /* the plot box, pixels */
    double lx0, lx1, ly0, ly1;       /* its ends, log10 of ρ (across) and η (up) */
} thx_lcurve_axes;

/* The mapping above for report r (borrowed) drawn with o (NULL: defaults). THX_EINPUT when the
 * report has no curve or no finite point on it. */
thx_status thx_lcurve_plot_axes(thx_ctx *ctx, const thx_inverse_report *r, const thx_lcurve_plot_opts *o,
                                thx_lcurve_axes *ax);

/* Writes the picture of r as a PNG to path (atomic; a file there is replaced only when it is
 * thorax's own PNG). Errors: THX_EINPUT as for thx_lcurve_plot_axes, a size out of range, a path
 * not ending in .png; the font's and the file's errors. */
thx_status thx_lcurve_plot_write(thx_ctx *ctx, const thx_inverse_report *r, const thx_lcurve_plot_opts *o,
                                 const char *path);

#ifdef __cplusplus
}
#endif
#endif
