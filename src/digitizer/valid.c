/* src/digitizer/valid.c — crossings of the loops of one plane (thorax/digitizer/valid.h). */
#include <math.h>
#include <stdlib.h>

#include "thorax/digitizer/valid.h"
#include "thorax/geom/predicates.h"

static void bbox(const thx_vec2 *L, size_t n, double b[4])
{
    b[0] = b[1] = INFINITY;
    b[2] = b[3] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        b[0] = fmin(b[0], L[i].x);
        b[1] = fmin(b[1], L[i].y);
        b[2] = fmax(b[2], L[i].x);
        b[3] = fmax(b[3], L[i].y);
    }
}

static thx_status push(thx_ctx *ctx, thx_loop_crossing **out, size_t *n, size_t *cap, thx_loop_crossing c)
{
    THX_CHECK(thx_grow(ctx, (void **)out, cap, *n + 1, sizeof **out));
    (*out)[(*n)++] = c;
    return THX_OK;
}

thx_status thx_loops_crossings(thx_ctx *ctx, const thx_vec2 *const *loops, const size_t *n, size_t n_loops,
                               thx_loop_crossing **out, size_t *n_out)
{
    *out = NULL;
    *n_out = 0;
    size_t cap = 0;
    thx_status st = THX_OK;
    double *bb = thx_malloc(ctx, (n_loops ? n_loops : 1) * 4 * sizeof *bb);
    if (!bb) return THX_ENOMEM;
    for (size_t a = 0; a < n_loops; a++) {
        if (n[a] < 3) {
            st = thx_error(ctx, THX_EINPUT, "loop %zu has %zu points (3 or more)", a + 1, n[a]);
            goto done;
        }
        bbox(loops[a], n[a], bb + 4 * a);
    }
    for (size_t a = 0; a < n_loops; a++) {
        /* thx_vec2 is two doubles, x then y: the layout thx_loop_touch reads */
        size_t ei, ej;
        int r = thx_loop_touch((const double *)loops[a], n[a], &ei, &ej);
        if (r < 0) {
            st = thx_error(ctx, THX_ENOMEM, "out of memory checking loop %zu", a + 1);
            goto done;
        }
        if (r && (st = push(ctx, out, n_out, &cap, (thx_loop_crossing){a, ei, a, ej})) != THX_OK) goto done;
        for (size_t b = a + 1; b < n_loops; b++) {
            const double *A = bb + 4 * a, *B = bb + 4 * b;
            if (A[0] > B[2] || B[0] > A[2] || A[1] > B[3] || B[1] > A[3]) continue;
            int found = 0;
            for (size_t i = 0; i < n[a] && !found; i++) {
                thx_vec2 p = loops[a][i], q = loops[a][(i + 1) % n[a]];
                double lx = fmin(p.x, q.x), hx = fmax(p.x, q.x), ly = fmin(p.y, q.y), hy = fmax(p.y, q.y);
                if (lx > B[2] || hx < B[0] || ly > B[3] || hy < B[1]) continue;
                for (size_t j = 0; j < n[b]; j++) {
                    thx_vec2 r0 = loops[b][j], r1 = loops[b][(j + 1) % n[b]];
                    if (fmax(r0.x, r1.x) < lx || fmin(r0.x, r1.x) > hx || fmax(r0.y, r1.y) < ly ||
                        fmin(r0.y, r1.y) > hy)
                        continue;
                    if (thx_segments_touch(&p.x, &q.x, &r0.x, &r1.x)) {
                        if ((st = push(ctx, out, n_out, &cap, (thx_loop_crossing){a, i, b, j})) != THX_OK) goto done;
                        found = 1;
                        break;
                    }
                }
            }
        }
    }
done:
    free(bb);
    if (st != THX_OK) {
        free(*out);
        *out = NULL;
        *n_out = 0;
    }
    return st;
}
