/*
 * Tests of map3d landmarks (thorax/model/landmarks.h, thorax/io/landmarks_file.h,
 * thorax/geom/landmark_mesh.h):
 *  - the two real files (map3d's tank sock and Dalhousie epicardium): segment and point counts,
 *    values and lines as in the files; the tank's landmarks lie on the sock they were digitized
 *    with (a units or axes mistake would put them far off);
 *  - write/read round trips equal field by field, byte-identical writes, nothing written for an
 *    invalid set;
 *  - the variants map3d reads (count line words, commas, case, index and colour, labels, CRLF,
 *    comments) accepted, and a table of bad inputs each refused with file:line and the segment;
 *  - meshes: closed and edge-manifold (every directed edge once, its reverse once), outward
 *    (volume > 0), no zero-area triangle; volumes against closed forms (frustum, cone, mitred
 *    bend, disc, arrow), no twist along a planar polyline; both real files' meshes; colours.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/geom/inside.h"
#include "thorax/geom/landmark_mesh.h"
#include "thorax/io/landmarks_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/landmarks.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static thx_ctx *ctx;
static char data_dir[2048];

static const char *data(const char *rel)
{
    static char buf[4][2300];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", data_dir, rel);
    return buf[k];
}

/* ------------------------------------------------------------- mesh properties */

static int cmp_edge(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;
    return *x < *y ? -1 : *x > *y;
}

/* Whether s is closed and edge-manifold with consistent orientation: every directed edge occurs
 * exactly once and its reverse exactly once. Also: no triangle of zero area (relative to the
 * surface's size) and indices in range. */
static int closed_manifold(const thx_surface *s)
{
    if (!s || s->n_tris == 0) return 0;
    if (thx_surface_validate(ctx, s) != THX_OK) return 0;
    int64_t *e = malloc(3 * s->n_tris * sizeof *e);
    if (!e) return 0;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < 3 * s->n_nodes; i++) lo = fmin(lo, s->xyz[i]), hi = fmax(hi, s->xyz[i]);
    double scale = hi - lo, min_area = INFINITY;
    for (size_t t = 0; t < s->n_tris; t++) {
        for (int k = 0; k < 3; k++) e[3 * t + (size_t)k] = (int64_t)s->tri[3 * t + (size_t)k] << 32 | s->tri[3 * t + (size_t)(k + 1) % 3];
        thx_vec3 a = thx_surface_node(s, (size_t)s->tri[3 * t]), b = thx_surface_node(s, (size_t)s->tri[3 * t + 1]),
                 c = thx_surface_node(s, (size_t)s->tri[3 * t + 2]);
        min_area = fmin(min_area, 0.5 * thx_v3_norm(thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a))));
    }
    qsort(e, 3 * s->n_tris, sizeof *e, cmp_edge);
    int ok = min_area > 1e-10 * scale * scale;
    if (!ok) fprintf(stderr, "  %s: a triangle of area %g (size %g)\n", s->name, min_area, scale);
    for (size_t i = 0; i < 3 * s->n_tris && ok; i++) {
        if (i + 1 < 3 * s->n_tris && e[i] == e[i + 1]) ok = 0; /* a directed edge twice */
        int64_t rev = (e[i] & 0xffffffff) << 32 | (e[i] >> 32);
        if (!bsearch(&rev, e, 3 * s->n_tris, sizeof *e, cmp_edge)) ok = 0; /* no twin */
        if (!ok) fprintf(stderr, "  %s: edge %lld-%lld is not shared by two opposite triangles\n", s->name,
                         (long long)(e[i] >> 32), (long long)(e[i] & 0xffffffff));
    }
    free(e);
    return ok;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Sum over a segment's pieces of pi h (r1^2 + r1 r2 + r2^2) / 3. */
static double frustum_sum(const thx_landmark_segment *g)
{
    double v = 0;
    for (size_t i = 0; i + 1 < g->n; i++) {
        const thx_landmark_point *a = &g->pt[i], *b = &g->pt[i + 1];
        double h = thx_v3_norm(thx_v3(b->xyz[0] - a->xyz[0], b->xyz[1] - a->xyz[1], b->xyz[2] - a->xyz[2]));
        v += M_PI * h * (a->radius * a->radius + a->radius * b->radius + b->radius * b->radius) / 3;
    }
    return v;
}

static thx_landmark_point P(double x, double y, double z, double r)
{
    thx_landmark_point p;
    memset(&p, 0, sizeof p);
    p.xyz[0] = x, p.xyz[1] = y, p.xyz[2] = z, p.radius = r;
    return p;
}

/* The mesh of a one-segment set of type t through the n points (NULL when refused). */
static thx_surface *mesh_of(thx_landmark_type t, const thx_landmark_point *pts, size_t n, const thx_landmark_mesh_opts *o)
{
    thx_landmarks *lm = NULL;
    thx_surface *s = NULL;
    CHECK_OK(ctx, thx_landmarks_create(ctx, &lm));
    CHECK_OK(ctx, thx_landmarks_add_segment(ctx, lm, t, pts, n, NULL));
    thx_status st = thx_landmark_segment_mesh(ctx, &lm->seg[0], 0, o, &s);
    if (st != THX_OK) fprintf(stderr, "  mesh refused: %s\n", thx_ctx_message(ctx));
    thx_landmarks_destroy(&lm);
    return s;
}

/* ------------------------------------------------------------- the real files */

static void test_real_tank(void)
{
    thx_landmarks *lm = NULL;
    const char *path = data("map3d/geom/tank/25feb97_sock.lmarks");
    CHECK(tl_exists(path)); /* the data folder is part of the setup: its absence is a failure */
    CHECK_OK(ctx, thx_landmarks_read(ctx, path, &lm));
    if (!lm) return;
    CHECK(lm->n == 11);
    CHECK(!strcmp(lm->path, path));
    /* segment sizes as in the file: 15 7 5 5 7 8 5 5 11, then two single sites */
    static const size_t npts[11] = {15, 7, 5, 5, 7, 8, 5, 5, 11, 1, 1};
    static const int lines[11] = {2, 18, 26, 32, 38, 46, 55, 61, 67, 79, 81};
    for (size_t k = 0; k < lm->n && k < 11; k++) {
        CHECK(lm->seg[k].n == npts[k]);
        CHECK(lm->seg[k].line == lines[k]);
        CHECK(lm->seg[k].type == (k < 9 ? THX_LANDMARK_ARTERY : k == 9 ? THX_LANDMARK_STIMULUS : THX_LANDMARK_OCCLUSION));
        CHECK(!lm->seg[k].has_color && !lm->seg[k].has_index);
    }
    /* "   1.732    5.707  297.844  2.69" and the tip " -27.407   22.326  237.588  0.00" */
    const thx_landmark_point *p = &lm->seg[0].pt[0];
    CHECK(p->xyz[0] == 1.732 && p->xyz[1] == 5.707 && p->xyz[2] == 297.844 && p->radius == 2.69 && !p->label[0]);
    p = &lm->seg[0].pt[14];
    CHECK(p->xyz[0] == -27.407 && p->xyz[1] == 22.326 && p->xyz[2] == 237.588 && p->radius == 0);
    p = &lm->seg[9].pt[0]; /* " -45.215   35.896  269.921  1.00" */
    CHECK(p->xyz[0] == -45.215 && p->xyz[1] == 35.896 && p->xyz[2] == 269.921 && p->radius == 1.0);
    p = &lm->seg[10].pt[0]; /* "  26.569    7.527  259.212  1.00" */
    CHECK(p->xyz[0] == 26.569 && p->xyz[1] == 7.527 && p->xyz[2] == 259.212);

    /* The landmarks were digitized with the sock: the arteries run on the epicardium, so the
     * points lie on the sock surface, not millimetres off (a units slip would put them 10x out,
     * an axes slip tens of mm away). Measured: median distance to the sock's triangles 1.40 mm
     * (largest 6.34 mm), to its nodes 5.28 mm (the 128 electrodes are about 15 mm apart). */
    thx_surface *sock = NULL;
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, data("map3d/geom/tank/25feb97_sock.pts"),
                                          data("map3d/geom/tank/25feb97_sock.fac"), "sock", THX_ROLE_HEART, &sock, NULL));
    if (sock) {
        double dt[80], dn[80];
        size_t m = 0;
        for (size_t k = 0; k < lm->n; k++)
            for (size_t i = 0; i < lm->seg[k].n && m < 80; i++, m++) {
                thx_vec3 x = thx_v3(lm->seg[k].pt[i].xyz[0], lm->seg[k].pt[i].xyz[1], lm->seg[k].pt[i].xyz[2]);
                dt[m] = dn[m] = INFINITY;
                for (size_t t = 0; t < sock->n_tris; t++)
                    dt[m] = fmin(dt[m], thx_triangle_distance(thx_surface_node(sock, (size_t)sock->tri[3 * t]),
                                                             thx_surface_node(sock, (size_t)sock->tri[3 * t + 1]),
                                                             thx_surface_node(sock, (size_t)sock->tri[3 * t + 2]), x));
                for (size_t v = 0; v < sock->n_nodes; v++)
                    dn[m] = fmin(dn[m], thx_v3_norm(thx_v3_sub(thx_surface_node(sock, v), x)));
            }
        CHECK(m == 70);
        qsort(dt, m, sizeof *dt, cmp_double);
        qsort(dn, m, sizeof *dn, cmp_double);
        double med_t = dt[m / 2], med_n = dn[m / 2];
        printf("tank landmarks to the sock: median %.2f mm to its triangles (max %.2f), %.2f mm to its nodes\n", med_t,
               dt[m - 1], med_n);
        CHECK(med_t < 3.0);
        CHECK(med_n < 8.0);
        CHECK(dt[m - 1] < 10.0);
    }
    thx_surface_destroy(&sock);
    thx_landmarks_destroy(&lm);
}

static void test_real_dalepi(void)
{
    thx_landmarks *lm = NULL;
    const char *path = data("map3d/geom/torso/dalepi-def.lmark");
    CHECK(tl_exists(path));
    CHECK_OK(ctx, thx_landmarks_read(ctx, path, &lm)); /* first line "12", headers "4 coronary 3 " */
    if (!lm) return;
    CHECK(lm->n == 12);
    static const size_t npts[12] = {10, 3, 6, 3, 3, 5, 3, 4, 9, 4, 4, 3};
    for (size_t k = 0; k < lm->n && k < 12; k++) {
        CHECK(lm->seg[k].n == npts[k]);
        CHECK(lm->seg[k].type == THX_LANDMARK_ARTERY);
    }
    CHECK(lm->seg[0].line == 2 && lm->seg[1].line == 13 && lm->seg[11].line == 67);
    /* "32.000000 349.000000 -22.000000 0.63333" (segment 1 point 9) */
    const thx_landmark_point *p = &lm->seg[0].pt[8];
    CHECK(p->xyz[0] == 32.0 && p->xyz[1] == 349.0 && p->xyz[2] == -22.0 && p->radius == 0.63333);
    /* "-4.333333 345.666656 -23.000000 0.375000" (segment 9 point 8) */
    p = &lm->seg[8].pt[7];
    CHECK(p->xyz[0] == -4.333333 && p->xyz[1] == 345.666656 && p->radius == 0.375);

    /* On the Dalhousie epicardium (98 nodes): the points are on it. Measured: median distance to
     * its triangles 0.00 mm (28 of the 57 points are its nodes), largest 2.51 mm. */
    thx_surface *epi = NULL;
    CHECK_OK(ctx, thx_surface_read_ptsfac(ctx, data("map3d/geom/torso/dalepi.pts"), data("map3d/geom/torso/dalepi.fac"),
                                          "epi", THX_ROLE_HEART, &epi, NULL));
    if (epi) {
        double d[64];
        size_t m = 0;
        for (size_t k = 0; k < lm->n; k++)
            for (size_t i = 0; i < lm->seg[k].n && m < 64; i++, m++) {
                thx_vec3 x = thx_v3(lm->seg[k].pt[i].xyz[0], lm->seg[k].pt[i].xyz[1], lm->seg[k].pt[i].xyz[2]);
                d[m] = INFINITY;
                for (size_t t = 0; t < epi->n_tris; t++)
                    d[m] = fmin(d[m], thx_triangle_distance(thx_surface_node(epi, (size_t)epi->tri[3 * t]),
                                                           thx_surface_node(epi, (size_t)epi->tri[3 * t + 1]),
                                                           thx_surface_node(epi, (size_t)epi->tri[3 * t + 2]), x));
            }
        CHECK(m == 57);
        qsort(d, m, sizeof *d, cmp_double);
        printf("dalepi landmarks to the epicardium: median %.2f mm (max %.2f)\n", d[m / 2], d[m - 1]);
        CHECK(d[m / 2] < 0.5);
        CHECK(d[m - 1] < 5.0);
    }
    thx_surface_destroy(&epi);
    thx_landmarks_destroy(&lm);
}

/* Both real files: every segment's mesh closed, outward, manifold; tubes' volumes near the
 * frustum formula; spheres' near 4/3 pi r^3. */
static void test_real_meshes(void)
{
    const char *files[2] = {"map3d/geom/tank/25feb97_sock.lmarks", "map3d/geom/torso/dalepi-def.lmark"};
    double worst = 0;
    for (int f = 0; f < 2; f++) {
        thx_landmarks *lm = NULL;
        CHECK_OK(ctx, thx_landmarks_read(ctx, data(files[f]), &lm));
        if (!lm) continue;
        thx_landmark_meshes *m = NULL;
        CHECK_OK(ctx, thx_landmarks_mesh(ctx, lm, NULL, &m));
        CHECK(m && m->n == lm->n);
        for (size_t k = 0; m && k < m->n; k++) {
            const thx_surface *s = m->surf[k];
            CHECK(closed_manifold(s));
            double v = thx_surface_volume(s);
            CHECK(v > 0);
            const thx_landmark_segment *g = &lm->seg[k];
            if (g->type == THX_LANDMARK_ARTERY) {
                double ref = frustum_sum(g), rel = fabs(v / ref - 1);
                worst = fmax(worst, rel);
                CHECK(rel < 0.03);
                CHECK(m->rgba[k][0] == 1 && m->rgba[k][1] == 0 && m->rgba[k][2] == 0 && m->rgba[k][3] == 1);
            } else {
                double r = g->pt[0].radius, ref = 4.0 / 3 * M_PI * r * r * r;
                CHECK(v < ref && v > 0.95 * ref); /* level 2 icosphere: nodes on the sphere, 320 flat faces */
            }
        }
        if (f == 0 && m && m->n == 11) {
            /* stimulus yellow, occlusion cyan (map3d's manual) */
            CHECK(m->rgba[9][0] == 1 && m->rgba[9][1] == 1 && m->rgba[9][2] == 0);
            CHECK(m->rgba[10][0] == 0 && m->rgba[10][1] == 1 && m->rgba[10][2] == 1);
        }
        thx_landmark_meshes_destroy(&m);
        CHECK(m == NULL);
        thx_landmarks_destroy(&lm);
    }
    printf("real arteries: tube volume within %.2f%% of the frustum formula (12 sides)\n", 100 * worst);
}

/* ------------------------------------------------------------- round trips */

static int same_sets(const thx_landmarks *a, const thx_landmarks *b)
{
    if (!a || !b || a->n != b->n) return 0;
    for (size_t k = 0; k < a->n; k++) {
        const thx_landmark_segment *x = &a->seg[k], *y = &b->seg[k];
        if (x->type != y->type || x->n != y->n || x->has_index != y->has_index || x->has_color != y->has_color) return 0;
        if (x->has_index && x->index != y->index) return 0;
        if (x->has_color && memcmp(x->rgb, y->rgb, 3)) return 0;
        for (size_t i = 0; i < x->n; i++) {
            const thx_landmark_point *p = &x->pt[i], *q = &y->pt[i];
            if (p->xyz[0] != q->xyz[0] || p->xyz[1] != q->xyz[1] || p->xyz[2] != q->xyz[2] || p->radius != q->radius ||
                strcmp(p->label, q->label))
                return 0;
        }
    }
    return 1;
}

static void test_round_trip(void)
{
    const char *files[2] = {"map3d/geom/tank/25feb97_sock.lmarks", "map3d/geom/torso/dalepi-def.lmark"};
    for (int f = 0; f < 2; f++) {
        thx_landmarks *a = NULL, *b = NULL;
        CHECK_OK(ctx, thx_landmarks_read(ctx, data(files[f]), &a));
        CHECK_OK(ctx, thx_landmarks_write(ctx, a, tl_path("rt.lmarks")));
        CHECK_OK(ctx, thx_landmarks_read(ctx, tl_path("rt.lmarks"), &b));
        CHECK(same_sets(a, b));
        size_t n1 = 0, n2 = 0;
        char *t1 = tl_slurp(ctx, tl_path("rt.lmarks"), &n1);
        CHECK_OK(ctx, thx_landmarks_write(ctx, b, tl_path("rt2.lmarks")));
        char *t2 = tl_slurp(ctx, tl_path("rt2.lmarks"), &n2);
        CHECK(t1 && t2 && n1 == n2 && !memcmp(t1, t2, n1)); /* byte-identical */
        if (f == 0 && t1) CHECK(!strncmp(t1, "11\n1 artery 15\n1.732000 5.707000 297.844000 2.690000\n", 52));
        free(t1);
        free(t2);
        thx_landmarks_destroy(&a);
        thx_landmarks_destroy(&b);
    }

    /* Every field: index, colour, labels, awkward numbers (written %.17g where %.6f loses them) */
    thx_landmarks *a = NULL, *b = NULL;
    CHECK_OK(ctx, thx_landmarks_create(ctx, &a));
    thx_landmark_point pts[3] = {P(0.1 + 0.2, -1e-7, 1234567.125, 0), P(-0.0, 2.5, 1e-300, 0.333333333333),
                                 P(7, 8, 9, 1)};
    snprintf(pts[0].label, sizeof pts[0].label, "LAD");
    snprintf(pts[2].label, sizeof pts[2].label, "%s", "a_label-of.39_characters_exactly_123456");
    thx_landmark_segment *s = NULL;
    CHECK_OK(ctx, thx_landmarks_add_segment(ctx, a, THX_LANDMARK_PLANE, pts, 3, &s));
    s->has_index = 1, s->index = 17, s->has_color = 1, s->rgb[0] = 0, s->rgb[1] = 128, s->rgb[2] = 255;
    CHECK_OK(ctx, thx_landmarks_add_segment(ctx, a, THX_LANDMARK_LEAD, pts + 2, 1, &s));
    s->has_color = 1, s->rgb[0] = 10, s->rgb[1] = 20, s->rgb[2] = 30;
    CHECK_OK(ctx, thx_landmarks_add_segment(ctx, a, THX_LANDMARK_FIBER, pts + 1, 2, &s));
    s->has_index = 1, s->index = 0;
    CHECK_OK(ctx, thx_landmarks_write(ctx, a, tl_path("all.lmarks")));
    CHECK_OK(ctx, thx_landmarks_read(ctx, tl_path("all.lmarks"), &b));
    CHECK(same_sets(a, b));
    char *t = tl_slurp(ctx, tl_path("all.lmarks"), NULL);
    CHECK(t && strstr(t, "1 plane 3 17 0 128 255\n") && strstr(t, "2 lead 1 10 20 30\n") && strstr(t, "3 fiber 2 0\n"));
    CHECK(t && strstr(t, "0.30000000000000004 -9.9999999999999995e-08 1234567.125000 0.000000 LAD\n"));
    CHECK(t && !strstr(t, "-0.0")); /* -0 written 0 */
    free(t);
    thx_landmarks_destroy(&b);

    /* An empty set writes "0" and reads back empty */
    thx_landmarks *e = NULL;
    CHECK_OK(ctx, thx_landmarks_create(ctx, &e));
    CHECK_OK(ctx, thx_landmarks_write(ctx, e, tl_path("empty.lmarks")));
    CHECK_OK(ctx, thx_landmarks_read(ctx, tl_path("empty.lmarks"), &b));
    CHECK(b && b->n == 0);
    thx_landmarks_destroy(&b);
    thx_landmarks_destroy(&e);

    /* An invalid set: refused before anything is created */
    a->seg[0].pt[1].radius = -1;
    CHECK(thx_landmarks_write(ctx, a, tl_path("bad.lmarks")) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "bad.lmarks: segment 1 point 2: radius -1"));
    CHECK(!tl_exists(tl_path("bad.lmarks")));
    a->seg[0].pt[1].radius = 1;
    snprintf(a->seg[1].pt[0].label, sizeof a->seg[1].pt[0].label, "two words");
    CHECK(thx_landmarks_write(ctx, a, tl_path("bad.lmarks")) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "segment 2 point 1: label \"two words\" holds a blank"));
    CHECK(!tl_exists(tl_path("bad.lmarks")));
    CHECK(!tl_leftover_tmp(""));
    thx_landmarks_destroy(&a);
}

/* ------------------------------------------------------------- variants and bad inputs */

static thx_landmarks *parse(const char *text)
{
    thx_landmarks *lm = NULL;
    tl_write_text(tl_path("v.lmarks"), text);
    thx_status st = thx_landmarks_read(ctx, tl_path("v.lmarks"), &lm);
    if (st != THX_OK) fprintf(stderr, "  refused: %s\n", thx_ctx_message(ctx));
    return lm;
}

static void test_variants(void)
{
    thx_landmarks *lm = parse("# a comment line\n\n2 Segments   # words after the count\r\n"
                              "1, Coronary, 2, 5, 255, 0, 0\r\n"
                              "\t0 0 0 1.5 LAD_origin\r\n"
                              "1e1 .5 5. -0.00\n"
                              "   # between points\n"
                              "2 STIMULUS 1 3\n"
                              "+1 -2 3 0\n");
    CHECK(lm && lm->n == 2);
    if (lm && lm->n == 2) {
        const thx_landmark_segment *a = &lm->seg[0], *b = &lm->seg[1];
        CHECK(a->type == THX_LANDMARK_ARTERY && a->n == 2 && a->has_index && a->index == 5 && a->has_color);
        CHECK(a->rgb[0] == 255 && a->rgb[1] == 0 && a->rgb[2] == 0 && a->line == 4);
        CHECK(!strcmp(a->pt[0].label, "LAD_origin") && a->pt[0].radius == 1.5);
        CHECK(a->pt[1].xyz[0] == 10 && a->pt[1].xyz[1] == 0.5 && a->pt[1].xyz[2] == 5 && a->pt[1].radius == 0);
        CHECK(!signbit(a->pt[1].radius));
        CHECK(b->type == THX_LANDMARK_STIMULUS && b->n == 1 && b->has_index && b->index == 3 && !b->has_color);
        CHECK(b->pt[0].xyz[0] == 1 && b->pt[0].xyz[1] == -2 && b->line == 8);
    }
    thx_landmarks_destroy(&lm);
    /* the types by name and alias, any case */
    static const struct { const char *word; thx_landmark_type t; } names[] = {
        {"artery", THX_LANDMARK_ARTERY},   {"CORONARY", THX_LANDMARK_ARTERY},      {"Occlusion", THX_LANDMARK_OCCLUSION},
        {"closure", THX_LANDMARK_CLOSURE}, {"Stitch", THX_LANDMARK_CLOSURE},       {"stimulus", THX_LANDMARK_STIMULUS},
        {"lead", THX_LANDMARK_LEAD},       {"PaceNeedle", THX_LANDMARK_PACENEEDLE}, {"cath", THX_LANDMARK_CATH},
        {"catheter", THX_LANDMARK_CATH},   {"RecNeedle", THX_LANDMARK_RECNEEDLE},  {"cannula", THX_LANDMARK_CANNULA},
        {"rod", THX_LANDMARK_ROD},         {"fiber", THX_LANDMARK_FIBER},          {"plane", THX_LANDMARK_PLANE},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        thx_landmark_type t;
        CHECK(thx_landmark_type_parse(names[i].word, &t) == 0 && t == names[i].t);
    }
    thx_landmark_type t;
    CHECK(thx_landmark_type_parse("stim", &t) == -1 && thx_landmark_type_parse("vein", &t) == -1);
    for (int i = 0; i < THX_LANDMARK_TYPE_COUNT; i++) {
        CHECK(thx_landmark_type_parse(thx_landmark_type_name((thx_landmark_type)i), &t) == 0 && t == (thx_landmark_type)i);
    }
    /* "0" segments: an empty set; a count line "11 segment" */
    lm = parse("0\n");
    CHECK(lm && lm->n == 0);
    thx_landmarks_destroy(&lm);
    lm = parse("1 segment\n1 lead 1 0\n1 2 3 4");  /* index 0, no newline at the end */
    CHECK(lm && lm->n == 1 && lm->seg[0].has_index && lm->seg[0].index == 0 && lm->seg[0].pt[0].radius == 4);
    thx_landmarks_destroy(&lm);
}

static void test_bad_inputs(void)
{
    /* the real tank file, altered */
    size_t len = 0;
    char *tank = tl_slurp(ctx, data("map3d/geom/tank/25feb97_sock.lmarks"), &len);
    CHECK(tank != NULL);
    if (!tank) return;
    struct {
        const char *from, *to; /* replace the first `from` by `to` in the tank file */
        const char *want;     /* the message holds "v.lmarks:" + want */
    } alter[] = {
        {" 11 segment", " 12 segment", ":82: truncated file: 11 of 12 segments (the count on line 1)"},
        {" 11 segment", " 10 segment", ":81: text after the last segment: the file declares 10 segments (line 1)"},
        {" 1 coronary 15", " 1 coronary 16", ":18: segment 1 point 16: expected 'X Y Z RADIUS [LABEL]', found a segment "
                                            "header: segment 1 (line 2) declares 16 points but has 15"},
        {" 1 coronary 15", " 1 coronary 14", ":17: expected the header of segment 2 ('2 TYPE NPOINTS [INDEX] [R G B]'), "
                                            "found a point: does segment 1 (line 2) have more than the 14 points"},
        {"   1.533    1.136", "   1.533    1.1x6", ":5: segment 1 point 3: y '1.1x6' is not a decimal number"},
        {"   1.533    1.136", "   nan    1.136", ":5: segment 1 point 3: x 'nan' is not a decimal number"},
        {"   1.533    1.136", "   inf    1.136", ":5: segment 1 point 3: x 'inf' is not a decimal number"},
        {"   1.533    1.136", "   1e999    1.136", ":5: segment 1 point 3: x '1e999' is beyond +-1e+07 mm"},
        {"   1.533    1.136", "   0x1p3    1.136", ":5: segment 1 point 3: x '0x1p3' is not a decimal number"},
        {" 3 coronary 5", " 3 vein 5", ":26: segment 3: unknown landmark type 'vein' (known: artery (or coronary), "
                                       "occlusion, closure (or stitch), stimulus, lead, plane, rod, paceneedle, cath "
                                       "(or catheter), fiber, recneedle, cannula)"},
        {"290.083  2.14", "290.083  -2.14", ":5: segment 1 point 3: radius -2.14 is negative"},
        {" 2 coronary 7", " 3 coronary 7", ":18: segment 2: numbered 3 (segments are numbered 1, 2, ... in order)"},
        {" 2 coronary 7", " 2 coronary 7 1 2", ":18: segment 2 (artery): 2 fields after the point count"},
        {" 2 coronary 7", " 2 coronary 7 1 2 3 4 5", ":18: segment 2 (artery): 5 fields after the point count"},
        {" 2 coronary 7", " 2 coronary 7 255 0 256", ":18: segment 2 (artery): colour blue '256' is not a whole number 0..255"},
        {" 2 coronary 7", " 2 coronary 7 -1 0 0", ":18: segment 2 (artery): colour red '-1'"},
        {" 2 coronary 7", " 2 coronary 7 -1", ":18: segment 2 (artery): index '-1' is not a whole number"},
        {" 2 coronary 7", " 2 coronary 7.0", ":18: segment 2 (artery): point count '7.0' is not a positive whole number"},
        {" 2 coronary 7", " 2 coronary 0", ":18: segment 2 (artery): point count '0' is not a positive whole number"},
        {"  2.69\n", "  2.69 LAD extra\n", ":3: segment 1 point 1: expected 'X Y Z RADIUS [LABEL]', found 6 fields"},
        {"  2.69\n", "  2.69 a_label_of_forty_characters_123456789012\n", ":3: segment 1 point 1: label "
                                                                           "'a_label_of_forty_characters_123456789012' is longer than 39"},
        {"  2.69\n", ",2.69\n", ":3: segment 1 point 1: a comma in '297.844,2.69'"},
        {" 11 segment", " 11 segmnet", ":1: unexpected text after the segment count: 'segmnet'"},
        {" 11 segment", " 11 segments 4", ":1: unexpected text after the segment count: '4'"},
        {" 11 segment", " 011", ":1: segment count '011' has a leading zero (map3d would read it as octal)"},
        {" 11 segment", " -11", ":1: expected the number of segments on the first line, found '-11'"},
        {" 11 segment", " 2000000000", ":1: the file declares 2000000000 segments, but the 2"},
        {" 1 coronary 15", " 1 coronary 999999999", ":2: segment 1 (artery) declares 999999999 points, but the"},
        {" 10 stimulus 1", " 10 plane 1", ":79: segment 10 (plane): 1 point; a plane needs exactly 3"},
        {" 10 stimulus 1", " 10 coronary 1", ":79: segment 10 (artery): 1 point; an artery needs at least 2"},
        {" 4 coronary 5\n -12.690   -3.111  272.061  1.10\n  -7.097   -3.483  265.394  0.50\n",
         " 4 plane 5\n -12.690   -3.111  272.061  1.10\n  -7.097   -3.483  265.394  0.50\n",
         ":32: segment 4 (plane): 5 points; a plane needs exactly 3"},
    };
    for (size_t i = 0; i < sizeof alter / sizeof alter[0]; i++) {
        const char *at = strstr(tank, alter[i].from);
        CHECK(at != NULL);
        if (!at) continue;
        size_t pre = (size_t)(at - tank), lf = strlen(alter[i].from), lt = strlen(alter[i].to);
        char *t = malloc(len + lt + 1);
        memcpy(t, tank, pre);
        memcpy(t + pre, alter[i].to, lt);
        memcpy(t + pre + lt, at + lf, len - pre - lf + 1);
        tl_write_text(tl_path("v.lmarks"), t);
        thx_landmarks *lm = (thx_landmarks *)1;
        CHECK(thx_landmarks_read(ctx, tl_path("v.lmarks"), &lm) == THX_EINPUT && lm == NULL);
        char want[600];
        snprintf(want, sizeof want, "v.lmarks%s", alter[i].want);
        if (!tl_msg_has(ctx, want)) fprintf(stderr, "  (case %zu)\n", i);
        CHECK(strstr(thx_ctx_message(ctx), want) != NULL);
        free(t);
    }
    free(tank);

    /* made-up files */
    struct {
        const char *text, *want;
    } bad[] = {
        {"", ":1: empty file (expected the number of segments on the first line)"},
        {"# only a comment\n\n", ":2: empty file"},
        {"1\n", ":1: the file declares 1 segment, but the 0 bytes that follow hold at most 0 (a segment takes at "
                   "least 16): a wrong count, or a file cut short"},
        {"1\n#                 \n", ":2: truncated file: 0 of 1 segment (the count on line 1)"},
        {"1\n1 lead 1\n\n\n\n\n\n\n\n", ":9: truncated file: segment 1 (lead, line 2) has 0 of its 1 points"},
        {"1\n1 artery 3\n0 0 0 1\n1 0 0 1\n        \n", ":5: truncated file: segment 1 (artery, line 2) has 2 of its 3 points"},
        {"1\n1 lead 1\n0 0 0 1\n\n2 lead 1\n", ":5: text after the last segment: the file declares 1 segment (line 1)"},
        {"1\n1 artery 2\n0 0 0 1\n0 0 0 2\n", ":2: segment 1 (artery): all 2 points are at one place (0, 0, 0); an "
                                              "artery needs a length"},
        {"1\n1 plane 3\n0 0 0 1\n1 1 1 1\n2 2 2 1\n", ":2: segment 1 (plane): the 3 points are collinear or coincide"},
        {"1\n1 fiber 2\n5 5 5 1\n5 5 5 1\n", ":2: segment 1 (fiber): all 2 points are at one place"},
        {"1\n1 lead 1\n0 0 0 \n", ":3: segment 1 point 1: expected 'X Y Z RADIUS [LABEL]', found 3 fields"},
        {"1\n1 lead 1\n0 0 0 1 a#b\n", NULL}, /* '#' starts a comment: label "a" — accepted, see below */
        {"1\n1 lead\n0 0 0 1\n", ":2: expected the header of segment 1 ('1 TYPE NPOINTS [INDEX] [R G B]'), found 2 fields"},
        {"1\n0 0 0 1\n        \n", ":2: expected the header of segment 1 ('1 TYPE NPOINTS [INDEX] [R G B]'), found a point"},
        {"1\n1 lead 1\n0 0 0 1 l\xe9on\n", ":3: segment 1 point 1: label 'l?on' holds a blank or a character outside"},
        {"1\n1 lead 1\n0,0,0,1\n", ":3: segment 1 point 1: a comma in '0,0,0,1'"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        tl_write_text(tl_path("v.lmarks"), bad[i].text);
        thx_landmarks *lm = NULL;
        thx_status st = thx_landmarks_read(ctx, tl_path("v.lmarks"), &lm);
        if (!bad[i].want) {
            CHECK(st == THX_OK && lm && !strcmp(lm->seg[0].pt[0].label, "a"));
            thx_landmarks_destroy(&lm);
            continue;
        }
        CHECK(st == THX_EINPUT && lm == NULL);
        char want[600];
        snprintf(want, sizeof want, "v.lmarks%s", bad[i].want);
        if (!tl_msg_has(ctx, want)) fprintf(stderr, "  (made-up case %zu)\n", i);
    }
    /* a NUL byte, with its line */
    tl_write_bytes(tl_path("v.lmarks"), "1\n1 lead 1\n0 0\0 0 1\n", 19);
    thx_landmarks *lm = NULL;
    CHECK(thx_landmarks_read(ctx, tl_path("v.lmarks"), &lm) == THX_EINPUT && !lm);
    CHECK(tl_msg_has(ctx, "v.lmarks:3: NUL byte at byte offset 14"));
    /* a missing file */
    CHECK(thx_landmarks_read(ctx, tl_path("none.lmarks"), &lm) == THX_EIO && !lm);
}

/* ------------------------------------------------------------- meshes against closed forms */

static void test_tube_shapes(void)
{
    thx_landmark_mesh_opts o;
    thx_landmark_mesh_opts_default(&o);
    CHECK(o.sides == 12 && o.sphere_level == 2 && o.min_radius == 0.5);
    /* a straight frustum along a skew axis: volume exact for any number of sides */
    int sides[3] = {3, 12, 64};
    for (int k = 0; k < 3; k++) {
        o.sides = sides[k];
        thx_landmark_point pts[2] = {P(1, 2, 3, 2), P(1 + 6, 2 + 3, 3 - 2, 1)}; /* h = 7 */
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, pts, 2, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 7 * (4 + 2 + 1) / 3, 1e-9 * 50);
        CHECK(s && s->n_nodes == (size_t)(2 * sides[k] + 2) && s->n_tris == (size_t)(4 * sides[k]));
        thx_surface_destroy(&s);
        /* closed to a point at the end: a cone, n_sides + 1 + 1 nodes, no degenerate triangle */
        pts[1].radius = 0;
        s = mesh_of(THX_LANDMARK_ARTERY, pts, 2, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 7 * 4 / 3, 1e-9 * 30);
        CHECK(s && s->n_nodes == (size_t)(sides[k] + 2) && s->n_tris == (size_t)(2 * sides[k]));
        thx_surface_destroy(&s);
        /* and at the start */
        pts[1].radius = 1, pts[0].radius = 0;
        s = mesh_of(THX_LANDMARK_CATH, pts, 2, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 7 * 1 / 3, 1e-9 * 10);
        thx_surface_destroy(&s);
    }
    o.sides = 12;
    /* a bend of 90 degrees, constant radius: the mitre keeps the volume pi r^2 (L1 + L2) exactly */
    {
        thx_landmark_point pts[3] = {P(0, 0, 0, 1.5), P(20, 0, 0, 1.5), P(20, 30, 0, 1.5)};
        thx_surface *s = mesh_of(THX_LANDMARK_CANNULA, pts, 3, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 2.25 * 50, 1e-9 * 400);
        thx_surface_destroy(&s);
    }
    /* a zig-zag in the plane z = 5, tapering: parallel transport keeps each ring vertex's height
       above the plane the same on every ring (no twist); volume near the frustum sum */
    {
        thx_landmark_point pts[6] = {P(0, 0, 5, 3), P(10, 4, 5, 2.6), P(20, -3, 5, 2.2), P(28, 8, 5, 1.8),
                                     P(40, 2, 5, 1.4), P(50, 10, 5, 0)};
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, pts, 6, &o);
        CHECK(closed_manifold(s));
        if (s) {
            /* rings: 12 nodes + the start cap's centre, then 12 per station, then the tip */
            int twist_ok = 1;
            for (int j = 0; j < 12; j++) {
                double h0 = s->xyz[3 * (size_t)j + 2] - 5, r0 = 3;
                for (int ring = 1; ring < 5; ring++) {
                    size_t v = 13 + 12 * (size_t)(ring - 1) + (size_t)j;
                    double h = s->xyz[3 * v + 2] - 5, r = pts[ring].radius;
                    if (fabs(h / r - h0 / r0) > 1e-9) twist_ok = 0;
                }
            }
            CHECK(twist_ok);
            thx_landmarks *lm = NULL;
            CHECK_OK(ctx, thx_landmarks_create(ctx, &lm));
            CHECK_OK(ctx, thx_landmarks_add_segment(ctx, lm, THX_LANDMARK_ARTERY, pts, 6, NULL));
            double ref = frustum_sum(&lm->seg[0]), v = thx_surface_volume(s);
            printf("zig-zag tube: volume %.2f, frustum sum %.2f (%.2f%%)\n", v, ref, 100 * (v / ref - 1));
            CHECK(fabs(v / ref - 1) < 0.03);
            thx_landmarks_destroy(&lm);
        }
        thx_surface_destroy(&s);
    }
    /* a repeated point (same place, same radius) is skipped; with another radius it is a step */
    {
        thx_landmark_point pts[4] = {P(0, 0, 0, 2), P(10, 0, 0, 2), P(10, 0, 0, 2), P(20, 0, 0, 2)};
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, pts, 4, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 4 * 20, 1e-8);
        CHECK(s && s->n_nodes == 3 * 12 + 2);
        thx_surface_destroy(&s);
        pts[2].radius = 1;
        pts[3].radius = 1;
        s = mesh_of(THX_LANDMARK_ARTERY, pts, 4, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * (4 * 10 + 1 * 10), 1e-8);
        thx_surface_destroy(&s);
    }
    /* radius 0 inside a tube and everywhere: drawn at min_radius */
    {
        thx_landmark_point pts[3] = {P(0, 0, 0, 1), P(10, 0, 0, 0), P(20, 0, 0, 1)};
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, pts, 3, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, 2 * M_PI * 10 * (1 + 0.5 + 0.25) / 3, 1e-8);
        thx_surface_destroy(&s);
        pts[0].radius = pts[2].radius = 0;
        s = mesh_of(THX_LANDMARK_ARTERY, pts, 3, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 0.25 * 20, 1e-8);
        thx_surface_destroy(&s);
    }
    /* sharp turns: a hairpin and a 170-degree bend stay closed and manifold */
    {
        thx_landmark_point hp[3] = {P(0, 0, 0, 1), P(10, 0, 0, 1), P(0, 0, 0, 0)};
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, hp, 3, &o);
        CHECK(closed_manifold(s));
        thx_surface_destroy(&s);
        thx_landmark_point sh[3] = {P(0, 0, 0, 1), P(10, 0, 0, 1), P(0, 1.7, 0, 1)};
        s = mesh_of(THX_LANDMARK_ARTERY, sh, 3, &o);
        CHECK(closed_manifold(s));
        thx_surface_destroy(&s);
    }
}

static void test_other_shapes(void)
{
    thx_landmark_mesh_opts o;
    thx_landmark_mesh_opts_default(&o);
    /* spheres: nodes on the sphere of the point's radius; two sites -> two closed pieces */
    {
        thx_landmark_point pts[2] = {P(10, 20, 30, 2), P(-5, 0, 0, 0)};
        thx_surface *s = mesh_of(THX_LANDMARK_OCCLUSION, pts, 2, &o);
        CHECK(closed_manifold(s));
        CHECK(s && s->n_nodes == 2 * 162 && s->n_tris == 2 * 320);
        int on = 1;
        for (size_t v = 0; s && v < s->n_nodes; v++) {
            const thx_landmark_point *c = &pts[v < 162 ? 0 : 1];
            double r = c->radius > 0 ? c->radius : o.min_radius;
            double d = thx_v3_norm(thx_v3(s->xyz[3 * v] - c->xyz[0], s->xyz[3 * v + 1] - c->xyz[1], s->xyz[3 * v + 2] - c->xyz[2]));
            if (fabs(d - r) > 1e-12 * 40) on = 0;
        }
        CHECK(on);
        double v = s ? thx_surface_volume(s) : 0, ref = 4.0 / 3 * M_PI * (8 + 0.125);
        CHECK(v < ref && v > 0.95 * ref);
        thx_surface_destroy(&s);
        o.sphere_level = 0;
        s = mesh_of(THX_LANDMARK_LEAD, pts, 1, &o);
        CHECK(closed_manifold(s) && s->n_tris == 20);
        thx_surface_destroy(&s);
        o.sphere_level = 2;
    }
    /* a plane: a disc of radius point 1's radius, thickness point 2's, about the centroid */
    {
        thx_landmark_point pts[3] = {P(0, 0, 10, 20), P(30, 0, 10, 2), P(0, 30, 10, 99)};
        thx_surface *s = mesh_of(THX_LANDMARK_PLANE, pts, 3, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 400 * 2, 1e-8 * 2500);
        int flat = 1;
        for (size_t v = 0; s && v < s->n_nodes; v++) flat &= fabs(s->xyz[3 * v + 2] - 10) <= 1 + 1e-12;
        CHECK(flat);
        double cx = 0;
        for (size_t v = 0; s && v < s->n_nodes; v++) cx += s->xyz[3 * v];
        CHECK_NEAR(s ? cx / (double)s->n_nodes : 0, 10, 1e-9);
        CHECK(s && s->n_nodes == 2 * 48 + 2);
        thx_surface_destroy(&s);
        pts[1].radius = 0; /* thickness 0: min_radius */
        s = mesh_of(THX_LANDMARK_PLANE, pts, 3, &o);
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 400 * 0.5, 1e-8 * 2500);
        thx_surface_destroy(&s);
    }
    /* a rod: point 1's radius along the points; an arrow: shaft + head */
    {
        thx_landmark_point pts[2] = {P(0, 0, 0, 0.4), P(0, 0, 25, 7)};
        thx_surface *s = mesh_of(THX_LANDMARK_ROD, pts, 2, &o);
        CHECK(closed_manifold(s));
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 0.16 * 25, 1e-9);
        thx_surface_destroy(&s);
        s = mesh_of(THX_LANDMARK_FIBER, pts, 2, &o);
        CHECK(closed_manifold(s));
        double hl = fmin(6 * 0.4, 0.4 * 25), R = 2.5 * 0.4;
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 0.16 * (25 - hl) + M_PI * R * R * hl / 3, 1e-9);
        double top = -INFINITY;
        for (size_t v = 0; s && v < s->n_nodes; v++) top = fmax(top, s->xyz[3 * v + 2]);
        CHECK(top == 25); /* the tip at the last point */
        thx_surface_destroy(&s);
        pts[0].radius = 0; /* radius 0: min_radius */
        s = mesh_of(THX_LANDMARK_RECNEEDLE, pts, 2, &o); /* a needle site: spheres at both points */
        CHECK(closed_manifold(s) && s->n_nodes == 2 * 162);
        thx_surface_destroy(&s);
        s = mesh_of(THX_LANDMARK_ROD, pts, 2, &o);
        CHECK_NEAR(s ? thx_surface_volume(s) : 0, M_PI * 0.25 * 25, 1e-9);
        thx_surface_destroy(&s);
    }
    /* colours: the file's wins; defaults by type */
    {
        thx_landmark_segment g;
        memset(&g, 0, sizeof g);
        float c[4];
        g.type = THX_LANDMARK_CLOSURE;
        thx_landmark_color(&g, c);
        CHECK(c[0] == 0 && c[1] == 0 && c[2] == 1 && c[3] == 1);
        g.type = THX_LANDMARK_PLANE;
        g.has_color = 1, g.rgb[0] = 255, g.rgb[1] = 51, g.rgb[2] = 0;
        thx_landmark_color(&g, c);
        CHECK(c[0] == 1 && fabsf(c[1] - 0.2f) < 1e-7f && c[2] == 0 && c[3] == 0.5f);
    }
    /* options out of range, and an invalid segment, refused */
    {
        thx_landmark_point pts[2] = {P(0, 0, 0, 1), P(1, 0, 0, 1)};
        o.sides = 2;
        thx_surface *s = mesh_of(THX_LANDMARK_ARTERY, pts, 2, &o);
        CHECK(!s && tl_msg_has(ctx, "sides 2 out of range 3..256"));
        thx_landmark_mesh_opts_default(&o);
        o.min_radius = 0;
        s = mesh_of(THX_LANDMARK_ROD, pts, 2, &o);
        CHECK(!s && tl_msg_has(ctx, "minimum radius 0 mm is not in [0.001, 1e+07]"));
        thx_landmark_mesh_opts_default(&o);
        pts[1].xyz[0] = NAN;
        s = mesh_of(THX_LANDMARK_ROD, pts, 2, &o);
        CHECK(!s && tl_msg_has(ctx, "segment 1 point 2: x = nan is not a finite number"));
    }
    /* a set read from a file: the mesh errors name the file and segment line */
    {
        tl_write_text(tl_path("m.lmarks"), "1\n1 lead 1\n0 0 0 1\n");
        thx_landmarks *lm = NULL;
        CHECK_OK(ctx, thx_landmarks_read(ctx, tl_path("m.lmarks"), &lm));
        if (lm) {
            lm->seg[0].pt[0].radius = -3;
            thx_landmark_meshes *m = NULL;
            CHECK(thx_landmarks_mesh(ctx, lm, NULL, &m) == THX_EINPUT && !m);
            CHECK(tl_msg_has(ctx, "m.lmarks:2: segment 1 point 1: radius -3"));
        }
        thx_landmarks_destroy(&lm);
    }
}

int main(void)
{
    snprintf(data_dir, sizeof data_dir, "%s", __FILE__);
    char *slash = strrchr(data_dir, '/');
    if (slash) *slash = '\0';
    else snprintf(data_dir, sizeof data_dir, ".");
    strncat(data_dir, "/../../shared/data", sizeof data_dir - strlen(data_dir) - 1);
    if (thx_ctx_create(&ctx) != THX_OK || tl_scratch_make("test_landmarks") != 0) return 1;
    test_real_tank();
    test_real_dalepi();
    test_real_meshes();
    test_round_trip();
    test_variants();
    test_bad_inputs();
    test_tube_shapes();
    test_other_shapes();
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_landmarks");
}
