/*
 * thorax/check/check.h — invariant checks of triangle surfaces and models
 * (paper 3.2, "Completing the model": "we select a point inside each surface,
 * and compute the total solid angle about that point. If the surface
 * description is complete (no holes), and all the outward normals are
 * correct, the result must be 4 pi").
 *
 * A surface passes when ALL of these hold:
 *  - it has at least one triangle and every node index is in range;
 *  - closed 2-manifold: every edge lies in exactly two triangles (no boundary
 *    edge, no non-manifold edge), every vertex's triangles form one fan (no
 *    non-manifold vertex, e.g. two cones touching at their apex), no node is
 *    unused (an unused node gives an empty row in a boundary-element matrix);
 *  - consistent orientation: the two triangles of every edge traverse it in
 *    opposite directions;
 *  - no duplicate triangles (same three nodes in any order) and no degenerate
 *    triangles (repeated node, or three collinear points: zero area, decided
 *    exactly);
 *  - outward orientation: the enclosed signed volume (divergence theorem) is > 0;
 *  - 4 pi: the total solid angle Omega about an interior point satisfies
 *    |Omega / (4 pi) - 1| <= opts->solid_angle_tol;
 *  - no self-intersection: no two triangles share a point other than the
 *    vertices and edges they share by index (exact predicates, see below);
 *  - no triangle with an angle below opts->min_angle_deg (default
 *    THX_CHECK_MIN_ANGLE_DEG, 1 deg: what thorax mesh can take, see below; 0: report
 *    only); the aspect ratio fails only if opts asks for it (max_aspect > 0).
 * Euler characteristic and the number of connected components are reported,
 * never failed on: a torus or two disjoint spheres are valid closed surfaces.
 *
 * Self-intersection, exactly (thx_orient3d / thx_orient2d signs):
 *  - triangles sharing no node intersect if their closed point sets meet at
 *    all (touching counts: a mesh that touches itself is not an embedding);
 *  - triangles sharing one node v intersect if they meet anywhere but v
 *    (an edge piercing the other triangle, coplanar overlapping wedges);
 *  - triangles sharing an edge intersect only if they are coplanar and lie on
 *    the same side of the edge (folded flat onto each other);
 *  - triangles sharing all three nodes are duplicates (counted there, not here);
 *  - degenerate triangles are counted as such and skipped here.
 *
 * Aspect ratio (per triangle) = longest edge / (2 sqrt(3) * inradius)
 *   = L_max * perimeter / (4 sqrt(3) * area): 1 for an equilateral triangle,
 *   growing without bound as a triangle flattens; +inf for zero area.
 *
 * Indices in reports are 0-based (in memory); JSON output is 1-based, like the
 * .fac files, and says so ("index_base": 1).
 */
#ifndef THORAX_CHECK_H
#define THORAX_CHECK_H

#include "thorax/model/surface.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#ifdef __cplusplus
extern "C" {
#endif

struct cJSON; /* <cjson/cJSON.h>; the JSON functions return cJSON trees */

/* The default smallest triangle angle (deg). thorax mesh cannot take a surface triangle with a smaller
 * angle: the tetrahedra on it are as flat as its smallest angle (measured: a box with one such triangle
 * meshes at 1.0 deg and is refused below it, at every grid, by the volume check's smallest dihedral
 * angle, THX_VCHECK default 1 deg), and far below it the conformity gives up ("a surface edge would be cut
 * in more than 2^22 pieces"). docs/design/check.md, "The smallest angle a surface may have". */
#define THX_CHECK_MIN_ANGLE_DEG 1.0

typedef struct {
    double solid_angle_tol;  /* max |Omega/(4 pi) - 1|; default 1e-6 */
    int check_intersections; /* default 1; 0 skips the self-intersection search */
    double min_angle_deg;    /* > 0: fail if any triangle has a smaller angle (deg); default THX_CHECK_MIN_ANGLE_DEG;
                                0: report only */
    double max_aspect;       /* > 0: fail if any aspect ratio exceeds it; default 0 (report only) */
} thx_check_opts;

/* Fills *o with the defaults above. */
void thx_check_opts_default(thx_check_opts *o);

/* Failure categories (bits of thx_surface_report.failures). */
typedef enum {
    THX_CHECKF_EMPTY = 1u << 0,          /* no triangles */
    THX_CHECKF_BAD_INDEX = 1u << 1,      /* node index out of range: nothing else checked */
    THX_CHECKF_BOUNDARY = 1u << 2,       /* edges in one triangle: not closed */
    THX_CHECKF_NONMANIFOLD = 1u << 3,    /* edges in > 2 triangles, or vertices with > 1 fan */
    THX_CHECKF_ORIENTATION = 1u << 4,    /* an edge traversed twice in the same direction */
    THX_CHECKF_DUPLICATE = 1u << 5,      /* two triangles on the same three nodes */
    THX_CHECKF_DEGENERATE = 1u << 6,     /* zero-area triangles */
    THX_CHECKF_UNUSED = 1u << 7,         /* nodes in no triangle */
    THX_CHECKF_VOLUME = 1u << 8,         /* signed volume <= 0: normals point inward */
    THX_CHECKF_SOLID_ANGLE = 1u << 9,    /* |Omega/4pi - 1| > tol, or no interior point */
    THX_CHECKF_INTERSECTION = 1u << 10,  /* self-intersecting triangle pairs */
    THX_CHECKF_QUALITY = 1u << 11        /* below opts->min_angle_deg / above opts->max_aspect */
} thx_check_failure;

#define THX_CHECK_MAX_PAIRS 8    /* intersecting pairs listed (the smallest (i, j), i < j) */
#define THX_CHECK_MAX_REASONS 16 /* at most one per failure category (two for quality) */
#define THX_CHECK_ASPECT_BINS 8
/* Histogram bin b counts aspect ratios in [edges[b], edges[b+1]);
 * the last bin is [100, inf] and includes degenerate triangles. */
extern const double thx_check_aspect_edges[THX_CHECK_ASPECT_BINS + 1];

typedef enum {
    THX_INTERIOR_NONE = 0,  /* no interior point: the 4 pi check failed */
    THX_INTERIOR_GIVEN = 1, /* supplied by the caller (e.g. stored in the model) */
    THX_INTERIOR_FOUND = 2  /* found by thx_surface_find_interior */
} thx_interior_source;

/* Everything thx_surface_check measured. Plain data (no pointers). */
typedef struct {
    char name[64];
    int ok;                 /* 1 iff failures == 0 */
    unsigned failures;      /* bits of thx_check_failure */
    size_t n_reasons;
    char reasons[THX_CHECK_MAX_REASONS][192]; /* human-readable, one per failed category */

    /* sizes and topology */
    size_t n_nodes, n_tris, n_edges; /* n_edges: distinct undirected edges */
    size_t n_bad_index_tris;
    size_t n_unused_nodes;
    size_t n_boundary_edges;     /* edges in exactly one triangle */
    size_t n_nonmanifold_edges;  /* edges in three or more triangles */
    size_t n_nonmanifold_vertices;
    size_t n_inconsistent_edges; /* edges in two triangles that traverse it the same way */
    size_t n_duplicate_tris;     /* triangles equal (as node sets) to an earlier one */
    size_t n_degenerate_tris;
    long euler;                  /* used nodes - edges + triangles (2 per sphere-like component) */
    size_t n_components;         /* edge-connected components of triangles */
    /* first example of each defect (0-based; valid when the count is > 0) */
    int32_t ex_boundary_edge[2], ex_nonmanifold_edge[2], ex_inconsistent_edge[2];
    int32_t ex_nonmanifold_vertex, ex_unused_node;
    size_t ex_duplicate_tri[2], ex_degenerate_tri, ex_bad_index_tri;

    /* geometry */
    double area;   /* total area, mm^2 */
    double volume; /* signed enclosed volume, mm^3: > 0 when normals point outward */
    thx_interior_source interior_source;
    thx_vec3 interior;          /* the point used for the solid angle */
    double solid_angle;         /* Omega at interior (sr); NaN if not computed */
    double solid_angle_rel_err; /* |Omega/(4 pi) - 1|; NaN if not computed */
    double solid_angle_tol;

    /* self-intersection */
    int intersections_checked;
    size_t n_intersecting_pairs;
    size_t n_listed_pairs;
    size_t pairs[THX_CHECK_MAX_PAIRS][2]; /* the smallest pairs (i < j) in lexicographic order */

    /* quality (over non-degenerate triangles; angles in degrees) */
    double min_angle, max_angle;
    size_t min_angle_tri, max_angle_tri;
    size_t n_small_angle_tris; /* triangles with an angle below opts->min_angle_deg (degenerate ones included) */
    double min_area, max_area;
    double min_edge, max_edge;
    double max_aspect, mean_aspect; /* max_aspect is +inf when a triangle is degenerate */
    size_t max_aspect_tri;
    size_t aspect_hist[THX_CHECK_ASPECT_BINS];
} thx_surface_report;

/*
 * Checks one surface and fills *rep (always, when the call gets that far).
 * interior: a point inside the surface for the 4 pi test, or NULL to find one
 * with thx_surface_find_interior (independent of the triangles' orientation,
 * so a surface with all normals inward shows Omega = -4 pi, not a miss).
 * opts: NULL for the defaults.
 * Returns THX_OK if the surface passed, THX_ECHECK if it failed (rep tells
 * why; the context holds the first reason, naming the surface), THX_ENOMEM.
 * Results do not depend on the number of OpenMP threads.
 */
thx_status thx_surface_check(thx_ctx *ctx, const thx_surface *s, const thx_vec3 *interior,
                             const thx_check_opts *opts, thx_surface_report *rep);

/* Releases what a report owns and zeroes it. A report is plain data today, so
 * this only clears it; calling it keeps callers right if that ever changes.
 * Accepts NULL. */
void thx_surface_report_free(thx_surface_report *r);

/*
 * Finds a point strictly inside a closed surface without trusting its
 * orientation: from the centroids of the largest triangles it steps along
 * +-normal to halfway to the next surface crossing, and keeps the first
 * candidate that a majority of rays in fixed pseudo-random directions
 * classify as inside by crossing parity (exact orient3d; rays grazing an edge
 * or vertex are discarded and replaced). Candidates with a larger free gap
 * are tried first. Returns THX_OK and *p, or THX_EGEOM if no candidate
 * qualified (e.g. an open surface), THX_EINPUT for bad indices, THX_ENOMEM.
 */
thx_status thx_surface_find_interior(thx_ctx *ctx, const thx_surface *s, thx_vec3 *p);


/* Per-surface reports of a whole model. */
typedef struct {
    int ok;                    /* 1 iff every surface passed and no two surfaces meet */
    size_t n_surfaces;
    thx_surface_report *surf;  /* n_surfaces reports, owned */
    double solid_angle_tol;
    /* surfaces that meet (touch or cross: a common point, exactly, as the self-intersection test with no
       node shared by index; with check_intersections): a volume mesh needs them apart */
    int meetings_checked;
    size_t n_meeting_pairs;    /* pairs of surfaces that meet */
    size_t meet_a, meet_b;     /* the first such pair (surface indices, a < b) */
    size_t meet_tris;          /* triangle pairs of meet_a and meet_b that meet */
    size_t meet_tri_a, meet_tri_b; /* the first of them (0-based triangles of meet_a and meet_b) */
    char meet_reason[768];     /* "" when none meet */
} thx_model_report;

/* Checks every surface of m (using m's stored interior points where
 * has_interior[s] is set), and with check_intersections every pair of surfaces for a common point,
 * into a new *out (caller destroys; filled even when a surface fails). Returns THX_OK if all passed, THX_ECHECK if any failed
 * (message names the first failing surface), or another error (then *out is NULL). */
thx_status thx_model_check(thx_ctx *ctx, const thx_model *m, const thx_check_opts *opts, thx_model_report **out);
/* Frees the report; accepts NULL; nulls *r. */
void thx_model_report_destroy(thx_model_report **r);

/* JSON form of a report (indices 1-based; every count and figure of the
 * struct, non-finite numbers as null), e.g. for one surface:
 *   {"name": "tank", "role": "outer", "ok": false, "failures": ["boundary", ...],
 *    "reasons": ["not closed: 3 boundary edges ...", ...],
 *    "nodes": 771, "triangles": 1537, "edges": 2307,
 *    "closed": false, "manifold": true, "consistently_oriented": true,
 *    "topology": {"bad_index_triangles": 0, "boundary_edges": 3, "nonmanifold_edges": 0,
 *                 "nonmanifold_vertices": 0, "inconsistent_edges": 0, "duplicate_triangles": 0,
 *                 "degenerate_triangles": 0, "unused_nodes": 0, "euler_characteristic": 1,
 *                 "components": 1, "first": {"boundary_edge": [717, 718]}},
 *    "area": 363300.5, "volume": 1.549e7,
 *    "solid_angle": {"interior_source": "found", "interior": [x, y, z], "omega": 12.547,
 *                    "omega_over_4pi": 0.99846, "rel_error": 0.00154, "tolerance": 1e-6, "ok": false},
 *    "intersections": {"checked": true, "pairs": 0, "first_pairs": [[i, j], ...]},
 *    "quality": {"min_angle_deg": 7.93, "min_angle_triangle": 1177, "triangles_below_min_angle": 0,
 *                "max_angle_deg": 138.3,
 *                "max_angle_triangle": 1369, "min_area": .., "max_area": .., "min_edge": ..,
 *                "max_edge": .., "aspect_ratio": {"definition": "...", "max": 4.57,
 *                "max_triangle": 11, "mean": 1.37, "histogram": {"edges": [1, 1.25, 1.5, 2, 3, 5,
 *                10, 100, null], "counts": [152, 1231, 124, 26, 4, 0, 0, 0]}}}}
 * Returns a new cJSON tree the caller frees with cJSON_Delete, or
 * NULL on allocation failure (THX_ENOMEM recorded in ctx). role may be NULL. */
struct cJSON *thx_surface_report_json(thx_ctx *ctx, const thx_surface_report *r, const char *role);
/* {"ok": .., "index_base": 1, "solid_angle_tol": .., "surfaces": [..]}; roles
 * taken from m if given (may be NULL). A model without surfaces is "ok" here;
 * `thorax check` treats it as a failure. */
struct cJSON *thx_model_report_json(thx_ctx *ctx, const thx_model_report *r, const thx_model *m);

/* Name of one failure category ("boundary", "orientation", ...). Static storage. */
const char *thx_check_failure_name(thx_check_failure f);

#ifdef __cplusplus
}
#endif
#endif
