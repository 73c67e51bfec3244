/*
 * Conforming Delaunay tetrahedralization of the model's surfaces (internal to
 * src/mesh; docs/decisions.md, "Conformity by Steiner points").
 *
 * Given the Delaunay tetrahedralization of the surface nodes and the grid
 * points (thx_dt), points are added ON the surfaces until every surface
 * triangle is exactly a union of faces of the tetrahedralization, which stays
 * Delaunay throughout (Bowyer-Watson insertion):
 *   - a piece of a surface edge (between consecutive points on it) that is not
 *     an edge of the mesh is split at its midpoint;
 *   - a triangle whose pieces of edges are all mesh edges but that is not
 *     covered by mesh faces gets the circumcentre of its largest missing
 *     piece (the pieces: the 2D Delaunay triangulation of the points on it),
 *     unless that centre lies outside the triangle or inside the diametral
 *     circle of a piece of its edges, which is then split instead (Ruppert's
 *     rule, as in Shewchuk's Delaunay refinement).
 * A piece of a triangle is "covered" when the mesh faces whose three corners
 * are points of the triangle add up to its area (faces of one mesh do not
 * overlap, so that is the whole triangle).
 *
 * Every added point is recorded (which surface, which triangle, barycentric
 * coordinates in it); every original surface node stays a node.
 */
#ifndef THORAX_MESH_CONFORM_H
#define THORAX_MESH_CONFORM_H

#include "thorax/mesh/delaunay.h"
#include "thorax/model/volume.h"
/* A face of the mesh on a surface triangle, oriented like the triangle (counterclockwise seen from
 * outside the surface). */
typedef struct {
    int32_t v[3];
    int32_t surf, tri;
} mesh_subface;

typedef struct {
    size_t n_triangles;      /* surface triangles */
    size_t missing_before;   /* not faces of the first tetrahedralization */
    size_t n_edge_points;    /* Steiner points added on surface edges */
    size_t n_face_points;    /* Steiner points added inside surface triangles */
    size_t n_split_triangles;/* surface triangles made of more than one mesh face */
    size_t rounds;
    double min_piece;        /* shortest piece of a surface edge, mm */
    size_t n_refine_points;  /* circumcentres inserted by the quality refinement */
    size_t n_refine_surface; /* points put on the surfaces instead (pieces split) */
    size_t refine_rounds;
    int refine_limited;      /* the refinement stopped at its point limit */
    size_t n_refine_skipped; /* bad tetrahedra left because their surface piece was already small */
    size_t n_refine_near;    /* centres inserted close to such a piece (no piece removed) */
    double t_refine;
    size_t n_fold_points;    /* of n_face_points: points at small corners on sharp folds (conform.c) */
    double seconds;
} conform_stats;

/* Quality refinement after conformity (Delaunay refinement): tetrahedra of
 * the domain (inside(user, centroid) != 0) with a radius-edge ratio above
 * radius_edge or a dihedral angle below min_dihedral (degrees; 0: that test
 * off) get their circumcentre, unless it would remove a piece of a surface
 * or encroach upon one, which is split instead; where that piece is already
 * below min_piece_ratio of its triangle, the centre is inserted if it removes
 * no piece, else the tetrahedron stays; at most max_points points (0: twice
 * as many as the tetrahedralization had). */
typedef struct {
    double radius_edge, min_dihedral;
    int (*inside)(void *user, const double p[3]);
    void *user;
    size_t max_points;
    double min_piece_ratio; /* pieces of a surface triangle shorter than this times its shortest edge
                               are not split for quality (the mesher: 0.12) */
    void (*progress)(void *user, const char *stage, double done); /* optional */
    void *progress_user;
    /* optional size bound: a tetrahedron of the domain whose circumradius exceeds size(user, its
       centroid) is refined like a badly shaped one (NULL: none; INFINITY: no bound there) */
    double (*size)(void *user, const double p[3]);
} conform_quality;

/*
 * dt: the tetrahedralization; points 0 .. offset[n_surf] - 1 are the surface
 * nodes (surface s's node i is point offset[s] + i). Every coordinate in dt
 * is a multiple of unit (a power of two, at least 2^-30 of the largest
 * coordinate): points added on a surface edge are dyadic fractions of it
 * and points added inside a triangle have dyadic barycentric coordinates,
 * so that they are EXACTLY on the edge / in the triangle's plane (tested
 * with the exact orientation predicate); coplanar points then never make
 * flat tetrahedra (thorax/mesh/delaunay.h). max_steiner: refuse to add more
 * (0: 20 per surface triangle). quality: NULL, or the refinement above.
 * Out: *steiner (n_steiner records, node = index in dt), *sub (n_sub faces on
 * the surfaces, each triangle's pieces), both malloc'ed.
 * Errors: THX_EGEOM naming the surface and triangle where the pieces became
 * shorter than 1e-4 mm or max_steiner was reached (surfaces touching or
 * crossing there); THX_ENOMEM.
 */
thx_status mesh_conform(thx_ctx *ctx, thx_dt *dt, const thx_surface *const *surf, const size_t *offset, size_t n_surf,
                        double unit, size_t max_steiner, const conform_quality *quality, thx_steiner **steiner, size_t *n_steiner, mesh_subface **sub, size_t *n_sub,
                        conform_stats *stats);

#endif
