/*
 * Finite elements (thorax/fem/fem.h): assembly properties, the linear patch test
 * (isotropic and anisotropic), Neumann loads, currents, and on the medium
 * phantom the epicardial forward problem against its transfer matrix (both
 * methods) and current conservation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/fem/fem.h"
#include "thorax/mesh/mesh.h"
#include "thorax/phantom/phantom.h"
#include "thorax/geom/surfaces.h"
#define N 7

/* A jittered lattice in [0, N-1]^3, tetrahedralized; boundary nodes (on the cube's faces) flagged. */
static thx_volume *box(thx_ctx *ctx, const double sigma[9], unsigned char **on_boundary)
{
    thx_volume *v = NULL;
    thx_volume_create(ctx, &v);
    size_t n = N * N * N, k = 0;
    v->n_nodes = n;
    v->xyz = malloc(3 * n * sizeof *v->xyz);
    *on_boundary = calloc(n, 1);
    srand(3);
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            for (int l = 0; l < N; l++, k++) {
                int on = i == 0 || j == 0 || l == 0 || i == N - 1 || j == N - 1 || l == N - 1;
                double jit = on ? 0 : 0.2;
                v->xyz[3 * k] = i + jit * (rand() / (double)RAND_MAX - 0.5);
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
    memcpy(v->regions[0].sigma, sigma, 9 * sizeof(double));
    return v;
}

static double linear(const double *p) { return 0.3 * p[0] - 0.7 * p[1] + 1.1 * p[2] + 2.0; }

static thx_model *phantom_model(thx_ctx *ctx)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    thx_mesh_opts mo;
    thx_mesh_opts_default(&mo);
    mo.no_heart = 1;
    CHECK_OK(ctx, thx_mesh_build(ctx, m, &mo, NULL));
    return m;
}

int main(int argc, char **argv)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    CHECK_OK(ctx, thx_fem_init(argc, argv, NULL, NULL));

    /* 1. assembly: symmetric, rows sum to zero, positive diagonal; linear patch test (iso and aniso) */
    const double iso[9] = {0.2, 0, 0, 0, 0.2, 0, 0, 0, 0.2};
    const double aniso[9] = {0.5, 0.1, 0.05, 0.1, 0.3, -0.04, 0.05, -0.04, 0.1};
    for (int which = 0; which < 2; which++) {
        unsigned char *onb = NULL;
        thx_volume *v = box(ctx, which ? aniso : iso, &onb);
        thx_csr K;
        CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
        double asym = 0, rowsum = 0, mindiag = INFINITY;
        for (int32_t i = 0; i < K.n_rows; i++) {
            double s = 0;
            for (int64_t k = K.row[i]; k < K.row[i + 1]; k++) {
                int32_t j = K.col[k];
                s += K.val[k];
                if (j == i) mindiag = fmin(mindiag, K.val[k]);
                /* K(j, i) */
                double kji = 0;
                for (int64_t q = K.row[j]; q < K.row[j + 1]; q++)
                    if (K.col[q] == i) kji = K.val[q];
                asym = fmax(asym, fabs(K.val[k] - kji));
            }
            rowsum = fmax(rowsum, fabs(s));
        }
        CHECK(asym < 1e-14);
        CHECK(rowsum < 1e-13);
        CHECK(mindiag > 0);
        /* K u = 0 at interior nodes for a linear u (any sigma: the patch test) */
        double *u = malloc(v->n_nodes * sizeof *u), *Ku = malloc(v->n_nodes * sizeof *Ku);
        for (size_t i = 0; i < v->n_nodes; i++) u[i] = linear(v->xyz + 3 * i);
        thx_csr_mul(&K, u, Ku);
        double worst = 0;
        for (size_t i = 0; i < v->n_nodes; i++)
            if (!onb[i]) worst = fmax(worst, fabs(Ku[i]));
        CHECK(worst < 1e-12);
        /* the solve reproduces the linear field from its boundary values */
        unsigned char *kind = malloc(v->n_nodes);
        for (size_t i = 0; i < v->n_nodes; i++) kind[i] = onb[i] ? 2 : 1;
        thx_fem_system *S = NULL;
        CHECK_OK(ctx, thx_fem_system_create(ctx, &K, kind, 0, &S));
        double *phi = calloc(v->n_nodes, sizeof *phi);
        for (size_t i = 0; i < v->n_nodes; i++)
            if (onb[i]) phi[i] = u[i];
        thx_fem_solve_stats ss;
        CHECK_OK(ctx, thx_fem_solve(ctx, S, phi, NULL, 0, &ss));
        double err = 0;
        for (size_t i = 0; i < v->n_nodes; i++) err = fmax(err, fabs(phi[i] - u[i]));
        printf("patch test (%s): max error %.2e after %d iterations\n", which ? "anisotropic" : "isotropic", err, ss.iterations);
        CHECK(err < 1e-7);
        /* currents: J = -sigma grad u * 1000 in every tetrahedron */
        double *jt = malloc(3 * v->n_tets * sizeof *jt), *jn = malloc(3 * v->n_nodes * sizeof *jn);
        thx_fem_currents(v, NULL, u, jt, jn);
        const double *s = v->regions[0].sigma, g[3] = {0.3, -0.7, 1.1};
        double jerr = 0;
        for (int c = 0; c < 3; c++) {
            double J = -1000 * (s[3 * c] * g[0] + s[3 * c + 1] * g[1] + s[3 * c + 2] * g[2]);
            for (size_t t = 0; t < v->n_tets; t++) jerr = fmax(jerr, fabs(jt[3 * t + c] - J));
            for (size_t i = 0; i < v->n_nodes; i++) jerr = fmax(jerr, fabs(jn[3 * i + c] - J));
        }
        CHECK(jerr < 1e-9);
        /* Neumann: inject +1 mA at one interior node, take it out at another, pin one node: the
           residual of K phi equals the loads, and the currents into each node balance */
        if (which == 0) {
            unsigned char *k2 = malloc(v->n_nodes);
            memset(k2, 1, v->n_nodes);
            thx_fem_system *S2 = NULL;
            CHECK_OK(ctx, thx_fem_system_create(ctx, &K, k2, 1, &S2));
            double *load = calloc(v->n_nodes, sizeof *load), *p2 = calloc(v->n_nodes, sizeof *p2);
            size_t a = (N / 2 * N + N / 2) * N + 1, b = (N / 2 * N + N / 2) * N + N - 2;
            load[a] = 1;
            load[b] = -1;
            CHECK_OK(ctx, thx_fem_solve(ctx, S2, p2, load, 0, &ss));
            double *r = malloc(v->n_nodes * sizeof *r);
            thx_csr_mul(&K, p2, r);
            double bal = 0;
            for (size_t i = 0; i < v->n_nodes; i++)
                if (i != 0) bal = fmax(bal, fabs(r[i] - load[i]));
            CHECK(bal < 1e-8);
            CHECK(p2[a] > p2[b]); /* current flows from a to b */
            free(r);
            free(load);
            free(p2);
            free(k2);
            thx_fem_system_destroy(&S2);
        }
        /* a non-positive-definite tensor is refused, naming the region */
        v->regions[0].sigma[8] = -0.1;
        thx_csr K2;
        CHECK(thx_fem_assemble(ctx, v, NULL, &K2) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "'test'") != NULL);
        free(jt);
        free(jn);
        free(phi);
        free(kind);
        free(u);
        free(Ku);
        free(onb);
        thx_fem_system_destroy(&S);
        thx_csr_free(&K);
        thx_volume_destroy(&v);
    }

    /* 2. the medium phantom: frames, transfer matrices (both methods), conservation, bad input */
    {
        thx_model *m = phantom_model(ctx);
        const thx_surface *heart = NULL, *torso = NULL;
        for (size_t s = 0; s < m->n_surfaces; s++) {
            if (m->surf[s]->role == THX_ROLE_HEART) heart = m->surf[s];
            if (m->surf[s]->role == THX_ROLE_OUTER) torso = m->surf[s];
        }
        size_t nh = heart->n_nodes, F = 3;
        thx_series *epi = NULL;
        CHECK_OK(ctx, thx_series_create(ctx, nh, F, &epi));
        snprintf(epi->unit, sizeof epi->unit, "mV");
        double c[3] = {0, 0, 0};
        for (size_t i = 0; i < nh; i++)
            for (int d = 0; d < 3; d++) c[d] += heart->xyz[3 * i + d] / (double)nh;
        for (size_t f = 0; f < F; f++)
            for (size_t i = 0; i < nh; i++) {
                const double *p = heart->xyz + 3 * i;
                double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]}, r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                epi->v[f * nh + i] = 1e4 * (d[f % 3] + 0.3 * d[(f + 1) % 3]) / (r * r * r);
            }
        thx_forward_opts fo;
        thx_forward_opts_default(&fo);
        fo.keep_volume = 1;
        thx_forward_result R;
        CHECK_OK(ctx, thx_forward_epicardial(ctx, m, epi, &fo, &R));
        printf("phantom: %zu free, %zu prescribed nodes; %d..%d iterations; assembly %.2f s, setup %.2f s, %zu solves %.2f s\n",
               R.n_free, R.n_prescribed, R.it_min, R.it_max, R.t_assemble, R.t_setup, F, R.t_solve);
        CHECK(R.torso && R.torso->n_rows == torso->n_nodes && R.torso->n_frames == F);
        CHECK(R.max_residual < 1e-8);
        /* conservation: no current leaves through the torso, so the currents the heart injects sum to
           zero: sum over prescribed nodes of (K phi) = 0 relative to their magnitude */
        {
            unsigned char use[16];
            for (size_t r = 0; r < m->volume->n_regions; r++) use[r] = strcmp(m->volume->regions[r].name, "heart") != 0;
            thx_csr K;
            CHECK_OK(ctx, thx_fem_assemble(ctx, m->volume, use, &K));
            double *Kp = malloc(m->volume->n_nodes * sizeof *Kp);
            size_t hs = 0;
            for (size_t s = 0; s < m->n_surfaces; s++)
                if (m->surf[s] == heart) hs = s;
            /* the heart nodes carry their prescribed values, and the Steiner nodes on the heart the
               barycentric mix of their triangle's corners' (exactly as computed, every frame) */
            const thx_volume *v = m->volume;
            double herr = 0, serr = 0;
            size_t n_st = 0;
            for (size_t i = 0; i < nh; i++) herr = fmax(herr, fabs(R.volume->v[v->surf_node[hs][i]] - epi->v[i]));
            CHECK(herr == 0);
            for (size_t k = 0; k < v->n_steiner; k++) {
                const thx_steiner *st = &v->steiner[k];
                if (st->surf != (int32_t)hs) continue;
                n_st++;
                const int32_t *tc = heart->tri + 3 * (size_t)st->tri;
                for (size_t f = 0; f < F; f++) {
                    const double *e = epi->v + f * nh;
                    double want = st->bary[0] * e[tc[0]] + st->bary[1] * e[tc[1]] + st->bary[2] * e[tc[2]];
                    serr = fmax(serr, fabs(R.volume->v[f * v->n_nodes + (size_t)st->node] - want));
                }
            }
            printf("phantom: %zu Steiner nodes on the heart, largest deviation from their interpolated value %.1e\n",
                   n_st, serr);
            CHECK(n_st > 0 && serr == 0);
            CHECK(R.n_prescribed == nh + n_st);
            for (size_t f = 0; f < F; f++) {
                thx_csr_mul(&K, R.volume->v + f * m->volume->n_nodes, Kp);
                double net = 0, mag = 0;
                for (size_t i = 0; i < nh; i++) {
                    double q = Kp[m->volume->surf_node[hs][i]];
                    net += q;
                    mag += fabs(q);
                }
                for (size_t k = 0; k < v->n_steiner; k++)
                    if (v->steiner[k].surf == (int32_t)hs) {
                        double q = Kp[v->steiner[k].node];
                        net += q;
                        mag += fabs(q);
                    }
                printf("frame %zu: current out of the heart %.3e of %.3e (relative %.1e)\n", f + 1, net, mag, fabs(net) / mag);
                CHECK(fabs(net) < 1e-7 * mag);
                /* and through closed surfaces further out: the node sets within 80, 100, 120 mm of the
                   heart's centre (each holds the whole heart) exchange no net current with the rest */
                for (double rad = 80; rad <= 120; rad += 20) {
                    double sum = 0;
                    size_t inside_heart = 0;
                    for (size_t i = 0; i < m->volume->n_nodes; i++) {
                        const double *x = m->volume->xyz + 3 * i;
                        double d = sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2]));
                        if (d < rad) sum += Kp[i];
                    }
                    for (size_t i = 0; i < nh; i++) {
                        const double *x = heart->xyz + 3 * i;
                        inside_heart += sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2])) < rad;
                    }
                    if (inside_heart < nh) continue;
                    if (f == 0) printf("  through the sphere r = %.0f mm: %.1e of %.3e\n", rad, fabs(sum), mag);
                    CHECK(fabs(sum) < 1e-7 * mag);
                }
            }
            free(Kp);
            thx_csr_free(&K);
        }
        /* transfer matrix, forward (a solve per heart node) and adjoint (a solve per row) on 12 rows */
        int32_t rows[12];
        for (int i = 0; i < 12; i++) rows[i] = (int32_t)((size_t)i * torso->n_nodes / 12);
        thx_series *Ta = NULL, *Tfull = NULL, *phi = NULL;
        CHECK_OK(ctx, thx_forward_transfer(ctx, m, rows, 12, 1, NULL, &Ta, NULL));
        CHECK_OK(ctx, thx_forward_transfer(ctx, m, NULL, 0, 0, NULL, &Tfull, NULL));
        CHECK(Tfull->n_rows == torso->n_nodes && Tfull->n_frames == nh);
        double terr = 0, tmax = 0;
        for (size_t j = 0; j < nh; j++)
            for (int i = 0; i < 12; i++) {
                double a = Ta->v[j * 12 + (size_t)i], b = Tfull->v[j * torso->n_nodes + (size_t)rows[i]];
                terr = fmax(terr, fabs(a - b));
                tmax = fmax(tmax, fabs(b));
            }
        printf("transfer: adjoint vs forward rows differ by %.2e (largest entry %.3f)\n", terr, tmax);
        CHECK(terr < 1e-7);
        /* the automatic choice takes the method with fewer solves: a solve per row for 12 rows, a
           solve per heart node for every torso node (the torso has more nodes than the heart) */
        {
            thx_series *Tauto = NULL;
            CHECK(torso->n_nodes > nh && nh > 12);
            CHECK_OK(ctx, thx_forward_transfer(ctx, m, rows, 12, -1, NULL, &Tauto, NULL));
            CHECK(Tauto && strstr(Tauto->label, "(adjoint)") != NULL);
            thx_series_destroy(&Tauto);
            CHECK_OK(ctx, thx_forward_transfer(ctx, m, NULL, 0, -1, NULL, &Tauto, NULL));
            CHECK(Tauto && strstr(Tauto->label, "(forward)") != NULL);
            thx_series_destroy(&Tauto);
        }
        /* electrodes between nodes (thx_forward_transfer_weighted): a row is the same weighted sum of
           node rows, by either method, whatever the weights */
        {
            int32_t corner[3 * 4];
            double weight[3 * 4];
            for (int i = 0; i < 4; i++) {
                const int32_t *t = torso->tri + 3 * ((size_t)(i + 1) * torso->n_tris / 5);
                double a = 0.1 + 0.2 * i, b = 0.6 - 0.1 * i;
                for (int k = 0; k < 3; k++) corner[3 * i + k] = t[k];
                weight[3 * i] = a;
                weight[3 * i + 1] = b;
                weight[3 * i + 2] = 1 - a - b;
            }
            for (int method = 0; method < 2; method++) {
                thx_series *Tw = NULL;
                CHECK_OK(ctx, thx_forward_transfer_weighted(ctx, m, corner, weight, 4, method, NULL, &Tw, NULL));
                if (!Tw) continue;
                CHECK(Tw->n_rows == 4 && Tw->n_frames == nh && strstr(Tw->label, "electrodes") != NULL);
                double werr = 0;
                for (size_t j = 0; j < nh; j++)
                    for (int i = 0; i < 4; i++) {
                        double want = 0;
                        for (int k = 0; k < 3; k++)
                            want += weight[3 * i + k] * Tfull->v[j * torso->n_nodes + (size_t)corner[3 * i + k]];
                        werr = fmax(werr, fabs(Tw->v[j * 4 + (size_t)i] - want));
                    }
                printf("transfer: off-node rows (%s) vs weighted node rows differ by %.2e\n", method ? "adjoint" : "forward",
                       werr);
                CHECK(werr < 1e-7);
                thx_series_destroy(&Tw);
            }
        }
        /* rows of the transfer matrix sum to one: a constant on the heart gives that constant everywhere */
        double rs = 0;
        for (size_t i = 0; i < torso->n_nodes; i++) {
            double s = 0;
            for (size_t j = 0; j < nh; j++) s += Tfull->v[j * torso->n_nodes + i];
            rs = fmax(rs, fabs(s - 1));
        }
        CHECK(rs < 1e-7);
        /* applying it reproduces the frame-by-frame solution */
        CHECK_OK(ctx, thx_transfer_apply(ctx, Tfull, epi, &phi));
        double perr = 0, pmax = 0;
        for (size_t k = 0; k < torso->n_nodes * F; k++) {
            perr = fmax(perr, fabs(phi->v[k] - R.torso->v[k]));
            pmax = fmax(pmax, fabs(R.torso->v[k]));
        }
        printf("transfer applied vs solved: %.2e (largest %.3f mV)\n", perr, pmax);
        CHECK(perr < 1e-6 * pmax);
        /* a linear potential on the heart's nodes: every Steiner node on the heart gets the same
           linear function at its own position (the Dirichlet data are the piecewise-linear
           interpolant on the heart's triangles, exact for a linear function) */
        {
            thx_series *lin = NULL;
            CHECK_OK(ctx, thx_series_create(ctx, nh, 1, &lin));
            for (size_t i = 0; i < nh; i++) lin->v[i] = linear(heart->xyz + 3 * i);
            thx_forward_result RL;
            CHECK_OK(ctx, thx_forward_epicardial(ctx, m, lin, &fo, &RL));
            const thx_volume *v = m->volume;
            size_t hs = 0, n_st = 0;
            for (size_t s = 0; s < m->n_surfaces; s++)
                if (m->surf[s] == heart) hs = s;
            double lerr = 0, lmax = 0;
            for (size_t k = 0; k < v->n_steiner; k++)
                if (v->steiner[k].surf == (int32_t)hs) {
                    int32_t g = v->steiner[k].node;
                    double want = linear(v->xyz + 3 * (size_t)g);
                    lerr = fmax(lerr, fabs(RL.volume->v[g] - want));
                    lmax = fmax(lmax, fabs(want));
                    n_st++;
                }
            printf("linear heart potential: %zu Steiner nodes on the heart within %.1e of it (largest %.1f)\n", n_st, lerr,
                   lmax);
            /* node coordinates carry 6 decimals: up to 8.7e-7 mm off, times |grad| = 1.34 */
            CHECK(n_st > 0 && lerr < 1.2e-6);
            thx_forward_result_free(&RL);
            thx_series_destroy(&lin);
        }
        /* defibrillation patches hold their Steiner nodes: at the voltage, in the patch's node list */
        {
            const thx_volume *v = m->volume;
            size_t os = 0;
            for (size_t s = 0; s < m->n_surfaces; s++)
                if (m->surf[s] == torso) os = s;
            thx_patch pp[2];
            memset(pp, 0, sizeof pp);
            snprintf(pp[0].name, sizeof pp[0].name, "pad");
            snprintf(pp[1].name, sizeof pp[1].name, "apex");
            pp[0].is_voltage = pp[1].is_voltage = 1;
            pp[0].value = 1.0;
            const double a0[3] = {71, 92, 170}, a1[3] = {-158, -20, 90};
            CHECK_OK(ctx, thx_patch_disc(ctx, m, os, a0, 60.0, &pp[0]));
            CHECK_OK(ctx, thx_patch_disc(ctx, m, os, a1, 60.0, &pp[1]));
            size_t n_surf_nodes = 0, n_st = 0;
            double wsum = 0;
            for (size_t i = 0; i < pp[0].n; i++) {
                int32_t g = pp[0].node[i];
                if (v->node_surf[g] == (int32_t)os) n_surf_nodes++;
                wsum += pp[0].weight[i];
            }
            for (size_t k = 0; k < v->n_steiner; k++)
                for (size_t i = 0; i < pp[0].n; i++) n_st += v->steiner[k].node == pp[0].node[i];
            printf("patch: %zu nodes, %zu of them Steiner nodes, %.0f mm^2\n", pp[0].n, n_st, pp[0].area);
            CHECK(n_st > 0 && n_surf_nodes + n_st == pp[0].n);
            CHECK(fabs(wsum - 1) < 1e-12);
            double *phi_d = NULL;
            thx_defib_report dr;
            CHECK_OK(ctx, thx_defib_solve(ctx, m, pp, 2, 5.0, &phi_d, NULL, &dr));
            double derr = 0;
            for (int e = 0; e < 2; e++)
                for (size_t i = 0; i < pp[e].n; i++) derr = fmax(derr, fabs(phi_d[pp[e].node[i]] - pp[e].value));
            CHECK(derr == 0);
            CHECK(fabs(dr.current[0] + dr.current[1]) < 1e-6 * fabs(dr.current[0]));
            free(phi_d);
            thx_patch_free(&pp[0]);
            thx_patch_free(&pp[1]);
        }
        /* bad input: a wrong row count, a NaN */
        thx_series *bad = NULL;
        CHECK_OK(ctx, thx_series_create(ctx, nh + 1, 2, &bad));
        thx_forward_result R2;
        CHECK(thx_forward_epicardial(ctx, m, bad, NULL, &R2) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "rows") != NULL);
        thx_series_destroy(&bad);
        epi->v[5] = NAN;
        CHECK(thx_forward_epicardial(ctx, m, epi, NULL, &R2) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "row 6, frame 1") != NULL);
        thx_series_destroy(&phi);
        thx_series_destroy(&Ta);
        thx_series_destroy(&Tfull);
        thx_forward_result_free(&R);
        thx_series_destroy(&epi);
        thx_model_destroy(&m);
    }
    thx_fem_finalize();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
