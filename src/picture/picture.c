/*
 * A picture of a model and its data (thorax/picture/picture.h): the data read once, the scene of
 * a frame built from the settings, drawn offscreen or into the caller's OpenGL context, and the
 * annotations over it. Shared by thorax render, animate and view.
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
#include "thorax/geom/landmark_mesh.h"
#include "thorax/geom/pick.h"
#include "thorax/io/landmarks_file.h"
#include "thorax/leads/activation.h"
#include "picture/picture_internal.h"

void thx_picture_data_free(thx_picture_data *d)
{
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
    thx_series_destroy(&d->ecg);
    thx_series_destroy(&d->currents);
    thx_series_destroy(&d->volume);
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
    for (int k = 0; k < o->n_only + o->n_look + o->n_whole; k++) {
        const char *name = k < o->n_only ? o->only[k] : k < o->n_only + o->n_look ? o->look[k - o->n_only].name
                                                                                   : o->whole[k - o->n_only - o->n_look];
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
        if (dot && dot != name) *dot = '\0';
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

/* map3d .channels: "N leads", then N lines "lead channel" (1-based). The series' rows are the
 * recording's channels; the result has one row per lead (NaN for a lead the file leaves out). */
static thx_status apply_channels(thx_ctx *ctx, const char *path, thx_series **sp, int **chan_out)
{
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_series *in = *sp, *outs = NULL;
    int *chan = NULL;
    thx_status st = THX_OK;
    char *p = text, *end;
    size_t line = 1;
    long n = strtol(p, &end, 10);
    if (end == p || n < 1 || n > 10000000) {
        st = thx_error(ctx, THX_EINPUT, "%s:1: expected 'N leads' (the number of leads first)", path);
        goto done;
    }
    p = strchr(end, '\n');
    p = p ? p + 1 : end + strlen(end);
    line = 2;
    st = thx_series_create(ctx, (size_t)n, in->n_frames, &outs);
    if (st != THX_OK) goto done;
    chan = calloc((size_t)n, sizeof *chan);
    if (!chan) { st = thx_error(ctx, THX_ENOMEM, "out of memory (%ld channels)", n); goto done; }
    for (size_t k = 0; k < (size_t)n * in->n_frames; k++) outs->v[k] = NAN;
    memcpy(outs->time, in->time, in->n_frames * sizeof *in->time);
    snprintf(outs->unit, sizeof outs->unit, "%s", in->unit);
    snprintf(outs->time_unit, sizeof outs->time_unit, "%s", in->time_unit);
    snprintf(outs->label, sizeof outs->label, "%.100s (by channel)", in->label);
    for (long k = 0; k < n; k++, line++) {
        while (*p == '\n' || *p == '\r') { if (*p == '\n') line++; p++; }
        char *e1, *e2;
        long lead = strtol(p, &e1, 10), ch = strtol(e1, &e2, 10);
        if (e1 == p || e2 == e1) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: expected 'lead channel' (%ld of %ld leads read)", path, line, k, n);
            goto done;
        }
        if (lead < 1 || lead > n) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: lead %ld is not in 1..%ld", path, line, lead, n);
            goto done;
        }
        if (ch < 1 || (size_t)ch > in->n_rows) {
            st = thx_error(ctx, THX_EINPUT, "%s:%zu: channel %ld is not in 1..%zu (the recording's rows)", path, line, ch, in->n_rows);
            goto done;
        }
        for (size_t f = 0; f < in->n_frames; f++)
            outs->v[f * (size_t)n + (size_t)(lead - 1)] = in->v[f * in->n_rows + (size_t)(ch - 1)];
        chan[lead - 1] = (int)ch;
        p = strchr(e2, '\n');
        p = p ? p + 1 : e2 + strlen(e2);
    }
done:
    free(text);
    if (st != THX_OK) { thx_series_destroy(&outs); free(chan); return st; }
    thx_series_destroy(sp);
    *sp = outs;
    *chan_out = chan;
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
    thx_status st = o->n_files ? surfaces_from_files(ctx, o, &d->m) : thx_model_read(ctx, model_dir, &d->m);
    if (!o->n_files) snprintf(d->model_dir, sizeof d->model_dir, "%s", model_dir);
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
        if (st == THX_OK && cJSON_IsString(cn) && o->arrows) {
            snprintf(path, sizeof path, "%s/%s", o->solution, cn->valuestring);
            st = thx_series_read(ctx, path, THX_SERIES_AUTO, &d->currents);
        }
        if (st == THX_OK && o->trace && lead_index(o->trace) >= 0) {
            const char *ext[3] = {"txt", "raw", "mat"};
            for (int k = 0; k < 3 && !d->ecg; k++) {
                snprintf(path, sizeof path, "%s/ecg12.%s", o->solution, ext[k]);
                if (access(path, R_OK) == 0) st = thx_series_read(ctx, path, THX_SERIES_AUTO, &d->ecg);
            }
            if (st == THX_OK && !d->ecg)
                st = thx_error(ctx, THX_EINPUT, "--trace: %s has no ecg12 file (run thorax leads first)", o->solution);
        }
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
        if (o->channels) {
            thx_status sc = apply_channels(ctx, o->channels, &s, &chan);
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
        if (bad != THX_OK) { thx_series_destroy(&s); free(chan); return bad; }
        d->sets[target][d->n_sets[target]++] = s;
        d->active[target] = d->n_sets[target] - 1;
        d->series[target] = s;
        d->sranged[target] = 0;
        if (chan) { free(d->channel[target]); d->channel[target] = chan; }
    }
    for (int k = 0; k < o->n_activation; k++) {
        char name[64];
        double t0 = NAN, t1 = NAN;
        const char *colon = strchr(o->activation[k], ':');
        snprintf(name, sizeof name, "%.*s", (int)(colon ? colon - o->activation[k] : (long)strlen(o->activation[k])), o->activation[k]);
        if (colon && (sscanf(colon + 1, "%lf:%lf", &t0, &t1) != 2 || !(t0 < t1)))
            return thx_error(ctx, THX_EINPUT, "--activation '%s': give SURFACE or SURFACE:T0:T1 (T0 < T1, the series' time unit)", o->activation[k]);
        int s = surface_by_name(d->m, name);
        if (s < 0) return thx_error(ctx, THX_EINPUT, "--activation '%s': the model has no surface '%s'", o->activation[k], name);
        if (!d->series[s]) return thx_error(ctx, THX_EINPUT, "--activation '%s': surface '%s' has no data", o->activation[k], name);
        THX_CHECK(thx_picture_add_activation(ctx, d, s, t0, t1));
    }
    for (int k = 0; k < o->n_landmarks; k++) {
        thx_landmarks *lm = NULL;
        THX_CHECK(thx_landmarks_read(ctx, o->landmarks[k], &lm));
        thx_status sl = thx_landmarks_mesh(ctx, lm, NULL, &d->marks[d->n_marks]);
        thx_landmarks_destroy(&lm);
        if (sl != THX_OK) return sl;
        d->n_marks++;
    }
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

/* ---- one picture ---- */
static void range_of(const double *v, size_t n, double *lo, double *hi)
{
    for (size_t i = 0; i < n; i++)
        if (isfinite(v[i])) { *lo = fmin(*lo, v[i]); *hi = fmax(*hi, v[i]); }
}

/* The finite range of surface k's whole series, computed at the first call (an animation asks
   for it every frame). */
static void series_range(thx_picture_data *d, size_t k, double *lo, double *hi)
{
    const thx_series *x = d->series[k];
    if (!d->sranged[k]) {
        double a = INFINITY, b = -INFINITY;
        range_of(x->v, x->n_rows * x->n_frames, &a, &b);
        d->smin[k] = a;
        d->smax[k] = b;
        d->sranged[k] = 1;
    }
    *lo = fmin(*lo, d->smin[k]);
    *hi = fmax(*hi, d->smax[k]);
}

/* Whether surface name is in the comma-separated list. */
static int in_list(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = list; *p;) {
        const char *c = strchr(p, ',');
        size_t len = c ? (size_t)(c - p) : strlen(p);
        if (len == n && !strncmp(p, name, n)) return 1;
        p = c ? c + 1 : p + len;
    }
    return 0;
}

/* The surface whose scale s takes (--slave NAME=MASTER), or s. */
static int master_of(const thx_picture_opts *o, const thx_model *m, int s)
{
    for (int k = 0; k < o->n_slaves; k++) {
        const char *eq = strchr(o->slaves[k], '=');
        if (!eq || strncmp(o->slaves[k], m->surf[s]->name, (size_t)(eq - o->slaves[k])) ||
            m->surf[s]->name[eq - o->slaves[k]])
            continue;
        for (size_t j = 0; j < m->n_surfaces; j++)
            if (!strcmp(m->surf[j]->name, eq + 1)) return (int)j;
    }
    return s;
}

/* Whether surface k's data count toward surface s's scale: all surfaces (scopes all and
 * surfaces), the surfaces of s's group (--scale-group), or s alone. */
static int shares_scale(const thx_picture_opts *o, const thx_model *m, int s, int k)
{
    if (o->scope == THX_SCOPE_ALL || o->scope == THX_SCOPE_SURFACES || k == s) return 1;
    for (int g = 0; g < o->n_groups; g++)
        if (in_list(o->groups[g], m->surf[s]->name) && in_list(o->groups[g], m->surf[k]->name)) return 1;
    return 0;
}

static void scale_for(const thx_picture_opts *o, thx_picture_data *d, int s, int frame, thx_scale *sc)
{
    double lo = INFINITY, hi = -INFINITY;
    memset(sc, 0, sizeof *sc);
    if (o->scope == THX_SCOPE_FIXED) {
        sc->model = o->model;
        sc->lo = o->lo;
        sc->hi = o->hi;
        sc->k = o->model == THX_SCALE_LOG ? 10 : 3;
        sc->mapping = (thx_scale_mapping)o->mapping;
    } else {
        s = master_of(o, d->m, s);
        for (size_t k = 0; k < d->m->n_surfaces && k < THX_PICTURE_SURFACES; k++) {
            const thx_series *x = d->series[k];
            if (!x || !shares_scale(o, d->m, s, (int)k)) continue;
            if (d->map[k][d->active[k]] != d->map[s][d->active[s]]) continue; /* times and potentials apart */
            size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
            if (o->scope == THX_SCOPE_FRAME || o->scope == THX_SCOPE_SURFACES) range_of(x->v + f * x->n_rows, x->n_rows, &lo, &hi);
            else series_range(d, k, &lo, &hi);
        }
        /* the library's one range rule (thorax/render/image.h): symmetric = the largest magnitude;
           a map of times over its true range */
        int map = s < THX_PICTURE_SURFACES && d->series[s] && d->map[s][d->active[s]];
        thx_scale_from_range_mapped(sc, (thx_scale_model)o->model, map ? THX_MAPPING_TRUE : (thx_scale_mapping)o->mapping, lo, hi);
    }
    if (o->invert) { /* the colour map reversed: the scale's ends swapped */
        double t = sc->lo;
        sc->lo = sc->hi;
        sc->hi = t;
    }
}

static const float palette[6][4] = {{0.85f, 0.75f, 0.65f, 1}, {0.95f, 0.85f, 0.55f, 1}, {0.75f, 0.35f, 0.35f, 1},
                                    {0.55f, 0.65f, 0.85f, 1}, {0.55f, 0.75f, 0.85f, 1}, {0.85f, 0.25f, 0.25f, 1}};

int thx_picture_mode_parse(const char *s, thx_draw_mode *out)
{
    static const char *names[] = {"hidden", "points", "wire", "flat", "gouraud", "phong", "orientation"};
    for (int k = 0; k < 7; k++)
        if (!strcmp(s, names[k])) { *out = (thx_draw_mode)k; return 0; }
    return -1;
}

typedef struct {
    thx_render_surface rs[THX_PICTURE_SURFACES + 64]; /* the surfaces, then landmark meshes */
    size_t n;
    thx_render_arrows arrows;
    double *apos, *avec;
    int have_arrows;
    int main_surface;
    size_t nan_count;
} built_scene;

/* The column of the currents series for a frame of the potentials: matched by time, because
   `thorax forward --currents LIST` writes only the listed frames. -1 if that frame has none. */
long thx_picture_currents_column(const thx_picture_data *d, int frame)
{
    const thx_series *c = d->currents, *ref = NULL;
    if (!c) return -1;
    for (size_t s = 0; s < d->m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (d->series[s] && (!ref || d->m->surf[s]->role == THX_ROLE_OUTER)) ref = d->series[s];
    if (!ref) return c->n_frames == 1 ? 0 : -1;
    if ((size_t)frame >= ref->n_frames) return -1;
    double t = ref->time[frame], tol = 1e-9 * (ref->n_frames > 1 ? fabs(ref->time[1] - ref->time[0]) : 1);
    for (size_t k = 0; k < c->n_frames; k++)
        if (fabs(c->time[k] - t) <= tol) return (long)k;
    return -1;
}

/*
 * Arrows of the current density at a frame: the node values inside the limits (a tissue region, a
 * box), averaged over the cells of a grid of arrow_spacing mm (or one per node when the spacing is
 * 0), then, strongest first, kept when no kept arrow lies within arrow_gap mm, up to arrow_max.
 */
static thx_status build_arrows(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d, int frame, built_scene *b)
{
    const thx_volume *v = d->m->volume;
    if (!o->arrows) return THX_OK;
    long col = thx_picture_currents_column(d, frame);
    if (col < 0) return thx_error(ctx, THX_EINPUT, "--arrows: the solution has no currents for frame %d (thorax forward --currents LIST)", frame + 1);
    const thx_series *c = d->currents;
    const double *J = c->v + (size_t)col * c->n_rows;
    unsigned char *in = malloc(v->n_nodes ? v->n_nodes : 1);
    if (!in) return thx_error(ctx, THX_ENOMEM, "out of memory (arrows)");
    memset(in, o->arrow_region ? 0 : 1, v->n_nodes);
    if (o->arrow_region) {
        int r = -1;
        for (size_t k = 0; k < v->n_regions; k++)
            if (!strcmp(v->regions[k].name, o->arrow_region)) r = (int)k;
        for (size_t t = 0; t < v->n_tets; t++)
            if (v->region[t] == r)
                for (int k = 0; k < 4; k++) in[v->tet[4 * t + k]] = 1;
    }
    if (o->have_box)
        for (size_t i = 0; i < v->n_nodes; i++) {
            const double *x = v->xyz + 3 * i;
            for (int k = 0; k < 3; k++)
                if (x[k] < o->box[k] || x[k] > o->box[3 + k]) in[i] = 0;
        }
    size_t kept = 0;
    double jmax = 0;
    thx_status st = thx_arrows_select(ctx, v->xyz, J, v->n_nodes, in, o->arrow_spacing, o->arrow_gap, (size_t)o->arrow_max,
                                      &b->apos, &b->avec, &kept, &jmax);
    free(in);
    if (st != THX_OK) return st;
    memset(&b->arrows, 0, sizeof b->arrows);
    b->arrows.pos = b->apos;
    b->arrows.vec = b->avec;
    b->arrows.n = kept;
    b->arrows.unit_length = o->arrow_unit;
    b->arrows.scale = o->arrow_unit ? o->arrow_scale : (jmax > 0 ? o->arrow_scale / jmax : 1);
    b->arrows.cmap = THX_CMAP_VIRIDIS;
    b->arrows.mag_scale.model = THX_SCALE_LINEAR;
    b->arrows.mag_scale.lo = 0;
    b->arrows.mag_scale.hi = jmax > 0 ? jmax : 1;
    b->arrows.color[0] = 1.0f;
    b->arrows.color[1] = 0.9f;
    b->arrows.color[2] = 0.2f;
    b->arrows.color[3] = 1;
    b->arrows.width = 2;
    b->have_arrows = kept > 0;
    return THX_OK;
}

static void build_surfaces(const thx_picture_opts *o, thx_picture_data *d, int frame, built_scene *b, int only_surface)
{
    const thx_model *m = d->m;
    b->n = 0;
    b->main_surface = -1;
    for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++) {
        if (only_surface >= 0 && (int)s != only_surface) continue;
        thx_render_surface *r = &b->rs[b->n];
        memset(r, 0, sizeof *r);
        r->surf = m->surf[s];
        int shown = o->n_only == 0;
        for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
        if (!shown) continue;
        /* default look: data surfaces opaque; the others translucent */
        memcpy(r->color, palette[s % 6], sizeof r->color);
        r->mode = o->mode;
        int has = d->series[s] != NULL;
        int any = 0;
        for (size_t k = 0; k < m->n_surfaces && k < THX_PICTURE_SURFACES; k++) any |= d->series[k] != NULL;
        if (!has && any && o->mode != THX_DRAW_ORIENTATION) {
            /* beside data, colour means potential: the other surfaces in greys (a shade each) */
            float g = 0.82f - 0.08f * (float)(s % 4);
            r->color[0] = r->color[1] = r->color[2] = g;
            if (o->mode != THX_DRAW_WIRE && o->mode != THX_DRAW_POINTS)
                r->color[3] = m->surf[s]->role == THX_ROLE_OUTER ? 0.25f : 0.35f;
        }
        for (int k = 0; k < o->n_whole; k++) r->no_clip |= !strcmp(o->whole[k], m->surf[s]->name);
        const thx_picture_look *look = NULL;
        for (int k = 0; k < o->n_look; k++)
            if (!strcmp(o->look[k].name, m->surf[s]->name)) look = &o->look[k];
        if (look) {
            r->mode = look->mode;
            if (look->opacity >= 0) r->color[3] = look->opacity;
            if (look->have_color) memcpy(r->color, look->color, sizeof look->color);
        }
        r->back_color[0] = 1;
        r->back_color[1] = 1;
        r->back_color[2] = 1;
        r->back_color[3] = 1;
        r->point_size = 3;
        r->line_width = 1.5f;
        if (has && r->mode != THX_DRAW_HIDDEN) {
            const thx_series *x = d->series[s];
            size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
            r->values = x->v + f * x->n_rows;
            for (size_t i = 0; i < x->n_rows; i++) b->nan_count += !isfinite(r->values[i]);
            r->style = look && look->style >= 0 ? look->style : o->style;
            r->n_levels = o->levels;
            r->cmap = o->cmap;
            scale_for(o, d, (int)s, (int)f, &r->scale);
            r->contour_color[3] = 1;
            r->color[3] = look && look->opacity >= 0 ? look->opacity : 1;
            if (b->main_surface < 0 || m->surf[s]->role == THX_ROLE_OUTER) {
                b->main_surface = (int)s;
            }
        }
        b->n++;
    }
    for (int k = 0; k < d->n_marks; k++)
        for (size_t j = 0; j < d->marks[k]->n && b->n < sizeof b->rs / sizeof b->rs[0]; j++) {
            thx_render_surface *r = &b->rs[b->n++];
            memset(r, 0, sizeof *r);
            r->surf = d->marks[k]->surf[j];
            r->mode = THX_DRAW_GOURAUD;
            memcpy(r->color, d->marks[k]->rgba[j], sizeof r->color);
            r->no_clip = 1;
        }
}

int thx_picture_axis_parse(const char *s, int *axis, double *sign)
{
    *sign = 1;
    if (*s == '+' || *s == '-') { *sign = *s == '-' ? -1 : 1; s++; }
    if ((*s == 'x' || *s == 'y' || *s == 'z') && !s[1]) { *axis = *s - 'x'; return 0; }
    return -1;
}

/* The anatomical frame: --up (cranial) and --front (anterior) over the model's frame (the model's
   own when it has one, else +z and +y); right = anterior x cranial. */
static int anat_frame(thx_picture_opts *o, const thx_frame *mf)
{
    int a = mf && mf->set ? mf->front.axis : 1, c = mf && mf->set ? mf->up.axis : 2;
    double sa = mf && mf->set ? mf->front.sign : 1, sc = mf && mf->set ? mf->up.sign : 1;
    if (o->front_spec && thx_picture_axis_parse(o->front_spec, &a, &sa)) return -1;
    if (o->up_spec && thx_picture_axis_parse(o->up_spec, &c, &sc)) return -1;
    if (a == c) return -1;
    int r = 3 - a - c;
    double eps = ((a + 1) % 3 == c) ? 1 : -1; /* e_a x e_c = eps e_r */
    o->ax[0] = r; o->sg[0] = sa * sc * eps;
    o->ax[1] = a; o->sg[1] = sa;
    o->ax[2] = c; o->sg[2] = sc;
    return 0;
}

/* Model box -> the box in the anatomical frame; a vector of the frame -> model coordinates. */
static void box_to_frame(const thx_picture_opts *o, const double lo[3], const double hi[3], double qlo[3], double qhi[3])
{
    for (int k = 0; k < 3; k++) {
        int a = o->ax[k];
        qlo[k] = o->sg[k] > 0 ? lo[a] : -hi[a];
        qhi[k] = o->sg[k] > 0 ? hi[a] : -lo[a];
    }
}

static void from_frame(const thx_picture_opts *o, const double q[3], double p[3])
{
    for (int k = 0; k < 3; k++) p[o->ax[k]] = o->sg[k] * q[k];
}

static int parse_clip(const char *spec, const double lo[3], const double hi[3], thx_clip_plane *p, int *named)
{
    *named = 0;
    /* "anterior[:F]" keeps the posterior part up to fraction F of the depth (default 0.45) from the
       back; "posterior", "left", "right", "superior", "inferior" likewise; or "nx,ny,nz,d" */
    static const char *names[] = {"anterior", "posterior", "left", "right", "superior", "inferior"};
    /* the side removed: anterior removes +y, posterior -y, left -x, right +x, superior +z, inferior -z */
    static const int axis[] = {1, 1, 0, 0, 2, 2}, sign[] = {1, -1, -1, 1, 1, -1};
    char name[32];
    double f = 0.5;
    const char *colon = strchr(spec, ':');
    snprintf(name, sizeof name, "%.*s", colon ? (int)(colon - spec) : (int)strlen(spec), spec);
    if (colon) f = atof(colon + 1);
    for (int k = 0; k < 6; k++)
        if (!strcmp(name, names[k])) {
            int a = axis[k];
            memset(p, 0, sizeof *p);
            p->n[a] = -sign[k];
            double cut = sign[k] > 0 ? lo[a] + f * (hi[a] - lo[a]) : hi[a] - f * (hi[a] - lo[a]);
            p->d = sign[k] * cut;
            *named = 1;
            return 0;
        }
    if (sscanf(spec, "%lf,%lf,%lf,%lf", &p->n[0], &p->n[1], &p->n[2], &p->d) == 4) return 0;
    return -1;
}



/* The views' frame: --up/--front over the model's frame. A model without a frame is refused for a
   named view (no --camera) or a named clip side unless both are given; loose surface files have no
   model and are drawn in +z/+y with a warning. */
static thx_status view_frame(thx_ctx *ctx, thx_picture_opts *o, const thx_picture_data *d)
{
    const thx_frame *mf = &d->m->frame;
    int named_clip = o->clip[0] && ((o->clip[0] >= 'a' && o->clip[0] <= 'z') || (o->clip[0] >= 'A' && o->clip[0] <= 'Z'));
    int needs = !o->have_camera || named_clip;
    if (!mf->set && needs && !(o->up_spec && o->front_spec)) {
        if (!o->n_files) {
            char what[PATH_MAX + 16];
            snprintf(what, sizeof what, "model %s", o->model_dir ? o->model_dir : o->solution ? o->solution : "?");
            char msg[1024];
            thx_frame_require(ctx, mf, what, o->have_camera ? "named clip sides" : "the named views (--view)");
            snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
            return thx_error(ctx, THX_EINPUT, "%s; or give --up and --front to thorax render (or --camera)", msg);
        }
        thx_log(ctx, THX_LOG_WARN, "surface files have no anatomical frame: the %s taken as +z superior, +y anterior "
                "(give --up and --front)", named_clip && o->have_camera ? "clip side is" : "view is");
    }
    if (anat_frame(o, mf))
        return thx_error(ctx, THX_EINPUT, "--up %s and --front %s are the same axis (cranial and anterior must differ)",
                         o->up_spec ? o->up_spec : "(the model's)", o->front_spec ? o->front_spec : "(the model's)");
    return THX_OK;
}

void thx_picture_opts_default(thx_picture_opts *o)
{
    memset(o, 0, sizeof *o);
    o->w = 800;
    o->h = 800;
    o->view = THX_VIEW_ANTERIOR;
    for (int k = 0; k < 3; k++) { o->ax[k] = k; o->sg[k] = 1; }
    o->mode = THX_DRAW_GOURAUD;
    o->style = THX_DATA_CONTINUOUS;
    o->levels = 12;
    o->cmap = THX_CMAP_ECG;
    o->model = THX_SCALE_LINEAR;
    o->scope = THX_SCOPE_SERIES;
    o->mapping = THX_MAPPING_SYMMETRIC;
    o->arrow_spacing = 20;
    o->arrow_scale = 15;
    o->arrow_max = 400;
}

thx_status thx_picture_add_activation(thx_ctx *ctx, thx_picture_data *d, int s, double t0, double t1)
{
    if (s < 0 || s >= THX_PICTURE_SURFACES || (size_t)s >= d->m->n_surfaces || !d->series[s])
        return thx_error(ctx, THX_EINPUT, "activation: surface %d has no data", s + 1);
    if (d->n_sets[s] >= THX_PICTURE_SETS)
        return thx_error(ctx, THX_EINPUT, "activation: surface '%s' has %d data sets already (at most %d)", d->m->surf[s]->name,
                         d->n_sets[s], THX_PICTURE_SETS);
    thx_activation_opts ao;
    thx_activation_opts_default(&ao);
    ao.t0 = t0;
    ao.t1 = t1;
    thx_series *map = NULL;
    THX_CHECK(thx_activation_times(ctx, d->series[s], &ao, &map));
    int k = d->n_sets[s]++;
    d->sets[s][k] = map;
    d->map[s][k] = 1;
    thx_picture_set_active(d, s, k);
    return THX_OK;
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

thx_status thx_picture_load(thx_ctx *ctx, thx_picture_opts *o, thx_picture_data *d)
{
    THX_CHECK(load_data(ctx, o, d));
    return view_frame(ctx, o, d);
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
}

static const unsigned char BG[4] = {24, 24, 28, 255}, FG[4] = {235, 235, 235, 255};

void thx_picture_viewport(const thx_picture_opts *o, thx_font *font, int w, int h, int vp[4])
{
    int trace_h = o->trace ? h / 5 : 0, bar_w = o->colorbar ? (w / 6 > 96 ? w / 6 : 96) : 0;
    int top = o->label && font ? thx_font_height(font) + 8 : 0;
    vp[0] = 0;
    vp[1] = top;
    vp[2] = w - bar_w;
    vp[3] = h - trace_h - top;
}

/* The panels: one, or a grid of one per surface shown (--panels). */
static int n_panels(const thx_picture_opts *o, const thx_model *m, int *cols, int *rows)
{
    int panels = 1;
    *cols = *rows = 1;
    if (o->panels) {
        panels = 0;
        for (size_t s = 0; s < m->n_surfaces; s++) {
            int shown = o->n_only == 0;
            for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
            panels += shown;
        }
        *cols = (int)ceil(sqrt((double)panels));
        *rows = (panels + *cols - 1) / *cols;
    }
    return panels;
}

void thx_picture_camera(const thx_picture_opts *o, const thx_picture_data *d, double aspect, thx_camera *cam)
{
    if (o->have_camera) { *cam = o->cam; return; }
    double lo[3], hi[3], qlo[3], qhi[3];
    thx_picture_bounds(d, lo, hi);
    box_to_frame(o, lo, hi, qlo, qhi);
    /* the standard view in the anatomical frame, carried back to the model's axes */
    thx_camera c;
    thx_camera_view(&c, o->view, qlo, qhi, aspect);
    *cam = c;
    from_frame(o, c.eye, cam->eye);
    from_frame(o, c.center, cam->center);
    from_frame(o, c.up, cam->up);
}

int thx_picture_clip(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d, thx_clip_plane *p)
{
    if (!o->clip[0]) return 0;
    double lo[3], hi[3], qlo[3], qhi[3];
    thx_picture_bounds(d, lo, hi);
    box_to_frame(o, lo, hi, qlo, qhi);
    int named = 0;
    if (parse_clip(o->clip, qlo, qhi, p, &named)) {
        thx_error(ctx, THX_EINPUT, "--clip '%s': a side (anterior, posterior, left, right, superior, inferior[:fraction]) or nx,ny,nz,d", o->clip);
        return -1;
    }
    if (!named) { /* an explicit plane is in the model's axes */
        if (parse_clip(o->clip, lo, hi, p, &named)) return -1;
    } else {
        double n[3] = {p->n[0], p->n[1], p->n[2]};
        from_frame(o, n, p->n);
    }
    return 1;
}

/* The scales of the surfaces with data in b, the main one first, each distinct one once. */
static void collect_bars(const thx_model *m, const built_scene *b, thx_picture_bars *bars)
{
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < b->n; i++) {
            const thx_render_surface *r = &b->rs[i];
            int main = b->main_surface >= 0 && r->surf == m->surf[b->main_surface];
            if (!r->values || (pass == 0) != main) continue;
            int k = 0;
            while (k < bars->n && memcmp(&bars->scale[k], &r->scale, sizeof r->scale)) k++;
            if (k == bars->n) {
                if (bars->n == THX_PICTURE_BARS) continue;
                bars->scale[bars->n++] = r->scale;
            }
            size_t len = strlen(bars->names[k]);
            if (len + strlen(r->surf->name) + 3 < sizeof bars->names[k])
                snprintf(bars->names[k] + len, sizeof bars->names[k] - len, "%s%s", len ? ", " : "", r->surf->name);
        }
}

/* The 3D part of the picture, panel by panel: offscreen into img (r of the picture's size), or
 * into the current framebuffer (img NULL, fb_w x fb_h). */
static thx_status draw_panels(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *rr,
                              thx_font *font, int frame, int fb_w, int fb_h, thx_image *img, thx_picture_bars *bars,
                              size_t *nan_total)
{
    thx_status st = THX_OK;
    const thx_model *m = d->m;
    int vp[4], cols, rows;
    thx_picture_viewport(o, font, fb_w, fb_h, vp);
    n_panels(o, m, &cols, &rows);
    built_scene *b = calloc(1, sizeof *b);
    if (!b) return thx_error(ctx, THX_ENOMEM, "out of memory (scene)");
    int panel = 0;
    memset(bars, 0, sizeof *bars);
    thx_clip_plane clip;
    int n_clip = thx_picture_clip(ctx, o, d, &clip);
    if (n_clip < 0) { free(b); return THX_EINPUT; }
    for (size_t s = 0; s < (o->panels ? m->n_surfaces : 1); s++) {
        int only = o->panels ? (int)s : -1;
        memset(b, 0, sizeof *b);
        build_surfaces(o, d, frame, b, only);
        if (b->n == 0) continue;
        if (!o->panels) {
            thx_status sa = build_arrows(ctx, o, d, frame, b);
            if (sa != THX_OK) { free(b->apos); free(b->avec); free(b); return sa; }
        }
        thx_scene sc;
        memset(&sc, 0, sizeof sc);
        sc.surfaces = b->rs;
        sc.n_surfaces = b->n;
        sc.arrows = b->have_arrows ? &b->arrows : NULL;
        sc.n_arrows = b->have_arrows ? 1 : 0;
        int pw = vp[2] / cols, ph = vp[3] / rows;
        sc.viewport[0] = (panel % cols) * pw;
        sc.viewport[1] = vp[1] + (panel / cols) * ph;
        sc.viewport[2] = pw;
        sc.viewport[3] = ph;
        sc.clear = 1;
        sc.background[0] = BG[0] / 255.0f;
        sc.background[1] = BG[1] / 255.0f;
        sc.background[2] = BG[2] / 255.0f;
        sc.background[3] = 1;
        sc.nan_color[0] = 0.6f;
        sc.nan_color[1] = 0.6f;
        sc.nan_color[2] = 0.2f;
        sc.nan_color[3] = 1;
        thx_picture_camera(o, d, (double)pw / ph, &sc.camera);
        if (n_clip > 0) { sc.clip[0] = clip; sc.n_clip = 1; }
        size_t nn = 0;
        st = img ? thx_render(ctx, rr, &sc, img, &nn) : thx_render_scene_gl(ctx, rr, &sc, fb_w, fb_h, &nn);
        if (nan_total) *nan_total += b->nan_count;
        free(b->apos);
        free(b->avec);
        b->apos = b->avec = NULL;
        if (st != THX_OK) break;
        collect_bars(m, b, bars);
        panel++;
    }
    free(b);
    return st;
}

thx_status thx_picture_annotate(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font,
                                int frame, const thx_picture_bars *bars, thx_image *img)
{
    const thx_model *m = d->m;
    if (!font) return THX_OK;
    int vp[4], cols, rows;
    thx_picture_viewport(o, font, img->w, img->h, vp);
    int vw = vp[2], vh = vp[3], top = vp[1];
    int trace_h = o->trace ? img->h / 5 : 0, bar_w = img->w - vw;
    if (o->panels) {
        n_panels(o, m, &cols, &rows);
        int pw = vw / cols, ph = vh / rows, panel = 0;
        for (size_t s = 0; s < m->n_surfaces; s++) {
            int shown = o->n_only == 0;
            for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
            if (!shown) continue;
            thx_draw_text(img, font, (panel % cols) * pw + 6, top + (panel / cols) * ph + thx_font_height(font) + 2,
                          m->surf[s]->name, FG);
            panel++;
        }
    }
    THX_CHECK(picture_marks(ctx, o, d, font, frame, img));
    const thx_series *any = NULL;
    for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (d->series[s] && (!any || m->surf[s]->role == THX_ROLE_OUTER)) any = d->series[s];
    int shades = o->style == THX_DATA_BANDS || o->style == THX_DATA_BANDS_CONTOURS ? o->levels : 0;
    int any_map = 0; /* the bar of a map of times says so */
    for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (d->series[s] == any && any) any_map = d->map[s][d->active[s]];
    if (o->colorbar && bars->n == 1)
        thx_draw_colorbar(img, font, vw + bar_w / 4, top + vh / 8, bar_w / 4, vh * 3 / 4, o->cmap, &bars->scale[0], shades,
                          5, any_map ? "activation" : "potential", any ? any->unit : "");
    else if (o->colorbar && bars->n > 1) {
        /* one bar per distinct scale, stacked, each titled with its surfaces */
        int slot = vh * 7 / 8 / bars->n, fh = thx_font_height(font);
        for (int k = 0; k < bars->n; k++) {
            const char *unit = "";
            for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
                if (d->series[s] && strstr(bars->names[k], m->surf[s]->name)) unit = d->series[s]->unit;
            int y0 = top + vh / 16 + k * slot + 2 * fh + 4, hh = slot - 3 * fh - 8;
            if (hh < 16) break;
            thx_draw_colorbar(img, font, vw + bar_w / 4, y0, bar_w / 4, hh, o->cmap, &bars->scale[k], shades, hh > 8 * fh ? 5 : 3,
                              bars->names[k], unit);
        }
    }
    if (o->label && any) {
        char text[128];
        size_t f = (size_t)frame < any->n_frames ? (size_t)frame : 0;
        snprintf(text, sizeof text, "t = %g %s   (frame %d of %zu)", any->time[f], any->time_unit, frame + 1, any->n_frames);
        thx_draw_text(img, font, 8, thx_font_height(font) + 2, text, FG);
    }
    if (d->trace) {
        const thx_series *x = d->trace;
        size_t n = x->n_frames;
        double *v = malloc(n * sizeof *v);
        if (!v) return thx_error(ctx, THX_ENOMEM, "out of memory (trace of %zu frames)", n);
        for (size_t f = 0; f < n; f++) v[f] = x->v[f * x->n_rows + d->trace_row];
        double dt = n > 1 ? x->time[1] - x->time[0] : 1;
        unsigned char tc[4] = {120, 230, 120, 255};
        thx_draw_trace(img, font, 8, img->h - trace_h + 4, img->w - 16, trace_h - 8, v, n, x->time[0], dt,
                       (size_t)frame, d->trace_label, x->unit, tc);
        free(v);
    }
    return THX_OK;
}

thx_status thx_picture_draw(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                            thx_font *font, int frame, thx_image *img, size_t *nan_total)
{
    thx_image_fill(img, BG);
    thx_picture_bars bars;
    THX_CHECK(draw_panels(ctx, o, d, r, font, frame, img->w, img->h, img, &bars, nan_total));
    return thx_picture_annotate(ctx, o, d, font, frame, &bars, img);
}

thx_status thx_picture_draw_gl(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                               thx_font *font, int frame, int fb_w, int fb_h, thx_picture_bars *bars, size_t *nan_total)
{
    /* the whole framebuffer in the background colour: the scene's viewport clears only itself */
    thx_scene bgs;
    memset(&bgs, 0, sizeof bgs);
    bgs.viewport[2] = fb_w;
    bgs.viewport[3] = fb_h;
    bgs.clear = 1;
    for (int k = 0; k < 3; k++) bgs.background[k] = BG[k] / 255.0f;
    bgs.background[3] = 1;
    bgs.camera.up[2] = 1;
    bgs.camera.eye[1] = 1;
    bgs.camera.height = 1;
    THX_CHECK(thx_render_scene_gl(ctx, r, &bgs, fb_w, fb_h, NULL));
    return draw_panels(ctx, o, d, r, font, frame, fb_w, fb_h, NULL, bars, nan_total);
}
