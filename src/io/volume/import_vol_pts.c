/*
 * Volume meshes made elsewhere: .pts + .tet / .elem, plain and CARP (thorax/io/volume_read.h).
 */
#include "io/volume/import_volume_impl.h"

/* ------------------------------------------------- .pts + .tet / .elem */

/* Nodes: "x y z" lines, optionally after a count line (CARP). */
static thx_status read_pts(raw *r, const char *text, size_t len, int *counted)
{
    cursor c = {text, len, 0, 1};
    tok tk[4];
    int line, first = 1;
    long long header = -1;
    int header_line = 0;
    size_t k;
    *counted = 0;
    while ((k = read_line(&c, tk, 4, &line)) != 0) {
        if (first && k == 1) {
            if (tk_int(&tk[0], &header) != 0 || header < 0)
                return fail(r, at_line(line), "expected a node count or \"x y z\", found \"%s\"", tok_show(tk[0].t, tk[0].n));
            header_line = line;
            first = 0;
            continue;
        }
        first = 0;
        if (k != 3)
            return fail(r, at_line(line), "node %zu: expected three coordinates \"x y z\", found %zu value%s", r->n_nodes + 1,
                        k, k == 1 ? "" : "s");
        double v[3];
        for (int j = 0; j < 3; j++)
            if (parse_num(tk[j].t, tk[j].n, &v[j]) != 0)
                return fail(r, at_line(line), "node %zu: coordinate %d is not a finite number: \"%s\"", r->n_nodes + 1, j + 1,
                            tok_show(tk[j].t, tk[j].n));
        THX_CHECK(add_node(r, at_line(line), v[0], v[1], v[2]));
    }
    if (header >= 0 && (size_t)header != r->n_nodes)
        return fail(r, at_line(header_line), "the count line says %lld nodes, but %zu follow", header, r->n_nodes);
    if (r->n_nodes == 0) return fail(r, at_file(), "no nodes");
    *counted = header >= 0;
    return THX_OK;
}

/* Elements: "a b c d [region]" lines, or CARP "Tt a b c d [region]" lines,
 * optionally after a count line. Node numbers are collected first so that
 * the index base can be detected from all of them (as for .fac files). */
static thx_status read_elem(raw *r, const char *text, size_t len, int pts_counted)
{
    thx_status st = THX_OK;
    cursor c = {text, len, 0, 1};
    tok tk[8];
    int line, first = 1, carp = -1, cols = -1;
    long long header = -1;
    int header_line = 0;
    long long *idx = NULL;
    int *lines = NULL;
    size_t n = 0, cap = 0, cap_l = 0, k;
    long long lo = LLONG_MAX, hi = LLONG_MIN;
    while ((k = read_line(&c, tk, 8, &line)) != 0) {
        if (first && k == 1) {
            if (tk_int(&tk[0], &header) != 0 || header < 0) {
                st = fail(r, at_line(line), "expected an element count or an element, found \"%s\"", tok_show(tk[0].t, tk[0].n));
                goto done;
            }
            header_line = line;
            first = 0;
            continue;
        }
        first = 0;
        int is_carp = isalpha((unsigned char)tk[0].t[0]) != 0;
        if (carp < 0) carp = is_carp;
        if (is_carp != carp) {
            st = fail(r, at_line(line), "element %zu: %s line among %s lines", n + 1, is_carp ? "a CARP \"Tt ...\"" : "a plain",
                      carp ? "CARP \"Tt ...\"" : "plain \"a b c d [region]\"");
            goto done;
        }
        size_t off = (size_t)is_carp;
        if (is_carp && !tok_is(tk[0].t, tk[0].n, "Tt")) {
            static const struct { const char *code, *name; } types[] = {
                {"Tr", "triangle"}, {"Qd", "quadrilateral"}, {"Hx", "hexahedron"}, {"Pr", "prism"},
                {"Py", "pyramid"}, {"Ln", "line"}, {"Cx", "cable"},
            };
            const char *nm = "unknown element type";
            for (size_t q = 0; q < sizeof types / sizeof types[0]; q++)
                if (tok_is(tk[0].t, tk[0].n, types[q].code)) nm = types[q].name;
            st = fail(r, at_line(line), "element %zu is \"%s\" (%s): only tetrahedra (\"Tt\") can be imported", n + 1,
                      tok_show(tk[0].t, tk[0].n), nm);
            goto done;
        }
        int nc = (int)(k - off);
        if (nc != 4 && nc != 5) {
            st = fail(r, at_line(line), "element %zu: expected four node numbers and an optional region, found %d value%s",
                      n + 1, nc, nc == 1 ? "" : "s");
            goto done;
        }
        if (cols < 0) cols = nc;
        if (nc != cols) {
            st = fail(r, at_line(line), "element %zu has %d columns but the first has %d (a region column on every line, "
                      "or on none)", n + 1, nc, cols);
            goto done;
        }
        if (n + 1 > cap) THX_TRY(thx_grow(r->ctx, (void **)&idx, &cap, n + 1, 5 * sizeof *idx));
        if (n + 1 > cap_l) THX_TRY(thx_grow(r->ctx, (void **)&lines, &cap_l, n + 1, sizeof *lines));
        for (int j = 0; j < nc; j++) {
            long long v;
            if (tk_int(&tk[off + (size_t)j], &v) != 0) {
                st = fail(r, at_line(line), "element %zu: %s \"%s\" is not an integer", n + 1, j < 4 ? "node number" : "region",
                          tok_show(tk[off + (size_t)j].t, tk[off + (size_t)j].n));
                goto done;
            }
            idx[5 * n + (size_t)j] = v;
            if (j < 4) {
                if (v < lo) lo = v;
                if (v > hi) hi = v;
            }
        }
        if (nc == 4) idx[5 * n + 4] = 1;
        lines[n] = line;
        n++;
    }
    if (header >= 0 && (size_t)header != n) {
        st = fail(r, at_line(header_line), "the count line says %lld elements, but %zu follow", header, n);
        goto done;
    }
    if (n == 0) {
        st = fail(r, at_file(), "no elements");
        goto done;
    }
    long long nn = (long long)r->n_nodes;
    int base;
    if (carp) {
        base = 0;
        r->index_base_detected = 0;
    } else {
        r->index_base_detected = 1;
        if (lo == 0) base = 0;
        else if (lo >= 1 && hi == nn) base = 1;
        else if (lo >= 1 && hi < nn) {
            st = fail(r, at_file(), "cannot tell whether node numbers are 0- or 1-based: they run %lld..%lld for %lld nodes "
                      "(0-based needs a 0, 1-based may reach %lld)", lo, hi, nn, nn);
            goto done;
        } else base = lo >= 1 ? 1 : 0; /* out of range: reported below */
    }
    r->index_base = base;
    if (lo < 0) /* named as written, before the base detection's guess makes another number the first out of range */
        for (size_t e = 0; e < n; e++)
            for (int j = 0; j < 4; j++)
                if (idx[5 * e + (size_t)j] < 0) {
                    st = fail(r, at_line(lines[e]), "element %zu: node number %lld is negative", e + 1, idx[5 * e + (size_t)j]);
                    goto done;
                }
    for (size_t e = 0; e < n; e++) {
        int32_t v[4];
        for (int j = 0; j < 4; j++) {
            long long x = idx[5 * e + (size_t)j] - base;
            if (x < 0 || x >= nn) {
                st = fail(r, at_line(lines[e]), "element %zu: node number %lld out of range %d..%lld (%d-based, %lld nodes)",
                          e + 1, x + base, base, nn - 1 + base, base, nn);
                goto done;
            }
            v[j] = (int32_t)x;
        }
        THX_TRY(add_tet(r, v, idx[5 * e + 4], lines[e]));
    }
    r->has_tags = cols == 5;
    r->ref_kind = "line";
    snprintf(r->region_source, sizeof r->region_source, "%s", cols == 5 ? "the region column" : "none (one region)");
    snprintf(r->detail, sizeof r->detail, "%s", carp ? "CARP .pts/.elem" : pts_counted ? ".pts (counted) + elements" : ".pts + elements");
done:
    free(idx);
    free(lines);
    return st;
}

thx_status vol_read_ptselem(raw *r, const char *path, const char *elem_path)
{
    thx_status st = THX_OK;
    char other[1024];
    const char *pts = path, *elem = elem_path;
    const char *ext = path_extension(path);
    int given_elem = !strcasecmp(ext, "tet") || !strcasecmp(ext, "elem");
    if (given_elem) {
        if (elem_path) return fail(r, at_file(), "an element file given twice: name the .pts, and the element file with --elem");
        elem = path;
        if (with_extension(other, sizeof other, path, "pts") != 0)
            return fail(r, at_file(), "cannot tell the name of the .pts file that goes with it");
        pts = other;
    } else if (!elem) {
        if (with_extension(other, sizeof other, path, "tet") != 0)
            return fail(r, at_file(), "cannot tell the name of the .tet or .elem file that goes with it");
        if (!readable(other)) with_extension(other, sizeof other, path, "elem");
        elem = other;
    }
    snprintf(r->path2, sizeof r->path2, "%s", given_elem ? pts : elem);
    char *text = NULL;
    size_t len = 0;
    int counted = 0;
    r->path = pts;
    THX_CHECK(thx_read_file(r->ctx, pts, &text, &len));
    if (nul_line(text, len)) {
        st = fail(r, at_line(nul_line(text, len)), "NUL byte at byte %zu: not a text file, or a damaged one",
                  (size_t)((const char *)memchr(text, 0, len) - text));
        free(text);
        return st;
    }
    st = read_pts(r, text, len, &counted);
    free(text);
    text = NULL;
    if (st) return st;
    r->path = elem;
    THX_CHECK(thx_read_file(r->ctx, elem, &text, &len));
    if (nul_line(text, len)) {
        st = fail(r, at_line(nul_line(text, len)), "NUL byte at byte %zu: not a text file, or a damaged one",
                  (size_t)((const char *)memchr(text, 0, len) - text));
        free(text);
        return st;
    }
    st = read_elem(r, text, len, counted);
    free(text);
    r->path = path;
    return st;
}

