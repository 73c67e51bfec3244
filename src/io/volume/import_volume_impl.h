/*
 * Private pieces shared by the volume-mesh readers (src/io/import_vol_*.c,
 * dispatched by src/io/import_volume.c): the mesh store every reader fills
 * (thx_volume_file, called raw here), error positions, line tokens, and the
 * VTK cell handling shared by the legacy and XML VTK readers. Not installed,
 * not public; the entry point is thx_volume_file_read (thorax/io/volume_read.h).
 */
#ifndef THORAX_IO_IMPORT_VOLUME_IMPL_H
#define THORAX_IO_IMPORT_VOLUME_IMPL_H

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

#include "io/common/import_text.h"
#include "thorax/core/fileio.h"
#include "thorax/io/volume_read.h"
/* Can path be opened for reading? */
static inline int readable(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    fclose(f);
    return 1;
}

/* path with its extension replaced by ext (in upper case if the old one
 * starts upper case); 0, or -1 if it does not fit or there is none. */
static inline int with_extension(char *out, size_t size, const char *path, const char *ext)
{
    const char *old = path_extension(path);
    if (!old[0]) return -1;
    size_t stem = (size_t)(old - path), el = strlen(ext);
    if (stem + el + 1 > size) return -1;
    memcpy(out, path, stem);
    for (size_t i = 0; i < el; i++)
        out[stem + i] = isupper((unsigned char)old[0]) ? (char)toupper((unsigned char)ext[i]) : ext[i];
    out[stem + el] = '\0';
    return 0;
}

/* ------------------------------------------------------- the mesh store */

/* The mesh store every reader fills (thorax/io/volume_read.h). */
typedef thx_volume_file raw;
typedef thx_volume_file_name tag_name;

/* Where an error is: a line of text (line > 0), a byte offset (line == 0,
 * byte != NOWHERE) or the file as a whole. */
typedef struct { int line; size_t byte; } where;
#define NOWHERE ((size_t)-1)
static inline where at_line(int line) { where w = {line, NOWHERE}; return w; }
static inline where at_byte(size_t byte) { where w = {0, byte}; return w; }
static inline where at_file(void) { where w = {0, NOWHERE}; return w; }

static inline thx_status fail(raw *r, where w, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static inline thx_status fail(raw *r, where w, const char *fmt, ...)
{
    char msg[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (w.line > 0) return thx_error(r->ctx, THX_EINPUT, "%s:%d: %s", r->path, w.line, msg);
    if (w.byte != NOWHERE) return thx_error(r->ctx, THX_EINPUT, "%s: byte %zu: %s", r->path, w.byte, msg);
    return thx_error(r->ctx, THX_EINPUT, "%s: %s", r->path, msg);
}

static inline thx_status add_node(raw *r, where w, double x, double y, double z)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(z)) return fail(r, w, "node %zu has a non-finite coordinate", r->n_nodes + 1);
    if (r->n_nodes >= (size_t)INT32_MAX) return fail(r, w, "too many nodes");
    if (r->n_nodes + 1 > r->cap_nodes) THX_CHECK(thx_grow(r->ctx, (void **)&r->xyz, &r->cap_nodes, r->n_nodes + 1, 3 * sizeof *r->xyz));
    double *p = r->xyz + 3 * r->n_nodes++;
    p[0] = x, p[1] = y, p[2] = z;
    return THX_OK;
}

/* Adds a tetrahedron of four 0-based nodes already checked against n_nodes. */
static inline thx_status add_tet(raw *r, const int32_t v[4], long long tag, long long ref)
{
    if (r->n_tets >= (size_t)INT32_MAX / 4) return fail(r, at_file(), "too many tetrahedra");
    size_t need = r->n_tets + 1;
    if (need > r->cap_tets) THX_CHECK(thx_grow(r->ctx, (void **)&r->tet, &r->cap_tets, need, 4 * sizeof *r->tet));
    if (need > r->cap_tag) THX_CHECK(thx_grow(r->ctx, (void **)&r->tag, &r->cap_tag, need, sizeof *r->tag));
    if (need > r->cap_ref) THX_CHECK(thx_grow(r->ctx, (void **)&r->ref, &r->cap_ref, need, sizeof *r->ref));
    memcpy(r->tet + 4 * r->n_tets, v, 4 * sizeof *v);
    r->tag[r->n_tets] = tag;
    r->ref[r->n_tets] = ref;
    r->n_tets++;
    return THX_OK;
}

static inline thx_status add_name(raw *r, int dim, long long tag, const char *name, size_t n)
{
    if (r->n_names + 1 > r->cap_names)
        THX_CHECK(thx_grow(r->ctx, (void **)&r->names, &r->cap_names, r->n_names + 1, sizeof *r->names));
    tag_name *e = &r->names[r->n_names++];
    e->dim = dim;
    e->tag = tag;
    copy_tok(e->name, sizeof e->name, name, n);
    return THX_OK;
}

static inline const char *name_of(const raw *r, int dim, long long tag) { return thx_volume_file_name_of(r, dim, tag); }

/* The tokens of the current line, from the cursor to the line's end (at
 * most max kept); returns how many there are (possibly more than max). */
typedef struct { const char *t; size_t n; } tok;
static inline size_t line_tokens(cursor *c, tok *tk, size_t max)
{
    size_t k = 0;
    const char *t;
    size_t n;
    while ((n = line_token(c, &t)) != 0) {
        if (k < max) tk[k].t = t, tk[k].n = n;
        k++;
    }
    return k;
}

/* Moves to the next line that is not blank (from the current position,
 * which may be the start of such a line); 0 at the end of the text. */
static inline int to_filled_line(cursor *c)
{
    for (;;) {
        size_t p = c->pos;
        while (p < c->len && is_blank(c->buf[p])) p++;
        if (p < c->len && c->buf[p] != '\n') return 1;
        if (!next_line(c)) return 0;
    }
}

/* Reads the next non-blank line's tokens (see line_tokens) and moves past
 * it; returns the token count, 0 at the end of the text (*line: its line). */
static inline size_t read_line(cursor *c, tok *tk, size_t max, int *line)
{
    if (!to_filled_line(c)) {
        *line = c->line;
        return 0;
    }
    *line = c->line;
    size_t k = line_tokens(c, tk, max);
    next_line(c);
    return k;
}

static inline int tk_int(const tok *t, long long *v) { return parse_int(t->t, t->n, v); }


/* ------------------------------------------ VTK cells (import_vol_vtk.c) */

/* A candidate region array: one value per cell. */
typedef struct {
    char name[128];
    double *v;
    size_t n;
} cell_array;

/* Chooses the region array (index into a, or -1) by the rule in import.h. */
thx_status vol_choose_region_array(raw *r, const cell_array *a, size_t n, const char *want, int *out);
/* Turns cells (VTK types, offsets into conn) into tetrahedra, with the
 * region array reg (NULL: one region). off has n_cells + 1 entries. */
thx_status vol_vtk_tets(raw *r, where w, const double *types, const double *off, size_t n_cells, const double *conn,
                        size_t n_conn, const double *reg, const char *reg_name);

/* ------------------------------------------------------------ the readers */

/* .pts + .tet/.elem (plain or CARP), import_vol_pts.c: reads both files. */
thx_status vol_read_ptselem(raw *r, const char *path, const char *elem_path);
/* Legacy VTK UNSTRUCTURED_GRID, import_vol_vtk.c. */
thx_status vol_read_vtk_ugrid(raw *r, const char *text, size_t len, const char *region_array);
/* VTK XML UnstructuredGrid, import_vol_vtu.c. */
thx_status vol_read_vtu(raw *r, const char *text, size_t len, const char *region_array);
/* Gmsh MSH 4.1 ASCII, import_vol_msh.c. */
thx_status vol_read_msh(raw *r, const char *text, size_t len);

#endif
