/*
 * The finite-element forward solution on meshes thorax's own mesher makes
 * (thx_verify_spheres, docs/validation.md "OpenMEEG's three spheres"):
 * OpenMEEG's radii 87, 92, 100 mm and conductivities 1 : 0.0125 : 1 S/m,
 * icospheres of 2,562 and 10,242 nodes meshed with brain, skull and scalp as
 * regions. RDM, |1 - MAG| and the largest error at the scalp's nodes
 * converge at second order against the analytic solution (the measured
 * mean edge halves between the two meshes); the brain's interior is the
 * linear z / a (the potential prescribed on its polyhedron is linear);
 * current is conserved. Levels out of range are refused.
 */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>

#include "testlib.h"
#include "thorax/fem/fem.h"
int main(int argc, char **argv)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    CHECK_OK(ctx, thx_fem_init(argc, argv, NULL, NULL));
    /* Levels 4 and 5 (2562 and 10242 nodes per sphere) and the order of convergence between them;
     * under the sanitizers (THORAX_QUICK, set by CMakeLists.txt) level 4 alone, its accuracy and
     * conservation checked, at a ninth of the cost (coarser levels are not yet asymptotic). */
    const int base = 4, levels = getenv("THORAX_QUICK") ? 1 : 2;
    thx_verify_row r[2];
    for (int k = 0; k < levels; k++) {
        CHECK_OK(ctx, thx_verify_spheres(ctx, base + k, &r[k]));
        printf("spheres level %d: %d nodes per sphere, %zu nodes, %zu tetrahedra (%zu Steiner nodes), h %.3f mm: "
               "RDM %.2e, |1-MAG| %.2e, max %.2e, brain's linear error %.1e, net current %.1e, %d iterations, mesh %.1f s\n",
               base + k, r[k].n, r[k].nodes, r[k].tets, r[k].steiner, r[k].h, r[k].rdm, fabs(1 - r[k].mag), r[k].max_err,
               r[k].lin_err, r[k].net_current, r[k].iterations, r[k].t_mesh);
        CHECK(r[k].n == (k ? 10242 : 2562));
        CHECK(r[k].steiner > 0);          /* the mesher did add points on the surfaces: they are part of the test */
        CHECK(r[k].lin_err < 1e-7);       /* the solver's tolerance, not the discretization's */
        CHECK(r[k].net_current < 1e-8);
    }
    if (levels == 1) {
        CHECK(r[0].rdm < 1e-3 && fabs(1 - r[0].mag) < 4e-3 && r[0].max_err < 4e-3);
        thx_fem_finalize();
        thx_ctx_destroy(&ctx);
        return tl_finish();
    }
    double ratio = r[0].h / r[1].h, lh = log(ratio);
    double o_rdm = log(r[0].rdm / r[1].rdm) / lh, o_mag = log(fabs(1 - r[0].mag) / fabs(1 - r[1].mag)) / lh,
           o_max = log(r[0].max_err / r[1].max_err) / lh;
    printf("h ratio %.3f; orders: RDM %.2f, |1-MAG| %.2f, max %.2f\n", ratio, o_rdm, o_mag, o_max);
    CHECK(ratio > 1.8 && ratio < 2.3); /* a real refinement (the tetrahedra 8 times as many) */
    CHECK(r[1].tets > 6 * r[0].tets && r[1].tets < 10 * r[0].tets);
    CHECK(o_rdm > 1.75);
    CHECK(o_mag > 1.75);
    CHECK(o_max > 1.75);
    CHECK(r[1].rdm < 2e-4 && fabs(1 - r[1].mag) < 1e-3 && r[1].max_err < 1e-3);
    thx_verify_row bad;
    CHECK(thx_verify_spheres(ctx, 1, &bad) == THX_EINPUT);
    CHECK(thx_verify_spheres(ctx, 7, &bad) == THX_EINPUT);
    thx_fem_finalize();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
