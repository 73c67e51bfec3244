/*
 * thorax/digitizer/valid.h — the loops of one plane checked as they are traced (issue 26 item 2: "a
 * loop that crosses itself or another surface's loop is marked at once"), with the exact predicates of
 * thorax/geom/predicates.h (thx_loop_touch for a loop on itself, thx_segments_touch between loops).
 */
#ifndef THORAX_DIGITIZER_VALID_H
#define THORAX_DIGITIZER_VALID_H

#include "thorax/core/core.h"
#include "thorax/core/vec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One crossing: loop `a`'s edge ea (from point ea to ea + 1 mod n) touches loop `b`'s edge eb; a == b
 * for a loop touching itself (ea < eb, not neighbours). */
typedef struct {
    size_t a, ea, b, eb;
} thx_loop_crossing;

/*
 * Checks the closed loops loops[i] (n[i] points each, 2D in the plane) of one plane: at most one
 * crossing reported per loop on itself and per pair of loops (the first found), in the order (a, b)
 * a <= b ascending. *out malloc'd (NULL when none), *n_out of them. A loop inside another does not
 * count (nesting is the contour model's rule); a shared point or an overlapping edge does.
 * THX_EINPUT for a loop of fewer than 3 points.
 */
thx_status thx_loops_crossings(thx_ctx *ctx, const thx_vec2 *const *loops, const size_t *n, size_t n_loops,
                               thx_loop_crossing **out, size_t *n_out);

#ifdef __cplusplus
}
#endif
#endif
