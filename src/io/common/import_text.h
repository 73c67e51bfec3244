/*
 * Private text and binary scanning helpers shared by the import readers
 * (src/io/import.c for surfaces, src/io/import_volume.c for volume meshes).
 * Not installed, not public.
 *
 * Text is scanned in place by a cursor that counts lines (1-based); tokens
 * are whitespace-separated and never NUL-terminated; numbers are parsed from
 * a bounded NUL-terminated copy and must be finite. Binary scalars are read
 * byte by byte in an explicit byte order, never by casting the buffer.
 */
#ifndef THORAX_IO_IMPORT_TEXT_H
#define THORAX_IO_IMPORT_TEXT_H

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/common/tokens.h"

/* The extension of the last path component (after its last '.'), or "". */
static inline const char *path_extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return (dot && dot != base) ? dot + 1 : "";
}

/* ---------------------------------------------------------- text cursor */

typedef struct {
    const char *buf;
    size_t len, pos;
    int line; /* line of pos, 1-based */
} cursor;

/* The blanks of the line readers (io/common/tokens.h): space, tab, CR, vertical tab, form feed. */
static inline int is_blank(char c) { return thx_io_is_blank(c); }

/* The next whitespace-separated token, crossing line ends. Returns its length
 * (0 at the end) and sets *t and *line. */
static inline size_t next_token(cursor *c, const char **t, int *line)
{
    *t = c->buf + c->pos;
    *line = c->line;
    while (c->pos < c->len && (is_blank(c->buf[c->pos]) || c->buf[c->pos] == '\n')) {
        if (c->buf[c->pos] == '\n') c->line++;
        c->pos++;
    }
    if (c->pos >= c->len) return 0;
    *t = c->buf + c->pos;
    *line = c->line;
    size_t s = c->pos;
    while (c->pos < c->len && !is_blank(c->buf[c->pos]) && c->buf[c->pos] != '\n') c->pos++;
    return c->pos - s;
}

/* The next token on the current line only (0 at the line's end). */
static inline size_t line_token(cursor *c, const char **t)
{
    while (c->pos < c->len && is_blank(c->buf[c->pos])) c->pos++;
    *t = c->buf + c->pos; /* set even at a line's end: a 0-length token there */
    if (c->pos >= c->len || c->buf[c->pos] == '\n') return 0;
    size_t s = c->pos;
    while (c->pos < c->len && !is_blank(c->buf[c->pos]) && c->buf[c->pos] != '\n') c->pos++;
    return c->pos - s;
}

/* Moves to the start of the next line; returns 0 at the end of the text. */
static inline int next_line(cursor *c)
{
    while (c->pos < c->len && c->buf[c->pos] != '\n') c->pos++;
    if (c->pos >= c->len) return 0;
    c->pos++;
    c->line++;
    return 1;
}

static inline int tok_is(const char *t, size_t n, const char *word) { return strlen(word) == n && strncmp(t, word, n) == 0; }
static inline int tok_is_ci(const char *t, size_t n, const char *word) { return strlen(word) == n && strncasecmp(t, word, n) == 0; }

/* Token as a printable, bounded C string for messages. */
static inline const char *tok_show(const char *t, size_t n)
{
    static _Thread_local char buf[48];
    size_t k = 0;
    for (size_t i = 0; i < n && k + 4 < sizeof buf; i++) buf[k++] = (t[i] >= 0x20 && t[i] < 0x7f) ? t[i] : '?';
    if (k < n) buf[k++] = '.', buf[k++] = '.', buf[k++] = '.';
    buf[k] = '\0';
    return buf;
}

/* A finite number; returns 0 on success. */
static inline int parse_num(const char *t, size_t n, double *out)
{
    char tmp[128];
    if (n == 0 || n >= sizeof tmp) return -1;
    memcpy(tmp, t, n);
    tmp[n] = '\0';
    char *end = NULL;
    double v = strtod(tmp, &end);
    if (end != tmp + n || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

/* The largest integer every reader accepts: 2^53, the last one a double
 * holds exactly, so that an index kept as a double (VTK, PLY arrays) is
 * still the number the file wrote, and index arithmetic cannot overflow. */
#define INT_LIMIT 9007199254740992LL

/* The one integer parser of the import readers (overflow-safe): a decimal
 * integer token, "3", "-3", "+3", or an integral number written as "3.0" or
 * "3e2" (some PLY/VTK writers do), within [lo, hi] (|lo|, |hi| <= 2^53).
 * Hexadecimal, "inf", "nan" and fractions are not integers. Returns 0 and
 * *out; -1 if the token is not an integer; -2 if it is one outside
 * [lo, hi] (*out untouched: the caller quotes the token as written). */
static inline int parse_i64(const char *t, size_t n, long long lo, long long hi, long long *out)
{
    size_t i = 0;
    int neg = 0;
    if (n == 0) return -1;
    if (t[0] == '+' || t[0] == '-') neg = t[0] == '-', i = 1;
    if (i == n || !isdigit((unsigned char)t[i])) {
        if (!(i < n && t[i] == '.')) return -1; /* ".5" and the like: not integers anyway, but parsed below */
    }
    unsigned long long v = 0;
    int big = 0;
    for (; i < n && isdigit((unsigned char)t[i]); i++) {
        unsigned d = (unsigned)(t[i] - '0');
        if (v > (ULLONG_MAX - d) / 10) big = 1;
        else v = 10 * v + d;
    }
    if (i < n) {
        /* a fraction or exponent: only an integral value of plain decimal notation */
        for (size_t k = i; k < n; k++)
            if (!(isdigit((unsigned char)t[k]) || t[k] == '.' || t[k] == 'e' || t[k] == 'E' || t[k] == '+' || t[k] == '-'))
                return -1;
        char tmp[128];
        if (n >= sizeof tmp) return -1;
        memcpy(tmp, t, n);
        tmp[n] = '\0';
        char *end = NULL;
        double d = strtod(tmp, &end);
        if (end != tmp + n || !isfinite(d) || d != floor(d)) return -1;
        if (d < (double)lo || d > (double)hi) return -2;
        *out = (long long)d;
        return 0;
    }
    if (big || v > (unsigned long long)INT_LIMIT) return -2;
    long long s = neg ? -(long long)v : (long long)v;
    if (s < lo || s > hi) return -2;
    *out = s;
    return 0;
}

/* An integer of magnitude at most 2^53 (parse_i64); returns 0 on success. */
static inline int parse_int(const char *t, size_t n, long long *out)
{
    return parse_i64(t, n, -INT_LIMIT, INT_LIMIT, out) == 0 ? 0 : -1;
}

/* A count: an integer in 0 .. hi; 0 on success, -1 not an integer, -2 out of range. */
static inline int parse_count(const char *t, size_t n, long long hi, long long *out) { return parse_i64(t, n, 0, hi, out); }

/* The first NUL byte of text[0, len) as a line number (1-based), or 0 if none. */
static inline int nul_line(const char *text, size_t len)
{
    const char *z = memchr(text, 0, len);
    if (!z) return 0;
    int line = 1;
    for (const char *q = text; q < z; q++)
        if (*q == '\n') line++;
    return line;
}

typedef enum { T_NONE = 0, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64 } scalar_type;
static const size_t type_size[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

static inline scalar_type vtk_type(const char *t, size_t n)
{
    static const struct { const char *name; scalar_type ty; } tab[] = {
        {"char", T_I8}, {"unsigned_char", T_U8}, {"short", T_I16}, {"unsigned_short", T_U16}, {"int", T_I32},
        {"unsigned_int", T_U32}, {"vtktypeint64", T_I64}, {"vtktypeuint64", T_U64}, {"vtkIdType", T_I64},
        {"float", T_F32}, {"double", T_F64}, {"vtktypeint32", T_I32}, {"vtktypeuint32", T_U32},
        /* "long" is 4 or 8 bytes depending on the writer's platform: only its ASCII form is unambiguous */
        {"long", T_I64}, {"unsigned_long", T_U64},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (tok_is(t, n, tab[i].name)) return tab[i].ty;
    return T_NONE;
}

/* A binary scalar of type ty at p, in big- or little-endian order. */
static inline double get_scalar(const unsigned char *p, scalar_type ty, int big)
{
    unsigned char q[8];
    size_t sz = type_size[ty];
    for (size_t i = 0; i < sz; i++) q[i] = big ? p[sz - 1 - i] : p[i]; /* q: little-endian */
    uint64_t u = 0;
    for (size_t i = 0; i < sz; i++) u |= (uint64_t)q[i] << (8 * i);
    switch (ty) {
    case T_I8: return (double)(int8_t)u;
    case T_U8: return (double)(uint8_t)u;
    case T_I16: return (double)(int16_t)u;
    case T_U16: return (double)(uint16_t)u;
    case T_I32: return (double)(int32_t)(uint32_t)u;
    case T_U32: return (double)(uint32_t)u;
    case T_I64: return (double)(int64_t)u;
    case T_U64: return (double)u;
    case T_F32: { uint32_t w = (uint32_t)u; float f; memcpy(&f, &w, 4); return f; }
    case T_F64: { double d; memcpy(&d, &u, 8); return d; }
    default: return NAN;
    }
}

/* The range of an integer type, clamped to +-2^53 (INT_LIMIT) for 64 bits. */
static inline void type_range(scalar_type ty, long long *lo, long long *hi)
{
    switch (ty) {
    case T_I8: *lo = INT8_MIN, *hi = INT8_MAX; break;
    case T_U8: *lo = 0, *hi = UINT8_MAX; break;
    case T_I16: *lo = INT16_MIN, *hi = INT16_MAX; break;
    case T_U16: *lo = 0, *hi = UINT16_MAX; break;
    case T_I32: *lo = INT32_MIN, *hi = INT32_MAX; break;
    case T_U32: *lo = 0, *hi = UINT32_MAX; break;
    case T_U64: *lo = 0, *hi = INT_LIMIT; break;
    default: *lo = -INT_LIMIT, *hi = INT_LIMIT; break;
    }
}

/* A binary 64-bit integer at p beyond +-2^53 (a double would not hold it
 * exactly): returns 1 and its decimal text in buf; 0 otherwise. */
static inline int int64_beyond(const unsigned char *p, scalar_type ty, int big, char *buf, size_t size)
{
    if (ty != T_I64 && ty != T_U64) return 0;
    uint64_t u = 0;
    for (size_t i = 0; i < 8; i++) u |= (uint64_t)p[big ? 7 - i : i] << (8 * i);
    if (ty == T_U64 || !(u >> 63)) {
        if (u <= (uint64_t)INT_LIMIT) return 0;
        snprintf(buf, size, "%llu", (unsigned long long)u);
        return 1;
    }
    uint64_t mag = ~u + 1; /* |v| of a negative value, without signed overflow */
    if (mag <= (uint64_t)INT_LIMIT) return 0;
    snprintf(buf, size, "-%llu", (unsigned long long)mag);
    return 1;
}

static inline void copy_tok(char *dst, size_t size, const char *t, size_t n)
{
    if (n >= size) n = size - 1;
    memcpy(dst, t, n);
    dst[n] = '\0';
}

static inline int line_of(const char *buf, const char *p)
{
    int line = 1;
    for (const char *q = buf; q < p; q++)
        if (*q == '\n') line++;
    return line;
}

/* The value of attribute key in the tag [tag, end) into out; 0 if found. */
static inline int xml_attr(const char *tag, const char *end, const char *key, char *out, size_t size)
{
    size_t kl = strlen(key);
    for (const char *p = tag; p + kl + 2 < end; p++) {
        if ((p == tag || isspace((unsigned char)p[-1])) && strncmp(p, key, kl) == 0 && p[kl] == '=' &&
            (p[kl + 1] == '"' || p[kl + 1] == '\'')) {
            char q = p[kl + 1];
            const char *v = p + kl + 2, *e = v;
            while (e < end && *e != q) e++;
            if (e >= end) return -1;
            copy_tok(out, size, v, (size_t)(e - v));
            return 0;
        }
    }
    return -1;
}

/* Finds "<name" (followed by a space, '>' or '/') in [p, end). */
static inline const char *xml_find(const char *p, const char *end, const char *name)
{
    size_t nl = strlen(name);
    for (; p + nl + 1 < end; p++)
        if (p[0] == '<' && strncmp(p + 1, name, nl) == 0 &&
            (isspace((unsigned char)p[nl + 1]) || p[nl + 1] == '>' || p[nl + 1] == '/'))
            return p;
    return NULL;
}

#endif
