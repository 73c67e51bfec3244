/*
 * Every thing the viewer does is a GAction of the application ("app.NAME"): the menus' items, the
 * keys (accelerators of the same actions) and a script's `action NAME [VALUE]` lines call the same
 * code. One table below names each action, its parameter, its keys and its line in the keyboard
 * overlay (`?`), so the three cannot drift apart. Actions that concern one window act on the
 * active one (the one with the focus; window 1 in scripts).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "view/view_internal.h"

/* ---- what the actions change ---- */

static void set_frame(view_app *a, view_win *w, int f)
{
    if (a->n_frames <= 0) return;
    if (f < 0) f = a->loop ? a->n_frames - 1 : 0;
    if (f >= a->n_frames) f = a->loop ? 0 : a->n_frames - 1;
    if (a->lock_frame) {
        a->frame = f;
        for (int k = 0; k < a->n_win; k++) a->win[k]->frame = f;
        view_redraw_all(a);
    } else if (w) {
        w->frame = f;
        w->pending = 1;
        gtk_gl_area_queue_render(GTK_GL_AREA(w->gl));
        view_update_titles(a);
    }
    view_plot_update(a);
}

static void step_frames(view_app *a, int by)
{
    view_win *w = view_active(a);
    int f = a->lock_frame || !w ? a->frame : w->frame;
    if (!a->loop && (f + by < 0 || f + by >= a->n_frames)) by = 0;
    set_frame(a, w, f + by);
}

/* The look entry of surface s in a window's picture (made from the window's defaults if none). */
static thx_picture_look *look_of(view_win *w, const char *name)
{
    for (int k = 0; k < w->o.n_look; k++)
        if (!strcmp(w->o.look[k].name, name)) return &w->o.look[k];
    if (w->o.n_look >= THX_PICTURE_MAX) return NULL;
    thx_picture_look *l = &w->o.look[w->o.n_look++];
    memset(l, 0, sizeof *l);
    snprintf(l->name, sizeof l->name, "%s", name);
    l->mode = (thx_draw_mode)w->o.mode;
    l->style = -1;
    l->opacity = -1;
    return l;
}

thx_picture_look *view_look_of(view_win *w, const char *name) { return look_of(w, name); }

static const char *current_name(view_app *a)
{
    const thx_model *m = a->d.m;
    return a->current >= 0 && (size_t)a->current < m->n_surfaces ? m->surf[a->current]->name : NULL;
}

/* the surface modes, then the data styles a surface may take alone (shaded, its data so) */
static const char *mode_names[] = {"hidden", "points", "wire", "flat", "gouraud", "phong", "orientation", "bands", "contours",
                                   "bands+contours", "continuous+contours"};
static const char *style_names[] = {"continuous", "bands", "contours", "bands+contours", "continuous+contours"};
static const char *cmap_names[] = {"ecg", "ecg-green", "coolwarm", "viridis", "gray", "jet"};
static const char *scale_names[] = {"linear", "log", "exp", "lab7", "lab13"};
static const char *mapping_names[] = {"true", "symmetric", "midpoint", "separate"};
static const char *scope_names[] = {"frame", "series", "all", "fixed", "surfaces"};
static const char *view_names[] = {"anterior", "posterior", "left", "right", "superior", "inferior"};

static int name_index(const char *const *names, int n, const char *s)
{
    for (int k = 0; k < n; k++)
        if (!strcmp(names[k], s)) return k;
    return -1;
}

#define N_OF(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* ---- the handlers ---- */

typedef void (*handler)(view_app *a, GSimpleAction *act, GVariant *v);

static void do_quit(view_app *a, GSimpleAction *act, GVariant *v)
{
    g_application_quit(G_APPLICATION(a->gapp));
}
static void do_next(view_app *a, GSimpleAction *act, GVariant *v) { step_frames(a, a->step); }
static void do_prev(view_app *a, GSimpleAction *act, GVariant *v) { step_frames(a, -a->step); }
static void do_first(view_app *a, GSimpleAction *act, GVariant *v) { set_frame(a, view_active(a), 0); }
static void do_last(view_app *a, GSimpleAction *act, GVariant *v) { set_frame(a, view_active(a), a->n_frames - 1); }
static void do_frame(view_app *a, GSimpleAction *act, GVariant *v)
{
    int f = g_variant_get_int32(v);
    if (f < 1 || f > a->n_frames) { view_set_info(a, "frame %d: the data have frames 1 to %d", f, a->n_frames); a->status = 1; return; }
    set_frame(a, view_active(a), f - 1);
}

static gboolean play_tick(gpointer user)
{
    view_app *a = user;
    if (!a->loop && (a->lock_frame ? a->frame : view_active(a)->frame) + a->step >= a->n_frames) {
        a->playing = 0;
        a->play_id = 0;
        GAction *p = g_action_map_lookup_action(G_ACTION_MAP(a->gapp), "play");
        g_simple_action_set_state(G_SIMPLE_ACTION(p), g_variant_new_boolean(FALSE));
        view_update_titles(a);
        return G_SOURCE_REMOVE;
    }
    step_frames(a, a->step);
    return G_SOURCE_CONTINUE;
}

static void restart_play(view_app *a)
{
    if (a->play_id) { g_source_remove(a->play_id); a->play_id = 0; }
    if (a->playing && a->n_frames > 1) a->play_id = g_timeout_add((guint)fmax(1, 1000.0 / a->rate), play_tick, a);
}

static void do_play(view_app *a, GSimpleAction *act, GVariant *v)
{
    a->playing = g_variant_get_boolean(v);
    g_simple_action_set_state(act, v);
    restart_play(a);
    view_update_titles(a);
}
static void do_rate(view_app *a, GSimpleAction *act, GVariant *v)
{
    double r = g_variant_get_double(v);
    if (!(r > 0 && r <= 1000)) { view_set_info(a, "rate %g: give 0 < frames per second <= 1000", r); a->status = 1; return; }
    a->rate = r;
    restart_play(a);
}
static void do_step(view_app *a, GSimpleAction *act, GVariant *v)
{
    int s = g_variant_get_int32(v);
    if (s < 1) { view_set_info(a, "step %d: at least 1", s); a->status = 1; return; }
    a->step = s;
}
static void do_toggle(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    int on = g_variant_get_boolean(v);
    g_simple_action_set_state(act, v);
    if (!strcmp(name, "loop")) a->loop = on;
    else if (!strcmp(name, "lock-frame")) {
        a->lock_frame = on;
        if (on) set_frame(a, NULL, view_active(a) ? view_active(a)->frame : a->frame);
    } else if (!strcmp(name, "lock-transform")) {
        a->lock_transform = on;
        if (on) view_copy_transform(a, view_active(a));
    } else if (!strcmp(name, "lock-scale")) {
        /* one scale over all surfaces and windows: the frame scope widens to every surface's frame,
           the series scope to every surface's series */
        a->lock_scale = on;
        for (int k = 0; k < a->n_win; k++) {
            thx_picture_opts *o = &a->win[k]->o;
            if (on && o->scope == THX_SCOPE_FRAME) o->scope = THX_SCOPE_SURFACES;
            else if (on && o->scope == THX_SCOPE_SERIES) o->scope = THX_SCOPE_ALL;
            else if (!on && o->scope == THX_SCOPE_SURFACES) o->scope = THX_SCOPE_FRAME;
            else if (!on && o->scope == THX_SCOPE_ALL) o->scope = THX_SCOPE_SERIES;
        }
    } else if (!strcmp(name, "colorbar") || !strcmp(name, "label") || !strcmp(name, "invert") || !strcmp(name, "extrema")) {
        for (int k = 0; k < a->n_win; k++) {
            thx_picture_opts *o = &a->win[k]->o;
            int *f = !strcmp(name, "colorbar") ? &o->colorbar : !strcmp(name, "label") ? &o->label
                   : !strcmp(name, "extrema") ? &o->extrema : &o->invert;
            *f = on;
        }
    }
    view_redraw_all(a);
}

static void do_surface_step(view_app *a, int by)
{
    int n = (int)a->d.m->n_surfaces;
    if (n <= 0) return;
    a->current = ((a->current + by) % n + n) % n;
    view_set_info(a, "surface %s", current_name(a));
}
static void do_surface_next(view_app *a, GSimpleAction *act, GVariant *v) { do_surface_step(a, 1); }
static void do_surface_prev(view_app *a, GSimpleAction *act, GVariant *v) { do_surface_step(a, -1); }
static void do_surface(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    for (size_t k = 0; k < a->d.m->n_surfaces; k++)
        if (!strcmp(a->d.m->surf[k]->name, s)) { a->current = (int)k; view_set_info(a, "surface %s", s); return; }
    view_set_info(a, "surface '%s': not in the model", s);
    a->status = 1;
}

/* A string choice on every window's picture (style, colour map, scale, scope) or on the current
 * surface's look (mode); "next" cycles. */
static void do_choice(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    const char *s = g_variant_get_string(v, NULL);
    const char *const *names;
    int n;
    if (!strcmp(name, "mode")) { names = mode_names; n = N_OF(mode_names); }
    else if (!strcmp(name, "style")) { names = style_names; n = N_OF(style_names); }
    else if (!strcmp(name, "colormap")) { names = cmap_names; n = N_OF(cmap_names); }
    else if (!strcmp(name, "scale")) { names = scale_names; n = N_OF(scale_names); }
    else if (!strcmp(name, "mapping")) { names = mapping_names; n = N_OF(mapping_names); }
    else { names = scope_names; n = N_OF(scope_names); }
    int k = name_index(names, n, s);
    if (!strcmp(s, "next")) {
        GVariant *cur = g_action_get_state(G_ACTION(act));
        k = (name_index(names, n, g_variant_get_string(cur, NULL)) + 1) % n;
        if (!strcmp(name, "scope") && k == THX_SCOPE_FIXED) k++; /* fixed needs limits: only by --scope fixed:LO:HI */
        g_variant_unref(cur);
    }
    if (k < 0) {
        GString *list = g_string_new("");
        for (int j = 0; j < n; j++) g_string_append_printf(list, "%s%s", j ? ", " : "", names[j]);
        view_set_info(a, "%s '%s': one of %s, or next", name, s, list->str);
        g_string_free(list, TRUE);
        a->status = 1;
        return;
    }
    if (!strcmp(name, "scope") && k == THX_SCOPE_FIXED) {
        view_set_info(a, "scope fixed: give it with its limits on the command line (--scope fixed:LO:HI)");
        a->status = 1;
        return;
    }
    g_simple_action_set_state(act, g_variant_new_string(names[k]));
    for (int j = 0; j < a->n_win; j++) {
        view_win *w = a->win[j];
        if (!strcmp(name, "mode")) {
            const char *cur = current_name(a);
            thx_picture_look *l = cur ? look_of(w, cur) : NULL;
            if (l && k <= THX_DRAW_ORIENTATION) { l->mode = (thx_draw_mode)k; l->style = -1; }
            else if (l) { l->mode = THX_DRAW_GOURAUD; l->style = k - THX_DRAW_ORIENTATION; }
        } else if (!strcmp(name, "style")) w->o.style = k;
        else if (!strcmp(name, "colormap")) w->o.cmap = k;
        else if (!strcmp(name, "scale")) w->o.model = k;
        else if (!strcmp(name, "mapping")) w->o.mapping = k;
        else w->o.scope = k;
    }
    if (!strcmp(name, "mode")) view_set_info(a, "%s: %s", current_name(a), names[k]);
    else view_set_info(a, "%s: %s", name, names[k]);
    view_redraw_all(a);
}

static void do_visible(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *cur = current_name(a);
    for (int j = 0; j < a->n_win && cur; j++) {
        thx_picture_look *l = look_of(a->win[j], cur);
        if (l) l->mode = l->mode == THX_DRAW_HIDDEN ? (thx_draw_mode)a->win[j]->o.mode : THX_DRAW_HIDDEN;
    }
    view_redraw_all(a);
}

static void do_opacity(view_app *a, GSimpleAction *act, GVariant *v)
{
    double x = g_variant_get_double(v);
    const char *cur = current_name(a);
    if (!(x >= 0 && x <= 1)) { view_set_info(a, "opacity %g: give 0 to 1", x); a->status = 1; return; }
    for (int j = 0; j < a->n_win && cur; j++) {
        thx_picture_look *l = look_of(a->win[j], cur);
        if (l) l->opacity = (float)x;
    }
    view_redraw_all(a);
}

static void do_color(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL), *h = s[0] == '#' ? s + 1 : s;
    unsigned rgb;
    int used = 0;
    if (strlen(h) != 6 || sscanf(h, "%6x%n", &rgb, &used) != 1 || used != 6) {
        view_set_info(a, "color '%s': give #RRGGBB", s);
        a->status = 1;
        return;
    }
    const char *cur = current_name(a);
    for (int j = 0; j < a->n_win && cur; j++) {
        thx_picture_look *l = look_of(a->win[j], cur);
        if (!l) continue;
        l->color[0] = (float)((rgb >> 16) & 255) / 255.0f;
        l->color[1] = (float)((rgb >> 8) & 255) / 255.0f;
        l->color[2] = (float)(rgb & 255) / 255.0f;
        l->have_color = 1;
    }
    view_redraw_all(a);
}

static void do_levels(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    for (int j = 0; j < a->n_win; j++) {
        thx_picture_opts *o = &a->win[j]->o;
        int n = !strcmp(name, "levels") ? g_variant_get_int32(v) : o->levels + (!strcmp(name, "levels-more") ? 1 : -1);
        if (n < 2 || n > 64) { view_set_info(a, "levels %d: 2 to 64", n); if (!strcmp(name, "levels")) a->status = 1; return; }
        o->levels = n;
    }
    view_set_info(a, "%d levels", a->win[0]->o.levels);
    view_redraw_all(a);
}

/* The window's camera back to the standard view v (or its own when v < 0). */
static void reset_view(view_app *a, view_win *w, int v)
{
    if (v >= 0) {
        w->o.view = v;
        w->o.have_camera = 0;
    }
    view_quat_identity(w->q);
    w->zoom = 1;
    w->pan[0] = w->pan[1] = 0;
    w->clip_offset = 0;
    view_copy_transform(a, w);
    if (a->lock_transform)
        for (int k = 0; k < a->n_win; k++)
            if (v >= 0) { a->win[k]->o.view = v; a->win[k]->o.have_camera = 0; }
    view_redraw_all(a);
}

static void do_view(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    int k = name_index(view_names, N_OF(view_names), s);
    if (k < 0) { view_set_info(a, "view '%s': anterior, posterior, left, right, superior or inferior", s); a->status = 1; return; }
    view_win *w = view_active(a);
    if (w) reset_view(a, w, k);
    view_set_info(a, "%s view", s);
}
static void do_reset(view_app *a, GSimpleAction *act, GVariant *v)
{
    view_win *w = view_active(a);
    if (w) reset_view(a, w, -1);
}

/* "right:15", "up:-15", "spin:10": the object turned by that many degrees about the screen's
 * vertical axis (right), horizontal axis (up) or the line of sight (spin). */
static void do_rotate(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    char dir[16];
    double deg;
    view_win *w = view_active(a);
    if (!w || sscanf(s, "%15[a-z]:%lf", dir, &deg) != 2 || (strcmp(dir, "right") && strcmp(dir, "up") && strcmp(dir, "spin"))) {
        view_set_info(a, "rotate '%s': right:DEG, up:DEG or spin:DEG", s);
        a->status = 1;
        return;
    }
    if (!strcmp(dir, "right")) view_rotate_screen(w, 0, 1, deg);
    else if (!strcmp(dir, "up")) view_rotate_screen(w, -1, 0, deg);
    else {
        /* about the line of sight: the camera's up turned */
        thx_camera cam;
        view_camera(w, 1, &cam);
        double axis[3] = {cam.eye[0] - cam.center[0], cam.eye[1] - cam.center[1], cam.eye[2] - cam.center[2]};
        double q[4], out[4];
        view_quat_axis_angle(axis, -deg, q);
        view_quat_mul(q, w->q, out);
        memcpy(w->q, out, sizeof out);
    }
    view_copy_transform(a, w);
    view_redraw_all(a);
}

static void do_zoom(view_app *a, GSimpleAction *act, GVariant *v)
{
    double f = g_variant_get_double(v);
    view_win *w = view_active(a);
    if (!(f > 0) || !w) { view_set_info(a, "zoom %g: a factor > 0", f); a->status = 1; return; }
    w->zoom = fmin(fmax((w->zoom > 0 ? w->zoom : 1) * f, 0.05), 200);
    view_copy_transform(a, w);
    view_redraw_all(a);
}

static void do_clip(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        char old[64];
        memcpy(old, w->o.clip, sizeof old);
        snprintf(w->o.clip, sizeof w->o.clip, "%s", strcmp(s, "none") ? s : "");
        thx_clip_plane p;
        if (w->o.clip[0] && thx_picture_clip(a->ctx, &w->o, &a->d, &p) < 0) {
            memcpy(w->o.clip, old, sizeof old);
            view_report(a, "clip");
            a->status = 1;
            return;
        }
        w->clip_offset = 0;
        w->clip_view = 0;
    }
    view_set_info(a, "clip: %s", s);
    view_redraw_all(a);
}

/* A plane facing the viewer through the model's centre, cutting away the near part (front) or the
 * far part (back); it turns with the camera until clip-lock fixes it to the object. */
static void do_clip_view(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    for (int k = 0; k < a->n_win; k++) {
        a->win[k]->clip_view = !strcmp(name, "clip-front") ? 1 : 2;
        a->win[k]->clip_offset = 0;
    }
    view_set_info(a, "%s clip plane, facing the viewer (clip-lock fixes it to the object)", !strcmp(name, "clip-front") ? "front" : "back");
    view_redraw_all(a);
}

static void do_clip_lock(view_app *a, GSimpleAction *act, GVariant *v)
{
    int locked = 0;
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        if (!w->clip_view && !(w->o.clip[0] && w->clip_offset != 0)) continue;
        thx_picture_opts o;
        int scale = gtk_widget_get_scale_factor(w->gl);
        view_picture(w, gtk_widget_get_width(w->gl) * scale, gtk_widget_get_height(w->gl) * scale, &o);
        memcpy(w->o.clip, o.clip, sizeof w->o.clip);
        w->clip_view = 0;
        w->clip_offset = 0;
        locked++;
    }
    view_set_info(a, locked ? "clip plane fixed to the object: %s" : "clip-lock: no plane facing the viewer%s", locked ? a->win[0]->o.clip : "");
    view_redraw_all(a);
}

static void do_data_next(view_app *a, GSimpleAction *act, GVariant *v)
{
    int s = a->current;
    if (s < 0 || s >= THX_PICTURE_SURFACES || a->d.n_sets[s] < 1) { view_set_info(a, "data-next: the surface has no data"); a->status = 1; return; }
    int k = (a->d.active[s] + 1) % a->d.n_sets[s];
    thx_picture_set_active(&a->d, s, k);
    view_set_info(a, "%s: data set %d of %d (%s)", a->d.m->surf[s]->name, k + 1, a->d.n_sets[s], a->d.series[s]->label);
    view_redraw_all(a);
    view_plot_update(a);
}

/* Scale groups and slaves (the picture's --scale-group and --slave): "A,B,..." / "NAME=MASTER",
 * "all" (every surface with data in one group; scale-group only), or "none" (clears them). */
static void do_scale_rel(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act)), *spec = g_variant_get_string(v, NULL);
    int group = !strcmp(name, "scale-group");
    char buf[256];
    snprintf(buf, sizeof buf, "%s", spec);
    if (group && !strcmp(spec, "all")) {
        size_t len = 0;
        buf[0] = '\0';
        for (size_t s = 0; s < a->d.m->n_surfaces && s < THX_PICTURE_SURFACES && len < sizeof buf - 70; s++)
            if (a->d.series[s]) len += (size_t)snprintf(buf + len, sizeof buf - len, "%s%s", len ? "," : "", a->d.m->surf[s]->name);
    }
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        thx_picture_opts o = w->o;
        if (!strcmp(spec, "none")) {
            if (group) o.n_groups = 0;
            else o.n_slaves = 0;
        } else if ((group ? o.n_groups : o.n_slaves) >= THX_PICTURE_MAX) {
            view_set_info(a, "%s: at most %d", name, THX_PICTURE_MAX);
            a->status = 1;
            return;
        } else if (group) {
            snprintf(w->group_buf[o.n_groups], sizeof w->group_buf[0], "%s", buf);
            o.groups[o.n_groups] = w->group_buf[o.n_groups];
            o.n_groups++;
        } else {
            snprintf(w->slave_buf[o.n_slaves], sizeof w->slave_buf[0], "%s", buf);
            o.slaves[o.n_slaves] = w->slave_buf[o.n_slaves];
            o.n_slaves++;
        }
        /* the names checked as the command line's are */
        for (int j = 0; j < o.n_groups + o.n_slaves; j++) {
            const char *sp = j < o.n_groups ? o.groups[j] : o.slaves[j - o.n_groups];
            if (j >= o.n_groups && (!strchr(sp, '=') || strchr(sp, '=') == sp)) {
                view_set_info(a, "slave '%s': give NAME=MASTER", sp);
                a->status = 1;
                return;
            }
            for (const char *p = sp; *p;) {
                size_t n = strcspn(p, ",=");
                int found = 0;
                for (size_t s = 0; s < a->d.m->n_surfaces; s++)
                    found |= strlen(a->d.m->surf[s]->name) == n && !strncmp(a->d.m->surf[s]->name, p, n);
                if (!found) { view_set_info(a, "%s '%s': no surface '%.*s'", name, sp, (int)n, p); a->status = 1; return; }
                p += n + (p[n] != '\0');
            }
        }
        w->o = o;
    }
    view_set_info(a, "%s %s", name, spec);
    view_redraw_all(a);
}

/* The current surface's activation (recovery) map: "T0:T1" a new map of that window; "" (the key)
 * the record's fiducials or the chosen beat (thx_picture_add_map), and the key again shows the
 * potentials back (map3d's toggle), a third time the same map without computing it again. */
static void do_map(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *spec = g_variant_get_string(v, NULL);
    int kind = !strcmp(g_action_get_name(G_ACTION(act)), "recovery") ? 2 : 1;
    const char *what = kind == 2 ? "recovery" : "activation";
    double t0 = NAN, t1 = NAN;
    if (spec[0] && (sscanf(spec, "%lf:%lf", &t0, &t1) != 2 || !(t0 < t1))) {
        view_set_info(a, "%s '%s': give T0:T1 (the data's time unit), or nothing for the record's own window", what, spec);
        a->status = 1;
        return;
    }
    int s = a->current;
    thx_picture_data *d = &a->d;
    if (s < 0 || s >= THX_PICTURE_SURFACES || !d->series[s]) {
        view_set_info(a, "%s: the surface has no data", what);
        a->status = 1;
        return;
    }
    if (!spec[0] && d->map[s][d->active[s]] == kind) { /* the key again: back to the potentials */
        int src = d->map_src[s][d->active[s]];
        thx_picture_set_active(d, s, src);
        view_set_info(a, "%s: the potentials again (%s shows the map)", d->m->surf[s]->name, kind == 2 ? "Shift+A" : "a");
        view_redraw_all(a);
        return;
    }
    int src = d->map[s][d->active[s]] ? d->map_src[s][d->active[s]] : d->active[s], found = -1;
    for (int k = 0; k < d->n_sets[s] && !spec[0]; k++)
        if (d->map[s][k] == kind && d->map_auto[s][k] && d->map_src[s][k] == src) found = k;
    if (found >= 0) {
        thx_picture_set_active(d, s, found);
    } else {
        /* a window given replaces the map of a window given before (the panel, a drag on the traces:
           one after another would fill the surface's data sets), else the potentials are mapped */
        int k = d->active[s];
        if (spec[0] && d->map[s][k] == kind && !d->map_auto[s][k]) thx_picture_drop_set(d, s, k);
        else if (d->map[s][d->active[s]]) thx_picture_set_active(d, s, src);
        if (thx_picture_add_map(a->ctx, d, s, kind, t0, t1) != THX_OK) { view_report(a, what); a->status = 1; return; }
    }
    snprintf(kind == 1 ? a->act_spec[s] : a->rec_spec[s], sizeof a->act_spec[s], "%s", spec);
    const thx_series *m = d->series[s];
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < m->n_rows; i++)
        if (isfinite(m->v[i])) { lo = fmin(lo, m->v[i]); hi = fmax(hi, m->v[i]); }
    view_set_info(a, "%s: %s times %.4g to %.4g %s: %s (data set %d; %s again: the potentials)", d->m->surf[s]->name, what, lo, hi,
                  m->unit, m->label, d->active[s] + 1, kind == 2 ? "Shift+A" : "a");
    if (a->vo->verbose >= 0) printf("%s: %s %.6g %.6g %s | %s\n", what, d->m->surf[s]->name, lo, hi, m->unit, m->label);
    fflush(stdout);
    /* the picture says which window the map took: its label line, turned on with the map */
    view_win *aw = view_active(a);
    if (aw && !aw->o.label) g_action_group_change_action_state(G_ACTION_GROUP(a->gapp), "label", g_variant_new_boolean(TRUE));
    view_redraw_all(a);
}

/* Node labels on the current surface: index, channel, value, or none. */
static void do_node_labels(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *kind = g_variant_get_string(v, NULL), *cur = current_name(a);
    if (!cur || (strcmp(kind, "index") && strcmp(kind, "channel") && strcmp(kind, "value") && strcmp(kind, "none"))) {
        view_set_info(a, "node-labels '%s': index, channel, value or none", kind);
        a->status = 1;
        return;
    }
    if (!strcmp(kind, "channel") && !a->d.channel[a->current]) { view_set_info(a, "node-labels channel: %s has no channels (--channels)", cur); a->status = 1; return; }
    if (!strcmp(kind, "value") && !a->d.series[a->current]) { view_set_info(a, "node-labels value: %s has no data", cur); a->status = 1; return; }
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        int j = 0;
        for (int i = 0; i < w->o.n_labels; i++) /* drop this surface's entry */
            if (strncmp(w->o.labels[i], cur, strlen(cur)) || w->o.labels[i][strlen(cur)] != '=') w->o.labels[j++] = w->o.labels[i];
        w->o.n_labels = j;
        if (strcmp(kind, "none") && w->o.n_labels < THX_PICTURE_MAX) {
            snprintf(w->label_buf[w->o.n_labels], sizeof w->label_buf[0], "%s=%s", cur, kind);
            /* the entries kept may point into label_buf: rebuild them all from copies */
            char tmp[THX_PICTURE_MAX][80];
            for (int i = 0; i <= w->o.n_labels; i++) snprintf(tmp[i], sizeof tmp[i], "%s", i < w->o.n_labels ? w->o.labels[i] : w->label_buf[w->o.n_labels]);
            w->o.n_labels++;
            for (int i = 0; i < w->o.n_labels; i++) {
                memcpy(w->label_buf[i], tmp[i], sizeof tmp[i]);
                w->o.labels[i] = w->label_buf[i];
            }
        }
    }
    view_set_info(a, "%s: node labels %s", cur, kind);
    view_redraw_all(a);
}

static void do_clip_move(view_app *a, GSimpleAction *act, GVariant *v)
{
    double mm = g_variant_get_double(v);
    view_win *w = view_active(a);
    if (!w || (!w->o.clip[0] && !w->clip_view)) { view_set_info(a, "clip-move: no clip plane (action clip SIDE[:F], clip-front or clip-back)"); a->status = 1; return; }
    w->clip_offset += mm;
    view_copy_transform(a, w);
    view_redraw_all(a);
}

/* The scan under the model (--image): its planes moved plane by plane, its window and level. */
static void do_image(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    if (!a->d.scan) { view_set_info(a, "%s: no image (--image IMG)", name); a->status = 1; return; }
    if (!strcmp(name, "image-plane") && a->trace) { /* tracing: the traced plane moves, the 3D view's with it */
        char line[32];
        snprintf(line, sizeof line, "plane %+d", g_variant_get_int32(v));
        view_trace_line(a, line);
        return;
    }
    if (!strcmp(name, "image-plane")) {
        int n = g_variant_get_int32(v), moved = 0;
        for (int k = 0; k < a->d.n_scan_planes; k++) moved |= thx_picture_scan_move(&a->d, k, n);
        if (!moved) { char t[160]; thx_picture_scan_describe(&a->d, t, sizeof t); view_set_info(a, "%s (the image's end)", t); return; }
    } else if (!strcmp(name, "image-window")) {
        double f = g_variant_get_double(v);
        if (!(f > 0)) { view_set_info(a, "image-window %g: a factor > 0", f); a->status = 1; return; }
        a->d.window *= f;
    } else { /* image-level: by a fraction of the window */
        a->d.level += g_variant_get_double(v) * a->d.window;
    }
    char t[160];
    thx_picture_scan_describe(&a->d, t, sizeof t);
    view_set_info(a, "%s", t);
    view_redraw_all(a);
}

static void do_screenshot(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    view_win *w = view_active(a);
    if (!w) return;
    char auto_name[64];
    if (!s[0]) {
        /* from the menu: the next free thorax-view-NNNN.png here */
        do snprintf(auto_name, sizeof auto_name, "thorax-view-%04d.png", ++a->shots);
        while (g_file_test(auto_name, G_FILE_TEST_EXISTS) && a->shots < 9999);
        s = auto_name;
    }
    g_free(w->shot_path);
    w->shot_path = g_strdup(s);
    w->pending = 1;
    gtk_gl_area_queue_render(GTK_GL_AREA(w->gl));
}

static void do_record(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    if (!s[0]) s = "thorax-view-frames";
    if (g_mkdir_with_parents(s, 0777) != 0) { view_set_info(a, "record: cannot create %s", s); a->status = 1; return; }
    snprintf(a->rec_dir, sizeof a->rec_dir, "%s", s);
    a->recording = 1;
    a->rec_count = 0;
    view_set_info(a, "recording every frame drawn into %s/", s);
    view_redraw_all(a);
}

/* Stops recording; with a path, assembles the frames recorded into an MP4 (as thorax animate). */
static void do_record_stop(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    if (!a->recording) { view_set_info(a, "record-stop: not recording"); a->status = 1; return; }
    a->recording = 0;
    if (s[0] && view_movie(a, s) != THX_OK) { view_report(a, "movie"); a->status = 1; return; }
    view_set_info(a, "recorded %d frames into %s/%s%s", a->rec_count, a->rec_dir, s[0] ? ", movie " : "", s);
}

static void do_record_all(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    if (a->n_frames <= 0) { view_set_info(a, "record-all: no data with frames"); a->status = 1; return; }
    view_record_all(a, s[0] ? s : "thorax-view-frames");
}

static void do_fly(view_app *a, GSimpleAction *act, GVariant *v)
{
    view_fly(a, g_variant_get_string(v, NULL));
}

static void do_save_session(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    if (!s[0]) s = "thorax-view-session.txt";
    if (view_save_session(a, s) != THX_OK) { view_report(a, "save session"); a->status = 1; return; }
    view_set_info(a, "session saved to %s", s);
}

static void do_pick(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    double x, y;
    view_win *w = view_active(a);
    if (!w || sscanf(s, "%lf,%lf", &x, &y) != 2) { view_set_info(a, "pick '%s': give X,Y (window pixels)", s); a->status = 1; return; }
    view_pick_at(w, x, y);
}

static void do_plot_zoom(view_app *a, GSimpleAction *act, GVariant *v)
{
    double f = g_variant_get_double(v);
    if (!(f > 0)) { view_set_info(a, "plot-zoom %g: a factor > 0 (1 shows every frame again)", f); a->status = 1; return; }
    a->plot_zoom = f == 1 ? 1 : fmin(fmax((a->plot_zoom > 1 ? a->plot_zoom : 1) * f, 1), 1000);
    view_plot_update(a);
}

static void do_traces_clear(view_app *a, GSimpleAction *act, GVariant *v)
{
    a->n_traces = 0;
    view_plot_update(a);
}

static void do_traces_export(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *s = g_variant_get_string(v, NULL);
    if (!s[0]) s = "thorax-view-traces.txt";
    if (view_plot_export(a, s) != THX_OK) { view_report(a, "export traces"); a->status = 1; return; }
    view_set_info(a, "traces written to %s", s);
}

static void do_shortcuts(view_app *a, GSimpleAction *act, GVariant *v);

/* ---- editing (view_edit.c) ---- */
static void do_edit(view_app *a, GSimpleAction *act, GVariant *v) { view_edit_line(a, g_variant_get_string(v, NULL)); }
/* while tracing (and no model edit under way) undo and redo are the tracing's */
static void do_undo(view_app *a, GSimpleAction *act, GVariant *v)
{
    if (a->trace && !a->edit) view_trace_line(a, "undo");
    else view_edit_undo(a, 0);
}
static void do_redo(view_app *a, GSimpleAction *act, GVariant *v)
{
    if (a->trace && !a->edit) view_trace_line(a, "redo");
    else view_edit_undo(a, 1);
}
static void do_save_model(view_app *a, GSimpleAction *act, GVariant *v) { view_edit_save(a, g_variant_get_string(v, NULL)); }
static void do_edit_picked(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    double x = v ? g_variant_get_double(v) : 0;
    view_edit_picked(a, !strcmp(name, "delete-triangle") ? "delete" : !strcmp(name, "flip-triangle") ? "flip"
                      : !strcmp(name, "build-triangle") ? "triangle" : name, x);
}

/* bench-rotate N, bench-frames N, bench-pick N (bench/view.sh) */
static void do_bench(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    int n = g_variant_get_int32(v);
    if (n < 1 || n > 100000) { view_set_info(a, "%s %d: 1 to 100000 steps", name, n); a->status = 1; return; }
    view_bench(a, !strcmp(name, "bench-rotate") ? 1 : !strcmp(name, "bench-frames") ? 2 : 3, n);
}

/* ---- the table ---- */

typedef struct {
    const char *name;
    const char *param;  /* NULL none, "i", "d", "s" */
    const char *state;  /* NULL stateless; "b" boolean; "s" string (radio) */
    handler fn;
    const char *keys[3]; /* accelerators (GTK syntax) */
    const char *target;  /* the key's parameter, as a GVariant text ("'next'", "'right:15'") */
    const char *help;    /* the overlay's line */
} action_def;

static const action_def ACTIONS[] = {
    {"frame-next", NULL, NULL, do_next, {"Right"}, NULL, "next frame (the frame step)"},
    {"frame-prev", NULL, NULL, do_prev, {"Left"}, NULL, "previous frame"},
    {"frame-first", NULL, NULL, do_first, {"Home"}, NULL, "first frame"},
    {"frame-last", NULL, NULL, do_last, {"End"}, NULL, "last frame"},
    {"frame", "i", NULL, do_frame, {NULL}, NULL, "go to frame K (1-based)"},
    {"play", NULL, "b", do_play, {"space"}, NULL, "play / pause"},
    {"rate", "d", NULL, do_rate, {NULL}, NULL, "frames per second when playing"},
    {"step", "i", NULL, do_step, {NULL}, NULL, "frames per step"},
    {"loop", NULL, "b", do_toggle, {"<Shift>l"}, NULL, "playing and stepping wrap around"},
    {"lock-frame", NULL, "b", do_toggle, {"<Shift>f"}, NULL, "frame lock: every window steps together"},
    {"lock-transform", NULL, "b", do_toggle, {"<Shift>t"}, NULL, "transform lock: every window turns together"},
    {"lock-scale", NULL, "b", do_toggle, {"<Shift>k"}, NULL, "scale lock: one colour scale over every surface"},
    {"surface-next", NULL, NULL, do_surface_next, {"Down"}, NULL, "the next surface (the one commands act on)"},
    {"surface-prev", NULL, NULL, do_surface_prev, {"Up"}, NULL, "the previous surface"},
    {"surface", "s", NULL, do_surface, {NULL}, NULL, "the surface commands act on, by name"},
    {"mode", "s", "s", do_choice, {"m"}, "'next'", "the surface's mode: points, wire, flat, gouraud, phong, orientation, hidden"},
    {"visible", NULL, NULL, do_visible, {"v"}, NULL, "show / hide the surface"},
    {"opacity", "d", NULL, do_opacity, {NULL}, NULL, "the surface's opacity, 0 to 1"},
    {"color", "s", NULL, do_color, {NULL}, NULL, "the surface's colour, #RRGGBB"},
    {"style", "s", "s", do_choice, {"b"}, "'next'", "data style: continuous, bands, contours, ..."},
    {"colormap", "s", "s", do_choice, {"c"}, "'next'", "colour map: ecg, ecg-green, coolwarm, viridis, gray, jet"},
    {"invert", NULL, "b", do_toggle, {"i"}, NULL, "colour map reversed"},
    {"scale", "s", "s", do_choice, {"s"}, "'next'", "scaling model: linear, log, exp, lab7, lab13"},
    {"scope", "s", "s", do_choice, {"o"}, "'next'", "scale scope: frame, series, surfaces, all"},
    {"mapping", "s", "s", do_choice, {"p"}, "'next'", "scale mapping: true, symmetric, midpoint, separate"},
    {"levels", "i", NULL, do_levels, {NULL}, NULL, "number of shades / contours"},
    {"levels-more", NULL, NULL, do_levels, {"plus", "equal", "KP_Add"}, NULL, "more shades / contours"},
    {"levels-fewer", NULL, NULL, do_levels, {"minus", "KP_Subtract"}, NULL, "fewer shades / contours"},
    {"data-next", NULL, NULL, do_data_next, {"d"}, NULL, "the surface's next data set"},
    {"scale-group", "s", NULL, do_scale_rel, {"g"}, "'all'", "surfaces sharing one scale: A,B,..., all (key g), or none"},
    {"slave", "s", NULL, do_scale_rel, {NULL}, NULL, "a surface drawn with another's scale: NAME=MASTER, or none"},
    {"activation", "s", NULL, do_map, {"a"}, "''", "activation map (the record's fiducials, else one beat's QRS; or T0:T1); again: the potentials"},
    {"recovery", "s", NULL, do_map, {"<Shift>a"}, "''", "recovery map (the record's fiducials, else the beat's T wave; or T0:T1); again: the potentials"},
    {"extrema", NULL, "b", do_toggle, {"x"}, NULL, "marks at the largest and smallest values"},
    {"node-labels", "s", NULL, do_node_labels, {"n"}, "'index'", "label the surface's nodes: index, channel, value or none"},
    {"colorbar", NULL, "b", do_toggle, {"<Shift>b"}, NULL, "colour bar"},
    {"label", NULL, "b", do_toggle, {"<Shift>n"}, NULL, "time label"},
    {"view", "s", NULL, do_view, {"1"}, "'anterior'", "anterior view"},
    {"view-posterior", NULL, NULL, NULL, {"2"}, NULL, "posterior view"},
    {"view-left", NULL, NULL, NULL, {"3"}, NULL, "left view"},
    {"view-right", NULL, NULL, NULL, {"4"}, NULL, "right view"},
    {"view-superior", NULL, NULL, NULL, {"5"}, NULL, "superior view"},
    {"view-inferior", NULL, NULL, NULL, {"6"}, NULL, "inferior view"},
    {"reset", NULL, NULL, do_reset, {"r"}, NULL, "back to the view (rotation, zoom, pan, clip offset)"},
    {"rotate", "s", NULL, do_rotate, {"<Control>Right"}, "'right:15'", "turn 15 degrees right (Ctrl+arrows)"},
    {"rotate-left", NULL, NULL, NULL, {"<Control>Left"}, NULL, "turn 15 degrees left"},
    {"rotate-up", NULL, NULL, NULL, {"<Control>Up"}, NULL, "turn 15 degrees up"},
    {"rotate-down", NULL, NULL, NULL, {"<Control>Down"}, NULL, "turn 15 degrees down"},
    {"zoom", "d", NULL, do_zoom, {"Page_Up"}, "1.25", "zoom in (the wheel; Page Down out)"},
    {"zoom-out", NULL, NULL, NULL, {"Page_Down"}, NULL, "zoom out"},
    {"clip", "s", NULL, do_clip, {NULL}, NULL, "clip plane: SIDE[:F], nx,ny,nz,d, or none"},
    {"clip-front", NULL, NULL, do_clip_view, {"<Shift>c"}, NULL, "a clip plane facing the viewer, cutting away the near half"},
    {"clip-back", NULL, NULL, do_clip_view, {"<Control><Shift>c"}, NULL, "a clip plane facing the viewer, cutting away the far half"},
    {"clip-lock", NULL, NULL, do_clip_lock, {"<Control>l"}, NULL, "fix the clip plane to the object (it then turns with it)"},
    {"clip-move", "d", NULL, do_clip_move, {"<Shift>Page_Up"}, "5.0", "move the clip plane (mm; Ctrl+drag)"},
    {"image-plane", "i", NULL, do_image, {"bracketright", "<Control>Page_Up"}, "1", "move the image's planes (--image) by N of its planes (] or Ctrl+Page Up: 1; [ or Ctrl+Page Down: -1)"},
    {"image-plane-back", NULL, NULL, NULL, {"bracketleft", "<Control>Page_Down"}, NULL, "the image's planes one plane back"},
    {"image-window", "d", NULL, do_image, {"w"}, "1.25", "the image's window (grey range) times a factor (w: wider; Shift+W: narrower)"},
    {"image-window-narrower", NULL, NULL, NULL, {"<Shift>w"}, NULL, "the image's window narrower (times 0.8)"},
    {"image-level", "d", NULL, do_image, {"e"}, "0.1", "the image's level up by a fraction of the window (e: up; Shift+E: down)"},
    {"image-level-down", NULL, NULL, NULL, {"<Shift>e"}, NULL, "the image's level down by a tenth of the window"},
    {"screenshot", "s", NULL, do_screenshot, {"<Control>s"}, "''", "save the window as PNG (path; empty: next free name)"},
    {"record", "s", NULL, do_record, {"<Control>r"}, "''", "record every frame drawn into a directory"},
    {"record-stop", "s", NULL, do_record_stop, {"<Control><Shift>r"}, "''", "stop recording (and make an MP4 at the path given)"},
    {"record-all", "s", NULL, do_record_all, {"<Control><Alt>r"}, "''", "record every frame, unattended, and make DIR/animation.mp4"},
    {"fly", "s", NULL, do_fly, {NULL}, NULL, "fly the camera along a camera key file (as thorax animate --keys), frame by frame"},
    {"save-session", "s", NULL, do_save_session, {"<Control><Shift>s"}, "''", "save the session as a script of options"},
    {"pick", "s", NULL, do_pick, {NULL}, NULL, "pick at X,Y (window pixels; a click does the same)"},
    {"plot-zoom", "d", NULL, do_plot_zoom, {"<Alt>Page_Up"}, "2.0", "the traces' time axis zoomed by a factor about the frame (the wheel over them; 1: all)"},
    {"traces-clear", NULL, NULL, do_traces_clear, {"Escape"}, NULL, "clear the traces"},
    {"traces-export", "s", NULL, do_traces_export, {"<Control>e"}, "''", "write the traces as text"},
    {"edit", "s", NULL, do_edit, {NULL}, NULL, "an edit as an edit-log line, 1-based: node_move S N X Y Z, tri_delete S T, ..."},
    {"delete-triangle", NULL, NULL, do_edit_picked, {"Delete"}, NULL, "delete the picked triangle"},
    {"flip-triangle", NULL, NULL, do_edit_picked, {"f"}, NULL, "flip the picked triangle's orientation"},
    {"build-triangle", NULL, NULL, do_edit_picked, {"t"}, NULL, "a triangle on the last three picked nodes"},
    {"layer-x", "d", NULL, do_edit_picked, {"<Alt>Right"}, "1.0", "move the picked node's layer along x (mm; Alt+Left: -1)"},
    {"layer-y", "d", NULL, do_edit_picked, {"<Alt>Up"}, "1.0", "move the picked node's layer along y (mm; Alt+Down: -1)"},
    {"layer-rotate", "d", NULL, do_edit_picked, {"<Alt>period"}, "1.0", "turn the picked node's layer in its plane (degrees; Alt+comma: -1)"},
    {"layer-smooth", "d", NULL, do_edit_picked, {"<Alt>s"}, "2.0", "smooth the picked node's layer (bandwidth, mm)"},
    {"layer-x-back", NULL, NULL, NULL, {"<Alt>Left"}, NULL, "move the layer by -1 mm along x"},
    {"layer-y-back", NULL, NULL, NULL, {"<Alt>Down"}, NULL, "move the layer by -1 mm along y"},
    {"layer-rotate-back", NULL, NULL, NULL, {"<Alt>comma"}, NULL, "turn the layer by -1 degree"},
    {"undo", NULL, NULL, do_undo, {"<Control>z"}, NULL, "undo the last edit"},
    {"redo", NULL, NULL, do_redo, {"<Control><Shift>z", "<Control>y"}, NULL, "redo"},
    {"save-model", "s", NULL, do_save_model, {"<Control><Shift>m"}, "''", "save the edited model with its edit log (a directory; empty: the model itself)"},
    {"bench-rotate", "i", NULL, do_bench, {NULL}, NULL, "benchmark: N drawings each turned 1 degree"},
    {"bench-frames", "i", NULL, do_bench, {NULL}, NULL, "benchmark: N frame steps"},
    {"bench-pick", "i", NULL, do_bench, {NULL}, NULL, "benchmark: N picks over a grid of the window"},
    /* the side panel and what it edits (view_panel.c) */
    {"panel", NULL, "b", view_panel_action, {"F9"}, NULL, "the side panel: equipotentials, slices, seeds, colour range, activation window"},
    {"isosurface", "s", NULL, view_panel_action, {NULL}, NULL, "the equipotentials: a --isosurface list (values, count:N, P%), or none"},
    {"isovalue-add", "d", NULL, view_panel_action, {NULL}, NULL, "an equipotential at this value (its mark on the colour bar drags)"},
    {"isovalue-remove", "d", NULL, view_panel_action, {NULL}, NULL, "the equipotential at this value removed"},
    {"slice-add", "s", NULL, view_panel_action, {NULL}, NULL, "a slice: x=MM, y=MM, z=MM or PX,PY,PZ:NX,NY,NZ (it becomes the selected)"},
    {"slice-remove", "i", NULL, view_panel_action, {NULL}, NULL, "slice K removed (1-based)"},
    {"slice-select", "i", NULL, view_panel_action, {NULL}, NULL, "slice K is the one slice-move and Ctrl+Shift+drag move"},
    {"slice-move", "d", NULL, view_panel_action, {NULL}, NULL, "the selected slice moved along its normal (mm; Ctrl+Shift+drag)"},
    {"seed-add", "s", NULL, view_panel_action, {NULL}, NULL, "streamline seeds: a --streamlines spec (point:X,Y,Z, line:A:B:N, ...)"},
    {"seed-remove", "i", NULL, view_panel_action, {NULL}, NULL, "seed specification K removed (1-based)"},
    {"seed-density", "i", NULL, view_panel_action, {NULL}, NULL, "N seeds spread by |J| (density:N; 0 none)"},
    {"seed-tool", "s", "s", view_panel_action, {NULL}, NULL, "what a click does: none (picks a node), point (a seed), rake (two clicks: a line of seeds)"},
    {"range", "s", NULL, view_panel_action, {NULL}, NULL, "the colour range fixed, LO:HI, or auto (drag the colour bar's ends)"},
    {"shortcuts", NULL, NULL, do_shortcuts, {"question", "F1"}, NULL, "this list"},
    {"quit", NULL, NULL, do_quit, {"<Control>q"}, NULL, "quit"},
};

/* Keys that are a parameterized action with a fixed value (view-left is app.view('left'), ...):
   their rows above have no handler of their own. */
static const struct {
    const char *alias, *action, *target;
} ALIASES[] = {
    {"view-posterior", "view", "'posterior'"}, {"view-left", "view", "'left'"},       {"view-right", "view", "'right'"},
    {"view-superior", "view", "'superior'"},   {"view-inferior", "view", "'inferior'"}, {"rotate-left", "rotate", "'right:-15'"},
    {"rotate-up", "rotate", "'up:15'"},        {"rotate-down", "rotate", "'up:-15'"},   {"zoom-out", "zoom", "0.8"},
    {"image-plane-back", "image-plane", "-1"}, {"image-window-narrower", "image-window", "0.8"},
    {"image-level-down", "image-level", "-0.1"},
    {"layer-x-back", "layer-x", "-1.0"},       {"layer-y-back", "layer-y", "-1.0"},     {"layer-rotate-back", "layer-rotate", "-1.0"},
};

static void on_activate_action(GSimpleAction *act, GVariant *v, gpointer user)
{
    view_app *a = user;
    const char *name = g_action_get_name(G_ACTION(act));
    for (size_t k = 0; k < sizeof ACTIONS / sizeof ACTIONS[0]; k++)
        if (!strcmp(ACTIONS[k].name, name) && ACTIONS[k].fn) {
            if (ACTIONS[k].state && !ACTIONS[k].param && !strcmp(ACTIONS[k].state, "b")) {
                /* a toggle: activation flips the state */
                GVariant *st = g_action_get_state(G_ACTION(act));
                gboolean on = !g_variant_get_boolean(st);
                g_variant_unref(st);
                ACTIONS[k].fn(a, act, g_variant_new_boolean(on));
            } else {
                ACTIONS[k].fn(a, act, v);
            }
            return;
        }
}

static void on_change_state(GSimpleAction *act, GVariant *v, gpointer user)
{
    view_app *a = user;
    const char *name = g_action_get_name(G_ACTION(act));
    for (size_t k = 0; k < sizeof ACTIONS / sizeof ACTIONS[0]; k++)
        if (!strcmp(ACTIONS[k].name, name) && ACTIONS[k].fn) { ACTIONS[k].fn(a, act, v); return; }
}

static GVariant *initial_state(view_app *a, const action_def *d)
{
    const thx_picture_opts *o = &a->vo->pic;
    if (!strcmp(d->state, "b")) {
        int on = !strcmp(d->name, "loop") ? a->loop : !strcmp(d->name, "lock-frame") ? a->lock_frame
               : !strcmp(d->name, "lock-transform") ? a->lock_transform : !strcmp(d->name, "lock-scale") ? a->lock_scale
               : !strcmp(d->name, "colorbar") ? o->colorbar : !strcmp(d->name, "label") ? o->label
               : !strcmp(d->name, "invert") ? o->invert : !strcmp(d->name, "extrema") ? o->extrema : 0;
        return g_variant_new_boolean(on);
    }
    if (!strcmp(d->name, "seed-tool")) return g_variant_new_string("none");
    const char *s = !strcmp(d->name, "mode") ? mode_names[o->mode] : !strcmp(d->name, "style") ? style_names[o->style]
                  : !strcmp(d->name, "colormap") ? cmap_names[o->cmap] : !strcmp(d->name, "scale") ? scale_names[o->model]
                  : !strcmp(d->name, "mapping") ? mapping_names[o->mapping] : scope_names[o->scope];
    return g_variant_new_string(s);
}

static void on_alias(GSimpleAction *act, GVariant *v, gpointer user)
{
    view_app *a = user;
    const char *name = g_action_get_name(G_ACTION(act));
    for (size_t k = 0; k < sizeof ALIASES / sizeof ALIASES[0]; k++)
        if (!strcmp(ALIASES[k].alias, name)) {
            GVariant *t = g_variant_parse(NULL, ALIASES[k].target, NULL, NULL, NULL);
            g_action_group_activate_action(G_ACTION_GROUP(a->gapp), ALIASES[k].action, t);
        }
}

void view_actions_install(view_app *a)
{
    for (size_t k = 0; k < sizeof ACTIONS / sizeof ACTIONS[0]; k++) {
        const action_def *d = &ACTIONS[k];
        GSimpleAction *act;
        const GVariantType *pt = d->param ? G_VARIANT_TYPE(d->param) : NULL;
        if (d->state) act = g_simple_action_new_stateful(d->name, pt, initial_state(a, d));
        else act = g_simple_action_new(d->name, pt);
        g_signal_connect(act, "activate", G_CALLBACK(d->fn ? on_activate_action : on_alias), a);
        if (d->state) g_signal_connect(act, "change-state", G_CALLBACK(on_change_state), a);
        g_action_map_add_action(G_ACTION_MAP(a->gapp), G_ACTION(act));
        g_object_unref(act);
        if (d->keys[0]) {
            char detailed[128];
            if (d->target) snprintf(detailed, sizeof detailed, "app.%s(%s)", d->name, d->target);
            else snprintf(detailed, sizeof detailed, "app.%s", d->name);
            gtk_application_set_accels_for_action(a->gapp, detailed, d->keys);
        }
    }
}

/* ---- the keyboard overlay (`?`): the table above, as it is ---- */

/* The mouse's gestures, the overlay's first part (docs/cli.md lists the same). */
static const char *const GESTURES[][2] = {
    {"drag", "turn the object (arcball; round the rim: about the line of sight)"},
    {"Shift+drag, middle drag", "pan"},
    {"wheel", "zoom"},
    {"Ctrl+drag", "move the clip plane along its normal"},
    {"Ctrl+Shift+drag", "move the selected slice along its normal (panel, slice-select)"},
    {"click", "pick the node under the pointer: its ring, number and trace; with the seed tool a streamline seed "
              "(rake: two clicks)"},
    {"Alt+drag", "move the node under the pointer (an edit)"},
    {"drag a colour bar's end", "fix the colour range there (symmetric mapping: both ends)"},
    {"drag a value's mark", "move that equipotential (its mark on the equipotentials' colour bar)"},
    {"drag across the traces", "the current surface's activation map from that time window"},
    {"wheel over the traces", "zoom their time axis about the frame"},
};

/* A label of the overlay's grid at (col, row), spanning `span` columns, wrapped when wrap. */
static GtkWidget *cell(GtkWidget *grid, int col, int row, int span, const char *text, int markup, int wrap)
{
    GtkWidget *l = gtk_label_new(NULL);
    if (markup) gtk_label_set_markup(GTK_LABEL(l), text);
    else gtk_label_set_text(GTK_LABEL(l), text);
    gtk_label_set_selectable(GTK_LABEL(l), FALSE); /* nothing selected when the window opens */
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_label_set_yalign(GTK_LABEL(l), 0);
    if (wrap) {
        gtk_label_set_wrap(GTK_LABEL(l), TRUE);
        gtk_label_set_max_width_chars(GTK_LABEL(l), 70);
        gtk_label_set_width_chars(GTK_LABEL(l), 50);
    }
    gtk_grid_attach(GTK_GRID(grid), l, col, row, span, 1);
    return l;
}

/* Under -v, the window's size and its list's once they are laid out: a test checks that nothing is
 * cut off (the list as wide as the window's view of it; only its height scrolls). */
static gboolean keys_laid_out(GtkWidget *win, GdkFrameClock *clock, gpointer user)
{
    GtkWidget *grid = user;
    int ww = gtk_widget_get_width(win), gw = gtk_widget_get_width(grid);
    if (ww <= 0 || gw <= 0) return G_SOURCE_CONTINUE;
    int min, nat;
    gtk_widget_measure(grid, GTK_ORIENTATION_HORIZONTAL, -1, &min, &nat, NULL, NULL);
    int hmin, hnat;
    gtk_widget_measure(grid, GTK_ORIENTATION_VERTICAL, gw, &hmin, &hnat, NULL, NULL);
    GtkWidget *scroll = gtk_widget_get_parent(gtk_widget_get_parent(grid));
    fprintf(stderr, "thorax view: keys window %dx%d, its list %dx%d (needs at least %d wide), in view %dx%d\n", ww,
            gtk_widget_get_height(win), gw, hnat, min, gtk_widget_get_width(scroll), gtk_widget_get_height(scroll));
    return G_SOURCE_REMOVE;
}

/* The slice pane's gestures (view_slice.c), listed while tracing. */
static const char *const PANE_GESTURES[][2] = {
    {"click", "a point at the end of the open loop (region tool: the region's seed); on a coronal or sagittal plane: that axial plane"},
    {"double click, or a click on the first point", "close the loop"},
    {"drag a point", "move it (the current surface's, on this plane)"},
    {"Shift+click on an edge", "insert a point there"},
    {"Ctrl+click on a point", "delete it"},
    {"wheel", "the next or previous plane (Ctrl+wheel: zoom)"},
    {"right button drag", "across: the grey window wider or narrower; up and down: the level"},
    {"middle button drag", "pan"},
};

/* One row of the key list: the keys (GTK accelerator texts, up to 3), the action, what it does. */
static void key_row(GtkWidget *grid, int *row, const char *const keys_in[3], const char *name, const char *what)
{
    GString *keys = g_string_new("");
    for (int j = 0; j < 3 && keys_in[j]; j++) {
        guint key;
        GdkModifierType mods;
        if (gtk_accelerator_parse(keys_in[j], &key, &mods)) {
            char *label = gtk_accelerator_get_label(key, mods);
            /* a letter alone is the lower-case key (GTK writes it in capitals, like Shift+A's) */
            if (!mods && label[0] && !label[1]) label[0] = (char)g_ascii_tolower(label[0]);
            g_string_append_printf(keys, "%s%s", j ? ", " : "", label);
            g_free(label);
        }
    }
    cell(grid, 0, *row, 1, keys->str, 0, 0);
    cell(grid, 1, *row, 1, name, 0, 0);
    GtkWidget *help = cell(grid, 2, (*row)++, 1, what, 0, 0);
    gtk_label_set_wrap(GTK_LABEL(help), TRUE);
    gtk_label_set_max_width_chars(GTK_LABEL(help), 60);
    gtk_label_set_width_chars(GTK_LABEL(help), 40);
    g_string_free(keys, TRUE);
}

static void do_shortcuts(view_app *a, GSimpleAction *act, GVariant *v)
{
    GtkWidget *grid = gtk_grid_new();
    gtk_grid_set_column_spacing(GTK_GRID(grid), 18);
    gtk_grid_set_row_spacing(GTK_GRID(grid), 3);
    gtk_widget_set_margin_start(grid, 14);
    gtk_widget_set_margin_end(grid, 14);
    gtk_widget_set_margin_top(grid, 10);
    gtk_widget_set_margin_bottom(grid, 14);
    int row = 0;
    cell(grid, 0, row++, 3, "<b>Mouse</b> (in the picture, unless said)", 1, 0);
    for (size_t k = 0; k < sizeof GESTURES / sizeof GESTURES[0]; k++) {
        cell(grid, 0, row, 1, GESTURES[k][0], 0, 0);
        cell(grid, 1, row++, 2, GESTURES[k][1], 0, 1);
    }
    GtkWidget *gap = cell(grid, 0, row++, 3, "<b>Keys</b> and actions: menus and script lines <tt>action NAME [VALUE]</tt> run the same", 1, 0);
    gtk_widget_set_margin_top(gap, 12);
    cell(grid, 0, row, 1, "<i>key</i>", 1, 0);
    cell(grid, 1, row, 1, "<i>action</i>", 1, 0);
    cell(grid, 2, row++, 1, "<i>what it does</i>", 1, 0);
    for (size_t k = 0; k < sizeof ACTIONS / sizeof ACTIONS[0]; k++) {
        const action_def *d = &ACTIONS[k];
        key_row(grid, &row, d->keys, d->fn ? d->name : "", d->help);
    }
    if (a->trace) { /* tracing a scan: the slice pane's mouse and the tracing keys (view_trace.c) */
        gap = cell(grid, 0, row++, 3, "<b>Tracing</b>: the slice pane's mouse, and the tracing keys", 1, 0);
        gtk_widget_set_margin_top(gap, 12);
        for (size_t k = 0; k < sizeof PANE_GESTURES / sizeof PANE_GESTURES[0]; k++) {
            cell(grid, 0, row, 1, PANE_GESTURES[k][0], 0, 0);
            cell(grid, 1, row++, 2, PANE_GESTURES[k][1], 0, 1);
        }
        const char *rows[32][3];
        size_t n = view_trace_help(rows, 32);
        for (size_t k = 0; k < n; k++) {
            const char *keys[3] = {rows[k][0][0] ? rows[k][0] : NULL, NULL, NULL};
            key_row(grid, &row, keys, rows[k][1], rows[k][2]);
        }
    }
    GtkWidget *win = gtk_window_new();
    gtk_window_set_title(GTK_WINDOW(win), "thorax — keys");
    view_win *w = view_active(a);
    if (w) gtk_window_set_transient_for(GTK_WINDOW(win), GTK_WINDOW(w->window));
    /* as wide as the list (nothing cut off at the right), as high as it or most of the screen: then
       the list scrolls */
    GtkWidget *scroll = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(scroll), GTK_POLICY_NEVER, GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_propagate_natural_width(GTK_SCROLLED_WINDOW(scroll), TRUE);
    gtk_scrolled_window_set_propagate_natural_height(GTK_SCROLLED_WINDOW(scroll), TRUE);
    int screen_h = 768;
    GListModel *mons = gdk_display_get_monitors(gdk_display_get_default());
    GdkMonitor *mon = mons && g_list_model_get_n_items(mons) ? g_list_model_get_item(mons, 0) : NULL;
    if (mon) {
        GdkRectangle r;
        gdk_monitor_get_geometry(mon, &r);
        screen_h = r.height;
        g_object_unref(mon);
    }
    gtk_scrolled_window_set_max_content_height(GTK_SCROLLED_WINDOW(scroll), screen_h * 85 / 100);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(scroll), grid);
    gtk_window_set_child(GTK_WINDOW(win), scroll);
    /* Escape closes it */
    GtkEventController *sc = gtk_shortcut_controller_new();
    gtk_shortcut_controller_add_shortcut(GTK_SHORTCUT_CONTROLLER(sc),
                                         gtk_shortcut_new(gtk_keyval_trigger_new(GDK_KEY_Escape, 0),
                                                          gtk_named_action_new("window.close")));
    gtk_widget_add_controller(win, sc);
    if (a->vo->verbose > 0) gtk_widget_add_tick_callback(win, keys_laid_out, grid, NULL);
    gtk_window_present(GTK_WINDOW(win));
}

/* ---- the menus ---- */

static void add(GMenu *m, const char *label, const char *action)
{
    g_menu_append(m, label, action);
}

static GMenu *choice_menu(const char *action, const char *const *names, int n)
{
    GMenu *m = g_menu_new();
    for (int k = 0; k < n; k++) {
        char detailed[96];
        snprintf(detailed, sizeof detailed, "app.%s::%s", action, names[k]);
        add(m, names[k], detailed);
    }
    return m;
}

GMenuModel *view_menu(void)
{
    GMenu *bar = g_menu_new();
    GMenu *file = g_menu_new();
    add(file, "Save picture (PNG)", "app.screenshot::");
    add(file, "Record frames", "app.record::");
    add(file, "Stop recording", "app.record-stop::");
    add(file, "Record every frame", "app.record-all::");
    add(file, "Export traces", "app.traces-export::");
    add(file, "Save session", "app.save-session::");
    add(file, "Quit", "app.quit");
    g_menu_append_submenu(bar, "File", G_MENU_MODEL(file));
    GMenu *view = g_menu_new();
    GMenu *views = choice_menu("view", view_names, N_OF(view_names));
    g_menu_append_section(view, NULL, G_MENU_MODEL(views));
    add(view, "Reset", "app.reset");
    add(view, "Zoom in", "app.zoom(1.25)");
    add(view, "Zoom out", "app.zoom(0.8)");
    GMenu *clip = g_menu_new();
    static const char *clips[] = {"anterior", "posterior", "left", "right", "superior", "inferior", "none"};
    for (int k = 0; k < N_OF(clips); k++) {
        char detailed[64];
        snprintf(detailed, sizeof detailed, "app.clip::%s", clips[k]);
        add(clip, clips[k], detailed);
    }
    g_menu_append_submenu(view, "Clip", G_MENU_MODEL(clip));
    add(view, "Clip front (facing the viewer)", "app.clip-front");
    add(view, "Clip back (facing the viewer)", "app.clip-back");
    add(view, "Fix the clip plane to the object", "app.clip-lock");
    add(view, "Colour bar", "app.colorbar");
    add(view, "Time label", "app.label");
    add(view, "Side panel", "app.panel");
    add(view, "Keys", "app.shortcuts");
    g_menu_append_submenu(bar, "View", G_MENU_MODEL(view));
    GMenu *surf = g_menu_new();
    add(surf, "Next surface", "app.surface-next");
    add(surf, "Previous surface", "app.surface-prev");
    add(surf, "Show / hide", "app.visible");
    g_menu_append_submenu(surf, "Mode", G_MENU_MODEL(choice_menu("mode", mode_names, N_OF(mode_names))));
    g_menu_append_submenu(bar, "Surface", G_MENU_MODEL(surf));
    GMenu *data = g_menu_new();
    g_menu_append_submenu(data, "Style", G_MENU_MODEL(choice_menu("style", style_names, N_OF(style_names))));
    g_menu_append_submenu(data, "Colour map", G_MENU_MODEL(choice_menu("colormap", cmap_names, N_OF(cmap_names))));
    add(data, "Reversed colours", "app.invert");
    g_menu_append_submenu(data, "Scaling model", G_MENU_MODEL(choice_menu("scale", scale_names, N_OF(scale_names))));
    static const char *scopes_menu[] = {"frame", "series", "surfaces", "all"};
    g_menu_append_submenu(data, "Scope", G_MENU_MODEL(choice_menu("scope", scopes_menu, N_OF(scopes_menu))));
    g_menu_append_submenu(data, "Mapping", G_MENU_MODEL(choice_menu("mapping", mapping_names, N_OF(mapping_names))));
    add(data, "More levels", "app.levels-more");
    add(data, "Fewer levels", "app.levels-fewer");
    add(data, "One scale for every surface with data", "app.scale-group::all");
    add(data, "Scales apart again", "app.scale-group::none");
    add(data, "Next data set", "app.data-next");
    add(data, "Activation times", "app.activation::");
    add(data, "Extrema", "app.extrema");
    add(data, "Node numbers", "app.node-labels::index");
    add(data, "Node channels", "app.node-labels::channel");
    add(data, "Node values", "app.node-labels::value");
    add(data, "No node labels", "app.node-labels::none");
    add(data, "Clear traces", "app.traces-clear");
    g_menu_append_submenu(bar, "Data", G_MENU_MODEL(data));
    GMenu *frames = g_menu_new();
    add(frames, "Next", "app.frame-next");
    add(frames, "Previous", "app.frame-prev");
    add(frames, "First", "app.frame-first");
    add(frames, "Last", "app.frame-last");
    add(frames, "Play", "app.play");
    add(frames, "Loop", "app.loop");
    add(frames, "Frame lock", "app.lock-frame");
    add(frames, "Transform lock", "app.lock-transform");
    add(frames, "Scale lock", "app.lock-scale");
    g_menu_append_submenu(bar, "Frames", G_MENU_MODEL(frames));
    GMenu *edit = g_menu_new();
    add(edit, "Undo", "app.undo");
    add(edit, "Redo", "app.redo");
    add(edit, "Delete the picked triangle", "app.delete-triangle");
    add(edit, "Flip the picked triangle", "app.flip-triangle");
    add(edit, "Triangle on the last three picked nodes", "app.build-triangle");
    add(edit, "Smooth the picked node's layer", "app.layer-smooth(2.0)");
    add(edit, "Save the model with its edit log", "app.save-model::");
    g_menu_append_submenu(bar, "Edit", G_MENU_MODEL(edit));
    return G_MENU_MODEL(bar);
}
