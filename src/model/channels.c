/*
 * Channel maps (thorax/model/channels.h): a recording's channels to a surface's nodes.
 */
#include "thorax/model/channels.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

thx_status thx_channels_create(thx_ctx *ctx, size_t n, thx_channels **out)
{
    *out = NULL;
    if (n == 0) return thx_error(ctx, THX_EINPUT, "a channel map needs at least one node");
    if (n > (size_t)INT32_MAX) return thx_error(ctx, THX_EINPUT, "%zu nodes are too many for a channel map", n);
    thx_channels *c = thx_calloc(ctx, 1, sizeof *c);
    if (!c) return THX_ENOMEM;
    c->channel = thx_malloc(ctx, n * sizeof *c->channel);
    c->line = thx_calloc(ctx, n, sizeof *c->line);
    if (!c->channel || !c->line) {
        thx_channels_destroy(&c);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) c->channel[i] = -1;
    c->n = n;
    *out = c;
    return THX_OK;
}

void thx_channels_destroy(thx_channels **c)
{
    if (!c || !*c) return;
    free((*c)->channel);
    free((*c)->line);
    free(*c);
    *c = NULL;
}

size_t thx_channels_unmapped(const thx_channels *c)
{
    size_t k = 0;
    for (size_t i = 0; c && i < c->n; i++) k += c->channel[i] < 0;
    return k;
}

thx_status thx_channels_apply(thx_ctx *ctx, const thx_channels *c, const thx_series *in, thx_series **out)
{
    *out = NULL;
    const char *path = c && c->path[0] ? c->path : "channel map";
    if (!c || c->n == 0) return thx_error(ctx, THX_EINPUT, "%s: no nodes", path);
    if (!in || in->n_rows == 0 || in->n_frames == 0) return thx_error(ctx, THX_EINPUT, "%s: the recording is empty", path);
    for (size_t i = 0; i < c->n; i++)
        if (c->channel[i] >= 0 && (size_t)c->channel[i] >= in->n_rows) {
            if (c->line[i])
                return thx_error(ctx, THX_EINPUT, "%s:%d: channel %d is not in 1..%zu (the recording's rows; node %zu)",
                                 path, (int)c->line[i], (int)c->channel[i] + 1, in->n_rows, i + 1);
            return thx_error(ctx, THX_EINPUT, "%s: channel %d is not in 1..%zu (the recording's rows; node %zu)", path,
                             (int)c->channel[i] + 1, in->n_rows, i + 1);
        }
    thx_series *s = NULL;
    THX_CHECK(thx_series_create(ctx, c->n, in->n_frames, &s));
    memcpy(s->time, in->time, in->n_frames * sizeof *in->time);
    memcpy(s->unit, in->unit, sizeof s->unit);
    memcpy(s->time_unit, in->time_unit, sizeof s->time_unit);
    snprintf(s->label, sizeof s->label, "%.100s (by channel)", in->label);
    size_t n = c->n, N = in->n_rows;
    for (size_t f = 0; f < in->n_frames; f++)
        for (size_t i = 0; i < n; i++)
            s->v[f * n + i] = c->channel[i] >= 0 ? in->v[f * N + (size_t)c->channel[i]] : NAN;
    *out = s;
    return THX_OK;
}
