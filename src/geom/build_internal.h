/*
 * What src/geom/build.c (surfaces from contours, steps 1-3 and the driver) and src/geom/build_orient.c
 * (steps 4 and 5: orientation and flat triangles, and the checks of a slice's triangles) share: the
 * layers of loops and the laced slices, and the functions build.c calls in build_orient.c.
 */
#ifndef THORAX_GEOM_BUILD_INTERNAL_H
#define THORAX_GEOM_BUILD_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/geom/surfaces.h"
#include "geom/chain_sdf.h"

typedef struct {
    size_t n;
    thx_vec2 *p;
    int32_t first; /* node id of p[0]; nodes are consecutive */
    int32_t *id;   /* first, first + 1, ... (for chains) */
    int down, up;  /* has a partner loop on the layer below / above */
    int hole;      /* 1: inside an odd number of the layer's other loops (a hole of the surface's section,
                      laced to holes only, as the solid it bounds; mark_holes) */
} rloop;

typedef struct {
    double z;
    size_t n_loops;
    rloop *loops;
    thx_chain *ch; /* the loops as chains (for the pocket rule of lacing) */
    thx_chain *kind_ch[2]; /* the same, outer loops [0] and holes [1] apart (the beyond chains of a group) */
    size_t n_kind[2];
} rlayer;

/* A chain owned by a slice (merged loops). */
typedef struct {
    int hole;         /* its loops are holes (rloop.hole) */
    thx_chain c;
    thx_vec2 *p;
    int32_t *id;
    chain_index ix;
    thx_chain *parts; /* the loops joined into c (branching), or NULL */
    int *sel;         /* indices of those loops in their layer */
    int n_sel;
} owned_chain;

typedef struct {
    size_t n_groups;
    owned_chain *ga, *gb; /* per group: chain on the lower and upper layer */
    int32_t *tris;
    size_t n_tris, cap;
    thx_lace_stats st;
    int branch;
    thx_lace_nodes nodes; /* the nodes its lacings added (filled pockets' chords; ids from nodes.base) */
} slice;

/* Do two of the nt triangles tri (node ids into xyz) intersect beyond the nodes they share? A sweep
 * over the triangles' x extents, exact test per candidate pair (thx_triangles_intersect); degenerate
 * (collinear) triangles are skipped. -1 out of memory. */
int build_tris_cross(const double *xyz, const int32_t *tri, size_t nt);
/* Is an edge of the nt triangles used by more than two of them? -1 out of memory. */
int build_edge_overused(const int32_t *tri, size_t nt);
/* Mends the edges used by three or more of a slice's triangles by flipping them (build_orient.c
 * says when it can): 1 when every such edge is mended, 0 when one cannot be, -1 out of memory. */
int build_mend_overused(const double *xyz, int32_t *tri, size_t nt);
/* Step 4: every triangle of s stored counterclockwise seen from outside (paper 3.2), by the layers'
 * and slices' inside test; the overruled votes into stats. */
thx_status build_orient(thx_ctx *ctx, thx_surface *s, const rlayer *layers, size_t nl, const slice *slices,
                        double spacing, size_t no_test_from, thx_surfaces_stats *stats);
/* The smallest corner (degrees) of the triangle p q r. */
double build_min_corner(const double *p, const double *q, const double *r);
/* Step 5: nearly flat triangles swapped with their neighbour where that betters both. */
thx_status build_flip_flat(thx_ctx *ctx, thx_surface *s, size_t *n_flipped);

#endif
