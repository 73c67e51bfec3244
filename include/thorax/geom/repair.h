/*
 * thorax/geom/repair.h — digitization noise in contours repaired, not refused
 * (paper 3.1: hand-digitized points are "inevitably jagged"; issue 11 item 6).
 *
 * What a loop may carry and what is done about it, in this order, repeated
 * until the loop is clean (each step removes at least one point, so it ends):
 *   1. a closing point: the last point equal to the first (a loop closes
 *      without repeating its first point): dropped;
 *   2. near-coincident points: a run of consecutive points (cyclically) all
 *      within merge_tol of the run's first point is replaced by its centroid
 *      (a slice through a mesh node gives points 1e-9 mm apart; two clicks
 *      on one spot);
 *   3. spikes: a point where the loop folds straight back on itself (its two
 *      edges collinear and overlapping) is removed;
 *   4. small self-crossings (at most 64 per loop: more is not noise, and
 *      refused): where two edges cross or touch, the loop is two
 *      loops joined at the crossing point X; the one whose points all lie
 *      within untangle_tol of X (the smaller if both do) is cut off and
 *      replaced by X: the bow-tie of a jittered point is removed, the loop
 *      kept. A crossing whose both sides reach farther than untangle_tol is
 *      a real error and refused (as before, with both edges named).
 *   5. holes: a loop inside another loop of its surface on the same layer
 *      (surfaces are built from solid loops only): dropped when narrower than
 *      the node spacing (width = 2 area / perimeter: a groove the layer cuts
 *      across, which nodes `spacing` apart cannot resolve), else refused.
 * Every repair is one message "FILE:LINE: surface "S" layer L (z=Z) loop K:
 * WHAT" (LINE: the first point concerned), logged as a warning (unless the
 * log is quiet) and kept in the log, with its kind, for the model's provenance. With strict set, the first repair
 * needed is refused instead: THX_EINPUT with the same message.
 *   6. tiny loops: a loop that steps 2-4 leave with fewer than 3 points (a
 *      plane grazing the body's end or a bump of it) is dropped where the
 *      plane missing the body would give the same surface: on a layer at an
 *      end of the surface's stack (a layer left without loops is dropped and
 *      the surface capped at its neighbour), inside another loop of its
 *      layer, or where no loop of one neighbouring layer encloses it (a
 *      branch ends at it). It is refused, naming it, when dropping would
 *      leave the surface fewer than 2 layers (its only loop), a gap in its
 *      stack (the only loop of a layer between others), or the surface cut
 *      in two (loops of both neighbouring layers enclose it).
 * After a successful
 * repair the contours satisfy thx_contours_validate's invariants.
 */
#ifndef THORAX_REPAIR_H
#define THORAX_REPAIR_H

#include "thorax/model/contours.h"
#include "thorax/geom/contours_valid.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double spacing;      /* mm: the node spacing the loops will be resampled at (holes narrower are dropped) */
    double merge_tol;    /* mm: consecutive points closer than this are one (0: exact repeats only) */
    double untangle_tol; /* mm: size of a self-crossing's small loop that is cut off (0: none) */
    int strict;          /* 1: refuse the first repair instead of making it */
} thx_repair_opts;

/* The defaults for node spacing `spacing` (mm; kept in o->spacing): merge_tol = spacing / 10 (points closer than a
 * tenth of the node spacing carry nothing the resampled loop can keep), untangle_tol =
 * spacing (a loop that fits within one node spacing of its crossing cannot survive resampling
 * anyway; spacing / 2 left the jittered tip of the Utah sock, 3.3 mm, refused at 5 mm). */
void thx_repair_opts_default(thx_repair_opts *o, double spacing);

/* The kinds of repair, in the order above. */
typedef enum {
    THX_REPAIR_CLOSING,
    THX_REPAIR_MERGED,
    THX_REPAIR_SPIKE,
    THX_REPAIR_UNTANGLED,
    THX_REPAIR_HOLE,
    THX_REPAIR_TINY,
    THX_REPAIR_KINDS
} thx_repair_kind;

typedef struct {
    size_t n, cap;
    char **msg;                                  /* n messages, one per repair (owned) */
    size_t closing, merged, spikes, untangled, holes, tiny; /* counts by kind (merged: points removed) */
    int *kind;                                   /* n kinds (thx_repair_kind), parallel to msg (owned) */
    int quiet; /* set by the caller: the messages are only kept, not logged (the caller summarizes
                  them: thorax surfaces prints a count per kind and the first few, issue 24) */
} thx_repair_log;

/* Repairs every loop of c in place (see above); appends one message per repair to *log
 * (zero it first; free with thx_repair_log_free). Structure must be valid
 * (thx_contours_validate_structure). Returns THX_EINPUT naming file, line, surface, layer and
 * loop for what cannot be repaired, or for the first repair when o->strict. */
thx_status thx_contours_repair(thx_ctx *ctx, thx_contours *c, const thx_repair_opts *o, thx_repair_log *log);
void thx_repair_log_free(thx_repair_log *log);

#ifdef __cplusplus
}
#endif
#endif
