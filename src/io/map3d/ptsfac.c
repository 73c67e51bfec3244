/*
 * map3d/SCIRun .pts/.fac surfaces and the text helpers every line-based reader
 * shares (see thorax/io/model_dir.h for the public entry points).
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - .fac index base. In a model directory .fac files are 1-based by
 *    definition (DESIGN.md) and are read strictly so. For a stand-alone
 *    .pts/.fac pair (thx_surface_read_ptsfac) the base is detected from the
 *    smallest and largest index and the node count n:
 *        min == 0                     -> 0-based (then max must be <= n-1)
 *        min >= 1 and max == n        -> 1-based (0-based would be out of range)
 *        otherwise (min >= 1, max < n) -> ambiguous: error naming the file and
 *                                       the line of the largest index
 *    (the brief's "min 1 and max n" rule, widened to min >= 1 because a
 *    1-based file whose node 1 is unused is still unambiguous). An empty .fac
 *    file has no base; 1 is reported.
 *
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "thorax/core/fileio.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "io/common/io_text.h"

/* Writes "%.6f" of v into buf (at least 64 bytes), a value that rounds to zero as "0.000000" (the
 * rule is in model.c); from 1e15 on (where a double holds no more than whole millimetres and "%.6f"
 * only grows: 1e56 took 64 characters and was cut at 63), "%.17g", which reads back exactly. Below
 * 1e6 in magnitude the millionths are rounded here, the bytes snprintf would write: v * 1e6 (under
 * 2^40) is within 2^-13 of the exact product, so where its fraction lies farther than 2.5e-4 from a
 * half the rounding is the exact value's; nearer (1 in 2,000), and above 1e6, snprintf itself. The
 * 512 bench map's model (865,000 nodes, 1.7 million triangles) took 2.5 s to write with snprintf
 * and fprintf. Returns the length. */
static int format_coord(char *buf, double v)
{
    if (isfinite(v) && fabs(v) < 1e6) {
        double sc = v * 1e6, r = floor(sc), frac = sc - r;
        if (fabs(frac - 0.5) > 2.5e-4) {
            long long q = (long long)r + (frac > 0.5);
            if (q == 0) { memcpy(buf, "0.000000", 9); return 8; }
            int n = 0;
            unsigned long long a = q < 0 ? (unsigned long long)-q : (unsigned long long)q;
            char tmp[32];
            int k = 0;
            for (int d = 0; d < 6; d++, a /= 10) tmp[k++] = (char)('0' + a % 10);
            tmp[k++] = '.';
            do { tmp[k++] = (char)('0' + a % 10); a /= 10; } while (a);
            if (q < 0) buf[n++] = '-';
            while (k) buf[n++] = tmp[--k];
            buf[n] = '\0';
            return n;
        }
    }
    if (fabs(v) >= 1e15) snprintf(buf, 64, "%.17g", v);
    else snprintf(buf, 64, "%.6f", v);
    if (strcmp(buf, "-0.000000") == 0) memcpy(buf, "0.000000", 9);
    return (int)strlen(buf);
}

double thx_surface_stored_coord(double v)
{
    char buf[64];
    format_coord(buf, v);
    return strtod(buf, NULL);
}

void thx_io_put_coord(FILE *f, double v)
{
    char buf[64];
    int n = format_coord(buf, v);
    fwrite(buf, 1, (size_t)n, f);
}

/* Writes the decimal digits of v (no sign) into buf; returns the length. */
static int format_ulong(char *buf, unsigned long v)
{
    char tmp[24];
    int k = 0, n = 0;
    do { tmp[k++] = (char)('0' + v % 10); v /= 10; } while (v);
    while (k) buf[n++] = tmp[--k];
    return n;
}

thx_status thx_io_read_text(thx_ctx *ctx, const char *path, char **text)
{
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, text, &len));
    const char *nul = memchr(*text, '\0', len);
    if (!nul) return THX_OK;
    int line = 1;
    for (const char *p = *text; p < nul; p++) line += *p == '\n';
    free(*text);
    *text = NULL;
    return thx_error(ctx, THX_EINPUT, "%s:%d: a NUL byte in a text file (the file is binary or damaged)", path, line);
}

/* Splits the NUL-terminated line at p (ending at '\n' or NUL) into at most
 * max whitespace-separated tokens; each token is NUL-terminated in place.
 * Returns the number of tokens found (max + 1 means "more than max"). *next
 * is set to the start of the following line or NULL at the end. */
int thx_io_split_line(char *p, char **tok, int max, char **next)
{
    char *end = strchr(p, '\n');
    if (end) {
        *end = '\0';
        *next = end + 1;
    } else {
        *next = NULL;
    }
    int n = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\v' || *p == '\f') p++;
        if (!*p) break;
        if (n == max) return max + 1;
        tok[n++] = p;
        while (*p && !(*p == ' ' || *p == '\t' || *p == '\r' || *p == '\v' || *p == '\f')) p++;
        if (*p) *p++ = '\0';
    }
    return n;
}

/* ------------------------------------------------------------ .pts / .fac */

size_t thx_io_cut_lines(char *text, size_t len, size_t max, size_t min_bytes, thx_io_piece *pieces)
{
    size_t n = 0;
    char *at = text, *end = text + len;
    size_t want = max < 1 ? 1 : max;
    size_t step = len / want > min_bytes ? len / want : min_bytes;
    memset(pieces, 0, want * sizeof *pieces);
    while (at < end && n + 1 < want) {
        if ((size_t)(end - at) <= step + min_bytes) break; /* the rest in one piece */
        char *cut = memchr(at + step, '\n', (size_t)(end - at) - step);
        if (!cut) break;
        pieces[n].begin = at;
        pieces[n].end = cut + 1;
        n++;
        at = cut + 1;
    }
    pieces[n].begin = at;
    pieces[n].end = end;
    return n + 1;
}

size_t thx_io_cut_for_threads(char *text, thx_io_piece *pieces)
{
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    return thx_io_cut_lines(text, strlen(text), (size_t)threads < THX_IO_PIECES_MAX ? (size_t)threads : THX_IO_PIECES_MAX,
                            THX_IO_PIECE_BYTES, pieces);
}

thx_status thx_io_pieces_verdict(thx_ctx *ctx, const char *path, const thx_io_piece *pc, size_t np, size_t *n)
{
    int line0 = 0;
    *n = 0;
    for (size_t k = 0; k < np; k++) {
        if (pc[k].bad_line < 0) return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
        if (pc[k].bad_line) return thx_error(ctx, THX_EINPUT, "%s:%d: %s", path, line0 + pc[k].bad_line, pc[k].why);
        line0 += pc[k].lines;
        *n += pc[k].n;
    }
    return THX_OK;
}

/* One piece of "x y z" lines: its points into *xyz (the piece holds their count and its first fault). */
static void xyz_parse(thx_io_piece *pc, const char *what, double **xyz)
{
    size_t cap = 0;
    for (char *p = pc->begin, *next = NULL; p && p < pc->end; p = next) {
        char *tok[3];
        pc->lines++;
        int nt = thx_io_split_line(p, tok, 3, &next);
        if (nt == 0) continue; /* blank lines are allowed anywhere */
        if (nt != 3) {
            pc->bad_line = pc->lines;
            snprintf(pc->why, sizeof pc->why, "%sexpected 3 coordinates (x y z), found %s", what,
                     nt > 3 ? "more" : nt == 1 ? "1" : "2");
            return;
        }
        if (pc->n + 1 > cap) {
            size_t c2 = cap ? 2 * cap : 1024;
            double *x = realloc(*xyz, 3 * c2 * sizeof *x);
            if (!x) {
                pc->bad_line = -1;
                return;
            }
            *xyz = x;
            cap = c2;
        }
        for (int k = 0; k < 3; k++) {
            char *end = NULL;
            double v = strtod(tok[k], &end);
            if (end == tok[k] || *end != '\0' || !isfinite(v)) {
                pc->bad_line = pc->lines;
                snprintf(pc->why, sizeof pc->why, "%scoordinate %d is not a finite number: \"%.60s\"", what, k + 1, tok[k]);
                return;
            }
            (*xyz)[3 * pc->n + (size_t)k] = v;
        }
        pc->n++;
    }
}

/* "x y z" per line, blank lines allowed (a surface's .pts and the volume's volume.pts): what
 * prefixes the messages after FILE:LINE: (e.g. "surface \"torso\": ", or ""). */
thx_status thx_io_read_xyz(thx_ctx *ctx, const char *path, const char *what, double **xyz_out, size_t *n_out)
{
    char *text = NULL;
    thx_status st = thx_io_read_text(ctx, path, &text);
    if (st) return st;
    thx_io_piece pc[THX_IO_PIECES_MAX];
    double *part[THX_IO_PIECES_MAX] = {NULL};
    size_t np = thx_io_cut_for_threads(text, pc), n = 0;
#pragma omp parallel for schedule(static, 1) num_threads((int)np) if (np > 1)
    for (size_t k = 0; k < np; k++) xyz_parse(&pc[k], what, &part[k]);
    st = thx_io_pieces_verdict(ctx, path, pc, np, &n);
    double *xyz = NULL;
    if (st == THX_OK && np == 1) {
        xyz = part[0];
        part[0] = NULL;
    } else if (st == THX_OK && !(xyz = malloc(3 * (n ? n : 1) * sizeof *xyz))) {
        st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    } else if (st == THX_OK) {
        for (size_t k = 0, at = 0; k < np; at += pc[k].n, k++)
            if (pc[k].n) memcpy(xyz + 3 * at, part[k], 3 * pc[k].n * sizeof *xyz); /* (a piece of blank lines has none) */
    }
    for (size_t k = 0; k < np; k++) free(part[k]);
    free(text);
    if (st != THX_OK) return st;
    *xyz_out = xyz;
    *n_out = n;
    return THX_OK;
}

static thx_status read_pts(thx_ctx *ctx, const char *path, const char *name, double **xyz_out, size_t *n_out)
{
    char what[96];
    snprintf(what, sizeof what, "surface \"%s\": ", name);
    THX_CHECK(thx_io_read_xyz(ctx, path, what, xyz_out, n_out));
    if (*n_out == 0) {
        free(*xyz_out);
        *xyz_out = NULL;
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": no nodes", path, name);
    }
    return THX_OK;
}

/* Reads a .fac file of n_nodes nodes. want_base is 0 or 1 to require that
 * base, or -1 to detect it (rules at the top of this file). The triangles are
 * returned 0-based. */
static thx_status read_fac(thx_ctx *ctx, const char *path, const char *name, size_t n_nodes, int want_base,
                           int32_t **tri_out, size_t *n_out, int *base_out)
{
    char *text = NULL;
    thx_status st = thx_io_read_text(ctx, path, &text);
    if (st) return st;
    int32_t *tri = NULL;
    size_t n = 0, cap = 0;
    long lo = LONG_MAX, hi = LONG_MIN;
    int lo_line = 0, hi_line = 0, line = 0;
    for (char *p = text, *next = NULL; p; p = next) {
        char *tok[3];
        line++;
        int nt = thx_io_split_line(p, tok, 3, &next);
        if (nt == 0) continue;
        if (nt != 3) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": expected 3 node numbers, found %s", path, line,
                           name, nt > 3 ? "more" : nt == 1 ? "1" : "2");
            goto done;
        }
        if (n + 1 > cap) THX_TRY(thx_grow(ctx, (void **)&tri, &cap, n + 1, 3 * sizeof *tri));
        for (int k = 0; k < 3; k++) {
            char *end = NULL;
            errno = 0;
            long v = strtol(tok[k], &end, 10);
            if (end == tok[k] || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > INT32_MAX) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %d is not an integer: \"%s\"",
                               path, line, name, k + 1, tok[k]);
                goto done;
            }
            if (v < lo) { lo = v; lo_line = line; }
            if (v > hi) { hi = v; hi_line = line; }
            tri[3 * n + (size_t)k] = (int32_t)v;
        }
        n++;
    }
    int base = 1;
    if (n > 0) {
        long nn = (long)n_nodes;
        if (want_base >= 0) base = want_base;
        else if (lo == 0) base = 0;
        else if (lo >= 1 && hi == nn) base = 1;
        else if (lo >= 1 && hi < nn) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s:%d: surface \"%s\": cannot tell whether node numbers are 0- or 1-based: they run "
                           "%ld..%ld for %zu nodes (0-based needs a 0, 1-based may reach %zu)",
                           path, hi_line, name, lo, hi, n_nodes, n_nodes);
            goto done;
        }
        /* else: lo < 0 or hi > n, reported as out of range below with base 1
         * when lo >= 1 (the likelier intent) and 0 otherwise. */
        else base = lo >= 1 ? 1 : 0;
        if (lo < base) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %ld out of range %d..%ld (%d-based, %zu nodes)",
                           path, lo_line, name, lo, base, nn - 1 + base, base, n_nodes);
            goto done;
        }
        if (hi > nn - 1 + base) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": node number %ld out of range %d..%ld (%d-based, %zu nodes)",
                           path, hi_line, name, hi, base, nn - 1 + base, base, n_nodes);
            goto done;
        }
        for (size_t i = 0; i < 3 * n; i++) tri[i] -= base;
    }
    *tri_out = tri;
    *n_out = n;
    if (base_out) *base_out = base;
    tri = NULL;
done:
    free(tri);
    free(text);
    return st;
}

thx_status thx_io_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                              int want_base, thx_surface **out, int *base)
{
    *out = NULL;
    thx_surface *s = NULL;
    thx_status st;
    THX_TRY(thx_surface_create(ctx, name, role, &s));
    THX_TRY(read_pts(ctx, pts, name, &s->xyz, &s->n_nodes));
    THX_TRY(read_fac(ctx, fac, name, s->n_nodes, want_base, &s->tri, &s->n_tris, base));
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    return st;
}

thx_status thx_surface_read_ptsfac(thx_ctx *ctx, const char *pts, const char *fac, const char *name, thx_role role,
                                   thx_surface **out, int *base)
{
    return thx_io_read_ptsfac(ctx, pts, fac, name, role, -1, out, base);
}

/* The checks every writer makes before touching a file: arrays present,
 * coordinates finite, triangle indices within 0..n_nodes-1. */
thx_status thx_surface_write_ptsfac(thx_ctx *ctx, const thx_surface *s, const char *pts, const char *fac)
{
    THX_CHECK(thx_surface_validate(ctx, s));
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, pts, &af));
    for (size_t i = 0; i < s->n_nodes; i++) {
        char line[200];
        int n = 0;
        for (int k = 0; k < 3; k++) {
            n += format_coord(line + n, s->xyz[3 * i + (size_t)k]);
            line[n++] = k < 2 ? ' ' : '\n';
        }
        fwrite(line, 1, (size_t)n, af.f);
    }
    THX_CHECK(thx_atomic_commit(ctx, &af));
    THX_CHECK(thx_atomic_open(ctx, fac, &af));
    for (size_t t = 0; t < s->n_tris; t++) { /* "%ld %ld %ld\n", 1-based (validated: 0 .. n_nodes - 1) */
        char line[80];
        int n = 0;
        for (int k = 0; k < 3; k++) {
            n += format_ulong(line + n, (unsigned long)s->tri[3 * t + (size_t)k] + 1);
            line[n++] = k < 2 ? ' ' : '\n';
        }
        fwrite(line, 1, (size_t)n, af.f);
    }
    return thx_atomic_commit(ctx, &af);
}

