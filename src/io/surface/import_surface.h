/*
 * Private pieces shared by the surface readers (src/io/import*.c): the
 * growable node/triangle store every reader builds into (0-based indices,
 * range-checked as they arrive), error positions, and one scalar reader for
 * text or binary data (PLY, VTK). Not installed, not public; the entry point
 * is thx_surface_read_file (thorax/io/surface_read.h).
 */
#ifndef THORAX_IO_IMPORT_SURFACE_H
#define THORAX_IO_IMPORT_SURFACE_H

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/io/surface_read.h"
#include "thorax/core/fileio.h"
#include "io/common/import_text.h"

/* ------------------------------------------------------- the surface store */

typedef struct {
    thx_ctx *ctx;
    const char *path; /* the file being read (for messages) */
    const char *name; /* the surface (for messages) */
    double *xyz;
    size_t n_nodes, cap_nodes;
    int32_t *tri;
    size_t n_tris, cap_tris;
    size_t n_split;   /* polygons with > 3 vertices */
    size_t n_ignored; /* cells that are not polygons */
} build;

/* Where an error is: a line of text (line > 0) or a byte offset (line == 0). */
typedef struct { int line; size_t byte; } where;

static inline where at_line(int line) { where w = {line, 0}; return w; }
static inline where at_byte(size_t byte) { where w = {0, byte}; return w; }

static inline thx_status fail(build *b, where w, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static inline thx_status fail(build *b, where w, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (w.line > 0) return thx_error(b->ctx, THX_EINPUT, "%s:%d: surface \"%s\": %s", b->path, w.line, b->name, msg);
    return thx_error(b->ctx, THX_EINPUT, "%s: byte %zu: surface \"%s\": %s", b->path, w.byte, b->name, msg);
}

static inline thx_status add_node(build *b, where w, double x, double y, double z)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(z)) return fail(b, w, "node %zu has a non-finite coordinate", b->n_nodes + 1);
    if (b->n_nodes >= (size_t)INT32_MAX) return fail(b, w, "too many nodes");
    if (b->n_nodes + 1 > b->cap_nodes) THX_CHECK(thx_grow(b->ctx, (void **)&b->xyz, &b->cap_nodes, b->n_nodes + 1, 3 * sizeof *b->xyz));
    double *p = b->xyz + 3 * b->n_nodes++;
    p[0] = x, p[1] = y, p[2] = z;
    return THX_OK;
}

static inline thx_status add_tri(build *b, int32_t i, int32_t j, int32_t k)
{
    if (b->n_tris >= (size_t)INT32_MAX) return thx_error(b->ctx, THX_EINPUT, "%s: surface \"%s\": too many triangles", b->path, b->name);
    if (b->n_tris + 1 > b->cap_tris) THX_CHECK(thx_grow(b->ctx, (void **)&b->tri, &b->cap_tris, b->n_tris + 1, 3 * sizeof *b->tri));
    int32_t *t = b->tri + 3 * b->n_tris++;
    t[0] = i, t[1] = j, t[2] = k;
    return THX_OK;
}

/* A polygon of n 0-based node indices (already range-checked) as a fan. */
static inline thx_status add_polygon(build *b, where w, const int32_t *v, size_t n)
{
    if (n < 3) return fail(b, w, "a face needs at least 3 vertices, this one has %zu", n);
    if (n > 3) b->n_split++;
    for (size_t i = 1; i + 1 < n; i++) THX_CHECK(add_tri(b, v[0], v[i], v[i + 1]));
    return THX_OK;
}

/* Checks a 0-based index against the node count, naming it as the file numbers it. */
static inline thx_status check_index(build *b, where w, const char *obj, long long v, int base, size_t n_nodes, int32_t *out)
{
    /* obj names the face or cell ("triangle 3: "), or is "" */
    if (v < 0 || (unsigned long long)v >= n_nodes)
        return fail(b, w, "%snode number %lld out of range %d..%lld (%d-based, %zu nodes)", obj, v + base, base,
                    (long long)n_nodes - 1 + base, base, n_nodes);
    *out = (int32_t)v;
    return THX_OK;
}

/* Hands the store to a new surface. */
static inline thx_status finish(build *b, thx_role role, thx_surface **out)
{
    thx_surface *s = NULL;
    THX_CHECK(thx_surface_create(b->ctx, b->name, role, &s));
    s->xyz = b->xyz, s->n_nodes = b->n_nodes;
    s->tri = b->tri, s->n_tris = b->n_tris;
    b->xyz = NULL, b->tri = NULL;
    *out = s;
    return THX_OK;
}


/* Reads one scalar of type ty, as text (a token) or binary (big/little endian).
 * Sets *w to where it was. */
typedef struct {
    cursor c;
    int binary, big;
} source;

static inline thx_status read_scalar(build *b, source *s, scalar_type ty, const char *what, double *out, where *w)
{
    if (s->binary) {
        *w = at_byte(s->c.pos);
        if (s->c.len - s->c.pos < type_size[ty]) return fail(b, *w, "file ends inside %s", what);
        char big[32];
        if (int64_beyond((const unsigned char *)s->c.buf + s->c.pos, ty, s->big, big, sizeof big))
            return fail(b, *w, "%s: integer %s is beyond +-2^53 (too large for any index or count)", what, big);
        *out = get_scalar((const unsigned char *)s->c.buf + s->c.pos, ty, s->big);
        s->c.pos += type_size[ty];
        if (ty >= T_F32 && !isfinite(*out)) return fail(b, *w, "%s is not a finite number", what);
        return THX_OK;
    }
    const char *t;
    int line = s->c.line;
    size_t n = next_token(&s->c, &t, &line);
    *w = at_line(n ? line : s->c.line);
    if (!n) return fail(b, *w, "file ends before %s", what);
    int bad;
    if (ty >= T_F32) {
        bad = parse_num(t, n, out) != 0;
    } else {
        long long v = 0, lo, hi;
        type_range(ty, &lo, &hi);
        int pr = parse_i64(t, n, lo, hi, &v);
        if (pr == -2) return fail(b, *w, "%s: \"%s\" is out of range %lld..%lld", what, tok_show(t, n), lo, hi);
        bad = pr != 0;
        *out = (double)v;
    }
    if (bad)
        return fail(b, *w, "%s: \"%s\" is not %s", what, tok_show(t, n), ty >= T_F32 ? "a finite number" : "an integer");
    return THX_OK;
}

/* The legacy VTK cell reader (import_vtk.c), which the .vtp reader shares: adds the cells of one
 * section: kind 0 polygons, 1 triangle strips, 2 ignored. */
thx_status import_vtk_cells(build *b, int kind, const double *off, size_t n_cells, const double *conn, size_t n_conn,
                            int legacy, where w, int32_t **poly, size_t *pcap);

/* The readers, one per format (src/io/import_FORMAT.c): each fills b from the
 * whole file text[0, len) and the reading fields of info (may be NULL). */
thx_status import_read_tri(build *b, const char *text, size_t len, thx_surface_read_info *info);
thx_status import_read_obj(build *b, const char *text, size_t len, thx_surface_read_info *info);
thx_status import_read_stl(build *b, const char *text, size_t len, thx_surface_read_info *info);
thx_status import_read_ply(build *b, const char *text, size_t len, thx_surface_read_info *info);
thx_status import_read_vtk(build *b, const char *text, size_t len, thx_surface_read_info *info);
thx_status import_read_vtp(build *b, const char *text, size_t len, thx_surface_read_info *info);

#endif
