/*
 * Digitization noise repaired, not refused (thorax/geom/repair.h; issue 11 items 6 and 9): the
 * repeated closing point, near-coincident points (1e-9 mm apart, as `thorax slice` gives them
 * beside a mesh node), spikes, small self-crossings (the bow-tie of a jittered point), holes;
 * what is refused (a wide crossing, a wide hole, anything under strict), the messages (file:line,
 * surface, layer, loop), and the reader's frame line.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/check/contours.h"
#include "thorax/io/contours_file.h"
#include "thorax/geom/repair.h"
#include "thorax/geom/surfaces.h"
static const char *HEAD = "thorax-contours 1\nsurface s outer\n";

/* A file of one surface on two layers: `loop0` (point lines) on z=0, a 40 mm square on z=10. */
static char *file_with(const char *loop0)
{
    static char buf[8192];
    snprintf(buf, sizeof buf, "%slayer 0\nloop s\n%slayer 10\nloop s\n0 0\n40 0\n40 40\n0 40\nend\n", HEAD, loop0);
    return buf;
}

/* Parses raw and repairs with the defaults for spacing 5; returns the status, the log in *log. */
static thx_status repair_text(thx_ctx *ctx, const char *text, int strict, thx_repair_log *log, thx_contours **out)
{
    thx_contours *c = NULL;
    memset(log, 0, sizeof *log);
    thx_status st = thx_contours_parse_raw(ctx, "c.txt", text, strlen(text), &c);
    if (st == THX_OK) {
        thx_repair_opts o;
        thx_repair_opts_default(&o, 5.0);
        o.strict = strict;
        st = thx_contours_repair(ctx, c, &o, log);
    }
    if (out) *out = c;
    else thx_contours_destroy(&c);
    return st;
}

static int has(const char *s, const char *what) { return strstr(s, what) != NULL; }

/* Item 9: a loop closed by repeating its first point is not "intersects itself". */
static void test_closing_point(thx_ctx *ctx)
{
    const char *text = file_with("0 0\n40 0\n40 40\n0 40\n0 0\n");
    thx_contours *c = NULL;
    /* the strict reader: a precise message, naming the line of the repeated point */
    CHECK(thx_contours_parse(ctx, "c.txt", text, strlen(text), &c) == THX_EINPUT);
    const char *m = thx_ctx_message(ctx);
    CHECK(has(m, "c.txt:9: ") && has(m, "repeats the first point") && !has(m, "intersects"));
    printf("strict reader: %s\n", m);
    /* thorax surfaces' path: dropped and reported */
    thx_repair_log log;
    CHECK_OK(ctx, repair_text(ctx, text, 0, &log, &c));
    CHECK(log.n == 1 && log.closing == 1);
    if (log.n) {
        CHECK(has(log.msg[0], "c.txt:9: surface \"s\" layer 1 (z=0) loop 1: ") && has(log.msg[0], "repeats the first point") &&
              has(log.msg[0], "dropped") && !has(log.msg[0], "intersects"));
        printf("repaired: %s\n", log.msg[0]);
    }
    if (c) CHECK(c->surf[0].layers[0].loops[0].n == 4);
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
    /* --strict: refused with the same message */
    CHECK(repair_text(ctx, text, 1, &log, NULL) == THX_EINPUT);
    m = thx_ctx_message(ctx);
    CHECK(has(m, "c.txt:9: ") && has(m, "repeats the first point") && !has(m, "intersects"));
    thx_repair_log_free(&log);
}

/* Points 1e-9 mm apart (a slice beside a mesh node): merged, and the surface builds (the spline
 * system was "not positive definite" before). */
static void test_near_coincident(thx_ctx *ctx)
{
    const char *text = file_with("0 0\n20 0\n20.000000001 0.000000001\n40 0\n40 40\n0 40\n");
    thx_contours *c = NULL;
    thx_repair_log log;
    CHECK_OK(ctx, repair_text(ctx, text, 0, &log, &c));
    CHECK(log.n == 1 && log.merged == 1);
    if (log.n) CHECK(has(log.msg[0], "c.txt:6: ") && has(log.msg[0], "near-coincident") && has(log.msg[0], "merged"));
    if (c) {
        CHECK(c->surf[0].layers[0].loops[0].n == 5);
        thx_surfaces_opts o;
        thx_surfaces_opts_default(&o);
        thx_model *m = NULL;
        CHECK_OK(ctx, thx_surfaces_build(ctx, c, &o, &m, NULL, NULL));
        thx_model_destroy(&m);
    }
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
    CHECK(repair_text(ctx, text, 1, &log, NULL) == THX_EINPUT);
    CHECK(has(thx_ctx_message(ctx), "near-coincident") && has(thx_ctx_message(ctx), "--strict"));
    thx_repair_log_free(&log);
    /* exact repeats are merged even with a zero tolerance */
    thx_contours *d = NULL;
    const char *rep = file_with("0 0\n20 0\n20 0\n40 0\n40 40\n0 40\n");
    CHECK_OK(ctx, thx_contours_parse_raw(ctx, "c.txt", rep, strlen(rep), &d));
    thx_repair_opts o0 = {5.0, 0.0, 0.0, 0};
    memset(&log, 0, sizeof log);
    if (d) CHECK_OK(ctx, thx_contours_repair(ctx, d, &o0, &log));
    CHECK(log.merged == 1 && log.n == 1);
    if (log.n) CHECK(has(log.msg[0], "repeats the point before"));
    thx_repair_log_free(&log);
    thx_contours_destroy(&d);
}

/* The bow-tie a jittered point makes (the loop crosses itself by a hair): the small loop is
 * cut off at the crossing; a wide crossing (a figure eight) is refused. */
static void test_untangle(thx_ctx *ctx)
{
    /* along the bottom edge the loop runs past x=21 and back to x=20 before going on: a bow-tie */
    const char *text = file_with("0 0\n21 0.3\n21 -0.3\n20 -0.3\n20 0.3\n40 0\n40 40\n0 40\n");
    thx_contours *c = NULL;
    thx_repair_log log;
    CHECK_OK(ctx, repair_text(ctx, text, 0, &log, &c));
    CHECK(log.untangled == 1);
    for (size_t k = 0; k < log.n; k++) printf("repaired: %s\n", log.msg[k]);
    if (c) CHECK_OK(ctx, thx_contours_validate(ctx, c));
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
    const char *eight = file_with("0 0\n40 40\n40 0\n0 40\n");
    CHECK(repair_text(ctx, eight, 0, &log, NULL) == THX_EINPUT);
    CHECK(has(thx_ctx_message(ctx), "c.txt:5: surface \"s\" layer 1 (z=0) loop 1: loop intersects itself") &&
          has(thx_ctx_message(ctx), "untangle tolerance"));
    printf("refused: %s\n", thx_ctx_message(ctx));
    thx_repair_log_free(&log);
}

/* A spike (the loop folds straight back) is removed; a narrow hole dropped, a wide one kept (the build
   laces holes to holes). */
static void test_spike_hole(thx_ctx *ctx)
{
    const char *sp = file_with("0 0\n20 0\n30 0\n25 0\n40 0\n40 40\n0 40\n");
    thx_contours *c = NULL;
    thx_repair_log log;
    CHECK_OK(ctx, repair_text(ctx, sp, 0, &log, &c));
    CHECK(log.spikes >= 1);
    if (c) CHECK_OK(ctx, thx_contours_validate(ctx, c));
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
    const char *narrow = file_with("0 0\n40 0\n40 40\n0 40\nloop s\n10 10\n12 10\n12 30\n10 30\n");
    CHECK_OK(ctx, repair_text(ctx, narrow, 0, &log, &c));
    CHECK(log.holes == 1);
    if (log.n) CHECK(has(log.msg[log.n - 1], "loop 2: the loop lies inside loop 1") && has(log.msg[log.n - 1], "dropped"));
    if (c) CHECK(c->surf[0].layers[0].n_loops == 1);
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
    const char *wide = file_with("0 0\n40 0\n40 40\n0 40\nloop s\n10 10\n30 10\n30 30\n10 30\n");
    CHECK_OK(ctx, repair_text(ctx, wide, 0, &log, &c));
    CHECK(log.holes == 0);
    if (c) CHECK(c->surf[0].layers[0].n_loops == 2);
    thx_contours_destroy(&c);
    thx_repair_log_free(&log);
}

/* The frame line: read, written, read back; absent = not set; bad ones refused with the line. */
static void test_frame(thx_ctx *ctx)
{
    const char *t = "thorax-contours 1\nframe -y +z\nsurface s outer\nlayer 0\nloop s\n0 0\n1 0\n0 1\nlayer 1\nloop s\n0 0\n1 0\n0 1\nend\n";
    thx_contours *c = NULL, *r = NULL;
    CHECK_OK(ctx, thx_contours_parse(ctx, "c.txt", t, strlen(t), &c));
    if (!c) return;
    CHECK(c->frame.set && c->frame.up.axis == 1 && c->frame.up.sign == -1 && c->frame.front.axis == 2 && c->frame.front.sign == 1);
    char dir[] = "/tmp/thorax-test-repair.XXXXXX", path[64];
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/c.txt", dir); /* a new file: the writer replaces only its own */
    CHECK_OK(ctx, thx_contours_write(ctx, c, path, "test"));
    CHECK_OK(ctx, thx_contours_read(ctx, path, &r));
    if (r) CHECK(r->frame.set && r->frame.up.axis == 1 && r->frame.up.sign == -1 && r->frame.front.axis == 2);
    remove(path);
    rmdir(dir);
    thx_contours_destroy(&r);
    thx_contours_destroy(&c);
    const char *none = "thorax-contours 1\nsurface s outer\nlayer 0\nloop s\n0 0\n1 0\n0 1\nend\n";
    CHECK_OK(ctx, thx_contours_parse(ctx, "c.txt", none, strlen(none), &c));
    if (c) CHECK(!c->frame.set);
    thx_contours_destroy(&c);
    const char *bad = "thorax-contours 1\nframe +z z\nsurface s outer\nlayer 0\nloop s\n0 0\n1 0\n0 1\nend\n";
    CHECK(thx_contours_parse(ctx, "c.txt", bad, strlen(bad), &c) == THX_EINPUT);
    CHECK(has(thx_ctx_message(ctx), "c.txt:2: "));
}

/* Issue 24: every message has its kind, in order; a quiet log keeps the messages without logging
 * them (thorax surfaces summarizes them), a log that is not quiet logs each as a warning. */
static void count_warnings(void *user, thx_log_level level, const char *message)
{
    (void)message;
    if (level == THX_LOG_WARN) ++*(int *)user;
}

static void test_kinds_quiet(void)
{
    /* a repeated point, a spike (10 0 -> 20 0 -> 15 0 folds back), a closing point */
    const char *text = file_with("0 0\n10 0\n10 0\n20 0\n15 0\n20 20\n0 20\n0 0\n");
    for (int quiet = 0; quiet < 2; quiet++) {
        thx_ctx *ctx = NULL;
        int warned = 0;
        thx_ctx_create(&ctx);
        thx_ctx_set_log(ctx, count_warnings, &warned, THX_LOG_DEBUG);
        thx_contours *c = NULL;
        thx_repair_log log;
        memset(&log, 0, sizeof log);
        log.quiet = quiet;
        CHECK_OK(ctx, thx_contours_parse_raw(ctx, "c.txt", text, strlen(text), &c));
        thx_repair_opts o;
        thx_repair_opts_default(&o, 5.0);
        if (c) CHECK_OK(ctx, thx_contours_repair(ctx, c, &o, &log));
        size_t count[THX_REPAIR_KINDS] = {0};
        for (size_t k = 0; k < log.n && log.kind; k++) {
            CHECK(log.kind[k] >= 0 && log.kind[k] < THX_REPAIR_KINDS);
            if (log.kind[k] >= 0 && log.kind[k] < THX_REPAIR_KINDS) count[log.kind[k]]++;
            /* the kind says what the message says */
            static const char *word[THX_REPAIR_KINDS] = {"repeats the first point", "merged", "spike", "crosses itself", "hole"};
            CHECK(has(log.msg[k], word[log.kind[k] >= 0 && log.kind[k] < THX_REPAIR_KINDS ? log.kind[k] : 0]));
        }
        CHECK(log.n == 3 && count[THX_REPAIR_CLOSING] == 1 && count[THX_REPAIR_MERGED] == 1 && count[THX_REPAIR_SPIKE] == 1);
        CHECK(warned == (quiet ? 0 : (int)log.n));
        printf("%s log: %zu repairs (%zu closing, %zu merged, %zu spike), %d warnings logged\n", quiet ? "quiet" : "loud",
               log.n, count[THX_REPAIR_CLOSING], count[THX_REPAIR_MERGED], count[THX_REPAIR_SPIKE], warned);
        thx_repair_log_free(&log);
        thx_contours_destroy(&c);
        thx_ctx_destroy(&ctx);
    }
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    test_closing_point(ctx);
    test_near_coincident(ctx);
    test_untangle(ctx);
    test_spike_hole(ctx);
    test_frame(ctx);
    test_kinds_quiet();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
