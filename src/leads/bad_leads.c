/* Bad leads: the checks, the bad-lead list and Laplacian interpolation (thorax/leads/bad_leads.h). */
#include "thorax/leads/bad_leads.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"

void thx_bad_leads_opts_default(thx_bad_leads_opts *o)
{
    memset(o, 0, sizeof *o);
    o->flat = 0.01;
    o->saturated = 0.10;
    o->duplicate_exact = 0.01;
    o->duplicate = 0.20;
    o->duplicate_contrast = 0.25;
    o->unlike = 2.5;
    o->small = 0.2;
    o->large = 5.0;
}

void thx_bad_leads_destroy(thx_bad_leads **bp)
{
    if (!bp || !*bp) return;
    thx_bad_leads *b = *bp;
    free(b->flags);
    free(b->missing);
    free(b->rms);
    free(b->extreme);
    free(b->nearest);
    free(b->d);
    free(b->contrast);
    free(b->twin);
    free(b->unlike);
    free(b->ratio);
    free(b->corr);
    free(b->n_nb);
    free(b);
    *bp = NULL;
}

/* ------------------------------------------------------------------ neighbours */

/* The 1-ring of every node: nodes sharing a triangle edge, sorted, each once (CSR: start[n + 1], adj). */
typedef struct {
    size_t n;
    size_t *start;
    int32_t *adj;
} ring;

static void ring_free(ring *r)
{
    free(r->start);
    free(r->adj);
    memset(r, 0, sizeof *r);
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

static thx_status ring_build(thx_ctx *ctx, const thx_surface *s, ring *r)
{
    size_t n = s->n_nodes;
    memset(r, 0, sizeof *r);
    r->n = n;
    size_t *cnt = thx_calloc(ctx, n + 1, sizeof *cnt);
    int32_t *tmp = thx_malloc(ctx, (6 * s->n_tris + 1) * sizeof *tmp);
    r->start = thx_calloc(ctx, n + 1, sizeof *r->start);
    if (!cnt || !tmp || !r->start) {
        free(cnt);
        free(tmp);
        ring_free(r);
        return THX_ENOMEM;
    }
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = s->tri[3 * t + k];
            if (a < 0 || (size_t)a >= n) {
                free(cnt);
                free(tmp);
                ring_free(r);
                return thx_error(ctx, THX_EINPUT, "surface '%s': triangle %zu has node %d of %zu", s->name, t + 1,
                                 (int)a + 1, n);
            }
            cnt[a] += 2;
        }
    size_t *pos = thx_calloc(ctx, n + 1, sizeof *pos);
    if (!pos) {
        free(cnt);
        free(tmp);
        ring_free(r);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) pos[i + 1] = pos[i] + cnt[i];
    memcpy(cnt, pos, (n + 1) * sizeof *cnt);
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3], c = s->tri[3 * t + (k + 2) % 3];
            tmp[cnt[a]++] = b;
            tmp[cnt[a]++] = c;
        }
    /* sort and deduplicate each node's list in place, compacting */
    size_t w = 0;
    for (size_t i = 0; i < n; i++) {
        size_t a = pos[i], e = pos[i + 1];
        qsort(tmp + a, e - a, sizeof *tmp, cmp_i32);
        r->start[i] = w;
        for (size_t k = a; k < e; k++)
            if ((k == a || tmp[k] != tmp[k - 1]) && tmp[k] != (int32_t)i) tmp[w++] = tmp[k];
    }
    r->start[n] = w;
    free(pos);
    free(cnt);
    r->adj = tmp;
    return THX_OK;
}

static int adjacent(const ring *r, int32_t i, int32_t j)
{
    for (size_t k = r->start[i]; k < r->start[i + 1]; k++)
        if (r->adj[k] == j) return 1;
    return 0;
}

/* ------------------------------------------------------------------ the checks */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of v[0..n) (n > 0), sorting a copy in w. */
static double median(const double *v, size_t n, double *w)
{
    memcpy(w, v, n * sizeof *w);
    qsort(w, n, sizeof *w, cmp_double);
    return n % 2 ? w[n / 2] : 0.5 * (w[n / 2 - 1] + w[n / 2]);
}

/* rms(x_i - x_j) / max(rms_i, rms_j) over the centred rows X (row-major, nf each). */
static double pair_d(const double *X, size_t nf, const double *rms, size_t i, size_t j)
{
    const double *a = X + i * nf, *b = X + j * nf;
    double s = 0;
    for (size_t f = 0; f < nf; f++) s += (a[f] - b[f]) * (a[f] - b[f]);
    double m = rms[i] > rms[j] ? rms[i] : rms[j];
    return m > 0 ? sqrt(s / (double)nf) / m : (s > 0 ? INFINITY : 0);
}

typedef struct {
    size_t i;
    double rms;
} by_rms;

static int cmp_by_rms(const void *a, const void *b)
{
    const by_rms *x = a, *y = b;
    if (x->rms != y->rms) return (x->rms > y->rms) - (x->rms < y->rms);
    return (x->i > y->i) - (x->i < y->i);
}

/* The neighbour scores of row i from its good neighbours (good[k] != 0); returns the count used. */
static size_t neighbour_scores(const ring *r, const double *X, size_t nf, const double *rms, const unsigned char *good,
                               size_t i, double *m, double *w, double *unlike, double *ratio, double *corr)
{
    size_t cnt = 0;
    memset(m, 0, nf * sizeof *m);
    for (size_t k = r->start[i]; k < r->start[i + 1]; k++) {
        int32_t j = r->adj[k];
        if (!good[j]) continue;
        for (size_t f = 0; f < nf; f++) m[f] += X[(size_t)j * nf + f];
        w[cnt++] = rms[j];
    }
    *unlike = *ratio = *corr = NAN;
    if (cnt < 2) return cnt;
    double mm = 0;
    for (size_t f = 0; f < nf; f++) mm += (m[f] /= (double)cnt);
    mm /= (double)nf;
    double res = 0, sxy = 0, syy = 0;
    const double *x = X + i * nf;
    for (size_t f = 0; f < nf; f++) {
        double y = m[f] - mm;
        res += (x[f] - y) * (x[f] - y);
        sxy += x[f] * y;
        syy += y * y;
    }
    double med = median(w, cnt, w + cnt);
    *unlike = rms[i] > 0 ? sqrt(res / (double)nf) / rms[i] : INFINITY;
    *ratio = med > 0 ? rms[i] / med : INFINITY;
    double sxx = rms[i] * rms[i] * (double)nf;
    *corr = sxx > 0 && syy > 0 ? sxy / sqrt(sxx * syy) : NAN;
    return cnt;
}

static thx_status check_opts(thx_ctx *ctx, const thx_bad_leads_opts *o)
{
    const struct {
        const char *name;
        double v, lo, hi;
    } t[] = {{"flat", o->flat, 0, 1},           {"saturated", o->saturated, 0, 1},
             {"duplicate_exact", o->duplicate_exact, 0, 1}, {"duplicate", o->duplicate, 0, 1},
             {"duplicate_contrast", o->duplicate_contrast, 0, 1}, {"unlike", o->unlike, 1, INFINITY},
             {"small", o->small, 0, 1},         {"large", o->large, 1, INFINITY}};
    for (size_t k = 0; k < sizeof t / sizeof t[0]; k++)
        if (!(t[k].v > t[k].lo && t[k].v <= t[k].hi))
            return thx_error(ctx, THX_EINPUT, "bad-lead check: threshold %s = %g is out of range (%g, %g]", t[k].name,
                             t[k].v, t[k].lo, t[k].hi);
    return THX_OK;
}

thx_status thx_bad_leads_detect(thx_ctx *ctx, const thx_series *s, const thx_surface *surf,
                                const thx_bad_leads_opts *o, thx_bad_leads **out)
{
    *out = NULL;
    thx_bad_leads_opts def;
    if (!o) {
        thx_bad_leads_opts_default(&def);
        o = &def;
    }
    THX_CHECK(check_opts(ctx, o));
    THX_CHECK(thx_series_validate(ctx, s, "bad-lead check"));
    size_t n = s->n_rows, nf = s->n_frames;
    if (nf < THX_BAD_MIN_FRAMES)
        return thx_error(ctx, THX_EINPUT,
                         "bad-lead check: %zu frame%s; the checks compare rows over time and need at least %d frames "
                         "(with fewer, unrelated leads look alike by chance)",
                         nf, nf == 1 ? "" : "s", THX_BAD_MIN_FRAMES);
    if (surf && surf->n_nodes != n)
        return thx_error(ctx, THX_EINPUT, "bad-lead check: %zu rows, surface '%s' has %zu nodes", n, surf->name,
                         surf->n_nodes);
    if (n > INT32_MAX) return thx_error(ctx, THX_EINPUT, "bad-lead check: %zu rows", n);
    thx_status st = THX_OK;
    ring r = {0};
    double *X = NULL, *w = NULL, *m = NULL;
    unsigned char *good = NULL;
    by_rms *order = NULL;
    thx_bad_leads *b = thx_calloc(ctx, 1, sizeof *b);
    if (!b) return THX_ENOMEM;
    b->n = n;
    b->flags = thx_calloc(ctx, n, sizeof *b->flags);
    b->missing = thx_calloc(ctx, n, sizeof *b->missing);
    b->rms = thx_malloc(ctx, n * sizeof *b->rms);
    b->extreme = thx_malloc(ctx, n * sizeof *b->extreme);
    b->nearest = thx_malloc(ctx, n * sizeof *b->nearest);
    b->d = thx_malloc(ctx, n * sizeof *b->d);
    b->contrast = thx_malloc(ctx, n * sizeof *b->contrast);
    b->twin = thx_malloc(ctx, n * sizeof *b->twin);
    b->unlike = thx_malloc(ctx, n * sizeof *b->unlike);
    b->ratio = thx_malloc(ctx, n * sizeof *b->ratio);
    b->corr = thx_malloc(ctx, n * sizeof *b->corr);
    b->n_nb = thx_calloc(ctx, n, sizeof *b->n_nb);
    X = thx_malloc(ctx, n * nf * sizeof *X);
    w = thx_malloc(ctx, (2 * n + 2) * sizeof *w);
    m = thx_malloc(ctx, nf * sizeof *m);
    good = thx_calloc(ctx, n, 1);
    order = thx_malloc(ctx, n * sizeof *order);
    if (!b->flags || !b->missing || !b->rms || !b->extreme || !b->nearest || !b->d || !b->contrast || !b->twin ||
        !b->unlike || !b->ratio || !b->corr || !b->n_nb || !X || !w || !m || !good || !order) {
        st = THX_ENOMEM;
        goto done;
    }
    if (surf) THX_TRY(ring_build(ctx, surf, &r));

    /* centred rows, rms, extremes */
    size_t n_ok = 0;
    for (size_t i = 0; i < n; i++) {
        double mean = 0, lo = INFINITY, hi = -INFINITY;
        int bad = 0;
        for (size_t f = 0; f < nf; f++) {
            double x = s->v[f * n + i];
            if (!isfinite(x)) bad = 1;
            mean += x;
            if (x < lo) lo = x;
            if (x > hi) hi = x;
        }
        b->nearest[i] = b->twin[i] = -1;
        b->d[i] = b->contrast[i] = b->unlike[i] = b->ratio[i] = b->corr[i] = NAN;
        if (bad) {
            b->missing[i] = 1;
            b->n_missing++;
            b->rms[i] = b->extreme[i] = NAN;
            memset(X + i * nf, 0, nf * sizeof *X);
            continue;
        }
        mean /= (double)nf;
        double ss = 0;
        size_t at_lo = 0, at_hi = 0;
        for (size_t f = 0; f < nf; f++) {
            double x = s->v[f * n + i];
            X[i * nf + f] = x - mean;
            ss += (x - mean) * (x - mean);
            at_lo += x == lo;
            at_hi += x == hi;
        }
        b->rms[i] = sqrt(ss / (double)nf);
        b->extreme[i] = (double)(at_lo > at_hi ? at_lo : at_hi) / (double)nf;
        if (hi == lo) b->flags[i] |= THX_BAD_FLAT;
        w[n_ok++] = b->rms[i];
    }
    b->median_rms = n_ok ? median(w, n_ok, w + n) : NAN;
    for (size_t i = 0; i < n; i++) {
        if (b->missing[i]) continue;
        if (b->rms[i] <= o->flat * b->median_rms) b->flags[i] |= THX_BAD_FLAT;
        /* a flat row is "at its extreme" everywhere: saturation is said of a row that moves */
        if (!(b->flags[i] & THX_BAD_FLAT) && b->extreme[i] >= o->saturated &&
            b->extreme[i] * (double)nf >= THX_BAD_SATURATED_MIN - 0.5)
            b->flags[i] |= THX_BAD_SATURATED;
    }

    /* the most alike row of each (rows sorted by rms: a pair with d <= tol has rms within 1 - tol of
       each other, as |rms_i - rms_j| <= rms(x_i - x_j)) */
    double tol = surf ? o->duplicate : o->duplicate_exact;
    size_t n_ord = 0;
    for (size_t i = 0; i < n; i++)
        if (!b->missing[i] && !(b->flags[i] & THX_BAD_FLAT)) order[n_ord++] = (by_rms){i, b->rms[i]};
    qsort(order, n_ord, sizeof *order, cmp_by_rms);
    for (size_t a = 0; a < n_ord; a++)
        for (size_t c = a + 1; c < n_ord && order[c].rms * (1 - tol) <= order[a].rms; c++) {
            size_t i = order[a].i, j = order[c].i;
            double d = pair_d(X, nf, b->rms, i, j);
            if (!(d <= tol)) continue;
            if (surf && adjacent(&r, (int32_t)i, (int32_t)j)) continue;
            if (isnan(b->d[i]) || d < b->d[i]) { b->d[i] = d; b->nearest[i] = (int32_t)j; }
            if (isnan(b->d[j]) || d < b->d[j]) { b->d[j] = d; b->nearest[j] = (int32_t)i; }
        }
    /* with a surface, how well each row's neighbours predict it (flat, saturated and missing rows
       left out): of a duplicated pair, a row its neighbours predict (unlike <= 1) is the original */
    if (surf) {
        for (size_t i = 0; i < n; i++) good[i] = !b->missing[i] && !(b->flags[i] & (THX_BAD_FLAT | THX_BAD_SATURATED));
        for (size_t i = 0; i < n; i++)
            if (good[i])
                b->n_nb[i] = (int32_t)neighbour_scores(&r, X, nf, b->rms, good, i, m, w, &b->unlike[i], &b->ratio[i],
                                                       &b->corr[i]);
    }
    for (size_t i = 0; i < n; i++) {
        int32_t j = b->nearest[i];
        if (j < 0) continue;
        int dup = 0;
        if (!surf) {
            dup = 1;
        } else {
            /* how alike each of the pair is to its own neighbours */
            double c[2] = {INFINITY, INFINITY};
            size_t p[2] = {i, (size_t)j};
            for (int q = 0; q < 2; q++)
                for (size_t k = r.start[p[q]]; k < r.start[p[q] + 1]; k++) {
                    int32_t nb = r.adj[k];
                    if (b->missing[nb] || (b->flags[nb] & THX_BAD_FLAT)) continue;
                    double d = pair_d(X, nf, b->rms, p[q], (size_t)nb);
                    if (d < c[q]) c[q] = d;
                }
            double cm = c[0] < c[1] ? c[0] : c[1];
            b->contrast[i] = isfinite(cm) && cm > 0 ? b->d[i] / cm : NAN;
            dup = isfinite(cm) && b->d[i] <= o->duplicate_contrast * cm && !(b->n_nb[i] >= 2 && b->unlike[i] <= 1);
        }
        if (dup) {
            b->flags[i] |= THX_BAD_DUPLICATE;
            b->twin[i] = j;
        }
    }

    /* the neighbour checks, one worst row at a time */
    if (surf) {
        for (;;) {
            for (size_t i = 0; i < n; i++) good[i] = !b->missing[i] && !b->flags[i];
            double worst = 1;
            size_t wi = n;
            unsigned wflag = 0;
            for (size_t i = 0; i < n; i++) {
                if (b->missing[i] || (b->flags[i] & (THX_BAD_FLAT | THX_BAD_SATURATED))) continue;
                double un, ra, co;
                b->n_nb[i] = (int32_t)neighbour_scores(&r, X, nf, b->rms, good, i, m, w, &un, &ra, &co);
                b->unlike[i] = un;
                b->ratio[i] = ra;
                b->corr[i] = co;
                if (b->flags[i] || b->n_nb[i] < 2) continue;
                double e[3] = {un / o->unlike, ra > 0 ? o->small / ra : INFINITY, ra / o->large};
                unsigned fl[3] = {THX_BAD_UNLIKE, THX_BAD_SMALL, THX_BAD_LARGE};
                for (int q = 0; q < 3; q++)
                    if (e[q] > worst) { worst = e[q]; wi = i; wflag = fl[q]; }
            }
            if (wi == n) break;
            b->flags[wi] |= wflag;
        }
        /* every neighbour threshold a bad row exceeds (scores of the last round), as its reasons */
        for (size_t i = 0; i < n; i++) {
            if (!b->flags[i] || b->missing[i] || b->n_nb[i] < 2 || (b->flags[i] & (THX_BAD_FLAT | THX_BAD_SATURATED)))
                continue;
            if (b->unlike[i] > o->unlike) b->flags[i] |= THX_BAD_UNLIKE;
            if (b->ratio[i] < o->small) b->flags[i] |= THX_BAD_SMALL;
            if (b->ratio[i] > o->large) b->flags[i] |= THX_BAD_LARGE;
        }
    }
    for (size_t i = 0; i < n; i++) b->n_bad += b->flags[i] != 0;
done:
    ring_free(&r);
    free(X);
    free(w);
    free(m);
    free(good);
    free(order);
    if (st != THX_OK) {
        thx_bad_leads_destroy(&b);
        return st;
    }
    *out = b;
    return THX_OK;
}

static void appendf(char *buf, size_t cap, size_t *len, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void appendf(char *buf, size_t cap, size_t *len, const char *fmt, ...)
{
    if (*len + 1 >= cap) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(buf + *len, cap - *len, fmt, ap);
    va_end(ap);
    if (k > 0) *len = *len + (size_t)k < cap ? *len + (size_t)k : cap - 1;
}

void thx_bad_leads_reason(const thx_bad_leads *b, size_t i, const int *channel, char *buf, size_t cap)
{
    size_t len = 0;
    if (!cap) return;
    buf[0] = '\0';
    unsigned f = b->flags[i];
    const char *sep = "";
    if (f & THX_BAD_LISTED) { appendf(buf, cap, &len, "listed"); sep = "; "; }
    if (f & THX_BAD_FLAT) { appendf(buf, cap, &len, "%sflat (rms %.3g, median %.3g)", sep, b->rms[i], b->median_rms); sep = "; "; }
    if (f & THX_BAD_SATURATED) {
        appendf(buf, cap, &len, "%ssaturated (%.0f%% of the frames at its extreme)", sep, 100 * b->extreme[i]);
        sep = "; ";
    }
    if ((f & THX_BAD_DUPLICATE) && b->twin[i] >= 0) {
        int32_t t = b->twin[i];
        appendf(buf, cap, &len, "%sduplicate of channel %d (d %.3f)", sep, channel ? (int)channel[t] : (int)t + 1, b->d[i]);
        sep = "; ";
    }
    if (f & THX_BAD_UNLIKE) {
        appendf(buf, cap, &len, "%sunlike its neighbours (residual %.2f x its rms)", sep, b->unlike[i]);
        sep = "; ";
    }
    if (f & THX_BAD_SMALL) { appendf(buf, cap, &len, "%ssmall (%.3f x its neighbours' rms)", sep, b->ratio[i]); sep = "; "; }
    if (f & THX_BAD_LARGE) { appendf(buf, cap, &len, "%slarge (%.3g x its neighbours' rms)", sep, b->ratio[i]); sep = "; "; }
}

/* ------------------------------------------------------------------ the list */

thx_status thx_bad_list_read(thx_ctx *ctx, const char *path, size_t max_channel, int32_t **channels, size_t *n)
{
    *channels = NULL;
    *n = 0;
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    if (memchr(text, '\0', len)) {
        free(text);
        return thx_error(ctx, THX_EINPUT, "%s: a NUL byte: not a bad-lead list (text)", path);
    }
    int32_t *ch = NULL, *lines = NULL;
    size_t cnt = 0, cap = 0, capl = 0;
    thx_status st = THX_OK;
    int line = 0;
    for (char *p = text; *p;) {
        char *eol = strchr(p, '\n');
        if (eol) *eol = '\0';
        line++;
        char *hash = strchr(p, '#');
        if (hash) *hash = '\0';
        while (isspace((unsigned char)*p)) p++;
        if (*p) {
            char *end = NULL;
            errno = 0;
            long v = strtol(p, &end, 10);
            if (end == p || errno || (*end && !isspace((unsigned char)*end))) {
                char word[40];
                size_t wl = strcspn(p, " \t\r");
                snprintf(word, sizeof word, "%.*s", (int)(wl < 32 ? wl : 32), p);
                st = thx_error(ctx, THX_EINPUT, "%s:%d: '%s' is not a channel number (1-based)", path, line, word);
                break;
            }
            if (v < 1 || v > INT32_MAX || (max_channel && (size_t)v > max_channel)) {
                if (max_channel)
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: channel %ld: the series has channels 1..%zu", path, line, v,
                                   max_channel);
                else
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: channel %ld: channels count from 1", path, line, v);
                break;
            }
            for (size_t k = 0; k < cnt; k++)
                if (ch[k] == (int32_t)(v - 1)) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: channel %ld listed twice (first on line %d)", path, line, v,
                                   (int)lines[k]);
                    break;
                }
            if (st != THX_OK) break;
            if ((st = thx_grow(ctx, (void **)&ch, &cap, cnt + 1, sizeof *ch)) != THX_OK) break;
            if ((st = thx_grow(ctx, (void **)&lines, &capl, cnt + 1, sizeof *lines)) != THX_OK) break;
            ch[cnt] = (int32_t)(v - 1);
            lines[cnt++] = line;
        }
        if (!eol) break;
        p = eol + 1;
    }
    free(text);
    free(lines);
    if (st != THX_OK) {
        free(ch);
        return st;
    }
    if (cnt) qsort(ch, cnt, sizeof *ch, cmp_i32); /* an empty list has no array (UBSan: qsort(NULL, 0)) */
    *channels = ch;
    *n = cnt;
    return THX_OK;
}

typedef struct {
    int32_t channel;
    size_t row;
} chan_row;

static int cmp_chan_row(const void *a, const void *b)
{
    const chan_row *x = a, *y = b;
    if (x->channel != y->channel) return (x->channel > y->channel) - (x->channel < y->channel);
    return (x->row > y->row) - (x->row < y->row);
}

thx_status thx_bad_list_write(thx_ctx *ctx, const char *path, const thx_bad_leads *b, const int *channel,
                              const char *note)
{
    chan_row *cr = thx_malloc(ctx, (b->n + 1) * sizeof *cr);
    if (!cr) return THX_ENOMEM;
    size_t k = 0;
    for (size_t i = 0; i < b->n; i++)
        if (b->flags[i]) cr[k++] = (chan_row){channel ? channel[i] : (int32_t)i + 1, i};
    qsort(cr, k, sizeof *cr, cmp_chan_row);
    thx_atomic_file af;
    thx_status st = thx_atomic_open_output(ctx, path, "# thorax bad-lead list", 22, NULL, 0, &af);
    if (st != THX_OK) {
        free(cr);
        return st;
    }
    fprintf(af.f, "# thorax bad-lead list: one channel a line (1-based, the recording's rows), then why\n");
    if (note && *note) fprintf(af.f, "# %s\n", note);
    fprintf(af.f, "# %zu bad of %zu\n", k, b->n);
    char why[512];
    for (size_t q = 0; q < k; q++) {
        thx_bad_leads_reason(b, cr[q].row, channel, why, sizeof why);
        fprintf(af.f, "%d  %s\n", (int)cr[q].channel, why);
    }
    free(cr);
    st = thx_atomic_commit(ctx, &af);
    if (st != THX_OK) thx_atomic_abort(&af);
    return st;
}

/* ------------------------------------------------------------------ marking and filling */

thx_status thx_bad_leads_mark(thx_ctx *ctx, const char *spec, const thx_series *s, const thx_surface *surf,
                              const int *channel, unsigned char *bad, size_t *n_bad)
{
    size_t n = s->n_rows, cnt = 0, len = 0;
    char list[480] = "";
    memset(bad, 0, n);
    *n_bad = 0;
    if (!strcmp(spec, "auto")) {
        thx_bad_leads *b = NULL;
        THX_CHECK(thx_bad_leads_detect(ctx, s, surf, NULL, &b));
        char why[512];
        for (size_t i = 0; i < n; i++) {
            if (!b->flags[i]) continue;
            bad[i] = 1;
            thx_bad_leads_reason(b, i, channel, why, sizeof why);
            thx_log(ctx, THX_LOG_DEBUG, "--bad-leads auto: channel %d: %s", channel ? channel[i] : (int)i + 1, why);
        }
        thx_bad_leads_destroy(&b);
    } else {
        int32_t *ch = NULL;
        size_t nl = 0;
        THX_CHECK(thx_bad_list_read(ctx, spec, 0, &ch, &nl));
        for (size_t k = 0; k < nl; k++) {
            int hit = 0;
            for (size_t i = 0; i < n; i++)
                if ((channel ? channel[i] : (int)i + 1) == (int)ch[k] + 1) bad[i] = 1, hit = 1;
            if (!hit) thx_log(ctx, THX_LOG_INFO, "%s: channel %d is not in the series (ignored)", spec, (int)ch[k] + 1);
        }
        free(ch);
    }
    for (size_t i = 0; i < n; i++)
        if (bad[i]) {
            cnt++;
            if (len < sizeof list - 16)
                appendf(list, sizeof list, &len, "%s%d", cnt > 1 ? ", " : ": ", channel ? channel[i] : (int)i + 1);
            else if (len < sizeof list - 1)
                appendf(list, sizeof list, &len, " ...");
        }
    *n_bad = cnt;
    thx_log(ctx, THX_LOG_INFO, "--bad-leads %s: %zu bad channel%s%s", spec, cnt, cnt == 1 ? "" : "s", list);
    return THX_OK;
}

thx_status thx_bad_leads_fill(thx_ctx *ctx, const char *spec, const thx_surface *surf, const int *channel, thx_series *s)
{
    if (surf->n_nodes != s->n_rows)
        return thx_error(ctx, THX_EINPUT, "--bad-leads: %zu rows, surface '%s' has %zu nodes", s->n_rows, surf->name,
                         surf->n_nodes);
    unsigned char *bad = thx_malloc(ctx, s->n_rows + 1);
    if (!bad) return THX_ENOMEM;
    size_t n_bad = 0;
    thx_status st = thx_bad_leads_mark(ctx, spec, s, surf, channel, bad, &n_bad);
    if (st == THX_OK && n_bad) st = thx_bad_leads_interpolate(ctx, surf, s, bad);
    if (st == THX_OK && n_bad)
        thx_log(ctx, THX_LOG_INFO, "--bad-leads: %zu node%s of '%s' filled by Laplacian interpolation", n_bad,
                n_bad == 1 ? "" : "s", surf->name);
    free(bad);
    return st;
}

/* ------------------------------------------------------------------ Laplacian interpolation */

/* Cholesky A = R^T R in place (upper triangle of the row-major n x n A); 0, or 1 + the failing pivot. */
static size_t cholesky(double *A, size_t n)
{
    for (size_t j = 0; j < n; j++) {
        double d = A[j * n + j];
        for (size_t k = 0; k < j; k++) d -= A[k * n + j] * A[k * n + j];
        if (!(d > 0)) return j + 1;
        d = sqrt(d);
        A[j * n + j] = d;
        for (size_t i = j + 1; i < n; i++) {
            double v = A[j * n + i];
            for (size_t k = 0; k < j; k++) v -= A[k * n + j] * A[k * n + i];
            A[j * n + i] = v / d;
        }
    }
    return 0;
}

static void chol_solve(const double *R, size_t n, double *x)
{
    for (size_t i = 0; i < n; i++) { /* R^T y = b */
        double v = x[i];
        for (size_t k = 0; k < i; k++) v -= R[k * n + i] * x[k];
        x[i] = v / R[i * n + i];
    }
    for (size_t i = n; i-- > 0;) { /* R x = y */
        double v = x[i];
        for (size_t k = i + 1; k < n; k++) v -= R[i * n + k] * x[k];
        x[i] = v / R[i * n + i];
    }
}

thx_status thx_bad_leads_interpolate(thx_ctx *ctx, const thx_surface *surf, thx_series *s, const unsigned char *fill)
{
    size_t n = s->n_rows, nf = s->n_frames;
    if (surf->n_nodes != n)
        return thx_error(ctx, THX_EINPUT, "Laplacian interpolation: %zu rows, surface '%s' has %zu nodes", n, surf->name,
                         surf->n_nodes);
    size_t nb = 0;
    for (size_t i = 0; i < n; i++) nb += fill[i] != 0;
    if (!nb) return THX_OK;
    if (nb > 4000)
        return thx_error(ctx, THX_EINPUT, "Laplacian interpolation: %zu nodes to fill on '%s' (at most 4000)", nb, surf->name);
    ring r;
    THX_CHECK(ring_build(ctx, surf, &r));
    thx_status st = THX_OK;
    double *L = NULL, *A = NULL, *rk = NULL, *x = NULL;
    int32_t *col = NULL, *rows = NULL, *comp = NULL, *stack = NULL;
    unsigned char *inrow = NULL;
    size_t nnz = r.start[n];
    L = thx_malloc(ctx, (nnz + n + 1) * sizeof *L); /* off-diagonal weights in ring order, then the diagonals */
    col = thx_malloc(ctx, (n + 1) * sizeof *col);    /* node -> its unknown's number, -1 for a kept node */
    rows = thx_malloc(ctx, (n + 1) * sizeof *rows);  /* the Laplacian rows that touch an unknown */
    inrow = thx_calloc(ctx, n + 1, 1);
    comp = thx_malloc(ctx, (n + 1) * sizeof *comp);
    stack = thx_malloc(ctx, (n + 1) * sizeof *stack);
    A = thx_calloc(ctx, nb * nb, sizeof *A);
    rk = thx_malloc(ctx, (n + 1) * sizeof *rk);
    x = thx_malloc(ctx, nb * sizeof *x);
    if (!L || !col || !rows || !inrow || !comp || !stack || !A || !rk || !x) {
        st = THX_ENOMEM;
        goto done;
    }
    double *diag = L + nnz;
    for (size_t i = 0; i < n; i++) {
        size_t a = r.start[i], e = r.start[i + 1];
        diag[i] = 0;
        if (a == e) continue; /* a node in no triangle: no row */
        double hbar = 0;
        for (size_t k = a; k < e; k++) {
            const double *p = surf->xyz + 3 * i, *q = surf->xyz + 3 * (size_t)r.adj[k];
            double h = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            if (!(h > 0)) {
                st = thx_error(ctx, THX_EGEOM, "surface '%s': nodes %zu and %d coincide (an edge of length 0)", surf->name,
                               i + 1, (int)r.adj[k] + 1);
                goto done;
            }
            L[k] = h;
            hbar += h;
        }
        hbar /= (double)(e - a);
        double scale = 4.0 / (hbar * (double)(e - a));
        for (size_t k = a; k < e; k++) {
            L[k] = scale / L[k];
            diag[i] -= L[k];
        }
    }
    /* unknowns; each group of connected filled nodes must touch a kept node */
    size_t u = 0;
    for (size_t i = 0; i < n; i++) col[i] = fill[i] ? (int32_t)u++ : -1;
    for (size_t i = 0; i < n; i++) comp[i] = -1;
    for (size_t i = 0; i < n; i++) {
        if (!fill[i] || comp[i] >= 0) continue;
        size_t top = 0;
        int touches = 0;
        stack[top++] = (int32_t)i;
        comp[i] = (int32_t)i;
        while (top) {
            int32_t v = stack[--top];
            for (size_t k = r.start[v]; k < r.start[v + 1]; k++) {
                int32_t w2 = r.adj[k];
                if (!fill[w2]) touches = 1;
                else if (comp[w2] < 0) { comp[w2] = (int32_t)i; stack[top++] = w2; }
            }
        }
        if (!touches) {
            st = thx_error(ctx, THX_EINPUT,
                           "Laplacian interpolation on '%s': node %zu (with the filled nodes joined to it) has no kept "
                           "neighbour to be filled from",
                           surf->name, i + 1);
            goto done;
        }
    }
    /* the rows of L with an unknown: the unknowns and their neighbours */
    size_t nr = 0;
    for (size_t i = 0; i < n; i++) {
        if (!fill[i]) continue;
        if (!inrow[i]) { inrow[i] = 1; rows[nr++] = (int32_t)i; }
        for (size_t k = r.start[i]; k < r.start[i + 1]; k++)
            if (!inrow[r.adj[k]]) { inrow[r.adj[k]] = 1; rows[nr++] = r.adj[k]; }
    }
    qsort(rows, nr, sizeof *rows, cmp_i32);
    /* A = L_B^T L_B: row k of L contributes L_ka L_kb for every pair of unknowns a, b in it */
    for (size_t q = 0; q < nr; q++) {
        int32_t k = rows[q];
        size_t a0 = r.start[k], e0 = r.start[k + 1];
        for (size_t p1 = a0; p1 <= e0; p1++) {
            int32_t na = p1 < e0 ? r.adj[p1] : k;
            double la = p1 < e0 ? L[p1] : diag[k];
            if (col[na] < 0) continue;
            for (size_t p2 = a0; p2 <= e0; p2++) {
                int32_t nb2 = p2 < e0 ? r.adj[p2] : k;
                double lb = p2 < e0 ? L[p2] : diag[k];
                if (col[nb2] < 0) continue;
                A[(size_t)col[na] * nb + (size_t)col[nb2]] += la * lb;
            }
        }
    }
    size_t fail = cholesky(A, nb);
    if (fail) {
        st = thx_error(ctx, THX_EINTERNAL, "Laplacian interpolation on '%s': the system is singular at unknown %zu", surf->name,
                       fail);
        goto done;
    }
    for (size_t f = 0; f < nf; f++) {
        double *v = s->v + f * n;
        /* r_k = (L_G u_G)_k over the rows touching an unknown */
        for (size_t q = 0; q < nr; q++) {
            int32_t k = rows[q];
            double acc = col[k] < 0 ? diag[k] * v[k] : 0;
            for (size_t p = r.start[k]; p < r.start[k + 1]; p++)
                if (col[r.adj[p]] < 0) acc += L[p] * v[r.adj[p]];
            rk[q] = acc;
        }
        memset(x, 0, nb * sizeof *x);
        for (size_t q = 0; q < nr; q++) {
            int32_t k = rows[q];
            if (col[k] >= 0) x[col[k]] -= diag[k] * rk[q];
            for (size_t p = r.start[k]; p < r.start[k + 1]; p++)
                if (col[r.adj[p]] >= 0) x[col[r.adj[p]]] -= L[p] * rk[q];
        }
        chol_solve(A, nb, x);
        for (size_t i = 0; i < n; i++)
            if (col[i] >= 0) v[i] = x[col[i]];
    }
done:
    ring_free(&r);
    free(L);
    free(col);
    free(rows);
    free(inrow);
    free(comp);
    free(stack);
    free(A);
    free(rk);
    free(x);
    return st;
}
