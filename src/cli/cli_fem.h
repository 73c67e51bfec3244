/* Helpers of the commands that solve with PETSc (forward, verify). */
#ifndef THORAX_CLI_FEM_H
#define THORAX_CLI_FEM_H
#include <stddef.h>

#include "thorax/core/core.h"
#include "thorax/core/fileio.h"
#include "thorax/model/model.h"
#include "thorax/model/series.h"
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
/* cli_command.pass for a command that passes PETSc options through (user: its cli_petsc_args):
 * adds argv[i] (and its value); returns how many words after argv[i] it took. */
int cli_petsc_pass(void *user, char **argv, int argc, int i);
/* PetscInitialize with those options; rank of this process. */
thx_status cli_petsc_init(thx_ctx *ctx, cli_petsc_args *pa, int *rank);
/* Warns about PETSc options nobody used, then PetscFinalize (if initialized). */
void cli_petsc_finish(cli_petsc_args *pa);

/* Writes j (then deleted, even on failure) as indented JSON and a newline to path, atomically:
 * a temporary file renamed into place. */
struct cJSON;
thx_status cli_write_json(thx_ctx *ctx, const char *path, struct cJSON *j);

/* The end of a command writing into an output directory (thorax/core/fileio.h): when st is THX_OK,
 * the manifest j as od->tmp/NAME (cli_write_json; j is deleted either way), then the directory
 * committed; on any failure the directory is abandoned (thx_outdir_abort). Returns the status. */
thx_status cli_outdir_finish(thx_ctx *ctx, thx_outdir *od, const char *name, struct cJSON *j, thx_status st);

/* A progress bar on stderr ("thorax LABEL [=====>    ] 120/300"); user is the label. */
void cli_progress(void *user, size_t done, size_t total);

/*
 * The volume check before a solve (thorax forward): thx_volume_check of m's
 * volume against m's surfaces, default options (thorax/check/check_volume.h).
 *  - passed: THX_OK;
 *  - failed, force = 0: every reason on stderr (rank 0 only), then THX_ECHECK
 *    with a message naming the failures and the first reason ("... not
 *    solved; --force solves anyway");
 *  - failed, force = 1: a warning on stderr (rank 0), THX_OK.
 * *note (if not NULL; on THX_OK and THX_ECHECK) is a new object for
 * solution.json's "volume_check": {"ok", "forced", "failures": [names],
 * "reasons": [..]}; with force and a failure, *warning (if not NULL) gets a
 * new array of strings for its "warnings". Caller deletes both.
 * Other statuses: THX_ENOMEM (nothing returned).
 */
struct thx_model;
/* Starts looking at model_dir's kept verdict (thorax/check/verdict.h: the SHA-256 of 70 MB for the
 * high phantom) in a thread of its own, while the caller reads the model; cli_volume_gate on the same
 * directory takes its answer. cli_volume_gate_end joins it (every path out of a command that started
 * it). Nothing is started when the thread cannot be made: the gate then looks itself. */
void cli_volume_gate_prefetch(const char *model_dir);
void cli_volume_gate_end(void);
thx_status cli_volume_gate(thx_ctx *ctx, const char *cmd, const char *model_dir, const struct thx_model *m, int force,
                           int rank, struct cJSON **note, struct cJSON **warning);

/* thorax forward --electrode ...: the defibrillation problem (cmd_defib.c); force: solve a volume
 * that fails the check (cli_volume_gate). */
int cli_forward_defib(const char *model_dir, const char *out, const char **specs, int n_specs, double threshold,
                      const char *format, cli_petsc_args *pa, int verbose, int force);

/* thorax forward --dipoles FILE: current dipole sources (cmd_forward_dipoles.c); method THX_DIPOLE_*; rows_path (may be
 * NULL): electrodes whose signals are written too. */
int cli_forward_dipoles(const char *model_dir, const char *out, const char *dip_path, int method, const char *rows_path,
                        double max_offset, const char *format, int want_volume, int warm, cli_petsc_args *pa, int verbose,
                        int force);
/* forward under mpirun with --volume (collective): rank 0 begins od (thx_outdir_begin) and makes
 * od->tmp/parts; every rank writes its part of the volume potentials there (thorax/fem/parts.h), rank
 * 0 the parts' manifest parts.json ("format": "thorax-parts"). */
thx_status cli_forward_parts(thx_ctx *ctx, thx_outdir *od, const thx_model *m, const thx_series *volume, int rank, int ranks);
#endif
