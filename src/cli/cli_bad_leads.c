/* --bad-leads FILE|auto: the bad rows of a series filled on its surface, or left out (cli_bad_leads.h). */
#include "cli/cli_bad_leads.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/io/channels_file.h"
#include "thorax/leads/bad_leads.h"

/* The 1-based channel of each of the n rows: from the .channels file (0 = none), else row + 1. */
static thx_status channel_numbers(thx_ctx *ctx, const char *channels, size_t n, int32_t **out)
{
    *out = NULL;
    int32_t *c = thx_malloc(ctx, (n + 1) * sizeof *c);
    if (!c) return THX_ENOMEM;
    if (!channels) {
        for (size_t i = 0; i < n; i++) c[i] = (int32_t)i + 1;
        *out = c;
        return THX_OK;
    }
    thx_channels *ch = NULL;
    thx_status st = thx_channels_read(ctx, channels, &ch);
    if (st == THX_OK && ch->n != n) st = thx_error(ctx, THX_EINPUT, "%s: %zu nodes, the series has %zu rows", channels, ch->n, n);
    if (st == THX_OK)
        for (size_t i = 0; i < n; i++) c[i] = ch->channel[i] + 1;
    thx_channels_destroy(&ch);
    if (st != THX_OK) {
        free(c);
        return st;
    }
    *out = c;
    return THX_OK;
}

/* The rows of a series (channel numbers chan, 1-based) that spec names bad: bad[i] = 1. "auto" checks
 * s (on surf when given). Logs what it found, in channels. */
static thx_status mark(thx_ctx *ctx, const char *spec, const thx_series *s, const thx_surface *surf, const int32_t *chan,
                       unsigned char *bad, size_t *n_bad)
{
    size_t n = s->n_rows;
    char list[512] = "";
    size_t len = 0, cnt = 0;
    memset(bad, 0, n);
    if (!strcmp(spec, "auto")) {
        thx_bad_leads *b = NULL;
        THX_CHECK(thx_bad_leads_detect(ctx, s, surf, NULL, &b));
        char why[512];
        for (size_t i = 0; i < n; i++) {
            if (!b->flags[i]) continue;
            bad[i] = 1;
            thx_bad_leads_reason(b, i, chan, why, sizeof why);
            thx_log(ctx, THX_LOG_DEBUG, "--bad-leads auto: channel %d: %s", (int)chan[i], why);
        }
        thx_bad_leads_destroy(&b);
    } else {
        int32_t *ch = NULL;
        size_t nl = 0;
        THX_CHECK(thx_bad_list_read(ctx, spec, 0, &ch, &nl));
        for (size_t k = 0; k < nl; k++) {
            int hit = 0;
            for (size_t i = 0; i < n; i++)
                if (chan[i] == ch[k] + 1) bad[i] = 1, hit = 1;
            if (!hit) thx_log(ctx, THX_LOG_INFO, "%s: channel %d is not in the series (ignored)", spec, (int)ch[k] + 1);
        }
        free(ch);
    }
    for (size_t i = 0; i < n; i++)
        if (bad[i]) {
            cnt++;
            if (len < sizeof list - 16) len += (size_t)snprintf(list + len, sizeof list - len, "%s%d", cnt > 1 ? ", " : "", (int)chan[i]);
        }
    *n_bad = cnt;
    if (cnt) snprintf(list + (len < sizeof list - 16 ? len : sizeof list - 16), 16, "%s", len < sizeof list - 16 ? "" : " ...");
    thx_log(ctx, THX_LOG_INFO, "--bad-leads %s: %zu bad channel%s%s%s", spec, cnt, cnt == 1 ? "" : "s", cnt ? ": " : "",
            list);
    return THX_OK;
}

thx_status cli_bad_leads_fill(thx_ctx *ctx, const char *spec, const char *channels, const thx_surface *surf, thx_series *s)
{
    if (!spec) return THX_OK;
    if (surf->n_nodes != s->n_rows)
        return thx_error(ctx, THX_EINPUT, "--bad-leads: %zu rows, surface '%s' has %zu nodes", s->n_rows, surf->name,
                         surf->n_nodes);
    int32_t *chan = NULL;
    THX_CHECK(channel_numbers(ctx, channels, s->n_rows, &chan));
    unsigned char *bad = thx_malloc(ctx, s->n_rows + 1);
    size_t n_bad = 0;
    thx_status st = bad ? mark(ctx, spec, s, surf, chan, bad, &n_bad) : THX_ENOMEM;
    if (st == THX_OK && n_bad) st = thx_bad_leads_interpolate(ctx, surf, s, bad);
    if (st == THX_OK && n_bad)
        thx_log(ctx, THX_LOG_INFO, "--bad-leads: %zu node%s of '%s' filled by Laplacian interpolation", n_bad,
                n_bad == 1 ? "" : "s", surf->name);
    free(chan);
    free(bad);
    return st;
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
    int32_t *chan = NULL;
    THX_CHECK(channel_numbers(ctx, NULL, n, &chan));
    unsigned char *bad = thx_malloc(ctx, n + 1);
    size_t n_bad = 0;
    thx_status st = bad ? mark(ctx, spec, *B, NULL, chan, bad, &n_bad) : THX_ENOMEM;
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
