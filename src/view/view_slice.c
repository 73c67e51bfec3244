/*
 * The slice pane (issue 26 item 1): the scan's plane beside the 3D view, drawn with cairo in a
 * GtkDrawingArea, in the radiological convention (the patient's right on the screen's left,
 * anterior or superior up), with the traced loops over it, and the mouse that traces.
 *
 * Axial planes are traced on: a click lays a point (or, with the region tool, seeds a region), a
 * double click closes the loop, a drag moves a point of the current surface, Shift+click inserts one
 * on the edge under the pointer, Ctrl+click deletes one; the livewire's path to the pointer is drawn
 * while the mouse moves. Coronal and sagittal planes show where the loops cut them; a click there
 * picks the axial plane. Everywhere: the wheel steps planes (Ctrl+wheel zooms), the right button
 * drags the grey window (across) and level (up and down), the middle button pans.
 *
 * Every change goes through view_trace_line as a line of the session's language: the pane holds no
 * loops of its own. The grey plane is kept as a cairo surface and made again only when the plane,
 * the window or the level changes, so scrolling and redrawing the loops cost what the loops cost.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "view/view_trace.h"

/* ---- geometry: pixel (a, b) of the shown plane <-> the pane's pixels ---- */

typedef struct {
    double W, H, scale, pu, pv, ac, bc, pan0, pan1;
} pane_geo;

static pane_geo geo_of(const view_tracing *t, const thx_image_slice *sl)
{
    pane_geo g;
    g.W = gtk_widget_get_width(t->area);
    g.H = gtk_widget_get_height(t->area);
    g.pu = sqrt(sl->du[0] * sl->du[0] + sl->du[1] * sl->du[1] + sl->du[2] * sl->du[2]);
    g.pv = sqrt(sl->dv[0] * sl->dv[0] + sl->dv[1] * sl->dv[1] + sl->dv[2] * sl->dv[2]);
    double fit = fmin(g.W / ((double)sl->w * g.pu), g.H / ((double)sl->h * g.pv));
    g.scale = 0.96 * fit * t->zoom;
    g.ac = 0.5 * ((double)sl->w - 1);
    g.bc = 0.5 * ((double)sl->h - 1);
    g.pan0 = t->pan[0];
    g.pan1 = t->pan[1];
    return g;
}

static void px_to_screen(const pane_geo *g, double a, double b, double *x, double *y)
{
    *x = 0.5 * g->W + g->pan0 - g->scale * g->pu * (a - g->ac);
    *y = 0.5 * g->H + g->pan1 - g->scale * g->pv * (b - g->bc);
}

static void screen_to_px(const pane_geo *g, double x, double y, double *a, double *b)
{
    *a = g->ac - (x - 0.5 * g->W - g->pan0) / (g->scale * g->pu);
    *b = g->bc - (y - 0.5 * g->H - g->pan1) / (g->scale * g->pv);
}

static void ras_to_px(const thx_image_slice *sl, const double p[3], double *a, double *b)
{
    double d[3] = {p[0] - sl->origin[0], p[1] - sl->origin[1], p[2] - sl->origin[2]};
    double uu = sl->du[0] * sl->du[0] + sl->du[1] * sl->du[1] + sl->du[2] * sl->du[2];
    double vv = sl->dv[0] * sl->dv[0] + sl->dv[1] * sl->dv[1] + sl->dv[2] * sl->dv[2];
    *a = (d[0] * sl->du[0] + d[1] * sl->du[1] + d[2] * sl->du[2]) / uu;
    *b = (d[0] * sl->dv[0] + d[1] * sl->dv[1] + d[2] * sl->dv[2]) / vv;
}

static void px_to_ras(const thx_image_slice *sl, double a, double b, double p[3])
{
    for (int k = 0; k < 3; k++) p[k] = sl->origin[k] + a * sl->du[k] + b * sl->dv[k];
}

static void ras_to_screen(const pane_geo *g, const thx_image_slice *sl, double x, double y, double z, double *sx, double *sy)
{
    double p[3] = {x, y, z}, a, b;
    ras_to_px(sl, p, &a, &b);
    px_to_screen(g, a, b, sx, sy);
}

/* The plane shown: the session's (axial) or a coronal/sagittal one through the cursor. */
static const thx_image_slice *shown_plane(view_app *a)
{
    view_tracing *t = a->trace;
    if (t->orient == 'z') return thx_dig_slice(a->ctx, t->s);
    int axis = t->orient == 'x' ? 0 : 1;
    double pos = t->cursor[axis];
    if (!t->have_other || t->other_key[0] != t->orient || t->other_key[1] != pos) {
        if (t->have_other) thx_image_slice_free(&t->other);
        t->have_other = 0;
        thx_image_plane_spec spec = {t->orient, pos};
        if (thx_image_sample_plane(a->ctx, t->img, &spec, 0, &t->other) != THX_OK) return NULL;
        t->have_other = 1;
        t->other_key[0] = t->orient;
        t->other_key[1] = pos;
    }
    return &t->other;
}

/* The grey plane under the window and level, kept until one of them or the plane changes. */
static cairo_surface_t *grey_plane(view_app *a, const thx_image_slice *sl)
{
    view_tracing *t = a->trace;
    double key[5] = {t->orient, sl->origin[0] + sl->origin[1] * 1e-3, sl->origin[2], a->d.window, a->d.level};
    if (t->grey && !memcmp(key, t->grey_key, sizeof key)) return t->grey;
    if (t->grey) cairo_surface_destroy(t->grey);
    t->grey = cairo_image_surface_create(CAIRO_FORMAT_RGB24, (int)sl->w, (int)sl->h);
    memcpy(t->grey_key, key, sizeof key);
    cairo_surface_flush(t->grey);
    unsigned char *px = cairo_image_surface_get_data(t->grey);
    int stride = cairo_image_surface_get_stride(t->grey);
    double lo = a->d.level - 0.5 * a->d.window, inv = a->d.window > 0 ? 255.0 / a->d.window : 0;
    for (size_t b = 0; b < sl->h; b++) {
        uint32_t *row = (uint32_t *)(px + (size_t)stride * b);
        for (size_t c = 0; c < sl->w; c++) {
            float v = sl->v[c + sl->w * b];
            if (!isfinite(v)) { row[c] = 0x202838u; continue; }
            double g = (v - lo) * inv;
            unsigned q = g <= 0 ? 0u : g >= 255 ? 255u : (unsigned)(g + 0.5);
            row[c] = (q << 16) | (q << 8) | q;
        }
    }
    cairo_surface_mark_dirty(t->grey);
    return t->grey;
}

/* A colour per role (the picture's own surface colours are the 3D view's; these read on grey). */
static void role_rgb(thx_role r, double rgb[3])
{
    static const double c[THX_ROLE_COUNT][3] = {
        {1.00, 0.80, 0.20}, /* outer */
        {0.30, 0.85, 1.00}, /* fat */
        {0.85, 0.45, 1.00}, /* muscle */
        {0.35, 1.00, 0.45}, /* lung */
        {1.00, 0.35, 0.35}, /* heart */
        {0.95, 0.95, 0.95}, /* other */
    };
    memcpy(rgb, c[r < THX_ROLE_COUNT ? r : THX_ROLE_OTHER], sizeof c[0]);
}

static void draw_loop(cairo_t *cr, const pane_geo *g, const thx_image_slice *sl, const thx_dig_loop *l, double z)
{
    for (size_t i = 0; i < l->n; i++) {
        double x, y;
        ras_to_screen(g, sl, l->p[i].x, l->p[i].y, z, &x, &y);
        if (i == 0) cairo_move_to(cr, x, y);
        else cairo_line_to(cr, x, y);
    }
    if (l->closed) cairo_close_path(cr);
}

/* Axial: every surface's loops on the plane, the current surface's neighbours faint, its points, the
 * crossings in red, the livewire's path to the pointer. */
static void draw_axial(view_app *a, cairo_t *cr, const pane_geo *g, const thx_image_slice *sl)
{
    view_tracing *t = a->trace;
    thx_dig_session *s = t->s;
    long k = thx_dig_current_plane(s);
    double z = thx_dig_plane_z(s, k);
    int cur = thx_dig_current_surface(s);
    double rgb[3];
    if (cur >= 0) { /* the neighbouring planes' loops, faint */
        role_rgb(thx_dig_surface_role(s, (size_t)cur), rgb);
        for (long d = -1; d <= 1; d += 2) {
            const thx_dig_loop *l;
            size_t n = thx_dig_loops(s, (size_t)cur, k + d, &l);
            cairo_set_source_rgba(cr, rgb[0], rgb[1], rgb[2], 0.35);
            cairo_set_line_width(cr, 1);
            double dash[2] = {4, 3};
            cairo_set_dash(cr, d < 0 ? dash : NULL, d < 0 ? 2 : 0, 0);
            for (size_t j = 0; j < n; j++) { draw_loop(cr, g, sl, &l[j], z); cairo_stroke(cr); }
            cairo_set_dash(cr, NULL, 0, 0);
        }
    }
    thx_dig_crossing *x = NULL;
    size_t nx = 0;
    thx_dig_crossings(a->ctx, s, k, &x, &nx);
    for (size_t i = 0; i < thx_dig_n_surfaces(s); i++) {
        const thx_dig_loop *l;
        size_t n = thx_dig_loops(s, i, k, &l);
        role_rgb(thx_dig_surface_role(s, i), rgb);
        for (size_t j = 0; j < n; j++) {
            int crossing = 0;
            for (size_t c = 0; c < nx; c++)
                crossing |= (x[c].sa == i && x[c].la == j) || (x[c].sb == i && x[c].lb == j);
            if (crossing) cairo_set_source_rgb(cr, 1, 0.1, 0.1);
            else cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
            cairo_set_line_width(cr, (int)i == cur ? 2 : 1.25);
            double dash[2] = {6, 4};
            cairo_set_dash(cr, l[j].closed ? NULL : dash, l[j].closed ? 0 : 2, 0);
            draw_loop(cr, g, sl, &l[j], z);
            cairo_stroke(cr);
            cairo_set_dash(cr, NULL, 0, 0);
            if ((int)i != cur) continue;
            for (size_t p = 0; p < l[j].n; p++) { /* the points that a drag takes */
                double sx, sy;
                double px = l[j].p[p].x, py = l[j].p[p].y;
                if (t->drag_node && t->drag_loop == j && t->drag_i == p) { px = t->drag_at[0]; py = t->drag_at[1]; }
                ras_to_screen(g, sl, px, py, z, &sx, &sy);
                cairo_rectangle(cr, sx - 1.5, sy - 1.5, 3, 3);
                cairo_fill(cr);
            }
        }
    }
    cairo_set_source_rgb(cr, 1, 0.1, 0.1);
    cairo_set_line_width(cr, 2);
    for (size_t c = 0; c < nx; c++) { /* a ring where loops cross */
        double sx, sy;
        ras_to_screen(g, sl, x[c].x, x[c].y, z, &sx, &sy);
        cairo_arc(cr, sx, sy, 7, 0, 2 * M_PI);
        cairo_stroke(cr);
    }
    if (nx) {
        char msg[200];
        snprintf(msg, sizeof msg, "%zu crossing%s on this plane (%s and %s)", nx, nx == 1 ? "" : "s",
                 thx_dig_surface_name(s, x[0].sa), thx_dig_surface_name(s, x[0].sb));
        cairo_select_font_face(cr, "monospace", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
        cairo_set_font_size(cr, 12);
        cairo_move_to(cr, 6, 34);
        cairo_show_text(cr, msg);
    }
    free(x);
    if (t->n_preview > 1) {
        cairo_set_source_rgb(cr, 1, 1, 0.2);
        cairo_set_line_width(cr, 1.25);
        for (size_t i = 0; i < t->n_preview; i++) {
            double sx, sy;
            ras_to_screen(g, sl, t->preview[3 * i], t->preview[3 * i + 1], z, &sx, &sy);
            if (i == 0) cairo_move_to(cr, sx, sy);
            else cairo_line_to(cr, sx, sy);
        }
        cairo_stroke(cr);
    }
}

/* Coronal and sagittal: the axial plane being traced (a line), and where each traced loop cuts the
 * plane shown (dots in its surface's colour). */
static void draw_other(view_app *a, cairo_t *cr, const pane_geo *g, const thx_image_slice *sl)
{
    view_tracing *t = a->trace;
    thx_dig_session *s = t->s;
    int axis = t->orient == 'x' ? 0 : 1, other = 1 - axis;
    double c = t->cursor[axis];
    double rgb[3];
    for (size_t i = 0; i < thx_dig_n_surfaces(s); i++) {
        role_rgb(thx_dig_surface_role(s, i), rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        long ks[4096];
        size_t nk = thx_dig_planes_traced(s, i, ks, 4096);
        for (size_t q = 0; q < nk && q < 4096; q++) {
            double z = thx_dig_plane_z(s, ks[q]);
            const thx_dig_loop *l;
            size_t n = thx_dig_loops(s, i, ks[q], &l);
            for (size_t j = 0; j < n; j++)
                for (size_t p = 0; p < l[j].n; p++) {
                    if (!l[j].closed && p + 1 == l[j].n) break;
                    const thx_vec2 *P = &l[j].p[p], *Q = &l[j].p[(p + 1) % l[j].n];
                    double pa = axis ? P->y : P->x, qa = axis ? Q->y : Q->x;
                    if ((pa < c) == (qa < c)) continue;
                    double u = (c - pa) / (qa - pa);
                    double po = other ? P->y : P->x, qo = other ? Q->y : Q->x, o = po + u * (qo - po);
                    double r[3];
                    r[axis] = c;
                    r[other] = o;
                    r[2] = z;
                    double sx, sy;
                    ras_to_screen(g, sl, r[0], r[1], r[2], &sx, &sy);
                    cairo_arc(cr, sx, sy, 2.5, 0, 2 * M_PI);
                    cairo_fill(cr);
                }
        }
    }
    double z = thx_dig_plane_z(s, thx_dig_current_plane(s)), r[3] = {t->cursor[0], t->cursor[1], z}, x0, y0;
    ras_to_screen(g, sl, r[0], r[1], r[2], &x0, &y0);
    cairo_set_source_rgba(cr, 0.3, 0.9, 1, 0.8);
    cairo_set_line_width(cr, 1);
    cairo_move_to(cr, 0, y0);
    cairo_line_to(cr, g->W, y0);
    cairo_stroke(cr);
}

static void text_line(cairo_t *cr, double x, double y, const char *s, double r, double gg, double b)
{
    cairo_set_source_rgba(cr, 0, 0, 0, 0.6);
    cairo_text_extents_t e;
    cairo_text_extents(cr, s, &e);
    cairo_rectangle(cr, x - 3, y - 13, e.x_advance + 6, 17);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, r, gg, b);
    cairo_move_to(cr, x, y);
    cairo_show_text(cr, s);
}

static void draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user)
{
    (void)area;
    view_app *a = user;
    view_tracing *t = a->trace;
    cairo_set_source_rgb(cr, 0.05, 0.05, 0.07);
    cairo_paint(cr);
    if (!t) return;
    const thx_image_slice *sl = shown_plane(a);
    t->shown = sl;
    if (!sl) {
        cairo_set_source_rgb(cr, 1, 0.4, 0.4);
        cairo_move_to(cr, 10, 20);
        cairo_show_text(cr, thx_ctx_message(a->ctx));
        return;
    }
    pane_geo g = geo_of(t, sl);
    cairo_surface_t *img = grey_plane(a, sl);
    cairo_save(cr);
    /* texel (i, j) covers [i, i + 1]: pixel a's centre is at i = a + 0.5 */
    double x0, y0;
    px_to_screen(&g, -0.5, -0.5, &x0, &y0);
    cairo_matrix_t m;
    cairo_matrix_init(&m, -g.scale * g.pu, 0, 0, -g.scale * g.pv, x0, y0);
    cairo_transform(cr, &m);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), g.scale * g.pu >= 2 ? CAIRO_FILTER_NEAREST : CAIRO_FILTER_GOOD);
    cairo_paint(cr);
    cairo_restore(cr);
    if (t->orient == 'z') draw_axial(a, cr, &g, sl);
    else draw_other(a, cr, &g, sl);
    /* what is traced, and each surface's verdict */
    thx_dig_session *s = t->s;
    cairo_select_font_face(cr, "monospace", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 12);
    static const char *tools[] = {"points", "livewire", "region"};
    int cur = thx_dig_current_surface(s);
    long k = thx_dig_current_plane(s);
    char line[512];
    snprintf(line, sizeof line, "%s  z=%.2f mm (%ld/%ld)  %s%s%s  %s  W %g L %g", t->orient == 'z' ? "axial" : t->orient == 'y' ? "coronal" : "sagittal",
             thx_dig_plane_z(s, k), k + 1, thx_dig_n_planes(s), cur >= 0 ? thx_dig_surface_name(s, (size_t)cur) : "(Tab: a surface)",
             cur >= 0 ? ":" : "", cur >= 0 ? thx_role_name(thx_dig_surface_role(s, (size_t)cur)) : "", tools[t->tool], a->d.window, a->d.level);
    text_line(cr, 6, 16, line, 1, 1, 1);
    double y = H - 8;
    for (size_t i = thx_dig_n_surfaces(s); i-- > 0;) {
        const view_trace_surf *ts = &t->surf[i < VIEW_TRACE_MAX ? i : 0];
        snprintf(line, sizeof line, "%s%s: %s", (int)i == cur ? "> " : "  ", thx_dig_surface_name(s, i),
                 ts->built ? ts->verdict : "not built yet");
        if (ts->ok) text_line(cr, 6, y, line, 0.45, 1, 0.45);
        else text_line(cr, 6, y, line, 1, 0.5, 0.4);
        y -= 17;
    }
    (void)W;
}

void view_slice_draw(view_app *a, cairo_t *cr, int W, int H)
{
    draw(GTK_DRAWING_AREA(a->trace->area), cr, W, H, a);
}

int view_slice_png(view_app *a, const char *path)
{
    view_tracing *t = a->trace;
    if (!t || !t->area) return -1;
    int W = gtk_widget_get_width(t->area), H = gtk_widget_get_height(t->area);
    if (W < 1 || H < 1) return -1;
    cairo_surface_t *cs = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(cs);
    draw(GTK_DRAWING_AREA(t->area), cr, W, H, a);
    cairo_destroy(cr);
    cairo_status_t st = cairo_surface_write_to_png(cs, path);
    cairo_surface_destroy(cs);
    return st == CAIRO_STATUS_SUCCESS ? 0 : -1;
}

void view_slice_redraw(view_app *a)
{
    if (a->trace && a->trace->area) gtk_widget_queue_draw(a->trace->area);
}

/* ---- the mouse ---- */

/* The RAS point under pane pixel (x, y) on the shown plane; -1 when nothing is shown. */
static int at_ras(view_app *a, double x, double y, double p[3])
{
    view_tracing *t = a->trace;
    const thx_image_slice *sl = t->shown = shown_plane(a); /* (a line may have changed the plane since the draw) */
    if (!sl) return -1;
    pane_geo g = geo_of(t, sl);
    double pa, pb;
    screen_to_px(&g, x, y, &pa, &pb);
    px_to_ras(sl, pa, pb, p);
    return 0;
}

/* The current surface's point (edge 0) or edge (edge 1: from that point to the next) nearest pane
 * pixel (x, y), within 7 pixels, on the axial plane shown: 0 and its loop and point; -1 none. */
static int nearest_at(view_app *a, double x, double y, int edge, size_t *loop, size_t *pt)
{
    view_tracing *t = a->trace;
    int cur = thx_dig_current_surface(t->s);
    if (cur < 0 || t->orient != 'z' || !(t->shown = shown_plane(a))) return -1;
    pane_geo g = geo_of(t, t->shown);
    long k = thx_dig_current_plane(t->s);
    double z = thx_dig_plane_z(t->s, k), best = 49;
    const thx_dig_loop *l;
    size_t n = thx_dig_loops(t->s, (size_t)cur, k, &l);
    int found = -1;
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < l[j].n; i++) {
            if (edge && !l[j].closed && i + 1 == l[j].n) break;
            double ax, ay, bx, by, u = 0;
            ras_to_screen(&g, t->shown, l[j].p[i].x, l[j].p[i].y, z, &ax, &ay);
            if (edge) {
                ras_to_screen(&g, t->shown, l[j].p[(i + 1) % l[j].n].x, l[j].p[(i + 1) % l[j].n].y, z, &bx, &by);
                double ex = bx - ax, ey = by - ay, len2 = ex * ex + ey * ey;
                u = len2 > 0 ? fmin(fmax(((x - ax) * ex + (y - ay) * ey) / len2, 0), 1) : 0;
                ax += u * ex;
                ay += u * ey;
            }
            double d = (ax - x) * (ax - x) + (ay - y) * (ay - y);
            if (d < best) { best = d; *loop = j; *pt = i; found = 0; }
        }
    return found;
}

static int node_at(view_app *a, double x, double y, size_t *loop, size_t *pt) { return nearest_at(a, x, y, 0, loop, pt); }
static int edge_at(view_app *a, double x, double y, size_t *loop, size_t *pt) { return nearest_at(a, x, y, 1, loop, pt); }

static gint64 last_click_time;
static double last_click_xy[2];

static void on_drag_begin(GtkGestureDrag *gd, double x, double y, gpointer user)
{
    view_app *a = user;
    view_tracing *t = a->trace;
    gtk_widget_grab_focus(t->area);
    t->drag_button = (int)gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(gd));
    t->drag_x0 = x;
    t->drag_y0 = y;
    t->drag_node = 0;
    t->drag_pan[0] = t->pan[0];
    t->drag_pan[1] = t->pan[1];
    t->drag_window = a->d.window;
    t->drag_level = a->d.level;
    if (t->drag_button != 1 || t->orient != 'z') return;
    GdkModifierType mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(gd));
    size_t l, i;
    char line[160];
    if ((mods & GDK_CONTROL_MASK) && node_at(a, x, y, &l, &i) == 0) {
        snprintf(line, sizeof line, "delete %zu %zu", l + 1, i + 1);
        view_trace_line(a, line);
        t->drag_button = 0;
    } else if ((mods & GDK_SHIFT_MASK) && edge_at(a, x, y, &l, &i) == 0) {
        double p[3];
        if (at_ras(a, x, y, p) == 0) {
            snprintf(line, sizeof line, "insert %zu %zu %.2f %.2f", l + 1, i + 1, p[0], p[1]);
            view_trace_line(a, line);
        }
        t->drag_button = 0;
    } else if (!(mods & (GDK_CONTROL_MASK | GDK_SHIFT_MASK)) && node_at(a, x, y, &l, &i) == 0) {
        const thx_dig_loop *lp;
        thx_dig_loops(t->s, (size_t)thx_dig_current_surface(t->s), thx_dig_current_plane(t->s), &lp);
        t->drag_node = 1;
        t->drag_loop = l;
        t->drag_i = i;
        t->drag_at[0] = lp[l].p[i].x;
        t->drag_at[1] = lp[l].p[i].y;
    }
}

static void on_drag_update(GtkGestureDrag *gd, double dx, double dy, gpointer user)
{
    (void)gd;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (t->drag_button == 2) {
        t->pan[0] = t->drag_pan[0] + dx;
        t->pan[1] = t->drag_pan[1] + dy;
    } else if (t->drag_button == 3) { /* across: the window (wider to the right); up: the level higher */
        a->d.window = t->drag_window * exp(dx / 200.0);
        a->d.level = t->drag_level - dy * t->drag_window / 400.0;
        view_redraw_all(a);
    } else if (t->drag_button == 1 && t->drag_node) {
        double p[3];
        if (at_ras(a, t->drag_x0 + dx, t->drag_y0 + dy, p) == 0) { t->drag_at[0] = p[0]; t->drag_at[1] = p[1]; }
    }
    view_slice_redraw(a);
}

static void on_drag_end(GtkGestureDrag *gd, double dx, double dy, gpointer user)
{
    (void)gd;
    view_app *a = user;
    view_tracing *t = a->trace;
    int button = t->drag_button;
    t->drag_button = 0;
    if (button != 1) return;
    double x = t->drag_x0 + dx, y = t->drag_y0 + dy, p[3];
    char line[200];
    if (t->drag_node && hypot(dx, dy) >= 1) {
        t->drag_node = 0;
        if (at_ras(a, x, y, p) == 0) {
            snprintf(line, sizeof line, "move %zu %zu %.2f %.2f", t->drag_loop + 1, t->drag_i + 1, p[0], p[1]);
            view_trace_line(a, line);
        }
        view_slice_redraw(a);
        return;
    }
    int on_node = t->drag_node;
    t->drag_node = 0;
    if (hypot(dx, dy) > 4 || at_ras(a, x, y, p) != 0) return; /* a drag that took nothing: not a click */
    if (t->orient != 'z') { /* coronal or sagittal: the axial plane clicked */
        snprintf(line, sizeof line, "plane z=%.4f", p[2]);
        view_trace_line(a, line);
        return;
    }
    gint64 now = g_get_monotonic_time();
    int twice = now - last_click_time < 400000 && hypot(x - last_click_xy[0], y - last_click_xy[1]) <= 4;
    last_click_time = twice ? 0 : now;
    last_click_xy[0] = x;
    last_click_xy[1] = y;
    if (twice && t->tool != VIEW_TOOL_REGION) { view_trace_line(a, "close"); return; }
    if (on_node) { /* a click on a point: on the open loop's first, it closes the loop; else it only takes it */
        const thx_dig_loop *l;
        int cur = thx_dig_current_surface(t->s);
        size_t n = cur >= 0 ? thx_dig_loops(t->s, (size_t)cur, thx_dig_current_plane(t->s), &l) : 0;
        if (t->drag_loop < n && !l[t->drag_loop].closed && t->drag_i == 0 && l[t->drag_loop].n >= 3) view_trace_line(a, "close");
        return;
    }
    if (t->tool == VIEW_TOOL_REGION) {
        double lo = t->have_thr ? t->thr_lo : a->d.level - 0.5 * a->d.window;
        double hi = t->have_thr ? t->thr_hi : a->d.level + 0.5 * a->d.window;
        snprintf(line, sizeof line, "region %.6g %.6g %.2f %.2f", lo, hi, p[0], p[1]);
    } else {
        snprintf(line, sizeof line, "point %.2f %.2f", p[0], p[1]);
    }
    view_trace_line(a, line);
}

static void on_motion(GtkEventControllerMotion *mc, double x, double y, gpointer user)
{
    (void)mc;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (t->tool != VIEW_TOOL_LIVEWIRE || t->orient != 'z' || t->drag_button) return;
    double p[3];
    if (at_ras(a, x, y, p) != 0) return;
    free(t->preview);
    t->preview = NULL;
    t->n_preview = 0;
    if (thx_dig_preview(a->ctx, t->s, p[0], p[1], &t->preview, &t->n_preview) != THX_OK) t->n_preview = 0;
    view_slice_redraw(a);
}

static gboolean on_scroll(GtkEventControllerScroll *sc, double dx, double dy, gpointer user)
{
    (void)dx;
    view_app *a = user;
    view_tracing *t = a->trace;
    GdkModifierType mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(sc));
    if (mods & GDK_CONTROL_MASK) {
        t->zoom = fmin(fmax(t->zoom * pow(1.15, -dy), 0.25), 32);
        view_slice_redraw(a);
        return TRUE;
    }
    int n = dy < 0 ? 1 : dy > 0 ? -1 : 0;
    if (!n) return TRUE;
    if (t->orient == 'z') {
        char line[32];
        snprintf(line, sizeof line, "plane %+d", n);
        view_trace_line(a, line);
    } else { /* the coronal / sagittal plane itself moves */
        int axis = t->orient == 'x' ? 0 : 1;
        double lo, hi, step;
        thx_image_plane_range(t->img, t->orient, &lo, &hi, &step);
        t->cursor[axis] = fmin(fmax(t->cursor[axis] + n * step, lo + 0.5 * step), hi - 0.5 * step);
        view_slice_redraw(a);
    }
    return TRUE;
}

GtkWidget *view_slice_new(view_app *a)
{
    view_tracing *t = a->trace;
    t->area = gtk_drawing_area_new();
    gtk_widget_set_size_request(t->area, 560, a->vo->win_h);
    gtk_widget_set_hexpand(t->area, TRUE);
    gtk_widget_set_vexpand(t->area, TRUE);
    gtk_widget_set_focusable(t->area, TRUE);
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(t->area), draw, a, NULL);
    for (int b = 1; b <= 3; b++) {
        GtkGesture *gd = gtk_gesture_drag_new();
        gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(gd), (guint)b);
        g_signal_connect(gd, "drag-begin", G_CALLBACK(on_drag_begin), a);
        g_signal_connect(gd, "drag-update", G_CALLBACK(on_drag_update), a);
        g_signal_connect(gd, "drag-end", G_CALLBACK(on_drag_end), a);
        gtk_widget_add_controller(t->area, GTK_EVENT_CONTROLLER(gd));
    }
    GtkEventController *mc = gtk_event_controller_motion_new();
    g_signal_connect(mc, "motion", G_CALLBACK(on_motion), a);
    gtk_widget_add_controller(t->area, mc);
    GtkEventController *sc = gtk_event_controller_scroll_new(GTK_EVENT_CONTROLLER_SCROLL_VERTICAL);
    g_signal_connect(sc, "scroll", G_CALLBACK(on_scroll), a);
    gtk_widget_add_controller(t->area, sc);
    return t->area;
}
