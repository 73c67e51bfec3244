/*
 * Sliver repair inside the domain (internal to src/mesh).
 *
 * A flat tetrahedron (sliver) inside the domain cannot be deleted without
 * leaving a void; it is repaired instead by local changes that leave the
 * union of the tetrahedra, and therefore the domain and its boundary, exactly
 * as they were:
 *   - edge removal: the n tetrahedra around an interior edge are replaced by
 *     the 2(n - 2) tetrahedra of the best triangulation of the ring of n
 *     vertices around it (n = 3 is the 3-2 flip, n = 4 the 4-4 flip), the
 *     triangulation chosen by dynamic programming to maximize the worst
 *     tetrahedron;
 *   - face removal: two tetrahedra sharing a face become three around the
 *     edge joining their apexes (2-3 flip);
 *   - vertex perturbation: an interior grid node (never a surface node) of a
 *     sliver is moved, within its star, to where the worst tetrahedron of the
 *     star is best (pattern search, positions rounded to the stored
 *     precision, orientations tested exactly).
 * An operation is applied only if the worst tetrahedron it touches becomes
 * better. Surface triangles that are faces of the mesh and surface edges
 * that are edges of it are never removed, so tissue interfaces the mesh
 * already follows stay. Quality is the smallest sine of the six dihedral
 * angles (flat tetrahedra have angles near 0 and near 180 degrees).
 */
#ifndef THORAX_MESH_IMPROVE_H
#define THORAX_MESH_IMPROVE_H

#include "thorax/volume.h"

enum { IMPROVE_EDGE = 1, IMPROVE_FACE = 2, IMPROVE_MOVE = 4 };

typedef struct {
    double target_deg; /* repair tetrahedra whose smallest dihedral angle is below this */
    int max_passes;    /* sweeps over the tetrahedra below target (each stops early when nothing improves) */
    unsigned ops;      /* IMPROVE_EDGE | IMPROVE_FACE | IMPROVE_MOVE; 0 = all of them */
    /* region of a new tetrahedron whose cavity mixed regions, from its centroid; NULL: the region
       of the old tetrahedron containing most of the cavity's volume */
    int (*classify)(void *user, thx_vec3 centroid);
    void *user;
} improve_opts;

typedef struct {
    size_t below_before, below_after; /* tetrahedra below target_deg */
    double min_before, min_after;     /* smallest dihedral angle in the mesh, degrees */
    size_t n_edge_removals, n_face_removals, n_moves;
    size_t tets_before, tets_after;
    double seconds;
} improve_stats;

/* Smallest dihedral angle of the tetrahedron q (node indices into xyz), degrees; either orientation. */
double mesh_tet_min_dihedral(const double *xyz, const int32_t *q);

/* Repairs v in place (tetrahedra, regions; grid node coordinates). Nodes with
 * v->node_surf[i] >= 0 never move; surface triangles and edges of the model
 * (via v->surf_node and the model's surfaces) stay. nbr: NULL, or the face
 * adjacency of v's tetrahedra (nbr[4t + f] across the face opposite corner f,
 * -1 on the boundary; malloc'ed), which the call takes over and frees: it
 * spares the search for it. On failure v is left without tetrahedra. */
thx_status mesh_improve(thx_ctx *ctx, thx_volume *v, int32_t *nbr, const thx_surface *const *surf, size_t n_surf,
                        const improve_opts *o, improve_stats *stats);

/* The surfaces' triangles (surface s's node i is node offset[s] + i) as a set of node triples. */
typedef struct mesh_triset mesh_triset;
thx_status mesh_triset_build(thx_ctx *ctx, const thx_surface *const *surf, const size_t *offset, size_t n_surf,
                             mesh_triset **out);
int mesh_triset_has(const mesh_triset *T, int32_t a, int32_t b, int32_t c);
void mesh_triset_free(mesh_triset **T);

/*
 * Recovery of the surfaces' triangles as faces of a tetrahedralization
 * (before the outside is removed): for every surface triangle that is not a
 * face, each missing edge is made an edge by one 2-3 flip (the segment crosses
 * one face) or by one edge removal whose ring triangulation is forced to hold
 * the edge as a chord (the segment passes by one edge: the other diagonal of a
 * lacing quadrilateral, the usual case). Surface triangles and edges already
 * present are never removed; new tetrahedra are positively oriented (exact)
 * and no worse than the cavity's worst or a floor (sine of 5 degrees). Edges
 * that need more than one operation are then walked from either end: the
 * face the segment leaves the end's star through goes by a 2-3 flip, or, when
 * that flip would invert a tetrahedron, the face's blocking edge by an edge
 * removal, or, when it would be too flat, the best of the face's edges (each
 * step at least the floor, at most 8 steps). A triangle whose three edges are
 * there but which edges pierce is made a face by removing those edges, each
 * ring triangulated holding the chords between the triangle's corners on it
 * (one piercing edge with ring a, b, c: the 3-2 flip). What still fails stays
 * missing (counted; missing_face_only: all three edges there, the face not). On the
 * convex hull (where the outer surface touches it) a hull edge that is the
 * other diagonal of a surface quadrilateral is removed with the open ring of
 * tetrahedra around it, so the hull gives up the thin wedge between the two
 * diagonals, which lies outside the surface.
 * tets/nbrs: right-handed tetrahedra and their adjacency (face f opposite
 * corner f), taken over and replaced; surface s's node i is node offset[s] + i.
 */
typedef struct {
    size_t n_triangles, missing_before, missing_after;
    size_t missing_face_only; /* of missing_after: all three edges are mesh edges, the face is not */
    size_t n_flip23, n_edge_removals;
    size_t n_walk; /* flips and edge removals of the walks along edges that needed several */
    size_t n_face_ops; /* edge removals that cleared edges piercing a triangle whose edges were there */
    size_t missing_before_walk; /* missing after the single-operation passes, before the walks */
    size_t n_boundary; /* convex-hull edges swapped for surface edges (the hull shrinks to the surface) */
    double seconds;
} recover_stats;

thx_status mesh_recover(thx_ctx *ctx, double *xyz, size_t nn, int32_t **tets, int32_t **nbrs, size_t *nt,
                        const thx_surface *const *surf, const size_t *offset, size_t n_surf, recover_stats *stats);

#endif
