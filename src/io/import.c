/*
 * Surfaces made elsewhere: readers for .pts/.fac, ECGSim .tri, OBJ, STL, PLY,
 * legacy VTK and ASCII VTP, and the import policy (see thorax/import.h).
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Every reader builds into one growable node/triangle store (struct
 *    build) whose indices are 0-based and range-checked as they arrive, so an
 *    out-of-range index is reported at the line (or byte) that holds it.
 *
 *  - Text is read whole (thx_read_file) and scanned by a cursor that counts
 *    lines; numbers are parsed with strtod/strtoll on a NUL-terminated copy
 *    of the token, and must be finite. Integers in files may be written as
 *    "3" or "3.0" (some PLY/VTK writers do), but must be integral.
 *
 *  - Binary data (STL, PLY, VTK) is read byte by byte with explicit byte
 *    order, never by casting the buffer, so the host's byte order and
 *    alignment do not matter. Errors give the byte offset.
 *
 *  - Polygons with more than three vertices are split into the fan
 *    (v0, vi, vi+1), which keeps their winding; a non-convex polygon may give
 *    overlapping triangles, which the self-intersection check then finds.
 *
 *  - STL has no shared vertices: corners are merged when their float
 *    coordinates are bit-identical (with -0 = +0), in order of first
 *    appearance, so the result is deterministic. Nothing is merged within a
 *    tolerance: that would change the geometry behind the user's back.
 *
 *  - .tri labels: a node (or triangle) block is "labelled" when the line of
 *    its first entry has four tokens (three: unlabelled). When the entries
 *    are not on lines of their own (the format allows free line breaks), the
 *    block is labelled iff the token before each would-be coordinate triple
 *    counts 1, 2, 3, ... (or 0, 1, 2, ...). Labels are otherwise ignored, as
 *    in Oostendorp's loadtri.m: entries are numbered by position.
 */
#include "thorax/import.h"

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

#include "thorax/fileio.h"
#include "thorax/model.h"
#include "io/import_text.h"

/* ------------------------------------------------------------ formats */

static const char *const format_names[] = {"auto", "pts/fac", "tri", "obj", "stl", "ply", "vtk", "vtp"};

const char *thx_import_format_name(thx_import_format f)
{
    return (f >= THX_IMPORT_AUTO && f <= THX_IMPORT_VTP) ? format_names[f] : "unknown";
}

int thx_import_format_parse(const char *s, thx_import_format *out)
{
    static const struct { const char *name; thx_import_format f; } tab[] = {
        {"pts", THX_IMPORT_PTSFAC}, {"fac", THX_IMPORT_PTSFAC}, {"pts/fac", THX_IMPORT_PTSFAC},
        {"tri", THX_IMPORT_TRI}, {"obj", THX_IMPORT_OBJ}, {"stl", THX_IMPORT_STL},
        {"ply", THX_IMPORT_PLY}, {"vtk", THX_IMPORT_VTK}, {"vtp", THX_IMPORT_VTP},
    };
    if (!s) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcasecmp(s, tab[i].name) == 0) {
            *out = tab[i].f;
            return 0;
        }
    return -1;
}


thx_import_format thx_import_format_from_path(const char *path)
{
    thx_import_format f;
    if (!path || thx_import_format_parse(path_extension(path), &f) != 0) return THX_IMPORT_AUTO;
    return f;
}

void thx_import_opts_default(thx_import_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = THX_IMPORT_AUTO;
    o->scale = 1.0;
    o->force = 0;
    thx_check_opts_default(&o->check);
}

void thx_import_info_free(thx_import_info *info)
{
    if (!info) return;
    thx_surface_report_free(&info->report);
    memset(info, 0, sizeof *info);
}

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

static where at_line(int line) { where w = {line, 0}; return w; }
static where at_byte(size_t byte) { where w = {0, byte}; return w; }

static thx_status fail(build *b, where w, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static thx_status fail(build *b, where w, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (w.line > 0) return thx_error(b->ctx, THX_EINPUT, "%s:%d: surface \"%s\": %s", b->path, w.line, b->name, msg);
    return thx_error(b->ctx, THX_EINPUT, "%s: byte %zu: surface \"%s\": %s", b->path, w.byte, b->name, msg);
}

static thx_status add_node(build *b, where w, double x, double y, double z)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(z)) return fail(b, w, "node %zu has a non-finite coordinate", b->n_nodes + 1);
    if (b->n_nodes >= (size_t)INT32_MAX) return fail(b, w, "too many nodes");
    if (b->n_nodes + 1 > b->cap_nodes) THX_CHECK(thx_grow(b->ctx, (void **)&b->xyz, &b->cap_nodes, b->n_nodes + 1, 3 * sizeof *b->xyz));
    double *p = b->xyz + 3 * b->n_nodes++;
    p[0] = x, p[1] = y, p[2] = z;
    return THX_OK;
}

static thx_status add_tri(build *b, int32_t i, int32_t j, int32_t k)
{
    if (b->n_tris >= (size_t)INT32_MAX) return thx_error(b->ctx, THX_EINPUT, "%s: surface \"%s\": too many triangles", b->path, b->name);
    if (b->n_tris + 1 > b->cap_tris) THX_CHECK(thx_grow(b->ctx, (void **)&b->tri, &b->cap_tris, b->n_tris + 1, 3 * sizeof *b->tri));
    int32_t *t = b->tri + 3 * b->n_tris++;
    t[0] = i, t[1] = j, t[2] = k;
    return THX_OK;
}

/* A polygon of n 0-based node indices (already range-checked) as a fan. */
static thx_status add_polygon(build *b, where w, const int32_t *v, size_t n)
{
    if (n < 3) return fail(b, w, "a face needs at least 3 vertices, this one has %zu", n);
    if (n > 3) b->n_split++;
    for (size_t i = 1; i + 1 < n; i++) THX_CHECK(add_tri(b, v[0], v[i], v[i + 1]));
    return THX_OK;
}

/* Checks a 0-based index against the node count, naming it as the file numbers it. */
static thx_status check_index(build *b, where w, long long v, int base, size_t n_nodes, int32_t *out)
{
    if (v < 0 || (unsigned long long)v >= n_nodes)
        return fail(b, w, "node number %lld out of range %d..%lld (%d-based, %zu nodes)", v + base, base,
                    (long long)n_nodes - 1 + base, base, n_nodes);
    *out = (int32_t)v;
    return THX_OK;
}

/* Hands the store to a new surface. */
static thx_status finish(build *b, thx_role role, thx_surface **out)
{
    thx_surface *s = NULL;
    THX_CHECK(thx_surface_create(b->ctx, b->name, role, &s));
    s->xyz = b->xyz, s->n_nodes = b->n_nodes;
    s->tri = b->tri, s->n_tris = b->n_tris;
    b->xyz = NULL, b->tri = NULL;
    *out = s;
    return THX_OK;
}


/* ----------------------------------------------------------- .pts/.fac */

static thx_status read_ptsfac(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              thx_surface **out, thx_import_info *info)
{
    char other[1024];
    const char *pts = path, *fac = path2;
    const char *ext = path_extension(path);
    int given_fac = strcasecmp(ext, "fac") == 0;
    if (given_fac) { /* the user named the .fac: the .pts is the other one */
        fac = path;
        pts = path2;
    }
    if (!(given_fac ? pts : fac)) {
        size_t stem = strlen(path) - strlen(ext);
        if (!ext[0] || stem + 4 > sizeof other)
            return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": cannot tell the name of the %s file that goes with it",
                             path, name, given_fac ? ".pts" : ".fac");
        memcpy(other, path, stem);
        /* keep the case of the extension given: .PTS goes with .FAC */
        const char *want = given_fac ? (isupper((unsigned char)ext[0]) ? "PTS" : "pts")
                                     : (isupper((unsigned char)ext[0]) ? "FAC" : "fac");
        memcpy(other + stem, want, 4);
        if (given_fac) pts = other;
        else fac = other;
    }
    int base = 1;
    THX_CHECK(thx_surface_read_ptsfac(ctx, pts, fac, name, role, out, &base));
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "map3d .pts/.fac");
        snprintf(info->path2, sizeof info->path2, "%s", given_fac ? pts : fac);
        info->index_base = base;
        info->index_base_detected = 1;
    }
    return THX_OK;
}

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
static thx_status read_tri_openmeeg(build *b, const char *text, size_t len, thx_import_info *info)
{
    cursor c = {text, len, 0, 1};
    const char *t;
    size_t n;
    long long nv, ntri;
    if (!next_filled_line(&c, &t, &n) || !tok_is(t, n, "-"))
        return fail(b, at_line(c.line), "not an OpenMEEG .tri file (the first line is not \"- NV\")");
    int line = c.line;
    n = line_token(&c, &t);
    if (!n || parse_int(t, n, &nv) != 0 || nv <= 0 || nv > INT32_MAX)
        return fail(b, at_line(line), "expected \"- NV\" (the number of vertices) on the first line");
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
        if (parse_int(t, n, &x) != 0 || x < 0 || x > INT32_MAX || (ntri >= 0 && x != ntri) || ++copies > 3)
            return fail(b, at_line(line), "expected \"- NT NT NT\" (one triangle count, repeated), found \"%s\"", tok_show(t, n));
        ntri = x;
    }
    if (ntri < 0) return fail(b, at_line(line), "expected \"- NT NT NT\": the triangle count is missing");
    for (long long e = 0; e < ntri; e++) {
        if (!next_line(&c) || !next_filled_line(&c, &t, &n))
            return fail(b, at_line(line), "file ends at triangle %lld of %lld", e + 1, ntri);
        line = c.line;
        int32_t v[3];
        for (int k = 0; k < 3; k++) {
            if (k > 0) n = line_token(&c, &t);
            long long x;
            if (!n) return fail(b, at_line(line), "triangle %lld: vertex number %d is missing", e + 1, k + 1);
            if (parse_int(t, n, &x) != 0)
                return fail(b, at_line(line), "triangle %lld: vertex number %d is not an integer: \"%s\"", e + 1, k + 1, tok_show(t, n));
            THX_CHECK(check_index(b, at_line(line), x, 0, b->n_nodes, &v[k]));
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

static thx_status read_tri(build *b, const char *text, size_t len, thx_import_info *info)
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
    if (parse_int(tk[0].t, tk[0].n, &npnt) != 0 || npnt <= 0 || npnt > INT32_MAX) {
        st = fail(b, at_line(tk[0].line), "expected the number of nodes, found \"%s\"", tok_show(tk[0].t, tk[0].n));
        goto done;
    }
    i = 1;
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
    if (parse_int(tk[i].t, tk[i].n, &ntri) != 0 || ntri < 0 || ntri > INT32_MAX) {
        st = fail(b, at_line(tk[i].line), "expected the number of triangles, found \"%s\"", tok_show(tk[i].t, tk[i].n));
        goto done;
    }
    i++;
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
            if (parse_int(tk[i].t, tk[i].n, &x) != 0) {
                st = fail(b, at_line(tk[i].line), "triangle %lld: node number %d is not an integer: \"%s\"", e + 1, k + 1,
                          tok_show(tk[i].t, tk[i].n));
                goto done;
            }
            THX_TRY(check_index(b, at_line(tk[i].line), x - base, base, b->n_nodes, &v[k]));
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

/* ------------------------------------------------------------- OBJ */

static thx_status read_obj(build *b, const char *text, size_t len, thx_import_info *info)
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
            /* an optional w (or vertex colour) may follow: not geometry here */
            THX_TRY(add_node(b, at_line(line), v[0], v[1], v[2]));
        } else if (tok_is(t, n, "f")) {
            size_t nv = 0;
            const char *u;
            size_t m;
            while ((m = line_token(&c, &u)) != 0) {
                /* v, v/vt, v//vn, v/vt/vn: the vertex is the part before the first '/' */
                size_t vlen = 0;
                while (vlen < m && u[vlen] != '/') vlen++;
                long long x;
                if (parse_int(u, vlen, &x) != 0 || x == 0) {
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

/* ------------------------------------------------- binary helpers, vertex merge */

static uint32_t get_u32le(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float get_f32le(const unsigned char *p)
{
    uint32_t u = get_u32le(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* Exact-coordinate vertex merging for STL: an open-addressing hash table of
 * node indices keyed by the coordinates' bit patterns. */
typedef struct {
    int32_t *slot; /* -1 empty */
    size_t cap;    /* power of two */
} merge_map;

static uint64_t hash_xyz(const double *p)
{
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; k++) {
        double d = p[k] == 0 ? 0.0 : p[k]; /* -0 and +0 are the same point */
        uint64_t u;
        memcpy(&u, &d, 8);
        h ^= u;
        h *= 1099511628211ull;
        h ^= h >> 29;
    }
    return h;
}

static thx_status merge_grow(build *b, merge_map *m)
{
    size_t ncap = m->cap ? 2 * m->cap : 1024;
    int32_t *ns = thx_malloc(b->ctx, ncap * sizeof *ns);
    if (!ns) return THX_ENOMEM;
    for (size_t i = 0; i < ncap; i++) ns[i] = -1;
    for (size_t i = 0; i < m->cap; i++) {
        if (m->slot[i] < 0) continue;
        size_t h = (size_t)hash_xyz(b->xyz + 3 * (size_t)m->slot[i]) & (ncap - 1);
        while (ns[h] >= 0) h = (h + 1) & (ncap - 1);
        ns[h] = m->slot[i];
    }
    free(m->slot);
    m->slot = ns;
    m->cap = ncap;
    return THX_OK;
}

/* The node at exactly (x, y, z), added if new. */
static thx_status merge_node(build *b, merge_map *m, where w, double x, double y, double z, int32_t *out)
{
    if (2 * (b->n_nodes + 1) > m->cap) THX_CHECK(merge_grow(b, m));
    const double p[3] = {x == 0 ? 0.0 : x, y == 0 ? 0.0 : y, z == 0 ? 0.0 : z};
    size_t h = (size_t)hash_xyz(p) & (m->cap - 1);
    while (m->slot[h] >= 0) {
        const double *q = b->xyz + 3 * (size_t)m->slot[h];
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) {
            *out = m->slot[h];
            return THX_OK;
        }
        h = (h + 1) & (m->cap - 1);
    }
    THX_CHECK(add_node(b, w, p[0], p[1], p[2]));
    m->slot[h] = (int32_t)(b->n_nodes - 1);
    *out = m->slot[h];
    return THX_OK;
}

/* ------------------------------------------------------------- STL */

static thx_status read_stl(build *b, const char *text, size_t len, thx_import_info *info)
{
    thx_status st = THX_OK;
    merge_map m = {NULL, 0};
    const unsigned char *u = (const unsigned char *)text;
    int32_t *poly = NULL;
    size_t pcap = 0, corners = 0;
    /* Binary iff the size fits the triangle count exactly: some binary files
     * begin their header with "solid" too, so the word alone decides nothing. */
    int binary = len >= 84 && (uint64_t)len == 84 + 50 * (uint64_t)get_u32le(u + 80);
    if (binary) {
        size_t n = get_u32le(u + 80);
        for (size_t t = 0; t < n; t++) {
            const unsigned char *f = u + 84 + 50 * t;
            int32_t v[3];
            for (int k = 0; k < 3; k++) {
                const unsigned char *p = f + 12 + 12 * k;
                double x = get_f32le(p), y = get_f32le(p + 4), z = get_f32le(p + 8);
                THX_TRY(merge_node(b, &m, at_byte((size_t)(p - u)), x, y, z, &v[k]));
            }
            corners += 3;
            THX_TRY(add_tri(b, v[0], v[1], v[2]));
        }
        if (info) snprintf(info->format_detail, sizeof info->format_detail, "binary STL");
    } else {
        cursor c = {text, len, 0, 1};
        const char *t;
        int line = 1;
        size_t n = next_token(&c, &t, &line);
        if (!n || !tok_is_ci(t, n, "solid")) {
            if (len >= 84)
                st = fail(b, at_byte(0), "neither ASCII STL (no \"solid\" at the start) nor binary STL (%zu bytes, but "
                          "84 + 50 x %u triangles = %llu)", len, (unsigned)get_u32le(u + 80),
                          84ull + 50ull * get_u32le(u + 80));
            else
                st = fail(b, at_line(1), "not an STL file: too short for binary, and no \"solid\" at the start");
            goto done;
        }
        next_line(&c);
        size_t nv = 0;
        int in_loop = 0, loop_line = 0;
        do {
            line = c.line;
            n = line_token(&c, &t);
            if (!n) continue;
            if (tok_is_ci(t, n, "vertex")) {
                if (!in_loop) {
                    st = fail(b, at_line(line), "\"vertex\" outside \"outer loop\" ... \"endloop\"");
                    goto done;
                }
                double v[3];
                for (int k = 0; k < 3; k++) {
                    const char *x;
                    size_t m2 = line_token(&c, &x);
                    if (!m2 || parse_num(x, m2, &v[k]) != 0) {
                        st = fail(b, at_line(line), "vertex coordinate %d %s", k + 1, m2 ? "is not a finite number" : "is missing");
                        goto done;
                    }
                }
                if (nv + 1 > pcap) THX_TRY(thx_grow(b->ctx, (void **)&poly, &pcap, nv + 1, sizeof *poly));
                THX_TRY(merge_node(b, &m, at_line(line), v[0], v[1], v[2], &poly[nv]));
                nv++;
                corners++;
            } else if (tok_is_ci(t, n, "outer")) {
                in_loop = 1;
                loop_line = line;
                nv = 0;
            } else if (tok_is_ci(t, n, "endloop")) {
                if (!in_loop) {
                    st = fail(b, at_line(line), "\"endloop\" without \"outer loop\"");
                    goto done;
                }
                THX_TRY(add_polygon(b, at_line(loop_line), poly, nv));
                in_loop = 0;
            } else if (tok_is_ci(t, n, "facet") || tok_is_ci(t, n, "endfacet") || tok_is_ci(t, n, "endsolid") ||
                       tok_is_ci(t, n, "solid")) {
                /* facet normals are recomputed from the corners; several solids are read as one surface */
            } else {
                st = fail(b, at_line(line), "unexpected \"%s\" in an ASCII STL file", tok_show(t, n));
                goto done;
            }
        } while (next_line(&c));
        if (in_loop) {
            st = fail(b, at_line(loop_line), "\"outer loop\" without \"endloop\"");
            goto done;
        }
        if (info) snprintf(info->format_detail, sizeof info->format_detail, "ASCII STL");
    }
    if (info) {
        info->index_base = -1;
        info->n_corners_merged = corners - b->n_nodes;
    }
done:
    free(m.slot);
    free(poly);
    return st;
}

/* -------------------------------------------------- scalar types (PLY, VTK) */


static scalar_type ply_type(const char *t, size_t n)
{
    static const struct { const char *name; scalar_type ty; } tab[] = {
        {"char", T_I8}, {"int8", T_I8}, {"uchar", T_U8}, {"uint8", T_U8}, {"short", T_I16}, {"int16", T_I16},
        {"ushort", T_U16}, {"uint16", T_U16}, {"int", T_I32}, {"int32", T_I32}, {"uint", T_U32}, {"uint32", T_U32},
        {"float", T_F32}, {"float32", T_F32}, {"double", T_F64}, {"float64", T_F64},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (tok_is(t, n, tab[i].name)) return tab[i].ty;
    return T_NONE;
}


/* Reads one scalar of type ty, as text (a token) or binary (big/little endian).
 * Sets *w to where it was. */
typedef struct {
    cursor c;
    int binary, big;
} source;

static thx_status read_scalar(build *b, source *s, scalar_type ty, const char *what, double *out, where *w)
{
    if (s->binary) {
        *w = at_byte(s->c.pos);
        if (s->c.len - s->c.pos < type_size[ty]) return fail(b, *w, "file ends inside %s", what);
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
        long long v = 0;
        bad = parse_int(t, n, &v) != 0;
        *out = (double)v;
    }
    if (bad)
        return fail(b, *w, "%s: \"%s\" is not %s", what, tok_show(t, n), ty >= T_F32 ? "a finite number" : "an integer");
    return THX_OK;
}

/* ------------------------------------------------------------- PLY */

#define PLY_MAX_ELEMS 16
#define PLY_MAX_PROPS 64

typedef struct {
    char name[32];
    scalar_type ty;       /* the value type (list items for a list) */
    scalar_type count_ty; /* T_NONE for a scalar property */
} ply_prop;

typedef struct {
    char name[32];
    size_t count;
    int line;
    size_t n_prop;
    ply_prop prop[PLY_MAX_PROPS];
} ply_elem;


static thx_status read_ply(build *b, const char *text, size_t len, thx_import_info *info)
{
    thx_status st = THX_OK;
    ply_elem *el = NULL;
    size_t n_el = 0;
    int32_t *poly = NULL;
    size_t pcap = 0;
    source s = {{text, len, 0, 1}, 0, 0};
    cursor *c = &s.c;
    const char *t;
    size_t n = line_token(c, &t);
    if (!n || !tok_is(t, n, "ply")) {
        st = fail(b, at_line(1), "not a PLY file (the first line is not \"ply\")");
        goto done;
    }
    el = thx_calloc(b->ctx, PLY_MAX_ELEMS, sizeof *el);
    if (!el) {
        st = THX_ENOMEM;
        goto done;
    }
    int have_format = 0, ended = 0;
    while (next_line(c)) {
        int line = c->line;
        n = line_token(c, &t);
        if (!n) continue;
        if (tok_is(t, n, "end_header")) {
            ended = 1;
            break;
        } else if (tok_is(t, n, "comment") || tok_is(t, n, "obj_info")) {
            continue;
        } else if (tok_is(t, n, "format")) {
            n = line_token(c, &t);
            if (tok_is(t, n, "ascii")) s.binary = 0;
            else if (tok_is(t, n, "binary_little_endian")) s.binary = 1, s.big = 0;
            else if (tok_is(t, n, "binary_big_endian")) s.binary = 1, s.big = 1;
            else {
                st = fail(b, at_line(line), "unknown PLY format \"%s\"", n ? tok_show(t, n) : "");
                goto done;
            }
            have_format = 1;
        } else if (tok_is(t, n, "element")) {
            if (n_el == PLY_MAX_ELEMS) {
                st = fail(b, at_line(line), "more than %d elements", PLY_MAX_ELEMS);
                goto done;
            }
            ply_elem *e = &el[n_el];
            const char *u;
            size_t m = line_token(c, &t), k = line_token(c, &u);
            long long cnt;
            if (!m || !k || parse_int(u, k, &cnt) != 0 || cnt < 0 || cnt > INT32_MAX) {
                st = fail(b, at_line(line), "expected \"element NAME COUNT\"");
                goto done;
            }
            copy_tok(e->name, sizeof e->name, t, m);
            e->count = (size_t)cnt;
            e->line = line;
            n_el++;
        } else if (tok_is(t, n, "property")) {
            if (n_el == 0) {
                st = fail(b, at_line(line), "\"property\" before any \"element\"");
                goto done;
            }
            ply_elem *e = &el[n_el - 1];
            if (e->n_prop == PLY_MAX_PROPS) {
                st = fail(b, at_line(line), "element \"%s\" has more than %d properties", e->name, PLY_MAX_PROPS);
                goto done;
            }
            ply_prop *p = &e->prop[e->n_prop];
            n = line_token(c, &t);
            if (tok_is(t, n, "list")) {
                const char *u;
                size_t m = line_token(c, &u);
                p->count_ty = ply_type(u, m);
                n = line_token(c, &t);
                p->ty = ply_type(t, n);
                if (!p->count_ty || p->count_ty >= T_F32 || !p->ty) {
                    st = fail(b, at_line(line), "expected \"property list COUNT_TYPE ITEM_TYPE NAME\" with integer COUNT_TYPE");
                    goto done;
                }
            } else {
                p->ty = ply_type(t, n);
                if (!p->ty) {
                    st = fail(b, at_line(line), "unknown property type \"%s\"", n ? tok_show(t, n) : "");
                    goto done;
                }
            }
            n = line_token(c, &t);
            if (!n) {
                st = fail(b, at_line(line), "property without a name");
                goto done;
            }
            copy_tok(p->name, sizeof p->name, t, n);
            e->n_prop++;
        } else {
            st = fail(b, at_line(line), "unexpected \"%s\" in the PLY header", tok_show(t, n));
            goto done;
        }
    }
    if (!ended || !have_format) {
        st = fail(b, at_line(c->line), "PLY header without %s", have_format ? "\"end_header\"" : "\"format\"");
        goto done;
    }
    next_line(c); /* the body starts after the end_header line (binary data right after its '\n') */

    int seen_vertex = 0;
    for (size_t ei = 0; ei < n_el; ei++) {
        ply_elem *e = &el[ei];
        int is_vertex = strcmp(e->name, "vertex") == 0, is_face = strcmp(e->name, "face") == 0;
        int ix = -1, iy = -1, iz = -1, iv = -1;
        for (size_t k = 0; k < e->n_prop; k++) {
            const ply_prop *p = &e->prop[k];
            if (is_vertex && !p->count_ty) {
                if (!strcmp(p->name, "x")) ix = (int)k;
                if (!strcmp(p->name, "y")) iy = (int)k;
                if (!strcmp(p->name, "z")) iz = (int)k;
            }
            if (is_face && p->count_ty && (!strcmp(p->name, "vertex_indices") || !strcmp(p->name, "vertex_index")))
                iv = (int)k;
        }
        if (is_vertex && (ix < 0 || iy < 0 || iz < 0)) {
            st = fail(b, at_line(e->line), "element \"vertex\" lacks scalar properties x, y and z");
            goto done;
        }
        if (is_face && iv < 0) {
            st = fail(b, at_line(e->line), "element \"face\" lacks a list property \"vertex_indices\"");
            goto done;
        }
        if (is_face && !seen_vertex) {
            st = fail(b, at_line(e->line), "element \"face\" comes before element \"vertex\"");
            goto done;
        }
        if (is_face && e->prop[iv].ty >= T_F32) {
            st = fail(b, at_line(e->line), "face vertex indices must have an integer type");
            goto done;
        }
        seen_vertex |= is_vertex;
        char what[96];
        for (size_t r = 0; r < e->count; r++) {
            double xyz[3] = {0, 0, 0};
            where w0 = {0, 0};
            size_t nv = 0;
            int first = 1;
            for (size_t k = 0; k < e->n_prop; k++) {
                const ply_prop *p = &e->prop[k];
                double v;
                where w;
                snprintf(what, sizeof what, "%s %zu property \"%s\"", e->name, r + 1, p->name);
                if (!p->count_ty) {
                    THX_TRY(read_scalar(b, &s, p->ty, what, &v, &w));
                    if (first) w0 = w, first = 0;
                    if ((int)k == ix) xyz[0] = v;
                    if ((int)k == iy) xyz[1] = v;
                    if ((int)k == iz) xyz[2] = v;
                    continue;
                }
                THX_TRY(read_scalar(b, &s, p->count_ty, what, &v, &w));
                if (first) w0 = w, first = 0;
                if (v < 0 || v > 1e6) {
                    st = fail(b, w, "%s: list length %g out of range", what, v);
                    goto done;
                }
                size_t cnt = (size_t)v;
                for (size_t q = 0; q < cnt; q++) {
                    where wi;
                    THX_TRY(read_scalar(b, &s, p->ty, what, &v, &wi));
                    if ((int)k != iv) continue;
                    if (nv + 1 > pcap) THX_TRY(thx_grow(b->ctx, (void **)&poly, &pcap, nv + 1, sizeof *poly));
                    THX_TRY(check_index(b, wi, (long long)v, 0, b->n_nodes, &poly[nv]));
                    nv++;
                }
            }
            if (is_vertex) THX_TRY(add_node(b, w0, xyz[0], xyz[1], xyz[2]));
            if (is_face) THX_TRY(add_polygon(b, w0, poly, nv));
        }
    }
    if (!seen_vertex) {
        st = fail(b, at_line(1), "no \"vertex\" element");
        goto done;
    }
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "%s PLY",
                 !s.binary ? "ascii" : s.big ? "binary big-endian" : "binary little-endian");
        info->index_base = 0;
    }
done:
    free(el);
    free(poly);
    return st;
}

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
    if (!n || parse_int(t, n, out) != 0 || *out < 0 || *out > INT32_MAX)
        return fail(b, at_line(line), "%s: expected a count", kw);
    return THX_OK;
}

/* Adds the cells of one section: kind 0 polygons, 1 triangle strips, 2 ignored. */
static thx_status vtk_cells(build *b, int kind, const double *off, size_t n_cells, const double *conn, size_t n_conn,
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
        for (size_t j = 0; j < k; j++) THX_CHECK(check_index(b, w, (long long)conn[start + j], 0, b->n_nodes, &(*poly)[j]));
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

static thx_status read_vtk(build *b, const char *text, size_t len, thx_import_info *info)
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
            THX_TRY(vtk_cells(b, kind, off, n_cells, conn, n_conn, legacy, at_line(kw_line), &poly, &pcap));
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

/* --------------------------------------------------------- VTK XML (.vtp) */


/* Reads an ascii DataArray starting at tag into *out (count values). */
static thx_status vtp_array(build *b, const char *buf, const char *tag, const char *end, const char *what, size_t count,
                            int integer, double **out)
{
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    if (!gt) return fail(b, at_line(line_of(buf, tag)), "%s: unterminated <DataArray> tag", what);
    char fmt[32] = "ascii";
    if (xml_attr(tag, gt, "format", fmt, sizeof fmt) == 0 && strcmp(fmt, "ascii") != 0)
        return fail(b, at_line(line_of(buf, tag)),
                    "%s: DataArray format \"%s\" is not supported: only format=\"ascii\" (in ParaView, save as "
                    "ASCII; or use a legacy .vtk file)", what, fmt);
    const char *lt = memchr(gt, '<', (size_t)(end - gt));
    if (!lt) return fail(b, at_line(line_of(buf, gt)), "%s: DataArray without its closing tag", what);
    source s = {{gt + 1, (size_t)(lt - gt - 1), 0, line_of(buf, gt)}, 0, 0};
    if (count > s.c.len / 2 + 1) /* as in vtk_values: no allocation for a count the data cannot hold */
        return fail(b, at_line(s.c.line), "%s: %zu values declared, but the DataArray is too short for them", what, count);
    double *v = NULL;
    if (count) {
        v = thx_malloc(b->ctx, count * sizeof *v);
        if (!v) return THX_ENOMEM;
    }
    char w_what[96];
    for (size_t i = 0; i < count; i++) {
        where w;
        snprintf(w_what, sizeof w_what, "%s value %zu", what, i + 1);
        thx_status st = read_scalar(b, &s, integer ? T_I64 : T_F64, w_what, &v[i], &w);
        if (st) {
            free(v);
            return st;
        }
    }
    const char *t;
    int l;
    if (next_token(&s.c, &t, &l)) {
        free(v);
        return fail(b, at_line(l), "%s: more than the %zu values expected", what, count);
    }
    *out = v;
    return THX_OK;
}

static thx_status read_vtp(build *b, const char *text, size_t len, thx_import_info *info)
{
    thx_status st = THX_OK;
    const char *end = text + len;
    double *pts = NULL, *off = NULL, *conn = NULL;
    int32_t *poly = NULL;
    size_t pcap = 0;
    char val[64];
    const char *vf = xml_find(text, end, "VTKFile");
    if (!vf) {
        st = fail(b, at_line(1), "not a VTK XML file (no <VTKFile>)");
        goto done;
    }
    const char *vf_end = memchr(vf, '>', (size_t)(end - vf));
    if (!vf_end || xml_attr(vf, vf_end, "type", val, sizeof val) != 0 || strcmp(val, "PolyData") != 0) {
        st = fail(b, at_line(line_of(text, vf)), "VTK XML file is not of type \"PolyData\"");
        goto done;
    }
    if (xml_find(vf, end, "AppendedData")) {
        st = fail(b, at_line(line_of(text, vf)), "appended (binary) VTP data is not supported: only format=\"ascii\"");
        goto done;
    }
    const char *piece = xml_find(vf, end, "Piece");
    const char *piece_end = piece ? memchr(piece, '>', (size_t)(end - piece)) : NULL;
    if (!piece_end) {
        st = fail(b, at_line(line_of(text, vf)), "no <Piece>");
        goto done;
    }
    if (xml_find(piece_end, end, "Piece")) {
        st = fail(b, at_line(line_of(text, piece)), "more than one <Piece> is not supported");
        goto done;
    }
    long long np = 0, npoly = 0, nstrip = 0;
    if (xml_attr(piece, piece_end, "NumberOfPoints", val, sizeof val) != 0 || parse_int(val, strlen(val), &np) != 0 ||
        np < 0 || np > INT32_MAX) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece> without a valid NumberOfPoints");
        goto done;
    }
    if (xml_attr(piece, piece_end, "NumberOfPolys", val, sizeof val) == 0 &&
        (parse_int(val, strlen(val), &npoly) != 0 || npoly < 0 || npoly > INT32_MAX)) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece>: invalid NumberOfPolys");
        goto done;
    }
    if (xml_attr(piece, piece_end, "NumberOfStrips", val, sizeof val) == 0 && parse_int(val, strlen(val), &nstrip) == 0 &&
        nstrip > 0) {
        st = fail(b, at_line(line_of(text, piece)), "triangle strips in a VTP file are not supported");
        goto done;
    }
    const char *ptag = xml_find(piece_end, end, "Points");
    const char *da = ptag ? xml_find(ptag, end, "DataArray") : NULL;
    if (!da) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece> without <Points><DataArray>");
        goto done;
    }
    THX_TRY(vtp_array(b, text, da, end, "Points", 3 * (size_t)np, 0, &pts));
    int pts_line = line_of(text, da); /* once: line_of scans from the start of the file */
    for (long long i = 0; i < np; i++) THX_TRY(add_node(b, at_line(pts_line), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
    if (npoly > 0) {
        const char *polys = xml_find(piece_end, end, "Polys");
        const char *pend = polys ? strstr(polys, "</Polys>") : NULL;
        if (!pend) {
            st = fail(b, at_line(line_of(text, piece)), "NumberOfPolys=%lld but no complete <Polys> element", npoly);
            goto done;
        }
        const char *ca = NULL, *oa = NULL;
        for (const char *p = polys; (p = xml_find(p + 1, pend, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(pend - p));
            if (!gt) break;
            if (xml_attr(p, gt, "Name", val, sizeof val) != 0) continue;
            if (!strcmp(val, "connectivity")) ca = p;
            if (!strcmp(val, "offsets")) oa = p;
        }
        if (!ca || !oa) {
            st = fail(b, at_line(line_of(text, polys)), "<Polys> needs DataArrays named \"connectivity\" and \"offsets\"");
            goto done;
        }
        THX_TRY(vtp_array(b, text, oa, pend, "Polys offsets", (size_t)npoly, 1, &off));
        double total = off[npoly - 1];
        if (!(total >= 0 && total <= 1e10)) {
            st = fail(b, at_line(line_of(text, oa)), "Polys offsets: last offset %g out of range", total);
            goto done;
        }
        THX_TRY(vtp_array(b, text, ca, pend, "Polys connectivity", (size_t)total, 1, &conn));
        /* XML offsets are the ends of the cells: prepend the start 0 */
        double *o2 = thx_malloc(b->ctx, ((size_t)npoly + 1) * sizeof *o2);
        if (!o2) {
            st = THX_ENOMEM;
            goto done;
        }
        o2[0] = 0;
        memcpy(o2 + 1, off, (size_t)npoly * sizeof *off);
        free(off);
        off = o2;
        THX_TRY(vtk_cells(b, 0, off, (size_t)npoly, conn, (size_t)total, 0, at_line(line_of(text, ca)), &poly, &pcap));
    }
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "VTK XML PolyData (ascii)");
        info->index_base = 0;
    }
done:
    free(pts);
    free(off);
    free(conn);
    free(poly);
    return st;
}

/* ----------------------------------------------------------- dispatch */

thx_status thx_surface_read_file(thx_ctx *ctx, const char *path, const char *path2, thx_import_format fmt,
                                 const char *name, thx_role role, thx_surface **out, thx_import_info *info)
{
    *out = NULL;
    if (info) {
        memset(info, 0, sizeof *info); /* overwritten, not freed: see import.h */
        info->index_base = 0;
        info->scale = 1.0;
    }
    if (fmt == THX_IMPORT_AUTO) fmt = thx_import_format_from_path(path);
    if (fmt == THX_IMPORT_AUTO)
        return thx_error(ctx, THX_EINPUT,
                         "%s: surface \"%s\": cannot tell the format from the extension \"%s\" (known: .pts/.fac, .tri, "
                         ".obj, .stl, .ply, .vtk, .vtp)", path, name, path_extension(path));
    if (info) info->format = fmt;
    thx_status st = THX_OK;
    if (fmt == THX_IMPORT_PTSFAC) {
        st = read_ptsfac(ctx, path, path2, name, role, out, info);
    } else {
        char *text = NULL;
        size_t len = 0;
        THX_CHECK(thx_read_file(ctx, path, &text, &len));
        build b;
        memset(&b, 0, sizeof b);
        b.ctx = ctx, b.path = path, b.name = name;
        switch (fmt) {
        case THX_IMPORT_TRI: st = read_tri(&b, text, len, info); break;
        case THX_IMPORT_OBJ: st = read_obj(&b, text, len, info); break;
        case THX_IMPORT_STL: st = read_stl(&b, text, len, info); break;
        case THX_IMPORT_PLY: st = read_ply(&b, text, len, info); break;
        case THX_IMPORT_VTK: st = read_vtk(&b, text, len, info); break;
        case THX_IMPORT_VTP: st = read_vtp(&b, text, len, info); break;
        default: st = thx_error(ctx, THX_EINTERNAL, "%s: unknown import format %d", path, (int)fmt); break;
        }
        if (st == THX_OK && b.n_nodes == 0) st = fail(&b, at_line(1), "no nodes");
        if (st == THX_OK) st = finish(&b, role, out);
        if (info) {
            info->n_polygons_split = b.n_split;
            info->n_cells_ignored = b.n_ignored;
        }
        free(b.xyz);
        free(b.tri);
        free(text);
    }
    if (st == THX_OK && info) {
        info->n_nodes_read = (*out)->n_nodes;
        info->n_tris_read = (*out)->n_tris;
    }
    return st;
}

/* ------------------------------------------------------------- import */

/* Removes nodes used by no triangle, keeping the order of the rest. */
static thx_status remove_unused(thx_ctx *ctx, thx_surface *s, size_t *removed, long *first)
{
    *removed = 0;
    *first = -1;
    int32_t *map = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < s->n_nodes; i++) map[i] = -1;
    for (size_t i = 0; i < 3 * s->n_tris; i++) map[s->tri[i]] = 0;
    size_t k = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        if (map[i] < 0) {
            if (*first < 0) *first = (long)i;
            continue;
        }
        map[i] = (int32_t)k;
        if (k != i) memmove(s->xyz + 3 * k, s->xyz + 3 * i, 3 * sizeof *s->xyz);
        k++;
    }
    for (size_t i = 0; i < 3 * s->n_tris; i++) s->tri[i] = map[s->tri[i]];
    *removed = s->n_nodes - k;
    s->n_nodes = k;
    free(map);
    return THX_OK;
}

/* Closed, manifold and consistently oriented, but enclosing a negative volume:
 * every triangle is clockwise seen from outside (policy step 5). */
static int inward_only(const thx_surface_report *r)
{
    return !(r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX)) && r->n_boundary_edges == 0 &&
           r->n_nonmanifold_edges == 0 && r->n_nonmanifold_vertices == 0 && r->n_inconsistent_edges == 0 &&
           r->volume < 0;
}

thx_status thx_surface_import(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              const thx_import_opts *opts, thx_surface **out, thx_import_info *info)
{
    thx_import_opts def;
    if (!opts) {
        thx_import_opts_default(&def);
        opts = &def;
    }
    *out = NULL;
    thx_import_info local;
    if (!info) {
        memset(&local, 0, sizeof local);
        info = &local;
    }
    if (!(opts->scale > 0) || !isfinite(opts->scale))
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": scale %g must be a finite positive number", path, name,
                         opts->scale);
    thx_surface *s = NULL;
    thx_status st;
    THX_TRY(thx_surface_read_file(ctx, path, path2, opts->format, name, role, &s, info));
    info->scale = opts->scale;
    if (opts->scale != 1.0)
        for (size_t i = 0; i < 3 * s->n_nodes; i++) {
            s->xyz[i] *= opts->scale;
            if (!isfinite(s->xyz[i])) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": node %zu is not finite after scaling by %g", path,
                               name, i / 3 + 1, opts->scale);
                goto done;
            }
        }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], s->xyz[3 * i + (size_t)k]);
            hi[k] = fmax(hi[k], s->xyz[3 * i + (size_t)k]);
        }
    info->extent = s->n_nodes ? fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2])) : 0;
    THX_TRY(remove_unused(ctx, s, &info->n_unused_removed, &info->first_unused));
    if (info->first_unused >= 0 && info->index_base > 0) info->first_unused += info->index_base;

    st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
    if (st != THX_OK && st != THX_ECHECK) goto done;
    if (inward_only(&info->report)) {
        for (size_t t = 0; t < s->n_tris; t++) {
            int32_t tmp = s->tri[3 * t + 1];
            s->tri[3 * t + 1] = s->tri[3 * t + 2];
            s->tri[3 * t + 2] = tmp;
        }
        info->reversed = 1;
        info->omega_before = info->report.solid_angle;
        thx_surface_report_free(&info->report);
        st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
        if (st != THX_OK && st != THX_ECHECK) goto done;
    }
    if (st == THX_ECHECK) {
        info->check_failed = 1;
        const thx_surface_report *r = &info->report;
        if (!opts->force) {
            char more[48] = "";
            if (r->n_reasons > 1) snprintf(more, sizeof more, " (and %zu more)", r->n_reasons - 1);
            st = thx_error(ctx, THX_ECHECK, "%s: surface \"%s\": refused: %s%s", path, name,
                           r->n_reasons ? r->reasons[0] : "failed its checks", more);
            goto done;
        }
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    if (info == &local) thx_import_info_free(&local);
    return st;
}
