/*
 * map3d .pot files (read only): the values of one time instant, one per node.
 */
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <matio.h>

#include "thorax/core/fileio.h"
#include "io/series/series_impl.h"

/* map3d .pot: the values of one time instant, one per node (any whitespace between them). */
thx_status series_read_pot(thx_ctx *ctx, const char *path, thx_series **out)
{
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        size_t at = (size_t)(nul - text), nl = 1, vals = 0;
        for (const char *c = text; c < nul; c++) nl += *c == '\n';
        /* the value it falls in (or would start), for the message */
        for (const char *c = text; c < nul; c++)
            vals += !isspace((unsigned char)*c) && (c == text || isspace((unsigned char)c[-1]));
        if (at == 0 || isspace((unsigned char)nul[-1])) vals++;
        free(text);
        return thx_error(ctx, THX_EINPUT,
                         "%s:%zu: NUL byte at byte offset %zu, in value %zu (a .pot file is text: one value per "
                         "node; damaged or binary file?)",
                         path, nl, at, vals);
    }
    size_t n = 0, cap = 1024, line = 1;
    double *v = malloc(cap * sizeof *v);
    thx_status st = v ? THX_OK : thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    for (char *p = text; st == THX_OK && *p;) {
        if (*p == '\n') { line++; p++; continue; }
        if (isspace((unsigned char)*p)) { p++; continue; }
        char *end;
        errno = 0;
        double x = strtod(p, &end);
        int range = errno == ERANGE && isinf(x);
        if (end == p || range || (*end && !isspace((unsigned char)*end))) {
            char tok[32];
            size_t k = 0;
            while (p[k] && !isspace((unsigned char)p[k]) && k < sizeof tok - 1) { tok[k] = p[k]; k++; }
            tok[k] = '\0';
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: '%s' is %s (value %zu; a .pot file holds one value per node)",
                           path, line, tok, range ? "too large for a double" : "not a number", n + 1);
            break;
        }
        if (n == cap) {
            double *w = realloc(v, 2 * cap * sizeof *v);
            if (!w) { st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", path); break; }
            v = w;
            cap *= 2;
        }
        v[n++] = x;
        p = end;
    }
    free(text);
    if (st == THX_OK && n == 0) st = thx_error(ctx, THX_EINPUT, "%s: no values (a .pot file holds one value per node)", path);
    thx_series *s = NULL;
    if (st == THX_OK) st = thx_series_create(ctx, n, 1, &s);
    if (st == THX_OK) {
        memcpy(s->v, v, n * sizeof *v);
        snprintf(s->label, sizeof s->label, "map3d .pot");
    }
    free(v);
    if (st != THX_OK) return st;
    *out = s;
    return THX_OK;
}

