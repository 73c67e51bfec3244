/* Inside/outside by angle sums (paper 3.2): 2D loops and 3D closed surfaces,
 * convex and concave, both orientations, on/near the boundary. */
#include "testlib.h"
#include "thorax/geom/inside.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#define PI 3.14159265358979323846

static thx_vec2 V2(double x, double y) { thx_vec2 v = {x, y}; return v; }

static void reverse2(thx_vec2 *p, size_t n)
{
    for (size_t i = 0; i < n / 2; i++) { thx_vec2 t = p[i]; p[i] = p[n - 1 - i]; p[n - 1 - i] = t; }
}

/* Independent reference: even-odd crossing count (for simple polygons). */
static int crossing_inside(const thx_vec2 *p, size_t n, thx_vec2 q)
{
    int c = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y) &&
            q.x < (p[j].x - p[i].x) * (q.y - p[i].y) / (p[j].y - p[i].y) + p[i].x)
            c = !c;
    return c;
}

static void test_square(void)
{
    thx_vec2 sq[4] = {V2(0, 0), V2(1, 0), V2(1, 1), V2(0, 1)};
    for (int dir = 0; dir < 2; dir++) {
        double s = dir ? -1.0 : 1.0;
        CHECK_NEAR(thx_loop_angle_sum(sq, 4, V2(0.5, 0.5)), s * 2 * PI, 1e-14);
        CHECK_NEAR(thx_loop_angle_sum(sq, 4, V2(0.3, 0.9)), s * 2 * PI, 1e-14);
        CHECK_NEAR(thx_loop_angle_sum(sq, 4, V2(2, 0.5)), 0.0, 1e-14);
        CHECK_NEAR(thx_loop_area(sq, 4), s * 1.0, 1e-15);
        CHECK(thx_loop_inside(sq, 4, V2(0.5, 0.5), 0) == THX_INSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(1.5, 0.5), 0) == THX_OUTSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(-1e-300, 0.5), 0) == THX_OUTSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(1e-300, 0.5), 0) == THX_INSIDE);
        /* exactly on an edge / a vertex */
        CHECK(thx_loop_inside(sq, 4, V2(1, 0.5), 0) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(sq, 4, V2(0.3, 0), 0) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(sq, 4, V2(1, 1), 0) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(sq, 4, V2(0, 0), 1e-6) == THX_ON_BOUNDARY);
        /* within / beyond the tolerance */
        CHECK(thx_loop_inside(sq, 4, V2(0.5, 1 - 1e-7), 1e-6) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(sq, 4, V2(0.5, 1 + 1e-7), 1e-6) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(sq, 4, V2(0.5, 1 - 1e-5), 1e-6) == THX_INSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(0.5, 1 + 1e-5), 1e-6) == THX_OUTSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(1 + 0.71e-6, 1 + 0.71e-6), 1e-6) == THX_OUTSIDE); /* 1.004e-6 from the corner */
        CHECK(thx_loop_inside(sq, 4, V2(1 + 0.7e-6, 1 + 0.7e-6), 1e-6) == THX_ON_BOUNDARY); /* 0.99e-6 */
        CHECK(thx_loop_inside(sq, 4, V2(1 + 0.7e-6, 1 + 0.7e-6), 1.0001e-6) == THX_ON_BOUNDARY);
        /* one ulp either side of an edge, tol = 0 */
        CHECK(thx_loop_inside(sq, 4, V2(nextafter(1.0, 0.0), 0.5), 0) == THX_INSIDE);
        CHECK(thx_loop_inside(sq, 4, V2(nextafter(1.0, 2.0), 0.5), 0) == THX_OUTSIDE);
        int w = 0;
        double res = 1;
        CHECK(thx_loop_classify(sq, 4, V2(0.2, 0.2), 0, &w, &res) == THX_INSIDE);
        CHECK(w == (dir ? -1 : 1));
        CHECK(res < 1e-14);
        CHECK_NEAR(thx_loop_distance(sq, 4, V2(0.5, 0.25)), 0.25, 1e-15);
        CHECK_NEAR(thx_loop_distance(sq, 4, V2(2, 2)), sqrt(2.0), 1e-15);
        CHECK_NEAR(thx_loop_distance(sq, 4, V2(0.5, -3)), 3.0, 1e-15);
        reverse2(sq, 4);
    }
}

/* Edge nearly through p with an irrational-looking slope: p one ulp off the
 * diagonal of a thin triangle. Naive cross products can get the sign wrong;
 * the exact orient2d inside the angle sum does not. */
static void test_near_edge(void)
{
    thx_vec2 tri[3] = {V2(0.1, 0.1), V2(10.3, 10.3), V2(0.1, 10.3)};
    for (int k = 1; k < 200; k++) {
        double x = 0.1 + k * 0.05;
        thx_vec2 on = V2(x, x);
        thx_vec2 above = V2(x, nextafter(x, 100.0)), below = V2(x, nextafter(x, -100.0));
        CHECK(thx_loop_inside(tri, 3, on, 0) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(tri, 3, above, 0) == THX_INSIDE);
        CHECK(thx_loop_inside(tri, 3, below, 0) == THX_OUTSIDE);
    }
}

static void test_concave(void)
{
    /* C shape: the bay (1..3) x (1..2) is open to the right. */
    thx_vec2 c[8] = {V2(0, 0), V2(3, 0), V2(3, 1), V2(1, 1), V2(1, 2), V2(3, 2), V2(3, 3), V2(0, 3)};
    for (int dir = 0; dir < 2; dir++) {
        CHECK(thx_loop_inside(c, 8, V2(2, 1.5), 0) == THX_OUTSIDE);
        CHECK(thx_loop_inside(c, 8, V2(1.01, 1.5), 0) == THX_OUTSIDE);
        CHECK(thx_loop_inside(c, 8, V2(0.99, 1.5), 0) == THX_INSIDE);
        CHECK(thx_loop_inside(c, 8, V2(2, 0.5), 0) == THX_INSIDE);
        CHECK(thx_loop_inside(c, 8, V2(2, 2.5), 0) == THX_INSIDE);
        CHECK(thx_loop_inside(c, 8, V2(1.0005, 1.5), 1e-3) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(c, 8, V2(1, 1.5), 0) == THX_ON_BOUNDARY);
        CHECK(thx_loop_inside(c, 8, V2(2.5, 1), 0) == THX_ON_BOUNDARY);
        CHECK_NEAR(fabs(thx_loop_area(c, 8)), 7.0, 1e-14);
        reverse2(c, 8);
    }

    /* Crescent: disc of radius 2 at the origin minus the disc of radius 2
     * centred at (1, 0); the circles meet at (0.5, +-sqrt(3.75)). */
    thx_vec2 cr[80];
    int m = 0;
    const double t0 = atan2(sqrt(3.75), 0.5);
    for (int i = 0; i <= 40; i++) { /* outer arc, counterclockwise through (-2, 0) */
        double t = t0 + (2 * PI - 2 * t0) * i / 40.0;
        cr[m++] = V2(2 * cos(t), 2 * sin(t));
    }
    const double u0 = PI + t0, u1 = PI - t0; /* angles on the second circle */
    for (int i = 1; i < 39; i++) { /* inner arc, clockwise, back to the top */
        double u = u0 + (u1 - u0) * i / 39.0;
        cr[m++] = V2(1 + 2 * cos(u), 2 * sin(u));
    }
    /* Randomized comparison with the crossing-number reference away from the boundary. */
    unsigned seed = 12345;
    int bad = 0, tested = 0;
    for (int dir = 0; dir < 2; dir++) {
        for (int it = 0; it < 4000; it++) {
            seed = seed * 1103515245u + 12345u;
            double x = -2.5 + 5.0 * ((seed >> 8) & 0xffff) / 65535.0;
            seed = seed * 1103515245u + 12345u;
            double y = -2.5 + 5.0 * ((seed >> 8) & 0xffff) / 65535.0;
            thx_vec2 q = V2(x, y);
            thx_inside r = thx_loop_inside(cr, (size_t)m, q, 1e-9);
            if (r == THX_ON_BOUNDARY) continue;
            tested++;
            bad += (r == THX_INSIDE) != crossing_inside(cr, (size_t)m, q);
        }
        reverse2(cr, (size_t)m);
    }
    CHECK(bad == 0);
    CHECK(tested > 7000);
    /* a point in the crescent's bay (the concavity) is outside */
    CHECK(thx_loop_inside(cr, (size_t)m, V2(1.0, 0.0), 0) == THX_OUTSIDE);
    CHECK(thx_loop_inside(cr, (size_t)m, V2(-1.9, 0.0), 0) == THX_INSIDE);
}

static void test_star(void)
{
    thx_vec2 st[10];
    for (int i = 0; i < 10; i++) {
        double r = (i & 1) ? 0.4 : 1.0, t = PI / 2 + 2 * PI * i / 10;
        st[i] = V2(r * cos(t), r * sin(t));
    }
    CHECK(thx_loop_inside(st, 10, V2(0, 0), 0) == THX_INSIDE);
    CHECK(thx_loop_inside(st, 10, V2(0, 0.9), 0) == THX_INSIDE);           /* in the top spike */
    CHECK(thx_loop_inside(st, 10, V2(0.45 * cos(PI / 2 + PI / 5), 0.45 * sin(PI / 2 + PI / 5)), 0) == THX_OUTSIDE); /* between spikes */
    unsigned seed = 7;
    int bad = 0;
    for (int it = 0; it < 5000; it++) {
        seed = seed * 1103515245u + 12345u;
        double x = -1.2 + 2.4 * ((seed >> 8) & 0xffff) / 65535.0;
        seed = seed * 1103515245u + 12345u;
        double y = -1.2 + 2.4 * ((seed >> 8) & 0xffff) / 65535.0;
        thx_inside r = thx_loop_inside(st, 10, V2(x, y), 0);
        bad += (r == THX_INSIDE) != crossing_inside(st, 10, V2(x, y));
    }
    CHECK(bad == 0);
    /* A loop winding twice around the origin: winding 2, still inside. */
    thx_vec2 twice[12];
    for (int i = 0; i < 12; i++) twice[i] = V2(cos(4 * PI * i / 12), sin(4 * PI * i / 12) * 0.9 + 0.001 * i);
    int w = 0;
    CHECK(thx_loop_classify(twice, 12, V2(0, 0), 0, &w, NULL) == THX_INSIDE);
    CHECK(w == 2);
}

/* ---------------------------------------------------------------------- 3D */

static thx_surface *make_surface(const double *xyz, size_t nn, const int32_t *tri, size_t nt)
{
    thx_ctx *ctx = NULL;
    thx_surface *s = NULL;
    thx_ctx_create(&ctx);
    thx_surface_create(ctx, "t", THX_ROLE_OTHER, &s);
    thx_ctx_destroy(&ctx);
    s->n_nodes = nn;
    s->xyz = malloc(3 * nn * sizeof(double));
    memcpy(s->xyz, xyz, 3 * nn * sizeof(double));
    s->n_tris = nt;
    s->tri = malloc(3 * nt * sizeof(int32_t));
    memcpy(s->tri, tri, 3 * nt * sizeof(int32_t));
    return s;
}

static void flip(thx_surface *s)
{
    for (size_t t = 0; t < s->n_tris; t++) {
        int32_t x = s->tri[3 * t + 1];
        s->tri[3 * t + 1] = s->tri[3 * t + 2];
        s->tri[3 * t + 2] = x;
    }
}

/* Closed surface from quads given counterclockwise seen from outside. */
static thx_surface *from_quads(const double *xyz, size_t nn, const int32_t (*q)[4], size_t nq)
{
    int32_t *t = malloc(6 * nq * sizeof(int32_t));
    for (size_t i = 0; i < nq; i++) {
        int32_t tt[6] = {q[i][0], q[i][1], q[i][2], q[i][0], q[i][2], q[i][3]};
        memcpy(t + 6 * i, tt, sizeof tt);
    }
    thx_surface *s = make_surface(xyz, nn, t, 2 * nq);
    free(t);
    return s;
}

static void test_cube(void)
{
    double xyz[24];
    for (int k = 0; k < 8; k++) {
        xyz[3 * k] = k & 1;
        xyz[3 * k + 1] = (k >> 1) & 1;
        xyz[3 * k + 2] = (k >> 2) & 1;
    }
    /* faces, counterclockwise seen from outside */
    const int32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    thx_surface *s = from_quads(xyz, 8, q, 6);
    CHECK(s->n_tris == 12);
    CHECK_NEAR(thx_surface_volume(s), 1.0, 1e-15);
    thx_vec3 in[4] = {{0.5, 0.5, 0.5}, {0.1, 0.2, 0.9}, {0.999, 0.001, 0.5}, {1e-3, 1e-3, 1e-3}};
    for (int i = 0; i < 4; i++) {
        CHECK_NEAR(thx_surface_solid_angle(s, in[i]), 4 * PI, 1e-12);
        CHECK(thx_surface_inside(s, in[i], 0) == THX_INSIDE);
    }
    thx_vec3 out[4] = {{1.5, 0.5, 0.5}, {-0.1, 0.2, 0.9}, {3, 3, 3}, {0.5, 0.5, -1e-3}};
    for (int i = 0; i < 4; i++) {
        CHECK_NEAR(thx_surface_solid_angle(s, out[i]), 0.0, 1e-12);
        CHECK(thx_surface_inside(s, out[i], 0) == THX_OUTSIDE);
    }
    /* near a face: the face's own triangles subtend almost 2 pi */
    thx_vec3 nearf = {0.5, 0.4, 1 - 1e-9};
    double face = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 a = thx_surface_node(s, (size_t)v[0]), b = thx_surface_node(s, (size_t)v[1]), c = thx_surface_node(s, (size_t)v[2]);
        if (a.z == 1 && b.z == 1 && c.z == 1) face += thx_triangle_solid_angle(a, b, c, nearf);
    }
    CHECK_NEAR(face, 2 * PI, 1e-6);
    CHECK(thx_surface_inside(s, nearf, 1e-6) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, nearf, 0) == THX_INSIDE);
    thx_vec3 nearo = {0.5, 0.4, 1 + 1e-9};
    CHECK(thx_surface_inside(s, nearo, 1e-6) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, nearo, 0) == THX_OUTSIDE);
    thx_vec3 onf = {0.5, 0.4, 1.0}, one = {1.0, 0.3, 1.0}, onv = {1, 1, 1};
    CHECK(thx_surface_inside(s, onf, 0) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, one, 0) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, onv, 0) == THX_ON_BOUNDARY);
    /* on the diagonal shared by two triangles of a face */
    thx_vec3 ond = {0.3, 0.3, 0.0};
    CHECK(thx_surface_inside(s, ond, 0) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, (thx_vec3){0.5, 0.5, 1.5}, 0.49) == THX_OUTSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){0.5, 0.5, 1.5}, 0.51) == THX_ON_BOUNDARY);
    CHECK_NEAR(thx_triangle_distance(thx_v3(0, 0, 0), thx_v3(1, 0, 0), thx_v3(0, 1, 0), thx_v3(2, 0, 0)), 1.0, 1e-15);
    CHECK_NEAR(thx_triangle_distance(thx_v3(0, 0, 0), thx_v3(1, 0, 0), thx_v3(0, 1, 0), thx_v3(0.2, 0.2, -3)), 3.0, 1e-15);
    CHECK_NEAR(thx_triangle_distance(thx_v3(0, 0, 0), thx_v3(1, 0, 0), thx_v3(0, 1, 0), thx_v3(1, 1, 0)), sqrt(0.5), 1e-15);
    /* a single triangle: sign convention */
    CHECK(thx_triangle_solid_angle(thx_v3(0, 0, 0), thx_v3(1, 0, 0), thx_v3(0, 1, 0), thx_v3(0.2, 0.2, -1)) > 0);
    CHECK(thx_triangle_solid_angle(thx_v3(0, 0, 0), thx_v3(1, 0, 0), thx_v3(0, 1, 0), thx_v3(0.2, 0.2, 1)) < 0);
    /* reversed orientation: -4 pi inside, still classified inside */
    flip(s);
    int w = 0;
    double res = 1;
    CHECK_NEAR(thx_surface_solid_angle(s, in[0]), -4 * PI, 1e-12);
    CHECK(thx_surface_classify(s, in[0], 0, &w, &res) == THX_INSIDE);
    CHECK(w == -1);
    CHECK(res < 1e-12);
    CHECK(thx_surface_inside(s, out[0], 0) == THX_OUTSIDE);
    thx_surface_destroy(&s);
}

/* Octahedron refined `level` times, projected on the unit sphere. */
static thx_surface *sphere(int level)
{
    size_t nn = 6, nt = 8;
    double *xyz = malloc(3 * 6 * sizeof(double));
    int32_t *tri = malloc(3 * 8 * sizeof(int32_t));
    const double v0[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    memcpy(xyz, v0, sizeof v0);
    int k = 0;
    for (int sx = 0; sx < 2; sx++)
        for (int sy = 0; sy < 2; sy++)
            for (int sz = 0; sz < 2; sz++) {
                int32_t a = sx, b = 2 + sy, c = 4 + sz;
                if ((sx + sy + sz) & 1) { int32_t t = b; b = c; c = t; }
                tri[k++] = a; tri[k++] = b; tri[k++] = c;
            }
    for (int l = 0; l < level; l++) {
        /* split each edge at its midpoint (shared through a simple map keyed by vertex pair) */
        size_t cap = nn + 3 * nt;
        xyz = realloc(xyz, 3 * cap * sizeof(double));
        int32_t *nt4 = malloc(12 * nt * sizeof(int32_t));
        int32_t *key = malloc(2 * 3 * nt * sizeof(int32_t)), *val = malloc(3 * nt * sizeof(int32_t));
        size_t nkey = 0;
        for (size_t t = 0; t < nt; t++) {
            int32_t m[3];
            for (int e = 0; e < 3; e++) {
                int32_t a = tri[3 * t + e], b = tri[3 * t + (e + 1) % 3];
                int32_t lo = a < b ? a : b, hi = a < b ? b : a, found = -1;
                for (size_t q = 0; q < nkey && found < 0; q++) /* quadratic but small */
                    if (key[2 * q] == lo && key[2 * q + 1] == hi) found = val[q];
                if (found < 0) {
                    double x = xyz[3 * a] + xyz[3 * b], y = xyz[3 * a + 1] + xyz[3 * b + 1], z = xyz[3 * a + 2] + xyz[3 * b + 2];
                    double r = sqrt(x * x + y * y + z * z);
                    xyz[3 * nn] = x / r; xyz[3 * nn + 1] = y / r; xyz[3 * nn + 2] = z / r;
                    key[2 * nkey] = lo; key[2 * nkey + 1] = hi; val[nkey++] = (int32_t)nn;
                    found = (int32_t)nn++;
                }
                m[e] = found;
            }
            int32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
            int32_t q4[12] = {a, m[0], m[2], m[0], b, m[1], m[2], m[1], c, m[0], m[1], m[2]};
            memcpy(nt4 + 12 * t, q4, sizeof q4);
        }
        free(key); free(val); free(tri);
        tri = nt4;
        nt *= 4;
    }
    thx_surface *s = make_surface(xyz, nn, tri, nt);
    free(xyz); free(tri);
    return s;
}

static void test_sphere(void)
{
    thx_surface *s = sphere(3);
    CHECK(s->n_tris == 512);
    CHECK(thx_surface_volume(s) > 4.0); /* outward (4/3 pi ~ 4.19 for the sphere) */
    thx_vec3 pin[3] = {{0, 0, 0}, {0.5, -0.3, 0.2}, {0.0, 0.0, 0.9}};
    for (int i = 0; i < 3; i++) {
        CHECK_NEAR(thx_surface_solid_angle(s, pin[i]), 4 * PI, 1e-12);
        CHECK(thx_surface_inside(s, pin[i], 1e-3) == THX_INSIDE);
    }
    thx_vec3 pout[2] = {{0, 0, 1.01}, {2, 1, 0}};
    for (int i = 0; i < 2; i++) {
        CHECK_NEAR(thx_surface_solid_angle(s, pout[i]), 0.0, 1e-12);
        CHECK(thx_surface_inside(s, pout[i], 1e-3) == THX_OUTSIDE);
    }
    CHECK(thx_surface_inside(s, (thx_vec3){1, 0, 0}, 0) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, (thx_vec3){0, 0, 1.0 + 1e-7}, 1e-6) == THX_ON_BOUNDARY);
    flip(s);
    CHECK_NEAR(thx_surface_solid_angle(s, pin[1]), -4 * PI, 1e-12);
    thx_surface_destroy(&s);

    /* Large surface: the parallel sum must not depend on the thread count. */
    s = sphere(6);
    CHECK(s->n_tris == 32768);
    thx_vec3 p = {0.1, 0.2, 0.3};
    double a1 = thx_surface_solid_angle(s, p);
#ifdef _OPENMP
    int nth = omp_get_max_threads();
    omp_set_num_threads(1);
    double b1 = thx_surface_solid_angle(s, p);
    omp_set_num_threads(3); /* (so that 1 thread is not all we compare, whatever OMP_NUM_THREADS says) */
    double c1 = thx_surface_solid_angle(s, p);
    omp_set_num_threads(nth);
    CHECK(memcmp(&a1, &b1, sizeof a1) == 0);
    CHECK(memcmp(&a1, &c1, sizeof a1) == 0);
#endif
    CHECK_NEAR(a1, 4 * PI, 1e-10);
    thx_surface_destroy(&s);
}

/* L-shaped prism: L polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) extruded over z in [0, 1]. */
static void test_l_prism(void)
{
    const double L[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    double xyz[36];
    for (int i = 0; i < 6; i++)
        for (int z = 0; z < 2; z++) {
            xyz[3 * (i + 6 * z)] = L[i][0];
            xyz[3 * (i + 6 * z) + 1] = L[i][1];
            xyz[3 * (i + 6 * z) + 2] = z;
        }
    int32_t tri[3 * 20];
    int k = 0;
    const int fan[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}};
    for (int f = 0; f < 4; f++) { /* top counterclockwise from +z, bottom reversed */
        tri[k++] = fan[f][0] + 6; tri[k++] = fan[f][1] + 6; tri[k++] = fan[f][2] + 6;
        tri[k++] = fan[f][0]; tri[k++] = fan[f][2]; tri[k++] = fan[f][1];
    }
    for (int i = 0; i < 6; i++) { /* sides: outward is to the right of each CCW edge */
        int j = (i + 1) % 6;
        tri[k++] = i; tri[k++] = j; tri[k++] = j + 6;
        tri[k++] = i; tri[k++] = j + 6; tri[k++] = i + 6;
    }
    thx_surface *s = make_surface(xyz, 12, tri, 20);
    CHECK_NEAR(thx_surface_volume(s), 3.0, 1e-14);
    CHECK(thx_surface_inside(s, (thx_vec3){0.5, 0.5, 0.5}, 1e-6) == THX_INSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){1.5, 0.5, 0.5}, 1e-6) == THX_INSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){0.5, 1.5, 0.5}, 1e-6) == THX_INSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){1.5, 1.5, 0.5}, 1e-6) == THX_OUTSIDE); /* in the concavity */
    CHECK(thx_surface_inside(s, (thx_vec3){1.01, 1.01, 0.5}, 1e-6) == THX_OUTSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){0.99, 0.99, 0.5}, 1e-6) == THX_INSIDE);
    CHECK(thx_surface_inside(s, (thx_vec3){1.0, 1.5, 0.5}, 0) == THX_ON_BOUNDARY);
    CHECK(thx_surface_inside(s, (thx_vec3){1.0000001, 1.5, 0.5}, 1e-6) == THX_ON_BOUNDARY);
    CHECK_NEAR(thx_surface_solid_angle(s, (thx_vec3){1.5, 1.5, 0.5}), 0.0, 1e-12);
    CHECK_NEAR(thx_surface_solid_angle(s, (thx_vec3){0.2, 1.7, 0.9}), 4 * PI, 1e-12);
    thx_surface_destroy(&s);
}

int main(void)
{
    test_square();
    test_near_edge();
    test_concave();
    test_star();
    test_cube();
    test_sphere();
    test_l_prism();
    return tl_finish();
}
