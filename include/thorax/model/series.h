/*
 * thorax/model/series.h — time series: a rows x frames matrix of values (one row per
 * node or lead, one column per time instant) with a time axis and units (model layer;
 * the files are thorax/io/series_file.h).
 *
 * Storage is column-major, as MATLAB stores a rows x frames matrix: the
 * values of frame f are contiguous, v[f * n_rows + r], so one frame is one
 * right-hand side or one coloured map.
 *
 * Values may be NaN (a missing lead); thx_series_find_nonfinite reports them,
 * callers that cannot use them (solvers) reject them.
 */
#ifndef THORAX_MODEL_SERIES_H
#define THORAX_MODEL_SERIES_H

#include <stddef.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_series {
    size_t n_rows;       /* nodes or leads */
    size_t n_frames;     /* time instants */
    double *v;           /* n_rows * n_frames, column-major: v[f * n_rows + r] */
    double *time;        /* n_frames sample times in time_unit (increasing) */
    char unit[32];       /* unit of the values, e.g. "mV", "uV", "V" ("" = unknown) */
    char time_unit[16];  /* unit of the time axis, "ms" by default */
    char label[128];     /* free text (what the series is, where it came from) */
} thx_series;

/* A zeroed rows x frames series with time[f] = f (ms), unit "". */
thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out);
/* Frees the series; accepts NULL; nulls *s. */
void thx_series_destroy(thx_series **s);

/* The invariants of a series every reader ends with and every writer starts with: values and times
 * present, at least 1 row x 1 frame, unit, time_unit and label NUL-terminated, a finite and strictly
 * increasing time axis. `path` names the file in messages. */
thx_status thx_series_validate(thx_ctx *ctx, const thx_series *s, const char *path);

/* Number of NaN/Inf values; the first one's row and frame (0-based) when any. */
size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame);

#ifdef __cplusplus
}
#endif
#endif
