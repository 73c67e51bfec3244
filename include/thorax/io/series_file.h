/*
 * thorax/io/series_file.h — time-series files (io layer).
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
 */
#ifndef THORAX_IO_SERIES_FILE_H
#define THORAX_IO_SERIES_FILE_H

#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_SERIES_AUTO = 0, /* by extension: .txt/.dat text, .raw raw, .mat MATLAB, .pot map3d; reading also sniffs content */
    THX_SERIES_TEXT,
    THX_SERIES_RAW,
    THX_SERIES_MAT,
    THX_SERIES_POT       /* map3d .pot, read only: one value per node (whitespace separated), one frame */
} thx_series_format;

/* The format to write: format_name ("text", "raw", "mat") if given, else path's extension (.txt, .dat,
 * .raw, .mat). 0, or -1 if neither names a format that can be written. */
int thx_series_output_format(const char *format_name, const char *path, thx_series_format *fmt);

/* Reads a series; errors name the file (and line, for text) and what is wrong. */
thx_status thx_series_read(thx_ctx *ctx, const char *path, thx_series_format fmt, thx_series **out);
/* Writes atomically (nothing half-written on failure). */
thx_status thx_series_write(thx_ctx *ctx, const thx_series *s, const char *path, thx_series_format fmt);

/* Parses "text", "raw", "mat" or "auto"; returns -1 for anything else. */
int thx_series_format_parse(const char *name, thx_series_format *fmt);

#ifdef __cplusplus
}
#endif
#endif
