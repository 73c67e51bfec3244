/*
 * thorax/model.h — a model: the surfaces of one subject, and the directory that holds them.
 *
 * Model directory layout (docs/formats.md, "Model directory"):
 *   model.json   manifest: format version, units ("mm"), surfaces (name, role,
 *                files, node and triangle counts, an interior point), provenance
 *                (thorax version, command line, options, input file)
 *   NAME.pts     per surface: one node per line, "x y z" in mm
 *   NAME.fac     per surface: one triangle per line, three 1-based node numbers,
 *                counterclockwise seen from outside
 * Writing is atomic: the directory is built under a temporary name and renamed.
 */
#ifndef THORAX_MODEL_H
#define THORAX_MODEL_H

#include "thorax/geom.h"
#include "thorax/volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct thx_model {
    size_t n_surfaces;
    thx_surface **surf;      /* owned */
    int *has_interior;       /* per surface: 1 if interior[s] is a known interior point */
    thx_vec3 *interior;      /* per surface: a point inside it (for the 4 pi check) */
    char *provenance_json;   /* owned JSON text of the "provenance" object, or NULL */
    struct thx_volume *volume; /* owned tetrahedral mesh with regions (thorax/volume.h), or NULL */
} thx_model;

thx_status thx_model_create(thx_ctx *ctx, thx_model **out);
/* Frees the model and its surfaces; accepts NULL; nulls *m. */
void thx_model_destroy(thx_model **m);
/* Appends a surface; the model takes ownership of *s (and nulls *s) even on failure. */
thx_status thx_model_add_surface(thx_ctx *ctx, thx_model *m, thx_surface **s);

/* Writes the model directory atomically (replacing an existing one). */
thx_status thx_model_write(thx_ctx *ctx, const thx_model *m, const char *dir);
/* Reads a model directory written by thx_model_write. Caller destroys *out. */
thx_status thx_model_read(thx_ctx *ctx, const char *dir, thx_model **out);

/* Reads a .pts/.fac pair into a surface. The .fac index base (0 or 1) is
 * detected from the node count and reported in *base (pass NULL to ignore). */
thx_status thx_surface_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name,
                                   thx_role role, thx_surface **out, int *base);
/* Writes a .pts/.fac pair (1-based). Each file written atomically. */
thx_status thx_surface_write_ptsfac(thx_ctx *ctx, const thx_surface *s, const char *pts, const char *fac);

typedef enum { THX_EXPORT_VTK = 0, THX_EXPORT_VTP, THX_EXPORT_OBJ, THX_EXPORT_STL, THX_EXPORT_PLY } thx_export_format;
/* Parses "vtk", "vtp", "obj", "stl", "ply"; 0 on success. */
int thx_export_format_parse(const char *s, thx_export_format *out);
/* Writes one surface in the given format (atomically). */
thx_status thx_surface_export(thx_ctx *ctx, const thx_surface *s, thx_export_format fmt, const char *path);

#ifdef __cplusplus
}
#endif
#endif
