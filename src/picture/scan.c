/*
 * The scan under the model (picture/scan.h, issue 25): --image read once, its planes cut by
 * thorax/image/sample.h and turned into textures for the renderer's image planes.
 */
#include "scan.h"

#include "thorax/image/image.h"
#include "thorax/image/sample.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct pic_scan {
    thx_image img;
    thx_window_kind kind;
    double window, level;
};

thx_status pic_scan_open(thx_ctx *ctx, const char *path, pic_scan **out)
{
    *out = NULL;
    pic_scan *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    thx_status st = thx_image_read(ctx, path, NULL, &s->img);
    if (st != THX_OK) {
        free(s);
        return st;
    }
    s->kind = thx_image_window_default(&s->img, &s->window, &s->level);
    *out = s;
    return THX_OK;
}

const struct thx_image *pic_scan_image(const pic_scan *s) { return &s->img; }

void pic_scan_close(pic_scan **s)
{
    if (!s || !*s) return;
    thx_image_free(&(*s)->img);
    free(*s);
    *s = NULL;
}

void pic_scan_window(const pic_scan *s, double *window, double *level, const char **why)
{
    *window = s->window;
    *level = s->level;
    if (why) *why = thx_window_kind_name(s->kind);
}

int pic_scan_is_labels(const pic_scan *s)
{
    return s->kind == THX_WINDOW_LABELS;
}

int pic_scan_parse(const char *spec, char *axis, double *pos)
{
    thx_image_plane_spec p;
    if (thx_image_plane_parse(spec, &p) != 0) return -1;
    *axis = p.axis;
    *pos = p.pos;
    return 0;
}

void pic_scan_range(const pic_scan *s, char axis, double *lo, double *hi, double *step)
{
    thx_image_plane_range(&s->img, axis, lo, hi, step);
}

/* A categorical table: distinct hues, bright enough over black (label 0). */
static const unsigned char LABEL_RGB[12][3] = {
    {230, 159, 0},  {86, 180, 233}, {0, 158, 115},  {240, 228, 66},  {0, 114, 178},   {213, 94, 0},
    {204, 121, 167}, {255, 255, 255}, {153, 153, 255}, {255, 128, 128}, {128, 255, 128}, {180, 120, 60}};

void pic_scan_label_color(long k, unsigned char rgb[3])
{
    if (k == 0) {
        rgb[0] = rgb[1] = rgb[2] = 0;
        return;
    }
    long i = (k > 0 ? k - 1 : -k) % 12;
    memcpy(rgb, LABEL_RGB[i], 3);
}

thx_status pic_scan_texture(thx_ctx *ctx, const pic_scan *s, char axis, double pos, int labels, double window,
                            double level, pic_scan_tex *out)
{
    memset(out, 0, sizeof *out);
    thx_image_plane_spec spec = {axis, pos};
    thx_image_slice sl;
    int nearest = labels || s->kind == THX_WINDOW_LABELS;
    THX_CHECK(thx_image_sample_plane(ctx, &s->img, &spec, nearest, &sl));
    out->rgba = thx_malloc(ctx, 4 * sl.w * sl.h);
    if (!out->rgba) {
        thx_image_slice_free(&sl);
        return THX_ENOMEM;
    }
    double w = window > 0 ? window : 1, base = level - 0.5 * w;
    for (size_t i = 0; i < sl.w * sl.h; i++) {
        unsigned char *q = out->rgba + 4 * i;
        float v = sl.v[i];
        if (isnan(v)) {
            q[0] = q[1] = q[2] = q[3] = 0;
            continue;
        }
        if (labels) {
            pic_scan_label_color(lround(v), q);
        } else {
            double g = fmin(fmax((v - base) / w, 0), 1);
            q[0] = q[1] = q[2] = (unsigned char)lround(255 * g);
        }
        q[3] = 255;
    }
    out->w = (int)sl.w;
    out->h = (int)sl.h;
    out->nearest = nearest;
    for (int k = 0; k < 3; k++) {
        out->origin[k] = sl.origin[k] - 0.5 * sl.du[k] - 0.5 * sl.dv[k];
        out->u[k] = (double)sl.w * sl.du[k];
        out->v[k] = (double)sl.h * sl.dv[k];
        out->normal[k] = sl.normal[k];
    }
    thx_image_slice_free(&sl);
    return THX_OK;
}
