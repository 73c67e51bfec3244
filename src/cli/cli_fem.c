/* PETSc option pass-through and progress display for the solving commands. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli/cli_fem.h"
#include "thorax/check/check_volume.h"
#include "thorax/check/verdict.h"
#include "thorax/core/fileio.h"
#include "thorax/fem/fem.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
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

int cli_petsc_pass(void *user, char **argv, int argc, int i)
{
    return cli_petsc_args_add(user, argv[i], i + 1 < argc ? argv[i + 1] : NULL);
}

thx_status cli_petsc_init(thx_ctx *ctx, cli_petsc_args *pa, int *rank)
{
    pa->argv[pa->argc] = NULL;
    thx_status st = thx_fem_available(ctx);
    if (st != THX_OK) return st;
    st = thx_fem_init(pa->argc, pa->argv, rank, NULL);
    if (st != THX_OK) return thx_error(ctx, THX_ESOLVER, "PETSc could not be initialized (PetscInitialize failed)");
    pa->inited = 1;
    return THX_OK;
}

void cli_petsc_finish(cli_petsc_args *pa)
{
    if (!pa->inited) return;
    int left = thx_fem_options_unused(0);
    if (left > 0) {
        int rank = 0;
        thx_fem_init(0, NULL, &rank, NULL);
        if (rank == 0) fprintf(stderr, "thorax: warning: %d PETSc option%s given but not used:\n", left, left > 1 ? "s" : "");
        thx_fem_options_unused(1);
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

/* The verdict looked at beside the model's reading (cli_volume_gate_prefetch). */
static struct {
    pthread_t thread;
    int started, joined;
    char dir[4096];
    int trusted;
    char why[512];
    double seconds;
} g_verdict;

static void *verdict_job(void *unused)
{
    (void)unused;
    thx_ctx *c = NULL;
    double t0 = thx_wtime();
    g_verdict.trusted = 0;
    snprintf(g_verdict.why, sizeof g_verdict.why, "out of memory");
    if (thx_ctx_create(&c) == THX_OK) {
        g_verdict.trusted = thx_volume_verdict_trusted(c, g_verdict.dir, g_verdict.why, sizeof g_verdict.why);
        thx_ctx_destroy(&c);
    }
    g_verdict.seconds = thx_wtime() - t0;
    return NULL;
}

void cli_volume_gate_prefetch(const char *model_dir)
{
    if (g_verdict.started || snprintf(g_verdict.dir, sizeof g_verdict.dir, "%s", model_dir) >= (int)sizeof g_verdict.dir)
        return;
    g_verdict.started = pthread_create(&g_verdict.thread, NULL, verdict_job, NULL) == 0;
    g_verdict.joined = 0;
}

void cli_volume_gate_end(void)
{
    if (g_verdict.started && !g_verdict.joined) pthread_join(g_verdict.thread, NULL);
    g_verdict.joined = 1;
}

/* 1 when the kept verdict is trusted: the prefetched answer for this directory, else looked at now. */
static int verdict_trusted(thx_ctx *ctx, const char *model_dir, char *why, size_t why_n, double *seconds)
{
    if (g_verdict.started && !strcmp(g_verdict.dir, model_dir)) {
        double t0 = thx_wtime();
        cli_volume_gate_end();
        g_verdict.started = 0;
        snprintf(why, why_n, "%s", g_verdict.why);
        *seconds = g_verdict.seconds;
        if (thx_wtime() - t0 >= 0.005)
            thx_log(ctx, THX_LOG_DEBUG, "volume check's verdict: waited %.2f s for it", thx_wtime() - t0);
        return g_verdict.trusted;
    }
    double t0 = thx_wtime();
    int ok = thx_volume_verdict_trusted(ctx, model_dir, why, why_n);
    *seconds = thx_wtime() - t0;
    return ok;
}

thx_status cli_volume_gate(thx_ctx *ctx, const char *cmd, const char *model_dir, const thx_model *m, int force,
                           int rank, cJSON **note, cJSON **warning)
{
    if (note) *note = NULL;
    if (warning) *warning = NULL;
    /* no volume: the solver says so in its own words */
    if (!m->volume || !m->volume->n_tets) return THX_OK;
    double t0 = thx_wtime();
    /* a verdict `thorax mesh` kept for exactly these files (thorax/check/verdict.h): the check is not run again */
    char why[512];
    double hashed = 0;
    if (verdict_trusted(ctx, model_dir, why, sizeof why, &hashed)) {
        if (rank == 0) /* (rank 0 speaks for all) */
            thx_log(ctx, THX_LOG_DEBUG, "volume check (%zu tetrahedra): passed, the verdict kept in model.json (its files "
                    "unchanged: SHA-256 in %.2f s)", m->volume->n_tets, hashed);
        if (note) {
            cJSON *j = cJSON_CreateObject();
            if (!j || !cJSON_AddArrayToObject(j, "failures") || !cJSON_AddArrayToObject(j, "reasons") ||
                !cJSON_AddBoolToObject(j, "ok", 1) || !cJSON_AddBoolToObject(j, "forced", 0) ||
                !cJSON_AddStringToObject(j, "verdict", "kept in model.json (thorax mesh's check; the files unchanged since)")) {
                cJSON_Delete(j);
                return thx_error(ctx, THX_ENOMEM, "out of memory recording the volume check");
            }
            *note = j;
        }
        return THX_OK;
    }
    if (rank == 0) thx_log(ctx, THX_LOG_DEBUG, "volume check: %s: checking", why);
    thx_volume_report r;
    thx_status st = thx_volume_check(ctx, m->volume, m, NULL, &r);
    if (st != THX_OK && st != THX_ECHECK) {
        thx_volume_report_free(&r);
        return st;
    }
    thx_ctx_clear(ctx);
    thx_log(ctx, THX_LOG_DEBUG, "volume check (%zu tetrahedra): %s in %.2f s", m->volume->n_tets,
            r.ok ? "passed" : "failed", thx_wtime() - t0);
    char names[256] = "";
    for (unsigned b = 0; b < THX_VCHECK_N_FAILURES; b++)
        if (r.failures & (1u << b)) {
            size_t n = strlen(names);
            snprintf(names + n, sizeof names - n, "%s%s", n ? ", " : "",
                     thx_volume_check_failure_name((thx_volume_check_failure)(1u << b)));
        }
    cJSON *j = NULL, *w = NULL;
    if (note) {
        j = cJSON_CreateObject();
        cJSON *fl = cJSON_AddArrayToObject(j, "failures"), *rs = cJSON_AddArrayToObject(j, "reasons");
        cJSON_AddBoolToObject(j, "ok", r.ok);
        cJSON_AddBoolToObject(j, "forced", !r.ok && force);
        for (unsigned b = 0; b < THX_VCHECK_N_FAILURES && fl; b++)
            if (r.failures & (1u << b))
                cJSON_AddItemToArray(fl, cJSON_CreateString(thx_volume_check_failure_name((thx_volume_check_failure)(1u << b))));
        for (size_t k = 0; k < r.n_reasons && rs; k++) cJSON_AddItemToArray(rs, cJSON_CreateString(r.reasons[k]));
        if (!j || !fl || !rs) {
            cJSON_Delete(j);
            thx_volume_report_free(&r);
            return thx_error(ctx, THX_ENOMEM, "out of memory recording the volume check");
        }
    }
    if (!r.ok && force && warning) {
        w = cJSON_CreateArray();
        char head[512];
        snprintf(head, sizeof head, "the volume mesh fails thorax check (%s); solved anyway (--force)", names);
        cJSON_AddItemToArray(w, cJSON_CreateString(head));
        for (size_t k = 0; k < r.n_reasons; k++) cJSON_AddItemToArray(w, cJSON_CreateString(r.reasons[k]));
    }
    if (!r.ok && rank == 0) {
        for (size_t k = 0; k < r.n_reasons; k++)
            fprintf(stderr, "thorax %s: %s: volume: %s\n", cmd, model_dir, r.reasons[k]);
        /* printed even with -q, as the reasons are: the solution is on a volume known to be wrong */
        if (force)
            fprintf(stderr, "thorax %s: warning: %s: the volume mesh fails thorax check (%s); solving anyway (--force)\n",
                    cmd, model_dir, names);
    }
    if (!r.ok && !force)
        st = thx_error(ctx, THX_ECHECK,
                       "%s: the volume mesh fails thorax check (%s): %s; not solved (--force solves anyway)", model_dir,
                       names, r.reasons[0]);
    else
        st = THX_OK;
    thx_volume_report_free(&r);
    if (note) *note = j;
    if (warning) *warning = w;
    return st;
}

thx_status cli_outdir_finish(thx_ctx *ctx, thx_outdir *od, const char *name, cJSON *j, thx_status st)
{
    if (st == THX_OK) {
        char path[sizeof od->tmp + 256];
        snprintf(path, sizeof path, "%s/%s", od->tmp, name);
        st = cli_write_json(ctx, path, j);
    } else {
        cJSON_Delete(j);
    }
    if (st == THX_OK) st = thx_outdir_commit(ctx, od);
    if (st != THX_OK) thx_outdir_abort(od);
    return st;
}
