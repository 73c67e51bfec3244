/* Time series (thorax/model/series.h): create, destroy, non-finite values. */
#include "thorax/model/series.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out)
{
    *out = NULL;
    if (n_frames && n_rows > SIZE_MAX / sizeof(double) / n_frames)
        return thx_error(ctx, THX_EINPUT, "a series of %zu rows x %zu frames is too large", n_rows, n_frames);
    thx_series *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    s->v = thx_calloc(ctx, n_rows * n_frames, sizeof *s->v);
    s->time = thx_malloc(ctx, (n_frames ? n_frames : 1) * sizeof *s->time);
    if (!s->v || !s->time) {
        thx_series_destroy(&s);
        return THX_ENOMEM;
    }
    s->n_rows = n_rows;
    s->n_frames = n_frames;
    for (size_t f = 0; f < n_frames; f++) s->time[f] = (double)f;
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    *out = s;
    return THX_OK;
}

void thx_series_destroy(thx_series **s)
{
    if (!s || !*s) return;
    free((*s)->v);
    free((*s)->time);
    free(*s);
    *s = NULL;
}

size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame)
{
    size_t n = s->n_rows * s->n_frames, count = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(s->v[i])) {
            if (count++ == 0) first = i;
        }
    if (count && s->n_rows) {
        if (row) *row = first % s->n_rows;
        if (frame) *frame = first / s->n_rows;
    }
    return count;
}

