/* Shared helpers of the thorax command-line subcommands. */
#ifndef THORAX_CLI_H
#define THORAX_CLI_H
#include "cli/options.h"
#include "thorax/core/core.h"
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
int cmd_animate(int argc, char **argv);
int cmd_view(int argc, char **argv);

/* A context whose log goes to stderr ("thorax: warning: ..."), verbosity from -v/-q. Every existing
 * regular file on the command line but the values of the last cli_parse's CLI_OUTPUT options is
 * registered as an input (thx_ctx_add_input): no single-file output may replace it. */
thx_ctx *cli_ctx(int verbose);
/* Prints "thorax CMD: <message>" for a failed status and returns the exit code (1, or 2 for usage). */
int cli_fail(thx_ctx *ctx, const char *cmd, thx_status st);
/* The whole command line joined by spaces (for provenance). Static buffer. */
const char *cli_command_line(void);
void cli_set_command_line(int argc, char **argv);
#endif
