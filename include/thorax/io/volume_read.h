/*
 * thorax/io/volume_read.h — tetrahedral meshes in the files of other programs, read as they are
 * (io layer; thorax/import/import.h turns one into a model).
 *
 * Formats (thx_volume_format_from_path decides; docs/formats.md, "Importing
 * volume meshes made elsewhere", has examples):
 *   .pts + .tet/.elem  node lines "x y z"; element lines "a b c d [region]"
 *                (every line the same number of columns); node numbers 0-
 *                or 1-based, detected as for .fac files (a 0 means 0-based;
 *                else the largest equal to the node count means 1-based;
 *                else refused as ambiguous) and reported. CARP / openCARP:
 *                a count line first in either file, and "Tt a b c d
 *                [region]" element lines, 0-based by the format; other
 *                element types (Tr, Qd, Hx, Pr, Py, Ln) are refused.
 *   .vtk         legacy VTK UNSTRUCTURED_GRID, ASCII or BINARY (big-endian),
 *                classic CELLS or file version 5.1 OFFSETS/CONNECTIVITY;
 *                cells of type 10 (tetrahedron) are read, cells of
 *                dimension 0-2 (vertices, lines, triangles, quads, ...)
 *                skipped and counted, any other cell type refused; regions
 *                from a one-component cell-data array (SCALARS or FIELD)
 *   .vtu         VTK XML UnstructuredGrid: DataArrays ascii, binary (base64)
 *                or appended (raw or base64), UInt32 or UInt64 headers,
 *                either byte order, uncompressed or zlib-compressed
 *                (vtkZLibDataCompressor; other compressors are refused);
 *                one <Piece>; cell types as for .vtk
 *   .msh         Gmsh MSH 4.1 ASCII: $Nodes, $Elements of type 4 (4-node
 *                tetrahedron) in volume entities, regions = the entity's
 *                physical group (dimension 3; $Entities), named by
 *                $PhysicalNames; without physical groups, the entity tags.
 *                Triangles (type 2) in surface entities with a named
 *                physical group name the surfaces they cover; other
 *                elements of dimension 0-2 are skipped; other 3-D element
 *                types, MSH 2.x/4.0, binary files and partitioned meshes are
 *                refused.
 * Region arrays of VTK files: opts->region_array if given; else the first
 * one-component cell array named (case-insensitively) "region", "regions",
 * "gmsh:physical", "CellEntityIds", "material", "materials", "MaterialIds",
 * "tissue", "elemTag" or "tag"; else the only one with integral values;
 * else every tetrahedron is in one region. Region numbers must be integers.
 *
 */
#ifndef THORAX_IO_VOLUME_READ_H
#define THORAX_IO_VOLUME_READ_H

#include <stdint.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_VOLFMT_NONE = 0, /* not a volume mesh: a surface file */
    THX_VOLFMT_PTS,      /* .pts + .tet or .elem (plain or CARP) */
    THX_VOLFMT_VTK,      /* legacy VTK UNSTRUCTURED_GRID */
    THX_VOLFMT_VTU,      /* VTK XML UnstructuredGrid */
    THX_VOLFMT_MSH       /* Gmsh MSH 4.1 ASCII */
} thx_volume_format;

/* The volume format of a file: .msh, .vtu, .tet, .elem by extension
 * (case-insensitive); .vtk when its DATASET line says UNSTRUCTURED_GRID;
 * .pts when no .fac is beside it but a .tet or .elem is. THX_VOLFMT_NONE
 * otherwise (a surface format, or a file that cannot be opened). */
thx_volume_format thx_volume_format_from_path(const char *path);
/* Parses "tet", "elem", "carp" (THX_VOLFMT_PTS), "vtu", "msh"; "vtk" gives
 * THX_VOLFMT_VTK (the caller decides by content whether a .vtk is a surface
 * or a volume). 0 on success, -1 otherwise. */
int thx_volume_format_parse(const char *s, thx_volume_format *out);
/* "pts/tet", "vtk", "vtu", "msh" (static storage). */
const char *thx_volume_format_name(thx_volume_format f);

/* A Gmsh physical name: dimension (2: surface, 3: volume), tag, name. */
typedef struct {
    int dim;
    long long tag;
    char name[128];
} thx_volume_file_name;

/*
 * A volume mesh as its file holds it (thx_volume_file_read): nodes, tetrahedra with 0-based nodes
 * checked against the node count, the file's region number of each tetrahedron, where the file has
 * each one (a line, a VTK cell index or a Gmsh element tag: ref_kind), Gmsh's triangles in named
 * physical surfaces and its physical names. Plain data; the cap_ fields are the arrays' capacities
 * while reading. thx_volume_file_free releases the arrays.
 */
typedef struct thx_volume_file {
    thx_ctx *ctx;         /* the reading's context (messages) */
    const char *path;     /* the file being read (for messages; borrowed) */
    double *xyz;
    size_t n_nodes, cap_nodes;
    long long *node_tag;  /* Gmsh: the file's node tags (else NULL: nodes are numbered by position) */
    size_t cap_node_tag;
    int32_t *tet;         /* 4 per tetrahedron, 0-based */
    long long *tag;       /* per tetrahedron: the file's region number (0 when has_tags is 0) */
    long long *ref;       /* per tetrahedron: where the file has it (ref_kind) */
    size_t n_tets, cap_tets, cap_tag, cap_ref;
    const char *ref_kind; /* "line", "cell", "element" */
    int has_tags;
    int32_t *tri;         /* Gmsh triangles of named physical surfaces (0-based nodes) */
    long long *tri_tag;
    size_t n_tris, cap_tri, cap_tri_tag;
    thx_volume_file_name *names; /* Gmsh physical names, dimensions 2 and 3 */
    size_t n_names, cap_names;
    size_t n_ignored;     /* cells of dimension 0-2 */
    char detail[96];      /* e.g. "legacy VTK binary UNSTRUCTURED_GRID", "Gmsh MSH 4.1 ASCII" */
    char region_source[160]; /* where the region numbers came from, e.g. "cell array \"region\"" */
    int index_base, index_base_detected;
    char path2[1024];     /* the other file read (the .tet/.elem or the .pts), else "" */
} thx_volume_file;

/*
 * Reads a volume mesh file into *f (overwritten; release it with thx_volume_file_free whatever the
 * result). fmt: THX_VOLFMT_NONE to decide by thx_volume_format_from_path. elem_path, region_array:
 * as thx_volume_import_opts's (NULL for the defaults). Every count is checked against what the file
 * can hold before anything is allocated for it; every node number against the nodes; nothing is
 * accepted in part. THX_EINPUT ("FILE:LINE: ...", "FILE: byte N: ..."), THX_EIO, THX_ENOMEM.
 */
thx_status thx_volume_file_read(thx_ctx *ctx, const char *path, thx_volume_format fmt, const char *elem_path,
                                const char *region_array, thx_volume_file *f);
void thx_volume_file_free(thx_volume_file *f);
/* The Gmsh physical name of (dim, tag), or NULL. */
const char *thx_volume_file_name_of(const thx_volume_file *f, int dim, long long tag);

#ifdef __cplusplus
}
#endif
#endif
