/*
 * Manual editing of a model's surfaces (thorax/edit/edit.h; paper 3.2 "Manual editing"; issue 13):
 * each edit changes exactly what it should and the strict check says what it did (a deleted
 * triangle opens the surface, a flipped one breaks the orientation, adding the triangle back or
 * flipping again passes); a layer moved or rotated moves that layer's nodes in its plane and
 * nothing else; undo restores the model directory byte for byte, redo gives it again; a re-lace
 * says which mesh edits it discarded; a session saved and the same log replayed on the contours
 * give identical model directories (the phantom at medium resolution, and a session reopened on a
 * saved model); edits that no longer apply stop a replay with LOG:LINE.
 * The log's format (round trip, refusals) is tests/test_edit_log.c.
 */
#include <cjson/cJSON.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/core/sha256.h"
#include "thorax/edit/edit.h"
#include "thorax/io/contours_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/phantom/phantom.h"

/* ---- helpers ------------------------------------------------------------------------------------- */

/* Two surfaces on z = 0..40 (10 mm apart): "tube", an ellipse 30 x 20 mm about (5, -3) with 40
 * points (cap polygon), and "core", a circle of 8 mm about (5, -3) on z = 10..30 inside it (cap
 * grid). Spacing 5 mm; a frame, so the start point is the anterior midline as in the CLI. */
static void write_small_contours(const char *path)
{
    char buf[32768];
    size_t at = 0;
    at += (size_t)snprintf(buf + at, sizeof buf - at,
                           "thorax-contours 1\nspacing 5\nframe +z +y\nsurface tube outer cap polygon\n"
                           "surface core heart cap grid\n");
    for (int l = 0; l <= 4; l++) {
        at += (size_t)snprintf(buf + at, sizeof buf - at, "layer %d\nloop tube\n", 10 * l);
        for (int i = 0; i < 40; i++) {
            double t = 2 * M_PI * i / 40;
            at += (size_t)snprintf(buf + at, sizeof buf - at, "%.9f %.9f\n", 5 + 30 * cos(t), -3 + 20 * sin(t));
        }
        if (l >= 1 && l <= 3) {
            at += (size_t)snprintf(buf + at, sizeof buf - at, "loop core\n");
            for (int i = 0; i < 16; i++) {
                double t = 2 * M_PI * i / 16;
                at += (size_t)snprintf(buf + at, sizeof buf - at, "%.9f %.9f\n", 5 + 8 * cos(t), -3 + 8 * sin(t));
            }
        }
    }
    snprintf(buf + at, sizeof buf - at, "end\n");
    tl_write_text(path, buf);
}

/* What `thorax surfaces CONTOURS -o MODEL` does (src/cli/cmd_surfaces.c), default options: read,
 * repair, build, the provenance (contours' hash and path from model_dir, the recipe). */
static thx_status build_like_cli(thx_ctx *ctx, const char *contours, const char *model_dir, thx_model **m,
                                 thx_contours **c, thx_edit_recipe *r, char sha[65])
{
    *m = NULL;
    *c = NULL;
    THX_CHECK(thx_contours_read_raw(ctx, contours, c));
    double spacing = (*c)->spacing > 0 ? (*c)->spacing : 5.0;
    thx_surfaces_opts_default(&r->surfaces);
    r->surfaces.spacing = spacing;
    thx_repair_opts_default(&r->repair, spacing);
    thx_repair_log rlog = {0};
    thx_status st = thx_contours_repair(ctx, *c, &r->repair, &rlog);
    thx_repair_log_free(&rlog);
    if (st == THX_OK) st = thx_surfaces_build(ctx, *c, &r->surfaces, m, NULL, NULL);
    if (st != THX_OK) return st;
    (*m)->frame = (*c)->frame;
    cJSON *p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "program", "test_edit");
    cJSON_AddStringToObject(p, "input", contours);
    st = thx_edit_record_contours(ctx, p, contours, model_dir, sha);
    cJSON *op = cJSON_AddObjectToObject(p, "options");
    if (st == THX_OK) st = thx_edit_recipe_json(ctx, r, op);
    (*m)->provenance_json = cJSON_PrintUnformatted(p);
    cJSON_Delete(p);
    return st;
}

/* A session on the model built from contours (in memory, as the CLI's replay makes it). */
static thx_edit_session *session_on(thx_ctx *ctx, const char *contours, const char *model_dir)
{
    thx_model *m = NULL;
    thx_contours *c = NULL;
    thx_edit_recipe r;
    char sha[65];
    thx_edit_session *s = NULL;
    thx_status st = build_like_cli(ctx, contours, model_dir, &m, &c, &r, sha);
    if (st == THX_OK) st = thx_edit_session_create(ctx, &m, &c, &r, contours, sha, NULL, &s);
    if (st != THX_OK) fprintf(stderr, "session_on(%s): %s\n", contours, thx_ctx_message(ctx));
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    return s;
}

/* Whether two directories hold the same files with the same bytes (every file compared; the first
 * difference is named on stderr unless quiet). */
static int same_dirs_q(thx_ctx *ctx, const char *a, const char *b, int quiet)
{
    int same = 1, n = 0;
    for (int side = 0; side < 2 && same; side++) {
        const char *x = side ? b : a, *y = side ? a : b;
        DIR *d = opendir(x);
        if (!d) return 0;
        struct dirent *e;
        while (same && (e = readdir(d))) {
            if (e->d_name[0] == '.') continue;
            char px[4096], py[4096];
            snprintf(px, sizeof px, "%s/%s", x, e->d_name);
            snprintf(py, sizeof py, "%s/%s", y, e->d_name);
            size_t lx = 0, ly = 0;
            char *tx = tl_slurp(ctx, px, &lx), *ty = tl_slurp(ctx, py, &ly);
            if (!tx || !ty || lx != ly || memcmp(tx, ty, lx) != 0) {
                if (!quiet) fprintf(stderr, "  %s and %s differ\n", px, py);
                same = 0;
            }
            n += side == 0;
            free(tx);
            free(ty);
        }
        closedir(d);
    }
    return same && n > 0;
}

static int same_dirs(thx_ctx *ctx, const char *a, const char *b) { return same_dirs_q(ctx, a, b, 0); }

/* ---- mesh edits ------------------------------------------------------------------------------- */

static void test_mesh_edits(thx_ctx *ctx)
{
    write_small_contours(tl_path("small.txt"));
    thx_edit_session *s = session_on(ctx, tl_path("small.txt"), tl_path("small_model"));
    CHECK(s != NULL);
    if (!s) return;
    const thx_model *m = thx_edit_session_model(s);
    CHECK(m->n_surfaces == 2 && strcmp(m->surf[0]->name, "tube") == 0);
    const thx_surface *tube = m->surf[0];
    size_t nn = tube->n_nodes, nt = tube->n_tris;
    printf("small model: tube %zu nodes, %zu triangles; core %zu nodes, %zu triangles\n", nn, nt, m->surf[1]->n_nodes,
           m->surf[1]->n_tris);
    thx_edit_result res;
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("m0")));

    /* node_move: the node moved by exactly the vector, every other coordinate untouched */
    double *before = malloc(3 * nn * sizeof *before);
    memcpy(before, tube->xyz, 3 * nn * sizeof *before);
    size_t k = 17;
    thx_vec3 to = thx_v3(before[3 * k] + 1.5, before[3 * k + 1] - 0.25, before[3 * k + 2] + 0.125);
    thx_edit e = thx_edit_tri_flip("nosuch", 0);
    CHECK(thx_edit_apply(ctx, s, &e, NULL) == THX_EINPUT && tl_msg_has(ctx, "the model has no surface \"nosuch\""));
    e = thx_edit_node_move("tube", k, to);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    tube = thx_edit_session_model(s)->surf[0];
    CHECK(tube->xyz[3 * k] - before[3 * k] == 1.5 && tube->xyz[3 * k + 1] - before[3 * k + 1] == -0.25 &&
          tube->xyz[3 * k + 2] - before[3 * k + 2] == 0.125);
    int others = 1;
    for (size_t i = 0; i < 3 * nn; i++)
        if (i / 3 != k && tube->xyz[i] != before[i]) others = 0;
    CHECK(others);
    CHECK(res.surface == 0 && res.check.n_nodes == nn && strstr(res.summary, "tube: ") == res.summary);
    printf("node_move: %s\n", res.summary);
    CHECK(thx_edit_session_mesh_edits(s, 0) == 1);
    CHECK_OK(ctx, thx_edit_undo(ctx, s, &res));
    tube = thx_edit_session_model(s)->surf[0];
    CHECK(memcmp(tube->xyz, before, 3 * nn * sizeof *before) == 0);
    CHECK(thx_edit_session_mesh_edits(s, 0) == 0 && strstr(res.note, "undone: node_move tube 18") != NULL);
    free(before);

    /* tri_delete: one triangle fewer, the surface open at its 3 edges, and the check says so */
    int32_t gone[3];
    size_t t = 40;
    memcpy(gone, &tube->tri[3 * t], sizeof gone);
    int32_t next[3];
    memcpy(next, &tube->tri[3 * (t + 1)], sizeof next);
    e = thx_edit_tri_delete("tube", t);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    tube = thx_edit_session_model(s)->surf[0];
    CHECK(tube->n_tris == nt - 1);
    CHECK(memcmp(&tube->tri[3 * t], next, sizeof next) == 0); /* the ones after moved down */
    CHECK(!res.check_ok && (res.check.failures & THX_CHECKF_BOUNDARY) && res.check.n_boundary_edges == 3);
    CHECK(strstr(res.summary, "FAILS: 3 open edges") != NULL);
    printf("tri_delete: %s\n", res.summary);

    /* tri_add of the same nodes, given in the other order: stored in the order of its neighbours,
       closed again, and the check passes */
    e = thx_edit_tri_add("tube", (size_t)gone[0], (size_t)gone[2], (size_t)gone[1]);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    tube = thx_edit_session_model(s)->surf[0];
    CHECK(tube->n_tris == nt && res.tri == nt - 1);
    const int32_t *a = &tube->tri[3 * (nt - 1)];
    int rotation = 0; /* a is a cyclic rotation of gone (the same orientation) */
    for (int r = 0; r < 3; r++)
        rotation |= a[0] == gone[r] && a[1] == gone[(r + 1) % 3] && a[2] == gone[(r + 2) % 3];
    CHECK(rotation);
    CHECK(res.neighbours_agree == 3 && res.neighbours_disagree == 0);
    CHECK(res.check_ok && res.check.failures == 0);
    printf("tri_add: %s; %s\n", res.note, res.summary);
    /* the same triangle twice is refused, and changes nothing */
    e = thx_edit_tri_add("tube", (size_t)gone[1], (size_t)gone[0], (size_t)gone[2]);
    CHECK(thx_edit_apply(ctx, s, &e, &res) == THX_EINPUT && tl_msg_has(ctx, "is already on these nodes"));
    CHECK(thx_edit_session_model(s)->surf[0]->n_tris == nt && thx_edit_undo_count(s) == 2);
    e = thx_edit_tri_add("tube", 1, 2, nn);
    CHECK(thx_edit_apply(ctx, s, &e, NULL) == THX_EINPUT && tl_msg_has(ctx, "tri_add tube 2 3 ") &&
          tl_msg_has(ctx, "out of range 1.."));
    /* undo both: the model directory byte for byte as before */
    CHECK_OK(ctx, thx_edit_undo(ctx, s, NULL));
    CHECK_OK(ctx, thx_edit_undo(ctx, s, &res));
    CHECK(res.check_ok);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("m1")));
    CHECK(same_dirs(ctx, tl_path("m0"), tl_path("m1")));

    /* tri_flip: an orientation fault on its three edges; flipping back clears it */
    e = thx_edit_tri_flip("core", 5);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    CHECK(res.surface == 1 && !res.check_ok && (res.check.failures & THX_CHECKF_ORIENTATION) &&
          res.check.n_inconsistent_edges == 3 && res.check.n_boundary_edges == 0);
    CHECK(strstr(res.summary, "core: FAILS: closed, orientation: 3 edges") != NULL);
    printf("tri_flip: %s\n", res.summary);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    CHECK(res.check_ok && strstr(res.summary, "core: passes: closed, orientation ok, solid angle 4pi within") != NULL);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("m2")));
    /* two flips give the same surfaces; only the log (two more lines) differs */
    CHECK(!same_dirs_q(ctx, tl_path("m0"), tl_path("m2"), 1));
    {
        char *f0 = tl_slurp(ctx, tl_path("m0/core.fac"), NULL), *f2 = tl_slurp(ctx, tl_path("m2/core.fac"), NULL);
        CHECK(f0 && f2 && strcmp(f0, f2) == 0);
        free(f0);
        free(f2);
    }
    thx_edit_session_destroy(&s);
    CHECK(s == NULL);
}

/* ---- layer edits ------------------------------------------------------------------------------ */

/* The nodes of surface s at height z: their indices (returned count), into idx (cap n). */
static size_t nodes_at(const thx_surface *s, double z, size_t *idx, size_t cap)
{
    size_t n = 0;
    for (size_t i = 0; i < s->n_nodes; i++)
        if (s->xyz[3 * i + 2] == z && n < cap) idx[n++] = i;
    return n;
}

static void test_layer_edits(thx_ctx *ctx)
{
    thx_edit_session *s = session_on(ctx, tl_path("small.txt"), tl_path("small_model"));
    CHECK(s != NULL);
    if (!s) return;
    const thx_surface *t0 = thx_edit_session_model(s)->surf[0];
    size_t nn = t0->n_nodes;
    double *old = malloc(3 * nn * sizeof *old);
    memcpy(old, t0->xyz, 3 * nn * sizeof *old);
    size_t idx[256], n20 = nodes_at(t0, 20, idx, 256);
    CHECK(n20 > 10);
    const thx_contours *c = thx_edit_session_contours(s);
    const thx_loop *lp = &c->surf[0].layers[2].loops[0];
    thx_vec2 p0 = lp->p[0], p7 = lp->p[7];
    CHECK(c->surf[0].layers[2].z == 20);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("l0")));

    /* a node edit first: the re-lace will discard it, and say so */
    thx_edit e = thx_edit_tri_flip("tube", 3);
    thx_edit_result res;
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, NULL));
    CHECK(thx_edit_session_mesh_edits(s, 0) == 1);

    /* layer_move: the contour points moved by exactly (dx, dy); the layer's nodes moved in its plane
       (z unchanged, on the moved ellipse), every node of the other layers as it was */
    e = thx_edit_layer_move("tube", thx_edit_layer_z(20), 2.5, -1.5);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    CHECK(res.relaced && res.discarded == 1 && strstr(res.note, "1 earlier node/triangle edit on it discarded") != NULL);
    CHECK(thx_edit_session_mesh_edits(s, 0) == 0);
    c = thx_edit_session_contours(s);
    lp = &c->surf[0].layers[2].loops[0];
    CHECK(lp->p[0].x == p0.x + 2.5 && lp->p[0].y == p0.y - 1.5 && lp->p[7].x == p7.x + 2.5 && lp->p[7].y == p7.y - 1.5);
    const thx_surface *t1 = thx_edit_session_model(s)->surf[0];
    CHECK(t1->n_nodes == nn);
    size_t idx1[256], m20 = nodes_at(t1, 20, idx1, 256);
    CHECK(m20 == n20);
    double worst = 0;
    for (size_t i = 0; i < m20; i++) {
        double x = t1->xyz[3 * idx1[i]] - 5 - 2.5, y = t1->xyz[3 * idx1[i] + 1] + 3 + 1.5;
        double r = sqrt(x * x / (30.0 * 30) + y * y / (20.0 * 20)); /* 1 on the moved ellipse */
        if (fabs(r - 1) > worst) worst = fabs(r - 1);
    }
    printf("layer_move: %zu nodes of z=20 on the moved ellipse within %.2g (relative); %s\n", m20, worst, res.summary);
    CHECK(worst < 2e-3);
    int others = 1, zs = 1;
    for (size_t i = 0; i < nn; i++) {
        if (t1->xyz[3 * i + 2] != old[3 * i + 2]) zs = 0;
        if (old[3 * i + 2] != 20)
            for (int q = 0; q < 3; q++) others &= t1->xyz[3 * i + q] == old[3 * i + q];
    }
    CHECK(zs && others);
    CHECK(res.check_ok && res.check.n_boundary_edges == 0);

    /* layer_rotate by 90 degrees about the layer's centroid (the moved ellipse's centre): the long
       axis turns from x to y; z unchanged; the other layers as they were */
    e = thx_edit_layer_rotate("tube", thx_edit_layer_index(2), 90);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    const thx_surface *t2 = thx_edit_session_model(s)->surf[0];
    size_t idx2[256], k20 = nodes_at(t2, 20, idx2, 256);
    CHECK(k20 == n20);
    worst = 0;
    for (size_t i = 0; i < k20; i++) {
        double x = t2->xyz[3 * idx2[i]] - 7.5, y = t2->xyz[3 * idx2[i] + 1] + 4.5;
        double r = sqrt(x * x / (20.0 * 20) + y * y / (30.0 * 30));
        if (fabs(r - 1) > worst) worst = fabs(r - 1);
    }
    printf("layer_rotate: %zu nodes of z=20 on the turned ellipse within %.2g; %s\n", k20, worst, res.summary);
    CHECK(worst < 2e-3);
    others = 1;
    for (size_t i = 0; i < nn; i++)
        if (old[3 * i + 2] != 20)
            for (int q = 0; q < 3; q++) others &= t2->xyz[3 * i + q] == old[3 * i + q];
    CHECK(others && res.check_ok);

    /* a layer that is not there: refused, nothing changed */
    e = thx_edit_layer_move("tube", thx_edit_layer_z(25), 1, 1);
    CHECK(thx_edit_apply(ctx, s, &e, NULL) == THX_EINPUT && tl_msg_has(ctx, "layer_move tube z=25 1 1: ") &&
          tl_msg_has(ctx, "has no layer at z=25"));
    e = thx_edit_layer_smooth("core", thx_edit_layer_index(3), 2);
    CHECK(thx_edit_apply(ctx, s, &e, NULL) == THX_EINPUT && tl_msg_has(ctx, "layer 4 out of range 1..3"));
    CHECK(thx_edit_undo_count(s) == 3);

    /* undo all three: the directory as it was, byte for byte; redo all: as after them */
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("l3")));
    for (int i = 0; i < 3; i++) CHECK_OK(ctx, thx_edit_undo(ctx, s, NULL));
    CHECK(thx_edit_undo(ctx, s, NULL) == THX_EINPUT && tl_msg_has(ctx, "nothing to undo"));
    CHECK(thx_edit_session_mesh_edits(s, 0) == 0 && thx_edit_redo_count(s) == 3);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("l0b")));
    CHECK(same_dirs(ctx, tl_path("l0"), tl_path("l0b")));
    c = thx_edit_session_contours(s);
    CHECK(c->surf[0].layers[2].loops[0].p[0].x == p0.x && c->surf[0].layers[2].loops[0].p[0].y == p0.y);
    for (int i = 0; i < 3; i++) CHECK_OK(ctx, thx_edit_redo(ctx, s, &res));
    CHECK(thx_edit_redo(ctx, s, NULL) == THX_EINPUT && tl_msg_has(ctx, "nothing to redo"));
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("l3b")));
    CHECK(same_dirs(ctx, tl_path("l3"), tl_path("l3b")));
    /* undo one, then a new edit: the redo stack is gone */
    CHECK_OK(ctx, thx_edit_undo(ctx, s, NULL));
    e = thx_edit_node_move("core", 0, thx_v3(5, -3, 10.5));
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, NULL));
    CHECK(thx_edit_redo_count(s) == 0 && thx_edit_undo_count(s) == 3);
    free(old);
    thx_edit_session_destroy(&s);
}

/* layer_smooth on the phantom's jittered torso: the layer's loop turns less (total absolute
 * turning falls toward 2 pi), its z stays, the surface still passes. */
static double turning(const thx_loop *lp)
{
    double sum = 0;
    for (size_t i = 0; i < lp->n; i++) {
        thx_vec2 a = lp->p[(i + lp->n - 1) % lp->n], b = lp->p[i], c = lp->p[(i + 1) % lp->n];
        sum += fabs(atan2((b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x),
                          (b.x - a.x) * (c.x - b.x) + (b.y - a.y) * (c.y - b.y)));
    }
    return sum;
}

/* ---- the phantom: smoothing, a session saved and replayed ----------------------------------- */

static void phantom_contours(thx_ctx *ctx, const char *path)
{
    thx_phantom_opts po;
    thx_phantom_opts_default(&po);
    po.resolution = THX_PHANTOM_MEDIUM;
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_phantom_contours(ctx, &po, &c));
    CHECK_OK(ctx, thx_contours_write(ctx, c, path, "test_edit"));
    thx_contours_destroy(&c);
}

/* The replay the CLI makes (thorax surfaces CONTOURS --edits LOG -o dir). */
static thx_status replay_into(thx_ctx *ctx, const char *contours, const char *log_path, const char *dir)
{
    thx_edit_log *log = NULL;
    thx_model *m = NULL;
    thx_contours *c = NULL;
    thx_edit_recipe r;
    char sha[65];
    thx_edit_session *s = NULL;
    thx_status st = thx_edit_log_read(ctx, log_path, &log);
    if (st == THX_OK) st = build_like_cli(ctx, contours, dir, &m, &c, &r, sha);
    if (st == THX_OK) st = thx_edit_session_create(ctx, &m, &c, &r, contours, sha, NULL, &s);
    if (st == THX_OK) st = thx_edit_replay(ctx, s, log, NULL, NULL);
    if (st == THX_OK) st = thx_edit_session_finish(ctx, &s, &m, NULL);
    if (st == THX_OK) st = thx_model_write(ctx, m, dir);
    thx_edit_session_destroy(&s);
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    thx_edit_log_destroy(&log);
    return st;
}

static void test_phantom(thx_ctx *ctx)
{
    char cpath[2048]; /* tl_path's buffers rotate */
    snprintf(cpath, sizeof cpath, "%s", tl_path("phantom.txt"));
    phantom_contours(ctx, cpath);
    /* the model as the CLI writes it, then a session opened on the directory: it finds the
       contours by the provenance's path from the model and checks their hash */
    thx_model *m = NULL;
    thx_contours *c = NULL;
    thx_edit_recipe r;
    char sha[65], hex[65];
    double t0 = thx_wtime();
    CHECK_OK(ctx, build_like_cli(ctx, cpath, tl_path("p0"), &m, &c, &r, sha));
    CHECK_OK(ctx, thx_sha256_file(ctx, cpath, hex));
    CHECK(strcmp(sha, hex) == 0);
    CHECK(m && strstr(m->provenance_json, "\"input_from_model\":\"../phantom.txt\"") != NULL);
    if (m) CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("p0")));
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    thx_edit_session *s = NULL;
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("p0"), NULL, NULL, &s));
    if (!s) return;
    CHECK(thx_edit_session_contours(s) != NULL && thx_edit_session_note(s)[0] == '\0');
    printf("phantom built and opened in %.2f s\n", thx_wtime() - t0);

    /* layer_smooth: the torso's layer at z=150 (phantom layer 30) turns less */
    const thx_contours *pc = thx_edit_session_contours(s);
    int ts = thx_contours_find_surface(pc, "torso");
    size_t L = 0;
    while (L < pc->surf[ts].n_layers && pc->surf[ts].layers[L].z != 150) L++;
    CHECK(L < pc->surf[ts].n_layers);
    double before = turning(&pc->surf[ts].layers[L].loops[0]);
    thx_edit_result res;
    thx_edit e = thx_edit_layer_smooth("torso", thx_edit_layer_z(150), 6);
    t0 = thx_wtime();
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    double t_smooth = thx_wtime() - t0;
    double after = turning(&thx_edit_session_contours(s)->surf[ts].layers[L].loops[0]);
    printf("layer_smooth torso z=150 6 mm: total turning %.3f -> %.3f rad (2 pi = %.3f), %.2f s; %s\n", before, after,
           2 * M_PI, t_smooth, res.summary);
    CHECK(after < before && after >= 2 * M_PI - 1e-9);
    CHECK(res.check_ok);
    size_t zi[4096];
    CHECK(nodes_at(thx_edit_session_model(s)->surf[0], 150, zi, 4096) > 20);

    /* a mixed session with undo and redo, saved; then the log it saved replayed from the contours
       gives the same directory, byte for byte */
    const thx_model *pm = thx_edit_session_model(s);
    long lung = -1;
    for (size_t k = 0; k < pm->n_surfaces; k++)
        if (!strcmp(pm->surf[k]->name, "lung_l")) lung = (long)k;
    CHECK(lung >= 0);
    thx_edit seq[] = {
        thx_edit_node_move("torso", 3, thx_v3(0.1, 1.0 / 3, 150)),
        thx_edit_node_move("heart", 12, thx_v3(-30.1, 10.3, 115.25)),
        thx_edit_tri_delete("lung_l", 100),
        thx_edit_tri_flip("fat", 7),
        thx_edit_layer_move("lung_l", thx_edit_layer_z(120), 1.5, -2),
        thx_edit_tri_add("lung_l", 3, 4, 40),
        thx_edit_layer_rotate("heart", thx_edit_layer_z(110), 7.5),
    };
    for (size_t i = 0; i < sizeof seq / sizeof *seq; i++) CHECK_OK(ctx, thx_edit_apply(ctx, s, &seq[i], &res));
    /* the heart's rotation and the tri_add undone, the tri_add done again */
    CHECK_OK(ctx, thx_edit_undo(ctx, s, NULL));
    CHECK_OK(ctx, thx_edit_undo(ctx, s, NULL));
    CHECK_OK(ctx, thx_edit_redo(ctx, s, NULL));
    CHECK(thx_edit_undo_count(s) == 7 && thx_edit_redo_count(s) == 1);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("pa")));
    CHECK_OK(ctx, thx_edit_session_write_log(ctx, s, tl_path("pa.edits")));
    CHECK_OK(ctx, thx_edit_session_write_log(ctx, s, tl_path("pa.edits"))); /* its own: replaced */
    tl_write_text(tl_path("notes.txt"), "my notes\n");
    CHECK(thx_edit_session_write_log(ctx, s, tl_path("notes.txt")) == THX_EIO && tl_msg_has(ctx, "notes.txt"));
    {
        char *n = tl_slurp(ctx, tl_path("notes.txt"), NULL);
        CHECK(n && strcmp(n, "my notes\n") == 0);
        free(n);
    }
    thx_edit_session_destroy(&s);
    t0 = thx_wtime();
    CHECK_OK(ctx, replay_into(ctx, cpath, tl_path("pa/edits.txt"), tl_path("pb")));
    printf("replayed 7 edits (2 re-laces) in %.2f s\n", thx_wtime() - t0);
    CHECK(same_dirs(ctx, tl_path("pa"), tl_path("pb")));
    {
        char *l1 = tl_slurp(ctx, tl_path("pa/edits.txt"), NULL), *l2 = tl_slurp(ctx, tl_path("pa.edits"), NULL);
        CHECK(l1 && l2 && strcmp(l1, l2) == 0 && strstr(l1, "node_move torso 4 0.1 0.3333333333333333 150\n"));
        free(l1);
        free(l2);
    }

    /* a session reopened on the edited model: the log is its start (not undoable); its layer edits
       are in the contours, so a further layer edit on lung_l starts from the moved layer; saved and
       replayed, the same again */
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("pa"), NULL, NULL, &s));
    if (!s) return;
    CHECK(thx_edit_undo_count(s) == 0 && thx_edit_undo(ctx, s, NULL) == THX_EINPUT &&
          tl_msg_has(ctx, "edits of the loaded log are the start"));
    CHECK(thx_edit_session_mesh_edits(s, (size_t)lung) == 1); /* the tri_add after its re-lace */
    e = thx_edit_layer_move("lung_l", thx_edit_layer_z(120), -0.5, 0.25);
    CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, &res));
    CHECK(res.discarded == 1);
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("pc")));
    thx_edit_session_destroy(&s);
    CHECK_OK(ctx, replay_into(ctx, cpath, tl_path("pc/edits.txt"), tl_path("pd")));
    CHECK(same_dirs(ctx, tl_path("pc"), tl_path("pd")));
    /* a session on pa with nothing edited saves pa again, byte for byte */
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("pa"), cpath, NULL, &s));
    CHECK_OK(ctx, thx_edit_session_save(ctx, s, tl_path("pa2")));
    CHECK(same_dirs(ctx, tl_path("pa"), tl_path("pa2")));
    thx_edit_session_destroy(&s);

    /* edits that no longer apply stop the replay at their line, naming it */
    tl_write_text(tl_path("bad1.edits"), "thorax-edits 1\nnode_move torso 2 1 2 3\n# next\nnode_move torso 99999 1 2 3\nend\n");
    CHECK(replay_into(ctx, cpath, tl_path("bad1.edits"), tl_path("pe")) == THX_EINPUT &&
          tl_msg_has(ctx, "bad1.edits:4: node_move torso 99999 1 2 3: node 99999 out of range 1..3023"));
    tl_write_text(tl_path("bad2.edits"), "thorax-edits 1\ntri_flip heart 1\nlayer_rotate lung_r z=125 3\nend\n");
    CHECK(replay_into(ctx, cpath, tl_path("bad2.edits"), tl_path("pe")) == THX_EINPUT &&
          tl_msg_has(ctx, "bad2.edits:3: layer_rotate lung_r z=125 3: surface \"lung_r\" has no layer at z=125"));
    tl_write_text(tl_path("bad3.edits"), "thorax-edits 1\ntri_delete lung 1\nend\n");
    CHECK(replay_into(ctx, cpath, tl_path("bad3.edits"), tl_path("pe")) == THX_EINPUT &&
          tl_msg_has(ctx, "bad3.edits:2: tri_delete lung 1: the model has no surface \"lung\""));
    CHECK(!tl_exists(tl_path("pe")));
    /* another contour file, or other options, than the log's: refused before any edit */
    char *log = tl_slurp(ctx, tl_path("pa/edits.txt"), NULL);
    if (log) {
        char *h = strstr(log, "sha256:"), was = h[7];
        h[7] = was == '0' ? '1' : '0';
        tl_write_text(tl_path("bad4.edits"), log);
        CHECK(replay_into(ctx, cpath, tl_path("bad4.edits"), tl_path("pe")) == THX_EINPUT &&
              tl_msg_has(ctx, "bad4.edits:3: the log was made on contours of SHA-256"));
        h[7] = was;
        char *sp = strstr(log, "spacing=11 ");
        CHECK(sp != NULL);
        if (sp) {
            memcpy(sp, "spacing=12 ", 11);
            tl_write_text(tl_path("bad5.edits"), log);
            CHECK(replay_into(ctx, cpath, tl_path("bad5.edits"), tl_path("pe")) == THX_EINPUT &&
                  tl_msg_has(ctx, "bad5.edits:4: the log was made on surfaces built with other options "
                                  "(spacing: 11 here, 12 in the log)"));
        }
        free(log);
    }
    CHECK(!tl_exists(tl_path("pe")));
}

/* ---- sessions without contours, on a meshed model, and finding contours --------------------- */

static void test_session_cases(thx_ctx *ctx)
{
    /* a model built straight from a label map (thorax surfaces LABELS --label ...; issue 25): its
       provenance names the image and no contour file; the note says so (not "built before thorax
       recorded it") */
    {
        thx_model *mi = NULL;
        thx_contours *ci = NULL;
        thx_edit_recipe ri;
        char shai[65];
        CHECK_OK(ctx, build_like_cli(ctx, tl_path("small.txt"), tl_path("qi"), &mi, &ci, &ri, shai));
        thx_contours_destroy(&ci);
        cJSON *p = mi ? cJSON_Parse(mi->provenance_json) : NULL;
        if (p) {
            cJSON_DeleteItemFromObject(p, "input_sha256");
            cJSON_DeleteItemFromObject(p, "input_from_model");
            cJSON_ReplaceItemInObject(p, "input", cJSON_CreateString("labels.nii.gz"));
            cJSON *im = cJSON_AddObjectToObject(p, "image");
            cJSON_AddStringToObject(im, "file", "labels.nii.gz");
            free(mi->provenance_json);
            mi->provenance_json = cJSON_PrintUnformatted(p);
            cJSON_Delete(p);
            CHECK_OK(ctx, thx_model_write(ctx, mi, tl_path("qi")));
        }
        thx_model_destroy(&mi);
        thx_edit_session *si = NULL;
        CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("qi"), NULL, NULL, &si));
        CHECK(si && thx_edit_session_contours(si) == NULL &&
              strstr(thx_edit_session_note(si), "built straight from the label map labels.nii.gz, without a contour "
                                                "file: mesh edits only") != NULL);
        thx_edit_session_destroy(&si);
    }
    /* a model without provenance: mesh edits only, and a layer edit says why it cannot */
    thx_model *m = NULL;
    thx_contours *c = NULL;
    thx_edit_recipe r;
    char sha[65];
    CHECK_OK(ctx, build_like_cli(ctx, tl_path("small.txt"), tl_path("q0"), &m, &c, &r, sha));
    thx_contours_destroy(&c);
    free(m->provenance_json);
    m->provenance_json = NULL;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("q0")));
    thx_model_destroy(&m);
    thx_edit_session *s = NULL;
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("q0"), NULL, NULL, &s));
    if (s) {
        CHECK(thx_edit_session_contours(s) == NULL && strstr(thx_edit_session_note(s), "mesh edits only") != NULL);
        thx_edit e = thx_edit_layer_move("tube", thx_edit_layer_z(20), 1, 0);
        CHECK(thx_edit_apply(ctx, s, &e, NULL) == THX_EINPUT && tl_msg_has(ctx, "no contours"));
        e = thx_edit_tri_flip("tube", 0);
        CHECK_OK(ctx, thx_edit_apply(ctx, s, &e, NULL));
        char *text = NULL;
        CHECK_OK(ctx, thx_edit_session_log_text(ctx, s, &text));
        CHECK(text && strcmp(text, "thorax-edits 1\n# edits of the model's surfaces (thorax/edit/edit.h); replay: "
                                   "thorax surfaces CONTOURS --edits THIS -o MODEL\ntri_flip tube 1\nend\n") == 0);
        free(text);
        /* explicit contours without a recipe in the model: refused */
        thx_edit_session *s2 = NULL;
        CHECK(thx_edit_session_open(ctx, tl_path("q0"), tl_path("small.txt"), NULL, &s2) == THX_EINPUT &&
              tl_msg_has(ctx, "no provenance"));
        thx_edit_session_destroy(&s);
    }

    /* a model whose contours changed since: the session opens without them and says so; given
       explicitly, the changed file is refused */
    write_small_contours(tl_path("small2.txt"));
    CHECK_OK(ctx, build_like_cli(ctx, tl_path("small2.txt"), tl_path("q1"), &m, &c, &r, sha));
    thx_contours_destroy(&c);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("q1")));
    thx_model_destroy(&m);
    char *txt = tl_slurp(ctx, tl_path("small2.txt"), NULL);
    if (txt) {
        strstr(txt, "layer 40")[7] = '1'; /* layer 41 */
        tl_write_text(tl_path("small2.txt"), txt);
        free(txt);
    }
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("q1"), NULL, NULL, &s));
    if (s) {
        CHECK(thx_edit_session_contours(s) == NULL && strstr(thx_edit_session_note(s), "was not found unchanged"));
        thx_edit_session_destroy(&s);
    }
    CHECK(thx_edit_session_open(ctx, tl_path("q1"), tl_path("small2.txt"), NULL, &s) == THX_EINPUT &&
          tl_msg_has(ctx, "was built from contours of SHA-256"));
    /* the right file given explicitly (another path, the same bytes) */
    CHECK_OK(ctx, thx_edit_session_open(ctx, tl_path("q1"), tl_path("small.txt"), NULL, &s));
    CHECK(s && thx_edit_session_contours(s) != NULL);
    thx_edit_session_destroy(&s);

    /* a model with a volume mesh: refused, unless the volume is dropped */
    CHECK_OK(ctx, build_like_cli(ctx, tl_path("small.txt"), tl_path("q2"), &m, &c, &r, sha));
    m->volume = calloc(1, sizeof *m->volume);
    CHECK(thx_edit_session_create(ctx, &m, &c, &r, "small.txt", sha, NULL, &s) == THX_EINPUT &&
          tl_msg_has(ctx, "volume mesh") && m == NULL && c == NULL && s == NULL);
    CHECK_OK(ctx, build_like_cli(ctx, tl_path("small.txt"), tl_path("q2"), &m, &c, &r, sha));
    m->volume = calloc(1, sizeof *m->volume);
    thx_edit_session_opts o;
    thx_edit_session_opts_default(&o);
    o.drop_volume = 1;
    CHECK_OK(ctx, thx_edit_session_create(ctx, &m, &c, &r, "small.txt", sha, &o, &s));
    CHECK(s && thx_edit_session_model(s)->volume == NULL);
    thx_edit_session_destroy(&s);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_edit")) return 1;
    test_mesh_edits(ctx);
    test_layer_edits(ctx);
    test_phantom(ctx);
    test_session_cases(ctx);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_edit");
}
