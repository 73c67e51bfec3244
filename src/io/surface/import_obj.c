/*
 * Surfaces made elsewhere: Wavefront OBJ (thorax/io/surface_read.h).
 */
#include "io/surface/import_surface.h"

/* ------------------------------------------------------------- OBJ */

thx_status import_read_obj(build *b, const char *text, size_t len, thx_surface_read_info *info)
{
    thx_status st = THX_OK;
    cursor c = {text, len, 0, 1};
    int32_t *poly = NULL;
    size_t cap = 0;
    do {
        const char *t;
        int line = c.line;
        size_t n = line_token(&c, &t);
        if (!n || t[0] == '#') continue;
        if (tok_is(t, n, "v")) {
            double v[3];
            for (int k = 0; k < 3; k++) {
                const char *u;
                size_t m = line_token(&c, &u);
                if (!m || parse_num(u, m, &v[k]) != 0) {
                    st = fail(b, at_line(line), "vertex %zu: coordinate %d %s", b->n_nodes + 1, k + 1,
                              m ? "is not a finite number" : "is missing");
                    goto done;
                }
            }
            /* an optional w, vertex colour (r g b) or both may follow: numbers, not geometry here */
            const char *u;
            size_t m, extra = 0;
            while ((m = line_token(&c, &u)) != 0 && u[0] != '#') { /* '#': a comment to the line's end */
                double x;
                if (parse_num(u, m, &x) != 0 || ++extra > 4) {
                    st = fail(b, at_line(line), "vertex %zu: unexpected \"%s\" after the coordinates (at most w and "
                              "a colour r g b may follow, as numbers)", b->n_nodes + 1, tok_show(u, m));
                    goto done;
                }
            }
            THX_TRY(add_node(b, at_line(line), v[0], v[1], v[2]));
        } else if (tok_is(t, n, "f")) {
            size_t nv = 0;
            const char *u;
            size_t m;
            while ((m = line_token(&c, &u)) != 0 && u[0] != '#') { /* '#': a comment to the line's end */
                /* v, v/vt, v//vn, v/vt/vn: the vertex is the part before the first '/' */
                size_t vlen = 0;
                while (vlen < m && u[vlen] != '/') vlen++;
                /* the texture and normal numbers after it (may be empty): integers, at most two */
                int parts = 0, bad_part = 0, last_empty = 0;
                for (size_t q = vlen; q < m;) {
                    size_t e = q + 1;
                    while (e < m && u[e] != '/') e++;
                    long long y;
                    if (++parts > 2 || (e > q + 1 && (parse_int(u + q + 1, e - q - 1, &y) != 0 || y == 0))) bad_part = 1;
                    last_empty = e == q + 1;
                    q = e;
                }
                if (parts && last_empty) bad_part = 1; /* "v/" and "v//": the number after the last '/' is missing */
                long long x;
                int pr = parse_i64(u, vlen, -INT_LIMIT, INT_LIMIT, &x);
                if (pr == -2) {
                    st = fail(b, at_line(line), "face refers to vertex %s but %zu vertices are defined before it",
                              tok_show(u, vlen), b->n_nodes);
                    goto done;
                }
                if (pr != 0 || x == 0 || bad_part) {
                    st = fail(b, at_line(line), "face vertex \"%s\" is not a vertex number (1-based, or negative "
                              "counting back from the last vertex)", tok_show(u, m));
                    goto done;
                }
                /* negative numbers count back from the last vertex defined so far */
                long long idx = x > 0 ? x - 1 : (long long)b->n_nodes + x;
                if (idx < 0 || (size_t)idx >= b->n_nodes) {
                    st = fail(b, at_line(line), "face refers to vertex %lld but %zu vertices are defined before it", x, b->n_nodes);
                    goto done;
                }
                if (nv + 1 > cap) THX_TRY(thx_grow(b->ctx, (void **)&poly, &cap, nv + 1, sizeof *poly));
                poly[nv++] = (int32_t)idx;
            }
            THX_TRY(add_polygon(b, at_line(line), poly, nv));
        } else if (tok_is(t, n, "l") || tok_is(t, n, "p")) {
            b->n_ignored++;
        }
        /* vt, vn, vp, g, o, s, usemtl, mtllib and other statements carry no surface geometry */
    } while (next_line(&c));
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "Wavefront OBJ");
        info->index_base = 1;
    }
done:
    free(poly);
    return st;
}

