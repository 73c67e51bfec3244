/*
 * Tests of volume mesh import (src/io/volume/import_volume.c, thorax/import/import.h):
 * a hand-made two-region cube written by hand in every format (.pts/.tet
 * with either index base, CARP .pts/.elem, legacy VTK, VTU, Gmsh MSH 4.1)
 * and read back into the same model; regions named and given conductivities
 * by maps, by the file and by default; left-handed tetrahedra counted;
 * surfaces (the boundary, the interface around the inner region, a Gmsh
 * physical surface naming it); a round trip through thx_model_write and
 * thx_volume_export (vtu, msh); errors naming file and line (truncated
 * files, counts larger than the file, indices out of range, non-tetrahedral
 * cells, flat tetrahedra, ambiguous index bases); the check refusing a mesh
 * and --force writing it.
 *
 * The cube: a 3 x 3 x 3 grid of 10 mm cells, node (i, j, k) = 10 (i, j, k)
 * numbered i + 4 j + 16 k (64 nodes); each cell split into the six Kuhn
 * tetrahedra along its main diagonal (162 in all), written as generated, so
 * that half of them are left-handed; region 2 is the centre cell (1000 mm^3),
 * region 1 the rest (26000 mm^3).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check_volume.h"
#include "thorax/import/import.h"
#include "thorax/mesh/mesh.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static thx_ctx *ctx;

/* ------------------------------------------------------------- the cube */

#define NN 64
#define NT 162
static double node_xyz[NN][3];
static int tet_v[NT][4];
static int tet_r[NT]; /* 1 or 2 */
static int n_left;    /* left-handed tetrahedra as written */

static int node_at(int i, int j, int k) { return i + 4 * j + 16 * k; }

static void make_cube(void)
{
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                double *p = node_xyz[node_at(i, j, k)];
                p[0] = 10.0 * i, p[1] = 10.0 * j, p[2] = 10.0 * k;
            }
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int t = 0;
    n_left = 0;
    for (int c = 0; c < 3; c++)
        for (int b = 0; b < 3; b++)
            for (int a = 0; a < 3; a++)
                for (int p = 0; p < 6; p++, t++) {
                    int x[3] = {a, b, c};
                    tet_v[t][0] = node_at(x[0], x[1], x[2]);
                    for (int s = 0; s < 3; s++) {
                        x[perm[p][s]]++;
                        tet_v[t][s + 1] = node_at(x[0], x[1], x[2]);
                    }
                    tet_r[t] = (a == 1 && b == 1 && c == 1) ? 2 : 1;
                    /* ((p1 - p0) x (p2 - p0)) . (p3 - p0) */
                    const double *p0 = node_xyz[tet_v[t][0]], *p1 = node_xyz[tet_v[t][1]], *p2 = node_xyz[tet_v[t][2]],
                                 *p3 = node_xyz[tet_v[t][3]];
                    double u[3], v[3], w[3];
                    for (int k = 0; k < 3; k++) u[k] = p1[k] - p0[k], v[k] = p2[k] - p0[k], w[k] = p3[k] - p0[k];
                    double d = (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] +
                               (u[0] * v[1] - u[1] * v[0]) * w[2];
                    n_left += d < 0;
                }
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
static void sb_write(sbuf *b, const char *name)
{
    tl_write_bytes(tl_path(name), b->p ? b->p : "", b->n);
    free(b->p);
    b->p = NULL, b->n = b->cap = 0;
}

/* .pts + .tet: base 0 or 1, with or without the region column */
static void write_ptstet(const char *stem, int base, int regions)
{
    sbuf b = {0};
    char name[256];
    for (int i = 0; i < NN; i++) sb_printf(&b, "%g %g %g\n", node_xyz[i][0], node_xyz[i][1], node_xyz[i][2]);
    snprintf(name, sizeof name, "%s.pts", stem);
    sb_write(&b, name);
    for (int t = 0; t < NT; t++) {
        sb_printf(&b, "%d %d %d %d", tet_v[t][0] + base, tet_v[t][1] + base, tet_v[t][2] + base, tet_v[t][3] + base);
        if (regions) sb_printf(&b, " %d", tet_r[t]);
        sb_printf(&b, "\n");
    }
    snprintf(name, sizeof name, "%s.tet", stem);
    sb_write(&b, name);
}

/* CARP: counted .pts and .elem, "Tt" lines, 0-based, region tags 10 and 20 */
static void write_carp(const char *stem)
{
    sbuf b = {0};
    char name[256];
    sb_printf(&b, "%d\n", NN);
    for (int i = 0; i < NN; i++) sb_printf(&b, "%g %g %g\n", node_xyz[i][0], node_xyz[i][1], node_xyz[i][2]);
    snprintf(name, sizeof name, "%s.pts", stem);
    sb_write(&b, name);
    sb_printf(&b, "%d\n", NT);
    for (int t = 0; t < NT; t++)
        sb_printf(&b, "Tt %d %d %d %d %d\n", tet_v[t][0], tet_v[t][1], tet_v[t][2], tet_v[t][3], 10 * tet_r[t]);
    snprintf(name, sizeof name, "%s.elem", stem);
    sb_write(&b, name);
}

/* Legacy VTK ASCII (classic CELLS), with one vertex cell to be skipped and
 * cell data: a scalar "region", a field array "quality" of floats. */
static void write_vtk(const char *name, const char *hex)
{
    sbuf b = {0};
    sb_printf(&b, "# vtk DataFile Version 3.0\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %d double\n", NN);
    for (int i = 0; i < NN; i++) sb_printf(&b, "%g %g %g\n", node_xyz[i][0], node_xyz[i][1], node_xyz[i][2]);
    int extra = hex ? 1 : 0;
    sb_printf(&b, "CELLS %d %d\n", NT + 1 + extra, 5 * NT + 2 + (hex ? 9 : 0));
    for (int t = 0; t < NT; t++) sb_printf(&b, "4 %d %d %d %d\n", tet_v[t][0], tet_v[t][1], tet_v[t][2], tet_v[t][3]);
    sb_printf(&b, "1 0\n");
    if (hex) sb_printf(&b, "%s\n", hex);
    sb_printf(&b, "CELL_TYPES %d\n", NT + 1 + extra);
    for (int t = 0; t < NT; t++) sb_printf(&b, "10\n");
    sb_printf(&b, "1\n");
    if (hex) sb_printf(&b, "12\n");
    sb_printf(&b, "POINT_DATA %d\nSCALARS temp float 1\nLOOKUP_TABLE default\n", NN);
    for (int i = 0; i < NN; i++) sb_printf(&b, "%d.5\n", i);
    sb_printf(&b, "CELL_DATA %d\nFIELD FieldData 1\nquality 1 %d float\n", NT + 1 + extra, NT + 1 + extra);
    for (int t = 0; t < NT + 1 + extra; t++) sb_printf(&b, "0.5 ");
    sb_printf(&b, "\nSCALARS region int 1\nLOOKUP_TABLE default\n");
    for (int t = 0; t < NT; t++) sb_printf(&b, "%d\n", tet_r[t]);
    sb_printf(&b, "0\n");
    if (hex) sb_printf(&b, "1\n");
    sb_write(&b, name);
}

/* VTU, ascii arrays; the regions in cell array array_name (plus an integer
 * array "other" that is not a region array) */
static void write_vtu(const char *name, const char *array_name, long long n_points)
{
    sbuf b = {0};
    sb_printf(&b, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
                  "<UnstructuredGrid>\n<Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%d\">\n<PointData>\n</PointData>\n"
                  "<CellData>\n<DataArray type=\"Int32\" Name=\"other\" format=\"ascii\">\n", n_points, NT);
    for (int t = 0; t < NT; t++) sb_printf(&b, "%d ", t % 7);
    sb_printf(&b, "\n</DataArray>\n<DataArray type=\"Int32\" Name=\"%s\" format=\"ascii\">\n", array_name);
    for (int t = 0; t < NT; t++) sb_printf(&b, "%d ", tet_r[t]);
    sb_printf(&b, "\n</DataArray>\n</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (int i = 0; i < NN; i++) sb_printf(&b, "%g %g %g\n", node_xyz[i][0], node_xyz[i][1], node_xyz[i][2]);
    sb_printf(&b, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for (int t = 0; t < NT; t++) sb_printf(&b, "%d %d %d %d\n", tet_v[t][0], tet_v[t][1], tet_v[t][2], tet_v[t][3]);
    sb_printf(&b, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for (int t = 0; t < NT; t++) sb_printf(&b, "%d ", 4 * (t + 1));
    sb_printf(&b, "\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (int t = 0; t < NT; t++) sb_printf(&b, "10 ");
    sb_printf(&b, "\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    sb_write(&b, name);
}

/* Is the face (a, b, c) on the centre cell's boundary? (all three nodes on
 * one of its six planes, and inside its square) */
static int on_centre(int a, int b, int c)
{
    int v[3] = {a, b, c};
    for (int k = 0; k < 3; k++)
        for (int side = 1; side <= 2; side++) {
            int all = 1;
            for (int j = 0; j < 3; j++) {
                const double *p = node_xyz[v[j]];
                all &= p[k] == 10.0 * side;
                for (int q = 0; q < 3; q++) all &= p[q] >= 10.0 && p[q] <= 20.0;
            }
            if (all) return 1;
        }
    return 0;
}

/* Gmsh MSH 4.1: physical volumes 7 "brain" (centre) and 3 "scalp"; the
 * centre cell's faces as triangles of a physical surface "cortex"; node
 * tags 1001.. (not positions); a point element, skipped. */
static void write_msh(const char *name, const char *mutate)
{
    sbuf b = {0};
    sb_printf(&b, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n2 5 \"cortex\"\n3 7 \"brain\"\n3 3 \"scalp and skull\"\n"
                  "$EndPhysicalNames\n$Entities\n1 0 1 2\n1 0 0 0 0\n"
                  "1 10 10 10 20 20 20 1 5 0\n"
                  "1 10 10 10 20 20 20 1 7 1 1\n2 0 0 0 30 30 30 1 3 1 -1\n$EndEntities\n");
    sb_printf(&b, "$Nodes\n1 %d 1001 %d\n3 2 0 %d\n", NN, 1000 + NN, NN);
    for (int i = 0; i < NN; i++) sb_printf(&b, "%d\n", 1001 + i);
    for (int i = 0; i < NN; i++) sb_printf(&b, "%g %g %g\n", node_xyz[i][0], node_xyz[i][1], node_xyz[i][2]);
    sb_printf(&b, "$EndNodes\n");
    /* centre-cell faces, from its tetrahedra */
    int tri[64][3], nt = 0;
    for (int t = 0; t < NT; t++) {
        if (tet_r[t] != 2) continue;
        static const int fc[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
        for (int f = 0; f < 4; f++) {
            int a = tet_v[t][fc[f][0]], c1 = tet_v[t][fc[f][1]], c2 = tet_v[t][fc[f][2]];
            if (on_centre(a, c1, c2) && nt < 64) tri[nt][0] = a, tri[nt][1] = c1, tri[nt][2] = c2, nt++;
        }
    }
    int n2 = 0, n1 = 0;
    for (int t = 0; t < NT; t++) {
        if (tet_r[t] == 2) n2++;
        else n1++;
    }
    sb_printf(&b, "$Elements\n4 %d 1 %d\n0 1 15 1\n1 1001\n2 1 2 %d\n", 1 + nt + NT, 1 + nt + NT, nt);
    for (int k = 0; k < nt; k++) sb_printf(&b, "%d %d %d %d\n", 2 + k, 1001 + tri[k][0], 1001 + tri[k][1], 1001 + tri[k][2]);
    int tag = 2 + nt;
    for (int vol = 1; vol <= 2; vol++) {
        sb_printf(&b, "3 %d 4 %d\n", vol, vol == 1 ? n2 : n1);
        for (int t = 0; t < NT; t++) {
            if ((tet_r[t] == 2) != (vol == 1)) continue;
            sb_printf(&b, "%d %d %d %d %d\n", tag++, 1001 + tet_v[t][0], 1001 + tet_v[t][1], 1001 + tet_v[t][2],
                      1001 + tet_v[t][3]);
        }
    }
    sb_printf(&b, "$EndElements\n$NodeData\n1\n\"x\"\n0\n0\n$EndNodeData\n");
    if (mutate) {
        /* mutate = "FROM\tTO": replace the first occurrence */
        char from[256], to[256];
        const char *tab = strchr(mutate, '\t');
        snprintf(from, sizeof from, "%.*s", (int)(tab - mutate), mutate);
        snprintf(to, sizeof to, "%s", tab + 1);
        char *at = strstr(b.p, from);
        if (at) {
            sbuf c = {0};
            sb_printf(&c, "%.*s%s%s", (int)(at - b.p), b.p, to, at + strlen(from));
            free(b.p);
            b = c;
        }
    }
    sb_write(&b, name);
}

/* ------------------------------------------------------------- helpers */

static thx_region default_sigma(void)
{
    thx_region g;
    thx_region_default("mean_thorax", &g);
    return g;
}

static thx_model *import_file(const char *name, thx_volume_import_opts *o, thx_volume_import_info *in, thx_status want)
{
    thx_volume_import_opts def;
    if (!o) {
        thx_volume_import_opts_default(&def);
        def.default_region = default_sigma();
        o = &def;
    }
    thx_model *m = NULL;
    thx_status st = thx_volume_import(ctx, tl_path(name), o, &m, in);
    if (st != want) fprintf(stderr, "  importing %s: status %d, expected %d: %s\n", name, (int)st, (int)want, thx_ctx_message(ctx));
    CHECK(st == want);
    CHECK((st == THX_OK) == (m != NULL));
    return m;
}

static double region_volume(const thx_volume *v, int region)
{
    double s = 0;
    for (size_t t = 0; t < v->n_tets; t++)
        if (v->region[t] == region) s += thx_volume_tet_volume(v, t);
    return s;
}

/* The model is the cube: counts, regions (by their file tags' order), volumes,
 * every tetrahedron right-handed, two surfaces (boundary, centre interface),
 * node tables, and the checks passed. */
static void check_cube(const thx_model *m, const thx_volume_import_info *in, const char *outer, const char *inner,
                       int flipped)
{
    CHECK(m && m->volume);
    if (!m || !m->volume) return;
    const thx_volume *v = m->volume;
    CHECK(v->n_nodes == NN && v->n_tets == NT && v->n_regions == 2 && v->n_steiner == 0);
    CHECK(in->n_flipped == (size_t)flipped);
    CHECK_NEAR(region_volume(v, 0), 26000, 1e-9);
    CHECK_NEAR(region_volume(v, 1), 1000, 1e-9);
    CHECK_NEAR(in->regions[0].volume, 26000, 1e-9);
    CHECK(in->regions[0].n_tets == NT - 6 && in->regions[1].n_tets == 6);
    int right = 1;
    for (size_t t = 0; t < v->n_tets; t++) right &= thx_volume_tet_volume(v, t) > 0;
    CHECK(right);
    CHECK(m->n_surfaces == 2 && v->n_surfaces == 2);
    if (m->n_surfaces != 2) return;
    CHECK(m->surf[0]->role == THX_ROLE_OUTER && m->surf[0]->n_tris == 108 && m->surf[0]->n_nodes == 56);
    CHECK(m->surf[1]->role == THX_ROLE_OTHER && m->surf[1]->n_tris == 12 && m->surf[1]->n_nodes == 8);
    CHECK(in->surfaces[0].kind == THX_VSURF_BOUNDARY && in->surfaces[1].kind == THX_VSURF_INTERFACE);
    CHECK(in->surfaces[1].inside == 1 && in->surfaces[1].outside == 0);
    CHECK_NEAR(thx_surface_volume(m->surf[0]), 27000, 1e-9);
    CHECK_NEAR(thx_surface_volume(m->surf[1]), 1000, 1e-9);
    if (outer) CHECK(strcmp(m->surf[0]->name, outer) == 0);
    if (inner) CHECK(strcmp(m->surf[1]->name, inner) == 0);
    /* node tables: surface node i is volume node surf_node[s][i], in increasing order */
    int tables = 1;
    for (size_t s = 0; s < 2; s++)
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            int32_t w = v->surf_node[s][i];
            tables &= memcmp(m->surf[s]->xyz + 3 * i, v->xyz + 3 * (size_t)w, 3 * sizeof(double)) == 0;
            tables &= v->node_surf[w] == (int32_t)s && v->node_snode[w] == (int32_t)i;
            if (i) tables &= v->surf_node[s][i] > v->surf_node[s][i - 1];
        }
    CHECK(tables);
    CHECK(!in->check_failed && in->volume_checked && in->volume_report.ok);
    CHECK(in->n_dropped == 0 && in->n_unused_removed == 0);
}

/* ------------------------------------------------------------- tests */

static void test_format_of(void)
{
    thx_volume_format f;
    CHECK(thx_volume_format_from_path("a/b.MSH") == THX_VOLFMT_MSH);
    CHECK(thx_volume_format_from_path("x.vtu") == THX_VOLFMT_VTU);
    CHECK(thx_volume_format_from_path("x.elem") == THX_VOLFMT_PTS);
    CHECK(thx_volume_format_from_path("x.obj") == THX_VOLFMT_NONE);
    CHECK(thx_volume_format_from_path(tl_path("missing.vtk")) == THX_VOLFMT_NONE);
    CHECK(thx_volume_format_parse("Tet", &f) == 0 && f == THX_VOLFMT_PTS);
    CHECK(thx_volume_format_parse("carp", &f) == 0 && f == THX_VOLFMT_PTS);
    CHECK(thx_volume_format_parse("vtp", &f) != 0);
    CHECK(strcmp(thx_volume_format_name(THX_VOLFMT_MSH), "msh") == 0);
    /* .pts: a volume when a .tet is beside it and no .fac */
    write_ptstet("fmt", 1, 1);
    CHECK(thx_volume_format_from_path(tl_path("fmt.pts")) == THX_VOLFMT_PTS);
    tl_write_text(tl_path("fmt.fac"), "1 2 3\n");
    CHECK(thx_volume_format_from_path(tl_path("fmt.pts")) == THX_VOLFMT_NONE);
    /* .vtk: by its DATASET */
    write_vtk("fmt.vtk", NULL);
    CHECK(thx_volume_format_from_path(tl_path("fmt.vtk")) == THX_VOLFMT_VTK);
    tl_write_text(tl_path("poly.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
    CHECK(thx_volume_format_from_path(tl_path("poly.vtk")) == THX_VOLFMT_NONE);
}

static void test_ptstet(void)
{
    thx_volume_import_info in;
    write_ptstet("one", 1, 1);
    thx_model *m = import_file("one.pts", NULL, &in, THX_OK);
    check_cube(m, &in, "region_1", "region_2", n_left);
    CHECK(in.format == THX_VOLFMT_PTS && in.index_base == 1 && in.index_base_detected == 1);
    CHECK(strstr(in.path2, "one.tet") != NULL && strstr(in.region_source, "region column") != NULL);
    CHECK(in.regions[0].tag == 1 && in.regions[0].name_from == THX_RNAME_DEFAULT && in.regions[0].sigma_defaulted);
    CHECK(m && m->volume->regions[0].sigma[0] == 0.239);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* the .tet named: the .pts beside it */
    m = import_file("one.tet", NULL, &in, THX_OK);
    check_cube(m, &in, NULL, NULL, n_left);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* 0-based, no region column: one region, no interface */
    write_ptstet("zero", 0, 0);
    m = import_file("zero.pts", NULL, &in, THX_OK);
    CHECK(m && m->volume->n_regions == 1 && m->n_surfaces == 1 && in.index_base == 0 && in.index_base_detected);
    CHECK(m && strcmp(m->volume->regions[0].name, "region_1") == 0 && strstr(in.region_source, "none") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* region maps: names and conductivities; an unmapped region without a default is an error */
    thx_region_map maps[2];
    memset(maps, 0, sizeof maps);
    maps[0].tag = 2, snprintf(maps[0].name, sizeof maps[0].name, "brain"), maps[0].sigma = 0.33, maps[0].has_sigma = 1;
    maps[1].tag = 1, maps[1].sigma = 0.43, maps[1].has_sigma = 1;
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.region_maps = maps, o.n_region_maps = 2;
    m = import_file("one.pts", &o, &in, THX_OK);
    check_cube(m, &in, "region_1", "brain", n_left);
    CHECK(m && strcmp(m->volume->regions[1].name, "brain") == 0 && m->volume->regions[1].sigma[8] == 0.33);
    CHECK(m && m->volume->regions[0].sigma[4] == 0.43 && !in.regions[0].sigma_defaulted);
    CHECK(in.regions[1].name_from == THX_RNAME_OPTION && in.regions[0].name_from == THX_RNAME_DEFAULT);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    o.n_region_maps = 1;
    m = import_file("one.pts", &o, &in, THX_EINPUT);
    CHECK(tl_msg_has(ctx, "region 1 (\"region_1\") has no conductivity: give --region 1=NAME:SIGMA"));
    thx_volume_import_info_free(&in);
    maps[0].tag = 9;
    o.default_region = default_sigma();
    m = import_file("one.pts", &o, &in, THX_EINPUT);
    CHECK(tl_msg_has(ctx, "--region 9: the mesh has no region 9 (its regions: 1, 2)"));
    thx_volume_import_info_free(&in);
    /* scale: metres to mm */
    thx_volume_import_opts_default(&o);
    o.default_region = default_sigma();
    o.scale = 0.1;
    m = import_file("one.pts", &o, &in, THX_OK);
    CHECK(m && fabs(region_volume(m->volume, 1) - 1.0) < 1e-12 && fabs(in.extent - 3.0) < 1e-12);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
}

static void test_carp(void)
{
    thx_volume_import_info in;
    write_carp("carp");
    thx_model *m = import_file("carp.pts", NULL, &in, THX_OK);
    check_cube(m, &in, "region_10", "region_20", n_left);
    CHECK(in.index_base == 0 && in.index_base_detected == 0 && strstr(in.format_detail, "CARP") != NULL);
    CHECK(strstr(in.path2, "carp.elem") != NULL && in.regions[1].tag == 20);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
}

static void test_vtk(void)
{
    thx_volume_import_info in;
    write_vtk("cube.vtk", NULL);
    thx_model *m = import_file("cube.vtk", NULL, &in, THX_OK);
    check_cube(m, &in, NULL, NULL, n_left);
    CHECK(in.n_cells_ignored == 1 && strstr(in.region_source, "\"region\"") != NULL);
    CHECK(strstr(in.format_detail, "legacy VTK ASCII") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* VTU with a region array by name; by --region-array; none recognised */
    write_vtu("cube.vtu", "MaterialIds", NN);
    m = import_file("cube.vtu", NULL, &in, THX_OK);
    check_cube(m, &in, NULL, NULL, n_left);
    CHECK(strstr(in.region_source, "MaterialIds") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    write_vtu("odd.vtu", "zone", NN);
    m = import_file("odd.vtu", NULL, &in, THX_OK);
    CHECK(m && m->volume->n_regions == 1 && strstr(in.region_source, "--region-array") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.default_region = default_sigma();
    o.region_array = "zone";
    m = import_file("odd.vtu", &o, &in, THX_OK);
    check_cube(m, &in, NULL, NULL, n_left);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    o.region_array = "nope";
    m = import_file("odd.vtu", &o, &in, THX_EINPUT);
    CHECK(tl_msg_has(ctx, "no one-component cell array named \"nope\" (the file has: \"other\", \"zone\")"));
    thx_volume_import_info_free(&in);
}

static void test_msh(void)
{
    thx_volume_import_info in;
    write_msh("cube.msh", NULL);
    thx_model *m = import_file("cube.msh", NULL, &in, THX_OK);
    /* regions in increasing tag order: 3 "scalp and skull" (cleaned), 7 "brain" */
    CHECK(m && m->volume->n_regions == 2);
    if (m && m->volume->n_regions == 2) {
        CHECK(strcmp(m->volume->regions[0].name, "scalp_and_skull") == 0 && strcmp(m->volume->regions[1].name, "brain") == 0);
        CHECK(in.regions[0].tag == 3 && strcmp(in.regions[0].file_name, "scalp and skull") == 0);
        CHECK(in.regions[0].name_from == THX_RNAME_FILE);
    }
    check_cube(m, &in, "scalp_and_skull", "cortex", n_left);
    CHECK(in.n_surfaces == 2 && in.surfaces[1].named_by_file && !in.surfaces[0].named_by_file);
    CHECK(in.n_cells_ignored == 1 && in.n_tris_named == 12 && in.index_base == 1);
    CHECK(strstr(in.region_source, "physical groups") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
}

/* Write, read back, export vtu and msh, import both: the same mesh. */
static void test_round_trip(void)
{
    thx_volume_import_info in;
    write_ptstet("rt", 1, 1);
    thx_region_map maps[2];
    memset(maps, 0, sizeof maps);
    maps[0].tag = 1, snprintf(maps[0].name, sizeof maps[0].name, "scalp"), maps[0].sigma = 0.43, maps[0].has_sigma = 1;
    maps[1].tag = 2, snprintf(maps[1].name, sizeof maps[1].name, "brain"), maps[1].sigma = 0.33, maps[1].has_sigma = 1;
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.region_maps = maps, o.n_region_maps = 2;
    thx_model *m = import_file("rt.pts", &o, &in, THX_OK);
    thx_volume_import_info_free(&in);
    if (!m) return;
    CHECK_OK(ctx, thx_model_write(ctx, m, tl_path("rt_model")));
    thx_model *back = NULL;
    CHECK_OK(ctx, thx_model_read(ctx, tl_path("rt_model"), &back));
    thx_volume_report rep;
    CHECK(back && thx_volume_check(ctx, back->volume, back, NULL, &rep) == THX_OK);
    thx_volume_report_free(&rep);
    CHECK_OK(ctx, thx_volume_export(ctx, back, THX_EXPORT_VTU, tl_path("rt.vtu")));
    CHECK_OK(ctx, thx_volume_export(ctx, back, THX_EXPORT_MSH, tl_path("rt.msh")));
    for (int k = 0; k < 2; k++) {
        thx_volume_import_opts_default(&o);
        o.default_region = default_sigma();
        thx_model *m2 = import_file(k ? "rt.msh" : "rt.vtu", &o, &in, THX_OK);
        check_cube(m2, &in, k ? "scalp" : "region_1", k ? "brain" : "region_2", 0);
        if (m2) {
            /* the same nodes, tetrahedra and regions, in the same order */
            const thx_volume *a = back->volume, *b = m2->volume;
            CHECK(a->n_nodes == b->n_nodes && a->n_tets == b->n_tets);
            int same = a->n_tets == b->n_tets && a->n_nodes == b->n_nodes;
            for (size_t t = 0; same && t < a->n_tets; t++) same = a->region[t] == b->region[t];
            CHECK(same && memcmp(a->tet, b->tet, 4 * a->n_tets * sizeof *a->tet) == 0);
            CHECK(same && memcmp(a->xyz, b->xyz, 3 * a->n_nodes * sizeof *a->xyz) == 0);
            /* names travel in .msh (physical names), not in .vtu (region numbers only) */
            CHECK(strcmp(b->regions[1].name, k ? "brain" : "region_2") == 0);
        }
        thx_model_destroy(&m2);
        thx_volume_import_info_free(&in);
    }
    thx_model_destroy(&back);
    thx_model_destroy(&m);
}

/* Writes text to name and expects THX_EINPUT (or want) naming name:where and what. */
static void expect_error_st(const char *name, const char *text, thx_status want, const char *where, const char *what)
{
    if (text) tl_write_text(tl_path(name), text);
    thx_volume_import_info in;
    thx_model *m = import_file(name, NULL, &in, want);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    char w[256];
    snprintf(w, sizeof w, "%s%s", name, where);
    CHECK(tl_msg_has(ctx, w));
    CHECK(tl_msg_has(ctx, what));
}
static void expect_error(const char *name, const char *text, const char *where, const char *what)
{
    expect_error_st(name, text, THX_EINPUT, where, what);
}

static const char vtk_head[] = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                               "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n";

static void test_errors(void)
{
    /* .pts/.tet */
    tl_write_text(tl_path("e1.pts"), "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n");
    expect_error("e1.tet", "1 2 3 4\n2 3 4 6\n", ":2:", "node number 6 out of range 1..5 (1-based, 5 nodes)");
    expect_error("e1.tet", "1 2 3 4\n", ": ", "cannot tell whether node numbers are 0- or 1-based: they run 1..4 for 5 nodes");
    expect_error("e1.tet", "1 2 3 4 1\n2 3 4 5\n", ":2:", "element 2 has 4 columns but the first has 5");
    expect_error("e1.tet", "1 2 3 x\n", ":1:", "element 1: node number \"x\" is not an integer");
    tl_write_text(tl_path("e2.tet"), "0 1 0 1\n");
    expect_error("e2.pts", "100\n0 0 0\n1 0 0\n", ":1:", "the count line says 100 nodes, but 2 follow");
    tl_write_text(tl_path("e3.tet"), "0 1 0 1\n");
    expect_error("e3.pts", "0 0 0\n1 0 0 7\n", ":2:", "node 2: expected three coordinates \"x y z\", found 4 values");
    /* CARP */
    tl_write_text(tl_path("c1.pts"), "5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n");
    expect_error("c1.elem", "2\nTt 0 1 2 3 1\nHx 0 1 2 3 4 0 1 2 1\n", ":3:", "element 2 is \"Hx\" (hexahedron): only tetrahedra");
    expect_error("c1.elem", "1000\nTt 0 1 2 3 1\n", ":1:", "the count line says 1000 elements, but 1 follow");
    expect_error("c1.elem", "1\nTt 0 1 2 5 1\n", ":2:", "node number 5 out of range 0..4 (0-based, 5 nodes)");
    /* a flat tetrahedron: refused as geometry, naming its line */
    expect_error_st("c1.elem", "2\nTt 0 1 2 3 1\nTt 0 1 2 2 1\n", THX_EGEOM, ": ", "1 flat tetrahedron");
    CHECK(tl_msg_has(ctx, "the one at line 3"));
    /* legacy VTK */
    char buf[2048];
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 7\nCELL_TYPES 1\n10\n", vtk_head);
    expect_error("v1.vtk", buf, ":7:", "point number 7 out of range 0..3");
    snprintf(buf, sizeof buf, "%sCELLS 1 9\n8 0 1 2 3 0 1 2 3\nCELL_TYPES 1\n12\n", vtk_head);
    expect_error("v2.vtk", buf, ":7:", "VTK type 12 (hexahedron): only tetrahedra (type 10)");
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 3\n", vtk_head);
    expect_error("v3.vtk", buf, ": ", "no CELL_TYPES");
    expect_error("v4.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 900000000 float\n0 0 0\n",
                 ":5:", "POINTS: 2700000000 values declared, but the file is too short");
    snprintf(buf, sizeof buf, "%sCELLS 2 10\n4 0 1 2 3\n4 0 1\n\n\n\n\n\n\n", vtk_head);
    expect_error("v5.vtk", buf, ":9:", "file ends at CELLS value 9 of 10");
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\nSCALARS region float 1\n"
                              "LOOKUP_TABLE default\n1.5\n", vtk_head);
    expect_error("v6.vtk", buf, ":7:", "cell array \"region\": cell 0 (0-based) has region 1.5, not an integer");
    expect_error("v7.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n", ": ", "not a volume mesh format");
    {
        thx_volume_import_opts o;
        thx_volume_import_opts_default(&o);
        o.format = THX_VOLFMT_VTK;
        thx_volume_import_info in;
        thx_model *m = import_file("v7.vtk", &o, &in, THX_EINPUT);
        thx_model_destroy(&m);
        thx_volume_import_info_free(&in);
        CHECK(tl_msg_has(ctx, "v7.vtk:4: dataset \"POLYDATA\" is not a volume mesh"));
        CHECK(tl_msg_has(ctx, "a POLYDATA file is a surface"));
    }
    /* VTU: counts beyond the file, truncated */
    write_vtu("x1.vtu", "region", 100000000);
    expect_error("x1.vtu", NULL, ":", "Points: 300000000 values declared, but the DataArray is too short");
    char *t = tl_slurp(ctx, tl_path("cube.vtu"), NULL);
    if (t) {
        char *cut = strstr(t, "Name=\"offsets\"");
        if (cut) *cut = '\0';
        expect_error("x2.vtu", t, ":", "<Piece> without a complete <Cells> element");
        free(t);
    }
    tl_write_text(tl_path("x3.vtu"), "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\">\n</VTKFile>\n");
    expect_error("x3.vtu", NULL, ":2:", "only \"UnstructuredGrid\" is a volume mesh (a PolyData file is a surface)");
    /* Gmsh: truncated, counts beyond the file, non-tetrahedra, unknown nodes, old versions */
    write_msh("g1.msh", "$EndElements\n\t");
    expect_error("g1.msh", NULL, ":", "expected $EndElements");
    write_msh("g2.msh", "$Nodes\n1 64 \t$Nodes\n1 640000000 ");
    expect_error("g2.msh", NULL, ":", "$Nodes: 640000000 nodes declared, but the file is too short for them");
    write_msh("g3.msh", "3 1 4 \t3 1 5 ");
    expect_error("g3.msh", NULL, ":", "elements of type 5 (8-node hexahedron) in volume 1: only 4-node tetrahedra");
    write_msh("g4.msh", " 1001 1002 \t 1001 9999 ");
    expect_error("g4.msh", NULL, ":", "refers to node 9999, which $Nodes does not have");
    write_msh("g5.msh", "4.1 0 8\t2.2 0 8");
    expect_error("g5.msh", NULL, ":2:", "MSH version 2.2 is not supported: only 4.1");
    write_msh("g6.msh", "4.1 0 8\t4.1 1 8");
    expect_error("g6.msh", NULL, ":2:", "binary MSH files are not supported");
    write_msh("g7.msh", "1 10 10 10 20 20 20 1 7 1 1\t1 10 10 10 20 20 20 0 1 1");
    expect_error("g7.msh", NULL, ":", "volume 1 belongs to no physical group while other volumes do");
    write_msh("g8.msh", "$EndNodeData\n\t");
    expect_error("g8.msh", NULL, ":", "section $NodeData is not closed by $EndNodeData");
    /* no tetrahedra at all */
    snprintf(buf, sizeof buf, "%sCELLS 1 2\n1 0\nCELL_TYPES 1\n1\n", vtk_head);
    expect_error("v8.vtk", buf, ": ", "no tetrahedra (only cells of dimension 0-2)");
    /* a missing file */
    thx_volume_import_info in;
    thx_model *m = import_file("none.msh", NULL, &in, THX_EIO);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    CHECK(tl_msg_has(ctx, "none.msh"));
}

/* Two tetrahedra on duplicated nodes (a crack between them): the volume
 * check fails (duplicate nodes), so the import is refused; with force it is
 * returned, marked. A region touching the boundary gives no surface of its
 * own (recorded). */
/* Issue 11: counts, sizes and integers of a file never trusted beyond what it holds; nothing
 * half-read. Each case failed on the code before (leaks, undefined behaviour, a heap overflow
 * or a wrong number in the message). */
static void write_bytes(const char *name, const void *data, size_t n)
{
    FILE *f = fopen(tl_path(name), "wb");
    CHECK(f && fwrite(data, 1, n, f) == n && fclose(f) == 0);
}

static void put_be(unsigned char **p, uint64_t v, int bytes)
{
    for (int k = bytes - 1; k >= 0; k--) *(*p)++ = (unsigned char)(v >> (8 * k));
}

static void test_bounded(void)
{
    char buf[2048];
    /* a second section (the first one leaked) */
    snprintf(buf, sizeof buf, "%sPOINTS 1 float\n0 0 0\n", vtk_head);
    expect_error("b1.vtk", buf, ":7:", "a second POINTS section");
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 3\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n", vtk_head);
    expect_error("b2.vtk", buf, ":9:", "a second CELLS section");
    /* classic CELLS: the cell count cannot exceed its entries (allocated before) */
    snprintf(buf, sizeof buf, "%sCELLS 2147483647 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n", vtk_head);
    expect_error("b3.vtk", buf, ":7:", "CELLS: 2147483647 cells cannot fit in 5 entries");
    /* huge indices: quoted as written, no float-to-integer conversion */
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 9223372036854775807\nCELL_TYPES 1\n10\n", vtk_head);
    expect_error("b4.vtk", buf, ":8:", "CELLS value 5: \"9223372036854775807\" is out of range -2147483648..2147483647");
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n1099511627776\n", vtk_head);
    expect_error("b5.vtk", buf, ":10:", "CELL_TYPES value 1: \"1099511627776\" is out of range");
    /* a value of a skipped array is read too */
    snprintf(buf, sizeof buf, "%sCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS p float 1\n"
             "LOOKUP_TABLE default\n0 0 x 0\n", vtk_head);
    expect_error("b6.vtk", buf, ":14:", "SCALARS \"p\" value 3: \"x\" is not a finite number");
    /* NUL bytes */
    {
        static const char t[] = "0 0 0\n1 0 0\n0 1 0\n\0" "0 0 1\n";
        write_bytes("b7.pts", t, sizeof t - 1);
        tl_write_text(tl_path("b7.tet"), "1 2 3 4\n");
        expect_error("b7.pts", NULL, ":4:", "NUL byte at byte 18");
    }
    /* a negative node number, named as written */
    tl_write_text(tl_path("b8.pts"), "0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
    expect_error("b8.tet", "1 2 3 4\n1 2 -3 4\n", ":2:", "element 2: node number -3 is negative");
    /* .msh: a second $Nodes (the first leaked) */
    expect_error("b9.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n0 1 0 1\n1\n0 0 0\n$EndNodes\n"
                 "$Nodes\n", ":10:", "a second $Nodes section");
    /* binary VTK: a 64-bit index beyond 2^53 with its exact value */
    for (int pass = 0; pass < 2; pass++) {
        unsigned char bin[1024], *p = bin;
        const char *h = "# vtk DataFile Version 5.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n";
        memcpy(p, h, strlen(h)), p += strlen(h);
        const double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        for (int i = 0; i < 12; i++) {
            uint64_t u;
            memcpy(&u, &xyz[i], 8);
            put_be(&p, u, 8);
        }
        const char *h2 = "\nCELLS 2 4\nOFFSETS vtktypeint64\n";
        memcpy(p, h2, strlen(h2)), p += strlen(h2);
        put_be(&p, 0, 8), put_be(&p, 4, 8);
        const char *h3 = "\nCONNECTIVITY vtktypeint64\n";
        memcpy(p, h3, strlen(h3)), p += strlen(h3);
        put_be(&p, 0, 8), put_be(&p, 1, 8), put_be(&p, 2, 8);
        put_be(&p, pass ? 0x7fffffffffffffffull : 0xfffffffffffffffdull, 8); /* 2^63 - 1, or -3 */
        const char *h4 = "\nCELL_TYPES 1\n";
        memcpy(p, h4, strlen(h4)), p += strlen(h4);
        put_be(&p, 10, 4);
        *p++ = '\n';
        write_bytes(pass ? "b11.vtk" : "b10.vtk", bin, (size_t)(p - bin));
        if (pass) expect_error("b11.vtk", NULL, ": byte ", "CONNECTIVITY value 4: integer 9223372036854775807 is beyond +-2^53");
        else expect_error("b10.vtk", NULL, ":", "cell 0 (0-based): point number -3 out of range");
    }
    /* VTU zlib: a UInt64 header whose block sizes wrap around 2^64 to the array's size (the old
     * reader then decompressed a block into a buffer far too small) */
    {
        static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        unsigned char hdr[48], *p = hdr;
        for (int i = 0; i < 6; i++) {
            const uint64_t v[6] = {3, 1ull << 63, 48, 8, 8, 8};
            for (int k = 0; k < 8; k++) *p++ = (unsigned char)(v[i] >> (8 * k)); /* little-endian */
        }
        char enc[80];
        size_t e = 0;
        for (size_t i = 0; i < sizeof hdr; i += 3) {
            uint32_t w = (uint32_t)hdr[i] << 16 | (uint32_t)hdr[i + 1] << 8 | hdr[i + 2];
            for (int k = 3; k >= 0; k--) enc[e++] = b64[(w >> (6 * k)) & 63];
        }
        enc[e] = '\0';
        snprintf(buf, sizeof buf,
                 "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n"
                 "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<Points>\n"
                 "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"binary\">\n%sAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA\n"
                 "</DataArray>\n</Points>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n", enc);
        expect_error("b12.vtu", buf, ":6:", "Points: compressed header (3 blocks of 9223372036854775808 bytes, the last 48) "
                     "inconsistent with the 48 bytes expected");
    }
}

static void test_policy(void)
{
    thx_volume_import_info in;
    tl_write_text(tl_path("dup.pts"), "0 0 0\n10 0 0\n0 10 0\n0 0 10\n10 0 0\n0 10 0\n0 0 10\n10 10 10\n");
    tl_write_text(tl_path("dup.tet"), "1 2 3 4 1\n5 7 6 8 1\n");
    thx_model *m = import_file("dup.pts", NULL, &in, THX_ECHECK);
    CHECK(tl_msg_has(ctx, "dup.pts: refused: volume: duplicate"));
    CHECK(in.check_failed && in.volume_checked && !in.volume_report.ok);
    thx_volume_import_info_free(&in);
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.default_region = default_sigma();
    o.force = 1;
    m = import_file("dup.pts", &o, &in, THX_OK);
    CHECK(m && in.check_failed && m->n_surfaces == 2);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* regions side by side: their interface touches the boundary */
    write_ptstet("side", 1, 0);
    char *t = tl_slurp(ctx, tl_path("side.tet"), NULL);
    if (t) {
        sbuf b = {0};
        int k = 0;
        for (char *p = strtok(t, "\n"); p; p = strtok(NULL, "\n"), k++)
            sb_printf(&b, "%s %d\n", p, (k / 6) % 3 == 0 ? 2 : 1); /* cells with a == 0 */
        sb_write(&b, "side.tet");
        free(t);
    }
    o.force = 1;
    m = import_file("side.pts", &o, &in, THX_OK);
    CHECK(m && m->n_surfaces == 1 && in.n_dropped == 1);
    CHECK(in.n_dropped == 1 && strstr(in.dropped[0], "touch the boundary of the mesh") != NULL);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
    /* unused nodes are removed, numbered as the file does in the report */
    tl_write_text(tl_path("unused.pts"), "0 0 0\n5 5 5\n10 0 0\n0 10 0\n0 0 10\n");
    tl_write_text(tl_path("unused.tet"), "1 3 4 5\n");
    m = import_file("unused.pts", NULL, &in, THX_OK);
    CHECK(m && m->volume->n_nodes == 4 && in.n_unused_removed == 1 && in.first_unused == 2 && in.n_flipped == 0);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&in);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_import_volume")) return 1;
    make_cube();
    test_format_of();
    test_ptstet();
    test_carp();
    test_vtk();
    test_msh();
    test_round_trip();
    test_errors();
    test_bounded();
    test_policy();
    int rc = tl_scratch_finish("test_import_volume");
    thx_ctx_destroy(&ctx);
    return rc;
}
