/*
 * Surfaces made elsewhere: PLY, ascii and binary (thorax/io/surface_read.h).
 */
#include "io/surface/import_surface.h"

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


thx_status import_read_ply(build *b, const char *text, size_t len, thx_surface_read_info *info)
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
            int pc = (m && k) ? parse_count(u, k, INT32_MAX, &cnt) : -1;
            if (pc == -2) {
                st = fail(b, at_line(line), "element \"%s\": count %s out of range 0..%d", tok_show(t, m), tok_show(u, k),
                          INT32_MAX);
                goto done;
            }
            if (pc != 0) {
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
    {
        /* no NUL in the header; none in an ascii body */
        int zl = nul_line(text, s.binary ? c->pos : len);
        if (zl) {
            st = fail(b, at_line(zl), "NUL byte in %s", s.binary ? "the PLY header" : "an ascii PLY file");
            goto done;
        }
    }

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
        /* The least each item takes (binary: its scalars and list counts; ascii: a
         * character and a separator per value): a count the rest of the file
         * cannot hold is refused before the loop; an element without properties
         * takes no bytes and is skipped at once, whatever its count. */
        size_t min_item = 0;
        for (size_t k = 0; k < e->n_prop; k++)
            min_item += s.binary ? type_size[e->prop[k].count_ty ? e->prop[k].count_ty : e->prop[k].ty] : 2;
        size_t left = len - c->pos;
        if (min_item == 0) continue;
        if (e->count > (s.binary ? left / min_item : left / min_item + 1)) {
            st = fail(b, at_line(e->line), "element \"%s\": %zu items declared, but the %zu bytes of data left can hold "
                      "at most %zu", e->name, e->count, left, s.binary ? left / min_item : left / min_item + 1);
            goto done;
        }
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
                size_t left2 = len - c->pos, most = s.binary ? left2 / type_size[p->ty] : left2 / 2 + 1;
                if (v < 0 || v > 1e6 || v > (double)most) {
                    st = fail(b, w, "%s: list length %.0f out of range (0..%zu: what the file has left, at most 1000000)",
                              what, v, most < 1000000 ? most : 1000000);
                    goto done;
                }
                size_t cnt = (size_t)v;
                for (size_t q = 0; q < cnt; q++) {
                    where wi;
                    THX_TRY(read_scalar(b, &s, p->ty, what, &v, &wi));
                    if ((int)k != iv) continue;
                    if (nv + 1 > pcap) THX_TRY(thx_grow(b->ctx, (void **)&poly, &pcap, nv + 1, sizeof *poly));
                    char obj[128];
                    snprintf(obj, sizeof obj, "%s %zu: ", e->name, r + 1);
                    THX_TRY(check_index(b, wi, obj, (long long)v, 0, b->n_nodes, &poly[nv]));
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
    /* nothing may follow the last item of the last element */
    if (s.binary && c->pos < len) {
        st = fail(b, at_byte(c->pos), "%zu byte%s after the last element's data (the header declares fewer items "
                  "than the file holds)", len - c->pos, len - c->pos == 1 ? "" : "s");
        goto done;
    }
    if (!s.binary) {
        int l;
        size_t m = next_token(c, &t, &l);
        if (m) {
            st = fail(b, at_line(l), "unexpected \"%s\" after the last element's data (the header declares fewer "
                      "items than the file holds)", tok_show(t, m));
            goto done;
        }
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

