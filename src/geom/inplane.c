/*
 * In-plane patches of a laced surface given interior nodes (see geom/inplane.h).
 *
 * A patch: laced triangles with their three nodes on one layer (equal z, exactly: layer nodes carry
 * their layer's z), joined through shared edges. Its boundary: the edges used once within it. When
 * every boundary node has two boundary edges and they close into one loop over all of them, the
 * region is a disc and thx_cap_triangulate (the grid cap of paper 3.2's caps) triangulates it again
 * with the same boundary edges, so the rest of the surface is untouched and stays watertight.
 */
#include "geom/inplane.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/union_find.h"
#include "thorax/geom/cdt.h"

typedef struct {
    int32_t a, b; /* a < b */
    size_t t;
} iedge;

static int cmp_iedge(const void *x, const void *y)
{
    const iedge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

/* smallest angle (degrees) of a triangle in the (x, y) plane */
double inplane_min_angle2(double ax, double ay, double bx, double by, double cx, double cy)
{
    double P[3][2] = {{ax, ay}, {bx, by}, {cx, cy}}, m = 180.0;
    for (int k = 0; k < 3; k++) {
        const double *o = P[k], *u = P[(k + 1) % 3], *v = P[(k + 2) % 3];
        double ux = u[0] - o[0], uy = u[1] - o[1], vx = v[0] - o[0], vy = v[1] - o[1];
        double a = fabs(atan2(ux * vy - uy * vx, ux * vx + uy * vy)) * 180.0 / M_PI;
        if (a < m) m = a;
    }
    return m;
}

double inplane_tri_min_angle(const thx_surface *s, size_t t)
{
    const int32_t *v = s->tri + 3 * t;
    const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
    return inplane_min_angle2(a[0], a[1], b[0], b[1], c[0], c[1]);
}

/* smallest angle (degrees) of a triangle in space */
static double min_angle3(const double *a, const double *b, const double *c)
{
    const double *P[3] = {a, b, c};
    double m = 180.0;
    for (int k = 0; k < 3; k++) {
        const double *o = P[k], *u = P[(k + 1) % 3], *v = P[(k + 2) % 3];
        double x[3] = {u[0] - o[0], u[1] - o[1], u[2] - o[2]}, y[3] = {v[0] - o[0], v[1] - o[1], v[2] - o[2]};
        double cr[3] = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
        double ang = atan2(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]), x[0] * y[0] + x[1] * y[1] + x[2] * y[2]);
        m = fmin(m, ang * 180.0 / M_PI);
    }
    return m;
}

static thx_status grow_tris(thx_ctx *ctx, thx_surface *s, size_t *tri_cap, size_t more)
{
    if (s->n_tris + more <= *tri_cap) return THX_OK;
    size_t nc = (s->n_tris + more) * 2;
    int32_t *ntr = thx_realloc(ctx, s->tri, nc * 3 * sizeof *ntr);
    if (!ntr) return THX_ENOMEM;
    s->tri = ntr;
    *tri_cap = nc;
    return THX_OK;
}

/* The boundary of a patch (its edges used once, from the sorted edge list) as one closed loop of node
 * ids in *loop (n_loop), or 0 when it is not one simple loop (a node with other than two boundary
 * edges, or several loops). */
static int patch_loop(thx_ctx *ctx, const iedge *e, size_t ne, const size_t *grp, size_t g, int32_t **loop,
                      size_t *n_loop)
{
    /* the patch's boundary edges */
    size_t nb = 0, cap = 0, n_edges = 0, n_sides = 0;
    int32_t *be = NULL; /* pairs */
    for (size_t i = 0; i < ne;) {
        size_t j = i, in = 0, last = 0;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) {
            if (grp[e[j].t] == g) in++, last = j;
            j++;
        }
        n_edges += in > 0;
        n_sides += in;
        if (in == 1) {
            if (nb == cap) {
                cap = cap ? 2 * cap : 64;
                int32_t *nbe = thx_realloc(ctx, be, cap * 2 * sizeof *nbe);
                if (!nbe) { free(be); return -1; }
                be = nbe;
            }
            be[2 * nb] = e[last].a;
            be[2 * nb + 1] = e[last].b;
            nb++;
        } else if (in > 2) {
            free(be);
            return 0;
        }
        i = j;
    }
    /* a disc of F triangles and E edges has V = 1 + E - F nodes (Euler); every one must be on the
       boundary, or the patch holds nodes (a loop's, cut in the plane with it) that a triangulation from
       the boundary would leave in no triangle */
    if (nb < 3 || 1 + n_edges - n_sides / 3 != nb) { free(be); return 0; }
    /* each node's two boundary neighbours: sort the half-edges by node */
    int32_t (*h)[2] = thx_malloc(ctx, 2 * nb * sizeof *h);
    int32_t *out = thx_malloc(ctx, nb * sizeof *out);
    if (!h || !out) { free(be), free(h), free(out); return -1; }
    for (size_t i = 0; i < nb; i++) {
        h[2 * i][0] = be[2 * i], h[2 * i][1] = be[2 * i + 1];
        h[2 * i + 1][0] = be[2 * i + 1], h[2 * i + 1][1] = be[2 * i];
    }
    free(be);
    /* insertion into a sorted order by (node, neighbour) */
    for (size_t i = 1; i < 2 * nb; i++) {
        int32_t x0 = h[i][0], x1 = h[i][1];
        size_t j = i;
        while (j > 0 && (h[j - 1][0] > x0 || (h[j - 1][0] == x0 && h[j - 1][1] > x1))) {
            h[j][0] = h[j - 1][0], h[j][1] = h[j - 1][1];
            j--;
        }
        h[j][0] = x0, h[j][1] = x1;
    }
    for (size_t i = 0; i < 2 * nb; i += 2)
        if (h[i][0] != h[i + 1][0] || (i + 2 < 2 * nb && h[i + 2][0] == h[i][0])) {
            free(h), free(out);
            return 0; /* a node with other than two boundary edges */
        }
    /* walk: from the first node, always to the neighbour not just left */
    size_t n = 0;
    int32_t prev = -1, cur = h[0][0];
    do {
        if (n == nb) { free(h), free(out); return 0; }
        out[n++] = cur;
        size_t lo = 0, hi = nb; /* node pair index by binary search */
        while (lo + 1 < hi) {
            size_t mid = (lo + hi) / 2;
            if (h[2 * mid][0] <= cur) lo = mid;
            else hi = mid;
        }
        int32_t nx = h[2 * lo][1] != prev ? h[2 * lo][1] : h[2 * lo + 1][1];
        prev = cur;
        cur = nx;
    } while (cur != out[0]);
    free(h);
    if (n != nb) { free(out); return 0; } /* several loops */
    *loop = out;
    *n_loop = n;
    return 1;
}

thx_status thx_inplane_refine(thx_ctx *ctx, thx_surface *s, size_t n_laced, double grid, double min_angle_deg,
                              size_t *node_cap, size_t *tri_cap, size_t *n_refined)
{
    *n_refined = 0;
    if (n_laced > s->n_tris) n_laced = s->n_tris;
    size_t nt = s->n_tris, ne = 0;
    thx_status st = THX_OK;
    unsigned char *flat = thx_calloc(ctx, n_laced ? n_laced : 1, 1);
    size_t *grp = thx_malloc(ctx, (nt ? nt : 1) * sizeof *grp);
    iedge *e = NULL, *ae = NULL;
    double *wa = NULL;
    unsigned char *touched = NULL;
    if (!flat || !grp) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < nt; t++) grp[t] = t;
    for (size_t t = 0; t < n_laced; t++) {
        const int32_t *v = s->tri + 3 * t;
        flat[t] = s->xyz[3 * v[0] + 2] == s->xyz[3 * v[1] + 2] && s->xyz[3 * v[0] + 2] == s->xyz[3 * v[2] + 2];
        ne += flat[t] ? 3 : 0;
    }
    if (!ne) goto done;
    e = thx_malloc(ctx, ne * sizeof *e);
    if (!e) { st = THX_ENOMEM; goto done; }
    ne = 0;
    for (size_t t = 0; t < n_laced; t++)
        if (flat[t])
            for (int k = 0; k < 3; k++) {
                int32_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
                e[ne++] = (iedge){a < b ? a : b, a < b ? b : a, t};
            }
    qsort(e, ne, sizeof *e, cmp_iedge);
    for (size_t i = 1; i < ne; i++)
        if (e[i].a == e[i - 1].a && e[i].b == e[i - 1].b) uf_union(grp, e[i].t, e[i - 1].t);
    for (size_t t = 0; t < nt; t++) grp[t] = t < n_laced && flat[t] ? uf_find(grp, t) : (size_t)-1;

    /* each patch's smallest angle, at its root */
    wa = thx_malloc(ctx, n_laced * sizeof *wa);
    if (!wa) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < n_laced; t++) wa[t] = 180.0;
    for (size_t t = 0; t < n_laced; t++)
        if (grp[t] != (size_t)-1) wa[grp[t]] = fmin(wa[grp[t]], inplane_tri_min_angle(s, t));
    /* each patch (root = its first triangle), in the order of its first triangle */
    for (size_t g = 0; g < n_laced && st == THX_OK; g++) {
        if (grp[g] != g) continue;
        double worst = wa[g];
        if (!(worst < min_angle_deg)) continue;
        int32_t *loop = NULL;
        size_t nl = 0;
        int r = patch_loop(ctx, e, ne, grp, g, &loop, &nl);
        if (r < 0) { st = THX_ENOMEM; break; }
        if (r == 0) continue;
        if (!ae) { /* every triangle's edges, for the triangle beyond a long boundary edge */
            ae = thx_malloc(ctx, 3 * nt * sizeof *ae);
            touched = thx_calloc(ctx, nt ? nt : 1, 1);
            if (!ae || !touched) { free(loop); st = THX_ENOMEM; break; }
            for (size_t t = 0; t < nt; t++)
                for (int k = 0; k < 3; k++) {
                    int32_t x = s->tri[3 * t + k], y = s->tri[3 * t + (k + 1) % 3];
                    ae[3 * t + (size_t)k] = (iedge){x < y ? x : y, x < y ? y : x, t};
                }
            qsort(ae, 3 * nt, sizeof *ae, cmp_iedge);
        }
        /* a boundary edge over 1.5 grid spacings long (the cut's chord, one edge among the node
           spacing's short ones) is split in pieces about a grid spacing long, and so is the triangle
           beyond it (a fan from its third node: the same plane, the same surface), unless that one is
           in a patch itself or already split */
        size_t *pieces = thx_malloc(ctx, nl * sizeof *pieces), *beyond = thx_malloc(ctx, nl * sizeof *beyond);
        if (!pieces || !beyond) { free(loop), free(pieces), free(beyond); st = THX_ENOMEM; break; }
        size_t nl2 = 0;
        for (size_t i = 0; i < nl; i++) {
            int32_t u = loop[i], v = loop[(i + 1) % nl];
            double L = hypot(s->xyz[3 * v] - s->xyz[3 * u], s->xyz[3 * v + 1] - s->xyz[3 * u + 1]);
            size_t k = L > 1.5 * grid ? (size_t)floor(L / grid + 0.5) : 1;
            pieces[i] = 1;
            beyond[i] = SIZE_MAX;
            if (k >= 2) {
                iedge key = {u < v ? u : v, u < v ? v : u, 0};
                const iedge *f = ae, *l = ae + 3 * nt; /* lower bound of the edge */
                while (f < l) {
                    const iedge *mid = f + (l - f) / 2;
                    if (mid->a < key.a || (mid->a == key.a && mid->b < key.b)) f = mid + 1;
                    else l = mid;
                }
                size_t other = SIZE_MAX, count = 0;
                for (; f < ae + 3 * nt && f->a == key.a && f->b == key.b; f++, count++)
                    if (grp[f->t] != g) other = f->t;
                int dup = 0;
                for (size_t j = 0; j < i; j++) dup |= beyond[j] == other;
                if (count == 2 && other != SIZE_MAX && grp[other] == (size_t)-1 && !touched[other] && !dup) {
                    pieces[i] = k;
                    beyond[i] = other;
                }
            }
            nl2 += pieces[i];
        }
        thx_vec2 *lp = thx_malloc(ctx, nl2 * sizeof *lp);
        int64_t *ids = thx_malloc(ctx, nl2 * sizeof *ids); /* >= 0: a node; < 0: -(1 + j), split point j */
        if (!lp || !ids) { free(loop), free(pieces), free(beyond), free(lp), free(ids); st = THX_ENOMEM; break; }
        size_t q = 0, n_split = 0;
        for (size_t i = 0; i < nl; i++) {
            int32_t u = loop[i], v = loop[(i + 1) % nl];
            for (size_t j = 0; j < pieces[i]; j++, q++) {
                double t = (double)j / (double)pieces[i];
                lp[q] = (thx_vec2){s->xyz[3 * u] + t * (s->xyz[3 * v] - s->xyz[3 * u]),
                                   s->xyz[3 * u + 1] + t * (s->xyz[3 * v + 1] - s->xyz[3 * u + 1])};
                ids[q] = j ? -(int64_t)(1 + n_split++) : u;
            }
        }
        double z = s->xyz[3 * loop[0] + 2];
        thx_ctx *lc = NULL; /* a loop the cap cannot take keeps its patch; its message is not the caller's */
        thx_vec2 *cp = NULL;
        int32_t *ct = NULL;
        size_t ncp = 0, nct = 0;
        thx_status cs = thx_ctx_create(&lc);
        if (cs == THX_OK) cs = thx_cap_triangulate(lc, lp, nl2, grid, 0.5 * grid, &cp, &ncp, &ct, &nct);
        thx_ctx_destroy(&lc);
        if (cs == THX_ENOMEM) { free(loop), free(pieces), free(beyond), free(lp), free(ids); st = THX_ENOMEM; break; }
        double better = 180.0;
        for (size_t t = 0; cs == THX_OK && t < nct; t++) {
            const thx_vec2 *a = &cp[ct[3 * t]], *b = &cp[ct[3 * t + 1]], *c = &cp[ct[3 * t + 2]];
            better = fmin(better, inplane_min_angle2(a->x, a->y, b->x, b->y, c->x, c->y));
        }
        /* the fans beyond the split edges */
        for (size_t i = 0, q0 = 0; cs == THX_OK && i < nl; q0 += pieces[i], i++) {
            if (pieces[i] < 2) continue;
            const int32_t *tv = s->tri + 3 * beyond[i];
            int32_t x = tv[0] + tv[1] + tv[2] - loop[i] - loop[(i + 1) % nl];
            for (size_t j = 0; j < pieces[i]; j++) {
                const thx_vec2 *p0 = &lp[q0 + j], *p1 = &lp[(q0 + j + 1) % nl2];
                double P0[3] = {p0->x, p0->y, z}, P1[3] = {p1->x, p1->y, z};
                better = fmin(better, min_angle3(P0, P1, s->xyz + 3 * x));
            }
        }
        free(lp);
        if (cs != THX_OK || !(better > worst)) {
            free(cp), free(ct), free(loop), free(pieces), free(beyond), free(ids);
            continue;
        }
        /* the new nodes (split points, then grid nodes), then the triangles: the patch's slots first,
           the rest appended, then each split edge's fan in place of the triangle beyond it */
        size_t base = s->n_nodes, add = n_split + ncp - nl2;
        if (s->n_nodes + add > *node_cap) {
            size_t nc = (s->n_nodes + add) * 2;
            double *nx = thx_realloc(ctx, s->xyz, nc * 3 * sizeof *nx);
            if (!nx) { free(cp), free(ct), free(loop), free(pieces), free(beyond), free(ids); st = THX_ENOMEM; break; }
            s->xyz = nx;
            *node_cap = nc;
        }
        for (size_t i = 0; i < nl2; i++)
            if (ids[i] < 0) {
                size_t j = (size_t)(-ids[i] - 1);
                s->xyz[3 * (base + j)] = cp[i].x;
                s->xyz[3 * (base + j) + 1] = cp[i].y;
                s->xyz[3 * (base + j) + 2] = z;
                ids[i] = (int64_t)(base + j);
            }
        s->n_nodes += n_split;
        for (size_t i = nl2; i < ncp; i++) {
            s->xyz[3 * s->n_nodes] = cp[i].x;
            s->xyz[3 * s->n_nodes + 1] = cp[i].y;
            s->xyz[3 * s->n_nodes + 2] = z;
            s->n_nodes++;
        }
        size_t grid_base = base + n_split;
        size_t used = g; /* the patch's first triangle is its root */
        for (size_t t = 0; t < nct && st == THX_OK; t++) {
            size_t slot = SIZE_MAX;
            while (used < n_laced && slot == SIZE_MAX) {
                if (grp[used] == g) slot = used;
                used++;
            }
            if (slot == SIZE_MAX) {
                st = grow_tris(ctx, s, tri_cap, 1);
                if (st != THX_OK) break;
                slot = s->n_tris++;
            } else
                grp[slot] = (size_t)-1; /* a slot of the patch filled: not the patch's any more */
            for (int v = 0; v < 3; v++) {
                size_t qv = (size_t)ct[3 * t + v];
                s->tri[3 * slot + v] = qv < nl2 ? (int32_t)ids[qv] : (int32_t)(grid_base + qv - nl2);
            }
        }
        for (size_t i = 0, q0 = 0; st == THX_OK && i < nl; q0 += pieces[i], i++) {
            if (pieces[i] < 2) continue;
            size_t t0 = beyond[i];
            int32_t tv[3] = {s->tri[3 * t0], s->tri[3 * t0 + 1], s->tri[3 * t0 + 2]};
            int32_t u = loop[i], v = loop[(i + 1) % nl];
            int p = 0;
            while (p < 3 && !((tv[p] == u && tv[(p + 1) % 3] == v) || (tv[p] == v && tv[(p + 1) % 3] == u))) p++;
            if (p == 3) { st = thx_error(ctx, THX_EGEOM, "in-plane patch: the triangle beyond a split edge lost it"); break; }
            int fwd = tv[p] == u; /* the triangle runs along the edge as the loop does */
            int32_t x = tv[(p + 2) % 3];
            st = grow_tris(ctx, s, tri_cap, pieces[i] - 1);
            if (st != THX_OK) break;
            for (size_t j = 0; j < pieces[i]; j++) {
                /* the j-th piece in the triangle's direction along the edge */
                size_t jj = fwd ? j : pieces[i] - 1 - j;
                int32_t c0 = (int32_t)ids[q0 + jj], c1 = (int32_t)ids[(q0 + jj + 1) % nl2];
                if (!fwd) { int32_t tmp = c0; c0 = c1; c1 = tmp; }
                size_t slot = j ? s->n_tris++ : t0;
                s->tri[3 * slot] = c0, s->tri[3 * slot + 1] = c1, s->tri[3 * slot + 2] = x;
            }
            touched[t0] = 1;
        }
        free(pieces), free(beyond), free(ids);
        if (st != THX_OK) { free(cp), free(ct), free(loop); break; }
        /* the patch's slots left over are removed below */
        for (size_t t = used; t < n_laced; t++)
            if (grp[t] == g) grp[t] = (size_t)-2;
        free(cp), free(ct), free(loop);
        (*n_refined)++;
    }
    if (st == THX_OK && *n_refined) {
        size_t w = 0;
        for (size_t t = 0; t < s->n_tris; t++) {
            if (t < n_laced && grp[t] == (size_t)-2) continue;
            if (w != t) memmove(s->tri + 3 * w, s->tri + 3 * t, 3 * sizeof *s->tri);
            w++;
        }
        s->n_tris = w;
    }
done:
    free(flat), free(grp), free(e), free(wa), free(ae), free(touched);
    return st;
}
