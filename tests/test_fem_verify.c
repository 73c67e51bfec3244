/*
 * The finite-element solver against closed forms (thorax/fem/fem.h, verify):
 * concentric spheres with one and two shells converge at second order in
 * RDM, MAG and the largest nodal error at the outer surface; current is
 * conserved; the anisotropic slab is reproduced exactly.
 */
#include <math.h>
#include <stdio.h>

#include "testlib.h"
#include "thorax/fem/fem.h"
int main(int argc, char **argv)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    CHECK_OK(ctx, thx_fem_init(argc, argv, NULL, NULL));
    const double cases[3][2] = {{0.2, 0.2}, {0.2, 0.04}, {0.2, 1.0}};
    for (int c = 0; c < 3; c++)
        for (int l = 1; l <= 2; l++) {
            thx_verify_row r[3];
            for (int k = 0; k < 3; k++) CHECK_OK(ctx, thx_verify_shells(ctx, l, cases[c][0], cases[c][1], 4 << k, &r[k]));
            for (int k = 1; k < 3; k++) {
                double lh = log(r[k - 1].h / r[k].h);
                double o_rdm = log(r[k - 1].rdm / r[k].rdm) / lh, o_max = log(r[k - 1].max_err / r[k].max_err) / lh,
                       o_mag = log(fabs(1 - r[k - 1].mag) / fabs(1 - r[k].mag)) / lh;
                printf("shells %.2f:%.2f, P_%d, n %d -> %d: RDM %.2e (order %.2f), |1-MAG| %.2e (order %.2f), max %.2e "
                       "(order %.2f), net current %.1e\n",
                       cases[c][0], cases[c][1], l, r[k - 1].n, r[k].n, r[k].rdm, o_rdm, fabs(1 - r[k].mag), o_mag, r[k].max_err,
                       o_max, r[k].net_current);
                CHECK(o_rdm > 1.75);
                CHECK(o_max > 1.75);
                CHECK(o_mag > 1.75);
            }
            CHECK(r[2].rdm < 0.01);
            CHECK(fabs(1 - r[2].mag) < 0.03); /* h = 7 mm */
            for (int k = 0; k < 3; k++) CHECK(r[k].net_current < 1e-8);
        }
    double e = 1;
    size_t n = 0;
    CHECK_OK(ctx, thx_verify_slab(ctx, &e, &n));
    printf("slab: %zu nodes, largest error %.1e\n", n, e);
    CHECK(e < 1e-8);
    thx_fem_finalize();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
