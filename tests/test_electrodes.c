/*
 * Tests of electrodes, leads and the phantom's beat (thorax/model/electrodes.h:
 * src/io/model/electrodes.c, src/io/leads.c, src/phantom/electrodes_phantom.c,
 * src/phantom/beat.c):
 *  - electrode files: round trip, byte-identical output, malformed files
 *    refused with the file, line and electrode named and nothing returned,
 *    invalid sets refused before a file is created;
 *  - the check against a model: unknown surface, node out of range, a
 *    position that does not match its node;
 *  - the phantom's electrodes: V1..V6 on the front and ordered from the
 *    subject's right to left, RA/LA at the top on their sides, LL low on the
 *    left, 192 array electrodes on distinct nodes in 12 rings of 16,
 *    deterministic;
 *  - the 12-lead algebra on synthetic fields (a linear field phi = x, and
 *    arbitrary values): lead I = x(LA) - x(RA), Einthoven's II = I + III,
 *    aVR + aVL + aVF = 0, V leads against Wilson's terminal; missing leads;
 *  - the beat: frames, time axis and unit, max |phi| = peak, baselines,
 *    smoothness, the analytic dipole field at every node (with the dipole
 *    and centroid recomputed here), QRS the largest wave and pointing
 *    left-inferior-posterior, positive potentials on the side the dipole
 *    points to; error cases.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include "thorax/core/fileio.h"
#include "thorax/phantom/phantom.h"
#include "thorax/geom/surfaces.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

static thx_model *phantom_model(void)
{
    thx_model *m = tl_phantom_surfaces(ctx);
    if (!m) exit(1);
    return m;
}

static const thx_surface *by_role(const thx_model *m, thx_role role)
{
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == role) return m->surf[s];
    return NULL;
}

static size_t find(const thx_electrodes *e, const char *name)
{
    for (size_t i = 0; i < e->n; i++)
        if (!strcmp(e->name[i], name)) return i;
    fprintf(stderr, "no electrode %s\n", name);
    exit(1);
}

static const double *pos(const thx_electrodes *e, const char *name) { return e->xyz + 3 * find(e, name); }

/* Equal names, nodes and surface; positions within tol (0: bit for bit). */
static int same_set_tol(const thx_electrodes *a, const thx_electrodes *b, double tol)
{
    if (!a || !b || a->n != b->n || strcmp(a->surface, b->surface)) return 0;
    for (size_t i = 0; i < a->n; i++) {
        if (strcmp(a->name[i], b->name[i]) || a->node[i] != b->node[i]) return 0;
        for (int k = 0; k < 3; k++)
            if (!(fabs(a->xyz[3 * i + k] - b->xyz[3 * i + k]) <= tol)) return 0;
    }
    return 1;
}

static int same_set(const thx_electrodes *a, const thx_electrodes *b) { return same_set_tol(a, b, 0); }

/* A read that must fail with THX_EINPUT, *out NULL, and a message holding both parts. */
static void expect_read_fail(const char *name, const char *text, const char *part1, const char *part2)
{
    tl_write_text(tl_path(name), text);
    thx_electrodes *e = (thx_electrodes *)&e;
    thx_ctx_clear(ctx);
    thx_status st = thx_electrodes_read(ctx, tl_path(name), &e);
    const char *msg = thx_ctx_message(ctx);
    int ok = st == THX_EINPUT && e == NULL && strstr(msg, part1) && (!part2 || strstr(msg, part2));
    CHECK(ok);
    if (!ok) fprintf(stderr, "  reading %s: status %d, message \"%s\", want \"%s\" and \"%s\"\n", name, (int)st, msg,
                     part1, part2 ? part2 : "");
    if (st == THX_OK && e != (thx_electrodes *)&e) thx_electrodes_destroy(&e);
}

/* ------------------------------------------------------------- files */

static void test_create(void)
{
    thx_electrodes *e = NULL;
    CHECK_OK(ctx, thx_electrodes_create(ctx, 3, &e));
    CHECK(e && e->n == 3 && e->name && e->node && e->xyz && e->surface[0] == '\0');
    if (e) CHECK(e->node[2] == 0 && e->xyz[8] == 0 && e->name[2][0] == '\0');
    thx_electrodes_destroy(&e);
    CHECK(e == NULL);
    thx_electrodes_destroy(&e);
    thx_electrodes_destroy(NULL);
    CHECK(thx_electrodes_create(ctx, 0, &e) == THX_EINPUT && e == NULL);
}

static void test_round_trip(const thx_model *m, const thx_electrodes *e12, const thx_electrodes *ea)
{
    const thx_electrodes *sets[2] = {e12, ea};
    const char *names[2] = {"12lead.txt", "array.txt"};
    for (int k = 0; k < 2; k++) {
        CHECK_OK(ctx, thx_electrodes_write(ctx, sets[k], tl_path(names[k])));
        thx_electrodes *b = NULL;
        CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path(names[k]), &b));
        /* positions are written "%.6f", as NAME.pts: within 5e-7 mm of a model built in memory */
        CHECK(same_set_tol(sets[k], b, 5.000001e-7));
        CHECK_OK(ctx, thx_electrodes_check(ctx, b, m));
        /* the same set gives the same bytes */
        CHECK_OK(ctx, thx_electrodes_write(ctx, b, tl_path("again.txt")));
        char *t1 = NULL, *t2 = NULL;
        size_t n1 = 0, n2 = 0;
        CHECK_OK(ctx, thx_read_file(ctx, tl_path(names[k]), &t1, &n1));
        CHECK_OK(ctx, thx_read_file(ctx, tl_path("again.txt"), &t2, &n2));
        CHECK(t1 && t2 && n1 == n2 && memcmp(t1, t2, n1) == 0);
        thx_electrodes *b2 = NULL;
        CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("again.txt"), &b2));
        CHECK(same_set(b, b2)); /* read -> write -> read: bit for bit */
        thx_electrodes_destroy(&b2);
        if (k == 0 && t1) {
            CHECK(strncmp(t1, "thorax-electrodes 1\nsurface torso\ncount 9\nRA ", 45) == 0);
            CHECK(n1 > 4 && strcmp(t1 + n1 - 4, "end\n") == 0);
        }
        free(t1);
        free(t2);
        thx_electrodes_destroy(&b);
    }
    /* on a model read from its directory (coordinates "%.6f", as the CLI sees it) the round trip is exact */
    {
        thx_model *md = NULL;
        thx_electrodes *a = NULL, *b = NULL;
        CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("model")));
        CHECK_OK(ctx, thx_model_read(ctx, tl_path("model"), &md));
        if (md) CHECK_OK(ctx, thx_phantom_electrodes(ctx, md, &a, 0, NULL));
        CHECK(a && a->n == 9);
        if (a) {
            CHECK_OK(ctx, thx_electrodes_write(ctx, a, tl_path("md12.txt")));
            CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("md12.txt"), &b));
            CHECK(same_set(a, b));
            CHECK_OK(ctx, thx_electrodes_check(ctx, b, md));
        }
        thx_electrodes_destroy(&a);
        thx_electrodes_destroy(&b);
        thx_model_destroy(&md);
    }
    /* comments, blank lines, CRLF */
    tl_write_text(tl_path("free.txt"), "# made by hand\n\nthorax-electrodes 1   # version\r\ncount 2\nsurface torso\n"
                               "  X1 1 0.5 -2 3e1  # first\r\nX2 3 0 0 0\n\nend\n# trailing comment\n");
    thx_electrodes *f = NULL;
    CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("free.txt"), &f));
    CHECK(f && f->n == 2 && !strcmp(f->surface, "torso") && !strcmp(f->name[0], "X1") && f->node[0] == 0 &&
          f->node[1] == 2 && f->xyz[0] == 0.5 && f->xyz[1] == -2 && f->xyz[2] == 30);
    thx_electrodes_destroy(&f);
    CHECK(!tl_leftover_tmp(""));
}

static void test_bad_files(void)
{
    const char *head = "thorax-electrodes 1\nsurface torso\ncount 3\n";
    char buf[1024];
    {
        /* a NUL byte: refused with its line and byte offset, not read up to it */
        static const char nul[] = "thorax-electrodes 1\nsurface torso\ncount 2\nRA 1 0 0 0\nL\0A 2 0 0 0\nend\n";
        tl_write_bytes(tl_path("nul.txt"), nul, sizeof nul - 1);
        thx_electrodes *e = NULL;
        thx_ctx_clear(ctx);
        CHECK(thx_electrodes_read(ctx, tl_path("nul.txt"), &e) == THX_EINPUT && e == NULL);
        CHECK(strstr(thx_ctx_message(ctx), "nul.txt:5: NUL byte at byte offset 54") != NULL);
    }
    /* counts and node numbers: digits only, overflow-checked (src/io/common/parse_uint.h) */
    expect_read_fail("count64.txt", "thorax-electrodes 1\nsurface torso\ncount 18446744073709551617\nRA 1 0 0 0\nend\n",
                     "count64.txt:3: expected 'count N' with N a positive integer", NULL);
    expect_read_fail("countbig.txt", "thorax-electrodes 1\nsurface torso\ncount 2147483646\nRA 1 0 0 0\nend\n",
                     "countbig.txt:3: 'count 2147483646' is more electrodes than a file of", NULL);
    expect_read_fail("countplus.txt", "thorax-electrodes 1\nsurface torso\ncount +1\nRA 1 0 0 0\nend\n",
                     "countplus.txt:3: expected 'count N'", NULL);
    expect_read_fail("node64.txt", "thorax-electrodes 1\nsurface torso\ncount 1\nRA 18446744073709551617 0 0 0\nend\n",
                     "node64.txt:4: electrode 1 (\"RA\"): node '18446744073709551617' is not a node number", NULL);
    expect_read_fail("node32.txt", "thorax-electrodes 1\nsurface torso\ncount 1\nRA 2147483647 0 0 0\nend\n",
                     "node32.txt:4: electrode 1 (\"RA\"): node '2147483647'", NULL);
    /* truncated: a line cut off, or the end missing */
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 0\n", head);
    expect_read_fail("trunc1.txt", buf, "trunc1.txt:5: truncated file: 2 of 3 electrodes", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 0\nLL 3 0 0 0\n", head);
    expect_read_fail("trunc2.txt", buf, "trunc2.txt:6: truncated file (no 'end' line)", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0", head);
    expect_read_fail("trunc3.txt", buf, "trunc3.txt:5: electrode 2: expected 'NAME NODE X Y Z', got 4 fields", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nend\n", head);
    expect_read_fail("early.txt", buf, "early.txt:5: 'end' after 1 of 3 electrodes ('count 3', line 3)", NULL);
    /* bad nodes */
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 0 0 0 0\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("node0.txt", buf, "node0.txt:5: electrode 2 (\"LA\"): node '0' is not a node number", NULL);
    snprintf(buf, sizeof buf, "%sRA -4 0 0 0\nLA 2 0 0 0\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("nodeneg.txt", buf, "nodeneg.txt:4: electrode 1 (\"RA\"): node '-4'", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 0\nLL 2.5 0 0 0\nend\n", head);
    expect_read_fail("nodefrac.txt", buf, "nodefrac.txt:6: electrode 3 (\"LL\"): node '2.5'", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 abc 0\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("coord.txt", buf, "coord.txt:5: electrode 2 (\"LA\"): y 'abc' is not a finite number", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 nan\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("nan.txt", buf, "nan.txt:5: electrode 2 (\"LA\"): z 'nan'", NULL);
    /* names */
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nRA 2 0 0 0\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("dup.txt", buf, "dup.txt:5: electrode 2: name \"RA\" already used by electrode 1", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nL,A 2 0 0 0\nLL 3 0 0 0\nend\n", head);
    expect_read_fail("name.txt", buf, "name.txt:5: electrode 2: name \"L,A\" has a character outside", NULL);
    /* structure */
    expect_read_fail("hdr.txt", "thorax-series 1\n", "hdr.txt:1: not a thorax electrodes file", NULL);
    expect_read_fail("ver.txt", "thorax-electrodes 2\n", "ver.txt:1: unsupported electrodes file version '2'", NULL);
    expect_read_fail("empty.txt", "# nothing\n", "empty.txt:1: empty file", NULL);
    expect_read_fail("nosurf.txt", "thorax-electrodes 1\ncount 1\nRA 1 0 0 0\nend\n",
                     "nosurf.txt:3: electrode line before 'surface NAME'", NULL);
    expect_read_fail("count.txt", "thorax-electrodes 1\nsurface torso\ncount 0\n",
                     "count.txt:3: expected 'count N' with N a positive integer, got '0'", NULL);
    expect_read_fail("huge.txt", "thorax-electrodes 1\nsurface torso\ncount 99999999\nend\n",
                     "huge.txt:3: 'count 99999999' is more electrodes than", NULL);
    expect_read_fail("twice.txt", "thorax-electrodes 1\nsurface torso\nsurface fat\n",
                     "twice.txt:3: 'surface' given twice (first on line 2)", NULL);
    expect_read_fail("surfname.txt", "thorax-electrodes 1\nsurface a/b\n", "surfname.txt:2: surface name \"a/b\"",
                     NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 0\nLL 3 0 0 0\nV1 4 0 0 0\nend\n", head);
    expect_read_fail("more.txt", buf, "more.txt:7: more electrode lines than 'count 3' (line 3)", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\nLA 2 0 0 0\nLL 3 0 0 0\nend\nRA 1 0 0 0\n", head);
    expect_read_fail("after.txt", buf, "after.txt:8: text after 'end'", NULL);
    snprintf(buf, sizeof buf, "%sRA 1 0 0 0\ncount 3\n", head);
    expect_read_fail("late.txt", buf, "late.txt:5: 'count' after the electrode lines began", NULL);
    {
        thx_electrodes *e = (thx_electrodes *)&e;
        CHECK(thx_electrodes_read(ctx, tl_path("none.txt"), &e) == THX_EIO && e == NULL);
        CHECK(strstr(thx_ctx_message(ctx), "none.txt") != NULL);
    }

    /* invalid sets are refused before any file is created */
    thx_electrodes *e = NULL;
    CHECK_OK(ctx, thx_electrodes_create(ctx, 2, &e));
    if (!e) return;
    snprintf(e->surface, sizeof e->surface, "torso");
    snprintf(e->name[0], sizeof e->name[0], "A");
    snprintf(e->name[1], sizeof e->name[1], "A");
    CHECK(thx_electrodes_write(ctx, e, tl_path("w1.txt")) == THX_EINPUT && !tl_exists(tl_path("w1.txt")));
    CHECK(strstr(thx_ctx_message(ctx), "electrode 2: name \"A\" already used by electrode 1") != NULL);
    snprintf(e->name[1], sizeof e->name[1], "B");
    e->node[1] = -2; /* -1 is THX_ELECTRODE_OFF_NODE, a point between nodes */
    CHECK(thx_electrodes_write(ctx, e, tl_path("w2.txt")) == THX_EINPUT && !tl_exists(tl_path("w2.txt")));
    CHECK(strstr(thx_ctx_message(ctx), "electrode 2 (\"B\"): node -2 is negative") != NULL);
    e->node[1] = 1;
    e->xyz[4] = NAN;
    CHECK(thx_electrodes_write(ctx, e, tl_path("w3.txt")) == THX_EINPUT && !tl_exists(tl_path("w3.txt")));
    e->xyz[4] = 0;
    snprintf(e->name[0], sizeof e->name[0], "end");
    CHECK(thx_electrodes_write(ctx, e, tl_path("w4.txt")) == THX_EINPUT && !tl_exists(tl_path("w4.txt")));
    snprintf(e->name[0], sizeof e->name[0], "A");
    e->surface[0] = '\0';
    CHECK(thx_electrodes_write(ctx, e, tl_path("w5.txt")) == THX_EINPUT && !tl_exists(tl_path("w5.txt")));
    snprintf(e->surface, sizeof e->surface, "torso");
    /* an existing file is kept when a write is refused */
    CHECK_OK(ctx, thx_electrodes_write(ctx, e, tl_path("keep.txt")));
    e->node[0] = -5;
    CHECK(thx_electrodes_write(ctx, e, tl_path("keep.txt")) == THX_EINPUT);
    thx_electrodes *k = NULL;
    CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("keep.txt"), &k));
    CHECK(k && k->node[0] == 0);
    thx_electrodes_destroy(&k);
    thx_electrodes_destroy(&e);
    CHECK(!tl_leftover_tmp(""));
}

static void test_check(const thx_model *m, const thx_electrodes *e12)
{
    thx_electrodes *e = NULL;
    CHECK_OK(ctx, thx_electrodes_write(ctx, e12, tl_path("c.txt")));
    CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("c.txt"), &e));
    if (!e) return;
    CHECK_OK(ctx, thx_electrodes_check(ctx, e, m));
    const thx_surface *outer = by_role(m, THX_ROLE_OUTER);

    /* a position 0.01 mm off its node */
    size_t v3 = find(e, "V3");
    e->xyz[3 * v3 + 1] += 0.01;
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "electrode 6 (\"V3\")") && strstr(thx_ctx_message(ctx), "0.01 mm from node"));
    /* within the tolerance */
    e->xyz[3 * v3 + 1] -= 0.0095;
    CHECK_OK(ctx, thx_electrodes_check(ctx, e, m));
    e->xyz[3 * v3 + 1] = outer->xyz[3 * (size_t)e->node[v3] + 1];
    /* the node of another electrode: the position no longer agrees */
    int32_t keep = e->node[v3];
    e->node[v3] = e->node[find(e, "V4")];
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT && strstr(thx_ctx_message(ctx), "\"V3\""));
    /* a node beyond the surface */
    e->node[v3] = (int32_t)outer->n_nodes;
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT);
    char want[200];
    snprintf(want, sizeof want, "node %zu is not on surface \"torso\" (nodes 1..%zu)", outer->n_nodes + 1,
             outer->n_nodes);
    CHECK(strstr(thx_ctx_message(ctx), want) != NULL);
    e->node[v3] = keep;
    CHECK_OK(ctx, thx_electrodes_check(ctx, e, m));
    /* an unknown surface (read from a file, then checked) */
    char *text = NULL;
    size_t len = 0;
    CHECK_OK(ctx, thx_read_file(ctx, tl_path("c.txt"), &text, &len));
    if (text) {
        char *s = strstr(text, "surface torso");
        if (s) memcpy(s, "surface tors0", 13);
        tl_write_text(tl_path("c2.txt"), text);
        free(text);
    }
    thx_electrodes *u = NULL;
    CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("c2.txt"), &u));
    CHECK(u && thx_electrodes_check(ctx, u, m) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "surface \"tors0\" is not in the model (surfaces: torso, fat, muscle") != NULL);
    thx_electrodes_destroy(&u);
    thx_electrodes_destroy(&e);
}

/* ------------------------------------------------------------- the phantom's electrodes */

static void test_phantom_electrodes(const thx_model *m, const thx_electrodes *e12, const thx_electrodes *ea)
{
    const thx_surface *outer = by_role(m, THX_ROLE_OUTER), *heart = by_role(m, THX_ROLE_HEART);
    CHECK(e12 && e12->n == 9 && !strcmp(e12->surface, outer->name));
    CHECK(ea && ea->n == 192 && !strcmp(ea->surface, outer->name));
    if (!e12 || !ea) return;
    CHECK_OK(ctx, thx_electrodes_check(ctx, e12, m));
    CHECK_OK(ctx, thx_electrodes_check(ctx, ea, m));
    static const char *const order[9] = {"RA", "LA", "LL", "V1", "V2", "V3", "V4", "V5", "V6"};
    for (int i = 0; i < 9; i++) CHECK(!strcmp(e12->name[i], order[i]));

    double zmin = INFINITY, zmax = -INFINITY, hz0 = INFINITY, hz1 = -INFINITY, ymid = 0;
    for (size_t i = 0; i < outer->n_nodes; i++) {
        zmin = fmin(zmin, outer->xyz[3 * i + 2]);
        zmax = fmax(zmax, outer->xyz[3 * i + 2]);
    }
    for (size_t i = 0; i < heart->n_nodes; i++) {
        hz0 = fmin(hz0, heart->xyz[3 * i + 2]);
        hz1 = fmax(hz1, heart->xyz[3 * i + 2]);
    }
    double H = zmax - zmin;
    /* the torso's y centre at the precordial height: mean of the extreme y of nodes near it */
    {
        double y0 = INFINITY, y1 = -INFINITY, z4 = pos(e12, "V4")[2];
        for (size_t i = 0; i < outer->n_nodes; i++)
            if (fabs(outer->xyz[3 * i + 2] - z4) < 1e-6) {
                y0 = fmin(y0, outer->xyz[3 * i + 1]);
                y1 = fmax(y1, outer->xyz[3 * i + 1]);
            }
        ymid = 0.5 * (y0 + y1);
        /* V1..V5 on the front (RAS: +y anterior), V6 at the side */
        const char *front[5] = {"V1", "V2", "V3", "V4", "V5"};
        for (int i = 0; i < 5; i++) CHECK(pos(e12, front[i])[1] > ymid + 0.4 * (y1 - ymid));
        CHECK(fabs(pos(e12, "V6")[1] - ymid) < 0.25 * (y1 - ymid));
    }
    /* ordered from the subject's right (+x) to the left (-x), V1 and V2 either side of the midline */
    const char *v[6] = {"V1", "V2", "V3", "V4", "V5", "V6"};
    for (int i = 0; i + 1 < 6; i++) CHECK(pos(e12, v[i])[0] > pos(e12, v[i + 1])[0]);
    CHECK(pos(e12, "V1")[0] > 0 && pos(e12, "V2")[0] < 0);
    CHECK(fabs(pos(e12, "V1")[0] + pos(e12, "V2")[0]) < 15);
    /* heights: V1 = V2 at mid-heart, V4 = V5 = V6 lower, V3 between; all within the heart's extent */
    CHECK(pos(e12, "V1")[2] == pos(e12, "V2")[2]);
    CHECK(pos(e12, "V4")[2] == pos(e12, "V5")[2] && pos(e12, "V5")[2] == pos(e12, "V6")[2]);
    CHECK(pos(e12, "V4")[2] < pos(e12, "V2")[2]);
    CHECK(pos(e12, "V3")[2] <= pos(e12, "V2")[2] && pos(e12, "V3")[2] >= pos(e12, "V4")[2]);
    for (int i = 0; i < 6; i++) CHECK(pos(e12, v[i])[2] > hz0 && pos(e12, v[i])[2] < hz1);
    /* V6 is the leftmost of all: the mid-axillary line */
    CHECK(pos(e12, "V6")[0] < pos(e12, "LA")[0]);
    /* limb leads: RA and LA at the top on their sides, LL low on the left */
    CHECK(pos(e12, "RA")[2] > zmax - 0.15 * H && pos(e12, "LA")[2] > zmax - 0.15 * H);
    CHECK(pos(e12, "RA")[0] > 50 && pos(e12, "LA")[0] < -50);
    CHECK(pos(e12, "LL")[2] < zmin + 0.15 * H && pos(e12, "LL")[0] < -30);
    CHECK(pos(e12, "RA")[1] > 0 && pos(e12, "LA")[1] > 0 && pos(e12, "LL")[1] > 0);
    /* nine distinct nodes */
    int distinct = 1;
    for (size_t i = 0; i < 9; i++)
        for (size_t j = 0; j < i; j++) distinct &= e12->node[i] != e12->node[j];
    CHECK(distinct);

    /* the array: names, distinct nodes, 12 rings of 16 from the bottom up, each from the anterior midline toward
     * the subject's left */
    int names_ok = 1;
    for (size_t i = 0; i < ea->n; i++) {
        char want[32];
        snprintf(want, sizeof want, "A%03zu", i + 1);
        names_ok &= !strcmp(ea->name[i], want);
    }
    CHECK(names_ok);
    unsigned char *used = calloc(outer->n_nodes, 1);
    size_t dup = 0;
    for (size_t i = 0; i < ea->n; i++) {
        if (used[ea->node[i]]) dup++;
        used[ea->node[i]] = 1;
    }
    free(used);
    CHECK(dup == 0);
    double prev = -INFINITY;
    int rings_up = 1, start_ok = 1, left_ok = 1, back_ok = 1;
    for (size_t k = 0; k < 12; k++) {
        double zsum = 0;
        for (size_t j = 0; j < 16; j++) zsum += ea->xyz[3 * (16 * k + j) + 2];
        rings_up &= zsum / 16 > prev;
        prev = zsum / 16;
        const double *a0 = ea->xyz + 3 * (16 * k), *a4 = ea->xyz + 3 * (16 * k + 4), *a8 = ea->xyz + 3 * (16 * k + 8);
        start_ok &= fabs(a0[0]) < 20 && a0[1] > 50;
        left_ok &= a4[0] < -80;
        back_ok &= a8[1] < -50;
    }
    CHECK(rings_up && start_ok && left_ok && back_ok);
    CHECK(ea->xyz[2] < zmin + 0.1 * H && ea->xyz[3 * 191 + 2] > zmax - 0.1 * H);

    /* deterministic; either output may be left out */
    thx_electrodes *b12 = NULL, *ba = NULL;
    CHECK_OK(ctx, thx_phantom_electrodes(ctx, m, &b12, 192, &ba));
    CHECK(same_set(e12, b12) && same_set(ea, ba));
    thx_electrodes_destroy(&b12);
    thx_electrodes_destroy(&ba);
    CHECK_OK(ctx, thx_phantom_electrodes(ctx, m, NULL, 50, &ba));
    CHECK(ba && ba->n == 50);
    if (ba) {
        CHECK_OK(ctx, thx_electrodes_check(ctx, ba, m));
        CHECK(!strcmp(ba->name[49], "A050"));
    }
    thx_electrodes_destroy(&ba);
    CHECK_OK(ctx, thx_phantom_electrodes(ctx, m, &b12, 0, &ba));
    CHECK(b12 && ba == NULL && same_set(e12, b12));
    thx_electrodes_destroy(&b12);
    /* too many array electrodes for distinct nodes; a model without a heart */
    CHECK(thx_phantom_electrodes(ctx, m, NULL, outer->n_nodes + 1, &ba) == THX_EINPUT && ba == NULL);
    thx_model *noheart = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &noheart));
    thx_surface *copy = NULL;
    CHECK_OK(ctx, thx_surface_create(ctx, "torso", THX_ROLE_OUTER, &copy));
    if (copy && noheart) {
        copy->n_nodes = outer->n_nodes;
        copy->n_tris = outer->n_tris;
        copy->xyz = malloc(3 * outer->n_nodes * sizeof *copy->xyz);
        copy->tri = malloc(3 * outer->n_tris * sizeof *copy->tri);
        memcpy(copy->xyz, outer->xyz, 3 * outer->n_nodes * sizeof *copy->xyz);
        memcpy(copy->tri, outer->tri, 3 * outer->n_tris * sizeof *copy->tri);
        CHECK_OK(ctx, thx_model_add_surface(ctx, noheart, &copy));
        CHECK(thx_phantom_electrodes(ctx, noheart, &b12, 192, &ba) == THX_EINPUT && !b12 && !ba);
        CHECK(strstr(thx_ctx_message(ctx), "no heart surface") != NULL);
    }
    thx_model_destroy(&noheart);
}

/* ------------------------------------------------------------- leads */

static void test_leads(const thx_model *m, const thx_electrodes *e12, const thx_electrodes *ea)
{
    const thx_surface *outer = by_role(m, THX_ROLE_OUTER);
    size_t N = outer->n_nodes, M = 4;
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, N, M, &s));
    if (!s) return;
    /* frame 0: phi = x; frame 1: phi = y; frame 2: phi = z; frame 3: irregular values */
    for (size_t r = 0; r < N; r++) {
        for (int k = 0; k < 3; k++) s->v[(size_t)k * N + r] = outer->xyz[3 * r + k];
        s->v[3 * N + r] = sin(0.37 * (double)r) * 1e3 + 1.0 / (1.0 + (double)r);
    }
    for (size_t f = 0; f < M; f++) s->time[f] = 2.5 * (double)f + 1;
    snprintf(s->unit, sizeof s->unit, "uV");
    snprintf(s->time_unit, sizeof s->time_unit, "s");

    thx_series *g = NULL;
    CHECK_OK(ctx, thx_electrodes_sample(ctx, ea, s, &g));
    CHECK(g && g->n_rows == ea->n && g->n_frames == M);
    if (g) {
        int ok = 1;
        for (size_t f = 0; f < M; f++)
            for (size_t i = 0; i < ea->n; i++) ok &= g->v[f * ea->n + i] == s->v[f * N + (size_t)ea->node[i]];
        CHECK(ok);
        CHECK(g->v[0] == ea->xyz[0] && g->v[ea->n + 5] == ea->xyz[3 * 5 + 1]);
        CHECK(g->time[3] == s->time[3] && !strcmp(g->unit, "uV") && !strcmp(g->time_unit, "s"));
    }
    thx_series_destroy(&g);

    thx_series *ecg = NULL;
    CHECK_OK(ctx, thx_ecg12(ctx, e12, s, &ecg));
    CHECK(ecg && ecg->n_rows == 12 && ecg->n_frames == M);
    if (ecg) {
        CHECK(!strcmp(ecg->unit, "uV") && !strcmp(ecg->time_unit, "s") && ecg->time[2] == s->time[2]);
        CHECK(strstr(ecg->label, "I II III aVR aVL aVF V1") != NULL);
        for (size_t f = 0; f < M; f++) {
            const double *L = ecg->v + f * 12;
            double ra = s->v[f * N + (size_t)e12->node[0]], la = s->v[f * N + (size_t)e12->node[1]],
                   ll = s->v[f * N + (size_t)e12->node[2]];
            double scale = fabs(ra) + fabs(la) + fabs(ll) + 1;
            /* frame 0, phi = x: lead I is x(LA) - x(RA) exactly */
            if (f == 0) CHECK(L[0] == pos(e12, "LA")[0] - pos(e12, "RA")[0]);
            if (f == 2) CHECK(L[1] == pos(e12, "LL")[2] - pos(e12, "RA")[2]);
            CHECK(L[0] == la - ra && L[1] == ll - ra && L[2] == ll - la);
            CHECK_NEAR(L[1], L[0] + L[2], 1e-13 * scale); /* Einthoven */
            CHECK_NEAR(L[3] + L[4] + L[5], 0.0, 1e-13 * scale);
            CHECK_NEAR(L[3], ra - 0.5 * (la + ll), 1e-13 * scale);
            CHECK_NEAR(L[4], la - 0.5 * (ra + ll), 1e-13 * scale);
            CHECK_NEAR(L[5], ll - 0.5 * (ra + la), 1e-13 * scale);
            /* aVF = (II + III) / 2, aVR = -(I + II) / 2 */
            CHECK_NEAR(L[5], 0.5 * (L[1] + L[2]), 1e-13 * scale);
            CHECK_NEAR(L[3], -0.5 * (L[0] + L[1]), 1e-13 * scale);
            for (int k = 0; k < 6; k++) {
                double vk = s->v[f * N + (size_t)e12->node[3 + k]];
                CHECK_NEAR(L[6 + k], vk - (ra + la + ll) / 3.0, 1e-12 * (scale + fabs(vk)));
            }
        }
        /* phi = y (frame 1): the V leads see the anterior electrodes above Wilson's terminal */
        CHECK(ecg->v[12 + 6] > 0 && ecg->v[12 + 7] > 0);
    }
    thx_series_destroy(&ecg);

    /* missing leads are named */
    CHECK(thx_ecg12(ctx, ea, s, &ecg) == THX_EINPUT && ecg == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "has no RA, LA, LL, V1, V2, V3, V4, V5, V6") != NULL);
    thx_electrodes *e = NULL;
    CHECK_OK(ctx, thx_electrodes_create(ctx, 9, &e));
    if (e) {
        memcpy(e->surface, e12->surface, sizeof e->surface);
        memcpy(e->name, e12->name, 9 * sizeof *e->name);
        memcpy(e->node, e12->node, 9 * sizeof *e->node);
        snprintf(e->name[7], sizeof e->name[7], "V5x");
        CHECK(thx_ecg12(ctx, e, s, &ecg) == THX_EINPUT && ecg == NULL);
        CHECK(strstr(thx_ctx_message(ctx), "has no V5 (it needs") != NULL);
        snprintf(e->name[7], sizeof e->name[7], "V5");
        /* a series on another surface (too few rows) */
        thx_series *small = NULL;
        CHECK_OK(ctx, thx_series_create(ctx, 10, 2, &small));
        CHECK(thx_ecg12(ctx, e, small, &ecg) == THX_EINPUT && ecg == NULL);
        CHECK(strstr(thx_ctx_message(ctx), "but the series has 10 rows") != NULL);
        CHECK(thx_electrodes_sample(ctx, e, small, &ecg) == THX_EINPUT && ecg == NULL);
        thx_series_destroy(&small);
    }
    thx_electrodes_destroy(&e);
    thx_series_destroy(&s);
}

/* ------------------------------------------------------------- the beat */

/* The centroid of a closed surface's enclosed volume, computed here independently (about the origin). */
static void centroid(const thx_surface *s, double c[3])
{
    double vol = 0, m[3] = {0, 0, 0};
    for (size_t t = 0; t < s->n_tris; t++) {
        const double *a = s->xyz + 3 * (size_t)s->tri[3 * t], *b = s->xyz + 3 * (size_t)s->tri[3 * t + 1],
                     *d = s->xyz + 3 * (size_t)s->tri[3 * t + 2];
        double v = (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                    a[2] * (b[0] * d[1] - b[1] * d[0])) / 6.0;
        vol += v;
        for (int k = 0; k < 3; k++) m[k] += v * (a[k] + b[k] + d[k]) / 4.0;
    }
    for (int k = 0; k < 3; k++) c[k] = m[k] / vol;
}

static double norm3(const double p[3]) { return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]); }

static void test_dipole_loop(void)
{
    thx_beat_opts o;
    thx_beat_opts_default(&o);
    CHECK(o.n_frames == 500 && o.dt_ms == 1 && o.sigma == 0.2 && o.peak_mv == 0 && o.dipole_mam == 0.016);
    /* at 10 us steps: the largest |p| is 1 (the QRS peak), in the QRS; P about 0.1, T about 0.3 */
    thx_beat_opts fine = o;
    fine.dt_ms = 0.01;
    double pmax[3] = {0, 0, 0}, tpk[3] = {0, 0, 0}, ppeak[3] = {0, 0, 0}, tpeak[3] = {0, 0, 0}, step = 0;
    double prev[3] = {0, 0, 0};
    int baseline = 1;
    for (size_t f = 0; f <= 50000; f++) {
        double p[3], t = 0.01 * (double)f;
        thx_beat_dipole(&fine, f, p);
        double n = norm3(p);
        int w = t < 150 ? 0 : t < 240 ? 1 : 2; /* P, QRS, T */
        if (n > pmax[w]) {
            pmax[w] = n;
            tpk[w] = t;
            if (w == 1) memcpy(ppeak, p, sizeof p);
            if (w == 2) memcpy(tpeak, p, sizeof p);
        }
        if (t <= 10 || (t >= 100 && t <= 150) || (t >= 240 && t <= 310) || t >= 470) baseline &= n == 0;
        double d[3] = {p[0] - prev[0], p[1] - prev[1], p[2] - prev[2]};
        step = fmax(step, norm3(d) / 0.01);
        memcpy(prev, p, sizeof p);
    }
    CHECK(baseline);
    CHECK_NEAR(pmax[1], 1.0, 1e-6);
    CHECK(tpk[1] > 170 && tpk[1] < 210);
    CHECK(pmax[0] > 0.05 && pmax[0] < 0.2);
    CHECK(pmax[2] > 0.2 && pmax[2] < 0.4);
    CHECK(step < 0.1); /* |dp/dt| per ms: smooth, no jumps */
    /* QRS peak: left (-x), posterior (-y), inferior (-z) */
    CHECK(ppeak[0] < -0.3 && ppeak[1] < -0.1 && ppeak[2] < -0.5);
    /* T: left and inferior, within 60 degrees of the QRS peak */
    CHECK(tpeak[0] < 0 && tpeak[2] < 0);
    CHECK((ppeak[0] * tpeak[0] + ppeak[1] * tpeak[1] + ppeak[2] * tpeak[2]) / (norm3(ppeak) * norm3(tpeak)) > 0.5);
    /* dt scales time: frame 100 at 2 ms is frame 200 at 1 ms */
    double a[3], b[3];
    thx_beat_opts two = o;
    two.dt_ms = 2;
    thx_beat_dipole(&two, 100, a);
    thx_beat_dipole(&o, 200, b);
    CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
    thx_beat_dipole(NULL, 200, a);
    CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
}

static void test_beat(const thx_model *m)
{
    const thx_surface *heart = by_role(m, THX_ROLE_HEART);
    thx_beat_opts o;
    thx_beat_opts_default(&o);
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_phantom_epicardial(ctx, heart, &o, &s));
    if (!s) return;
    size_t N = heart->n_nodes, M = s->n_frames;
    CHECK(s->n_rows == N && M == 500 && M >= 300);
    CHECK(!strcmp(s->unit, "mV") && !strcmp(s->time_unit, "ms") && s->time[0] == 0 && s->time[499] == 499);
    CHECK(strncmp(s->label, "phantom beat", 12) == 0);
    double vmax = 0, step = 0, wmax[3] = {0, 0, 0};
    int base = 1;
    for (size_t f = 0; f < M; f++)
        for (size_t r = 0; r < N; r++) {
            double v = s->v[f * N + r];
            vmax = fmax(vmax, fabs(v));
            if (f) step = fmax(step, fabs(v - s->v[(f - 1) * N + r]));
            wmax[f < 150 ? 0 : f < 240 ? 1 : 2] = fmax(wmax[f < 150 ? 0 : f < 240 ? 1 : 2], fabs(v));
            if (f <= 10 || (f >= 100 && f <= 150) || (f >= 240 && f <= 310) || f >= 470) base &= v == 0;
        }
    /* the default scale is the dipole moment (16 uA m at the QRS peak): about 2 mV on the phantom's heart */
    CHECK(vmax > 1 && vmax < 4);
    CHECK(base);
    CHECK(step < 0.1 * vmax); /* per 1 ms frame */
    CHECK(wmax[1] == vmax && wmax[0] < 0.25 * vmax && wmax[2] < 0.5 * vmax && wmax[2] > 0.15 * vmax);

    /* the analytic field: phi = k p . d / |d|^3 with one k for every node and frame */
    double r0[3];
    centroid(heart, r0);
    size_t fpk = 0;
    double best = 0;
    for (size_t f = 0; f < M; f++) {
        double p[3];
        thx_beat_dipole(&o, f, p);
        if (norm3(p) > best) {
            best = norm3(p);
            fpk = f;
        }
    }
    double k = 0, worst = 0;
    int sign_ok = 1;
    for (size_t f = 0; f < M; f += 7) {
        double p[3];
        thx_beat_dipole(&o, f, p);
        for (size_t r = 0; r < N; r++) {
            double d[3], d2 = 0;
            for (int c = 0; c < 3; c++) {
                d[c] = (heart->xyz[3 * r + c] - r0[c]) * 1e-3;
                d2 += d[c] * d[c];
            }
            double phi = 1e3 * (p[0] * d[0] + p[1] * d[1] + p[2] * d[2]) / (4 * M_PI * o.sigma * d2 * sqrt(d2));
            if (k == 0 && fabs(phi) > 1e-3) k = s->v[f * N + r] / phi;
            if (k) worst = fmax(worst, fabs(s->v[f * N + r] - k * phi));
        }
    }
    CHECK_NEAR(k, o.dipole_mam * 1e-3, 1e-12 * o.dipole_mam * 1e-3); /* A m at |p| = 1 */
    CHECK(worst < 1e-9 * vmax);
    /* the label reports the dipole: k A m at |p| = 1, in mA m */
    char want[32];
    snprintf(want, sizeof want, "dipole %.4g mA m", k * 1e3);
    CHECK(strstr(s->label, want) != NULL);
    /* at the QRS peak: positive where the dipole points, negative behind it */
    {
        double p[3];
        thx_beat_dipole(&o, fpk, p);
        size_t pos_n = 0, neg_n = 0;
        for (size_t r = 0; r < N; r++) {
            double dot = 0;
            for (int c = 0; c < 3; c++) dot += p[c] * (heart->xyz[3 * r + c] - r0[c]);
            double v = s->v[fpk * N + r];
            if (dot > 0) {
                sign_ok &= v > 0;
                pos_n++;
            } else if (dot < 0) {
                sign_ok &= v < 0;
                neg_n++;
            }
        }
        CHECK(sign_ok && pos_n > N / 4 && neg_n > N / 4);
        CHECK(fpk > 170 && fpk < 210);
    }
    thx_series_destroy(&s);

    /* options: frames, dt and peak */
    thx_beat_opts o2 = o;
    o2.n_frames = 300;
    o2.dt_ms = 2;
    o2.peak_mv = 5;
    CHECK_OK(ctx, thx_phantom_epicardial(ctx, heart, &o2, &s));
    if (s) {
        double mx = 0;
        for (size_t i = 0; i < N * 300; i++) mx = fmax(mx, fabs(s->v[i]));
        CHECK(s->n_frames == 300 && s->time[299] == 598);
        CHECK_NEAR(mx, 5, 1e-12 * 5);
    }
    thx_series_destroy(&s);

    /* errors */
    thx_beat_opts bad = o;
    bad.n_frames = 0;
    CHECK(thx_phantom_epicardial(ctx, heart, &bad, &s) == THX_EINPUT && s == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "n_frames is 0") != NULL);
    bad = o;
    bad.n_frames = 5; /* all baseline: nothing to scale */
    CHECK(thx_phantom_epicardial(ctx, heart, &bad, &s) == THX_EINPUT && s == NULL);
    bad = o;
    bad.dt_ms = 0;
    CHECK(thx_phantom_epicardial(ctx, heart, &bad, &s) == THX_EINPUT && s == NULL);
    bad = o;
    bad.peak_mv = -1;
    CHECK(thx_phantom_epicardial(ctx, heart, &bad, &s) == THX_EINPUT && s == NULL);
    bad = o;
    bad.dipole_mam = 0; /* no --peak either: nothing sets the scale */
    CHECK(thx_phantom_epicardial(ctx, heart, &bad, &s) == THX_EINPUT && s == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "dipole moment 0 mA m is not positive") != NULL);
    thx_surface *empty = NULL;
    CHECK_OK(ctx, thx_surface_create(ctx, "heart", THX_ROLE_HEART, &empty));
    CHECK(thx_phantom_epicardial(ctx, empty, &o, &s) == THX_EINPUT && s == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "heart surface \"heart\" has no nodes") != NULL);
    /* an octahedron (centroid at the origin) with a seventh node at the origin: on the dipole */
    static const double oct[21] = {10, 0, 0, -10, 0, 0, 0, 10, 0, 0, -10, 0, 0, 0, 10, 0, 0, -10, 0, 0, 0};
    static const int32_t tri[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    empty->n_nodes = 7;
    empty->n_tris = 8;
    empty->xyz = malloc(sizeof oct);
    empty->tri = malloc(sizeof tri);
    memcpy(empty->xyz, oct, sizeof oct);
    memcpy(empty->tri, tri, sizeof tri);
    CHECK(thx_surface_volume(empty) > 0);
    CHECK(thx_phantom_epicardial(ctx, empty, &o, &s) == THX_EGEOM && s == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "node 7 at (0.000000, 0.000000, 0.000000) lies on the dipole") != NULL);
    /* without the seventh node: the field of a dipole at the centre, antisymmetric between opposite nodes */
    empty->n_nodes = 6;
    CHECK_OK(ctx, thx_phantom_epicardial(ctx, empty, &o, &s));
    if (s) {
        int anti = 1;
        for (size_t f = 0; f < s->n_frames; f++)
            for (size_t r = 0; r < 6; r += 2) anti &= fabs(s->v[f * 6 + r] + s->v[f * 6 + r + 1]) < 1e-9;
        CHECK(anti);
        /* nodes +-x: phi ~ p_x; at the QRS peak p_x < 0, so the left node (-x, index 1) is positive */
        CHECK(s->v[fpk * 6 + 1] > 0 && s->v[fpk * 6 + 0] < 0);
    }
    thx_series_destroy(&s);
    thx_surface_destroy(&empty);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_electrodes")) return 1;
    test_create();
    thx_model *m = phantom_model();
    thx_electrodes *e12 = NULL, *ea = NULL;
    CHECK_OK(ctx, thx_phantom_electrodes(ctx, m, &e12, 192, &ea));
    if (!e12 || !ea) return 1;
    test_round_trip(m, e12, ea);
    test_bad_files();
    test_check(m, e12);
    test_phantom_electrodes(m, e12, ea);
    test_leads(m, e12, ea);
    test_dipole_loop();
    test_beat(m);
    thx_electrodes_destroy(&e12);
    thx_electrodes_destroy(&ea);
    thx_model_destroy(&m);
    int rc = tl_scratch_finish("test_electrodes");
    thx_ctx_destroy(&ctx);
    return rc;
}
