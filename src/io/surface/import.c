/*
 * Surfaces made elsewhere: the format table, the .pts/.fac pair and the
 * dispatch to the readers (src/io/import_FORMAT.c, sharing
 * src/io/import_surface.h); see thorax/io/surface_read.h.
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Every reader builds into one growable node/triangle store (struct
 *    build) whose indices are 0-based and range-checked as they arrive, so an
 *    out-of-range index is reported at the line (or byte) that holds it.
 *
 *  - Text is read whole (thx_read_file) and scanned by a cursor that counts
 *    lines; numbers are parsed with strtod/strtoll on a NUL-terminated copy
 *    of the token, and must be finite. Integers in files may be written as
 *    "3" or "3.0" (some PLY/VTK writers do), but must be integral.
 *
 *  - Binary data (STL, PLY, VTK) is read byte by byte with explicit byte
 *    order, never by casting the buffer, so the host's byte order and
 *    alignment do not matter. Errors give the byte offset.
 *
 *  - Polygons with more than three vertices are split into the fan
 *    (v0, vi, vi+1), which keeps their winding; a non-convex polygon may give
 *    overlapping triangles, which the self-intersection check then finds.
 */
#include "io/surface/import_surface.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/graphicsio.h"
/* ------------------------------------------------------------ formats */

static const char *const format_names[] = {"auto", "pts/fac", "tri", "obj", "stl", "ply", "vtk", "vtp", "geom"};

const char *thx_import_format_name(thx_import_format f)
{
    return (f >= THX_IMPORT_AUTO && f <= THX_IMPORT_GEOM) ? format_names[f] : "unknown";
}

int thx_import_format_parse(const char *s, thx_import_format *out)
{
    static const struct { const char *name; thx_import_format f; } tab[] = {
        {"pts", THX_IMPORT_PTSFAC}, {"fac", THX_IMPORT_PTSFAC}, {"pts/fac", THX_IMPORT_PTSFAC},
        {"tri", THX_IMPORT_TRI}, {"obj", THX_IMPORT_OBJ}, {"stl", THX_IMPORT_STL},
        {"ply", THX_IMPORT_PLY}, {"vtk", THX_IMPORT_VTK}, {"vtp", THX_IMPORT_VTP}, {"geom", THX_IMPORT_GEOM},
    };
    if (!s) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcasecmp(s, tab[i].name) == 0) {
            *out = tab[i].f;
            return 0;
        }
    return -1;
}


thx_import_format thx_import_format_from_path(const char *path)
{
    thx_import_format f;
    char file[4096];
    const char *sel = NULL;
    if (path && thx_gio_split_select(path, "geom", file, sizeof file, &sel) == 0 && sel) return THX_IMPORT_GEOM;
    if (!path || thx_import_format_parse(path_extension(path), &f) != 0) return THX_IMPORT_AUTO;
    return f;
}

/* ----------------------------------------------------------- .pts/.fac */

static thx_status read_ptsfac(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              thx_surface **out, thx_surface_read_info *info)
{
    char other[1024];
    const char *pts = path, *fac = path2;
    const char *ext = path_extension(path);
    int given_fac = strcasecmp(ext, "fac") == 0;
    if (given_fac) { /* the user named the .fac: the .pts is the other one */
        fac = path;
        pts = path2;
    }
    if (!(given_fac ? pts : fac)) {
        size_t stem = strlen(path) - strlen(ext);
        if (!ext[0] || stem + 4 > sizeof other)
            return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": cannot tell the name of the %s file that goes with it",
                             path, name, given_fac ? ".pts" : ".fac");
        memcpy(other, path, stem);
        /* keep the case of the extension given: .PTS goes with .FAC */
        const char *want = given_fac ? (isupper((unsigned char)ext[0]) ? "PTS" : "pts")
                                     : (isupper((unsigned char)ext[0]) ? "FAC" : "fac");
        memcpy(other + stem, want, 4);
        if (given_fac) pts = other;
        else fac = other;
    }
    int base = 1;
    THX_CHECK(thx_surface_read_ptsfac(ctx, pts, fac, name, role, out, &base));
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "map3d .pts/.fac");
        snprintf(info->path2, sizeof info->path2, "%s", given_fac ? pts : fac);
        info->index_base = base;
        info->index_base_detected = 1;
    }
    return THX_OK;
}

/* ----------------------------------------------------------- dispatch */

thx_status thx_surface_read_file(thx_ctx *ctx, const char *path, const char *path2, thx_import_format fmt,
                                 const char *name, thx_role role, thx_surface **out, thx_surface_read_info *info)
{
    *out = NULL;
    if (info) memset(info, 0, sizeof *info);
    if (fmt == THX_IMPORT_AUTO) fmt = thx_import_format_from_path(path);
    if (fmt == THX_IMPORT_AUTO)
        return thx_error(ctx, THX_EINPUT,
                         "%s: surface \"%s\": cannot tell the format from the extension \"%s\" (known: .pts/.fac, .tri, "
                         ".obj, .stl, .ply, .vtk, .vtp, .geom)", path, name, path_extension(path));
    if (info) info->format = fmt;
    thx_status st = THX_OK;
    if (fmt == THX_IMPORT_GEOM) {
        char file[4096];
        const char *sel = NULL;
        if (thx_gio_split_select(path, "geom", file, sizeof file, &sel) != 0)
            return thx_error(ctx, THX_EIO, "%s: path too long", path);
        char *buf = NULL;
        size_t len = 0;
        THX_CHECK(thx_read_file(ctx, file, &buf, &len));
        thx_geom_info gi;
        st = thx_geom_parse(ctx, file, (const unsigned char *)buf, len, sel, name, role, out, &gi);
        free(buf);
        if (st == THX_OK && info) {
            snprintf(info->format_detail, sizeof info->format_detail, "map3d graphicsio .geom, surface %zu of %zu",
                     gi.index, gi.n_surfaces);
            info->index_base = 1;
            info->index_base_detected = 0;
        }
    } else if (fmt == THX_IMPORT_PTSFAC) {
        st = read_ptsfac(ctx, path, path2, name, role, out, info);
    } else {
        char *text = NULL;
        size_t len = 0;
        THX_CHECK(thx_read_file(ctx, path, &text, &len));
        build b;
        memset(&b, 0, sizeof b);
        b.ctx = ctx, b.path = path, b.name = name;
        /* Text formats hold no NUL byte: one means a binary or damaged file (the
         * binary formats, STL, PLY and VTK, check their text parts themselves). */
        int zl = (fmt == THX_IMPORT_TRI || fmt == THX_IMPORT_OBJ || fmt == THX_IMPORT_VTP) ? nul_line(text, len) : 0;
        if (zl) {
            st = fail(&b, at_line(zl), "NUL byte at byte %zu: not a text file, or a damaged one",
                      (size_t)((const char *)memchr(text, 0, len) - text));
        } else switch (fmt) {
        case THX_IMPORT_TRI: st = import_read_tri(&b, text, len, info); break;
        case THX_IMPORT_OBJ: st = import_read_obj(&b, text, len, info); break;
        case THX_IMPORT_STL: st = import_read_stl(&b, text, len, info); break;
        case THX_IMPORT_PLY: st = import_read_ply(&b, text, len, info); break;
        case THX_IMPORT_VTK: st = import_read_vtk(&b, text, len, info); break;
        case THX_IMPORT_VTP: st = import_read_vtp(&b, text, len, info); break;
        default: st = thx_error(ctx, THX_EINTERNAL, "%s: unknown import format %d", path, (int)fmt); break;
        }
        if (st == THX_OK && b.n_nodes == 0) st = fail(&b, at_line(1), "no nodes");
        if (st == THX_OK) st = finish(&b, role, out);
        if (info) {
            info->n_polygons_split = b.n_split;
            info->n_cells_ignored = b.n_ignored;
        }
        free(b.xyz);
        free(b.tri);
        free(text);
    }
    if (st == THX_OK && info) {
        info->n_nodes_read = (*out)->n_nodes;
        info->n_tris_read = (*out)->n_tris;
    }
    return st;
}
