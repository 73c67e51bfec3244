/*
 * A picture of a model and its data (thorax/picture/picture.h): the scale of each surface, the
 * scene of a frame built from the settings, drawn offscreen or into the caller's OpenGL context,
 * and the annotations over it. Shared by thorax render, animate and view.
 */
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "thorax/core/fileio.h"
#include "thorax/fem/fem.h"
#include "thorax/import/import.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/geom/landmark_mesh.h"
#include "thorax/geom/pick.h"
#include "thorax/io/landmarks_file.h"
#include "thorax/leads/activation.h"
#include "picture/picture_internal.h"
#include "thorax/parallel/parallel.h"

/* ---- one picture ---- */
void picture_range_of(const double *v, size_t n, double *lo, double *hi)
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
        picture_range_of(x->v, x->n_rows * x->n_frames, &a, &b);
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

void picture_scale_settings(const thx_picture_opts *o, double lo, double hi, int true_range, thx_scale *sc)
{
    memset(sc, 0, sizeof *sc);
    if (o->scope == THX_SCOPE_FIXED) {
        sc->model = o->model;
        sc->lo = o->lo;
        sc->hi = o->hi;
        sc->k = o->model == THX_SCALE_LOG ? 10 : 3;
        sc->mapping = (thx_scale_mapping)o->mapping;
    } else
        thx_scale_from_range_mapped(sc, (thx_scale_model)o->model, true_range ? THX_MAPPING_TRUE : (thx_scale_mapping)o->mapping,
                                    lo, hi);
    if (o->invert) { /* the colour map reversed: the scale's ends swapped */
        double t = sc->lo;
        sc->lo = sc->hi;
        sc->hi = t;
    }
}

static void scale_for(const thx_picture_opts *o, thx_picture_data *d, int s, int frame, thx_scale *sc)
{
    double lo = INFINITY, hi = -INFINITY;
    int map = 0;
    if (o->scope != THX_SCOPE_FIXED) {
        s = master_of(o, d->m, s);
        for (size_t k = 0; k < d->m->n_surfaces && k < THX_PICTURE_SURFACES; k++) {
            const thx_series *x = d->series[k];
            if (!x || !shares_scale(o, d->m, s, (int)k)) continue;
            if (d->map[k][d->active[k]] != d->map[s][d->active[s]]) continue; /* times and potentials apart */
            size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
            if (o->scope == THX_SCOPE_FRAME || o->scope == THX_SCOPE_SURFACES) picture_range_of(x->v + f * x->n_rows, x->n_rows, &lo, &hi);
            else series_range(d, k, &lo, &hi);
        }
        /* the library's one range rule (thorax/render/image.h): symmetric = the largest magnitude;
           a map of times over its true range */
        map = s < THX_PICTURE_SURFACES && d->series[s] && d->map[s][d->active[s]];
    }
    picture_scale_settings(o, lo, hi, map, sc);
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
        if (picture_has_field(o) && m->surf[s]->role != THX_ROLE_HEART && o->mode != THX_DRAW_WIRE &&
            o->mode != THX_DRAW_POINTS && o->mode != THX_DRAW_ORIENTATION)
            r->color[3] = 0.2f; /* the volume's cuts inside are what is shown: the body around them faint */
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
            r->color[3] = look && look->opacity >= 0 ? look->opacity
                          : picture_has_field(o) && m->surf[s]->role != THX_ROLE_HEART ? 0.2f : 1;
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
    /* the volume mesh (--tetrahedra): each region's faces flat in its colour (the region's index in
       this palette, docs/cli.md), then their edges; already clipped element by element */
    static const float REGION_RGB[8][3] = {{0.93f, 0.80f, 0.62f}, {0.55f, 0.72f, 0.93f}, {0.98f, 0.62f, 0.62f},
                                           {0.62f, 0.87f, 0.62f}, {0.85f, 0.70f, 0.93f}, {0.95f, 0.90f, 0.45f},
                                           {0.55f, 0.88f, 0.88f}, {0.80f, 0.80f, 0.80f}};
    for (int k = 0; k < d->n_tets; k++)
        for (int pass = 0; pass < 2 && b->n < sizeof b->rs / sizeof b->rs[0]; pass++) {
            thx_render_surface *r = &b->rs[b->n++];
            memset(r, 0, sizeof *r);
            r->surf = d->tets[k];
            r->mode = pass ? THX_DRAW_WIRE : THX_DRAW_FLAT;
            const float *c = REGION_RGB[d->tets_region[k] % 8];
            for (int i = 0; i < 3; i++) r->color[i] = pass ? 0.25f * c[i] : c[i];
            r->color[3] = 1;
            r->no_clip = 1;
        }
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
    thx_raytrace_opts_default(&o->rt);
    o->next_frame = -1;
}

static const unsigned char BG[4] = {24, 24, 28, 255}, FG[4] = {235, 235, 235, 255};

void thx_picture_colors(float background[4], float nan_color[4])
{
    for (int k = 0; k < 4; k++) background[k] = BG[k] / 255.0f;
    nan_color[0] = 0.6f, nan_color[1] = 0.6f, nan_color[2] = 0.2f, nan_color[3] = 1;
}

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

/* Scale sc (colour map cmap, quantity title, unit) into the bars, once per distinct one; the
   surface (or "currents") named on it. */
static void add_bar(thx_picture_bars *bars, const thx_scale *sc, int cmap, const char *title, const char *unit,
                    const char *name)
{
    int k = 0;
    while (k < bars->n && (memcmp(&bars->scale[k], sc, sizeof *sc) || bars->cmap[k] != cmap ||
                           strcmp(bars->title[k], title) || strncmp(bars->unit[k], unit, sizeof bars->unit[k] - 1)))
        k++;
    if (k == bars->n) {
        if (bars->n == THX_PICTURE_SCALES) { bars->more = 1; return; }
        bars->scale[k] = *sc;
        bars->cmap[k] = cmap;
        snprintf(bars->title[k], sizeof bars->title[k], "%s", title);
        snprintf(bars->unit[k], sizeof bars->unit[k], "%s", unit);
        bars->names[k][0] = '\0';
        bars->n++;
    }
    size_t len = strlen(bars->names[k]), n = strlen(name);
    for (const char *p = bars->names[k]; *p;) { /* already named (a surface drawn in several passes) */
        const char *c = strstr(p, ", ");
        size_t l = c ? (size_t)(c - p) : strlen(p);
        if (l == n && !strncmp(p, name, n)) return;
        p = c ? c + 2 : p + l;
    }
    if (len + n + 3 < sizeof bars->names[k])
        snprintf(bars->names[k] + len, sizeof bars->names[k] - len, "%s%s", len ? ", " : "", name);
}

static void collect_bars(const thx_picture_data *d, const built_scene *b, thx_picture_bars *bars)
{
    const thx_model *m = d->m;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < b->n; i++) {
            const thx_render_surface *r = &b->rs[i];
            int main = b->main_surface >= 0 && r->surf == m->surf[b->main_surface];
            if (!r->values || (pass == 0) != main) continue;
            int s = -1;
            for (size_t k = 0; k < m->n_surfaces && k < THX_PICTURE_SURFACES && s < 0; k++)
                if (m->surf[k] == r->surf) s = (int)k;
            int map = s >= 0 && d->series[s] ? d->map[s][d->active[s]] : 0;
            int field = -1;
            for (int q = 0; q < 3 && s < 0 && d->volume; q++)
                if (r->surf == &d->field_surf[q]) field = q;
            if (field >= 0) {
                /* equipotentials, slices, streamlines: the volume's potentials, or |J| */
                char unit[16];
                int current = d->field_current[field];
                /* (as thorax forward labels its currents: "per unit" for potentials without a unit) */
                const char *vu = d->volume->unit[0] ? d->volume->unit : current ? "unit" : "";
                snprintf(unit, sizeof unit, current ? "A/m^2 per %.4s" : "%.15s", vu);
                add_bar(bars, &r->scale, (int)r->cmap, current ? "|J|" : "potential", unit, r->surf->name);
                continue;
            }
            add_bar(bars, &r->scale, (int)r->cmap, map == 2 ? "recovery" : map ? "activation" : "potential",
                    s >= 0 && d->series[s] ? d->series[s]->unit : "", r->surf->name);
        }
    if (b->have_arrows && b->arrows.unit_length)
        add_bar(bars, &b->arrows.mag_scale, (int)b->arrows.cmap, "|J|", d->currents ? d->currents->unit : "", "currents");
}

/* The bar of the volume-rendered field (--volume potential|current): its colour map, the scale volume_of
 * gave it (the frame's own range), titled and with the unit as the field's surfaces have theirs. */
static void add_volume_bar(const thx_picture_opts *o, const thx_picture_data *d, const thx_scale *sc, thx_colormap cmap,
                           thx_picture_bars *bars)
{
    int current = !strcmp(o->volume_render, "current");
    char unit[16];
    const char *vu = d->volume && d->volume->unit[0] ? d->volume->unit : current ? "unit" : "";
    snprintf(unit, sizeof unit, current ? "A/m^2 per %.4s" : "%.15s", vu);
    add_bar(bars, sc, (int)cmap, current ? "|J|" : "potential", unit, "volume");
}

int thx_picture_bar_layout(const thx_picture_opts *o, thx_font *font, int w, int h, int n, int box[][4])
{
    int vp[4];
    thx_picture_viewport(o, font, w, h, vp);
    int vw = vp[2], vh = vp[3], top = vp[1], bar_w = w - vw;
    if (n <= 0 || !o->colorbar) return 0;
    if (n == 1) {
        box[0][0] = vw + bar_w / 4;
        box[0][1] = top + vh / 8;
        box[0][2] = bar_w / 4;
        box[0][3] = vh * 3 / 4;
        return box[0][3] >= 16 ? 1 : 0;
    }
    /* stacked, each below its three title lines (its surfaces, what is shown, the unit) */
    int slot = vh * 7 / 8 / n, fh = thx_font_height(font), fit = 0;
    for (int k = 0; k < n && k < THX_PICTURE_BARS; k++) {
        int y0 = top + vh / 16 + k * slot + 3 * fh + 8, hh = slot - 4 * fh - 12;
        if (hh < 16) break;
        box[k][0] = vw + bar_w / 4;
        box[k][1] = y0;
        box[k][2] = bar_w / 4;
        box[k][3] = hh;
        fit++;
    }
    return fit;
}

void thx_picture_bar_title(const thx_picture_opts *o, const thx_picture_bars *bars, int k, char *head, size_t head_size,
                           char *unit, size_t unit_size)
{
    const char *title = o->n_bar_title == 1 ? o->bar_title[0] : k < o->n_bar_title ? o->bar_title[k] : bars->title[k];
    const char *u = o->n_bar_unit == 1 ? o->bar_unit[0] : k < o->n_bar_unit ? o->bar_unit[k] : bars->unit[k];
    snprintf(head, head_size, "%s", title);
    snprintf(unit, unit_size, "%s", u);
}

thx_status thx_picture_bars_check(thx_ctx *ctx, const thx_picture_opts *o, thx_font *font, int w, int h,
                                  const thx_picture_bars *bars)
{
    if (!o->colorbar) return THX_OK;
    if (o->n_bar_title > 1 && o->n_bar_title > bars->n)
        return thx_error(ctx, THX_EINPUT, "--bar-title is given %d times, but the picture has %d colour bar%s",
                         o->n_bar_title, bars->n, bars->n == 1 ? "" : "s");
    if (o->n_bar_unit > 1 && o->n_bar_unit > bars->n)
        return thx_error(ctx, THX_EINPUT, "--bar-unit is given %d times, but the picture has %d colour bar%s",
                         o->n_bar_unit, bars->n, bars->n == 1 ? "" : "s");
    int box[THX_PICTURE_BARS][4];
    int fit = thx_picture_bar_layout(o, font, w, h, bars->n, box);
    if (fit >= bars->n && !bars->more) return THX_OK;
    char list[1024] = "";
    for (int k = 0; k < bars->n; k++) {
        size_t at = strlen(list);
        char lo[32], hi[32];
        snprintf(lo, sizeof lo, "%.3g", bars->scale[k].lo);
        snprintf(hi, sizeof hi, "%.3g", bars->scale[k].hi);
        if (at + 200 < sizeof list)
            snprintf(list + at, sizeof list - at, "%s%s %s %s..%s %s", k ? "; " : "", bars->names[k], bars->title[k], lo, hi,
                     bars->unit[k]);
    }
    return thx_error(ctx, THX_EINPUT,
                     "--colorbar: the surfaces are coloured on %s%d different scales (%s), but %d colour bar%s fit "
                     "beside a %dx%d picture, and one bar for all would not be the scale of every surface: give "
                     "them one scale (--scope all or surfaces, --scale-group A,B, --slave NAME=MASTER), draw fewer "
                     "surfaces (--only), or a taller picture (--size)",
                     bars->more ? "more than " : "", bars->n, list, fit, fit == 1 ? "" : "s", w, h);
}

/* A panel traced (RaySpray): the materials given by name placed at their surfaces' places in the
 * scene, the tracer made at the first traced draw and kept (its geometry cache spans frames). */
/* The field rendered inside the mesh (o->volume_render): the tetrahedra of the solution's domain
 * (once), the frame's potentials (point data) or |J| per tetrahedron (cell data), the scale. */
static thx_status volume_of(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame, thx_raytrace_volume *v)
{
    const thx_volume *vm = d->m->volume;
    if (!d->volume || !vm) return thx_error(ctx, THX_EINPUT, "--volume: needs --solution with volume potentials (thorax forward --volume)");
    int current = !strcmp(o->volume_render, "current");
    if (!d->vr_tet) {
        d->vr_tet = malloc(4 * (vm->n_tets ? vm->n_tets : 1) * sizeof *d->vr_tet);
        if (!d->vr_tet) return thx_error(ctx, THX_ENOMEM, "out of memory (volume rendering)");
        d->vr_n_tets = 0;
        for (size_t t = 0; t < vm->n_tets; t++) /* (sort-last: the ghosts too, the rays cut to the part's box) */
            if (!d->field_use || d->field_use[vm->region[t]])
                memcpy(d->vr_tet + 4 * d->vr_n_tets++, vm->tet + 4 * t, 4 * sizeof *d->vr_tet);
    }
    size_t f = (size_t)frame < d->volume->n_frames ? (size_t)frame : d->volume->n_frames - 1;
    const double *phi = d->volume->v + f * d->volume->n_rows;
    memset(v, 0, sizeof *v);
    v->xyz = vm->xyz;
    v->n_nodes = vm->n_nodes;
    v->tet = d->vr_tet;
    v->n_tets = d->vr_n_tets;
    v->cmap = current ? THX_CMAP_VIRIDIS : o->cmap;
    if (current) {
        double *j = malloc(3 * (vm->n_tets ? vm->n_tets : 1) * sizeof *j);
        free(d->vr_cell);
        d->vr_cell = malloc((d->vr_n_tets ? d->vr_n_tets : 1) * sizeof *d->vr_cell);
        if (!j || !d->vr_cell) { free(j); return thx_error(ctx, THX_ENOMEM, "out of memory (volume rendering)"); }
        thx_fem_currents(vm, d->field_use, phi, j, NULL);
        double hi = 0;
        for (size_t t = 0, k = 0; t < vm->n_tets; t++) {
            if (d->field_use && !d->field_use[vm->region[t]]) continue;
            d->vr_cell[k] = sqrt(j[3 * t] * j[3 * t] + j[3 * t + 1] * j[3 * t + 1] + j[3 * t + 2] * j[3 * t + 2]);
            if (isfinite(d->vr_cell[k])) hi = fmax(hi, d->vr_cell[k]);
            k++;
        }
        free(j);
        d->vr_local_hi = hi;
        if (d->part_size > 1 && isfinite(d->part_jmax)) hi = d->part_jmax; /* sort-last: the whole's */
        v->cell_values = d->vr_cell;
        thx_scale_from_range(&v->scale, THX_SCALE_LINEAR, 0, hi > 0 ? hi : 1, 0);
    } else {
        /* the frame's own range: the volume's contrast at every frame (the series' extremes, near the
           heart at the peak of the beat, would leave most frames clear) */
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < d->vr_n_tets * 4; i++) {
            double x = phi[d->vr_tet[i]];
            if (isfinite(x)) { lo = fmin(lo, x); hi = fmax(hi, x); }
        }
        if (d->part_size > 1) { lo = d->part_lo; hi = d->part_hi; } /* sort-last: the whole's (the same nodes) */
        if (!(lo < hi)) { lo = d->vmin; hi = d->vmax; }
        v->point_values = phi;
        picture_scale_settings(o, lo, hi, 0, &v->scale);
    }
    memcpy(v->opacity, o->volume_opacity, sizeof v->opacity);
    v->n_opacity = o->n_volume_opacity;
    if (!o->n_volume_opacity && current) { /* |J|: clear where weak, rising to opaque */
        v->opacity[0][0] = 0;
        v->opacity[0][1] = 0;
        v->opacity[1][0] = 1;
        v->opacity[1][1] = 1;
        v->n_opacity = 2;
    }
    v->density = o->volume_density > 0 ? o->volume_density : 0.02;
    if (d->part_size > 1) { /* sort-last: the rays' pieces in this rank's box alone */
        v->have_box = 1;
        picture_part_box(d, v->box);
    }
    return THX_OK;
}

/* The panel traced into img, blurred towards next (NULL: no motion blur); with --volume, *vol_scale
 * and *vol_cmap the volume's colours (for its bar). */
/* Sort-first's share of a picture (thx_picture_draw_share): rank, size, and the pixels written. */
typedef struct {
    int rank, size;
    unsigned char *own;
    float *layer; /* sort-last: the traced pixels as premultiplied floats (thx_raytrace_opts.layer) */
} share_of;

static thx_status trace_panel(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const thx_scene *sc,
                              const thx_scene *next, int frame, thx_raster *img, thx_scale *vol_scale, thx_colormap *vol_cmap,
                              const share_of *share)
{
    if (!d->tracer) THX_CHECK(thx_tracer_create(ctx, &d->tracer));
    thx_raytrace_volume vol;
    if (o->volume_render) {
        THX_CHECK(volume_of(ctx, o, d, frame, &vol));
        *vol_scale = vol.scale;
        *vol_cmap = vol.cmap;
    }
    thx_raytrace_opts *rt = malloc(sizeof *rt);
    if (!rt) return thx_error(ctx, THX_ENOMEM, "out of memory (ray tracer options)");
    *rt = o->rt;
    if (o->rt_key && rt->n_lights == 0) { /* the headlight dimmed, and a key light over the viewer's right shoulder */
        rt->lights[0] = (thx_light){.kind = THX_LIGHT_HEAD, .intensity = 0.35};
        rt->lights[1] = (thx_light){.kind = THX_LIGHT_DIRECTIONAL, .in_camera = 1, .dir = {-0.5, -0.9, 1}, .intensity = 0.8, .shadows = 1};
        rt->n_lights = 2;
    }
    for (size_t i = 0; i < sc->n_surfaces && i < THX_RAYTRACE_MAX_SURFACES; i++) {
        const thx_surface *s = sc->surfaces[i].surf;
        for (int k = 0; s && k < o->n_rt_mat; k++)
            if (!strcmp(o->rt_mat[k].name, s->name)) rt->material[i] = o->rt_mat[k].m;
    }
    rt->volume = o->volume_render ? &vol : NULL;
    rt->next = next;
    if (o->environment && !strcmp(o->environment, "sky")) {
        rt->sky = 1;
    } else if (o->environment) {
        thx_status se = d->rt_env ? THX_OK : thx_raster_read_png(ctx, o->environment, &d->rt_env);
        if (se != THX_OK) { free(rt); return se; }
        rt->environment = d->rt_env;
    }
    if (share && share->layer) { /* sort-last: the whole picture, as a layer */
        rt->layer = share->layer;
    } else if (share) { /* sort-first: this rank's tiles */
        rt->share_rank = share->rank;
        rt->share_size = share->size;
        rt->own = share->own;
    }
    thx_status st = thx_raytrace_scene(ctx, d->tracer, sc, rt, img, &d->rt_stats);
    free(rt);
    return st;
}

/* Motion blur: the panel's scene sc at the next frame (o->next_frame, o->next_cam), into *next with
 * its surfaces in *rs_out (malloc'd): the model's surfaces with the next frame's values and scales,
 * everything else as in sc. */
static thx_status next_scene(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame, int only,
                             const thx_scene *sc, thx_scene *next, thx_render_surface **rs_out)
{
    built_scene *bn = calloc(1, sizeof *bn);
    thx_render_surface *rs = malloc((sc->n_surfaces ? sc->n_surfaces : 1) * sizeof *rs);
    if (!bn || !rs) {
        free(bn);
        free(rs);
        return thx_error(ctx, THX_ENOMEM, "out of memory (motion blur's next scene)");
    }
    build_surfaces(o, d, o->next_frame >= 0 ? o->next_frame : frame + 1, bn, only);
    memcpy(rs, sc->surfaces, sc->n_surfaces * sizeof *rs);
    for (size_t i = 0; i < bn->n && i < sc->n_surfaces; i++)
        if (rs[i].surf == bn->rs[i].surf) {
            rs[i].values = bn->rs[i].values;
            rs[i].scale = bn->rs[i].scale;
        }
    free(bn);
    *next = *sc;
    next->surfaces = rs;
    if (o->have_next_cam) next->camera = o->next_cam;
    *rs_out = rs;
    return THX_OK;
}

/* The scene of panel (of cols x rows in the viewport vp): b's surfaces and arrows, the scan's planes,
 * the background, the camera; no clip plane. */
static void panel_scene(const thx_picture_opts *o, const thx_picture_data *d, const built_scene *b, const int vp[4], int cols,
                        int rows, int panel, thx_scene *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->surfaces = b->rs;
    sc->n_surfaces = b->n;
    sc->arrows = b->have_arrows ? &b->arrows : NULL;
    sc->n_arrows = b->have_arrows ? 1 : 0;
    sc->planes = d->scan_plane;
    sc->n_planes = (size_t)d->n_scan_planes;
    int pw = vp[2] / cols, ph = vp[3] / rows;
    sc->viewport[0] = (panel % cols) * pw;
    sc->viewport[1] = vp[1] + (panel / cols) * ph;
    sc->viewport[2] = pw;
    sc->viewport[3] = ph;
    sc->clear = 1;
    thx_picture_colors(sc->background, sc->nan_color);
    thx_picture_camera(o, d, (double)pw / ph, &sc->camera);
}

/* The 3D part of the picture, panel by panel: offscreen into img (r of the picture's size), or
 * into the current framebuffer (img NULL, fb_w x fb_h). */
/* share (NULL: the whole picture): sort-first's rank, size and own mask (thx_picture_draw_share) */

static thx_status draw_panels(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *rr,
                              thx_font *font, int frame, int fb_w, int fb_h, thx_raster *img, thx_picture_bars *bars,
                              size_t *nan_total, const share_of *share)
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
    st = picture_field_build(ctx, o, d, frame);
    if (st == THX_OK) st = picture_scan_build(ctx, o, d);
    if (st != THX_OK) { free(b); return st; }
    for (size_t s = 0; s < (o->panels ? m->n_surfaces : 1); s++) {
        int only = o->panels ? (int)s : -1;
        memset(b, 0, sizeof *b);
        build_surfaces(o, d, frame, b, only);
        if (!o->panels) b->n += picture_field_surfaces(o, d, b->rs + b->n, sizeof b->rs / sizeof b->rs[0] - b->n);
        if (!o->panels) b->n += picture_scan_surfaces(d, b->rs + b->n, sizeof b->rs / sizeof b->rs[0] - b->n);
        if (b->n == 0 && (o->panels || !d->n_scan_planes)) continue; /* (a scan alone is drawn: tracing starts so) */
        if (!o->panels) {
            thx_status sa = build_arrows(ctx, o, d, frame, b);
            if (sa != THX_OK) { free(b->apos); free(b->avec); free(b); return sa; }
        }
        thx_scene sc;
        panel_scene(o, d, b, vp, cols, rows, panel, &sc);
        if (n_clip > 0) { sc.clip[0] = clip; sc.n_clip = 1; }
        size_t nn = 0;
        thx_scale vol_scale;
        thx_colormap vol_cmap = THX_CMAP_ECG;
        int traced = o->renderer == 1 && img;
        if (traced) {
            thx_scene next;
            thx_render_surface *nrs = NULL;
            if (o->rt.shutter > 0) st = next_scene(ctx, o, d, frame, only, &sc, &next, &nrs);
            if (st == THX_OK)
                st = trace_panel(ctx, o, d, &sc, o->rt.shutter > 0 ? &next : NULL, frame, img, &vol_scale, &vol_cmap, share);
            free(nrs);
        } else if (img && share) { /* sort-first: this rank's band of rows */
            st = thx_renderer_set_share(ctx, rr, share->rank, share->size, share->own);
            if (st == THX_OK) st = thx_render(ctx, rr, &sc, img, &nn);
            thx_renderer_set_share(NULL, rr, 0, 1, NULL);
        } else st = img ? thx_render(ctx, rr, &sc, img, &nn) : thx_render_scene_gl(ctx, rr, &sc, fb_w, fb_h, &nn);
        if (nan_total) *nan_total += b->nan_count;
        free(b->apos);
        free(b->avec);
        b->apos = b->avec = NULL;
        if (st != THX_OK) break;
        collect_bars(d, b, bars);
        if (traced && o->volume_render) /* the field rendered inside the mesh: its bar (one with the surfaces' when the same) */
            add_volume_bar(o, d, &vol_scale, vol_cmap, bars);
        panel++;
    }
    free(b);
    return st;
}

thx_status thx_picture_annotate(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font,
                                int frame, const thx_picture_bars *bars, thx_raster *img)
{
    const thx_model *m = d->m;
    if (!font) return THX_OK;
    int vp[4], cols, rows;
    thx_picture_viewport(o, font, img->w, img->h, vp);
    int vw = vp[2], vh = vp[3], top = vp[1];
    int trace_h = o->trace ? img->h / 5 : 0;
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
    if (o->colorbar) {
        /* one bar per distinct scale, each with its own colour map and titles; those that do not
           fit are left out here (thx_picture_draw refuses such a picture before) */
        int box[THX_PICTURE_BARS][4];
        int fit = thx_picture_bar_layout(o, font, img->w, img->h, bars->n, box), fh = thx_font_height(font);
        for (int k = 0; k < fit; k++) {
            char head[160], unit[64];
            thx_picture_bar_title(o, bars, k, head, sizeof head, unit, sizeof unit);
            if (bars->n > 1) { /* the surfaces the bar serves, above its title and unit */
                int tw = thx_text_width(font, bars->names[k]), tx = box[k][0];
                if (tx + tw > img->w - 2) tx = img->w - 2 - tw;
                thx_draw_text(img, font, tx < 0 ? 0 : tx, box[k][1] - 3 * fh - 2, bars->names[k], FG);
            }
            thx_draw_colorbar(img, font, box[k][0], box[k][1], box[k][2], box[k][3], (thx_colormap)bars->cmap[k],
                              &bars->scale[k], bars->cmap[k] == (int)o->cmap ? shades : 0,
                              bars->n == 1 || box[k][3] > 8 * fh ? 5 : 3, head, unit);
        }
    }
    if (o->orientation) {
        thx_picture_letter L[4 * 64];
        int nl = thx_picture_orientation(o, d, font, img->w, img->h, L, 4 * 64);
        for (int k = 0; k < nl; k++) thx_draw_text(img, font, L[k].x, L[k].y, L[k].text, FG);
    }
    if (o->label && any) {
        /* the time of the potentials shown, then what each map is and which window it took */
        char text[512];
        const thx_series *pot = NULL;
        for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
            if (d->series[s] && !d->map[s][d->active[s]] && (!pot || m->surf[s]->role == THX_ROLE_OUTER)) pot = d->series[s];
        size_t len = 0;
        text[0] = '\0';
        if (pot) {
            size_t f = (size_t)frame < pot->n_frames ? (size_t)frame : 0;
            len += (size_t)snprintf(text, sizeof text, "t = %g %s   (frame %d of %zu)", pot->time[f], pot->time_unit, frame + 1,
                                    pot->n_frames);
        }
        for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES && len < sizeof text - 1; s++)
            if (d->series[s] && d->map[s][d->active[s]])
                len += (size_t)snprintf(text + len, sizeof text - len, "%s%s: %s", len ? "   " : "", m->surf[s]->name,
                                        d->series[s]->label);
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

thx_status thx_picture_layers(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame,
                              thx_render_surface *out, size_t max, size_t *n, const thx_render_plane **planes,
                              size_t *n_planes)
{
    *n = 0;
    *planes = NULL;
    *n_planes = 0;
    THX_CHECK(picture_field_build(ctx, o, d, frame));
    THX_CHECK(picture_scan_build(ctx, o, d));
    *n = picture_field_surfaces(o, d, out, max);
    *n += picture_scan_surfaces(d, out + *n, max - *n);
    *planes = d->scan_plane;
    *n_planes = (size_t)d->n_scan_planes;
    return THX_OK;
}

size_t thx_picture_surface_looks(const thx_picture_opts *o, thx_picture_data *d, int frame, thx_render_surface *out,
                                 size_t max)
{
    built_scene *b = calloc(1, sizeof *b);
    if (!b) return 0;
    build_surfaces(o, d, frame, b, -1);
    size_t n = 0;
    for (size_t i = 0; i < b->n && n < max; i++)
        for (size_t s = 0; s < d->m->n_surfaces; s++)
            if (b->rs[i].surf == d->m->surf[s]) out[n++] = b->rs[i];
    free(b);
    return n;
}

thx_status thx_picture_draw(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                            thx_font *font, int frame, thx_raster *img, size_t *nan_total)
{
    thx_raster_fill(img, BG);
    thx_picture_bars bars;
    THX_CHECK(draw_panels(ctx, o, d, r, font, frame, img->w, img->h, img, &bars, nan_total, NULL));
    if (font) THX_CHECK(thx_picture_bars_check(ctx, o, font, img->w, img->h, &bars));
    return thx_picture_annotate(ctx, o, d, font, frame, &bars, img);
}

thx_status thx_picture_draw_share(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                                  thx_font *font, int frame, int rank, int size, thx_raster *img, unsigned char *own,
                                  thx_picture_bars *bars, size_t *nan_total)
{
    if (size < 1 || rank < 0 || rank >= size) return thx_error(ctx, THX_EINPUT, "picture: share %d of %d", rank, size);
    thx_raster_fill(img, BG);
    memset(own, 0, (size_t)img->w * (size_t)img->h);
    share_of share = {rank, size, own, NULL};
    THX_CHECK(draw_panels(ctx, o, d, r, font, frame, img->w, img->h, img, bars, nan_total, &share));
    if (font) THX_CHECK(thx_picture_bars_check(ctx, o, font, img->w, img->h, bars));
    return THX_OK;
}

/* The box around what the renderer would draw of the scene: every node of its surfaces (as the
 * renderer's box is), for one depth scale over the ranks. */
static void scene_box(const thx_scene *sc, double lo[3], double hi[3])
{
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        if (rs->mode == THX_DRAW_HIDDEN || !rs->surf) continue;
        for (size_t n = 0; n < rs->surf->n_nodes; n++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], rs->surf->xyz[3 * n + k]);
                hi[k] = fmax(hi[k], rs->surf->xyz[3 * n + k]);
            }
    }
}

/* Sort-last volume rendering (thx_picture_draw_part with o->volume_render): each rank traces the field
 * in its own tetrahedra as a layer of premultiplied floats, the layers are blended front to back in
 * the order of the parts' boxes from the eye (thx_fem_cut_order), rank 0 puts them over the
 * background. The colour scale is the whole's (the frame's range, or |J|'s largest, over the ranks). */
static thx_status draw_part_volume(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font, int frame,
                                   thx_raster *img, thx_picture_bars *bars)
{
    int w = img->w, h = img->h, rank = thx_par_rank(), size = thx_par_size();
    thx_raster_fill(img, BG);
    memset(bars, 0, sizeof *bars);
    built_scene *b = calloc(1, sizeof *b);
    size_t ns = (size_t)o->rt.samples * (size_t)o->rt.samples; /* samples a pixel: composited one by one */
    float *layer = ns <= 256 && (size_t)w * h <= SIZE_MAX / 16 / ns ? calloc(4 * (size_t)w * h * ns, sizeof *layer) : NULL;
    int *order = malloc(2 * (size_t)size * sizeof *order);
    thx_status st = b && layer && order ? THX_OK : thx_error(ctx, THX_ENOMEM, "out of memory (sort-last layers)");
    /* collective steps, reached by every rank whatever befell it before (st carried) */
    st = picture_part_frame_range(ctx, o, d, frame, st); /* the frame's range over the whole volume */
    thx_raytrace_volume vol;
    double jmax = -INFINITY;
    if (st == THX_OK && !strcmp(o->volume_render, "current")) { /* |J|'s largest over the ranks */
        d->part_jmax = NAN;
        st = volume_of(ctx, o, d, frame, &vol);
        jmax = d->vr_local_hi;
    }
    st = thx_par_max(ctx, st, &jmax, 1);
    if (st == THX_OK) d->part_jmax = jmax;
    int vp[4];
    thx_scene sc;
    thx_picture_viewport(o, font, w, h, vp);
    if (st == THX_OK) {
        if (rank == 0) build_surfaces(o, d, frame, b, -1);
        for (size_t i = 0; i < b->n && st == THX_OK; i++)
            if (b->rs[i].mode != THX_DRAW_HIDDEN && b->rs[i].surf->n_tris)
                st = thx_error(ctx, THX_EINPUT, "sort-last volume rendering blends the ranks' layers of the volume alone: '%s' "
                               "would be drawn (hide the surfaces: --mode hidden)", b->rs[i].surf->name);
        panel_scene(o, d, b, vp, 1, 1, 0, &sc);
    }
    thx_scale vol_scale;
    thx_colormap vol_cmap = THX_CMAP_ECG;
    if (st == THX_OK) {
        share_of share = {0, 1, NULL, layer};
        st = trace_panel(ctx, o, d, &sc, NULL, frame, img, &vol_scale, &vol_cmap, &share);
    }
    st = thx_par_agree(ctx, st, NULL);
    if (st == THX_OK) { /* the parts front to back from the eye (an orthographic camera's: far back along its view) */
        double eye[3], dir[3], len = 0;
        for (int k = 0; k < 3; k++) dir[k] = sc.camera.center[k] - sc.camera.eye[k], len += dir[k] * dir[k];
        len = sqrt(len);
        for (int k = 0; k < 3; k++)
            eye[k] = sc.camera.fov_deg > 0 || !(len > 0) ? sc.camera.eye[k] : sc.camera.eye[k] - 1e7 * dir[k] / len;
        thx_fem_cut_order((const thx_fem_cut *)d->part_cuts, size, eye, order + size);
        for (int k = 0; k < size; k++) order[k] = order[2 * size - 1 - k];
        st = thx_par_composite_blend(ctx, layer, w * (int)ns, h, order); /* (an image of w ns x h samples) */
    }
    if (st == THX_OK && rank == 0) {
        thx_raytrace_layer_finish(&sc, o->rt.samples, layer, img);
        collect_bars(d, b, bars);
        add_volume_bar(o, d, &vol_scale, vol_cmap, bars);
    }
    free(b);
    free(layer);
    free(order);
    return st;
}

thx_status thx_picture_draw_part(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r, thx_font *font,
                                 int frame, thx_raster *img, thx_picture_bars *bars, size_t *nan_total)
{
    if (o->volume_render) return draw_part_volume(ctx, o, d, font, frame, img, bars);
    int w = img->w, h = img->h, rank = thx_par_rank();
    thx_raster_fill(img, BG);
    memset(bars, 0, sizeof *bars);
    built_scene *b = calloc(1, sizeof *b);
    unsigned char *rgba = malloc(4 * (size_t)w * h), *mine = malloc(4 * (size_t)w * h);
    float *depth = malloc((size_t)w * h * sizeof *depth);
    thx_status st = b && rgba && mine && depth ? THX_OK : thx_error(ctx, THX_ENOMEM, "out of memory (sort-last layers)");
    /* collective steps, each reached by every rank whatever befell it before (st carried) */
    st = picture_part_frame_range(ctx, o, d, frame, st); /* 1: the frame's range over the whole volume */
    if (st == THX_OK) st = picture_field_build(ctx, o, d, frame);
    int vp[4];
    thx_scene sc;
    thx_picture_viewport(o, font, w, h, vp);
    size_t n_model = 0; /* the model's surfaces, first in b: in every rank's box, drawn by rank 0 alone */
    if (st == THX_OK) {
        build_surfaces(o, d, frame, b, -1);
        n_model = b->n;
        b->n += picture_field_surfaces(o, d, b->rs + b->n, sizeof b->rs / sizeof b->rs[0] - b->n);
        panel_scene(o, d, b, vp, 1, 1, 0, &sc);
        for (size_t i = 0; i < b->n && st == THX_OK; i++)
            if (b->rs[i].mode != THX_DRAW_HIDDEN && b->rs[i].color[3] < 1)
                st = thx_error(ctx, THX_EINPUT, "sort-last rendering composites by depth, so every surface drawn must be opaque: "
                               "'%s' is drawn at opacity %.2f (give it --surface %s=phong:1, or leave it out with --only)",
                               b->rs[i].surf->name, b->rs[i].color[3], b->rs[i].surf->name);
    }
    /* 2: one depth scale (the box of everything drawn, over the ranks), and |J|'s largest on the slices */
    double g[7] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY};
    if (st == THX_OK) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        scene_box(&sc, lo, hi);
        if (rank != 0) { /* the others draw their cuts alone */
            sc.surfaces = b->rs + n_model;
            sc.n_surfaces = b->n - n_model;
        }
        for (int k = 0; k < 3; k++) g[k] = -lo[k], g[3 + k] = hi[k];
        if (o->slice_current && d->field[1]) g[6] = d->field_hi[1];
    }
    st = thx_par_max(ctx, st, g, 7);
    if (st == THX_OK) {
        for (int k = 0; k < 3; k++) sc.box[0][k] = -g[k], sc.box[1][k] = g[3 + k];
        sc.have_box = 1;
        if (o->slice_current && d->field[1]) { /* the slices' |J| scale: the whole's */
            d->field_hi[1] = g[6];
            for (size_t i = 0; i < b->n; i++)
                if (b->rs[i].surf == &d->field_surf[1])
                    thx_scale_from_range_mapped(&b->rs[i].scale, THX_SCALE_LINEAR, THX_MAPPING_TRUE, d->field_lo[1], g[6]);
        }
        size_t nn = 0;
        st = thx_render_layer(ctx, r, &sc, rgba, depth, &nn);
        if (nan_total && rank == 0) *nan_total += b->nan_count; /* (the model's surfaces' values: rank 0 draws them) */
        if (st == THX_OK && rank == 0) memcpy(mine, rgba, 4 * (size_t)w * h);
    }
    /* 3: the layers composited by depth on rank 0 (every rank's status agreed first) */
    st = thx_par_agree(ctx, st, NULL);
    if (st == THX_OK) st = thx_par_composite_depth(ctx, rgba, depth, w, h);
    if (st == THX_OK && rank == 0) {
        for (size_t i = 0; i < (size_t)w * h; i++) /* drawn by no rank: rank 0's background */
            if (!(depth[i] < 1.0f)) memcpy(rgba + 4 * i, mine + 4 * i, 4);
        st = thx_render_layer_finish(ctx, r, &sc, rgba, img);
        if (st == THX_OK) collect_bars(d, b, bars);
    }
    free(b);
    free(rgba);
    free(mine);
    free(depth);
    return st;
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
    return draw_panels(ctx, o, d, r, font, frame, fb_w, fb_h, NULL, bars, nan_total, NULL);
}

