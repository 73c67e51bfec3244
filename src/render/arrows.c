/*
 * Arrows of a vector field with clutter control (paper 4.2, "Displaying vector fields"): grid
 * averaging, then greedy thinning by distance, strongest first, up to a count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/render/render.h"
typedef struct {
    double mag2;
    size_t i;
} cand;

/* Descending magnitude; ties by index, so the order is the same on every run. */
static int stronger(const void *a, const void *b)
{
    const cand *x = a, *y = b;
    if (x->mag2 != y->mag2) return x->mag2 < y->mag2 ? 1 : -1;
    return (x->i > y->i) - (x->i < y->i);
}

/* Kept tails are bucketed in a hash grid of cell `gap`, so each candidate looks at 27 cells. */
typedef struct {
    size_t *head, *next; /* head[bucket] -> kept index + 1, chained through next */
    size_t nb;
    double g;
} buckets;

static size_t bucket_of(const buckets *b, long ix, long iy, long iz)
{
    unsigned long long h = (unsigned long long)ix * 73856093ULL ^ (unsigned long long)iy * 19349663ULL ^
                           (unsigned long long)iz * 83492791ULL;
    return (size_t)(h % b->nb);
}

thx_status thx_arrows_select(thx_ctx *ctx, const double *xyz, const double *vec, size_t n_points,
                             const unsigned char *in, double spacing, double gap, size_t max_n,
                             double **pos_out, double **vec_out, size_t *n_out, double *vmax)
{
    *pos_out = *vec_out = NULL;
    *n_out = 0;
    *vmax = 0;
    if (!(spacing >= 0) || !(gap >= 0))
        return thx_error(ctx, THX_EINPUT, "arrows: the grid spacing and the gap must be 0 or positive (got %g, %g)", spacing, gap);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n_points; i++)
        if (!in || in[i])
            for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], xyz[3 * i + k]); hi[k] = fmax(hi[k], xyz[3 * i + k]); }
    size_t cells = n_points;
    long n[3] = {1, 1, 1};
    if (spacing > 0 && lo[0] <= hi[0]) {
        double c = 1;
        for (int k = 0; k < 3; k++) {
            n[k] = (long)((hi[k] - lo[k]) / spacing) + 1;
            c *= (double)n[k];
        }
        if (c > 4e8) return thx_error(ctx, THX_EINPUT, "arrows: a %g mm grid over this field has %.3g cells; give a larger spacing", spacing, c);
        cells = (size_t)c;
    }
    double *acc = calloc((cells ? cells : 1) * 7, sizeof *acc); /* position sum, vector sum, count */
    cand *cd = malloc((cells ? cells : 1) * sizeof *cd);
    if (!acc || !cd) { free(acc); free(cd); return thx_error(ctx, THX_ENOMEM, "arrows: out of memory (%zu cells)", cells); }
    for (size_t i = 0; i < n_points; i++) {
        if (in && !in[i]) continue;
        const double *x = xyz + 3 * i, *v = vec + 3 * i;
        if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]))) continue;
        size_t q = i;
        if (spacing > 0) {
            long ix = (long)((x[0] - lo[0]) / spacing), iy = (long)((x[1] - lo[1]) / spacing), iz = (long)((x[2] - lo[2]) / spacing);
            if (ix >= n[0]) ix = n[0] - 1;
            if (iy >= n[1]) iy = n[1] - 1;
            if (iz >= n[2]) iz = n[2] - 1;
            q = ((size_t)iz * (size_t)n[1] + (size_t)iy) * (size_t)n[0] + (size_t)ix;
        }
        double *a = acc + 7 * q;
        for (int k = 0; k < 3; k++) { a[k] += x[k]; a[3 + k] += v[k]; }
        a[6] += 1;
    }
    size_t nc = 0;
    for (size_t q = 0; q < cells; q++) {
        double *a = acc + 7 * q;
        if (!(a[6] > 0)) continue;
        for (int k = 0; k < 6; k++) a[k] /= a[6];
        double m2 = a[3] * a[3] + a[4] * a[4] + a[5] * a[5];
        if (m2 > 0) cd[nc++] = (cand){m2, q};
    }
    qsort(cd, nc, sizeof *cd, stronger);
    size_t cap = nc < max_n ? nc : max_n;
    double *P = malloc(3 * (cap ? cap : 1) * sizeof *P), *V = malloc(3 * (cap ? cap : 1) * sizeof *V);
    buckets B = {0};
    if (gap > 0) {
        B.nb = 2 * cap + 1;
        B.g = gap;
        B.head = calloc(B.nb, sizeof *B.head);
        B.next = calloc(cap ? cap : 1, sizeof *B.next);
    }
    if (!P || !V || (gap > 0 && (!B.head || !B.next))) {
        free(acc); free(cd); free(P); free(V); free(B.head); free(B.next);
        return thx_error(ctx, THX_ENOMEM, "arrows: out of memory");
    }
    size_t kept = 0;
    for (size_t r = 0; r < nc && kept < cap; r++) {
        const double *a = acc + 7 * cd[r].i;
        long c[3] = {0, 0, 0};
        if (gap > 0) {
            for (int k = 0; k < 3; k++) c[k] = (long)floor(a[k] / gap);
            int near = 0;
            for (long dz = -1; dz <= 1 && !near; dz++)
                for (long dy = -1; dy <= 1 && !near; dy++)
                    for (long dx = -1; dx <= 1 && !near; dx++)
                        for (size_t e = B.head[bucket_of(&B, c[0] + dx, c[1] + dy, c[2] + dz)]; e && !near; e = B.next[e - 1]) {
                            const double *p = P + 3 * (e - 1);
                            double d0 = a[0] - p[0], d1 = a[1] - p[1], d2 = a[2] - p[2];
                            near = d0 * d0 + d1 * d1 + d2 * d2 < gap * gap;
                        }
            if (near) continue;
        }
        for (int k = 0; k < 3; k++) { P[3 * kept + k] = a[k]; V[3 * kept + k] = a[3 + k]; }
        if (gap > 0) {
            size_t h = bucket_of(&B, c[0], c[1], c[2]);
            B.next[kept] = B.head[h];
            B.head[h] = kept + 1;
        }
        kept++;
    }
    *vmax = nc ? sqrt(cd[0].mag2) : 0;
    free(acc);
    free(cd);
    free(B.head);
    free(B.next);
    *pos_out = P;
    *vec_out = V;
    *n_out = kept;
    return THX_OK;
}
