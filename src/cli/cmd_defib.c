/* thorax forward --electrode: the defibrillation problem (paper 4.1). */
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include "thorax/fem/fem.h"
#include "thorax/core/fileio.h"
/* NAME,surface=S,at=X:Y:Z,radius=R,voltage=V | current=I | nodes=FILE (an electrode file) */
static thx_status parse_spec(thx_ctx *ctx, const thx_model *m, const char *spec, thx_patch *p)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", spec);
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    memset(p, 0, sizeof *p);
    if (!tok || strchr(tok, '=')) return thx_error(ctx, THX_EINPUT, "--electrode '%s': starts with a name (NAME,surface=...)", spec);
    snprintf(p->name, sizeof p->name, "%s", tok);
    const char *surface = NULL, *nodes = NULL;
    double at[3] = {0, 0, 0}, radius = 0;
    int have_at = 0, have_value = 0;
    char surfname[64] = "";
    while ((tok = strtok_r(NULL, ",", &save))) {
        char *eq = strchr(tok, '=');
        if (!eq) return thx_error(ctx, THX_EINPUT, "electrode '%s': '%s' is not KEY=VALUE", p->name, tok);
        *eq = '\0';
        const char *k = tok, *val = eq + 1;
        char *end;
        if (!strcmp(k, "surface")) { snprintf(surfname, sizeof surfname, "%s", val); surface = surfname; }
        else if (!strcmp(k, "at")) {
            if (sscanf(val, "%lf:%lf:%lf", &at[0], &at[1], &at[2]) != 3)
                return thx_error(ctx, THX_EINPUT, "electrode '%s': at=X:Y:Z (mm), not '%s'", p->name, val);
            have_at = 1;
        } else if (!strcmp(k, "radius")) {
            radius = strtod(val, &end);
            if (*end || !(radius > 0)) return thx_error(ctx, THX_EINPUT, "electrode '%s': radius must be a positive number of mm", p->name);
        } else if (!strcmp(k, "voltage") || !strcmp(k, "current")) {
            p->value = strtod(val, &end);
            if (*end || !isfinite(p->value)) return thx_error(ctx, THX_EINPUT, "electrode '%s': %s=%s is not a number", p->name, k, val);
            p->is_voltage = k[0] == 'v';
            have_value++;
        } else if (!strcmp(k, "nodes")) nodes = val;
        else return thx_error(ctx, THX_EINPUT, "electrode '%s': unknown key '%s' (surface, at, radius, voltage, current, nodes)", p->name, k);
    }
    if (have_value != 1) return thx_error(ctx, THX_EINPUT, "electrode '%s': give exactly one of voltage=V, current=I", p->name);
    thx_electrodes *e = NULL;
    if (nodes) {
        THX_CHECK(thx_electrodes_read(ctx, nodes, &e));
        if (!surface) surface = e->surface;
    }
    size_t s = m->n_surfaces;
    for (size_t k = 0; k < m->n_surfaces; k++)
        if (surface ? !strcmp(m->surf[k]->name, surface) : m->surf[k]->role == THX_ROLE_OUTER) s = k;
    thx_status st = THX_OK;
    if (s == m->n_surfaces) st = thx_error(ctx, THX_EINPUT, "electrode '%s': the model has no surface '%s'", p->name, surface ? surface : "(outer)");
    else if (nodes) {
        st = thx_electrodes_check(ctx, e, m);
        for (size_t i = 0; st == THX_OK && i < e->n; i++)
            if (e->node[i] < 0) /* a patch is a set of nodes */
                st = thx_error(ctx, THX_EINPUT, "electrode '%s': %s: electrode %zu (\"%s\") is not on a node ('-')", p->name,
                               nodes, i + 1, e->name[i]);
        if (st == THX_OK) st = thx_patch_nodes(ctx, m, s, e->node, e->n, p);
    } else if (!have_at || !(radius > 0))
        st = thx_error(ctx, THX_EINPUT, "electrode '%s': give at=X:Y:Z and radius=R, or nodes=FILE", p->name);
    else st = thx_patch_disc(ctx, m, s, at, radius, p);
    thx_electrodes_destroy(&e);
    return st;
}

int cli_forward_defib(const char *model_dir, const char *out, const char **specs, int n_specs, double threshold,
                      const char *format, cli_petsc_args *pa, int verbose, int force)
{
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_patch p[16];
    memset(p, 0, sizeof p);
    double *phi = NULL, *field = NULL;
    thx_series *vol = NULL, *torso = NULL, *fld = NULL;
    thx_defib_report R;
    cJSON *vcheck = NULL, *warnings = NULL;
    thx_outdir od;
    memset(&od, 0, sizeof od);
    int rank = 0, rc = 0;
    thx_series_format fmt = THX_SERIES_RAW;
    thx_series_format_parse(format, &fmt);
    const char *ext = fmt == THX_SERIES_TEXT ? "txt" : fmt == THX_SERIES_MAT ? "mat" : "raw";
    /* the output directory first: refused before any work if it is not thorax's own solution */
    const char *inputs[] = {model_dir};
    thx_status st = thx_outdir_claim(ctx, &od, out, "solution.json", "thorax-solution", inputs, 1);
    if (st == THX_OK) st = thx_model_read(ctx, model_dir, &m);
    for (int k = 0; k < n_specs && st == THX_OK; k++) st = parse_spec(ctx, m, specs[k], &p[k]);
    if (st == THX_OK) st = cli_petsc_init(ctx, pa, &rank);
    if (st == THX_OK) st = cli_volume_gate(ctx, "forward", model_dir, m, force, rank, &vcheck, &warnings);
    if (st == THX_OK) st = thx_defib_solve(ctx, m, p, (size_t)n_specs, threshold, &phi, &field, &R);
    if (st != THX_OK) goto fail;
    const thx_volume *v = m->volume;
    size_t outer = 0;
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == THX_ROLE_OUTER) outer = s;
    if (thx_series_create(ctx, v->n_nodes, 1, &vol) || thx_series_create(ctx, m->surf[outer]->n_nodes, 1, &torso) ||
        thx_series_create(ctx, v->n_tets, 1, &fld)) { st = THX_ENOMEM; goto fail; }
    memcpy(vol->v, phi, v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < m->surf[outer]->n_nodes; i++) torso->v[i] = phi[v->surf_node[outer][i]];
    memcpy(fld->v, field, v->n_tets * sizeof *field);
    snprintf(vol->unit, sizeof vol->unit, "V");
    snprintf(torso->unit, sizeof torso->unit, "V");
    snprintf(fld->unit, sizeof fld->unit, "V/cm");
    snprintf(vol->label, sizeof vol->label, "defibrillation: potential at the volume nodes");
    snprintf(torso->label, sizeof torso->label, "defibrillation: potential on the outer surface");
    snprintf(fld->label, sizeof fld->label, "defibrillation: field magnitude |E| per tetrahedron");
    if (rank == 0) {
        char path[4400];
        st = thx_outdir_begin(ctx, &od);
        if (st != THX_OK) goto fail;
        struct { const char *key; thx_series *s; } w[] = {{"volume", vol}, {"torso", torso}, {"field_tet", fld}};
        cJSON *j = cJSON_CreateObject(), *files = cJSON_CreateObject(), *el = cJSON_CreateArray(), *heart = cJSON_CreateObject();
        for (size_t k = 0; k < 3 && st == THX_OK; k++) {
            snprintf(path, sizeof path, "%s/%s.%s", od.tmp, w[k].key, ext);
            st = thx_series_write(ctx, w[k].s, path, fmt);
            char name[64];
            snprintf(name, sizeof name, "%s.%s", w[k].key, ext);
            cJSON_AddStringToObject(files, w[k].key, name);
        }
        cJSON_AddStringToObject(j, "format", "thorax-solution");
        cJSON_AddNumberToObject(j, "version", 1);
        char abs[PATH_MAX];
        cJSON_AddStringToObject(j, "model", realpath(model_dir, abs) ? abs : model_dir);
        cJSON_AddStringToObject(j, "problem", "defibrillation");
        cJSON_AddStringToObject(j, "command", cli_command_line());
        cJSON_AddItemToObject(j, "files", files);
        for (int k = 0; k < n_specs; k++) {
            cJSON *e = cJSON_CreateObject();
            cJSON_AddStringToObject(e, "name", p[k].name);
            cJSON_AddStringToObject(e, "kind", p[k].is_voltage ? "voltage" : "current");
            cJSON_AddNumberToObject(e, p[k].is_voltage ? "voltage_V" : "current_A", p[k].value);
            cJSON_AddNumberToObject(e, "nodes", (double)p[k].n);
            cJSON_AddNumberToObject(e, "area_mm2", p[k].area);
            cJSON_AddNumberToObject(e, "current_A", R.current[k]);
            cJSON_AddNumberToObject(e, "mean_potential_V", R.voltage[k]);
            cJSON_AddItemToArray(el, e);
        }
        cJSON_AddItemToObject(j, "electrodes", el);
        cJSON_AddNumberToObject(heart, "volume_mm3", R.heart_volume);
        cJSON_AddNumberToObject(heart, "threshold_V_per_cm", R.threshold);
        cJSON_AddNumberToObject(heart, "fraction_above_threshold", R.frac_above);
        cJSON_AddNumberToObject(heart, "field_min_V_per_cm", R.e_min);
        cJSON_AddNumberToObject(heart, "field_mean_V_per_cm", R.e_mean);
        cJSON_AddNumberToObject(heart, "field_max_V_per_cm", R.e_max);
        cJSON_AddNumberToObject(heart, "current_density_min_A_per_m2", R.j_min);
        cJSON_AddNumberToObject(heart, "current_density_mean_A_per_m2", R.j_mean);
        cJSON_AddNumberToObject(heart, "current_density_max_A_per_m2", R.j_max);
        cJSON_AddNumberToObject(heart, "potential_min_V", R.phi_min);
        cJSON_AddNumberToObject(heart, "potential_max_V", R.phi_max);
        cJSON_AddItemToObject(j, "heart", heart);
        cJSON *solver = cJSON_CreateObject();
        cJSON_AddStringToObject(solver, "ksp", R.ksp);
        cJSON_AddStringToObject(solver, "pc", R.pc);
        cJSON_AddNumberToObject(solver, "ranks", R.ranks);
        cJSON_AddNumberToObject(solver, "iterations", R.iterations);
        cJSON_AddNumberToObject(solver, "relative_residual", R.residual);
        cJSON_AddNumberToObject(solver, "seconds_assembly", R.t_assemble);
        cJSON_AddBoolToObject(solver, "assembly_kept", R.assembly.kept);
        if (R.assembly.note[0]) cJSON_AddStringToObject(solver, "assembly_note", R.assembly.note);
        cJSON_AddNumberToObject(solver, "seconds_setup", R.t_setup);
        cJSON_AddNumberToObject(solver, "seconds_solve", R.t_solve);
        cJSON_AddItemToObject(j, "solver", solver);
        if (vcheck) {
            cJSON_AddItemToObject(j, "volume_check", vcheck);
            vcheck = NULL;
        }
        if (warnings) {
            cJSON_AddItemToObject(j, "warnings", warnings);
            warnings = NULL;
        }
        st = cli_outdir_finish(ctx, &od, "solution.json", j, st);
        if (st != THX_OK) goto fail;
        if (verbose >= 0) {
            for (int k = 0; k < n_specs; k++)
                printf("electrode %-10s %4zu nodes, %7.0f mm^2: %s %g %s; current %+.4f A, mean potential %+.3f V\n", p[k].name,
                       p[k].n, p[k].area, p[k].is_voltage ? "voltage" : "current", p[k].value, p[k].is_voltage ? "V" : "A",
                       R.current[k], R.voltage[k]);
            printf("heart: %.0f mm^3, field %.2f .. %.2f V/cm (mean %.2f), current density %.1f .. %.1f A/m^2 (mean %.1f), "
                   "potential %.2f .. %.2f V; %.1f%% of the volume above %g V/cm\n",
                   R.heart_volume, R.e_min, R.e_max, R.e_mean, R.j_min, R.j_max, R.j_mean, R.phi_min, R.phi_max,
                   100 * R.frac_above, R.threshold);
            printf("solver: %s + %s, %d iterations, assembly %.2f s%s, setup %.2f s, solve %.2f s\nwrote %s\n", R.ksp, R.pc,
                   R.iterations, R.t_assemble, R.assembly.kept ? " (kept)" : "", R.t_setup, R.t_solve, out);
        }
    }
    goto end;
fail:
    rc = cli_fail(ctx, "forward", st);
end:
    cJSON_Delete(vcheck);
    cJSON_Delete(warnings);
    for (int k = 0; k < 16; k++) thx_patch_free(&p[k]);
    free(phi);
    free(field);
    thx_series_destroy(&vol);
    thx_series_destroy(&torso);
    thx_series_destroy(&fld);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
