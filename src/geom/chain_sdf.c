/* Tree-accelerated signed distance to a closed chain (see chain_sdf.h). */
#include "geom/chain_sdf.h"

#include <math.h>
#include <stdlib.h>

int chain_index_init(chain_index *ci, const thx_vec2 *p, size_t n)
{
    ci->n = n;
    ci->p = p;
    ci->n_blocks = (n + CHAIN_BLOCK - 1) / CHAIN_BLOCK;
    ci->leaves = 1;
    while (ci->leaves < ci->n_blocks) ci->leaves *= 2;
    ci->box = malloc(2 * ci->leaves * sizeof *ci->box);
    if (!ci->box) return -1;
    for (size_t k = 0; k < 2 * ci->leaves; k++) {
        chain_box e = {INFINITY, INFINITY, -INFINITY, -INFINITY, 0, 0};
        ci->box[k] = e;
    }
    for (size_t b = 0; b < ci->n_blocks; b++) {
        chain_box *bx = &ci->box[ci->leaves + b];
        size_t end = (b + 1) * CHAIN_BLOCK < n ? (b + 1) * CHAIN_BLOCK : n;
        for (size_t k = b * CHAIN_BLOCK; k <= end; k++) { /* edge k runs from p[k] to p[k+1]: include both ends */
            thx_vec2 q = p[k % n];
            bx->x0 = fmin(bx->x0, q.x); bx->x1 = fmax(bx->x1, q.x);
            bx->y0 = fmin(bx->y0, q.y); bx->y1 = fmax(bx->y1, q.y);
        }
        bx->first = b * CHAIN_BLOCK;
        bx->last = end % n;
    }
    for (size_t k = ci->leaves - 1; k >= 1; k--) {
        const chain_box *l = &ci->box[2 * k], *r = &ci->box[2 * k + 1];
        chain_box *bx = &ci->box[k];
        bx->x0 = fmin(l->x0, r->x0); bx->x1 = fmax(l->x1, r->x1);
        bx->y0 = fmin(l->y0, r->y0); bx->y1 = fmax(l->y1, r->y1);
        bx->first = l->first;
        bx->last = r->x0 <= r->x1 ? r->last : l->last; /* an empty right child adds no edges */
    }
    return 0;
}

void chain_index_free(chain_index *ci)
{
    free(ci->box);
    ci->box = NULL;
}

static double box_d2(const chain_box *bx, thx_vec2 q)
{
    double dx = q.x < bx->x0 ? bx->x0 - q.x : q.x > bx->x1 ? q.x - bx->x1 : 0;
    double dy = q.y < bx->y0 ? bx->y0 - q.y : q.y > bx->y1 ? q.y - bx->y1 : 0;
    return dx * dx + dy * dy;
}

double chain_index_sdf(const chain_index *ci, thx_vec2 q)
{
    double best = INFINITY;
    int wn = 0;
    size_t n = ci->n;
    if (n == 0) return INFINITY;
    /* entries 2 node + counted: counted = 1 when an ancestor has added the node's crossings */
    size_t stack[128], top = 0; /* depth <= 64: each level pushes at most 2 */
    stack[top++] = 2;
    while (top) {
        size_t k = stack[top - 1] / 2, counted = stack[top - 1] % 2;
        top--;
        const chain_box *bx = &ci->box[k];
        if (!(bx->x0 <= bx->x1)) continue; /* empty */
        int near = box_d2(bx, q) < best;
        int wind = !counted && bx->y0 <= q.y && q.y < bx->y1 && bx->x1 >= q.x;
        if (wind && bx->x0 > q.x) { /* wholly right of q: the run's crossings of y = q.y, telescoped */
            wn += (ci->p[bx->last].y > q.y) - (ci->p[bx->first].y > q.y);
            wind = 0;
            counted = 1;
        }
        if (!near && !wind) continue;
        if (k < ci->leaves) {
            /* nearer child last on the stack (visited first) */
            size_t a = 2 * k, b = 2 * k + 1;
            if (box_d2(&ci->box[a], q) < box_d2(&ci->box[b], q)) { size_t t = a; a = b; b = t; }
            /* a node with no crossings to count passes that on (its children have none either) */
            size_t c = counted || !wind;
            stack[top++] = 2 * a + c;
            stack[top++] = 2 * b + c;
            continue;
        }
        size_t blk = k - ci->leaves;
        size_t end = (blk + 1) * CHAIN_BLOCK < n ? (blk + 1) * CHAIN_BLOCK : n;
        for (size_t e = blk * CHAIN_BLOCK; e < end; e++) {
            thx_vec2 a = ci->p[e], c = ci->p[e + 1 == n ? 0 : e + 1];
            double ex = c.x - a.x, ey = c.y - a.y, px = q.x - a.x, py = q.y - a.y;
            if (near) {
                double l2 = ex * ex + ey * ey;
                double t = l2 > 0 ? (px * ex + py * ey) / l2 : 0;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                double ddx = px - t * ex, ddy = py - t * ey, d2 = ddx * ddx + ddy * ddy;
                if (d2 < best) best = d2;
            }
            if (wind) {
                double cr = ex * py - ey * px;
                if (a.y <= q.y) {
                    if (c.y > q.y && cr > 0) wn++;
                } else if (c.y <= q.y && cr < 0) wn--;
            }
        }
    }
    double d = sqrt(best);
    return wn != 0 ? -d : d;
}
