/*
 * thorax/mesh/delaunay.h — 3D Delaunay tetrahedralization (paper 3.3, "the volume
 * mesh": the tetrahedra are built from the nodes of the layered surfaces and
 * the interior grid points).
 *
 * Method (details in src/mesh/delaunay3d.c and docs/decisions.md, "3D Delaunay
 * tetrahedralization"): incremental Bowyer–Watson insertion in BRIO order
 * (random rounds, Hilbert curve order inside each round), point location by a
 * remembering stochastic visibility walk, exact adaptive predicates
 * (thorax/geom/predicates.h), the exterior covered by "ghost" tetrahedra sharing a
 * vertex at infinity. Cospherical input (grids: the normal case for thorax) is
 * resolved by a symbolic perturbation of the paraboloid lifting, so the result
 * is always a true Delaunay tetrahedralization (no point strictly inside the
 * circumsphere of any tetrahedron) and each input gives one well-defined
 * answer among the Delaunay tetrahedralizations that exist when points are
 * cospherical.
 *
 * Conventions:
 *  - Indices are 0-based into the input points.
 *  - Every output tetrahedron (p0, p1, p2, p3) is positively oriented in the
 *    sense of thx_orient3d: thx_orient3d(p0, p1, p2, p3) > 0, i.e. p3 lies
 *    below the plane of p0, p1, p2 seen counterclockwise from above. Since
 *    thx_orient3d(a,b,c,d) = det[a-d; b-d; c-d] = -((b-a) x (c-a)) . (d-a),
 *    this means ((p1-p0) x (p2-p0)) . (p3-p0) < 0, and the volume is
 *    thx_orient3d(p0,p1,p2,p3) / 6.
 *  - Face i of a tetrahedron is the face opposite vertex i. Its vertices,
 *    ordered so that they appear counterclockwise seen from OUTSIDE the
 *    tetrahedron (outward normal (b-a) x (c-a)), are
 *        face 0: (p1, p3, p2)   face 1: (p0, p2, p3)
 *        face 2: (p0, p3, p1)   face 3: (p0, p1, p2)
 *    (thx_delaunay_face below). Hull faces taken this way are
 *    counterclockwise seen from outside the hull, the thx_surface convention.
 *  - Output is deterministic: the same points give the same tetrahedra, in the
 *    same order, with the same vertex order (the code is sequential).
 */
#ifndef THORAX_DELAUNAY_H
#define THORAX_DELAUNAY_H

#include "thorax/core/core.h"
#ifdef __cplusplus
extern "C" {
#endif

/* Local vertex indices of face f (opposite vertex f), counterclockwise seen
 * from outside the tetrahedron. */
static const int thx_delaunay_face[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};

/* Figures of one run (all optional reading; pass NULL to thx_delaunay3d to skip). */
typedef struct {
    size_t n_points;      /* input points, all of them vertices of the output */
    size_t n_tets;        /* output tetrahedra */
    size_t n_hull_faces;  /* boundary triangles of the convex hull */
    size_t walk_steps;    /* tetrahedra visited by point location, in total */
    size_t cavity_tets;   /* tetrahedra deleted by insertions, in total (ghosts included) */
    size_t n_degenerate;  /* in-sphere tests that were exactly 0 and were decided by the perturbation */
    double t_sort;        /* seconds: BRIO / Hilbert ordering */
    double t_insert;      /* seconds: incremental insertion */
    double t_output;      /* seconds: compaction of the output arrays */
} thx_delaunay_stats;

/*
 * Delaunay tetrahedralization of the convex hull of n points.
 *
 * xyz: 3n doubles (x, y, z of point i at xyz[3i..3i+2]), mm, finite.
 * On success:
 *   *tets    4 * *n_tets vertex indices, every tetrahedron positively oriented
 *            (thx_orient3d(p0,p1,p2,p3) > 0). Owned by the caller (free()).
 *   *nbrs    (if nbrs != NULL) 4 * *n_tets entries: nbrs[4t + i] is the
 *            tetrahedron across face i (the face opposite vertex i) of
 *            tetrahedron t, or -1 on the convex hull. Symmetric. Owned by the
 *            caller (free()).
 *   *stats   (if stats != NULL) figures of the run.
 * Every input point is a vertex of the output (no point is dropped, points on
 * the hull between hull corners included). Tetrahedra are positive-volume for
 * the coordinates GIVEN (exact arithmetic on the doubles). Points meant to be
 * coplanar but computed inexactly (a 3.9 mm grid: (i + 0.5) * 3.9 in double)
 * are not coplanar, and the result may hold slivers with orient3d ~ 1e-13
 * that turn flat or inverted if the coordinates are rounded afterwards (e.g.
 * written "%.6f"): round the points to their stored precision BEFORE the call;
 * exact degeneracies are then resolved by the perturbation below.
 * Among cospherical points the tetrahedralization chosen is the one of a
 * symbolic perturbation that lifts point i by eps^(n - i) (the largest index
 * perturbed most): deterministic and independent of the insertion order.
 *
 * Errors (message in ctx; *tets = NULL, *nbrs = NULL, *n_tets = 0):
 *   THX_EINPUT  a non-finite coordinate; n > 2^26 points, or more than 2^29
 *               tetrahedra needed (neighbour codes are 32-bit).
 *   THX_EGEOM   two points coincide ("points 12 and 4711 coincide (x, y, z)");
 *               fewer than 4 points, or all points collinear or coplanar
 *               (no tetrahedron exists).
 *   THX_ENOMEM
 *   THX_EINTERNAL  an invariant was broken (a bug: please report).
 * Cost: O(n log n) expected time. Working memory: 32 bytes per tetrahedron
 * slot (vertices, neighbours; about 7 slots per point) and about 46 bytes
 * per point; the vertex output is written over the slots, the neighbour
 * output (if asked for) takes 16 bytes per tetrahedron more.
 */
thx_status thx_delaunay3d(thx_ctx *ctx, const double *xyz, size_t n, int32_t **tets, int32_t **nbrs,
                          size_t *n_tets, thx_delaunay_stats *stats);

/*
 * Incremental use: the tetrahedralization kept as a structure that takes
 * more points (Bowyer-Watson, same predicates and perturbation) and answers
 * adjacency queries; what the conforming mesher (src/mesh/conform.c) needs to
 * add Steiner points on the surfaces while the mesh stays Delaunay.
 *
 * thx_dt_create   as thx_delaunay3d (same errors), keeping the structure.
 * thx_dt_insert   adds point p (3 doubles) with the next index
 *                 (thx_dt_n_points before the call); near: an existing point
 *                 close to p where the search starts (-1: the last insertion).
 *                 A point equal to an existing one is THX_EGEOM and leaves
 *                 the structure unchanged. The perturbation ranks it by its
 *                 index like the others (largest perturbed most), so the
 *                 result is the Delaunay tetrahedralization of all points.
 * thx_dt_star     the tetrahedra around point a as vertex quads (input
 *                 indices; -1 is the vertex at infinity: hull faces), valid
 *                 until the next call; returns their count (-1: no memory).
 * thx_dt_has_edge / thx_dt_has_face   1 if (a, b) / (a, b, c) is an edge /
 *                 face of the tetrahedralization.
 * thx_dt_finish   the output of thx_delaunay3d (same conventions) for all
 *                 points; destroys the structure (*d = NULL) in every case.
 */
typedef struct thx_dt thx_dt;
thx_status thx_dt_create(thx_ctx *ctx, const double *xyz, size_t n, thx_dt **out);
thx_status thx_dt_insert(thx_dt *d, const double p[3], int32_t near, int32_t *index);
size_t thx_dt_n_points(const thx_dt *d);
const double *thx_dt_point(const thx_dt *d, int32_t i);
int thx_dt_star(thx_dt *d, int32_t a, const int32_t (**quads)[4]);
int thx_dt_has_edge(thx_dt *d, int32_t a, int32_t b);
int thx_dt_has_face(thx_dt *d, int32_t a, int32_t b, int32_t c);
/* As thx_dt_insert, but reject(user, a, b, c, interior) is asked about every
 * face that the insertion would remove (interior = 1: a face between two
 * tetrahedra of the cavity), then about every face of the cavity's boundary
 * (interior = 0: kept, joined to the new point); the first face it answers
 * nonzero for stops the insertion: *index = -1, face[] = that face, the
 * structure unchanged. reject must not call thx_dt_* functions on d (the
 * structure is in the middle of an insertion while it is asked). */
thx_status thx_dt_insert_checked(thx_dt *d, const double p[3], int32_t near,
                                 int (*reject)(void *user, int32_t a, int32_t b, int32_t c, int interior), void *user,
                                 int32_t *index, int32_t face[3]);
/* The solid tetrahedra now (4 input indices each, orientation of thx_delaunay3d), malloc'ed. */
thx_status thx_dt_tets(thx_dt *d, int32_t **quads, size_t *n);
/* The tetrahedra the last successful insertion made (vertex quads as thx_dt_star,
 * the new point last; -1 the vertex at infinity), valid until the next call
 * that takes the structure; their vertices are all the vertices whose star
 * changed. Returns the count, -1 on no memory. */
int thx_dt_new_tets(thx_dt *d, const int32_t (**quads)[4]);
/* 1 if the four points are a tetrahedron of the tetrahedralization. */
int thx_dt_has_tet(thx_dt *d, const int32_t q[4]);
thx_status thx_dt_finish(thx_dt **d, int32_t **tets, int32_t **nbrs, size_t *n_tets);
void thx_dt_destroy(thx_dt **d);

#ifdef __cplusplus
}
#endif
#endif
