/*
 * Colour scales (thorax/render/image.h; paper 4.2, "Standards"): a value to t in [0, 1] under a
 * scaling model (linear, log, exp, map3d's lab7 and lab13) and a mapping (true, symmetric,
 * midpoint, separate), the inverse for labels, bands, levels, and the range rule.
 *
 * Every evaluation first resolves the scale (the struct as the caller filled it) into a form ready
 * for values: a centre and a half width on each side for the analytic models, knots for the lab
 * models. Resolving a lab scale finds its levels (a log10 and a few steps per side), so
 * thx_scale_apply_n resolves once for many values.
 *
 * Invariants:
 *  - TRUE and MIDPOINT under linear, log and exp are computed with exactly the operations of the
 *    scale before mappings existed (c = (lo + hi) / 2, h = (hi - lo) / 2, u = (v - c) / h ...), and
 *    SYMMETRIC with lo = -M, hi = M too, so pictures made before do not change by a bit; that
 *    includes lo > hi, the reversed colours of the picture module (h < 0).
 *  - lo > hi under SEPARATE or a lab model: the scale of hi..lo with t turned to 1 - t.
 *  - Lab knots y[0] < y[1] < ... < y[n] with t(y[j]) = j / n; y[1 .. n - 1] are the levels. A level
 *    value is an integer mantissa (10, 15, 22, ...) times or divided by an exact power of ten: the
 *    double nearest to the decimal value (4.7, 0.068) over the range of exact powers (1e-22..1e22).
 */
#include <math.h>
#include <string.h>

#include "thorax/render/image.h"

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

/* ------------------------------------------------------------- names */

static const char *const MODEL_NAMES[] = {"linear", "log", "exp", "lab7", "lab13"};
static const char *const MAPPING_NAMES[] = {"true", "symmetric", "midpoint", "separate"};
#define N_MODELS ((int)(sizeof MODEL_NAMES / sizeof MODEL_NAMES[0]))
#define N_MAPPINGS ((int)(sizeof MAPPING_NAMES / sizeof MAPPING_NAMES[0]))

static int find_name(const char *const *names, int n, const char *name)
{
    if (!name) return -1;
    for (int i = 0; i < n; i++)
        if (!strcmp(name, names[i])) return i;
    return -1;
}

int thx_scale_model_parse(const char *name, thx_scale_model *out)
{
    int i = find_name(MODEL_NAMES, N_MODELS, name);
    if (i < 0) return -1;
    *out = (thx_scale_model)i;
    return 0;
}

const char *thx_scale_model_name(thx_scale_model m) { return (int)m >= 0 && (int)m < N_MODELS ? MODEL_NAMES[m] : "unknown"; }

int thx_scale_mapping_parse(const char *name, thx_scale_mapping *out)
{
    int i = find_name(MAPPING_NAMES, N_MAPPINGS, name);
    if (i < 0) return -1;
    *out = (thx_scale_mapping)i;
    return 0;
}

const char *thx_scale_mapping_name(thx_scale_mapping m)
{
    return (int)m >= 0 && (int)m < N_MAPPINGS ? MAPPING_NAMES[m] : "unknown";
}

/* ------------------------------------------------------------- the lab series */

/* One decade of each series as integer mantissas (value = mantissa / 10 within the decade
   [1, 10)); the decade's end, 10, is the next decade's 1. */
static const int LAB7[6] = {10, 15, 22, 33, 47, 68};
static const int LAB13[12] = {10, 12, 15, 18, 22, 27, 33, 39, 47, 56, 68, 82};

static int is_lab(thx_scale_model m) { return m == THX_SCALE_LAB7 || m == THX_SCALE_LAB13; }

/* m times 10^e, correctly rounded where 10^|e| is exact (|e| <= 22). */
static double times_pow10(double m, int e)
{
    static const double P[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    if (e >= 0) return e <= 22 ? m * P[e] : m * pow(10, e);
    return -e <= 22 ? m / P[-e] : m / pow(10, -e);
}

/* The g-th value of the series (g = 0: 1, ascending; p entries per decade). */
static double lab_value(const int *series, int p, long g)
{
    long d = g >= 0 ? g / p : -((-g + p - 1) / p); /* the decade, rounded down */
    return times_pow10(series[g - d * p], (int)(d - 1));
}

/* The m levels below h, descending: the largest value of the series strictly below h, then the
   next m - 1 down (one decade: the last is the first / 10). 0 if h is not a positive normal
   number. */
static int lab_levels(thx_scale_model model, double h, double *out)
{
    if (!isnormal(h) || h <= 0) return 0;
    const int *series = model == THX_SCALE_LAB13 ? LAB13 : LAB7;
    int p = model == THX_SCALE_LAB13 ? 12 : 6, m = p + 1;
    long g = (long)floor(log10(h)) * p + p - 1; /* the top of h's decade, give or take log10's rounding */
    for (int guard = 0; guard < 4 * p && lab_value(series, p, g) >= h; guard++) g--;
    for (int guard = 0; guard < 4 * p && lab_value(series, p, g + 1) < h; guard++) g++;
    for (int i = 0; i < m; i++) out[i] = lab_value(series, p, g - i);
    return m;
}

/* ------------------------------------------------------------- a scale resolved for values */

#define MAX_KNOTS (2 * 13 + 3)

typedef struct {
    int lab;          /* knots below, else the analytic form */
    int flip;         /* lo > hi under SEPARATE or a lab model: t -> 1 - t of the range put in order */
    int step;         /* a degenerate range: 0 below c, 1 above, 0.5 at c */
    int separate;     /* analytic: h- below c, h+ above */
    thx_scale_model model;
    double c, h, hn, hp;
    double k, norm;   /* log/exp: strength and log1p(k) or expm1(k) */
    int n;            /* lab: bands; knots y[0..n] */
    double y[MAX_KNOTS];
} resolved;

static double default_k(thx_scale_model m) { return m == THX_SCALE_LOG ? 10 : m == THX_SCALE_EXP ? 3 : 0; }

/* The strength in use: the struct's k, or the model's default when k is not positive. */
static double strength(const thx_scale *s) { return s->k > 0 && isfinite(s->k) ? s->k : default_k(s->model); }

/* SEPARATE's two half widths: |lo| below zero, hi above; a side without a range takes the other's. */
static void separate_sides(double lo, double hi, double *hn, double *hp)
{
    *hn = lo < 0 ? -lo : 0;
    *hp = hi > 0 ? hi : 0;
    if (*hn == 0) *hn = *hp;
    if (*hp == 0) *hp = *hn;
}

/* Knots of a lab scale about c with half widths hn below, hp above: 2 m + 3 of them. */
static int lab_two_sided(resolved *r, thx_scale_model model, double c, double hn, double hp)
{
    double ln[13], lp[13];
    int m = lab_levels(model, hn, ln);
    if (m == 0 || lab_levels(model, hp, lp) == 0) return -1;
    int j = 0;
    r->y[j++] = c - hn;
    for (int i = 0; i < m; i++) r->y[j++] = c - ln[i];
    r->y[j++] = c;
    for (int i = m - 1; i >= 0; i--) r->y[j++] = c + lp[i];
    r->y[j] = c + hp;
    r->n = j;
    return 0;
}

/* Knots of a TRUE lab scale over one sign: the levels of the side of larger magnitude strictly
   inside lo..hi. */
static int lab_one_sided(resolved *r, thx_scale_model model, double lo, double hi)
{
    double l[13];
    int neg = hi <= 0, m = lab_levels(model, neg ? -lo : hi, l), j = 0;
    if (m == 0) return -1;
    r->y[j++] = lo;
    if (neg) {
        for (int i = 0; i < m; i++)
            if (-l[i] < hi) r->y[j++] = -l[i];
    } else {
        for (int i = m - 1; i >= 0; i--)
            if (l[i] > lo) r->y[j++] = l[i];
    }
    r->y[j] = hi;
    r->n = j;
    return 0;
}

static void resolve(const thx_scale *s, resolved *r)
{
    r->model = s->model;
    r->lab = is_lab(s->model);
    r->step = r->separate = r->flip = 0;
    r->n = 0;
    double lo = s->lo, hi = s->hi;
    int reversed = lo > hi;
    if (s->mapping == THX_MAPPING_SYMMETRIC) {
        double mag = fmax(fabs(lo), fabs(hi));
        lo = reversed ? mag : -mag, hi = reversed ? -mag : mag;
    }
    if (reversed && (r->lab || s->mapping == THX_MAPPING_SEPARATE)) {
        /* these are built on an ascending range: build that, and turn t around */
        double x = lo;
        lo = hi, hi = x;
        r->flip = 1;
    }
    /* TRUE, MIDPOINT and SYMMETRIC: the centre and half width as the scale always had them (a
       reversed range, h < 0, turns the analytic models around by itself) */
    r->c = 0.5 * (lo + hi);
    r->h = 0.5 * (hi - lo);
    r->hn = r->hp = r->h;
    if (s->mapping == THX_MAPPING_SEPARATE) {
        r->separate = 1;
        r->c = 0;
        separate_sides(lo, hi, &r->hn, &r->hp);
    }
    if (!r->lab) {
        r->k = strength(s);
        r->norm = s->model == THX_SCALE_LOG ? log1p(r->k) : s->model == THX_SCALE_EXP ? expm1(r->k) : 1;
        if (r->separate) r->step = r->hn == 0 || !isfinite(r->hn) || r->hp == 0 || !isfinite(r->hp);
        else r->step = r->h == 0 || !isfinite(r->h);
        return;
    }
    int bad;
    if (s->mapping == THX_MAPPING_TRUE && !(lo < 0 && hi > 0)) {
        bad = !(lo < hi) || !isfinite(lo) || !isfinite(hi) || lab_one_sided(r, s->model, lo, hi) != 0;
    } else {
        if (s->mapping == THX_MAPPING_TRUE) r->c = 0, r->hn = -lo, r->hp = hi; /* map3d's: each side its own */
        bad = lab_two_sided(r, s->model, r->c, r->hn, r->hp) != 0;
    }
    if (bad) r->step = 1;
}

/* t of v, the range taken in ascending order. */
static double eval_ordered(const resolved *r, double v)
{
    if (isnan(v)) return v;
    if (r->step) return v < r->c ? 0 : v > r->c ? 1 : 0.5;
    if (r->lab) {
        const double *y = r->y;
        int n = r->n;
        if (!(v > y[0])) return 0;
        if (!(v < y[n])) return 1;
        int a = 0, b = n; /* y[a] < v < y[b] */
        while (b - a > 1) {
            int mid = (a + b) / 2;
            if (y[mid] <= v) a = mid;
            else b = mid;
        }
        double width = y[a + 1] - y[a], f = width > 0 ? (v - y[a]) / width : 0;
        return (a + f) / n;
    }
    double h = r->separate && v < r->c ? r->hn : r->separate ? r->hp : r->h;
    double u = (v - r->c) / h;
    u = u < -1 ? -1 : u > 1 ? 1 : u;
    double a = fabs(u), w = a;
    if (r->model == THX_SCALE_LOG) w = log1p(r->k * a) / r->norm;
    else if (r->model == THX_SCALE_EXP) w = expm1(r->k * a) / r->norm;
    return 0.5 * (copysign(w, u) + 1);
}

/* t of v (a reversed range turned around). */
static double eval(const resolved *r, double v)
{
    double t = eval_ordered(r, v);
    return r->flip ? 1 - t : t;
}

static double uneval(const resolved *r, double t)
{
    if (isnan(t)) return t;
    t = clamp01(t);
    if (r->flip) t = 1 - t;
    if (r->lab && !r->step) {
        double x = t * r->n;
        int j = (int)floor(x);
        if (j > r->n - 1) j = r->n - 1;
        return r->y[j] + (x - j) * (r->y[j + 1] - r->y[j]);
    }
    if (r->lab) return r->c;
    double w = 2 * t - 1, a = fabs(w), u = a;
    double h = r->separate && w < 0 ? r->hn : r->separate ? r->hp : r->h;
    if (r->model == THX_SCALE_LOG) u = expm1(a * r->norm) / r->k;
    else if (r->model == THX_SCALE_EXP) u = log1p(a * r->norm) / r->k;
    return r->c + h * copysign(u, w);
}

/* ------------------------------------------------------------- the public calls */

double thx_scale_apply(const thx_scale *s, double v)
{
    if (isnan(v)) return v;
    resolved r;
    resolve(s, &r);
    return eval(&r, v);
}

void thx_scale_apply_n(const thx_scale *s, const double *v, size_t n, float *t)
{
    resolved r;
    resolve(s, &r);
    for (size_t i = 0; i < n; i++) t[i] = (float)eval(&r, v[i]);
}

double thx_scale_invert(const thx_scale *s, double t)
{
    if (isnan(t)) return t;
    resolved r;
    resolve(s, &r);
    return uneval(&r, t);
}

double thx_scale_band(double t, int n)
{
    if (isnan(t) || n <= 0) return t;
    t = clamp01(t);
    double b = floor(t * n);
    if (b > n - 1) b = n - 1; /* t = 1 belongs to the last band */
    return (b + 0.5) / n;
}

int thx_scale_bands(const thx_scale *s, int n_requested)
{
    if (!is_lab(s->model)) return n_requested;
    resolved r;
    resolve(s, &r);
    return r.step ? 1 : r.n;
}

int thx_scale_levels(const thx_scale *s, int n_requested, double *out, int max)
{
    resolved r;
    resolve(s, &r);
    int n = r.lab ? (r.step ? 1 : r.n) : n_requested;
    if (n < 1) return 0;
    int down = !r.lab && uneval(&r, 0) > uneval(&r, 1); /* a reversed range: read t from the top */
    for (int j = 1; j < n && j - 1 < max; j++)
        out[j - 1] = r.lab ? r.y[j] : uneval(&r, (double)(down ? n - j : j) / n);
    return n - 1;
}

/* ------------------------------------------------------------- ranges */

void thx_scale_from_range_mapped(thx_scale *s, thx_scale_model model, thx_scale_mapping mapping, double lo, double hi)
{
    s->model = model;
    s->mapping = mapping;
    s->k = default_k(model);
    if (!(lo <= hi) || !isfinite(lo) || !isfinite(hi)) { /* no finite value */
        s->lo = -1, s->hi = 1;
    } else if (mapping == THX_MAPPING_SYMMETRIC) {
        /* the largest magnitude, whichever side it is on; all zeros: -1/1, so zero still sits in the middle */
        double mag = fmax(fabs(lo), fabs(hi));
        s->hi = mag > 0 ? mag : 1;
        s->lo = -s->hi;
    } else if (mapping == THX_MAPPING_SEPARATE) {
        /* the magnitudes of the two ends are the two sides' scales; all zeros: -1/1 */
        if (lo == 0 && hi == 0) s->lo = -1, s->hi = 1;
        else s->lo = lo, s->hi = hi;
    } else if (lo == hi) {
        /* Constant data: a unit range around the value, which maps to the middle. */
        s->lo = lo - 1, s->hi = hi + 1;
    } else {
        s->lo = lo, s->hi = hi;
    }
}

void thx_scale_from_data_mapped(thx_scale *s, thx_scale_model model, thx_scale_mapping mapping, const double *v,
                                size_t n)
{
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i])) continue;
        lo = fmin(lo, v[i]);
        hi = fmax(hi, v[i]);
    }
    thx_scale_from_range_mapped(s, model, mapping, lo, hi);
}

void thx_scale_from_range(thx_scale *s, thx_scale_model model, double lo, double hi, int symmetric)
{
    thx_scale_from_range_mapped(s, model, symmetric ? THX_MAPPING_SYMMETRIC : THX_MAPPING_TRUE, lo, hi);
}

void thx_scale_from_data(thx_scale *s, thx_scale_model model, const double *v, size_t n, int symmetric)
{
    thx_scale_from_data_mapped(s, model, symmetric ? THX_MAPPING_SYMMETRIC : THX_MAPPING_TRUE, v, n);
}
