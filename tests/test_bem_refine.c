/* The heart's subdivision for the transfer matrix (src/bem/refine.c, thx_bem_transfer_refined;
 * issue 24): counts (n + e nodes, 4 t triangles a level), closure and orientation kept, the old
 * nodes kept, the interpolation W (rows summing to 1, linear functions carried exactly, the fine
 * nodes at W times the coarse ones). Then concentric spheres, the heart (radius a, an icosphere of
 * 42 nodes) inside the torso (radius R, homogeneous): heart potentials cos(theta) give
 * u = (A r + B / r^2) cos(theta) with u(a) = cos(theta) and du/dr(R) = 0, so
 * u(R) = 3 a^2 R cos(theta) / (2 a^3 + R^3). The subdivided system, given u at its fine nodes,
 * comes nearer u on the torso with each subdivision; the refined transfer is that system's
 * matrix times W, and converges. (The refined transfer applied to cos(theta) at the 42 coarse
 * nodes does not come nearer the sphere's u: it converges to the solution for the flat-faceted
 * heart with potentials linear on each coarse facet, 9% off the sphere's; printed, not checked.) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/bem/bem.h"
#include "thorax/geom/verify.h"

static thx_ctx *ctx;

/* An icosphere (thx_icosphere) moved to centre c. */
static thx_surface *icosphere(const char *name, int level, const double c[3], double r)
{
    thx_surface *s = NULL;
    if (thx_icosphere(ctx, level, r, name, THX_ROLE_OTHER, &s) != THX_OK) return NULL;
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int k = 0; k < 3; k++) s->xyz[3 * i + (size_t)k] += c[k];
    return s;
}

static int cmp_pair(const void *pa, const void *pb)
{
    const long long *a = pa, *b = pb;
    return a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : a[1] < b[1] ? -1 : a[1] > b[1];
}

/* Every directed edge once and its reverse present: closed and consistently oriented. */
static int closed_oriented(const thx_surface *s)
{
    size_t ne = 3 * s->n_tris;
    long long *e = malloc(ne * 2 * sizeof *e);
    for (size_t t = 0; t < s->n_tris; t++)
        for (size_t k = 0; k < 3; k++) {
            e[2 * (3 * t + k)] = s->tri[3 * t + k];
            e[2 * (3 * t + k) + 1] = s->tri[3 * t + (k + 1) % 3];
        }
    qsort(e, ne, 2 * sizeof *e, cmp_pair);
    int ok = 1;
    for (size_t i = 0; i < ne && ok; i++) {
        if (i + 1 < ne && e[2 * i] == e[2 * i + 2] && e[2 * i + 1] == e[2 * i + 3]) ok = 0;
        long long key[2] = {e[2 * i + 1], e[2 * i]};
        if (!bsearch(key, e, ne, 2 * sizeof *e, cmp_pair)) ok = 0;
    }
    free(e);
    return ok;
}

static size_t count_edges(const thx_surface *s)
{
    size_t ne = 3 * s->n_tris, n = 0;
    long long *e = malloc(ne * 2 * sizeof *e);
    for (size_t t = 0; t < s->n_tris; t++)
        for (size_t k = 0; k < 3; k++) {
            long long a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            e[2 * (3 * t + k)] = a < b ? a : b;
            e[2 * (3 * t + k) + 1] = a < b ? b : a;
        }
    qsort(e, ne, 2 * sizeof *e, cmp_pair);
    for (size_t i = 0; i < ne; i++) n += i == 0 || cmp_pair(e + 2 * i, e + 2 * i - 2) != 0;
    free(e);
    return n;
}

/* The outward normal's mean alignment with the position (a star-shaped surface about 0): > 0. */
static double outward(const thx_surface *s)
{
    double sum = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const double *a = s->xyz + 3 * s->tri[3 * t], *b = s->xyz + 3 * s->tri[3 * t + 1], *c = s->xyz + 3 * s->tri[3 * t + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double g[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
        sum += (n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) > 0 ? 1 : -1;
    }
    return sum / (double)s->n_tris;
}

/* A surface with an irregular shape and numbering: the icosphere of level 1 squashed and
 * renumbered, so that the midpoints' order is no accident of the input's. */
static thx_surface *lumpy(void)
{
    const double c[3] = {0.3, -0.2, 0.1};
    thx_surface *s = icosphere("lumpy", 1, c, 2.0);
    for (size_t i = 0; i < s->n_nodes; i++) {
        double *p = s->xyz + 3 * i;
        p[0] *= 1.7;
        p[2] = 0.6 * p[2] + 0.1 * p[0] * p[1];
    }
    /* renumbered: node i -> (5 i) mod n (42 nodes: 5 is coprime with 42) */
    size_t n = s->n_nodes;
    double *x = malloc(3 * n * sizeof *x);
    for (size_t i = 0; i < n; i++) memcpy(x + 3 * ((5 * i) % n), s->xyz + 3 * i, 3 * sizeof *x);
    for (size_t t = 0; t < 3 * s->n_tris; t++) s->tri[t] = (int32_t)((5 * (size_t)s->tri[t]) % n);
    free(s->xyz);
    s->xyz = x;
    return s;
}

static void test_subdivide(void)
{
    thx_surface *s = lumpy();
    CHECK(closed_oriented(s));
    double o0 = outward(s);
    size_t n = s->n_nodes, t = s->n_tris;
    for (int L = 0; L <= 3; L++) {
        thx_surface *f = NULL;
        thx_bem_refinement W;
        CHECK_OK(ctx, thx_bem_subdivide(ctx, s, L, &f, &W));
        if (!f) continue;
        /* counts: each level n + e nodes, 4 t triangles; the predicted counts agree */
        size_t n_exp = n, t_exp = t, e = count_edges(s);
        for (int l = 0; l < L; l++) {
            n_exp += e;
            e = 2 * e + 3 * t_exp;
            t_exp *= 4;
        }
        CHECK(f->n_nodes == n_exp && f->n_tris == t_exp);
        size_t nf = 0, tf = 0;
        thx_bem_refined_counts(n, t, L, &nf, &tf);
        CHECK(nf == n_exp && tf == t_exp);
        CHECK(W.n_fine == f->n_nodes && W.n_coarse == n);
        CHECK(count_edges(f) == 3 * f->n_tris / 2);
        CHECK(closed_oriented(f));
        CHECK(outward(f) == o0);
        CHECK_NEAR(thx_surface_volume(f), thx_surface_volume(s), 1e-12 * fabs(thx_surface_volume(s)));
        /* the old nodes kept, with their own numbers */
        CHECK(!memcmp(f->xyz, s->xyz, 3 * n * sizeof *f->xyz));
        /* W: rows sum to 1, weights in [0, 1], a linear function carried exactly, the fine nodes
         * themselves W times the coarse ones */
        double worst_sum = 0, worst_lin = 0, worst_xyz = 0;
        int in_range = 1;
        for (size_t q = 0; q < f->n_nodes; q++) {
            double sum = 0, lin = 0, x[3] = {0, 0, 0};
            for (int k = 0; k < 3; k++) {
                double w = W.w[3 * q + k];
                size_t c = W.node[3 * q + k];
                if (c >= n || w < 0 || w > 1) in_range = 0;
                if (c >= n) continue;
                const double *p = s->xyz + 3 * c;
                sum += w;
                lin += w * (0.7 - 1.3 * p[0] + 2.1 * p[1] + 0.4 * p[2]);
                for (int j = 0; j < 3; j++) x[j] += w * p[j];
            }
            const double *p = f->xyz + 3 * q;
            double exact = 0.7 - 1.3 * p[0] + 2.1 * p[1] + 0.4 * p[2];
            worst_sum = fmax(worst_sum, fabs(sum - 1));
            worst_lin = fmax(worst_lin, fabs(lin - exact));
            for (int j = 0; j < 3; j++) worst_xyz = fmax(worst_xyz, fabs(x[j] - p[j]));
        }
        CHECK(in_range);
        CHECK(worst_sum < 1e-15);
        CHECK(worst_lin < 1e-13);
        CHECK(worst_xyz < 1e-14);
        /* thx_bem_refinement_apply is T W: a row of fine values of a linear function becomes,
         * for each coarse hat function, the sum over fine nodes of its weight there */
        double *Tf = malloc(f->n_nodes * sizeof *Tf), *Tc = malloc(n * sizeof *Tc), *ref = calloc(n, sizeof *ref);
        for (size_t q = 0; q < f->n_nodes; q++) Tf[q] = 1.0 + (double)q;
        for (size_t q = 0; q < f->n_nodes; q++)
            for (int k = 0; k < 3; k++) ref[W.node[3 * q + k]] += W.w[3 * q + k] * Tf[q];
        thx_bem_refinement_apply(&W, Tf, 1, Tc);
        double d = 0;
        for (size_t i = 0; i < n; i++) d = fmax(d, fabs(Tc[i] - ref[i]));
        CHECK(d < 1e-9);
        if (L == 0) CHECK(!memcmp(Tc, Tf, n * sizeof *Tc));
        printf("subdivision %d: %zu nodes, %zu triangles; W rows sum to 1 within %.1e, linear within %.1e\n", L,
               f->n_nodes, f->n_tris, worst_sum, worst_lin);
        free(Tf);
        free(Tc);
        free(ref);
        thx_surface_destroy(&f);
        thx_bem_refinement_free(&W);
    }
    /* out of range */
    thx_surface *f = NULL;
    thx_bem_refinement W;
    CHECK(thx_bem_subdivide(ctx, s, -1, &f, &W) == THX_EINPUT && !f);
    CHECK(thx_bem_subdivide(ctx, s, THX_BEM_REFINE_MAX + 1, &f, &W) == THX_EINPUT && !f);
    thx_surface_destroy(&s);
}

/* u(r, theta) of the concentric spheres (heart radius a, torso R): cos(theta) on the heart, no
 * current through the torso; at any point p (r <= a on the heart's flat facets too). */
static double sphere_u(const double *p, double a, double R)
{
    double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), den = 2 * a * a * a + R * R * R;
    double A = 2 * a * a / den, B = a * a * R * R * R / den;
    return (A * r + B / (r * r)) * p[2] / r;
}

/* The heart (radius a, a coarse icosphere) inside the torso (radius R, homogeneous). (1) The
 * system thx_bem_transfer_refined solves (thx_bem_transfer on thx_bem_refine's subdivided heart,
 * its columns the fine nodes) applied to the exact u at the fine heart nodes (on the coarse flat
 * facets: the polyhedral heart's own problem, whose solution is u): the error at the torso's nodes
 * falls with each subdivision (0.0423, 0.0086, 0.0006 for the heart of 42 nodes). (2) thx_bem_transfer_refined is that fine matrix times W. (3) Its
 * columns (the coarse heart's hat functions) converge: |T2 - T1| < |T1 - T0| / 2. Errors relative,
 * 2-norm over the torso's nodes. */
static void test_spheres(void)
{
    const double c[3] = {0, 0, 0}, a = 0.5, R = 1.0;
    const int heart_level = 1, torso_level = 3; /* 42 and 642 nodes */
    thx_surface *s[2] = {icosphere("torso", torso_level, c, R), icosphere("heart", heart_level, c, a)};
    double sig[2] = {0.2, 0};
    thx_bem *b = NULL;
    CHECK_OK(ctx, thx_bem_create(ctx, (const thx_surface *const *)s, 2, sig, &b));
    if (!b) return;
    size_t no = s[0]->n_nodes, nh = s[1]->n_nodes;
    double *T[3], err_fine[3] = {0, 0, 0}, err_coarse[3] = {0, 0, 0};
    for (int L = 0; L <= 2; L++) {
        T[L] = malloc(no * nh * sizeof *T[L]);
        thx_bem_opts o;
        thx_bem_opts_default(&o);
        thx_bem_info inf;
        CHECK_OK(ctx, thx_bem_transfer_refined(ctx, b, 1, L, &o, T[L], &inf));
        thx_bem *f = NULL;
        thx_bem_refinement W;
        CHECK_OK(ctx, thx_bem_refine(ctx, b, 1, L, &f, &W));
        if (!f) continue;
        CHECK(inf.n_unknowns == no + W.n_fine);
        const thx_surface *hf = thx_bem_surface(f, 1);
        double *Tf = malloc(no * W.n_fine * sizeof *Tf), *Tc = malloc(no * nh * sizeof *Tc);
        CHECK_OK(ctx, thx_bem_transfer(ctx, f, 1, &o, Tf, NULL));
        /* (2) */
        thx_bem_refinement_apply(&W, Tf, no, Tc);
        double d = 0, m = 0;
        for (size_t i = 0; i < no * nh; i++) { d = fmax(d, fabs(Tc[i] - T[L][i])); m = fmax(m, fabs(T[L][i])); }
        CHECK(d < 1e-10 * m);
        /* (1), and the coarse matrix on cos(theta) at the coarse nodes for the record */
        double e2 = 0, c2 = 0, x2 = 0;
        for (size_t i = 0; i < no; i++) {
            double uf = 0, uc = 0, ex = sphere_u(s[0]->xyz + 3 * i, a, R);
            for (size_t j = 0; j < W.n_fine; j++) uf += Tf[j * no + i] * sphere_u(hf->xyz + 3 * j, a, R);
            for (size_t j = 0; j < nh; j++) uc += T[L][j * no + i] * s[1]->xyz[3 * j + 2] / a;
            e2 += (uf - ex) * (uf - ex);
            c2 += (uc - ex) * (uc - ex);
            x2 += ex * ex;
        }
        err_fine[L] = sqrt(e2 / x2);
        err_coarse[L] = sqrt(c2 / x2);
        printf("concentric spheres (heart %zu nodes, torso %zu), heart subdivided %d times (%zu nodes): the fine "
               "system on the exact u: relative error %.4f; the refined transfer on cos(theta) at the %zu nodes: %.4f\n",
               nh, no, L, W.n_fine, err_fine[L], nh, err_coarse[L]);
        free(Tf);
        free(Tc);
        thx_bem_destroy(&f);
        thx_bem_refinement_free(&W);
    }
    /* the torso's own discretization (642 nodes) is a floor of about 0.003 (measured with a heart of
     * 162 nodes: 0.0090, 0.0006, 0.0029), so past the first subdivision only a fall is asked */
    CHECK(err_fine[1] < 0.5 * err_fine[0]);
    CHECK(err_fine[2] < err_fine[1]);
    /* (3) */
    double d10 = 0, d21 = 0;
    for (size_t i = 0; i < no * nh; i++) {
        d10 += (T[1][i] - T[0][i]) * (T[1][i] - T[0][i]);
        d21 += (T[2][i] - T[1][i]) * (T[2][i] - T[1][i]);
    }
    printf("refined transfer: |T1 - T0| %.3e, |T2 - T1| %.3e (Frobenius)\n", sqrt(d10), sqrt(d21));
    CHECK(sqrt(d21) < 0.5 * sqrt(d10));
    for (int L = 0; L <= 2; L++) free(T[L]);
    thx_bem_destroy(&b);
    thx_surface_destroy(&s[0]);
    thx_surface_destroy(&s[1]);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_subdivide();
    test_spheres();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
