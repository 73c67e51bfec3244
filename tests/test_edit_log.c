/*
 * The edit log (thorax/edit/edit.h; docs/formats.md "Edit logs"): every edit kind and the header
 * written and read back exactly (numbers to the bit, a path with spaces, the recipe); comments,
 * blank lines and CRLF; the strict reader's refusals, each with file:line (a table); and the log
 * in a model directory (edits.txt named with its SHA-256 in the provenance: written, read back,
 * refused when changed or missing, dropped from the record when the model has none, a directory
 * holding it replaced as thorax's own).
 */
#include <cjson/cJSON.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/sha256.h"
#include "thorax/edit/edit.h"
#include "thorax/io/model_dir.h"

static const char *H64 = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";

static thx_edit_recipe odd_recipe(void)
{
    thx_edit_recipe r;
    thx_surfaces_opts_default(&r.surfaces);
    r.surfaces.spacing = 7.5;
    r.surfaces.smoothing = 0.1;
    r.surfaces.start.x = -3.25;
    r.surfaces.start.y = 1.0 / 3;
    r.surfaces.cap_method = THX_CAP_GRID;
    r.surfaces.cap_grid = 2.5e-3;
    r.surfaces.lace.fan_limit = 4;
    r.surfaces.lace.concave_tol = 0.3;
    thx_repair_opts_default(&r.repair, 7.5);
    r.repair.strict = 1;
    r.repair.untangle_tol = 123456.789;
    return r;
}

static int same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static void test_round_trip(thx_ctx *ctx)
{
    thx_edit e[] = {
        thx_edit_node_move("torso", 0, thx_v3(0.1, 1.0 / 3, -1e-7)),
        thx_edit_node_move("lung_l", 2147483646, thx_v3(1e20, -0.0, 123456.789)),
        thx_edit_tri_delete("heart", 41),
        thx_edit_tri_add("fat.2", 5, 0, 9),
        thx_edit_tri_flip("a-b_c", 7),
        thx_edit_layer_move("torso", thx_edit_layer_z(-120.5), 2.25, -M_PI),
        thx_edit_layer_rotate("muscle", thx_edit_layer_index(0), -7.5),
        thx_edit_layer_smooth("muscle", thx_edit_layer_z(1e-5), 4),
    };
    size_t n = sizeof e / sizeof *e;
    thx_edit_recipe r = odd_recipe();
    char *text = NULL;
    CHECK_OK(ctx, thx_edit_log_text(ctx, "my dir/c 1.txt", H64, &r, e, n, "made by test_edit_log", &text));
    if (!text) return;
    printf("%s", text);
    CHECK(strncmp(text, "thorax-edits 1\n# made by test_edit_log\ncontours sha256:", 55) == 0);
    CHECK(strstr(text, "node_move torso 1 0.1 0.3333333333333333 -1e-07\n") != NULL);
    CHECK(strstr(text, "node_move lung_l 2147483647 1e+20 -0 123456.789\n") != NULL);
    CHECK(strstr(text, "tri_add fat.2 6 1 10\n") && strstr(text, "tri_delete heart 42\n") && strstr(text, "tri_flip a-b_c 8\n"));
    CHECK(strstr(text, "layer_move torso z=-120.5 2.25 -3.141592653589793\n") != NULL);
    CHECK(strstr(text, "layer_rotate muscle layer=1 -7.5\nlayer_smooth muscle z=1e-05 4\nend\n") != NULL);
    CHECK(strstr(text, "build spacing=7.5 smoothing=0.1 start=-3.25,0.3333333333333333 cap=grid cap_grid=0.0025 ") != NULL);
    thx_edit_log *log = NULL;
    CHECK_OK(ctx, thx_edit_log_parse(ctx, "rt.edits", text, strlen(text), &log));
    if (!log) { free(text); return; }
    CHECK(log->has_contours && strcmp(log->contours_sha256, H64) == 0 && strcmp(log->contours_path, "my dir/c 1.txt") == 0);
    CHECK(log->contours_line == 3 && log->has_recipe && log->recipe_line == 4);
    CHECK(thx_edit_recipe_same(&r, &log->recipe, NULL, 0));
    CHECK(same_double(log->recipe.surfaces.start.y, 1.0 / 3) && log->recipe.repair.strict == 1 &&
          log->recipe.surfaces.lace.fan_limit == 4 && log->recipe.repair.spacing == 7.5);
    CHECK(log->n_edits == n);
    int all = log->n_edits == n;
    for (size_t i = 0; all && i < n; i++) {
        const thx_edit *a = &e[i], *b = &log->edits[i];
        all &= a->kind == b->kind && !strcmp(a->surface, b->surface) && a->node == b->node && a->tri == b->tri &&
               !memcmp(a->nodes, b->nodes, sizeof a->nodes) && a->layer.by_index == b->layer.by_index &&
               a->layer.index == b->layer.index && same_double(a->layer.z, b->layer.z) && b->line == (int)(5 + i);
        for (int k = 0; k < 3; k++) all &= same_double(a->v[k], b->v[k]);
    }
    CHECK(all);
    CHECK(strcmp(log->text + log->end_offset, "end\n") == 0);
    /* written again from what was read: the same text */
    char *again = NULL;
    CHECK_OK(ctx, thx_edit_log_text(ctx, log->contours_path, log->contours_sha256, &log->recipe, log->edits,
                                    log->n_edits, "made by test_edit_log", &again));
    CHECK(again && strcmp(again, text) == 0);
    free(again);
    thx_edit_log_destroy(&log);
    CHECK(log == NULL);
    free(text);

    /* comments, blank lines, tabs, CRLF, comments after `end` */
    const char *loose = "# a log written by hand\r\n\r\n  thorax-edits 1   # version\r\n\ttri_flip torso 3\t# flip it\r\n"
                        "\n# no header: fine\r\nlayer_move torso layer=2 +1.5 .5\r\nend # done\r\n# after\n\n";
    CHECK_OK(ctx, thx_edit_log_parse(ctx, "loose.edits", loose, strlen(loose), &log));
    if (log) {
        CHECK(!log->has_contours && !log->has_recipe && log->n_edits == 2 && log->edits[0].line == 4 &&
              log->edits[1].line == 7 && log->edits[1].layer.by_index && log->edits[1].layer.index == 1 &&
              log->edits[1].v[0] == 1.5 && log->edits[1].v[1] == 0.5);
        thx_edit_log_destroy(&log);
    }
    /* a name with a '#' cannot be written */
    CHECK(thx_edit_log_text(ctx, "c#1.txt", H64, NULL, NULL, 0, NULL, &text) == THX_EINPUT && tl_msg_has(ctx, "'#'"));
}

/* The build line of the default recipe (for the table). */
static void default_build(thx_ctx *ctx, char *out, size_t cap)
{
    thx_edit_recipe r;
    thx_surfaces_opts_default(&r.surfaces);
    r.surfaces.spacing = 5;
    thx_repair_opts_default(&r.repair, 5);
    char *t = NULL;
    thx_edit_log_text(ctx, NULL, NULL, &r, NULL, 0, NULL, &t);
    char *b = t ? strstr(t, "build ") : NULL;
    char *nl = b ? strchr(b, '\n') : NULL;
    snprintf(out, cap, "%.*s", b && nl ? (int)(nl - b) : 0, b ? b : "");
    free(t);
}

/* Replaces @H by a good hash and @B by a good build line. */
static void subst(const char *tmpl, const char *build, char *out, size_t cap)
{
    size_t at = 0;
    for (const char *p = tmpl; *p && at + 1 < cap; p++) {
        const char *put = NULL;
        if (p[0] == '@' && p[1] == 'H') put = H64;
        if (p[0] == '@' && p[1] == 'B') put = build;
        if (put) {
            at += (size_t)snprintf(out + at, cap - at, "%s", put);
            p++;
        } else out[at++] = *p;
    }
    out[at < cap ? at : cap - 1] = '\0';
}

static void test_bad_logs(thx_ctx *ctx)
{
    static const struct {
        const char *text, *msg;
    } T[] = {
        {"", "bad.edits: empty: not a thorax edit log"},
        {"# only a comment\n\n", "bad.edits: empty"},
        {"thorax-contours 1\nend\n", "bad.edits:1: not a thorax edit log: the first line must be \"thorax-edits 1\""},
        {"thorax-edits 2\nend\n", "bad.edits:1: edit log version \"2\": this thorax reads version 1"},
        {"thorax-edits\nend\n", "bad.edits:1: edit log version \"\""},
        {"thorax-edits 1 x\nend\n", "bad.edits:1: edit log version \"1\""},
        {"thorax-edits 1\n", "bad.edits:1: truncated edit log (no 'end' line)"},
        {"thorax-edits 1\ntri_flip torso 1\n", "bad.edits:2: truncated edit log"},
        {"thorax-edits 1\ntri_flip torso 1", "bad.edits:2: truncated edit log"},
        {"thorax-edits 1\nend\ntri_flip torso 1\n", "bad.edits:3: text after 'end'"},
        {"thorax-edits 1\nend\nend\n", "bad.edits:3: text after 'end'"},
        {"thorax-edits 1\nend now\n", "bad.edits:2: end: nothing may follow it"},
        {"thorax-edits 1\nmove torso 1\nend\n", "bad.edits:2: unknown word \"move\""},
        {"thorax-edits 1\nNODE_MOVE torso 1 0 0 0\nend\n", "bad.edits:2: unknown word \"NODE_MOVE\""},
        {"thorax-edits 1\nnode_move torso 1 2 3\nend\n", "bad.edits:2: node_move: 4 values after the word, 5 needed"},
        {"thorax-edits 1\ntri_flip torso\nend\n", "bad.edits:2: tri_flip: 1 value after the word, 2 needed"},
        {"thorax-edits 1\ntri_add torso 1 2 3 4\nend\n", "bad.edits:2: tri_add: 5 values after the word, 4 needed"},
        {"thorax-edits 1\nlayer_rotate torso z=1\nend\n", "bad.edits:2: layer_rotate: 2 values after the word, 3 needed"},
        {"thorax-edits 1\nnode_move torso 0 1 2 3\nend\n", "bad.edits:2: node_move torso: node \"0\" must be 1..2147483647"},
        {"thorax-edits 1\nnode_move torso 2147483648 1 2 3\nend\n", "node \"2147483648\" must be 1..2147483647"},
        {"thorax-edits 1\nnode_move torso -1 1 2 3\nend\n", "node \"-1\" must be"},
        {"thorax-edits 1\nnode_move torso 1.0 1 2 3\nend\n", "node \"1.0\" must be"},
        {"thorax-edits 1\ntri_delete torso +3\nend\n", "bad.edits:2: tri_delete torso: triangle \"+3\" must be"},
        {"thorax-edits 1\nnode_move torso 1 0x10 2 3\nend\n", "bad.edits:2: node_move torso: x = \"0x10\" is not a finite decimal number"},
        {"thorax-edits 1\nnode_move torso 1 inf 2 3\nend\n", "x = \"inf\" is not"},
        {"thorax-edits 1\nnode_move torso 1 1 nan 3\nend\n", "y = \"nan\" is not"},
        {"thorax-edits 1\nnode_move torso 1 1 1e999 3\nend\n", "y = \"1e999\" is not"},
        {"thorax-edits 1\nnode_move torso 1 1 2 1.5x\nend\n", "z = \"1.5x\" is not"},
        {"thorax-edits 1\nnode_move torso 1 1 2 1e\nend\n", "z = \"1e\" is not"},
        {"thorax-edits 1\nnode_move torso 1 . 2 3\nend\n", "x = \".\" is not"},
        {"thorax-edits 1\nnode_move torso 1 - 2 3\nend\n", "x = \"-\" is not"},
        {"thorax-edits 1\nlayer_move torso z=0 1,5 2\nend\n", "layer_move torso: \"1,5\" is not a finite decimal number"},
        {"thorax-edits 1\ntri_add torso 1 2 1\nend\n", "bad.edits:2: tri_add torso: a triangle needs three different nodes (1 2 1)"},
        {"thorax-edits 1\ntri_delete to/rso 1\nend\n", "bad.edits:2: tri_delete: \"to/rso\" is not a surface name"},
        {"thorax-edits 1\ntri_delete .torso 1\nend\n", "\".torso\" is not a surface name"},
        {"thorax-edits 1\ntri_delete aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa 1\nend\n", "is not a surface name"},
        {"thorax-edits 1\nlayer_move torso q=3 1 1\nend\n", "bad.edits:2: layer_move: \"q=3\": a layer is z=Z"},
        {"thorax-edits 1\nlayer_move torso 120 1 1\nend\n", "\"120\": a layer is z=Z"},
        {"thorax-edits 1\nlayer_move torso layer=0 1 1\nend\n", "\"layer=0\": the layer's number must be 1..2147483647"},
        {"thorax-edits 1\nlayer_move torso z=abc 1 1\nend\n", "\"z=abc\": the layer's z must be a decimal number"},
        {"thorax-edits 1\nlayer_smooth torso z=10 0\nend\n", "bad.edits:2: layer_smooth torso: the smoothing bandwidth must be > 0 mm (0)"},
        {"thorax-edits 1\nlayer_smooth torso z=10 -2\nend\n", "the smoothing bandwidth must be > 0 mm (-2)"},
        {"thorax-edits 1\ntri_flip torso 1\ncontours sha256:@H c.txt\nend\n", "bad.edits:3: contours: header lines come before the first edit"},
        {"thorax-edits 1\ntri_flip torso 1\n@B\nend\n", "bad.edits:3: build: header lines come before the first edit"},
        {"thorax-edits 1\ncontours sha256:@H c.txt\ncontours sha256:@H c.txt\nend\n", "bad.edits:3: contours: given twice (first on line 2)"},
        {"thorax-edits 1\n@B\n\n@B\nend\n", "bad.edits:4: build: given twice (first on line 2)"},
        {"thorax-edits 1\ncontours sha256:abc c.txt\nend\n", "bad.edits:2: contours: needs \"contours sha256:HEX PATH\""},
        {"thorax-edits 1\ncontours sha256:@H\nend\n", "bad.edits:2: contours: needs"},
        {"thorax-edits 1\ncontours md5:@H c.txt\nend\n", "bad.edits:2: contours: needs"},
        {"thorax-edits 1\ncontours sha256:0123456789ABCDEF0123456789abcdef0123456789abcdef0123456789abcdef c.txt\nend\n", "contours: needs"},
        {"thorax-edits 1\nbuild spacing=5\nend\n", "bad.edits:2: build: option \"smoothing\" missing"},
        {"thorax-edits 1\nbuild\nend\n", "bad.edits:2: build: option \"spacing\" missing"},
        {"thorax-edits 1\n@B spacing=5\nend\n", "bad.edits:2: build: option \"spacing\" given twice"},
        {"thorax-edits 1\n@B colour=red\nend\n", "bad.edits:2: build: unknown option \"colour\""},
        {"thorax-edits 1\n@B spacing\nend\n", "bad.edits:2: build: \"spacing\" is not OPTION=VALUE"},
        {"thorax-edits 1\nbuild spacing=-1\nend\n", "bad.edits:2: build: spacing=\"-1\" is not a valid value (mm, > 0)"},
        {"thorax-edits 1\nbuild cap=hexagon\nend\n", "build: cap=\"hexagon\" is not a valid value (per-surface, polygon or grid)"},
        {"thorax-edits 1\nbuild strict=yes\nend\n", "build: strict=\"yes\" is not a valid value (0 or 1)"},
        {"thorax-edits 1\nbuild fan_limit=2.5\nend\n", "build: fan_limit=\"2.5\" is not a valid value"},
        {"thorax-edits 1\nbuild fan_limit=6e0\nend\n", "build: fan_limit=\"6e0\" is not a valid value"},
        {"thorax-edits 1\nbuild start=1\nend\n", "build: start=\"1\" is not a valid value (X,Y in mm)"},
        {"thorax-edits 1\nbuild projected_aspect=0.5\nend\n", "build: projected_aspect=\"0.5\" is not a valid value"},
        {"thorax-edits 1\nbuild smoothing=nan\nend\n", "build: smoothing=\"nan\" is not a valid value"},
        {"thorax-edits 1\ntri_flip a 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1\nend\n",
         "bad.edits:2: more than 32 words on a line"},
    };
    char build[1024], text[8192];
    default_build(ctx, build, sizeof build);
    CHECK(strncmp(build, "build spacing=5 smoothing=2 start=0,1000 cap=per-surface ", 57) == 0);
    int bad_rows = 0;
    for (size_t i = 0; i < sizeof T / sizeof *T; i++) {
        subst(T[i].text, build, text, sizeof text);
        thx_edit_log *log = NULL;
        thx_status st = thx_edit_log_parse(ctx, "bad.edits", text, strlen(text), &log);
        int ok = st == THX_EINPUT && log == NULL && strstr(thx_ctx_message(ctx), T[i].msg) != NULL;
        if (!ok) {
            fprintf(stderr, "row %zu: status %d, message \"%s\", wanted \"%s\"\n", i, (int)st, thx_ctx_message(ctx), T[i].msg);
            bad_rows++;
        }
        thx_edit_log_destroy(&log);
    }
    CHECK(bad_rows == 0);
    printf("%zu bad logs refused with file:line\n", sizeof T / sizeof *T);
    /* a NUL byte, a line too long */
    const char nul[] = "thorax-edits 1\ntri_\0flip torso 1\nend\n";
    thx_edit_log *log = NULL;
    CHECK(thx_edit_log_parse(ctx, "bad.edits", nul, sizeof nul - 1, &log) == THX_EINPUT &&
          tl_msg_has(ctx, "bad.edits:2: NUL byte at byte offset 19"));
    char *lng = malloc(6000);
    snprintf(lng, 6000, "thorax-edits 1\n# %05000d\nend\n", 0);
    CHECK(thx_edit_log_parse(ctx, "bad.edits", lng, strlen(lng), &log) == THX_EINPUT &&
          tl_msg_has(ctx, "bad.edits:2: line of 5002 bytes (at most 4096)"));
    free(lng);
    /* files: missing, a directory, larger than 64 MiB (sparse) */
    CHECK(thx_edit_log_read(ctx, tl_path("none.edits"), &log) == THX_EIO && tl_msg_has(ctx, "none.edits: cannot open"));
    CHECK(thx_edit_log_read(ctx, tl_scratch, &log) == THX_EIO && tl_msg_has(ctx, "not a regular file"));
    int fd = open(tl_path("huge.edits"), O_CREAT | O_WRONLY | O_TRUNC, 0644);
    CHECK(fd >= 0 && ftruncate(fd, (65 << 20)) == 0);
    if (fd >= 0) close(fd);
    CHECK(thx_edit_log_read(ctx, tl_path("huge.edits"), &log) == THX_EINPUT && tl_msg_has(ctx, "larger than any edit log"));
    unlink(tl_path("huge.edits"));
}

/* ---- the log in a model directory ---------------------------------------------------------- */

/* A tetrahedron surface "tet" (closed, outward). */
static thx_model *tet_model(thx_ctx *ctx)
{
    thx_model *m = NULL;
    thx_surface *s = NULL;
    thx_model_create(ctx, &m);
    thx_surface_create(ctx, "tet", THX_ROLE_OUTER, &s);
    static const double xyz[12] = {0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10};
    static const int32_t tri[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    s->n_nodes = 4;
    s->xyz = malloc(sizeof xyz);
    memcpy(s->xyz, xyz, sizeof xyz);
    s->n_tris = 4;
    s->tri = malloc(sizeof tri);
    memcpy(s->tri, tri, sizeof tri);
    thx_model_add_surface(ctx, m, &s);
    m->provenance_json = strdup("{\"program\":\"test_edit_log\"}");
    return m;
}

static void test_model_dir(thx_ctx *ctx)
{
    const char *log = "thorax-edits 1\ntri_flip tet 1\ntri_flip tet 1\nend\n";
    thx_model *m = tet_model(ctx);
    m->edit_log = strdup(log);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("t1")));
    thx_model_destroy(&m);
    char *on_disk = tl_slurp(ctx, tl_path("t1/edits.txt"), NULL);
    CHECK(on_disk && strcmp(on_disk, log) == 0);
    free(on_disk);
    char hex[65];
    thx_sha256_hex(log, strlen(log), hex);
    char *manifest = tl_slurp(ctx, tl_path("t1/model.json"), NULL);
    cJSON *j = manifest ? cJSON_Parse(manifest) : NULL;
    const cJSON *p = cJSON_GetObjectItemCaseSensitive(j, "provenance");
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(p, "edit_log")) &&
          !strcmp(cJSON_GetObjectItemCaseSensitive(p, "edit_log")->valuestring, "edits.txt"));
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(p, "edit_log_sha256")) &&
          !strcmp(cJSON_GetObjectItemCaseSensitive(p, "edit_log_sha256")->valuestring, hex));
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(p, "program")));
    cJSON_Delete(j);
    free(manifest);
    /* read back: the log in the model; written again: the same directory */
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("t1"), &m));
    CHECK(m && m->edit_log && strcmp(m->edit_log, log) == 0);
    /* replaced over itself: its own output, edits.txt included (named by the manifest) */
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("t1")));
    /* without the log: no edits.txt and no record of one, whatever the provenance said */
    free(m->edit_log);
    m->edit_log = NULL;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("t1")));
    CHECK(!tl_exists(tl_path("t1/edits.txt")));
    manifest = tl_slurp(ctx, tl_path("t1/model.json"), NULL);
    CHECK(manifest && !strstr(manifest, "\"edit_log") && strstr(manifest, "test_edit_log"));
    free(manifest);
    m->edit_log = strdup(log);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("t2")));
    thx_model_destroy(&m);
    /* changed by hand: refused, naming the file and both hashes */
    tl_write_text(tl_path("t2/edits.txt"), "thorax-edits 1\ntri_flip tet 2\ntri_flip tet 2\nend\n");
    CHECK(thx_model_read(ctx, tl_path("t2"), &m) == THX_EINPUT && tl_msg_has(ctx, "t2/edits.txt: its SHA-256 is ") &&
          tl_msg_has(ctx, hex) && m == NULL);
    tl_write_bytes(tl_path("t2/edits.txt"), "thorax-edits 1\0\n", 16);
    CHECK(thx_model_read(ctx, tl_path("t2"), &m) == THX_EINPUT && tl_msg_has(ctx, "edits.txt:1: NUL byte"));
    unlink(tl_path("t2/edits.txt"));
    CHECK(thx_model_read(ctx, tl_path("t2"), &m) == THX_EINPUT && tl_msg_has(ctx, "t2/edits.txt: the edit log model.json names is missing"));
    /* a manifest naming a file outside the directory, or with a bad hash: refused */
    char *mj = tl_slurp(ctx, tl_path("t2/model.json"), NULL);
    if (mj) {
        char *q = strstr(mj, "\"edits.txt\"");
        memcpy(q, "\"../x.txt\"", 10);
        q[10] = ' ';
        tl_write_text(tl_path("t2/model.json"), mj);
        CHECK(thx_model_read(ctx, tl_path("t2"), &m) == THX_EINPUT &&
              tl_msg_has(ctx, "\"provenance\".\"edit_log\" must name a file in the model directory"));
        free(mj);
    }
    /* an unnamed file beside the model still stops a write (thorax replaces only its own) */
    m = tet_model(ctx);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("t3")));
    tl_write_text(tl_path("t3/notes.txt"), "mine\n");
    CHECK(thx_model_write(ctx, m, tl_path("t3")) == THX_EIO && tl_msg_has(ctx, "notes.txt"));
    thx_model_destroy(&m);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK || tl_scratch_make("test_edit_log")) return 1;
    test_round_trip(ctx);
    test_bad_logs(ctx);
    test_model_dir(ctx);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_edit_log");
}
