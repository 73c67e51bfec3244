/*
 * Surfaces from contours (paper 3.1-3.2): the whole pipeline for every surface
 *   1. layers: each loop -> smoothing spline -> nodes at constant spacing,
 *      counterclockwise, starting nearest the anatomical start point;
 *   2. slices: the loops of adjacent layers are matched by overlap; in a group
 *      of one loop on one layer and k on the other (a branching surface) the one
 *      loop is cut by chords into k polygons, each laced with its loop
 *      (split_single); other groups with more than one loop on a layer, and a
 *      split that fails, are joined into one chain by bridges between nearest
 *      nodes; each group is laced (lace.c);
 *   3. caps: every loop with no partner on the layer below (above) is closed by
 *      a cap in its plane, triangulating the loop itself or a grid inside it;
 *   4. orientation: every triangle is tested as in the paper: the two candidate
 *      normal endpoints are classified inside/outside the surface (by the layer
 *      curves, interpolated between layers); the one outside gives the outward
 *      side and the triangle is stored counterclockwise seen from it. Triangles
 *      the test cannot decide take the orientation of decided neighbours.
 *   5. nearly flat triangles (a corner above 170 degrees) are swapped with
 *      their neighbour across the long edge where that betters both.
 * Node numbering per surface: layer by layer (increasing z), loop by loop, then
 * the cap grid nodes.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/cdt.h"
#include "thorax/geom/tri_intersect.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include "thorax/geom/surfaces.h"
#include "geom/chain_sdf.h"
#include "geom/build_internal.h"
#include "geom/inplane.h"

/* Layer number for messages: the file's layer number, or the surface's own for contours built in memory. */
#define LAYER_NO(cs, l) ((cs)->layers[l].index >= 0 ? (cs)->layers[l].index + 1 : (int)(l) + 1)

void thx_surfaces_opts_default(thx_surfaces_opts *o)
{
    memset(o, 0, sizeof *o);
    o->spacing = 0;
    o->smoothing = 2.0;
    o->start.x = 0;
    o->start.y = 1000.0;
    o->cap_method = -1;
    o->cap_grid = 0;
    thx_lace_opts_default(&o->lace);
}



/* A laced in-plane patch with a smaller angle (degrees) is triangulated again with grid nodes (step 3b;
   thorax check fails triangles under 1 degree) */
#define THX_INPLANE_MIN_ANGLE 2.0
/* A slice's lacing with a smaller angle (degrees: thorax check's floor) is laced once more on the chains'
   own positions (quality_retry). */
#define THX_LACE_MIN_ANGLE 1.0
/* quality_retry's whole-slice dynamic programme only for slices of at most this many node pairs (its
   outside tests: 0.5 s at 560 x 449 nodes, 6 s at 688 x 748 on the bench map's dome, which it did not
   mend) */
#define THX_LACE_DP_PAIRS ((size_t)1 << 18)
/* A layer's plane whose in-plane triangles have a smaller angle (degrees: thorax check's floor) after
   step 3b is triangulated again from its laced triangles' edges (step 3c). */
#define THX_RESOLVE_MIN_ANGLE 1.0

/* A loop whose every overlapping partner on the neighbouring layers encloses over this many times its
   area is a speck (thx_contours_drop_flat) */
#define THX_SPECK_RATIO 100.0

static double rloop_area(const rloop *r)
{
    double a = 0;
    for (size_t k = 0, j = r->n - 1; k < r->n; j = k++) a += r->p[j].x * r->p[k].y - r->p[k].x * r->p[j].y;
    return fabs(0.5 * a);
}

/* A point just inside counterclockwise loop r: edge k's midpoint moved inward by a tenth of the edge. */
static thx_vec2 edge_probe(const rloop *r, size_t k)
{
    thx_vec2 u = r->p[k], v = r->p[(k + 1) % r->n];
    return (thx_vec2){0.5 * (u.x + v.x) - 0.1 * (v.y - u.y), 0.5 * (u.y + v.y) + 0.1 * (v.x - u.x)};
}

/* Do the projections of two loops overlap? */
static int loops_overlap(const rloop *a, const rloop *b)
{
    double ax0 = INFINITY, ax1 = -INFINITY, ay0 = INFINITY, ay1 = -INFINITY;
    double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY;
    for (size_t k = 0; k < a->n; k++) { ax0 = fmin(ax0, a->p[k].x); ax1 = fmax(ax1, a->p[k].x); ay0 = fmin(ay0, a->p[k].y); ay1 = fmax(ay1, a->p[k].y); }
    for (size_t k = 0; k < b->n; k++) { bx0 = fmin(bx0, b->p[k].x); bx1 = fmax(bx1, b->p[k].x); by0 = fmin(by0, b->p[k].y); by1 = fmax(by1, b->p[k].y); }
    if (ax1 < bx0 || bx1 < ax0 || ay1 < by0 || by1 < ay0) return 0;
    /* Probe points just inside each loop (edge midpoints moved inward by a tenth of the edge),
       so that identical or nearly identical loops are found to overlap. */
    const rloop *pair[2][2] = {{a, b}, {b, a}};
    for (int r = 0; r < 2; r++) {
        const rloop *p = pair[r][0], *q = pair[r][1];
        chain_index cq;
        if (chain_index_init(&cq, q->p, q->n) != 0) return 1;
        for (size_t k = 0; k < p->n; k++)
            if (chain_index_sdf(&cq, edge_probe(p, k)) < 0) { chain_index_free(&cq); return 1; }
        chain_index_free(&cq);
    }
    return 0;
}

/* Sets each loop's hole flag: inside an odd number of the layer's other loops (tested at its first node).
   Loops of one layer do not cross (the contours' check), so one node decides. 0, or -1 out of memory. */
static int mark_holes(rlayer *L)
{
    for (size_t k = 0; k < L->n_loops; k++) L->loops[k].hole = 0;
    if (L->n_loops < 2) return 0;
    for (size_t j = 0; j < L->n_loops; j++) {
        const rloop *o = &L->loops[j];
        chain_index ci;
        if (chain_index_init(&ci, o->p, o->n) != 0) return -1;
        for (size_t k = 0; k < L->n_loops; k++)
            if (k != j && chain_index_sdf(&ci, L->loops[k].p[0]) < 0) L->loops[k].hole ^= 1;
        chain_index_free(&ci);
    }
    return 0;
}

/* Is most of hole h's region (probes just inside its edges) inside layer O's outer loops? */
static int hole_covered(const rloop *h, const rlayer *O)
{
    size_t in = 0;
    for (size_t j = 0; j < O->n_loops; j++) {
        if (O->loops[j].hole) continue;
        chain_index cq;
        if (chain_index_init(&cq, O->loops[j].p, O->loops[j].n) != 0) return 1; /* (out of memory: capped) */
        for (size_t k = 0; k < h->n; k++) in += chain_index_sdf(&cq, edge_probe(h, k)) < 0;
        chain_index_free(&cq);
    }
    return 2 * in > h->n;
}

/* The outer loop of layer L that hole i lies in (the innermost, by area), or -1. */
static int enclosing_outer(const rlayer *L, size_t i)
{
    int best = -1;
    double best_area = INFINITY;
    for (size_t j = 0; j < L->n_loops; j++) {
        if (j == i || L->loops[j].hole) continue;
        chain_index c;
        if (chain_index_init(&c, L->loops[j].p, L->loops[j].n) != 0) return -1;
        int inside = chain_index_sdf(&c, L->loops[i].p[0]) < 0;
        chain_index_free(&c);
        double a = rloop_area(&L->loops[j]);
        if (inside && a < best_area) { best_area = a; best = (int)j; }
    }
    return best;
}

/* The region of the other layer's loops in a slice group (inside an outer loop, outside the holes):
   where a hole's bridge must not run. */
typedef struct {
    chain_index *ix;
    size_t n;
} group_region;

static int in_region(const group_region *g, thx_vec2 q)
{
    int in = 0;
    for (size_t k = 0; k < g->n; k++)
        if (chain_index_sdf(&g->ix[k], q) < 0) in ^= 1; /* (holes lie inside their outer loop: parity) */
    return in;
}

/* The bridge of hole q into the chain out->p[0..n): the nearest pair of nodes whose segment's midpoint
   lies outside the other layer's region (the mouth where the other layer's horseshoe opens into the
   hole's pocket), else the nearest pair. */
static void hole_bridge(const thx_vec2 *p, size_t n, const rloop *q, const group_region *other, size_t *bp, size_t *bq)
{
    typedef struct { double d; size_t i, j; } cand;
    cand *c = malloc(q->n * sizeof *c);
    double best = INFINITY;
    for (size_t j = 0; j < q->n; j++) {
        double dj = INFINITY;
        size_t ij = 0;
        for (size_t i = 0; i < n; i++) {
            double d = hypot(p[i].x - q->p[j].x, p[i].y - q->p[j].y);
            if (d < dj) { dj = d; ij = i; }
        }
        if (c) c[j] = (cand){dj, ij, j};
        if (dj < best) { best = dj; *bp = ij; *bq = j; }
    }
    if (!c || !other || !other->n) { free(c); return; }
    double found = INFINITY;
    for (size_t j = 0; j < q->n; j++) {
        if (!(c[j].d < found)) continue;
        thx_vec2 m = {0.5 * (p[c[j].i].x + q->p[j].x), 0.5 * (p[c[j].i].y + q->p[j].y)};
        if (!in_region(other, m)) { found = c[j].d; *bp = c[j].i; *bq = j; }
    }
    free(c);
}

static void group_region_free(group_region *g)
{
    for (size_t k = 0; k < g->n; k++) chain_index_free(&g->ix[k]);
    free(g->ix);
    memset(g, 0, sizeof *g);
}

/* The region of layer L's loops in component c (comp[off + k] for loop k): made only for a group with
   a hole (build_slice), whose bridge looks at it. */
static thx_status group_region_make(thx_ctx *ctx, const rlayer *L, const int *comp, size_t off, int c, group_region *g)
{
    memset(g, 0, sizeof *g);
    size_t m = 0;
    for (size_t k = 0; k < L->n_loops; k++) m += comp[off + k] == c;
    if (!m) return THX_OK;
    g->ix = thx_calloc(ctx, m, sizeof *g->ix);
    if (!g->ix) return THX_ENOMEM;
    for (size_t k = 0; k < L->n_loops; k++) {
        if (comp[off + k] != c) continue;
        if (chain_index_init(&g->ix[g->n], L->loops[k].p, L->loops[k].n) != 0) { group_region_free(g); return THX_ENOMEM; }
        g->n++;
    }
    return THX_OK;
}

/* Joins loops (indices sel[0..m-1] of layer L) into one chain with bridges between nearest nodes; a
   hole is walked clockwise and bridged where `other` (the slice's other layer's loops of the group,
   or NULL) leaves the way open (hole_bridge). */
static thx_status merge_loops(thx_ctx *ctx, const rlayer *L, const int *sel, int m, const group_region *other,
                              thx_lace_nodes *nd, double spacing, owned_chain *out)
{
    size_t total = 0;
    for (int k = 0; k < m; k++) total += L->loops[sel[k]].n + 2;
    for (int k = 0; k < m && nd; k++) /* a hole's bridge, both ways: room for nodes at the spacing */
        if (L->loops[sel[k]].hole) total += 2 * (nd->cap - nd->n < (size_t)1 << 20 ? nd->cap - nd->n : (size_t)1 << 20);
    out->p = thx_malloc(ctx, total * sizeof *out->p);
    out->id = thx_malloc(ctx, total * sizeof *out->id);
    if (!out->p || !out->id) return THX_ENOMEM;
    const rloop *l0 = &L->loops[sel[0]];
    size_t n = l0->n;
    for (size_t k = 0; k < n; k++) { out->p[k] = l0->p[k]; out->id[k] = l0->first + (int32_t)k; }
    for (int g = 1; g < m; g++) {
        const rloop *q = &L->loops[sel[g]];
        double best = INFINITY;
        size_t bp = 0, bq = 0;
        if (q->hole)
            hole_bridge(out->p, n, q, other, &bp, &bq);
        else
            for (size_t i = 0; i < n; i++)
                for (size_t j = 0; j < q->n; j++) {
                    double d = hypot(out->p[i].x - q->p[j].x, out->p[i].y - q->p[j].y);
                    if (d < best) { best = d; bp = i; bq = j; }
                }
        /* chain[0..bp], [bridge in], q[bq..bq-1], q[bq], [bridge out], chain[bp..n-1]; a hole's bridge
           gets nodes at the spacing in the layer's plane (else the other layer's channel walls, nodes a
           spacing apart, are fanned to its two ends), the same nodes both ways */
        size_t nb_ = 0;
        thx_vec2 a = out->p[bp], b = q->p[bq];
        if (q->hole && nd && spacing > 0) {
            double len = hypot(b.x - a.x, b.y - a.y);
            nb_ = len > 1.5 * spacing ? (size_t)lround(len / spacing) - 1 : 0;
            if (nd->n + nb_ > nd->cap) nb_ = 0;
        }
        int32_t id0 = nb_ ? nd->base + (int32_t)nd->n : 0;
        size_t ins = q->n + 2 + 2 * nb_, w = bp + 1;
        memmove(out->p + bp + 1 + ins, out->p + bp + 1, (n - bp - 1) * sizeof *out->p);
        memmove(out->id + bp + 1 + ins, out->id + bp + 1, (n - bp - 1) * sizeof *out->id);
        for (size_t t = 0; t < nb_; t++, w++) { /* the bridge in: its nodes, kept for the surface too */
            double f = (double)(t + 1) / (double)(nb_ + 1);
            out->p[w] = (thx_vec2){a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)};
            out->id[w] = id0 + (int32_t)t;
            double *x = nd->xyz + 3 * (nd->n + t);
            x[0] = out->p[w].x, x[1] = out->p[w].y, x[2] = L->z;
        }
        for (size_t s = 0; s <= q->n; s++, w++) { /* a hole walked clockwise: the chain then bounds the annulus */
            size_t j = q->hole ? (bq + q->n - s % q->n) % q->n : (bq + s) % q->n;
            out->p[w] = q->p[j];
            out->id[w] = q->first + (int32_t)j;
        }
        for (size_t t = nb_; t-- > 0; w++) { /* the bridge out: the same nodes, back */
            out->p[w] = out->p[bp + 1 + t];
            out->id[w] = id0 + (int32_t)t;
        }
        out->p[w] = out->p[bp];
        out->id[w] = out->id[bp];
        if (nb_) nd->n += nb_;
        n += ins;
    }
    out->c.n = n;
    out->c.p = out->p;
    out->c.id = out->id;
    out->c.z = L->z;
    out->sel = thx_malloc(ctx, (size_t)m * sizeof *out->sel);
    if (!out->sel) return THX_ENOMEM;
    memcpy(out->sel, sel, (size_t)m * sizeof *sel);
    out->n_sel = m;
    if (m > 1) {
        out->parts = thx_malloc(ctx, (size_t)m * sizeof *out->parts);
        if (!out->parts) return THX_ENOMEM;
        for (int k = 0; k < m; k++) out->parts[k] = L->ch[sel[k]];
        out->c.parts = out->parts;
        out->c.n_parts = (size_t)m;
    }
    if (chain_index_init(&out->ix, out->p, n) != 0) return thx_error(ctx, THX_ENOMEM, "out of memory");
    return THX_OK;
}

/* A point well inside the surface: on the middle layer, the grid point of the
 * largest loop farthest inside its curve. */
static thx_vec3 interior_point(const rlayer *layers, size_t nl)
{
    const rlayer *L = &layers[nl / 2];
    if (nl >= 2 && nl % 2 == 0) L = &layers[nl / 2 - 1];
    thx_vec3 best = {0, 0, L->z};
    double bestd = INFINITY;
    size_t nh = 0;
    for (size_t k = 0; k < L->n_loops; k++) nh += (size_t)L->loops[k].hole;
    chain_index *hi = nh ? calloc(nh, sizeof *hi) : NULL; /* the holes: the point lies outside them */
    if (nh && !hi) nh = 0;
    for (size_t k = 0, m = 0; k < L->n_loops && m < nh; k++)
        if (L->loops[k].hole && chain_index_init(&hi[m++], L->loops[k].p, L->loops[k].n) != 0) {
            for (size_t q = 0; q + 1 < m; q++) chain_index_free(&hi[q]);
            nh = 0;
        }
    for (size_t k = 0; k < L->n_loops; k++) {
        const rloop *r = &L->loops[k];
        if (r->hole) continue;
        chain_index c;
        if (chain_index_init(&c, r->p, r->n) != 0) continue;
        double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        for (size_t i = 0; i < r->n; i++) { x0 = fmin(x0, r->p[i].x); x1 = fmax(x1, r->p[i].x); y0 = fmin(y0, r->p[i].y); y1 = fmax(y1, r->p[i].y); }
        for (int i = 1; i < 40; i++)
            for (int j = 1; j < 40; j++) {
                thx_vec2 q = {x0 + (x1 - x0) * i / 40.0, y0 + (y1 - y0) * j / 40.0};
                double d = chain_index_sdf(&c, q);
                for (size_t m = 0; m < nh; m++) d = fmax(d, -chain_index_sdf(&hi[m], q));
                if (d < bestd) { bestd = d; best = thx_v3(q.x, q.y, L->z); }
            }
        chain_index_free(&c);
    }
    for (size_t m = 0; m < nh; m++) chain_index_free(&hi[m]);
    free(hi);
    /* Lift it half-way toward the next layer so it is not exactly in a layer plane. */
    const rlayer *N = (L + 1 < layers + nl) ? L + 1 : NULL;
    if (N) best.z = L->z + 0.5 * (N->z - L->z);
    return best;
}

static void free_layers(rlayer *layers, size_t nl)
{
    if (!layers) return;
    for (size_t l = 0; l < nl; l++) {
        for (size_t k = 0; k < layers[l].n_loops; k++) {
            free(layers[l].loops[k].p);
            free(layers[l].loops[k].id);
        }
        free(layers[l].loops);
        free(layers[l].ch);
        free(layers[l].kind_ch[0]);
        free(layers[l].kind_ch[1]);
    }
    free(layers);
}

static void free_slices(slice *s, size_t ns)
{
    if (!s) return;
    for (size_t i = 0; i < ns; i++) {
        for (size_t g = 0; g < s[i].n_groups; g++) {
            free(s[i].ga[g].p); free(s[i].ga[g].id); chain_index_free(&s[i].ga[g].ix); free(s[i].ga[g].parts); free(s[i].ga[g].sel);
            free(s[i].gb[g].p); free(s[i].gb[g].id); chain_index_free(&s[i].gb[g].ix); free(s[i].gb[g].parts); free(s[i].gb[g].sel);
        }
        free(s[i].ga);
        free(s[i].gb);
        free(s[i].tris);
    }
    free(s);
}

/* Groups of overlapping loops between layers A and B (connected components);
 * fills slice groups with merged chains and marks partners. */
static thx_status build_slice(thx_ctx *ctx, rlayer *layers, size_t nl, size_t k, double spacing, slice *s)
{
    rlayer *A = &layers[k], *B = &layers[k + 1];
    const rlayer *below = k > 0 ? &layers[k - 1] : NULL, *above = k + 2 < nl ? &layers[k + 2] : NULL;
    size_t na = A->n_loops, nb = B->n_loops, n = na + nb;
    int *comp = thx_malloc(ctx, n * sizeof *comp);
    unsigned char *adj = thx_calloc(ctx, (na * nb > 0) ? na * nb : 1, 1);
    int *sel = thx_malloc(ctx, n * sizeof *sel), *host = NULL;
    thx_status st = THX_OK;
    if (!comp || !adj || !sel) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < na; i++)
        for (size_t j = 0; j < nb; j++)
            adj[i * nb + j] = (unsigned char)(A->loops[i].hole == B->loops[j].hole &&
                                              ((na == 1 && nb == 1) || loops_overlap(&A->loops[i], &B->loops[j])));
    for (size_t i = 0; i < n; i++) comp[i] = -1;
    /* A hole with no hole of the other layer to lace to, over a region the other layer does not cover
       (the lung's annulus around the diaphragm's dome over the horseshoe below it, the dome's section
       open at one saddle): joined to the loop it lies in, so that its walls are laced to the other
       layer's pocket (merge_loops bridges it in, walked clockwise). One the other layer covers (the
       dome's top under a full disc) is capped. */
    host = thx_malloc(ctx, (n ? n : 1) * sizeof *host);
    if (!host) { st = THX_ENOMEM; goto done; }
    for (size_t r = 0; r < n; r++) {
        host[r] = -1;
        const rlayer *L = r < na ? A : B, *O = r < na ? B : A;
        size_t i = r < na ? r : r - na;
        if (!L->loops[i].hole) continue;
        int partnered = 0;
        for (size_t j = 0; j < O->n_loops && !partnered; j++)
            partnered = r < na ? adj[i * nb + j] : adj[j * nb + i];
        if (partnered || hole_covered(&L->loops[i], O)) continue;
        host[r] = enclosing_outer(L, i);
        if (host[r] >= 0 && r >= na) host[r] += (int)na;
    }
    int nc = 0;
    for (size_t r = 0; r < n; r++) {
        if (comp[r] >= 0) continue;
        /* flood fill */
        int *stack = sel, top = 0;
        stack[top++] = (int)r;
        comp[r] = nc;
        while (top) {
            int u = stack[--top];
            for (size_t v = 0; v < n; v++) {
                if (comp[v] >= 0) continue;
                int linked = host[v] == u || host[u] == (int)v;
                if ((size_t)u < na && v >= na) linked = linked || adj[(size_t)u * nb + (v - na)];
                if ((size_t)u >= na && v < na) linked = linked || adj[v * nb + ((size_t)u - na)];
                if (linked) { comp[v] = nc; stack[top++] = (int)v; }
            }
        }
        nc++;
    }
    s->ga = thx_calloc(ctx, (size_t)nc, sizeof *s->ga);
    s->gb = thx_calloc(ctx, (size_t)nc, sizeof *s->gb);
    if (!s->ga || !s->gb) { st = THX_ENOMEM; goto done; }
    for (int c = 0; c < nc; c++) {
        int ma = 0, mb = 0;
        for (size_t i = 0; i < na; i++) if (comp[i] == c) sel[ma++] = (int)i;
        if (ma == 0) continue;
        for (size_t j = 0; j < nb; j++) if (comp[na + j] == c) mb++;
        if (mb == 0) continue; /* loop(s) of A end here: capped */
        group_region ra = {0}, rb = {0}; /* each layer's loops of the group: where the other's hole bridges may not run */
        int any_hole = 0;
        for (size_t i = 0; i < na; i++) any_hole |= comp[i] == c && A->loops[i].hole;
        for (size_t j = 0; j < nb; j++) any_hole |= comp[na + j] == c && B->loops[j].hole;
        if (any_hole) {
            st = group_region_make(ctx, A, comp, 0, c, &ra);
            if (st == THX_OK) st = group_region_make(ctx, B, comp, na, c, &rb);
        }
        if (st == THX_OK) st = merge_loops(ctx, A, sel, ma, &rb, &s->nodes, spacing, &s->ga[s->n_groups]);
        mb = 0;
        for (size_t j = 0; j < nb; j++) if (comp[na + j] == c) sel[mb++] = (int)j;
        if (st == THX_OK) st = merge_loops(ctx, B, sel, mb, &ra, &s->nodes, spacing, &s->gb[s->n_groups]);
        group_region_free(&ra);
        group_region_free(&rb);
        if (st != THX_OK) goto done;
        int h = 1; /* a group of holes only (a hole joined to its loop is part of that loop's group) */
        for (size_t i = 0; i < na; i++) if (comp[i] == c && !A->loops[i].hole) h = 0;
        for (size_t j = 0; j < nb; j++) if (comp[na + j] == c && !B->loops[j].hole) h = 0;
        s->ga[s->n_groups].hole = s->gb[s->n_groups].hole = h;
        if (below) { s->ga[s->n_groups].c.beyond = below->kind_ch[h]; s->ga[s->n_groups].c.n_beyond = below->n_kind[h]; }
        if (above) { s->gb[s->n_groups].c.beyond = above->kind_ch[h]; s->gb[s->n_groups].c.n_beyond = above->n_kind[h]; }
        for (size_t i = 0; i < na; i++) if (comp[i] == c) A->loops[i].up = 1;
        for (size_t j = 0; j < nb; j++) if (comp[na + j] == c) B->loops[j].down = 1;
        if (ma > 1 || mb > 1) s->branch = 1;
        s->n_groups++;
    }
done:
    free(comp);
    free(adj);
    free(sel);
    free(host);
    return st;
}

/* Laces chain a with chain b into sl->tris, appending. A lacing whose triangles cross each other (a
 * fold the lacing's own tests do not see, e.g. a narrow protrusion of one layer fanned across to
 * the other side of the other layer) is laced again with other settings: a tighter and a looser
 * outside test, tongues cut from shorter fans, the position-only metric, and last the pockets of
 * either layer that the other fills cut in their plane first (a CT skull's loop that runs in
 * through the frontal sinus's notch around the cranial cavity, against a full disc: issue 25). The
 * first that does not cross is kept (else the last, with *crossing = 1). */
/* smallest angle (degrees) of triangles tri[0 .. nt) in space */
static double tris_min_angle(const double *xyz, const int32_t *tri, size_t nt)
{
    double m = 180.0;
    for (size_t t = 0; t < nt; t++)
        m = fmin(m, build_min_corner(xyz + 3 * tri[3 * t], xyz + 3 * tri[3 * t + 1], xyz + 3 * tri[3 * t + 2]));
    return m;
}

/* The options of quality_retry's variant v: the lacing metric on the chains' own positions, no phase;
 * variant 1 also laces the whole slice by one dynamic programme, variant 2 cuts the pockets of either
 * layer that the other fills, or else its tongues one voxel wide, in their plane first. */
static thx_lace_opts quality_opts(const thx_lace_opts *la, int v)
{
    thx_lace_opts lr = *la;
    lr.raw_positions = 1;
    lr.phase_weight = 0;
    if (v == 1) lr.whole_dp = 1;
    if (v == 2) {
        lr.cut_filled_pockets = 1;
        lr.cut_tongue_runs = 1;
    }
    return lr;
}

/* A lacing (sl's triangles from `first`, made with options la) that does not cross but has an angle under
 * THX_LACE_MIN_ANGLE is laced again: (0) with the metric on the chains' own positions (thin crescents of
 * unequal length at a lung's base: mapped to a common centroid, one crescent's tip node is fanned to a
 * run of the other's side, issue 25); (1) if that still has a thin triangle, the whole slice by one
 * dynamic programme over every pair of nodes (the path of least cost, where the greedy walk took the
 * next shortest diagonal and could not undo an offset of a whole straight run); (2) if that still
 * has one, with the pockets that the other layer fills cut in their plane first (a dome's top: a
 * pocket in one layer's loop, none in the next, whose side was fanned to the other's run), or if
 * there are none the tongues the other layer lacks (a wedge's tail one voxel wide). The one
 * with the largest smallest angle that does not cross is kept. (1) only for slices of at most
 * THX_LACE_DP_PAIRS pairs of nodes. */
static thx_status quality_retry(thx_ctx *lc, const thx_chain *a, const thx_chain *b, const thx_lace_opts *la,
                                const double *lxyz, slice *sl, size_t first, const thx_lace_stats *keep)
{
    double ang = tris_min_angle(lxyz, sl->tris + 3 * first, sl->n_tris - first);
    if (ang >= THX_LACE_MIN_ANGLE || la->raw_positions) return THX_OK;
    size_t n0 = sl->n_tris;
    thx_lace_stats st0 = sl->st;
    int best = -1;
    for (int v = 0; v < 3 && ang < THX_LACE_MIN_ANGLE; v++) {
        thx_lace_opts lr = quality_opts(la, v);
        if (v == 1 && a->n * b->n > THX_LACE_DP_PAIRS) break;
        thx_status r = thx_lace(lc, a, b, &lr, &sl->tris, &sl->n_tris, &sl->cap, &sl->st);
        if (r != THX_OK) return r;
        int x = build_tris_cross(lxyz, sl->tris + 3 * n0, sl->n_tris - n0);
        if (x == 0) x = build_edge_overused(sl->tris + 3 * n0, sl->n_tris - n0);
        if (x < 0) return thx_error(lc, THX_ENOMEM, "out of memory");
        double ang2 = x ? -1 : tris_min_angle(lxyz, sl->tris + 3 * n0, sl->n_tris - n0);
        if (ang2 > ang) { ang = ang2; best = v; }
        sl->n_tris = n0;
        sl->st = st0;
    }
    thx_status r = THX_OK;
    if (best >= 0) { /* laced again in its place, the statistics as that lacing's alone (the same lacing) */
        thx_lace_opts lr = quality_opts(la, best);
        sl->n_tris = first;
        sl->st = *keep;
        r = thx_lace(lc, a, b, &lr, &sl->tris, &sl->n_tris, &sl->cap, &sl->st);
        sl->st.relaced_quality++;
    }
    return r;
}

static thx_status lace_tries(thx_ctx *lc, const thx_chain *a, const thx_chain *b, const thx_lace_opts *lo,
                             const double *lxyz, slice *sl, int *crossing)
{
    enum { N_TRY = 7 };
    size_t first = sl->n_tris;
    thx_lace_stats keep = sl->st;
    thx_status r = THX_OK;
    *crossing = 0;
    int without = 0; /* 1: this attempt again without the long fan's filled-pocket cut */
    for (int attempt = 0; attempt < N_TRY; attempt++) {
        thx_lace_opts la = *lo;
        if (without) la.cut_filled_pockets = -1;
        if (attempt == 1) la.concave_tol *= 0.5;
        if (attempt == 2) la.concave_tol *= 2;
        if (attempt == 3 && la.fan_limit > 3) la.fan_limit = 3;
        if (attempt == 4) la.phase_weight = 0;
        if (attempt == 5) { la.phase_weight *= 4; la.concave_tol *= 0.5; }
        if (attempt == 6) la.cut_filled_pockets = 2;
        int was_without = without;
        without = 0;
        sl->n_tris = first;
        sl->st = keep;
        r = thx_lace(lc, a, b, &la, &sl->tris, &sl->n_tris, &sl->cap, &sl->st);
        if (r != THX_OK) return r;
        if (attempt == 6 && sl->st.filled_pockets == keep.filled_pockets) {
            /* no filled pocket: the slice stays as the previous retry laced it (what a slice that
               crosses kept before this retry existed) */
            la = *lo;
            la.phase_weight *= 4;
            la.concave_tol *= 0.5;
            la.cut_filled_pockets = -1;
            sl->n_tris = first;
            sl->st = keep;
            r = thx_lace(lc, a, b, &la, &sl->tris, &sl->n_tris, &sl->cap, &sl->st);
            if (r != THX_OK) return r;
            break;
        }
        int x = build_tris_cross(lxyz, sl->tris + 3 * first, sl->n_tris - first);
        /* an edge in three triangles is laced again as well (issue 24: the Dalhousie torso
           cut across its long axis at 10 mm, where a layer's loop branches in two) */
        if (x == 0) x = build_edge_overused(sl->tris + 3 * first, sl->n_tris - first);
        if (x == 1 && !build_tris_cross(lxyz, sl->tris + 3 * first, sl->n_tris - first)) {
            int m = build_mend_overused(lxyz, sl->tris + 3 * first, sl->n_tris - first);
            x = m < 0 ? -1 : !m;
        }
        if (x == 1 && attempt < 6 && !was_without && sl->st.filled_pockets > keep.filled_pockets) {
            /* the long fan's filled pocket, cut (thx_lace), made the lacing cross: these settings
               again without it (the bench's torso map's lungs, two loops merging) */
            without = 1;
            attempt--;
            continue;
        }
        if (x < 0) return thx_error(lc, THX_ENOMEM, "out of memory");
        if (!x) {
            if (attempt) sl->st.relaced_crossing++;
            return quality_retry(lc, a, b, &la, lxyz, sl, first, &keep);
        }
    }
    *crossing = 1;
    return THX_OK;
}

/*
 * Branching by splitting the single loop (Christiansen and Sederberg 1978; Meyers, Skinner and
 * Sloan 1992, "Surfaces from contours", section 5): where one loop S of a layer meets k loops
 * P_1..P_k of the next, the loops joined by bridges into one chain can be too unlike S for any
 * lacing (issue 24: the Utah tank cut across x, where a loop at the flat bottom and the shoulders'
 * loop 97 mm above it meet one loop of the full height; the bridge's node was fanned to half of S
 * and the lacing crossed itself). S is cut instead by chords between its own nodes into k
 * polygons, one around each P_i, and each pair is laced alone. A node of S belongs to the loop P_i of least signed distance; the run of
 * P_i's nodes along S, widened to the node on each side nearer the bisector, is cut off by the
 * chord between its ends, provided the chord lies inside S (it touches no other edge of S and its
 * midpoint is inside) and touches no P_j. The chord, in S's plane, is the ridge where the laced
 * bands meet: each of its two triangles belongs to one band, so the surface stays a manifold.
 * One P_i at a time is cut off what is left of S. Fills sub[0..k-1] (points and ids, malloc'd;
 * sub[i] around parts[i]); *ok = 0 when no such chords exist.
 */
typedef struct { size_t n; thx_vec2 *p; int32_t *id; } poly_buf;

static int chord_valid(const poly_buf *c, size_t i1, size_t i2, const thx_chain *parts, const int *alive, int k)
{
    size_t m = c->n;
    const double *a = &c->p[i1].x, *b = &c->p[i2].x;
    if (c->p[i1].x == c->p[i2].x && c->p[i1].y == c->p[i2].y) return 0;
    for (size_t e = 0; e < m; e++) {
        size_t e1 = (e + 1) % m;
        if (e == i1 || e == i2 || e1 == i1 || e1 == i2) continue;
        if (thx_segments_touch(a, b, &c->p[e].x, &c->p[e1].x)) return 0;
    }
    chain_index ci;
    if (chain_index_init(&ci, c->p, c->n) != 0) return 0;
    thx_vec2 mid = {0.5 * (c->p[i1].x + c->p[i2].x), 0.5 * (c->p[i1].y + c->p[i2].y)};
    int inside = chain_index_sdf(&ci, mid) < 0;
    chain_index_free(&ci);
    if (!inside) return 0;
    for (int q = 0; q < k; q++) {
        if (!alive[q]) continue;
        for (size_t e = 0; e < parts[q].n; e++)
            if (thx_segments_touch(a, b, &parts[q].p[e].x, &parts[q].p[(e + 1) % parts[q].n].x)) return 0;
    }
    return 1;
}

/* The arc c[i1..i2] (cyclic, inclusive) as a new polygon. */
static int arc_copy(const poly_buf *c, size_t i1, size_t i2, poly_buf *out)
{
    size_t len = (i2 + c->n - i1) % c->n + 1;
    out->p = malloc(len * sizeof *out->p);
    out->id = malloc(len * sizeof *out->id);
    if (!out->p || !out->id) return -1;
    for (size_t s = 0; s < len; s++) { out->p[s] = c->p[(i1 + s) % c->n]; out->id[s] = c->id[(i1 + s) % c->n]; }
    out->n = len;
    return 0;
}

static int split_single(const thx_chain *S, const thx_chain *parts, int k, poly_buf *sub)
{
    poly_buf cur = {S->n, malloc(S->n * sizeof(thx_vec2)), malloc(S->n * sizeof(int32_t))};
    int *alive = malloc((size_t)k * sizeof *alive), *lab = malloc(S->n * sizeof *lab), ok = 1, left = k;
    double *d = malloc(S->n * (size_t)k * sizeof *d);
    chain_index *ix = calloc((size_t)k, sizeof *ix);
    if (!cur.p || !cur.id || !alive || !lab || !d || !ix) ok = -1;
    for (int q = 0; ok == 1 && q < k; q++) if (chain_index_init(&ix[q], parts[q].p, parts[q].n) != 0) ok = -1;
    if (ok == 1) {
        memcpy(cur.p, S->p, S->n * sizeof *cur.p);
        memcpy(cur.id, S->id, S->n * sizeof *cur.id);
        for (int q = 0; q < k; q++) alive[q] = 1;
    }
    while (ok == 1 && left > 1) {
        size_t m = cur.n;
        for (size_t v = 0; v < m; v++) {
            lab[v] = -1;
            for (int q = 0; q < k; q++) {
                if (!alive[q]) continue;
                d[v * (size_t)k + (size_t)q] = chain_index_sdf(&ix[q], cur.p[v]);
                if (lab[v] < 0 || d[v * (size_t)k + (size_t)q] < d[v * (size_t)k + (size_t)lab[v]]) lab[v] = q;
            }
        }
        int done = 0;
        for (int q = 0; q < k && !done; q++) {
            if (!alive[q]) continue;
            /* the one run of q's nodes: s0 its first node (after a node of another loop), s1 its last */
            size_t s0 = m, s1 = m;
            int runs = 0;
            for (size_t v = 0; v < m; v++) {
                int here = lab[v] == q, prev = lab[(v + m - 1) % m] == q, next = lab[(v + 1) % m] == q;
                if (here && !prev) { runs++; s0 = v; }
                if (here && !next) s1 = v;
            }
            if (runs != 1) continue;
            /* widen each end to the neighbour when that is nearer the bisector */
            size_t b0 = (s0 + m - 1) % m, b1 = (s1 + 1) % m;
            double g0 = d[s0 * (size_t)k + (size_t)q] - d[s0 * (size_t)k + (size_t)lab[b0]];
            double h0 = d[b0 * (size_t)k + (size_t)lab[b0]] - d[b0 * (size_t)k + (size_t)q];
            double g1 = d[s1 * (size_t)k + (size_t)q] - d[s1 * (size_t)k + (size_t)lab[b1]];
            double h1 = d[b1 * (size_t)k + (size_t)lab[b1]] - d[b1 * (size_t)k + (size_t)q];
            size_t c1 = fabs(h0) < fabs(g0) ? b0 : s0, c2 = fabs(h1) < fabs(g1) ? b1 : s1;
            size_t len = (c2 + m - c1) % m + 1;
            if (len < 3 || m - len + 2 < 3) continue;
            if (!chord_valid(&cur, c1, c2, parts, alive, k)) continue;
            poly_buf rest = {0, NULL, NULL};
            if (arc_copy(&cur, c1, c2, &sub[q]) || arc_copy(&cur, c2, c1, &rest)) {
                free(rest.p);
                free(rest.id);
                ok = -1;
                break;
            }
            free(cur.p);
            free(cur.id);
            cur = rest;
            alive[q] = 0;
            left--;
            done = 1;
        }
        if (!done && ok == 1) ok = 0;
    }
    for (int q = 0; ok == 1 && q < k; q++)
        if (alive[q]) { sub[q] = cur; cur.p = NULL; cur.id = NULL; }
    free(cur.p);
    free(cur.id);
    for (int q = 0; ix && q < k; q++) chain_index_free(&ix[q]);
    free(ix);
    free(alive);
    free(lab);
    free(d);
    return ok;
}

/* Do the k loops lie strictly inside S in projection (every node inside, no edges touching)?
 * -1 out of memory. */
static int parts_nested(const thx_chain *S, const thx_chain *parts, int k)
{
    chain_index si;
    if (chain_index_init(&si, S->p, S->n) != 0) return -1;
    int in = 1;
    for (int q = 0; q < k && in; q++)
        for (size_t v = 0; v < parts[q].n && in; v++) in = chain_index_sdf(&si, parts[q].p[v]) < 0;
    chain_index_free(&si);
    for (int q = 0; q < k && in; q++)
        for (size_t v = 0; v < parts[q].n && in; v++)
            for (size_t e = 0; e < S->n && in; e++)
                in = !thx_segments_touch(&parts[q].p[v].x, &parts[q].p[(v + 1) % parts[q].n].x, &S->p[e].x,
                                         &S->p[(e + 1) % S->n].x);
    return in;
}

/* A branching group (one loop on one layer, k on the other) laced by split_single, each part by
 * lace_tries, unless the k loops lie strictly inside the one (the ring between them is then
 * triangulated in projection by thx_lace: islands under a large loop, test_surfaces). *done = 1 when that lacing is kept: it was found and no triangle of the group
 * crosses another and no edge is in three triangles; else nothing is added (*done = 0) and the
 * caller laces the bridged chains. */
static thx_status lace_branch_split(thx_ctx *lc, const owned_chain *ga, const owned_chain *gb, const thx_lace_opts *lo,
                                    const double *lxyz, slice *sl, int *done)
{
    /* the parts are laced without the long fan's filled-pocket cut (thx_lace): each part's lacing
       is checked alone, and a cut that passes there made the parts cross each other (the bench's
       torso map's lungs, issue 25) */
    thx_lace_opts lp = *lo;
    lp.cut_filled_pockets = -1;
    *done = 0;
    int single_lower = ga->n_sel == 1 && gb->n_sel > 1;
    if (!single_lower && !(gb->n_sel == 1 && ga->n_sel > 1)) return THX_OK;
    const owned_chain *one = single_lower ? ga : gb, *many = single_lower ? gb : ga;
    int k = many->n_sel;
    int nest = parts_nested(&one->c, many->c.parts, k);
    if (nest < 0) return thx_error(lc, THX_ENOMEM, "out of memory");
    if (nest) return THX_OK; /* thx_lace triangulates the ring between them in projection */
    size_t first = sl->n_tris;
    thx_lace_stats old_st = sl->st;
    thx_status r = THX_OK;
    poly_buf *sub = calloc((size_t)k, sizeof *sub);
    if (!sub) return thx_error(lc, THX_ENOMEM, "out of memory");
    int ok = split_single(&one->c, many->c.parts, k, sub), x = 1;
    if (ok < 0) r = thx_error(lc, THX_ENOMEM, "out of memory");
    if (ok == 1) {
        x = 0;
        for (int q = 0; q < k && r == THX_OK && !x; q++) {
            thx_chain sc = one->c, pq = many->c.parts[q];
            sc.n = sub[q].n;
            sc.p = sub[q].p;
            sc.id = sub[q].id;
            sc.parts = NULL;
            sc.n_parts = 0;
            pq.beyond = many->c.beyond;
            pq.n_beyond = many->c.n_beyond;
            size_t before = sl->n_tris;
            thx_lace_stats st_before = sl->st;
            r = single_lower ? lace_tries(lc, &sc, &pq, &lp, lxyz, sl, &x) : lace_tries(lc, &pq, &sc, &lp, lxyz, sl, &x);
            if (r == THX_OK && x) {
                /* Laced again with the seam opposite the chord: both chains start there (the part at
                   its node nearest the polygon's middle node). The chord is one long edge with no
                   node between its ends; a lacing that starts at one of them can twist there (issue
                   24: the Utah tank across x at 7 mm, where the bottom part's top nodes were laced
                   to the far end of the chord). Only after a crossing, so what laced stays as it was. */
                size_t ns = sub[q].n, np = pq.n, h = ns / 2, j0 = 0;
                thx_vec2 *rp = malloc((ns + np) * sizeof *rp);
                int32_t *ri = malloc((ns + np) * sizeof *ri);
                if (!rp || !ri) { free(rp); free(ri); r = thx_error(lc, THX_ENOMEM, "out of memory"); break; }
                double best = INFINITY;
                for (size_t v = 0; v < np; v++) {
                    double d = hypot(pq.p[v].x - sub[q].p[h].x, pq.p[v].y - sub[q].p[h].y);
                    if (d < best) { best = d; j0 = v; }
                }
                for (size_t v = 0; v < ns; v++) { rp[v] = sub[q].p[(h + v) % ns]; ri[v] = sub[q].id[(h + v) % ns]; }
                for (size_t v = 0; v < np; v++) { rp[ns + v] = pq.p[(j0 + v) % np]; ri[ns + v] = pq.id[(j0 + v) % np]; }
                thx_chain sr = sc, pr = pq;
                sr.p = rp;
                sr.id = ri;
                pr.p = rp + ns;
                pr.id = ri + ns;
                sl->n_tris = before;
                sl->st = st_before;
                r = single_lower ? lace_tries(lc, &sr, &pr, &lp, lxyz, sl, &x) : lace_tries(lc, &pr, &sr, &lp, lxyz, sl, &x);
                free(rp);
                free(ri);
            }
        }
        if (r == THX_OK && !x) {
            x = build_tris_cross(lxyz, sl->tris + 3 * first, sl->n_tris - first);
            if (x == 0) x = build_edge_overused(sl->tris + 3 * first, sl->n_tris - first);
            if (x < 0) r = thx_error(lc, THX_ENOMEM, "out of memory");
        }
    }
    if (r == THX_OK && !x) *done = 1;
    else {
        sl->n_tris = first;
        sl->st = old_st;
    }
    for (int q = 0; q < k; q++) { free(sub[q].p); free(sub[q].id); }
    free(sub);
    return r;
}

static thx_status build_one(thx_ctx *ctx, const thx_contours *c, const thx_contour_surface *cs, const thx_surfaces_opts *o,
                            double spacing, thx_surface **out, thx_vec3 *interior, thx_surfaces_stats *stats)
{
    thx_status st = THX_OK;
    size_t nl = cs->n_layers;
    rlayer *layers = thx_calloc(ctx, nl, sizeof *layers);
    slice *slices = NULL;
    double *lxyz = NULL;
    thx_surface *s = NULL;
    const char *path = c->path[0] ? c->path : "<contours>";
    double t0 = thx_wtime();
    if (!layers) return THX_ENOMEM;
    memset(stats, 0, sizeof *stats);
    if (nl < 2) {
        free(layers);
        return thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" is digitized on only one layer (at least two are needed)",
                         path, cs->line, cs->name);
    }
    /* 1. layers */
    size_t n_loops = 0;
    for (size_t l = 0; l < nl; l++) {
        layers[l].z = cs->layers[l].z;
        layers[l].n_loops = cs->layers[l].n_loops;
        layers[l].loops = thx_calloc(ctx, layers[l].n_loops, sizeof(rloop));
        if (!layers[l].loops) { st = THX_ENOMEM; goto done; }
        n_loops += layers[l].n_loops;
    }
    {
        size_t *li = thx_malloc(ctx, n_loops * 2 * sizeof *li);
        if (!li) { st = THX_ENOMEM; goto done; }
        size_t q = 0;
        for (size_t l = 0; l < nl; l++)
            for (size_t k = 0; k < layers[l].n_loops; k++) { li[2 * q] = l; li[2 * q + 1] = k; q++; }
        int failed = 0;
        char msg[1024] = "";
        thx_status fst = THX_OK;
#pragma omp parallel for schedule(dynamic, 4)
        for (long w = 0; w < (long)n_loops; w++) {
            size_t l = li[2 * w], k = li[2 * w + 1];
            thx_ctx *lc = NULL;
            if (thx_ctx_create(&lc) != THX_OK) { failed = 1; continue; }
            const thx_loop *lp = &cs->layers[l].loops[k];
            thx_status r = thx_loop_resample(lc, lp->p, lp->n, spacing, o->smoothing, o->start, &layers[l].loops[k].p,
                                             &layers[l].loops[k].n);
            if (r != THX_OK) {
#pragma omp critical(thx_build_err)
                if (!failed) {
                    failed = 1;
                    fst = r;
                    snprintf(msg, sizeof msg, "%s:%d: surface \"%s\" layer %d (z=%g): %s", path, lp->line, cs->name,
                             LAYER_NO(cs, l), cs->layers[l].z, thx_ctx_message(lc));
                }
            }
            thx_ctx_destroy(&lc);
        }
        free(li);
        if (failed) { st = thx_error(ctx, fst ? fst : THX_ENOMEM, "%s", msg); goto done; }
    }
    int32_t next_id = 0;
    for (size_t l = 0; l < nl; l++) {
        if (mark_holes(&layers[l]) != 0) { st = THX_ENOMEM; goto done; }
        layers[l].ch = thx_calloc(ctx, layers[l].n_loops, sizeof *layers[l].ch);
        if (!layers[l].ch) { st = THX_ENOMEM; goto done; }
        for (size_t k = 0; k < layers[l].n_loops; k++) {
            rloop *r = &layers[l].loops[k];
            r->first = next_id;
            r->id = thx_malloc(ctx, r->n * sizeof *r->id);
            if (!r->id) { st = THX_ENOMEM; goto done; }
            for (size_t i = 0; i < r->n; i++) r->id[i] = next_id + (int32_t)i;
            next_id += (int32_t)r->n;
            layers[l].ch[k].n = r->n;
            layers[l].ch[k].p = r->p;
            layers[l].ch[k].id = r->id;
            layers[l].ch[k].z = layers[l].z;
        }
        for (int h = 0; h < 2; h++) { /* the beyond chains of a group: its kind's loops */
            layers[l].kind_ch[h] = thx_calloc(ctx, layers[l].n_loops ? layers[l].n_loops : 1, sizeof *layers[l].kind_ch[h]);
            if (!layers[l].kind_ch[h]) { st = THX_ENOMEM; goto done; }
            for (size_t k = 0; k < layers[l].n_loops; k++)
                if (layers[l].loops[k].hole == h) layers[l].kind_ch[h][layers[l].n_kind[h]++] = layers[l].ch[k];
        }
    }
    stats->n_loops = n_loops;
    double t1 = thx_wtime();
    stats->t_layers = t1 - t0;
    /* 2. slices */
    size_t ns = nl > 1 ? nl - 1 : 0;
    slices = thx_calloc(ctx, ns ? ns : 1, sizeof *slices);
    if (!slices) { st = THX_ENOMEM; goto done; }
    /* the layer nodes, for the crossing test, then each slice's room for the nodes it may add (its
       holes' bridges, build_slice; its lacings' chords, thx_lace_nodes): four times its layers' nodes
       (pages never written are never touched) */
    size_t n_room = 0;
    for (size_t i = 0; i < ns; i++) {
        size_t r = 64;
        for (size_t l = i; l <= i + 1; l++)
            for (size_t k = 0; k < layers[l].n_loops; k++) r += 4 * layers[l].loops[k].n;
        slices[i].nodes.base = next_id + (int32_t)n_room;
        slices[i].nodes.cap = r;
        n_room += r;
    }
    if ((size_t)next_id + n_room >= (size_t)INT32_MAX) { st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\" has too many nodes", path, cs->name); goto done; }
    lxyz = thx_malloc(ctx, ((size_t)next_id + n_room + 1) * 3 * sizeof *lxyz);
    if (!lxyz) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < ns; i++) slices[i].nodes.xyz = lxyz + 3 * (size_t)slices[i].nodes.base;
    for (size_t i = 0; i < ns; i++) {
        st = build_slice(ctx, layers, nl, i, spacing, &slices[i]);
        if (st != THX_OK) goto done;
    }
    /* A chain with a loop that ends at its layer (capped on the far side: no partner on the layer
       beyond) has nothing beyond it there: the end cap covers that loop, so the lacing must not cut
       a tongue of it in the layer's plane too (the two would overlap). */
    for (size_t i = 0; i < ns; i++)
        for (size_t g = 0; g < slices[i].n_groups; g++) {
            owned_chain *ca = &slices[i].ga[g], *cb = &slices[i].gb[g];
            for (int q = 0; q < ca->n_sel; q++)
                if (!layers[i].loops[ca->sel[q]].down) { ca->c.beyond = NULL; ca->c.n_beyond = 0; }
            for (int q = 0; q < cb->n_sel; q++)
                if (!layers[i + 1].loops[cb->sel[q]].up) { cb->c.beyond = NULL; cb->c.n_beyond = 0; }
        }
    for (size_t l = 0; l < nl; l++)
        for (size_t k = 0; k < layers[l].n_loops; k++)
            for (size_t q = 0; q < layers[l].loops[k].n; q++) {
                size_t id = (size_t)layers[l].loops[k].first + q;
                lxyz[3 * id] = layers[l].loops[k].p[q].x;
                lxyz[3 * id + 1] = layers[l].loops[k].p[q].y;
                lxyz[3 * id + 2] = layers[l].z;
            }
    {
        thx_lace_opts lo = o->lace;
        lo.spacing = spacing;
        int failed = 0;
        char msg[1024] = "";
        thx_status fst = THX_OK;
#pragma omp parallel for schedule(dynamic, 1)
        for (long i = 0; i < (long)ns; i++) {
            thx_ctx *lc = NULL;
            if (thx_ctx_create(&lc) != THX_OK) { failed = 1; continue; }
            thx_lace_opts lo_i = lo;
            lo_i.nodes = &slices[i].nodes;
            for (size_t g = 0; g < slices[i].n_groups; g++) {
                int split = 0, x = 0;
                /* a branching group of one loop and k is laced by splitting the one loop first; the
                   loops joined by bridges when no split is found or it crosses */
                thx_status r = lace_branch_split(lc, &slices[i].ga[g], &slices[i].gb[g], &lo_i, lxyz, &slices[i], &split);
                if (r == THX_OK && !split) r = lace_tries(lc, &slices[i].ga[g].c, &slices[i].gb[g].c, &lo_i, lxyz, &slices[i], &x);
                if (r == THX_OK && x) slices[i].st.crossing++;
                if (r != THX_OK) {
#pragma omp critical(thx_build_err)
                    if (!failed) {
                        failed = 1;
                        fst = r;
                        snprintf(msg, sizeof msg, "%s:%d: surface \"%s\" slice between z=%g and z=%g: %s", path,
                                 cs->layers[i + 1].line, cs->name, layers[i].z, layers[i + 1].z, thx_ctx_message(lc));
                    }
                    break;
                }
            }
            thx_ctx_destroy(&lc);
        }
        if (failed) { st = thx_error(ctx, fst ? fst : THX_ENOMEM, "%s", msg); goto done; }
    }
    /* A loop that overlaps no loop on either neighbouring layer would be a flat disc: its two caps
       would coincide. */
    for (size_t l = 0; l < nl; l++)
        for (size_t k = 0; k < layers[l].n_loops; k++)
            if (!layers[l].loops[k].up && !layers[l].loops[k].down) {
                const thx_loop *lp = &cs->layers[l].loops[k];
                st = thx_error(ctx, THX_EINPUT,
                               "%s:%d: surface \"%s\" layer %d (z=%g): the loop overlaps no loop of the layers above "
                               "and below, so it would enclose no volume",
                               path, lp->line ? lp->line : cs->layers[l].line, cs->name, LAYER_NO(cs, l), layers[l].z);
                goto done;
            }
    size_t ntri = 0;
    for (size_t i = 0; i < ns; i++) {
        ntri += slices[i].n_tris;
        thx_lace_stats *a = &stats->lace, *b = &slices[i].st;
        a->n_tris += b->n_tris; a->removed += b->removed; a->relaced_gaps += b->relaced_gaps;
        a->inplane_tris += b->inplane_tris; a->unresolved += b->unresolved; a->too_large += b->too_large;
        a->tongues += b->tongues; a->filled_pockets += b->filled_pockets; a->projected += b->projected; a->crossing += b->crossing;
        a->relaced_crossing += b->relaced_crossing;
        a->relaced_quality += b->relaced_quality;
        if (b->max_fan > a->max_fan) a->max_fan = b->max_fan;
        stats->n_branch_slices += (size_t)slices[i].branch;
    }
    stats->n_slices = ns;
    double t2 = thx_wtime();
    stats->t_lace = t2 - t1;
    /* 3. caps, appended after the laced triangles; grid nodes after the layer nodes. */
    THX_TRY(thx_surface_create(ctx, cs->name, cs->role, &s));
    size_t n_added = 0; /* the nodes the lacings added, after the layer nodes */
    for (size_t i = 0; i < ns; i++) n_added += slices[i].nodes.n;
    size_t node_cap = (size_t)next_id + n_added + 64, tri_cap = ntri + 64;
    s->xyz = thx_malloc(ctx, node_cap * 3 * sizeof *s->xyz);
    s->tri = thx_malloc(ctx, tri_cap * 3 * sizeof *s->tri);
    if (!s->xyz || !s->tri) { st = THX_ENOMEM; goto done; }
    for (size_t l = 0; l < nl; l++)
        for (size_t k = 0; k < layers[l].n_loops; k++) {
            const rloop *r = &layers[l].loops[k];
            for (size_t i = 0; i < r->n; i++) {
                size_t id = (size_t)r->first + i;
                s->xyz[3 * id] = r->p[i].x;
                s->xyz[3 * id + 1] = r->p[i].y;
                s->xyz[3 * id + 2] = layers[l].z;
            }
        }
    s->n_nodes = (size_t)next_id;
    for (size_t i = 0; i < ns; i++) {
        const thx_lace_nodes *nd = &slices[i].nodes;
        int32_t shift = (int32_t)s->n_nodes - nd->base; /* the slice's added nodes, packed */
        memcpy(s->xyz + 3 * s->n_nodes, nd->xyz, nd->n * 3 * sizeof *s->xyz);
        s->n_nodes += nd->n;
        int32_t *T = s->tri + 3 * s->n_tris;
        memcpy(T, slices[i].tris, slices[i].n_tris * 3 * sizeof *s->tri);
        if (nd->n)
            for (size_t k = 0; k < 3 * slices[i].n_tris; k++)
                if (T[k] >= next_id) T[k] += shift;
        s->n_tris += slices[i].n_tris;
    }
    int method = o->cap_method >= 0 ? o->cap_method : (int)cs->cap;
    double grid = o->cap_grid > 0 ? o->cap_grid : (cs->cap_grid > 0 ? cs->cap_grid : spacing);
    {
        /* the caps: triangulated in parallel (each thread its own context), appended in the order of the
           serial loop (layer, loop, bottom then top); the first failing cap's message, as that loop's */
        typedef struct {
            size_t l, k;
            thx_vec2 *cp;
            int32_t *ct;
            size_t ncp, nct;
            thx_status st;
            char msg[512];
        } cap_job;
        size_t nj = 0;
        for (size_t l = 0; l < nl; l++)
            for (size_t k = 0; k < layers[l].n_loops; k++)
                nj += (size_t)!layers[l].loops[k].down + (size_t)!layers[l].loops[k].up;
        cap_job *jobs = thx_calloc(ctx, nj ? nj : 1, sizeof *jobs);
        if (!jobs) { st = THX_ENOMEM; goto done; }
        nj = 0;
        for (size_t l = 0; l < nl; l++)
            for (size_t k = 0; k < layers[l].n_loops; k++)
                for (int side = 0; side < 2; side++)
                    if (!(side == 0 ? layers[l].loops[k].down : layers[l].loops[k].up)) {
                        jobs[nj].l = l;
                        jobs[nj].k = k;
                        nj++;
                    }
#pragma omp parallel
        {
            thx_ctx *lc = NULL;
            int ok = thx_ctx_create(&lc) == THX_OK;
#pragma omp for schedule(dynamic, 1)
            for (long j = 0; j < (long)nj; j++) {
                cap_job *jb = &jobs[j];
                const rloop *r = &layers[jb->l].loops[jb->k];
                jb->st = ok ? thx_cap_triangulate(lc, r->p, r->n, method == THX_CAP_GRID ? grid : 0.0,
                                                  method == THX_CAP_GRID ? 0.5 * grid : 0.0, &jb->cp, &jb->ncp, &jb->ct,
                                                  &jb->nct)
                            : THX_ENOMEM;
                if (jb->st != THX_OK) snprintf(jb->msg, sizeof jb->msg, "%s", ok ? thx_ctx_message(lc) : "out of memory");
            }
            thx_ctx_destroy(&lc);
        }
        for (size_t j = 0; j < nj && st == THX_OK; j++) {
            cap_job *jb = &jobs[j];
            size_t l = jb->l;
            rloop *r = &layers[l].loops[jb->k];
            if (jb->st != THX_OK) {
                st = thx_error(ctx, jb->st, "%s:%d: surface \"%s\" layer %d (z=%g): end cap: %s", path,
                               cs->layers[l].line, cs->name, LAYER_NO(cs, l), layers[l].z, jb->msg);
                break;
            }
            thx_vec2 *cp = jb->cp;
            int32_t *ct = jb->ct;
            size_t ncp = jb->ncp, nct = jb->nct;
            size_t base = s->n_nodes;
            if (s->n_nodes + ncp > node_cap) {
                node_cap = (s->n_nodes + ncp) * 2;
                double *nx = thx_realloc(ctx, s->xyz, node_cap * 3 * sizeof *nx);
                if (!nx) { st = THX_ENOMEM; break; }
                s->xyz = nx;
            }
            for (size_t i = r->n; i < ncp; i++) {
                s->xyz[3 * s->n_nodes] = cp[i].x;
                s->xyz[3 * s->n_nodes + 1] = cp[i].y;
                s->xyz[3 * s->n_nodes + 2] = layers[l].z;
                s->n_nodes++;
            }
            if (s->n_tris + nct > tri_cap) {
                tri_cap = (s->n_tris + nct) * 2;
                int32_t *nt2 = thx_realloc(ctx, s->tri, tri_cap * 3 * sizeof *nt2);
                if (!nt2) { st = THX_ENOMEM; break; }
                s->tri = nt2;
            }
            for (size_t t = 0; t < nct; t++)
                for (int v = 0; v < 3; v++) {
                    int32_t q = ct[3 * t + v];
                    s->tri[3 * (s->n_tris + t) + v] = (size_t)q < r->n ? r->first + q : (int32_t)(base + (size_t)q - r->n);
                }
            s->n_tris += nct;
            stats->n_caps++;
        }
        for (size_t j = 0; j < nj; j++) {
            free(jobs[j].cp);
            free(jobs[j].ct);
        }
        free(jobs);
        if (st != THX_OK) goto done;
    }
    /* 3b. the lacing's in-plane patches (pockets cut in their plane: a CT skull's cavity closed where the
       frontal sinus notches its loop, ~300 boundary nodes) have triangles from their boundary nodes only,
       down to 0.2 degrees, which thorax check fails and thorax mesh cannot take: a patch with an angle
       under THX_INPLANE_MIN_ANGLE is triangulated again as a grid cap (geom/inplane.h) */
    {
        size_t nr = 0;
        THX_TRY(thx_inplane_refine(ctx, s, ntri, grid, THX_INPLANE_MIN_ANGLE, &node_cap, &tri_cap, &nr));
        stats->n_inplane_refined += nr;
    }
    /* 3c. a layer's plane where in-plane triangles overlap or double an edge (two slices cut the same
       pocket of their shared layer), or have an angle under 1 degree that step 3b could not mend, gets
       one triangulation of the region its laced triangles bound (geom/inplane.h) */
    size_t n_resolved = 0, n_resolved_tris = 0;
    THX_TRY(thx_inplane_resolve(ctx, s, grid, THX_RESOLVE_MIN_ANGLE, &node_cap, &tri_cap, &n_resolved, &n_resolved_tris));
    stats->n_inplane_resolved += n_resolved;
    double t3 = thx_wtime();
    stats->t_caps = t3 - t2;
    /* 4. orientation */
    THX_TRY(build_orient(ctx, s, layers, nl, slices, spacing, s->n_tris - n_resolved_tris, stats));
    /* 5. nearly flat triangles swapped away */
    {
        /* The swaps are local; one that makes triangles cross elsewhere (coplanar in-plane triangles
           at a pocket) is not worth it: the surface is kept as it was when the swaps add a crossing. */
        int32_t *before = thx_malloc(ctx, s->n_tris * 3 * sizeof *before);
        if (!before) { st = THX_ENOMEM; goto done; }
        memcpy(before, s->tri, s->n_tris * 3 * sizeof *before);
        size_t nf = 0;
        st = build_flip_flat(ctx, s, &nf);
        int x1 = st == THX_OK && nf ? build_tris_cross(s->xyz, s->tri, s->n_tris) : 0;
        int x0 = x1 > 0 ? build_tris_cross(s->xyz, before, s->n_tris) : 0;
        if (x1 < 0 || x0 < 0) st = THX_ENOMEM;
        if (x1 > 0 && !x0) { memcpy(s->tri, before, s->n_tris * 3 * sizeof *before); nf = 0; }
        free(before);
        if (st != THX_OK) goto done;
        stats->n_flat_flipped += nf;
    }
    if (n_resolved || n_added) { /* the nodes of the in-plane triangles replaced in step 3c, and those added
                                     by lacings laced again and discarded, and no other */
        size_t nd = 0;
        THX_TRY(thx_surface_drop_unused(ctx, s, &nd));
    }
    *interior = interior_point(layers, nl);
    stats->t_orient = thx_wtime() - t3;
    stats->n_nodes = s->n_nodes;
    stats->n_tris = s->n_tris;
    stats->t_total = thx_wtime() - t0;
    *out = s;
    s = NULL;
done:
    free(lxyz);
    thx_surface_destroy(&s);
    free_slices(slices, nl > 1 ? nl - 1 : 0);
    free_layers(layers, nl);
    return st;
}

thx_status thx_surfaces_build(thx_ctx *ctx, const thx_contours *c, const thx_surfaces_opts *o, thx_model **out,
                              thx_surfaces_stats *stats, thx_surfaces_stats *total)
{
    thx_model *m = NULL;
    thx_status st = THX_OK;
    *out = NULL;
    double spacing = o->spacing > 0 ? o->spacing : (c->spacing > 0 ? c->spacing : 5.0);
    /* Contours built in memory have not been through the reader's validation. */
    THX_CHECK(thx_contours_validate(ctx, c));
    THX_CHECK(thx_model_create(ctx, &m));
    if (total) memset(total, 0, sizeof *total);
    double t0 = thx_wtime();
    for (size_t k = 0; k < c->n_surfaces; k++) {
        thx_surface *s = NULL;
        thx_vec3 interior;
        thx_surfaces_stats one;
        THX_TRY(build_one(ctx, c, &c->surf[k], o, spacing, &s, &interior, &one));
        THX_TRY(thx_model_add_surface(ctx, m, &s));
        m->has_interior[m->n_surfaces - 1] = 1;
        m->interior[m->n_surfaces - 1] = interior;
        thx_log(ctx, THX_LOG_DEBUG,
                "surface %s: %zu nodes, %zu triangles; lacing removed %zu outside triangles, re-laced %zu gaps, "
                "%zu in-plane (%zu filled pockets; %zu in-plane patches given grid nodes), %zu unresolved, %zu too "
                "large, largest fan %d; %zu caps; orientation: %zu by test, %zu from neighbours (%zu votes overruled), "
                "%zu flipped",
                c->surf[k].name, one.n_nodes, one.n_tris, one.lace.removed, one.lace.relaced_gaps, one.lace.inplane_tris,
                one.lace.filled_pockets, one.n_inplane_refined,
                one.lace.unresolved, one.lace.too_large, one.lace.max_fan, one.n_caps, one.orient_by_test,
                one.orient_by_neighbours, one.orient_overruled, one.orient_flipped);
        if (one.lace.crossing)
            thx_log(ctx, THX_LOG_WARN, "surface %s: %zu slice groups keep crossing triangles after re-lacing",
                    c->surf[k].name, one.lace.crossing);
        if (one.lace.unresolved)
            thx_log(ctx, THX_LOG_WARN, "surface %s: %zu triangles still span a concave region after re-lacing",
                    c->surf[k].name, one.lace.unresolved);
        if (stats) stats[k] = one;
        if (total) {
            total->n_nodes += one.n_nodes; total->n_tris += one.n_tris; total->n_loops += one.n_loops;
            total->n_slices += one.n_slices; total->n_branch_slices += one.n_branch_slices; total->n_caps += one.n_caps;
            total->lace.n_tris += one.lace.n_tris; total->lace.removed += one.lace.removed;
            total->lace.relaced_gaps += one.lace.relaced_gaps; total->lace.inplane_tris += one.lace.inplane_tris;
            total->lace.tongues += one.lace.tongues; total->lace.projected += one.lace.projected;
            total->lace.filled_pockets += one.lace.filled_pockets;
            total->lace.unresolved += one.lace.unresolved; total->lace.crossing += one.lace.crossing;
            total->lace.relaced_crossing += one.lace.relaced_crossing; total->lace.too_large += one.lace.too_large;
            total->lace.relaced_quality += one.lace.relaced_quality;
            if (one.lace.max_fan > total->lace.max_fan) total->lace.max_fan = one.lace.max_fan;
            total->orient_by_test += one.orient_by_test; total->orient_by_neighbours += one.orient_by_neighbours;
            total->orient_flipped += one.orient_flipped; total->orient_overruled += one.orient_overruled;
            total->n_flat_flipped += one.n_flat_flipped;
            total->n_inplane_refined += one.n_inplane_refined;
            total->n_inplane_resolved += one.n_inplane_resolved;
            total->t_layers += one.t_layers; total->t_lace += one.t_lace; total->t_caps += one.t_caps;
            total->t_orient += one.t_orient;
        }
    }
    if (total) total->t_total = thx_wtime() - t0;
    *out = m;
    m = NULL;
done:
    thx_model_destroy(&m);
    return st;
}

thx_status thx_surface_build(thx_ctx *ctx, const thx_contours *c, size_t k, const thx_surfaces_opts *o,
                             thx_surface **out, thx_vec3 *interior, thx_surfaces_stats *stats)
{
    *out = NULL;
    if (k >= c->n_surfaces)
        return thx_error(ctx, THX_EINPUT, "surface %zu: the contours have %zu surfaces", k + 1, c->n_surfaces);
    double spacing = o->spacing > 0 ? o->spacing : (c->spacing > 0 ? c->spacing : 5.0);
    /* the contours seen as holding this surface alone: its loops are checked, not the others' */
    thx_contours one = *c;
    one.n_surfaces = 1;
    one.surf = &c->surf[k];
    THX_CHECK(thx_contours_validate(ctx, &one));
    thx_surfaces_stats local;
    return build_one(ctx, c, &c->surf[k], o, spacing, out, interior, stats ? stats : &local);
}

thx_status thx_contours_drop_flat(thx_ctx *ctx, thx_contours *c, const thx_surfaces_opts *o, size_t *dropped)
{
    double spacing = o->spacing > 0 ? o->spacing : (c->spacing > 0 ? c->spacing : 5.0);
    const char *path = c->path[0] ? c->path : "<contours>";
    for (size_t k = 0; k < c->n_surfaces; k++) {
        thx_contour_surface *cs = &c->surf[k];
        size_t nl = cs->n_layers, gone = 0;
        if (dropped) dropped[k] = 0;
        rlayer *layers = thx_calloc(ctx, nl ? nl : 1, sizeof *layers);
        unsigned char **keep = thx_calloc(ctx, nl ? nl : 1, sizeof *keep);
        thx_status st = THX_OK;
        if (!layers || !keep) {
            free(layers), free(keep);
            return THX_ENOMEM;
        }
        /* the loops as the lacing sees them: resampled by the same splines at the same spacing; the
           layers in parallel (each thread its own context; the first failing layer's message wins, as
           the serial loop's would) */
        for (size_t l = 0; l < nl && st == THX_OK; l++) {
            size_t n = cs->layers[l].n_loops;
            layers[l].n_loops = n;
            layers[l].loops = thx_calloc(ctx, n ? n : 1, sizeof(rloop));
            keep[l] = thx_malloc(ctx, n ? n : 1);
            if (!layers[l].loops || !keep[l]) {
                st = THX_ENOMEM;
                break;
            }
            memset(keep[l], 1, n ? n : 1);
        }
        if (st == THX_OK) {
            long bad = -1;
            thx_status bad_st = THX_OK;
            char bad_msg[1024] = "";
#pragma omp parallel
            {
                thx_ctx *lc = NULL;
                int ok = thx_ctx_create(&lc) == THX_OK;
#pragma omp for schedule(dynamic, 4)
                for (long l = 0; l < (long)nl; l++) {
                    for (size_t i = 0; i < layers[l].n_loops; i++) {
                        const thx_loop *lp = &cs->layers[l].loops[i];
                        thx_status r = ok ? thx_loop_resample(lc, lp->p, lp->n, spacing, o->smoothing, o->start,
                                                              &layers[l].loops[i].p, &layers[l].loops[i].n)
                                          : THX_ENOMEM;
                        if (r == THX_OK) continue;
#pragma omp critical(thx_drop_flat_err)
                        if (bad < 0 || l < bad) {
                            bad = l;
                            bad_st = r;
                            snprintf(bad_msg, sizeof bad_msg, "%s:%d: surface \"%s\" layer %d (z=%g): %s", path,
                                     lp->line, cs->name, LAYER_NO(cs, (size_t)l), cs->layers[l].z,
                                     ok ? thx_ctx_message(lc) : "out of memory");
                        }
                        break;
                    }
                }
                thx_ctx_destroy(&lc);
            }
            if (bad >= 0) st = thx_error(ctx, bad_st, "%s", bad_msg);
            for (size_t l = 0; l < nl && st == THX_OK; l++)
                if (mark_holes(&layers[l]) != 0) st = THX_ENOMEM;
        }
        /* to a fixed point: a loop with no kept partner on either neighbouring layer (the rule of the
           slices: two single loops always pair, else their projections must overlap) is dropped */
        for (int changed = 1; changed && st == THX_OK;) {
            changed = 0;
            for (size_t l = 0; l < nl; l++)
                for (size_t i = 0; i < layers[l].n_loops; i++) {
                    if (!keep[l][i]) continue;
                    int partner = 0;
                    size_t na = 0;
                    for (size_t q = 0; q < layers[l].n_loops; q++) na += keep[l][q];
                    for (int side = -1; side <= 1 && !partner; side += 2) {
                        if ((side < 0 && l == 0) || (side > 0 && l + 1 == nl)) continue;
                        size_t m = l + (size_t)side, nb = 0;
                        for (size_t q = 0; q < layers[m].n_loops; q++) nb += keep[m][q];
                        for (size_t j = 0; j < layers[m].n_loops && !partner; j++)
                            if (keep[m][j] && layers[l].loops[i].hole == layers[m].loops[j].hole)
                                partner = (na == 1 && nb == 1) || loops_overlap(&layers[l].loops[i], &layers[m].loops[j]);
                    }
                    if (!partner) {
                        keep[l][i] = 0;
                        changed = 1;
                    }
                }
            /* an end layer of specks: every kept loop of the layer has partners on one side only, and
               every partner exceeds it over THX_SPECK_RATIO times in area (the bottom plane of a
               ray-voxelized torso, on a plane of voxel centres: 143 one-voxel specks 0.9 mm across
               under the body's 300 mm loop). Laced, they fan the big loop's nodes into needles
               (thorax check fails triangles under 1 degree: thorax mesh cannot take them); dropped,
               the surface is capped on its big loop. Only a layer of nothing but specks: a small
               loop beside a big one on its layer is a branch of the lacing, and dropping such loops
               changed how bench/image.sh's lungs branched (edges in three triangles) */
            for (size_t l = 0; l < nl; l++) {
                size_t n_kept = 0, n_speck = 0;
                for (size_t i = 0; i < layers[l].n_loops; i++) {
                    if (!keep[l][i]) continue;
                    n_kept++;
                    double ai = rloop_area(&layers[l].loops[i]);
                    int speck = 1, sides = 0;
                    for (int side = -1; side <= 1 && speck; side += 2) {
                        if ((side < 0 && l == 0) || (side > 0 && l + 1 == nl)) continue;
                        size_t m = l + (size_t)side;
                        int any = 0;
                        for (size_t j = 0; j < layers[m].n_loops && speck; j++)
                            if (keep[m][j] && loops_overlap(&layers[l].loops[i], &layers[m].loops[j])) {
                                any = 1;
                                speck = rloop_area(&layers[m].loops[j]) > THX_SPECK_RATIO * ai;
                            }
                        sides += any;
                    }
                    n_speck += speck && sides == 1;
                }
                if (n_kept && n_speck == n_kept) {
                    memset(keep[l], 0, layers[l].n_loops);
                    changed = 1;
                }
            }
        }
        /* the loops dropped from the contours, and the layers left empty at either end */
        for (size_t l = 0; l < nl && st == THX_OK; l++) {
            thx_contour_layer *L = &cs->layers[l];
            size_t w = 0;
            for (size_t i = 0; i < L->n_loops; i++) {
                if (keep[l][i]) {
                    L->loops[w++] = L->loops[i];
                    continue;
                }
                free(L->loops[i].p);
                free(L->loops[i].lines);
                gone++;
            }
            L->n_loops = w;
        }
        size_t first = 0, last = nl;
        while (first < last && cs->layers[first].n_loops == 0) first++;
        while (last > first && cs->layers[last - 1].n_loops == 0) last--;
        for (size_t l = first; l < last && st == THX_OK; l++)
            if (cs->layers[l].n_loops == 0)
                st = thx_error(ctx, THX_EINPUT,
                               "%s: surface \"%s\": with the loops that no neighbouring layer's loop overlaps dropped, "
                               "layer %d (z=%g) holds none: the surface would break in two",
                               path, cs->name, LAYER_NO(cs, l), cs->layers[l].z);
        if (st == THX_OK && last - first < 2 && nl >= 2)
            st = thx_error(ctx, THX_EINPUT,
                           "%s: surface \"%s\": no two consecutive layers hold overlapping loops (a surface needs two)",
                           path, cs->name);
        if (st == THX_OK && (first > 0 || last < nl)) {
            for (size_t l = 0; l < nl; l++)
                if (l < first || l >= last) free(cs->layers[l].loops);
            memmove(cs->layers, cs->layers + first, (last - first) * sizeof *cs->layers);
            cs->n_layers = last - first;
        }
        for (size_t l = 0; l < nl; l++) {
            for (size_t i = 0; layers[l].loops && i < layers[l].n_loops; i++) free(layers[l].loops[i].p);
            free(layers[l].loops);
            free(keep[l]);
        }
        free(layers), free(keep);
        if (st != THX_OK) return st;
        if (dropped) dropped[k] = gone;
    }
    return THX_OK;
}
