/*
 * thorax/import/import.h — surfaces and volume meshes made by other programs, read (thorax/io/
 * surface_read.h, thorax/io/volume_read.h), put in order and checked before they enter a model
 * (`thorax import`).
 *
 * Units: coordinates are taken as millimetres and multiplied by opts->scale
 * (1000 for a file in metres, such as ECGSim's own downloads).
 *
 * Import policy (thx_surface_import), in this order:
 *  1. read; every index is checked against the node count (errors name the
 *     file and line, or the byte offset in binary data);
 *  2. scale;
 *  3. nodes used by no triangle are removed and the rest renumbered in their
 *     order (counted in info->n_unused_removed): an unused node would give an
 *     empty row in a boundary-element matrix, and it carries no geometry;
 *  4. thx_surface_check (check.h) with opts->check;
 *  5. a surface that is closed, manifold and consistently oriented but
 *     encloses a negative volume (its solid angle about an interior point is
 *     -4 pi) has every triangle reversed (info->reversed) and is checked
 *     again: its triangles were clockwise seen from outside;
 *  6. any remaining failure (not closed, non-manifold, inconsistent
 *     orientation, duplicate or degenerate triangles, self-intersection,
 *     4 pi miss, quality limits of opts->check) refuses the surface
 *     (THX_ECHECK, *out NULL) unless opts->force, which returns it anyway
 *     with info->check_failed set.
 * Nothing else is changed: nodes are not moved, merged (except STL corners)
 * or re-triangulated.
 */
#ifndef THORAX_IMPORT_IMPORT_H
#define THORAX_IMPORT_IMPORT_H

#include "thorax/check/check.h"
#include "thorax/check/check_volume.h"
#include "thorax/io/surface_read.h"
#include "thorax/io/volume_read.h"
#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    thx_import_format format; /* default THX_IMPORT_AUTO */
    double scale;             /* coordinates are multiplied by this; default 1 (file in mm) */
    int force;                /* 1: return a surface that failed its checks (default 0: refuse) */
    thx_check_opts check;     /* options of thx_surface_check (its defaults) */
} thx_import_opts;

/* Fills *o with the defaults above. */
void thx_import_opts_default(thx_import_opts *o);

/* What reading and post-processing found. Plain data. */
typedef struct {
    thx_surface_read_info read; /* what thx_surface_read_file found (format, index base, counts as read) */
    size_t n_unused_removed;   /* nodes in no triangle, removed */
    long first_unused;         /* the first of them, numbered as in the file (its index base) */
    double scale;              /* the scale applied */
    double extent;             /* largest side of the bounding box after scaling (mm): a units hint */
    int reversed;              /* 1 if every triangle was reversed (policy step 5) */
    double omega_before;       /* when reversed: the solid angle found before (about -4 pi) */
    int check_failed;          /* 1 if the final check failed (returned only with opts->force) */
    thx_surface_report report; /* thx_surface_check of the surface as returned */
} thx_import_info;

/*
 * Reads, scales and checks one surface by the policy at the top of this file.
 * opts: NULL for the defaults. info (may be NULL) is overwritten, not freed
 * (call thx_import_info_free before reusing one), and filled as far as the
 * call got, including the check report (release it with thx_import_info_free).
 * Returns THX_OK and *out (caller destroys); THX_ECHECK when the surface
 * failed its checks and opts->force is 0 (then *out is NULL, info->report
 * says why and the context message names the file and the first reason);
 * or a reading error as thx_surface_read_file.
 */
thx_status thx_surface_import(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              const thx_import_opts *opts, thx_surface **out, thx_import_info *info);

/* Releases what info owns (its report) and zeroes it. Accepts NULL. */
void thx_import_info_free(thx_import_info *info);


/* ================================================================ volume meshes
 *
 * Tetrahedral meshes made by other programs (`thorax import MESH`), read
 * into a model: its volume (thorax/model/volume.h, with the region table) and the
 * surfaces the mesh's regions are bounded by (src/import/volume.c; the formats are
 * thorax/io/volume_read.h's).
 *
 * Import policy (thx_volume_import), in this order:
 *  1. read (every count is checked against what the file can hold before
 *     anything is allocated for it; every node number against the nodes);
 *  2. scale the coordinates;
 *  3. the region table: one region per distinct region number of the file,
 *     in increasing order (ids 1, 2, ...). Name: opts->region_maps, else
 *     the file's (Gmsh physical) name, else "region_N" (N the file's
 *     number); made of [A-Za-z0-9_.-], at most 31 characters (other
 *     characters become '_'), unique ("_2" ... appended). Conductivity:
 *     the map's isotropic sigma, else opts->default_region (reported as
 *     defaulted; with no default, such a region is an input error). A map
 *     for a region number the file does not have is an input error;
 *  4. nodes used by no tetrahedron are removed, the rest renumbered in
 *     order (reported);
 *  5. orientation: each tetrahedron with thx_orient3d > 0 (left-handed) has
 *     its last two nodes swapped (counted); a flat one (= 0, exact) refuses
 *     the file (THX_EGEOM), naming it;
 *  6. surfaces, from the faces (a face is in one tetrahedron: boundary; in
 *     two of different regions: interface; in three or more: ignored, the
 *     check then fails). Boundary faces, split into node-connected
 *     components, oriented outward of the mesh: a component of positive
 *     enclosed volume is a surface of role "outer" (named after the one
 *     region whose tetrahedra it bounds, else "outer"); of negative volume a
 *     "cavity" (reversed, so that it faces out of the hole; role heart,
 *     which `thorax check` takes as an excluded hole). Interface faces,
 *     split into node-connected components: a component is a surface of
 *     role "other" when it shares no node with the boundary, one region
 *     lies on the same side of all its faces and it passes
 *     thx_surface_check; it is oriented outward of the region inside it and
 *     named after that region ("interface" when the region is outside and
 *     several are inside). Components that fail are not stored (the reason
 *     is recorded in info->dropped; a model surface cannot share a node
 *     with another). A Gmsh file's named physical surface that holds every
 *     face of a surface names it. Surface names are unique ("_2" ...);
 *     surface nodes are volume nodes in increasing order (the node tables);
 *  7. thx_surface_check on the boundary surfaces (opts->check) and
 *     thx_volume_check of the volume against the model (opts->vcheck):
 *     any failure refuses the import (THX_ECHECK, *out NULL) unless
 *     opts->force, which returns the model with info->check_failed set.
 * Coordinates are not moved, nodes not merged, tetrahedra not added or
 * removed (other than reordering the nodes of left-handed ones).
 */

/* One --region option: the file's region number tag gets a name and/or an
 * isotropic conductivity. */
typedef struct {
    long long tag;
    char name[64];  /* "" keeps the default name */
    double sigma;   /* S/m; used when has_sigma */
    int has_sigma;
} thx_region_map;

typedef struct {
    thx_volume_format format;     /* THX_VOLFMT_NONE: thx_volume_format_from_path */
    const char *elem_path;        /* .pts: the element file; NULL: the .pts's name with .tet, else .elem
                                   * (a .tet or .elem given as path finds its .pts the same way; then
                                   * elem_path must be NULL) */
    const char *region_array;     /* .vtk/.vtu: the cell array of region numbers; NULL: by name (above) */
    double scale;                 /* default 1 (file in mm) */
    int force;                    /* 1: return a model that failed its checks (default 0: refuse) */
    size_t n_region_maps;
    const thx_region_map *region_maps; /* borrowed */
    thx_region default_region;    /* sigma/source of regions without a mapped conductivity (its name is
                                   * not used); default: none (sigma 0), and such a region is an error */
    thx_check_opts check;         /* thx_surface_check of the surfaces (defaults) */
    thx_volume_check_opts vcheck; /* thx_volume_check (defaults) */
} thx_volume_import_opts;

/* Fills *o with the defaults above. */
void thx_volume_import_opts_default(thx_volume_import_opts *o);

/* Where a region's name came from. */
typedef enum { THX_RNAME_DEFAULT = 0, THX_RNAME_FILE, THX_RNAME_OPTION } thx_region_name_source;

typedef struct {
    long long tag;              /* the file's region number */
    char file_name[128];        /* the file's name for it ("" if none), before cleaning */
    thx_region_name_source name_from;
    int sigma_defaulted;        /* conductivity from opts->default_region */
    size_t n_tets;
    double volume;              /* mm^3, after scaling */
} thx_volume_import_region;

typedef enum { THX_VSURF_BOUNDARY = 0, THX_VSURF_CAVITY, THX_VSURF_INTERFACE } thx_volume_surface_kind;

typedef struct {
    thx_volume_surface_kind kind;
    int inside, outside;        /* region indices (0-based) on either side; -1: several or none */
    int named_by_file;          /* named after a Gmsh physical surface */
} thx_volume_import_surface;

#define THX_VIMPORT_MAX_DROPPED 16

/* What reading and post-processing found. Owns regions, surfaces and the
 * reports (thx_volume_import_info_free). */
typedef struct {
    thx_volume_format format;
    char format_detail[96];     /* e.g. "legacy VTK binary UNSTRUCTURED_GRID", "Gmsh MSH 4.1 ASCII" */
    char path2[1024];           /* the other file read (the .tet/.elem or the .pts), else "" */
    int index_base;             /* base of the file's node numbers (0 or 1) */
    int index_base_detected;    /* 1 if detected from the data, 0 if fixed by the format */
    char region_source[160];    /* where the region numbers came from, e.g. "cell array \"region\"" */
    size_t n_nodes_read, n_tets_read;
    size_t n_cells_ignored;     /* cells/elements of dimension 0-2 skipped */
    size_t n_tris_named;        /* Gmsh triangles in named physical surfaces (used to name surfaces) */
    size_t n_unused_removed;    /* nodes in no tetrahedron, removed */
    long long first_unused;     /* the first of them, numbered as in the file */
    size_t n_flipped;           /* left-handed tetrahedra made right-handed */
    size_t n_nonconforming_faces; /* faces in three or more tetrahedra */
    double scale;
    double extent;              /* largest side of the bounding box after scaling (mm) */
    size_t n_regions;
    thx_volume_import_region *regions;   /* per region of the table, in its order */
    size_t n_surfaces;
    thx_volume_import_surface *surfaces; /* per surface of the model, in its order */
    thx_surface_report *surface_reports; /* per surface of the model: thx_surface_check */
    size_t n_dropped;           /* interface components not stored as surfaces */
    char dropped[THX_VIMPORT_MAX_DROPPED][256]; /* why (the first ones) */
    int volume_checked;
    thx_volume_report volume_report;
    int check_failed;           /* a check failed (returned only with opts->force) */
} thx_volume_import_info;

/*
 * Reads, orients and checks a volume mesh by the policy above and returns a
 * new model: its surfaces and m->volume (regions, node tables; no Steiner
 * records; no provenance). opts: NULL for the defaults. info (may be NULL)
 * is overwritten, not freed, and filled as far as the call got. Returns
 * THX_OK and *out (caller destroys); THX_ECHECK when a check failed and
 * opts->force is 0 (then *out is NULL, the context names the first reason);
 * THX_EINPUT for malformed files ("FILE:LINE: ...", "FILE: byte N: ...");
 * THX_EGEOM for flat tetrahedra; THX_EIO, THX_ENOMEM.
 */
thx_status thx_volume_import(thx_ctx *ctx, const char *path, const thx_volume_import_opts *opts, thx_model **out,
                             thx_volume_import_info *info);

/* Releases what info owns and zeroes it. Accepts NULL. */
void thx_volume_import_info_free(thx_volume_import_info *info);

#ifdef __cplusplus
}
#endif
#endif
