/*
 * map3d's legacy CVRTI "graphicsio" files: .geom surfaces and .tsdf time series
 * (thorax/io/graphicsio.h; docs/formats.md, "map3d graphicsio files", is the
 * specification, worked out from the files in ../shared/data/map3d and checked
 * against the text files holding the same data).
 *
 * Decisions recorded here:
 *
 *  - The whole file is read into memory and walked by offsets; every offset
 *    and count is checked against the file's length before it is followed or
 *    anything is allocated for it, so a damaged file costs at most a small
 *    multiple of its own size. Links are followed exactly as many times as the
 *    header's counts say, so a cycle cannot loop.
 *
 *  - Reals are VAX F_floating (the format's VAX heritage), decoded bit by bit
 *    into doubles, which is exact; the VAX "reserved operand" (sign bit with a
 *    zero exponent) is refused like a NaN. Integers are little-endian.
 *
 *  - The text fields of the format (labels, names, the info block's text) are
 *    fixed-size arrays written from uninitialised memory: they are read up to
 *    their first NUL, with control bytes shown as '?'.
 */
#include "thorax/io/graphicsio.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

typedef struct {
    thx_ctx *ctx;
    const char *path;
    const unsigned char *b;
    size_t len;
} gio;

static thx_status gerr(gio *g, size_t at, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static thx_status gerr(gio *g, size_t at, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(g->ctx, THX_EINPUT, "%s: byte %zu: %s", g->path, at, msg);
}

/* A 32-bit little-endian integer at off (the caller checked off + 4 <= len). */
static long i32(const gio *g, size_t off)
{
    const unsigned char *p = g->b + off;
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    return u >= 0x80000000u ? (long)((int64_t)u - 0x100000000LL) : (long)u;
}

/* n bytes at off lie inside the file. */
static int inside(const gio *g, size_t off, size_t n) { return off <= g->len && n <= g->len - off; }

/* VAX F_floating at p into *out; -1 for the reserved operand. */
static int vax_f(const unsigned char *p, double *out)
{
    uint32_t w = (uint32_t)p[1] << 24 | (uint32_t)p[0] << 16 | (uint32_t)p[3] << 8 | (uint32_t)p[2];
    unsigned e = (w >> 23) & 0xffu;
    if (e == 0) {
        if (w >> 31) return -1;
        *out = 0.0;
        return 0;
    }
    double m = 0.5 + (double)(w & 0x7fffffu) / 16777216.0;
    *out = ldexp((w >> 31) ? -m : m, (int)e - 128);
    return 0;
}

/* A fixed-size text field (cap bytes in the file) into dst (dstcap with the NUL). */
static void text_field(const gio *g, size_t off, size_t cap, char *dst, size_t dstcap)
{
    size_t n = 0;
    for (size_t i = 0; i < cap && n + 1 < dstcap; i++) {
        unsigned char c = g->b[off + i];
        if (!c) break;
        dst[n++] = (c < 32 || c == 127) ? '?' : (char)c;
    }
    while (n && dst[n - 1] == ' ') n--;
    dst[n] = '\0';
}

/* An offset field at `at` (inside the file): points to `need` bytes inside the file. */
static thx_status link_to(gio *g, size_t at, size_t need, const char *what, size_t *out)
{
    long v = i32(g, at);
    if (v <= 0 || !inside(g, (size_t)v, need))
        return gerr(g, at, "%s at byte %ld (%zu bytes) is not inside the file (%zu bytes): truncated or damaged file",
                    what, v, need, g->len);
    *out = (size_t)v;
    return THX_OK;
}

/* The file header: sizes checked, counts returned. */
typedef struct {
    size_t header_size, fib, n_surfaces, first_surface, n_series, first_series;
} gio_header;

static thx_status read_header(gio *g, gio_header *h)
{
    memset(h, 0, sizeof *h);
    if (g->len < 40)
        return gerr(g, 0, "the file is %zu bytes, shorter than the 40-byte graphicsio header (truncated, or not a "
                          "map3d .geom/.tsdf file)", g->len);
    long hs = i32(g, 0);
    if (hs != 40 && hs != 44)
        return gerr(g, 0, "header size %ld: not a map3d graphicsio (.geom/.tsdf) file (40 or 44 expected)", hs);
    if ((size_t)hs > g->len) return gerr(g, 0, "header size %ld is beyond the end of the file (%zu bytes)", hs, g->len);
    h->header_size = (size_t)hs;
    long ns = i32(g, 12), nt = i32(g, 28);
    if (ns < 0 || (size_t)ns > g->len / 20)
        return gerr(g, 12, "surface count %ld is impossible in a file of %zu bytes", ns, g->len);
    if (nt < 0 || (size_t)nt > g->len / 308)
        return gerr(g, 28, "time series count %ld is impossible in a file of %zu bytes", nt, g->len);
    h->n_surfaces = (size_t)ns;
    h->n_series = (size_t)nt;
    if (ns) THX_CHECK(link_to(g, 16, 20, "the first surface header", &h->first_surface));
    if (nt) THX_CHECK(link_to(g, 32, 4, "the first time series header", &h->first_series));
    if (i32(g, 8) != 0) THX_CHECK(link_to(g, 8, 428, "the file info block", &h->fib));
    return THX_OK;
}

/* Which of n (1-based): select NULL/"" (n must be 1), digits, or a name matched by name_of. */
static thx_status pick(gio *g, const char *select, size_t n, const char *kind, const char *by,
                       void (*name_of)(gio *, size_t, void *, char *, size_t), void *user, size_t *which)
{
    const char *plural = kind[strlen(kind) - 1] == 's' ? "" : "s"; /* "surfaces", "time series" */
    if (!select || !*select) {
        if (n == 1) {
            *which = 1;
            return THX_OK;
        }
        return thx_error(g->ctx, THX_EINPUT, "%s: holds %zu %s%s: pick one as %s@1 .. %s@%zu (or @%s)", g->path, n,
                         kind, plural, g->path, g->path, n, by);
    }
    size_t k = strspn(select, "0123456789");
    if (!select[k]) {
        errno = 0;
        unsigned long long v = strtoull(select, NULL, 10);
        if (errno || v < 1 || v > n)
            return thx_error(g->ctx, THX_EINPUT, "%s@%s: the file holds %zu %s%s (1..%zu)", g->path, select, n, kind,
                             n == 1 ? "" : plural, n);
        *which = (size_t)v;
        return THX_OK;
    }
    for (size_t i = 1; i <= n; i++) {
        char nm[260];
        name_of(g, i, user, nm, sizeof nm);
        if (nm[0] && !strcmp(nm, select)) {
            *which = i;
            return THX_OK;
        }
    }
    return thx_error(g->ctx, THX_EINPUT, "%s@%s: no %s of that %s (the file holds %zu; pick by number, @1 .. @%zu)",
                     g->path, select, kind, by, n, n);
}

/* ------------------------------------------------------------------ .geom */

typedef struct {
    size_t *at;   /* surface header offsets */
    size_t *info; /* surface info block offsets (0: none) */
} geom_walk;

static void surface_name(gio *g, size_t i, void *user, char *dst, size_t cap)
{
    geom_walk *w = user;
    dst[0] = '\0';
    if (w->info[i - 1]) text_field(g, w->info[i - 1] + 4, 80, dst, cap);
}

/* The blocks of surface k (1-based) whose header is at `at`, checked against the file: its nodes
 * (nn x 3 reals at *nodes) and triangles (ne x 3 longs at *elems). */
static thx_status surface_blocks(gio *g, size_t at, size_t k, long *nn, size_t *nodes, long *ne, size_t *elems)
{
    size_t nh = 0, eh = 0;
    THX_CHECK(link_to(g, at + 8, 12, "the node header", &nh));
    *nn = i32(g, nh + 4);
    if (*nn < 1 || (size_t)*nn > g->len / 12)
        return gerr(g, nh + 4, "surface %zu: node count %ld is impossible in a file of %zu bytes", k, *nn, g->len);
    THX_CHECK(link_to(g, nh + 8, (size_t)*nn * 12, "the nodes", nodes));
    if (i32(g, at + 12) == 0) return gerr(g, at + 12, "surface %zu has no elements (nodes only: not a surface)", k);
    THX_CHECK(link_to(g, at + 12, 16, "the element header", &eh));
    *ne = i32(g, eh + 4);
    long es = i32(g, eh + 8);
    if (es != 3)
        return gerr(g, eh + 8, "surface %zu: elements of %ld nodes%s; only triangles (3) make a surface", k, es,
                    es == 2 ? " (line segments)" : es == 4 ? " (tetrahedra: a volume)" : "");
    if (*ne < 1 || (size_t)*ne > g->len / 12)
        return gerr(g, eh + 4, "surface %zu: triangle count %ld is impossible in a file of %zu bytes", k, *ne, g->len);
    return link_to(g, eh + 12, (size_t)*ne * 12, "the triangles", elems);
}

thx_status thx_geom_parse(thx_ctx *ctx, const char *path, const unsigned char *buf, size_t len, const char *select,
                          const char *name, thx_role role, thx_surface **out, thx_geom_info *info)
{
    *out = NULL;
    if (info) memset(info, 0, sizeof *info);
    gio g = {ctx, path, buf, len};
    gio_header h;
    THX_CHECK(read_header(&g, &h));
    if (h.n_surfaces == 0)
        return gerr(&g, 12, "the file holds no surface%s", h.n_series ? " but time series (a .tsdf file?)" : "");
    geom_walk w = {thx_calloc(ctx, h.n_surfaces, sizeof(size_t)), thx_calloc(ctx, h.n_surfaces, sizeof(size_t))};
    thx_status st = (w.at && w.info) ? THX_OK : THX_ENOMEM;
    size_t at = h.first_surface;
    for (size_t k = 0; st == THX_OK && k < h.n_surfaces; k++) {
        /* SurfaceHeader: size, next, node header, element header, info block */
        w.at[k] = at;
        long hs = i32(&g, at);
        if (hs < 20) {
            st = gerr(&g, at, "surface %zu: header size %ld (at least 20 expected)", k + 1, hs);
            break;
        }
        if (i32(&g, at + 16) != 0) st = link_to(&g, at + 16, 88, "the surface info block", &w.info[k]);
        /* every surface's blocks inside the file, not only the one picked: a file is read whole or not at all */
        long nn, ne;
        size_t nodes, elems;
        if (st == THX_OK) st = surface_blocks(&g, at, k + 1, &nn, &nodes, &ne, &elems);
        if (st == THX_OK && k + 1 < h.n_surfaces) st = link_to(&g, at + 4, 20, "the next surface header", &at);
    }
    size_t which = 0;
    if (st == THX_OK) st = pick(&g, select, h.n_surfaces, "surface", "NAME", surface_name, &w, &which);
    thx_surface *s = NULL;
    if (st == THX_OK) {
        at = w.at[which - 1];
        if (info) {
            info->n_surfaces = h.n_surfaces;
            info->index = which;
            surface_name(&g, which, &w, info->file_name, sizeof info->file_name);
            if (h.fib) text_field(&g, h.fib + 172, 256, info->text, sizeof info->text);
        }
        size_t nodes = 0, elems = 0;
        long nn = 0, ne = 0;
        st = surface_blocks(&g, at, which, &nn, &nodes, &ne, &elems);
        char nm[80];
        if (!name || !*name) {
            surface_name(&g, which, &w, nm, sizeof nm);
            if (!nm[0]) snprintf(nm, sizeof nm, "surface%zu", which);
            name = nm;
        }
        if (st == THX_OK) st = thx_surface_create(ctx, name, role, &s);
        if (st == THX_OK) {
            s->xyz = thx_malloc(ctx, (size_t)nn * 3 * sizeof *s->xyz);
            s->tri = thx_malloc(ctx, (size_t)ne * 3 * sizeof *s->tri);
            if (!s->xyz || !s->tri) st = THX_ENOMEM;
        }
        for (size_t i = 0; st == THX_OK && i < 3 * (size_t)nn; i++)
            if (vax_f(buf + nodes + 4 * i, &s->xyz[i]) != 0)
                st = gerr(&g, nodes + 4 * i, "surface %zu: node %zu: coordinate %c is a VAX reserved operand (not a number)",
                          which, i / 3 + 1, "xyz"[i % 3]);
        for (size_t i = 0; st == THX_OK && i < 3 * (size_t)ne; i++) {
            long v = i32(&g, elems + 4 * i);
            if (v < 1 || v > nn)
                st = gerr(&g, elems + 4 * i, "surface %zu: triangle %zu: node number %ld out of range 1..%ld (1-based)",
                          which, i / 3 + 1, v, nn);
            else
                s->tri[i] = (int32_t)(v - 1);
        }
        if (st == THX_OK) {
            s->n_nodes = (size_t)nn;
            s->n_tris = (size_t)ne;
        }
    }
    free(w.at);
    free(w.info);
    if (st != THX_OK) {
        thx_surface_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}

/* ------------------------------------------------------------------ .tsdf */

static void series_label(gio *g, size_t i, void *user, char *dst, size_t cap)
{
    text_field(g, ((size_t *)user)[i - 1] + 212, 80, dst, cap);
}

thx_status thx_tsdf_parse(thx_ctx *ctx, const char *path, const unsigned char *buf, size_t len, const char *select,
                          thx_series **out)
{
    *out = NULL;
    gio g = {ctx, path, buf, len};
    gio_header h;
    THX_CHECK(read_header(&g, &h));
    if (h.n_series == 0)
        return gerr(&g, 28, "the file holds no time series%s", h.n_surfaces ? " but surfaces (a .geom file?)" : "");
    size_t *at = thx_calloc(ctx, h.n_series, sizeof *at);
    if (!at) return THX_ENOMEM;
    thx_status st = THX_OK;
    size_t p = h.first_series;
    for (size_t k = 0; st == THX_OK && k < h.n_series; k++) {
        at[k] = p;
        long hs = i32(&g, p);
        if (hs < 308 || hs > 4096)
            st = gerr(&g, p, "time series %zu: header size %ld (308 to 336 expected: not a .tsdf header)", k + 1, hs);
        else if (!inside(&g, p, (size_t)hs))
            st = gerr(&g, p, "time series %zu: its %ld-byte header runs past the end of the file (%zu bytes)", k + 1, hs, len);
        else {
            /* every series' data inside the file, not only the one picked */
            long nch = i32(&g, p + 92), nfr = i32(&g, p + 96);
            size_t es = (hs >= 328 && i32(&g, p + 324) == 0) ? 2 : 4, data = 0;
            char ext[81];
            text_field(&g, p + 132, 80, ext, sizeof ext);
            if (nch < 1 || nfr < 1)
                st = gerr(&g, p + 92, "time series %zu: %ld channels x %ld frames (at least 1 x 1 needed)", k + 1, nch, nfr);
            else if ((size_t)nfr > len / es / (size_t)nch)
                st = gerr(&g, p + 92, "time series %zu: %ld channels x %ld frames of %zu bytes cannot fit in a file of %zu "
                                      "bytes", k + 1, nch, nfr, es, len);
            else if (!ext[0])
                st = link_to(&g, p + 100, (size_t)nch * (size_t)nfr * es, "the data", &data);
        }
        if (st == THX_OK && k + 1 < h.n_series) st = link_to(&g, p + 4, 4, "the next time series header", &p);
    }
    size_t which = 0;
    if (st == THX_OK) st = pick(&g, select, h.n_series, "time series", "LABEL", series_label, at, &which);
    thx_series *s = NULL;
    if (st == THX_OK) {
        size_t t = at[which - 1], hs = (size_t)i32(&g, t);
        char ext[81];
        text_field(&g, t + 132, 80, ext, sizeof ext);
        long nch = i32(&g, t + 92), nfr = i32(&g, t + 96);
        size_t es = 4;
        if (hs >= 328) {
            long sf = i32(&g, t + 324);
            if (sf == 0) es = 2;
            else if (sf != 1) st = gerr(&g, t + 324, "time series %zu: storage format %ld (0 integers, 1 reals)", which, sf);
        }
        size_t data = 0;
        if (st == THX_OK && ext[0])
            st = gerr(&g, t + 132, "time series %zu: its data are in the external file '%s' (a raw/pak tape), which is "
                                   "not read", which, ext);
        if (st == THX_OK && (nch < 1 || nfr < 1))
            st = gerr(&g, t + 92, "time series %zu: %ld channels x %ld frames (at least 1 x 1 needed)", which, nch, nfr);
        if (st == THX_OK && (size_t)nfr > len / es / (size_t)nch)
            st = gerr(&g, t + 92, "time series %zu: %ld channels x %ld frames of %zu bytes cannot fit in a file of %zu "
                                  "bytes", which, nch, nfr, es, len);
        if (st == THX_OK) st = link_to(&g, t + 100, (size_t)nch * (size_t)nfr * es, "the data", &data);
        if (st == THX_OK) st = thx_series_create(ctx, (size_t)nch, (size_t)nfr, &s);
        size_t n = st == THX_OK ? (size_t)nch * (size_t)nfr : 0;
        for (size_t i = 0; st == THX_OK && i < n; i++) {
            /* frame-major in the file, as the series holds them: v[f * rows + r] */
            if (es == 2) {
                const unsigned char *q = buf + data + 2 * i;
                s->v[i] = (double)(int16_t)(uint16_t)(q[0] | q[1] << 8);
            } else if (vax_f(buf + data + 4 * i, &s->v[i]) != 0) {
                st = gerr(&g, data + 4 * i, "time series %zu: channel %zu, frame %zu is a VAX reserved operand (not a "
                                            "number)", which, i % (size_t)nch + 1, i / (size_t)nch + 1);
            }
        }
        if (st == THX_OK) {
            for (size_t f = 0; f < s->n_frames; f++) s->time[f] = (double)f;
            snprintf(s->time_unit, sizeof s->time_unit, "frame");
            static const char *const units[] = {"", "mV", "uV", "ms", "V", "mV ms"};
            long u = i32(&g, t + 300);
            if (u >= 0 && u <= 5) snprintf(s->unit, sizeof s->unit, "%s", units[u]);
            else thx_log(ctx, THX_LOG_WARN, "%s: byte %zu: data units %ld unknown (1 mV, 2 uV, 3 ms, 4 V, 5 mV ms)", path, t + 300, u);
            text_field(&g, t + 212, 80, s->label, sizeof s->label);
            if (!s->label[0] && h.fib) text_field(&g, h.fib + 172, 256, s->label, sizeof s->label);
            /* global fiducials, 1-based frames in the file (0 = not set) */
            static const struct { size_t off; int type; } fid[] = {{308, 0}, {312, 1}, {108, 2}, {316, 3}, {112, 4}, {320, 6}, {116, 7}};
            for (size_t k = 0; st == THX_OK && k < sizeof fid / sizeof fid[0]; k++) {
                if (fid[k].off + 4 > hs) continue;
                long v = i32(&g, t + fid[k].off);
                if (v == 0) continue;
                double x = (double)v - 1.0;
                st = thx_series_add_fiducial(ctx, s, fid[k].type, 0, 1, &x);
            }
            if (hs >= 336 && i32(&g, t + 332) > 0)
                thx_log(ctx, THX_LOG_WARN, "%s: byte %zu: time series %zu: %ld lead fiducial sets not read", path, t + 332,
                        which, i32(&g, t + 332));
        }
        if (st == THX_OK) st = thx_series_validate(ctx, s, path);
    }
    free(at);
    if (st != THX_OK) {
        thx_series_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}

int thx_gio_split_select(const char *path, const char *ext, char *file, size_t cap, const char **sel)
{
    *sel = NULL;
    if (strlen(path) >= cap) return -1;
    snprintf(file, cap, "%s", path);
    struct stat sb;
    if (stat(path, &sb) == 0) return 0;
    char *at = strrchr(file, '@');
    if (!at || strchr(at, '/')) return 0;
    size_t n = (size_t)(at - file), e = strlen(ext);
    if (n < e + 1 || file[n - e - 1] != '.' || strncasecmp(file + n - e, ext, e) != 0) return 0;
    *at = '\0';
    *sel = path + n + 1;
    return 0;
}
