/*
 * Tests of map3d's files (src/io/map3d/graphicsio.c, src/io/series/series_potset.c, series_fids.c,
 * series_matrix.c, the fids and kept fields of series_mat.c) on the real files
 * of shared/data/map3d:
 *  - every .geom surface equals the .pts/.fac text pair holding the same surface
 *    (daltorso, both surfaces of daltorsoepi, the closed sock): nodes to the
 *    float precision of the text, triangles exactly (1-based in both);
 *  - dipole2.tsdf equals dipole2_001..006.pot, read one by one and as one
 *    numbered set (pattern and directory); cool1-atdr-run1.tsdf equals the
 *    int32 recording cool1-atdr-run1.mat exactly; the q/s/t times of the .tsdf
 *    header are kept as fiducials (minus 1);
 *  - VAX F_floating decoding on hand-made bytes (1, -62, 0.5, the largest
 *    value, the reserved operand refused with its byte offset);
 *  - damaged files: every truncation of the sock .geom and of dipole2.tsdf is
 *    refused with the file and a byte offset, never read; counts larger than
 *    the file, pointers out of it, node numbers out of range, tetrahedra, an
 *    external data file: each refused, naming the byte;
 *  - map3d's ts struct (rsm10jan01-cs-0004.mat) through .mat and back: the same
 *    fields in the same order, the same fiducials; a .fids file read onto a
 *    series; CSV out and back exactly; plain matrices in (blanks, commas, a
 *    header of times, ragged rows refused); .pot sets with a gap refused.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testlib.h"
#include "thorax/io/graphicsio.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/io/surface_read.h"
#include "thorax/model/series.h"

static thx_ctx *ctx;
static char data[2048];

static const char *dpath(const char *rel)
{
    static char p[4][2300];
    static int k;
    k = (k + 1) % 4;
    snprintf(p[k], sizeof p[k], "%s/%s", data, rel);
    return p[k];
}

static unsigned char *slurp(const char *path, size_t *len)
{
    char *b = tl_slurp(ctx, path, len);
    return (unsigned char *)b;
}

/* The message of the last error holds every needle. */
static int msg_has(const char *a, const char *b)
{
    const char *m = thx_ctx_message(ctx);
    int ok = m && strstr(m, a) && (!b || strstr(m, b));
    if (!ok) fprintf(stderr, "  message: %s (wanted '%s'%s%s)\n", m ? m : "(none)", a, b ? ", " : "", b ? b : "");
    return ok;
}

/* ----------------------------------------------------------------- .geom */

static void geom_vs_ptsfac(const char *geom, const char *pts, size_t n_nodes, size_t n_tris)
{
    thx_surface *g = NULL, *t = NULL;
    thx_surface_read_info info;
    CHECK_OK(ctx, thx_surface_read_file(ctx, dpath(geom), NULL, THX_IMPORT_AUTO, "g", THX_ROLE_OUTER, &g, &info));
    CHECK_OK(ctx, thx_surface_read_file(ctx, dpath(pts), NULL, THX_IMPORT_AUTO, "t", THX_ROLE_OUTER, &t, NULL));
    if (!g || !t) goto out;
    CHECK(info.format == THX_IMPORT_GEOM && info.index_base == 1);
    CHECK(g->n_nodes == n_nodes && t->n_nodes == n_nodes);
    CHECK(g->n_tris == n_tris && t->n_tris == n_tris);
    if (g->n_nodes != t->n_nodes || g->n_tris != t->n_tris) goto out;
    /* the text has 2 decimals (daltorso) or more: the .geom's floats agree to their precision */
    double worst = 0;
    for (size_t i = 0; i < 3 * g->n_nodes; i++) {
        double d = fabs(g->xyz[i] - t->xyz[i]) / fmax(1.0, fabs(t->xyz[i]));
        if (d > worst) worst = d;
    }
    CHECK(worst < 1e-6);
    size_t same = 0;
    for (size_t i = 0; i < 3 * g->n_tris; i++) same += g->tri[i] == t->tri[i];
    CHECK(same == 3 * g->n_tris);
out:
    thx_surface_destroy(&g);
    thx_surface_destroy(&t);
}

static void test_geom_real(void)
{
    geom_vs_ptsfac("geom/torso/daltorso.geom", "geom/torso/daltorso.pts", 352, 700);
    geom_vs_ptsfac("geom/torso/daltorsoepi.geom@1", "geom/torso/daltorso.pts", 352, 700);
    geom_vs_ptsfac("geom/torso/daltorsoepi.geom@2", "geom/torso/dalepi.pts", 98, 192);
    geom_vs_ptsfac("geom/tank/25feb97_sock_closed.geom", "geom/tank/25feb97_sock_closed.pts", 128, 252);
    /* two surfaces and no pick: refused, naming the way to pick */
    thx_surface *s = NULL;
    CHECK(thx_surface_read_file(ctx, dpath("geom/torso/daltorsoepi.geom"), NULL, THX_IMPORT_AUTO, "x", THX_ROLE_OUTER, &s,
                                NULL) == THX_EINPUT);
    CHECK(msg_has("holds 2 surfaces", "daltorsoepi.geom@1"));
    CHECK(thx_surface_read_file(ctx, dpath("geom/torso/daltorsoepi.geom@3"), NULL, THX_IMPORT_AUTO, "x", THX_ROLE_OUTER,
                                &s, NULL) == THX_EINPUT);
    CHECK(msg_has("holds 2 surfaces (1..2)", NULL));
    CHECK(!s);
}

/* A hand-made .geom: one surface of n nodes and t triangles (1-based node numbers), 40-byte header. */
typedef struct { unsigned char b[4096]; size_t n; } buf;

static void put32(buf *b, size_t at, long v)
{
    uint32_t u = (uint32_t)v;
    for (int k = 0; k < 4; k++) b->b[at + k] = (unsigned char)(u >> (8 * k));
    if (at + 4 > b->n) b->n = at + 4;
}

/* VAX F_floating bytes of x (x exactly representable, normal). */
static void putvax(buf *b, size_t at, double x)
{
    uint32_t w = 0;
    if (x != 0) {
        int e;
        double m = frexp(fabs(x), &e); /* x = m 2^e, m in [0.5, 1) = VAX's 0.1f */
        uint32_t f = (uint32_t)llround((m - 0.5) * 16777216.0);
        w = (x < 0 ? 1u << 31 : 0) | (uint32_t)(e + 128) << 23 | f;
    }
    b->b[at] = (unsigned char)(w >> 16), b->b[at + 1] = (unsigned char)(w >> 24);
    b->b[at + 2] = (unsigned char)w, b->b[at + 3] = (unsigned char)(w >> 8);
    if (at + 4 > b->n) b->n = at + 4;
}

static void make_tet_geom(buf *b)
{
    memset(b, 0, sizeof *b);
    put32(b, 0, 40), put32(b, 8, 0), put32(b, 12, 1), put32(b, 16, 40);
    /* surface header at 40: size, next, node header 60, element header 72, no info block */
    put32(b, 40, 20), put32(b, 44, 0), put32(b, 48, 60), put32(b, 52, 72), put32(b, 56, 0);
    put32(b, 60, 12), put32(b, 64, 4), put32(b, 68, 88);
    put32(b, 72, 16), put32(b, 76, 4), put32(b, 80, 3), put32(b, 84, 136);
    static const double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 12; i++) putvax(b, 88 + 4 * (size_t)i, xyz[i]);
    static const long tri[12] = {1, 3, 2, 1, 2, 4, 1, 4, 3, 2, 3, 4};
    for (int i = 0; i < 12; i++) put32(b, 136 + 4 * (size_t)i, tri[i]);
}

static thx_status parse_geom(buf *b, thx_surface **s)
{
    return thx_geom_parse(ctx, "t.geom", b->b, b->n, NULL, "t", THX_ROLE_OUTER, s, NULL);
}

static void test_geom_bad(void)
{
    buf b;
    thx_surface *s = NULL;
    make_tet_geom(&b);
    CHECK_OK(ctx, parse_geom(&b, &s));
    CHECK(s && s->n_nodes == 4 && s->n_tris == 4 && s->xyz[3] == 1 && s->tri[0] == 0 && s->tri[1] == 2);
    thx_surface_destroy(&s);
    /* every truncation is refused (never read past the end) */
    size_t full = b.n, refused = 0;
    for (size_t n = 0; n < full; n++) {
        b.n = n;
        refused += parse_geom(&b, &s) == THX_EINPUT && !s;
    }
    CHECK(refused == full);
    b.n = full;
    CHECK(parse_geom(&b, &s) == THX_OK);
    thx_surface_destroy(&s);
    /* a node count larger than the file */
    make_tet_geom(&b);
    put32(&b, 64, 1000000);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("t.geom: byte 64:", "node count 1000000"));
    /* nodes pointing out of the file */
    make_tet_geom(&b);
    put32(&b, 68, 5000);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("t.geom: byte 68:", "the nodes at byte 5000"));
    /* a node number out of range, named at its byte */
    make_tet_geom(&b);
    put32(&b, 136 + 4 * 5, 5);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("t.geom: byte 156:", "triangle 2: node number 5 out of range 1..4"));
    /* 0 is not a node number (1-based) */
    make_tet_geom(&b);
    put32(&b, 136, 0);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("byte 136:", "node number 0"));
    /* tetrahedra are a volume */
    make_tet_geom(&b);
    put32(&b, 80, 4);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("byte 80:", "tetrahedra"));
    /* the VAX reserved operand (sign, zero exponent) is not a number */
    make_tet_geom(&b);
    b.b[88 + 4 * 4 + 1] = 0x80, b.b[88 + 4 * 4] = 0;
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("byte 104:", "node 2: coordinate y is a VAX reserved operand"));
    /* not a graphicsio file */
    make_tet_geom(&b);
    put32(&b, 0, 48);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("byte 0:", "not a map3d graphicsio"));
    /* a surface count the file cannot hold */
    make_tet_geom(&b);
    put32(&b, 12, 100000);
    CHECK(parse_geom(&b, &s) == THX_EINPUT && msg_has("byte 12:", "surface count 100000"));
    CHECK(!s);
}

/* VAX F_floating values through a 1-node "surface" is awkward: decode through a tsdf of 1 x k. */
static void make_tsdf(buf *b, size_t nch, size_t nfr, const double *v)
{
    memset(b, 0, sizeof *b);
    put32(b, 0, 40), put32(b, 28, 1), put32(b, 32, 40);
    size_t t = 40, d = t + 324;
    put32(b, t, 324), put32(b, t + 88, 1), put32(b, t + 92, (long)nch), put32(b, t + 96, (long)nfr);
    put32(b, t + 100, (long)d), put32(b, t + 108, 3), put32(b, t + 300, 1);
    memcpy(b->b + t + 212, "hand made", 9);
    for (size_t i = 0; i < nch * nfr; i++) putvax(b, d + 4 * i, v[i]);
}

static thx_status parse_tsdf(buf *b, thx_series **s) { return thx_tsdf_parse(ctx, "t.tsdf", b->b, b->n, NULL, s); }

static void test_tsdf_hand(void)
{
    /* frame-major: frame 0 = (1, -62), frame 1 = (0.5, max), frame 2 = (0, -3.25) */
    const double vmax = ldexp(1.0 - ldexp(1.0, -24), 127); /* VAX F's largest, 2^127 (1 - 2^-24) */
    double v[6] = {1, -62, 0.5, vmax, 0, -3.25};
    buf b;
    make_tsdf(&b, 2, 3, v);
    thx_series *s = NULL;
    CHECK_OK(ctx, parse_tsdf(&b, &s));
    if (s) {
        CHECK(s->n_rows == 2 && s->n_frames == 3);
        for (int i = 0; i < 6; i++) CHECK(s->v[i] == v[i]);
        CHECK(!strcmp(s->unit, "mV") && !strcmp(s->label, "hand made") && !strcmp(s->time_unit, "frame"));
        CHECK(s->n_fids == 1 && s->fids[0].type == 2 && s->fids[0].n == 1 && s->fids[0].v[0] == 2);
    }
    thx_series_destroy(&s);
    size_t full = b.n, refused = 0;
    for (size_t n = 0; n < full; n++) {
        b.n = n;
        refused += parse_tsdf(&b, &s) == THX_EINPUT && !s;
    }
    CHECK(refused == full);
    /* frames beyond the file */
    make_tsdf(&b, 2, 3, v);
    put32(&b, 40 + 96, 1 << 30);
    CHECK(parse_tsdf(&b, &s) == THX_EINPUT && msg_has("t.tsdf: byte 132:", "cannot fit in a file"));
    /* data pointer beyond the end */
    make_tsdf(&b, 2, 3, v);
    put32(&b, 40 + 100, 400);
    CHECK(parse_tsdf(&b, &s) == THX_EINPUT && msg_has("byte 140:", "the data at byte 400"));
    /* the reserved operand in channel 2, frame 2 */
    make_tsdf(&b, 2, 3, v);
    b.b[364 + 12 + 1] = 0x80, b.b[364 + 12] = 0;
    CHECK(parse_tsdf(&b, &s) == THX_EINPUT && msg_has("byte 376:", "channel 2, frame 2 is a VAX reserved operand"));
    /* data in an external file */
    make_tsdf(&b, 2, 3, v);
    memcpy(b.b + 40 + 132, "t1f001.raw", 10);
    CHECK(parse_tsdf(&b, &s) == THX_EINPUT && msg_has("byte 172:", "external file 't1f001.raw'"));
    /* a header size that is no .tsdf header */
    make_tsdf(&b, 2, 3, v);
    put32(&b, 40, 100);
    CHECK(parse_tsdf(&b, &s) == THX_EINPUT && msg_has("byte 40:", "header size 100"));
    CHECK(!s);
}

/* Two series in one file, and two named surfaces: picked by number and by label or name. */
static void test_pick(void)
{
    double v[6] = {1, 2, 3, 4, 5, 6};
    buf b;
    make_tsdf(&b, 2, 3, v);
    /* a second series header after the data (at 388), 1 x 2, label "second" */
    size_t t2 = b.n, d2 = t2 + 308;
    put32(&b, 28, 2), put32(&b, 40 + 4, (long)t2);
    put32(&b, t2, 308), put32(&b, t2 + 92, 1), put32(&b, t2 + 96, 2), put32(&b, t2 + 100, (long)d2);
    memcpy(b.b + t2 + 212, "second", 6);
    putvax(&b, d2, 7), putvax(&b, d2 + 4, -8);
    thx_series *s = NULL;
    CHECK(thx_tsdf_parse(ctx, "t.tsdf", b.b, b.n, NULL, &s) == THX_EINPUT);
    CHECK(msg_has("t.tsdf: holds 2 time series: pick one as t.tsdf@1 .. t.tsdf@2 (or @LABEL)", NULL));
    CHECK_OK(ctx, thx_tsdf_parse(ctx, "t.tsdf", b.b, b.n, "2", &s));
    if (s) CHECK(s->n_rows == 1 && s->n_frames == 2 && s->v[1] == -8 && !strcmp(s->label, "second") && !s->unit[0]);
    thx_series_destroy(&s);
    CHECK_OK(ctx, thx_tsdf_parse(ctx, "t.tsdf", b.b, b.n, "hand made", &s));
    if (s) CHECK(s->n_rows == 2 && s->v[5] == 6);
    thx_series_destroy(&s);
    CHECK(thx_tsdf_parse(ctx, "t.tsdf", b.b, b.n, "third", &s) == THX_EINPUT && msg_has("t.tsdf@third: no time series", NULL));
    /* the second series' data cut off: the file is refused even when the first is picked */
    CHECK(thx_tsdf_parse(ctx, "t.tsdf", b.b, b.n - 2, "1", &s) == THX_EINPUT && msg_has("byte 488: the data at byte 696", NULL));
    CHECK(!s);
    /* a .geom with a named surface (info block at 184: size 88, name "heart") */
    make_tet_geom(&b);
    put32(&b, 56, 184), put32(&b, 184, 88);
    memcpy(b.b + 188, "heart", 5);
    b.n = 184 + 88;
    thx_surface *g = NULL;
    CHECK_OK(ctx, thx_geom_parse(ctx, "t.geom", b.b, b.n, "heart", NULL, THX_ROLE_HEART, &g, NULL));
    if (g) CHECK(!strcmp(g->name, "heart") && g->n_tris == 4);
    thx_surface_destroy(&g);
    CHECK(thx_geom_parse(ctx, "t.geom", b.b, b.n, "lung", NULL, THX_ROLE_HEART, &g, NULL) == THX_EINPUT &&
          msg_has("t.geom@lung: no surface of that NAME", NULL));
}

/* ----------------------------------------------------------------- .tsdf */

static void test_tsdf_real(void)
{
    thx_series *t = NULL, *set = NULL, *dir = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/torso/dipole2.tsdf"), THX_SERIES_AUTO, &t));
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/torso/dipole2_%03d.pot"), THX_SERIES_AUTO, &set));
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/torso"), THX_SERIES_AUTO, &dir));
    if (t && set && dir) {
        CHECK(t->n_rows == 352 && t->n_frames == 6 && set->n_rows == 352 && set->n_frames == 6);
        CHECK(!strcmp(t->unit, "uV"));
        double worst = 0;
        size_t same = 0;
        for (size_t i = 0; i < 352 * 6; i++) {
            /* the .pot text has 2 decimals, the .tsdf float32 precision */
            worst = fmax(worst, fabs(t->v[i] - set->v[i]));
            same += set->v[i] == dir->v[i];
        }
        CHECK(worst < 1e-6);
        CHECK(same == 352 * 6);
        /* frame 3 of the set is dipole2_004.pot */
        thx_series *one = NULL;
        CHECK_OK(ctx, thx_series_read(ctx, dpath("data/torso/dipole2_004.pot"), THX_SERIES_AUTO, &one));
        if (one) CHECK(!memcmp(one->v, set->v + 3 * 352, 352 * sizeof(double)));
        thx_series_destroy(&one);
    }
    thx_series_destroy(&t);
    thx_series_destroy(&set);
    thx_series_destroy(&dir);
    /* the tank recording: the same numbers as the int32 .mat, and its q/s/t times */
    thx_series *a = NULL, *m = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/tank/cool1-atdr-run1.tsdf"), THX_SERIES_AUTO, &a));
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/tank/cool1-atdr-run1.mat"), THX_SERIES_AUTO, &m));
    if (a && m) {
        CHECK(a->n_rows == 512 && a->n_frames == 608 && m->n_rows == 512 && m->n_frames == 608);
        CHECK(!memcmp(a->v, m->v, 512 * 608 * sizeof(double)));
        CHECK(!strcmp(a->unit, "uV"));
        CHECK(a->n_fids == 3);
        if (a->n_fids == 3)
            CHECK(a->fids[0].type == 2 && a->fids[0].v[0] == 155 && a->fids[1].type == 4 && a->fids[1].v[0] == 196 &&
                  a->fids[2].type == 7 && a->fids[2].v[0] == 384);
    }
    thx_series_destroy(&a);
    thx_series_destroy(&m);
    /* .tsdfc refused, saying why */
    CHECK(thx_series_read(ctx, "x.tsdfc", THX_SERIES_AUTO, &a) == THX_EINPUT && msg_has("x.tsdfc", "GDBM"));
    /* every truncation of a real .tsdf refused */
    size_t len = 0;
    unsigned char *b = slurp(dpath("data/torso/dipole2.tsdf"), &len);
    size_t refused = 0, tried = 0;
    for (size_t n = 0; b && n < len; n += 37, tried++) {
        thx_series *s = NULL;
        refused += thx_tsdf_parse(ctx, "d.tsdf", b, n, NULL, &s) == THX_EINPUT && !s;
    }
    CHECK(tried > 200 && refused == tried);
    free(b);
}

/* ---------------------------------------------------------- .pot sets */

static void test_pot_sets(void)
{
    char p[1200];
    for (int k = 1; k <= 4; k++) {
        if (k == 3) continue; /* a gap */
        snprintf(p, sizeof p, "%s/m_%02d.pot", tl_scratch, k);
        tl_write_text(p, k == 4 ? "1\n2\n" : "1\n2\n3\n");
    }
    thx_series *s = NULL;
    snprintf(p, sizeof p, "%s/m_%%02d.pot", tl_scratch);
    CHECK(thx_series_read(ctx, p, THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("jump from 2 (m_02.pot) to 4 (m_04.pot)", NULL));
    snprintf(p, sizeof p, "%s/m_03.pot", tl_scratch);
    tl_write_text(p, "4 5 6");
    snprintf(p, sizeof p, "%s/m_%%02d.pot", tl_scratch);
    CHECK(thx_series_read(ctx, p, THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("m_04.pot: 2 values", NULL));
    snprintf(p, sizeof p, "%s/m_04.pot", tl_scratch);
    tl_write_text(p, "7 8 9");
    snprintf(p, sizeof p, "%s/m_%%02d.pot", tl_scratch);
    CHECK_OK(ctx, thx_series_read(ctx, p, THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 3 && s->n_frames == 4 && s->v[6] == 4 && s->v[11] == 9);
    thx_series_destroy(&s);
    /* %d matches m_1 and m_01 alike: two files of number 1 */
    snprintf(p, sizeof p, "%s/m_1.pot", tl_scratch);
    tl_write_text(p, "1 2 3");
    snprintf(p, sizeof p, "%s/m_%%d.pot", tl_scratch);
    CHECK(thx_series_read(ctx, p, THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("the same number 1", NULL));
    snprintf(p, sizeof p, "%s/m_1.pot", tl_scratch);
    remove(p);
}

/* ------------------------------------------- map3d's ts struct, fids, CSV */

static int same_fields(const thx_series *a, const thx_series *b)
{
    if (a->n_fields != b->n_fields || strcmp(a->group, b->group)) return 0;
    for (size_t k = 0; k < a->n_fields; k++) {
        const thx_series_field *x = &a->fields[k], *y = &b->fields[k];
        if (strcmp(x->name, y->name) || x->cls != y->cls || x->nbytes != y->nbytes) return 0;
        if (x->nbytes && memcmp(x->data, y->data, x->nbytes)) return 0;
    }
    return 1;
}

static int same_fids(const thx_series *a, const thx_series *b)
{
    if (a->n_fids != b->n_fids) return 0;
    for (size_t k = 0; k < a->n_fids; k++)
        if (a->fids[k].type != b->fids[k].type || a->fids[k].n != b->fids[k].n ||
            memcmp(a->fids[k].v, b->fids[k].v, a->fids[k].n * sizeof(double)))
            return 0;
    return 1;
}

static void test_ts_struct(void)
{
    thx_series *a = NULL, *b = NULL;
    CHECK_OK(ctx, thx_series_read(ctx, dpath("data/socks/10jan01/rsm10jan01-cs-0004.mat"), THX_SERIES_AUTO, &a));
    if (!a) return;
    CHECK(!strcmp(a->group, "ts") && a->n_fields == 23 && a->n_fids == 9);
    const thx_series_field *fs = thx_series_field_get(a, "samplefrequency"), *au = thx_series_field_get(a, "audit");
    CHECK(fs && fs->cls == THX_FIELD_DOUBLE && *(double *)fs->data == 1000);
    CHECK(au && au->cls == THX_FIELD_CHAR && !strncmp(au->data, "ACQ-file converted", 18));
    CHECK(a->fids[7].type == 10 && a->fids[7].n == 490 && a->fids[0].type == 2 && a->fids[0].n == 1);
    CHECK_OK(ctx, thx_series_write(ctx, a, tl_path("ts.mat"), THX_SERIES_AUTO));
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("ts.mat"), THX_SERIES_AUTO, &b));
    if (b) {
        CHECK(same_fields(a, b));
        CHECK(same_fids(a, b));
        CHECK(!memcmp(a->v, b->v, a->n_rows * a->n_frames * sizeof(double)));
        CHECK(!memcmp(a->time, b->time, a->n_frames * sizeof(double)));
        CHECK(!strcmp(a->unit, b->unit) && !strcmp(a->label, b->label));
    }
    thx_series_destroy(&b);
    /* CSV and back: the same values and times, exactly */
    CHECK_OK(ctx, thx_series_write(ctx, a, tl_path("ts.csv"), THX_SERIES_AUTO));
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("ts.csv"), THX_SERIES_AUTO, &b));
    if (b) {
        CHECK(b->n_rows == 490 && b->n_frames == 712);
        CHECK(!memcmp(a->v, b->v, a->n_rows * a->n_frames * sizeof(double)));
        CHECK(!memcmp(a->time, b->time, a->n_frames * sizeof(double)));
        CHECK(!strcmp(b->unit, "mV") && !strcmp(b->time_unit, "ms"));
    }
    thx_series_destroy(&b);
    /* a .fids file on a 3-row series; its values count from 1 */
    thx_series *s = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 3, 10, &s));
    tl_write_text(tl_path("a.fids"), "% map3d fids\n1\n1 -1\n3 activation, recovery\n1 8 212\n2 16 225\n3 9.5 214\n");
    CHECK_OK(ctx, thx_series_read_fids(ctx, tl_path("a.fids"), s));
    CHECK(s->n_fids == 2 && s->fids[0].type == 10 && s->fids[1].type == 13 && s->fids[0].v[2] == 8.5 &&
          s->fids[1].v[0] == 211);
    tl_write_text(tl_path("b.fids"), "1\n1\n3 act\n1 8\n3 9\n2 7\n");
    CHECK(thx_series_read_fids(ctx, tl_path("b.fids"), s) == THX_EINPUT && msg_has("b.fids:5:", "lead number 2"));
    tl_write_text(tl_path("c.fids"), "1\n1\n4 act\n");
    CHECK(thx_series_read_fids(ctx, tl_path("c.fids"), s) == THX_EINPUT && msg_has("c.fids:3:", "4 leads, but the series has 3"));
    tl_write_text(tl_path("d.fids"), "1\n1\n3 wobble\n");
    CHECK(thx_series_read_fids(ctx, tl_path("d.fids"), s) == THX_EINPUT && msg_has("d.fids:3:", "'wobble' unknown"));
    CHECK(s->n_fids == 2);
    thx_series_destroy(&s);
    thx_series_destroy(&a);
}

static void test_matrix(void)
{
    thx_series *s = NULL;
    tl_write_text(tl_path("m.txt"), "# two channels, three frames\n1 2 3\n4\t5 6e1\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("m.txt"), THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 2 && s->n_frames == 3 && s->v[1] == 4 && s->v[5] == 60 && !strcmp(s->time_unit, "frame"));
    CHECK_OK(ctx, thx_series_transpose(ctx, &s));
    if (s) CHECK(s->n_rows == 3 && s->n_frames == 2 && s->v[3] == 4 && s->v[5] == 60);
    thx_series_destroy(&s);
    tl_write_text(tl_path("m.csv"), "1,2,3\n4,5,nan\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("m.csv"), THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 2 && s->n_frames == 3 && isnan(s->v[5]));
    thx_series_destroy(&s);
    tl_write_text(tl_path("r.csv"), "1,2,3\n4,5\n");
    CHECK(thx_series_read(ctx, tl_path("r.csv"), THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("r.csv:2:", "row 2 has 2 values, row 1 has 3"));
    tl_write_text(tl_path("e.csv"), "1,,3\n");
    CHECK(thx_series_read(ctx, tl_path("e.csv"), THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("e.csv:1:", "two commas"));
    tl_write_text(tl_path("w.csv"), "1,2\n3,x\n");
    CHECK(thx_series_read(ctx, tl_path("w.csv"), THX_SERIES_AUTO, &s) == THX_EINPUT && msg_has("w.csv:2:", "'x' is not a number"));
    /* a header of times (pandas' index column) */
    tl_write_text(tl_path("h.csv"), "lead,0,2.5,5\nV1,1,2,3\nV2,4,5,6\n");
    CHECK_OK(ctx, thx_series_read(ctx, tl_path("h.csv"), THX_SERIES_AUTO, &s));
    if (s) CHECK(s->n_rows == 2 && s->n_frames == 3 && s->time[1] == 2.5 && s->v[5] == 6);
    thx_series_destroy(&s);
    CHECK(!s);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_series_map3d")) return 1;
    snprintf(data, sizeof data, "%s", __FILE__);
    char *slash = strrchr(data, '/');
    if (slash) *slash = '\0';
    else snprintf(data, sizeof data, ".");
    strncat(data, "/../../shared/data/map3d", sizeof data - strlen(data) - 1);
    CHECK(tl_exists(dpath("data/torso/dipole2.tsdf")));
    test_geom_real();
    test_geom_bad();
    test_tsdf_hand();
    test_pick();
    test_tsdf_real();
    test_pot_sets();
    test_ts_struct();
    test_matrix();
    int rc = tl_scratch_finish("test_series_map3d");
    thx_ctx_destroy(&ctx);
    return rc;
}
