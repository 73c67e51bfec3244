/*
 * thorax/geom/contours_valid.h — the loops' geometry of digitized contours: every invariant of
 * thorax/model/contours.h, the geometric ones included (no two consecutive equal points, no loop
 * that intersects itself, by an O(n log n) sweep with exact predicates).
 */
#ifndef THORAX_GEOM_CONTOURS_VALID_H
#define THORAX_GEOM_CONTOURS_VALID_H

#include "thorax/model/contours.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Checks every invariant of thorax/model/contours.h: the structure, then each loop's geometry.
 * Errors name file:line (when the contours came from a file), surface, layer, loop and points. */
thx_status thx_contours_validate(thx_ctx *ctx, const thx_contours *c);

#ifdef __cplusplus
}
#endif
#endif
