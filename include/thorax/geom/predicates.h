/*
 * thorax/geom/predicates.h — exact geometric predicates.
 *
 * Each predicate returns a value whose SIGN is exact for the given double
 * inputs (a fast floating-point evaluation with a rigorous error bound; when the
 * bound cannot decide the sign, an exact evaluation). The magnitude is only an
 * approximation of the determinant.
 *
 * Points are arrays of 2 (orient2d, incircle) or 3 (orient3d, insphere)
 * doubles. Signs:
 *
 *  thx_orient2d(a,b,c) = det[a-c; b-c] (2x2, rows) = twice the signed area of
 *      triangle a, b, c: > 0 iff a, b, c are counterclockwise (seen from +z,
 *      x to the right, y up), < 0 iff clockwise, = 0 iff collinear.
 *  thx_orient3d(a,b,c,d) = det[a-d; b-d; c-d] (3x3, rows): > 0 iff d lies
 *      below the plane of a, b, c, "below" meaning on the side from which
 *      a, b, c appear clockwise; equivalently a, b, c appear counterclockwise
 *      seen from above (from the side opposite to d), i.e. d is on the side
 *      opposite to the normal (b-a) x (c-a). = 0 iff coplanar.
 *      Example: orient3d((0,0,0),(1,0,0),(0,1,0),(0,0,-1)) > 0.
 *  thx_incircle(a,b,c,d) > 0 iff d lies strictly inside the circle through
 *      a, b, c when a, b, c are counterclockwise (orient2d(a,b,c) > 0);
 *      < 0 outside; = 0 iff the four points are cocircular. (If a, b, c are
 *      clockwise the sign is reversed.)
 *  thx_insphere(a,b,c,d,e) > 0 iff e lies strictly inside the sphere through
 *      a, b, c, d when orient3d(a,b,c,d) > 0; < 0 outside; = 0 iff the five
 *      points are cospherical. (Reversed if orient3d(a,b,c,d) < 0.)
 *
 * Assumptions: IEEE binary64, round to nearest, no overflow/underflow in
 * the products (|coordinates| within about 1e-60 .. 1e60, or 0). The calls
 * are pure and thread-safe; the exact fallback of insphere uses ~130 kB of
 * stack.
 */
#ifndef THORAX_PREDICATES_H
#define THORAX_PREDICATES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

double thx_orient2d(const double *a, const double *b, const double *c);
double thx_orient3d(const double *a, const double *b, const double *c, const double *d);
double thx_incircle(const double *a, const double *b, const double *c, const double *d);
double thx_insphere(const double *a, const double *b, const double *c, const double *d, const double *e);

/* Do the closed segments p0-p1 and q0-q1 have a point in common (crossing or
 * touching, collinear overlaps included)? Exact, built on thx_orient2d. */
int thx_segments_touch(const double *p0, const double *p1, const double *q0, const double *q1);

/* Does the closed loop of n points xy[2i], xy[2i+1] touch itself: two edges that are not
 * neighbours along the loop cross, touch or overlap (exact)? 1 and the pair (ei < ej; edge i
 * joins point i to point i + 1 mod n), 0 if not, -1 out of memory. O(n log n): a sweep
 * (Shamos and Hoey; src/geom/loop_touch.c). Edges folding back onto their neighbour are not
 * looked for here. */
int thx_loop_touch(const double *xy, size_t n, size_t *ei, size_t *ej);

#ifdef __cplusplus
}
#endif
#endif
