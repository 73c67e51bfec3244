/*
 * Tests of the time series files (src/io/series/series.c, thorax/model/series.h):
 * round trips through text, raw and .mat (values, times, units and label;
 * NaN and infinities), byte-identical output, every malformed input refused
 * with the file, line and fault named and nothing written, .mat files made
 * here through libmatio in the shapes other programs write (a struct holding
 * potvals, integer matrices, named variables), the real map3d recording
 * shared/data/map3d/data/tank/cool1-atdr-run1.mat, and the speed of a
 * 5000 x 1000 series.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <matio.h>
#include <zlib.h>

#include "testlib.h"
#include "thorax/core/fileio.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

/* Bitwise equality of doubles, NaN equal to NaN (payloads aside). */
static int same_double(double a, double b)
{
    if (isnan(a) || isnan(b)) return isnan(a) && isnan(b);
    return a == b && signbit(a) == signbit(b);
}

static int same_series(const thx_series *a, const thx_series *b)
{
    if (!a || !b || a->n_rows != b->n_rows || a->n_frames != b->n_frames) return 0;
    for (size_t f = 0; f < a->n_frames; f++)
        if (!same_double(a->time[f], b->time[f])) {
            fprintf(stderr, "time[%zu]: %.17g vs %.17g\n", f, a->time[f], b->time[f]);
            return 0;
        }
    for (size_t i = 0; i < a->n_rows * a->n_frames; i++)
        if (!same_double(a->v[i], b->v[i])) {
            fprintf(stderr, "v[%zu]: %.17g vs %.17g\n", i, a->v[i], b->v[i]);
            return 0;
        }
    if (strcmp(a->unit, b->unit) || strcmp(a->time_unit, b->time_unit) || strcmp(a->label, b->label)) {
        fprintf(stderr, "strings: '%s' '%s' '%s' vs '%s' '%s' '%s'\n", a->unit, a->time_unit, a->label, b->unit,
                b->time_unit, b->label);
        return 0;
    }
    return 1;
}

/* A read that must fail with `code` and a message holding every given part. */
static void expect_read_fail(const char *path, thx_series_format fmt, thx_status code, const char *part1,
                             const char *part2)
{
    thx_series *s = (thx_series *)&s; /* must come back NULL */
    thx_ctx_clear(ctx);
    thx_status st = thx_series_read(ctx, path, fmt, &s);
    const char *msg = thx_ctx_message(ctx);
    int ok = st == code && s == NULL && (!part1 || strstr(msg, part1)) && (!part2 || strstr(msg, part2));
    CHECK(ok);
    if (!ok) fprintf(stderr, "  reading %s: status %d (want %d), message \"%s\", want \"%s\" and \"%s\"\n", path,
                     (int)st, (int)code, msg, part1 ? part1 : "", part2 ? part2 : "");
    if (st == THX_OK && s != (thx_series *)&s) thx_series_destroy(&s);
}

/* A text file that must be refused: "NAME:LINE: ..." holding `what`. */
static void bad_text(const char *name, const char *text, int line, const char *what)
{
    tl_write_text(tl_path(name), text);
    char where[2300];
    snprintf(where, sizeof where, "%s:%d: ", tl_path(name), line);
    expect_read_fail(tl_path(name), THX_SERIES_AUTO, THX_EINPUT, where, what);
}

/* 3 rows x 5 frames with awkward values, NaN and infinities, a non-uniform time axis. */
static thx_series *sample(void)
{
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 3, 5, &s));
    if (!s) exit(1);
    const double vals[15] = {0.1,     -1e-300,  1e300,   123456789012345678.0, M_PI, -0.0, 1.0 / 3, 2.5e-7,
                             -7.0,    1e15,     NAN,     1e-320, /* subnormal */ 42.0, -INFINITY, INFINITY};
    /* v[f * 3 + r]: NaN at row 1 frame 3, -Inf at row 1 frame 4, +Inf at row 2 frame 4 (0-based) */
    memcpy(s->v, vals, sizeof vals);
    const double t[5] = {0, 0.5, 1.25, 2, 10};
    memcpy(s->time, t, sizeof t);
    snprintf(s->unit, sizeof s->unit, "mV");
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    snprintf(s->label, sizeof s->label, "ecg run #3: lead II  (x)");
    return s;
}

/* ------------------------------------------------------------- tests */

static void test_create(void)
{
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 4, 3, &s));
    CHECK(s && s->n_rows == 4 && s->n_frames == 3);
    if (!s) return;
    int zero = 1;
    for (size_t i = 0; i < 12; i++) zero &= s->v[i] == 0;
    CHECK(zero);
    CHECK(s->time[0] == 0 && s->time[1] == 1 && s->time[2] == 2);
    CHECK(strcmp(s->time_unit, "ms") == 0 && s->unit[0] == '\0' && s->label[0] == '\0');
    size_t r = 99, f = 99;
    CHECK(thx_series_find_nonfinite(s, &r, &f) == 0 && r == 99 && f == 99);
    s->v[2 * 4 + 3] = NAN;     /* row 3, frame 2 (0-based) */
    s->v[1 * 4 + 2] = INFINITY; /* row 2, frame 1: earlier in memory */
    CHECK(thx_series_find_nonfinite(s, &r, &f) == 2 && r == 2 && f == 1);
    CHECK(thx_series_find_nonfinite(s, NULL, NULL) == 2);
    thx_series_destroy(&s);
    CHECK(s == NULL);
    thx_series_destroy(&s); /* NULL accepted */
    thx_series_destroy(NULL);

    thx_series_format fmt = THX_SERIES_TEXT;
    CHECK(thx_series_format_parse("raw", &fmt) == 0 && fmt == THX_SERIES_RAW);
    CHECK(thx_series_format_parse("mat", &fmt) == 0 && fmt == THX_SERIES_MAT);
    CHECK(thx_series_format_parse("text", &fmt) == 0 && fmt == THX_SERIES_TEXT);
    CHECK(thx_series_format_parse("auto", &fmt) == 0 && fmt == THX_SERIES_AUTO);
    CHECK(thx_series_format_parse("xml", &fmt) == -1 && thx_series_format_parse(NULL, &fmt) == -1);

    /* too large to allocate: refused, not overflowed */
    CHECK(thx_series_create(ctx, SIZE_MAX / 4, 3, &s) == THX_EINPUT && s == NULL);
}

static void test_round_trips(void)
{
    thx_series *s = sample();
    size_t r = 0, f = 0;
    CHECK(thx_series_find_nonfinite(s, &r, &f) == 3 && r == 1 && f == 3);
    const char *names[3] = {"rt.txt", "rt.raw", "rt.mat"};
    const thx_series_format fmts[3] = {THX_SERIES_TEXT, THX_SERIES_RAW, THX_SERIES_MAT};
    for (int k = 0; k < 3; k++) {
        CHECK_OK(ctx, thx_series_write(ctx, s, tl_path(names[k]), THX_SERIES_AUTO));
        thx_series *b = NULL;
        CHECK_OK(ctx, thx_series_read(ctx, tl_path(names[k]), THX_SERIES_AUTO, &b));
        CHECK(same_series(s, b));
        thx_series_destroy(&b);
        /* the format given explicitly, and the content recognized under another name */
        CHECK_OK(ctx, thx_series_read(ctx, tl_path(names[k]), fmts[k], &b));
        CHECK(same_series(s, b));
        thx_series_destroy(&b);
        char other[64];
        snprintf(other, sizeof other, "rt%d.bin", k);
        CHECK_OK(ctx, thx_series_write(ctx, s, tl_path(other), fmts[k]));
        CHECK_OK(ctx, thx_series_read(ctx, tl_path(other), THX_SERIES_AUTO, &b));
        CHECK(same_series(s, b));
        thx_series_destroy(&b);
        /* determinism: byte-identical files */
        char again[64];
        snprintf(again, sizeof again, "rt_again%d.%s", k, k == 0 ? "txt" : k == 1 ? "raw" : "mat");
        CHECK_OK(ctx, thx_series_write(ctx, s, tl_path(again), fmts[k]));
        size_t n1 = 0, n2 = 0;
        char *t1 = tl_slurp(ctx, tl_path(names[k]), &n1), *t2 = tl_slurp(ctx, tl_path(again), &n2);
        CHECK(t1 && t2 && n1 == n2 && memcmp(t1, t2, n1) == 0);
        free(t1);
        free(t2);
    }
    /* the text is readable: the shortest exact decimals, the time axis as written */
    char *t = tl_slurp(ctx, tl_path("rt.txt"), NULL);
    CHECK(t && strstr(t, "thorax-series 1\nrows 3\nframes 5\nunit mV\ntime_unit ms\n"));
    CHECK(t && strstr(t, "\nlabel ecg run #3: lead II  (x)\n"));
    CHECK(t && strstr(t, "\ntime 0 0.5 1.25 2 10\n"));
    CHECK(t && strstr(t, "\n0.1 1.2345678901234568e+17 0.3333333333333333 1e+15 42\n"));
    CHECK(t && strstr(t, "\n-1e-300 3.141592653589793 2.5e-07 nan -inf\n"));
    CHECK(t && strstr(t, "\n1e+300 -0 -7 ") && strstr(t, " inf\nend\n"));
    free(t);
    /* raw: the size is exactly header + 8 x frames x (rows + 1) */
    struct stat st;
    CHECK(stat(tl_path("rt.raw"), &st) == 0 && st.st_size == 200 + 8 * 5 * 4);
    thx_series_destroy(&s);
    CHECK(!tl_leftover_tmp(""));
}

static void test_text_variants(void)
{
    /* a uniform axis is written as t0 + dt and read back bit for bit */
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 2, 1000, &s));
    for (size_t f = 0; f < 1000; f++) s->time[f] = -5 + (double)f * 0.1; /* time[1] - time[0] is not 0.1 */
    for (size_t i = 0; i < 2000; i++) s->v[i] = sin((double)i) * 1e3;
    s->time_unit[0] = '\0'; /* none */
    CHECK_OK(ctx, thx_series_write(ctx, s, tl_path("uni.txt"), THX_SERIES_AUTO));
    char *t = tl_slurp(ctx, tl_path("uni.txt"), NULL);
    CHECK(t && strstr(t, "\nt0 -5\ndt 0.1\n") && !strstr(t, "\ntime ") && strstr(t, "\ntime_unit\n") &&
          !strstr(t, "\nunit"));
    free(t);
    thx_series *b = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("uni.txt"), THX_SERIES_AUTO, &b));
    CHECK(same_series(s, b));
    thx_series_destroy(&b);
    /* control characters in a label become blanks, outer blanks go */
    snprintf(s->label, sizeof s->label, "  two\nlines\there  ");
    CHECK_OK(ctx, thx_series_write(ctx, s, tl_path("lab.txt"), THX_SERIES_TEXT));
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("lab.txt"), THX_SERIES_AUTO, &b));
    CHECK(b && strcmp(b->label, "two lines here") == 0);
    thx_series_destroy(&b);
    thx_series_destroy(&s);

    /* what a person may write: comments, blank lines, CRLF, several time lines,
     * any keyword order, NaN and infinities in any spelling strtod knows */
    tl_write_text(tl_path("hand.dat"),
               "# recorded by hand\r\n"
               "\r\n"
               "thorax-series 1   # version\r\n"
               "frames 3\r\n"
               "rows 2\r\n"
               "label   lead #1 and #2   \r\n"
               "unit uV # microvolts\r\n"
               "time 1 2\r\n"
               "time 4\r\n"
               "1 NaN -Infinity   # first row\r\n"
               "\r\n"
               "  4e1\t5 6 \r\n"
               "end\r\n"
               "# trailing comment\r\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("hand.dat"), THX_SERIES_AUTO, &b));
    if (b) {
        CHECK(b->n_rows == 2 && b->n_frames == 3);
        CHECK(b->v[0] == 1 && b->v[1] == 40 && isnan(b->v[2]) && b->v[3] == 5 && isinf(b->v[4]) && b->v[4] < 0 &&
              b->v[5] == 6);
        CHECK(b->time[0] == 1 && b->time[1] == 2 && b->time[2] == 4);
        CHECK(strcmp(b->unit, "uV") == 0 && strcmp(b->time_unit, "ms") == 0);
        CHECK(strcmp(b->label, "lead #1 and #2") == 0);
    }
    thx_series_destroy(&b);
    /* no time axis given: frame numbers */
    tl_write_text(tl_path("notime.txt"), "thorax-series 1\nrows 1\nframes 3\n7 8 9\nend\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("notime.txt"), THX_SERIES_AUTO, &b));
    CHECK(b && b->time[0] == 0 && b->time[2] == 2 && strcmp(b->time_unit, "ms") == 0 && b->unit[0] == '\0');
    thx_series_destroy(&b);
    /* dt without t0 starts at 0 */
    tl_write_text(tl_path("dt.txt"), "thorax-series 1\nrows 1\nframes 3\ndt 2\ntime_unit s\n7 8 9\nend\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("dt.txt"), THX_SERIES_AUTO, &b));
    CHECK(b && b->time[0] == 0 && b->time[1] == 2 && b->time[2] == 4 && strcmp(b->time_unit, "s") == 0);
    thx_series_destroy(&b);
}

static void test_bad_text(void)
{
    const char *H = "thorax-series 1\nrows 2\nframes 3\n";
    char buf[512];
#define T(name, body, line, what)                     \
    do {                                              \
        snprintf(buf, sizeof buf, "%s%s", H, body);   \
        bad_text(name, buf, line, what);              \
    } while (0)
    /* truncation: no 'end' */
    T("trunc_all.txt", "1 2 3\n4 5 6\n", 5, "truncated file (no 'end' line)");
    T("trunc_mid.txt", "1 2 3\n", 4, "truncated file: 1 of 2 value rows");
    T("trunc_head.txt", "", 3, "truncated file: no value rows");
    T("trunc_line.txt", "1 2 3\n4 5", 5, "row 2 has 2 values, expected 3");
    /* wrong counts */
    T("few.txt", "1 2\n4 5 6\nend\n", 4, "row 1 has 2 values, expected 3");
    T("many.txt", "1 2 3\n4 5 6 7 8\nend\n", 5, "row 2 has 5 values, expected 3");
    T("rows_more.txt", "1 2 3\n4 5 6\n7 8 9\nend\n", 6, "more value rows than 'rows 2'");
    T("end_early.txt", "1 2 3\nend\n", 5, "'end' after 1 of 2 value rows");
    T("end_first.txt", "end\n", 4, "'end' before any value row");
    /* values that are not numbers, named by row and frame */
    T("nan_word.txt", "1 2 3\n4 abc 6\nend\n", 5, "row 2, frame 2: 'abc' is not a number");
    T("suffix.txt", "1 2.5x 3\n4 5 6\nend\n", 4, "row 1, frame 2: '2.5x' is not a number");
    T("comma.txt", "1,2,3\n4 5 6\nend\n", 4, "row 1, frame 1: '1,2,3' is not a number");
    T("word_first.txt", "1 2 3\nfoo 5 6\nend\n", 5, "row 2, frame 1: 'foo' is not a number");
    T("after_end.txt", "1 2 3\n4 5 6\nend\n1 2 3\n", 7, "text after 'end'");
    T("no_end_word.txt", "1 2 3\n4 5 6\nfin\n", 6, "'fin' where 'end' was expected after 2 value rows");
    /* header faults */
    T("unknown_kw.txt", "colour red\n1 2 3\n4 5 6\nend\n", 4, "unknown keyword 'colour'");
    T("kw_late.txt", "1 2 3\nunit mV\n4 5 6\nend\n", 5, "'unit' after the value rows began");
    T("label_late.txt", "1 2 3\nlabel x\n4 5 6\nend\n", 5, "'label' after the value rows began");
    T("time_count.txt", "time 0 1\n1 2 3\n4 5 6\nend\n", 4, "'time' gives 2 values for 3 frames");
    T("time_order.txt", "time 0 2 2\n1 2 3\n4 5 6\nend\n", 4, "time 3 (2) is not after time 2");
    T("time_word.txt", "time 0 x 2\n1 2 3\n4 5 6\nend\n", 4, "time 2: 'x' is not a finite number");
    T("time_inf.txt", "time 0 1 inf\n1 2 3\n4 5 6\nend\n", 4, "time 3: 'inf' is not a finite number");
    T("time_dt.txt", "time 0 1 2\ndt 1\n1 2 3\n4 5 6\nend\n", 4, "'time' and 'dt' (line 5) both give");
    T("t0_only.txt", "t0 5\n1 2 3\n4 5 6\nend\n", 4, "'t0' without 'dt'");
    T("dt_zero.txt", "dt 0\n1 2 3\n4 5 6\nend\n", 4, "expected 'dt T' with T a finite number > 0");
    T("dt_tiny.txt", "t0 1e20\ndt 1\n1 2 3\n4 5 6\nend\n", 5, "'dt 1' is too small for t0 = 1e+20");
    T("rows_twice.txt", "rows 2\n1 2 3\n4 5 6\nend\n", 4, "'rows' given twice (first on line 2)");
    T("unit_two.txt", "unit micro volt\n1 2 3\n4 5 6\nend\n", 4, "'unit' takes one word");
    T("unit_long.txt", "unit abcdefghijklmnopqrstuvwxyz0123456789\n1 2 3\n4 5 6\nend\n", 4,
      "is longer than 31 bytes");
#undef T
    bad_text("rows_zero.txt", "thorax-series 1\nrows 0\nframes 3\nend\n", 2, "expected 'rows N' with N a positive integer");
    bad_text("rows_neg.txt", "thorax-series 1\nrows -2\nframes 3\nend\n", 2, "expected 'rows N'");
    bad_text("rows_frac.txt", "thorax-series 1\nframes 3\nrows 1.5\nend\n", 3, "expected 'rows N'");
    bad_text("no_rows.txt", "thorax-series 1\nframes 3\n1 2 3\nend\n", 3, "value row before 'rows N'");
    bad_text("no_frames.txt", "thorax-series 1\nrows 1\n1 2 3\nend\n", 3, "value row before 'frames M'");
    bad_text("header.txt", "# c\nthorax-contours 1\nrows 1\n", 2, "not a thorax series file");
    bad_text("version.txt", "thorax-series 2\nrows 1\n", 1, "unsupported series file version '2'");
    bad_text("too_big.txt", "thorax-series 1\nrows 4611686018427387904\nframes 4\n1 2 3 4\nend\n", 2,
             "a file of 62 bytes cannot hold 4611686018427387904 value rows");
    bad_text("rows_overflow.txt", "thorax-series 1\nrows 99999999999999999999999\nframes 4\n1 2 3 4\nend\n", 2,
             "expected 'rows N' with N a positive integer");
    bad_text("value_range.txt", "thorax-series 1\nrows 1\nframes 2\n1 1e999\nend\n", 4,
             "row 1, frame 2: '1e999' is too large for a double");
    /* a file with no header at all, and an empty one */
    tl_write_text(tl_path("empty.txt"), "# nothing\n\n");
    expect_read_fail(tl_path("empty.txt"), THX_SERIES_AUTO, THX_EINPUT, "empty.txt: empty file", NULL);
    tl_write_bytes(tl_path("nul.txt"), "thorax-series 1\nrows 1\0\n", 24);
    expect_read_fail(tl_path("nul.txt"), THX_SERIES_TEXT, THX_EINPUT, "nul.txt:2: NUL byte", NULL);
    /* missing files and unknown formats */
    expect_read_fail(tl_path("missing.txt"), THX_SERIES_AUTO, THX_EIO, "missing.txt: cannot open", NULL);
    expect_read_fail(tl_path("missing"), THX_SERIES_AUTO, THX_EIO, "missing: cannot open", NULL);
    tl_write_text(tl_path("what.xyz"), "hello, world\n");
    expect_read_fail(tl_path("what.xyz"), THX_SERIES_AUTO, THX_EINPUT, "unknown series format", NULL);
    CHECK(!tl_leftover_tmp(""));
}

static void put_u64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static void test_bad_raw(void)
{
    thx_series *s = sample();
    CHECK_OK(ctx, thx_series_write(ctx, s, tl_path("good.raw"), THX_SERIES_RAW));
    thx_series_destroy(&s);
    size_t n = 0;
    unsigned char *good = (unsigned char *)tl_slurp(ctx, tl_path("good.raw"), &n);
    CHECK(good && n == 200 + 8 * 5 * 4);
    if (!good) return;
    CHECK(memcmp(good, "THXSER01", 8) == 0 && good[8] == 3 && good[16] == 5);
    CHECK(strcmp((char *)good + 24, "mV") == 0 && strcmp((char *)good + 56, "ms") == 0 &&
          strcmp((char *)good + 72, "ecg run #3: lead II  (x)") == 0);
    unsigned char *b = malloc(n + 16);
    if (!b) exit(1);

    memcpy(b, good, n);
    memcpy(b, "HELLOSER", 8);
    tl_write_bytes(tl_path("magic.raw"), b, n);
    expect_read_fail(tl_path("magic.raw"), THX_SERIES_AUTO, THX_EINPUT, "magic.raw: byte offset 0: not a thorax raw series", NULL);

    memcpy(b, good, n);
    memcpy(b, "THXSER02", 8);
    tl_write_bytes(tl_path("version.raw"), b, n);
    expect_read_fail(tl_path("version.raw"), THX_SERIES_AUTO, THX_EINPUT, "version.raw: byte offset 6: raw series version '02'", NULL);

    tl_write_bytes(tl_path("short.raw"), good, 50);
    expect_read_fail(tl_path("short.raw"), THX_SERIES_AUTO, THX_EINPUT, "short.raw: byte offset 50: truncated: the file ends inside the 200-byte", NULL);
    tl_write_bytes(tl_path("tiny.raw"), "TH", 2);
    expect_read_fail(tl_path("tiny.raw"), THX_SERIES_RAW, THX_EINPUT, "tiny.raw: byte offset 2: truncated", NULL);

    tl_write_bytes(tl_path("trunc.raw"), good, n - 8);
    expect_read_fail(tl_path("trunc.raw"), THX_SERIES_AUTO, THX_EINPUT, "trunc.raw: byte offset 352: truncated (the file ends here): 3 rows x 5 frames take 360 bytes", NULL);

    memcpy(b, good, n);
    b[n] = 0;
    tl_write_bytes(tl_path("extra.raw"), b, n + 1);
    expect_read_fail(tl_path("extra.raw"), THX_SERIES_AUTO, THX_EINPUT, "extra.raw: byte offset 360: trailing bytes after the data", NULL);

    memcpy(b, good, n);
    put_u64(b + 8, 0);
    tl_write_bytes(tl_path("zero.raw"), b, n);
    expect_read_fail(tl_path("zero.raw"), THX_SERIES_AUTO, THX_EINPUT, "zero.raw: bytes 8-23: empty series", NULL);

    memcpy(b, good, n);
    put_u64(b + 8, UINT64_MAX / 2);
    tl_write_bytes(tl_path("huge.raw"), b, n);
    expect_read_fail(tl_path("huge.raw"), THX_SERIES_AUTO, THX_EINPUT, "huge.raw: bytes 8-23: impossible sizes", NULL);

    memcpy(b, good, n);
    memset(b + 24, 'u', 32);
    tl_write_bytes(tl_path("unit.raw"), b, n);
    expect_read_fail(tl_path("unit.raw"), THX_SERIES_AUTO, THX_EINPUT, "unit.raw: bytes 24-55: the unit field has no terminating NUL", NULL);

    memcpy(b, good, n);
    double t2 = 0.5; /* time of frame 3 = time of frame 2 */
    memcpy(b + 200 + 16, &t2, 8);
    tl_write_bytes(tl_path("time.raw"), b, n);
    expect_read_fail(tl_path("time.raw"), THX_SERIES_AUTO, THX_EINPUT, "time.raw: byte offset 216: time of frame 3 is 0.5: not after the previous one", NULL);

    free(b);
    free(good);
}

/* ----------------------------------------------------- .mat made here */

static void mat_put(mat_t *mat, const char *name, enum matio_classes cls, enum matio_types type, size_t r, size_t c,
                    const void *data)
{
    size_t dims[2] = {r, c};
    matvar_t *v = Mat_VarCreate(name, cls, type, 2, dims, (void *)data, MAT_F_DONT_COPY_DATA);
    if (!v || Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE) != 0) {
        fprintf(stderr, "cannot write variable %s\n", name);
        exit(1);
    }
    Mat_VarFree(v);
}

static mat_t *mat_new(const char *path)
{
    mat_t *m = Mat_CreateVer(path, NULL, MAT_FT_MAT5);
    if (!m) {
        fprintf(stderr, "cannot create %s\n", path);
        exit(1);
    }
    return m;
}

/* ------------------------------------- .mat files built byte by byte */

/* Appends a MATLAB 5 element (tag, data, padding to 8) to b at *n. */
static void m5_el(unsigned char *b, size_t *n, uint32_t type, const void *d, uint32_t bytes)
{
    memcpy(b + *n, &type, 4);
    memcpy(b + *n + 4, &bytes, 4);
    if (bytes) memcpy(b + *n + 8, d, bytes);
    *n += 8 + bytes;
    while (*n % 8) b[(*n)++] = 0;
}

/* A miMATRIX element of class cls, rows x cols, named name, whose data part is `data` (type dtype,
 * dbytes bytes; dtype 0: no data part, for cells and structs the caller appends the rest). Returns
 * the offset of its size word so that callers can fix it up. */
static size_t m5_matrix(unsigned char *b, size_t *n, uint32_t cls, uint32_t rows, uint32_t cols, const char *name,
                        uint32_t dtype, const void *data, uint32_t dbytes)
{
    size_t start = *n;
    uint32_t t = 14, z = 0;
    memcpy(b + *n, &t, 4);
    memcpy(b + *n + 4, &z, 4);
    *n += 8;
    uint32_t flags[2] = {cls, 0}, dims[2] = {rows, cols};
    m5_el(b, n, 6, flags, 8);
    m5_el(b, n, 5, dims, 8);
    m5_el(b, n, 1, name, (uint32_t)strlen(name));
    if (dtype) m5_el(b, n, dtype, data, dbytes);
    uint32_t size = (uint32_t)(*n - start - 8);
    memcpy(b + start + 4, &size, 4);
    return start + 4;
}

static size_t m5_header(unsigned char *b)
{
    memset(b, ' ', 116);
    memcpy(b, "MATLAB 5.0 MAT-file, made by test_series", 40);
    memset(b + 116, 0, 8);
    b[124] = 0;
    b[125] = 1;
    b[126] = 'I';
    b[127] = 'M';
    return 128;
}

/* Issue 11's .mat findings: files of a few hundred bytes drove libmatio to 16.8 GB (exit 0); a file
 * cut in half lost its time step, unit and label (exit 0). Each is refused now, before libmatio
 * allocates anything, naming the variable and the byte offset. */
static void test_mat_bounded(void)
{
    unsigned char b[4096];
    size_t n = m5_header(b);
    double one = 1;
    /* dims 100000 x 100000 over 8 bytes of data: libmatio would allocate 80 GB */
    m5_matrix(b, &n, 6, 100000, 100000, "potvals", 9, &one, 8);
    tl_write_bytes(tl_path("dims.mat"), b, n);
    double t0 = thx_wtime();
    expect_read_fail(tl_path("dims.mat"), THX_SERIES_AUTO, THX_EINPUT, "dims.mat: variable 1 ('potvals', at byte offset 128",
                     "its 10000000000 elements of 8 bytes need 80000000000 bytes, the file holds 8");
    CHECK(thx_wtime() - t0 < 1.0);
    /* a cell claiming 10^9 cells and a struct claiming 2^40 fields, both with no data */
    n = m5_header(b);
    m5_matrix(b, &n, 1, 1, 1000000000, "c", 0, NULL, 0);
    tl_write_bytes(tl_path("cell.mat"), b, n);
    expect_read_fail(tl_path("cell.mat"), THX_SERIES_AUTO, THX_EINPUT, "cell.mat: variable 1 ('c'",
                     "1000000000 cells claimed, but 0 bytes can hold at most 0");
    n = m5_header(b);
    size_t sz = m5_matrix(b, &n, 2, 1 << 20, 1 << 20, "s", 0, NULL, 0);
    int32_t flen = 8;
    m5_el(b, &n, 5, &flen, 4);
    m5_el(b, &n, 1, "potvals\0", 8);
    uint32_t size = (uint32_t)(n - sz - 4);
    memcpy(b + sz, &size, 4);
    tl_write_bytes(tl_path("struct.mat"), b, n);
    expect_read_fail(tl_path("struct.mat"), THX_SERIES_AUTO, THX_EINPUT, "struct.mat: variable 1 ('s'",
                     "1099511627776 struct fields claimed");
    /* a good series written by thorax, then cut in half, then with bytes after its end */
    thx_series *s = sample(), *r = NULL;
    CHECK_OK(ctx, thx_series_write(ctx, s, tl_path("good.mat"), THX_SERIES_MAT));
    size_t len = 0;
    char *good = tl_slurp(ctx, tl_path("good.mat"), &len);
    CHECK(good && len > 400);
    if (good) {
        tl_write_bytes(tl_path("half.mat"), good, len / 2);
        expect_read_fail(tl_path("half.mat"), THX_SERIES_AUTO, THX_EINPUT, "half.mat: variable ", "truncated");
        for (size_t cut = 129; cut < len; cut += 37) {
            tl_write_bytes(tl_path("cut.mat"), good, cut);
            expect_read_fail(tl_path("cut.mat"), THX_SERIES_AUTO, THX_EINPUT, "cut.mat: ", NULL);
        }
        char *longer = malloc(len + 16);
        memcpy(longer, good, len);
        memset(longer + len, 0x55, 16);
        tl_write_bytes(tl_path("tail5.mat"), longer, len + 5);
        expect_read_fail(tl_path("tail5.mat"), THX_SERIES_AUTO, THX_EINPUT, "tail5.mat: byte offset", "5 stray bytes after the last variable");
        tl_write_bytes(tl_path("tail16.mat"), longer, len + 16);
        expect_read_fail(tl_path("tail16.mat"), THX_SERIES_AUTO, THX_EINPUT, "tail16.mat: variable 6 ('?', at byte offset", "a small element of 21845 bytes");
        free(longer);
        CHECK_OK(ctx, thx_series_read(ctx, tl_path("good.mat"), THX_SERIES_AUTO, &r));
        if (r) CHECK(same_series(s, r));
        thx_series_destroy(&r);
    }
    free(good);
    thx_series_destroy(&s);
    /* zlib: 16e6 zero doubles stored as uint8 compress to about 16 KB and would make 128 MB of doubles:
     * refused (more than 1032 x the compressed size + 1 MiB); the same variable 3 x 4 reads */
    for (int big = 1; big >= 0; big--) {
        uint32_t cols = big ? 16000000u : 4u, rows = big ? 1 : 3;
        size_t cap = (size_t)rows * cols + 256, in = 0;
        unsigned char *inner = calloc(1, cap), *zbuf = malloc(compressBound(cap) + 8);
        unsigned char *zeros = calloc(1, (size_t)rows * cols);
        m5_matrix(inner, &in, 6, rows, cols, "potvals", 2, zeros, rows * cols);
        uLongf zl = compressBound(cap);
        CHECK(compress2(zbuf + 8, &zl, inner, in, 9) == Z_OK);
        uint32_t t = 15, zs = (uint32_t)zl;
        memcpy(zbuf, &t, 4);
        memcpy(zbuf + 4, &zs, 4);
        n = m5_header(b);
        unsigned char *file = malloc(n + 8 + zl);
        memcpy(file, b, n);
        memcpy(file + n, zbuf, 8 + zl);
        tl_write_bytes(tl_path("zlib.mat"), file, n + 8 + zl);
        if (big) {
            expect_read_fail(tl_path("zlib.mat"), THX_SERIES_AUTO, THX_EINPUT, "zlib.mat: variable 1 ('potvals'",
                             "would expand to 128000000 bytes of values");
        } else {
            CHECK_OK(ctx, thx_series_read(ctx, tl_path("zlib.mat"), THX_SERIES_AUTO, &r));
            if (r) CHECK(r->n_rows == 3 && r->n_frames == 4 && r->v[11] == 0);
            thx_series_destroy(&r);
            /* the zlib stream cut short, and compressed bytes after its end */
            file[n + 4] = (unsigned char)(zl - 3);
            tl_write_bytes(tl_path("zcut.mat"), file, n + 8 + zl - 3);
            expect_read_fail(tl_path("zcut.mat"), THX_SERIES_AUTO, THX_EINPUT, "zcut.mat: variable 1 ('potvals'", NULL);
        }
        free(inner);
        free(zbuf);
        free(zeros);
        free(file);
    }
    /* MATLAB v7.3 (HDF5): refused with the reason */
    mat_t *m = Mat_CreateVer(tl_path("v73.mat"), NULL, MAT_FT_MAT73);
    if (m) {
        double d[2] = {1, 2};
        mat_put(m, "potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 2, d);
        Mat_Close(m);
        expect_read_fail(tl_path("v73.mat"), THX_SERIES_AUTO, THX_EINPUT, "v73.mat: byte offset 124: a MATLAB v7.3 (HDF5) file", "-v7");
    }
}

static void test_mat_inputs(void)
{
    thx_series *s = NULL;
    const int16_t ecg[6] = {1, -2, 3, -4, 5, -6}; /* 2 x 3, column-major */
    const double other[4] = {9, 9, 9, 9};
    const double t3[3] = {0, 4, 8}, t2[2] = {0, 1};

    /* no potvals: the first 2-D numeric matrix, any class; top-level unit and time */
    mat_t *m = mat_new(tl_path("int16.mat"));
    mat_put(m, "note", MAT_C_CHAR, MAT_T_UINT8, 1, 5, "hello");
    mat_put(m, "ecg", MAT_C_INT16, MAT_T_INT16, 2, 3, ecg);
    mat_put(m, "other", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, 2, other);
    mat_put(m, "unit", MAT_C_CHAR, MAT_T_UINT8, 1, 2, "mV");
    mat_put(m, "time", MAT_C_DOUBLE, MAT_T_DOUBLE, 3, 1, t3); /* a column is fine */
    Mat_Close(m);
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("int16.mat"), THX_SERIES_AUTO, &s));
    if (s) {
        CHECK(s->n_rows == 2 && s->n_frames == 3);
        CHECK(s->v[0] == 1 && s->v[1] == -2 && s->v[4] == 5 && s->v[5] == -6);
        CHECK(strcmp(s->unit, "mV") == 0 && s->time[2] == 8 && strcmp(s->time_unit, "ms") == 0);
    }
    thx_series_destroy(&s);
    /* a variable named after a colon; a top-level time of another length is an error */
    char named[2100];
    snprintf(named, sizeof named, "%s:other", tl_path("int16.mat"));
    expect_read_fail(named, THX_SERIES_AUTO, THX_EINPUT, "int16.mat: time is double with 3 elements, but the series has 2 frames", NULL);
    snprintf(named, sizeof named, "%s:nope", tl_path("int16.mat"));
    expect_read_fail(named, THX_SERIES_AUTO, THX_EINPUT, "int16.mat: no variable 'nope' (variables: note (char 1x5), ecg (int16 2x3)", NULL);
    snprintf(named, sizeof named, "%s:note", tl_path("int16.mat"));
    expect_read_fail(named, THX_SERIES_AUTO, THX_EINPUT, "int16.mat: note (char) is not a numeric matrix", NULL);
    snprintf(named, sizeof named, "%s:ecg", tl_path("rt.txt"));
    expect_read_fail(named, THX_SERIES_AUTO, THX_EINPUT, "applies only to .mat files", NULL);

    /* a struct holding potvals (as map3d writes), its own unit and label */
    m = mat_new(tl_path("struct.mat"));
    {
        size_t d1[2] = {1, 1}, dp[2] = {2, 3}, du[2] = {1, 2}, dl[2] = {1, 4};
        const float pv[6] = {0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f};
        matvar_t *fields[4];
        fields[0] = Mat_VarCreate("potvals", MAT_C_SINGLE, MAT_T_SINGLE, 2, dp, (void *)pv, 0);
        fields[1] = Mat_VarCreate("unit", MAT_C_CHAR, MAT_T_UINT8, 2, du, "uV", 0);
        fields[2] = Mat_VarCreate("label", MAT_C_CHAR, MAT_T_UINT8, 2, dl, "run7", 0);
        fields[3] = NULL;
        matvar_t *st = Mat_VarCreate("rec", MAT_C_STRUCT, MAT_T_STRUCT, 2, d1, fields, 0);
        mat_put(m, "first", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 2, t2); /* a matrix before the struct */
        CHECK(st && Mat_VarWrite(m, st, MAT_COMPRESSION_ZLIB) == 0);
        Mat_VarFree(st);
    }
    Mat_Close(m);
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("struct.mat"), THX_SERIES_AUTO, &s));
    if (s) {
        CHECK(s->n_rows == 2 && s->n_frames == 3 && s->v[0] == 0.5 && s->v[5] == 5.5);
        CHECK(strcmp(s->unit, "uV") == 0 && strcmp(s->label, "run7") == 0 && s->time[2] == 2);
    }
    thx_series_destroy(&s);

    /* map3d's ts struct: time is the clock time of the recording (text), samplefrequency in Hz
       gives the axis (1 / fs apart, in ms) */
    m = mat_new(tl_path("ts.mat"));
    {
        size_t d1[2] = {1, 1}, dp[2] = {2, 3}, dt[2] = {1, 10};
        const double pv[6] = {1, 2, 3, 4, 5, 6}, fs = 500;
        matvar_t *fields[4];
        fields[0] = Mat_VarCreate("potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dp, (void *)pv, 0);
        fields[1] = Mat_VarCreate("time", MAT_C_CHAR, MAT_T_UINT8, 2, dt, "2:06:25 PM", 0);
        fields[2] = Mat_VarCreate("samplefrequency", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d1, (void *)&fs, 0);
        fields[3] = NULL;
        matvar_t *st = Mat_VarCreate("ts", MAT_C_STRUCT, MAT_T_STRUCT, 2, d1, fields, 0);
        CHECK(st && Mat_VarWrite(m, st, MAT_COMPRESSION_NONE) == 0);
        Mat_VarFree(st);
    }
    Mat_Close(m);
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("ts.mat"), THX_SERIES_AUTO, &s));
    if (s) {
        CHECK(s->n_rows == 2 && s->n_frames == 3 && s->v[5] == 6);
        CHECK(s->time[0] == 0 && s->time[1] == 2 && s->time[2] == 4 && strcmp(s->time_unit, "ms") == 0);
    }
    thx_series_destroy(&s);

    /* what cannot be a series */
    m = mat_new(tl_path("chars.mat"));
    mat_put(m, "name", MAT_C_CHAR, MAT_T_UINT8, 1, 3, "abc");
    Mat_Close(m);
    expect_read_fail(tl_path("chars.mat"), THX_SERIES_AUTO, THX_EINPUT, "chars.mat: no numeric variable", "(variables: name (char 1x3))");

    /* map3d .pot: one value per node, one frame; read only */
    tl_write_text(tl_path("a.pot"), "      -2.39000    \n  1.5e1\n\n 3 4\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("a.pot"), THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 4 && s->n_frames == 1 && s->v[0] == -2.39 && s->v[1] == 15 && s->v[3] == 4 && s->time[0] == 0);
    if (s) {
        thx_status w = thx_series_write(ctx, s, tl_path("b.pot"), THX_SERIES_AUTO);
        CHECK(w == THX_EINPUT && strstr(thx_ctx_message(ctx), "read, not written"));
    }
    thx_series_destroy(&s);
    tl_write_text(tl_path("bad.pot"), "1\n2\nx3\n");
    expect_read_fail(tl_path("bad.pot"), THX_SERIES_AUTO, THX_EINPUT, "bad.pot:3: 'x3' is not a number", NULL);
    tl_write_text(tl_path("empty.pot"), "\n  \n");
    expect_read_fail(tl_path("empty.pot"), THX_SERIES_AUTO, THX_EINPUT, "empty.pot: no values", NULL);

    m = mat_new(tl_path("potchar.mat"));
    mat_put(m, "potvals", MAT_C_CHAR, MAT_T_UINT8, 1, 3, "abc");
    Mat_Close(m);
    expect_read_fail(tl_path("potchar.mat"), THX_SERIES_AUTO, THX_EINPUT, "potchar.mat: potvals (char) is not a numeric matrix", NULL);

    m = mat_new(tl_path("complex.mat"));
    {
        const double re[2] = {1, 2}, im[2] = {3, 4};
        mat_complex_split_t z = {(void *)re, (void *)im};
        size_t d[2] = {1, 2};
        matvar_t *v = Mat_VarCreate("potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d, &z, MAT_F_COMPLEX | MAT_F_DONT_COPY_DATA);
        CHECK(v && Mat_VarWrite(m, v, MAT_COMPRESSION_NONE) == 0);
        Mat_VarFree(v);
    }
    Mat_Close(m);
    expect_read_fail(tl_path("complex.mat"), THX_SERIES_AUTO, THX_EINPUT, "complex.mat: potvals (double) is complex", NULL);

    m = mat_new(tl_path("badtime.mat"));
    mat_put(m, "potvals", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, 2, other);
    mat_put(m, "time", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 2, (const double[2]){3, 1});
    Mat_Close(m);
    expect_read_fail(tl_path("badtime.mat"), THX_SERIES_AUTO, THX_EINPUT, "badtime.mat: time of frame 2 (1) is not after that of frame 1 (3)", NULL);

    tl_write_text(tl_path("junk.mat"), "this is not a MAT file at all, just some text that goes on for a while.\n");
    expect_read_fail(tl_path("junk.mat"), THX_SERIES_AUTO, THX_EINPUT, "junk.mat: byte offset 0: not a MATLAB .mat file", NULL);
    expect_read_fail(tl_path("nothere.mat"), THX_SERIES_AUTO, THX_EIO, "nothere.mat: cannot open", NULL);

    /* non-ASCII strings survive our .mat (UTF-16 inside) */
    thx_series *u = sample();
    snprintf(u->unit, sizeof u->unit, "\xc2\xb5V");                                     /* µV */
    snprintf(u->label, sizeof u->label, "Schr\xc3\xb6" "dinger \xe2\x98\xba \xf0\x9d\x84\x9e"); /* ö ☺ 𝄞 */
    CHECK_OK(ctx, thx_series_write(ctx, u, tl_path("utf.mat"), THX_SERIES_AUTO));
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("utf.mat"), THX_SERIES_AUTO, &s));
    CHECK(same_series(u, s));
    thx_series_destroy(&s);
    thx_series_destroy(&u);
    CHECK(!tl_leftover_tmp(""));
}

static void test_failed_writes(void)
{
    thx_series *s = sample();
    const char *names[3] = {"fail.txt", "fail.raw", "fail.mat"};
    /* a time axis that does not increase: refused before anything is created */
    s->time[3] = s->time[2];
    for (int k = 0; k < 3; k++) {
        thx_ctx_clear(ctx);
        CHECK(thx_series_write(ctx, s, tl_path(names[k]), THX_SERIES_AUTO) == THX_EINPUT);
        CHECK(strstr(thx_ctx_message(ctx), "time of frame 4 (1.25) is not after that of frame 3") != NULL);
        CHECK(!tl_exists(tl_path(names[k])));
    }
    s->time[3] = NAN;
    CHECK(thx_series_write(ctx, s, tl_path("fail.raw"), THX_SERIES_AUTO) == THX_EINPUT && !tl_exists(tl_path("fail.raw")));
    CHECK(strstr(thx_ctx_message(ctx), "time of frame 4 is nan (times must be finite)") != NULL);
    s->time[3] = 2;
    /* an existing file is left as it was */
    tl_write_text(tl_path("keep.txt"), "old content\n");
    s->time[0] = 100;
    CHECK(thx_series_write(ctx, s, tl_path("keep.txt"), THX_SERIES_TEXT) == THX_EINPUT);
    char *t = tl_slurp(ctx, tl_path("keep.txt"), NULL);
    CHECK(t && strcmp(t, "old content\n") == 0);
    free(t);
    s->time[0] = 0;
    /* a unit text cannot hold */
    snprintf(s->unit, sizeof s->unit, "micro volt");
    CHECK(thx_series_write(ctx, s, tl_path("unit.txt"), THX_SERIES_TEXT) == THX_EINPUT && !tl_exists(tl_path("unit.txt")));
    CHECK(strstr(thx_ctx_message(ctx), "unit \"micro volt\" has a blank") != NULL);
    CHECK_OK(ctx, thx_series_write(ctx, s, tl_path("unit.raw"), THX_SERIES_RAW)); /* raw and mat can */
    snprintf(s->unit, sizeof s->unit, "mV");
    /* strings must be terminated */
    memset(s->time_unit, 'x', sizeof s->time_unit);
    CHECK(thx_series_write(ctx, s, tl_path("term.mat"), THX_SERIES_MAT) == THX_EINPUT && !tl_exists(tl_path("term.mat")));
    snprintf(s->time_unit, sizeof s->time_unit, "ms");
    /* no format from the name; a directory that does not exist */
    CHECK(thx_series_write(ctx, s, tl_path("out.xyz"), THX_SERIES_AUTO) == THX_EINPUT && !tl_exists(tl_path("out.xyz")));
    CHECK(strstr(thx_ctx_message(ctx), "extension 'xyz'") != NULL);
    for (int k = 0; k < 3; k++) {
        char p[2100];
        snprintf(p, sizeof p, "%s/no/such/dir/x.%s", tl_scratch, k == 0 ? "txt" : k == 1 ? "raw" : "mat");
        CHECK(thx_series_write(ctx, s, p, THX_SERIES_AUTO) == THX_EIO);
    }
    /* an empty series */
    thx_series *e = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 0, 4, &e));
    CHECK(thx_series_write(ctx, e, tl_path("empty.raw"), THX_SERIES_AUTO) == THX_EINPUT && !tl_exists(tl_path("empty.raw")));
    thx_series_destroy(&e);
    thx_series_destroy(&s);
    CHECK(!tl_leftover_tmp(""));
}

/* The real recording: map3d's struct `onerun` with potvals (512 x 608) and unit 'uV'. */
static void test_real_recording(void)
{
    char path[2300];
    snprintf(path, sizeof path, "%s", tl_src_path(__FILE__, "../../shared/data/map3d/data/tank/cool1-atdr-run1.mat"));
    /* the data folder is part of the project's setup: its absence is a failure */
    CHECK(tl_exists(path));
    if (!tl_exists(path)) {
        fprintf(stderr, "test_series: %s missing\n", path);
        return;
    }
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, path, THX_SERIES_AUTO, &s));
    if (!s) return;
    CHECK(s->n_rows == 512 && s->n_frames == 608);
    CHECK(strcmp(s->unit, "uV") == 0 && strcmp(s->time_unit, "ms") == 0);
    CHECK(s->time[0] == 0 && s->time[607] == 607);
    /* values checked against scipy.io.loadmat(...)['onerun'][0,0]['potvals'] */
    CHECK(s->v[0] == 45 && s->v[1] == 30 && s->v[512] == 40);
    CHECK(s->v[300 * 512 + 100] == 185 && s->v[512 * 608 - 1] == 0);
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < 512 * 608; i++) {
        if (s->v[i] < lo) lo = s->v[i];
        if (s->v[i] > hi) hi = s->v[i];
    }
    CHECK(lo == -36860 && hi == 20555);
    CHECK(thx_series_find_nonfinite(s, NULL, NULL) == 0);
    /* the struct named explicitly gives the same; potvals is not top-level there */
    thx_series *b = NULL;
    char named[2400];
    snprintf(named, sizeof named, "%s:onerun", path);
    CHECK_OK(ctx, thx_series_read(ctx, named, THX_SERIES_MAT, &b));
    CHECK(same_series(s, b));
    thx_series_destroy(&b);
    snprintf(named, sizeof named, "%s:potvals", path);
    expect_read_fail(named, THX_SERIES_AUTO, THX_EINPUT, "no variable 'potvals' (variables: onerun (struct 1x1))", NULL);
    /* and through all three formats unchanged */
    const char *names[3] = {"real.txt", "real.raw", "real.mat"};
    for (int k = 0; k < 3; k++) {
        CHECK_OK(ctx, thx_series_write(ctx, s, tl_path(names[k]), THX_SERIES_AUTO));
        CHECK_OK(ctx, thx_series_read(ctx, tl_path(names[k]), THX_SERIES_AUTO, &b));
        CHECK(same_series(s, b));
        thx_series_destroy(&b);
    }
    thx_series_destroy(&s);
}

/* Many frames: 5000 x 1000 through raw and .mat (timed; figures printed, not judged
 * here: sanitizer builds are slow), 1000 x 1000 through text. */
static void test_large(void)
{
    const size_t sizes[2][2] = {{5000, 1000}, {1000, 1000}};
    const char *names[3] = {"big.raw", "big.mat", "big.txt"};
    for (int k = 0; k < 3; k++) {
        size_t N = sizes[k == 2][0], M = sizes[k == 2][1];
        thx_series *s = NULL;
        CHECK_OK(ctx, thx_series_create(ctx, N, M, &s));
        if (!s) return;
        uint64_t x = 88172645463325252ULL;
        for (size_t i = 0; i < N * M; i++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            s->v[i] = ((double)(x >> 11) * 0x1.0p-53 - 0.5) * 1e4;
        }
        s->v[N * 7 + 3] = NAN;
        for (size_t f = 0; f < M; f++) s->time[f] = 0.5 * (double)f;
        double t0 = thx_wtime();
        CHECK_OK(ctx, thx_series_write(ctx, s, tl_path(names[k]), THX_SERIES_AUTO));
        double t1 = thx_wtime();
        thx_series *b = NULL;
        CHECK_OK(ctx, thx_series_read(ctx, tl_path(names[k]), THX_SERIES_AUTO, &b));
        double t2 = thx_wtime();
        CHECK(same_series(s, b));
        printf("%-8s %zu x %zu: write %.3f s, read %.3f s\n", names[k], N, M, t1 - t0, t2 - t1);
        thx_series_destroy(&b);
        thx_series_destroy(&s);
        unlink(tl_path(names[k]));
    }
}

/* Issue 11's findings on the text and .pot readers (each failed on the code before the fix). */
static void test_bounded_findings(void)
{
    /* a 48-byte text series claiming 5e8 frames took 3.9 GB and 15 s before it was refused: now
     * refused at its 'frames' line, at once */
    const char *t48 = "thorax-series 1\nrows 1\nframes 500000000\n0 0\nend\n";
    CHECK(strlen(t48) == 48);
    double t0 = thx_wtime();
    bad_text("frames_5e8.txt", t48, 3, "'frames 500000000': a file of 48 bytes cannot hold 500000000 values per row");
    CHECK(thx_wtime() - t0 < 1.0);
    /* rows x frames beyond the file, each count alone within it */
    bad_text("product.txt", "thorax-series 1\nrows 20\nframes 20\n0 0\nend\n", 4,
             "'rows 20' (line 2) x 'frames 20' (line 3) values cannot be in a file of 42 bytes");
    /* a .pot with a NUL byte gave 11 of its 352 values (exit 0): now refused, naming the byte and line */
    char pot[352 * 8 + 1];
    size_t n = 0;
    for (int i = 0; i < 352; i++) n += (size_t)snprintf(pot + n, sizeof pot - n, "%6.2f\n", i * 0.25 - 40);
    size_t at = 11 * 7 + 3; /* inside value 12, line 12 */
    pot[at] = '\0';
    tl_write_bytes(tl_path("nul.pot"), pot, n);
    char want[64];
    snprintf(want, sizeof want, "nul.pot:12: NUL byte at byte offset %zu", at);
    expect_read_fail(tl_path("nul.pot"), THX_SERIES_AUTO, THX_EINPUT, want, "in value 12");
    pot[at] = '1';
    tl_write_bytes(tl_path("good.pot"), pot, n);
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("good.pot"), THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 352 && s->n_frames == 1);
    thx_series_destroy(&s);
    /* a NUL in a text series names its byte offset */
    tl_write_bytes(tl_path("nul.txt"), "thorax-series 1\nrows 1\nframes 1\n\0\nend\n", 38);
    expect_read_fail(tl_path("nul.txt"), THX_SERIES_AUTO, THX_EINPUT, "nul.txt:4: NUL byte at byte offset 32", NULL);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_series")) return 1;
    test_create();
    test_round_trips();
    test_text_variants();
    test_bad_text();
    test_bad_raw();
    test_bounded_findings();
    test_mat_inputs();
    test_mat_bounded();
    test_failed_writes();
    test_real_recording();
    test_large();
    int rc = tl_scratch_finish("test_series");
    thx_ctx_destroy(&ctx);
    return rc;
}
