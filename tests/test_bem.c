/* Boundary elements (src/bem): the analytic triangle integrals against quadrature, the
 * solid-angle identity of the double-layer rows on OpenMEEG's real meshes, a homogeneous sphere
 * against its closed-form potential, the transfer matrix against the dipole solution, OpenMEEG's
 * three-shell spheres (Head1, Head2) against their analytic potentials, bad input refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/bem/bem.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static thx_ctx *ctx;
static char data_dir[2048];

/* An icosphere: the icosahedron subdivided `level` times, projected on the sphere (centre c,
 * radius r); counterclockwise seen from outside. */
static thx_surface *icosphere(const char *name, int level, const double c[3], double r)
{
    const double t = (1 + sqrt(5.0)) / 2;
    double v0[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                        {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    int f0[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    size_t nv = 12, nt = 20, cap_v = 12, cap_t = 20;
    for (int l = 0; l < level; l++) cap_t *= 4;
    cap_v = 10 * cap_t + 12;
    double *v = malloc(cap_v * 3 * sizeof *v);
    int32_t *f = malloc(cap_t * 3 * sizeof *f);
    for (size_t i = 0; i < 12; i++) memcpy(v + 3 * i, v0[i], sizeof v0[i]);
    for (size_t i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++) f[3 * i + (size_t)k] = f0[i][k];
    for (int l = 0; l < level; l++) {
        /* midpoints keyed by edge through a linear search table (small meshes) */
        size_t ne = 0;
        int32_t *ek = malloc(nt * 3 * 3 * sizeof *ek);
        int32_t *g = malloc(nt * 4 * 3 * sizeof *g);
        for (size_t i = 0; i < nt; i++) {
            int32_t m[3];
            for (int k = 0; k < 3; k++) {
                int32_t a = f[3 * i + (size_t)k], b = f[3 * i + (size_t)(k + 1) % 3];
                int32_t lo = a < b ? a : b, hi = a < b ? b : a, id = -1;
                for (size_t e = 0; e < ne; e++)
                    if (ek[3 * e] == lo && ek[3 * e + 1] == hi) id = ek[3 * e + 2];
                if (id < 0) {
                    id = (int32_t)nv;
                    for (int q = 0; q < 3; q++) v[3 * nv + (size_t)q] = (v[3 * (size_t)a + (size_t)q] + v[3 * (size_t)b + (size_t)q]) / 2;
                    nv++;
                    ek[3 * ne] = lo; ek[3 * ne + 1] = hi; ek[3 * ne + 2] = id;
                    ne++;
                }
                m[k] = id;
            }
            int32_t a = f[3 * i], b = f[3 * i + 1], cc = f[3 * i + 2];
            int32_t nf[4][3] = {{a, m[0], m[2]}, {m[0], b, m[1]}, {m[2], m[1], cc}, {m[0], m[1], m[2]}};
            memcpy(g + 12 * i, nf, sizeof nf);
        }
        free(f);
        free(ek);
        f = g;
        nt *= 4;
    }
    thx_surface *s = NULL;
    thx_surface_create(ctx, name, THX_ROLE_OTHER, &s);
    s->n_nodes = nv;
    s->n_tris = nt;
    s->xyz = v;
    s->tri = f;
    for (size_t i = 0; i < nv; i++) {
        double *p = v + 3 * i, l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int k = 0; k < 3; k++) p[k] = c[k] + r * p[k] / l;
    }
    return s;
}

/* OpenMEEG's RDM and MAG of a against the reference e, both after removing their means. */
static void rdm_mag(const double *a, const double *e, size_t n, double *rdm, double *mag)
{
    double ma = 0, me = 0, na = 0, ne = 0, d = 0;
    for (size_t i = 0; i < n; i++) { ma += a[i] / (double)n; me += e[i] / (double)n; }
    for (size_t i = 0; i < n; i++) { na += (a[i] - ma) * (a[i] - ma); ne += (e[i] - me) * (e[i] - me); }
    na = sqrt(na);
    ne = sqrt(ne);
    for (size_t i = 0; i < n; i++) {
        double x = (a[i] - ma) / na - (e[i] - me) / ne;
        d += x * x;
    }
    *rdm = sqrt(d);
    *mag = na / ne;
}

static void test_triangle(void)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0.2, 0}, c[3] = {0.3, 1.1, 0.1};
    double xs[4][3] = {{0.3, 0.4, 0.5}, {2, -1, 0.3}, {0.4, 0.3, -0.05}, {0.5, 0.1, 0.02}};
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double A2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++) n[k] /= A2;
    for (int t = 0; t < 4; t++) {
        double *x = xs[t], dl[3], sl[3], qd[3] = {0, 0, 0}, qs[3] = {0, 0, 0}, qo = 0;
        double om = thx_bem_triangle(x, a, b, c, dl, sl);
        /* the midpoint rule on M^2 subtriangles */
        int M = 1200;
        for (int i = 0; i < M; i++)
            for (int j = 0; j < M - i; j++)
                for (int up = 0; up < 2; up++) {
                    if (up && i + j + 2 > M) continue;
                    double u = (i + (up ? 2.0 : 1.0) / 3) / M, w = (j + (up ? 2.0 : 1.0) / 3) / M, y[3];
                    for (int k = 0; k < 3; k++) y[k] = a[k] + u * e1[k] + w * e2[k] - x[k];
                    double R = sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
                    double K = (n[0] * y[0] + n[1] * y[1] + n[2] * y[2]) / (R * R * R), wt = A2 / (2.0 * M * M);
                    double h[3] = {1 - u - w, u, w};
                    for (int k = 0; k < 3; k++) { qd[k] += wt * h[k] * K; qs[k] += wt * h[k] / R; }
                    qo += wt * K;
                }
        double tol = t == 3 ? 2e-3 : 2e-5;
        CHECK_NEAR(om, qo, tol * (1 + fabs(qo)));
        for (int k = 0; k < 3; k++) {
            CHECK_NEAR(dl[k], qd[k], tol * (1 + fabs(qd[k])));
            CHECK_NEAR(sl[k], qs[k], tol * (1 + fabs(qs[k])));
        }
        CHECK_NEAR(dl[0] + dl[1] + dl[2], om, 1e-12);
    }
    /* a corner: no solid angle, a finite single layer */
    double dl[3], sl[3];
    CHECK(thx_bem_triangle(a, a, b, c, dl, sl) == 0 && isfinite(sl[0]) && sl[0] > 0 && dl[1] == 0);
}

static thx_status read_head(int h, thx_model **m, double **sig)
{
    char g[2300], c[2300];
    snprintf(g, sizeof g, "%s/openmeeg-spheres/data/Head%d/Head%d.geom", data_dir, h, h);
    snprintf(c, sizeof c, "%s/openmeeg-spheres/data/Head%d/Head%d.cond", data_dir, h, h);
    return thx_bem_read_openmeeg(ctx, g, c, m, sig);
}

/* Each row of the double layer over the node's own surface sums to the inner solid angle at the
 * node (the polyhedral cone, from the dihedral angles: computed independently), over a surface
 * enclosing the node to 4 pi, over any other to 0. */
static void test_solid_angles(void)
{
    thx_model *m = NULL;
    double *sig = NULL;
    CHECK_OK(ctx, read_head(2, &m, &sig));
    if (!m) return;
    thx_bem *b = NULL;
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)m->surf, m->n_surfaces, sig, &b));
    size_t N = thx_bem_n_nodes(b), S = thx_bem_n_surfaces(b);
    CHECK(N == 3 * 162);
    double *B = malloc(N * N * sizeof *B), worst = 0;
    int convex = 1;
    CHECK_OK(ctx, thx_bem_double_layer(ctx, b, B));
    for (size_t k = 0; k < S; k++)
        for (size_t i = 0; i < thx_bem_surface(b, k)->n_nodes; i++) {
            size_t row = thx_bem_offset(b, k) + i;
            for (size_t l = 0; l < S; l++) {
                double sum = 0;
                for (size_t j = 0; j < thx_bem_surface(b, l)->n_nodes; j++) sum += B[(thx_bem_offset(b, l) + j) * N + row];
                double want;
                if (l == k) want = thx_bem_vertex_angle(b, k, i);
                else {
                    int p = thx_bem_parent(b, k);
                    while (p >= 0 && p != (int)l) p = thx_bem_parent(b, (size_t)p);
                    want = p == (int)l ? 4 * M_PI : 0;
                }
                if (fabs(sum - want) > worst) worst = fabs(sum - want);
                if (l == k) convex &= want > 0 && want < 2 * M_PI;
            }
        }
    CHECK(worst < 1e-9);
    /* the spheres are convex polyhedra: every inner solid angle below 2 pi */
    CHECK(convex);
    free(B);
    thx_bem_destroy(&b);
    thx_model_destroy(&m);
    free(sig);
}

/* phi on a homogeneous sphere (radius R, sigma) of a dipole q at r0 (derived from the Legendre
 * series of the Neumann problem): q.[2 d/|d|^3 + (r + R d/|d|)/(R (R^2 - r.r0 + R |d|))]/(4 pi sigma). */
static double sphere_phi(const double *r, const double *r0, const double *q, double R, double sigma)
{
    double d[3] = {r[0] - r0[0], r[1] - r0[1], r[2] - r0[2]};
    double dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), rr = r[0] * r0[0] + r[1] * r0[1] + r[2] * r0[2];
    double den = R * (R * R - rr + R * dn), v = 0;
    for (int k = 0; k < 3; k++) v += q[k] * (2 * d[k] / (dn * dn * dn) + (r[k] + R * d[k] / dn) / den);
    return v / (4 * M_PI * sigma);
}

static void test_homogeneous_sphere(void)
{
    double c[3] = {0, 0, 0};
    thx_surface *s = icosphere("sphere", 3, c, 1.0);
    double sig = 0.3;
    thx_bem *b = NULL;
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)&s, 1, &sig, &b));
    double pos[6] = {0.1, 0, 0.3, 0, 0.2, -0.5}, mom[6] = {0, 0, 1, 1, 0.5, 0};
    size_t N = thx_bem_n_nodes(b);
    CHECK(N == 642);
    double *phi = malloc(2 * N * sizeof *phi), *ref = malloc(N * sizeof *ref);
    thx_bem_info info;
    CHECK_OK(ctx, thx_bem_dipoles(ctx, b, pos, mom, 2, NULL, phi, &info));
    CHECK(info.ipa_surface == -1); /* the outer surface: no isolated problem */
    for (int d = 0; d < 2; d++) {
        for (size_t i = 0; i < N; i++) ref[i] = sphere_phi(s->xyz + 3 * i, pos + 3 * d, mom + 3 * d, 1.0, sig);
        double rdm, mag;
        rdm_mag(phi + (size_t)d * N, ref, N, &rdm, &mag);
        printf("homogeneous sphere, 642 nodes, dipole %d: RDM %.4f MAG %.4f\n", d + 1, rdm, mag);
        CHECK(rdm < 0.02);
        CHECK(fabs(1 - mag) < 0.03);
        /* zero area-weighted mean on the outer surface: the plain mean of a near-uniform mesh ~ 0 */
        double mean = 0, mx = 0;
        for (size_t i = 0; i < N; i++) { mean += phi[(size_t)d * N + i] / (double)N; mx = fmax(mx, fabs(phi[(size_t)d * N + i])); }
        CHECK(fabs(mean) < 0.02 * mx);
    }
    free(phi);
    free(ref);
    thx_bem_destroy(&b);
    thx_surface_destroy(&s);
}

/* A heart sphere inside a torso sphere with a lung beside it: the dipole solution with the heart
 * of the torso's conductivity gives phi on heart and torso; the transfer matrix applied to the
 * heart's must give the torso's. */
static void test_transfer_vs_dipole(void)
{
    double c0[3] = {0, 0, 0}, ch[3] = {-0.2, 0.1, 0}, cl[3] = {0.45, 0, 0.1};
    thx_surface *s[3] = {icosphere("torso", 3, c0, 1.0), icosphere("heart", 3, ch, 0.3), icosphere("lung", 2, cl, 0.3)};
    s[0]->role = THX_ROLE_OUTER;
    s[1]->role = THX_ROLE_HEART;
    s[2]->role = THX_ROLE_LUNG;
    double sig[3] = {0.2, 0.2, 0.05};
    thx_bem *b = NULL;
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)s, 3, sig, &b));
    if (!b) return;
    CHECK(thx_bem_parent(b, 1) == 0 && thx_bem_parent(b, 2) == 0 && thx_bem_outer(b) == 0);
    size_t N = thx_bem_n_nodes(b), no = s[0]->n_nodes, nh = s[1]->n_nodes;
    double pos[3] = {-0.15, 0.12, 0.05}, mom[3] = {0.3, -0.5, 1};
    double *phi = malloc(N * sizeof *phi), *T = malloc(no * nh * sizeof *T);
    CHECK_OK(ctx, thx_bem_dipoles(ctx, b, pos, mom, 1, NULL, phi, NULL));
    CHECK_OK(ctx, thx_bem_transfer(ctx, b, 1, NULL, T, NULL));
    double *pt = malloc(no * sizeof *pt);
    for (size_t i = 0; i < no; i++) {
        pt[i] = 0;
        for (size_t j = 0; j < nh; j++) pt[i] += T[j * no + i] * phi[thx_bem_offset(b, 1) + j];
    }
    double rdm, mag;
    rdm_mag(pt, phi + thx_bem_offset(b, 0), no, &rdm, &mag);
    printf("transfer matrix vs dipole solution: RDM %.4f MAG %.4f\n", rdm, mag);
    CHECK(rdm < 0.03);
    CHECK(fabs(1 - mag) < 0.03);
    /* a constant on the heart gives that constant on the torso (no current flows) */
    double worst = 0;
    for (size_t i = 0; i < no; i++) {
        double r = 0;
        for (size_t j = 0; j < nh; j++) r += T[j * no + i];
        worst = fmax(worst, fabs(r - 1));
    }
    CHECK(worst < 1e-8);
    free(phi);
    free(T);
    free(pt);
    thx_bem_destroy(&b);
    for (int k = 0; k < 3; k++) thx_surface_destroy(&s[k]);
}

/* OpenMEEG's Head1, Head2 (and Head3 in the plain build) against the analytic potentials at the
 * electrodes (the patches projected on the scalp mesh and interpolated). The symmetric method must
 * meet OpenMEEG's own thresholds (RDM and |1 - MAG| below 0.13, 0.10, 0.03), except RDM of Head1's
 * dipoles 4 and 5, which OpenMEEG's suite itself expects to fail (WILL_FAIL): bounded by what this
 * method reaches. Collocation: the bounds it reaches (docs/validation.md). */
static void test_heads(int method)
{
    static const double thr[3] = {0.13, 0.10, 0.03};
    static const double coll_max[2][5] = {{0.08, 0.35, 0.62, 0.70, 0.70}, {0.05, 0.08, 0.25, 0.55, 0.72}};
    int last = method == THX_BEM_SYMMETRIC && !getenv("THORAX_QUICK") ? 3 : 2;
    for (int h = 1; h <= last; h++) {
        thx_model *m = NULL;
        double *sig = NULL, *pos = NULL, *mom = NULL;
        size_t nd = 0;
        CHECK_OK(ctx, read_head(h, &m, &sig));
        if (!m) return;
        char p[2300];
        snprintf(p, sizeof p, "%s/openmeeg-spheres/data/Head%d/Head%d.dip", data_dir, h, h);
        CHECK_OK(ctx, thx_bem_read_dipoles(ctx, p, &pos, &mom, &nd));
        CHECK(nd == 6);
        thx_bem *b = NULL;
        CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)m->surf, m->n_surfaces, sig, &b));
        size_t N = thx_bem_n_nodes(b);
        double *phi = malloc(N * nd * sizeof *phi);
        thx_bem_info info;
        thx_bem_opts o;
        thx_bem_opts_default(&o);
        o.method = method;
        CHECK_OK(ctx, thx_bem_dipoles(ctx, b, pos, mom, nd, &o, phi, &info));
        if (method == THX_BEM_COLLOCATION)
            CHECK(info.ipa_surface >= 0 && !strcmp(thx_bem_surface(b, (size_t)info.ipa_surface)->name, "cortex"));
        else
            CHECK(info.ipa_surface == -1 && info.n_unknowns == N + 2 * (m->surf[0]->n_tris));
        size_t so = thx_bem_outer(b), off = thx_bem_offset(b, so);
        const thx_surface *S = thx_bem_surface(b, so);
        CHECK(!strcmp(S->name, "scalp"));
        /* electrodes and the analytic values */
        snprintf(p, sizeof p, "%s/openmeeg-spheres/data/Head%d/Head%d.patches", data_dir, h, h);
        FILE *f = fopen(p, "r");
        double E[128][3], an[128][6], v[128];
        size_t ne = 0;
        char line[512], lab[64];
        while (f && ne < 128 && fgets(line, sizeof line, f))
            if (sscanf(line, "%lf %lf %lf", &E[ne][0], &E[ne][1], &E[ne][2]) == 3 ||
                sscanf(line, "%63s %lf %lf %lf", lab, &E[ne][0], &E[ne][1], &E[ne][2]) == 4)
                ne++;
        if (f) fclose(f);
        CHECK(ne == (h == 1 ? 32u : h == 2 ? 64u : 128u));
        snprintf(p, sizeof p, "%s/openmeeg-spheres/tests/analytic/eeg_head%d_analytic.txt", data_dir, h);
        f = fopen(p, "r");
        for (size_t i = 0; f && i < ne; i++)
            for (int k = 0; k < 6; k++) CHECK(fscanf(f, "%lf", &an[i][k]) == 1);
        if (f) fclose(f);
        for (int d = 0; d < 5; d++) {
            double ref[128], rdm, mag;
            for (size_t i = 0; i < ne; i++) {
                size_t t;
                double w[3], q[3];
                thx_surface_nearest(S, E[i], &t, w, q);
                v[i] = 0;
                for (int k = 0; k < 3; k++) v[i] += w[k] * phi[(size_t)d * N + off + (size_t)S->tri[3 * t + (size_t)k]];
                ref[i] = an[i][d];
            }
            rdm_mag(v, ref, ne, &rdm, &mag);
            printf("%s, Head%d dipole %d: RDM %.4f MAG %.4f (OpenMEEG's threshold %.2f)\n",
                   method == THX_BEM_SYMMETRIC ? "symmetric" : "collocation", h, d + 1, rdm, mag, thr[h - 1]);
            if (method == THX_BEM_COLLOCATION) {
                CHECK(rdm < coll_max[h - 1][d]);
            } else {
                CHECK(fabs(1 - mag) < thr[h - 1]);
                /* Head1's dipoles 4 and 5 (0.06 and 0.03 under a cortex of 42 nodes): 0.188, 0.246 */
                CHECK(rdm < (h == 1 && d == 3 ? 0.20 : h == 1 && d == 4 ? 0.26 : thr[h - 1]));
            }
        }
        free(phi);
        free(pos);
        free(mom);
        free(sig);
        thx_bem_destroy(&b);
        thx_model_destroy(&m);
    }
}

/* Compartments side by side (a heart and a lung inside a torso, no chain of shells): the symmetric
 * method's sums over the compartments two surfaces share, against collocation, for a dipole in the
 * torso between the organs (its compartment has two inner boundaries) and one in the heart. */
static void test_siblings(void)
{
    double c0[3] = {0, 0, 0}, ch[3] = {-0.2, 0.1, 0}, cl[3] = {0.45, 0, 0.1};
    thx_surface *s[3] = {icosphere("torso", 3, c0, 1.0), icosphere("heart", 3, ch, 0.3), icosphere("lung", 3, cl, 0.3)};
    double sig[3] = {0.2, 0.6, 0.05};
    thx_bem *b = NULL;
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)s, 3, sig, &b));
    if (!b) return;
    size_t N = thx_bem_n_nodes(b), no = s[0]->n_nodes, o0 = thx_bem_offset(b, 0);
    double pos[6] = {0.2, -0.4, 0.1, -0.15, 0.12, 0.05}, mom[6] = {1, 0.3, -0.5, 0.3, -0.5, 1};
    double *ps = malloc(2 * N * sizeof *ps), *pc = malloc(2 * N * sizeof *pc);
    thx_bem_opts o;
    thx_bem_opts_default(&o);
    thx_bem_info info;
    CHECK_OK(ctx, thx_bem_dipoles(ctx, b, pos, mom, 2, &o, ps, &info));
    CHECK(info.n_unknowns == N + s[1]->n_tris + s[2]->n_tris);
    o.method = THX_BEM_COLLOCATION;
    CHECK_OK(ctx, thx_bem_dipoles(ctx, b, pos, mom, 2, &o, pc, NULL));
    for (int d = 0; d < 2; d++) {
        double rdm, mag;
        rdm_mag(ps + (size_t)d * N + o0, pc + (size_t)d * N + o0, no, &rdm, &mag);
        printf("heart and lung in a torso, dipole %d (%s): symmetric vs collocation on the torso RDM %.4f MAG %.4f\n",
               d + 1, d ? "in the heart" : "in the torso", rdm, mag);
        CHECK(rdm < 0.02);
        CHECK(fabs(1 - mag) < 0.02);
    }
    free(ps);
    free(pc);
    thx_bem_destroy(&b);
    for (int k = 0; k < 3; k++) thx_surface_destroy(&s[k]);
}

static void test_refusals(void)
{
    double c0[3] = {0, 0, 0}, c1[3] = {0.8, 0, 0}, c2[3] = {3, 0, 0};
    thx_surface *a = icosphere("a", 1, c0, 1.0), *o = icosphere("crossing", 1, c1, 0.5), *far = icosphere("apart", 1, c2, 0.5);
    double sig[2] = {1, 1};
    thx_bem *b = NULL;
    const thx_surface *two[2] = {a, o};
    CHECK(thx_bem_create(ctx, two, 2, sig, &b) == THX_EGEOM && tl_msg_has(ctx, "cross") && !b);
    two[1] = far;
    CHECK(thx_bem_create(ctx, two, 2, sig, &b) == THX_EGEOM && tl_msg_has(ctx, "outermost") && !b);
    /* open: a triangle removed */
    a->n_tris--;
    CHECK(thx_bem_create(ctx, (const thx_surface *const *)&a, 1, sig, &b) == THX_EGEOM && tl_msg_has(ctx, "not closed"));
    a->n_tris++;
    double bad = -1;
    CHECK(thx_bem_create(ctx, (const thx_surface *const *)&a, 1, &bad, &b) == THX_EINPUT && tl_msg_has(ctx, "conductivity"));
    /* issue 24: conductivities beyond thorax sigma's bounds (NaN potentials before), two copies of
       one surface under different names (solved, 33% off, before), a surface touching another */
    double huge = 1e308, tiny = 1e-320;
    CHECK(thx_bem_create(ctx, (const thx_surface *const *)&a, 1, &huge, &b) == THX_EINPUT &&
          tl_msg_has(ctx, "outside 1e-12..1e+12") && !b);
    CHECK(thx_bem_create(ctx, (const thx_surface *const *)&a, 1, &tiny, &b) == THX_EINPUT &&
          tl_msg_has(ctx, "outside 1e-12..1e+12") && !b);
    {
        thx_surface *copy = icosphere("copy", 1, c0, 1.0), *in = icosphere("in", 1, c0, 0.5);
        double c3[3] = {0.5, 0, 0}, s3[3] = {1, 1, 1};
        thx_surface *touch = icosphere("t2", 1, c3, 0.5); /* reaches x = 1: on a */
        const thx_surface *dup[3] = {a, in, copy};
        CHECK(thx_bem_create(ctx, dup, 3, s3, &b) == THX_EGEOM && tl_msg_has(ctx, "coincide") && !b);
        const thx_surface *tt[2] = {a, touch};
        CHECK(thx_bem_create(ctx, tt, 2, s3, &b) == THX_EGEOM && tl_msg_has(ctx, "touch: node") && !b);
        const thx_surface *ok[2] = {a, in};
        CHECK_OK(ctx, thx_bem_create(ctx, ok, 2, s3, &b));
        thx_bem_destroy(&b);
        thx_surface_destroy(&copy);
        thx_surface_destroy(&in);
        thx_surface_destroy(&touch);
    }
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)&a, 1, sig, &b));
    double pos[3] = {0, 0, 1.5}, mom[3] = {0, 0, 1}, phi[64];
    CHECK(thx_bem_dipoles(ctx, b, pos, mom, 1, NULL, phi, NULL) == THX_EINPUT && tl_msg_has(ctx, "dipole 1") &&
          tl_msg_has(ctx, "outside"));
    CHECK(thx_bem_transfer(ctx, b, 0, NULL, phi, NULL) == THX_EINPUT && tl_msg_has(ctx, "outermost"));
    thx_bem_destroy(&b);
    CHECK(b == NULL);
    /* dipole file: a short line */
    CHECK(tl_scratch_make("bem") == 0);
    tl_write_text(tl_path("d.dip"), "0 0 0.5 0 0 1\n0 0 0.4 0 1\n");
    double *p = NULL, *q = NULL;
    size_t n = 0;
    CHECK(thx_bem_read_dipoles(ctx, tl_path("d.dip"), &p, &q, &n) == THX_EINPUT && tl_msg_has(ctx, "d.dip:2") && !p && n == 0);
    thx_surface_destroy(&a);
    thx_surface_destroy(&o);
    thx_surface_destroy(&far);
}

int main(void)
{
    snprintf(data_dir, sizeof data_dir, "%s", __FILE__);
    char *slash = strrchr(data_dir, '/');
    if (slash) *slash = '\0';
    else snprintf(data_dir, sizeof data_dir, ".");
    strncat(data_dir, "/../../shared/data", sizeof data_dir - strlen(data_dir) - 1);
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_triangle();
    test_solid_angles();
    test_homogeneous_sphere();
    test_transfer_vs_dipole();
    test_siblings();
    test_heads(THX_BEM_SYMMETRIC);
    test_heads(THX_BEM_COLLOCATION);
    test_refusals();
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("bem");
}
