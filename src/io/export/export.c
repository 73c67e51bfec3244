/*
 * Surface export for other tools (see thorax/io/model_dir.h): legacy VTK (.vtk),
 * VTK XML PolyData (.vtp), Wavefront OBJ, binary STL and ASCII PLY. The
 * volume formats (.vtu, Gmsh .msh) are written by src/io/volume_io.c.
 *
 * Invariants shared by every format:
 *  - Triangles keep thorax's orientation (counterclockwise seen from outside),
 *    so outward normals computed by the reading tool point outward.
 *  - Text formats write coordinates "%.6f" mm, the precision of the model's
 *    .pts files (src/io/model.c), so exporting a model reproduces its
 *    coordinates exactly; "-0.000000" is written as "0.000000"; from 1e15 mm
 *    on "%.17g" (thx_io_put_coord), which reads back exactly.
 *  - STL stores float32 (the format allows nothing else): a coordinate beyond
 *    float's range (3.4e38) is refused, not written as inf; facet normals are the
 *    unit normal of (b - a) x (c - a) computed in double, (0,0,0) for a
 *    degenerate triangle. The 80-byte header never starts with "solid", which
 *    some readers take as the mark of an ASCII STL.
 *  - Every file is written through thx_atomic_file, and the surface is
 *    validated (finite coordinates, indices in range) before it is opened.
 *  - Output depends only on the surface: byte-identical for the same input.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "io/common/io_text.h"
int thx_export_format_parse(const char *s, thx_export_format *out)
{
    static const struct { const char *name; thx_export_format f; } tab[] = {
        {"vtk", THX_EXPORT_VTK}, {"vtp", THX_EXPORT_VTP}, {"obj", THX_EXPORT_OBJ},
        {"stl", THX_EXPORT_STL}, {"ply", THX_EXPORT_PLY}, {"vtu", THX_EXPORT_VTU},
        {"msh", THX_EXPORT_MSH},
    };
    if (!s) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcmp(s, tab[i].name) == 0) {
            *out = tab[i].f;
            return 0;
        }
    return -1;
}

int thx_export_format_is_volume(thx_export_format fmt) { return fmt == THX_EXPORT_VTU || fmt == THX_EXPORT_MSH; }

/* "%.6f", "%.17g" from 1e15 on (thx_io_put_coord: the model's .pts rule) */
static void put_coord(FILE *f, double v) { thx_io_put_coord(f, v); }

static void put_xyz(FILE *f, const thx_surface *s, size_t i, const char *sep, const char *eol)
{
    put_coord(f, s->xyz[3 * i]);
    fputs(sep, f);
    put_coord(f, s->xyz[3 * i + 1]);
    fputs(sep, f);
    put_coord(f, s->xyz[3 * i + 2]);
    fputs(eol, f);
}

/* The surface name as it may appear in a comment or header line: printable
 * ASCII only, so that no name can break a line-oriented format. */
static void safe_name(const thx_surface *s, char *out, size_t size)
{
    size_t k = 0;
    for (const char *p = s->name; *p && k + 1 < size; p++) out[k++] = (*p >= 0x20 && *p < 0x7f) ? *p : '_';
    out[k] = '\0';
}

static thx_status validate(thx_ctx *ctx, const thx_surface *s, const char *path)
{
    if ((s->n_nodes && !s->xyz) || (s->n_tris && !s->tri))
        return thx_error(ctx, THX_EINTERNAL, "%s: surface \"%s\": counts set but arrays missing", path, s->name);
    for (size_t i = 0; i < 3 * s->n_nodes; i++)
        if (!isfinite(s->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": node %zu has a non-finite coordinate", path, s->name,
                             i / 3 + 1);
    for (size_t i = 0; i < 3 * s->n_tris; i++)
        if (s->tri[i] < 0 || (size_t)s->tri[i] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": triangle %zu has node index %ld out of range (%zu nodes)",
                             path, s->name, i / 3 + 1, (long)s->tri[i], s->n_nodes);
    if (s->n_nodes > (size_t)INT32_MAX || s->n_tris > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": too large to export", path, s->name);
    return THX_OK;
}

static void write_vtk(FILE *f, const thx_surface *s)
{
    char nm[80];
    safe_name(s, nm, sizeof nm);
    fprintf(f, "# vtk DataFile Version 3.0\nthorax surface %s (mm)\nASCII\nDATASET POLYDATA\n", nm);
    fprintf(f, "POINTS %zu double\n", s->n_nodes);
    for (size_t i = 0; i < s->n_nodes; i++) put_xyz(f, s, i, " ", "\n");
    fprintf(f, "POLYGONS %zu %zu\n", s->n_tris, 4 * s->n_tris);
    for (size_t t = 0; t < s->n_tris; t++)
        fprintf(f, "3 %ld %ld %ld\n", (long)s->tri[3 * t], (long)s->tri[3 * t + 1], (long)s->tri[3 * t + 2]);
}

static void write_vtp(FILE *f, const thx_surface *s)
{
    /* The name is not written into the XML: it would need escaping and VTK
     * does not use it; the file name carries it. */
    fprintf(f, "<?xml version=\"1.0\"?>\n"
               "<!-- thorax surface, mm -->\n"
               "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
               "  <PolyData>\n"
               "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
               "NumberOfPolys=\"%zu\">\n"
               "      <Points>\n"
               "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n",
            s->n_nodes, s->n_tris);
    for (size_t i = 0; i < s->n_nodes; i++) {
        fputs("          ", f);
        put_xyz(f, s, i, " ", "\n");
    }
    fputs("        </DataArray>\n      </Points>\n      <Polys>\n"
          "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n", f);
    for (size_t t = 0; t < s->n_tris; t++)
        fprintf(f, "          %ld %ld %ld\n", (long)s->tri[3 * t], (long)s->tri[3 * t + 1], (long)s->tri[3 * t + 2]);
    fputs("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n", f);
    for (size_t t = 0; t < s->n_tris; t++) fprintf(f, "%s%zu%s", t % 10 == 0 ? "          " : " ", 3 * (t + 1),
                                                    (t % 10 == 9 || t + 1 == s->n_tris) ? "\n" : "");
    fputs("        </DataArray>\n      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n", f);
}

static void write_obj(FILE *f, const thx_surface *s)
{
    char nm[80];
    safe_name(s, nm, sizeof nm);
    for (char *p = nm; *p; p++)
        if (*p == ' ') *p = '_'; /* an OBJ object name is one token */
    fprintf(f, "# thorax surface %s, mm, %zu nodes, %zu triangles (counterclockwise seen from outside)\no %s\n", nm,
            s->n_nodes, s->n_tris, nm[0] ? nm : "surface");
    for (size_t i = 0; i < s->n_nodes; i++) {
        fputs("v ", f);
        put_xyz(f, s, i, " ", "\n");
    }
    for (size_t t = 0; t < s->n_tris; t++) /* OBJ is 1-based */
        fprintf(f, "f %ld %ld %ld\n", (long)s->tri[3 * t] + 1, (long)s->tri[3 * t + 1] + 1, (long)s->tri[3 * t + 2] + 1);
}

/* Little-endian output independent of the host's byte order. */
static void put_u32(FILE *f, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    fwrite(b, 1, 4, f);
}

static void put_f32(FILE *f, double v)
{
    float x = (float)v;
    uint32_t u;
    memcpy(&u, &x, 4);
    put_u32(f, u);
}

static void write_stl(FILE *f, const thx_surface *s)
{
    char header[80];
    char nm[49]; /* 31 characters of prefix + 48 of name + NUL fill the header; longer names are cut */
    safe_name(s, nm, sizeof nm);
    memset(header, 0, sizeof header);
    snprintf(header, sizeof header, "thorax binary STL, mm, surface %s", nm);
    fwrite(header, 1, sizeof header, f);
    put_u32(f, (uint32_t)s->n_tris);
    for (size_t t = 0; t < s->n_tris; t++) {
        thx_vec3 a = thx_surface_node(s, (size_t)s->tri[3 * t]);
        thx_vec3 b = thx_surface_node(s, (size_t)s->tri[3 * t + 1]);
        thx_vec3 c = thx_surface_node(s, (size_t)s->tri[3 * t + 2]);
        thx_vec3 n = thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a));
        double len = thx_v3_norm(n);
        n = len > 0 ? thx_v3_scale(n, 1.0 / len) : thx_v3(0, 0, 0);
        put_f32(f, n.x), put_f32(f, n.y), put_f32(f, n.z);
        put_f32(f, a.x), put_f32(f, a.y), put_f32(f, a.z);
        put_f32(f, b.x), put_f32(f, b.y), put_f32(f, b.z);
        put_f32(f, c.x), put_f32(f, c.y), put_f32(f, c.z);
        const unsigned char attr[2] = {0, 0};
        fwrite(attr, 1, 2, f);
    }
}

static void write_ply(FILE *f, const thx_surface *s)
{
    char nm[80];
    safe_name(s, nm, sizeof nm);
    fprintf(f, "ply\nformat ascii 1.0\ncomment thorax surface %s, mm\n"
               "element vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
               "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
            nm, s->n_nodes, s->n_tris);
    for (size_t i = 0; i < s->n_nodes; i++) put_xyz(f, s, i, " ", "\n");
    for (size_t t = 0; t < s->n_tris; t++)
        fprintf(f, "3 %ld %ld %ld\n", (long)s->tri[3 * t], (long)s->tri[3 * t + 1], (long)s->tri[3 * t + 2]);
}

/* An existing file is replaced only when it is one of thorax's exports of this format: the
 * signature each writer above puts in its first line or header (thorax/core/fileio.h). */
static const char *const marker[] = {[THX_EXPORT_VTK] = "\nthorax surface ", [THX_EXPORT_VTP] = "<!-- thorax surface",
                                     [THX_EXPORT_OBJ] = "# thorax surface ", [THX_EXPORT_STL] = "thorax binary STL",
                                     [THX_EXPORT_PLY] = "comment thorax surface ",
                                     [THX_EXPORT_VTU] = "<!-- thorax volume mesh",
                                     [THX_EXPORT_MSH] = "$Comments\nthorax volume mesh"};

thx_status thx_export_claim(thx_ctx *ctx, thx_export_format fmt, const char *path)
{
    thx_atomic_file af;
    return thx_output_claim(ctx, path, marker[fmt], strlen(marker[fmt]), NULL, 0, &af);
}

thx_status thx_surface_export(thx_ctx *ctx, const thx_surface *s, thx_export_format fmt, const char *path)
{
    THX_CHECK(validate(ctx, s, path));
    void (*writer)(FILE *, const thx_surface *) = NULL;
    switch (fmt) {
    case THX_EXPORT_VTK: writer = write_vtk; break;
    case THX_EXPORT_VTP: writer = write_vtp; break;
    case THX_EXPORT_OBJ: writer = write_obj; break;
    case THX_EXPORT_STL: writer = write_stl; break;
    case THX_EXPORT_PLY: writer = write_ply; break;
    case THX_EXPORT_VTU:
    case THX_EXPORT_MSH:
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": vtu and msh are volume formats (thx_volume_export)", path,
                         s->name);
    }
    if (!writer) return thx_error(ctx, THX_EINTERNAL, "%s: unknown export format %d", path, (int)fmt);
    if (fmt == THX_EXPORT_STL) /* float32: a larger coordinate would be written as inf, which no reader takes */
        for (size_t i = 0; i < 3 * s->n_nodes; i++)
            if (!isfinite((float)s->xyz[i]))
                return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": node %zu: coordinate %g is beyond float32's range "
                                 "(%g), which binary STL stores; export it as vtk, vtp, obj or ply", path, s->name,
                                 i / 3 + 1, s->xyz[i], (double)FLT_MAX);
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(ctx, path, marker[fmt], strlen(marker[fmt]), NULL, 0, &af));
    writer(af.f, s);
    return thx_atomic_commit(ctx, &af); /* checks ferror: a short write fails here */
}
