/*
 * Time series, text format (series.c has the dispatch; docs/formats.md,
 * "Time series", is the specification).
 *
 * Decisions recorded here:
 *
 *  - Text numbers are printed in a short form that reads back to the same
 *    double (put_double: integers and few-decimal values without printf,
 *    else the shortest of 15, 16, 17 significant digits), so a text round
 *    trip is exact and the files stay readable ("0.1", not
 *    "0.10000000000000001"). NaN is "nan" (its payload and sign are not kept),
 *    infinities "inf" and "-inf". Rows are formatted in parallel (OpenMP) in
 *    blocks and written in order, so the bytes do not depend on the thread
 *    count. Text is read line by line (getline) and parsed with strtod; a
 *    token ends at a blank or '#'.
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
#include "io/common/parse_uint.h"
#include "io/series/series_impl.h"

/* ------------------------------------------------------------ text out */

/* Appends the decimal digits of u (no sign); returns the end. */
static char *put_uint(char *p, unsigned long long u)
{
    char tmp[24];
    int n = 0;
    do tmp[n++] = (char)('0' + u % 10); while ((u /= 10) != 0);
    while (n) *p++ = tmp[--n];
    return p;
}

/* The digits d[0..n-1] (d[0] != 0) times 10^(e - n + 1), written as printf's
 * %g would: scientific when e < -4 or e >= n_max, trailing zeros dropped. */
static char *put_digits(char *p, int neg, const char *d, int n, int e, int n_max)
{
    while (n > 1 && d[n - 1] == '0') n--;
    if (neg) *p++ = '-';
    if (e < -4 || e >= n_max) {
        *p++ = d[0];
        if (n > 1) {
            *p++ = '.';
            memcpy(p, d + 1, (size_t)n - 1);
            p += n - 1;
        }
        *p++ = 'e';
        *p++ = e < 0 ? '-' : '+';
        int a = e < 0 ? -e : e;
        if (a < 10) *p++ = '0';
        return put_uint(p, (unsigned long long)a);
    }
    if (e < 0) {
        *p++ = '0';
        *p++ = '.';
        for (int i = 0; i < -e - 1; i++) *p++ = '0';
        memcpy(p, d, (size_t)n);
        return p + n;
    }
    for (int i = 0; i <= e; i++) *p++ = i < n ? d[i] : '0';
    if (n > e + 1) {
        *p++ = '.';
        memcpy(p, d + e + 1, (size_t)(n - e - 1));
        p += n - e - 1;
    }
    return p;
}

/* Appends a short decimal that reads back exactly as x; returns the end (at
 * most 24 characters). In order of cost:
 *  - integers below 1e15 as integers;
 *  - m / 10^k with k <= 9 and |m| < 2^53 when that quotient is x: m and 10^k
 *    are exact doubles, so IEEE division rounds the exact decimal m / 10^k
 *    the way strtod does, and the k-decimal string reads back as x (measured
 *    values with a few decimals: no printf, no strtod);
 *  - else the 17 significant digits of %.16e (correctly rounded by the C
 *    library, so they always read back), shortened to 15 or 16 digits when
 *    strtod confirms that those read back too. */
char *series_put_double(char *p, double x)
{
    if (isnan(x) || isinf(x)) {
        const char *t = isnan(x) ? "nan" : x > 0 ? "inf" : "-inf";
        size_t n = strlen(t);
        memcpy(p, t, n);
        return p + n;
    }
    int neg = signbit(x) != 0;
    double ax = fabs(x);
    if (ax < 1e15 && ax == (double)(long long)ax && !(x == 0 && neg)) {
        if (neg) *p++ = '-';
        return put_uint(p, (unsigned long long)ax);
    }
#if FLT_EVAL_METHOD == 0
    if (ax >= 1e-4 && ax < 1e15) {
        static const double p10[10] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
        for (int k = 1; k <= 9; k++) {
            double y = nearbyint(ax * p10[k]);
            if (y >= 9007199254740992.0) break;
            if (y / p10[k] == ax) {
                char d[24];
                char *q = put_uint(d, (unsigned long long)y);
                int n = (int)(q - d);
                /* y = d * 10^0, so x = d * 10^-k: first digit at exponent n - 1 - k */
                return put_digits(p, neg, d, n, n - 1 - k, 17);
            }
        }
    }
#endif
    char e17[40];
    snprintf(e17, sizeof e17, "%.16e", ax); /* d.dddddddddddddddde[+-]XX */
    char d[18];
    d[0] = e17[0];
    memcpy(d + 1, e17 + 2, 16);
    int e = atoi(e17 + 19);
    for (int n = 15; n <= 16; n++) {
        /* round the 17 digits to n (half up; the check below catches any double rounding) */
        char r[18];
        memcpy(r, d, 17);
        int er = e;
        if (r[n] >= '5') {
            int i = n - 1;
            while (i >= 0 && r[i] == '9') r[i--] = '0';
            if (i >= 0) r[i]++;
            else {
                memmove(r + 1, r, (size_t)n - 1);
                r[0] = '1';
                er++;
            }
        }
        char *end = put_digits(p, neg, r, n, er, n);
        *end = '\0';
        if (strtod(p, NULL) == x) return end;
    }
    return put_digits(p, neg, d, 17, e, 17);
}

thx_status series_write_text(thx_ctx *ctx, const thx_series *s, const char *path)
{
    /* units are one word on their line; reject what could not be read back */
    const char *ustr[2] = {s->unit, s->time_unit}, *uname[2] = {"unit", "time_unit"};
    for (int k = 0; k < 2; k++)
        for (const char *c = ustr[k]; *c; c++)
            if ((unsigned char)*c <= ' ' || *c == '#' || *c == 127)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: %s \"%s\" has a blank, control character or '#' (a text series "
                                 "unit is one word)",
                                 path, uname[k], ustr[k]);
    size_t N = s->n_rows, M = s->n_frames;
    /* a row is at most M numbers of 24 characters, blanks and a newline; rows
     * are formatted in blocks of about 16 MB, in parallel, and written in order */
    if (M > (SIZE_MAX - 64) / 26) return thx_error(ctx, THX_ENOMEM, "%s: %zu frames: a text line too long", path, M);
    size_t row_cap = M * 26 + 64;
    size_t block = (16u << 20) / row_cap;
    block = block < 1 ? 1 : block > N ? N : block;
    char *line = thx_malloc(ctx, row_cap);
    char *rows = thx_malloc(ctx, block * row_cap);
    size_t *row_len = thx_malloc(ctx, block * sizeof *row_len);
    if (!line || !rows || !row_len) {
        free(line);
        free(rows);
        free(row_len);
        return THX_ENOMEM;
    }
    thx_atomic_file af; /* an existing file is replaced only when it is thorax's series (thorax/core/fileio.h) */
    thx_status st = thx_atomic_open_output(ctx, path, "thorax-series", 13, NULL, 0, &af);
    if (st != THX_OK) {
        free(line);
        free(rows);
        free(row_len);
        return st;
    }
    FILE *f = af.f;
    fprintf(f, "thorax-series 1\n");
    fprintf(f, "rows %zu\nframes %zu\n", N, M);
    if (s->unit[0]) fprintf(f, "unit %s\n", s->unit);
    if (s->time_unit[0]) fprintf(f, "time_unit %s\n", s->time_unit);
    else fprintf(f, "time_unit\n"); /* none: a missing line would mean ms */
    if (s->label[0]) {
        /* the label is the rest of its line: control characters become blanks,
         * leading and trailing blanks are not kept */
        char lab[sizeof s->label];
        size_t n = 0;
        for (const char *c = s->label; *c; c++) lab[n++] = ((unsigned char)*c < ' ' || *c == 127) ? ' ' : *c;
        while (n && lab[n - 1] == ' ') n--;
        size_t b = 0;
        while (b < n && lab[b] == ' ') b++;
        if (b < n) fprintf(f, "label %.*s\n", (int)(n - b), lab + b);
    }
    /* a uniform axis is written as t0 + dt when t0 + f dt gives every time
     * exactly; two candidates for dt: the mean step and the first step */
    int uniform = 0;
    double dt = 0;
    for (int c = 0; c < 2 && !uniform && M >= 2; c++) {
        dt = c == 0 ? (s->time[M - 1] - s->time[0]) / (double)(M - 1) : s->time[1] - s->time[0];
        uniform = 1;
        for (size_t k = 0; k < M && uniform; k++) uniform = uniform_time(s->time[0], dt, k) == s->time[k];
    }
    if (uniform) {
        char *p = line;
        p = series_put_double(p + sprintf(p, "t0 "), s->time[0]);
        p = series_put_double(p + sprintf(p, "\ndt "), dt);
        *p++ = '\n';
        fwrite(line, 1, (size_t)(p - line), f);
    } else {
        char *p = line + sprintf(line, "time");
        for (size_t k = 0; k < M; k++) {
            *p++ = ' ';
            p = series_put_double(p, s->time[k]);
        }
        *p++ = '\n';
        fwrite(line, 1, (size_t)(p - line), f);
    }
    for (size_t r0 = 0; r0 < N; r0 += block) {
        long nb = (long)(N - r0 < block ? N - r0 : block);
#pragma omp parallel for schedule(dynamic, 1) if (nb * M > 50000)
        for (long i = 0; i < nb; i++) {
            char *p = rows + (size_t)i * row_cap;
            const double *v = s->v + r0 + (size_t)i;
            for (size_t k = 0; k < M; k++) {
                if (k) *p++ = ' ';
                p = series_put_double(p, v[k * N]);
            }
            *p++ = '\n';
            row_len[i] = (size_t)(p - (rows + (size_t)i * row_cap));
        }
        for (long i = 0; i < nb; i++) fwrite(rows + (size_t)i * row_cap, 1, row_len[i], f);
    }
    fprintf(f, "end\n");
    free(line);
    free(rows);
    free(row_len);
    return thx_atomic_commit(ctx, &af);
}

/* ------------------------------------------------------------- text in */

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next token of a keyword line, NUL-terminated in place; NULL at the end
 * of the line or at a '#' (the rest is a comment). */
static char *next_token(char **cur)
{
    char *p = *cur;
    while (is_blank(*p)) p++;
    if (!*p || *p == '#') {
        *cur = p;
        return NULL;
    }
    char *t = p;
    while (*p && !is_blank(*p) && *p != '#') p++;
    if (*p == '#') *p = '\0'; /* the comment goes too */
    else if (*p) *p++ = '\0';
    *cur = p;
    return t;
}

/* strtod, refusing a finite decimal too large for a double ("1e999"), which
 * strtod would silently make an infinity; "inf" and "nan" are accepted. */
static double parse_double(const char *t, char **end)
{
    errno = 0;
    double x = strtod(t, end);
    if (errno == ERANGE && isinf(x)) *end = (char *)t;
    return x;
}

static int parse_number(const char *t, double *x)
{
    char *end;
    *x = parse_double(t, &end);
    return end != t && *end == '\0';
}

/* A positive decimal integer (digits only, overflow-checked). */
static int parse_count(const char *t, size_t *n)
{
    uint64_t v;
    if (thx_parse_uint(t, 0, SIZE_MAX, &v) != 0 || v == 0) return 0;
    *n = (size_t)v;
    return 1;
}

typedef struct {
    thx_ctx *ctx;
    const char *path;
    size_t line;
    unsigned long long size;   /* the file's size in bytes */
    unsigned long long offset; /* byte offset of the current line */
    /* header */
    size_t rows, frames, rows_line, frames_line;
    size_t unit_line, time_unit_line, label_line, t0_line, dt_line, time_line;
    char unit[32], time_unit[16], label[128];
    double t0, dt;
    double *times;
    size_t n_times, cap_times;
    /* values */
    thx_series *s;
    size_t r; /* rows read */
} text_reader;

static thx_status text_fail(text_reader *tr, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status text_fail(text_reader *tr, const char *fmt, ...)
{
    char msg[1536];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(tr->ctx, THX_EINPUT, "%s:%zu: %s", tr->path, tr->line, msg);
}

/* `unit`, `time_unit`: zero or one word, at most cap - 1 bytes. */
static thx_status text_word(text_reader *tr, const char *kw, char **cur, char *dst, size_t cap, size_t *seen)
{
    if (*seen) return text_fail(tr, "'%s' given twice (first on line %zu)", kw, *seen);
    *seen = tr->line;
    char *w = next_token(cur);
    if (w && next_token(cur)) return text_fail(tr, "'%s' takes one word", kw);
    if (w && strlen(w) >= cap) return text_fail(tr, "%s '%s' is longer than %zu bytes", kw, w, cap - 1);
    snprintf(dst, cap, "%s", w ? w : "");
    return THX_OK;
}

static thx_status text_header_line(text_reader *tr, const char *kw, char *cur)
{
    size_t *seen = NULL;
    if (!strcmp(kw, "rows") || !strcmp(kw, "frames")) {
        int is_rows = kw[0] == 'r';
        seen = is_rows ? &tr->rows_line : &tr->frames_line;
        if (*seen) return text_fail(tr, "'%s' given twice (first on line %zu)", kw, *seen);
        char *t = next_token(&cur);
        size_t n;
        if (!parse_count(t, &n) || next_token(&cur))
            return text_fail(tr, "expected '%s N' with N a positive integer", kw);
        /* a value takes at least 2 bytes (a digit and a blank or newline): refuse a
         * count the file cannot hold now, before anything is allocated */
        if (n > tr->size / 2)
            return text_fail(tr, "'%s %zu': a file of %llu bytes cannot hold %zu %s (a value takes at least 2 bytes)",
                             kw, n, tr->size, n, is_rows ? "value rows" : "values per row");
        *seen = tr->line;
        *(is_rows ? &tr->rows : &tr->frames) = n;
        return THX_OK;
    }
    if (!strcmp(kw, "unit")) return text_word(tr, kw, &cur, tr->unit, sizeof tr->unit, &tr->unit_line);
    if (!strcmp(kw, "time_unit"))
        return text_word(tr, kw, &cur, tr->time_unit, sizeof tr->time_unit, &tr->time_unit_line);
    if (!strcmp(kw, "t0") || !strcmp(kw, "dt")) {
        int is_dt = kw[0] == 'd';
        seen = is_dt ? &tr->dt_line : &tr->t0_line;
        if (*seen) return text_fail(tr, "'%s' given twice (first on line %zu)", kw, *seen);
        char *t = next_token(&cur);
        double x;
        if (!t || !parse_number(t, &x) || next_token(&cur) || !isfinite(x) || (is_dt && !(x > 0)))
            return text_fail(tr, "expected '%s T' with T a finite number%s", kw, is_dt ? " > 0" : "");
        *seen = tr->line;
        *(is_dt ? &tr->dt : &tr->t0) = x;
        return THX_OK;
    }
    if (!strcmp(kw, "time")) {
        if (!tr->time_line) tr->time_line = tr->line;
        char *t;
        int any = 0;
        while ((t = next_token(&cur))) {
            double x;
            if (!parse_number(t, &x) || !isfinite(x))
                return text_fail(tr, "time %zu: '%s' is not a finite number", tr->n_times + 1, t);
            if (tr->n_times && !(x > tr->times[tr->n_times - 1]))
                return text_fail(tr, "time %zu (%s) is not after time %zu (%.17g): times must increase",
                                 tr->n_times + 1, t, tr->n_times, tr->times[tr->n_times - 1]);
            if (thx_grow(tr->ctx, (void **)&tr->times, &tr->cap_times, tr->n_times + 1, sizeof *tr->times))
                return THX_ENOMEM;
            tr->times[tr->n_times++] = x;
            any = 1;
        }
        if (!any) return text_fail(tr, "'time' needs at least one number");
        return THX_OK;
    }
    return text_fail(tr, "unknown keyword '%s' (rows, frames, unit, time_unit, label, time, t0, dt, "
                         "then the value rows and 'end')",
                     kw);
}

/* Called at the first value row: checks the header and makes the series. */
static thx_status text_begin_values(text_reader *tr)
{
    if (!tr->rows_line) return text_fail(tr, "value row before 'rows N'");
    if (!tr->frames_line) return text_fail(tr, "value row before 'frames M'");
    if (tr->time_line && (tr->dt_line || tr->t0_line))
        return thx_error(tr->ctx, THX_EINPUT, "%s:%zu: 'time' and '%s' (line %zu) both give the time axis",
                         tr->path, tr->time_line, tr->dt_line ? "dt" : "t0", tr->dt_line ? tr->dt_line : tr->t0_line);
    if (tr->t0_line && !tr->dt_line)
        return thx_error(tr->ctx, THX_EINPUT, "%s:%zu: 't0' without 'dt'", tr->path, tr->t0_line);
    if (tr->time_line && tr->n_times != tr->frames)
        return thx_error(tr->ctx, THX_EINPUT, "%s:%zu: 'time' gives %zu values for %zu frames (line %zu)", tr->path,
                         tr->time_line, tr->n_times, tr->frames, tr->frames_line);
    /* the rows x frames values, at least 2 bytes each, must fit in the file (the
     * header is not subtracted: a file cut short gets the more telling message
     * of the row where it ends) */
    if (tr->rows > tr->size / 2 / tr->frames)
        return text_fail(tr, "'rows %zu' (line %zu) x 'frames %zu' (line %zu) values cannot be in a file of %llu "
                             "bytes (a value takes at least 2 bytes): wrong sizes, or a truncated file",
                         tr->rows, tr->rows_line, tr->frames, tr->frames_line, tr->size);
    thx_status st = thx_series_create(tr->ctx, tr->rows, tr->frames, &tr->s);
    if (st != THX_OK) return st == THX_EINPUT ? text_fail(tr, "%s", thx_ctx_message(tr->ctx)) : st;
    thx_series *s = tr->s;
    for (size_t f = 0; f < s->n_frames; f++) {
        if (tr->time_line) s->time[f] = tr->times[f];
        else if (tr->dt_line) s->time[f] = uniform_time(tr->t0, tr->dt, f);
    }
    snprintf(s->unit, sizeof s->unit, "%s", tr->unit);
    if (tr->time_unit_line) snprintf(s->time_unit, sizeof s->time_unit, "%s", tr->time_unit);
    snprintf(s->label, sizeof s->label, "%s", tr->label);
    if (tr->dt_line) {
        /* t0 + f dt must still increase in floating point */
        for (size_t f = 1; f < s->n_frames; f++)
            if (!(s->time[f] > s->time[f - 1]) || !isfinite(s->time[f]))
                return thx_error(tr->ctx, THX_EINPUT,
                                 "%s:%zu: 'dt %.17g' is too small for t0 = %.17g: frames %zu and %zu get time %.17g",
                                 tr->path, tr->dt_line, tr->dt, tr->t0, f, f + 1, s->time[f]);
    }
    return THX_OK;
}

/* One value row: exactly `frames` numbers, then nothing but a comment. */
static thx_status text_value_row(text_reader *tr, char *p)
{
    thx_series *s = tr->s;
    if (tr->r == s->n_rows)
        return text_fail(tr, "more value rows than 'rows %zu' (line %zu), or a missing 'end'", s->n_rows,
                         tr->rows_line);
    size_t N = s->n_rows, M = s->n_frames, r = tr->r;
    double *v = s->v + r;
    for (size_t f = 0; f < M; f++) {
        while (is_blank(*p)) p++;
        if (!*p || *p == '#')
            return text_fail(tr, "row %zu has %zu value%s, expected %zu (frames %zu, line %zu)", r + 1, f,
                             f == 1 ? "" : "s", M, M, tr->frames_line);
        char *end;
        double x = parse_double(p, &end);
        if (end == p || !(is_blank(*end) || !*end || *end == '#')) {
            size_t n = 0;
            while (p[n] && !is_blank(p[n]) && p[n] != '#') n++;
            errno = 0;
            char *e2;
            (void)strtod(p, &e2);
            return text_fail(tr, "row %zu, frame %zu: '%.*s' is %s", r + 1, f + 1, (int)(n > 40 ? 40 : n), p,
                             errno == ERANGE && e2 != p ? "too large for a double" : "not a number");
        }
        v[f * N] = x;
        p = end;
    }
    while (is_blank(*p)) p++;
    if (*p && *p != '#') {
        size_t extra = 0;
        char *q = p;
        while (next_token(&q)) extra++;
        return text_fail(tr, "row %zu has %zu values, expected %zu (frames %zu, line %zu)", r + 1, M + extra, M, M,
                         tr->frames_line);
    }
    tr->r++;
    return THX_OK;
}

thx_status series_read_text(thx_ctx *ctx, const char *path, thx_series **out)
{
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    setvbuf(f, NULL, _IOFBF, 1 << 20);
    text_reader tr;
    memset(&tr, 0, sizeof tr);
    tr.ctx = ctx;
    tr.path = path;
    struct stat sb;
    if (fstat(fileno(f), &sb) != 0) {
        fclose(f);
        return thx_error(ctx, THX_EIO, "%s: cannot stat: %s", path, strerror(errno));
    }
    tr.size = (unsigned long long)sb.st_size;
    thx_status st = THX_OK;
    char *buf = NULL;
    size_t cap = 0;
    int seen_header = 0, seen_end = 0;
    ssize_t len;
    unsigned long long next = 0;
    while ((len = getline(&buf, &cap, f)) >= 0) {
        tr.line++;
        tr.offset = next;
        next += (unsigned long long)len;
        const char *nul = memchr(buf, '\0', (size_t)len);
        if (nul) {
            st = text_fail(&tr, "NUL byte at byte offset %llu (a text file holds none: a binary file, or a "
                                "damaged one?)",
                           tr.offset + (unsigned long long)(nul - buf));
            goto done;
        }
        if (len && buf[len - 1] == '\n') buf[--len] = '\0';
        if (len && buf[len - 1] == '\r') buf[--len] = '\0';
        char *p = buf;
        while (is_blank(*p)) p++;
        if (!*p || *p == '#') continue;
        if (seen_end) {
            st = text_fail(&tr, "text after 'end'");
            goto done;
        }
        if (!seen_header) {
            char *cur = p;
            char *kw = next_token(&cur), *ver = next_token(&cur);
            if (!kw || strcmp(kw, "thorax-series") != 0) {
                st = text_fail(&tr, "not a thorax series file (expected 'thorax-series 1' as the first line)");
                goto done;
            }
            if (!ver || strcmp(ver, "1") != 0 || next_token(&cur)) {
                st = text_fail(&tr, "unsupported series file version '%s' (this reader knows 'thorax-series 1')",
                               ver ? ver : "");
                goto done;
            }
            seen_header = 1;
            continue;
        }
        /* `label`: the rest of the line, verbatim ('#' included) */
        if (!strncmp(p, "label", 5) && (!p[5] || is_blank(p[5]))) {
            if (tr.s) {
                st = text_fail(&tr, "'label' after the value rows began");
                goto done;
            }
            if (tr.label_line) {
                st = text_fail(&tr, "'label' given twice (first on line %zu)", tr.label_line);
                goto done;
            }
            char *q = p + 5;
            while (is_blank(*q)) q++;
            size_t n = strlen(q);
            while (n && is_blank(q[n - 1])) n--;
            if (n >= sizeof tr.label) {
                st = text_fail(&tr, "label is %zu bytes, longer than %zu", n, sizeof tr.label - 1);
                goto done;
            }
            memcpy(tr.label, q, n);
            tr.label[n] = '\0';
            tr.label_line = tr.line;
            continue;
        }
        /* a value row starts with a number (nan and inf included); "1,2" is a
         * value row too, whose first value is then reported as not a number */
        char *end;
        (void)strtod(p, &end);
        if (end != p) {
            if (!tr.s && (st = text_begin_values(&tr)) != THX_OK) goto done;
            if ((st = text_value_row(&tr, p)) != THX_OK) goto done;
            continue;
        }
        char *cur = p;
        char *kw = next_token(&cur);
        if (!strcmp(kw, "end")) {
            if (next_token(&cur)) {
                st = text_fail(&tr, "'end' takes nothing after it");
                goto done;
            }
            if (!tr.s) {
                st = text_fail(&tr, "'end' before any value row");
                goto done;
            }
            if (tr.r < tr.s->n_rows) {
                st = text_fail(&tr, "'end' after %zu of %zu value rows ('rows %zu', line %zu)", tr.r, tr.s->n_rows,
                               tr.s->n_rows, tr.rows_line);
                goto done;
            }
            seen_end = 1;
            continue;
        }
        if (tr.s) {
            static const char *const kws[] = {"rows", "frames", "unit", "time_unit", "t0", "dt", "time"};
            for (size_t k = 0; k < sizeof kws / sizeof kws[0]; k++)
                if (!strcmp(kw, kws[k])) {
                    st = text_fail(&tr, "'%s' after the value rows began", kw);
                    goto done;
                }
            if (tr.r == tr.s->n_rows)
                st = text_fail(&tr, "'%.40s' where 'end' was expected after %zu value rows", kw, tr.r);
            else
                st = text_fail(&tr, "row %zu, frame 1: '%.40s' is not a number", tr.r + 1, kw);
            goto done;
        }
        if ((st = text_header_line(&tr, kw, cur)) != THX_OK) goto done;
    }
    if (ferror(f)) {
        st = thx_error(ctx, THX_EIO, "%s: read error: %s", path, strerror(errno));
        goto done;
    }
    if (!seen_header) {
        st = thx_error(ctx, THX_EINPUT, "%s: empty file (expected 'thorax-series 1' as the first line)", path);
        goto done;
    }
    if (!seen_end) {
        if (!tr.s)
            st = text_fail(&tr, "truncated file: no value rows and no 'end' line");
        else if (tr.r < tr.s->n_rows)
            st = text_fail(&tr, "truncated file: %zu of %zu value rows ('rows %zu', line %zu) and no 'end' line",
                           tr.r, tr.s->n_rows, tr.s->n_rows, tr.rows_line);
        else
            st = text_fail(&tr, "truncated file (no 'end' line)");
        goto done;
    }
    st = thx_series_validate(ctx, tr.s, path);
done:
    free(buf);
    free(tr.times);
    fclose(f);
    if (st != THX_OK) thx_series_destroy(&tr.s);
    *out = tr.s;
    return st;
}

