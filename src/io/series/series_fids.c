/*
 * map3d .fids files: per-lead fiducials (activation, recovery ...) of a time
 * series, read into the series' fiducials (thorax/io/series_file.h;
 * docs/formats.md, "map3d .fids"). The layout is map3d's (its manual,
 * doc/manual/input.tex, and its reader, thirdparty/fids/fidfilesubs.c):
 *
 *     1                      number of time series (map3d reads one)
 *     1 -1                   series number, pak file number (optional)
 *     256 activation recovery   number of leads, fiducial type names
 *     1 8 212                lead number (1, 2, ... in order), one value per type
 *     ...
 *
 * Lines that are blank or hold '#', '%' or '!' are comments (map3d's
 * QComment); values are separated by blanks or commas. Values count frames
 * from 1; map3d subtracts 1 when it reads them, and so does this reader
 * (the series holds fiducials as map3d does in memory and in .mat files).
 */
#include "thorax/io/series_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"

typedef struct {
    char *p;
    size_t line;
} fcur;

/* The next line that is not a comment (NUL-terminated in place), or NULL. */
static char *next_line(fcur *c)
{
    while (c->p && *c->p) {
        char *l = c->p, *e = strchr(l, '\n');
        if (e) {
            *e = '\0';
            c->p = e + 1;
        } else {
            c->p = l + strlen(l);
        }
        c->line++;
        if (strpbrk(l, "#%!")) continue;
        if (strspn(l, " \t\r,") == strlen(l)) continue;
        return l;
    }
    return NULL;
}

static char *word(char **p)
{
    char *s = *p + strspn(*p, " \t\r,");
    if (!*s) return NULL;
    size_t n = strcspn(s, " \t\r,");
    *p = s + n;
    if (**p) *(*p)++ = '\0';
    return s;
}

thx_status thx_series_read_fids(thx_ctx *ctx, const char *path, thx_series *s)
{
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    if (memchr(text, '\0', len)) {
        free(text);
        return thx_error(ctx, THX_EINPUT, "%s: NUL byte at byte offset %zu (a .fids file is text)", path,
                         (size_t)((char *)memchr(text, '\0', len) - text));
    }
    fcur c = {text, 0};
    thx_status st = THX_OK;
    double *vals = NULL;
    int types[64];
    size_t nt = 0;
    char *l = next_line(&c), *w, *end;
    long nseries = l && (w = word(&l)) ? strtol(w, &end, 10) : 0;
    if (nseries < 1 || *end) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: expected the number of time series", path, c.line);
        goto done;
    }
    if (nseries > 1) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: %ld time series: only files of one are read (as map3d does)", path, c.line,
                       nseries);
        goto done;
    }
    l = next_line(&c);
    if (!l || !(w = word(&l)) || strtol(w, &end, 10) != 1 || *end) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: expected 'series-number [pak-number]' with series number 1", path, c.line);
        goto done;
    }
    l = next_line(&c);
    long nleads = l && (w = word(&l)) ? strtol(w, &end, 10) : 0;
    if (nleads < 1 || *end) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: expected 'number-of-leads type-name ...'", path, c.line);
        goto done;
    }
    if ((size_t)nleads != s->n_rows) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: %ld leads, but the series has %zu rows", path, c.line, nleads, s->n_rows);
        goto done;
    }
    while ((w = word(&l))) {
        int t = thx_fiducial_type_parse(w);
        if (t < 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: fiducial type '%s' unknown (pon poff qon rpeak soff stoff tpeak toff "
                                            "actplus actminus act recplus recminus rec ref jpt baseline pacing, or "
                                            "activation, recovery ...)", path, c.line, w);
            goto done;
        }
        if (nt == sizeof types / sizeof types[0]) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: more than %zu fiducial types", path, c.line, nt);
            goto done;
        }
        types[nt++] = t;
    }
    if (!nt) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: no fiducial type names after the number of leads", path, c.line);
        goto done;
    }
    /* the leads must fit: each takes a line of at least 2 bytes per value */
    if ((size_t)nleads > len / (2 * (nt + 1))) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: %ld leads cannot fit in a file of %zu bytes", path, c.line, nleads, len);
        goto done;
    }
    vals = thx_malloc(ctx, nt * (size_t)nleads * sizeof *vals);
    if (!vals) {
        st = THX_ENOMEM;
        goto done;
    }
    for (long k = 0; k < nleads; k++) {
        l = next_line(&c);
        if (!l) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: the file ends at lead %ld of %ld", path, c.line, k + 1, nleads);
            goto done;
        }
        w = word(&l);
        if (!w || strtol(w, &end, 10) != k + 1 || *end) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: expected lead number %ld first", path, c.line, k + 1);
            goto done;
        }
        for (size_t j = 0; j < nt; j++) {
            w = word(&l);
            errno = 0;
            double x = w ? strtod(w, &end) : NAN;
            if (!w || *end || !isfinite(x)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: lead %ld: value %zu (%s) %s", path, c.line, k + 1, j + 1,
                               thx_fiducial_type_name(types[j]), w ? "is not a finite number" : "is missing");
                goto done;
            }
            vals[j * (size_t)nleads + (size_t)k] = x - 1.0;
        }
        if ((w = word(&l))) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: lead %ld: more values than the %zu types", path, c.line, k + 1, nt);
            goto done;
        }
    }
    if (next_line(&c)) {
        st = thx_error(ctx, THX_EINPUT, "%s:%zu: text after the last lead", path, c.line);
        goto done;
    }
    for (size_t j = 0; j < nt && st == THX_OK; j++)
        st = thx_series_add_fiducial(ctx, s, types[j], 0, (size_t)nleads, vals + j * (size_t)nleads);
done:
    free(vals);
    free(text);
    return st;
}
