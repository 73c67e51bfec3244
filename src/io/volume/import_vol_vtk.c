/*
 * Volume meshes made elsewhere: legacy VTK UNSTRUCTURED_GRID, and the VTK
 * cell handling the XML reader shares (thorax/io/volume_read.h).
 */
#include "io/volume/import_volume_impl.h"

/* ------------------------------------------------------------ cell types */

/* VTK cell types of dimension 0-2 (skipped): vertex, poly-vertex, line,
 * poly-line, triangle, strip, polygon, pixel, quad, and the quadratic and
 * higher-order 1-D/2-D cells. */
static int vtk_low_dim(long long type)
{
    static const int low[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 21, 22, 23, 28, 30, 34, 35, 36, 37, 68, 69, 70};
    for (size_t i = 0; i < sizeof low / sizeof low[0]; i++)
        if (type == low[i]) return 1;
    return 0;
}

static const char *vtk_type_name(long long type)
{
    switch (type) {
    case 10: return "tetrahedron";
    case 11: return "voxel";
    case 12: return "hexahedron";
    case 13: return "wedge";
    case 14: return "pyramid";
    case 15: return "pentagonal prism";
    case 16: return "hexagonal prism";
    case 24: return "quadratic tetrahedron";
    case 25: return "quadratic hexahedron";
    case 26: return "quadratic wedge";
    case 27: return "quadratic pyramid";
    case 42: return "polyhedron";
    case 71: return "Lagrange tetrahedron";
    default: return "not a linear tetrahedron";
    }
}


/* Region arrays by name, in order of preference (case-insensitive). */
static const char *const region_names[] = {"region", "regions", "gmsh:physical", "CellEntityIds", "material",
                                           "materials", "MaterialIds", "tissue", "elemTag", "tag"};

static int integral(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (v[i] != floor(v[i]) || fabs(v[i]) > 9007199254740992.0) return 0;
    return 1;
}

thx_status vol_choose_region_array(raw *r, const cell_array *a, size_t n, const char *want, int *out)
{
    *out = -1;
    if (want) {
        for (size_t i = 0; i < n; i++)
            if (!strcmp(a[i].name, want)) {
                *out = (int)i;
                return THX_OK;
            }
        char list[256] = "";
        for (size_t i = 0; i < n; i++)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s\"%s\"", i ? ", " : "", a[i].name);
        return fail(r, at_file(), "no one-component cell array named \"%s\" (the file has: %s)", want, n ? list : "none");
    }
    for (size_t k = 0; k < sizeof region_names / sizeof region_names[0]; k++)
        for (size_t i = 0; i < n; i++)
            if (!strcasecmp(a[i].name, region_names[k])) {
                *out = (int)i;
                return THX_OK;
            }
    int only = -1, count = 0;
    for (size_t i = 0; i < n; i++)
        if (integral(a[i].v, a[i].n)) only = (int)i, count++;
    if (count == 1) *out = only;
    return THX_OK;
}

thx_status vol_vtk_tets(raw *r, where w, const double *types, const double *off, size_t n_cells, const double *conn,
                           size_t n_conn, const double *reg, const char *reg_name)
{
    for (size_t i = 0; i < n_cells; i++) {
        if (!(off[i] >= 0 && off[i + 1] >= off[i] && off[i + 1] <= (double)n_conn))
            return fail(r, w, "cell %zu: offsets %g..%g out of order or beyond the %zu connectivity entries", i, off[i],
                        off[i + 1], n_conn);
        long long ty = (long long)types[i];
        size_t k = (size_t)(off[i + 1] - off[i]), s = (size_t)off[i];
        if (ty != 10) {
            if (vtk_low_dim(ty)) {
                r->n_ignored++;
                continue;
            }
            return fail(r, w, "cell %zu (0-based) is of VTK type %lld (%s): only tetrahedra (type 10) can be imported; "
                        "cells of dimension 0-2 are skipped", i, ty, vtk_type_name(ty));
        }
        if (k != 4) return fail(r, w, "cell %zu (0-based): a tetrahedron with %zu points", i, k);
        int32_t v[4];
        for (int j = 0; j < 4; j++) {
            double x = conn[s + (size_t)j];
            if (!(x >= 0 && x < (double)r->n_nodes) || x != floor(x))
                return fail(r, w, "cell %zu (0-based): point number %g out of range 0..%zu (0-based, %zu points)", i, x,
                            r->n_nodes - 1, r->n_nodes);
            v[j] = (int32_t)x;
        }
        long long tag = 0;
        if (reg) {
            if (reg[i] != floor(reg[i]) || fabs(reg[i]) > 9007199254740992.0)
                return fail(r, w, "cell array \"%s\": cell %zu (0-based) has region %g, not an integer", reg_name, i, reg[i]);
            tag = (long long)reg[i];
        }
        THX_CHECK(add_tet(r, v, tag, (long long)i));
    }
    r->has_tags = reg != NULL;
    r->ref_kind = "cell (0-based)";
    return THX_OK;
}

/* ------------------------------------------------------- legacy VTK */

typedef struct {
    cursor c;
    int binary; /* big-endian binary data after each header line */
} vsrc;

/* Reads count values of type ty into *out (NULL: skipped), after checking
 * that the rest of the file can hold them. */
static thx_status vtk_read_values(raw *r, vsrc *s, scalar_type ty, size_t count, const char *what, double **out)
{
    size_t left = s->c.len - s->c.pos;
    if (s->binary ? count > left / type_size[ty] : count > left / 2 + 1)
        return fail(r, s->binary ? at_byte(s->c.pos) : at_line(s->c.line),
                    "%s: %zu values declared, but the file is too short for them", what, count);
    double *v = NULL;
    if (out && count) {
        v = thx_malloc(r->ctx, count * sizeof *v);
        if (!v) return THX_ENOMEM;
    }
    if (s->binary) {
        const unsigned char *p = (const unsigned char *)s->c.buf + s->c.pos;
        char big[32];
        for (size_t i = 0; ty <= T_U64 && ty >= T_I64 && i < count; i++)
            if (int64_beyond(p + i * type_size[ty], ty, 1, big, sizeof big)) {
                free(v);
                return fail(r, at_byte(s->c.pos + i * type_size[ty]), "%s value %zu: integer %s is beyond +-2^53 (too large "
                            "for any index, count or region)", what, i + 1, big);
            }
        for (size_t i = 0; v && i < count; i++) {
            v[i] = get_scalar(p + i * type_size[ty], ty, 1);
            if (ty >= T_F32 && !isfinite(v[i])) {
                free(v);
                return fail(r, at_byte(s->c.pos + i * type_size[ty]), "%s value %zu is not a finite number", what, i + 1);
            }
        }
        s->c.pos += count * type_size[ty];
    } else {
        for (size_t i = 0; i < count; i++) {
            const char *t;
            int line;
            size_t n = next_token(&s->c, &t, &line);
            if (!n) {
                free(v);
                return fail(r, at_line(line), "file ends at %s value %zu of %zu", what, i + 1, count);
            }
            /* every value is parsed, kept or not: a damaged array is never skipped unseen */
            int bad;
            double d = 0;
            if (ty >= T_F32) {
                bad = parse_num(t, n, &d) != 0;
            } else {
                long long x = 0, lo, hi;
                type_range(ty, &lo, &hi);
                int pr = parse_i64(t, n, lo, hi, &x);
                if (pr == -2) {
                    free(v);
                    return fail(r, at_line(line), "%s value %zu: \"%s\" is out of range %lld..%lld", what, i + 1,
                                tok_show(t, n), lo, hi);
                }
                bad = pr != 0;
                d = (double)x;
            }
            if (v) v[i] = d;
            if (bad) {
                free(v);
                return fail(r, at_line(line), "%s value %zu: \"%s\" is not %s", what, i + 1, tok_show(t, n),
                            ty >= T_F32 ? "a finite number" : "an integer");
            }
        }
    }
    if (out) *out = v;
    return THX_OK;
}

/* The data type token on the current line (binary: not the platform-sized "long"). */
static thx_status vtk_line_type(raw *r, vsrc *s, int line, const char *what, scalar_type *ty)
{
    const char *u;
    size_t m = line_token(&s->c, &u);
    *ty = vtk_type(u, m);
    if (!*ty || (s->binary && (tok_is(u, m, "long") || tok_is(u, m, "unsigned_long"))))
        return fail(r, at_line(line), "%s: unsupported data type \"%s\"", what, m ? tok_show(u, m) : "");
    return THX_OK;
}

/* An integer token on the current line. */
static thx_status vtk_line_count(raw *r, cursor *c, int line, const char *what, long long *out)
{
    const char *t;
    size_t n = line_token(c, &t);
    int pc = n ? parse_count(t, n, INT32_MAX, out) : -1;
    if (pc == -2) return fail(r, at_line(line), "%s: count %s out of range 0..%d", what, tok_show(t, n), INT32_MAX);
    if (pc != 0) return fail(r, at_line(line), "%s: expected a count", what);
    return THX_OK;
}

/* After a header line: to the start of the binary data. */
static void vtk_data_start(vsrc *s)
{
    if (s->binary) next_line(&s->c);
}

/* METADATA: information keys (VTK 9 writers), up to the next blank line. */
static void vtk_skip_metadata(vsrc *s)
{
    while (next_line(&s->c)) {
        const char *u;
        cursor probe = s->c;
        if (!line_token(&probe, &u)) break;
    }
}

/* Skips a METADATA block if one comes next. */
static void vtk_maybe_metadata(vsrc *s)
{
    cursor save = s->c;
    const char *t;
    int line;
    size_t n = next_token(&s->c, &t, &line);
    if (tok_is(t, n, "METADATA")) vtk_skip_metadata(s);
    else s->c = save;
}

/* One attribute (the keyword kw just read at line) of a POINT_DATA or
 * CELL_DATA section of n_items; one-component arrays of cell data are kept
 * in *arr. */
static thx_status vtk_attribute(raw *r, vsrc *s, const char *kw, size_t kwn, int line, size_t n_items, int cells,
                                cell_array **arr, size_t *n_arr, size_t *cap_arr)
{
    thx_status st = THX_OK;
    const char *t;
    size_t n;
    char name[128] = "";
    char what[160];
    n = line_token(&s->c, &t);
    if (!n) return fail(r, at_line(line), "%.*s without a name", (int)kwn, kw);
    copy_tok(name, sizeof name, t, n);
    snprintf(what, sizeof what, "%.*s \"%s\"", (int)kwn, kw, name);
    double *v = NULL;
    if (tok_is(kw, kwn, "FIELD")) {
        long long na;
        THX_CHECK(vtk_line_count(r, &s->c, line, what, &na));
        for (long long a = 0; a < na; a++) {
            int l2;
            n = next_token(&s->c, &t, &l2);
            if (!n) return fail(r, at_line(l2), "%s: file ends at array %lld of %lld", what, a + 1, na);
            char an[128];
            copy_tok(an, sizeof an, t, n);
            if (!strcmp(an, "NULL_ARRAY")) continue;
            long long nc, nt;
            scalar_type ty;
            THX_CHECK(vtk_line_count(r, &s->c, l2, an, &nc));
            THX_CHECK(vtk_line_count(r, &s->c, l2, an, &nt));
            /* a string array (names: VTK writes thorax export's region_name, surface_name back so) holds no
             * region: in ASCII one string a line, skipped */
            cursor peek = s->c;
            const char *u;
            size_t un = line_token(&peek, &u);
            if (s->binary && (tok_is(u, un, "string") || tok_is(u, un, "utf8_string"))) {
                /* BINARY: after the header line each string is a big-endian length whose top two bits
                 * give its size (11: 1 byte, 10: 2, 01: 4, 00: 8; VTK's vtkDataWriter), then its bytes */
                s->c = peek;
                next_line(&s->c);
                cursor *c = &s->c;
                for (long long k = 0; k < nc * nt; k++) {
                    if (c->pos >= c->len)
                        return fail(r, at_line(l2), "%s array \"%s\": file ends at string %lld of %lld", what, an,
                                    k + 1, nc * nt);
                    unsigned char b0 = (unsigned char)c->buf[c->pos];
                    size_t hb = (b0 >> 6) == 3 ? 1 : (b0 >> 6) == 2 ? 2 : (b0 >> 6) == 1 ? 4 : 8;
                    if (c->len - c->pos < hb)
                        return fail(r, at_line(l2), "%s array \"%s\": string %lld cut short", what, an, k + 1);
                    unsigned long long sl = b0 & 0x3fu;
                    for (size_t q = 1; q < hb; q++) sl = (sl << 8) | (unsigned char)c->buf[c->pos + q];
                    c->pos += hb;
                    if (sl > c->len - c->pos)
                        return fail(r, at_line(l2), "%s array \"%s\": string %lld of %llu bytes runs past the end", what,
                                    an, k + 1, sl);
                    c->pos += (size_t)sl;
                }
                next_line(&s->c); /* the newline after the data */
                vtk_maybe_metadata(s);
                continue;
            }
            if (!s->binary && (tok_is(u, un, "string") || tok_is(u, un, "utf8_string"))) {
                s->c = peek;
                for (long long k = 0; k <= nc * nt; k++) /* the header line's end, then a line per string */
                    if (!next_line(&s->c) && k < nc * nt)
                        return fail(r, at_line(l2), "%s array \"%s\": file ends at string %lld of %lld", what, an, k + 1,
                                    nc * nt);
                vtk_maybe_metadata(s);
                continue;
            }
            THX_CHECK(vtk_line_type(r, s, l2, an, &ty));
            vtk_data_start(s);
            char aw[320];
            snprintf(aw, sizeof aw, "%s array \"%s\"", what, an);
            if ((unsigned long long)nc * (unsigned long long)nt > (unsigned long long)INT32_MAX * 4)
                return fail(r, at_line(l2), "%s: %lld x %lld values is too many", aw, nc, nt);
            int keep = cells && nc == 1 && (size_t)nt == n_items;
            THX_CHECK(vtk_read_values(r, s, ty, (size_t)(nc * nt), aw, keep ? &v : NULL));
            if (keep) {
                if (*n_arr + 1 > *cap_arr) {
                    st = thx_grow(r->ctx, (void **)arr, cap_arr, *n_arr + 1, sizeof **arr);
                    if (st) {
                        free(v);
                        return st;
                    }
                }
                cell_array *ca = &(*arr)[(*n_arr)++];
                snprintf(ca->name, sizeof ca->name, "%s", an);
                ca->v = v, ca->n = (size_t)nt;
                v = NULL;
            }
            vtk_maybe_metadata(s);
        }
        return THX_OK;
    }
    size_t per = 1;
    scalar_type ty = T_F32;
    int keep = 0;
    if (tok_is(kw, kwn, "SCALARS")) {
        THX_CHECK(vtk_line_type(r, s, line, what, &ty));
        long long nc = 1;
        n = line_token(&s->c, &t);
        if (n && (parse_int(t, n, &nc) != 0 || nc < 1 || nc > 4))
            return fail(r, at_line(line), "%s: the number of components must be 1..4", what);
        per = (size_t)nc;
        /* "LOOKUP_TABLE name" follows on its own line */
        cursor save = s->c;
        int l2;
        n = next_token(&s->c, &t, &l2);
        if (tok_is(t, n, "LOOKUP_TABLE")) line_token(&s->c, &t);
        else s->c = save;
        keep = cells && per == 1;
    } else if (tok_is(kw, kwn, "COLOR_SCALARS")) {
        long long nc;
        THX_CHECK(vtk_line_count(r, &s->c, line, what, &nc));
        per = (size_t)nc;
        ty = s->binary ? T_U8 : T_F32;
    } else if (tok_is(kw, kwn, "LOOKUP_TABLE")) {
        long long size;
        THX_CHECK(vtk_line_count(r, &s->c, line, what, &size));
        n_items = (size_t)size;
        per = 4;
        ty = s->binary ? T_U8 : T_F32;
    } else if (tok_is(kw, kwn, "VECTORS") || tok_is(kw, kwn, "NORMALS")) {
        THX_CHECK(vtk_line_type(r, s, line, what, &ty));
        per = 3;
    } else if (tok_is(kw, kwn, "TENSORS") || tok_is(kw, kwn, "TENSORS6")) {
        THX_CHECK(vtk_line_type(r, s, line, what, &ty));
        per = tok_is(kw, kwn, "TENSORS") ? 9 : 6;
    } else if (tok_is(kw, kwn, "TEXTURE_COORDINATES")) {
        long long dim;
        THX_CHECK(vtk_line_count(r, &s->c, line, what, &dim));
        if (dim < 1 || dim > 3) return fail(r, at_line(line), "%s: dimension must be 1..3", what);
        THX_CHECK(vtk_line_type(r, s, line, what, &ty));
        per = (size_t)dim;
    } else if (tok_is(kw, kwn, "GLOBAL_IDS") || tok_is(kw, kwn, "PEDIGREE_IDS")) {
        THX_CHECK(vtk_line_type(r, s, line, what, &ty));
    } else {
        return fail(r, at_line(line), "unexpected \"%s\" in the %s data", tok_show(kw, kwn), cells ? "cell" : "point");
    }
    vtk_data_start(s);
    THX_CHECK(vtk_read_values(r, s, ty, per * n_items, what, keep ? &v : NULL));
    if (keep) {
        if (*n_arr + 1 > *cap_arr) {
            st = thx_grow(r->ctx, (void **)arr, cap_arr, *n_arr + 1, sizeof **arr);
            if (st) {
                free(v);
                return st;
            }
        }
        cell_array *ca = &(*arr)[(*n_arr)++];
        snprintf(ca->name, sizeof ca->name, "%s", name);
        ca->v = v, ca->n = n_items;
    }
    return THX_OK;
}

thx_status vol_read_vtk_ugrid(raw *r, const char *text, size_t len, const char *region_array)
{
    thx_status st = THX_OK;
    vsrc s = {{text, len, 0, 1}, 0};
    cursor *c = &s.c;
    double *pts = NULL, *off = NULL, *conn = NULL, *types = NULL;
    cell_array *arr = NULL;
    size_t n_arr = 0, cap_arr = 0;
    size_t n_cells = 0, n_conn = 0;
    long long np = -1;
    int have_cells = 0, cells_line = 0, mode = 0; /* mode: 0 geometry, 1 point data, 2 cell data */
    size_t mode_items = 0;
    const char *t;
    size_t n;
    int line;
    if (len < 5 || strncasecmp(text, "# vtk", 5) != 0) {
        st = fail(r, at_line(1), "not a legacy VTK file (no \"# vtk DataFile Version\" line)");
        goto done;
    }
    next_line(c);
    next_line(c);
    line = c->line;
    n = line_token(c, &t);
    if (tok_is_ci(t, n, "BINARY")) s.binary = 1;
    else if (!tok_is_ci(t, n, "ASCII")) {
        st = fail(r, at_line(line), "expected ASCII or BINARY");
        goto done;
    }
    if (!s.binary && nul_line(text, len)) {
        st = fail(r, at_line(nul_line(text, len)), "NUL byte in an ASCII VTK file (at byte %zu)",
                  (size_t)((const char *)memchr(text, 0, len) - text));
        goto done;
    }
    n = next_token(c, &t, &line);
    if (!tok_is(t, n, "DATASET")) {
        st = fail(r, at_line(line), "expected \"DATASET UNSTRUCTURED_GRID\"");
        goto done;
    }
    n = line_token(c, &t);
    if (!tok_is(t, n, "UNSTRUCTURED_GRID")) {
        st = fail(r, at_line(line), "dataset \"%s\" is not a volume mesh: only UNSTRUCTURED_GRID%s", n ? tok_show(t, n) : "",
                  tok_is(t, n, "POLYDATA") ? " (a POLYDATA file is a surface: import it with --name and --role)" : "");
        goto done;
    }
    while ((n = next_token(c, &t, &line)) != 0) {
        if ((tok_is(t, n, "POINTS") && np >= 0) || (tok_is(t, n, "CELLS") && have_cells) ||
            (tok_is(t, n, "CELL_TYPES") && types)) {
            st = fail(r, at_line(line), "a second %s section", tok_show(t, n));
            goto done;
        }
        if (tok_is(t, n, "POINTS")) {
            scalar_type ty;
            THX_TRY(vtk_line_count(r, c, line, "POINTS", &np));
            THX_TRY(vtk_line_type(r, &s, line, "POINTS", &ty));
            vtk_data_start(&s);
            THX_TRY(vtk_read_values(r, &s, ty, 3 * (size_t)np, "POINTS", &pts));
            for (long long i = 0; i < np; i++)
                THX_TRY(add_node(r, at_line(line), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
            free(pts);
            pts = NULL;
            mode = 0;
        } else if (tok_is(t, n, "CELLS")) {
            long long n1, n2;
            cells_line = line;
            THX_TRY(vtk_line_count(r, c, line, "CELLS", &n1));
            THX_TRY(vtk_line_count(r, c, line, "CELLS", &n2));
            cursor save = *c;
            int l2;
            n = next_token(c, &t, &l2);
            if (!tok_is(t, n, "OFFSETS")) { /* classic: n1 cells, n2 entries "k p1 .. pk" */
                *c = save;
                vtk_data_start(&s);
                if (n1 > n2) { /* every cell takes one entry for its point count at least */
                    st = fail(r, at_line(line), "CELLS: %lld cells cannot fit in %lld entries", n1, n2);
                    goto done;
                }
                double *list = NULL;
                THX_TRY(vtk_read_values(r, &s, T_I32, (size_t)n2, "CELLS", &list));
                n_cells = (size_t)n1;
                off = thx_malloc(r->ctx, (n_cells + 1) * sizeof *off);
                conn = thx_malloc(r->ctx, ((size_t)n2 + 1) * sizeof *conn);
                if (!off || !conn) {
                    free(list);
                    st = THX_ENOMEM;
                    goto done;
                }
                size_t pos = 0;
                n_conn = 0;
                for (size_t i = 0; i < n_cells; i++) {
                    if (pos >= (size_t)n2) {
                        free(list);
                        st = fail(r, at_line(line), "CELLS: cell %zu (0-based) is beyond the %lld entries declared", i, n2);
                        goto done;
                    }
                    double k = list[pos++];
                    if (!(k >= 0 && k <= (double)((size_t)n2 - pos))) {
                        free(list);
                        st = fail(r, at_line(line), "CELLS: cell %zu (0-based) has a bad point count %g", i, k);
                        goto done;
                    }
                    off[i] = (double)n_conn;
                    for (size_t j = 0; j < (size_t)k; j++) conn[n_conn++] = list[pos++];
                }
                off[n_cells] = (double)n_conn;
                free(list);
                if (pos != (size_t)n2) {
                    st = fail(r, at_line(line), "CELLS: %lld entries declared, but the cells use %zu", n2, pos);
                    goto done;
                }
            } else { /* file version 5.x */
                scalar_type ty;
                THX_TRY(vtk_line_type(r, &s, l2, "OFFSETS", &ty));
                if (ty >= T_F32) {
                    st = fail(r, at_line(l2), "OFFSETS: not an integer type");
                    goto done;
                }
                vtk_data_start(&s);
                if (n1 < 1) {
                    st = fail(r, at_line(l2), "CELLS: %lld offsets (at least 1 needed)", n1);
                    goto done;
                }
                THX_TRY(vtk_read_values(r, &s, ty, (size_t)n1, "OFFSETS", &off));
                n = next_token(c, &t, &l2);
                if (!tok_is(t, n, "CONNECTIVITY")) {
                    st = fail(r, at_line(l2), "expected CONNECTIVITY after the OFFSETS");
                    goto done;
                }
                THX_TRY(vtk_line_type(r, &s, l2, "CONNECTIVITY", &ty));
                if (ty >= T_F32) {
                    st = fail(r, at_line(l2), "CONNECTIVITY: not an integer type");
                    goto done;
                }
                vtk_data_start(&s);
                THX_TRY(vtk_read_values(r, &s, ty, (size_t)n2, "CONNECTIVITY", &conn));
                n_cells = (size_t)n1 - 1;
                n_conn = (size_t)n2;
                if (off[0] != 0) {
                    st = fail(r, at_line(l2), "OFFSETS: the first offset is %g, not 0", off[0]);
                    goto done;
                }
            }
            have_cells = 1;
            mode = 0;
        } else if (tok_is(t, n, "CELL_TYPES")) {
            long long nt;
            THX_TRY(vtk_line_count(r, c, line, "CELL_TYPES", &nt));
            if (!have_cells || (size_t)nt != n_cells) {
                st = fail(r, at_line(line), "CELL_TYPES: %lld types for %zu cells%s", nt, n_cells, have_cells ? "" : " (no CELLS before)");
                goto done;
            }
            vtk_data_start(&s);
            THX_TRY(vtk_read_values(r, &s, T_I32, (size_t)nt, "CELL_TYPES", &types));
            mode = 0;
        } else if (tok_is(t, n, "POINT_DATA") || tok_is(t, n, "CELL_DATA")) {
            int cells = tok_is(t, n, "CELL_DATA");
            long long k;
            THX_TRY(vtk_line_count(r, c, line, cells ? "CELL_DATA" : "POINT_DATA", &k));
            size_t want = cells ? n_cells : (size_t)(np < 0 ? 0 : np);
            if ((size_t)k != want) {
                st = fail(r, at_line(line), "%s %lld, but the file has %zu %s", cells ? "CELL_DATA" : "POINT_DATA", k, want,
                          cells ? "cells" : "points");
                goto done;
            }
            mode = cells ? 2 : 1;
            mode_items = (size_t)k;
        } else if (tok_is(t, n, "METADATA")) {
            vtk_skip_metadata(&s);
        } else if (tok_is(t, n, "FIELD") && mode == 0) { /* dataset field data (TIME, ...): skipped */
            size_t dummy_n = 0, dummy_cap = 0;
            cell_array *dummy = NULL;
            THX_TRY(vtk_attribute(r, &s, t, n, line, 0, 0, &dummy, &dummy_n, &dummy_cap));
        } else if (mode) {
            THX_TRY(vtk_attribute(r, &s, t, n, line, mode_items, mode == 2, &arr, &n_arr, &cap_arr));
        } else {
            st = fail(r, at_line(line), "unexpected \"%s\" in an UNSTRUCTURED_GRID file", tok_show(t, n));
            goto done;
        }
    }
    if (np < 0) {
        st = fail(r, at_file(), "no POINTS");
        goto done;
    }
    if (!have_cells || !types) {
        st = fail(r, at_file(), "%s", have_cells ? "no CELL_TYPES" : "no CELLS");
        goto done;
    }
    int ri;
    THX_TRY(vol_choose_region_array(r, arr, n_arr, region_array, &ri));
    THX_TRY(vol_vtk_tets(r, at_line(cells_line), types, off, n_cells, conn, n_conn, ri >= 0 ? arr[ri].v : NULL,
                     ri >= 0 ? arr[ri].name : NULL));
    if (ri >= 0) snprintf(r->region_source, sizeof r->region_source, "cell array \"%s\"", arr[ri].name);
    else snprintf(r->region_source, sizeof r->region_source, "none (one region%s)",
                  n_arr ? ": no cell array is named as a region array; give --region-array" : "");
    snprintf(r->detail, sizeof r->detail, "legacy VTK %s UNSTRUCTURED_GRID", s.binary ? "binary" : "ASCII");
    r->index_base = 0;
done:
    free(pts);
    free(off);
    free(conn);
    free(types);
    for (size_t i = 0; i < n_arr; i++) free(arr[i].v);
    free(arr);
    return st;
}

