/*
 * The P_1 study on OpenMEEG's three spheres (docs/validation.md, "On meshes
 * thorax makes") with the variants thx_verify_spheres does not run: the
 * brain's Steiner nodes interpolated (as thorax forward does), given the
 * analytic value at their own position, or left free; the brain meshed or
 * not; another skull conductivity. One line of figures per run:
 *
 *   spheres_study LEVEL [interp|analytic|free] [brain|nobrain] [SIGMA_SKULL]
 *
 * Icospheres of 10 4^LEVEL + 2 nodes at 87, 92, 100 mm, grid 60 / 2^LEVEL mm,
 * brain and scalp 1 S/m. Errors against the analytic solution: at the
 * scalp's own nodes (as thorax verify), at all its nodes with Steiner nodes
 * (the reference at r = 100 and at the node's own radius), and at every node
 * between the spheres (the reference at the node's position, continued
 * harmonically below r = 87 where the polyhedral skull dips inside the
 * sphere), relative to the largest potential there. Built and run by
 * bench/spheres_study.sh.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/check/check_volume.h"
#include "thorax/fem/fem.h"
#include "thorax/mesh/mesh.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/geom/verify.h"
static const double A = 87, B = 92, C = 100, S_SCALP = 1;
static double s_skull = 0.0125;

/* The radial factor of the analytic solution (thorax/geom/verify.h, l = 1), for any r > 0 (harmonic on
 * either side of b; thx_shells_potential refuses r outside [a, c]). */
static double radial(double r)
{
    const double l = 1, rho = S_SCALP / s_skull;
    double G = pow(B / C, l) + l / (l + 1) * pow(C / B, l + 1), D = l * (pow(B / C, l) - pow(C / B, l + 1));
    double alpha = ((l + 1) * G + rho * D) / (2 * l + 1), beta = (l * G - rho * D) / (2 * l + 1);
    double A2 = 1 / (alpha * pow(A / B, l) + beta * pow(B / A, l + 1));
    if (r < B) return A2 * (alpha * pow(r / B, l) + beta * pow(B / r, l + 1));
    return A2 * (pow(r / C, l) + l / (l + 1) * pow(C / r, l + 1));
}

static double norm3(const double *p) { return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

static int die(thx_ctx *ctx, const char *what)
{
    fprintf(stderr, "spheres_study: %s: %s\n", what, thx_ctx_message(ctx));
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: spheres_study LEVEL [interp|analytic|free] [brain|nobrain] [SIGMA_SKULL]\n");
        return 2;
    }
    int level = atoi(argv[1]);
    const char *mode = argc > 2 ? argv[2] : "interp";
    int mesh_brain = !(argc > 3 && !strcmp(argv[3], "nobrain"));
    if (argc > 4) s_skull = atof(argv[4]);
    if (level < 2 || level > 6 || !(s_skull > 0) || (strcmp(mode, "interp") && strcmp(mode, "analytic") && strcmp(mode, "free"))) {
        fprintf(stderr, "spheres_study: LEVEL 2..6, interp|analytic|free, SIGMA_SKULL > 0\n");
        return 2;
    }
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    if (thx_fem_init(1, argv, NULL, NULL) != THX_OK) return die(ctx, "PETSc");
    /* the model: scalp, skull, brain (a region of its own, or the heart's role and not meshed) */
    thx_model *m = NULL;
    thx_model_create(ctx, &m);
    const char *name[3] = {"scalp", "skull", "brain"};
    const double radius[3] = {C, B, A};
    for (int s = 0; s < 3; s++) {
        thx_surface *su = NULL;
        thx_role role = s == 0 ? THX_ROLE_OUTER : s == 1 || mesh_brain ? THX_ROLE_OTHER : THX_ROLE_HEART;
        if (thx_icosphere(ctx, level, radius[s], name[s], role, &su) != THX_OK) return die(ctx, "icosphere");
        thx_model_add_surface(ctx, m, &su);
    }
    thx_mesh_opts o;
    thx_mesh_opts_default(&o);
    o.grid = 60.0 / (double)(1 << level);
    o.no_heart = !mesh_brain;
    const char *set[3][2] = {{"mean_thorax", "scalp"}, {"skull", ""}, {"brain", ""}};
    const double sig[3] = {S_SCALP, s_skull, 1};
    for (int k = 0; k < 2 + mesh_brain; k++) {
        snprintf(o.region_set[k].name, sizeof o.region_set[k].name, "%s", set[k][0]);
        snprintf(o.region_set[k].rename, sizeof o.region_set[k].rename, "%s", set[k][1]);
        o.region_set[k].sigma = sig[k];
    }
    o.n_region_set = (size_t)(2 + mesh_brain);
    thx_mesh_stats ms;
    if (thx_mesh_build(ctx, m, &o, &ms) != THX_OK) return die(ctx, "mesh");
    thx_volume *v = m->volume;
    thx_volume_report rep;
    if (thx_volume_check(ctx, v, m, NULL, &rep) != THX_OK) return die(ctx, "volume check");
    thx_volume_report_free(&rep);
    /* the finite elements on the shells only (the brain is decoupled once its surface is prescribed;
       with free Steiner nodes it is not, and is then solved with them) */
    unsigned char use[16];
    for (size_t r = 0; r < v->n_regions; r++) use[r] = strcmp(v->regions[r].name, "brain") || !strcmp(mode, "free");
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL, *steiner_on = calloc(v->n_nodes, 1);
    double *phi = calloc(v->n_nodes, sizeof *phi);
    if (thx_fem_assemble(ctx, v, use, &K) != THX_OK || thx_fem_active_nodes(ctx, v, use, &kind) != THX_OK) return die(ctx, "assembly");
    for (size_t i = 0; i < v->surf_n_nodes[2]; i++) {
        int32_t n = v->surf_node[2][i];
        kind[n] = 2;
        phi[n] = v->xyz[3 * (size_t)n + 2] / norm3(v->xyz + 3 * (size_t)n);
    }
    size_t n_steiner[3] = {0, 0, 0};
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *s = &v->steiner[k];
        steiner_on[s->node] = (unsigned char)(1 + s->surf);
        n_steiner[s->surf]++;
        if (s->surf != 2 || !strcmp(mode, "free") || !kind[s->node]) continue;
        kind[s->node] = 2;
        const double *p = v->xyz + 3 * (size_t)s->node;
        if (!strcmp(mode, "analytic")) phi[s->node] = p[2] / norm3(p);
        else
            for (int c = 0; c < 3; c++) phi[s->node] += s->bary[c] * phi[v->surf_node[2][m->surf[2]->tri[3 * s->tri + c]]];
    }
    thx_fem_system *S = NULL;
    thx_fem_solve_stats ss;
    if (thx_fem_system_create(ctx, &K, kind, 0, &S) != THX_OK || thx_fem_solve(ctx, S, phi, NULL, 0, &ss) != THX_OK)
        return die(ctx, "solve");
    /* the scalp: its own nodes, then all of them with the Steiner nodes */
    size_t cap = v->n_nodes, n_own = 0, n_all = 0;
    double *own = malloc(cap * sizeof *own), *own_ref = malloc(cap * sizeof *own_ref);
    double *all = malloc(cap * sizeof *all), *ref_c = malloc(cap * sizeof *ref_c), *ref_r = malloc(cap * sizeof *ref_r);
    double e_own = 0, top = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        if (v->node_surf[i] != 0 && steiner_on[i] != 1) continue;
        const double *p = v->xyz + 3 * i;
        double r = norm3(p);
        all[n_all] = phi[i];
        ref_c[n_all] = radial(C) * p[2] / r;
        ref_r[n_all++] = radial(r) * p[2] / r;
        if (v->node_surf[i] != 0) continue;
        own[n_own] = phi[i];
        own_ref[n_own] = radial(C) * p[2] / r;
        e_own = fmax(e_own, fabs(own[n_own] - own_ref[n_own]));
        top = fmax(top, fabs(own_ref[n_own++]));
    }
    /* every free node of the shells' tetrahedra, against the solution at its own position */
    unsigned char *in_shells = calloc(v->n_nodes, 1);
    for (size_t t = 0; t < v->n_tets; t++)
        if (strcmp(v->regions[v->region[t]].name, "brain"))
            for (int k = 0; k < 4; k++) in_shells[v->tet[4 * t + k]] = 1;
    double e_vol = 0, top_vol = 0, r_worst = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        if (kind[i] != 1 || !in_shells[i]) continue;
        const double *p = v->xyz + 3 * i;
        double r = norm3(p);
        double ex = radial(r) * p[2] / r, e = fabs(phi[i] - ex);
        if (e > e_vol) { e_vol = e; r_worst = r; }
        top_vol = fmax(top_vol, fabs(ex));
    }
    /* mean edge of the shells' tetrahedra, and of the skull's */
    static const int ed[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    double h = 0, h_skull = 0;
    size_t nh = 0, nh_skull = 0, n_tets = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        const char *rn = v->regions[v->region[t]].name;
        if (!strcmp(rn, "brain")) continue;
        n_tets++;
        for (int k = 0; k < 6; k++) {
            const double *p = v->xyz + 3 * (size_t)v->tet[4 * t + ed[k][0]], *q = v->xyz + 3 * (size_t)v->tet[4 * t + ed[k][1]];
            double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]}, l = norm3(d);
            h += l;
            nh++;
            if (!strcmp(rn, "skull")) { h_skull += l; nh_skull++; }
        }
    }
    printf("level %d (%zu nodes/sphere), Steiner %s, brain %s, skull %g S/m: %zu nodes, %zu tetrahedra between the spheres, "
           "h %.3f mm (skull %.3f), Steiner nodes scalp/skull/brain %zu/%zu/%zu | scalp's own nodes: RDM %.3e, MAG - 1 %+.3e, "
           "max %.3e | all scalp nodes: RDM %.3e (reference at r = 100), %.3e (at the node's radius) | volume: max %.3e at "
           "r = %.2f mm | %d iterations\n",
           level, m->surf[0]->n_nodes, mode, mesh_brain ? "meshed" : "not meshed", s_skull, v->n_nodes, n_tets, h / (double)nh,
           nh_skull ? h_skull / (double)nh_skull : 0.0, n_steiner[0], n_steiner[1], n_steiner[2], thx_rdm(own, own_ref, n_own),
           thx_mag(own, own_ref, n_own) - 1, e_own / top, thx_rdm(all, ref_c, n_all), thx_rdm(all, ref_r, n_all),
           e_vol / top_vol, r_worst, ss.iterations);
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    thx_model_destroy(&m);
    free(kind);
    free(steiner_on);
    free(in_shells);
    free(phi);
    free(own);
    free(own_ref);
    free(all);
    free(ref_c);
    free(ref_r);
    thx_fem_finalize();
    thx_ctx_destroy(&ctx);
    return 0;
}
