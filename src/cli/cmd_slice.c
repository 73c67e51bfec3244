/* thorax slice: a model's closed surfaces cut by planes z = const, written as contours. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/contours_file.h"
#include "thorax/geom/slice.h"
int cmd_slice(int argc, char **argv)
{
    const char *out = NULL;
    thx_slice_opts o;
    thx_slice_opts_default(&o);
    int verbose = 0;
    static const cli_choice axes[] = {{"x", 0}, {"y", 1}, {"z", 2}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "CONTOURS", .s = &out,
         .help = "contour file to write (atomically)"},
        {.name = "--spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.spacing, .rule = CLI_GT,
         .bad = "--spacing must be positive", .help = "largest distance between the planes"},
        {.name = "--margin", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.margin, .rule = CLI_GE,
         .bad = "--margin must be >= 0", .def = "spacing/10",
         .help = "distance of the first and last plane from the lowest and highest node"},
        {.name = "--densify", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.densify, .rule = CLI_GE,
         .bad = "--densify must be >= 0", .def = "spacing/2", .note = "0 = only the crossing points",
         .help = "insert points so that no loop segment is longer"},
        {.name = "--node-spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.node_spacing, .rule = CLI_GT,
         .bad = "--node-spacing must be positive", .def = "--spacing",
         .help = "the contour file's suggested node spacing"},
        {.name = "--axis", .type = CLI_CHOICE, .choices = axes, .i = &o.axis, .def = "z",
         .help = "the planes are perpendicular to this axis; for x and y the contours are those of the model turned "
                 "(x, y, z) -> (y, z, x) or (z, x, y), a rotation, so the layer coordinate is that axis (the frame "
                 "turned with it)"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "less logging (no summary line)"},
    };
    cli_command cmd = {
        .name = "slice",
        .usage = "MODEL -o [--spacing] [--margin] [--densify] [--node-spacing] [--axis]",
        .about = "Cuts every surface of the model directory MODEL with planes z = const (or\n"
                 "x, y: --axis) spread evenly from the lowest node + margin to the highest -\n"
                 "margin, at most spacing\n"
                 "apart, and writes the cross-sections as a contour file\n"
                 "(docs/formats.md), names and roles kept: the contours the surfaces would have\n"
                 "been digitized as. `thorax surfaces` rebuilds surfaces from them.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos > 1) return cli_usage_error("slice", "more than one model given");
    const char *in = cmd.n_pos ? cmd.pos[0] : NULL;
    if (!in) return cli_usage_error("slice", "no model given");
    if (!out) return cli_usage_error("slice", "no output file given (-o CONTOURS)");
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_contours *c = NULL;
    int rc = 0;
    thx_status st = thx_model_read(ctx, in, &m);
    if (st == THX_OK) st = thx_model_slice(ctx, m, &o, &c);
    if (st == THX_OK) {
        char comment[4200];
        snprintf(comment, sizeof comment, "sliced from the model %s\ncommand: %s", in, cli_command_line());
        st = thx_contours_write(ctx, c, out, comment);
    }
    if (st != THX_OK) rc = cli_fail(ctx, "slice", st);
    else if (verbose >= 0) {
        size_t loops = 0;
        for (size_t k = 0; k < c->n_surfaces; k++)
            for (size_t l = 0; l < c->surf[k].n_layers; l++) loops += c->surf[k].layers[l].n_loops;
        fprintf(stderr, "thorax: wrote %s: %zu surfaces, %zu loops\n", out, c->n_surfaces, loops);
    }
    thx_contours_destroy(&c);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
