/*
 * Tests of the volume mesh files of a model directory (volume.pts,
 * volume.tet, NAME.vmap, the "volume" and "regions" parts of model.json) and
 * of the volume exports .vtu and Gmsh .msh (src/io/model/volume_io.c).
 *
 * The test volume: a 10 mm cube with its 8 corners, its 6 face centres, the
 * 6 nodes of an octahedron (radius 2 about the centre) and random interior
 * points, tetrahedralized by thx_delaunay3d and turned right-handed. Two
 * surfaces whose nodes are volume nodes: "box", the hull (24 triangles), and
 * "heart", the octahedron. Regions by the tetrahedron's centroid: inside the
 * octahedron "heart", else x < 5 "mean_thorax" (isotropic), else "muscle"
 * (a tensor with off-diagonal entries); a fourth region "blood" is unused.
 *
 * Usage: test_volume_io                 runs the tests
 *        test_volume_io --write-model DIR [N]
 *                                       writes the test model with N random
 *                                       points (default 300) to DIR and exits
 *                                       (tests/e2e_volume_export.sh uses it)
 */
#define _XOPEN_SOURCE 700
#ifdef _OPENMP
#include <omp.h>
#endif
#include <dirent.h>
#include <ftw.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "testlib.h"
#include "thorax/mesh/delaunay.h"
#include "thorax/core/fileio.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/export_data.h"
#include "thorax/model/volume.h"
static thx_ctx *ctx;

/* ------------------------------------------------------------- helpers */

static int same_file(const char *a, const char *b)
{
    size_t l1 = 0, l2 = 0;
    char *t1 = tl_slurp(ctx, a, &l1), *t2 = tl_slurp(ctx, b, &l2);
    int same = t1 && t2 && l1 == l2 && memcmp(t1, t2, l1) == 0;
    free(t1);
    free(t2);
    return same;
}

/* Replaces line `line` (1-based) of a text file by `text` (no newline). */
static void replace_line(const char *path, int line, const char *text)
{
    char *t = tl_slurp(ctx, path, NULL);
    if (!t) exit(1);
    FILE *f = fopen(path, "w");
    if (!f) exit(1);
    int k = 1;
    for (char *p = t; *p;) {
        char *e = strchr(p, '\n');
        size_t n = e ? (size_t)(e - p) : strlen(p);
        if (k == line) fputs(text, f);
        else fwrite(p, 1, n, f);
        if (e) fputc('\n', f);
        p += n + (e ? 1 : 0);
        k++;
    }
    fclose(f);
    free(t);
}

/* Deletes the last line of a text file. */
static void drop_last_line(const char *path)
{
    size_t n = 0;
    char *t = tl_slurp(ctx, path, &n);
    if (!t || n < 2) exit(1);
    n--; /* the final newline */
    while (n > 0 && t[n - 1] != '\n') n--;
    FILE *f = fopen(path, "w");
    fwrite(t, 1, n, f);
    fclose(f);
    free(t);
}

static uint64_t rng_state = 88172645463325252ull;
static double rnd(void) /* xorshift64, uniform in [0, 1) */
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* ------------------------------------------------------- the test model */

static const int32_t oct_tri[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static thx_region region(const char *name, double s, const char *source)
{
    thx_region r;
    memset(&r, 0, sizeof r);
    snprintf(r.name, sizeof r.name, "%s", name);
    r.sigma[0] = r.sigma[4] = r.sigma[8] = s;
    snprintf(r.source, sizeof r.source, "%s", source);
    return r;
}

/* The model described at the top, with n_random interior points. */
static thx_model *make_model(size_t n_random)
{
    rng_state = 88172645463325252ull;
    size_t n = 8 + 6 + 6 + n_random;
    double *xyz = malloc(3 * n * sizeof *xyz);
    size_t k = 0;
    for (int i = 0; i < 8; i++) { /* corners */
        xyz[3 * k] = (i & 1) ? 10 : 0, xyz[3 * k + 1] = (i & 2) ? 10 : 0, xyz[3 * k + 2] = (i & 4) ? 10 : 0;
        k++;
    }
    for (int a = 0; a < 3; a++) /* face centres */
        for (int side = 0; side < 2; side++) {
            xyz[3 * k] = xyz[3 * k + 1] = xyz[3 * k + 2] = 5;
            xyz[3 * k + (size_t)a] = side ? 10 : 0;
            k++;
        }
    const double oct[6][3] = {{7, 5, 5}, {3, 5, 5}, {5, 7, 5}, {5, 3, 5}, {5, 5, 7}, {5, 5, 3}};
    for (int i = 0; i < 6; i++, k++)
        for (int c = 0; c < 3; c++) xyz[3 * k + (size_t)c] = oct[i][c];
    for (size_t i = 0; i < n_random; i++, k++) /* a 1e-3 grid keeps them exact in "%.6f" */
        for (int c = 0; c < 3; c++) xyz[3 * k + (size_t)c] = 0.5 + floor(rnd() * 9000.0) / 1000.0;

    int32_t *tets = NULL, *nbrs = NULL;
    size_t nt = 0;
    if (thx_delaunay3d(ctx, xyz, n, &tets, &nbrs, &nt, NULL) != THX_OK) {
        fprintf(stderr, "thx_delaunay3d: %s\n", thx_ctx_message(ctx));
        exit(1);
    }
    thx_model *m = NULL;
    if (thx_model_create(ctx, &m) != THX_OK) exit(1);

    /* Hull faces (outward in delaunay.h's convention) make the surface "box";
     * its nodes are the hull vertices in increasing volume order. */
    int32_t *snode = malloc(n * sizeof *snode);
    for (size_t i = 0; i < n; i++) snode[i] = -1;
    size_t n_faces = 0;
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++)
            if (nbrs[4 * t + (size_t)f] < 0) {
                n_faces++;
                for (int j = 0; j < 3; j++) snode[tets[4 * t + (size_t)thx_delaunay_face[f][j]]] = 0;
            }
    thx_surface *box = NULL;
    if (thx_surface_create(ctx, "box", THX_ROLE_OUTER, &box) != THX_OK) exit(1);
    int32_t *box_map = malloc(n * sizeof *box_map);
    for (size_t i = 0; i < n; i++)
        if (snode[i] == 0) {
            snode[i] = (int32_t)box->n_nodes;
            box_map[box->n_nodes++] = (int32_t)i;
        }
    box->xyz = malloc(3 * box->n_nodes * sizeof *box->xyz);
    for (size_t i = 0; i < box->n_nodes; i++) memcpy(box->xyz + 3 * i, xyz + 3 * (size_t)box_map[i], 3 * sizeof *xyz);
    box->tri = malloc(3 * n_faces * sizeof *box->tri);
    for (size_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++)
            if (nbrs[4 * t + (size_t)f] < 0) {
                for (int j = 0; j < 3; j++)
                    box->tri[3 * box->n_tris + (size_t)j] = snode[tets[4 * t + (size_t)thx_delaunay_face[f][j]]];
                box->n_tris++;
            }
    thx_surface *heart = NULL;
    if (thx_surface_create(ctx, "heart", THX_ROLE_HEART, &heart) != THX_OK) exit(1);
    heart->n_nodes = 6;
    heart->xyz = malloc(18 * sizeof *heart->xyz);
    memcpy(heart->xyz, xyz + 3 * 14, 18 * sizeof *xyz);
    heart->n_tris = 8;
    heart->tri = malloc(sizeof oct_tri);
    memcpy(heart->tri, oct_tri, sizeof oct_tri);
    size_t box_nodes = box->n_nodes;
    if (thx_model_add_surface(ctx, m, &box) || thx_model_add_surface(ctx, m, &heart)) exit(1);

    thx_volume *v = NULL;
    if (thx_volume_create(ctx, &v) != THX_OK) exit(1);
    v->n_nodes = n;
    v->xyz = xyz;
    v->n_tets = nt;
    v->tet = tets;
    v->region = malloc(nt * sizeof *v->region);
    for (size_t t = 0; t < nt; t++) {
        int32_t *q = tets + 4 * t;
        int32_t sw = q[2]; /* delaunay.h's tetrahedra are left-handed: swap two vertices */
        q[2] = q[3];
        q[3] = sw;
        double c[3] = {0, 0, 0};
        for (int a = 0; a < 4; a++)
            for (int j = 0; j < 3; j++) c[j] += 0.25 * xyz[3 * (size_t)q[a] + (size_t)j];
        double l1 = fabs(c[0] - 5) + fabs(c[1] - 5) + fabs(c[2] - 5);
        v->region[t] = l1 < 2 ? 2 : c[0] < 5 ? 0 : 1;
    }
    v->n_regions = 4;
    v->regions = malloc(4 * sizeof *v->regions);
    v->regions[0] = region("mean_thorax", 0.2, "test value");
    v->regions[1] = region("muscle", 0, "test value: 0.04 across, 0.3 along an axis tilted 30 degrees from z");
    /* diag(0.04, 0.04, 0.3) rotated by 30 degrees about x, made exactly symmetric. */
    double cs = cos(3.14159265358979323846 / 6), sn = sin(3.14159265358979323846 / 6), lt = 0.04, ll = 0.3;
    double *S = v->regions[1].sigma;
    S[0] = lt;
    S[4] = lt * cs * cs + ll * sn * sn;
    S[8] = lt * sn * sn + ll * cs * cs;
    S[5] = S[7] = (lt - ll) * cs * sn;
    S[1] = S[2] = S[3] = S[6] = 0;
    v->regions[1].anisotropic = 1;
    v->regions[2] = region("heart", 0.4, "");
    v->regions[3] = region("blood", 0.7, "unused region, \"quoted\" source");

    v->n_surfaces = 2;
    v->surf_n_nodes = malloc(2 * sizeof *v->surf_n_nodes);
    v->surf_n_nodes[0] = box_nodes;
    v->surf_n_nodes[1] = 6;
    v->surf_node = malloc(2 * sizeof *v->surf_node);
    v->surf_node[0] = realloc(box_map, box_nodes * sizeof *box_map);
    v->surf_node[1] = malloc(6 * sizeof **v->surf_node);
    v->node_surf = malloc(n * sizeof *v->node_surf);
    v->node_snode = malloc(n * sizeof *v->node_snode);
    for (size_t i = 0; i < n; i++) v->node_surf[i] = v->node_snode[i] = -1;
    for (int i = 0; i < 6; i++) v->surf_node[1][i] = 14 + i;
    for (size_t s = 0; s < 2; s++)
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            v->node_surf[v->surf_node[s][i]] = (int32_t)s;
            v->node_snode[v->surf_node[s][i]] = (int32_t)i;
        }
    m->volume = v;
    m->provenance_json = strdup("{\"command\":\"test_volume_io\"}");
    free(snode);
    free(nbrs);
    return m;
}

/* ------------------------------------------------------------- tests */

static void test_model_shape(void)
{
    thx_model *m = make_model(60);
    const thx_volume *v = m->volume;
    CHECK(m->n_surfaces == 2 && m->surf[0]->n_nodes == 14 && m->surf[0]->n_tris == 24);
    CHECK(thx_surface_volume(m->surf[0]) > 999.999 && thx_surface_volume(m->surf[0]) < 1000.001);
    double total = 0;
    int right_handed = 1;
    size_t per[4] = {0, 0, 0, 0};
    for (size_t t = 0; t < v->n_tets; t++) {
        double vol = thx_volume_tet_volume(v, t);
        right_handed &= vol > 0;
        total += vol;
        per[v->region[t]]++;
    }
    CHECK(right_handed);
    CHECK_NEAR(total, 1000, 1e-9);
    CHECK(per[0] > 0 && per[1] > 0 && per[2] > 0 && per[3] == 0);
    thx_model_destroy(&m);
}

/* The scratch model "bad" is edited by hand between cases; thorax rightly refuses to replace a model
 * whose files its manifest no longer names (thorax/core/fileio.h), so each case starts from a new one. */
static int rm_entry(const char *p, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb; (void)flag; (void)ftw;
    return remove(p);
}

static thx_status write_fresh(thx_ctx *c, const thx_model *m, const char *dir)
{
    nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    return thx_model_write(c, m, dir);
}

static void compare_models(const thx_model *a, const thx_model *b)
{
    CHECK(b->n_surfaces == a->n_surfaces);
    const thx_volume *u = a->volume, *w = b->volume;
    CHECK(w != NULL);
    if (!w || b->n_surfaces != a->n_surfaces) return;
    CHECK(w->n_nodes == u->n_nodes && w->n_tets == u->n_tets && w->n_regions == u->n_regions);
    if (w->n_nodes != u->n_nodes || w->n_tets != u->n_tets || w->n_regions != u->n_regions) return;
    double worst = 0;
    for (size_t i = 0; i < 3 * u->n_nodes; i++) worst = fmax(worst, fabs(u->xyz[i] - w->xyz[i]));
    CHECK(worst <= 5.0000001e-7);
    CHECK(memcmp(u->tet, w->tet, 4 * u->n_tets * sizeof *u->tet) == 0);
    CHECK(memcmp(u->region, w->region, u->n_tets * sizeof *u->region) == 0);
    for (size_t k = 0; k < u->n_regions; k++) {
        CHECK(strcmp(u->regions[k].name, w->regions[k].name) == 0);
        CHECK(strcmp(u->regions[k].source, w->regions[k].source) == 0);
        CHECK(u->regions[k].anisotropic == w->regions[k].anisotropic);
        CHECK(memcmp(u->regions[k].sigma, w->regions[k].sigma, sizeof u->regions[k].sigma) == 0); /* bit-exact */
    }
    CHECK(w->n_surfaces == u->n_surfaces);
    for (size_t s = 0; s < u->n_surfaces && s < w->n_surfaces; s++) {
        CHECK(w->surf_n_nodes[s] == u->surf_n_nodes[s]);
        CHECK(w->surf_n_nodes[s] == u->surf_n_nodes[s] &&
              memcmp(u->surf_node[s], w->surf_node[s], u->surf_n_nodes[s] * sizeof **u->surf_node) == 0);
    }
    CHECK(w->node_surf && w->node_snode);
    if (w->node_surf && w->node_snode) {
        CHECK(memcmp(u->node_surf, w->node_surf, u->n_nodes * sizeof *u->node_surf) == 0);
        CHECK(memcmp(u->node_snode, w->node_snode, u->n_nodes * sizeof *u->node_snode) == 0);
    }
    /* Every surface node is its volume node, exactly, after reading. */
    int same = 1;
    for (size_t s = 0; s < b->n_surfaces; s++)
        for (size_t i = 0; i < b->surf[s]->n_nodes; i++)
            same &= memcmp(b->surf[s]->xyz + 3 * i, w->xyz + 3 * (size_t)w->surf_node[s][i], 3 * sizeof(double)) == 0;
    CHECK(same);
}

static void test_round_trip(void)
{
    thx_model *m = make_model(200);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("rt")));
    const char *files[] = {"model.json", "box.pts", "box.fac", "box.vmap", "heart.pts",
                           "heart.fac",  "heart.vmap", "volume.pts", "volume.tet"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        char n1[64];
        snprintf(n1, sizeof n1, "rt/%s", files[k]);
        CHECK(tl_exists(tl_path(n1)));
    }
    CHECK(!tl_leftover_tmp("rt"));

    /* The files are what docs/formats.md says. */
    char *tet = tl_slurp(ctx, tl_path("rt/volume.tet"), NULL);
    if (tet) {
        const int32_t *q = m->volume->tet;
        char first[128];
        snprintf(first, sizeof first, "%d %d %d %d %d\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1, m->volume->region[0] + 1);
        CHECK(strncmp(tet, first, strlen(first)) == 0);
        size_t lines = 0;
        for (char *p = tet; *p; p++) lines += *p == '\n';
        CHECK(lines == m->volume->n_tets);
    }
    free(tet);
    char *pts = tl_slurp(ctx, tl_path("rt/volume.pts"), NULL);
    const char *pts_head = "0 0 0\n10 0 0\n"; /* "%.17g": exact */
    CHECK(pts && strncmp(pts, pts_head, strlen(pts_head)) == 0);
    free(pts);
    char *hv = tl_slurp(ctx, tl_path("rt/heart.vmap"), NULL);
    CHECK(hv && strcmp(hv, "15\n16\n17\n18\n19\n20\n") == 0);
    free(hv);
    char *bv = tl_slurp(ctx, tl_path("rt/box.vmap"), NULL);
    CHECK(bv && strncmp(bv, "1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n11\n12\n13\n14\n", 33) == 0 && strlen(bv) == 33);
    free(bv);

    /* model.json: "volume", "regions", a "vmap" per surface. */
    char *json = tl_slurp(ctx, tl_path("rt/model.json"), NULL);
    cJSON *root = json ? cJSON_Parse(json) : NULL;
    const cJSON *vo = cJSON_GetObjectItemCaseSensitive(root, "volume");
    CHECK(cJSON_IsObject(vo));
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(vo, "pts")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(vo, "pts")->valuestring, "volume.pts") == 0);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(vo, "tet")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(vo, "tet")->valuestring, "volume.tet") == 0);
    CHECK(cJSON_GetObjectItemCaseSensitive(vo, "n_nodes") &&
          cJSON_GetObjectItemCaseSensitive(vo, "n_nodes")->valuedouble == (double)m->volume->n_nodes);
    CHECK(cJSON_GetObjectItemCaseSensitive(vo, "n_tets") &&
          cJSON_GetObjectItemCaseSensitive(vo, "n_tets")->valuedouble == (double)m->volume->n_tets);
    CHECK(cJSON_GetObjectItemCaseSensitive(vo, "n_regions") &&
          cJSON_GetObjectItemCaseSensitive(vo, "n_regions")->valuedouble == 4);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(vo, "units")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(vo, "units")->valuestring, "mm") == 0);
    CHECK(cJSON_GetObjectItemCaseSensitive(vo, "index_base") &&
          cJSON_GetObjectItemCaseSensitive(vo, "index_base")->valuedouble == 1);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(vo, "orientation")) &&
          strstr(cJSON_GetObjectItemCaseSensitive(vo, "orientation")->valuestring, "right-handed"));
    const cJSON *regs = cJSON_GetObjectItemCaseSensitive(root, "regions");
    CHECK(cJSON_GetArraySize(regs) == 4);
    const cJSON *r0 = cJSON_GetArrayItem(regs, 0), *r1 = cJSON_GetArrayItem(regs, 1);
    CHECK(cJSON_GetObjectItemCaseSensitive(r0, "id") && cJSON_GetObjectItemCaseSensitive(r0, "id")->valuedouble == 1);
    CHECK(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(r0, "sigma")) &&
          cJSON_GetObjectItemCaseSensitive(r0, "sigma")->valuedouble == 0.2);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(r0, "units")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(r0, "units")->valuestring, "S/m") == 0);
    const cJSON *t1 = cJSON_GetObjectItemCaseSensitive(r1, "sigma");
    CHECK(cJSON_IsArray(t1) && cJSON_GetArraySize(t1) == 3 && cJSON_GetArraySize(cJSON_GetArrayItem(t1, 2)) == 3);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(r1, "name")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(r1, "name")->valuestring, "muscle") == 0);
    const cJSON *s1 = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(root, "surfaces"), 1);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(s1, "vmap")) &&
          strcmp(cJSON_GetObjectItemCaseSensitive(s1, "vmap")->valuestring, "heart.vmap") == 0);
    cJSON_Delete(root);
    free(json);

    /* Read back: everything equal; write again: byte-identical files. */
    thx_model *r = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("rt"), &r));
    if (r) {
        compare_models(m, r);
        CHECK_OK(ctx, thx_model_write(ctx, r, tl_path("rt2")));
        for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
            char n1[64], n2[64];
            snprintf(n1, sizeof n1, "rt/%s", files[k]);
            snprintf(n2, sizeof n2, "rt2/%s", files[k]);
            CHECK(same_file(tl_path(n1), tl_path(n2)));
        }
    }
    thx_model_destroy(&r);

    /* Damaged volume files are refused, never read in part: a NUL byte in volume.pts (the line
       parser would stop there), a Steiner record the manifest does not announce, a cut record. */
    {
        size_t len = 0;
        char *vp = tl_slurp(ctx, tl_path("rt/volume.pts"), &len);
        CHECK(vp != NULL && len > 10);
        if (vp) {
            vp[len / 2] = '\0';
            tl_write_bytes(tl_path("rt2/volume.pts"), vp, len);
            CHECK(thx_model_read(ctx, tl_path("rt2"), &r) == THX_EINPUT && tl_msg_has(ctx, "NUL byte"));
            CHECK(r == NULL);
            tl_write_bytes(tl_path("rt2/volume.pts"), vp, len / 2); /* back to a whole file for what follows */
            free(vp);
        }
        vp = tl_slurp(ctx, tl_path("rt/volume.pts"), &len);
        if (vp) { tl_write_bytes(tl_path("rt2/volume.pts"), vp, len); free(vp); }
        tl_write_text(tl_path("rt2/volume.steiner"), "1 1 1 0.5 0.5 0\n");
        CHECK(thx_model_read(ctx, tl_path("rt2"), &r) == THX_EINPUT && tl_msg_has(ctx, "more records than the 0"));
        CHECK(r == NULL);
        tl_write_text(tl_path("rt2/volume.steiner"), "1 1 1 0.5\n");
        CHECK(thx_model_read(ctx, tl_path("rt2"), &r) == THX_EINPUT && tl_msg_has(ctx, "volume.steiner:1: expected 6 fields"));
        CHECK(r == NULL);
    }

    /* A model without a volume has none of the volume files or keys. */
    thx_volume_destroy(&m->volume);
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("novol")));
    CHECK(!tl_exists(tl_path("novol/volume.pts")) && !tl_exists(tl_path("novol/box.vmap")));
    json = tl_slurp(ctx, tl_path("novol/model.json"), NULL);
    CHECK(json && !strstr(json, "\"volume\"") && !strstr(json, "\"regions\"") && !strstr(json, "vmap"));
    free(json);
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("novol"), &r));
    CHECK(r && r->volume == NULL);
    thx_model_destroy(&r);
    thx_model_destroy(&m);

    /* A volume in a model without surfaces (no node tables). */
    m = make_model(10);
    for (size_t i = 0; i < m->n_surfaces; i++) thx_surface_destroy(&m->surf[i]);
    m->n_surfaces = 0;
    thx_volume *v = m->volume;
    for (size_t s = 0; s < v->n_surfaces; s++) free(v->surf_node[s]);
    v->n_surfaces = 0;
    for (size_t i = 0; i < v->n_nodes; i++) v->node_surf[i] = v->node_snode[i] = -1;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("nosurf")));
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("nosurf"), &r));
    if (r) compare_models(m, r);
    thx_model_destroy(&r);
    thx_model_destroy(&m);
}

/* In-memory faults: each refused by thx_model_write before anything is
 * written, with a message naming the object. */
static void test_failed_write(void)
{
    thx_model *m = make_model(40);
    thx_volume *v = m->volume;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("keep")));
    char *before = tl_slurp(ctx, tl_path("keep/volume.tet"), NULL);

    struct fault { const char *what, *want; } faults[] = {
        {"tet index", "tetrahedron 3: node index"},
        {"negative index", "tetrahedron 1: node index -1"},
        {"repeated node", "tetrahedron 2: node"},
        {"region", "tetrahedron 5: region index 4"},
        {"non-SPD", "region 2 (\"muscle\"): conductivity tensor not positive definite"},
        {"asymmetric", "region 2 (\"muscle\"): conductivity tensor not symmetric"},
        {"isotropic not identity", "region 1 (\"mean_thorax\"): marked isotropic"},
        {"zero conductivity", "region 3 (\"heart\"): conductivity 0 S/m is not positive"},
        {"region name", "region 4: name"},
        {"duplicate region", "regions 1 and 4 are both named \"mean_thorax\""},
        {"vmap coordinates", "surface \"heart\" node 2 is volume node 14 but the coordinates differ"},
        {"vmap twice", "are both volume node 15"},
        {"vmap range", "surface \"box\" node 3: volume node index"},
        {"reverse table", "volume node 15: reverse node table"},
        {"table count", "node tables for 1 surfaces but the model has 2"},
        {"surface named volume", "surface \"volume\": name is reserved"},
        {"nan", "volume node 7 has a non-finite coordinate"},
    };
    for (size_t k = 0; k < sizeof faults / sizeof faults[0]; k++) {
        const char *w = faults[k].what;
        double save[9];
        memcpy(save, v->regions[1].sigma, sizeof save);
        thx_region save_r0 = v->regions[0], save_r2 = v->regions[2], save_r3 = v->regions[3];
        int32_t save_t[20];
        memcpy(save_t, v->tet, sizeof save_t);
        int32_t save_reg = v->region[4], save_h1 = v->surf_node[1][1], save_h0 = v->surf_node[1][0];
        int32_t save_b2 = v->surf_node[0][2], save_ns = v->node_surf[14];
        double save_x = v->xyz[18], save_h[3];
        memcpy(save_h, m->surf[1]->xyz + 3, sizeof save_h);
        if (!strcmp(w, "tet index")) v->tet[4 * 2 + 1] = (int32_t)v->n_nodes;
        else if (!strcmp(w, "negative index")) v->tet[3] = -1;
        else if (!strcmp(w, "repeated node")) v->tet[4 + 3] = v->tet[4];
        else if (!strcmp(w, "region")) v->region[4] = 4;
        else if (!strcmp(w, "non-SPD")) v->regions[1].sigma[0] = -0.01;
        else if (!strcmp(w, "asymmetric")) v->regions[1].sigma[5] += 1e-6;
        else if (!strcmp(w, "isotropic not identity")) v->regions[0].sigma[8] = 0.3;
        else if (!strcmp(w, "zero conductivity")) v->regions[2].sigma[0] = v->regions[2].sigma[4] = v->regions[2].sigma[8] = 0;
        else if (!strcmp(w, "region name")) snprintf(v->regions[3].name, sizeof v->regions[3].name, "no spaces");
        else if (!strcmp(w, "duplicate region")) snprintf(v->regions[3].name, sizeof v->regions[3].name, "mean_thorax");
        else if (!strcmp(w, "vmap coordinates")) v->surf_node[1][1] = 13;
        else if (!strcmp(w, "vmap twice")) { /* heart node 2 moved onto node 1, and mapped to its volume node */
            memcpy(m->surf[1]->xyz + 3, m->surf[1]->xyz, sizeof save_h);
            v->surf_node[1][1] = 14;
        }
        else if (!strcmp(w, "vmap range")) v->surf_node[0][2] = (int32_t)v->n_nodes;
        else if (!strcmp(w, "reverse table")) v->node_surf[14] = 0;
        else if (!strcmp(w, "table count")) v->n_surfaces = 1;
        else if (!strcmp(w, "surface named volume")) snprintf(m->surf[1]->name, sizeof m->surf[1]->name, "volume");
        else if (!strcmp(w, "nan")) v->xyz[18] = NAN;
        thx_status st = write_fresh(ctx, m, tl_path("bad"));
        CHECK(st == THX_EINPUT);
        if (st != THX_EINPUT || !tl_msg_has(ctx, faults[k].want)) fprintf(stderr, "  (fault \"%s\")\n", w);
        CHECK(!tl_exists(tl_path("bad")) && !tl_leftover_tmp("bad"));
        /* An existing model is left as it was by a failed write. */
        CHECK(thx_model_write(ctx, m, tl_path("keep")) == THX_EINPUT);
        memcpy(v->regions[1].sigma, save, sizeof save);
        v->regions[0] = save_r0, v->regions[2] = save_r2, v->regions[3] = save_r3;
        memcpy(v->tet, save_t, sizeof save_t);
        v->region[4] = save_reg, v->surf_node[1][1] = save_h1, v->surf_node[1][0] = save_h0;
        v->surf_node[0][2] = save_b2, v->node_surf[14] = save_ns, v->n_surfaces = 2, v->xyz[18] = save_x;
        snprintf(m->surf[1]->name, sizeof m->surf[1]->name, "heart");
        memcpy(m->surf[1]->xyz + 3, save_h, sizeof save_h);
    }
    char *after = tl_slurp(ctx, tl_path("keep/volume.tet"), NULL);
    CHECK(before && after && strcmp(before, after) == 0);
    CHECK(!tl_leftover_tmp("keep"));
    free(before);
    free(after);
    /* All faults undone: the model writes again. */
    CHECK_OK(ctx, write_fresh(ctx, m, tl_path("bad")));
    /* A missing parent directory is an i/o error; nothing is created. */
    CHECK(thx_model_write(ctx, m, tl_path("no/such/dir")) == THX_EIO && tl_msg_has(ctx, "no/such/dir"));
    CHECK(!tl_exists(tl_path("no")));
    thx_model_destroy(&m);
}

/* Edits model.json of dir with fn, rewriting it. */
static void edit_json(const char *dir, void (*fn)(cJSON *root))
{
    char path[2200];
    snprintf(path, sizeof path, "%s/model.json", dir);
    char *t = tl_slurp(ctx, path, NULL);
    cJSON *root = t ? cJSON_Parse(t) : NULL;
    if (!root) exit(1);
    fn(root);
    char *out = cJSON_Print(root);
    tl_write_text(path, out);
    free(out);
    free(t);
    cJSON_Delete(root);
}

static cJSON *region_item(cJSON *root, int k) { return cJSON_GetArrayItem(cJSON_GetObjectItem(root, "regions"), k); }
static void set_tensor(cJSON *root, const double *a)
{
    cJSON *rows = cJSON_CreateArray();
    for (int i = 0; i < 3; i++) cJSON_AddItemToArray(rows, cJSON_CreateDoubleArray(a + 3 * i, 3));
    cJSON_ReplaceItemInObject(region_item(root, 1), "sigma", rows);
}
static void j_not_spd(cJSON *root)
{
    const double a[9] = {0.1, 0.2, 0, 0.2, 0.1, 0, 0, 0, 0.3}; /* eigenvalues 0.3, -0.1, 0.3 */
    set_tensor(root, a);
}
static void j_asym(cJSON *root)
{
    const double a[9] = {0.1, 0.01, 0, 0.02, 0.1, 0, 0, 0, 0.3};
    set_tensor(root, a);
}
static void j_bad_sigma_shape(cJSON *root)
{
    cJSON_ReplaceItemInObject(region_item(root, 1), "sigma", cJSON_CreateString("0.3"));
}
static void j_negative(cJSON *root)
{
    cJSON_ReplaceItemInObject(region_item(root, 0), "sigma", cJSON_CreateNumber(-0.2));
}
static void j_bad_id(cJSON *root) { cJSON_ReplaceItemInObject(region_item(root, 2), "id", cJSON_CreateNumber(7)); }
static void j_bad_units(cJSON *root) { cJSON_ReplaceItemInObject(region_item(root, 0), "units", cJSON_CreateString("mS/cm")); }
static void j_no_regions(cJSON *root) { cJSON_DeleteItemFromObject(root, "regions"); }
static void j_dup_region(cJSON *root)
{
    cJSON_ReplaceItemInObject(region_item(root, 3), "name", cJSON_CreateString("heart"));
}
static void j_no_vmap(cJSON *root)
{
    cJSON_DeleteItemFromObject(cJSON_GetArrayItem(cJSON_GetObjectItem(root, "surfaces"), 1), "vmap");
}
static void j_no_volume(cJSON *root) { cJSON_DeleteItemFromObject(root, "volume"); }
static void j_base0(cJSON *root)
{
    cJSON_ReplaceItemInObject(cJSON_GetObjectItem(root, "volume"), "index_base", cJSON_CreateNumber(0));
}
static void j_count(cJSON *root)
{
    cJSON *vo = cJSON_GetObjectItem(root, "volume");
    cJSON_ReplaceItemInObject(vo, "n_tets", cJSON_CreateNumber(cJSON_GetObjectItem(vo, "n_tets")->valuedouble + 1));
}
static void j_path(cJSON *root) { cJSON_ReplaceItemInObject(cJSON_GetObjectItem(root, "volume"), "tet", cJSON_CreateString("../x.tet")); }

static int warnings;
static void count_warning(void *user, thx_log_level level, const char *message)
{
    (void)user;
    if (level == THX_LOG_WARN && strstr(message, "ignored: the model has no \"volume\"")) warnings++;
}

/* On-disk faults: thx_model_read refuses each, naming the file (and line). */
static void test_bad_files(void)
{
    thx_model *m = make_model(40);
    const thx_volume *v = m->volume;
    char line[256];
    struct {
        const char *file;
        int line;          /* 0: edit model.json with fn; -1: drop the last line */
        const char *text;
        void (*fn)(cJSON *);
        const char *want1, *want2;
        const char *file2; /* optional second edit: line 1 of file2 becomes text2 */
        int line2;
        const char *text2;
    } cases[] = {
        {"volume.tet", 3, "1 2 3 99999 1", NULL, "volume.tet:3:", "node number 99999 out of range 1..", NULL, 0, NULL},
        {"volume.tet", 3, "0 2 3 4 1", NULL, "volume.tet:3:", "node number 0 out of range", NULL, 0, NULL},
        {"volume.tet", 5, "1 2 3 4 9", NULL, "volume.tet:5:", "region 9 out of range 1..4", NULL, 0, NULL},
        {"volume.tet", 5, "1 2 3 4 0", NULL, "volume.tet:5:", "region 0 out of range", NULL, 0, NULL},
        {"volume.tet", 2, "1 2 3 2 1", NULL, "volume.tet:2:", "node 2 appears twice", NULL, 0, NULL},
        {"volume.tet", 4, "1 2 3 4", NULL, "volume.tet:4:", "expected 5 numbers", NULL, 0, NULL},
        {"volume.tet", 4, "1 2 3 4 1 1", NULL, "volume.tet:4:", "expected 5 numbers", NULL, 0, NULL},
        {"volume.tet", 6, "1 2 3.5 4 1", NULL, "volume.tet:6:", "not an integer", NULL, 0, NULL},
        {"volume.tet", -1, NULL, NULL, "model.json: volume: manifest says", "tetrahedra", NULL, 0, NULL},
        {"volume.pts", 7, "1 2", NULL, "volume.pts:7:", "expected 3 coordinates", NULL, 0, NULL},
        {"volume.pts", 9, "1 2 nan", NULL, "volume.pts:9:", "not a finite number", NULL, 0, NULL},
        {"volume.pts", -1, NULL, NULL, "model.json: volume: manifest says", "nodes", NULL, 0, NULL},
        {"box.vmap", 2, "3", NULL, "box.vmap:2:", "surface \"box\" node 2 is volume node 3 but the coordinates differ",
         NULL, 0, NULL},
        /* injective: the surface node is moved onto the volume node first, so
         * that only the double use is wrong */
        {"heart.vmap", 1, "1", NULL, "heart.vmap:1:", "already node 1 of surface \"box\"", "heart.pts", 1, "0 0 0"},
        {"heart.vmap", 4, "16", NULL, "heart.vmap:4:", "already node 2 of surface \"heart\"", "heart.pts", 4, "3 5 5"},
        {"heart.vmap", 2, "14", NULL, "heart.vmap:2:", "coordinates differ", NULL, 0, NULL},
        {"box.vmap", 5, "0", NULL, "box.vmap:5:", "volume node 0 out of range", NULL, 0, NULL},
        {"box.vmap", 5, "5 6", NULL, "box.vmap:5:", "expected one volume node number", NULL, 0, NULL},
        {"box.vmap", -1, NULL, NULL, "box.vmap: surface \"box\": 13 lines for the surface's 14 nodes", "", NULL, 0,
         NULL},
        {"model.json", 0, NULL, j_not_spd, "model.json: region 2 (\"muscle\")", "not positive definite", NULL, 0, NULL},
        {"model.json", 0, NULL, j_asym, "region 2 (\"muscle\")", "not symmetric", NULL, 0, NULL},
        {"model.json", 0, NULL, j_bad_sigma_shape, "region 2 (\"muscle\")", "3x3 array", NULL, 0, NULL},
        {"model.json", 0, NULL, j_negative, "region 1 (\"mean_thorax\")", "not positive", NULL, 0, NULL},
        {"model.json", 0, NULL, j_bad_id, "region 3", "\"id\" must be 3", NULL, 0, NULL},
        {"model.json", 0, NULL, j_bad_units, "region 1 (\"mean_thorax\")", "\"S/m\"", NULL, 0, NULL},
        {"model.json", 0, NULL, j_no_regions, "model.json", "\"regions\"", NULL, 0, NULL},
        {"model.json", 0, NULL, j_dup_region, "regions 3 and 4", "\"heart\"", NULL, 0, NULL},
        {"model.json", 0, NULL, j_no_vmap, "surface 2 (\"heart\")", "\"vmap\"", NULL, 0, NULL},
        {"model.json", 0, NULL, j_base0, "\"index_base\" must be 1", "", NULL, 0, NULL},
        {"model.json", 0, NULL, j_count, "manifest says", "tetrahedra", NULL, 0, NULL},
        {"model.json", 0, NULL, j_path, "\"pts\" and \"tet\" must name files", "", NULL, 0, NULL},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        CHECK_OK(ctx, write_fresh(ctx, m, tl_path("bad")));
        snprintf(line, sizeof line, "bad/%s", cases[k].file);
        if (cases[k].line > 0) replace_line(tl_path(line), cases[k].line, cases[k].text);
        else if (cases[k].line < 0) drop_last_line(tl_path(line));
        else edit_json(tl_path("bad"), cases[k].fn);
        if (cases[k].file2) {
            snprintf(line, sizeof line, "bad/%s", cases[k].file2);
            replace_line(tl_path(line), cases[k].line2, cases[k].text2);
        }
        thx_model *r = NULL;
        thx_status st = thx_model_read(ctx, tl_path("bad"), &r);
        CHECK(st == THX_EINPUT && r == NULL);
        if (st != THX_EINPUT || !tl_msg_has(ctx, cases[k].want1) || !tl_msg_has(ctx, cases[k].want2))
            fprintf(stderr, "  (case %zu: %s line %d)\n", k, cases[k].file, cases[k].line);
        thx_model_destroy(&r);
    }
    /* Without "volume", "regions" and "vmap" are ignored (readers ignore keys
     * they do not use), each with a warning. */
    CHECK_OK(ctx, write_fresh(ctx, m, tl_path("bad")));
    edit_json(tl_path("bad"), j_no_volume);
    warnings = 0;
    thx_ctx_set_log(ctx, count_warning, NULL, THX_LOG_WARN);
    thx_model *r = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("bad"), &r));
    thx_ctx_set_log(ctx, NULL, NULL, THX_LOG_WARN);
    CHECK(r && r->volume == NULL && r->n_surfaces == 2);
    CHECK(warnings == 3);
    thx_model_destroy(&r);
    /* Blank lines and CRLF are tolerated, as in the surface files. */
    CHECK_OK(ctx, write_fresh(ctx, m, tl_path("bad")));
    const int32_t *q = v->tet;
    snprintf(line, sizeof line, "\n %d\t%d %d %d  %d\r\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1, v->region[0] + 1);
    replace_line(tl_path("bad/volume.tet"), 1, line);
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("bad"), &r));
    if (r) compare_models(m, r);
    thx_model_destroy(&r);
    thx_model_destroy(&m);
}

static size_t count_str(const char *text, const char *needle)
{
    size_t n = 0;
    for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle)) n++;
    return n;
}

static void test_export(void)
{
    thx_model *m = make_model(80);
    const thx_volume *v = m->volume;
    thx_export_format f;
    CHECK(thx_export_format_parse("vtu", &f) == 0 && f == THX_EXPORT_VTU && thx_export_format_is_volume(f));
    CHECK(thx_export_format_parse("msh", &f) == 0 && f == THX_EXPORT_MSH && thx_export_format_is_volume(f));
    CHECK(thx_export_format_parse("vtp", &f) == 0 && !thx_export_format_is_volume(f));

    CHECK_OK(ctx, thx_volume_export(ctx, m, THX_EXPORT_VTU, tl_path("v.vtu")));
    CHECK_OK(ctx, thx_volume_export(ctx, m, THX_EXPORT_MSH, tl_path("v.msh")));
    CHECK_OK(ctx, thx_volume_export(ctx, m, THX_EXPORT_VTU, tl_path("v2.vtu")));
    CHECK_OK(ctx, thx_volume_export(ctx, m, THX_EXPORT_MSH, tl_path("v2.msh")));
    CHECK(same_file(tl_path("v.vtu"), tl_path("v2.vtu")) && same_file(tl_path("v.msh"), tl_path("v2.msh")));

    char want[256];
    char *vtu = tl_slurp(ctx, tl_path("v.vtu"), NULL);
    snprintf(want, sizeof want, "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">", v->n_nodes, v->n_tets);
    CHECK(vtu && strstr(vtu, "type=\"UnstructuredGrid\"") && strstr(vtu, want));
    /* binary appended arrays (VTK itself reads them back: tests/volume_read.py, export_data_read.py) */
    CHECK(vtu && strstr(vtu, "<DataArray type=\"Int32\" Name=\"region\" format=\"appended\" offset=\""));
    CHECK(vtu && strstr(vtu, "<DataArray type=\"Float64\" Name=\"conductivity\" format=\"appended\""));
    CHECK(vtu && strstr(vtu, "Name=\"conductivity_tensor\" NumberOfComponents=\"9\"")); /* muscle is anisotropic */
    CHECK(vtu && strstr(vtu, "<Array type=\"String\" Name=\"region_name\" NumberOfTuples=\"4\" format=\"ascii\">"));
    CHECK(vtu && count_str(vtu, "<AppendedData encoding=\"raw\">") == 1);
    free(vtu);

    char *msh = tl_slurp(ctx, tl_path("v.msh"), NULL);
    const char *head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nthorax volume mesh, mm, tagged surfaces\n"
                       "$EndComments\n$PhysicalNames\n6\n2 1 \"box\"\n2 2 \"heart\"\n3 1 \"mean_thorax\"\n";
    CHECK(msh && strncmp(msh, head, strlen(head)) == 0); /* the comment: thorax's signature */
    CHECK(msh && strstr(msh, "3 4 \"blood\"\n$EndPhysicalNames\n$Entities\n0 0 2 4\n"));
    /* Region 4 holds no node (region 3, the heart, may hold none either). */
    const char *nodes = msh ? strstr(msh, "$Nodes\n") : NULL;
    size_t nb = 0, nn = 0, lo = 0, hi = 0;
    CHECK(nodes && sscanf(nodes, "$Nodes\n%zu %zu %zu %zu", &nb, &nn, &lo, &hi) == 4);
    CHECK((nb == 2 || nb == 3) && nn == v->n_nodes && lo == 1 && hi == v->n_nodes);
    /* region 4 has no element; the box's triangles are faces of the tetrahedra (its hull), the
     * heart's octahedron is not meshed conformingly: its own 8 triangles are written */
    size_t n_box = m->surf[0]->n_tris;
    snprintf(want, sizeof want, "$Elements\n5 %zu 1 %zu\n", v->n_tets + n_box + 8, v->n_tets + n_box + 8);
    CHECK(msh && strstr(msh, want));
    snprintf(want, sizeof want, "\n2 1 2 %zu\n", n_box);
    CHECK(msh && strstr(msh, want) && strstr(msh, "\n2 2 2 8\n"));
    CHECK(msh && strstr(msh, "\n4 0 0 0 0 0 0 1 4 0\n"));
    CHECK(msh && strstr(msh, "$EndElements\n") && msh[strlen(msh) - 1] == '\n');
    free(msh);

    /* Wrong uses: a surface format for the volume, a volume format for a
     * surface, a model without a volume, a faulty volume (no file left). */
    CHECK(thx_volume_export(ctx, m, THX_EXPORT_VTK, tl_path("x.vtk")) == THX_EINPUT && tl_msg_has(ctx, "vtu or msh"));
    CHECK(thx_surface_export(ctx, m->surf[0], THX_EXPORT_MSH, tl_path("x.msh")) == THX_EINPUT && tl_msg_has(ctx, "volume formats"));
    CHECK(!tl_exists(tl_path("x.vtk")) && !tl_exists(tl_path("x.msh")));
    m->volume->region[3] = 9;
    CHECK(thx_volume_export(ctx, m, THX_EXPORT_MSH, tl_path("bad.msh")) == THX_EINPUT && tl_msg_has(ctx, "bad.msh") &&
          tl_msg_has(ctx, "tetrahedron 4: region index 9"));
    CHECK(!tl_exists(tl_path("bad.msh")) && !tl_leftover_tmp("bad.msh"));
    CHECK(thx_volume_export(ctx, m, THX_EXPORT_VTU, tl_path("no/such.vtu")) == THX_EINPUT);
    m->volume->region[3] = 0;
    CHECK(thx_volume_export(ctx, m, THX_EXPORT_VTU, tl_path("no/such.vtu")) == THX_EIO && tl_msg_has(ctx, "no/such.vtu"));
    thx_volume_destroy(&m->volume);
    CHECK(thx_volume_export(ctx, m, THX_EXPORT_VTU, tl_path("none.vtu")) == THX_EINPUT && tl_msg_has(ctx, "no volume"));
    CHECK(!tl_exists(tl_path("none.vtu")));
    thx_model_destroy(&m);
}

/* The values of a Gmsh view in test_export_data: frame k gives node i the value k + i / 3. */
static void third_values(void *user, size_t k, double *out)
{
    size_t n = *(const size_t *)user;
    for (size_t i = 0; i < n; i++) out[i] = (double)k + (double)i / 3.0;
}

/* The writers with data (thorax/io/export_data.h); VTK and Gmsh read them in tests/e2e_export_data.sh. */
static void test_export_data(void)
{
    thx_model *m = make_model(40);
    const thx_volume *v = m->volume;
    double *phi = malloc(v->n_nodes * sizeof *phi), *j = calloc(3 * v->n_tets, sizeof *j);
    for (size_t i = 0; i < v->n_nodes; i++) phi[i] = 0.1 * (double)i;
    thx_export_array pt = {"potential", 1, phi}, ce = {"current_density", 3, j};
    thx_export_frame fr = {.has_time = 1, .time = 2.5, .point = &pt, .n_point = 1, .cell = &ce, .n_cell = 1};
    CHECK_OK(ctx, thx_volume_export_vtu(ctx, m, &fr, tl_path("d.vtu")));
    char *t = tl_slurp(ctx, tl_path("d.vtu"), NULL);
    CHECK(t && strstr(t, "<!-- thorax volume mesh") && strstr(t, "Name=\"potential\" format=\"appended\""));
    CHECK(t && strstr(t, "Name=\"current_density\" NumberOfComponents=\"3\" format=\"appended\""));
    CHECK(t && strstr(t, "Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">\n        2.5\n"));
    CHECK(t && !strstr(t, "conductivity_tensor")); /* per frame: region_sigma holds the tensors */
    free(t);
    /* a name XML or legacy VTK cannot hold is refused before anything is written */
    pt.name = "phi<1>";
    CHECK(thx_volume_export_vtu(ctx, m, &fr, tl_path("n.vtu")) == THX_EINPUT && tl_msg_has(ctx, "phi<1>"));
    pt.name = "phi 1";
    CHECK(thx_surface_export_data(ctx, m, 0, THX_EXPORT_VTK, &fr, tl_path("n.vtk")) == THX_EINPUT);
    CHECK(!tl_exists(tl_path("n.vtu")) && !tl_exists(tl_path("n.vtk")) && !tl_leftover_tmp("n."));
    pt.name = "potential";
    fr.n_cell = 0;
    pt.v = phi; /* surface 0 has fewer nodes than the volume: the first ones serve */
    CHECK_OK(ctx, thx_surface_export_data(ctx, m, 0, THX_EXPORT_VTK, &fr, tl_path("s.vtk")));
    t = tl_slurp(ctx, tl_path("s.vtk"), NULL);
    CHECK(t && strstr(t, "\nthorax surface box (mm, with data)\n") && strstr(t, "\nTimeValue 1 1 double\n2.5\n") &&
          strstr(t, "\nsurface_name 1 2 string\nbox\nheart\n") && strstr(t, "\nSCALARS potential double 1\n"));
    free(t);
    /* the collection: times must increase; a file it did not write is never replaced */
    const char *files[] = {"a_0001.vtu", "a_0002.vtu"};
    double times[] = {0.5, 0.25};
    CHECK(thx_export_pvd(ctx, tl_path("a.pvd"), files, times, 2) == THX_EINPUT && tl_msg_has(ctx, "increasing"));
    CHECK(!tl_exists(tl_path("a.pvd")));
    times[1] = 1e-3 + 0.5;
    CHECK_OK(ctx, thx_export_pvd(ctx, tl_path("a.pvd"), files, times, 2));
    t = tl_slurp(ctx, tl_path("a.pvd"), NULL);
    CHECK(t && strstr(t, "<DataSet timestep=\"0.501\" group=\"\" part=\"0\" file=\"a_0002.vtu\"/>"));
    free(t);
    CHECK_OK(ctx, thx_export_pvd(ctx, tl_path("a.pvd"), files, times, 2)); /* its own: replaced */
    tl_write_text(tl_path("b.pvd"), "<VTKFile type=\"Collection\"/>\n");
    CHECK(thx_export_pvd(ctx, tl_path("b.pvd"), files, times, 2) != THX_OK && tl_msg_has(ctx, "b.pvd"));
    t = tl_slurp(ctx, tl_path("b.pvd"), NULL);
    CHECK(t && strcmp(t, "<VTKFile type=\"Collection\"/>\n") == 0);
    free(t);
    /* Gmsh views: one $NodeData per frame, values exact ("%.17g") */
    size_t n = v->n_nodes;
    double vt[3] = {0, 2, 4};
    thx_msh_view view = {.name = "potential (mV)", .n_comp = 1, .n = n, .n_frames = 3, .time = vt,
                         .values = third_values, .user = &n};
    CHECK_OK(ctx, thx_volume_export_msh(ctx, m, &view, 1, tl_path("d.msh")));
    t = tl_slurp(ctx, tl_path("d.msh"), NULL);
    CHECK(t && count_str(t, "$NodeData\n1\n\"potential (mV)\"\n1\n") == 3 && count_str(t, "$EndNodeData\n") == 3);
    char want[128];
    snprintf(want, sizeof want, "$NodeData\n1\n\"potential (mV)\"\n1\n4\n3\n2\n1\n%zu\n1 2\n2 2.3333333333333335\n", n);
    CHECK(t && strstr(t, want));
    free(t);
    int32_t bad_id = (int32_t)n;
    view.ids = &bad_id;
    view.n = 1;
    CHECK(thx_volume_export_msh(ctx, m, &view, 1, tl_path("e.msh")) == THX_EINTERNAL && !tl_exists(tl_path("e.msh")));
    free(phi);
    free(j);
    thx_model_destroy(&m);
}

/* Large files are parsed in pieces, a thread each (src/io/common/io_text.h): a model whose volume.pts and
   volume.tet begin with 3 million blank lines (3 MB: two pieces or more) reads as the model does, and a
   fault in a later piece is named at its line in the whole file. */
static void prepend_blank(const char *path, size_t lines)
{
    size_t n = 0;
    char *t = tl_slurp(ctx, path, &n);
    FILE *f = fopen(path, "wb");
    if (!t || !f) exit(1);
    for (size_t i = 0; i < lines; i++) fputc('\n', f);
    fwrite(t, 1, n, f);
    fclose(f);
    free(t);
}

static void test_pieces(void)
{
#ifdef _OPENMP
    int was = omp_get_max_threads();
    omp_set_num_threads(4);
#endif
    thx_model *m = make_model(200), *r = NULL;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("pc")));
    const size_t B = 3000000;
    prepend_blank(tl_path("pc/volume.pts"), B);
    prepend_blank(tl_path("pc/volume.tet"), B);
    /* the verdict's digest no longer matches, which reading does not look at */
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("pc"), &r));
    if (r) compare_models(m, r);
    thx_model_destroy(&r);
    char want[64];
    replace_line(tl_path("pc/volume.tet"), (int)B + 7, "1 2 3 x 1");
    snprintf(want, sizeof want, "volume.tet:%zu:", B + 7);
    CHECK(thx_model_read(ctx, tl_path("pc"), &r) == THX_EINPUT && tl_msg_has(ctx, want) && tl_msg_has(ctx, "not an integer"));
    replace_line(tl_path("pc/volume.tet"), (int)B + 7, "");
    replace_line(tl_path("pc/volume.tet"), (int)B - 1, "1 2 3");
    snprintf(want, sizeof want, "volume.tet:%zu:", B - 1);
    CHECK(thx_model_read(ctx, tl_path("pc"), &r) == THX_EINPUT && tl_msg_has(ctx, want) && tl_msg_has(ctx, "expected 5 numbers"));
    replace_line(tl_path("pc/volume.pts"), (int)B + 11, "1 2 inf");
    snprintf(want, sizeof want, "volume.pts:%zu:", B + 11);
    CHECK(thx_model_read(ctx, tl_path("pc"), &r) == THX_EINPUT && tl_msg_has(ctx, want) && tl_msg_has(ctx, "not a finite number"));
    printf("pieces: a 3 MB volume.pts and volume.tet read as the model; faults named at lines %zu, %zu and %zu\n", B + 7,
           B - 1, B + 11);
    thx_model_destroy(&m);
#ifdef _OPENMP
    omp_set_num_threads(was);
#endif
}

int main(int argc, char **argv)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (argc >= 3 && strcmp(argv[1], "--write-model") == 0) {
        size_t n = argc >= 4 ? (size_t)strtoul(argv[3], NULL, 10) : 300;
        thx_model *m = make_model(n);
        thx_status st = thx_model_write(ctx, m, argv[2]);
        if (st) fprintf(stderr, "test_volume_io: %s\n", thx_ctx_message(ctx));
        thx_model_destroy(&m);
        thx_ctx_destroy(&ctx);
        return st ? 1 : 0;
    }
    if (tl_scratch_make("test_volume_io")) return 1;
    test_model_shape();
    test_round_trip();
    test_failed_write();
    test_bad_files();
    test_pieces();
    test_export();
    test_export_data();
    int rc = tl_scratch_finish("test_volume_io");
    thx_ctx_destroy(&ctx);
    return rc;
}
