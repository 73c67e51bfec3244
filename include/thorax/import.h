/*
 * thorax/import.h — closed triangle surfaces made by other programs, read
 * into thx_surface and checked before they enter a model (`thorax import`).
 *
 * Formats (chosen by the file name's extension, case-insensitive, unless
 * opts->format says otherwise; docs/formats.md, "Importing surfaces made
 * elsewhere", has the details and examples):
 *   .pts + .fac  map3d / SCIRun pair; the .fac numbering (0- or 1-based) is
 *                detected by thx_surface_read_ptsfac and reported
 *   .tri         ECGSim / MBFYS (Oostendorp, van Oosterom) text triangulation:
 *                "npnt", npnt lines "label x y z", "ntri", ntri lines
 *                "label a b c"; labels optional (detected); indices 1-based
 *                by the format, 0-based accepted when an index 0 occurs; any
 *                text after the last triangle (the "descriptive trailers" of
 *                the PhysioNet 2007 files) is ignored. ECGSim documents its
 *                triangles as clockwise seen from outside: such files are
 *                reversed by the orientation policy below.
 *   .obj         Wavefront OBJ: v and f lines; f accepts v, v/vt, v//vn,
 *                v/vt/vn and negative (relative) indices; polygons with more
 *                than three vertices are split into fans (v0, vi, vi+1)
 *   .stl         binary (recognised by its size, 84 + 50 n bytes) or ASCII;
 *                facet corners with bit-identical coordinates become one node
 *   .ply         ascii, binary_little_endian, binary_big_endian; vertex x y z
 *                of any numeric type; face list "vertex_indices" (or
 *                "vertex_index"); other elements and properties skipped
 *   .vtk         legacy VTK POLYDATA, ASCII or BINARY (big-endian), file
 *                versions up to 5.1 (OFFSETS/CONNECTIVITY): POINTS, POLYGONS,
 *                TRIANGLE_STRIPS; VERTICES and LINES ignored; attributes
 *                (POINT_DATA, CELL_DATA) ignored
 *   .vtp         VTK XML PolyData with format="ascii" arrays (as `thorax
 *                export` writes); binary and appended data are refused
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
#ifndef THORAX_IMPORT_H
#define THORAX_IMPORT_H

#include "thorax/check.h"
#include "thorax/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_IMPORT_AUTO = 0, /* by the extension of the file name */
    THX_IMPORT_PTSFAC,
    THX_IMPORT_TRI,
    THX_IMPORT_OBJ,
    THX_IMPORT_STL,
    THX_IMPORT_PLY,
    THX_IMPORT_VTK,
    THX_IMPORT_VTP
} thx_import_format;

/* The format a file name's extension implies (THX_IMPORT_AUTO if none matches).
 * ".fac" counts as THX_IMPORT_PTSFAC (the .pts is then found beside it). */
thx_import_format thx_import_format_from_path(const char *path);
/* Parses "pts", "tri", "obj", "stl", "ply", "vtk", "vtp" ("fac" = "pts"); 0 on success. */
int thx_import_format_parse(const char *s, thx_import_format *out);
/* Short name: "pts/fac", "tri", "obj", ... (static storage). */
const char *thx_import_format_name(thx_import_format f);

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
    thx_import_format format;  /* the format read */
    char format_detail[64];    /* e.g. "binary STL", "ascii PLY", "ECGSim .tri (labelled lines)" */
    char path2[1024];          /* the second file read (the .fac or .pts of a pair), else "" */
    int index_base;            /* base of the file's node numbers: 0 or 1; -1 for STL (none) */
    int index_base_detected;   /* 1 if detected from the data (.fac, .tri), 0 if fixed by the format */
    size_t n_nodes_read;       /* as read (STL: after merging corners) */
    size_t n_tris_read;        /* as read, after splitting polygons into fans */
    size_t n_polygons_split;   /* faces with more than three vertices split into fans */
    size_t n_corners_merged;   /* STL: facet corners merged into existing nodes */
    size_t n_cells_ignored;    /* OBJ l/p lines, VTK VERTICES and LINES cells */
    int trailer_line;          /* .tri: first line of ignored text after the triangles, 0 if none */
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
 * Reads one surface file without any checks or changes beyond format
 * conversion (0-based indices in range, polygons split into fans, STL corners
 * merged). path2: for a .pts file the .fac (NULL: the same name with .fac;
 * for a .fac file given as path, the .pts beside it); ignored otherwise.
 * fmt: THX_IMPORT_AUTO to choose by extension. info (may be NULL) is
 * overwritten (not freed) with the reading fields. Caller destroys *out.
 * Returns THX_EINPUT for malformed files (message "FILE:LINE: ..." or
 * "FILE: byte N: ..."), THX_EIO, THX_ENOMEM.
 */
thx_status thx_surface_read_file(thx_ctx *ctx, const char *path, const char *path2, thx_import_format fmt,
                                 const char *name, thx_role role, thx_surface **out, thx_import_info *info);

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

#ifdef __cplusplus
}
#endif
#endif
