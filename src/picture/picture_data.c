/*
 * A picture's data (thorax/picture/picture.h): the model or the surface files, a solution's
 * series, the data sets given, recording channels, the trace, the currents, landmarks and
 * activation maps — read once, checked against the model, owned by thx_picture_data.
 */
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "thorax/core/fileio.h"
#include "thorax/import/import.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/io/channels_file.h"
#include "thorax/leads/bad_leads.h"
#include "thorax/geom/landmark_mesh.h"
#include "thorax/geom/pick.h"
#include "thorax/io/landmarks_file.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/activation.h"
#include "picture/picture_internal.h"
#include "picture/scan.h"

static thx_status electrode_marks(thx_ctx *ctx, const char *path, thx_picture_data *d);

void thx_picture_data_free(thx_picture_data *d)
{
    thx_tracer_destroy(&d->tracer);
    thx_raster_destroy(&d->rt_env);
    free(d->vr_tet);
    free(d->vr_cell);
    d->vr_tet = NULL;
    d->vr_cell = NULL;
    for (int s = 0; s < THX_PICTURE_SURFACES; s++) {
        int owned = 0;
        for (int k = 0; k < d->n_sets[s]; k++) {
            owned |= d->sets[s][k] == d->series[s];
            thx_series_destroy(&d->sets[s][k]);
        }
        if (!owned) thx_series_destroy(&d->series[s]);
        d->series[s] = NULL;
        d->n_sets[s] = 0;
        free(d->channel[s]);
        d->channel[s] = NULL;
    }
    thx_pick_index_destroy(&d->pick);
    for (int k = 0; k < d->n_marks; k++) thx_landmark_meshes_destroy(&d->marks[k]);
    d->n_marks = 0;
    for (int k = 0; k < d->n_elec; k++) thx_electrodes_destroy(&d->elec[k]);
    d->n_elec = 0;
    for (int k = 0; k < d->n_tets; k++) thx_surface_destroy(&d->tets[k]);
    d->n_tets = 0;
    thx_series_destroy(&d->ecg);
    thx_series_destroy(&d->currents);
    thx_series_destroy(&d->volume);
    picture_field_free(d);
    picture_scan_free(d);
    free(d->field_use);
    d->field_use = NULL;
    free(d->part_own);
    d->part_own = NULL;
    free(d->part_node), free(d->part_tet_id), free(d->part_owner);
    d->part_node = d->part_tet_id = d->part_owner = NULL;
    free(d->part_cuts);
    d->part_cuts = NULL;
    thx_model_destroy(&d->m);
}

static int surface_by_role(const thx_model *m, thx_role role)
{
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == role) return (int)s;
    return -1;
}

static int surface_by_name(const thx_model *m, const char *name)
{
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (!strcmp(m->surf[s]->name, name)) return (int)s;
    return -1;
}

static const char *lead_names[12] = {"I", "II", "III", "aVR", "aVL", "aVF", "V1", "V2", "V3", "V4", "V5", "V6"};

static int lead_index(const char *name)
{
    for (int k = 0; k < 12; k++)
        if (!strcmp(name, lead_names[k])) return k;
    return -1;
}

/* Every surface named by --only and --surface exists in the model. */
static thx_status check_names(thx_ctx *ctx, const thx_picture_opts *o, const thx_model *m)
{
    char list[512] = "";
    size_t len = 0;
    for (size_t s = 0; s < m->n_surfaces && len < sizeof list - 80; s++)
        len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", s ? ", " : "", m->surf[s]->name);
    if (o->isosurface) len += (size_t)snprintf(list + len, sizeof list - len, ", equipotentials");
    if (o->n_slices && len < sizeof list - 20) len += (size_t)snprintf(list + len, sizeof list - len, ", slices");
    if (o->n_streamlines && len < sizeof list - 20) len += (size_t)snprintf(list + len, sizeof list - len, ", streamlines");
    for (int k = 0; k < o->n_only + o->n_look + o->n_whole; k++) {
        const char *name = k < o->n_only ? o->only[k] : k < o->n_only + o->n_look ? o->look[k - o->n_only].name
                                                                                   : o->whole[k - o->n_only - o->n_look];
        if ((o->isosurface && !strcmp(name, "equipotentials")) || (o->n_slices && !strcmp(name, "slices")) ||
            (o->n_streamlines && !strcmp(name, "streamlines")))
            continue; /* the volume's cuts (field_layers.c) */
        if (surface_by_name(m, name) < 0)
            return thx_error(ctx, THX_EINPUT, "%s: the model has no surface '%s' (it has %s)",
                             k < o->n_only ? "--only" : k < o->n_only + o->n_look ? "--surface" : "--no-clip", name, list);
    }
    /* the surfaces of --scale-group A,B and --slave A=B */
    for (int k = 0; k < o->n_groups + o->n_slaves; k++) {
        const char *spec = k < o->n_groups ? o->groups[k] : o->slaves[k - o->n_groups];
        const char *what = k < o->n_groups ? "--scale-group" : "--slave";
        if (k >= o->n_groups && (!strchr(spec, '=') || strchr(spec, '=') == spec))
            return thx_error(ctx, THX_EINPUT, "--slave '%s': give NAME=MASTER", spec);
        for (const char *p = spec; *p;) {
            const char *c = p + strcspn(p, ",=");
            char name[64];
            snprintf(name, sizeof name, "%.*s", (int)(c - p < 63 ? c - p : 63), p);
            if (surface_by_name(m, name) < 0)
                return thx_error(ctx, THX_EINPUT, "%s '%s': the model has no surface '%s' (it has %s)", what, spec, name, list);
            p = *c ? c + 1 : c;
        }
    }
    return THX_OK;
}

/* --trace: a lead of the solution's 12-lead ECG (I .. V6), or SURFACE:NODE / NODE (1-based) of a
   surface's data (without a surface name: the body surface's data, else the only data there is). */
static thx_status resolve_trace(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d)
{
    if (!o->trace) return THX_OK;
    int lead = lead_index(o->trace);
    if (lead >= 0) {
        if (!d->ecg)
            return thx_error(ctx, THX_EINPUT, "--trace %s: a lead needs --solution DIR with an ecg12 file (run thorax leads)", o->trace);
        if ((size_t)lead >= d->ecg->n_rows)
            return thx_error(ctx, THX_EINPUT, "--trace %s: the ECG file has %zu rows", o->trace, d->ecg->n_rows);
        d->trace = d->ecg;
        d->trace_row = (size_t)lead;
        snprintf(d->trace_label, sizeof d->trace_label, "%s", o->trace);
        return THX_OK;
    }
    char name[64] = "";
    const char *num = o->trace, *colon = strrchr(o->trace, ':');
    if (colon) {
        snprintf(name, sizeof name, "%.*s", (int)(colon - o->trace < 63 ? colon - o->trace : 63), o->trace);
        num = colon + 1;
    }
    char *end = NULL;
    long node = strtol(num, &end, 10);
    if (!*num || *end || node < 1)
        return thx_error(ctx, THX_EINPUT, "--trace '%s': give a lead (I, II, III, aVR, aVL, aVF, V1..V6) or SURFACE:NODE (1-based)", o->trace);
    int s = -1;
    if (name[0]) {
        s = surface_by_name(d->m, name);
        if (s < 0) return thx_error(ctx, THX_EINPUT, "--trace '%s': the model has no surface '%s'", o->trace, name);
    } else {
        for (size_t k = 0; k < d->m->n_surfaces && k < THX_PICTURE_SURFACES; k++)
            if (d->series[k] && (s < 0 || d->m->surf[k]->role == THX_ROLE_OUTER)) s = (int)k;
        if (s < 0) return thx_error(ctx, THX_EINPUT, "--trace '%s': there are no data to trace (give --solution or --data)", o->trace);
    }
    const thx_series *x = d->series[s];
    if (!x) return thx_error(ctx, THX_EINPUT, "--trace '%s': surface '%s' has no data", o->trace, d->m->surf[s]->name);
    if ((size_t)node > x->n_rows)
        return thx_error(ctx, THX_EINPUT, "--trace '%s': surface '%s' has %zu nodes", o->trace, d->m->surf[s]->name, x->n_rows);
    d->trace = x;
    d->trace_row = (size_t)node - 1;
    snprintf(d->trace_label, sizeof d->trace_label, "%s node %ld", d->m->surf[s]->name, node);
    return THX_OK;
}

/* A model of the surface files given instead of a model directory, read as `thorax import` reads
 * them but drawn whatever their checks say (a measured sock is an open surface): a failed check
 * is a warning. Each surface is named after its file. */
static thx_status surfaces_from_files(thx_ctx *ctx, const thx_picture_opts *o, thx_model **out)
{
    thx_model *m = NULL;
    THX_CHECK(thx_model_create(ctx, &m));
    thx_status st = THX_OK;
    for (int k = 0; k < o->n_files && st == THX_OK; k++) {
        char name[64];
        const char *base = strrchr(o->files[k], '/');
        base = base ? base + 1 : o->files[k];
        snprintf(name, sizeof name, "%s", base);
        char *dot = strrchr(name, '.');
        const char *at = dot ? strchr(dot, '@') : NULL; /* FILE.geom@2: one surface of several, "FILE_2" */
        char sel[32] = "";
        if (at) snprintf(sel, sizeof sel, "_%s", at + 1);
        if (dot && dot != name) *dot = '\0';
        if (sel[0] && strlen(name) + strlen(sel) < sizeof name) strcat(name, sel);
        thx_import_opts io;
        thx_import_opts_default(&io);
        io.force = 1;
        thx_import_info info;
        memset(&info, 0, sizeof info);
        thx_surface *sf = NULL;
        st = thx_surface_import(ctx, o->files[k], NULL, name, THX_ROLE_OTHER, &io, &sf, &info);
        if (st == THX_OK && !info.report.ok)
            thx_log(ctx, THX_LOG_WARN, "%s: drawn as it is, although %s", o->files[k],
                    info.report.n_reasons ? info.report.reasons[0] : "it fails 'thorax check'");
        thx_import_info_free(&info);
        if (st == THX_OK) st = thx_model_add_surface(ctx, m, &sf);
        thx_surface_destroy(&sf);
    }
    if (st != THX_OK) { thx_model_destroy(&m); return st; }
    *out = m;
    return THX_OK;
}

/* map3d .channels (thorax/io/channels_file.h, the one reader every --channels uses): the series'
 * rows are the recording's channels; the result has one row per node (NaN for a node with no
 * channel), and chan_out the channel of each node (1-based; 0 none) for the node labels. */
static thx_status apply_channels(thx_ctx *ctx, const char *path, thx_series **sp, int **chan_out)
{
    thx_channels *c = NULL;
    thx_series *outs = NULL;
    THX_CHECK(thx_channels_read(ctx, path, &c));
    thx_status st = thx_channels_apply(ctx, c, *sp, &outs);
    int *chan = NULL;
    if (st == THX_OK) {
        chan = calloc(c->n, sizeof *chan);
        if (!chan) st = thx_error(ctx, THX_ENOMEM, "out of memory (%zu channels)", c->n);
        else
            for (size_t i = 0; i < c->n; i++) chan[i] = c->channel[i] + 1;
    }
    /* the recording's fiducials follow (the activation map's window, its per-lead times): a global
       one as it is, a per-channel one to the nodes as the values are (NaN for a node without one) */
    const thx_series *in = *sp;
    if (st == THX_OK && outs->n_fids == 0)
        for (size_t k = 0; k < in->n_fids && st == THX_OK; k++) {
            const thx_fiducial *f = &in->fids[k];
            if (f->n == 1) { st = thx_series_add_fiducial(ctx, outs, f->type, f->fidset, 1, f->v); continue; }
            if (f->n != in->n_rows || outs->n_rows < 2) continue;
            double *v = malloc(outs->n_rows * sizeof *v);
            if (!v) { st = thx_error(ctx, THX_ENOMEM, "out of memory (fiducials)"); break; }
            for (size_t i = 0; i < outs->n_rows; i++)
                v[i] = i < c->n && c->channel[i] >= 0 && (size_t)c->channel[i] < f->n ? f->v[c->channel[i]] : NAN;
            st = thx_series_add_fiducial(ctx, outs, f->type, f->fidset, outs->n_rows, v);
            free(v);
        }
    thx_channels_destroy(&c);
    if (st != THX_OK) { thx_series_destroy(&outs); return st; }
    thx_series_destroy(sp);
    *sp = outs;
    *chan_out = chan;
    return THX_OK;
}

/* The volume potentials of the solution whose solution.json is j (its files.volume) into d->volume,
 * checked against the model's volume mesh; `what` asked for them (an option, in the messages). */
static thx_status read_volume(thx_ctx *ctx, const thx_picture_opts *o, const cJSON *j, const char *what, thx_picture_data *d)
{
    char path[PATH_MAX + 64];
    const cJSON *files = cJSON_GetObjectItem(j, "files"), *vo = files ? cJSON_GetObjectItem(files, "volume") : NULL;
    if (!cJSON_IsString(vo))
        return thx_error(ctx, THX_EINPUT, "%s: %s needs the volume potentials: run thorax forward ... --volume", o->solution, what);
    if (!d->m->volume) return thx_error(ctx, THX_EINPUT, "%s: the model %s has no volume mesh", o->solution, d->model_dir);
    snprintf(path, sizeof path, "%s/%s", o->solution, vo->valuestring);
    THX_CHECK(thx_series_read(ctx, path, THX_SERIES_AUTO, &d->volume));
    if (d->volume->n_rows != d->m->volume->n_nodes)
        return thx_error(ctx, THX_EINPUT, "%s: %zu rows, the model's volume mesh has %zu nodes", path, d->volume->n_rows,
                         d->m->volume->n_nodes);
    return THX_OK;
}

thx_status thx_picture_volume_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const char *what)
{
    if (d->volume) return THX_OK;
    if (!o->solution) return thx_error(ctx, THX_EINPUT, "%s: needs --solution DIR (a solution with volume potentials)", what);
    char path[PATH_MAX + 64], *text = NULL;
    size_t len = 0;
    snprintf(path, sizeof path, "%s/solution.json", o->solution);
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    cJSON *j = cJSON_Parse(text);
    free(text);
    if (!j) return thx_error(ctx, THX_EINPUT, "%s: not a thorax solution", path);
    thx_status st = read_volume(ctx, o, j, what, d);
    cJSON_Delete(j);
    /* the range and the domain the cuts take (picture_field_load), for no cut yet */
    thx_picture_opts none = *o;
    none.isosurface = NULL;
    none.n_slices = none.n_streamlines = 0;
    if (st == THX_OK) st = picture_field_load(ctx, &none, d);
    if (st != THX_OK) {
        thx_series_destroy(&d->volume);
        free(d->field_use);
        d->field_use = NULL;
    }
    return st;
}

/* The solution's 12-lead ECG, the file its manifest names (thorax leads writes it into the
   solution): the binary ecg12_raw, else ecg12_mat, else the text ecg12 (exact numbers first). *out
   NULL when it names none; a file that is not the 12 leads is an error naming it. */
static thx_status solution_ecg12(thx_ctx *ctx, const char *sol, const cJSON *files, thx_series **out)
{
    static const char *const KEYS[3] = {"ecg12_raw", "ecg12_mat", "ecg12"};
    for (int k = 0; k < 3; k++) {
        const cJSON *f = cJSON_GetObjectItemCaseSensitive(files, KEYS[k]);
        if (!cJSON_IsString(f)) continue;
        char path[PATH_MAX + 64];
        snprintf(path, sizeof path, "%s/%s", sol, f->valuestring);
        THX_CHECK(thx_series_read(ctx, path, THX_SERIES_AUTO, out));
        if ((*out)->n_rows != 12) {
            size_t r = (*out)->n_rows;
            thx_series_destroy(out);
            return thx_error(ctx, THX_EINPUT, "%s: %zu rows, not the 12 leads (I, II, III, aVR, aVL, aVF, V1..V6)", path, r);
        }
        return THX_OK;
    }
    return THX_OK;
}

static thx_status load_data(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d)
{
    memset(d, 0, sizeof *d);
    char model_dir[PATH_MAX] = "";
    char path[PATH_MAX + 64];
    cJSON *j = NULL;
    if (o->solution) {
        char *text = NULL;
        size_t len = 0;
        snprintf(path, sizeof path, "%s/solution.json", o->solution);
        THX_CHECK(thx_read_file(ctx, path, &text, &len));
        j = cJSON_Parse(text);
        free(text);
        cJSON *mo = cJSON_GetObjectItem(j, "model");
        if (!j || !cJSON_IsString(mo)) {
            cJSON_Delete(j);
            return thx_error(ctx, THX_EINPUT, "%s: not a thorax solution (no \"model\")", path);
        }
        snprintf(model_dir, sizeof model_dir, "%s", mo->valuestring);
    }
    if (o->model_dir) snprintf(model_dir, sizeof model_dir, "%s", o->model_dir);
    /* a scan alone (thorax view --image IMG: tracing starts from nothing): a model without surfaces */
    int scan_only = !o->n_files && !model_dir[0] && o->image;
    int part = j && picture_part_wanted(o, j); /* sort-last: this rank's part of the volume alone */
    thx_status st = o->n_files ? surfaces_from_files(ctx, o, &d->m)
                  : scan_only ? thx_model_create(ctx, &d->m)
                  : part ? thx_model_read_regions_only(ctx, model_dir, &d->m) : thx_model_read(ctx, model_dir, &d->m);
    if (!o->n_files) snprintf(d->model_dir, sizeof d->model_dir, "%s", model_dir);
    if (st == THX_OK && scan_only) d->m->frame = thx_frame_ras(); /* the scan's RAS millimetres */
    if (st == THX_OK) st = check_names(ctx, o, d->m);
    if (st != THX_OK) { cJSON_Delete(j); return st; }
    if (j) {
        cJSON *files = cJSON_GetObjectItem(j, "files"), *epi = cJSON_GetObjectItem(j, "epicardial");
        cJSON *to = files ? cJSON_GetObjectItem(files, "torso") : NULL;
        cJSON *cn = files ? cJSON_GetObjectItem(files, "currents_node") : NULL;
        int outer = surface_by_role(d->m, THX_ROLE_OUTER), heart = surface_by_role(d->m, THX_ROLE_HEART);
        if (cJSON_IsString(to) && outer >= 0) {
            snprintf(path, sizeof path, "%s/%s", o->solution, to->valuestring);
            st = thx_series_read(ctx, path, THX_SERIES_AUTO, &d->series[outer]);
        }
        if (st == THX_OK && cJSON_IsString(epi) && heart >= 0 && access(epi->valuestring, R_OK) == 0)
            st = thx_series_read(ctx, epi->valuestring, THX_SERIES_AUTO, &d->series[heart]);
        if (st == THX_OK && part)
            st = picture_part_read(ctx, o, j, d);
        else if (st == THX_OK && picture_has_field(o))
            st = read_volume(ctx, o, j, o->isosurface ? "--isosurface" : o->n_slices ? "--slice" : o->n_streamlines ? "--streamlines" : "--volume", d);
        if (st == THX_OK && cJSON_IsString(cn) && o->arrows) {
            snprintf(path, sizeof path, "%s/%s", o->solution, cn->valuestring);
            st = thx_series_read(ctx, path, THX_SERIES_AUTO, &d->currents);
        }
        if (st == THX_OK) st = solution_ecg12(ctx, o->solution, files, &d->ecg);
        if (st == THX_OK && o->trace && lead_index(o->trace) >= 0 && !d->ecg)
            st = thx_error(ctx, THX_EINPUT, "--trace: %s has no ecg12 file (run thorax leads first)", o->solution);
        cJSON_Delete(j);
        if (st != THX_OK) return st;
    }
    /* the solution's series are each surface's first data set */
    for (size_t k = 0; k < d->m->n_surfaces && k < THX_PICTURE_SURFACES; k++)
        if (d->series[k]) { d->sets[k][0] = d->series[k]; d->n_sets[k] = 1; }
    for (int k = 0; k < o->n_data; k++) {
        const char *dpath = o->data[k], *on = k < o->n_data_surface ? o->data_surface[k] : NULL;
        thx_series *s = NULL;
        int *chan = NULL;
        THX_CHECK(thx_series_read(ctx, dpath, THX_SERIES_AUTO, &s));
        const char *cpath = o->n_channels ? o->data_channels[k] : o->channels;
        if (cpath) {
            thx_status sc = apply_channels(ctx, cpath, &s, &chan);
            if (sc != THX_OK) { thx_series_destroy(&s); return sc; }
        }
        int target = -1;
        thx_status bad = THX_OK;
        if (on) {
            target = surface_by_name(d->m, on);
            if (target < 0) bad = thx_error(ctx, THX_EINPUT, "--data-surface: no surface '%s'", on);
        } else {
            int n = 0;
            for (size_t q = 0; q < d->m->n_surfaces; q++)
                if (d->m->surf[q]->n_nodes == s->n_rows) { target = (int)q; n++; }
            if (n != 1)
                bad = thx_error(ctx, THX_EINPUT, "%s: %zu rows match %s (give --data-surface NAME)", dpath, s->n_rows,
                                n ? "several surfaces" : "no surface's node count");
        }
        if (bad == THX_OK && d->m->surf[target]->n_nodes != s->n_rows)
            bad = thx_error(ctx, THX_EINPUT, "%s: %zu rows, surface '%s' has %zu nodes", dpath, s->n_rows,
                            d->m->surf[target]->name, d->m->surf[target]->n_nodes);
        if (bad == THX_OK && target >= THX_PICTURE_SURFACES)
            bad = thx_error(ctx, THX_EINPUT, "%s: data on surface %d: at most %d surfaces carry data", dpath, target + 1, THX_PICTURE_SURFACES);
        if (bad == THX_OK && d->n_sets[target] >= THX_PICTURE_SETS)
            bad = thx_error(ctx, THX_EINPUT, "%s: surface '%s' has %d data sets already (at most %d)", dpath,
                            d->m->surf[target]->name, d->n_sets[target], THX_PICTURE_SETS);
        if (bad == THX_OK && o->bad_leads) bad = thx_bad_leads_fill(ctx, o->bad_leads, d->m->surf[target], chan, s);
        if (bad != THX_OK) { thx_series_destroy(&s); free(chan); return bad; }
        d->sets[target][d->n_sets[target]++] = s;
        d->active[target] = d->n_sets[target] - 1;
        d->series[target] = s;
        d->sranged[target] = 0;
        if (chan) { free(d->channel[target]); d->channel[target] = chan; }
    }
    for (int k = 0; k < o->n_activation + o->n_recovery; k++) {
        int rec = k >= o->n_activation;
        const char *spec = rec ? o->recovery[k - o->n_activation] : o->activation[k], *opt = rec ? "--recovery" : "--activation";
        char name[64];
        double t0 = NAN, t1 = NAN;
        const char *colon = strchr(spec, ':');
        snprintf(name, sizeof name, "%.*s", (int)(colon ? colon - spec : (long)strlen(spec)), spec);
        if (colon && (sscanf(colon + 1, "%lf:%lf", &t0, &t1) != 2 || !(t0 < t1)))
            return thx_error(ctx, THX_EINPUT, "%s '%s': give SURFACE or SURFACE:T0:T1 (T0 < T1, the series' time unit)", opt, spec);
        int s = surface_by_name(d->m, name);
        if (s < 0) return thx_error(ctx, THX_EINPUT, "%s '%s': the model has no surface '%s'", opt, spec, name);
        if (!d->series[s]) return thx_error(ctx, THX_EINPUT, "%s '%s': surface '%s' has no data", opt, spec, name);
        THX_CHECK(thx_picture_add_map(ctx, d, s, rec ? 2 : 1, t0, t1));
    }
    for (int k = 0; k < o->n_landmarks; k++) {
        thx_landmarks *lm = NULL;
        THX_CHECK(thx_landmarks_read(ctx, o->landmarks[k], &lm));
        thx_status sl = thx_landmarks_mesh(ctx, lm, NULL, &d->marks[d->n_marks]);
        thx_landmarks_destroy(&lm);
        if (sl != THX_OK) return sl;
        d->n_marks++;
    }
    if (o->n_landmarks + o->n_electrodes > THX_PICTURE_MAX)
        return thx_error(ctx, THX_EINPUT, "--landmarks and --electrodes: %d files, at most %d together",
                         o->n_landmarks + o->n_electrodes, THX_PICTURE_MAX);
    for (int k = 0; k < o->n_electrodes; k++) THX_CHECK(electrode_marks(ctx, o->electrodes[k], d));
    THX_CHECK(resolve_trace(ctx, o, d));
    if (o->arrows) {
        const thx_volume *v = d->m->volume;
        if (!o->solution || !d->currents)
            return thx_error(ctx, THX_EINPUT, "--arrows: needs --solution DIR with currents (thorax forward ... --currents LIST)");
        if (!v) return thx_error(ctx, THX_EINPUT, "--arrows: the model has no volume mesh (thorax mesh)");
        if (d->currents->n_rows != 3 * v->n_nodes)
            return thx_error(ctx, THX_EINPUT, "--arrows: the currents have %zu rows, the volume mesh has %zu nodes (3 rows each)",
                             d->currents->n_rows, v->n_nodes);
        if (o->arrow_region) {
            int r = -1;
            char list[512] = "";
            size_t len = 0;
            for (size_t k = 0; k < v->n_regions; k++) {
                if (!strcmp(v->regions[k].name, o->arrow_region)) r = (int)k;
                if (len < sizeof list - 80) len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", k ? ", " : "", v->regions[k].name);
            }
            if (r < 0) return thx_error(ctx, THX_EINPUT, "--arrow-region: the volume mesh has no region '%s' (it has %s)", o->arrow_region, list);
        }
    }
    for (size_t s = 0; s < d->m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (o->check_frame && d->series[s] && !d->map[s][d->active[s]] && (size_t)o->frame >= d->series[s]->n_frames)
            return thx_error(ctx, THX_EINPUT, "--frame %d: the data on '%s' has %zu frames", o->frame + 1, d->m->surf[s]->name,
                             d->series[s]->n_frames);
    return THX_OK;
}

thx_status thx_picture_add_activation(thx_ctx *ctx, thx_picture_data *d, int s, double t0, double t1)
{
    return thx_picture_add_map(ctx, d, s, 1, t0, t1);
}

thx_status thx_picture_add_map(thx_ctx *ctx, thx_picture_data *d, int s, int kind, double t0, double t1)
{
    if (s < 0 || s >= THX_PICTURE_SURFACES || (size_t)s >= d->m->n_surfaces || !d->series[s])
        return thx_error(ctx, THX_EINPUT, "%s: surface %d has no data", kind == 2 ? "recovery" : "activation", s + 1);
    if (d->n_sets[s] >= THX_PICTURE_SETS)
        return thx_error(ctx, THX_EINPUT, "%s: surface '%s' has %d data sets already (at most %d)",
                         kind == 2 ? "recovery" : "activation", d->m->surf[s]->name, d->n_sets[s], THX_PICTURE_SETS);
    int src = d->active[s];
    if (d->map[s][src]) /* a map of a map: of the potentials it came from */
        src = d->map_src[s][src] >= 0 ? d->map_src[s][src] : src;
    const thx_series *pot = d->sets[s][src];
    if (d->map[s][src]) return thx_error(ctx, THX_EINPUT, "activation: surface '%s' shows a map, not potentials", d->m->surf[s]->name);
    thx_series *map = NULL;
    int chosen = isnan(t0) && isnan(t1);
    if (chosen) THX_CHECK(thx_activation_from_fiducials(ctx, pot, kind == 2 ? 13 : 10, &map));
    if (!map) {
        thx_activation_window w = {0};
        if (chosen) THX_CHECK(thx_activation_window_choose(ctx, pot, &w));
        thx_activation_opts ao;
        thx_activation_opts_default(&ao);
        if (kind == 2) {
            ao.recovery = 1;
            ao.t0 = chosen ? w.t0 : NAN;
            ao.t1 = chosen ? w.t1 : NAN;
            ao.rec_t0 = chosen ? w.rec_t0 : t0;
            ao.rec_t1 = chosen ? w.rec_t1 : t1;
            if (!chosen) { /* the activation window before the T wave given: the beat's QRS if it lies before */
                thx_activation_window q;
                THX_CHECK(thx_activation_window_choose(ctx, pot, &q));
                ao.t0 = q.t1 < t0 ? q.t0 : NAN;
                ao.t1 = q.t1 < t0 ? q.t1 : t0;
            }
        } else {
            ao.t0 = chosen ? w.t0 : t0;
            ao.t1 = chosen ? w.t1 : t1;
        }
        thx_series *both = NULL;
        THX_CHECK(thx_activation_times(ctx, pot, &ao, &both));
        if (kind == 2) { /* the recovery frame alone */
            thx_status st = thx_series_create(ctx, pot->n_rows, 1, &map);
            if (st != THX_OK) { thx_series_destroy(&both); return st; }
            memcpy(map->v, both->v + pot->n_rows, pot->n_rows * sizeof *map->v);
            snprintf(map->unit, sizeof map->unit, "%s", both->unit);
            map->time_unit[0] = '\0';
            thx_series_destroy(&both);
        } else {
            map = both;
        }
        if (chosen)
            snprintf(map->label, sizeof map->label, "%s %.4g-%.4g %.15s (%.60s)", kind == 2 ? "recovery, T" : "activation, QRS",
                     kind == 2 ? w.rec_t0 : w.t0, kind == 2 ? w.rec_t1 : w.t1, pot->time_unit, kind == 2 ? w.rec_why : w.why);
        else
            snprintf(map->label, sizeof map->label, "%s %.4g-%.4g %s (as given)", kind == 2 ? "recovery, T" : "activation, window",
                     t0, t1, pot->time_unit);
    }
    int k = d->n_sets[s]++;
    d->sets[s][k] = map;
    d->map[s][k] = (unsigned char)kind;
    d->map_src[s][k] = (signed char)src;
    d->map_auto[s][k] = (unsigned char)chosen;
    thx_picture_set_active(d, s, k);
    return THX_OK;
}

int thx_picture_drop_set(thx_picture_data *d, int s, int k)
{
    if (s < 0 || s >= THX_PICTURE_SURFACES || k < 0 || k >= d->n_sets[s] || !d->map[s][k]) return -1;
    int src = d->map_src[s][k] >= 0 ? d->map_src[s][k] : 0;
    thx_series_destroy(&d->sets[s][k]);
    for (int j = k; j + 1 < d->n_sets[s]; j++) {
        d->sets[s][j] = d->sets[s][j + 1];
        d->map[s][j] = d->map[s][j + 1];
        d->map_src[s][j] = d->map_src[s][j + 1];
        d->map_auto[s][j] = d->map_auto[s][j + 1];
    }
    d->n_sets[s]--;
    d->sets[s][d->n_sets[s]] = NULL;
    for (int j = 0; j < d->n_sets[s]; j++) /* the maps' sources after k moved down one */
        if (d->map_src[s][j] > k) d->map_src[s][j]--;
    if (src > k) src--;
    return thx_picture_set_active(d, s, src);
}

int thx_picture_set_active(thx_picture_data *d, int s, int k)
{
    if (s < 0 || s >= THX_PICTURE_SURFACES || k < 0 || k >= d->n_sets[s]) return -1;
    d->active[s] = k;
    d->series[s] = d->sets[s][k];
    d->sranged[s] = 0;
    return 0;
}

void thx_picture_geometry_changed(thx_picture_data *d)
{
    thx_pick_index_destroy(&d->pick);
}

/* An electrode file as marks: one sphere per electrode (1.2% of the model's diagonal across, at
 * least 2 mm), in one colour that is neither a potential's nor a tissue's grey; its names are drawn
 * beside them by picture_marks. */
static thx_status electrode_marks(thx_ctx *ctx, const char *path, thx_picture_data *d)
{
    thx_electrodes *e = NULL;
    THX_CHECK(thx_electrodes_read(ctx, path, &e));
    if (d->m && d->m->n_surfaces) {
        thx_status sc = thx_electrodes_check(ctx, e, d->m);
        if (sc != THX_OK) {
            thx_electrodes_destroy(&e);
            return sc;
        }
    }
    double lo[3], hi[3], diag = 0;
    thx_picture_bounds(d, lo, hi);
    for (int k = 0; k < 3; k++) diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    double r = fmax(2.0, 0.006 * sqrt(diag));
    thx_landmarks *lm = NULL;
    thx_landmark_point *pt = calloc(e->n, sizeof *pt);
    thx_status st = pt ? thx_landmarks_create(ctx, &lm) : thx_error(ctx, THX_ENOMEM, "out of memory (electrodes)");
    if (st == THX_OK) {
        for (size_t i = 0; i < e->n; i++) {
            memcpy(pt[i].xyz, e->xyz + 3 * i, sizeof pt[i].xyz);
            pt[i].radius = r;
            snprintf(pt[i].label, sizeof pt[i].label, "%s", e->name[i]);
        }
        thx_landmark_segment *seg = NULL;
        st = thx_landmarks_add_segment(ctx, lm, THX_LANDMARK_LEAD, pt, e->n, &seg);
        if (st == THX_OK) {
            seg->has_color = 1;
            seg->rgb[0] = 0x10;
            seg->rgb[1] = 0xa0;
            seg->rgb[2] = 0x40;
            st = thx_landmarks_mesh(ctx, lm, NULL, &d->marks[d->n_marks]);
        }
        if (st == THX_OK) d->n_marks++;
    }
    free(pt);
    thx_landmarks_destroy(&lm);
    if (st == THX_OK) d->elec[d->n_elec++] = e;
    else thx_electrodes_destroy(&e);
    return st;
}

thx_status thx_picture_load(thx_ctx *ctx, thx_picture_opts *o, thx_picture_data *d)
{
    if (picture_has_field(o) && !o->solution) {
        memset(d, 0, sizeof *d);
        return thx_error(ctx, THX_EINPUT, "%s: needs --solution DIR (a solution with volume potentials)",
                         o->isosurface ? "--isosurface" : o->n_slices ? "--slice" : o->n_streamlines ? "--streamlines" : "--volume");
    }
    THX_CHECK(load_data(ctx, o, d));
    THX_CHECK(picture_field_load(ctx, o, d));
    THX_CHECK(picture_scan_load(ctx, o, d));
    THX_CHECK(picture_view_frame(ctx, o, d));
    THX_CHECK(thx_picture_clip_check(ctx, o, d));
    if (o->tetrahedra) {
        if (!d->m || !d->m->volume)
            return thx_error(ctx, THX_EINPUT, "--tetrahedra: %s has no volume mesh (thorax mesh makes one)",
                             d->model_dir[0] ? d->model_dir : "the picture");
        thx_clip_plane cp;
        int nc = thx_picture_clip(ctx, o, d, &cp);
        if (nc < 0) return THX_EINPUT;
        THX_CHECK(picture_tet_surfaces(ctx, d->m->volume, nc ? &cp : NULL, d->tets, d->tets_region, THX_PICTURE_MAX,
                                       &d->n_tets));
    }
    return THX_OK;
}

size_t thx_picture_n_frames(const thx_picture_data *d)
{
    const thx_series *any = NULL;
    for (size_t s = 0; d->m && s < d->m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (d->series[s] && (!any || d->m->surf[s]->role == THX_ROLE_OUTER)) any = d->series[s];
    return any ? any->n_frames : 0;
}

void thx_picture_bounds(const thx_picture_data *d, double lo[3], double hi[3])
{
    const thx_model *m = d->m;
    for (int k = 0; k < 3; k++) { lo[k] = INFINITY; hi[k] = -INFINITY; }
    for (size_t s = 0; s < m->n_surfaces; s++)
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], m->surf[s]->xyz[3 * i + k]);
                hi[k] = fmax(hi[k], m->surf[s]->xyz[3 * i + k]);
            }
    if ((!(lo[0] <= hi[0]) || d->bounds_from_scan) && d->scan) { /* no node yet (a scan being traced): the image's box */
        static const char axes[3] = {'x', 'y', 'z'};
        for (int k = 0; k < 3; k++) {
            double step;
            pic_scan_range(d->scan, axes[k], &lo[k], &hi[k], &step);
        }
    }
}

