/*
 * thorax/mesh.h — tetrahedral volume meshes from a surface model (paper 3.3,
 * "Volume Segmentation").
 *
 * The paper's hybrid method: the nodes of the surfaces, plus a planar grid of
 * points on each layer inside the outer boundary with the points within a
 * tolerance of any surface dropped, are tetrahedralized (Delaunay,
 * thorax/delaunay.h); tetrahedra any part of which lies outside the domain
 * (tested at edge midpoints and centroids, as the paper does) are removed;
 * every tetrahedron gets a tissue region by a chain of inside/outside tests
 * against the surfaces; conductivities come from a region table.
 */
#ifndef THORAX_MESH_H
#define THORAX_MESH_H

#include "thorax/model.h"
#include "thorax/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double grid;          /* grid spacing in each layer plane, mm; 0 (default) = 6.5 + 0.3 (d - 5) for a
                             median gap d between the planes (5 mm layers: 6.5 mm; 10 mm layers: 8 mm) */
    double tol;           /* grid points closer than tol to a surface are dropped, mm (0 = grid / 2) */
    double layer_spacing; /* planes every layer_spacing mm; 0 = the layers of the outer surface's nodes
                             when they lie on planes (a model built from contours), else `grid` */
    int no_heart;         /* 1: the heart's interior is not part of the domain */
    double sliver_deg;    /* tetrahedra on the boundary with a dihedral angle below this (degrees) are
                             peeled off (default 5; 0 = keep them) */
    double repair_deg;    /* tetrahedra inside with a dihedral angle below this (degrees) are repaired by
                             flips and by moving grid nodes (default 15; 0 = no repair) */
    int recover;          /* 1 (default): make the surfaces' triangles faces of the tetrahedralization by
                             flips before the outside is removed, so the boundary and the tissue
                             interfaces follow the surfaces' own triangles */
} thx_mesh_opts;

typedef struct {
    size_t n_surface_nodes, n_grid_nodes, n_planes;
    double grid;              /* the grid spacing used, mm */
    size_t n_delaunay_tets;   /* tetrahedra of the convex hull */
    size_t n_outside;         /* removed: part of them outside the outer surface */
    size_t n_heart;           /* removed: inside the heart (no_heart) */
    size_t n_slivers_peeled;  /* flat tetrahedra removed from the boundary */
    size_t n_readded;         /* put back by the boundary repair (centroid inside) */
    size_t n_taken;           /* taken away by the boundary repair (where nothing could be put back) */
    size_t n_pinches;         /* pinched boundary edges and unused surface nodes left after the repair */
    size_t repair_below_before, repair_below_after; /* tetrahedra below repair_deg before/after the repair */
    double repair_min_before, repair_min_after;     /* smallest dihedral angle before/after, degrees */
    size_t n_edge_removals, n_face_removals, n_moves; /* repair operations applied */
    double t_repair;          /* seconds */
    size_t n_surface_tris, n_missing_before, n_missing_after; /* surface triangles not faces of the
                                                                 tetrahedralization, before/after recovery */
    size_t n_missing_face_only; /* of those left: all three edges are mesh edges, the face is not */
    size_t n_recover_flips;   /* flips and edge removals that recovered them */
    double t_recover;         /* seconds */
    size_t n_tets, n_nodes;   /* the result */
    size_t per_region[16];    /* tetrahedra per region (the region table's order) */
    double t_points, t_delaunay, t_classify, t_total; /* seconds */
} thx_mesh_stats;

void thx_mesh_opts_default(thx_mesh_opts *o);

/*
 * Meshes the model's domain: inside its surface of role "outer" (exactly one
 * is required), minus the heart's interior when o->no_heart. Nodes: every
 * surface node (volume node numbers follow the model's surface order), then
 * the grid points. The result is stored in m->volume (replacing any), with
 * the default region table (thx_region_defaults) and the node tables.
 */
thx_status thx_mesh_build(thx_ctx *ctx, thx_model *m, const thx_mesh_opts *o, thx_mesh_stats *stats);

/* Fills r with the default conductivity of a tissue region by name
 * ("mean_thorax", "fat", "muscle", "lung", "heart", "blood"), with its
 * literature source. Returns 0, or -1 for an unknown name. */
int thx_region_default(const char *tissue, thx_region *r);

#ifdef __cplusplus
}
#endif
#endif
