/*
 * Private to the time series files (src/io/series*.c): the checks every
 * series passes and the reader and writer of each format. thx_series_read
 * and thx_series_write (series.c) dispatch to these.
 */
#ifndef THORAX_IO_SERIES_IMPL_H
#define THORAX_IO_SERIES_IMPL_H

#include <stddef.h>

#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
/* The time axis of `dt` files: one expression, shared by writer and reader so
 * that the writer's "is this axis uniform?" test predicts the reader's bits. */
static inline double uniform_time(double t0, double dt, size_t f) { return t0 + (double)f * dt; }


thx_status series_read_text(thx_ctx *ctx, const char *path, thx_series **out);
thx_status series_write_text(thx_ctx *ctx, const thx_series *s, const char *path);
thx_status series_read_raw(thx_ctx *ctx, const char *path, thx_series **out);
thx_status series_write_raw(thx_ctx *ctx, const thx_series *s, const char *path);
/* varname: the variable to read, or NULL (potvals, a struct with potvals, the first matrix). */
thx_status series_read_mat(thx_ctx *ctx, const char *path, const char *varname, thx_series **out);
/* Walks a MATLAB 5 file's every element before libmatio sees it (series_matcheck.c): sizes against
 * the file, truncation, stray bytes, compressed variables within zlib's ratio; v7.3 and v4 refused. */
thx_status series_mat_preflight(thx_ctx *ctx, const char *path);
thx_status series_write_mat(thx_ctx *ctx, const thx_series *s, const char *path);
thx_status series_read_pot(thx_ctx *ctx, const char *path, thx_series **out);
/* numbered .pot files: a pattern with one %d, or a directory (series_potset.c) */
thx_status series_read_pot_set(thx_ctx *ctx, const char *path, thx_series **out);
/* plain numeric matrices in, CSV out (series_matrix.c) */
thx_status series_read_matrix(thx_ctx *ctx, const char *path, thx_series **out);
thx_status series_write_csv(thx_ctx *ctx, const thx_series *s, const char *path);
/* the shortest text that reads back to x (series_text.c); writes at most 25 characters */
char *series_put_double(char *p, double x);

#endif
