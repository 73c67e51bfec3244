/*
 * thorax/mesh/tet_locate.h — which tetrahedron of a volume mesh holds a point: a visibility walk
 * across the mesh's faces (the volume's face adjacency built once), for callers that locate many
 * points (thx_forward_dipoles: every dipole).
 *
 * The walk: at tetrahedron t, for each face (the one opposite corner k), the exact orientation
 * test (thorax/geom/predicates.h, thx_orient3d) with p in place of corner k tells whether p lies
 * strictly beyond that face; if it does for some face the walk crosses it (trying the faces from a
 * pseudo-randomly varying first one, the stochastic walk of Devillers, Pion and Teillaud, so that
 * it does not go round the same cycle of tetrahedra for ever; the face it came in by is not
 * tested again: p is strictly on this side of it), else t holds p (on its boundary included) and the walk ends there. It
 * fails — returns -1 — when the face to cross is on the mesh's boundary (p outside the mesh, or a
 * non-convex mesh whose boundary lies between the start and p: the caller then scans), when the
 * tetrahedron is flat (orientation 0), or after max(1000, 20 n_tets^(1/3)) steps. The exact tests make
 * the answer right for every p the walk reaches; it is not unique for p on a face, an edge or a
 * node shared by several tetrahedra: any of them may come out.
 *
 * The start: the caller's tetrahedron, or (start < 0) the seed of the grid cell that holds p: a
 * grid of about n_tets / 8 cells (at most 64 a side) over the mesh's bounding box, each cell's seed
 * the lowest-numbered tetrahedron whose centroid lies in it (an empty cell: tetrahedron 0).
 *
 * The locator borrows the volume (which must outlive it and not change); queries are thread-safe.
 */
#ifndef THORAX_MESH_TET_LOCATE_H
#define THORAX_MESH_TET_LOCATE_H
#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_tet_locator thx_tet_locator;

/* Builds the face adjacency (the tetrahedron across each face, -1 on the boundary; a face shared
 * by more than two tetrahedra — a broken mesh — is THX_EGEOM naming it) and the seed grid. */
thx_status thx_tet_locator_create(thx_ctx *ctx, const thx_volume *v, thx_tet_locator **out);
void thx_tet_locator_destroy(thx_tet_locator **l);

/* The walk above from start (< 0: the seed of p's cell): the tetrahedron holding p, or -1; on a
 * part (thx_tet_locator_set_part), -2 when the walk leaves the part by a face the whole has a
 * tetrahedron behind. steps (may be NULL): the tetrahedra visited. */
long thx_tet_locate(const thx_tet_locator *l, const double p[3], long start, size_t *steps);

/* The locator of a part of a volume (sort-last's streamlines): id (n_tets, borrowed) the tetrahedra's
 * numbers in the whole, which the walk's face order is drawn from, so that a part walks the whole's
 * path; edge (4 n_tets, borrowed) the faces without a neighbour in the part that have one in the
 * whole. NULL, NULL: the whole. */
void thx_tet_locator_set_part(thx_tet_locator *l, const int32_t *id, const unsigned char *edge);

/* The tetrahedron across face k (opposite corner k) of tetrahedron t, or -1 (the boundary). */
long thx_tet_neighbour(const thx_tet_locator *l, size_t t, int k);

#ifdef __cplusplus
}
#endif
#endif
