/*
 * Surfaces from contours, steps 4 and 5 (src/geom/build.c is the pipeline; build_internal.h what the two
 * share): the triangles of a slice checked (crossings, edges used more than twice, mended where they can
 * be), every triangle oriented outward by the paper's test reconciled over the mesh, and nearly flat
 * triangles swapped with a neighbour.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/tri_intersect.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include "geom/build_internal.h"

/* Do two of the nt triangles tri (node ids into xyz) intersect beyond the nodes they share?
 * A sweep over the triangles' x extents, exact test per candidate pair (thx_triangles_intersect);
 * degenerate (collinear) triangles are skipped. -1 out of memory. */
typedef struct { double x0, x1; size_t t; } tri_span;
static int cmp_span(const void *a, const void *b)
{
    const tri_span *p = a, *q = b;
    if (p->x0 != q->x0) return (p->x0 > q->x0) - (p->x0 < q->x0);
    return (p->t > q->t) - (p->t < q->t);
}

int build_tris_cross(const double *xyz, const int32_t *tri, size_t nt)
{
    tri_span *sp = malloc((nt ? nt : 1) * sizeof *sp);
    double *box = malloc((nt ? nt : 1) * 6 * sizeof *box); /* x0 x1 y0 y1 z0 z1 */
    if (!sp || !box) { free(sp); free(box); return -1; }
    size_t m = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, span[3] = {0, 0, 0};
    for (size_t t = 0; t < nt; t++) {
        const double *a = xyz + 3 * (size_t)tri[3 * t], *b = xyz + 3 * (size_t)tri[3 * t + 1], *c = xyz + 3 * (size_t)tri[3 * t + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double cr = fabs(u[1] * v[2] - u[2] * v[1]) + fabs(u[2] * v[0] - u[0] * v[2]) + fabs(u[0] * v[1] - u[1] * v[0]);
        if (!(cr > 0)) continue;
        double *bx = box + 6 * t;
        for (int k = 0; k < 3; k++) {
            bx[2 * k] = fmin(a[k], fmin(b[k], c[k]));
            bx[2 * k + 1] = fmax(a[k], fmax(b[k], c[k]));
            lo[k] = fmin(lo[k], bx[2 * k]);
            hi[k] = fmax(hi[k], bx[2 * k + 1]);
            span[k] += bx[2 * k + 1] - bx[2 * k];
        }
        sp[m++].t = t;
    }
    /* Sweep along the axis where the triangles overlap least (extent over the mean extent of a
       triangle: along a tall comb's teeth, not across them, issue 24), so a triangle meets few others. */
    int ax = 0;
    double bestr = -1;
    for (int k = 0; k < 3; k++) {
        double r = m ? (hi[k] - lo[k]) / (span[k] / (double)m + 1e-300) : 0;
        if (r > bestr) { bestr = r; ax = k; }
    }
    for (size_t i = 0; i < m; i++) {
        sp[i].x0 = box[6 * sp[i].t + 2 * ax];
        sp[i].x1 = box[6 * sp[i].t + 2 * ax + 1];
    }
    qsort(sp, m, sizeof *sp, cmp_span);
    int hit = 0;
    for (size_t i = 0; i < m && !hit; i++)
        for (size_t j = i + 1; j < m && sp[j].x0 <= sp[i].x1 && !hit; j++) {
            const double *p = box + 6 * sp[i].t, *q = box + 6 * sp[j].t;
            if (p[1] < q[0] || q[1] < p[0] || p[3] < q[2] || q[3] < p[2] || p[5] < q[4] || q[5] < p[4]) continue;
            hit = thx_triangles_intersect(xyz, tri + 3 * sp[i].t, tri + 3 * sp[j].t);
        }
    free(sp);
    free(box);
    return hit;
}

/* Does an edge lie in three or more of the nt triangles (a lacing that is no manifold: a branching
 * chain joined to one node of the other chain twice)? -1 out of memory. */
typedef struct { int32_t a, b; } slice_edge;
static int cmp_slice_edge(const void *x, const void *y)
{
    const slice_edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

int build_edge_overused(const int32_t *tri, size_t nt)
{
    slice_edge *e = malloc((nt ? 3 * nt : 1) * sizeof *e);
    if (!e) return -1;
    for (size_t k = 0; k < 3 * nt; k++) {
        int32_t a = tri[k], b = tri[k % 3 == 2 ? k - 2 : k + 1];
        e[k] = (slice_edge){a < b ? a : b, a < b ? b : a};
    }
    qsort(e, 3 * nt, sizeof *e, cmp_slice_edge);
    int bad = 0;
    for (size_t k = 0; k + 2 < 3 * nt && !bad; k++) bad = e[k].a == e[k + 2].a && e[k].b == e[k + 2].b;
    free(e);
    return bad;
}

/* Layered inside test: signed distance at p (negative inside), from the chains
 * of the slice containing p.z, interpolated in z. Outside the layer range: +inf. */
static double layered_sdf(const rlayer *layers, size_t nl, const slice *slices, thx_vec3 p)
{
    if (nl == 0 || p.z < layers[0].z || p.z > layers[nl - 1].z) return INFINITY;
    if (nl == 1) return INFINITY;
    size_t lo = 0, hi = nl - 1;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (layers[mid].z <= p.z) lo = mid; else hi = mid;
    }
    const slice *s = &slices[lo];
    double t = (p.z - layers[lo].z) / (layers[lo + 1].z - layers[lo].z);
    thx_vec2 q = {p.x, p.y};
    double best[2] = {INFINITY, INFINITY}; /* the outer groups' solids, the holes' */
    for (size_t g = 0; g < s->n_groups; g++) {
        double d = (1 - t) * chain_index_sdf(&s->ga[g].ix, q) + t * chain_index_sdf(&s->gb[g].ix, q);
        int h = s->ga[g].hole;
        if (d < best[h]) best[h] = d;
    }
    return fmax(best[0], -best[1]); /* inside the outer solids and outside the holes */
}

typedef struct { int32_t a, b; int32_t t; } edge_rec;
static int cmp_edge(const void *x, const void *y)
{
    const edge_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->t - q->t;
}

/* An edge (u, v) in three or more triangles of a slice's lacing comes from a bridge node (a
 * branching chain visits it twice) joined to the same node of the other chain on both visits,
 * the small loop between fanned to that node. Each such edge is mended by flipping it in two of
 * its triangles, (u, v, x) and (v, u, y) -> (u, x, y) and (v, x, y): x and y on different layers,
 * the new edge x-y not in the lacing yet, and no triangle crossing another after the flip. 1 when
 * every overused edge is mended, 0 when one cannot be, -1 out of memory. */
int build_mend_overused(const double *xyz, int32_t *tri, size_t nt)
{
    for (int round = 0; round < 16; round++) {
        edge_rec *e = malloc((nt ? 3 * nt : 1) * sizeof *e);
        if (!e) return -1;
        for (size_t k = 0; k < 3 * nt; k++) {
            int32_t a = tri[k], b = tri[k % 3 == 2 ? k - 2 : k + 1];
            e[k] = (edge_rec){a < b ? a : b, a < b ? b : a, (int32_t)(k / 3)};
        }
        qsort(e, 3 * nt, sizeof *e, cmp_edge);
        size_t at = 3 * nt, cnt = 0;
        for (size_t k = 0; k + 2 < 3 * nt; k++)
            if (e[k].a == e[k + 2].a && e[k].b == e[k + 2].b) { at = k; break; }
        if (at == 3 * nt) { free(e); return 1; }
        int32_t u = e[at].a, v = e[at].b, ts[8];
        while (at + cnt < 3 * nt && cnt < 8 && e[at + cnt].a == u && e[at + cnt].b == v) { ts[cnt] = e[at + cnt].t; cnt++; }
        int mended = 0;
        for (size_t i = 0; i < cnt && !mended; i++)
            for (size_t j = i + 1; j < cnt && !mended; j++) {
                int32_t *ti = tri + 3 * (size_t)ts[i], *tj = tri + 3 * (size_t)ts[j], x = -1, y = -1;
                for (int q = 0; q < 3; q++) {
                    if (ti[q] != u && ti[q] != v) x = ti[q];
                    if (tj[q] != u && tj[q] != v) y = tj[q];
                }
                if (x < 0 || y < 0 || x == y || xyz[3 * (size_t)x + 2] == xyz[3 * (size_t)y + 2]) continue;
                edge_rec key = {x < y ? x : y, x < y ? y : x, -1};
                int exists = 0;
                for (size_t k = 0; k < 3 * nt && !exists; k++) exists = e[k].a == key.a && e[k].b == key.b;
                if (exists) continue;
                int32_t oi[3] = {ti[0], ti[1], ti[2]}, oj[3] = {tj[0], tj[1], tj[2]};
                ti[0] = u; ti[1] = x; ti[2] = y;
                tj[0] = v; tj[1] = y; tj[2] = x;
                int c = build_tris_cross(xyz, tri, nt);
                if (c < 0) { free(e); return -1; }
                if (c == 0) { mended = 1; break; }
                for (int q = 0; q < 3; q++) { ti[q] = oi[q]; tj[q] = oj[q]; }
            }
        free(e);
        if (!mended) return 0;
    }
    return 0;
}

/*
 * Orientation (paper 3.2, "The final step ..."). Every triangle casts a vote
 * from the paper's test: both candidate normal endpoints (at the centroid, then
 * near each vertex, at decreasing distances) are classified against the
 * surface; the one outside gives the outward side. Votes are then reconciled
 * with the mesh: triangles sharing an edge must traverse it in opposite
 * directions, which fixes each connected component's orientation up to one
 * global choice, and that choice is the majority of the component's votes.
 * This stores every triangle counterclockwise seen from outside even where an
 * individual test was undecided or fooled (a narrow slot, a fold), and the
 * number of overruled votes is reported.
 */
thx_status build_orient(thx_ctx *ctx, thx_surface *s, const rlayer *layers, size_t nl, const slice *slices,
                        double spacing, size_t no_test_from, thx_surfaces_stats *stats)
{
    size_t nt = s->n_tris;
    thx_status st = THX_OK;
    signed char *vote = thx_calloc(ctx, nt ? nt : 1, 1); /* +1 keep, -1 flip, 0 undecided */
    signed char *rel = NULL;                              /* per adjacency: +1 same decision, -1 opposite */
    int32_t *nbr = NULL, *queue = NULL, *flip = NULL;
    edge_rec *e = NULL;
    if (!vote) return THX_ENOMEM;
    double delta = 0.25 * spacing;
    long by_test = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : by_test)
    for (long t = 0; t < (long)nt; t++) {
        if ((size_t)t >= no_test_from) continue; /* step 3c's in-plane triangles: from their neighbours */
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 P[3] = {thx_surface_node(s, (size_t)v[0]), thx_surface_node(s, (size_t)v[1]), thx_surface_node(s, (size_t)v[2])};
        thx_vec3 nrm = thx_v3_cross(thx_v3_sub(P[1], P[0]), thx_v3_sub(P[2], P[0]));
        double len = thx_v3_norm(nrm);
        if (!(len > 0)) continue;
        nrm = thx_v3_scale(nrm, 1.0 / len);
        thx_vec3 c = thx_v3_scale(thx_v3_add(thx_v3_add(P[0], P[1]), P[2]), 1.0 / 3.0);
        /* Candidate base points: the centroid, then the paper's vertices (pulled slightly toward the centroid). */
        thx_vec3 base[4] = {c, thx_v3_add(P[0], thx_v3_scale(thx_v3_sub(c, P[0]), 0.3)),
                            thx_v3_add(P[1], thx_v3_scale(thx_v3_sub(c, P[1]), 0.3)),
                            thx_v3_add(P[2], thx_v3_scale(thx_v3_sub(c, P[2]), 0.3))};
        int d = 0;
        for (int scale = 0; scale < 3 && !d; scale++) {
            double dl = delta / (double)(1 << scale);
            for (int b = 0; b < 4 && !d; b++) {
                double dp = layered_sdf(layers, nl, slices, thx_v3_add(base[b], thx_v3_scale(nrm, dl)));
                double dm = layered_sdf(layers, nl, slices, thx_v3_sub(base[b], thx_v3_scale(nrm, dl)));
                if (dp > 0 && dm < 0) d = 1;       /* +normal endpoint outside: already outward */
                else if (dp < 0 && dm > 0) d = -1; /* the other one is outside: flip */
            }
        }
        vote[t] = (signed char)d;
        if (d) by_test++;
    }
    /* Edge adjacency: sort the 3 nt half-edges by their undirected key. */
    e = thx_malloc(ctx, 3 * (nt ? nt : 1) * sizeof *e);
    nbr = thx_malloc(ctx, 3 * (nt ? nt : 1) * sizeof *nbr);
    rel = thx_malloc(ctx, 3 * (nt ? nt : 1));
    queue = thx_malloc(ctx, (nt ? nt : 1) * sizeof *queue);
    flip = thx_calloc(ctx, nt ? nt : 1, sizeof *flip); /* 0 = unvisited, +1 keep, -1 flip (relative, then final) */
    if (!e || !nbr || !rel || !queue || !flip) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            e[3 * t + k].a = a < b ? a : b;
            e[3 * t + k].b = a < b ? b : a;
            e[3 * t + k].t = (int32_t)(a < b ? (int32_t)t : -(int32_t)t - 1); /* sign: direction of traversal */
            nbr[3 * t + k] = -1;
        }
    qsort(e, 3 * nt, sizeof *e, cmp_edge);
    for (size_t k = 0; k < 3 * nt;) {
        size_t j = k + 1;
        while (j < 3 * nt && e[j].a == e[k].a && e[j].b == e[k].b) j++;
        if (j - k == 2) { /* a manifold edge: link the two triangles */
            int32_t t1 = e[k].t >= 0 ? e[k].t : -e[k].t - 1, t2 = e[k + 1].t >= 0 ? e[k + 1].t : -e[k + 1].t - 1;
            int same_dir = (e[k].t >= 0) == (e[k + 1].t >= 0);
            for (int q = 0; q < 3; q++) {
                int32_t a = s->tri[3 * t1 + q], b = s->tri[3 * t1 + (q + 1) % 3];
                if ((a < b ? a : b) == e[k].a && (a < b ? b : a) == e[k].b) { nbr[3 * t1 + q] = t2; rel[3 * t1 + q] = same_dir ? -1 : 1; }
                a = s->tri[3 * t2 + q]; b = s->tri[3 * t2 + (q + 1) % 3];
                if ((a < b ? a : b) == e[k].a && (a < b ? b : a) == e[k].b) { nbr[3 * t2 + q] = t1; rel[3 * t2 + q] = same_dir ? -1 : 1; }
            }
        }
        k = j;
    }
    /* Components: propagate relative decisions, then let the votes choose the global sign. */
    size_t conflicts = 0, overruled = 0;
    for (size_t root = 0; root < nt; root++) {
        if (flip[root]) continue;
        size_t head = 0, tail = 0, start = 0;
        flip[root] = 1;
        queue[tail++] = (int32_t)root;
        long score = 0;
        while (head < tail) {
            int32_t t = queue[head++];
            score += vote[t] * flip[t];
            for (int q = 0; q < 3; q++) {
                int32_t u = nbr[3 * t + q];
                if (u < 0) continue;
                int want = flip[t] * rel[3 * t + q];
                if (!flip[u]) { flip[u] = want; queue[tail++] = u; }
                else if (flip[u] != want) conflicts++;
            }
        }
        int sign = score < 0 ? -1 : 1;
        for (size_t k = start; k < tail; k++) {
            int32_t t = queue[k];
            flip[t] *= sign;
            if (vote[t] && vote[t] != flip[t]) overruled++;
        }
    }
    size_t flipped = 0;
    for (size_t t = 0; t < nt; t++)
        if (flip[t] < 0) {
            int32_t x = s->tri[3 * t + 1];
            s->tri[3 * t + 1] = s->tri[3 * t + 2];
            s->tri[3 * t + 2] = x;
            flipped++;
        }
    stats->orient_by_test = (size_t)by_test - overruled;
    stats->orient_by_neighbours = nt - (size_t)by_test + overruled;
    stats->orient_flipped = flipped;
    stats->orient_overruled = overruled;
    if (conflicts) st = thx_error(ctx, THX_EGEOM, "surface \"%s\": the triangles cannot be oriented consistently (%zu conflicting edges: not an orientable manifold)", s->name, conflicts / 2);
done:
    free(vote);
    free(e);
    free(nbr);
    free(rel);
    free(queue);
    free(flip);
    return st;
}

/* ---- 5. flat triangles ---- */

#define FLAT_DEG 170.0 /* a corner above this makes a triangle nearly flat */

static double corner_deg(const double *o, const double *a, const double *b)
{
    double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]}, v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
    double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return atan2(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]), u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) *
           (180.0 / M_PI);
}

double build_min_corner(const double *p, const double *q, const double *r)
{
    return fmin(corner_deg(p, q, r), fmin(corner_deg(q, r, p), corner_deg(r, p, q)));
}

static void tri_normal(const double *p, const double *q, const double *r, double n[3])
{
    double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

static int find_edge(const edge_rec *E, size_t ne, int32_t a, int32_t b, int32_t not_t)
{
    edge_rec key = {a < b ? a : b, a < b ? b : a, -1};
    size_t lo = 0, hi = ne;
    while (lo < hi) { /* first record of (a, b) */
        size_t mid = (lo + hi) / 2;
        if (E[mid].a < key.a || (E[mid].a == key.a && E[mid].b < key.b)) lo = mid + 1;
        else hi = mid;
    }
    int found = -1, count = 0;
    for (size_t i = lo; i < ne && E[i].a == key.a && E[i].b == key.b; i++, count++)
        if (E[i].t != not_t) found = E[i].t;
    return count == 2 ? found : (not_t < 0 && count ? 0 : -1);
}

/*
 * A triangle with a corner above FLAT_DEG (a node almost on the edge
 * opposite it: a pocket's chord grazing a contour node) is nearly flat; it is
 * swapped with its neighbour across that edge for the two triangles that join
 * the node to the neighbour's far corner, when both are better (smallest
 * corner), face the same way as the neighbour, and their edge is not in the
 * surface yet. The surface moves by the node's distance from the edge. The
 * orientation is kept (after step 4).
 */
thx_status build_flip_flat(thx_ctx *ctx, thx_surface *s, size_t *n_flipped)
{
    size_t nt = s->n_tris;
    edge_rec *E = thx_malloc(ctx, 3 * (nt ? nt : 1) * sizeof *E);
    unsigned char *touched = thx_calloc(ctx, nt ? nt : 1, 1);
    if (!E || !touched) { free(E); free(touched); return THX_ENOMEM; }
    for (int pass = 0; pass < 8; pass++) {
        size_t ne = 0, flips = 0;
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 3; k++) {
                int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
                E[ne++] = (edge_rec){a < b ? a : b, a < b ? b : a, (int32_t)t};
            }
        qsort(E, ne, sizeof *E, cmp_edge);
        memset(touched, 0, nt);
        for (size_t t = 0; t < nt; t++) {
            if (touched[t]) continue;
            int32_t *T = s->tri + 3 * t;
            const double *P[3] = {s->xyz + 3 * (size_t)T[0], s->xyz + 3 * (size_t)T[1], s->xyz + 3 * (size_t)T[2]};
            int k = -1;
            for (int i = 0; i < 3; i++)
                if (corner_deg(P[i], P[(i + 1) % 3], P[(i + 2) % 3]) > FLAT_DEG) k = i;
            if (k < 0) continue;
            int32_t v = T[k], a = T[(k + 1) % 3], b = T[(k + 2) % 3]; /* t = (v, a, b) */
            int u = find_edge(E, ne, a, b, (int32_t)t);
            if (u < 0 || touched[u]) continue;
            int32_t *U = s->tri + 3 * (size_t)u, x = -1;
            for (int i = 0; i < 3; i++)
                if (U[i] == b && U[(i + 1) % 3] == a) x = U[(i + 2) % 3]; /* u = (b, a, x) */
            if (x < 0 || x == v || find_edge(E, ne, v, x, -1) >= 0) continue;
            const double *V = s->xyz + 3 * (size_t)v, *A = s->xyz + 3 * (size_t)a, *B = s->xyz + 3 * (size_t)b,
                         *Xp = s->xyz + 3 * (size_t)x;
            double before = fmin(build_min_corner(V, A, B), build_min_corner(B, A, Xp));
            double after = fmin(build_min_corner(V, A, Xp), build_min_corner(V, Xp, B));
            if (!(after > before)) continue;
            double nu[3], n1[3], n2[3];
            tri_normal(B, A, Xp, nu);
            tri_normal(V, A, Xp, n1);
            tri_normal(V, Xp, B, n2);
            if (nu[0] * n1[0] + nu[1] * n1[1] + nu[2] * n1[2] <= 0 || nu[0] * n2[0] + nu[1] * n2[1] + nu[2] * n2[2] <= 0)
                continue;
            T[0] = v; T[1] = a; T[2] = x;
            U[0] = v; U[1] = x; U[2] = b;
            touched[t] = touched[u] = 1;
            flips++;
        }
        *n_flipped += flips;
        if (!flips) break;
    }
    free(E);
    free(touched);
    return THX_OK;
}
