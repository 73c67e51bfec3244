/*
 * map3d landmark files (thorax/io/landmarks_file.h; docs/formats.md, "Landmarks (.lmarks)", is
 * the specification of what is accepted).
 *
 * Facts about map3d's reader (thirdparty/gfilelib/readlmarkfile.c, cutil/readline.c) that the
 * choices below follow:
 *  - lines are read with `#` comments cut and blank lines skipped;
 *  - the first line is read with sscanf "%i": a count followed by anything ("11 segment" in the
 *    tank file) — and "011" would be octal, "0x0b" hexadecimal;
 *  - a segment line is split at blanks and commas: number, type word (prefix-matched after
 *    upper-casing), point count, then up to four integers: 1 = an index, 3 = a colour, 4 = index
 *    and colour (2 gives a garbled colour; a fifth is ignored); a segment number out of order
 *    is only warned about; a colour or index of -1 means "none";
 *  - a point line is sscanf "%f %f %f %f %39s": four numbers separated by blanks (no commas),
 *    an optional one-word label of up to 39 characters, the rest of the line ignored;
 *  - a file ending early keeps the segments read so far; points closer than |p|^2/1e9 to an
 *    earlier point of the segment are dropped.
 *
 * thorax reads the same files the same way where they are well formed, and refuses, naming the
 * line, where map3d would guess or silently drop: a segment count that disagrees with the
 * segments, a point count that disagrees with the point lines, segments out of order, a second
 * optional field (2 extra integers), a fifth, -1 or out-of-range colours, text after a label or
 * after the last segment, a leading zero in the first count (octal to map3d), a label map3d would
 * cut. Doubled points are kept as written (the meshes skip a repeated point; the file's content
 * round-trips).
 */
#include "thorax/io/landmarks_file.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/core/fileio.h"
#include "io/common/parse_uint.h"

/* Fewest bytes a segment takes in a file ("1 lead 1\n0 0 0 0\n", 17, less a last newline), and a
 * point ("0 0 0 0\n", 8, less a last newline): the counts a file can hold are bounded by these
 * before anything else is believed. */
#define SEGMENT_MIN_BYTES 16
#define POINT_MIN_BYTES 8

/* ------------------------------------------------------------ reading */

typedef struct {
    thx_ctx *ctx;
    const char *name;
    size_t line;
} reader;

static thx_status rfail(const reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static thx_status rfail(const reader *r, const char *fmt, ...)
{
    char msg[1200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(r->ctx, THX_EINPUT, "%s:%zu: %s", r->name, r->line, msg);
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Splits line p (NUL-terminated, comment cut) into tokens at blanks (and at commas when
 * `commas`), NUL-terminating them in place; stores at most max, returns how many there are. */
static int split(char *p, char **tok, int max, int commas)
{
    int n = 0;
    for (;;) {
        while (is_blank(*p) || (commas && *p == ',')) p++;
        if (!*p) return n;
        if (n < max) tok[n] = p;
        n++;
        while (*p && !is_blank(*p) && !(commas && *p == ',')) p++;
        if (*p) *p++ = '\0';
    }
}

/* A token shown in a message: at most 40 bytes, non-printable bytes as '?'. */
static const char *show(const char *t, char buf[48])
{
    size_t k = 0;
    for (; t[k] && k < 40; k++) buf[k] = (t[k] > ' ' && t[k] <= '~') ? t[k] : '?';
    if (t[k]) buf[k++] = '.', buf[k++] = '.', buf[k++] = '.';
    buf[k] = '\0';
    return buf;
}

/* A decimal number and nothing else: [+-] digits [. digits] [e [+-] digits] with at least one
 * digit in the mantissa (".5" and "5." included, as sscanf "%f" reads them). No hex, inf or nan,
 * which strtod would take. Returns 0 and *v (possibly infinite: 1e999; the caller bounds it). */
static int parse_decimal(const char *t, double *v)
{
    const char *q = t;
    int digits = 0;
    if (*q == '+' || *q == '-') q++;
    while (isdigit((unsigned char)*q)) q++, digits++;
    if (*q == '.') {
        q++;
        while (isdigit((unsigned char)*q)) q++, digits++;
    }
    if (!digits) return -1;
    if (*q == 'e' || *q == 'E') {
        q++;
        if (*q == '+' || *q == '-') q++;
        if (!isdigit((unsigned char)*q)) return -1;
        while (isdigit((unsigned char)*q)) q++;
    }
    if (*q) return -1;
    char *end = NULL;
    *v = strtod(t, &end);
    return end == q ? 0 : -1;
}

/* An unsigned decimal integer <= max: digits only (thx_parse_uint). */
static int parse_uint(const char *t, uint64_t max, uint64_t *out) { return thx_parse_uint(t, 0, max, out); }

/* Whether the tokens look like a point line: 4 or 5 fields, the first four decimal numbers. */
static int looks_like_point(char **tok, int ntok)
{
    if (ntok < 4 || ntok > 5) return 0;
    double v;
    for (int i = 0; i < 4; i++)
        if (parse_decimal(tok[i], &v) != 0) return 0;
    return 1;
}

/* Whether the tokens look like a segment header: an integer, a type name, an integer. */
static int looks_like_header(char **tok, int ntok)
{
    uint64_t u;
    thx_landmark_type t;
    return ntok >= 3 && parse_uint(tok[0], UINT32_MAX, &u) == 0 && thx_landmark_type_parse(tok[1], &t) == 0;
}

typedef enum { S_COUNT, S_HEADER, S_POINTS, S_DONE } rstate;

typedef struct {
    thx_landmark_type type;
    size_t npts;        /* the count the header gives */
    size_t line;        /* the header's line */
    int has_index, has_color;
    long index;
    unsigned char rgb[3];
} seg_header;

/* Parses a segment header line (tokens split at blanks and commas) for segment k (0-based). */
static thx_status parse_header(const reader *r, char **tok, int ntok, size_t k, size_t prev_line, size_t prev_n,
                               size_t bytes_left, seg_header *h)
{
    char b1[48], b2[48];
    uint64_t u;
    if (ntok < 3) {
        if (looks_like_point(tok, ntok))
            return rfail(r, "expected the header of segment %zu ('%zu TYPE NPOINTS [INDEX] [R G B]'), found a point", k + 1, k + 1);
        return rfail(r, "expected the header of segment %zu ('%zu TYPE NPOINTS [INDEX] [R G B]'), found %d field%s",
                     k + 1, k + 1, ntok, ntok == 1 ? "" : "s");
    }
    if (!looks_like_header(tok, ntok) && looks_like_point(tok, ntok)) {
        if (k == 0)
            return rfail(r, "expected the header of segment 1 ('1 TYPE NPOINTS [INDEX] [R G B]'), found a point");
        return rfail(r, "expected the header of segment %zu ('%zu TYPE NPOINTS [INDEX] [R G B]'), found a point: does "
                     "segment %zu (line %zu) have more than the %zu points it declares?", k + 1, k + 1, k, prev_line, prev_n);
    }
    if (parse_uint(tok[0], UINT32_MAX, &u) != 0)
        return rfail(r, "segment %zu: segment number '%s' is not a whole number (expected '%zu TYPE NPOINTS ...')", k + 1,
                     show(tok[0], b1), k + 1);
    if (u != k + 1)
        return rfail(r, "segment %zu: numbered %s (segments are numbered 1, 2, ... in order)", k + 1, show(tok[0], b1));
    if (thx_landmark_type_parse(tok[1], &h->type) != 0)
        return rfail(r, "segment %zu: unknown landmark type '%s' (known: %s)", k + 1, show(tok[1], b1),
                     thx_landmark_type_names());
    const char *tn = thx_landmark_type_name(h->type);
    if (parse_uint(tok[2], INT32_MAX, &u) != 0 || u == 0)
        return rfail(r, "segment %zu (%s): point count '%s' is not a positive whole number", k + 1, tn, show(tok[2], b1));
    if (u > (bytes_left + 1) / POINT_MIN_BYTES)
        return rfail(r, "segment %zu (%s) declares %llu point%s, but the %zu bytes that follow hold at most %zu (a "
                     "point line takes at least %d): a wrong count, or a file cut short", k + 1, tn,
                     (unsigned long long)u, u == 1 ? "" : "s", bytes_left, (bytes_left + 1) / POINT_MIN_BYTES, POINT_MIN_BYTES);
    h->npts = (size_t)u;
    int extra = ntok - 3;
    if (extra == 2 || extra > 4)
        return rfail(r, "segment %zu (%s): %d fields after the point count; expected none, INDEX, R G B or INDEX R G B",
                     k + 1, tn, extra);
    h->has_index = extra == 1 || extra == 4;
    h->has_color = extra >= 3;
    int f = 3;
    if (h->has_index) {
        if (parse_uint(tok[f], INT32_MAX, &u) != 0)
            return rfail(r, "segment %zu (%s): index '%s' is not a whole number 0..%d", k + 1, tn, show(tok[f], b1),
                         INT32_MAX);
        h->index = (long)u;
        f++;
    }
    if (h->has_color)
        for (int c = 0; c < 3; c++, f++) {
            if (parse_uint(tok[f], 255, &u) != 0)
                return rfail(r, "segment %zu (%s): colour %s '%s' is not a whole number 0..255", k + 1, tn,
                             c == 0 ? "red" : c == 1 ? "green" : "blue", show(tok[f], b2));
            h->rgb[c] = (unsigned char)u;
        }
    return THX_OK;
}

/* Parses point j (0-based) of segment k from its tokens (split at blanks). */
static thx_status parse_point(const reader *r, char **tok, int ntok, size_t k, size_t j, const seg_header *h,
                              thx_landmark_point *p)
{
    char b[48];
    /* a point's second field is a number, a header's a type name: the two cannot be confused */
    if (looks_like_header(tok, ntok))
        return rfail(r, "segment %zu point %zu: expected 'X Y Z RADIUS [LABEL]', found a segment header: segment %zu "
                     "(line %zu) declares %zu points but has %zu", k + 1, j + 1, k + 1, h->line, h->npts, j);
    if (ntok < 4 || ntok > 5) {
        for (int i = 0; i < ntok && i < 6; i++)
            if (strchr(tok[i], ','))
                return rfail(r, "segment %zu point %zu: a comma in '%s': the fields of a point are separated by blanks "
                             "(map3d reads them so)", k + 1, j + 1, show(tok[i], b));
        return rfail(r, "segment %zu point %zu: expected 'X Y Z RADIUS [LABEL]', found %d field%s", k + 1, j + 1, ntok,
                     ntok == 1 ? "" : "s");
    }
    static const char *const what[4] = {"x", "y", "z", "radius"};
    double v[4];
    for (int i = 0; i < 4; i++) {
        if (parse_decimal(tok[i], &v[i]) != 0) {
            if (strchr(tok[i], ','))
                return rfail(r, "segment %zu point %zu: a comma in '%s': the fields of a point are separated by blanks "
                             "(map3d reads them so)", k + 1, j + 1, show(tok[i], b));
            return rfail(r, "segment %zu point %zu: %s '%s' is not a decimal number", k + 1, j + 1, what[i],
                         show(tok[i], b));
        }
        if (!isfinite(v[i]) || fabs(v[i]) > THX_LANDMARK_MAX_COORD)
            return rfail(r, "segment %zu point %zu: %s '%s' is beyond +-%g mm", k + 1, j + 1, what[i], show(tok[i], b),
                         THX_LANDMARK_MAX_COORD);
    }
    if (v[3] < 0) /* "-0.00" (map3d's "%6.2f" of a tiny negative) is 0 */
        return rfail(r, "segment %zu point %zu: radius %s is negative (a radius is >= 0)", k + 1, j + 1, show(tok[3], b));
    memset(p, 0, sizeof *p);
    for (int i = 0; i < 3; i++) p->xyz[i] = v[i];
    p->radius = v[3] + 0.0; /* -0 -> +0 */
    if (ntok == 5) {
        const char *why = thx_landmark_label_why(tok[4]);
        if (why) return rfail(r, "segment %zu point %zu: label '%s' %s", k + 1, j + 1, show(tok[4], b), why);
        snprintf(p->label, sizeof p->label, "%s", tok[4]);
    }
    return THX_OK;
}

thx_status thx_landmarks_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_landmarks **out)
{
    *out = NULL;
    reader r = {ctx, name, 0};
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        r.line = 1;
        for (const char *q = text; q < nul; q++) r.line += *q == '\n';
        return rfail(&r, "NUL byte at byte offset %zu: not a text file", (size_t)(nul - text));
    }
    char *buf = thx_malloc(ctx, len + 1);
    if (!buf) return THX_ENOMEM;
    memcpy(buf, text, len);
    buf[len] = '\0';
    thx_landmarks *lm = NULL;
    thx_landmark_point *pts = NULL;
    size_t cap = 0, got = 0;
    thx_status st = THX_OK;
    THX_TRY(thx_landmarks_create(ctx, &lm));
    snprintf(lm->path, sizeof lm->path, "%s", name);

    rstate state = S_COUNT;
    size_t n_segs = 0, count_line = 0, k = 0;
    seg_header h = {0};
    size_t prev_line = 0, prev_n = 0;
    char *p = buf;
    while (*p) {
        char *nl = strchr(p, '\n');
        if (nl) *nl = '\0';
        char *line = p;
        p = nl ? nl + 1 : p + strlen(p);
        size_t bytes_left = len - (size_t)(p - buf);
        r.line++;
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        char *tok[8];
        char b[48];
        int ntok = split(line, tok, 8, state == S_HEADER);
        if (ntok == 0) continue;
        switch (state) {
        case S_COUNT: {
            uint64_t u;
            if (parse_uint(tok[0], INT32_MAX, &u) != 0) {
                st = rfail(&r, "expected the number of segments on the first line, found '%s'", show(tok[0], b));
                goto done;
            }
            if (tok[0][0] == '0' && tok[0][1]) {
                st = rfail(&r, "segment count '%s' has a leading zero (map3d would read it as octal)", show(tok[0], b));
                goto done;
            }
            if (ntok >= 2) {
                int word = !strcasecmp(tok[1], "segment") || !strcasecmp(tok[1], "segments");
                if (!word || ntok > 2) {
                    st = rfail(&r, "unexpected text after the segment count: '%s' (only 'segment' or 'segments' may "
                               "follow)", show(tok[word ? 2 : 1], b));
                    goto done;
                }
            }
            if (u > (bytes_left + 1) / SEGMENT_MIN_BYTES) {
                st = rfail(&r, "the file declares %llu segment%s, but the %zu bytes that follow hold at most %zu (a "
                           "segment takes at least %d): a wrong count, or a file cut short", (unsigned long long)u,
                           u == 1 ? "" : "s", bytes_left, (bytes_left + 1) / SEGMENT_MIN_BYTES, SEGMENT_MIN_BYTES);
                goto done;
            }
            n_segs = (size_t)u;
            count_line = r.line;
            state = n_segs ? S_HEADER : S_DONE;
            break;
        }
        case S_HEADER:
            memset(&h, 0, sizeof h);
            THX_TRY(parse_header(&r, tok, ntok, k, prev_line, prev_n, bytes_left, &h));
            h.line = r.line;
            got = 0;
            state = S_POINTS;
            break;
        case S_POINTS: {
            if (got + 1 > cap) THX_TRY(thx_grow(ctx, (void **)&pts, &cap, got + 1, sizeof *pts));
            THX_TRY(parse_point(&r, tok, ntok, k, got, &h, &pts[got]));
            got++;
            if (got < h.npts) break;
            thx_landmark_segment *s = NULL;
            THX_TRY(thx_landmarks_add_segment(ctx, lm, h.type, pts, got, &s));
            s->has_index = h.has_index;
            s->index = h.has_index ? h.index : 0;
            s->has_color = h.has_color;
            if (h.has_color) memcpy(s->rgb, h.rgb, 3);
            s->line = (int)(h.line <= INT32_MAX ? h.line : INT32_MAX);
            {
                char where[700];
                snprintf(where, sizeof where, "%s:%zu: ", name, h.line);
                THX_TRY(thx_landmark_segment_validate(ctx, s, k, where));
            }
            prev_line = h.line;
            prev_n = h.npts;
            k++;
            state = k < n_segs ? S_HEADER : S_DONE;
            break;
        }
        case S_DONE:
            if (looks_like_point(tok, ntok) && n_segs)
                st = rfail(&r, "text after the last segment: the file declares %zu segment%s (line %zu); does segment %zu "
                           "(line %zu) have more than the %zu points it declares?", n_segs, n_segs == 1 ? "" : "s",
                           count_line, n_segs, prev_line, prev_n);
            else
                st = rfail(&r, "text after the last segment: the file declares %zu segment%s (line %zu)", n_segs,
                           n_segs == 1 ? "" : "s", count_line);
            goto done;
        }
    }
    if (r.line == 0) r.line = 1;
    if (state == S_COUNT) {
        st = rfail(&r, "empty file (expected the number of segments on the first line)");
        goto done;
    }
    if (state == S_HEADER) {
        st = rfail(&r, "truncated file: %zu of %zu segment%s (the count on line %zu)", k, n_segs, n_segs == 1 ? "" : "s",
                   count_line);
        goto done;
    }
    if (state == S_POINTS) {
        st = rfail(&r, "truncated file: segment %zu (%s, line %zu) has %zu of its %zu points", k + 1,
                   thx_landmark_type_name(h.type), h.line, got, h.npts);
        goto done;
    }
    THX_TRY(thx_landmarks_validate(ctx, lm, NULL)); /* holds after the checks above; kept as the invariant */
done:
    free(buf);
    free(pts);
    if (st != THX_OK) thx_landmarks_destroy(&lm);
    *out = lm;
    return st;
}

thx_status thx_landmarks_read(thx_ctx *ctx, const char *path, thx_landmarks **out)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_status st = thx_landmarks_parse(ctx, path, text, len, out);
    free(text);
    return st;
}

/* ------------------------------------------------------------ writing */

/* "%.6f" when it reads back to v exactly (every value of the real files), else "%.17g"; -0 as 0. */
static void put_num(FILE *f, double v)
{
    char s[64];
    if (v == 0) v = 0; /* -0 -> +0 */
    snprintf(s, sizeof s, "%.6f", v);
    if (strtod(s, NULL) != v) snprintf(s, sizeof s, "%.17g", v);
    fputs(s, f);
}

thx_status thx_landmarks_write(thx_ctx *ctx, const thx_landmarks *lm, const char *path)
{
    char where[1100];
    snprintf(where, sizeof where, "%s: ", path);
    THX_CHECK(thx_landmarks_validate(ctx, lm, where));
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    fprintf(f, "%zu\n", lm->n);
    for (size_t k = 0; k < lm->n; k++) {
        const thx_landmark_segment *s = &lm->seg[k];
        fprintf(f, "%zu %s %zu", k + 1, thx_landmark_type_name(s->type), s->n);
        if (s->has_index) fprintf(f, " %ld", s->index);
        if (s->has_color) fprintf(f, " %u %u %u", s->rgb[0], s->rgb[1], s->rgb[2]);
        fputc('\n', f);
        for (size_t i = 0; i < s->n; i++) {
            const thx_landmark_point *p = &s->pt[i];
            for (int c = 0; c < 3; c++) {
                put_num(f, p->xyz[c]);
                fputc(' ', f);
            }
            put_num(f, p->radius);
            if (p->label[0]) fprintf(f, " %s", p->label);
            fputc('\n', f);
        }
    }
    return thx_atomic_commit(ctx, &af);
}
