/*
 * thorax/inside.h — inside/outside tests (paper 3.2, "Inside/Outside algorithm").
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
 * answer is trustworthy. Otherwise the angle sum is rounded to the nearest
 * multiple of 2*pi (4*pi) and its distance from that multiple is returned in
 * *residual for callers that want to verify closure.
 */
#ifndef THORAX_INSIDE_H
#define THORAX_INSIDE_H

#include "thorax/geom.h"

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

/* Signed area of a loop (positive counterclockwise seen from +z). */
double thx_loop_area(const thx_vec2 *pts, size_t n);

/* Distance from p to the closest edge of a closed loop. */
double thx_loop_distance(const thx_vec2 *pts, size_t n, thx_vec2 p);

/* Solid angle (steradians, signed) subtended at p by triangle a, b, c:
 * positive when p sees the triangle counterclockwise... i.e. when p is on the
 * side opposite to the triangle's normal (b-a)x(c-a). (Van Oosterom–Strackee.) */
double thx_triangle_solid_angle(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p);

/* Total solid angle subtended at p by all triangles of s (steradians):
 * 4pi inside a closed surface oriented counterclockwise from outside, 0 outside. */
double thx_surface_solid_angle(const thx_surface *s, thx_vec3 p);

/* Classifies p against a closed surface (see tolerance above). */
thx_inside thx_surface_inside(const thx_surface *s, thx_vec3 p, double tol);

#ifdef __cplusplus
}
#endif
#endif
