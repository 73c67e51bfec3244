/* Helpers of the commands that solve with PETSc (forward, verify). */
#ifndef THORAX_CLI_FEM_H
#define THORAX_CLI_FEM_H
#include <stddef.h>

#include "thorax/core.h"

/* The PETSc options of a command line: every argument with a single leading '-' that the command
 * does not know, with its value when the next argument does not start with '-' (or is a number). */
typedef struct {
    int argc;
    char *argv[256];
    int inited;
} cli_petsc_args;

void cli_petsc_args_init(cli_petsc_args *pa, char *argv0);
/* Adds option a (and value v when it takes one); returns 1 if v was taken, else 0. */
int cli_petsc_args_add(cli_petsc_args *pa, char *a, char *v);
/* PetscInitialize with those options; rank of this process. */
thx_status cli_petsc_init(thx_ctx *ctx, cli_petsc_args *pa, int *rank);
/* Warns about PETSc options nobody used, then PetscFinalize (if initialized). */
void cli_petsc_finish(cli_petsc_args *pa);

/* Writes j (then deleted, even on failure) as indented JSON and a newline to path, atomically:
 * a temporary file renamed into place. */
struct cJSON;
thx_status cli_write_json(thx_ctx *ctx, const char *path, struct cJSON *j);

/* A progress bar on stderr ("thorax LABEL [=====>    ] 120/300"); user is the label. */
void cli_progress(void *user, size_t done, size_t total);

/* thorax forward --electrode ...: the defibrillation problem (cmd_defib.c). */
int cli_forward_defib(const char *model_dir, const char *out, const char **specs, int n_specs, double threshold,
                      const char *format, cli_petsc_args *pa, int verbose);
#endif
