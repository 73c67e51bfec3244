/* thorax forward --dipoles: the potentials of current dipole sources (thx_forward_dipoles). */
#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/io/dipoles_file.h"
#include "thorax/leads/leads.h"
#include "thorax/fem/fem.h"
#include "thorax/core/fileio.h"

int cli_forward_dipoles(const char *model_dir, const char *out, const char *dip_path, int method, const char *rows_path,
                        double max_offset, const char *format, int want_volume, int warm, cli_petsc_args *pa, int verbose,
                        int force)
{
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_dipoles *d = NULL;
    thx_electrodes *rowset = NULL;
    thx_series *at_electrodes = NULL;
    thx_forward_result R;
    memset(&R, 0, sizeof R);
    cJSON *vcheck = NULL, *warnings = NULL;
    thx_outdir od;
    memset(&od, 0, sizeof od);
    int rank = 0, rc = 0;
    double t0 = thx_wtime();
    thx_series_format fmt = THX_SERIES_RAW;
    thx_series_format_parse(format, &fmt);
    const char *ext = fmt == THX_SERIES_TEXT ? "txt" : fmt == THX_SERIES_MAT ? "mat" : "raw";
    /* the output directory first: refused before any work if it is not thorax's own solution */
    const char *inputs[] = {model_dir, dip_path, rows_path};
    thx_status st = thx_outdir_claim(ctx, &od, out, "solution.json", "thorax-solution", inputs, rows_path ? 3 : 2);
    if (st == THX_OK) st = thx_model_read(ctx, model_dir, &m);
    if (st == THX_OK) st = thx_dipoles_read(ctx, dip_path, &d);
    if (st == THX_OK && rows_path) {
        double moved = 0;
        st = thx_electrodes_load(ctx, rows_path, m, NULL, max_offset, &rowset, NULL, &moved);
        if (st == THX_OK && moved > 0)
            thx_log(ctx, THX_LOG_INFO, "%s: electrodes moved onto the surface by up to %.3g mm", rows_path, moved);
    }
    if (st == THX_OK) st = cli_petsc_init(ctx, pa, &rank);
    if (st == THX_OK) st = cli_volume_gate(ctx, "forward", model_dir, m, force, rank, &vcheck, &warnings);
    thx_forward_opts fo;
    thx_forward_opts_default(&fo);
    fo.warm = warm;
    fo.keep_volume = want_volume;
    fo.dipole_method = method;
    if (rank == 0 && isatty(2) && verbose >= 0) { fo.progress = cli_progress; fo.user = (void *)"forward"; }
    if (st == THX_OK) st = thx_forward_dipoles(ctx, m, d, &fo, &R);
    if (st == THX_OK && rowset && rank == 0) st = thx_electrodes_sample(ctx, rowset, R.torso, &at_electrodes);
    if (st == THX_OK && at_electrodes) {
        snprintf(at_electrodes->unit, sizeof at_electrodes->unit, "mV");
        snprintf(at_electrodes->time_unit, sizeof at_electrodes->time_unit, "%s", R.torso->time_unit);
        snprintf(at_electrodes->label, sizeof at_electrodes->label, "potentials at the electrodes (dipole sources)");
    }
    if (st != THX_OK) goto fail;
    if (rank == 0) {
        char path[4400], abs[PATH_MAX];
        st = thx_outdir_begin(ctx, &od);
        if (st != THX_OK) goto fail;
        cJSON *j = cJSON_CreateObject(), *files = cJSON_CreateObject(), *solver = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "format", "thorax-solution");
        cJSON_AddNumberToObject(j, "version", 1);
        cJSON_AddStringToObject(j, "model", realpath(model_dir, abs) ? abs : model_dir);
        cJSON_AddStringToObject(j, "problem", "dipoles");
        cJSON_AddStringToObject(j, "command", cli_command_line());
        cJSON_AddStringToObject(j, "dipoles", realpath(dip_path, abs) ? abs : dip_path);
        cJSON_AddNumberToObject(j, "dipole_count", (double)d->n);
        cJSON_AddNumberToObject(j, "frames", (double)d->n_frames);
        cJSON_AddStringToObject(j, "layout", d->separate ? "one frame per dipole (OpenMEEG .dip)" : "moments over time");
        cJSON_AddStringToObject(j, "method", method == THX_DIPOLE_PARTIAL ? "partial integration" : "Saint-Venant");
        if (method != THX_DIPOLE_PARTIAL)
            cJSON_AddNumberToObject(j, "partial_integration_fallbacks", (double)R.n_fallback);
        /* dipoles the walk through the mesh could not place, found by scanning every tetrahedron */
        cJSON_AddNumberToObject(j, "dipoles_located_by_scan", (double)R.n_located_by_scan);
        cJSON_AddStringToObject(j, "reference", "zero integral over the outer surface");
        cJSON_AddStringToObject(j, "unit", "mV");
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (m->surf[s]->role == THX_ROLE_OUTER) cJSON_AddStringToObject(j, "surface", m->surf[s]->name);
        struct { const char *key; thx_series *s; } w[] = {{"torso", R.torso}, {"electrodes", at_electrodes}, {"volume", R.volume}};
        for (size_t k = 0; k < sizeof w / sizeof w[0] && st == THX_OK; k++) {
            if (!w[k].s) continue;
            snprintf(path, sizeof path, "%s/%s.%s", od.tmp, w[k].key, ext);
            st = thx_series_write(ctx, w[k].s, path, fmt);
            char name[64];
            snprintf(name, sizeof name, "%s.%s", w[k].key, ext);
            cJSON_AddStringToObject(files, w[k].key, name);
        }
        if (rowset) cJSON_AddStringToObject(j, "rows", realpath(rows_path, abs) ? abs : rows_path);
        cJSON_AddItemToObject(j, "files", files);
        if (vcheck) { cJSON_AddItemToObject(j, "volume_check", vcheck); vcheck = NULL; }
        if (warnings) { cJSON_AddItemToObject(j, "warnings", warnings); warnings = NULL; }
        cJSON_AddStringToObject(solver, "ksp", R.ksp);
        cJSON_AddStringToObject(solver, "pc", R.pc);
        cJSON_AddNumberToObject(solver, "ranks", R.ranks);
        cJSON_AddNumberToObject(solver, "free_nodes", (double)R.n_free);
        cJSON_AddNumberToObject(solver, "block", (double)R.block); /* right-hand sides per solve (1: one by one) */
        cJSON_AddNumberToObject(solver, "iterations_min", R.it_min);
        cJSON_AddNumberToObject(solver, "iterations_max", R.it_max);
        cJSON_AddNumberToObject(solver, "iterations_total", (double)R.it_total);
        cJSON_AddNumberToObject(solver, "max_relative_residual", R.max_residual);
        cJSON_AddNumberToObject(solver, "seconds_assembly", R.t_assemble);
        cJSON_AddBoolToObject(solver, "assembly_kept", R.assembly.kept);
        if (R.assembly.note[0]) cJSON_AddStringToObject(solver, "assembly_note", R.assembly.note);
        cJSON_AddNumberToObject(solver, "seconds_setup", R.t_setup);
        cJSON_AddNumberToObject(solver, "seconds_solve", R.t_solve);
        cJSON_AddNumberToObject(solver, "seconds_total", thx_wtime() - t0);
        cJSON_AddItemToObject(j, "solver", solver);
        st = cli_outdir_finish(ctx, &od, "solution.json", j, st);
        if (st != THX_OK) goto fail;
        if (verbose >= 0) {
            printf("%zu dipole%s, %zu frame%s: %zu free nodes; %s + %s on %d rank%s, blocks of %zu, %d..%d iterations per "
                   "solve; assembly %.2f s%s, setup %.2f s, solves %.2f s\n",
                   d->n, d->n > 1 ? "s" : "", d->n_frames, d->n_frames > 1 ? "s" : "", R.n_free, R.ksp, R.pc, R.ranks,
                   R.ranks > 1 ? "s" : "", R.block, R.it_min, R.it_max, R.t_assemble, R.assembly.kept ? " (kept)" : "", R.t_setup, R.t_solve);
            printf("wrote %s\n", out);
        }
    }
    goto end;
fail:
    rc = cli_fail(ctx, "forward", st);
end:
    cJSON_Delete(vcheck);
    cJSON_Delete(warnings);
    thx_series_destroy(&at_electrodes);
    thx_electrodes_destroy(&rowset);
    thx_dipoles_destroy(&d);
    thx_forward_result_free(&R);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    cli_petsc_finish(pa);
    return rc;
}
