/*
 * The volume check's coverage of the model's surfaces (see check_volume.c): every interface face
 * of the mesh (on the boundary or between two regions) is mapped onto the surface triangles it
 * lies on, and each triangle's area must be covered by the faces' areas.
 */
#include "check_volume_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Surface coverage: interface faces mapped onto surface triangles. */

typedef struct {
    const thx_model *m;
    const int32_t *gsurf, *gtri; /* BVH box -> surface, triangle */
    thx_bvh *bvh;
    double tol;
} cover_set;

typedef struct {
    const cover_set *cs;
    const double *p[3];
    double cen[3];
    int n;
    int32_t g[2], s[2];
    double score[2];
} cover_query;

/* Whether the three points p lie on triangle (a, b, c): within tol of its
 * plane and inside it within tol. *score: how deep inside the face's
 * centroid is (the smallest of its distances to the edges, negative if out). */
static int on_triangle(const double *a, const double *b, const double *c, const double *const p[3], const double *cen,
                       double tol, double *score)
{
    thx_vec3 A = thx_v3(a[0], a[1], a[2]), B = thx_v3(b[0], b[1], b[2]), C = thx_v3(c[0], c[1], c[2]);
    thx_vec3 n = thx_v3_cross(thx_v3_sub(B, A), thx_v3_sub(C, A));
    double nn = thx_v3_norm(n);
    if (!(nn > 0.0)) return 0;
    thx_vec3 u = thx_v3_scale(n, 1.0 / nn);
    thx_vec3 P[3];
    for (int k = 0; k < 3; k++) {
        P[k] = thx_v3(p[k][0], p[k][1], p[k][2]);
        if (!(fabs(thx_v3_dot(u, thx_v3_sub(P[k], A))) <= tol)) return 0;
    }
    thx_vec3 V[3] = {A, B, C}, X = thx_v3(cen[0], cen[1], cen[2]);
    double sc = INFINITY;
    for (int e = 0; e < 3; e++) {
        thx_vec3 d = thx_v3_sub(V[(e + 1) % 3], V[e]);
        double len = thx_v3_norm(d);
        if (!(len > 0.0)) return 0;
        thx_vec3 w = thx_v3_scale(thx_v3_cross(u, d), 1.0 / len); /* in the plane, towards the inside */
        for (int k = 0; k < 3; k++)
            if (!(thx_v3_dot(w, thx_v3_sub(P[k], V[e])) >= -tol)) return 0;
        sc = fmin(sc, thx_v3_dot(w, thx_v3_sub(X, V[e])));
    }
    *score = sc;
    return 1;
}

static int cover_visit(void *user, size_t box)
{
    cover_query *q = user;
    const cover_set *cs = q->cs;
    int32_t s = cs->gsurf[box], t = cs->gtri[box];
    const thx_surface *su = cs->m->surf[s];
    const int32_t *c = su->tri + 3 * (size_t)t;
    double sc;
    if (!on_triangle(su->xyz + 3 * (size_t)c[0], su->xyz + 3 * (size_t)c[1], su->xyz + 3 * (size_t)c[2], q->p, q->cen,
                     cs->tol, &sc))
        return 0;
    for (int k = 0; k < q->n; k++)
        if (q->s[k] == s) {
            /* best per surface; equal scores: the lower triangle number (the visiting order is fixed anyway) */
            if (sc > q->score[k] || (sc == q->score[k] && t < cs->gtri[q->g[k]])) {
                q->g[k] = (int32_t)box;
                q->score[k] = sc;
            }
            return 0;
        }
    if (q->n < 2) {
        q->g[q->n] = (int32_t)box;
        q->s[q->n] = s;
        q->score[q->n] = sc;
        q->n++;
    }
    return 0;
}

static double tri_area3(const double *a, const double *b, const double *c, double *perimeter)
{
    thx_vec3 A = thx_v3(a[0], a[1], a[2]), B = thx_v3(b[0], b[1], b[2]), C = thx_v3(c[0], c[1], c[2]);
    if (perimeter)
        *perimeter = thx_v3_norm(thx_v3_sub(B, A)) + thx_v3_norm(thx_v3_sub(C, B)) + thx_v3_norm(thx_v3_sub(A, C));
    return 0.5 * thx_v3_norm(thx_v3_cross(thx_v3_sub(B, A), thx_v3_sub(C, A)));
}

/* Fills the coverage part of r (r->surfaces allocated by the caller). */
thx_status cv_coverage(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const size_t *iface, size_t n_iface,
                       const thx_volume_check_opts *o, thx_volume_report *r)
{
    thx_status st = THX_OK;
    size_t ns = m->n_surfaces, ng = 0;
    for (size_t s = 0; s < ns; s++) ng += m->surf[s]->n_tris;
    int32_t *gsurf = thx_malloc(ctx, (ng + 1) * sizeof *gsurf), *gtri = thx_malloc(ctx, (ng + 1) * sizeof *gtri);
    double *lo = thx_malloc(ctx, (3 * ng + 1) * sizeof *lo), *hi = thx_malloc(ctx, (3 * ng + 1) * sizeof *hi);
    double *cov = thx_calloc(ctx, ng + 1, sizeof *cov);
    size_t *gfirst = thx_calloc(ctx, ns + 1, sizeof *gfirst); /* surface s's triangle t is global gfirst[s] + t */
    int32_t *match = thx_malloc(ctx, (2 * n_iface + 1) * sizeof *match);
    int32_t *gbox = thx_malloc(ctx, (ng + 1) * sizeof *gbox); /* global triangle -> BVH box, -1 degenerate */
    cover_set cs = {m, gsurf, gtri, NULL, o->node_tol};
    if (!gsurf || !gtri || !lo || !hi || !cov || !gfirst || !match || !gbox) {
        st = THX_ENOMEM;
        goto done;
    }
    /* boxes of the non-degenerate triangles (corners in range), widened by the tolerance */
    size_t nb = 0, g = 0;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *su = m->surf[s];
        gfirst[s] = g;
        for (size_t t = 0; t < su->n_tris; t++, g++) {
            gbox[g] = -1;
            const int32_t *c = su->tri + 3 * t;
            int ok = 1;
            for (int k = 0; k < 3; k++) ok &= c[k] >= 0 && (size_t)c[k] < su->n_nodes;
            if (!ok) continue;
            const double *a = su->xyz + 3 * (size_t)c[0], *b = su->xyz + 3 * (size_t)c[1];
            const double *d = su->xyz + 3 * (size_t)c[2];
            if (!(tri_area3(a, b, d, NULL) > 0.0)) continue;
            for (int k = 0; k < 3; k++) {
                lo[3 * nb + k] = fmin(a[k], fmin(b[k], d[k])) - 2.0 * o->node_tol;
                hi[3 * nb + k] = fmax(a[k], fmax(b[k], d[k])) + 2.0 * o->node_tol;
            }
            gsurf[nb] = (int32_t)s;
            gtri[nb] = (int32_t)t;
            gbox[g] = (int32_t)nb++;
        }
    }
    gfirst[ns] = g;
    st = thx_bvh_create(ctx, lo, hi, nb, &cs.bvh);
    if (st == THX_EINPUT) { /* non-finite coordinates: the surface checks say so */
        thx_ctx_clear(ctx);
        st = THX_OK;
        goto done;
    }
    if (st != THX_OK) goto done;
    long long nf_ll = (long long)n_iface;
THX_OMP(omp parallel for schedule(dynamic, 1024))
    for (long long i = 0; i < nf_ll; i++) {
        size_t t = iface[i] / 4;
        int lf = (int)(iface[i] % 4);
        cover_query q;
        memset(&q, 0, sizeof q);
        q.cs = &cs;
        double flo[3], fhi[3];
        for (int k = 0; k < 3; k++) q.p[k] = v->xyz + 3 * (size_t)v->tet[4 * t + vface[lf][k]];
        for (int a = 0; a < 3; a++) {
            q.cen[a] = (q.p[0][a] + q.p[1][a] + q.p[2][a]) / 3.0;
            flo[a] = fmin(q.p[0][a], fmin(q.p[1][a], q.p[2][a]));
            fhi[a] = fmax(q.p[0][a], fmax(q.p[1][a], q.p[2][a]));
        }
        thx_bvh_query_box(cs.bvh, flo, fhi, cover_visit, &q);
        match[2 * i] = q.n > 0 ? q.g[0] : -1;
        match[2 * i + 1] = q.n > 1 ? q.g[1] : -1;
    }
    /* serial sums in face order (deterministic) */
    for (size_t i = 0; i < n_iface; i++) {
        size_t t = iface[i] / 4;
        int lf = (int)(iface[i] % 4);
        const int32_t *q = v->tet + 4 * t;
        const double *p0 = v->xyz + 3 * (size_t)q[vface[lf][0]], *p1 = v->xyz + 3 * (size_t)q[vface[lf][1]];
        const double *p2 = v->xyz + 3 * (size_t)q[vface[lf][2]];
        double area = tri_area3(p0, p1, p2, NULL);
        if (match[2 * i] < 0) {
            if (!r->n_faces_off_surfaces) {
                int32_t k3[3] = {q[vface[lf][0]], q[vface[lf][1]], q[vface[lf][2]]};
                sort3(k3);
                memcpy(r->ex_off_face, k3, sizeof k3);
                for (int a = 0; a < 3; a++) r->ex_off_centroid[a] = (p0[a] + p1[a] + p2[a]) / 3.0;
            }
            r->n_faces_off_surfaces++;
            continue;
        }
        for (int k = 0; k < 2; k++) {
            int32_t b = match[2 * i + k];
            if (b < 0) continue;
            cov[gfirst[gsurf[b]] + (size_t)gtri[b]] += area;
            r->surfaces[gsurf[b]].covered_area += area;
        }
    }
    r->n_interface_faces = n_iface;
    for (size_t s = 0; s < ns; s++) {
        const thx_surface *su = m->surf[s];
        thx_volume_surface_report *sr = &r->surfaces[s];
        sr->n_tris = su->n_tris;
        int have_ex = 0;
        for (size_t t = 0; t < su->n_tris; t++) {
            size_t gi = gfirst[s] + t;
            if (gbox[gi] < 0) { /* degenerate or bad: nothing to cover */
                sr->n_covered++;
                continue;
            }
            const int32_t *c = su->tri + 3 * t;
            const double *a = su->xyz + 3 * (size_t)c[0], *b = su->xyz + 3 * (size_t)c[1];
            const double *d = su->xyz + 3 * (size_t)c[2];
            double per, A = tri_area3(a, b, d, &per);
            sr->area += A;
            /* relative tolerance, plus the 6-decimal rounding of nodes on the edges */
            if (fabs(cov[gi] - A) <= o->coverage_tol * A + 1e-6 * per) {
                sr->n_covered++;
                continue;
            }
            if (!have_ex) { /* the first triangle of this surface not covered */
                have_ex = 1;
                sr->ex_uncovered = t;
                for (int k = 0; k < 3; k++) sr->ex_centroid[k] = (a[k] + b[k] + d[k]) / 3.0;
                sr->ex_covered_share = cov[gi] / A;
            }
            r->n_uncovered_tris++;
        }
        sr->share = sr->n_tris ? (double)sr->n_covered / (double)sr->n_tris : 1.0;
    }
    r->coverage_checked = 1;
done:
    thx_bvh_destroy(&cs.bvh);
    free(gsurf);
    free(gtri);
    free(lo);
    free(hi);
    free(cov);
    free(gfirst);
    free(match);
    free(gbox);
    return st;
}
