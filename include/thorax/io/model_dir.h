/*
 * thorax/io/model_dir.h — the model directory (reading and writing a thx_model), surface
 * .pts/.fac files, and exports of surfaces and volumes to other programs' formats (io layer).
 *
 * Model directory layout (docs/formats.md, "Model directory"):
 *   model.json   manifest: format version, units ("mm"), surfaces (name, role,
 *                files, node and triangle counts, an interior point), the
 *                anatomical frame ("frame": {"superior": "+z", "anterior": "+y",
 *                "left": "-x"}; absent when unknown), provenance (thorax
 *                version, command line, options, input file)
 *   NAME.pts     per surface: one node per line, "x y z" in mm
 *   NAME.fac     per surface: one triangle per line, three 1-based node numbers,
 *                counterclockwise seen from outside
 * and, when the model has a volume mesh (m->volume; docs/formats.md, "Volume
 * mesh files"; paper 3.3):
 *   volume.pts   one volume node per line, "x y z" in mm
 *   volume.tet   one tetrahedron per line, "a b c d r": four 1-based volume
 *                node numbers, right-handed (((b-a) x (c-a)) . (d-a) > 0),
 *                then the 1-based region number
 *   NAME.vmap    per surface, one line per surface node: its 1-based volume
 *                node number (the node table; the reverse table is rebuilt)
 *   model.json   gains "volume" (files, counts, units, orientation), a "vmap"
 *                per surface, and "regions": the conductivity table (id,
 *                name, sigma in S/m as a number or a 3x3 tensor, source)
 * and, when the surfaces went through edits (m->edit_log; thorax/edit/edit.h, docs/formats.md
 * "Edit logs"; paper 3.2 "Manual editing"):
 *   edits.txt    the edit log, as m->edit_log holds it
 *   model.json   "provenance" gains "edit_log": "edits.txt" and "edit_log_sha256": its SHA-256
 *                (the writer sets both, or removes them when the model has no log)
 * Writing is atomic: the directory is built under a temporary name and renamed.
 */
#ifndef THORAX_IO_MODEL_DIR_H
#define THORAX_IO_MODEL_DIR_H

#include "thorax/core/fileio.h"
#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Writes the model directory atomically (replacing an existing one). A
 * volume (m->volume) is checked first and refused with the reason: node
 * numbers in range and distinct per tetrahedron, region numbers in the
 * table, region names unique ([A-Za-z0-9_.-], at most 31 characters),
 * conductivities positive / tensors symmetric positive definite, one node
 * table per surface with each surface node on a volume node of the same
 * coordinates ("%.6f") and no volume node on two surface nodes. A surface
 * may not be called "volume" then. Geometry (orientation, quality) is not
 * checked here: that is the volume checker's. */
thx_status thx_model_write(thx_ctx *ctx, const thx_model *m, const char *dir);
/* The same into a directory claimed earlier (thx_outdir_claim with manifest
 * model.json, format THX_MODEL_FORMAT): a command claims its output before it
 * reads and computes, so that a directory another command writes meanwhile is
 * never replaced (thorax/core/fileio.h). thx_model_write claims dir itself. */
#define THX_MODEL_MANIFEST "model.json"
#define THX_MODEL_EDIT_LOG "edits.txt"
#define THX_MODEL_FORMAT "thorax-model"
thx_status thx_model_write_claimed(thx_ctx *ctx, const thx_model *m, thx_outdir *od);
/* Reads a model directory written by thx_model_write, with its volume if
 * the manifest has one; every file is validated as the writer validates
 * memory, and errors name the file and line ("volume.tet:17: region 4 out of
 * range 1..3"). The manifest is read strictly: a NUL byte, an unknown or
 * repeated key, a value of the wrong type, a count that disagrees with its
 * file or a bad frame is refused, naming model.json and the key (and the
 * surface); nothing is returned half-read. A manifest without "frame" gives
 * frame.set = 0. An edit log the provenance names is read into m->edit_log, refused when missing,
 * holding a NUL byte, over 64 MiB or not of the recorded SHA-256. Caller destroys *out. */
thx_status thx_model_read(thx_ctx *ctx, const char *dir, thx_model **out);
/* The same without the volume mesh's files: m->volume holds the region table alone (no nodes, no
 * tetrahedra, no node tables), for a reader that takes its part of the volume from elsewhere (a rank
 * of sort-last rendering reading its part of a solution, thorax/fem/parts.h). */
thx_status thx_model_read_regions_only(thx_ctx *ctx, const char *dir, thx_model **out);

/* Reads a .pts/.fac pair into a surface. The .fac index base (0 or 1) is
 * detected from the node count and reported in *base (pass NULL to ignore). */
thx_status thx_surface_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name,
                                   thx_role role, thx_surface **out, int *base);
/* Writes a .pts/.fac pair (1-based). Each file written atomically. */
thx_status thx_surface_write_ptsfac(thx_ctx *ctx, const thx_surface *s, const char *pts, const char *fac);
/* The value a coordinate v reads back as from a NAME.pts file thx_surface_write_ptsfac wrote ("%.6f";
 * a value that rounds to zero reads back as +0). `thorax mesh` checks its surfaces at these values, so
 * that the verdict it keeps covers the files (thorax/check/verdict.h). */
double thx_surface_stored_coord(double v);

/* Export formats: surface formats (VTK ... PLY), then volume formats (VTU, MSH). */
typedef enum {
    THX_EXPORT_VTK = 0,
    THX_EXPORT_VTP,
    THX_EXPORT_OBJ,
    THX_EXPORT_STL,
    THX_EXPORT_PLY,
    THX_EXPORT_VTU, /* volume: VTK XML UnstructuredGrid */
    THX_EXPORT_MSH  /* volume: Gmsh MSH 4.1 ASCII */
} thx_export_format;
/* Parses "vtk", "vtp", "obj", "stl", "ply", "vtu", "msh"; 0 on success. */
int thx_export_format_parse(const char *s, thx_export_format *out);
/* Whether fmt is a volume format (vtu, msh) rather than a surface format. */
int thx_export_format_is_volume(thx_export_format fmt);
/* Writes one surface in a surface format (atomically); a volume format is an
 * input error. */
thx_status thx_surface_export(thx_ctx *ctx, const thx_surface *s, thx_export_format fmt, const char *path);
/* Checks, writing nothing, that thx_surface_export or thx_volume_export may write path: absent,
 * empty or thorax's own export of this format (its signature in the first 4096 bytes), a regular
 * file, not a link, not an input (thorax/core/fileio.h). A command writing several files claims all first. */
thx_status thx_export_claim(thx_ctx *ctx, thx_export_format fmt, const char *path);
/*
 * Writes the model's volume mesh (m->volume; THX_EINPUT if there is none) in
 * a volume format, atomically, after the checks of thx_model_write:
 *   THX_EXPORT_VTU  VTK XML UnstructuredGrid, ASCII inline: Float64 points
 *                   (mm, "%.6f"), tetrahedra (cell type 10) with 0-based
 *                   connectivity in volume.tet's order, cell data "region"
 *                   (Int32, 1-based region id), point data "surface" (Int32,
 *                   1-based surface index, 0 for an interior node) and
 *                   "surface_node" (Int32, 1-based node number on it, 0).
 *   THX_EXPORT_MSH  Gmsh MSH 4.1 ASCII: one physical group ($PhysicalNames,
 *                   dimension 3, tag = region id, the region's name) and one
 *                   volume entity (same tag) per region; node tags = volume
 *                   node numbers, element tags = volume.tet line numbers,
 *                   elements of type 4 (4-node tetrahedron).
 * Both keep the right-handed node order. Output is byte-identical for the
 * same model.
 */
thx_status thx_volume_export(thx_ctx *ctx, const thx_model *m, thx_export_format fmt, const char *path);

#ifdef __cplusplus
}
#endif
#endif
