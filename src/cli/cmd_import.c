/* thorax import: a model directory from closed surfaces made elsewhere
 * (.pts/.fac, ECGSim .tri, OBJ, STL, PLY, VTK, VTP), each checked as `thorax check` does. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/check.h"
#include "thorax/import.h"
#include "thorax/model.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: thorax import -o MODEL FILE --name NAME --role ROLE [--fac FAC] [--format F] [--scale S]\n"
            "                     [FILE --name NAME --role ROLE ...] [--force] [-q] [-v]\n"
            "\n"
            "Builds the model directory MODEL from closed triangle surfaces made by other\n"
            "programs. Each FILE starts a surface; the options after it, up to the next\n"
            "FILE, describe that surface:\n"
            "  --name NAME      surface name (file names NAME.pts/NAME.fac in the model)\n"
            "  --role ROLE      outer, fat, muscle, lung, heart or other\n"
            "  --fac FAC        the .fac of a .pts FILE (default: FILE with .fac for .pts)\n"
            "  --format F       pts, tri, obj, stl, ply, vtk or vtp (default: FILE's extension)\n"
            "  --scale S        multiply this surface's coordinates by S\n"
            "\n"
            "formats (by extension):\n"
            "  .pts + .fac  map3d/SCIRun; .fac numbering 0- or 1-based, detected and reported\n"
            "  .tri         ECGSim: node count, 'label x y z' lines, triangle count,\n"
            "               'label a b c' lines (labels optional; 1-based, 0-based detected)\n"
            "  .obj         Wavefront OBJ: v, f (v/vt/vn, negative indices; polygons fanned)\n"
            "  .stl         binary or ASCII; corners with identical coordinates merged\n"
            "  .ply         ascii or binary PLY: vertex x y z, face vertex_indices\n"
            "  .vtk         legacy VTK POLYDATA, ASCII or BINARY (POLYGONS, TRIANGLE_STRIPS)\n"
            "  .vtp         VTK XML PolyData with ascii arrays\n"
            "\n"
            "Every surface is checked as 'thorax check' does (closed 2-manifold, consistent\n"
            "and outward orientation, 4 pi solid angle, no self-intersections, no\n"
            "degenerate or duplicate triangles). Then:\n"
            "  - nodes used by no triangle are removed (reported);\n"
            "  - a closed, consistently oriented surface whose triangles face inward\n"
            "    (clockwise seen from outside, Omega = -4 pi) is reversed (reported);\n"
            "  - any other failure refuses the import: nothing is written, exit 1.\n"
            "\n"
            "options:\n"
            "  -o, --output DIR  model directory to write (replaced atomically)\n"
            "  --scale S         before the first FILE: default scale of every surface\n"
            "                    (coordinates are taken as mm; 1000 for a file in metres)\n"
            "  --force           write surfaces that fail their checks anyway (warns)\n"
            "  -q                print nothing but warnings and errors\n"
            "  -v                more logging\n"
            "  -h, --help        this text\n"
            "\n"
            "example:\n"
            "  thorax import -o tank tank_full_771.pts --name tank --role outer \\\n"
            "                25feb97_sock_closed.pts --name sock --role heart\n"
            "\n"
            "Exit status: 0 written, 1 a file could not be read or a surface was refused\n"
            "(nothing written), 2 bad usage.\n");
}

typedef struct {
    const char *file, *fac, *name;
    thx_role role;
    int has_role;
    thx_import_format fmt;
    double scale;
    int has_scale;
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
    printf("surface \"%s\" (%s) from %s%s%s\n", sp->name, thx_role_name(sp->role), sp->file, in->path2[0] ? " + " : "",
           in->path2);
    printf("  read: %s, %zu nodes, %zu triangles", in->format_detail, in->n_nodes_read, in->n_tris_read);
    if (in->index_base >= 0)
        printf("; node numbers %d-based (%s)", in->index_base, in->index_base_detected ? "detected" : "by the format");
    printf("\n");
    if (in->n_polygons_split) printf("  split %zu polygons with more than 3 vertices into triangle fans\n", in->n_polygons_split);
    if (in->n_corners_merged) printf("  merged %zu STL facet corners into %zu shared nodes\n", in->n_corners_merged, in->n_nodes_read);
    if (in->n_cells_ignored) printf("  ignored %zu vertex/line cells (not triangles)\n", in->n_cells_ignored);
    if (in->trailer_line) printf("  ignored the text after the last triangle (from line %d)\n", in->trailer_line);
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
    if (in->path2[0]) {
        /* a pair named by its .fac: path2 is then the .pts */
        size_t n = strlen(sp->file);
        int file_is_fac = n >= 4 && (!strcmp(sp->file + n - 4, ".fac") || !strcmp(sp->file + n - 4, ".FAC"));
        cJSON_AddStringToObject(o, file_is_fac ? "pts" : "fac", in->path2);
    }
    cJSON_AddStringToObject(o, "format", thx_import_format_name(in->format));
    cJSON_AddStringToObject(o, "format_detail", in->format_detail);
    if (in->index_base >= 0) cJSON_AddNumberToObject(o, "index_base", in->index_base);
    else cJSON_AddNullToObject(o, "index_base");
    cJSON_AddBoolToObject(o, "index_base_detected", in->index_base_detected);
    add_num(o, "scale", in->scale);
    cJSON_AddNumberToObject(o, "nodes_read", (double)in->n_nodes_read);
    cJSON_AddNumberToObject(o, "triangles_read", (double)in->n_tris_read);
    cJSON_AddNumberToObject(o, "polygons_split", (double)in->n_polygons_split);
    cJSON_AddNumberToObject(o, "stl_corners_merged", (double)in->n_corners_merged);
    cJSON_AddNumberToObject(o, "cells_ignored", (double)in->n_cells_ignored);
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

int cmd_import(int argc, char **argv)
{
    const char *cmd = "import";
    const char *outdir = NULL;
    double default_scale = 1.0;
    int force = 0, verbose = 0, quiet = 0, rc = 0;
    spec *sp = calloc((size_t)argc + 1, sizeof *sp);
    if (!sp) {
        fprintf(stderr, "thorax import: out of memory\n");
        return 1;
    }
    int n = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        spec *cur = n ? &sp[n - 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            free(sp);
            return 0;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!v) { rc = cli_usage_error(cmd, "%s needs a value", a); goto out; }
            outdir = v;
            i++;
        } else if (!strcmp(a, "--name") || !strcmp(a, "--role") || !strcmp(a, "--fac") || !strcmp(a, "--format")) {
            if (!v) { rc = cli_usage_error(cmd, "%s needs a value", a); goto out; }
            if (!cur) { rc = cli_usage_error(cmd, "%s must follow the FILE it describes", a); goto out; }
            i++;
            if (!strcmp(a, "--name")) {
                if (cur->name) { rc = cli_usage_error(cmd, "%s: --name given twice", cur->file); goto out; }
                cur->name = v;
            } else if (!strcmp(a, "--role")) {
                if (cur->has_role) { rc = cli_usage_error(cmd, "%s: --role given twice", cur->file); goto out; }
                if (thx_role_parse(v, &cur->role) != 0) {
                    rc = cli_usage_error(cmd, "unknown role '%s' (outer, fat, muscle, lung, heart or other)", v);
                    goto out;
                }
                cur->has_role = 1;
            } else if (!strcmp(a, "--fac")) {
                cur->fac = v;
            } else if (thx_import_format_parse(v, &cur->fmt) != 0) {
                rc = cli_usage_error(cmd, "unknown format '%s' (pts, tri, obj, stl, ply, vtk or vtp)", v);
                goto out;
            }
        } else if (!strcmp(a, "--scale")) {
            double s;
            if (cli_parse_double(cmd, a, v, &s)) { rc = 2; goto out; }
            i++;
            if (!(s > 0) || isinf(s)) { rc = cli_usage_error(cmd, "--scale must be a finite number > 0"); goto out; }
            if (cur) cur->scale = s, cur->has_scale = 1;
            else default_scale = s;
        } else if (!strcmp(a, "--force")) {
            force = 1;
        } else if (!strcmp(a, "-q")) {
            quiet = 1; /* warnings stay: they say what was written despite doubts */
        } else if (!strcmp(a, "-v")) {
            verbose++;
        } else if (a[0] == '-' && a[1]) {
            rc = cli_usage_error(cmd, "unknown option '%s'", a);
            goto out;
        } else {
            sp[n].file = a;
            sp[n].fmt = THX_IMPORT_AUTO;
            n++;
        }
    }
    if (!outdir) { rc = cli_usage_error(cmd, "no output directory given (-o MODEL)"); goto out; }
    if (n == 0) { rc = cli_usage_error(cmd, "no surface FILE given"); goto out; }
    for (int k = 0; k < n; k++) {
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
    thx_import_info *info = calloc((size_t)n, sizeof *info);
    thx_surface **surf = calloc((size_t)n, sizeof *surf);
    thx_model *m = NULL;
    cJSON *prov = NULL;
    int n_failed = 0;
    if (!info || !surf) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
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
    }
    m->provenance_json = cJSON_PrintUnformatted(prov);
    if (!m->provenance_json) {
        rc = cli_fail(ctx, cmd, thx_error(ctx, THX_ENOMEM, "out of memory"));
        goto done;
    }
    st = thx_model_write(ctx, m, outdir);
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (!quiet) printf("wrote %s (%d surface%s)\n", outdir, n, n == 1 ? "" : "s");
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
    return rc;
}
