/* src/digitizer/region.c — threshold + seed -> the region's boundary loop (thorax/digitizer/region.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"
#include "thorax/digitizer/region.h"

thx_status thx_region_loop(thx_ctx *ctx, const thx_image_slice *plane, double lo, double hi, const double seed[3],
                           int conn8, double **xyz, size_t *n, thx_region_info *info)
{
    *xyz = NULL;
    *n = 0;
    if (!(lo <= hi)) return thx_error(ctx, THX_EINPUT, "region: window [%g, %g] (lo <= hi)", lo, hi);
    size_t w = plane->w, h = plane->h, np = w * h;
    double fa, fb;
    dig_ras_to_px(plane, seed, &fa, &fb);
    fa = floor(fa + 0.5);
    fb = floor(fb + 0.5);
    if (!(fa >= 0 && fb >= 0 && fa < (double)w && fb < (double)h))
        return thx_error(ctx, THX_EINPUT, "region: seed (%g, %g, %g) mm lies outside the plane", seed[0], seed[1],
                         seed[2]);
    size_t s0 = (size_t)fa + w * (size_t)fb;
    double v0 = plane->v[s0];
    if (!(v0 >= lo && v0 <= hi))
        return thx_error(ctx, THX_EINPUT, "region: the seed's value %g lies outside the window [%g, %g]", v0, lo, hi);
    unsigned char *in = thx_calloc(ctx, np, 1);
    size_t *stack = thx_malloc(ctx, np * sizeof *stack);
    double *f = thx_malloc(ctx, np * sizeof *f);
    dig_loops L = {0};
    thx_status st = THX_OK;
    if (!in || !stack || !f) {
        st = THX_ENOMEM;
        goto done;
    }
    /* flood fill */
    size_t top = 0, count = 0;
    stack[top++] = s0;
    in[s0] = 1;
    while (top) {
        size_t p = stack[--top];
        count++;
        long a = (long)(p % w), b = (long)(p / w);
        for (int db = -1; db <= 1; db++)
            for (int da = -1; da <= 1; da++) {
                if ((!da && !db) || (!conn8 && da && db)) continue;
                long qa = a + da, qb = b + db;
                if (qa < 0 || qb < 0 || qa >= (long)w || qb >= (long)h) continue;
                size_t q = (size_t)qa + w * (size_t)qb;
                double v = plane->v[q];
                if (in[q] || !(v >= lo && v <= hi)) continue;
                in[q] = 1;
                stack[top++] = q;
            }
    }
    const double tiny = 1e-6 * (fabs(hi - lo) + fabs(hi) + fabs(lo) + 1e-30);
    for (size_t p = 0; p < np; p++) {
        double v = plane->v[p];
        double m = isfinite(v) ? fmin(v - lo, hi - v) : -1.0;
        if (in[p]) f[p] = m > tiny ? m : tiny;
        else f[p] = m < -tiny ? m : -tiny;
    }
    if ((st = dig_march(ctx, f, w, h, conn8, &L)) != THX_OK) goto done;
    size_t best = dig_largest_loop(&L);
    if (best == (size_t)-1) {
        st = thx_error(ctx, THX_EINTERNAL, "region: no outer boundary traced round %zu pixels", count);
        goto done;
    }
    double *o = thx_malloc(ctx, 3 * L.loop[best].n * sizeof *o);
    if (!o) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < L.loop[best].n; i++)
        dig_px_to_ras(plane, L.loop[best].xy[2 * i], L.loop[best].xy[2 * i + 1], o + 3 * i);
    *xyz = o;
    *n = L.loop[best].n;
    if (info) {
        info->n_pixels = count;
        info->n_holes = L.n - 1;
        double cx[3];
        cx[0] = plane->du[1] * plane->dv[2] - plane->du[2] * plane->dv[1];
        cx[1] = plane->du[2] * plane->dv[0] - plane->du[0] * plane->dv[2];
        cx[2] = plane->du[0] * plane->dv[1] - plane->du[1] * plane->dv[0];
        info->area = dig_area(L.loop[best].xy, L.loop[best].n) * dig_len3(cx); /* pixel area times the area of one pixel */
    }
done:
    dig_loops_free(&L);
    free(in);
    free(stack);
    free(f);
    return st;
}
