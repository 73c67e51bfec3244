/*
 * Surfaces made elsewhere: the format table, the .pts/.fac pair, the
 * dispatch to the readers (src/io/import_FORMAT.c, sharing
 * src/io/import_surface.h) and the import policy (see thorax/import.h).
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
#include "io/import_surface.h"
#include "thorax/model.h"

/* ------------------------------------------------------------ formats */

static const char *const format_names[] = {"auto", "pts/fac", "tri", "obj", "stl", "ply", "vtk", "vtp"};

const char *thx_import_format_name(thx_import_format f)
{
    return (f >= THX_IMPORT_AUTO && f <= THX_IMPORT_VTP) ? format_names[f] : "unknown";
}

int thx_import_format_parse(const char *s, thx_import_format *out)
{
    static const struct { const char *name; thx_import_format f; } tab[] = {
        {"pts", THX_IMPORT_PTSFAC}, {"fac", THX_IMPORT_PTSFAC}, {"pts/fac", THX_IMPORT_PTSFAC},
        {"tri", THX_IMPORT_TRI}, {"obj", THX_IMPORT_OBJ}, {"stl", THX_IMPORT_STL},
        {"ply", THX_IMPORT_PLY}, {"vtk", THX_IMPORT_VTK}, {"vtp", THX_IMPORT_VTP},
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
    if (!path || thx_import_format_parse(path_extension(path), &f) != 0) return THX_IMPORT_AUTO;
    return f;
}

void thx_import_opts_default(thx_import_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = THX_IMPORT_AUTO;
    o->scale = 1.0;
    o->force = 0;
    thx_check_opts_default(&o->check);
}

void thx_import_info_free(thx_import_info *info)
{
    if (!info) return;
    thx_surface_report_free(&info->report);
    memset(info, 0, sizeof *info);
}


/* ----------------------------------------------------------- .pts/.fac */

static thx_status read_ptsfac(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              thx_surface **out, thx_import_info *info)
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
                                 const char *name, thx_role role, thx_surface **out, thx_import_info *info)
{
    *out = NULL;
    if (info) {
        memset(info, 0, sizeof *info); /* overwritten, not freed: see import.h */
        info->index_base = 0;
        info->scale = 1.0;
    }
    if (fmt == THX_IMPORT_AUTO) fmt = thx_import_format_from_path(path);
    if (fmt == THX_IMPORT_AUTO)
        return thx_error(ctx, THX_EINPUT,
                         "%s: surface \"%s\": cannot tell the format from the extension \"%s\" (known: .pts/.fac, .tri, "
                         ".obj, .stl, .ply, .vtk, .vtp)", path, name, path_extension(path));
    if (info) info->format = fmt;
    thx_status st = THX_OK;
    if (fmt == THX_IMPORT_PTSFAC) {
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

/* ------------------------------------------------------------- import */

/* Removes nodes used by no triangle, keeping the order of the rest. */
static thx_status remove_unused(thx_ctx *ctx, thx_surface *s, size_t *removed, long *first)
{
    *removed = 0;
    *first = -1;
    int32_t *map = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * sizeof *map);
    if (!map) return THX_ENOMEM;
    for (size_t i = 0; i < s->n_nodes; i++) map[i] = -1;
    for (size_t i = 0; i < 3 * s->n_tris; i++) map[s->tri[i]] = 0;
    size_t k = 0;
    for (size_t i = 0; i < s->n_nodes; i++) {
        if (map[i] < 0) {
            if (*first < 0) *first = (long)i;
            continue;
        }
        map[i] = (int32_t)k;
        if (k != i) memmove(s->xyz + 3 * k, s->xyz + 3 * i, 3 * sizeof *s->xyz);
        k++;
    }
    for (size_t i = 0; i < 3 * s->n_tris; i++) s->tri[i] = map[s->tri[i]];
    *removed = s->n_nodes - k;
    s->n_nodes = k;
    free(map);
    return THX_OK;
}

/* Closed, manifold and consistently oriented, but enclosing a negative volume:
 * every triangle is clockwise seen from outside (policy step 5). */
static int inward_only(const thx_surface_report *r)
{
    return !(r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX)) && r->n_boundary_edges == 0 &&
           r->n_nonmanifold_edges == 0 && r->n_nonmanifold_vertices == 0 && r->n_inconsistent_edges == 0 &&
           r->volume < 0;
}

thx_status thx_surface_import(thx_ctx *ctx, const char *path, const char *path2, const char *name, thx_role role,
                              const thx_import_opts *opts, thx_surface **out, thx_import_info *info)
{
    thx_import_opts def;
    if (!opts) {
        thx_import_opts_default(&def);
        opts = &def;
    }
    *out = NULL;
    thx_import_info local;
    if (!info) {
        memset(&local, 0, sizeof local);
        info = &local;
    }
    if (!(opts->scale > 0) || !isfinite(opts->scale))
        return thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": scale %g must be a finite positive number", path, name,
                         opts->scale);
    thx_surface *s = NULL;
    thx_status st;
    THX_TRY(thx_surface_read_file(ctx, path, path2, opts->format, name, role, &s, info));
    info->scale = opts->scale;
    if (opts->scale != 1.0)
        for (size_t i = 0; i < 3 * s->n_nodes; i++) {
            s->xyz[i] *= opts->scale;
            if (!isfinite(s->xyz[i])) {
                st = thx_error(ctx, THX_EINPUT, "%s: surface \"%s\": node %zu is not finite after scaling by %g", path,
                               name, i / 3 + 1, opts->scale);
                goto done;
            }
        }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < s->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], s->xyz[3 * i + (size_t)k]);
            hi[k] = fmax(hi[k], s->xyz[3 * i + (size_t)k]);
        }
    info->extent = s->n_nodes ? fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2])) : 0;
    THX_TRY(remove_unused(ctx, s, &info->n_unused_removed, &info->first_unused));
    if (info->first_unused >= 0 && info->index_base > 0) info->first_unused += info->index_base;

    st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
    if (st != THX_OK && st != THX_ECHECK) goto done;
    if (inward_only(&info->report)) {
        for (size_t t = 0; t < s->n_tris; t++) {
            int32_t tmp = s->tri[3 * t + 1];
            s->tri[3 * t + 1] = s->tri[3 * t + 2];
            s->tri[3 * t + 2] = tmp;
        }
        info->reversed = 1;
        info->omega_before = info->report.solid_angle;
        thx_surface_report_free(&info->report);
        st = thx_surface_check(ctx, s, NULL, &opts->check, &info->report);
        if (st != THX_OK && st != THX_ECHECK) goto done;
    }
    if (st == THX_ECHECK) {
        info->check_failed = 1;
        const thx_surface_report *r = &info->report;
        if (!opts->force) {
            char more[48] = "";
            if (r->n_reasons > 1) snprintf(more, sizeof more, " (and %zu more)", r->n_reasons - 1);
            st = thx_error(ctx, THX_ECHECK, "%s: surface \"%s\": refused: %s%s", path, name,
                           r->n_reasons ? r->reasons[0] : "failed its checks", more);
            goto done;
        }
        thx_ctx_clear(ctx);
        st = THX_OK;
    }
    *out = s;
    s = NULL;
done:
    thx_surface_destroy(&s);
    if (info == &local) thx_import_info_free(&local);
    return st;
}
