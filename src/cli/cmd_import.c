/* thorax import: a model directory from closed surfaces made elsewhere
 * (.pts/.fac, ECGSim and OpenMEEG .tri, OBJ, STL, PLY, VTK, VTP, map3d .geom), each checked
 * as `thorax check` does, or from one tetrahedral volume mesh (.pts +
 * .tet/.elem, CARP, VTK unstructured grid, VTU, Gmsh .msh), its regions mapped
 * to tissues and conductivities, its surfaces extracted and the whole checked. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/check/check.h"
#include "thorax/import/import.h"
#include "thorax/mesh/mesh.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
typedef struct {
    const char *file, *fac, *name, *elem, *fmt_text;
    thx_role role;
    int has_role;
    thx_import_format fmt;
    double scale;
    int has_scale;
    thx_volume_format vfmt; /* THX_VOLFMT_NONE: a surface */
} spec;

/* One line describing the check's figures. */
static void print_check(const thx_surface_report *r)
{
    printf("  check: %zu nodes, %zu triangles", r->n_nodes, r->n_tris);
    if (!(r->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX))) {
        int closed = !(r->n_boundary_edges || r->n_nonmanifold_edges || r->n_nonmanifold_vertices);
        printf(", %s", closed ? "closed" : r->n_boundary_edges ? "not closed" : "non-manifold");
        /* the sign of the volume tells the orientation only of a closed surface */
        if (r->n_inconsistent_edges) printf(", inconsistent orientation");
        else if (closed) printf(", %s", r->volume > 0 ? "outward" : "inward");
    }
    if (r->solid_angle_rel_err == r->solid_angle_rel_err)
        printf(", Omega/4pi = %.12g (|error| %.2e)", r->solid_angle / (4 * M_PI), r->solid_angle_rel_err);
    else
        printf(", no interior point");
    if (r->intersections_checked) printf(", %zu intersecting pairs", r->n_intersecting_pairs);
    if (r->min_angle == r->min_angle) printf(", min angle %.2f deg", r->min_angle);
    if (isinf(r->max_aspect)) printf(", worst aspect inf");
    else if (r->max_aspect == r->max_aspect) printf(", worst aspect %.3g", r->max_aspect);
    printf(": %s\n", r->ok ? "ok" : "FAILED");
}

static void print_report(const spec *sp, const thx_import_info *in)
{
    printf("surface \"%s\" (%s) from %s%s%s\n", sp->name, thx_role_name(sp->role), sp->file, in->read.path2[0] ? " + " : "",
           in->read.path2);
    printf("  read: %s, %zu nodes, %zu triangles", in->read.format_detail, in->read.n_nodes_read, in->read.n_tris_read);
    if (in->read.index_base >= 0)
        printf("; node numbers %d-based (%s)", in->read.index_base, in->read.index_base_detected ? "detected" : "by the format");
    printf("\n");
    if (in->read.n_polygons_split) printf("  split %zu polygons with more than 3 vertices into triangle fans\n", in->read.n_polygons_split);
    if (in->read.n_corners_merged) printf("  merged %zu STL facet corners into %zu shared nodes\n", in->read.n_corners_merged, in->read.n_nodes_read);
    if (in->read.n_cells_ignored) printf("  ignored %zu vertex/line cells (not triangles)\n", in->read.n_cells_ignored);
    if (in->read.trailer_line) printf("  ignored the text after the last triangle (from line %d)\n", in->read.trailer_line);
    if (in->scale != 1.0) printf("  scaled coordinates by %g\n", in->scale);
    if (in->n_unused_removed)
        printf("  removed %zu unused nodes (in no triangle; the first is node %ld as numbered in the file); the rest "
               "renumbered\n", in->n_unused_removed, in->first_unused);
    if (in->reversed)
        printf("  reversed: triangles were clockwise seen from outside (Omega/4pi was %.12g)\n", in->omega_before / (4 * M_PI));
    print_check(&in->report);
}

static void add_num(cJSON *o, const char *key, double v)
{
    if (isfinite(v)) cJSON_AddNumberToObject(o, key, v);
    else cJSON_AddNullToObject(o, key);
}

static cJSON *input_json(const spec *sp, const thx_import_info *in)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    cJSON_AddStringToObject(o, "surface", sp->name);
    cJSON_AddStringToObject(o, "role", thx_role_name(sp->role));
    cJSON_AddStringToObject(o, "file", sp->file);
    if (in->read.path2[0]) {
        /* a pair named by its .fac: path2 is then the .pts */
        size_t n = strlen(sp->file);
        int file_is_fac = n >= 4 && (!strcmp(sp->file + n - 4, ".fac") || !strcmp(sp->file + n - 4, ".FAC"));
        cJSON_AddStringToObject(o, file_is_fac ? "pts" : "fac", in->read.path2);
    }
    cJSON_AddStringToObject(o, "format", thx_import_format_name(in->read.format));
    cJSON_AddStringToObject(o, "format_detail", in->read.format_detail);
    if (in->read.index_base >= 0) cJSON_AddNumberToObject(o, "index_base", in->read.index_base);
    else cJSON_AddNullToObject(o, "index_base");
    cJSON_AddBoolToObject(o, "index_base_detected", in->read.index_base_detected);
    add_num(o, "scale", in->scale);
    cJSON_AddNumberToObject(o, "nodes_read", (double)in->read.n_nodes_read);
    cJSON_AddNumberToObject(o, "triangles_read", (double)in->read.n_tris_read);
    cJSON_AddNumberToObject(o, "polygons_split", (double)in->read.n_polygons_split);
    cJSON_AddNumberToObject(o, "stl_corners_merged", (double)in->read.n_corners_merged);
    cJSON_AddNumberToObject(o, "cells_ignored", (double)in->read.n_cells_ignored);
    cJSON_AddNumberToObject(o, "unused_nodes_removed", (double)in->n_unused_removed);
    cJSON_AddBoolToObject(o, "reversed", in->reversed);
    cJSON *c = cJSON_AddObjectToObject(o, "check");
    if (c) {
        cJSON_AddBoolToObject(c, "ok", in->report.ok);
        cJSON_AddBoolToObject(c, "forced", in->check_failed);
        cJSON_AddNumberToObject(c, "nodes", (double)in->report.n_nodes);
        cJSON_AddNumberToObject(c, "triangles", (double)in->report.n_tris);
        add_num(c, "solid_angle_rel_error", in->report.solid_angle_rel_err);
        add_num(c, "min_angle_deg", in->report.min_angle);
        add_num(c, "max_aspect", in->report.max_aspect);
        cJSON *rs = cJSON_AddArrayToObject(c, "reasons");
        for (size_t k = 0; rs && k < in->report.n_reasons; k++)
            cJSON_AddItemToArray(rs, cJSON_CreateString(in->report.reasons[k]));
    }
    return o;
}

/* Parses "N=NAME[:SIGMA]" or "N=:SIGMA" into *mp; 0, or -1 with a usage message. */
static int parse_region(const char *cmd, const char *v, thx_region_map *mp)
{
    memset(mp, 0, sizeof *mp);
    const char *eq = strchr(v, '=');
    char *end = NULL;
    errno = 0;
    long long tag = eq ? strtoll(v, &end, 10) : 0;
    if (!eq || end != eq || end == v || errno) {
        cli_usage_error(cmd, "--region '%s': expected N=NAME[:SIGMA] (N the file's region number)", v);
        return -1;
    }
    mp->tag = tag;
    const char *name = eq + 1, *colon = strchr(name, ':');
    size_t nl = colon ? (size_t)(colon - name) : strlen(name);
    if (nl >= sizeof mp->name) {
        cli_usage_error(cmd, "--region '%s': name too long", v);
        return -1;
    }
    memcpy(mp->name, name, nl);
    mp->name[nl] = '\0';
    if (colon) {
        errno = 0;
        double sg = strtod(colon + 1, &end);
        if (end == colon + 1 || *end || errno || !(sg >= THX_SIGMA_MIN && sg <= THX_SIGMA_MAX)) {
            cli_usage_error(cmd, "--region '%s': the conductivity must be a number from %g to %g (S/m)", v, THX_SIGMA_MIN,
                            THX_SIGMA_MAX);
            return -1;
        }
        mp->sigma = sg;
        mp->has_sigma = 1;
    }
    if (!nl && !colon) {
        cli_usage_error(cmd, "--region '%s': give a name, a conductivity (N=:SIGMA), or both", v);
        return -1;
    }
    return 0;
}

static int import_volume(const spec *sp, const char *outdir, double default_scale, int force, int quiet, int verbose,
                         const thx_region_map *maps, size_t n_maps, const char *region_array, const thx_frame *frame);

/* The summary's frame line and the provenance's record of it. */
static void print_frame(const thx_frame *f)
{
    char a[3], b[3], c[3];
    if (f->set)
        printf("frame: superior %s, anterior %s, left %s\n", thx_axis_name(f->up, a), thx_axis_name(f->front, b),
               thx_axis_name(thx_frame_left(f), c));
    else
        printf("frame: unknown (no --up/--front): thorax electrodes, beat and render's named views will refuse this "
               "model until it is imported with them\n");
}

static void frame_json(cJSON *op, const thx_frame *f)
{
    char a[3];
    if (!f->set) return;
    cJSON_AddStringToObject(op, "up", thx_axis_name(f->up, a));
    cJSON_AddStringToObject(op, "front", thx_axis_name(f->front, a));
}

/* The parser's state (cli_command.user): the FILEs so far, each with the options after it. */
typedef struct {
    spec *sp;
    int n;
    thx_region_map *maps;
    size_t n_maps;
    const char *up, *front;
    double scale, default_scale; /* the last --scale; the one before the first FILE */
    int role;                    /* the last --role */
} import_args;

static int add_file(void *user, const char *arg)
{
    import_args *A = user;
    A->sp[A->n].file = arg;
    A->sp[A->n].fmt = THX_IMPORT_AUTO;
    A->n++;
    return 0;
}

/* --name, --role, --fac, --elem, --format, --scale: of the FILE before them (--scale before the first
   FILE: every file's default) */
static int file_option(void *user, const cli_opt *opt, const char *v)
{
    const char *cmd = "import", *a = opt->name;
    import_args *A = user;
    spec *cur = A->n ? &A->sp[A->n - 1] : NULL;
    if (!strcmp(a, "--scale")) {
        if (cur) cur->scale = A->scale, cur->has_scale = 1;
        else A->default_scale = A->scale;
        return 0;
    }
    if (!cur) return cli_usage_error(cmd, "%s must follow the FILE it describes", a);
    if (!strcmp(a, "--name")) {
        if (cur->name) return cli_usage_error(cmd, "%s: --name given twice", cur->file);
        cur->name = v;
    } else if (!strcmp(a, "--role")) {
        if (cur->has_role) return cli_usage_error(cmd, "%s: --role given twice", cur->file);
        cur->role = (thx_role)A->role;
        cur->has_role = 1;
    } else if (!strcmp(a, "--fac")) {
        cur->fac = v;
    } else if (!strcmp(a, "--elem")) {
        cur->elem = v;
    } else {
        thx_volume_format vf;
        if (thx_import_format_parse(v, &cur->fmt) != 0 && thx_volume_format_parse(v, &vf) != 0)
            return cli_usage_error(cmd, "unknown format '%s' (pts, tri, obj, stl, ply, vtk, vtp; tet, elem, vtu, msh)", v);
        cur->fmt_text = v;
    }
    return 0;
}

static int region_option(void *user, const cli_opt *opt, const char *v)
{
    import_args *A = user;
    if (parse_region("import", v, &A->maps[A->n_maps]) != 0) return 2;
    for (size_t k = 0; k < A->n_maps; k++)
        if (A->maps[k].tag == A->maps[A->n_maps].tag) return cli_usage_error("import", "--region %lld given twice", A->maps[k].tag);
    A->n_maps++;
    return 0;
}

static int axis_option(void *user, const cli_opt *opt, const char *v)
{
    import_args *A = user;
    const char **dst = !strcmp(opt->name, "--up") ? &A->up : &A->front;
    if (*dst) return cli_usage_error("import", "%s given twice", opt->name);
    *dst = v;
    return 0;
}

int cmd_import(int argc, char **argv)
{
    const char *cmd = "import";
    const char *outdir = NULL, *region_array = NULL;
    thx_frame frame = {0};
    int force = 0, verbose = 0, quiet = 0, rc = 0;
    import_args A = {.sp = calloc((size_t)argc + 1, sizeof *A.sp), .maps = calloc((size_t)argc + 1, sizeof *A.maps),
                     .default_scale = 1.0};
    if (!A.sp || !A.maps) {
        fprintf(stderr, "thorax import: out of memory\n");
        free(A.sp);
        free(A.maps);
        return 1;
    }
    static const cli_choice roles[] = {{"outer", THX_ROLE_OUTER}, {"fat", THX_ROLE_FAT}, {"muscle", THX_ROLE_MUSCLE},
                                       {"lung", THX_ROLE_LUNG},   {"heart", THX_ROLE_HEART}, {"other", THX_ROLE_OTHER},
                                       {NULL, 0}};
    cli_opt per_file[] = {
        {.name = "--name", .type = CLI_STRING, .meta = "NAME", .fn = file_option,
         .help = "surface name (file names NAME.pts/NAME.fac in the model); required for a surface"},
        {.name = "--role", .type = CLI_CHOICE, .meta = "ROLE", .choices = roles, .i = &A.role, .def = "",
         .fn = file_option,
         .help = "the surface's role: outer, fat, muscle, lung, heart or other; required for a surface"},
        {.name = "--fac", .type = CLI_INPUT, .meta = "FAC", .fn = file_option, .def = "FILE with .fac",
         .help = "the .fac of a .pts FILE (a .fac given as FILE finds its .pts the same way)"},
        {.name = "--elem", .type = CLI_INPUT, .meta = "ELEM", .fn = file_option, .def = "MESH with .tet, else .elem",
         .help = "the element file (.tet or .elem) of a .pts volume MESH"},
        {.name = "--format", .type = CLI_STRING, .meta = "F", .fn = file_option, .def = "by the extension",
         .help = "pts, tri, obj, stl, ply, vtk, vtp or geom for a surface; tet, elem (or carp), vtk, vtu or msh for a "
                 "volume MESH"},
        {.name = "--scale", .type = CLI_REAL, .meta = "S", .d = &A.scale, .fn = file_option, .rule = CLI_GT | CLI_FINITE,
         .bad = "--scale must be a finite number > 0", .def = "1, or the --scale before the first FILE",
         .help = "multiply this file's coordinates by S (they are taken as mm: 1000 for a file in metres); before "
                 "the first FILE: the default of every file"},
    };
    cli_opt volume[] = {
        {.name = "--region", .type = CLI_STRING, .meta = "N=NAME[:SIGMA]", .unit = "S/m", .flags = CLI_REPEAT,
         .fn = region_option,
         .help = "region number N of the file: its name (1-31 characters of A-Z a-z 0-9 _ . -) and its isotropic "
                 "conductivity SIGMA; N=:SIGMA keeps the name; once per N. Default name: the file's (a Gmsh "
                 "physical name), else region_N; default conductivity: mean thorax (0.239 S/m, with a warning)"},
        {.name = "--region-array", .type = CLI_STRING, .meta = "A", .s = &region_array,
         .def = "one named region, gmsh:physical, CellEntityIds, material, MaterialIds, tissue, elemTag ..., else "
                "the only integer one, else one region",
         .help = "the cell array of region numbers of a .vtk/.vtu MESH"},
    };
    cli_opt general[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "MODEL", .s = &outdir,
         .help = "model directory to write (replaced atomically)"},
        {.name = "--up", .type = CLI_STRING, .meta = "AXIS", .fn = axis_option,
         .help = "the model axis toward the head (superior): +x -x +y -y +z -z"},
        {.name = "--front", .type = CLI_STRING, .meta = "AXIS", .fn = axis_option,
         .help = "the model axis toward the front (anterior); with --up, the model's anatomical frame, recorded in "
                 "model.json (\"frame\") and read by electrodes, beat and render's named views; left = up x front. "
                 "Without them the frame is unknown and those commands refuse the model (e.g. the Dalhousie torso: "
                 "--up -y --front -z; thorax's own models: --up +z --front +y)"},
        {.name = "--force", .type = CLI_FLAG, .i = &force,
         .help = "write surfaces or a mesh that fail their checks (with a warning)"},
        {.name = "-q", .type = CLI_FLAG, .i = &quiet, .help = "print nothing but warnings and errors"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .help = "more logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "-o FILE --name --role [--fac] [--format] [--scale] [FILE --name --role ...] [--up --front] "
                 "[--force] [-q] [-v]\n"
                 "-o MESH [--elem] [--format] [--scale] [--region]... [--region-array] [--up --front] [--force] [-q] "
                 "[-v]",
        .about =
            "Builds the model directory MODEL from closed triangle surfaces made by other\n"
            "programs, or from one tetrahedral volume mesh. Each surface FILE starts a\n"
            "surface; the options after it, up to the next FILE, describe that surface.\n"
            "\n"
            "surface formats (by extension):\n"
            "  .pts + .fac  map3d/SCIRun; .fac numbering 0- or 1-based, detected and reported\n"
            "  .tri         OpenMEEG ('- NV', NV lines 'x y z nx ny nz', '- NT NT NT', NT\n"
            "               lines 'i j k', 0-based; normals ignored), or ECGSim: node count,\n"
            "               'label x y z' lines, triangle count, 'label a b c' lines\n"
            "               (labels optional; 1-based, 0-based detected)\n"
            "  .obj         Wavefront OBJ: v, f (v/vt/vn, negative indices; polygons fanned)\n"
            "  .stl         binary or ASCII; corners with identical coordinates merged\n"
            "  .ply         ascii or binary PLY: vertex x y z, face vertex_indices\n"
            "  .vtk         legacy VTK POLYDATA, ASCII or BINARY (POLYGONS, TRIANGLE_STRIPS)\n"
            "  .vtp         VTK XML PolyData with ascii arrays\n"
            "  .geom        map3d/CVRTI binary graphicsio: FILE.geom@N (or @NAME) picks one\n"
            "               surface; a file of several needs the pick (1-based triangles)\n"
            "\n"
            "volume mesh formats (a MESH is the only FILE; no --name/--role):\n"
            "  .pts + .tet  'x y z' node lines; 'a b c d [region]' element lines, node\n"
            "   or .elem    numbers 0- or 1-based (detected, reported); CARP/openCARP: a\n"
            "               count line first, 'Tt a b c d [region]' lines, 0-based\n"
            "               (--elem names the element file; default: MESH with .tet, .elem)\n"
            "  .vtk         legacy VTK UNSTRUCTURED_GRID, ASCII or BINARY: tetrahedra (cell\n"
            "               type 10); cells of dimension 0-2 skipped; others refused\n"
            "  .vtu         VTK XML UnstructuredGrid: ascii, binary or appended (raw or\n"
            "               base64) arrays, uncompressed or zlib\n"
            "  .msh         Gmsh MSH 4.1 ASCII: tetrahedra (type 4); regions = physical\n"
            "               volumes (names from $PhysicalNames), else volume entities;\n"
            "               named physical surfaces (triangles) name the surfaces\n"
            "\n"
            "Every surface is checked as 'thorax check' does (closed 2-manifold, consistent\n"
            "and outward orientation, 4 pi solid angle, no self-intersections, no\n"
            "degenerate or duplicate triangles). Then:\n"
            "  - nodes used by no triangle are removed (reported);\n"
            "  - a closed, consistently oriented surface whose triangles face inward\n"
            "    (clockwise seen from outside, Omega = -4 pi) is reversed (reported);\n"
            "  - any other failure refuses the import: nothing is written, exit 1.\n"
            "\n"
            "A volume MESH becomes a model with that volume: one region per region number\n"
            "of the file (ids 1, 2, ... in increasing order), named and given a\n"
            "conductivity by --region; nodes in no tetrahedron removed; left-handed\n"
            "tetrahedra made right-handed (counted), flat ones refused; the mesh's\n"
            "boundary becomes a surface of role outer (named after the region inside it;\n"
            "a hole in the mesh becomes 'cavity', role heart), and each closed interface\n"
            "between regions that touches no other surface becomes a surface of role\n"
            "other, named after the region inside it. Then the surfaces and the volume are\n"
            "checked as 'thorax check' does: a failure refuses the import.\n",
        .epilog =
            "examples:\n"
            "  thorax import -o tank tank_full_771.pts --name tank --role outer \\\n"
            "                25feb97_sock_closed.pts --name sock --role heart\n"
            "  thorax import -o head --scale 100 scalp.3.tri --name scalp --role outer \\\n"
            "                skull.3.tri --name skull --role other cortex.3.tri --name brain --role other\n"
            "  thorax import -o dal --up -y --front -z daltorso.pts --name torso --role outer \\\n"
            "                dalepi.pts --name epicardium --role heart\n"
            "  thorax import -o head head.msh --region 1=brain:0.33 --region 2=skull:0.0042\n"
            "  thorax import -o dal --up -y --front -z daltorsoepi.geom@1 --name torso --role outer \\\n"
            "                daltorsoepi.geom@2 --name epicardium --role heart\n"
            "\n"
            "Exit status: 0 written, 1 a file could not be read or a surface or mesh was\n"
            "refused (nothing written), 2 bad usage.\n",
        .group = {{"options after a FILE (they describe it)", per_file, sizeof per_file / sizeof per_file[0]},
                  {"options of a volume MESH", volume, sizeof volume / sizeof volume[0]},
                  {NULL, general, sizeof general / sizeof general[0]}},
        .positional = add_file,
        .user = &A,
    };
    spec *sp = A.sp;
    thx_region_map *maps = A.maps;
    int pr = cli_parse(&c, argc, argv);
    if (pr) {
        rc = CLI_EXIT(pr);
        goto out;
    }
    int n = A.n;
    size_t n_maps = A.n_maps;
    const char *up = A.up, *front = A.front;
    double default_scale = A.default_scale;
    if (!outdir) { rc = cli_usage_error(cmd, "no output directory given (-o MODEL)"); goto out; }
    if (n == 0) { rc = cli_usage_error(cmd, "no surface FILE or volume MESH given"); goto out; }
    if (up || front) {
        if (!up || !front) {
            rc = cli_usage_error(cmd, "%s needs %s too (the anatomical frame takes both axes)", up ? "--up" : "--front",
                                 up ? "--front" : "--up");
            goto out;
        }
        thx_ctx *fctx = cli_ctx(-1);
        if (thx_frame_from_names(fctx, up, front, "--up/--front", &frame) != THX_OK) {
            rc = cli_usage_error(cmd, "%s", thx_ctx_message(fctx));
            thx_ctx_destroy(&fctx);
            goto out;
        }
        thx_ctx_destroy(&fctx);
    }
    /* a volume mesh: by --format (vtk decided by the content), else by the file */
    int n_volumes = 0;
    for (int k = 0; k < n; k++) {
        thx_volume_format vf = THX_VOLFMT_NONE;
        if (sp[k].fmt_text && thx_volume_format_parse(sp[k].fmt_text, &vf) == 0 && vf == THX_VOLFMT_VTK) {
            thx_volume_format by_content = thx_volume_format_from_path(sp[k].file);
            vf = by_content == THX_VOLFMT_VTK ? THX_VOLFMT_VTK : THX_VOLFMT_NONE;
        } else if (!sp[k].fmt_text) {
            vf = sp[k].elem ? THX_VOLFMT_PTS : thx_volume_format_from_path(sp[k].file);
        }
        sp[k].vfmt = vf;
        n_volumes += vf != THX_VOLFMT_NONE;
    }
    if (n_volumes) {
        const spec *vs = NULL;
        for (int k = 0; k < n; k++)
            if (sp[k].vfmt != THX_VOLFMT_NONE) vs = &sp[k];
        if (n > 1) {
            rc = cli_usage_error(cmd, "%s is a volume mesh: it must be the only FILE", vs->file);
            goto out;
        }
        if (vs->name || vs->has_role || vs->fac) {
            rc = cli_usage_error(cmd, "%s is a volume mesh: --name, --role and --fac do not apply (its surfaces are "
                                 "named after its regions)", vs->file);
            goto out;
        }
        rc = import_volume(vs, outdir, default_scale, force, quiet, verbose, maps, n_maps, region_array, &frame);
        goto out;
    }
    if (n_maps || region_array) {
        rc = cli_usage_error(cmd, "--region and --region-array apply to a volume mesh only");
        goto out;
    }
    for (int k = 0; k < n; k++) {
        if (sp[k].elem) { rc = cli_usage_error(cmd, "%s: --elem applies to a .pts volume mesh only", sp[k].file); goto out; }
        if (!sp[k].name) { rc = cli_usage_error(cmd, "%s: --name NAME missing after it", sp[k].file); goto out; }
        if (!sp[k].has_role) { rc = cli_usage_error(cmd, "%s: --role ROLE missing after it", sp[k].file); goto out; }
        if (!sp[k].has_scale) sp[k].scale = default_scale;
        for (int j = 0; j < k; j++)
            if (!strcmp(sp[j].name, sp[k].name)) {
                rc = cli_usage_error(cmd, "two surfaces are named '%s'", sp[k].name);
                goto out;
            }
    }

    thx_ctx *ctx = cli_ctx(verbose);
    size_t n_files = (size_t)(n > 0 ? n : 1);
    thx_import_info *info = calloc(n_files, sizeof *info);
    thx_surface **surf = calloc(n_files, sizeof *surf);
    thx_model *m = NULL;
    cJSON *prov = NULL;
    int n_failed = 0;
    if (!info || !surf) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    /* the output first: refused before any work unless it is absent or thorax's own model */
    thx_outdir od;
    {
        const char *inputs[2 * 64];
        size_t ni = 0;
        for (int k = 0; k < n && ni + 2 <= sizeof inputs / sizeof *inputs; k++) {
            inputs[ni++] = sp[k].file;
            inputs[ni++] = sp[k].fac;
        }
        thx_status cst = thx_outdir_claim(ctx, &od, outdir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, inputs, ni);
        if (cst != THX_OK) { rc = cli_fail(ctx, cmd, cst); goto done; }
    }
    /* Every surface is read and checked, so that one run reports every problem. */
    for (int k = 0; k < n; k++) {
        thx_import_opts o;
        thx_import_opts_default(&o);
        o.format = sp[k].fmt;
        o.scale = sp[k].scale;
        o.force = force;
        thx_status st = thx_surface_import(ctx, sp[k].file, sp[k].fac, sp[k].name, sp[k].role, &o, &surf[k], &info[k]);
        if (st == THX_OK || st == THX_ECHECK) {
            if (!quiet) print_report(&sp[k], &info[k]);
            if (info[k].scale == 1.0 && info[k].extent > 0 && info[k].extent < 5.0)
                thx_log(ctx, THX_LOG_WARN, "%s: surface \"%s\" spans only %g mm: if the file is in metres, use --scale 1000",
                        sp[k].file, sp[k].name, info[k].extent);
        }
        if (st == THX_ECHECK) {
            for (size_t r = 0; r < info[k].report.n_reasons; r++)
                fprintf(stderr, "thorax import: %s: surface \"%s\": %s\n", sp[k].file, sp[k].name, info[k].report.reasons[r]);
            fprintf(stderr, "thorax import: %s: surface \"%s\": refused (--force writes it anyway)\n", sp[k].file,
                    sp[k].name);
            n_failed++;
        } else if (st != THX_OK) {
            cli_fail(ctx, cmd, st);
            n_failed++;
        } else if (info[k].check_failed) {
            for (size_t r = 0; r < info[k].report.n_reasons; r++)
                thx_log(ctx, THX_LOG_WARN, "%s: surface \"%s\": %s", sp[k].file, sp[k].name, info[k].report.reasons[r]);
            thx_log(ctx, THX_LOG_WARN, "%s: surface \"%s\": failed its checks; written anyway (--force)", sp[k].file,
                    sp[k].name);
        }
    }
    if (n_failed) {
        fprintf(stderr, "thorax import: %d of %d surface%s failed; nothing written\n", n_failed, n, n == 1 ? "" : "s");
        rc = 1;
        goto done;
    }

    thx_status st = thx_model_create(ctx, &m);
    if (st == THX_OK) m->frame = frame;
    for (int k = 0; st == THX_OK && k < n; k++) {
        st = thx_model_add_surface(ctx, m, &surf[k]);
        /* the point is stored only where it gave 4 pi: a forced open surface has no inside */
        if (st == THX_OK && info[k].report.interior_source != THX_INTERIOR_NONE &&
            !(info[k].report.failures & THX_CHECKF_SOLID_ANGLE)) {
            m->has_interior[m->n_surfaces - 1] = 1;
            m->interior[m->n_surfaces - 1] = info[k].report.interior;
        }
    }
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    prov = cJSON_CreateObject();
    cJSON *inputs = prov ? cJSON_AddArrayToObject(prov, "inputs") : NULL;
    if (!inputs) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    cJSON_AddStringToObject(prov, "program", "thorax 0.1.0");
    cJSON_AddStringToObject(prov, "command", cli_command_line());
    for (int k = 0; k < n; k++) cJSON_AddItemToArray(inputs, input_json(&sp[k], &info[k]));
    cJSON *op = cJSON_AddObjectToObject(prov, "options");
    if (op) {
        cJSON_AddNumberToObject(op, "default_scale", default_scale);
        cJSON_AddBoolToObject(op, "force", force);
        frame_json(op, &frame);
    }
    m->provenance_json = cJSON_PrintUnformatted(prov);
    if (!m->provenance_json) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    st = thx_model_write_claimed(ctx, m, &od);
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (!quiet) {
        print_frame(&m->frame);
        printf("wrote %s (%d surface%s)\n", outdir, n, n == 1 ? "" : "s");
    }
done:
    cJSON_Delete(prov);
    thx_model_destroy(&m);
    for (int k = 0; surf && k < n; k++) thx_surface_destroy(&surf[k]);
    for (int k = 0; info && k < n; k++) thx_import_info_free(&info[k]);
    free(surf);
    free(info);
    thx_ctx_destroy(&ctx);
out:
    free(sp);
    free(maps);
    return rc;
}

/* ------------------------------------------------------------ volume meshes */

static const char *surface_kind_name(thx_volume_surface_kind k)
{
    return k == THX_VSURF_BOUNDARY ? "boundary" : k == THX_VSURF_CAVITY ? "cavity" : "interface";
}

static const char *name_from_text(thx_region_name_source s)
{
    return s == THX_RNAME_OPTION ? "--region" : s == THX_RNAME_FILE ? "the file's name" : "default name";
}

static void print_volume_report(const spec *sp, const thx_model *m, const thx_volume_import_info *in)
{
    const thx_volume *v = m->volume;
    printf("volume mesh from %s%s%s\n", sp->file, in->path2[0] ? " + " : "", in->path2);
    printf("  read: %s, %zu nodes, %zu tetrahedra", in->format_detail, in->n_nodes_read, in->n_tets_read);
    printf("; node numbers %d-based (%s)\n", in->index_base, in->index_base_detected ? "detected" : "by the format");
    printf("  regions from %s\n", in->region_source);
    if (in->n_cells_ignored) printf("  skipped %zu cells of dimension 0-2 (points, lines, triangles, ...)\n", in->n_cells_ignored);
    if (in->scale != 1.0) printf("  scaled coordinates by %g\n", in->scale);
    if (in->n_unused_removed)
        printf("  removed %zu unused nodes (in no tetrahedron; the first is node %lld as numbered in the file); the rest "
               "renumbered\n", in->n_unused_removed, in->first_unused);
    if (in->n_flipped) printf("  made %zu left-handed tetrahedra right-handed (two nodes swapped)\n", in->n_flipped);
    for (size_t k = 0; k < in->n_regions; k++) {
        const thx_volume_import_region *g = &in->regions[k];
        const thx_region *rg = &v->regions[k];
        printf("  region %zu \"%s\" (file region %lld, %s): %zu tetrahedra, %.6g mm^3, sigma %g S/m%s%s\n", k + 1, rg->name,
               g->tag, name_from_text(g->name_from), g->n_tets, g->volume, rg->sigma[0],
               rg->anisotropic ? " (anisotropic)" : "", g->sigma_defaulted ? " (default)" : "");
    }
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const thx_volume_import_surface *u = &in->surfaces[s];
        printf("surface \"%s\" (%s): %s", m->surf[s]->name, thx_role_name(m->surf[s]->role), surface_kind_name(u->kind));
        if (u->inside >= 0) printf(", inside: %s", v->regions[u->inside].name);
        if (u->outside >= 0) printf(", outside: %s", v->regions[u->outside].name);
        if (u->named_by_file) printf(", named by the file");
        printf("\n");
        print_check(&in->surface_reports[s]);
    }
    for (size_t k = 0; k < in->n_dropped && k < THX_VIMPORT_MAX_DROPPED; k++) printf("  not a surface: %s\n", in->dropped[k]);
    if (in->n_dropped > THX_VIMPORT_MAX_DROPPED)
        printf("  not a surface: ... and %zu more\n", in->n_dropped - THX_VIMPORT_MAX_DROPPED);
    if (in->volume_checked) {
        const thx_volume_report *r = &in->volume_report;
        printf("  volume check: %zu nodes, %zu tetrahedra, %zu boundary faces, %zu shell%s, %zu cavit%s, volume %.6g mm^3",
               r->n_nodes, r->n_tets, r->n_boundary_faces, r->n_shells, r->n_shells == 1 ? "" : "s", r->n_cavities,
               r->n_cavities == 1 ? "y" : "ies", r->tet_volume);
        if (r->volume_rel_diff == r->volume_rel_diff) printf(" (%+.2e vs the surfaces)", r->volume_rel_diff);
        if (r->min_dihedral == r->min_dihedral) printf(", dihedral %.2f..%.2f deg", r->min_dihedral, r->max_dihedral);
        printf(": %s\n", r->ok ? "ok" : "FAILED");
    }
}

static cJSON *volume_input_json(const spec *sp, const thx_model *m, const thx_volume_import_info *in)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    const thx_volume *v = m->volume;
    cJSON_AddStringToObject(o, "volume_mesh", sp->file);
    if (in->path2[0]) cJSON_AddStringToObject(o, "other_file", in->path2);
    cJSON_AddStringToObject(o, "format", thx_volume_format_name(in->format));
    cJSON_AddStringToObject(o, "format_detail", in->format_detail);
    cJSON_AddNumberToObject(o, "index_base", in->index_base);
    cJSON_AddBoolToObject(o, "index_base_detected", in->index_base_detected);
    add_num(o, "scale", in->scale);
    cJSON_AddNumberToObject(o, "nodes_read", (double)in->n_nodes_read);
    cJSON_AddNumberToObject(o, "tetrahedra_read", (double)in->n_tets_read);
    cJSON_AddNumberToObject(o, "cells_skipped", (double)in->n_cells_ignored);
    cJSON_AddNumberToObject(o, "unused_nodes_removed", (double)in->n_unused_removed);
    cJSON_AddNumberToObject(o, "tetrahedra_flipped", (double)in->n_flipped);
    cJSON_AddStringToObject(o, "region_source", in->region_source);
    cJSON *rs = cJSON_AddArrayToObject(o, "regions");
    for (size_t k = 0; rs && k < in->n_regions; k++) {
        cJSON *g = cJSON_CreateObject();
        if (!g) break;
        cJSON_AddNumberToObject(g, "id", (double)(k + 1));
        cJSON_AddNumberToObject(g, "file_region", (double)in->regions[k].tag);
        cJSON_AddStringToObject(g, "name", v->regions[k].name);
        if (in->regions[k].file_name[0]) cJSON_AddStringToObject(g, "file_name", in->regions[k].file_name);
        cJSON_AddStringToObject(g, "name_from", name_from_text(in->regions[k].name_from));
        cJSON_AddBoolToObject(g, "sigma_defaulted", in->regions[k].sigma_defaulted);
        cJSON_AddNumberToObject(g, "tetrahedra", (double)in->regions[k].n_tets);
        add_num(g, "volume", in->regions[k].volume);
        cJSON_AddItemToArray(rs, g);
    }
    cJSON *ss = cJSON_AddArrayToObject(o, "surfaces");
    for (size_t s = 0; ss && s < m->n_surfaces; s++) {
        const thx_volume_import_surface *u = &in->surfaces[s];
        cJSON *g = cJSON_CreateObject();
        if (!g) break;
        cJSON_AddStringToObject(g, "surface", m->surf[s]->name);
        cJSON_AddStringToObject(g, "role", thx_role_name(m->surf[s]->role));
        cJSON_AddStringToObject(g, "kind", surface_kind_name(u->kind));
        if (u->inside >= 0) cJSON_AddStringToObject(g, "inside", v->regions[u->inside].name);
        if (u->outside >= 0) cJSON_AddStringToObject(g, "outside", v->regions[u->outside].name);
        cJSON_AddBoolToObject(g, "check_ok", in->surface_reports[s].ok);
        cJSON_AddItemToArray(ss, g);
    }
    cJSON *ds = cJSON_AddArrayToObject(o, "not_surfaces");
    for (size_t k = 0; ds && k < in->n_dropped && k < THX_VIMPORT_MAX_DROPPED; k++)
        cJSON_AddItemToArray(ds, cJSON_CreateString(in->dropped[k]));
    cJSON *c = cJSON_AddObjectToObject(o, "check");
    if (c) {
        const thx_volume_report *r = &in->volume_report;
        cJSON_AddBoolToObject(c, "ok", !in->check_failed);
        cJSON_AddBoolToObject(c, "forced", in->check_failed);
        cJSON_AddBoolToObject(c, "volume_ok", r->ok);
        add_num(c, "volume_rel_diff", r->volume_rel_diff);
        add_num(c, "min_dihedral_deg", r->min_dihedral);
        cJSON *rr = cJSON_AddArrayToObject(c, "reasons");
        for (size_t s = 0; rr && s < m->n_surfaces; s++)
            for (size_t k = 0; k < in->surface_reports[s].n_reasons; k++) {
                char buf[320];
                snprintf(buf, sizeof buf, "surface \"%s\": %s", m->surf[s]->name, in->surface_reports[s].reasons[k]);
                cJSON_AddItemToArray(rr, cJSON_CreateString(buf));
            }
        for (size_t k = 0; rr && k < r->n_reasons; k++) cJSON_AddItemToArray(rr, cJSON_CreateString(r->reasons[k]));
    }
    return o;
}

/* The reasons a volume import failed its checks, to stderr (refused) or as warnings (forced). */
static void volume_reasons(thx_ctx *ctx, const spec *sp, const thx_volume_import_info *in, const thx_model *m, int warn)
{
    for (size_t s = 0; s < in->n_surfaces; s++)
        for (size_t k = 0; k < in->surface_reports[s].n_reasons; k++) {
            const char *nm = m ? m->surf[s]->name : in->surface_reports[s].name;
            if (warn) thx_log(ctx, THX_LOG_WARN, "%s: surface \"%s\": %s", sp->file, nm, in->surface_reports[s].reasons[k]);
            else fprintf(stderr, "thorax import: %s: surface \"%s\": %s\n", sp->file, nm, in->surface_reports[s].reasons[k]);
        }
    for (size_t k = 0; in->volume_checked && k < in->volume_report.n_reasons; k++) {
        if (warn) thx_log(ctx, THX_LOG_WARN, "%s: volume: %s", sp->file, in->volume_report.reasons[k]);
        else fprintf(stderr, "thorax import: %s: volume: %s\n", sp->file, in->volume_report.reasons[k]);
    }
}

static int import_volume(const spec *sp, const char *outdir, double default_scale, int force, int quiet, int verbose,
                         const thx_region_map *maps, size_t n_maps, const char *region_array, const thx_frame *frame)
{
    const char *cmd = "import";
    int rc = 0;
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    cJSON *prov = NULL;
    thx_volume_import_info info;
    memset(&info, 0, sizeof info);
    thx_volume_import_opts o;
    thx_volume_import_opts_default(&o);
    o.format = sp->vfmt;
    o.elem_path = sp->elem;
    o.region_array = region_array;
    o.scale = sp->has_scale ? sp->scale : default_scale;
    o.force = force;
    o.region_maps = maps;
    o.n_region_maps = n_maps;
    thx_region_default("mean_thorax", &o.default_region);
    thx_outdir od;
    const char *in_files[] = {sp->file, sp->elem};
    thx_status st = thx_outdir_claim(ctx, &od, outdir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, in_files, 2);
    if (st == THX_OK) st = thx_volume_import(ctx, sp->file, &o, &m, &info);
    if (st == THX_ECHECK) {
        volume_reasons(ctx, sp, &info, NULL, 0);
        for (size_t k = 0; k < info.n_dropped && k < THX_VIMPORT_MAX_DROPPED; k++)
            fprintf(stderr, "thorax import: %s: not a surface: %s\n", sp->file, info.dropped[k]);
        fprintf(stderr, "thorax import: %s: refused: the mesh failed its checks (--force writes it anyway); nothing written\n",
                sp->file);
        rc = 1;
        goto done;
    }
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    m->frame = *frame;
    if (!quiet) print_volume_report(sp, m, &info);
    for (size_t k = 0; k < info.n_regions; k++)
        if (info.regions[k].sigma_defaulted)
            thx_log(ctx, THX_LOG_WARN, "%s: region %lld (\"%s\"): no conductivity given, using %s (%g S/m); set it with "
                    "--region %lld=%s:SIGMA", sp->file, info.regions[k].tag, m->volume->regions[k].name, "mean_thorax",
                    m->volume->regions[k].sigma[0], info.regions[k].tag, m->volume->regions[k].name);
    if (o.scale == 1.0 && info.extent > 0 && info.extent < 5.0)
        thx_log(ctx, THX_LOG_WARN, "%s: the mesh spans only %g mm: if the file is in metres, use --scale 1000", sp->file,
                info.extent);
    if (info.check_failed) {
        volume_reasons(ctx, sp, &info, m, 1);
        thx_log(ctx, THX_LOG_WARN, "%s: the mesh failed its checks; written anyway (--force)", sp->file);
    }
    prov = cJSON_CreateObject();
    cJSON *inputs = prov ? cJSON_AddArrayToObject(prov, "inputs") : NULL;
    if (!inputs) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    cJSON_AddStringToObject(prov, "program", "thorax 0.1.0");
    cJSON_AddStringToObject(prov, "command", cli_command_line());
    cJSON_AddItemToArray(inputs, volume_input_json(sp, m, &info));
    cJSON *op = cJSON_AddObjectToObject(prov, "options");
    if (op) {
        cJSON_AddNumberToObject(op, "default_scale", default_scale);
        cJSON_AddBoolToObject(op, "force", force);
        if (region_array) cJSON_AddStringToObject(op, "region_array", region_array);
        frame_json(op, frame);
    }
    m->provenance_json = cJSON_PrintUnformatted(prov);
    if (!m->provenance_json) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    st = thx_model_write_claimed(ctx, m, &od);
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (!quiet) print_frame(&m->frame);
    if (!quiet)
        printf("wrote %s (%zu nodes, %zu tetrahedra, %zu region%s, %zu surface%s)\n", outdir, m->volume->n_nodes,
               m->volume->n_tets, m->volume->n_regions, m->volume->n_regions == 1 ? "" : "s", m->n_surfaces,
               m->n_surfaces == 1 ? "" : "s");
done:
    cJSON_Delete(prov);
    thx_model_destroy(&m);
    thx_volume_import_info_free(&info);
    thx_ctx_destroy(&ctx);
    return rc;
}
