/*
 * Repair of digitization noise in contours (see thorax/geom/repair.h; paper 3.1,
 * issue 11 item 6). Works loop by loop on the points and their source lines.
 */
#include "thorax/geom/repair.h"
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
void thx_repair_opts_default(thx_repair_opts *o, double spacing)
{
    o->spacing = spacing;
    o->merge_tol = spacing / 10.0;
    o->untangle_tol = spacing;
    o->strict = 0;
}

void thx_repair_log_free(thx_repair_log *log)
{
    if (!log) return;
    for (size_t i = 0; i < log->n; i++) free(log->msg[i]);
    free(log->msg);
    free(log->kind);
    memset(log, 0, sizeof *log);
}

/* The loop being repaired and where it came from (for messages). */
typedef struct {
    thx_ctx *ctx;
    const thx_repair_opts *o;
    thx_repair_log *log;
    const char *path, *surf;
    int layer_no, loop_line;
    size_t loop_no;
    double z;
    thx_loop *lp;
} job;

static int line_of(const job *j, size_t k) { return j->lp->lines ? j->lp->lines[k] : j->loop_line; }

/* One repair of kind `kind`: refused under strict, else logged (unless the log is quiet) and kept. */
static thx_status report(job *j, thx_repair_kind kind, int line, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    char msg[1200];
    snprintf(msg, sizeof msg, "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: %s", j->path, line, j->surf, j->layer_no,
             j->z, j->loop_no, what);
    if (j->o->strict)
        return thx_error(j->ctx, THX_EINPUT, "%s (refused: --strict; without it this is repaired)", msg);
    if (!j->log || !j->log->quiet) thx_log(j->ctx, THX_LOG_WARN, "%s", msg);
    if (j->log) {
        if (j->log->n == j->log->cap) {
            size_t nc = j->log->cap ? 2 * j->log->cap : 16;
            char **nm = thx_realloc(j->ctx, j->log->msg, nc * sizeof *nm);
            if (!nm) return THX_ENOMEM;
            j->log->msg = nm;
            int *nk = thx_realloc(j->ctx, j->log->kind, nc * sizeof *nk);
            if (!nk) return THX_ENOMEM;
            j->log->kind = nk;
            j->log->cap = nc;
        }
        j->log->kind[j->log->n] = (int)kind;
        char *m = thx_malloc(j->ctx, strlen(msg) + 1);
        if (!m) return THX_ENOMEM;
        memcpy(m, msg, strlen(msg) + 1);
        j->log->msg[j->log->n++] = m;
    }
    return THX_OK;
}

/* Removes points [k, k + m) of the loop (indices mod n, m < n) and, if x is not NULL, puts x
 * (with source line `line`) in their place; the loop then starts after the removed run. */
static thx_status splice(thx_ctx *ctx, thx_loop *lp, size_t k, size_t m, const thx_vec2 *x, int line)
{
    size_t n = lp->n, w = 0;
    thx_vec2 *tp = thx_malloc(ctx, n * sizeof *tp);
    int *tl = lp->lines ? thx_malloc(ctx, n * sizeof *tl) : NULL;
    if (!tp || (lp->lines && !tl)) { free(tp); free(tl); return THX_ENOMEM; }
    for (size_t s = 0; s < n - m; s++) {
        size_t i = (k + m + s) % n;
        tp[w] = lp->p[i];
        if (tl) tl[w] = lp->lines[i];
        w++;
    }
    if (x) {
        tp[w] = *x;
        if (tl) tl[w] = line;
        w++;
    }
    memcpy(lp->p, tp, w * sizeof *tp);
    if (tl) memcpy(lp->lines, tl, w * sizeof *tl);
    lp->n = w;
    free(tp);
    free(tl);
    return THX_OK;
}

static double dist(thx_vec2 a, thx_vec2 b) { return hypot(a.x - b.x, a.y - b.y); }

/* 1. The last point equal to the first. */
static thx_status drop_closing(job *j)
{
    thx_loop *lp = j->lp;
    while (lp->n > 1 && lp->p[lp->n - 1].x == lp->p[0].x && lp->p[lp->n - 1].y == lp->p[0].y) {
        THX_CHECK(report(j, THX_REPAIR_CLOSING, line_of(j, lp->n - 1),
                         "the last point (%zu) repeats the first point (%g, %g): dropped (a loop closes "
                         "without repeating its first point)",
                         lp->n, lp->p[0].x, lp->p[0].y));
        lp->n--;
        j->log->closing++;
    }
    return THX_OK;
}

/* 2. Runs of consecutive points within merge_tol of the run's first point (exact repeats always). */
static thx_status merge_near(job *j, int *changed)
{
    thx_loop *lp = j->lp;
    double tol = j->o->merge_tol;
    if (lp->n < 2) return THX_OK;
    /* Start at a point that does not continue a run from its predecessor, so no run wraps. */
    size_t s0 = 0;
    for (size_t t = 0; t < lp->n; t++) {
        size_t prev = (t + lp->n - 1) % lp->n;
        double d = dist(lp->p[prev], lp->p[t]);
        if (d > tol || (tol == 0 && d > 0)) { s0 = t; break; }
        if (t + 1 == lp->n) s0 = 0; /* every point within tol of its predecessor: one run */
    }
    if (s0) THX_CHECK(splice(j->ctx, lp, s0, 0, NULL, 0)); /* rotate: s0 first */
    size_t n = lp->n, w = 0;
    for (size_t i = 0; i < n;) {
        size_t e = i + 1;
        double far = 0;
        while (e < n) {
            double d = dist(lp->p[i], lp->p[e]);
            if (!(d <= tol || d == 0)) break;
            if (d > far) far = d;
            e++;
        }
        if (e - i > 1) {
            thx_vec2 c = {0, 0};
            for (size_t k = i; k < e; k++) { c.x += lp->p[k].x; c.y += lp->p[k].y; }
            c.x /= (double)(e - i);
            c.y /= (double)(e - i);
            int l0 = line_of(j, i), l1 = line_of(j, e - 1);
            if (far == 0)
            {
                if (e - i == 2)
                    THX_CHECK(report(j, THX_REPAIR_MERGED, line_of(j, i + 1), "the point repeats the point before (%g, %g): merged into one",
                                     lp->p[i].x, lp->p[i].y));
                else
                    THX_CHECK(report(j, THX_REPAIR_MERGED, line_of(j, i + 1), "%zu points (lines %d-%d) repeat the point before (%g, %g): merged into one",
                                     e - i - 1, line_of(j, i + 1), l1, lp->p[i].x, lp->p[i].y));
            }
            else
                THX_CHECK(report(j, THX_REPAIR_MERGED, l0,
                                 "%zu near-coincident points (lines %d-%d, %.3g mm apart, within the merge tolerance "
                                 "%g mm) merged into their centroid (%g, %g)",
                                 e - i, l0, l1, far, tol, c.x, c.y));
            j->log->merged += e - i - 1;
            lp->p[w] = c;
            if (lp->lines) lp->lines[w] = l0;
            *changed = 1;
        } else {
            lp->p[w] = lp->p[i];
            if (lp->lines) lp->lines[w] = lp->lines[i];
        }
        w++;
        i = e;
    }
    lp->n = w;
    /* The last run may end within tol of the first point (after the rotation: only by merging). */
    while (lp->n > 1 && (dist(lp->p[lp->n - 1], lp->p[0]) == 0 || dist(lp->p[lp->n - 1], lp->p[0]) <= tol)) {
        THX_CHECK(report(j, THX_REPAIR_MERGED, line_of(j, lp->n - 1),
                         "the last point (%zu) lies %.3g mm from the first point (within the merge tolerance "
                         "%g mm): merged into it",
                         lp->n, dist(lp->p[lp->n - 1], lp->p[0]), tol));
        lp->n--;
        j->log->merged++;
        *changed = 1;
    }
    return THX_OK;
}

/* 3. A point where the loop folds straight back (its edges collinear and overlapping). */
static thx_status remove_spikes(job *j, int *changed)
{
    thx_loop *lp = j->lp;
    size_t from = 0; /* a removal can only make a spike of its neighbours: scan on from there */
    while (lp->n >= 3) {
        size_t n = lp->n, hit = n;
        for (size_t i = from < n ? from : 0; i < n; i++) {
            thx_vec2 a = lp->p[(i + n - 1) % n], b = lp->p[i], c = lp->p[(i + 1) % n];
            if (thx_orient2d(&a.x, &b.x, &c.x) == 0 && (a.x - b.x) * (c.x - b.x) + (a.y - b.y) * (c.y - b.y) > 0) {
                hit = i;
                break;
            }
        }
        if (hit == n) break;
        THX_CHECK(report(j, THX_REPAIR_SPIKE, line_of(j, hit), "the point (%g, %g) is a spike (the loop folds straight back on itself "
                                             "there): removed",
                         lp->p[hit].x, lp->p[hit].y));
        /* remove point `hit` in place (the order is kept, so the scan can go on before it) */
        memmove(lp->p + hit, lp->p + hit + 1, (lp->n - hit - 1) * sizeof *lp->p);
        if (lp->lines) memmove(lp->lines + hit, lp->lines + hit + 1, (lp->n - hit - 1) * sizeof *lp->lines);
        lp->n--;
        from = hit > 0 ? hit - 1 : 0;
        if (hit == 0 || hit >= lp->n) from = 0; /* the wrap: its neighbours are at both ends */
        j->log->spikes++;
        *changed = 1;
    }
    return THX_OK;
}

/* A common point of segments a-b and c-d, which touch. */
static thx_vec2 touch_point(thx_vec2 a, thx_vec2 b, thx_vec2 c, thx_vec2 d)
{
    double rx = b.x - a.x, ry = b.y - a.y, sx = d.x - c.x, sy = d.y - c.y;
    double den = rx * sy - ry * sx;
    if (den != 0) {
        double t = ((c.x - a.x) * sy - (c.y - a.y) * sx) / den;
        if (t < 0) t = 0;
        if (t > 1) t = 1;
        thx_vec2 x = {a.x + t * rx, a.y + t * ry};
        return x;
    }
    /* parallel (collinear overlap): an endpoint of one lying on the other */
    const thx_vec2 *cand[4] = {&c, &d, &a, &b};
    for (int k = 0; k < 4; k++) {
        thx_vec2 p = *cand[k];
        const thx_vec2 *u = k < 2 ? &a : &c, *v = k < 2 ? &b : &d;
        if (thx_segments_touch(&p.x, &p.x, &u->x, &v->x)) return p;
    }
    return c;
}

/* 4. One self-crossing: cut off its small side, or refuse. *found = 0 when there is none. */
static thx_status untangle_one(job *j, int *found)
{
    thx_loop *lp = j->lp;
    size_t n = lp->n, e1 = 0, e2 = 0;
    *found = 0;
    int r = thx_loop_touch(&lp->p[0].x, n, &e1, &e2);
    if (r < 0) return thx_error(j->ctx, THX_ENOMEM, "out of memory");
    if (r == 0) return THX_OK;
    *found = 1;
    thx_vec2 a = lp->p[e1], b = lp->p[(e1 + 1) % n], c = lp->p[e2], d = lp->p[(e2 + 1) % n];
    thx_vec2 x = touch_point(a, b, c, d);
    /* side A: points e1+1 .. e2; side B: points e2+1 .. e1 (mod n) */
    size_t ma = e2 - e1, mb = n - ma;
    double ra = 0, rb = 0;
    for (size_t k = 0; k < ma; k++) ra = fmax(ra, dist(lp->p[(e1 + 1 + k) % n], x));
    for (size_t k = 0; k < mb; k++) rb = fmax(rb, dist(lp->p[(e2 + 1 + k) % n], x));
    int cut_a = ra <= rb;
    double rr = cut_a ? ra : rb;
    size_t m = cut_a ? ma : mb, k0 = cut_a ? e1 + 1 : e2 + 1;
    int line = line_of(j, e1);
    if (!(rr <= j->o->untangle_tol) || n - m + 1 < 3)
        return thx_error(j->ctx, THX_EINPUT,
                         "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: loop intersects itself (the edge from line %d "
                         "crosses the edge from line %d at (%g, %g)); the smaller side reaches %.3g mm from the crossing, "
                         "beyond the untangle tolerance %g mm, so it is not repaired",
                         j->path, line, j->surf, j->layer_no, j->z, j->loop_no, line, line_of(j, e2), x.x, x.y, rr,
                         j->o->untangle_tol);
    /* Area of the cut-off loop (x and its points), for the report. */
    double area = 0;
    thx_vec2 prev = x;
    for (size_t k = 0; k <= m; k++) {
        thx_vec2 q = k < m ? lp->p[(k0 + k) % n] : x;
        area += prev.x * q.y - q.x * prev.y;
        prev = q;
    }
    area = fabs(area) / 2;
    THX_CHECK(report(j, THX_REPAIR_UNTANGLED, line,
                     "loop crosses itself (the edge from line %d crosses the edge from line %d at (%g, %g)): the "
                     "small loop of %zu point%s (within %.3g mm of the crossing, %.3g mm^2) cut off",
                     line, line_of(j, e2), x.x, x.y, m, m == 1 ? "" : "s", rr, area));
    THX_CHECK(splice(j->ctx, lp, k0 % n, m, &x, line_of(j, k0 % n)));
    j->log->untangled++;
    return THX_OK;
}

static void loop_box(const thx_loop *lp, double box[4])
{
    box[0] = box[2] = INFINITY;
    box[1] = box[3] = -INFINITY;
    for (size_t k = 0; k < lp->n; k++) {
        box[0] = fmin(box[0], lp->p[k].x); box[1] = fmax(box[1], lp->p[k].x);
        box[2] = fmin(box[2], lp->p[k].y); box[3] = fmax(box[3], lp->p[k].y);
    }
}

/* A loop that crosses itself more often than this is not digitization noise (and each untangling
 * costs a sweep of the loop: the bound keeps the repair O(n log n)). */
#define MAX_UNTANGLE 64

static thx_status repair_loop(job *j, double *extent)
{
    double box[4];
    loop_box(j->lp, box);
    *extent = hypot(box[1] - box[0], box[3] - box[2]);
    THX_CHECK(drop_closing(j));
    size_t untangled = 0;
    for (;;) { /* each round removes at least one point or ends */
        int changed = 0, found = 0;
        THX_CHECK(merge_near(j, &changed));
        if (j->lp->n < 3) break;
        THX_CHECK(remove_spikes(j, &changed));
        if (j->lp->n < 3) break;
        if (untangled == MAX_UNTANGLE) {
            size_t e1 = 0, e2 = 0;
            int r = thx_loop_touch(&j->lp->p[0].x, j->lp->n, &e1, &e2);
            if (r < 0) return thx_error(j->ctx, THX_ENOMEM, "out of memory");
            if (r)
                return thx_error(j->ctx, THX_EINPUT,
                                 "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: the loop crosses itself more than %d "
                                 "times (here the edge from line %d crosses the edge from line %d): that is not "
                                 "digitization noise, so it is not repaired",
                                 j->path, line_of(j, e1), j->surf, j->layer_no, j->z, j->loop_no, MAX_UNTANGLE,
                                 line_of(j, e1), line_of(j, e2));
            break;
        }
        THX_CHECK(untangle_one(j, &found));
        if (!found || j->lp->n < 3) break;
        untangled++;
    }
    return THX_OK; /* a loop left with fewer than 3 points is dropped or refused by resolve_tiny */
}

/* Is point q inside the closed loop p (crossing number; points on the boundary count either way)? */
static int point_in_loop(thx_vec2 q, const thx_loop *lp)
{
    int in = 0;
    for (size_t i = 0, j = lp->n - 1; i < lp->n; j = i++) {
        thx_vec2 a = lp->p[i], b = lp->p[j];
        if ((a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x) in = !in;
    }
    return in;
}

/* 5. Holes: a loop inside another loop of its surface on the same layer. The build laces holes to
 * holes (src/geom/build.c, rloop.hole); a hole narrower than the node spacing (width 2 area /
 * perimeter: a groove the layer cuts across, which the nodes could not resolve) is dropped and
 * reported; a wider one is kept. */
static thx_status drop_holes(thx_ctx *ctx, const thx_contours *c, thx_contour_surface *cs, size_t l,
                             const thx_repair_opts *o, double spacing, thx_repair_log *log, double *extent)
{
    thx_contour_layer *L = &cs->layers[l];
    if (L->n_loops < 2) return THX_OK;
    double *box = thx_malloc(ctx, L->n_loops * 4 * sizeof *box);
    if (!box) return THX_ENOMEM;
    for (size_t i = 0; i < L->n_loops; i++) loop_box(&L->loops[i], box + 4 * i);
    thx_status st = THX_OK;
    for (size_t i = 0; i < L->n_loops && st == THX_OK; i++) {
        const thx_loop *b = &L->loops[i];
        const double *bb = box + 4 * i;
        size_t outer = L->n_loops;
        if (b->n < 3) continue; /* collapsed by the merge: resolve_tiny's */
        for (size_t k = 0; k < L->n_loops && outer == L->n_loops; k++) {
            const double *ab = box + 4 * k;
            if (k == i || L->loops[k].n < 3 || bb[0] < ab[0] || bb[1] > ab[1] || bb[2] < ab[2] || bb[3] > ab[3]) continue;
            if (point_in_loop(b->p[0], &L->loops[k])) outer = k;
        }
        if (outer == L->n_loops) continue;
        double area = fabs(thx_loop_area(b->p, b->n)), per = 0;
        for (size_t k = 0; k < b->n; k++) per += dist(b->p[k], b->p[(k + 1) % b->n]);
        double width = per > 0 ? 2 * area / per : 0;
        job j = {ctx, o, log, c->path[0] ? c->path : "<contours>", cs->name, L->index >= 0 ? L->index + 1 : (int)l + 1,
                 b->line ? b->line : L->line, i + 1, L->z, &L->loops[i]};
        if (!(width < spacing)) continue; /* a hole the nodes resolve: kept */
        st = report(&j, THX_REPAIR_HOLE, j.loop_line,
                    "the loop lies inside loop %zu of the same surface (a hole of %.3g mm^2, %.3g mm wide: "
                    "narrower than the node spacing %g mm, which cannot resolve it): dropped",
                    outer + 1, area, width, spacing);
        if (st != THX_OK) break;
        free(L->loops[i].p);
        free(L->loops[i].lines);
        memmove(&L->loops[i], &L->loops[i + 1], (L->n_loops - i - 1) * sizeof *L->loops);
        memmove(box + 4 * i, box + 4 * (i + 1), (L->n_loops - i - 1) * 4 * sizeof *box);
        memmove(extent + i, extent + i + 1, (L->n_loops - i - 1) * sizeof *extent);
        L->n_loops--;
        log->holes++;
        i--;
    }
    free(box);
    return st;
}

/* Is point q inside a loop (of 3 points or more) of layer L other than loop `not`? Its index, or L->n_loops. */
static size_t inside_layer(thx_vec2 q, const thx_contour_layer *L, size_t not)
{
    for (size_t k = 0; k < L->n_loops; k++)
        if (k != not && L->loops[k].n >= 3 && point_in_loop(q, &L->loops[k])) return k;
    return L->n_loops;
}

static size_t alive_loops(const thx_contour_layer *L)
{
    size_t m = 0;
    for (size_t k = 0; k < L->n_loops; k++) m += L->loops[k].n >= 3;
    return m;
}

/* 6. Loops the merge left with fewer than 3 points (issue 24: a plane that just grazes the body's
 * end or a bump of it cuts a sliver smaller than the merge tolerance). Such a loop is dropped
 * where that is what the plane missing the body would give: on a layer at an end of the surface's
 * stack (a layer left without loops is dropped, and the surface is capped at its neighbour); inside
 * another loop of its layer (a hole too small to resolve); on a layer between others, where no loop
 * of the layer below or none of the layer above encloses it (a branch of the surface ends, or
 * begins, at it: the branch is capped at its next layer). It is refused (the file is broken, or
 * dropping would change the surface's shape) when it would leave the surface fewer than 2 layers
 * (e.g. it is the surface's only loop), when it is the only loop of a layer between others (the
 * surface would vanish and reappear), and when loops of both neighbouring layers enclose it (the
 * surface narrows to it: dropping it would cut the surface in two). extent[base[l] + i]: the size of
 * loop i of layer l before the repair (its bounding box's diagonal). */
static thx_status resolve_tiny(thx_ctx *ctx, const thx_contours *c, thx_contour_surface *cs, const thx_repair_opts *o,
                               thx_repair_log *log, const double *extent, const size_t *base)
{
    size_t nl = cs->n_layers, n_tiny = 0, n_loops = 0;
    for (size_t l = 0; l < nl; l++) {
        n_loops += cs->layers[l].n_loops;
        n_tiny += cs->layers[l].n_loops - alive_loops(&cs->layers[l]);
    }
    if (!n_tiny) return THX_OK;
    const char *path = c->path[0] ? c->path : "<contours>";
    /* the layers that keep a loop: first .. last (those outside are dropped whole) */
    size_t first = 0, last = nl;
    while (first < nl && !alive_loops(&cs->layers[first])) first++;
    while (last > first && !alive_loops(&cs->layers[last - 1])) last--;
    /* pass 0 decides (and refuses), pass 1 reports and drops */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t l = 0; l < nl; l++) {
            thx_contour_layer *L = &cs->layers[l];
            for (size_t i = 0; i < L->n_loops; i++) {
                size_t e = base[l] + i;
                thx_loop *lp = &L->loops[i];
                if (lp->n >= 3) continue;
                job j = {ctx, o, log, path, cs->name, L->index >= 0 ? L->index + 1 : (int)l + 1,
                         lp->line ? lp->line : L->line, i + 1, L->z, lp};
                thx_vec2 q = lp->p[0];
                if (lp->n == 2) { q.x = 0.5 * (lp->p[0].x + lp->p[1].x); q.y = 0.5 * (lp->p[0].y + lp->p[1].y); }
                char why[300] = "";
                size_t hole = l >= first && l < last ? inside_layer(q, L, i) : L->n_loops;
                if (last - first < 2) {
                    if (n_loops == 1) snprintf(why, sizeof why, "it is the surface's only loop");
                    else snprintf(why, sizeof why, "dropping the surface's loops smaller than the merge tolerance "
                                                   "would leave it %zu layer%s (at least 2 needed)",
                                  last - first, last - first == 1 ? "" : "s");
                } else if (l > first && l + 1 < last && !alive_loops(L)) {
                    snprintf(why, sizeof why, "it is the only loop of its layer, which lies between layers that keep "
                                              "loops (the surface would vanish and reappear)");
                } else if (l > first && l + 1 < last && hole == L->n_loops &&
                           inside_layer(q, &cs->layers[l - 1], SIZE_MAX) < cs->layers[l - 1].n_loops &&
                           inside_layer(q, &cs->layers[l + 1], SIZE_MAX) < cs->layers[l + 1].n_loops) {
                    snprintf(why, sizeof why, "loops of the layers below (z=%g) and above (z=%g) both enclose it (the "
                                              "surface narrows to it: dropping it would cut the surface in two)",
                             cs->layers[l - 1].z, cs->layers[l + 1].z);
                }
                if (why[0]) {
                    if (pass == 1) continue; /* not reached: pass 0 refused */
                    return thx_error(ctx, THX_EINPUT,
                                     "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: fewer than 3 distinct points are "
                                     "left after merging points within %g mm (the loop is smaller than the merge "
                                     "tolerance: %.3g mm across); it is not dropped: %s",
                                     path, j.loop_line, cs->name, j.layer_no, L->z, i + 1, o->merge_tol, extent[e], why);
                }
                if (pass == 0) continue;
                if (l < first || l >= last)
                    snprintf(why, sizeof why, "its layer keeps no loop and is dropped: the surface ends at z=%g, "
                                              "capped there, as if the plane had missed the body",
                             l < first ? cs->layers[first].z : cs->layers[last - 1].z);
                else if (hole < L->n_loops)
                    snprintf(why, sizeof why, "it lies inside loop %zu of its layer (a hole too small to resolve)",
                             hole + 1);
                else if (l == first || l + 1 == last)
                    snprintf(why, sizeof why, "its layer is the surface's %s: the layer's other loops are kept",
                             l == first ? "first" : "last");
                else {
                    /* the side with no enclosing loop, and the layer the branch is capped on */
                    int below = inside_layer(q, &cs->layers[l - 1], SIZE_MAX) < cs->layers[l - 1].n_loops;
                    snprintf(why, sizeof why, "no loop of the layer %s (z=%g) encloses it: a branch of the surface "
                                              "ends at it, and is capped at z=%g instead",
                             below ? "above" : "below", cs->layers[below ? l + 1 : l - 1].z,
                             cs->layers[below ? l - 1 : l + 1].z);
                }
                THX_CHECK(report(&j, THX_REPAIR_TINY, j.loop_line,
                                 "%zu distinct point%s left after merging points within %g mm (the loop, %.3g mm "
                                 "across, is smaller than the merge tolerance): dropped (%s)",
                                 lp->n, lp->n == 1 ? " is" : "s are", o->merge_tol, extent[e], why));
                log->tiny++;
            }
        }
    }
    /* drop them: the collapsed loops, then the layers left empty (at the ends only) */
    for (size_t l = 0; l < nl; l++) {
        thx_contour_layer *L = &cs->layers[l];
        size_t w = 0;
        for (size_t i = 0; i < L->n_loops; i++) {
            if (L->loops[i].n >= 3) { L->loops[w++] = L->loops[i]; continue; }
            free(L->loops[i].p);
            free(L->loops[i].lines);
        }
        L->n_loops = w;
        if (!w) { free(L->loops); L->loops = NULL; }
    }
    memmove(cs->layers, cs->layers + first, (last - first) * sizeof *cs->layers);
    cs->n_layers = last - first;
    return THX_OK;
}

thx_status thx_contours_repair(thx_ctx *ctx, thx_contours *c, const thx_repair_opts *o, thx_repair_log *log)
{
    thx_repair_log dummy = {0};
    if (!log) log = &dummy;
    THX_CHECK(thx_contours_validate_structure(ctx, c));
    thx_status st = THX_OK;
    for (size_t s = 0; s < c->n_surfaces && st == THX_OK; s++) {
        thx_contour_surface *cs = &c->surf[s];
        size_t n_loops = 0;
        size_t *base = thx_malloc(ctx, (cs->n_layers + 1) * sizeof *base);
        if (!base) { st = THX_ENOMEM; break; }
        for (size_t l = 0; l < cs->n_layers; l++) { base[l] = n_loops; n_loops += cs->layers[l].n_loops; }
        double *extent = thx_malloc(ctx, (n_loops ? n_loops : 1) * sizeof *extent);
        if (!extent) { free(base); st = THX_ENOMEM; break; }
        for (size_t l = 0; l < cs->n_layers && st == THX_OK; l++) {
            thx_contour_layer *L = &cs->layers[l];
            for (size_t i = 0; i < L->n_loops && st == THX_OK; i++) {
                job j = {ctx, o, log, c->path[0] ? c->path : "<contours>", cs->name,
                         L->index >= 0 ? L->index + 1 : (int)l + 1, L->loops[i].line ? L->loops[i].line : L->line,
                         i + 1, L->z, &L->loops[i]};
                st = repair_loop(&j, &extent[base[l] + i]);
            }
            if (st == THX_OK) st = drop_holes(ctx, c, cs, l, o, o->spacing, log, extent + base[l]);
        }
        if (st == THX_OK) st = resolve_tiny(ctx, c, cs, o, log, extent, base);
        free(extent);
        free(base);
    }
    if (log == &dummy) thx_repair_log_free(&dummy);
    if (st == THX_OK) st = thx_contours_validate(ctx, c);
    return st;
}
