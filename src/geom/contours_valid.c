/*
 * The loops' geometry of digitized contours (thorax/geom/contours_valid.h): no two consecutive
 * equal points, no loop that touches itself. The structure is checked by the model's walk
 * (thx_contours_validate_with), which calls check_loop after each point and after each loop.
 */
#include "thorax/geom/contours_valid.h"

#include <stdint.h>

#include "thorax/geom/predicates.h"

/* Finds a pair of non-adjacent edges of a closed loop that touch (an O(n log n) sweep), or a spike. */
static int loop_self_intersection(thx_ctx *ctx, const thx_loop *lp, int *ei, int *ej)
{
    int n = (int)lp->n;
    size_t e1 = 0, e2 = 0;
    int found = thx_loop_touch(&lp->p[0].x, lp->n, &e1, &e2);
    if (found < 0) return -1;
    if (found) { *ei = (int)e1; *ej = (int)e2; }
    (void)ctx;
    /* Adjacent edges folding back onto each other (a spike) also make a loop invalid. */
    if (!found)
        for (int i = 0; i < n; i++) {
            thx_vec2 a = lp->p[(i + n - 1) % n], b = lp->p[i], c = lp->p[(i + 1) % n];
            if (thx_orient2d(&a.x, &b.x, &c.x) == 0 && (a.x - b.x) * (c.x - b.x) + (a.y - b.y) * (c.y - b.y) > 0) {
                *ei = (i + n - 1) % n;
                *ej = i;
                return 1;
            }
        }
    return found;
}

static thx_status check_loop(thx_ctx *ctx, const thx_contours_at *at, void *user)
{
    (void)user;
    const thx_contour_surface *cs = at->surf;
    const thx_contour_layer *L = at->layer;
    const thx_loop *lp = &L->loops[at->loop];
    const char *path = at->path;
    int lno = at->layer_no, where = lp->line ? lp->line : L->line;
    size_t i = at->loop;
    if (at->point != SIZE_MAX) {
        size_t k = at->point;
        thx_vec2 a = lp->p[k], b = lp->p[(k + 1) % lp->n];
        if (a.x != b.x || a.y != b.y) return THX_OK;
        int line = lp->lines ? lp->lines[k] : where;
        int bl = lp->lines ? lp->lines[(k + 1) % lp->n] : where;
        if (k + 1 == lp->n)
            return thx_error(ctx, THX_EINPUT,
                             "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: the last point repeats the "
                             "first point (%g, %g): a loop is closed without repeating its first point",
                             path, line, cs->name, lno, L->z, i + 1, a.x, a.y);
        return thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: point %zu repeats point %zu (%g, %g)",
                         path, bl, cs->name, lno, L->z, i + 1, k + 2, k + 1, a.x, a.y);
    }
    int ei = 0, ej = 0;
    int r = loop_self_intersection(ctx, lp, &ei, &ej);
    if (r < 0) return thx_error(ctx, THX_ENOMEM, "out of memory");
    if (r > 0) {
        int line = lp->lines ? lp->lines[ei] : where;
        return thx_error(ctx, THX_EINPUT,
                         "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: loop intersects itself "
                         "(edge %d-%d crosses edge %d-%d)",
                         path, line, cs->name, lno, L->z, i + 1, ei + 1, (int)((ei + 1) % lp->n) + 1, ej + 1,
                         (int)((ej + 1) % lp->n) + 1);
    }
    return THX_OK;
}

thx_status thx_contours_validate(thx_ctx *ctx, const thx_contours *c)
{
    return thx_contours_validate_with(ctx, c, check_loop, NULL);
}
