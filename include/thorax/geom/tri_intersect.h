/*
 * thorax/geom/tri_intersect.h — exact triangle-triangle intersection, the test behind the surface
 * check's "no self-intersection" (thorax/check/check.h explains the rules: triangles sharing a node
 * intersect when they meet anywhere else, triangles sharing an edge when they fold onto each other).
 */
#ifndef THORAX_GEOM_TRI_INTERSECT_H
#define THORAX_GEOM_TRI_INTERSECT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Do triangles ta and tb (3 node indices each into xyz, 3 doubles per node)
 * intersect beyond the nodes they share by index? The rules of thorax/check/check.h (exact).
 * Both triangles must be non-degenerate (not collinear); returns 0 for
 * triangles on the same three nodes. Pure and thread-safe. */
int thx_triangles_intersect(const double *xyz, const int32_t ta[3], const int32_t tb[3]);
/* Does the closed segment e0-e1 meet the closed triangle a, b, c (non-degenerate)? Exact. */
int thx_segment_triangle3(const double *e0, const double *e1, const double *a, const double *b, const double *c);
/* Whether a, b, c (3 doubles each) are exactly collinear (a triangle of zero area). */
int thx_collinear3(const double *a, const double *b, const double *c);

#ifdef __cplusplus
}
#endif
#endif
