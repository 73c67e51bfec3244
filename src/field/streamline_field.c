/* The field current streamlines integrate (thorax/field/streamline.h): J at the nodes interpolated
 * linearly in each tetrahedron of the domain, point location by the walking locator, and the walk of a
 * straight path face to face to where it leaves the domain. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "field/streamline_impl.h"
#include "thorax/geom/predicates.h"

void thx_stream_opts_default(thx_stream_opts *o)
{
    memset(o, 0, sizeof *o);
    o->integrator = THX_STREAM_RK2;
    o->direction = THX_STREAM_BOTH;
    o->step = 0.2;
    o->tolerance = 1e-4;
    o->min_step = 0.01;
    o->max_step = 0.5;
    o->min_current = 1e-3;
    o->max_length = 0;
    o->max_steps = 100000;
    o->loops = 1;
    o->loop_tol = 0.5;
}

const char *thx_stream_stop_name(int reason)
{
    static const char *const names[THX_STOP_COUNT] = {"boundary", "low_current", "max_length", "max_steps", "loop"};
    return reason >= 0 && reason < THX_STOP_COUNT ? names[reason] : "unknown";
}

double thx_stream_rand(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

void thx_stream_field_destroy(thx_stream_field **f)
{
    if (!f || !*f) return;
    thx_tet_locator_destroy(&(*f)->loc);
    free((*f)->j);
    free((*f)->phi);
    free((*f)->active);
    free(*f);
    *f = NULL;
}

double thx_stream_field_max(const thx_stream_field *f) { return f->jmax; }

const thx_tet_locator *thx_stream_field_locator(const thx_stream_field *f) { return f->loc; }

void thx_stream_field_set_part(thx_stream_field *f, const unsigned char *own, const int32_t *id, const unsigned char *edge,
                               double jmax, double diag)
{
    f->own = own;
    f->edge = edge;
    thx_tet_locator_set_part(f->loc, id, edge);
    f->jmax = jmax;
    f->diag = diag;
}

thx_status thx_stream_field_create(thx_ctx *ctx, const thx_volume *v, const double *j_node, const double *phi,
                                   const unsigned char *use_region, thx_stream_field **out)
{
    *out = NULL;
    size_t nn = v->n_nodes, nt = v->n_tets;
    for (size_t i = 0; i < 3 * nn; i++)
        if (!isfinite(j_node[i]))
            return thx_error(ctx, THX_EINPUT, "streamlines: the current density at node %zu is not finite", i / 3 + 1);
    thx_stream_field *f = thx_calloc(ctx, 1, sizeof *f);
    if (!f) return THX_ENOMEM;
    f->v = v;
    f->j = thx_malloc(ctx, (3 * nn + 1) * sizeof *f->j);
    f->active = thx_malloc(ctx, nt + 1);
    if (phi) f->phi = thx_malloc(ctx, (nn + 1) * sizeof *f->phi);
    if (!f->j || !f->active || (phi && !f->phi)) {
        thx_stream_field_destroy(&f);
        return THX_ENOMEM;
    }
    memcpy(f->j, j_node, 3 * nn * sizeof *f->j);
    if (phi) memcpy(f->phi, phi, nn * sizeof *f->phi);
    size_t n_active = 0;
    double jmax = 0;
    unsigned char *node_on = thx_calloc(ctx, nn + 1, 1);
    if (!node_on) {
        thx_stream_field_destroy(&f);
        return THX_ENOMEM;
    }
    for (size_t t = 0; t < nt; t++) {
        int32_t r = v->region[t];
        f->active[t] = r >= 0 && (size_t)r < v->n_regions && (!use_region || use_region[r]);
        if (!f->active[t]) continue;
        n_active++;
        for (int a = 0; a < 4; a++) node_on[v->tet[4 * t + (size_t)a]] = 1;
    }
    for (size_t i = 0; i < nn; i++)
        if (node_on[i]) {
            const double *J = f->j + 3 * i;
            jmax = fmax(jmax, J[0] * J[0] + J[1] * J[1] + J[2] * J[2]);
        }
    jmax = sqrt(jmax);
    free(node_on);
    if (!n_active) {
        thx_stream_field_destroy(&f);
        return thx_error(ctx, THX_EINPUT, "streamlines: no tetrahedron is in the domain (every region left out)");
    }
    f->jmax = jmax;
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = hi[a] = v->xyz[a];
    for (size_t i = 0; i < nn; i++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], v->xyz[3 * i + (size_t)a]);
            hi[a] = fmax(hi[a], v->xyz[3 * i + (size_t)a]);
        }
    memcpy(f->lo, lo, sizeof lo);
    memcpy(f->hi, hi, sizeof hi);
    f->diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    thx_status st = thx_tet_locator_create(ctx, v, &f->loc);
    if (st) {
        thx_stream_field_destroy(&f);
        return st;
    }
    *out = f;
    return THX_OK;
}

void thx_stream_bary(const thx_volume *v, size_t t, const double p[3], double lam[4])
{
    const int32_t *q = v->tet + 4 * t;
    const double *P0 = v->xyz + 3 * (size_t)q[0];
    double e[3][3], r[3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) e[k][c] = v->xyz[3 * (size_t)q[k + 1] + (size_t)c] - P0[c];
    for (int c = 0; c < 3; c++) r[c] = p[c] - P0[c];
    /* r = l1 e0 + l2 e1 + l3 e2: Cramer with the cross products of the edges */
    double c12[3] = {e[1][1] * e[2][2] - e[1][2] * e[2][1], e[1][2] * e[2][0] - e[1][0] * e[2][2],
                     e[1][0] * e[2][1] - e[1][1] * e[2][0]};
    double c20[3] = {e[2][1] * e[0][2] - e[2][2] * e[0][1], e[2][2] * e[0][0] - e[2][0] * e[0][2],
                     e[2][0] * e[0][1] - e[2][1] * e[0][0]};
    double c01[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                     e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double det = e[0][0] * c12[0] + e[0][1] * c12[1] + e[0][2] * c12[2];
    double inv = det != 0 ? 1.0 / det : 0;
    lam[1] = (r[0] * c12[0] + r[1] * c12[1] + r[2] * c12[2]) * inv;
    lam[2] = (r[0] * c20[0] + r[1] * c20[1] + r[2] * c20[2]) * inv;
    lam[3] = (r[0] * c01[0] + r[1] * c01[1] + r[2] * c01[2]) * inv;
    lam[0] = 1.0 - lam[1] - lam[2] - lam[3];
}

void thx_stream_interp(const thx_stream_field *f, size_t t, const double p[3], double *j, double *phi)
{
    double lam[4];
    thx_stream_bary(f->v, t, p, lam);
    const int32_t *q = f->v->tet + 4 * t;
    if (j) {
        j[0] = j[1] = j[2] = 0;
        for (int k = 0; k < 4; k++) {
            const double *J = f->j + 3 * (size_t)q[k];
            j[0] += lam[k] * J[0], j[1] += lam[k] * J[1], j[2] += lam[k] * J[2];
        }
    }
    if (phi) {
        *phi = 0;
        if (f->phi)
            for (int k = 0; k < 4; k++) *phi += lam[k] * f->phi[q[k]];
    }
}

double thx_stream_cell_size(const thx_volume *v, size_t t)
{
    const int32_t *q = v->tet + 4 * t;
    double h = 0;
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++) {
            const double *P = v->xyz + 3 * (size_t)q[a], *Q = v->xyz + 3 * (size_t)q[b];
            h += sqrt((P[0] - Q[0]) * (P[0] - Q[0]) + (P[1] - Q[1]) * (P[1] - Q[1]) + (P[2] - Q[2]) * (P[2] - Q[2]));
        }
    return h / 6.0;
}

/* Whether tetrahedron t holds p (its boundary included), by the exact orientation tests. */
static int holds(const thx_volume *v, size_t t, const double p[3])
{
    const int32_t *q = v->tet + 4 * t;
    const double *P[4];
    for (int k = 0; k < 4; k++) P[k] = v->xyz + 3 * (size_t)q[k];
    double s0 = thx_orient3d(P[0], P[1], P[2], P[3]);
    if (s0 == 0) return 0;
    for (int k = 0; k < 4; k++) {
        const double *R[4] = {P[0], P[1], P[2], P[3]};
        R[k] = p;
        double sk = thx_orient3d(R[0], R[1], R[2], R[3]);
        if ((s0 > 0 && sk < 0) || (s0 < 0 && sk > 0)) return 0;
    }
    return 1;
}

/* Every tetrahedron, for a point the walk from the grid did not reach (a mesh with holes): the first
 * domain tetrahedron holding p, else -1. */
static long scan(const thx_stream_field *f, const double p[3])
{
    const thx_volume *v = f->v;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (!f->active[t]) continue;
        const int32_t *q = v->tet + 4 * t;
        int out = 0;
        for (int c = 0; c < 3 && !out; c++) {
            double lo = v->xyz[3 * (size_t)q[0] + (size_t)c], hi = lo;
            for (int k = 1; k < 4; k++) {
                double x = v->xyz[3 * (size_t)q[k] + (size_t)c];
                lo = fmin(lo, x), hi = fmax(hi, x);
            }
            out = p[c] < lo || p[c] > hi;
        }
        if (!out && holds(v, t, p)) return (long)t;
    }
    return -1;
}

long thx_stream_field_lowest(const thx_stream_field *f, const double p[3], long t)
{
    enum { MAX = 512 };
    long seen[MAX], best = t;
    int n = 1;
    seen[0] = t;
    for (int i = 0; i < n; i++) {
        long u = seen[i];
        const int32_t *q = f->v->tet + 4 * (size_t)u;
        for (int k = 0; k < 4; k++) {
            const double *A = f->v->xyz + 3 * (size_t)q[(k + 1) & 3], *B = f->v->xyz + 3 * (size_t)q[(k + 2) & 3],
                         *C = f->v->xyz + 3 * (size_t)q[(k + 3) & 3];
            if (thx_orient3d(A, B, C, p) != 0) continue; /* p not on this face: nothing of it behind */
            long w = thx_tet_neighbour(f->loc, (size_t)u, k);
            if (w < 0 || !f->active[w] || !holds(f->v, (size_t)w, p)) continue;
            int known = 0;
            for (int j = 0; j < n && !known; j++) known = seen[j] == w;
            if (known || n == MAX) continue;
            seen[n++] = w;
            if (w < best) best = w;
        }
    }
    return best;
}

long thx_stream_field_eval(const thx_stream_field *f, const double p[3], long hint, double *j, double *phi)
{
    /* The walk's first test, in floating point: p clearly inside the hint (every barycentric coordinate
     * above 1e-9) is in it whatever the rounding; anything closer to a face is left to the exact walk. */
    if (hint >= 0 && f->active[hint]) {
        double lam[4];
        thx_stream_bary(f->v, (size_t)hint, p, lam);
        if (lam[0] > 1e-9 && lam[1] > 1e-9 && lam[2] > 1e-9 && lam[3] > 1e-9) {
            const int32_t *q = f->v->tet + 4 * (size_t)hint;
            if (j) {
                j[0] = j[1] = j[2] = 0;
                for (int k = 0; k < 4; k++) {
                    const double *J = f->j + 3 * (size_t)q[k];
                    j[0] += lam[k] * J[0], j[1] += lam[k] * J[1], j[2] += lam[k] * J[2];
                }
            }
            if (phi) {
                *phi = 0;
                if (f->phi)
                    for (int k = 0; k < 4; k++) *phi += lam[k] * f->phi[q[k]];
            }
            return hint;
        }
    }
    long t = thx_tet_locate(f->loc, p, hint, NULL);
    if (t == -2 && hint >= 0) return -2; /* a step beyond a part's edge: the part cannot tell */
    if (t == -2) t = -1;                  /* a seed: the scan below, then its owner's */
    if (t >= 0 && !f->active[t]) {
        /* p on a face between the domain and a region outside it: the domain's side, if it holds p */
        long u = -1;
        for (int k = 0; k < 4 && u < 0; k++) {
            long w = thx_tet_neighbour(f->loc, (size_t)t, k);
            if (w >= 0 && f->active[w] && holds(f->v, (size_t)w, p)) u = w;
        }
        t = u;
    }
    if (t < 0 && hint < 0 && p[0] >= f->lo[0] && p[0] <= f->hi[0] && p[1] >= f->lo[1] && p[1] <= f->hi[1] &&
        p[2] >= f->lo[2] && p[2] <= f->hi[2])
        t = scan(f, p);
    if (t >= 0) thx_stream_interp(f, (size_t)t, p, j, phi);
    return t;
}

double thx_stream_exit(const thx_stream_field *f, size_t t, const double p[3], const double d[3], double smax,
                       long *exit_tet, int *unknown)
{
    const thx_volume *v = f->v;
    long u = (long)t, from = -1;
    double s_in = 0;
    for (int it = 0; it < 100000; it++) {
        const int32_t *q = v->tet + 4 * (size_t)u;
        double s_out = INFINITY;
        int kout = -1;
        for (int k = 0; k < 4; k++) {
            long w = thx_tet_neighbour(f->loc, (size_t)u, k);
            if (w >= 0 && w == from) continue;
            const double *A = v->xyz + 3 * (size_t)q[(k + 1) & 3], *B = v->xyz + 3 * (size_t)q[(k + 2) & 3],
                         *C = v->xyz + 3 * (size_t)q[(k + 3) & 3], *O = v->xyz + 3 * (size_t)q[k];
            double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ac[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
            double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
            if (n[0] * (O[0] - A[0]) + n[1] * (O[1] - A[1]) + n[2] * (O[2] - A[2]) > 0) n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
            double nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            if (!(nd > 0)) continue; /* not moving out through this face */
            double s = (n[0] * (A[0] - p[0]) + n[1] * (A[1] - p[1]) + n[2] * (A[2] - p[2])) / nd;
            if (s < s_out) s_out = s, kout = k;
        }
        if (kout < 0) break; /* no face ahead: flat tetrahedron */
        if (s_out < s_in) s_out = s_in;
        *exit_tet = u;
        if (s_out >= smax) return INFINITY;
        long w = thx_tet_neighbour(f->loc, (size_t)u, kout);
        if (w < 0 && f->edge && f->edge[4 * (size_t)u + (size_t)kout]) *unknown = 1;
        if (w < 0 || !f->active[w]) return s_out;
        from = u;
        u = w;
        s_in = s_out;
    }
    *exit_tet = u;
    return INFINITY;
}
