/* Activation and recovery times: steepest downstroke and T-wave upstroke (thorax/leads/activation.h). */
#include "thorax/leads/activation.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void thx_activation_opts_default(thx_activation_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = THX_DERIV_SAVGOL;
    o->half_width = 2;
    o->t0 = o->t1 = NAN;
    o->min_slope = 0;
    o->recovery = 0;
    o->rec_t0 = o->rec_t1 = NAN;
}

/* One row: values v[f * stride], times t[f], f < n. */
typedef struct {
    const double *v, *t;
    size_t stride, n;
    int h;
    thx_deriv_method method;
} row;

static double val(const row *r, size_t f) { return r->v[f * r->stride]; }

/* The derivative at sample i (h <= i < n - h), NaN if its window holds a value that is not a number. */
static double deriv(const row *r, size_t i)
{
    size_t h = (size_t)r->h;
    if (r->method == THX_DERIV_CENTRED) {
        double a = val(r, i - h), b = val(r, i + h);
        if (!isfinite(a) || !isfinite(b)) return NAN;
        return (b - a) / (r->t[i + h] - r->t[i - h]);
    }
    /* least-squares slope about the window's mean time (centred sums: no cancellation) */
    double tm = 0, vm = 0;
    for (size_t k = i - h; k <= i + h; k++) {
        double x = val(r, k);
        if (!isfinite(x)) return NAN;
        tm += r->t[k];
        vm += x;
    }
    tm /= (double)(2 * h + 1);
    vm /= (double)(2 * h + 1);
    double sxy = 0, sxx = 0;
    for (size_t k = i - h; k <= i + h; k++) {
        double dt = r->t[k] - tm;
        sxy += dt * (val(r, k) - vm);
        sxx += dt * dt;
    }
    return sxy / sxx;
}

/* The first sample index with time >= t (n if none). */
static size_t first_at_or_after(const double *time, size_t n, double t)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (time[mid] < t) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/*
 * The time of the extreme derivative (sign = -1: most negative; +1: most positive) at samples
 * lo..hi (inclusive, clipped to where the derivative is defined), steeper than min_slope; NaN if
 * none. The extreme sample is refined by the parabola through it and its neighbours.
 */
static double extreme_time(const row *r, size_t lo, size_t hi, int sign, double min_slope)
{
    size_t h = (size_t)r->h;
    if (r->n < 2 * h + 1) return NAN;
    if (lo < h) lo = h;
    if (hi > r->n - 1 - h) hi = r->n - 1 - h;
    if (lo > hi) return NAN;
    size_t best = 0;
    double bd = -INFINITY; /* sign * derivative, largest wanted */
    for (size_t i = lo; i <= hi; i++) {
        double d = sign * deriv(r, i);
        if (d > bd) { /* NaN never compares greater: skipped */
            bd = d;
            best = i;
        }
    }
    if (!(bd > min_slope)) return NAN;
    double t = r->t[best];
    if (best > h && best + h + 1 < r->n) {
        double a = sign * deriv(r, best - 1), c = sign * deriv(r, best + 1);
        /* a maximum of sign * D: the parabola through (-1, a), (0, bd), (1, c) opens downward */
        double den = a - 2 * bd + c;
        if (isfinite(a) && isfinite(c) && den < 0) {
            double off = 0.5 * (a - c) / den;
            if (off > 0.5) off = 0.5;
            if (off < -0.5) off = -0.5;
            t += off >= 0 ? off * (r->t[best + 1] - t) : off * (t - r->t[best - 1]);
        }
    }
    return t;
}

thx_status thx_activation_times(thx_ctx *ctx, const thx_series *s, const thx_activation_opts *o, thx_series **out)
{
    *out = NULL;
    thx_activation_opts def;
    if (!o) {
        thx_activation_opts_default(&def);
        o = &def;
    }
    THX_CHECK(thx_series_validate(ctx, s, "activation times"));
    if (o->method != THX_DERIV_SAVGOL && o->method != THX_DERIV_CENTRED)
        return thx_error(ctx, THX_EINPUT, "activation times: unknown derivative method %d", (int)o->method);
    if (o->half_width < 1 || (size_t)o->half_width > (s->n_frames - 1) / 2)
        return thx_error(ctx, THX_EINPUT,
                         "activation times: a derivative over %d samples either side needs at least %lld frames; "
                         "the series \"%s\" has %zu", o->half_width, 2LL * o->half_width + 1, s->label, s->n_frames);
    if (!isnan(o->t0) && !isnan(o->t1) && o->t0 > o->t1)
        return thx_error(ctx, THX_EINPUT, "activation times: window %g..%g %s is empty (start after end)", o->t0,
                         o->t1, s->time_unit);
    if (!isnan(o->rec_t0) && !isnan(o->rec_t1) && o->rec_t0 > o->rec_t1)
        return thx_error(ctx, THX_EINPUT, "activation times: recovery window %g..%g %s is empty (start after end)",
                         o->rec_t0, o->rec_t1, s->time_unit);
    if (!(o->min_slope >= 0) || !isfinite(o->min_slope))
        return thx_error(ctx, THX_EINPUT, "activation times: min_slope %g must be finite and >= 0", o->min_slope);

    size_t n = s->n_frames, nf = o->recovery ? 2 : 1;
    thx_series *r = NULL;
    THX_CHECK(thx_series_create(ctx, s->n_rows, nf, &r));
    snprintf(r->unit, sizeof r->unit, "%s", s->time_unit);
    r->time_unit[0] = '\0';
    snprintf(r->label, sizeof r->label, "activation time (steepest downstroke)%s; dV/dt %s, %d samples",
             o->recovery ? "; frame 2 recovery (steepest T upstroke)" : "",
             o->method == THX_DERIV_SAVGOL ? "least-squares" : "centred", 2 * o->half_width + 1);

    size_t lo = isnan(o->t0) ? 0 : first_at_or_after(s->time, n, o->t0);
    size_t hi_end = isnan(o->t1) ? n : first_at_or_after(s->time, n, nextafter(o->t1, INFINITY));
    long long n_rows = (long long)s->n_rows;
#pragma omp parallel for schedule(static)
    for (long long i = 0; i < n_rows; i++) {
        row rw = {.v = s->v + i, .t = s->time, .stride = s->n_rows, .n = n, .h = o->half_width, .method = o->method};
        double ta = hi_end > lo ? extreme_time(&rw, lo, hi_end - 1, -1, o->min_slope) : NAN;
        r->v[i] = ta;
        if (!o->recovery) continue;
        double tr = NAN;
        if (!isnan(ta)) {
            /* from the window's start (rec_t0, else t1), and strictly after the activation time */
            double from = isnan(o->rec_t0) ? o->t1 : o->rec_t0;
            size_t rlo = first_at_or_after(s->time, n, nextafter(ta, INFINITY));
            if (!isnan(from)) {
                size_t w = first_at_or_after(s->time, n, from);
                if (w > rlo) rlo = w;
            }
            size_t rend = isnan(o->rec_t1) ? n : first_at_or_after(s->time, n, nextafter(o->rec_t1, INFINITY));
            if (rend > rlo) tr = extreme_time(&rw, rlo, rend - 1, +1, o->min_slope);
        }
        r->v[s->n_rows + i] = tr;
    }
    *out = r;
    return THX_OK;
}
