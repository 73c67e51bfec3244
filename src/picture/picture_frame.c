/*
 * Where a picture looks from (thorax/picture/picture.h): the anatomical frame of the views (the
 * model's, or --up and --front), the standard views' cameras, and clip planes named by a side.
 */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "picture/picture_internal.h"

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
    if (colon) { /* the fraction of the depth kept, 0 < F <= 1 (0 or less removes everything) */
        char *end;
        f = strtod(colon + 1, &end);
        if (end == colon + 1 || *end || !(f > 0 && f <= 1)) return -2;
    }
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
thx_status picture_view_frame(thx_ctx *ctx, thx_picture_opts *o, const thx_picture_data *d)
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

void thx_picture_camera(const thx_picture_opts *o, const thx_picture_data *d, double aspect, thx_camera *cam)
{
    if (o->have_camera) { *cam = o->cam; return; }
    thx_picture_view_camera(o, d, o->view, aspect, cam);
}

/* The box of the surfaces drawn (o->only; all when none is named or none of them has a node). */
static void shown_bounds(const thx_picture_opts *o, const thx_picture_data *d, double lo[3], double hi[3])
{
    thx_picture_bounds(d, lo, hi);
    if (o->n_only == 0) return;
    const thx_model *m = d->m;
    double a[3] = {INFINITY, INFINITY, INFINITY}, b[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t s = 0; s < m->n_surfaces; s++) {
        int shown = 0;
        for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
        if (!shown) continue;
        for (size_t i = 0; i < m->surf[s]->n_nodes; i++)
            for (int k = 0; k < 3; k++) {
                a[k] = fmin(a[k], m->surf[s]->xyz[3 * i + k]);
                b[k] = fmax(b[k], m->surf[s]->xyz[3 * i + k]);
            }
    }
    if (a[0] <= b[0])
        for (int k = 0; k < 3; k++) { lo[k] = a[k]; hi[k] = b[k]; }
}

void thx_picture_view_camera(const thx_picture_opts *o, const thx_picture_data *d, int view, double aspect, thx_camera *cam)
{
    double lo[3], hi[3], qlo[3], qhi[3];
    shown_bounds(o, d, lo, hi); /* each window of --separate (or --only) framed on its own surfaces */
    box_to_frame(o, lo, hi, qlo, qhi);
    /* the standard view in the anatomical frame, carried back to the model's axes */
    thx_camera c;
    thx_camera_view(&c, (thx_view)view, qlo, qhi, aspect);
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
    int pc = parse_clip(o->clip, qlo, qhi, p, &named);
    if (pc == -2) {
        thx_error(ctx, THX_EINPUT, "--clip '%s': the fraction of the depth kept is a number above 0 and at most 1 (0 or "
                  "less would remove the whole model)", o->clip);
        return -1;
    }
    if (pc) {
        thx_error(ctx, THX_EINPUT, "--clip '%s': a side (anterior, posterior, left, right, superior, inferior[:fraction]) or nx,ny,nz,d", o->clip);
        return -1;
    }
    if (!named && !(p->n[0] != 0 || p->n[1] != 0 || p->n[2] != 0)) {
        thx_error(ctx, THX_EINPUT, "--clip '%s': the plane's normal nx,ny,nz is zero", o->clip);
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

thx_status thx_picture_clip_check(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d)
{
    thx_clip_plane p;
    int nc = thx_picture_clip(ctx, o, d, &p);
    if (nc < 0) return THX_EINPUT;
    if (nc == 0) return THX_OK;
    const thx_model *m = d->m;
    size_t kept = 0, cut = 0;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        int shown = o->n_only == 0, whole = 0;
        for (int k = 0; k < o->n_only; k++) shown |= !strcmp(o->only[k], m->surf[s]->name);
        for (int k = 0; k < o->n_whole; k++) whole |= !strcmp(o->whole[k], m->surf[s]->name);
        if (!shown) continue;
        if (whole) return THX_OK; /* drawn whole: something is left */
        const thx_surface *sf = m->surf[s];
        for (size_t i = 0; i < sf->n_nodes; i++) {
            const double *x = sf->xyz + 3 * i;
            kept += p.n[0] * x[0] + p.n[1] * x[1] + p.n[2] * x[2] + p.d >= 0;
        }
        cut += sf->n_nodes;
    }
    if (cut && !kept)
        return thx_error(ctx, THX_EINPUT, "--clip '%s' removes the whole picture: none of the %zu nodes of the surfaces drawn "
                         "is on the kept side (n.x + d >= 0 with n = %g,%g,%g, d = %g)", o->clip, cut, p.n[0], p.n[1], p.n[2], p.d);
    return THX_OK;
}
