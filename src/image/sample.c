/*
 * Planes cut through an image and its default grey-level window (thorax/image/sample.h): what
 * `thorax render --image` and `thorax view --image` show under the model (issue 25).
 */
#include "thorax/image/sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SAMPLES 16384 /* along one side of a plane (the renderer's texture limit) */

int thx_image_plane_parse(const char *s, thx_image_plane_spec *out)
{
    if (!s || !strchr("xyzijk", s[0]) || !s[0] || s[1] != '=' || !s[2]) return -1;
    char *end = NULL;
    double v = strtod(s + 2, &end);
    if (!end || *end || !isfinite(v)) return -1;
    out->axis = s[0];
    out->pos = v;
    return 0;
}

/* The index axis most nearly along RAS axis r. */
static int index_axis_along(const thx_image *img, int r)
{
    int best = 0;
    for (int c = 1; c < 3; c++)
        if (fabs(img->dir[r * 3 + c]) > fabs(img->dir[r * 3 + best])) best = c;
    return best;
}

/* The range of RAS coordinate r over the box of continuous indices from a to n - 1 - a on every
 * axis (a = -0.5: the voxels' outer faces; a = 0: the outer voxel centres). */
static void ras_range(const thx_image *img, int r, double a, double *lo, double *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (int c = 0; c < 8; c++) {
        double ijk[3], p[3];
        for (int k = 0; k < 3; k++) ijk[k] = (c >> k) & 1 ? (double)img->n[k] - 1 - a : a;
        thx_image_index_to_ras(img, ijk, p);
        *lo = fmin(*lo, p[r]);
        *hi = fmax(*hi, p[r]);
    }
}

void thx_image_plane_range(const thx_image *img, char axis, double *lo, double *hi, double *step)
{
    if (axis >= 'i' && axis <= 'k') {
        *lo = 0;
        *hi = (double)img->n[axis - 'i'] - 1;
        *step = 1;
        return;
    }
    int r = axis - 'x';
    ras_range(img, r, -0.5, lo, hi);
    *step = img->spacing[index_axis_along(img, r)];
}

double thx_image_sample_at(const thx_image *img, const double p[3], int nearest)
{
    double x[3];
    thx_image_ras_to_index(img, p, x);
    const double tol = 1e-6;
    for (int k = 0; k < 3; k++)
        if (!(x[k] >= -0.5 - tol && x[k] <= (double)img->n[k] - 0.5 + tol)) return NAN;
    if (nearest) {
        size_t q[3];
        for (int k = 0; k < 3; k++) {
            double r = floor(x[k] + 0.5);
            q[k] = r < 0 ? 0 : r > (double)img->n[k] - 1 ? img->n[k] - 1 : (size_t)r;
        }
        return img->v[thx_image_at(img, q[0], q[1], q[2])];
    }
    size_t i0[3], i1[3];
    double f[3];
    for (int k = 0; k < 3; k++) {
        double c = fmin(fmax(x[k], 0), (double)img->n[k] - 1);
        double fl = floor(c);
        i0[k] = (size_t)fl;
        i1[k] = i0[k] + 1 < img->n[k] ? i0[k] + 1 : i0[k];
        f[k] = c - fl;
    }
    double s = 0;
    for (int c = 0; c < 8; c++) {
        double w = 1;
        size_t q[3];
        for (int k = 0; k < 3; k++) {
            int hi = (c >> k) & 1;
            w *= hi ? f[k] : 1 - f[k];
            q[k] = hi ? i1[k] : i0[k];
        }
        if (w != 0) s += w * img->v[thx_image_at(img, q[0], q[1], q[2])];
    }
    return s;
}

thx_status thx_image_sample_plane(thx_ctx *ctx, const thx_image *img, const thx_image_plane_spec *spec, int nearest,
                                  thx_image_slice *out)
{
    memset(out, 0, sizeof *out);
    const char *name = img->path[0] ? img->path : "<image>";
    if (!spec || !strchr("xyzijk", spec->axis) || !spec->axis)
        return thx_error(ctx, THX_EINPUT, "%s: image plane: unknown axis (x=MM, y=MM, z=MM, i=N, j=N or k=N)", name);
    double lo, hi, step;
    thx_image_plane_range(img, spec->axis, &lo, &hi, &step);
    int ras = spec->axis <= 'z' && spec->axis >= 'x';
    const double tol = 1e-9 * (fabs(lo) + fabs(hi) + 1);
    if (!(spec->pos >= lo - tol && spec->pos <= hi + tol)) {
        if (ras)
            return thx_error(ctx, THX_EINPUT, "%s: image plane %c=%g is outside the image: %c from %g to %g mm", name,
                             spec->axis, spec->pos, spec->axis, lo, hi);
        return thx_error(ctx, THX_EINPUT, "%s: image plane %c=%g is outside the image: %c from 0 to %zu", name,
                         spec->axis, spec->pos, spec->axis, img->n[spec->axis - 'i'] - 1);
    }
    out->step = step;
    out->lo = lo;
    out->hi = hi;
    size_t w, h;
    if (ras) {
        int r = spec->axis - 'x', ru = r == 0 ? 1 : 0, rv = r == 2 ? 1 : 2;
        double su = img->spacing[index_axis_along(img, ru)], sv = img->spacing[index_axis_along(img, rv)];
        double ulo, uhi, vlo, vhi;
        ras_range(img, ru, 0, &ulo, &uhi);
        ras_range(img, rv, 0, &vlo, &vhi);
        w = (size_t)floor((uhi - ulo) / su + 1e-6) + 1;
        h = (size_t)floor((vhi - vlo) / sv + 1e-6) + 1;
        if (w > MAX_SAMPLES) su = (uhi - ulo) / (MAX_SAMPLES - 1), w = MAX_SAMPLES;
        if (h > MAX_SAMPLES) sv = (vhi - vlo) / (MAX_SAMPLES - 1), h = MAX_SAMPLES;
        out->origin[r] = spec->pos;
        out->origin[ru] = ulo;
        out->origin[rv] = vlo;
        out->du[ru] = su;
        out->dv[rv] = sv;
        out->normal[r] = 1;
    } else {
        int c = spec->axis - 'i', cu = c == 0 ? 1 : 0, cv = c == 2 ? 1 : 2;
        double ijk[3] = {0, 0, 0};
        ijk[c] = spec->pos;
        thx_image_index_to_ras(img, ijk, out->origin);
        for (int k = 0; k < 3; k++) {
            out->du[k] = img->dir[k * 3 + cu] * img->spacing[cu];
            out->dv[k] = img->dir[k * 3 + cv] * img->spacing[cv];
            out->normal[k] = img->dir[k * 3 + c];
        }
        w = img->n[cu];
        h = img->n[cv];
        if (w > MAX_SAMPLES || h > MAX_SAMPLES)
            return thx_error(ctx, THX_EINPUT, "%s: image plane %c=%g: %zu x %zu voxels (at most %d a side)", name,
                             spec->axis, spec->pos, w, h, MAX_SAMPLES);
    }
    out->v = thx_malloc(ctx, w * h * sizeof *out->v);
    if (!out->v) return THX_ENOMEM;
    out->w = w;
    out->h = h;
    for (size_t b = 0; b < h; b++)
        for (size_t a = 0; a < w; a++) {
            double p[3];
            for (int k = 0; k < 3; k++) p[k] = out->origin[k] + (double)a * out->du[k] + (double)b * out->dv[k];
            out->v[a + w * b] = (float)thx_image_sample_at(img, p, nearest);
        }
    return THX_OK;
}

void thx_image_slice_free(thx_image_slice *s)
{
    if (!s) return;
    free(s->v);
    memset(s, 0, sizeof *s);
}

static int cmp_float(const void *x, const void *y)
{
    float a = *(const float *)x, b = *(const float *)y;
    return (a > b) - (a < b);
}

thx_window_kind thx_image_window_default(const thx_image *img, double *window, double *level)
{
    float lo, hi;
    thx_image_range(img, &lo, &hi);
    size_t n = thx_image_count(img);
    thx_window_kind kind = THX_WINDOW_PERCENTILE;
    if (img->integral && lo >= 0 && hi <= 65535) { /* a label map: few distinct values */
        unsigned char *seen = calloc(65536, 1);
        size_t distinct = 0;
        if (seen) {
            for (size_t i = 0; i < n && distinct <= 256; i++) {
                size_t q = (size_t)img->v[i];
                distinct += !seen[q];
                seen[q] = 1;
            }
            free(seen);
            if (distinct <= 256) kind = THX_WINDOW_LABELS;
        }
    }
    if (kind == THX_WINDOW_PERCENTILE && lo <= -500 && hi >= 200 && lo >= -3100) kind = THX_WINDOW_CT;
    double a = lo, b = hi;
    if (kind == THX_WINDOW_CT) {
        *window = 400;
        *level = 40;
        return kind;
    }
    if (kind == THX_WINDOW_PERCENTILE) {
        size_t stride = n > (1u << 20) ? n / (1u << 20) : 1, m = 0;
        float *s = malloc(((n + stride - 1) / stride) * sizeof *s);
        if (s) {
            for (size_t i = 0; i < n; i += stride) s[m++] = img->v[i];
            qsort(s, m, sizeof *s, cmp_float);
            a = s[(size_t)floor(0.01 * (double)(m - 1) + 0.5)];
            b = s[(size_t)floor(0.99 * (double)(m - 1) + 0.5)];
            free(s);
        }
    }
    *window = b - a > 0 ? b - a : 1;
    *level = b - a > 0 ? 0.5 * (a + b) : a;
    return kind;
}

const char *thx_window_kind_name(thx_window_kind k)
{
    return k == THX_WINDOW_LABELS ? "label map, full range"
           : k == THX_WINDOW_CT   ? "Hounsfield units, soft tissue"
                                  : "1st-99th percentile";
}
