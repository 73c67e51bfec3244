/* The boundary-element geometry: closed, outward surfaces, their nesting and conductivities;
 * the double-layer matrix (thorax/bem/bem.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bem/bem_impl.h"
#include "thorax/mesh/mesh.h"

/* Nodes of a surface tested against each other surface for the nesting (all of a smaller one). */
#define NEST_SAMPLES 400

static int cmp_edge(const void *pa, const void *pb)
{
    const int64_t *a = pa, *b = pb;
    return a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : a[1] < b[1] ? -1 : a[1] > b[1];
}

/* Every edge in exactly two triangles, in opposite directions. */
static thx_status check_closed(thx_ctx *ctx, const thx_surface *s)
{
    size_t ne = 3 * s->n_tris;
    int64_t *e = thx_malloc(ctx, (ne ? ne : 1) * 2 * sizeof *e);
    if (!e) return THX_ENOMEM;
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            int64_t a = s->tri[3 * t + (size_t)k], c = s->tri[3 * t + (size_t)(k + 1) % 3];
            e[2 * (3 * t + (size_t)k)] = a;
            e[2 * (3 * t + (size_t)k) + 1] = c;
        }
    /* directed edges: each (a, c) once, and (c, a) present */
    qsort(e, ne, 2 * sizeof *e, cmp_edge);
    thx_status st = THX_OK;
    for (size_t i = 0; i < ne && st == THX_OK; i++) {
        if (e[2 * i] == e[2 * i + 1]) {
            st = thx_error(ctx, THX_EGEOM, "surface '%s': a triangle repeats node %lld", s->name, (long long)e[2 * i] + 1);
        } else if (i + 1 < ne && e[2 * i] == e[2 * i + 2] && e[2 * i + 1] == e[2 * i + 3]) {
            st = thx_error(ctx, THX_EGEOM, "surface '%s': edge %lld-%lld is used twice in the same direction (triangles "
                           "not consistently oriented, or the surface is not manifold there)", s->name,
                           (long long)e[2 * i] + 1, (long long)e[2 * i + 1] + 1);
        } else {
            int64_t key[2] = {e[2 * i + 1], e[2 * i]};
            if (!bsearch(key, e, ne, 2 * sizeof *e, cmp_edge))
                st = thx_error(ctx, THX_EGEOM, "surface '%s' is not closed: edge %lld-%lld (1-based nodes) has a "
                               "triangle on one side only", s->name, (long long)e[2 * i] + 1, (long long)e[2 * i + 1] + 1);
        }
    }
    free(e);
    return st;
}

double thx_bem_surface_angle(const thx_bem *b, size_t k, const double p[3])
{
    const thx_surface *s = b->surf[k];
    double sum = 0, dl[3];
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        sum += thx_bem_triangle(p, s->xyz + 3 * v[0], s->xyz + 3 * v[1], s->xyz + 3 * v[2], dl, NULL);
    }
    return sum;
}

void thx_bem_destroy(thx_bem **pb)
{
    if (!pb || !*pb) return;
    thx_bem *b = *pb;
    for (size_t k = 0; k < b->n; k++) thx_surface_destroy(&b->surf[k]);
    free(b->surf);
    free(b->off);
    free(b->parent);
    free(b->sig_in);
    free(b->sig_out);
    free(b->area);
    free(b);
    *pb = NULL;
}

static thx_status copy_surface(thx_ctx *ctx, const thx_surface *s, thx_surface **out)
{
    THX_CHECK(thx_surface_create(ctx, s->name, s->role, out));
    thx_surface *c = *out;
    c->xyz = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *c->xyz);
    c->tri = thx_malloc(ctx, (s->n_tris ? s->n_tris : 1) * 3 * sizeof *c->tri);
    if (!c->xyz || !c->tri) return THX_ENOMEM;
    c->n_nodes = s->n_nodes;
    c->n_tris = s->n_tris;
    memcpy(c->xyz, s->xyz, s->n_nodes * 3 * sizeof *c->xyz);
    memcpy(c->tri, s->tri, s->n_tris * 3 * sizeof *c->tri);
    return THX_OK;
}

thx_status thx_bem_create(thx_ctx *ctx, const thx_surface *const *surf, size_t n, const double *sigma_in,
                          thx_bem **out)
{
    *out = NULL;
    if (n == 0) return thx_error(ctx, THX_EINPUT, "bem: no surfaces");
    thx_status st = THX_OK;
    thx_bem *b = thx_calloc(ctx, 1, sizeof *b);
    if (!b) return THX_ENOMEM;
    b->n = n;
    b->surf = thx_calloc(ctx, n, sizeof *b->surf);
    b->off = thx_calloc(ctx, n + 1, sizeof *b->off);
    b->parent = thx_malloc(ctx, n * sizeof *b->parent);
    b->sig_in = thx_malloc(ctx, n * sizeof *b->sig_in);
    b->sig_out = thx_malloc(ctx, n * sizeof *b->sig_out);
    double *vol = thx_malloc(ctx, n * sizeof *vol);
    unsigned char *inside = thx_calloc(ctx, n * n, 1); /* inside[k * n + l]: k inside l */
    if (!b->surf || !b->off || !b->parent || !b->sig_in || !b->sig_out || !vol || !inside) { st = THX_ENOMEM; goto done; }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < n; k++) {
        THX_TRY(thx_surface_validate(ctx, surf[k]));
        {
            /* the solid angles and integrals take products of three lengths: a surface whose size
               is beyond 1e-30..1e30 (in the model's units) underflows or overflows them (at 1e-110
               nested spheres were taken for touching ones, at 1e110 for empty ones) */
            double slo[3] = {INFINITY, INFINITY, INFINITY}, shi[3] = {-INFINITY, -INFINITY, -INFINITY}, d2 = 0;
            for (size_t i = 0; i < 3 * surf[k]->n_nodes; i++) {
                slo[i % 3] = fmin(slo[i % 3], surf[k]->xyz[i]);
                shi[i % 3] = fmax(shi[i % 3], surf[k]->xyz[i]);
            }
            for (int c = 0; c < 3; c++) d2 += (shi[c] - slo[c]) / 1e30 * ((shi[c] - slo[c]) / 1e30);
            double size = sqrt(d2) * 1e30;
            if (!(size >= 1e-30 && size <= 1e30)) {
                st = thx_error(ctx, THX_EGEOM, "surface '%s': its size %g (bounding-box diagonal, in the model's units) is "
                               "outside 1e-30..1e30, where the boundary integrals underflow or overflow", surf[k]->name, size);
                goto done;
            }
        }
        if (surf[k]->n_tris < 4) { st = thx_error(ctx, THX_EGEOM, "surface '%s': %zu triangles cannot close a volume", surf[k]->name, surf[k]->n_tris); goto done; }
        if (!isfinite(sigma_in[k]) || sigma_in[k] < 0) {
            st = thx_error(ctx, THX_EINPUT, "surface '%s': conductivity inside %g S/m is not a finite value >= 0", surf[k]->name, sigma_in[k]);
            goto done;
        }
        /* thorax sigma's bounds (thorax/mesh/mesh.h), or 0 (an insulator): beyond them the systems
           overflow or underflow (1e308 and 1e-320 gave NaN potentials with exit 0) */
        if (sigma_in[k] != 0 && !(sigma_in[k] >= THX_SIGMA_MIN && sigma_in[k] <= THX_SIGMA_MAX)) {
            st = thx_error(ctx, THX_EINPUT, "surface '%s': conductivity inside %g S/m is outside %g..%g S/m (or 0, an "
                           "insulator)", surf[k]->name, sigma_in[k], THX_SIGMA_MIN, THX_SIGMA_MAX);
            goto done;
        }
        THX_TRY(copy_surface(ctx, surf[k], &b->surf[k]));
        THX_TRY(check_closed(ctx, b->surf[k]));
        vol[k] = thx_surface_volume(b->surf[k]);
        if (vol[k] < 0) { /* inward: reverse */
            thx_surface *s = b->surf[k];
            for (size_t t = 0; t < s->n_tris; t++) {
                int32_t tmp = s->tri[3 * t + 1];
                s->tri[3 * t + 1] = s->tri[3 * t + 2];
                s->tri[3 * t + 2] = tmp;
            }
            vol[k] = -vol[k];
            thx_log(ctx, THX_LOG_INFO, "bem: surface '%s' was oriented inward; reversed", s->name);
        }
        if (!(vol[k] > 0)) { st = thx_error(ctx, THX_EGEOM, "surface '%s' encloses no volume", surf[k]->name); goto done; }
        b->sig_in[k] = sigma_in[k];
        b->off[k + 1] = b->off[k] + surf[k]->n_nodes;
        for (size_t i = 0; i < surf[k]->n_nodes; i++)
            for (int c = 0; c < 3; c++) {
                double x = surf[k]->xyz[3 * i + (size_t)c];
                if (x < lo[c]) lo[c] = x;
                if (x > hi[c]) hi[c] = x;
            }
    }
    b->scale = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    /* nesting: every node of k on one side of l */
    for (size_t k = 0; k < n && st == THX_OK; k++)
        for (size_t l = 0; l < n && st == THX_OK; l++) {
            if (k == l) continue;
            const thx_surface *s = b->surf[k];
            size_t n_in = 0, n_on = 0, first_in = 0, first_out = 0, n_test = 0;
            int have_in = 0, have_out = 0;
            /* at most NEST_SAMPLES nodes, evenly spread over the surface's numbering */
            size_t stride = s->n_nodes > NEST_SAMPLES ? s->n_nodes / NEST_SAMPLES : 1;
            for (size_t i = 0; i < s->n_nodes; i += stride) n_test++;
            /* a node on l (a coincident or touching surface) sees about 2 pi; off it, 0 or 4 pi
               however near (the solid angle jumps across the surface) */
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : n_in, n_on)
            for (size_t i = 0; i < s->n_nodes; i += stride) {
                double w = thx_bem_surface_angle(b, l, s->xyz + 3 * i);
                n_in += w > 2 * M_PI;
                n_on += w > M_PI && w < 3 * M_PI;
            }
            if (n_on > 0) {
                size_t first_on = 0;
                for (size_t i = 0; i < s->n_nodes; i += stride) {
                    double w = thx_bem_surface_angle(b, l, s->xyz + 3 * i);
                    if (w > M_PI && w < 3 * M_PI) { first_on = i; break; }
                }
                const double *x = s->xyz + 3 * first_on;
                st = thx_error(ctx, THX_EGEOM, "surfaces '%s' and '%s' %s: node %zu of '%s' (%.6g, %.6g, %.6g) lies on '%s' "
                               "(%zu of %zu nodes tested); the surfaces must be nested or apart, without touching",
                               s->name, b->surf[l]->name, n_on == n_test ? "coincide" : "touch", first_on + 1, s->name,
                               x[0], x[1], x[2], b->surf[l]->name, n_on, n_test);
            } else if (n_in > 0 && n_in < n_test) {
                for (size_t i = 0; i < s->n_nodes && !(have_in && have_out); i += stride) {
                    int in = thx_bem_surface_angle(b, l, s->xyz + 3 * i) > 2 * M_PI;
                    if (in && !have_in) { have_in = 1; first_in = i; }
                    if (!in && !have_out) { have_out = 1; first_out = i; }
                }
                st = thx_error(ctx, THX_EGEOM, "surfaces '%s' and '%s' cross: node %zu of '%s' is inside '%s', node %zu "
                               "outside (the surfaces must be nested or apart)", s->name, b->surf[l]->name, first_in + 1,
                               s->name, b->surf[l]->name, first_out + 1);
            }
            inside[k * n + l] = n_in == n_test;
        }
    if (st != THX_OK) goto done;
    size_t n_outer = 0;
    for (size_t k = 0; k < n; k++) {
        int p = -1;
        for (size_t l = 0; l < n; l++)
            if (inside[k * n + l] && (p < 0 || vol[l] < vol[p])) p = (int)l;
        if (p >= 0 && inside[(size_t)p * n + k]) { st = thx_error(ctx, THX_EGEOM, "surfaces '%s' and '%s' are inside each other", b->surf[k]->name, b->surf[p]->name); goto done; }
        b->parent[k] = p;
        if (p < 0) { n_outer++; b->outer = k; }
    }
    if (n_outer != 1) {
        st = thx_error(ctx, THX_EGEOM, "bem: %zu surfaces are outermost (not inside any other); the conductor must "
                       "be one closed body: one surface holding all the others", n_outer);
        goto done;
    }
    for (size_t k = 0; k < n; k++) b->sig_out[k] = b->parent[k] >= 0 ? b->sig_in[b->parent[k]] : 0;
    /* node areas */
    b->area = thx_calloc(ctx, b->off[n] ? b->off[n] : 1, sizeof *b->area);
    if (!b->area) { st = THX_ENOMEM; goto done; }
    for (size_t k = 0; k < n; k++) {
        const thx_surface *s = b->surf[k];
        for (size_t t = 0; t < s->n_tris; t++) {
            const int32_t *v = s->tri + 3 * t;
            const double *a = s->xyz + 3 * v[0], *p = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
            double u[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
            double ar = 0.5 * sqrt(x * x + y * y + z * z);
            for (int q = 0; q < 3; q++) b->area[b->off[k] + (size_t)v[q]] += ar / 3;
        }
    }
done:
    free(vol);
    free(inside);
    if (st != THX_OK) thx_bem_destroy(&b);
    *out = b;
    return st;
}

size_t thx_bem_n_surfaces(const thx_bem *b) { return b->n; }
size_t thx_bem_n_nodes(const thx_bem *b) { return b->off[b->n]; }
size_t thx_bem_offset(const thx_bem *b, size_t k) { return b->off[k]; }
const thx_surface *thx_bem_surface(const thx_bem *b, size_t k) { return b->surf[k]; }
int thx_bem_parent(const thx_bem *b, size_t k) { return b->parent[k]; }
size_t thx_bem_outer(const thx_bem *b) { return b->outer; }
double thx_bem_sigma_in(const thx_bem *b, size_t k) { return b->sig_in[k]; }
double thx_bem_sigma_out(const thx_bem *b, size_t k) { return b->sig_out[k]; }

void thx_bem_assemble_rows(const thx_bem *b, size_t i0, size_t i1, const unsigned char *use, int sl_surf, double *B,
                           double *S, size_t ld)
{
    /* every collocation node against every triangle: a row at a time (no write conflicts) */
#pragma omp parallel for schedule(dynamic, 8)
    for (size_t i = i0; i < i1; i++) {
        size_t ks = 0;
        while (b->off[ks + 1] <= i) ks++;
        const double *x = b->surf[ks]->xyz + 3 * (i - b->off[ks]);
        for (size_t l = 0; l < b->n; l++) {
            int want_dl = use[l], want_sl = (int)l == sl_surf;
            if (!want_dl && !want_sl) continue;
            const thx_surface *s = b->surf[l];
            size_t o = b->off[l];
            double *col = want_dl ? B : NULL;
            for (size_t t = 0; t < s->n_tris; t++) {
                const int32_t *v = s->tri + 3 * t;
                double dl[3], sl[3];
                thx_bem_triangle(x, s->xyz + 3 * v[0], s->xyz + 3 * v[1], s->xyz + 3 * v[2], dl, want_sl ? sl : NULL);
                for (int q = 0; q < 3; q++) {
                    if (col) col[(o + (size_t)v[q]) * ld + i - i0] += dl[q];
                    if (want_sl) S[(size_t)v[q] * ld + i - i0] += sl[q];
                }
            }
        }
    }
}

thx_status thx_bem_double_layer(thx_ctx *ctx, const thx_bem *b, double *B)
{
    size_t N = b->off[b->n];
    unsigned char *use = thx_malloc(ctx, b->n);
    if (!use) return THX_ENOMEM;
    memset(use, 1, b->n);
    memset(B, 0, N * N * sizeof *B);
    thx_bem_assemble_rows(b, 0, N, use, -1, B, NULL, N);
    free(use);
    return THX_OK;
}

double thx_bem_vertex_angle(const thx_bem *b, size_t k, size_t i)
{
    /* the triangles at node i and, for each, its edges from i; the dihedral at edge (i, j) between
     * the two triangles sharing it, measured inside */
    const thx_surface *s = b->surf[k];
    const double *p = s->xyz + 3 * i;
    double sum = 0;
    size_t m = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        int c = v[0] == (int32_t)i ? 0 : v[1] == (int32_t)i ? 1 : v[2] == (int32_t)i ? 2 : -1;
        if (c < 0) continue;
        m++;
        /* the edge i -> next of this triangle is shared with the triangle holding next -> i */
        int32_t j = v[(c + 1) % 3], a = v[(c + 2) % 3];
        int32_t bb = -1;
        for (size_t u = 0; u < s->n_tris && bb < 0; u++) {
            const int32_t *w = s->tri + 3 * u;
            for (int q = 0; q < 3; q++)
                if (w[q] == j && w[(q + 1) % 3] == (int32_t)i) bb = w[(q + 2) % 3];
        }
        if (bb < 0) continue;
        const double *pj = s->xyz + 3 * j, *pa = s->xyz + 3 * a, *pb = s->xyz + 3 * bb;
        double e[3] = {pj[0] - p[0], pj[1] - p[1], pj[2] - p[2]};
        double el = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        for (int q = 0; q < 3; q++) e[q] /= el;
        /* components of (a - p), (bb - p) orthogonal to the edge */
        double u1[3] = {pa[0] - p[0], pa[1] - p[1], pa[2] - p[2]}, u2[3] = {pb[0] - p[0], pb[1] - p[1], pb[2] - p[2]};
        double d1 = u1[0] * e[0] + u1[1] * e[1] + u1[2] * e[2], d2 = u2[0] * e[0] + u2[1] * e[1] + u2[2] * e[2];
        for (int q = 0; q < 3; q++) { u1[q] -= d1 * e[q]; u2[q] -= d2 * e[q]; }
        /* the angle from u1 to u2 about e, through the inside: the inside is on the side opposite
         * the outward normal of triangle (i, j, a), n1 = e x u1 direction */
        double n1[3] = {e[1] * u1[2] - e[2] * u1[1], e[2] * u1[0] - e[0] * u1[2], e[0] * u1[1] - e[1] * u1[0]};
        double cs = u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2];
        double sn = n1[0] * u2[0] + n1[1] * u2[1] + n1[2] * u2[2];
        /* rotating u1 toward -n1 (inward) reaches u2 after the interior dihedral */
        double ang = atan2(-sn, cs);
        if (ang < 0) ang += 2 * M_PI;
        sum += ang;
    }
    return sum - ((double)m - 2) * M_PI;
}
