/*
 * Strict reading of contour files (thorax/check/contours.h): the file's structure, then every
 * loop's geometry.
 */
#include "thorax/check/contours.h"

#include "thorax/geom/contours_valid.h"
#include "thorax/io/contours_file.h"

static thx_status validated(thx_ctx *ctx, thx_status st, thx_contours **out)
{
    if (st == THX_OK) st = thx_contours_validate(ctx, *out);
    if (st != THX_OK) thx_contours_destroy(out);
    return st;
}

thx_status thx_contours_read(thx_ctx *ctx, const char *path, thx_contours **out)
{
    return validated(ctx, thx_contours_read_raw(ctx, path, out), out);
}

thx_status thx_contours_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out)
{
    return validated(ctx, thx_contours_parse_raw(ctx, name, text, len, out), out);
}
