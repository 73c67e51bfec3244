/*
 * Verification geometry (src/geom/verify.c, thorax/geom/verify.h): the analytic
 * shells solution satisfies its boundary value problem (checked by finite
 * differences and against an independent 4x4 solve), the cubed-sphere shell
 * mesh is a conforming, positively oriented tetrahedralization of exactly
 * the shells (boundary on r = a and r = c, interface on r = b, volume
 * converging at second order), the slab mesh and its closed form are
 * consistent (the linear potential is the discrete solution of the P1
 * problem with zero flux through the sides), RDM/MAG on hand cases, and the
 * icospheres (closed, outward, on the sphere, volume deficit of second order).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/check/check_volume.h"
#include "thorax/geom/predicates.h"
#include "thorax/geom/verify.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ------------------------------------------------------------------ */
/* Legendre polynomials */

static void test_legendre(void)
{
    const double xs[] = {-1.0, -0.73, -0.5, -0.1, 0.0, 0.2, 0.5, 0.81, 1.0};
    for (size_t k = 0; k < sizeof xs / sizeof xs[0]; k++) {
        double x = xs[k], x2 = x * x;
        CHECK_NEAR(thx_legendre(0, x), 1.0, 0.0);
        CHECK_NEAR(thx_legendre(1, x), x, 0.0);
        CHECK_NEAR(thx_legendre(2, x), (3 * x2 - 1) / 2, 1e-15);
        CHECK_NEAR(thx_legendre(3, x), (5 * x2 - 3) * x / 2, 1e-15);
        CHECK_NEAR(thx_legendre(4, x), (35 * x2 * x2 - 30 * x2 + 3) / 8, 1e-15);
        CHECK_NEAR(thx_legendre(5, x), ((63 * x2 - 70) * x2 + 15) * x / 8, 1e-15);
    }
    for (int l = 0; l <= 60; l++) {
        CHECK_NEAR(thx_legendre(l, 1.0), 1.0, 1e-13);
        CHECK_NEAR(thx_legendre(l, -1.0), l % 2 ? -1.0 : 1.0, 1e-13);
    }
    /* P_l(0) = (-1)^(l/2) (l-1)!! / l!! for even l, 0 for odd l */
    double p0 = 1.0;
    for (int l = 2; l <= 40; l += 2) {
        p0 *= -(double)(l - 1) / l;
        CHECK_NEAR(thx_legendre(l, 0.0), p0, 1e-15);
        CHECK_NEAR(thx_legendre(l + 1, 0.0), 0.0, 1e-15);
    }
    /* exact rational values (Python fractions), then rounded */
    CHECK_NEAR(thx_legendre(10, 0.5), -0.18822860717773438, 1e-15);
    CHECK_NEAR(thx_legendre(20, 0.3), 0.18028715947998047, 1e-13);
    CHECK_NEAR(thx_legendre(7, -0.9), 0.36782499375, 1e-13);
    CHECK_NEAR(thx_legendre(50, 1.0 / 3.0), 0.013396887820779106, 1e-13);
    CHECK_NEAR(thx_legendre(100, 0.7), -0.077132507199779113, 1e-12);
    CHECK(isnan(thx_legendre(-1, 0.5)));
}

/* ------------------------------------------------------------------ */
/* The shells solution */

#define RA 40.0
#define RB 70.0
#define RC 100.0

static double radial(int l, double s1, double s2, double r)
{
    return thx_shells_potential(l, RA, RB, RC, s1, s2, r, 1.0);
}

/* derivative at x0 of the quadratic through x0 + d h, x0 + 2 d h, x0 + 3 d h
 * (d = -1: from the left, +1: from the right); extrapolated value likewise */
static double left_or_right_derivative(int l, double s1, double s2, double x0, double h, int d)
{
    double f1 = radial(l, s1, s2, x0 + d * h), f2 = radial(l, s1, s2, x0 + 2 * d * h),
           f3 = radial(l, s1, s2, x0 + 3 * d * h);
    return -d * (2.5 * f1 - 4.0 * f2 + 1.5 * f3) / h;
}
static double left_or_right_value(int l, double s1, double s2, double x0, double h, int d)
{
    return 3.0 * radial(l, s1, s2, x0 + d * h) - 3.0 * radial(l, s1, s2, x0 + 2 * d * h) +
           radial(l, s1, s2, x0 + 3 * d * h);
}

/* Gaussian elimination with partial pivoting, n x n row-major, in place. */
static void gauss(int n, double *A, double *x)
{
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k])) p = i;
        for (int j = 0; j < n; j++) {
            double t = A[k * n + j];
            A[k * n + j] = A[p * n + j];
            A[p * n + j] = t;
        }
        double t = x[k];
        x[k] = x[p];
        x[p] = t;
        for (int i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            for (int j = k; j < n; j++) A[i * n + j] -= f * A[k * n + j];
            x[i] -= f * x[k];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        for (int j = k + 1; j < n; j++) x[k] -= A[k * n + j] * x[j];
        x[k] /= A[k * n + k];
    }
}

/* The radial function from the raw 4x4 system in A r^l + B r^-(l+1) form. */
static double radial_4x4(int l, double s1, double s2, double r)
{
    double a = RA, b = RB, c = RC, L = l;
    double M[16] = {pow(a, L), pow(a, -L - 1), 0, 0,
                    pow(b, L), pow(b, -L - 1), -pow(b, L), -pow(b, -L - 1),
                    s1 * L * pow(b, L - 1), -s1 * (L + 1) * pow(b, -L - 2), -s2 * L * pow(b, L - 1), s2 * (L + 1) * pow(b, -L - 2),
                    0, 0, L * pow(c, L - 1), -(L + 1) * pow(c, -L - 2)};
    double x[4] = {1, 0, 0, 0};
    gauss(4, M, x);
    return r < b ? x[0] * pow(r, L) + x[1] * pow(r, -L - 1) : x[2] * pow(r, L) + x[3] * pow(r, -L - 1);
}

static double potential_xyz(int l, double s1, double s2, const double p[3])
{
    double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return thx_shells_potential(l, RA, RB, RC, s1, s2, r, p[2] / r);
}

static void test_shells_solution(void)
{
    const double ratios[] = {1.0, 1.0 / 80.0, 5.0};
    const double cts[] = {-1.0, -0.6, 0.0, 0.3, 0.77, 1.0};
    const double s1 = 0.2;
    for (int l = 0; l <= 3; l++)
        for (int q = 0; q < 3; q++) {
            double s2 = s1 * ratios[q];
            /* phi(a, ct) = P_l(ct) */
            for (int k = 0; k < 6; k++)
                CHECK_NEAR(thx_shells_potential(l, RA, RB, RC, s1, s2, RA, cts[k]), thx_legendre(l, cts[k]), 1e-13);
            /* angular dependence: P_l(ct) times the radial function */
            for (double r = RA; r <= RC; r += 7.5)
                CHECK_NEAR(thx_shells_potential(l, RA, RB, RC, s1, s2, r, 0.3), radial(l, s1, s2, r) * thx_legendre(l, 0.3),
                           1e-14);
            double scale = 0.0; /* typical |dR/dr| */
            for (double r = RA; r <= RC; r += 1.0) scale = fmax(scale, fabs(radial(l, s1, s2, r)));
            scale /= RC - RA;
            double h = 1e-4 * RB;
            /* continuity of phi at b: from both sides, and the value at b */
            double vl = left_or_right_value(l, s1, s2, RB, h, -1), vr = left_or_right_value(l, s1, s2, RB, h, +1);
            CHECK_NEAR(vl, vr, 1e-9);
            CHECK_NEAR(vl, radial(l, s1, s2, RB), 1e-9);
            /* continuity of the normal current s dphi/dr at b */
            double dl = left_or_right_derivative(l, s1, s2, RB, h, -1), dr = left_or_right_derivative(l, s1, s2, RB, h, +1);
            double jl = s1 * dl, jr = s2 * dr;
            CHECK_NEAR(jl, jr, 1e-6 * fmax(s1, s2) * scale + 1e-15);
            if (l > 0 && ratios[q] != 1.0) CHECK(fabs(dl - dr) > 1e-3 * scale); /* the kink is there */
            /* no current through r = c */
            CHECK_NEAR(left_or_right_derivative(l, s1, s2, RC, 1e-4 * RC, -1), 0.0, 1e-6 * scale + 1e-15);
            /* against the raw 4x4 system */
            for (double r = RA; r <= RC; r += 2.5)
                CHECK_NEAR(radial(l, s1, s2, r), radial_4x4(l, s1, s2, r), 1e-10);
            /* harmonic: the 7-point Laplacian in Cartesian coordinates, one point per shell */
            const double pts[2][3] = {{20.0, -30.0, 35.0}, {-50.0, 31.0, -40.0}}; /* r = 50.2, 71.5 */
            for (int k = 0; k < 2; k++) {
                double p[3] = {pts[k][0], pts[k][1], pts[k][2]}, hh = 0.01, lap = 0.0, size = 0.0;
                double f0 = potential_xyz(l, s1, s2, p);
                for (int d = 0; d < 3; d++) {
                    double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
                    pp[d] += hh;
                    pm[d] -= hh;
                    double d2 = (potential_xyz(l, s1, s2, pp) - 2 * f0 + potential_xyz(l, s1, s2, pm)) / (hh * hh);
                    lap += d2;
                    size += fabs(d2);
                }
                /* truncation h^2/12 f'''' and rounding eps f/h^2: about 1e-7 of the terms here */
                CHECK_NEAR(lap, 0.0, 1e-5 * size + 1e-12);
            }
            if (l == 0) /* the constant */
                for (double r = RA; r <= RC; r += 3.0) CHECK_NEAR(thx_shells_potential(0, RA, RB, RC, s1, s2, r, 0.4), 1.0, 1e-15);
            if (l > 0 && ratios[q] == 1.0) {
                /* single shell: A r^l + B r^-(l+1), B = l/(l+1) c^(2l+1) A, phi(a) = 1 */
                double L = l, A = 1.0 / (pow(RA, L) + L / (L + 1) * pow(RC, 2 * L + 1) * pow(RA, -L - 1));
                double B = L / (L + 1) * pow(RC, 2 * L + 1) * A;
                for (double r = RA; r <= RC; r += 3.0)
                    CHECK_NEAR(radial(l, s1, s2, r), A * pow(r, L) + B * pow(r, -L - 1), 1e-13);
            }
        }
    /* physically: with s2 = s1/80 the outer shell nearly insulates -> nearly no current flows
     * anywhere and phi is nearly uniform in radius; check the monotone trend at c */
    double f1 = radial(1, 1.0, 1.0 / 80.0, RC), f2 = radial(1, 1.0, 1.0, RC), f3 = radial(1, 1.0, 5.0, RC);
    CHECK(f1 > f2 && f2 > f3 && f3 > 0.0);
    /* invalid arguments */
    CHECK(isnan(thx_shells_potential(-1, RA, RB, RC, 1, 1, 50, 0)));
    CHECK(isnan(thx_shells_potential(1, RB, RA, RC, 1, 1, 50, 0)));
    CHECK(isnan(thx_shells_potential(1, RA, RB, RC, 0, 1, 50, 0)));
    CHECK(isnan(thx_shells_potential(1, RA, RB, RC, 1, 1, 30, 0)));
    CHECK(isnan(thx_shells_potential(1, RA, RB, RC, 1, 1, 101, 0)));
    /* large l stays finite and right at a */
    CHECK_NEAR(thx_shells_potential(60, RA, RB, RC, 1, 3, RA, 1.0), 1.0, 1e-12);
    CHECK(isfinite(thx_shells_potential(60, RA, RB, RC, 1, 3, RC, 0.5)));
}

/* ------------------------------------------------------------------ */
/* Mesh helpers */

typedef struct { int32_t a, b, c, t; } face_rec;

static int cmp_face(const void *x, const void *y)
{
    const face_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return (p->c > q->c) - (p->c < q->c);
}

static face_rec sorted_face(int32_t a, int32_t b, int32_t c, int32_t t)
{
    int32_t x;
    if (a > b) { x = a; a = b; b = x; }
    if (b > c) { x = b; b = c; c = x; }
    if (a > b) { x = a; a = b; b = x; }
    return (face_rec){a, b, c, t};
}

/* outward faces of a right-handed tetrahedron (check_volume.h) */
static const int out_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

static const double *node(const thx_volume *v, int32_t i) { return v->xyz + 3 * (size_t)i; }
static double radius(const thx_volume *v, int32_t i)
{
    const double *p = node(v, i);
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
}

typedef struct {
    int32_t n[3]; /* oriented outward */
} tri;

/* Sorted faces (all 4 per tetrahedron). */
static face_rec *all_faces(const thx_volume *v)
{
    face_rec *f = malloc(4 * v->n_tets * sizeof *f);
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        for (int k = 0; k < 4; k++)
            f[4 * t + k] = sorted_face(q[out_face[k][0]], q[out_face[k][1]], q[out_face[k][2]], (int32_t)(4 * t + k));
    }
    qsort(f, 4 * v->n_tets, sizeof *f, cmp_face);
    return f;
}

static tri oriented_face(const thx_volume *v, int32_t tk)
{
    const int32_t *q = v->tet + 4 * (size_t)(tk / 4);
    tri r = {{q[out_face[tk % 4][0]], q[out_face[tk % 4][1]], q[out_face[tk % 4][2]]}};
    return r;
}

typedef struct { int32_t a, b; } edge_rec;
static int cmp_edge(const void *x, const void *y)
{
    const edge_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

/* A closed, consistently oriented 2-manifold surface of Euler characteristic
 * 2 on exactly n_expected nodes: every directed edge once and its reverse once,
 * the faces around every node one cycle, V - E + F = 2. */
static int closed_sphere(const tri *t, size_t nt, size_t n_expected)
{
    size_t nc = 3 * nt;
    edge_rec *e = malloc(nc * sizeof *e), *cn = malloc(nc * sizeof *cn);
    int32_t *nx = malloc(nc * sizeof *nx), *pv = malloc(nc * sizeof *pv);
    for (size_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            e[3 * i + k] = (edge_rec){t[i].n[k], t[i].n[(k + 1) % 3]};
            cn[3 * i + k] = (edge_rec){t[i].n[k], (int32_t)(3 * i + k)}; /* corners by node */
        }
    qsort(e, nc, sizeof *e, cmp_edge);
    qsort(cn, nc, sizeof *cn, cmp_edge);
    int ok = 1;
    for (size_t i = 0; i + 1 < nc; i++)
        if (!cmp_edge(&e[i], &e[i + 1])) ok = 0; /* a directed edge twice */
    for (size_t i = 0; i < nc && ok; i++) {
        edge_rec r = {e[i].b, e[i].a};
        if (!bsearch(&r, e, nc, sizeof *e, cmp_edge)) ok = 0; /* no twin: open */
    }
    /* the link of every node: its faces' (next, prev) corners chain into one cycle */
    size_t n_nodes = 0;
    for (size_t i = 0; i < nc && ok;) {
        size_t j = i;
        while (j < nc && cn[j].a == cn[i].a) j++;
        n_nodes++;
        size_t deg = j - i;
        for (size_t m = 0; m < deg; m++) {
            size_t corner = (size_t)cn[i + m].b, f = corner / 3;
            int k = (int)(corner % 3);
            nx[m] = t[f].n[(k + 1) % 3];
            pv[m] = t[f].n[(k + 2) % 3];
        }
        size_t cur = 0, steps = 0;
        do { /* the face after cur around the node starts where cur ends */
            size_t found = deg;
            for (size_t m = 0; m < deg; m++)
                if (nx[m] == pv[cur]) { found = m; break; }
            if (found == deg) { ok = 0; break; }
            cur = found;
            steps++;
        } while (cur != 0 && steps <= deg);
        if (steps != deg) ok = 0;
        i = j;
    }
    long chi = (long)n_nodes - (long)(nc / 2) + (long)nt;
    if (chi != 2 || n_nodes != n_expected) ok = 0;
    free(e);
    free(cn);
    free(nx);
    free(pv);
    return ok;
}

static int cmp_i32(const void *x, const void *y)
{
    int32_t a = *(const int32_t *)x, b = *(const int32_t *)y;
    return (a > b) - (a < b);
}

static const double *sort_xyz;
static int cmp_node_x(const void *x, const void *y)
{
    double a = sort_xyz[3 * (size_t)*(const int32_t *)x], b = sort_xyz[3 * (size_t)*(const int32_t *)y];
    return (a > b) - (a < b);
}

/* Smallest distance between two distinct nodes (sweep in x). */
static double min_node_distance(const thx_volume *v)
{
    int32_t *o = malloc(v->n_nodes * sizeof *o);
    for (size_t i = 0; i < v->n_nodes; i++) o[i] = (int32_t)i;
    sort_xyz = v->xyz;
    qsort(o, v->n_nodes, sizeof *o, cmp_node_x);
    double best = INFINITY;
    for (size_t i = 0; i < v->n_nodes; i++)
        for (size_t j = i + 1; j < v->n_nodes; j++) {
            const double *p = node(v, o[i]), *q = node(v, o[j]);
            if (q[0] - p[0] >= best) break;
            double d = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            best = fmin(best, d);
        }
    free(o);
    return best;
}

static double min_dihedral(const thx_volume *v)
{
    double mn = INFINITY;
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        double d;
        thx_tet_quality(node(v, q[0]), node(v, q[1]), node(v, q[2]), node(v, q[3]), &d, NULL, NULL, NULL);
        mn = fmin(mn, d);
    }
    return mn;
}

static size_t n_positive(const thx_volume *v)
{
    size_t np = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        np += thx_orient3d(node(v, q[0]), node(v, q[1]), node(v, q[2]), node(v, q[3])) < 0.0;
        np -= !(thx_volume_tet_volume(v, t) > 0.0); /* the floating-point volume agrees */
    }
    return np;
}

static void check_node_tables_empty(const thx_volume *v)
{
    CHECK(v->n_surfaces == 0);
    CHECK(v->node_surf != NULL && v->node_snode != NULL);
    if (!v->node_surf || !v->node_snode) return;
    size_t bad = 0;
    for (size_t i = 0; i < v->n_nodes; i++) bad += v->node_surf[i] != -1 || v->node_snode[i] != -1;
    CHECK(bad == 0);
}

static void run_volume_check(thx_ctx *ctx, const thx_volume *v, int cavities)
{
    thx_volume_check_opts o;
    thx_volume_check_opts_default(&o);
    o.expected_cavities = cavities;
    thx_volume_report r;
    CHECK_OK(ctx, thx_volume_check(ctx, v, NULL, &o, &r));
    CHECK(r.ok && r.n_shells == 1 && r.n_cavities == (size_t)cavities && r.n_nonconforming_faces == 0 &&
          r.n_overlapping_faces == 0 && r.n_duplicate_nodes == 0 && r.n_unused_nodes == 0);
    thx_volume_report_free(&r);
}

/* ------------------------------------------------------------------ */
/* Shells mesh */

typedef struct {
    double volume, volume0; /* total, region 0 */
    double min_dihedral;
} shells_figures;

static void test_shells_mesh_one(thx_ctx *ctx, int n, int nr1, int nr2, shells_figures *fig)
{
    const double a = RA, b = RB, c = RC, s1 = 0.2, s2 = 0.0025;
    thx_volume *v = NULL;
    int32_t *inner = NULL, *outer = NULL;
    size_t ni = 0, no = 0;
    CHECK_OK(ctx, thx_shells_mesh(ctx, a, b, c, s1, s2, n, nr1, nr2, &v, &inner, &ni, &outer, &no));
    if (!v) return;
    size_t ns = 6 * (size_t)n * n + 2, nq = 6 * (size_t)n * n;
    CHECK(v->n_nodes == ns * (size_t)(nr1 + nr2 + 1));
    CHECK(v->n_tets == 6 * nq * (size_t)(nr1 + nr2));
    CHECK(ni == ns && no == ns);

    /* regions */
    CHECK(v->n_regions == 2);
    CHECK(!strcmp(v->regions[0].name, "inner_shell") && !strcmp(v->regions[1].name, "outer_shell"));
    CHECK(!strcmp(v->regions[0].source, "verification") && !strcmp(v->regions[1].source, "verification"));
    CHECK(!v->regions[0].anisotropic && !v->regions[1].anisotropic);
    CHECK(v->regions[0].sigma[0] == s1 && v->regions[0].sigma[4] == s1 && v->regions[0].sigma[8] == s1 &&
          v->regions[0].sigma[1] == 0.0 && v->regions[1].sigma[0] == s2 && v->regions[1].sigma[8] == s2 &&
          v->regions[1].sigma[5] == 0.0);
    check_node_tables_empty(v);

    /* every node on one of the layer spheres; inner/outer exactly the nodes on r = a / r = c */
    size_t off = 0;
    int32_t *on_a = malloc(v->n_nodes * sizeof *on_a), *on_c = malloc(v->n_nodes * sizeof *on_c);
    size_t na = 0, nc = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        double r = radius(v, (int32_t)i);
        int hit = 0;
        for (int L = 0; L <= nr1 + nr2; L++) {
            double rl = L <= nr1 ? a + (b - a) * L / nr1 : b + (c - b) * (L - nr1) / nr2;
            hit |= fabs(r - rl) <= 1e-12 * c;
        }
        off += !hit;
        if (fabs(r - a) <= 1e-12 * a) on_a[na++] = (int32_t)i;
        if (fabs(r - c) <= 1e-12 * c) on_c[nc++] = (int32_t)i;
    }
    CHECK(off == 0);
    qsort(inner, ni, sizeof *inner, cmp_i32);
    qsort(outer, no, sizeof *outer, cmp_i32);
    CHECK(na == ni && !memcmp(on_a, inner, ni * sizeof *inner));
    CHECK(nc == no && !memcmp(on_c, outer, no * sizeof *outer));
    free(on_a);
    free(on_c);

    /* no duplicate nodes (merged across the cube's edges and corners) */
    double dmin = min_node_distance(v);
    CHECK(dmin > 1e-3);

    /* every tetrahedron right-handed (exact), regions by the centroid's radius */
    CHECK(n_positive(v) == v->n_tets);
    size_t bad_region = 0;
    double vol = 0.0, vol0 = 0.0;
    for (size_t t = 0; t < v->n_tets; t++) {
        /* region 0 iff all four nodes have r <= b, region 1 iff all have r >= b: none crosses r = b */
        const int32_t *q = v->tet + 4 * t;
        double rmin = INFINITY, rmax = 0.0;
        for (int k = 0; k < 4; k++) {
            rmin = fmin(rmin, radius(v, q[k]));
            rmax = fmax(rmax, radius(v, q[k]));
        }
        int expect = rmax <= b * (1 + 1e-12) ? 0 : rmin >= b * (1 - 1e-12) ? 1 : -1;
        bad_region += v->region[t] != expect;
        double tv = thx_volume_tet_volume(v, t);
        vol += tv;
        if (v->region[t] == 0) vol0 += tv;
    }
    CHECK(bad_region == 0);

    /* conformity: each face in 1 or 2 tetrahedra; boundary faces exactly the triangles on r = a and
     * r = c (12 n^2 each), each a closed sphere; faces on r = b: 12 n^2, all interior, between
     * regions 0 and 1, and every other interior face inside one region */
    face_rec *f = all_faces(v);
    size_t nf = 4 * v->n_tets, over = 0, nb_a = 0, nb_c = 0, nb_other = 0, n_b = 0, b_bad = 0, region_jump = 0;
    size_t wrong_side = 0;
    tri *ta = malloc(nf * sizeof *ta), *tc = malloc(nf * sizeof *tc);
    for (size_t i = 0; i < nf;) {
        size_t j = i;
        while (j < nf && !cmp_face(&f[i], &f[j])) j++;
        double ra = radius(v, f[i].a), rb = radius(v, f[i].b), rc = radius(v, f[i].c);
        int all_a = fabs(ra - a) < 1e-9 && fabs(rb - a) < 1e-9 && fabs(rc - a) < 1e-9;
        int all_b = fabs(ra - b) < 1e-9 && fabs(rb - b) < 1e-9 && fabs(rc - b) < 1e-9;
        int all_c = fabs(ra - c) < 1e-9 && fabs(rb - c) < 1e-9 && fabs(rc - c) < 1e-9;
        if (j - i > 2) over++;
        if (j - i == 1) {
            tri t = oriented_face(v, f[i].t);
            /* outward normal: away from the centre on r = c, toward it on r = a */
            const double *p0 = node(v, t.n[0]), *p1 = node(v, t.n[1]), *p2 = node(v, t.n[2]);
            double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            double dot = nrm[0] * (p0[0] + p1[0] + p2[0]) + nrm[1] * (p0[1] + p1[1] + p2[1]) + nrm[2] * (p0[2] + p1[2] + p2[2]);
            if (all_a) { ta[nb_a++] = t; wrong_side += !(dot < 0); }
            else if (all_c) { tc[nb_c++] = t; wrong_side += !(dot > 0); }
            else nb_other++;
        }
        if (j - i == 2) {
            int r0 = v->region[f[i].t / 4], r1 = v->region[f[i + 1].t / 4];
            if (all_b) {
                n_b++;
                b_bad += r0 == r1;
            } else {
                region_jump += r0 != r1;
            }
            if (all_a || all_c) nb_other++; /* a face on the boundary spheres inside the mesh */
        } else if (all_b) {
            b_bad++;
        }
        i = j;
    }
    CHECK(over == 0);
    CHECK(nb_other == 0);
    CHECK(nb_a == 2 * nq && nb_c == 2 * nq);
    CHECK(wrong_side == 0);
    CHECK(n_b == 2 * nq && b_bad == 0 && region_jump == 0);
    CHECK(closed_sphere(ta, nb_a, ns));
    CHECK(closed_sphere(tc, nb_c, ns));
    free(ta);
    free(tc);
    free(f);

    /* the project's own volume checker agrees: one shell, one cavity */
    if (n <= 8) run_volume_check(ctx, v, 1);

    fig->volume = vol;
    fig->volume0 = vol0;
    fig->min_dihedral = min_dihedral(v);
    printf("shells n = %2d, nr1 = %d, nr2 = %d: %zu nodes, %zu tetrahedra, min dihedral %.2f deg, "
           "min node distance %.3f mm, volume %.1f mm^3 (analytic %.1f)\n",
           n, nr1, nr2, v->n_nodes, v->n_tets, fig->min_dihedral, dmin, vol, 4.0 / 3.0 * M_PI * (c * c * c - a * a * a));
    CHECK(fig->min_dihedral > (n >= 4 ? 15.0 : 5.0));
    free(inner);
    free(outer);
    thx_volume_destroy(&v);
    CHECK(v == NULL);
}

static void test_shells_mesh(thx_ctx *ctx)
{
    const double a = RA, b = RB, c = RC;
    double exact = 4.0 / 3.0 * M_PI * (c * c * c - a * a * a), exact0 = 4.0 / 3.0 * M_PI * (b * b * b - a * a * a);
    shells_figures fig[3];
    int ns[3] = {4, 8, 16};
    for (int k = 0; k < 3; k++) test_shells_mesh_one(ctx, ns[k], ns[k] / 2, ns[k] / 2, &fig[k]);
    /* odd n and the coarsest case, uneven layers */
    shells_figures extra;
    test_shells_mesh_one(ctx, 1, 1, 1, &extra);
    test_shells_mesh_one(ctx, 5, 3, 2, &extra);
    /* second-order convergence of the volume (inscribed polyhedra: from below) */
    double e[3], e0[3];
    for (int k = 0; k < 3; k++) {
        e[k] = (exact - fig[k].volume) / exact;
        e0[k] = (exact0 - fig[k].volume0) / exact0;
        CHECK(e[k] > 0.0 && e0[k] > 0.0);
    }
    printf("shells volume: relative error %.3e, %.3e, %.3e (ratios %.2f, %.2f); inner shell %.3e, %.3e, %.3e\n", e[0],
           e[1], e[2], e[0] / e[1], e[1] / e[2], e0[0], e0[1], e0[2]);
    CHECK(e[0] / e[1] > 3.5 && e[0] / e[1] < 4.5);
    CHECK(e[1] / e[2] > 3.7 && e[1] / e[2] < 4.3);
    CHECK(e0[1] / e0[2] > 3.7 && e0[1] / e0[2] < 4.3);
    CHECK(e[2] < 5e-3);

    /* bad input: nothing returned */
    thx_volume *v = (thx_volume *)1;
    int32_t *in = (int32_t *)1, *out = (int32_t *)1;
    size_t ni = 7, no = 7;
    CHECK(thx_shells_mesh(ctx, b, a, c, 1, 1, 4, 2, 2, &v, &in, &ni, &out, &no) == THX_EINPUT);
    CHECK(v == NULL && in == NULL && out == NULL && ni == 0 && no == 0);
    CHECK(strlen(thx_ctx_message(ctx)) > 0);
    CHECK(thx_shells_mesh(ctx, a, b, c, 1, 1, 0, 2, 2, &v, &in, &ni, &out, &no) == THX_EINPUT);
    CHECK(thx_shells_mesh(ctx, a, b, c, 1, 1, 4, 0, 2, &v, &in, &ni, &out, &no) == THX_EINPUT);
    CHECK(thx_shells_mesh(ctx, a, b, c, 1, -1, 4, 2, 2, &v, &in, &ni, &out, &no) == THX_EINPUT);
    CHECK(thx_shells_mesh(ctx, a, b, NAN, 1, 1, 4, 2, 2, &v, &in, &ni, &out, &no) == THX_EINPUT);
    thx_ctx_clear(ctx);
    /* layers far thinner than the sag of the cells (1e-7 against about 0.1) still give only
     * right-handed tetrahedra: every cell's smallest node is on its inner layer, under the
     * smallest node of its outer face (src/geom/verify.c) */
    CHECK_OK(ctx, thx_shells_mesh(ctx, 1.0, 1.0 + 1e-7, 2.0, 1, 1, 3, 1, 1, &v, &in, &ni, &out, &no));
    if (v) CHECK(n_positive(v) == v->n_tets);
    thx_volume_destroy(&v);
    free(in);
    free(out);
}

/* ------------------------------------------------------------------ */
/* Slab */

/* Gradients of the 4 P1 basis functions of tetrahedron t (constant), and its volume. */
static double p1_gradients(const thx_volume *v, size_t t, double g[4][3])
{
    const int32_t *q = v->tet + 4 * t;
    const double *p0 = node(v, q[0]);
    double J[3][3]; /* rows: p_k - p0 */
    for (int k = 0; k < 3; k++)
        for (int d = 0; d < 3; d++) J[k][d] = node(v, q[k + 1])[d] - p0[d];
    double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                 J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    /* grad N_k (k = 1..3) = columns of J^-1: (J^-1)[d][k-1] */
    double inv[3][3];
    inv[0][0] = (J[1][1] * J[2][2] - J[1][2] * J[2][1]) / det;
    inv[0][1] = (J[0][2] * J[2][1] - J[0][1] * J[2][2]) / det;
    inv[0][2] = (J[0][1] * J[1][2] - J[0][2] * J[1][1]) / det;
    inv[1][0] = (J[1][2] * J[2][0] - J[1][0] * J[2][2]) / det;
    inv[1][1] = (J[0][0] * J[2][2] - J[0][2] * J[2][0]) / det;
    inv[1][2] = (J[0][2] * J[1][0] - J[0][0] * J[1][2]) / det;
    inv[2][0] = (J[1][0] * J[2][1] - J[1][1] * J[2][0]) / det;
    inv[2][1] = (J[0][1] * J[2][0] - J[0][0] * J[2][1]) / det;
    inv[2][2] = (J[0][0] * J[1][1] - J[0][1] * J[1][0]) / det;
    for (int k = 1; k < 4; k++)
        for (int d = 0; d < 3; d++) g[k][d] = inv[d][k - 1];
    for (int d = 0; d < 3; d++) g[0][d] = -(g[1][d] + g[2][d] + g[3][d]);
    return det / 6.0;
}

static void test_slab(thx_ctx *ctx)
{
    const double L = 30.0, W = 10.0, H = 5.0;
    const int nx = 6, ny = 3, nz = 2;
    /* fibres along (cos 30, sin 30 cos 20, sin 30 sin 20): 0.5 along, 0.05 across */
    double fdir[3] = {cos(M_PI / 6), sin(M_PI / 6) * cos(M_PI / 9), sin(M_PI / 6) * sin(M_PI / 9)};
    double sigma[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) sigma[3 * i + j] = 0.05 * (i == j) + 0.45 * fdir[i] * fdir[j];
    for (int i = 0; i < 3; i++) /* exactly symmetric */
        for (int j = 0; j < i; j++) sigma[3 * i + j] = sigma[3 * j + i];

    thx_volume *v = NULL;
    int32_t *ends = NULL;
    size_t ne = 0;
    CHECK_OK(ctx, thx_slab_mesh(ctx, L, W, H, nx, ny, nz, sigma, &v, &ends, &ne));
    if (!v) return;
    CHECK(v->n_nodes == (size_t)(nx + 1) * (ny + 1) * (nz + 1));
    CHECK(v->n_tets == 6 * (size_t)nx * ny * nz);
    CHECK(v->n_regions == 1 && !strcmp(v->regions[0].name, "slab") && v->regions[0].anisotropic &&
          !strcmp(v->regions[0].source, "verification") && !memcmp(v->regions[0].sigma, sigma, sizeof sigma));
    check_node_tables_empty(v);
    CHECK(n_positive(v) == v->n_tets);
    double vol = 0.0;
    for (size_t t = 0; t < v->n_tets; t++) vol += thx_volume_tet_volume(v, t);
    CHECK_NEAR(vol, L * W * H, 1e-10 * L * W * H);
    CHECK(min_node_distance(v) > 1.0);
    printf("slab %dx%dx%d: %zu nodes, %zu tetrahedra, min dihedral %.2f deg\n", nx, ny, nz, v->n_nodes, v->n_tets,
           min_dihedral(v));
    CHECK(min_dihedral(v) > 20.0);
    run_volume_check(ctx, v, 0);

    /* boundary faces all on the box's planes, area 2 (LW + LH + WH) */
    face_rec *f = all_faces(v);
    size_t nf = 4 * v->n_tets, over = 0, off_planes = 0;
    double area = 0.0;
    for (size_t i = 0; i < nf;) {
        size_t j = i;
        while (j < nf && !cmp_face(&f[i], &f[j])) j++;
        if (j - i > 2) over++;
        if (j - i == 1) {
            const double *p[3] = {node(v, f[i].a), node(v, f[i].b), node(v, f[i].c)};
            const double lim[3] = {L, W, H};
            int on = 0;
            for (int d = 0; d < 3; d++)
                on |= (p[0][d] == 0 && p[1][d] == 0 && p[2][d] == 0) ||
                      (p[0][d] == lim[d] && p[1][d] == lim[d] && p[2][d] == lim[d]);
            off_planes += !on;
            double e1[3], e2[3];
            for (int d = 0; d < 3; d++) e1[d] = p[1][d] - p[0][d], e2[d] = p[2][d] - p[0][d];
            double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
            area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        }
        i = j;
    }
    free(f);
    CHECK(over == 0 && off_planes == 0);
    CHECK_NEAR(area, 2 * (L * W + L * H + W * H), 1e-9);

    /* ends: exactly the nodes on x = 0 and x = L */
    size_t n_end_nodes = 0;
    for (size_t i = 0; i < v->n_nodes; i++) n_end_nodes += v->xyz[3 * i] == 0.0 || v->xyz[3 * i] == L;
    CHECK(ne == n_end_nodes && ne == 2 * (size_t)(ny + 1) * (nz + 1));
    qsort(ends, ne, sizeof *ends, cmp_i32);
    size_t bad_end = 0;
    for (size_t k = 0; k < ne; k++) {
        double x = v->xyz[3 * (size_t)ends[k]];
        bad_end += !(x == 0.0 || x == L) || (k && ends[k] == ends[k - 1]);
    }
    CHECK(bad_end == 0);

    /* the closed form: linear, 0 at the origin, L at (L, 0, 0) */
    const double o[3] = {0, 0, 0}, pl[3] = {L, 0, 0};
    CHECK_NEAR(thx_slab_potential(sigma, o), 0.0, 0.0);
    CHECK_NEAR(thx_slab_potential(sigma, pl), L, 1e-12);
    double g[3];
    for (int d = 0; d < 3; d++) {
        double e[3] = {0, 0, 0};
        e[d] = 1.0;
        g[d] = thx_slab_potential(sigma, e);
    }
    CHECK_NEAR(g[0], 1.0, 1e-15);
    size_t nonlinear = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        const double *p = node(v, (int32_t)i);
        nonlinear += fabs(thx_slab_potential(sigma, p) - (g[0] * p[0] + g[1] * p[1] + g[2] * p[2])) > 1e-12;
    }
    CHECK(nonlinear == 0);
    /* g = sigma^-1 e_x / (sigma^-1)_xx, solved independently */
    double S[9], x[3] = {1, 0, 0};
    memcpy(S, sigma, sizeof S);
    gauss(3, S, x);
    for (int d = 0; d < 3; d++) CHECK_NEAR(g[d], x[d] / x[0], 1e-13);
    /* current -sigma g along -x only */
    double J[3];
    for (int i = 0; i < 3; i++) J[i] = -(sigma[3 * i] * g[0] + sigma[3 * i + 1] * g[1] + sigma[3 * i + 2] * g[2]);
    CHECK(J[0] < 0.0);
    CHECK_NEAR(J[1], 0.0, 1e-15 * fabs(J[0]) + 1e-16);
    CHECK_NEAR(J[2], 0.0, 1e-15 * fabs(J[0]) + 1e-16);
    CHECK(fabs(g[1]) > 0.1 && fabs(g[2]) > 0.01); /* the case really couples x with y and z */

    /* the linear potential is the discrete (P1) solution: the residual of the
     * stiffness matrix vanishes at every node where phi is not prescribed
     * (zero flux through y = 0, W and z = 0, H is the natural condition) */
    double *res = calloc(v->n_nodes, sizeof *res), rmax = 0.0, kscale = 0.0;
    double *phi = malloc(v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = thx_slab_potential(sigma, node(v, (int32_t)i));
    for (size_t t = 0; t < v->n_tets; t++) {
        double gr[4][3];
        double tv = p1_gradients(v, t, gr);
        double gphi[3] = {0, 0, 0}, sg[3];
        for (int k = 0; k < 4; k++)
            for (int d = 0; d < 3; d++) gphi[d] += phi[v->tet[4 * t + k]] * gr[k][d];
        for (int i = 0; i < 3; i++) sg[i] = sigma[3 * i] * gphi[0] + sigma[3 * i + 1] * gphi[1] + sigma[3 * i + 2] * gphi[2];
        for (int k = 0; k < 4; k++) {
            double c = tv * (gr[k][0] * sg[0] + gr[k][1] * sg[1] + gr[k][2] * sg[2]);
            res[v->tet[4 * t + k]] += c;
            kscale = fmax(kscale, fabs(c));
        }
    }
    char *is_end = calloc(v->n_nodes, 1);
    for (size_t k = 0; k < ne; k++) is_end[ends[k]] = 1;
    double end_sum = 0.0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        if (!is_end[i]) rmax = fmax(rmax, fabs(res[i]));
        else if (v->xyz[3 * i] == 0.0) end_sum += res[i];
    }
    CHECK(rmax < 1e-12 * kscale);
    /* the current through x = 0 is |J| W H */
    CHECK_NEAR(-end_sum, fabs(J[0]) * W * H, 1e-10 * fabs(J[0]) * W * H);
    free(res);
    free(phi);
    free(is_end);
    free(ends);
    thx_volume_destroy(&v);

    /* isotropic: phi = x, so 0 on the whole end x = 0 */
    double iso[9] = {0.3, 0, 0, 0, 0.3, 0, 0, 0, 0.3};
    CHECK_OK(ctx, thx_slab_mesh(ctx, L, W, H, 2, 2, 2, iso, &v, &ends, &ne));
    if (v) {
        CHECK(!v->regions[0].anisotropic);
        size_t bad = 0;
        for (size_t k = 0; k < ne; k++) {
            const double *p = node(v, ends[k]);
            bad += thx_slab_potential(iso, p) != p[0];
        }
        CHECK(bad == 0);
    }
    free(ends);
    thx_volume_destroy(&v);
    /* diagonal anisotropic: still phi = x */
    double diag[9] = {0.5, 0, 0, 0, 0.05, 0.01, 0, 0.01, 0.04};
    const double p[3] = {3.0, 7.0, -2.0};
    CHECK_NEAR(thx_slab_potential(diag, p), 3.0, 0.0);

    /* bad input */
    double nonsym[9] = {1, 0.2, 0, 0, 1, 0, 0, 0, 1}, indef[9] = {1, 2, 0, 2, 1, 0, 0, 0, 1};
    CHECK(thx_slab_mesh(ctx, L, W, H, 2, 2, 2, nonsym, &v, &ends, &ne) == THX_EINPUT && !v && !ends && !ne);
    CHECK(thx_slab_mesh(ctx, L, W, H, 2, 2, 2, indef, &v, &ends, &ne) == THX_EINPUT && !v);
    CHECK(thx_slab_mesh(ctx, -L, W, H, 2, 2, 2, iso, &v, &ends, &ne) == THX_EINPUT && !v);
    CHECK(thx_slab_mesh(ctx, L, W, H, 0, 2, 2, iso, &v, &ends, &ne) == THX_EINPUT && !v);
    double neg[9] = {1, 0, 0, 0, -1, 0, 0, 0, 1};
    CHECK(isnan(thx_slab_potential(neg, p)));
    thx_ctx_clear(ctx);
}

/* ------------------------------------------------------------------ */
/* RDM and MAG */

static void test_rdm_mag(void)
{
    const double u[4] = {1, -2, 3, 0.5}, u2[4] = {2, -4, 6, 1}, un[4] = {-1, 2, -3, -0.5};
    CHECK_NEAR(thx_rdm(u, u, 4), 0.0, 1e-15);
    CHECK_NEAR(thx_mag(u, u, 4), 1.0, 1e-15);
    CHECK_NEAR(thx_rdm(u2, u, 4), 0.0, 1e-15); /* scale does not matter */
    CHECK_NEAR(thx_mag(u2, u, 4), 2.0, 1e-15);
    CHECK_NEAR(thx_mag(u, u2, 4), 0.5, 1e-15);
    CHECK_NEAR(thx_rdm(un, u, 4), 2.0, 1e-15); /* opposite */
    CHECK_NEAR(thx_mag(un, u, 4), 1.0, 1e-15);
    const double e1[2] = {1, 0}, e2[2] = {0, 3}, d[2] = {1, 1};
    CHECK_NEAR(thx_rdm(e1, e2, 2), sqrt(2.0), 1e-15); /* orthogonal */
    CHECK_NEAR(thx_rdm(e1, d, 2), sqrt(2.0 - sqrt(2.0)), 1e-15);
    CHECK_NEAR(thx_rdm(d, e1, 2), sqrt(2.0 - sqrt(2.0)), 1e-15);
    CHECK_NEAR(thx_mag(e1, d, 2), 1.0 / sqrt(2.0), 1e-15);
    /* nearly parallel: RDM ~ the angle, not lost to cancellation */
    const double w[2] = {1, 1e-9};
    CHECK_NEAR(thx_rdm(w, e1, 2), 1e-9, 1e-17);
    /* no overflow or underflow */
    const double big[2] = {1e200, 1e200}, bige[2] = {1e200, 0}, tiny[2] = {1e-200, 1e-200}, tinye[2] = {1e-200, 0};
    CHECK_NEAR(thx_mag(big, bige, 2), sqrt(2.0), 1e-15);
    CHECK_NEAR(thx_rdm(big, bige, 2), sqrt(2.0 - sqrt(2.0)), 1e-15);
    CHECK_NEAR(thx_mag(tiny, tinye, 2), sqrt(2.0), 1e-15);
    CHECK_NEAR(thx_rdm(tiny, bige, 2), sqrt(2.0 - sqrt(2.0)), 1e-15);
    /* undefined */
    const double z[2] = {0, 0};
    CHECK(isnan(thx_rdm(z, e1, 2)) && isnan(thx_rdm(e1, z, 2)));
    CHECK(isnan(thx_mag(e1, z, 2)));
    CHECK_NEAR(thx_mag(z, e1, 2), 0.0, 0.0);
    CHECK(isnan(thx_rdm(e1, e1, 0)) && isnan(thx_mag(e1, e1, 0)));
}

/* ------------------------------------------------------------------ */
/* Icospheres (thx_icosphere) */

static void test_icosphere(thx_ctx *ctx)
{
    double prev_edge = 0, prev_deficit = 0;
    for (int level = 0; level <= 5; level++) {
        const double r = 87.0;
        thx_surface *s = NULL;
        CHECK_OK(ctx, thx_icosphere(ctx, level, r, "ico", THX_ROLE_OTHER, &s));
        if (!s) continue;
        size_t f = (size_t)1 << (2 * level); /* 4^level */
        CHECK(s->n_nodes == 10 * f + 2 && s->n_tris == 20 * f);
        CHECK(!strcmp(s->name, "ico") && s->role == THX_ROLE_OTHER);
        /* every node on the sphere, none twice (nearest other node: at least half the shortest edge) */
        double off = 0;
        for (size_t i = 0; i < s->n_nodes; i++) {
            const double *p = s->xyz + 3 * i;
            off = fmax(off, fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - r));
        }
        CHECK(off < 1e-12 * r);
        /* closed, consistently oriented, outward (the project's surface checker, and each normal by hand) */
        tri *t = malloc(s->n_tris * sizeof *t);
        size_t outward = 0;
        double emin = INFINITY, emax = 0, esum = 0;
        for (size_t k = 0; k < s->n_tris; k++) {
            const int32_t *q = s->tri + 3 * k;
            for (int c = 0; c < 3; c++) t[k].n[c] = q[c];
            const double *a = s->xyz + 3 * (size_t)q[0], *b = s->xyz + 3 * (size_t)q[1], *c = s->xyz + 3 * (size_t)q[2];
            double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            outward += nrm[0] * (a[0] + b[0] + c[0]) + nrm[1] * (a[1] + b[1] + c[1]) + nrm[2] * (a[2] + b[2] + c[2]) > 0;
            for (int e = 0; e < 3; e++) {
                const double *p = s->xyz + 3 * (size_t)q[e], *pn = s->xyz + 3 * (size_t)q[(e + 1) % 3];
                double l = sqrt((p[0] - pn[0]) * (p[0] - pn[0]) + (p[1] - pn[1]) * (p[1] - pn[1]) + (p[2] - pn[2]) * (p[2] - pn[2]));
                emin = fmin(emin, l);
                emax = fmax(emax, l);
                esum += l;
            }
        }
        CHECK(outward == s->n_tris);
        CHECK(closed_sphere(t, s->n_tris, s->n_nodes));
        free(t);
        /* the midpoint rule keeps the triangles near-equilateral: edges within a factor 1.25 (level 5: 1.21) */
        CHECK(emax < 1.25 * emin);
        if (level <= 4) {
            thx_surface_report rep;
            CHECK_OK(ctx, thx_surface_check(ctx, s, NULL, NULL, &rep));
            CHECK(rep.ok && rep.euler == 2 && rep.n_components == 1 && rep.n_intersecting_pairs == 0 && rep.volume > 0);
            thx_surface_report_free(&rep);
        }
        /* the inscribed polyhedron's volume deficit shrinks with the edge squared (about (h/r)^2 3/8) */
        double edge = esum / (3.0 * (double)s->n_tris), deficit = 1.0 - thx_surface_volume(s) / (4.0 / 3.0 * M_PI * r * r * r);
        CHECK(deficit > 0);
        if (level >= 3) { /* (level 1 -> 2 halves the edge only roughly: 1.94) */
            double order = log(prev_deficit / deficit) / log(prev_edge / edge);
            CHECK(order > 1.95 && order < 2.05);
            CHECK(prev_edge / edge > 1.95 && prev_edge / edge < 2.05);
        }
        printf("icosphere level %d: %zu nodes, %zu triangles, mean edge %.3f mm (r = %.0f), edges %.3f..%.3f, volume deficit %.2e\n",
               level, s->n_nodes, s->n_tris, edge, r, emin, emax, deficit);
        prev_edge = edge;
        prev_deficit = deficit;
        thx_surface_destroy(&s);
    }
    thx_surface *s = NULL;
    CHECK(thx_icosphere(ctx, -1, 1.0, "x", THX_ROLE_OTHER, &s) == THX_EINPUT && !s);
    CHECK(thx_icosphere(ctx, 9, 1.0, "x", THX_ROLE_OTHER, &s) == THX_EINPUT && !s);
    CHECK(thx_icosphere(ctx, 2, 0.0, "x", THX_ROLE_OTHER, &s) == THX_EINPUT && !s);
    CHECK(thx_icosphere(ctx, 2, NAN, "x", THX_ROLE_OTHER, &s) == THX_EINPUT && !s);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_legendre();
    test_shells_solution();
    test_shells_mesh(ctx);
    test_slab(ctx);
    test_rdm_mag();
    test_icosphere(ctx);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
