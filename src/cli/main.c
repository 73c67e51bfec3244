/* thorax: the command-line front end. Each subcommand is a thin client of libthorax. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/cli.h"
#include "thorax/parallel/parallel.h"
#include "thorax/core/startup.h"

static const struct {
    const char *name;
    cli_cmd_fn fn;
    const char *summary;
} commands[] = {
    {"phantom", cmd_phantom, "write the built-in synthetic thorax as digitized contours"},
    {"image", cmd_image, "image volumes (NIfTI, NRRD, MetaImage, DICOM): grid, orientation, values, labels; convert; label by thresholds"},
    {"digitize", cmd_digitize, "a label map (NIfTI ...) -> contours: each tissue's boundary traced plane by plane"},
    {"surfaces", cmd_surfaces, "contours -> spline layers -> laced, capped, oriented surfaces (a model)"},
    {"check", cmd_check, "verify a model: closure, orientation, 4 pi solid angle, intersections, quality"},
    {"export", cmd_export, "write a model's surfaces as VTK, VTP, OBJ, STL or PLY"},
    {"slice", cmd_slice, "cut a model's surfaces by planes z = const into contours"},
    {"mesh", cmd_mesh, "tetrahedral volume mesh with tissue regions and conductivities (paper 3.3)"},
    {"sigma", cmd_sigma, "a meshed model's conductivity table: list it, or change regions' values in place"},
    {"import", cmd_import, "a model from surfaces or a volume mesh made elsewhere (tri, obj, stl, vtk, vtu, msh, ...)"},
    {"series", cmd_series, "time series (rows x frames): summary, conversion between text, raw and .mat"},
    {"electrodes", cmd_electrodes, "the phantom's electrodes: 12-lead positions and a body-surface array"},
    {"beat", cmd_beat, "the phantom's heartbeat: epicardial potentials of a dipole tracing a VCG loop"},
    {"forward", cmd_forward, "finite-element forward solutions: heart to body surface, currents, defibrillation"},
    {"bem", cmd_bem, "boundary-element forward solutions: heart-surface transfer matrix, dipoles (OpenMEEG spheres)"},
    {"inverse", cmd_inverse, "the inverse problem: heart-surface potentials from body-surface potentials, regularized"},
    {"verify", cmd_verify, "the finite-element solver against analytic solutions: convergence table"},
    {"leads", cmd_leads, "the 12-lead ECG and electrode-array signals of a forward solution"},
    {"field", cmd_field, "inside the volume: equipotential surfaces and slices of a solution (VTP, OBJ)"},
    {"render", cmd_render, "pictures of surfaces and potentials (headless OpenGL): views, clip planes, colour bar, ECG trace"},
    {"trace", cmd_trace, "the same pictures ray traced (RaySpray, Embree): shadows, glass and mirrors, ambient occlusion"},
    {"animate", cmd_animate, "one picture per frame and an MP4 movie (ffmpeg), resumable"},
    {"view", cmd_view, "the interactive viewer (GTK 4): linked surfaces, frames, picking, scripts"},
    {"streamlines", cmd_field_streamlines, "current streamlines of a solution, as tubes or lines (VTP, OBJ); also thorax field --streamlines"},
};
#define N_COMMANDS (sizeof commands / sizeof commands[0])

static char command_line[4096];

static int g_argc;
static char **g_argv;

void cli_set_command_line(int argc, char **argv)
{
    g_argc = argc;
    g_argv = argv;
    size_t off = 0;
    command_line[0] = '\0';
    for (int i = 0; i < argc && off < sizeof command_line; i++)
        off += (size_t)snprintf(command_line + off, sizeof command_line - off, "%s%s", i ? " " : "", argv[i]);
}

const char *cli_command_line(void) { return command_line; }

static void log_stderr(void *user, thx_log_level level, const char *msg)
{
    (void)user;
    fprintf(stderr, "thorax: %s%s\n", level == THX_LOG_WARN ? "warning: " : "", msg);
}

thx_ctx *cli_ctx(int verbose)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) {
        fprintf(stderr, "thorax: out of memory\n");
        exit(1);
    }
    thx_ctx_set_log(ctx, log_stderr, NULL,
                    verbose > 0 ? THX_LOG_DEBUG : verbose < 0 ? THX_LOG_WARN + 1 : THX_LOG_INFO);
    /* Every existing regular file named on the command line, except the values of the options the
     * command's table declares outputs (CLI_OUTPUT: -o/--output, --mp4, ...), is one of the command's
     * inputs: no single-file output may replace it (thorax/core/fileio.h). */
    for (int i = 2; i < g_argc; i++) {
        struct stat st;
        if (cli_is_output_arg(g_argv[i])) continue;
        if (stat(g_argv[i], &st) == 0 && S_ISREG(st.st_mode) && thx_ctx_add_input(ctx, g_argv[i]) != THX_OK) {
            fprintf(stderr, "thorax: out of memory\n");
            exit(1);
        }
    }
    return ctx;
}

int cli_fail(thx_ctx *ctx, const char *cmd, thx_status st)
{
    const char *msg = thx_ctx_message(ctx);
    fprintf(stderr, "thorax %s: %s: %s\n", cmd, thx_status_name(st), msg[0] ? msg : "(no detail)");
    return 1;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: thorax COMMAND [options]\n\n"
               "thorax: computational electrocardiology, from digitized contours of the body\n"
               "to the heart's electric field in it.\n\ncommands:\n");
    for (size_t i = 0; i < N_COMMANDS; i++) fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "  %-10s %s\n\nRun 'thorax COMMAND --help' for a command's options.\n", "help", "this text, or 'thorax help COMMAND'");
}

/* The command's help through its option table: the help itself, or one of the manual's sections, or
 * the table's check (options.h). */
static int command_help(size_t k, cli_help_mode mode)
{
    char *hargv[] = {(char *)commands[k].name, "--help", NULL};
    cli_set_help_mode(mode);
    return commands[k].fn(2, hargv);
}

/* thorax help --usage|--markdown COMMAND: docs/cli.md's generated sections (scripts/cli_docs.sh);
 * thorax help --check [COMMAND...]: every command's (or these) option table against its usage lines
 * (exit 1 on a problem, each on stderr). Not in the command list: they are the manual's tools. */
static int manual(int argc, char **argv)
{
    const char *what = argv[2];
    cli_help_mode mode = !strcmp(what, "--usage")      ? CLI_HELP_USAGE_MD
                         : !strcmp(what, "--markdown") ? CLI_HELP_OPTIONS_MD
                                                       : CLI_HELP_CHECK;
    if (mode != CLI_HELP_CHECK && argc != 4) {
        fprintf(stderr, "thorax: usage: thorax help %s COMMAND\n", what);
        return 2;
    }
    for (size_t k = 0; k < N_COMMANDS; k++) {
        int named = argc == 3;
        for (int i = 3; i < argc; i++) named |= !strcmp(argv[i], commands[k].name);
        if (named) command_help(k, mode);
    }
    for (int i = 3; i < argc; i++) {
        size_t k = 0;
        while (k < N_COMMANDS && strcmp(argv[i], commands[k].name)) k++;
        if (k == N_COMMANDS) {
            fprintf(stderr, "thorax: unknown command '%s'\n", argv[i]);
            return 2;
        }
    }
    if (mode == CLI_HELP_CHECK && cli_check_problems()) {
        int n = cli_check_problems();
        fprintf(stderr, "thorax help --check: %d problem%s\n", n, n > 1 ? "s" : "");
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
#ifdef THORAX_VIEW_PROGRAM
    /* thorax-view: the viewer alone, started by `thorax view ...` as `thorax-view view ...` */
    cli_set_command_line(argc, argv);
    if (argc < 2 || strcmp(argv[1], "view")) {
        fprintf(stderr, "thorax-view: run it as thorax view ... (see thorax help view)\n");
        return 2;
    }
    return cmd_view(argc - 1, argv + 1);
#endif
    cli_set_command_line(argc, argv);
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *name = argv[1];
    if (strcmp(name, "help") == 0 || strcmp(name, "--help") == 0 || strcmp(name, "-h") == 0) {
        if (argc >= 3 && strcmp(name, "help") == 0) {
            if (!strcmp(argv[2], "--usage") || !strcmp(argv[2], "--markdown") || !strcmp(argv[2], "--check"))
                return manual(argc, argv);
            for (size_t i = 0; i < N_COMMANDS; i++)
                if (strcmp(argv[2], commands[i].name) == 0) return command_help(i, CLI_HELP_TEXT);
            fprintf(stderr, "thorax: unknown command '%s'\n", argv[2]);
            return 2;
        }
        usage(stdout);
        return 0;
    }
    if (strcmp(name, "--version") == 0) {
        printf("thorax 0.1.0\n");
        return 0;
    }
    for (size_t i = 0; i < N_COMMANDS; i++)
        if (strcmp(name, commands[i].name) == 0) {
            /* The commands whose time goes into dense or sparse-direct algebra (factorizations, the
               boundary elements' dense systems, the SVDs) and large blocks of memory first make sure
               OpenBLAS runs the right kernels and malloc's large blocks are on huge pages, which may
               mean starting again (thorax/core/startup.h); the others are not worth the second start
               (about 0.08 s). */
            /* Under mpirun with more than one rank, only the commands that share their work among the
               ranks run: any other would be run whole by every rank, each writing the same outputs. */
            int ranks = thx_par_launched();
            if (ranks != 1) {
                static const char *const shared[] = {"forward", "bem", "verify", "render", "trace", "animate", "field"};
                int ok = 0;
                for (size_t k = 0; k < sizeof shared / sizeof shared[0]; k++) ok |= !strcmp(name, shared[k]);
                if (!ok) {
                    if (thx_par_launched_rank() == 0) /* (rank 0 speaks for all) */
                        fprintf(stderr, "thorax %s: started by mpirun with %s ranks, but %s runs in one process (every rank "
                            "would do the whole work and write the same outputs): run it without mpirun, or with -np 1. "
                            "The commands that share their work among ranks: forward, bem, verify, render, trace, "
                            "animate, field\n", name, ranks > 1 ? "several" : "an unreadable count of", name);
                    return 2;
                }
            }
            static const char *const blas_heavy[] = {"forward", "bem", "inverse", "verify"};
            for (size_t k = 0; k < sizeof blas_heavy / sizeof blas_heavy[0]; k++)
                if (!strcmp(name, blas_heavy[k])) thx_startup_heavy(argv);
            return commands[i].fn(argc - 1, argv + 1);
        }
    fprintf(stderr, "thorax: unknown command '%s' (see 'thorax help')\n", name);
    return 2;
}
