/* thorax slice: a model's closed surfaces cut by planes z = const, written as contours. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/contours_file.h"
#include "thorax/geom/slice.h"
static void help(void)
{
    printf("usage: thorax slice MODEL -o CONTOURS [--spacing MM] [--margin MM] [--densify MM]\n"
           "                          [--node-spacing MM]\n\n"
           "Cuts every surface of the model directory MODEL with planes z = const spread\n"
           "evenly from the lowest node + margin to the highest - margin, at most spacing\n"
           "apart, and writes the cross-sections as a contour file\n"
           "(docs/formats.md), names and roles kept: the contours the surfaces would have\n"
           "been digitized as. `thorax surfaces` rebuilds surfaces from them.\n\n"
           "options:\n"
           "  -o, --output FILE   contour file to write (atomically)\n"
           "  --spacing MM        largest distance between the planes (default 5)\n"
           "  --margin MM         distance of the first and last plane from the lowest and\n"
           "                      highest node (default spacing/10)\n"
           "  --densify MM        insert points so no loop segment is longer (default spacing/2;\n"
           "                      0 = only the crossing points)\n"
           "  --node-spacing MM   the contour file's suggested node spacing (default: --spacing)\n");
}

int cmd_slice(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    thx_slice_opts o;
    thx_slice_opts_default(&o);
    int verbose = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) { help(); return 0; }
        else if (!strcmp(a, "-o") || !strcmp(a, "--output")) { if (!v) return cli_usage_error("slice", "%s needs a value", a); out = v; i++; }
        else if (!strcmp(a, "--spacing")) { if (cli_parse_double("slice", a, v, &o.spacing)) return 2; i++; if (!(o.spacing > 0)) return cli_usage_error("slice", "--spacing must be positive"); }
        else if (!strcmp(a, "--margin")) { if (cli_parse_double("slice", a, v, &o.margin)) return 2; i++; if (o.margin < 0) return cli_usage_error("slice", "--margin must be >= 0"); }
        else if (!strcmp(a, "--densify")) { if (cli_parse_double("slice", a, v, &o.densify)) return 2; i++; if (o.densify < 0) return cli_usage_error("slice", "--densify must be >= 0"); }
        else if (!strcmp(a, "--node-spacing")) { if (cli_parse_double("slice", a, v, &o.node_spacing)) return 2; i++; if (!(o.node_spacing > 0)) return cli_usage_error("slice", "--node-spacing must be positive"); }
        else if (!strcmp(a, "-v")) verbose = 1;
        else if (!strcmp(a, "-q")) verbose = -1;
        else if (a[0] == '-' && a[1]) return cli_usage_error("slice", "unknown option '%s'", a);
        else if (!in) in = a;
        else return cli_usage_error("slice", "more than one model given");
    }
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
