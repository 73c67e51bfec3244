/*
 * The stiffness matrix against closed forms, so that its scale is tested, not
 * only its structure (a pure-Dirichlet solve is blind to a constant factor in
 * K; the currents and the defibrillation resistance are not):
 *  - one tetrahedron: K_e = V G S G^T (V the volume, G the 4x3 gradients of
 *    the barycentric coordinates), against the reference tetrahedron's exact
 *    matrix, isotropic and anisotropic, scaled and moved;
 *  - a box of L x W x H mm meshed by Delaunay from a jittered lattice: with
 *    phi = x / L (exact in the element space) the energy phi^T K phi is the
 *    box's conductance sigma A / L (S/m * mm; x 1e-3 for siemens), for
 *    isotropic sigma and for a tensor along x.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/fem/fem.h"
static thx_volume *one_tet(thx_ctx *ctx, const double p[4][3], const double sigma[9])
{
    thx_volume *v = NULL;
    CHECK_OK(ctx, thx_volume_create(ctx, &v));
    v->n_nodes = 4;
    v->xyz = malloc(12 * sizeof *v->xyz);
    for (int i = 0; i < 4; i++) memcpy(v->xyz + 3 * i, p[i], 3 * sizeof(double));
    v->n_tets = 1;
    v->tet = malloc(4 * sizeof *v->tet);
    for (int i = 0; i < 4; i++) v->tet[i] = i;
    v->region = calloc(1, sizeof *v->region);
    v->n_regions = 1;
    v->regions = calloc(1, sizeof *v->regions);
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "t");
    memcpy(v->regions[0].sigma, sigma, 9 * sizeof(double));
    v->regions[0].anisotropic = sigma[1] != 0 || sigma[4] != sigma[0] || sigma[8] != sigma[0];
    return v;
}

/* Dense copy of a small CSR matrix. */
static void dense(const thx_csr *K, double *out, int n)
{
    memset(out, 0, (size_t)n * n * sizeof *out);
    for (int i = 0; i < K->n_rows; i++)
        for (int64_t k = K->row[i]; k < K->row[i + 1]; k++) out[i * n + K->col[k]] += K->val[k];
}

static void test_reference_tet(thx_ctx *ctx)
{
    /* Reference tetrahedron scaled by h and moved: gradients scale 1/h, volume h^3/6, so
     * K = sigma h / 6 * [[3 -1 -1 -1] [-1 1 0 0] [-1 0 1 0] [-1 0 0 1]]. */
    const double h = 7.5, o[3] = {12, -40, 3};
    const double p[4][3] = {{o[0], o[1], o[2]}, {o[0] + h, o[1], o[2]}, {o[0], o[1] + h, o[2]}, {o[0], o[1], o[2] + h}};
    const double s = 0.2;
    const double iso[9] = {s, 0, 0, 0, s, 0, 0, 0, s};
    const double ref[16] = {3, -1, -1, -1, -1, 1, 0, 0, -1, 0, 1, 0, -1, 0, 0, 1};
    thx_volume *v = one_tet(ctx, p, iso);
    thx_csr K = {0};
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    double d[16];
    dense(&K, d, 4);
    for (int i = 0; i < 16; i++) CHECK_NEAR(d[i], s * h / 6 * ref[i], 1e-12);
    thx_csr_free(&K);
    thx_volume_destroy(&v);

    /* Anisotropic diag(a, b, c): K_ij = V g_i^T S g_j with g_1 = (-1,-1,-1)/h, g_2 = e_x/h, ... */
    const double a = 0.5, b = 0.05, c = 0.2;
    const double an[9] = {a, 0, 0, 0, b, 0, 0, 0, c};
    v = one_tet(ctx, p, an);
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    dense(&K, d, 4);
    const double g[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double e = (a * g[i][0] * g[j][0] + b * g[i][1] * g[j][1] + c * g[i][2] * g[j][2]) * h / 6;
            CHECK_NEAR(d[i * 4 + j], e, 1e-12);
        }
    thx_csr_free(&K);
    thx_volume_destroy(&v);
}

/* A box [0,L]x[0,W]x[0,H] from a jittered lattice (boundary nodes on the faces, unjittered). */
static thx_volume *box(thx_ctx *ctx, double L, double W, double H, int nx, int ny, int nz, const double sigma[9])
{
    thx_volume *v = NULL;
    CHECK_OK(ctx, thx_volume_create(ctx, &v));
    size_t n = (size_t)(nx + 1) * (ny + 1) * (nz + 1), k = 0;
    v->n_nodes = n;
    v->xyz = malloc(3 * n * sizeof *v->xyz);
    srand(11);
    for (int i = 0; i <= nx; i++)
        for (int j = 0; j <= ny; j++)
            for (int l = 0; l <= nz; l++, k++) {
                double jx = (i > 0 && i < nx) ? 0.3 * (rand() / (double)RAND_MAX - 0.5) : 0;
                double jy = (j > 0 && j < ny) ? 0.3 * (rand() / (double)RAND_MAX - 0.5) : 0;
                double jz = (l > 0 && l < nz) ? 0.3 * (rand() / (double)RAND_MAX - 0.5) : 0;
                v->xyz[3 * k] = L * (i + jx) / nx;
                v->xyz[3 * k + 1] = W * (j + jy) / ny;
                v->xyz[3 * k + 2] = H * (l + jz) / nz;
            }
    int32_t *tets = NULL;
    size_t nt = 0;
    CHECK_OK(ctx, thx_delaunay3d(ctx, v->xyz, n, &tets, NULL, &nt, NULL));
    /* thorax's volumes are positively oriented; the Delaunay output is flipped (test_fem.c). */
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
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "box");
    memcpy(v->regions[0].sigma, sigma, 9 * sizeof(double));
    v->regions[0].anisotropic = sigma[4] != sigma[0] || sigma[8] != sigma[0];
    return v;
}

static double energy(const thx_csr *K, const double *phi)
{
    double *y = malloc((size_t)K->n_rows * sizeof *y), e = 0;
    thx_csr_mul(K, phi, y);
    for (int i = 0; i < K->n_rows; i++) e += phi[i] * y[i];
    free(y);
    return e;
}

static void test_box_conductance(thx_ctx *ctx)
{
    const double L = 120, W = 40, H = 25; /* mm */
    const double s = 0.22;               /* S/m, blood-like */
    const double iso[9] = {s, 0, 0, 0, s, 0, 0, 0, s};
    thx_volume *v = box(ctx, L, W, H, 9, 4, 3, iso);
    double vol = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        double tv = thx_volume_tet_volume(v, t);
        CHECK(tv > 0);
        vol += tv;
    }
    CHECK_NEAR(vol, L * W * H, 1e-6 * L * W * H);
    thx_csr K = {0};
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    double *phi = malloc(v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = v->xyz[3 * i] / L; /* 1 V across the box */
    double G = energy(&K, phi) * 1e-3; /* S/m * mm -> S */
    double exact = s * (W * H * 1e-6) / (L * 1e-3);
    CHECK_NEAR(G, exact, 1e-9 * exact);
    /* The resistance the defibrillation solve reports from the same K: 1 / G ohm. */
    CHECK_NEAR(1.0 / G, 1.0 / exact, 1e-9 / exact);
    /* Constants are in K's null space (rows sum to zero). */
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = 3.7;
    CHECK(fabs(energy(&K, phi)) < 1e-9);
    thx_csr_free(&K);
    thx_volume_destroy(&v);

    /* A tensor: along x only sigma_xx matters for phi = x / L. */
    const double an[9] = {0.5, 0, 0, 0, 0.05, 0, 0, 0, 0.05};
    v = box(ctx, L, W, H, 9, 4, 3, an);
    CHECK_OK(ctx, thx_fem_assemble(ctx, v, NULL, &K));
    phi = realloc(phi, v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = v->xyz[3 * i] / L;
    G = energy(&K, phi) * 1e-3;
    exact = 0.5 * (W * H * 1e-6) / (L * 1e-3);
    CHECK_NEAR(G, exact, 1e-9 * exact);
    /* and across z, sigma_zz: phi = z / H gives sigma_zz L W / H. */
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = v->xyz[3 * i + 2] / H;
    G = energy(&K, phi) * 1e-3;
    exact = 0.05 * (L * W * 1e-6) / (H * 1e-3);
    CHECK_NEAR(G, exact, 1e-9 * exact);
    free(phi);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    test_reference_tet(ctx);
    test_box_conductance(ctx);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
