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
 *   map3d (read): .pot (one frame), numbered .pot sets (a pattern "NAME_%03d.pot" or a directory),
 *                 .tsdf (thorax/io/graphicsio.h), .fids fiducials (thx_series_read_fids);
 *   matrices (read): plain numbers in text, one line per row, one column per frame;
 *   CSV   (.csv)  written with a header of times, read back as a matrix.
 * A .mat struct (map3d's ts) is kept whole: its fields (thx_series_field) and fids
 * (thx_fiducial) are written back as the same struct.
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
    THX_SERIES_POT,      /* map3d .pot, read only: one value per node (whitespace separated), one frame */
    THX_SERIES_TSDF,     /* map3d/CVRTI graphicsio .tsdf, read only (thorax/io/graphicsio.h); FILE.tsdf@N picks one */
    THX_SERIES_CSV,      /* written: CSV with a header of times; read as a matrix (below) */
    THX_SERIES_MATRIX    /* read only: a plain numeric matrix in text, rows x frames (blanks or commas) */
} thx_series_format;

/* The format to write: format_name ("text", "raw", "mat", "csv") if given, else path's extension (.txt,
 * .dat, .raw, .mat, .csv). 0, or -1 if neither names a format that can be written. */
int thx_series_output_format(const char *format_name, const char *path, thx_series_format *fmt);

/* Reads a series; path may also be a set of numbered map3d .pot files (a pattern such as
 * "dipole2_%03d.pot", or a directory of NAME + number + .pot files: one frame per file, in number
 * order, gaps refused) or "FILE.tsdf@N". .tsdfc (map3d's GDBM container of fiducial sets) is refused.
 * Errors name the file (and line, for text) and what is wrong. */
thx_status thx_series_read(thx_ctx *ctx, const char *path, thx_series_format fmt, thx_series **out);
/* Adds the fiducials of a map3d .fids file to s (its lead count must be s's rows; values minus 1,
 * as map3d reads them). */
thx_status thx_series_read_fids(thx_ctx *ctx, const char *path, thx_series *s);
/* Swaps rows and frames (a matrix laid out frames x channels); the time axis becomes the frame
 * number from 0 (time_unit "frame"); per-row fiducials and kept fields are dropped. */
thx_status thx_series_transpose(thx_ctx *ctx, thx_series **s);
/* Writes atomically (nothing half-written on failure). */
thx_status thx_series_write(thx_ctx *ctx, const thx_series *s, const char *path, thx_series_format fmt);

/* Parses "text", "raw", "mat", "csv", "pot", "tsdf", "matrix" or "auto"; returns -1 for anything else. */
int thx_series_format_parse(const char *name, thx_series_format *fmt);

#ifdef __cplusplus
}
#endif
#endif
