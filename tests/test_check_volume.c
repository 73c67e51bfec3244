/* Tests of thorax/check/check_volume.h on hand-made volume meshes: clean meshes of
 * several kinds must pass, and every defect the checker claims to find is
 * planted once and must be found (alone, where the defect allows it).
 *
 * Environment: THX_CHECK_VOLUME_BENCH=N also times the check on a Delaunay
 * mesh of N points (N = 80000 gives about 500,000 tetrahedra); the test
 * itself times a smaller one. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "testlib.h"
#include "thorax/check/check_volume.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/geom/predicates.h"
#include "thorax/model/volume.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static thx_ctx *ctx;

static uint64_t rng = 0x2545f4914f6cdd1dull;
static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* ---------- builders (test side; deliberately simple) ---------- */

/* Makes tetrahedron t right-handed (thx_orient3d < 0) by swapping two nodes if needed. */
static void fix_orientation(const double *xyz, int32_t *q)
{
    if (thx_orient3d(xyz + 3 * q[0], xyz + 3 * q[1], xyz + 3 * q[2], xyz + 3 * q[3]) > 0) {
        int32_t x = q[2];
        q[2] = q[3];
        q[3] = x;
    }
}

/* A volume of nn nodes and nt tets (copied), one region "mean_thorax", no node tables. */
static thx_volume *vol_new(const double *xyz, size_t nn, const int32_t *tet, size_t nt)
{
    thx_volume *v = NULL;
    if (thx_volume_create(ctx, &v) != THX_OK) abort();
    v->n_nodes = nn;
    v->n_tets = nt;
    v->xyz = malloc((nn + 1) * 3 * sizeof(double));
    v->tet = malloc((nt + 1) * 4 * sizeof(int32_t));
    v->region = calloc(nt + 1, sizeof(int32_t));
    v->regions = calloc(1, sizeof(thx_region));
    if (!v->xyz || !v->tet || !v->region || !v->regions) abort();
    memcpy(v->xyz, xyz, nn * 3 * sizeof(double));
    memcpy(v->tet, tet, nt * 4 * sizeof(int32_t));
    v->n_regions = 1;
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "mean_thorax");
    v->regions[0].sigma[0] = v->regions[0].sigma[4] = v->regions[0].sigma[8] = 0.2;
    return v;
}

static void vol_add_tet(thx_volume *v, const int32_t q_in[4], int32_t region)
{
    int32_t q[4]; /* q_in may point into v->tet */
    memcpy(q, q_in, sizeof q);
    v->tet = realloc(v->tet, (v->n_tets + 1) * 4 * sizeof(int32_t));
    v->region = realloc(v->region, (v->n_tets + 1) * sizeof(int32_t));
    if (!v->tet || !v->region) abort();
    memcpy(v->tet + 4 * v->n_tets, q, 4 * sizeof(int32_t));
    v->region[v->n_tets] = region;
    v->n_tets++;
}

static int32_t vol_add_node(thx_volume *v, double x, double y, double z)
{
    v->xyz = realloc(v->xyz, (v->n_nodes + 1) * 3 * sizeof(double));
    if (!v->xyz) abort();
    v->xyz[3 * v->n_nodes] = x;
    v->xyz[3 * v->n_nodes + 1] = y;
    v->xyz[3 * v->n_nodes + 2] = z;
    return (int32_t)v->n_nodes++;
}

static void vol_remove_tet(thx_volume *v, size_t t)
{
    memmove(v->tet + 4 * t, v->tet + 4 * (t + 1), (v->n_tets - t - 1) * 4 * sizeof(int32_t));
    memmove(v->region + t, v->region + t + 1, (v->n_tets - t - 1) * sizeof(int32_t));
    v->n_tets--;
}

/* Drops nodes in no tetrahedron, renumbering the others (tables not kept). */
static void vol_drop_unused(thx_volume *v)
{
    int32_t *map = malloc((v->n_nodes + 1) * sizeof(int32_t));
    if (!map) abort();
    for (size_t g = 0; g < v->n_nodes; g++) map[g] = -1;
    for (size_t k = 0; k < 4 * v->n_tets; k++) map[v->tet[k]] = 0;
    size_t n = 0;
    for (size_t g = 0; g < v->n_nodes; g++)
        if (map[g] == 0) {
            memmove(v->xyz + 3 * n, v->xyz + 3 * g, 3 * sizeof(double));
            map[g] = (int32_t)n++;
        }
    for (size_t k = 0; k < 4 * v->n_tets; k++) v->tet[k] = map[v->tet[k]];
    v->n_nodes = n;
    free(map);
}

static int32_t add_region(thx_volume *v, const char *name)
{
    v->regions = realloc(v->regions, (v->n_regions + 1) * sizeof(thx_region));
    if (!v->regions) abort();
    memset(&v->regions[v->n_regions], 0, sizeof(thx_region));
    snprintf(v->regions[v->n_regions].name, sizeof v->regions[0].name, "%s", name);
    v->regions[v->n_regions].sigma[0] = v->regions[v->n_regions].sigma[4] = v->regions[v->n_regions].sigma[8] = 0.1;
    return (int32_t)v->n_regions++;
}

/* Unit cube's corner i at (i & 1, i >> 1 & 1, i >> 2 & 1) scaled into [lo, hi]^3. */
static void cube_corner(int i, double lo, double hi, double *p)
{
    p[0] = (i & 1) ? hi : lo;
    p[1] = (i & 2) ? hi : lo;
    p[2] = (i & 4) ? hi : lo;
}

/* The cube [lo, hi]^3 as a closed surface, counterclockwise seen from outside. */
static thx_surface *cube_surface(const char *name, thx_role role, double lo, double hi)
{
    static const int32_t tri[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                       {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, role, &s) != THX_OK) abort();
    s->n_nodes = 8;
    s->n_tris = 12;
    s->xyz = malloc(24 * sizeof(double));
    s->tri = malloc(36 * sizeof(int32_t));
    if (!s->xyz || !s->tri) abort();
    for (int i = 0; i < 8; i++) cube_corner(i, lo, hi, s->xyz + 3 * i);
    memcpy(s->tri, tri, sizeof tri);
    return s;
}

/* The unit cube in 5 tetrahedra (four corners cut off, one in the middle). */
static thx_volume *cube5(void)
{
    double xyz[24];
    for (int i = 0; i < 8; i++) cube_corner(i, 0.0, 1.0, xyz + 3 * i);
    int32_t tet[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
    for (int t = 0; t < 5; t++) fix_orientation(xyz, tet[t]);
    return vol_new(xyz, 8, &tet[0][0], 5);
}

/* The cube [0, n]^3 as n^3 unit cubes, 6 tetrahedra each (Kuhn/Freudenthal:
 * conforming across cubes), every tetrahedron in region 0. */
static thx_volume *kuhn_grid(int n)
{
    size_t m = (size_t)n + 1, nn = m * m * m, nt = 6 * (size_t)n * n * n;
    double *xyz = malloc(nn * 3 * sizeof(double));
    int32_t *tet = malloc(nt * 4 * sizeof(int32_t));
    if (!xyz || !tet) abort();
    for (size_t z = 0; z < m; z++)
        for (size_t y = 0; y < m; y++)
            for (size_t x = 0; x < m; x++) {
                size_t i = x + m * (y + m * z);
                xyz[3 * i] = (double)x;
                xyz[3 * i + 1] = (double)y;
                xyz[3 * i + 2] = (double)z;
            }
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    size_t t = 0;
    for (int z = 0; z < n; z++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {x, y, z};
                    int32_t *q = tet + 4 * t++;
                    for (int k = 0; k < 4; k++) {
                        if (k > 0) c[perm[p][k - 1]]++;
                        q[k] = (int32_t)((size_t)c[0] + m * ((size_t)c[1] + m * (size_t)c[2]));
                    }
                    fix_orientation(xyz, q);
                }
    thx_volume *v = vol_new(xyz, nn, tet, nt);
    free(xyz);
    free(tet);
    return v;
}

static thx_vec3 centroid(const thx_volume *v, size_t t)
{
    thx_vec3 c = thx_v3(0, 0, 0);
    for (int k = 0; k < 4; k++) {
        const double *p = v->xyz + 3 * (size_t)v->tet[4 * t + k];
        c = thx_v3_add(c, thx_v3(p[0], p[1], p[2]));
    }
    return thx_v3_scale(c, 0.25);
}

static int in_box(thx_vec3 c, double lo, double hi)
{
    return c.x > lo && c.x < hi && c.y > lo && c.y < hi && c.z > lo && c.z < hi;
}

static int cmp_key3(const void *x, const void *y)
{
    const int32_t *a = x, *b = y;
    for (int i = 0; i < 5; i++)
        if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* A model of the given surfaces (ownership taken). */
static thx_model *model_of(thx_surface **s, int n)
{
    thx_model *m = NULL;
    if (thx_model_create(ctx, &m) != THX_OK) abort();
    for (int i = 0; i < n; i++)
        if (thx_model_add_surface(ctx, m, &s[i]) != THX_OK) abort();
    return m;
}

/* The boundary of v (faces in one tetrahedron, outward) as a surface of its
 * own nodes: a model surface the mesh conforms to by construction. */
static thx_surface *boundary_surface(const thx_volume *v, const char *name, thx_role role)
{
    static const int vf[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    size_t nf = 4 * v->n_tets;
    int32_t(*key)[5] = malloc((nf + 1) * sizeof *key); /* sorted nodes, then tet, face */
    if (!key) abort();
    for (size_t t = 0; t < v->n_tets; t++)
        for (int f = 0; f < 4; f++) {
            int32_t *k = key[4 * t + (size_t)f];
            for (int j = 0; j < 3; j++) k[j] = v->tet[4 * t + vf[f][j]];
            for (int i = 1; i < 3; i++)
                for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
                    int32_t x = k[j];
                    k[j] = k[j - 1];
                    k[j - 1] = x;
                }
            k[3] = (int32_t)t;
            k[4] = f;
        }
    qsort(key, nf, sizeof *key, cmp_key3);
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, role, &s) != THX_OK) abort();
    int32_t *map = malloc((v->n_nodes + 1) * sizeof(int32_t));
    s->tri = malloc((3 * nf + 1) * sizeof(int32_t));
    s->xyz = malloc((3 * v->n_nodes + 1) * sizeof(double));
    if (!map || !s->tri || !s->xyz) abort();
    for (size_t g = 0; g < v->n_nodes; g++) map[g] = -1;
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && !memcmp(key[j], key[i], 3 * sizeof(int32_t))) j++;
        if (j == i + 1)
            for (int c = 0; c < 3; c++) {
                int32_t g = v->tet[4 * (size_t)key[i][3] + vf[key[i][4]][c]];
                if (map[g] < 0) {
                    map[g] = (int32_t)s->n_nodes;
                    memcpy(s->xyz + 3 * s->n_nodes++, v->xyz + 3 * (size_t)g, 3 * sizeof(double));
                }
                s->tri[3 * s->n_tris + (size_t)c] = map[g];
            }
        s->n_tris += j == i + 1;
        i = j;
    }
    free(map);
    free(key);
    return s;
}

/* Node tables: every surface node of m on the volume node at the same
 * coordinates (brute force; there must be one). */
static void link_nodes(thx_volume *v, const thx_model *m)
{
    if (v->surf_node)
        for (size_t s = 0; s < v->n_surfaces; s++) free(v->surf_node[s]);
    free(v->surf_node);
    free(v->surf_n_nodes);
    free(v->node_surf);
    free(v->node_snode);
    v->n_surfaces = m->n_surfaces;
    v->surf_n_nodes = calloc(m->n_surfaces + 1, sizeof(size_t));
    v->surf_node = calloc(m->n_surfaces + 1, sizeof(int32_t *));
    v->node_surf = malloc((v->n_nodes + 1) * sizeof(int32_t));
    v->node_snode = malloc((v->n_nodes + 1) * sizeof(int32_t));
    if (!v->surf_n_nodes || !v->surf_node || !v->node_surf || !v->node_snode) abort();
    for (size_t g = 0; g < v->n_nodes; g++) v->node_surf[g] = v->node_snode[g] = -1;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const thx_surface *ms = m->surf[s];
        v->surf_n_nodes[s] = ms->n_nodes;
        v->surf_node[s] = malloc((ms->n_nodes + 1) * sizeof(int32_t));
        if (!v->surf_node[s]) abort();
        for (size_t i = 0; i < ms->n_nodes; i++) {
            int32_t found = -1;
            for (size_t g = 0; g < v->n_nodes && found < 0; g++)
                if (!memcmp(v->xyz + 3 * g, ms->xyz + 3 * i, 3 * sizeof(double))) found = (int32_t)g;
            if (found < 0) abort();
            v->surf_node[s][i] = found;
            v->node_surf[found] = (int32_t)s;
            v->node_snode[found] = (int32_t)i;
        }
    }
}

/* Checks v into *r (a zeroed or earlier report: freed first). */
static unsigned run(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, thx_volume_report *r)
{
    thx_volume_report_free(r);
    thx_status st = thx_volume_check(ctx, v, m, o, r);
    if (st != THX_OK && st != THX_ECHECK) {
        fprintf(stderr, "thx_volume_check: %s: %s\n", thx_status_name(st), thx_ctx_message(ctx));
        tl_fail++;
    }
    CHECK((st == THX_OK) == (r->ok != 0));
    return r->failures;
}

static void show_reasons(const char *what, const thx_volume_report *r)
{
    for (size_t k = 0; k < r->n_reasons; k++) printf("  %s: %s\n", what, r->reasons[k]);
}

/* ---------- quality of single tetrahedra ---------- */

static void test_quality(void)
{
    double a[3] = {1, 1, 1}, b[3] = {1, -1, -1}, c[3] = {-1, 1, -1}, d[3] = {-1, -1, 1};
    double mn, mx, re, rr;
    thx_tet_quality(a, b, c, d, &mn, &mx, &re, &rr);
    CHECK_NEAR(mn, acos(1.0 / 3.0) * 180.0 / M_PI, 1e-9);
    CHECK_NEAR(mn, 70.528779365509308, 1e-9);
    CHECK_NEAR(mx, 70.528779365509308, 1e-9);
    CHECK_NEAR(re, sqrt(6.0) / 4.0, 1e-12);
    CHECK_NEAR(rr, 1.0, 1e-12);
    /* either orientation gives the same figures */
    thx_tet_quality(a, c, b, d, &mn, &mx, &re, &rr);
    CHECK_NEAR(mn, 70.528779365509308, 1e-9);
    CHECK_NEAR(re, sqrt(6.0) / 4.0, 1e-12);
    /* the corner tetrahedron of a cube: right angles at the origin, 54.7 deg at the far edges */
    double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    thx_tet_quality(o, x, y, z, &mn, &mx, &re, &rr);
    CHECK_NEAR(mx, 90.0, 1e-9);
    CHECK_NEAR(mn, acos(1.0 / sqrt(3.0)) * 180.0 / M_PI, 1e-9);
    CHECK_NEAR(re, (sqrt(3.0) / 2.0) / 1.0, 1e-12); /* circumradius sqrt(3)/2, shortest edge 1 */
    /* flat: four coplanar points */
    double f[3] = {0.3, 0.3, 0.0};
    thx_tet_quality(o, x, y, f, &mn, &mx, &re, &rr);
    CHECK(mn == 0.0 && mx == 180.0 && isinf(re) && rr == 0.0);
    /* a sliver: a flattened regular tetrahedron has tiny dihedral angles but no short edge */
    double s1[3] = {1, 1, 1e-3}, s2[3] = {1, -1, -1e-3}, s3[3] = {-1, 1, -1e-3}, s4[3] = {-1, -1, 1e-3};
    thx_tet_quality(s1, s2, s3, s4, &mn, &mx, &re, &rr);
    CHECK(mn < 1.0 && mx > 179.0 && rr < 0.01 && re < 1.0);

    /* in a mesh: the regular tetrahedron alone passes and reports the same */
    double xyz[12];
    memcpy(xyz, a, sizeof a);
    memcpy(xyz + 3, b, sizeof b);
    memcpy(xyz + 6, c, sizeof c);
    memcpy(xyz + 9, d, sizeof d);
    int32_t q[4] = {0, 1, 2, 3};
    fix_orientation(xyz, q);
    thx_volume *v = vol_new(xyz, 4, q, 1);
    thx_volume_report r = {0};
    CHECK(run(v, NULL, NULL, &r) == 0);
    CHECK_NEAR(r.min_dihedral, 70.528779365509308, 1e-9);
    CHECK_NEAR(r.max_radius_edge, 0.61237243569579452, 1e-12);
    CHECK_NEAR(r.min_radius_ratio, 1.0, 1e-12);
    CHECK_NEAR(r.tet_volume, 8.0 / 3.0, 1e-12);
    CHECK(r.dihedral_hist[THX_VCHECK_DIHEDRAL_BINS - 1] == 1);
    CHECK(r.radius_edge_hist[0] == 1);
    CHECK(r.n_boundary_faces == 4 && r.n_interior_faces == 0 && r.n_shells == 1 && r.n_cavities == 0);
    CHECK(r.boundary_checked && r.boundary.ok && r.boundary.volume > 0);
    /* a quality threshold turns the report into a failure */
    thx_volume_check_opts qo;
    thx_volume_check_opts_default(&qo);
    qo.max_radius_edge = 0.6;
    CHECK(run(v, NULL, &qo, &r) == THX_VCHECKF_QUALITY);
    qo.max_radius_edge = 0.0;
    qo.min_dihedral_deg = 71.0;
    CHECK(run(v, NULL, &qo, &r) == THX_VCHECKF_QUALITY);
    thx_volume_report_free(&r);
    thx_volume_destroy(&v);
}

/* ---------- clean meshes pass ---------- */

static void test_cube_passes(void)
{
    thx_volume_report r = {0};
    thx_volume *v = cube5();
    unsigned f = run(v, NULL, NULL, &r);
    CHECK(f == 0);
    show_reasons("cube5", &r);
    CHECK(r.n_faces == 16 && r.n_boundary_faces == 12 && r.n_interior_faces == 4);
    CHECK_NEAR(r.tet_volume, 1.0, 1e-14);
    CHECK(r.n_shells == 1 && r.n_cavities == 0 && r.n_voids == 0);
    CHECK(r.boundary.n_nodes == 8 && r.boundary.euler == 2 && r.boundary.n_components == 1);
    CHECK(!r.containment_checked && !r.node_tables_checked);
    CHECK(isnan(r.volume_rel_diff));

    /* with the cube as the outer surface (triangulated as the mesh's boundary) and node tables */
    thx_surface *s[1] = {boundary_surface(v, "torso", THX_ROLE_OUTER)};
    thx_model *m = model_of(s, 1);
    CHECK(thx_surface_volume(m->surf[0]) > 0.999);
    link_nodes(v, m);
    f = run(v, m, NULL, &r);
    CHECK(f == 0);
    show_reasons("cube5 + model", &r);
    CHECK(r.coverage_checked && r.n_surface_reports == 1 && r.surfaces[0].n_covered == 12);
    CHECK(r.n_interface_faces == 12 && r.n_faces_off_surfaces == 0 && r.n_uncovered_tris == 0);
    CHECK_NEAR(r.surfaces[0].covered_area, 6.0, 1e-14);
    CHECK(r.cells_checked && r.n_outside_region_tets == 0 && r.regions[0].cell == 0);
    CHECK(r.surfaces[0].parent == -1);
    CHECK(r.containment_checked && r.n_outside_tets == 0 && r.n_in_cavity_tets == 0);
    CHECK(r.node_tables_checked && r.n_table_mismatches == 0 && r.table_max_distance == 0.0);
    CHECK_NEAR(r.enclosed_volume, 1.0, 1e-14);
    CHECK(fabs(r.volume_rel_diff) < 1e-14);
    CHECK(r.n_boundary_nodes_off_surfaces == 0);
    CHECK(r.n_regions == 1 && !strcmp(r.regions[0].definition, "torso"));
    CHECK(fabs(r.regions[0].rel_diff) < 1e-14);
    thx_volume_destroy(&v);

    /* the same cube in 6 tetrahedra (Kuhn; its boundary diagonals are cube_surface's) */
    thx_model_destroy(&m);
    s[0] = cube_surface("torso", THX_ROLE_OUTER, 0.0, 1.0);
    m = model_of(s, 1);
    v = kuhn_grid(1);
    link_nodes(v, m);
    CHECK(run(v, m, NULL, &r) == 0);
    CHECK(r.n_tets == 6 && r.n_boundary_faces == 12 && r.n_interior_faces == 6);
    /* all six share the diagonal: each is a third of a cube-corner shape */
    CHECK_NEAR(r.min_dihedral, 45.0, 1e-9);
    CHECK_NEAR(r.max_dihedral, 90.0, 1e-9);
    thx_volume_destroy(&v);
    thx_volume_report_free(&r);
    thx_model_destroy(&m);
}

/* Random points in the unit cube plus its corners, tetrahedralized by
 * thx_delaunay3d, orientation swapped to right-handed. */
static thx_volume *delaunay_cube(size_t n, int32_t **nbrs_out)
{
    size_t nn = n + 8;
    double *xyz = malloc(nn * 3 * sizeof(double));
    if (!xyz) abort();
    for (int i = 0; i < 8; i++) cube_corner(i, 0.0, 1.0, xyz + 3 * i);
    for (size_t i = 8; i < nn; i++)
        for (int a = 0; a < 3; a++) xyz[3 * i + a] = 0.001 + 0.998 * urand();
    int32_t *tets = NULL, *nbrs = NULL;
    size_t nt = 0;
    if (thx_delaunay3d(ctx, xyz, nn, &tets, nbrs_out ? &nbrs : NULL, &nt, NULL) != THX_OK) {
        fprintf(stderr, "delaunay: %s\n", thx_ctx_message(ctx));
        abort();
    }
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = x;
    }
    thx_volume *v = vol_new(xyz, nn, tets, nt);
    free(xyz);
    free(tets);
    if (nbrs_out) *nbrs_out = nbrs; /* entries 2 and 3 now belong to the swapped nodes' opposite faces */
    return v;
}

static void test_delaunay_passes(void)
{
    thx_volume_report r = {0};
    thx_volume *v = delaunay_cube(2000, NULL);
    thx_surface *s[1] = {boundary_surface(v, "torso", THX_ROLE_OUTER)};
    thx_model *m = model_of(s, 1);
    link_nodes(v, m);
    /* random points make slivers: the dihedral limit is not what this tests */
    thx_volume_check_opts no_q;
    thx_volume_check_opts_default(&no_q);
    no_q.min_dihedral_deg = 0.0;
    CHECK(run(v, m, NULL, &r) == THX_VCHECKF_QUALITY && r.min_dihedral < 1.0);
    CHECK(run(v, m, &no_q, &r) == 0);
    show_reasons("delaunay", &r);
    CHECK(r.n_tets > 10000 && r.n_nodes == 2008);
    CHECK(fabs(r.volume_rel_diff) < 1e-12);
    CHECK(r.n_boundary_faces == 12 && r.n_shells == 1 && r.n_cavities == 0);
    CHECK(r.n_nonconforming_faces == 0 && r.n_overlapping_faces == 0);
    CHECK(4 * r.n_tets == 2 * r.n_interior_faces + r.n_boundary_faces);
    CHECK(r.n_outside_tets == 0 && r.n_undecided_tets == 0);
    size_t h1 = 0, h2 = 0;
    for (int b = 0; b < THX_VCHECK_DIHEDRAL_BINS; b++) h1 += r.dihedral_hist[b];
    for (int b = 0; b < THX_VCHECK_RADIUS_EDGE_BINS; b++) h2 += r.radius_edge_hist[b];
    CHECK(h1 == r.n_tets && h2 == r.n_tets);
    CHECK(r.n_worst_dihedral == THX_VCHECK_MAX_WORST && r.worst_dihedral[0].value == r.min_dihedral);
    CHECK(r.worst_dihedral[0].tet == r.min_dihedral_tet);
    CHECK(r.worst_radius_edge[0].value == r.max_radius_edge);
    for (int k = 1; k < THX_VCHECK_MAX_WORST; k++) {
        CHECK(r.worst_dihedral[k].value >= r.worst_dihedral[k - 1].value);
        CHECK(r.worst_radius_edge[k].value <= r.worst_radius_edge[k - 1].value);
    }
    CHECK(r.max_radius_edge >= r.mean_radius_edge && r.mean_radius_edge >= 0.6123);
    CHECK(r.min_dihedral > 0.0 && r.min_dihedral < 70.53);
    CHECK_NEAR(r.regions[0].volume, 1.0, 1e-12);

    /* the JSON form: parses back, 1-based, figures match; deterministic in the thread count */
    cJSON *j = thx_volume_report_json(ctx, &r);
    CHECK(j != NULL);
    char *text = cJSON_PrintUnformatted(j);
    cJSON *p = cJSON_Parse(text);
    CHECK(p != NULL);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(p, "ok")));
    CHECK(cJSON_GetObjectItem(p, "index_base")->valuedouble == 1);
    CHECK(cJSON_GetObjectItem(p, "tetrahedra")->valuedouble == (double)r.n_tets);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(p, "conforming")) && cJSON_IsTrue(cJSON_GetObjectItem(p, "boundary_closed")));
    cJSON *co = cJSON_GetObjectItem(p, "conformity");
    CHECK(cJSON_GetObjectItem(co, "shells")->valuedouble == 1 && cJSON_GetObjectItem(co, "voids")->valuedouble == 0);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(cJSON_GetObjectItem(co, "boundary"), "closed")));
    cJSON *q = cJSON_GetObjectItem(p, "quality");
    cJSON *wd = cJSON_GetObjectItem(cJSON_GetObjectItem(q, "dihedral"), "worst");
    CHECK(cJSON_GetArraySize(wd) == THX_VCHECK_MAX_WORST);
    CHECK(cJSON_GetArrayItem(cJSON_GetArrayItem(wd, 0), 0)->valuedouble == (double)r.min_dihedral_tet + 1);
    cJSON *hc = cJSON_GetObjectItem(cJSON_GetObjectItem(cJSON_GetObjectItem(q, "radius_edge"), "histogram"), "counts");
    CHECK(cJSON_GetArraySize(hc) == THX_VCHECK_RADIUS_EDGE_BINS);
    cJSON *vo = cJSON_GetObjectItem(p, "volume");
    CHECK(fabs(cJSON_GetObjectItem(vo, "rel_diff")->valuedouble) < 1e-12);
    CHECK(!strcmp(cJSON_GetObjectItem(vo, "definition")->valuestring, "torso"));
    cJSON *ct = cJSON_GetObjectItem(p, "containment");
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(ct, "outer_surfaces")) == 1);
#ifdef _OPENMP
    int threads = omp_get_max_threads();
    omp_set_num_threads(threads > 1 ? 1 : 3); /* another thread count than the first run's */
    thx_volume_report r1 = {0};
    run(v, m, &no_q, &r1);
    cJSON *j1 = thx_volume_report_json(ctx, &r1);
    char *text1 = cJSON_PrintUnformatted(j1);
    CHECK(!strcmp(text, text1));
    omp_set_num_threads(threads);
    free(text1);
    cJSON_Delete(j1);
    thx_volume_report_free(&r1);
#endif
    free(text);
    cJSON_Delete(p);
    cJSON_Delete(j);
    thx_volume_report_free(&r);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
}

/* ---------- every defect, planted once ---------- */

static void test_validity_failures(void)
{
    thx_volume_report r = {0};
    /* inverted */
    thx_volume *v = cube5();
    int32_t x = v->tet[1];
    v->tet[1] = v->tet[2];
    v->tet[2] = x;
    unsigned f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_INVERTED);
    CHECK(r.n_inverted_tets == 1 && r.ex_inverted_tet == 0 && r.n_flat_tets == 0);
    CHECK(r.n_overlapping_faces > 0); /* its faces now face the way of its neighbours' */
    CHECK(strstr(r.reasons[0], "inverted: 1 tetrahedra") != NULL);
    thx_volume_destroy(&v);

    /* duplicated */
    v = cube5();
    vol_add_tet(v, v->tet + 4 * 2, 0);
    f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_DUPLICATE_TET);
    CHECK(r.n_duplicate_tets == 1 && r.ex_duplicate_tet[0] == 2 && r.ex_duplicate_tet[1] == 5);
    CHECK(f & THX_VCHECKF_NONCONFORMING);
    thx_volume_destroy(&v);

    /* a repeated node; a flat tetrahedron */
    v = cube5();
    int32_t rep[4] = {0, 1, 1, 2};
    vol_add_tet(v, rep, 0);
    f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_REPEATED_NODE);
    CHECK(r.n_repeated_node_tets == 1 && r.ex_repeated_node_tet == 5);
    thx_volume_destroy(&v);
    v = cube5();
    int32_t flat[4] = {0, 1, 3, 2}; /* the bottom face's four corners */
    vol_add_tet(v, flat, 0);
    f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_FLAT);
    CHECK(r.n_flat_tets == 1 && r.n_inverted_tets == 0);
    thx_volume_destroy(&v);

    /* bad index: nothing else is checked */
    v = cube5();
    v->tet[4 * 3 + 2] = 8;
    f = run(v, NULL, NULL, &r);
    CHECK(f == THX_VCHECKF_BAD_INDEX && r.n_bad_index_tets == 1 && r.ex_bad_index_tet == 3);
    v->tet[4 * 3 + 2] = -1;
    CHECK(run(v, NULL, NULL, &r) == THX_VCHECKF_BAD_INDEX);
    thx_volume_destroy(&v);

    /* bad region */
    v = cube5();
    v->region[4] = 1;
    CHECK(run(v, NULL, NULL, &r) == THX_VCHECKF_BAD_REGION && r.ex_bad_region_tet == 4);
    thx_volume_destroy(&v);

    /* an unused node, coincident with a used one */
    v = cube5();
    vol_add_node(v, 1.0, 1.0, 1.0);
    f = run(v, NULL, NULL, &r);
    CHECK(f == (THX_VCHECKF_UNUSED | THX_VCHECKF_DUPLICATE_NODE));
    CHECK(r.n_unused_nodes == 1 && r.ex_unused_node == 8);
    CHECK(r.n_duplicate_nodes == 1 && r.ex_duplicate_node[0] == 7 && r.ex_duplicate_node[1] == 8);
    thx_volume_destroy(&v);

    /* empty */
    v = cube5();
    v->n_tets = 0;
    CHECK(run(v, NULL, NULL, &r) == THX_VCHECKF_EMPTY);
    thx_volume_destroy(&v);
    thx_volume_report_free(&r);
}

static void test_conformity_failures(void)
{
    thx_volume_report r = {0};
    /* a face in three tetrahedra: abc with one apex above and two below */
    double xyz[6 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.2, 0.2, -1, 0.3, 0.3, -2};
    int32_t tet[3][4] = {{0, 1, 2, 3}, {0, 1, 2, 4}, {0, 1, 2, 5}};
    for (int t = 0; t < 3; t++) fix_orientation(xyz, tet[t]);
    thx_volume *v = vol_new(xyz, 6, &tet[0][0], 3);
    unsigned f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_NONCONFORMING);
    CHECK(r.n_nonconforming_faces == 1);
    CHECK(r.ex_nonconforming_face[0] == 0 && r.ex_nonconforming_face[1] == 1 && r.ex_nonconforming_face[2] == 2);
    show_reasons("face in 3", &r);
    thx_volume_destroy(&v);

    /* two tetrahedra on the same side of their shared face (overlap) */
    double xyz2[5 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.3, 0.2, 2};
    int32_t tet2[2][4] = {{0, 1, 2, 3}, {0, 1, 2, 4}};
    for (int t = 0; t < 2; t++) fix_orientation(xyz2, tet2[t]);
    v = vol_new(xyz2, 5, &tet2[0][0], 2);
    f = run(v, NULL, NULL, &r);
    CHECK(f & THX_VCHECKF_NONCONFORMING);
    CHECK(r.n_overlapping_faces == 1 && r.n_nonconforming_faces == 0);
    CHECK(f & THX_VCHECKF_BOUNDARY); /* the boundary faces cross each other */
    thx_volume_destroy(&v);

    /* a hanging node: one cube split in 5, its neighbour in 5 mirrored, so the
     * shared square's diagonals differ (a non-conforming interface) */
    thx_volume *a = cube5();
    double xyzb[12 * 3];
    memcpy(xyzb, a->xyz, 8 * 3 * sizeof(double));
    for (int i = 0; i < 4; i++) { /* the second cube's far corners, x = 2 */
        cube_corner(2 * i + 1, 0.0, 1.0, xyzb + 3 * (8 + i));
        xyzb[3 * (8 + i)] += 1.0;
    }
    /* the second cube shares the face x = 1 (nodes 1, 3, 5, 7) of the first */
    int32_t idx[8] = {1, 8, 3, 9, 5, 10, 7, 11};
    int32_t tb[10][4];
    memcpy(tb, a->tet, 5 * 4 * sizeof(int32_t));
    int32_t same[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
    for (int t = 0; t < 5; t++)
        for (int k = 0; k < 4; k++) tb[5 + t][k] = idx[same[t][k]];
    for (int t = 5; t < 10; t++) fix_orientation(xyzb, tb[t]);
    v = vol_new(xyzb, 12, &tb[0][0], 10);
    thx_volume_destroy(&a);
    f = run(v, NULL, NULL, &r);
    /* cube5 splits its x = 1 face along 1-7 (a corner tet's face) and the
     * shifted copy splits its x = 1 face... the mirrored diagonals leave 4
     * boundary faces inside the mesh, crossing each other */
    CHECK(f == THX_VCHECKF_BOUNDARY);
    CHECK(r.boundary.n_intersecting_pairs > 0 || r.boundary.n_nonmanifold_edges > 0);
    show_reasons("nonconforming interface", &r);
    thx_volume_destroy(&v);
    thx_volume_report_free(&r);
}

static void test_void_and_missing(void)
{
    thx_volume_report r = {0};
    int32_t *nbrs = NULL;
    thx_volume *v = delaunay_cube(300, &nbrs);
    /* an interior tetrahedron none of whose nodes is a corner (the hull) */
    size_t pick = v->n_tets;
    for (size_t t = 0; t < v->n_tets && pick == v->n_tets; t++) {
        int ok = 1;
        for (int k = 0; k < 4; k++) ok &= v->tet[4 * t + k] >= 8 && nbrs[4 * t + k] >= 0;
        if (ok) pick = t;
    }
    free(nbrs);
    CHECK(pick < v->n_tets);
    vol_remove_tet(v, pick);
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);
    o.min_dihedral_deg = 0.0; /* random points: slivers */
    unsigned f = run(v, NULL, &o, &r);
    CHECK(f == THX_VCHECKF_COMPONENTS);
    CHECK(r.n_shells == 1 && r.n_cavities == 1 && r.n_voids == 1 && r.expected_cavities == 0);
    CHECK(r.boundary.ok && r.n_boundary_faces == 12 + 4);
    CHECK(r.n_reasons == 1 && strstr(r.reasons[0], "1 void") != NULL);
    show_reasons("void", &r);
    /* said to be expected: passes */
    o.expected_cavities = 1;
    CHECK(run(v, NULL, &o, &r) == 0);
    o.expected_cavities = -1;
    thx_volume_destroy(&v);

    /* a missing tetrahedron at the boundary: still one closed shell, but
     * the volume is 1/6 short of the surface's: only the volume fails */
    v = kuhn_grid(1);
    thx_surface *s[1] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 1.0)};
    thx_model *m = model_of(s, 1);
    link_nodes(v, m);
    vol_remove_tet(v, 2);
    f = run(v, m, NULL, &r);
    /* and the surface triangles where it was are not covered, its inner faces are on no surface */
    CHECK(f == (THX_VCHECKF_VOLUME | THX_VCHECKF_REGION_VOLUME | THX_VCHECKF_COVERAGE));
    CHECK(r.n_uncovered_tris == 2 && r.n_faces_off_surfaces == 2);
    CHECK_NEAR(r.volume_rel_diff, -1.0 / 6.0, 1e-12);
    CHECK(r.n_shells == 1 && r.n_cavities == 0 && r.boundary.ok);
    show_reasons("missing boundary tet", &r);
    o.volume_tol = 0.2;
    o.region_volume_tol = 0.2;
    o.coverage_tol = 1.0; /* the uncovered triangles are not covered at all: still fail */
    CHECK(run(v, m, &o, &r) == THX_VCHECKF_COVERAGE);
    o.volume_tol = o.region_volume_tol = 0.0; /* report only */
    CHECK(run(v, m, &o, &r) == THX_VCHECKF_COVERAGE);
    CHECK_NEAR(r.volume_rel_diff, -1.0 / 6.0, 1e-12);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
    thx_volume_report_free(&r);
}

/* A mesh whose volume is 1.5% short of the outer surface's: a 4x4x4 grid
 * against a surface slightly larger than it (no node tables: the surface's
 * corners are not mesh nodes). */
static void test_volume_difference(void)
{
    thx_volume_report r = {0};
    thx_volume *v = kuhn_grid(4);
    double h = 4.0 * pow(1.0 / (1.0 - 0.015), 1.0 / 3.0);
    thx_surface *s[1] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, h)};
    thx_model *m = model_of(s, 1);
    v->n_surfaces = 0;
    /* tables present but empty: the model has a surface the volume has no table for */
    unsigned f = run(v, m, NULL, &r);
    CHECK(f & THX_VCHECKF_VOLUME);
    CHECK_NEAR(r.volume_rel_diff, -0.015, 1e-12);
    CHECK(f & THX_VCHECKF_NODE_TABLE);
    CHECK(r.n_table_size_errors >= 1);
    /* 0.5 % short passes */
    thx_surface_destroy(&m->surf[0]);
    m->surf[0] = cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0 * pow(1.0 / (1.0 - 0.005), 1.0 / 3.0));
    f = run(v, m, NULL, &r);
    CHECK(!(f & THX_VCHECKF_VOLUME));
    CHECK_NEAR(r.volume_rel_diff, -0.005, 1e-12);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
    thx_volume_report_free(&r);
}

static void test_containment_and_tables(void)
{
    thx_volume_report r = {0};
    thx_surface *s[1] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 1.0)};
    thx_model *m = model_of(s, 1);

    /* a tetrahedron outside the outer surface */
    thx_volume *v = kuhn_grid(1);
    int32_t q[4];
    for (int k = 0; k < 4; k++) q[k] = vol_add_node(v, 3.0 + (k == 1), 0.5 + (k == 2), 0.5 + (k == 3));
    fix_orientation(v->xyz, q);
    vol_add_tet(v, q, 0);
    link_nodes(v, m);
    unsigned f = run(v, m, NULL, &r);
    CHECK(f & THX_VCHECKF_CONTAINMENT);
    CHECK(r.n_outside_tets == 1 && r.ex_outside_tet == 6 && r.n_in_cavity_tets == 0);
    CHECK(f & THX_VCHECKF_COMPONENTS); /* two shells */
    CHECK(r.n_shells == 2);
    CHECK(r.n_boundary_nodes_off_surfaces == 4);
    show_reasons("outside", &r);
    thx_volume_destroy(&v);

    /* a node table pointing to a wrong node */
    v = kuhn_grid(1);
    link_nodes(v, m);
    v->surf_node[0][3] = v->surf_node[0][4];
    f = run(v, m, NULL, &r);
    CHECK(f == THX_VCHECKF_NODE_TABLE);
    CHECK(r.n_table_mismatches == 1 && r.ex_table_surface == 0 && r.ex_table_node == 3);
    CHECK(r.n_table_backlink_errors >= 1);
    CHECK_NEAR(r.table_max_distance, sqrt(3.0), 1e-12); /* corner (1,1,0) on node (0,0,1) */
    show_reasons("node table", &r);
    /* a volume node that claims a surface node that does not claim it */
    link_nodes(v, m);
    v->node_snode[v->surf_node[0][5]] = 6;
    f = run(v, m, NULL, &r);
    CHECK(f == THX_VCHECKF_NODE_TABLE && r.n_table_backlink_errors == 2 && r.n_table_mismatches == 0);
    /* out of range */
    link_nodes(v, m);
    v->surf_node[0][0] = 99;
    f = run(v, m, NULL, &r);
    CHECK(f == THX_VCHECKF_NODE_TABLE && r.n_table_bad_entries == 1);
    /* within node_tol (files carry 6 decimals): still fine */
    link_nodes(v, m);
    m->surf[0]->xyz[3 * 7] += 4e-7;
    CHECK(run(v, m, NULL, &r) == 0);
    CHECK(r.table_max_distance > 0.0 && r.table_max_distance < 1e-6);
    m->surf[0]->xyz[3 * 7] -= 4e-7;
    /* no tables at all while the model has surfaces */
    thx_volume_destroy(&v);
    v = kuhn_grid(1);
    f = run(v, m, NULL, &r);
    CHECK(f == THX_VCHECKF_NODE_TABLE);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
    thx_volume_report_free(&r);
}

/* 4x4x4 grid with an inner cube [1,3]^3. */
static void test_regions_and_heart(void)
{
    thx_volume_report r = {0};
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);

    /* lung_l inside the muscle-less thorax */
    {
        thx_volume *v = kuhn_grid(4);
        int32_t lung = add_region(v, "lung_l");
        for (size_t t = 0; t < v->n_tets; t++)
            if (in_box(centroid(v, t), 1.0, 3.0)) v->region[t] = lung;
        thx_surface *s[2] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0),
                             cube_surface("lung_l", THX_ROLE_LUNG, 1.0, 3.0)};
        thx_model *m = model_of(s, 2);
        link_nodes(v, m);
        o.region_volume_tol = 1e-9;
        CHECK(run(v, m, &o, &r) == 0);
        show_reasons("lung", &r);
        CHECK(r.n_regions == 2);
        CHECK_NEAR(r.regions[0].volume, 56.0, 1e-12);
        CHECK_NEAR(r.regions[0].expected, 56.0, 1e-12);
        CHECK(!strcmp(r.regions[0].definition, "torso - lung_l"));
        CHECK_NEAR(r.regions[1].volume, 8.0, 1e-12);
        CHECK(!strcmp(r.regions[1].definition, "lung_l"));
        CHECK(r.regions[1].n_tets == 48);
        CHECK(r.n_boundary_nodes_off_surfaces == 98 - 8); /* the outer grid nodes not on the 8-node torso */
        /* four tetrahedra of the lung labelled mean_thorax: both regions off by 4/6 mm^3 */
        int moved = 0;
        for (size_t t = 0; t < v->n_tets && moved < 4; t++)
            if (v->region[t] == lung) {
                v->region[t] = 0;
                moved++;
            }
        /* ... and in the lung's cell, which holds lung_l; the lung surface is no longer all interface */
        unsigned f = run(v, m, &o, &r);
        CHECK(f == (THX_VCHECKF_REGION_VOLUME | THX_VCHECKF_REGION_CELLS | THX_VCHECKF_COVERAGE));
        CHECK(!r.regions[0].ok && !r.regions[1].ok);
        CHECK_NEAR(r.regions[1].rel_diff, -(4.0 / 6.0) / 8.0, 1e-12);
        CHECK(r.n_outside_region_tets == 4 && r.regions[0].n_outside == 4 && r.regions[1].n_outside == 0);
        CHECK(r.regions[0].ex_outside_cell == 1 && r.regions[0].cell == 0 && r.regions[1].cell == 1);
        show_reasons("lung mislabelled", &r);
        int said = 0;
        for (size_t k = 0; k < r.n_reasons; k++)
            said |= strstr(r.reasons[k], "region \"mean_thorax\": 4 of 340 tetrahedra lie inside lung_l, which holds "
                                         "region \"lung_l\"") != NULL;
        CHECK(said);
        o.region_volume_tol = 0.0; /* volumes report only: the cells and the coverage still fail */
        CHECK(run(v, m, &o, &r) == (THX_VCHECKF_REGION_CELLS | THX_VCHECKF_COVERAGE));
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    /* fat: the layer between the outer and the fat surface; inside it, mean_thorax */
    {
        thx_volume *v = kuhn_grid(4);
        int32_t fat = add_region(v, "fat");
        for (size_t t = 0; t < v->n_tets; t++)
            if (!in_box(centroid(v, t), 1.0, 3.0)) v->region[t] = fat;
        thx_surface *s[2] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0),
                             cube_surface("fat", THX_ROLE_FAT, 1.0, 3.0)};
        thx_model *m = model_of(s, 2);
        link_nodes(v, m);
        o.region_volume_tol = 1e-9;
        CHECK(run(v, m, &o, &r) == 0);
        CHECK(!strcmp(r.regions[1].definition, "torso - fat") && fabs(r.regions[1].rel_diff) < 1e-12);
        CHECK(!strcmp(r.regions[0].definition, "fat") && fabs(r.regions[0].rel_diff) < 1e-12);
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    /* the heart excluded: no tetrahedra inside it, a cavity expected */
    {
        thx_volume *v = kuhn_grid(4);
        for (size_t t = v->n_tets; t-- > 0;)
            if (in_box(centroid(v, t), 1.0, 3.0)) vol_remove_tet(v, t);
        vol_drop_unused(v); /* the centre node */
        thx_surface *s[2] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0),
                             cube_surface("heart", THX_ROLE_HEART, 1.0, 3.0)};
        thx_model *m = model_of(s, 2);
        link_nodes(v, m);
        CHECK(run(v, m, &o, &r) == 0);
        show_reasons("heart excluded", &r);
        CHECK(r.n_excluded_hearts == 1 && !strcmp(r.excluded_names, "heart"));
        CHECK(r.n_shells == 1 && r.n_cavities == 1 && r.expected_cavities == 1 && r.n_voids == 0);
        CHECK_NEAR(r.enclosed_volume, 56.0, 1e-12);
        CHECK(!strcmp(r.volume_definition, "torso - heart"));
        CHECK(!strcmp(r.regions[0].definition, "torso - heart") && fabs(r.regions[0].rel_diff) < 1e-12);
        CHECK(r.n_boundary_nodes_off_surfaces == (98 - 8) + (26 - 8));
        thx_volume_destroy(&v);

        /* tetrahedra inside the excluded heart */
        v = kuhn_grid(4);
        link_nodes(v, m);
        unsigned f = run(v, m, &o, &r);
        CHECK(f == (THX_VCHECKF_CONTAINMENT | THX_VCHECKF_VOLUME | THX_VCHECKF_COMPONENTS | THX_VCHECKF_REGION_VOLUME |
                    THX_VCHECKF_COVERAGE));
        CHECK(r.surfaces[1].n_covered == 0 && r.surfaces[0].n_covered == 12); /* the heart is no interface */
        CHECK(r.n_in_cavity_tets == 48 && r.n_outside_tets == 0);
        CHECK_NEAR(r.volume_rel_diff, 8.0 / 56.0, 1e-12);
        show_reasons("heart filled", &r);

        /* the same mesh with a heart region: nothing excluded, passes */
        int32_t heart = add_region(v, "heart");
        for (size_t t = 0; t < v->n_tets; t++)
            if (in_box(centroid(v, t), 1.0, 3.0)) v->region[t] = heart;
        CHECK(run(v, m, &o, &r) == 0);
        CHECK(r.n_excluded_hearts == 0 && r.expected_cavities == 0);
        CHECK_NEAR(r.enclosed_volume, 64.0, 1e-12);
        CHECK(!strcmp(r.regions[1].definition, "heart") && fabs(r.regions[1].rel_diff) < 1e-12);
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    thx_volume_report_free(&r);
}

/* Steiner records for the boundary nodes of v that are no node of surface s
 * of m: the triangle of s each lies on (brute force), its barycentric coordinates. */
static void add_steiner(thx_volume *v, const thx_model *m, size_t s)
{
    const thx_surface *su = m->surf[s];
    for (size_t g = 0; g < v->n_nodes; g++) {
        if (v->node_surf[g] >= 0) continue;
        const double *p = v->xyz + 3 * g;
        for (size_t t = 0; t < su->n_tris; t++) {
            const int32_t *c = su->tri + 3 * t;
            const double *a = su->xyz + 3 * (size_t)c[0], *b = su->xyz + 3 * (size_t)c[1], *d = su->xyz + 3 * (size_t)c[2];
            double e1[3], e2[3], w[3], n[3];
            for (int k = 0; k < 3; k++) {
                e1[k] = b[k] - a[k];
                e2[k] = d[k] - a[k];
                w[k] = p[k] - a[k];
            }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
            if (fabs(n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) > 1e-12 * sqrt(nn)) continue;
            /* barycentric by areas: (w x e2) . n / |n|^2 and (e1 x w) . n / |n|^2 */
            double b1 = ((w[1] * e2[2] - w[2] * e2[1]) * n[0] + (w[2] * e2[0] - w[0] * e2[2]) * n[1] +
                         (w[0] * e2[1] - w[1] * e2[0]) * n[2]) / nn;
            double b2 = ((e1[1] * w[2] - e1[2] * w[1]) * n[0] + (e1[2] * w[0] - e1[0] * w[2]) * n[1] +
                         (e1[0] * w[1] - e1[1] * w[0]) * n[2]) / nn;
            if (b1 < -1e-12 || b2 < -1e-12 || b1 + b2 > 1 + 1e-12) continue;
            v->steiner = realloc(v->steiner, (v->n_steiner + 1) * sizeof *v->steiner);
            if (!v->steiner) abort();
            thx_steiner *r = &v->steiner[v->n_steiner++];
            r->node = (int32_t)g;
            r->surf = (int32_t)s;
            r->tri = (int32_t)t;
            r->bary[0] = 1.0 - b1 - b2;
            r->bary[1] = b1;
            r->bary[2] = b2;
            break;
        }
    }
}

/* Coverage: surface triangles that are not unions of mesh faces, faces off
 * the surfaces, the rounding tolerance; Steiner records. */
static void test_coverage_and_steiner(void)
{
    thx_volume_report r = {0};
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);
    /* cube5's boundary squares are split along the other diagonals than the
     * surface's: every face straddles two surface triangles */
    {
        thx_volume *v = cube5();
        thx_surface *s[1] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 1.0)};
        thx_model *m = model_of(s, 1);
        link_nodes(v, m);
        unsigned f = run(v, m, NULL, &r);
        CHECK(f == THX_VCHECKF_COVERAGE);
        CHECK(r.n_interface_faces == 12 && r.n_faces_off_surfaces == 6 && r.n_uncovered_tris == 6);
        CHECK(r.surfaces[0].n_covered == 6 && fabs(r.surfaces[0].share - 0.5) < 1e-15);
        CHECK(r.surfaces[0].ex_covered_share == 0.0);
        CHECK(strstr(r.reasons[0], "coverage: surface \"torso\": 6 of 12 triangles not covered") != NULL);
        CHECK(strstr(r.reasons[1], "6 faces between regions or on the boundary lie on no surface triangle") != NULL);
        show_reasons("diagonals", &r);
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    /* a lung cube inside the grid; the inner nodes moved by up to 5e-7 mm (6-decimal
     * rounding) still cover; one torso grid node 2e-5 mm off the plane does not */
    {
        thx_volume *v = kuhn_grid(4);
        int32_t lung = add_region(v, "lung_l");
        for (size_t t = 0; t < v->n_tets; t++)
            if (in_box(centroid(v, t), 1.0, 3.0)) v->region[t] = lung;
        thx_surface *s[2] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0),
                             cube_surface("lung_l", THX_ROLE_LUNG, 1.0, 3.0)};
        thx_model *m = model_of(s, 2);
        link_nodes(v, m);
        CHECK(run(v, m, NULL, &r) == 0);
        CHECK(r.n_interface_faces == 16 * 6 * 2 + 4 * 6 * 2 && r.n_uncovered_tris == 0);
        CHECK(r.surfaces[1].parent == 0 && r.surfaces[0].parent == -1);
        for (size_t g = 0; g < v->n_nodes; g++)
            if (v->node_surf[g] < 0)
                for (int a = 0; a < 3; a++) v->xyz[3 * g + a] += (urand() - 0.5) * 1e-6;
        CHECK(run(v, m, NULL, &r) == 0);
        show_reasons("rounded", &r);
        size_t g0 = v->n_nodes; /* a grid node on the plane x = 0, inside the face */
        for (size_t g = 0; g < v->n_nodes; g++)
            if (v->node_surf[g] < 0 && fabs(v->xyz[3 * g]) < 1e-5 && v->xyz[3 * g + 1] > 1.5 && v->xyz[3 * g + 1] < 2.5 &&
                v->xyz[3 * g + 2] > 1.5 && v->xyz[3 * g + 2] < 2.5)
                g0 = g;
        CHECK(g0 < v->n_nodes);
        v->xyz[3 * g0] = -2e-5;
        unsigned f = run(v, m, NULL, &r);
        CHECK(f == THX_VCHECKF_COVERAGE);
        CHECK(r.n_faces_off_surfaces == 6 && r.n_uncovered_tris >= 1); /* the faces around the node */
        show_reasons("off by 2e-5", &r);
        /* a looser node_tol (0.1 mm) takes them: within tolerance */
        o.node_tol = 1e-4;
        CHECK(run(v, m, &o, &r) == 0);
        o.node_tol = 1e-5;
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    /* Steiner records: the torso's grid nodes are on its triangles */
    {
        thx_volume *v = kuhn_grid(4);
        thx_surface *s[1] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 4.0)};
        thx_model *m = model_of(s, 1);
        link_nodes(v, m);
        CHECK(run(v, m, NULL, &r) == 0 && r.n_boundary_nodes_off_surfaces == 98 - 8);
        add_steiner(v, m, 0);
        CHECK(v->n_steiner == 98 - 8);
        CHECK(run(v, m, NULL, &r) == 0);
        CHECK(r.n_steiner == 90 && r.surfaces[0].n_steiner == 90 && r.steiner_max_distance < 1e-14);
        CHECK(r.n_boundary_nodes_off_surfaces == 0); /* Steiner nodes are on the surface */
        /* a record whose coordinates point elsewhere */
        v->steiner[17].bary[0] -= 1e-3;
        v->steiner[17].bary[1] += 1e-3;
        unsigned f = run(v, m, NULL, &r);
        CHECK(f == THX_VCHECKF_NODE_TABLE && r.n_steiner_mismatches == 1 && r.ex_steiner == 17);
        CHECK(r.steiner_max_distance > 1e-3);
        CHECK(strstr(r.reasons[0], "Steiner nodes: 0 records out of range or on a surface node, 1 nodes farther") != NULL);
        show_reasons("Steiner", &r);
        v->steiner[17].bary[0] += 1e-3;
        v->steiner[17].bary[1] -= 1e-3;
        /* out of range, and a surface node named as a Steiner node */
        v->steiner[3].tri = 12;
        v->steiner[5].node = v->surf_node[0][2];
        f = run(v, m, NULL, &r);
        CHECK(f == THX_VCHECKF_NODE_TABLE && r.n_steiner_bad == 2 && r.ex_steiner == 3);
        thx_volume_destroy(&v);
        thx_model_destroy(&m);
    }
    thx_volume_report_free(&r);
}

/* Cells: one region per cell between the surfaces; a region may fill several. */
static void test_region_cells(void)
{
    thx_volume_report r = {0};
    thx_volume *v = kuhn_grid(6);
    int32_t lungs = add_region(v, "lungs");
    for (size_t t = 0; t < v->n_tets; t++) {
        thx_vec3 c = centroid(v, t);
        if (in_box(c, 1.0, 2.0) || in_box(c, 4.0, 5.0)) v->region[t] = lungs;
    }
    thx_surface *s[3] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 6.0), cube_surface("lung_r", THX_ROLE_LUNG, 1.0, 2.0),
                         cube_surface("lung_l", THX_ROLE_LUNG, 4.0, 5.0)};
    thx_model *m = model_of(s, 3);
    link_nodes(v, m);
    CHECK(run(v, m, NULL, &r) == 0);
    show_reasons("two lungs", &r);
    CHECK(r.cells_checked && r.n_outside_region_tets == 0);
    CHECK(!strcmp(r.regions[1].definition, "lung_r + lung_l") && fabs(r.regions[1].rel_diff) < 1e-12);
    CHECK(!strcmp(r.regions[0].definition, "torso - lung_r - lung_l") && fabs(r.regions[0].rel_diff) < 1e-12);
    CHECK(r.regions[0].cell == 0 && r.regions[1].cell == 1);
    /* one tetrahedron next to lung_r labelled "lungs": outside its region */
    size_t moved = v->n_tets;
    for (size_t t = 0; t < v->n_tets && moved == v->n_tets; t++) {
        thx_vec3 c = centroid(v, t);
        if (v->region[t] == 0 && c.x > 2.0 && c.x < 3.0 && c.y > 1.0 && c.y < 2.0 && c.z > 1.0 && c.z < 2.0) moved = t;
    }
    CHECK(moved < v->n_tets);
    v->region[moved] = lungs;
    unsigned f = run(v, m, NULL, &r);
    CHECK(f == (THX_VCHECKF_REGION_CELLS | THX_VCHECKF_COVERAGE | THX_VCHECKF_REGION_VOLUME));
    CHECK(r.n_outside_region_tets == 1 && r.ex_outside_region_tet == moved);
    CHECK(r.regions[1].n_outside == 1 && r.regions[1].ex_outside == moved && r.regions[1].ex_outside_cell == 0);
    show_reasons("moved", &r);
    char want[160];
    snprintf(want, sizeof want,
             "region \"lungs\": 1 of 13 tetrahedra lie inside torso, which holds region \"mean_thorax\" (first: "
             "tetrahedron %zu)",
             moved + 1);
    int said = 0;
    for (size_t k = 0; k < r.n_reasons; k++) said |= strstr(r.reasons[k], want) != NULL;
    CHECK(said);
    /* the JSON names the cell */
    cJSON *j = thx_volume_report_json(ctx, &r);
    cJSON *rc = cJSON_GetObjectItem(j, "region_cells");
    CHECK(rc && cJSON_GetObjectItem(rc, "outside_region")->valuedouble == 1);
    cJSON *r1 = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "regions"), 1);
    CHECK(!strcmp(cJSON_GetObjectItem(r1, "cell")->valuestring, "inside lung_r"));
    CHECK(cJSON_GetObjectItem(r1, "outside_region")->valuedouble == 1);
    cJSON *cv = cJSON_GetObjectItem(j, "coverage");
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(cv, "surfaces")) == 3);
    cJSON_Delete(j);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
    thx_volume_report_free(&r);
}

/* A lung shell around the heart: the lung's volume is its surface's less the heart's. */
static void test_nested_volumes(void)
{
    thx_volume_report r = {0};
    thx_volume *v = kuhn_grid(6);
    int32_t lung = add_region(v, "lung_l"), heart = add_region(v, "heart");
    for (size_t t = 0; t < v->n_tets; t++) {
        thx_vec3 c = centroid(v, t);
        if (in_box(c, 2.0, 4.0)) v->region[t] = heart;
        else if (in_box(c, 1.0, 5.0)) v->region[t] = lung;
    }
    thx_surface *s[3] = {cube_surface("torso", THX_ROLE_OUTER, 0.0, 6.0), cube_surface("lung_l", THX_ROLE_LUNG, 1.0, 5.0),
                         cube_surface("heart", THX_ROLE_HEART, 2.0, 4.0)};
    thx_model *m = model_of(s, 3);
    link_nodes(v, m);
    CHECK(run(v, m, NULL, &r) == 0);
    show_reasons("lung around heart", &r);
    CHECK(r.surfaces[2].parent == 1 && r.surfaces[1].parent == 0 && r.surfaces[0].parent == -1);
    CHECK(!strcmp(r.regions[1].definition, "lung_l - heart"));
    CHECK_NEAR(r.regions[1].expected, 56.0, 1e-12);
    CHECK(fabs(r.regions[1].rel_diff) < 1e-12);
    CHECK(!strcmp(r.regions[0].definition, "torso - lung_l") && fabs(r.regions[0].rel_diff) < 1e-12);
    CHECK(!strcmp(r.regions[2].definition, "heart") && r.regions[2].cell == 2);
    /* the heart left out: a cavity, the lung still "lung_l - heart" */
    for (size_t t = v->n_tets; t-- > 0;)
        if (v->region[t] == heart) vol_remove_tet(v, t);
    vol_drop_unused(v);
    v->n_regions = 2;
    link_nodes(v, m);
    CHECK(run(v, m, NULL, &r) == 0);
    show_reasons("lung around excluded heart", &r);
    CHECK(r.n_excluded_hearts == 1 && fabs(r.regions[1].rel_diff) < 1e-12 && fabs(r.volume_rel_diff) < 1e-12);
    CHECK(r.n_interface_faces == 36 * 6 * 2 + 16 * 6 * 2 + 4 * 6 * 2);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
    thx_volume_report_free(&r);
}

/* The smallest dihedral angle fails below 1 degree by default. */
static void test_min_dihedral(void)
{
    /* a flattened regular tetrahedron: h found so that its smallest dihedral is 0.5 degrees */
    double lo = 1e-4, hi = 1.0, mn = 0.0;
    for (int it = 0; it < 100; it++) {
        double h = 0.5 * (lo + hi);
        double a[3] = {1, 1, h}, b[3] = {1, -1, -h}, c[3] = {-1, 1, -h}, d[3] = {-1, -1, h};
        thx_tet_quality(a, b, c, d, &mn, NULL, NULL, NULL);
        if (mn < 0.5) lo = h;
        else hi = h;
    }
    double xyz[12] = {1, 1, hi, 1, -1, -hi, -1, 1, -hi, -1, -1, hi};
    int32_t q[4] = {0, 1, 2, 3};
    fix_orientation(xyz, q);
    thx_volume *v = vol_new(xyz, 4, q, 1);
    thx_volume_report r = {0};
    CHECK(run(v, NULL, NULL, &r) == THX_VCHECKF_QUALITY);
    CHECK_NEAR(r.min_dihedral, 0.5, 1e-9);
    CHECK(r.n_reasons == 1 && strstr(r.reasons[0], "smallest dihedral angle 0.5 deg < 1 deg (tetrahedron 1)") != NULL);
    show_reasons("sliver", &r);
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);
    CHECK(o.min_dihedral_deg == 1.0 && o.region_volume_tol == 0.005);
    o.min_dihedral_deg = 0.4;
    CHECK(run(v, NULL, &o, &r) == 0);
    o.min_dihedral_deg = 0.0; /* off */
    CHECK(run(v, NULL, &o, &r) == 0);
    thx_volume_destroy(&v);
    thx_volume_report_free(&r);
}

/* Random points in a ball and on its sphere; the outer surface is the hull
 * (a sphere of 2 n_s triangles), so containment runs against a realistic
 * surface. Prints the time of the check. */
static void timing(size_t n_in, size_t n_s, int strict)
{
    size_t nn = n_in + n_s;
    double *xyz = malloc(nn * 3 * sizeof(double));
    if (!xyz) abort();
    const double R = 100.0, ga = M_PI * (3.0 - sqrt(5.0));
    for (size_t i = 0; i < n_s; i++) { /* Fibonacci sphere */
        double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n_s, rr = sqrt(1.0 - z * z), a = ga * (double)i;
        xyz[3 * i] = R * rr * cos(a);
        xyz[3 * i + 1] = R * rr * sin(a);
        xyz[3 * i + 2] = R * z;
    }
    for (size_t i = n_s; i < nn;) {
        double p[3] = {2 * urand() - 1, 2 * urand() - 1, 2 * urand() - 1};
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > 0.95 * 0.95) continue;
        for (int a = 0; a < 3; a++) xyz[3 * i + a] = R * p[a];
        i++;
    }
    int32_t *tets = NULL, *nbrs = NULL;
    size_t nt = 0;
    double t0 = thx_wtime();
    if (thx_delaunay3d(ctx, xyz, nn, &tets, &nbrs, &nt, NULL) != THX_OK) abort();
    double t_del = thx_wtime() - t0;
    /* hull faces (Delaunay orientation: outward as thx_delaunay_face lists them) */
    thx_surface *hull = NULL;
    if (thx_surface_create(ctx, "skin", THX_ROLE_OUTER, &hull) != THX_OK) abort();
    size_t nf = 0;
    for (size_t k = 0; k < 4 * nt; k++) nf += nbrs[k] < 0;
    hull->n_tris = nf;
    hull->tri = malloc(3 * nf * sizeof(int32_t));
    hull->n_nodes = n_s;
    hull->xyz = malloc(3 * n_s * sizeof(double));
    if (!hull->tri || !hull->xyz) abort();
    memcpy(hull->xyz, xyz, 3 * n_s * sizeof(double));
    size_t f = 0;
    int hull_ok = 1;
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 4; i++)
            if (nbrs[4 * t + i] < 0)
                for (int j = 0; j < 3; j++) {
                    int32_t g = tets[4 * t + thx_delaunay_face[i][j]];
                    hull_ok &= g < (int32_t)n_s;
                    hull->tri[f++] = g;
                }
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = x;
    }
    thx_volume *v = vol_new(xyz, nn, tets, nt);
    free(tets);
    free(nbrs);
    free(xyz);
    thx_surface *s[1] = {hull};
    thx_model *m = model_of(s, 1);
    /* node tables: surface node i is volume node i */
    v->n_surfaces = 1;
    v->surf_n_nodes = malloc(sizeof(size_t));
    v->surf_node = malloc(sizeof(int32_t *));
    v->surf_node[0] = malloc(n_s * sizeof(int32_t));
    v->node_surf = malloc(nn * sizeof(int32_t));
    v->node_snode = malloc(nn * sizeof(int32_t));
    v->surf_n_nodes[0] = n_s;
    for (size_t g = 0; g < nn; g++) {
        v->node_surf[g] = g < n_s ? 0 : -1;
        v->node_snode[g] = g < n_s ? (int32_t)g : -1;
        if (g < n_s) v->surf_node[0][g] = (int32_t)g;
    }
    thx_volume_report r = {0};
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);
    o.min_dihedral_deg = 0.0; /* random points: slivers */
    t0 = thx_wtime();
    unsigned fl = run(v, m, &o, &r);
    double t_check = thx_wtime() - t0;
    show_reasons("timing", &r);
    if (strict) {
        CHECK(hull_ok);
        CHECK(fl == 0);
        CHECK(fabs(r.volume_rel_diff) < 1e-12);
        CHECK(r.n_outside_tets == 0 && r.boundary.n_tris == nf);
    }
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    printf("timing: %zu nodes, %zu tetrahedra, %zu surface triangles: delaunay %.3f s, check %.3f s "
           "(%.2f M tets/s, %d threads); min dihedral %.3g deg, worst radius-edge %.3g, %zu undecided\n",
           nn, nt, nf, t_del, t_check, (double)nt / t_check * 1e-6, threads, r.min_dihedral, r.max_radius_edge,
           r.n_undecided_tets);
    thx_volume_report_free(&r);
    thx_volume_destroy(&v);
    thx_model_destroy(&m);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_quality();
    test_cube_passes();
    test_delaunay_passes();
    test_validity_failures();
    test_conformity_failures();
    test_void_and_missing();
    test_volume_difference();
    test_containment_and_tables();
    test_regions_and_heart();
    test_coverage_and_steiner();
    test_region_cells();
    test_nested_volumes();
    test_min_dihedral();
    timing(12000, 3000, 1);
    const char *bench = getenv("THX_CHECK_VOLUME_BENCH");
    if (bench && atol(bench) > 0) {
        size_t n = (size_t)atol(bench);
        timing(n, n / 8 + 4, 1);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
