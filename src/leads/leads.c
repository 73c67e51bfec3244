/*
 * Signals at electrodes and the standard 12-lead ECG (thorax/model/electrodes.h).
 *
 * thx_electrodes_sample takes each electrode's value from a surface series:
 * its node's row, or for an electrode between nodes (placed by
 * thx_electrodes_place) the weighted sum of its triangle's three node rows.
 * Row i of the result is electrode i.
 *
 * thx_ecg12 forms the twelve standard leads from the electrodes named RA,
 * LA, LL and V1..V6 (names matched exactly, case included), as rows in this
 * order (docs/formats.md, "Electrodes", lists them too):
 *
 *   row  lead  definition
 *    1   I     LA - RA                       (Einthoven)
 *    2   II    LL - RA
 *    3   III   LL - LA
 *    4   aVR   RA - (LA + LL) / 2            (Goldberger)
 *    5   aVL   LA - (RA + LL) / 2
 *    6   aVF   LL - (RA + LA) / 2
 *    7   V1    V1 - WCT, WCT = (RA + LA + LL) / 3   (Wilson)
 *   ...
 *   12   V6    V6 - WCT
 *
 * So II = I + III and aVR + aVL + aVF = 0 (to rounding). The time axis, the
 * units and the time unit are the input's; NaN in an electrode's row (a lost
 * electrode) gives NaN in the leads that use it. The label names the leads.
 */
#include "thorax/model/electrodes.h"
#include "thorax/leads/leads.h"
#include <stdio.h>
#include <string.h>

/* Every node an electrode reads must be a row of the series. */
static thx_status check_rows(thx_ctx *ctx, const thx_electrodes *e, const thx_series *surface, const char *what)
{
    for (size_t i = 0; i < e->n; i++) {
        if (e->node[i] < 0) {
            if (!e->placed || e->node[i] != THX_ELECTRODE_OFF_NODE)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: electrode %zu (\"%s\") is not on a node and was not placed on surface \"%s\" "
                                 "(thx_electrodes_place)",
                                 what, i + 1, e->name[i], e->surface);
            for (int k = 0; k < 3; k++) {
                int32_t c = e->corner[3 * i + (size_t)k];
                if (c < 0 || (size_t)c >= surface->n_rows)
                    return thx_error(ctx, THX_EINPUT,
                                     "%s: electrode %zu (\"%s\") lies on a triangle of node %d of surface \"%s\", but the "
                                     "series has %zu rows (is it a series on that surface?)",
                                     what, i + 1, e->name[i], (int)c + 1, e->surface, surface->n_rows);
            }
        } else if ((size_t)e->node[i] >= surface->n_rows)
            return thx_error(ctx, THX_EINPUT,
                             "%s: electrode %zu (\"%s\") is node %d of surface \"%s\", but the series has %zu rows "
                             "(is it a series on that surface?)",
                             what, i + 1, e->name[i], (int)e->node[i] + 1, e->surface, surface->n_rows);
    }
    return THX_OK;
}

static void copy_axis(const thx_series *in, thx_series *out)
{
    memcpy(out->time, in->time, in->n_frames * sizeof *in->time);
    memcpy(out->unit, in->unit, sizeof out->unit);
    memcpy(out->time_unit, in->time_unit, sizeof out->time_unit);
}

thx_status thx_electrodes_sample(thx_ctx *ctx, const thx_electrodes *e, const thx_series *surface, thx_series **out)
{
    *out = NULL;
    if (!e || e->n == 0) return thx_error(ctx, THX_EINPUT, "sample: no electrodes");
    if (!surface || surface->n_rows == 0 || surface->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "sample: the series is empty");
    THX_CHECK(check_rows(ctx, e, surface, "sample"));
    thx_series *s = NULL;
    THX_CHECK(thx_series_create(ctx, e->n, surface->n_frames, &s));
    copy_axis(surface, s);
    size_t N = surface->n_rows, n = e->n;
    for (size_t f = 0; f < surface->n_frames; f++)
        for (size_t i = 0; i < n; i++) s->v[f * n + i] = thx_electrode_value(e, i, surface->v + f * N);
    snprintf(s->label, sizeof s->label, "%zu electrodes on surface %.40s", n, e->surface);
    *out = s;
    return THX_OK;
}

thx_status thx_ecg12(thx_ctx *ctx, const thx_electrodes *e, const thx_series *surface, thx_series **out)
{
    *out = NULL;
    static const char *const need[9] = {"RA", "LA", "LL", "V1", "V2", "V3", "V4", "V5", "V6"};
    if (!e || e->n == 0) return thx_error(ctx, THX_EINPUT, "12-lead ECG: no electrodes");
    if (!surface || surface->n_rows == 0 || surface->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "12-lead ECG: the series is empty");
    size_t at[9];
    char missing[64] = "";
    size_t off = 0;
    for (int k = 0; k < 9; k++) {
        at[k] = e->n;
        for (size_t i = 0; i < e->n; i++)
            if (!strcmp(e->name[i], need[k])) {
                if (at[k] != e->n)
                    return thx_error(ctx, THX_EINPUT, "12-lead ECG: two electrodes are named \"%s\" (%zu and %zu)",
                                     need[k], at[k] + 1, i + 1);
                at[k] = i;
            }
        if (at[k] == e->n) off += (size_t)snprintf(missing + off, sizeof missing - off, "%s%s", off ? ", " : "", need[k]);
    }
    if (off)
        return thx_error(ctx, THX_EINPUT,
                         "12-lead ECG: the electrode set has no %s (it needs RA, LA, LL and V1..V6, by name)", missing);
    THX_CHECK(check_rows(ctx, e, surface, "12-lead ECG"));
    thx_series *s = NULL;
    THX_CHECK(thx_series_create(ctx, 12, surface->n_frames, &s));
    copy_axis(surface, s);
    size_t N = surface->n_rows;
    for (size_t f = 0; f < surface->n_frames; f++) {
        const double *u = surface->v + f * N;
        double x[9];
        for (int k = 0; k < 9; k++) x[k] = thx_electrode_value(e, at[k], u);
        double ra = x[0], la = x[1], ll = x[2], wct = (ra + la + ll) / 3.0;
        double *v = s->v + f * 12;
        v[0] = la - ra;
        v[1] = ll - ra;
        v[2] = ll - la;
        v[3] = ra - 0.5 * (la + ll);
        v[4] = la - 0.5 * (ra + ll);
        v[5] = ll - 0.5 * (ra + la);
        for (int k = 0; k < 6; k++) v[6 + k] = x[3 + k] - wct;
    }
    snprintf(s->label, sizeof s->label, "12-lead ECG: I II III aVR aVL aVF V1 V2 V3 V4 V5 V6");
    *out = s;
    return THX_OK;
}
