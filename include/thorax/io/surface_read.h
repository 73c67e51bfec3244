/*
 * thorax/io/surface_read.h — closed triangle surfaces in the files of other programs, read into
 * thx_surface as they are (io layer; thorax/import/import.h checks them before they enter a model).
 *
 * Formats (chosen by the file name's extension, case-insensitive, unless
 * opts->format says otherwise; docs/formats.md, "Importing surfaces made
 * elsewhere", has the details and examples):
 *   .pts + .fac  map3d / SCIRun pair; the .fac numbering (0- or 1-based) is
 *                detected by thx_surface_read_ptsfac and reported
 *   .tri         OpenMEEG, recognised by its first line "- NV": NV lines
 *                "x y z nx ny nz" (the normals must be numbers; they are not
 *                used), a line "- NT NT NT", NT lines "i j k" of 0-based
 *                vertex numbers; nothing may follow. Otherwise:
 *                ECGSim / MBFYS (Oostendorp, van Oosterom) text triangulation:
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
 *   .geom        map3d's legacy binary graphicsio file (thorax/io/graphicsio.h):
 *                one or more surfaces; "FILE.geom@N" (1-based) or "@NAME" picks
 *                one, and a file of several surfaces needs the pick; node
 *                numbers 1-based by the format
 *
 * Coordinates are returned as the file has them (thorax/import/import.h scales them).
 *
 */
#ifndef THORAX_IO_SURFACE_READ_H
#define THORAX_IO_SURFACE_READ_H

#include "thorax/model/surface.h"

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
    THX_IMPORT_VTP,
    THX_IMPORT_GEOM      /* map3d/CVRTI graphicsio .geom (thorax/io/graphicsio.h); FILE.geom@N or @NAME picks a surface */
} thx_import_format;

/* The format a file name's extension implies (THX_IMPORT_AUTO if none matches).
 * ".fac" counts as THX_IMPORT_PTSFAC (the .pts is then found beside it). */
thx_import_format thx_import_format_from_path(const char *path);
/* Parses "pts", "tri", "obj", "stl", "ply", "vtk", "vtp", "geom" ("fac" = "pts"); 0 on success. */
int thx_import_format_parse(const char *s, thx_import_format *out);
/* Short name: "pts/fac", "tri", "obj", ... (static storage). */
const char *thx_import_format_name(thx_import_format f);

/* What reading found (thx_surface_read_file). Plain data. */
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
} thx_surface_read_info;

/*
 * Reads one surface file without any checks or changes beyond format
 * conversion (0-based indices in range, polygons split into fans, STL corners
 * merged). path2: for a .pts file the .fac (NULL: the same name with .fac;
 * for a .fac file given as path, the .pts beside it); ignored otherwise.
 * fmt: THX_IMPORT_AUTO to choose by extension. info (may be NULL) is
 * overwritten. Caller destroys *out.
 * Returns THX_EINPUT for malformed files (message "FILE:LINE: ..." or
 * "FILE: byte N: ..."), THX_EIO, THX_ENOMEM.
 */
thx_status thx_surface_read_file(thx_ctx *ctx, const char *path, const char *path2, thx_import_format fmt,
                                 const char *name, thx_role role, thx_surface **out, thx_surface_read_info *info);

#ifdef __cplusplus
}
#endif
#endif
