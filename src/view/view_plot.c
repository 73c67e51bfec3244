/*
 * Picking and the plot pane (paper 4.2; map3d's pick window): a click casts the ray under the
 * pointer through the camera (thorax/geom/pick.h: watertight, clip planes honoured, hidden
 * surfaces skipped); the node nearest the hit is reported (index, coordinates, value, the
 * triangle) and its time signal joins the traces under the picture (at most VIEW_MAX_TRACES, the
 * oldest dropped), each drawn by the same trace code as `thorax render --trace`, with a marker
 * at the current frame. The traces export as text (time, then one column per trace).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/geom/pick.h"
#include "view/view_internal.h"

#define TRACE_H 110    /* pixels per trace, when they fit */
#define TRACE_MIN_H 64 /* ... at least: more traces than fit the pane are scrolled */
#define PANE_H 220     /* the trace pane's height (at most a third of the window's drawing area) */

/* The pane's height: two traces, or a third of the drawing area of a small window. */
static int pane_height(const view_app *a)
{
    int h = a->vo->win_h / 3;
    return h < PANE_H ? (h < TRACE_MIN_H ? TRACE_MIN_H : h) : PANE_H;
}

/* Each trace's colour, also its picked node's marker in the picture (view_picture). */
const unsigned char view_trace_colors[VIEW_MAX_TRACES][4] = {{120, 230, 120, 255}, {250, 200, 80, 255}, {110, 180, 250, 255},
                                                             {240, 120, 200, 255}, {200, 200, 200, 255}, {250, 120, 90, 255}};

static gboolean on_plot_scroll(GtkEventControllerScroll *c, double dx, double dy, gpointer user)
{
    view_win *w = user;
    g_action_group_activate_action(G_ACTION_GROUP(w->app->gapp), "plot-zoom", g_variant_new_double(pow(1.25, -dy)));
    return TRUE;
}

void view_plot_attach(view_win *w)
{
    gtk_widget_set_size_request(w->plot, -1, 0);
    gtk_picture_set_can_shrink(GTK_PICTURE(w->plot), FALSE);
    GtkEventController *scroll = gtk_event_controller_scroll_new(GTK_EVENT_CONTROLLER_SCROLL_VERTICAL);
    g_signal_connect(scroll, "scroll", G_CALLBACK(on_plot_scroll), w);
    gtk_widget_add_controller(w->plot, scroll);
}

/* The frames the plot shows: all, or 1/zoom of them centred on the frame (kept inside). */
static void plot_window(const view_app *a, size_t n, size_t frame, size_t *f0, size_t *f1)
{
    double z = a->plot_zoom > 1 ? a->plot_zoom : 1;
    size_t span = (size_t)ceil((double)n / z);
    if (span < 8) span = n < 8 ? n : 8;
    size_t lo = frame > span / 2 ? frame - span / 2 : 0;
    if (lo + span > n) lo = n - span;
    *f0 = lo;
    *f1 = lo + span;
}

/* The first trace's time axis in a pane image `width` pixels wide (thx_draw_trace's layout in the box
 * at x = 8, 16 pixels narrower, inset by 2): the frames shown f0..f1 and the series. NULL: no traces. */
static const thx_series *plot_axis(const view_win *w, int width, size_t *f0, size_t *f1, double *px, double *pw)
{
    const view_app *a = w->app;
    if (a->n_traces == 0) return NULL;
    const thx_series *x = a->d.series[a->traces[0].surface];
    if (!x || x->n_frames < 2) return NULL;
    int frame = view_frame_of(w);
    size_t fr = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1;
    plot_window(a, x->n_frames, fr, f0, f1);
    *px = 8 + 2 + 0.5;
    *pw = width - 16 - 4 - 1;
    return *f1 - *f0 > 1 && *pw > 1 ? x : NULL;
}

int view_plot_time_at(view_win *w, double x, double *t)
{
    const GdkPaintable *p = gtk_picture_get_paintable(GTK_PICTURE(w->plot));
    if (!p) return -1;
    int iw = gdk_paintable_get_intrinsic_width((GdkPaintable *)p), ih = gdk_paintable_get_intrinsic_height((GdkPaintable *)p);
    double ww = gtk_widget_get_width(w->plot), wh = gtk_widget_get_height(w->plot);
    double scale = iw > 0 && ih > 0 ? fmin(ww / iw, wh / ih) : 1; /* the image as GtkPicture shows it: fitted, centred */
    if (!(scale > 0)) scale = 1;
    x = (x - 0.5 * (ww - scale * iw)) / scale;
    size_t f0, f1;
    double px, pw;
    const thx_series *s = plot_axis(w, iw, &f0, &f1, &px, &pw);
    if (!s) return -1;
    double i = (x - px) / pw * (double)(f1 - f0 - 1), dt = s->time[1] - s->time[0];
    if (i < 0) i = 0;
    if (i > (double)(f1 - f0 - 1)) i = (double)(f1 - f0 - 1);
    *t = s->time[f0] + i * dt;
    return 0;
}

/* The window being dragged on the pane (the panel's activation window), shaded over the traces. */
static void shade_selection(const view_win *w, thx_raster *img)
{
    const view_app *a = w->app;
    size_t f0, f1;
    double px, pw;
    const thx_series *s = plot_axis(w, img->w, &f0, &f1, &px, &pw);
    if (!s || !a->cuts.selecting) return;
    double dt = s->time[1] - s->time[0], t0 = fmin(a->cuts.sel[0], a->cuts.sel[1]), t1 = fmax(a->cuts.sel[0], a->cuts.sel[1]);
    int x0 = (int)floor(px + (t0 - s->time[f0]) / dt / (double)(f1 - f0 - 1) * pw);
    int x1 = (int)ceil(px + (t1 - s->time[f0]) / dt / (double)(f1 - f0 - 1) * pw);
    for (int y = 0; y < img->h; y++)
        for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < img->w; x++) {
            unsigned char *q = img->rgba + 4 * ((size_t)y * (size_t)img->w + (size_t)x);
            q[0] = (unsigned char)((q[0] + 2 * 90) / 3);
            q[1] = (unsigned char)((q[1] + 2 * 110) / 3);
            q[2] = (unsigned char)((q[2] + 2 * 170) / 3);
        }
}

/* The traces as one image, one row each (thx_draw_trace), then shown in every window's pane. */
void view_plot_update(view_app *a)
{
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        int pane = pane_height(a);
        if (a->n_traces == 0) {
            /* the drawing area takes the pane's room back: the window keeps its size */
            if (gtk_widget_get_visible(w->plot_scroll)) gtk_widget_set_size_request(w->gl, a->vo->win_w, a->vo->win_h);
            gtk_widget_set_visible(w->plot_scroll, FALSE);
            continue;
        }
        int width = gtk_widget_get_width(w->gl);
        if (width < 64) width = a->vo->win_w;
        /* the traces share the pane (stacked), each at least TRACE_MIN_H high; beyond, it scrolls */
        int trace_h = pane / a->n_traces;
        if (trace_h > TRACE_H) trace_h = TRACE_H;
        if (trace_h < TRACE_MIN_H) trace_h = TRACE_MIN_H;
        int height = trace_h * a->n_traces;
        if (height < pane) height = pane; /* the pane's background under fewer traces than fill it */
        thx_raster *img = NULL;
        if (thx_raster_create(a->ctx, width, height, &img) != THX_OK) return;
        static const unsigned char bg[4] = {24, 24, 28, 255};
        thx_raster_fill(img, bg);
        if (!w->plot_font) thx_font_open(a->ctx, w->o.font, 13, &w->plot_font);
        int frame = view_frame_of(w);
        for (int t = 0; t < a->n_traces; t++) {
            const thx_series *x = a->d.series[a->traces[t].surface];
            if (!x) continue;
            size_t row = a->traces[t].node, fr = (size_t)frame < x->n_frames ? (size_t)frame : x->n_frames - 1, f0, f1;
            plot_window(a, x->n_frames, fr, &f0, &f1);
            size_t n = f1 - f0;
            double *v = malloc(n * sizeof *v);
            if (!v) break;
            for (size_t f = 0; f < n; f++) v[f] = x->v[(f0 + f) * x->n_rows + row];
            char label[128];
            snprintf(label, sizeof label, "%s node %zu", a->d.m->surf[a->traces[t].surface]->name, row + 1);
            double dt = n > 1 ? x->time[1] - x->time[0] : 1;
            thx_draw_trace(img, w->plot_font, 8, t * trace_h + 4, width - 16, trace_h - 8, v, n, x->time[f0], dt, fr - f0,
                           label, x->unit, view_trace_colors[t % VIEW_MAX_TRACES]);
            free(v);
        }
        shade_selection(w, img);
        GBytes *bytes = g_bytes_new(img->rgba, (size_t)width * (size_t)height * 4);
        GdkTexture *tex = gdk_memory_texture_new(width, height, GDK_MEMORY_R8G8B8A8, bytes, (size_t)width * 4);
        gtk_picture_set_paintable(GTK_PICTURE(w->plot), GDK_PAINTABLE(tex));
        gtk_widget_set_size_request(w->plot, -1, height);
        gtk_scrolled_window_set_min_content_height(GTK_SCROLLED_WINDOW(w->plot_scroll), pane);
        gtk_scrolled_window_set_max_content_height(GTK_SCROLLED_WINDOW(w->plot_scroll), pane);
        if (!gtk_widget_get_visible(w->plot_scroll)) {
            /* the pane takes its room from the drawing area, not from the screen: the window keeps its size */
            int gh = a->vo->win_h - pane;
            gtk_widget_set_size_request(w->gl, a->vo->win_w, gh > 64 ? gh : 64);
            gtk_widget_set_visible(w->plot_scroll, TRUE);
        }
        /* the newest trace in sight */
        GtkAdjustment *adj = gtk_scrolled_window_get_vadjustment(GTK_SCROLLED_WINDOW(w->plot_scroll));
        gtk_adjustment_set_value(adj, height);
        g_object_unref(tex);
        g_bytes_unref(bytes);
        thx_raster_destroy(&img);
    }
}

thx_status view_plot_export(view_app *a, const char *path)
{
    if (a->n_traces == 0) return thx_error(a->ctx, THX_EINPUT, "no traces to export (pick a node first)");
    const thx_series *x0 = a->d.series[a->traces[0].surface];
    thx_atomic_file af;
    static const char marker[] = "# thorax view traces";
    THX_CHECK(thx_atomic_open_output(a->ctx, path, marker, sizeof marker - 1, NULL, 0, &af));
    fprintf(af.f, "%s\n# time (%s)", marker, x0->time_unit);
    for (int t = 0; t < a->n_traces; t++)
        fprintf(af.f, "\t%s:%zu (%s)", a->d.m->surf[a->traces[t].surface]->name, a->traces[t].node + 1,
                a->d.series[a->traces[t].surface]->unit);
    fprintf(af.f, "\n");
    for (size_t f = 0; f < x0->n_frames; f++) {
        fprintf(af.f, "%.9g", x0->time[f]);
        for (int t = 0; t < a->n_traces; t++) {
            const thx_series *x = a->d.series[a->traces[t].surface];
            if (f < x->n_frames) fprintf(af.f, "\t%.9g", x->v[f * x->n_rows + a->traces[t].node]);
            else fprintf(af.f, "\tnan");
        }
        fprintf(af.f, "\n");
    }
    return thx_atomic_commit(a->ctx, &af);
}

/* The ray under window point (x, y) (logical pixels) through the window's camera. 0, or -1 when
 * the point is outside the 3D viewport. */
static int ray_at(view_win *w, double x, double y, double origin[3], double dir[3])
{
    int scale = gtk_widget_get_scale_factor(w->gl);
    int fb_w = gtk_widget_get_width(w->gl) * scale, fb_h = gtk_widget_get_height(w->gl) * scale;
    int vp[4];
    view_scene_viewport(w, fb_w, fb_h, vp);
    if (vp[2] <= 0 || vp[3] <= 0) return -1;
    double px = x * scale, py = y * scale;
    if (px < vp[0] || py < vp[1] || px > vp[0] + vp[2] || py > vp[1] + vp[3]) return -1;
    thx_camera cam;
    view_camera(w, (double)vp[2] / vp[3], &cam);
    return thx_camera_ray(&cam, vp[2], vp[3], px - vp[0], py - vp[1], origin, dir);
}

static int pick(view_win *w, double x, double y, int quiet);

/* The pick index, built once the first picture is up (so the first click answers as fast as the
 * others) and again after an edit. */
static gboolean build_index(gpointer user)
{
    view_app *a = user;
    const thx_model *m = a->d.m;
    const thx_surface *surf[THX_PICTURE_SURFACES];
    size_t n = m->n_surfaces < THX_PICTURE_SURFACES ? m->n_surfaces : THX_PICTURE_SURFACES;
    for (size_t s = 0; s < n; s++) surf[s] = m->surf[s];
    if (!a->d.pick && thx_pick_index_create(a->ctx, surf, n, &a->d.pick) != THX_OK) view_report(a, "pick index");
    return G_SOURCE_REMOVE;
}

void view_pick_prepare(view_app *a)
{
    if (!a->d.pick) g_idle_add(build_index, a);
}

int view_pick_at(view_win *w, double x, double y)
{
    return pick(w, x, y, 0);
}

/* The same search, reporting nothing (benchmarks). */
void view_pick_quiet(view_win *w, double x, double y)
{
    pick(w, x, y, 1);
}

/* The ray under (x, y) cast into the surfaces shown (hidden ones skipped, the clip plane honoured):
 * the hit in *hit (surface -1: none), the ray's direction in dir. 1 when the point is outside the
 * 3D viewport (nothing cast), else the status. */
static int cast(view_win *w, double x, double y, thx_pick_hit *out, double dir[3])
{
    view_app *a = w->app;
    const thx_model *m = a->d.m;
    double origin[3];
    if (ray_at(w, x, y, origin, dir)) return 1;
    out->surface = -1;
    const thx_surface *surf[THX_PICTURE_SURFACES];
    unsigned char skip[THX_PICTURE_SURFACES];
    size_t n = m->n_surfaces < THX_PICTURE_SURFACES ? m->n_surfaces : THX_PICTURE_SURFACES;
    for (size_t s = 0; s < n; s++) {
        surf[s] = m->surf[s];
        int shown = w->o.n_only == 0;
        for (int k = 0; k < w->o.n_only; k++) shown |= !strcmp(w->o.only[k], m->surf[s]->name);
        for (int k = 0; k < w->o.n_look; k++)
            if (!strcmp(w->o.look[k].name, m->surf[s]->name) && w->o.look[k].mode == THX_DRAW_HIDDEN) shown = 0;
        if (w->o.mode == THX_DRAW_HIDDEN) shown = 0;
        skip[s] = !shown;
    }
    thx_pick_index *idx = NULL;
    thx_pick_hit hit = {.surface = -1};
    thx_pick_opts po;
    thx_pick_opts_default(&po);
    po.skip = skip;
    thx_pick_plane clip;
    thx_clip_plane cp;
    thx_picture_opts o;
    int scale = gtk_widget_get_scale_factor(w->gl);
    view_picture(w, gtk_widget_get_width(w->gl) * scale, gtk_widget_get_height(w->gl) * scale, &o);
    if (o.clip[0] && thx_picture_clip(a->ctx, &o, &a->d, &cp) == 1) {
        memcpy(clip.n, cp.n, sizeof clip.n);
        clip.d = cp.d;
        po.clip = &clip;
        po.n_clip = 1;
    }
    /* a surface the clip plane leaves whole (--no-clip) is not clipped for picking either: picked
       in a second pass without the plane, the nearer hit kept */
    thx_status st = THX_OK;
    if (!a->d.pick) st = thx_pick_index_create(a->ctx, surf, n, &a->d.pick);
    idx = a->d.pick;
    if (st == THX_OK) st = thx_pick_ray(a->ctx, idx, origin, dir, &po, &hit);
    if (st == THX_OK && po.n_clip && w->o.n_whole) {
        unsigned char skip2[THX_PICTURE_SURFACES];
        for (size_t s = 0; s < n; s++) {
            int whole = 0;
            for (int k = 0; k < w->o.n_whole; k++) whole |= !strcmp(w->o.whole[k], m->surf[s]->name);
            skip2[s] = skip[s] || !whole;
        }
        thx_pick_opts p2 = po;
        p2.skip = skip2;
        p2.clip = NULL;
        p2.n_clip = 0;
        thx_pick_hit h2;
        st = thx_pick_ray(a->ctx, idx, origin, dir, &p2, &h2);
        if (st == THX_OK && h2.surface >= 0 && (hit.surface < 0 || h2.t < hit.t)) hit = h2;
    }
    *out = hit;
    return st == THX_OK ? 0 : -1;
}

int view_pick_point(view_win *w, double x, double y, double p[3], double dir[3])
{
    thx_pick_hit hit;
    int rc = cast(w, x, y, &hit, dir);
    if (rc < 0) view_report(w->app, "pick");
    if (rc || hit.surface < 0) return 0;
    memcpy(p, hit.point, sizeof hit.point);
    return 1;
}

/* 1 when something was hit (and, unless quiet, kept among the picks and reported), else 0. */
static int pick(view_win *w, double x, double y, int quiet)
{
    view_app *a = w->app;
    const thx_model *m = a->d.m;
    double dir[3];
    thx_pick_hit hit;
    gint64 t0 = g_get_monotonic_time();
    int rc = cast(w, x, y, &hit, dir);
    if (rc > 0) { view_set_info(a, "pick: outside the picture"); return 0; }
    double ms = (double)(g_get_monotonic_time() - t0) / 1000.0;
    if (rc < 0) { view_report(a, "pick"); return 0; }
    if (quiet) return hit.surface >= 0;
    if (hit.surface < 0) { view_set_info(a, "pick: nothing under the pointer (%.1f ms)", ms); return 0; }
    const thx_surface *s = m->surf[hit.surface];
    const double *p = s->xyz + 3 * hit.node;
    const thx_series *ser = a->d.series[hit.surface];
    char value[64] = "no data";
    int f = view_frame_of(w);
    if (ser) {
        size_t fi = (size_t)f < ser->n_frames ? (size_t)f : ser->n_frames - 1;
        snprintf(value, sizeof value, "%.4g %s", ser->v[fi * ser->n_rows + hit.node], ser->unit);
    }
    a->current = hit.surface;
    if (a->n_picked == 3) {
        memmove(a->picked, a->picked + 1, 2 * sizeof a->picked[0]);
        a->n_picked = 2;
    }
    view_pick *kept = &a->picked[a->n_picked++];
    kept->surface = hit.surface;
    kept->tri = hit.tri;
    kept->node = hit.node;
    memcpy(kept->start, p, sizeof kept->start);
    view_set_info(a, "picked %s (%s) node %zu (%.1f, %.1f, %.1f) mm, %s, triangle %zu (%.1f ms)", s->name, thx_role_name(s->role),
                  hit.node + 1, p[0], p[1], p[2], value, hit.tri + 1, ms);
    if (a->vo->verbose >= 0) printf("pick: surface %s node %zu triangle %zu value %s time %.2f ms\n", s->name, hit.node + 1,
                                    hit.tri + 1, value, ms);
    fflush(stdout);
    if (ser) {
        if (a->n_traces == VIEW_MAX_TRACES) {
            memmove(a->traces, a->traces + 1, (VIEW_MAX_TRACES - 1) * sizeof a->traces[0]);
            a->n_traces--;
        }
        a->traces[a->n_traces].surface = hit.surface;
        a->traces[a->n_traces].node = hit.node;
        a->n_traces++;
        view_plot_update(a);
    }
    return 1;
}
