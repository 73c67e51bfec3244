/* src/digitizer/plane.c — what the digitizer's tools share: pixel <-> RAS, smoothing and gradients of a
 * plane, the sub-voxel edge step, marching squares on a plane (docs/design/digitizer.md). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"

double dig_len3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

void dig_px_to_ras(const thx_image_slice *s, double a, double b, double ras[3])
{
    for (int c = 0; c < 3; c++) ras[c] = s->origin[c] + a * s->du[c] + b * s->dv[c];
}

/* Least squares on the plane's two steps (they need not be orthogonal for an oblique image's plane):
 * the projection along the normal of the plane. */
void dig_ras_to_px(const thx_image_slice *s, const double ras[3], double *a, double *b)
{
    double r[3], uu = 0, uv = 0, vv = 0, ru = 0, rv = 0;
    for (int c = 0; c < 3; c++) {
        r[c] = ras[c] - s->origin[c];
        uu += s->du[c] * s->du[c];
        uv += s->du[c] * s->dv[c];
        vv += s->dv[c] * s->dv[c];
        ru += r[c] * s->du[c];
        rv += r[c] * s->dv[c];
    }
    double det = uu * vv - uv * uv;
    if (det <= 0) {
        *a = *b = 0;
        return;
    }
    *a = (ru * vv - rv * uv) / det;
    *b = (rv * uu - ru * uv) / det;
}

float *dig_smooth(thx_ctx *ctx, const thx_image_slice *s, double sigma, size_t *n_finite)
{
    size_t w = s->w, h = s->h, n = w * h, nf = 0;
    float lo = FLT_MAX;
    for (size_t p = 0; p < n; p++)
        if (isfinite(s->v[p])) {
            nf++;
            if (s->v[p] < lo) lo = s->v[p];
        }
    if (n_finite) *n_finite = nf;
    float *f = thx_malloc(ctx, n * sizeof *f), *t = thx_malloc(ctx, n * sizeof *t);
    if (!f || !t) {
        free(f);
        free(t);
        return NULL;
    }
    for (size_t p = 0; p < n; p++) f[p] = isfinite(s->v[p]) ? s->v[p] : (nf ? lo : 0.0f);
    if (sigma > 0) {
        int r = (int)ceil(3 * sigma);
        double *k = thx_malloc(ctx, (size_t)(2 * r + 1) * sizeof *k), ks = 0;
        if (!k) {
            free(f);
            free(t);
            return NULL;
        }
        for (int i = -r; i <= r; i++) ks += k[i + r] = exp(-0.5 * i * i / (sigma * sigma));
        for (int i = 0; i <= 2 * r; i++) k[i] /= ks;
        for (size_t b = 0; b < h; b++)
            for (size_t a = 0; a < w; a++) {
                double acc = 0;
                for (int i = -r; i <= r; i++) {
                    long x = (long)a + i;
                    x = x < 0 ? 0 : x >= (long)w ? (long)w - 1 : x;
                    acc += k[i + r] * f[(size_t)x + w * b];
                }
                t[a + w * b] = (float)acc;
            }
        for (size_t b = 0; b < h; b++)
            for (size_t a = 0; a < w; a++) {
                double acc = 0;
                for (int i = -r; i <= r; i++) {
                    long y = (long)b + i;
                    y = y < 0 ? 0 : y >= (long)h ? (long)h - 1 : y;
                    acc += k[i + r] * t[a + w * (size_t)y];
                }
                f[a + w * b] = (float)acc;
            }
        free(k);
    }
    free(t);
    return f;
}

void dig_gradient(const float *f, size_t w, size_t h, double su, double sv, float *gx, float *gy, float *g)
{
    for (size_t b = 0; b < h; b++)
        for (size_t a = 0; a < w; a++) {
            size_t a0 = a ? a - 1 : a, a1 = a + 1 < w ? a + 1 : a, b0 = b ? b - 1 : b, b1 = b + 1 < h ? b + 1 : b;
            double x = a1 > a0 ? (f[a1 + w * b] - f[a0 + w * b]) / ((double)(a1 - a0) * su) : 0;
            double y = b1 > b0 ? (f[a + w * b1] - f[a + w * b0]) / ((double)(b1 - b0) * sv) : 0;
            gx[a + w * b] = (float)x;
            gy[a + w * b] = (float)y;
            g[a + w * b] = (float)sqrt(x * x + y * y);
        }
}

double dig_bilinear(const float *f, size_t w, size_t h, double a, double b)
{
    if (a < 0) a = 0;
    if (b < 0) b = 0;
    if (a > (double)(w - 1)) a = (double)(w - 1);
    if (b > (double)(h - 1)) b = (double)(h - 1);
    size_t i = (size_t)a, j = (size_t)b;
    if (i + 1 >= w && i) i = w - 2;
    if (j + 1 >= h && j) j = h - 2;
    double s = a - (double)i, t = b - (double)j;
    size_t i1 = i + 1 < w ? i + 1 : i, j1 = j + 1 < h ? j + 1 : j;
    return (1 - s) * (1 - t) * f[i + w * j] + s * (1 - t) * f[i1 + w * j] + (1 - s) * t * f[i + w * j1] +
           s * t * f[i1 + w * j1];
}

void dig_edge_refine(const float *g, const float *gx, const float *gy, size_t w, size_t h, double su, double sv,
                     double reach, double *a, double *b)
{
    double a0 = *a, b0 = *b, hmm = su < sv ? su : sv;
    for (int it = 0; it < 4; it++) {
        double x = dig_bilinear(gx, w, h, *a, *b), y = dig_bilinear(gy, w, h, *a, *b), m = sqrt(x * x + y * y);
        if (!(m > 0)) return;
        double da = hmm * x / m / su, db = hmm * y / m / sv; /* one step of hmm mm along the gradient */
        double gm = dig_bilinear(g, w, h, *a - da, *b - db), g0 = dig_bilinear(g, w, h, *a, *b),
               gp = dig_bilinear(g, w, h, *a + da, *b + db);
        double den = gm - 2 * g0 + gp, t;
        if (den < 0) t = 0.5 * (gm - gp) / den;
        else t = gp > gm ? 1 : gp < gm ? -1 : 0; /* no maximum between: climb */
        if (t > 1) t = 1;
        if (t < -1) t = -1;
        double na = *a + t * da, nb = *b + t * db;
        double ea = (na - a0) * su, eb = (nb - b0) * sv;
        if (sqrt(ea * ea + eb * eb) > reach * hmm) return; /* would leave the reach: keep the last */
        *a = na;
        *b = nb;
        if (fabs(t) < 0.5) return; /* the maximum lies within this step's parabola */
    }
}

void dig_loops_free(dig_loops *L)
{
    if (!L) return;
    for (size_t i = 0; i < L->n; i++) free(L->loop[i].xy);
    free(L->loop);
    memset(L, 0, sizeof *L);
}

double dig_area(const double *xy, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++) {
        size_t j = (i + 1) % n;
        s += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return 0.5 * s;
}

size_t dig_largest_loop(const dig_loops *L)
{
    size_t best = (size_t)-1;
    double barea = 0;
    for (size_t i = 0; i < L->n; i++) {
        double ar = dig_area(L->loop[i].xy, L->loop[i].n);
        if (ar > barea) {
            barea = ar;
            best = i;
        }
    }
    return best;
}

int dig_inside(const double *xy, size_t n, double x, double y)
{
    int in = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) {
        double xi = xy[2 * i], yi = xy[2 * i + 1], xj = xy[2 * j], yj = xy[2 * j + 1];
        if ((yi > y) != (yj > y) && x < xj + (y - yj) * (xi - xj) / (yi - yj)) in = !in;
    }
    return in;
}

/* ---- marching squares ----
 * Cell (i, j), i = -1 .. w - 1, j = -1 .. h - 1 (the grid padded by one outside sample each side),
 * corners c0 (i, j), c1 (i+1, j), c2 (i+1, j+1), c3 (i, j+1) counterclockwise; its edges e0 = c0c1,
 * e1 = c1c2, e2 = c3c2 (top), e3 = c0c3 (left). Walking round the cell counterclockwise, a crossing
 * edge is in->out or out->in; a segment runs from an in->out edge to an out->in edge, which keeps the
 * inside on its left. Without a saddle the cell has one of each. In a saddle (two of each), joining
 * the inside corners pairs each in->out edge with the next out->in edge, separating them with the
 * previous one. Each edge is left by one segment at most (its two cells cross it in opposite
 * directions), so next[edge] links the segments into loops. */
typedef struct {
    const double *f;
    size_t w, h;
} grid;

static double G(const grid *g, long i, long j)
{
    if (i < 0 || j < 0 || i >= (long)g->w || j >= (long)g->h) return -1.0;
    double v = g->f[(size_t)i + g->w * (size_t)j];
    return isfinite(v) ? v : -1.0;
}

/* Edge ids: horizontal edge from (i, j) to (i+1, j) = 2 ((j+1)(w+2) + i+1), vertical (i, j)-(i, j+1) that + 1. */
static size_t edge_id(const grid *g, long i, long j, int vertical)
{
    return 2 * ((size_t)(j + 1) * (g->w + 2) + (size_t)(i + 1)) + (size_t)vertical;
}

static void edge_point(const grid *g, size_t id, double *x, double *y)
{
    int vertical = (int)(id & 1);
    size_t k = id / 2;
    long i = (long)(k % (g->w + 2)) - 1, j = (long)(k / (g->w + 2)) - 1;
    double f0 = G(g, i, j), f1 = vertical ? G(g, i, j + 1) : G(g, i + 1, j);
    double t = f0 / (f0 - f1);
    if (!(t >= 0)) t = 0;
    if (t > 1) t = 1;
    *x = (double)i + (vertical ? 0 : t);
    *y = (double)j + (vertical ? t : 0);
}

thx_status dig_march(thx_ctx *ctx, const double *f, size_t w, size_t h, int conn8, dig_loops *out)
{
    memset(out, 0, sizeof *out);
    grid g = {f, w, h};
    size_t ne = 2 * (w + 2) * (h + 2);
    long *next = thx_malloc(ctx, ne * sizeof *next);
    if (!next) return THX_ENOMEM;
    for (size_t e = 0; e < ne; e++) next[e] = -1;
    for (long j = -1; j < (long)h; j++)
        for (long i = -1; i < (long)w; i++) {
            int in[4] = {G(&g, i, j) > 0, G(&g, i + 1, j) > 0, G(&g, i + 1, j + 1) > 0, G(&g, i, j + 1) > 0};
            int mask = in[0] | in[1] << 1 | in[2] << 2 | in[3] << 3;
            if (mask == 0 || mask == 15) continue;
            size_t eid[4] = {edge_id(&g, i, j, 0), edge_id(&g, i + 1, j, 1), edge_id(&g, i, j + 1, 0),
                             edge_id(&g, i, j, 1)};
            /* edge k joins corner k to corner k+1 in the counterclockwise walk */
            int kind[4]; /* +1 in->out, -1 out->in, 0 none */
            for (int k = 0; k < 4; k++) kind[k] = in[k] && !in[(k + 1) % 4] ? 1 : !in[k] && in[(k + 1) % 4] ? -1 : 0;
            int saddle = mask == 5 || mask == 10;
            for (int k = 0; k < 4; k++) {
                if (kind[k] != 1) continue;
                int step = (!saddle || conn8) ? 1 : 3; /* next (join) or previous (separate) */
                int m = (k + step) % 4;
                while (kind[m] != -1) m = (m + step) % 4;
                next[eid[k]] = (long)eid[m];
            }
        }
    thx_status st = THX_OK;
    size_t cap = 0; /* doubles */
    double *buf = NULL;
    for (size_t e0 = 0; e0 < ne; e0++) {
        if (next[e0] < 0) continue;
        size_t n = 0;
        size_t e = e0;
        while (next[e] >= 0) {
            size_t nx = (size_t)next[e];
            next[e] = -1;
            if ((st = thx_grow(ctx, (void **)&buf, &cap, 2 * (n + 1), sizeof *buf)) != THX_OK) goto done;
            double x, y;
            edge_point(&g, e, &x, &y);
            if (!(n && fabs(x - buf[2 * n - 2]) < 1e-12 && fabs(y - buf[2 * n - 1]) < 1e-12)) {
                buf[2 * n] = x;
                buf[2 * n + 1] = y;
                n++;
            }
            e = nx;
        }
        while (n > 1 && fabs(buf[0] - buf[2 * n - 2]) < 1e-12 && fabs(buf[1] - buf[2 * n - 1]) < 1e-12) n--;
        if (n < 3) continue;
        if (out->n == out->cap) {
            size_t c = out->cap;
            if ((st = thx_grow(ctx, (void **)&out->loop, &c, out->n + 1, sizeof *out->loop)) != THX_OK) goto done;
            out->cap = c;
        }
        double *xy = thx_malloc(ctx, 2 * n * sizeof *xy);
        if (!xy) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(xy, buf, 2 * n * sizeof *xy);
        out->loop[out->n].xy = xy;
        out->loop[out->n].n = n;
        out->n++;
    }
done:
    free(buf);
    free(next);
    if (st != THX_OK) dig_loops_free(out);
    return st;
}
