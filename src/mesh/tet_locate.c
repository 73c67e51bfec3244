/* Point location in a volume mesh by a visibility walk (thorax/mesh/tet_locate.h). */
#include "thorax/mesh/tet_locate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"

struct thx_tet_locator {
    const thx_volume *v;
    int32_t *nb;      /* 4 n_tets: the tetrahedron across face k of t at 4 t + k, or -1 */
    double lo[3], inv_h[3];
    int g[3];         /* seed grid cells per axis */
    int32_t *seed;    /* per cell */
    size_t max_steps;
};

void thx_tet_locator_destroy(thx_tet_locator **l)
{
    if (!l || !*l) return;
    free((*l)->nb);
    free((*l)->seed);
    free(*l);
    *l = NULL;
}

long thx_tet_neighbour(const thx_tet_locator *l, size_t t, int k) { return l->nb[4 * t + (size_t)k]; }

static int has(const int32_t *q, int32_t a) { return q[0] == a || q[1] == a || q[2] == a || q[3] == a; }

static int cell_axis(const thx_tet_locator *l, int a, double x)
{
    double f = (x - l->lo[a]) * l->inv_h[a];
    if (!(f >= 0)) return 0;
    if (f >= l->g[a]) return l->g[a] - 1;
    return (int)f;
}

static size_t cell_of(const thx_tet_locator *l, const double p[3])
{
    return (size_t)cell_axis(l, 0, p[0]) +
           (size_t)l->g[0] * ((size_t)cell_axis(l, 1, p[1]) + (size_t)l->g[1] * (size_t)cell_axis(l, 2, p[2]));
}

thx_status thx_tet_locator_create(thx_ctx *ctx, const thx_volume *v, thx_tet_locator **out)
{
    *out = NULL;
    size_t nt = v->n_tets, nn = v->n_nodes;
    if (!nt) return thx_error(ctx, THX_EINPUT, "point location: the volume has no tetrahedra");
    thx_tet_locator *l = thx_calloc(ctx, 1, sizeof *l);
    size_t *start = thx_calloc(ctx, nn + 1, sizeof *start);
    int32_t *inc = thx_malloc(ctx, 4 * nt * sizeof *inc);
    if (!l || !start || !inc) {
        free(l), free(start), free(inc);
        return THX_ENOMEM;
    }
    l->v = v;
    l->nb = thx_malloc(ctx, 4 * nt * sizeof *l->nb);
    if (!l->nb) {
        free(start), free(inc), thx_tet_locator_destroy(&l);
        return THX_ENOMEM;
    }
    /* the tetrahedra around each node (CSR, ascending) */
    for (size_t i = 0; i < 4 * nt; i++) start[v->tet[i] + 1]++;
    for (size_t i = 0; i < nn; i++) start[i + 1] += start[i];
    {
        size_t *fill = thx_malloc(ctx, (nn ? nn : 1) * sizeof *fill);
        if (!fill) {
            free(start), free(inc), thx_tet_locator_destroy(&l);
            return THX_ENOMEM;
        }
        memcpy(fill, start, nn * sizeof *fill);
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 4; k++) inc[fill[v->tet[4 * t + (size_t)k]]++] = (int32_t)t;
        free(fill);
    }
    /* across each face: the other tetrahedron around its first corner that has all three */
    long bad = -1;
    int bad_k = 0;
#pragma omp parallel for schedule(static)
    for (long t = 0; t < (long)nt; t++)
        for (int k = 0; k < 4; k++) {
            const int32_t *q = v->tet + 4 * t;
            int32_t a = q[(k + 1) % 4], b = q[(k + 2) % 4], c = q[(k + 3) % 4], found = -1;
            int count = 0;
            for (size_t j = start[a]; j < start[a + 1]; j++) {
                int32_t u = inc[j];
                if (u == t) continue;
                const int32_t *r = v->tet + 4 * (size_t)u;
                if (has(r, b) && has(r, c)) {
                    if (found < 0) found = u;
                    count++;
                }
            }
            l->nb[4 * t + k] = found;
            if (count > 1) {
#pragma omp critical
                if (bad < 0 || t < bad) bad = t, bad_k = k;
            }
        }
    free(start);
    free(inc);
    if (bad >= 0) {
        const int32_t *q = v->tet + 4 * bad;
        thx_status st = thx_error(ctx, THX_EGEOM, "point location: the face (%d, %d, %d) of tetrahedron %ld (1-based) is "
                                                  "shared by more than two tetrahedra",
                                  q[(bad_k + 1) % 4] + 1, q[(bad_k + 2) % 4] + 1, q[(bad_k + 3) % 4] + 1, bad + 1);
        thx_tet_locator_destroy(&l);
        return st;
    }
    /* the seed grid */
    double hi[3];
    for (int a = 0; a < 3; a++) l->lo[a] = hi[a] = v->xyz[a];
    for (size_t i = 0; i < nn; i++)
        for (int a = 0; a < 3; a++) {
            double x = v->xyz[3 * i + (size_t)a];
            l->lo[a] = fmin(l->lo[a], x);
            hi[a] = fmax(hi[a], x);
        }
    int side = (int)ceil(cbrt((double)nt / 8.0));
    side = side < 1 ? 1 : side > 64 ? 64 : side;
    size_t nc = 1;
    for (int a = 0; a < 3; a++) {
        l->g[a] = side;
        double w = hi[a] - l->lo[a];
        l->inv_h[a] = w > 0 ? side / w : 0;
        nc *= (size_t)side;
    }
    l->seed = thx_malloc(ctx, nc * sizeof *l->seed);
    if (!l->seed) {
        thx_tet_locator_destroy(&l);
        return THX_ENOMEM;
    }
    for (size_t c = 0; c < nc; c++) l->seed[c] = -1;
    for (size_t t = 0; t < nt; t++) {
        double m[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int a = 0; a < 3; a++) m[a] += 0.25 * v->xyz[3 * (size_t)v->tet[4 * t + (size_t)k] + (size_t)a];
        size_t c = cell_of(l, m);
        if (l->seed[c] < 0) l->seed[c] = (int32_t)t;
    }
    for (size_t c = 0; c < nc; c++)
        if (l->seed[c] < 0) l->seed[c] = 0;
    l->max_steps = (size_t)fmax(1000.0, 20.0 * cbrt((double)nt));
    *out = l;
    return THX_OK;
}

long thx_tet_locate(const thx_tet_locator *l, const double p[3], long start, size_t *steps)
{
    const thx_volume *v = l->v;
    long t = start >= 0 && (size_t)start < v->n_tets ? start : l->seed[cell_of(l, p)];
    long from = -1;
    unsigned rot = (unsigned)t * 2654435761u;
    size_t n = 0;
    for (;;) {
        if (++n > l->max_steps) break;
        const int32_t *q = v->tet + 4 * (size_t)t;
        const double *P[4];
        for (int k = 0; k < 4; k++) P[k] = v->xyz + 3 * (size_t)q[k];
        double s0 = thx_orient3d(P[0], P[1], P[2], P[3]);
        if (s0 == 0) break; /* flat: no side to tell */
        rot = rot * 1103515245u + 12345u;
        int first = (int)((rot >> 16) & 3), next = -1;
        for (int j = 0; j < 4 && next < 0; j++) {
            int k = (first + j) & 3;
            long u = l->nb[4 * (size_t)t + (size_t)k];
            if (u >= 0 && u == from) continue; /* p lies on our side of the face we came in by */
            const double *R[4] = {P[0], P[1], P[2], P[3]};
            R[k] = p;
            double sk = thx_orient3d(R[0], R[1], R[2], R[3]);
            if ((s0 > 0 && sk < 0) || (s0 < 0 && sk > 0)) next = k;
        }
        if (next < 0) {
            if (steps) *steps = n;
            return t;
        }
        long u = l->nb[4 * (size_t)t + (size_t)next];
        if (u < 0) break; /* out through the boundary */
        from = t;
        t = u;
    }
    if (steps) *steps = n;
    return -1;
}
