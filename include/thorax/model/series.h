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

/* A fiducial (map3d's "fids"): a time marker of one type, for the whole series (n == 1, a "global"
 * fiducial) or one per row (n == n_rows). Values count frames from 0 as map3d holds them in memory
 * and in its .mat files (a .tsdf or .fids file counts from 1: its readers subtract 1); they may be
 * fractional; NaN = no value for that row. */
typedef struct {
    int type;   /* map3d's fiducial type: 0 pon, 1 poff, 2 qon, 3 rpeak, 4 soff, 5 stoff, 6 tpeak, 7 toff,
                   8 actplus, 9 actminus, 10 act, 11 recplus, 12 recminus, 13 rec, 14 ref, 15 jpt,
                   16 baseline, 17 subseries, 30 pacing (thx_fiducial_type_name) */
    int fidset; /* map3d's fidset number (0 when the file has none) */
    size_t n;   /* 1 or n_rows */
    double *v;  /* n values (owned by the series) */
} thx_fiducial;

/* Classes of kept fields (below). */
typedef enum {
    THX_FIELD_SERIES = 0, /* a field the series holds itself (potvals, label, unit, fids): no data here */
    THX_FIELD_DOUBLE, THX_FIELD_SINGLE, THX_FIELD_INT8, THX_FIELD_UINT8, THX_FIELD_INT16, THX_FIELD_UINT16,
    THX_FIELD_INT32, THX_FIELD_UINT32, THX_FIELD_INT64, THX_FIELD_UINT64,
    THX_FIELD_CHAR,      /* data: UTF-8 text, NUL-terminated; dims as the file had them (1 x n, or 0 x 0) */
    THX_FIELD_EMPTY_CELL /* an empty cell array (map3d's ts.fidset), dims as the file had them */
} thx_field_class;

/* A field of the struct the series was read from (map3d's ts: filename, gain, leadinfo,
 * samplefrequency, audit ...), kept as the file had it so that a .mat written back holds the same
 * struct. Numeric data are dims[0] x dims[1] elements of the class, column-major, host order. */
typedef struct {
    char name[64];
    thx_field_class cls;
    size_t dims[2];
    void *data;     /* owned by the series; NULL for THX_FIELD_SERIES and empty arrays */
    size_t nbytes;
} thx_series_field;

typedef struct thx_series {
    size_t n_rows;       /* nodes or leads */
    size_t n_frames;     /* time instants */
    double *v;           /* n_rows * n_frames, column-major: v[f * n_rows + r] */
    double *time;        /* n_frames sample times in time_unit (increasing) */
    char unit[32];       /* unit of the values, e.g. "mV", "uV", "V" ("" = unknown) */
    char time_unit[16];  /* unit of the time axis, "ms" by default */
    char label[128];     /* free text (what the series is, where it came from) */
    thx_fiducial *fids;  /* n_fids fiducials (may be NULL) */
    size_t n_fids;
    /* Where the series came from when it was a struct (map3d's "ts" in a .mat): its name and every
     * field in the file's order, so that a .mat writer can write the same struct back. group[0] == 0:
     * top-level variables (no struct). */
    char group[64];
    thx_series_field *fields;
    size_t n_fields;
} thx_series;

/* A zeroed rows x frames series with time[f] = f (ms), unit "". */
thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out);
/* Frees the series; accepts NULL; nulls *s. */
void thx_series_destroy(thx_series **s);

/* The invariants of a series every reader ends with and every writer starts with: values and times
 * present, at least 1 row x 1 frame, unit, time_unit and label NUL-terminated, a finite and strictly
 * increasing time axis. `path` names the file in messages. */
thx_status thx_series_validate(thx_ctx *ctx, const thx_series *s, const char *path);

/* Appends a fiducial (values copied; n must be 1 or s->n_rows). */
thx_status thx_series_add_fiducial(thx_ctx *ctx, thx_series *s, int type, int fidset, size_t n, const double *v);
/* Appends a kept field (data copied, nbytes bytes; for THX_FIELD_CHAR a NUL-terminated UTF-8 string). */
thx_status thx_series_add_field(thx_ctx *ctx, thx_series *s, const char *name, thx_field_class cls,
                                const size_t dims[2], const void *data, size_t nbytes);
/* The kept field of that name, or NULL. */
const thx_series_field *thx_series_field_get(const thx_series *s, const char *name);
/* Bytes per element of a numeric field class (0 for the others). */
size_t thx_field_class_size(thx_field_class c);
/* map3d's short name of a fiducial type ("qon", "act" ...), or NULL for a number it does not define. */
const char *thx_fiducial_type_name(int type);
/* The type of a fiducial name: map3d's names and the aliases of its manual (qrson, activation,
 * recovery ...), case-insensitive; -1 if unknown. */
int thx_fiducial_type_parse(const char *name);

/* Number of NaN/Inf values; the first one's row and frame (0-based) when any. */
size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame);

#ifdef __cplusplus
}
#endif
#endif
