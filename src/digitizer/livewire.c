/* src/digitizer/livewire.c — the livewire on one plane (thorax/digitizer/livewire.h; Mortensen & Barrett
 * 1995, Falcão et al. 2000's on-the-fly search; docs/design/digitizer.md). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"
#include "thorax/digitizer/livewire.h"

#define NACOS 4096 /* intervals of the acos table */
#define NB (THX_LIVEWIRE_MAX_LINK + 1) /* buckets: every cost in the queue lies within [d, d + MAX_LINK] */

/* The 8 neighbours, counterclockwise from +a; the opposite of k is k ^ 4. */
static const int DA[8] = {1, 1, 0, -1, -1, -1, 0, 1};
static const int DB[8] = {0, 1, 1, 1, 0, -1, -1, -1};

enum { UNSEEN = 0, QUEUED = 1, DONE = 2 };

/* acos on [-1, 1] from a table of the livewire's (NACOS intervals, linear: error below 1e-4 rad, far
 * below one step of the integer scale). */

static inline double acos_fast(const double *acos_t, double x)
{
    double u = (x + 1) * (NACOS / 2.0);
    u = u < 0 ? 0 : u > NACOS ? NACOS : u;
    int i = (int)u;
    return acos_t[i] + (u - i) * (acos_t[i + 1] - acos_t[i]);
}

struct thx_livewire {
    size_t w, h, n;
    double origin[3], du[3], dv[3], su, sv;
    thx_livewire_opts o;
    /* per pixel, what the link costs need (computed once per plane; the links themselves on the fly,
     * when the search expands a pixel: Falcão's live-wire on the fly, so a short path costs little) */
    float *dx, *dy;  /* unit vector across the gradient, (Iy, -Ix) / G; 0 where G = 0 */
    float *fg;       /* 1 - G / max G */
    uint8_t *zc;     /* 1 on a zero crossing of the Laplacian */
    uint8_t *ok;     /* 1 for a finite sample */
    double lxk[8], lyk[8], lenk[8], diag, sz, sg, sd; /* unit links, their lengths; the terms' integer scales */
    double acos_t[NACOS + 2];
    float *g, *gx, *gy; /* gradient of the smoothed plane (sub-voxel step) */
    /* the search */
    int seeded;
    size_t seed;
    int64_t *dist;
    int32_t *parent, *bnext, *bprev;
    uint8_t *state;
    int32_t head[NB];
    int64_t cur;     /* cost of the bucket scanned last */
    size_t queued, done;
    /* path cooling: the last path asked for, and the prefix each query shared with the one before */
    size_t *last, n_last, last_cap;
    size_t shared[THX_LIVEWIRE_COOL_MAX];
    int n_shared;
};

void thx_livewire_opts_default(thx_livewire_opts *o)
{
    o->wz = 0.43;
    o->wg = 0.43;
    o->wd = 0.14;
    o->sigma = 1.0;
    o->subvoxel = 1;
}

void thx_livewire_destroy(thx_livewire **lw)
{
    if (!lw || !*lw) return;
    thx_livewire *L = *lw;
    free(L->dx);
    free(L->dy);
    free(L->fg);
    free(L->zc);
    free(L->ok);
    free(L->g);
    free(L->gx);
    free(L->gy);
    free(L->dist);
    free(L->parent);
    free(L->bnext);
    free(L->bprev);
    free(L->state);
    free(L->last);
    free(L);
    *lw = NULL;
}

static thx_image_slice geometry(const thx_livewire *L)
{
    thx_image_slice s;
    memset(&s, 0, sizeof s);
    s.w = L->w;
    s.h = L->h;
    memcpy(s.origin, L->origin, sizeof s.origin);
    memcpy(s.du, L->du, sizeof s.du);
    memcpy(s.dv, L->dv, sizeof s.dv);
    return s;
}

thx_status thx_livewire_create(thx_ctx *ctx, const thx_image_slice *plane, const thx_livewire_opts *o,
                               thx_livewire **out)
{
    *out = NULL;
    thx_livewire_opts def;
    if (!o) {
        thx_livewire_opts_default(&def);
        o = &def;
    }
    size_t w = plane->w, h = plane->h, n = w * h;
    if (!plane->v || w < 2 || h < 2 || n / w != h || n >= (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "livewire: plane of %zu x %zu samples (2 x 2 up to 2^31 samples)", w, h);
    if (!(o->wz >= 0 && o->wg >= 0 && o->wd >= 0) || !(o->wz + o->wg + o->wd > 0) || !(o->sigma >= 0) ||
        !isfinite(o->wz + o->wg + o->wd + o->sigma))
        return thx_error(ctx, THX_EINPUT, "livewire: weights %g %g %g (>= 0, not all 0) and sigma %g (>= 0)", o->wz,
                         o->wg, o->wd, o->sigma);
    double su = dig_len3(plane->du), sv = dig_len3(plane->dv);
    if (!(su > 0 && sv > 0)) return thx_error(ctx, THX_EINPUT, "livewire: plane with a zero step");
    thx_status st = THX_OK;
    thx_livewire *L = thx_calloc(ctx, 1, sizeof *L);
    float *f = NULL, *lap = NULL;
    uint8_t *zc = NULL;
    if (!L) return THX_ENOMEM;
    L->w = w;
    L->h = h;
    L->n = n;
    L->su = su;
    L->sv = sv;
    L->o = *o;
    memcpy(L->origin, plane->origin, sizeof L->origin);
    memcpy(L->du, plane->du, sizeof L->du);
    memcpy(L->dv, plane->dv, sizeof L->dv);
    size_t nf = 0;
    f = dig_smooth(ctx, plane, o->sigma, &nf);
    L->dx = thx_malloc(ctx, n * sizeof *L->dx);
    L->dy = thx_malloc(ctx, n * sizeof *L->dy);
    L->fg = thx_malloc(ctx, n * sizeof *L->fg);
    L->ok = thx_malloc(ctx, n);
    L->g = thx_malloc(ctx, n * sizeof *L->g);
    L->gx = thx_malloc(ctx, n * sizeof *L->gx);
    L->gy = thx_malloc(ctx, n * sizeof *L->gy);
    lap = thx_malloc(ctx, n * sizeof *lap);
    L->zc = zc = thx_calloc(ctx, n, 1);
    L->dist = thx_malloc(ctx, n * sizeof *L->dist);
    L->parent = thx_malloc(ctx, n * sizeof *L->parent);
    L->bnext = thx_malloc(ctx, n * sizeof *L->bnext);
    L->bprev = thx_malloc(ctx, n * sizeof *L->bprev);
    L->state = thx_calloc(ctx, n, 1);
    if (!f || !L->dx || !L->dy || !L->fg || !L->ok || !L->g || !L->gx || !L->gy || !lap || !zc || !L->dist || !L->parent || !L->bnext ||
        !L->bprev || !L->state) {
        st = THX_ENOMEM;
        goto done;
    }
    if (nf == 0) {
        st = thx_error(ctx, THX_EINPUT, "livewire: the plane has no sample inside the image");
        goto done;
    }
    dig_gradient(f, w, h, su, sv, L->gx, L->gy, L->g);
    /* Laplacian (5 points, per mm^2; borders mirrored) and its zero crossings: the pixel of a sign
     * change with a 4-neighbour that lies nearer zero. */
    for (size_t b = 0; b < h; b++)
        for (size_t a = 0; a < w; a++) {
            size_t p = a + w * b;
            double fa0 = f[a ? p - 1 : p + 1], fa1 = f[a + 1 < w ? p + 1 : p - 1];
            double fb0 = f[b ? p - w : p + w], fb1 = f[b + 1 < h ? p + w : p - w];
            lap[p] = (float)((fa0 + fa1 - 2 * f[p]) / (su * su) + (fb0 + fb1 - 2 * f[p]) / (sv * sv));
        }
    for (size_t b = 0; b < h; b++)
        for (size_t a = 0; a < w; a++) {
            size_t p = a + w * b;
            size_t nb4[4];
            int k4 = 0;
            if (a) nb4[k4++] = p - 1;
            if (a + 1 < w) nb4[k4++] = p + 1;
            if (b) nb4[k4++] = p - w;
            if (b + 1 < h) nb4[k4++] = p + w;
            for (int k = 0; k < k4; k++) {
                double x = lap[p], y = lap[nb4[k]];
                if (((x >= 0) != (y >= 0)) && fabs(x) <= fabs(y)) zc[p] = 1;
            }
        }
    double gmax = 0;
    for (size_t p = 0; p < n; p++)
        if (isfinite(plane->v[p]) && L->g[p] > gmax) gmax = L->g[p];
    const double wsum = o->wz + o->wg + o->wd;
    for (int i = 0; i <= NACOS; i++) L->acos_t[i] = acos(i / (NACOS / 2.0) - 1.0);
    L->acos_t[NACOS + 1] = L->acos_t[NACOS];
    L->diag = sqrt(su * su + sv * sv);
    for (int k = 0; k < 8; k++) {
        L->lenk[k] = sqrt(DA[k] * su * DA[k] * su + DB[k] * sv * DB[k] * sv);
        L->lxk[k] = DA[k] * su / L->lenk[k];
        L->lyk[k] = DB[k] * sv / L->lenk[k];
    }
    L->sz = o->wz / wsum * THX_LIVEWIRE_MAX_LINK;
    L->sg = o->wg / wsum * THX_LIVEWIRE_MAX_LINK;
    L->sd = o->wd / wsum * THX_LIVEWIRE_MAX_LINK * 2.0 / (3.0 * M_PI);
    for (size_t p = 0; p < n; p++) {
        double gp = L->g[p];
        L->dx[p] = gp > 0 ? (float)(L->gy[p] / gp) : 0.0f;
        L->dy[p] = gp > 0 ? (float)(-L->gx[p] / gp) : 0.0f;
        L->fg[p] = (float)(gmax > 0 ? 1.0 - gp / gmax : 1.0);
        L->ok[p] = isfinite(plane->v[p]) ? 1 : 0;
    }
    *out = L;
    L = NULL;
done:
    free(f);
    free(lap);
    thx_livewire_destroy(&L);
    return st;
}

/* The cost of the link from p (at a, b) to its neighbour k; 0 when there is none (the plane's edge, a
 * NaN sample). */
static inline int link_cost(const thx_livewire *L, size_t p, size_t a, size_t b, int k)
{
    long qa = (long)a + DA[k], qb = (long)b + DB[k];
    if (qa < 0 || qb < 0 || qa >= (long)L->w || qb >= (long)L->h) return 0;
    size_t q = (size_t)qa + L->w * (size_t)qb;
    if (!L->ok[p] || !L->ok[q]) return 0;
    double lx = L->lxk[k], ly = L->lyk[k], dp = L->dx[p] * lx + L->dy[p] * ly;
    if (dp < 0) { /* the link taken the way the boundary runs at p */
        lx = -lx;
        ly = -ly;
        dp = -dp;
    }
    double dq = lx * L->dx[q] + ly * L->dy[q];
    double c = L->sz * (L->zc[q] ? 0.0 : 1.0) + L->sg * L->fg[q] * L->lenk[k] / L->diag +
               L->sd * (acos_fast(L->acos_t, dp) + acos_fast(L->acos_t, dq));
    long ic = (long)(c + 0.5);
    return ic < 1 ? 1 : ic > THX_LIVEWIRE_MAX_LINK ? THX_LIVEWIRE_MAX_LINK : (int)ic;
}

long thx_livewire_link_cost(const thx_livewire *L, size_t p, size_t q)
{
    if (p >= L->n || q >= L->n) return -1;
    long pa = (long)(p % L->w), pb = (long)(p / L->w), qa = (long)(q % L->w), qb = (long)(q / L->w);
    for (int k = 0; k < 8; k++)
        if (pa + DA[k] == qa && pb + DB[k] == qb) {
            int c = link_cost(L, p, (size_t)pa, (size_t)pb, k);
            return c ? c : -1;
        }
    return -1;
}

void thx_livewire_size(const thx_livewire *L, size_t *w, size_t *h, size_t *n_done)
{
    if (w) *w = L->w;
    if (h) *h = L->h;
    if (n_done) *n_done = L->done;
}

/* ---- Dial's queue: bucket d % NB holds the queued pixels of cost d ---- */
static void q_insert(thx_livewire *L, size_t p, int64_t d)
{
    int32_t b = (int32_t)(d % NB);
    L->dist[p] = d;
    L->bprev[p] = -1;
    L->bnext[p] = L->head[b];
    if (L->head[b] >= 0) L->bprev[L->head[b]] = (int32_t)p;
    L->head[b] = (int32_t)p;
    L->queued++;
}

static void q_remove(thx_livewire *L, size_t p)
{
    int32_t b = (int32_t)(L->dist[p] % NB);
    if (L->bprev[p] >= 0) L->bnext[L->bprev[p]] = L->bnext[p];
    else L->head[b] = L->bnext[p];
    if (L->bnext[p] >= 0) L->bprev[L->bnext[p]] = L->bprev[p];
    L->queued--;
}

/* Pops the cheapest queued pixel (the first of the lowest non-empty bucket from cur on); -1 if none. */
static long q_pop(thx_livewire *L)
{
    if (!L->queued) return -1;
    for (;;) {
        int32_t b = (int32_t)(L->cur % NB);
        if (L->head[b] >= 0) {
            size_t p = (size_t)L->head[b];
            q_remove(L, p);
            return (long)p;
        }
        L->cur++;
    }
}

static thx_status seed_at(thx_ctx *ctx, thx_livewire *L, size_t a, size_t b)
{
    if (a >= L->w || b >= L->h)
        return thx_error(ctx, THX_EINPUT, "livewire: seed pixel (%zu, %zu) outside the plane (%zu x %zu)", a, b, L->w,
                         L->h);
    size_t p = a + L->w * b;
    if (!L->ok[p]) return thx_error(ctx, THX_EINPUT, "livewire: seed pixel (%zu, %zu) lies outside the image", a, b);
    memset(L->state, UNSEEN, L->n);
    for (int i = 0; i < NB; i++) L->head[i] = -1;
    L->queued = L->done = 0;
    L->n_last = 0;
    L->n_shared = 0;
    L->cur = 0;
    L->seed = p;
    L->seeded = 1;
    L->parent[p] = -1;
    L->state[p] = QUEUED;
    q_insert(L, p, 0);
    return THX_OK;
}

thx_status thx_livewire_seed_pixel(thx_ctx *ctx, thx_livewire *L, size_t a, size_t b) { return seed_at(ctx, L, a, b); }

static int nearest_pixel(const thx_livewire *L, const double ras[3], size_t *a, size_t *b)
{
    thx_image_slice s = geometry(L);
    double fa, fb;
    dig_ras_to_px(&s, ras, &fa, &fb);
    fa = floor(fa + 0.5);
    fb = floor(fb + 0.5);
    if (!(fa >= 0 && fb >= 0 && fa < (double)L->w && fb < (double)L->h)) return -1;
    *a = (size_t)fa;
    *b = (size_t)fb;
    return 0;
}

thx_status thx_livewire_seed(thx_ctx *ctx, thx_livewire *L, const double ras[3])
{
    size_t a, b;
    if (nearest_pixel(L, ras, &a, &b))
        return thx_error(ctx, THX_EINPUT, "livewire: seed (%g, %g, %g) mm lies outside the plane", ras[0], ras[1],
                         ras[2]);
    return seed_at(ctx, L, a, b);
}

/* Expands the search until pixel t is final (on the fly: the queue is kept between calls). 0, or -1
 * when the queue empties first (t unreachable). */
static int expand_to(thx_livewire *L, size_t t)
{
    while (L->state[t] != DONE) {
        long pl = q_pop(L);
        if (pl < 0) return -1;
        size_t p = (size_t)pl;
        L->state[p] = DONE;
        L->done++;
        size_t a = p % L->w, b = p / L->w;
        for (int k = 0; k < 8; k++) {
            long qa = (long)a + DA[k], qb = (long)b + DB[k];
            if (qa < 0 || qb < 0 || qa >= (long)L->w || qb >= (long)L->h) continue;
            size_t q = (size_t)qa + L->w * (size_t)qb;
            if (L->state[q] == DONE || !L->ok[q]) continue;
            int64_t d = L->dist[p] + link_cost(L, p, a, b, k);
            if (L->state[q] == QUEUED) {
                if (d >= L->dist[q]) continue;
                q_remove(L, q);
            }
            L->state[q] = QUEUED;
            L->parent[q] = (int32_t)p;
            q_insert(L, q, d);
        }
    }
    return 0;
}

thx_status thx_livewire_path_pixels(thx_ctx *ctx, thx_livewire *L, size_t a, size_t b, size_t **idx, size_t *n,
                                    long *cost)
{
    *idx = NULL;
    *n = 0;
    if (!L->seeded) return thx_error(ctx, THX_EINPUT, "livewire: a path asked for before a seed was set");
    if (a >= L->w || b >= L->h)
        return thx_error(ctx, THX_EINPUT, "livewire: target pixel (%zu, %zu) outside the plane (%zu x %zu)", a, b,
                         L->w, L->h);
    size_t t = a + L->w * b;
    if (expand_to(L, t))
        return thx_error(ctx, THX_EINPUT, "livewire: target pixel (%zu, %zu) cannot be reached from the seed", a, b);
    size_t m = 1;
    for (size_t p = t; L->parent[p] >= 0; p = (size_t)L->parent[p]) m++;
    size_t *out = thx_malloc(ctx, m * sizeof *out);
    if (!out) return THX_ENOMEM;
    size_t i = m;
    for (size_t p = t;; p = (size_t)L->parent[p]) {
        out[--i] = p;
        if (L->parent[p] < 0) break;
    }
    /* for path cooling: the prefix shared with the previous path, then this path kept */
    size_t c = 0;
    while (c < m && c < L->n_last && L->last[c] == out[c]) c++;
    if (L->n_last) {
        if (L->n_shared == THX_LIVEWIRE_COOL_MAX) {
            memmove(L->shared, L->shared + 1, (THX_LIVEWIRE_COOL_MAX - 1) * sizeof *L->shared);
            L->n_shared--;
        }
        L->shared[L->n_shared++] = c;
    }
    if (thx_grow(ctx, (void **)&L->last, &L->last_cap, m, sizeof *L->last) != THX_OK) {
        free(out);
        return THX_ENOMEM;
    }
    memcpy(L->last, out, m * sizeof *out);
    L->n_last = m;
    *idx = out;
    *n = m;
    if (cost) *cost = (long)L->dist[t];
    return THX_OK;
}

/* Pixel path -> RAS points (moved onto the edge with subvoxel). */
static thx_status to_ras(thx_ctx *ctx, const thx_livewire *L, const size_t *idx, size_t m, double **xyz)
{
    double *o = thx_malloc(ctx, 3 * m * sizeof *o);
    if (!o) return THX_ENOMEM;
    thx_image_slice s = geometry(L);
    for (size_t i = 0; i < m; i++) {
        double a = (double)(idx[i] % L->w), b = (double)(idx[i] / L->w);
        if (L->o.subvoxel) dig_edge_refine(L->g, L->gx, L->gy, L->w, L->h, L->su, L->sv, 1.0, &a, &b);
        dig_px_to_ras(&s, a, b, o + 3 * i);
    }
    *xyz = o;
    return THX_OK;
}

thx_status thx_livewire_path(thx_ctx *ctx, thx_livewire *L, const double to[3], double **xyz, size_t *n)
{
    *xyz = NULL;
    *n = 0;
    size_t a, b, *idx = NULL, m = 0;
    if (nearest_pixel(L, to, &a, &b))
        return thx_error(ctx, THX_EINPUT, "livewire: target (%g, %g, %g) mm lies outside the plane", to[0], to[1],
                         to[2]);
    THX_CHECK(thx_livewire_path_pixels(ctx, L, a, b, &idx, &m, NULL));
    thx_status st = to_ras(ctx, L, idx, m, xyz);
    free(idx);
    if (st == THX_OK) *n = m;
    return st;
}

thx_status thx_livewire_loop(thx_ctx *ctx, thx_livewire *L, const double *clicked, size_t m, double **xyz,
                             size_t *n)
{
    *xyz = NULL;
    *n = 0;
    if (m < 2) return thx_error(ctx, THX_EINPUT, "livewire: a loop needs 2 points or more (%zu given)", m);
    size_t *all = NULL, cap = 0, na = 0;
    thx_status st = THX_OK;
    for (size_t i = 0; i < m; i++) {
        size_t a, b, *idx = NULL, k = 0;
        const double *p = clicked + 3 * i, *q = clicked + 3 * ((i + 1) % m);
        if ((st = thx_livewire_seed(ctx, L, p)) != THX_OK) goto done;
        if (nearest_pixel(L, q, &a, &b)) {
            st = thx_error(ctx, THX_EINPUT, "livewire: point %zu (%g, %g, %g) mm lies outside the plane", (i + 1) % m + 1,
                           q[0], q[1], q[2]);
            goto done;
        }
        if ((st = thx_livewire_path_pixels(ctx, L, a, b, &idx, &k, NULL)) != THX_OK) goto done;
        /* each segment without its last pixel (the next segment's first; the first's for the last) */
        if ((st = thx_grow(ctx, (void **)&all, &cap, na + k, sizeof *all)) != THX_OK) {
            free(idx);
            goto done;
        }
        for (size_t j = 0; j + 1 < k; j++) all[na++] = idx[j];
        free(idx);
    }
    if (na < 3) {
        st = thx_error(ctx, THX_EGEOM, "livewire: the loop through %zu points has %zu pixels", m, na);
        goto done;
    }
    if ((st = to_ras(ctx, L, all, na, xyz)) == THX_OK) *n = na;
done:
    free(all);
    return st;
}

thx_status thx_livewire_cool(thx_ctx *ctx, thx_livewire *L, int k, size_t min_pixels, double **xyz, size_t *n)
{
    *xyz = NULL;
    *n = 0;
    if (k < 1 || k > THX_LIVEWIRE_COOL_MAX)
        return thx_error(ctx, THX_EINPUT, "livewire: cooling over %d paths (1..%d)", k, THX_LIVEWIRE_COOL_MAX);
    if (!L->seeded || L->n_shared < k) return THX_OK;
    size_t m = L->n_last;
    for (int i = L->n_shared - k; i < L->n_shared; i++)
        if (L->shared[i] < m) m = L->shared[i];
    if (m < 2 || m < min_pixels) return THX_OK;
    size_t *frozen = thx_malloc(ctx, m * sizeof *frozen);
    if (!frozen) return THX_ENOMEM;
    memcpy(frozen, L->last, m * sizeof *frozen);
    size_t end = frozen[m - 1];
    thx_status st = to_ras(ctx, L, frozen, m, xyz);
    if (st == THX_OK) st = seed_at(ctx, L, end % L->w, end / L->w);
    free(frozen);
    if (st != THX_OK) {
        free(*xyz);
        *xyz = NULL;
        return st;
    }
    *n = m;
    return THX_OK;
}
