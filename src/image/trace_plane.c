/*
 * One plane of a label map traced into loops (src/image/trace_plane.h; docs/design/image.md,
 * "Tracing label maps"): the tissue's mask smoothed on the plane at the partial-volume scale,
 * marching squares at 0.5 with the asymptotic decider, holes filled or kept, beads dropped, the loops
 * resampled at the node spacing, finer while they would cross. Split from src/image/trace.c (the
 * driver: masks, components, layers) unchanged.
 */
#include "trace_plane.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---- the smoothed plane ----------------------------------------------------------------------- */

static thx_status plane_size(thx_ctx *ctx, plane *pl, size_t W, size_t H)
{
    pl->W = W;
    pl->H = H;
    if (W * H > pl->cap) {
        free(pl->f);
        free(pl->tmp);
        pl->f = thx_malloc(ctx, W * H * sizeof *pl->f);
        pl->tmp = thx_malloc(ctx, W * H * sizeof *pl->tmp);
        if (!pl->f || !pl->tmp) return THX_ENOMEM;
        pl->cap = W * H;
    }
    memset(pl->f, 0, W * H * sizeof *pl->f);
    return THX_OK;
}

/* Adds w * mask plane k into the buffer (rows of the buffer inside the image; a row walked by the
 * stride of the in-plane axis a0). */
static void plane_add(const cut *g, const unsigned char *mask, plane *pl, long k, double w)
{
    if (k < 0 || (size_t)k >= g->ns) return;
    long x0 = pl->u0 < 0 ? -pl->u0 : 0, x1 = (long)g->n0 - pl->u0; /* buffer columns inside the image */
    if (x1 > (long)pl->W) x1 = (long)pl->W;
    if (x0 >= x1) return;
    const size_t sa0 = g->st[g->a0];
    const float fw = (float)w;
    for (size_t y = 0; y < pl->H; y++) {
        long v = pl->v0 + (long)y;
        if (v < 0 || (size_t)v >= g->n1) continue;
        const unsigned char *m = mask + vox(g, (size_t)k, (size_t)(pl->u0 + x0), (size_t)v);
        float *f = pl->f + y * pl->W;
        for (long x = x0; x < x1; x++, m += sa0)
            if (*m == 1) f[x] += fw;
            else if (*m) f[x] -= fw; /* a sibling's voxel (2): the competition field S(tissue) - S(siblings) */
    }
}

void tp_gauss_weights(double sigma, double w[2 * KR + 1])
{
    double sum = 0;
    for (int d = -KR; d <= KR; d++) {
        w[d + KR] = sigma > 0 ? exp(-0.5 * d * d / (sigma * sigma)) : (d == 0);
        sum += w[d + KR];
    }
    for (int d = 0; d <= 2 * KR; d++) w[d] /= sum;
}

/* Separable in-plane smoothing of pl->f (zero outside the buffer). Each output is the same sum in
 * the same order (taps -KR..KR, in double, from 0) in the interior, without the bounds tests, as at
 * the rim with them. */
static void plane_smooth(plane *pl, const double w[2 * KR + 1])
{
    size_t W = pl->W, H = pl->H;
    for (size_t y = 0; y < H; y++) {
        const float *f = pl->f + y * W;
        float *t = pl->tmp + y * W;
        for (size_t x = 0; x < W; x++) {
            double s = 0;
            if (x >= KR && x + KR < W)
                for (int d = -KR; d <= KR; d++) s += w[d + KR] * f[x + (size_t)((long)d)];
            else
                for (int d = -KR; d <= KR; d++) {
                    long xx = (long)x + d;
                    if (xx >= 0 && (size_t)xx < W) s += w[d + KR] * f[xx];
                }
            t[x] = (float)s;
        }
    }
    for (size_t y = 0; y < H; y++) {
        float *f = pl->f + y * W;
        if (y >= KR && y + KR < H) {
            const float *r[2 * KR + 1];
            for (int d = -KR; d <= KR; d++) r[d + KR] = pl->tmp + (size_t)((long)y + d) * W;
            for (size_t x = 0; x < W; x++) {
                double s = 0;
                for (int d = 0; d <= 2 * KR; d++) s += w[d] * r[d][x];
                f[x] = (float)s;
            }
        } else
            for (size_t x = 0; x < W; x++) {
                double s = 0;
                for (int d = -KR; d <= KR; d++) {
                    long yy = (long)y + d;
                    if (yy >= 0 && (size_t)yy < H) s += w[d + KR] * pl->tmp[(size_t)yy * W + x];
                }
                f[x] = (float)s;
            }
    }
}

/* ---- marching squares ------------------------------------------------------------------------ */


static thx_status poly_push(thx_ctx *ctx, poly *p, double x, double y)
{
    if (p->n == p->cap) {
        size_t nc = p->cap ? 2 * p->cap : 16;
        thx_vec2 *np = thx_realloc(ctx, p->p, nc * sizeof *np);
        if (!np) return THX_ENOMEM;
        p->p = np;
        p->cap = nc;
    }
    p->p[p->n].x = x;
    p->p[p->n].y = y;
    p->n++;
    return THX_OK;
}

void tp_polyset_clear(polyset *s)
{
    for (size_t i = 0; i < s->n; i++) free(s->l[i].p);
    s->n = 0;
}

void tp_polyset_free(polyset *s)
{
    tp_polyset_clear(s);
    free(s->l);
    s->l = NULL;
    s->cap = 0;
}

thx_status tp_polyset_new(thx_ctx *ctx, polyset *s, poly **out)
{
    if (s->n == s->cap) {
        size_t nc = s->cap ? 2 * s->cap : 8;
        poly *nl = thx_realloc(ctx, s->l, nc * sizeof *nl);
        if (!nl) return THX_ENOMEM;
        s->l = nl;
        s->cap = nc;
    }
    memset(&s->l[s->n], 0, sizeof s->l[s->n]);
    *out = &s->l[s->n++];
    return THX_OK;
}

double tp_poly_area(const thx_vec2 *p, size_t n)
{
    double a = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) a += p[j].x * p[i].y - p[i].x * p[j].y;
    return 0.5 * a;
}

/* The crossing point on edge id of the buffer (buffer cell coordinates). Edge 2 (y W + x) joins
 * (x, y)-(x+1, y); edge 2 (y W + x) + 1 joins (x, y)-(x, y+1). */
static void edge_point(const plane *pl, size_t e, double *px, double *py)
{
    size_t c = e / 2, x = c % pl->W, y = c / pl->W;
    double fa = pl->f[c], fb = (e & 1) ? pl->f[c + pl->W] : pl->f[c + 1];
    double t = (ISO - fa) / (fb - fa);
    *px = (double)x + ((e & 1) ? 0 : t);
    *py = (double)y + ((e & 1) ? t : 0);
}

/* Traces the 0.5 level of pl->f into loops (buffer coordinates), inside on the left: outer loops
 * counterclockwise, holes clockwise. next is scratch of 2 W H entries. */
static thx_status march(thx_ctx *ctx, plane *pl, uint32_t **next, size_t *next_cap, polyset *out)
{
    size_t W = pl->W, H = pl->H, ne = 2 * W * H;
    if (ne > UINT32_MAX) return thx_error(ctx, THX_EINPUT, "trace: a plane of %zu x %zu cells is too large", W, H);
    if (ne > *next_cap) {
        free(*next);
        *next = thx_malloc(ctx, ne * sizeof **next);
        if (!*next) return THX_ENOMEM;
        *next_cap = ne;
    }
    uint32_t *nx = *next;
    const uint32_t NONE = UINT32_MAX;
    for (size_t e = 0; e < ne; e++) nx[e] = NONE;
    /* a value exactly at the level is moved just outside it: every crossing strictly inside its edge */
    for (size_t c = 0; c < W * H; c++)
        if (pl->f[c] == (float)ISO) pl->f[c] = nextafterf((float)ISO, 0.0f);
    for (size_t y = 0; y + 1 < H; y++)
        for (size_t x = 0; x + 1 < W; x++) {
            size_t c = y * W + x;
            double f[4] = {pl->f[c], pl->f[c + 1], pl->f[c + 1 + W], pl->f[c + W]};
            int in[4], cnt = 0;
            for (int k = 0; k < 4; k++) cnt += in[k] = f[k] > ISO;
            if (cnt == 0 || cnt == 4) continue;
            /* edges counterclockwise: e0 c0->c1, e1 c1->c2, e2 c2->c3 (reversed), e3 c3->c0 */
            size_t eid[4] = {2 * c, 2 * (c + 1) + 1, 2 * (c + W), 2 * c + 1};
            int exit_[4], entry[4];
            for (int k = 0; k < 4; k++) {
                exit_[k] = in[k] && !in[(k + 1) % 4];
                entry[k] = !in[k] && in[(k + 1) % 4];
            }
            int saddle = cnt == 2 && in[0] == in[2];
            int connected = 0;
            if (saddle) {
                /* asymptotic decider: the bilinear interpolant's value at its saddle point */
                double den = f[0] + f[2] - f[1] - f[3];
                double sv = den != 0 ? (f[0] * f[2] - f[1] * f[3]) / den : 0.25 * (f[0] + f[1] + f[2] + f[3]);
                connected = sv > ISO;
            }
            for (int k = 0; k < 4; k++) {
                if (!exit_[k]) continue;
                int to;
                if (saddle) to = connected ? (k + 1) % 4 : (k + 3) % 4;
                else {
                    to = -1;
                    for (int m = 0; m < 4; m++)
                        if (entry[m]) to = m;
                }
                nx[eid[k]] = (uint32_t)eid[to];
            }
        }
    for (size_t e = 0; e < ne; e++) {
        if (nx[e] == NONE) continue;
        poly *p;
        THX_CHECK(tp_polyset_new(ctx, out, &p));
        size_t cur = e;
        while (nx[cur] != NONE) {
            double px, py;
            edge_point(pl, cur, &px, &py);
            THX_CHECK(poly_push(ctx, p, px, py));
            size_t nn = nx[cur];
            nx[cur] = NONE;
            cur = nn;
        }
        if (cur != e) return thx_error(ctx, THX_EINPUT, "trace: internal error: an open contour");
    }
    return THX_OK;
}

/* ---- loops: holes, resampling, crossing --------------------------------------------------------- */

int tp_point_in(const thx_vec2 *p, size_t n, thx_vec2 q)
{
    int in = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y) && q.x < (p[j].x - p[i].x) * (q.y - p[i].y) / (p[j].y - p[i].y) + p[i].x)
            in = !in;
    return in;
}

/* The midpoint of edge i of a counterclockwise loop, moved a thousandth of the edge's length to its left (inside). */
thx_vec2 tp_inward(const poly *P, size_t i)
{
    thx_vec2 a = P->p[i], b = P->p[(i + 1) % P->n], q;
    q.x = 0.5 * (a.x + b.x) - 1e-3 * (b.y - a.y);
    q.y = 0.5 * (a.y + b.y) + 1e-3 * (b.x - a.x);
    return q;
}

void tp_bbox(const thx_vec2 *p, size_t n, double b[4])
{
    b[0] = b[2] = INFINITY;
    b[1] = b[3] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        b[0] = fmin(b[0], p[i].x);
        b[1] = fmax(b[1], p[i].x);
        b[2] = fmin(b[2], p[i].y);
        b[3] = fmax(b[3], p[i].y);
    }
}

static int box_in(const double in[4], const double out[4])
{
    return in[0] >= out[0] && in[1] <= out[1] && in[2] >= out[2] && in[3] <= out[3];
}

/* Arc-length resampling of a closed polyline into m points (m < n), from point 0. */
static thx_status resample(thx_ctx *ctx, const poly *src, size_t m, poly *dst)
{
    size_t n = src->n;
    double per = 0;
    for (size_t i = 0; i < n; i++) per += hypot(src->p[(i + 1) % n].x - src->p[i].x, src->p[(i + 1) % n].y - src->p[i].y);
    dst->n = 0;
    size_t i = 0;
    double acc = 0; /* arc length at src point i */
    for (size_t k = 0; k < m; k++) {
        double s = per * (double)k / (double)m;
        for (;;) {
            thx_vec2 a = src->p[i], b = src->p[(i + 1) % n];
            double len = hypot(b.x - a.x, b.y - a.y);
            if (acc + len >= s || i + 1 == n) {
                double t = len > 0 ? (s - acc) / len : 0;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                THX_CHECK(poly_push(ctx, dst, a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)));
                break;
            }
            acc += len;
            i++;
        }
    }
    return THX_OK;
}

static double orient(thx_vec2 a, thx_vec2 b, thx_vec2 c)
{
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static int seg_cross(thx_vec2 a, thx_vec2 b, thx_vec2 c, thx_vec2 d)
{
    double d1 = orient(a, b, c), d2 = orient(a, b, d), d3 = orient(c, d, a), d4 = orient(c, d, b);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 1;
    /* touching counts (the contour model's rule) */
    if (d1 == 0 && fmin(a.x, b.x) <= c.x && c.x <= fmax(a.x, b.x) && fmin(a.y, b.y) <= c.y && c.y <= fmax(a.y, b.y)) return 1;
    if (d2 == 0 && fmin(a.x, b.x) <= d.x && d.x <= fmax(a.x, b.x) && fmin(a.y, b.y) <= d.y && d.y <= fmax(a.y, b.y)) return 1;
    if (d3 == 0 && fmin(c.x, d.x) <= a.x && a.x <= fmax(c.x, d.x) && fmin(c.y, d.y) <= a.y && a.y <= fmax(c.y, d.y)) return 1;
    if (d4 == 0 && fmin(c.x, d.x) <= b.x && b.x <= fmax(c.x, d.x) && fmin(c.y, d.y) <= b.y && b.y <= fmax(c.y, d.y)) return 1;
    return 0;
}

/* Whether any two edges of the loops cross or touch (other than consecutive edges of a loop at
 * their shared point): segments bucketed in a uniform grid. */
static thx_status any_crossing(thx_ctx *ctx, const polyset *s, int *crossing)
{
    *crossing = 0;
    size_t ns = 0;
    double b[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY}, maxlen = 0;
    for (size_t l = 0; l < s->n; l++) {
        double lb[4];
        tp_bbox(s->l[l].p, s->l[l].n, lb);
        b[0] = fmin(b[0], lb[0]);
        b[1] = fmax(b[1], lb[1]);
        b[2] = fmin(b[2], lb[2]);
        b[3] = fmax(b[3], lb[3]);
        ns += s->l[l].n;
        for (size_t i = 0; i < s->l[l].n; i++) {
            thx_vec2 p = s->l[l].p[i], q = s->l[l].p[(i + 1) % s->l[l].n];
            maxlen = fmax(maxlen, hypot(q.x - p.x, q.y - p.y));
        }
    }
    if (ns < 3) return THX_OK;
    double w = b[1] - b[0], h = b[3] - b[2];
    double cs = fmax(maxlen, sqrt(fmax(w * h, 1e-300) / (double)ns));
    size_t gx = (size_t)(w / cs) + 1, gy = (size_t)(h / cs) + 1;
    while (gx * gy > 4 * ns + 16) {
        cs *= 2;
        gx = (size_t)(w / cs) + 1;
        gy = (size_t)(h / cs) + 1;
    }
    /* counting sort of (cell, segment) pairs */
    size_t *cnt = thx_calloc(ctx, gx * gy + 1, sizeof *cnt);
    if (!cnt) return THX_ENOMEM;
    size_t npair = 0;
    for (int pass = 0; pass < 2; pass++) {
        size_t *ent = NULL;
        if (pass == 1) {
            for (size_t c = 1; c <= gx * gy; c++) cnt[c] += cnt[c - 1];
            ent = thx_malloc(ctx, (npair ? npair : 1) * 2 * sizeof *ent);
            if (!ent) {
                free(cnt);
                return THX_ENOMEM;
            }
        }
        size_t *fill = NULL;
        if (pass == 1) {
            fill = thx_malloc(ctx, (gx * gy + 1) * sizeof *fill);
            if (!fill) {
                free(ent);
                free(cnt);
                return THX_ENOMEM;
            }
            memcpy(fill, cnt, (gx * gy + 1) * sizeof *fill);
        }
        for (size_t l = 0; l < s->n; l++)
            for (size_t i = 0; i < s->l[l].n; i++) {
                thx_vec2 p = s->l[l].p[i], q = s->l[l].p[(i + 1) % s->l[l].n];
                size_t x0 = (size_t)((fmin(p.x, q.x) - b[0]) / cs), x1 = (size_t)((fmax(p.x, q.x) - b[0]) / cs);
                size_t y0 = (size_t)((fmin(p.y, q.y) - b[2]) / cs), y1 = (size_t)((fmax(p.y, q.y) - b[2]) / cs);
                if (x1 >= gx) x1 = gx - 1;
                if (y1 >= gy) y1 = gy - 1;
                for (size_t y = y0; y <= y1; y++)
                    for (size_t x = x0; x <= x1; x++) {
                        size_t c = y * gx + x;
                        if (pass == 0) {
                            cnt[c + 1]++;
                            npair++;
                        } else {
                            ent[2 * fill[c]] = l;
                            ent[2 * fill[c] + 1] = i;
                            fill[c]++;
                        }
                    }
            }
        if (pass == 1) {
            for (size_t c = 0; c < gx * gy && !*crossing; c++)
                for (size_t a = cnt[c]; a < cnt[c + 1] && !*crossing; a++)
                    for (size_t e = a + 1; e < cnt[c + 1]; e++) {
                        size_t la = ent[2 * a], ia = ent[2 * a + 1], lb = ent[2 * e], ib = ent[2 * e + 1];
                        const poly *A = &s->l[la], *B = &s->l[lb];
                        if (la == lb) {
                            size_t n = A->n;
                            if (ia == ib || (ia + 1) % n == ib || (ib + 1) % n == ia) continue;
                        }
                        if (seg_cross(A->p[ia], A->p[(ia + 1) % A->n], B->p[ib], B->p[(ib + 1) % B->n])) {
                            *crossing = 1;
                            break;
                        }
                    }
            free(fill);
            free(ent);
        }
    }
    free(cnt);
    return THX_OK;
}

/* The smoothed field of output plane `p` for the tissue's mask into pl (box: the in-plane index
 * box of the mask's planes involved, per-plane boxes in pb). */
static thx_status plane_field(thx_ctx *ctx, const cut *g, const unsigned char *mask, const long *pb,
                              double t, int resampled, const double w[2 * KR + 1], plane *pl, int *empty)
{
    long k0 = (long)floor(t);
    double a = t - (double)k0;
    if (a < 1e-9) a = 0;
    long kmin = k0 - (resampled ? KR : 0), kmax = (a > 0 ? k0 + 1 : k0) + (resampled ? KR : 0);
    long u0 = LONG_MAX, u1 = LONG_MIN, v0 = LONG_MAX, v1 = LONG_MIN;
    for (long k = kmin; k <= kmax; k++) {
        if (k < 0 || (size_t)k >= g->ns || pb[4 * k] > pb[4 * k + 1]) continue;
        u0 = pb[4 * k] < u0 ? pb[4 * k] : u0;
        u1 = pb[4 * k + 1] > u1 ? pb[4 * k + 1] : u1;
        v0 = pb[4 * k + 2] < v0 ? pb[4 * k + 2] : v0;
        v1 = pb[4 * k + 3] > v1 ? pb[4 * k + 3] : v1;
    }
    *empty = u0 > u1;
    if (*empty) return THX_OK;
    THX_CHECK(plane_size(ctx, pl, (size_t)(u1 - u0 + 1 + 2 * PAD), (size_t)(v1 - v0 + 1 + 2 * PAD)));
    pl->u0 = u0 - PAD;
    pl->v0 = v0 - PAD;
    /* across planes: the Gaussian (when resampling) of each image plane, then linear in t */
    for (int side = 0; side < 2; side++) {
        double ws = side == 0 ? 1 - a : a;
        if (ws == 0) continue;
        long kc = k0 + side;
        if (!resampled) plane_add(g, mask, pl, kc, ws);
        else
            for (int d = -KR; d <= KR; d++) plane_add(g, mask, pl, kc + d, ws * w[d + KR]);
    }
    plane_smooth(pl, w);
    return THX_OK;
}

void tp_scratch_free(plane_scratch *sc)
{
    free(sc->pl.f);
    free(sc->pl.tmp);
    free(sc->nxt);
    tp_polyset_free(&sc->raw);
    tp_polyset_free(&sc->fin);
}

/* Is loop l of the plane (ar: area and bounding box of each, 5 values) a bead pinched off: under
 * PINCH_BEAD_VOXELS voxels' in-plane area (amin: one voxel's), with nodes of the tissue's other loops
 * nearer than PINCH_BEAD_GAP voxels at two places, on two loops or on one loop more than
 * PINCH_BEAD_APART of its nodes apart? Where a boundary meets another at a saddle of the smoothed
 * field (a lung's dome where it touches the lung's outer wall), marching squares leaves the voxels
 * between the two loops' tips as a loop of their own; laced, it is a branch of a voxel the lacing must
 * bridge into its neighbour (issue 25: the bench map's lungs crossed there). A bead beside one stretch
 * of a loop (a dome's sliver along the lung) is not pinched: the branching lacing takes it. */
#define PINCH_BEAD_VOXELS 4.0
#define PINCH_BEAD_GAP 1.5
#define PINCH_BEAD_APART 10
static int pinch_bead(const polyset *raw, const double *ar, size_t l, double amin)
{
    if (!(amin > 0) || !(fabs(ar[5 * l]) < PINCH_BEAD_VOXELS * amin)) return 0;
    double gap = PINCH_BEAD_GAP * sqrt(amin), g2 = gap * gap;
    const double *bl = ar + 5 * l + 1; /* xmin xmax ymin ymax */
    const poly *P = &raw->l[l];
    int places = 0;
    for (size_t k = 0; k < raw->n && places < 2; k++) {
        const double *bk = ar + 5 * k + 1;
        if (k == l || bk[0] > bl[1] + gap || bk[1] < bl[0] - gap || bk[2] > bl[3] + gap || bk[3] < bl[2] - gap) continue;
        const poly *Q = &raw->l[k];
        /* Q's nodes near the bead, in order along Q: the places are the runs of them, split where two
           consecutive ones (cyclically) are more than PINCH_BEAD_APART nodes apart */
        long first = -1, prev = -1;
        int runs = 0;
        for (size_t j = 0; j < Q->n; j++) {
            int near = 0;
            for (size_t i = 0; i < P->n && !near; i++) {
                double dx = P->p[i].x - Q->p[j].x, dy = P->p[i].y - Q->p[j].y;
                near = dx * dx + dy * dy < g2;
            }
            if (!near) continue;
            if (first < 0) first = (long)j, runs = 1;
            else if ((long)j - prev > PINCH_BEAD_APART) runs++;
            prev = (long)j;
        }
        if (first >= 0 && runs > 1 && first + (long)Q->n - prev <= PINCH_BEAD_APART) runs--; /* joined across the start */
        places += runs;
    }
    return places >= 2;
}

/* A point just inside hole P (a clockwise loop): its longest edge's midpoint moved a tenth of that
 * edge to the right, into the hole. */
static thx_vec2 hole_probe(const poly *P)
{
    size_t best = 0;
    double bl = -1;
    for (size_t k = 0; k < P->n; k++) {
        thx_vec2 a = P->p[k], b = P->p[(k + 1) % P->n];
        double l = hypot(b.x - a.x, b.y - a.y);
        if (l > bl) { bl = l; best = k; }
    }
    thx_vec2 a = P->p[best], b = P->p[(best + 1) % P->n];
    return (thx_vec2){0.5 * (a.x + b.x) + 0.1 * (b.y - a.y), 0.5 * (a.y + b.y) - 0.1 * (b.x - a.x)};
}

/* One output plane of a tissue (continuous image plane index tk): its loops in model coordinates,
 * holes filled or kept, resampled at the node spacing h, into *out (empty: no loop); the holes seen
 * and the islands filled counted into *n_holes, *n_islands. Reads only the mask and the plane boxes,
 * so planes are traced in parallel. */
thx_status tp_trace_plane(thx_ctx *ctx, const cut *g, const unsigned char *mask, const long *pb, double tk,
                              int resampled, const double w[2 * KR + 1], thx_trace_holes holes, double h,
                              double amin, plane_scratch *sc, polyset *out, size_t *n_holes, size_t *n_islands,
                              size_t *n_tiny, thx_vec2 *probe)
{
    polyset *raw = &sc->raw, *fin = &sc->fin;
    int empty;
    probe->x = probe->y = NAN;
    tp_polyset_clear(out);
    THX_CHECK(plane_field(ctx, g, mask, pb, tk, resampled, w, &sc->pl, &empty));
    if (empty) return THX_OK;
    tp_polyset_clear(raw);
    THX_CHECK(march(ctx, &sc->pl, &sc->nxt, &sc->nxt_cap, raw));
    if (!raw->n) return THX_OK;
    /* to model coordinates; the orientation kept (inside on the left) */
    double det = g->A0[0] * g->A1[1] - g->A0[1] * g->A1[0];
    for (size_t l = 0; l < raw->n; l++) {
        poly *P = &raw->l[l];
        for (size_t i = 0; i < P->n; i++) {
            double u = P->p[i].x + (double)sc->pl.u0, v = P->p[i].y + (double)sc->pl.v0;
            P->p[i].x = g->P0[0] + g->A0[0] * u + g->A1[0] * v;
            P->p[i].y = g->P0[1] + g->A0[1] * u + g->A1[1] * v;
        }
        if (det < 0)
            for (size_t i = 0, j = P->n - 1; i < j; i++, j--) {
                thx_vec2 tmp = P->p[i];
                P->p[i] = P->p[j];
                P->p[j] = tmp;
            }
    }
    /* holes: loops of negative area; filled (dropped, with any loop inside them) or kept */
    double *ar = thx_malloc(ctx, raw->n * 6 * sizeof *ar); /* area, box; then 1: a pinched bead */
    if (!ar) return THX_ENOMEM;
    for (size_t l = 0; l < raw->n; l++) {
        ar[5 * l] = tp_poly_area(raw->l[l].p, raw->l[l].n);
        tp_bbox(raw->l[l].p, raw->l[l].n, ar + 5 * l + 1);
    }
    for (size_t l = 0; l < raw->n; l++) ar[5 * raw->n + l] = ar[5 * l] > 0 && pinch_bead(raw, ar, l, amin);
    tp_polyset_clear(fin);
    double probe_area = 0;
    for (size_t l = 0; l < raw->n; l++) {
        int hole = ar[5 * l] < 0, drop = 0;
        if (fabs(ar[5 * l]) < amin || ar[5 * raw->n + l] != 0) {
            /* below the image's resolution: a bead of the staircase, or a bead pinched off another loop */
            (*n_tiny)++;
            continue;
        }
        if (hole) (*n_holes)++;
        if (holes == THX_TRACE_HOLES_FILL) {
            if (hole && -ar[5 * l] > probe_area) { /* the largest filled hole: a point just inside it */
                probe_area = -ar[5 * l];
                *probe = hole_probe(&raw->l[l]);
            }
            if (hole) drop = 1;
            else
                for (size_t k = 0; k < raw->n && !drop; k++)
                    if (k != l && ar[5 * k] > 0 && box_in(ar + 5 * l + 1, ar + 5 * k + 1) &&
                        tp_point_in(raw->l[k].p, raw->l[k].n, raw->l[l].p[0]))
                        drop = 1;
            if (drop && !hole) (*n_islands)++;
        }
        if (drop) continue;
        poly *d;
        thx_status r = tp_polyset_new(ctx, fin, &d);
        if (r != THX_OK) {
            free(ar);
            return r;
        }
        *d = raw->l[l];
        raw->l[l].p = NULL;
        raw->l[l].n = raw->l[l].cap = 0;
    }
    free(ar);
    /* resampled at the node spacing; finer while loops would cross */
    double hh = h;
    for (int attempt = 0; attempt < 6; attempt++) {
        tp_polyset_clear(out);
        int shrunk = 0;
        for (size_t l = 0; l < fin->n; l++) {
            const poly *P = &fin->l[l];
            double per = 0;
            for (size_t i = 0; i < P->n; i++)
                per += hypot(P->p[(i + 1) % P->n].x - P->p[i].x, P->p[(i + 1) % P->n].y - P->p[i].y);
            size_t m = (size_t)floor(per / hh + 0.5);
            if (m < 8) m = 8;
            poly *d;
            THX_CHECK(tp_polyset_new(ctx, out, &d));
            if (attempt == 5 || m >= P->n) {
                for (size_t i = 0; i < P->n; i++) THX_CHECK(poly_push(ctx, d, P->p[i].x, P->p[i].y));
            } else {
                THX_CHECK(resample(ctx, P, m, d));
                shrunk = 1;
            }
        }
        if (!shrunk) break;
        int crossing;
        THX_CHECK(any_crossing(ctx, out, &crossing));
        if (!crossing) break;
        hh /= 2;
    }
    return THX_OK;
}
