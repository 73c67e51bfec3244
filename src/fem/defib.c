/*
 * Defibrillation (paper 4.1: "the distribution of electric potential and
 * current throughout the thorax in response to defibrillation stimuli"):
 * electrode patches on a surface at fixed voltages or injecting currents,
 * the field in the heart, and the share of the heart's volume above a field
 * threshold (a standard measure of defibrillation success, e.g. 5 V/cm).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem.h"

void thx_patch_free(thx_patch *p)
{
    if (!p) return;
    free(p->node);
    free(p->weight);
    p->node = NULL;
    p->weight = NULL;
    p->n = 0;
}

static double tri_area(const thx_surface *s, const int32_t *t)
{
    const double *a = s->xyz + 3 * (size_t)t[0], *b = s->xyz + 3 * (size_t)t[1], *c = s->xyz + 3 * (size_t)t[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}

/* Patch from a membership flag per surface node. */
static thx_status patch_from_flags(thx_ctx *ctx, const thx_model *m, size_t s, const unsigned char *in, thx_patch *p)
{
    const thx_surface *su = m->surf[s];
    const thx_volume *v = m->volume;
    double *w = thx_calloc(ctx, su->n_nodes ? su->n_nodes : 1, sizeof *w);
    if (!w) return THX_ENOMEM;
    for (size_t t = 0; t < su->n_tris; t++) {
        const int32_t *q = su->tri + 3 * t;
        double a = tri_area(su, q) / 3.0;
        for (int k = 0; k < 3; k++)
            if (in[q[k]]) w[q[k]] += a;
    }
    size_t n = 0;
    double total = 0;
    for (size_t i = 0; i < su->n_nodes; i++)
        if (in[i]) { n++; total += w[i]; }
    p->node = thx_malloc(ctx, (n ? n : 1) * sizeof *p->node);
    p->weight = thx_malloc(ctx, (n ? n : 1) * sizeof *p->weight);
    if (!p->node || !p->weight) { free(w); thx_patch_free(p); return THX_ENOMEM; }
    p->n = 0;
    for (size_t i = 0; i < su->n_nodes; i++)
        if (in[i]) {
            p->node[p->n] = v->surf_node[s][i];
            p->weight[p->n] = total > 0 ? w[i] / total : 1.0 / (double)n;
            p->n++;
        }
    p->area = total;
    free(w);
    return THX_OK;
}

thx_status thx_patch_disc(thx_ctx *ctx, const thx_model *m, size_t s, const double center[3], double radius,
                          thx_patch *p)
{
    if (!m->volume) return thx_error(ctx, THX_EINPUT, "electrode '%s': the model has no volume mesh", p->name);
    const thx_surface *su = m->surf[s];
    unsigned char *in = thx_calloc(ctx, su->n_nodes ? su->n_nodes : 1, 1);
    if (!in) return THX_ENOMEM;
    size_t n = 0;
    double best = INFINITY;
    for (size_t i = 0; i < su->n_nodes; i++) {
        const double *x = su->xyz + 3 * i;
        double d = sqrt((x[0] - center[0]) * (x[0] - center[0]) + (x[1] - center[1]) * (x[1] - center[1]) +
                        (x[2] - center[2]) * (x[2] - center[2]));
        best = fmin(best, d);
        if (d <= radius) { in[i] = 1; n++; }
    }
    if (!n) {
        free(in);
        return thx_error(ctx, THX_EINPUT,
                         "electrode '%s': no node of surface '%s' within %g mm of (%g, %g, %g) (the nearest is %.1f mm away)",
                         p->name, su->name, radius, center[0], center[1], center[2], best);
    }
    thx_status st = patch_from_flags(ctx, m, s, in, p);
    free(in);
    return st;
}

thx_status thx_patch_nodes(thx_ctx *ctx, const thx_model *m, size_t s, const int32_t *nodes, size_t n, thx_patch *p)
{
    if (!m->volume) return thx_error(ctx, THX_EINPUT, "electrode '%s': the model has no volume mesh", p->name);
    const thx_surface *su = m->surf[s];
    if (!n) return thx_error(ctx, THX_EINPUT, "electrode '%s': no nodes given", p->name);
    unsigned char *in = thx_calloc(ctx, su->n_nodes ? su->n_nodes : 1, 1);
    if (!in) return THX_ENOMEM;
    for (size_t k = 0; k < n; k++) {
        if (nodes[k] < 0 || (size_t)nodes[k] >= su->n_nodes) {
            free(in);
            return thx_error(ctx, THX_EINPUT, "electrode '%s': node %d is not on surface '%s' (1..%zu)", p->name, nodes[k] + 1,
                             su->name, su->n_nodes);
        }
        in[nodes[k]] = 1;
    }
    thx_status st = patch_from_flags(ctx, m, s, in, p);
    free(in);
    return st;
}

thx_status thx_defib_solve(thx_ctx *ctx, const thx_model *m, const thx_patch *patches, size_t np, double threshold,
                           double **phi_out, double **field_out, thx_defib_report *rep)
{
    memset(rep, 0, sizeof *rep);
    rep->threshold = threshold;
    if (phi_out) *phi_out = NULL;
    if (field_out) *field_out = NULL;
    const thx_volume *v = m->volume;
    if (!v || !v->n_tets) return thx_error(ctx, THX_EINPUT, "defibrillation: the model has no volume mesh (run thorax mesh)");
    if (np == 0 || np > 16) return thx_error(ctx, THX_EINPUT, "defibrillation: %zu electrodes (1 to 16 are handled)", np);
    int any_voltage = 0;
    double isum = 0, iabs = 0;
    for (size_t k = 0; k < np; k++) {
        if (!patches[k].n) return thx_error(ctx, THX_EINPUT, "electrode '%s' touches no node", patches[k].name);
        if (!isfinite(patches[k].value)) return thx_error(ctx, THX_EINPUT, "electrode '%s': value is not finite", patches[k].name);
        if (patches[k].is_voltage) any_voltage = 1;
        else { isum += patches[k].value; iabs += fabs(patches[k].value); }
    }
    if (!any_voltage && fabs(isum) > 1e-9 * (iabs > 0 ? iabs : 1))
        return thx_error(ctx, THX_EINPUT,
                         "defibrillation: with current electrodes only, the currents must sum to zero (they sum to %g A): "
                         "add a return electrode or a voltage (ground) electrode",
                         isum);
    thx_status st = THX_OK;
    thx_csr K;
    memset(&K, 0, sizeof K);
    unsigned char *kind = NULL;
    double *phi = NULL, *load = NULL, *field = NULL, *Kp = NULL;
    thx_fem_system *S = NULL;
    double t0 = thx_wtime();
    THX_TRY(thx_fem_assemble(ctx, v, NULL, &K));
    rep->t_assemble = thx_wtime() - t0;
    THX_TRY(thx_fem_active_nodes(ctx, v, NULL, &kind));
    phi = thx_calloc(ctx, v->n_nodes ? v->n_nodes : 1, sizeof *phi);
    load = thx_calloc(ctx, v->n_nodes ? v->n_nodes : 1, sizeof *load);
    if (!phi || !load) { st = THX_ENOMEM; goto done; }
    for (size_t k = 0; k < np; k++) {
        const thx_patch *p = &patches[k];
        for (size_t i = 0; i < p->n; i++) {
            int32_t n = p->node[i];
            if (!kind[n]) continue;
            if (p->is_voltage) {
                if (kind[n] == 2 && phi[n] != p->value) {
                    st = thx_error(ctx, THX_EINPUT, "electrodes overlap at volume node %d with different voltages", n + 1);
                    goto done;
                }
                kind[n] = 2;
                phi[n] = p->value;
            } else {
                load[n] += 1000.0 * p->value * p->weight[i]; /* A -> mA (K in mS) */
            }
        }
    }
    THX_TRY(thx_fem_system_create(ctx, &K, kind, !any_voltage, &S));
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve(ctx, S, phi, load, 0, &ss));
    rep->iterations = ss.iterations;
    rep->residual = ss.residual;
    rep->t_solve = ss.seconds;
    thx_fem_system_info(S, NULL, NULL, &rep->t_setup);
    thx_fem_system_describe(S, rep->ksp, rep->pc, &rep->ranks);
    if (!any_voltage) { /* potential relative to its volume-weighted mean */
        double sum = 0, vol = 0;
        for (size_t t = 0; t < v->n_tets; t++) {
            double tv = thx_volume_tet_volume(v, t);
            for (int k = 0; k < 4; k++) sum += 0.25 * tv * phi[v->tet[4 * t + k]];
            vol += tv;
        }
        double mean = vol > 0 ? sum / vol : 0;
        for (size_t i = 0; i < v->n_nodes; i++)
            if (kind[i]) phi[i] -= mean;
    }
    /* currents through the patches: the residual K phi at their nodes (mA -> A) */
    Kp = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *Kp);
    if (!Kp) { st = THX_ENOMEM; goto done; }
    thx_csr_mul(&K, phi, Kp);
    for (size_t k = 0; k < np; k++) {
        const thx_patch *p = &patches[k];
        double cur = 0, vs = 0;
        for (size_t i = 0; i < p->n; i++) {
            cur += Kp[p->node[i]];
            vs += p->weight[i] * phi[p->node[i]];
        }
        rep->current[k] = p->is_voltage ? cur / 1000.0 : p->value;
        rep->voltage[k] = vs;
    }
    /* the field in the heart */
    field = thx_calloc(ctx, v->n_tets ? v->n_tets : 1, sizeof *field);
    if (!field) { st = THX_ENOMEM; goto done; }
    int heart = -1;
    for (size_t r = 0; r < v->n_regions; r++)
        if (!strcmp(v->regions[r].name, "heart")) heart = (int)r;
    double *j = thx_malloc(ctx, 3 * (v->n_tets ? v->n_tets : 1) * sizeof *j);
    if (!j) { st = THX_ENOMEM; goto done; }
    thx_fem_currents(v, NULL, phi, j, NULL);
    rep->e_min = INFINITY;
    rep->j_min = INFINITY;
    double jsum = 0;
    rep->phi_min = INFINITY;
    rep->phi_max = -INFINITY;
    double esum = 0, vabove = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        /* |E| from J = sigma E: E = sigma^-1 J; recompute from phi directly instead (exact for tensors) */
        const int32_t *q = v->tet + 4 * t;
        double e[3][3], g[3];
        const double *p0 = v->xyz + 3 * (size_t)q[0];
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++) e[k][c] = v->xyz[3 * (size_t)q[k + 1] + c] - p0[c];
        double d[3] = {phi[q[1]] - phi[q[0]], phi[q[2]] - phi[q[0]], phi[q[3]] - phi[q[0]]};
        /* solve E g = d (rows of E are edge vectors): Cramer */
        double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                     e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
        for (int c = 0; c < 3; c++) {
            double mtx[3][3];
            memcpy(mtx, e, sizeof mtx);
            for (int k = 0; k < 3; k++) mtx[k][c] = d[k];
            g[c] = (mtx[0][0] * (mtx[1][1] * mtx[2][2] - mtx[1][2] * mtx[2][1]) -
                    mtx[0][1] * (mtx[1][0] * mtx[2][2] - mtx[1][2] * mtx[2][0]) +
                    mtx[0][2] * (mtx[1][0] * mtx[2][1] - mtx[1][1] * mtx[2][0])) / det;
        }
        field[t] = 10.0 * sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]); /* V/mm -> V/cm */
        if (v->region[t] != heart) continue;
        double tv = det / 6.0;
        rep->heart_volume += tv;
        esum += tv * field[t];
        if (field[t] > threshold) vabove += tv;
        rep->e_min = fmin(rep->e_min, field[t]);
        rep->e_max = fmax(rep->e_max, field[t]);
        double jm = sqrt(j[3 * t] * j[3 * t] + j[3 * t + 1] * j[3 * t + 1] + j[3 * t + 2] * j[3 * t + 2]);
        rep->j_min = fmin(rep->j_min, jm);
        rep->j_max = fmax(rep->j_max, jm);
        jsum += tv * jm;
        for (int k = 0; k < 4; k++) {
            rep->phi_min = fmin(rep->phi_min, phi[q[k]]);
            rep->phi_max = fmax(rep->phi_max, phi[q[k]]);
        }
    }
    free(j);
    if (rep->heart_volume > 0) {
        rep->e_mean = esum / rep->heart_volume;
        rep->j_mean = jsum / rep->heart_volume;
        rep->frac_above = vabove / rep->heart_volume;
    } else {
        rep->e_min = rep->e_max = rep->phi_min = rep->phi_max = rep->j_min = rep->j_max = NAN;
        thx_log(ctx, THX_LOG_WARN, "defibrillation: the mesh has no region named 'heart' (mesh without --no-heart)");
    }
    if (phi_out) { *phi_out = phi; phi = NULL; }
    if (field_out) { *field_out = field; field = NULL; }
done:
    thx_csr_free(&K);
    thx_fem_system_destroy(&S);
    free(kind);
    free(phi);
    free(load);
    free(field);
    free(Kp);
    return st;
}
