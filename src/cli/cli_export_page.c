/*
 * thorax export --format html: the picture `thorax render` draws from the same options, as one
 * self-contained interactive web page (issue 29; docs/design/web.md). The picture module loads the
 * model and the data and says how each surface is drawn (thx_picture_surface_looks); here that is
 * written down as the page's description and blobs (thorax/web/page.h): geometry, normals, the
 * potentials quantized to 16 bits, the colour maps and scales, the camera of every standard view,
 * the leads and the electrodes.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_export.h"
#include "cli/render_cli.h"
#include "thorax/capi/capi.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/web/page.h"

#define CMAP_N 1024 /* texels of a colour map's table: render's (src/render/render_shaders.c) */

static const char *const VIEWS[6] = {"anterior", "posterior", "left", "right", "superior", "inferior"};
static const char *const LEAD12[12] = {"I", "II", "III", "aVR", "aVL", "aVF", "V1", "V2", "V3", "V4", "V5", "V6"};

typedef struct {
    ropts r;
    const char *title, *leads;
} page_opts;

static cJSON *vec3(const double v[3])
{
    return cJSON_CreateDoubleArray(v, 3);
}

static cJSON *rgba(const float c[4])
{
    double d[4] = {c[0], c[1], c[2], c[3]};
    return cJSON_CreateDoubleArray(d, 4);
}

static const char *mode_name(thx_draw_mode m)
{
    switch (m) {
    case THX_DRAW_HIDDEN: return "hidden";
    case THX_DRAW_WIRE: return "wire";
    case THX_DRAW_FLAT: return "flat";
    case THX_DRAW_PHONG: return "phong";
    default: return "gouraud";
    }
}

static const char *style_name(int s)
{
    switch (s) {
    case THX_DATA_BANDS: return "bands";
    case THX_DATA_CONTOURS: return "contours";
    case THX_DATA_BANDS_CONTOURS: return "bands+contours";
    case THX_DATA_CONTINUOUS_CONTOURS: return "continuous+contours";
    default: return "continuous";
    }
}

/* What the page cannot show of render's options: refused with the reason, before anything is read. */
static int refuse_unsupported(const page_opts *o)
{
    const thx_picture_opts *p = &o->r.p;
    const char *what = p->clip[0]        ? "--clip"
                       : p->panels       ? "--panels"
                       : p->arrows       ? "--arrows"
                       : p->tetrahedra   ? "--tetrahedra"
                       : p->n_landmarks  ? "--landmarks"
                       : p->n_labels     ? "--node-labels"
                       : p->extrema      ? "--extrema"
                       : p->trace        ? "--trace"
                       : p->renderer     ? "--renderer trace"
                       : p->volume_render ? "--volume"
                                         : NULL;
    if (!what) return 0;
    return cli_usage_error("export", "%s: not in the web page (it draws the model's surfaces with their potentials, the "
                           "leads, a picked node's signal, the electrodes, and the equipotentials, slices, streamlines and "
                           "scan planes of the frame shown first; --trace's leads are the page's own plot)", what);
}

/* The knots of t(v) for a scale: exact for linear scales (their ends, and zero where a separate
   mapping bends), sampled for log and exp, the levels for lab scales; ascending in v. */
static size_t scale_knots(const thx_scale *sc, int levels, double *v, double *t, size_t max)
{
    double a = thx_scale_invert(sc, 0), b = thx_scale_invert(sc, 1);
    double lo = fmin(a, b), hi = fmax(a, b);
    size_t n = 0;
    if (!(hi > lo) || !isfinite(lo) || !isfinite(hi)) { /* a step at the centre */
        double c = isfinite(a) ? a : 0;
        double eps = fmax(fabs(c), 1) * 1e-12;
        v[0] = c - eps, v[1] = c + eps;
        t[0] = thx_scale_apply(sc, v[0]), t[1] = thx_scale_apply(sc, v[1]);
        return 2;
    }
    size_t samples = sc->model == THX_SCALE_LOG || sc->model == THX_SCALE_EXP ? 1024 : 1;
    double lv[64];
    int nl = sc->model == THX_SCALE_LAB7 || sc->model == THX_SCALE_LAB13 ? thx_scale_levels(sc, levels, lv, 64) : 0;
    if (nl > 64) nl = 64;
    for (size_t k = 0; k <= samples && n < max; k++) v[n++] = lo + (hi - lo) * (double)k / (double)samples;
    if (sc->mapping == THX_MAPPING_SEPARATE && lo < 0 && hi > 0 && n < max) v[n++] = 0; /* its bend */
    for (int k = 0; k < nl && n < max; k++)
        if (lv[k] > lo && lv[k] < hi) v[n++] = lv[k];
    /* sort (insertion: few unsorted at the end) and drop repeats */
    for (size_t i = 1; i < n; i++)
        for (size_t j = i; j > 0 && v[j - 1] > v[j]; j--) {
            double x = v[j];
            v[j] = v[j - 1];
            v[j - 1] = x;
        }
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (!m || v[i] > v[m - 1]) v[m++] = v[i];
    for (size_t i = 0; i < m; i++) t[i] = thx_scale_apply(sc, v[i]);
    return m;
}

static int same_scale(const thx_scale *a, const thx_scale *b)
{
    return a->model == b->model && a->mapping == b->mapping && a->lo == b->lo && a->hi == b->hi && a->k == b->k;
}

/* The scale of surface k at every frame (one when they are all the same). */
typedef struct {
    thx_scale *sc;
    size_t n;
} scales;

static thx_status blob(thx_ctx *ctx, thx_web_page *pg, const char *type, const void *data, size_t count, size_t size,
                       cJSON *into, const char *key)
{
    int k;
    THX_CHECK(thx_web_page_blob(ctx, pg, type, data, count, size, 1, &k));
    cJSON_AddNumberToObject(into, key, k);
    return THX_OK;
}

/* Geometry of a surface: points, triangles, render's unit normals (area-weighted sums). */
static thx_status surface_geometry(thx_ctx *ctx, thx_web_page *pg, const thx_surface *s, cJSON *js)
{
    size_t nn = s->n_nodes, nt = s->n_tris;
    float *xyz = malloc((3 * nn + 1) * sizeof *xyz), *nrm = malloc((3 * nn + 1) * sizeof *nrm);
    double *acc = calloc(3 * nn + 1, sizeof *acc);
    uint32_t *tri = malloc((3 * nt + 1) * sizeof *tri);
    thx_status st = THX_OK;
    if (!xyz || !nrm || !acc || !tri) st = thx_error(ctx, THX_ENOMEM, "export: out of memory (surface \"%s\")", s->name);
    if (st == THX_OK) {
        thx_surface_normal_sums(s, acc);
        for (size_t i = 0; i < 3 * nt; i++) tri[i] = (uint32_t)s->tri[i];
    }
    for (size_t i = 0; st == THX_OK && i < nn; i++) {
        const double *n = acc + 3 * i;
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) {
            xyz[3 * i + (size_t)k] = (float)s->xyz[3 * i + (size_t)k];
            nrm[3 * i + (size_t)k] = l > 0 ? (float)(n[k] / l) : (k == 2 ? 1.0f : 0.0f);
        }
    }
    if (st == THX_OK) st = blob(ctx, pg, "float32", xyz, 3 * nn, sizeof *xyz, js, "points");
    if (st == THX_OK) st = blob(ctx, pg, "uint32", tri, 3 * nt, sizeof *tri, js, "indices");
    if (st == THX_OK) st = blob(ctx, pg, "float32", nrm, 3 * nn, sizeof *nrm, js, "normals");
    free(xyz);
    free(nrm);
    free(acc);
    free(tri);
    return st;
}

/* A surface's data: the codes, the range, the scales' knots, the colour bar's ticks. */
static thx_status surface_data(thx_ctx *ctx, thx_web_page *pg, const double *v, size_t n_rows, size_t n_frames,
                               const scales *S, const thx_render_surface *rs, int cmap, const char *quantity,
                               const char *unit, cJSON *jd, double *max_error)
{
    const int levels = rs->n_levels;
    thx_web_quant q;
    THX_CHECK(thx_web_quantize(ctx, v, n_rows, n_frames, &q));
    thx_status st = THX_OK;
    double err = thx_web_quant_error(&q, v);
    if (!(err <= q.step / 2 * (1 + 1e-9) + 1e-300))
        st = thx_error(ctx, THX_EINTERNAL, "export: the quantized values are %g from the data, more than half a step (%g)",
                       err, q.step / 2);
    thx_web_delta_encode(q.codes, q.n_rows, q.n_frames);
    if (st == THX_OK) st = blob(ctx, pg, "uint16", q.codes, q.n_rows * q.n_frames, sizeof *q.codes, jd, "values");
    cJSON_AddStringToObject(jd, "encoding", "u16-delta");
    cJSON_AddNumberToObject(jd, "origin", q.origin);
    cJSON_AddNumberToObject(jd, "step", q.step);
    cJSON_AddNumberToObject(jd, "max_error", q.step / 2);
    cJSON_AddNumberToObject(jd, "measured_error", err);
    if (q.min <= q.max) {
        cJSON_AddNumberToObject(jd, "min", q.min);
        cJSON_AddNumberToObject(jd, "max", q.max);
    } else {
        cJSON_AddNullToObject(jd, "min");
        cJSON_AddNullToObject(jd, "max");
    }
    cJSON_AddNumberToObject(jd, "nan_values", (double)q.n_nan);
    cJSON_AddNumberToObject(jd, "colormap", cmap);
    *max_error = fmax(*max_error, q.step / 2);
    thx_web_quant_free(&q);
    /* the scales: knots for each */
    enum { KMAX = 1100 };
    double *kv = malloc(KMAX * sizeof *kv), *kt = malloc(KMAX * sizeof *kt);
    size_t kn = 0;
    double *knots = NULL;
    if (st == THX_OK && (!kv || !kt)) st = thx_error(ctx, THX_ENOMEM, "export: out of memory");
    for (size_t f = 0; st == THX_OK && f < S->n; f++) {
        size_t n = scale_knots(&S->sc[f], levels, kv, kt, KMAX);
        if (!knots) {
            kn = n;
            knots = malloc(2 * kn * S->n * sizeof *knots);
            if (!knots) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); break; }
        }
        if (n != kn) { /* frames whose lab scales have other level counts: resampled to the first's count */
            st = thx_error(ctx, THX_EINPUT, "export: the colour scale changes its number of levels from frame to frame "
                           "(--scope frame with a lab scale): give --scope series or fixed");
            break;
        }
        memcpy(knots + 2 * kn * f, kv, kn * sizeof *kv);
        memcpy(knots + 2 * kn * f + kn, kt, kn * sizeof *kt);
    }
    if (st == THX_OK) st = blob(ctx, pg, "float64", knots, 2 * kn * S->n, sizeof *knots, jd, "knots");
    cJSON_AddNumberToObject(jd, "knots_n", (double)kn);
    cJSON *js = cJSON_AddObjectToObject(jd, "scale");
    const thx_scale *s0 = &S->sc[0];
    cJSON_AddStringToObject(js, "model", thx_scale_model_name(s0->model));
    cJSON_AddStringToObject(js, "mapping", thx_scale_mapping_name(s0->mapping));
    cJSON_AddNumberToObject(js, "lo", s0->lo);
    cJSON_AddNumberToObject(js, "hi", s0->hi);
    cJSON_AddNumberToObject(js, "frames", (double)S->n);
    /* the colour bar's ticks (of the first scale): the ends, the band boundaries when few, the middle */
    double ticks[40];
    int nt = 0;
    ticks[nt++] = thx_scale_invert(s0, 0);
    int nlev = thx_scale_levels(s0, levels, ticks + 1, 30);
    if (nlev > 0 && nlev <= 30) nt += nlev;
    else ticks[nt++] = thx_scale_invert(s0, 0.5);
    ticks[nt++] = thx_scale_invert(s0, 1);
    for (int i = 1; i < nt; i++) /* ascending */
        for (int j = i; j > 0 && ticks[j - 1] > ticks[j]; j--) {
            double t = ticks[j];
            ticks[j] = ticks[j - 1];
            ticks[j - 1] = t;
        }
    cJSON_AddItemToObject(jd, "ticks", cJSON_CreateDoubleArray(ticks, nt));
    cJSON_AddStringToObject(jd, "quantity", quantity);
    cJSON_AddStringToObject(jd, "unit", unit);
    /* the surface's data style (--surface NAME=bands...) and its bands (a lab scale's own count) */
    cJSON *sty = cJSON_AddObjectToObject(jd, "style");
    cJSON_AddStringToObject(sty, "kind", style_name(rs->style));
    cJSON_AddNumberToObject(sty, "levels", thx_scale_bands(&rs->scale, rs->n_levels));
    free(kv);
    free(kt);
    free(knots);
    return st;
}

/* The leads: --leads FILE (its electrodes' signals, or the 12-lead ECG when it holds RA, LA, LL and
   V1..V6), else the solution's ecg12 file (the picture's, d->ecg), else the 12-lead ECG of the
   model's electrodes/12lead.txt; all from the outer surface's series. *out: the leads (NULL: none),
   *made what of them the caller frees. */
static thx_status leads_of(thx_ctx *ctx, const page_opts *o, const thx_picture_data *d, const thx_series *outer_series,
                           const thx_surface *outer, const thx_series **out, thx_series **made, thx_electrodes **elec,
                           int *twelve)
{
    *out = NULL;
    *made = NULL;
    *elec = NULL;
    *twelve = 0;
    char path[4400];
    const char *file = o->leads;
    if (!file && d->ecg) {
        *out = d->ecg;
        *twelve = 1;
    }
    if (!file && d->model_dir[0]) {
        snprintf(path, sizeof path, "%s/electrodes/12lead.txt", d->model_dir);
        if (access(path, R_OK) == 0) file = path;
    }
    if (!file) return THX_OK;
    THX_CHECK(thx_electrodes_read(ctx, file, elec));
    if (!outer || !outer_series || strcmp((*elec)->surface, outer->name) != 0) {
        if (o->leads)
            return thx_error(ctx, THX_EINPUT, "--leads %s: its electrodes are on surface \"%s\", which has no data here",
                             file, (*elec)->surface);
        return THX_OK; /* the model's electrodes without data on their surface: shown, no leads */
    }
    if (!(*elec)->placed) THX_CHECK(thx_electrodes_place(ctx, *elec, d->m, 10.0, NULL));
    if (*out) return THX_OK; /* the solution's own ECG, the electrodes shown */
    static const char *const TWELVE_AT[9] = {"RA", "LA", "LL", "V1", "V2", "V3", "V4", "V5", "V6"};
    int have = 0;
    for (int k = 0; k < 9; k++) {
        int found = 0;
        for (size_t i = 0; i < (*elec)->n; i++) found |= !strcmp((*elec)->name[i], TWELVE_AT[k]);
        have += found;
    }
    *twelve = have == 9;
    THX_CHECK(have == 9 ? thx_ecg12(ctx, *elec, outer_series, made) : thx_electrodes_sample(ctx, *elec, outer_series, made));
    *out = *made;
    return THX_OK;
}

/* A surface's entry in the description as render draws it (rs): name, role, sizes, geometry, mode,
   colour, visibility and opacity; *out for what the caller adds (its data, a layer's frame). */
static thx_status surface_head(thx_ctx *ctx, thx_web_page *pg, const thx_render_surface *rs, const char *role,
                               cJSON *jsurf, cJSON **out)
{
    const thx_surface *s = rs->surf;
    cJSON *x = cJSON_CreateObject();
    cJSON_AddItemToArray(jsurf, x);
    *out = x;
    cJSON_AddStringToObject(x, "name", s->name);
    cJSON_AddStringToObject(x, "role", role);
    cJSON_AddNumberToObject(x, "nodes", (double)s->n_nodes);
    cJSON_AddNumberToObject(x, "triangles", (double)s->n_tris);
    THX_CHECK(surface_geometry(ctx, pg, s, x));
    cJSON_AddStringToObject(x, "mode", mode_name(rs->mode));
    float c[4] = {rs->color[0], rs->color[1], rs->color[2], 1};
    if (!c[0] && !c[1] && !c[2]) c[0] = c[1] = c[2] = 0.8f; /* render's light grey */
    cJSON_AddItemToObject(x, "color", rgba(c));
    cJSON_AddBoolToObject(x, "visible", rs->mode != THX_DRAW_HIDDEN);
    cJSON_AddNumberToObject(x, "opacity", rs->color[3]);
    return THX_OK;
}

/* The page's index of colour map c, its table added at its first use. */
static thx_status colormap_index(thx_ctx *ctx, thx_web_page *pg, cJSON *cms, thx_colormap c, int *index, int *n, int *out)
{
    int k = (int)c >= 0 && (int)c < 64 ? (int)c : 0;
    if (index[k] < 0) {
        unsigned char table[3 * CMAP_N];
        thx_colormap_table((thx_colormap)k, CMAP_N, table);
        cJSON *cm = cJSON_CreateObject();
        cJSON_AddItemToArray(cms, cm);
        cJSON_AddStringToObject(cm, "name", thx_colormap_name((thx_colormap)k));
        cJSON_AddNumberToObject(cm, "n", CMAP_N);
        THX_CHECK(blob(ctx, pg, "uint8", table, 3 * CMAP_N, 1, cm, "blob"));
        index[k] = (*n)++;
    }
    *out = index[k];
    return THX_OK;
}

static thx_status build(thx_ctx *ctx, page_opts *o, thx_picture_data *d, const char *out, size_t *bytes, size_t *nblobs,
                        double *max_err, char *unit, size_t unit_size)
{
    thx_picture_opts *p = &o->r.p;
    const thx_model *m = d->m;
    size_t ns = m->n_surfaces < THX_PICTURE_SURFACES ? m->n_surfaces : THX_PICTURE_SURFACES;
    /* the time axis: the outer surface's series, else the first with data */
    const thx_series *axis = NULL;
    int outer = -1;
    for (size_t s = 0; s < ns; s++) {
        if (m->surf[s]->role == THX_ROLE_OUTER && outer < 0) outer = (int)s;
        if (d->series[s] && (!axis || m->surf[s]->role == THX_ROLE_OUTER)) axis = d->series[s];
    }
    for (size_t s = 0; s < ns; s++)
        if (d->series[s] && axis && d->series[s]->n_frames != axis->n_frames)
            return thx_error(ctx, THX_EINPUT, "export: surface \"%s\" has %zu frames of data, \"%s\"'s has %zu: the page "
                             "steps through one time axis", m->surf[s]->name, d->series[s]->n_frames,
                             m->surf[outer >= 0 && d->series[outer] ? outer : (int)s]->name, axis->n_frames);
    size_t M = axis ? axis->n_frames : 1;
    thx_render_surface *looks = calloc(ns + 1, sizeof *looks);
    scales *S = calloc(ns + 1, sizeof *S);
    thx_web_page *pg = NULL;
    cJSON *j = cJSON_CreateObject();
    const thx_series *leads = NULL;
    thx_series *leads_made = NULL;
    thx_electrodes *elec = NULL;
    char *text = NULL;
    thx_status st = THX_OK;
    if (!looks || !S || !j) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
    THX_TRY(thx_web_page_create(ctx, &pg));
    size_t nl = thx_picture_surface_looks(p, d, 0, looks, ns);
    /* every frame's scale of each surface with data (one kept when they are all the same) */
    for (size_t i = 0; i < nl; i++) {
        if (!looks[i].values) continue;
        if (!(S[i].sc = malloc(M * sizeof *S[i].sc))) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
        S[i].sc[0] = looks[i].scale;
        S[i].n = 1;
    }
    thx_render_surface *lf = calloc(ns + 1, sizeof *lf);
    if (!lf) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
    for (size_t f = 1; f < M && (p->scope == THX_SCOPE_FRAME || p->scope == THX_SCOPE_SURFACES); f++) {
        size_t n2 = thx_picture_surface_looks(p, d, (int)f, lf, ns);
        for (size_t i = 0; i < nl && i < n2; i++)
            if (S[i].sc) S[i].sc[f] = lf[i].scale;
    }
    if (p->scope == THX_SCOPE_FRAME || p->scope == THX_SCOPE_SURFACES)
        for (size_t i = 0; i < nl; i++) {
            if (!S[i].sc) continue;
            int all_same = 1;
            for (size_t f = 1; f < M; f++) all_same &= same_scale(&S[i].sc[f], &S[i].sc[0]);
            S[i].n = all_same ? 1 : M;
        }
    free(lf);

    /* the description */
    char title[8400];
    if (o->title) snprintf(title, sizeof title, "%s", o->title);
    else snprintf(title, sizeof title, "thorax: %s%s%s", d->model_dir[0] ? d->model_dir : p->n_files ? p->files[0] : "model",
                  p->solution ? ", solution " : "", p->solution ? p->solution : "");
    cJSON_AddStringToObject(j, "format", "thorax-page");
    cJSON_AddNumberToObject(j, "version", 1);
    cJSON_AddStringToObject(j, "title", title);
    char gen[64];
    snprintf(gen, sizeof gen, "thorax %s", thx_capi_version());
    cJSON_AddStringToObject(j, "generator", gen);
    cJSON *src = cJSON_AddObjectToObject(j, "source");
    if (d->model_dir[0]) cJSON_AddStringToObject(src, "model", d->model_dir);
    else if (p->n_files) cJSON_AddStringToObject(src, "model", p->files[0]);
    else cJSON_AddNullToObject(src, "model");
    if (p->solution) cJSON_AddStringToObject(src, "solution", p->solution);
    else cJSON_AddNullToObject(src, "solution");
    if (p->n_data) cJSON_AddStringToObject(src, "data", p->data[0]);
    else cJSON_AddNullToObject(src, "data");
    cJSON_AddNumberToObject(j, "frames", (double)M);
    double *time = malloc(M * sizeof *time);
    if (!time) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
    for (size_t f = 0; f < M; f++) time[f] = axis ? axis->time[f] : 0;
    cJSON_AddItemToObject(j, "time", cJSON_CreateDoubleArray(time, (int)M));
    free(time);
    cJSON_AddStringToObject(j, "time_unit", axis && axis->time_unit[0] ? axis->time_unit : "ms");
    cJSON_AddStringToObject(j, "unit", axis && axis->unit[0] ? axis->unit : "mV");
    cJSON_AddNumberToObject(j, "initial_frame", o->r.frame < (int)M ? o->r.frame : 0);
    double size[2] = {p->w, p->h};
    cJSON_AddItemToObject(j, "size", cJSON_CreateDoubleArray(size, 2));
    float bg[4], nan_c[4];
    thx_picture_colors(bg, nan_c); /* render's */
    cJSON_AddItemToObject(j, "background", rgba(bg));
    cJSON_AddItemToObject(j, "nan_color", rgba(nan_c));
    cJSON *light = cJSON_AddObjectToObject(j, "light");
    cJSON_AddNumberToObject(light, "ka", 0.25);
    cJSON_AddNumberToObject(light, "kd", 0.75);
    cJSON_AddNumberToObject(light, "ks", 0.2);
    cJSON_AddNumberToObject(light, "shine", 40);
    cJSON *style = cJSON_AddObjectToObject(j, "style");
    cJSON_AddStringToObject(style, "kind", style_name(p->style));
    cJSON_AddNumberToObject(style, "levels", p->levels);
    const float black[4] = {0, 0, 0, 1};
    cJSON_AddItemToObject(style, "contour_color", rgba(black));
    cJSON_AddNumberToObject(style, "line_width", 1.5);
    /* the colour maps, each once, in the order the surfaces first use them */
    cJSON *cms = cJSON_AddArrayToObject(j, "colormaps");
    int cmap_index[64];
    for (int k = 0; k < 64; k++) cmap_index[k] = -1;
    int n_cmaps = 0;
    /* the cameras: render's at the page's size, and every standard view's with its extents (the camera
       for another aspect w/h is the same with height = 1.1 max(ev, eh / aspect)) */
    thx_camera cam;
    thx_picture_camera(p, d, (double)p->w / p->h, &cam);
    cJSON *jc = cJSON_AddObjectToObject(j, "camera");
    cJSON_AddItemToObject(jc, "eye", vec3(cam.eye));
    cJSON_AddItemToObject(jc, "center", vec3(cam.center));
    cJSON_AddItemToObject(jc, "up", vec3(cam.up));
    cJSON_AddNumberToObject(jc, "height", cam.height);
    cJSON_AddNumberToObject(jc, "fov_deg", cam.fov_deg);
    cJSON *jv = cJSON_AddObjectToObject(j, "views");
    for (int v = 0; v < 6; v++) {
        thx_camera wide, tall;
        thx_picture_view_camera(p, d, v, 1e12, &wide); /* height = 1.1 ev */
        thx_picture_view_camera(p, d, v, 1e-12, &tall); /* height = 1.1 eh / 1e-12 */
        cJSON *x = cJSON_AddObjectToObject(jv, VIEWS[v]);
        cJSON_AddItemToObject(x, "eye", vec3(wide.eye));
        cJSON_AddItemToObject(x, "center", vec3(wide.center));
        cJSON_AddItemToObject(x, "up", vec3(wide.up));
        double ext[2] = {tall.height * 1e-12 / 1.1, wide.height / 1.1};
        cJSON_AddItemToObject(x, "extent", cJSON_CreateDoubleArray(ext, 2));
    }
    cJSON_AddStringToObject(j, "view", VIEWS[p->view >= 0 && p->view < 6 ? p->view : 0]);
    cJSON *fr = cJSON_AddObjectToObject(j, "frame");
    cJSON_AddItemToObject(fr, "ax", cJSON_CreateIntArray(p->ax, 3));
    cJSON_AddItemToObject(fr, "sg", cJSON_CreateDoubleArray(p->sg, 3));
    /* the surfaces */
    cJSON *jsurf = cJSON_AddArrayToObject(j, "surfaces");
    double max_error = 0;
    for (size_t i = 0; i < nl; i++) {
        const thx_render_surface *rs = &looks[i];
        const thx_surface *s = rs->surf;
        size_t k = 0;
        while (k < ns && m->surf[k] != s) k++;
        cJSON *x;
        THX_TRY(surface_head(ctx, pg, rs, thx_role_name(s->role), jsurf, &x));
        if (rs->values && k < ns && d->series[k]) {
            cJSON *jd = cJSON_AddObjectToObject(x, "data");
            int ci;
            THX_TRY(colormap_index(ctx, pg, cms, rs->cmap, cmap_index, &n_cmaps, &ci));
            int map = d->map[k][d->active[k]]; /* 1 activation, 2 recovery times */
            double err = 0;
            THX_TRY(surface_data(ctx, pg, d->series[k]->v, d->series[k]->n_rows, d->series[k]->n_frames, &S[i], rs, ci,
                                 map == 1 ? "activation" : map == 2 ? "recovery" : "potential",
                                 d->series[k]->unit[0] ? d->series[k]->unit : "mV", jd, map ? &err : &max_error));
        } else
            cJSON_AddNullToObject(x, "data");
    }
    /* the layers, made for the frame shown first: the volume's cuts (equipotentials, slices,
       streamlines) and the scan's contour lines as surfaces whose data has that one frame, and the
       scan's planes as textured rectangles */
    int f0 = o->r.frame < (int)M ? o->r.frame : 0;
    thx_render_surface lay[16];
    size_t nlay = 0, npl = 0;
    const thx_render_plane *pl = NULL;
    THX_TRY(thx_picture_layers(ctx, p, d, f0, lay, 16, &nlay, &pl, &npl));
    for (size_t i = 0; i < nlay; i++) {
        const thx_render_surface *rs = &lay[i];
        const thx_surface *s = rs->surf;
        cJSON *x;
        THX_TRY(surface_head(ctx, pg, rs, "layer", jsurf, &x));
        if (rs->line_width > 0) cJSON_AddNumberToObject(x, "line_width", rs->line_width);
        cJSON *jl = cJSON_AddObjectToObject(x, "layer");
        cJSON_AddNumberToObject(jl, "frame", f0);
        cJSON_AddNumberToObject(jl, "time", axis ? axis->time[f0] : 0);
        if (rs->values) {
            cJSON *jd = cJSON_AddObjectToObject(x, "data");
            int ci;
            scales one = {(thx_scale *)&rs->scale, 1};
            THX_TRY(colormap_index(ctx, pg, cms, rs->cmap, cmap_index, &n_cmaps, &ci));
            int current = 0;
            for (int q = 0; q < 3; q++)
                if (s == &d->field_surf[q]) current = d->field_current[q];
            /* the units render's colour bar gives them (src/picture/picture.c) */
            const char *vu = d->volume && d->volume->unit[0] ? d->volume->unit : current ? "unit" : "mV";
            char lunit[32];
            snprintf(lunit, sizeof lunit, current ? "A/m^2 per %.4s" : "%.15s", vu);
            double err = 0;
            THX_TRY(surface_data(ctx, pg, rs->values, s->n_nodes, 1, &one, rs, ci, current ? "|J|" : "potential", lunit,
                                 jd, current ? &err : &max_error));
        } else
            cJSON_AddNullToObject(x, "data");
    }
    cJSON *jpl = cJSON_AddArrayToObject(j, "planes");
    for (size_t k = 0; k < npl; k++) {
        cJSON *x = cJSON_CreateObject();
        cJSON_AddItemToArray(jpl, x);
        cJSON_AddNumberToObject(x, "w", pl[k].w);
        cJSON_AddNumberToObject(x, "h", pl[k].h);
        THX_TRY(blob(ctx, pg, "uint8", pl[k].rgba, 4 * (size_t)pl[k].w * (size_t)pl[k].h, 1, x, "texels"));
        cJSON_AddItemToObject(x, "origin", vec3(pl[k].origin));
        cJSON_AddItemToObject(x, "u", vec3(pl[k].u));
        cJSON_AddItemToObject(x, "v", vec3(pl[k].v));
        cJSON_AddBoolToObject(x, "nearest", pl[k].nearest);
        cJSON_AddNumberToObject(x, "frame", f0);
    }
    cJSON *jq = cJSON_AddObjectToObject(j, "quantization");
    cJSON_AddNumberToObject(jq, "bits", 16);
    cJSON_AddNumberToObject(jq, "max_error", max_error);
    cJSON_AddStringToObject(jq, "unit", axis && axis->unit[0] ? axis->unit : "mV");
    /* the leads and the electrodes */
    int twelve = 0;
    THX_TRY(leads_of(ctx, o, d, outer >= 0 ? d->series[outer] : NULL, outer >= 0 ? m->surf[outer] : NULL, &leads,
                     &leads_made, &elec, &twelve));
    if (leads && leads->n_frames != M) {
        st = thx_error(ctx, THX_EINPUT, "export: the leads have %zu frames, the potentials %zu", leads->n_frames, M);
        goto done;
    }
    if (leads) {
        cJSON *jl = cJSON_AddObjectToObject(j, "leads");
        cJSON_AddStringToObject(jl, "title", twelve ? "12-lead ECG" : "leads");
        cJSON *names = cJSON_AddArrayToObject(jl, "names");
        for (size_t r = 0; r < leads->n_rows; r++)
            cJSON_AddItemToArray(names, cJSON_CreateString(twelve ? LEAD12[r % 12] : elec ? elec->name[r] : "lead"));
        float *lv = malloc((leads->n_rows * M + 1) * sizeof *lv);
        if (!lv) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
        for (size_t r = 0; r < leads->n_rows; r++)
            for (size_t f = 0; f < M; f++) lv[r * M + f] = (float)leads->v[f * leads->n_rows + r];
        st = blob(ctx, pg, "float32", lv, leads->n_rows * M, sizeof *lv, jl, "values");
        free(lv);
        if (st != THX_OK) goto done;
        cJSON_AddStringToObject(jl, "unit", leads->unit[0] ? leads->unit : "mV");
    } else
        cJSON_AddNullToObject(j, "leads");
    cJSON *je = cJSON_AddArrayToObject(j, "electrodes");
    for (size_t i = 0; elec && i < elec->n; i++) {
        cJSON *x = cJSON_CreateObject();
        cJSON_AddItemToArray(je, x);
        cJSON_AddStringToObject(x, "name", elec->name[i]);
        cJSON_AddItemToObject(x, "position", vec3(elec->xyz + 3 * i));
    }
    for (int k = 0; k < d->n_elec; k++)
        for (size_t i = 0; i < d->elec[k]->n; i++) {
            cJSON *x = cJSON_CreateObject();
            cJSON_AddItemToArray(je, x);
            cJSON_AddStringToObject(x, "name", d->elec[k]->name[i]);
            cJSON_AddItemToObject(x, "position", vec3(d->elec[k]->xyz + 3 * i));
        }
    cJSON *jb = cJSON_AddArrayToObject(j, "blobs");
    for (size_t k = 0; k < thx_web_page_blobs(pg); k++) {
        size_t count = 0;
        const char *type = thx_web_page_blob_type(pg, k, &count, NULL);
        cJSON *x = cJSON_CreateObject();
        cJSON_AddItemToArray(jb, x);
        cJSON_AddStringToObject(x, "type", type);
        cJSON_AddNumberToObject(x, "count", (double)count);
    }
    if (!(text = cJSON_PrintUnformatted(j))) { st = thx_error(ctx, THX_ENOMEM, "export: out of memory"); goto done; }
    size_t vlen = 0;
    const char *viewer = thx_web_viewer(&vlen);
    const char *inputs[2 + 2 * THX_PICTURE_MAX + 1] = {p->solution, p->model_dir};
    size_t ni = 2;
    for (int k = 0; k < p->n_data && k < THX_PICTURE_MAX; k++) inputs[ni++] = p->data[k];
    for (int k = 0; k < p->n_files && k < THX_PICTURE_MAX; k++) inputs[ni++] = p->files[k];
    if (o->leads) inputs[ni++] = o->leads;
    st = thx_web_page_write(ctx, pg, out, title, text, viewer, vlen, inputs, ni, bytes);
    *nblobs = thx_web_page_blobs(pg);
    *max_err = max_error;
    snprintf(unit, unit_size, "%s", axis && axis->unit[0] ? axis->unit : "mV");
done:
    for (size_t i = 0; S && i < ns; i++) free(S[i].sc);
    free(S);
    free(looks);
    free(text);
    cJSON_Delete(j);
    thx_web_page_free(&pg);
    thx_series_destroy(&leads_made);
    thx_electrodes_destroy(&elec);
    return st;
}

int cli_export_page(int argc, char **argv)
{
    page_opts o;
    memset(&o, 0, sizeof o);
    render_opts_default(&o.r);
    o.r.cmd = "export";
    int frame = 1, format = 0;
    static const cli_choice formats[] = {{"html", 0}, {NULL, 0}};
    cli_opt own[] = {
        {.name = "--format", .type = CLI_CHOICE, .meta = "html", .choices = formats, .i = &format,
         .help = "html: one self-contained interactive web page"},
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "PAGE.html", .s = &o.r.out,
         .help = "the page (replaced only if thorax wrote it)"},
        {.name = "--title", .type = CLI_STRING, .meta = "TEXT", .s = &o.title, .def = "thorax: MODEL, solution DIR",
         .help = "the page's title"},
        {.name = "--leads", .type = CLI_INPUT, .meta = "FILE", .s = &o.leads,
         .def = "the solution's ecg12, else MODEL/electrodes/12lead.txt",
         .help = "electrodes on the outer surface whose signals are plotted (the 12-lead ECG when the file holds RA, "
                 "LA, LL and V1..V6)"},
        {.name = "--frame", .type = CLI_INT, .meta = "K", .i = &frame, .rule = CLI_GE, .lo = 1, .bad = "--frame: 1, 2, ...",
         .help = "the frame shown first, 1-based"},
    };
    cli_opt common[N_RENDER_OPTS];
    cli_command cmd = {
        .name = "export",
        .usage = "MODEL --format [--solution|--data] -o [options]\n"
                 "--solution --format -o [options]\n"
                 "SURFACE_FILE... --format [--data [--channels]] -o [options]",
        .about = "Writes the picture thorax render draws from the same options as one\n"
                 "self-contained web page that opens offline in a browser: the surfaces coloured\n"
                 "by the potentials (render's colour maps, scales and shading), turned with the\n"
                 "mouse, each one hidden or made translucent; a frame slider with play and pause;\n"
                 "the 12-lead ECG (or --leads) with a marker at the current frame (a click there\n"
                 "moves to that time); a click on a surface plots that node's signal. Render's\n"
                 "layers (--isosurface, --slice, --streamlines, --image, --contours) are made for\n"
                 "the frame shown first and kept as layers of that frame. The potentials are\n"
                 "quantized to 16 bits per surface (the error bound is printed and kept in the\n"
                 "page). docs/design/web.md.\n",
        .epilog = "Options of render that the page cannot show (--clip, --panels, --arrows,\n"
                  "--trace, --tetrahedra, --landmarks, --node-labels, --extrema, --renderer\n"
                  "trace, --volume) are refused.\n"
                  "Exit status: 0 ok, 1 error, 2 bad usage.\n",
        .group = {{NULL, own, sizeof own / sizeof own[0]}, {"what is drawn, and how", common, render_options(common, &o.r)}},
        .positional = render_positional,
        .user = &o.r,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    o.r.frame = frame - 1;
    if (!o.r.p.model_dir && !o.r.p.n_files && !o.r.p.solution)
        return cli_usage_error("export", "no model directory, surface file or --solution given");
    if (!o.r.out) return cli_usage_error("export", "no page given (-o PAGE.html)");
    if (refuse_unsupported(&o)) return 2;
    thx_ctx *ctx = cli_ctx(o.r.verbose);
    thx_picture_data d;
    memset(&d, 0, sizeof d);
    o.r.p.frame = o.r.frame;
    o.r.p.check_frame = 1;
    double t0 = thx_wtime();
    size_t bytes = 0, nblobs = 0;
    double max_error = 0;
    char unit[32] = "mV";
    thx_status st = thx_picture_load(ctx, &o.r.p, &d);
    if (st == THX_OK) st = build(ctx, &o, &d, o.r.out, &bytes, &nblobs, &max_error, unit, sizeof unit);
    thx_picture_data_free(&d);
    if (st != THX_OK) {
        int rc = cli_fail(ctx, "export", st);
        thx_ctx_destroy(&ctx);
        return rc;
    }
    if (o.r.verbose >= 0)
        printf("wrote %s (%.2f MB, %zu blobs, %.2f s; potentials to within %.3g %s)\n", o.r.out, bytes / 1e6, nblobs,
               thx_wtime() - t0, max_error, unit);
    thx_ctx_destroy(&ctx);
    return 0;
}
