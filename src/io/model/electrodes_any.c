/*
 * Any electrode set (thorax/io/electrodes_file.h, thx_electrodes_load): a thorax electrode file,
 * a map3d .leadlinks, a node list or a list of positions, told apart by the first line that is
 * not blank or a comment:
 *   "thorax-electrodes ..."      the thorax file (its own reader and messages);
 *   "N WORD" (WORD not a number) a .leadlinks (thorax/io/channels_file.h);
 *   one integer                  a node list, every line one node number (1-based);
 *   three numbers                positions, every line X Y Z (mm), as a map3d .pts.
 * The content decides, not the extension: a .pts of nodes and a .txt of positions read alike.
 */
#include "thorax/io/electrodes_file.h"
#include "thorax/io/channels_file.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "io/common/parse_uint.h"
#include "io/common/tokens.h"

const char *thx_electrodes_kind_name(thx_electrodes_kind k)
{
    switch (k) {
    case THX_ELECTRODES_FILE: return "thorax electrode file";
    case THX_ELECTRODES_LEADLINKS: return "map3d .leadlinks";
    case THX_ELECTRODES_NODES: return "node list";
    case THX_ELECTRODES_POINTS: return "positions";
    }
    return "?";
}

static int is_number(const char *t)
{
    char *end = NULL;
    double v = strtod(t, &end);
    return end != t && !*end && isfinite(v);
}

/* The surface the non-thorax files lie on: `surface`, or the model's one outer surface. */
static const thx_surface *pick_surface(thx_ctx *ctx, const char *path, const thx_model *m, const char *surface)
{
    const thx_surface *s = NULL;
    int n = 0;
    for (size_t k = 0; k < m->n_surfaces; k++)
        if (surface ? !strcmp(m->surf[k]->name, surface) : m->surf[k]->role == THX_ROLE_OUTER) {
            s = m->surf[k];
            n++;
        }
    if (surface && !s) thx_error(ctx, THX_EINPUT, "%s: the model has no surface \"%s\"", path, surface);
    else if (!surface && n != 1)
        thx_error(ctx, THX_EINPUT, "%s: the model has %s outer surface (role outer); name the electrodes' surface", path,
                  n ? "more than one" : "no");
    return n == 1 || surface ? s : NULL;
}

/* A node list or a list of positions: every non-blank line `per` tokens. */
static thx_status read_list(thx_ctx *ctx, const char *path, char *text, const thx_surface *s, int per, thx_electrodes **out)
{
    size_t cap = 64, n = 0, line = 0;
    int32_t *node = NULL;
    double *xyz = NULL;
    thx_status st = THX_OK;
    node = thx_malloc(ctx, cap * sizeof *node);
    xyz = thx_malloc(ctx, 3 * cap * sizeof *xyz);
    if (!node || !xyz) { st = THX_ENOMEM; goto done; }
    char *p = text;
    for (char *l; st == THX_OK && (l = thx_io_next_line(&p, '#'));) {
        line++;
        char *tok[4];
        int nt = thx_io_split(l, tok, 4);
        if (!nt) continue;
        if (n == cap) {
            cap *= 2;
            int32_t *a = realloc(node, cap * sizeof *a);
            if (a) node = a;
            double *b = a ? realloc(xyz, 3 * cap * sizeof *b) : NULL;
            if (b) xyz = b;
            if (!a || !b) { st = thx_error(ctx, THX_ENOMEM, "%s: out of memory at line %zu", path, line); break; }
        }
        if (per == 1) {
            uint64_t v;
            if (nt != 1 || thx_parse_uint(tok[0], 0, INT32_MAX, &v) != 0 || v < 1) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: a node list holds one node number (1, 2, ...) a line, got '%.40s%s'",
                               path, line, tok[0], nt > 1 ? " ..." : "");
                break;
            }
            if (v > s->n_nodes) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: node %llu is not on surface \"%s\" (nodes 1..%zu)", path, line,
                               (unsigned long long)v, s->name, s->n_nodes);
                break;
            }
            node[n] = (int32_t)(v - 1);
        } else {
            if (nt != 3 || !is_number(tok[0]) || !is_number(tok[1]) || !is_number(tok[2])) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: a position file holds 'X Y Z' (three finite numbers, mm) a line",
                               path, line);
                break;
            }
            for (int k = 0; k < 3; k++) xyz[3 * n + (size_t)k] = strtod(tok[k], NULL);
        }
        n++;
    }
    if (st == THX_OK && n == 0) st = thx_error(ctx, THX_EINPUT, "%s: no electrodes", path);
    if (st != THX_OK) goto done;
    if (per == 1) {
        st = thx_electrodes_from_nodes(ctx, s, node, NULL, n, out);
        if (st != THX_OK) { /* a node listed twice: its name is taken twice */
            char msg[600];
            snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
            st = thx_error(ctx, st, "%s: %s", path, msg);
        }
    } else {
        thx_electrodes *e = NULL;
        st = thx_electrodes_create(ctx, n, &e);
        if (st == THX_OK) {
            snprintf(e->surface, sizeof e->surface, "%s", s->name);
            for (size_t i = 0; i < n; i++) {
                snprintf(e->name[i], sizeof e->name[i], "P%zu", i + 1);
                e->node[i] = THX_ELECTRODE_OFF_NODE;
            }
            memcpy(e->xyz, xyz, 3 * n * sizeof *xyz);
        }
        *out = e;
    }
done:
    free(node);
    free(xyz);
    return st;
}

thx_status thx_electrodes_load(thx_ctx *ctx, const char *path, const thx_model *m, const char *surface,
                               double max_offset, thx_electrodes **out, thx_electrodes_kind *kind, double *max_moved)
{
    *out = NULL;
    if (max_moved) *max_moved = 0;
    if (!m) return thx_error(ctx, THX_EINPUT, "%s: no model to place the electrodes on", path);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    /* the first line that says something */
    thx_electrodes_kind k = THX_ELECTRODES_POINTS;
    int known = 0;
    size_t line_no = 0;
    if (memchr(text, '\0', len)) k = THX_ELECTRODES_FILE, known = 1; /* the thorax reader names the NUL's line */
    for (const char *p = text; *p && !known;) {
        const char *nl = strchr(p, '\n');
        size_t ll = nl ? (size_t)(nl - p) : strlen(p);
        char line[256];
        snprintf(line, sizeof line, "%.*s", (int)(ll < sizeof line ? ll : sizeof line - 1), p);
        p = nl ? nl + 1 : p + ll;
        line_no++;
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        char *tok[4];
        int nt = thx_io_split(line, tok, 4);
        if (!nt) continue;
        known = 1;
        if (!strcmp(tok[0], "thorax-electrodes")) k = THX_ELECTRODES_FILE;
        else if (nt == 2 && is_number(tok[0]) && !is_number(tok[1])) k = THX_ELECTRODES_LEADLINKS;
        else if (nt == 1) k = THX_ELECTRODES_NODES;
        else if (nt == 3) k = THX_ELECTRODES_POINTS;
        else known = -1;
    }
    thx_status st = THX_OK;
    thx_electrodes *e = NULL;
    const thx_surface *s = NULL;
    if (known != 1) {
        st = thx_error(ctx, THX_EINPUT,
                       "%s:%zu: %s (a thorax electrode file, a map3d .leadlinks 'N leads' + 'LABEL NODE' lines, a node "
                       "list (one node number a line) or positions ('X Y Z' a line))",
                       path, line_no ? line_no : 1, known ? "not an electrode file" : "empty file: no electrodes");
        goto done;
    }
    if (k == THX_ELECTRODES_FILE) {
        st = thx_electrodes_read(ctx, path, &e);
        if (st == THX_OK && surface && strcmp(surface, e->surface) != 0) {
            /* a surface the model lacks is said as the check says it */
            if (thx_electrodes_surface(ctx, e, m)) /* else: its message stands */
                thx_error(ctx, THX_EINPUT, "%s: the electrodes lie on surface \"%s\", not \"%s\" (the potentials' surface)",
                          path, e->surface, surface);
            st = THX_EINPUT;
        }
    } else {
        s = pick_surface(ctx, path, m, surface);
        if (!s) { st = THX_EINPUT; goto done; }
        if (k == THX_ELECTRODES_LEADLINKS) st = thx_leadlinks_read(ctx, path, s, &e);
        else st = read_list(ctx, path, text, s, k == THX_ELECTRODES_NODES ? 1 : 3, &e);
        if (st == THX_OK) snprintf(e->path, sizeof e->path, "%s", path);
    }
    if (st == THX_OK) st = thx_electrodes_place(ctx, e, m, max_offset, max_moved);
done:
    free(text);
    if (st != THX_OK) thx_electrodes_destroy(&e);
    else if (kind) *kind = k;
    *out = e;
    return st;
}
