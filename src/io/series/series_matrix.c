/*
 * Time series as a plain numeric matrix in text (read) and as CSV (written);
 * series.c has the dispatch, docs/formats.md ("Plain matrices and CSV") the rules.
 *
 * Decisions recorded here:
 *
 *  - A matrix is read as the file lays it out: one line per row (channel or
 *    node), one column per frame, numbers separated by blanks, tabs or
 *    commas (one comma between two numbers at most). Every line must have the
 *    same number of values: a short or long line is an error naming its line.
 *    Blank lines and lines starting with '#' are skipped. `nan` is a missing
 *    value, as in the text series; "inf" is accepted too (the series keeps it;
 *    thx_series_find_nonfinite reports it).
 *
 *  - A header line is recognised by its first cell not being a number: its
 *    other cells are the times of the frames, and then the first cell of every
 *    following line names the row and is skipped (a CSV written by thorax or
 *    by pandas with an index). "time(U)" and "value(U)" words in the header's
 *    first cell give the units. Without a header the time axis is the frame
 *    number from 0 (time_unit "frame").
 *
 *  - CSV is written with that header (first cell "thorax-series-csv time(U)
 *    value(U)") and one line per row, the row number first, numbers in the
 *    shortest form that reads back to the same double, so the CSV reads back
 *    exactly (values and times) and opens in a spreadsheet or
 *    pandas.read_csv(path, index_col=0).
 */
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/core/fileio.h"
#include "io/series/series_impl.h"

/* One cell at *p (skipping blanks and one comma); returns its length, 0 at the end of the line. */
static size_t cell(char **p, const char **start, int *commas)
{
    char *c = *p;
    *commas = 0;
    while (*c == ' ' || *c == '\t' || *c == '\r' || *c == ',') {
        if (*c == ',') (*commas)++;
        c++;
    }
    *start = c;
    while (*c && *c != '\n' && *c != ' ' && *c != '\t' && *c != '\r' && *c != ',') c++;
    *p = c;
    return (size_t)(c - *start);
}

static int number(const char *t, size_t n, double *x)
{
    char buf[64];
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, t, n);
    buf[n] = '\0';
    char *end;
    errno = 0;
    *x = strtod(buf, &end);
    if (*end || (errno == ERANGE && isinf(*x))) return -1;
    return 0;
}

/* "time(ms)" in the header's first cell: copies ms into dst. */
static void unit_word(const char *cell0, const char *key, char *dst, size_t cap)
{
    const char *k = strstr(cell0, key);
    if (!k) return;
    k += strlen(key);
    const char *e = strchr(k, ')');
    if (!e || (size_t)(e - k) >= cap) return;
    memcpy(dst, k, (size_t)(e - k));
    dst[e - k] = '\0';
}

thx_status series_read_matrix(thx_ctx *ctx, const char *path, thx_series **out)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        size_t line = 1, at = (size_t)(nul - text);
        for (const char *c = text; c < nul; c++) line += *c == '\n';
        free(text);
        return thx_error(ctx, THX_EINPUT, "%s:%zu: NUL byte at byte offset %zu (a matrix is text: damaged or binary file?)",
                         path, line, at);
    }
    /* values are stored as read (row-major), then transposed into the series */
    size_t cap = 1024, n = 0, cols = 0, rows = 0, line = 0, hdr_cols = 0;
    double *v = thx_malloc(ctx, cap * sizeof *v), *times = NULL;
    char cell0[256] = "";
    int header = 0;
    thx_status st = v ? THX_OK : THX_ENOMEM;
    char *p = text;
    while (st == THX_OK && *p) {
        line++;
        char *eol = strchr(p, '\n');
        char *next = eol ? eol + 1 : p + strlen(p);
        if (eol) *eol = '\0';
        char *q = p;
        while (*q == ' ' || *q == '\t' || *q == '\r') q++;
        if (!*q || *q == '#') {
            p = next;
            continue;
        }
        const char *t;
        int commas;
        size_t k = cell(&q, &t, &commas), count = 0;
        double x;
        if (rows == 0 && !header && number(t, k, &x) != 0) {
            /* a header: the first cell names the columns, the rest are the times */
            header = 1;
            /* the first cell runs to the first comma (it may hold blanks: "thorax-series-csv time(ms) ...") */
            char *comma = strchr(t, ',');
            if (comma) {
                k = (size_t)(comma - t);
                q = comma;
                while (k && (t[k - 1] == ' ' || t[k - 1] == '\t' || t[k - 1] == '\r')) k--;
            }
            snprintf(cell0, sizeof cell0, "%.*s", (int)(k < 255 ? k : 255), t);
            while ((k = cell(&q, &t, &commas)) > 0) {
                if (number(t, k, &x) != 0) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%zu: header cell %zu '%.*s' is not a number (a header's cells after "
                                                    "the first are the times of the frames)",
                                   path, line, hdr_cols + 2, (int)(k < 40 ? k : 40), t);
                    break;
                }
                double *w = thx_realloc(ctx, times, (hdr_cols + 1) * sizeof *w);
                if (!w) { st = THX_ENOMEM; break; }
                times = w;
                times[hdr_cols++] = x;
            }
            if (st == THX_OK && hdr_cols == 0)
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: '%s' is not a number, and no times follow it", path, line, cell0);
            p = next;
            continue;
        }
        if (header) k = cell(&q, &t, &commas); /* the row's name */
        while (st == THX_OK && k > 0) {
            if (commas > 1 || (count == 0 && commas && !header)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: empty cell before value %zu (two commas)", path, line, count + 1);
                break;
            }
            if (number(t, k, &x) != 0) {
                st = thx_error(ctx, THX_EINPUT, "%s:%zu: value %zu '%.*s' is not a number", path, line, count + 1,
                               (int)(k < 40 ? k : 40), t);
                break;
            }
            if (n == cap) {
                double *w = thx_realloc(ctx, v, 2 * cap * sizeof *v);
                if (!w) { st = THX_ENOMEM; break; }
                v = w;
                cap *= 2;
            }
            v[n++] = x;
            count++;
            k = cell(&q, &t, &commas);
        }
        if (st != THX_OK) break;
        if (commas) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: the line ends with a comma (an empty cell)", path, line);
            break;
        }
        if (count == 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: a row name and no values", path, line);
            break;
        }
        if (rows == 0) cols = count;
        if (count != cols) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: row %zu has %zu values, row 1 has %zu (every row of a matrix has one "
                                            "value per frame)", path, line, rows + 1, count, cols);
            break;
        }
        if (header && count != hdr_cols) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: row %zu has %zu values, the header has %zu times", path, line, rows + 1,
                           count, hdr_cols);
            break;
        }
        rows++;
        p = next;
    }
    free(text);
    if (st == THX_OK && rows == 0) st = thx_error(ctx, THX_EINPUT, "%s: no values (a matrix: one line per row, one column per frame)", path);
    thx_series *s = NULL;
    if (st == THX_OK) st = thx_series_create(ctx, rows, cols, &s);
    if (st == THX_OK) {
        for (size_t r = 0; r < rows; r++)
            for (size_t f = 0; f < cols; f++) s->v[f * rows + r] = v[r * cols + f];
        if (header) {
            memcpy(s->time, times, cols * sizeof *times);
            snprintf(s->time_unit, sizeof s->time_unit, "ms");
            unit_word(cell0, "time(", s->time_unit, sizeof s->time_unit);
            unit_word(cell0, "value(", s->unit, sizeof s->unit);
        } else {
            snprintf(s->time_unit, sizeof s->time_unit, "frame");
        }
        st = thx_series_validate(ctx, s, path);
    }
    free(v);
    free(times);
    if (st != THX_OK) {
        thx_series_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}

thx_status series_write_csv(thx_ctx *ctx, const thx_series *s, const char *path)
{
    for (const char *c = s->unit; *c; c++)
        if ((unsigned char)*c <= ' ' || *c == ',' || *c == ')' || *c == 127)
            return thx_error(ctx, THX_EINPUT, "%s: unit \"%s\" has a blank, comma or ')' (it goes in the CSV header)", path, s->unit);
    for (const char *c = s->time_unit; *c; c++)
        if ((unsigned char)*c <= ' ' || *c == ',' || *c == ')' || *c == 127)
            return thx_error(ctx, THX_EINPUT, "%s: time unit \"%s\" has a blank, comma or ')'", path, s->time_unit);
    size_t N = s->n_rows, M = s->n_frames;
    if (M > (SIZE_MAX - 64) / 26) return thx_error(ctx, THX_ENOMEM, "%s: %zu frames: a line too long", path, M);
    char *line = thx_malloc(ctx, M * 26 + 64);
    if (!line) return THX_ENOMEM;
    thx_atomic_file af;
    thx_status st = thx_atomic_open_output(ctx, path, "thorax-series-csv", 17, NULL, 0, &af);
    if (st != THX_OK) {
        free(line);
        return st;
    }
    fprintf(af.f, "thorax-series-csv time(%s) value(%s)", s->time_unit, s->unit);
    char *p = line;
    for (size_t f = 0; f < M; f++) {
        *p++ = ',';
        p = series_put_double(p, s->time[f]);
    }
    *p++ = '\n';
    fwrite(line, 1, (size_t)(p - line), af.f);
    for (size_t r = 0; r < N; r++) {
        p = line + sprintf(line, "%zu", r + 1);
        for (size_t f = 0; f < M; f++) {
            *p++ = ',';
            p = series_put_double(p, s->v[f * N + r]);
        }
        *p++ = '\n';
        fwrite(line, 1, (size_t)(p - line), af.f);
    }
    free(line);
    return thx_atomic_commit(ctx, &af);
}
