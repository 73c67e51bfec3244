/*
 * End caps (paper 3.2, "Completing the model"): triangulate the first and
 * last layer of a surface, either from the loop points alone ("polygon") or
 * with an added square grid of points ("grid"), then discard the triangles
 * outside a concave loop by the inside test on their centroids.
 *
 * The triangulation is a constrained Delaunay triangulation with the loop's
 * edges as constraints (thx_cdt2d), so no triangle straddles the loop and the
 * cap meets the laced side wall edge for edge (watertight).
 *
 * Which triangles are kept: those whose centroid is inside the loop (the
 * paper's test, thx_loop_inside). Because no triangle crosses a loop edge,
 * "inside" is also a topological property: starting from the hull, it flips
 * each time a loop edge is crossed. That parity is exact, while a centroid
 * computed in floating point can fall outside an extremely thin triangle;
 * the two are compared, and where they disagree (only possible for such
 * slivers) the exact parity decides. See thorax/geom/cdt.h for the contract.
 */
#include "thorax/geom/cdt.h"
#include "geom/chain_sdf.h"
#include "thorax/geom/inside.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_GRID_NODES 100000000.0

typedef struct {
    int32_t lo, hi; /* vertex indices, lo < hi */
    int32_t tri;    /* triangle index */
    int32_t slot;   /* edge slot 0..2 within the triangle */
} edge_rec;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct {
    double y; /* the lower end's y */
    size_t k; /* edge k -> k+1 */
} edge_low;

static int cmp_edge_low(const void *a, const void *b)
{
    const edge_low *u = a, *v = b;
    if (u->y != v->y) return (u->y > v->y) - (u->y < v->y);
    return (u->k > v->k) - (u->k < v->k);
}

static int cmp_edge(const void *a, const void *b)
{
    const edge_rec *u = a, *v = b;
    if (u->lo != v->lo) return u->lo < v->lo ? -1 : 1;
    if (u->hi != v->hi) return u->hi < v->hi ? -1 : 1;
    return (u->tri > v->tri) - (u->tri < v->tri);
}

/* Loop edge i -> i+1 (mod n) between vertices a, b (both < n)? */
static int is_loop_edge(int32_t a, int32_t b, size_t n)
{
    if (a < 0 || b < 0 || (size_t)a >= n || (size_t)b >= n) return 0;
    int32_t d = a > b ? a - b : b - a;
    return d == 1 || (size_t)d == n - 1;
}

/* Keeps the message of a failed cdt2d call, prefixed with the cap context. */
static thx_status cap_fail(thx_ctx *ctx, thx_status st)
{
    char buf[512];
    snprintf(buf, sizeof buf, "%s", thx_ctx_message(ctx));
    if (st == THX_EGEOM) return thx_error(ctx, st, "cap: the loop is not a simple polygon: %s", buf);
    return thx_error(ctx, st, "cap: %s", buf);
}

thx_status thx_cap_triangulate(thx_ctx *ctx, const thx_vec2 *loop, size_t n, double grid_spacing, double tol,
                               thx_vec2 **out_pts, size_t *n_out, int32_t **tris, size_t *n_tris)
{
    *out_pts = NULL;
    *n_out = 0;
    *tris = NULL;
    *n_tris = 0;
    if (n < 3) return thx_error(ctx, THX_EINPUT, "cap: loop has %zu points (needs at least 3)", n);
    if (n > (size_t)INT32_MAX / 8) return thx_error(ctx, THX_EINPUT, "cap: loop has too many points (%zu)", n);
    if (!(grid_spacing >= 0.0) || !isfinite(grid_spacing))
        return thx_error(ctx, THX_EINPUT, "cap: grid spacing %g must be >= 0", grid_spacing);
    if (!(tol >= 0.0) || !isfinite(tol)) return thx_error(ctx, THX_EINPUT, "cap: tolerance %g must be >= 0", tol);
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(loop[i].x) || !isfinite(loop[i].y))
            return thx_error(ctx, THX_EINPUT, "cap: loop point %zu has a non-finite coordinate", i);
        x0 = fmin(x0, loop[i].x); x1 = fmax(x1, loop[i].x);
        y0 = fmin(y0, loop[i].y); y1 = fmax(y1, loop[i].y);
    }

    thx_status st = THX_OK;
    thx_vec2 *pts = NULL;
    int32_t *segs = NULL, *all = NULL, *keep = NULL, *cnt = NULL;
    int8_t *par = NULL;
    edge_rec *er = NULL;
    int32_t *queue = NULL;
    size_t np = n, cap = n, nall = 0;

    pts = thx_malloc(ctx, n * sizeof *pts);
    if (!pts) return THX_ENOMEM;
    memcpy(pts, loop, n * sizeof *pts);

    /* Grid nodes ((i + 1/2) h, (j + 1/2) h) inside the loop, >= tol from it. */
    if (grid_spacing > 0.0) {
        double h = grid_spacing;
        double i0 = ceil(x0 / h - 0.5), i1 = floor(x1 / h - 0.5);
        double j0 = ceil(y0 / h - 0.5), j1 = floor(y1 / h - 0.5);
        double count = (i1 >= i0 && j1 >= j0) ? (i1 - i0 + 1) * (j1 - j0 + 1) : 0.0;
        if (count > MAX_GRID_NODES) {
            st = thx_error(ctx, THX_EINPUT, "cap: grid spacing %g gives %.3g grid nodes (limit %.0g)", h, count,
                           MAX_GRID_NODES);
            goto done;
        }
        /* Row by row: the loop's crossings with the row's line (half-open rule) give inside by
           parity, O(n + k log k) per row; the distance test then uses the block index. Nodes
           within a hair of the loop are decided by the exact test of inside.h. */
        chain_index ci;
        double *xs = NULL;
        size_t xcap = 0, n_act = 0, next_edge = 0;
        if (chain_index_init(&ci, loop, n) != 0) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
        /* The edges by their lower end, and those that may cross the current row (rows rise):
           each row costs its crossings, not the whole loop (issue 24: a tall comb's cap). */
        edge_low *by_low = thx_malloc(ctx, n * sizeof *by_low);
        size_t *act = thx_malloc(ctx, n * sizeof *act);
        if (!by_low || !act) { free(by_low); free(act); chain_index_free(&ci); st = THX_ENOMEM; goto done; }
        for (size_t k = 0; k < n; k++) by_low[k] = (edge_low){fmin(loop[k].y, loop[(k + 1) % n].y), k};
        qsort(by_low, n, sizeof *by_low, cmp_edge_low);
        double hair = 1e-9 * fmax(fmax(fabs(x0), fabs(x1)), fmax(fmax(fabs(y0), fabs(y1)), h));
        for (double j = j0; j <= j1 && st == THX_OK; j += 1.0) {
            double gy = (j + 0.5) * h;
            size_t nx = 0, kept = 0;
            while (next_edge < n && by_low[next_edge].y <= gy) act[n_act++] = by_low[next_edge++].k;
            for (size_t q = 0; q < n_act; q++) { /* an edge wholly at or below the row is done */
                size_t k = act[q];
                if (fmax(loop[k].y, loop[(k + 1) % n].y) > gy) act[kept++] = k;
            }
            n_act = kept;
            for (size_t q = 0; q < n_act; q++) {
                size_t k = act[q];
                thx_vec2 a = loop[k], b = loop[(k + 1) % n];
                if ((a.y <= gy) == (b.y <= gy)) continue;
                if (nx == xcap) {
                    st = thx_grow(ctx, (void **)&xs, &xcap, nx + 1, sizeof *xs);
                    if (st != THX_OK) break;
                }
                xs[nx++] = a.x + (gy - a.y) * (b.x - a.x) / (b.y - a.y);
            }
            if (st != THX_OK) break;
            qsort(xs, nx, sizeof *xs, cmp_double);
            size_t c = 0;
            for (double i = i0; i <= i1; i += 1.0) {
                thx_vec2 g = {(i + 0.5) * h, gy};
                while (c < nx && xs[c] < g.x) c++;
                if (!(c & 1)) continue; /* even number of crossings to the left: outside */
                double d = fabs(chain_index_sdf(&ci, g));
                if (d < tol) continue;
                if (d <= hair && thx_loop_inside(loop, n, g, tol) != THX_INSIDE) continue;
                if (np == cap) {
                    st = thx_grow(ctx, (void **)&pts, &cap, np + 1, sizeof *pts);
                    if (st != THX_OK) break;
                }
                pts[np++] = g;
            }
        }
        free(xs);
        free(by_low);
        free(act);
        chain_index_free(&ci);
        if (st != THX_OK) goto done;
    }
    if (np > (size_t)INT32_MAX / 8) {
        st = thx_error(ctx, THX_EINPUT, "cap: too many grid points (%zu)", np);
        goto done;
    }

    segs = thx_malloc(ctx, 2 * n * sizeof *segs);
    if (!segs) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < n; i++) {
        segs[2 * i] = (int32_t)i;
        segs[2 * i + 1] = (int32_t)((i + 1) % n);
    }
    st = thx_cdt2d(ctx, pts, np, segs, n, &all, &nall);
    if (st != THX_OK) { st = cap_fail(ctx, st); goto done; }
    if (nall == 0) {
        st = thx_error(ctx, THX_EGEOM, "cap: the %zu loop points are collinear (no area)", n);
        goto done;
    }

    /* Edge adjacency by sorting (lo, hi, tri). */
    er = thx_malloc(ctx, 3 * nall * sizeof *er);
    par = thx_malloc(ctx, nall * sizeof *par);
    queue = thx_malloc(ctx, nall * sizeof *queue);
    if (!er || !par || !queue) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < nall; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = all[3 * t + k], b = all[3 * t + (k + 1) % 3];
            edge_rec *e = &er[3 * t + k];
            e->lo = a < b ? a : b;
            e->hi = a < b ? b : a;
            e->tri = (int32_t)t;
            e->slot = k;
        }
    qsort(er, 3 * nall, sizeof *er, cmp_edge);
    /* nb[3t + k]: triangle across edge k of t, -1 on the hull */
    int32_t *nb = thx_malloc(ctx, 3 * nall * sizeof *nb);
    if (!nb) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < 3 * nall; i++) nb[i] = -1;
    for (size_t i = 0; i + 1 < 3 * nall; i++)
        if (er[i].lo == er[i + 1].lo && er[i].hi == er[i + 1].hi) {
            nb[3 * er[i].tri + er[i].slot] = er[i + 1].tri;
            nb[3 * er[i + 1].tri + er[i + 1].slot] = er[i].tri;
        }

    /* Parity flood: hull triangles are outside unless the hull edge is a loop
     * edge; crossing a loop edge flips inside/outside. */
    memset(par, -1, nall * sizeof *par);
    size_t qh = 0, qt = 0;
    for (size_t t = 0; t < nall; t++)
        for (int k = 0; k < 3; k++) {
            if (nb[3 * t + k] >= 0 || par[t] >= 0) continue;
            par[t] = (int8_t)is_loop_edge(all[3 * t + k], all[3 * t + (k + 1) % 3], n);
            queue[qt++] = (int32_t)t;
        }
    while (qh < qt) {
        int32_t t = queue[qh++];
        for (int k = 0; k < 3; k++) {
            int32_t o = nb[3 * t + k];
            if (o < 0) continue;
            int8_t want = (int8_t)(par[t] ^ is_loop_edge(all[3 * t + k], all[3 * t + (k + 1) % 3], n));
            if (par[o] < 0) {
                par[o] = want;
                queue[qt++] = o;
            } else if (par[o] != want) {
                free(nb);
                st = thx_error(ctx, THX_EINTERNAL, "cap: inconsistent inside/outside parity at triangle %d", (int)o);
                goto done;
            }
        }
    }
    free(nb);

    /* The paper's check: the centroid of each kept triangle is inside (winding number by crossings,
       the angle sum of inside.h where the centroid is within a hair of the loop). */
    size_t nkeep = 0, disagree = 0;
    chain_index cidx;
    if (chain_index_init(&cidx, loop, n) != 0) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
    for (size_t t = 0; t < nall; t++) {
        const thx_vec2 a = pts[all[3 * t]], b = pts[all[3 * t + 1]], c = pts[all[3 * t + 2]];
        thx_vec2 g = {(a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0};
        double sd = chain_index_sdf(&cidx, g);
        int in = fabs(sd) > 1e-9 ? sd < 0 : thx_loop_inside(loop, n, g, 0.0) == THX_INSIDE;
        if (par[t] < 0) par[t] = (int8_t)in; /* unreachable: the hull triangulation is connected */
        disagree += in != par[t];
        nkeep += par[t] == 1;
    }
    chain_index_free(&cidx);
    if (disagree)
        thx_log(ctx, THX_LOG_DEBUG, "cap: %zu sliver triangle(s) with a centroid on the wrong side; kept by parity",
                disagree);

    keep = thx_malloc(ctx, (nkeep ? nkeep : 1) * 3 * sizeof *keep);
    cnt = thx_calloc(ctx, n, sizeof *cnt);
    if (!keep || !cnt) { st = THX_ENOMEM; goto done; }
    size_t w = 0;
    for (size_t t = 0; t < nall; t++) {
        if (par[t] != 1) continue;
        for (int k = 0; k < 3; k++) {
            int32_t a = all[3 * t + k], b = all[3 * t + (k + 1) % 3];
            keep[3 * w + k] = a;
            if (is_loop_edge(a, b, n)) {
                int32_t lo = a < b ? a : b, hi = a < b ? b : a;
                cnt[(lo == 0 && (size_t)hi == n - 1) ? hi : lo]++;
            }
        }
        w++;
    }
    for (size_t i = 0; i < n; i++)
        if (cnt[i] != 1) {
            st = thx_error(ctx, THX_EINTERNAL, "cap: loop edge %zu-%zu is in %d cap triangles (expected 1)", i,
                           (i + 1) % n, (int)cnt[i]);
            goto done;
        }

    *out_pts = pts;
    *n_out = np;
    *tris = keep;
    *n_tris = nkeep;
    pts = NULL;
    keep = NULL;
done:
    free(pts);
    free(segs);
    free(all);
    free(keep);
    free(cnt);
    free(par);
    free(er);
    free(queue);
    return st;
}
