/*
 * The side panel (issue 26, item 4): what was only in options and scripts, at the right of each
 * window's drawing area (F9, action `panel`): the equipotentials' values (--isosurface), the slice
 * planes (--slice), the streamlines' seeds (--streamlines), the colour range (--scope fixed:LO:HI)
 * and the activation window (action activation T0:T1). Every control runs an action, so a script
 * line `action NAME VALUE` does what a click does, and every action changes every window's picture
 * and redraws it at once (the cuts are rebuilt when their options change: field_layers.c's key).
 *
 * Gestures in the drawing area, panel shown or not:
 *   - on the colour bar of the equipotentials, each value has a mark; dragging a mark moves the value;
 *   - dragging the top or bottom end of any colour bar fixes the colour range there (under the
 *     symmetric mapping both ends move together, as the bar shows them);
 *   - Ctrl+Shift+drag moves the selected slice along its normal (its projection on the screen: a
 *     drag across a plane seen edge-on moves it, a plane facing the viewer moves with the vertical);
 *   - with the seed tool on, a click seeds a streamline at the point under the pointer (just inside
 *     the volume: the surfaces bound it), two clicks a rake of seeds between them;
 *   - a drag across the traces under the picture is a time window: the current surface's
 *     activation map from it.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/field/field.h"
#include "thorax/field/streamline.h"
#include "view/view_internal.h"

#define PANEL_W 270
#define MAX_ISO 64

enum { DRAG_NONE, DRAG_ISO, DRAG_TOP, DRAG_BOTTOM, DRAG_SLICE };

struct view_panel {
    view_win *w;
    GtkWidget *root;                       /* the scrolled column at the right of the drawing area */
    GtkWidget *iso_list, *iso_entry;
    GtkWidget *slice_list, *slice_axis, *slice_pos;
    GtkWidget *seed_list, *seed_tool, *density, *rake_n;
    GtkWidget *lo, *hi, *range_note;
    GtkWidget *t0, *t1;
    GtkWidget *note, *cut_boxes[3];        /* without volume potentials the cuts' sections are off, and why */
    int refreshing;                        /* the controls being filled from the state: their signals do nothing */
    /* a gesture under way in the drawing area */
    int drag, drag_iso;
    int box[4];                            /* the bar's strip, framebuffer pixels */
    thx_scale scale;                       /* its scale when the drag began */
    double value0;                         /* the value dragged, as it began */
    double slice_s[2];                     /* the selected slice's unit normal on the screen (right, up) */
    char slice0[96];                       /* the selected slice as the drag began */
};

static const char *const scope_words[] = {"frame", "series", "all", "fixed", "surfaces"};

/* ---- the state every window shares ---- */

/* The range the volume's colour scale spans at the frame shown (field_layers.c's volume_range): the
 * counts and percentages of an --isosurface list are of it. */
static void volume_range(view_app *a, double *lo, double *hi)
{
    const thx_picture_opts *o = &a->win[0]->o;
    const thx_series *x = a->d.volume;
    *lo = a->d.vmin;
    *hi = a->d.vmax;
    if (o->scope == THX_SCOPE_FIXED) { *lo = o->lo; *hi = o->hi; return; }
    if (!x || (o->scope != THX_SCOPE_FRAME && o->scope != THX_SCOPE_SURFACES)) return;
    size_t f = (size_t)view_frame_of(a->win[0]);
    if (f >= x->n_frames) f = x->n_frames - 1;
    double l = INFINITY, h = -INFINITY;
    for (size_t i = 0; i < x->n_rows; i++) {
        double v = x->v[f * x->n_rows + i];
        if (isfinite(v)) { l = fmin(l, v); h = fmax(h, v); }
    }
    if (l < h) { *lo = l; *hi = h; }
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The equipotentials' values, ascending: the list's numbers, and its counts and percentages as the
 * values they give at the frame shown. */
static int iso_values(view_app *a, double *out, int max)
{
    const char *spec = a->win[0]->o.isosurface;
    if (!spec || !a->d.volume) return 0;
    double lo, hi, *v = NULL;
    size_t n = 0;
    volume_range(a, &lo, &hi);
    if (thx_field_values_parse(a->ctx, spec, lo, hi, &v, &n) != THX_OK) return 0;
    int k = 0;
    for (; k < (int)n && k < max; k++) out[k] = v[k];
    free(v);
    qsort(out, (size_t)k, sizeof *out, cmp_double);
    return k;
}

static void format_list(const double *v, int n, char *buf, size_t size)
{
    size_t len = 0;
    buf[0] = '\0';
    for (int k = 0; k < n && len < size; k++) len += (size_t)snprintf(buf + len, size - len, "%s%.6g", k ? "," : "", v[k]);
}

/* orient3d: six times the signed volume of a, b, c, d */
static double orient(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; v[k] = c[k] - a[k]; w[k] = d[k] - a[k]; }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/* Whether p lies in a tetrahedron of the solution's domain (every tetrahedron tried, most at their
 * bounding box: a click's worth; a seed click took 3.8 ms, pick included, on the medium phantom's
 * 288,048 tetrahedra). */
static int in_domain(const thx_picture_data *d, const double p[3])
{
    const thx_volume *v = d->m->volume;
    if (!v) return 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (d->field_use && !d->field_use[v->region[t]]) continue;
        const double *c[4];
        int out = 0;
        for (int k = 0; k < 4; k++) c[k] = v->xyz + 3 * (size_t)v->tet[4 * t + k];
        for (int k = 0; k < 3 && !out; k++) {
            double lo = fmin(fmin(c[0][k], c[1][k]), fmin(c[2][k], c[3][k])), hi = fmax(fmax(c[0][k], c[1][k]), fmax(c[2][k], c[3][k]));
            out = p[k] < lo || p[k] > hi;
        }
        if (out) continue;
        double o = orient(c[0], c[1], c[2], c[3]);
        double s0 = orient(p, c[1], c[2], c[3]), s1 = orient(c[0], p, c[2], c[3]), s2 = orient(c[0], c[1], p, c[3]),
               s3 = orient(c[0], c[1], c[2], p);
        if (o > 0 ? s0 >= 0 && s1 >= 0 && s2 >= 0 && s3 >= 0 : s0 <= 0 && s1 <= 0 && s2 <= 0 && s3 <= 0) return 1;
    }
    return 0;
}

/* A point seed must lie in the volume and a rake must have a seed there (thx_stream_seeds would
 * refuse them at the draw, with the picture gone); the other seeds are checked as they are drawn.
 * Seeds the pictures have already were checked when they came. */
static int seeds_inside(view_app *a, char seeds[][256], int n)
{
    const thx_picture_opts *o = &a->win[0]->o;
    for (int k = 0; k < n; k++) {
        int known = 0;
        for (int j = 0; j < o->n_streamlines; j++) known |= !strcmp(o->streamlines[j], seeds[k]);
        if (known) continue;
        thx_seed_spec s;
        if (thx_seed_spec_parse(a->ctx, seeds[k], &s) != THX_OK) return -1;
        int inside = s.kind != THX_SEED_POINT && s.kind != THX_SEED_LINE;
        size_t m = s.kind == THX_SEED_LINE ? s.n : 1;
        for (size_t i = 0; i < m && !inside; i++) {
            double t = m > 1 ? (double)i / (double)(m - 1) : 0.5, p[3];
            for (int c = 0; c < 3; c++) p[c] = s.kind == THX_SEED_LINE ? s.a[c] + t * (s.b[c] - s.a[c]) : s.a[c];
            inside = in_domain(&a->d, p);
        }
        if (!inside) {
            thx_error(a->ctx, THX_EINPUT, "--streamlines %s: %s outside the volume of %s", seeds[k],
                      s.kind == THX_SEED_POINT ? "the point lies" : "every seed of the line lies", a->win[0]->o.solution);
            return -1;
        }
    }
    return 0;
}

/*
 * Every window's cuts replaced by these (iso NULL or "": no equipotentials), after the checks
 * thorax render makes (thx_picture_cuts_check), and every window redrawn at once. 0, or -1 after
 * saying why in the status line, with a failed status (a script stops there naming its line);
 * quiet (a drag): -1 without a word, the cuts as they were (the drag stops at the last good place).
 */
static int set_cuts(view_app *a, const char *what, const char *iso, char slices[][96], int n_slices, char seeds[][256],
                    int n_seeds, int quiet)
{
    /* copies first: the arguments may be the buffers the pictures point to */
    char iso_t[sizeof a->cuts.iso], sl_t[8][96], se_t[4][256];
    snprintf(iso_t, sizeof iso_t, "%s", iso ? iso : "");
    for (int k = 0; k < n_slices; k++) snprintf(sl_t[k], sizeof sl_t[k], "%s", slices[k]);
    for (int k = 0; k < n_seeds; k++) snprintf(se_t[k], sizeof se_t[k], "%s", seeds[k]);
    thx_picture_opts o = a->win[0]->o;
    o.isosurface = iso_t[0] ? iso_t : NULL;
    o.n_slices = n_slices;
    for (int k = 0; k < n_slices; k++) o.slices[k] = sl_t[k];
    o.n_streamlines = n_seeds;
    for (int k = 0; k < n_seeds; k++) o.streamlines[k] = se_t[k];
    if (thx_picture_cuts_check(a->ctx, &o, &a->d) != THX_OK || seeds_inside(a, se_t, n_seeds)) {
        if (!quiet) {
            view_report(a, what);
            a->status = 1;
        }
        return -1;
    }
    memcpy(a->cuts.iso, iso_t, sizeof iso_t);
    memcpy(a->cuts.slice, sl_t, sizeof sl_t);
    memcpy(a->cuts.seed, se_t, sizeof se_t);
    for (int j = 0; j < a->n_win; j++) {
        thx_picture_opts *p = &a->win[j]->o;
        p->isosurface = a->cuts.iso[0] ? a->cuts.iso : NULL;
        p->n_slices = n_slices;
        for (int k = 0; k < n_slices; k++) p->slices[k] = a->cuts.slice[k];
        p->n_streamlines = n_seeds;
        for (int k = 0; k < n_seeds; k++) p->streamlines[k] = a->cuts.seed[k];
    }
    if (a->cuts.slice_sel >= n_slices) a->cuts.slice_sel = n_slices > 0 ? n_slices - 1 : 0;
    view_redraw_all(a);
    if (!quiet) view_panel_refresh(a);
    return 0;
}

/* The cuts as they are now, into the buffers set_cuts takes. */
static void current_cuts(view_app *a, char *iso, size_t iso_size, char slices[8][96], int *n_slices, char seeds[4][256], int *n_seeds)
{
    const thx_picture_opts *o = &a->win[0]->o;
    snprintf(iso, iso_size, "%s", o->isosurface ? o->isosurface : "");
    *n_slices = o->n_slices;
    for (int k = 0; k < o->n_slices; k++) snprintf(slices[k], 96, "%s", o->slices[k]);
    *n_seeds = o->n_streamlines;
    for (int k = 0; k < o->n_streamlines; k++) snprintf(seeds[k], 256, "%s", o->streamlines[k]);
}

/* The equipotentials at exactly these values (ascending, distinct). */
static int set_iso_values(view_app *a, const char *what, double *v, int n, int quiet)
{
    char iso[1024], list[1024], sl[8][96], se[4][256];
    int ns, nse;
    current_cuts(a, iso, sizeof iso, sl, &ns, se, &nse);
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    format_list(v, n, list, sizeof list);
    return set_cuts(a, what, list, sl, ns, se, nse, quiet);
}

/* Plane spec moved by mm along its normal: "z=110" -> "z=115"; "P:N" -> the point moved. */
static int move_plane(const char *spec, double mm, char *out, size_t size)
{
    char axis;
    double pos, p[3], n[3];
    int used = 0;
    if (sscanf(spec, " %c=%lf%n", &axis, &pos, &used) == 2 && !spec[used] && (axis == 'x' || axis == 'y' || axis == 'z')) {
        snprintf(out, size, "%c=%.6g", axis, pos + mm);
        return 0;
    }
    if (sscanf(spec, "%lf,%lf,%lf:%lf,%lf,%lf", &p[0], &p[1], &p[2], &n[0], &n[1], &n[2]) == 6) {
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0)) return -1;
        snprintf(out, size, "%.6g,%.6g,%.6g:%.6g,%.6g,%.6g", p[0] + mm * n[0] / l, p[1] + mm * n[1] / l, p[2] + mm * n[2] / l, n[0],
                 n[1], n[2]);
        return 0;
    }
    return -1;
}

/* The fixed colour range lo..hi on every window (scope fixed), or back to the scope it replaced. */
static void set_range(view_app *a, int fixed, double lo, double hi)
{
    for (int j = 0; j < a->n_win; j++) {
        thx_picture_opts *o = &a->win[j]->o;
        if (fixed) {
            if (o->scope != THX_SCOPE_FIXED) a->cuts.scope_auto = o->scope;
            o->scope = THX_SCOPE_FIXED;
            o->lo = lo;
            o->hi = hi;
        } else if (o->scope == THX_SCOPE_FIXED) {
            o->scope = a->cuts.scope_auto;
        }
    }
    /* the scope's radio state follows (fixed is not one of its menu's items) */
    GAction *s = g_action_map_lookup_action(G_ACTION_MAP(a->gapp), "scope");
    if (s) g_simple_action_set_state(G_SIMPLE_ACTION(s), g_variant_new_string(scope_words[a->win[0]->o.scope]));
    if (fixed) view_set_info(a, "colour range fixed: %.6g to %.6g", lo, hi);
    else view_set_info(a, "colour range: scope %s", scope_words[a->win[0]->o.scope]);
    view_redraw_all(a);
    view_panel_refresh(a);
}

/* ---- the actions (the table in view_actions.c names them) ---- */

/* An action refused: the status line says why, and a script stops at its line. */
static void fail(view_app *a, const char *fmt, ...) G_GNUC_PRINTF(2, 3);
static void fail(view_app *a, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    view_set_info(a, "%s", msg);
    a->status = 1;
}

/* A GTK 4 window keeps the largest size it had: after the panel is hidden, a default size below its
 * minimum makes it take the minimum again, the drawing area's --size (set once the panel's hiding
 * is laid out; unset again when it is shown, so that the next hiding is a change). */
static gboolean shrink_window(gpointer user)
{
    view_win *w = user;
    gtk_window_set_default_size(GTK_WINDOW(w->window), 1, 1);
    return G_SOURCE_REMOVE;
}

static void act_panel(view_app *a, GSimpleAction *act, GVariant *v)
{
    int on = g_variant_get_boolean(v);
    g_simple_action_set_state(act, v);
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        if (!w->panel) continue;
        if (gtk_widget_get_visible(w->panel->root) == on) continue;
        /* the drawing area keeps its size: the window grows by the panel, and shrinks back after */
        gtk_widget_set_visible(w->panel->root, on);
        if (!on) g_idle_add(shrink_window, w);
        else gtk_window_set_default_size(GTK_WINDOW(w->window), -1, -1);
    }
    view_set_info(a, "side panel %s", on ? "shown (F9 hides it)" : "hidden");
    view_panel_refresh(a);
}

static void act_isovalue(view_app *a, const char *name, double x)
{
    double v[MAX_ISO + 1];
    int n = iso_values(a, v, MAX_ISO), at = -1;
    /* a value as listed (6 digits) is the value: the list shows them so */
    double tol = 1e-6 * fmax(fabs(x), fmax(fabs(a->d.vmin), fabs(a->d.vmax)));
    for (int k = 0; k < n; k++)
        if (fabs(v[k] - x) <= tol) at = k;
    char s[64];
    snprintf(s, sizeof s, "%.6g", x);
    if (!strcmp(name, "isovalue-add")) {
        if (at >= 0) { fail(a, "isovalue-add %s: already among the values", s); return; }
        if (n == MAX_ISO) { fail(a, "isovalue-add %s: 64 values at most", s); return; }
        v[n++] = x;
    } else {
        if (at < 0) {
            char list[1024];
            format_list(v, n, list, sizeof list);
            fail(a, "isovalue-remove %s: not among the values (%.400s)", s, n ? list : "none");
            return;
        }
        v[at] = v[--n];
    }
    if (set_iso_values(a, name, v, n, 0) == 0) {
        char list[1024];
        format_list(v, n, list, sizeof list);
        view_set_info(a, "equipotentials: %s", n ? list : "none");
    }
}

static void act_slice(view_app *a, const char *name, GVariant *v)
{
    char iso[1024], sl[8][96], se[4][256];
    int ns, nse;
    current_cuts(a, iso, sizeof iso, sl, &ns, se, &nse);
    if (!strcmp(name, "slice-add")) {
        const char *spec = g_variant_get_string(v, NULL);
        if (ns == 8) { fail(a, "slice-add %s: 8 slices at most", spec); return; }
        snprintf(sl[ns++], sizeof sl[0], "%s", spec);
        if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) {
            a->cuts.slice_sel = ns - 1;
            view_set_info(a, "slice %d: %s (selected)", ns, spec);
            view_panel_refresh(a);
        }
        return;
    }
    if (!strcmp(name, "slice-move")) {
        double mm = g_variant_get_double(v);
        int k = a->cuts.slice_sel;
        if (k >= ns) { fail(a, "slice-move: no slice (slice-add x=MM|y=MM|z=MM|P:N)"); return; }
        char moved[96];
        if (move_plane(sl[k], mm, moved, sizeof moved)) { fail(a, "slice-move: cannot move the plane %s", sl[k]); return; }
        snprintf(sl[k], sizeof sl[k], "%s", moved);
        if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) view_set_info(a, "slice %d: %s", k + 1, moved);
        return;
    }
    int k = g_variant_get_int32(v);
    if (k < 1 || k > ns) {
        if (ns) fail(a, "%s %d: the slices are 1 to %d", name, k, ns);
        else fail(a, "%s %d: there is no slice (slice-add)", name, k);
        return;
    }
    if (!strcmp(name, "slice-select")) {
        a->cuts.slice_sel = k - 1;
        view_set_info(a, "slice %d selected: %s", k, sl[k - 1]);
        view_panel_refresh(a);
        return;
    }
    for (int j = k - 1; j + 1 < ns; j++) memcpy(sl[j], sl[j + 1], sizeof sl[j]);
    ns--;
    if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) view_set_info(a, "slice %d removed; %d left", k, ns);
}

static void act_seed(view_app *a, const char *name, GSimpleAction *act, GVariant *v)
{
    char iso[1024], sl[8][96], se[4][256];
    int ns, nse;
    current_cuts(a, iso, sizeof iso, sl, &ns, se, &nse);
    if (!strcmp(name, "seed-tool")) {
        const char *s = g_variant_get_string(v, NULL);
        int t = !strcmp(s, "none") ? 0 : !strcmp(s, "point") ? 1 : !strcmp(s, "rake") ? 2 : -1;
        if (t < 0) { fail(a, "seed-tool '%s': none, point or rake", s); return; }
        a->cuts.seed_tool = t;
        a->cuts.have_rake_a = 0;
        g_simple_action_set_state(act, g_variant_new_string(s));
        if (t == 2) view_set_info(a, "seed tool: two clicks, the ends of a rake of %d seeds", a->cuts.rake_n);
        else view_set_info(a, "seed tool: %s", t ? "a click seeds a streamline there" : "off");
        view_panel_refresh(a);
        return;
    }
    if (!strcmp(name, "seed-add")) {
        const char *spec = g_variant_get_string(v, NULL);
        if (nse == 4) { fail(a, "seed-add %s: 4 seed specifications at most (seed-remove K)", spec); return; }
        snprintf(se[nse++], sizeof se[0], "%s", spec);
        if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) view_set_info(a, "streamlines from %s (%zu lines)", spec, a->d.n_stream_lines);
        return;
    }
    int k = g_variant_get_int32(v);
    if (!strcmp(name, "seed-density")) {
        int at = -1;
        for (int j = 0; j < nse; j++)
            if (!strncmp(se[j], "density:", 8)) at = j;
        if (k < 0 || k > 100000) { fail(a, "seed-density %d: 0 (none) to 100000", k); return; }
        if (at < 0 && k == 0) return;
        if (at < 0 && nse == 4) { fail(a, "seed-density: 4 seed specifications at most (seed-remove K)"); return; }
        if (at < 0) at = nse++;
        snprintf(se[at], sizeof se[at], "density:%d", k);
        if (k == 0) {
            for (int j = at; j + 1 < nse; j++) memcpy(se[j], se[j + 1], sizeof se[j]);
            nse--;
        }
        if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) view_set_info(a, "streamlines: %d seeds by density", k);
        return;
    }
    if (k < 1 || k > nse) {
        if (nse) fail(a, "seed-remove %d: the seed specifications are 1 to %d", k, nse);
        else fail(a, "seed-remove %d: there are no seeds (seed-add, seed-density)", k);
        return;
    }
    for (int j = k - 1; j + 1 < nse; j++) memcpy(se[j], se[j + 1], sizeof se[j]);
    nse--;
    if (set_cuts(a, name, iso, sl, ns, se, nse, 0) == 0) view_set_info(a, "seeds %d removed; %d left", k, nse);
}

void view_panel_action(view_app *a, GSimpleAction *act, GVariant *v)
{
    const char *name = g_action_get_name(G_ACTION(act));
    if (!strcmp(name, "panel")) { act_panel(a, act, v); return; }
    if (!strcmp(name, "range")) {
        const char *s = g_variant_get_string(v, NULL);
        double lo, hi;
        int used = 0;
        if (!strcmp(s, "auto") || !s[0]) { set_range(a, 0, 0, 0); return; }
        if (sscanf(s, "%lf:%lf%n", &lo, &hi, &used) != 2 || s[used] || !isfinite(lo) || !isfinite(hi) || !(lo < hi)) {
            fail(a, "range '%s': give LO:HI (LO < HI, the data's unit), or auto", s);
            return;
        }
        set_range(a, 1, lo, hi);
        return;
    }
    /* the volume potentials, read at the first cut (without a cut at the start they were not) */
    if ((strcmp(name, "seed-tool") || strcmp(g_variant_get_string(v, NULL), "none")) &&
        thx_picture_volume_load(a->ctx, &a->win[0]->o, &a->d, name) != THX_OK) {
        view_report(a, name);
        a->status = 1;
        view_panel_refresh(a);
        return;
    }
    if (!strcmp(name, "isosurface")) {
        const char *s = g_variant_get_string(v, NULL);
        char iso[1024], sl[8][96], se[4][256];
        int ns, nse;
        current_cuts(a, iso, sizeof iso, sl, &ns, se, &nse);
        if (set_cuts(a, name, strcmp(s, "none") ? s : "", sl, ns, se, nse, 0) == 0) view_set_info(a, "equipotentials: %s", s[0] ? s : "none");
    } else if (!strncmp(name, "isovalue-", 9)) {
        act_isovalue(a, name, g_variant_get_double(v));
    } else if (!strncmp(name, "slice-", 6)) {
        act_slice(a, name, v);
    } else {
        act_seed(a, name, act, v);
    }
}

/* ---- the colour bar's marks and gestures ---- */

/* The bar under framebuffer point (fx, fy) (any, fx < 0), or of the equipotentials (want_iso): its
 * index and strip, from the last draw's bars. -1 when none. */
static int bar_at(view_win *w, double fx, double fy, int want_iso, int box[4])
{
    int b[THX_PICTURE_BARS][4];
    if (!w->o.colorbar || !w->font || w->bars.n < 1) return -1;
    int fit = thx_picture_bar_layout(&w->o, w->font, w->fb_w, w->fb_h, w->bars.n, b);
    for (int k = 0; k < fit; k++) {
        if (want_iso && !strstr(w->bars.names[k], "equipotentials") && w->bars.n > 1) continue;
        if (want_iso && w->bars.n == 1 && !w->o.isosurface) continue;
        /* the strip and a margin: the width of the bar's column left of its labels, 8 pixels above and below */
        if (fx >= 0 && (fx < b[k][0] - 12 || fx > b[k][0] + b[k][2] + 6 || fy < b[k][1] - 10 || fy > b[k][1] + b[k][3] + 10)) continue;
        memcpy(box, b[k], sizeof b[k]);
        return k;
    }
    return -1;
}

/* The row of value x on a bar's strip (t 0 at the bottom, as thx_draw_colorbar draws it). */
static double bar_row(const int box[4], double t)
{
    return box[1] + box[3] - t * box[3];
}

void view_panel_marks(view_win *w, const thx_picture_opts *o, thx_raster *img)
{
    (void)o;
    int box[4], k = bar_at(w, -1, -1, 1, box);
    if (k < 0) return;
    double v[MAX_ISO];
    int n = iso_values(w->app, v, MAX_ISO);
    static const unsigned char white[4] = {255, 255, 255, 255}, black[4] = {0, 0, 0, 255};
    for (int i = 0; i < n; i++) {
        double t = thx_scale_apply(&w->bars.scale[k], v[i]);
        if (!(t >= 0 && t <= 1)) continue;
        int y = (int)lround(bar_row(box, t));
        /* a line across the strip and a notch at its left, white on black: seen on every colour */
        thx_draw_rect(img, box[0] - 7, y - 1, box[2] + 8, 3, black);
        thx_draw_rect(img, box[0] - 6, y, box[2] + 6, 1, white);
        for (int d = 1; d <= 3; d++) {
            thx_draw_rect(img, box[0] - 10 + d, y - d - 1, 2, 2 * d + 3, black);
            thx_draw_rect(img, box[0] - 9 + d, y - d, 1, 2 * d + 1, white);
        }
    }
}

int view_panel_drag_begin(view_win *w, double x, double y, GdkModifierType m, guint button)
{
    view_panel *p = w->panel;
    view_app *a = w->app;
    if (!p || button != 1) return 0;
    p->drag = DRAG_NONE;
    int scale = gtk_widget_get_scale_factor(w->gl);
    double fx = x * scale, fy = y * scale;
    if ((m & GDK_CONTROL_MASK) && (m & GDK_SHIFT_MASK)) {
        /* the selected slice, along its normal as the screen shows it */
        const thx_picture_opts *o = &w->o;
        if (a->cuts.slice_sel >= o->n_slices) { view_set_info(a, "Ctrl+Shift+drag moves the selected slice: no slice (slice-add)"); return 1; }
        thx_field_plane pl;
        if (thx_field_plane_parse(a->ctx, o->slices[a->cuts.slice_sel], &pl) != THX_OK) return 1;
        double r[3], u[3], b[3], nl = sqrt(pl.n[0] * pl.n[0] + pl.n[1] * pl.n[1] + pl.n[2] * pl.n[2]);
        view_camera_basis(w, r, u, b);
        p->slice_s[0] = p->slice_s[1] = 0;
        for (int k = 0; k < 3 && nl > 0; k++) { p->slice_s[0] += r[k] * pl.n[k] / nl; p->slice_s[1] += u[k] * pl.n[k] / nl; }
        snprintf(p->slice0, sizeof p->slice0, "%s", o->slices[a->cuts.slice_sel]);
        p->drag = DRAG_SLICE;
        return 1;
    }
    if (m & (GDK_CONTROL_MASK | GDK_SHIFT_MASK | GDK_ALT_MASK)) return 0;
    int box[4], k = bar_at(w, fx, fy, 0, box);
    if (k < 0) return 0;
    p->scale = w->bars.scale[k];
    memcpy(p->box, box, sizeof box);
    /* a value's mark (the equipotentials' bar), else the nearer end */
    int ib[4];
    if (bar_at(w, fx, fy, 1, ib) == k) {
        double v[MAX_ISO], best = 6;
        int n = iso_values(a, v, MAX_ISO);
        for (int i = 0; i < n; i++) {
            double d = fabs(bar_row(box, thx_scale_apply(&p->scale, v[i])) - fy);
            if (d <= best) { best = d; p->drag = DRAG_ISO; p->drag_iso = i; p->value0 = v[i]; }
        }
        if (p->drag == DRAG_ISO) return 1;
    }
    if (fy < box[1] + 0.25 * box[3]) p->drag = DRAG_TOP;
    else if (fy > box[1] + 0.75 * box[3]) p->drag = DRAG_BOTTOM;
    else return 1; /* the bar's middle: nothing (and no turn) */
    p->value0 = thx_scale_invert(&p->scale, p->drag == DRAG_TOP ? 1 : 0);
    return 1;
}

void view_panel_drag_update(view_win *w, double dx, double dy)
{
    view_panel *p = w->panel;
    view_app *a = w->app;
    if (!p) return;
    int scale = gtk_widget_get_scale_factor(w->gl);
    if (p->drag == DRAG_SLICE) {
        double mmpp = view_mm_per_pixel(w), s2 = p->slice_s[0] * p->slice_s[0] + p->slice_s[1] * p->slice_s[1];
        /* the distance along the normal whose screen image is nearest the drag; a plane seen face-on: the vertical */
        double mm = s2 > 0.04 ? mmpp * (dx * p->slice_s[0] - dy * p->slice_s[1]) / s2 : -dy * mmpp;
        char iso[1024], sl[8][96], se[4][256], moved[96];
        int ns, nse;
        current_cuts(a, iso, sizeof iso, sl, &ns, se, &nse);
        if (a->cuts.slice_sel >= ns || move_plane(p->slice0, mm, moved, sizeof moved)) return;
        snprintf(sl[a->cuts.slice_sel], sizeof sl[0], "%s", moved);
        if (set_cuts(a, "slice", iso, sl, ns, se, nse, 1) == 0) view_set_info(a, "slice %d: %s", a->cuts.slice_sel + 1, moved);
        return;
    }
    if (p->drag == DRAG_NONE) return;
    /* the value under the pointer on the bar as it was when the drag began (linear between its ends,
       beyond them too for the range) */
    double t = (p->box[1] + p->box[3] - (bar_row(p->box, thx_scale_apply(&p->scale, p->value0)) + dy * scale)) / p->box[3];
    if (p->drag == DRAG_ISO) {
        double v[MAX_ISO];
        int n = iso_values(a, v, MAX_ISO);
        if (p->drag_iso >= n) return;
        double x = thx_scale_invert(&p->scale, fmin(fmax(t, 0), 1));
        for (int i = 0; i < n; i++) /* values stay distinct */
            if (i != p->drag_iso && fabs(v[i] - x) < 1e-9 * fmax(1, fabs(x))) return;
        v[p->drag_iso] = x;
        if (set_iso_values(a, "isovalue", v, n, 1) == 0) {
            /* the list is sorted again: follow the value */
            n = iso_values(a, v, MAX_ISO);
            for (int i = 0; i < n; i++)
                if (v[i] == x || fabs(v[i] - x) < 1e-6 * fmax(1, fabs(x))) p->drag_iso = i;
            view_set_info(a, "equipotential %.6g (was %.6g)", x, p->value0);
        }
        return;
    }
    double b0 = thx_scale_invert(&p->scale, 0), b1 = thx_scale_invert(&p->scale, 1);
    double x = b0 + t * (b1 - b0), lo = p->drag == DRAG_TOP ? b0 : x, hi = p->drag == DRAG_TOP ? x : b1;
    if (p->scale.mapping == THX_MAPPING_SYMMETRIC) { /* the bar is symmetric about zero: both ends move */
        hi = fabs(x);
        lo = -hi;
    }
    double l = fmin(lo, hi), h = fmax(lo, hi);
    if (!(h - l > 1e-9 * fmax(fabs(l), fabs(h))) || !isfinite(l) || !isfinite(h)) return;
    for (int j = 0; j < a->n_win; j++) {
        thx_picture_opts *o = &a->win[j]->o;
        if (o->scope != THX_SCOPE_FIXED) a->cuts.scope_auto = o->scope;
        o->scope = THX_SCOPE_FIXED;
        o->lo = l;
        o->hi = h;
    }
    view_set_info(a, "colour range fixed: %.6g to %.6g", l, h);
    view_redraw_all(a);
}

void view_panel_drag_end(view_win *w, double dx, double dy)
{
    view_panel *p = w->panel;
    if (!p) return;
    view_panel_drag_update(w, dx, dy);
    int was = p->drag;
    p->drag = DRAG_NONE;
    view_app *a = w->app;
    if (was == DRAG_TOP || was == DRAG_BOTTOM) set_range(a, 1, w->o.lo, w->o.hi); /* the scope's state, the panel */
    else view_panel_refresh(a);
    if (a->vo->verbose > 0 && was != DRAG_NONE) fprintf(stderr, "thorax view: %s\n", a->info);
}

/* A click with the seed tool on: a point seed, or a rake's end. 1 when the click was the tool's. */
int view_panel_click(view_win *w, double x, double y)
{
    view_app *a = w->app;
    if (!a->cuts.seed_tool || !a->d.volume) return 0;
    double p[3], dir[3], q[3], lo[3], hi[3];
    gint64 t0 = g_get_monotonic_time();
    if (!view_pick_point(w, x, y, p, dir)) { view_set_info(a, "seed: no surface under the pointer"); return 1; }
    /* the point hit is on a surface, the volume's boundary: the seed goes just inside, along the ray
       (beyond a surface facing the viewer, before one met from inside) */
    thx_picture_bounds(&a->d, lo, hi);
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]), step = fmax(0.002 * diag, 0.1);
    int found = 0;
    for (int k = 1; k <= 40 && !found; k++)
        for (int sg = 1; sg >= -1 && !found; sg -= 2) {
            for (int c = 0; c < 3; c++) q[c] = p[c] + sg * k * step * dir[c] / dl;
            found = in_domain(&a->d, q);
        }
    if (!found) { view_set_info(a, "seed: the volume is not near the point picked (%.1f, %.1f, %.1f)", p[0], p[1], p[2]); return 1; }
    char spec[256];
    if (a->cuts.seed_tool == 2 && !a->cuts.have_rake_a) {
        memcpy(a->cuts.rake_a, q, sizeof q);
        a->cuts.have_rake_a = 1;
        view_set_info(a, "rake: one end at (%.1f, %.1f, %.1f); click the other", q[0], q[1], q[2]);
        return 1;
    }
    if (a->cuts.seed_tool == 2) {
        const double *r = a->cuts.rake_a;
        snprintf(spec, sizeof spec, "line:%.6g,%.6g,%.6g:%.6g,%.6g,%.6g:%d", r[0], r[1], r[2], q[0], q[1], q[2], a->cuts.rake_n);
        a->cuts.have_rake_a = 0;
    } else {
        snprintf(spec, sizeof spec, "point:%.6g,%.6g,%.6g", q[0], q[1], q[2]);
    }
    int before = a->status;
    g_action_group_activate_action(G_ACTION_GROUP(a->gapp), "seed-add", g_variant_new_string(spec));
    a->status = before; /* a click's failure is the status line's, not the exit status's */
    if (a->vo->verbose >= 0) printf("seed: %s (placed in %.1f ms)\n", spec, (double)(g_get_monotonic_time() - t0) / 1000.0);
    fflush(stdout);
    return 1;
}

/* ---- the trace pane: a dragged time window is the activation window ---- */

static void plot_drag_begin(GtkGestureDrag *g, double x, double y, gpointer user)
{
    view_win *w = user;
    double t;
    if (view_plot_time_at(w, x, &t)) return;
    w->app->cuts.selecting = 1;
    w->app->cuts.sel[0] = w->app->cuts.sel[1] = t;
}

static void plot_drag_update(GtkGestureDrag *g, double dx, double dy, gpointer user)
{
    view_win *w = user;
    double x0, y0, t;
    if (!w->app->cuts.selecting || !gtk_gesture_drag_get_start_point(g, &x0, &y0) || view_plot_time_at(w, x0 + dx, &t)) return;
    w->app->cuts.sel[1] = t;
    view_plot_update(w->app);
}

static void plot_drag_end(GtkGestureDrag *g, double dx, double dy, gpointer user)
{
    view_win *w = user;
    view_app *a = w->app;
    plot_drag_update(g, dx, dy, user);
    if (!a->cuts.selecting) return;
    a->cuts.selecting = 0;
    double t0 = fmin(a->cuts.sel[0], a->cuts.sel[1]), t1 = fmax(a->cuts.sel[0], a->cuts.sel[1]);
    view_plot_update(a);
    if (fabs(dx) < 3 || !(t1 > t0)) return;
    char spec[64];
    snprintf(spec, sizeof spec, "%.6g:%.6g", t0, t1);
    int before = a->status;
    g_action_group_activate_action(G_ACTION_GROUP(a->gapp), "activation", g_variant_new_string(spec));
    a->status = before;
    if (a->vo->verbose > 0) fprintf(stderr, "thorax view: activation window %s dragged on the traces\n", spec);
    for (int k = 0; k < a->n_win; k++)
        if (a->win[k]->panel) {
            char s[32];
            snprintf(s, sizeof s, "%.6g", t0);
            gtk_editable_set_text(GTK_EDITABLE(a->win[k]->panel->t0), s);
            snprintf(s, sizeof s, "%.6g", t1);
            gtk_editable_set_text(GTK_EDITABLE(a->win[k]->panel->t1), s);
        }
}

/* ---- the panel's controls ---- */

/* An action from a control; its failure stays in the status line (the exit status is a script's). */
static void run(view_win *w, const char *name, GVariant *param)
{
    view_app *a = w->app;
    int before = a->status;
    g_action_group_activate_action(G_ACTION_GROUP(a->gapp), name, param);
    a->status = before;
}

static double entry_number(GtkWidget *e, int *ok)
{
    const char *s = gtk_editable_get_text(GTK_EDITABLE(e));
    char *end;
    double x = strtod(s, &end);
    while (*end == ' ') end++;
    *ok = s[0] && !*end && isfinite(x);
    return x;
}

static void on_iso_add(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    int ok;
    double x = entry_number(p->iso_entry, &ok);
    if (!ok) { view_set_info(p->w->app, "equipotential: type a value (the potentials' unit)"); return; }
    run(p->w, "isovalue-add", g_variant_new_double(x));
}

static void on_remove(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    const char *what = g_object_get_data(G_OBJECT(b), "action");
    if (!strcmp(what, "isovalue-remove")) run(p->w, what, g_variant_new_double(*(double *)g_object_get_data(G_OBJECT(b), "value")));
    else run(p->w, what, g_variant_new_int32(GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "index"))));
}

static void on_slice_add(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    static const char axes[] = "xyz";
    char spec[64];
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(p->slice_axis));
    snprintf(spec, sizeof spec, "%c=%.6g", axes[k < 3 ? k : 2], gtk_spin_button_get_value(GTK_SPIN_BUTTON(p->slice_pos)));
    run(p->w, "slice-add", g_variant_new_string(spec));
}

/* A new slice's position starts at the model's middle along the axis chosen. */
static void on_axis(GObject *dd, GParamSpec *ps, gpointer user)
{
    view_panel *p = user;
    double lo[3], hi[3];
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(dd));
    thx_picture_bounds(&p->w->app->d, lo, hi);
    if (k < 3) gtk_spin_button_set_value(GTK_SPIN_BUTTON(p->slice_pos), round(0.5 * (lo[k] + hi[k])));
}

static void on_slice_move(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    run(p->w, "slice-move", g_variant_new_double(atof(g_object_get_data(G_OBJECT(b), "mm"))));
}

static void on_slice_select(GtkCheckButton *b, gpointer user)
{
    view_panel *p = user;
    if (p->refreshing || !gtk_check_button_get_active(b)) return;
    run(p->w, "slice-select", g_variant_new_int32(GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "index"))));
}

static void on_tool(GObject *dd, GParamSpec *ps, gpointer user)
{
    view_panel *p = user;
    static const char *tools[] = {"none", "point", "rake"};
    if (p->refreshing) return;
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(dd));
    p->w->app->cuts.rake_n = gtk_spin_button_get_value_as_int(GTK_SPIN_BUTTON(p->rake_n));
    run(p->w, "seed-tool", g_variant_new_string(tools[k < 3 ? k : 0]));
}

static void on_rake_n(GtkSpinButton *s, gpointer user)
{
    view_panel *p = user;
    p->w->app->cuts.rake_n = gtk_spin_button_get_value_as_int(s);
}

static void on_density(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    run(p->w, "seed-density", g_variant_new_int32(gtk_spin_button_get_value_as_int(GTK_SPIN_BUTTON(p->density))));
}

static void on_range(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    int ok1, ok2;
    double lo = entry_number(p->lo, &ok1), hi = entry_number(p->hi, &ok2);
    if (!ok1 || !ok2) { view_set_info(p->w->app, "colour range: type both ends"); return; }
    char s[96];
    snprintf(s, sizeof s, "%.17g:%.17g", lo, hi);
    run(p->w, "range", g_variant_new_string(s));
}

static void on_range_auto(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    run(p->w, "range", g_variant_new_string("auto"));
}

static void on_window(GtkWidget *b, gpointer user)
{
    view_panel *p = user;
    int ok1, ok2;
    double t0 = entry_number(p->t0, &ok1), t1 = entry_number(p->t1, &ok2);
    if (!ok1 || !ok2) { view_set_info(p->w->app, "activation window: type T0 and T1 (the data's time unit)"); return; }
    char s[96];
    snprintf(s, sizeof s, "%.17g:%.17g", t0, t1);
    run(p->w, "activation", g_variant_new_string(s));
}

static GtkWidget *heading(GtkWidget *col, const char *text)
{
    GtkWidget *l = gtk_label_new(NULL);
    char *m = g_markup_printf_escaped("<b>%s</b>", text);
    gtk_label_set_markup(GTK_LABEL(l), m);
    g_free(m);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_widget_set_margin_top(l, 10);
    gtk_box_append(GTK_BOX(col), l);
    return l;
}

static GtkWidget *hint(GtkWidget *col, const char *text)
{
    GtkWidget *l = gtk_label_new(text);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_label_set_wrap(GTK_LABEL(l), TRUE);
    gtk_label_set_max_width_chars(GTK_LABEL(l), 34);
    gtk_widget_add_css_class(l, "dim-label");
    gtk_box_append(GTK_BOX(col), l);
    return l;
}

static GtkWidget *row(GtkWidget *col)
{
    GtkWidget *r = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(col), r);
    return r;
}

static GtkWidget *button(GtkWidget *r, const char *label, GCallback cb, view_panel *p)
{
    GtkWidget *b = gtk_button_new_with_label(label);
    g_signal_connect(b, "clicked", cb, p);
    gtk_box_append(GTK_BOX(r), b);
    return b;
}

static GtkWidget *entry(GtkWidget *r, const char *placeholder, int chars)
{
    GtkWidget *e = gtk_entry_new();
    gtk_entry_set_placeholder_text(GTK_ENTRY(e), placeholder);
    gtk_editable_set_width_chars(GTK_EDITABLE(e), chars);
    gtk_widget_set_hexpand(e, TRUE);
    gtk_box_append(GTK_BOX(r), e);
    return e;
}

/* Typing into the panel's fields: a key that types text is the field's, not the viewer's (`6` is a
 * digit there, not the inferior view): the window's first look at a key hands it to the field
 * (the application's keys would otherwise take it first). Keys with Control or Alt, F1-F12 and
 * Escape stay the viewer's. */
static gboolean on_key(GtkEventControllerKey *c, guint key, guint code, GdkModifierType mods, gpointer user)
{
    view_win *w = user;
    GtkWidget *f = gtk_root_get_focus(GTK_ROOT(w->window));
    if (!f || !GTK_IS_TEXT(f) || (mods & (GDK_CONTROL_MASK | GDK_ALT_MASK | GDK_SUPER_MASK | GDK_META_MASK)) ||
        (key >= GDK_KEY_F1 && key <= GDK_KEY_F12) || key == GDK_KEY_Escape)
        return FALSE;
    gtk_event_controller_key_forward(c, f);
    return TRUE;
}

/* Under -v, a field of the panel taking the keyboard is said (a test types once it has it). */
static void on_focus(GObject *win, GParamSpec *ps, gpointer user)
{
    view_win *w = user;
    GtkWidget *f = gtk_root_get_focus(GTK_ROOT(win));
    if (w->app->vo->verbose > 0 && f && GTK_IS_TEXT(f) && w->panel && gtk_widget_is_ancestor(f, w->panel->root))
        fprintf(stderr, "thorax view: window %d: a field of the panel has the keyboard\n", w->id);
}

void view_panel_attach(view_win *w, GtkWidget *box)
{
    view_panel *p = calloc(1, sizeof *p);
    if (!p) return;
    w->panel = p;
    p->w = w;
    if (w->app->cuts.rake_n < 2) { /* the first window: the tools' defaults */
        w->app->cuts.rake_n = 10;
        /* range auto goes back to the scope a fixed range replaced; fixed from the start: the series' */
        w->app->cuts.scope_auto = w->o.scope != THX_SCOPE_FIXED ? w->o.scope : THX_SCOPE_SERIES;
    }
    GtkWidget *col = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_widget_set_margin_start(col, 10);
    gtk_widget_set_margin_end(col, 10);
    gtk_widget_set_margin_bottom(col, 10);
    p->note = hint(col, "");
    gtk_widget_set_margin_top(p->note, 10);
    for (int k = 0; k < 3; k++) p->cut_boxes[k] = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);

    GtkWidget *c = p->cut_boxes[0], *r;
    heading(c, "Equipotentials");
    p->iso_list = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
    gtk_box_append(GTK_BOX(c), p->iso_list);
    r = row(c);
    p->iso_entry = entry(r, "value", 8);
    g_signal_connect(p->iso_entry, "activate", G_CALLBACK(on_iso_add), p);
    button(r, "Add", G_CALLBACK(on_iso_add), p);
    hint(c, "Drag a value's mark on the colour bar to move it.");

    c = p->cut_boxes[1];
    heading(c, "Slices");
    p->slice_list = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
    gtk_box_append(GTK_BOX(c), p->slice_list);
    r = row(c);
    static const char *axes[] = {"x =", "y =", "z =", NULL};
    p->slice_axis = gtk_drop_down_new_from_strings(axes);
    gtk_drop_down_set_selected(GTK_DROP_DOWN(p->slice_axis), 2);
    g_signal_connect(p->slice_axis, "notify::selected", G_CALLBACK(on_axis), p);
    gtk_box_append(GTK_BOX(r), p->slice_axis);
    p->slice_pos = gtk_spin_button_new_with_range(-10000, 10000, 1);
    gtk_spin_button_set_digits(GTK_SPIN_BUTTON(p->slice_pos), 1);
    gtk_editable_set_width_chars(GTK_EDITABLE(p->slice_pos), 6);
    gtk_widget_set_hexpand(p->slice_pos, TRUE);
    gtk_box_append(GTK_BOX(r), p->slice_pos);
    button(r, "Add", G_CALLBACK(on_slice_add), p);
    on_axis(G_OBJECT(p->slice_axis), NULL, p);
    hint(c, "Move the selected slice along its normal (mm), or Ctrl+Shift+drag it in the view:");
    r = row(c);
    static const char *steps[] = {"-10", "-1", "+1", "+10"};
    for (int k = 0; k < 4; k++) {
        GtkWidget *b = button(r, steps[k], G_CALLBACK(on_slice_move), p);
        gtk_widget_set_hexpand(b, TRUE);
        g_object_set_data(G_OBJECT(b), "mm", (gpointer)steps[k]);
    }

    c = p->cut_boxes[2];
    heading(c, "Streamline seeds");
    r = row(c);
    gtk_box_append(GTK_BOX(r), gtk_label_new("Click seeds"));
    static const char *tools[] = {"nothing", "a point", "a rake", NULL};
    p->seed_tool = gtk_drop_down_new_from_strings(tools);
    gtk_widget_set_hexpand(p->seed_tool, TRUE);
    g_signal_connect(p->seed_tool, "notify::selected", G_CALLBACK(on_tool), p);
    gtk_box_append(GTK_BOX(r), p->seed_tool);
    r = row(c);
    gtk_box_append(GTK_BOX(r), gtk_label_new("Rake seeds"));
    p->rake_n = gtk_spin_button_new_with_range(2, 500, 1);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(p->rake_n), w->app->cuts.rake_n);
    g_signal_connect(p->rake_n, "value-changed", G_CALLBACK(on_rake_n), p);
    gtk_box_append(GTK_BOX(r), p->rake_n);
    r = row(c);
    gtk_box_append(GTK_BOX(r), gtk_label_new("Density"));
    p->density = gtk_spin_button_new_with_range(0, 100000, 10);
    gtk_widget_set_hexpand(p->density, TRUE);
    gtk_box_append(GTK_BOX(r), p->density);
    button(r, "Set", G_CALLBACK(on_density), p);
    p->seed_list = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
    gtk_box_append(GTK_BOX(c), p->seed_list);
    for (int k = 0; k < 3; k++) gtk_box_append(GTK_BOX(col), p->cut_boxes[k]);

    heading(col, "Colour range");
    p->range_note = hint(col, "");
    r = row(col);
    p->lo = entry(r, "low", 6);
    p->hi = entry(r, "high", 6);
    g_signal_connect(p->hi, "activate", G_CALLBACK(on_range), p);
    r = row(col);
    button(r, "Fix", G_CALLBACK(on_range), p);
    button(r, "Automatic", G_CALLBACK(on_range_auto), p);
    hint(col, "Drag the colour bar's ends to change it.");

    heading(col, "Activation window");
    r = row(col);
    p->t0 = entry(r, "T0", 6);
    p->t1 = entry(r, "T1", 6);
    g_signal_connect(p->t1, "activate", G_CALLBACK(on_window), p);
    button(r, "Map", G_CALLBACK(on_window), p);
    hint(col, "Of the current surface; or drag across the traces (a click on the model adds one).");

    p->root = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(p->root), GTK_POLICY_NEVER, GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(p->root), col);
    gtk_widget_set_size_request(p->root, PANEL_W, -1);
    gtk_widget_set_visible(p->root, FALSE);
    gtk_box_append(GTK_BOX(box), p->root);

    /* the traces at their own size under the drawing area (a GtkPicture given more room scales its
       image up, blurred, and centres it under the drawing area and the panel) */
    gtk_widget_set_halign(w->plot, GTK_ALIGN_START);
    gtk_widget_set_valign(w->plot, GTK_ALIGN_START);
    g_signal_connect(w->window, "notify::focus-widget", G_CALLBACK(on_focus), w);
    GtkEventController *keys = gtk_event_controller_key_new();
    gtk_event_controller_set_propagation_phase(keys, GTK_PHASE_CAPTURE);
    g_signal_connect(keys, "key-pressed", G_CALLBACK(on_key), w);
    gtk_widget_add_controller(w->window, keys);
    GtkGesture *drag = gtk_gesture_drag_new();
    g_signal_connect(drag, "drag-begin", G_CALLBACK(plot_drag_begin), w);
    g_signal_connect(drag, "drag-update", G_CALLBACK(plot_drag_update), w);
    g_signal_connect(drag, "drag-end", G_CALLBACK(plot_drag_end), w);
    gtk_widget_add_controller(w->plot, GTK_EVENT_CONTROLLER(drag));
}

static void clear(GtkWidget *box)
{
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(box))) gtk_box_remove(GTK_BOX(box), c);
}

/* A list's row: its text and a button removing it (action `what` with the value or index). */
static GtkWidget *list_row(view_panel *p, GtkWidget *list, GtkWidget *lead, const char *what)
{
    GtkWidget *r = row(list);
    gtk_widget_set_hexpand(lead, TRUE);
    if (GTK_IS_LABEL(lead)) {
        gtk_label_set_xalign(GTK_LABEL(lead), 0);
        gtk_label_set_ellipsize(GTK_LABEL(lead), PANGO_ELLIPSIZE_MIDDLE);
    }
    gtk_box_append(GTK_BOX(r), lead);
    GtkWidget *b = button(r, "Remove", G_CALLBACK(on_remove), p);
    g_object_set_data(G_OBJECT(b), "action", (gpointer)what);
    return b;
}

static void refresh_one(view_panel *p)
{
    view_app *a = p->w->app;
    const thx_picture_opts *o = &p->w->o;
    p->refreshing = 1;
    int vol = a->d.volume || o->solution; /* (read at the first cut) */
    gtk_label_set_text(GTK_LABEL(p->note), vol ? "" : "The equipotentials, slices and streamlines need a solution with "
                                                     "volume potentials (--solution DIR; thorax forward --volume makes "
                                                     "them).");
    gtk_widget_set_visible(p->note, !vol);
    for (int k = 0; k < 3; k++) gtk_widget_set_sensitive(p->cut_boxes[k], vol);
    clear(p->iso_list);
    double v[MAX_ISO];
    int n = iso_values(a, v, MAX_ISO);
    for (int k = 0; k < n; k++) {
        char s[64];
        snprintf(s, sizeof s, "%.6g %s", v[k], a->d.volume && a->d.volume->unit[0] ? a->d.volume->unit : "");
        GtkWidget *b = list_row(p, p->iso_list, gtk_label_new(s), "isovalue-remove");
        double *keep = g_new(double, 1);
        *keep = v[k];
        g_object_set_data_full(G_OBJECT(b), "value", keep, g_free);
    }
    if (!n) hint(p->iso_list, "none");
    clear(p->slice_list);
    GtkWidget *first = NULL;
    for (int k = 0; k < o->n_slices; k++) {
        char s[128];
        snprintf(s, sizeof s, "%d.  %s", k + 1, o->slices[k]);
        GtkWidget *c = gtk_check_button_new_with_label(s);
        if (first) gtk_check_button_set_group(GTK_CHECK_BUTTON(c), GTK_CHECK_BUTTON(first));
        else first = c;
        gtk_check_button_set_active(GTK_CHECK_BUTTON(c), k == a->cuts.slice_sel);
        g_object_set_data(G_OBJECT(c), "index", GINT_TO_POINTER(k + 1));
        g_signal_connect(c, "toggled", G_CALLBACK(on_slice_select), p);
        GtkWidget *b = list_row(p, p->slice_list, c, "slice-remove");
        g_object_set_data(G_OBJECT(b), "index", GINT_TO_POINTER(k + 1));
    }
    if (!o->n_slices) hint(p->slice_list, "none");
    clear(p->seed_list);
    int density = 0;
    for (int k = 0; k < o->n_streamlines; k++) {
        GtkWidget *l = gtk_label_new(o->streamlines[k]);
        gtk_widget_set_tooltip_text(l, o->streamlines[k]);
        GtkWidget *b = list_row(p, p->seed_list, l, "seed-remove");
        g_object_set_data(G_OBJECT(b), "index", GINT_TO_POINTER(k + 1));
        if (!strncmp(o->streamlines[k], "density:", 8)) density = atoi(o->streamlines[k] + 8);
    }
    if (!o->n_streamlines) hint(p->seed_list, "no seeds");
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(p->density), density);
    gtk_drop_down_set_selected(GTK_DROP_DOWN(p->seed_tool), (guint)a->cuts.seed_tool);
    char s[160];
    if (o->scope == THX_SCOPE_FIXED) {
        snprintf(s, sizeof s, "Fixed: %.6g to %.6g.", o->lo, o->hi);
        char t[64];
        snprintf(t, sizeof t, "%.6g", o->lo);
        gtk_editable_set_text(GTK_EDITABLE(p->lo), t);
        snprintf(t, sizeof t, "%.6g", o->hi);
        gtk_editable_set_text(GTK_EDITABLE(p->hi), t);
    } else {
        snprintf(s, sizeof s, "Automatic: the data's range over the scope %s.", scope_words[o->scope]);
    }
    gtk_label_set_text(GTK_LABEL(p->range_note), s);
    p->refreshing = 0;
}

void view_panel_refresh(view_app *a)
{
    for (int k = 0; k < a->n_win; k++)
        if (a->win[k]->panel && gtk_widget_get_visible(a->win[k]->panel->root)) refresh_one(a->win[k]->panel);
}

void view_panel_free(view_app *a)
{
    for (int k = 0; k < a->n_win; k++) {
        free(a->win[k]->panel);
        a->win[k]->panel = NULL;
    }
}
