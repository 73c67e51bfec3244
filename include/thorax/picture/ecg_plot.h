/*
 * thorax/picture/ecg_plot.h — the 12-lead ECG on ECG paper, as an SVG (written by thorax itself,
 * no library) or a PNG (through thorax/render/image.h).
 *
 * Layout: the standard 3 x 4 arrangement of a clinical 12-lead printout —
 *     I    aVR  V1  V4
 *     II   aVL  V2  V5
 *     III  aVF  V3  V6
 * — each cell holding its lead over the whole series (a clinical printout shows 2.5 s per column
 * of a continuous recording; a simulated beat is one beat, so every column shows all of it), a
 * 1 mV x 200 ms calibration pulse at the start of each row, the lead's name, and a time axis in ms
 * under the bottom row.
 *
 * Scale: the paper's (AHA; Kligfield et al., Circulation 2007): 25 mm/s and 10 mm/mV by default,
 * a 1 mm grid (0.1 mV by 40 ms) with every fifth line heavier (0.5 mV by 200 ms). In the SVG one
 * user unit is one millimetre (width and height are given in mm), y downwards: a sample v (mV)
 * at time t (ms) of a lead whose cell starts at x0 with its baseline (0 mV) at y0 is drawn at
 * (x0 + (t - t_first) * mm_per_s / 1000, y0 - v * mm_per_mv). Every row's baseline lies on a
 * millimetre line. Each lead is an SVG group <g class="lead" id="lead-NAME" data-x0=".."
 * data-baseline=".."> holding <polyline class="trace"> with every sample (no decimation: the
 * trace's extremes are the series' extremes).
 *
 * Rows of the series: I, II, III, aVR, aVL, aVF, V1..V6 (thorax leads' ecg12 order); unit mV, uV
 * or V (converted to mV), time unit ms or s. Non-finite samples break the trace.
 */
#ifndef THORAX_PICTURE_ECG_PLOT_H
#define THORAX_PICTURE_ECG_PLOT_H
#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/model/series.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double mm_per_mv;  /* gain, default 10 mm/mV */
    double mm_per_s;   /* paper speed, default 25 mm/s */
    double px_per_mm;  /* PNG only: pixels per millimetre, default 6 */
    const char *title; /* a line above the plot (NULL: none) */
    const char *font;  /* PNG only: a TrueType font (NULL: sans-serif through fontconfig) */
} thx_ecg_plot_opts;

void thx_ecg_plot_opts_default(thx_ecg_plot_opts *o);

/* Writes the plot of ecg (12 rows, as above; borrowed) to path, SVG or PNG by its extension
 * (.svg, .png; anything else: THX_EINPUT). Atomic; a file already there is replaced only when it is
 * thorax's own output of that kind, never when it is one of inputs[0..n_inputs) (thorax/core/
 * fileio.h). o NULL: the defaults. Errors (THX_EINPUT) name the series' label: not 12 rows, an
 * unknown unit, a time unit other than ms or s. */
thx_status thx_ecg_plot_write(thx_ctx *ctx, const thx_series *ecg, const thx_ecg_plot_opts *o, const char *path,
                              const char *const *inputs, size_t n_inputs);

#ifdef __cplusplus
}
#endif
#endif
