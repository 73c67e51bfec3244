/*
 * thorax phantom: writes the built-in synthetic thorax (include/thorax/phantom/phantom.h)
 * as hand-digitized contours, the input of `thorax surfaces`.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "thorax/io/contours_file.h"
#include "thorax/core/fileio.h"
#include "thorax/phantom/phantom.h"
static const char *CMD = "phantom";

/* Writes contours to standard output through a temporary file: the writer is
 * atomic by path, and the text must be complete before any of it is shown. The
 * file goes into a private temporary directory (the writer replaces only a file
 * that is thorax's own, so it must not exist beforehand). */
static thx_status write_stdout(thx_ctx *ctx, const thx_contours *c, const char *comment)
{
    const char *tmp = getenv("TMPDIR");
    char dir[1024], path[1100];
    snprintf(dir, sizeof dir, "%s/thorax-phantom-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(dir)) return thx_error(ctx, THX_EIO, "%s: cannot create a temporary directory", dir);
    snprintf(path, sizeof path, "%s/contours.txt", dir);
    thx_status st = thx_contours_write(ctx, c, path, comment);
    char *text = NULL;
    size_t len = 0;
    if (st == THX_OK) st = thx_read_file(ctx, path, &text, &len);
    if (st == THX_OK && (fwrite(text, 1, len, stdout) != len || fflush(stdout) != 0))
        st = thx_error(ctx, THX_EIO, "standard output: write failed");
    free(text);
    remove(path);
    rmdir(dir);
    return st;
}

int cmd_phantom(int argc, char **argv)
{
    thx_phantom_opts o;
    thx_phantom_opts_default(&o);
    const char *out = NULL, *beat = NULL;
    int verbose = 0;
    long seed = (long)o.seed;
    static const cli_choice resolutions[] = {{"high", THX_PHANTOM_HIGH}, {"medium", THX_PHANTOM_MEDIUM}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--resolution", .alias = "-r", .type = CLI_CHOICE, .choices = resolutions, .i = &o.resolution,
         .help = "high: every layer, 5 mm apart, node spacing 5 mm (thorax surfaces builds about 42,400 nodes and "
                 "84,800 triangles from it); medium: every second layer, node spacing 11 mm (about 9,400 nodes and "
                 "18,800 triangles)"},
        {.name = "--seed", .alias = "-s", .type = CLI_INT, .meta = "N", .l = &seed, .rule = CLI_GE,
         .bad = "--seed: the seed must be >= 0", .help = "random seed; the same seed gives byte-identical files"},
        {.name = "--jitter", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.jitter_mm, .rule = CLI_GE,
         .bad = "--jitter: must be >= 0 mm",
         .help = "standard deviation of the point jitter normal to the outline; each point moves at most "
                 "min(2.5 sd, 1.5 mm)"},
        {.name = "--shift", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.shift_mm, .rule = CLI_GE,
         .bad = "--shift: must be >= 0 mm", .help = "standard deviation of the whole-layer shifts (breathing)"},
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "FILE", .s = &out,
         .help = "output file, '-' for standard output; written atomically"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE,
         .help = "more messages on standard error"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "fewer messages on standard error"},
        {.name = "--beat", .type = CLI_INPUT, .meta = "MODEL", .s = &beat,
         .help = "instead: the phantom's heartbeat on MODEL's heart surface, the same as 'thorax beat MODEL' with the "
                 "other options (see thorax beat --help)"},
    };
    cli_command cmd = {
        .name = CMD,
        .usage = "[--resolution] [--seed] [--jitter] [--shift] -o\n--beat -o=SERIES [beat options]",
        .about = "Writes a synthetic human thorax as hand-digitized contours (text format\n"
                 "'thorax-contours 1'): outer torso, subcutaneous fat/muscle interface, inner\n"
                 "border of the skeletal muscle, right and left lungs (crescent-shaped lower\n"
                 "layers around the heart and diaphragm), and the epicardium. The points imitate\n"
                 "hand digitization: uneven spacing, jitter, a shift of each whole layer\n"
                 "(breathing), random start points and directions. Deterministic for a seed.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    /* --beat MODEL: the heartbeat (epicardial sequence) of a phantom model, as thorax beat, which
       reads the other options */
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--beat")) {
            if (i + 1 >= argc) return cli_usage_error(CMD, "--beat needs a model directory");
            char *args[64];
            int n = 0;
            args[n++] = "beat";
            args[n++] = argv[i + 1];
            for (int k = 1; k < argc && n < 63; k++)
                if (k != i && k != i + 1) args[n++] = argv[k];
            args[n] = NULL;
            return cmd_beat(n, args);
        }
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos) return cli_usage_error(CMD, "unknown argument '%s'", cmd.pos[0]);
    o.seed = (unsigned long)seed;
    if (!out) return cli_usage_error(CMD, "no output given (-o FILE, or -o - for standard output)");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_contours *c = NULL;
    thx_phantom_counts est;
    thx_status st = thx_phantom_contours(ctx, &o, &c);
    if (st == THX_OK) st = thx_phantom_estimate(ctx, &o, &est);
    if (st == THX_OK) {
        /* The header records the options, not the raw command line: the output
         * then depends only on them, not on the name of the file. */
        const char *res = o.resolution == THX_PHANTOM_HIGH ? "high" : "medium";
        size_t loops = 0, points = 0;
        for (size_t s = 0; s < c->n_surfaces; s++)
            for (size_t l = 0; l < c->surf[s].n_layers; l++)
                for (size_t k = 0; k < c->surf[s].layers[l].n_loops; k++) {
                    loops++;
                    points += c->surf[s].layers[l].loops[k].n;
                }
        char comment[1024];
        snprintf(comment, sizeof comment,
                 "synthetic thorax, imitated hand digitization (thorax phantom)\n"
                 "command: thorax phantom --resolution %s --seed %lu --jitter %g --shift %g\n"
                 "%zu layers %g mm apart, %zu loops, %zu points; RAS coordinates, mm\n"
                 "expected model at spacing %g: about %zu surface nodes, %zu triangles",
                 res, o.seed, o.jitter_mm, o.shift_mm, est.layers,
                 o.resolution == THX_PHANTOM_HIGH ? 5.0 : 10.0, loops, points, c->spacing, est.nodes,
                 est.triangles);
        if (!strcmp(out, "-")) st = write_stdout(ctx, c, comment);
        else st = thx_contours_write(ctx, c, out, comment);
        if (st == THX_OK)
            thx_log(ctx, THX_LOG_INFO, "phantom (%s, seed %lu): %zu layers, %zu loops, %zu points -> %s", res, o.seed,
                    est.layers, loops, points, strcmp(out, "-") ? out : "standard output");
    }
    int rc = st == THX_OK ? 0 : cli_fail(ctx, CMD, st);
    thx_contours_destroy(&c);
    thx_ctx_destroy(&ctx);
    return rc;
}
