/*
 * The faces --tetrahedra draws (src/picture/tets.c, picture_tet_surfaces), on two 10 mm cubes
 * stacked along z, each cut into the 6 tetrahedra around its main diagonal (half of them listed
 * with negative orientation on purpose), the lower cube region 0, the upper region 1:
 *  - no clip: the faces are the outside of the 20 x 10 x 10 box (20 triangles: the two cubes'
 *    12 each, less the 2 + 2 of the square they share), one surface per region (10 each), every
 *    face turned outward: the divergence theorem over them gives the box's 2000 mm^3;
 *  - a clip keeping z <= 10: only the lower cube, whole (12 triangles, 1000 mm^3), region 0;
 *  - a clip that leaves no tetrahedron whole: no surface;
 *  - each surface's nodes are distinct and are volume nodes.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "picture/picture_internal.h"

static thx_ctx *ctx;

static thx_volume *two_cubes(void)
{
    thx_volume *v = NULL;
    CHECK_OK(ctx, thx_volume_create(ctx, &v));
    if (!v) return NULL;
    v->n_nodes = 12; /* node x + 2 y + 4 z for z = 0, 1, 2 */
    v->xyz = malloc(3 * v->n_nodes * sizeof *v->xyz);
    for (int i = 0; i < 12; i++) {
        v->xyz[3 * i] = 10.0 * (i & 1);
        v->xyz[3 * i + 1] = 10.0 * ((i >> 1) & 1);
        v->xyz[3 * i + 2] = 10.0 * (i >> 2);
    }
    /* Kuhn's 6 tetrahedra of a cube: 0 -> e_a -> e_a + e_b -> 7 for each order of the axes */
    static const int axis[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
    v->n_tets = 12;
    v->tet = malloc(4 * v->n_tets * sizeof *v->tet);
    v->region = malloc(v->n_tets * sizeof *v->region);
    for (int c = 0; c < 2; c++)
        for (int k = 0; k < 6; k++) {
            int32_t *t = v->tet + 4 * (6 * c + k), base = 4 * c;
            int32_t a = base + axis[k][0], b = base + axis[k][0] + axis[k][1], e = base + 7;
            t[0] = base;
            t[1] = k % 2 ? b : a; /* every other one listed the wrong way round */
            t[2] = k % 2 ? a : b;
            t[3] = e;
            v->region[6 * c + k] = c;
        }
    v->n_regions = 2;
    v->regions = calloc(2, sizeof *v->regions);
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "lower");
    snprintf(v->regions[1].name, sizeof v->regions[1].name, "upper");
    return v;
}

/* Sum over the triangles of the signed volume of (origin, a, b, c): the enclosed volume when the
 * faces close a region and face outward. */
static double enclosed(thx_surface *const *s, int n, size_t *n_tris)
{
    double vol = 0;
    *n_tris = 0;
    for (int k = 0; k < n; k++) {
        *n_tris += s[k]->n_tris;
        for (size_t t = 0; t < s[k]->n_tris; t++) {
            const double *a = s[k]->xyz + 3 * (size_t)s[k]->tri[3 * t], *b = s[k]->xyz + 3 * (size_t)s[k]->tri[3 * t + 1],
                         *c = s[k]->xyz + 3 * (size_t)s[k]->tri[3 * t + 2];
            vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                    a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        }
    }
    return vol;
}

static int nodes_distinct(const thx_surface *s)
{
    for (size_t i = 0; i < s->n_nodes; i++)
        for (size_t j = i + 1; j < s->n_nodes; j++)
            if (!memcmp(s->xyz + 3 * i, s->xyz + 3 * j, 3 * sizeof(double))) return 0;
    return 1;
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_volume *v = two_cubes();
    if (!v) return 1;
    thx_surface *s[8];
    int region[8], n = -1;
    size_t nt;

    CHECK_OK(ctx, picture_tet_surfaces(ctx, v, NULL, s, region, 8, &n));
    CHECK(n == 2 && region[0] == 0 && region[1] == 1);
    CHECK_NEAR(enclosed(s, n, &nt), 2000.0, 1e-9);
    CHECK(nt == 20 && s[0]->n_tris == 10 && s[1]->n_tris == 10);
    CHECK(!strcmp(s[0]->name, "lower") && !strcmp(s[1]->name, "upper"));
    for (int k = 0; k < n; k++) {
        CHECK(nodes_distinct(s[k]) && s[k]->n_nodes == 8);
        thx_surface_destroy(&s[k]);
    }

    thx_clip_plane below = {{0, 0, -1}, 10}; /* keeps -z + 10 >= 0 */
    CHECK_OK(ctx, picture_tet_surfaces(ctx, v, &below, s, region, 8, &n));
    CHECK(n == 1 && region[0] == 0);
    CHECK_NEAR(enclosed(s, n, &nt), 1000.0, 1e-9);
    CHECK(nt == 12);
    for (int k = 0; k < n; k++) thx_surface_destroy(&s[k]);

    thx_clip_plane half = {{1, 0, 0}, -5}; /* keeps x >= 5: every tetrahedron has a node at x = 0 */
    CHECK_OK(ctx, picture_tet_surfaces(ctx, v, &half, s, region, 8, &n));
    CHECK(n == 0);

    thx_volume_destroy(&v);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
