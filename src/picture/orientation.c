/*
 * Orientation letters (thorax/picture/picture.h): which anatomical directions - the subject's
 * right/left, anterior/posterior, superior/inferior - point to each edge of a picture, from its
 * camera and the anatomical frame of its views (the model's frame, or --up/--front).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "picture/picture_internal.h"

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static int unit(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(n > 0) || !isfinite(n)) return -1;
    for (int k = 0; k < 3; k++) v[k] /= n;
    return 0;
}

/* The letters of screen direction e (model coordinates, unit): the anatomical axes within about
   70 degrees of it, nearest first. */
static void letters_of(const thx_picture_opts *o, const double e[3], char text[4])
{
    static const char pos[3] = {'R', 'A', 'S'}, neg[3] = {'L', 'P', 'I'};
    double c[3];
    int order[3] = {0, 1, 2};
    for (int k = 0; k < 3; k++) c[k] = o->sg[k] * e[o->ax[k]]; /* component along canonical axis k */
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (fabs(c[order[j]]) > fabs(c[order[i]]) + 1e-12) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    int n = 0;
    for (int i = 0; i < 3; i++) {
        int k = order[i];
        if (i > 0 && fabs(c[k]) < 0.35) break;
        text[n++] = c[k] >= 0 ? pos[k] : neg[k];
    }
    text[n] = '\0';
}

void thx_picture_orientation_text(const thx_picture_opts *o, const thx_camera *cam, thx_picture_letter out[4])
{
    memset(out, 0, 4 * sizeof *out);
    double f[3], r[3], u[3];
    for (int k = 0; k < 3; k++) f[k] = cam->center[k] - cam->eye[k];
    /* the renderer's look-at: screen right = forward x up, screen up = right x forward */
    if (unit(f)) return;
    cross(f, cam->up, r);
    if (unit(r)) return;
    cross(r, f, u);
    double e[3];
    for (int k = 0; k < 3; k++) e[k] = -r[k];
    letters_of(o, e, out[0].text);
    letters_of(o, r, out[1].text);
    letters_of(o, u, out[2].text);
    for (int k = 0; k < 3; k++) e[k] = -u[k];
    letters_of(o, e, out[3].text);
}

int thx_picture_orientation(const thx_picture_opts *o, const thx_picture_data *d, thx_font *font, int w, int h,
                            thx_picture_letter *out, int max)
{
    int vp[4];
    thx_picture_viewport(o, font, w, h, vp);
    int cols = 1, rows = 1, panels = 1;
    if (o->panels) {
        panels = 0;
        for (size_t s = 0; s < d->m->n_surfaces; s++) {
            int shown = o->n_only == 0;
            for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], d->m->surf[s]->name);
            panels += shown;
        }
        cols = (int)ceil(sqrt((double)panels));
        rows = (panels + cols - 1) / cols;
    }
    int pw = vp[2] / cols, ph = vp[3] / rows, n = 0, fh = thx_font_height(font);
    for (int p = 0; p < panels && n + 4 <= max; p++) {
        thx_camera cam;
        thx_picture_camera(o, d, (double)pw / ph, &cam);
        thx_picture_letter L[4];
        thx_picture_orientation_text(o, &cam, L);
        int x0 = (p % cols) * pw, y0 = vp[1] + (p / cols) * ph;
        for (int k = 0; k < 4; k++) {
            int tw = font ? thx_text_width(font, L[k].text) : 0;
            switch (k) {
            case 0: L[k].x = x0 + 6; L[k].y = y0 + ph / 2 + fh / 2; break;
            case 1: L[k].x = x0 + pw - 6 - tw; L[k].y = y0 + ph / 2 + fh / 2; break;
            /* the top letter below a panel's title line */
            case 2: L[k].x = x0 + (pw - tw) / 2; L[k].y = y0 + (o->panels ? 2 : 1) * (fh + 2); break;
            default: L[k].x = x0 + (pw - tw) / 2; L[k].y = y0 + ph - 6; break;
            }
            out[n++] = L[k];
        }
    }
    return n;
}
