/*
 * Volume meshing (paper 3.3, "Volume Segmentation"): the hybrid method.
 *
 *  1. Nodes: every surface node (volume node numbers follow the model's
 *     surface order), then a square grid ((i + 1/2) g, (j + 1/2) g) on each
 *     layer plane, kept where it lies inside the outer surface and no surface
 *     comes closer than the tolerance ("removed all points that were within
 *     some tolerance of an existing surface").
 *  2. Delaunay tetrahedralization of all nodes (thorax/mesh/delaunay.h); the
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

#include "mesh/conform.h"
#include "mesh/folds.h"
#include "mesh/improve.h"
#include "mesh/locate.h"
#include "mesh/triset.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/mesh/mesh.h"
void thx_mesh_opts_default(thx_mesh_opts *o)
{
    memset(o, 0, sizeof *o);
    o->grid = 0; /* automatic: from the layer spacing */
    o->tol = 0;
    o->layer_spacing = 0;
    o->no_heart = 0;
    o->repair_deg = 15.0;
    o->radius_edge = 1.6;
    o->refine_deg = 10.0;
    o->fold_deg = 120.0;
    o->fold_size = 0;
}

/* x on the mesher's binary grid (spacing unit, a power of two: exact). */
static double snap(double x, double unit) { return nearbyint(x / unit) * unit; }

/* The grid spacing: a power of two, 2^-30 of the largest coordinate (rounded up to a power of two),
 * so that dyadic fractions of surface edges with 22 bits stay exact in double (53 bits). For a
 * thorax in mm (|x| < 1024) that is 2^-20 mm, about 1e-6 mm. */
static double grid_unit(const thx_model *m)
{
    double mx = 1e-300;
    for (size_t s = 0; s < m->n_surfaces; s++)
        for (size_t i = 0; i < 3 * m->surf[s]->n_nodes; i++) mx = fmax(mx, fabs(m->surf[s]->xyz[i]));
    int e;
    frexp(mx, &e); /* mx < 2^e */
    return ldexp(1.0, e - 30);
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
    /* organs and other surfaces: the innermost one containing the point (smallest enclosed volume:
       surfaces do not cross, so of two containing it one contains the other) */
    int best = 0;
    double best_v = INFINITY;
    for (size_t s = 0; s < ns; s++) {
        thx_role role = m->surf[s]->role;
        if ((role == THX_ROLE_LUNG || role == THX_ROLE_HEART || role == THX_ROLE_OTHER) && surf_region[s] >= 0 &&
            loc[s].volume < best_v && locator_inside(&loc[s], c)) {
            best = surf_region[s];
            best_v = loc[s].volume;
        }
    }
    return best;
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

static thx_vec3 tet_centroid(const double *xyz, const int32_t *q)
{
    thx_vec3 c = {0, 0, 0};
    for (int k = 0; k < 4; k++) c = thx_v3_add(c, thx_v3(xyz[3 * q[k]], xyz[3 * q[k] + 1], xyz[3 * q[k] + 2]));
    return thx_v3_scale(c, 0.25);
}

/* The domain for the quality refinement: inside the outer surface, not inside an excluded heart. */
typedef struct { const locator *outer, *heart; double on_eps; const mesh_folds *folds; } domain_ctx;
static int in_domain_cb(void *user, const double p[3])
{
    const domain_ctx *d = user;
    thx_vec3 v = thx_v3(p[0], p[1], p[2]);
    if (outside_domain(d->outer, v, d->on_eps)) return 0;
    return !(d->heart && locator_inside(d->heart, v));
}

/* The size bound of the quality refinement: graded towards the excluded heart's folds. */
static double size_cb(void *user, const double p[3])
{
    const domain_ctx *d = user;
    return mesh_folds_size(d->folds, p);
}

/*
 * The pieces of space the surfaces cut the tetrahedralization into: tetrahedra
 * joined across every face that is not on a surface (breadth-first). comp[t]
 * gets the piece's number; *n_comp their count; touches_hull[piece] 1 when
 * the piece reaches the convex hull (then it is outside the outer surface).
 */
static thx_status components(thx_ctx *ctx, const int32_t *tets, const int32_t *nbrs, size_t nt, const tset *fs,
                             int32_t *comp, size_t *n_comp, unsigned char **touches_hull)
{
    int32_t *queue = thx_malloc(ctx, (nt ? nt : 1) * sizeof *queue);
    size_t cap = 64, nc = 0;
    unsigned char *hull = thx_calloc(ctx, cap, 1);
    if (!queue || !hull) { free(queue); free(hull); return THX_ENOMEM; }
    for (size_t t = 0; t < nt; t++) comp[t] = -1;
    for (size_t t0 = 0; t0 < nt; t0++) {
        if (comp[t0] >= 0) continue;
        if (nc >= cap) {
            size_t old = cap;
            if (thx_grow(ctx, (void **)&hull, &cap, nc + 1, 1) != THX_OK) { free(queue); free(hull); return THX_ENOMEM; }
            memset(hull + old, 0, cap - old);
        }
        size_t head = 0, tail = 0;
        queue[tail++] = (int32_t)t0;
        comp[t0] = (int32_t)nc;
        while (head < tail) {
            int32_t t = queue[head++];
            const int32_t *q = tets + 4 * (size_t)t;
            for (int f = 0; f < 4; f++) {
                int32_t u = nbrs[4 * (size_t)t + f];
                if (tset_has(fs, tri_sorted(q[(f + 1) & 3], q[(f + 2) & 3], q[(f + 3) & 3]))) continue;
                if (u < 0) { hull[nc] = 1; continue; }
                if (comp[u] >= 0) continue;
                comp[u] = (int32_t)nc;
                queue[tail++] = u;
            }
        }
        nc++;
    }
    free(queue);
    *n_comp = nc;
    *touches_hull = hull;
    return THX_OK;
}

/* Nodes in no tetrahedron (none expected: grid points inside the outer surface, Steiner points on
 * surfaces that bound kept tetrahedra) are dropped and the rest renumbered; surface nodes are never
 * unused (they bound regions), so their numbers stay. */
static thx_status drop_unused_nodes(thx_ctx *ctx, thx_volume *v)
{
    unsigned char *used = thx_calloc(ctx, v->n_nodes ? v->n_nodes : 1, 1);
    if (!used) return THX_ENOMEM;
    for (size_t k = 0; k < 4 * v->n_tets; k++) used[v->tet[k]] = 1;
    size_t n_used = 0;
    for (size_t i = 0; i < v->n_nodes; i++) n_used += used[i];
    if (n_used == v->n_nodes) { free(used); return THX_OK; }
    for (size_t i = 0; i < v->n_nodes; i++)
        if (!used[i] && v->node_surf[i] >= 0) {
            free(used);
            return thx_error(ctx, THX_EINTERNAL, "mesh: node %zu of surface %ld is in no tetrahedron", i + 1, (long)v->node_surf[i] + 1);
        }
    int32_t *map = thx_malloc(ctx, v->n_nodes * sizeof *map);
    if (!map) { free(used); return THX_ENOMEM; }
    size_t k = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        map[i] = used[i] ? (int32_t)k : -1;
        if (used[i]) {
            memmove(v->xyz + 3 * k, v->xyz + 3 * i, 3 * sizeof *v->xyz);
            v->node_surf[k] = v->node_surf[i];
            v->node_snode[k] = v->node_snode[i];
            k++;
        }
    }
    for (size_t j = 0; j < 4 * v->n_tets; j++) v->tet[j] = map[v->tet[j]];
    size_t ks = 0;
    for (size_t j = 0; j < v->n_steiner; j++)
        if (map[v->steiner[j].node] >= 0) {
            v->steiner[ks] = v->steiner[j];
            v->steiner[ks++].node = map[v->steiner[j].node];
        }
    v->n_steiner = ks;
    for (size_t s = 0; s < v->n_surfaces; s++)
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) v->surf_node[s][i] = map[v->surf_node[s][i]];
    v->n_nodes = k;
    free(map);
    free(used);
    return THX_OK;
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
    int32_t *tets = NULL, *nbrs = NULL, *region = NULL, *vnbr = NULL, *comp = NULL;
    unsigned char *keep = NULL;
    thx_volume *v = NULL;
    size_t *offset = thx_calloc(ctx, ns + 1, sizeof *offset);
    double **gp = NULL;
    size_t *gn = NULL, np = 0;
    if (!loc || !offset) { st = THX_ENOMEM; goto done; }
    for (size_t s = 0; s < ns; s++) {
        THX_TRY(locator_init(ctx, &loc[s], m->surf[s]));
        loc[s].volume = thx_surface_volume(m->surf[s]);
    }
    for (size_t s = 0; s < ns; s++) offset[s + 1] = offset[s] + m->surf[s]->n_nodes;
    S.n_surface_nodes = offset[ns];
    const double unit = grid_unit(m);

    /* 1. grid points, plane by plane (in parallel, gathered in plane order: deterministic) */
#define PROGRESS(stage, f) do { if (o->progress) o->progress(o->progress_user, stage, f); } while (0)
    PROGRESS("points", 0.0);
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
                    thx_vec3 p = thx_v3(snap(((double)i + 0.5 + sh) * grid, unit), snap(((double)j + 0.5 + sh) * grid, unit),
                                        snap(planes[k], unit));
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
    /* the surface nodes on the binary grid (within unit / 2 of the surfaces' own coordinates) */
    for (size_t s = 0; s < ns; s++)
        for (size_t i = 0; i < 3 * m->surf[s]->n_nodes; i++) xyz[3 * offset[s] + i] = snap(m->surf[s]->xyz[i], unit);
    {
        size_t at = offset[ns];
        for (size_t k = 0; k < np; k++) {
            if (gn[k]) memcpy(xyz + 3 * at, gp[k], 3 * gn[k] * sizeof *xyz);
            at += gn[k];
        }
    }
    double t1 = thx_wtime();
    S.t_points = t1 - t0;

    /* 2. Delaunay, then points on the surfaces until every surface triangle is a union of faces */
    size_t nt = 0;
    mesh_subface *sub = NULL;
    size_t n_sub = 0;
    thx_steiner *steiner = NULL;
    size_t n_steiner = 0;
    {
        thx_dt *dt = NULL;
        PROGRESS("points", 1.0);
        PROGRESS("Delaunay", 0.0);
        st = thx_dt_create(ctx, xyz, nn, &dt);
        PROGRESS("Delaunay", 1.0);
        if (st != THX_OK) {
            /* name the surfaces whose nodes coincide: indices below offset[ns] are surface nodes */
            st = thx_error(ctx, st, "mesh: tetrahedralization failed: %s (volume nodes 1..%zu are the surface nodes in "
                           "model order, then the grid points)", thx_ctx_message(ctx), offset[ns]);
            goto done;
        }
        double t_dt = thx_wtime();
        S.t_delaunay = t_dt - t1;
        conform_stats cs;
        /* the excluded heart's sharp folds: a graded size bound around them (folds.h) */
        mesh_folds folds;
        memset(&folds, 0, sizeof folds);
        if (o->no_heart && heart >= 0 && o->fold_deg > 0) {
            double h0 = o->fold_size > 0 ? o->fold_size : grid / 14.0;
            st = mesh_folds_find(ctx, m->surf[heart], o->fold_deg, h0, THX_MESH_FOLD_GRADE, grid, &folds);
            if (st != THX_OK) { thx_dt_destroy(&dt); goto done; }
            S.n_folds = folds.n;
            S.fold_size = folds.n ? h0 : 0;
        }
        domain_ctx dc = {&loc[outer], o->no_heart && heart >= 0 ? &loc[heart] : NULL, on_eps, &folds};
        conform_quality q = {o->radius_edge, o->refine_deg, in_domain_cb, &dc, 0, 0.12, o->progress, o->progress_user,
                             folds.n ? size_cb : NULL};
        /* the Steiner budget (mesh_conform's default: 20 a surface triangle, plus 1000), plus the surface
           points a graded band around the folds needs: on each side of a fold of length L about
           L / (grade h0) points (the integral of L dr / h(r)^2), counted four times over */
        size_t max_steiner = 0;
        if (folds.n) {
            size_t n_tris = 0;
            for (size_t s = 0; s < ns; s++) n_tris += m->surf[s]->n_tris;
            double L = 0;
            for (size_t k = 0; k < folds.n; k++) {
                const double *a = folds.seg + 6 * k;
                L += sqrt((a[3] - a[0]) * (a[3] - a[0]) + (a[4] - a[1]) * (a[4] - a[1]) + (a[5] - a[2]) * (a[5] - a[2]));
            }
            max_steiner = 20 * n_tris + 1000 + (size_t)(8.0 * L / (folds.grade * folds.h0));
        }
        st = mesh_conform(ctx, dt, (const thx_surface *const *)m->surf, offset, ns, unit, max_steiner, &q, &steiner, &n_steiner, &sub,
                          &n_sub, &cs);
        mesh_folds_free(&folds);
        if (st != THX_OK) { thx_dt_destroy(&dt); goto done; }
        S.n_surface_tris = cs.n_triangles;
        S.n_missing_before = cs.missing_before;
        S.n_steiner_edge = cs.n_edge_points;
        S.n_steiner_face = cs.n_face_points;
        S.n_split_triangles = cs.n_split_triangles;
        S.conform_rounds = cs.rounds;
        S.min_piece = cs.min_piece;
        S.t_conform = cs.seconds - cs.t_refine;
        S.n_refine_points = cs.n_refine_points;
        S.n_refine_surface = cs.n_refine_surface;
        S.n_refine_near = cs.n_refine_near;
        S.n_refine_left = cs.n_refine_skipped;
        S.refine_rounds = cs.refine_rounds;
        S.refine_limited = cs.refine_limited;
        S.t_refine = cs.t_refine;
        size_t nall = thx_dt_n_points(dt);
        double *all = thx_realloc(ctx, xyz, 3 * nall * sizeof *all);
        if (!all) { thx_dt_destroy(&dt); st = THX_ENOMEM; goto done; }
        xyz = all;
        for (size_t i = nn; i < nall; i++) memcpy(xyz + 3 * i, thx_dt_point(dt, (int32_t)i), 3 * sizeof *xyz);
        nn = nall;
        st = thx_dt_finish(&dt, &tets, &nbrs, &nt);
        if (st != THX_OK) goto done;
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
    double t2 = thx_wtime();

    PROGRESS("regions", 0.0);
    /* 3. regions: the pieces the surfaces cut space into, each classified by the majority of its
       tetrahedra's centroids (the chain of inside/outside tests); outside the outer surface -> removed */
    keep = thx_malloc(ctx, nt ? nt : 1);
    region = thx_malloc(ctx, (nt ? nt : 1) * sizeof *region);
    comp = thx_malloc(ctx, (nt ? nt : 1) * sizeof *comp);
    if (!keep || !region || !comp) { st = THX_ENOMEM; goto done; }
    /* the region table: mean thorax first, then per surface role */
    thx_region table[16];
    int n_regions = 0, surf_region[64];
    if (ns > 64) { st = thx_error(ctx, THX_EINPUT, "mesh: more than 64 surfaces"); goto done; }
    thx_region_default("mean_thorax", &table[n_regions++]);
    for (size_t s = 0; s < ns; s++) {
        surf_region[s] = -1;
        const thx_surface *su = m->surf[s];
        const char *tissue = NULL;
        switch (su->role) {
        case THX_ROLE_FAT: tissue = "fat"; break;
        case THX_ROLE_MUSCLE: tissue = "muscle"; break;
        case THX_ROLE_LUNG: tissue = "lung"; break;
        case THX_ROLE_HEART: tissue = "heart"; break;
        case THX_ROLE_OTHER: tissue = "mean_thorax"; break;
        default: break;
        }
        if (!tissue) continue;
        if (n_regions >= 16) { st = thx_error(ctx, THX_EINPUT, "mesh: more than 16 tissue regions"); goto done; }
        thx_region_default(tissue, &table[n_regions]);
        /* lungs and other surfaces are named after their surface */
        if (su->role == THX_ROLE_LUNG || su->role == THX_ROLE_OTHER) snprintf(table[n_regions].name, sizeof table[n_regions].name, "%s", su->name);
        surf_region[s] = n_regions++;
    }
    /* the defaults' "along" on the body axis: the model's superior axis (z without a frame) */
    thx_regions_orient(table, (size_t)n_regions, &m->frame);
    for (size_t k = 0; k < o->n_region_set; k++) {
        int found = -1;
        for (int r = 0; r < n_regions && found < 0; r++)
            if (!strcmp(table[r].name, o->region_set[k].name)) found = r;
        if (found < 0) {
            char names[16 * 68] = "";
            for (int r = 0; r < n_regions; r++) {
                size_t at = strlen(names);
                snprintf(names + at, sizeof names - at, "%s%.64s", r ? ", " : "", table[r].name);
            }
            st = thx_error(ctx, THX_EINPUT, "mesh: no region \"%s\" to set (the regions are %s)", o->region_set[k].name, names);
            goto done;
        }
        thx_region *R = &table[found];
        if (o->region_set[k].rename[0]) snprintf(R->name, sizeof R->name, "%s", o->region_set[k].rename);
        if (o->region_set[k].sigma > 0) {
            memset(R->sigma, 0, sizeof R->sigma);
            R->sigma[0] = R->sigma[4] = R->sigma[8] = o->region_set[k].sigma;
            R->anisotropic = 0;
            snprintf(R->source, sizeof R->source, "set by the user (thorax mesh --region)");
        }
    }
    for (int r = 0; r < n_regions; r++)
        for (int q = 0; q < r; q++)
            if (!strcmp(table[r].name, table[q].name)) {
                st = thx_error(ctx, THX_EINPUT, "mesh: two regions would be named \"%s\"", table[r].name);
                goto done;
            }
    for (size_t k = 0; k < o->n_sigma_set; k++) {
        st = thx_regions_assign(ctx, table, (size_t)n_regions, o->sigma_set[k], "set by the user (thorax mesh --sigma)");
        if (st != THX_OK) {
            char why[512];
            snprintf(why, sizeof why, "%s", thx_ctx_message(ctx));
            st = thx_error(ctx, st, "mesh: --sigma %s", why);
            goto done;
        }
    }
    {
        tset fs = {NULL, 0};
        st = tset_init(ctx, &fs, n_sub);
        if (st == THX_OK)
            for (size_t i = 0; i < n_sub; i++) tset_add(&fs, tri_sorted(sub[i].v[0], sub[i].v[1], sub[i].v[2]));
        if (st != THX_OK) goto done;
        size_t n_comp = 0;
        unsigned char *hull = NULL;
        st = components(ctx, tets, nbrs, nt, &fs, comp, &n_comp, &hull);
        free(fs.slot);
        if (st != THX_OK) goto done;
        /* per tetrahedron: -1 outside, else its region by the chain; votes per piece */
        const int NV = 17; /* outside + 16 regions */
        size_t *votes = thx_calloc(ctx, n_comp * (size_t)NV, sizeof *votes);
        if (!votes) { free(hull); st = THX_ENOMEM; goto done; }
        /* a piece is one region by construction: its vote is taken on at most about 512 of its
           tetrahedra, evenly spread over it (all of them in small pieces) */
        size_t *size = thx_calloc(ctx, n_comp, sizeof *size), *seen = thx_calloc(ctx, n_comp, sizeof *seen);
        if (!size || !seen) { free(size); free(seen); free(votes); free(hull); st = THX_ENOMEM; goto done; }
        for (size_t t = 0; t < nt; t++) size[comp[t]]++;
        unsigned char *sampled = keep; /* as scratch until the keep flags are set below */
        for (size_t t = 0; t < nt; t++) {
            size_t k = (size_t)comp[t], stride = size[k] / 512 + 1;
            sampled[t] = seen[k]++ % stride == 0;
        }
        free(size);
        free(seen);
#pragma omp parallel for schedule(dynamic, 4096)
        for (long t = 0; t < (long)nt; t++) {
            region[t] = -2;
            if (!sampled[t]) continue;
            thx_vec3 c = tet_centroid(xyz, tets + 4 * t);
            region[t] = outside_domain(&loc[outer], c, on_eps) ? -1 : classify_region(m, loc, surf_region, c);
        }
        size_t n_sampled = 0;
        for (size_t t = 0; t < nt; t++)
            if (region[t] > -2) { votes[(size_t)comp[t] * NV + (size_t)(region[t] + 1)]++; n_sampled++; }
        int32_t *comp_region = thx_malloc(ctx, n_comp * sizeof *comp_region);
        if (!comp_region) { free(votes); free(hull); st = THX_ENOMEM; goto done; }
        size_t n_out = 0, n_heart = 0, n_disagree = 0;
        for (size_t k = 0; k < n_comp; k++) {
            int best = 0;
            for (int r = 1; r < NV; r++)
                if (votes[k * NV + r] > votes[k * NV + best]) best = r;
            comp_region[k] = hull[k] ? -1 : best - 1; /* a piece reaching the hull is outside */
        }
        for (size_t t = 0; t < nt; t++) {
            int32_t r = comp_region[comp[t]];
            n_disagree += region[t] > -2 && region[t] != r;
            region[t] = r;
            if (r < 0) { keep[t] = 0; n_out++; }
            else if (o->no_heart && heart >= 0 && r == surf_region[heart]) { keep[t] = 2; n_heart++; }
            else keep[t] = 1;
        }
        S.n_outside = n_out;
        S.n_heart = n_heart;
        S.n_pieces = n_comp;
        S.n_centroid_disagree = n_disagree;
        S.n_centroid_tested = n_sampled;
        free(votes);
        free(hull);
        free(comp_region);
    }
    double t3 = thx_wtime();
    S.t_classify = t3 - t2;
    PROGRESS("regions", 1.0);

    /* the volume */
    THX_TRY(thx_volume_create(ctx, &v));
    size_t kept = 0;
    for (size_t t = 0; t < nt; t++) kept += keep[t] == 1;
    v->tet = thx_malloc(ctx, 4 * (kept ? kept : 1) * sizeof *v->tet);
    v->region = thx_malloc(ctx, (kept ? kept : 1) * sizeof *v->region);
    v->regions = thx_malloc(ctx, (size_t)n_regions * sizeof *v->regions);
    if (!v->tet || !v->region || !v->regions) { st = THX_ENOMEM; goto done; }
    /* the kept tetrahedra's adjacency, for the sliver repair (Delaunay numbering -> kept numbering) */
    /* the repair always runs: at --repair's target, and at least at THX_MESH_REPAIR_FLOOR, so that the
       slivers the mesher itself makes (which thorax check refuses) are removed even with --repair 0 */
    const double repair_deg = fmax(o->repair_deg, THX_MESH_REPAIR_FLOOR);
    {
        int32_t *newidx = thx_malloc(ctx, (nt ? nt : 1) * sizeof *newidx);
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
        memcpy(v->tet + 4 * k, tets + 4 * t, 4 * sizeof *v->tet);
        v->region[k] = region[t];
        k++;
    }
    v->n_tets = kept;
    /* the Delaunay arrays are done with: free them before the repair's working memory */
    free(tets);
    free(nbrs);
    free(keep);
    free(region);
    free(comp);
    tets = nbrs = region = comp = NULL;
    keep = NULL;
    if (o->no_heart && heart >= 0 && surf_region[heart] >= 0) {
        /* the heart's region held its piece only to remove it: out of the table */
        int rh = surf_region[heart];
        for (size_t t = 0; t < v->n_tets; t++) v->region[t] -= v->region[t] > rh;
        memmove(table + rh, table + rh + 1, (size_t)(n_regions - rh - 1) * sizeof *table);
        n_regions--;
        for (size_t s = 0; s < ns; s++) surf_region[s] = surf_region[s] == rh ? -1 : surf_region[s] - (surf_region[s] > rh);
    }
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
    v->steiner = steiner;
    v->n_steiner = n_steiner;
    steiner = NULL;
    /* slivers: repaired (flips, moving grid nodes) with the faces on the surfaces kept, never removed */
    {
        region_ctx rc = {m, loc, surf_region};
        int32_t *corners = thx_malloc(ctx, 3 * (v->n_steiner ? v->n_steiner : 1) * sizeof *corners);
        if (!corners) { st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < v->n_steiner; i++)
            for (int k = 0; k < 3; k++)
                corners[3 * i + k] = v->surf_node[v->steiner[i].surf][m->surf[v->steiner[i].surf]->tri[3 * (size_t)v->steiner[i].tri + k]];
        /* the pocket pass for the heart's nodes (their potentials are given in forward problems) */
        improve_opts io = {repair_deg, o->radius_edge > 0 ? o->radius_edge : 2.0, 6, 0, classify_cb, &rc, corners, heart >= 0 ? heart : -2};
        improve_stats is;
        int32_t *prot = thx_malloc(ctx, 3 * (n_sub ? n_sub : 1) * sizeof *prot);
        if (!prot) { free(corners); st = THX_ENOMEM; goto done; }
        for (size_t i = 0; i < n_sub; i++) memcpy(prot + 3 * i, sub[i].v, 3 * sizeof *prot);
        int32_t *adj = vnbr;
        vnbr = NULL; /* taken over */
        PROGRESS("repair", 0.0);
        st = mesh_improve(ctx, v, adj, prot, n_sub, &io, &is);
        PROGRESS("repair", 1.0);
        free(prot);
        free(corners);
        if (st != THX_OK) goto done;
        S.repair_below_before = is.below_before;
        S.repair_below_after = is.below_after;
        S.repair_min_before = is.min_before;
        S.repair_min_after = is.min_after;
        S.n_edge_removals = is.n_edge_removals;
        S.n_face_removals = is.n_face_removals;
        S.n_moves = is.n_moves;
        S.n_slides = is.n_slides;
        S.n_collapses = is.n_collapses;
        S.n_inserts = is.n_inserts;
        S.n_pockets = is.n_pockets;
        S.n_pocket_nodes = is.n_pocket_nodes;
        S.t_repair = is.seconds;
    }
    /* nodes in no tetrahedron (collapsed by the repair, or any the removed pieces held) go */
    THX_TRY(drop_unused_nodes(ctx, v));
    S.n_steiner = v->n_steiner;
    memset(S.per_region, 0, sizeof S.per_region);
    for (size_t t = 0; t < v->n_tets; t++)
        if (v->region[t] >= 0 && v->region[t] < 16) S.per_region[v->region[t]]++;
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
    free(comp);
    free(sub);
    free(steiner);
    thx_volume_destroy(&v);
    return st;
}
