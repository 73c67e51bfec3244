/*
 * Surfaces made elsewhere: OpenMEEG and ECGSim / MBFYS .tri (thorax/io/surface_read.h).
 *
 * .tri labels: a node (or triangle) block is "labelled" when the line of
 * its first entry has four tokens (three: unlabelled). When the entries
 * are not on lines of their own (the format allows free line breaks), the
 * block is labelled iff the token before each would-be coordinate triple
 * counts 1, 2, 3, ... (or 0, 1, 2, ...). Labels are otherwise ignored, as
 * in Oostendorp's loadtri.m: entries are numbered by position.
 */
#include "io/surface/import_surface.h"

/* ------------------------------------------------------------- .tri */

typedef struct { const char *t; size_t n; int line; } token;

/* Is the block of count entries (width values each after an optional label)
 * starting at tokens[i] labelled? Rule at the top of this file. */
static int tri_labelled(const token *tk, size_t nt, size_t i, size_t count, int width)
{
    if (i >= nt || count == 0) return 0;
    int line = tk[i].line;
    int on_line = 0;
    for (size_t k = i; k < nt && tk[k].line == line; k++) on_line++;
    int alone = (i == 0 || tk[i - 1].line != line);
    if (alone && on_line == width + 1) return 1;
    if (alone && on_line == width) return 0;
    /* free-format stream: labels must count up by one from 0 or 1 */
    long long first;
    if (parse_int(tk[i].t, tk[i].n, &first) != 0 || (first != 0 && first != 1)) return 0;
    for (size_t e = 0; e < count; e++) {
        size_t k = i + e * (size_t)(width + 1);
        long long v;
        if (k >= nt || parse_int(tk[k].t, tk[k].n, &v) != 0 || v != first + (long long)e) return 0;
    }
    return 1;
}

/* The next line that is not blank; 0 at the end of the text. Its first
 * token is in *t (length returned through *n). */
static int next_filled_line(cursor *c, const char **t, size_t *n)
{
    for (;;) {
        *n = line_token(c, t);
        if (*n) return 1;
        if (!next_line(c)) return 0;
    }
}

/* OpenMEEG's .tri (recognised by its first token "-"):
 *     - NV
 *     x y z nx ny nz        NV lines: a vertex and its normal
 *     - NT NT NT
 *     i j k                 NT lines: 0-based vertex numbers
 * Read line by line and strictly: every vertex line has six finite numbers
 * (the normals are not used: orientation comes from the triangles, and the
 * check decides it), every triangle line three vertex numbers in range, the
 * triangle header repeats one count (once to three times), and nothing but
 * blank lines follows the last triangle. */
static thx_status read_tri_openmeeg(build *b, const char *text, size_t len, thx_surface_read_info *info)
{
    cursor c = {text, len, 0, 1};
    const char *t;
    size_t n;
    long long nv, ntri;
    if (!next_filled_line(&c, &t, &n) || !tok_is(t, n, "-"))
        return fail(b, at_line(c.line), "not an OpenMEEG .tri file (the first line is not \"- NV\")");
    int line = c.line;
    n = line_token(&c, &t);
    int pc = n ? parse_count(t, n, INT32_MAX, &nv) : -1;
    if (pc == -2) return fail(b, at_line(line), "vertex count \"%s\" out of range 1..%d", tok_show(t, n), INT32_MAX);
    if (pc != 0 || nv <= 0)
        return fail(b, at_line(line), "expected \"- NV\" (the number of vertices) on the first line");
    /* A vertex line takes at least 12 bytes ("0 0 0 0 0 0\n"): a count the rest
     * of the file cannot hold is refused at once, before any loop or allocation. */
    if ((unsigned long long)nv > (len - c.pos) / 12 + 1)
        return fail(b, at_line(line), "%lld vertices declared, but the %zu bytes that follow can hold at most %zu",
                    nv, len - c.pos, (len - c.pos) / 12 + 1);
    if ((n = line_token(&c, &t)) != 0)
        return fail(b, at_line(line), "unexpected \"%s\" after the vertex count", tok_show(t, n));
    for (long long e = 0; e < nv; e++) {
        if (!next_line(&c) || !next_filled_line(&c, &t, &n))
            return fail(b, at_line(line), "file ends at vertex %lld of %lld", e + 1, nv);
        line = c.line;
        double v[6];
        static const char *const what[6] = {"x", "y", "z", "normal x", "normal y", "normal z"};
        for (int k = 0; k < 6; k++) {
            if (k > 0) n = line_token(&c, &t);
            if (!n)
                return fail(b, at_line(line), "vertex %lld: %s is missing (expected \"x y z nx ny nz\")", e + 1, what[k]);
            if (parse_num(t, n, &v[k]) != 0)
                return fail(b, at_line(line), "vertex %lld: %s is not a finite number: \"%s\"", e + 1, what[k], tok_show(t, n));
        }
        if ((n = line_token(&c, &t)) != 0)
            return fail(b, at_line(line), "vertex %lld: more than six numbers (\"%s\")", e + 1, tok_show(t, n));
        THX_CHECK(add_node(b, at_line(line), v[0], v[1], v[2]));
    }
    if (!next_line(&c) || !next_filled_line(&c, &t, &n))
        return fail(b, at_line(line), "file ends after the vertices (expected \"- NT NT NT\")");
    line = c.line;
    if (!tok_is(t, n, "-"))
        return fail(b, at_line(line), "expected \"- NT NT NT\" after the %lld vertices, found \"%s\"", nv, tok_show(t, n));
    int copies = 0;
    ntri = -1;
    while ((n = line_token(&c, &t)) != 0) {
        long long x;
        if (parse_count(t, n, INT32_MAX, &x) != 0 || (ntri >= 0 && x != ntri) || ++copies > 3)
            return fail(b, at_line(line), "expected \"- NT NT NT\" (one triangle count, repeated), found \"%s\"", tok_show(t, n));
        ntri = x;
    }
    if (ntri < 0) return fail(b, at_line(line), "expected \"- NT NT NT\": the triangle count is missing");
    if ((unsigned long long)ntri > (len - c.pos) / 6 + 1) /* "0 1 2\n": 6 bytes a triangle */
        return fail(b, at_line(line), "%lld triangles declared, but the %zu bytes that follow can hold at most %zu",
                    ntri, len - c.pos, (len - c.pos) / 6 + 1);
    for (long long e = 0; e < ntri; e++) {
        if (!next_line(&c) || !next_filled_line(&c, &t, &n))
            return fail(b, at_line(line), "file ends at triangle %lld of %lld", e + 1, ntri);
        line = c.line;
        int32_t v[3];
        for (int k = 0; k < 3; k++) {
            if (k > 0) n = line_token(&c, &t);
            long long x;
            if (!n) return fail(b, at_line(line), "triangle %lld: vertex number %d is missing", e + 1, k + 1);
            int pr = parse_i64(t, n, -INT_LIMIT, INT_LIMIT, &x);
            if (pr == -2)
                return fail(b, at_line(line), "triangle %lld: vertex number %s out of range 0..%zu (0-based, %zu vertices)",
                            e + 1, tok_show(t, n), b->n_nodes - 1, b->n_nodes);
            if (pr != 0)
                return fail(b, at_line(line), "triangle %lld: vertex number %d is not an integer: \"%s\"", e + 1, k + 1, tok_show(t, n));
            char obj[48];
            snprintf(obj, sizeof obj, "triangle %lld: ", e + 1);
            THX_CHECK(check_index(b, at_line(line), obj, x, 0, b->n_nodes, &v[k]));
        }
        if ((n = line_token(&c, &t)) != 0)
            return fail(b, at_line(line), "triangle %lld: more than three vertex numbers (\"%s\")", e + 1, tok_show(t, n));
        THX_CHECK(add_tri(b, v[0], v[1], v[2]));
    }
    if (next_line(&c) && next_filled_line(&c, &t, &n))
        return fail(b, at_line(c.line), "unexpected \"%s\" after the last of the %lld triangles", tok_show(t, n), ntri);
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "OpenMEEG .tri (vertex normals ignored)");
        info->index_base = 0;
        info->index_base_detected = 0;
    }
    return THX_OK;
}

thx_status import_read_tri(build *b, const char *text, size_t len, thx_surface_read_info *info)
{
    thx_status st = THX_OK;
    /* OpenMEEG's variant begins with "- NV"; ECGSim's with the node count */
    {
        cursor c0 = {text, len, 0, 1};
        const char *t0;
        int l0;
        size_t n0 = next_token(&c0, &t0, &l0);
        if (tok_is(t0, n0, "-")) return read_tri_openmeeg(b, text, len, info);
    }
    if (len >= 8 && (strncmp(text, ";;mbftri", 8) == 0 || strncmp(text, ";;mbfpnt", 8) == 0))
        return fail(b, at_byte(0), "binary MBFYS triangulation (\";;mbftri\") is not supported; write it as text");
    /* Tokenize the whole file: the format allows free line breaks, and label
     * detection needs to look ahead. */
    token *tk = NULL;
    size_t nt = 0, cap = 0;
    cursor c = {text, len, 0, 1};
    for (;;) {
        token t;
        t.n = next_token(&c, &t.t, &t.line);
        if (!t.n) break;
        if (nt + 1 > cap) THX_TRY(thx_grow(b->ctx, (void **)&tk, &cap, nt + 1, sizeof *tk));
        tk[nt++] = t;
    }
    size_t i = 0;
    long long npnt, ntri;
    if (nt == 0) {
        st = fail(b, at_line(1), "empty file (expected the number of nodes)");
        goto done;
    }
    if (parse_count(tk[0].t, tk[0].n, INT32_MAX, &npnt) != 0 || npnt <= 0) {
        st = fail(b, at_line(tk[0].line), "expected the number of nodes (1..%d), found \"%s\"", INT32_MAX,
                  tok_show(tk[0].t, tk[0].n));
        goto done;
    }
    i = 1;
    /* Counts are checked against the tokens the file holds (three per entry at
     * least) before any loop: a damaged count is refused at once. */
    if ((unsigned long long)npnt > (nt - i) / 3) {
        st = fail(b, at_line(tk[0].line), "%lld nodes declared, but the file holds only %zu numbers after the count "
                  "(3 a node at least)", npnt, nt - i);
        goto done;
    }
    int lab_nodes = tri_labelled(tk, nt, i, (size_t)npnt, 3);
    for (long long e = 0; e < npnt; e++) {
        int w = 3 + lab_nodes;
        if (i + (size_t)w > nt) {
            st = fail(b, at_line(nt ? tk[nt - 1].line : 1), "file ends at node %lld of %lld", e + 1, npnt);
            goto done;
        }
        if (lab_nodes) {
            long long lab;
            if (parse_int(tk[i].t, tk[i].n, &lab) != 0) {
                st = fail(b, at_line(tk[i].line), "node %lld: label \"%s\" is not an integer", e + 1, tok_show(tk[i].t, tk[i].n));
                goto done;
            }
            i++;
        }
        double v[3];
        for (int k = 0; k < 3; k++, i++)
            if (parse_num(tk[i].t, tk[i].n, &v[k]) != 0) {
                st = fail(b, at_line(tk[i].line), "node %lld: coordinate %d is not a finite number: \"%s\"", e + 1, k + 1,
                          tok_show(tk[i].t, tk[i].n));
                goto done;
            }
        THX_TRY(add_node(b, at_line(tk[i - 1].line), v[0], v[1], v[2]));
    }
    if (i >= nt) {
        st = fail(b, at_line(tk[nt - 1].line + 1), "file ends after the nodes (expected the number of triangles)");
        goto done;
    }
    if (parse_count(tk[i].t, tk[i].n, INT32_MAX, &ntri) != 0) {
        st = fail(b, at_line(tk[i].line), "expected the number of triangles (0..%d), found \"%s\"", INT32_MAX,
                  tok_show(tk[i].t, tk[i].n));
        goto done;
    }
    i++;
    if ((unsigned long long)ntri > (nt - i) / 3) {
        st = fail(b, at_line(tk[i - 1].line), "%lld triangles declared, but the file holds only %zu numbers after the "
                  "count (3 a triangle at least)", ntri, nt - i);
        goto done;
    }
    int lab_tris = tri_labelled(tk, nt, i, (size_t)ntri, 3);
    size_t first_tri = i;
    /* base: 0 if any index is 0, else 1 (the format's own numbering) */
    int base = 1;
    for (long long e = 0; e < ntri; e++) {
        size_t k = first_tri + (size_t)e * (size_t)(3 + lab_tris) + (size_t)lab_tris;
        for (int j = 0; j < 3 && k + (size_t)j < nt; j++) {
            long long v;
            if (parse_int(tk[k + (size_t)j].t, tk[k + (size_t)j].n, &v) == 0 && v == 0) base = 0;
        }
    }
    for (long long e = 0; e < ntri; e++) {
        int w = 3 + lab_tris;
        if (i + (size_t)w > nt) {
            st = fail(b, at_line(tk[nt - 1].line), "file ends at triangle %lld of %lld", e + 1, ntri);
            goto done;
        }
        if (lab_tris) {
            long long lab;
            if (parse_int(tk[i].t, tk[i].n, &lab) != 0) {
                st = fail(b, at_line(tk[i].line), "triangle %lld: label \"%s\" is not an integer", e + 1, tok_show(tk[i].t, tk[i].n));
                goto done;
            }
            i++;
        }
        int32_t v[3];
        for (int k = 0; k < 3; k++, i++) {
            long long x;
            int pr = parse_i64(tk[i].t, tk[i].n, -INT_LIMIT, INT_LIMIT, &x);
            if (pr == -2) {
                st = fail(b, at_line(tk[i].line), "triangle %lld: node number %s out of range %d..%lld (%d-based, %zu nodes)",
                          e + 1, tok_show(tk[i].t, tk[i].n), base, (long long)b->n_nodes - 1 + base, base, b->n_nodes);
                goto done;
            }
            if (pr != 0) {
                st = fail(b, at_line(tk[i].line), "triangle %lld: node number %d is not an integer: \"%s\"", e + 1, k + 1,
                          tok_show(tk[i].t, tk[i].n));
                goto done;
            }
            char obj[48];
            snprintf(obj, sizeof obj, "triangle %lld: ", e + 1);
            THX_TRY(check_index(b, at_line(tk[i].line), obj, x - base, base, b->n_nodes, &v[k]));
        }
        THX_TRY(add_tri(b, v[0], v[1], v[2]));
    }
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "ECGSim .tri (%s nodes, %s triangles)",
                 lab_nodes ? "labelled" : "unlabelled", lab_tris ? "labelled" : "unlabelled");
        info->index_base = base;
        info->index_base_detected = 1;
        info->trailer_line = i < nt ? tk[i].line : 0;
    }
done:
    free(tk);
    return st;
}

