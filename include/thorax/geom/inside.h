/*
 * thorax/geom/inside.h — inside/outside tests (paper 3.2, "Inside/Outside algorithm").
 *
 * 2D: the algebraic sum of the angles subtended at P by consecutive points of a
 *     closed loop is 2*pi (times the winding number) if P is inside, 0 outside.
 * 3D: the sum of the solid angles subtended at P by the triangles of a closed,
 *     consistently oriented surface is 4*pi inside (triangles counterclockwise
 *     seen from outside), 0 outside.
 *
 * Tolerance behaviour: both tests first measure the distance from P to the
 * boundary (loop edges / triangles). If it is below `tol` (mm), P is reported
 * as THX_ON_BOUNDARY, because there the angle sum jumps and no floating-point
 * answer is trustworthy. A point exactly on the boundary (decided with the
 * exact predicates) is THX_ON_BOUNDARY for every tol, including tol = 0.
 * Otherwise the angle sum is rounded to the nearest multiple of 2*pi (4*pi):
 * a nonzero multiple (the winding number, in either direction) means inside.
 * thx_loop_classify / thx_surface_classify also return the winding number and
 * the distance of the sum from that multiple (*residual), for callers that
 * want to verify closure.
 *
 * The functions are pure (no context: they cannot fail) and thread-safe.
 * Loops are pts[0..n-1] with the closing edge pts[n-1] -> pts[0] implicit.
 */
#ifndef THORAX_INSIDE_H
#define THORAX_INSIDE_H

#include "thorax/model/surface.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef enum { THX_OUTSIDE = 0, THX_INSIDE = 1, THX_ON_BOUNDARY = 2 } thx_inside;

/* Sum of the signed angles subtended at p by the edges of the closed loop
 * pts[0..n-1] (radians): +2pi for a counterclockwise loop around p, -2pi
 * clockwise, 0 outside. */
double thx_loop_angle_sum(const thx_vec2 *pts, size_t n, thx_vec2 p);

/* Classifies p against a closed loop in either direction (see tolerance above;
 * tol = 0 classifies every point not exactly on the loop). */
thx_inside thx_loop_inside(const thx_vec2 *pts, size_t n, thx_vec2 p, double tol);

/* As thx_loop_inside; also returns (either may be NULL) the winding number
 * round(sum / 2pi) (+1 inside a counterclockwise loop, -1 inside a clockwise
 * one) and the residual |sum - 2pi winding| (0 and 0 when ON_BOUNDARY). */
thx_inside thx_loop_classify(const thx_vec2 *pts, size_t n, thx_vec2 p, double tol, int *winding, double *residual);

/* Signed area of a loop (positive counterclockwise seen from +z). */
double thx_loop_area(const thx_vec2 *pts, size_t n);

/* Distance from p to the closest edge of a closed loop. */
double thx_loop_distance(const thx_vec2 *pts, size_t n, thx_vec2 p);

/* Solid angle (steradians, signed, in (-2pi, 2pi]) subtended at p by
 * triangle a, b, c (Van Oosterom & Strackee 1983:
 * Omega = 2 atan2(R1.(R2 x R3), r1 r2 r3 + (R1.R2) r3 + (R1.R3) r2 + (R2.R3) r1),
 * Ri = vertex - p, ri = |Ri|).
 * Sign: positive when p lies on the side opposite to the normal
 * n = (b-a) x (c-a), i.e. when p sees a, b, c clockwise. Equivalently: for
 * a triangle stored counterclockwise seen from outside (n points out), a
 * point inside the surface sees a positive solid angle, so the total over a
 * closed surface so oriented is +4pi inside (-4pi if all triangles are
 * reversed) and 0 outside. 0 when p is in the triangle's plane (outside the
 * triangle). */
double thx_triangle_solid_angle(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p);

/* Distance from p to the closed triangle a, b, c (mm). */
double thx_triangle_distance(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p);
/* The same distance squared (no square root: for comparisons against r * r). */
double thx_triangle_distance2(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p);

/* Total solid angle subtended at p by all triangles of s (steradians):
 * 4pi inside a closed surface oriented counterclockwise from outside, 0 outside.
 * Large surfaces are summed in parallel (OpenMP) over fixed chunks whose
 * partial sums are added in order: the result does not depend on the number
 * of threads. */
double thx_surface_solid_angle(const thx_surface *s, thx_vec3 p);

/* Classifies p against a closed surface (see tolerance above; the distance
 * is the point-to-triangle distance). Either direction of orientation works
 * (winding -1 counts as inside). */
thx_inside thx_surface_inside(const thx_surface *s, thx_vec3 p, double tol);

/* As thx_surface_inside; also returns (either may be NULL) the winding
 * number round(sum / 4pi) and the residual |sum - 4pi winding|. */
thx_inside thx_surface_classify(const thx_surface *s, thx_vec3 p, double tol, int *winding, double *residual);

#ifdef __cplusplus
}
#endif
#endif
