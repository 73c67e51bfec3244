/*
 * thorax/predicates.h — exact geometric predicates.
 *
 * Each predicate returns a value whose SIGN is exact for the given double
 * inputs (a fast floating-point evaluation with a rigorous error bound; when the
 * bound cannot decide the sign, an exact evaluation). The magnitude is only an
 * approximation of the determinant.
 *
 *  thx_orient2d(a,b,c) > 0  iff a, b, c are counterclockwise (positive area).
 *  thx_orient3d(a,b,c,d) > 0 iff d lies below the plane of a, b, c, where
 *      "below" means a, b, c appear counterclockwise seen from d's side ... with
 *      the convention det[b-a, c-a, d-a] < 0 ... see predicates.c for the exact
 *      statement; = 0 iff coplanar.
 *  thx_incircle(a,b,c,d) > 0 iff d is inside the circle through a, b, c
 *      (a, b, c counterclockwise).
 *  thx_insphere(a,b,c,d,e) > 0 iff e is inside the sphere through a, b, c, d
 *      (with thx_orient3d(a,b,c,d) > 0).
 */
#ifndef THORAX_PREDICATES_H
#define THORAX_PREDICATES_H

#ifdef __cplusplus
extern "C" {
#endif

double thx_orient2d(const double *a, const double *b, const double *c);
double thx_orient3d(const double *a, const double *b, const double *c, const double *d);
double thx_incircle(const double *a, const double *b, const double *c, const double *d);
double thx_insphere(const double *a, const double *b, const double *c, const double *d, const double *e);

#ifdef __cplusplus
}
#endif
#endif
