/*
 * Blocked multi-right-hand-side solves (thx_fem_solve_block, issue 15 item 6):
 * on a jittered box, linear fields reproduced exactly by a blocked Cholesky
 * solve with CHOLMOD and with MUMPS, block sizes that do and do not divide the
 * number of right-hand sides, loads, one right-hand side; a singular system
 * (a current into a floating piece) refused by both the frame-by-frame and
 * the blocked solve, by CG and by the factorization, a system without any
 * prescribed node refused before; and on the
 * phantom at test resolution the epicardial series and both transfer
 * methods, blocked, against the frame-by-frame solve to 1e-12 (THORAX_QUICK:
 * two block sizes of the series and the adjoint transfer alone).
 */
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <petscsys.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/core/sha256.h"
#include "thorax/fem/fem.h"
#include "thorax/geom/surfaces.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/mesh/mesh.h"
#define N 6

/* A jittered lattice in [0, N-1]^3 shifted by x0 along x, tetrahedralized (positive orientation);
 * boundary nodes flagged. */
static thx_volume *box_of(thx_ctx *ctx, int side, double x0, unsigned char **on_boundary)
{
    thx_volume *v = NULL;
    thx_volume_create(ctx, &v);
    size_t n = (size_t)side * side * side, k = 0;
    v->n_nodes = n;
    v->xyz = malloc(3 * n * sizeof *v->xyz);
    *on_boundary = calloc(n, 1);
    srand(5);
    for (int i = 0; i < side; i++)
        for (int j = 0; j < side; j++)
            for (int l = 0; l < side; l++, k++) {
                int on = i == 0 || j == 0 || l == 0 || i == side - 1 || j == side - 1 || l == side - 1;
                double jit = on ? 0 : 0.2;
                v->xyz[3 * k] = x0 + i + jit * (rand() / (double)RAND_MAX - 0.5);
                v->xyz[3 * k + 1] = j + jit * (rand() / (double)RAND_MAX - 0.5);
                v->xyz[3 * k + 2] = l + jit * (rand() / (double)RAND_MAX - 0.5);
                (*on_boundary)[k] = (unsigned char)on;
            }
    int32_t *tets = NULL;
    size_t nt = 0;
    thx_delaunay3d(ctx, v->xyz, n, &tets, NULL, &nt, NULL);
    for (size_t t = 0; t < nt; t++) {
        int32_t x = tets[4 * t + 2];
        tets[4 * t + 2] = tets[4 * t + 3];
        tets[4 * t + 3] = x;
    }
    v->tet = tets;
    v->n_tets = nt;
    v->region = calloc(nt, sizeof *v->region);
    v->n_regions = 1;
    v->regions = calloc(1, sizeof *v->regions);
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "test");
    const double sigma[9] = {0.5, 0.1, 0.05, 0.1, 0.3, -0.04, 0.05, -0.04, 0.1};
    memcpy(v->regions[0].sigma, sigma, sizeof sigma);
    return v;
}

static thx_volume *box(thx_ctx *ctx, double x0, unsigned char **on_boundary) { return box_of(ctx, N, x0, on_boundary); }

/* The j-th linear field (a different one per column). */
static double lin(size_t j, const double *p)
{
    return (0.3 + 0.1 * (double)j) * p[0] - 0.7 * p[1] + (1.1 - 0.05 * (double)j) * p[2] + 2.0 + (double)j;
}

/* Largest |a - b| over n values, relative to the largest |b|. */
static double rel_diff(const double *a, const double *b, size_t n)
{
    double d = 0, m = 0;
    for (size_t i = 0; i < n; i++) {
        d = fmax(d, fabs(a[i] - b[i]));
        m = fmax(m, fabs(b[i]));
    }
    return m > 0 ? d / m : d;
}

/* Box tests with the factorization package `pkg` (NULL: thorax's own choice for many right-hand sides). */
static void box_tests(thx_ctx *ctx, const char *pkg)
{
    unsigned char *onb = NULL;
    thx_volume *v = box(ctx, 0, &onb);
    thx_csr K;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    size_t n = v->n_nodes, R = 11;
    unsigned char *kind = malloc(n);
    for (size_t i = 0; i < n; i++) kind[i] = onb[i] ? 2 : 1;
    if (pkg) {
        PetscOptionsSetValue(NULL, "-ksp_type", "preonly");
        PetscOptionsSetValue(NULL, "-pc_type", "cholesky");
        PetscOptionsSetValue(NULL, "-pc_factor_mat_solver_type", pkg);
    }
    thx_fem_system *S = NULL;
    CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S));
    if (S) {
        thx_fem_system_hint_rhs(S, R);
        thx_fem_system_hint_rhs(S, 100); /* 11 < 12 does not switch; this does (without options) */
    }
    if (pkg) {
        PetscOptionsClearValue(NULL, "-ksp_type");
        PetscOptionsClearValue(NULL, "-pc_type");
        PetscOptionsClearValue(NULL, "-pc_factor_mat_solver_type");
    }
    if (!S) goto out;
    char ksp[32], pc[32];
    thx_fem_system_describe(S, ksp, pc, NULL);
    CHECK(!strcmp(ksp, "preonly") && !strcmp(pc, "cholesky"));
    /* the automatic block: at most 64, and 64 for a system this small; thorax's own path (one rank, no
       package named) at most 256, and 256 here */
    CHECK(thx_fem_system_block(S) == (pkg ? 64u : 256u));
    double *phi = calloc(n * R, sizeof *phi), *ref = calloc(n * R, sizeof *ref);
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n; i++)
            if (onb[i]) phi[j * n + i] = ref[j * n + i] = lin(j, v->xyz + 3 * i);
    /* frame by frame (KSPSolve per column) */
    for (size_t j = 0; j < R; j++) {
        thx_fem_solve_stats ss;
        CHECK_OK(ctx, thx_fem_solve(ctx, S, ref + j * n, NULL, 0, &ss));
    }
    /* blocks of 4: 11 = 4 + 4 + 3 */
    thx_fem_system_set_block(S, 4);
    CHECK(thx_fem_system_block(S) == 4);
    thx_fem_solve_stats bs;
    CHECK_OK(ctx, thx_fem_solve_block(ctx, S, phi, NULL, R, 0, &bs));
    double exact = 0;
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n; i++) exact = fmax(exact, fabs(phi[j * n + i] - lin(j, v->xyz + 3 * i)));
    double d = rel_diff(phi, ref, n * R);
    printf("box (%s): %zu right-hand sides in blocks of 4: linear fields to %.1e, against one by one %.1e, residual %.1e\n",
           pkg ? pkg : "default", R, exact, d, bs.residual);
    CHECK(exact < 1e-11);
    CHECK(d < 1e-12);
    CHECK(bs.iterations_total == (long)R && bs.iterations == 1 && bs.iterations_min == 1);
    CHECK(bs.residual < 1e-13);
    /* one right-hand side, and a block larger than the count */
    memset(phi, 0, n * R * sizeof *phi);
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n; i++)
            if (onb[i]) phi[j * n + i] = lin(j, v->xyz + 3 * i);
    CHECK_OK(ctx, thx_fem_solve_block(ctx, S, phi, NULL, 1, 0, &bs));
    CHECK(rel_diff(phi, ref, n) < 1e-12 && bs.iterations_total == 1);
    thx_fem_system_set_block(S, 0);
    CHECK_OK(ctx, thx_fem_solve_block(ctx, S, phi + n, NULL, R - 1, 0, &bs)); /* 10 columns, block 64 */
    CHECK(rel_diff(phi + n, ref + n, n * (R - 1)) < 1e-12);
    /* loads: a dipole of currents inside, on top of the linear field; blocked == one by one */
    {
        double *load = calloc(n * R, sizeof *load);
        size_t a = (N / 2 * N + N / 2) * N + 1, b = (N / 2 * N + N / 2) * N + N - 2;
        for (size_t j = 0; j < R; j++) {
            load[j * n + a] = 1.0 + (double)j;
            load[j * n + b] = -1.0;
            for (size_t i = 0; i < n; i++)
                if (onb[i]) phi[j * n + i] = ref[j * n + i] = lin(j, v->xyz + 3 * i);
                else phi[j * n + i] = ref[j * n + i] = 0;
        }
        for (size_t j = 0; j < R; j++) CHECK_OK(ctx, thx_fem_solve(ctx, S, ref + j * n, load + j * n, 0, NULL));
        thx_fem_system_set_block(S, 5);
        CHECK_OK(ctx, thx_fem_solve_block(ctx, S, phi, load, R, 0, &bs));
        double dl = rel_diff(phi, ref, n * R);
        printf("box (%s): with loads, blocks of 5 against one by one %.1e\n", pkg ? pkg : "default", dl);
        CHECK(dl < 1e-12);
        /* the load is felt: the field is no longer linear at the loaded node */
        CHECK(fabs(phi[a] - lin(0, v->xyz + 3 * a)) > 1e-3);
        free(load);
    }
    free(phi);
    free(ref);
out:
    thx_fem_system_destroy(&S);
    free(kind);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    free(onb);
}

/* Two boxes side by side with no tetrahedron between them; only the first one's boundary is prescribed:
 * the second is a floating piece and K_ff is singular. */
static void singular_tests(thx_ctx *ctx)
{
    unsigned char *ob1 = NULL, *ob2 = NULL;
    thx_volume *v1 = box(ctx, 0, &ob1), *v2 = box(ctx, 3 * N, &ob2);
    size_t n1 = v1->n_nodes, n = n1 + v2->n_nodes;
    thx_volume *v = NULL;
    thx_volume_create(ctx, &v);
    v->n_nodes = n;
    v->xyz = malloc(3 * n * sizeof *v->xyz);
    memcpy(v->xyz, v1->xyz, 3 * n1 * sizeof *v->xyz);
    memcpy(v->xyz + 3 * n1, v2->xyz, 3 * v2->n_nodes * sizeof *v->xyz);
    v->n_tets = v1->n_tets + v2->n_tets;
    v->tet = malloc(4 * v->n_tets * sizeof *v->tet);
    memcpy(v->tet, v1->tet, 4 * v1->n_tets * sizeof *v->tet);
    for (size_t t = 0; t < 4 * v2->n_tets; t++) v->tet[4 * v1->n_tets + t] = v2->tet[t] + (int32_t)n1;
    v->region = calloc(v->n_tets, sizeof *v->region);
    v->n_regions = 1;
    v->regions = calloc(1, sizeof *v->regions);
    v->regions[0] = v1->regions[0];
    thx_csr K;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    unsigned char *kind = malloc(n);
    for (size_t i = 0; i < n; i++) kind[i] = i < n1 && ob1[i] ? 2 : 1;
    double *phi = calloc(3 * n, sizeof *phi);
    for (size_t j = 0; j < 3; j++)
        for (size_t i = 0; i < n1; i++)
            if (ob1[i]) phi[j * n + i] = lin(j, v->xyz + 3 * i);
    /* a current into the floating piece has nowhere to go (no solution): refused by CG + GAMG (mode 0) and by
       the factorization (mode 1), one by one and blocked, with nothing written; without it (mode 2) the
       system is consistent and the factorization's answer is the linear field on the first box, 0 on the
       piece, the same both ways */
    double *load = calloc(3 * n, sizeof *load), *first = NULL;
    for (size_t j = 0; j < 3; j++) load[j * n + n1 + (N / 2 * N + N / 2) * N + N / 2] = 1;
    for (int mode = 0; mode < 3; mode++)
        for (int blocked = 0; blocked < 2; blocked++) {
            thx_fem_system *S = NULL;
            CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S));
            if (!S) continue;
            if (mode) thx_fem_system_hint_rhs(S, 100);
            for (size_t j = 0; j < 3; j++)
                for (size_t i = 0; i < n; i++) phi[j * n + i] = i < n1 && ob1[i] ? lin(j, v->xyz + 3 * i) : 0;
            const double *L = mode == 2 ? NULL : load;
            thx_status st = blocked ? thx_fem_solve_block(ctx, S, phi, L, 3, 0, NULL) : thx_fem_solve(ctx, S, phi, L, 0, NULL);
            double piece = 0, err = 0;
            for (size_t j = 0; j < (blocked ? 3u : 1u); j++)
                for (size_t i = 0; i < n; i++)
                    if (i >= n1) piece = fmax(piece, fabs(phi[j * n + i]));
                    else err = fmax(err, fabs(phi[j * n + i] - lin(j, v->xyz + 3 * i)));
            printf("floating piece, %s, %s: %s\n", mode == 0 ? "CG + GAMG, a current into it" : mode == 1 ?
                   "Cholesky, a current into it" : "Cholesky, no current", blocked ? "blocked" : "one by one",
                   st ? thx_ctx_message(ctx) : "solved");
            if (mode < 2) {
                CHECK(st == THX_ESOLVER);
                CHECK(strstr(thx_ctx_message(ctx), "did not converge") != NULL);
                if (mode == 1) CHECK(strstr(thx_ctx_message(ctx), "singular") != NULL);
                CHECK(piece == 0); /* nothing written */
            } else {
                CHECK(st == THX_OK && piece == 0 && err < 1e-11);
                if (!blocked) first = memcpy(malloc(n * sizeof *first), phi, n * sizeof *first);
                else if (first) CHECK(rel_diff(phi, first, n) < 1e-12);
            }
            thx_fem_system_destroy(&S);
        }
    free(first);
    free(load);
    /* no prescribed node anywhere: refused when the system is made, as before */
    memset(kind, 1, n);
    thx_fem_system *S = NULL;
    CHECK(thx_fem_system_create(ctx, &K, kind, 0, &S) == THX_EINPUT && S == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "no prescribed potential") != NULL);
    free(phi);
    free(kind);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    thx_volume_destroy(&v1);
    thx_volume_destroy(&v2);
    free(ob1);
    free(ob2);
}

/* The phantom at test resolution: the series and both transfer methods, blocked against frame by frame. */
static void phantom_tests(thx_ctx *ctx)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    thx_mesh_opts mo;
    thx_mesh_opts_default(&mo);
    mo.no_heart = 1;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &mo, NULL));
    const thx_surface *heart = NULL, *torso = NULL;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        if (m->surf[s]->role == THX_ROLE_HEART) heart = m->surf[s];
        if (m->surf[s]->role == THX_ROLE_OUTER) torso = m->surf[s];
    }
    /* 29 frames of a rotating dipole-like pattern on the heart (29: prime, no block size divides it) */
    size_t nh = heart->n_nodes, F = 29;
    thx_series *epi = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, nh, F, &epi));
    double c[3] = {0, 0, 0};
    for (size_t i = 0; i < nh; i++)
        for (int d = 0; d < 3; d++) c[d] += heart->xyz[3 * i + d] / (double)nh;
    for (size_t f = 0; f < F; f++) {
        double a = 0.2 * (double)f, u[3] = {cos(a), sin(a), 0.3 * cos(2 * a)};
        for (size_t i = 0; i < nh; i++) {
            const double *p = heart->xyz + 3 * i;
            double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]}, r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            epi->v[f * nh + i] = 1e4 * (u[0] * d[0] + u[1] * d[1] + u[2] * d[2]) / (r * r * r);
        }
    }
    thx_forward_opts fo;
    thx_forward_opts_default(&fo);
    fo.keep_volume = 1;
    fo.block = 1;
    thx_forward_result R1, RB;
    CHECK_OK(ctx, thx_forward_epicardial(ctx, m, epi, &fo, &R1));
    CHECK(R1.block == 1 && !strcmp(R1.pc, "cholesky"));
    /* THORAX_QUICK (make check, make sanitize): blocks of the automatic size and of 8, not also of
     * 1000 (more than the frames: the automatic size's path again), and the adjoint transfer alone (the
     * forward one, a solve per heart node, is the test's longest step; test_fem compares the two) */
    int quick = getenv("THORAX_QUICK") != NULL;
    size_t blocks[] = {0, 8, 1000};
    for (size_t q = 0; q < (quick ? 2 : sizeof blocks / sizeof *blocks); q++) {
        fo.block = blocks[q];
        CHECK_OK(ctx, thx_forward_epicardial(ctx, m, epi, &fo, &RB));
        if (!RB.torso || !R1.torso) continue;
        double dt = 0, dv = 0;
        for (size_t f = 0; f < F; f++) {
            dt = fmax(dt, rel_diff(RB.torso->v + f * torso->n_nodes, R1.torso->v + f * torso->n_nodes, torso->n_nodes));
            dv = fmax(dv, rel_diff(RB.volume->v + f * m->volume->n_nodes, R1.volume->v + f * m->volume->n_nodes,
                                   m->volume->n_nodes));
        }
        printf("phantom series, %zu frames in blocks of %zu (asked %zu): torso %.1e, volume %.1e from frame by frame "
               "(relative, worst frame); solves %.3f s against %.3f s\n",
               F, RB.block, blocks[q], dt, dv, RB.t_solve, R1.t_solve);
        CHECK(RB.block == (blocks[q] == 0 ? 29 : blocks[q] > F ? F : blocks[q]));
        CHECK(dt < 1e-12 && dv < 1e-12);
        CHECK(RB.it_total == (long)F && RB.max_residual < 1e-12);
        thx_forward_result_free(&RB);
    }
    /* one frame: too few for a factorization, CG + GAMG as before, whatever the block asked */
    {
        thx_series *one = NULL;
        CHECK_OK(ctx, thx_series_create(ctx, nh, 1, &one));
        memcpy(one->v, epi->v + 5 * nh, nh * sizeof *one->v);
        fo.block = 16;
        CHECK_OK(ctx, thx_forward_epicardial(ctx, m, one, &fo, &RB));
        CHECK(RB.block == 1 && !strcmp(RB.ksp, "cg") && RB.it_min > 1);
        if (RB.torso) {
            double d1 = rel_diff(RB.torso->v, R1.torso->v + 5 * torso->n_nodes, torso->n_nodes);
            printf("phantom, one frame by CG + GAMG (%d iterations): %.1e from the factorization's\n", RB.it_max, d1);
            CHECK(d1 < 1e-7);
        }
        thx_forward_result_free(&RB);
        thx_series_destroy(&one);
    }
    /* transfer matrices: forward (a solve per heart node) and adjoint (13 rows), blocked against one by one */
    {
        int32_t rows[13];
        for (int i = 0; i < 13; i++) rows[i] = (int32_t)((size_t)i * torso->n_nodes / 13);
        for (int method = quick ? 1 : 0; method < 2; method++) {
            thx_series *T1 = NULL, *TB = NULL;
            thx_forward_result I1, IB;
            fo.block = 1;
            CHECK_OK(ctx, thx_forward_transfer(ctx, m, rows, 13, method, &fo, &T1, &I1));
            fo.block = method ? 5 : 0; /* 13 rows in 5 + 5 + 3; heart nodes in the own path's automatic blocks (256) */
            CHECK_OK(ctx, thx_forward_transfer(ctx, m, rows, 13, method, &fo, &TB, &IB));
            if (!T1 || !TB) continue;
            double d = rel_diff(TB->v, T1->v, T1->n_rows * T1->n_frames);
            printf("transfer (%s), %zu solves in blocks of %zu: %.1e from one by one; solves %.3f s against %.3f s\n",
                   method ? "adjoint" : "forward", method ? (size_t)13 : nh, IB.block, d, IB.t_solve, I1.t_solve);
            CHECK(d < 1e-12);
            CHECK(I1.block == 1 && IB.block == (method ? 5u : 256u));
            CHECK(IB.it_total == (long)(method ? 13 : nh));
            thx_series_destroy(&T1);
            thx_series_destroy(&TB);
        }
    }
    thx_forward_result_free(&R1);
    thx_series_destroy(&epi);
    thx_model_destroy(&m);
}

/* One solve of R columns of linear fields on the box with a fresh system; the answers into phi, the
   factor's figures into fi. */
static thx_status own_solve_box(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, const thx_volume *v,
                                const unsigned char *onb, size_t R, double *phi, thx_fem_factor_info *fi)
{
    size_t n = v->n_nodes;
    memset(phi, 0, n * R * sizeof *phi);
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n; i++)
            if (onb[i]) phi[j * n + i] = lin(j, v->xyz + 3 * i);
    thx_fem_system *S = NULL;
    thx_status st = thx_fem_system_create(ctx, K, kind, 0, &S);
    if (st == THX_OK) {
        thx_fem_system_hint_rhs(S, R);
        st = thx_fem_solve_block(ctx, S, phi, NULL, R, 0, NULL);
        thx_fem_system_factor_info(S, fi);
    }
    thx_fem_system_destroy(&S);
    return st;
}

/* The symbolic factor kept in the cache (src/fem/chol_cache.h: magic, key, n, nsuper, ssize, xsize, two
   counts, perm, super, pi, px, rows, SHA-256 of all after the key) made wrong but whole: one supernode's
   last row moved to a row its parent's front lacks, the checksum written anew. 1 when done. */
static int symbolic_made_wrong(const char *dir)
{
    char cmd[1400], file[1200] = "";
    snprintf(cmd, sizeof cmd, "ls -t '%s'/symbolic-*.bin 2>/dev/null | head -n 1", dir);
    FILE *ls = popen(cmd, "r");
    int listed = ls && fgets(file, sizeof file, ls) != NULL;
    if (ls) pclose(ls);
    file[strcspn(file, "\n")] = 0;
    size_t len = 0;
    unsigned char *b = listed ? (unsigned char *)tl_slurp(NULL, file, &len) : NULL;
    if (!b || len < 8 + 32 + 32 + 16 + 32) { free(b); return 0; }
    uint64_t hdr[4];
    memcpy(hdr, b + 40, sizeof hdr);
    int64_t n = (int64_t)hdr[0], ns = (int64_t)hdr[1];
    int64_t *blk = (int64_t *)(b + 40 + 32 + 16);
    int64_t *super = blk + n, *pi = super + ns + 1, *rows = pi + 2 * (ns + 1);
    int done = 0;
    for (int64_t sn = 0; sn < ns && !done; sn++) {
        int64_t k = super[sn + 1] - super[sn], r = pi[sn + 1] - pi[sn];
        if (r - k < 2) continue;
        int64_t last = rows[pi[sn] + r - 1], first_below = rows[pi[sn] + k];
        int64_t p = 0;
        while (!(super[p] <= first_below && first_below < super[p + 1])) p++;
        for (int64_t cand = last + 1; cand < n && !done; cand++) {
            int in_parent = 0;
            for (int64_t t = pi[p]; t < pi[p + 1]; t++) in_parent |= rows[t] == cand;
            if (!in_parent) { rows[pi[sn] + r - 1] = cand; done = 1; }
        }
    }
    if (done) {
        thx_sha256_ctx h;
        thx_sha256_init(&h);
        thx_sha256_update(&h, b + 40, len - 40 - 32);
        thx_sha256_final(&h, b + len - 32);
        FILE *f = fopen(file, "wb");
        done = f && fwrite(b, 1, len, f) == len;
        if (f) fclose(f);
    }
    free(b);
    return done;
}

/* thorax's own direct path (src/fem/cholesky.h): the ordering computed once and kept in the cache
   (THORAX_CACHE_DIR), read back the next time with the same answers to the bit, a damaged cache file
   computed again, an unwritable cache said and solved anyway; linear fields exact; the same answers as
   PETSc's interface to CHOLMOD (-thorax_direct petsc) and on 1 and 2 threads. */
static void own_path_tests(thx_ctx *ctx)
{
    if (tl_scratch_make("fem_own") != 0) { CHECK(0); return; }
    setenv("THORAX_CACHE_DIR", tl_path("cache"), 1);
    unsigned char *onb = NULL;
    thx_volume *v = box(ctx, 0, &onb);
    thx_csr K;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    size_t n = v->n_nodes, R = 20;
    unsigned char *kind = malloc(n);
    for (size_t i = 0; i < n; i++) kind[i] = onb[i] ? 2 : 1;
    double *a = malloc(n * R * sizeof *a), *b = malloc(n * R * sizeof *b);
    thx_fem_factor_info fi;
    /* first: METIS runs, the ordering is stored */
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, a, &fi));
    CHECK(fi.used == 1 && fi.ordering_cached == 0 && fi.cache_note[0] == 0 && fi.flops > 0 && fi.nonzeros > 0);
    CHECK(fi.solve_flops > 0);
    double err = 0;
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n; i++) err = fmax(err, fabs(a[j * n + i] - lin(j, v->xyz + 3 * i)));
    CHECK(err < 1e-11);
    char cmd[1400], file[1200] = "";
    snprintf(cmd, sizeof cmd, "ls '%s'/ordering-*.bin 2>/dev/null", tl_path("cache"));
    FILE *ls = popen(cmd, "r");
    int listed = ls && fgets(file, sizeof file, ls) != NULL;
    if (ls) pclose(ls);
    file[strcspn(file, "\n")] = 0;
    CHECK(listed);
    /* second: read from the cache (the ordering and the symbolic factor), the same answers to the bit */
    CHECK(fi.symbolic_cached == 0);
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
    CHECK(fi.used == 1 && fi.ordering_cached == 1 && fi.symbolic_cached == 1);
    CHECK(memcmp(a, b, n * R * sizeof *a) == 0);
    /* a damaged cache file (two entries of the ordering swapped: still a permutation, but not the one its
       checksum names) is computed again, with the same answers, and stored whole again */
    if (listed) {
        FILE *f = fopen(file, "r+b");
        int64_t p[2];
        int ok = f && fseek(f, 8 + 8 + 32, SEEK_SET) == 0 && fread(p, sizeof *p, 2, f) == 2;
        int64_t q[2] = {p[1], p[0]};
        ok = ok && fseek(f, 8 + 8 + 32, SEEK_SET) == 0 && fwrite(q, sizeof *q, 2, f) == 2;
        if (f) fclose(f);
        CHECK(ok);
        CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
        CHECK(fi.used == 1 && fi.ordering_cached == 0);
        CHECK(memcmp(a, b, n * R * sizeof *a) == 0);
        CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
        CHECK(fi.ordering_cached == 1);
    }
    /* a cache directory that cannot be made (under a regular file): said, and solved the same */
    FILE *blocker = fopen(tl_path("plainfile"), "w");
    if (blocker) fclose(blocker);
    char sub[1200];
    snprintf(sub, sizeof sub, "%s/cache", tl_path("plainfile"));
    setenv("THORAX_CACHE_DIR", sub, 1);
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
    CHECK(fi.used == 1 && fi.ordering_cached == 0 && strstr(fi.cache_note, "cache directory") != NULL);
    CHECK(memcmp(a, b, n * R * sizeof *a) == 0);
    printf("own path: linear fields to %.1e; ordering cached, recomputed when damaged, unwritable cache: \"%s\"\n", err,
           fi.cache_note);
    setenv("THORAX_CACHE_DIR", tl_path("cache"), 1);
    /* two threads (columns dealt in two groups) against one */
#ifdef _OPENMP
    int was = omp_get_max_threads();
    omp_set_num_threads(2);
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
    omp_set_num_threads(was);
    double d2 = rel_diff(b, a, n * R);
    CHECK(d2 < 1e-13);
    printf("own path: 2 threads against %d: %.1e\n", was, d2);
#endif
    /* our multifrontal factorization (src/fem/multifrontal.h) against CHOLMOD's numeric one on the same
       analysis, and on 1, 2 and 3 threads (the tree cut into subtrees for 2 and 3, the rest above them) */
    CHECK(strstr(fi.numeric, "multifrontal") != NULL);
    PetscOptionsSetValue(NULL, "-thorax_factor", "cholmod");
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
    PetscOptionsClearValue(NULL, "-thorax_factor");
    CHECK(fi.used == 1 && strstr(fi.numeric, "CHOLMOD") != NULL && fi.threads == 0);
    double dc = rel_diff(b, a, n * R);
    CHECK(dc < 1e-12);
    printf("own path: our factorization against CHOLMOD's: %.1e\n", dc);
    /* a box large enough for a tree of many supernodes (18^3 nodes) */
    unsigned char *onb2 = NULL;
    thx_volume *v2 = box_of(ctx, 18, 0, &onb2);
    thx_csr K2;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v2, NULL, &K2));
    size_t n2 = v2->n_nodes;
    unsigned char *kind2 = malloc(n2);
    for (size_t i = 0; i < n2; i++) kind2[i] = onb2[i] ? 2 : 1;
    double *a2 = malloc(n2 * R * sizeof *a2), *b2 = malloc(n2 * R * sizeof *b2);
    setenv("THORAX_FACTOR_THREADS", "1", 1);
    CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, a2, &fi));
    double e2 = 0;
    for (size_t j = 0; j < R; j++)
        for (size_t i = 0; i < n2; i++) e2 = fmax(e2, fabs(a2[j * n2 + i] - lin(j, v2->xyz + 3 * i)));
    CHECK(e2 < 1e-10);
    printf("own path, %zu nodes: linear fields to %.1e\n", n2, e2);
    /* the symbolic factor in the cache made wrong but whole (its checksum right): the factorization finds the
       missing row as it assembles, analyses again and answers the same */
    CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, b2, &fi));
    CHECK(fi.symbolic_cached == 1 && memcmp(a2, b2, n2 * R * sizeof *a2) == 0);
    CHECK(symbolic_made_wrong(tl_path("cache")));
    CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, b2, &fi));
    CHECK(fi.symbolic_cached == 0 && memcmp(a2, b2, n2 * R * sizeof *a2) == 0);
    CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, b2, &fi));
    CHECK(fi.symbolic_cached == 1 && memcmp(a2, b2, n2 * R * sizeof *a2) == 0);
    /* a header that claims more than the file holds (its row count 2^39): refused before any allocation */
    {
        char lcmd[1400], sym[1200] = "";
        snprintf(lcmd, sizeof lcmd, "ls -t '%s'/symbolic-*.bin 2>/dev/null | head -n 1", tl_path("cache"));
        FILE *lp = popen(lcmd, "r");
        int found = lp && fgets(sym, sizeof sym, lp) != NULL;
        if (lp) pclose(lp);
        sym[strcspn(sym, "\n")] = 0;
        FILE *f = found ? fopen(sym, "r+b") : NULL;
        uint64_t big = (uint64_t)1 << 39;
        int ok = f && fseek(f, 8 + 32 + 16, SEEK_SET) == 0 && fwrite(&big, sizeof big, 1, f) == 1;
        if (f) fclose(f);
        CHECK(ok);
        CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, b2, &fi));
        CHECK(fi.symbolic_cached == 0 && memcmp(a2, b2, n2 * R * sizeof *a2) == 0);
    }
    printf("own path: a wrong symbolic factor in the cache found, analysed again, kept again; an oversized claim "
           "refused\n");

    for (int th = 1; th <= 3; th++) {
        char tn[8];
        snprintf(tn, sizeof tn, "%d", th);
        setenv("THORAX_FACTOR_THREADS", tn, 1);
        CHECK_OK(ctx, own_solve_box(ctx, &K2, kind2, v2, onb2, R, b2, &fi));
        double dt = rel_diff(b2, a2, n2 * R);
        CHECK(fi.threads == th && dt < 1e-12);
        CHECK(th == 1 ? fi.subtrees == 1 && fi.top == 0 : fi.subtrees >= (size_t)th && fi.top >= 1);
        CHECK(fi.top_share >= 0 && fi.top_share < 1);
        printf("own path: factorization on %d thread%s: %zu subtrees, %zu supernodes above them (%.0f %% of the work): "
               "%.1e\n", th, th > 1 ? "s" : "", fi.subtrees, fi.top, 100 * fi.top_share, dt);
    }
    unsetenv("THORAX_FACTOR_THREADS");
    free(a2);
    free(b2);
    free(kind2);
    free(onb2);
    thx_csr_free(&K2);
    thx_volume_destroy(&v2);
    PetscOptionsSetValue(NULL, "-thorax_factor", "frontal");
    thx_status bad = own_solve_box(ctx, &K, kind, v, onb, R, b, &fi);
    PetscOptionsClearValue(NULL, "-thorax_factor");
    CHECK(bad == THX_EINPUT && strstr(thx_ctx_message(ctx), "-thorax_factor frontal") != NULL);
    /* PETSc's interface to the same package */
    PetscOptionsSetValue(NULL, "-thorax_direct", "petsc");
    CHECK_OK(ctx, own_solve_box(ctx, &K, kind, v, onb, R, b, &fi));
    PetscOptionsClearValue(NULL, "-thorax_direct");
    CHECK(fi.used == 0);
    double dp = rel_diff(b, a, n * R);
    CHECK(dp < 1e-12);
    printf("own path against PETSc's interface to CHOLMOD: %.1e\n", dp);
    free(a);
    free(b);
    free(kind);
    free(onb);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    unsetenv("THORAX_CACHE_DIR");
    char rm[1200];
    snprintf(rm, sizeof rm, "rm -rf '%s'", tl_scratch);
    if (!tl_fail && system(rm) != 0) fprintf(stderr, "could not remove %s\n", tl_scratch);
}

/* thx_fem_solve_rows: the prescribed values per prescribed node in, a few rows out; the same answers as
   thx_fem_solve_block's columns of every node, on the own path, through PETSc's interface to CHOLMOD, and
   with CG frame by frame; a node list that does not match the system refused. */
static void rows_tests(thx_ctx *ctx)
{
    unsigned char *onb = NULL;
    thx_volume *v = box_of(ctx, 10, 0, &onb);
    thx_csr K;
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    size_t n = v->n_nodes, R = 30, np = 0, m = 0;
    unsigned char *kind = malloc(n);
    int32_t *pnode = malloc(n * sizeof *pnode), *rows = malloc(n * sizeof *rows);
    for (size_t i = 0; i < n; i++) {
        kind[i] = onb[i] ? 2 : 1;
        if (onb[n - 1 - i]) pnode[np++] = (int32_t)(n - 1 - i); /* the caller's own order: backwards */
        if (i % 7 == 3) rows[m++] = (int32_t)i;                 /* free and prescribed rows */
    }
    double *phi = malloc(n * R * sizeof *phi), *pres = malloc(np * R * sizeof *pres);
    double *out = malloc(m * R * sizeof *out), *want = malloc(m * R * sizeof *want);
    const char *how[3] = {"own", "petsc", "cg"};
    for (int h = 0; h < 3; h++) {
        if (h == 1) PetscOptionsSetValue(NULL, "-thorax_direct", "petsc");
        memset(phi, 0, n * R * sizeof *phi);
        for (size_t j = 0; j < R; j++) {
            for (size_t c = 0; c < np; c++) {
                const double *x = v->xyz + 3 * (size_t)pnode[c];
                pres[j * np + c] = phi[j * n + (size_t)pnode[c]] = sin(0.3 * x[0] + 0.1 * (double)j) + x[1] * x[2] * 0.01;
            }
        }
        thx_fem_system *S = NULL;
        CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S));
        if (h < 2) thx_fem_system_hint_rhs(S, R);
        thx_fem_solve_stats a, b;
        CHECK_OK(ctx, thx_fem_solve_block(ctx, S, phi, NULL, R, 0, &a));
        for (size_t j = 0; j < R; j++)
            for (size_t i = 0; i < m; i++) want[j * m + i] = phi[j * n + (size_t)rows[i]];
        CHECK_OK(ctx, thx_fem_solve_rows(ctx, S, pnode, np, pres, R, 0, rows, m, out, &b));
        double d = rel_diff(out, want, m * R);
        CHECK(d < (h == 2 ? 1e-6 : 1e-14) && b.residual < 1e-6 && b.block >= 1);
        CHECK(h == 2 ? b.iterations_total > (long)R : b.iterations_total == (long)R);
        printf("solve_rows (%s): %zu of %zu rows, %zu frames, block %zu: %.1e from the columns of every node\n", how[h], m,
               n, R, b.block, d);
        if (h == 0) {
            /* the rows alone: the backward sweep pruned, the block checked by two combinations of its columns
               (fem.h, thx_fem_solve_stats); a column made wrong by 1e-6 of itself is found, one by 1e-13 is
               within rounding's reach and passes */
            printf("solve_rows (own): backward sweep %.0f %% of its flops, check %.1e, combined residual %.1e\n",
                   100 * b.backward_share, b.check, b.residual);
            CHECK(b.backward_share > 0 && b.backward_share < 1 && b.check < 1e-13 && b.residual < 1e-13);
#ifdef _OPENMP
            /* the columns dealt to 2 and 3 threads: the partial sums of the check added in the threads' order */
            double *out1 = malloc(m * R * sizeof *out1);
            int was = omp_get_max_threads();
            for (int th = 2; th <= 3; th++) {
                omp_set_num_threads(th);
                CHECK_OK(ctx, thx_fem_solve_rows(ctx, S, pnode, np, pres, R, 0, rows, m, out1, &b));
                CHECK(rel_diff(out1, want, m * R) < 1e-14 && b.check < 1e-13 && b.residual < 1e-13);
                printf("solve_rows (own), %d threads: %.1e from the columns of every node, check %.1e\n", th,
                       rel_diff(out1, want, m * R), b.check);
            }
            /* a fresh system asked for rows on 2 and 3 threads: the top of its factorization factored by one
               thread while the others run the forward sweep below it, the same answers */
            for (int th = 2; th <= 3; th++) {
                omp_set_num_threads(th);
                thx_fem_system *S2 = NULL;
                CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S2));
                thx_fem_system_hint_rhs(S2, R);
                CHECK_OK(ctx, thx_fem_solve_rows(ctx, S2, pnode, np, pres, R, 0, rows, m, out1, &b));
                thx_fem_factor_info fi;
                thx_fem_system_factor_info(S2, &fi);
                CHECK(fi.used && fi.top > 0 && fi.top_beside == 1);
                CHECK(rel_diff(out1, want, m * R) < 1e-14 && b.check < 1e-13 && b.residual < 1e-13);
                printf("solve_rows (own), %d threads, the top beside the solves: %zu supernodes, %.1e from the columns of "
                       "every node, check %.1e\n", th, fi.top, rel_diff(out1, want, m * R), b.check);
                /* a second call on the same system: the factor complete, the same answers to the bit as a third */
                double *out2 = malloc(m * R * sizeof *out2);
                CHECK_OK(ctx, thx_fem_solve_rows(ctx, S2, pnode, np, pres, R, 0, rows, m, out2, &b));
                CHECK_OK(ctx, thx_fem_solve_rows(ctx, S2, pnode, np, pres, R, 0, rows, m, out1, &b));
                CHECK(memcmp(out1, out2, m * R * sizeof *out1) == 0);
                free(out2);
                thx_fem_system_destroy(&S2);
                /* the top beside the solves failing on a pivot: the system handed to PETSc's interface, as when
                   the subtrees meet one, and solved there (-thorax_test_fail_top: the failure made) */
                PetscOptionsSetValue(NULL, "-thorax_test_fail_top", NULL);
                CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S2));
                thx_fem_system_hint_rhs(S2, R);
                thx_status hs = thx_fem_solve_rows(ctx, S2, pnode, np, pres, R, 0, rows, m, out1, &b);
                PetscOptionsClearValue(NULL, "-thorax_test_fail_top");
                thx_fem_system_factor_info(S2, &fi);
                CHECK(hs == THX_OK && !fi.used && rel_diff(out1, want, m * R) < 1e-12);
                printf("solve_rows (own), %d threads, the top failing beside the solves: %s, handed to PETSc, %.1e from "
                       "the columns of every node\n", th, hs ? thx_ctx_message(ctx) : "solved", rel_diff(out1, want, m * R));
                thx_fem_system_destroy(&S2);
            }
            omp_set_num_threads(was);
            free(out1);
#endif
            for (int spoil = 0; spoil < 2; spoil++) {
                PetscOptionsSetValue(NULL, "-thorax_test_spoil_column", "7");
                PetscOptionsSetValue(NULL, "-thorax_test_spoil_by", spoil ? "1e-13" : "1e-6");
                thx_status sp = thx_fem_solve_rows(ctx, S, pnode, np, pres, R, 0, rows, m, out, &b);
                PetscOptionsClearValue(NULL, "-thorax_test_spoil_column");
                PetscOptionsClearValue(NULL, "-thorax_test_spoil_by");
                printf("solve_rows (own), column 7 made wrong by %s: %s\n", spoil ? "1e-13" : "1e-6",
                       sp ? thx_ctx_message(ctx) : "passed");
                if (!spoil) CHECK(sp == THX_EINTERNAL && strstr(thx_ctx_message(ctx), "disagrees") != NULL);
                else CHECK(sp == THX_OK && b.check < 1e-9);
            }
            /* a prescribed node left out, and a free node given a value */
            thx_status bad = thx_fem_solve_rows(ctx, S, pnode, np - 1, pres, R, 0, rows, m, out, &b);
            CHECK(bad == THX_EINTERNAL && strstr(thx_ctx_message(ctx), "has no value") != NULL);
            int32_t keep = pnode[0];
            int32_t inner = 0;
            while (onb[inner]) inner++;
            pnode[0] = inner;
            bad = thx_fem_solve_rows(ctx, S, pnode, np, pres, R, 0, rows, m, out, &b);
            CHECK(bad == THX_EINTERNAL && strstr(thx_ctx_message(ctx), "does not prescribe") != NULL);
            pnode[0] = keep;
        }
        thx_fem_system_destroy(&S);
        if (h == 1) PetscOptionsClearValue(NULL, "-thorax_direct");
    }
    free(phi);
    free(pres);
    free(out);
    free(want);
    free(pnode);
    free(rows);
    free(kind);
    free(onb);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
}

int main(int argc, char **argv)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    CHECK_OK(ctx, thx_fem_init(argc, argv, NULL, NULL));
    box_tests(ctx, NULL);
    box_tests(ctx, "mumps");
    own_path_tests(ctx);
    rows_tests(ctx);
    singular_tests(ctx);
    phantom_tests(ctx);
    thx_fem_finalize();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
