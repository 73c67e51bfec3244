/*
 * The mesh repair's quality function and its node insertion (src/mesh/improve.c), tested directly
 * (issue 24):
 *  - mesh_tet_quality against an independent computation: dihedral angles from face normals
 *    (acos), the circumradius from the 3x3 linear system by Cramer's rule, on tetrahedra chosen
 *    so that each branch decides: the regular tetrahedron (sin acos(1/3) = 2 sqrt(2) / 3), a
 *    corner tetrahedron whose radius-edge ratio (1.436) lies between sqrt(1.6) and 1.6 (a bound
 *    compared unsquared would take it for a needle), needles beyond the bound (re_scale / RE),
 *    flat and inverted ones (0), 2000 random ones;
 *  - node insertion alone (IMPROVE_INSERT) on a sliver whose two lower faces are protected surface
 *    triangles that meet at 178.9 deg: no flip may remove it, and a new free node must; the
 *    protected faces stay, the boundary and the volume are unchanged, every tetrahedron positive.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/improve.h"
#include "testlib.h"
#include "thorax/check/check_volume.h"
#include "thorax/geom/predicates.h"

/* independent: smallest dihedral angle (degrees) from the outward unit normals; *min_sine: the
 * smallest sine of the six (an angle near 180 deg counts as one near 0) */
static double dihedrals(const double p[4][3], double *min_sine)
{
    static const int fo[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    double n[4][3];
    for (int f = 0; f < 4; f++) {
        const double *a = p[fo[f][0]], *b = p[fo[f][1]], *c = p[fo[f][2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        n[f][0] = u[1] * v[2] - u[2] * v[1];
        n[f][1] = u[2] * v[0] - u[0] * v[2];
        n[f][2] = u[0] * v[1] - u[1] * v[0];
        double l = sqrt(n[f][0] * n[f][0] + n[f][1] * n[f][1] + n[f][2] * n[f][2]);
        double o = 0; /* outward: away from the opposite corner */
        for (int k = 0; k < 3; k++) o += n[f][k] * (p[f][k] - a[k]);
        for (int k = 0; k < 3; k++) n[f][k] *= (o > 0 ? -1 : 1) / l;
    }
    double best = 180, ms = 1;
    for (int f = 0; f < 4; f++)
        for (int g = f + 1; g < 4; g++) {
            double d = -(n[f][0] * n[g][0] + n[f][1] * n[g][1] + n[f][2] * n[g][2]);
            double a = acos(fmax(-1, fmin(1, d))) * 180 / M_PI;
            if (a < best) best = a;
            ms = fmin(ms, sin(a * M_PI / 180));
        }
    if (min_sine) *min_sine = ms;
    return best;
}
static double min_dihedral(const double p[4][3]) { return dihedrals(p, NULL); }
static double min_sine(const double p[4][3])
{
    double s;
    dihedrals(p, &s);
    return s;
}

/* independent: radius-edge ratio, the circumcentre c solving 2 (p_i - p_0) . c = |p_i|^2 - |p_0|^2 */
static double radius_edge(const double p[4][3])
{
    double A[3][3], r[3];
    for (int i = 0; i < 3; i++) {
        r[i] = 0;
        for (int k = 0; k < 3; k++) {
            A[i][k] = 2 * (p[i + 1][k] - p[0][k]);
            r[i] += p[i + 1][k] * p[i + 1][k] - p[0][k] * p[0][k];
        }
    }
#define DET3(M) ((M)[0][0] * ((M)[1][1] * (M)[2][2] - (M)[1][2] * (M)[2][1]) - (M)[0][1] * ((M)[1][0] * (M)[2][2] - (M)[1][2] * (M)[2][0]) + (M)[0][2] * ((M)[1][0] * (M)[2][1] - (M)[1][1] * (M)[2][0]))
    double d = DET3(A), c[3];
    for (int k = 0; k < 3; k++) {
        double B[3][3];
        memcpy(B, A, sizeof B);
        for (int i = 0; i < 3; i++) B[i][k] = r[i];
        c[k] = DET3(B) / d;
    }
    double R = sqrt((c[0] - p[0][0]) * (c[0] - p[0][0]) + (c[1] - p[0][1]) * (c[1] - p[0][1]) + (c[2] - p[0][2]) * (c[2] - p[0][2]));
    double e = INFINITY;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            e = fmin(e, sqrt((p[i][0] - p[j][0]) * (p[i][0] - p[j][0]) + (p[i][1] - p[j][1]) * (p[i][1] - p[j][1]) +
                             (p[i][2] - p[j][2]) * (p[i][2] - p[j][2])));
    return R / e;
}

static double q_of(const double p[4][3], double bound, double scale)
{
    const double *pp[4] = {p[0], p[1], p[2], p[3]};
    return mesh_tet_quality(pp, bound, scale);
}

/* the expected quality, from the independent figures */
static double expected(const double p[4][3], double bound, double scale)
{
    double s = min_sine(p), re = radius_edge(p);
    if (!(bound > 0) || re <= bound) return s;
    return fmin(s, scale / re);
}

static void test_quality(void)
{
    const double B = 1.6, S = sin(15 * M_PI / 180) * B; /* the mesher's bound and target */
    /* the regular tetrahedron: sine 2 sqrt(2) / 3, radius-edge sqrt(6) / 4 */
    const double reg[4][3] = {{1, 1, 1}, {-1, 1, -1}, {1, -1, -1}, {-1, -1, 1}};
    const double *pr[4] = {reg[0], reg[1], reg[2], reg[3]};
    CHECK(thx_orient3d(pr[0], pr[1], pr[2], pr[3]) < 0); /* right-handed, as the repair stores them */
    CHECK_NEAR(q_of(reg, B, S), 2 * sqrt(2) / 3, 1e-12);
    CHECK_NEAR(radius_edge(reg), sqrt(6) / 4, 1e-12);
    /* the corner tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,2.5): radius-edge sqrt(0.5 + 2.5^2 / 4)
       = 1.436, between sqrt(B) = 1.265 and B; smallest dihedral 47.1 deg. Within the bound: the
       dihedral sine (0.733), not S / RE (0.288) */
    const double cor[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 2.5}};
    CHECK_NEAR(radius_edge(cor), sqrt(0.5 + 2.5 * 2.5 / 4), 1e-12);
    CHECK(radius_edge(cor) > sqrt(B) && radius_edge(cor) < B);
    CHECK_NEAR(q_of(cor, B, S), min_sine(cor), 1e-12);
    CHECK(q_of(cor, B, S) > 0.7);
    /* ... and beyond a bound of 1.3: S / RE */
    CHECK_NEAR(q_of(cor, 1.3, S), S / radius_edge(cor), 1e-12);
    /* a needle (0,0,0), (1,0,0), (0,1,0), (0,0,6): RE 3.04, fine angles: S / RE = 0.136 */
    const double nee[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 6}};
    CHECK_NEAR(q_of(nee, B, S), S / radius_edge(nee), 1e-12);
    CHECK_NEAR(q_of(nee, B, S), expected(nee, B, S), 1e-12);
    /* a long needle, RE 40: S / RE = 0.010, worse than a 0.6 deg sliver */
    const double lng[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 80}};
    CHECK(S / radius_edge(lng) < sin(1 * M_PI / 180));
    CHECK_NEAR(q_of(lng, B, S), S / radius_edge(lng), 1e-12);
    /* without a bound: the sine alone */
    CHECK_NEAR(q_of(lng, 0, 0), min_sine(lng), 1e-12);
    /* a sliver: four nearly coplanar points of a square, one lifted by 0.01: its sine */
    const double sl[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.01}};
    double qs = q_of(sl, B, S);
    CHECK(qs > 0 && qs < sin(2 * M_PI / 180));
    CHECK_NEAR(qs, expected(sl, B, S), 1e-9);
    /* flat and inverted: 0 */
    const double flat[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    CHECK(q_of(flat, B, S) == 0);
    const double inv[4][3] = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
    CHECK(q_of(inv, B, S) == 0);
    /* random tetrahedra: the function agrees with the independent figures everywhere */
    srand(7);
    int agree = 0, n = 0, needles = 0;
    for (int i = 0; i < 2000; i++) {
        double p[4][3];
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < 3; c++) p[k][c] = rand() / (double)RAND_MAX * (c == 2 && k == 3 ? 8 : 1);
        const double *pp[4] = {p[0], p[1], p[2], p[3]};
        if (thx_orient3d(pp[0], pp[1], pp[2], pp[3]) > 0) { double t[3]; memcpy(t, p[1], sizeof t); memcpy(p[1], p[2], sizeof t); memcpy(p[2], t, sizeof t); }
        double e = expected(p, B, S), re = radius_edge(p);
        if (!(min_sine(p) > 1e-6)) continue;
        n++;
        needles += re > B && S / re < min_sine(p);
        int ok = fabs(q_of(p, B, S) - e) <= 1e-9 * fmax(1, e);
        if (!ok) printf("disagree: q %.17g expected %.17g re %.17g dih %.17g\n", q_of(p, B, S), e, re, min_dihedral(p));
        agree += ok;
    }
    printf("quality: %d of %d random tetrahedra agree (%d decided by the radius-edge ratio)\n", agree, n, needles);
    CHECK(agree == n);
    CHECK(needles > 50 && needles < n - 50); /* both branches were taken */
}

/* The tetrahedra of v holding the face (a, b, c). */
static int face_count(const thx_volume *v, int32_t a, int32_t b, int32_t c)
{
    int n = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        int hit = 0;
        for (int i = 0; i < 4; i++) hit += q[i] == a || q[i] == b || q[i] == c;
        n += hit == 3;
    }
    return n;
}

static void test_insert(thx_ctx *ctx)
{
    /* A (0,0,0), B (1,0,0), C (0,1,0), D (1,1,0.02): the sliver ABCD lies on the surface triangles
       ABC and BDC (protected; nearly flat along BC, where the sliver, 1.15 deg, is the only tetrahedron);
       E (0.5,0.5,1) caps it with EABD and EACD. */
    thx_volume *v = NULL;
    CHECK_OK(ctx, thx_volume_create(ctx, &v));
    const double P[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.02}, {0.5, 0.5, 1}};
    enum { A, Bn, C, D, E };
    int32_t T[3][4] = {{A, Bn, C, D}, {E, A, Bn, D}, {E, A, D, C}};
    for (int t = 0; t < 3; t++) { /* right-handed */
        const double *q[4] = {P[T[t][0]], P[T[t][1]], P[T[t][2]], P[T[t][3]]};
        if (thx_orient3d(q[0], q[1], q[2], q[3]) > 0) { int32_t x = T[t][2]; T[t][2] = T[t][3]; T[t][3] = x; }
    }
    v->n_nodes = 5;
    v->xyz = malloc(sizeof P);
    memcpy(v->xyz, P, sizeof P);
    v->node_surf = malloc(5 * sizeof *v->node_surf);
    v->node_snode = malloc(5 * sizeof *v->node_snode);
    for (int i = 0; i < 5; i++) v->node_surf[i] = v->node_snode[i] = -1;
    for (int i = 0; i < 4; i++) v->node_surf[i] = 0; /* A..D on the surface: fixed */
    v->n_tets = 3;
    v->tet = malloc(sizeof T);
    memcpy(v->tet, T, sizeof T);
    v->region = calloc(3, sizeof *v->region);
    double before = mesh_tet_min_dihedral(v->xyz, v->tet);
    double vol0 = 0;
    for (size_t t = 0; t < v->n_tets; t++) vol0 += thx_volume_tet_volume(v, t);
    const int32_t prot[2][3] = {{A, Bn, C}, {Bn, D, C}};
    improve_opts o = {15.0, 1.6, 6, IMPROVE_INSERT, NULL, NULL, NULL, -2};
    improve_stats S;
    CHECK_OK(ctx, mesh_improve(ctx, v, NULL, &prot[0][0], 2, &o, &S));
    double after = 180, vol1 = 0;
    int positive = 1;
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        after = fmin(after, mesh_tet_min_dihedral(v->xyz, q));
        vol1 += thx_volume_tet_volume(v, t);
        positive &= thx_orient3d(v->xyz + 3 * q[0], v->xyz + 3 * q[1], v->xyz + 3 * q[2], v->xyz + 3 * q[3]) < 0;
    }
    printf("insertion: sliver %.2f deg -> smallest %.2f deg, %zu -> %zu tetrahedra, %zu nodes, %zu inserted\n", before, after,
           S.tets_before, v->n_tets, v->n_nodes, S.n_inserts);
    CHECK(before < 2);
    CHECK(S.n_inserts >= 1);
    CHECK(v->n_nodes >= 6 && v->node_surf[5] == -1 && v->node_snode[5] == -1);
    CHECK(after > 5 * before && after > 10);
    CHECK(positive);
    CHECK_NEAR(vol1, vol0, 1e-12);
    /* the surface triangles are still faces (once: on the boundary), and so is the rest of the boundary */
    CHECK(face_count(v, A, Bn, C) == 1 && face_count(v, Bn, D, C) == 1);
    CHECK(face_count(v, E, A, Bn) == 1 && face_count(v, E, Bn, D) == 1 && face_count(v, E, A, C) == 1 && face_count(v, E, D, C) == 1);
    /* the fixed nodes did not move */
    CHECK(memcmp(v->xyz, P, 4 * sizeof P[0]) == 0);
    thx_volume_destroy(&v);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    test_quality();
    test_insert(ctx);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
