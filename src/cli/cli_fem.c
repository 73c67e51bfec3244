/* PETSc option pass-through and progress display for the solving commands. */
#include <petscsys.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli/cli_fem.h"
#include "thorax/fileio.h"
#include "thorax/fem.h"

void cli_petsc_args_init(cli_petsc_args *pa, char *argv0)
{
    memset(pa, 0, sizeof *pa);
    pa->argv[pa->argc++] = argv0;
}

static int is_number(const char *s)
{
    char *e;
    if (!s || !*s) return 0;
    strtod(s, &e);
    return *e == '\0';
}

int cli_petsc_args_add(cli_petsc_args *pa, char *a, char *v)
{
    if (pa->argc < 254) pa->argv[pa->argc++] = a;
    if (v && (v[0] != '-' || is_number(v))) {
        if (pa->argc < 254) pa->argv[pa->argc++] = v;
        return 1;
    }
    return 0;
}

thx_status cli_petsc_init(thx_ctx *ctx, cli_petsc_args *pa, int *rank)
{
    pa->argv[pa->argc] = NULL;
    thx_status st = thx_fem_init(pa->argc, pa->argv, rank, NULL);
    if (st != THX_OK) return thx_error(ctx, THX_ESOLVER, "PETSc could not be initialized (PetscInitialize failed)");
    pa->inited = 1;
    return THX_OK;
}

void cli_petsc_finish(cli_petsc_args *pa)
{
    if (!pa->inited) return;
    PetscInt left = 0;
    PetscOptionsAllUsed(NULL, &left);
    if (left > 0) {
        int rank = 0;
        thx_fem_init(0, NULL, &rank, NULL);
        if (rank == 0) fprintf(stderr, "thorax: warning: %d PETSc option%s given but not used:\n", (int)left, left > 1 ? "s" : "");
        if (rank == 0) PetscOptionsLeft(NULL);
    }
    thx_fem_finalize();
    pa->inited = 0;
}

void cli_progress(void *user, size_t done, size_t total)
{
    const char *label = user ? (const char *)user : "";
    int width = 30, fill = total ? (int)((double)done / (double)total * width) : width;
    char bar[64];
    for (int i = 0; i < width; i++) bar[i] = i < fill ? '=' : (i == fill ? '>' : ' ');
    bar[width] = '\0';
    fprintf(stderr, "\rthorax %s [%s] %zu/%zu", label, bar, done, total);
    if (done >= total) fputc('\n', stderr);
    fflush(stderr);
}

thx_status cli_write_json(thx_ctx *ctx, const char *path, cJSON *j)
{
    char *text = j ? cJSON_Print(j) : NULL;
    cJSON_Delete(j);
    if (!text) return thx_error(ctx, THX_ENOMEM, "%s: out of memory writing the JSON", path);
    thx_atomic_file af;
    thx_status st = thx_atomic_open(ctx, path, &af);
    if (st == THX_OK) {
        fputs(text, af.f);
        fputc('\n', af.f);
        st = thx_atomic_commit(ctx, &af);
    }
    free(text);
    return st;
}
