/*
 * Surfaces made elsewhere: STL, binary and ASCII (thorax/io/surface_read.h).
 *
 * STL has no shared vertices: corners are merged when their float
 * coordinates are bit-identical (with -0 = +0), in order of first
 * appearance, so the result is deterministic. Nothing is merged within a
 * tolerance: that would change the geometry behind the user's back.
 */
#include "io/surface/import_surface.h"

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

thx_status import_read_stl(build *b, const char *text, size_t len, thx_surface_read_info *info)
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
        int zl = nul_line(text, len);
        if (zl) {
            st = fail(b, at_line(zl), "NUL byte in an ASCII STL file (a binary STL has exactly 84 + 50 n bytes)");
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
                const char *x;
                size_t m3 = line_token(&c, &x);
                if (m3) {
                    st = fail(b, at_line(line), "unexpected \"%s\" after the vertex's three coordinates", tok_show(x, m3));
                    goto done;
                }
                if (nv + 1 > pcap) THX_TRY(thx_grow(b->ctx, (void **)&poly, &pcap, nv + 1, sizeof *poly));
                THX_TRY(merge_node(b, &m, at_line(line), v[0], v[1], v[2], &poly[nv]));
                nv++;
                corners++;
            } else if (tok_is_ci(t, n, "outer")) {
                const char *x;
                size_t m3 = line_token(&c, &x);
                if (!tok_is_ci(x, m3, "loop") || in_loop) {
                    st = fail(b, at_line(line), in_loop ? "\"outer loop\" inside another (no \"endloop\" before it)"
                                                        : "expected \"outer loop\"");
                    goto done;
                }
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
            } else if (tok_is_ci(t, n, "facet")) {
                /* "facet normal nx ny nz": numbers (NaN allowed: some writers give degenerate facets one);
                 * the normal is recomputed from the corners */
                const char *x;
                size_t m3 = line_token(&c, &x);
                int ok = tok_is_ci(x, m3, "normal");
                for (int k = 0; ok && k < 3; k++) {
                    m3 = line_token(&c, &x);
                    char tmp[64], *end = NULL;
                    if (!m3 || m3 >= sizeof tmp) ok = 0;
                    else {
                        memcpy(tmp, x, m3);
                        tmp[m3] = '\0';
                        (void)strtod(tmp, &end);
                        ok = end == tmp + m3;
                    }
                }
                if (ok && line_token(&c, &x)) ok = 0;
                if (!ok) {
                    st = fail(b, at_line(line), "expected \"facet normal nx ny nz\" (three numbers)");
                    goto done;
                }
            } else if (tok_is_ci(t, n, "endfacet") || tok_is_ci(t, n, "endsolid") || tok_is_ci(t, n, "solid")) {
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

