/*
 * Volume meshing (paper 3.3) of the medium-resolution phantom: every
 * tetrahedron right-handed, the mesh's volume against the volume the outer
 * surface encloses, each region's volume against its surfaces', surface nodes
 * kept as volume nodes, deterministic output, the heart left out on request.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/improve.h"
#include "thorax/model/volume.h"
#include "testlib.h"
#include "thorax/mesh/mesh.h"
#include "thorax/phantom/phantom.h"
#include "thorax/geom/surfaces.h"
/* Largest radius-edge ratio (circumradius / shortest edge) of v's tetrahedra, computed here
 * independently of the mesher. */
static double worst_radius_edge(const thx_volume *v)
{
    double worst = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        const double *p[4];
        for (int k = 0; k < 4; k++) p[k] = v->xyz + 3 * (size_t)v->tet[4 * t + k];
        double a[3][3], l2[3];
        for (int k = 0; k < 3; k++) {
            for (int d = 0; d < 3; d++) a[k][d] = p[k + 1][d] - p[0][d];
            l2[k] = a[k][0] * a[k][0] + a[k][1] * a[k][1] + a[k][2] * a[k][2];
        }
        /* circumcentre c - p0 solves 2 a_k . x = |a_k|^2 (Cramer's rule) */
        double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        double x[3];
        for (int c = 0; c < 3; c++) {
            double m[3][3];
            memcpy(m, a, sizeof m);
            for (int k = 0; k < 3; k++) m[k][c] = 0.5 * l2[k];
            x[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                    m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
        }
        double e = INFINITY;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) {
                double d2 = 0;
                for (int d = 0; d < 3; d++) d2 += (p[i][d] - p[j][d]) * (p[i][d] - p[j][d]);
                e = fmin(e, d2);
            }
        double re = sqrt((x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) / e);
        worst = re > worst ? re : worst;
    }
    return worst;
}

static thx_model *phantom_model(thx_ctx *ctx)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    return m;
}

static const thx_surface *by_name(const thx_model *m, const char *name)
{
    for (size_t s = 0; s < m->n_surfaces; s++) if (!strcmp(m->surf[s]->name, name)) return m->surf[s];
    return NULL;
}

static double region_volume(const thx_volume *v, const char *name)
{
    double sum = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        if (!strcmp(v->regions[v->region[t]].name, name)) sum += thx_volume_tet_volume(v, t);
    return sum;
}

typedef struct { int32_t a, b, c; } tri3;
static int cmp_tri3(const void *x, const void *y)
{
    const tri3 *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->c > q->c) - (p->c < q->c);
}
static tri3 sort3(int32_t a, int32_t b, int32_t c)
{
    int32_t x;
    if (a > b) { x = a; a = b; b = x; }
    if (b > c) { x = b; b = c; c = x; }
    if (a > b) { x = a; a = b; b = x; }
    return (tri3){a, b, c};
}

/* The faces of the mesh between two regions or on its boundary (found from the tetrahedra alone),
 * per surface: their area where all three corners are nodes of that surface (its own or the
 * Steiner nodes recorded on it) in area[s]; returns how many such faces lie on no single surface. */
static size_t interface_area(const thx_model *m, double *area)
{
    const thx_volume *v = m->volume;
    typedef struct { tri3 k; int32_t t; } frec;
    frec *f = malloc(4 * v->n_tets * sizeof *f);
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        for (int k = 0; k < 4; k++) f[4 * t + k] = (frec){sort3(q[(k + 1) & 3], q[(k + 2) & 3], q[(k + 3) & 3]), (int32_t)t};
    }
    qsort(f, 4 * v->n_tets, sizeof *f, cmp_tri3); /* the key comes first */
    int32_t *on = malloc(v->n_nodes * sizeof *on);
    for (size_t i = 0; i < v->n_nodes; i++) on[i] = v->node_surf[i];
    for (size_t i = 0; i < v->n_steiner; i++) on[v->steiner[i].node] = v->steiner[i].surf;
    for (size_t s = 0; s < m->n_surfaces; s++) area[s] = 0;
    size_t off = 0, n = 4 * v->n_tets;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && !cmp_tri3(&f[j].k, &f[i].k)) j++;
        int interface = j - i == 1 || v->region[f[i].t] != v->region[f[i + 1].t];
        if (interface) {
            int32_t a = f[i].k.a, b = f[i].k.b, c = f[i].k.c;
            if (on[a] < 0 || on[a] != on[b] || on[a] != on[c]) off++;
            else {
                const double *A = v->xyz + 3 * a, *B = v->xyz + 3 * b, *C = v->xyz + 3 * c;
                double u[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, w[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
                double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
                area[on[a]] += 0.5 * sqrt(x * x + y * y + z * z);
            }
        }
        i = j;
    }
    free(on);
    free(f);
    return off;
}

static double surface_area(const thx_surface *s)
{
    double sum = 0;
    for (size_t i = 0; i < s->n_tris; i++) {
        const double *A = s->xyz + 3 * s->tri[3 * i], *B = s->xyz + 3 * s->tri[3 * i + 1], *C = s->xyz + 3 * s->tri[3 * i + 2];
        double u[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, w[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
        double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
        sum += 0.5 * sqrt(x * x + y * y + z * z);
    }
    return sum;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_model *m = phantom_model(ctx);
    thx_mesh_opts o;
    thx_mesh_opts_default(&o);
    thx_mesh_stats st;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &o, &st));
    const thx_volume *v = m->volume;
    CHECK(v != NULL);
    if (!v) return tl_finish();
    printf("medium phantom: %zu nodes (%zu surface, %zu grid), %zu tetrahedra (paper: 22,000 and 130,000)\n",
           v->n_nodes, st.n_surface_nodes, st.n_grid_nodes, v->n_tets);
    /* every tetrahedron right-handed */
    size_t bad = 0;
    double total = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        double vol = thx_volume_tet_volume(v, t);
        if (!(vol > 0)) bad++;
        total += vol;
    }
    CHECK(bad == 0);
    /* the mesh fills the outer surface: volume within 1% */
    double outer = thx_surface_volume(by_name(m, "torso"));
    printf("volume: tetrahedra %.0f mm^3, torso surface %.0f mm^3 (%+.3f%%)\n", total, outer, 100 * (total - outer) / outer);
    CHECK(fabs(total - outer) / outer < 1e-6);
    /* regions against the volumes their surfaces enclose */
    double lr = region_volume(v, "lung_r"), ll = region_volume(v, "lung_l"), h = region_volume(v, "heart");
    double slr = thx_surface_volume(by_name(m, "lung_r")), sll = thx_surface_volume(by_name(m, "lung_l")),
           sh = thx_surface_volume(by_name(m, "heart"));
    double fat = region_volume(v, "fat"), sfat = outer - thx_surface_volume(by_name(m, "fat"));
    printf("regions: lung_r %+.2f%%, lung_l %+.2f%%, heart %+.2f%%, fat %+.2f%%\n", 100 * (lr - slr) / slr,
           100 * (ll - sll) / sll, 100 * (h - sh) / sh, 100 * (fat - sfat) / sfat);
    /* the regions are bounded by their surfaces exactly: volumes equal up to the 1e-6 mm rounding */
    CHECK(fabs(lr - slr) / slr < 1e-6);
    CHECK(fabs(ll - sll) / sll < 1e-6);
    CHECK(fabs(h - sh) / sh < 1e-6);
    CHECK(fabs(fat - sfat) / sfat < 1e-6);
    /* node tables: surface nodes are volume nodes with the same coordinates */
    size_t mism = 0;
    for (size_t s = 0; s < m->n_surfaces; s++)
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++) {
            int32_t k = v->surf_node[s][i];
            /* on the mesher's binary grid: within half its spacing (2^-21 mm here) */
            for (int d = 0; d < 3; d++) mism += !(fabs(v->xyz[3 * (size_t)k + (size_t)d] - m->surf[s]->xyz[3 * i + (size_t)d]) <= 0x1p-21);
            mism += v->node_surf[k] != (int32_t)s || v->node_snode[k] != (int32_t)i;
        }
    CHECK(mism == 0);
    /* conductivity table: anisotropic skeletal muscle along z, every tensor positive */
    int muscle = -1;
    for (size_t r = 0; r < v->n_regions; r++) {
        CHECK(v->regions[r].sigma[0] > 0 && v->regions[r].sigma[4] > 0 && v->regions[r].sigma[8] > 0);
        CHECK(v->regions[r].source[0] != '\0');
        if (!strcmp(v->regions[r].name, "muscle")) muscle = (int)r;
    }
    CHECK(muscle >= 0 && v->regions[muscle].anisotropic && v->regions[muscle].sigma[8] > v->regions[muscle].sigma[0]);
    /* conformity, judged from the tetrahedra alone: the faces between regions and on the boundary lie
       on the surfaces and add up to each surface's area (the surfaces' triangles, split by Steiner
       points where the mesher added them) */
    printf("conformity: %zu of %zu surface triangles not faces of the Delaunay tetrahedralization; %zu Steiner "
           "points (%zu on edges), %zu triangles split\n", st.n_missing_before, st.n_surface_tris,
           st.n_steiner_edge + st.n_steiner_face, st.n_steiner_edge, st.n_split_triangles);
    CHECK(st.n_missing_before > 1000); /* the Delaunay step alone does not conform */
    CHECK(v->n_steiner == st.n_steiner_edge + st.n_steiner_face);
    {
        double area[16];
        size_t off = interface_area(m, area);
        CHECK(off == 0);
        for (size_t s = 0; s < m->n_surfaces; s++) {
            double sa = surface_area(m->surf[s]);
            printf("  %-8s interface faces %.3f mm^2, surface %.3f mm^2 (%+.2e)\n", m->surf[s]->name, area[s], sa, (area[s] - sa) / sa);
            CHECK_NEAR(area[s], sa, 1e-6 * sa);
        }
        /* Steiner records: on their triangle, at their barycentric coordinates */
        double worst = 0;
        for (size_t i = 0; i < v->n_steiner; i++) {
            const thx_steiner *r = &v->steiner[i];
            const thx_surface *su = m->surf[r->surf];
            const int32_t *g = su->tri + 3 * (size_t)r->tri;
            CHECK(r->bary[0] >= -1e-9 && r->bary[1] >= -1e-9 && r->bary[2] >= -1e-9);
            CHECK_NEAR(r->bary[0] + r->bary[1] + r->bary[2], 1.0, 1e-12);
            for (int d = 0; d < 3; d++) {
                double x = 0;
                for (int k = 0; k < 3; k++) x += r->bary[k] * su->xyz[3 * (size_t)g[k] + (size_t)d];
                double e = fabs(x - v->xyz[3 * (size_t)r->node + (size_t)d]);
                worst = e > worst ? e : worst;
            }
        }
        printf("  Steiner nodes within %.2e mm of their recorded positions\n", worst);
        CHECK(worst <= 1e-6);
    }
    /* interior slivers repaired: few flat tetrahedra left, the same domain as without the repair */
    {
        size_t below5 = 0, below10 = 0;
        double mn = 180;
        for (size_t t = 0; t < v->n_tets; t++) {
            double d = mesh_tet_min_dihedral(v->xyz, v->tet + 4 * t);
            below5 += d < 5;
            below10 += d < 10;
            mn = d < mn ? d : mn;
        }
        printf("quality: smallest dihedral %.2f deg, %zu below 5 deg, %zu below 10 deg (%.4f%%)\n", mn, below5, below10,
               100.0 * (double)below10 / (double)v->n_tets);
        printf("repair below %g deg: %zu -> %zu tetrahedra, smallest dihedral %.2f -> %.2f deg (%zu below 5 deg left)\n",
               o.repair_deg, st.repair_below_before, st.repair_below_after, st.repair_min_before, st.repair_min_after, below5);
        CHECK(st.repair_below_before > 100);
        printf("repair: %zu Steiner nodes slid in their triangles (records checked above)\n", st.n_slides);
        CHECK(st.n_slides > 0);
        CHECK(st.repair_below_after * 10 < st.repair_below_before);
        CHECK_NEAR(st.repair_min_after, mn, 1e-9);
        CHECK(mn >= 5.0);                    /* issue 10: no tetrahedron below 5 degrees */
        double re = worst_radius_edge(v);
        printf("quality: largest radius-edge ratio %.2f\n", re);
        CHECK(re < 9.58); /* what tetgen -pq1.414/10 leaves on the medium phantom (bench/mesh.sh) */
        CHECK(below10 * 2000 < v->n_tets);   /* fewer than 0.05% below 10 degrees */
        thx_model *m0 = phantom_model(ctx);
        thx_mesh_opts o0 = o;
        o0.repair_deg = 0;
        thx_mesh_stats st0;
        CHECK_OK(ctx, thx_mesh_build(ctx, m0, &o0, &st0));
        double total0 = 0;
        for (size_t t = 0; t < m0->volume->n_tets; t++) total0 += thx_volume_tet_volume(m0->volume, t);
        CHECK_NEAR(total0, total, 1e-9 * total);
        /* the repair's collapses remove nodes and its insertions add some (--repair 0 still repairs
           below 5 deg): both meshes come from the same nodes */
        CHECK(m0->volume->n_nodes + st0.n_collapses - st0.n_inserts == v->n_nodes + st.n_collapses - st.n_inserts);
        CHECK(st0.repair_min_after >= 1.0); /* repair 0 still gives a mesh thorax check accepts */
        thx_model_destroy(&m0);
    }
    /* deterministic */
    size_t nt = v->n_tets;
    int32_t *copy = malloc(4 * nt * sizeof *copy);
    memcpy(copy, v->tet, 4 * nt * sizeof *copy);
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &o, &st));
    CHECK(m->volume->n_tets == nt && memcmp(copy, m->volume->tet, 4 * nt * sizeof *copy) == 0);
    free(copy);
    /* without the heart: no heart region, and the heart's volume is missing from the mesh */
    o.no_heart = 1;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &o, &st));
    v = m->volume;
    double total2 = 0;
    for (size_t t = 0; t < v->n_tets; t++) total2 += thx_volume_tet_volume(v, t);
    CHECK(region_volume(v, "heart") == 0);
    printf("without the heart: %zu tetrahedra, volume %+.3f%% of torso minus heart\n", v->n_tets,
           100 * (total2 - (outer - sh)) / (outer - sh));
    CHECK(fabs(total2 - (outer - sh)) / (outer - sh) < 1e-6);
    /* a model without an outer surface is refused */
    thx_model *empty = NULL;
    thx_model_create(ctx, &empty);
    CHECK(thx_mesh_build(ctx, empty, &o, &st) == THX_EINPUT);
    thx_model_destroy(&empty);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
