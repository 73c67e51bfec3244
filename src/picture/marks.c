/*
 * Marks over a picture (map3d's node labels and extrema marks; paper 4.2; electrodes' names): a surface's nodes
 * labelled with their number, recording channel or value, and the largest and smallest value of
 * each surface's data marked. A node is labelled only where the camera sees it — the ray from the
 * eye through it meets it first (thorax/geom/pick.h, clip plane and hidden surfaces honoured) —
 * and where its label overlaps none drawn before (nodes nearer the viewer first), so a dense mesh
 * gives a readable sample instead of a smear. An extremum behind the surface is drawn in grey.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "picture/picture_internal.h"
#include "thorax/geom/pick.h"

typedef struct {
    size_t node;
    double x, y, depth;
} cand;

static int by_depth(const void *a, const void *b)
{
    double u = ((const cand *)a)->depth, v = ((const cand *)b)->depth;
    return (u > v) - (u < v);
}

/* Whether surface s is drawn in the picture. */
static int shown(const thx_picture_opts *o, const thx_model *m, int s)
{
    int on = o->n_only == 0;
    for (int k = 0; k < o->n_only; k++) on |= !strcmp(o->only[k], m->surf[s]->name);
    thx_draw_mode mode = (thx_draw_mode)o->mode;
    for (int k = 0; k < o->n_look; k++)
        if (!strcmp(o->look[k].name, m->surf[s]->name)) mode = o->look[k].mode;
    return on && mode != THX_DRAW_HIDDEN;
}

typedef struct {
    thx_camera cam;
    int vp[4];
    thx_pick_opts po;
    thx_pick_plane clip;
    unsigned char skip[THX_PICTURE_SURFACES];
    double tol;
    const char *const *whole; /* surfaces the clip plane leaves whole */
    int n_whole;
} seeing;

/* Whether node i of surface s is the first thing the eye meets along its line of sight: 1 yes, 0
 * behind something, -1 cut away by the clip plane. */
static int visible(thx_ctx *ctx, const thx_picture_data *d, const seeing *v, int s, size_t i, double x, double y)
{
    const double *p = d->m->surf[s]->xyz + 3 * i;
    int whole = 0;
    for (int k = 0; k < v->n_whole; k++) whole |= !strcmp(v->whole[k], d->m->surf[s]->name);
    if (v->po.n_clip && !whole && v->clip.n[0] * p[0] + v->clip.n[1] * p[1] + v->clip.n[2] * p[2] + v->clip.d < 0) return -1;
    double o[3], dir[3];
    if (thx_camera_ray(&v->cam, v->vp[2], v->vp[3], x, y, o, dir)) return 0;
    thx_pick_hit hit;
    if (thx_pick_ray(ctx, d->pick, o, dir, &v->po, &hit) != THX_OK || hit.surface < 0) return 0;
    double t = 0;
    for (int k = 0; k < 3; k++) t += (p[k] - o[k]) * dir[k];
    return hit.t >= t - v->tol;
}

static void text_shadowed(thx_raster *img, thx_font *font, int x, int y, const char *s, const unsigned char rgba[4])
{
    static const unsigned char black[4] = {0, 0, 0, 200};
    thx_draw_text(img, font, x + 1, y + 1, s, black);
    thx_draw_text(img, font, x, y, s, rgba);
}

thx_status picture_marks(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font, int frame,
                         thx_raster *img)
{
    const thx_model *m = d->m;
    if (!font || o->panels || (!o->n_labels && !o->extrema && !d->n_elec && !o->n_pins)) return THX_OK;
    size_t n = m->n_surfaces < THX_PICTURE_SURFACES ? m->n_surfaces : THX_PICTURE_SURFACES;
    if (!d->pick) {
        const thx_surface *surf[THX_PICTURE_SURFACES];
        for (size_t s = 0; s < n; s++) surf[s] = m->surf[s];
        THX_CHECK(thx_pick_index_create(ctx, surf, n, &d->pick));
    }
    seeing v;
    memset(&v, 0, sizeof v);
    thx_picture_viewport(o, font, img->w, img->h, v.vp);
    if (v.vp[2] <= 0 || v.vp[3] <= 0) return THX_OK;
    thx_picture_camera(o, d, (double)v.vp[2] / v.vp[3], &v.cam);
    thx_pick_opts_default(&v.po);
    for (size_t s = 0; s < n; s++) v.skip[s] = !shown(o, m, (int)s);
    v.po.skip = v.skip;
    v.whole = o->whole;
    v.n_whole = o->n_whole;
    thx_clip_plane cp;
    int nc = thx_picture_clip(ctx, o, d, &cp);
    if (nc < 0) return THX_EINPUT;
    if (nc > 0) {
        memcpy(v.clip.n, cp.n, sizeof v.clip.n);
        v.clip.d = cp.d;
        v.po.clip = &v.clip;
        v.po.n_clip = 1;
    }
    double lo[3], hi[3], diag = 0;
    thx_picture_bounds(d, lo, hi);
    for (int k = 0; k < 3; k++) diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    v.tol = 1e-3 * sqrt(diag) + 1e-6;
    static const unsigned char white[4] = {245, 245, 245, 255}, grey[4] = {150, 150, 150, 255};
    int fh = thx_font_height(font);
    /* node labels: the visible nodes nearest the viewer first, a label where none is yet */
    for (int k = 0; k < o->n_labels; k++) {
        const char *eq = strchr(o->labels[k], '=');
        if (!eq) return thx_error(ctx, THX_EINPUT, "--node-labels '%s': give SURFACE=index|channel|value", o->labels[k]);
        const char *what = eq + 1;
        int s = -1;
        for (size_t j = 0; j < n; j++)
            if (strlen(m->surf[j]->name) == (size_t)(eq - o->labels[k]) && !strncmp(m->surf[j]->name, o->labels[k], (size_t)(eq - o->labels[k])))
                s = (int)j;
        if (s < 0) return thx_error(ctx, THX_EINPUT, "--node-labels '%s': the model has no surface '%.*s'", o->labels[k], (int)(eq - o->labels[k]), o->labels[k]);
        int kind = !strcmp(what, "index") ? 0 : !strcmp(what, "channel") ? 1 : !strcmp(what, "value") ? 2 : -1;
        if (kind < 0) return thx_error(ctx, THX_EINPUT, "--node-labels '%s': label with index, channel or value", o->labels[k]);
        if (kind == 1 && !d->channel[s])
            return thx_error(ctx, THX_EINPUT, "--node-labels '%s': surface '%s' has no channels (give --data with --channels)", o->labels[k], m->surf[s]->name);
        if (kind == 2 && !d->series[s])
            return thx_error(ctx, THX_EINPUT, "--node-labels '%s': surface '%s' has no data", o->labels[k], m->surf[s]->name);
        if (v.skip[s]) continue;
        const thx_surface *sf = m->surf[s];
        cand *c = malloc((sf->n_nodes ? sf->n_nodes : 1) * sizeof *c);
        unsigned char *used = calloc((size_t)img->w * (size_t)img->h, 1);
        if (!c || !used) { free(c); free(used); return thx_error(ctx, THX_ENOMEM, "out of memory (labels)"); }
        size_t nc2 = 0;
        for (size_t i = 0; i < sf->n_nodes; i++) {
            double x, y, dep;
            if (thx_camera_project(&v.cam, v.vp[2], v.vp[3], sf->xyz + 3 * i, &x, &y, &dep)) continue;
            if (x < 0 || y < 0 || x >= v.vp[2] || y >= v.vp[3]) continue;
            c[nc2++] = (cand){i, x, y, dep};
        }
        qsort(c, nc2, sizeof *c, by_depth);
        const thx_series *x = d->series[s];
        size_t f = x ? ((size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1) : 0;
        for (size_t j = 0; j < nc2; j++) {
            char text[48];
            size_t i = c[j].node;
            if (kind == 0) snprintf(text, sizeof text, "%zu", i + 1);
            else if (kind == 1) {
                if (d->channel[s][i] <= 0) continue;
                snprintf(text, sizeof text, "%d", d->channel[s][i]);
            } else {
                double val = x->v[f * x->n_rows + i];
                if (!isfinite(val)) continue;
                snprintf(text, sizeof text, "%.3g", val);
            }
            int px = v.vp[0] + (int)lround(c[j].x), py = v.vp[1] + (int)lround(c[j].y);
            int tw = thx_text_width(font, text) + 6, x0 = px + 3, y0 = py - fh + 2;
            if (x0 < 0 || y0 < 0 || x0 + tw >= img->w || py + 3 >= img->h) continue;
            int clash = 0;
            for (int yy = y0; yy < py + 3 && !clash; yy += 2)
                for (int xx = x0; xx < x0 + tw && !clash; xx += 2) clash = used[(size_t)yy * (size_t)img->w + (size_t)xx];
            if (clash || visible(ctx, d, &v, s, i, c[j].x, c[j].y) != 1) continue;
            for (int yy = y0 - 2; yy < py + 4; yy++)
                for (int xx = x0 - 4; xx < x0 + tw; xx++)
                    if (yy >= 0 && xx >= 0 && yy < img->h && xx < img->w) used[(size_t)yy * (size_t)img->w + (size_t)xx] = 1;
            thx_draw_rect(img, px - 1, py - 1, 3, 3, white);
            text_shadowed(img, font, x0 + 2, py, text, white);
        }
        free(c);
        free(used);
    }
    /* electrodes (--electrodes): each one's name beside its sphere, wherever it is (the spheres are
       never clipped, like landmarks); dimmed when the electrode is behind the surfaces */
    for (int k = 0; k < d->n_elec; k++) {
        const thx_electrodes *e = d->elec[k];
        int es = -1;
        for (size_t j = 0; j < n; j++)
            if (!strcmp(m->surf[j]->name, e->surface)) es = (int)j;
        for (size_t i = 0; i < e->n; i++) {
            double px, py, dep;
            if (thx_camera_project(&v.cam, v.vp[2], v.vp[3], e->xyz + 3 * i, &px, &py, &dep)) continue;
            if (px < 0 || py < 0 || px >= v.vp[2] || py >= v.vp[3]) continue;
            int seen = es >= 0 && e->node[i] >= 0 && (size_t)e->node[i] < m->surf[es]->n_nodes
                           ? visible(ctx, d, &v, es, (size_t)e->node[i], px, py) != 0
                           : 1;
            int cx = v.vp[0] + (int)lround(px), cy = v.vp[1] + (int)lround(py);
            text_shadowed(img, font, cx + 8, cy + fh / 3, e->name[i], seen ? white : grey);
        }
    }
    /* picked nodes: a ring in the pin's colour (filled when seen) and the node's number */
    for (int k = 0; k < o->n_pins && k < 8; k++) {
        int s = o->pins[k].surface;
        size_t i = o->pins[k].node;
        if (s < 0 || (size_t)s >= n || i >= m->surf[s]->n_nodes || v.skip[s]) continue;
        double px, py, dep;
        if (thx_camera_project(&v.cam, v.vp[2], v.vp[3], m->surf[s]->xyz + 3 * i, &px, &py, &dep)) continue;
        if (px < 0 || py < 0 || px >= v.vp[2] || py >= v.vp[3]) continue;
        int seen = visible(ctx, d, &v, s, i, px, py) == 1;
        unsigned char col[4] = {o->pins[k].rgba[0], o->pins[k].rgba[1], o->pins[k].rgba[2], 255};
        if (!seen)
            for (int c = 0; c < 3; c++) col[c] = (unsigned char)((col[c] + 2 * 110) / 3);
        static const unsigned char dark[4] = {0, 0, 0, 255};
        int cx = v.vp[0] + (int)lround(px), cy = v.vp[1] + (int)lround(py);
        for (int a = 0; a < 24; a++) { /* a dark ring under a coloured one: seen on any colour */
            double t0 = 2 * M_PI * a / 24, t1 = 2 * M_PI * (a + 1) / 24;
            thx_draw_line(img, cx + 6 * cos(t0), cy + 6 * sin(t0), cx + 6 * cos(t1), cy + 6 * sin(t1), 3.5, dark);
            thx_draw_line(img, cx + 6 * cos(t0), cy + 6 * sin(t0), cx + 6 * cos(t1), cy + 6 * sin(t1), 2, col);
        }
        if (seen) thx_draw_rect(img, cx - 2, cy - 2, 5, 5, col);
        char text[32];
        snprintf(text, sizeof text, "%zu", i + 1);
        text_shadowed(img, font, cx + 9, cy - 4, text, col);
    }
    /* extrema of each surface's data at the frame */
    if (o->extrema)
        for (size_t s = 0; s < n; s++) {
            const thx_series *x = d->series[s];
            if (!x || v.skip[s]) continue;
            size_t f = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
            const double *val = x->v + f * x->n_rows;
            size_t imax = (size_t)-1, imin = (size_t)-1;
            for (size_t i = 0; i < x->n_rows; i++) {
                if (!isfinite(val[i])) continue;
                if (imax == (size_t)-1 || val[i] > val[imax]) imax = i;
                if (imin == (size_t)-1 || val[i] < val[imin]) imin = i;
            }
            for (int e = 0; e < 2 && imax != (size_t)-1; e++) {
                size_t i = e ? imin : imax;
                double px, py, dep;
                if (thx_camera_project(&v.cam, v.vp[2], v.vp[3], m->surf[s]->xyz + 3 * i, &px, &py, &dep)) continue;
                if (px < 0 || py < 0 || px >= v.vp[2] || py >= v.vp[3]) continue;
                int seen = visible(ctx, d, &v, (int)s, i, px, py);
                const unsigned char *col = seen == 1 ? white : grey;
                int cx = v.vp[0] + (int)lround(px), cy = v.vp[1] + (int)lround(py);
                /* a plus for the largest, a minus for the smallest, in a ring */
                for (int a = 0; a < 24; a++) {
                    double t0 = 2 * M_PI * a / 24, t1 = 2 * M_PI * (a + 1) / 24;
                    thx_draw_line(img, cx + 7 * cos(t0), cy + 7 * sin(t0), cx + 7 * cos(t1), cy + 7 * sin(t1), 1.5, col);
                }
                thx_draw_line(img, cx - 4, cy, cx + 4, cy, 2, col);
                if (!e) thx_draw_line(img, cx, cy - 4, cx, cy + 4, 2, col);
                char text[64];
                snprintf(text, sizeof text, "%s %.3g %s%s", e ? "min" : "max", val[i], x->unit,
                         seen == 1 ? "" : seen < 0 ? " (clipped)" : " (behind)");
                text_shadowed(img, font, cx + 10, cy + fh / 3, text, col);
            }
        }
    return THX_OK;
}
