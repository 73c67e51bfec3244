/* thorax export with data (cli_export_data.c), called by cmd_export.c once the options are parsed. */
#ifndef THORAX_CLI_EXPORT_H
#define THORAX_CLI_EXPORT_H

#include "thorax/io/model_dir.h"

typedef struct {
    const char *model_dir, *out_dir;
    const char *solution; /* a solution directory (thorax forward), or NULL */
    const char *data;     /* a series file, or NULL (exactly one of the two is set) */
    const char *frames;   /* --frames, or NULL: all */
    const char *const *only; /* --surface names */
    int n_only;
    thx_export_format fmt;
    int verbose;
} cli_export_request;

/* Runs the export; the exit status (0, 1, or 2 for a bad --frames). */
int cli_export_data(const cli_export_request *rq);

/* thorax export --format html (cli_export_page.c): the whole command, render's options with it. */
int cli_export_page(int argc, char **argv);

/* Frame lists: cli_parse_frames (cli/options.h). */

#endif
