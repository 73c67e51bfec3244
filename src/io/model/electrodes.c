/*
 * The electrode file (see thorax/io/electrodes_file.h; docs/formats.md,
 * "Electrodes", is the specification of the file).
 *
 * Decisions recorded here:
 *
 *  - One validator (thx_electrodes_validate, src/model/electrodes.c) serves the
 *    writer, the reader and thx_electrodes_check: at least one electrode, a surface name as a model
 *    would accept it, electrode names 1-31 characters from [A-Za-z0-9_.+-]
 *    (one word on their line; not a keyword of the file), unique, nodes >= 0,
 *    finite positions. So whatever is written reads back, and a set read from
 *    a file can be written again.
 *
 *  - Positions are printed "%.6f" like NAME.pts (a node read from a model
 *    prints back to the same text), and a value that rounds to zero is
 *    written "0.000000", never "-0.000000" (byte-identical output).
 *
 *  - The file is read whole and scanned line by line; `#` starts a comment,
 *    blank lines and CRLF are allowed. Every message names the file and the
 *    line, and, where it concerns one, the electrode ("e.txt:7: electrode 4
 *    (\"V1\"): node '0' is not a node number (1, 2, ...)"). Electrodes are
 *    counted from 1 in messages, like nodes in the file.
 */
#include "thorax/io/electrodes_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "io/common/parse_uint.h"
#include "io/common/tokens.h"

/* ------------------------------------------------------------ writing */

/* "%.6f", with values that round to zero written as 0.000000 (no "-0.000000"). */
static void put_coord(FILE *f, double v)
{
    if (fabs(v) < 5e-7) v = 0.0;
    fprintf(f, "%.6f", v);
}

thx_status thx_electrodes_write(thx_ctx *ctx, const thx_electrodes *e, const char *path)
{
    char where[1100];
    snprintf(where, sizeof where, "%s: ", path);
    THX_CHECK(thx_electrodes_validate(ctx, e, where));
    thx_atomic_file af;
    /* a file of that name is replaced only if thorax wrote it (thorax/core/fileio.h) */
    THX_CHECK(thx_atomic_open_output(ctx, path, "thorax-electrodes", 17, NULL, 0, &af));
    FILE *f = af.f;
    fprintf(f, "thorax-electrodes 1\nsurface %s\ncount %zu\n", e->surface, e->n);
    for (size_t i = 0; i < e->n; i++) {
        if (e->node[i] == THX_ELECTRODE_OFF_NODE) fprintf(f, "%s - ", e->name[i]);
        else fprintf(f, "%s %d ", e->name[i], (int)e->node[i] + 1);
        put_coord(f, e->xyz[3 * i]);
        fputc(' ', f);
        put_coord(f, e->xyz[3 * i + 1]);
        fputc(' ', f);
        put_coord(f, e->xyz[3 * i + 2]);
        fputc('\n', f);
    }
    fprintf(f, "end\n");
    return thx_atomic_commit(ctx, &af);
}

/* ------------------------------------------------------------ reading */

typedef struct {
    thx_ctx *ctx;
    const char *path;
    size_t line;
} reader;

static thx_status rfail(const reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status rfail(const reader *r, const char *fmt, ...)
{
    char msg[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(r->ctx, THX_EINPUT, "%s:%zu: %s", r->path, r->line, msg);
}

/* A positive integer count or node number that fits in 32 bits (digits only, overflow-checked). */
static int parse_positive(const char *t, long *out)
{
    uint64_t v;
    if (thx_parse_uint(t, 0, INT32_MAX - 1, &v) != 0 || v < 1) return -1;
    *out = (long)v;
    return 0;
}

static thx_status parse_electrode(const reader *r, char **tok, int ntok, size_t i, thx_electrodes *e)
{
    if (ntok != 5)
        return rfail(r, "electrode %zu: expected 'NAME NODE X Y Z', got %d field%s", i + 1, ntok, ntok == 1 ? "" : "s");
    const char *why = thx_electrodes_name_why(tok[0], sizeof e->name[0]);
    if (why) return rfail(r, "electrode %zu: name \"%.40s\" %s", i + 1, tok[0], why);
    for (size_t j = 0; j < i; j++)
        if (!strcmp(e->name[j], tok[0]))
            return rfail(r, "electrode %zu: name \"%s\" already used by electrode %zu", i + 1, tok[0], j + 1);
    long node;
    if (!strcmp(tok[1], "-")) node = 0; /* between nodes: placed on the surface by its position */
    else if (parse_positive(tok[1], &node) != 0)
        return rfail(r, "electrode %zu (\"%s\"): node '%.40s' is not a node number (1, 2, ...) or '-' (a point "
                        "between nodes)", i + 1, tok[0], tok[1]);
    double x[3];
    for (int k = 0; k < 3; k++) {
        char *end = NULL;
        x[k] = strtod(tok[2 + k], &end);
        if (end == tok[2 + k] || *end || !isfinite(x[k]))
            return rfail(r, "electrode %zu (\"%s\"): %c '%.40s' is not a finite number", i + 1, tok[0], "xyz"[k],
                         tok[2 + k]);
    }
    snprintf(e->name[i], sizeof e->name[i], "%s", tok[0]);
    e->node[i] = node ? (int32_t)(node - 1) : THX_ELECTRODE_OFF_NODE;
    memcpy(e->xyz + 3 * i, x, sizeof x);
    return THX_OK;
}

thx_status thx_electrodes_read(thx_ctx *ctx, const char *path, thx_electrodes **out)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    reader r = {ctx, path, 0};
    thx_electrodes *e = NULL;
    thx_status st = THX_OK;
    char surface[sizeof e->surface] = "";
    size_t surface_line = 0, count_line = 0, count = 0, got = 0;
    int seen_header = 0, seen_end = 0;
    if (memchr(text, '\0', len)) {
        /* name the line of the first NUL */
        const char *z = memchr(text, '\0', len);
        r.line = thx_io_line_at(text, z);
        st = rfail(&r, "NUL byte at byte offset %zu (a text file holds none: a binary file, or a damaged one?)",
                   (size_t)(z - text));
        goto done;
    }
    char *p = text;
    for (char *line; (line = thx_io_next_line(&p, '#'));) {
        r.line++;
        char *tok[6];
        int ntok = thx_io_split(line, tok, 6);
        if (ntok == 0) continue;
        if (seen_end) {
            st = rfail(&r, "text after 'end'");
            goto done;
        }
        if (!seen_header) {
            if (strcmp(tok[0], "thorax-electrodes") != 0) {
                st = rfail(&r, "not a thorax electrodes file (expected 'thorax-electrodes 1' as the first line)");
                goto done;
            }
            if (ntok != 2 || strcmp(tok[1], "1") != 0) {
                st = rfail(&r, "unsupported electrodes file version '%.20s' (this reader knows 'thorax-electrodes 1')",
                           ntok >= 2 ? tok[1] : "");
                goto done;
            }
            seen_header = 1;
            continue;
        }
        if (!strcmp(tok[0], "surface") || !strcmp(tok[0], "count")) {
            int is_surface = tok[0][0] == 's';
            if (e) {
                st = rfail(&r, "'%s' after the electrode lines began", tok[0]);
                goto done;
            }
            size_t *seen = is_surface ? &surface_line : &count_line;
            if (*seen) {
                st = rfail(&r, "'%s' given twice (first on line %zu)", tok[0], *seen);
                goto done;
            }
            if (ntok != 2) {
                st = rfail(&r, is_surface ? "expected 'surface NAME'" : "expected 'count N' with N a positive integer");
                goto done;
            }
            if (is_surface) {
                const char *why = thx_electrodes_surface_name_why(tok[1], sizeof surface);
                if (why) {
                    st = rfail(&r, "surface name \"%.63s\" %s", tok[1], why);
                    goto done;
                }
                snprintf(surface, sizeof surface, "%s", tok[1]);
            } else {
                long c;
                if (parse_positive(tok[1], &c) != 0) {
                    st = rfail(&r, "expected 'count N' with N a positive integer, got '%.40s'", tok[1]);
                    goto done;
                }
                if ((size_t)c > len / 10) { /* an electrode line takes at least 10 bytes */
                    st = rfail(&r, "'count %ld' is more electrodes than a file of %zu bytes can hold", c, len);
                    goto done;
                }
                count = (size_t)c;
            }
            *seen = r.line;
            continue;
        }
        if (!strcmp(tok[0], "end") && ntok == 1) {
            if (!e) {
                st = rfail(&r, "'end' before any electrode line");
                goto done;
            }
            if (got < count) {
                st = rfail(&r, "'end' after %zu of %zu electrodes ('count %zu', line %zu)", got, count, count,
                           count_line);
                goto done;
            }
            seen_end = 1;
            continue;
        }
        /* an electrode line */
        if (!e) {
            if (!surface_line || !count_line) {
                st = rfail(&r, "electrode line before %s", !surface_line ? "'surface NAME'" : "'count N'");
                goto done;
            }
            if ((st = thx_electrodes_create(ctx, count, &e)) != THX_OK) goto done;
            snprintf(e->surface, sizeof e->surface, "%s", surface);
        }
        if (got == count) {
            st = rfail(&r, "more electrode lines than 'count %zu' (line %zu), or a missing 'end'", count, count_line);
            goto done;
        }
        if ((st = parse_electrode(&r, tok, ntok, got, e)) != THX_OK) goto done;
        got++;
    }
    if (!seen_header) {
        r.line = r.line ? r.line : 1;
        st = rfail(&r, "empty file (expected 'thorax-electrodes 1' as the first line)");
        goto done;
    }
    if (!seen_end) {
        if (e && got < count)
            st = rfail(&r, "truncated file: %zu of %zu electrodes ('count %zu', line %zu) and no 'end' line", got,
                       count, count, count_line);
        else
            st = rfail(&r, "truncated file (no 'end' line)");
        goto done;
    }
    {
        char where[1100];
        snprintf(where, sizeof where, "%s: ", path);
        st = thx_electrodes_validate(ctx, e, where); /* cannot fail after the checks above; kept as the invariant */
    }
done:
    free(text);
    if (st != THX_OK) thx_electrodes_destroy(&e);
    if (e) snprintf(e->path, sizeof e->path, "%s", path);
    *out = e;
    return st;
}
