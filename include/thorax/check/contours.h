/*
 * thorax/check/contours.h — strict reading of contour files: the file's structure (thorax/io/
 * contours_file.h) and then the loops' geometry (thorax/geom/contours_valid.h), so that what is
 * returned holds every invariant of thorax/model/contours.h.
 */
#ifndef THORAX_CHECK_CONTOURS_H
#define THORAX_CHECK_CONTOURS_H

#include "thorax/model/contours.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads and validates a contour file. On error the message names file and line
 * and, where known, surface and layer. Caller destroys *out. */
thx_status thx_contours_read(thx_ctx *ctx, const char *path, thx_contours **out);
/* Parses contour text held in memory; `name` is used in messages. */
thx_status thx_contours_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out);

#ifdef __cplusplus
}
#endif
#endif
