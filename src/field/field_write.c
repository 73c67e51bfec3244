/*
 * Writers of cut meshes (thorax/field/field.h; docs/formats.md, "Slices and equipotential
 * surfaces"): VTK XML PolyData (.vtp, binary appended, little-endian, UInt64 headers, Float64
 * values) and Wavefront OBJ. The second line of either carries "thorax field", the claim's
 * signature: an existing file is replaced only when it is such a file (thorax/core/fileio.h).
 * VTK numbers a PolyData's cells verts, lines, polys, strips: cell data list the contour lines
 * first, then the triangles.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "field_impl.h"

static const char vtp_marker[] = "<!-- thorax field";
static const char obj_marker[] = "# thorax field";

thx_status thx_field_claim(thx_ctx *ctx, const char *path)
{
    size_t l = strlen(path);
    int obj = l > 4 && !strcmp(path + l - 4, ".obj");
    const char *mk = obj ? obj_marker : vtp_marker;
    thx_atomic_file af;
    return thx_output_claim(ctx, path, mk, strlen(mk), NULL, 0, &af);
}

/* One appended array: n values of 8 (Float64) or 4 (Int32) bytes. */
typedef struct {
    const char *name;
    int n_comp, f64;
    size_t n;
    const void *p;
} arr;

static void put_le(FILE *f, const void *p, size_t n, size_t elem)
{
    unsigned char buf[8192];
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        uint64_t u = 0;
        if (elem == 8) {
            double d = ((const double *)p)[i] + 0.0;
            memcpy(&u, &d, 8);
        } else {
            u = (uint32_t)((const int32_t *)p)[i];
        }
        if (k + elem > sizeof buf) {
            fwrite(buf, 1, k, f);
            k = 0;
        }
        for (size_t b = 0; b < elem; b++) buf[k++] = (unsigned char)(u >> (8 * b));
    }
    fwrite(buf, 1, k, f);
}

static void declare(FILE *f, const arr *a, uint64_t *off)
{
    fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", a->f64 ? "Float64" : "Int32", a->name);
    if (a->n_comp > 1) fprintf(f, " NumberOfComponents=\"%d\"", a->n_comp);
    fprintf(f, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)*off);
    *off += 8 + a->n * (a->f64 ? 8 : 4);
}

static int name_ok(const char *s)
{
    if (!s || !*s) return 0;
    for (; *s; s++)
        if (*s < 32 || *s > 126 || *s == '"' || *s == '<' || *s == '>' || *s == '&') return 0;
    return 1;
}

thx_status thx_field_mesh_write_vtp(thx_ctx *ctx, const thx_field_mesh *m, const thx_field_write_opts *o,
                                    const char *path)
{
    thx_field_write_opts none;
    memset(&none, 0, sizeof none);
    if (!o) o = &none;
    if ((o->tag_name[0] && (!name_ok(o->tag_name[0]) || !o->tag_value[0])) ||
        (o->tag_name[1] && (!name_ok(o->tag_name[1]) || !o->tag_value[1])) ||
        (o->cell_scalar && !name_ok(o->cell_scalar_name)))
        return thx_error(ctx, THX_EINTERNAL, "%s: a cell array without a printable name or values", path);
    size_t np = m->n_points + m->n_cpoints, nl = m->n_segs, nt = m->n_tris, nc = nl + nt;
    if (np > (size_t)INT32_MAX || 3 * nt + 2 * nl > (size_t)INT32_MAX)
        return thx_error(ctx, THX_EINPUT, "%s: too large for Int32 connectivity", path);
    double *xyz = thx_malloc(ctx, 3 * (np + 1) * sizeof *xyz), *pot = thx_malloc(ctx, (np + 1) * sizeof *pot);
    int32_t *lconn = thx_malloc(ctx, (2 * nl + 1) * sizeof *lconn), *loff = thx_malloc(ctx, (nl + 1) * sizeof *loff);
    int32_t *poff = thx_malloc(ctx, (nt + 1) * sizeof *poff), *tet = thx_malloc(ctx, (nc + 1) * sizeof *tet);
    double *tagv = thx_malloc(ctx, 2 * (nc + 1) * sizeof *tagv), *cs = thx_malloc(ctx, (nc + 1) * sizeof *cs);
    double *cv = thx_malloc(ctx, (nc + 1) * sizeof *cv);
    thx_status st = THX_OK;
    if (!xyz || !pot || !lconn || !loff || !poff || !tet || !tagv || !cs || !cv) {
        st = THX_ENOMEM;
        goto done;
    }
    /* (an empty array may be NULL, which memcpy must not be given even for 0 bytes) */
    if (m->n_points) {
        memcpy(xyz, m->xyz, 3 * m->n_points * sizeof *xyz);
        memcpy(pot, m->value, m->n_points * sizeof *pot);
    }
    if (m->n_cpoints) {
        memcpy(xyz + 3 * m->n_points, m->cxyz, 3 * m->n_cpoints * sizeof *xyz);
        memcpy(pot + m->n_points, m->cvalue, m->n_cpoints * sizeof *pot);
    }
    for (size_t s = 0; s < nl; s++) {
        lconn[2 * s] = m->seg[2 * s] + (int32_t)m->n_points;
        lconn[2 * s + 1] = m->seg[2 * s + 1] + (int32_t)m->n_points;
        loff[s] = (int32_t)(2 * s + 2);
    }
    for (size_t t = 0; t < nt; t++) poff[t] = (int32_t)(3 * t + 3);
    for (size_t c = 0; c < nc; c++) {
        size_t t = c < nl ? (size_t)m->seg_tri[c] : c - nl; /* a line: the triangle it crosses */
        tet[c] = m->cell[t];
        for (int i = 0; i < 2; i++) tagv[i * nc + c] = o->tag_value[i] ? o->tag_value[i][m->tag[t]] : 0;
        cs[c] = o->cell_scalar ? o->cell_scalar[m->cell[t]] : 0;
        cv[c] = c < nl && o->seg_value ? o->seg_value[m->seg_tag[c]] : NAN;
    }
    arr pd[] = {{"potential", 1, 1, np, pot}};
    arr cd[5];
    size_t ncd = 0;
    for (int i = 0; i < 2; i++)
        if (o->tag_name[i]) cd[ncd++] = (arr){o->tag_name[i], 1, 1, nc, tagv + (size_t)i * nc};
    if (o->cell_scalar) cd[ncd++] = (arr){o->cell_scalar_name, 1, 1, nc, cs};
    if (nl && o->seg_value) cd[ncd++] = (arr){"contour_value", 1, 1, nc, cv};
    cd[ncd++] = (arr){"tetrahedron", 1, 0, nc, tet};
    arr pts = {"Points", 3, 1, 3 * np, xyz};
    arr lines[] = {{"connectivity", 1, 0, 2 * nl, lconn}, {"offsets", 1, 0, nl, loff}};
    arr polys[] = {{"connectivity", 1, 0, 3 * nt, m->tri}, {"offsets", 1, 0, nt, poff}};
    thx_atomic_file af;
    THX_TRY(thx_field_claim(ctx, path));
    THX_TRY(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    uint64_t off = 0;
    fprintf(f, "<?xml version=\"1.0\"?>\n%s, mm -->\n"
               "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
               "  <PolyData>\n", vtp_marker);
    if (o->has_time) {
        fprintf(f, "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
                   "format=\"ascii\">%.17g</DataArray>\n    </FieldData>\n", o->time);
    }
    fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" NumberOfLines=\"%zu\" NumberOfStrips=\"0\" "
               "NumberOfPolys=\"%zu\">\n      <PointData Scalars=\"potential\">\n", np, nl, nt);
    declare(f, &pd[0], &off);
    fputs("      </PointData>\n      <CellData>\n", f);
    for (size_t k = 0; k < ncd; k++) declare(f, &cd[k], &off);
    fputs("      </CellData>\n      <Points>\n", f);
    declare(f, &pts, &off);
    fputs("      </Points>\n      <Lines>\n", f);
    for (int k = 0; k < 2; k++) declare(f, &lines[k], &off);
    fputs("      </Lines>\n      <Polys>\n", f);
    for (int k = 0; k < 2; k++) declare(f, &polys[k], &off);
    fputs("      </Polys>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _", f);
    const arr *all[16];
    size_t na = 0;
    all[na++] = &pd[0];
    for (size_t k = 0; k < ncd; k++) all[na++] = &cd[k];
    all[na++] = &pts;
    all[na++] = &lines[0];
    all[na++] = &lines[1];
    all[na++] = &polys[0];
    all[na++] = &polys[1];
    for (size_t k = 0; k < na; k++) {
        uint64_t bytes = all[k]->n * (all[k]->f64 ? 8 : 4);
        unsigned char h[8];
        for (int b = 0; b < 8; b++) h[b] = (unsigned char)(bytes >> (8 * b));
        fwrite(h, 1, 8, f);
        put_le(f, all[k]->p, all[k]->n, all[k]->f64 ? 8 : 4);
    }
    fputs("\n  </AppendedData>\n</VTKFile>\n", f);
    st = thx_atomic_commit(ctx, &af);
done:
    free(xyz);
    free(pot);
    free(lconn);
    free(loff);
    free(poff);
    free(tet);
    free(tagv);
    free(cs);
    free(cv);
    return st;
}

thx_status thx_field_mesh_write_obj(thx_ctx *ctx, const thx_field_mesh *m, const char *const *tag_names, size_t n_tags,
                                    const char *path)
{
    for (size_t t = 0; tag_names && t < n_tags; t++)
        if (!tag_names[t] || !*tag_names[t] || strpbrk(tag_names[t], " \t\r\n"))
            return thx_error(ctx, THX_EINTERNAL, "%s: OBJ group name %zu is not one word", path, t + 1);
    for (size_t t = 0; tag_names && t < m->n_tris; t++)
        if (m->tag[t] < 0 || (size_t)m->tag[t] >= n_tags)
            return thx_error(ctx, THX_EINTERNAL, "%s: triangle %zu has tag %ld of %zu names", path, t + 1, (long)m->tag[t],
                             n_tags);
    thx_atomic_file af;
    THX_CHECK(thx_field_claim(ctx, path));
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    fprintf(f, "# Wavefront OBJ\n%s: %zu vertices, %zu triangles, %zu contour segments; mm; no potentials (OBJ "
               "has no vertex data: use .vtp)\n", obj_marker, m->n_points + m->n_cpoints, m->n_tris, m->n_segs);
    for (size_t i = 0; i < m->n_points; i++)
        fprintf(f, "v %.17g %.17g %.17g\n", m->xyz[3 * i] + 0.0, m->xyz[3 * i + 1] + 0.0, m->xyz[3 * i + 2] + 0.0);
    for (size_t i = 0; i < m->n_cpoints; i++)
        fprintf(f, "v %.17g %.17g %.17g\n", m->cxyz[3 * i] + 0.0, m->cxyz[3 * i + 1] + 0.0, m->cxyz[3 * i + 2] + 0.0);
    int32_t g = -1;
    for (size_t t = 0; t < m->n_tris; t++) {
        if (m->tag[t] != g) {
            g = m->tag[t];
            if (tag_names) fprintf(f, "g %s\n", tag_names[g]);
            else fprintf(f, "g cut_%ld\n", (long)g + 1);
        }
        fprintf(f, "f %ld %ld %ld\n", (long)m->tri[3 * t] + 1, (long)m->tri[3 * t + 1] + 1, (long)m->tri[3 * t + 2] + 1);
    }
    if (m->n_segs) fputs("g contours\n", f);
    for (size_t s = 0; s < m->n_segs; s++)
        fprintf(f, "l %ld %ld\n", (long)(m->seg[2 * s] + (int32_t)m->n_points) + 1,
                (long)(m->seg[2 * s + 1] + (int32_t)m->n_points) + 1);
    return thx_atomic_commit(ctx, &af);
}
