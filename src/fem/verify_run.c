/*
 * Verification runs of the finite-element solver against closed forms
 * (thorax verify; tests/test_fem_verify.c; docs/validation.md): on the
 * structured meshes of thorax/geom/verify.h, and on meshes the library's own
 * mesher makes of OpenMEEG's three spheres (thx_verify_spheres).
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
static double mean_edge(const thx_volume *v)
{
    static const int e[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    double s = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        for (int k = 0; k < 6; k++) {
            const double *p = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][0]], *q = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][1]];
            s += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        }
    return v->n_tets ? s / (6.0 * (double)v->n_tets) : 0;
}

thx_status thx_verify_shells(thx_ctx *ctx, int l, double s1, double s2, int n, thx_verify_row *row)
{
    const double a = 40, b = 70, c = 100;
    memset(row, 0, sizeof *row);
    row->n = n;
    thx_volume *v = NULL;
    int32_t *inner = NULL, *outer = NULL;
    size_t ni = 0, no = 0;
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL;
    double *phi = NULL, *num = NULL, *ref = NULL, *Kp = NULL;
    thx_fem_system *S = NULL;
    thx_status st = THX_OK;
    int nr = n / 2 > 0 ? n / 2 : 1;
    THX_TRY(thx_shells_mesh(ctx, a, b, c, s1, s2, n, nr, nr, &v, &inner, &ni, &outer, &no));
    row->nodes = v->n_nodes;
    row->tets = v->n_tets;
    row->h = mean_edge(v);
    THX_TRY(thx_fem_assemble(ctx, v, NULL, &K));
    kind = thx_malloc(ctx, v->n_nodes);
    phi = thx_calloc(ctx, v->n_nodes, sizeof *phi);
    num = thx_malloc(ctx, (no ? no : 1) * sizeof *num);
    ref = thx_malloc(ctx, (no ? no : 1) * sizeof *ref);
    Kp = thx_malloc(ctx, v->n_nodes * sizeof *Kp);
    if (!kind || !phi || !num || !ref || !Kp) { st = THX_ENOMEM; goto done; }
    memset(kind, 1, v->n_nodes);
    for (size_t k = 0; k < ni; k++) {
        const double *p = v->xyz + 3 * (size_t)inner[k];
        double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        kind[inner[k]] = 2;
        phi[inner[k]] = thx_legendre(l, p[2] / r);
    }
    THX_TRY(thx_fem_system_create(ctx, &K, kind, 0, &S));
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve(ctx, S, phi, NULL, 0, &ss));
    row->iterations = ss.iterations;
    row->seconds = ss.seconds;
    double emax = 0, rmax = 0;
    for (size_t k = 0; k < no; k++) {
        const double *p = v->xyz + 3 * (size_t)outer[k];
        double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        num[k] = phi[outer[k]];
        /* the analytic solution at the node's angle on the sphere r = c (the node lies on it) */
        ref[k] = thx_shells_potential(l, a, b, c, s1, s2, c, p[2] / r);
        emax = fmax(emax, fabs(num[k] - ref[k]));
        rmax = fmax(rmax, fabs(ref[k]));
    }
    row->rdm = thx_rdm(num, ref, no);
    row->mag = thx_mag(num, ref, no);
    row->max_err = rmax > 0 ? emax / rmax : emax;
    /* conservation: the current leaving the inner sphere sums to zero (the outer one is insulated) */
    thx_csr_mul(&K, phi, Kp);
    double net = 0, mag = 0;
    for (size_t k = 0; k < ni; k++) {
        net += Kp[inner[k]];
        mag += fabs(Kp[inner[k]]);
    }
    row->net_current = mag > 0 ? fabs(net) / mag : fabs(net);
done:
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    free(inner);
    free(outer);
    free(kind);
    free(phi);
    free(num);
    free(ref);
    free(Kp);
    return st;
}

thx_status thx_verify_slab(thx_ctx *ctx, double *rel_err, size_t *nodes)
{
    /* skeletal muscle-like: fibres tilted in the x-z plane, 4:1 along the fibre */
    const double th = 0.5;
    double ct = cos(th), sn = sin(th), sl = 0.5, st_ = 0.125;
    double sigma[9] = {sl * ct * ct + st_ * sn * sn, 0, (sl - st_) * ct * sn, 0, st_, 0, (sl - st_) * ct * sn, 0,
                       sl * sn * sn + st_ * ct * ct};
    thx_volume *v = NULL;
    int32_t *ends = NULL;
    size_t ne = 0;
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL;
    double *phi = NULL;
    thx_fem_system *S = NULL;
    thx_status st = THX_OK;
    THX_TRY(thx_slab_mesh(ctx, 60, 30, 20, 12, 6, 4, sigma, &v, &ends, &ne));
    THX_TRY(thx_fem_assemble(ctx, v, NULL, &K));
    kind = thx_malloc(ctx, v->n_nodes);
    phi = thx_calloc(ctx, v->n_nodes, sizeof *phi);
    if (!kind || !phi) { st = THX_ENOMEM; goto done; }
    memset(kind, 1, v->n_nodes);
    for (size_t k = 0; k < ne; k++) {
        kind[ends[k]] = 2;
        phi[ends[k]] = thx_slab_potential(sigma, v->xyz + 3 * (size_t)ends[k]);
    }
    THX_TRY(thx_fem_system_create(ctx, &K, kind, 0, &S));
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve(ctx, S, phi, NULL, 0, &ss));
    double e = 0, m = 0;
    for (size_t i = 0; i < v->n_nodes; i++) {
        double x = thx_slab_potential(sigma, v->xyz + 3 * i);
        e = fmax(e, fabs(phi[i] - x));
        m = fmax(m, fabs(x));
    }
    *rel_err = m > 0 ? e / m : e;
    if (nodes) *nodes = v->n_nodes;
done:
    thx_fem_system_destroy(&S);
    thx_csr_free(&K);
    thx_volume_destroy(&v);
    free(ends);
    free(kind);
    free(phi);
    return st;
}

/* ------------------------------------------------------------------ */
/* OpenMEEG's three spheres, meshed by thorax mesh (thx_verify_spheres). */

/* Mean edge length of the tetrahedra whose region is enabled. */
static double mean_edge_of(const thx_volume *v, const unsigned char *use_region)
{
    static const int e[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    double s = 0;
    size_t n = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (!use_region[v->region[t]]) continue;
        for (int k = 0; k < 6; k++) {
            const double *p = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][0]], *q = v->xyz + 3 * (size_t)v->tet[4 * t + e[k][1]];
            s += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        }
        n += 6;
    }
    return n ? s / (double)n : 0;
}

/* Sets a region of the mesher's table: rename (may be "") and conductivity. */
static void region_set(thx_mesh_opts *o, const char *name, const char *rename, double sigma)
{
    snprintf(o->region_set[o->n_region_set].name, sizeof o->region_set[0].name, "%s", name);
    snprintf(o->region_set[o->n_region_set].rename, sizeof o->region_set[0].rename, "%s", rename);
    o->region_set[o->n_region_set++].sigma = sigma;
}

thx_status thx_verify_spheres(thx_ctx *ctx, int level, thx_verify_row *row)
{
    const double a = 87, b = 92, c = 100, s_brain = 1, s_skull = 0.0125, s_scalp = 1;
    memset(row, 0, sizeof *row);
    if (level < 2 || level > 6) return thx_error(ctx, THX_EINPUT, "verify: icosphere level %d out of range 2..6", level);
    thx_model *m = NULL;
    thx_series *epi = NULL;
    thx_forward_result fr;
    memset(&fr, 0, sizeof fr);
    thx_volume_report rep;
    memset(&rep, 0, sizeof rep);
    thx_csr K;
    memset(&K, 0, sizeof K);
    double *Kp = NULL;
    unsigned char *use = NULL, *prescribed = NULL;
    thx_status st = THX_OK;
    /* the model: scalp (outer), skull, and the brain's surface in the heart's role (the prescribed one) */
    THX_TRY(thx_model_create(ctx, &m));
    {
        const char *name[3] = {"scalp", "skull", "brain"};
        const double radius[3] = {c, b, a};
        const thx_role role[3] = {THX_ROLE_OUTER, THX_ROLE_OTHER, THX_ROLE_HEART};
        for (int s = 0; s < 3; s++) {
            thx_surface *su = NULL;
            THX_TRY(thx_icosphere(ctx, level, radius[s], name[s], role[s], &su));
            THX_TRY(thx_model_add_surface(ctx, m, &su));
        }
    }
    const size_t SCALP = 0, BRAIN = 2;
    row->n = (int)m->surf[0]->n_nodes;
    /* thorax mesh's defaults but the grid: half the icosphere's edge on the scalp (15 mm at level 2) */
    thx_mesh_opts mo;
    thx_mesh_opts_default(&mo);
    mo.grid = 60.0 / (double)(1 << level);
    region_set(&mo, "mean_thorax", "scalp", s_scalp);
    region_set(&mo, "skull", "", s_skull);
    region_set(&mo, "heart", "brain", s_brain);
    thx_mesh_stats ms;
    THX_TRY(thx_mesh_build(ctx, m, &mo, &ms));
    row->t_mesh = ms.t_total;
    const thx_volume *v = m->volume;
    /* as thorax mesh does: never use a mesh that fails its own check */
    st = thx_volume_check(ctx, v, m, NULL, &rep);
    if (st == THX_ECHECK)
        st = thx_error(ctx, THX_ECHECK, "verify: the mesh of the spheres (level %d) fails its check: %s", level,
                       rep.n_reasons ? rep.reasons[0] : "(no reason given)");
    if (st != THX_OK) goto done;
    row->nodes = v->n_nodes;
    row->tets = v->n_tets;
    row->steiner = v->n_steiner;
    int brain = -1;
    for (size_t r = 0; r < v->n_regions; r++)
        if (!strcmp(v->regions[r].name, "brain")) brain = (int)r;
    if (brain < 0) { st = thx_error(ctx, THX_EINTERNAL, "verify: the mesh of the spheres has no brain region"); goto done; }
    use = thx_malloc(ctx, v->n_regions);
    prescribed = thx_calloc(ctx, v->n_nodes, 1);
    Kp = thx_malloc(ctx, v->n_nodes * sizeof *Kp);
    if (!use || !prescribed || !Kp) { st = THX_ENOMEM; goto done; }
    for (size_t r = 0; r < v->n_regions; r++) use[r] = (int)r != brain;
    row->h = mean_edge_of(v, use);
    /* P_1 on the brain's surface: cos(theta) = z / a at its nodes (on the sphere) */
    const thx_surface *bs = m->surf[BRAIN], *ss = m->surf[SCALP];
    THX_TRY(thx_series_create(ctx, bs->n_nodes, 1, &epi));
    for (size_t i = 0; i < bs->n_nodes; i++) {
        const double *p = bs->xyz + 3 * i;
        epi->v[i] = p[2] / sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    }
    thx_forward_opts fo;
    thx_forward_opts_default(&fo);
    fo.keep_volume = 1;
    THX_TRY(thx_forward_epicardial(ctx, m, epi, &fo, &fr));
    row->iterations = fr.it_max;
    row->seconds = fr.t_solve;
    const double *phi = fr.volume->v;
    /* the scalp's nodes (on r = c) against the analytic solution there */
    {
        double *num = fr.torso->v, *ref = thx_malloc(ctx, ss->n_nodes * sizeof *ref);
        if (!ref) { st = THX_ENOMEM; goto done; }
        double emax = 0, rmax = 0;
        for (size_t i = 0; i < ss->n_nodes; i++) {
            const double *p = ss->xyz + 3 * i;
            ref[i] = thx_shells_potential(1, a, b, c, s_skull, s_scalp, c, p[2] / sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
            emax = fmax(emax, fabs(num[i] - ref[i]));
            rmax = fmax(rmax, fabs(ref[i]));
        }
        row->rdm = thx_rdm(num, ref, ss->n_nodes);
        row->mag = thx_mag(num, ref, ss->n_nodes);
        row->max_err = rmax > 0 ? emax / rmax : emax;
        free(ref);
    }
    /* the prescribed nodes: the brain surface's and its Steiner nodes */
    for (size_t i = 0; i < bs->n_nodes; i++) prescribed[v->surf_node[BRAIN][i]] = 1;
    for (size_t k = 0; k < v->n_steiner; k++)
        if (v->steiner[k].surf == (int32_t)BRAIN) prescribed[v->steiner[k].node] = 1;
    /* the brain's interior: the potential prescribed on its polyhedron is the linear z / a (its corners
       on the sphere, the Steiner nodes interpolated), so the finite elements give z / a exactly */
    for (size_t t = 0; t < v->n_tets; t++) {
        if (v->region[t] != brain) continue;
        for (int k = 0; k < 4; k++) {
            int32_t n = v->tet[4 * t + k];
            if (!prescribed[n]) row->lin_err = fmax(row->lin_err, fabs(phi[n] - v->xyz[3 * (size_t)n + 2] / a));
        }
    }
    /* conservation: the current from the brain's surface into the skull sums to zero (the scalp is insulated) */
    THX_TRY(thx_fem_assemble(ctx, v, use, &K));
    thx_csr_mul(&K, phi, Kp);
    double net = 0, mag = 0;
    for (size_t i = 0; i < v->n_nodes; i++)
        if (prescribed[i]) {
            net += Kp[i];
            mag += fabs(Kp[i]);
        }
    row->net_current = mag > 0 ? fabs(net) / mag : fabs(net);
done:
    thx_volume_report_free(&rep);
    thx_forward_result_free(&fr);
    thx_series_destroy(&epi);
    thx_model_destroy(&m);
    thx_csr_free(&K);
    free(Kp);
    free(use);
    free(prescribed);
    return st;
}
