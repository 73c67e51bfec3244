/*
 * The model layer (src/model, thorax/model/): each type's validator accepts a valid object and
 * refuses each planted fault with a message naming the object; the contours' structural walk calls
 * its hook after every point and every loop, in order, and stops at the hook's first error.
 */
#include "testlib.h"
#include "thorax/model/contours.h"
#include "thorax/model/electrodes.h"
#include "thorax/model/model.h"
#include "thorax/model/series.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static thx_ctx *ctx;

static int says(const char *needle)
{
    const char *m = thx_ctx_message(ctx);
    if (strstr(m, needle)) return 1;
    fprintf(stderr, "  message \"%s\" lacks \"%s\"\n", m, needle);
    return 0;
}

/* A tetrahedron as a surface: 4 nodes, 4 outward triangles. */
static thx_surface *tet_surface(const char *name)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, THX_ROLE_OUTER, &s) != THX_OK) return NULL;
    static const double x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const int32_t t[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    s->n_nodes = 4, s->n_tris = 4;
    s->xyz = malloc(sizeof x);
    s->tri = malloc(sizeof t);
    memcpy(s->xyz, x, sizeof x);
    memcpy(s->tri, t, sizeof t);
    return s;
}

static void test_surface(void)
{
    thx_surface *s = tet_surface("box");
    CHECK_OK(ctx, thx_surface_validate(ctx, s));
    CHECK_NEAR(thx_surface_volume(s), 1.0 / 6, 1e-15); /* outward: positive */
    /* The normal sums: at the origin the three axis faces' (-1,-1,-1); at the corner on axis k the
     * two axis faces' -e_i - e_j plus the slanted face's (1,1,1): e_k. Overwritten, whatever was there. */
    double nsum[12];
    for (int i = 0; i < 12; i++) nsum[i] = 7.0;
    thx_surface_normal_sums(s, nsum);
    static const double want[12] = {-1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 12; i++) CHECK_NEAR(nsum[i], want[i], 0);
    s->tri[7] = 4;
    CHECK(thx_surface_validate(ctx, s) == THX_EINPUT && says("triangle 3 has node index 4 out of range 0..3"));
    s->tri[7] = 1;
    s->xyz[5] = NAN;
    CHECK(thx_surface_validate(ctx, s) == THX_EINPUT && says("surface \"box\": node 2 has a non-finite coordinate"));
    thx_surface_destroy(&s);
    CHECK(s == NULL);
    thx_surface_destroy(&s); /* NULL accepted */
}

static void test_series(void)
{
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 3, 4, &s));
    CHECK_OK(ctx, thx_series_validate(ctx, s, "s.txt"));
    s->time[2] = s->time[1];
    CHECK(thx_series_validate(ctx, s, "s.txt") == THX_EINPUT && says("s.txt: time of frame 3") && says("times must increase"));
    s->time[2] = INFINITY;
    CHECK(thx_series_validate(ctx, s, "s.txt") == THX_EINPUT && says("time of frame 3 is inf"));
    thx_series_destroy(&s);
    CHECK_OK(ctx, thx_series_create(ctx, 0, 4, &s));
    CHECK(thx_series_validate(ctx, s, "e.raw") == THX_EINPUT && says("e.raw: empty series (0 rows x 4 frames"));
    thx_series_destroy(&s);
    CHECK(thx_series_create(ctx, SIZE_MAX / 4, 8, &s) == THX_EINPUT && s == NULL);
}

/* The tetrahedron as a model with a one-tetrahedron volume whose node table maps the surface. */
static thx_model *tet_model(void)
{
    thx_model *m = NULL;
    if (thx_model_create(ctx, &m) != THX_OK) return NULL;
    thx_surface *s = tet_surface("torso");
    thx_model_add_surface(ctx, m, &s);
    thx_volume *v = NULL;
    thx_volume_create(ctx, &v);
    m->volume = v;
    v->n_nodes = 4, v->n_tets = 1, v->n_regions = 1, v->n_surfaces = 1;
    v->xyz = malloc(12 * sizeof *v->xyz);
    memcpy(v->xyz, m->surf[0]->xyz, 12 * sizeof *v->xyz);
    v->tet = malloc(4 * sizeof *v->tet);
    for (int k = 0; k < 4; k++) v->tet[k] = k;
    v->region = calloc(1, sizeof *v->region);
    v->regions = calloc(1, sizeof *v->regions);
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "mean_thorax");
    v->regions[0].sigma[0] = v->regions[0].sigma[4] = v->regions[0].sigma[8] = 0.2;
    v->surf_n_nodes = malloc(sizeof *v->surf_n_nodes);
    v->surf_n_nodes[0] = 4;
    v->surf_node = malloc(sizeof *v->surf_node);
    v->surf_node[0] = malloc(4 * sizeof **v->surf_node);
    v->node_surf = malloc(4 * sizeof *v->node_surf);
    v->node_snode = malloc(4 * sizeof *v->node_snode);
    for (int k = 0; k < 4; k++) v->surf_node[0][k] = k, v->node_surf[k] = 0, v->node_snode[k] = k;
    return m;
}

static void test_volume(void)
{
    thx_model *m = tet_model();
    thx_volume *v = m->volume;
    CHECK_OK(ctx, thx_model_volume_validate(ctx, m, "vol"));
    CHECK_NEAR(thx_volume_tet_volume(v, 0), 1.0 / 6, 1e-15);
    v->region[0] = 1;
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("tetrahedron 1: region index 1 out of range"));
    v->region[0] = 0;
    v->tet[3] = 2;
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("node 3 appears twice"));
    v->tet[3] = 3;
    v->regions[0].anisotropic = 1;
    v->regions[0].sigma[1] = 0.5; /* not symmetric */
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("not symmetric"));
    v->regions[0].sigma[3] = 0.5; /* symmetric, indefinite: pivot 2 = 0.2 - 1.25 < 0 */
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("not positive definite"));
    v->regions[0].anisotropic = 0;
    v->regions[0].sigma[1] = v->regions[0].sigma[3] = 0;
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "lung/l");
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("region 1: name"));
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "lung_l");
    v->xyz[0] = 1e-3; /* surface node 1 and its volume node apart */
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("coordinates differ"));
    v->xyz[0] = 0;
    v->node_snode[2] = 1; /* the reverse table disagrees */
    CHECK(thx_model_volume_validate(ctx, m, "vol") == THX_EINPUT && says("volume node 3: reverse node table"));
    v->node_snode[2] = 2;
    CHECK_OK(ctx, thx_model_volume_validate(ctx, m, "vol"));
    thx_model_destroy(&m);
    CHECK(m == NULL);
}

static void test_electrodes(void)
{
    thx_electrodes *e = NULL;
    CHECK(thx_electrodes_create(ctx, 0, &e) == THX_EINPUT && e == NULL);
    CHECK_OK(ctx, thx_electrodes_create(ctx, 2, &e));
    snprintf(e->surface, sizeof e->surface, "torso");
    snprintf(e->name[0], sizeof e->name[0], "V1");
    snprintf(e->name[1], sizeof e->name[1], "V2");
    e->node[0] = 1, e->node[1] = 2;
    e->xyz[0] = 1, e->xyz[4] = 1; /* nodes 1 (1, 0, 0) and 2 (0, 1, 0) of the tetrahedron */
    CHECK_OK(ctx, thx_electrodes_validate(ctx, e, "e: "));
    thx_model *m = tet_model();
    CHECK_OK(ctx, thx_electrodes_check(ctx, e, m));
    e->node[1] = 7;
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT && says("electrode 2 (\"V2\"): node 8 is not on surface \"torso\""));
    e->node[1] = 2;
    e->xyz[4] = 1.01;
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT && says("electrode 2 (\"V2\"): position"));
    snprintf(e->name[1], sizeof e->name[1], "V1");
    CHECK(thx_electrodes_validate(ctx, e, "e: ") == THX_EINPUT && says("e: electrode 2: name \"V1\" already used by electrode 1"));
    CHECK(thx_electrodes_name_why("end", 32) != NULL && thx_electrodes_name_why("V1 ", 32) != NULL &&
          thx_electrodes_name_why("aVR", 32) == NULL);
    CHECK(thx_electrodes_surface_name_why(".hidden", 64) != NULL && thx_electrodes_surface_name_why("torso", 64) == NULL);
    thx_model_destroy(&m);
    thx_electrodes_destroy(&e);
    CHECK(e == NULL);
}

typedef struct {
    int points, loops, stop_at;
} walk_count;

static thx_status count_hook(thx_ctx *c, const thx_contours_at *at, void *user)
{
    walk_count *w = user;
    if (at->point == SIZE_MAX) w->loops++;
    else {
        CHECK(at->point < at->layer->loops[at->loop].n);
        w->points++;
    }
    if (w->stop_at && w->points == w->stop_at) return thx_error(c, THX_EINPUT, "%s: stopped at point %d", at->path, w->points);
    return THX_OK;
}

static void test_contours(void)
{
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    CHECK(thx_contours_validate_structure(ctx, c) == THX_EINPUT && says("<contours>: no surfaces declared"));
    size_t s;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "torso", THX_ROLE_OUTER, THX_CAP_GRID, 0, &s));
    CHECK(thx_contours_add_surface(ctx, c, "torso", THX_ROLE_OUTER, THX_CAP_GRID, 0, NULL) == THX_EINPUT && says("declared twice"));
    const thx_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 0, sq, 4));
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 5, sq, 4));
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 5, sq, 3));
    CHECK(thx_contours_add_loop(ctx, c, s, 2, sq, 4) == THX_EINPUT && says("layer z=2 added after z=5"));
    CHECK_OK(ctx, thx_contours_validate_structure(ctx, c));
    CHECK(thx_contours_find_surface(c, "torso") == 0 && thx_contours_find_surface(c, "heart") == -1);
    double *zs = NULL;
    size_t nz = 0;
    CHECK_OK(ctx, thx_contours_layer_z(ctx, c, &zs, &nz));
    CHECK(nz == 2 && zs && zs[0] == 0 && zs[1] == 5);
    free(zs);
    walk_count w = {0, 0, 0};
    CHECK_OK(ctx, thx_contours_validate_with(ctx, c, count_hook, &w));
    CHECK(w.points == 11 && w.loops == 3);
    walk_count stop = {0, 0, 6};
    CHECK(thx_contours_validate_with(ctx, c, count_hook, &stop) == THX_EINPUT && says("<contours>: stopped at point 6"));
    CHECK(stop.points == 6 && stop.loops == 1);
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 10, sq, 2));
    CHECK(thx_contours_validate_structure(ctx, c) == THX_EINPUT &&
          says("surface \"torso\" layer 3 (z=10) loop 1: loop has 2 points (at least 3 needed)"));
    thx_contours_destroy(&c);
    CHECK(c == NULL);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_surface();
    test_series();
    test_volume();
    test_electrodes();
    test_contours();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
