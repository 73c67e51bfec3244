/*
 * Surfaces made elsewhere: legacy VTK POLYDATA (thorax/io/surface_read.h); its cell reader serves
 * the .vtp reader too (import_vtp.c).
 */
#include "io/surface/import_surface.h"

/* ------------------------------------------------------- legacy VTK */

/* Reads count values of type ty (binary: after the keyword line). */
static thx_status vtk_values(build *b, source *s, scalar_type ty, size_t count, const char *what, double **out)
{
    /* A count the rest of the file cannot hold is an error before any
     * allocation (a damaged header must not ask for gigabytes): a binary
     * value takes its size, a text value at least one character and a
     * separator. */
    size_t left = s->c.len - s->c.pos;
    if (s->binary ? count > left / type_size[ty] : count > left / 2 + 1)
        return fail(b, s->binary ? at_byte(s->c.pos) : at_line(s->c.line),
                    "%s: %zu values declared, but the file is too short for them", what, count);
    double *v = NULL;
    if (count > 0) {
        v = thx_malloc(b->ctx, count * sizeof *v);
        if (!v) return THX_ENOMEM;
    }
    char w_what[96];
    for (size_t i = 0; i < count; i++) {
        where w;
        snprintf(w_what, sizeof w_what, "%s value %zu", what, i + 1);
        thx_status st = read_scalar(b, s, ty, w_what, &v[i], &w);
        if (st) {
            free(v);
            return st;
        }
    }
    *out = v;
    return THX_OK;
}

/* Reads "KEYWORD COUNT" header tokens on the current line. */
static thx_status vtk_count(build *b, cursor *c, int line, const char *kw, long long *out)
{
    const char *t;
    size_t n = line_token(c, &t);
    int pc = n ? parse_count(t, n, INT32_MAX, out) : -1;
    if (pc == -2) return fail(b, at_line(line), "%s: count %s out of range 0..%d", kw, tok_show(t, n), INT32_MAX);
    if (pc != 0) return fail(b, at_line(line), "%s: expected a count", kw);
    return THX_OK;
}

/* Adds the cells of one section: kind 0 polygons, 1 triangle strips, 2 ignored. */
thx_status import_vtk_cells(build *b, int kind, const double *off, size_t n_cells, const double *conn, size_t n_conn,
                            int legacy, where w, int32_t **poly, size_t *pcap)
{
    size_t pos = 0;
    for (size_t cidx = 0; cidx < n_cells; cidx++) {
        size_t start, k;
        if (legacy) {
            if (pos >= n_conn) return fail(b, w, "cell %zu: cell list shorter than its declared size", cidx + 1);
            double cnt = conn[pos++];
            if (cnt < 0 || cnt > (double)(n_conn - pos)) return fail(b, w, "cell %zu: bad vertex count %g", cidx + 1, cnt);
            start = pos;
            k = (size_t)cnt;
            pos += k;
        } else {
            if (off[cidx] < 0 || off[cidx + 1] < off[cidx] || off[cidx + 1] > (double)n_conn)
                return fail(b, w, "cell %zu: offsets %g..%g out of order or beyond the %zu connectivity entries", cidx + 1,
                            off[cidx], off[cidx + 1], n_conn);
            start = (size_t)off[cidx];
            k = (size_t)off[cidx + 1] - start;
        }
        if (kind == 2) {
            b->n_ignored++;
            continue;
        }
        if (k > *pcap) THX_CHECK(thx_grow(b->ctx, (void **)poly, pcap, k, sizeof **poly));
        char obj[48];
        snprintf(obj, sizeof obj, "cell %zu: ", cidx + 1);
        for (size_t j = 0; j < k; j++) THX_CHECK(check_index(b, w, obj, (long long)conn[start + j], 0, b->n_nodes, &(*poly)[j]));
        if (kind == 0) {
            THX_CHECK(add_polygon(b, w, *poly, k));
        } else {
            if (k < 3) return fail(b, w, "triangle strip %zu has %zu vertices", cidx + 1, k);
            /* every second triangle of a strip is flipped back to the strip's winding */
            for (size_t j = 0; j + 2 < k; j++) {
                const int32_t *p = *poly + j;
                THX_CHECK(j % 2 == 0 ? add_tri(b, p[0], p[1], p[2]) : add_tri(b, p[1], p[0], p[2]));
            }
        }
    }
    if (legacy && pos != n_conn)
        return fail(b, w, "cell list has %zu entries but its cells use %zu", n_conn, pos);
    return THX_OK;
}

thx_status import_read_vtk(build *b, const char *text, size_t len, thx_surface_read_info *info)
{
    thx_status st = THX_OK;
    source s = {{text, len, 0, 1}, 0, 1};
    cursor *c = &s.c;
    double *off = NULL, *conn = NULL, *pts = NULL;
    int32_t *poly = NULL;
    size_t pcap = 0;
    const char *t;
    size_t n;
    /* line 1: "# vtk DataFile Version x.y" */
    if (len < 5 || strncasecmp(text, "# vtk", 5) != 0) {
        st = fail(b, at_line(1), "not a legacy VTK file (no \"# vtk DataFile Version\" line)");
        goto done;
    }
    next_line(c); /* line 2: title */
    next_line(c);
    int line = c->line;
    n = line_token(c, &t);
    if (tok_is_ci(t, n, "BINARY")) s.binary = 1;
    else if (!tok_is_ci(t, n, "ASCII")) {
        st = fail(b, at_line(line), "expected ASCII or BINARY");
        goto done;
    }
    if (!s.binary && nul_line(text, len)) {
        st = fail(b, at_line(nul_line(text, len)), "NUL byte in an ASCII VTK file (at byte %zu)",
                  (size_t)((const char *)memchr(text, 0, len) - text));
        goto done;
    }
    n = next_token(c, &t, &line);
    if (!tok_is(t, n, "DATASET")) {
        st = fail(b, at_line(line), "expected \"DATASET POLYDATA\"");
        goto done;
    }
    n = line_token(c, &t);
    if (!tok_is(t, n, "POLYDATA")) {
        st = fail(b, at_line(line), "dataset \"%s\" is not supported: only POLYDATA (a surface)", n ? tok_show(t, n) : "");
        goto done;
    }
    int have_points = 0;
    while ((n = next_token(c, &t, &line)) != 0) {
        if (tok_is(t, n, "POINTS")) {
            long long np;
            THX_TRY(vtk_count(b, c, line, "POINTS", &np));
            const char *u;
            size_t m = line_token(c, &u);
            scalar_type ty = vtk_type(u, m);
            if (!ty || (s.binary && (ty == T_I64 || ty == T_U64) && !tok_is(u, m, "vtktypeint64") &&
                        !tok_is(u, m, "vtktypeuint64"))) {
                st = fail(b, at_line(line), "POINTS: unsupported type \"%s\"", m ? tok_show(u, m) : "");
                goto done;
            }
            if (s.binary) next_line(c);
            THX_TRY(vtk_values(b, &s, ty, 3 * (size_t)np, "POINTS", &pts));
            for (long long i = 0; i < np; i++)
                THX_TRY(add_node(b, at_line(line), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
            free(pts);
            pts = NULL;
            have_points = 1;
        } else if (tok_is(t, n, "POLYGONS") || tok_is(t, n, "TRIANGLE_STRIPS") || tok_is(t, n, "VERTICES") ||
                   tok_is(t, n, "LINES")) {
            int kind = tok_is(t, n, "POLYGONS") ? 0 : tok_is(t, n, "TRIANGLE_STRIPS") ? 1 : 2;
            char kw[32];
            copy_tok(kw, sizeof kw, t, n);
            int kw_line = line;
            if (!have_points && kind != 2) {
                st = fail(b, at_line(line), "%s before POINTS", kw);
                goto done;
            }
            long long n1, n2;
            THX_TRY(vtk_count(b, c, line, kw, &n1));
            THX_TRY(vtk_count(b, c, line, kw, &n2));
            /* file version 5.x: "OFFSETS type" (n1 values) and "CONNECTIVITY type" (n2 values) follow */
            cursor save = *c;
            int l2;
            n = next_token(c, &t, &l2);
            int legacy = !tok_is(t, n, "OFFSETS");
            size_t n_cells, n_conn;
            if (legacy) {
                *c = save;
                if (s.binary) next_line(c);
                n_cells = (size_t)n1;
                n_conn = (size_t)n2;
                THX_TRY(vtk_values(b, &s, T_I32, n_conn, kw, &conn));
            } else {
                const char *u;
                size_t m = line_token(c, &u);
                scalar_type ty = vtk_type(u, m);
                if (!ty || ty >= T_F32) {
                    st = fail(b, at_line(l2), "OFFSETS: unsupported type \"%s\"", m ? tok_show(u, m) : "");
                    goto done;
                }
                if (s.binary) next_line(c);
                if (n1 < 1 && n2 > 0) {
                    st = fail(b, at_line(l2), "%s: no offsets for %lld connectivity entries", kw, n2);
                    goto done;
                }
                n_cells = n1 > 0 ? (size_t)n1 - 1 : 0;
                n_conn = (size_t)n2;
                THX_TRY(vtk_values(b, &s, ty, (size_t)n1, "OFFSETS", &off));
                n = next_token(c, &t, &l2);
                if (!tok_is(t, n, "CONNECTIVITY")) {
                    st = fail(b, at_line(l2), "expected CONNECTIVITY after the OFFSETS of %s", kw);
                    goto done;
                }
                m = line_token(c, &u);
                ty = vtk_type(u, m);
                if (!ty || ty >= T_F32) {
                    st = fail(b, at_line(l2), "CONNECTIVITY: unsupported type \"%s\"", m ? tok_show(u, m) : "");
                    goto done;
                }
                if (s.binary) next_line(c);
                THX_TRY(vtk_values(b, &s, ty, n_conn, "CONNECTIVITY", &conn));
            }
            THX_TRY(import_vtk_cells(b, kind, off, n_cells, conn, n_conn, legacy, at_line(kw_line), &poly, &pcap));
            free(off);
            free(conn);
            off = conn = NULL;
        } else if (tok_is(t, n, "METADATA")) {
            /* information keys (VTK 9 writers): skipped up to the next blank line */
            while (next_line(c)) {
                const char *u;
                cursor probe = *c;
                if (!line_token(&probe, &u)) break;
            }
        } else if (tok_is(t, n, "POINT_DATA") || tok_is(t, n, "CELL_DATA") || tok_is(t, n, "FIELD")) {
            break; /* attributes carry no geometry */
        } else {
            st = fail(b, at_line(line), "unexpected \"%s\" in a POLYDATA file", tok_show(t, n));
            goto done;
        }
    }
    if (!have_points) {
        st = fail(b, at_line(c->line), "no POINTS");
        goto done;
    }
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "legacy VTK %s POLYDATA", s.binary ? "binary" : "ASCII");
        info->index_base = 0;
    }
done:
    free(pts);
    free(off);
    free(conn);
    free(poly);
    return st;
}
