/*
 * Tests of surface import (src/io/surface/import.c): every format written here by
 * hand (a cube, and variants) and read back; the index base of .fac and .tri;
 * OpenMEEG's .tri (normals, strict counts);
 * OBJ quads, v/vt/vn and negative indices; STL vertex merging; PLY ascii and
 * both binary byte orders; legacy VTK (ASCII, 5.1 offsets, binary, strips);
 * VTP; errors naming file and line (or byte); the import policy (unused
 * nodes removed, inward surfaces reversed, open or inconsistent ones refused,
 * --force, scale).
 *
 * The cube: node i at (i&1 ? 8.25 : -1.5, i&2 ? 8.25 : -1.5, i&4 ? 12.5 : 2)
 * (values exact in float32, so binary STL reproduces them), six quads
 * counterclockwise seen from outside, each split (a,b,c),(a,c,d).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdint.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/import/import.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static thx_ctx *ctx;

static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

static double cube_x(int i, int k)
{
    if (k == 0) return (i & 1) ? 8.25 : -1.5;
    if (k == 1) return (i & 2) ? 8.25 : -1.5;
    return (i & 4) ? 12.5 : 2.0;
}

/* Triangle t of the cube (0..11) as node numbers. */
static void cube_tri(int t, int v[3])
{
    const int *q = quads[t / 2];
    v[0] = q[0];
    v[1] = t % 2 ? q[2] : q[1];
    v[2] = t % 2 ? q[3] : q[2];
}

/* A growable text buffer. */
typedef struct { char *p; size_t n, cap; } sbuf;
static void sb_printf(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_printf(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int need = vsnprintf(b->p ? b->p + b->n : NULL, b->p ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (b->p && b->n + (size_t)need < b->cap) {
            b->n += (size_t)need;
            return;
        }
        b->cap = 2 * (b->cap + (size_t)need + 64);
        b->p = realloc(b->p, b->cap);
        if (!b->p) exit(1);
    }
}
static void sb_bytes(sbuf *b, const void *d, size_t n)
{
    if (b->n + n + 1 > b->cap) {
        b->cap = 2 * (b->n + n + 64);
        b->p = realloc(b->p, b->cap);
        if (!b->p) exit(1);
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}
static void put_le(sbuf *b, uint64_t v, int n)
{
    unsigned char c[8];
    for (int i = 0; i < n; i++) c[i] = (unsigned char)(v >> (8 * i));
    sb_bytes(b, c, (size_t)n);
}
static void put_be(sbuf *b, uint64_t v, int n)
{
    unsigned char c[8];
    for (int i = 0; i < n; i++) c[i] = (unsigned char)(v >> (8 * (n - 1 - i)));
    sb_bytes(b, c, (size_t)n);
}
static uint32_t f32_bits(double d)
{
    float f = (float)d;
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}
static uint64_t f64_bits(double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    return u;
}

/* Does s have the cube's triangles, corner by corner (coordinates exactly,
 * orientation kept), and nn nodes? */
static int is_cube(const thx_surface *s, size_t nn)
{
    if (!s || s->n_nodes != nn || s->n_tris != 12) return 0;
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                if (s->xyz[3 * (size_t)s->tri[3 * t + c] + (size_t)k] != cube_x(v[c], k)) return 0;
    }
    return 1;
}

static int contains(const char *hay, const char *needle)
{
    if (!strstr(hay, needle)) {
        fprintf(stderr, "  message \"%s\" lacks \"%s\"\n", hay, needle);
        return 0;
    }
    return 1;
}

/* Reads (no checks) and returns the surface, or NULL with the message printed. */
static thx_surface *rd(const char *path, thx_import_info *info)
{
    thx_surface *s = NULL;
    memset(info, 0, sizeof *info);
    thx_status st = thx_surface_read_file(ctx, path, NULL, THX_IMPORT_AUTO, "cube", THX_ROLE_HEART, &s, &info->read);
    if (st) fprintf(stderr, "  reading %s: %s\n", path, thx_ctx_message(ctx));
    return s;
}

/* Imports with the policy; checks it passed. */
static thx_surface *imp(const char *path, const thx_import_opts *o, thx_import_info *info)
{
    thx_surface *s = NULL;
    thx_status st = thx_surface_import(ctx, path, NULL, "cube", THX_ROLE_HEART, o, &s, info);
    if (st) fprintf(stderr, "  importing %s: %s\n", path, thx_ctx_message(ctx));
    return s;
}

/* ------------------------------------------------------------------ pts/fac */

static void write_ptsfac(const char *stem, int base)
{
    sbuf p = {0}, f = {0};
    for (int i = 0; i < 8; i++) sb_printf(&p, "%.3f %.3f %.3f\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        sb_printf(&f, "%d %d %d\n", v[0] + base, v[1] + base, v[2] + base);
    }
    char path[2048];
    snprintf(path, sizeof path, "%s.pts", tl_path(stem));
    tl_write_bytes(path, p.p, p.n);
    snprintf(path, sizeof path, "%s.fac", tl_path(stem));
    tl_write_bytes(path, f.p, f.n);
    free(p.p);
    free(f.p);
}

static void test_ptsfac(void)
{
    thx_import_info in;
    thx_surface *s;
    write_ptsfac("one", 1);
    write_ptsfac("zero", 0);
    s = rd(tl_path("one.pts"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.format == THX_IMPORT_PTSFAC && in.read.index_base == 1 && in.read.index_base_detected == 1);
    CHECK(strstr(in.read.path2, "one.fac") != NULL);
    thx_surface_destroy(&s);
    s = rd(tl_path("zero.pts"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.index_base == 0 && in.read.index_base_detected == 1);
    thx_surface_destroy(&s);
    /* the .fac named first: the .pts is found beside it */
    s = rd(tl_path("zero.fac"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.index_base == 0 && strstr(in.read.path2, "zero.pts") != NULL);
    thx_surface_destroy(&s);
    /* an explicit second file */
    CHECK_OK(ctx, thx_surface_read_file(ctx, tl_path("one.pts"), tl_path("one.fac"), THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL));
    CHECK(is_cube(s, 8));
    thx_surface_destroy(&s);
    /* the full import passes the checks */
    s = imp(tl_path("one.pts"), NULL, &in);
    CHECK(is_cube(s, 8) && in.report.ok && !in.reversed && in.n_unused_removed == 0);
    CHECK(in.report.solid_angle_rel_err < 1e-12);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
}

/* ------------------------------------------------------------------ .tri */

/* ECGSim text: labelled or not; base 1 or 0; stream = everything on few lines;
 * cw = triangles clockwise seen from outside (ECGSim's own convention). */
static void write_tri(const char *name, int labelled, int base, int stream, int cw, double unit, const char *trailer)
{
    sbuf b = {0};
    const char *nl = stream ? " " : "\n";
    sb_printf(&b, "%d%s", 8, "\n");
    for (int i = 0; i < 8; i++) {
        if (labelled) sb_printf(&b, "%d ", i + 1);
        sb_printf(&b, "%.6f %.6f %.6f%s", cube_x(i, 0) * unit, cube_x(i, 1) * unit, cube_x(i, 2) * unit, nl);
    }
    sb_printf(&b, "%s12\n", stream ? "\n" : "");
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        if (labelled) sb_printf(&b, "%d\t", t + 1);
        if (cw) sb_printf(&b, "%d %d %d%s", v[0] + base, v[2] + base, v[1] + base, nl);
        else sb_printf(&b, "%d %d %d%s", v[0] + base, v[1] + base, v[2] + base, nl);
    }
    if (trailer) sb_printf(&b, "\n%s", trailer);
    tl_write_bytes(tl_path(name), b.p, b.n);
    free(b.p);
}

static void test_tri(void)
{
    thx_import_info in;
    thx_surface *s;
    write_tri("lab.tri", 1, 1, 0, 0, 1, NULL);
    s = rd(tl_path("lab.tri"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.format == THX_IMPORT_TRI && in.read.index_base == 1 && in.read.index_base_detected && in.read.trailer_line == 0);
    CHECK(strstr(in.read.format_detail, "labelled nodes") != NULL);
    thx_surface_destroy(&s);

    write_tri("unlab.tri", 0, 1, 0, 0, 1, NULL);
    s = rd(tl_path("unlab.tri"), &in);
    CHECK(is_cube(s, 8));
    CHECK(strstr(in.read.format_detail, "unlabelled nodes") != NULL);
    thx_surface_destroy(&s);

    write_tri("zero.tri", 1, 0, 0, 0, 1, NULL);
    s = rd(tl_path("zero.tri"), &in);
    CHECK(is_cube(s, 8) && in.read.index_base == 0);
    thx_surface_destroy(&s);

    /* free line breaks (the format allows them): labels found by counting */
    write_tri("stream.tri", 1, 1, 1, 0, 1, NULL);
    s = rd(tl_path("stream.tri"), &in);
    CHECK(is_cube(s, 8));
    CHECK(strstr(in.read.format_detail, "labelled nodes") != NULL);
    thx_surface_destroy(&s);
    write_tri("stream0.tri", 0, 1, 1, 0, 1, NULL);
    s = rd(tl_path("stream0.tri"), &in);
    CHECK(is_cube(s, 8));
    thx_surface_destroy(&s);

    /* a descriptive trailer (PhysioNet 2007 files) is ignored and reported */
    write_tri("trailer.tri", 1, 1, 0, 0, 1, "case 3 thorax\nunits mm\n");
    s = rd(tl_path("trailer.tri"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.trailer_line == 24); /* 1 + 8 + 1 + 12 lines, a blank one, then the text */
    thx_surface_destroy(&s);

    /* ECGSim's own convention: clockwise seen from outside, metres. Import
     * reverses it (reported) and --scale 1000 gives mm. */
    write_tri("ecgsim.tri", 1, 1, 0, 1, 0.001, NULL);
    thx_import_opts o;
    thx_import_opts_default(&o);
    o.scale = 1000;
    s = imp(tl_path("ecgsim.tri"), &o, &in);
    CHECK(s != NULL && in.reversed == 1 && in.report.ok && in.report.volume > 0);
    CHECK_NEAR(in.omega_before, -4 * M_PI, 1e-9);
    CHECK(s && s->n_nodes == 8);
    if (s) CHECK_NEAR(s->xyz[3 * 7 + 2], 12.5, 1e-9);
    CHECK_NEAR(in.extent, 12.5 - 2.0, 1e-9);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
    /* without the scale, the extent (a units hint) is tiny */
    s = imp(tl_path("ecgsim.tri"), NULL, &in);
    CHECK(s != NULL && in.extent < 0.1);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
}

/* ------------------------------------------------------- OpenMEEG .tri */

/* The cube in OpenMEEG's .tri: "- 8", vertex lines with (unused) normals,
 * "- 12 12 12", 0-based triangles; cw = clockwise seen from outside (as the
 * OpenMEEG sphere files have them). */
static void write_openmeeg(const char *name, int cw)
{
    sbuf b = {0};
    sb_printf(&b, "- 8\n");
    for (int i = 0; i < 8; i++)
        sb_printf(&b, "%g %g %g %g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2), (i & 1) ? 0.57735 : -0.57735,
                  (i & 2) ? 0.57735 : -0.57735, (i & 4) ? 0.57735 : -0.57735);
    sb_printf(&b, "- 12 12 12\n");
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        if (cw) sb_printf(&b, "%d %d %d\n", v[0], v[2], v[1]);
        else sb_printf(&b, "%d %d %d\n", v[0], v[1], v[2]);
    }
    tl_write_bytes(tl_path(name), b.p, b.n);
    free(b.p);
}

static void test_openmeeg(void)
{
    thx_import_info in;
    write_openmeeg("om.tri", 0);
    thx_surface *s = rd(tl_path("om.tri"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.format == THX_IMPORT_TRI && strstr(in.read.format_detail, "OpenMEEG") != NULL);
    CHECK(in.read.index_base == 0 && in.read.index_base_detected == 0 && in.read.trailer_line == 0);
    thx_surface_destroy(&s);
    /* clockwise, as OpenMEEG's sphere files: reversed by the policy, then the cube exactly */
    write_openmeeg("om_cw.tri", 1);
    s = imp(tl_path("om_cw.tri"), NULL, &in);
    CHECK(is_cube(s, 8) && in.reversed && in.report.ok);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
    /* blank lines and CRLF are allowed; the normals are not used (any numbers) */
    s = NULL;
    tl_write_text(tl_path("om_crlf.tri"), "- 4\r\n0 0 0 9 9 9\r\n1 0 0 0 0 0\r\n\r\n0 1 0 1 1 1\r\n0 0 1 -1 -1 -1\r\n"
                                          "- 4 4 4\r\n0 2 1\r\n0 1 3\r\n0 3 2\r\n1 2 3\r\n\r\n");
    s = rd(tl_path("om_crlf.tri"), &in);
    CHECK(s && s->n_nodes == 4 && s->n_tris == 4 && s->tri[3 * 3 + 2] == 3 && s->xyz[3 * 3 + 2] == 1.0);
    thx_surface_destroy(&s);
}

/* ------------------------------------------------------------------ OBJ */

static void test_obj(void)
{
    thx_import_info in;
    thx_surface *s;
    sbuf b = {0};
    sb_printf(&b, "# cube\nmtllib cube.mtl\no cube\n");
    for (int i = 0; i < 8; i++) sb_printf(&b, "v %g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    sb_printf(&b, "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ns off\nusemtl skin\n");
    /* every syntax of a face vertex, and quads */
    sb_printf(&b, "f %d/1 %d/2 %d/3 %d/1\n", quads[0][0] + 1, quads[0][1] + 1, quads[0][2] + 1, quads[0][3] + 1);
    sb_printf(&b, "f %d//1 %d//1 %d//1 %d//1\n", quads[1][0] + 1, quads[1][1] + 1, quads[1][2] + 1, quads[1][3] + 1);
    sb_printf(&b, "f %d/1/1 %d/2/1 %d/3/1 %d/1/1\n", quads[2][0] + 1, quads[2][1] + 1, quads[2][2] + 1, quads[2][3] + 1);
    /* negative: -1 is the last vertex (node 7), -8 the first */
    for (int q = 3; q < 6; q++)
        sb_printf(&b, "f %d %d %d %d\n", quads[q][0] - 8, quads[q][1] - 8, quads[q][2] - 8, quads[q][3] - 8);
    sb_printf(&b, "l 1 2\n");
    tl_write_bytes(tl_path("cube.obj"), b.p, b.n);
    s = rd(tl_path("cube.obj"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.format == THX_IMPORT_OBJ && in.read.index_base == 1 && !in.read.index_base_detected);
    CHECK(in.read.n_polygons_split == 6 && in.read.n_cells_ignored == 1);
    thx_surface_destroy(&s);

    /* an unused vertex: removed and reported (numbered as in the file) */
    b.n = 0;
    sb_printf(&b, "v 100 100 100\n");
    for (int i = 0; i < 8; i++) sb_printf(&b, "v %g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        sb_printf(&b, "f %d %d %d\n", v[0] + 2, v[1] + 2, v[2] + 2);
    }
    tl_write_bytes(tl_path("unused.obj"), b.p, b.n);
    s = imp(tl_path("unused.obj"), NULL, &in);
    CHECK(is_cube(s, 8) && in.n_unused_removed == 1 && in.first_unused == 1 && in.report.ok);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
    free(b.p);
}

/* ------------------------------------------------------------------ STL */

static void test_stl(void)
{
    thx_import_info in;
    thx_surface *s;
    /* binary, with a header starting "solid" (allowed; the size decides) */
    sbuf b = {0};
    char header[80] = "solid but binary";
    sb_bytes(&b, header, 80);
    put_le(&b, 12, 4);
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        for (int k = 0; k < 3; k++) put_le(&b, f32_bits(0), 4);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) put_le(&b, f32_bits(cube_x(v[c], k)), 4);
        put_le(&b, 0, 2);
    }
    tl_write_bytes(tl_path("bin.stl"), b.p, b.n);
    s = rd(tl_path("bin.stl"), &in);
    CHECK(is_cube(s, 8));
    CHECK(in.read.index_base == -1 && in.read.n_corners_merged == 36 - 8);
    CHECK(strcmp(in.read.format_detail, "binary STL") == 0);
    thx_surface_destroy(&s);
    /* a binary file cut short: neither binary nor ASCII, said at byte 0 */
    tl_write_bytes(tl_path("short.stl"), b.p + 5, b.n - 20);
    CHECK(thx_surface_read_file(ctx, tl_path("short.stl"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "short.stl: byte 0:"));

    /* ASCII, -0 written for one coordinate (same point as +0) */
    b.n = 0;
    sb_printf(&b, "solid cube\n");
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        sb_printf(&b, "  facet normal 0 0 0\n    outer loop\n");
        for (int c = 0; c < 3; c++) sb_printf(&b, "      vertex %g %g %g\n", cube_x(v[c], 0), cube_x(v[c], 1), cube_x(v[c], 2));
        sb_printf(&b, "    endloop\n  endfacet\n");
    }
    sb_printf(&b, "endsolid cube\n");
    tl_write_bytes(tl_path("ascii.stl"), b.p, b.n);
    s = rd(tl_path("ascii.stl"), &in);
    CHECK(is_cube(s, 8) && in.read.n_corners_merged == 28 && strcmp(in.read.format_detail, "ASCII STL") == 0);
    thx_surface_destroy(&s);
    /* an error names the line */
    char *bad = strdup(b.p);
    char *p = strstr(bad, "vertex 8.25");
    memcpy(p, "vertex xxxx", 11);
    tl_write_text(tl_path("bad.stl"), bad);
    CHECK(thx_surface_read_file(ctx, tl_path("bad.stl"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    int line = 1;
    for (char *q = bad; q < p; q++) line += *q == '\n';
    char want[64];
    snprintf(want, sizeof want, "bad.stl:%d:", line);
    CHECK(contains(thx_ctx_message(ctx), want));
    free(bad);
    free(b.p);
}

/* ------------------------------------------------------------------ PLY */

static void test_ply(void)
{
    thx_import_info in;
    thx_surface *s;
    sbuf b = {0};
    /* ascii, an extra vertex property, quads, an extra element */
    sb_printf(&b, "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 8\r\nproperty float x\r\n"
                  "property float y\r\nproperty float z\r\nproperty uchar red\r\nelement face 6\r\n"
                  "property list uchar int vertex_indices\r\nelement edge 1\r\nproperty int vertex1\r\n"
                  "property int vertex2\r\nend_header\r\n");
    for (int i = 0; i < 8; i++) sb_printf(&b, "%g %g %g 255\r\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    for (int q = 0; q < 6; q++) sb_printf(&b, "4 %d %d %d %d\r\n", quads[q][0], quads[q][1], quads[q][2], quads[q][3]);
    sb_printf(&b, "0 1\r\n");
    tl_write_bytes(tl_path("ascii.ply"), b.p, b.n);
    s = rd(tl_path("ascii.ply"), &in);
    CHECK(is_cube(s, 8) && in.read.n_polygons_split == 6 && in.read.index_base == 0);
    CHECK(strcmp(in.read.format_detail, "ascii PLY") == 0);
    thx_surface_destroy(&s);

    /* binary little-endian: float coordinates, a list property before the indices */
    b.n = 0;
    sb_printf(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nproperty uchar alpha\nelement face 12\nproperty list uchar float texcoord\n"
                  "property list uchar int vertex_indices\nend_header\n");
    for (int i = 0; i < 8; i++) {
        for (int k = 0; k < 3; k++) put_le(&b, f32_bits(cube_x(i, k)), 4);
        put_le(&b, 7, 1);
    }
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        put_le(&b, 2, 1);
        put_le(&b, f32_bits(0.5), 4);
        put_le(&b, f32_bits(0.25), 4);
        put_le(&b, 3, 1);
        for (int c = 0; c < 3; c++) put_le(&b, (uint32_t)v[c], 4);
    }
    tl_write_bytes(tl_path("le.ply"), b.p, b.n);
    s = rd(tl_path("le.ply"), &in);
    CHECK(is_cube(s, 8) && strcmp(in.read.format_detail, "binary little-endian PLY") == 0);
    thx_surface_destroy(&s);
    /* truncated: the byte offset is named */
    tl_write_bytes(tl_path("trunc.ply"), b.p, b.n - 3);
    CHECK(thx_surface_read_file(ctx, tl_path("trunc.ply"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "trunc.ply: byte "));
    CHECK(contains(thx_ctx_message(ctx), "face 12"));

    /* binary big-endian: double coordinates, uint8 count, uint32 indices */
    b.n = 0;
    sb_printf(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
                  "property double z\nelement face 6\nproperty list uint8 uint32 vertex_index\nend_header\n");
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) put_be(&b, f64_bits(cube_x(i, k)), 8);
    for (int q = 0; q < 6; q++) {
        put_be(&b, 4, 1);
        for (int c = 0; c < 4; c++) put_be(&b, (uint32_t)quads[q][c], 4);
    }
    tl_write_bytes(tl_path("be.ply"), b.p, b.n);
    s = rd(tl_path("be.ply"), &in);
    CHECK(is_cube(s, 8) && strcmp(in.read.format_detail, "binary big-endian PLY") == 0);
    thx_surface_destroy(&s);

    /* an index out of range names the line */
    b.n = 0;
    sb_printf(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    tl_write_bytes(tl_path("range.ply"), b.p, b.n);
    CHECK(thx_surface_read_file(ctx, tl_path("range.ply"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "range.ply:13:"));
    CHECK(contains(thx_ctx_message(ctx), "node number 3 out of range 0..2"));
    free(b.p);
}

/* ------------------------------------------------------------------ VTK */

static void test_vtk(void)
{
    thx_import_info in;
    thx_surface *s;
    sbuf b = {0};
    /* legacy ASCII: quads, a LINES cell, attributes after the geometry */
    sb_printf(&b, "# vtk DataFile Version 3.0\ncube\nASCII\nDATASET POLYDATA\nPOINTS 8 float\n");
    for (int i = 0; i < 8; i++) sb_printf(&b, "%g %g %g%s", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2), i % 2 ? "\n" : " ");
    sb_printf(&b, "LINES 1 3\n2 0 1\nPOLYGONS 6 30\n");
    for (int q = 0; q < 6; q++) sb_printf(&b, "4 %d %d %d %d\n", quads[q][0], quads[q][1], quads[q][2], quads[q][3]);
    sb_printf(&b, "POINT_DATA 8\nSCALARS p float 1\nLOOKUP_TABLE default\n0 0 0 0 0 0 0 0\n");
    tl_write_bytes(tl_path("legacy.vtk"), b.p, b.n);
    s = rd(tl_path("legacy.vtk"), &in);
    CHECK(is_cube(s, 8) && in.read.n_polygons_split == 6 && in.read.n_cells_ignored == 1);
    CHECK(strcmp(in.read.format_detail, "legacy VTK ASCII POLYDATA") == 0);
    thx_surface_destroy(&s);

    /* file version 5.1 (VTK 9 writers): OFFSETS / CONNECTIVITY, METADATA */
    b.n = 0;
    sb_printf(&b, "# vtk DataFile Version 5.1\ncube\nASCII\nDATASET POLYDATA\nPOINTS 8 double\n");
    for (int i = 0; i < 8; i++) sb_printf(&b, "%g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    sb_printf(&b, "METADATA\nINFORMATION 0\n\nPOLYGONS 13 36\nOFFSETS vtktypeint64\n");
    for (int t = 0; t <= 12; t++) sb_printf(&b, "%d ", 3 * t);
    sb_printf(&b, "\nCONNECTIVITY vtktypeint64\n");
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        sb_printf(&b, "%d %d %d\n", v[0], v[1], v[2]);
    }
    tl_write_bytes(tl_path("v51.vtk"), b.p, b.n);
    s = rd(tl_path("v51.vtk"), &in);
    CHECK(is_cube(s, 8));
    thx_surface_destroy(&s);

    /* legacy BINARY (big-endian), triangle strips: a quad (a,b,c,d) split
     * (a,b,c),(a,c,d) is the strip b,c,a,d */
    b.n = 0;
    sb_printf(&b, "# vtk DataFile Version 3.0\ncube\nBINARY\nDATASET POLYDATA\nPOINTS 8 float\n");
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) put_be(&b, f32_bits(cube_x(i, k)), 4);
    sb_printf(&b, "\nTRIANGLE_STRIPS 6 30\n");
    for (int q = 0; q < 6; q++) {
        put_be(&b, 4, 4);
        put_be(&b, (uint32_t)quads[q][1], 4);
        put_be(&b, (uint32_t)quads[q][2], 4);
        put_be(&b, (uint32_t)quads[q][0], 4);
        put_be(&b, (uint32_t)quads[q][3], 4);
    }
    sb_printf(&b, "\n");
    tl_write_bytes(tl_path("bin.vtk"), b.p, b.n);
    s = rd(tl_path("bin.vtk"), &in);
    /* the strip gives (b,c,a) and (a,c,d): the same triangles, rotated */
    int ok = s && s->n_nodes == 8 && s->n_tris == 12;
    for (int t = 0; ok && t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        int r = t % 2 ? 0 : 2; /* (b,c,a) is (a,b,c) rotated by 2 */
        for (int c = 0; c < 3; c++) ok = ok && s->tri[3 * t + (c + r) % 3] == v[c];
    }
    CHECK(ok);
    CHECK(strcmp(in.read.format_detail, "legacy VTK binary POLYDATA") == 0);
    thx_surface_destroy(&s);

    /* not a surface dataset */
    tl_write_text(tl_path("grid.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 float\n");
    CHECK(thx_surface_read_file(ctx, tl_path("grid.vtk"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "grid.vtk:4:"));
    CHECK(contains(thx_ctx_message(ctx), "only POLYDATA"));
    free(b.p);
}

/* ------------------------------------------ our own exports, VTP, round trips */

static void make_cube(thx_surface **out)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, "cube", THX_ROLE_HEART, &s) != THX_OK) exit(1);
    s->n_nodes = 8;
    s->n_tris = 12;
    s->xyz = malloc(24 * sizeof *s->xyz);
    s->tri = malloc(36 * sizeof *s->tri);
    if (!s->xyz || !s->tri) exit(1);
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) s->xyz[3 * i + k] = cube_x(i, k);
    for (int t = 0; t < 12; t++) {
        int v[3];
        cube_tri(t, v);
        for (int c = 0; c < 3; c++) s->tri[3 * t + c] = v[c];
    }
    *out = s;
}

static void test_exports(void)
{
    thx_surface *cube = NULL;
    make_cube(&cube);
    const char *ext[] = {"vtk", "vtp", "obj", "stl", "ply"};
    for (int f = 0; f < 5; f++) {
        thx_export_format fmt;
        char name[32];
        snprintf(name, sizeof name, "export.%s", ext[f]);
        CHECK(thx_export_format_parse(ext[f], &fmt) == 0);
        CHECK_OK(ctx, thx_surface_export(ctx, cube, fmt, tl_path(name)));
        thx_import_info in;
        thx_surface *s = imp(tl_path(name), NULL, &in);
        CHECK(is_cube(s, 8) && in.report.ok && !in.reversed);
        if (!is_cube(s, 8)) fprintf(stderr, "  round trip through %s failed\n", ext[f]);
        thx_import_info_free(&in);
        thx_surface_destroy(&s);
    }
    /* the format may be given when the extension says nothing */
    CHECK_OK(ctx, thx_surface_export(ctx, cube, THX_EXPORT_PLY, tl_path("noext")));
    thx_surface *s = NULL;
    CHECK(thx_surface_read_file(ctx, tl_path("noext"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "cannot tell the format"));
    CHECK_OK(ctx, thx_surface_read_file(ctx, tl_path("noext"), NULL, THX_IMPORT_PLY, "c", THX_ROLE_OUTER, &s, NULL));
    CHECK(is_cube(s, 8));
    thx_surface_destroy(&s);
    /* binary VTP is refused with a reason */
    tl_write_text(tl_path("bin.vtp"), "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\">\n<PolyData>\n"
                              "<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n<Points>\n"
                              "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"binary\">AAAA</DataArray>\n"
                              "</Points>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    CHECK(thx_surface_read_file(ctx, tl_path("bin.vtp"), NULL, THX_IMPORT_AUTO, "c", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "bin.vtp:6:"));
    CHECK(contains(thx_ctx_message(ctx), "only format=\"ascii\""));
    thx_surface_destroy(&cube);
}

/* ------------------------------------------------------------ errors */

static void expect_error(const char *name, const char *text, const char *where, const char *what)
{
    tl_write_text(tl_path(name), text);
    thx_surface *s = NULL;
    thx_status st = thx_surface_read_file(ctx, tl_path(name), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL);
    CHECK(st == THX_EINPUT && s == NULL);
    char want[256];
    snprintf(want, sizeof want, "%s:%s", name, where);
    CHECK(contains(thx_ctx_message(ctx), want));
    CHECK(contains(thx_ctx_message(ctx), "surface \"skin\""));
    CHECK(contains(thx_ctx_message(ctx), what));
}

static void test_errors(void)
{
    expect_error("e1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 4\n", "5:", "face refers to vertex 4 but 3 vertices");
    expect_error("e2.obj", "v 0 0 0\nv 1 0 zz\n", "2:", "vertex 2: coordinate 3 is not a finite number");
    expect_error("e3.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "3:", "at least 3 vertices, this one has 2");
    expect_error("e4.obj", "v 0 0 0\nf 1/2/3 0 1\n", "2:", "face vertex \"0\" is not a vertex number");
    expect_error("e5.obj", "v 0 0 0\nf -2 1 1\n", "2:", "face refers to vertex -2");
    expect_error("e1.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n1\n1 1 2 4\n", "6:", "node number 4 out of range 1..3");
    expect_error("e2.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1 nan\n1\n1 1 2 3\n", "4:", "node 3: coordinate 3 is not a finite");
    expect_error("e3.tri", "x\n", "1:", "expected the number of nodes");
    expect_error("e4.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1\n", "4:", "file ends at node 3 of 3");
    expect_error("e4b.tri", "3\n1 0 0 0\n2 1 0 0\n", "1:", "3 nodes declared, but the file holds only 8 numbers");
    /* OpenMEEG .tri: counts beyond the file, indices out of range, missing normals, trailing text */
    expect_error("om1.tri", "- 100\n0 0 0 0 0 1\n1 0 0 0 0 1\n", "1:", "100 vertices declared, but the 25 bytes that follow can hold at most 3");
    expect_error("om1b.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n", "3:", "file ends at vertex 3 of 3");
    expect_error("om2.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 1 1 1\n0 1 3\n", "6:",
                 "node number 3 out of range 0..2");
    expect_error("om3.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0\n0 1 0 0 0 1\n- 1 1 1\n0 1 2\n", "3:",
                 "vertex 2: normal z is missing");
    expect_error("om4.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 x 1\n0 1 0 0 0 1\n- 1 1 1\n0 1 2\n", "3:",
                 "vertex 2: normal y is not a finite number");
    expect_error("om5.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 3 3 3\n0 1 2\n2 1 0\n", "7:",
                 "file ends at triangle 3 of 3");
    expect_error("om5b.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 5 5 5\n0 1 2\n2 1 0\n", "5:",
                 "5 triangles declared, but the 13 bytes that follow can hold at most 3");
    expect_error("om6.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 1 2 1\n0 1 2\n", "5:",
                 "one triangle count, repeated");
    expect_error("om7.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 1 1 1\n0 1 2\nextra\n", "7:",
                 "unexpected \"extra\" after the last of the 1 triangles");
    expect_error("om8.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 1 1 1\n0 1\n", "6:",
                 "triangle 1: vertex number 3 is missing");
    expect_error("om9.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1 7\n", "3:", "vertex 2: more than six numbers");
    expect_error("om10.tri", "- 2\n0 0 0 0 0 1\n1 0 0 0 0 1\n", "3:", "file ends after the vertices");
    expect_error("e1.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                           "POLYGONS 1 4\n3 0 1 7\n", "7:", "node number 7 out of range 0..2");
    expect_error("e2.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n0 1\n",
                 "8:", "file ends before POINTS value 9");
    expect_error("e3.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2000000000 float\n0 0 0\n",
                 "5:", "POINTS: 6000000000 values declared, but the file is too short");
    expect_error("e1.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", "3:",
                 "lacks scalar properties x, y and z");
    expect_error("e1.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n",
                 "3:", "at least 3 vertices, this one has 2");
    expect_error("e2.stl", "solid x\nfacet normal 0 0 1\nfoo\n", "3:", "unexpected \"foo\"");
    /* .pts/.fac errors come from the pair reader, also naming file and line */
    tl_write_text(tl_path("e1.pts"), "0 0 0\n1 0 0\n0 1 0\n");
    tl_write_text(tl_path("e1.fac"), "1 2 3\n1 2 5\n");
    thx_surface *s = NULL;
    CHECK(thx_surface_read_file(ctx, tl_path("e1.pts"), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
    CHECK(contains(thx_ctx_message(ctx), "e1.fac:2:"));
    /* a missing file */
    CHECK(thx_surface_read_file(ctx, tl_path("none.obj"), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL) == THX_EIO);
    CHECK(contains(thx_ctx_message(ctx), "none.obj"));
}

/* ------------------------------------------------------------ policy */

/* The cube as OBJ with triangle t reversed if mask bit t is set, and
 * triangles with bit t of drop set left out. */
static void write_cube_obj(const char *name, unsigned reverse, unsigned drop)
{
    sbuf b = {0};
    for (int i = 0; i < 8; i++) sb_printf(&b, "v %g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    for (int t = 0; t < 12; t++) {
        if (drop >> t & 1) continue;
        int v[3];
        cube_tri(t, v);
        if (reverse >> t & 1) sb_printf(&b, "f %d %d %d\n", v[0] + 1, v[2] + 1, v[1] + 1);
        else sb_printf(&b, "f %d %d %d\n", v[0] + 1, v[1] + 1, v[2] + 1);
    }
    tl_write_bytes(tl_path(name), b.p, b.n);
    free(b.p);
}

/* Issue 11's findings: counts checked against the file before any loop, and
 * indices too large for any integer type refused as written, with no
 * undefined behaviour (the sanitizer build runs this too). */
static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_bounded(void)
{
    static const char *ply_head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                  "property float z\n";
    char buf[1024];
    /* a PLY element without properties and a count of 2^31 - 1 takes no bytes: skipped at once (it was
     * iterated one by one, 9 s) */
    snprintf(buf, sizeof buf, "%selement nothing 2147483647\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ply_head);
    tl_write_text(tl_path("empty-elem.ply"), buf);
    thx_surface *s = NULL;
    double t0 = seconds_now();
    CHECK_OK(ctx, thx_surface_read_file(ctx, tl_path("empty-elem.ply"), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL));
    CHECK(seconds_now() - t0 < 2.0);
    CHECK(s && s->n_nodes == 3 && s->n_tris == 1);
    thx_surface_destroy(&s);
    /* a PLY element count the data cannot hold: refused from the size */
    snprintf(buf, sizeof buf, "%selement face 2147483647\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ply_head);
    t0 = seconds_now();
    expect_error("big-face.ply", buf, "7:", "element \"face\": 2147483647 items declared, but the 9 bytes of data left");
    CHECK(seconds_now() - t0 < 2.0);
    /* a .tri claiming 2^31 - 1 triangles: refused from the size at once (it took 8 s) */
    t0 = seconds_now();
    expect_error("big.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n2147483647\n1 1 2 3\n", "5:",
                 "2147483647 triangles declared, but the file holds only 4 numbers");
    expect_error("big-om.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 2147483647\n0 1 2\n", "5:",
                 "2147483647 triangles declared");
    expect_error("big-nodes.tri", "2147483647\n1 0 0 0\n", "1:", "2147483647 nodes declared");
    CHECK(seconds_now() - t0 < 2.0);
    /* huge indices: no signed overflow (x - base), reported as written */
    expect_error("huge1.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n1\n1 1 2 -9223372036854775808\n", "6:",
                 "node number -9223372036854775808 out of range 1..3");
    expect_error("huge2.tri", "3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n1\n1 1 2 9223372036854775807\n", "6:",
                 "node number 9223372036854775807 out of range");
    expect_error("huge3.tri", "- 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n- 1\n0 1 99999999999999999999\n", "6:",
                 "vertex number 99999999999999999999 out of range");
    /* float-to-integer conversions: PLY and VTK keep values as doubles; one past 2^53 (or 2^63) was rounded
     * (and converted with undefined behaviour), then reported as another number */
    snprintf(buf, sizeof buf, "%selement face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 9223372036854775807\n", ply_head);
    expect_error("huge.ply", buf, "13:", "\"9223372036854775807\" is out of range -2147483648..2147483647");
    snprintf(buf, sizeof buf, "%selement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 4294967296\n", ply_head);
    expect_error("huge2.ply", buf, "13:", "\"4294967296\" is out of range 0..4294967295");
    expect_error("huge.vtk", "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                 "POLYGONS 1 4\n3 0 1 9007199254740993\n", "8:", "\"9007199254740993\" is out of range");
    expect_error("huge51.vtk", "# vtk DataFile Version 5.1\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                 "POLYGONS 2 3\nOFFSETS vtktypeint64\n0 3\nCONNECTIVITY vtktypeint64\n0 1 9223372036854775807\n", "11:",
                 "\"9223372036854775807\" is out of range");
    /* binary: a 64-bit index beyond 2^53, named as written */
    {
        static const char head[] = "# vtk DataFile Version 5.1\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n";
        unsigned char bin[512];
        size_t n = 0;
        memcpy(bin, head, sizeof head - 1), n = sizeof head - 1;
        const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        for (int i = 0; i < 9; i++) {
            uint32_t u;
            memcpy(&u, &p[i], 4);
            for (int k = 3; k >= 0; k--) bin[n++] = (unsigned char)(u >> (8 * k));
        }
        const char *h2 = "\nPOLYGONS 2 3\nOFFSETS vtktypeint64\n";
        memcpy(bin + n, h2, strlen(h2)), n += strlen(h2);
        const uint64_t off[2] = {0, 3}, conn[3] = {0, 1, 0x7fffffffffffffffull};
        for (int i = 0; i < 2; i++)
            for (int k = 7; k >= 0; k--) bin[n++] = (unsigned char)(off[i] >> (8 * k));
        const char *h3 = "\nCONNECTIVITY vtktypeint64\n";
        memcpy(bin + n, h3, strlen(h3)), n += strlen(h3);
        for (int i = 0; i < 3; i++)
            for (int k = 7; k >= 0; k--) bin[n++] = (unsigned char)(conn[i] >> (8 * k));
        bin[n++] = '\n';
        FILE *f = fopen(tl_path("huge-bin.vtk"), "wb");
        CHECK(f && fwrite(bin, 1, n, f) == n && fclose(f) == 0);
        CHECK(thx_surface_read_file(ctx, tl_path("huge-bin.vtk"), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL) ==
              THX_EINPUT);
        CHECK(contains(thx_ctx_message(ctx), "integer 9223372036854775807 is beyond +-2^53"));
        CHECK(contains(thx_ctx_message(ctx), "huge-bin.vtk: byte "));
    }
    /* nothing half-read: NUL bytes, trailing data */
    {
        static const char obj[] = "v 0 0 0\nv 1 0 0\n\0v 0 1 0\nf 1 2 3\n";
        FILE *f = fopen(tl_path("nul.obj"), "wb");
        CHECK(f && fwrite(obj, 1, sizeof obj - 1, f) == sizeof obj - 1 && fclose(f) == 0);
        CHECK(thx_surface_read_file(ctx, tl_path("nul.obj"), NULL, THX_IMPORT_AUTO, "skin", THX_ROLE_OUTER, &s, NULL) == THX_EINPUT);
        CHECK(contains(thx_ctx_message(ctx), "nul.obj:3: surface \"skin\": NUL byte at byte 16"));
    }
    snprintf(buf, sizeof buf, "%selement face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", ply_head);
    expect_error("trail.ply", buf, "14:", "unexpected \"3\" after the last element's data");
    expect_error("trail.obj", "v 0 0 0 junk\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "1:", "vertex 1: unexpected \"junk\"");
    expect_error("vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", "4:", "face vertex \"1/x\" is not a vertex number");
    expect_error("trail.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0 9\n", "4:",
                 "unexpected \"9\" after the vertex's three coordinates");
    expect_error("normal.stl", "solid s\nfacet normal 0 x 1\n", "2:", "expected \"facet normal nx ny nz\"");
}

static void test_policy(void)
{
    thx_import_info in;
    thx_surface *s = NULL;
    thx_import_opts o;
    thx_import_opts_default(&o);

    /* every triangle clockwise: reversed, reported, then it passes */
    write_cube_obj("inward.obj", 0xfff, 0);
    s = imp(tl_path("inward.obj"), NULL, &in);
    CHECK(is_cube(s, 8));
    CHECK(in.reversed == 1 && in.report.ok && in.report.volume > 0 && !in.check_failed);
    CHECK_NEAR(in.omega_before / (4 * M_PI), -1.0, 1e-12);
    CHECK_NEAR(in.report.solid_angle / (4 * M_PI), 1.0, 1e-12);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);

    /* open (one triangle missing): refused, nothing returned, reasons given */
    write_cube_obj("open.obj", 0, 1u << 5);
    CHECK(thx_surface_import(ctx, tl_path("open.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, &in) == THX_ECHECK);
    CHECK(s == NULL && in.check_failed && !in.report.ok && in.report.n_boundary_edges == 3);
    CHECK(contains(thx_ctx_message(ctx), "open.obj: surface \"box\": refused: not closed"));
    CHECK(!in.reversed);
    thx_import_info_free(&in);
    /* ... unless forced: returned, flagged */
    o.force = 1;
    CHECK(thx_surface_import(ctx, tl_path("open.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, &in) == THX_OK);
    CHECK(s != NULL && s->n_tris == 11 && in.check_failed == 1 && !in.report.ok);
    thx_import_info_free(&in);
    thx_surface_destroy(&s);
    o.force = 0;

    /* one triangle flipped: inconsistent orientation, never "repaired" */
    write_cube_obj("flip1.obj", 1u << 3, 0);
    CHECK(thx_surface_import(ctx, tl_path("flip1.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, &in) == THX_ECHECK);
    CHECK(s == NULL && !in.reversed && in.report.n_inconsistent_edges > 0);
    CHECK(contains(thx_ctx_message(ctx), "refused"));
    thx_import_info_free(&in);

    /* a duplicate triangle */
    sbuf b = {0};
    for (int i = 0; i < 8; i++) sb_printf(&b, "v %g %g %g\n", cube_x(i, 0), cube_x(i, 1), cube_x(i, 2));
    for (int t = 0; t < 13; t++) {
        int v[3];
        cube_tri(t % 12, v);
        sb_printf(&b, "f %d %d %d\n", v[0] + 1, v[1] + 1, v[2] + 1);
    }
    tl_write_bytes(tl_path("dup.obj"), b.p, b.n);
    free(b.p);
    CHECK(thx_surface_import(ctx, tl_path("dup.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, &in) == THX_ECHECK);
    CHECK(s == NULL && (in.report.failures & THX_CHECKF_DUPLICATE));
    thx_import_info_free(&in);

    /* scale must be positive; NULL info is accepted */
    o.scale = -1;
    CHECK(thx_surface_import(ctx, tl_path("inward.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, NULL) == THX_EINPUT);
    o.scale = 2;
    CHECK(thx_surface_import(ctx, tl_path("inward.obj"), NULL, "box", THX_ROLE_OUTER, &o, &s, NULL) == THX_OK);
    CHECK(s && s->xyz[3 * 7 + 2] == 25.0);
    thx_surface_destroy(&s);
}

static void test_format_names(void)
{
    thx_import_format f;
    CHECK(thx_import_format_from_path("a/b.c/torso.STL") == THX_IMPORT_STL);
    CHECK(thx_import_format_from_path("x.fac") == THX_IMPORT_PTSFAC);
    CHECK(thx_import_format_from_path("x.pts") == THX_IMPORT_PTSFAC);
    CHECK(thx_import_format_from_path("dir.vtk/x") == THX_IMPORT_AUTO);
    CHECK(thx_import_format_from_path(".obj") == THX_IMPORT_AUTO);
    CHECK(thx_import_format_parse("Tri", &f) == 0 && f == THX_IMPORT_TRI);
    CHECK(thx_import_format_parse("gltf", &f) != 0);
    CHECK(strcmp(thx_import_format_name(THX_IMPORT_VTP), "vtp") == 0);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_import")) return 1;
    test_format_names();
    test_ptsfac();
    test_tri();
    test_openmeeg();
    test_obj();
    test_stl();
    test_ply();
    test_vtk();
    test_exports();
    test_errors();
    test_bounded();
    test_policy();
    int rc = tl_scratch_finish("test_import");
    thx_ctx_destroy(&ctx);
    return rc;
}
