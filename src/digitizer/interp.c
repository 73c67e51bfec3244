/* src/digitizer/interp.c — shape-based interpolation of loops (thorax/digitizer/interp.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"
#include "thorax/digitizer/interp.h"

static double seg_dist(double px, double py, thx_vec2 p, thx_vec2 q)
{
    double ex = q.x - p.x, ey = q.y - p.y, l2 = ex * ex + ey * ey;
    double s = l2 > 0 ? ((px - p.x) * ex + (py - p.y) * ey) / l2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    double dx = px - (p.x + s * ex), dy = py - (p.y + s * ey);
    return sqrt(dx * dx + dy * dy);
}

static double loop_dist(const thx_vec2 *L, size_t n, double x, double y)
{
    double m = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double d = seg_dist(x, y, L[i], L[(i + 1) % n]);
        if (d < m) m = d;
    }
    return m;
}

static int cmp_d(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* s[] = signed distance to L (positive inside, |.| clamped at band) on the grid x0 + i step, y0 + j step. */
static thx_status signed_dist(thx_ctx *ctx, const thx_vec2 *L, size_t n, double x0, double y0, double step,
                              size_t nx, size_t ny, double band, double *s)
{
    for (size_t c = 0; c < nx * ny; c++) s[c] = band;
    for (size_t i = 0; i < n; i++) {
        thx_vec2 p = L[i], q = L[(i + 1) % n];
        double lx = fmin(p.x, q.x) - band, hx = fmax(p.x, q.x) + band, ly = fmin(p.y, q.y) - band,
               hy = fmax(p.y, q.y) + band;
        long i0 = (long)floor((lx - x0) / step), i1 = (long)ceil((hx - x0) / step);
        long j0 = (long)floor((ly - y0) / step), j1 = (long)ceil((hy - y0) / step);
        if (i0 < 0) i0 = 0;
        if (j0 < 0) j0 = 0;
        if (i1 >= (long)nx) i1 = (long)nx - 1;
        if (j1 >= (long)ny) j1 = (long)ny - 1;
        for (long j = j0; j <= j1; j++)
            for (long k = i0; k <= i1; k++) {
                double d = seg_dist(x0 + (double)k * step, y0 + (double)j * step, p, q);
                double *c = &s[(size_t)k + nx * (size_t)j];
                if (d < *c) *c = d;
            }
    }
    /* inside by scanlines (even-odd): the crossings of each row sorted */
    double *xs = thx_malloc(ctx, (n + 1) * sizeof *xs);
    if (!xs) return THX_ENOMEM;
    for (size_t j = 0; j < ny; j++) {
        double y = y0 + (double)j * step;
        size_t m = 0;
        for (size_t i = 0; i < n; i++) {
            thx_vec2 p = L[i], q = L[(i + 1) % n];
            if ((p.y > y) != (q.y > y)) xs[m++] = p.x + (y - p.y) * (q.x - p.x) / (q.y - p.y);
        }
        qsort(xs, m, sizeof *xs, cmp_d);
        for (size_t r = 0; r + 1 < m; r += 2) {
            long k0 = (long)ceil((xs[r] - x0) / step), k1 = (long)floor((xs[r + 1] - x0) / step);
            if (k0 < 0) k0 = 0;
            if (k1 >= (long)nx) k1 = (long)nx - 1;
            for (long k = k0; k <= k1; k++) s[(size_t)k + nx * j] = -s[(size_t)k + nx * j];
        }
    }
    free(xs);
    /* the negation above marked the inside: flip so that inside is positive */
    for (size_t c = 0; c < nx * ny; c++) s[c] = -s[c];
    return THX_OK;
}

thx_status thx_loop_interpolate(thx_ctx *ctx, const thx_vec2 *a, size_t na, const thx_vec2 *b, size_t nb, double t,
                                double step, thx_vec2 **out, size_t *n)
{
    *out = NULL;
    *n = 0;
    if (na < 3 || nb < 3) return thx_error(ctx, THX_EINPUT, "interpolate: loops of %zu and %zu points (3 or more)", na, nb);
    if (!(t >= 0 && t <= 1)) return thx_error(ctx, THX_EINPUT, "interpolate: t = %g (0..1)", t);
    if (!(step > 0) || !isfinite(step)) return thx_error(ctx, THX_EINPUT, "interpolate: grid step %g (> 0)", step);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; i < na + nb; i++) {
        thx_vec2 p = i < na ? a[i] : b[i - na];
        if (!isfinite(p.x) || !isfinite(p.y))
            return thx_error(ctx, THX_EINPUT, "interpolate: loop %c point %zu is not finite", i < na ? 'a' : 'b',
                             (i < na ? i : i - na) + 1);
        lo[0] = fmin(lo[0], p.x);
        lo[1] = fmin(lo[1], p.y);
        hi[0] = fmax(hi[0], p.x);
        hi[1] = fmax(hi[1], p.y);
    }
    /* The band: farther than the loops' largest point-to-loop distance (either way) plus two cells,
     * the distances are exact, beyond it clamped; the zero level of the mix lies between the loops. */
    double hd = 0;
    for (size_t i = 0; i < na; i++) hd = fmax(hd, loop_dist(b, nb, a[i].x, a[i].y));
    for (size_t i = 0; i < nb; i++) hd = fmax(hd, loop_dist(a, na, b[i].x, b[i].y));
    double band = hd + 2 * step;
    double x0 = lo[0] - 2 * step, y0 = lo[1] - 2 * step;
    double fx = (hi[0] - lo[0]) / step + 5, fy = (hi[1] - lo[1]) / step + 5;
    if (fx * fy > (double)(1u << 26))
        return thx_error(ctx, THX_EINPUT, "interpolate: grid step %g gives %.0f cells (2^26 at most)", step, fx * fy);
    size_t nx = (size_t)fx, ny = (size_t)fy;
    thx_status st = THX_OK;
    double *sa = thx_malloc(ctx, nx * ny * sizeof *sa), *sb = thx_malloc(ctx, nx * ny * sizeof *sb);
    dig_loops L = {0};
    if (!sa || !sb) {
        st = THX_ENOMEM;
        goto done;
    }
    if ((st = signed_dist(ctx, a, na, x0, y0, step, nx, ny, band, sa)) != THX_OK) goto done;
    if ((st = signed_dist(ctx, b, nb, x0, y0, step, nx, ny, band, sb)) != THX_OK) goto done;
    for (size_t c = 0; c < nx * ny; c++) sa[c] = (1 - t) * sa[c] + t * sb[c];
    if ((st = dig_march(ctx, sa, nx, ny, 1, &L)) != THX_OK) goto done;
    size_t best = dig_largest_loop(&L);
    if (best == (size_t)-1) {
        st = thx_error(ctx, THX_EGEOM, "interpolate: the loops mixed at t = %g enclose nothing (too far apart)", t);
        goto done;
    }
    thx_vec2 *o = thx_malloc(ctx, L.loop[best].n * sizeof *o);
    if (!o) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < L.loop[best].n; i++) {
        o[i].x = x0 + L.loop[best].xy[2 * i] * step;
        o[i].y = y0 + L.loop[best].xy[2 * i + 1] * step;
    }
    *out = o;
    *n = L.loop[best].n;
done:
    dig_loops_free(&L);
    free(sa);
    free(sb);
    return st;
}
