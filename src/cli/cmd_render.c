/*
 * thorax render: batch pictures of models and potentials (paper 4.2), headless; the options,
 * data and drawing it shares with thorax animate (cmd_animate.c, cli/render_cli.h).
 */
#include <assert.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "cli/render_cli.h"
#include "thorax/core/fileio.h"
#include "thorax/render/image.h"
#include "thorax/import/import.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/render/render.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
void render_data_free(rdata *d)
{
    for (int s = 0; s < 64; s++) thx_series_destroy(&d->series[s]);
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
static thx_status check_names(thx_ctx *ctx, const ropts *o, const thx_model *m)
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
    return THX_OK;
}

/* --trace: a lead of the solution's 12-lead ECG (I .. V6), or SURFACE:NODE / NODE (1-based) of a
   surface's data (without a surface name: the body surface's data, else the only data there is). */
static thx_status resolve_trace(thx_ctx *ctx, const ropts *o, rdata *d)
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
        for (size_t k = 0; k < d->m->n_surfaces && k < 64; k++)
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
static thx_status surfaces_from_files(thx_ctx *ctx, const ropts *o, thx_model **out)
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
static thx_status apply_channels(thx_ctx *ctx, const char *path, thx_series **sp)
{
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_series *in = *sp, *outs = NULL;
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
        p = strchr(e2, '\n');
        p = p ? p + 1 : e2 + strlen(e2);
    }
done:
    free(text);
    if (st != THX_OK) { thx_series_destroy(&outs); return st; }
    thx_series_destroy(sp);
    *sp = outs;
    return THX_OK;
}

static thx_status load_data(thx_ctx *ctx, const ropts *o, rdata *d)
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
    if (o->data) {
        thx_series *s = NULL;
        THX_CHECK(thx_series_read(ctx, o->data, THX_SERIES_AUTO, &s));
        if (o->channels) {
            thx_status sc = apply_channels(ctx, o->channels, &s);
            if (sc != THX_OK) { thx_series_destroy(&s); return sc; }
        }
        int target = -1;
        if (o->data_surface) {
            target = surface_by_name(d->m, o->data_surface);
            if (target < 0) { thx_series_destroy(&s); return thx_error(ctx, THX_EINPUT, "--data-surface: no surface '%s'", o->data_surface); }
        } else {
            int n = 0;
            for (size_t k = 0; k < d->m->n_surfaces; k++)
                if (d->m->surf[k]->n_nodes == s->n_rows) { target = (int)k; n++; }
            if (n != 1) {
                size_t rows = s->n_rows;
                thx_series_destroy(&s);
                return thx_error(ctx, THX_EINPUT, "%s: %zu rows match %s (give --data-surface NAME)", o->data, rows,
                                 n ? "several surfaces" : "no surface's node count");
            }
        }
        if (d->m->surf[target]->n_nodes != s->n_rows) {
            size_t rows = s->n_rows;
            thx_series_destroy(&s);
            return thx_error(ctx, THX_EINPUT, "%s: %zu rows, surface '%s' has %zu nodes", o->data, rows,
                             d->m->surf[target]->name, d->m->surf[target]->n_nodes);
        }
        thx_series_destroy(&d->series[target]);
        d->series[target] = s;
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
    for (size_t s = 0; s < d->m->n_surfaces && s < 64; s++)
        if (d->series[s] && (size_t)o->frame >= d->series[s]->n_frames && o->last < 0)
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
static void series_range(rdata *d, size_t k, double *lo, double *hi)
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

static void scale_for(const ropts *o, rdata *d, int s, int frame, thx_scale *sc)
{
    double lo = INFINITY, hi = -INFINITY;
    memset(sc, 0, sizeof *sc);
    if (o->scope == SCOPE_FIXED) {
        sc->model = o->model;
        sc->lo = o->lo;
        sc->hi = o->hi;
        sc->k = o->model == THX_SCALE_LOG ? 10 : 3;
        return;
    }
    for (size_t k = 0; k < d->m->n_surfaces && k < 64; k++) {
        const thx_series *x = d->series[k];
        if (!x || (o->scope != SCOPE_ALL && (int)k != s)) continue;
        if (o->scope == SCOPE_FRAME) range_of(x->v + (size_t)frame * x->n_rows, x->n_rows, &lo, &hi);
        else series_range(d, k, &lo, &hi);
    }
    /* the library's one range rule (thorax/render/render.h): symmetric = the largest magnitude */
    thx_scale_from_range(sc, o->model, lo, hi, o->symmetric);
}

static const float palette[6][4] = {{0.85f, 0.75f, 0.65f, 1}, {0.95f, 0.85f, 0.55f, 1}, {0.75f, 0.35f, 0.35f, 1},
                                    {0.55f, 0.65f, 0.85f, 1}, {0.55f, 0.75f, 0.85f, 1}, {0.85f, 0.25f, 0.25f, 1}};

static thx_draw_mode parse_mode(const char *s, int *ok)
{
    static const char *names[] = {"hidden", "points", "wire", "flat", "gouraud", "phong", "orientation"};
    for (int k = 0; k < 7; k++)
        if (!strcmp(s, names[k])) { *ok = 1; return (thx_draw_mode)k; }
    *ok = 0;
    return THX_DRAW_GOURAUD;
}

typedef struct {
    thx_render_surface rs[64];
    size_t n;
    thx_render_arrows arrows;
    double *apos, *avec;
    int have_arrows;
    thx_scale main_scale;
    int main_surface;
    size_t nan_count;
} built_scene;

/* The column of the currents series for a frame of the potentials: matched by time, because
   `thorax forward --currents LIST` writes only the listed frames. -1 if that frame has none. */
long render_currents_column(const rdata *d, int frame)
{
    const thx_series *c = d->currents, *ref = NULL;
    if (!c) return -1;
    for (size_t s = 0; s < d->m->n_surfaces && s < 64; s++)
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
static thx_status build_arrows(thx_ctx *ctx, const ropts *o, const rdata *d, int frame, built_scene *b)
{
    const thx_volume *v = d->m->volume;
    if (!o->arrows) return THX_OK;
    long col = render_currents_column(d, frame);
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

static void build_surfaces(const ropts *o, rdata *d, int frame, built_scene *b, int only_surface)
{
    const thx_model *m = d->m;
    b->n = 0;
    b->main_surface = -1;
    for (size_t s = 0; s < m->n_surfaces && s < 64; s++) {
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
        for (size_t k = 0; k < m->n_surfaces && k < 64; k++) any |= d->series[k] != NULL;
        if (!has && any && o->mode != THX_DRAW_ORIENTATION) {
            /* beside data, colour means potential: the other surfaces in greys (a shade each) */
            float g = 0.82f - 0.08f * (float)(s % 4);
            r->color[0] = r->color[1] = r->color[2] = g;
            if (o->mode != THX_DRAW_WIRE && o->mode != THX_DRAW_POINTS)
                r->color[3] = m->surf[s]->role == THX_ROLE_OUTER ? 0.25f : 0.35f;
        }
        for (int k = 0; k < o->n_whole; k++) r->no_clip |= !strcmp(o->whole[k], m->surf[s]->name);
        const struct surf_look *look = NULL;
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
            r->style = o->style;
            r->n_levels = o->levels;
            r->cmap = o->cmap;
            scale_for(o, d, (int)s, (int)f, &r->scale);
            r->contour_color[3] = 1;
            r->color[3] = look && look->opacity >= 0 ? look->opacity : 1;
            if (b->main_surface < 0 || m->surf[s]->role == THX_ROLE_OUTER) {
                b->main_surface = (int)s;
                b->main_scale = r->scale;
            }
        }
        b->n++;
    }
}

/* "+y", "-z", "x" -> axis index and sign; -1 if not an axis. */
static int parse_axis(const char *s, int *axis, double *sign)
{
    *sign = 1;
    if (*s == '+' || *s == '-') { *sign = *s == '-' ? -1 : 1; s++; }
    if ((*s == 'x' || *s == 'y' || *s == 'z') && !s[1]) { *axis = *s - 'x'; return 0; }
    return -1;
}

/* The anatomical frame: --up (cranial) and --front (anterior) over the model's frame (the model's
   own when it has one, else +z and +y); right = anterior x cranial. */
static int anat_frame(ropts *o, const thx_frame *mf)
{
    int a = mf && mf->set ? mf->front.axis : 1, c = mf && mf->set ? mf->up.axis : 2;
    double sa = mf && mf->set ? mf->front.sign : 1, sc = mf && mf->set ? mf->up.sign : 1;
    if (o->front_spec && parse_axis(o->front_spec, &a, &sa)) return -1;
    if (o->up_spec && parse_axis(o->up_spec, &c, &sc)) return -1;
    if (a == c) return -1;
    int r = 3 - a - c;
    double eps = ((a + 1) % 3 == c) ? 1 : -1; /* e_a x e_c = eps e_r */
    o->ax[0] = r; o->sg[0] = sa * sc * eps;
    o->ax[1] = a; o->sg[1] = sa;
    o->ax[2] = c; o->sg[2] = sc;
    return 0;
}

/* Model box -> the box in the anatomical frame; a vector of the frame -> model coordinates. */
static void box_to_frame(const ropts *o, const double lo[3], const double hi[3], double qlo[3], double qhi[3])
{
    for (int k = 0; k < 3; k++) {
        int a = o->ax[k];
        qlo[k] = o->sg[k] > 0 ? lo[a] : -hi[a];
        qhi[k] = o->sg[k] > 0 ? hi[a] : -lo[a];
    }
}

static void from_frame(const ropts *o, const double q[3], double p[3])
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


thx_status render_frame(thx_ctx *ctx, const ropts *o, rdata *d, thx_renderer *rr, thx_font *font, int frame,
                        thx_image *img, size_t *nan_total)
{
    thx_status st = THX_OK;
    const thx_model *m = d->m;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t s = 0; s < m->n_surfaces; s++)
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], m->surf[s]->xyz[3 * i + k]);
                hi[k] = fmax(hi[k], m->surf[s]->xyz[3 * i + k]);
            }
    unsigned char bg[4] = {24, 24, 28, 255}, fg[4] = {235, 235, 235, 255};
    thx_image_fill(img, bg);
    int trace_h = o->trace ? img->h / 5 : 0, bar_w = o->colorbar ? (img->w / 6 > 96 ? img->w / 6 : 96) : 0;
    int top = o->label ? thx_font_height(font) + 8 : 0;
    int vw = img->w - bar_w, vh = img->h - trace_h - top;
    int panels = 1, cols = 1, rows = 1;
    if (o->panels) {
        panels = 0;
        for (size_t s = 0; s < m->n_surfaces; s++) {
            int shown = o->n_only == 0;
            for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
            panels += shown;
        }
        cols = (int)ceil(sqrt((double)panels));
        rows = (panels + cols - 1) / cols;
    }
    built_scene *b = calloc(1, sizeof *b);
    if (!b) return THX_ENOMEM;
    int panel = 0;
    thx_scale bar_scale = {0};
    int have_bar = 0;
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
        int pw = vw / cols, ph = vh / rows;
        sc.viewport[0] = (panel % cols) * pw;
        sc.viewport[1] = top + (panel / cols) * ph;
        sc.viewport[2] = pw;
        sc.viewport[3] = ph;
        sc.clear = 1;
        sc.background[0] = bg[0] / 255.0f;
        sc.background[1] = bg[1] / 255.0f;
        sc.background[2] = bg[2] / 255.0f;
        sc.background[3] = 1;
        sc.nan_color[0] = 0.6f;
        sc.nan_color[1] = 0.6f;
        sc.nan_color[2] = 0.2f;
        sc.nan_color[3] = 1;
        double qlo[3], qhi[3];
        box_to_frame(o, lo, hi, qlo, qhi);
        if (o->have_camera) sc.camera = o->cam;
        else {
            /* the standard view in the anatomical frame, carried back to the model's axes */
            thx_camera c;
            thx_camera_view(&c, o->view, qlo, qhi, (double)pw / ph);
            sc.camera = c;
            from_frame(o, c.eye, sc.camera.eye);
            from_frame(o, c.center, sc.camera.center);
            from_frame(o, c.up, sc.camera.up);
        }
        if (o->clip[0]) {
            int named = 0;
            if (parse_clip(o->clip, qlo, qhi, &sc.clip[0], &named)) { free(b->apos); free(b->avec); free(b); return thx_error(ctx, THX_EINPUT, "--clip '%s': a side (anterior, posterior, left, right, superior, inferior[:fraction]) or nx,ny,nz,d", o->clip); }
            if (!named) { /* an explicit plane is in the model's axes */
                if (parse_clip(o->clip, lo, hi, &sc.clip[0], &named)) { free(b->apos); free(b->avec); free(b); return THX_EINPUT; }
            } else {
                double n[3] = {sc.clip[0].n[0], sc.clip[0].n[1], sc.clip[0].n[2]};
                from_frame(o, n, sc.clip[0].n);
            }
            sc.n_clip = 1;
        }
        size_t nn = 0;
        st = thx_render(ctx, rr, &sc, img, &nn);
        if (nan_total) *nan_total += b->nan_count;
        free(b->apos);
        free(b->avec);
        b->apos = b->avec = NULL;
        if (st != THX_OK) break;
        if (b->main_surface >= 0 && !have_bar) { bar_scale = b->main_scale; have_bar = 1; }
        if (o->panels && font) {
            const char *name = m->surf[s]->name;
            thx_draw_text(img, font, sc.viewport[0] + 6, sc.viewport[1] + thx_font_height(font) + 2, name, fg);
        }
        panel++;
    }
    free(b);
    if (st != THX_OK) return st;
    /* annotations */
    const thx_series *any = NULL;
    for (size_t s = 0; s < m->n_surfaces && s < 64; s++)
        if (d->series[s] && (!any || m->surf[s]->role == THX_ROLE_OUTER)) any = d->series[s];
    if (o->colorbar && have_bar && font)
        thx_draw_colorbar(img, font, vw + bar_w / 4, top + vh / 8, bar_w / 4, vh * 3 / 4, o->cmap, &bar_scale,
                          o->style == THX_DATA_BANDS || o->style == THX_DATA_BANDS_CONTOURS ? o->levels : 0, 5,
                          "potential", any ? any->unit : "");
    if (o->label && font && any) {
        char text[128];
        size_t f = (size_t)frame < any->n_frames ? (size_t)frame : 0;
        snprintf(text, sizeof text, "t = %g %s   (frame %d of %zu)", any->time[f], any->time_unit, frame + 1, any->n_frames);
        thx_draw_text(img, font, 8, thx_font_height(font) + 2, text, fg);
    }
    if (d->trace && font) {
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

/* ---- the options of render and animate ---- */

/* A positional argument: the model directory, or a surface file (a model of its own surfaces).
 * 0, or -1 for a second directory, a directory beside files, or too many files. */
static int positional(ropts *o, const char *a)
{
    struct stat sb;
    int dir = stat(a, &sb) == 0 && S_ISDIR(sb.st_mode);
    if (dir) {
        if (o->model_dir || o->n_files) return -1;
        o->model_dir = a;
        return 0;
    }
    if (o->model_dir || o->n_files >= 16) return -1;
    o->files[o->n_files++] = a;
    return 0;
}
void render_opts_default(ropts *o)
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
    o->scope = SCOPE_SERIES;
    o->symmetric = 1;
    o->last = -1;
    o->fps = 25;
    o->arrow_spacing = 20;
    o->arrow_scale = 15;
    o->arrow_max = 400;
}

/* --surface NAME=MODE[:OPACITY[:#RRGGBB]]; 0, or 2 after printing the usage error */
static int parse_look(void *user, const cli_opt *opt, const char *spec)
{
    ropts *o = user;
    const char *cmd = o->cmd;
    if (o->n_look >= 16) { cli_usage_error(cmd, "--surface: at most 16"); return 2; }
    struct surf_look *l = &o->look[o->n_look];
    memset(l, 0, sizeof *l);
    l->opacity = -1;
    char buf[160];
    snprintf(buf, sizeof buf, "%s", spec);
    char *eq = strchr(buf, '=');
    if (!eq || eq == buf || eq - buf >= (long)sizeof l->name) {
        cli_usage_error(cmd, "--surface '%s': give NAME=MODE[:OPACITY[:#RRGGBB]]", spec);
        return 2;
    }
    *eq = '\0';
    memcpy(l->name, buf, (size_t)(eq - buf) + 1);
    char *mode = eq + 1, *op = strchr(mode, ':'), *col = NULL;
    if (op) { *op++ = '\0'; col = strchr(op, ':'); if (col) *col++ = '\0'; }
    int ok;
    l->mode = parse_mode(mode, &ok);
    if (!ok) {
        cli_usage_error(cmd, "--surface '%s': mode '%s' is not hidden, points, wire, flat, gouraud, phong or orientation", spec, mode);
        return 2;
    }
    if (op && *op) {
        char *end;
        double a = strtod(op, &end);
        if (*end || !(a >= 0 && a <= 1)) { cli_usage_error(cmd, "--surface '%s': opacity '%s' is not a number in 0..1", spec, op); return 2; }
        l->opacity = (float)a;
    }
    if (col) {
        const char *h = col[0] == '#' ? col + 1 : col;
        unsigned rgb;
        int used = 0;
        if (strlen(h) != 6 || sscanf(h, "%6x%n", &rgb, &used) != 1 || used != 6) {
            cli_usage_error(cmd, "--surface '%s': colour '%s' is not #RRGGBB", spec, col);
            return 2;
        }
        l->color[0] = (float)((rgb >> 16) & 255) / 255.0f;
        l->color[1] = (float)((rgb >> 8) & 255) / 255.0f;
        l->color[2] = (float)(rgb & 255) / 255.0f;
        l->have_color = 1;
    }
    o->n_look++;
    return 0;
}

int render_positional(void *user, const char *a)
{
    ropts *o = user;
    if (positional(o, a)) return cli_usage_error(o->cmd, "'%s': give one model directory, or surface files (at most 16)", a);
    return 0;
}

static int parse_size(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    if (sscanf(v, "%dx%d", &o->w, &o->h) != 2 || o->w < 16 || o->h < 16 || o->w > 8192 || o->h > 8192)
        return cli_usage_error(o->cmd, "--size WxH (16..8192)");
    return 0;
}

static int parse_camera(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    thx_camera *c = &o->cam;
    if (sscanf(v, "%lf,%lf,%lf:%lf,%lf,%lf:%lf,%lf,%lf:%lf", &c->eye[0], &c->eye[1], &c->eye[2], &c->center[0],
               &c->center[1], &c->center[2], &c->up[0], &c->up[1], &c->up[2], &c->fov_deg) != 10)
        return cli_usage_error(o->cmd, "--camera EX,EY,EZ:CX,CY,CZ:UX,UY,UZ:FOV");
    o->have_camera = 1;
    return 0;
}

static int parse_scope(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    if (!strcmp(v, "frame")) o->scope = SCOPE_FRAME;
    else if (!strcmp(v, "series")) o->scope = SCOPE_SERIES;
    else if (!strcmp(v, "all")) o->scope = SCOPE_ALL;
    else if (sscanf(v, "fixed:%lf:%lf", &o->lo, &o->hi) == 2 && o->lo < o->hi) o->scope = SCOPE_FIXED;
    else return cli_usage_error(o->cmd, "--scope: frame, series, all, or fixed:LO:HI");
    return 0;
}

static int parse_clip_option(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    snprintf(o->clip, sizeof o->clip, "%s", v);
    return 0;
}

static int parse_axis_option(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    int axis;
    double sign;
    if (!strcmp(opt->name, "--up")) o->up_spec = v;
    else o->front_spec = v;
    if (parse_axis(v, &axis, &sign)) return cli_usage_error(o->cmd, "%s: an axis: +x, -x, +y, -y, +z or -z", opt->name);
    return 0;
}

static int set_arrows(void *user, const cli_opt *opt, const char *v)
{
    ((ropts *)user)->arrows = "node";
    return 0;
}

static int parse_box(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    double *b = o->box;
    if (sscanf(v, "%lf:%lf:%lf:%lf:%lf:%lf", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) != 6 || b[0] >= b[3] ||
        b[1] >= b[4] || b[2] >= b[5])
        return cli_usage_error(o->cmd, "--arrow-box X0:Y0:Z0:X1:Y1:Z1 (mm, low corner then high)");
    o->have_box = 1;
    return 0;
}

static const cli_choice views[] = {{"anterior", THX_VIEW_ANTERIOR}, {"posterior", THX_VIEW_POSTERIOR},
                                   {"left", THX_VIEW_LEFT},         {"right", THX_VIEW_RIGHT},
                                   {"superior", THX_VIEW_SUPERIOR}, {"inferior", THX_VIEW_INFERIOR},
                                   {NULL, 0}};
static const cli_choice modes[] = {{"hidden", THX_DRAW_HIDDEN}, {"points", THX_DRAW_POINTS},   {"wire", THX_DRAW_WIRE},
                                   {"flat", THX_DRAW_FLAT},     {"gouraud", THX_DRAW_GOURAUD}, {"phong", THX_DRAW_PHONG},
                                   {"orientation", THX_DRAW_ORIENTATION}, {NULL, 0}};
static const cli_choice styles[] = {{"continuous", THX_DATA_CONTINUOUS}, {"bands", THX_DATA_BANDS},
                                    {"contours", THX_DATA_CONTOURS},     {"bands+contours", THX_DATA_BANDS_CONTOURS},
                                    {"continuous+contours", THX_DATA_CONTINUOUS_CONTOURS}, {NULL, 0}};
static const cli_choice cmaps[] = {{"ecg", THX_CMAP_ECG},         {"ecg-green", THX_CMAP_ECG_GREEN},
                                   {"coolwarm", THX_CMAP_COOLWARM}, {"viridis", THX_CMAP_VIRIDIS},
                                   {"gray", THX_CMAP_GRAY},       {"jet", THX_CMAP_JET}, {NULL, 0}};
static const cli_choice scales[] = {{"linear", THX_SCALE_LINEAR}, {"log", THX_SCALE_LOG}, {"exp", THX_SCALE_EXP},
                                    {NULL, 0}};

size_t render_options(cli_opt *t, ropts *o)
{
    size_t n = 0;
    t[n++] = (cli_opt){.name = "--solution", .type = CLI_INPUT, .meta = "DIR", .s = &o->solution,
                       .help = "a thorax forward solution: its model, the torso potentials (and the heart's, when the "
                               "epicardial series is still where the solution says)"};
    t[n++] = (cli_opt){.name = "--data", .type = CLI_INPUT, .meta = "SERIES", .s = &o->data,
                       .help = "per-node values of one surface (rows = its nodes), any series format"};
    t[n++] = (cli_opt){.name = "--data-surface", .type = CLI_STRING, .meta = "NAME", .s = &o->data_surface,
                       .help = "the surface --data belongs to, when several have that many nodes"};
    t[n++] = (cli_opt){.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .s = &o->channels,
                       .help = "map3d .channels: the --data rows are recording channels, node i takes channel c"};
    t[n++] = (cli_opt){.name = "--size", .type = CLI_STRING, .meta = "WxH", .fn = parse_size, .def = "800x800",
                       .unit = "pixels", .help = "image size, 16 to 8192 each"};
    t[n++] = (cli_opt){.name = "--view", .type = CLI_CHOICE, .meta = "V", .choices = views, .i = &o->view,
                       .help = "anterior, posterior, left, right, superior or inferior, in the model's frame"};
    t[n++] = (cli_opt){.name = "--up", .type = CLI_STRING, .meta = "AXIS", .fn = parse_axis_option,
                       .def = "the model's frame, model.json \"frame\"",
                       .help = "the model's cranial axis for the views and clip sides: +x, -x, +y, -y, +z or -z (a "
                               "model without a frame needs --up and --front for a named view or clip side; surface "
                               "files without them are drawn as +z and +y, with a warning)"};
    t[n++] = (cli_opt){.name = "--front", .type = CLI_STRING, .meta = "AXIS", .fn = parse_axis_option,
                       .def = "the model's frame", .help = "the model's anterior axis, as --up"};
    t[n++] = (cli_opt){.name = "--camera", .type = CLI_STRING, .meta = "E:C:U:FOV", .fn = parse_camera,
                       .help = "explicit camera: eye, centre, up (x,y,z each), field of view in degrees (0: "
                               "orthographic)"};
    t[n++] = (cli_opt){.name = "--mode", .type = CLI_CHOICE, .meta = "M", .choices = modes, .i = &o->mode,
                       .help = "hidden, points, wire, flat, gouraud, phong, or orientation (the paper's check: "
                               "triangles only where their outward side faces the viewer, the nodes behind as points)"};
    t[n++] = (cli_opt){.name = "--surface", .type = CLI_STRING, .meta = "NAME=M[:OPACITY[:#RRGGBB]]",
                       .flags = CLI_REPEAT, .fn = parse_look,
                       .help = "one surface's mode (as --mode), opacity and colour (a surface with data keeps the colour "
                               "map); at most 16"};
    t[n++] = (cli_opt){.name = "--only", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = o->only,
                       .count = &o->n_only, .max = 16, .help = "draw only these surfaces"};
    t[n++] = (cli_opt){.name = "--panels", .type = CLI_FLAG, .i = &o->panels, .help = "a grid of panels, one per surface"};
    t[n++] = (cli_opt){.name = "--style", .type = CLI_CHOICE, .meta = "S", .choices = styles, .i = &o->style,
                       .help = "continuous, bands, contours, bands+contours or continuous+contours"};
    t[n++] = (cli_opt){.name = "--levels", .type = CLI_INT, .meta = "N", .i = &o->levels, .rule = CLI_GE | CLI_LE,
                       .lo = 2, .hi = 64, .bad = "--levels: 2..64", .help = "shades / contour levels, 2 to 64"};
    t[n++] = (cli_opt){.name = "--cmap", .type = CLI_CHOICE, .meta = "C", .choices = cmaps, .i = &o->cmap,
                       .help = "ecg (red positive, blue negative, white zero), ecg-green, coolwarm (perceptually "
                               "uniform, diverging), viridis, gray or jet"};
    t[n++] = (cli_opt){.name = "--scale", .type = CLI_CHOICE, .choices = scales, .i = &o->model,
                       .help = "the scaling model from values to colours"};
    t[n++] = (cli_opt){.name = "--scope", .type = CLI_STRING, .meta = "S", .fn = parse_scope, .def = "series",
                       .help = "the range the colours span: frame (this frame), series (all frames of the surface), "
                               "all (all surfaces), or fixed:LO:HI"};
    t[n++] = (cli_opt){.name = "--true-range", .type = CLI_SET, .i = &o->symmetric, .ival = 0,
                       .help = "map min..max instead of a range symmetric about zero"};
    t[n++] = (cli_opt){.name = "--symmetric", .type = CLI_SET, .i = &o->symmetric, .ival = 1,
                       .help = "a range symmetric about zero (the default; undoes --true-range)"};
    t[n++] = (cli_opt){.name = "--clip", .type = CLI_STRING, .meta = "SIDE[:F]|PLANE", .fn = parse_clip_option,
                       .help = "remove a side (anterior, posterior, left, right, superior, inferior) from fraction F of "
                               "the depth (default 0.5), or cut by a plane nx,ny,nz,d (keeps n.x + d >= 0)"};
    t[n++] = (cli_opt){.name = "--no-clip", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = o->whole,
                       .count = &o->n_whole, .max = 16,
                       .help = "this surface is left whole by the clip plane (e.g. the heart inside an opened chest)"};
    t[n++] = (cli_opt){.name = "--colorbar", .type = CLI_FLAG, .i = &o->colorbar,
                       .help = "a colour bar with values, title and unit"};
    t[n++] = (cli_opt){.name = "--label", .type = CLI_FLAG, .i = &o->label, .help = "the time and frame"};
    t[n++] = (cli_opt){.name = "--trace", .type = CLI_STRING, .meta = "T", .s = &o->trace,
                       .help = "a signal under the picture with a marker at the frame: an ECG lead (I..V6, from the "
                               "solution's ecg12), or SURFACE:NODE / NODE (1-based) of the data"};
    t[n++] = (cli_opt){.name = "--arrows", .type = CLI_FLAG, .fn = set_arrows,
                       .help = "current density arrows (the solution's currents_node, for the frame shown)"};
    t[n++] = (cli_opt){.name = "--arrow-spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->arrow_spacing,
                       .rule = CLI_GE, .bad = "--arrow-spacing must be 0 (one arrow per node) or positive (mm)",
                       .note = "0: one arrow per node", .help = "arrows averaged on a grid of this spacing"};
    t[n++] = (cli_opt){.name = "--arrow-gap", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->arrow_gap,
                       .rule = CLI_GE, .bad = "--arrow-gap must be 0 or positive (mm)", .note = "0: none",
                       .help = "no arrow closer than this to a stronger one"};
    t[n++] = (cli_opt){.name = "--arrow-max", .type = CLI_INT, .meta = "N", .i = &o->arrow_max, .rule = CLI_GE, .lo = 1,
                       .bad = "--arrow-max must be at least 1", .help = "at most N arrows, the strongest"};
    t[n++] = (cli_opt){.name = "--arrow-length", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->arrow_scale,
                       .rule = CLI_GT, .bad = "--arrow-length must be positive (mm)",
                       .help = "the longest arrow's length (lengths proportional to magnitude)"};
    t[n++] = (cli_opt){.name = "--arrow-unit", .type = CLI_FLAG, .i = &o->arrow_unit,
                       .help = "every arrow the same length, coloured by magnitude"};
    t[n++] = (cli_opt){.name = "--arrow-region", .type = CLI_STRING, .meta = "NAME", .s = &o->arrow_region,
                       .help = "arrows only at nodes of this tissue region"};
    t[n++] = (cli_opt){.name = "--arrow-box", .type = CLI_STRING, .meta = "X0:Y0:Z0:X1:Y1:Z1", .unit = "mm",
                       .fn = parse_box, .help = "arrows only inside this box, low corner then high"};
    t[n++] = (cli_opt){.name = "--font", .type = CLI_INPUT, .meta = "FILE", .s = &o->font,
                       .def = "sans-serif, through fontconfig", .help = "a TrueType font for the annotations"};
    t[n++] = (cli_opt){.name = "-v", .type = CLI_SET, .i = &o->verbose, .ival = 1, .flags = CLI_NOUSAGE,
                       .help = "more logging"};
    t[n++] = (cli_opt){.name = "-q", .type = CLI_SET, .i = &o->verbose, .ival = -1, .flags = CLI_NOUSAGE,
                       .help = "less logging"};
    assert(n <= N_RENDER_OPTS);
    return n;
}

/* The views' frame: --up/--front over the model's frame. A model without a frame is refused for a
   named view (no --camera) or a named clip side unless both are given; loose surface files have no
   model and are drawn in +z/+y with a warning. */
static thx_status view_frame(thx_ctx *ctx, ropts *o, const rdata *d)
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

thx_status render_setup(thx_ctx *ctx, ropts *o, rdata *d, thx_renderer **rr, thx_font **font, thx_image **img)
{
    memset(d, 0, sizeof *d);
    THX_CHECK(load_data(ctx, o, d));
    THX_CHECK(view_frame(ctx, o, d));
    THX_CHECK(thx_renderer_create(ctx, o->w, o->h, rr));
    THX_CHECK(thx_image_create(ctx, o->w, o->h, img));
    if (o->colorbar || o->label || o->trace || o->panels) THX_CHECK(thx_font_open(ctx, o->font, o->h / 40 > 11 ? o->h / 40 : 11, font));
    return THX_OK;
}

static int cmp_dbl(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

int cmd_render(int argc, char **argv)
{
    ropts o;
    render_opts_default(&o);
    o.cmd = "render";
    int repeat = 1, frame = 1;
    cli_opt own[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "IMAGE.png", .s = &o.out,
         .help = "the picture (PNG)"},
        {.name = "--frame", .type = CLI_INT, .meta = "K", .i = &frame, .rule = CLI_GE, .lo = 1, .bad = "--frame: 1, 2, ...",
         .help = "the frame, 1-based"},
        {.name = "--repeat", .type = CLI_INT, .meta = "N", .i = &repeat, .rule = CLI_GE | CLI_LE, .lo = 1, .hi = 10000,
         .bad = "--repeat: 1..10000", .help = "draw N times and print the median time a frame (benchmarks)"},
    };
    cli_opt common[N_RENDER_OPTS];
    cli_command cmd = {
        .name = "render",
        .usage = "MODEL [--data [--data-surface]] [--frame] -o [options]\n"
                 "--solution [--frame] -o [options]\n"
                 "SURFACE_FILE... [--data [--channels]] [--frame] -o [options]",
        .about = "Draws the model's surfaces, headless (EGL, OpenGL 3.3; Mesa's llvmpipe without a\n"
                 "GPU), with potentials coloured per pixel (the value interpolated, then the colour\n"
                 "looked up, so bands and contours are exact), following the field's display\n"
                 "conventions (paper 4.2).\n",
        .group = {{NULL, own, sizeof own / sizeof own[0]}, {"what is drawn, and how", common, render_options(common, &o)}},
        .positional = render_positional,
        .user = &o,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    o.frame = frame - 1;
    if (!o.model_dir && !o.n_files && !o.solution) return cli_usage_error("render", "no model, surface file or --solution given");
    if (!o.out) return cli_usage_error("render", "no output image given (-o IMAGE.png)");
    thx_ctx *ctx = cli_ctx(o.verbose);
    rdata d;
    thx_renderer *rr = NULL;
    thx_font *font = NULL;
    thx_image *img = NULL;
    size_t nan = 0;
    double t0 = thx_wtime();
    thx_status st = render_setup(ctx, &o, &d, &rr, &font, &img);
    double *times = malloc((size_t)repeat * sizeof *times);
    if (!times) st = THX_ENOMEM;
    for (int k = 0; k < repeat && st == THX_OK; k++) { /* --repeat: the same frame again, timed (benchmarks) */
        double t1 = thx_wtime();
        nan = 0;
        st = render_frame(ctx, &o, &d, rr, font, o.frame, img, &nan);
        times[k] = thx_wtime() - t1;
    }
    if (st == THX_OK) st = thx_image_write_png(ctx, img, o.out);
    if (st == THX_OK && repeat > 1 && o.verbose >= 0) {
        qsort(times, (size_t)repeat, sizeof *times, cmp_dbl);
        printf("render: %d repetitions, median %.1f ms a frame (min %.1f, max %.1f), %.1f frames per second\n", repeat,
               1000 * times[repeat / 2], 1000 * times[0], 1000 * times[repeat - 1], 1.0 / times[repeat / 2]);
    }
    free(times);
    int rc = 0;
    if (st != THX_OK) rc = cli_fail(ctx, "render", st);
    else {
        if (nan) thx_log(ctx, THX_LOG_WARN, "%zu values are not numbers (drawn in the NaN colour)", nan);
        if (o.verbose >= 0) printf("wrote %s (%dx%d, %.3f s; %s)\n", o.out, o.w, o.h, thx_wtime() - t0, thx_renderer_info(rr));
    }
    thx_image_destroy(&img);
    thx_font_close(&font);
    thx_renderer_destroy(&rr);
    render_data_free(&d);
    thx_ctx_destroy(&ctx);
    return rc;
}
