/* Current streamlines (thorax/field/streamline.h) on meshes made here by thorax's Delaunay:
 *  - a uniform field in a cube: every line straight to rounding, ending on the cube's face (reason
 *    "boundary"), forward and backward, RK2/RK4/RK45; max_length stops at exactly that length;
 *  - a current dipole (unbounded homogeneous medium) sampled at the nodes of two balls, one finer: the
 *    lines keep sin^2(theta)/r and the azimuth of their seed (the exact field lines) within tolerances
 *    that shrink with the mesh and the step, for each integrator (errors printed);
 *  - the integrator's own error (against RK4 with a tiny step on the same field) falls with the step;
 *  - the piecewise-constant J (from the dipole's nodal potentials) integrated exactly, beside the
 *    node-averaged J that thorax integrates: the latter closer to the field lines, never stuck;
 *  - every point of every line in the tetrahedron a scan of all tetrahedra finds for it;
 *  - J = (-y, x, 0): a closed loop, detected (reason "loop"), on its circle;
 *  - J = (-x, 0, 0): the low-current stop where |J| falls below the threshold;
 *  - seeds: a rake, a sphere, a region (and one outside the domain: on its faces), |J| density
 *    (deterministic, denser where |J| is); bad seeds refused by name;
 *  - tubes: radius, outward normals, watertight with caps; VTP/OBJ written, never over another file.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/core/core.h"
#include "thorax/field/streamline.h"
#include "thorax/geom/predicates.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/mesh/tet_locate.h"
#include "thorax/model/volume.h"

static unsigned long long rs = 0x9E3779B97F4A7C15ULL;
static double urand(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 7;
    rs ^= rs << 17;
    return ((double)(rs >> 11) + 0.5) / 9007199254740992.0;
}

/* A volume of the Delaunay tetrahedra of pts (right-handed, thx_volume's convention), one region "a"
 * (two, "left" x < 0 and "right", if two_regions). */
static thx_volume *make_volume(thx_ctx *ctx, double *pts, size_t n, int two_regions)
{
    int32_t *tets = NULL;
    size_t nt = 0;
    if (thx_delaunay3d(ctx, pts, n, &tets, NULL, &nt, NULL) != THX_OK) {
        fprintf(stderr, "delaunay: %s\n", thx_ctx_message(ctx));
        free(pts);
        return NULL;
    }
    thx_volume *v = NULL;
    thx_volume_create(ctx, &v);
    v->n_nodes = n;
    v->xyz = pts;
    v->n_tets = nt;
    v->tet = tets;
    for (size_t t = 0; t < nt; t++) {
        int32_t s = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = s;
    }
    v->region = calloc(nt, sizeof *v->region);
    v->n_regions = two_regions ? 2 : 1;
    v->regions = calloc(v->n_regions, sizeof *v->regions);
    strcpy(v->regions[0].name, two_regions ? "left" : "a");
    if (two_regions) strcpy(v->regions[1].name, "right");
    for (size_t r = 0; r < v->n_regions; r++) v->regions[r].sigma[0] = v->regions[r].sigma[4] = v->regions[r].sigma[8] = 1;
    if (two_regions)
        for (size_t t = 0; t < nt; t++) {
            double cx = 0;
            for (int k = 0; k < 4; k++) cx += 0.25 * pts[3 * (size_t)tets[4 * t + k]];
            v->region[t] = cx > 0;
        }
    return v;
}

/* The cube [-10, 10]^3: a grid of step g, every coordinate on the binary grid. */
static thx_volume *cube(thx_ctx *ctx, int m, int two_regions)
{
    size_t n = (size_t)(m + 1) * (size_t)(m + 1) * (size_t)(m + 1), i = 0;
    double *p = malloc(3 * n * sizeof *p);
    for (int a = 0; a <= m; a++)
        for (int b = 0; b <= m; b++)
            for (int c = 0; c <= m; c++, i++) {
                p[3 * i] = -10 + 20.0 * a / m;
                p[3 * i + 1] = -10 + 20.0 * b / m;
                p[3 * i + 2] = -10 + 20.0 * c / m;
                /* interior nodes jittered a little: no flat tetrahedra to decide */
                if (a > 0 && a < m && b > 0 && b < m && c > 0 && c < m)
                    for (int k = 0; k < 3; k++) p[3 * i + (size_t)k] += (urand() - 0.5) * 4.0 / m;
            }
    return make_volume(ctx, p, n, two_regions);
}

/* A ball of radius R about c: nodes on a jittered grid of step g inside, a Fibonacci sphere on it. */
static thx_volume *ball(thx_ctx *ctx, const double c[3], double R, double g)
{
    int m = (int)ceil(R / g);
    size_t ns = (size_t)(4 * M_PI * R * R / (g * g) * 1.1), cap = ns + (size_t)(8 * (m + 1) * (m + 1) * (m + 1)), n = 0;
    double *p = malloc(3 * cap * sizeof *p);
    for (size_t i = 0; i < ns; i++) {
        double z = 1 - (2.0 * (double)i + 1) / (double)ns, r = sqrt(1 - z * z), lon = (double)i * 2.39996322972865332;
        p[3 * n] = c[0] + R * r * cos(lon), p[3 * n + 1] = c[1] + R * r * sin(lon), p[3 * n + 2] = c[2] + R * z;
        n++;
    }
    for (int a = -m; a <= m; a++)
        for (int b = -m; b <= m; b++)
            for (int d = -m; d <= m; d++) {
                double q[3] = {a * g + (urand() - 0.5) * 0.3 * g, b * g + (urand() - 0.5) * 0.3 * g,
                               d * g + (urand() - 0.5) * 0.3 * g};
                if (sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) > R - 0.6 * g) continue;
                for (int k = 0; k < 3; k++) p[3 * n + (size_t)k] = c[k] + q[k];
                n++;
            }
    return make_volume(ctx, p, n, 0);
}

/* The dipole p = (0, 0, 1) at the origin: J = (3 (p.rh) rh - p) / (4 pi r^3). */
static void dipole_J(const double x[3], double J[3])
{
    double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), pr = x[2] / r;
    for (int c = 0; c < 3; c++) J[c] = (3 * pr * x[c] / r - (c == 2)) / (4 * M_PI * r * r * r);
}

/* 1 if tetrahedron t of v holds p (boundary included), exact. */
static int holds(const thx_volume *v, size_t t, const double *p)
{
    const double *P[4];
    for (int k = 0; k < 4; k++) P[k] = v->xyz + 3 * (size_t)v->tet[4 * t + k];
    double s0 = thx_orient3d(P[0], P[1], P[2], P[3]);
    for (int k = 0; k < 4; k++) {
        const double *R[4] = {P[0], P[1], P[2], P[3]};
        R[k] = p;
        double s = thx_orient3d(R[0], R[1], R[2], R[3]);
        if (s * s0 < 0) return 0;
    }
    return 1;
}

static thx_stream_field *field_of(thx_ctx *ctx, const thx_volume *v, void (*fn)(const double *, double *),
                                  const unsigned char *use)
{
    double *J = malloc(3 * v->n_nodes * sizeof *J), *phi = malloc(v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) {
        fn(v->xyz + 3 * i, J + 3 * i);
        phi[i] = v->xyz[3 * i + 2];
    }
    thx_stream_field *f = NULL;
    CHECK_OK(ctx, thx_stream_field_create(ctx, v, J, phi, use, &f));
    free(J), free(phi);
    return f;
}

static const double U[3] = {1, 0.3, -0.2};
static void uniform_J(const double *x, double *J) { (void)x, memcpy(J, U, sizeof U); }
static void rot_J(const double *x, double *J) { J[0] = -x[1], J[1] = x[0], J[2] = 0; }
static void sink_J(const double *x, double *J) { J[0] = -x[0], J[1] = 0, J[2] = 0; }

static void test_uniform(thx_ctx *ctx)
{
    thx_volume *v = cube(ctx, 8, 0);
    thx_stream_field *f = field_of(ctx, v, uniform_J, NULL);
    double u[3], ul = sqrt(U[0] * U[0] + U[1] * U[1] + U[2] * U[2]);
    for (int c = 0; c < 3; c++) u[c] = U[c] / ul;
    double seed[3] = {0.3, -1.1, 0.7};
    for (int ig = 0; ig < 3; ig++) {
        thx_stream_opts o;
        thx_stream_opts_default(&o);
        o.integrator = ig;
        thx_streamlines *s = NULL;
        CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seed, NULL, 1, &o, &s));
        if (!s) continue;
        CHECK(s->n_lines == 2);
        double off = 0;
        for (size_t i = 0; i < s->n_points; i++) {
            double d[3] = {s->xyz[3 * i] - seed[0], s->xyz[3 * i + 1] - seed[1], s->xyz[3 * i + 2] - seed[2]};
            double a = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
            for (int c = 0; c < 3; c++) off = fmax(off, fabs(d[c] - a * u[c]));
        }
        CHECK(off < 1e-12);
        for (size_t l = 0; l < s->n_lines; l++) {
            CHECK(s->stop[l] == THX_STOP_BOUNDARY);
            const double *e = s->xyz + 3 * (s->first[l + 1] - 1);
            /* forward leaves by x = 10, backward by x = -10: exactly on that face, to rounding */
            CHECK_NEAR(e[0], s->direction[l] > 0 ? 10.0 : -10.0, 1e-12);
            double expect = s->direction[l] > 0 ? (10 - seed[0]) / u[0] : (10 + seed[0]) / u[0];
            CHECK_NEAR(s->length[l], expect, 1e-9);
            CHECK(s->direction[l] == (l == 0 ? 1 : -1));
        }
        thx_streamlines_destroy(&s);
        /* max_length: stops there exactly */
        o.max_length = 3.0;
        o.direction = THX_STREAM_FORWARD;
        CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seed, NULL, 1, &o, &s));
        if (s) {
            CHECK(s->n_lines == 1 && s->stop[0] == THX_STOP_MAX_LENGTH);
            CHECK_NEAR(s->length[0], 3.0, 1e-12);
            const double *e = s->xyz + 3 * (s->n_points - 1);
            CHECK_NEAR(e[0], seed[0] + 3.0 * u[0], 1e-12);
        }
        thx_streamlines_destroy(&s);
    }
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);
}

/* Largest relative change of sin^2(theta)/r and largest change of the azimuth along the lines. */
static void dipole_errors(const thx_streamlines *s, double *ec, double *ea)
{
    *ec = *ea = 0;
    for (size_t l = 0; l < s->n_lines; l++) {
        const double *x0 = s->xyz + 3 * s->first[l];
        double r0 = sqrt(x0[0] * x0[0] + x0[1] * x0[1] + x0[2] * x0[2]);
        double c0 = (x0[0] * x0[0] + x0[1] * x0[1]) / (r0 * r0 * r0), a0 = atan2(x0[1], x0[0]);
        for (size_t i = s->first[l]; i < s->first[l + 1]; i++) {
            const double *x = s->xyz + 3 * i;
            double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            *ec = fmax(*ec, fabs((x[0] * x[0] + x[1] * x[1]) / (r * r * r) / c0 - 1));
            *ea = fmax(*ea, fabs(atan2(x[1], x[0]) - a0));
        }
    }
}


/* The dipole's potential phi = z / (4 pi r^3) (sigma 1: J = -grad phi is dipole_J). */
static double dipole_phi(const double *x)
{
    double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    return x[2] / (4 * M_PI * r * r * r);
}

/* J = -grad phi of the linear interpolant of phi in tetrahedron t (what linear finite elements give). */
static void tet_J(const thx_volume *v, size_t t, double J[3])
{
    const int32_t *q = v->tet + 4 * t;
    const double *P0 = v->xyz + 3 * (size_t)q[0];
    double e[3][3], d[3];
    for (int k = 0; k < 3; k++) {
        for (int c = 0; c < 3; c++) e[k][c] = v->xyz[3 * (size_t)q[k + 1] + (size_t)c] - P0[c];
        d[k] = dipole_phi(v->xyz + 3 * (size_t)q[k + 1]) - dipole_phi(P0);
    }
    /* e g = d (rows: edges): Cramer */
    double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    for (int c = 0; c < 3; c++) {
        double m[3][3];
        memcpy(m, e, sizeof m);
        for (int k = 0; k < 3; k++) m[k][c] = d[k];
        J[c] = -(m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
    }
}

/*
 * The alternative to the node-averaged field (docs/decisions.md, "Current streamlines"): the
 * piecewise-constant J of linear elements integrated exactly, a straight segment across each
 * tetrahedron along its own J, face to face. Where the next tetrahedron's J points back through the
 * face they share (J's normal component is not continuous between elements), the line cannot go on:
 * it is stuck on that face. Returns the largest |C/C0 - 1| along the line (C = sin^2 theta / r) and
 * its length; *stuck: whether it ended on such a face.
 */
static double p0_line(const thx_volume *v, const thx_tet_locator *L, const double *Jt, const double x0[3], long t,
                      double *length, int *stuck)
{
    double x[3] = {x0[0], x0[1], x0[2]}, err = 0;
    double r0 = sqrt(x0[0] * x0[0] + x0[1] * x0[1] + x0[2] * x0[2]), c0 = (x0[0] * x0[0] + x0[1] * x0[1]) / (r0 * r0 * r0);
    long from = -1;
    *length = 0;
    *stuck = 0;
    for (int it = 0; it < 100000; it++) {
        const double *J = Jt + 3 * t;
        double m = sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]), d[3] = {J[0] / m, J[1] / m, J[2] / m};
        const int32_t *q = v->tet + 4 * (size_t)t;
        double best = INFINITY;
        int kb = -1;
        for (int k = 0; k < 4; k++) {
            if (thx_tet_neighbour(L, (size_t)t, k) == from && from >= 0) continue;
            const double *A = v->xyz + 3 * (size_t)q[(k + 1) & 3], *B = v->xyz + 3 * (size_t)q[(k + 2) & 3],
                         *C = v->xyz + 3 * (size_t)q[(k + 3) & 3], *O = v->xyz + 3 * (size_t)q[k];
            double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ac[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
            double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
            if (n[0] * (O[0] - A[0]) + n[1] * (O[1] - A[1]) + n[2] * (O[2] - A[2]) > 0) n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
            double nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            if (!(nd > 0)) continue;
            double sk = (n[0] * (A[0] - x[0]) + n[1] * (A[1] - x[1]) + n[2] * (A[2] - x[2])) / nd;
            if (sk < best) best = sk, kb = k;
        }
        if (kb < 0) break;
        if (best < 0) best = 0;
        for (int c = 0; c < 3; c++) x[c] += best * d[c];
        *length += best;
        double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        err = fmax(err, fabs((x[0] * x[0] + x[1] * x[1]) / (r * r * r) / c0 - 1));
        long u = thx_tet_neighbour(L, (size_t)t, kb);
        if (u < 0) break; /* the boundary */
        /* the face's normal (out of t) against the next tetrahedron's J: back through the face? */
        const double *A = v->xyz + 3 * (size_t)q[(kb + 1) & 3], *B = v->xyz + 3 * (size_t)q[(kb + 2) & 3],
                     *C = v->xyz + 3 * (size_t)q[(kb + 3) & 3], *O = v->xyz + 3 * (size_t)q[kb];
        double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ac[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
        double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
        if (n[0] * (O[0] - A[0]) + n[1] * (O[1] - A[1]) + n[2] * (O[2] - A[2]) > 0) n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
        const double *Ju = Jt + 3 * u;
        if (n[0] * Ju[0] + n[1] * Ju[1] + n[2] * Ju[2] <= 0) {
            *stuck = 1;
            break;
        }
        from = t;
        t = u;
    }
    return err;
}

/* On the dipole balls, from the potentials at the nodes (as thorax forward gives them): the
 * piecewise-constant J integrated exactly against the node-averaged J integrated by RK2 (what thorax
 * does), the same seeds. The averaged field's lines are the closer to the exact field lines, and none
 * of them is stuck. */
static void test_p0_vs_averaged(thx_ctx *ctx)
{
    const double c[3] = {14, 3, 0};
    const double gs[2] = {1.6, 0.8};
    for (int gi = 0; gi < 2; gi++) {
        thx_volume *v = ball(ctx, c, 10, gs[gi]);
        if (!v) return;
        size_t nt = v->n_tets, nn = v->n_nodes;
        double *Jt = malloc(3 * nt * sizeof *Jt), *Jn = calloc(3 * nn, sizeof *Jn), *w = calloc(nn, sizeof *w);
        for (size_t t = 0; t < nt; t++) {
            tet_J(v, t, Jt + 3 * t);
            double vol = fabs(thx_volume_tet_volume(v, t));
            for (int k = 0; k < 4; k++) {
                size_t i = (size_t)v->tet[4 * t + k];
                for (int cc = 0; cc < 3; cc++) Jn[3 * i + cc] += vol * Jt[3 * t + cc];
                w[i] += vol;
            }
        }
        for (size_t i = 0; i < nn; i++)
            for (int cc = 0; cc < 3; cc++) Jn[3 * i + cc] /= w[i];
        thx_stream_field *f = NULL;
        CHECK_OK(ctx, thx_stream_field_create(ctx, v, Jn, NULL, NULL, &f));
        thx_tet_locator *L = NULL;
        CHECK_OK(ctx, thx_tet_locator_create(ctx, v, &L));
        if (!f || !L) return;
        double seeds[3 * 24];
        long st[24];
        for (int i = 0; i < 24; i++) {
            seeds[3 * i] = c[0] - 6 + 0.5 * i, seeds[3 * i + 1] = c[1] + 0.25 * (i % 5) - 0.5, seeds[3 * i + 2] = c[2] + 0.5 * i - 6;
            st[i] = thx_stream_field_eval(f, seeds + 3 * i, -1, NULL, NULL);
        }
        thx_stream_opts o;
        thx_stream_opts_default(&o);
        o.direction = THX_STREAM_FORWARD;
        thx_streamlines *s = NULL;
        CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, st, 24, &o, &s));
        double e_avg = 0, e_p0 = 0, len_avg = 0, len_p0 = 0;
        int n_stuck = 0;
        if (s) {
            double ea;
            dipole_errors(s, &e_avg, &ea);
            for (size_t l = 0; l < s->n_lines; l++) len_avg += s->length[l] / 24;
        }
        for (int i = 0; i < 24; i++) {
            double len;
            int stuck;
            e_p0 = fmax(e_p0, p0_line(v, L, Jt, seeds + 3 * i, st[i], &len, &stuck));
            len_p0 += len / 24;
            n_stuck += stuck;
        }
        printf("dipole from nodal potentials, ball h %.1f mm: node-averaged J + RK2: max |C/C0 - 1| %.2e, mean length "
               "%.1f mm; piecewise-constant J exactly: %.2e, mean length %.1f mm, %d of 24 lines stuck on a face\n",
               gs[gi], e_avg, len_avg, e_p0, len_p0, n_stuck);
        CHECK(e_avg < e_p0);
        if (s) for (size_t l = 0; l < s->n_lines; l++) CHECK(s->stop[l] == THX_STOP_BOUNDARY);
        thx_streamlines_destroy(&s);
        thx_tet_locator_destroy(&L);
        thx_stream_field_destroy(&f);
        free(Jt), free(Jn), free(w);
        thx_volume_destroy(&v);
    }
}

/* The point at arc length a along line l (linear between its points), or 0 if the line is shorter. */
static int at_arc(const thx_streamlines *s, size_t l, double a, double p[3])
{
    for (size_t i = s->first[l]; i + 1 < s->first[l + 1]; i++)
        if (s->arc[i + 1] >= a) {
            double u = (a - s->arc[i]) / (s->arc[i + 1] - s->arc[i]);
            for (int c = 0; c < 3; c++) p[c] = s->xyz[3 * i + (size_t)c] + u * (s->xyz[3 * i + 3 + (size_t)c] - s->xyz[3 * i + (size_t)c]);
            return 1;
        }
    return 0;
}

/* The integrator's own error on the same interpolated field: each line's point at 6 mm of arc against
 * RK4 with a step of 0.005 of the cell, for steps 0.4, 0.2, 0.1; the error falls as the step does (the
 * field is only continuous across faces, so both methods converge at second order there). */
static void test_step_convergence(thx_ctx *ctx)
{
    const double c[3] = {14, 3, 0};
    thx_volume *v = ball(ctx, c, 10, 1.6);
    if (!v) return;
    thx_stream_field *f = field_of(ctx, v, dipole_J, NULL);
    double seeds[3 * 8];
    for (int i = 0; i < 8; i++) seeds[3 * i] = c[0] - 4 + i, seeds[3 * i + 1] = c[1] + 0.5 * (i % 3) - 0.5, seeds[3 * i + 2] = c[2] + i - 4;
    thx_stream_opts o;
    thx_stream_opts_default(&o);
    o.direction = THX_STREAM_FORWARD;
    o.integrator = THX_STREAM_RK4;
    o.step = 0.005;
    thx_streamlines *ref = NULL;
    CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, NULL, 8, &o, &ref));
    if (!ref) return;
    const double steps[3] = {0.4, 0.2, 0.1};
    for (int ig = 0; ig < 2; ig++) {
        double e[3];
        for (int k = 0; k < 3; k++) {
            o.integrator = ig;
            o.step = steps[k];
            thx_streamlines *s = NULL;
            CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, NULL, 8, &o, &s));
            e[k] = 0;
            size_t used = 0;
            for (size_t l = 0; s && l < s->n_lines; l++) {
                double p[3], q[3];
                if (!at_arc(s, l, 6.0, p) || !at_arc(ref, l, 6.0, q)) continue;
                e[k] = fmax(e[k], sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])));
                used++;
            }
            CHECK(used >= 6);
            thx_streamlines_destroy(&s);
        }
        printf("%s against RK4 step 0.005, point at 6 mm: step 0.4 %.2e, 0.2 %.2e, 0.1 %.2e mm\n", ig ? "RK4" : "RK2", e[0],
               e[1], e[2]);
        CHECK(e[1] < 0.5 * e[0] && e[2] < 0.5 * e[1]);
    }
    thx_streamlines_destroy(&ref);
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);
}

static void test_dipole(thx_ctx *ctx)
{
    const double c[3] = {14, 3, 0};
    const double gs[2] = {1.6, 0.8};
    double err[2][3], errs[3];
    size_t evals[2][3];
    for (int gi = 0; gi < 2; gi++) {
        thx_volume *v = ball(ctx, c, 10, gs[gi]);
        if (!v) return;
        thx_stream_field *f = field_of(ctx, v, dipole_J, NULL);
        double seeds[3 * 8];
        for (int i = 0; i < 8; i++) {
            seeds[3 * i] = c[0] - 4 + i, seeds[3 * i + 1] = c[1] + 0.5 * (i % 3) - 0.5, seeds[3 * i + 2] = c[2] + i - 4;
        }
        for (int ig = 0; ig < 3; ig++) {
            thx_stream_opts o;
            thx_stream_opts_default(&o);
            o.integrator = ig;
            thx_streamlines *s = NULL;
            CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, NULL, 8, &o, &s));
            if (!s) continue;
            double ec, ea;
            dipole_errors(s, &ec, &ea);
            err[gi][ig] = ec;
            evals[gi][ig] = s->n_evals;
            printf("dipole, ball h %.1f mm (%zu tets), %s: max |C/C0 - 1| %.2e, azimuth %.2e rad, %zu points, %zu evals\n",
                   gs[gi], v->n_tets, ig == 0 ? "RK2" : ig == 1 ? "RK4" : "RK45", ec, ea, s->n_points, s->n_evals);
            CHECK(ec < (gi ? 0.01 : 0.03));
            CHECK(ea < (gi ? 0.01 : 0.03));
            for (size_t l = 0; l < s->n_lines; l++) CHECK(s->stop[l] == THX_STOP_BOUNDARY);
            /* every point in the tetrahedron the scan finds (the last one of a line: on its face, to rounding) */
            if (gi == 0 && ig == 0) {
                size_t bad = 0, scanned = 0;
                for (size_t l = 0; l < s->n_lines; l++)
                    for (size_t i = s->first[l]; i + 1 < s->first[l + 1]; i++) {
                        const double *p = s->xyz + 3 * i;
                        long first = -1;
                        for (size_t t = 0; t < v->n_tets && first < 0; t++)
                            if (holds(v, t, p)) first = (long)t;
                        scanned++;
                        if (first < 0 || !holds(v, (size_t)s->tet[i], p)) bad++;
                        /* the same tetrahedron, unless p is on a face they share */
                        else if (first != s->tet[i]) {
                            int shared = 0;
                            for (int a = 0; a < 4; a++)
                                for (int b = 0; b < 4; b++) shared += v->tet[4 * first + a] == v->tet[4 * (size_t)s->tet[i] + b];
                            if (shared < 3) bad++;
                        }
                    }
                printf("walk vs scan: %zu points, %zu disagree\n", scanned, bad);
                CHECK(bad == 0 && scanned > 100);
            }
            /* the step halved: the error shrinks (RK2) */
            if (ig == 0) {
                thx_streamlines *s2 = NULL;
                o.step = 0.05;
                CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, NULL, 8, &o, &s2));
                if (s2) {
                    dipole_errors(s2, &ec, &ea);
                    errs[gi] = ec;
                    printf("  RK2 step 0.05: max |C/C0 - 1| %.2e\n", ec);
                }
                thx_streamlines_destroy(&s2);
            }
            thx_streamlines_destroy(&s);
        }
        thx_stream_field_destroy(&f);
        thx_volume_destroy(&v);
    }
    /* a finer mesh: smaller errors, for each integrator */
    for (int ig = 0; ig < 3; ig++) CHECK(err[1][ig] < 0.6 * err[0][ig]);
    (void)errs;
    (void)evals;
}

static void test_loop_and_low(thx_ctx *ctx)
{
    thx_volume *v = cube(ctx, 10, 0);
    thx_stream_field *f = field_of(ctx, v, rot_J, NULL);
    double seed[3] = {5, 0, 1};
    for (int ig = 0; ig < 3; ig++) {
        thx_stream_opts o;
        thx_stream_opts_default(&o);
        o.integrator = ig;
        thx_streamlines *s = NULL;
        CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seed, NULL, 1, &o, &s));
        if (!s) continue;
        CHECK(s->n_lines == 1); /* a closed loop: no backward line */
        CHECK(s->stop[0] == THX_STOP_LOOP);
        const double *e = s->xyz + 3 * (s->n_points - 1);
        CHECK(e[0] == seed[0] && e[1] == seed[1] && e[2] == seed[2]);
        double dr = 0, dz = 0;
        for (size_t i = 0; i < s->n_points; i++) {
            const double *p = s->xyz + 3 * i;
            dr = fmax(dr, fabs(sqrt(p[0] * p[0] + p[1] * p[1]) - 5));
            dz = fmax(dz, fabs(p[2] - 1));
        }
        printf("loop (%s): %zu points, length %.6f (2 pi 5 = %.6f), radius off by %.2e\n",
               ig == 0 ? "RK2" : ig == 1 ? "RK4" : "RK45", s->n_points, s->length[0], 10 * M_PI, dr);
        CHECK(dr < 0.01 && dz < 1e-9);
        CHECK_NEAR(s->length[0], 10 * M_PI, 0.05);
        /* the quarter turn: counterclockwise about z */
        CHECK(s->xyz[3 * 1 + 1] > 0);
        thx_streamlines_destroy(&s);
        o.loops = 0;
        o.max_length = 100;
        CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seed, NULL, 1, &o, &s));
        if (s) CHECK(s->stop[0] == THX_STOP_MAX_LENGTH);
        thx_streamlines_destroy(&s);
    }
    thx_stream_field_destroy(&f);
    f = field_of(ctx, v, sink_J, NULL);
    double seed2[3] = {5, 1, 1};
    thx_stream_opts o;
    thx_stream_opts_default(&o);
    o.min_current = 0.05; /* max |J| = 10: stop below 0.5 */
    o.direction = THX_STREAM_FORWARD;
    thx_streamlines *s = NULL;
    CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seed2, NULL, 1, &o, &s));
    if (s) {
        CHECK(s->stop[0] == THX_STOP_LOW_CURRENT);
        const double *e = s->xyz + 3 * (s->n_points - 1);
        CHECK(e[0] < 0.5 && e[0] > 0.0);
        CHECK(s->current[s->n_points - 1] < 0.5);
    }
    thx_streamlines_destroy(&s);
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);
}

static void test_seeds(thx_ctx *ctx)
{
    thx_volume *v = cube(ctx, 8, 1);
    unsigned char use[2] = {0, 1}; /* "left" (x < 0) out of the domain */
    thx_stream_field *f = field_of(ctx, v, uniform_J, use);
    thx_seed_spec sp;
    double *x = NULL;
    long *t = NULL;
    size_t n = 0;
    /* a rake */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "line:1,0,0:9,0,0:5", &sp));
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
    CHECK(n == 5);
    for (size_t i = 0; i < n; i++) CHECK_NEAR(x[3 * i], 1 + 2.0 * (double)i, 1e-12);
    /* a sphere in the right half */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "sphere:5,0,0:3:50", &sp));
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
    CHECK(n == 55);
    double mean[3] = {0, 0, 0};
    for (size_t i = 5; i < n; i++) {
        double d[3] = {x[3 * i] - 5, x[3 * i + 1], x[3 * i + 2]};
        CHECK_NEAR(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), 3.0, 1e-12);
        for (int c = 0; c < 3; c++) mean[c] += d[c] / 50;
    }
    CHECK(fabs(mean[0]) < 0.1 && fabs(mean[1]) < 0.1 && fabs(mean[2]) < 0.1); /* spread evenly */
    /* a sphere across the domain's edge: those outside left out */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "sphere:0,0,0:3:40", &sp));
    size_t before = n;
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
    CHECK(n - before > 10 && n - before < 30);
    /* the region in the domain: inside its tetrahedra, deterministic */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "region:right:20", &sp));
    before = n;
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
    CHECK(n == before + 20);
    for (size_t i = before; i < n; i++) CHECK(v->region[t[i]] == 1 && holds(v, (size_t)t[i], x + 3 * i));
    double *x2 = NULL;
    long *t2 = NULL;
    size_t n2 = 0;
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x2, &t2, &n2));
    CHECK(n2 == 20 && !memcmp(x2, x + 3 * before, 60 * sizeof *x2));
    free(x2), free(t2);
    /* the region outside the domain: its seeds on its faces to the domain (x = 0), in the domain */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "region:left:20", &sp));
    before = n;
    CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
    CHECK(n == before + 20);
    for (size_t i = before; i < n; i++) {
        CHECK(v->region[t[i]] == 1 && holds(v, (size_t)t[i], x + 3 * i));
        CHECK(fabs(x[3 * i]) < 0.3); /* the faces near x = 0 (the jittered grid's) */
    }
    /* the lines from there run into the domain (forward, along +x) */
    thx_stream_opts o;
    thx_stream_opts_default(&o);
    thx_streamlines *s = NULL;
    CHECK_OK(ctx, thx_streamlines_trace(ctx, f, x + 3 * before, t + before, 20, &o, &s));
    if (s) {
        CHECK(s->n_lines == 40);
        for (size_t l = 0; l < s->n_lines; l++) {
            CHECK(s->stop[l] == THX_STOP_BOUNDARY);
            const double *e = s->xyz + 3 * (s->first[l + 1] - 1);
            if (s->direction[l] > 0) CHECK_NEAR(e[0], 10.0, 1e-9);
            else CHECK(s->length[l] < 0.1); /* backward: straight into the left region's face */
        }
    }
    thx_streamlines_destroy(&s);
    free(x), free(t);
    x = NULL, t = NULL, n = 0;
    /* bad seeds, refused by name */
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "point:-5,0,0", &sp));
    CHECK(thx_stream_seeds(ctx, f, &sp, &x, &t, &n) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "point:-5,0,0") && strstr(thx_ctx_message(ctx), "outside"));
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "point:50,0,0", &sp));
    CHECK(thx_stream_seeds(ctx, f, &sp, &x, &t, &n) == THX_EINPUT);
    CHECK_OK(ctx, thx_seed_spec_parse(ctx, "region:heart:10", &sp));
    CHECK(thx_stream_seeds(ctx, f, &sp, &x, &t, &n) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "\"heart\"") && strstr(thx_ctx_message(ctx), "left, right"));
    CHECK(n == 0);
    const char *bad[] = {"point:1,2", "line:1,2,3:4,5,6", "sphere:0,0,0:-1:5", "density:0", "density:x", "blob:3",
                         "region::4", "point:1,2,3,4", "nothing"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK(thx_seed_spec_parse(ctx, bad[i], &sp) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), bad[i]) != NULL);
    }
    double out_pt[3] = {-5, 0, 0};
    CHECK(thx_streamlines_trace(ctx, f, out_pt, NULL, 1, &o, &s) == THX_EINPUT && !s);
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);

    /* |J| density on the dipole ball: seeds where |J| is larger than the region's uniform ones */
    const double c[3] = {14, 3, 0};
    v = ball(ctx, c, 10, 1.6);
    f = field_of(ctx, v, dipole_J, NULL);
    double mj[2];
    for (int k = 0; k < 2; k++) {
        CHECK_OK(ctx, thx_seed_spec_parse(ctx, k ? "density:400" : "region:a:400", &sp));
        CHECK_OK(ctx, thx_stream_seeds(ctx, f, &sp, &x, &t, &n));
        mj[k] = 0;
        for (size_t i = 0; i < n; i++) {
            double J[3];
            dipole_J(x + 3 * i, J);
            mj[k] += sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]) / (double)n;
            CHECK(holds(v, (size_t)t[i], x + 3 * i));
        }
        free(x), free(t);
        x = NULL, t = NULL, n = 0;
    }
    printf("mean |J| at 400 seeds: uniform %.3e, by density %.3e\n", mj[0], mj[1]);
    CHECK(mj[1] > 1.3 * mj[0]);
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);
}

static void test_tubes_files(thx_ctx *ctx)
{
    thx_volume *v = cube(ctx, 10, 0);
    thx_stream_field *f = field_of(ctx, v, rot_J, NULL);
    double seeds[6] = {5, 0, 1, 0, 7, -2};
    thx_stream_opts o;
    thx_stream_opts_default(&o);
    o.loops = 0;
    o.max_length = 20;
    thx_streamlines *s = NULL;
    CHECK_OK(ctx, thx_streamlines_trace(ctx, f, seeds, NULL, 2, &o, &s));
    if (!s) return;
    thx_stream_tubes *T = NULL;
    CHECK_OK(ctx, thx_stream_tubes_make(ctx, s, 0.25, 8, 1, &T));
    if (T) {
        size_t want_v = 0, want_t = 0;
        for (size_t l = 0; l < s->n_lines; l++) {
            size_t m = s->first[l + 1] - s->first[l];
            want_v += 8 * m + 2, want_t += 16 * (m - 1) + 16;
        }
        CHECK(T->n_vertices == want_v && T->n_tris == want_t);
        /* ring vertices at the radius from the axis (the circle about z: sqrt(x^2+y^2) = 5 +- 0.25 or
           within the tube's plane), normals outward and unit */
        size_t bad = 0;
        for (size_t i = 0; i < T->n_vertices; i++) {
            double nl = sqrt(T->normal[3 * i] * T->normal[3 * i] + T->normal[3 * i + 1] * T->normal[3 * i + 1] +
                             T->normal[3 * i + 2] * T->normal[3 * i + 2]);
            if (fabs(nl - 1) > 1e-12) bad++;
        }
        CHECK(bad == 0);
        /* watertight and consistently oriented: each directed edge once, its reverse once */
        size_t ne = 3 * T->n_tris, unmatched = 0;
        long long *e = malloc(ne * sizeof *e);
        for (size_t t = 0; t < T->n_tris; t++)
            for (int k = 0; k < 3; k++)
                e[3 * t + (size_t)k] = (long long)T->tri[3 * t + (size_t)k] * 10000000LL + T->tri[3 * t + (size_t)((k + 1) % 3)];
        for (size_t i = 0; i < ne; i++) {
            long long a = e[i] / 10000000LL, b = e[i] % 10000000LL, rev = b * 10000000LL + a;
            int fw = 0, bw = 0;
            for (size_t j = 0; j < ne; j++) fw += e[j] == e[i], bw += e[j] == rev;
            if (fw != 1 || bw != 1) unmatched++;
        }
        free(e);
        CHECK(unmatched == 0);
        /* outward: each triangle's normal points away from its line's nearest point */
        size_t inward = 0;
        for (size_t t = 0; t < T->n_tris; t++) {
            const int32_t *q = T->tri + 3 * t;
            const double *A = T->xyz + 3 * (size_t)q[0], *B = T->xyz + 3 * (size_t)q[1], *C = T->xyz + 3 * (size_t)q[2];
            double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ac[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
            double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
            double m[3] = {(A[0] + B[0] + C[0]) / 3, (A[1] + B[1] + C[1]) / 3, (A[2] + B[2] + C[2]) / 3};
            double best = INFINITY, dir[3] = {0, 0, 0};
            size_t l = (size_t)T->line[t], near = 0;
            for (size_t i = s->first[l]; i < s->first[l + 1]; i++) {
                double d[3] = {m[0] - s->xyz[3 * i], m[1] - s->xyz[3 * i + 1], m[2] - s->xyz[3 * i + 2]};
                double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                if (dd < best) best = dd, memcpy(dir, d, sizeof dir), near = i;
            }
            if (best < 0.2 * 0.2) { /* a cap's triangle (its centroid 2/3 of the radius from the end): along the line, out */
                size_t other = near == s->first[l] ? near + 1 : near - 1;
                for (int k = 0; k < 3; k++) dir[k] = s->xyz[3 * near + (size_t)k] - s->xyz[3 * other + (size_t)k];
            }
            if (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] <= 0) inward++;
        }
        CHECK(inward == 0);
    }
    /* files: written, replaced when thorax's own, never over another file */
    char vtp[1024], obj[1024], other[1024];
    snprintf(vtp, sizeof vtp, "%s", tl_path("lines.vtp"));
    snprintf(obj, sizeof obj, "%s", tl_path("tubes.obj"));
    snprintf(other, sizeof other, "%s", tl_path("mine.vtp"));
    CHECK_OK(ctx, thx_streamlines_write(ctx, s, NULL, vtp));
    CHECK_OK(ctx, thx_streamlines_write(ctx, s, NULL, vtp));
    CHECK_OK(ctx, thx_streamlines_write(ctx, s, T, obj));
    tl_write_text(other, "<VTKFile>someone else's</VTKFile>\n");
    CHECK(thx_streamlines_write(ctx, s, NULL, other) != THX_OK);
    size_t len = 0;
    char *txt = tl_slurp(ctx, other, &len);
    CHECK(txt && strstr(txt, "someone else's"));
    free(txt);
    CHECK(thx_streamlines_write(ctx, s, NULL, tl_path("lines.txt")) == THX_EINPUT);
    txt = tl_slurp(ctx, vtp, &len);
    CHECK(txt && strstr(txt, "Name=\"current_magnitude\"") && strstr(txt, "Name=\"stop_reason\"") &&
          strstr(txt, "Name=\"direction\"") && strstr(txt, "NumberOfLines=\"4\""));
    free(txt);
    txt = tl_slurp(ctx, obj, &len);
    CHECK(txt && !strncmp(txt, "# thorax streamlines", 20) && strstr(txt, "\nf "));
    free(txt);
    CHECK(tl_leftover_tmp("lines") == 0);
    thx_stream_tubes_destroy(&T);
    thx_streamlines_destroy(&s);
    thx_stream_field_destroy(&f);
    thx_volume_destroy(&v);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    if (tl_scratch_make("field_streamline")) return 1;
    test_uniform(ctx);
    test_loop_and_low(ctx);
    test_seeds(ctx);
    test_tubes_files(ctx);
    test_dipole(ctx);
    test_p0_vs_averaged(ctx);
    test_step_convergence(ctx);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("field_streamline");
}
