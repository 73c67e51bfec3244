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
    const int32_t *id;         /* on a part: the tetrahedra's numbers in the whole (borrowed), or NULL */
    const unsigned char *edge; /* on a part: 4 n_tets, face k of t at 4 t + k on the part's edge, or NULL */
};

void thx_tet_locator_set_part(thx_tet_locator *l, const int32_t *id, const unsigned char *edge)
{
    l->id = id;
    l->edge = edge;
}

void thx_tet_locator_destroy(thx_tet_locator **l)
{
    if (!l || !*l) return;
    free((*l)->nb);
    free((*l)->seed);
    free(*l);
    *l = NULL;
}

long thx_tet_neighbour(const thx_tet_locator *l, size_t t, int k) { return l->nb[4 * t + (size_t)k]; }

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
    size_t *start = thx_calloc(ctx, nn + 2, sizeof *start);
    int32_t *fb = thx_malloc(ctx, 3 * 4 * nt * sizeof *fb); /* per face, bucketed: b, c, 4 t + k */
    if (l) l->nb = thx_malloc(ctx, 4 * nt * sizeof *l->nb);
    if (!l || !start || !fb || !l->nb) {
        free(start), free(fb), thx_tet_locator_destroy(&l);
        return THX_ENOMEM;
    }
    l->v = v;
    /* Faces matched by their smallest node: each face (a < b < c, the corners other than k) goes to a's
     * bucket (a counting sort); the two tetrahedra of an inner face meet in one bucket, sorted there (a
     * few dozen faces: 4 n_tets / n_nodes, about 24, on average) to bring them together. */
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            const int32_t *q = v->tet + 4 * t;
            int32_t a = q[(k + 1) % 4], b = q[(k + 2) % 4], c = q[(k + 3) % 4];
            start[(a < b ? (a < c ? a : c) : (b < c ? b : c)) + 2]++;
        }
    for (size_t i = 0; i < nn; i++) start[i + 2] += start[i + 1];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            const int32_t *q = v->tet + 4 * t;
            int32_t a = q[(k + 1) % 4], b = q[(k + 2) % 4], c = q[(k + 3) % 4], x;
            if (a > b) x = a, a = b, b = x;
            if (b > c) x = b, b = c, c = x;
            if (a > b) x = a, a = b, b = x;
            size_t j = start[a + 1]++;
            fb[3 * j] = b, fb[3 * j + 1] = c, fb[3 * j + 2] = (int32_t)(4 * t + (size_t)k);
        }
    /* now start[a] .. start[a + 1] is a's bucket */
    long bad = -1;
    int bad_k = 0;
#pragma omp parallel for schedule(dynamic, 1024)
    for (long a = 0; a < (long)nn; a++) {
        /* the bucket sorted by (b, c) (insertion: a few dozen faces), then its runs of equal faces */
        int32_t *B = fb + 3 * start[a];
        size_t m = start[a + 1] - start[a];
        for (size_t i = 1; i < m; i++) {
            int32_t r[3] = {B[3 * i], B[3 * i + 1], B[3 * i + 2]};
            size_t j = i;
            while (j > 0 && (B[3 * j - 3] > r[0] || (B[3 * j - 3] == r[0] && B[3 * j - 2] > r[1]))) {
                B[3 * j] = B[3 * j - 3], B[3 * j + 1] = B[3 * j - 2], B[3 * j + 2] = B[3 * j - 1];
                j--;
            }
            B[3 * j] = r[0], B[3 * j + 1] = r[1], B[3 * j + 2] = r[2];
        }
        for (size_t i = 0; i < m;) {
            size_t e = i + 1;
            while (e < m && B[3 * e] == B[3 * i] && B[3 * e + 1] == B[3 * i + 1]) e++;
            if (e - i == 1) l->nb[B[3 * i + 2]] = -1;
            else if (e - i == 2) {
                l->nb[B[3 * i + 2]] = B[3 * i + 5] / 4;
                l->nb[B[3 * i + 5]] = B[3 * i + 2] / 4;
            } else {
                /* a face of more than two tetrahedra: the first of them (and its face) is reported */
                int32_t f = B[3 * i + 2];
                for (size_t j = i; j < e; j++) {
                    l->nb[B[3 * j + 2]] = -1;
                    if (B[3 * j + 2] < f) f = B[3 * j + 2];
                }
                long t = f / 4;
                int k = f % 4;
#pragma omp critical
                if (bad < 0 || t < bad || (t == bad && k < bad_k)) bad = t, bad_k = k;
            }
            i = e;
        }
    }
    free(start);
    free(fb);
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
    unsigned rot = (unsigned)(l->id ? l->id[t] : t) * 2654435761u; /* a part walks as the whole does */
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
        if (u < 0 && l->edge && l->edge[4 * (size_t)t + (size_t)next]) { /* the whole goes on: the part cannot tell */
            if (steps) *steps = n;
            return -2;
        }
        if (u < 0) break; /* out through the boundary */
        from = t;
        t = u;
    }
    if (steps) *steps = n;
    return -1;
}
