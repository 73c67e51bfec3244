/* Shared by test_field_iso.c and test_field_slice.c: a box of tetrahedra (each grid cube cut
 * into the six Kuhn tetrahedra round its main diagonal, so neighbouring cubes share their faces'
 * diagonals: a conforming mesh), optionally with its interior nodes jittered, and checks of a cut
 * mesh's topology. */
#ifndef THORAX_TESTS_FIELD_BOX_H
#define THORAX_TESTS_FIELD_BOX_H
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/field/field.h"
#include "thorax/model/volume.h"

/* The box's extent (set by the test) and whether an edge's two points lie on one face of it. */
static double G_L[3];
static int on_box(const thx_field_mesh *m, int32_t a, int32_t b)
{
    const double *p = m->xyz + 3 * (size_t)a, *q = m->xyz + 3 * (size_t)b;
    for (int k = 0; k < 3; k++) {
        double e = 1e-9 * G_L[k];
        if (fabs(p[k]) < e && fabs(q[k]) < e) return 1;
        if (fabs(p[k] - G_L[k]) < e && fabs(q[k] - G_L[k]) < e) return 1;
    }
    return 0;
}

/* nx x ny x nz cubes of side h from the origin; jitter (fraction of h) moves interior nodes by a
 * fixed pseudo-random amount; region 1 for tetrahedra whose centroid has z > split (0 if none). */
static thx_volume *box_mesh(thx_ctx *ctx, int nx, int ny, int nz, double h, double jitter, double split)
{
    thx_volume *v = NULL;
    if (thx_volume_create(ctx, &v)) return NULL;
    size_t NX = (size_t)nx + 1, NY = (size_t)ny + 1, NZ = (size_t)nz + 1;
    v->n_nodes = NX * NY * NZ;
    v->xyz = malloc(3 * v->n_nodes * sizeof *v->xyz);
    v->n_tets = 6 * (size_t)nx * (size_t)ny * (size_t)nz;
    v->tet = malloc(4 * v->n_tets * sizeof *v->tet);
    v->region = malloc(v->n_tets * sizeof *v->region);
    v->n_regions = 2;
    v->regions = calloc(2, sizeof *v->regions);
    snprintf(v->regions[0].name, sizeof v->regions[0].name, "lower");
    snprintf(v->regions[1].name, sizeof v->regions[1].name, "upper");
    for (int r = 0; r < 2; r++) v->regions[r].sigma[0] = v->regions[r].sigma[4] = v->regions[r].sigma[8] = 0.2;
    uint32_t seed = 12345;
    for (size_t k = 0; k < NZ; k++)
        for (size_t j = 0; j < NY; j++)
            for (size_t i = 0; i < NX; i++) {
                double *x = v->xyz + 3 * ((k * NY + j) * NX + i);
                x[0] = (double)i * h;
                x[1] = (double)j * h;
                x[2] = (double)k * h;
                int interior = i && j && k && i < NX - 1 && j < NY - 1 && k < NZ - 1;
                for (int c = 0; c < 3; c++) {
                    seed = seed * 1664525u + 1013904223u;
                    if (interior && jitter > 0) x[c] += jitter * h * ((double)(seed >> 8) / 16777216.0 - 0.5);
                }
            }
    /* the six paths from corner 0 to corner 7 of a cube, one tetrahedron each */
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    size_t t = 0;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k};
                    int32_t q[4];
                    q[0] = (int32_t)(((size_t)c[2] * NY + (size_t)c[1]) * NX + (size_t)c[0]);
                    for (int s = 0; s < 3; s++) {
                        c[perm[p][s]]++;
                        q[s + 1] = (int32_t)(((size_t)c[2] * NY + (size_t)c[1]) * NX + (size_t)c[0]);
                    }
                    memcpy(v->tet + 4 * t, q, sizeof q);
                    if (thx_volume_tet_volume(v, t) < 0) {
                        v->tet[4 * t + 2] = q[3];
                        v->tet[4 * t + 3] = q[2];
                    }
                    double zc = 0;
                    for (int s = 0; s < 4; s++) zc += v->xyz[3 * (size_t)v->tet[4 * t + s] + 2] / 4;
                    v->region[t] = zc > split;
                    t++;
                }
    return v;
}

/* Facts about a cut mesh's triangles with tag == tag (< 0: all). */
typedef struct {
    size_t tris, edges, open_edges, bad_edges; /* bad: used more than twice, or twice the same way */
    size_t degenerate, duplicate;
    double min_area;
} mesh_facts;

typedef struct {
    int32_t a, b; /* a < b */
    int dir;      /* +1: used as a->b, -1: b->a */
} ekey;

static int ekey_cmp(const void *pa, const void *pb)
{
    const ekey *x = pa, *y = pb;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    if (x->b != y->b) return x->b < y->b ? -1 : 1;
    return (x->dir > y->dir) - (x->dir < y->dir);
}

typedef struct {
    int32_t v[3];
} tkey;

static int tkey_cmp(const void *pa, const void *pb)
{
    const tkey *x = pa, *y = pb;
    for (int i = 0; i < 3; i++)
        if (x->v[i] != y->v[i]) return x->v[i] < y->v[i] ? -1 : 1;
    return 0;
}

/* on_boundary(user, a, b): whether the edge between points a and b lies on the cut region's
 * boundary (where the surface may end). open_edges counts the edges used once that are not. */
static mesh_facts mesh_check(const thx_field_mesh *m, int tag, int (*on_boundary)(const thx_field_mesh *, int32_t, int32_t))
{
    mesh_facts f;
    memset(&f, 0, sizeof f);
    f.min_area = INFINITY;
    ekey *e = malloc((3 * m->n_tris + 1) * sizeof *e);
    tkey *tk = malloc((m->n_tris + 1) * sizeof *tk);
    size_t ne = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        if (tag >= 0 && m->tag[t] != tag) continue;
        const int32_t *c = m->tri + 3 * t;
        const double *p = m->xyz + 3 * (size_t)c[0], *q = m->xyz + 3 * (size_t)c[1], *r = m->xyz + 3 * (size_t)c[2];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double a = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (a < f.min_area) f.min_area = a;
        if (!(a > 1e-12) || c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) f.degenerate++;
        int32_t s[3] = {c[0], c[1], c[2]}, x;
        if (s[0] > s[1]) x = s[0], s[0] = s[1], s[1] = x;
        if (s[1] > s[2]) x = s[1], s[1] = s[2], s[2] = x;
        if (s[0] > s[1]) x = s[0], s[0] = s[1], s[1] = x;
        memcpy(tk[f.tris].v, s, sizeof s);
        f.tris++;
        for (int k = 0; k < 3; k++) {
            int32_t i = c[k], j = c[(k + 1) % 3];
            e[ne++] = i < j ? (ekey){i, j, 1} : (ekey){j, i, -1};
        }
    }
    qsort(tk, f.tris, sizeof *tk, tkey_cmp);
    for (size_t i = 0; i + 1 < f.tris; i++) f.duplicate += !tkey_cmp(&tk[i], &tk[i + 1]);
    qsort(e, ne, sizeof *e, ekey_cmp);
    for (size_t i = 0; i < ne;) {
        size_t j = i;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) j++;
        f.edges++;
        if (j - i == 1) {
            if (!on_boundary || !on_boundary(m, e[i].a, e[i].b)) f.open_edges++;
        } else if (j - i > 2 || e[i].dir == e[i + 1].dir) {
            f.bad_edges++;
        }
        i = j;
    }
    free(e);
    free(tk);
    return f;
}

/* Area of the polygon where the plane n.x = d cuts the box [0,L]^3 (L per axis): the points where
 * it crosses the box's 12 edges, ordered by angle round their centroid. */
static double box_section_area(const double *n, double d, const double *L)
{
    double p[12][3];
    int np = 0;
    for (int ax = 0; ax < 3; ax++)
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 2; b++) {
                double x[3];
                int u = (ax + 1) % 3, w = (ax + 2) % 3;
                x[u] = a * L[u];
                x[w] = b * L[w];
                if (n[ax] == 0) continue;
                x[ax] = (d - n[u] * x[u] - n[w] * x[w]) / n[ax];
                if (x[ax] < 0 || x[ax] > L[ax]) continue;
                memcpy(p[np++], x, sizeof x);
            }
    if (np < 3) return 0;
    double c[3] = {0, 0, 0};
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 3; k++) c[k] += p[i][k] / np;
    /* a frame in the plane */
    double e1[3] = {p[0][0] - c[0], p[0][1] - c[1], p[0][2] - c[2]};
    double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int k = 0; k < 3; k++) e1[k] /= l;
    double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0]};
    double ang[12], uv[12][2];
    for (int i = 0; i < np; i++) {
        double r[3] = {p[i][0] - c[0], p[i][1] - c[1], p[i][2] - c[2]};
        uv[i][0] = r[0] * e1[0] + r[1] * e1[1] + r[2] * e1[2];
        uv[i][1] = r[0] * e2[0] + r[1] * e2[1] + r[2] * e2[2];
        ang[i] = atan2(uv[i][1], uv[i][0]);
    }
    for (int i = 1; i < np; i++)
        for (int j = i; j > 0 && ang[j] < ang[j - 1]; j--) {
            double t = ang[j];
            ang[j] = ang[j - 1];
            ang[j - 1] = t;
            double a0 = uv[j][0], a1 = uv[j][1];
            uv[j][0] = uv[j - 1][0];
            uv[j][1] = uv[j - 1][1];
            uv[j - 1][0] = a0;
            uv[j - 1][1] = a1;
        }
    double A = 0;
    for (int i = 0; i < np; i++) {
        int j = (i + 1) % np;
        A += uv[i][0] * uv[j][1] - uv[j][0] * uv[i][1];
    }
    return fabs(A) / 2 / sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}
#endif
