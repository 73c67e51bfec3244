/* Block-accelerated signed distance to a closed chain (see chain_sdf.h). */
#include "geom/chain_sdf.h"

#include <math.h>
#include <stdlib.h>

int chain_index_init(chain_index *ci, const thx_vec2 *p, size_t n)
{
    ci->n = n;
    ci->p = p;
    ci->n_blocks = (n + CHAIN_BLOCK - 1) / CHAIN_BLOCK;
    ci->box = malloc((ci->n_blocks ? ci->n_blocks : 1) * sizeof *ci->box);
    if (!ci->box) return -1;
    for (size_t b = 0; b < ci->n_blocks; b++) {
        chain_box bx = {INFINITY, INFINITY, -INFINITY, -INFINITY};
        size_t end = (b + 1) * CHAIN_BLOCK < n ? (b + 1) * CHAIN_BLOCK : n;
        for (size_t k = b * CHAIN_BLOCK; k <= end; k++) { /* edge k runs from p[k] to p[k+1]: include both ends */
            thx_vec2 q = p[k % n];
            bx.x0 = fmin(bx.x0, q.x); bx.x1 = fmax(bx.x1, q.x);
            bx.y0 = fmin(bx.y0, q.y); bx.y1 = fmax(bx.y1, q.y);
        }
        ci->box[b] = bx;
    }
    return 0;
}

void chain_index_free(chain_index *ci)
{
    free(ci->box);
    ci->box = NULL;
}

double chain_index_sdf(const chain_index *ci, thx_vec2 q)
{
    double best = INFINITY;
    int wn = 0;
    size_t n = ci->n;
    for (size_t b = 0; b < ci->n_blocks; b++) {
        const chain_box *bx = &ci->box[b];
        double dx = q.x < bx->x0 ? bx->x0 - q.x : q.x > bx->x1 ? q.x - bx->x1 : 0;
        double dy = q.y < bx->y0 ? bx->y0 - q.y : q.y > bx->y1 ? q.y - bx->y1 : 0;
        int near = dx * dx + dy * dy < best;
        int wind = bx->y0 <= q.y && q.y < bx->y1 && bx->x1 >= q.x;
        if (!near && !wind) continue;
        size_t end = (b + 1) * CHAIN_BLOCK < n ? (b + 1) * CHAIN_BLOCK : n;
        for (size_t k = b * CHAIN_BLOCK; k < end; k++) {
            thx_vec2 a = ci->p[k], c = ci->p[k + 1 == n ? 0 : k + 1];
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
