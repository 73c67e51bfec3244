/*
 * thorax/io/graphicsio.h — the legacy CVRTI "graphicsio" binary files of map3d (io layer):
 * .geom (surfaces: nodes and triangles) and .tsdf (time series: leads x frames, with fiducials).
 *
 * Layout (docs/formats.md, "map3d graphicsio files", from the files in ../shared/data/map3d
 * and map3d's graphicsio library, removed in its commit eae9c3d):
 *   - integers: 32-bit two's complement, little-endian (VAX order, whatever the writer's host);
 *   - reals: VAX F_floating, 4 bytes: two 16-bit little-endian words, the high word first
 *     (sign, 8-bit exponent biased by 128, 7 fraction bits), value 0.1f x 2^(e-128); e = 0
 *     is zero, or with the sign bit the VAX "reserved operand" (refused);
 *   - a file header (40 bytes, 44 with the audit string pointer): header size, file type,
 *     file info block offset, surface count, first surface header, bounding surface count and
 *     header, time series count and first header, preferred settings, audit string;
 *   - linked blocks at absolute byte offsets: surface headers -> node and element headers ->
 *     nodes (x y z reals) and elements (1-based node numbers); time series headers (308, 324
 *     or 336 bytes) -> data (frame-major reals, or 16-bit integers), power curve, fiducials.
 * Every offset and count is checked against the file's length before anything is allocated;
 * errors name the file, the byte offset and the object ("x.tsdf: byte 472: time series 1: ...").
 *
 * Selection: a file holding several surfaces or time series needs one picked, FILE@N (1-based)
 * or FILE@NAME (the surface's name or the series' label); a file of one needs none.
 */
#ifndef THORAX_IO_GRAPHICSIO_H
#define THORAX_IO_GRAPHICSIO_H

#include <stddef.h>

#include "thorax/model/series.h"
#include "thorax/model/surface.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What thx_geom_parse found. Plain data. */
typedef struct {
    size_t n_surfaces;  /* surfaces in the file */
    size_t index;       /* the one read, 1-based */
    char file_name[80]; /* its name in the file ("" in every real file seen) */
    char text[256];     /* the file info block's text */
} thx_geom_info;

/*
 * Reads one surface of a .geom file held in buf[0, len). path names the file in messages.
 * select: NULL or "" (the file must hold one surface), "N" (1-based) or a surface name.
 * Triangles are returned 0-based, in the file's order and orientation; coordinates as stored.
 * Caller destroys *out. THX_EINPUT for a malformed file or a bad selection.
 */
thx_status thx_geom_parse(thx_ctx *ctx, const char *path, const unsigned char *buf, size_t len, const char *select,
                          const char *name, thx_role role, thx_surface **out, thx_geom_info *info);

/*
 * Reads one time series of a .tsdf file held in buf[0, len) (select as above: "N" or a label).
 * Rows = leads (channels), frames as stored; the time axis is the frame number from 0 (time_unit
 * "frame": the format holds no sampling rate); unit from the header's data units (1 mV, 2 uV,
 * 3 ms, 4 V, 5 mV ms; 0 unknown); label from the series label, else the file's text; the
 * header's q/s/t times and extended fiducials (P onset/offset, R peak, T peak), when set
 * (non-zero), become global fiducials (qon, soff, toff, pon, poff, rpeak, tpeak), minus 1.
 * Data kept in an external file (raw/pak tapes) are refused. Caller destroys *out.
 */
thx_status thx_tsdf_parse(thx_ctx *ctx, const char *path, const unsigned char *buf, size_t len, const char *select,
                          thx_series **out);

/* Splits "FILE@SEL" when FILE has the extension ext (case-insensitive, e.g. "geom") and a file of
 * the whole name does not exist: copies FILE into file (cap bytes) and points *sel into path (or
 * NULL). Returns 0, or -1 when the path does not fit. */
int thx_gio_split_select(const char *path, const char *ext, char *file, size_t cap, const char **sel);

#ifdef __cplusplus
}
#endif
#endif
