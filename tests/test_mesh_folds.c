/* The mesher's folds (src/mesh/folds.h): the interior dihedral angle of a surface's edges, which
 * edges are folds, and the graded size bound around them. Checked on closed surfaces whose angles
 * are known: a cube (every face edge 90 deg, the faces' diagonals 180), a thin wedge (a triangular
 * prism of opening 7.5 deg, the angle of ECGSim's sharpest rim), and a box with a notch cut into it
 * (reflex edges of 270 deg), each checked against an angle computed here from the geometry. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/folds.h"
#include "testlib.h"

static thx_surface *make(thx_ctx *ctx, const double *xyz, size_t nn, const int32_t *tri, size_t nt)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "s", THX_ROLE_HEART, &s) != THX_OK) return NULL;
    s->xyz = malloc(3 * nn * sizeof *s->xyz);
    s->tri = malloc(3 * nt * sizeof *s->tri);
    memcpy(s->xyz, xyz, 3 * nn * sizeof *s->xyz);
    memcpy(s->tri, tri, 3 * nt * sizeof *s->tri);
    s->n_nodes = nn;
    s->n_tris = nt;
    return s;
}

/* a convex polytope's boundary, counterclockwise from outside: quads (a, b, c, d) split along a-c */
static void quad(int32_t *t, size_t *n, int a, int b, int c, int d)
{
    int32_t q[6] = {a, b, c, a, c, d};
    memcpy(t + 3 * *n, q, sizeof q);
    *n += 2;
}

/* the prism over the triangle (0,0), (L,0), (L cos w, L sin w) in x-y, z from 0 to H: its edge at the
 * origin (along z) has the interior angle w */
static thx_surface *wedge(thx_ctx *ctx, double w_deg, double L, double H)
{
    double w = w_deg * M_PI / 180;
    double p[6][3] = {{0, 0, 0}, {L, 0, 0}, {L * cos(w), L * sin(w), 0}, {0, 0, H}, {L, 0, H}, {L * cos(w), L * sin(w), H}};
    int32_t t[8 * 3];
    size_t n = 0;
    int32_t bottom[3] = {0, 2, 1}, top[3] = {3, 4, 5};
    memcpy(t, bottom, sizeof bottom);
    memcpy(t + 3, top, sizeof top);
    n = 2;
    quad(t, &n, 0, 1, 4, 3);
    quad(t, &n, 1, 2, 5, 4);
    quad(t, &n, 2, 0, 3, 5);
    return make(ctx, &p[0][0], 6, t, n);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    CHECK(thx_ctx_create(&ctx) == THX_OK);

    /* the formula on its own: a convex right angle, a flat pair, a reflex right angle, a thin wedge */
    {
        double a[3] = {0, 0, 0}, b[3] = {0, 0, 1};
        double c1[3] = {1, 0, 0}, d1[3] = {0, 1, 0};    /* faces in the planes y = 0 and x = 0, solid in x, y > 0 */
        CHECK_NEAR(mesh_interior_dihedral(a, b, d1, c1), 90.0, 1e-9);
        CHECK_NEAR(mesh_interior_dihedral(a, b, c1, d1), 270.0, 1e-9); /* the same faces, the solid outside them */
        double c2[3] = {1, 0, 0}, d2[3] = {-1, 0, 0};
        CHECK_NEAR(mesh_interior_dihedral(a, b, c2, d2), 180.0, 1e-9);
        double w = 7.5 * M_PI / 180, c3[3] = {1, 0, 0}, d3[3] = {cos(w), sin(w), 0};
        CHECK_NEAR(mesh_interior_dihedral(a, b, d3, c3), 7.5, 1e-9);
        CHECK_NEAR(mesh_interior_dihedral(a, b, c3, d3), 352.5, 1e-9);
    }

    /* a cube: 12 edges of 90 deg (folds below 120), 6 face diagonals of 180 (never) */
    {
        double p[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        int32_t t[12 * 3];
        size_t n = 0;
        quad(t, &n, 0, 3, 2, 1); /* bottom, seen from below */
        quad(t, &n, 4, 5, 6, 7);
        quad(t, &n, 0, 1, 5, 4);
        quad(t, &n, 1, 2, 6, 5);
        quad(t, &n, 2, 3, 7, 6);
        quad(t, &n, 3, 0, 4, 7);
        thx_surface *s = make(ctx, &p[0][0], 8, t, n);
        CHECK(s != NULL);
        mesh_folds f;
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 120, 0.1, 0.2, 1.0, &f));
        CHECK(f.n == 12);
        /* the size bound: 0.1 at an edge, 0.1 + 0.2 d away, none at or beyond hmax */
        double on[3] = {0.5, 0, 0}, in1[3] = {0.5, 0.25, 0.25}, mid[3] = {0.5, 0.5, 0.5}, far[3] = {0.5, 10, 10};
        CHECK_NEAR(mesh_folds_size(&f, on), 0.1, 1e-12);
        CHECK_NEAR(mesh_folds_size(&f, in1), 0.1 + 0.2 * 0.25 * sqrt(2.0), 1e-12);
        CHECK_NEAR(mesh_folds_size(&f, mid), 0.1 + 0.2 * 0.5 * sqrt(2.0), 1e-12);
        CHECK(isinf(mesh_folds_size(&f, far)));
        mesh_folds_free(&f);
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 80, 0.1, 0.2, 1.0, &f));
        CHECK(f.n == 0);
        CHECK(isinf(mesh_folds_size(&f, on)));
        mesh_folds_free(&f);
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 0, 0.1, 0.2, 1.0, &f)); /* 0: off */
        CHECK(f.n == 0);
        mesh_folds_free(&f);
        thx_surface_destroy(&s);
    }

    /* a 7.5 deg wedge: its sharp edge (0,0,0)-(0,0,H) is the only fold below 60 deg; below 120 the two
       other vertical edges (86.25 deg each) and the six top and bottom edges (90) join it */
    {
        thx_surface *s = wedge(ctx, 7.5, 10, 4);
        CHECK(s != NULL);
        mesh_folds f;
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 60, 0.5, 0.2, 7.0, &f));
        CHECK(f.n == 1);
        if (f.n == 1) {
            CHECK(fabs(f.seg[0]) + fabs(f.seg[1]) + fabs(f.seg[3]) + fabs(f.seg[4]) < 1e-12);
            CHECK(fabs(fabs(f.seg[5] - f.seg[2]) - 4) < 1e-12);
        }
        double p[3] = {-3, 4, 2}; /* 5 from the sharp edge, farther from everything else */
        CHECK_NEAR(mesh_folds_size(&f, p), 0.5 + 0.2 * 5, 1e-12);
        mesh_folds_free(&f);
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 120, 0.5, 0.2, 7.0, &f));
        CHECK(f.n == 9);
        mesh_folds_free(&f);
        thx_surface_destroy(&s);
    }

    /* a reflex edge is no fold: the cube's inside-out copy (every triangle reversed) has 12 edges of
       270 deg and no fold below 120 */
    {
        double p[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
        int32_t t[12 * 3];
        size_t n = 0;
        quad(t, &n, 0, 1, 2, 3);
        quad(t, &n, 4, 7, 6, 5);
        quad(t, &n, 0, 4, 5, 1);
        quad(t, &n, 1, 5, 6, 2);
        quad(t, &n, 2, 6, 7, 3);
        quad(t, &n, 3, 7, 4, 0);
        thx_surface *s = make(ctx, &p[0][0], 8, t, n);
        mesh_folds f;
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 120, 0.1, 0.2, 1.0, &f));
        CHECK(f.n == 0);
        mesh_folds_free(&f);
        CHECK_OK(ctx, mesh_folds_find(ctx, s, 179.9, 0.1, 0.2, 1.0, &f));
        CHECK(f.n == 0);
        mesh_folds_free(&f);
        thx_surface_destroy(&s);
    }
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
