/* Activation and recovery times: steepest downstroke and T-wave upstroke (thorax/leads/activation.h). */
#include "thorax/leads/activation.h"

#include <math.h>
#include <stdlib.h>
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

/* The time at frame f (0-based, fractional), linear between frames; NaN outside the frames. */
static double time_at_frame(const thx_series *s, double f)
{
    if (!isfinite(f) || f < 0 || f > (double)(s->n_frames - 1)) return NAN;
    size_t i = (size_t)f;
    if (i >= s->n_frames - 1) return s->time[s->n_frames - 1];
    return s->time[i] + (f - (double)i) * (s->time[i + 1] - s->time[i]);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* A fiducial's frame: its value (a global one) or the median of its finite values (one per row); NaN if none. */
static double fid_frame(const thx_series *s, int type)
{
    for (size_t k = 0; k < s->n_fids; k++) {
        const thx_fiducial *f = &s->fids[k];
        if (f->type != type) continue;
        if (f->n == 1) return f->v[0];
        double *c = malloc(f->n * sizeof *c);
        if (!c) return NAN;
        size_t m = 0;
        for (size_t i = 0; i < f->n; i++)
            if (isfinite(f->v[i])) c[m++] = f->v[i];
        qsort(c, m, sizeof *c, cmp_double);
        double med = m ? (m % 2 ? c[m / 2] : 0.5 * (c[m / 2 - 1] + c[m / 2])) : NAN;
        free(c);
        return med;
    }
    return NAN;
}

thx_status thx_activation_from_fiducials(thx_ctx *ctx, const thx_series *s, int type, thx_series **out)
{
    *out = NULL;
    THX_CHECK(thx_series_validate(ctx, s, "fiducial map"));
    const thx_fiducial *f = NULL;
    for (size_t k = 0; k < s->n_fids && !f; k++)
        if (s->fids[k].type == type && s->fids[k].n == s->n_rows && s->n_rows > 1) f = &s->fids[k];
    if (!f) return THX_OK;
    thx_series *r = NULL;
    THX_CHECK(thx_series_create(ctx, s->n_rows, 1, &r));
    snprintf(r->unit, sizeof r->unit, "%s", s->time_unit);
    r->time_unit[0] = '\0';
    const char *name = thx_fiducial_type_name(type);
    snprintf(r->label, sizeof r->label, "%s: the record's %s fiducials", type == 13 ? "recovery" : "activation", name ? name : "?");
    for (size_t i = 0; i < s->n_rows; i++) r->v[i] = time_at_frame(s, f->v[i]);
    *out = r;
    return THX_OK;
}

/* The smoothed curve's first local minimum after p, or where c falls under thr; at most n - 1. */
static size_t qrs_end(const double *c, const double *sm, size_t n, size_t p, double thr)
{
    size_t f = p + 1;
    while (f + 1 < n && c[f] > thr && !(sm[f] <= sm[f + 1] && sm[f] < sm[p])) f++;
    return f < n ? f : n - 1;
}

thx_status thx_activation_window_choose(thx_ctx *ctx, const thx_series *s, thx_activation_window *w)
{
    THX_CHECK(thx_series_validate(ctx, s, "activation window"));
    size_t n = s->n_frames;
    memset(w, 0, sizeof *w);
    w->t0 = s->time[0];
    w->t1 = s->time[n - 1];
    w->rec_t0 = w->rec_t1 = NAN;
    w->source = THX_WINDOW_WHOLE;

    /* the record's fiducials */
    double qon = fid_frame(s, 2), soff = fid_frame(s, 4), stoff = fid_frame(s, 5), toff = fid_frame(s, 7);
    double a0 = time_at_frame(s, qon), a1 = time_at_frame(s, soff);
    if (isfinite(a0) && isfinite(a1) && a0 < a1) {
        w->t0 = a0;
        w->t1 = a1;
        double r0 = time_at_frame(s, isfinite(stoff) && stoff > soff ? stoff : soff), r1 = time_at_frame(s, toff);
        w->rec_t0 = r0;
        w->rec_t1 = isfinite(r1) && r1 > r0 ? r1 : s->time[n - 1];
        w->source = THX_WINDOW_FIDUCIALS;
        snprintf(w->why, sizeof w->why, "fiducials qon-soff");
        snprintf(w->rec_why, sizeof w->rec_why, "fiducials %s-%s", isfinite(stoff) && stoff > soff ? "stoff" : "soff",
                 isfinite(r1) && r1 > r0 ? "toff" : "end");
        return THX_OK;
    }
    if (n < 8) {
        snprintf(w->why, sizeof w->why, "whole series: %zu frames, too short for a beat", n);
        memcpy(w->rec_why, w->why, sizeof w->why);
        return THX_OK;
    }

    /* one beat of the RMS curve */
    double *c = malloc(3 * n * sizeof *c);
    if (!c) return thx_error(ctx, THX_ENOMEM, "out of memory (RMS curve of %zu frames)", n);
    double *sm = c + n, *srt = c + 2 * n;
    for (size_t f = 0; f < n; f++) {
        double ss = 0;
        size_t m = 0;
        const double *vals = s->v + f * s->n_rows;
        for (size_t i = 0; i < s->n_rows; i++)
            if (isfinite(vals[i])) { ss += vals[i] * vals[i]; m++; }
        c[f] = m ? sqrt(ss / (double)m) : 0;
    }
    for (size_t f = 0; f < n; f++) {
        size_t lo = f >= 2 ? f - 2 : 0, hi = f + 2 < n ? f + 2 : n - 1;
        double a = 0;
        for (size_t k = lo; k <= hi; k++) a += c[k];
        sm[f] = a / (double)(hi - lo + 1);
    }
    memcpy(srt, c, n * sizeof *c);
    qsort(srt, n, sizeof *srt, cmp_double);
    double base = srt[n / 10], top = srt[n - 1], half = base + 0.5 * (top - base);
    /* the beats: runs above half way, each with its QRS (onset, end) and window (w0, w1) */
    enum { MAXB = 64 };
    size_t on[MAXB], en[MAXB], pk[MAXB];
    int nb = 0, complete[MAXB];
    /* beats only where the curve falls between them to under half its peak (a record at rest between
       beats); a curve that never falls so far (a slow activation sequence that keeps every lead away
       from zero: test_bars' plate) is one beat */
    for (size_t f = 0; top > base && base < 0.5 * top && f < n && nb < MAXB;) {
        if (c[f] <= half) { f++; continue; }
        size_t p = f;
        while (f < n && c[f] > half) {
            if (c[f] > c[p]) p = f;
            f++;
        }
        double thr = base + 0.1 * (c[p] - base);
        size_t o = p;
        while (o > 0 && c[o - 1] > thr) o--;
        size_t e = qrs_end(c, sm, n, p, thr);
        if (nb && o <= en[nb - 1]) { /* a second peak of the same QRS */
            if (c[p] > c[pk[nb - 1]]) pk[nb - 1] = p;
            if (e > en[nb - 1]) en[nb - 1] = e;
            if (f < e) f = e;
            continue;
        }
        on[nb] = o;
        en[nb] = e;
        pk[nb] = p;
        complete[nb] = o > 0 && e < n - 1;
        nb++;
        if (f < e) f = e;
    }
    if (nb < 2) {
        /* one beat (or none) in the record: the whole series is that beat, and its activation may
           run as long as the series does (a slow sequence keeps the RMS curve high throughout, and a
           window cut at its one QRS would clip the late nodes: test_bars' 20-60 ms plate read
           20-31 ms) */
        free(c);
        snprintf(w->why, sizeof w->why, "whole series: %s beat on the RMS curve", nb ? "one" : "no");
        memcpy(w->rec_why, w->why, sizeof w->why);
        return THX_OK;
    }
    int b = -1;
    for (int k = 0; k < nb && b < 0; k++)
        if (complete[k]) b = k;
    if (b < 0)
        for (int k = 0; k < nb; k++)
            if (b < 0 || c[pk[k]] > c[pk[b]]) b = k;
    size_t width = en[b] - on[b], margin = width / 4 > 3 ? width / 4 : 3;
    size_t w0 = on[b] > margin ? on[b] - margin : 0, w1 = en[b] + margin < n - 1 ? en[b] + margin : n - 1;
    if (b > 0 && w0 <= en[b - 1]) w0 = en[b - 1] + 1;
    if (b + 1 < nb && w1 >= on[b + 1]) w1 = on[b + 1] - 1;
    size_t r1 = n - 1;
    if (b + 1 < nb) {
        size_t nw = en[b + 1] - on[b + 1], nm = nw / 4 > 3 ? nw / 4 : 3;
        r1 = on[b + 1] > nm + w1 ? on[b + 1] - nm : w1;
    }
    free(c);
    w->t0 = s->time[w0];
    w->t1 = s->time[w1];
    w->rec_t0 = s->time[w1];
    w->rec_t1 = s->time[r1];
    w->source = THX_WINDOW_RMS;
    snprintf(w->why, sizeof w->why, "RMS curve, beat %d of %d", b + 1, nb);
    memcpy(w->rec_why, w->why, sizeof w->why);
    return THX_OK;
}
