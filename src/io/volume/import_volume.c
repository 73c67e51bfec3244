/*
 * Volume meshes made elsewhere: the format table and the dispatch to the
 * readers (see thorax/io/volume_read.h); the readers for .pts +
 * .tet/.elem (plain and CARP), legacy VTK and VTK XML unstructured grids and
 * Gmsh MSH 4.1 are src/io/import_vol_{pts,vtk,vtu,msh}.c, sharing
 * src/io/import_volume_impl.h.
 *
 * Decisions recorded here (docs/formats.md repeats them for users):
 *
 *  - Every reader fills one store (struct raw): nodes, tetrahedra with
 *    0-based nodes checked against the node count as they arrive, the
 *    file's region number per tetrahedron, and where the file has each
 *    tetrahedron (a line, a VTK cell index or a Gmsh element tag), so that
 *    a later refusal (a flat tetrahedron) still names it as the file does.
 *
 *  - Counts a file declares are never trusted beyond its size: before an
 *    array is allocated for n values, the bytes left must be able to hold
 *    them (binary: n times the value size; text: two characters a value;
 *    base64: four characters for three bytes; zlib: at most 1032 bytes out
 *    for one byte in, zlib's limit). Every reader requires its file to be
 *    complete (the closing line of every Gmsh section, the last value of
 *    every array): a file cut short is an error, never half a mesh.
 */
#include "io/volume/import_volume_impl.h"
/* ------------------------------------------------------------ formats */

static const char *const vformat_names[] = {"none", "pts/tet", "vtk", "vtu", "msh"};

const char *thx_volume_format_name(thx_volume_format f)
{
    return (f >= THX_VOLFMT_NONE && f <= THX_VOLFMT_MSH) ? vformat_names[f] : "unknown";
}

int thx_volume_format_parse(const char *s, thx_volume_format *out)
{
    static const struct { const char *name; thx_volume_format f; } tab[] = {
        {"tet", THX_VOLFMT_PTS}, {"elem", THX_VOLFMT_PTS}, {"carp", THX_VOLFMT_PTS}, {"pts/tet", THX_VOLFMT_PTS},
        {"vtk", THX_VOLFMT_VTK}, {"vtu", THX_VOLFMT_VTU}, {"msh", THX_VOLFMT_MSH},
    };
    if (!s) return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcasecmp(s, tab[i].name) == 0) {
            *out = tab[i].f;
            return 0;
        }
    return -1;
}



/* Does the legacy VTK file at path declare DATASET UNSTRUCTURED_GRID? */
static int vtk_is_ugrid(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    cursor c = {buf, n, 0, 1};
    if (n < 5 || strncasecmp(buf, "# vtk", 5) != 0) return 0;
    next_line(&c);
    next_line(&c);
    const char *t;
    int line;
    size_t k = next_token(&c, &t, &line); /* ASCII or BINARY */
    if (!k) return 0;
    k = next_token(&c, &t, &line);
    if (!tok_is(t, k, "DATASET")) return 0;
    k = next_token(&c, &t, &line);
    return tok_is(t, k, "UNSTRUCTURED_GRID");
}

thx_volume_format thx_volume_format_from_path(const char *path)
{
    if (!path) return THX_VOLFMT_NONE;
    const char *ext = path_extension(path);
    if (!strcasecmp(ext, "msh")) return THX_VOLFMT_MSH;
    if (!strcasecmp(ext, "vtu")) return THX_VOLFMT_VTU;
    if (!strcasecmp(ext, "tet") || !strcasecmp(ext, "elem")) return THX_VOLFMT_PTS;
    if (!strcasecmp(ext, "vtk")) return vtk_is_ugrid(path) ? THX_VOLFMT_VTK : THX_VOLFMT_NONE;
    if (!strcasecmp(ext, "pts")) {
        char other[1024];
        if (with_extension(other, sizeof other, path, "fac") == 0 && readable(other)) return THX_VOLFMT_NONE;
        if (with_extension(other, sizeof other, path, "tet") == 0 && readable(other)) return THX_VOLFMT_PTS;
        if (with_extension(other, sizeof other, path, "elem") == 0 && readable(other)) return THX_VOLFMT_PTS;
    }
    return THX_VOLFMT_NONE;
}

/* ------------------------------------------------------------ reading */

thx_status thx_volume_file_read(thx_ctx *ctx, const char *path, thx_volume_format fmt, const char *elem_path,
                                const char *region_array, thx_volume_file *r)
{
    memset(r, 0, sizeof *r);
    r->ctx = ctx, r->path = path, r->ref_kind = "element";
    if (fmt == THX_VOLFMT_NONE) fmt = thx_volume_format_from_path(path);
    if (fmt == THX_VOLFMT_NONE)
        return thx_error(ctx, THX_EINPUT, "%s: not a volume mesh format (.pts + .tet/.elem, .vtk unstructured grid, .vtu, .msh)",
                         path);
    if (fmt == THX_VOLFMT_PTS) return vol_read_ptselem(r, path, elem_path);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_status st;
    if (fmt == THX_VOLFMT_VTK) st = vol_read_vtk_ugrid(r, text, len, region_array);
    else if (fmt == THX_VOLFMT_VTU) st = vol_read_vtu(r, text, len, region_array);
    else st = vol_read_msh(r, text, len);
    free(text);
    return st;
}

void thx_volume_file_free(thx_volume_file *r)
{
    if (!r) return;
    free(r->xyz);
    free(r->node_tag);
    free(r->tet);
    free(r->tag);
    free(r->ref);
    free(r->tri);
    free(r->tri_tag);
    free(r->names);
    memset(r, 0, sizeof *r);
}

const char *thx_volume_file_name_of(const thx_volume_file *r, int dim, long long tag)
{
    for (size_t i = 0; i < r->n_names; i++)
        if (r->names[i].dim == dim && r->names[i].tag == tag) return r->names[i].name;
    return NULL;
}
