/* Tubes around current streamlines and the files of both (thorax/field/streamline.h): VTK XML
 * PolyData (.vtp) and Wavefront OBJ (.obj), docs/formats.md "Streamlines". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "field/streamline_impl.h"
#include "thorax/core/fileio.h"

void thx_stream_tubes_destroy(thx_stream_tubes **t)
{
    if (!t || !*t) return;
    free((*t)->xyz), free((*t)->normal), free((*t)->current), free((*t)->potential), free((*t)->tri), free((*t)->line);
    free(*t);
    *t = NULL;
}

static double norm3(double *a)
{
    double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (l > 0) a[0] /= l, a[1] /= l, a[2] /= l;
    return l;
}

/* A unit vector perpendicular to the unit vector t. */
static void perpendicular(const double t[3], double n[3])
{
    int a = fabs(t[0]) <= fabs(t[1]) && fabs(t[0]) <= fabs(t[2]) ? 0 : fabs(t[1]) <= fabs(t[2]) ? 1 : 2;
    double e[3] = {0, 0, 0};
    e[a] = 1;
    for (int c = 0; c < 3; c++) n[c] = e[c] - t[a] * t[c];
    norm3(n);
}

thx_status thx_stream_tubes_make(thx_ctx *ctx, const thx_streamlines *s, double radius, int sides, int caps,
                                 thx_stream_tubes **out)
{
    *out = NULL;
    if (!(radius > 0) || !isfinite(radius) || sides < 3 || sides > 64)
        return thx_error(ctx, THX_EINPUT, "tubes: the radius must be positive and the sides 3 to 64 (%g, %d)", radius,
                         sides);
    /* sizes first: at most every point a ring */
    size_t nv = 0, nt = 0;
    for (size_t l = 0; l < s->n_lines; l++) {
        size_t m = s->first[l + 1] - s->first[l];
        if (m < 2) continue;
        nv += m * (size_t)sides + (caps ? 2 : 0);
        nt += 2 * (m - 1) * (size_t)sides + (caps ? 2 * (size_t)sides : 0);
    }
    if (nv > INT32_MAX) return thx_error(ctx, THX_EINPUT, "tubes: %zu vertices, too many for 32-bit indices", nv);
    thx_stream_tubes *T = thx_calloc(ctx, 1, sizeof *T);
    if (!T) return THX_ENOMEM;
    T->xyz = thx_malloc(ctx, (3 * nv + 1) * sizeof *T->xyz);
    T->normal = thx_malloc(ctx, (3 * nv + 1) * sizeof *T->normal);
    T->current = thx_malloc(ctx, (nv + 1) * sizeof *T->current);
    T->potential = thx_malloc(ctx, (nv + 1) * sizeof *T->potential);
    T->tri = thx_malloc(ctx, (3 * nt + 1) * sizeof *T->tri);
    T->line = thx_malloc(ctx, (nt + 1) * sizeof *T->line);
    size_t *keep = thx_malloc(ctx, (s->n_points + 1) * sizeof *keep);
    if (!T->xyz || !T->normal || !T->current || !T->potential || !T->tri || !T->line || !keep) {
        free(keep);
        thx_stream_tubes_destroy(&T);
        return THX_ENOMEM;
    }
    size_t v = 0, t = 0;
    for (size_t l = 0; l < s->n_lines; l++) {
        /* the line's distinct points (a repeated point has no tangent) */
        size_t m = 0;
        for (size_t i = s->first[l]; i < s->first[l + 1]; i++) {
            const double *p = s->xyz + 3 * i;
            if (m) {
                const double *q = s->xyz + 3 * keep[m - 1];
                if (fabs(p[0] - q[0]) + fabs(p[1] - q[1]) + fabs(p[2] - q[2]) <= 1e-9 * radius) continue;
            }
            keep[m++] = i;
        }
        if (m < 2) continue;
        size_t v0 = v;
        double N[3] = {0, 0, 0}, Tg[3], T0[3] = {0, 0, 0}, Tn[3] = {0, 0, 0};
        for (size_t k = 0; k < m; k++) {
            const double *a = s->xyz + 3 * keep[k > 0 ? k - 1 : 0], *b = s->xyz + 3 * keep[k + 1 < m ? k + 1 : m - 1];
            for (int c = 0; c < 3; c++) Tg[c] = b[c] - a[c];
            norm3(Tg);
            if (k == 0) {
                perpendicular(Tg, N);
                memcpy(T0, Tg, sizeof T0);
            } else {
                /* parallel transport: the previous normal with its part along the tangent removed */
                double d = N[0] * Tg[0] + N[1] * Tg[1] + N[2] * Tg[2];
                for (int c = 0; c < 3; c++) N[c] -= d * Tg[c];
                if (norm3(N) < 1e-6) perpendicular(Tg, N);
            }
            memcpy(Tn, Tg, sizeof Tn);
            double B[3] = {Tg[1] * N[2] - Tg[2] * N[1], Tg[2] * N[0] - Tg[0] * N[2], Tg[0] * N[1] - Tg[1] * N[0]};
            const double *p = s->xyz + 3 * keep[k];
            for (int j = 0; j < sides; j++) {
                double th = 2 * M_PI * j / sides, cs = cos(th), sn = sin(th);
                for (int c = 0; c < 3; c++) {
                    double d = cs * N[c] + sn * B[c];
                    T->normal[3 * v + (size_t)c] = d;
                    T->xyz[3 * v + (size_t)c] = p[c] + radius * d;
                }
                T->current[v] = s->current[keep[k]];
                T->potential[v] = s->potential[keep[k]];
                v++;
            }
        }
        for (size_t k = 0; k + 1 < m; k++)
            for (int j = 0; j < sides; j++) {
                int32_t a = (int32_t)(v0 + k * (size_t)sides + (size_t)j);
                int32_t b = (int32_t)(v0 + k * (size_t)sides + (size_t)((j + 1) % sides));
                int32_t c = a + sides, d = b + sides;
                int32_t tr[6] = {a, b, c, b, d, c};
                memcpy(T->tri + 3 * t, tr, sizeof tr);
                T->line[t++] = (int32_t)l;
                T->line[t++] = (int32_t)l;
            }
        if (caps) {
            for (int e = 0; e < 2; e++) {
                const double *p = s->xyz + 3 * keep[e ? m - 1 : 0];
                const double *dir = e ? Tn : T0;
                size_t ring = v0 + (e ? (m - 1) * (size_t)sides : 0);
                for (int c = 0; c < 3; c++) {
                    T->xyz[3 * v + (size_t)c] = p[c];
                    T->normal[3 * v + (size_t)c] = e ? dir[c] : -dir[c];
                }
                T->current[v] = s->current[keep[e ? m - 1 : 0]];
                T->potential[v] = s->potential[keep[e ? m - 1 : 0]];
                for (int j = 0; j < sides; j++) {
                    int32_t a = (int32_t)(ring + (size_t)j), b = (int32_t)(ring + (size_t)((j + 1) % sides));
                    int32_t tr[3] = {(int32_t)v, e ? a : b, e ? b : a};
                    memcpy(T->tri + 3 * t, tr, sizeof tr);
                    T->line[t++] = (int32_t)l;
                }
                v++;
            }
        }
    }
    free(keep);
    T->n_vertices = v;
    T->n_tris = t;
    *out = T;
    return THX_OK;
}

static const char vtp_marker[] = "<!-- thorax streamlines";
static const char obj_marker[] = "# thorax streamlines";

/* One data array of the VTP: its section, name, VTK type, components, values (count of them, element
 * size) and its offset in the appended block. */
typedef struct {
    int where; /* 0 point data, 1 cell data, 2 points, 3 cells (connectivity, offsets) */
    const char *name, *type;
    int comps;
    const void *data;
    size_t n, elem, offset;
} vtp_array;

/* VTK XML PolyData, binary appended (raw, little-endian, UInt64 block headers): every array's values
 * after the XML header, in the order listed. Returns 0, or -1 when out of memory. */
static int write_vtp(FILE *f, const thx_streamlines *s, const thx_stream_tubes *T)
{
    size_t np = T ? T->n_vertices : s->n_points, nc = T ? T->n_tris : s->n_lines;
    size_t nconn = T ? 3 * T->n_tris : s->n_points;
    int32_t *cell[4] = {NULL, NULL, NULL, NULL};
    double *len = malloc((nc + 1) * sizeof *len);
    int64_t *conn = malloc((nconn + 1) * sizeof *conn), *offs = malloc((nc + 1) * sizeof *offs);
    int ok = len && conn && offs;
    for (int k = 0; k < 4; k++) ok = ok && (cell[k] = malloc((nc + 1) * sizeof *cell[k])) != NULL;
    if (!ok) {
        for (int k = 0; k < 4; k++) free(cell[k]);
        free(len), free(conn), free(offs);
        return -1;
    }
    for (size_t i = 0; i < nc; i++) {
        size_t l = T ? (size_t)T->line[i] : i;
        cell[0][i] = s->stop[l], cell[1][i] = s->direction[l], cell[2][i] = s->seed[l], cell[3][i] = (int32_t)l;
        len[i] = s->length[l];
        offs[i] = T ? (int64_t)(3 * (i + 1)) : (int64_t)s->first[i + 1];
    }
    for (size_t i = 0; i < nconn; i++) conn[i] = T ? (int64_t)T->tri[i] : (int64_t)i;
    vtp_array A[16];
    int na = 0;
#define ARR(w, nm, ty, c, d, cnt, el) A[na++] = (vtp_array){w, nm, ty, c, d, cnt, el, 0}
    ARR(0, "current_magnitude", "Float64", 1, T ? T->current : s->current, np, 8);
    ARR(0, "potential", "Float64", 1, T ? T->potential : s->potential, np, 8);
    if (T) ARR(0, "normals", "Float64", 3, T->normal, 3 * np, 8);
    else {
        ARR(0, "arc_length", "Float64", 1, s->arc, np, 8);
        ARR(0, "tet", "Int32", 1, s->tet, np, 4);
    }
    ARR(1, "stop_reason", "Int32", 1, cell[0], nc, 4);
    ARR(1, "direction", "Int32", 1, cell[1], nc, 4);
    ARR(1, "seed", "Int32", 1, cell[2], nc, 4);
    ARR(1, "line", "Int32", 1, cell[3], nc, 4);
    ARR(1, "length", "Float64", 1, len, nc, 8);
    ARR(2, "Points", "Float64", 3, T ? T->xyz : s->xyz, 3 * np, 8);
    ARR(3, "connectivity", "Int64", 1, conn, nconn, 8);
    ARR(3, "offsets", "Int64", 1, offs, nc, 8);
#undef ARR
    size_t off = 0;
    for (int k = 0; k < na; k++) {
        A[k].offset = off;
        off += 8 + A[k].n * A[k].elem;
    }
    fprintf(f, "<?xml version=\"1.0\"?>\n%s, mm: %s; stop_reason 0 boundary, 1 low_current, 2 max_length, 3 max_steps, "
               "4 loop -->\n", vtp_marker, T ? "tubes around the lines" : "lines");
    fputs("<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PolyData>\n", f);
    fprintf(f, "<Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" NumberOfLines=\"%zu\" NumberOfStrips=\"0\" "
               "NumberOfPolys=\"%zu\">\n", np, T ? (size_t)0 : nc, T ? nc : (size_t)0);
    static const char *const open[4] = {"<PointData Scalars=\"current_magnitude\"%s>\n", "<CellData Scalars=\"stop_reason\">\n",
                                        "<Points>\n", "<%s>\n"};
    static const char *const close[4] = {"</PointData>\n", "</CellData>\n", "</Points>\n", "</%s>\n"};
    for (int w = 0; w < 4; w++) {
        fprintf(f, open[w], w == 0 ? (T ? " Normals=\"normals\"" : "") : (T ? "Polys" : "Lines"));
        for (int k = 0; k < na; k++)
            if (A[k].where == w)
                fprintf(f, "<DataArray type=\"%s\" Name=\"%s\" NumberOfComponents=\"%d\" format=\"appended\" "
                           "offset=\"%zu\"/>\n", A[k].type, A[k].name, A[k].comps, A[k].offset);
        fprintf(f, close[w], T ? "Polys" : "Lines");
    }
    fputs("</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_", f);
    for (int k = 0; k < na; k++) {
        uint64_t bytes = (uint64_t)(A[k].n * A[k].elem);
        fwrite(&bytes, sizeof bytes, 1, f);
        if (A[k].n) fwrite(A[k].data, A[k].elem, A[k].n, f);
    }
    fputs("\n</AppendedData>\n</VTKFile>\n", f);
    for (int k = 0; k < 4; k++) free(cell[k]);
    free(len), free(conn), free(offs);
    return 0;
}

static void write_obj(FILE *f, const thx_streamlines *s, const thx_stream_tubes *T)
{
    fprintf(f, "%s, mm: %s\n", obj_marker, T ? "tubes around the lines" : "lines");
    fputs("# per line: its seed (0-based), direction (+1 forward, -1 backward), stop reason, length (mm)\n", f);
    fputs("o streamlines\n", f);
    size_t np = T ? T->n_vertices : s->n_points;
    const double *x = T ? T->xyz : s->xyz;
    for (size_t i = 0; i < np; i++) fprintf(f, "v %.10g %.10g %.10g\n", x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    if (T) {
        for (size_t i = 0; i < np; i++)
            fprintf(f, "vn %.6f %.6f %.6f\n", T->normal[3 * i], T->normal[3 * i + 1], T->normal[3 * i + 2]);
        int32_t prev = -1;
        for (size_t t = 0; t < T->n_tris; t++) {
            if (T->line[t] != prev) {
                prev = T->line[t];
                fprintf(f, "# line %d seed %d direction %+d stop %s length %.6g\n", (int)prev, (int)s->seed[prev],
                        (int)s->direction[prev], thx_stream_stop_name(s->stop[prev]), s->length[prev]);
            }
            const int32_t *q = T->tri + 3 * t;
            fprintf(f, "f %d//%d %d//%d %d//%d\n", q[0] + 1, q[0] + 1, q[1] + 1, q[1] + 1, q[2] + 1, q[2] + 1);
        }
        return;
    }
    for (size_t l = 0; l < s->n_lines; l++) {
        fprintf(f, "# line %zu seed %d direction %+d stop %s length %.6g\n", l, (int)s->seed[l], (int)s->direction[l],
                thx_stream_stop_name(s->stop[l]), s->length[l]);
        if (s->first[l + 1] - s->first[l] < 2) continue; /* OBJ's l needs two points */
        fputc('l', f);
        for (size_t i = s->first[l]; i < s->first[l + 1]; i++) fprintf(f, " %zu", i + 1);
        fputc('\n', f);
    }
}

thx_status thx_streamlines_write(thx_ctx *ctx, const thx_streamlines *s, const thx_stream_tubes *tubes,
                                 const char *path)
{
    const char *dot = strrchr(path, '.');
    int vtp = dot && !strcasecmp(dot, ".vtp"), obj = dot && !strcasecmp(dot, ".obj");
    if (!vtp && !obj)
        return thx_error(ctx, THX_EINPUT, "%s: streamlines go to .vtp or .obj files (the name's extension)", path);
    const char *marker = vtp ? vtp_marker : obj_marker;
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(ctx, path, marker, strlen(marker), NULL, 0, &af));
    if (vtp) {
        if (write_vtp(af.f, s, tubes)) {
            thx_atomic_abort(&af);
            return thx_error(ctx, THX_ENOMEM, "%s: out of memory writing the streamlines", path);
        }
    } else
        write_obj(af.f, s, tubes);
    return thx_atomic_commit(ctx, &af);
}
