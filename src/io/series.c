/*
 * Time series files: text, raw binary and MATLAB .mat (see thorax/series.h;
 * docs/formats.md, "Time series", is the specification).
 *
 * Decisions recorded here:
 *
 *  - Every reader ends with the same checks as the writers start with
 *    (check_series): at least one row and one frame, a finite, strictly
 *    increasing time axis, NUL-terminated strings. So whatever is written
 *    reads back, and whatever is read can be written in any format.
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
 *
 *  - Raw files are written and read with explicit little-endian byte order;
 *    on a little-endian host the arrays go through fwrite/fread directly. The
 *    file size must equal the header's sizes exactly, so truncation and
 *    trailing bytes are both caught before anything is allocated.
 *
 *  - .mat files go through libmatio as MATLAB 5 files without compression
 *    (scipy.io.loadmat and every MATLAB since 5 read them; compression would
 *    cost more time than the file size is worth here), with a fixed header
 *    text and no date, so the same series gives byte-identical files. Strings
 *    are written as UTF-16 code units (miUINT16), MATLAB's own char
 *    encoding: libmatio writes UTF-8 char arrays with one byte per
 *    character, which would cut multi-byte characters. On reading, UTF-8,
 *    UTF-16 and 8-bit (Latin-1) char data are accepted and stored as UTF-8.
 *    libmatio prints nothing unless someone calls Mat_LogInit, which the
 *    library never does; its failures are reported in our own words.
 *
 *  - Messages count rows and frames from 1, like the lines of a text file.
 */
#include "thorax/series.h"

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

#include "thorax/fileio.h"

#define RAW_MAGIC "THXSER01"
#define RAW_HEADER 200 /* 8 magic + 8 rows + 8 frames + 32 unit + 16 time_unit + 128 label */

/* ------------------------------------------------------------ the object */

thx_status thx_series_create(thx_ctx *ctx, size_t n_rows, size_t n_frames, thx_series **out)
{
    *out = NULL;
    if (n_frames && n_rows > SIZE_MAX / sizeof(double) / n_frames)
        return thx_error(ctx, THX_EINPUT, "a series of %zu rows x %zu frames is too large", n_rows, n_frames);
    thx_series *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    s->v = thx_calloc(ctx, n_rows * n_frames, sizeof *s->v);
    s->time = thx_malloc(ctx, (n_frames ? n_frames : 1) * sizeof *s->time);
    if (!s->v || !s->time) {
        thx_series_destroy(&s);
        return THX_ENOMEM;
    }
    s->n_rows = n_rows;
    s->n_frames = n_frames;
    for (size_t f = 0; f < n_frames; f++) s->time[f] = (double)f;
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    *out = s;
    return THX_OK;
}

void thx_series_destroy(thx_series **s)
{
    if (!s || !*s) return;
    free((*s)->v);
    free((*s)->time);
    free(*s);
    *s = NULL;
}

size_t thx_series_find_nonfinite(const thx_series *s, size_t *row, size_t *frame)
{
    size_t n = s->n_rows * s->n_frames, count = 0, first = 0;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(s->v[i])) {
            if (count++ == 0) first = i;
        }
    if (count && s->n_rows) {
        if (row) *row = first % s->n_rows;
        if (frame) *frame = first / s->n_rows;
    }
    return count;
}

int thx_series_format_parse(const char *name, thx_series_format *fmt)
{
    static const struct { const char *name; thx_series_format f; } tab[] = {
        {"auto", THX_SERIES_AUTO}, {"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
        {"pot", THX_SERIES_POT}};
    if (!name) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcmp(name, tab[i].name) == 0) {
            *fmt = tab[i].f;
            return 0;
        }
    return -1;
}

static const char *format_name(thx_series_format f)
{
    return f == THX_SERIES_TEXT ? "text" : f == THX_SERIES_RAW ? "raw" : f == THX_SERIES_MAT ? "mat" : f == THX_SERIES_POT ? "pot" : "auto";
}

/* The time axis of `dt` files: one expression, shared by writer and reader so
 * that the writer's "is this axis uniform?" test predicts the reader's bits. */
static double uniform_time(double t0, double dt, size_t f) { return t0 + (double)f * dt; }

/* What every series must satisfy to be written, and satisfies once read. */
static thx_status check_series(thx_ctx *ctx, const thx_series *s, const char *path)
{
    if (!s || !s->v || !s->time) return thx_error(ctx, THX_EINPUT, "%s: no series (NULL values or time)", path);
    if (s->n_rows == 0 || s->n_frames == 0)
        return thx_error(ctx, THX_EINPUT, "%s: empty series (%zu rows x %zu frames; at least 1 x 1 needed)", path,
                         s->n_rows, s->n_frames);
    if (!memchr(s->unit, '\0', sizeof s->unit) || !memchr(s->time_unit, '\0', sizeof s->time_unit) ||
        !memchr(s->label, '\0', sizeof s->label))
        return thx_error(ctx, THX_EINPUT, "%s: unit, time_unit or label is not NUL-terminated", path);
    for (size_t f = 0; f < s->n_frames; f++) {
        if (!isfinite(s->time[f]))
            return thx_error(ctx, THX_EINPUT, "%s: time of frame %zu is %g (times must be finite)", path, f + 1,
                             s->time[f]);
        if (f > 0 && !(s->time[f] > s->time[f - 1]))
            return thx_error(ctx, THX_EINPUT,
                             "%s: time of frame %zu (%.17g) is not after that of frame %zu (%.17g): "
                             "times must increase",
                             path, f + 1, s->time[f], f, s->time[f - 1]);
    }
    return THX_OK;
}

/* ------------------------------------------------------ formats by name */

/* The extension of the last path component (after its last '.'), or "". */
static const char *extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return (dot && dot != base) ? dot + 1 : "";
}

static thx_series_format format_of_extension(const char *path)
{
    const char *e = extension(path);
    if (!strcasecmp(e, "txt") || !strcasecmp(e, "dat")) return THX_SERIES_TEXT;
    if (!strcasecmp(e, "raw")) return THX_SERIES_RAW;
    if (!strcasecmp(e, "mat")) return THX_SERIES_MAT;
    if (!strcasecmp(e, "pot")) return THX_SERIES_POT;
    return THX_SERIES_AUTO;
}

int thx_series_output_format(const char *format_name, const char *path, thx_series_format *fmt)
{
    thx_series_format f = THX_SERIES_AUTO;
    if (format_name) {
        if (thx_series_format_parse(format_name, &f) != 0) return -1;
    } else {
        f = format_of_extension(path);
    }
    if (f == THX_SERIES_AUTO || f == THX_SERIES_POT) return -1;
    *fmt = f;
    return 0;
}

/* The format a file's first bytes announce, or THX_SERIES_AUTO. */
static thx_series_format format_of_content(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return THX_SERIES_AUTO;
    char b[512];
    size_t n = fread(b, 1, sizeof b - 1, f);
    fclose(f);
    b[n] = '\0';
    if (n >= 6 && memcmp(b, "THXSER", 6) == 0) return THX_SERIES_RAW;
    if (n >= 6 && memcmp(b, "MATLAB", 6) == 0) return THX_SERIES_MAT; /* v5, v7 and v7.3 headers */
    /* text: skip blank and comment lines */
    size_t i = 0;
    while (i < n) {
        while (i < n && (b[i] == ' ' || b[i] == '\t' || b[i] == '\r' || b[i] == '\n')) i++;
        if (i < n && b[i] == '#') {
            while (i < n && b[i] != '\n') i++;
            continue;
        }
        break;
    }
    if (n - i >= 13 && memcmp(b + i, "thorax-series", 13) == 0) return THX_SERIES_TEXT;
    return THX_SERIES_AUTO;
}

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
static char *put_double(char *p, double x)
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

static thx_status write_text(thx_ctx *ctx, const thx_series *s, const char *path)
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
    thx_atomic_file af;
    thx_status st = thx_atomic_open(ctx, path, &af);
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
        p = put_double(p + sprintf(p, "t0 "), s->time[0]);
        p = put_double(p + sprintf(p, "\ndt "), dt);
        *p++ = '\n';
        fwrite(line, 1, (size_t)(p - line), f);
    } else {
        char *p = line + sprintf(line, "time");
        for (size_t k = 0; k < M; k++) {
            *p++ = ' ';
            p = put_double(p, s->time[k]);
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
                p = put_double(p, v[k * N]);
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

static int parse_number(const char *t, double *x)
{
    char *end;
    *x = strtod(t, &end);
    return end != t && *end == '\0';
}

/* A positive decimal integer (digits only). */
static int parse_count(const char *t, size_t *n)
{
    if (!t || !*t) return 0;
    for (const char *c = t; *c; c++)
        if (*c < '0' || *c > '9') return 0;
    errno = 0;
    unsigned long long v = strtoull(t, NULL, 10);
    if (errno || v == 0 || v > SIZE_MAX) return 0;
    *n = (size_t)v;
    return 1;
}

typedef struct {
    thx_ctx *ctx;
    const char *path;
    size_t line;
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
        double x = strtod(p, &end);
        if (end == p || !(is_blank(*end) || !*end || *end == '#')) {
            size_t n = 0;
            while (p[n] && !is_blank(p[n]) && p[n] != '#') n++;
            return text_fail(tr, "row %zu, frame %zu: '%.*s' is not a number", r + 1, f + 1, (int)(n > 40 ? 40 : n), p);
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

static thx_status read_text(thx_ctx *ctx, const char *path, thx_series **out)
{
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    setvbuf(f, NULL, _IOFBF, 1 << 20);
    text_reader tr;
    memset(&tr, 0, sizeof tr);
    tr.ctx = ctx;
    tr.path = path;
    thx_status st = THX_OK;
    char *buf = NULL;
    size_t cap = 0;
    int seen_header = 0, seen_end = 0;
    ssize_t len;
    while ((len = getline(&buf, &cap, f)) >= 0) {
        tr.line++;
        if (memchr(buf, '\0', (size_t)len)) {
            st = text_fail(&tr, "NUL byte in a text file (is this a binary file?)");
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
    st = check_series(ctx, tr.s, path);
done:
    free(buf);
    free(tr.times);
    fclose(f);
    if (st != THX_OK) thx_series_destroy(&tr.s);
    *out = tr.s;
    return st;
}

/* ------------------------------------------------------------- raw */

static void put_u64le(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get_u64le(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

/* Writes n doubles as little-endian float64. */
static int fwrite_f64le(const double *x, size_t n, FILE *f)
{
    if (host_is_little_endian()) return fwrite(x, sizeof *x, n, f) == n;
    unsigned char buf[8 * 1024];
    for (size_t i = 0; i < n;) {
        size_t k = 0;
        for (; k < 1024 && i < n; k++, i++) {
            uint64_t u;
            memcpy(&u, &x[i], 8);
            put_u64le(buf + 8 * k, u);
        }
        if (fwrite(buf, 8, k, f) != k) return 0;
    }
    return 1;
}

/* Reads n little-endian float64 values. */
static int fread_f64le(double *x, size_t n, FILE *f)
{
    if (fread(x, sizeof *x, n, f) != n) return 0;
    if (!host_is_little_endian())
        for (size_t i = 0; i < n; i++) {
            unsigned char b[8];
            memcpy(b, &x[i], 8);
            uint64_t u = get_u64le(b);
            memcpy(&x[i], &u, 8);
        }
    return 1;
}

static thx_status write_raw(thx_ctx *ctx, const thx_series *s, const char *path)
{
    unsigned char h[RAW_HEADER];
    memset(h, 0, sizeof h);
    memcpy(h, RAW_MAGIC, 8);
    put_u64le(h + 8, (uint64_t)s->n_rows);
    put_u64le(h + 16, (uint64_t)s->n_frames);
    memcpy(h + 24, s->unit, strlen(s->unit));           /* < 32: checked NUL-terminated */
    memcpy(h + 56, s->time_unit, strlen(s->time_unit)); /* < 16 */
    memcpy(h + 72, s->label, strlen(s->label));         /* < 128 */
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    if (fwrite(h, 1, sizeof h, af.f) != sizeof h || !fwrite_f64le(s->time, s->n_frames, af.f) ||
        !fwrite_f64le(s->v, s->n_rows * s->n_frames, af.f)) {
        int e = errno;
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: write failed: %s", path, strerror(e));
    }
    return thx_atomic_commit(ctx, &af);
}

/* Copies a NUL-terminated header field, or fails. */
static thx_status raw_string(thx_ctx *ctx, const char *path, const unsigned char *h, size_t off, size_t size,
                             const char *name, char *dst)
{
    if (!memchr(h + off, '\0', size))
        return thx_error(ctx, THX_EINPUT, "%s: the %s field (bytes %zu-%zu) has no terminating NUL byte", path, name,
                         off, off + size - 1);
    memcpy(dst, h + off, size);
    return THX_OK;
}

static thx_status read_raw(thx_ctx *ctx, const char *path, thx_series **out)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    thx_status st = THX_OK;
    thx_series *s = NULL;
    struct stat sb;
    if (fstat(fileno(f), &sb) != 0) {
        st = thx_error(ctx, THX_EIO, "%s: cannot stat: %s", path, strerror(errno));
        goto done;
    }
    unsigned long long size = (unsigned long long)sb.st_size;
    unsigned char h[RAW_HEADER];
    size_t got = fread(h, 1, sizeof h, f);
    if (memcmp(h, "THXSER", got < 6 ? got : 6) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: not a thorax raw series (the file does not start with \"%s\")", path,
                       RAW_MAGIC);
        goto done;
    }
    if (got >= 8 && memcmp(h, RAW_MAGIC, 8) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: raw series version '%c%c' is not supported (this reader knows \"%s\")",
                       path, h[6] >= ' ' && h[6] < 127 ? h[6] : '?', h[7] >= ' ' && h[7] < 127 ? h[7] : '?',
                       RAW_MAGIC);
        goto done;
    }
    if (got < sizeof h) {
        st = thx_error(ctx, THX_EINPUT, "%s: truncated: %llu bytes, shorter than the %d-byte raw series header", path,
                       size, RAW_HEADER);
        goto done;
    }
    uint64_t rows = get_u64le(h + 8), frames = get_u64le(h + 16);
    if (rows == 0 || frames == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: empty series in the header (%llu rows x %llu frames)", path,
                       (unsigned long long)rows, (unsigned long long)frames);
        goto done;
    }
    /* expected size = 200 + 8 frames (rows + 1), without overflow */
    uint64_t lim = (UINT64_MAX - RAW_HEADER) / 8;
    if (rows >= lim || frames > lim / (rows + 1) || rows > SIZE_MAX || frames > SIZE_MAX) {
        st = thx_error(ctx, THX_EINPUT, "%s: impossible sizes in the header (%llu rows x %llu frames)", path,
                       (unsigned long long)rows, (unsigned long long)frames);
        goto done;
    }
    uint64_t want = RAW_HEADER + 8 * frames * (rows + 1);
    if (size != want) {
        st = thx_error(ctx, THX_EINPUT,
                       "%s: %s: %llu bytes, but %llu rows x %llu frames take %llu (header %d + 8 x frames x "
                       "(rows + 1))",
                       path, size < want ? "truncated" : "trailing bytes", size, (unsigned long long)rows,
                       (unsigned long long)frames, (unsigned long long)want, RAW_HEADER);
        goto done;
    }
    char unit[32] = "", time_unit[16] = "", label[128] = "";
    if ((st = raw_string(ctx, path, h, 24, 32, "unit", unit)) || (st = raw_string(ctx, path, h, 56, 16, "time_unit", time_unit)) ||
        (st = raw_string(ctx, path, h, 72, 128, "label", label)))
        goto done;
    if ((st = thx_series_create(ctx, (size_t)rows, (size_t)frames, &s)) != THX_OK) goto done;
    memcpy(s->unit, unit, sizeof unit);
    memcpy(s->time_unit, time_unit, sizeof time_unit);
    memcpy(s->label, label, sizeof label);
    if (!fread_f64le(s->time, s->n_frames, f) || !fread_f64le(s->v, s->n_rows * s->n_frames, f)) {
        st = thx_error(ctx, THX_EIO, "%s: read error (file changed while reading?)", path);
        goto done;
    }
    st = check_series(ctx, s, path);
done:
    fclose(f);
    if (st != THX_OK) thx_series_destroy(&s);
    *out = s;
    return st;
}

/* ------------------------------------------------------------- MATLAB */

#define MAT_HEADER_TEXT "MATLAB 5.0 MAT-file, Platform: any, Created by: thorax (libmatio)"

/* The code point of the UTF-8 sequence at p and its length in *len, or -1
 * (with *len = 1) for a byte that does not start a valid sequence. */
static long utf8_decode(const unsigned char *p, int *len)
{
    *len = 1;
    int n;
    uint32_t c;
    if (p[0] < 0x80) return p[0];
    if (p[0] >= 0xC2 && p[0] < 0xE0) n = 2, c = p[0] & 0x1Fu;
    else if (p[0] >= 0xE0 && p[0] < 0xF0) n = 3, c = p[0] & 0x0Fu;
    else if (p[0] >= 0xF0 && p[0] < 0xF5) n = 4, c = p[0] & 0x07u;
    else return -1;
    for (int i = 1; i < n; i++) {
        if ((p[i] & 0xC0) != 0x80) return -1; /* also stops at the NUL */
        c = (c << 6) | (p[i] & 0x3Fu);
    }
    static const uint32_t least[5] = {0, 0, 0x80, 0x800, 0x10000}; /* no overlong forms */
    if (c < least[n] || c > 0x10FFFF || (c >= 0xD800 && c < 0xE000)) return -1;
    *len = n;
    return (long)c;
}

/* UTF-8 to UTF-16 code units; a byte that is not valid UTF-8 is taken as
 * Latin-1. Returns the count (at most strlen(s)). */
static size_t utf8_to_utf16(const char *s, uint16_t *w)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t n = 0;
    while (*p) {
        int len;
        long c = utf8_decode(p, &len);
        if (c < 0) c = *p;
        p += len;
        if (c >= 0x10000) {
            c -= 0x10000;
            w[n++] = (uint16_t)(0xD800 + (c >> 10));
            w[n++] = (uint16_t)(0xDC00 + (c & 0x3FF));
        } else {
            w[n++] = (uint16_t)c;
        }
    }
    return n;
}

/* Appends code point c as UTF-8 if it fits in cap bytes (NUL excluded); 0 if not. */
static int put_utf8(char *dst, size_t *n, size_t cap, uint32_t c)
{
    unsigned char b[4];
    size_t k = c < 0x80 ? 1 : c < 0x800 ? 2 : c < 0x10000 ? 3 : 4;
    if (*n + k > cap) return 0;
    if (k == 1) {
        b[0] = (unsigned char)c;
    } else {
        static const unsigned char lead[5] = {0, 0, 0xC0, 0xE0, 0xF0};
        for (size_t i = k - 1; i > 0; i--, c >>= 6) b[i] = (unsigned char)(0x80 | (c & 0x3F));
        b[0] = (unsigned char)(lead[k] | c);
    }
    memcpy(dst + *n, b, k);
    *n += k;
    return 1;
}

static thx_status mat_write_string(mat_t *mat, const char *name, const char *str, uint16_t *w)
{
    size_t n = utf8_to_utf16(str, w);
    size_t dims[2] = {n ? 1 : 0, n};
    matvar_t *v = Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UINT16, 2, dims, n ? w : NULL, MAT_F_DONT_COPY_DATA);
    if (!v) return THX_EIO;
    int bad = Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
    Mat_VarFree(v);
    return bad ? THX_EIO : THX_OK;
}

static thx_status write_mat(thx_ctx *ctx, const thx_series *s, const char *path)
{
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    /* libmatio opens files by name: keep the temporary name, write through it */
    fclose(af.f);
    af.f = NULL;
    errno = 0;
    mat_t *mat = Mat_CreateVer(af.tmp, MAT_HEADER_TEXT, MAT_FT_MAT5);
    if (!mat) {
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: libmatio cannot create the file", path);
    }
    const char *what = "potvals";
    uint16_t w[2 * sizeof s->label];
    size_t dims[2] = {s->n_rows, s->n_frames};
    matvar_t *v = Mat_VarCreate("potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, s->v, MAT_F_DONT_COPY_DATA);
    int bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
    Mat_VarFree(v);
    if (!bad) {
        what = "time";
        size_t tdims[2] = {1, s->n_frames};
        v = Mat_VarCreate("time", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, tdims, s->time, MAT_F_DONT_COPY_DATA);
        bad = !v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0;
        Mat_VarFree(v);
    }
    if (!bad) bad = mat_write_string(mat, what = "unit", s->unit, w) != THX_OK;
    if (!bad) bad = mat_write_string(mat, what = "time_unit", s->time_unit, w) != THX_OK;
    if (!bad) bad = mat_write_string(mat, what = "label", s->label, w) != THX_OK;
    int e = errno;
    if (Mat_Close(mat) != 0 && !bad) {
        bad = 1;
        what = "the end of the file";
    }
    /* libmatio does not always report a failed fwrite: a file shorter than
     * its data is (a full disk) is caught here */
    struct stat sb;
    if (!bad && (stat(af.tmp, &sb) != 0 || (uint64_t)sb.st_size < 128 + 8 * (uint64_t)s->n_frames * (s->n_rows + 1))) {
        bad = 1;
        what = "the data (the file is too short: disk full?)";
    }
    if (bad) {
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: writing %s failed: %s", path, what, e ? strerror(e) : "libmatio error");
    }
    if (rename(af.tmp, af.path) != 0) {
        e = errno;
        thx_atomic_abort(&af);
        return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", path, strerror(e));
    }
    af.tmp[0] = '\0';
    return THX_OK;
}

static const char *mat_class_name(const matvar_t *v)
{
    static const char *const names[] = {"empty", "cell", "struct", "object", "char", "sparse", "double", "single",
                                        "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                                        "function", "opaque"};
    if (v->isLogical) return "logical";
    return (unsigned)v->class_type < sizeof names / sizeof names[0] ? names[v->class_type] : "unknown";
}

static int mat_is_numeric_class(enum matio_classes c)
{
    return c == MAT_C_DOUBLE || c == MAT_C_SINGLE || c == MAT_C_INT8 || c == MAT_C_UINT8 || c == MAT_C_INT16 ||
           c == MAT_C_UINT16 || c == MAT_C_INT32 || c == MAT_C_UINT32 || c == MAT_C_INT64 || c == MAT_C_UINT64;
}

static size_t mat_numel(const matvar_t *v)
{
    size_t n = 1;
    for (int i = 0; i < v->rank; i++) n *= v->dims[i];
    return v->rank > 0 ? n : 0;
}

/* A candidate for the values: real, numeric, 2-D, not empty. */
static int mat_is_matrix(const matvar_t *v)
{
    return v && mat_is_numeric_class(v->class_type) && !v->isComplex && !v->isLogical && v->rank == 2 &&
           mat_numel(v) > 0;
}

/* Why v cannot be the values (for messages), or NULL. */
static const char *mat_not_matrix(const matvar_t *v)
{
    if (!mat_is_numeric_class(v->class_type)) return "not a numeric matrix";
    if (v->isComplex) return "complex (only real values are supported)";
    if (v->rank != 2) return "not 2-D (a series is a rows x frames matrix)";
    if (mat_numel(v) == 0) return "empty";
    return NULL;
}

/* Converts n numeric elements of v (any real class) to double. */
static int mat_to_double(const matvar_t *v, size_t n, double *out)
{
    if (!v->data) return 0;
    switch (v->class_type) {
#define CONV(T)                                                 \
    do {                                                        \
        const T *d = (const T *)v->data;                        \
        for (size_t i = 0; i < n; i++) out[i] = (double)d[i];   \
    } while (0)
    case MAT_C_DOUBLE: memcpy(out, v->data, n * sizeof *out); return 1;
    case MAT_C_SINGLE: CONV(float); return 1;
    case MAT_C_INT8: CONV(int8_t); return 1;
    case MAT_C_UINT8: CONV(uint8_t); return 1;
    case MAT_C_INT16: CONV(int16_t); return 1;
    case MAT_C_UINT16: CONV(uint16_t); return 1;
    case MAT_C_INT32: CONV(int32_t); return 1;
    case MAT_C_UINT32: CONV(uint32_t); return 1;
    case MAT_C_INT64: CONV(int64_t); return 1;
    case MAT_C_UINT64: CONV(uint64_t); return 1;
    default: return 0;
#undef CONV
    }
}

/* A char variable as UTF-8 into dst (cap bytes with the NUL). Returns 0 if it
 * is not a one-line char array; sets *cut when it had to be shortened. */
static int mat_string(const matvar_t *v, char *dst, size_t cap, int *cut)
{
    *cut = 0;
    dst[0] = '\0';
    if (v->class_type != MAT_C_CHAR || v->rank != 2 || v->dims[0] > 1) return 0;
    size_t n = 0, limit = cap - 1;
    if (!v->data || v->nbytes == 0 || mat_numel(v) == 0) return 1;
    switch (v->data_type) {
    case MAT_T_UTF8: {
        /* whole characters only */
        const unsigned char *b = v->data;
        size_t len = v->nbytes, i = 0;
        while (i < len && b[i]) {
            size_t k = 1;
            if (b[i] >= 0xC0) while (i + k < len && (b[i + k] & 0xC0) == 0x80) k++;
            if (n + k > limit) {
                *cut = 1;
                break;
            }
            memcpy(dst + n, b + i, k);
            n += k;
            i += k;
        }
        break;
    }
    case MAT_T_UINT16:
    case MAT_T_INT16:
    case MAT_T_UTF16: {
        const uint16_t *w = v->data;
        size_t len = v->nbytes / 2;
        for (size_t i = 0; i < len && w[i]; i++) {
            uint32_t c = w[i];
            if (c >= 0xD800 && c < 0xDC00 && i + 1 < len && w[i + 1] >= 0xDC00 && w[i + 1] < 0xE000) {
                c = 0x10000 + ((c - 0xD800) << 10) + (w[i + 1] - 0xDC00u);
                i++;
            } else if (c >= 0xD800 && c < 0xE000) {
                c = 0xFFFD;
            }
            if (!put_utf8(dst, &n, limit, c)) {
                *cut = 1;
                break;
            }
        }
        break;
    }
    case MAT_T_UINT8:
    case MAT_T_INT8: {
        const unsigned char *b = v->data;
        for (size_t i = 0; i < v->nbytes && b[i]; i++)
            if (!put_utf8(dst, &n, limit, b[i])) {
                *cut = 1;
                break;
            }
        break;
    }
    default: return 0;
    }
    dst[n] = '\0';
    return 1;
}

/* Where the metadata (time, unit, time_unit, label) come from: top-level
 * variables, or the fields of the struct that held the values. */
typedef struct {
    mat_t *mat;
    matvar_t *holder; /* the struct, or NULL for top level */
    matvar_t *owned;  /* the top-level variable last read (freed by the next mat_meta_get or the caller) */
} mat_meta;

static matvar_t *mat_meta_get(mat_meta *m, const char *name)
{
    if (m->holder) return Mat_VarGetStructFieldByName(m->holder, name, 0);
    Mat_VarFree(m->owned);
    m->owned = NULL;
    matvar_t *info = Mat_VarReadInfo(m->mat, name);
    if (!info) return NULL;
    Mat_VarFree(info);
    m->owned = Mat_VarRead(m->mat, name);
    return m->owned;
}

static thx_status mat_read_meta(thx_ctx *ctx, const char *path, const char *where, mat_meta *m, thx_series *s)
{
    matvar_t *t = mat_meta_get(m, "time");
    int have_time = 0;
    if (t && t->class_type == MAT_C_CHAR) {
        /* map3d's ts.time is the clock time of the recording ("2:06:25 PM"), not an axis */
        char clock[64];
        int cut = 0;
        if (mat_string(t, clock, sizeof clock, &cut))
            thx_log(ctx, THX_LOG_DEBUG, "%s: %stime '%s' is text (a clock time), not a time axis", path, where, clock);
        t = NULL;
    }
    if (t) {
        have_time = 1;
        size_t n = mat_numel(t);
        if (!mat_is_numeric_class(t->class_type) || t->isComplex || n != s->n_frames)
            return thx_error(ctx, THX_EINPUT, "%s: %stime is %s with %zu elements, but the series has %zu frames "
                                              "(a numeric vector of one time per frame is needed)",
                             path, where, mat_class_name(t), n, s->n_frames);
        if (!mat_to_double(t, n, s->time))
            return thx_error(ctx, THX_EINPUT, "%s: %stime: no data", path, where);
    }
    if (!have_time) {
        /* map3d's samplefrequency (Hz): frames 1 / fs apart, in ms */
        matvar_t *fs = mat_meta_get(m, "samplefrequency");
        double hz = 0;
        if (fs && mat_is_numeric_class(fs->class_type) && !fs->isComplex && mat_numel(fs) == 1 && mat_to_double(fs, 1, &hz) &&
            isfinite(hz) && hz > 0) {
            for (size_t f = 0; f < s->n_frames; f++) s->time[f] = (double)f * (1000.0 / hz);
            snprintf(s->time_unit, sizeof s->time_unit, "ms");
        } else if (fs) {
            thx_log(ctx, THX_LOG_WARN, "%s: %ssamplefrequency ignored: not one positive number", path, where);
        }
    }
    static const char *const names[] = {"unit", "time_unit", "label"};
    char *dst[] = {s->unit, s->time_unit, s->label};
    size_t cap[] = {sizeof s->unit, sizeof s->time_unit, sizeof s->label};
    for (int k = 0; k < 3; k++) {
        matvar_t *v = mat_meta_get(m, names[k]);
        if (!v) continue;
        char tmp[128];
        int cut = 0;
        if (!mat_string(v, tmp, cap[k], &cut)) {
            thx_log(ctx, THX_LOG_WARN, "%s: %s%s ignored: %s, not a one-line char array", path, where, names[k],
                    mat_class_name(v));
            continue;
        }
        if (cut) thx_log(ctx, THX_LOG_WARN, "%s: %s%s cut to %zu bytes", path, where, names[k], cap[k] - 1);
        memcpy(dst[k], tmp, cap[k]);
    }
    Mat_VarFree(m->owned);
    m->owned = NULL;
    return THX_OK;
}

/* "a (double 3x4), b (char 1x2)" for messages. */
static void mat_list_vars(mat_t *mat, char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    Mat_Rewind(mat);
    matvar_t *v;
    int count = 0;
    while ((v = Mat_VarReadNextInfo(mat)) && n < cap) {
        int w = snprintf(buf + n, cap - n, "%s%s (%s", count++ ? ", " : "", v->name ? v->name : "?",
                         mat_class_name(v));
        n += w > 0 ? (size_t)w : 0;
        for (int i = 0; i < v->rank && n < cap; i++) {
            w = snprintf(buf + n, cap - n, "%s%zu", i ? "x" : " ", v->dims[i]);
            n += w > 0 ? (size_t)w : 0;
        }
        if (n < cap) {
            w = snprintf(buf + n, cap - n, ")");
            n += w > 0 ? (size_t)w : 0;
        }
        Mat_VarFree(v);
    }
    Mat_VarFree(v);
    if (!count) snprintf(buf, cap, "none");
}

static thx_status read_mat(thx_ctx *ctx, const char *path, const char *varname, thx_series **out)
{
    *out = NULL;
    FILE *probe = fopen(path, "rb");
    if (!probe) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    mat_t *mat = Mat_Open(path, MAT_ACC_RDONLY);
    if (!mat) return thx_error(ctx, THX_EINPUT, "%s: not a MATLAB .mat file that libmatio can read", path);
    thx_status st = THX_OK;
    thx_series *s = NULL;
    matvar_t *top = NULL;     /* the variable read */
    const matvar_t *vals = NULL;
    char where[200] = "", vars[1024];
    const char *name = varname;
    if (!name) {
        /* potvals, else the first struct with a potvals field, else the first matrix */
        matvar_t *info = Mat_VarReadInfo(mat, "potvals");
        if (info) {
            name = "potvals";
            Mat_VarFree(info);
        } else {
            char fs[256] = "", fm[256] = "";
            Mat_Rewind(mat);
            while ((info = Mat_VarReadNextInfo(mat))) {
                if (!fs[0] && info->class_type == MAT_C_STRUCT && mat_numel(info) >= 1 && info->name &&
                    Mat_VarGetStructFieldByName(info, "potvals", 0))
                    snprintf(fs, sizeof fs, "%s", info->name);
                if (!fm[0] && mat_is_matrix(info) && info->name) snprintf(fm, sizeof fm, "%s", info->name);
                Mat_VarFree(info);
            }
            if (!fs[0] && !fm[0]) {
                mat_list_vars(mat, vars, sizeof vars);
                st = thx_error(ctx, THX_EINPUT,
                               "%s: no numeric variable: no 'potvals', no struct with a 'potvals' field, no 2-D "
                               "numeric matrix (variables: %s)",
                               path, vars);
                goto done;
            }
            top = Mat_VarRead(mat, fs[0] ? fs : fm);
            if (!top) {
                st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' cannot be read (damaged file?)", path,
                               fs[0] ? fs : fm);
                goto done;
            }
            name = top->name;
        }
    }
    if (!top) {
        matvar_t *info = Mat_VarReadInfo(mat, name);
        if (!info) {
            mat_list_vars(mat, vars, sizeof vars);
            st = thx_error(ctx, THX_EINPUT, "%s: no variable '%s' (variables: %s)", path, name, vars);
            goto done;
        }
        Mat_VarFree(info);
        top = Mat_VarRead(mat, name);
        if (!top) {
            st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' cannot be read (damaged file?)", path, name);
            goto done;
        }
    }
    mat_meta meta = {mat, NULL, NULL};
    if (top->class_type == MAT_C_STRUCT) {
        const matvar_t *pv = mat_numel(top) >= 1 ? Mat_VarGetStructFieldByName(top, "potvals", 0) : NULL;
        if (!pv) {
            st = thx_error(ctx, THX_EINPUT, "%s: variable '%s' is a struct without a 'potvals' field", path,
                           top->name);
            goto done;
        }
        if (mat_numel(top) > 1)
            thx_log(ctx, THX_LOG_WARN, "%s: '%s' is a struct array of %zu elements; the first is read", path,
                    top->name, mat_numel(top));
        vals = pv;
        meta.holder = top;
        snprintf(where, sizeof where, "%s.", top->name);
    } else {
        vals = top;
    }
    const char *why = mat_not_matrix(vals);
    if (why) {
        st = thx_error(ctx, THX_EINPUT, "%s: %s%s (%s) is %s", path, where, meta.holder ? "potvals" : top->name,
                       mat_class_name(vals), why);
        goto done;
    }
    if ((st = thx_series_create(ctx, vals->dims[0], vals->dims[1], &s)) != THX_OK) goto done;
    if (!mat_to_double(vals, s->n_rows * s->n_frames, s->v)) {
        st = thx_error(ctx, THX_EINPUT, "%s: %s%s: no data", path, where, meta.holder ? "potvals" : top->name);
        goto done;
    }
    if ((st = mat_read_meta(ctx, path, where, &meta, s)) != THX_OK) {
        Mat_VarFree(meta.owned);
        goto done;
    }
    st = check_series(ctx, s, path);
done:
    Mat_VarFree(top);
    Mat_Close(mat);
    if (st != THX_OK) thx_series_destroy(&s);
    *out = s;
    return st;
}

/* ------------------------------------------------------------- dispatch */

/* map3d .pot: the values of one time instant, one per node (any whitespace between them). */
static thx_status read_pot(thx_ctx *ctx, const char *path, thx_series **out)
{
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    size_t n = 0, cap = 1024, line = 1;
    double *v = malloc(cap * sizeof *v);
    thx_status st = v ? THX_OK : thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    for (char *p = text; st == THX_OK && *p;) {
        if (*p == '\n') { line++; p++; continue; }
        if (isspace((unsigned char)*p)) { p++; continue; }
        char *end;
        errno = 0;
        double x = strtod(p, &end);
        if (end == p || (*end && !isspace((unsigned char)*end))) {
            char tok[32];
            size_t k = 0;
            while (p[k] && !isspace((unsigned char)p[k]) && k < sizeof tok - 1) { tok[k] = p[k]; k++; }
            tok[k] = '\0';
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: '%s' is not a number (a .pot file holds one value per node)", path, line, tok);
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

thx_status thx_series_read(thx_ctx *ctx, const char *path, thx_series_format fmt, thx_series **out)
{
    *out = NULL;
    /* "file.mat:NAME" names a variable, unless a file of that whole name exists */
    char file[4096];
    const char *varname = NULL;
    if (strlen(path) >= sizeof file) return thx_error(ctx, THX_EIO, "%s: path too long", path);
    snprintf(file, sizeof file, "%s", path);
    struct stat sb;
    if (stat(path, &sb) != 0) {
        char *colon = strrchr(file, ':');
        if (colon && colon[1] && !strchr(colon, '/')) {
            *colon = '\0';
            if (stat(file, &sb) == 0) varname = colon + 1;
            else *colon = ':';
        }
    }
    if (fmt == THX_SERIES_AUTO) {
        fmt = format_of_content(file);
        if (fmt == THX_SERIES_AUTO) fmt = format_of_extension(file);
        if (fmt == THX_SERIES_AUTO) {
            if (stat(file, &sb) != 0) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", file, strerror(errno));
            return thx_error(ctx, THX_EINPUT,
                             "%s: unknown series format: not a thorax text or raw series nor a MATLAB file "
                             "(name it .txt, .raw or .mat, or give the format)",
                             file);
        }
    }
    if (varname && fmt != THX_SERIES_MAT)
        return thx_error(ctx, THX_EINPUT, "%s: a variable name (':%s') applies only to .mat files", file, varname);
    switch (fmt) {
    case THX_SERIES_TEXT: return read_text(ctx, file, out);
    case THX_SERIES_RAW: return read_raw(ctx, file, out);
    case THX_SERIES_MAT: return read_mat(ctx, file, varname, out);
    case THX_SERIES_POT: return read_pot(ctx, file, out);
    default: return thx_error(ctx, THX_EINPUT, "%s: unknown series format %d", file, (int)fmt);
    }
}

thx_status thx_series_write(thx_ctx *ctx, const thx_series *s, const char *path, thx_series_format fmt)
{
    if (fmt == THX_SERIES_AUTO) {
        fmt = format_of_extension(path);
        if (fmt == THX_SERIES_AUTO)
            return thx_error(ctx, THX_EINPUT,
                             "%s: cannot tell the series format from the extension '%s' (.txt, .dat, .raw or "
                             ".mat; or give the format)",
                             path, extension(path));
    }
    if (fmt == THX_SERIES_POT)
        return thx_error(ctx, THX_EINPUT, "%s: map3d .pot files are read, not written (write .txt, .raw or .mat)", path);
    THX_CHECK(check_series(ctx, s, path));
    switch (fmt) {
    case THX_SERIES_TEXT: return write_text(ctx, s, path);
    case THX_SERIES_RAW: return write_raw(ctx, s, path);
    case THX_SERIES_MAT: return write_mat(ctx, s, path);
    default: return thx_error(ctx, THX_EINPUT, "%s: unknown series format %d (%s)", path, (int)fmt, format_name(fmt));
    }
}
