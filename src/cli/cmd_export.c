/* thorax export: a model's surfaces as VTK, VTP, OBJ, STL or PLY files, or its
 * volume mesh as VTU or Gmsh MSH, for other tools; with --solution or --data, the potentials per
 * frame (cli_export_data.c). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/core/fileio.h"
#include "cli/cli_export.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
static const char *const ext_of[] = {"vtk", "vtp", "obj", "stl", "ply", "vtu", "msh"}; /* indexed by thx_export_format */

int cmd_export(int argc, char **argv)
{
    /* --format html: the web page, with render's options (cli_export_page.c) */
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--format=html") || (!strcmp(argv[i], "--format") && i + 1 < argc && !strcmp(argv[i + 1], "html")))
            return cli_export_page(argc, argv);
    const char *cmd = "export";
    const char *out_dir = NULL, *solution = NULL, *data = NULL, *frames = NULL;
    const char **only = calloc((size_t)argc + 1, sizeof *only);
    int n_only = 0, verbose = 0, rc = 0, format = -1;
    if (!only) {
        fprintf(stderr, "thorax export: out of memory\n");
        return 1;
    }
    static const cli_choice formats[] = {{"vtk", THX_EXPORT_VTK}, {"vtp", THX_EXPORT_VTP}, {"obj", THX_EXPORT_OBJ},
                                         {"stl", THX_EXPORT_STL}, {"ply", THX_EXPORT_PLY}, {"vtu", THX_EXPORT_VTU},
                                         {"msh", THX_EXPORT_MSH}, {"html", 100}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--format", .type = CLI_CHOICE, .meta = "F", .choices = formats, .i = &format,
         .help = "the format (required): vtk: legacy VTK ASCII polydata (ParaView, VTK); vtp: VTK XML polydata; "
                 "obj: Wavefront OBJ; stl: binary STL (float32, facet normals pointing outward); ply: ASCII PLY; "
                 "vtu: the volume as a VTK XML unstructured grid of tetrahedra (binary), cell data \"region\" "
                 "(1-based region id) and \"conductivity\" (S/m), point data \"surface\" and \"surface_node\" (the node "
                 "tables), field data \"region_name\", \"region_sigma\", \"surface_name\"; msh: the volume as Gmsh MSH 4.1 "
                 "ASCII, one physical volume per region and one physical surface per surface (the tetrahedra's faces on "
                 "it); html: one self-contained interactive web page of the potentials (thorax export --format html --help)"},
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out_dir,
         .def = "MODEL itself; required with --solution or --data",
         .help = "directory for the files (created if missing, with its parents)"},
        {.name = "--surface", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = only, .count = &n_only,
         .max = argc, .def = "all",
         .help = "export only this surface (surface formats); with --data, the surface whose nodes are the series' rows"},
        {.name = "--solution", .type = CLI_INPUT, .meta = "DIR", .s = &solution,
         .help = "a solution directory of thorax forward: the potentials of its volume series (every surface's taken "
                 "through the node tables, J = -sigma grad phi per tetrahedron) or of its torso series, per frame "
                 "(docs/formats.md, \"Exports with data\")"},
        {.name = "--data", .type = CLI_INPUT, .meta = "SERIES", .s = &data,
         .help = "a series whose rows are the volume's nodes or one surface's (any format thorax series reads), "
                 "exported per frame as --solution's"},
        {.name = "--frames", .type = CLI_STRING, .meta = "LIST", .s = &frames, .def = "all",
         .help = "the frames of --solution or --data to export: 1-based A:B[:STEP] items separated by commas "
                 "(1:40:5,60)"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "MODEL --format=vtk|vtp|obj|stl|ply [-o] [--surface]\nMODEL --format=vtu|msh [-o]\n"
                 "MODEL --format=vtu|vtp|vtk|msh --solution|--data -o [--frames] [--surface]",
        .about = "Writes each surface of the model directory MODEL as DIR/NAME.EXT, or, with\n"
                 "a volume format, its volume mesh (made by `thorax mesh`) as DIR/volume.EXT.\n"
                 "vtu files carry the region ids, names and conductivities; msh files tag the\n"
                 "surfaces' triangles (physical surfaces) and the regions (physical volumes).\n\n"
                 "With --solution or --data: the potentials of every frame (or --frames), as\n"
                 "DIR/volume_FFFF.vtu (point data potential, cell data current_density) or\n"
                 "DIR/NAME_FFFF.vtp|vtk per surface (point data potential), FFFF the 1-based\n"
                 "frame number, with DIR/volume.pvd or DIR/NAME.pvd (not for vtk): the\n"
                 "collection ParaView opens with the series' time axis; or DIR/volume.msh with\n"
                 "one $NodeData per frame (Gmsh views with their times).\n",
        .epilog = "Coordinates are in mm; triangles stay counterclockwise seen from outside,\n"
                  "tetrahedra right-handed.\n"
                  "Each file is written atomically. Exit status: 0 ok, 1 error, 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) {
        free(only);
        return CLI_EXIT(pr);
    }
    const char *model_dir = c.n_pos ? c.pos[0] : NULL;
    if (c.n_pos > 1) {
        rc = cli_usage_error(cmd, "unexpected argument '%s' (one MODEL directory expected)", c.pos[1]);
        goto out;
    }
    if (!model_dir) {
        rc = cli_usage_error(cmd, "no MODEL directory given");
        goto out;
    }
    if (format < 0) {
        rc = cli_usage_error(cmd, "--format is required (vtk, vtp, obj, stl, ply, vtu or msh)");
        goto out;
    }
    thx_export_format fmt = (thx_export_format)format;
    int volume = thx_export_format_is_volume(fmt);
    if (solution && data) {
        rc = cli_usage_error(cmd, "give --solution or --data, not both");
        goto out;
    }
    if (frames && !solution && !data) {
        rc = cli_usage_error(cmd, "--frames goes with --solution or --data");
        goto out;
    }
    if (solution || data) {
        if (!out_dir) {
            rc = cli_usage_error(cmd, "--solution and --data need -o DIR (one file per frame)");
            goto out;
        }
        if (fmt != THX_EXPORT_VTU && fmt != THX_EXPORT_VTP && fmt != THX_EXPORT_VTK && fmt != THX_EXPORT_MSH) {
            rc = cli_usage_error(cmd, "data go to vtu, vtp, vtk or msh, not '%s'", ext_of[fmt]);
            goto out;
        }
        if (fmt == THX_EXPORT_VTU && n_only > 0) {
            rc = cli_usage_error(cmd, "--surface does not apply to the volume format 'vtu'");
            goto out;
        }
        cli_export_request rq = {.model_dir = model_dir, .out_dir = out_dir, .solution = solution, .data = data,
                                 .frames = frames, .only = only, .n_only = n_only, .fmt = fmt, .verbose = verbose};
        rc = cli_export_data(&rq);
        goto out;
    }
    if (volume && n_only > 0) {
        rc = cli_usage_error(cmd, "--surface does not apply to the volume format '%s'", ext_of[fmt]);
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
    if (thx_make_dirs(out_dir) != 0) {
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
