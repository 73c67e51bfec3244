/*
 * The viewer's application (thorax/view/view.h): the data loaded once, the windows (all surfaces
 * in one, one per surface, or the groups the user names), each a GtkGLArea over a plot pane and a
 * status line, titled "thorax — SURFACES — frame K of N (t = ...)".
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/pick.h"
#include "view/view_trace.h"

view_win *view_active(view_app *a)
{
    GtkWindow *gw = gtk_application_get_active_window(a->gapp);
    for (int k = 0; k < a->n_win; k++)
        if (a->win[k]->window == (GtkWidget *)gw) return a->win[k];
    return a->n_win ? a->win[0] : NULL;
}

int view_frame_of(const view_win *w)
{
    return w->app->lock_frame ? w->app->frame : w->frame;
}

void view_redraw_all(view_app *a)
{
    for (int k = 0; k < a->n_win; k++) {
        a->win[k]->pending = 1;
        gtk_gl_area_queue_render(GTK_GL_AREA(a->win[k]->gl));
    }
    view_update_titles(a);
}

void view_set_info(view_app *a, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(a->info, sizeof a->info, fmt, ap);
    va_end(ap);
    if (a->vo->verbose > 0) fprintf(stderr, "thorax view: %s\n", a->info);
    view_update_titles(a);
}

void view_report(view_app *a, const char *what)
{
    fprintf(stderr, "thorax view: %s: %s\n", what, thx_ctx_message(a->ctx));
    snprintf(a->info, sizeof a->info, "%s: %s", what, thx_ctx_message(a->ctx));
    view_update_titles(a);
}

/* The series of the frame label: the body surface's, else the first with data. */
static const thx_series *time_series(const view_app *a)
{
    const thx_series *any = NULL;
    const thx_model *m = a->d.m;
    for (size_t s = 0; s < m->n_surfaces && s < THX_PICTURE_SURFACES; s++)
        if (a->d.series[s] && (!any || m->surf[s]->role == THX_ROLE_OUTER)) any = a->d.series[s];
    return any;
}

void view_update_titles(view_app *a)
{
    const thx_series *ts = time_series(a);
    const thx_model *m = a->d.m;
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        char names[256] = "";
        size_t len = 0;
        for (int j = 0; j < w->o.n_only && len < sizeof names - 70; j++)
            len += (size_t)snprintf(names + len, sizeof names - len, "%s%s", j ? ", " : "", w->o.only[j]);
        if (!w->o.n_only) snprintf(names, sizeof names, "%zu surfaces", m->n_surfaces);
        char title[512], status[1024];
        int f = view_frame_of(w);
        if (ts) {
            size_t fi = (size_t)f < ts->n_frames ? (size_t)f : 0;
            snprintf(title, sizeof title, "thorax — %s — frame %d of %zu (t = %g %s)", names, f + 1, ts->n_frames,
                     ts->time[fi], ts->time_unit);
        } else {
            snprintf(title, sizeof title, "thorax — %s", names);
        }
        gtk_window_set_title(GTK_WINDOW(w->window), title);
        const char *cur = a->current >= 0 && (size_t)a->current < m->n_surfaces ? m->surf[a->current]->name : "-";
        snprintf(status, sizeof status, "frame %d%s   surface: %s   %s%s%s%s   %s", f + 1, a->playing ? " (playing)" : "",
                 cur, a->lock_frame ? "[frame lock] " : "", a->lock_transform ? "[transform lock] " : "",
                 a->lock_scale ? "[scale lock] " : "", a->recording ? "[recording] " : "", a->info);
        gtk_label_set_text(GTK_LABEL(w->status), status);
    }
}

static view_win *new_window(view_app *a, const char *surfaces)
{
    if (a->n_win >= THX_VIEW_MAX_WINDOWS) return NULL;
    view_win *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    w->app = a;
    w->id = a->n_win + 1;
    w->o = a->vo->pic;
    w->zoom = 1;
    view_quat_identity(w->q);
    w->frame = a->frame;
    if (surfaces) {
        /* "heart,torso": this window's surfaces (the picture's --only) */
        w->o.n_only = 0;
        const char *p = surfaces;
        while (*p && w->o.n_only < THX_PICTURE_MAX) {
            const char *c = strchr(p, ',');
            size_t n = c ? (size_t)(c - p) : strlen(p);
            if (n > 63) n = 63;
            memcpy(w->only_buf[w->o.n_only], p, n);
            w->only_buf[w->o.n_only][n] = '\0';
            w->o.only[w->o.n_only] = w->only_buf[w->o.n_only];
            w->o.n_only++;
            p = c ? c + 1 : p + strlen(p);
        }
    }
    a->win[a->n_win++] = w;
    w->window = gtk_application_window_new(a->gapp);
    gtk_application_window_set_show_menubar(GTK_APPLICATION_WINDOW(w->window), TRUE);
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 0);
    w->gl = gtk_gl_area_new();
    gtk_widget_set_size_request(w->gl, a->vo->win_w, a->vo->win_h);
    gtk_widget_set_hexpand(w->gl, TRUE);
    gtk_widget_set_vexpand(w->gl, TRUE);
    w->plot = gtk_picture_new();
    w->plot_scroll = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(w->plot_scroll), GTK_POLICY_NEVER, GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(w->plot_scroll), w->plot);
    gtk_widget_set_visible(w->plot_scroll, FALSE);
    w->status = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(w->status), 0);
    gtk_label_set_ellipsize(GTK_LABEL(w->status), PANGO_ELLIPSIZE_END);
    gtk_widget_set_margin_start(w->status, 6);
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 0); /* the drawing area, the side panel at its right */
    if (a->trace && w->id == 1) { /* tracing: the slice pane on the first window's left */
        GtkWidget *paned = gtk_paned_new(GTK_ORIENTATION_HORIZONTAL);
        gtk_paned_set_start_child(GTK_PANED(paned), view_slice_new(a));
        gtk_paned_set_end_child(GTK_PANED(paned), w->gl);
        gtk_paned_set_resize_start_child(GTK_PANED(paned), TRUE);
        gtk_paned_set_shrink_start_child(GTK_PANED(paned), FALSE);
        gtk_widget_set_vexpand(paned, TRUE);
        gtk_widget_set_hexpand(paned, TRUE);
        gtk_box_append(GTK_BOX(row), paned);
    } else {
        gtk_box_append(GTK_BOX(row), w->gl);
    }
    gtk_box_append(GTK_BOX(box), row);
    gtk_box_append(GTK_BOX(box), w->plot_scroll);
    gtk_box_append(GTK_BOX(box), w->status);
    gtk_window_set_child(GTK_WINDOW(w->window), box);
    if (a->trace) { /* the traced (axial) plane seen from above and in front, not edge on */
        const double x_axis[3] = {1, 0, 0};
        view_quat_axis_angle(x_axis, -55, w->q);
    }
    gtk_window_set_resizable(GTK_WINDOW(w->window), TRUE);
    view_gl_attach(w);
    view_input_attach(w);
    view_plot_attach(w);
    view_panel_attach(w, row);
    return w;
}

static void on_activate(GtkApplication *gapp, gpointer user)
{
    view_app *a = user;
    thx_view_opts *vo = a->vo;
    if (a->n_win) return;
    view_actions_install(a);
    view_trace_install(a);
    gtk_application_set_menubar(gapp, view_menu());
    const thx_model *m = a->d.m;
    if (vo->separate) {
        for (size_t s = 0; s < m->n_surfaces && a->n_win < THX_VIEW_MAX_WINDOWS; s++) {
            int shown = vo->pic.n_only == 0;
            for (int k = 0; k < vo->pic.n_only; k++) shown |= !strcmp(vo->pic.only[k], m->surf[s]->name);
            if (shown) new_window(a, m->surf[s]->name);
        }
    } else if (vo->n_windows) {
        for (int k = 0; k < vo->n_windows; k++) new_window(a, vo->windows[k]);
    } else {
        new_window(a, NULL);
    }
    for (int k = 0; k < a->n_win; k++) gtk_window_present(GTK_WINDOW(a->win[k]->window));
    view_update_titles(a);
    if (vo->play) g_action_group_activate_action(G_ACTION_GROUP(gapp), "play", NULL);
    view_script_start(a);
}

/* Every name a window is given exists in the model. */
static thx_status check_windows(thx_ctx *ctx, const thx_view_opts *o, const thx_model *m)
{
    for (int k = 0; k < o->n_windows; k++) {
        const char *p = o->windows[k];
        while (*p) {
            const char *c = strchr(p, ',');
            size_t n = c ? (size_t)(c - p) : strlen(p);
            int found = 0;
            for (size_t s = 0; s < m->n_surfaces; s++)
                found |= strlen(m->surf[s]->name) == n && !strncmp(m->surf[s]->name, p, n);
            if (!found) return thx_error(ctx, THX_EINPUT, "--window '%s': the model has no surface '%.*s'", o->windows[k], (int)n, p);
            p = c ? c + 1 : p + n;
        }
    }
    return THX_OK;
}

int thx_view_run(thx_ctx *ctx, thx_view_opts *o)
{
    view_app a;
    memset(&a, 0, sizeof a);
    a.ctx = ctx;
    a.vo = o;
    a.frame = o->frame;
    a.rate = o->rate;
    a.loop = o->loop;
    a.step = o->step > 0 ? o->step : 1;
    a.lock_frame = a.lock_transform = 1;
    o->pic.frame = o->frame;
    o->pic.check_frame = 1;
    thx_status st = thx_picture_load(ctx, &o->pic, &a.d);
    if (st == THX_OK) st = check_windows(ctx, o, a.d.m);
    if (st != THX_OK) {
        fprintf(stderr, "thorax view: %s\n", thx_ctx_message(ctx));
        thx_picture_data_free(&a.d);
        return 1;
    }
    if (view_trace_open(&a)) {
        view_trace_close(&a);
        thx_picture_data_free(&a.d);
        return 1;
    }
    a.n_frames = (int)thx_picture_n_frames(&a.d);
    for (size_t s = 0; s < a.d.m->n_surfaces; s++)
        if (a.d.series[s] && (a.current <= 0 || a.d.m->surf[s]->role == THX_ROLE_OUTER)) a.current = (int)s;
    if (!gtk_init_check()) {
        fprintf(stderr, "thorax view: no display: the viewer needs a window system (set DISPLAY, or run it under xvfb-run)\n");
        thx_picture_data_free(&a.d);
        return 1;
    }
    a.gapp = gtk_application_new("org.thorax.view", G_APPLICATION_NON_UNIQUE);
    g_signal_connect(a.gapp, "activate", G_CALLBACK(on_activate), &a);
    char *argv0[] = {"thorax-view", NULL};
    int rc = g_application_run(G_APPLICATION(a.gapp), 1, argv0);
    if (a.play_id) g_source_remove(a.play_id);
    if (a.script_id) g_source_remove(a.script_id);
    g_object_unref(a.gapp);
    view_panel_free(&a);
    for (int k = 0; k < a.n_win; k++) {
        view_win *w = a.win[k];
        thx_font_close(&w->font);
        thx_font_close(&w->plot_font);
        thx_raster_destroy(&w->img);
        free(w->scene);
        g_free(w->shot_path);
        if (a.vo->verbose > 0 && w->ms_n)
            fprintf(stderr, "thorax view: window %d: %d draws, %.1f ms a draw on average\n", w->id, w->ms_n, w->ms_sum / w->ms_n);
        free(w);
    }
    thx_edit_session_destroy(&a.edit);
    view_trace_close(&a);
    thx_camera_path_destroy(&a.flight);
    thx_picture_data_free(&a.d);
    if (rc != 0 && a.status == 0) a.status = 1;
    return a.status;
}
