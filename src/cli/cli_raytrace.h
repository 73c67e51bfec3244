/* The ray tracer's options (cli_raytrace.c) that thorax render, animate and trace take. */
#ifndef THORAX_CLI_RAYTRACE_H
#define THORAX_CLI_RAYTRACE_H
#include "cli/render_cli.h"

/* Into t[N_RAYTRACE_OPTS]; their values into o->p (renderer, rt, rt_mat); returns their count. */
#define N_RAYTRACE_OPTS 12
size_t raytrace_options(cli_opt *t, ropts *o);
#endif
