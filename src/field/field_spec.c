/* The texts that name cuts (thorax/field/field.h): planes ("x=MM", "P:N") and value lists
 * ("-5,0,5", "0", "count:10", "25%,50%"). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/field/field.h"

/* Reads n numbers separated by commas from p; the end in *end. */
static int numbers(const char *p, double *x, int n, const char **end)
{
    for (int i = 0; i < n; i++) {
        char *e;
        errno = 0;
        x[i] = strtod(p, &e);
        if (e == p || errno || !isfinite(x[i])) return -1;
        p = e;
        if (i + 1 < n) {
            if (*p != ',') return -1;
            p++;
        }
    }
    *end = p;
    return 0;
}

thx_status thx_field_plane_parse(thx_ctx *ctx, const char *spec, thx_field_plane *pl)
{
    memset(pl, 0, sizeof *pl);
    const char *e;
    if ((spec[0] == 'x' || spec[0] == 'y' || spec[0] == 'z') && spec[1] == '=') {
        int axis = spec[0] - 'x';
        double d;
        if (numbers(spec + 2, &d, 1, &e) || *e)
            return thx_error(ctx, THX_EINPUT, "plane \"%s\": %c=MM expected (a finite number of mm)", spec, spec[0]);
        pl->n[axis] = 1;
        pl->d = d;
        pl->origin[axis] = d;
        return THX_OK;
    }
    double p[3], n[3];
    if (numbers(spec, p, 3, &e) || *e != ':' || numbers(e + 1, n, 3, &e) || *e)
        return thx_error(ctx, THX_EINPUT, "plane \"%s\": x=MM, y=MM, z=MM or PX,PY,PZ:NX,NY,NZ expected", spec);
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0) || !isfinite(len)) return thx_error(ctx, THX_EINPUT, "plane \"%s\": the normal is zero", spec);
    for (int i = 0; i < 3; i++) {
        pl->n[i] = n[i] / len;
        pl->origin[i] = p[i];
    }
    pl->d = pl->n[0] * p[0] + pl->n[1] * p[1] + pl->n[2] * p[2];
    return THX_OK;
}

thx_status thx_field_values_parse(thx_ctx *ctx, const char *spec, double lo, double hi, double **values, size_t *n)
{
    *values = NULL;
    *n = 0;
    if (!isfinite(lo) || !isfinite(hi) || lo > hi)
        return thx_error(ctx, THX_EINPUT, "values \"%s\": the range [%g, %g] is not a range", spec, lo, hi);
    /* a count has its own spelling, count:N; a number is always a value ("0" is the zero
       equipotential, the one asked for first) */
    if (!strncmp(spec, "count:", 6)) {
        const char *c0 = spec + 6;
        size_t len = strlen(c0), digits = strspn(c0, "0123456789");
        long c = len && digits == len && len <= 4 ? strtol(c0, NULL, 10) : 0;
        if (c < 1 || c > 1000)
            return thx_error(ctx, THX_EINPUT, "values \"%s\": count:N takes a count of values from 1 to 1000", spec);
        if (c > 1 && !(hi > lo))
            return thx_error(ctx, THX_EINPUT, "values \"%s\": the range is one value (%g): no %ld distinct values in it",
                             spec, lo, c);
        double *v = thx_malloc(ctx, (size_t)c * sizeof *v);
        if (!v) return THX_ENOMEM;
        for (long k = 1; k <= c; k++) v[k - 1] = lo + (hi - lo) * (double)k / (double)(c + 1);
        *values = v;
        *n = (size_t)c;
        return THX_OK;
    }
    size_t cap = 1;
    for (const char *p = spec; *p; p++) cap += *p == ',';
    double *v = thx_malloc(ctx, cap * sizeof *v);
    if (!v) return THX_ENOMEM;
    size_t k = 0;
    const char *p = spec;
    while (*p) {
        char *e;
        errno = 0;
        double x = strtod(p, &e);
        if (e == p || errno || !isfinite(x)) {
            free(v);
            return thx_error(ctx, THX_EINPUT, "values \"%s\": item %zu: a number or N%% expected (a count is count:N)", spec, k + 1);
        }
        if (*e == '%') {
            if (x < 0 || x > 100) {
                free(v);
                return thx_error(ctx, THX_EINPUT, "values \"%s\": item %zu: %g%% is outside 0..100%%", spec, k + 1, x);
            }
            x = lo + (hi - lo) * x / 100;
            e++;
        }
        for (size_t j = 0; j < k; j++)
            if (v[j] == x) {
                free(v);
                return thx_error(ctx, THX_EINPUT, "values \"%s\": item %zu: the value %g is given twice", spec, k + 1, x);
            }
        v[k++] = x;
        p = e;
        if (*p == ',') p++;
        else if (*p) {
            free(v);
            return thx_error(ctx, THX_EINPUT, "values \"%s\": item %zu: ',' expected after it", spec, k);
        }
    }
    if (!k) {
        free(v);
        return thx_error(ctx, THX_EINPUT, "values \"%s\": no value", spec);
    }
    *values = v;
    *n = k;
    return THX_OK;
}

thx_status thx_field_values_explicit(thx_ctx *ctx, const char *spec, double **values, size_t *n)
{
    /* read against two ranges: a count or a percentage moves with the range, a number does not */
    double *a = NULL, *b = NULL;
    size_t na = 0, nb = 0, k = 0;
    *values = NULL;
    *n = 0;
    thx_status st = thx_field_values_parse(ctx, spec, 0, 1, &a, &na);
    if (st == THX_OK) st = thx_field_values_parse(ctx, spec, 2, 3, &b, &nb);
    if (st == THX_OK && na == nb) {
        for (size_t i = 0; i < na; i++)
            if (a[i] == b[i]) a[k++] = a[i];
        *values = a;
        *n = k;
        a = NULL;
    }
    free(a);
    free(b);
    return st;
}

void thx_field_plane_span(const thx_volume *v, const unsigned char *use, const thx_field_plane *p, double *dmin,
                          double *dmax)
{
    *dmin = INFINITY;
    *dmax = -INFINITY;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (use && !use[v->region[t]]) continue;
        for (int c = 0; c < 4; c++) {
            const double *x = v->xyz + 3 * (size_t)v->tet[4 * t + c];
            double d = p->n[0] * x[0] + p->n[1] * x[1] + p->n[2] * x[2] - p->d;
            if (d < *dmin) *dmin = d;
            if (d > *dmax) *dmax = d;
        }
    }
}
