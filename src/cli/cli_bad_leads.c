/* --bad-leads FILE|auto: the bad rows of a series filled on its surface, or left out (cli_bad_leads.h). */
#include "cli/cli_bad_leads.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/io/channels_file.h"
#include "thorax/leads/bad_leads.h"

/* The 1-based channel of each of the n rows: from the .channels file (0 = none), else row + 1. */
static thx_status channel_numbers(thx_ctx *ctx, const char *channels, size_t n, int **out)
{
    *out = NULL;
    int *c = thx_malloc(ctx, (n + 1) * sizeof *c);
    if (!c) return THX_ENOMEM;
    if (!channels) {
        for (size_t i = 0; i < n; i++) c[i] = (int)i + 1;
        *out = c;
        return THX_OK;
    }
    thx_channels *ch = NULL;
    thx_status st = thx_channels_read(ctx, channels, &ch);
    if (st == THX_OK && ch->n != n) st = thx_error(ctx, THX_EINPUT, "%s: %zu nodes, the series has %zu rows", channels, ch->n, n);
    if (st == THX_OK)
        for (size_t i = 0; i < n; i++) c[i] = (int)ch->channel[i] + 1;
    thx_channels_destroy(&ch);
    if (st != THX_OK) {
        free(c);
        return st;
    }
    *out = c;
    return THX_OK;
}

thx_status cli_bad_leads_fill(thx_ctx *ctx, const char *spec, const char *channels, const thx_surface *surf, thx_series *s)
{
    if (!spec) return THX_OK;
    int *chan = NULL;
    THX_CHECK(channel_numbers(ctx, channels, s->n_rows, &chan));
    thx_status st = thx_bad_leads_fill(ctx, spec, surf, chan, s);
    free(chan);
    return st;
}

thx_status cli_bad_leads_fill_role(thx_ctx *ctx, const char *spec, const char *channels, const thx_model *m, thx_role role,
                                   thx_series *s)
{
    if (!spec) return THX_OK;
    for (size_t k = 0; k < m->n_surfaces; k++)
        if (m->surf[k]->role == role) return cli_bad_leads_fill(ctx, spec, channels, m->surf[k], s);
    return thx_error(ctx, THX_EINPUT, "--bad-leads: the model has no %s surface to interpolate on", thx_role_name(role));
}

/* A new series of the rows of s with keep[i] != 0 (time axis, units and label kept). */
static thx_status keep_rows(thx_ctx *ctx, const thx_series *s, const unsigned char *keep, thx_series **out)
{
    size_t nk = 0, n = s->n_rows;
    for (size_t i = 0; i < n; i++) nk += keep[i] != 0;
    if (!nk) return thx_error(ctx, THX_EINPUT, "--bad-leads: every lead is bad: nothing left");
    thx_series *o = NULL;
    THX_CHECK(thx_series_create(ctx, nk, s->n_frames, &o));
    for (size_t f = 0; f < s->n_frames; f++) {
        size_t r = 0;
        for (size_t i = 0; i < n; i++)
            if (keep[i]) o->v[f * nk + r++] = s->v[f * n + i];
        o->time[f] = s->time[f];
    }
    memcpy(o->unit, s->unit, sizeof o->unit);
    memcpy(o->time_unit, s->time_unit, sizeof o->time_unit);
    memcpy(o->label, s->label, sizeof o->label);
    *out = o;
    return THX_OK;
}

thx_status cli_bad_leads_drop(thx_ctx *ctx, const char *spec, thx_series **A, thx_series **B)
{
    if (!spec) return THX_OK;
    size_t n = (*B)->n_rows;
    if ((*A)->n_rows != n)
        return thx_error(ctx, THX_EINPUT, "--bad-leads: the data has %zu rows, the transfer matrix %zu", n, (*A)->n_rows);
    int *chan = NULL;
    THX_CHECK(channel_numbers(ctx, NULL, n, &chan));
    unsigned char *bad = thx_malloc(ctx, n + 1);
    size_t n_bad = 0;
    thx_status st = bad ? thx_bad_leads_mark(ctx, spec, *B, NULL, chan, bad, &n_bad) : THX_ENOMEM;
    thx_series *a2 = NULL, *b2 = NULL;
    if (st == THX_OK && n_bad) {
        for (size_t i = 0; i < n; i++) bad[i] = !bad[i]; /* now: keep */
        st = keep_rows(ctx, *A, bad, &a2);
        if (st == THX_OK) st = keep_rows(ctx, *B, bad, &b2);
        if (st == THX_OK) {
            thx_series_destroy(A);
            thx_series_destroy(B);
            *A = a2;
            *B = b2;
            a2 = b2 = NULL;
            thx_log(ctx, THX_LOG_INFO, "--bad-leads: %zu lead%s left out (rows of the data and the transfer matrix): %zu left",
                    n_bad, n_bad == 1 ? "" : "s", n - n_bad);
        }
    }
    thx_series_destroy(&a2);
    thx_series_destroy(&b2);
    free(chan);
    free(bad);
    return st;
}
