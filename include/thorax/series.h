/*
 * thorax/series.h — time series: a rows x frames matrix of values (one row per
 * node or lead, one column per time instant) with a time axis and units.
 *
 * Storage is column-major, as MATLAB stores a rows x frames matrix: the
 * values of frame f are contiguous, v[f * n_rows + r], so one frame is one
 * right-hand side or one coloured map.
 *
 * Files (docs/formats.md, "Time series"):
 *   text  (.txt)  a small header (rows, frames, unit, time axis), one line
 *                 per row, an `end` line so truncation is detected;
 *   raw   (.raw)  a fixed binary header (magic, version, sizes, units)
 *                 followed by little-endian float64 times and values;
 *   MATLAB (.mat) through libmatio. Written as top-level variables
 *                 `potvals` (rows x frames double), `time` (1 x frames),
 *                 `unit`, `time_unit`, `label` (char). Read: the variable
 *                 named after a colon ("file.mat:name"), else `potvals`, else
 *                 the first struct holding a `potvals` field (map3d's
 *                 recordings, unit from its `unit` field), else the first
 *                 2-D numeric matrix; any numeric class is converted to double.
 *                 MATLAB 5/7 files only (v7.3 HDF5 and v4 are refused); the
 *                 whole file is checked before libmatio reads it (every
 *                 variable's data against its dimensions, nothing cut short
 *                 or left over, a compressed variable within 1032 times its
 *                 compressed size: src/io/series_matcheck.c).
 * Readers accept a file whole or not at all: every count is checked against
 * the file's size before anything is allocated (memory stays a small multiple
 * of the file's size), and a NUL byte, a truncation, trailing bytes or a
 * partial row, frame or variable is an error naming the file, the line or
 * byte offset, and the object.
 * Values may be NaN (a missing lead); thx_series_find_nonfinite reports them,
 * callers that cannot use them (solvers) reject them.
 */
#ifndef THORAX_SERIES_H
#define THORAX_SERIES_H

#include <stddef.h>

#include "thorax/core.h"

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

typedef enum {
    THX_SERIES_AUTO = 0, /* by extension: .txt/.dat text, .raw raw, .mat MATLAB, .pot map3d; reading also sniffs content */
    THX_SERIES_TEXT,
    THX_SERIES_RAW,
    THX_SERIES_MAT,
    THX_SERIES_POT       /* map3d .pot, read only: one value per node (whitespace separated), one frame */
} thx_series_format;

/* A zeroed rows x frames series with time[f] = f (ms), unit "". */
thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out);
/* Frees the series; accepts NULL; nulls *s. */
void thx_series_destroy(thx_series **s);

/* The format to write: format_name ("text", "raw", "mat") if given, else path's extension (.txt, .dat,
 * .raw, .mat). 0, or -1 if neither names a format that can be written. */
int thx_series_output_format(const char *format_name, const char *path, thx_series_format *fmt);

/* Reads a series; errors name the file (and line, for text) and what is wrong. */
thx_status thx_series_read(thx_ctx *ctx, const char *path, thx_series_format fmt, thx_series **out);
/* Writes atomically (nothing half-written on failure). */
thx_status thx_series_write(thx_ctx *ctx, const thx_series *s, const char *path, thx_series_format fmt);

/* Number of NaN/Inf values; the first one's row and frame (0-based) when any. */
size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame);

/* Parses "text", "raw", "mat" or "auto"; returns -1 for anything else. */
int thx_series_format_parse(const char *name, thx_series_format *fmt);

#ifdef __cplusplus
}
#endif
#endif
