/*
 * The volume check's look at each tetrahedron (see check_volume.c): its quality (thx_tet_quality),
 * then the pass over all of them: orientation (exact), volume, dihedral angles, radius-edge and
 * radius ratios, edge lengths, and their counts, sums, histograms and worst lists in the report.
 */
#include "check_volume_impl.h"

#include <math.h>

#include "thorax/geom/predicates.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

const double thx_vcheck_dihedral_edges[THX_VCHECK_DIHEDRAL_BINS + 1] = {0, 5, 10, 15, 20, 30, 40, 50, 60, INFINITY};
const double thx_vcheck_radius_edge_edges[THX_VCHECK_RADIUS_EDGE_BINS + 1] = {
    0.61237243569579452, 0.8, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 100.0, INFINITY};

/* ------------------------------------------------------------------ */
/* Quality of one tetrahedron. */

void thx_tet_quality(const double *a, const double *b, const double *c, const double *d, double *min_dihedral,
                     double *max_dihedral, double *radius_edge, double *radius_ratio)
{
    double mn = 0.0, mx = 180.0, re = INFINITY, rr = 0.0;
    if (thx_orient3d(a, b, c, d) != 0.0) {
        thx_vec3 p[4] = {thx_v3(a[0], a[1], a[2]), thx_v3(b[0], b[1], b[2]), thx_v3(c[0], c[1], c[2]),
                         thx_v3(d[0], d[1], d[2])};
        /* face normals, all outward for a right-handed tetrahedron (all inward
         * otherwise: the angles between them are the same) */
        thx_vec3 n[4];
        double nn[4], area2 = 0.0;
        for (int k = 0; k < 4; k++) {
            thx_vec3 o = p[vface[k][0]];
            n[k] = thx_v3_cross(thx_v3_sub(p[vface[k][1]], o), thx_v3_sub(p[vface[k][2]], o));
            nn[k] = thx_v3_norm(n[k]);
            area2 += nn[k];
        }
        mn = INFINITY;
        mx = -INFINITY;
        for (int k = 0; k < 4; k++)
            for (int l = k + 1; l < 4; l++) {
                /* interior angle at the shared edge = pi - angle between the outward normals */
                double ang = atan2(thx_v3_norm(thx_v3_cross(n[k], n[l])), -thx_v3_dot(n[k], n[l])) * (180.0 / M_PI);
                mn = fmin(mn, ang);
                mx = fmax(mx, ang);
            }
        thx_vec3 e1 = thx_v3_sub(p[1], p[0]), e2 = thx_v3_sub(p[2], p[0]), e3 = thx_v3_sub(p[3], p[0]);
        double det = fabs(thx_v3_dot(e1, thx_v3_cross(e2, e3))); /* 6 V */
        double lmin = INFINITY;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) lmin = fmin(lmin, thx_v3_norm(thx_v3_sub(p[j], p[i])));
        /* circumcentre - p0 = (|e1|^2 (e2 x e3) + |e2|^2 (e3 x e1) + |e3|^2 (e1 x e2)) / (2 det) */
        thx_vec3 num = thx_v3_add(thx_v3_scale(thx_v3_cross(e2, e3), thx_v3_dot(e1, e1)),
                                  thx_v3_add(thx_v3_scale(thx_v3_cross(e3, e1), thx_v3_dot(e2, e2)),
                                             thx_v3_scale(thx_v3_cross(e1, e2), thx_v3_dot(e3, e3))));
        double R = det > 0.0 ? thx_v3_norm(num) / (2.0 * det) : INFINITY;
        double rin = area2 > 0.0 ? det / area2 : 0.0; /* 3 V / total area */
        re = lmin > 0.0 ? R / lmin : INFINITY;
        rr = isfinite(R) && R > 0.0 ? 3.0 * rin / R : 0.0;
        if (det == 0.0) { /* exactly non-flat but underflowed: treat as flat */
            mn = 0.0;
            mx = 180.0;
        }
    }
    if (min_dihedral) *min_dihedral = mn;
    if (max_dihedral) *max_dihedral = mx;
    if (radius_edge) *radius_edge = re;
    if (radius_ratio) *radius_ratio = rr;
}

/* ------------------------------------------------------------------ */
/* The pass over the tetrahedra. */

/* Inserts (t, val) into a list kept sorted by val (ascending if !desc), ties
 * by smaller t first; at most THX_VCHECK_MAX_WORST entries. */
static void worst_add(thx_volume_worst *l, size_t *n, size_t t, double val, int desc)
{
    size_t k = *n < THX_VCHECK_MAX_WORST ? (*n)++ : THX_VCHECK_MAX_WORST;
#define WORSE(va, ta, vb, tb) ((desc ? (va) > (vb) : (va) < (vb)) || ((va) == (vb) && (ta) < (tb)))
    if (k == THX_VCHECK_MAX_WORST) {
        const thx_volume_worst *last = &l[THX_VCHECK_MAX_WORST - 1];
        if (!WORSE(val, t, last->value, last->tet)) return;
        k = THX_VCHECK_MAX_WORST - 1;
    }
    while (k > 0 && WORSE(val, t, l[k - 1].value, l[k - 1].tet)) {
        l[k] = l[k - 1];
        k--;
    }
#undef WORSE
    l[k].tet = t;
    l[k].value = val;
}

/* Per tetrahedron, in parallel: orientation (exact), volume, quality (fig[t]); then, serially in
 * tetrahedron order (deterministic): the counts, sums, extremes, histograms and worst lists of r,
 * the regions' tetrahedra and volumes, the nodes used (used: n_nodes + 1 bytes, zeroed) and the
 * unused ones. Every node index is in range (checked before). */
void cv_tets(const thx_volume *v, tet_fig *fig, unsigned char *used, thx_volume_report *r)
{
    size_t nt = v->n_tets, nv = v->n_nodes;
    /* per tetrahedron, in parallel: orientation (exact), volume, quality */
    long long nt_ll = (long long)nt;
THX_OMP(omp parallel for schedule(dynamic, 4096))
    for (long long t = 0; t < nt_ll; t++) {
        const int32_t *q = v->tet + 4 * t;
        tet_fig *f = &fig[t];
        f->repeated = q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] || q[2] == q[3];
        const double *p[4];
        for (int k = 0; k < 4; k++) p[k] = v->xyz + 3 * (size_t)q[k];
        double o3 = thx_orient3d(p[0], p[1], p[2], p[3]);
        f->orient = (int8_t)sgn(o3);
        f->vol = thx_volume_tet_volume(v, (size_t)t);
        thx_tet_quality(p[0], p[1], p[2], p[3], &f->mind, &f->maxd, &f->re, &f->rr);
        f->lmin = INFINITY;
        f->lmax = 0.0;
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) {
                double l = thx_v3_norm(thx_v3_sub(node3(v->xyz, q[j]), node3(v->xyz, q[i])));
                f->lmin = fmin(f->lmin, l);
                f->lmax = fmax(f->lmax, l);
            }
    }

    /* serial pass: counts, sums and lists in tetrahedron order (deterministic) */
    double vsum = 0.0, re_sum = 0.0, rr_sum = 0.0;
    size_t n_re = 0, n_q = 0;
    r->min_tet_volume = INFINITY;
    r->max_tet_volume = -INFINITY;
    r->min_dihedral = r->min_radius_ratio = r->min_edge = INFINITY;
    r->max_dihedral = r->max_radius_edge = r->max_edge = -INFINITY;
    for (size_t t = 0; t < nt; t++) {
        const tet_fig *f = &fig[t];
        for (int k = 0; k < 4; k++) used[v->tet[4 * t + k]] = 1;
        int32_t reg = v->region ? v->region[t] : -1;
        if (!v->region || reg < 0 || (size_t)reg >= v->n_regions) {
            if (!r->n_bad_region_tets) r->ex_bad_region_tet = t;
            r->n_bad_region_tets++;
        } else {
            r->regions[reg].n_tets++;
            r->regions[reg].volume += f->vol;
        }
        vsum += f->vol;
        r->min_tet_volume = fmin(r->min_tet_volume, f->vol);
        r->max_tet_volume = fmax(r->max_tet_volume, f->vol);
        if (f->repeated) {
            if (!r->n_repeated_node_tets) r->ex_repeated_node_tet = t;
            r->n_repeated_node_tets++;
            continue;
        }
        if (f->orient > 0) {
            if (!r->n_inverted_tets) r->ex_inverted_tet = t;
            r->n_inverted_tets++;
        } else if (f->orient == 0) {
            if (!r->n_flat_tets) r->ex_flat_tet = t;
            r->n_flat_tets++;
        }
        /* quality */
        n_q++;
        if (f->mind < r->min_dihedral) { r->min_dihedral = f->mind; r->min_dihedral_tet = t; }
        if (f->maxd > r->max_dihedral) { r->max_dihedral = f->maxd; r->max_dihedral_tet = t; }
        if (f->re > r->max_radius_edge) { r->max_radius_edge = f->re; r->max_radius_edge_tet = t; }
        if (f->rr < r->min_radius_ratio) { r->min_radius_ratio = f->rr; r->min_radius_ratio_tet = t; }
        if (isfinite(f->re)) {
            re_sum += f->re;
            n_re++;
        }
        rr_sum += f->rr;
        r->min_edge = fmin(r->min_edge, f->lmin);
        r->max_edge = fmax(r->max_edge, f->lmax);
        int bin = 0;
        while (bin < THX_VCHECK_DIHEDRAL_BINS - 1 && !(f->mind < thx_vcheck_dihedral_edges[bin + 1])) bin++;
        r->dihedral_hist[bin]++;
        bin = 0;
        while (bin < THX_VCHECK_RADIUS_EDGE_BINS - 1 && !(f->re < thx_vcheck_radius_edge_edges[bin + 1])) bin++;
        r->radius_edge_hist[bin]++;
        worst_add(r->worst_dihedral, &r->n_worst_dihedral, t, f->mind, 0);
        worst_add(r->worst_radius_edge, &r->n_worst_radius_edge, t, f->re, 1);
    }
    r->tet_volume = vsum;
    r->mean_radius_edge = n_re ? re_sum / (double)n_re : NAN;
    r->mean_radius_ratio = n_q ? rr_sum / (double)n_q : NAN;
    if (!n_q) {
        r->min_dihedral = r->max_dihedral = r->max_radius_edge = r->min_radius_ratio = NAN;
        r->min_edge = r->max_edge = NAN;
    }
    for (size_t g = 0; g < nv; g++)
        if (!used[g]) {
            if (!r->n_unused_nodes) r->ex_unused_node = (int32_t)g;
            r->n_unused_nodes++;
        }
}
