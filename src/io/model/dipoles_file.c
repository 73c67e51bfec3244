/*
 * Dipole files (thorax/io/dipoles_file.h; docs/formats.md, "Dipoles"): OpenMEEG's .dip layout
 * (six numbers a line, each line a source of its own) and thorax's time series of moments at
 * fixed positions. Every value must be a finite number; every error names the file and line.
 */
#include "thorax/io/dipoles_file.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"

thx_status thx_dipoles_create(thx_ctx *ctx, size_t n, size_t n_frames, thx_dipoles **out)
{
    *out = NULL;
    if (n > ((size_t)1 << 24) || n_frames > ((size_t)1 << 28) || (n && n_frames > ((size_t)1 << 32) / n))
        return thx_error(ctx, THX_EINPUT, "dipoles: %zu dipoles x %zu frames: too many", n, n_frames);
    thx_dipoles *d = thx_calloc(ctx, 1, sizeof *d);
    if (!d) return THX_ENOMEM;
    d->n = n;
    d->n_frames = n_frames;
    d->pos = thx_calloc(ctx, 3 * (n ? n : 1), sizeof *d->pos);
    d->line = thx_calloc(ctx, n ? n : 1, sizeof *d->line);
    d->time = thx_calloc(ctx, n_frames ? n_frames : 1, sizeof *d->time);
    d->frame_line = thx_calloc(ctx, n_frames ? n_frames : 1, sizeof *d->frame_line);
    d->moment = thx_calloc(ctx, 3 * (n ? n : 1) * (n_frames ? n_frames : 1), sizeof *d->moment);
    if (!d->pos || !d->line || !d->time || !d->frame_line || !d->moment) {
        thx_dipoles_destroy(&d);
        return THX_ENOMEM;
    }
    *out = d;
    return THX_OK;
}

void thx_dipoles_destroy(thx_dipoles **dp)
{
    if (!dp || !*dp) return;
    thx_dipoles *d = *dp;
    free(d->pos);
    free(d->line);
    free(d->time);
    free(d->frame_line);
    free(d->moment);
    free(d);
    *dp = NULL;
}

/* ---- a line reader over the file's text: comments cut, blank lines skipped ---- */

typedef struct {
    thx_ctx *ctx;
    const char *path;
    char *p, *end;   /* the rest of the text */
    size_t line;     /* the line last returned (1-based) */
    char *cur;       /* it, NUL-terminated, comment cut */
} lines;

static thx_status lfail(const lines *L, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status lfail(const lines *L, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(L->ctx, THX_EINPUT, "%s:%zu: %s", L->path, L->line, msg);
}

/* The next line that holds anything but blanks and a comment; 0 at the end of the file. */
static int next_line(lines *L)
{
    while (L->p < L->end) {
        char *s = L->p, *e = memchr(s, '\n', (size_t)(L->end - s));
        if (!e) e = L->end;
        L->p = e < L->end ? e + 1 : e;
        *e = '\0';
        L->line++;
        char *h = strchr(s, '#');
        if (h) *h = '\0';
        char *q = s;
        while (*q == ' ' || *q == '\t' || *q == '\r') q++;
        if (*q) {
            L->cur = q;
            return 1;
        }
    }
    L->cur = NULL;
    return 0;
}

/* Reads up to max numbers of the current line into v; *n how many words there are. A word that
 * is not a finite number is an error naming it (and its column, 1-based). */
static thx_status numbers(lines *L, double *v, int max, int *n)
{
    char *p = L->cur;
    int k = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',') p++;
        if (!*p) break;
        char *w = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\r' && *p != ',') p++;
        char save = *p;
        *p = '\0';
        char *e;
        errno = 0;
        double x = strtod(w, &e);
        if (e == w || *e) return lfail(L, "value %d ('%s') is not a number", k + 1, w);
        if (!isfinite(x) || errno == ERANGE) return lfail(L, "value %d ('%s') is not a finite number", k + 1, w);
        if (k < max) v[k] = x;
        k++;
        *p = save;
    }
    *n = k;
    return THX_OK;
}

/* `word N [rest]` on the current line: N (a count >= 1 up to cap) and the rest (or NULL). */
static thx_status keyword_count(lines *L, const char *word, size_t cap, size_t *n, char **rest)
{
    size_t wl = strlen(word);
    char *p = L->cur;
    if (strncmp(p, word, wl) || (p[wl] != ' ' && p[wl] != '\t'))
        return lfail(L, "expected '%s N', found '%.40s'", word, p);
    p += wl;
    char *e;
    errno = 0;
    unsigned long long v = strtoull(p, &e, 10);
    if (e == p || errno || v < 1 || v > cap || strchr(p, '-')) return lfail(L, "'%s' needs a count from 1 to %zu", word, cap);
    while (*e == ' ' || *e == '\t' || *e == '\r') e++;
    if (rest) *rest = *e ? e : NULL;
    else if (*e) return lfail(L, "text after the count: '%.40s'", e);
    *n = (size_t)v;
    return THX_OK;
}

static thx_status read_dip(lines *L, thx_dipoles **out)
{
    /* one pass into growing arrays (the line reader cuts the text as it goes), then the set */
    double *row = NULL;
    size_t *ln = NULL, n = 0, cap = 0, lcap = 0;
    thx_dipoles *d = NULL;
    thx_status st = THX_OK;
    do {
        THX_TRY(thx_grow(L->ctx, (void **)&row, &cap, 6 * (n + 1), sizeof *row));
        THX_TRY(thx_grow(L->ctx, (void **)&ln, &lcap, n + 1, sizeof *ln));
        int k = 0;
        THX_TRY(numbers(L, row + 6 * n, 6, &k));
        if (k != 6) { st = lfail(L, "%d value%s; a dipole line is 'px py pz qx qy qz' (6 numbers)", k, k == 1 ? "" : "s"); goto done; }
        ln[n++] = L->line;
    } while (next_line(L));
    THX_TRY(thx_dipoles_create(L->ctx, n, n, &d));
    d->separate = 1;
    snprintf(d->time_unit, sizeof d->time_unit, "dipole");
    for (size_t i = 0; i < n; i++) {
        memcpy(d->pos + 3 * i, row + 6 * i, 3 * sizeof *row);
        memcpy(d->moment + 3 * (i * n + i), row + 6 * i + 3, 3 * sizeof *row);
        d->line[i] = d->frame_line[i] = ln[i];
        d->time[i] = (double)(i + 1);
    }
    *out = d;
    d = NULL;
done:
    free(row);
    free(ln);
    thx_dipoles_destroy(&d);
    return st;
}

static thx_status read_series(lines *L, thx_dipoles **out)
{
    thx_dipoles *d = NULL;
    thx_status st = THX_OK;
    size_t n = 0, nf = 0;
    char *rest = NULL;
    if (!next_line(L)) return lfail(L, "the file ends before 'dipoles N'");
    THX_CHECK(keyword_count(L, "dipoles", (size_t)1 << 20, &n, NULL));
    /* positions first into a temporary array: the frame count comes after them */
    double *pos = thx_malloc(L->ctx, 3 * n * sizeof *pos);
    size_t *pline = thx_malloc(L->ctx, n * sizeof *pline);
    if (!pos || !pline) { free(pos); free(pline); return THX_ENOMEM; }
    for (size_t i = 0; i < n; i++) {
        if (!next_line(L)) { st = lfail(L, "the file ends after %zu of %zu dipole positions", i, n); goto done; }
        double v[3];
        int k = 0;
        THX_TRY(numbers(L, v, 3, &k));
        if (k != 3) { st = lfail(L, "dipole %zu: %d values; a position is 'px py pz' (mm)", i + 1, k); goto done; }
        memcpy(pos + 3 * i, v, sizeof v);
        pline[i] = L->line;
    }
    if (!next_line(L)) { st = lfail(L, "the file ends before 'frames F'"); goto done; }
    THX_TRY(keyword_count(L, "frames", (size_t)1 << 24, &nf, &rest));
    char unit[16] = "";
    if (rest) {
        size_t ul = strcspn(rest, " \t\r");
        if (ul >= sizeof unit || rest[ul + strspn(rest + ul, " \t\r")]) {
            st = lfail(L, "after 'frames %zu' one word (the time unit, up to 15 characters) may follow", nf);
            goto done;
        }
        memcpy(unit, rest, ul);
        unit[ul] = '\0';
    }
    THX_TRY(thx_dipoles_create(L->ctx, n, nf, &d));
    memcpy(d->pos, pos, 3 * n * sizeof *pos);
    memcpy(d->line, pline, n * sizeof *pline);
    snprintf(d->time_unit, sizeof d->time_unit, "%s", unit);
    double *v = thx_malloc(L->ctx, (3 * n + 1) * sizeof *v);
    if (!v) { st = THX_ENOMEM; goto done; }
    for (size_t f = 0; f < nf && st == THX_OK; f++) {
        int k = 0;
        if (!next_line(L)) st = lfail(L, "the file ends after %zu of %zu frames", f, nf);
        else if ((st = numbers(L, v, (int)(3 * n + 1), &k)) == THX_OK && (size_t)k != 3 * n + 1)
            st = lfail(L, "frame %zu: %d values; a frame is the time and 3 moments per dipole (%zu)", f + 1, k, 3 * n + 1);
        if (st != THX_OK) break;
        if (f > 0 && !(v[0] > d->time[f - 1])) {
            st = lfail(L, "frame %zu: time %g does not follow %g (times must increase)", f + 1, v[0], d->time[f - 1]);
            break;
        }
        d->time[f] = v[0];
        memcpy(d->moment + 3 * n * f, v + 1, 3 * n * sizeof *v);
        d->frame_line[f] = L->line;
    }
    free(v);
    if (st != THX_OK) goto done;
    if (!next_line(L)) { st = lfail(L, "the file ends without 'end' after %zu frames", nf); goto done; }
    if (strncmp(L->cur, "end", 3) || L->cur[3 + strspn(L->cur + 3, " \t\r")]) {
        st = lfail(L, "expected 'end' after %zu frames, found '%.40s'", nf, L->cur);
        goto done;
    }
    if (next_line(L)) { st = lfail(L, "text after 'end'"); goto done; }
    *out = d;
    d = NULL;
done:
    free(pos);
    free(pline);
    thx_dipoles_destroy(&d);
    return st;
}

thx_status thx_dipoles_read(thx_ctx *ctx, const char *path, thx_dipoles **out)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    if (memchr(text, '\0', len)) {
        free(text);
        return thx_error(ctx, THX_EINPUT, "%s: a NUL byte: not a text file of dipoles", path);
    }
    lines L = {ctx, path, text, text + len, 0, NULL};
    thx_status st;
    if (!next_line(&L)) st = thx_error(ctx, THX_EINPUT, "%s: no dipole in the file", path);
    else if (!strncmp(L.cur, "thorax-dipoles", 14)) {
        char *v = L.cur + 14;
        while (*v == ' ' || *v == '\t') v++;
        if (strcmp(v, "1") && strncmp(v, "1 ", 2) && strncmp(v, "1\t", 2) && strncmp(v, "1\r", 2))
            st = lfail(&L, "thorax-dipoles version '%.20s': this thorax reads version 1", v);
        else st = read_series(&L, out);
    } else st = read_dip(&L, out);
    if (st == THX_OK) snprintf((*out)->path, sizeof (*out)->path, "%s", path);
    free(text);
    return st;
}
