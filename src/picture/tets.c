/*
 * The volume mesh in a picture (--tetrahedra): the tetrahedra whose four nodes all lie on the kept
 * side of the clip plane (a "crinkle" clip: whole elements, not cut ones, so the elements' shapes
 * and sizes show where the plane passes), and of them only the faces not shared by two kept
 * tetrahedra — the faces one can see. One surface per tissue region, so each region takes its own
 * colour; every face turned away from its tetrahedron (outward), whatever the file's node order.
 */
#include <stdlib.h>
#include <string.h>

#include "picture/picture_internal.h"

typedef struct {
    int32_t k[3];  /* sorted nodes: the key */
    int32_t v[3];  /* the nodes, outward */
    int32_t tet;
} face;

static int by_key(const void *a, const void *b)
{
    const face *p = a, *q = b;
    for (int i = 0; i < 3; i++)
        if (p->k[i] != q->k[i]) return p->k[i] < q->k[i] ? -1 : 1;
    return 0;
}

static void sort3(int32_t k[3])
{
    int32_t t;
    if (k[0] > k[1]) t = k[0], k[0] = k[1], k[1] = t;
    if (k[1] > k[2]) t = k[1], k[1] = k[2], k[2] = t;
    if (k[0] > k[1]) t = k[0], k[0] = k[1], k[1] = t;
}

/* Face (a, b, c) of a tetrahedron whose fourth node is d: ordered so that its normal points away
 * from d. */
static void outward(const double *xyz, int32_t a, int32_t b, int32_t c, int32_t d, int32_t out[3])
{
    const double *A = xyz + 3 * (size_t)a, *B = xyz + 3 * (size_t)b, *C = xyz + 3 * (size_t)c, *D = xyz + 3 * (size_t)d;
    double u[3], w[3], e[3];
    for (int i = 0; i < 3; i++) {
        u[i] = B[i] - A[i];
        w[i] = C[i] - A[i];
        e[i] = D[i] - A[i];
    }
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    int flip = n[0] * e[0] + n[1] * e[1] + n[2] * e[2] > 0;
    out[0] = a;
    out[1] = flip ? c : b;
    out[2] = flip ? b : c;
}

thx_status picture_tet_surfaces(thx_ctx *ctx, const thx_volume *v, const thx_clip_plane *cp, thx_surface **out,
                                int *region, int max, int *n_out)
{
    *n_out = 0;
    size_t nf = 0;
    face *f = malloc((v->n_tets ? 4 * v->n_tets : 1) * sizeof *f);
    if (!f) return thx_error(ctx, THX_ENOMEM, "out of memory (--tetrahedra: %zu tetrahedra)", v->n_tets);
    static const int FACE[4][4] = {{1, 2, 3, 0}, {0, 3, 2, 1}, {0, 1, 3, 2}, {0, 2, 1, 3}};
    for (size_t t = 0; t < v->n_tets; t++) {
        const int32_t *q = v->tet + 4 * t;
        int keep = 1;
        if (cp)
            for (int i = 0; i < 4 && keep; i++) {
                const double *p = v->xyz + 3 * (size_t)q[i];
                keep = cp->n[0] * p[0] + cp->n[1] * p[1] + cp->n[2] * p[2] + cp->d >= 0;
            }
        if (!keep) continue;
        for (int j = 0; j < 4; j++) {
            face *g = &f[nf++];
            outward(v->xyz, q[FACE[j][0]], q[FACE[j][1]], q[FACE[j][2]], q[FACE[j][3]], g->v);
            memcpy(g->k, g->v, sizeof g->k);
            sort3(g->k);
            g->tet = (int32_t)t;
        }
    }
    qsort(f, nf, sizeof *f, by_key);
    /* the exposed faces (a key seen once), gathered per region */
    size_t *count = calloc(v->n_regions ? v->n_regions : 1, sizeof *count);
    int32_t *map = malloc((v->n_nodes ? v->n_nodes : 1) * sizeof *map);
    thx_status st = count && map ? THX_OK : thx_error(ctx, THX_ENOMEM, "out of memory (--tetrahedra)");
    size_t n_exposed = 0;
    for (size_t i = 0; st == THX_OK && i < nf;) {
        size_t j = i + 1;
        while (j < nf && !by_key(&f[i], &f[j])) j++;
        if (j == i + 1) {
            int32_t r = v->region[f[i].tet];
            if (r >= 0 && (size_t)r < v->n_regions) count[r]++;
            f[n_exposed++] = f[i];
        }
        i = j;
    }
    for (size_t r = 0; st == THX_OK && r < v->n_regions && *n_out < max; r++) {
        if (!count[r]) continue;
        thx_surface *s = NULL;
        st = thx_surface_create(ctx, v->regions[r].name, THX_ROLE_OTHER, &s);
        if (st != THX_OK) break;
        for (size_t i = 0; i < v->n_nodes; i++) map[i] = -1;
        s->tri = malloc(3 * count[r] * sizeof *s->tri);
        s->xyz = malloc(3 * (3 * count[r]) * sizeof *s->xyz);
        if (!s->tri || !s->xyz) {
            thx_surface_destroy(&s);
            st = thx_error(ctx, THX_ENOMEM, "out of memory (--tetrahedra)");
            break;
        }
        for (size_t i = 0; i < n_exposed; i++) {
            if (v->region[f[i].tet] != (int32_t)r) continue;
            for (int c = 0; c < 3; c++) {
                int32_t g = f[i].v[c];
                if (map[g] < 0) {
                    map[g] = (int32_t)s->n_nodes;
                    memcpy(s->xyz + 3 * s->n_nodes, v->xyz + 3 * (size_t)g, 3 * sizeof *s->xyz);
                    s->n_nodes++;
                }
                s->tri[3 * s->n_tris + (size_t)c] = map[g];
            }
            s->n_tris++;
        }
        region[*n_out] = (int)r;
        out[(*n_out)++] = s;
    }
    free(count);
    free(map);
    free(f);
    if (st != THX_OK)
        while (*n_out > 0) thx_surface_destroy(&out[--*n_out]);
    return st;
}
