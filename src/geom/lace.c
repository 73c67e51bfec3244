/*
 * Lacing adjacent layers into triangles (paper 3.2, "Lacing triangles").
 *
 * Moves and states. Lacing chain A (lower) with chain B (upper) is a walk from
 * the first connective segment (A_i0, B_j0) around both chains: each move makes
 * one triangle and advances one chain by one node,
 *     A-move at (i, j): triangle (A_i, A_i+1, B_j), new segment (A_i+1, B_j)
 *     B-move at (i, j): triangle (A_i, B_j+1, B_j), new segment (A_i, B_j+1)
 * so a complete lacing is na A-moves and nb B-moves in some order (na + nb
 * triangles). With both chains counterclockwise seen from above and A below B
 * these triangles are counterclockwise seen from outside; the orientation pass
 * (build.c) re-decides every triangle by the inside test anyway.
 *
 * The steps:
 *  1. Shortest-diagonal rule (paper steps 3-5) on the chains mapped to a common
 *     centroid and RMS radius: in those coordinates layers of very different size
 *     or offset (paper figure 2A) look alike, so one node is not fanned into
 *     many triangles.
 *  2. Outside test (figure 2B). A triangle is outside the surface when its
 *     centroid c, at height fraction t between the layers, has
 *         (1 - t) dA(c) + t dB(c) > concave_tol * (spacing + |dA(c) - dB(c)|),
 *     where dA, dB are the signed distances (positive outside) from the
 *     projection of c to the curves of layers A and B (the tolerance grows with
 *     the layers' disagreement, the uncertainty of the interpolation; in a
 *     concave bay both distances are alike and large). This is the paper's test
 *     "projected centroid outside either layer's curve" made consistent for
 *     layers of different size: the literal rule rejects every triangle of a
 *     tapering surface (a cone), because there the centroid always lies outside
 *     the smaller curve; interpolating the signed distance to the triangle's
 *     height gives the paper's rule where the layers coincide and zero false
 *     alarms on tapers (docs/decisions.md).
 *  3. Each run of outside triangles (a gap) is re-laced by dynamic programming
 *     over the states in a window around it: the valid path of least total
 *     diagonal length (triangles too large are penalized). The window grows
 *     until a valid path exists.
 *  4. If none exists, one layer has a concave pocket the other layer does not
 *     have (the pocket closes between the layers). The pocket (a bay between two
 *     consecutive convex-hull vertices of its chain) is cut off with triangles in
 *     the plane of its layer, the chain is shortened to the pocket's chord, and
 *     the slice is laced again.
 *  0. (Before 1, when asked: thx_lace for a fan over 3 fan_limit, thx_surfaces_build's last retry
 *     of a lacing that crosses.) A pocket of one chain that the other layer fills (a CT skull's
 *     loop around the cranial cavity through the frontal sinus's notch, against the full loop of
 *     the next plane: issue 25) is cut as in step 4 first; no outside triangle reveals it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/cdt.h"
#include "thorax/core/core.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include "thorax/geom/surfaces.h"
#include "geom/chain_sdf.h"

#define BIG 1e9       /* cost of a triangle outside the surface */
#define LARGE 1e4     /* cost of a triangle with an edge that is too long */
#define OUTSIDE_MEMO_MAX ((size_t)64 << 20) /* bytes of remembered outside tests per slice */

void thx_lace_opts_default(thx_lace_opts *o)
{
    o->spacing = 5.0;
    o->concave_tol = 0.25;
    o->max_edge = 3.0;
    o->window = 4;
    o->fan_limit = 6;
    o->projected_aspect = 10;
    o->phase_weight = 0.25;
    o->cut_filled_pockets = 0;
    o->raw_positions = 0;
    o->whole_dp = 0;
    o->cut_tongue_runs = 0;
    o->nodes = NULL;
}

typedef struct {
    const thx_chain *a, *b;
    const thx_lace_opts *o;
    thx_vec2 *na, *nb;  /* normalized coordinates */
    thx_vec2 *pa, *pb;  /* arc-length phase of each node, as a point on a circle of radius phase_weight */
    chain_index ia, ib; /* signed distances to the chains */
    int i0, j0;         /* first connective segment */
    double big_edge;    /* "too large" edge length */
    unsigned char *outside; /* NULL, or per (node of A, node of B, move): 0 not known yet, 1 inside, 2 outside
                               (the dynamic programming's outside tests, each made once: issue 25) */
    struct sdf_grid *grid;  /* NULL, or the signed distances on a grid (sdf_grid) */
} lacer;

/* The signed distances to both chains at the nodes of a grid over the slice, each computed when first
 * needed. A signed distance is 1-Lipschitz, so at a point e from the nearest node it is that node's
 * value within e; the outside test is decided from the node's values where that bound leaves no doubt
 * (the answer the exact test gives), and made exactly otherwise. The dome's slices of the bench map's
 * right lung ran their gaps' dynamic programme over every pair of up to 688 x 748 nodes at each of
 * several levels of cuts, each state's test two exact distances (issue 25, item 6). */
typedef struct sdf_grid {
    double x0, y0, h;
    int nx, ny;
    double *v;            /* per node: to A, to B */
    unsigned char *known; /* per node: v computed */
} sdf_grid;

#define SDF_GRID_NODES_MAX ((size_t)1 << 20)

/* The grid for L's chains at the node spacing (finer grids computed more nodes than they saved: 0.25,
 * 0.5, 1 and 2 spacings took 1.7, 1.1, 0.93 and 1.0 s on the dome's slowest slice), or NULL when the
 * spacing is unknown, the grid would be too large or memory is short: the tests are then all exact. */
static sdf_grid *sdf_grid_new(const lacer *L)
{
    double h = L->o->spacing, lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    if (!(h > 0)) return NULL;
    for (int c = 0; c < 2; c++) {
        const thx_chain *ch = c ? L->b : L->a;
        for (size_t k = 0; k < ch->n; k++) {
            lo[0] = fmin(lo[0], ch->p[k].x), hi[0] = fmax(hi[0], ch->p[k].x);
            lo[1] = fmin(lo[1], ch->p[k].y), hi[1] = fmax(hi[1], ch->p[k].y);
        }
    }
    double nxd = ceil((hi[0] - lo[0]) / h) + 3, nyd = ceil((hi[1] - lo[1]) / h) + 3;
    if (!(nxd * nyd <= (double)SDF_GRID_NODES_MAX)) return NULL;
    sdf_grid *g = malloc(sizeof *g);
    if (!g) return NULL;
    g->x0 = lo[0] - h, g->y0 = lo[1] - h, g->h = h, g->nx = (int)nxd, g->ny = (int)nyd;
    g->v = malloc((size_t)g->nx * (size_t)g->ny * 2 * sizeof *g->v);
    g->known = calloc((size_t)g->nx * (size_t)g->ny, 1);
    if (!g->v || !g->known) { free(g->v); free(g->known); free(g); return NULL; }
    return g;
}

static void sdf_grid_free(sdf_grid *g)
{
    if (!g) return;
    free(g->v);
    free(g->known);
    free(g);
}

/* The three 3D points of the triangle of a move from state (ca, cb). */
static void move_tri(const lacer *L, int ca, int cb, int bmove, thx_vec3 t[3], int32_t id[3])
{
    const thx_chain *A = L->a, *B = L->b;
    int na = (int)A->n, nb = (int)B->n;
    int i = (L->i0 + ca) % na, j = (L->j0 + cb) % nb;
    int i1 = (i + 1) % na, j1 = (j + 1) % nb;
    if (!bmove) {
        t[0] = thx_v3(A->p[i].x, A->p[i].y, A->z);
        t[1] = thx_v3(A->p[i1].x, A->p[i1].y, A->z);
        t[2] = thx_v3(B->p[j].x, B->p[j].y, B->z);
        id[0] = A->id[i]; id[1] = A->id[i1]; id[2] = B->id[j];
    } else {
        t[0] = thx_v3(A->p[i].x, A->p[i].y, A->z);
        t[1] = thx_v3(B->p[j1].x, B->p[j1].y, B->z);
        t[2] = thx_v3(B->p[j].x, B->p[j].y, B->z);
        id[0] = A->id[i]; id[1] = B->id[j1]; id[2] = B->id[j];
    }
}

/* 1 if the triangle lies outside the surface (step 2 of the file comment). */
static int tri_outside(const lacer *L, const thx_vec3 t[3])
{
    thx_vec2 c = {(t[0].x + t[1].x + t[2].x) / 3.0, (t[0].y + t[1].y + t[2].y) / 3.0};
    double zc = (t[0].z + t[1].z + t[2].z) / 3.0;
    double dz = L->b->z - L->a->z;
    double f = dz != 0 ? (zc - L->a->z) / dz : 0.5;
    double tol = L->o->concave_tol, sp = L->o->spacing;
    sdf_grid *g = L->grid;
    if (g) { /* decided from the nearest grid node where the bound allows (sdf_grid) */
        long gx = lround((c.x - g->x0) / g->h), gy = lround((c.y - g->y0) / g->h);
        if (gx >= 0 && gy >= 0 && gx < g->nx && gy < g->ny) {
            size_t k = (size_t)gy * (size_t)g->nx + (size_t)gx;
            thx_vec2 p = {g->x0 + (double)gx * g->h, g->y0 + (double)gy * g->h};
            if (!g->known[k]) {
                g->v[2 * k] = chain_index_sdf(&L->ia, p);
                g->v[2 * k + 1] = chain_index_sdf(&L->ib, p);
                g->known[k] = 1;
            }
            double va = g->v[2 * k], vb = g->v[2 * k + 1];
            double ex = c.x - p.x, ey = c.y - p.y;
            double e = sqrt(ex * ex + ey * ey) + 1e-9 * (1 + fabs(va) + fabs(vb)); /* (and the rounding) */
            double w = fabs(1 - f) + fabs(f), dg = (1 - f) * va + f * vb, gap = fabs(va - vb);
            if (dg - w * e > tol * (sp + gap + 2 * e)) return 1;
            if (dg + w * e <= tol * (sp + fmax(0.0, gap - 2 * e))) return 0;
        }
    }
    double da = chain_index_sdf(&L->ia, c), db = chain_index_sdf(&L->ib, c);
    double d = (1 - f) * da + f * db;
    /* Linear interpolation of the signed distance is uncertain by about the layers' disagreement
       |da - db| (a flat, strongly offset slice); a concave bay has da ~ db > 0. */
    return d > tol * (sp + fabs(da - db));
}

static double dist3(thx_vec3 a, thx_vec3 b) { return thx_v3_norm(thx_v3_sub(a, b)); }
static inline double dist3_sq(thx_vec3 a, thx_vec3 b)
{
    double x = a.x - b.x, y = a.y - b.y, z = a.z - b.z;
    return x * x + y * y + z * z;
}

/* Distance between node i of A and node j of B in the lacing metric: normalized
 * position and arc-length phase (see thx_lace_opts.phase_weight). */
static double ndist(const lacer *L, int i, int j)
{
    double dx = L->na[i].x - L->nb[j].x, dy = L->na[i].y - L->nb[j].y;
    double px = L->pa[i].x - L->pb[j].x, py = L->pa[i].y - L->pb[j].y;
    return sqrt(dx * dx + dy * dy + px * px + py * py);
}

/* Cost of a move: the length of its new diagonal, plus penalties. */
static double move_cost(const lacer *L, int ca, int cb, int bmove, int check)
{
    thx_vec3 t[3];
    int32_t id[3];
    move_tri(L, ca, cb, bmove, t, id);
    /* the new diagonal, measured like the shortest-diagonal rule: in normalized coordinates */
    int na = (int)L->a->n, nb = (int)L->b->n;
    int i = (L->i0 + ca) % na, j = (L->j0 + cb) % nb;
    double c = bmove ? ndist(L, i, (j + 1) % nb) : ndist(L, (i + 1) % na, j);
    double e2 = fmax(dist3_sq(t[0], t[1]), fmax(dist3_sq(t[1], t[2]), dist3_sq(t[2], t[0])));
    if (e2 > L->big_edge * L->big_edge) c += LARGE;
    if (check) {
        unsigned char *m = L->outside ? &L->outside[((size_t)i * (size_t)nb + (size_t)j) * 2 + (size_t)bmove] : NULL;
        int out = m && *m ? *m == 2 : tri_outside(L, t);
        if (m) *m = (unsigned char)(1 + out);
        if (out) c += BIG;
    }
    return c;
}

/* Arc-length phase of each node (fraction of the perimeter from node 0) as a point on a circle. */
static void phases(const thx_chain *c, double w, thx_vec2 *out)
{
    double total = 0, s = 0;
    for (size_t k = 0; k < c->n; k++) total += hypot(c->p[(k + 1) % c->n].x - c->p[k].x, c->p[(k + 1) % c->n].y - c->p[k].y);
    for (size_t k = 0; k < c->n; k++) {
        double a = total > 0 ? 2 * M_PI * s / total : 0;
        out[k].x = w * cos(a);
        out[k].y = w * sin(a);
        s += hypot(c->p[(k + 1) % c->n].x - c->p[k].x, c->p[(k + 1) % c->n].y - c->p[k].y);
    }
}

static void normalize(const thx_chain *c, thx_vec2 *out)
{
    double cx = 0, cy = 0, r = 0;
    for (size_t k = 0; k < c->n; k++) { cx += c->p[k].x; cy += c->p[k].y; }
    cx /= (double)c->n;
    cy /= (double)c->n;
    for (size_t k = 0; k < c->n; k++) r += (c->p[k].x - cx) * (c->p[k].x - cx) + (c->p[k].y - cy) * (c->p[k].y - cy);
    r = sqrt(r / (double)c->n);
    if (!(r > 0)) r = 1;
    for (size_t k = 0; k < c->n; k++) { out[k].x = (c->p[k].x - cx) / r; out[k].y = (c->p[k].y - cy) / r; }
}

/* DP over states [ca0..ca1] x [cb0..cb1]; writes the best path's moves (0 = A, 1 = B) to mv.
 * Returns the path's cost. */
static double dp_path(const lacer *L, int ca0, int cb0, int ca1, int cb1, unsigned char *mv, double *cost_buf,
                      unsigned char *from_buf, int check)
{
    int W = ca1 - ca0 + 1, H = cb1 - cb0 + 1;
    for (int x = 0; x < W; x++)
        for (int y = 0; y < H; y++) {
            double best = x == 0 && y == 0 ? 0 : INFINITY;
            unsigned char from = 0;
            if (x > 0) {
                double c = cost_buf[(x - 1) * H + y] + move_cost(L, ca0 + x - 1, cb0 + y, 0, check);
                if (c < best) { best = c; from = 0; }
            }
            if (y > 0) {
                double c = cost_buf[x * H + y - 1] + move_cost(L, ca0 + x, cb0 + y - 1, 1, check);
                if (c < best) { best = c; from = 1; }
            }
            cost_buf[x * H + y] = best;
            from_buf[x * H + y] = from;
        }
    int x = W - 1, y = H - 1, k = W - 1 + H - 1;
    while (x > 0 || y > 0) {
        unsigned char f = from_buf[x * H + y];
        mv[--k] = f;
        if (f) y--; else x--;
    }
    return cost_buf[W * H - 1];
}

/* Greedy shortest-diagonal path in normalized coordinates. */
static void greedy_path(const lacer *L, unsigned char *mv)
{
    int na = (int)L->a->n, nb = (int)L->b->n, ca = 0, cb = 0;
    for (int k = 0; k < na + nb; k++) {
        int b;
        if (ca == na) b = 1;
        else if (cb == nb) b = 0;
        else {
            int i = (L->i0 + ca) % na, j = (L->j0 + cb) % nb;
            double dA = ndist(L, (i + 1) % na, j), dB = ndist(L, i, (j + 1) % nb);
            b = dB < dA;
        }
        mv[k] = (unsigned char)b;
        if (b) cb++; else ca++;
    }
}

/* Pocket of a chain: indices lo..hi (cyclic, hi after lo) between two consecutive
 * convex-hull vertices with at least one chain node between them. */
typedef struct { int lo, hi; } pocket;

typedef struct { double x, y; int i; } sort_pt;
static int cmp_sort_pt(const void *x, const void *y)
{
    const sort_pt *p = x, *q = y;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    if (p->y != q->y) return p->y < q->y ? -1 : 1;
    return p->i - q->i;
}

static double cross3(thx_vec2 o, thx_vec2 a, thx_vec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* Convex hull vertex flags (Andrew's monotone chain; collinear points excluded). */
static int hull_flags(thx_ctx *ctx, const thx_chain *c, unsigned char *on_hull)
{
    int n = (int)c->n;
    if (n <= 0) return -1;
    sort_pt *sp = malloc((size_t)n * sizeof *sp);
    int *idx = malloc((size_t)n * sizeof *idx), *h = malloc((size_t)(2 * n + 2) * sizeof *h);
    if (!sp || !idx || !h) { free(sp); free(idx); free(h); return -1; }
    for (int k = 0; k < n; k++) { sp[k].x = c->p[k].x; sp[k].y = c->p[k].y; sp[k].i = k; }
    qsort(sp, (size_t)n, sizeof *sp, cmp_sort_pt);
    for (int k = 0; k < n; k++) idx[k] = sp[k].i;
    free(sp);
    int m = 0;
    for (int k = 0; k < n; k++) {
        while (m >= 2 && cross3(c->p[h[m - 2]], c->p[h[m - 1]], c->p[idx[k]]) <= 0) m--;
        h[m++] = idx[k];
    }
    for (int k = n - 2, lo = m + 1; k >= 0; k--) {
        while (m >= lo && cross3(c->p[h[m - 2]], c->p[h[m - 1]], c->p[idx[k]]) <= 0) m--;
        h[m++] = idx[k];
    }
    memset(on_hull, 0, (size_t)n);
    for (int k = 0; k < m; k++) on_hull[h[k]] = 1;
    free(idx);
    free(h);
    (void)ctx;
    return 0;
}

/* The node of the arc c[lo+1 .. lo+len-1] farthest from the chord c[lo]-c[lo+len] (cyclic
 * indices); its distance in *depth. -1 if the arc has no inner node. */
static int deepest_node(const thx_chain *c, int lo, int len, double *depth)
{
    int n = (int)c->n, deep = -1;
    thx_vec2 a = c->p[lo], b = c->p[(lo + len) % n];
    double chord = fmax(hypot(b.x - a.x, b.y - a.y), 1e-300);
    *depth = -1;
    for (int s = 1; s < len; s++) {
        thx_vec2 q = c->p[(lo + s) % n];
        double d = fabs(cross3(a, b, q)) / chord;
        if (d > *depth) { *depth = d; deep = (lo + s) % n; }
    }
    return deep;
}

/* Is the deep part of a pocket (deepest node q, chord a-b) inside any of the chains? */
static int pocket_covered(const thx_chain *chains, size_t n_chains, thx_vec2 a, thx_vec2 b, thx_vec2 q, double margin)
{
    thx_vec2 mid = {0.5 * (a.x + b.x), 0.5 * (a.y + b.y)};
    thx_vec2 probe = {0.5 * (q.x + mid.x), 0.5 * (q.y + mid.y)};
    int inside = 0;
    for (size_t k = 0; k < n_chains && !inside; k++) {
        chain_index io;
        if (chain_index_init(&io, chains[k].p, chains[k].n) != 0) continue;
        inside = chain_index_sdf(&io, probe) < -margin * 0.5 || chain_index_sdf(&io, q) < 0;
        chain_index_free(&io);
    }
    return inside;
}

/* Finds a pocket of chain `c` that overlaps the chain range [r0, r1] (cyclic) and
 * that the surface closes in this slice: its deep part lies inside the other
 * chain `o`, and (unless c is the slice's lower chain) not inside the layer
 * beyond c, so that a dent of one layer is cut by exactly one slice. */
static int find_pocket(thx_ctx *ctx, const thx_chain *c, const thx_chain *o, int c_is_lower, int r0, int r1,
                       double margin, pocket *pk)
{
    int n = (int)c->n;
    unsigned char *on = malloc((size_t)n);
    if (!on || hull_flags(ctx, c, on) != 0) { free(on); return 0; }
    int found = 0, first = -1;
    for (int k = 0; k < n; k++) if (on[k]) { first = k; break; }
    if (first < 0) { free(on); return 0; }
    int k = first;
    do {
        int nx = (k + 1) % n;
        while (!on[nx]) nx = (nx + 1) % n;
        int len = (nx - k + n) % n;
        if (len > 1) {
            /* overlap with [r0, r1]? (cyclic ranges) */
            int overlap = 0;
            for (int s = 0; s <= len && !overlap; s++) {
                int q = (k + s) % n;
                int off = (q - r0 + n) % n, rl = (r1 - r0 + n) % n;
                if (off <= rl) overlap = 1;
            }
            if (overlap) {
                thx_vec2 a = c->p[k], b = c->p[nx];
                double best;
                int deep = deepest_node(c, k, len, &best);
                if (deep >= 0 && best > margin && pocket_covered(o, 1, a, b, c->p[deep], margin) &&
                    (c_is_lower || !pocket_covered(c->beyond, c->n_beyond, a, b, c->p[deep], margin))) {
                    pk->lo = k;
                    pk->hi = nx;
                    found = 1;
                    break;
                }
            }
        }
        k = nx;
    } while (k != first);
    free(on);
    return found;
}

/* Do at least 90% of the inner nodes of the arc c[lo .. lo+len] (cyclic) lie inside one of the
 * n_ix curves ix by more than margin? */
static int arc_filled(const thx_chain *c, int lo, int len, const chain_index *ix, size_t n_ix, double margin)
{
    int n = (int)c->n, in = 0;
    if (n_ix == 0 || len < 2) return 0;
    for (int q = 1; q < len; q++) {
        int inside = 0;
        for (size_t r = 0; r < n_ix && !inside; r++) inside = chain_index_sdf(&ix[r], c->p[(lo + q) % n]) < -margin;
        in += inside;
    }
    return in >= 0.9 * (len - 1);
}

/* Does the chord c[lo]-c[hi] cross (or touch) an edge of c other than those at its ends? */
static int chord_crosses(const thx_chain *c, int lo, int hi)
{
    int n = (int)c->n;
    for (int k = 0; k < n; k++) {
        int k1 = (k + 1) % n;
        if (k == lo || k1 == lo || k == hi || k1 == hi) continue;
        if (thx_segments_touch(&c->p[lo].x, &c->p[hi].x, &c->p[k].x, &c->p[k1].x)) return 1;
    }
    return 0;
}

/* Twice the signed area of the polygon of the arc c[lo .. lo+len] (cyclic) closed by its chord
 * (positive: counterclockwise, a tongue of a counterclockwise chain; negative: a dent). */
static double arc_area2(const thx_chain *c, int lo, int len)
{
    int n = (int)c->n, hi = (lo + len) % n;
    double area = 0;
    for (int s = 0; s < len; s++) {
        thx_vec2 p = c->p[(lo + s) % n], q = c->p[(lo + s + 1) % n];
        area += p.x * q.y - q.x * p.y;
    }
    return area + c->p[hi].x * c->p[lo].y - c->p[lo].x * c->p[hi].y;
}

/* The runs of c's nodes deeper than margin on one side of the other layer's curve io (side -1:
 * inside it, +1: outside), each as the arc c[q .. q+len] (cyclic) from the node before the run to
 * the node after it: for each, fn(c, q, len, user). */
static void deep_runs(const thx_chain *c, const chain_index *io, int side, double margin,
                      void (*fn)(const thx_chain *c, int q, int len, void *user), void *user)
{
    int n = (int)c->n, start = -1;
    unsigned char *deep = malloc((size_t)n);
    if (!deep) return; /* no run found: the lacing goes on without the cut */
    for (int k = 0; k < n; k++) deep[k] = side * chain_index_sdf(io, c->p[k]) > margin;
    for (int k = 0; k < n && start < 0; k++)
        if (!deep[k]) start = k;
    for (int k = 0; start >= 0 && k < n;) {
        int q = (start + k) % n;
        if (!deep[(q + 1) % n]) { k++; continue; }
        int len = 1; /* c[q] not deep, c[q+1 ..] deep */
        while (len < n && deep[(q + len) % n]) len++;
        k += len;
        fn(c, q, len, user);
    }
    free(deep);
}

typedef struct {
    int c_is_lower, level;
    const chain_index *bi;
    double margin, best_depth;
    pocket pk;
} run_find;

/* A pocket of c inside a concave bay of its hull (find_filled_pocket's hull bays miss it: the bay's
 * arc runs along the other layer's curve, and only the pocket's nodes lie inside it): the arc of a
 * run of c's nodes inside the other layer's curve by more than margin (deep_runs). It must be a dent
 * (the arc with its chord runs clockwise), deeper than 4 margins (two node spacings: a shallower one
 * is the other layer's curve bending past a chord just cut, and its in-plane triangles would be as
 * thin), with a chord that crosses no edge of c, and pass the hull bays' test of the layer beyond c.
 * The left lung's dome top of the 512 bench map (issue 25): the diaphragm's dome cuts an oval pocket
 * into the lower layer's loop from the crescent's concave side; the layer above is the crescent
 * without it. Laced as one chain, the oval's side is fanned to the crescent's concave run, down to
 * 0.8 degrees. The deepest is kept in f->pk. */
static void run_pocket(const thx_chain *c, int q, int len, void *user)
{
    run_find *f = user;
    int n = (int)c->n, hi = (q + len) % n;
    if (len < 2 || len >= n - 1 || !(arc_area2(c, q, len) < 0)) return;
    double depth;
    int deep = deepest_node(c, q, len, &depth);
    if (deep < 0 || !(depth > 4 * f->margin) || !(depth > f->best_depth) || chord_crosses(c, q, hi)) return;
    if (!f->c_is_lower &&
        (arc_filled(c, q, len, f->bi, c->n_beyond, f->margin) ||
         (f->level < 2 && pocket_covered(c->beyond, c->n_beyond, c->p[q], c->p[hi], c->p[deep], f->margin))))
        return;
    f->best_depth = depth;
    f->pk = (pocket){q, hi};
}

/* A tongue of c that the other layer lacks, found as a run of c's nodes outside the other layer's
 * curve by more than margin (deep_runs), where the fan rule of step 5 sees only one side of it: a
 * tongue one voxel wide (a wedge of tissue whose tip line runs nearly along the layers: the right
 * lung of the 512 bench map beside the mediastinum, issue 25, 14 mm further on each layer up) is
 * fanned side by side to the other layer's tip, down to 0.1 degrees, and no lacing without new
 * nodes does better. Cut in its plane, its in-plane triangles join its two sides a node spacing
 * apart. It must bulge (the arc with its chord runs counterclockwise), reach deeper than 4 margins,
 * have a chord that crosses no edge of c, and, as in is_tongue, not lie on the surface's end layer
 * and be held by the layer beyond unless c is the lower chain. The deepest is kept in f->pk. */
static void run_tongue(const thx_chain *c, int q, int len, void *user)
{
    run_find *f = user;
    int n = (int)c->n, hi = (q + len) % n;
    if (len < 2 || len >= n - 1 || c->n_beyond == 0 || !(arc_area2(c, q, len) > 0)) return;
    double depth;
    int deep = deepest_node(c, q, len, &depth);
    if (deep < 0 || !(depth > 4 * f->margin) || !(depth > f->best_depth) || chord_crosses(c, q, hi)) return;
    if (!f->c_is_lower && !pocket_covered(c->beyond, c->n_beyond, c->p[q], c->p[hi], c->p[deep], -1e300)) return;
    f->best_depth = depth;
    f->pk = (pocket){q, hi};
}

/* The deepest pocket of chain c that the other layer fills (io: its signed distance): a bay
 * between consecutive convex-hull vertices, deeper than margin, with at least 90% of the nodes of
 * its arc inside the other layer's curve by more than margin (the other layer covers the bay, not
 * merely a shallower bay of its own along it); unless c is the slice's lower chain, the
 * layer beyond c must not fill it the same way (a dent of one layer is cut by one slice only),
 * and at level 1 not even hold its deepest node (pocket_covered, the test of step 4: the slice
 * beyond may cut it there as its lower chain). At level 2 (the retry of a lacing that crosses
 * itself) that second test is dropped: the notched loops of the next layers up, whose cavity is
 * shifted a little, hold the deepest node in their bone, and no slice would cut the pocket. This is the
 * frontal sinus of a CT's skull (issue 25): a loop that runs in through a narrow notch and around
 * the whole cranial cavity, against the next layer's loop without the notch (a full disc). Laced
 * as one chain, the cavity's side is fanned to a few nodes of the disc across the skull, and those
 * triangles pass the outside test (their centroids lie inside the disc). Without such a bay, a
 * pocket inside a bay (run_pocket). 1 if found. */
static int find_filled_pocket(thx_ctx *ctx, const thx_chain *c, const chain_index *io, int c_is_lower, int level,
                              double margin, pocket *pk)
{
    int n = (int)c->n;
    if (n < 4) return 0;
    unsigned char *on = malloc((size_t)n);
    chain_index *bi = c_is_lower || !c->n_beyond ? NULL : calloc(c->n_beyond, sizeof *bi);
    if (!on || hull_flags(ctx, c, on) != 0 || (!c_is_lower && c->n_beyond && !bi)) { free(on); free(bi); return 0; }
    for (size_t q = 0; bi && q < c->n_beyond; q++)
        if (chain_index_init(&bi[q], c->beyond[q].p, c->beyond[q].n)) {
            for (size_t r = 0; r < q; r++) chain_index_free(&bi[r]);
            free(bi);
            free(on);
            return 0;
        }
    int first = -1;
    double best_depth = -1;
    for (int k = 0; k < n; k++) if (on[k]) { first = k; break; }
    int k = first;
    do {
        if (first < 0) break;
        int nx = (k + 1) % n;
        while (!on[nx]) nx = (nx + 1) % n;
        int len = (nx - k + n) % n;
        double depth;
        int deep = len > 1 ? deepest_node(c, k, len, &depth) : -1;
        if (deep >= 0 && depth > margin && depth > best_depth && arc_filled(c, k, len, io, 1, margin) &&
            (c_is_lower || (!arc_filled(c, k, len, bi, c->n_beyond, margin) &&
                            (level >= 2 || !pocket_covered(c->beyond, c->n_beyond, c->p[k], c->p[nx], c->p[deep], margin))))) {
            best_depth = depth;
            pk->lo = k;
            pk->hi = nx;
        }
        k = nx;
    } while (k != first);
    if (best_depth < 0) {
        run_find f = {c_is_lower, level, bi, margin, -1, {0, 0}};
        deep_runs(c, io, -1, margin, run_pocket, &f);
        best_depth = f.best_depth;
        *pk = f.pk;
    }
    for (size_t q = 0; bi && q < c->n_beyond; q++) chain_index_free(&bi[q]);
    free(bi);
    free(on);
    return best_depth > 0;
}

/* Is the arc c[lo .. lo+len] (cyclic) a tongue of c that the other layer lacks, to be cut in
 * the plane of c's layer? A tongue bulges outward (the arc with its chord runs counterclockwise),
 * its chord crosses no other edge of c, its deepest node lies outside the other layer's curve
 * (io) by more than margin, and, so that a tongue of one layer alone is cut by one slice only,
 * either c is the slice's lower chain or the layer beyond c has the tongue too. A tongue of the
 * first or last layer is never cut: the end cap covers it. */
static int is_tongue(const thx_chain *c, const chain_index *io, int c_is_lower, int lo, int len, double margin)
{
    int n = (int)c->n, hi = (lo + len) % n;
    if (len < 2 || len >= n - 1) return 0;
    if (!(arc_area2(c, lo, len) > 0) || chord_crosses(c, lo, hi)) return 0;
    thx_vec2 a = c->p[lo], b = c->p[hi];
    double best;
    int deep = deepest_node(c, lo, len, &best);
    if (deep < 0 || !(chain_index_sdf(io, c->p[deep]) > margin)) return 0;
    /* At the surface's first or last layer the end cap already covers the tongue: never cut there. */
    if (c->n_beyond == 0) return 0;
    return c_is_lower || pocket_covered(c->beyond, c->n_beyond, a, b, c->p[deep], -1e300);
}

static thx_status emit(thx_ctx *ctx, int32_t **tris, size_t *n_tris, size_t *cap, const int32_t id[3])
{
    THX_CHECK(thx_grow(ctx, (void **)tris, cap, (*n_tris + 1) * 3, sizeof **tris));
    memcpy(*tris + 3 * *n_tris, id, 3 * sizeof *id);
    (*n_tris)++;
    return THX_OK;
}

static thx_status lace_rec(thx_ctx *ctx, const thx_chain *a, const thx_chain *b, const thx_lace_opts *o, int32_t **tris,
                           size_t *n_tris, size_t *cap, thx_lace_stats *stats, int depth);

/* Cuts pocket pk of chain c with in-plane triangles (cap triangulation of the pocket polygon) and
 * returns the shortened chain in *out (arrays malloc'd). A chord longer than 1.5 spacings gets nodes
 * along it at the spacing when nd (not NULL) has room (thx_lace_nodes: so far the filled pockets'
 * chords only; the other cuts, older, keep their whole chords and outputs). */
static thx_status cut_pocket(thx_ctx *ctx, const thx_chain *c, pocket pk, thx_lace_nodes *nd, double spacing, int32_t **tris,
                             size_t *n_tris, size_t *cap, thx_lace_stats *stats, thx_chain *out, thx_vec2 **op,
                             int32_t **oid)
{
    int n = (int)c->n, len = (pk.hi - pk.lo + n) % n;
    thx_vec2 a = c->p[pk.lo], b = c->p[pk.hi];
    double chord = hypot(b.x - a.x, b.y - a.y);
    int m = 0; /* nodes on the chord, b to a in the polygon */
    if (nd && spacing > 0 && chord > 1.5 * spacing) {
        m = (int)lround(chord / spacing) - 1;
        if (nd->n + (size_t)m > nd->cap) m = 0;
    }
    int32_t id0 = m ? nd->base + (int32_t)nd->n : 0;
    thx_status st = THX_OK;
    thx_vec2 *poly = thx_malloc(ctx, (size_t)(len + 1 + m) * sizeof *poly);
    if (!poly) return THX_ENOMEM;
    for (int s = 0; s <= len; s++) poly[s] = c->p[(pk.lo + s) % n];
    for (int j = 1; j <= m; j++) {
        double t = (double)j / (m + 1);
        poly[len + j] = (thx_vec2){b.x + t * (a.x - b.x), b.y + t * (a.y - b.y)};
    }
    thx_vec2 *cp = NULL;
    int32_t *ct = NULL;
    size_t ncp = 0, nct = 0;
    st = thx_cap_triangulate(ctx, poly, (size_t)(len + 1 + m), 0.0, 0.0, &cp, &ncp, &ct, &nct);
    if (st == THX_OK) {
        for (size_t t = 0; t < nct && st == THX_OK; t++) {
            int32_t id[3];
            for (int v = 0; v < 3; v++) {
                int q = ct[3 * t + v];
                id[v] = q <= len ? c->id[(pk.lo + q) % n] : id0 + (q - len - 1);
            }
            st = emit(ctx, tris, n_tris, cap, id);
            stats->inplane_tris++;
        }
    }
    free(cp);
    free(ct);
    if (st != THX_OK) { free(poly); return st; }
    int mo = n - (len - 1) + m;
    *op = thx_malloc(ctx, (size_t)mo * sizeof **op);
    *oid = thx_malloc(ctx, (size_t)mo * sizeof **oid);
    if (!*op || !*oid) { free(poly); return THX_ENOMEM; }
    int k = 0;
    for (int s = 0; s < n; s++) {
        int off = (s - pk.lo + n) % n;
        if (off > 0 && off < len) continue;
        (*op)[k] = c->p[s];
        (*oid)[k] = c->id[s];
        k++;
        if (off == 0)
            for (int j = m; j >= 1; j--) { /* a to b along the chord */
                (*op)[k] = poly[len + j];
                (*oid)[k] = id0 + (j - 1);
                k++;
            }
    }
    for (int j = 1; j <= m; j++) {
        double *x = nd->xyz + 3 * (nd->n + (size_t)j - 1);
        x[0] = poly[len + j].x;
        x[1] = poly[len + j].y;
        x[2] = c->z;
    }
    if (m) nd->n += (size_t)m;
    free(poly);
    out->n = (size_t)k;
    out->p = *op;
    out->id = *oid;
    out->z = c->z;
    out->beyond = c->beyond;
    out->n_beyond = c->n_beyond;
    return THX_OK;
}

static thx_status lace_rec(thx_ctx *ctx, const thx_chain *a, const thx_chain *b, const thx_lace_opts *o, int32_t **tris,
                           size_t *n_tris, size_t *cap, thx_lace_stats *stats, int depth)
{
    int na = (int)a->n, nb = (int)b->n, N = na + nb;
    thx_status st = THX_OK;
    lacer L;
    memset(&L, 0, sizeof L);
    L.a = a;
    L.b = b;
    L.o = o;
    L.big_edge = o->max_edge * fmax(o->spacing, fabs(b->z - a->z));
    L.na = thx_malloc(ctx, (size_t)na * sizeof *L.na);
    L.nb = thx_malloc(ctx, (size_t)nb * sizeof *L.nb);
    L.pa = thx_malloc(ctx, (size_t)na * sizeof *L.pa);
    L.pb = thx_malloc(ctx, (size_t)nb * sizeof *L.pb);
    unsigned char *mv = thx_malloc(ctx, (size_t)N), *bad = thx_calloc(ctx, (size_t)N, 1);
    int *sa = thx_malloc(ctx, (size_t)(N + 1) * sizeof *sa), *sb = thx_malloc(ctx, (size_t)(N + 1) * sizeof *sb);
    double *costb = NULL;
    unsigned char *fromb = NULL;
    if (!L.na || !L.nb || !L.pa || !L.pb || !mv || !bad || !sa || !sb) { st = THX_ENOMEM; goto done; }
    if (chain_index_init(&L.ia, a->p, a->n) || chain_index_init(&L.ib, b->p, b->n)) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
    if (o->raw_positions) {
        memcpy(L.na, a->p, (size_t)na * sizeof *L.na);
        memcpy(L.nb, b->p, (size_t)nb * sizeof *L.nb);
    } else {
        normalize(a, L.na);
        normalize(b, L.nb);
    }
    phases(a, o->phase_weight, L.pa);
    phases(b, o->phase_weight, L.pb);
    /* First connective segment: A's start node and the nearest node of B (normalized). */
    {
        double best = INFINITY;
        for (int j = 0; j < nb; j++) {
            double d = ndist(&L, 0, j);
            if (d < best) { best = d; L.j0 = j; }
        }
    }
    if (o->cut_filled_pockets > 0 && depth < 8) {
        /* Step 0 of a retry (thx_surfaces_build, after a lacing that crosses itself): a pocket of
           either chain that the other layer fills is cut off in its own plane first, and the rest
           laced again (recursively: one pocket per level); with cut_tongue_runs, when neither chain has
           such a pocket, a tongue run of either (run_tongue) the same way. */
        for (int side = 0; side < 2 * (1 + (o->cut_tongue_runs > 0)); side++) {
            pocket pk;
            const thx_chain *c = side % 2 ? b : a;
            const chain_index *io = side % 2 ? &L.ia : &L.ib;
            if (side < 2 && !find_filled_pocket(ctx, c, io, !side, o->cut_filled_pockets, 0.5 * o->spacing, &pk))
                continue;
            if (side >= 2) { /* no filled pocket: a tongue run (cut_tongue_runs) */
                run_find f = {side == 2, 0, NULL, 0.5 * o->spacing, -1, {0, 0}};
                deep_runs(c, io, +1, f.margin, run_tongue, &f);
                if (f.best_depth < 0) continue;
                pk = f.pk;
            }
            thx_chain nc;
            thx_vec2 *np = NULL;
            int32_t *nid = NULL;
            size_t keep = *n_tris, keep_inplane = stats->inplane_tris;
            st = cut_pocket(ctx, c, pk, o->nodes, o->spacing, tris, n_tris, cap, stats, &nc, &np, &nid);
            if (st == THX_OK && nc.n >= 3) {
                if (side < 2) stats->filled_pockets++;
                else stats->tongues++;
                st = side % 2 ? lace_rec(ctx, a, &nc, o, tris, n_tris, cap, stats, depth + 1)
                              : lace_rec(ctx, &nc, b, o, tris, n_tris, cap, stats, depth + 1);
                free(np);
                free(nid);
                goto done;
            }
            free(np);
            free(nid);
            if (st != THX_OK && st != THX_EGEOM) goto done;
            /* a pocket that is no simple polygon stays laced */
            *n_tris = keep;
            stats->inplane_tris = keep_inplane;
            st = THX_OK;
        }
    }
    greedy_path(&L, mv);
    if (o->whole_dp && (size_t)na * (size_t)nb * 2 <= OUTSIDE_MEMO_MAX) {
        /* the whole slice by one dynamic programme from the first connective segment: the path of
           least cost over every pair of nodes (the retry of a lacing with a thin triangle), where the
           greedy walk goes by the next shortest diagonal */
        L.outside = calloc((size_t)na * (size_t)nb * 2, 1);
        L.grid = sdf_grid_new(&L);
        costb = malloc((size_t)(na + 1) * (size_t)(nb + 1) * sizeof *costb);
        fromb = malloc((size_t)(na + 1) * (size_t)(nb + 1));
        if (!L.outside || !costb || !fromb) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
        dp_path(&L, 0, 0, na, nb, mv, costb, fromb, 1);
    }
    /* Outside test of every triangle of the shortest-diagonal lacing. */
    int nbad = 0;
    sa[0] = sb[0] = 0;
    for (int k = 0; k < N; k++) {
        thx_vec3 t[3];
        int32_t id[3];
        move_tri(&L, sa[k], sb[k], mv[k], t, id);
        bad[k] = (unsigned char)tri_outside(&L, t);
        nbad += bad[k];
        sa[k + 1] = sa[k] + !mv[k];
        sb[k + 1] = sb[k] + mv[k];
    }
    if (nbad && nbad < N) {
        /* Rotate so that the walk starts inside the longest run of valid triangles (gaps never wrap). */
        int best_len = 0, best_start = 0, run = 0;
        for (int k = 0; k < 2 * N; k++) {
            if (!bad[k % N]) { run++; if (run > best_len && run <= N) { best_len = run; best_start = k - run + 1; } }
            else run = 0;
        }
        int r = (best_start + best_len / 2) % N;
        if (r != 0) {
            L.i0 = (L.i0 + sa[r]) % na;
            L.j0 = (L.j0 + sb[r]) % nb;
            unsigned char *tmp = thx_malloc(ctx, (size_t)N);
            if (!tmp) { st = THX_ENOMEM; goto done; }
            for (int k = 0; k < N; k++) tmp[k] = mv[(k + r) % N];
            memcpy(mv, tmp, (size_t)N);
            for (int k = 0; k < N; k++) tmp[k] = bad[(k + r) % N];
            memcpy(bad, tmp, (size_t)N);
            free(tmp);
            for (int k = 0; k < N; k++) { sa[k + 1] = sa[k] + !mv[k]; sb[k + 1] = sb[k] + mv[k]; }
        }
    }
    stats->removed += (size_t)nbad;
    /* the gaps' dynamic programming meets the same moves again as its window grows: their outside tests
       remembered (up to OUTSIDE_MEMO_MAX bytes; beyond, each made again) */
    if (nbad && !L.outside && (size_t)na * (size_t)nb * 2 <= OUTSIDE_MEMO_MAX) L.outside = calloc((size_t)na * (size_t)nb * 2, 1);
    if (nbad && !L.grid) L.grid = sdf_grid_new(&L);
    int unresolved_pocket = 0;
    for (int k = 0; k < N && nbad;) {
        if (!bad[k]) { k++; continue; }
        int k1 = k, k2 = k;
        while (k2 + 1 < N && bad[k2 + 1]) k2++;
        stats->relaced_gaps++;
        int w = o->window, ok = 0;
        for (;;) {
            int s0 = k1 - w < 0 ? 0 : k1 - w, s1 = k2 + 1 + w > N ? N : k2 + 1 + w;
            int W = sa[s1] - sa[s0] + 1, H = sb[s1] - sb[s0] + 1;
            costb = realloc(costb, (size_t)W * (size_t)H * sizeof *costb);
            fromb = realloc(fromb, (size_t)W * (size_t)H);
            if (!costb || !fromb) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
            double c = dp_path(&L, sa[s0], sb[s0], sa[s1], sb[s1], mv + s0, costb, fromb, 1);
            if (c < BIG) {
                ok = 1;
                for (int q = s0; q < s1; q++) { sa[q + 1] = sa[q] + !mv[q]; sb[q + 1] = sb[q] + mv[q]; bad[q] = 0; }
                k = s1;
                break;
            }
            if (s0 == 0 && s1 == N) {
                for (int q = s0; q < s1; q++) { sa[q + 1] = sa[q] + !mv[q]; sb[q + 1] = sb[q] + mv[q]; }
                k = s1;
                break;
            }
            w *= 2;
        }
        if (!ok) {
            unresolved_pocket = 1;
            break;
        }
    }
    if (unresolved_pocket && depth < 8) {
        /* Step 4: a pocket that closes between the layers is cut off in its own plane. */
        int gi0 = 0, gj0 = 0, gi1 = 0, gj1 = 0, have = 0;
        for (int k = 0; k < N; k++) {
            thx_vec3 t[3];
            int32_t id[3];
            move_tri(&L, sa[k], sb[k], mv[k], t, id);
            if (tri_outside(&L, t)) {
                if (!have) { gi0 = (L.i0 + sa[k]) % na; gj0 = (L.j0 + sb[k]) % nb; have = 1; }
                gi1 = (L.i0 + sa[k + 1]) % na;
                gj1 = (L.j0 + sb[k + 1]) % nb;
            }
        }
        pocket pk;
        thx_chain nc;
        thx_vec2 *np = NULL;
        int32_t *nid = NULL;
        double margin = 0.5 * o->spacing;
        /* A pocket whose polygon is not simple (it passes a bridge node of a branching chain twice,
           or touches itself where a layer lies along a flat cap: issue 24) is not cut: THX_EGEOM
           from its triangulation leaves the lacing as it is, instead of refusing the surface. */
        if (have && find_pocket(ctx, a, b, 1, gi0, gi1, margin, &pk)) {
            st = cut_pocket(ctx, a, pk, NULL, 0, tris, n_tris, cap, stats, &nc, &np, &nid);
            if (st != THX_EGEOM) {
                if (st == THX_OK) st = lace_rec(ctx, &nc, b, o, tris, n_tris, cap, stats, depth + 1);
                free(np);
                free(nid);
                goto done;
            }
            st = THX_OK;
        }
        if (have && find_pocket(ctx, b, a, 0, gj0, gj1, margin, &pk)) {
            st = cut_pocket(ctx, b, pk, NULL, 0, tris, n_tris, cap, stats, &nc, &np, &nid);
            if (st != THX_EGEOM) {
                if (st == THX_OK) st = lace_rec(ctx, a, &nc, o, tris, n_tris, cap, stats, depth + 1);
                free(np);
                free(nid);
                goto done;
            }
            st = THX_OK;
        }
    }
    /* Step 5: a long fan (one node joined to a long run of the other chain) where that run is a
       tongue the node's layer lacks: the tongue is cut off in its own plane and the slice laced
       again, instead of a spray of long, thin triangles. */
    if (depth < 8 && o->fan_limit > 1) {
        for (int k = 0; k < N;) {
            int r = 1;
            while (k + r < N && mv[k + r] == mv[k]) r++;
            if (r >= o->fan_limit) {
                int bm = mv[k];
                const thx_chain *c = bm ? b : a;
                int lo = bm ? (L.j0 + sb[k]) % nb : (L.i0 + sa[k]) % na;
                if (is_tongue(c, bm ? &L.ia : &L.ib, !bm, lo, r, 0.5 * o->spacing)) {
                    pocket pk = {lo, (lo + r) % (int)c->n};
                    thx_chain nc;
                    thx_vec2 *np = NULL;
                    int32_t *nid = NULL;
                    st = cut_pocket(ctx, c, pk, NULL, 0, tris, n_tris, cap, stats, &nc, &np, &nid);
                    if (st != THX_EGEOM) { /* a tongue that is not a simple polygon stays laced */
                        if (st == THX_OK) stats->tongues++;
                        if (st == THX_OK) st = bm ? lace_rec(ctx, a, &nc, o, tris, n_tris, cap, stats, depth + 1)
                                                  : lace_rec(ctx, &nc, b, o, tris, n_tris, cap, stats, depth + 1);
                        free(np);
                        free(nid);
                        goto done;
                    }
                    st = THX_OK;
                }
            }
            k += r;
        }
    }
    /* Emit the path. */
    for (int k = 0; k < N && st == THX_OK; k++) {
        thx_vec3 t[3];
        int32_t id[3];
        move_tri(&L, sa[k], sb[k], mv[k], t, id);
        if (tri_outside(&L, t)) stats->unresolved++;
        double e = fmax(dist3(t[0], t[1]), fmax(dist3(t[1], t[2]), dist3(t[2], t[0])));
        if (e > L.big_edge) stats->too_large++;
        st = emit(ctx, tris, n_tris, cap, id);
    }
done:
    free(L.outside);
    sdf_grid_free(L.grid);
    chain_index_free(&L.ia);
    chain_index_free(&L.ib);
    free(L.na);
    free(L.nb);
    free(L.pa);
    free(L.pb);
    free(mv);
    free(bad);
    free(sa);
    free(sb);
    free(costb);
    free(fromb);
    return st;
}

/* The loops of a chain: its parts, or the chain itself. */
static const thx_chain *chain_parts(const thx_chain *c, size_t *n)
{
    *n = c->n_parts ? c->n_parts : 1;
    return c->n_parts ? c->parts : c;
}

/* Are all loops of `in` strictly inside the union of the loops of `out` and all
 * loops of `out` strictly outside every loop of `in` (in projection)? */
static int nested_in(const thx_chain *in, const thx_chain *out)
{
    size_t ni, no;
    const thx_chain *pi = chain_parts(in, &ni), *po = chain_parts(out, &no);
    int ok = 1;
    chain_index *io = calloc(no, sizeof *io), *ii = calloc(ni, sizeof *ii);
    if (!io || !ii) ok = 0;
    for (size_t k = 0; ok && k < no; k++) if (chain_index_init(&io[k], po[k].p, po[k].n)) ok = 0;
    for (size_t k = 0; ok && k < ni; k++) if (chain_index_init(&ii[k], pi[k].p, pi[k].n)) ok = 0;
    /* every inner node inside some outer loop, and no outer node inside an inner loop */
    for (size_t k = 0; ok && k < ni; k++)
        for (size_t q = 0; ok && q < pi[k].n; q++) {
            int inside = 0;
            for (size_t r = 0; r < no && !inside; r++) inside = chain_index_sdf(&io[r], pi[k].p[q]) < 0;
            ok = inside;
        }
    for (size_t k = 0; ok && k < no; k++)
        for (size_t q = 0; ok && q < po[k].n; q++)
            for (size_t r = 0; ok && r < ni; r++) ok = chain_index_sdf(&ii[r], po[k].p[q]) > 0;
    /* and no edge of one crosses an edge of the other */
    for (size_t k = 0; ok && k < ni; k++)
        for (size_t q = 0; ok && q < pi[k].n; q++)
            for (size_t r = 0; ok && r < no; r++)
                for (size_t t = 0; ok && t < po[r].n; t++)
                    ok = !thx_segments_touch(&pi[k].p[q].x, &pi[k].p[(q + 1) % pi[k].n].x, &po[r].p[t].x,
                                             &po[r].p[(t + 1) % po[r].n].x);
    for (size_t k = 0; io && k < no; k++) chain_index_free(&io[k]);
    for (size_t k = 0; ii && k < ni; k++) chain_index_free(&ii[k]);
    free(io);
    free(ii);
    return ok;
}

/* Laces nested chains by a constrained Delaunay triangulation of the ring between them in
 * projection: every loop edge is a constraint; the triangles inside the outer loops and outside
 * the inner ones are kept, with their nodes on their own layers. Returns 0 in *ok when the
 * chains are not nested or the triangulation is not possible (coincident points). */
static thx_status lace_projected(thx_ctx *ctx, const thx_chain *a, const thx_chain *b, int32_t **tris, size_t *n_tris,
                                 size_t *cap, int *ok)
{
    *ok = 0;
    int a_inner = nested_in(a, b);
    if (!a_inner && !nested_in(b, a)) return THX_OK;
    const thx_chain *inner = a_inner ? a : b, *outer = a_inner ? b : a;
    size_t ni, no, np = 0, ns = 0;
    const thx_chain *pi = chain_parts(inner, &ni), *po = chain_parts(outer, &no);
    for (size_t k = 0; k < ni; k++) np += pi[k].n;
    for (size_t k = 0; k < no; k++) np += po[k].n;
    thx_vec2 *pts = thx_malloc(ctx, np * sizeof *pts);
    int32_t *ids = thx_malloc(ctx, np * sizeof *ids), *segs = thx_malloc(ctx, 2 * np * sizeof *segs), *t = NULL;
    chain_index *ix = thx_calloc(ctx, ni + no, sizeof *ix);
    size_t nt = 0;
    thx_status st = THX_OK;
    if (!pts || !ids || !segs || !ix) { st = THX_ENOMEM; goto done; }
    np = 0;
    for (int side = 0; side < 2; side++) {
        const thx_chain *parts = side ? po : pi;
        size_t n_parts = side ? no : ni;
        for (size_t k = 0; k < n_parts; k++) {
            size_t base = np;
            for (size_t q = 0; q < parts[k].n; q++) {
                pts[np] = parts[k].p[q];
                ids[np] = parts[k].id[q];
                segs[2 * ns] = (int32_t)np;
                segs[2 * ns + 1] = (int32_t)(q + 1 < parts[k].n ? np + 1 : base);
                ns++;
                np++;
            }
            if (chain_index_init(&ix[(side ? ni : 0) + k], parts[k].p, parts[k].n)) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
        }
    }
    {
        thx_ctx *quiet = NULL;
        if (thx_ctx_create(&quiet) != THX_OK) { st = THX_ENOMEM; goto done; }
        thx_status r = thx_cdt2d(quiet, pts, np, segs, ns, &t, &nt);
        thx_ctx_destroy(&quiet);
        if (r != THX_OK) goto done; /* coincident points or crossing loops: not this way */
    }
    for (size_t k = 0; k < nt && st == THX_OK; k++) {
        thx_vec2 c = {(pts[t[3 * k]].x + pts[t[3 * k + 1]].x + pts[t[3 * k + 2]].x) / 3.0,
                      (pts[t[3 * k]].y + pts[t[3 * k + 1]].y + pts[t[3 * k + 2]].y) / 3.0};
        int in_outer = 0, in_inner = 0;
        for (size_t q = 0; q < no && !in_outer; q++) in_outer = chain_index_sdf(&ix[ni + q], c) < 0;
        for (size_t q = 0; q < ni && !in_inner; q++) in_inner = chain_index_sdf(&ix[q], c) < 0;
        if (!in_outer || in_inner) continue;
        int32_t id[3] = {ids[t[3 * k]], ids[t[3 * k + 1]], ids[t[3 * k + 2]]};
        st = emit(ctx, tris, n_tris, cap, id);
    }
    if (st == THX_OK) *ok = 1;
done:
    for (size_t k = 0; ix && k < ni + no; k++) chain_index_free(&ix[k]);
    free(ix);
    free(pts);
    free(ids);
    free(segs);
    free(t);
    return st;
}

typedef struct { int32_t a, b; } lace_edge;
static int cmp_lace_edge(const void *x, const void *y)
{
    const lace_edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

/* 1 if some edge lies in more than two triangles of the slice (a chain that visits a bridge node
 * twice can join it to the same node of the other chain twice), 0 if not, -1 out of memory. */
static int slice_overused_edge(const int32_t *tris, size_t first, size_t n_tris)
{
    size_t ne = 3 * (n_tris - first);
    lace_edge *e = malloc((ne ? ne : 1) * sizeof *e);
    if (!e) return -1;
    for (size_t k = 0; k < ne; k++) {
        size_t t = first + k / 3;
        int32_t a = tris[3 * t + k % 3], b = tris[3 * t + (k % 3 + 1) % 3];
        e[k].a = a < b ? a : b;
        e[k].b = a < b ? b : a;
    }
    qsort(e, ne, sizeof *e, cmp_lace_edge);
    int bad = 0;
    for (size_t k = 0; k + 2 < ne && !bad; k++)
        bad = e[k].a == e[k + 2].a && e[k].b == e[k + 2].b;
    free(e);
    return bad;
}

typedef struct { int32_t id; thx_vec3 p; } id_point;
static int cmp_id_point(const void *x, const void *y)
{
    int32_t a = ((const id_point *)x)->id, b = ((const id_point *)y)->id;
    return (a > b) - (a < b);
}

/* Worst aspect ratio (longest edge / (2 sqrt(3) inradius); 1 = equilateral) of the slice's
 * triangles, with node positions looked up from the two chains. -1 when out of memory. */
static double slice_worst_aspect(const thx_chain *a, const thx_chain *b, const int32_t *tris, size_t first, size_t n_tris)
{
    size_t n = a->n + b->n;
    id_point *m = malloc(n * sizeof *m);
    if (!m) return -1;
    for (size_t k = 0; k < a->n; k++) { m[k].id = a->id[k]; m[k].p = thx_v3(a->p[k].x, a->p[k].y, a->z); }
    for (size_t k = 0; k < b->n; k++) { m[a->n + k].id = b->id[k]; m[a->n + k].p = thx_v3(b->p[k].x, b->p[k].y, b->z); }
    qsort(m, n, sizeof *m, cmp_id_point);
    double worst = 1;
    for (size_t t = first; t < n_tris; t++) {
        thx_vec3 v[3];
        for (int q = 0; q < 3; q++) {
            id_point key = {tris[3 * t + q], {0, 0, 0}};
            id_point *f = bsearch(&key, m, n, sizeof *m, cmp_id_point);
            v[q] = f ? f->p : thx_v3(0, 0, 0);
        }
        double e0 = dist3(v[0], v[1]), e1 = dist3(v[1], v[2]), e2 = dist3(v[2], v[0]);
        double area = 0.5 * thx_v3_norm(thx_v3_cross(thx_v3_sub(v[1], v[0]), thx_v3_sub(v[2], v[0])));
        double ar = area > 0 ? fmax(e0, fmax(e1, e2)) * (e0 + e1 + e2) / (4 * sqrt(3.0) * area) : INFINITY;
        if (ar > worst) worst = ar;
    }
    free(m);
    return worst;
}

static int slice_max_fan(thx_ctx *ctx, const int32_t *tris, size_t first, size_t n_tris, int *fan)
{
    int32_t maxid = 0;
    *fan = 0;
    for (size_t k = 3 * first; k < 3 * n_tris; k++) if (tris[k] > maxid) maxid = tris[k];
    int *cnt = thx_calloc(ctx, (size_t)maxid + 1, sizeof *cnt);
    if (!cnt) return -1;
    for (size_t k = 3 * first; k < 3 * n_tris; k++) {
        int c = ++cnt[tris[k]];
        if (c > *fan) *fan = c;
    }
    free(cnt);
    return 0;
}

thx_status thx_lace(thx_ctx *ctx, const thx_chain *a, const thx_chain *b, const thx_lace_opts *o, int32_t **tris,
                    size_t *n_tris, size_t *cap, thx_lace_stats *stats)
{
    if (a->n < 3 || b->n < 3) return thx_error(ctx, THX_EINPUT, "lacing needs chains of at least 3 nodes (%zu, %zu)", a->n, b->n);
    size_t first = *n_tris;
    thx_lace_stats local = {0};
    THX_CHECK(lace_rec(ctx, a, b, o, tris, n_tris, cap, &local, 0));
    /* Largest fan: triangles per node id within this slice. */
    if (slice_max_fan(ctx, *tris, first, *n_tris, &local.max_fan)) return THX_ENOMEM;
    if (o->cut_filled_pockets == 0 && o->fan_limit > 0 && local.max_fan > 3 * o->fan_limit) {
        /* A long fan where one layer has a pocket the other fills (a CT skull's loop around the
           cranial cavity through the frontal sinus's notch, against a full disc: issue 25): the
           cavity's side fanned to one node of the other layer closes the pocket with a cone, not a
           floor. Laced again with the filled pockets cut in their plane first; kept if it cut one
           and leaves no more triangles outside the surface. (Its largest fan may be as long: the
           in-plane triangulation of a large pocket joins a node of its notch to many.) */
        thx_lace_opts o2 = *o;
        o2.cut_filled_pockets = 1;
        size_t keep = *n_tris;
        thx_lace_stats l2 = {0};
        THX_CHECK(lace_rec(ctx, a, b, &o2, tris, n_tris, cap, &l2, 0));
        if (slice_max_fan(ctx, *tris, keep, *n_tris, &l2.max_fan)) return THX_ENOMEM;
        if (l2.filled_pockets > 0 && l2.unresolved <= local.unresolved) {
            memmove(*tris + 3 * first, *tris + 3 * keep, (*n_tris - keep) * 3 * sizeof **tris);
            *n_tris = first + (*n_tris - keep);
            local = l2;
        } else {
            *n_tris = keep;
        }
    }
    int overused = slice_overused_edge(*tris, first, *n_tris);
    if (overused < 0) return thx_error(ctx, THX_ENOMEM, "out of memory");
    int must = local.unresolved > 0 || overused;
    double worst = must ? INFINITY : slice_worst_aspect(a, b, *tris, first, *n_tris);
    if (worst < 0) return thx_error(ctx, THX_ENOMEM, "out of memory");
    if (must || worst > o->projected_aspect || (o->fan_limit > 0 && local.max_fan > 3 * o->fan_limit)) {
        /* A lacing with triangles outside the surface, or one that is not a manifold (an edge in three
           triangles): if the loops are nested, triangulate the ring between them in projection instead.
           A merely poor lacing (long fans, thin triangles) is replaced only if that is better. */
        size_t keep = *n_tris;
        int ok = 0;
        THX_CHECK(lace_projected(ctx, a, b, tris, n_tris, cap, &ok));
        if (ok && !must) {
            double w2 = slice_worst_aspect(a, b, *tris, keep, *n_tris);
            if (w2 < 0) return thx_error(ctx, THX_ENOMEM, "out of memory");
            if (!(w2 < worst)) { *n_tris = keep; ok = 0; }
        }
        if (ok) {
            memmove(*tris + 3 * first, *tris + 3 * keep, (*n_tris - keep) * 3 * sizeof **tris);
            *n_tris = first + (*n_tris - keep);
            thx_lace_stats proj = {0};
            proj.projected = 1;
            local = proj;
            if (slice_max_fan(ctx, *tris, first, *n_tris, &local.max_fan)) return THX_ENOMEM;
        }
    }
    local.n_tris = *n_tris - first;
    stats->n_tris += local.n_tris;
    stats->removed += local.removed;
    stats->relaced_gaps += local.relaced_gaps;
    stats->inplane_tris += local.inplane_tris;
    stats->tongues += local.tongues;
    stats->filled_pockets += local.filled_pockets;
    stats->projected += local.projected;
    stats->unresolved += local.unresolved;
    stats->too_large += local.too_large;
    if (local.max_fan > stats->max_fan) stats->max_fan = local.max_fan;
    return THX_OK;
}
