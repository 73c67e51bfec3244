/* A surface subdivided by edge midpoints and the interpolation from its nodes to the fine ones
 * (thorax/bem/bem.h: thx_bem_subdivide, thx_bem_refine; issue 24). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bem/bem_impl.h"

void thx_bem_refinement_free(thx_bem_refinement *W)
{
    if (!W) return;
    free(W->node);
    free(W->w);
    memset(W, 0, sizeof *W);
}

void thx_bem_refined_counts(size_t n_nodes, size_t n_tris, int levels, size_t *n_fine, size_t *t_fine)
{
    /* a closed surface: every edge in two triangles, e = 3 t / 2; each level adds a node per edge,
     * doubles the edges and adds three inside each triangle, and makes four triangles of one */
    double n = (double)n_nodes, t = (double)n_tris, e = 1.5 * t;
    for (int l = 0; l < levels; l++) {
        n += e;
        e = 2 * e + 3 * t;
        t *= 4;
    }
    if (n_fine) *n_fine = n < (double)SIZE_MAX ? (size_t)n : SIZE_MAX;
    if (t_fine) *t_fine = t < (double)SIZE_MAX ? (size_t)t : SIZE_MAX;
}

/* (min node, max node, triangle * 3 + corner) of each triangle's edge from its corner k */
static int cmp_edge3(const void *pa, const void *pb)
{
    const int64_t *a = pa, *b = pb;
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* One level: s (n nodes, t triangles) into f; rows of W for the fine nodes from those of s's
 * (w_in/node_in: 3 per node of s; NULL: the identity), into node_out/w_out. */
static thx_status subdivide_once(thx_ctx *ctx, const thx_surface *s, const size_t *node_in, const double *w_in,
                                 thx_surface *f, size_t **node_out, double **w_out)
{
    size_t n = s->n_nodes, t = s->n_tris, ne = 3 * t;
    thx_status st = THX_OK;
    int64_t *e = thx_malloc(ctx, (ne ? ne : 1) * 3 * sizeof *e);
    size_t *mid = thx_malloc(ctx, (ne ? ne : 1) * sizeof *mid); /* per triangle corner: the node amid its edge */
    if (!e || !mid) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < t; i++)
        for (size_t k = 0; k < 3; k++) {
            int64_t a = s->tri[3 * i + k], c = s->tri[3 * i + (k + 1) % 3];
            e[3 * (3 * i + k)] = a < c ? a : c;
            e[3 * (3 * i + k) + 1] = a < c ? c : a;
            e[3 * (3 * i + k) + 2] = (int64_t)(3 * i + k);
        }
    qsort(e, ne, 3 * sizeof *e, cmp_edge3);
    /* one midpoint per distinct edge, numbered in edge order after the old nodes */
    size_t m = n;
    for (size_t i = 0; i < ne; i++) {
        if (i > 0 && e[3 * i] == e[3 * (i - 1)] && e[3 * i + 1] == e[3 * (i - 1) + 1]) {
            mid[e[3 * i + 2]] = m - 1;
            continue;
        }
        mid[e[3 * i + 2]] = m++;
    }
    if (m > INT32_MAX || t > SIZE_MAX / 4 / 3) {
        st = thx_error(ctx, THX_EINPUT, "bem: surface '%s' subdivided: %zu nodes, more than a surface holds", s->name, m);
        goto done;
    }
    f->n_nodes = m;
    f->n_tris = 4 * t;
    f->xyz = thx_malloc(ctx, 3 * m * sizeof *f->xyz);
    f->tri = thx_malloc(ctx, 3 * 4 * (t ? t : 1) * sizeof *f->tri);
    *node_out = thx_malloc(ctx, 3 * m * sizeof **node_out);
    *w_out = thx_malloc(ctx, 3 * m * sizeof **w_out);
    if (!f->xyz || !f->tri || !*node_out || !*w_out) { st = THX_ENOMEM; goto done; }
    memcpy(f->xyz, s->xyz, 3 * n * sizeof *f->xyz);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            (*node_out)[3 * i + k] = node_in ? node_in[3 * i + k] : i;
            (*w_out)[3 * i + k] = node_in ? w_in[3 * i + k] : k == 0;
        }
    for (size_t i = 0; i < ne; i++) {
        if (i > 0 && e[3 * i] == e[3 * (i - 1)] && e[3 * i + 1] == e[3 * (i - 1) + 1]) continue;
        size_t a = (size_t)e[3 * i], c = (size_t)e[3 * i + 1], q = mid[e[3 * i + 2]];
        for (int k = 0; k < 3; k++) f->xyz[3 * q + k] = (s->xyz[3 * a + k] + s->xyz[3 * c + k]) / 2;
        /* the row of the midpoint: half of each end's; both ends lie on one coarse triangle, so
         * at most three coarse nodes take a weight */
        size_t nn[6];
        double ww[6];
        int cnt = 0;
        for (int end = 0; end < 2; end++) {
            size_t v = end ? c : a;
            for (int k = 0; k < 3; k++) {
                size_t node = node_in ? node_in[3 * v + k] : v;
                double w = node_in ? w_in[3 * v + k] : k == 0;
                if (w == 0) continue;
                int j = 0;
                while (j < cnt && nn[j] != node) j++;
                if (j == cnt) { nn[cnt] = node; ww[cnt++] = 0; }
                ww[j] += w / 2;
            }
        }
        if (cnt > 3) {
            st = thx_error(ctx, THX_EINTERNAL, "bem: surface '%s' subdivided: edge %zu-%zu spans %d coarse nodes", s->name,
                           a + 1, c + 1, cnt);
            goto done;
        }
        for (int k = 0; k < 3; k++) {
            (*node_out)[3 * q + k] = k < cnt ? nn[k] : nn[0];
            (*w_out)[3 * q + k] = k < cnt ? ww[k] : 0;
        }
    }
    /* (a, b, c) into (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca): the same orientation */
    for (size_t i = 0; i < t; i++) {
        int32_t a = s->tri[3 * i], b = s->tri[3 * i + 1], c = s->tri[3 * i + 2];
        int32_t ab = (int32_t)mid[3 * i], bc = (int32_t)mid[3 * i + 1], ca = (int32_t)mid[3 * i + 2];
        int32_t q[12] = {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca};
        memcpy(f->tri + 12 * i, q, sizeof q);
    }
done:
    free(e);
    free(mid);
    return st;
}

thx_status thx_bem_subdivide(thx_ctx *ctx, const thx_surface *s, int levels, thx_surface **fine,
                             thx_bem_refinement *W)
{
    *fine = NULL;
    memset(W, 0, sizeof *W);
    if (levels < 0 || levels > THX_BEM_REFINE_MAX)
        return thx_error(ctx, THX_EINPUT, "bem: surface '%s': %d subdivisions, 0 to %d", s->name, levels,
                         THX_BEM_REFINE_MAX);
    thx_status st = THX_OK;
    thx_surface *cur = NULL;
    size_t *node = NULL;
    double *w = NULL;
    THX_TRY(thx_surface_create(ctx, s->name, s->role, &cur));
    cur->n_nodes = s->n_nodes;
    cur->n_tris = s->n_tris;
    cur->xyz = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *cur->xyz);
    cur->tri = thx_malloc(ctx, (s->n_tris ? s->n_tris : 1) * 3 * sizeof *cur->tri);
    node = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *node);
    w = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *w);
    if (!cur->xyz || !cur->tri || !node || !w) { st = THX_ENOMEM; goto done; }
    memcpy(cur->xyz, s->xyz, s->n_nodes * 3 * sizeof *cur->xyz);
    memcpy(cur->tri, s->tri, s->n_tris * 3 * sizeof *cur->tri);
    for (size_t i = 0; i < s->n_nodes; i++) {
        node[3 * i] = node[3 * i + 1] = node[3 * i + 2] = i;
        w[3 * i] = 1;
        w[3 * i + 1] = w[3 * i + 2] = 0;
    }
    for (int l = 0; l < levels; l++) {
        thx_surface *f = NULL;
        size_t *nf = NULL;
        double *wf = NULL;
        THX_TRY(thx_surface_create(ctx, s->name, s->role, &f));
        st = subdivide_once(ctx, cur, node, w, f, &nf, &wf);
        thx_surface_destroy(&cur);
        free(node);
        free(w);
        cur = f;
        node = nf;
        w = wf;
        if (st != THX_OK) goto done;
    }
    W->n_fine = cur->n_nodes;
    W->n_coarse = s->n_nodes;
    W->node = node;
    W->w = w;
    node = NULL;
    w = NULL;
    *fine = cur;
    cur = NULL;
done:
    thx_surface_destroy(&cur);
    free(node);
    free(w);
    return st;
}

void thx_bem_refinement_apply(const thx_bem_refinement *W, const double *Tf, size_t n_rows, double *T)
{
    memset(T, 0, n_rows * W->n_coarse * sizeof *T);
    for (size_t f = 0; f < W->n_fine; f++)
        for (int k = 0; k < 3; k++) {
            double w = W->w[3 * f + k];
            if (w == 0) continue;
            double *dst = T + W->node[3 * f + k] * n_rows;
            const double *src = Tf + f * n_rows;
            for (size_t i = 0; i < n_rows; i++) dst[i] += w * src[i];
        }
}

thx_status thx_bem_refine(thx_ctx *ctx, const thx_bem *b, size_t k, int levels, thx_bem **out, thx_bem_refinement *W)
{
    *out = NULL;
    memset(W, 0, sizeof *W);
    if (k >= b->n) return thx_error(ctx, THX_EINPUT, "bem: surface %zu of %zu", k + 1, b->n);
    thx_surface *f = NULL;
    thx_status st = thx_bem_subdivide(ctx, b->surf[k], levels, &f, W);
    const thx_surface **s = NULL;
    if (st != THX_OK) goto done;
    s = thx_malloc(ctx, b->n * sizeof *s);
    if (!s) { st = THX_ENOMEM; goto done; }
    for (size_t l = 0; l < b->n; l++) s[l] = l == k ? f : b->surf[l];
    st = thx_bem_create(ctx, s, b->n, b->sig_in, out);
done:
    free(s);
    thx_surface_destroy(&f);
    if (st != THX_OK) thx_bem_refinement_free(W);
    return st;
}
