/* Point location in a volume mesh (thorax/mesh/tet_locate.h) and the dipole locator
 * (thx_fem_locate_walk, thorax/fem/fem.h) against the scan of every tetrahedron (thx_fem_locate)
 * on the meshes the dipole tests use: OpenMEEG's Head2 spheres (its real .tri files, scaled by 100
 * to mm, meshed with the three regions as tests/e2e_dipoles.sh does), thorax's own three shells
 * (icospheres of level 3 at OpenMEEG's radii, as test_dipole.c) and the medium phantom, heart
 * meshed. On each:
 *  - the face adjacency is symmetric and each neighbour holds the face's three nodes;
 *  - the walk from the seed finds the very tetrahedron whose centroid it is asked for (1000 of them);
 *  - 1000 (phantom: 300) seeded random points of the bounding box: the walk's locator and the scan give the same
 *    tetrahedron (or both none: outside), and the walk decides most of those inside (it is used);
 *  - points on nodes, edge midpoints and face centroids (of 100 tetrahedra) (shared by several tetrahedra): the same
 *    tetrahedron as the scan (the scan's rule decides them);
 * Prints the walk's and the scan's time a point. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/core/core.h"
#include "thorax/fem/fem.h"
#include "thorax/geom/verify.h"
#include "thorax/import/import.h"
#include "thorax/mesh/mesh.h"
#include "thorax/mesh/tet_locate.h"
#include "thorax/model/model.h"

static unsigned long long rs = 0x2545F4914F6CDD1DULL;
static double urand(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 7;
    rs ^= rs << 17;
    return ((double)(rs >> 11) + 0.5) / 9007199254740992.0;
}

static void region_set(thx_mesh_opts *o, const char *name, const char *rename, double sigma)
{
    snprintf(o->region_set[o->n_region_set].name, sizeof o->region_set[0].name, "%s", name);
    snprintf(o->region_set[o->n_region_set].rename, sizeof o->region_set[0].rename, "%s", rename);
    o->region_set[o->n_region_set++].sigma = sigma;
}

static void check_mesh(thx_ctx *ctx, const char *name, const thx_volume *v, int n_random)
{
    thx_tet_locator *L = NULL;
    CHECK_OK(ctx, thx_tet_locator_create(ctx, v, &L));
    if (!L) return;
    size_t nt = v->n_tets, bad_adj = 0, boundary = 0;
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            long u = thx_tet_neighbour(L, t, k);
            if (u < 0) {
                boundary++;
                continue;
            }
            const int32_t *q = v->tet + 4 * t, *r = v->tet + 4 * (size_t)u;
            int back = 0, shared = 0;
            for (int j = 0; j < 4; j++) back += thx_tet_neighbour(L, (size_t)u, j) == (long)t;
            for (int j = 1; j < 4; j++) {
                int32_t a = q[(k + j) % 4];
                shared += r[0] == a || r[1] == a || r[2] == a || r[3] == a;
            }
            bad_adj += back != 1 || shared != 3 || u == (long)t;
        }
    CHECK(bad_adj == 0);
    CHECK(boundary > 0);
    /* centroids: the walk from the seed lands on that very tetrahedron */
    size_t miss = 0, steps_sum = 0;
    for (int i = 0; i < 1000; i++) {
        size_t t = (size_t)(urand() * (double)nt) % nt;
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int a = 0; a < 3; a++) c[a] += 0.25 * v->xyz[3 * (size_t)v->tet[4 * t + (size_t)k] + (size_t)a];
        size_t st = 0;
        long w = thx_tet_locate(L, c, -1, &st);
        steps_sum += st;
        /* a non-convex mesh may stop the walk at its boundary: then the locator scans; never a wrong one */
        if (w >= 0) CHECK(w == (long)t);
        else miss++;
        long f = -1;
        thx_fem_locate_walk(L, v, c, -1, &f, NULL);
        CHECK(f == (long)t);
    }
    CHECK(miss < 50);
    /* random points of the bounding box */
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = hi[a] = v->xyz[a];
    for (size_t i = 0; i < v->n_nodes; i++)
        for (int a = 0; a < 3; a++) lo[a] = fmin(lo[a], v->xyz[3 * i + a]), hi[a] = fmax(hi[a], v->xyz[3 * i + a]);
    size_t inside = 0, by_walk = 0, differ = 0;
    double t_walk = 0, t_scan = 0;
    long prev = -1;
    for (int i = 0; i < n_random; i++) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = lo[a] + urand() * (hi[a] - lo[a]);
        long ts = -1, tw = -1;
        double l1[4], l2[4];
        double t0 = thx_wtime();
        int w = thx_fem_locate_walk(L, v, p, prev, &tw, l1);
        double t1 = thx_wtime();
        thx_fem_locate(v, p, &ts, l2);
        if (w) { /* the times of the points the walk placed */
            t_scan += thx_wtime() - t1;
            t_walk += t1 - t0;
        }
        differ += ts != tw;
        if (ts >= 0) {
            inside++;
            by_walk += (size_t)w;
            prev = tw;
            CHECK(memcmp(l1, l2, sizeof l1) == 0);
        }
    }
    CHECK(differ == 0);
    CHECK(inside > (size_t)n_random / 10);
    CHECK(by_walk >= inside * 9 / 10);
    /* ties: nodes, edge midpoints, face centroids of random tetrahedra */
    size_t tdiff = 0;
    for (int i = 0; i < 100; i++) {
        const int32_t *q = v->tet + 4 * ((size_t)(urand() * (double)nt) % nt);
        const double *A = v->xyz + 3 * (size_t)q[0], *B = v->xyz + 3 * (size_t)q[1], *C = v->xyz + 3 * (size_t)q[2];
        double pts[3][3];
        for (int a = 0; a < 3; a++) {
            pts[0][a] = A[a];
            pts[1][a] = 0.5 * (A[a] + B[a]);
            pts[2][a] = (A[a] + B[a] + C[a]) / 3;
        }
        for (int k = 0; k < 3; k++) {
            long ts = -1, tw = -1;
            thx_fem_locate(v, pts[k], &ts, NULL);
            thx_fem_locate_walk(L, v, pts[k], -1, &tw, NULL);
            tdiff += ts != tw;
        }
    }
    CHECK(tdiff == 0);
    printf("%s: %zu tetrahedra, %zu boundary faces; centroids: %.1f steps a walk, %zu walks stopped at the boundary; "
           "%d random points, %zu inside: %zu placed by the walk, %zu by the scan, %zu differ from the scan; ties "
           "differ %zu; of those the walk placed, %.1f us a point by walk, %.1f us by scan\n",
           name, nt, boundary, steps_sum / 1000.0, miss, n_random, inside, by_walk, inside - by_walk, differ, tdiff,
           1e6 * t_walk / (double)(by_walk ? by_walk : 1), 1e6 * t_scan / (double)(by_walk ? by_walk : 1));
    thx_tet_locator_destroy(&L);
}

static thx_model *openmeeg_head(thx_ctx *ctx, const char *dir)
{
    static const char *file[3] = {"scalp.2.tri", "skull.2.tri", "cortex.2.tri"}, *name[3] = {"scalp", "skull", "brain"};
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &m));
    thx_import_opts io;
    thx_import_opts_default(&io);
    io.scale = 100;
    for (int s = 0; s < 3 && m; s++) {
        char path[2300];
        snprintf(path, sizeof path, "%s/%s", dir, file[s]);
        thx_surface *su = NULL;
        CHECK_OK(ctx, thx_surface_import(ctx, path, NULL, name[s], s ? THX_ROLE_OTHER : THX_ROLE_OUTER, &io, &su, NULL));
        if (!su || thx_model_add_surface(ctx, m, &su)) {
            thx_surface_destroy(&su);
            thx_model_destroy(&m);
        }
    }
    if (!m) return NULL;
    thx_mesh_opts mo;
    thx_mesh_opts_default(&mo);
    region_set(&mo, "mean_thorax", "scalp", 1);
    region_set(&mo, "skull", "", 0.0125);
    region_set(&mo, "brain", "", 1);
    thx_mesh_stats ms;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &mo, &ms));
    return m;
}

static thx_model *shells(thx_ctx *ctx)
{
    const double r[3] = {100, 92, 87}, sg[3] = {1, 0.0125, 1};
    static const char *name[3] = {"scalp", "skull", "brain"};
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &m));
    for (int s = 0; s < 3 && m; s++) {
        thx_surface *su = NULL;
        CHECK_OK(ctx, thx_icosphere(ctx, 3, r[s], name[s], s ? THX_ROLE_OTHER : THX_ROLE_OUTER, &su));
        if (!su || thx_model_add_surface(ctx, m, &su)) thx_model_destroy(&m);
    }
    if (!m) return NULL;
    thx_mesh_opts mo;
    thx_mesh_opts_default(&mo);
    mo.grid = 60.0 / 8;
    region_set(&mo, "mean_thorax", "scalp", sg[0]);
    region_set(&mo, "skull", "", sg[1]);
    region_set(&mo, "brain", "", sg[2]);
    thx_mesh_stats ms;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &mo, &ms));
    return m;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    /* the data beside the checkout: tests/../../shared/data */
    char dir[2100];
    snprintf(dir, sizeof dir, "%s", tl_src_path(__FILE__, "../../shared/data/openmeeg-spheres/data/Head2"));
    FILE *f = NULL;
    {
        char probe[2200];
        snprintf(probe, sizeof probe, "%s/scalp.2.tri", dir);
        f = fopen(probe, "r");
    }
    if (f) {
        fclose(f);
        thx_model *m = openmeeg_head(ctx, dir);
        if (m && m->volume) check_mesh(ctx, "OpenMEEG Head2 (x 100 mm)", m->volume, 1000);
        CHECK(m && m->volume);
        thx_model_destroy(&m);
    } else
        printf("OpenMEEG Head2 not found at %s: skipped\n", dir);
    thx_model *s = shells(ctx);
    CHECK(s && s->volume);
    if (s && s->volume) check_mesh(ctx, "three shells, level 3", s->volume, 1000);
    thx_model_destroy(&s);
    thx_model *ph = tl_phantom_surfaces(ctx);
    if (ph) {
        thx_mesh_opts mo;
        thx_mesh_opts_default(&mo);
        thx_mesh_stats ms;
        CHECK_OK(ctx, thx_mesh_build(ctx, ph, &mo, &ms));
        if (ph->volume) {
            double t0 = thx_wtime();
            check_mesh(ctx, "medium phantom, heart meshed", ph->volume, 300);
            printf("(phantom checks %.1f s)\n", thx_wtime() - t0);
        }
    }
    thx_model_destroy(&ph);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
