/*
 * Time series, raw binary format (series.c has the dispatch).
 *
 * Decisions recorded here:
 *
 *  - Raw files are written and read with explicit little-endian byte order;
 *    on a little-endian host the arrays go through fwrite/fread directly. The
 *    file size must equal the header's sizes exactly, so truncation and
 *    trailing bytes are both caught before anything is allocated.
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

#define RAW_MAGIC "THXSER01"
#define RAW_HEADER 200 /* 8 magic + 8 rows + 8 frames + 32 unit + 16 time_unit + 128 label */

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

thx_status series_write_raw(thx_ctx *ctx, const thx_series *s, const char *path)
{
    unsigned char h[RAW_HEADER];
    memset(h, 0, sizeof h);
    memcpy(h, RAW_MAGIC, 8);
    put_u64le(h + 8, (uint64_t)s->n_rows);
    put_u64le(h + 16, (uint64_t)s->n_frames);
    memcpy(h + 24, s->unit, strlen(s->unit));           /* < 32: checked NUL-terminated */
    memcpy(h + 56, s->time_unit, strlen(s->time_unit)); /* < 16 */
    memcpy(h + 72, s->label, strlen(s->label));         /* < 128 */
    thx_atomic_file af; /* an existing file is replaced only when it is thorax's raw series (thorax/core/fileio.h) */
    THX_CHECK(thx_atomic_open_output(ctx, path, RAW_MAGIC, 8, NULL, 0, &af));
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
        return thx_error(ctx, THX_EINPUT, "%s: bytes %zu-%zu: the %s field has no terminating NUL byte", path, off,
                         off + size - 1, name);
    memcpy(dst, h + off, size);
    return THX_OK;
}

thx_status series_read_raw(thx_ctx *ctx, const char *path, thx_series **out)
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
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 0: not a thorax raw series (the file does not start with \"%s\")", path,
                       RAW_MAGIC);
        goto done;
    }
    if (got >= 8 && memcmp(h, RAW_MAGIC, 8) != 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset 6: raw series version '%c%c' is not supported (this reader knows \"%s\")",
                       path, h[6] >= ' ' && h[6] < 127 ? h[6] : '?', h[7] >= ' ' && h[7] < 127 ? h[7] : '?',
                       RAW_MAGIC);
        goto done;
    }
    if (got < sizeof h) {
        st = thx_error(ctx, THX_EINPUT, "%s: byte offset %llu: truncated: the file ends inside the %d-byte raw series header", path,
                       size, RAW_HEADER);
        goto done;
    }
    uint64_t rows = get_u64le(h + 8), frames = get_u64le(h + 16);
    if (rows == 0 || frames == 0) {
        st = thx_error(ctx, THX_EINPUT, "%s: bytes 8-23: empty series in the header (%llu rows x %llu frames)", path,
                       (unsigned long long)rows, (unsigned long long)frames);
        goto done;
    }
    /* expected size = 200 + 8 frames (rows + 1), without overflow */
    uint64_t lim = (UINT64_MAX - RAW_HEADER) / 8;
    if (rows >= lim || frames > lim / (rows + 1) || rows > SIZE_MAX || frames > SIZE_MAX) {
        st = thx_error(ctx, THX_EINPUT, "%s: bytes 8-23: impossible sizes in the header (%llu rows x %llu frames)", path,
                       (unsigned long long)rows, (unsigned long long)frames);
        goto done;
    }
    uint64_t want = RAW_HEADER + 8 * frames * (rows + 1);
    if (size != want) {
        st = thx_error(ctx, THX_EINPUT,
                       "%s: byte offset %llu: %s: %llu rows x %llu frames take %llu bytes (header %d + 8 x frames x "
                       "(rows + 1)), the file has %llu",
                       path, size < want ? size : want, size < want ? "truncated (the file ends here)" : "trailing bytes after the data",
                       (unsigned long long)rows, (unsigned long long)frames, (unsigned long long)want, RAW_HEADER, size);
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
    /* the time axis, with the byte offset of a bad time (thx_series_validate would give the frame only) */
    for (size_t k = 0; k < s->n_frames; k++)
        if (!isfinite(s->time[k]) || (k && !(s->time[k] > s->time[k - 1]))) {
            st = thx_error(ctx, THX_EINPUT, "%s: byte offset %zu: time of frame %zu is %.17g: %s", path,
                           (size_t)RAW_HEADER + 8 * k, k + 1, s->time[k],
                           isfinite(s->time[k]) ? "not after the previous one (times must increase)" : "not finite");
            goto done;
        }
    st = thx_series_validate(ctx, s, path);
done:
    fclose(f);
    if (st != THX_OK) thx_series_destroy(&s);
    *out = s;
    return st;
}

