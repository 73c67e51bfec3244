/*
 * Label maps -> contours (thorax/image/trace.h; docs/design/image.md, "Tracing label maps"):
 * per tissue a 3D mask cleaned by 6-connected flood fills, per plane the smoothed indicator traced
 * by marching squares at 0.5 (asymptotic decider), loops resampled at the node spacing.
 */
#include "thorax/image/trace.h"

#include "components.h"
#include "thorax/core/union_find.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define ISO 0.5
#define PAD 3 /* zero cells around a plane's box: the smoothed field is below 0.5 on the buffer's rim */
#define KR 2  /* Gaussian kernel radius, cells (sigma 0.5: the weight at 3 is 1e-8) */

void thx_trace_opts_default(thx_trace_opts *o)
{
    memset(o, 0, sizeof *o);
    o->min_size = 8;
    o->sigma = 0.5;
    o->holes = THX_TRACE_HOLES_FILL;
}

void thx_trace_report_free(thx_trace_report *rep)
{
    if (!rep) return;
    free(rep->tissue);
    rep->tissue = NULL;
    rep->n_tissues = 0;
}

/* ---- geometry of the cut ---------------------------------------------------------------------- */

typedef struct {
    const thx_image *img;
    int s, a0, a1;        /* superior index axis; the in-plane axes (a0 < a1) */
    size_t ns, n0, n1;    /* planes, and the plane's size along a0, a1 */
    size_t st[3];         /* stride of each index axis in the voxel array */
    double P0[2], A0[2], A1[2]; /* model (x, y) = P0 + A0 u + A1 v for in-plane indices (u, v) */
    double z0, dz;        /* model z of image plane k = z0 + dz k (dz = +-spacing) */
    double Q[9];          /* RAS = Q model, row-major */
} cut;

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static void cut_init(const thx_image *img, cut *g, double *oblique_deg)
{
    int sa, ss, aa, as;
    double cosine;
    thx_image_axes(img, &sa, &ss, &aa, &as, &cosine);
    g->img = img;
    g->s = sa;
    g->a0 = sa == 0 ? 1 : 0;
    g->a1 = sa == 2 ? 1 : 2;
    g->ns = img->n[sa];
    g->n0 = img->n[g->a0];
    g->n1 = img->n[g->a1];
    g->st[0] = 1;
    g->st[1] = img->n[0];
    g->st[2] = img->n[0] * img->n[1];
    double u[3][3]; /* u[c] = RAS unit vector of index axis c */
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) u[c][r] = img->dir[r * 3 + c];
    double zx[3], yx[3], xx[3];
    for (int r = 0; r < 3; r++) {
        zx[r] = ss * u[sa][r];
        yx[r] = as * u[aa][r];
    }
    cross3(yx, zx, xx);
    if (thx_image_axis_aligned(img)) /* exactly RAS: no rounding residue in the coordinates */
        for (int r = 0; r < 3; r++) {
            xx[r] = round(xx[r]);
            yx[r] = round(yx[r]);
            zx[r] = round(zx[r]);
        }
    for (int r = 0; r < 3; r++) {
        g->Q[r * 3 + 0] = xx[r];
        g->Q[r * 3 + 1] = yx[r];
        g->Q[r * 3 + 2] = zx[r];
    }
    /* model p = Q^T ras; ras = origin + sum_c u_c spacing_c i_c */
    double po[3], pc[3][3];
    for (int m = 0; m < 3; m++) {
        const double *ax = m == 0 ? xx : m == 1 ? yx : zx;
        po[m] = ax[0] * img->origin[0] + ax[1] * img->origin[1] + ax[2] * img->origin[2];
        for (int c = 0; c < 3; c++) pc[c][m] = (ax[0] * u[c][0] + ax[1] * u[c][1] + ax[2] * u[c][2]) * img->spacing[c];
    }
    g->P0[0] = po[0];
    g->P0[1] = po[1];
    g->A0[0] = pc[g->a0][0];
    g->A0[1] = pc[g->a0][1];
    g->A1[0] = pc[g->a1][0];
    g->A1[1] = pc[g->a1][1];
    g->z0 = po[2];
    g->dz = pc[sa][2];
    if (oblique_deg) *oblique_deg = acos(fmin(1.0, fabs(zx[2]))) * 180.0 / M_PI;
}

static size_t vox(const cut *g, size_t k, size_t u, size_t v)
{
    return k * g->st[g->s] + u * g->st[g->a0] + v * g->st[g->a1];
}

/* ---- the tissue's mask and its cleaning ------------------------------------------------------ */

typedef struct {
    long lo, hi;              /* LUT range */
    unsigned char *lut;       /* hi - lo + 1 entries, or NULL: search `vals` */
    long *vals;
    size_t n;
    int all;
} labelset;

/* The paper's nesting (3.1): the torso's outer boundary holds the fat/muscle interface, which holds the
 * inner border of the muscle, which holds the organs. */
static int nest_depth(thx_role r)
{
    switch (r) {
    case THX_ROLE_OUTER: return 0;
    case THX_ROLE_FAT: return 1;
    case THX_ROLE_MUSCLE: return 2;
    default: return 3;
    }
}

static int in_set(const labelset *ls, long v)
{
    if (ls->all && v != 0) return 1;
    if (ls->lut) return v >= ls->lo && v <= ls->hi && ls->lut[v - ls->lo];
    size_t a = 0, b = ls->n;
    while (a < b) {
        size_t m = (a + b) / 2;
        if (ls->vals[m] < v) a = m + 1;
        else b = m;
    }
    return a < ls->n && ls->vals[a] == v;
}

static int cmp_long(const void *a, const void *b)
{
    long x = *(const long *)a, y = *(const long *)b;
    return (x > y) - (x < y);
}

/* Small components: those of fewer than `min` voxels (and, when !touching_ok, not touching the box's
 * faces) are set to `to`; counted, their voxels summed, the first THX_TRACE_SIZES_KEPT sizes kept. */
typedef struct {
    unsigned char val, to;
    size_t min;
    int touching_ok;
    size_t *count, *voxels, *sizes;
} clean_rule;

static unsigned char clean_decide(void *user, size_t size, int touches, size_t ordinal)
{
    clean_rule *r = user;
    (void)ordinal;
    if (!(size < r->min && (r->touching_ok || !touches))) return r->val;
    if (*r->count < THX_TRACE_SIZES_KEPT && r->sizes) r->sizes[*r->count] = size;
    (*r->count)++;
    *r->voxels += size;
    return r->to;
}

/* 6-connected components of mask voxels equal to `val` inside box [lo, hi) (inclusive lo, exclusive
 * hi per axis) that have fewer than min voxels (and, when !touching_ok, do not touch the box's
 * border) are set to `to` (thx_components6, shared with the segmentation). The number of components
 * changed goes to *count, their sizes to sizes (first THX_TRACE_SIZES_KEPT), the total to *voxels. */
static thx_status clean(thx_ctx *ctx, unsigned char *mask, const size_t n[3], const size_t lo[3], const size_t hi[3],
                        unsigned char val, unsigned char to, size_t min, int touching_ok, size_t *count, size_t *voxels,
                        size_t *sizes)
{
    clean_rule r = {val, to, min, touching_ok, count, voxels, sizes};
    return thx_components6(ctx, mask, n, lo, hi, val, clean_decide, &r, NULL);
}

/* ---- the smoothed plane ----------------------------------------------------------------------- */

typedef struct {
    size_t W, H;          /* buffer size (cells) */
    long u0, v0;          /* in-plane index of buffer cell (0, 0) */
    float *f, *tmp;
    size_t cap;
} plane;

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

static void gauss_weights(double sigma, double w[2 * KR + 1])
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

typedef struct {
    size_t n, cap;
    thx_vec2 *p;
} poly;

typedef struct {
    size_t n, cap;
    poly *l;
} polyset;

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

static void polyset_clear(polyset *s)
{
    for (size_t i = 0; i < s->n; i++) free(s->l[i].p);
    s->n = 0;
}

static void polyset_free(polyset *s)
{
    polyset_clear(s);
    free(s->l);
    s->l = NULL;
    s->cap = 0;
}

static thx_status polyset_new(thx_ctx *ctx, polyset *s, poly **out)
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

static double poly_area(const thx_vec2 *p, size_t n)
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
        THX_CHECK(polyset_new(ctx, out, &p));
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

static int point_in(const thx_vec2 *p, size_t n, thx_vec2 q)
{
    int in = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y) && q.x < (p[j].x - p[i].x) * (q.y - p[i].y) / (p[j].y - p[i].y) + p[i].x)
            in = !in;
    return in;
}

/* The midpoint of edge i of a counterclockwise loop, moved a thousandth of the edge's length to its left (inside). */
static thx_vec2 inward(const poly *P, size_t i)
{
    thx_vec2 a = P->p[i], b = P->p[(i + 1) % P->n], q;
    q.x = 0.5 * (a.x + b.x) - 1e-3 * (b.y - a.y);
    q.y = 0.5 * (a.y + b.y) + 1e-3 * (b.x - a.x);
    return q;
}

static void bbox(const thx_vec2 *p, size_t n, double b[4])
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
        bbox(s->l[l].p, s->l[l].n, lb);
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

/* ---- components (one surface each) and siblings (pulled apart) ----------------------------------- */

static unsigned char keep_all_decide(void *user, size_t size, int touches, size_t ordinal)
{
    (void)user;
    (void)size;
    (void)touches;
    (void)ordinal;
    return 1;
}

#define MAX_SPLIT 16 /* more components than this: a fragmented region, traced as one surface */

/* keeps the components of group `want` */
typedef struct {
    const size_t *grp;
    size_t want;
} pick_rule;
static unsigned char pick_decide(void *user, size_t size, int touches, size_t ordinal)
{
    const pick_rule *r = user;
    (void)size;
    (void)touches;
    return r->grp[ordinal] == r->want;
}

/* The voxels equal to 1 in box [lo, hi): their count, the sums of their indices and their index box
 * b = {min i, max i, min j, max j, min k, max k}. */
static void box_scan(const thx_image *img, const unsigned char *m, const size_t lo[3], const size_t hi[3], size_t *count,
                     double sum[3], long b[6])
{
    double s0 = 0, s1 = 0, s2 = 0;
    size_t cnt = 0;
    long mn0 = LONG_MAX, mn1 = LONG_MAX, mn2 = LONG_MAX, mx0 = -1, mx1 = -1, mx2 = -1;
    const size_t n0 = img->n[0], n01 = img->n[0] * img->n[1];
#pragma omp parallel for reduction(+ : s0, s1, s2, cnt) reduction(min : mn0, mn1, mn2) reduction(max : mx0, mx1, mx2) \
    schedule(static)
    for (long k = (long)lo[2]; k < (long)hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++) {
            const unsigned char *r = m + (size_t)k * n01 + j * n0;
            for (size_t i = lo[0]; i < hi[0]; i++)
                if (r[i] == 1) {
                    s0 += (double)i;
                    s1 += (double)j;
                    s2 += (double)k;
                    cnt++;
                    if ((long)i < mn0) mn0 = (long)i;
                    if ((long)i > mx0) mx0 = (long)i;
                    if ((long)j < mn1) mn1 = (long)j;
                    if ((long)j > mx1) mx1 = (long)j;
                    if (k < mn2) mn2 = k;
                    if (k > mx2) mx2 = k;
                }
        }
    *count = cnt;
    sum[0] = s0, sum[1] = s1, sum[2] = s2;
    b[0] = mn0, b[1] = mx0, b[2] = mn1, b[3] = mx1, b[4] = mn2, b[5] = mx2;
}

static int lab_in(const labelset *ls, long x)
{
    if (ls->all && x != 0) return 1;
    if (ls->lut) return (unsigned long)(x - ls->lo) <= (unsigned long)(ls->hi - ls->lo) ? ls->lut[x - ls->lo] : 0;
    return in_set(ls, x);
}

/* The voxels equal to 1 in box [lo, hi): their count, the RAS centroid of their centres and the
 * RAS x range of their index box's corners. */
static void box_centroid(const thx_image *img, const unsigned char *m, const size_t lo[3], const size_t hi[3],
                         size_t *count, double ras[3], double xr[2])
{
    double sum[3];
    size_t cnt;
    long bx[6];
    box_scan(img, m, lo, hi, &cnt, sum, bx);
    long mn0 = bx[0], mx0 = bx[1], mn1 = bx[2], mx1 = bx[3], mn2 = bx[4], mx2 = bx[5];
    double s0 = sum[0], s1 = sum[1], s2 = sum[2];
    xr[0] = INFINITY;
    xr[1] = -INFINITY;
    for (int corner = 0; cnt && corner < 8; corner++) {
        double id[3] = {(double)(corner & 1 ? mx0 : mn0), (double)(corner & 2 ? mx1 : mn1), (double)(corner & 4 ? mx2 : mn2)};
        double x = img->origin[0];
        for (int c = 0; c < 3; c++) x += img->dir[c] * img->spacing[c] * id[c];
        xr[0] = fmin(xr[0], x);
        xr[1] = fmax(xr[1], x);
    }
    *count = cnt;
    double idx[3] = {cnt ? s0 / (double)cnt : 0, cnt ? s1 / (double)cnt : 0, cnt ? s2 / (double)cnt : 0};
    for (int r = 0; r < 3; r++) {
        ras[r] = img->origin[r];
        for (int c = 0; c < 3; c++) ras[r] += img->dir[r * 3 + c] * img->spacing[c] * idx[c];
    }
}

/* Sets the voxels equal to 0 in box [wlo, whi) whose label is a sibling's (sl) to 2; returns the
 * voxels equal to 1 in [lo, hi) with a face on such a voxel. */
static size_t mark_siblings(const thx_image *img, unsigned char *m, const labelset *sl, const size_t wlo[3],
                            const size_t whi[3], const size_t lo[3], const size_t hi[3])
{
    const size_t n0 = img->n[0], n1 = img->n[1], n2 = img->n[2], n01 = n0 * n1;
#pragma omp parallel for schedule(static)
    for (long k = (long)wlo[2]; k < (long)whi[2]; k++)
        for (size_t j = wlo[1]; j < whi[1]; j++) {
            size_t q = (size_t)k * n01 + j * n0;
            for (size_t i = wlo[0]; i < whi[0]; i++)
                if (!m[q + i] && lab_in(sl, (long)img->v[q + i])) m[q + i] = 2;
        }
    size_t cnt = 0;
#pragma omp parallel for reduction(+ : cnt) schedule(static)
    for (long k = (long)lo[2]; k < (long)hi[2]; k++)
        for (size_t j = lo[1]; j < hi[1]; j++)
            for (size_t i = lo[0]; i < hi[0]; i++) {
                size_t q = (size_t)k * n01 + j * n0 + i;
                if (m[q] != 1) continue;
                cnt += (i > 0 && m[q - 1] == 2) || (i + 1 < n0 && m[q + 1] == 2) || (j > 0 && m[q - n0] == 2) ||
                       (j + 1 < n1 && m[q + n0] == 2) || (k > 0 && m[q - n01] == 2) ||
                       ((size_t)k + 1 < n2 && m[q + n01] == 2);
            }
    return cnt;
}

static thx_status sr_push(thx_ctx *ctx, thx_trace_tissue_report **sr, size_t **sr_t, size_t *n, size_t *cap,
                          const thx_trace_tissue_report *r, size_t t)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 8;
        thx_trace_tissue_report *a = thx_realloc(ctx, *sr, nc * sizeof *a);
        if (!a) return THX_ENOMEM;
        *sr = a;
        size_t *b = thx_realloc(ctx, *sr_t, nc * sizeof *b);
        if (!b) return THX_ENOMEM;
        *sr_t = b;
        *cap = nc;
    }
    (*sr)[*n] = *r;
    (*sr_t)[*n] = t;
    (*n)++;
    return THX_OK;
}

/* The surfaces traced (c->surf[i] <-> sr[i], in tracing order) put in the order of the tissues given,
 * a tissue's components right to left (decreasing centroid RAS x), and named: the tissue's name
 * for one component, NAME_right and NAME_left for two, NAME_1, NAME_2, ... for more. */
static thx_status order_surfaces(thx_ctx *ctx, thx_contours *c, const thx_trace_opts *o, thx_trace_tissue_report *sr,
                                 const size_t *sr_t, size_t n, const char *what)
{
    if (c->n_surfaces != n) return thx_error(ctx, THX_EINPUT, "trace: internal error: %zu surfaces, %zu reports", c->n_surfaces, n);
    size_t *perm = thx_malloc(ctx, (n ? n : 1) * sizeof *perm);
    thx_contour_surface *ns = thx_malloc(ctx, (n ? n : 1) * sizeof *ns);
    thx_trace_tissue_report *nr = thx_malloc(ctx, (n ? n : 1) * sizeof *nr);
    if (!perm || !ns || !nr) {
        free(perm);
        free(ns);
        free(nr);
        return THX_ENOMEM;
    }
    size_t m = 0;
    for (size_t t = 0; t < o->n_tissues; t++) {
        size_t a = m;
        for (size_t i = 0; i < n; i++)
            if (sr_t[i] == t) perm[m++] = i;
        for (size_t i = a + 1; i < m; i++) /* insertion sort: decreasing RAS x, ties by component */
            for (size_t j = i; j > a && sr[perm[j]].centroid_ras[0] > sr[perm[j - 1]].centroid_ras[0]; j--) {
                size_t tmp = perm[j];
                perm[j] = perm[j - 1];
                perm[j - 1] = tmp;
            }
        for (size_t i = a; i < m; i++) {
            size_t k = i - a, nk = m - a;
            char nm[160];
            if (nk == 1) snprintf(nm, sizeof nm, "%s", o->tissues[t].name);
            else if (nk == 2 && (sr[perm[a]].ras_x_range[0] > sr[perm[a + 1]].ras_x_range[1]))
                snprintf(nm, sizeof nm, "%s_%s", o->tissues[t].name, k == 0 ? "right" : "left");
            else snprintf(nm, sizeof nm, "%s_%zu", o->tissues[t].name, k + 1);
            if (strlen(nm) >= sizeof c->surf[0].name) {
                thx_status e = thx_error(ctx, THX_EINPUT,
                                         "%s: tissue \"%s\" has %zu components, one surface each: the name \"%s\" is "
                                         "longer than 63 characters (give the tissue a shorter name)",
                                         what, o->tissues[t].name, nk, nm);
                free(perm);
                free(ns);
                free(nr);
                return e;
            }
            snprintf(c->surf[perm[i]].name, sizeof c->surf[0].name, "%s", nm);
            snprintf(sr[perm[i]].name, sizeof sr[0].name, "%s", nm);
            sr[perm[i]].component = k;
        }
    }
    for (size_t i = 0; i < n; i++) {
        ns[i] = c->surf[perm[i]];
        nr[i] = sr[perm[i]];
    }
    memcpy(c->surf, ns, n * sizeof *ns);
    memcpy(sr, nr, n * sizeof *nr);
    free(perm);
    free(ns);
    free(nr);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            if (strcmp(c->surf[i].name, c->surf[j].name) == 0)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: surface \"%s\" named twice: a tissue's components are named NAME_right/_left "
                                 "(or NAME_1..), which another --label's name takes (rename one)",
                                 what, c->surf[i].name);
    return THX_OK;
}

/* ---- the driver --------------------------------------------------------------------------------- */

typedef struct {
    size_t plane;   /* output plane number */
    size_t loop0, n; /* its loops in the tissue's loop list */
} layer_rec;

typedef struct {
    polyset loops;        /* all loops of the tissue (model coordinates), plane by plane */
    double *area;         /* signed area per loop */
    layer_rec *layers;
    size_t n_layers, cap_layers, cap_area;
} tissue_trace;

/* Whether organ tissues a and b are siblings: both of depth 3 (organs), neither `all`, their label
 * sets disjoint (blood {5} inside heart {4,5} is nested, not a sibling). */
static int siblings(const thx_trace_opts *o, size_t a, size_t b)
{
    const thx_trace_tissue *A = &o->tissues[a], *B = &o->tissues[b];
    if (a == b || nest_depth(A->role) != 3 || nest_depth(B->role) != 3 || A->all || B->all) return 0;
    for (size_t i = 0; i < A->n_values; i++)
        for (size_t j = 0; j < B->n_values; j++)
            if (A->values[i] == B->values[j]) return 0;
    return 1;
}

/* The label set of tissue t (sib = 0: its own values, and every tissue's for the outer role) or of
 * its siblings (sib = 1). */
/* Whether loops l and k of the tissue (outer loops, on neighbouring planes) overlap: a point just inside
 * an edge of one (to its left: outer loops run counterclockwise) in the other; loops that coincide (a
 * straight stack) overlap too. */
static int loops_overlap(const tissue_trace *tt, size_t l, size_t k)
{
    const double *ab = tt->area + 5 * l + 1, *bb = tt->area + 5 * k + 1;
    if (ab[0] > bb[1] || bb[0] > ab[1] || ab[2] > bb[3] || bb[2] > ab[3]) return 0;
    const poly *A = &tt->loops.l[l], *B = &tt->loops.l[k];
    for (size_t i = 0; i < A->n; i++)
        if (point_in(B->p, B->n, inward(A, i))) return 1;
    for (size_t i = 0; i < B->n; i++)
        if (point_in(A->p, A->n, inward(B, i))) return 1;
    return 0;
}

static thx_status build_labelset(thx_ctx *ctx, const thx_trace_opts *o, size_t t, int sib, float lo, float hi,
                                 labelset *ls)
{
    memset(ls, 0, sizeof *ls);
    const thx_trace_tissue *ti = &o->tissues[t];
    int outer = ti->role == THX_ROLE_OUTER;
#define TAKE(k) (sib ? siblings(o, t, (k)) : ((k) == t || outer))
    size_t n = 0;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (TAKE(k)) n += o->tissues[k].n_values;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (o->tissues[k].all && TAKE(k)) ls->all = 1;
    ls->vals = thx_malloc(ctx, (n ? n : 1) * sizeof *ls->vals);
    if (!ls->vals) return THX_ENOMEM;
    for (size_t k = 0; k < o->n_tissues; k++)
        if (TAKE(k))
            for (size_t j = 0; j < o->tissues[k].n_values; j++) ls->vals[ls->n++] = o->tissues[k].values[j];
    qsort(ls->vals, ls->n, sizeof *ls->vals, cmp_long);
    if (hi - lo < 16777216.0f) {
        ls->lo = (long)lo;
        ls->hi = (long)hi;
        ls->lut = thx_calloc(ctx, (size_t)(ls->hi - ls->lo + 1), 1);
        if (!ls->lut) return THX_ENOMEM;
        for (size_t j = 0; j < ls->n; j++)
            if (ls->vals[j] >= ls->lo && ls->vals[j] <= ls->hi) ls->lut[ls->vals[j] - ls->lo] = 1;
    }
    return THX_OK;
#undef TAKE
}

static void labelset_free(labelset *ls)
{
    free(ls->lut);
    free(ls->vals);
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

/* Per-thread scratch of the plane loop. */
typedef struct {
    plane pl;
    uint32_t *nxt;
    size_t nxt_cap;
    polyset raw, fin;
} plane_scratch;

static void scratch_free(plane_scratch *sc)
{
    free(sc->pl.f);
    free(sc->pl.tmp);
    free(sc->nxt);
    polyset_free(&sc->raw);
    polyset_free(&sc->fin);
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
static thx_status trace_plane(thx_ctx *ctx, const cut *g, const unsigned char *mask, const long *pb, double tk,
                              int resampled, const double w[2 * KR + 1], thx_trace_holes holes, double h,
                              double amin, plane_scratch *sc, polyset *out, size_t *n_holes, size_t *n_islands,
                              size_t *n_tiny, thx_vec2 *probe)
{
    polyset *raw = &sc->raw, *fin = &sc->fin;
    int empty;
    probe->x = probe->y = NAN;
    polyset_clear(out);
    THX_CHECK(plane_field(ctx, g, mask, pb, tk, resampled, w, &sc->pl, &empty));
    if (empty) return THX_OK;
    polyset_clear(raw);
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
        ar[5 * l] = poly_area(raw->l[l].p, raw->l[l].n);
        bbox(raw->l[l].p, raw->l[l].n, ar + 5 * l + 1);
    }
    for (size_t l = 0; l < raw->n; l++) ar[5 * raw->n + l] = ar[5 * l] > 0 && pinch_bead(raw, ar, l, amin);
    polyset_clear(fin);
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
                        point_in(raw->l[k].p, raw->l[k].n, raw->l[l].p[0]))
                        drop = 1;
            if (drop && !hole) (*n_islands)++;
        }
        if (drop) continue;
        poly *d;
        thx_status r = polyset_new(ctx, fin, &d);
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
        polyset_clear(out);
        int shrunk = 0;
        for (size_t l = 0; l < fin->n; l++) {
            const poly *P = &fin->l[l];
            double per = 0;
            for (size_t i = 0; i < P->n; i++)
                per += hypot(P->p[(i + 1) % P->n].x - P->p[i].x, P->p[(i + 1) % P->n].y - P->p[i].y);
            size_t m = (size_t)floor(per / hh + 0.5);
            if (m < 8) m = 8;
            poly *d;
            THX_CHECK(polyset_new(ctx, out, &d));
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

thx_status thx_image_trace(thx_ctx *ctx, const thx_image *img, const thx_trace_opts *o, thx_contours **out,
                           thx_trace_report *rep)
{
    *out = NULL;
    if (rep) memset(rep, 0, sizeof *rep);
    const char *what = img->path[0] ? img->path : "<image>";
    if (!img->integral)
        return thx_error(ctx, THX_EINPUT,
                         "%s: not a label map: its voxels are stored as %s, not integers (threshold or segment the "
                         "image first)", what, img->stored_type[0] ? img->stored_type : "non-integral values");
    if (!o->n_tissues) return thx_error(ctx, THX_EINPUT, "%s: no tissue to trace (give at least one label)", what);
    if (!(o->spacing >= 0) || !(o->node_spacing >= 0) || !(o->sigma >= 0) || !isfinite(o->spacing) ||
        !isfinite(o->node_spacing) || o->sigma > 2)
        return thx_error(ctx, THX_EINPUT, "trace: bad options (spacing %g, node spacing %g, sigma %g)", o->spacing,
                         o->node_spacing, o->sigma);
    for (size_t t = 0; t < o->n_tissues; t++) {
        if (!o->tissues[t].all && !o->tissues[t].n_values)
            return thx_error(ctx, THX_EINPUT, "tissue \"%s\": no label value", o->tissues[t].name);
        for (size_t k = 0; k < t; k++)
            if (strcmp(o->tissues[k].name, o->tissues[t].name) == 0)
                return thx_error(ctx, THX_EINPUT, "tissue \"%s\" given twice", o->tissues[t].name);
    }
    cut g;
    double oblique;
    cut_init(img, &g, &oblique);
    float vlo, vhi;
    thx_image_range(img, &vlo, &vhi);
    size_t nv = thx_image_count(img);

    /* planes: every image plane (in increasing z), or `spacing` apart from the lowest */
    double hs = img->spacing[g.s];
    int resampled = o->spacing > 0;
    double zlo = g.dz > 0 ? g.z0 : g.z0 + g.dz * (double)(g.ns - 1);
    double span = hs * (double)(g.ns - 1);
    double pspace = resampled ? o->spacing : hs;
    size_t np = resampled ? (size_t)floor(span / pspace + 1e-9) + 1 : g.ns;
    double inplane = fmax(img->spacing[g.a0], img->spacing[g.a1]);
    double h = o->node_spacing > 0 ? o->node_spacing : fmax(inplane, pspace);
    /* loops enclosing less than one voxel's in-plane area are dropped when cleaning (min_size > 1): at a
       gently sloping boundary (a lung's dome) the staircase's single-voxel steps give beads of the
       smoothed field just over 0.5, loops of a tenth of a voxel that the lacing would have to branch to */
    double amin = o->min_size > 1 ? img->spacing[g.a0] * img->spacing[g.a1] : 0;

    thx_status st = THX_OK;
    thx_contours *c = NULL;
    size_t *order = NULL;
    thx_trace_tissue_report *sr = NULL; /* per surface traced (in tracing order): its report */
    size_t *sr_t = NULL, n_sr = 0, cap_sr = 0; /* and its tissue */
    unsigned char *scratch = NULL;      /* one component's mask */
    long *t_first = NULL, *t_last = NULL;
    unsigned char *mask = NULL;
    long *pb = NULL;
    polyset *pout = NULL;    /* per output plane: its loops */
    thx_status *pst = NULL;  /* per output plane: the status of its tracing */
    size_t *pcount = NULL;   /* per output plane: holes seen, islands filled, tiny loops dropped */
    thx_vec2 *pprobe = NULL; /* per output plane: a point inside its largest filled hole, or NaN */
    size_t *kcount = NULL;   /* per image plane along the superior axis: the tissue's voxels */
    tissue_trace tt = {0};
    labelset ls = {0};
    double w[2 * KR + 1];
    gauss_weights(o->sigma, w);
    if (rep) {
        rep->tissue = thx_calloc(ctx, o->n_tissues, sizeof *rep->tissue);
        if (!rep->tissue) return THX_ENOMEM;
        rep->n_tissues = o->n_tissues;
        rep->n_planes = np;
        rep->plane_spacing = pspace;
        rep->node_spacing = h;
        rep->z_first = zlo;
        rep->sup_axis = g.s;
        rep->oblique_deg = oblique;
        memcpy(rep->to_ras, g.Q, sizeof g.Q);
    }
    /* listed values absent from the image */
    {
        size_t nval = 0;
        for (size_t t = 0; t < o->n_tissues; t++) nval += o->tissues[t].n_values;
        long *vals = thx_malloc(ctx, (nval ? nval : 1) * sizeof *vals);
        unsigned char *seen = thx_calloc(ctx, nval ? nval : 1, 1);
        if (!vals || !seen) {
            free(vals);
            free(seen);
            st = THX_ENOMEM;
            goto done;
        }
        nval = 0;
        for (size_t t = 0; t < o->n_tissues; t++)
            for (size_t j = 0; j < o->tissues[t].n_values; j++) vals[nval++] = o->tissues[t].values[j];
        qsort(vals, nval, sizeof *vals, cmp_long);
        size_t left = nval;
        for (size_t i = 0; i < nv && left; i++) {
            long v = (long)img->v[i];
            size_t a = 0, b = nval;
            while (a < b) {
                size_t m = (a + b) / 2;
                if (vals[m] < v) a = m + 1;
                else b = m;
            }
            for (; a < nval && vals[a] == v; a++)
                if (!seen[a]) {
                    seen[a] = 1;
                    left--;
                }
        }
        for (size_t j = 0; j < nval; j++)
            if (!seen[j] && (j == 0 || vals[j] != vals[j - 1]) && rep) {
                if (rep->n_absent < THX_TRACE_SIZES_KEPT) rep->absent[rep->n_absent] = vals[j];
                rep->n_absent++;
            }
        free(vals);
        free(seen);
    }

    THX_TRY(thx_contours_create(ctx, &c));
    c->spacing = h;
    c->frame = thx_frame_ras();
    snprintf(c->image, sizeof c->image, "%s", img->path);
    snprintf(c->image_sha256, sizeof c->image_sha256, "%s", img->sha256);
    mask = thx_malloc(ctx, nv);
    pb = thx_malloc(ctx, 4 * g.ns * sizeof *pb);
    pout = thx_calloc(ctx, np, sizeof *pout);
    pst = thx_calloc(ctx, np, sizeof *pst);
    pcount = thx_calloc(ctx, 3 * np, sizeof *pcount);
    pprobe = thx_calloc(ctx, np ? np : 1, sizeof *pprobe);
    kcount = thx_malloc(ctx, g.ns * sizeof *kcount);
    if (!mask || !pb || !pout || !pst || !pcount || !pprobe || !kcount) {
        st = THX_ENOMEM;
        goto done;
    }
    /* the surfaces in the order given; traced in the paper's nesting order (outer, fat, muscle, then the
       organs) so that each tissue's container is traced before it: an inner surface must close inside its
       container's end planes, or the two caps would lie in one plane (a scan that cuts a torso or a neck
       cuts every layer at its end planes) */
    order = thx_malloc(ctx, o->n_tissues * sizeof *order);
    t_first = thx_malloc(ctx, o->n_tissues * sizeof *t_first);
    t_last = thx_malloc(ctx, o->n_tissues * sizeof *t_last);
    if (!order || !t_first || !t_last) {
        st = THX_ENOMEM;
        goto done;
    }
    {
        size_t k = 0;
        for (int d = 0; d <= 3; d++)
            for (size_t t = 0; t < o->n_tissues; t++)
                if (nest_depth(o->tissues[t].role) == d) order[k++] = t;
    }
    for (size_t oi = 0; oi < o->n_tissues; oi++) {
        size_t t = order[oi];
        const thx_trace_tissue *ti = &o->tissues[t];
        thx_trace_tissue_report trr;
        memset(&trr, 0, sizeof trr);
        snprintf(trr.name, sizeof trr.name, "%s", ti->name);
        size_t sidx = 0;
        t_first[t] = t_last[t] = -1;
        /* the container: the deepest tissue traced before of a lesser depth */
        long container = -1;
        for (size_t oj = 0; oj < oi; oj++) {
            size_t u = order[oj];
            if (nest_depth(o->tissues[u].role) >= nest_depth(ti->role)) continue;
            if (container < 0 || nest_depth(o->tissues[u].role) > nest_depth(o->tissues[container].role))
                container = (long)u;
        }
        /* the mask, its box and the in-plane box of each plane (before cleaning: a removed component
           only widens its planes' boxes) */
        THX_TRY(build_labelset(ctx, o, t, 0, vlo, vhi, &ls));
        for (size_t k = 0; k < g.ns; k++) {
            pb[4 * k] = pb[4 * k + 2] = LONG_MAX;
            pb[4 * k + 1] = pb[4 * k + 3] = LONG_MIN;
        }
        /* plane by plane along the superior axis, in parallel (each plane writes its own voxels, box
           and count) */
#pragma omp parallel for schedule(dynamic, 4)
        for (long k = 0; k < (long)g.ns; k++) {
            long *b = pb + 4 * k;
            size_t cnt = 0;
            for (size_t v = 0; v < g.n1; v++) {
                size_t row = 0, first = 0, last = 0;
                for (size_t u = 0; u < g.n0; u++) {
                    size_t q = vox(&g, (size_t)k, u, v);
                    long x = (long)img->v[q];
                    /* in_set, its look-up table inlined */
                    unsigned char m = (ls.all && x != 0) ? 1
                                      : ls.lut ? ((unsigned long)(x - ls.lo) <= (unsigned long)(ls.hi - ls.lo) ? ls.lut[x - ls.lo] : 0)
                                               : (unsigned char)in_set(&ls, x);
                    mask[q] = m;
                    if (m) {
                        if (!row) first = u;
                        last = u;
                        row++;
                    }
                }
                if (!row) continue;
                cnt += row;
                if ((long)first < b[0]) b[0] = (long)first;
                if ((long)last > b[1]) b[1] = (long)last;
                if ((long)v < b[2]) b[2] = (long)v;
                if ((long)v > b[3]) b[3] = (long)v;
            }
            kcount[k] = cnt;
        }
        size_t lo[3] = {SIZE_MAX, SIZE_MAX, SIZE_MAX}, hi[3] = {0, 0, 0}, count = 0;
        for (size_t k = 0; k < g.ns; k++) {
            if (!kcount[k]) continue;
            count += kcount[k];
            if (k < lo[g.s]) lo[g.s] = k;
            hi[g.s] = k + 1;
            if ((size_t)pb[4 * k] < lo[g.a0]) lo[g.a0] = (size_t)pb[4 * k];
            if ((size_t)pb[4 * k + 1] + 1 > hi[g.a0]) hi[g.a0] = (size_t)pb[4 * k + 1] + 1;
            if ((size_t)pb[4 * k + 2] < lo[g.a1]) lo[g.a1] = (size_t)pb[4 * k + 2];
            if ((size_t)pb[4 * k + 3] + 1 > hi[g.a1]) hi[g.a1] = (size_t)pb[4 * k + 3] + 1;
        }
        labelset_free(&ls);
        memset(&ls, 0, sizeof ls);
        if (!count) {
            st = thx_error(ctx, THX_EINPUT, "%s: tissue \"%s\": none of its label values is in the image", what, ti->name);
            goto done;
        }
        /* 3D cleaning in the box widened by one voxel (the outside of a cavity reaches the rim). With
           holes filled, a cavity is a hole in each of its planes and is filled with them: only kept
           holes need the cavity pass. */
        for (int q = 0; q < 3; q++) {
            if (lo[q] > 0) lo[q]--;
            if (hi[q] < img->n[q]) hi[q]++;
        }
        if (o->min_size > 1) {
            THX_TRY(clean(ctx, mask, img->n, lo, hi, 1, 0, o->min_size, 1, &trr.n_removed, &trr.removed_voxels,
                          trr.removed_size));
            if (o->holes == THX_TRACE_HOLES_KEEP)
                THX_TRY(clean(ctx, mask, img->n, lo, hi, 0, 1, o->min_size, 0, &trr.n_cavities, &trr.cavity_voxels, NULL));
        }
        trr.voxels = count - trr.removed_voxels + trr.cavity_voxels;
        if (!trr.voxels) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s: tissue \"%s\": all of its %zu voxels are in components of fewer than %zu voxels "
                           "(--min-size): nothing left to trace",
                           what, ti->name, trr.removed_voxels, o->min_size);
            goto done;
        }
        /* components: an organ's region of several 6-connected 3D components (two lungs under one label)
           gives a surface per component; siblings: organs of disjoint labels, marked 2 in the mask traced
           (the field S(tissue) - S(siblings)) */
        size_t ncomp = 1;
        int is_organ = nest_depth(ti->role) == 3, has_sib = 0;
        for (size_t k = 0; k < o->n_tissues; k++) has_sib |= siblings(o, t, k);
        size_t grp[MAX_SPLIT];
        if (is_organ) THX_TRY(thx_components6(ctx, mask, img->n, lo, hi, 1, keep_all_decide, NULL, &ncomp));
        if (ncomp > MAX_SPLIT) ncomp = 1;
        if (ncomp > 1 && !scratch) {
            scratch = thx_calloc(ctx, nv, 1);
            if (!scratch) {
                st = THX_ENOMEM;
                goto done;
            }
        }
        if (ncomp > 1) {
            /* components whose index boxes, widened by the smoothing's reach in the plane (KR + 1 voxels)
               and a plane across, overlap are one group, one surface: only organs well apart are split
               (two lungs; not parts that touch along an edge, whose loops would merge in the field) */
            long bx[MAX_SPLIT][6];
            size_t par[MAX_SPLIT];
            for (size_t cc = 0; cc < ncomp; cc++) {
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++) {
                        size_t q = k * img->n[0] * img->n[1] + j * img->n[0];
                        memcpy(scratch + q + lo[0], mask + q + lo[0], hi[0] - lo[0]);
                    }
                for (size_t q = 0; q < ncomp; q++) grp[q] = q;
                pick_rule pr = {grp, cc};
                THX_TRY(thx_components6(ctx, scratch, img->n, lo, hi, 1, pick_decide, &pr, NULL));
                size_t cnt;
                double sum[3];
                box_scan(img, scratch, lo, hi, &cnt, sum, bx[cc]);
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++)
                        memset(scratch + k * img->n[0] * img->n[1] + j * img->n[0] + lo[0], 0, hi[0] - lo[0]);
                par[cc] = cc;
            }
            for (size_t a = 0; a < ncomp; a++)
                for (size_t b = a + 1; b < ncomp; b++) {
                    int apart = 0;
                    for (int q = 0; q < 3; q++) {
                        long r = q == g.s ? 1 : KR + 1;
                        apart |= bx[a][2 * q] > bx[b][2 * q + 1] + r || bx[b][2 * q] > bx[a][2 * q + 1] + r;
                    }
                    if (!apart) uf_union(par, a, b);
                }
            size_t ng = 0, gid[MAX_SPLIT];
            for (size_t a = 0; a < ncomp; a++) gid[a] = SIZE_MAX;
            for (size_t a = 0; a < ncomp; a++) {
                size_t r = uf_find(par, a);
                if (gid[r] == SIZE_MAX) gid[r] = ng++;
                grp[a] = gid[r];
            }
            trr.n_components = ncomp; /* before grouping, for the report */
            ncomp = ng;
        }
        /* the box the field reads: the tissue's box widened by the buffer's rim (and the smoothing across
           planes) */
        size_t wlo[3], whi[3];
        for (int q = 0; q < 3; q++) {
            size_t r = q == g.s ? (size_t)KR + 1 : (size_t)PAD;
            wlo[q] = lo[q] > r ? lo[q] - r : 0;
            whi[q] = hi[q] + r < img->n[q] ? hi[q] + r : img->n[q];
        }
        if (has_sib) THX_TRY(build_labelset(ctx, o, t, 1, vlo, vhi, &ls));
        thx_trace_tissue_report trr0 = trr;
        for (size_t comp = 0; comp < ncomp; comp++) {
            unsigned char *work = mask;
            trr = trr0;
            snprintf(trr.tissue, sizeof trr.tissue, "%s", ti->name);
            trr.component = comp;
            if (ncomp > 1) {
                work = scratch; /* the group's components only */
                for (size_t k = lo[2]; k < hi[2]; k++)
                    for (size_t j = lo[1]; j < hi[1]; j++) {
                        size_t q = k * img->n[0] * img->n[1] + j * img->n[0];
                        memcpy(work + q + lo[0], mask + q + lo[0], hi[0] - lo[0]);
                    }
                pick_rule pr = {grp, comp};
                THX_TRY(thx_components6(ctx, work, img->n, lo, hi, 1, pick_decide, &pr, NULL));
            }
            box_centroid(img, work, lo, hi, &trr.voxels, trr.centroid_ras, trr.ras_x_range);
            if (has_sib) trr.contact_voxels = mark_siblings(img, work, &ls, wlo, whi, lo, hi);
            /* trace plane by plane (increasing z): the planes are independent, traced in parallel each into
               its own slot (each thread with its own scratch and context), then joined in plane order, so
               the contours are the same bytes whatever the thread count */
            polyset_clear(&tt.loops);
            tt.n_layers = 0;
            for (size_t p = 0; p < np; p++) {
                polyset_clear(&pout[p]);
                pst[p] = THX_OK;
                pcount[3 * p] = pcount[3 * p + 1] = pcount[3 * p + 2] = 0;
            }
            {
                long bad = -1;
                char bad_msg[1024] = "";
    #pragma omp parallel
                {
                    plane_scratch sc;
                    memset(&sc, 0, sizeof sc);
                    thx_ctx *lc = NULL;
                    int ok = thx_ctx_create(&lc) == THX_OK;
    #pragma omp for schedule(dynamic, 1)
                    for (long p = 0; p < (long)np; p++) {
                        double z = zlo + pspace * (double)p;
                        /* continuous image plane index of z */
                        double tk = (z - g.z0) / g.dz;
                        if (tk < 0) tk = 0;
                        if (tk > (double)(g.ns - 1)) tk = (double)(g.ns - 1);
                        if (!resampled) tk = g.dz > 0 ? (double)p : (double)(g.ns - 1 - (size_t)p);
                        thx_status r = ok ? trace_plane(lc, &g, work, pb, tk, resampled, w, o->holes, h, amin, &sc, &pout[p],
                                                        &pcount[3 * p], &pcount[3 * p + 1], &pcount[3 * p + 2], &pprobe[p])
                                          : THX_ENOMEM;
                        pst[p] = r;
                        if (r != THX_OK) {
    #pragma omp critical(thx_trace_err)
                            if (bad < 0 || p < bad) {
                                bad = p;
                                snprintf(bad_msg, sizeof bad_msg, "%s", ok ? thx_ctx_message(lc) : "out of memory");
                            }
                        }
                    }
                    scratch_free(&sc);
                    thx_ctx_destroy(&lc);
                }
                if (bad >= 0) {
                    st = thx_error(ctx, pst[bad], "%s", bad_msg);
                    goto done;
                }
            }
            /* a filled hole that opens: its probe outside every loop of a neighbouring plane */
            for (size_t p = 0; p < np; p++) {
                if (isnan(pprobe[p].x)) continue;
                int open = 0;
                for (int side = -1; side <= 1 && !open; side += 2) {
                    if ((side < 0 && p == 0) || (side > 0 && p + 1 == np)) continue;
                    const polyset *N = &pout[p + (size_t)side];
                    int in = 0;
                    for (size_t l = 0; l < N->n && !in; l++) in = point_in(N->l[l].p, N->l[l].n, pprobe[p]);
                    open = !in;
                }
                if (open && !trr.n_holes_open++) trr.z_hole_open = zlo + pspace * (double)p;
            }
            for (size_t p = 0; p < np; p++) {
                trr.n_holes += pcount[3 * p];
                trr.n_islands_filled += pcount[3 * p + 1];
                trr.n_tiny += pcount[3 * p + 2];
                if (!pout[p].n) continue;
                /* the layer */
                if (tt.n_layers == tt.cap_layers) {
                    size_t ncap = tt.cap_layers ? 2 * tt.cap_layers : 64;
                    layer_rec *nl = thx_realloc(ctx, tt.layers, ncap * sizeof *nl);
                    if (!nl) {
                        st = THX_ENOMEM;
                        goto done;
                    }
                    tt.layers = nl;
                    tt.cap_layers = ncap;
                }
                tt.layers[tt.n_layers].plane = p;
                tt.layers[tt.n_layers].loop0 = tt.loops.n;
                tt.layers[tt.n_layers].n = pout[p].n;
                tt.n_layers++;
                for (size_t l = 0; l < pout[p].n; l++) {
                    poly *d;
                    THX_TRY(polyset_new(ctx, &tt.loops, &d));
                    *d = pout[p].l[l];
                    pout[p].l[l].p = NULL;
                    pout[p].l[l].n = 0;
                }
                pout[p].n = 0;
            }
            /* loops with no partner on either neighbouring plane: dropped (the lacing cannot close them) */
            size_t nl = tt.loops.n;
            if (nl > tt.cap_area) {
                free(tt.area);
                tt.area = thx_malloc(ctx, nl * 5 * sizeof *tt.area);
                if (!tt.area) {
                    st = THX_ENOMEM;
                    goto done;
                }
                tt.cap_area = nl;
            }
            for (size_t l = 0; l < nl; l++) {
                tt.area[5 * l] = poly_area(tt.loops.l[l].p, tt.loops.l[l].n);
                bbox(tt.loops.l[l].p, tt.loops.l[l].n, tt.area + 5 * l + 1);
            }
            unsigned char *keep = thx_malloc(ctx, nl ? nl : 1);
            if (!keep) {
                st = THX_ENOMEM;
                goto done;
            }
            /* to a fixed point: a loop whose only partners are dropped has none */
            for (size_t l = 0; l < nl; l++) keep[l] = 1;
            for (int changed = 1; changed;) {
                changed = 0;
                for (size_t L = 0; L < tt.n_layers; L++) {
                    const layer_rec *lr = &tt.layers[L];
                    for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                        if (!keep[l] || tt.area[5 * l] < 0) continue; /* a kept hole goes with its outer loop */
                        int partner = 0;
                        for (int side = -1; side <= 1 && !partner; side += 2) {
                            if ((side < 0 && L == 0) || (side > 0 && L + 1 == tt.n_layers)) continue;
                            const layer_rec *nb = &tt.layers[L + (size_t)side];
                            if (nb->plane != lr->plane + (size_t)side) continue;
                            for (size_t k = nb->loop0; k < nb->loop0 + nb->n && !partner; k++)
                                partner = keep[k] && tt.area[5 * k] >= 0 && loops_overlap(&tt, l, k);
                        }
                        if (!partner) {
                            keep[l] = 0;
                            changed = 1;
                        }
                    }
                }
            }
            /* a layer of holes only (its outer loops dropped) goes too */
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                int outer_kept = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) outer_kept |= keep[l] && tt.area[5 * l] > 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                    if (!outer_kept) keep[l] = 0;
                    if (!keep[l] && tt.area[5 * l] > 0) trr.n_flat_dropped++;
                }
            }
            /* inside the container's end planes */
            if (container >= 0 && t_first[container] >= 0) {
                for (size_t L = 0; L < tt.n_layers; L++) {
                    const layer_rec *lr = &tt.layers[L];
                    if ((long)lr->plane > t_first[container] && (long)lr->plane < t_last[container]) continue;
                    int had = 0;
                    for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                        had |= keep[l];
                        keep[l] = 0;
                    }
                    trr.n_trimmed_layers += (size_t)had;
                }
            }
            /* one stack of consecutive planes */
            long first = -1, last = -1, gap_at = -1;
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                int any = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) any |= keep[l];
                if (!any) continue;
                if (first < 0) first = (long)lr->plane;
                else if ((long)lr->plane != last + 1 && gap_at < 0) gap_at = last;
                last = (long)lr->plane;
            }
            if ((first < 0 || first == last) && ncomp > 1) {
                /* a component one plane thick (or with no loop partnered): dropped, counted */
                free(keep);
                continue;
            }
            if (first < 0) {
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\": no plane holds a loop with a partner above or below (its %zu voxels lie "
                               "within single planes)", what, ti->name, trr.voxels);
                goto done;
            }
            if (gap_at >= 0) {
                /* the next plane with loops after the gap */
                long resume = -1;
                for (size_t L = 0; L < tt.n_layers && resume < 0; L++)
                    if ((long)tt.layers[L].plane > gap_at + 1) {
                        for (size_t l = tt.layers[L].loop0; l < tt.layers[L].loop0 + tt.layers[L].n; l++)
                            if (keep[l]) resume = (long)tt.layers[L].plane;
                    }
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\" vanishes and reappears along the superior axis: it is in the planes "
                               "z=%g..%g and again from z=%g to z=%g, none between (a surface is one stack of consecutive "
                               "layers: trace the parts as tissues of their own, or remove the stray part with a larger "
                               "--min-size)",
                               what, ti->name, zlo + pspace * (double)first, zlo + pspace * (double)gap_at,
                               zlo + pspace * (double)resume, zlo + pspace * (double)last);
                goto done;
            }
            if (first == last) {
                free(keep);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\" lies in one plane only (z=%g): a surface needs at least two layers (a finer "
                               "--spacing may give it more)", what, ti->name, zlo + pspace * (double)first);
                goto done;
            }
            {
                char tmp[64];
                snprintf(tmp, sizeof tmp, "%s", ti->name);
                if (ncomp > 1) snprintf(tmp, sizeof tmp, "\x01%zu.%zu", t, comp); /* named when sorted */
                st = thx_contours_add_surface(ctx, c, tmp, ti->role, THX_CAP_GRID, 0, &sidx);
                if (st != THX_OK) {
                    free(keep);
                    goto done;
                }
            }
            for (size_t L = 0; L < tt.n_layers; L++) {
                const layer_rec *lr = &tt.layers[L];
                double z = zlo + pspace * (double)lr->plane;
                int any = 0;
                for (size_t l = lr->loop0; l < lr->loop0 + lr->n; l++) {
                    if (!keep[l]) continue;
                    any = 1;
                    st = thx_contours_add_loop(ctx, c, sidx, z, tt.loops.l[l].p, tt.loops.l[l].n);
                    if (st != THX_OK) break;
                    trr.n_loops++;
                    trr.area_sum += tt.area[5 * l];
                }
                if (st != THX_OK) break;
                if (any) {
                    if (!trr.n_layers) trr.z_first = z;
                    trr.z_last = z;
                    trr.n_layers++;
                }
            }
            free(keep);
            if (st != THX_OK) goto done;
            if (t_first[t] < 0 || first < t_first[t]) t_first[t] = first;
            if (last > t_last[t]) t_last[t] = last;
            THX_TRY(sr_push(ctx, &sr, &sr_t, &n_sr, &cap_sr, &trr, t));
            if (work == scratch)
                for (size_t k = wlo[2]; k < whi[2]; k++)
                    for (size_t j = wlo[1]; j < whi[1]; j++)
                        memset(work + k * img->n[0] * img->n[1] + j * img->n[0] + wlo[0], 0, whi[0] - wlo[0]);
        }
        labelset_free(&ls);
        memset(&ls, 0, sizeof ls);
        {
            /* the tissue's surfaces traced: named, and ordered right to left (decreasing centroid RAS x) */
            size_t first_sr = n_sr, kept = 0;
            while (first_sr > 0 && sr_t[first_sr - 1] == t) first_sr--;
            kept = n_sr - first_sr;
            if (!kept) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s: tissue \"%s\": none of its %zu components holds a loop with a partner above or "
                               "below (each lies within single planes)", what, ti->name, ncomp);
                goto done;
            }
            for (size_t i = first_sr; i < n_sr; i++) {
                sr[i].n_components = kept;
                sr[i].components_dropped = ncomp - kept;
            }
        }
    }
    THX_TRY(order_surfaces(ctx, c, o, sr, sr_t, n_sr, what));
    if (rep) {
        free(rep->tissue);
        rep->tissue = sr;
        rep->n_tissues = n_sr;
        sr = NULL;
    }
    *out = c;
    c = NULL;
done:
    labelset_free(&ls);
    for (size_t p = 0; pout && p < np; p++) polyset_free(&pout[p]);
    free(pout);
    free(pst);
    free(pcount);
    free(pprobe);
    free(kcount);
    polyset_free(&tt.loops);
    free(tt.layers);
    free(tt.area);
    free(mask);
    free(pb);
    thx_contours_destroy(&c);
    free(sr);
    free(sr_t);
    free(scratch);
    free(order);
    free(t_first);
    free(t_last);
    if (st != THX_OK && rep) thx_trace_report_free(rep);
    return st;
}
