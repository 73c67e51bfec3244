/*
 * thorax/leads/activation.h — activation and recovery times from electrograms (leads layer; the
 * isochrone maps of paper 4.2 are drawn from them).
 *
 * Activation time: the time of the steepest downstroke (most negative dV/dt) of each row of a time
 * series, the field's standard for unipolar electrograms (the intrinsic deflection). Recovery
 * time: the time of the steepest upstroke (largest dV/dt) of the T wave after it (Wyatt et al.
 * 1981), whatever the T wave's polarity (as Coronel et al. 2006 found it to track repolarization
 * in both).
 *
 * Method: a derivative at each sample i, from the samples i - h .. i + h (h = half_width):
 *   THX_DERIV_SAVGOL   the slope of the least-squares line through them (for equal steps the
 *                      Savitzky-Golay first derivative of a quadratic or linear fit: sum k v[i+k] /
 *                      (dt sum k^2)): smooths as it differentiates;
 *   THX_DERIV_CENTRED  (v[i+h] - v[i-h]) / (t[i+h] - t[i-h]).
 * A derivative whose window holds a NaN or infinite value is not a number and is skipped. The
 * extreme derivative sample in the search window is refined to a fraction of a sample by the
 * parabola through it and its two neighbours (when they are numbers and the parabola has its
 * extreme there; the offset is limited to half a sample), and the time interpolated on the time
 * axis. The derivative is attributed to the centre sample: the time axis should be about uniform.
 *
 * A row whose steepest downstroke in the window is not steeper than -min_slope (a flat row, a row
 * of NaN, fewer than 2 h + 1 numbers) has NaN as its activation time, and then NaN as its recovery
 * time; likewise a recovery whose steepest upstroke is not steeper than +min_slope.
 */
#ifndef THORAX_LEADS_ACTIVATION_H
#define THORAX_LEADS_ACTIVATION_H

#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { THX_DERIV_SAVGOL = 0, THX_DERIV_CENTRED = 1 } thx_deriv_method;

typedef struct {
    thx_deriv_method method; /* default THX_DERIV_SAVGOL */
    int half_width;          /* h >= 1 samples either side (default 2: a 5-sample window) */
    double t0, t1;           /* activation searched at samples with t0 <= time <= t1 (the series' time unit);
                                NaN: from the first or to the last sample (default both NaN) */
    double min_slope;        /* >= 0, value unit per time unit (mV/ms): a downstroke (upstroke) must be
                                steeper than this (default 0) */
    int recovery;            /* 1: also the recovery times, as a second frame (default 0) */
    double rec_t0, rec_t1;   /* recovery searched at samples with rec_t0 <= time <= rec_t1, and after the
                                row's activation time; NaN: from t1 (or the activation time when t1 is
                                NaN), to the last sample (default both NaN). Give the T wave's window. */
} thx_activation_opts;

/* Fills the defaults listed above. */
void thx_activation_opts_default(thx_activation_opts *o);

/*
 * The activation time of each row of s (and its recovery time if o->recovery): a new series of
 * s->n_rows rows and 1 frame (2 with recovery: frame 1 activation, frame 2 recovery), values in
 * s's time unit (unit = s->time_unit, so it can be drawn as an isochrone map), NaN where a row has
 * none; time axis 0, 1 with no unit (the frames are maps, not instants); the label names the
 * method. o NULL: defaults. Rows are independent (computed in parallel; the result does not
 * depend on the thread count). Errors: THX_EINPUT for an invalid series (thx_series_validate),
 * half_width < 1 or more samples than the series has, t0 > t1, rec_t0 > rec_t1, a negative or
 * non-finite min_slope, an unknown method. Caller destroys *out.
 */
thx_status thx_activation_times(thx_ctx *ctx, const thx_series *s, const thx_activation_opts *o, thx_series **out);

/* Where the windows of an activation map came from (thx_activation_window). */
typedef enum {
    THX_WINDOW_GIVEN = 0,     /* the caller's T0:T1 */
    THX_WINDOW_FIDUCIALS = 1, /* the record's global fiducials: qon .. soff (recovery: soff .. toff) */
    THX_WINDOW_RMS = 2,       /* one beat found on the RMS curve of all rows */
    THX_WINDOW_WHOLE = 3      /* the whole series (no beat found: too short or flat) */
} thx_window_source;

typedef struct {
    double t0, t1;         /* activation: the QRS, in the series' time unit */
    double rec_t0, rec_t1; /* recovery: the T wave, after the QRS to the beat's end */
    thx_window_source source;
    char why[96];          /* where from, for a picture: "RMS curve, beat 1 of 2", "fiducials qon-soff",
                              "whole series: no beat on the RMS curve" */
    char rec_why[96];      /* ... of the recovery window: "fiducials soff-toff", else as why */
} thx_activation_window;

/*
 * The window a map3d user expects an activation map to be taken from, never the whole of a
 * multi-beat record: the record's global fiducials qon and soff when it has both (recovery from
 * soff, or stoff, to toff, else to the end); otherwise one beat of the RMS curve of all rows (the
 * square root of the mean square over the rows' finite values at each frame): the beats are the
 * runs of frames above half way from the curve's 10th percentile (its baseline) to its maximum;
 * the first beat whose QRS lies inside the record is taken (else the tallest); its QRS runs from
 * where the curve, going back from the beat's peak, falls under a tenth of the peak's height over
 * the baseline, to the first minimum of the curve (smoothed over 5 frames) after the peak or where
 * it falls under that tenth, whichever comes first; the window is that QRS widened by a quarter of
 * its width on each side (at least 3 frames), kept clear of the other beats. Recovery: from the
 * window's end to the next beat's window (else the record's end). A series too short (fewer than
 * 8 frames) or with no beat (a flat curve) gives the whole series. Errors: an invalid series.
 */
thx_status thx_activation_window_choose(thx_ctx *ctx, const thx_series *s, thx_activation_window *w);

/*
 * The map of the record's own per-row fiducials of type `type` (10 act, 13 rec: map3d's; values
 * frames counted from 0) as times (the series' time axis, linearly interpolated; a value outside
 * the frames is NaN): a new series of s->n_rows rows and one frame, as thx_activation_times gives.
 * Returns THX_OK with *out NULL when s has no such fiducial with one value per row.
 */
thx_status thx_activation_from_fiducials(thx_ctx *ctx, const thx_series *s, int type, thx_series **out);

#ifdef __cplusplus
}
#endif
#endif
