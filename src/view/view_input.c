/*
 * The viewer's mouse (paper 4.2: rotate, translate, zoom and clip "in real time"): the left
 * button turns the object with an arcball (Shoemake: the drag's two points lifted onto a sphere
 * over the viewport, the rotation between them, so a drag round the rim spins about the line of
 * sight), the middle button or Shift+left pans, the wheel zooms, Ctrl+left drags the clip plane
 * along its normal; a click without a drag picks the node under the pointer.
 */
#include <math.h>
#include <string.h>

#include "view/view_internal.h"

void view_quat_identity(double q[4])
{
    q[0] = 1;
    q[1] = q[2] = q[3] = 0;
}

void view_quat_mul(const double a[4], const double b[4], double out[4])
{
    double r[4] = {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                   a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                   a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                   a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
    double n = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
    for (int k = 0; k < 4; k++) out[k] = n > 0 ? r[k] / n : (k == 0);
}

void view_quat_axis_angle(const double axis[3], double deg, double q[4])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (!(n > 0)) { view_quat_identity(q); return; }
    double h = 0.5 * deg * M_PI / 180, s = sin(h) / n;
    q[0] = cos(h);
    q[1] = axis[0] * s;
    q[2] = axis[1] * s;
    q[3] = axis[2] * s;
}

void view_quat_rotate(const double q[4], const double v[3], double out[3])
{
    /* v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z) */
    const double *u = q + 1, w = q[0];
    double t[3] = {2 * (u[1] * v[2] - u[2] * v[1]), 2 * (u[2] * v[0] - u[0] * v[2]), 2 * (u[0] * v[1] - u[1] * v[0])};
    double c[3] = {u[1] * t[2] - u[2] * t[1], u[2] * t[0] - u[0] * t[2], u[0] * t[1] - u[1] * t[0]};
    for (int k = 0; k < 3; k++) out[k] = v[k] + w * t[k] + c[k];
}

/* The camera's right, up and backward (toward the eye) directions in the model's axes. */
void view_camera_basis(const view_win *w, double right[3], double up[3], double back[3])
{
    thx_camera cam;
    view_camera(w, 1, &cam);
    double b[3], bn = 0, un = 0;
    for (int k = 0; k < 3; k++) { b[k] = cam.eye[k] - cam.center[k]; bn += b[k] * b[k]; }
    bn = sqrt(bn);
    for (int k = 0; k < 3; k++) back[k] = bn > 0 ? b[k] / bn : (k == 1);
    /* up made orthogonal to back */
    double d = cam.up[0] * back[0] + cam.up[1] * back[1] + cam.up[2] * back[2];
    for (int k = 0; k < 3; k++) { up[k] = cam.up[k] - d * back[k]; un += up[k] * up[k]; }
    un = sqrt(un);
    for (int k = 0; k < 3; k++) up[k] = un > 0 ? up[k] / un : (k == 2);
    right[0] = up[1] * back[2] - up[2] * back[1];
    right[1] = up[2] * back[0] - up[0] * back[2];
    right[2] = up[0] * back[1] - up[1] * back[0];
}

/* Turning the object by deg about a screen axis (ax right, ay up, in the screen plane) turns the
 * camera the other way about the same axis in the model's axes. */
void view_rotate_screen(view_win *w, double ax, double ay, double deg)
{
    double r[3], u[3], b[3], axis[3], q[4], out[4];
    view_camera_basis(w, r, u, b);
    for (int k = 0; k < 3; k++) axis[k] = ax * r[k] + ay * u[k];
    view_quat_axis_angle(axis, -deg, q);
    view_quat_mul(q, w->q, out);
    memcpy(w->q, out, sizeof out);
}

void view_copy_transform(view_app *a, const view_win *from)
{
    if (!a->lock_transform) return;
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        if (w == from) continue;
        memcpy(w->q, from->q, sizeof w->q);
        w->zoom = from->zoom;
        memcpy(w->pan, from->pan, sizeof w->pan);
        w->clip_offset = from->clip_offset;
        gtk_gl_area_queue_render(GTK_GL_AREA(w->gl));
    }
}

/* A point of the viewport lifted onto the arcball (unit sphere over the viewport's smaller side;
 * outside it, onto the rim). */
static void arcball_point(const view_win *w, double x, double y, double p[3])
{
    int vp[4];
    int sw = gtk_widget_get_width(w->gl), sh = gtk_widget_get_height(w->gl);
    view_scene_viewport(w, sw, sh, vp);
    double cx = vp[0] + 0.5 * vp[2], cy = vp[1] + 0.5 * vp[3], r = 0.5 * fmin(vp[2], vp[3]);
    if (!(r > 0)) r = 1;
    p[0] = (x - cx) / r;
    p[1] = (cy - y) / r;
    double d = p[0] * p[0] + p[1] * p[1];
    if (d > 1) {
        double s = 1 / sqrt(d);
        p[0] *= s;
        p[1] *= s;
        p[2] = 0;
    } else {
        p[2] = sqrt(1 - d);
    }
}

/* mm per screen pixel in the viewport (orthographic height, or the height at the centre). */
double view_mm_per_pixel(const view_win *w)
{
    thx_camera cam;
    int vp[4];
    int sw = gtk_widget_get_width(w->gl), sh = gtk_widget_get_height(w->gl);
    view_scene_viewport(w, sw, sh, vp);
    view_camera(w, vp[3] > 0 ? (double)vp[2] / vp[3] : 1, &cam);
    double h = cam.height;
    if (cam.fov_deg > 0) {
        double d = 0;
        for (int k = 0; k < 3; k++) d += (cam.eye[k] - cam.center[k]) * (cam.eye[k] - cam.center[k]);
        h = 2 * sqrt(d) * tan(0.5 * cam.fov_deg * M_PI / 180);
    }
    return vp[3] > 0 ? h / vp[3] : 1;
}

static void drag_begin(GtkGestureDrag *g, double x, double y, gpointer user)
{
    view_win *w = user;
    GdkModifierType m = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(g));
    guint button = gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    w->drag_x0 = x;
    w->drag_y0 = y;
    memcpy(w->drag_q, w->q, sizeof w->q);
    memcpy(w->drag_pan, w->pan, sizeof w->pan);
    w->drag_clip = w->clip_offset;
    if (view_panel_drag_begin(w, x, y, m, button)) w->drag_mode = 5; /* the colour bar, a slice (view_panel.c) */
    else if (button == 2 || (m & GDK_SHIFT_MASK)) w->drag_mode = 2;
    else if (m & GDK_CONTROL_MASK) w->drag_mode = 3;
    else if (m & GDK_ALT_MASK) {
        /* moving a node: the one under the pointer */
        w->drag_mode = view_pick_at(w, x, y) ? 4 : 0;
    } else w->drag_mode = 1;
    gtk_widget_grab_focus(w->gl);
}

static void drag_update(GtkGestureDrag *g, double dx, double dy, gpointer user)
{
    view_win *w = user;
    if (w->drag_mode == 1) {
        double p0[3], p1[3];
        arcball_point(w, w->drag_x0, w->drag_y0, p0);
        arcball_point(w, w->drag_x0 + dx, w->drag_y0 + dy, p1);
        double ax[3] = {p0[1] * p1[2] - p0[2] * p1[1], p0[2] * p1[0] - p0[0] * p1[2], p0[0] * p1[1] - p0[1] * p1[0]};
        double dot = p0[0] * p1[0] + p0[1] * p1[1] + p0[2] * p1[2];
        double deg = atan2(sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]), dot) * 180 / M_PI;
        memcpy(w->q, w->drag_q, sizeof w->q);
        if (deg > 0) {
            /* the screen axis (ax[0] right, ax[1] up, ax[2] toward the viewer) in the model's axes */
            double r[3], u[3], b[3], axis[3], q[4], out[4];
            view_camera_basis(w, r, u, b);
            for (int k = 0; k < 3; k++) axis[k] = ax[0] * r[k] + ax[1] * u[k] + ax[2] * b[k];
            view_quat_axis_angle(axis, -deg, q);
            view_quat_mul(q, w->drag_q, out);
            memcpy(w->q, out, sizeof out);
        }
    } else if (w->drag_mode == 2) {
        double s = view_mm_per_pixel(w);
        w->pan[0] = w->drag_pan[0] - dx * s;
        w->pan[1] = w->drag_pan[1] + dy * s;
    } else if (w->drag_mode == 4) {
        view_edit_drag(w, dx, dy, 0);
        return;
    } else if (w->drag_mode == 5) {
        view_panel_drag_update(w, dx, dy);
        return;
    } else if (w->drag_mode == 3) {
        if (!w->o.clip[0] && !w->clip_view) return;
        w->clip_offset = w->drag_clip - dy * view_mm_per_pixel(w);
    }
    gtk_gl_area_queue_render(GTK_GL_AREA(w->gl));
    view_copy_transform(w->app, w);
}

static void drag_end(GtkGestureDrag *g, double dx, double dy, gpointer user)
{
    view_win *w = user;
    int mode = w->drag_mode;
    w->drag_mode = 0;
    if (mode == 4) { view_edit_drag(w, dx, dy, 1); return; }
    if (mode == 5) { view_panel_drag_end(w, dx, dy); return; }
    if (mode == 1 && fabs(dx) < 3 && fabs(dy) < 3) {
        memcpy(w->q, w->drag_q, sizeof w->q);
        /* with the panel's seed tool on, a click seeds a streamline; else it picks the node */
        if (!view_panel_click(w, w->drag_x0, w->drag_y0)) view_pick_at(w, w->drag_x0, w->drag_y0);
    }
    view_update_titles(w->app);
}

static gboolean on_scroll(GtkEventControllerScroll *c, double dx, double dy, gpointer user)
{
    view_win *w = user;
    w->zoom = (w->zoom > 0 ? w->zoom : 1) * pow(1.1, -dy);
    if (w->zoom < 0.05) w->zoom = 0.05;
    if (w->zoom > 200) w->zoom = 200;
    gtk_gl_area_queue_render(GTK_GL_AREA(w->gl));
    view_copy_transform(w->app, w);
    return TRUE;
}

void view_input_attach(view_win *w)
{
    GtkGesture *drag = gtk_gesture_drag_new();
    gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(drag), 0); /* any button; the mode from button and keys */
    g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), w);
    g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), w);
    g_signal_connect(drag, "drag-end", G_CALLBACK(drag_end), w);
    gtk_widget_add_controller(w->gl, GTK_EVENT_CONTROLLER(drag));
    GtkEventController *scroll = gtk_event_controller_scroll_new(GTK_EVENT_CONTROLLER_SCROLL_VERTICAL);
    g_signal_connect(scroll, "scroll", G_CALLBACK(on_scroll), w);
    gtk_widget_add_controller(w->gl, scroll);
    gtk_widget_set_focusable(w->gl, TRUE);
}
