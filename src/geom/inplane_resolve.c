/*
 * In-plane triangles of a laced surface that overlap, made one region again (see geom/inplane.h,
 * thx_inplane_resolve; build.c's step 3c).
 *
 * In one layer's plane, a closed surface's in-plane triangles (end caps, pockets and tongues cut in
 * their plane) must cover every point of the plane at most once, and every in-plane edge must be in
 * exactly two triangles. Along an in-plane edge, w laced ("wall") triangles and f in-plane triangles
 * meet; w + f = 2 on a manifold. So an edge with one wall triangle bounds the in-plane region, an edge
 * with two has no in-plane triangle beside it, and the region is the even-odd interior of the edges
 * with one wall triangle: it follows from the walls alone. Where two cuts cover the same part of the
 * plane (the slice below cuts a pocket in its upper layer, the slice above in its lower one: the bench
 * map's lungs, issue 25), the in-plane triangles are replaced by a triangulation of that region:
 * a constrained Delaunay triangulation of its boundary with grid nodes inside (as a grid cap).
 */
#include "geom/inplane.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/cdt.h"
#include "thorax/geom/predicates.h"

typedef struct {
    int32_t a, b; /* a < b */
    int wall;     /* 1: a wall triangle's edge, 0: an in-plane triangle's */
    size_t t;     /* the triangle */
} pedge;

static int cmp_pedge(const void *x, const void *y)
{
    const pedge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    if (p->wall != q->wall) return p->wall - q->wall;
    return p->t < q->t ? -1 : p->t > q->t;
}

typedef struct {
    double z;
    int32_t a, b;
    size_t t;
} zedge;

static int cmp_zedge(const void *x, const void *y)
{
    const zedge *p = x, *q = y;
    if (p->z != q->z) return p->z < q->z ? -1 : 1;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

typedef struct {
    double z;
    size_t t;
} ztri;

static int cmp_ztri(const void *x, const void *y)
{
    const ztri *p = x, *q = y;
    if (p->z != q->z) return p->z < q->z ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

typedef struct {
    double x0, x1, y0, y1;
    size_t t;
} tbox;

static int cmp_tbox(const void *x, const void *y)
{
    const tbox *p = x, *q = y;
    if (p->x0 != q->x0) return p->x0 < q->x0 ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

/* Do the interiors of in-plane triangles t and u overlap (exact; either orientation)? */
static int tri_overlap(const double *xyz, const int32_t *t, const int32_t *u)
{
    const int32_t *T[2] = {t, u};
    for (int s = 0; s < 2; s++) {
        const int32_t *A = T[s], *B = T[1 - s];
        double o = thx_orient2d(xyz + 3 * A[0], xyz + 3 * A[1], xyz + 3 * A[2]);
        if (o == 0) return 0; /* no interior */
        for (int k = 0; k < 3; k++) {
            const double *p = xyz + 3 * A[k], *q = xyz + 3 * A[(k + 1) % 3];
            int separates = 1;
            for (int m = 0; m < 3 && separates; m++) {
                double d = thx_orient2d(p, q, xyz + 3 * B[m]);
                if (o > 0 ? d > 0 : d < 0) separates = 0;
            }
            if (separates) return 0;
        }
    }
    return 1;
}

/* Do any two of the n in-plane triangles tl[] overlap? -1 out of memory. */
static int any_overlap(const thx_surface *s, const size_t *tl, size_t n)
{
    tbox *b = malloc((n ? n : 1) * sizeof *b);
    if (!b) return -1;
    for (size_t i = 0; i < n; i++) {
        const int32_t *v = s->tri + 3 * tl[i];
        b[i].t = tl[i];
        b[i].x0 = b[i].y0 = INFINITY;
        b[i].x1 = b[i].y1 = -INFINITY;
        for (int k = 0; k < 3; k++) {
            const double *p = s->xyz + 3 * v[k];
            b[i].x0 = fmin(b[i].x0, p[0]), b[i].x1 = fmax(b[i].x1, p[0]);
            b[i].y0 = fmin(b[i].y0, p[1]), b[i].y1 = fmax(b[i].y1, p[1]);
        }
    }
    qsort(b, n, sizeof *b, cmp_tbox);
    int hit = 0;
    for (size_t i = 0; i < n && !hit; i++)
        for (size_t j = i + 1; j < n && b[j].x0 < b[i].x1 && !hit; j++) {
            if (b[j].y0 >= b[i].y1 || b[j].y1 <= b[i].y0) continue;
            hit = tri_overlap(s->xyz, s->tri + 3 * b[i].t, s->tri + 3 * b[j].t);
        }
    free(b);
    return hit;
}

/* Even-odd test of point p against the segments (node pairs into pts). */
static int inside_parity(const thx_vec2 *pts, const int32_t *seg, size_t ns, double px, double py)
{
    int in = 0;
    for (size_t k = 0; k < ns; k++) {
        const thx_vec2 *a = &pts[seg[2 * k]], *b = &pts[seg[2 * k + 1]];
        if ((a->y > py) != (b->y > py)) {
            double x = a->x + (py - a->y) * (b->x - a->x) / (b->y - a->y);
            if (x > px) in = !in;
        }
    }
    return in;
}

/* The grid rows j0..j1 (row j at y = (j + 1/2) grid) whose band of half a grid spacing each side
 * segment q's y range meets: *ja..*jb. */
static void seg_rows(const thx_vec2 *pts, const int32_t *seg, size_t q, double grid, long j0, long j1, long *ja, long *jb)
{
    double ya = pts[seg[2 * q]].y, yb = pts[seg[2 * q + 1]].y;
    *ja = (long)floor((fmin(ya, yb) - 0.5 * grid) / grid - 0.5);
    *jb = (long)ceil((fmax(ya, yb) + 0.5 * grid) / grid - 0.5);
    if (*ja < j0) *ja = j0;
    if (*jb > j1) *jb = j1;
}

static double seg_dist2(const thx_vec2 *a, const thx_vec2 *b, double px, double py)
{
    double ux = b->x - a->x, uy = b->y - a->y, L = ux * ux + uy * uy;
    double t = L > 0 ? ((px - a->x) * ux + (py - a->y) * uy) / L : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double dx = a->x + t * ux - px, dy = a->y + t * uy - py;
    return dx * dx + dy * dy;
}

/* The new triangulation of one plane: triangles over plane-local points (the first nb the boundary
 * nodes, node ids in ids[]; then the points where two boundary edges cross, new nodes; then grid
 * nodes). Where two boundary edges cross (the chords of pockets cut by the slices below and above,
 * each bounding its own wall), both are split at the crossing point, and so is each one's wall
 * triangle (a fan from its third node, in its own plane): the region's two lobes meet at that node,
 * where the walls below and above meet the plane. */
typedef struct {
    size_t t;         /* the wall triangle */
    int32_t a, b;     /* its edge in the plane (node ids) */
    size_t first, n;  /* its split points, ordered from a to b: splits[first .. first + n) (plane-local) */
} wall_split;

typedef struct {
    double z;
    size_t *old;      /* the plane's in-plane triangles, replaced */
    size_t n_old;
    int32_t *ids;     /* boundary nodes' ids */
    thx_vec2 *pts;    /* boundary nodes, crossing points, grid nodes */
    size_t nb, np;
    int32_t *tris;    /* plane-local */
    size_t nt;
    wall_split *ws;
    size_t n_ws;
    int32_t *splits;
    size_t base;      /* the surface node of pts[nb] */
} plane_fix;

static void plane_fix_free(plane_fix *pf)
{
    free(pf->old), free(pf->ids), free(pf->pts), free(pf->tris), free(pf->ws), free(pf->splits);
}

typedef struct {
    double t;
    int32_t q; /* plane-local point */
} cut_pt;

static int cmp_cut(const void *x, const void *y)
{
    const cut_pt *p = x, *q = y;
    return p->t < q->t ? -1 : p->t > q->t;
}

/* 1 made, 0 the plane cannot be resolved (an edge in three wall triangles, a boundary node with other
 * than two boundary edges, boundary edges that touch other than by crossing properly), -1 out of memory. */
static int resolve_plane(const thx_surface *s, const pedge *e, size_t ne, double grid, plane_fix *pf)
{
    /* the boundary: edges with one wall triangle */
    size_t nbe = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i, w = 0;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) w += (size_t)e[j++].wall;
        if (w >= 3) return 0;
        nbe += w == 1;
        i = j;
    }
    size_t sz = nbe ? nbe : 1;
    int32_t *seg = malloc(sz * 2 * sizeof *seg), *node = malloc(sz * 2 * sizeof *node);
    size_t *wt = malloc(sz * sizeof *wt);
    thx_vec2 *pts = NULL;
    cut_pt *cuts = NULL;
    size_t *ncut = NULL;
    int32_t *seg2 = NULL, *tr = NULL, *keep = NULL;
    int r = 1;
    if (!seg || !node || !wt) { r = -1; goto out; }
    size_t k = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i, w = 0, t = 0;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) {
            if (e[j].wall) w++, t = e[j].t;
            j++;
        }
        if (w == 1) node[2 * k] = e[i].a, node[2 * k + 1] = e[i].b, wt[k] = t, k++;
        i = j;
    }
    memcpy(seg, node, 2 * nbe * sizeof *seg);
    /* the boundary nodes (sorted, unique), each with two boundary edges */
    size_t nn = 2 * nbe;
    for (size_t i = 1; i < nn; i++) { /* insertion sort: boundaries are short */
        int32_t x = node[i];
        size_t j = i;
        while (j > 0 && node[j - 1] > x) node[j] = node[j - 1], j--;
        node[j] = x;
    }
    size_t nb = 0;
    for (size_t i = 0; i < nn;) {
        size_t j = i;
        while (j < nn && node[j] == node[i]) j++;
        if (j - i != 2) { r = 0; goto out; }
        node[nb++] = node[i];
        i = j;
    }
    for (size_t i = 0; i < 2 * nbe; i++) { /* to plane-local indices */
        size_t lo = 0, hi = nb;
        while (lo + 1 < hi) {
            size_t mid = (lo + hi) / 2;
            if (node[mid] <= seg[i]) lo = mid;
            else hi = mid;
        }
        seg[i] = (int32_t)lo;
    }
    size_t cap = nb + 16, np = nb;
    pts = malloc(cap * sizeof *pts);
    if (!pts) { r = -1; goto out; }
    for (size_t i = 0; i < nb; i++) pts[i] = (thx_vec2){s->xyz[3 * node[i]], s->xyz[3 * node[i] + 1]};
    /* boundary edges that cross: both split at the crossing point */
    size_t n_cuts = 0, cap_cuts = 0;
    for (size_t a = 0; a < nbe && r == 1; a++)
        for (size_t b = a + 1; b < nbe && r == 1; b++) {
            int32_t a0 = seg[2 * a], a1 = seg[2 * a + 1], b0 = seg[2 * b], b1 = seg[2 * b + 1];
            const double *p0 = &pts[a0].x, *p1 = &pts[a1].x, *q0 = &pts[b0].x, *q1 = &pts[b1].x;
            if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) {
                /* neighbours: they may only meet at their shared node */
                if (a0 == b0 && a1 == b1) { r = 0; break; }
                int32_t sa = (a0 == b0 || a0 == b1) ? a1 : a0, sb = (b0 == a0 || b0 == a1) ? b1 : b0;
                int32_t c = (a0 == b0 || a0 == b1) ? a0 : a1;
                if (thx_orient2d(&pts[c].x, &pts[sa].x, &pts[sb].x) == 0 &&
                    (pts[sa].x - pts[c].x) * (pts[sb].x - pts[c].x) + (pts[sa].y - pts[c].y) * (pts[sb].y - pts[c].y) > 0)
                    r = 0; /* folded onto each other */
                continue;
            }
            if (!thx_segments_touch(p0, p1, q0, q1)) continue;
            double o0 = thx_orient2d(p0, p1, q0), o1 = thx_orient2d(p0, p1, q1);
            double o2 = thx_orient2d(q0, q1, p0), o3 = thx_orient2d(q0, q1, p1);
            if (!((o0 > 0 && o1 < 0) || (o0 < 0 && o1 > 0)) || !((o2 > 0 && o3 < 0) || (o2 < 0 && o3 > 0))) {
                r = 0; /* a node on another edge, or collinear overlap */
                break;
            }
            double ta = o2 / (o2 - o3), tb = o0 / (o0 - o1);
            if (!(ta > 1e-6 && ta < 1 - 1e-6 && tb > 1e-6 && tb < 1 - 1e-6)) { r = 0; break; }
            if (np == cap) {
                cap *= 2;
                thx_vec2 *n2 = realloc(pts, cap * sizeof *n2);
                if (!n2) { r = -1; break; }
                pts = n2;
                p0 = &pts[a0].x, p1 = &pts[a1].x;
            }
            pts[np] = (thx_vec2){p0[0] + ta * (p1[0] - p0[0]), p0[1] + ta * (p1[1] - p0[1])};
            if (n_cuts + 2 > cap_cuts) {
                cap_cuts = cap_cuts ? 2 * cap_cuts : 16;
                cut_pt *nc = realloc(cuts, cap_cuts * 2 * sizeof *nc);
                size_t *nn2 = realloc(ncut, cap_cuts * sizeof *nn2);
                if (nc) cuts = nc;
                if (nn2) ncut = nn2;
                if (!nc || !nn2) { r = -1; break; }
            }
            /* (segment, parameter, point) as two records: segment index in ncut[] */
            cuts[2 * n_cuts] = (cut_pt){ta, (int32_t)np}, ncut[n_cuts++] = a;
            cuts[2 * n_cuts] = (cut_pt){tb, (int32_t)np}, ncut[n_cuts++] = b;
            np++;
        }
    if (r != 1) goto out;
    size_t n_seg = nbe;
    if (n_cuts) {
        /* the split segments, and each one's wall triangle split along with it */
        seg2 = malloc((nbe + n_cuts) * 2 * sizeof *seg2);
        pf->ws = malloc(nbe * sizeof *pf->ws);
        pf->splits = malloc(n_cuts * sizeof *pf->splits);
        cut_pt *mine = malloc(n_cuts * sizeof *mine);
        if (!seg2 || !pf->ws || !pf->splits || !mine) { free(mine); r = -1; goto out; }
        n_seg = 0;
        size_t n_split = 0;
        for (size_t a = 0; a < nbe; a++) {
            size_t m = 0;
            for (size_t c = 0; c < n_cuts; c++)
                if (ncut[c] == a) mine[m++] = cuts[2 * c];
            qsort(mine, m, sizeof *mine, cmp_cut);
            int32_t prev = seg[2 * a];
            if (m) {
                /* the split points from the wall edge's node a (its smaller id) to b */
                int32_t ia = node[seg[2 * a]], ib = node[seg[2 * a + 1]];
                wall_split *w = &pf->ws[pf->n_ws++];
                w->t = wt[a], w->a = ia, w->b = ib, w->first = n_split, w->n = m;
                for (size_t c = 0; c < m; c++) pf->splits[n_split++] = mine[c].q;
            }
            for (size_t c = 0; c < m; c++) {
                seg2[2 * n_seg] = prev, seg2[2 * n_seg + 1] = mine[c].q, n_seg++;
                prev = mine[c].q;
            }
            seg2[2 * n_seg] = prev, seg2[2 * n_seg + 1] = seg[2 * a + 1], n_seg++;
        }
        free(mine);
        free(seg);
        seg = seg2;
        seg2 = NULL;
    }
    /* grid nodes inside, at least grid/2 from the boundary: each grid row tests the segments whose y range
       meets its band (row lists of segment indices) */
    if (grid > 0 && nb) {
        double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        for (size_t i = 0; i < nb; i++)
            x0 = fmin(x0, pts[i].x), x1 = fmax(x1, pts[i].x), y0 = fmin(y0, pts[i].y), y1 = fmax(y1, pts[i].y);
        double tol2 = 0.25 * grid * grid;
        long i0 = (long)floor(x0 / grid - 0.5), i1 = (long)ceil(x1 / grid - 0.5);
        long j0 = (long)floor(y0 / grid - 0.5), j1 = (long)ceil(y1 / grid - 0.5);
        size_t nrow = (size_t)(j1 - j0 + 1);
        size_t *rstart = calloc(nrow + 1, sizeof *rstart), *rlist = NULL, total = 0;
        if (!rstart) { r = -1; goto out; }
        for (size_t q = 0; q < n_seg; q++) {
            long ja, jb;
            seg_rows(pts, seg, q, grid, j0, j1, &ja, &jb);
            for (long jj = ja; jj <= jb; jj++) rstart[jj - j0 + 1]++;
        }
        for (size_t k2 = 0; k2 < nrow; k2++) rstart[k2 + 1] += rstart[k2];
        total = rstart[nrow];
        rlist = malloc((total ? total : 1) * sizeof *rlist);
        if (!rlist) { free(rstart); r = -1; goto out; }
        size_t *fill = calloc(nrow, sizeof *fill);
        if (!fill) { free(rstart), free(rlist); r = -1; goto out; }
        for (size_t q = 0; q < n_seg; q++) {
            long ja, jb;
            seg_rows(pts, seg, q, grid, j0, j1, &ja, &jb);
            for (long jj = ja; jj <= jb; jj++) rlist[rstart[jj - j0] + fill[jj - j0]++] = q;
        }
        free(fill);
        for (long j = j0; j <= j1 && r == 1; j++) {
            const size_t *rl = rlist + rstart[j - j0];
            size_t rn = rstart[j - j0 + 1] - rstart[j - j0];
            double py = ((double)j + 0.5) * grid;
            for (long i = i0; i <= i1; i++) {
                double px = ((double)i + 0.5) * grid;
                int in = 0, near = 0;
                for (size_t u = 0; u < rn && !near; u++) {
                    const thx_vec2 *a = &pts[seg[2 * rl[u]]], *b = &pts[seg[2 * rl[u] + 1]];
                    if ((a->y > py) != (b->y > py) && a->x + (py - a->y) * (b->x - a->x) / (b->y - a->y) > px) in = !in;
                    near = seg_dist2(a, b, px, py) < tol2;
                }
                if (!in || near) continue;
                if (np == cap) {
                    cap *= 2;
                    thx_vec2 *n2 = realloc(pts, cap * sizeof *n2);
                    if (!n2) { r = -1; break; }
                    pts = n2;
                }
                pts[np++] = (thx_vec2){px, py};
            }
        }
        free(rstart), free(rlist);
        if (r != 1) goto out;
    }
    size_t ntr = 0, nk = 0;
    if (n_seg) {
        thx_ctx *lc = NULL; /* a boundary the triangulation refuses leaves the plane as it was */
        thx_status cs = thx_ctx_create(&lc);
        if (cs == THX_OK) cs = thx_cdt2d(lc, pts, np, seg, n_seg, &tr, &ntr);
        thx_ctx_destroy(&lc);
        if (cs == THX_ENOMEM) { r = -1; goto out; }
        if (cs != THX_OK) { r = 0; goto out; }
        keep = malloc((ntr ? ntr : 1) * 3 * sizeof *keep);
        if (!keep) { r = -1; goto out; }
        for (size_t t = 0; t < ntr; t++) {
            const thx_vec2 *a = &pts[tr[3 * t]], *b = &pts[tr[3 * t + 1]], *c = &pts[tr[3 * t + 2]];
            if (!inside_parity(pts, seg, n_seg, (a->x + b->x + c->x) / 3.0, (a->y + b->y + c->y) / 3.0)) continue;
            memcpy(keep + 3 * nk++, tr + 3 * t, 3 * sizeof *keep);
        }
    }
    pf->ids = node;
    pf->pts = pts;
    pf->nb = nb;
    pf->np = np;
    pf->tris = keep;
    pf->nt = nk;
    node = NULL, pts = NULL, keep = NULL;
out:
    free(seg), free(node), free(wt), free(pts), free(cuts), free(ncut), free(seg2), free(tr), free(keep);
    return r;
}

/* smallest angle (degrees) of a plane's new triangles (the split wall triangles not counted: a split
 * at a crossing point only happens in a plane that is resolved whatever its angles) */
static double fix_min_angle(const plane_fix *pf)
{
    double m = 180.0;
    for (size_t t = 0; t < pf->nt; t++) {
        const thx_vec2 *a = &pf->pts[pf->tris[3 * t]], *b = &pf->pts[pf->tris[3 * t + 1]], *c = &pf->pts[pf->tris[3 * t + 2]];
        m = fmin(m, inplane_min_angle2(a->x, a->y, b->x, b->y, c->x, c->y));
    }
    return m;
}

thx_status thx_inplane_resolve(thx_ctx *ctx, thx_surface *s, double grid, double min_angle_deg, size_t *node_cap,
                               size_t *tri_cap, size_t *n_resolved, size_t *n_new_tris)
{
    *n_resolved = 0;
    *n_new_tris = 0;
    size_t nt = s->n_tris, nf = 0, nw = 0;
    thx_status st = THX_OK;
    ztri *ft = thx_malloc(ctx, (nt ? nt : 1) * sizeof *ft);
    zedge *we = thx_malloc(ctx, (nt ? nt : 1) * sizeof *we);
    plane_fix *fix = NULL;
    size_t n_fix = 0, cap_fix = 0;
    pedge *e = NULL;
    size_t *tl = NULL;
    unsigned char *gone = NULL;
    if (!ft || !we) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = s->tri + 3 * t;
        double z0 = s->xyz[3 * v[0] + 2], z1 = s->xyz[3 * v[1] + 2], z2 = s->xyz[3 * v[2] + 2];
        if (z0 == z1 && z1 == z2) ft[nf++] = (ztri){z0, t};
        else {
            int32_t a = z0 == z1 ? v[0] : z1 == z2 ? v[1] : v[2], b = z0 == z1 ? v[1] : z1 == z2 ? v[2] : v[0];
            if (z0 == z1 || z1 == z2 || z2 == z0) we[nw++] = (zedge){s->xyz[3 * a + 2], a < b ? a : b, a < b ? b : a, t};
        }
    }
    if (!nf) goto done;
    qsort(ft, nf, sizeof *ft, cmp_ztri);
    qsort(we, nw, sizeof *we, cmp_zedge);
    tl = thx_malloc(ctx, nf * sizeof *tl);
    if (!tl) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0, w0 = 0; i < nf;) {
        size_t j = i;
        double z = ft[i].z;
        while (j < nf && ft[j].z == z) j++;
        while (w0 < nw && we[w0].z < z) w0++;
        size_t w1 = w0;
        while (w1 < nw && we[w1].z == z) w1++;
        size_t ne = 3 * (j - i) + (w1 - w0);
        pedge *ne_e = thx_realloc(ctx, e, ne * sizeof *e);
        if (!ne_e) { st = THX_ENOMEM; goto done; }
        e = ne_e;
        size_t q = 0;
        for (size_t f = i; f < j; f++) {
            const int32_t *v = s->tri + 3 * ft[f].t;
            tl[f - i] = ft[f].t;
            for (int k = 0; k < 3; k++) {
                int32_t a = v[k], b = v[(k + 1) % 3];
                e[q++] = (pedge){a < b ? a : b, a < b ? b : a, 0, ft[f].t};
            }
        }
        for (size_t w = w0; w < w1; w++) e[q++] = (pedge){we[w].a, we[w].b, 1, we[w].t};
        qsort(e, ne, sizeof *e, cmp_pedge);
        int bad = 0;
        for (size_t a = 0; a < ne && !bad;) {
            size_t b = a;
            while (b < ne && e[b].a == e[a].a && e[b].b == e[a].b) b++;
            bad = b - a != 2;
            a = b;
        }
        if (!bad) {
            bad = any_overlap(s, tl, j - i);
            if (bad < 0) { st = THX_ENOMEM; goto done; }
        }
        /* a plane that is well formed but has an in-plane angle under min_angle_deg (a patch step 3b
           could not take: its boundary is no one simple loop) is triangulated again when that is better */
        double worst = 180.0;
        for (size_t f = i; f < j; f++) worst = fmin(worst, inplane_tri_min_angle(s, ft[f].t));
        int quality = !bad && worst < min_angle_deg;
        if (bad || quality) {
            plane_fix pf = {0};
            int r = resolve_plane(s, e, ne, grid, &pf);
            if (r == 1 && quality && !(fix_min_angle(&pf) > worst)) r = 0;
            if (r == 1) {
                pf.z = z;
                pf.n_old = j - i;
                pf.old = malloc(pf.n_old * sizeof *pf.old);
                if (pf.old) memcpy(pf.old, tl, pf.n_old * sizeof *pf.old);
                if (pf.old && n_fix == cap_fix) {
                    cap_fix = cap_fix ? 2 * cap_fix : 8;
                    plane_fix *nfix = realloc(fix, cap_fix * sizeof *nfix);
                    if (nfix) fix = nfix;
                    else r = -1;
                }
                if (!pf.old) r = -1;
                if (r == 1) fix[n_fix++] = pf;
            }
            if (r != 1) plane_fix_free(&pf);
            if (r < 0) { st = THX_ENOMEM; goto done; }
        }
        i = j;
        w0 = w1;
    }
    if (!n_fix) goto done;
    /* the new nodes (crossing points, grid nodes); the wall triangles split at crossing points; the old
       in-plane triangles out, the new ones in */
    size_t add_n = 0, add_t = 0;
    for (size_t f = 0; f < n_fix; f++) {
        add_n += fix[f].np - fix[f].nb;
        add_t += fix[f].nt;
        for (size_t w = 0; w < fix[f].n_ws; w++) add_t += fix[f].ws[w].n;
    }
    if (s->n_nodes + add_n > *node_cap) {
        size_t nc = (s->n_nodes + add_n) * 2;
        double *nx = thx_realloc(ctx, s->xyz, nc * 3 * sizeof *nx);
        if (!nx) { st = THX_ENOMEM; goto done; }
        s->xyz = nx;
        *node_cap = nc;
    }
    if (s->n_tris + add_t > *tri_cap) {
        size_t nc = (s->n_tris + add_t) * 2;
        int32_t *ntr = thx_realloc(ctx, s->tri, nc * 3 * sizeof *ntr);
        if (!ntr) { st = THX_ENOMEM; goto done; }
        s->tri = ntr;
        *tri_cap = nc;
    }
    for (size_t f = 0; f < n_fix; f++) {
        plane_fix *pf = &fix[f];
        size_t base = pf->base = s->n_nodes;
        for (size_t i = pf->nb; i < pf->np; i++) {
            s->xyz[3 * s->n_nodes] = pf->pts[i].x;
            s->xyz[3 * s->n_nodes + 1] = pf->pts[i].y;
            s->xyz[3 * s->n_nodes + 2] = pf->z;
            s->n_nodes++;
        }
#define GLOBAL(q) ((size_t)(q) < pf->nb ? pf->ids[q] : (int32_t)(base + (size_t)(q) - pf->nb))
        for (size_t w = 0; w < pf->n_ws; w++) {
            const wall_split *ws = &pf->ws[w];
            int32_t *tv = s->tri + 3 * ws->t, v[3] = {tv[0], tv[1], tv[2]};
            int p = 0;
            while (p < 3 && !((v[p] == ws->a && v[(p + 1) % 3] == ws->b) || (v[p] == ws->b && v[(p + 1) % 3] == ws->a))) p++;
            if (p == 3) { st = thx_error(ctx, THX_EGEOM, "in-plane resolve: a wall triangle lost its edge"); goto done; }
            int fwd = v[p] == ws->a, x = v[(p + 2) % 3];
            int32_t prev = v[p];
            for (size_t c = 0; c <= ws->n; c++) {
                int32_t nxt = c < ws->n ? GLOBAL(pf->splits[ws->first + (fwd ? c : ws->n - 1 - c)]) : v[(p + 1) % 3];
                int32_t *dst = c == 0 ? tv : s->tri + 3 * s->n_tris++;
                dst[0] = prev, dst[1] = nxt, dst[2] = x;
                prev = nxt;
            }
        }
    }
    /* the new in-plane triangles last (*n_new_tris: the orientation takes them from their neighbours) */
    for (size_t f = 0; f < n_fix; f++) {
        plane_fix *pf = &fix[f];
        size_t base = pf->base;
        for (size_t t = 0; t < pf->nt; t++) {
            for (int v = 0; v < 3; v++) s->tri[3 * s->n_tris + (size_t)v] = GLOBAL(pf->tris[3 * t + v]);
            s->n_tris++;
        }
        *n_new_tris += pf->nt;
    }
#undef GLOBAL
    gone = thx_calloc(ctx, nt ? nt : 1, 1);
    if (!gone) { st = THX_ENOMEM; goto done; }
    for (size_t f = 0; f < n_fix; f++)
        for (size_t k = 0; k < fix[f].n_old; k++) gone[fix[f].old[k]] = 1;
    size_t w = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        if (t < nt && gone[t]) continue;
        if (w != t) memmove(s->tri + 3 * w, s->tri + 3 * t, 3 * sizeof *s->tri);
        w++;
    }
    s->n_tris = w;
    *n_resolved = n_fix;
done:
    for (size_t f = 0; f < n_fix; f++) plane_fix_free(&fix[f]);
    free(fix), free(ft), free(we), free(e), free(tl), free(gone);
    return st;
}

thx_status thx_surface_drop_unused(thx_ctx *ctx, thx_surface *s, size_t *n_dropped)
{
    *n_dropped = 0;
    int32_t *map = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < s->n_nodes; i++) map[i] = -1;
    for (size_t k = 0; k < 3 * s->n_tris; k++) map[s->tri[k]] = 0;
    size_t m = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        if (map[i] < 0) continue;
        if (m != i) memcpy(s->xyz + 3 * m, s->xyz + 3 * i, 3 * sizeof *s->xyz);
        map[i] = (int32_t)m++;
    }
    for (size_t k = 0; k < 3 * s->n_tris; k++) s->tri[k] = map[s->tri[k]];
    *n_dropped = s->n_nodes - m;
    s->n_nodes = m;
    free(map);
    return THX_OK;
}
