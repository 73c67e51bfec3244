/*
 * Volume meshing (paper 3.3, "Volume Segmentation"): the hybrid method.
 *
 *  1. Nodes: every surface node (volume node numbers follow the model's
 *     surface order), then a square grid ((i + 1/2) g, (j + 1/2) g) on each
 *     layer plane, kept where it lies inside the outer surface and no surface
 *     comes closer than the tolerance ("removed all points that were within
 *     some tolerance of an existing surface").
 *  2. Delaunay tetrahedralization of all nodes (thorax/delaunay.h); the
 *     surfaces' triangles it lacks are flipped in where one operation per
 *     edge does it (mesh_recover, src/mesh/improve.h).
 *  3. Tetrahedra any part of which lies outside the domain are removed: the
 *     paper tests "the midpoint of each side of the tetrahedron" against the
 *     enclosing surface; we test the midpoints of the edges whose two ends are
 *     surface nodes and, when at least two corners are, the centroid (an edge
 *     with an interior grid node has at least that end strictly inside, and
 *     the grid keeps a tolerance from every surface). With no_heart, tetrahedra
 *     whose centroid is inside the heart are removed too.
 *     Flat tetrahedra are then peeled off the boundary; inside, they are
 *     repaired by flips and grid-node moves (mesh_improve).
 *  4. Regions by a chain of inside/outside tests on the centroid (paper 3.3):
 *     outside the fat/muscle interface -> fat; outside the inner muscle border
 *     -> muscle; inside a lung -> that lung; inside the heart -> heart;
 *     inside an "other" surface -> that surface's region; else mean thorax.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/improve.h"
#include "mesh/locate.h"
#include "thorax/delaunay.h"
#include "thorax/mesh.h"

void thx_mesh_opts_default(thx_mesh_opts *o)
{
    memset(o, 0, sizeof *o);
    o->grid = 0; /* automatic: from the layer spacing */
    o->tol = 0;
    o->layer_spacing = 0;
    o->no_heart = 0;
    o->sliver_deg = 5.0;
    o->repair_deg = 15.0;
    o->recover = 1;
}

/* x as it reads back from the model files ("%.6f"). */
static double stored(double x)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.6f", x);
    return strtod(buf, NULL);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Planes of the grid: the distinct z of the outer surface's nodes when they lie on few planes. */
static thx_status find_planes(thx_ctx *ctx, const thx_surface *outer, const thx_mesh_opts *o, double fallback,
                              double **planes, size_t *n)
{
    double zlo = INFINITY, zhi = -INFINITY;
    for (size_t i = 0; i < outer->n_nodes; i++) {
        zlo = fmin(zlo, outer->xyz[3 * i + 2]);
        zhi = fmax(zhi, outer->xyz[3 * i + 2]);
    }
    double *z = thx_malloc(ctx, (outer->n_nodes + 1) * sizeof *z);
    if (!z) return THX_ENOMEM;
    size_t m = 0;
    if (o->layer_spacing <= 0) {
        for (size_t i = 0; i < outer->n_nodes; i++) z[i] = outer->xyz[3 * i + 2];
        qsort(z, outer->n_nodes, sizeof *z, cmp_double);
        for (size_t i = 0; i < outer->n_nodes; i++)
            if (m == 0 || z[i] != z[m - 1]) z[m++] = z[i];
        if (m * 4 > outer->n_nodes) m = 0; /* not a layered model */
    }
    if (m == 0) {
        double step = o->layer_spacing > 0 ? o->layer_spacing : fallback;
        size_t k = (size_t)floor((zhi - zlo) / step);
        free(z);
        z = thx_malloc(ctx, (k + 2) * sizeof *z);
        if (!z) return THX_ENOMEM;
        double z0 = zlo + 0.5 * ((zhi - zlo) - (double)k * step);
        for (size_t i = 0; i <= k; i++) z[m++] = z0 + (double)i * step;
    }
    *planes = z;
    *n = m;
    return THX_OK;
}

/* The domain is closed: a point on the outer surface (the midpoint of one of its
 * edges, say) is inside, whatever a ray from it would say. */
static int outside_domain(const locator *outer, thx_vec3 p, double on_eps)
{
    return !locator_inside(outer, p) && !locator_near(outer, p, on_eps);
}

/* The region of a point (paper 3.3): a chain of inside/outside tests, the innermost surface
 * containing it deciding: outside the fat/muscle interface -> fat; outside the inner muscle
 * border -> muscle; inside a lung, the heart or an "other" surface -> its region; else the
 * mean thorax (region 0). */
static int classify_region(const thx_model *m, const locator *loc, const int *surf_region, thx_vec3 c)
{
    size_t ns = m->n_surfaces;
    for (size_t s = 0; s < ns; s++) {
        thx_role role = m->surf[s]->role;
        if ((role == THX_ROLE_FAT || role == THX_ROLE_MUSCLE) && !locator_inside(&loc[s], c)) return surf_region[s];
    }
    for (size_t s = 0; s < ns; s++) {
        thx_role role = m->surf[s]->role;
        if ((role == THX_ROLE_LUNG || role == THX_ROLE_HEART || role == THX_ROLE_OTHER) && surf_region[s] >= 0 &&
            locator_inside(&loc[s], c))
            return surf_region[s];
    }
    return 0;
}

typedef struct {
    const thx_model *m;
    const locator *loc;
    const int *surf_region;
} region_ctx;

static int classify_cb(void *user, thx_vec3 c)
{
    const region_ctx *r = user;
    return classify_region(r->m, r->loc, r->surf_region, c);
}

typedef struct { int32_t a, b; } medge;
static int cmp_medge(const void *x, const void *y)
{
    const medge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

typedef struct { int32_t v, w1, w2; } link_rec;
static int cmp_link_rec(const void *x, const void *y)
{
    int32_t a = ((const link_rec *)x)->v, b = ((const link_rec *)y)->v;
    return (a > b) - (a < b);
}

static int uf_find(int *parent, int i)
{
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

/* Connected components of a vertex's link: the graph of the edges (w1, w2) of n records. */
static int link_components(const link_rec *r, size_t n)
{
    int32_t w[128];
    int parent[128], nw = 0, comps = 0;
    if (2 * n > 128) return 1; /* an unusually crowded vertex: not judged */
    for (size_t k = 0; k < n; k++)
        for (int e = 0; e < 2; e++) {
            int32_t x = e ? r[k].w2 : r[k].w1;
            int found = 0;
            for (int i = 0; i < nw && !found; i++) found = w[i] == x;
            if (!found) { w[nw] = x; parent[nw] = nw; nw++; }
        }
    comps = nw;
    for (size_t k = 0; k < n; k++) {
        int i1 = 0, i2 = 0;
        while (w[i1] != r[k].w1) i1++;
        while (w[i2] != r[k].w2) i2++;
        int a = uf_find(parent, i1), b = uf_find(parent, i2);
        if (a != b) { parent[a] = b; comps--; }
    }
    return comps;
}

static thx_vec3 tet_centroid(const double *xyz, const int32_t *q)
{
    thx_vec3 c = {0, 0, 0};
    for (int k = 0; k < 4; k++) c = thx_v3_add(c, thx_v3(xyz[3 * q[k]], xyz[3 * q[k] + 1], xyz[3 * q[k] + 2]));
    return thx_v3_scale(c, 0.25);
}

/*
 * Boundary repair. Removing the tetrahedra that reach outside leaves a boundary
 * that can pinch: an edge in four boundary faces (two wedges of tetrahedra
 * touching along it), a vertex where two cones of tetrahedra touch, or a
 * surface node left in no tetrahedron. For each such
 * edge or node, the removed tetrahedra around it whose centroid lies inside the
 * domain are put back (the paper's centroid test instead of the stricter
 * edge-midpoint test); where none is, the tetrahedra at the pinch that touch
 * the boundary are taken away instead; until nothing changes. Returns the number put back and,
 * in *bad, the pinched edges and unused surface nodes that remain.
 */
static thx_status repair_boundary(thx_ctx *ctx, size_t nt, const int32_t *tets, const int32_t *nbrs, unsigned char *keep,
                                  const double *xyz, size_t nn, size_t n_surf_nodes, const locator *outer, double on_eps,
                                  size_t *readded, size_t *removed, size_t *bad)
{
    thx_status st = THX_OK;
    *readded = 0;
    *removed = 0;
    *bad = 0;
    /* vertex -> tetrahedra (CSR) */
    size_t *start = thx_calloc(ctx, nn + 1, sizeof *start);
    int32_t *inc = thx_malloc(ctx, 4 * (nt ? nt : 1) * sizeof *inc);
    medge *e = NULL;
    unsigned char *used = thx_malloc(ctx, nn ? nn : 1), *want = thx_malloc(ctx, nn ? nn : 1);
    size_t cap = 0;
    if (!start || !inc || !used || !want) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < 4 * nt; t++) start[tets[t] + 1]++;
    for (size_t v = 0; v < nn; v++) start[v + 1] += start[v];
    {
        size_t *fill = thx_malloc(ctx, (nn ? nn : 1) * sizeof *fill);
        if (!fill) { st = THX_ENOMEM; goto done; }
        memcpy(fill, start, nn * sizeof *fill);
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 4; k++) inc[fill[tets[4 * t + k]]++] = (int32_t)t;
        free(fill);
    }
    for (int iter = 0; iter < 20; iter++) {
        /* boundary edges of the kept set, and nodes in use */
        size_t ne = 0;
        memset(used, 0, nn);
        memset(want, 0, nn);
        for (size_t t = 0; t < nt; t++) {
            if (keep[t] != 1) continue;
            for (int k = 0; k < 4; k++) used[tets[4 * t + k]] = 1;
            for (int f = 0; f < 4; f++) {
                int32_t u = nbrs[4 * t + f];
                if (u >= 0 && keep[u] == 1) continue;
                st = thx_grow(ctx, (void **)&e, &cap, ne + 3, sizeof *e);
                if (st != THX_OK) goto done;
                int32_t v[3];
                for (int q = 0, k = 0; q < 4; q++) if (q != f) v[k++] = tets[4 * t + q];
                for (int q = 0; q < 3; q++) {
                    int32_t a = v[q], b = v[(q + 1) % 3];
                    e[ne].a = a < b ? a : b;
                    e[ne].b = a < b ? b : a;
                    ne++;
                }
            }
        }
        qsort(e, ne, sizeof *e, cmp_medge);
        size_t n_bad = 0;
        for (size_t k = 0; k < ne;) {
            size_t j = k + 1;
            while (j < ne && e[j].a == e[k].a && e[j].b == e[k].b) j++;
            if (j - k > 2) { want[e[k].a] = want[e[k].b] = 1; n_bad++; }
            k = j;
        }
        for (size_t v = 0; v < n_surf_nodes; v++)
            if (!used[v]) { want[v] = 1; n_bad++; }
        /* Pinched vertices: at a vertex of a closed 2-manifold the opposite edges of its boundary
           faces (its link) form one cycle; two cones touching at the vertex give two. */
        {
            size_t nr = 0;
            link_rec *rec = thx_malloc(ctx, (ne ? ne : 1) * sizeof *rec); /* ne = 3 x faces: one per corner */
            if (!rec) { st = THX_ENOMEM; goto done; }
            for (size_t t = 0; t < nt; t++) {
                if (keep[t] != 1) continue;
                for (int f = 0; f < 4; f++) {
                    int32_t u = nbrs[4 * t + f];
                    if (u >= 0 && keep[u] == 1) continue;
                    int32_t c3[3];
                    for (int q = 0, k = 0; q < 4; q++) if (q != f) c3[k++] = tets[4 * t + q];
                    for (int q = 0; q < 3; q++) {
                        rec[nr].v = c3[q];
                        rec[nr].w1 = c3[(q + 1) % 3];
                        rec[nr].w2 = c3[(q + 2) % 3];
                        nr++;
                    }
                }
            }
            qsort(rec, nr, sizeof *rec, cmp_link_rec);
            for (size_t k = 0; k < nr;) {
                size_t j = k + 1;
                while (j < nr && rec[j].v == rec[k].v) j++;
                if (link_components(rec + k, j - k) > 1 && !want[rec[k].v]) { want[rec[k].v] = 1; n_bad++; }
                k = j;
            }
            free(rec);
        }
        *bad = n_bad;
        if (n_bad == 0) break;
        size_t added = 0;
        for (size_t v = 0; v < nn; v++) {
            if (!want[v]) continue;
            for (size_t k = start[v]; k < start[v + 1]; k++) {
                int32_t t = inc[k];
                if (keep[t] == 3) { keep[t] = 1; added++; continue; } /* a peeled sliver: it was inside */
                if (keep[t] != 0) continue;
                thx_vec3 c = tet_centroid(xyz, tets + 4 * t);
                if (locator_inside(outer, c) || locator_near(outer, c, on_eps)) { keep[t] = 1; added++; }
            }
        }
        *readded += added;
        if (added == 0) {
            /* Nothing inside to put back: open the pinch instead, taking away the tetrahedra at the
               pinched edges and vertices that touch the boundary (never to be put back). */
            size_t taken = 0;
            for (size_t t = 0; t < nt; t++) {
                if (keep[t] != 1) continue;
                int pinched = 0;
                for (int k = 0; k < 4 && !pinched; k++) pinched = want[tets[4 * t + k]];
                if (!pinched) continue;
                int touches = 0;
                for (int f = 0; f < 4 && !touches; f++) {
                    int32_t u = nbrs[4 * t + f];
                    touches = u < 0 || keep[u] != 1;
                }
                /* only tetrahedra with at least two corners at pinches: the wedge or cone itself */
                int corners = 0;
                for (int k = 0; k < 4; k++) corners += want[tets[4 * t + k]];
                if (touches && corners >= 2) { keep[t] = 4; taken++; }
            }
            *removed += taken;
            if (taken == 0) break;
        }
    }
done:
    free(start);
    free(inc);
    free(e);
    free(used);
    free(want);
    return st;
}

thx_status thx_mesh_build(thx_ctx *ctx, thx_model *m, const thx_mesh_opts *o, thx_mesh_stats *stats)
{
    thx_status st = THX_OK;
    thx_mesh_stats S;
    memset(&S, 0, sizeof S);
    double t0 = thx_wtime();
    int outer = -1, heart = -1;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        if (m->surf[s]->role == THX_ROLE_OUTER) {
            if (outer >= 0) return thx_error(ctx, THX_EINPUT, "mesh: more than one surface has the role \"outer\" (%s, %s)", m->surf[outer]->name, m->surf[s]->name);
            outer = (int)s;
        }
        if (m->surf[s]->role == THX_ROLE_HEART) {
            if (heart >= 0) return thx_error(ctx, THX_EINPUT, "mesh: more than one surface has the role \"heart\"");
            heart = (int)s;
        }
    }
    if (outer < 0) return thx_error(ctx, THX_EINPUT, "mesh: the model has no surface of role \"outer\" (the domain's boundary)");
    if (o->grid < 0) return thx_error(ctx, THX_EINPUT, "mesh: grid spacing must be positive (got %g)", o->grid);
    size_t ns = m->n_surfaces;
    locator *loc = thx_calloc(ctx, ns, sizeof *loc);
    double *planes = NULL, *xyz = NULL;
    int32_t *tets = NULL, *nbrs = NULL, *region = NULL, *vnbr = NULL;
    unsigned char *keep = NULL;
    thx_volume *v = NULL;
    size_t *offset = thx_calloc(ctx, ns + 1, sizeof *offset);
    double **gp = NULL;
    size_t *gn = NULL, np = 0;
    if (!loc || !offset) { st = THX_ENOMEM; goto done; }
    for (size_t s = 0; s < ns; s++) THX_TRY(locator_init(ctx, &loc[s], m->surf[s]));
    for (size_t s = 0; s < ns; s++) offset[s + 1] = offset[s] + m->surf[s]->n_nodes;
    S.n_surface_nodes = offset[ns];

    /* 1. grid points, plane by plane (in parallel, gathered in plane order: deterministic) */
    THX_TRY(find_planes(ctx, m->surf[outer], o, o->grid > 0 ? o->grid : 6.5, &planes, &np));
    S.n_planes = np;
    /* Automatic grid spacing from the median gap between the planes, chosen so that the
       phantom's two models get the paper's sizes (5 mm layers: 6.5 mm grid, about 82,000
       nodes; 10 mm layers: 8 mm grid, about 22,000 nodes). */
    double grid = o->grid;
    if (!(grid > 0)) {
        double *gaps = thx_malloc(ctx, (np > 1 ? np - 1 : 1) * sizeof *gaps);
        if (!gaps) { st = THX_ENOMEM; goto done; }
        for (size_t k = 0; k + 1 < np; k++) gaps[k] = planes[k + 1] - planes[k];
        double gap = 5.0;
        if (np > 1) { qsort(gaps, np - 1, sizeof *gaps, cmp_double); gap = gaps[(np - 1) / 2]; }
        free(gaps);
        grid = fmax(1.0, 6.5 + 0.3 * (gap - 5.0));
    }
    S.grid = grid;
    double tol = o->tol > 0 ? o->tol : 0.5 * grid;
    const double on_eps = 1e-6 * grid; /* "on the surface" for midpoints of surface edges */
    {
        const thx_surface *os = m->surf[outer];
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (size_t i = 0; i < os->n_nodes; i++)
            for (int d = 0; d < 2; d++) { lo[d] = fmin(lo[d], os->xyz[3 * i + d]); hi[d] = fmax(hi[d], os->xyz[3 * i + d]); }
        long i0 = (long)ceil(lo[0] / grid - 0.5), i1 = (long)floor(hi[0] / grid - 0.5);
        long j0 = (long)ceil(lo[1] / grid - 0.5), j1 = (long)floor(hi[1] / grid - 0.5);
        gp = thx_calloc(ctx, np ? np : 1, sizeof *gp);
        gn = thx_calloc(ctx, np ? np : 1, sizeof *gn);
        if (!gp || !gn) { st = THX_ENOMEM; goto done; }
        int failed = 0;
#pragma omp parallel for schedule(dynamic, 1)
        for (long k = 0; k < (long)np; k++) {
            size_t cap = 0, n = 0;
            double *buf = NULL;
            for (long j = j0; j <= j1; j++)
                for (long i = i0; i <= i1; i++) {
                    /* every other plane's grid is shifted by half a step in x and y: the nodes of two
                       neighbouring planes are then not above one another (a body-centred lattice),
                       which avoids the flat tetrahedra of vertically aligned squares */
                    double sh = (k & 1) ? 0.5 : 0.0;
                    /* rounded to the precision volume.pts stores, so that the file holds exactly the
                       points that were tetrahedralized (a thin tetrahedron of unrounded grid points
                       can become exactly flat once written) */
                    thx_vec3 p = thx_v3(stored(((double)i + 0.5 + sh) * grid), stored(((double)j + 0.5 + sh) * grid),
                                        stored(planes[k]));
                    if (!locator_inside(&loc[outer], p)) continue;
                    if (o->no_heart && heart >= 0 && locator_inside(&loc[heart], p)) continue;
                    int near = 0;
                    for (size_t s = 0; s < ns && !near; s++) near = locator_near(&loc[s], p, tol);
                    if (near) continue;
                    if (n + 1 > cap) {
                        cap = cap ? 2 * cap : 256;
                        double *nb = realloc(buf, 3 * cap * sizeof *nb);
                        if (!nb) { failed = 1; break; }
                        buf = nb;
                    }
                    buf[3 * n] = p.x; buf[3 * n + 1] = p.y; buf[3 * n + 2] = p.z;
                    n++;
                }
            gp[k] = buf;
            gn[k] = n;
        }
        if (failed) { st = thx_error(ctx, THX_ENOMEM, "mesh: out of memory placing grid points"); goto done; }
    }
    size_t n_grid = 0;
    for (size_t k = 0; k < np; k++) n_grid += gn[k];
    S.n_grid_nodes = n_grid;
    size_t nn = offset[ns] + n_grid;
    xyz = thx_malloc(ctx, 3 * nn * sizeof *xyz);
    if (!xyz) { st = THX_ENOMEM; goto done; }
    for (size_t s = 0; s < ns; s++) memcpy(xyz + 3 * offset[s], m->surf[s]->xyz, 3 * m->surf[s]->n_nodes * sizeof *xyz);
    {
        size_t at = offset[ns];
        for (size_t k = 0; k < np; k++) {
            if (gn[k]) memcpy(xyz + 3 * at, gp[k], 3 * gn[k] * sizeof *xyz);
            at += gn[k];
        }
    }
    double t1 = thx_wtime();
    S.t_points = t1 - t0;

    /* 2. Delaunay */
    size_t nt = 0;
    {
        thx_ctx *dc = NULL;
        if (thx_ctx_create(&dc) != THX_OK) { st = THX_ENOMEM; goto done; }
        st = thx_delaunay3d(dc, xyz, nn, &tets, &nbrs, &nt, NULL);
        if (st != THX_OK) {
            char msg[2048];
            snprintf(msg, sizeof msg, "%s", thx_ctx_message(dc));
            thx_ctx_destroy(&dc);
            /* name the surfaces whose nodes coincide: indices below offset[ns] are surface nodes */
            st = thx_error(ctx, st, "mesh: tetrahedralization failed: %s (volume nodes 1..%zu are the surface nodes in "
                           "model order, then the grid points)", msg, offset[ns]);
            goto done;
        }
        thx_ctx_destroy(&dc);
    }
    /* right-handed from here on (the volume's convention): swap corners 2 and 3, and their faces */
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = x;
        x = nbrs[4 * t + 2];
        nbrs[4 * t + 2] = nbrs[4 * t + 3];
        nbrs[4 * t + 3] = x;
    }
    S.n_delaunay_tets = nt;
    /* the surfaces' triangles made faces where one flip per edge does it */
    if (o->recover) {
        recover_stats rs;
        THX_TRY(mesh_recover(ctx, xyz, nn, &tets, &nbrs, &nt, (const thx_surface *const *)m->surf, offset, ns, &rs));
        S.n_surface_tris = rs.n_triangles;
        S.n_missing_before = rs.missing_before;
        S.n_missing_after = rs.missing_after;
        S.n_missing_face_only = rs.missing_face_only;
        S.n_recover_flips = rs.n_flip23 + rs.n_edge_removals + rs.n_boundary + rs.n_walk + rs.n_face_ops;
        S.t_recover = rs.seconds;
    }
    double t2 = thx_wtime();
    S.t_delaunay = t2 - t1;

    /* 3. outside tetrahedra, 4. regions */
    keep = thx_malloc(ctx, nt ? nt : 1);
    region = thx_malloc(ctx, (nt ? nt : 1) * sizeof *region);
    if (!keep || !region) { st = THX_ENOMEM; goto done; }
    /* the region table: mean thorax first, then per surface role */
    thx_region table[16];
    int n_regions = 0, surf_region[64];
    thx_region_default("mean_thorax", &table[n_regions++]);
    for (size_t s = 0; s < ns && s < 64; s++) {
        surf_region[s] = -1;
        const thx_surface *su = m->surf[s];
        const char *tissue = NULL;
        switch (su->role) {
        case THX_ROLE_FAT: tissue = "fat"; break;
        case THX_ROLE_MUSCLE: tissue = "muscle"; break;
        case THX_ROLE_LUNG: tissue = "lung"; break;
        case THX_ROLE_HEART: tissue = o->no_heart ? NULL : "heart"; break;
        case THX_ROLE_OTHER: tissue = "mean_thorax"; break;
        default: break;
        }
        if (!tissue || n_regions >= 16) continue;
        thx_region_default(tissue, &table[n_regions]);
        /* lungs and other surfaces are named after their surface */
        if (su->role == THX_ROLE_LUNG || su->role == THX_ROLE_OTHER) snprintf(table[n_regions].name, sizeof table[n_regions].name, "%s", su->name);
        surf_region[s] = n_regions++;
    }
    if (ns > 64) { st = thx_error(ctx, THX_EINPUT, "mesh: more than 64 surfaces"); goto done; }
    size_t n_out = 0, n_heart = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : n_out, n_heart)
    for (long t = 0; t < (long)nt; t++) {
        const int32_t *q = tets + 4 * t;
        thx_vec3 P[4];
        int on_surf = 0;
        for (int k = 0; k < 4; k++) {
            P[k] = thx_v3(xyz[3 * q[k]], xyz[3 * q[k] + 1], xyz[3 * q[k] + 2]);
            on_surf += (size_t)q[k] < offset[ns];
        }
        int out = 0;
        for (int a = 0; a < 4 && !out; a++)
            for (int b = a + 1; b < 4 && !out; b++) {
                if ((size_t)q[a] >= offset[ns] || (size_t)q[b] >= offset[ns]) continue;
                out = outside_domain(&loc[outer], thx_v3_scale(thx_v3_add(P[a], P[b]), 0.5), on_eps);
            }
        thx_vec3 c = thx_v3_scale(thx_v3_add(thx_v3_add(P[0], P[1]), thx_v3_add(P[2], P[3])), 0.25);
        if (!out && on_surf >= 2) out = outside_domain(&loc[outer], c, on_eps);
        region[t] = -1;
        if (out) { keep[t] = 0; n_out++; continue; }
        if (o->no_heart && heart >= 0 && locator_inside(&loc[heart], c)) { keep[t] = 2; n_heart++; continue; }
        keep[t] = 1;
        region[t] = classify_region(m, loc, surf_region, c);
    }
    S.n_outside = n_out;
    S.n_heart = n_heart;
    /* Flat tetrahedra (slivers) with a face on the boundary are peeled off, layer by layer (the
       paper's quality control); inside the domain they stay, since removing them would leave a void.
       A boundary face that is a surface triangle is where the boundary belongs: a sliver whose
       boundary faces are all surface triangles stays, unless it is flatter than half the limit (its
       interior edge cannot be flipped then: the ring around it is not convex; peeling it moves the
       boundary by less than sin(2.5 deg) of an edge). */
    if (o->sliver_deg > 0) {
        size_t peeled = 0;
        mesh_triset *tris = NULL;
        THX_TRY(mesh_triset_build(ctx, (const thx_surface *const *)m->surf, offset, ns, &tris));
        for (int round = 0; round < 8; round++) {
            size_t this_round = 0;
            for (size_t t = 0; t < nt; t++) {
                if (keep[t] != 1) continue;
                int on_boundary = 0, off_surface = 0;
                for (int f = 0; f < 4; f++) {
                    int32_t u = nbrs[4 * t + f];
                    const int32_t *q = tets + 4 * t;
                    if (u >= 0 && keep[u] == 1) continue;
                    on_boundary = 1;
                    off_surface |= !mesh_triset_has(tris, q[(f + 1) & 3], q[(f + 2) & 3], q[(f + 3) & 3]);
                }
                if (!on_boundary) continue;
                double d = mesh_tet_min_dihedral(xyz, tets + 4 * t);
                if (d < (off_surface ? o->sliver_deg : 0.5 * o->sliver_deg)) { keep[t] = 3; this_round++; }
            }
            peeled += this_round;
            if (!this_round) break;
        }
        S.n_slivers_peeled = peeled;
        mesh_triset_free(&tris);
    }
    {
        size_t readded = 0, bad = 0, taken = 0;
        THX_TRY(repair_boundary(ctx, nt, tets, nbrs, keep, xyz, nn, offset[ns], &loc[outer], on_eps, &readded, &taken, &bad));
        if (bad && S.n_slivers_peeled) {
            /* the peeling opened a pinch the repair cannot close: keep the slivers instead */
            for (size_t t = 0; t < nt; t++) if (keep[t] == 3) keep[t] = 1;
            S.n_slivers_peeled = 0;
            for (size_t t = 0; t < nt; t++) if (keep[t] == 4) keep[t] = 1;
            size_t more = 0;
            THX_TRY(repair_boundary(ctx, nt, tets, nbrs, keep, xyz, nn, offset[ns], &loc[outer], on_eps, &more, &taken, &bad));
            readded += more;
        }
        S.n_readded = readded;
        S.n_taken = taken;
        S.n_pinches = bad;
        if (readded)
#pragma omp parallel for schedule(dynamic, 4096)
            for (long t = 0; t < (long)nt; t++)
                if (keep[t] == 1 && region[t] < 0) region[t] = classify_region(m, loc, surf_region, tet_centroid(xyz, tets + 4 * t));
    }
    double t3 = thx_wtime();
    S.t_classify = t3 - t2;

    /* the volume: right-handed tetrahedra (swap two corners of the Delaunay output) */
    THX_TRY(thx_volume_create(ctx, &v));
    size_t kept = 0;
    for (size_t t = 0; t < nt; t++) kept += keep[t] == 1;
    v->tet = thx_malloc(ctx, 4 * (kept ? kept : 1) * sizeof *v->tet);
    v->region = thx_malloc(ctx, (kept ? kept : 1) * sizeof *v->region);
    v->regions = thx_malloc(ctx, (size_t)n_regions * sizeof *v->regions);
    if (!v->tet || !v->region || !v->regions) { st = THX_ENOMEM; goto done; }
    /* the kept tetrahedra's adjacency, for the sliver repair (Delaunay numbering -> kept numbering) */
    int32_t *newidx = NULL;
    if (o->repair_deg > 0) {
        newidx = thx_malloc(ctx, (nt ? nt : 1) * sizeof *newidx);
        vnbr = thx_malloc(ctx, 4 * (kept ? kept : 1) * sizeof *vnbr);
        if (!newidx || !vnbr) { free(newidx); st = THX_ENOMEM; goto done; }
        for (size_t t = 0, k = 0; t < nt; t++) newidx[t] = keep[t] == 1 ? (int32_t)k++ : -1;
        for (size_t t = 0; t < nt; t++) {
            if (keep[t] != 1) continue;
            for (int f = 0; f < 4; f++) {
                int32_t u = nbrs[4 * t + f];
                vnbr[4 * (size_t)newidx[t] + f] = u >= 0 ? newidx[u] : -1;
            }
        }
        free(newidx);
    }
    for (size_t t = 0, k = 0; t < nt; t++) {
        if (keep[t] != 1) continue;
        v->tet[4 * k] = tets[4 * t];
        v->tet[4 * k + 1] = tets[4 * t + 1];
        v->tet[4 * k + 2] = tets[4 * t + 2];
        v->tet[4 * k + 3] = tets[4 * t + 3];
        v->region[k] = region[t];
        if (region[t] >= 0 && region[t] < 16) S.per_region[region[t]]++;
        k++;
    }
    v->n_tets = kept;
    /* the Delaunay arrays are done with: free them before the repair's working memory */
    free(tets);
    free(nbrs);
    free(keep);
    free(region);
    tets = nbrs = region = NULL;
    keep = NULL;
    memcpy(v->regions, table, (size_t)n_regions * sizeof *table);
    v->n_regions = (size_t)n_regions;
    v->n_nodes = nn;
    v->xyz = xyz;
    xyz = NULL;
    /* node tables */
    v->n_surfaces = ns;
    v->surf_n_nodes = thx_malloc(ctx, ns * sizeof *v->surf_n_nodes);
    v->surf_node = thx_calloc(ctx, ns, sizeof *v->surf_node);
    v->node_surf = thx_malloc(ctx, nn * sizeof *v->node_surf);
    v->node_snode = thx_malloc(ctx, nn * sizeof *v->node_snode);
    if (!v->surf_n_nodes || !v->surf_node || !v->node_surf || !v->node_snode) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < nn; i++) v->node_surf[i] = v->node_snode[i] = -1;
    for (size_t s = 0; s < ns; s++) {
        v->surf_n_nodes[s] = m->surf[s]->n_nodes;
        v->surf_node[s] = thx_malloc(ctx, (m->surf[s]->n_nodes ? m->surf[s]->n_nodes : 1) * sizeof **v->surf_node);
        if (!v->surf_node[s]) { st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++) {
            v->surf_node[s][i] = (int32_t)(offset[s] + i);
            v->node_surf[offset[s] + i] = (int32_t)s;
            v->node_snode[offset[s] + i] = (int32_t)i;
        }
    }
    /* slivers inside the domain: repaired (flips, perturbation of grid nodes), never removed */
    if (o->repair_deg > 0) {
        region_ctx rc = {m, loc, surf_region};
        improve_opts io = {o->repair_deg, 6, 0, classify_cb, &rc};
        improve_stats is;
        int32_t *adj = vnbr;
        vnbr = NULL; /* taken over */
        THX_TRY(mesh_improve(ctx, v, adj, (const thx_surface *const *)m->surf, ns, &io, &is));
        S.repair_below_before = is.below_before;
        S.repair_below_after = is.below_after;
        S.repair_min_before = is.min_before;
        S.repair_min_after = is.min_after;
        S.n_edge_removals = is.n_edge_removals;
        S.n_face_removals = is.n_face_removals;
        S.n_moves = is.n_moves;
        S.t_repair = is.seconds;
        memset(S.per_region, 0, sizeof S.per_region);
        for (size_t t = 0; t < v->n_tets; t++)
            if (v->region[t] >= 0 && v->region[t] < 16) S.per_region[v->region[t]]++;
    }
    S.n_tets = v->n_tets;
    S.n_nodes = v->n_nodes;
    thx_volume_destroy(&m->volume);
    m->volume = v;
    v = NULL;
    S.t_total = thx_wtime() - t0;
    if (stats) *stats = S;
done:
    if (loc) for (size_t s = 0; s < ns; s++) locator_free(&loc[s]);
    free(loc);
    free(offset);
    free(planes);
    if (gp) for (size_t k = 0; k < np; k++) free(gp[k]);
    free(gp);
    free(gn);
    free(xyz);
    free(tets);
    free(nbrs);
    free(vnbr);
    free(keep);
    free(region);
    thx_volume_destroy(&v);
    return st;
}
