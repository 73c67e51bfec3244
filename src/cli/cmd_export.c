/* thorax export: a model's surfaces as VTK, VTP, OBJ, STL or PLY files, or its
 * volume mesh as VTU or Gmsh MSH, for other tools. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/cli.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static const char *const ext_of[] = {"vtk", "vtp", "obj", "stl", "ply", "vtu", "msh"}; /* indexed by thx_export_format */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: thorax export MODEL --format vtk|vtp|obj|stl|ply [-o DIR] [--surface NAME]...\n"
            "       thorax export MODEL --format vtu|msh [-o DIR]\n"
            "\n"
            "Writes each surface of the model directory MODEL as DIR/NAME.EXT, or, with\n"
            "a volume format, its volume mesh (made by `thorax mesh`) as DIR/volume.EXT.\n"
            "\n"
            "options:\n"
            "  --format F       vtk  legacy VTK ASCII polydata (ParaView, VTK)\n"
            "                   vtp  VTK XML polydata\n"
            "                   obj  Wavefront OBJ\n"
            "                   stl  binary STL (float32, facet normals pointing outward)\n"
            "                   ply  ASCII PLY\n"
            "                   vtu  volume: VTK XML unstructured grid, tetrahedra, cell data\n"
            "                        \"region\" (1-based region id), point data \"surface\" and\n"
            "                        \"surface_node\" (the node tables)\n"
            "                   msh  volume: Gmsh MSH 4.1 ASCII, one physical volume per region\n"
            "  -o, --output DIR directory for the files (default: MODEL itself; created if missing)\n"
            "  --surface NAME   export only this surface (repeatable; default: all;\n"
            "                   surface formats only)\n"
            "  -v, -q           more / less logging\n"
            "  -h, --help       this text\n"
            "\n"
            "Coordinates are in mm; triangles stay counterclockwise seen from outside,\n"
            "tetrahedra right-handed.\n"
            "Each file is written atomically. Exit status: 0 ok, 1 error, 2 bad usage.\n");
}

int cmd_export(int argc, char **argv)
{
    const char *cmd = "export";
    const char *model_dir = NULL, *out_dir = NULL, *format = NULL;
    const char **only = calloc((size_t)argc + 1, sizeof *only);
    int n_only = 0, verbose = 0, rc = 0;
    if (!only) {
        fprintf(stderr, "thorax export: out of memory\n");
        return 1;
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            free(only);
            return 0;
        } else if (!strcmp(a, "--format") || !strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--surface")) {
            if (i + 1 >= argc) {
                rc = cli_usage_error(cmd, "%s needs a value", a);
                goto out;
            }
            const char *v = argv[++i];
            if (!strcmp(a, "--format")) format = v;
            else if (!strcmp(a, "--surface")) only[n_only++] = v;
            else out_dir = v;
        } else if (!strcmp(a, "-v")) {
            verbose++;
        } else if (!strcmp(a, "-q")) {
            verbose--;
        } else if (a[0] == '-' && a[1]) {
            rc = cli_usage_error(cmd, "unknown option '%s'", a);
            goto out;
        } else if (!model_dir) {
            model_dir = a;
        } else {
            rc = cli_usage_error(cmd, "unexpected argument '%s' (one MODEL directory expected)", a);
            goto out;
        }
    }
    if (!model_dir) {
        rc = cli_usage_error(cmd, "no MODEL directory given");
        goto out;
    }
    thx_export_format fmt;
    if (!format) {
        rc = cli_usage_error(cmd, "--format is required (vtk, vtp, obj, stl, ply, vtu or msh)");
        goto out;
    }
    if (thx_export_format_parse(format, &fmt) != 0) {
        rc = cli_usage_error(cmd, "unknown format '%s' (vtk, vtp, obj, stl, ply, vtu or msh)", format);
        goto out;
    }
    int volume = thx_export_format_is_volume(fmt);
    if (volume && n_only > 0) {
        rc = cli_usage_error(cmd, "--surface does not apply to the volume format '%s'", format);
        goto out;
    }
    if (!out_dir) out_dir = model_dir;

    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_status st = thx_model_read(ctx, model_dir, &m);
    if (st) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (volume && !m->volume) {
        fprintf(stderr, "thorax export: %s: the model has no volume mesh (make one with `thorax mesh`)\n", model_dir);
        rc = 1;
        goto done;
    }
    /* Every requested name must exist before anything is written. */
    for (int k = 0; k < n_only; k++) {
        size_t i = 0;
        while (i < m->n_surfaces && strcmp(m->surf[i]->name, only[k]) != 0) i++;
        if (i == m->n_surfaces) {
            fprintf(stderr, "thorax export: %s: no surface \"%s\"; the model has:", model_dir, only[k]);
            for (size_t j = 0; j < m->n_surfaces; j++) fprintf(stderr, " %s", m->surf[j]->name);
            fprintf(stderr, "\n");
            rc = 1;
            goto done;
        }
    }
    /* Every file this run writes is claimed before any is written: one refused, none written. */
    for (size_t i = 0; i < m->n_surfaces && !volume; i++) {
        int wanted = n_only == 0;
        for (int k = 0; k < n_only && !wanted; k++) wanted = strcmp(m->surf[i]->name, only[k]) == 0;
        char path[4096];
        if (!wanted || (size_t)snprintf(path, sizeof path, "%s/%s.%s", out_dir, m->surf[i]->name, ext_of[fmt]) >= sizeof path)
            continue; /* a path too long is reported below */
        st = thx_export_claim(ctx, fmt, path);
        if (st) {
            rc = cli_fail(ctx, cmd, st);
            goto done;
        }
    }
    if (mkdir(out_dir, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "thorax export: %s: cannot create directory: %s\n", out_dir, strerror(errno));
        rc = 1;
        goto done;
    }
    if (volume) {
        char path[4096];
        if ((size_t)snprintf(path, sizeof path, "%s/volume.%s", out_dir, ext_of[fmt]) >= sizeof path) {
            fprintf(stderr, "thorax export: %s: path too long\n", out_dir);
            rc = 1;
            goto done;
        }
        st = thx_volume_export(ctx, m, fmt, path);
        if (st) {
            rc = cli_fail(ctx, cmd, st);
            goto done;
        }
        thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu nodes, %zu tetrahedra, %zu regions)", path, m->volume->n_nodes,
                m->volume->n_tets, m->volume->n_regions);
        goto done;
    }
    for (size_t i = 0; i < m->n_surfaces; i++) {
        const thx_surface *s = m->surf[i];
        int wanted = n_only == 0;
        for (int k = 0; k < n_only && !wanted; k++) wanted = strcmp(s->name, only[k]) == 0;
        if (!wanted) continue;
        char path[4096];
        if ((size_t)snprintf(path, sizeof path, "%s/%s.%s", out_dir, s->name, ext_of[fmt]) >= sizeof path) {
            fprintf(stderr, "thorax export: %s: path too long\n", out_dir);
            rc = 1;
            goto done;
        }
        st = thx_surface_export(ctx, s, fmt, path);
        if (st) {
            rc = cli_fail(ctx, cmd, st);
            goto done;
        }
        thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu nodes, %zu triangles)", path, s->n_nodes, s->n_tris);
    }
done:
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
out:
    free(only);
    return rc;
}
