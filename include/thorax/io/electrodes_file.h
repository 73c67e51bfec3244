/*
 * thorax/io/electrodes_file.h — the electrode file (docs/formats.md, "Electrodes"; io layer).
 */
#ifndef THORAX_IO_ELECTRODES_FILE_H
#define THORAX_IO_ELECTRODES_FILE_H

#include "thorax/model/electrodes.h"
#include "thorax/model/model.h"

#ifdef __cplusplus
extern "C" {
#endif

thx_status thx_electrodes_read(thx_ctx *ctx, const char *path, thx_electrodes **out);
/* Atomic; nothing half-written on failure. An existing file at path is replaced only if thorax
 * wrote it (its first line, thx_atomic_open_output). An electrode between nodes is written with
 * node `-`. */
thx_status thx_electrodes_write(thx_ctx *ctx, const thx_electrodes *e, const char *path);

/* What an electrode source was read as (thx_electrodes_load). */
typedef enum {
    THX_ELECTRODES_FILE = 0, /* a thorax electrode file ("thorax-electrodes 1") */
    THX_ELECTRODES_LEADLINKS, /* map3d .leadlinks: "N leads", then "LABEL NODE" lines */
    THX_ELECTRODES_NODES,     /* a node list: one node number (1-based) a line; names N<node> */
    THX_ELECTRODES_POINTS     /* positions: "X Y Z" a line (mm, map3d .pts); names P1, P2, ... */
} thx_electrodes_kind;

/* "thorax electrode file", "map3d .leadlinks", "node list", "positions". */
const char *thx_electrodes_kind_name(thx_electrodes_kind k);

/*
 * Any electrode set, told by its content (src/io/electrodes_any.c), placed on its surface of m
 * (thx_electrodes_place: positions off the nodes projected, at most max_offset mm). The surface:
 * a thorax electrode file names its own (`surface`, if given, must agree); the others lie on
 * `surface`, or when NULL on the model's outer surface (role outer, exactly one). `#` starts a
 * comment in node lists and position files. *kind (may be NULL) says what the file was read as,
 * *max_moved (may be NULL) the farthest an electrode was moved onto the surface. Errors name the
 * file and line. Caller destroys *out.
 */
thx_status thx_electrodes_load(thx_ctx *ctx, const char *path, const thx_model *m, const char *surface,
                               double max_offset, thx_electrodes **out, thx_electrodes_kind *kind, double *max_moved);

#ifdef __cplusplus
}
#endif
#endif
