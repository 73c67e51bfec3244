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
 *   - edge collapse: an interior grid or refinement node of a sliver is
 *     removed by collapsing it onto a neighbour (the tetrahedra around the edge
 *     vanish, the rest of its star takes the neighbour), when that fills the
 *     star exactly and betters its worst tetrahedron; the node is then unused;
 *   - vertex perturbation: an interior grid node (never a surface node) of a
 *     sliver is moved, within its star, to where the worst tetrahedron of the
 *     star is best (pattern search, positions rounded to the stored
 *     precision, orientations tested exactly);
 *   - Steiner node sliding: a Steiner node of a sliver moves within its
 *     surface triangle (along its edge for a node on an edge), on the
 *     mesher's dyadic grid of barycentric coordinates, so that it stays
 *     exactly in the triangle's plane; its record follows.
 * An operation is applied only if the worst tetrahedron it touches becomes
 * better. The faces on the surfaces and their edges are never removed, so
 * the tissue interfaces stay exactly where they are. Quality is the smallest sine of the six dihedral
 * angles (flat tetrahedra have angles near 0 and near 180 degrees), or, for
 * a needle whose radius-edge ratio RE exceeds the bound B (radius_edge),
 * sin(target) * B / RE where that is smaller: a needle just above the bound
 * counts as a sliver of the target angle.
 */
#ifndef THORAX_MESH_IMPROVE_H
#define THORAX_MESH_IMPROVE_H

#include "thorax/model/volume.h"
enum { IMPROVE_EDGE = 1, IMPROVE_FACE = 2, IMPROVE_MOVE = 4, IMPROVE_COLLAPSE = 8, IMPROVE_SLIDE = 16, IMPROVE_INSERT = 32 };

typedef struct {
    double target_deg; /* repair tetrahedra whose smallest dihedral angle is below this */
    double radius_edge; /* ... or whose radius-edge ratio is above this (0: dihedral angles only) */
    int max_passes;    /* sweeps over the tetrahedra below target (each stops early when nothing improves) */
    unsigned ops;      /* IMPROVE_EDGE | IMPROVE_FACE | IMPROVE_MOVE | IMPROVE_SLIDE | IMPROVE_COLLAPSE; 0 = all */
    /* region of a new tetrahedron whose cavity mixed regions, from its centroid; NULL: the region
       of the old tetrahedron containing most of the cavity's volume */
    int (*classify)(void *user, thx_vec3 centroid);
    void *user;
    /* NULL, or 3 volume nodes per Steiner record of v (its surface triangle's corners, in the
       order of its barycentric coordinates): those Steiner nodes may slide in their triangle */
    const int32_t *steiner_corners;
    /* the surface whose nodes the pocket pass looks after (its potentials given: the heart's);
       -1: every surface (the default of a zeroed struct is surface 0) */
    int pocket_surface;
} improve_opts;

typedef struct {
    size_t below_before, below_after; /* tetrahedra below target_deg */
    double min_before, min_after;     /* smallest dihedral angle in the mesh, degrees */
    size_t n_edge_removals, n_face_removals, n_moves, n_slides, n_collapses, n_inserts;
    size_t n_pockets, n_pocket_nodes; /* surface nodes with only their own surface's nodes around; given a free node */
    size_t tets_before, tets_after;
    double seconds;
} improve_stats;

/* The repair's quality of tetrahedron (p0, p1, p2, p3) (right-handed): the smallest sine of its
 * dihedral angles; for a radius-edge ratio RE above re_bound (> 0), re_scale / RE where that is
 * smaller; 0 when flat or inverted. The repair uses re_scale = sin(target) * re_bound. */
double mesh_tet_quality(const double *p[4], double re_bound, double re_scale);

/* Smallest dihedral angle of the tetrahedron q (node indices into xyz), degrees; either orientation. */
double mesh_tet_min_dihedral(const double *xyz, const int32_t *q);

/* Repairs v in place (tetrahedra, regions; grid node coordinates; Steiner
 * nodes and their records, within their triangles, when o->steiner_corners
 * is given). Nodes with v->node_surf[i] >= 0 never move; the
 * faces prot (n_prot node triples: the surfaces' pieces) and their edges stay.
 * nbr: NULL, or the face adjacency of v's tetrahedra (nbr[4t + f] across the
 * face opposite corner f, -1 on the boundary; malloc'ed), which the call takes
 * over and frees: it spares the search for it. On failure v is left without
 * tetrahedra. */
thx_status mesh_improve(thx_ctx *ctx, thx_volume *v, int32_t *nbr, const int32_t *prot, size_t n_prot,
                        const improve_opts *o, improve_stats *stats);

#endif
