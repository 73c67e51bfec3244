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
#include "testlib.h"
#include "thorax/mesh.h"
#include "thorax/phantom.h"
#include "thorax/surfaces.h"

static thx_model *phantom_model(thx_ctx *ctx)
{
    thx_phantom_opts po;
    thx_phantom_opts_default(&po);
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_phantom_contours(ctx, &po, &c));
    thx_surfaces_opts so;
    thx_surfaces_opts_default(&so);
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_surfaces_build(ctx, c, &so, &m, NULL, NULL));
    thx_contours_destroy(&c);
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

/* Fraction of surface s's triangles that are faces of the volume mesh. */
static double faces_present(const thx_model *m, size_t s)
{
    const thx_volume *v = m->volume;
    tri3 *f = malloc(4 * v->n_tets * sizeof *f);
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        for (int k = 0; k < 4; k++) f[4 * t + k] = sort3(q[(k + 1) & 3], q[(k + 2) & 3], q[(k + 3) & 3]);
    }
    qsort(f, 4 * v->n_tets, sizeof *f, cmp_tri3);
    const thx_surface *su = m->surf[s];
    size_t hit = 0;
    for (size_t i = 0; i < su->n_tris; i++) {
        const int32_t *g = su->tri + 3 * i;
        tri3 k = sort3(v->surf_node[s][g[0]], v->surf_node[s][g[1]], v->surf_node[s][g[2]]);
        hit += bsearch(&k, f, 4 * v->n_tets, sizeof *f, cmp_tri3) != NULL;
    }
    free(f);
    return su->n_tris ? (double)hit / (double)su->n_tris : 1;
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
    CHECK(fabs(total - outer) / outer < 0.01);
    /* regions against the volumes their surfaces enclose */
    double lr = region_volume(v, "lung_r"), ll = region_volume(v, "lung_l"), h = region_volume(v, "heart");
    double slr = thx_surface_volume(by_name(m, "lung_r")), sll = thx_surface_volume(by_name(m, "lung_l")),
           sh = thx_surface_volume(by_name(m, "heart"));
    double fat = region_volume(v, "fat"), sfat = outer - thx_surface_volume(by_name(m, "fat"));
    printf("regions: lung_r %+.2f%%, lung_l %+.2f%%, heart %+.2f%%, fat %+.2f%%\n", 100 * (lr - slr) / slr,
           100 * (ll - sll) / sll, 100 * (h - sh) / sh, 100 * (fat - sfat) / sfat);
    CHECK(fabs(lr - slr) / slr < 0.05);
    CHECK(fabs(ll - sll) / sll < 0.05);
    CHECK(fabs(h - sh) / sh < 0.05);
    CHECK(fabs(fat - sfat) / sfat < 0.10);
    /* node tables: surface nodes are volume nodes with the same coordinates */
    size_t mism = 0;
    for (size_t s = 0; s < m->n_surfaces; s++)
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++) {
            int32_t k = v->surf_node[s][i];
            for (int d = 0; d < 3; d++) mism += v->xyz[3 * (size_t)k + (size_t)d] != m->surf[s]->xyz[3 * i + (size_t)d];
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
    /* the surfaces' triangles are faces of the mesh (recovered by flips where the Delaunay step chose
       the other diagonal): the boundary is the torso's own triangles, interfaces follow the surfaces */
    printf("recovery: %zu of %zu surface triangles not faces of the Delaunay tetrahedralization, %zu after\n",
           st.n_missing_before, st.n_surface_tris, st.n_missing_after);
    CHECK(st.n_missing_after * 3 < st.n_missing_before);
    for (size_t s = 0; s < m->n_surfaces; s++) {
        double fr = faces_present(m, s);
        printf("  %-8s %5.1f%% of its triangles are faces of the mesh\n", m->surf[s]->name, 100 * fr);
        CHECK(fr > (m->surf[s]->role == THX_ROLE_OUTER ? 0.95 : 0.85)); /* lungs: 88-93%, see decisions.md */
    }
    /* interior slivers repaired: few flat tetrahedra left, the same domain as without the repair */
    {
        size_t below5 = 0;
        double mn = 180;
        for (size_t t = 0; t < v->n_tets; t++) {
            double d = mesh_tet_min_dihedral(v->xyz, v->tet + 4 * t);
            below5 += d < 5;
            mn = d < mn ? d : mn;
        }
        printf("repair below %g deg: %zu -> %zu tetrahedra, smallest dihedral %.2f -> %.2f deg (%zu below 5 deg left)\n",
               o.repair_deg, st.repair_below_before, st.repair_below_after, st.repair_min_before, st.repair_min_after, below5);
        CHECK(st.repair_below_before > 100);
        CHECK(st.repair_below_after * 10 < st.repair_below_before);
        CHECK_NEAR(st.repair_min_after, mn, 1e-9);
        CHECK(mn > 2.0);
        CHECK(below5 * 20000 < v->n_tets); /* under 0.005% */
        thx_model *m0 = phantom_model(ctx);
        thx_mesh_opts o0 = o;
        o0.repair_deg = 0;
        thx_mesh_stats st0;
        CHECK_OK(ctx, thx_mesh_build(ctx, m0, &o0, &st0));
        double total0 = 0;
        for (size_t t = 0; t < m0->volume->n_tets; t++) total0 += thx_volume_tet_volume(m0->volume, t);
        CHECK_NEAR(total0, total, 1e-9 * total);
        CHECK(m0->volume->n_nodes == v->n_nodes);
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
    CHECK(fabs(total2 - (outer - sh)) / (outer - sh) < 0.01);
    /* a model without an outer surface is refused */
    thx_model *empty = NULL;
    thx_model_create(ctx, &empty);
    CHECK(thx_mesh_build(ctx, empty, &o, &st) == THX_EINPUT);
    thx_model_destroy(&empty);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
