/*
 * thorax/check_volume.h — invariant checks of a tetrahedral volume mesh
 * (paper 3.3, "Volume Segmentation": "quality control of the
 * tetrahedralization ... removing tetrahedra which were flat ... or which
 * spanned concave regions of the outer boundaries of the domain", "we kept
 * tables which described the location of each point, in terms of both the
 * volume and surface point numbers").
 *
 * A thx_volume (thorax/volume.h) passes when ALL of these hold:
 *
 *  validity
 *   - it has at least one tetrahedron; every node index is in range (if not,
 *     nothing else is checked); every region index is in the region table;
 *   - the four nodes of every tetrahedron are distinct;
 *   - every tetrahedron has positive volume, decided exactly:
 *     thx_orient3d(p0, p1, p2, p3) < 0 (right-handed, volume.h). "inverted"
 *     means > 0, "flat" means = 0;
 *   - no unused node (in no tetrahedron: an empty row of the FEM matrix), no
 *     two nodes with identical coordinates, no two tetrahedra on the same four
 *     nodes;
 *
 *  conformity (one conforming mesh)
 *   - every face is in at most two tetrahedra, and the two tetrahedra of an
 *     interior face lie on opposite sides of it (they traverse it in opposite
 *     directions; the same direction means they overlap);
 *   - the faces in exactly one tetrahedron, the boundary, taken as a surface
 *     with each face counterclockwise seen from outside the mesh (for a
 *     right-handed tetrahedron p0..p3 the outward faces are (p1,p2,p3),
 *     (p0,p3,p2), (p0,p1,p3), (p0,p2,p1)), pass thx_surface_check: closed
 *     2-manifold, consistently oriented, positive enclosed volume, 4 pi,
 *     no self-intersection (an interior non-conformity — a node hanging on
 *     another tetrahedron's face — shows up here as overlapping boundary
 *     faces inside the mesh);
 *   - the boundary components (node-connected) are shells (positive enclosed
 *     volume: an outer boundary) or cavities (negative: faces point into a
 *     hole of the mesh). Expected: as many shells as the model has "outer"
 *     surfaces (1 without a model), and as many cavities as excluded hearts
 *     (below; 0 without a model) unless opts->expected_cavities >= 0. Any
 *     further cavity is an interior "void" (missing tetrahedra);
 *
 *  containment (only when a model is given)
 *   - no tetrahedron's centroid lies outside every surface of role "outer";
 *   - a heart surface (role heart) is "excluded" when no region maps to it
 *     (no region named like the surface, nor "heart"): then no centroid lies
 *     inside it. Inside is decided by ray parity with exact orient3d signs
 *     over a BVH of the surface's triangles (rays grazing an edge are cast
 *     again in another direction; after 8 tries the solid-angle test of
 *     thorax/inside.h decides). The surfaces should pass thx_surface_check;
 *
 *  volumes (only when a model is given)
 *   - total: V_tets = sum of the tetrahedra's volumes, against
 *     V_enclosed = sum over "outer" surfaces of thx_surface_volume minus
 *     that of every excluded heart. rel_diff = (V_tets - V_enclosed) / V_enclosed;
 *     fails when |rel_diff| > opts->volume_tol (default 0.01, the "target
 *     under 1%"; <= 0 reports only);
 *   - per region, V_region = sum over its tetrahedra against the volume its
 *     surfaces enclose (V(role) = sum of thx_surface_volume over the
 *     surfaces of that role), by the region's name:
 *        a surface's name (e.g. "lung_l", "heart")    V(that surface)
 *        "heart"                                       V(heart)
 *        "lung", "lungs"                               V(lung)
 *        "fat"                                         V(outer) - V(fat)
 *        "muscle"                                      V(fat, else outer) - V(muscle)
 *        "mean_thorax", "thorax", "torso"              V(muscle, else fat, else outer)
 *                                                      - V(lung) - V(heart) - V(other)
 *                                                      (unless the name is a surface's)
 *     (roles are layers: outer contains fat contains muscle contains the
 *     organs; role fat is the fat/muscle interface, role muscle the inner
 *     border of the muscle). Other names: the volume is reported, no
 *     expectation. A region fails when |rel_diff| > opts->region_volume_tol
 *     (default 0: report only; centroid classification makes region volumes
 *     only as good as the mesh's conformity to the inner surfaces);
 *
 *  node tables (paper 3.3; when the volume has them or a model is given)
 *   - with a model: v->n_surfaces = m->n_surfaces and every table has the
 *     surface's node count (tables missing entirely: a failure);
 *   - every surf_node[s][i] is a volume node whose coordinates equal surface
 *     s's node i within opts->node_tol (default 1e-5 mm: files carry 6
 *     decimals), and node_surf/node_snode of that volume node are set (if
 *     they name surface s, they name node i: two surface nodes on one volume
 *     node are an error);
 *   - every volume node v with node_surf[v] = s >= 0 is listed back:
 *     surf_node[s][node_snode[v]] = v;
 *   - reported, not failed: boundary nodes of the mesh that are not on an
 *     "outer" surface or an excluded heart (a mesh not conforming to them);
 *
 *  quality (reported; fails only when opts asks)
 *   - dihedral angles (degrees, 6 per tetrahedron, between the two faces at
 *     an edge): smallest and largest; regular tetrahedron acos(1/3) = 70.53;
 *   - radius-edge ratio = circumradius / shortest edge: sqrt(6)/4 = 0.612
 *     for the regular tetrahedron, large for needles and caps, +inf when flat;
 *   - radius ratio = 3 inradius / circumradius: 1 regular, 0 flat (all shapes
 *     bad, slivers included, are small here);
 *   - histograms in fixed bins (thx_vcheck_dihedral_edges,
 *     thx_vcheck_radius_edge_edges below) and the THX_VCHECK_MAX_WORST worst
 *     tetrahedra by smallest dihedral and by radius-edge ratio (ties: smaller
 *     index first). Quality covers every tetrahedron with four distinct nodes
 *     (inverted ones by their shape; flat ones count as dihedral 0 and
 *     radius-edge +inf).
 *
 * Indices in reports are 0-based; JSON is 1-based (like volume.tet) and says
 * so. The boundary's sub-report numbers nodes as volume nodes; its triangles
 * are the boundary faces in the order of their tetrahedra (face 0..3).
 * Results do not depend on the number of OpenMP threads.
 */
#ifndef THORAX_CHECK_VOLUME_H
#define THORAX_CHECK_VOLUME_H

#include "thorax/check.h"
#include "thorax/model.h"
#include "thorax/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double volume_tol;        /* max |total rel_diff|; default 0.01; <= 0: report only */
    double region_volume_tol; /* max |region rel_diff|; default 0 (report only) */
    double node_tol;          /* surface node vs its volume node, mm; default 1e-5 */
    int expected_cavities;    /* >= 0: cavities expected; default -1: excluded hearts (0 without a model) */
    int check_intersections;  /* of the boundary surface; default 1 */
    double min_dihedral_deg;  /* > 0: fail if a dihedral angle is smaller; default 0 (report only) */
    double max_radius_edge;   /* > 0: fail if a radius-edge ratio is larger; default 0 (report only) */
} thx_volume_check_opts;

/* Fills *o with the defaults above. */
void thx_volume_check_opts_default(thx_volume_check_opts *o);

/* Failure categories (bits of thx_volume_report.failures). */
typedef enum {
    THX_VCHECKF_EMPTY = 1u << 0,          /* no tetrahedra */
    THX_VCHECKF_BAD_INDEX = 1u << 1,      /* node index out of range: nothing else checked */
    THX_VCHECKF_BAD_REGION = 1u << 2,     /* region index outside the region table */
    THX_VCHECKF_REPEATED_NODE = 1u << 3,  /* a tetrahedron with a node twice */
    THX_VCHECKF_INVERTED = 1u << 4,       /* negative volume */
    THX_VCHECKF_FLAT = 1u << 5,           /* zero volume (four coplanar nodes) */
    THX_VCHECKF_UNUSED = 1u << 6,         /* nodes in no tetrahedron */
    THX_VCHECKF_DUPLICATE_NODE = 1u << 7, /* two nodes at the same coordinates */
    THX_VCHECKF_DUPLICATE_TET = 1u << 8,  /* two tetrahedra on the same four nodes */
    THX_VCHECKF_NONCONFORMING = 1u << 9,  /* a face in 3+ tetrahedra, or two on the same side of a face */
    THX_VCHECKF_BOUNDARY = 1u << 10,      /* the boundary surface failed thx_surface_check */
    THX_VCHECKF_COMPONENTS = 1u << 11,    /* shells/cavities not as expected (voids) */
    THX_VCHECKF_CONTAINMENT = 1u << 12,   /* centroids outside the outer surface / inside an excluded heart */
    THX_VCHECKF_VOLUME = 1u << 13,        /* total volume differs from the enclosed one */
    THX_VCHECKF_REGION_VOLUME = 1u << 14, /* a region's volume differs from its surfaces' */
    THX_VCHECKF_NODE_TABLE = 1u << 15,    /* node tables wrong or missing */
    THX_VCHECKF_QUALITY = 1u << 16        /* below opts->min_dihedral_deg / above opts->max_radius_edge */
} thx_volume_check_failure;
#define THX_VCHECK_N_FAILURES 17

#define THX_VCHECK_MAX_REASONS 20
#define THX_VCHECK_MAX_WORST 8
#define THX_VCHECK_DIHEDRAL_BINS 9
#define THX_VCHECK_RADIUS_EDGE_BINS 9
/* Smallest dihedral angle per tetrahedron (degrees): bin b counts
 * [edges[b], edges[b+1]); edges 0 5 10 15 20 30 40 50 60 inf (the last bin
 * holds 60 .. 70.53, the regular tetrahedron's). */
extern const double thx_vcheck_dihedral_edges[THX_VCHECK_DIHEDRAL_BINS + 1];
/* Radius-edge ratio per tetrahedron: edges sqrt(6)/4 0.8 1 1.5 2 3 5 10 100 inf;
 * the last bin [100, inf] holds flat ones; rounding below sqrt(6)/4 counts in bin 0. */
extern const double thx_vcheck_radius_edge_edges[THX_VCHECK_RADIUS_EDGE_BINS + 1];

/* One region of the region table. */
typedef struct {
    char name[64];
    size_t n_tets;
    double volume;          /* sum of its tetrahedra's signed volumes, mm^3 */
    double expected;        /* from the surfaces (mapping above); NaN if none */
    double rel_diff;        /* (volume - expected) / expected; NaN if no expectation */
    char definition[160];   /* e.g. "torso - fat", "" if none */
    int ok;                 /* 0 iff |rel_diff| > region_volume_tol > 0 */
} thx_volume_region_report;

typedef struct {
    size_t tet;
    double value;
} thx_volume_worst;

/* Everything thx_volume_check measured. Owns regions (thx_volume_report_free). */
typedef struct {
    int ok;                 /* 1 iff failures == 0 */
    unsigned failures;      /* bits of thx_volume_check_failure */
    size_t n_reasons;
    char reasons[THX_VCHECK_MAX_REASONS][256]; /* human-readable, numbers 1-based */

    size_t n_nodes, n_tets, n_table_regions;

    /* validity (first examples 0-based, valid when the count is > 0) */
    size_t n_bad_index_tets, ex_bad_index_tet;
    size_t n_bad_region_tets, ex_bad_region_tet;
    size_t n_repeated_node_tets, ex_repeated_node_tet;
    size_t n_inverted_tets, ex_inverted_tet;
    size_t n_flat_tets, ex_flat_tet;
    size_t n_unused_nodes;
    int32_t ex_unused_node;
    size_t n_duplicate_nodes;       /* nodes equal to an earlier node */
    int32_t ex_duplicate_node[2];
    size_t n_duplicate_tets;        /* tetrahedra on the nodes of an earlier one */
    size_t ex_duplicate_tet[2];     /* the earliest tetrahedron repeated by the lowest-numbered duplicate */

    /* conformity */
    size_t n_faces, n_interior_faces, n_boundary_faces;
    /* face examples: the first by node numbers (sorted), not by tetrahedron */
    size_t n_nonconforming_faces;   /* faces in three or more tetrahedra */
    int32_t ex_nonconforming_face[3];
    size_t n_overlapping_faces;     /* interior faces whose two tetrahedra lie on one side */
    int32_t ex_overlapping_face[3];
    int boundary_checked;           /* the boundary surface was built and checked */
    thx_surface_report boundary;    /* named "boundary"; nodes are volume nodes */
    size_t n_boundary_components, n_shells, n_cavities;
    size_t expected_shells, expected_cavities;
    size_t n_voids;                 /* cavities beyond the expected ones */
    size_t n_boundary_nodes_off_surfaces; /* with a model: boundary nodes on no outer/excluded heart surface */

    /* containment */
    int containment_checked;
    size_t n_outer_surfaces, n_excluded_hearts;
    char outer_names[160], excluded_names[160]; /* comma-separated surface names */
    size_t n_outside_tets, ex_outside_tet;
    size_t n_in_cavity_tets, ex_in_cavity_tet;
    size_t n_undecided_tets;        /* classified by the solid-angle fallback (counted, not failed) */

    /* volumes (mm^3) */
    double tet_volume;              /* sum of all tetrahedra's signed volumes */
    double min_tet_volume, max_tet_volume;
    double enclosed_volume;         /* from the surfaces; NaN without a model */
    double volume_rel_diff;         /* NaN without a model */
    double volume_tol;
    char volume_definition[160];    /* e.g. "torso - heart" */
    double region_volume_tol;
    size_t n_regions;
    thx_volume_region_report *regions; /* n_regions (= the region table), owned */

    /* node tables */
    int node_tables_checked;
    size_t n_table_surfaces;        /* v->n_surfaces */
    size_t n_table_size_errors;     /* surfaces missing or with the wrong node count */
    size_t n_table_bad_entries;     /* surf_node out of range */
    size_t n_table_mismatches;      /* coordinates differ by more than node_tol */
    size_t n_table_backlink_errors; /* node_surf/node_snode not pointing back */
    double table_max_distance;      /* largest surface/volume node distance (mm); NaN if none */
    double node_tol;
    size_t ex_table_surface, ex_table_node; /* first bad surf_node entry (surface, node) */
    int32_t ex_backlink_node;

    /* quality (dihedral angles in degrees) */
    double min_dihedral, max_dihedral;
    size_t min_dihedral_tet, max_dihedral_tet;
    double max_radius_edge, mean_radius_edge; /* +inf when a tetrahedron is flat */
    size_t max_radius_edge_tet;
    double min_radius_ratio, mean_radius_ratio;
    size_t min_radius_ratio_tet;
    double min_edge, max_edge;
    size_t dihedral_hist[THX_VCHECK_DIHEDRAL_BINS];
    size_t radius_edge_hist[THX_VCHECK_RADIUS_EDGE_BINS];
    size_t n_worst_dihedral, n_worst_radius_edge;
    thx_volume_worst worst_dihedral[THX_VCHECK_MAX_WORST];    /* smallest first */
    thx_volume_worst worst_radius_edge[THX_VCHECK_MAX_WORST]; /* largest first */
    double min_dihedral_opt, max_radius_edge_opt;             /* the opts thresholds (0: none) */
} thx_volume_report;

/*
 * Checks v (and, if m is not NULL, v against m's surfaces) and fills *r
 * (always, when the call gets that far; free it with thx_volume_report_free).
 * *r is overwritten without being freed: free a report before reusing it.
 * opts: NULL for the defaults. Returns THX_OK if the volume passed,
 * THX_ECHECK if it failed (r tells why; the context holds the first reason),
 * THX_ENOMEM. Cost: O(T log T) for T tetrahedra plus one ray per
 * tetrahedron and outer/heart surface (BVH); 500,000 tetrahedra take about
 * a second.
 */
thx_status thx_volume_check(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const thx_volume_check_opts *opts,
                            thx_volume_report *r);

/* Frees what *r owns and zeroes it; accepts NULL. */
void thx_volume_report_free(thx_volume_report *r);

/* Quality of one tetrahedron a, b, c, d (either orientation; 3 doubles each):
 * smallest and largest dihedral angle (degrees), radius-edge ratio, radius
 * ratio (any output may be NULL). Flat: 0, 180, +inf, 0. Pure. */
void thx_tet_quality(const double *a, const double *b, const double *c, const double *d, double *min_dihedral,
                     double *max_dihedral, double *radius_edge, double *radius_ratio);

/* JSON form of a report (numbers 1-based, non-finite as null):
 *   {"ok", "index_base": 1, "failures": [names], "reasons": [..],
 *    "nodes", "tetrahedra", "region_table_size",
 *    "conforming", "boundary_closed", "positive",
 *    "validity": {"bad_index_tetrahedra", "bad_region_tetrahedra",
 *                 "repeated_node_tetrahedra", "inverted_tetrahedra", "flat_tetrahedra",
 *                 "unused_nodes", "duplicate_nodes", "duplicate_tetrahedra", "first": {..}},
 *    "conformity": {"faces", "interior_faces", "boundary_faces", "faces_in_3_or_more",
 *                   "overlapping_faces", "boundary_components", "shells", "cavities",
 *                   "expected_shells", "expected_cavities", "voids",
 *                   "boundary_nodes_off_surfaces", "first": {..},
 *                   "boundary": <thx_surface_report_json of the boundary> | null},
 *    "containment": {"checked", "outer_surfaces": [..], "excluded_surfaces": [..],
 *                    "outside": n, "in_excluded": n, "undecided": n, "first": {..}},
 *    "volume": {"tetrahedra": V, "enclosed": V|null, "definition": "..",
 *               "rel_diff": d|null, "tolerance": t, "min_tet": .., "max_tet": .., "ok"},
 *    "regions": [{"name", "tetrahedra", "volume", "expected", "definition",
 *                 "rel_diff", "ok"}, ..], "region_tolerance": t,
 *    "node_tables": {"checked", "surfaces", "size_errors", "bad_entries",
 *                    "coordinate_mismatches", "backlink_errors", "max_distance",
 *                    "tolerance", "first": {..}},
 *    "quality": {"min_dihedral_deg", "min_dihedral_tetrahedron", "max_dihedral_deg",
 *                "max_dihedral_tetrahedron", "min_edge", "max_edge",
 *                "dihedral": {"definition", "histogram": {"edges", "counts"},
 *                             "worst": [[tet, deg], ..]},
 *                "radius_edge": {"definition", "max", "max_tetrahedron", "mean",
 *                                "histogram": {..}, "worst": [[tet, ratio], ..]},
 *                "radius_ratio": {"definition", "min", "min_tetrahedron", "mean"}}}
 * Returns a new cJSON tree (cJSON_Delete), or NULL (THX_ENOMEM in ctx). */
struct cJSON *thx_volume_report_json(thx_ctx *ctx, const thx_volume_report *r);

/* Name of one failure category ("inverted", "nonconforming", ...). Static storage. */
const char *thx_volume_check_failure_name(thx_volume_check_failure f);

#ifdef __cplusplus
}
#endif
#endif
