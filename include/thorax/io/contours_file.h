/*
 * thorax/io/contours_file.h — the contour file (docs/formats.md, "Contour files"): reading and
 * writing thx_contours (io layer).
 *
 * The reader is bounded and reads nothing in part: a NUL byte, a number with
 * trailing characters, hex/inf/nan or a value out of range, a layer without
 * loops, a loop cut short and a file without its 'end' line are refused, with
 * file:line and the surface, layer and loop concerned. Memory is a small
 * multiple of the file's size (no count is read from the file).
 * The readers here check the structure (thx_contours_validate_structure); the strict reading
 * that also checks the loops' geometry is thx_contours_read (thorax/check/contours.h).
 */
#ifndef THORAX_IO_CONTOURS_FILE_H
#define THORAX_IO_CONTOURS_FILE_H

#include "thorax/model/contours.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a contour file, checking its structure only (not repeated points nor self-intersections:
 * what thx_contours_repair mends). On error the message names file and line and, where known,
 * surface, layer and loop. Caller destroys *out. */
thx_status thx_contours_read_raw(thx_ctx *ctx, const char *path, thx_contours **out);
/* The same for contour text held in memory; `name` is used in messages. */
thx_status thx_contours_parse_raw(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out);
/* Writes contours in the text format, atomically (temporary file + rename); the frame line
 * ("frame UP FRONT") when c->frame.set. */
thx_status thx_contours_write(thx_ctx *ctx, const thx_contours *c, const char *path, const char *comment);

#ifdef __cplusplus
}
#endif
#endif
