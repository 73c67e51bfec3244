/*
 * Exports with data for ParaView (thorax/io/export_data.h): the volume as VTK XML
 * UnstructuredGrid (.vtu), a surface as VTK XML PolyData (.vtp) or legacy VTK (.vtk), and the
 * .pvd collection that gives ParaView the time axis.
 *
 * Invariants:
 *  - XML files are binary: every DataArray of the piece is raw appended data (a UInt64 byte
 *    count, then the values little-endian whatever the host), laid out in the order the XML
 *    names them; field data (a few strings and numbers) is inline ASCII. Float64 throughout for
 *    values and points, so the numbers read back bit for bit; Int32 connectivity and offsets.
 *  - The second line is a comment carrying the export's signature ("<!-- thorax volume mesh",
 *    "<!-- thorax surface", "<!-- thorax collection"): thx_export_claim replaces only such files.
 *  - Everything that may fail (names, sizes, memory) is checked before the file is opened; the
 *    file is written through thx_atomic_file, so a failed run leaves nothing half-written.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/io/export_data.h"

/* ------------------------------------------------------------ appended blocks */

typedef enum { B_F64, B_I32_PLUS, B_I32_CONST, B_I32_OFFSETS, B_U8_CONST } blk_kind;

/* One appended DataArray: n values from a source. */
typedef struct {
    blk_kind kind;
    size_t n;              /* values (tuples x components) */
    const double *f;       /* B_F64 */
    const int32_t *i;      /* B_I32_PLUS */
    long long k;           /* B_I32_PLUS: added; B_I32_CONST, B_U8_CONST: the value; B_I32_OFFSETS: stride */
} blk;

static size_t blk_elem(blk_kind k)
{
    return k == B_U8_CONST ? 1 : k == B_F64 ? 8 : 4;
}

static const char *blk_type(blk_kind k)
{
    return k == B_F64 ? "Float64" : k == B_U8_CONST ? "UInt8" : "Int32";
}

/* A little-endian byte buffer in front of a FILE. */
typedef struct {
    FILE *f;
    unsigned char b[1 << 16];
    size_t n;
} lebuf;

static void le_put(lebuf *o, uint64_t v, size_t bytes)
{
    if (o->n + bytes > sizeof o->b) {
        fwrite(o->b, 1, o->n, o->f);
        o->n = 0;
    }
    for (size_t k = 0; k < bytes; k++) o->b[o->n++] = (unsigned char)(v >> (8 * k));
}

static void le_flush(lebuf *o)
{
    fwrite(o->b, 1, o->n, o->f);
    o->n = 0;
}

static void blk_write(lebuf *o, const blk *b)
{
    size_t e = blk_elem(b->kind);
    le_put(o, (uint64_t)(b->n * e), 8); /* header_type UInt64 */
    for (size_t j = 0; j < b->n; j++) {
        uint64_t u = 0;
        switch (b->kind) {
        case B_F64: {
            double d = b->f[j] + 0.0; /* no negative zero from a computed value */
            memcpy(&u, &d, 8);
            break;
        }
        case B_I32_PLUS: u = (uint32_t)(int32_t)(b->i[j] + b->k); break;
        case B_I32_CONST: u = (uint32_t)(int32_t)b->k; break;
        case B_I32_OFFSETS: u = (uint32_t)(int32_t)((long long)(j + 1) * b->k); break;
        case B_U8_CONST: u = (uint64_t)b->k; break;
        }
        le_put(o, u, e);
    }
}

/* The appended blocks of one file and the running offset. */
typedef struct {
    blk b[64];
    size_t n;
    uint64_t offset;
} blk_list;

/* Declares one DataArray element referring to the next appended block. */
static void declare(FILE *f, blk_list *L, const char *name, int n_comp, blk b)
{
    fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", blk_type(b.kind), name);
    if (n_comp > 1) fprintf(f, " NumberOfComponents=\"%d\"", n_comp);
    fprintf(f, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)L->offset);
    L->b[L->n++] = b;
    L->offset += 8 + b.n * blk_elem(b.kind);
}

/* The appended section; o is the caller's buffer (allocated before the file was opened). */
static void write_appended(FILE *f, lebuf *o, const blk_list *L)
{
    fputs("  <AppendedData encoding=\"raw\">\n   _", f);
    o->f = f;
    o->n = 0;
    for (size_t k = 0; k < L->n; k++) blk_write(o, &L->b[k]);
    le_flush(o);
    fputs("\n  </AppendedData>\n</VTKFile>\n", f);
}

/* ------------------------------------------------------------ names and field data */

/* An XML attribute value or legacy token we write verbatim: printable ASCII without the
 * characters XML would need escaped; legacy VTK also needs it without blanks. */
static int name_ok(const char *s, int legacy)
{
    if (!s || !*s || strlen(s) > 200) return 0;
    for (const char *p = s; *p; p++)
        if (*p < 0x21 || *p > 0x7e || *p == '"' || *p == '<' || *p == '>' || *p == '&' || (legacy && *p == '%'))
            return 0;
    return 1;
}

static thx_status check_frame(thx_ctx *ctx, const thx_export_frame *fr, const char *path, int legacy)
{
    if (!fr) return THX_OK;
    if (fr->has_time && !isfinite(fr->time)) return thx_error(ctx, THX_EINPUT, "%s: the frame's time is not finite", path);
    for (int pc = 0; pc < 2; pc++) {
        const thx_export_array *a = pc ? fr->cell : fr->point;
        size_t n = pc ? fr->n_cell : fr->n_point;
        if (n && !a) return thx_error(ctx, THX_EINTERNAL, "%s: %zu arrays announced, none given", path, n);
        if (n > 24) return thx_error(ctx, THX_EINPUT, "%s: %zu %s arrays (at most 24)", path, n, pc ? "cell" : "point");
        for (size_t k = 0; k < n; k++) {
            if (!name_ok(a[k].name, legacy))
                return thx_error(ctx, THX_EINPUT, "%s: array name \"%s\" cannot be written (printable ASCII, no blank, "
                                 "'\"', '<', '>', '&' or '%%')", path, a[k].name ? a[k].name : "(null)");
            if (a[k].n_comp < 1 || a[k].n_comp > 9 || !a[k].v)
                return thx_error(ctx, THX_EINTERNAL, "%s: array \"%s\": %d components, values %s", path, a[k].name,
                                 a[k].n_comp, a[k].v ? "given" : "missing");
        }
    }
    return THX_OK;
}

/* A String array inline: each string's bytes as numbers, each string ended by 0 (VTK's ASCII
 * form); get(src, i) is string i. */
static void xml_strings(FILE *f, const char *name, const char *(*get)(const void *, size_t), const void *src, size_t n)
{
    fprintf(f, "      <Array type=\"String\" Name=\"%s\" NumberOfTuples=\"%zu\" format=\"ascii\">\n        ", name, n);
    for (size_t i = 0; i < n; i++) {
        for (const char *p = get(src, i); *p; p++) fprintf(f, "%d ", (unsigned char)*p);
        fputs(i + 1 < n ? "0 " : "0\n", f);
    }
    fputs("      </Array>\n", f);
}

static const char *surface_name_of(const void *m, size_t i) { return ((const thx_model *)m)->surf[i]->name; }
static const char *region_name_of(const void *v, size_t i) { return ((const thx_volume *)v)->regions[i].name; }

static void put_num(FILE *f, double v)
{
    fprintf(f, "%.17g", v + 0.0);
}

/* Field data of a volume or surface export. */
static void xml_field(FILE *f, const thx_model *m, int volume, const thx_export_frame *fr)
{
    fputs("    <FieldData>\n", f);
    if (fr && fr->has_time) {
        fputs("      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">\n        ", f);
        put_num(f, fr->time);
        fputs("\n      </DataArray>\n", f);
    }
    if (m->n_surfaces) xml_strings(f, "surface_name", surface_name_of, m, m->n_surfaces);
    if (volume && m->volume->n_regions) {
        const thx_volume *v = m->volume;
        xml_strings(f, "region_name", region_name_of, v, v->n_regions);
        fprintf(f, "      <DataArray type=\"Float64\" Name=\"region_sigma\" NumberOfComponents=\"9\" "
                   "NumberOfTuples=\"%zu\" format=\"ascii\">\n", v->n_regions);
        for (size_t r = 0; r < v->n_regions; r++) {
            fputs("        ", f);
            for (int k = 0; k < 9; k++) {
                put_num(f, v->regions[r].sigma[k]);
                fputs(k < 8 ? " " : "\n", f);
            }
        }
        fputs("      </DataArray>\n", f);
    }
    fputs("    </FieldData>\n", f);
}

/* ------------------------------------------------------------ volume (.vtu) */

thx_status thx_volume_export_vtu(thx_ctx *ctx, const thx_model *m, const thx_export_frame *fr, const char *path)
{
    if (!m->volume) return thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh to export", path);
    THX_CHECK(thx_model_volume_validate(ctx, m, path));
    THX_CHECK(check_frame(ctx, fr, path, 0));
    const thx_volume *v = m->volume;
    if (v->n_nodes > (size_t)INT32_MAX || v->n_tets > (size_t)INT32_MAX / 4)
        return thx_error(ctx, THX_EINPUT, "%s: the volume is too large to export", path);
    thx_status st = THX_OK;
    int32_t *ns = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *ns);
    int32_t *nn = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *nn);
    double *cond = thx_malloc(ctx, (v->n_tets ? v->n_tets : 1) * sizeof *cond);
    double *tens = NULL;
    int aniso = 0; /* the per-cell tensor in the geometry-only export (fr NULL): per frame it would double the file */
    for (size_t r = 0; r < v->n_regions && !fr; r++) aniso |= v->regions[r].anisotropic;
    if (aniso) tens = thx_malloc(ctx, (v->n_tets ? 9 * v->n_tets : 1) * sizeof *tens);
    lebuf *buf = thx_malloc(ctx, sizeof *buf);
    if (!ns || !nn || !cond || (aniso && !tens) || !buf) {
        st = THX_ENOMEM;
        goto done;
    }
    /* node tables, rebuilt from the forward tables (validated): -1 inside, written 1-based (0) */
    for (size_t w = 0; w < v->n_nodes; w++) ns[w] = nn[w] = -1;
    for (size_t s = 0; s < v->n_surfaces; s++)
        for (size_t i = 0; i < v->surf_n_nodes[s]; i++) {
            ns[v->surf_node[s][i]] = (int32_t)s;
            nn[v->surf_node[s][i]] = (int32_t)i;
        }
    for (size_t t = 0; t < v->n_tets; t++) {
        const double *sg = v->regions[v->region[t]].sigma;
        cond[t] = (sg[0] + sg[4] + sg[8]) / 3.0;
        if (tens) memcpy(tens + 9 * t, sg, 9 * sizeof *sg);
    }
    thx_atomic_file af;
    THX_TRY(thx_export_claim(ctx, THX_EXPORT_VTU, path));
    THX_TRY(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    blk_list L;
    L.n = 0;
    L.offset = 0;
    fprintf(f, "<?xml version=\"1.0\"?>\n<!-- thorax volume mesh, mm, with data -->\n"
               "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
               "  <UnstructuredGrid>\n");
    xml_field(f, m, 1, fr);
    fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n", v->n_nodes, v->n_tets);
    fputs("      <PointData>\n", f);
    declare(f, &L, "surface", 1, (blk){.kind = B_I32_PLUS, .n = v->n_nodes, .i = ns, .k = 1});
    declare(f, &L, "surface_node", 1, (blk){.kind = B_I32_PLUS, .n = v->n_nodes, .i = nn, .k = 1});
    for (size_t k = 0; fr && k < fr->n_point; k++)
        declare(f, &L, fr->point[k].name, fr->point[k].n_comp,
                (blk){.kind = B_F64, .n = v->n_nodes * (size_t)fr->point[k].n_comp, .f = fr->point[k].v});
    fputs("      </PointData>\n      <CellData>\n", f);
    declare(f, &L, "region", 1, (blk){.kind = B_I32_PLUS, .n = v->n_tets, .i = v->region, .k = 1});
    declare(f, &L, "conductivity", 1, (blk){.kind = B_F64, .n = v->n_tets, .f = cond});
    if (tens) declare(f, &L, "conductivity_tensor", 9, (blk){.kind = B_F64, .n = 9 * v->n_tets, .f = tens});
    for (size_t k = 0; fr && k < fr->n_cell; k++)
        declare(f, &L, fr->cell[k].name, fr->cell[k].n_comp,
                (blk){.kind = B_F64, .n = v->n_tets * (size_t)fr->cell[k].n_comp, .f = fr->cell[k].v});
    fputs("      </CellData>\n      <Points>\n", f);
    declare(f, &L, "Points", 3, (blk){.kind = B_F64, .n = 3 * v->n_nodes, .f = v->xyz});
    fputs("      </Points>\n      <Cells>\n", f);
    declare(f, &L, "connectivity", 1, (blk){.kind = B_I32_PLUS, .n = 4 * v->n_tets, .i = v->tet, .k = 0});
    declare(f, &L, "offsets", 1, (blk){.kind = B_I32_OFFSETS, .n = v->n_tets, .k = 4});
    declare(f, &L, "types", 1, (blk){.kind = B_U8_CONST, .n = v->n_tets, .k = 10}); /* VTK_TETRA */
    fputs("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n", f);
    write_appended(f, buf, &L);
    st = thx_atomic_commit(ctx, &af); /* checks ferror: a short write fails here */
done:
    free(buf);
    free(ns);
    free(nn);
    free(cond);
    free(tens);
    return st;
}

/* ------------------------------------------------------------ surfaces (.vtp, .vtk) */

static thx_status check_surface(thx_ctx *ctx, const thx_surface *s, const char *path)
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
    if (s->n_nodes > (size_t)INT32_MAX || s->n_tris > (size_t)INT32_MAX / 3)
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": too large to export", path, s->name);
    return THX_OK;
}

static void write_vtp(FILE *f, lebuf *buf, const thx_model *m, size_t si, const thx_export_frame *fr)
{
    const thx_surface *s = m->surf[si];
    blk_list L;
    L.n = 0;
    L.offset = 0;
    fprintf(f, "<?xml version=\"1.0\"?>\n<!-- thorax surface, mm, with data -->\n"
               "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
               "  <PolyData>\n");
    xml_field(f, m, 0, fr);
    fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
               "NumberOfPolys=\"%zu\">\n      <PointData>\n", s->n_nodes, s->n_tris);
    for (size_t k = 0; fr && k < fr->n_point; k++)
        declare(f, &L, fr->point[k].name, fr->point[k].n_comp,
                (blk){.kind = B_F64, .n = s->n_nodes * (size_t)fr->point[k].n_comp, .f = fr->point[k].v});
    fputs("      </PointData>\n      <CellData>\n", f);
    declare(f, &L, "surface", 1, (blk){.kind = B_I32_CONST, .n = s->n_tris, .k = (long long)si + 1});
    for (size_t k = 0; fr && k < fr->n_cell; k++)
        declare(f, &L, fr->cell[k].name, fr->cell[k].n_comp,
                (blk){.kind = B_F64, .n = s->n_tris * (size_t)fr->cell[k].n_comp, .f = fr->cell[k].v});
    fputs("      </CellData>\n      <Points>\n", f);
    declare(f, &L, "Points", 3, (blk){.kind = B_F64, .n = 3 * s->n_nodes, .f = s->xyz});
    fputs("      </Points>\n      <Polys>\n", f);
    declare(f, &L, "connectivity", 1, (blk){.kind = B_I32_PLUS, .n = 3 * s->n_tris, .i = s->tri, .k = 0});
    declare(f, &L, "offsets", 1, (blk){.kind = B_I32_OFFSETS, .n = s->n_tris, .k = 3});
    fputs("      </Polys>\n    </Piece>\n  </PolyData>\n", f);
    write_appended(f, buf, &L);
}

/* A string as one legacy token: characters other than [A-Za-z0-9_.-] as %XX (VTK's encoding). */
static void legacy_token(FILE *f, const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        int plain = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                    *p == '.' || *p == '-';
        if (plain) fputc(*p, f);
        else fprintf(f, "%%%02X", *p);
    }
}

static void legacy_values(FILE *f, const double *v, size_t n, int per_line)
{
    for (size_t i = 0; i < n; i++) {
        put_num(f, v[i]);
        fputc((i + 1) % (size_t)per_line == 0 || i + 1 == n ? '\n' : ' ', f);
    }
}

static void legacy_arrays(FILE *f, const thx_export_array *a, size_t n_arr, size_t n)
{
    for (size_t k = 0; k < n_arr; k++) {
        if (a[k].n_comp == 1) {
            fprintf(f, "SCALARS %s double 1\nLOOKUP_TABLE default\n", a[k].name);
            legacy_values(f, a[k].v, n, 1);
        } else if (a[k].n_comp == 3) {
            fprintf(f, "VECTORS %s double\n", a[k].name);
            legacy_values(f, a[k].v, 3 * n, 3);
        } else {
            fprintf(f, "FIELD FieldData 1\n%s %d %zu double\n", a[k].name, a[k].n_comp, n);
            legacy_values(f, a[k].v, (size_t)a[k].n_comp * n, a[k].n_comp);
        }
    }
}

static void write_vtk(FILE *f, const thx_model *m, size_t si, const thx_export_frame *fr)
{
    const thx_surface *s = m->surf[si];
    fputs("# vtk DataFile Version 3.0\nthorax surface ", f);
    legacy_token(f, s->name);
    fputs(" (mm, with data)\nASCII\nDATASET POLYDATA\n", f);
    int has_time = fr && fr->has_time;
    fprintf(f, "FIELD FieldData %d\n", 1 + has_time);
    if (has_time) {
        fputs("TimeValue 1 1 double\n", f);
        put_num(f, fr->time);
        fputc('\n', f);
    }
    fprintf(f, "surface_name 1 %zu string\n", m->n_surfaces);
    for (size_t k = 0; k < m->n_surfaces; k++) {
        legacy_token(f, m->surf[k]->name);
        fputc('\n', f);
    }
    fprintf(f, "POINTS %zu double\n", s->n_nodes);
    legacy_values(f, s->xyz, 3 * s->n_nodes, 3);
    fprintf(f, "POLYGONS %zu %zu\n", s->n_tris, 4 * s->n_tris);
    for (size_t t = 0; t < s->n_tris; t++)
        fprintf(f, "3 %ld %ld %ld\n", (long)s->tri[3 * t], (long)s->tri[3 * t + 1], (long)s->tri[3 * t + 2]);
    fprintf(f, "CELL_DATA %zu\nSCALARS surface int 1\nLOOKUP_TABLE default\n", s->n_tris);
    for (size_t t = 0; t < s->n_tris; t++) fprintf(f, "%zu\n", si + 1);
    if (fr) legacy_arrays(f, fr->cell, fr->n_cell, s->n_tris);
    if (fr && fr->n_point) {
        fprintf(f, "POINT_DATA %zu\n", s->n_nodes);
        legacy_arrays(f, fr->point, fr->n_point, s->n_nodes);
    }
}

thx_status thx_surface_export_data(thx_ctx *ctx, const thx_model *m, size_t si, thx_export_format fmt,
                                   const thx_export_frame *fr, const char *path)
{
    if (si >= m->n_surfaces) return thx_error(ctx, THX_EINTERNAL, "%s: surface %zu of %zu", path, si + 1, m->n_surfaces);
    if (fmt != THX_EXPORT_VTP && fmt != THX_EXPORT_VTK)
        return thx_error(ctx, THX_EINPUT, "%s: surface data go to vtp or vtk files", path);
    const thx_surface *s = m->surf[si];
    THX_CHECK(check_surface(ctx, s, path));
    THX_CHECK(check_frame(ctx, fr, path, fmt == THX_EXPORT_VTK));
    lebuf *buf = NULL;
    if (fmt == THX_EXPORT_VTP && !(buf = thx_malloc(ctx, sizeof *buf))) return THX_ENOMEM;
    thx_atomic_file af;
    thx_status st = thx_export_claim(ctx, fmt, path);
    if (st == THX_OK) st = thx_atomic_open(ctx, path, &af);
    if (st == THX_OK) {
        if (fmt == THX_EXPORT_VTP) write_vtp(af.f, buf, m, si, fr);
        else write_vtk(af.f, m, si, fr);
        st = thx_atomic_commit(ctx, &af);
    }
    free(buf);
    return st;
}

/* ------------------------------------------------------------ collection (.pvd) */

static const char pvd_marker[] = "<!-- thorax collection";

thx_status thx_export_pvd_claim(thx_ctx *ctx, const char *path)
{
    thx_atomic_file af;
    return thx_output_claim(ctx, path, pvd_marker, strlen(pvd_marker), NULL, 0, &af);
}

thx_status thx_export_pvd(thx_ctx *ctx, const char *path, const char *const *files, const double *times, size_t n)
{
    if (!n) return thx_error(ctx, THX_EINPUT, "%s: a collection of no dataset", path);
    for (size_t i = 0; i < n; i++) {
        if (!name_ok(files[i], 1))
            return thx_error(ctx, THX_EINPUT, "%s: file name \"%s\" cannot be written into a collection", path, files[i]);
        if (!isfinite(times[i]) || (i && !(times[i] > times[i - 1])))
            return thx_error(ctx, THX_EINPUT, "%s: dataset %zu: time %g is not finite and increasing", path, i + 1,
                             times[i]);
    }
    thx_atomic_file af;
    THX_CHECK(thx_export_pvd_claim(ctx, path));
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    fprintf(af.f, "<?xml version=\"1.0\"?>\n%s: %zu datasets -->\n"
                  "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
            pvd_marker, n);
    for (size_t i = 0; i < n; i++) {
        fputs("    <DataSet timestep=\"", af.f);
        put_num(af.f, times[i]);
        fprintf(af.f, "\" group=\"\" part=\"0\" file=\"%s\"/>\n", files[i]);
    }
    fputs("  </Collection>\n</VTKFile>\n", af.f);
    return thx_atomic_commit(ctx, &af);
}
