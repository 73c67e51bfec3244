/*
 * Shared by the time series harnesses (fuzz_series_{text,raw,mat,pot}.c):
 * reads the bytes as one format and checks what an accepted series must be.
 * Properties: at least one row and frame; no more values than the file's
 * bytes can hold (values_per_byte: text and .pot 1/2, raw 1/8 - its exact
 * size -, .mat up to zlib's ratio); a finite, strictly increasing time axis;
 * NUL-terminated strings; and a write/read round trip (text, raw and .mat
 * writers) that keeps the sizes, the times and every value bit for bit
 * (NaN as NaN).
 */
#ifndef THORAX_TESTS_SERIES_FUZZ_H
#define THORAX_TESTS_SERIES_FUZZ_H

#include <math.h>

#include "fuzz.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
static int same_value(double a, double b) { return (isnan(a) && isnan(b)) || a == b; }

static void series_fuzz_round_trip(thx_ctx *ctx, const thx_series *s, const char *name, thx_series_format fmt)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", fuzz_dir(), name);
    /* a text unit with a blank cannot be written as text: a writer may refuse, never crash */
    if (thx_series_write(ctx, s, p, fmt) != THX_OK) return;
    thx_series *r = NULL;
    FUZZ_ASSERT(thx_series_read(ctx, p, fmt, &r) == THX_OK);
    FUZZ_ASSERT(r->n_rows == s->n_rows && r->n_frames == s->n_frames);
    for (size_t f = 0; f < s->n_frames; f++) FUZZ_ASSERT(r->time[f] == s->time[f]);
    for (size_t i = 0; i < s->n_rows * s->n_frames; i++) FUZZ_ASSERT(same_value(r->v[i], s->v[i]));
    thx_series_destroy(&r);
}

/* max_values(size): how many values a file of `size` bytes of this format can hold. */
static void series_fuzz_one(const uint8_t *data, size_t size, const char *name, thx_series_format fmt,
                            size_t (*max_values)(size_t))
{
    const char *path = fuzz_file(name, data, size);
    thx_ctx *ctx = fuzz_ctx();
    thx_series *s = NULL;
    if (thx_series_read(ctx, path, fmt, &s) == THX_OK) {
        FUZZ_ASSERT(s->n_rows >= 1 && s->n_frames >= 1);
        FUZZ_ASSERT(s->n_rows <= max_values(size) / s->n_frames);
        FUZZ_ASSERT(memchr(s->unit, 0, sizeof s->unit) && memchr(s->time_unit, 0, sizeof s->time_unit) &&
                    memchr(s->label, 0, sizeof s->label));
        for (size_t f = 0; f < s->n_frames; f++) {
            FUZZ_ASSERT(isfinite(s->time[f]));
            if (f) FUZZ_ASSERT(s->time[f] > s->time[f - 1]);
        }
        series_fuzz_round_trip(ctx, s, "r.txt", THX_SERIES_TEXT);
        series_fuzz_round_trip(ctx, s, "r.raw", THX_SERIES_RAW);
        series_fuzz_round_trip(ctx, s, "r.mat", THX_SERIES_MAT);
    }
    thx_series_destroy(&s);
    thx_ctx_destroy(&ctx);
}

#endif
