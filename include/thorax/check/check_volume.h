/*
 * thorax/check/check_volume.h — invariant checks of a tetrahedral volume mesh
 * (paper 3.3, "Volume Segmentation": "quality control of the
 * tetrahedralization ... removing tetrahedra which were flat ... or which
 * spanned concave regions of the outer boundaries of the domain", "we kept
 * tables which described the location of each point, in terms of both the
 * volume and surface point numbers").
 *
 * A thx_volume (thorax/model/volume.h) passes when ALL of these hold:
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
 *  surface coverage (only when a model is given) — decided from the
 *  geometry alone, not from the mesher's Steiner table (docs/decisions.md,
 *  "Checks"):
 *   - "interface faces" are the boundary faces and the interior faces whose
 *     two tetrahedra have different regions. Each is mapped to the surface
 *     triangle it lies on: its three corners within opts->node_tol of the
 *     triangle's plane and inside the triangle within node_tol (a BVH over
 *     every surface's triangles; of several candidates on one surface the
 *     one whose inside holds the face's centroid deepest; a face on two
 *     surfaces that coincide there counts for both);
 *   - every non-degenerate triangle of every surface must be covered: the
 *     areas of the faces mapped to it sum to its area within
 *     opts->coverage_tol (relative, default 1e-6) + 1e-6 mm x its perimeter
 *     (files carry 6 decimals, so a node on an edge may be 5e-7 mm off in
 *     each coordinate; a missing sliver of a triangle along an edge is found
 *     from a few 1e-6 mm of width up);
 *   - no interface face lies on no surface triangle ("region boundary off
 *     the surfaces": a region that does not follow its surfaces, or a mesh
 *     that cuts across a surface);
 *   reported per surface: triangles, covered, share; failure "coverage";
 *
 *  containment and regions (only when a model is given)
 *   - inside a surface is decided by ray parity with exact orient3d signs
 *     over a BVH of the surface's triangles and a voxel grid: a point in a
 *     voxel the surface misses takes the voxel's side (one ray per connected
 *     set of such voxels), a point in a voxel it passes through the side of
 *     a free voxel nearby flipped by the parity of the segment between them,
 *     else a full ray (rays grazing an edge are cast again in another
 *     direction; after 8 tries the solid-angle test of thorax/geom/inside.h
 *     decides). The surfaces should pass thx_surface_check;
 *   - no tetrahedron's centroid lies outside every surface of role "outer";
 *   - a heart surface (role heart) is "excluded" when no region maps to it
 *     (no region named like the surface, nor "heart"): then no centroid lies
 *     inside it;
 *   - nesting: surface A is inside surface B when most of (up to 256 spread)
 *     nodes of A are inside B; A's parent is the smallest-volume surface
 *     containing it (reported per surface as "inside");
 *   - cells: the cell of a tetrahedron is the innermost (smallest-volume)
 *     surface containing its centroid, or "outside every surface". Each
 *     cell should hold one region: the region most of its tetrahedra have
 *     (ties: the lower region number). A tetrahedron of another region in
 *     it is "outside its region" (failure "region_cells"), reported per
 *     region and with the first such tetrahedron. (Per cell rather than per
 *     region, because one region may fill several cells: "lungs" for both
 *     lungs.)
 *
 *  volumes (only when a model is given)
 *   - total: V_tets = sum of the tetrahedra's volumes, against
 *     V_enclosed = sum over "outer" surfaces of thx_surface_volume minus
 *     that of every excluded heart. rel_diff = (V_tets - V_enclosed) / V_enclosed;
 *     fails when |rel_diff| > opts->volume_tol (default 0.01, the "target
 *     under 1%"; <= 0 reports only);
 *   - per region, V_region = sum over its tetrahedra against the volume
 *     between its surfaces. The region belongs to the inside of one or
 *     more surfaces, chosen by its name:
 *        a surface's name (role lung, heart, other)    that surface
 *        "heart"                                       the heart surfaces
 *        "lung", "lungs"                               the lung surfaces
 *        "fat"                                         outer (if a fat surface exists)
 *        "muscle"                                      fat, else outer (if a muscle surface exists)
 *        "mean_thorax", "thorax", "torso"              muscle, else fat, else outer
 *                                                      (unless the name is a surface's)
 *     and the region inside a surface S is V(S) minus the volumes of the
 *     surfaces directly nested in S (their parent is S, nesting above):
 *     "fat" is "torso - fat", "mean_thorax" "muscle - lung_r - lung_l -
 *     heart", and a lung shell around the heart "lung - heart". Other
 *     names: the volume is reported, no expectation. A region fails when
 *     |rel_diff| > opts->region_volume_tol (default 0.005; <= 0 reports
 *     only);
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
 *   - every Steiner record (v->steiner, with a model) names a node, surface
 *     and triangle in range, and its node lies within opts->node_tol of the
 *     point its barycentric coordinates give on that triangle;
 *   - reported, not failed: boundary nodes of the mesh that are neither nodes
 *     nor Steiner nodes of an "outer" surface or an excluded heart (a mesh
 *     not conforming to them);
 *
 *  quality (dihedral angles fail below opts->min_dihedral_deg, default 1
 *  degree; the rest is reported, failing only when opts asks)
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

#include "thorax/check/check.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double volume_tol;        /* max |total rel_diff|; default 0.01; <= 0: report only */
    double region_volume_tol; /* max |region rel_diff|; default 0.005; <= 0: report only */
    double node_tol;          /* surface node vs its volume node, Steiner node vs its triangle point,
                               * interface face corners vs a surface triangle, mm; default 1e-5 */
    double coverage_tol;      /* covered area of a surface triangle vs its area, relative; default 1e-6 */
    int expected_cavities;    /* >= 0: cavities expected; default -1: excluded hearts (0 without a model) */
    int check_intersections;  /* of the boundary surface; default 1 */
    double min_dihedral_deg;  /* > 0: fail if a dihedral angle is smaller; default 1; 0: report only */
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
    THX_VCHECKF_NODE_TABLE = 1u << 15,    /* node tables or Steiner records wrong or missing */
    THX_VCHECKF_QUALITY = 1u << 16,       /* below opts->min_dihedral_deg / above opts->max_radius_edge */
    THX_VCHECKF_COVERAGE = 1u << 17,      /* a surface triangle not covered by interface faces, or an
                                           * interface face on no surface */
    THX_VCHECKF_REGION_CELLS = 1u << 18   /* tetrahedra outside their region (in another region's cell) */
} thx_volume_check_failure;
#define THX_VCHECK_N_FAILURES 19

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
    int cell;               /* the cell most of its tetrahedra are in: a surface index (inside it,
                             * innermost), -1 outside every surface; -2 if not decided */
    size_t n_outside;       /* its tetrahedra in a cell that holds another region */
    size_t ex_outside;      /* the first of them (0-based; valid when n_outside > 0) */
    int ex_outside_cell;    /* that tetrahedron's cell (as cell) */
} thx_volume_region_report;

/* Coverage and nesting of one surface of the model. */
typedef struct {
    char name[64];
    size_t n_tris;          /* all triangles (degenerate ones count as covered) */
    size_t n_covered;
    double share;           /* n_covered / n_tris (1 for no triangles) */
    double area, covered_area; /* mm^2: the surface's, and that of the interface faces on it */
    size_t ex_uncovered;    /* first triangle not covered (0-based; valid when n_covered < n_tris) */
    double ex_centroid[3];  /* its centroid, mm */
    double ex_covered_share;/* covered area / area of that triangle */
    size_t n_steiner;       /* Steiner records on this surface */
    int parent;             /* the smallest-volume surface containing it (index), -1 none */
    double volume;          /* thx_surface_volume, mm^3 */
} thx_volume_surface_report;

typedef struct {
    size_t tet;
    double value;
} thx_volume_worst;

/* Everything thx_volume_check measured. Owns regions and surfaces (thx_volume_report_free). */
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
    size_t n_boundary_nodes_off_surfaces; /* with a model: boundary nodes that are neither nodes nor Steiner
                                           * nodes of an outer surface or an excluded heart */

    /* surface coverage (with a model) */
    int coverage_checked;
    size_t n_interface_faces;       /* boundary faces + faces between two regions */
    size_t n_uncovered_tris;        /* over all surfaces */
    size_t n_faces_off_surfaces;    /* interface faces on no surface triangle */
    int32_t ex_off_face[3];         /* the first (volume nodes, sorted) */
    double ex_off_centroid[3];
    double coverage_tol;
    size_t n_surface_reports;
    thx_volume_surface_report *surfaces; /* one per model surface, owned */

    /* containment */
    int containment_checked;
    size_t n_outer_surfaces, n_excluded_hearts;
    char outer_names[160], excluded_names[160]; /* comma-separated surface names */
    size_t n_outside_tets, ex_outside_tet;
    size_t n_in_cavity_tets, ex_in_cavity_tet;
    size_t n_undecided_tets;        /* classified by the solid-angle fallback (counted, not failed) */
    int cells_checked;              /* cells decided against every surface of the model */
    size_t n_outside_region_tets;   /* tetrahedra in a cell that holds another region */
    size_t ex_outside_region_tet;   /* the first of them */

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
    size_t n_steiner;               /* v->n_steiner */
    size_t n_steiner_bad;           /* records out of range */
    size_t n_steiner_mismatches;    /* node farther than node_tol from its barycentric point */
    double steiner_max_distance;    /* mm; NaN if none checked */
    size_t ex_steiner;              /* first bad record (0-based) */

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
 * THX_ENOMEM. Cost: O(T log T) for T tetrahedra, plus per tetrahedron a
 * voxel lookup or a ray (BVH) for each surface up to the innermost one
 * holding its centroid and the outer/excluded ones, plus a BVH query per
 * interface face; the high-resolution phantom (1.21 M tetrahedra, 6
 * surfaces) takes about 2.5 s of CPU on one thread.
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
 *    "coverage": {"checked", "interface_faces", "uncovered_triangles", "faces_off_surfaces",
 *                 "tolerance", "surfaces": [{"name", "triangles", "covered", "share", "area",
 *                 "covered_area", "steiner_nodes", "inside": name|null,
 *                 "first_uncovered": {"triangle", "centroid", "covered_share"}}, ..],
 *                 "first_off_surface": {"nodes", "centroid"}},
 *    "region_cells": {"checked", "outside_region", "first_tetrahedron"},
 *    "volume": {"tetrahedra": V, "enclosed": V|null, "definition": "..",
 *               "rel_diff": d|null, "tolerance": t, "min_tet": .., "max_tet": .., "ok"},
 *    "regions": [{"name", "tetrahedra", "volume", "expected", "definition",
 *                 "rel_diff", "ok", "cell": "inside NAME"|"outside every surface"|null,
 *                 "outside_region", "first_outside_tetrahedron"}, ..], "region_tolerance": t,
 *    "node_tables": {"checked", "surfaces", "size_errors", "bad_entries",
 *                    "coordinate_mismatches", "backlink_errors", "max_distance",
 *                    "tolerance", "steiner_nodes", "steiner_bad", "steiner_mismatches",
 *                    "steiner_max_distance", "first": {..}},
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
