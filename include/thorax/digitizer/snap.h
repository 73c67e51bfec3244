/*
 * thorax/digitizer/snap.h — a loop copied from one plane to the next and snapped to the edges there
 * (issue 26 item 2), an active contour of the "normal search" kind (as in Cootes et al.'s active shape
 * models; docs/design/digitizer.md says why this one rather than Kass-Witkin-Terzopoulos or the greedy
 * snake): each iteration
 *   1. moves every node's search along its normal (the loop's, from its two neighbours) within
 *      +-range pixels, sampling the directional derivative |grad I . n| of the Gaussian-smoothed plane
 *      every half pixel, weighted by exp(-s^2 / (2 range^2)) (a nearer edge preferred), and takes the
 *      best, refined by a parabola: the node's wanted displacement d_i;
 *   2. the internal stiffness: d replaced by the median of the five around each node (one stray edge
 *      cannot pull a node off), then `smooth` passes of d_i <- (1 - k) d_i + k (d_{i-1} + d_{i+1}) / 2
 *      with k = stiffness (a membrane on the displacements);
 *   3. moves each node by d_i along its normal;
 * with the range halved each iteration down to 1.5 pixels, until no node moves more than 0.02 pixel
 * or `iterations` are done. The node count, order (orientation) and start point are kept.
 */
#ifndef THORAX_DIGITIZER_SNAP_H
#define THORAX_DIGITIZER_SNAP_H

#include "thorax/image/sample.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double range;     /* search half-width along the normals at the first iteration, pixels (8) */
    double sigma;     /* Gaussian smoothing of the plane, pixels (1.5) */
    double stiffness; /* k of the displacement membrane, 0..1 (0.5) */
    int smooth;       /* passes of the membrane per iteration (4) */
    int iterations;   /* at most (30) */
} thx_snap_opts;

void thx_snap_opts_default(thx_snap_opts *o);

/*
 * Snaps the closed loop in[0..n-1] (RAS points, 3 doubles each, n >= 3; taken to this plane by
 * projecting along its normal: a loop of the neighbouring plane is copied so) to the plane's edges:
 * out (n RAS points, the caller's array; may be in) on the plane. THX_EINPUT for n < 3, bad options,
 * or a loop with a node outside the plane.
 */
thx_status thx_snap_loop(thx_ctx *ctx, const thx_image_slice *plane, const thx_snap_opts *o, const double *in,
                         size_t n, double *out);

#ifdef __cplusplus
}
#endif
#endif
