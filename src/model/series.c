/* Time series (thorax/model/series.h): create, destroy, non-finite values. */
#include "thorax/model/series.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

thx_status thx_series_validate(thx_ctx *ctx, const thx_series *s, const char *path)
{
    if (!s || !s->v || !s->time) return thx_error(ctx, THX_EINPUT, "%s: no series (NULL values or time)", path);
    if (s->n_rows == 0 || s->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "%s: empty series (%zu rows x %zu frames; at least 1 x 1 needed)", path,
                         s->n_rows, s->n_frames);
    if (!memchr(s->unit, '\0', sizeof s->unit) || !memchr(s->time_unit, '\0', sizeof s->time_unit) ||
        !memchr(s->label, '\0', sizeof s->label))
        return thx_error(ctx, THX_EINPUT, "%s: unit, time_unit or label is not NUL-terminated", path);
    for (size_t f = 0; f < s->n_frames; f++) {
        if (!isfinite(s->time[f]))
            return thx_error(ctx, THX_EINPUT, "%s: time of frame %zu is %g (times must be finite)", path, f + 1,
                             s->time[f]);
        if (f > 0 && !(s->time[f] > s->time[f - 1]))
            return thx_error(ctx, THX_EINPUT,
                             "%s: time of frame %zu (%.17g) is not after that of frame %zu (%.17g): "
                             "times must increase",
                             path, f + 1, s->time[f], f, s->time[f - 1]);
    }
    return THX_OK;
}
