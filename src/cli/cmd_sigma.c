/* thorax sigma: a meshed model's conductivity table, listed or changed in place (model.json's
 * "regions"; thorax/mesh/mesh.h thx_regions_assign). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/mesh/mesh.h"

/* A region's conductivity as thorax sigma and thorax mesh --sigma read it back. */
static void sigma_text(const thx_region *r, char *buf, size_t size)
{
    const double *s = r->sigma;
    if (!r->anisotropic) snprintf(buf, size, "%.6g", s[0]);
    else if (s[1] == 0 && s[2] == 0 && s[5] == 0 && s[3] == 0 && s[6] == 0 && s[7] == 0)
        snprintf(buf, size, "%.6g,%.6g,%.6g", s[0], s[4], s[8]);
    else snprintf(buf, size, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", s[0], s[4], s[8], s[1], s[2], s[5]);
}

int cmd_sigma(int argc, char **argv)
{
    const char *source = NULL;
    double scale = 1;
    int verbose = 0;
    cli_opt opts[] = {
        {.name = "--scale", .type = CLI_REAL, .meta = "K", .d = &scale, .rule = CLI_GT | CLI_FINITE, .lo = 0,
         .bad = "--scale must be a positive number",
         .help = "multiply every region's conductivity by K (after the assignments), e.g. to test that a "
                 "potential-driven solution does not change"},
        {.name = "--source", .type = CLI_STRING, .meta = "TEXT", .s = &source, .def = "set by the user (thorax sigma)",
         .help = "the source recorded with the values assigned (a literature reference)"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command cmd = {
        .name = "sigma",
        .usage = "MODEL\nMODEL NAME=SIGMA... [--scale] [--source]",
        .about = "Lists a meshed model's conductivity table (region, conductivity in S/m, source),\n"
                 "or changes it: each NAME=SIGMA gives region NAME a number (isotropic) or a tensor\n"
                 "in the model's axes, SXX,SYY,SZZ or SXX,SYY,SZZ,SXY,SXZ,SYZ (positive definite),\n"
                 "as thorax mesh --sigma does at meshing. Unknown names are refused with the\n"
                 "table's names. The model's model.json is rewritten atomically, the mesh and\n"
                 "the surfaces unchanged; the forward and defibrillation solvers read the new\n"
                 "table (solutions made before keep the old one: run them again).\n",
        .epilog = "Example:\n  thorax sigma model lung_l=0.08 lung_r=0.08 muscle=0.04,0.04,0.4 --source \"Rush et al. 1963\"\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos < 1) return cli_usage_error("sigma", "no model given");
    const char *dir = cmd.pos[0];
    for (int k = 1; k < cmd.n_pos; k++)
        if (!strchr(cmd.pos[k], '='))
            return cli_usage_error("sigma", "'%s': expected NAME=SIGMA (one model, then assignments)", cmd.pos[k]);
    int change = cmd.n_pos > 1 || scale != 1;
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_outdir od;
    const char *inputs[] = {dir};
    thx_status st = THX_OK;
    /* claimed before reading: a model another command rewrites meanwhile is not replaced */
    if (change) st = thx_outdir_claim(ctx, &od, dir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, inputs, 0);
    if (st == THX_OK) st = thx_model_read(ctx, dir, &m);
    if (st == THX_OK && !m->volume)
        st = thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh, so no conductivity table (thorax mesh %s)", dir,
                       dir);
    thx_volume *v = st == THX_OK ? m->volume : NULL;
    for (int k = 1; st == THX_OK && k < cmd.n_pos; k++)
        st = thx_regions_assign(ctx, v->regions, v->n_regions, cmd.pos[k],
                                source ? source : "set by the user (thorax sigma)");
    if (st == THX_OK && scale != 1)
        for (size_t r = 0; r < v->n_regions; r++) {
            for (int k = 0; k < 9; k++) v->regions[r].sigma[k] *= scale;
            char why[160];
            if (!thx_sigma_in_range(v->regions[r].sigma, why, sizeof why)) {
                st = thx_error(ctx, THX_EINPUT, "--scale %g: region \"%s\": %s (thorax takes %g to %g S/m)", scale,
                               v->regions[r].name, why, THX_SIGMA_MIN, THX_SIGMA_MAX);
                break;
            }
            char *src = v->regions[r].source;
            size_t at = strlen(src);
            if (at + 32 < sizeof v->regions[r].source) snprintf(src + at, sizeof v->regions[r].source - at, "; scaled by %g", scale);
        }
    if (st == THX_OK && change) st = thx_model_write_claimed(ctx, m, &od);
    int rc = 0;
    if (st != THX_OK) rc = cli_fail(ctx, "sigma", st);
    else if (verbose >= 0 || !change) {
        printf("%-16s %-34s %s\n", "region", "sigma (S/m)", "source");
        for (size_t r = 0; r < v->n_regions; r++) {
            char t[256];
            sigma_text(&v->regions[r], t, sizeof t);
            printf("%-16s %-34s %s\n", v->regions[r].name, t, v->regions[r].source);
        }
        if (change) printf("wrote %s/%s\n", dir, THX_MODEL_MANIFEST);
    }
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
