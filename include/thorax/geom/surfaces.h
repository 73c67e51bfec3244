/*
 * thorax/geom/surfaces.h — from digitized contours to closed, oriented triangle
 * surfaces (paper 3.1 "From MRI to points", 3.2 "Surface Segmentation").
 *
 *   contours --(3.1: periodic smoothing spline, arc-length resampling)--> layers
 *   layers   --(3.2: lacing adjacent layers, slice by slice)--> open surfaces
 *            --(3.2: end caps, outward orientation by the inside test)--> model
 *
 * Invariants of a built surface: closed 2-manifold, every triangle
 * counterclockwise seen from outside, nodes of a layer lie exactly in its plane.
 */
#ifndef THORAX_SURFACES_H
#define THORAX_SURFACES_H

#include "thorax/model/contours.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/model/model.h"
#ifdef __cplusplus
extern "C" {
#endif

/* ---- layers (3.1) ------------------------------------------------------- */

/*
 * Fits a closed parametric cubic smoothing spline x(t), y(t) (t = chord length)
 * to a digitized loop and resamples it at constant arc-length spacing.
 *   smoothing: bandwidth of the smoothing, mm (0 = interpolating spline). The
 *              spline minimizes sum |p_i - s(t_i)|^2 + lambda * int |s''|^2 with
 *              lambda = smoothing^4 * (points per mm), so the same value smooths
 *              alike whatever the digitization density. A loop the smoothing would shrink
 *              below half its digitized area (one not much larger than the bandwidth) is
 *              fitted with half the smoothing, and so on down to none.
 *   spacing:   target node spacing along the curve, mm. The loop gets
 *              N = max(3, round(L / spacing)) nodes exactly L/N apart in arc length.
 *              A digitized edge longer than the spacing along which the spline strays
 *              farther than a smooth curve through the neighbouring points would (at most
 *              0.4 spacing) is resampled linearly first and the spline fitted again: sparse
 *              polygons (40 mm between points) are rebuilt within half the spacing of the
 *              polygon, without the free spline's overshoot, and smooth curves sampled
 *              sparsely keep the spline's accuracy.
 *   start:     the first node is the curve point nearest this point (the
 *              anatomical start point, paper 3.2 step 1).
 * The result runs counterclockwise seen cranio-caudally (positive area),
 * whatever the input direction. *out is allocated (caller frees).
 */
thx_status thx_loop_resample(thx_ctx *ctx, const thx_vec2 *pts, size_t n, double spacing, double smoothing,
                             thx_vec2 start, thx_vec2 **out, size_t *n_out);

/* ---- lacing (3.2) ------------------------------------------------------- */

/* Nodes a lacing may add. A chord that cuts a filled pocket (cut_filled_pockets) off in its layer's
 * plane, longer than 1.5 node spacings, gets nodes along it at the spacing (without them the other layer's
 * run along the chord is fanned to its two ends: a dome's top, 27 mm across, gave 22 triangles under 1
 * degree). The caller gives the room: ids base .. base + cap - 1, their points at xyz[3 * (id - base)];
 * n counts those taken (a lacing laced again and discarded leaves its nodes unused: the caller drops
 * them). Full: the chord is left whole. */
typedef struct thx_lace_nodes {
    double *xyz;
    int32_t base;
    size_t n, cap;
} thx_lace_nodes;

typedef struct {
    double spacing;        /* node spacing of the layers, mm (scales the tolerances) */
    double concave_tol;    /* a triangle is outside the surface if its centroid c lies more than
                              concave_tol * (spacing + |dA(c) - dB(c)|) outside the layer curves
                              interpolated to its height (dA, dB: signed distances to the curves) */
    double max_edge;       /* an edge longer than max_edge * max(spacing, layer gap) makes a triangle "too large" */
    int window;            /* initial half-width (nodes) of the re-lacing window around a gap */
    double phase_weight;   /* weight of the arc-length phase in the lacing metric (0 = position only) */
    int whole_dp;          /* 1: the whole slice laced by one dynamic programme over every pair of nodes (the
                              path of least cost: diagonals, outside and too long triangles penalized; the
                              second retry of a lacing with an angle under 1 degree); 0: the greedy
                              shortest-diagonal walk, its outside runs mended by windowed DP */
    int raw_positions;     /* 1: the lacing metric takes the chains' own positions, not mapped to a common
                              centroid and RMS radius (thin crescents of unequal length: the retry of a
                              lacing with an angle under 1 degree) */
    int fan_limit;         /* a run of this many triangles at one node is cut as a tongue where it is one */
    double projected_aspect; /* nested loops whose lacing has a triangle of worse aspect ratio (or a
                              fan over 3 fan_limit) are laced in projection if that is better */
    int cut_filled_pockets; /* before lacing, cut in its plane the pockets of either chain that the
                              other layer fills: 0 no (default; thx_lace still does it for a fan over
                              3 fan_limit, at level 1), -1 never, 1 those the slice beyond cannot cut,
                              2 also those it might (the retry of a lacing that crosses, thx_surfaces_build) */
    int cut_tongue_runs;   /* 1: with the filled pockets (cut_filled_pockets > 0), also cut in its plane a
                              tongue of either chain found as a run of its nodes outside the other layer's
                              curve (one voxel wide: the retry of a lacing with an angle under 1 degree);
                              0 (default): no */
    thx_lace_nodes *nodes; /* where cut chords' nodes go; NULL (default): chords are not split */
} thx_lace_opts;

typedef struct {
    size_t n_tris;
    size_t removed;        /* triangles of the shortest-diagonal lacing removed as outside (concave) */
    size_t relaced_gaps;   /* gaps re-triangulated */
    size_t inplane_tris;   /* triangles made in the plane of a layer (pockets, tongues; caps excluded) */
    size_t tongues;        /* tongues of one layer cut in its plane (instead of a long fan) */
    size_t filled_pockets; /* pockets of one layer that the other fills, cut in its plane before
                              lacing (the retry of a crossing lacing: thx_lace_opts.cut_filled_pockets) */
    size_t projected;      /* slices of nested loops laced by triangulating the ring between them
                              in projection (fallback for fans and unresolved triangles) */
    size_t unresolved;     /* triangles still failing the outside test (reported, kept closed) */
    size_t too_large;      /* triangles with an edge longer than the max_edge bound */
    size_t relaced_crossing; /* groups whose lacing had crossing triangles, laced again with other
                              settings until it had none (thx_surfaces_build) */
    size_t relaced_quality;  /* groups laced again on the chains' own positions for an angle under 1 degree */
    size_t crossing;       /* groups whose lacing still has crossing triangles after the retries
                              (thx_surfaces_build; reported, the check then fails) */
    int max_fan;           /* largest number of triangles at one node of this slice */
} thx_lace_stats;

void thx_lace_opts_default(thx_lace_opts *o);

/* One layer's worth of a surface in a slice: a closed chain of nodes. Node ids
 * may repeat (bridges joining two loops of a branching surface). */
typedef struct thx_chain {
    size_t n;
    const thx_vec2 *p;     /* n points */
    const int32_t *id;     /* n node ids written into the triangles */
    double z;
    /* Optional: the same surface's loops on the layer beyond this one (the far
     * side from the other chain of the slice). A concave pocket of this chain
     * is cut in the plane of its layer only where the surface closes it in
     * this slice: if the layer beyond covers the pocket too (a dent of this
     * layer alone), only the slice above the layer cuts it, so no pocket is
     * cut twice. NULL / 0 when unknown or at the end of the surface. */
    const struct thx_chain *beyond;
    size_t n_beyond;
    /* Optional: the loops this chain was joined from (a branching surface), each with its
     * points and node ids; NULL / 0 when the chain is a single loop. */
    const struct thx_chain *parts;
    size_t n_parts;
} thx_chain;

/*
 * Laces chain a (lower layer) with chain b (upper layer) into triangles
 * (node ids from the chains), by the shortest-diagonal rule on the two chains
 * normalized to a common centroid and size (so layers of very different size or
 * offset do not fan), then removes triangles outside the surface (concave
 * regions), re-laces each gap optimally among valid triangles, and where no
 * valid lacing exists cuts the concave pocket off with triangles in the plane of
 * its layer. If the result still leaves triangles outside the surface or puts an
 * edge into three triangles (possible where a branching chain visits a bridge
 * node twice), or is merely poor (a triangle of aspect ratio over
 * projected_aspect, a fan over 3 fan_limit) and the alternative is better, and
 * one chain's loops lie
 * strictly inside the other's in projection, the slice is laced instead by a
 * constrained Delaunay triangulation of the ring between them in projection,
 * lifted to the layers (a graph over the ring: it cannot fold or intersect
 * itself). Both chains counterclockwise seen from above. Appends 3 ids per
 * triangle to *tris (grown with thx_grow; *n_tris, *cap updated).
 */
thx_status thx_lace(thx_ctx *ctx, const thx_chain *a, const thx_chain *b, const thx_lace_opts *o,
                    int32_t **tris, size_t *n_tris, size_t *cap, thx_lace_stats *stats);

/* ---- whole surfaces ------------------------------------------------------ */

typedef struct {
    double spacing;        /* node spacing, mm; 0 = the contour file's `spacing`, else 5 */
    double smoothing;      /* spline smoothing bandwidth, mm */
    thx_vec2 start;        /* anatomical start point (default: anterior midline, (0, 1000)) */
    int cap_method;        /* -1: per surface (contour file); else a thx_cap_method for all */
    double cap_grid;       /* grid spacing for grid caps, mm; 0 = the surface's, else the node spacing */
    thx_lace_opts lace;
} thx_surfaces_opts;

typedef struct {
    size_t n_nodes, n_tris;
    size_t n_loops, n_slices, n_branch_slices, n_caps;
    thx_lace_stats lace;             /* summed over slices */
    size_t orient_by_test;           /* triangles whose own inside test gave the final orientation */
    size_t orient_by_neighbours;     /* test undecided or overruled: oriented consistently with neighbours */
    size_t orient_overruled;         /* tests contradicted by the majority of their component */
    size_t orient_flipped;           /* triangles whose stored order the test reversed */
    size_t n_flat_flipped;           /* nearly flat triangles swapped with their neighbour (step 5) */
    size_t n_inplane_refined;        /* the lacing's in-plane patches triangulated again with grid nodes (step 3b) */
    size_t n_inplane_resolved;       /* layer planes whose overlapping in-plane triangles were made one region (step 3c) */
    double t_layers, t_lace, t_caps, t_orient, t_total; /* seconds */
} thx_surfaces_stats;

void thx_surfaces_opts_default(thx_surfaces_opts *o);

/* Builds one closed surface per contour surface. `provenance_json`, if not NULL,
 * is stored in the model. Per-surface statistics go to stats[s] when stats is
 * not NULL (array of c->n_surfaces), totals to *total when not NULL. */
thx_status thx_surfaces_build(thx_ctx *ctx, const thx_contours *c, const thx_surfaces_opts *o, thx_model **out,
                              thx_surfaces_stats *stats, thx_surfaces_stats *total);

/* Drops, to a fixed point, every loop that the lacing would find without a partner on either
 * neighbouring layer (the loops resampled as thx_surfaces_build resamples them, with o's spacing and
 * smoothing, and paired by its rule), and the layers so left empty at a surface's ends; dropped[k]
 * (may be NULL; c->n_surfaces entries) counts surface k's. For contours traced from a label map
 * (thorax/image/trace.h), whose small loops a spline may move off their neighbours; a contour file a
 * person digitized keeps its error instead. THX_EINPUT when a layer inside a surface is left empty or
 * fewer than two layers remain. */
thx_status thx_contours_drop_flat(thx_ctx *ctx, thx_contours *c, const thx_surfaces_opts *o, size_t *dropped);

/* Builds the one surface c->surf[k] as thx_surfaces_build does (the same code: a surface never
 * depends on the others, so the result is byte for byte the surface thx_surfaces_build makes from
 * the same contours), after checking that surface's loops (thx_contours_validate on it alone).
 * *out is a new surface (caller destroys), *interior a point inside it, stats (may be NULL) its
 * statistics. Used to lace one surface again after its contours changed (thorax/edit/edit.h). */
thx_status thx_surface_build(thx_ctx *ctx, const thx_contours *c, size_t k, const thx_surfaces_opts *o,
                             thx_surface **out, thx_vec3 *interior, thx_surfaces_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
