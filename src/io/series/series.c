/*
 * Time series files: formats by name and the dispatch to the readers and
 * writers of each format (series_text.c, series_raw.c, series_mat.c,
 * series_pot.c); see thorax/io/series_file.h; docs/formats.md, "Time
 * series", is the specification.
 *
 * Decisions recorded here:
 *
 *  - Every reader ends with the same checks as the writers start with
 *    (thx_series_validate, src/model/series.c): at least one row and one frame, a finite, strictly
 *    increasing time axis, NUL-terminated strings. So whatever is written
 *    reads back, and whatever is read can be written in any format.
 *
 *  - Messages count rows and frames from 1, like the lines of a text file.
 */
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
#include "thorax/io/graphicsio.h"
#include "io/series/series_impl.h"

int thx_series_format_parse(const char *name, thx_series_format *fmt)
{
    static const struct { const char *name; thx_series_format f; } tab[] = {
        {"auto", THX_SERIES_AUTO}, {"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
        {"pot", THX_SERIES_POT}, {"tsdf", THX_SERIES_TSDF}, {"csv", THX_SERIES_CSV}, {"matrix", THX_SERIES_MATRIX}};
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
    static const char *const names[] = {"auto", "text", "raw", "mat", "pot", "tsdf", "csv", "matrix"};
    return (unsigned)f < sizeof names / sizeof names[0] ? names[f] : "unknown";
}

/* The time axis of `dt` files: one expression, shared by writer and reader so
 * that the writer's "is this axis uniform?" test predicts the reader's bits. */

/* What every series must satisfy to be written, and satisfies once read. */
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
    if (!strcasecmp(e, "tsdf")) return THX_SERIES_TSDF;
    if (!strcasecmp(e, "csv")) return THX_SERIES_CSV;
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
    if (f == THX_SERIES_AUTO || f == THX_SERIES_POT || f == THX_SERIES_TSDF || f == THX_SERIES_MATRIX) return -1;
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
    /* graphicsio: header size 40 or 44 (little-endian), and the info block right after it */
    if (n >= 12 && (b[0] == 40 || b[0] == 44) && !b[1] && !b[2] && !b[3] && !memcmp(b, b + 8, 4)) return THX_SERIES_TSDF;
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
    if (n - i >= 17 && memcmp(b + i, "thorax-series-csv", 17) == 0) return THX_SERIES_MATRIX;
    if (n - i >= 13 && memcmp(b + i, "thorax-series", 13) == 0) return THX_SERIES_TEXT;
    /* a plain matrix: its first cell is a number (or a header cell followed by a comma) */
    if (i < n && (isdigit((unsigned char)b[i]) || strchr("+-.", b[i]) || !strncasecmp(b + i, "nan", 3))) return THX_SERIES_MATRIX;
    return THX_SERIES_AUTO;
}

thx_status thx_series_read(thx_ctx *ctx, const char *path, thx_series_format fmt, thx_series **out)
{
    *out = NULL;
    struct stat sd;
    int exists = stat(path, &sd) == 0;
    if ((fmt == THX_SERIES_AUTO || fmt == THX_SERIES_POT) &&
        ((exists && S_ISDIR(sd.st_mode)) || (!exists && strchr(path, '%'))))
        return series_read_pot_set(ctx, path, out);
    {
        char gfile[4096];
        const char *sel = NULL;
        if (thx_gio_split_select(path, "tsdf", gfile, sizeof gfile, &sel) != 0)
            return thx_error(ctx, THX_EIO, "%s: path too long", path);
        const char *e = extension(gfile);
        if (!strcasecmp(e, "tsdfc"))
            return thx_error(ctx, THX_EINPUT,
                             "%s: .tsdfc (map3d's container of fiducial sets, a GDBM database keyed by .tsdf names) is "
                             "not read: its layout is GDBM's own, host-dependent, and no file exists to check a reader "
                             "against; read the .tsdf, and its fiducials from a .fids or .mat file",
                             gfile);
        if (fmt == THX_SERIES_TSDF || (fmt == THX_SERIES_AUTO && (sel || format_of_extension(gfile) == THX_SERIES_TSDF ||
                                                                  format_of_content(gfile) == THX_SERIES_TSDF))) {
            char *buf = NULL;
            size_t len = 0;
            THX_CHECK(thx_read_file(ctx, gfile, &buf, &len));
            thx_status st = thx_tsdf_parse(ctx, gfile, (const unsigned char *)buf, len, sel, out);
            free(buf);
            return st;
        }
    }
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
        thx_series_format byext = format_of_extension(file);
        /* numbers first: a matrix, unless the extension names a format (.pot) other than text */
        if (fmt == THX_SERIES_MATRIX && byext != THX_SERIES_AUTO && byext != THX_SERIES_TEXT && byext != THX_SERIES_CSV)
            fmt = byext;
        if (fmt == THX_SERIES_AUTO) fmt = byext;
        if (fmt == THX_SERIES_CSV) fmt = THX_SERIES_MATRIX;
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
    case THX_SERIES_TEXT: return series_read_text(ctx, file, out);
    case THX_SERIES_RAW: return series_read_raw(ctx, file, out);
    case THX_SERIES_MAT: return series_read_mat(ctx, file, varname, out);
    case THX_SERIES_POT: return series_read_pot(ctx, file, out);
    case THX_SERIES_CSV:
    case THX_SERIES_MATRIX: return series_read_matrix(ctx, file, out);
    default: return thx_error(ctx, THX_EINPUT, "%s: unknown series format %d", file, (int)fmt);
    }
}

thx_status thx_series_write(thx_ctx *ctx, const thx_series *s, const char *path, thx_series_format fmt)
{
    if (fmt == THX_SERIES_AUTO) {
        fmt = format_of_extension(path);
        if (fmt == THX_SERIES_AUTO)
            return thx_error(ctx, THX_EINPUT,
                             "%s: cannot tell the series format from the extension '%s' (.txt, .dat, .raw, "
                             ".mat or .csv; or give the format)",
                             path, extension(path));
    }
    if (fmt == THX_SERIES_POT || fmt == THX_SERIES_TSDF || fmt == THX_SERIES_MATRIX)
        return thx_error(ctx, THX_EINPUT, "%s: %s files are read, not written (write .txt, .raw, .mat or .csv)", path,
                         format_name(fmt));
    THX_CHECK(thx_series_validate(ctx, s, path));
    switch (fmt) {
    case THX_SERIES_TEXT: return series_write_text(ctx, s, path);
    case THX_SERIES_RAW: return series_write_raw(ctx, s, path);
    case THX_SERIES_MAT: return series_write_mat(ctx, s, path);
    case THX_SERIES_CSV: return series_write_csv(ctx, s, path);
    default: return thx_error(ctx, THX_EINPUT, "%s: unknown series format %d (%s)", path, (int)fmt, format_name(fmt));
    }
}

thx_status thx_series_transpose(thx_ctx *ctx, thx_series **sp)
{
    thx_series *a = *sp, *b = NULL;
    THX_CHECK(thx_series_create(ctx, a->n_frames, a->n_rows, &b));
    for (size_t r = 0; r < a->n_rows; r++)
        for (size_t f = 0; f < a->n_frames; f++) b->v[r * b->n_rows + f] = a->v[f * a->n_rows + r];
    snprintf(b->unit, sizeof b->unit, "%s", a->unit);
    snprintf(b->label, sizeof b->label, "%s", a->label);
    snprintf(b->time_unit, sizeof b->time_unit, "frame");
    for (size_t k = 0; k < a->n_fids; k++)
        if (a->fids[k].n == 1) {
            thx_status st = thx_series_add_fiducial(ctx, b, a->fids[k].type, a->fids[k].fidset, 1, a->fids[k].v);
            if (st != THX_OK) {
                thx_series_destroy(&b);
                return st;
            }
        }
    thx_series_destroy(sp);
    *sp = b;
    return THX_OK;
}
