/*
 * thorax/mesh/mesh.h — tetrahedral volume meshes from a surface model (paper 3.3,
 * "Volume Segmentation").
 *
 * The paper's hybrid method, made conforming: the nodes of the surfaces, plus
 * a planar grid of points on each layer inside the outer boundary with the
 * points within a tolerance of any surface dropped, are tetrahedralized
 * (Delaunay, thorax/mesh/delaunay.h); points are then added ON the surfaces
 * (Steiner points, recorded in the volume) until every surface triangle is a
 * union of mesh faces; the surfaces cut the mesh into pieces, each piece
 * gets a tissue region by a chain of inside/outside tests (the paper's) and
 * the pieces outside the outer surface are removed, so the boundary is the
 * outer surface and every region's boundary is its surfaces, exactly;
 * slivers inside are repaired by flips and grid-node moves that keep every
 * face on a surface; conductivities come from a region table.
 */
#ifndef THORAX_MESH_H
#define THORAX_MESH_H

#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

/* The repair's smallest target, degrees: thx_mesh_build removes tetrahedra below it whatever
   repair_deg says (thorax check refuses dihedral angles below 1 degree). */
#define THX_MESH_REPAIR_FLOOR 5.0

/* the growth of the size bound away from a fold: mm of circumradius per mm of distance */
#define THX_MESH_FOLD_GRADE 0.2

typedef struct {
    double grid;          /* grid spacing in each layer plane, mm; 0 (default) = 6.5 + 0.3 (d - 5) for a
                             median gap d between the planes (5 mm layers: 6.5 mm; 10 mm layers: 8 mm) */
    double tol;           /* grid points closer than tol to a surface are dropped, mm (0 = grid / 2) */
    double layer_spacing; /* planes every layer_spacing mm; 0 = the layers of the outer surface's nodes
                             when they lie on planes (a model built from contours), else `grid` */
    int no_heart;         /* 1: the heart's interior is not part of the domain */
    double radius_edge;   /* Delaunay refinement: tetrahedra with a larger radius-edge ratio get their
                             circumcentre (default 2; 0 = off) */
    double refine_deg;    /* ... and those with a smaller dihedral angle, degrees (default 10; 0 = off) */
    double fold_deg;      /* with no_heart: the heart's edges whose interior dihedral angle is below this
                             (degrees) are folds, re-entrant edges of the domain, and the tetrahedra around
                             them are refined to a circumradius of fold_size + THX_MESH_FOLD_GRADE * (distance)
                             (default 120; 0 = off) */
    double fold_size;     /* mm at the fold (0 = grid / 14) */
    double repair_deg;    /* tetrahedra inside with a dihedral angle below this (degrees) are repaired by
                             flips, node moves and node insertion (default 15); below THX_MESH_REPAIR_FLOOR
                             (0 included) the repair still runs at that floor: the slivers the mesher
                             makes are its own to remove */
    /* region table changes: region `name` (mean_thorax, fat, muscle, lung, heart or a surface's name)
       renamed to `rename` (when not empty) and given the isotropic conductivity sigma (S/m, when > 0) */
    struct { char name[64], rename[64]; double sigma; } region_set[16];
    size_t n_region_set;
    /* conductivity assignments "NAME=SIGMA" (thx_regions_assign), applied after the renames of
       region_set, so NAME is the region's final name; strings not owned */
    const char *sigma_set[16];
    size_t n_sigma_set;
    /* progress (optional): called from the calling thread with the stage's name ("points",
       "Delaunay", "conformity", "refinement", "regions", "repair") and the share done, 0 to 1 */
    void (*progress)(void *user, const char *stage, double done);
    void *progress_user;
} thx_mesh_opts;

typedef struct {
    size_t n_surface_nodes, n_grid_nodes, n_planes;
    double grid;              /* the grid spacing used, mm */
    size_t n_delaunay_tets;   /* tetrahedra of the convex hull (after the Steiner points) */
    size_t n_surface_tris;    /* surface triangles */
    size_t n_missing_before;  /* of those, not faces of the first Delaunay tetrahedralization */
    size_t n_steiner_edge, n_steiner_face; /* Steiner points added on surface edges / inside triangles */
    size_t n_steiner;         /* Steiner nodes in the result */
    size_t n_split_triangles; /* surface triangles that are more than one mesh face */
    size_t conform_rounds;
    double min_piece;         /* shortest piece of a surface edge, mm */
    double t_conform;         /* seconds */
    size_t n_refine_points;   /* quality refinement: circumcentres inserted */
    size_t n_refine_surface;  /* ... points put on the surfaces instead */
    size_t n_refine_near;     /* ... of the circumcentres, those put close to a small surface piece */
    size_t n_refine_left;     /* bad tetrahedra left at small surface pieces */
    size_t refine_rounds;
    int refine_limited;       /* stopped at its point limit */
    double t_refine;
    size_t n_folds;           /* the heart's fold edges refined around (no_heart) */
    double fold_size;         /* the circumradius bound at them, mm */
    size_t n_pieces;          /* pieces of space between the surfaces (flood fill) */
    size_t n_centroid_tested;   /* tetrahedra whose centroid was classified (about 512 per piece) */
    size_t n_centroid_disagree; /* of those, disagreeing with their piece's majority */
    size_t n_outside;         /* removed: outside the outer surface */
    size_t n_heart;           /* removed: inside the heart (no_heart) */
    size_t repair_below_before, repair_below_after; /* tetrahedra below repair_deg before/after the repair */
    double repair_min_before, repair_min_after;     /* smallest dihedral angle before/after, degrees */
    size_t n_edge_removals, n_face_removals, n_moves, n_slides, n_collapses; /* repair operations applied */
    size_t n_inserts;         /* repair: free nodes inserted (slivers between surface faces, pockets) */
    size_t n_pockets, n_pocket_nodes; /* surface nodes with only their own surface's nodes around them;
                                         of those, given a free node beside them */
    double t_repair;          /* seconds */
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
 * the default region table (thx_region_default; anisotropic defaults along the
 * model's superior axis, z without a frame), then o->region_set and
 * o->sigma_set applied, and the node tables.
 */
thx_status thx_mesh_build(thx_ctx *ctx, thx_model *m, const thx_mesh_opts *o, thx_mesh_stats *stats);

/* Fills r with the default conductivity of a tissue region by name
 * ("mean_thorax", "fat", "muscle", "lung", "heart", "blood"), with its
 * literature source (docs/decisions.md, "Default conductivities"). An
 * anisotropic one (muscle) is diagonal with its "along" value on z
 * (sigma[8]); thx_mesh_build puts it on the model's superior axis. Returns 0,
 * or -1 for an unknown name. */
int thx_region_default(const char *tissue, thx_region *r);
/* Turns the defaults' body axis to the model's: every region of table[0..n-1] whose tensor is
 * diagonal with sxx = syy != szz (a default's "along z") gets szz on frame's superior axis and sxx
 * on the other two. Nothing changes without a frame or when the superior axis is z. */
void thx_regions_orient(thx_region *table, size_t n, const thx_frame *frame);

/*
 * Parses a conductivity in S/m, in the model's axes (x, y, z of its coordinates, whatever its
 * anatomical frame): "S" (isotropic), "SXX,SYY,SZZ" (a diagonal tensor) or
 * "SXX,SYY,SZZ,SXY,SXZ,SYZ" (a symmetric tensor). Refused (THX_EINPUT, the message quoting the
 * text): another count, a value that is not a finite number, a diagonal entry that is not
 * positive, a tensor that is not positive definite, a value outside the bounds below. sigma
 * gets the 3x3 row-major tensor; *anisotropic is 0 when it is a multiple of the identity.
 */
thx_status thx_sigma_parse(thx_ctx *ctx, const char *text, double sigma[9], int *anisotropic);
/*
 * The conductivities thorax accepts, S/m: each diagonal entry in [THX_SIGMA_MIN, THX_SIGMA_MAX],
 * each entry at most THX_SIGMA_MAX in magnitude (1e-12: far below any tissue's, or glass's 1e-11;
 * 1e12: far above copper's 6e7). Beyond them the solvers' checks (the minors of the tensor, the
 * stiffness matrix) underflow or overflow: 1e-320 and 1e308 were accepted by thorax sigma, then
 * refused by thorax forward (issue 24). thx_sigma_in_range: 1 when sigma is within them, else 0
 * and why ("the diagonal entry 1e-320 is below 1e-12 S/m").
 */
#define THX_SIGMA_MIN 1e-12
#define THX_SIGMA_MAX 1e12
int thx_sigma_in_range(const double sigma[9], char *why, size_t size);
/*
 * Applies one assignment "NAME=SIGMA" (SIGMA as thx_sigma_parse reads it) to the region table
 * table[0..n-1]: region NAME gets the conductivity and `source` as its source (NULL: "set by the
 * user"). An unknown name is refused with the table's names and the nearest one ("did you
 * mean"); the table is unchanged on any error.
 */
thx_status thx_regions_assign(thx_ctx *ctx, thx_region *table, size_t n, const char *assignment, const char *source);

#ifdef __cplusplus
}
#endif
#endif
