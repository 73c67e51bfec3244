/*
 * The scan under the model in a picture (issue 25; thorax/picture/picture.h, o->image): the image
 * read at load, its planes checked against its extent, their textures rebuilt when a plane, the
 * window or the level changes (the viewer moves them), and the contours of o->contours drawn on
 * the axial planes: the file's layer nearest each plane, each loop a closed line lying in the
 * plane, a colour per contour surface (the label table's colour k + 1 for the file's surface k).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/io/contours_file.h"
#include "picture/picture_internal.h"
#include "picture/scan.h"

thx_status picture_scan_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d)
{
    for (int k = 0; k < 4; k++) d->contour_z[k] = NAN;
    if (!o->image) {
        if (o->n_image_planes || o->contours || o->image_labels || o->window > 0 || o->have_level)
            return thx_error(ctx, THX_EINPUT, "%s: needs --image IMG (the scan the planes are cut from)",
                             o->contours ? "--contours" : o->n_image_planes ? "--image-plane" : o->image_labels ? "--image-labels"
                             : o->window > 0 ? "--image-window" : "--image-level");
        return THX_OK;
    }
    THX_CHECK(pic_scan_open(ctx, o->image, &d->scan));
    double w, l;
    pic_scan_window(d->scan, &w, &l, NULL);
    d->window = o->window > 0 ? o->window : w;
    d->level = o->have_level ? o->level : l;
    if (o->n_image_planes == 0) { /* the axial plane through the image's middle */
        double lo, hi, step;
        pic_scan_range(d->scan, 'z', &lo, &hi, &step);
        d->scan_axis[0] = 'z';
        d->scan_pos[0] = 0.5 * (lo + hi);
        d->n_scan_planes = 1;
    }
    for (int k = 0; k < o->n_image_planes && k < 4; k++) {
        if (pic_scan_parse(o->image_planes[k], &d->scan_axis[k], &d->scan_pos[k]) != 0)
            return thx_error(ctx, THX_EINPUT,
                             "--image-plane %s: not a plane (x=MM, y=MM, z=MM in the model's RAS millimetres, or the "
                             "image's own i=N, j=N, k=N)", o->image_planes[k]);
        double lo, hi, step;
        pic_scan_range(d->scan, d->scan_axis[k], &lo, &hi, &step);
        double tol = 1e-9 * (fabs(lo) + fabs(hi) + 1);
        if (!(d->scan_pos[k] >= lo - tol && d->scan_pos[k] <= hi + tol))
            return thx_error(ctx, THX_EINPUT, "--image-plane %s is outside %s: %c from %g to %g%s", o->image_planes[k],
                             o->image, d->scan_axis[k], lo, hi, d->scan_axis[k] <= 'z' && d->scan_axis[k] >= 'x' ? " mm" : "");
        d->n_scan_planes = k + 1;
    }
    if (o->contours) THX_CHECK(thx_contours_read_raw(ctx, o->contours, &d->contours));
    return THX_OK;
}

/* The contour file's layers nearest plane k (an axial plane at height z) as wire surfaces lying in
 * the plane: one per contour surface with a layer there, each loop's edges as degenerate triangles
 * (a, b, b), so the renderer's wire mode draws exactly the loop's edges. */
static thx_status contour_lines(thx_ctx *ctx, thx_picture_data *d, int k, double z)
{
    const thx_contours *c = d->contours;
    double *zs = NULL;
    size_t nz = 0;
    THX_CHECK(thx_contours_layer_z(ctx, c, &zs, &nz));
    double best = NAN, gap = 0;
    for (size_t i = 0; i < nz; i++) {
        if (isnan(best) || fabs(zs[i] - z) < fabs(best - z)) best = zs[i];
        if (i) gap = fmax(gap, zs[i] - zs[i - 1]);
    }
    free(zs);
    /* nearer than half the widest gap between layers (half a millimetre with one layer) */
    if (isnan(best) || fabs(best - z) > fmax(0.5 * gap, 0.5) + 1e-9) return THX_OK;
    d->contour_z[k] = best;
    for (size_t s = 0; s < c->n_surfaces && d->n_contour_lines < 64; s++) {
        const thx_contour_surface *cs = &c->surf[s];
        const thx_contour_layer *L = NULL;
        for (size_t j = 0; j < cs->n_layers; j++)
            if (cs->layers[j].z == best) L = &cs->layers[j];
        if (!L) continue;
        size_t n = 0;
        for (size_t j = 0; j < L->n_loops; j++) n += L->loops[j].n;
        if (!n || n > INT32_MAX) continue;
        thx_surface *sf = NULL;
        THX_CHECK(thx_surface_create(ctx, cs->name, THX_ROLE_OTHER, &sf));
        sf->xyz = thx_malloc(ctx, 3 * n * sizeof *sf->xyz);
        sf->tri = thx_malloc(ctx, 3 * n * sizeof *sf->tri);
        if (!sf->xyz || !sf->tri) {
            thx_surface_destroy(&sf);
            return THX_ENOMEM;
        }
        size_t at = 0;
        for (size_t j = 0; j < L->n_loops; j++) {
            const thx_loop *lp = &L->loops[j];
            for (size_t i = 0; i < lp->n; i++) {
                sf->xyz[3 * (at + i) + 0] = lp->p[i].x;
                sf->xyz[3 * (at + i) + 1] = lp->p[i].y;
                sf->xyz[3 * (at + i) + 2] = z;
                int32_t a = (int32_t)(at + i), b = (int32_t)(at + (i + 1) % lp->n);
                sf->tri[3 * (at + i) + 0] = a;
                sf->tri[3 * (at + i) + 1] = b;
                sf->tri[3 * (at + i) + 2] = b;
            }
            at += lp->n;
        }
        sf->n_nodes = n;
        sf->n_tris = n;
        unsigned char rgb[3];
        pic_scan_label_color((long)s + 1, rgb);
        float *col = d->contour_rgba[d->n_contour_lines];
        for (int i = 0; i < 3; i++) col[i] = rgb[i] / 255.0f;
        col[3] = 1;
        d->contour_lines[d->n_contour_lines++] = sf;
    }
    return THX_OK;
}

static void free_lines(thx_picture_data *d)
{
    for (int i = 0; i < d->n_contour_lines; i++) thx_surface_destroy(&d->contour_lines[i]);
    d->n_contour_lines = 0;
}

thx_status picture_scan_build(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d)
{
    if (!d->scan) return THX_OK;
    int changed = 0;
    for (int k = 0; k < d->n_scan_planes; k++) {
        double key[4] = {d->scan_pos[k], d->window, d->level, o->image_labels};
        if (d->scan_built[k] && !memcmp(key, d->scan_key[k], sizeof key)) continue;
        pic_scan_tex t;
        THX_CHECK(pic_scan_texture(ctx, d->scan, d->scan_axis[k], d->scan_pos[k], o->image_labels, d->window, d->level, &t));
        free(d->scan_rgba[k]);
        d->scan_rgba[k] = t.rgba;
        thx_render_plane *pl = &d->scan_plane[k];
        memset(pl, 0, sizeof *pl);
        pl->w = t.w;
        pl->h = t.h;
        pl->rgba = t.rgba;
        memcpy(pl->origin, t.origin, sizeof pl->origin);
        memcpy(pl->u, t.u, sizeof pl->u);
        memcpy(pl->v, t.v, sizeof pl->v);
        pl->nearest = t.nearest;
        memcpy(d->scan_key[k], key, sizeof key);
        d->scan_built[k] = 1;
        changed = 1;
    }
    if (!d->contours || (!changed && d->n_contour_lines)) return THX_OK;
    free_lines(d);
    int axial = 0;
    for (int k = 0; k < d->n_scan_planes; k++) {
        const thx_render_plane *pl = &d->scan_plane[k];
        d->contour_z[k] = NAN;
        /* axial: both edges without a z component (the contours' layers are planes of constant z) */
        if (fabs(pl->u[2]) > 1e-6 * (fabs(pl->u[0]) + fabs(pl->u[1])) ||
            fabs(pl->v[2]) > 1e-6 * (fabs(pl->v[0]) + fabs(pl->v[1])))
            continue;
        axial = 1;
        THX_CHECK(contour_lines(ctx, d, k, pl->origin[2]));
    }
    if (!axial)
        return thx_error(ctx, THX_EINPUT,
                         "--contours %s: the contours' layers are planes of constant z: give an axial --image-plane "
                         "(z=MM, or the image's own plane along z)", o->contours);
    return THX_OK;
}

size_t picture_scan_surfaces(const thx_picture_data *d, thx_render_surface *rs, size_t max)
{
    size_t n = 0;
    for (int i = 0; i < d->n_contour_lines && n < max; i++) {
        thx_render_surface *r = &rs[n++];
        memset(r, 0, sizeof *r);
        r->surf = d->contour_lines[i];
        r->mode = THX_DRAW_WIRE;
        memcpy(r->color, d->contour_rgba[i], sizeof r->color);
        r->line_width = 2;
        r->no_clip = 1;
    }
    return n;
}

void picture_scan_free(thx_picture_data *d)
{
    free_lines(d);
    for (int k = 0; k < 4; k++) {
        free(d->scan_rgba[k]);
        d->scan_rgba[k] = NULL;
        d->scan_built[k] = 0;
    }
    thx_contours_destroy(&d->contours);
    pic_scan_close(&d->scan);
}

int thx_picture_scan_move(thx_picture_data *d, int k, int n)
{
    if (!d->scan || k < 0 || k >= d->n_scan_planes) return 0;
    double lo, hi, step, old = d->scan_pos[k], pos;
    pic_scan_range(d->scan, d->scan_axis[k], &lo, &hi, &step);
    if (d->scan_axis[k] >= 'i' && d->scan_axis[k] <= 'k') { /* an index: the next whole index */
        pos = floor(old + 0.5) + n;
        pos = fmin(fmax(pos, lo), hi);
    } else { /* millimetres: the planes of voxel centres, half a step inside the faces */
        double c0 = lo + 0.5 * step, m = floor((old - c0) / step + 0.5) + n, top = floor((hi - lo) / step + 1e-6) - 1;
        m = fmin(fmax(m, 0), fmax(top, 0));
        pos = c0 + m * step;
    }
    d->scan_pos[k] = pos;
    return pos != old;
}

const struct thx_image *thx_picture_scan_image(const thx_picture_data *d)
{
    return d->scan ? pic_scan_image(d->scan) : NULL;
}

void thx_picture_scan_describe(const thx_picture_data *d, char *buf, size_t size)
{
    if (!d->scan || !d->n_scan_planes) {
        snprintf(buf, size, "no image");
        return;
    }
    int ras = d->scan_axis[0] <= 'z' && d->scan_axis[0] >= 'x';
    snprintf(buf, size, "image plane %c=%g%s, window %g level %g", d->scan_axis[0], d->scan_pos[0], ras ? " mm" : "",
             d->window, d->level);
}
