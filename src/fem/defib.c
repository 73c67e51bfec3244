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

#include "thorax/fem/fem.h"
void thx_patch_free(thx_patch *p)
{
    if (!p) return;
    free(p->node);
    free(p->weight);
    p->node = NULL;
    p->weight = NULL;
    p->n = 0;
}

static int cmp_i32x3(const void *x, const void *y)
{
    const int32_t *a = x, *b = y;
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

/*
 * Patch from a membership flag per node of surface s. The patch's volume
 * nodes are its surface nodes and the Steiner nodes on s (thorax/model/volume.h)
 * whose non-zero barycentric weights all fall on patch nodes (a Steiner node
 * inside a triangle, or on an edge, spanned by patch nodes): a voltage holds
 * the whole part of the surface they span, as before the mesher subdivided
 * it. Weights: a third of the area of each mesh face on s around a patch
 * node (the faces the finite elements see; s's own triangles when nothing
 * was subdivided), normalized; a face is on s when its three nodes lie on
 * one triangle of s (each node a corner of it, or a Steiner node whose
 * weights fall on its corners).
 */
static thx_status patch_from_flags(thx_ctx *ctx, const thx_model *m, size_t s, const unsigned char *in, thx_patch *p)
{
    const thx_surface *su = m->surf[s];
    const thx_volume *v = m->volume;
    size_t nv = v->n_nodes, ns = su->n_nodes;
    thx_status st = THX_OK;
    int32_t *sup = thx_malloc(ctx, 3 * (nv ? nv : 1) * sizeof *sup); /* per volume node on s: surface nodes it lies between */
    unsigned char *member = thx_calloc(ctx, nv ? nv : 1, 1);
    double *w = thx_calloc(ctx, nv ? nv : 1, sizeof *w);
    size_t *tstart = thx_calloc(ctx, ns + 1, sizeof *tstart);
    int32_t *ttri = thx_malloc(ctx, (3 * su->n_tris + 1) * sizeof *ttri);
    int32_t(*face)[3] = NULL;
    size_t nface = 0, capf = 0;
    if (!sup || !member || !w || !tstart || !ttri) { st = THX_ENOMEM; goto done; }
    for (size_t g = 0; g < 3 * nv; g++) sup[g] = -1;
    for (size_t i = 0; i < ns; i++) {
        int32_t g = v->surf_node[s][i];
        sup[3 * (size_t)g] = (int32_t)i;
        if (in[i]) member[g] = 1;
    }
    for (size_t k = 0; k < v->n_steiner; k++) {
        const thx_steiner *r = &v->steiner[k];
        if (r->surf != (int32_t)s || r->node < 0 || (size_t)r->node >= nv || r->tri < 0 || (size_t)r->tri >= su->n_tris)
            continue;
        int all_in = 1, n = 0;
        for (int c = 0; c < 3; c++)
            if (r->bary[c] > 1e-12) {
                int32_t i = su->tri[3 * (size_t)r->tri + (size_t)c];
                sup[3 * (size_t)r->node + (size_t)n++] = i;
                all_in &= in[i] != 0;
            }
        if (all_in && n) member[r->node] = 1;
    }
    /* triangles around each surface node */
    for (size_t t = 0; t < su->n_tris; t++)
        for (int c = 0; c < 3; c++) tstart[su->tri[3 * t + (size_t)c] + 1]++;
    for (size_t i = 0; i < ns; i++) tstart[i + 1] += tstart[i];
    {
        size_t *fill = thx_malloc(ctx, (ns + 1) * sizeof *fill);
        if (!fill) { st = THX_ENOMEM; goto done; }
        memcpy(fill, tstart, (ns + 1) * sizeof *fill);
        for (size_t t = 0; t < su->n_tris; t++)
            for (int c = 0; c < 3; c++) ttri[fill[su->tri[3 * t + (size_t)c]]++] = (int32_t)t;
        free(fill);
    }
    /* mesh faces on s with a patch node: their nodes' supports are one triangle's corners */
    static const int vf[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    for (size_t t = 0; t < v->n_tets; t++)
        for (int f = 0; f < 4; f++) {
            int32_t q[3];
            int any = 0, on = 1;
            for (int k = 0; k < 3; k++) {
                q[k] = v->tet[4 * t + (size_t)vf[f][k]];
                any |= member[q[k]];
                on &= sup[3 * (size_t)q[k]] >= 0;
            }
            if (!any || !on) continue;
            int32_t u[9];
            int nu = 0;
            for (int k = 0; k < 3; k++)
                for (int c = 0; c < 3; c++) {
                    int32_t i = sup[3 * (size_t)q[k] + (size_t)c];
                    if (i < 0) break;
                    int seen = 0;
                    for (int j = 0; j < nu; j++) seen |= u[j] == i;
                    if (!seen) u[nu++] = i;
                }
            if (nu != 3) continue;
            int tri = 0;
            for (size_t e = tstart[u[0]]; e < tstart[u[0] + 1] && !tri; e++) {
                const int32_t *c = su->tri + 3 * (size_t)ttri[e];
                int h1 = c[0] == u[1] || c[1] == u[1] || c[2] == u[1], h2 = c[0] == u[2] || c[1] == u[2] || c[2] == u[2];
                tri = h1 && h2;
            }
            if (!tri) continue;
            if (nface + 1 > capf && (st = thx_grow(ctx, (void **)&face, &capf, nface + 1, sizeof *face)) != THX_OK) goto done;
            if (q[0] > q[1]) { int32_t x = q[0]; q[0] = q[1]; q[1] = x; }
            if (q[1] > q[2]) { int32_t x = q[1]; q[1] = q[2]; q[2] = x; }
            if (q[0] > q[1]) { int32_t x = q[0]; q[0] = q[1]; q[1] = x; }
            memcpy(face[nface++], q, sizeof q);
        }
    if (nface > 1) qsort(face, nface, sizeof *face, cmp_i32x3);
    for (size_t k = 0; k < nface; k++) {
        if (k && !memcmp(face[k], face[k - 1], sizeof face[k])) continue; /* a face on an inner surface, seen from both sides */
        const double *a = v->xyz + 3 * (size_t)face[k][0], *b = v->xyz + 3 * (size_t)face[k][1];
        const double *c = v->xyz + 3 * (size_t)face[k][2];
        double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2], wx = c[0] - a[0], wy = c[1] - a[1], wz = c[2] - a[2];
        double x = uy * wz - uz * wy, y = uz * wx - ux * wz, z = ux * wy - uy * wx;
        double third = 0.5 * sqrt(x * x + y * y + z * z) / 3.0;
        for (int j = 0; j < 3; j++)
            if (member[face[k][j]]) w[face[k][j]] += third;
    }
    size_t n = 0;
    double total = 0;
    for (size_t g = 0; g < nv; g++)
        if (member[g]) { n++; total += w[g]; }
    p->node = thx_malloc(ctx, (n ? n : 1) * sizeof *p->node);
    p->weight = thx_malloc(ctx, (n ? n : 1) * sizeof *p->weight);
    if (!p->node || !p->weight) { thx_patch_free(p); st = THX_ENOMEM; goto done; }
    p->n = 0;
    /* the surface's nodes first, in their order, then the Steiner nodes in volume order */
    for (size_t i = 0; i < ns; i++)
        if (in[i]) {
            int32_t g = v->surf_node[s][i];
            p->node[p->n] = g;
            p->weight[p->n] = total > 0 ? w[g] / total : 1.0 / (double)n;
            p->n++;
            member[g] = 0;
        }
    for (size_t g = 0; g < nv; g++)
        if (member[g]) {
            p->node[p->n] = (int32_t)g;
            p->weight[p->n] = total > 0 ? w[g] / total : 1.0 / (double)n;
            p->n++;
        }
    p->area = total;
done:
    free(sup);
    free(member);
    free(w);
    free(tstart);
    free(ttri);
    free(face);
    return st;
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
    THX_TRY(thx_fem_assemble_kept(ctx, v, NULL, &K, &rep->assembly)); /* (every rank holds the whole matrix) */
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
