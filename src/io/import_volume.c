/*
 * Volume meshes made elsewhere: readers for .pts + .tet/.elem (plain and
 * CARP), legacy VTK and VTK XML unstructured grids and Gmsh MSH 4.1, and
 * the import policy that turns one into a model (see thorax/import.h).
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Every reader fills one store (struct raw): nodes, tetrahedra with
 *    0-based nodes checked against the node count as they arrive, the
 *    file's region number per tetrahedron, and where the file has each
 *    tetrahedron (a line, a VTK cell index or a Gmsh element tag), so that
 *    a later refusal (a flat tetrahedron) still names it as the file does.
 *
 *  - Counts a file declares are never trusted beyond its size: before an
 *    array is allocated for n values, the bytes left must be able to hold
 *    them (binary: n times the value size; text: two characters a value;
 *    base64: four characters for three bytes; zlib: at most 1032 bytes out
 *    for one byte in, zlib's limit). Every reader requires its file to be
 *    complete (the closing line of every Gmsh section, the last value of
 *    every array): a file cut short is an error, never half a mesh.
 *
 *  - Surfaces come from face counts only (a face in one tetrahedron is a
 *    boundary face; in two of different regions an interface face): a
 *    sort of the 4T faces, a union-find over their nodes, a sum of signed
 *    volumes. No geometric predicate beyond the orientation of each
 *    tetrahedron, so this small step stays in io/.
 *
 *  - Model surfaces may not share nodes (a volume node is on at most one
 *    surface node: thorax/model.h), so an interface that touches the outer
 *    boundary or another interface cannot be a surface of its own; it is
 *    recorded in info->dropped, and the volume check judges the rest.
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
#include <zlib.h>

#include "io/import_text.h"
#include "thorax/fileio.h"
#include "thorax/predicates.h"

/* ------------------------------------------------------------ formats */

static const char *const vformat_names[] = {"none", "pts/tet", "vtk", "vtu", "msh"};

const char *thx_volume_format_name(thx_volume_format f)
{
    return (f >= THX_VOLFMT_NONE && f <= THX_VOLFMT_MSH) ? vformat_names[f] : "unknown";
}

int thx_volume_format_parse(const char *s, thx_volume_format *out)
{
    static const struct { const char *name; thx_volume_format f; } tab[] = {
        {"tet", THX_VOLFMT_PTS}, {"elem", THX_VOLFMT_PTS}, {"carp", THX_VOLFMT_PTS}, {"pts/tet", THX_VOLFMT_PTS},
        {"vtk", THX_VOLFMT_VTK}, {"vtu", THX_VOLFMT_VTU}, {"msh", THX_VOLFMT_MSH},
    };
    if (!s) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcasecmp(s, tab[i].name) == 0) {
            *out = tab[i].f;
            return 0;
        }
    return -1;
}


static int readable(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    fclose(f);
    return 1;
}

/* path with its extension replaced by ext (in upper case if the old one
 * starts upper case); 0, or -1 if it does not fit or there is none. */
static int with_extension(char *out, size_t size, const char *path, const char *ext)
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

/* Does the legacy VTK file at path declare DATASET UNSTRUCTURED_GRID? */
static int vtk_is_ugrid(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    cursor c = {buf, n, 0, 1};
    if (n < 5 || strncasecmp(buf, "# vtk", 5) != 0) return 0;
    next_line(&c);
    next_line(&c);
    const char *t;
    int line;
    size_t k = next_token(&c, &t, &line); /* ASCII or BINARY */
    if (!k) return 0;
    k = next_token(&c, &t, &line);
    if (!tok_is(t, k, "DATASET")) return 0;
    k = next_token(&c, &t, &line);
    return tok_is(t, k, "UNSTRUCTURED_GRID");
}

thx_volume_format thx_volume_format_from_path(const char *path)
{
    if (!path) return THX_VOLFMT_NONE;
    const char *ext = path_extension(path);
    if (!strcasecmp(ext, "msh")) return THX_VOLFMT_MSH;
    if (!strcasecmp(ext, "vtu")) return THX_VOLFMT_VTU;
    if (!strcasecmp(ext, "tet") || !strcasecmp(ext, "elem")) return THX_VOLFMT_PTS;
    if (!strcasecmp(ext, "vtk")) return vtk_is_ugrid(path) ? THX_VOLFMT_VTK : THX_VOLFMT_NONE;
    if (!strcasecmp(ext, "pts")) {
        char other[1024];
        if (with_extension(other, sizeof other, path, "fac") == 0 && readable(other)) return THX_VOLFMT_NONE;
        if (with_extension(other, sizeof other, path, "tet") == 0 && readable(other)) return THX_VOLFMT_PTS;
        if (with_extension(other, sizeof other, path, "elem") == 0 && readable(other)) return THX_VOLFMT_PTS;
    }
    return THX_VOLFMT_NONE;
}

void thx_volume_import_opts_default(thx_volume_import_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = THX_VOLFMT_NONE;
    o->scale = 1.0;
    thx_check_opts_default(&o->check);
    thx_volume_check_opts_default(&o->vcheck);
}

void thx_volume_import_info_free(thx_volume_import_info *info)
{
    if (!info) return;
    free(info->regions);
    free(info->surfaces);
    if (info->surface_reports)
        for (size_t s = 0; s < info->n_surfaces; s++) thx_surface_report_free(&info->surface_reports[s]);
    free(info->surface_reports);
    thx_volume_report_free(&info->volume_report);
    memset(info, 0, sizeof *info);
}

/* ------------------------------------------------------- the mesh store */

typedef struct {
    int dim;
    long long tag;
    char name[128];
} tag_name;

typedef struct {
    thx_ctx *ctx;
    const char *path;     /* the file being read (for messages) */
    double *xyz;
    size_t n_nodes, cap_nodes;
    long long *node_tag;  /* Gmsh: the file's node tags (else NULL: nodes are numbered by position) */
    size_t cap_node_tag;
    int32_t *tet;         /* 4 per tetrahedron, 0-based */
    long long *tag;       /* per tetrahedron: the file's region number (0 when has_tags is 0) */
    long long *ref;       /* per tetrahedron: where the file has it (ref_kind) */
    size_t n_tets, cap_tets, cap_tag, cap_ref;
    const char *ref_kind; /* "line", "cell", "element" */
    int has_tags;
    int32_t *tri;         /* Gmsh triangles of named physical surfaces (0-based nodes) */
    long long *tri_tag;
    size_t n_tris, cap_tri, cap_tri_tag;
    tag_name *names;      /* Gmsh physical names, dimensions 2 and 3 */
    size_t n_names, cap_names;
    size_t n_ignored;     /* cells of dimension 0-2 */
    char detail[96];
    char region_source[160];
    int index_base, index_base_detected;
    char path2[1024];
} raw;

static void raw_free(raw *r)
{
    free(r->xyz);
    free(r->node_tag);
    free(r->tet);
    free(r->tag);
    free(r->ref);
    free(r->tri);
    free(r->tri_tag);
    free(r->names);
}

/* Where an error is: a line of text (line > 0), a byte offset (line == 0,
 * byte != NOWHERE) or the file as a whole. */
typedef struct { int line; size_t byte; } where;
#define NOWHERE ((size_t)-1)
static where at_line(int line) { where w = {line, NOWHERE}; return w; }
static where at_byte(size_t byte) { where w = {0, byte}; return w; }
static where at_file(void) { where w = {0, NOWHERE}; return w; }

static thx_status fail(raw *r, where w, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static thx_status fail(raw *r, where w, const char *fmt, ...)
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

static thx_status add_node(raw *r, where w, double x, double y, double z)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(z)) return fail(r, w, "node %zu has a non-finite coordinate", r->n_nodes + 1);
    if (r->n_nodes >= (size_t)INT32_MAX) return fail(r, w, "too many nodes");
    if (r->n_nodes + 1 > r->cap_nodes) THX_CHECK(thx_grow(r->ctx, (void **)&r->xyz, &r->cap_nodes, r->n_nodes + 1, 3 * sizeof *r->xyz));
    double *p = r->xyz + 3 * r->n_nodes++;
    p[0] = x, p[1] = y, p[2] = z;
    return THX_OK;
}

/* Adds a tetrahedron of four 0-based nodes already checked against n_nodes. */
static thx_status add_tet(raw *r, const int32_t v[4], long long tag, long long ref)
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

static thx_status add_name(raw *r, int dim, long long tag, const char *name, size_t n)
{
    if (r->n_names + 1 > r->cap_names)
        THX_CHECK(thx_grow(r->ctx, (void **)&r->names, &r->cap_names, r->n_names + 1, sizeof *r->names));
    tag_name *e = &r->names[r->n_names++];
    e->dim = dim;
    e->tag = tag;
    copy_tok(e->name, sizeof e->name, name, n);
    return THX_OK;
}

static const char *name_of(const raw *r, int dim, long long tag)
{
    for (size_t i = 0; i < r->n_names; i++)
        if (r->names[i].dim == dim && r->names[i].tag == tag) return r->names[i].name;
    return NULL;
}

/* The tokens of the current line, from the cursor to the line's end (at
 * most max kept); returns how many there are (possibly more than max). */
typedef struct { const char *t; size_t n; } tok;
static size_t line_tokens(cursor *c, tok *tk, size_t max)
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
static int to_filled_line(cursor *c)
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
static size_t read_line(cursor *c, tok *tk, size_t max, int *line)
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

static int tk_int(const tok *t, long long *v) { return parse_int(t->t, t->n, v); }

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

static thx_status read_ptselem(raw *r, const char *path, const char *elem_path)
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
    st = read_pts(r, text, len, &counted);
    free(text);
    text = NULL;
    if (st) return st;
    r->path = elem;
    THX_CHECK(thx_read_file(r->ctx, elem, &text, &len));
    st = read_elem(r, text, len, counted);
    free(text);
    r->path = path;
    return st;
}

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

/* A candidate region array: one value per cell. */
typedef struct {
    char name[128];
    double *v;
    size_t n;
} cell_array;

/* Region arrays by name, in order of preference (case-insensitive). */
static const char *const region_names[] = {"region", "regions", "gmsh:physical", "CellEntityIds", "material",
                                           "materials", "MaterialIds", "tissue", "elemTag", "tag"};

static int integral(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (v[i] != floor(v[i]) || fabs(v[i]) > 9007199254740992.0) return 0;
    return 1;
}

/* Chooses the region array (index into a, or -1) by the rule in import.h. */
static thx_status choose_region_array(raw *r, const cell_array *a, size_t n, const char *want, int *out)
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

/* Turns cells (VTK types, offsets into conn) into tetrahedra, with the
 * region array reg (NULL: one region). off has n_cells + 1 entries. */
static thx_status vtk_tets(raw *r, where w, const double *types, const double *off, size_t n_cells, const double *conn,
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
            if (!v) continue;
            int bad;
            if (ty >= T_F32) {
                bad = parse_num(t, n, &v[i]) != 0;
            } else {
                long long x = 0;
                bad = parse_int(t, n, &x) != 0;
                v[i] = (double)x;
            }
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
    if (!n || parse_int(t, n, out) != 0 || *out < 0 || *out > INT32_MAX)
        return fail(r, at_line(line), "%s: expected a count", what);
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

static thx_status read_vtk_ugrid(raw *r, const char *text, size_t len, const char *region_array)
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
    THX_TRY(choose_region_array(r, arr, n_arr, region_array, &ri));
    THX_TRY(vtk_tets(r, at_line(cells_line), types, off, n_cells, conn, n_conn, ri >= 0 ? arr[ri].v : NULL,
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

/* ---------------------------------------------------------- VTK XML (.vtu) */

/* Binary data: raw bytes or base64 text (concatenated encodings allowed:
 * VTK encodes a header and its data separately). */
typedef struct {
    const unsigned char *p, *end;
    int b64;
    unsigned char q[3];
    int nq, iq;
} bstream;

static int b64_value(unsigned char ch)
{
    if (ch >= 'A' && ch <= 'Z') return ch - 'A';
    if (ch >= 'a' && ch <= 'z') return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9') return ch - '0' + 52;
    if (ch == '+') return 62;
    if (ch == '/') return 63;
    return -1;
}

/* Reads n bytes; 0, or -1 (end of data, or not base64). */
static int bs_read(bstream *s, unsigned char *out, size_t n)
{
    if (!s->b64) {
        if ((size_t)(s->end - s->p) < n) return -1;
        if (out) memcpy(out, s->p, n);
        s->p += n;
        return 0;
    }
    for (size_t i = 0; i < n;) {
        if (s->iq < s->nq) {
            unsigned char b = s->q[s->iq++];
            if (out) out[i] = b;
            i++;
            continue;
        }
        int v[4], k = 0;
        while (k < 4) {
            if (s->p >= s->end || *s->p == '<') return -1;
            unsigned char ch = *s->p++;
            if (isspace(ch)) continue;
            v[k] = ch == '=' ? -2 : b64_value(ch);
            if (v[k] == -1) return -1;
            k++;
        }
        if (v[0] < 0 || v[1] < 0 || (v[2] == -2 && v[3] != -2)) return -1;
        s->q[0] = (unsigned char)(v[0] << 2 | v[1] >> 4);
        s->nq = 1;
        if (v[2] >= 0) {
            s->q[1] = (unsigned char)((v[1] & 15) << 4 | v[2] >> 2);
            s->nq = 2;
            if (v[3] >= 0) {
                s->q[2] = (unsigned char)((v[2] & 3) << 6 | v[3]);
                s->nq = 3;
            }
        }
        s->iq = 0;
    }
    return 0;
}

/* An upper bound of the bytes left. */
static size_t bs_left(const bstream *s)
{
    size_t n = (size_t)(s->end - s->p);
    return s->b64 ? n / 4 * 3 + 3 + (size_t)(s->nq - s->iq) : n;
}

typedef struct {
    const char *text;      /* the whole file */
    size_t len;
    const char *xml_end;   /* where XML parsing stops: <AppendedData, else the end */
    int big;               /* byte_order="BigEndian" */
    int header64;          /* header_type="UInt64" */
    int zlib;              /* compressor="vtkZLibDataCompressor" */
    const char *app;       /* the first byte after the appended data's '_' (NULL: none) */
    int app_b64;           /* appended encoding="base64" */
} vtu_file;

static scalar_type vtu_type(const char *s)
{
    static const struct { const char *name; scalar_type ty; } tab[] = {
        {"Int8", T_I8}, {"UInt8", T_U8}, {"Int16", T_I16}, {"UInt16", T_U16}, {"Int32", T_I32}, {"UInt32", T_U32},
        {"Int64", T_I64}, {"UInt64", T_U64}, {"Float32", T_F32}, {"Float64", T_F64},
        /* VTK 0.1-era names */
        {"Char", T_I8}, {"UChar", T_U8}, {"Short", T_I16}, {"UShort", T_U16}, {"Int", T_I32}, {"UInt", T_U32},
        {"Float", T_F32}, {"Double", T_F64},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (!strcmp(s, tab[i].name)) return tab[i].ty;
    return T_NONE;
}

static int read_uint(bstream *b, const vtu_file *f, uint64_t *out)
{
    unsigned char q[8];
    size_t k = f->header64 ? 8 : 4;
    if (bs_read(b, q, k) != 0) return -1;
    *out = (uint64_t)get_scalar(q, f->header64 ? T_U64 : T_U32, f->big);
    return 0;
}

/* The bytes of one binary DataArray (header + data, compressed or not),
 * nbytes expected, into a new buffer. */
static thx_status vtu_block(raw *r, const vtu_file *f, bstream *b, where w, const char *what, size_t nbytes,
                            unsigned char **out)
{
    thx_status st = THX_OK;
    unsigned char *data = NULL, *cbuf = NULL;
    uint64_t *csize = NULL;
    *out = NULL;
    if (!f->zlib) {
        uint64_t nb;
        if (read_uint(b, f, &nb) != 0) return fail(r, w, "%s: the binary data end before their header", what);
        if (nb != (uint64_t)nbytes)
            return fail(r, w, "%s: the data hold %llu bytes, %zu expected", what, (unsigned long long)nb, nbytes);
        if (nbytes > bs_left(b)) return fail(r, w, "%s: %zu bytes declared, but the data are shorter", what, nbytes);
        data = thx_malloc(r->ctx, nbytes ? nbytes : 1);
        if (!data) return THX_ENOMEM;
        if (bs_read(b, data, nbytes) != 0) {
            free(data);
            return fail(r, w, "%s: the data end before their %zu bytes (or are not valid base64)", what, nbytes);
        }
        *out = data;
        return THX_OK;
    }
    uint64_t nblk, bsz, last;
    if (read_uint(b, f, &nblk) != 0 || read_uint(b, f, &bsz) != 0 || read_uint(b, f, &last) != 0)
        return fail(r, w, "%s: the compressed data end before their header", what);
    if (nblk > bs_left(b) / (f->header64 ? 8 : 4))
        return fail(r, w, "%s: %llu compressed blocks declared, but the data are too short", what, (unsigned long long)nblk);
    uint64_t total = nblk == 0 ? 0 : (nblk - 1) * bsz + (last ? last : bsz);
    if (total != (uint64_t)nbytes)
        return fail(r, w, "%s: the compressed data hold %llu bytes, %zu expected", what, (unsigned long long)total, nbytes);
    csize = thx_malloc(r->ctx, (nblk ? nblk : 1) * sizeof *csize);
    if (!csize) return THX_ENOMEM;
    uint64_t csum = 0, cmax = 0;
    for (uint64_t i = 0; i < nblk; i++) {
        if (read_uint(b, f, &csize[i]) != 0) {
            st = fail(r, w, "%s: the compressed data end in their header", what);
            goto done;
        }
        csum += csize[i];
        if (csize[i] > cmax) cmax = csize[i];
    }
    if (csum > bs_left(b) || (uint64_t)nbytes > 1032 * csum + 64) {
        st = fail(r, w, "%s: compressed sizes (%llu bytes) inconsistent with the data", what, (unsigned long long)csum);
        goto done;
    }
    data = thx_malloc(r->ctx, nbytes ? nbytes : 1);
    cbuf = thx_malloc(r->ctx, cmax ? cmax : 1);
    if (!data || !cbuf) {
        st = THX_ENOMEM;
        goto done;
    }
    size_t at = 0;
    for (uint64_t i = 0; i < nblk; i++) {
        if (bs_read(b, cbuf, csize[i]) != 0) {
            st = fail(r, w, "%s: compressed block %llu ends early", what, (unsigned long long)i + 1);
            goto done;
        }
        uLongf dl = (uLongf)((i + 1 == nblk && last) ? last : bsz);
        uLongf want = dl;
        int zr = uncompress(data + at, &dl, cbuf, (uLong)csize[i]);
        if (zr != Z_OK || dl != want) {
            st = fail(r, w, "%s: compressed block %llu is not valid zlib data of %lu bytes", what, (unsigned long long)i + 1,
                      (unsigned long)want);
            goto done;
        }
        at += dl;
    }
    *out = data;
    data = NULL;
done:
    free(data);
    free(cbuf);
    free(csize);
    return st;
}

/* Reads the DataArray whose tag starts at tag: count values (components
 * included) into a new array. what names it in messages. */
static thx_status vtu_array(raw *r, const vtu_file *f, const char *tag, const char *what, size_t count, double **out)
{
    const char *end = f->xml_end;
    where w = at_line(line_of(f->text, tag));
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    if (!gt) return fail(r, w, "%s: unterminated <DataArray> tag", what);
    char val[64] = "";
    if (xml_attr(tag, gt, "type", val, sizeof val) != 0) return fail(r, w, "%s: DataArray without a type", what);
    scalar_type ty = vtu_type(val);
    if (!ty) return fail(r, w, "%s: DataArray type \"%s\" is not supported", what, val);
    char fmt[32] = "ascii";
    xml_attr(tag, gt, "format", fmt, sizeof fmt);
    int self_closing = gt > tag && gt[-1] == '/';
    double *v = NULL;
    if (!strcmp(fmt, "ascii")) {
        if (self_closing) return fail(r, w, "%s: ascii DataArray without data", what);
        const char *lt = memchr(gt, '<', (size_t)(end - gt));
        if (!lt) return fail(r, w, "%s: DataArray without its closing tag", what);
        cursor c = {gt + 1, (size_t)(lt - gt - 1), 0, line_of(f->text, gt)};
        if (count > c.len / 2 + 1) return fail(r, w, "%s: %zu values declared, but the DataArray is too short for them", what, count);
        v = thx_malloc(r->ctx, (count ? count : 1) * sizeof *v);
        if (!v) return THX_ENOMEM;
        for (size_t i = 0; i < count; i++) {
            const char *t;
            int line;
            size_t n = next_token(&c, &t, &line);
            int bad = !n;
            if (n && ty >= T_F32) bad = parse_num(t, n, &v[i]) != 0;
            else if (n) {
                long long x = 0;
                bad = parse_int(t, n, &x) != 0;
                v[i] = (double)x;
            }
            if (bad) {
                free(v);
                if (!n) return fail(r, at_line(line), "%s: the DataArray ends at value %zu of %zu", what, i + 1, count);
                return fail(r, at_line(line), "%s: value %zu \"%s\" is not %s", what, i + 1, tok_show(t, n),
                            ty >= T_F32 ? "a finite number" : "an integer");
            }
        }
        const char *t;
        int line;
        if (next_token(&c, &t, &line)) {
            free(v);
            return fail(r, at_line(line), "%s: more than the %zu values expected", what, count);
        }
        *out = v;
        return THX_OK;
    }
    bstream b;
    memset(&b, 0, sizeof b);
    if (!strcmp(fmt, "binary")) {
        if (self_closing) return fail(r, w, "%s: binary DataArray without data", what);
        const char *lt = memchr(gt, '<', (size_t)(end - gt));
        if (!lt) return fail(r, w, "%s: DataArray without its closing tag", what);
        b.p = (const unsigned char *)gt + 1, b.end = (const unsigned char *)lt, b.b64 = 1;
    } else if (!strcmp(fmt, "appended")) {
        if (!f->app) return fail(r, w, "%s: format=\"appended\" but the file has no <AppendedData> section", what);
        long long offs;
        if (xml_attr(tag, gt, "offset", val, sizeof val) != 0 || parse_int(val, strlen(val), &offs) != 0 || offs < 0 ||
            (size_t)offs > (size_t)(f->text + f->len - f->app))
            return fail(r, w, "%s: appended DataArray without a valid offset", what);
        b.p = (const unsigned char *)f->app + offs, b.end = (const unsigned char *)f->text + f->len, b.b64 = f->app_b64;
        w = at_byte((size_t)(f->app - f->text) + (size_t)offs);
    } else {
        return fail(r, w, "%s: DataArray format \"%s\" is not supported (ascii, binary, appended)", what, fmt);
    }
    if (count > SIZE_MAX / 16) return fail(r, w, "%s: too many values", what);
    size_t nbytes = count * type_size[ty];
    unsigned char *bytes = NULL;
    THX_CHECK(vtu_block(r, f, &b, w, what, nbytes, &bytes));
    v = thx_malloc(r->ctx, (count ? count : 1) * sizeof *v);
    if (!v) {
        free(bytes);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < count; i++) {
        v[i] = get_scalar(bytes + i * type_size[ty], ty, f->big);
        if (ty >= T_F32 && !isfinite(v[i])) {
            free(bytes);
            free(v);
            return fail(r, w, "%s: value %zu is not a finite number", what, i + 1);
        }
    }
    free(bytes);
    *out = v;
    return THX_OK;
}

/* The NumberOfComponents of a DataArray tag (1 when absent); -1 if invalid. */
static long long vtu_components(const char *tag, const char *end)
{
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    char val[32];
    long long nc = 1;
    if (gt && xml_attr(tag, gt, "NumberOfComponents", val, sizeof val) == 0 &&
        (parse_int(val, strlen(val), &nc) != 0 || nc < 1 || nc > 64))
        return -1;
    return nc;
}

/* The element `name` directly after from and before limit, with its closing tag. */
static const char *vtu_section(const char *from, const char *limit, const char *name, const char **close)
{
    const char *p = xml_find(from, limit, name);
    if (!p) return NULL;
    char ct[48];
    snprintf(ct, sizeof ct, "</%s>", name);
    size_t cl = strlen(ct);
    const char *q = p;
    *close = NULL;
    for (; q + cl <= limit; q++)
        if (!memcmp(q, ct, cl)) {
            *close = q;
            break;
        }
    return p;
}

static thx_status read_vtu(raw *r, const char *text, size_t len, const char *region_array)
{
    thx_status st = THX_OK;
    vtu_file f;
    memset(&f, 0, sizeof f);
    f.text = text, f.len = len;
    const char *end = text + len;
    double *pts = NULL, *conn = NULL, *off = NULL, *types = NULL;
    cell_array *arr = NULL;
    size_t n_arr = 0, cap_arr = 0;
    char val[96];
    /* the appended data may hold any bytes: XML is parsed only before it */
    const char *ad = xml_find(text, end, "AppendedData");
    f.xml_end = ad ? ad : end;
    const char *vf = xml_find(text, f.xml_end, "VTKFile");
    const char *vf_end = vf ? memchr(vf, '>', (size_t)(f.xml_end - vf)) : NULL;
    if (!vf_end) {
        st = fail(r, at_line(1), "not a VTK XML file (no <VTKFile>)");
        goto done;
    }
    int vline = line_of(text, vf);
    if (xml_attr(vf, vf_end, "type", val, sizeof val) != 0 || strcmp(val, "UnstructuredGrid") != 0) {
        st = fail(r, at_line(vline), "VTK XML file of type \"%s\": only \"UnstructuredGrid\" is a volume mesh%s", val,
                  !strcmp(val, "PolyData") ? " (a PolyData file is a surface)" : "");
        goto done;
    }
    if (xml_attr(vf, vf_end, "byte_order", val, sizeof val) == 0) {
        if (!strcmp(val, "BigEndian")) f.big = 1;
        else if (strcmp(val, "LittleEndian") != 0) {
            st = fail(r, at_line(vline), "unknown byte_order \"%s\"", val);
            goto done;
        }
    }
    if (xml_attr(vf, vf_end, "header_type", val, sizeof val) == 0) {
        if (!strcmp(val, "UInt64")) f.header64 = 1;
        else if (strcmp(val, "UInt32") != 0) {
            st = fail(r, at_line(vline), "unknown header_type \"%s\" (UInt32 or UInt64)", val);
            goto done;
        }
    }
    if (xml_attr(vf, vf_end, "compressor", val, sizeof val) == 0 && val[0]) {
        if (!strcmp(val, "vtkZLibDataCompressor")) f.zlib = 1;
        else {
            st = fail(r, at_line(vline), "compressor \"%s\" is not supported (only vtkZLibDataCompressor, or none)", val);
            goto done;
        }
    }
    if (ad) {
        const char *ad_end = memchr(ad, '>', (size_t)(end - ad));
        if (!ad_end) {
            st = fail(r, at_line(line_of(text, ad)), "unterminated <AppendedData> tag");
            goto done;
        }
        f.app_b64 = 1;
        if (xml_attr(ad, ad_end, "encoding", val, sizeof val) == 0) {
            if (!strcmp(val, "raw")) f.app_b64 = 0;
            else if (strcmp(val, "base64") != 0) {
                st = fail(r, at_line(line_of(text, ad)), "unknown AppendedData encoding \"%s\" (raw or base64)", val);
                goto done;
            }
        }
        const char *u = memchr(ad_end, '_', (size_t)(end - ad_end));
        if (!u) {
            st = fail(r, at_line(line_of(text, ad)), "<AppendedData> without its '_' marker");
            goto done;
        }
        f.app = u + 1;
    }
    const char *piece = xml_find(vf_end, f.xml_end, "Piece");
    const char *piece_end = piece ? memchr(piece, '>', (size_t)(f.xml_end - piece)) : NULL;
    if (!piece_end) {
        st = fail(r, at_line(vline), "no <Piece>");
        goto done;
    }
    int pline = line_of(text, piece);
    if (xml_find(piece_end, f.xml_end, "Piece")) {
        st = fail(r, at_line(pline), "more than one <Piece> is not supported");
        goto done;
    }
    long long np, nc;
    if (xml_attr(piece, piece_end, "NumberOfPoints", val, sizeof val) != 0 || parse_int(val, strlen(val), &np) != 0 || np < 0 ||
        np > INT32_MAX || xml_attr(piece, piece_end, "NumberOfCells", val, sizeof val) != 0 ||
        parse_int(val, strlen(val), &nc) != 0 || nc < 0 || nc > INT32_MAX) {
        st = fail(r, at_line(pline), "<Piece> needs valid NumberOfPoints and NumberOfCells");
        goto done;
    }
    const char *close;
    const char *ptag = vtu_section(piece_end, f.xml_end, "Points", &close);
    const char *da = ptag && close ? xml_find(ptag, close, "DataArray") : NULL;
    if (!da) {
        st = fail(r, at_line(pline), "<Piece> without <Points><DataArray>");
        goto done;
    }
    if (vtu_components(da, f.xml_end) != 3) {
        st = fail(r, at_line(line_of(text, da)), "Points: NumberOfComponents must be 3");
        goto done;
    }
    THX_TRY(vtu_array(r, &f, da, "Points", 3 * (size_t)np, &pts));
    {
        int pl = line_of(text, da);
        for (long long i = 0; i < np; i++) THX_TRY(add_node(r, at_line(pl), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
    }
    const char *cells = vtu_section(piece_end, f.xml_end, "Cells", &close);
    if (!cells || !close) {
        st = fail(r, at_line(pline), "<Piece> without a complete <Cells> element");
        goto done;
    }
    const char *ca = NULL, *oa = NULL, *ta = NULL;
    for (const char *p = cells; (p = xml_find(p + 1, close, "DataArray")) != NULL;) {
        const char *gt = memchr(p, '>', (size_t)(close - p));
        if (!gt || xml_attr(p, gt, "Name", val, sizeof val) != 0) continue;
        if (!strcmp(val, "connectivity")) ca = p;
        if (!strcmp(val, "offsets")) oa = p;
        if (!strcmp(val, "types")) ta = p;
    }
    if (!ca || !oa || !ta) {
        st = fail(r, at_line(line_of(text, cells)), "<Cells> needs DataArrays named \"connectivity\", \"offsets\" and \"types\"");
        goto done;
    }
    int cline = line_of(text, ca);
    THX_TRY(vtu_array(r, &f, oa, "Cells offsets", (size_t)nc, &off));
    THX_TRY(vtu_array(r, &f, ta, "Cells types", (size_t)nc, &types));
    double total = nc ? off[nc - 1] : 0;
    if (!(total >= 0 && total <= 64.0 * (double)(nc + 1))) {
        st = fail(r, at_line(line_of(text, oa)), "Cells offsets: last offset %g out of range", total);
        goto done;
    }
    THX_TRY(vtu_array(r, &f, ca, "Cells connectivity", (size_t)total, &conn));
    /* XML offsets are the ends of the cells: prepend the start 0 */
    double *o2 = thx_malloc(r->ctx, ((size_t)nc + 1) * sizeof *o2);
    if (!o2) {
        st = THX_ENOMEM;
        goto done;
    }
    o2[0] = 0;
    if (nc) memcpy(o2 + 1, off, (size_t)nc * sizeof *off);
    free(off);
    off = o2;
    const char *cd = vtu_section(piece_end, f.xml_end, "CellData", &close);
    if (cd && close) {
        for (const char *p = cd; (p = xml_find(p + 1, close, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(close - p));
            char nm[128] = "";
            if (!gt || xml_attr(p, gt, "Name", nm, sizeof nm) != 0 || vtu_components(p, f.xml_end) != 1) continue;
            char what[160];
            snprintf(what, sizeof what, "CellData \"%s\"", nm);
            char tyv[32] = "";
            if (xml_attr(p, gt, "type", tyv, sizeof tyv) == 0 && !vtu_type(tyv)) continue; /* strings etc. */
            double *v = NULL;
            THX_TRY(vtu_array(r, &f, p, what, (size_t)nc, &v));
            if (n_arr + 1 > cap_arr) {
                st = thx_grow(r->ctx, (void **)&arr, &cap_arr, n_arr + 1, sizeof *arr);
                if (st) {
                    free(v);
                    goto done;
                }
            }
            snprintf(arr[n_arr].name, sizeof arr[n_arr].name, "%s", nm);
            arr[n_arr].v = v, arr[n_arr].n = (size_t)nc;
            n_arr++;
        }
    }
    int ri;
    THX_TRY(choose_region_array(r, arr, n_arr, region_array, &ri));
    THX_TRY(vtk_tets(r, at_line(cline), types, off, (size_t)nc, conn, (size_t)total, ri >= 0 ? arr[ri].v : NULL,
                     ri >= 0 ? arr[ri].name : NULL));
    if (ri >= 0) snprintf(r->region_source, sizeof r->region_source, "cell array \"%s\"", arr[ri].name);
    else snprintf(r->region_source, sizeof r->region_source, "none (one region%s)",
                  n_arr ? ": no cell array is named as a region array; give --region-array" : "");
    {
        int any_app = 0, any_bin = 0, any_ascii = 0;
        for (const char *p = piece; (p = xml_find(p + 1, f.xml_end, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(f.xml_end - p));
            char fm[32] = "ascii";
            if (gt) xml_attr(p, gt, "format", fm, sizeof fm);
            any_app |= !strcmp(fm, "appended"), any_bin |= !strcmp(fm, "binary"), any_ascii |= !strcmp(fm, "ascii");
        }
        snprintf(r->detail, sizeof r->detail, "VTK XML UnstructuredGrid (%s%s%s%s%s)",
                 any_ascii ? "ascii" : "", any_ascii && (any_bin || any_app) ? ", " : "", any_bin ? "binary" : "",
                 any_bin && any_app ? ", " : "",
                 any_app ? (f.app_b64 ? "appended base64" : "appended raw") : "");
        if (f.zlib) snprintf(r->detail + strlen(r->detail) - 1, sizeof r->detail - strlen(r->detail) + 1, ", zlib)");
    }
    r->index_base = 0;
done:
    free(pts);
    free(conn);
    free(off);
    free(types);
    for (size_t i = 0; i < n_arr; i++) free(arr[i].v);
    free(arr);
    return st;
}

/* ---------------------------------------------------------- Gmsh .msh */

typedef struct {
    long long tag;
    long long phys; /* the physical tag when n_phys == 1 */
    int n_phys;
} msh_entity;

static int cmp_entity(const void *a, const void *b)
{
    long long x = ((const msh_entity *)a)->tag, y = ((const msh_entity *)b)->tag;
    return x < y ? -1 : x > y;
}

static const msh_entity *find_entity(const msh_entity *e, size_t n, long long tag)
{
    msh_entity key = {tag, 0, 0};
    return bsearch(&key, e, n, sizeof *e, cmp_entity);
}

typedef struct { long long tag; int32_t index; } node_key;

static int cmp_node_key(const void *a, const void *b)
{
    long long x = ((const node_key *)a)->tag, y = ((const node_key *)b)->tag;
    return x < y ? -1 : x > y;
}

static const char *msh_type_name(long long type)
{
    switch (type) {
    case 1: return "2-node line";
    case 2: return "3-node triangle";
    case 3: return "4-node quadrangle";
    case 4: return "4-node tetrahedron";
    case 5: return "8-node hexahedron";
    case 6: return "6-node prism";
    case 7: return "5-node pyramid";
    case 11: return "10-node second-order tetrahedron";
    case 12: return "27-node hexahedron";
    case 13: return "18-node prism";
    case 14: return "14-node pyramid";
    case 15: return "1-node point";
    case 17: return "20-node hexahedron";
    case 18: return "15-node prism";
    case 19: return "13-node pyramid";
    case 29: return "20-node third-order tetrahedron";
    default: return "not a 4-node tetrahedron";
    }
}

/* Skips lines to "$End<name>" (after the section's opening line). */
static thx_status msh_skip_section(raw *r, cursor *c, const char *name, int open_line)
{
    char want[80];
    snprintf(want, sizeof want, "$End%s", name);
    tok tk[1];
    int line;
    size_t k;
    while ((k = read_line(c, tk, 1, &line)) != 0)
        if (tok_is(tk[0].t, tk[0].n, want)) return THX_OK;
    return fail(r, at_line(open_line), "section $%s is not closed by %s (file truncated?)", name, want);
}

static thx_status msh_end(raw *r, cursor *c, const char *name)
{
    char want[80];
    snprintf(want, sizeof want, "$End%s", name);
    tok tk[2];
    int line;
    size_t k = read_line(c, tk, 2, &line);
    if (k != 1 || !tok_is(tk[0].t, tk[0].n, want))
        return fail(r, at_line(line), "expected %s, found %s", want, k ? tok_show(tk[0].t, tk[0].n) : "the end of the file");
    return THX_OK;
}

/* The counts on a section's header line: n integers >= 0. */
static thx_status msh_counts(raw *r, cursor *c, const char *what, int n, long long *v)
{
    tok tk[8];
    int line;
    size_t k = read_line(c, tk, 8, &line);
    if ((int)k != n) return fail(r, at_line(line), "%s: expected %d numbers on this line, found %zu", what, n, k);
    for (int i = 0; i < n; i++)
        if (tk_int(&tk[i], &v[i]) != 0 || v[i] < 0)
            return fail(r, at_line(line), "%s: \"%s\" is not a count", what, tok_show(tk[i].t, tk[i].n));
    return THX_OK;
}

static int cmp_ref(const void *a, const void *b)
{
    const long long *x = a, *y = b; /* (element tag, index) pairs */
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

/* Tetrahedra in the order of their element tags (blocks come per entity;
 * thorax's own export numbers elements as volume.tet's lines). */
static thx_status sort_tets_by_tag(raw *r, int line)
{
    size_t n = r->n_tets;
    long long *key = thx_malloc(r->ctx, 2 * (n ? n : 1) * sizeof *key);
    int32_t *tet = thx_malloc(r->ctx, 4 * (n ? n : 1) * sizeof *tet);
    long long *tag = thx_malloc(r->ctx, (n ? n : 1) * sizeof *tag);
    thx_status st = THX_OK;
    if (!key || !tet || !tag) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < n; t++) key[2 * t] = r->ref[t], key[2 * t + 1] = (long long)t;
    qsort(key, n, 2 * sizeof *key, cmp_ref);
    for (size_t t = 0; t < n; t++) {
        if (t && key[2 * t] == key[2 * t - 2]) {
            st = fail(r, at_line(line), "$Elements: element tag %lld appears twice", key[2 * t]);
            goto done;
        }
        size_t o = (size_t)key[2 * t + 1];
        memcpy(tet + 4 * t, r->tet + 4 * o, 4 * sizeof *tet);
        tag[t] = r->tag[o];
    }
    memcpy(r->tet, tet, 4 * n * sizeof *tet);
    memcpy(r->tag, tag, n * sizeof *tag);
    for (size_t t = 0; t < n; t++) r->ref[t] = key[2 * t];
done:
    free(key);
    free(tet);
    free(tag);
    return st;
}

static thx_status read_msh(raw *r, const char *text, size_t len)
{
    thx_status st = THX_OK;
    cursor c = {text, len, 0, 1};
    tok tk[16];
    int line;
    size_t k;
    msh_entity *ents[4] = {NULL, NULL, NULL, NULL};
    size_t n_ents[4] = {0, 0, 0, 0};
    int have_entities = 0, have_nodes = 0, have_elements = 0, phys3 = 0;
    node_key *keys = NULL;
    int32_t *tri_nodes = NULL;
    k = read_line(&c, tk, 2, &line);
    if (k != 1 || !tok_is(tk[0].t, tk[0].n, "$MeshFormat")) {
        st = fail(r, at_line(line), "not a Gmsh .msh file (no $MeshFormat on the first line)");
        goto done;
    }
    k = read_line(&c, tk, 4, &line);
    if (k != 3) {
        st = fail(r, at_line(line), "$MeshFormat: expected \"version file-type data-size\"");
        goto done;
    }
    if (!tok_is(tk[0].t, tk[0].n, "4.1")) {
        st = fail(r, at_line(line), "MSH version %s is not supported: only 4.1 (gmsh -format msh41, or Mesh.MshFileVersion = 4.1)",
                  tok_show(tk[0].t, tk[0].n));
        goto done;
    }
    if (!tok_is(tk[1].t, tk[1].n, "0")) {
        st = fail(r, at_line(line), "binary MSH files are not supported: write ASCII (Mesh.Binary = 0)");
        goto done;
    }
    THX_TRY(msh_end(r, &c, "MeshFormat"));
    while ((k = read_line(&c, tk, 2, &line)) != 0) {
        if (tk[0].n < 2 || tk[0].t[0] != '$') {
            st = fail(r, at_line(line), "expected a section ($Nodes, $Elements, ...), found \"%s\"", tok_show(tk[0].t, tk[0].n));
            goto done;
        }
        char name[64];
        copy_tok(name, sizeof name, tk[0].t + 1, tk[0].n - 1);
        int open_line = line;
        if (!strcmp(name, "PhysicalNames")) {
            long long n;
            THX_TRY(msh_counts(r, &c, "$PhysicalNames", 1, &n));
            if ((size_t)n > len / 8) {
                st = fail(r, at_line(open_line), "$PhysicalNames: %lld names declared, but the file is too short for them", n);
                goto done;
            }
            for (long long i = 0; i < n; i++) {
                if (!to_filled_line(&c)) {
                    st = fail(r, at_line(c.line), "$PhysicalNames: file ends at name %lld of %lld", i + 1, n);
                    goto done;
                }
                line = c.line;
                cursor lc = c;
                k = line_tokens(&lc, tk, 2);
                long long dim, tag;
                if (k < 3 || tk_int(&tk[0], &dim) != 0 || tk_int(&tk[1], &tag) != 0) {
                    st = fail(r, at_line(line), "$PhysicalNames: expected 'dimension tag \"name\"'");
                    goto done;
                }
                /* the name is quoted and may hold spaces */
                const char *ls = c.buf + c.pos, *le = memchr(ls, '\n', c.len - c.pos);
                if (!le) le = c.buf + c.len;
                const char *q1 = memchr(ls, '"', (size_t)(le - ls));
                const char *q2 = q1 ? memchr(q1 + 1, '"', (size_t)(le - q1 - 1)) : NULL;
                if (!q2) {
                    st = fail(r, at_line(line), "$PhysicalNames: the name must be in double quotes");
                    goto done;
                }
                if (dim == 2 || dim == 3) THX_TRY(add_name(r, (int)dim, tag, q1 + 1, (size_t)(q2 - q1 - 1)));
                next_line(&c);
            }
            THX_TRY(msh_end(r, &c, name));
        } else if (!strcmp(name, "Entities")) {
            long long cnt[4];
            THX_TRY(msh_counts(r, &c, "$Entities", 4, cnt));
            for (int d = 0; d < 4; d++) {
                if ((size_t)cnt[d] > len / 8) {
                    st = fail(r, at_line(open_line), "$Entities: %lld entities of dimension %d declared, but the file is too "
                              "short for them", cnt[d], d);
                    goto done;
                }
                if (d >= 2) {
                    ents[d] = thx_calloc(r->ctx, (size_t)cnt[d] + 1, sizeof *ents[d]);
                    if (!ents[d]) {
                        st = THX_ENOMEM;
                        goto done;
                    }
                }
                for (long long i = 0; i < cnt[d]; i++) {
                    k = read_line(&c, tk, 16, &line);
                    int at = d == 0 ? 4 : 7; /* numPhysicalTags after the tag and the coordinates / bounding box */
                    long long tag, np = 0;
                    if (k == 0) {
                        st = fail(r, at_line(line), "$Entities: file ends at entity %lld of dimension %d", i + 1, d);
                        goto done;
                    }
                    if (k < (size_t)at + 1 || tk_int(&tk[0], &tag) != 0 || tk_int(&tk[at], &np) != 0 || np < 0 ||
                        k < (size_t)(at + 1 + np)) {
                        st = fail(r, at_line(line), "$Entities: malformed entity of dimension %d", d);
                        goto done;
                    }
                    if (d < 2) continue;
                    msh_entity *e = &ents[d][n_ents[d]++];
                    e->tag = tag;
                    e->n_phys = (int)(np > 2 ? 2 : np);
                    if (np >= 1) {
                        if ((size_t)at + 1 >= 16 || tk_int(&tk[at + 1], &e->phys) != 0) {
                            st = fail(r, at_line(line), "$Entities: malformed physical tag");
                            goto done;
                        }
                        if (d == 3) phys3 = 1;
                    }
                }
                if (d >= 2) qsort(ents[d], n_ents[d], sizeof *ents[d], cmp_entity);
            }
            have_entities = 1;
            THX_TRY(msh_end(r, &c, name));
        } else if (!strcmp(name, "PartitionedEntities")) {
            st = fail(r, at_line(line), "partitioned meshes are not supported (write the mesh unpartitioned)");
            goto done;
        } else if (!strcmp(name, "Nodes")) {
            long long h[4];
            THX_TRY(msh_counts(r, &c, "$Nodes", 4, h));
            if ((size_t)h[1] > len / 8) {
                st = fail(r, at_line(open_line), "$Nodes: %lld nodes declared, but the file is too short for them", h[1]);
                goto done;
            }
            for (long long b = 0; b < h[0]; b++) {
                long long bh[4];
                THX_TRY(msh_counts(r, &c, "$Nodes block", 4, bh));
                long long dim = bh[0], param = bh[2], n = bh[3];
                if (dim > 3 || param > 1 || (size_t)n > (len - c.pos) / 8) {
                    st = fail(r, at_line(c.line - 1), "$Nodes: malformed block header (or more nodes than the file holds)");
                    goto done;
                }
                size_t first = r->n_nodes;
                if (first + (size_t)n > r->cap_node_tag)
                    THX_TRY(thx_grow(r->ctx, (void **)&r->node_tag, &r->cap_node_tag, first + (size_t)n, sizeof *r->node_tag));
                for (long long i = 0; i < n; i++) {
                    long long tag;
                    k = read_line(&c, tk, 2, &line);
                    if (k != 1 || tk_int(&tk[0], &tag) != 0 || tag < 1) {
                        st = fail(r, at_line(line), "$Nodes: expected a node tag (a positive integer)%s", k ? "" : ": file ends");
                        goto done;
                    }
                    r->node_tag[first + (size_t)i] = tag;
                }
                size_t want = 3 + (size_t)(param ? dim : 0);
                for (long long i = 0; i < n; i++) {
                    k = read_line(&c, tk, 8, &line);
                    double v[3];
                    if (k != want) {
                        st = fail(r, at_line(line), "$Nodes: node %lld: expected %zu coordinates, found %zu",
                                  r->node_tag[first + (size_t)i], want, k);
                        goto done;
                    }
                    for (int j = 0; j < 3; j++)
                        if (parse_num(tk[j].t, tk[j].n, &v[j]) != 0) {
                            st = fail(r, at_line(line), "$Nodes: node %lld: coordinate \"%s\" is not a finite number",
                                      r->node_tag[first + (size_t)i], tok_show(tk[j].t, tk[j].n));
                            goto done;
                        }
                    THX_TRY(add_node(r, at_line(line), v[0], v[1], v[2]));
                }
            }
            if (r->n_nodes != (size_t)h[1]) {
                st = fail(r, at_line(open_line), "$Nodes: %lld nodes declared, %zu in the blocks", h[1], r->n_nodes);
                goto done;
            }
            THX_TRY(msh_end(r, &c, name));
            keys = thx_malloc(r->ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *keys);
            if (!keys) {
                st = THX_ENOMEM;
                goto done;
            }
            for (size_t i = 0; i < r->n_nodes; i++) keys[i].tag = r->node_tag[i], keys[i].index = (int32_t)i;
            qsort(keys, r->n_nodes, sizeof *keys, cmp_node_key);
            for (size_t i = 1; i < r->n_nodes; i++)
                if (keys[i].tag == keys[i - 1].tag) {
                    st = fail(r, at_line(open_line), "$Nodes: node tag %lld appears twice", keys[i].tag);
                    goto done;
                }
            /* nodes in the order of their tags (a tag is a node's identity; thorax's
             * own export uses the volume node numbers) */
            {
                double *xyz = thx_malloc(r->ctx, 3 * (r->n_nodes ? r->n_nodes : 1) * sizeof *xyz);
                if (!xyz) {
                    st = THX_ENOMEM;
                    goto done;
                }
                for (size_t i = 0; i < r->n_nodes; i++) {
                    memcpy(xyz + 3 * i, r->xyz + 3 * (size_t)keys[i].index, 3 * sizeof *xyz);
                    r->node_tag[i] = keys[i].tag;
                    keys[i].index = (int32_t)i;
                }
                free(r->xyz);
                r->xyz = xyz;
                r->cap_nodes = r->n_nodes;
            }
            have_nodes = 1;
        } else if (!strcmp(name, "Elements")) {
            if (!have_nodes) {
                st = fail(r, at_line(line), "$Elements before $Nodes");
                goto done;
            }
            long long h[4];
            THX_TRY(msh_counts(r, &c, "$Elements", 4, h));
            if ((size_t)h[1] > len / 4) {
                st = fail(r, at_line(open_line), "$Elements: %lld elements declared, but the file is too short for them", h[1]);
                goto done;
            }
            long long seen = 0;
            for (long long b = 0; b < h[0]; b++) {
                long long bh[4];
                THX_TRY(msh_counts(r, &c, "$Elements block", 4, bh));
                int hline = c.line - 1;
                long long dim = bh[0], etag = bh[1], type = bh[2], n = bh[3];
                if (dim > 3 || (size_t)n > (len - c.pos) / 4) {
                    st = fail(r, at_line(hline), "$Elements: malformed block header (or more elements than the file holds)");
                    goto done;
                }
                seen += n;
                if (dim == 3 && type != 4) {
                    st = fail(r, at_line(hline), "elements of type %lld (%s) in volume %lld: only 4-node tetrahedra (type 4) "
                              "can be imported", type, msh_type_name(type), etag);
                    goto done;
                }
                if (type == 4 && dim != 3) {
                    st = fail(r, at_line(hline), "tetrahedra in an entity of dimension %lld", dim);
                    goto done;
                }
                long long region = etag, sphys = -1;
                if (dim == 3 && phys3) {
                    const msh_entity *e = find_entity(ents[3], n_ents[3], etag);
                    if (!e) {
                        st = fail(r, at_line(hline), "volume %lld is not listed in $Entities", etag);
                        goto done;
                    }
                    if (e->n_phys == 0) {
                        st = fail(r, at_line(hline), "volume %lld belongs to no physical group while other volumes do: "
                                  "give every volume one physical group, or none", etag);
                        goto done;
                    }
                    if (e->n_phys > 1) {
                        st = fail(r, at_line(hline), "volume %lld belongs to several physical groups: its region is ambiguous",
                                  etag);
                        goto done;
                    }
                    region = e->phys;
                }
                if (dim == 2 && type == 2 && have_entities) {
                    const msh_entity *e = find_entity(ents[2], n_ents[2], etag);
                    if (e && e->n_phys == 1 && name_of(r, 2, e->phys)) sphys = e->phys;
                }
                for (long long i = 0; i < n; i++) {
                    k = read_line(&c, tk, 8, &line);
                    if (k == 0) {
                        st = fail(r, at_line(line), "$Elements: file ends in a block of %lld elements", n);
                        goto done;
                    }
                    if (type != 4 && !(type == 2 && sphys >= 0)) {
                        r->n_ignored++;
                        continue;
                    }
                    size_t want = type == 4 ? 5 : 4;
                    long long tag;
                    if (k != want || tk_int(&tk[0], &tag) != 0) {
                        st = fail(r, at_line(line), "$Elements: expected an element tag and %zu node tags, found %zu values",
                                  want - 1, k);
                        goto done;
                    }
                    int32_t v[4];
                    for (size_t j = 1; j < want; j++) {
                        node_key key = {0, 0};
                        if (tk_int(&tk[j], &key.tag) != 0) {
                            st = fail(r, at_line(line), "element %lld: node tag \"%s\" is not an integer", tag,
                                      tok_show(tk[j].t, tk[j].n));
                            goto done;
                        }
                        const node_key *f = bsearch(&key, keys, r->n_nodes, sizeof *keys, cmp_node_key);
                        if (!f) {
                            st = fail(r, at_line(line), "element %lld refers to node %lld, which $Nodes does not have", tag,
                                      key.tag);
                            goto done;
                        }
                        v[j - 1] = f->index;
                    }
                    if (type == 4) {
                        THX_TRY(add_tet(r, v, region, tag));
                    } else {
                        if (r->n_tris + 1 > r->cap_tri)
                            THX_TRY(thx_grow(r->ctx, (void **)&r->tri, &r->cap_tri, r->n_tris + 1, 3 * sizeof *r->tri));
                        if (r->n_tris + 1 > r->cap_tri_tag)
                            THX_TRY(thx_grow(r->ctx, (void **)&r->tri_tag, &r->cap_tri_tag, r->n_tris + 1, sizeof *r->tri_tag));
                        memcpy(r->tri + 3 * r->n_tris, v, 3 * sizeof *v);
                        r->tri_tag[r->n_tris++] = sphys;
                    }
                }
            }
            if (seen != h[1]) {
                st = fail(r, at_line(open_line), "$Elements: %lld elements declared, %lld in the blocks", h[1], seen);
                goto done;
            }
            THX_TRY(sort_tets_by_tag(r, open_line));
            THX_TRY(msh_end(r, &c, name));
            have_elements = 1;
        } else {
            /* $Periodic, $NodeData, $ElementData, $Comments, ...: no mesh in them */
            THX_TRY(msh_skip_section(r, &c, name, open_line));
        }
    }
    if (!have_nodes || !have_elements) {
        st = fail(r, at_file(), "no %s section", have_nodes ? "$Elements" : "$Nodes");
        goto done;
    }
    r->has_tags = 1;
    r->ref_kind = "element";
    r->index_base = 1;
    snprintf(r->detail, sizeof r->detail, "Gmsh MSH 4.1 ASCII");
    snprintf(r->region_source, sizeof r->region_source, "%s",
             phys3 ? "physical groups (dimension 3)" : "volume entities (no physical groups)");
done:
    for (int d = 0; d < 4; d++) free(ents[d]);
    free(keys);
    free(tri_nodes);
    return st;
}

/* ------------------------------------------------------------- names */

/* A region or surface name from any text: [A-Za-z0-9_.-], other characters
 * as '_', at most 31 characters, not starting with '.'; "" if in is empty. */
static void clean_name(char *out, const char *in)
{
    size_t k = 0;
    for (const char *p = in; *p && k < 31; p++) {
        char c = *p;
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                 c == '.';
        out[k++] = ok ? c : '_';
    }
    out[k] = '\0';
    if (out[0] == '.') out[0] = '_';
}

static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > 31 || s[0] == '.') return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.'))
            return 0;
    }
    return 1;
}

/* Makes name unique among used[0..n) by appending "_2", "_3", ... */
static void unique_name(char *name, char (*used)[64], size_t n)
{
    char base[64];
    snprintf(base, sizeof base, "%s", name);
    for (int k = 1;; k++) {
        int clash = 0;
        for (size_t i = 0; i < n && !clash; i++) clash = !strcmp(used[i], name);
        if (!clash) return;
        char suffix[16];
        snprintf(suffix, sizeof suffix, "_%d", k + 1);
        size_t bl = strlen(base), sl = strlen(suffix);
        if (bl + sl > 31) bl = 31 - sl;
        snprintf(name, 64, "%.*s%s", (int)bl, base, suffix);
    }
}

/* ------------------------------------------------------------- faces */

/* The outward faces of a right-handed tetrahedron p0..p3, counterclockwise
 * seen from outside (thorax/check_volume.h). */
static const int tet_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

typedef struct { int32_t a, b, c, tf; } face_rec; /* sorted nodes; tf = 4 * tet + local face */

static int cmp_face(const void *x, const void *y)
{
    const face_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    if (p->c != q->c) return p->c < q->c ? -1 : 1;
    return (p->tf > q->tf) - (p->tf < q->tf);
}

/* Sorts faces by (a, b, c, tf). Below 2^21 nodes the three node numbers
 * pack into one 63-bit key and an LSD radix sort (stable, so ties stay in tf
 * order, as the input is) does it in 8 passes at most: about ten times faster
 * than qsort on the 4.8 M faces of 1.2 M tetrahedra. */
static thx_status sort_faces(thx_ctx *ctx, face_rec *fr, size_t n, size_t n_nodes)
{
    if (n_nodes >= ((size_t)1 << 21) || n < 1024) {
        qsort(fr, n, sizeof *fr, cmp_face);
        return THX_OK;
    }
    typedef struct { uint64_t key; int32_t tf; } fkey;
    fkey *a = thx_malloc(ctx, n * sizeof *a), *b = thx_malloc(ctx, n * sizeof *b);
    if (!a || !b) {
        free(a);
        free(b);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n; i++)
        a[i].key = (uint64_t)fr[i].a << 42 | (uint64_t)fr[i].b << 21 | (uint64_t)fr[i].c, a[i].tf = fr[i].tf;
    for (int shift = 0; shift < 64; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++) count[(a[i].key >> shift & 255) + 1]++;
        int all_one = 0;
        for (int k = 1; k <= 256; k++) all_one |= count[k] == n;
        if (all_one) continue; /* every key has the same byte here */
        for (int k = 1; k <= 256; k++) count[k] += count[k - 1];
        for (size_t i = 0; i < n; i++) b[count[a[i].key >> shift & 255]++] = a[i];
        fkey *t = a;
        a = b, b = t;
    }
    const uint64_t m21 = ((uint64_t)1 << 21) - 1;
    for (size_t i = 0; i < n; i++) {
        fr[i].a = (int32_t)(a[i].key >> 42), fr[i].b = (int32_t)(a[i].key >> 21 & m21), fr[i].c = (int32_t)(a[i].key & m21);
        fr[i].tf = a[i].tf;
    }
    free(a);
    free(b);
    return THX_OK;
}

static void sort3(int32_t *v)
{
    int32_t t;
    if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
    if (v[1] > v[2]) t = v[1], v[1] = v[2], v[2] = t;
    if (v[0] > v[1]) t = v[0], v[0] = v[1], v[1] = t;
}

/* The outward triangle of face tf of a right-handed tetrahedron. */
static void face_tri(const int32_t *tet, int32_t tf, int32_t out[3])
{
    const int32_t *q = tet + 4 * (size_t)(tf / 4);
    for (int j = 0; j < 3; j++) out[j] = q[tet_face[tf % 4][j]];
}

static int32_t uf_find(int32_t *p, int32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static void uf_union(int32_t *p, int32_t a, int32_t b)
{
    a = uf_find(p, a), b = uf_find(p, b);
    if (a != b) p[a < b ? b : a] = a < b ? a : b;
}

/* Signed volume enclosed by triangles (3 volume nodes each), about ref. */
static double tris_volume(const double *xyz, const int32_t *tri, size_t n)
{
    if (!n) return 0;
    const double *o = xyz + 3 * (size_t)tri[0];
    double v = 0;
    for (size_t t = 0; t < n; t++) {
        const double *a = xyz + 3 * (size_t)tri[3 * t], *b = xyz + 3 * (size_t)tri[3 * t + 1], *c = xyz + 3 * (size_t)tri[3 * t + 2];
        double ax = a[0] - o[0], ay = a[1] - o[1], az = a[2] - o[2];
        double bx = b[0] - o[0], by = b[1] - o[1], bz = b[2] - o[2];
        double cx = c[0] - o[0], cy = c[1] - o[1], cz = c[2] - o[2];
        v += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    }
    return v / 6.0;
}

/* A candidate surface: triangles of volume nodes, its kind and regions. */
typedef struct {
    int32_t *tri;
    size_t n_tris;
    thx_volume_surface_kind kind;
    int inside, outside;
    char name[64];
    int named_by_file;
} cand;

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Builds a thx_surface from triangles of volume nodes: its nodes are the
 * distinct volume nodes, in increasing order (*vnodes, new). */
static thx_status make_surface(thx_ctx *ctx, const double *xyz, const cand *cd, thx_role role, thx_surface **out,
                               int32_t **vnodes, size_t *n_vnodes)
{
    thx_status st = THX_OK;
    thx_surface *s = NULL;
    int32_t *nodes = thx_malloc(ctx, (3 * cd->n_tris + 1) * sizeof *nodes);
    if (!nodes) return THX_ENOMEM;
    memcpy(nodes, cd->tri, 3 * cd->n_tris * sizeof *nodes);
    size_t n = 3 * cd->n_tris;
    qsort(nodes, n, sizeof *nodes, cmp_i32);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (!u || nodes[i] != nodes[u - 1]) nodes[u++] = nodes[i];
    THX_TRY(thx_surface_create(ctx, cd->name, role, &s));
    s->xyz = thx_malloc(ctx, 3 * (u ? u : 1) * sizeof *s->xyz);
    s->tri = thx_malloc(ctx, 3 * (cd->n_tris ? cd->n_tris : 1) * sizeof *s->tri);
    if (!s->xyz || !s->tri) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < u; i++) memcpy(s->xyz + 3 * i, xyz + 3 * (size_t)nodes[i], 3 * sizeof *xyz);
    s->n_nodes = u;
    for (size_t i = 0; i < 3 * cd->n_tris; i++) {
        const int32_t *f = bsearch(&cd->tri[i], nodes, u, sizeof *nodes, cmp_i32);
        s->tri[i] = (int32_t)(f - nodes);
    }
    s->n_tris = cd->n_tris;
    *out = s;
    s = NULL;
    *vnodes = nodes;
    *n_vnodes = u;
    nodes = NULL;
done:
    thx_surface_destroy(&s);
    free(nodes);
    return st;
}

/* ------------------------------------------------------------- the policy */

static int cmp_ll(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Policy step 3: the region table, and each tetrahedron's region index. */
static thx_status build_regions(raw *r, const thx_volume_import_opts *o, thx_region **table_out, size_t *n_out,
                                int32_t **region_out, thx_volume_import_region **info_out)
{
    thx_status st = THX_OK;
    long long *tags = thx_malloc(r->ctx, r->n_tets * sizeof *tags);
    thx_region *table = NULL;
    thx_volume_import_region *ri = NULL;
    int32_t *region = NULL;
    char(*used)[64] = NULL;
    if (!tags) return THX_ENOMEM;
    for (size_t t = 0; t < r->n_tets; t++) tags[t] = r->has_tags ? r->tag[t] : 1;
    qsort(tags, r->n_tets, sizeof *tags, cmp_ll);
    size_t n = 0;
    for (size_t t = 0; t < r->n_tets; t++)
        if (!n || tags[t] != tags[n - 1]) tags[n++] = tags[t];
    for (size_t k = 0; k < o->n_region_maps; k++) {
        const thx_region_map *mp = &o->region_maps[k];
        if (!bsearch(&mp->tag, tags, n, sizeof *tags, cmp_ll)) {
            char list[200] = "";
            for (size_t i = 0; i < n && strlen(list) < sizeof list - 24; i++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%lld", i ? ", " : "", tags[i]);
            if (n > 0 && strlen(list) >= sizeof list - 24) snprintf(list + strlen(list), sizeof list - strlen(list), ", ...");
            st = thx_error(r->ctx, THX_EINPUT, "%s: --region %lld: the mesh has no region %lld (its regions: %s)", r->path,
                           mp->tag, mp->tag, list);
            goto done;
        }
        for (size_t j = 0; j < k; j++)
            if (o->region_maps[j].tag == mp->tag) {
                st = thx_error(r->ctx, THX_EINPUT, "--region %lld given twice", mp->tag);
                goto done;
            }
        if (mp->name[0] && !valid_name(mp->name)) {
            st = thx_error(r->ctx, THX_EINPUT, "--region %lld=%s: a region name is 1-31 characters of A-Z a-z 0-9 _ . - "
                           "(not starting with '.')", mp->tag, mp->name);
            goto done;
        }
        if (mp->has_sigma && !(mp->sigma > 0 && isfinite(mp->sigma))) {
            st = thx_error(r->ctx, THX_EINPUT, "--region %lld: conductivity %g must be a finite number > 0 (S/m)", mp->tag,
                           mp->sigma);
            goto done;
        }
    }
    table = thx_calloc(r->ctx, n, sizeof *table);
    ri = thx_calloc(r->ctx, n, sizeof *ri);
    used = thx_calloc(r->ctx, n + 1, sizeof *used);
    region = thx_malloc(r->ctx, r->n_tets * sizeof *region);
    if (!table || !ri || !used || !region) {
        st = THX_ENOMEM;
        goto done;
    }
    /* names given by options first, so that a default name yields to them */
    for (int pass = 0; pass < 2; pass++)
        for (size_t k = 0; k < n; k++) {
            const thx_region_map *mp = NULL;
            for (size_t j = 0; j < o->n_region_maps; j++)
                if (o->region_maps[j].tag == tags[k]) mp = &o->region_maps[j];
            int by_option = mp && mp->name[0];
            if (by_option != (pass == 0)) continue;
            thx_region *g = &table[k];
            ri[k].tag = tags[k];
            const char *fname = name_of(r, 3, tags[k]);
            if (fname) snprintf(ri[k].file_name, sizeof ri[k].file_name, "%s", fname);
            if (by_option) {
                snprintf(g->name, sizeof g->name, "%s", mp->name);
                for (size_t j = 0; j < k; j++)
                    if (table[j].name[0] && !strcmp(table[j].name, g->name)) {
                        st = thx_error(r->ctx, THX_EINPUT, "--region: regions %lld and %lld are both named \"%s\"",
                                       tags[j], tags[k], g->name);
                        goto done;
                    }
                ri[k].name_from = THX_RNAME_OPTION;
            } else {
                char nm[64] = "";
                if (fname) clean_name(nm, fname);
                ri[k].name_from = nm[0] ? THX_RNAME_FILE : THX_RNAME_DEFAULT;
                if (!nm[0]) snprintf(nm, sizeof nm, "region_%lld", tags[k]);
                size_t nu = 0;
                for (size_t j = 0; j < n; j++)
                    if (table[j].name[0]) snprintf(used[nu++], 64, "%s", table[j].name);
                unique_name(nm, used, nu);
                snprintf(g->name, sizeof g->name, "%s", nm);
            }
            if (mp && mp->has_sigma) {
                g->sigma[0] = g->sigma[4] = g->sigma[8] = mp->sigma;
                snprintf(g->source, sizeof g->source, "thorax import --region (isotropic, S/m)");
            } else if (o->default_region.sigma[0] > 0) {
                memcpy(g->sigma, o->default_region.sigma, sizeof g->sigma);
                g->anisotropic = o->default_region.anisotropic;
                snprintf(g->source, sizeof g->source, "%s", o->default_region.source);
                ri[k].sigma_defaulted = 1;
            } else {
                st = thx_error(r->ctx, THX_EINPUT, "%s: region %lld (\"%s\") has no conductivity: give --region %lld=NAME:SIGMA",
                               r->path, tags[k], g->name, tags[k]);
                goto done;
            }
        }
    for (size_t t = 0; t < r->n_tets; t++) {
        long long tg = r->has_tags ? r->tag[t] : 1;
        const long long *f = bsearch(&tg, tags, n, sizeof *tags, cmp_ll);
        region[t] = (int32_t)(f - tags);
        ri[region[t]].n_tets++;
    }
    *table_out = table, *n_out = n, *region_out = region, *info_out = ri;
    table = NULL, ri = NULL, region = NULL;
done:
    free(tags);
    free(table);
    free(ri);
    free(region);
    free(used);
    return st;
}

/* Policy step 4: removes nodes in no tetrahedron (and tagged triangles on them). */
static thx_status drop_unused(raw *r, size_t *removed, long long *first)
{
    int32_t *map = thx_malloc(r->ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < r->n_nodes; i++) map[i] = -1;
    for (size_t i = 0; i < 4 * r->n_tets; i++) map[r->tet[i]] = 0;
    size_t k = 0;
    *first = -1;
    for (size_t i = 0; i < r->n_nodes; i++) {
        if (map[i] < 0) {
            if (*first < 0) *first = r->node_tag ? r->node_tag[i] : (long long)i + r->index_base;
            continue;
        }
        map[i] = (int32_t)k;
        if (k != i) memmove(r->xyz + 3 * k, r->xyz + 3 * i, 3 * sizeof *r->xyz);
        k++;
    }
    *removed = r->n_nodes - k;
    for (size_t i = 0; i < 4 * r->n_tets; i++) r->tet[i] = map[r->tet[i]];
    size_t kt = 0;
    for (size_t t = 0; t < r->n_tris; t++) {
        int32_t a = map[r->tri[3 * t]], b = map[r->tri[3 * t + 1]], c = map[r->tri[3 * t + 2]];
        if (a < 0 || b < 0 || c < 0) continue;
        r->tri[3 * kt] = a, r->tri[3 * kt + 1] = b, r->tri[3 * kt + 2] = c;
        r->tri_tag[kt++] = r->tri_tag[t];
    }
    r->n_tris = kt;
    r->n_nodes = k;
    free(map);
    return THX_OK;
}

/* Policy step 5: left-handed tetrahedra get their last two nodes swapped;
 * a flat one refuses the file. */
static thx_status orient_tets(raw *r, size_t *flipped)
{
    size_t n_flat = 0, ex = 0;
    *flipped = 0;
    for (size_t t = 0; t < r->n_tets; t++) {
        int32_t *q = r->tet + 4 * t;
        double o = thx_orient3d(r->xyz + 3 * (size_t)q[0], r->xyz + 3 * (size_t)q[1], r->xyz + 3 * (size_t)q[2],
                                r->xyz + 3 * (size_t)q[3]);
        if (o > 0) {
            int32_t s = q[2];
            q[2] = q[3], q[3] = s;
            (*flipped)++;
        } else if (o == 0) {
            if (!n_flat) ex = t;
            n_flat++;
        }
    }
    if (n_flat)
        return thx_error(r->ctx, THX_EGEOM,
                         "%s: %zu flat tetrahedr%s (four nodes in one plane, or a node twice; first: the one at %s %lld): "
                         "refused, a flat tetrahedron cannot be made right-handed", r->path, n_flat, n_flat == 1 ? "on" : "a",
                         r->ref_kind, r->ref[ex]);
    return THX_OK;
}

/* A Gmsh physical surface that holds every triangle of cd, if there is one. */
static const char *file_surface_name(const raw *r, const face_rec *named, size_t n_named, const cand *cd)
{
    if (!n_named || !cd->n_tris) return NULL;
    long long tag = LLONG_MIN;
    for (size_t t = 0; t < cd->n_tris; t++) {
        face_rec key;
        int32_t v[3] = {cd->tri[3 * t], cd->tri[3 * t + 1], cd->tri[3 * t + 2]};
        sort3(v);
        key.a = v[0], key.b = v[1], key.c = v[2], key.tf = INT32_MIN;
        /* the first record with this key */
        size_t lo = 0, hi = n_named;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (cmp_face(&named[mid], &key) < 0) lo = mid + 1;
            else hi = mid;
        }
        if (lo == n_named || named[lo].a != v[0] || named[lo].b != v[1] || named[lo].c != v[2]) return NULL;
        long long tg = r->tri_tag[named[lo].tf];
        if (tag != LLONG_MIN && tg != tag) return NULL;
        tag = tg;
    }
    return name_of(r, 2, tag);
}

/* Collects faces [begin, end) of kind into components by node-connectivity
 * (a union-find over the nodes of those faces). comp[i] = component of face
 * i (in order of first appearance); returns the component count. */
static size_t components(const int32_t *tet, const int32_t *faces, size_t n_faces, int32_t *parent, size_t n_nodes,
                         int32_t *cid, int32_t *comp)
{
    for (size_t i = 0; i < n_nodes; i++) parent[i] = (int32_t)i, cid[i] = -1;
    for (size_t i = 0; i < n_faces; i++) {
        int32_t v[3];
        face_tri(tet, faces[i], v);
        uf_union(parent, v[0], v[1]);
        uf_union(parent, v[0], v[2]);
    }
    size_t nc = 0;
    for (size_t i = 0; i < n_faces; i++) {
        int32_t v[3];
        face_tri(tet, faces[i], v);
        int32_t root = uf_find(parent, v[0]);
        if (cid[root] < 0) cid[root] = (int32_t)nc++;
        comp[i] = cid[root];
    }
    return nc;
}

/* Face indices grouped by component, in order within each (a counting
 * sort): component k's are order[start[k] .. start[k + 1]). */
static thx_status group_faces(thx_ctx *ctx, const int32_t *comp, size_t n, size_t nc, int32_t **order, size_t **start)
{
    *order = thx_malloc(ctx, (n ? n : 1) * sizeof **order);
    *start = thx_calloc(ctx, nc + 2, sizeof **start);
    if (!*order || !*start) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) (*start)[comp[i] + 2]++;
    for (size_t k = 0; k < nc; k++) (*start)[k + 2] += (*start)[k + 1];
    for (size_t i = 0; i < n; i++) (*order)[(*start)[comp[i] + 1]++] = (int32_t)i;
    return THX_OK;
}

static void add_dropped(thx_volume_import_info *info, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add_dropped(thx_volume_import_info *info, const char *fmt, ...)
{
    if (info->n_dropped < THX_VIMPORT_MAX_DROPPED) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(info->dropped[info->n_dropped], sizeof info->dropped[0], fmt, ap);
        va_end(ap);
    }
    info->n_dropped++;
}

static void free_cands(cand *c, size_t n)
{
    for (size_t i = 0; c && i < n; i++) free(c[i].tri);
    free(c);
}

/* Policy step 6: the candidate surfaces (boundary components first, then
 * interface components that can be surfaces of their own). */
static thx_status find_surfaces(raw *r, const int32_t *region, const thx_region *table, const thx_volume_import_opts *o,
                                thx_volume_import_info *info, cand **out, size_t *n_out)
{
    thx_status st = THX_OK;
    thx_ctx *ctx = r->ctx;
    size_t nt = r->n_tets, nf = 4 * nt;
    face_rec *fr = thx_malloc(ctx, (nf ? nf : 1) * sizeof *fr);
    int32_t *nb = thx_malloc(ctx, (nf ? nf : 1) * sizeof *nb);
    int32_t *parent = thx_malloc(ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *parent);
    int32_t *cid = thx_malloc(ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *cid);
    unsigned char *on_boundary = thx_calloc(ctx, r->n_nodes ? r->n_nodes : 1, 1);
    int32_t *bf = NULL, *ifc = NULL, *comp = NULL, *tri = NULL, *order = NULL;
    size_t *start = NULL;
    face_rec *named = NULL;
    cand *cands = NULL;
    size_t n_cands = 0, n_bf = 0, n_if = 0;
    if (!fr || !nb || !parent || !cid || !on_boundary) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++) {
            int32_t v[3];
            face_tri(r->tet, (int32_t)(4 * t + (size_t)f), v);
            sort3(v);
            face_rec *e = &fr[4 * t + (size_t)f];
            e->a = v[0], e->b = v[1], e->c = v[2], e->tf = (int32_t)(4 * t + (size_t)f);
        }
    THX_TRY(sort_faces(ctx, fr, nf, r->n_nodes));
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && fr[j].a == fr[i].a && fr[j].b == fr[i].b && fr[j].c == fr[i].c) j++;
        for (size_t k = i; k < j; k++)
            nb[fr[k].tf] = j - i == 1 ? -1 : j - i == 2 ? fr[i + (k == i)].tf : -2;
        if (j - i > 2) info->n_nonconforming_faces++;
        i = j;
    }
    /* boundary and interface faces, in tetrahedron order */
    bf = thx_malloc(ctx, (nf ? nf : 1) * sizeof *bf);
    ifc = thx_malloc(ctx, (nf ? nf : 1) * sizeof *ifc);
    comp = thx_malloc(ctx, (nf ? nf : 1) * sizeof *comp);
    if (!bf || !ifc || !comp) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t tf = 0; tf < nf; tf++) {
        if (nb[tf] == -1) bf[n_bf++] = (int32_t)tf;
        else if (nb[tf] >= 0 && (int32_t)tf < nb[tf] && region[tf / 4] != region[nb[tf] / 4]) ifc[n_if++] = (int32_t)tf;
    }
    for (size_t i = 0; i < n_bf; i++) {
        int32_t v[3];
        face_tri(r->tet, bf[i], v);
        on_boundary[v[0]] = on_boundary[v[1]] = on_boundary[v[2]] = 1;
    }
    /* Gmsh's named triangles, sorted by their nodes (tf holds the triangle's index) */
    if (r->n_tris) {
        named = thx_malloc(ctx, r->n_tris * sizeof *named);
        if (!named) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t t = 0; t < r->n_tris; t++) {
            int32_t v[3] = {r->tri[3 * t], r->tri[3 * t + 1], r->tri[3 * t + 2]};
            sort3(v);
            named[t].a = v[0], named[t].b = v[1], named[t].c = v[2], named[t].tf = (int32_t)t;
        }
        qsort(named, r->n_tris, sizeof *named, cmp_face);
    }
    size_t n_bc = components(r->tet, bf, n_bf, parent, r->n_nodes, cid, comp);
    THX_TRY(group_faces(ctx, comp, n_bf, n_bc, &order, &start));
    size_t n_tri_total = n_bf + n_if;
    tri = thx_malloc(ctx, 3 * (n_tri_total ? n_tri_total : 1) * sizeof *tri);
    if (!tri) {
        st = THX_ENOMEM;
        goto done;
    }
    cands = thx_calloc(ctx, n_bc + n_if + 1, sizeof *cands);
    if (!cands) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t k = 0; k < n_bc; k++) {
        cand *cd = &cands[n_cands];
        size_t m = 0;
        int reg = -2;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            face_tri(r->tet, bf[i], tri + 3 * m++);
            int rg = region[bf[i] / 4];
            reg = reg == -2 ? rg : reg == rg ? reg : -1;
        }
        cd->tri = thx_malloc(ctx, 3 * m * sizeof *cd->tri);
        if (!cd->tri) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(cd->tri, tri, 3 * m * sizeof *tri);
        cd->n_tris = m;
        n_cands++;
        double vol = tris_volume(r->xyz, cd->tri, m);
        if (vol < 0) { /* a hole in the mesh: faces out of the hole */
            for (size_t t = 0; t < m; t++) {
                int32_t s = cd->tri[3 * t + 1];
                cd->tri[3 * t + 1] = cd->tri[3 * t + 2], cd->tri[3 * t + 2] = s;
            }
            cd->kind = THX_VSURF_CAVITY;
            cd->inside = -1, cd->outside = reg >= 0 ? reg : -1;
            snprintf(cd->name, sizeof cd->name, "cavity");
        } else {
            cd->kind = THX_VSURF_BOUNDARY;
            cd->inside = reg >= 0 ? reg : -1, cd->outside = -1;
            snprintf(cd->name, sizeof cd->name, "%s", reg >= 0 ? table[reg].name : "outer");
        }
    }
    size_t n_ic = components(r->tet, ifc, n_if, parent, r->n_nodes, cid, comp);
    free(order);
    free(start);
    order = NULL, start = NULL;
    THX_TRY(group_faces(ctx, comp, n_if, n_ic, &order, &start));
    for (size_t k = 0; k < n_ic; k++) {
        size_t m = 0, first = (size_t)order[start[k]];
        int touches = 0;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int32_t v[3];
            face_tri(r->tet, ifc[i], v);
            touches |= on_boundary[v[0]] | on_boundary[v[1]] | on_boundary[v[2]];
            m++;
        }
        int ra = region[ifc[first] / 4], rb = region[nb[ifc[first]] / 4];
        int ok_a = 1, ok_b = 1;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int r1 = region[ifc[i] / 4], r2 = region[nb[ifc[i]] / 4];
            ok_a &= r1 == ra || r2 == ra;
            ok_b &= r1 == rb || r2 == rb;
        }
        if (touches) {
            add_dropped(info, "%zu faces between regions \"%s\" and \"%s\"%s touch the boundary of the mesh: not a surface "
                        "of their own", m, table[ra].name, table[rb].name, ok_a && ok_b ? "" : " (and others)");
            continue;
        }
        if (!ok_a && !ok_b) {
            add_dropped(info, "%zu faces between regions \"%s\", \"%s\" and others meet where three or more regions do: not a "
                        "surface of their own", m, table[ra].name, table[rb].name);
            continue;
        }
        /* oriented outward of region c: the face as its tetrahedron in c has it */
        int c = ok_a ? ra : rb;
        m = 0;
        for (size_t q = start[k]; q < start[k + 1]; q++) {
            size_t i = (size_t)order[q];
            int32_t tf = region[ifc[i] / 4] == c ? ifc[i] : nb[ifc[i]];
            face_tri(r->tet, tf, tri + 3 * m++);
        }
        double vol = tris_volume(r->xyz, tri, m);
        int inside = c, outside = ok_a && ok_b ? rb : -1;
        if (vol < 0) {
            for (size_t t = 0; t < m; t++) {
                int32_t s = tri[3 * t + 1];
                tri[3 * t + 1] = tri[3 * t + 2], tri[3 * t + 2] = s;
            }
            outside = c;
            inside = ok_a && ok_b ? rb : -1;
        }
        cand *cd = &cands[n_cands];
        cd->tri = thx_malloc(ctx, 3 * m * sizeof *cd->tri);
        if (!cd->tri) {
            st = THX_ENOMEM;
            goto done;
        }
        memcpy(cd->tri, tri, 3 * m * sizeof *tri);
        cd->n_tris = m;
        cd->kind = THX_VSURF_INTERFACE;
        cd->inside = inside, cd->outside = outside;
        snprintf(cd->name, sizeof cd->name, "%s", inside >= 0 ? table[inside].name : "interface");
        n_cands++;
    }
    /* names: a Gmsh physical surface holding every face; then unique */
    {
        char(*used)[64] = thx_calloc(ctx, n_cands + 1, sizeof *used);
        if (!used) {
            st = THX_ENOMEM;
            goto done;
        }
        snprintf(used[0], 64, "volume");
        for (size_t k = 0; k < n_cands; k++) {
            const char *fname = file_surface_name(r, named, r->n_tris, &cands[k]);
            char nm[64] = "";
            if (fname) clean_name(nm, fname);
            if (nm[0] && strcmp(nm, "model.json") != 0) {
                snprintf(cands[k].name, sizeof cands[k].name, "%s", nm);
                cands[k].named_by_file = 1;
            }
            unique_name(cands[k].name, used, k + 1);
            snprintf(used[k + 1], 64, "%s", cands[k].name);
        }
        free(used);
    }
    (void)o;
    *out = cands, *n_out = n_cands;
    cands = NULL;
done:
    free_cands(cands, n_cands);
    free(fr);
    free(nb);
    free(parent);
    free(cid);
    free(on_boundary);
    free(bf);
    free(ifc);
    free(comp);
    free(tri);
    free(named);
    free(order);
    free(start);
    return st;
}

thx_status thx_volume_import(thx_ctx *ctx, const char *path, const thx_volume_import_opts *opts, thx_model **out,
                             thx_volume_import_info *info)
{
    thx_volume_import_opts def;
    if (!opts) {
        thx_volume_import_opts_default(&def);
        opts = &def;
    }
    *out = NULL;
    thx_volume_import_info local;
    if (!info) info = &local;
    memset(info, 0, sizeof *info);
    info->first_unused = -1;
    info->scale = opts->scale;
    thx_status st = THX_OK;
    raw r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx, r.path = path, r.ref_kind = "element";
    thx_model *m = NULL;
    thx_volume *v = NULL;
    thx_region *table = NULL;
    int32_t *region = NULL;
    cand *cands = NULL;
    size_t n_reg = 0, n_cands = 0;
    char *text = NULL;
    if (!(opts->scale > 0) || !isfinite(opts->scale)) {
        st = thx_error(ctx, THX_EINPUT, "%s: scale %g must be a finite positive number", path, opts->scale);
        goto done;
    }
    thx_volume_format fmt = opts->format != THX_VOLFMT_NONE ? opts->format : thx_volume_format_from_path(path);
    info->format = fmt;
    if (fmt == THX_VOLFMT_NONE) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a volume mesh format (.pts + .tet/.elem, .vtk unstructured grid, .vtu, .msh)",
                       path);
        goto done;
    }
    /* 1. read */
    if (fmt == THX_VOLFMT_PTS) {
        THX_TRY(read_ptselem(&r, path, opts->elem_path));
    } else {
        size_t len = 0;
        THX_TRY(thx_read_file(ctx, path, &text, &len));
        if (fmt == THX_VOLFMT_VTK) st = read_vtk_ugrid(&r, text, len, opts->region_array);
        else if (fmt == THX_VOLFMT_VTU) st = read_vtu(&r, text, len, opts->region_array);
        else st = read_msh(&r, text, len);
        free(text);
        text = NULL;
        if (st) goto done;
    }
    snprintf(info->format_detail, sizeof info->format_detail, "%s", r.detail);
    snprintf(info->path2, sizeof info->path2, "%s", r.path2);
    snprintf(info->region_source, sizeof info->region_source, "%s", r.region_source);
    info->index_base = r.index_base;
    info->index_base_detected = r.index_base_detected;
    info->n_nodes_read = r.n_nodes;
    info->n_tets_read = r.n_tets;
    info->n_cells_ignored = r.n_ignored;
    info->n_tris_named = r.n_tris;
    if (r.n_tets == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: no tetrahedra%s", path, r.n_ignored ? " (only cells of dimension 0-2)" : "");
        goto done;
    }
    /* 2. scale */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < r.n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            double *x = &r.xyz[3 * i + (size_t)k];
            *x *= opts->scale;
            if (!isfinite(*x)) {
                st = thx_error(ctx, THX_EINPUT, "%s: node %zu is not finite after scaling by %g", path, i + 1, opts->scale);
                goto done;
            }
            lo[k] = fmin(lo[k], *x), hi[k] = fmax(hi[k], *x);
        }
    info->extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    /* 3. regions */
    THX_TRY(build_regions(&r, opts, &table, &n_reg, &region, &info->regions));
    info->n_regions = n_reg;
    /* 4. unused nodes; 5. orientation */
    THX_TRY(drop_unused(&r, &info->n_unused_removed, &info->first_unused));
    THX_TRY(orient_tets(&r, &info->n_flipped));
    /* 6. surfaces */
    THX_TRY(find_surfaces(&r, region, table, opts, info, &cands, &n_cands));

    /* the model: its volume first (the surfaces' node tables point into it) */
    THX_TRY(thx_model_create(ctx, &m));
    THX_TRY(thx_volume_create(ctx, &v));
    m->volume = v;
    v->n_nodes = r.n_nodes;
    v->xyz = r.xyz, r.xyz = NULL;
    v->n_tets = r.n_tets;
    v->tet = r.tet, r.tet = NULL;
    v->region = region, region = NULL;
    v->n_regions = n_reg;
    v->regions = table, table = NULL;
    for (size_t t = 0; t < v->n_tets; t++) info->regions[v->region[t]].volume += thx_volume_tet_volume(v, t);
    v->node_surf = thx_malloc(ctx, v->n_nodes * sizeof *v->node_surf);
    v->node_snode = thx_malloc(ctx, v->n_nodes * sizeof *v->node_snode);
    v->surf_node = thx_calloc(ctx, n_cands + 1, sizeof *v->surf_node);
    v->surf_n_nodes = thx_calloc(ctx, n_cands + 1, sizeof *v->surf_n_nodes);
    info->surfaces = thx_calloc(ctx, n_cands + 1, sizeof *info->surfaces);
    info->surface_reports = thx_calloc(ctx, n_cands + 1, sizeof *info->surface_reports);
    if (!v->node_surf || !v->node_snode || !v->surf_node || !v->surf_n_nodes || !info->surfaces || !info->surface_reports) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t i = 0; i < v->n_nodes; i++) v->node_surf[i] = v->node_snode[i] = -1;
    /* 7a. each surface checked; interfaces that fail are not stored */
    char first_reason[400] = "";
    for (size_t k = 0; k < n_cands; k++) {
        const cand *cd = &cands[k];
        thx_role role = cd->kind == THX_VSURF_BOUNDARY ? THX_ROLE_OUTER : cd->kind == THX_VSURF_CAVITY ? THX_ROLE_HEART : THX_ROLE_OTHER;
        thx_surface *s = NULL;
        int32_t *vn = NULL;
        size_t nvn = 0;
        THX_TRY(make_surface(ctx, v->xyz, cd, role, &s, &vn, &nvn));
        thx_surface_report rep;
        memset(&rep, 0, sizeof rep);
        st = thx_surface_check(ctx, s, NULL, &opts->check, &rep);
        if (st != THX_OK && st != THX_ECHECK) {
            thx_surface_destroy(&s);
            free(vn);
            goto done;
        }
        if (st == THX_ECHECK && cd->kind == THX_VSURF_INTERFACE) {
            add_dropped(info, "interface \"%s\" (%zu triangles) is not a valid surface: %s", cd->name, cd->n_tris,
                        rep.n_reasons ? rep.reasons[0] : "failed its checks");
            thx_surface_report_free(&rep);
            thx_surface_destroy(&s);
            free(vn);
            st = THX_OK;
            thx_ctx_clear(ctx);
            continue;
        }
        if (st == THX_ECHECK) {
            info->check_failed = 1;
            if (!first_reason[0])
                snprintf(first_reason, sizeof first_reason, "surface \"%s\": %s", cd->name,
                         rep.n_reasons ? rep.reasons[0] : "failed its checks");
            st = THX_OK;
            thx_ctx_clear(ctx);
        }
        size_t si = m->n_surfaces;
        st = thx_model_add_surface(ctx, m, &s);
        if (st) {
            thx_surface_report_free(&rep);
            free(vn);
            goto done;
        }
        if (rep.interior_source != THX_INTERIOR_NONE && !(rep.failures & THX_CHECKF_SOLID_ANGLE)) {
            m->has_interior[si] = 1;
            m->interior[si] = rep.interior;
        }
        info->surface_reports[si] = rep;
        info->surfaces[si].kind = cd->kind;
        info->surfaces[si].inside = cd->inside;
        info->surfaces[si].outside = cd->outside;
        info->surfaces[si].named_by_file = cd->named_by_file;
        v->surf_node[si] = vn;
        v->surf_n_nodes[si] = nvn;
        for (size_t i = 0; i < nvn; i++) v->node_surf[vn[i]] = (int32_t)si, v->node_snode[vn[i]] = (int32_t)i;
        v->n_surfaces = m->n_surfaces;
        info->n_surfaces = m->n_surfaces;
    }
    /* 7b. the volume against its surfaces */
    st = thx_volume_check(ctx, v, m, &opts->vcheck, &info->volume_report);
    info->volume_checked = 1;
    if (st != THX_OK && st != THX_ECHECK) goto done;
    if (st == THX_ECHECK) {
        info->check_failed = 1;
        if (!first_reason[0])
            snprintf(first_reason, sizeof first_reason, "volume: %s",
                     info->volume_report.n_reasons ? info->volume_report.reasons[0] : "failed its checks");
    }
    st = THX_OK;
    thx_ctx_clear(ctx);
    if (info->check_failed && !opts->force) {
        st = thx_error(ctx, THX_ECHECK, "%s: refused: %s", path, first_reason);
        goto done;
    }
    *out = m;
    m = NULL;
done:
    free(text);
    raw_free(&r);
    free(table);
    free(region);
    free_cands(cands, n_cands);
    thx_model_destroy(&m);
    if (info == &local) thx_volume_import_info_free(&local);
    return st;
}
