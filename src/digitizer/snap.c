/* src/digitizer/snap.c — a loop snapped to a plane's edges (thorax/digitizer/snap.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"
#include "thorax/digitizer/snap.h"

void thx_snap_opts_default(thx_snap_opts *o)
{
    o->range = 8.0;
    o->sigma = 1.5;
    o->stiffness = 0.5;
    o->smooth = 4;
    o->iterations = 30;
}

static int cmp_d(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

thx_status thx_snap_loop(thx_ctx *ctx, const thx_image_slice *plane, const thx_snap_opts *o, const double *in,
                         size_t n, double *out)
{
    thx_snap_opts def;
    if (!o) {
        thx_snap_opts_default(&def);
        o = &def;
    }
    if (n < 3) return thx_error(ctx, THX_EINPUT, "snap: a loop of %zu points (3 or more)", n);
    if (!(o->range > 0 && o->sigma >= 0 && o->stiffness >= 0 && o->stiffness <= 1 && o->smooth >= 0 &&
          o->iterations >= 1 && isfinite(o->range + o->sigma)))
        return thx_error(ctx, THX_EINPUT, "snap: range %g (> 0), sigma %g (>= 0), stiffness %g (0..1), smooth %d "
                                          "(>= 0), iterations %d (>= 1)",
                         o->range, o->sigma, o->stiffness, o->smooth, o->iterations);
    size_t w = plane->w, h = plane->h, np = w * h;
    if (w < 2 || h < 2) return thx_error(ctx, THX_EINPUT, "snap: plane of %zu x %zu samples", w, h);
    double su = dig_len3(plane->du), sv = dig_len3(plane->dv), hmm = fmin(su, sv);
    thx_status st = THX_OK;
    double *ab = thx_malloc(ctx, 2 * n * sizeof *ab), *nrm = thx_malloc(ctx, 2 * n * sizeof *nrm),
           *d = thx_malloc(ctx, n * sizeof *d), *t = thx_malloc(ctx, n * sizeof *t);
    float *f = dig_smooth(ctx, plane, o->sigma, NULL), *gx = thx_malloc(ctx, np * sizeof *gx),
          *gy = thx_malloc(ctx, np * sizeof *gy), *g = thx_malloc(ctx, np * sizeof *g);
    if (!ab || !nrm || !d || !t || !f || !gx || !gy || !g) {
        st = THX_ENOMEM;
        goto done;
    }
    dig_gradient(f, w, h, su, sv, gx, gy, g);
    for (size_t i = 0; i < n; i++) {
        dig_ras_to_px(plane, in + 3 * i, &ab[2 * i], &ab[2 * i + 1]);
        if (!(ab[2 * i] >= -0.5 && ab[2 * i + 1] >= -0.5 && ab[2 * i] <= (double)w - 0.5 &&
              ab[2 * i + 1] <= (double)h - 0.5)) {
            st = thx_error(ctx, THX_EINPUT, "snap: loop point %zu (%g, %g, %g) mm lies outside the plane", i + 1,
                           in[3 * i], in[3 * i + 1], in[3 * i + 2]);
            goto done;
        }
    }
    double range = o->range;
    for (int it = 0; it < o->iterations; it++) {
        /* normals (mm frame of the plane's steps), from the two neighbours */
        for (size_t i = 0; i < n; i++) {
            size_t ip = (i + n - 1) % n, in1 = (i + 1) % n;
            double tx = (ab[2 * in1] - ab[2 * ip]) * su, ty = (ab[2 * in1 + 1] - ab[2 * ip + 1]) * sv;
            double l = sqrt(tx * tx + ty * ty);
            nrm[2 * i] = l > 0 ? ty / l : 0;
            nrm[2 * i + 1] = l > 0 ? -tx / l : 0;
        }
        /* 1. the best edge along each normal */
        int steps = (int)ceil(2 * range);
        for (size_t i = 0; i < n; i++) {
            double nx = nrm[2 * i], ny = nrm[2 * i + 1], best = -1, sb = 0, sm = 0, sp = 0;
            int kb = 0;
            d[i] = 0;
            if (nx == 0 && ny == 0) continue;
#define SCORE(k, out_)                                                                                           \
    do {                                                                                                         \
        double s_ = 0.5 * (k), a_ = ab[2 * i] + s_ * hmm * nx / su, b_ = ab[2 * i + 1] + s_ * hmm * ny / sv;     \
        double dd_ = fabs(dig_bilinear(gx, w, h, a_, b_) * nx + dig_bilinear(gy, w, h, a_, b_) * ny);             \
        out_ = (a_ < 0 || b_ < 0 || a_ > (double)(w - 1) || b_ > (double)(h - 1))                                 \
                   ? 0                                                                                            \
                   : dd_ * exp(-0.5 * s_ * s_ / (range * range));                                                 \
    } while (0)
            for (int k = -steps; k <= steps; k++) {
                double sc;
                SCORE(k, sc);
                if (sc > best || (sc == best && abs(k) < abs(kb))) {
                    best = sc;
                    kb = k;
                }
            }
            SCORE(kb - 1, sm);
            SCORE(kb, sb);
            SCORE(kb + 1, sp);
#undef SCORE
            double den = sm - 2 * sb + sp, off = den < 0 ? 0.5 * (sm - sp) / den : 0;
            if (off > 1) off = 1;
            if (off < -1) off = -1;
            d[i] = 0.5 * (kb + off); /* pixels (of hmm mm) along the normal */
        }
        /* 2. stiffness: median of five, then the membrane */
        for (size_t i = 0; i < n; i++) {
            double m5[5];
            for (int k = -2; k <= 2; k++) m5[k + 2] = d[(i + n + (size_t)(k + 2) - 2) % n];
            qsort(m5, 5, sizeof *m5, cmp_d);
            t[i] = m5[2];
        }
        for (int pass = 0; pass < o->smooth; pass++) {
            for (size_t i = 0; i < n; i++) d[i] = (1 - o->stiffness) * t[i] + o->stiffness * 0.5 * (t[(i + n - 1) % n] + t[(i + 1) % n]);
            memcpy(t, d, n * sizeof *d);
        }
        if (o->smooth == 0) memcpy(d, t, n * sizeof *d);
        /* 3. move */
        double moved = 0;
        for (size_t i = 0; i < n; i++) {
            ab[2 * i] += d[i] * hmm * nrm[2 * i] / su;
            ab[2 * i + 1] += d[i] * hmm * nrm[2 * i + 1] / sv;
            if (fabs(d[i]) > moved) moved = fabs(d[i]);
        }
        if (moved < 0.02) break;
        range = fmax(1.5, range / 2);
    }
    for (size_t i = 0; i < n; i++) dig_px_to_ras(plane, ab[2 * i], ab[2 * i + 1], out + 3 * i);
done:
    free(ab);
    free(nrm);
    free(d);
    free(t);
    free(f);
    free(gx);
    free(gy);
    free(g);
    return st;
}
