/* Invariant checks of triangle surfaces and models (see thorax/check/check.h; paper 3.2). */
#include "thorax/check/check.h"
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include "thorax/geom/spatial.h"
#include "thorax/core/union_find.h"
#include "thorax/geom/tri_intersect.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* OpenMP pragmas that vanish (without -Wunknown-pragmas noise) when the
 * library is built without OpenMP. */
#ifdef _OPENMP
#define THX_OMP(x) _Pragma(#x)
#else
#define THX_OMP(x)
#endif

const double thx_check_aspect_edges[THX_CHECK_ASPECT_BINS + 1] = {1.0, 1.25, 1.5, 2.0, 3.0, 5.0, 10.0, 100.0, INFINITY};

void thx_check_opts_default(thx_check_opts *o)
{
    o->solid_angle_tol = 1e-6;
    o->check_intersections = 1;
    o->min_angle_deg = THX_CHECK_MIN_ANGLE_DEG;
    o->max_aspect = 0.0;
}

const char *thx_check_failure_name(thx_check_failure f)
{
    switch (f) {
    case THX_CHECKF_EMPTY: return "empty";
    case THX_CHECKF_BAD_INDEX: return "bad_index";
    case THX_CHECKF_BOUNDARY: return "boundary";
    case THX_CHECKF_NONMANIFOLD: return "nonmanifold";
    case THX_CHECKF_ORIENTATION: return "orientation";
    case THX_CHECKF_DUPLICATE: return "duplicate";
    case THX_CHECKF_DEGENERATE: return "degenerate";
    case THX_CHECKF_UNUSED: return "unused_nodes";
    case THX_CHECKF_VOLUME: return "volume";
    case THX_CHECKF_SOLID_ANGLE: return "solid_angle";
    case THX_CHECKF_INTERSECTION: return "intersection";
    case THX_CHECKF_QUALITY: return "quality";
    }
    return "?";
}

static void add_reason(thx_surface_report *r, thx_check_failure f, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void add_reason(thx_surface_report *r, thx_check_failure f, const char *fmt, ...)
{
    r->failures |= (unsigned)f;
    if (r->n_reasons >= THX_CHECK_MAX_REASONS) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->reasons[r->n_reasons++], sizeof r->reasons[0], fmt, ap);
    va_end(ap);
}

static int sgn(double x) { return (x > 0) - (x < 0); }

static double o3(const double *a, const double *b, const double *c, const double *d)
{
    return thx_orient3d(a, b, c, d);
}

/* ------------------------------------------------------------------ */
/* Interior point search (orientation-free). */

/* Deterministic pseudo-random unit vectors (64-bit LCG, fixed seed). */
static thx_vec3 ray_direction(uint64_t *state)
{
    for (;;) {
        double v[3];
        for (int k = 0; k < 3; k++) {
            *state = *state * 6364136223846793005ull + 1442695040888963407ull;
            v[k] = 2.0 * (double)(*state >> 11) / 9007199254740992.0 - 1.0;
        }
        double n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (n2 > 1e-4 && n2 <= 1.0) {
            double n = sqrt(n2);
            return thx_v3(v[0] / n, v[1] / n, v[2] / n);
        }
    }
}

typedef struct {
    const thx_surface *s;
    const unsigned char *degen; /* per triangle: 1 = exactly degenerate */
    const double *p, *q;
    size_t skip; /* triangle to ignore */
    int crossings;
    int ambiguous; /* the ray touched an edge or vertex, or p is on the surface */
    /* nearest hit along p + t (q - p), floating point */
    double t_min;
} ray_state;

/* Exact parity visitor: counts proper crossings of segment p-q; a touch of an
 * edge, a vertex or the plane of a triangle at an endpoint makes the ray
 * ambiguous (it is discarded). */
static int ray_parity_visit(void *user, size_t t)
{
    ray_state *rs = user;
    if (rs->degen[t]) return 0;
    const int32_t *v = rs->s->tri + 3 * t;
    const double *a = rs->s->xyz + 3 * (size_t)v[0], *b = rs->s->xyz + 3 * (size_t)v[1];
    const double *c = rs->s->xyz + 3 * (size_t)v[2];
    int sp = sgn(o3(a, b, c, rs->p)), sq = sgn(o3(a, b, c, rs->q));
    if (sp == sq && sp != 0) return 0;
    if (sp == 0 || sq == 0) {
        if (thx_segment_triangle3(rs->p, rs->q, a, b, c)) {
            rs->ambiguous = 1;
            return 1;
        }
        return 0;
    }
    int w1 = sgn(o3(rs->p, rs->q, a, b)), w2 = sgn(o3(rs->p, rs->q, b, c)), w3 = sgn(o3(rs->p, rs->q, c, a));
    if ((w1 > 0 && w2 > 0 && w3 > 0) || (w1 < 0 && w2 < 0 && w3 < 0)) rs->crossings++;
    else if ((w1 >= 0 && w2 >= 0 && w3 >= 0) || (w1 <= 0 && w2 <= 0 && w3 <= 0)) {
        rs->ambiguous = 1; /* through an edge or a vertex */
        return 1;
    }
    return 0;
}

/* Floating-point nearest hit (Moller-Trumbore, slightly widened so a ray
 * through a shared edge is not missed), for choosing candidate points only. */
static int ray_nearest_visit(void *user, size_t t)
{
    ray_state *rs = user;
    if (t == rs->skip || rs->degen[t]) return 0;
    const int32_t *v = rs->s->tri + 3 * t;
    thx_vec3 a = thx_surface_node(rs->s, (size_t)v[0]), b = thx_surface_node(rs->s, (size_t)v[1]);
    thx_vec3 c = thx_surface_node(rs->s, (size_t)v[2]);
    thx_vec3 o = thx_v3(rs->p[0], rs->p[1], rs->p[2]);
    thx_vec3 d = thx_v3(rs->q[0] - rs->p[0], rs->q[1] - rs->p[1], rs->q[2] - rs->p[2]);
    thx_vec3 e1 = thx_v3_sub(b, a), e2 = thx_v3_sub(c, a);
    thx_vec3 h = thx_v3_cross(d, e2);
    double det = thx_v3_dot(e1, h);
    if (det == 0.0) return 0;
    double inv = 1.0 / det;
    thx_vec3 sv = thx_v3_sub(o, a);
    double u = thx_v3_dot(sv, h) * inv;
    const double eps = 1e-9;
    if (u < -eps || u > 1.0 + eps) return 0;
    thx_vec3 qv = thx_v3_cross(sv, e1);
    double w = thx_v3_dot(d, qv) * inv;
    if (w < -eps || u + w > 1.0 + eps) return 0;
    double tt = thx_v3_dot(e2, qv) * inv;
    if (tt > 0.0 && tt < rs->t_min) rs->t_min = tt;
    return 0;
}

typedef struct {
    double gap;
    size_t order;
    thx_vec3 p;
} candidate;

static int cmp_candidate(const void *x, const void *y)
{
    const candidate *a = x, *b = y;
    if (a->gap != b->gap) return a->gap > b->gap ? -1 : 1;
    return (a->order > b->order) - (a->order < b->order);
}

/* Classifies p by ray parity: 1 inside, 0 outside, -1 undecided. */
static int parity_inside(const thx_surface *s, const thx_bvh *bvh, const unsigned char *degen, thx_vec3 p,
                         double reach)
{
    uint64_t state = 0x9e3779b97f4a7c15ull; /* fixed seed: deterministic */
    int inside = 0, outside = 0, valid = 0;
    double pp[3] = {p.x, p.y, p.z};
    for (int tries = 0; tries < 21 && valid < 7; tries++) {
        thx_vec3 d = ray_direction(&state);
        double qq[3] = {p.x + reach * d.x, p.y + reach * d.y, p.z + reach * d.z};
        ray_state rs = {s, degen, pp, qq, (size_t)-1, 0, 0, INFINITY};
        thx_bvh_query_segment(bvh, pp, qq, ray_parity_visit, &rs);
        if (rs.ambiguous) continue;
        valid++;
        if (rs.crossings & 1) inside++;
        else outside++;
    }
    if (valid < 3 || inside == outside) return -1;
    return inside > outside;
}

enum { N_CANDIDATE_TRIS = 8 };

/* The search itself, on a checked surface with its tree and degeneracy flags. */
static int find_interior(const thx_surface *s, const thx_bvh *bvh, const unsigned char *degen, thx_vec3 *out)
{
    /* bounding box: rays must end outside it */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], s->xyz[3 * i + a]);
            hi[a] = fmax(hi[a], s->xyz[3 * i + a]);
        }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(diag > 0.0)) return 0;
    double reach = 4.0 * diag;

    /* the N largest triangles (ties by index) */
    size_t top[2 * N_CANDIDATE_TRIS];
    double top_area[N_CANDIDATE_TRIS];
    size_t n_top = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        if (degen[t]) continue;
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 a = thx_surface_node(s, (size_t)v[0]);
        double ar = thx_v3_norm(thx_v3_cross(thx_v3_sub(thx_surface_node(s, (size_t)v[1]), a),
                                             thx_v3_sub(thx_surface_node(s, (size_t)v[2]), a)));
        size_t k = n_top < N_CANDIDATE_TRIS ? n_top++ : N_CANDIDATE_TRIS;
        if (k == N_CANDIDATE_TRIS) {
            if (!(ar > top_area[N_CANDIDATE_TRIS - 1])) continue;
            k = N_CANDIDATE_TRIS - 1;
        }
        while (k > 0 && ar > top_area[k - 1]) {
            top[k] = top[k - 1];
            top_area[k] = top_area[k - 1];
            k--;
        }
        top[k] = t;
        top_area[k] = ar;
    }

    /* then triangles spread over the index range, in case the largest all sit
     * where the inside is hard to reach (thin slabs, touching parts) */
    for (size_t k = 0; k < N_CANDIDATE_TRIS && s->n_tris > 0; k++) {
        size_t t = (2 * k + 1) * s->n_tris / (2 * N_CANDIDATE_TRIS);
        int dup = degen[t] != 0;
        for (size_t j = 0; j < n_top && !dup; j++) dup = top[j] == t;
        if (!dup) top[n_top++] = t;
    }

    candidate cand[4 * N_CANDIDATE_TRIS];
    size_t n_cand = 0;
    for (size_t k = 0; k < n_top; k++) {
        const int32_t *v = s->tri + 3 * top[k];
        thx_vec3 a = thx_surface_node(s, (size_t)v[0]), b = thx_surface_node(s, (size_t)v[1]);
        thx_vec3 c = thx_surface_node(s, (size_t)v[2]);
        thx_vec3 cen = thx_v3_scale(thx_v3_add(a, thx_v3_add(b, c)), 1.0 / 3.0);
        thx_vec3 n = thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a));
        double nn = thx_v3_norm(n);
        if (!(nn > 0.0)) continue;
        n = thx_v3_scale(n, 1.0 / nn);
        for (int side = 0; side < 2; side++) {
            thx_vec3 dir = thx_v3_scale(n, side ? -1.0 : 1.0);
            double pp[3] = {cen.x, cen.y, cen.z};
            double qq[3] = {cen.x + reach * dir.x, cen.y + reach * dir.y, cen.z + reach * dir.z};
            ray_state rs = {s, degen, pp, qq, top[k], 0, 0, INFINITY};
            thx_bvh_query_segment(bvh, pp, qq, ray_nearest_visit, &rs);
            if (!isfinite(rs.t_min)) continue; /* escapes: that side is outside */
            double gap = 0.5 * rs.t_min * reach;
            if (!(gap > 1e-9 * diag)) continue;
            cand[n_cand].gap = gap;
            cand[n_cand].order = n_cand;
            cand[n_cand].p = thx_v3_add(cen, thx_v3_scale(dir, gap));
            n_cand++;
        }
    }
    qsort(cand, n_cand, sizeof cand[0], cmp_candidate);
    for (size_t k = 0; k < n_cand; k++)
        if (parity_inside(s, bvh, degen, cand[k].p, reach) == 1) {
            *out = cand[k].p;
            return 1;
        }
    return 0;
}

/* Index range check; returns the number of bad triangles and the first. */
static size_t count_bad_index(const thx_surface *s, size_t *first)
{
    size_t n = 0;
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int32_t v = s->tri[3 * t + k];
            if (v < 0 || (size_t)v >= s->n_nodes) {
                if (!n) *first = t;
                n++;
                break;
            }
        }
    return n;
}

/* Per-triangle degeneracy: repeated node (topological) = 2, collinear = 1, else 0. */
static unsigned char *degeneracy(thx_ctx *ctx, const thx_surface *s)
{
    unsigned char *dg = thx_calloc(ctx, s->n_tris ? s->n_tris : 1, 1);
    if (!dg) return NULL;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) dg[t] = 2;
        else if (thx_collinear3(s->xyz + 3 * (size_t)v[0], s->xyz + 3 * (size_t)v[1], s->xyz + 3 * (size_t)v[2]))
            dg[t] = 1;
    }
    return dg;
}

thx_status thx_surface_find_interior(thx_ctx *ctx, const thx_surface *s, thx_vec3 *p)
{
    size_t first = 0;
    if (count_bad_index(s, &first))
        return thx_error(ctx, THX_EINPUT, "surface \"%s\": triangle %zu refers to a node outside 1..%zu", s->name,
                         first + 1, s->n_nodes);
    thx_status st = THX_OK;
    thx_bvh *bvh = NULL;
    unsigned char *dg = degeneracy(ctx, s);
    if (!dg) return THX_ENOMEM;
    THX_TRY(thx_bvh_create_triangles(ctx, s->xyz, s->n_nodes, s->tri, s->n_tris, &bvh));
    if (!find_interior(s, bvh, dg, p))
        st = thx_error(ctx, THX_EGEOM, "surface \"%s\": no interior point found (is it closed?)", s->name);
done:
    thx_bvh_destroy(&bvh);
    free(dg);
    return st;
}

/* ------------------------------------------------------------------ */
/* Topology. */

typedef struct {
    int32_t hi;   /* the larger node of the edge (the smaller is the CSR bucket) */
    uint32_t t;   /* triangle */
    int32_t from; /* the node the triangle's edge starts at (direction) */
} half_edge;

static int cmp_half_edge(const void *x, const void *y)
{
    const half_edge *a = x, *b = y;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

typedef struct {
    int32_t k[3];
    size_t t;
} tri_key;

static int cmp_tri_key(const void *x, const void *y)
{
    const tri_key *a = x, *b = y;
    for (int i = 0; i < 3; i++)
        if (a->k[i] != b->k[i]) return a->k[i] < b->k[i] ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

typedef struct {
    int32_t other;
    uint32_t slot; /* position of the triangle in the vertex's fan list */
} fan_entry;

static int cmp_fan_entry(const void *x, const void *y)
{
    const fan_entry *a = x, *b = y;
    if (a->other != b->other) return a->other < b->other ? -1 : 1;
    return (a->slot > b->slot) - (a->slot < b->slot);
}

/* Edges, components, non-manifold vertices, duplicates, unused nodes. Only
 * triangles with three distinct nodes take part (dg[t] != 2). */
static thx_status topology(thx_ctx *ctx, const thx_surface *s, const unsigned char *dg, thx_surface_report *r)
{
    thx_status st = THX_OK;
    size_t nv = s->n_nodes, nt = s->n_tris;
    size_t *start = thx_calloc(ctx, nv + 1, sizeof *start);
    half_edge *he = thx_malloc(ctx, (3 * nt + 1) * sizeof *he);
    size_t *parent = thx_malloc(ctx, (nt + 1) * sizeof *parent);
    size_t *vstart = thx_calloc(ctx, nv + 1, sizeof *vstart);
    uint32_t *vtri = thx_malloc(ctx, (3 * nt + 1) * sizeof *vtri);
    tri_key *keys = thx_malloc(ctx, (nt + 1) * sizeof *keys);
    fan_entry *fan = NULL;
    size_t *fparent = NULL;
    size_t fan_cap = 0;
    if (!start || !he || !parent || !vstart || !vtri || !keys) {
        st = THX_ENOMEM;
        goto done;
    }

    /* half-edges bucketed by their smaller node (counting sort keeps triangle order) */
    for (size_t t = 0; t < nt; t++) {
        parent[t] = t;
        if (dg[t] == 2) continue;
        for (int k = 0; k < 3; k++) {
            int32_t u = s->tri[3 * t + k], w = s->tri[3 * t + (k + 1) % 3];
            start[(size_t)(u < w ? u : w) + 1]++;
            vstart[(size_t)u + 1]++;
        }
    }
    for (size_t i = 0; i < nv; i++) {
        start[i + 1] += start[i];
        vstart[i + 1] += vstart[i];
    }
    {
        size_t *fill = thx_malloc(ctx, (nv + 1) * sizeof *fill);
        size_t *vfill = thx_malloc(ctx, (nv + 1) * sizeof *vfill);
        if (!fill || !vfill) {
            free(fill);
            free(vfill);
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(fill, start, nv * sizeof *fill);
        memcpy(vfill, vstart, nv * sizeof *vfill);
        for (size_t t = 0; t < nt; t++) {
            if (dg[t] == 2) continue;
            for (int k = 0; k < 3; k++) {
                int32_t u = s->tri[3 * t + k], w = s->tri[3 * t + (k + 1) % 3];
                size_t lo = (size_t)(u < w ? u : w);
                half_edge h = {u < w ? w : u, (uint32_t)t, u};
                he[fill[lo]++] = h;
                vtri[vfill[(size_t)u]++] = (uint32_t)t;
            }
        }
        free(fill);
        free(vfill);
    }

    /* edges: groups of equal (lo, hi) */
    size_t n_faces = 0;
    for (size_t t = 0; t < nt; t++) n_faces += dg[t] != 2;
    for (size_t lo = 0; lo < nv; lo++) {
        size_t b = start[lo], e = start[lo + 1];
        if (e - b > 1) qsort(he + b, e - b, sizeof *he, cmp_half_edge);
        for (size_t g = b; g < e;) {
            size_t h = g;
            while (h < e && he[h].hi == he[g].hi) h++;
            size_t m = h - g;
            r->n_edges++;
            if (m == 1) {
                if (!r->n_boundary_edges) {
                    r->ex_boundary_edge[0] = (int32_t)lo;
                    r->ex_boundary_edge[1] = he[g].hi;
                }
                r->n_boundary_edges++;
            } else if (m == 2) {
                if (he[g].from == he[g + 1].from) {
                    if (!r->n_inconsistent_edges) {
                        r->ex_inconsistent_edge[0] = (int32_t)lo;
                        r->ex_inconsistent_edge[1] = he[g].hi;
                    }
                    r->n_inconsistent_edges++;
                }
            } else {
                if (!r->n_nonmanifold_edges) {
                    r->ex_nonmanifold_edge[0] = (int32_t)lo;
                    r->ex_nonmanifold_edge[1] = he[g].hi;
                }
                r->n_nonmanifold_edges++;
            }
            for (size_t k = g + 1; k < h; k++) uf_union(parent, he[g].t, he[k].t);
            g = h;
        }
    }
    for (size_t t = 0; t < nt; t++)
        if (dg[t] != 2 && uf_find(parent, t) == t) r->n_components++;

    /* vertices: unused, and the number of fans (triangles around v joined
     * through the edges at v) */
    size_t used = 0;
    for (size_t v = 0; v < nv; v++) {
        size_t b = vstart[v], e = vstart[v + 1], k = e - b;
        if (k == 0) {
            if (!r->n_unused_nodes) r->ex_unused_node = (int32_t)v;
            r->n_unused_nodes++;
            continue;
        }
        used++;
        if (2 * k > fan_cap) {
            size_t nc = 2 * k;
            fan_entry *nf = realloc(fan, nc * sizeof *fan);
            if (!nf) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
            fan = nf;
            size_t *np = realloc(fparent, nc * sizeof *fparent);
            if (!np) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
            fparent = np;
            fan_cap = nc;
        }
        for (size_t i = 0; i < k; i++) {
            const int32_t *tv = s->tri + 3 * (size_t)vtri[b + i];
            int at = tv[0] == (int32_t)v ? 0 : tv[1] == (int32_t)v ? 1 : 2;
            fan[2 * i].other = tv[(at + 1) % 3];
            fan[2 * i].slot = (uint32_t)i;
            fan[2 * i + 1].other = tv[(at + 2) % 3];
            fan[2 * i + 1].slot = (uint32_t)i;
            fparent[i] = i;
        }
        qsort(fan, 2 * k, sizeof *fan, cmp_fan_entry);
        for (size_t i = 1; i < 2 * k; i++)
            if (fan[i].other == fan[i - 1].other) uf_union(fparent, fan[i].slot, fan[i - 1].slot);
        size_t fans = 0;
        for (size_t i = 0; i < k; i++) fans += uf_find(fparent, i) == i;
        if (fans > 1) {
            if (!r->n_nonmanifold_vertices) r->ex_nonmanifold_vertex = (int32_t)v;
            r->n_nonmanifold_vertices++;
        }
    }
    r->euler = (long)used - (long)r->n_edges + (long)n_faces;

    /* duplicates: equal sorted node triples */
    size_t nk = 0;
    for (size_t t = 0; t < nt; t++) {
        if (dg[t] == 2) continue;
        int32_t a = s->tri[3 * t], b = s->tri[3 * t + 1], c = s->tri[3 * t + 2], x;
        if (a > b) { x = a; a = b; b = x; }
        if (b > c) { x = b; b = c; c = x; }
        if (a > b) { x = a; a = b; b = x; }
        keys[nk].k[0] = a;
        keys[nk].k[1] = b;
        keys[nk].k[2] = c;
        keys[nk].t = t;
        nk++;
    }
    qsort(keys, nk, sizeof *keys, cmp_tri_key);
    for (size_t i = 1; i < nk; i++)
        if (!memcmp(keys[i].k, keys[i - 1].k, sizeof keys[i].k)) {
            if (!r->n_duplicate_tris) {
                /* the earliest triangle of the group and this one */
                size_t g = i - 1;
                while (g > 0 && !memcmp(keys[g - 1].k, keys[i].k, sizeof keys[i].k)) g--;
                r->ex_duplicate_tri[0] = keys[g].t;
                r->ex_duplicate_tri[1] = keys[i].t;
            }
            r->n_duplicate_tris++;
        }
done:
    free(start);
    free(he);
    free(parent);
    free(vstart);
    free(vtri);
    free(keys);
    free(fan);
    free(fparent);
    return st;
}

/* ------------------------------------------------------------------ */
/* Geometry and quality (serial: sums in a fixed order). */

static void geometry(const thx_surface *s, const unsigned char *dg, double min_angle_deg, thx_surface_report *r)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], s->xyz[3 * i + a]);
            hi[a] = fmax(hi[a], s->xyz[3 * i + a]);
        }
    /* volume about the box centre: smaller terms, less cancellation */
    thx_vec3 o = thx_v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    double vol6 = 0.0, area2 = 0.0, aspect_sum = 0.0;
    size_t n_good = 0;
    r->min_angle = INFINITY;
    r->max_angle = -INFINITY;
    r->min_area = INFINITY;
    r->max_area = -INFINITY;
    r->min_edge = INFINITY;
    r->max_edge = -INFINITY;
    r->max_aspect = -INFINITY;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 p[3];
        for (int k = 0; k < 3; k++) p[k] = thx_surface_node(s, (size_t)v[k]);
        thx_vec3 a = thx_v3_sub(p[0], o), b = thx_v3_sub(p[1], o), c = thx_v3_sub(p[2], o);
        vol6 += thx_v3_dot(a, thx_v3_cross(b, c));
        double cr = thx_v3_norm(thx_v3_cross(thx_v3_sub(p[1], p[0]), thx_v3_sub(p[2], p[0])));
        area2 += cr;
        double ar = 0.5 * cr;
        if (dg[t]) {
            if (!r->n_degenerate_tris) r->ex_degenerate_tri = t;
            r->n_degenerate_tris++;
            r->min_area = 0.0;
            r->max_aspect = INFINITY;
            r->max_aspect_tri = t;
            r->aspect_hist[THX_CHECK_ASPECT_BINS - 1]++;
            r->n_small_angle_tris += min_angle_deg > 0.0;
            continue;
        }
        if (ar < r->min_area) r->min_area = ar;
        if (ar > r->max_area) r->max_area = ar;
        double len[3], lmax = 0.0, per = 0.0;
        for (int k = 0; k < 3; k++) {
            len[k] = thx_v3_norm(thx_v3_sub(p[(k + 1) % 3], p[k]));
            lmax = fmax(lmax, len[k]);
            per += len[k];
            r->min_edge = fmin(r->min_edge, len[k]);
            r->max_edge = fmax(r->max_edge, len[k]);
        }
        double tmin = INFINITY;
        for (int k = 0; k < 3; k++) {
            /* angle at p[k] by atan2(|u x w|, u.w): accurate for small and large angles */
            thx_vec3 u = thx_v3_sub(p[(k + 1) % 3], p[k]), w = thx_v3_sub(p[(k + 2) % 3], p[k]);
            double ang = atan2(thx_v3_norm(thx_v3_cross(u, w)), thx_v3_dot(u, w)) * (180.0 / M_PI);
            if (ang < r->min_angle) { r->min_angle = ang; r->min_angle_tri = t; }
            if (ang > r->max_angle) { r->max_angle = ang; r->max_angle_tri = t; }
            tmin = fmin(tmin, ang);
        }
        r->n_small_angle_tris += tmin < min_angle_deg;
        /* longest edge / (2 sqrt(3) inradius), inradius = 2 area / perimeter */
        double asp = ar > 0.0 ? lmax * per / (4.0 * sqrt(3.0) * ar) : INFINITY;
        if (asp > r->max_aspect) { r->max_aspect = asp; r->max_aspect_tri = t; }
        if (isfinite(asp)) {
            aspect_sum += asp;
            n_good++;
        }
        int bin = 0;
        while (bin < THX_CHECK_ASPECT_BINS - 1 && !(asp < thx_check_aspect_edges[bin + 1])) bin++;
        r->aspect_hist[bin]++;
    }
    r->volume = vol6 / 6.0;
    r->area = 0.5 * area2;
    r->mean_aspect = n_good ? aspect_sum / (double)n_good : NAN;
    if (!isfinite(r->min_angle)) r->min_angle = r->max_angle = NAN;
    if (!isfinite(r->min_area)) r->min_area = r->max_area = NAN;
    if (!isfinite(r->min_edge)) r->min_edge = r->max_edge = NAN;
    if (r->max_aspect == -INFINITY) r->max_aspect = NAN;
}

/* ------------------------------------------------------------------ */
/* Self-intersections: every pair of triangles with overlapping boxes, in
 * parallel over the first triangle; each thread keeps its count and its
 * THX_CHECK_MAX_PAIRS smallest pairs, merged at the end, so the result does
 * not depend on the threads. */

typedef struct {
    size_t n;
    size_t pair[THX_CHECK_MAX_PAIRS][2];
} pair_list;

static void pair_list_add(pair_list *l, size_t i, size_t j)
{
    size_t k = l->n < THX_CHECK_MAX_PAIRS ? l->n++ : THX_CHECK_MAX_PAIRS;
    if (k == THX_CHECK_MAX_PAIRS) {
        const size_t *last = l->pair[THX_CHECK_MAX_PAIRS - 1];
        if (!(i < last[0] || (i == last[0] && j < last[1]))) return;
        k = THX_CHECK_MAX_PAIRS - 1;
    }
    while (k > 0 && (i < l->pair[k - 1][0] || (i == l->pair[k - 1][0] && j < l->pair[k - 1][1]))) {
        l->pair[k][0] = l->pair[k - 1][0];
        l->pair[k][1] = l->pair[k - 1][1];
        k--;
    }
    l->pair[k][0] = i;
    l->pair[k][1] = j;
}

typedef struct {
    const thx_surface *s;
    const unsigned char *dg;
    size_t i;
    size_t count;
    pair_list list;
} isect_state;

static int isect_visit(void *user, size_t j)
{
    isect_state *st = user;
    if (j <= st->i || st->dg[j]) return 0;
    if (thx_triangles_intersect(st->s->xyz, st->s->tri + 3 * st->i, st->s->tri + 3 * j)) {
        st->count++;
        pair_list_add(&st->list, st->i, j);
    }
    return 0;
}

static thx_status intersections(thx_ctx *ctx, const thx_surface *s, const thx_bvh *bvh, const unsigned char *dg,
                                thx_surface_report *r)
{
    size_t total = 0;
    pair_list all = {0};
    long long nt = (long long)s->n_tris;
THX_OMP(omp parallel)
    {
        isect_state st = {s, dg, 0, 0, {0}};
THX_OMP(omp for schedule(dynamic, 256))
        for (long long i = 0; i < nt; i++) {
            if (dg[i]) continue;
            const int32_t *v = s->tri + 3 * i;
            double lo[3], hi[3];
            for (int a = 0; a < 3; a++) {
                double x0 = s->xyz[3 * (size_t)v[0] + a], x1 = s->xyz[3 * (size_t)v[1] + a];
                double x2 = s->xyz[3 * (size_t)v[2] + a];
                lo[a] = fmin(x0, fmin(x1, x2));
                hi[a] = fmax(x0, fmax(x1, x2));
            }
            st.i = (size_t)i;
            thx_bvh_query_box(bvh, lo, hi, isect_visit, &st);
        }
THX_OMP(omp critical(thx_check_merge))
        {
            total += st.count;
            for (size_t k = 0; k < st.list.n; k++) pair_list_add(&all, st.list.pair[k][0], st.list.pair[k][1]);
        }
    }
    (void)ctx;
    r->intersections_checked = 1;
    r->n_intersecting_pairs = total;
    r->n_listed_pairs = all.n;
    memcpy(r->pairs, all.pair, sizeof all.pair);
    return THX_OK;
}

/* ------------------------------------------------------------------ */

thx_status thx_surface_check(thx_ctx *ctx, const thx_surface *s, const thx_vec3 *interior,
                             const thx_check_opts *opts_in, thx_surface_report *r)
{
    thx_check_opts opts;
    if (opts_in) opts = *opts_in;
    else thx_check_opts_default(&opts);
    memset(r, 0, sizeof *r);
    snprintf(r->name, sizeof r->name, "%s", s->name);
    r->n_nodes = s->n_nodes;
    r->n_tris = s->n_tris;
    r->solid_angle = NAN;
    r->solid_angle_rel_err = NAN;
    r->solid_angle_tol = opts.solid_angle_tol;
    r->min_angle = r->max_angle = r->min_area = r->max_area = NAN;
    r->min_edge = r->max_edge = r->max_aspect = r->mean_aspect = NAN;
    r->volume = r->area = NAN;

    thx_status st = THX_OK;
    unsigned char *dg = NULL;
    thx_bvh *bvh = NULL;

    if (s->n_tris == 0) {
        add_reason(r, THX_CHECKF_EMPTY, "empty: the surface has no triangles");
        goto verdict;
    }
    r->n_bad_index_tris = count_bad_index(s, &r->ex_bad_index_tri);
    if (r->n_bad_index_tris) {
        add_reason(r, THX_CHECKF_BAD_INDEX,
                   "bad index: %zu triangles refer to nodes outside 1..%zu (first: triangle %zu); nothing else checked",
                   r->n_bad_index_tris, s->n_nodes, r->ex_bad_index_tri + 1);
        goto verdict;
    }
    dg = degeneracy(ctx, s);
    if (!dg) {
        st = THX_ENOMEM;
        goto done;
    }
    THX_TRY(topology(ctx, s, dg, r));
    geometry(s, dg, opts.min_angle_deg, r);
    THX_TRY(thx_bvh_create_triangles(ctx, s->xyz, s->n_nodes, s->tri, s->n_tris, &bvh));

    /* 4 pi about an interior point (paper 3.2) */
    if (interior) {
        r->interior_source = THX_INTERIOR_GIVEN;
        r->interior = *interior;
    } else if (find_interior(s, bvh, dg, &r->interior)) {
        r->interior_source = THX_INTERIOR_FOUND;
    }
    if (r->interior_source != THX_INTERIOR_NONE) {
        r->solid_angle = thx_surface_solid_angle(s, r->interior);
        r->solid_angle_rel_err = fabs(r->solid_angle / (4.0 * M_PI) - 1.0);
    }
    if (opts.check_intersections) THX_TRY(intersections(ctx, s, bvh, dg, r));

    /* reasons, in a fixed order (numbers 1-based, as in .fac files) */
    if (r->n_boundary_edges)
        add_reason(r, THX_CHECKF_BOUNDARY, "not closed: %zu boundary edges (in one triangle only; first: nodes %ld-%ld)",
                   r->n_boundary_edges, (long)r->ex_boundary_edge[0] + 1, (long)r->ex_boundary_edge[1] + 1);
    if (r->n_nonmanifold_edges && r->n_nonmanifold_vertices)
        add_reason(r, THX_CHECKF_NONMANIFOLD,
                   "non-manifold: %zu edges in 3 or more triangles (first: nodes %ld-%ld), %zu vertices whose "
                   "triangles form several fans (first: node %ld)",
                   r->n_nonmanifold_edges, (long)r->ex_nonmanifold_edge[0] + 1, (long)r->ex_nonmanifold_edge[1] + 1,
                   r->n_nonmanifold_vertices, (long)r->ex_nonmanifold_vertex + 1);
    else if (r->n_nonmanifold_edges)
        add_reason(r, THX_CHECKF_NONMANIFOLD, "non-manifold: %zu edges in 3 or more triangles (first: nodes %ld-%ld)",
                   r->n_nonmanifold_edges, (long)r->ex_nonmanifold_edge[0] + 1, (long)r->ex_nonmanifold_edge[1] + 1);
    else if (r->n_nonmanifold_vertices)
        add_reason(r, THX_CHECKF_NONMANIFOLD,
                   "non-manifold: %zu vertices whose triangles form several fans (first: node %ld)",
                   r->n_nonmanifold_vertices, (long)r->ex_nonmanifold_vertex + 1);
    if (r->n_inconsistent_edges)
        add_reason(r, THX_CHECKF_ORIENTATION,
                   "orientation: %zu edges traversed in the same direction by both triangles (first: nodes %ld-%ld)",
                   r->n_inconsistent_edges, (long)r->ex_inconsistent_edge[0] + 1, (long)r->ex_inconsistent_edge[1] + 1);
    if (r->n_duplicate_tris)
        add_reason(r, THX_CHECKF_DUPLICATE, "duplicate: %zu triangles repeat the nodes of another (first: triangles %zu and %zu)",
                   r->n_duplicate_tris, r->ex_duplicate_tri[0] + 1, r->ex_duplicate_tri[1] + 1);
    if (r->n_degenerate_tris)
        add_reason(r, THX_CHECKF_DEGENERATE, "degenerate: %zu zero-area triangles (first: triangle %zu)",
                   r->n_degenerate_tris, r->ex_degenerate_tri + 1);
    if (r->n_unused_nodes)
        add_reason(r, THX_CHECKF_UNUSED, "unused nodes: %zu nodes in no triangle (first: node %ld)", r->n_unused_nodes,
                   (long)r->ex_unused_node + 1);
    if (!(r->volume > 0.0))
        add_reason(r, THX_CHECKF_VOLUME, "inward: signed volume %.6g mm^3 is not positive (normals point inward)",
                   r->volume);
    if (r->interior_source == THX_INTERIOR_NONE)
        add_reason(r, THX_CHECKF_SOLID_ANGLE, "solid angle: no interior point found (is the surface closed?)");
    else if (!(r->solid_angle_rel_err <= opts.solid_angle_tol))
        add_reason(r, THX_CHECKF_SOLID_ANGLE,
                   "solid angle: Omega/4pi = %.9g at (%.6g, %.6g, %.6g) (%s interior point): |Omega/4pi - 1| = %.3g > %.3g",
                   r->solid_angle / (4.0 * M_PI), r->interior.x, r->interior.y, r->interior.z,
                   r->interior_source == THX_INTERIOR_GIVEN ? "given" : "found", r->solid_angle_rel_err,
                   opts.solid_angle_tol);
    if (r->n_intersecting_pairs)
        add_reason(r, THX_CHECKF_INTERSECTION, "self-intersection: %zu triangle pairs intersect (first: triangles %zu and %zu)",
                   r->n_intersecting_pairs, r->pairs[0][0] + 1, r->pairs[0][1] + 1);
    if (opts.min_angle_deg > 0.0 && (r->n_degenerate_tris || r->min_angle < opts.min_angle_deg))
        add_reason(r, THX_CHECKF_QUALITY,
                   "quality: triangle %zu has a %.3g deg angle (< %.3g deg; %zu triangles below it): thorax mesh "
                   "cannot take it (the tetrahedra on it would be as flat)",
                   (r->n_degenerate_tris ? r->ex_degenerate_tri : r->min_angle_tri) + 1,
                   r->n_degenerate_tris ? 0.0 : r->min_angle, opts.min_angle_deg, r->n_small_angle_tris);
    if (opts.max_aspect > 0.0 && !(r->max_aspect <= opts.max_aspect))
        add_reason(r, THX_CHECKF_QUALITY, "quality: aspect ratio %.4g > %.4g (triangle %zu)", r->max_aspect,
                   opts.max_aspect, r->max_aspect_tri + 1);

verdict:
    r->ok = r->failures == 0;
    if (!r->ok) st = thx_error(ctx, THX_ECHECK, "surface \"%s\": %s", s->name, r->reasons[0]);
done:
    thx_bvh_destroy(&bvh);
    free(dg);
    return st;
}

/* Surfaces that meet: for every pair whose boxes overlap, each triangle of the first against the second's
 * triangles in its box (a BVH), by the exact test with the second's nodes numbered after the first's, so
 * that no node is shared by index and a common node, edge or face counts. Degenerate triangles (their own
 * surface's check names them) and surfaces with bad indices are left out. */
typedef struct {
    const double *xyz;
    const int32_t *tb;      /* the second surface's triangles, offset */
    const unsigned char *dgb;
    int32_t ta[3];
    size_t i, count, first_i, first_j;
} meet_state;

static int meet_visit(void *user, size_t j)
{
    meet_state *st = user;
    if (st->dgb[j]) return 0;
    if (thx_triangles_intersect(st->xyz, st->ta, st->tb + 3 * j)) {
        if (st->count == 0 || st->i < st->first_i || (st->i == st->first_i && j < st->first_j)) {
            st->first_i = st->i;
            st->first_j = j;
        }
        st->count++;
    }
    return 0;
}

static void surface_box(const thx_surface *s, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) lo[a] = INFINITY, hi[a] = -INFINITY;
    for (size_t k = 0; k < s->n_nodes; k++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], s->xyz[3 * k + a]);
            hi[a] = fmax(hi[a], s->xyz[3 * k + a]);
        }
}

static thx_status meetings(thx_ctx *ctx, const thx_model *m, thx_model_report *r)
{
    size_t ns = m->n_surfaces;
    thx_status st = THX_OK;
    r->meetings_checked = 1;
    for (size_t a = 0; a < ns; a++) {
        const thx_surface *A = m->surf[a];
        if (!A->n_tris || r->surf[a].n_bad_index_tris) continue;
        double alo[3], ahi[3];
        surface_box(A, alo, ahi);
        for (size_t b = a + 1; b < ns; b++) {
            const thx_surface *B = m->surf[b];
            if (!B->n_tris || r->surf[b].n_bad_index_tris) continue;
            double blo[3], bhi[3];
            surface_box(B, blo, bhi);
            int apart = 0;
            for (int k = 0; k < 3; k++) apart |= ahi[k] < blo[k] || bhi[k] < alo[k];
            if (apart) continue;
            double *xyz = malloc((A->n_nodes + B->n_nodes) * 3 * sizeof *xyz);
            int32_t *tb = malloc(B->n_tris * 3 * sizeof *tb);
            unsigned char *dga = degeneracy(ctx, A), *dgb = degeneracy(ctx, B);
            thx_bvh *bvh = NULL;
            if (!xyz || !tb || !dga || !dgb) {
                free(xyz), free(tb), free(dga), free(dgb);
                return thx_error(ctx, THX_ENOMEM, "check: out of memory");
            }
            memcpy(xyz, A->xyz, A->n_nodes * 3 * sizeof *xyz);
            memcpy(xyz + 3 * A->n_nodes, B->xyz, B->n_nodes * 3 * sizeof *xyz);
            for (size_t k = 0; k < 3 * B->n_tris; k++) tb[k] = B->tri[k] + (int32_t)A->n_nodes;
            st = thx_bvh_create_triangles(ctx, B->xyz, B->n_nodes, B->tri, B->n_tris, &bvh);
            size_t count = 0, fi = 0, fj = 0;
            if (st == THX_OK) {
                long long nt = (long long)A->n_tris;
THX_OMP(omp parallel)
                {
                    meet_state ms = {xyz, tb, dgb, {0, 0, 0}, 0, 0, 0, 0};
THX_OMP(omp for schedule(dynamic, 256))
                    for (long long i = 0; i < nt; i++) {
                        if (dga[i]) continue;
                        const int32_t *v = A->tri + 3 * i;
                        double lo[3], hi[3];
                        for (int k = 0; k < 3; k++) {
                            double x0 = A->xyz[3 * (size_t)v[0] + k], x1 = A->xyz[3 * (size_t)v[1] + k];
                            double x2 = A->xyz[3 * (size_t)v[2] + k];
                            lo[k] = fmin(x0, fmin(x1, x2));
                            hi[k] = fmax(x0, fmax(x1, x2));
                        }
                        memcpy(ms.ta, v, sizeof ms.ta);
                        ms.i = (size_t)i;
                        thx_bvh_query_box(bvh, lo, hi, meet_visit, &ms);
                    }
THX_OMP(omp critical(thx_check_meet))
                    {
                        if (ms.count && (count == 0 || ms.first_i < fi || (ms.first_i == fi && ms.first_j < fj))) {
                            fi = ms.first_i;
                            fj = ms.first_j;
                        }
                        count += ms.count;
                    }
                }
            }
            thx_bvh_destroy(&bvh);
            free(xyz), free(tb), free(dga), free(dgb);
            if (st != THX_OK) return st;
            if (!count) continue;
            if (r->n_meeting_pairs++ == 0) {
                r->meet_a = a;
                r->meet_b = b;
                r->meet_tris = count;
                r->meet_tri_a = fi;
                r->meet_tri_b = fj;
                snprintf(r->meet_reason, sizeof r->meet_reason,
                         "surfaces \"%s\" and \"%s\" meet: %zu triangle pairs touch or cross (first: triangle %zu of "
                         "\"%s\" and triangle %zu of \"%s\"); a volume mesh needs every surface apart from the others",
                         A->name, B->name, count, fi + 1, A->name, fj + 1, B->name);
            }
        }
    }
    return THX_OK;
}

thx_status thx_model_check(thx_ctx *ctx, const thx_model *m, const thx_check_opts *opts, thx_model_report **out)
{
    *out = NULL;
    thx_check_opts o;
    if (opts) o = *opts;
    else thx_check_opts_default(&o);
    thx_model_report *r = thx_calloc(ctx, 1, sizeof *r);
    if (!r) return THX_ENOMEM;
    r->surf = thx_calloc(ctx, m->n_surfaces ? m->n_surfaces : 1, sizeof *r->surf);
    if (!r->surf) {
        free(r);
        return THX_ENOMEM;
    }
    r->n_surfaces = m->n_surfaces;
    r->solid_angle_tol = o.solid_angle_tol;
    r->ok = 1;
    char first[2048] = "";
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const thx_vec3 *in = (m->has_interior && m->interior && m->has_interior[i]) ? &m->interior[i] : NULL;
        thx_status st = thx_surface_check(ctx, m->surf[i], in, &o, &r->surf[i]);
        if (st == THX_ECHECK) {
            if (r->ok) snprintf(first, sizeof first, "%s", thx_ctx_message(ctx));
            r->ok = 0;
        } else if (st != THX_OK) {
            thx_model_report_destroy(&r);
            return st;
        }
    }
    if (o.check_intersections) {
        thx_status st = meetings(ctx, m, r);
        if (st != THX_OK) {
            thx_model_report_destroy(&r);
            return st;
        }
        if (r->n_meeting_pairs) {
            if (r->ok) snprintf(first, sizeof first, "%s", r->meet_reason);
            r->ok = 0;
        }
    }
    *out = r;
    if (!r->ok) return thx_error(ctx, THX_ECHECK, "%s", first);
    return THX_OK;
}

void thx_surface_report_free(thx_surface_report *r)
{
    if (r) memset(r, 0, sizeof *r);
}

void thx_model_report_destroy(thx_model_report **r)
{
    if (!r || !*r) return;
    free((*r)->surf);
    free(*r);
    *r = NULL;
}

/* ------------------------------------------------------------------ */
/* JSON. Non-finite numbers become null (JSON has no inf/NaN). */

static cJSON *num(double x) { return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull(); }

static void add_num(cJSON *o, const char *k, double x) { cJSON_AddItemToObject(o, k, num(x)); }

static void add_pair1(cJSON *o, const char *k, long a, long b)
{
    cJSON *arr = cJSON_CreateArray();
    cJSON_AddItemToArray(arr, cJSON_CreateNumber((double)a + 1));
    cJSON_AddItemToArray(arr, cJSON_CreateNumber((double)b + 1));
    cJSON_AddItemToObject(o, k, arr);
}

cJSON *thx_surface_report_json(thx_ctx *ctx, const thx_surface_report *r, const char *role)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) goto nomem;
    cJSON_AddStringToObject(o, "name", r->name);
    if (role) cJSON_AddStringToObject(o, "role", role);
    cJSON_AddBoolToObject(o, "ok", r->ok);
    cJSON *fl = cJSON_AddArrayToObject(o, "failures");
    for (unsigned b = 0; b < 12; b++)
        if (r->failures & (1u << b)) cJSON_AddItemToArray(fl, cJSON_CreateString(thx_check_failure_name((thx_check_failure)(1u << b))));
    cJSON *rs = cJSON_AddArrayToObject(o, "reasons");
    for (size_t i = 0; i < r->n_reasons; i++) cJSON_AddItemToArray(rs, cJSON_CreateString(r->reasons[i]));
    cJSON_AddNumberToObject(o, "nodes", (double)r->n_nodes);
    cJSON_AddNumberToObject(o, "triangles", (double)r->n_tris);
    cJSON_AddNumberToObject(o, "edges", (double)r->n_edges);
    int indexed = !(r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX));
    cJSON_AddBoolToObject(o, "closed", indexed && !r->n_boundary_edges && !r->n_nonmanifold_edges);
    cJSON_AddBoolToObject(o, "manifold", indexed && !r->n_nonmanifold_edges && !r->n_nonmanifold_vertices);
    cJSON_AddBoolToObject(o, "consistently_oriented", indexed && !r->n_inconsistent_edges);

    cJSON *tp = cJSON_AddObjectToObject(o, "topology");
    cJSON_AddNumberToObject(tp, "bad_index_triangles", (double)r->n_bad_index_tris);
    cJSON_AddNumberToObject(tp, "boundary_edges", (double)r->n_boundary_edges);
    cJSON_AddNumberToObject(tp, "nonmanifold_edges", (double)r->n_nonmanifold_edges);
    cJSON_AddNumberToObject(tp, "nonmanifold_vertices", (double)r->n_nonmanifold_vertices);
    cJSON_AddNumberToObject(tp, "inconsistent_edges", (double)r->n_inconsistent_edges);
    cJSON_AddNumberToObject(tp, "duplicate_triangles", (double)r->n_duplicate_tris);
    cJSON_AddNumberToObject(tp, "degenerate_triangles", (double)r->n_degenerate_tris);
    cJSON_AddNumberToObject(tp, "unused_nodes", (double)r->n_unused_nodes);
    cJSON_AddNumberToObject(tp, "euler_characteristic", (double)r->euler);
    cJSON_AddNumberToObject(tp, "components", (double)r->n_components);
    cJSON *ex = cJSON_AddObjectToObject(tp, "first");
    if (r->n_bad_index_tris) cJSON_AddNumberToObject(ex, "bad_index_triangle", (double)r->ex_bad_index_tri + 1);
    if (r->n_boundary_edges) add_pair1(ex, "boundary_edge", r->ex_boundary_edge[0], r->ex_boundary_edge[1]);
    if (r->n_nonmanifold_edges) add_pair1(ex, "nonmanifold_edge", r->ex_nonmanifold_edge[0], r->ex_nonmanifold_edge[1]);
    if (r->n_nonmanifold_vertices) cJSON_AddNumberToObject(ex, "nonmanifold_vertex", (double)r->ex_nonmanifold_vertex + 1);
    if (r->n_inconsistent_edges)
        add_pair1(ex, "inconsistent_edge", r->ex_inconsistent_edge[0], r->ex_inconsistent_edge[1]);
    if (r->n_duplicate_tris)
        add_pair1(ex, "duplicate_triangles", (long)r->ex_duplicate_tri[0], (long)r->ex_duplicate_tri[1]);
    if (r->n_degenerate_tris) cJSON_AddNumberToObject(ex, "degenerate_triangle", (double)r->ex_degenerate_tri + 1);
    if (r->n_unused_nodes) cJSON_AddNumberToObject(ex, "unused_node", (double)r->ex_unused_node + 1);

    add_num(o, "area", r->area);
    add_num(o, "volume", r->volume);

    cJSON *sa = cJSON_AddObjectToObject(o, "solid_angle");
    static const char *const src[] = {"none", "given", "found"};
    cJSON_AddStringToObject(sa, "interior_source", src[r->interior_source]);
    if (r->interior_source != THX_INTERIOR_NONE) {
        cJSON *ip = cJSON_AddArrayToObject(sa, "interior");
        cJSON_AddItemToArray(ip, num(r->interior.x));
        cJSON_AddItemToArray(ip, num(r->interior.y));
        cJSON_AddItemToArray(ip, num(r->interior.z));
    } else {
        cJSON_AddNullToObject(sa, "interior");
    }
    add_num(sa, "omega", r->solid_angle);
    add_num(sa, "omega_over_4pi", r->solid_angle / (4.0 * M_PI));
    add_num(sa, "rel_error", r->solid_angle_rel_err);
    add_num(sa, "tolerance", r->solid_angle_tol);
    cJSON_AddBoolToObject(sa, "ok", !(r->failures & THX_CHECKF_SOLID_ANGLE) && r->interior_source != THX_INTERIOR_NONE);

    cJSON *is = cJSON_AddObjectToObject(o, "intersections");
    cJSON_AddBoolToObject(is, "checked", r->intersections_checked);
    cJSON_AddNumberToObject(is, "pairs", (double)r->n_intersecting_pairs);
    cJSON *fp = cJSON_AddArrayToObject(is, "first_pairs");
    for (size_t k = 0; k < r->n_listed_pairs; k++) {
        cJSON *pr = cJSON_CreateArray();
        cJSON_AddItemToArray(pr, cJSON_CreateNumber((double)r->pairs[k][0] + 1));
        cJSON_AddItemToArray(pr, cJSON_CreateNumber((double)r->pairs[k][1] + 1));
        cJSON_AddItemToArray(fp, pr);
    }

    cJSON *q = cJSON_AddObjectToObject(o, "quality");
    add_num(q, "min_angle_deg", r->min_angle);
    if (isfinite(r->min_angle)) cJSON_AddNumberToObject(q, "min_angle_triangle", (double)r->min_angle_tri + 1);
    cJSON_AddNumberToObject(q, "triangles_below_min_angle", (double)r->n_small_angle_tris);
    add_num(q, "max_angle_deg", r->max_angle);
    if (isfinite(r->max_angle)) cJSON_AddNumberToObject(q, "max_angle_triangle", (double)r->max_angle_tri + 1);
    add_num(q, "min_area", r->min_area);
    add_num(q, "max_area", r->max_area);
    add_num(q, "min_edge", r->min_edge);
    add_num(q, "max_edge", r->max_edge);
    cJSON *as = cJSON_AddObjectToObject(q, "aspect_ratio");
    cJSON_AddStringToObject(as, "definition",
                            "longest edge / (2 sqrt(3) inradius); 1 = equilateral; null = infinite (zero area)");
    add_num(as, "max", r->max_aspect);
    if (r->max_aspect == r->max_aspect) cJSON_AddNumberToObject(as, "max_triangle", (double)r->max_aspect_tri + 1);
    add_num(as, "mean", r->mean_aspect);
    cJSON *hist = cJSON_AddObjectToObject(as, "histogram");
    cJSON *he = cJSON_AddArrayToObject(hist, "edges");
    for (int b = 0; b <= THX_CHECK_ASPECT_BINS; b++) cJSON_AddItemToArray(he, num(thx_check_aspect_edges[b]));
    cJSON *hc = cJSON_AddArrayToObject(hist, "counts");
    for (int b = 0; b < THX_CHECK_ASPECT_BINS; b++) cJSON_AddItemToArray(hc, cJSON_CreateNumber((double)r->aspect_hist[b]));
    /* cJSON's Add* return NULL on allocation failure; a final walk catches it */
    if (!hc || !q || !is || !sa || !tp || !fl || !rs || !ex || !as || !he || !fp) {
        cJSON_Delete(o);
        goto nomem;
    }
    return o;
nomem:
    thx_error(ctx, THX_ENOMEM, "out of memory building the check report");
    return NULL;
}

cJSON *thx_model_report_json(thx_ctx *ctx, const thx_model_report *r, const thx_model *m)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) goto nomem;
    cJSON_AddBoolToObject(o, "ok", r->ok);
    cJSON_AddNumberToObject(o, "index_base", 1);
    add_num(o, "solid_angle_tol", r->solid_angle_tol);
    cJSON *arr = cJSON_AddArrayToObject(o, "surfaces");
    if (!arr) {
        cJSON_Delete(o);
        goto nomem;
    }
    for (size_t i = 0; i < r->n_surfaces; i++) {
        const char *role = (m && i < m->n_surfaces) ? thx_role_name(m->surf[i]->role) : NULL;
        cJSON *so = thx_surface_report_json(ctx, &r->surf[i], role);
        if (!so) {
            cJSON_Delete(o);
            return NULL;
        }
        cJSON_AddItemToArray(arr, so);
    }
    cJSON *mt = cJSON_AddObjectToObject(o, "meetings");
    if (!mt) {
        cJSON_Delete(o);
        goto nomem;
    }
    cJSON_AddBoolToObject(mt, "checked", r->meetings_checked);
    cJSON_AddNumberToObject(mt, "pairs", (double)r->n_meeting_pairs);
    if (r->n_meeting_pairs && r->meet_a < r->n_surfaces && r->meet_b < r->n_surfaces) {
        cJSON *f = cJSON_AddObjectToObject(mt, "first");
        if (f) {
            cJSON_AddStringToObject(f, "a", r->surf[r->meet_a].name);
            cJSON_AddStringToObject(f, "b", r->surf[r->meet_b].name);
            cJSON_AddNumberToObject(f, "triangle_pairs", (double)r->meet_tris);
            cJSON_AddNumberToObject(f, "triangle_a", (double)r->meet_tri_a + 1);
            cJSON_AddNumberToObject(f, "triangle_b", (double)r->meet_tri_b + 1);
        }
        cJSON_AddStringToObject(mt, "reason", r->meet_reason);
    }
    return o;
nomem:
    thx_error(ctx, THX_ENOMEM, "out of memory building the check report");
    return NULL;
}
