/* Shared helpers of the thorax command-line subcommands. */
#ifndef THORAX_CLI_H
#define THORAX_CLI_H
#include "cli/options.h"
#include "thorax/core/core.h"
#include "thorax/model/contours.h"
typedef int (*cli_cmd_fn)(int argc, char **argv);

int cmd_phantom(int argc, char **argv);
int cmd_surfaces(int argc, char **argv);
int cmd_image(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_slice(int argc, char **argv);
int cmd_field_streamlines(int argc, char **argv); /* thorax streamlines (issue 16), to join thorax field */
/* 0 when the streamline seeds of specs (density:N, region:NAME:N ...) fit in memory, else the exit
 * code after a message naming the limit (cmd_field_streamlines.c; field, render, animate, view). */
int cli_check_seed_counts(const char *cmd, const char *const *specs, int n);
int cmd_import(int argc, char **argv);
int cmd_mesh(int argc, char **argv);
int cmd_sigma(int argc, char **argv);
int cmd_series(int argc, char **argv);
int cmd_electrodes(int argc, char **argv);
int cmd_beat(int argc, char **argv);
int cmd_forward(int argc, char **argv);
int cmd_bem(int argc, char **argv);
int cmd_inverse(int argc, char **argv);
int cmd_verify(int argc, char **argv);
int cmd_leads(int argc, char **argv);
int cmd_field(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_trace(int argc, char **argv);
int cmd_animate(int argc, char **argv);
int cmd_view(int argc, char **argv);
int cmd_digitize(int argc, char **argv);

/* A context whose log goes to stderr ("thorax: warning: ..."), verbosity from -v/-q. Every existing
 * regular file on the command line but the values of the last cli_parse's CLI_OUTPUT options is
 * registered as an input (thx_ctx_add_input): no single-file output may replace it. */
thx_ctx *cli_ctx(int verbose);
/* Prints "thorax CMD: <message>" for a failed status and returns the exit code (1, or 2 for usage). */
int cli_fail(thx_ctx *ctx, const char *cmd, thx_status st);
/* The whole command line joined by spaces (for provenance). Static buffer. */
const char *cli_command_line(void);
void cli_set_command_line(int argc, char **argv);
/* Label maps (cmd_digitize.c; thorax digitize, thorax surfaces LABELS --label ...): the --label
 * specs, the planes and the cleaning, then the traced and validated contours (thorax/image/trace.h)
 * with the report on stdout (verbose >= 0). 0, or the exit status after the message. */
typedef struct {
    const char **labels; /* --label specs VALUE[,VALUE...]=NAME:ROLE */
    int n_labels;
    double spacing;      /* mm between planes; 0: every image plane */
    long min_size;       /* voxels */
    double node_spacing; /* mm; 0: the default */
    int holes;           /* thx_trace_holes */
    double surfaces_spacing, surfaces_smoothing; /* how thorax surfaces will resample the loops (its --spacing and
                                                    --smoothing; 0 and -1: its defaults): loops it would find with no
                                                    partner are dropped (thx_contours_drop_flat) */
    /* out: the image's format, declared frame and the model-to-RAS rotation (row-major) */
    char format[16], source_frame[32];
    double to_ras[9];
} cli_trace_args;
int cli_trace_labels(const char *cmd, const char *image, cli_trace_args *a, int verbose, thx_ctx *ctx,
                     thx_contours **out);
/* The options they share (in a cli_opt table): --label, PLANE (the plane spacing's option name),
 * --axis, --min-size, --holes. */
#define CLI_TRACE_OPTIONS(A, LABELS, NLABELS, MINSIZE, AXIS, AXES, HOLES, PLANE)                                        \
    {.name = "--label", .type = CLI_STRING, .meta = "VALUES=NAME:ROLE", .flags = CLI_REPEAT, .sv = LABELS,               \
     .count = &NLABELS, .max = 64,                                                                                       \
     .help = "a surface traced from the label map: the label values (integers, comma-separated, or 'all' for every "    \
             "non-zero value) whose union it bounds, its name and role (outer, fat, muscle, lung, heart, other; an "    \
             "outer surface also takes every other --label's values); a value absent from the image is a warning, a "  \
             "surface with none an error. An organ (lung, heart, other) whose voxels form parts well apart (two "      \
             "lungs under one label) gives a surface per part: NAME_right and NAME_left side by side, else NAME_1.. "  \
             "right to left; organs of disjoint labels that touch are traced apart (a gap of ~0.6 voxel)"},           \
    {.name = PLANE, .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &(A).spacing, .rule = CLI_GE | CLI_FINITE,      \
     .bad = PLANE " must be >= 0", .def = "0", .note = "0 = every image plane",                                         \
     .help = "distance between the planes cut across the label map (resampled by interpolating each tissue's "         \
             "smoothed indicator)"},                                                                                    \
    {.name = "--axis", .type = CLI_CHOICE, .meta = "AXIS", .choices = AXES, .i = &AXIS, .def = "superior",             \
     .help = "the anatomical axis the planes are cut across: superior (the image's index axis nearest it; the only "   \
             "one so far)"},                                                                                            \
    {.name = "--min-size", .type = CLI_INT, .meta = "VOXELS", .l = &MINSIZE, .rule = CLI_GE, .lo = 0,                   \
     .bad = "--min-size must be >= 0", .note = "0 keeps all",                                                            \
     .help = "6-connected 3D components of a surface's labels with fewer voxels are removed (and reported), cavities "  \
             "with fewer filled"},                                                                                      \
    {.name = "--holes", .type = CLI_CHOICE, .choices = HOLES, .i = &(A).holes, .def = "fill",                            \
     .help = "a hole of a surface's labels in a plane: filled (surfaces bound solids; the inner boundary is the "        \
             "surface of what lies inside) or kept as a clockwise loop, laced to the next plane's holes (a lung "     \
             "around the diaphragm's dome; a hole on a surface's end plane is not capped: the check fails it)"}
#endif
