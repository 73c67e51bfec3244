/*
 * map3d's .channels and .leadlinks (thorax/io/channels_file.h; docs/formats.md, "Channels and
 * lead links"). Both are `N WORD` and then N pairs; one scanner serves both, and the CLI's
 * `--channels` (render, view, forward, series, leads) all read through thx_channels_read.
 */
#include "thorax/io/channels_file.h"

#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "io/common/parse_uint.h"
#include "io/common/tokens.h"

/* A signed decimal integer that fits in 32 bits (the whole token). */
static int parse_int(const char *t, long *out)
{
    int neg = t[0] == '-';
    uint64_t v;
    if (thx_parse_uint(t + (neg || t[0] == '+'), 0, INT32_MAX, &v) != 0) return -1;
    *out = neg ? -(long)v : (long)v;
    return 0;
}

typedef struct {
    thx_ctx *ctx;
    const char *path;
    char *text, *p;
    size_t len, line;
} scan;

static thx_status sfail(const scan *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status sfail(const scan *r, const char *fmt, ...)
{
    char msg[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(r->ctx, THX_EINPUT, "%s:%zu: %s", r->path, r->line, msg);
}

/* The next non-blank line's tokens (0 at the end of the file). */
static int next_line(scan *r, char **tok, int max)
{
    for (char *line; (line = thx_io_next_line(&r->p, 0));) {
        r->line++;
        int n = thx_io_split(line, tok, max);
        if (n) return n;
    }
    return 0;
}

/* Opens the file and reads the `N WORD` line. */
static thx_status open_pairs(thx_ctx *ctx, const char *path, const char *what, scan *r, size_t *count)
{
    memset(r, 0, sizeof *r);
    r->ctx = ctx;
    r->path = path;
    THX_CHECK(thx_read_file(ctx, path, &r->text, &r->len));
    r->p = r->text;
    const char *z = memchr(r->text, '\0', r->len);
    if (z) {
        r->line = thx_io_line_at(r->text, z);
        return sfail(r, "NUL byte at byte offset %zu (a %s file is text)", (size_t)(z - r->text), what);
    }
    char *tok[4];
    int n = next_line(r, tok, 4);
    uint64_t v;
    if (n == 0) {
        r->line = r->line ? r->line : 1;
        return sfail(r, "empty file (a %s file starts with 'N leads')", what);
    }
    if (n != 2 || thx_parse_uint(tok[0], 0, INT32_MAX, &v) != 0 || v < 1 || !(tok[1][0] < '0' || tok[1][0] > '9'))
        return sfail(r, "expected 'N leads' (the number of %s lines first), got '%.40s%s'", what, tok[0],
                     n > 1 ? " ..." : "");
    if (v > r->len / 4) return sfail(r, "'%llu %s' is more lines than a file of %zu bytes holds", (unsigned long long)v, tok[1], r->len);
    *count = (size_t)v;
    return THX_OK;
}

/* After the pairs: nothing but blank lines. */
static thx_status close_pairs(scan *r, size_t count, const char *first)
{
    char *tok[2];
    if (next_line(r, tok, 2)) return sfail(r, "more than the %zu lines the first line announces ('%s')", count, first);
    return THX_OK;
}

thx_status thx_channels_read(thx_ctx *ctx, const char *path, thx_channels **out)
{
    *out = NULL;
    scan r;
    size_t n = 0;
    thx_channels *c = NULL;
    thx_status st = open_pairs(ctx, path, ".channels", &r, &n);
    char first[64] = "";
    if (st == THX_OK) {
        snprintf(first, sizeof first, "%zu leads", n);
        st = thx_channels_create(ctx, n, &c);
    }
    for (size_t k = 0; st == THX_OK && k < n; k++) {
        char *tok[3];
        int nt = next_line(&r, tok, 3);
        long node, ch;
        if (nt == 0) {
            st = sfail(&r, "truncated: %zu of the %zu 'NODE CHANNEL' lines", k, n);
            break;
        }
        if (nt != 2 || parse_int(tok[0], &node) != 0 || parse_int(tok[1], &ch) != 0) {
            st = sfail(&r, "line %zu of %zu: expected 'NODE CHANNEL' (two integers)", k + 1, n);
            break;
        }
        if (node < 1 || (size_t)node > n) {
            st = sfail(&r, "node %ld is not in 1..%zu (the file's first line)", node, n);
            break;
        }
        if (c->line[node - 1]) {
            st = sfail(&r, "node %ld given twice (first on line %d)", node, (int)c->line[node - 1]);
            break;
        }
        c->channel[node - 1] = ch >= 1 ? (int32_t)(ch - 1) : -1;
        c->line[node - 1] = (int32_t)(r.line > INT32_MAX ? INT32_MAX : r.line);
    }
    if (st == THX_OK) st = close_pairs(&r, n, first);
    free(r.text);
    if (st != THX_OK) {
        thx_channels_destroy(&c);
        return st;
    }
    snprintf(c->path, sizeof c->path, "%s", path);
    *out = c;
    return THX_OK;
}

thx_status thx_leadlinks_read(thx_ctx *ctx, const char *path, const thx_surface *s, thx_electrodes **out)
{
    *out = NULL;
    scan r;
    size_t n = 0;
    int32_t *node = NULL, *line = NULL;
    char(*name)[32] = NULL;
    thx_electrodes *e = NULL;
    thx_status st = open_pairs(ctx, path, ".leadlinks", &r, &n);
    char first[64] = "";
    int zero = 0;
    size_t zero_line = 0;
    if (st == THX_OK) {
        snprintf(first, sizeof first, "%zu leads", n);
        node = thx_malloc(ctx, n * sizeof *node);
        line = thx_malloc(ctx, n * sizeof *line);
        name = thx_calloc(ctx, n, sizeof *name);
        if (!node || !line || !name) st = THX_ENOMEM;
    }
    for (size_t k = 0; st == THX_OK && k < n; k++) {
        char *tok[3];
        int nt = next_line(&r, tok, 3);
        long v;
        if (nt == 0) {
            st = sfail(&r, "truncated: %zu of the %zu 'LABEL NODE' lines", k, n);
            break;
        }
        if (nt != 2 || parse_int(tok[1], &v) != 0) {
            st = sfail(&r, "lead %zu: expected 'LABEL NODE' (a name and a node number)", k + 1);
            break;
        }
        const char *why = thx_electrodes_name_why(tok[0], sizeof name[0]);
        if (why) {
            st = sfail(&r, "lead %zu: label \"%.40s\" %s (thorax names its electrodes by the labels)", k + 1, tok[0], why);
            break;
        }
        for (size_t j = 0; j < k; j++)
            if (!strcmp(name[j], tok[0])) {
                st = sfail(&r, "lead %zu: label \"%s\" already used on line %d", k + 1, tok[0], (int)line[j]);
                break;
            }
        if (st != THX_OK) break;
        if (v < 0) {
            st = sfail(&r, "lead %zu (\"%s\"): node %ld is negative (map3d's unlinked lead; thorax needs every lead on a "
                           "node)", k + 1, tok[0], v);
            break;
        }
        if (v == 0 && !zero) {
            zero = 1;
            zero_line = r.line;
        }
        snprintf(name[k], sizeof name[k], "%s", tok[0]);
        node[k] = (int32_t)v;
        line[k] = (int32_t)(r.line > INT32_MAX ? INT32_MAX : r.line);
    }
    if (st == THX_OK) st = close_pairs(&r, n, first);
    if (st == THX_OK) {
        if (zero) thx_log(ctx, THX_LOG_INFO, "%s: read as 0-based (node 0 on line %zu)", path, zero_line);
        for (size_t k = 0; k < n && st == THX_OK; k++) {
            if (!zero) node[k]--;
            if ((size_t)node[k] >= s->n_nodes) {
                r.line = (size_t)line[k];
                st = sfail(&r, "lead %zu (\"%s\"): node %d is not on surface \"%s\" (nodes %d..%zu)", k + 1, name[k],
                           (int)node[k] + !zero, s->name, !zero, s->n_nodes - (size_t)zero);
            }
        }
    }
    if (st == THX_OK) st = thx_electrodes_from_nodes(ctx, s, node, (const char(*)[32])name, n, &e);
    if (st == THX_OK) snprintf(e->path, sizeof e->path, "%s", path);
    free(r.text);
    free(node);
    free(line);
    free(name);
    *out = e;
    return st;
}
