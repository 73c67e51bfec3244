/*
 * Tests of model directories, .pts/.fac reading and writing, and surface export
 * (src/io/model/model.c, src/io/export/export.c).
 *
 * A model.json written by thx_model_write looks like this (the schema the
 * reader checks):
 *   {
 *     "format": "thorax-model", "version": 1, "units": "mm",
 *     "surfaces": [
 *       { "name": "tetra", "role": "heart", "pts": "tetra.pts", "fac": "tetra.fac",
 *         "n_nodes": 4, "n_tris": 4, "interior": [0.25, 0.25, 0.25] }, ...
 *     ],
 *     "provenance": { "thorax": "0.1.0", "command": "..." }
 *   }
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "testlib.h"
#include "thorax/core/fileio.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

static thx_surface *make_surface(const char *name, thx_role role, size_t n, const double *xyz, size_t t,
                                 const int32_t *tri)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, role, &s) != THX_OK) exit(1);
    s->n_nodes = n;
    s->xyz = malloc(3 * n * sizeof *s->xyz);
    memcpy(s->xyz, xyz, 3 * n * sizeof *s->xyz);
    s->n_tris = t;
    s->tri = malloc(3 * t * sizeof *s->tri);
    memcpy(s->tri, tri, 3 * t * sizeof *s->tri);
    return s;
}

/* A tetrahedron (outward CCW) with coordinates that need all six decimals. */
static const double tet_xyz[] = {0.1234567, -0.0000001, 0, 10.000001, 0, 0, 0, 10, 0, 0, 0, -123.4567891};
static const int32_t tet_tri[] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
/* An octahedron of radius 5 about (1, 2, 3). */
static const double oct_xyz[] = {6, 2, 3, -4, 2, 3, 1, 7, 3, 1, -3, 3, 1, 2, 8, 1, 2, -2};
static const int32_t oct_tri[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static thx_model *make_model(void)
{
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &m));
    thx_surface *a = make_surface("tetra", THX_ROLE_HEART, 4, tet_xyz, 4, tet_tri);
    thx_surface *b = make_surface("octa", THX_ROLE_OUTER, 6, oct_xyz, 8, oct_tri);
    CHECK_OK(ctx, thx_model_add_surface(ctx, m, &a));
    CHECK(a == NULL);
    CHECK_OK(ctx, thx_model_add_surface(ctx, m, &b));
    m->has_interior[1] = 1;
    m->interior[1] = thx_v3(1, 2, 3.5);
    m->provenance_json = strdup("{\"thorax\":\"0.1.0\",\"command\":\"test_model\",\"options\":{\"n\":3}}");
    return m;
}

/* ------------------------------------------------------------- tests */

/* The .pts writer formats the millionths itself (ptsfac.c, format_coord): its text must be the bytes of
   "%.6f" (a value that rounds to zero as "0.000000"; "%.17g" from 1e15 on), for values on both sides of
   every half-millionth, negative ones, ones that round to zero, large ones and random ones; the .fac's
   the bytes of "%ld %ld %ld". 200,000 values. */
static void test_coord_text(void)
{
    enum { N = 66667 };
    double *xyz = malloc(3 * (size_t)N * sizeof *xyz);
    int32_t tri[3] = {0, 1, 2};
    uint64_t r = 88172645463325252ull;
    for (size_t k = 0; k < 3 * (size_t)N; k++) {
        r ^= r << 13, r ^= r >> 7, r ^= r << 17;
        double u = (double)(r >> 11) / 9007199254740992.0; /* [0, 1) */
        long long m = (long long)(r % 2000000001ull) - 1000000000ll;
        switch (k % 6) {
        case 0: xyz[k] = (u - 0.5) * 600; break;                                  /* a body's millimetres */
        case 1: xyz[k] = (m + 0.5) * 1e-6 + ((r >> 3) % 3 - 1) * 1e-12; break;    /* at a half-millionth */
        case 2: xyz[k] = (u - 0.5) * 2e-6; break;                                 /* rounds to zero, or -0.000001 */
        case 3: xyz[k] = (u - 0.5) * 4e6 * (1 + (r >> 7) % 1000); break;         /* beyond 1e6, up to 2e9 */
        case 4: xyz[k] = (m + 0.5) * 1e-6 * 997; break;                           /* halves at larger values */
        default: xyz[k] = ((r >> 5) % 2 ? 1 : -1) * (1e15 + u * 1e16); break;   /* "%.17g" */
        }
    }
    thx_surface *s = make_surface("coords", THX_ROLE_OTHER, N, xyz, 1, tri);
    char pts[1200], fac[1200];
    snprintf(pts, sizeof pts, "%s/coords.pts", tl_scratch);
    snprintf(fac, sizeof fac, "%s/coords.fac", tl_scratch);
    CHECK_OK(ctx, thx_surface_write_ptsfac(ctx, s, pts, fac));
    FILE *f = fopen(pts, "r");
    CHECK(f != NULL);
    size_t bad = 0, lines = 0;
    char line[400], want[400];
    for (size_t i = 0; f && i < (size_t)N && fgets(line, sizeof line, f); i++, lines++) {
        int n = 0;
        for (int k = 0; k < 3; k++) {
            char b[64];
            double v = xyz[3 * i + (size_t)k];
            snprintf(b, sizeof b, fabs(v) >= 1e15 ? "%.17g" : "%.6f", v);
            n += snprintf(want + n, sizeof want - (size_t)n, "%s%c", strcmp(b, "-0.000000") ? b : "0.000000", k < 2 ? ' ' : '\n');
        }
        if (strcmp(line, want) != 0 && bad++ < 3) printf("line %zu: \"%s\" where \"%%.6f\" gives \"%s\"\n", i + 1, line, want);
    }
    if (f) fclose(f);
    printf("coordinate text: %zu lines, %zu unlike \"%%.6f\"\n", lines, bad);
    CHECK(lines == (size_t)N && bad == 0);
    f = fopen(fac, "r");
    CHECK(f != NULL && fgets(line, sizeof line, f) && strcmp(line, "1 2 3\n") == 0);
    if (f) fclose(f);
    thx_surface_destroy(&s);
    free(xyz);
}

static void test_round_trip(void)
{
    thx_model *m = make_model();
    CHECK(m->n_surfaces == 2);

    /* A second surface of the same name is refused and freed. */
    thx_surface *dup = make_surface("octa", THX_ROLE_LUNG, 6, oct_xyz, 8, oct_tri);
    CHECK(thx_model_add_surface(ctx, m, &dup) == THX_EINPUT);
    CHECK(dup == NULL);
    CHECK(m->n_surfaces == 2);

    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("rt")));
    CHECK(tl_exists(tl_path("rt/model.json")) && tl_exists(tl_path("rt/tetra.pts")) && tl_exists(tl_path("rt/octa.fac")));
    CHECK(!tl_leftover_tmp("rt"));

    /* The .fac on disk is 1-based; the .pts uses %.6f with no "-0.000000". */
    char *fac = tl_slurp(ctx, tl_path("rt/tetra.fac"), NULL);
    CHECK(fac && strcmp(fac, "1 3 2\n1 2 4\n2 3 4\n3 1 4\n") == 0);
    free(fac);
    char *pts = tl_slurp(ctx, tl_path("rt/tetra.pts"), NULL);
    CHECK(pts && strncmp(pts, "0.123457 0.000000 0.000000\n10.000001 0.000000 0.000000\n", 55) == 0);
    CHECK(pts && strstr(pts, "-123.456789\n"));
    free(pts);

    thx_model *r = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("rt"), &r));
    if (r) {
        CHECK(r->n_surfaces == 2);
        for (size_t i = 0; i < 2 && i < r->n_surfaces; i++) {
            const thx_surface *a = m->surf[i], *b = r->surf[i];
            CHECK(strcmp(a->name, b->name) == 0);
            CHECK(a->role == b->role);
            CHECK(a->n_nodes == b->n_nodes && a->n_tris == b->n_tris);
            for (size_t k = 0; k < 3 * a->n_nodes && a->n_nodes == b->n_nodes; k++)
                CHECK_NEAR(b->xyz[k], a->xyz[k], 5.0000001e-7); /* "%.6f" rounds to half a unit of 1e-6 */
            CHECK(a->n_tris == b->n_tris && memcmp(a->tri, b->tri, 3 * a->n_tris * sizeof *a->tri) == 0);
        }
        CHECK(r->has_interior[0] == 0 && r->has_interior[1] == 1);
        CHECK_NEAR(r->interior[1].z, 3.5, 0);
        cJSON *p = r->provenance_json ? cJSON_Parse(r->provenance_json) : NULL;
        const cJSON *opt = cJSON_GetObjectItemCaseSensitive(p, "options");
        CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(p, "command")) &&
              strcmp(cJSON_GetObjectItemCaseSensitive(p, "command")->valuestring, "test_model") == 0);
        CHECK(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(opt, "n")));
        cJSON_Delete(p);

        /* Writing what was read gives byte-identical files (determinism, and
         * the precision is a fixed point of the round trip). */
        CHECK_OK(ctx, thx_model_write(ctx, r, tl_path("rt2")));
        const char *files[] = {"model.json", "tetra.pts", "tetra.fac", "octa.pts", "octa.fac"};
        for (size_t k = 0; k < 5; k++) {
            char n1[64], n2[64];
            snprintf(n1, sizeof n1, "rt/%s", files[k]);
            snprintf(n2, sizeof n2, "rt2/%s", files[k]);
            size_t l1 = 0, l2 = 0;
            char *t1 = tl_slurp(ctx, tl_path(n1), &l1), *t2 = tl_slurp(ctx, tl_path(n2), &l2);
            CHECK(t1 && t2 && l1 == l2 && memcmp(t1, t2, l1) == 0);
            free(t1);
            free(t2);
        }
    }

    /* The manifest has the documented schema. */
    char *json = tl_slurp(ctx, tl_path("rt/model.json"), NULL);
    cJSON *root = json ? cJSON_Parse(json) : NULL;
    CHECK(root != NULL);
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
    CHECK(cJSON_IsString(fmt) && strcmp(fmt->valuestring, "thorax-model") == 0);
    CHECK(cJSON_GetObjectItemCaseSensitive(root, "version") &&
          cJSON_GetObjectItemCaseSensitive(root, "version")->valuedouble == 1);
    const cJSON *s0 = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(root, "surfaces"), 1);
    CHECK(cJSON_GetObjectItemCaseSensitive(s0, "n_tris") && cJSON_GetObjectItemCaseSensitive(s0, "n_tris")->valuedouble == 8);
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(s0, "interior")) == 3);
    cJSON_Delete(root);
    free(json);

    /* Writing over an existing model replaces it whole. */
    m->surf[0]->xyz[0] = 42;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("rt")));
    thx_model_destroy(&r);
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("rt"), &r));
    CHECK(r && r->surf[0]->xyz[0] == 42);
    CHECK(!tl_leftover_tmp("rt"));
    thx_model_destroy(&r);
    CHECK(r == NULL);
    thx_model_destroy(&m);
    thx_model_destroy(&m); /* NULL accepted */
}

static void test_failed_write(void)
{
    thx_model *m = make_model();
    /* Parent directory missing: error naming the path, nothing created. */
    CHECK(thx_model_write(ctx, m, tl_path("no/such/dir")) == THX_EIO);
    CHECK(tl_msg_has(ctx, "no/such/dir"));
    CHECK(!tl_exists(tl_path("no")));

    /* An out-of-range triangle index is rejected before anything is written. */
    m->surf[1]->tri[5] = 6;
    CHECK(thx_model_write(ctx, m, tl_path("bad")) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "octa") && tl_msg_has(ctx, "triangle 2"));
    CHECK(!tl_exists(tl_path("bad")));
    CHECK(!tl_leftover_tmp("bad"));

    /* ... and an existing model of that name is left as it was. */
    m->surf[1]->tri[5] = 4;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("keep")));
    m->surf[1]->tri[5] = -1;
    CHECK(thx_model_write(ctx, m, tl_path("keep")) == THX_EINPUT);
    thx_model *r = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("keep"), &r));
    CHECK(r && r->n_surfaces == 2 && r->surf[1]->tri[5] == 4);
    thx_model_destroy(&r);
    CHECK(!tl_leftover_tmp("keep"));
    m->surf[1]->tri[5] = 4;

    /* Non-finite coordinates and unsafe names are refused. */
    m->surf[0]->xyz[4] = NAN;
    CHECK(thx_model_write(ctx, m, tl_path("nan")) == THX_EINPUT && tl_msg_has(ctx, "tetra") && tl_msg_has(ctx, "node 2"));
    CHECK(!tl_exists(tl_path("nan")));
    m->surf[0]->xyz[4] = 0;
    snprintf(m->surf[0]->name, sizeof m->surf[0]->name, "../evil");
    CHECK(thx_model_write(ctx, m, tl_path("evil")) == THX_EINPUT && tl_msg_has(ctx, "../evil"));
    CHECK(!tl_exists(tl_path("evil")));
    snprintf(m->surf[0]->name, sizeof m->surf[0]->name, "octa"); /* duplicate after mutation */
    CHECK(thx_model_write(ctx, m, tl_path("dup")) == THX_EINPUT && tl_msg_has(ctx, "octa"));
    snprintf(m->surf[0]->name, sizeof m->surf[0]->name, "tetra");
    free(m->provenance_json);
    m->provenance_json = strdup("[1, 2");
    CHECK(thx_model_write(ctx, m, tl_path("prov")) == THX_EINPUT && tl_msg_has(ctx, "provenance"));
    CHECK(!tl_exists(tl_path("prov")));
    thx_model_destroy(&m);
}

static void test_base_detection(void)
{
    const char *pts = "\n  0 0 0\n1.5\t0   0 \r\n\n0 1 0\n0 0 1\n\n";
    tl_write_text(tl_path("t.pts"), pts);
    tl_write_text(tl_path("t0.fac"), "0 2 1\n0 1 3\n1 2 3\n2 0 3\n");
    tl_write_text(tl_path("t1.fac"), "  1 3 2\n\n1 2 4\n2 3 4\r\n3 1 4\n");
    thx_surface *s0 = NULL, *s1 = NULL;
    int base = -7;
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("t0.fac"), "t", THX_ROLE_OTHER, &s0, &base));
    CHECK(base == 0);
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("t1.fac"), "t", THX_ROLE_OTHER, &s1, &base));
    CHECK(base == 1);
    CHECK(s0 && s1 && s0->n_nodes == 4 && s0->n_tris == 4 && s1->n_tris == 4);
    if (s0 && s1) {
        CHECK(memcmp(s0->tri, tet_tri, sizeof tet_tri) == 0);
        CHECK(memcmp(s1->tri, tet_tri, sizeof tet_tri) == 0);
        CHECK(s0->xyz[3] == 1.5 && s0->xyz[11] == 1);
        CHECK(strcmp(s0->name, "t") == 0 && s0->role == THX_ROLE_OTHER);
    }
    thx_surface_destroy(&s0);
    thx_surface_destroy(&s1);
    CHECK(s0 == NULL);

    /* 1-based with node 1 unused is still unambiguous (max == n). */
    tl_write_text(tl_path("t1b.fac"), "2 3 4\n");
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("t1b.fac"), "t", THX_ROLE_OTHER, &s0, &base));
    CHECK(base == 1 && s0 && s0->tri[0] == 1);
    thx_surface_destroy(&s0);

    /* min 1, max < n: could be either; refused, naming file and line. */
    tl_write_text(tl_path("amb.fac"), "1 2 3\n3 2 1\n");
    CHECK(thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("amb.fac"), "t", THX_ROLE_OTHER, &s0, &base) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "amb.fac:1:") && tl_msg_has(ctx, "0- or 1-based"));
    CHECK(s0 == NULL);

    /* write_ptsfac then read: 1-based on disk, same triangles. */
    thx_surface *w = make_surface("w", THX_ROLE_LUNG, 6, oct_xyz, 8, oct_tri);
    CHECK_OK(ctx, thx_surface_write_ptsfac(ctx, w, tl_path("w.pts"), tl_path("w.fac")));
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, tl_path("w.pts"), tl_path("w.fac"), "w", THX_ROLE_LUNG, &s0, &base));
    CHECK(base == 1 && s0 && s0->n_tris == 8 && memcmp(s0->tri, oct_tri, sizeof oct_tri) == 0);
    thx_surface_destroy(&s0);
    thx_surface_destroy(&w);
}

static void test_bad_files(void)
{
    thx_surface *s = NULL;
    tl_write_text(tl_path("t.pts"), "0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
    struct { const char *fac; const char *want; } facs[] = {
        {"1 2 3\n1 2 5\n", "bad.fac:2:"},          /* 1-based, 5 > 4 nodes */
        {"0 1 2\n0 1 4\n", "bad.fac:2:"},          /* 0-based, 4 > 3 */
        {"0 1 2\n-1 1 2\n", "bad.fac:2:"},         /* negative */
        {"1 2 3\n1 2 x\n", "bad.fac:2:"},          /* non-numeric */
        {"1 2 3\n1 2 3.5\n", "bad.fac:2:"},        /* not an integer */
        {"1 2 3\n\n1 2\n", "bad.fac:3:"},          /* two columns */
        {"1 2 3 4\n", "bad.fac:1:"},               /* four columns */
        {"1 2 99999999999999999999\n", "bad.fac:1:"},
    };
    for (size_t i = 0; i < sizeof facs / sizeof facs[0]; i++) {
        tl_write_text(tl_path("bad.fac"), facs[i].fac);
        thx_status st = thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("bad.fac"), "t", THX_ROLE_OTHER, &s, NULL);
        CHECK(st == THX_EINPUT);
        CHECK(tl_msg_has(ctx, facs[i].want) && tl_msg_has(ctx, "surface \"t\""));
        CHECK(s == NULL);
    }
    struct { const char *pts; const char *want; } ptss[] = {
        {"0 0 0\n1 0\n", "bad.pts:2:"},
        {"0 0 0\n\n1 0 0 0\n", "bad.pts:3:"},
        {"0 0 0\n1 y 0\n", "bad.pts:2:"},
        {"0 0 0\n1 nan 0\n", "bad.pts:2:"},
        {"0 0 0\n1 2,5 0\n", "bad.pts:2:"},
        {"\n\n", "bad.pts: surface \"t\": no nodes"},
    };
    tl_write_text(tl_path("ok.fac"), "1 2 3\n");
    for (size_t i = 0; i < sizeof ptss / sizeof ptss[0]; i++) {
        tl_write_text(tl_path("bad.pts"), ptss[i].pts);
        CHECK(thx_surface_read_ptsfac(ctx, tl_path("bad.pts"), tl_path("ok.fac"), "t", THX_ROLE_OTHER, &s, NULL) == THX_EINPUT);
        CHECK(tl_msg_has(ctx, ptss[i].want));
        CHECK(s == NULL);
    }
    /* Missing files are named. */
    CHECK(thx_surface_read_ptsfac(ctx, tl_path("missing.pts"), tl_path("ok.fac"), "t", THX_ROLE_OTHER, &s, NULL) == THX_EIO);
    CHECK(tl_msg_has(ctx, "missing.pts"));
    CHECK(thx_surface_read_ptsfac(ctx, tl_path("t.pts"), tl_path("missing.fac"), "t", THX_ROLE_OTHER, &s, NULL) == THX_EIO);
    CHECK(tl_msg_has(ctx, "missing.fac"));
    CHECK(s == NULL);
}

/* Writes a model directory with the given manifest around a valid tetra.pts/.fac. */
static void manifest_case(const char *json)
{
    mkdir(tl_path("man"), 0755);
    tl_write_text(tl_path("man/tetra.pts"), "0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
    tl_write_text(tl_path("man/tetra.fac"), "1 3 2\n1 2 4\n2 3 4\n3 1 4\n");
    tl_write_text(tl_path("man/model.json"), json);
}

static void test_bad_manifest(void)
{
    thx_model *m = NULL;
    const char *head = "{\"format\":\"thorax-model\",\"version\":1,\"units\":\"mm\",\"surfaces\":[";
    struct { const char *tail; const char *want; } cases[] = {
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         NULL},
        {"{\"name\":\"tetra\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         "surface 1 (\"tetra\"): \"role\""},
        {"{\"name\":\"tetra\",\"role\":\"liver\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         "\"liver\""},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":5,\"n_tris\":4}]}",
         "surface \"tetra\": manifest says 5 nodes"},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":3}]}",
         "manifest says 3 triangles"},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"gone.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         "gone.pts"},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"../t.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         "\"pts\" and \"fac\""},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":-1}]}",
         "\"n_tris\""},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4,"
         "\"interior\":[1,2]}]}",
         "\"interior\""},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4},"
         "{\"name\":\"tetra\",\"role\":\"lung\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}",
         "surface 2 (\"tetra\"): a surface of that name appears twice"},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]",
         "model.json:1: not valid JSON"},
        {"{\"name\":\"tetra\",\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]} x",
         "not valid JSON"},
        {"7]}", "surface 1: not a JSON object"},
    };
    char json[2048];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(json, sizeof json, "%s%s", head, cases[i].tail);
        manifest_case(json);
        thx_status st = thx_model_read(ctx, tl_path("man"), &m);
        if (!cases[i].want) {
            CHECK_OK(ctx, st);
            CHECK(m && m->n_surfaces == 1 && m->surf[0]->role == THX_ROLE_HEART && m->provenance_json == NULL);
        } else {
            CHECK(st == THX_EINPUT || st == THX_EIO);
            CHECK(tl_msg_has(ctx, cases[i].want));
            CHECK(m == NULL);
        }
        thx_model_destroy(&m);
    }
    /* Errors naming the file: wrong format name, version, units, line of a syntax error. */
    manifest_case("{\"format\":\"other\",\"version\":1,\"units\":\"mm\",\"surfaces\":[]}");
    CHECK(thx_model_read(ctx, tl_path("man"), &m) == THX_EINPUT && tl_msg_has(ctx, "man/model.json") && tl_msg_has(ctx, "\"format\""));
    manifest_case("{\"format\":\"thorax-model\",\"version\":2,\"units\":\"mm\",\"surfaces\":[]}");
    CHECK(thx_model_read(ctx, tl_path("man"), &m) == THX_EINPUT && tl_msg_has(ctx, "version 2"));
    manifest_case("{\"format\":\"thorax-model\",\"version\":1,\"units\":\"m\",\"surfaces\":[]}");
    CHECK(thx_model_read(ctx, tl_path("man"), &m) == THX_EINPUT && tl_msg_has(ctx, "\"units\""));
    manifest_case("{\n\"format\": \"thorax-model\",\n\"version\": 1,\n\"units\": \"mm\"\n\"surfaces\": []}\n");
    CHECK(thx_model_read(ctx, tl_path("man"), &m) == THX_EINPUT && tl_msg_has(ctx, "man/model.json:5:"));
    /* A 0-based .fac inside a model directory is an error (model files are 1-based). */
    manifest_case("{\"format\":\"thorax-model\",\"version\":1,\"units\":\"mm\",\"surfaces\":[{\"name\":\"tetra\",\"role\":"
                  "\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}");
    tl_write_text(tl_path("man/tetra.fac"), "0 2 1\n0 1 3\n1 2 3\n2 0 3\n");
    CHECK(thx_model_read(ctx, tl_path("man"), &m) == THX_EINPUT && tl_msg_has(ctx, "tetra.fac:1:") && tl_msg_has(ctx, "1-based"));
    /* No model.json at all. */
    CHECK(thx_model_read(ctx, tl_path("nowhere"), &m) == THX_EIO && tl_msg_has(ctx, "nowhere/model.json"));
    CHECK(m == NULL);
    /* Unknown keys are ignored (room for regions, conductivities ...). */
    manifest_case("{\"format\":\"thorax-model\",\"version\":1,\"units\":\"mm\",\"regions\":[1],\"surfaces\":[]}");
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("man"), &m));
    CHECK(m && m->n_surfaces == 0);
    thx_model_destroy(&m);
}

static void test_real_data(void)
{
    /* __FILE__ is tests/test_model.c under the source tree; the data sit beside it. */
    const char *pts = tl_src_path(__FILE__, "../../shared/data/map3d/geom/tank/tank_full_771.pts");
    const char *fac = tl_src_path(__FILE__, "../../shared/data/map3d/geom/tank/tank_full_771.fac");
    /* The data folder is part of the project's setup: its absence is a failure, not a skip. */
    CHECK(tl_exists(pts) && tl_exists(fac));
    if (!tl_exists(pts)) {
        fprintf(stderr, "test_model: %s missing\n", pts);
        return;
    }
    thx_surface *s = NULL;
    int base = -1;
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, pts, fac, "tank", THX_ROLE_OUTER, &s, &base));
    CHECK(base == 1);
    CHECK(s && s->n_nodes == 771 && s->n_tris == 1538);
    if (s) {
        CHECK_NEAR(s->xyz[0], 88.80, 0);
        CHECK_NEAR(s->xyz[1], 9.30, 0);
        CHECK(s->tri[0] == 23 && s->tri[1] == 32 && s->tri[2] == 24); /* "24 33 25" */
        /* A closed surface: 2 n - 4 triangles (Euler, genus 0). */
        CHECK(s->n_tris == 2 * s->n_nodes - 4);

        /* Through a model directory and back: same counts, coordinates exact
         * (the file has two decimals, below the written precision). */
        thx_model *m = NULL;
        CHECK_OK(ctx, thx_model_create(ctx, &m));
        double x0 = s->xyz[3 * 770 + 2];
        CHECK_OK(ctx, thx_model_add_surface(ctx, m, &s));
        CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("tank")));
        thx_model *r = NULL;
        CHECK_OK(ctx, thx_model_read(ctx, tl_path("tank"), &r));
        CHECK(r && r->n_surfaces == 1 && r->surf[0]->n_nodes == 771 && r->surf[0]->n_tris == 1538);
        CHECK(r && r->surf[0]->xyz[3 * 770 + 2] == x0);
        CHECK(r && memcmp(r->surf[0]->tri, m->surf[0]->tri, 3 * 1538 * sizeof(int32_t)) == 0);
        thx_model_destroy(&r);
        thx_model_destroy(&m);
    }
    thx_surface_destroy(&s);

    pts = tl_src_path(__FILE__, "../../shared/data/map3d/geom/torso/daltorso.pts");
    fac = tl_src_path(__FILE__, "../../shared/data/map3d/geom/torso/daltorso.fac");
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, pts, fac, "torso", THX_ROLE_OUTER, &s, &base));
    CHECK(base == 1 && s && s->n_nodes == 352 && s->n_tris == 700);
    thx_surface_destroy(&s);
}

static float get_f32(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static void test_export(void)
{
    thx_export_format f;
    CHECK(thx_export_format_parse("vtk", &f) == 0 && f == THX_EXPORT_VTK);
    CHECK(thx_export_format_parse("vtp", &f) == 0 && f == THX_EXPORT_VTP);
    CHECK(thx_export_format_parse("obj", &f) == 0 && f == THX_EXPORT_OBJ);
    CHECK(thx_export_format_parse("stl", &f) == 0 && f == THX_EXPORT_STL);
    CHECK(thx_export_format_parse("ply", &f) == 0 && f == THX_EXPORT_PLY);
    CHECK(thx_export_format_parse("VTK", &f) != 0 && thx_export_format_parse("", &f) != 0);

    thx_surface *s = make_surface("octa", THX_ROLE_OUTER, 6, oct_xyz, 8, oct_tri);
    CHECK_OK(ctx, thx_surface_export(ctx, s, THX_EXPORT_VTK, tl_path("o.vtk")));
    CHECK_OK(ctx, thx_surface_export(ctx, s, THX_EXPORT_VTP, tl_path("o.vtp")));
    CHECK_OK(ctx, thx_surface_export(ctx, s, THX_EXPORT_OBJ, tl_path("o.obj")));
    CHECK_OK(ctx, thx_surface_export(ctx, s, THX_EXPORT_STL, tl_path("o.stl")));
    CHECK_OK(ctx, thx_surface_export(ctx, s, THX_EXPORT_PLY, tl_path("o.ply")));

    char *t = tl_slurp(ctx, tl_path("o.vtk"), NULL);
    CHECK(t && strstr(t, "POINTS 6 double\n") && strstr(t, "POLYGONS 8 32\n3 0 2 4\n"));
    free(t);
    t = tl_slurp(ctx, tl_path("o.obj"), NULL);
    CHECK(t && strstr(t, "\nv 6.000000 2.000000 3.000000\n") && strstr(t, "\nf 1 3 5\n"));
    free(t);
    t = tl_slurp(ctx, tl_path("o.ply"), NULL);
    CHECK(t && strstr(t, "element vertex 6\n") && strstr(t, "element face 8\n") && strstr(t, "end_header\n"));
    free(t);
    t = tl_slurp(ctx, tl_path("o.vtp"), NULL);
    CHECK(t && strstr(t, "NumberOfPoints=\"6\"") && strstr(t, "NumberOfPolys=\"8\"") && strstr(t, "</VTKFile>\n"));
    free(t);

    /* Binary STL: 84 + 50 t bytes, unit outward normals (octahedron centre (1,2,3)). */
    size_t len = 0;
    unsigned char *b = (unsigned char *)tl_slurp(ctx, tl_path("o.stl"), &len);
    CHECK(b && len == 84 + 50 * 8);
    if (b && len == 84 + 50 * 8) {
        CHECK(strncmp((char *)b, "solid", 5) != 0);
        CHECK(b[80] == 8 && b[81] == 0 && b[82] == 0 && b[83] == 0);
        for (int k = 0; k < 8; k++) {
            const unsigned char *r = b + 84 + 50 * k;
            double n[3] = {get_f32(r), get_f32(r + 4), get_f32(r + 8)};
            double c[3] = {0, 0, 0};
            for (int v = 0; v < 3; v++)
                for (int d = 0; d < 3; d++) c[d] += get_f32(r + 12 + 12 * v + 4 * d) / 3.0;
            double out = n[0] * (c[0] - 1) + n[1] * (c[1] - 2) + n[2] * (c[2] - 3);
            CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1, 1e-6);
            CHECK(out > 0);
            CHECK_NEAR(fabs(n[0]), 1 / sqrt(3.0), 1e-6);
        }
    }
    free(b);

    /* A bad surface is refused and leaves no file. */
    s->tri[3] = 17;
    CHECK(thx_surface_export(ctx, s, THX_EXPORT_PLY, tl_path("bad.ply")) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "bad.ply") && tl_msg_has(ctx, "octa"));
    CHECK(!tl_exists(tl_path("bad.ply")));
    /* An unwritable destination is an i/o error naming it. */
    s->tri[3] = 1;
    CHECK(thx_surface_export(ctx, s, THX_EXPORT_OBJ, tl_path("no/such.obj")) == THX_EIO && tl_msg_has(ctx, "no/such.obj"));
    thx_surface_destroy(&s);
}

/* The anatomical frame in model.json: written and read back; absent (an old model) = unknown;
 * refused when it is not a frame; and the strict reading of the manifest (keys, NUL). */
static void test_frame(void)
{
    thx_model *m = NULL, *r = NULL;
    thx_surface *s = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &m));
    CHECK_OK(ctx, thx_surface_create(ctx, "tetra", THX_ROLE_HEART, &s));
    static const double xyz[12] = {0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10};
    static const int32_t tri[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
    s->xyz = malloc(sizeof xyz);
    s->tri = malloc(sizeof tri);
    memcpy(s->xyz, xyz, sizeof xyz);
    memcpy(s->tri, tri, sizeof tri);
    s->n_nodes = s->n_tris = 4;
    CHECK_OK(ctx, thx_model_add_surface(ctx, m, &s));
    CHECK(m->frame.set == 0);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("fr")));
    char *t = tl_slurp(ctx, tl_path("fr/model.json"), NULL);
    CHECK(t && !strstr(t, "\"frame\""));
    free(t);
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("fr"), &r));
    CHECK(r && r->frame.set == 0);
    thx_model_destroy(&r);
    CHECK_OK(ctx, thx_frame_from_names(ctx, "-y", "-z", "t", &m->frame));
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("fr")));
    t = tl_slurp(ctx, tl_path("fr/model.json"), NULL);
    CHECK(t && strstr(t, "\"superior\":\t\"-y\"") && strstr(t, "\"anterior\":\t\"-z\"") && strstr(t, "\"left\":\t\"+x\""));
    free(t);
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("fr"), &r));
    CHECK(r && r->frame.set && r->frame.up.axis == 1 && r->frame.up.sign == -1 && r->frame.front.axis == 2 &&
          r->frame.front.sign == -1);
    thx_model_destroy(&r);
    m->frame.front = m->frame.up; /* not a frame */
    CHECK(thx_model_write(ctx, m, tl_path("fr2")) == THX_EINPUT && !tl_exists(tl_path("fr2")));
    thx_model_destroy(&m);

    const char *head = "{\"format\":\"thorax-model\",\"version\":1,\"units\":\"mm\",\"surfaces\":[{\"name\":\"tetra\","
                       "\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]";
    struct { const char *tail, *want; } cases[] = {
        {",\"frame\":{\"superior\":\"+z\",\"anterior\":\"+y\"}}", NULL},
        {",\"frame\":null}", NULL},
        {",\"frame\":{\"superior\":\"+z\",\"anterior\":\"+w\"}}", "\"frame\".\"anterior\" is not an axis"},
        {",\"frame\":{\"superior\":\"+z\"}}", "\"frame\".\"anterior\" missing"},
        {",\"frame\":{\"superior\":\"+z\",\"anterior\":\"-z\"}}", "two different axes"},
        {",\"frame\":{\"superior\":\"+z\",\"anterior\":\"+y\",\"left\":\"+x\"}}", "\"frame\".\"left\" is +x"},
        {",\"frame\":{\"superior\":\"+z\",\"anterior\":\"+y\",\"up\":\"+z\"}}", "\"frame\": unknown key \"up\""},
        {",\"frame\":\"+z +y\"}", "\"frame\" must be an object"},
        {",\"frame\":{\"superior\":\"+z\",\"superior\":\"-z\",\"anterior\":\"+y\"}}", "key \"superior\" appears twice"},
        {",\"colour\":\"red\"}", "unknown key \"colour\""},
        {",\"units\":\"mm\"}", "key \"units\" appears twice"},
        {",\"volume\":{\"pts\":\"v.pts\",\"tets\":\"v.tet\"}}", "\"volume\": unknown key \"tets\""},
        {",\"regions\":[{\"id\":1,\"nme\":\"x\"}]}", "region 1: unknown key \"nme\""},
    };
    char json[2048];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(json, sizeof json, "%s%s", head, cases[i].tail);
        manifest_case(json);
        thx_status st = thx_model_read(ctx, tl_path("man"), &r);
        if (!cases[i].want) {
            CHECK_OK(ctx, st);
            CHECK(r && r->frame.set == (strstr(cases[i].tail, "null") == NULL));
        } else {
            CHECK(st == THX_EINPUT && r == NULL);
            CHECK(tl_msg_has(ctx, cases[i].want) && tl_msg_has(ctx, "man/model.json"));
        }
        thx_model_destroy(&r);
    }
    /* a NUL byte: cJSON would stop there and accept what comes before */
    snprintf(json, sizeof json, "%s}", head);
    size_t n = strlen(json);
    json[n] = '\0';
    memcpy(json + n + 1, "garbage", 8);
    tl_write_bytes(tl_path("man/model.json"), json, n + 8);
    CHECK(thx_model_read(ctx, tl_path("man"), &r) == THX_EINPUT && r == NULL && tl_msg_has(ctx, "NUL byte at byte offset"));
    /* a surface named model.json (the writer refuses it too) */
    manifest_case("{\"format\":\"thorax-model\",\"version\":1,\"units\":\"mm\",\"surfaces\":[{\"name\":\"model.json\","
                  "\"role\":\"heart\",\"pts\":\"tetra.pts\",\"fac\":\"tetra.fac\",\"n_nodes\":4,\"n_tris\":4}]}");
    CHECK(thx_model_read(ctx, tl_path("man"), &r) == THX_EINPUT && tl_msg_has(ctx, "surface 1: \"name\""));
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_model")) return 1;
    test_round_trip();
    test_coord_text();
    test_failed_write();
    test_base_detection();
    test_bad_files();
    test_bad_manifest();
    test_frame();
    test_real_data();
    test_export();
    int rc = tl_scratch_finish("test_model");
    thx_ctx_destroy(&ctx);
    return rc;
}
