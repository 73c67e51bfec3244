/* A label map from a scan by nested thresholds, closing, largest component and plane filling
 * (thorax/image/segment.h). Distances are exact Euclidean (Felzenszwalb & Huttenlocher 2012,
 * "Distance transforms of sampled functions": the lower envelope of parabolas, one axis at a time). */
#include "thorax/image/segment.h"

#include "components.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One line of the separable transform: out[q] = min_j f[j] + (s (q - j))^2 over the n samples (f may be
 * INFINITY: such a sample is no parabola). v, z: scratch of n and n + 1. */
static void edt_line(const float *f, float *out, size_t n, double s, size_t *v, double *z)
{
    long k = -1;
    for (size_t q = 0; q < n; q++) {
        if (isinf(f[q])) continue;
        double pq = s * (double)q, fq = f[q] + pq * pq;
        while (k >= 0) {
            double pv = s * (double)v[k];
            double x = (fq - (f[v[k]] + pv * pv)) / (2 * (pq - pv));
            if (x > z[k]) {
                k++;
                v[k] = q;
                z[k] = x;
                z[k + 1] = INFINITY;
                break;
            }
            k--;
        }
        if (k < 0) {
            k = 0;
            v[0] = q;
            z[0] = -INFINITY;
            z[1] = INFINITY;
        }
    }
    if (k < 0) {
        for (size_t q = 0; q < n; q++) out[q] = INFINITY;
        return;
    }
    k = 0;
    for (size_t q = 0; q < n; q++) {
        double p = s * (double)q;
        while (z[k + 1] < p) k++;
        double d = p - s * (double)v[k];
        out[q] = (float)(d * d + f[v[k]]);
    }
}

thx_status thx_distance_squared(thx_ctx *ctx, const size_t n[3], const double spacing[3], const unsigned char *mask,
                                float *d)
{
    size_t count = n[0] * n[1] * n[2], longest = n[0];
    if (n[1] > longest) longest = n[1];
    if (n[2] > longest) longest = n[2];
    float *in = malloc(longest * sizeof *in), *out = malloc(longest * sizeof *out);
    size_t *v = malloc(longest * sizeof *v);
    double *z = malloc((longest + 1) * sizeof *z);
    if (!in || !out || !v || !z) {
        free(in), free(out), free(v), free(z);
        return thx_error(ctx, THX_ENOMEM, "distance transform: out of memory");
    }
    for (size_t q = 0; q < count; q++) d[q] = mask[q] ? 0.0f : INFINITY;
    size_t stride[3] = {1, n[0], n[0] * n[1]};
    for (int a = 0; a < 3; a++) {
        int b = (a + 1) % 3, c = (a + 2) % 3;
        for (size_t jb = 0; jb < n[b]; jb++)
            for (size_t jc = 0; jc < n[c]; jc++) {
                size_t base = jb * stride[b] + jc * stride[c];
                for (size_t i = 0; i < n[a]; i++) in[i] = d[base + i * stride[a]];
                edt_line(in, out, n[a], spacing[a], v, z);
                for (size_t i = 0; i < n[a]; i++) d[base + i * stride[a]] = out[i];
            }
    }
    free(in), free(out), free(v), free(z);
    return THX_OK;
}

/* Morphological closing of r by a ball of radius rad mm. */
static thx_status close_region(thx_ctx *ctx, const thx_image *g, unsigned char *r, double rad, float *d)
{
    size_t count = thx_image_count(g);
    double r2 = rad * rad;
    THX_CHECK(thx_distance_squared(ctx, g->n, g->spacing, r, d));
    for (size_t q = 0; q < count; q++) r[q] = d[q] <= r2; /* dilated */
    for (size_t q = 0; q < count; q++) r[q] = !r[q];      /* its complement */
    THX_CHECK(thx_distance_squared(ctx, g->n, g->spacing, r, d));
    for (size_t q = 0; q < count; q++) r[q] = d[q] > r2;  /* eroded back */
    return THX_OK;
}

/* The largest component: found in a first pass (the first found among equals), kept in a second. */
typedef struct {
    size_t best, best_size, total;
    int pass;
} largest;

static unsigned char largest_decide(void *user, size_t size, int touches, size_t ordinal)
{
    largest *l = user;
    (void)touches;
    if (l->pass == 1) return ordinal == l->best;
    l->total += size;
    if (size > l->best_size) {
        l->best_size = size;
        l->best = ordinal;
    }
    return 1;
}

/* Keeps the largest 6-connected component of r (the first found among equals); returns the voxels
 * dropped. thx_components6 (src/image/components.c), shared with the tracer's cleaning. */
static thx_status keep_largest(thx_ctx *ctx, const thx_image *g, unsigned char *r, size_t *dropped)
{
    const size_t lo[3] = {0, 0, 0};
    largest l = {0, 0, 0, 0};
    thx_status st = thx_components6(ctx, r, g->n, lo, g->n, 1, largest_decide, &l, NULL);
    if (st != THX_OK) return thx_error(ctx, st, "largest component: out of memory");
    l.pass = 1;
    st = thx_components6(ctx, r, g->n, lo, g->n, 1, largest_decide, &l, NULL);
    if (st != THX_OK) return thx_error(ctx, st, "largest component: out of memory");
    *dropped = l.total - l.best_size;
    return THX_OK;
}

/* Fills every plane's holes along axis `ax`; returns the voxels added. */
static thx_status fill_planes(thx_ctx *ctx, const thx_image *g, unsigned char *r, int ax, double rad, size_t *added)
{
    int a = (ax + 1) % 3, b = (ax + 2) % 3;
    size_t stride[3] = {1, g->n[0], g->n[0] * g->n[1]};
    size_t na = g->n[a], nb = g->n[b], np = na * nb;
    unsigned char *out = malloc(np), *wall = malloc(np);
    size_t *queue = malloc(np * sizeof *queue);
    float *d = rad > 0 ? malloc(np * sizeof *d) : NULL;
    if (!out || !wall || !queue || (rad > 0 && !d)) {
        free(out), free(wall), free(queue), free(d);
        return thx_error(ctx, THX_ENOMEM, "plane filling: out of memory");
    }
    size_t pn[3] = {na, nb, 1};
    double ps[3] = {g->spacing[a], g->spacing[b], 1};
    thx_status st = THX_OK;
    *added = 0;
    for (size_t s = 0; s < g->n[ax]; s++) {
        size_t base = s * stride[ax];
#define AT(ia, ib) (base + (ia) * stride[a] + (ib) * stride[b])
        /* the wall the outside floods against: the plane's region, closed in the plane by a disc of rad
         * (a gap in a thin wall that the 3-D closing left, as partial volume leaves in a skull, is bridged) */
        for (size_t p = 0; p < np; p++) wall[p] = r[AT(p % na, p / na)];
        if (rad > 0) {
            if ((st = thx_distance_squared(ctx, pn, ps, wall, d)) != THX_OK) break;
            for (size_t p = 0; p < np; p++) wall[p] = !(d[p] <= rad * rad);
            if ((st = thx_distance_squared(ctx, pn, ps, wall, d)) != THX_OK) break;
            for (size_t p = 0; p < np; p++) wall[p] = d[p] > rad * rad;
        }
        memset(out, 0, np);
        size_t head = 0, tail = 0;
        for (size_t ia = 0; ia < na; ia++)
            for (size_t ib = 0; ib < nb; ib++)
                if ((ia == 0 || ib == 0 || ia + 1 == na || ib + 1 == nb) && !wall[ia + na * ib]) {
                    out[ia + na * ib] = 1;
                    queue[tail++] = ia + na * ib;
                }
        while (head < tail) {
            size_t p = queue[head++], ia = p % na, ib = p / na;
            size_t cand[4];
            int m = 0;
            if (ia > 0) cand[m++] = p - 1;
            if (ia + 1 < na) cand[m++] = p + 1;
            if (ib > 0) cand[m++] = p - na;
            if (ib + 1 < nb) cand[m++] = p + na;
            for (int t = 0; t < m; t++) {
                size_t c = cand[t];
                if (!out[c] && !wall[c]) {
                    out[c] = 1;
                    queue[tail++] = c;
                }
            }
        }
        for (size_t p = 0; p < np; p++)
            if (!out[p] && !r[AT(p % na, p / na)]) {
                r[AT(p % na, p / na)] = 1;
                (*added)++;
            }
#undef AT
    }
    free(out), free(wall), free(queue), free(d);
    return st;
}

/* Erosion by the 3 x 3 x 3 cube, separably (a voxel stays when its whole cube is in; outside the grid counts
 * as out). */
static void erode_cube(const size_t n[3], unsigned char *r)
{
    size_t stride[3] = {1, n[0], n[0] * n[1]};
    for (int a = 0; a < 3; a++) {
        int b = (a + 1) % 3, c = (a + 2) % 3;
        for (size_t jb = 0; jb < n[b]; jb++)
            for (size_t jc = 0; jc < n[c]; jc++) {
                unsigned char *line = r + jb * stride[b] + jc * stride[c];
                size_t s = stride[a], m = n[a];
                unsigned char before = 0; /* the original value of the previous voxel */
                for (size_t i = 0; i < m; i++) {
                    unsigned char here = line[i * s], after = i + 1 < m ? line[(i + 1) * s] : 0;
                    line[i * s] = (unsigned char)(before && here && after);
                    before = here;
                }
            }
    }
}

thx_status thx_image_segment(thx_ctx *ctx, const thx_image *in, const thx_segment_opts *opts, thx_image *out,
                             thx_segment_report *rep)
{
    memset(out, 0, sizeof *out);
    if (rep) memset(rep, 0, sizeof *rep);
    if (opts->n_tissues == 0) return thx_error(ctx, THX_EINPUT, "segment: no tissue ranges given");
    int any_close = 0;
    for (size_t t = 0; t < opts->n_tissues; t++) {
        const thx_threshold *th = &opts->tissues[t];
        if (!(th->lo <= th->hi))
            return thx_error(ctx, THX_EINPUT, "segment: tissue %zu (label %d): range %g..%g is empty", t + 1, th->label,
                             th->lo, th->hi);
        if (th->label < 1 || th->label > 65535)
            return thx_error(ctx, THX_EINPUT, "segment: tissue %zu: label %d is not in 1..65535", t + 1, th->label);
        if (!(th->close_mm >= 0) || !isfinite(th->close_mm))
            return thx_error(ctx, THX_EINPUT, "segment: tissue %zu (label %d): closing radius %g mm must be >= 0",
                             t + 1, th->label, th->close_mm);
        if (th->close_mm > 0) any_close = 1;
    }
    THX_CHECK(thx_image_alloc(ctx, in->n, out));
    memcpy(out->spacing, in->spacing, sizeof out->spacing);
    memcpy(out->origin, in->origin, sizeof out->origin);
    memcpy(out->dir, in->dir, sizeof out->dir);
    snprintf(out->source_frame, sizeof out->source_frame, "%s", in->source_frame);
    out->integral = 1;
    size_t count = thx_image_count(in);
    unsigned char *r = malloc(count), *prev = NULL;
    float *d = any_close ? malloc(count * sizeof *d) : NULL;
    thx_status st = THX_OK;
    if (!r || (any_close && !d)) {
        st = thx_error(ctx, THX_ENOMEM, "segment: out of memory for %zu voxels", count);
        goto done;
    }
    int sup;
    thx_image_axes(in, &sup, NULL, NULL, NULL, NULL);
    for (size_t t = 0; t < opts->n_tissues; t++) {
        for (size_t q = 0; q < count; q++) {
            double v = in->v[q];
            int inside = 0;
            for (size_t u = t; u < opts->n_tissues && !inside; u++)
                inside = v >= opts->tissues[u].lo && v <= opts->tissues[u].hi;
            r[q] = (unsigned char)(inside && (!prev || prev[q]));
        }
        double rad = opts->tissues[t].close_mm;
        if (rad > 0 && (st = close_region(ctx, in, r, rad, d)) != THX_OK) goto done;
        if (prev)
            for (size_t q = 0; q < count; q++) r[q] &= prev[q];
        size_t dropped = 0, added = 0;
        if (opts->largest && (st = keep_largest(ctx, in, r, &dropped)) != THX_OK) goto done;
        if (opts->fill_planes && (st = fill_planes(ctx, in, r, sup, rad, &added)) != THX_OK) goto done;
        if (prev)
            for (size_t q = 0; q < count; q++) r[q] &= prev[q];
        for (size_t q = 0; q < count; q++)
            if (r[q]) out->v[q] = (float)opts->tissues[t].label;
        if (rep && t < 16) {
            rep->dropped[t] = dropped;
            rep->filled[t] = added;
        }
        if (!prev && !(prev = malloc(count))) {
            st = thx_error(ctx, THX_ENOMEM, "segment: out of memory");
            goto done;
        }
        memcpy(prev, r, count);
        /* the next tissue keeps a voxel's distance from this one's boundary (and from the image's faces):
           their traced boundaries never meet, and the inner surface's caps lie inside the outer's */
        erode_cube(in->n, prev);
    }
    if (rep)
        for (size_t q = 0; q < count; q++)
            for (size_t t = 0; t < opts->n_tissues && t < 16; t++)
                if (out->v[q] == (float)opts->tissues[t].label) {
                    rep->voxels[t]++;
                    break;
                }
done:
    free(r), free(prev), free(d);
    if (st != THX_OK) thx_image_free(out);
    return st;
}
