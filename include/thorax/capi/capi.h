/*
 * thorax/capi/capi.h — flat accessors for bindings (ctypes, cffi, other languages).
 *
 * The library's structs (thx_model, thx_surface, thx_series, thx_volume) are plain C structs whose
 * layout may change between versions; a binding that mirrored them would break silently. These
 * functions take and return only opaque pointers, sizes, C strings and caller-allocated arrays,
 * so a binding needs no struct layout at all (python/thorax uses them; docs/decisions.md,
 * "An installable library").
 *
 * Conventions, as everywhere: a thx_ctx * first, a thx_status back, the message in the context.
 * Arrays are the caller's, sized from the matching *_info / *_shape call; indices are 0-based;
 * millimetres; series values row-major here (values[r * n_frames + f], as NumPy's C order gives
 * for a rows x frames array), although thx_series stores them frame by frame.
 * Strings returned are owned by the object they describe and live as long as it does.
 */
#ifndef THORAX_CAPI_CAPI_H
#define THORAX_CAPI_CAPI_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"
#include "thorax/model/model.h"
#include "thorax/model/series.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The library's version, "MAJOR.MINOR.PATCH" (static storage). */
const char *thx_capi_version(void);

/* ---- models (read with thx_model_read, written with thx_model_write) ---- */

/* Number of surfaces of m. */
size_t thx_capi_model_n_surfaces(const thx_model *m);
/* Surface s of m: its name, role ("outer", "heart", ...), node and triangle counts (any output may
 * be NULL). THX_EINPUT when s is out of range. */
thx_status thx_capi_surface_info(thx_ctx *ctx, const thx_model *m, size_t s, const char **name, const char **role,
                                 size_t *n_nodes, size_t *n_tris);
/* Copies surface s's nodes (n_nodes x 3, mm) into xyz and its triangles (n_tris x 3, 0-based,
 * counterclockwise seen from outside) into tri; either may be NULL. */
thx_status thx_capi_surface_copy(thx_ctx *ctx, const thx_model *m, size_t s, double *xyz, int32_t *tri);
/* Index of the surface named name, or of the first surface of role role_name when name is NULL;
 * THX_EINPUT (naming what was sought) when there is none. */
thx_status thx_capi_surface_find(thx_ctx *ctx, const thx_model *m, const char *name, const char *role_name,
                                 size_t *index);
/* The volume mesh's counts (all 0 when m has none). */
void thx_capi_volume_info(const thx_model *m, size_t *n_nodes, size_t *n_tets, size_t *n_regions);
/* Copies the volume's nodes (n_nodes x 3), tetrahedra (n_tets x 4, 0-based) and each tetrahedron's
 * region (0-based into the region table); any may be NULL. THX_EINPUT when m has no volume. */
thx_status thx_capi_volume_copy(thx_ctx *ctx, const thx_model *m, double *xyz, int32_t *tet, int32_t *region);
/* Region r of the volume: its name and conductivity tensor (9 values, S/m, row-major; any output
 * may be NULL). THX_EINPUT when r is out of range. */
thx_status thx_capi_region_info(thx_ctx *ctx, const thx_model *m, size_t r, const char **name, double sigma[9]);

/* ---- series (read with thx_series_read, written with thx_series_write) ---- */

/* Rows and frames of s. */
void thx_capi_series_shape(const thx_series *s, size_t *n_rows, size_t *n_frames);
/* The unit of the values and of the time axis ("" when unknown). */
const char *thx_capi_series_unit(const thx_series *s);
const char *thx_capi_series_time_unit(const thx_series *s);
/* Copies the values (row-major, n_rows x n_frames) and the times (n_frames) out; either may be NULL. */
void thx_capi_series_copy(const thx_series *s, double *values, double *time);
/* A new series from row-major values (n_rows x n_frames); time NULL gives 0, 1, 2 ... ms; unit and
 * time_unit NULL give "" and "ms". Refuses NaN/Inf values and times that do not increase (the
 * invariants thx_series_validate states), naming the row and frame. Caller destroys *out. */
thx_status thx_capi_series_from(thx_ctx *ctx, size_t n_rows, size_t n_frames, const double *values,
                                const double *time, const char *unit, const char *time_unit, thx_series **out);

/* ---- meshing and forward solutions ---- */

/* Meshes m's volume in place as `thorax mesh` does with its defaults (grid spacing grid_mm, 0 = the
 * default for the model), then checks the volume as thorax check does and refuses one that fails
 * (THX_ECHECK, the reasons in the message), leaving m->volume NULL then. n_nodes, n_tets may be NULL. */
thx_status thx_capi_mesh(thx_ctx *ctx, thx_model *m, double grid_mm, size_t *n_nodes, size_t *n_tets);

/* The epicardial forward problem, as `thorax forward MODEL --epicardial SERIES` solves it: the
 * potentials of epi (rows: the heart surface's nodes) prescribed on the heart, the potentials of the
 * outer surface's nodes returned in *torso (rows x epi's frames; caller destroys). The volume is
 * checked first, as the CLI does (THX_ECHECK with the reasons when it fails). Starts PETSc on first
 * use, without its signal handlers (options from the PETSC_OPTIONS environment variable); PETSc
 * stays up until the process ends or thx_capi_finalize. */
thx_status thx_capi_forward(thx_ctx *ctx, const thx_model *m, const thx_series *epi, thx_series **torso);
/* Ends what thx_capi_forward started (PETSc); harmless when nothing was started. */
void thx_capi_finalize(void);

#ifdef __cplusplus
}
#endif
#endif
