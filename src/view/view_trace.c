/*
 * Tracing a scan in the viewer (issue 26 items 1-3 and 6; paper 3.1 "each image was digitized by hand,
 * surface by surface, into closed loops"): the session of thorax/digitizer/session.h on the picture's
 * scan, the actions that feed it lines (clicks and keys become lines first, so that a script of the
 * same lines does the same), each traced surface built again through the library's spline, lacing
 * and caps as soon as its loops change and shown in the 3D view with `thorax check`'s verdict, and
 * the outputs: the contour file, the model, the label map and the session to go on with.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "thorax/check/check.h"
#include "thorax/core/fileio.h"
#include "thorax/geom/surfaces.h"
#include "thorax/io/contours_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/phantom/voxelize.h"
#include "view/view_trace.h"

static const char *default_names[] = {"torso:outer", "fat:fat", "muscle:muscle", "lungs:lung", "heart:heart"};

static double now_ms(void) { return (double)g_get_monotonic_time() / 1000.0; }

/* The failing colour of a surface whose model fails the check, and the role's own otherwise. */
static void set_look(view_app *a, int model_index, int ok)
{
    const char *name = a->d.m->surf[model_index]->name;
    for (int k = 0; k < a->n_win; k++) {
        thx_picture_look *l = view_look_of(a->win[k], name);
        if (!l) continue;
        l->have_color = !ok;
        if (!ok) {
            l->color[0] = 0.90f;
            l->color[1] = 0.15f;
            l->color[2] = 0.15f;
        }
    }
}

/* The model surface of session surface i, made (empty) when new. */
static int model_surface(view_app *a, size_t i)
{
    view_tracing *t = a->trace;
    if (t->surf[i].model_index >= 0) return t->surf[i].model_index;
    thx_model *m = a->d.m;
    if (m->n_surfaces >= THX_PICTURE_SURFACES) return -1;
    thx_surface *s = NULL;
    if (thx_surface_create(a->ctx, thx_dig_surface_name(t->s, i), thx_dig_surface_role(t->s, i), &s) != THX_OK) return -1;
    if (thx_model_add_surface(a->ctx, m, &s) != THX_OK) { thx_surface_destroy(&s); return -1; }
    t->surf[i].model_index = (int)m->n_surfaces - 1;
    return t->surf[i].model_index;
}

/* FNV-1a over what a surface is built from: its closed loops, plane by plane. */
static unsigned long long contours_hash(const thx_contours *c)
{
    unsigned long long h = 1469598103934665603ULL;
    for (size_t s = 0; c && s < c->n_surfaces; s++)
        for (size_t j = 0; j < c->surf[s].n_layers; j++) {
            const thx_contour_layer *L = &c->surf[s].layers[j];
            const unsigned char *z = (const unsigned char *)&L->z;
            for (size_t b = 0; b < sizeof L->z; b++) h = (h ^ z[b]) * 1099511628211ULL;
            for (size_t l = 0; l < L->n_loops; l++) {
                const unsigned char *p = (const unsigned char *)L->loops[l].p;
                for (size_t b = 0; b < L->loops[l].n * sizeof *L->loops[l].p; b++) h = (h ^ p[b]) * 1099511628211ULL;
                h = (h ^ 0xff) * 1099511628211ULL;
            }
        }
    return h;
}

/* Builds session surface i from its loops (thx_surface_build: the spline, lacing and caps of thorax
 * surfaces) and checks it; the model shows the result (or nothing, with the reason, when it cannot be
 * built). */
static void build_one(view_app *a, size_t i)
{
    view_tracing *t = a->trace;
    view_trace_surf *ts = &t->surf[i];
    int mi = model_surface(a, i);
    if (mi < 0) return;
    double t0 = now_ms();
    thx_contours *c = NULL;
    thx_surface *s = NULL;
    thx_vec3 interior;
    const char *name = thx_dig_surface_name(t->s, i);
    thx_status st = thx_dig_contours(a->ctx, t->s, (int)i, &c, NULL);
    unsigned long long hash = st == THX_OK ? contours_hash(c) : 0;
    int again = ts->built && hash == ts->built_hash;
    ts->built_gen = thx_dig_surface_gen(t->s, i);
    ts->built = 1;
    if (again) { /* only open loops changed: nothing to build again */
        thx_contours_destroy(&c);
        return;
    }
    ts->built_hash = hash;
    ts->ok = 0;
    if (st != THX_OK) {
        snprintf(ts->verdict, sizeof ts->verdict, "nothing closed yet");
    } else if (c->surf[0].n_layers < 2) {
        snprintf(ts->verdict, sizeof ts->verdict, "one plane traced (a surface needs two)");
    } else {
        thx_surfaces_opts so;
        thx_surfaces_opts_default(&so);
        st = thx_surface_build(a->ctx, c, 0, &so, &s, &interior, NULL);
        if (st != THX_OK) {
            snprintf(ts->verdict, sizeof ts->verdict, "not built: %s", thx_ctx_message(a->ctx));
        } else {
            thx_surface_report rep;
            memset(&rep, 0, sizeof rep);
            thx_check_opts co;
            thx_check_opts_default(&co);
            st = thx_surface_check(a->ctx, s, &interior, &co, &rep);
            ts->ok = st == THX_OK;
            if (ts->ok)
                snprintf(ts->verdict, sizeof ts->verdict, "passes thorax check: %zu planes, %zu nodes, %zu triangles",
                         c->surf[0].n_layers, s->n_nodes, s->n_tris);
            else
                snprintf(ts->verdict, sizeof ts->verdict, "fails thorax check: %s",
                         rep.n_reasons ? rep.reasons[0] : thx_ctx_message(a->ctx));
            thx_surface_report_free(&rep);
        }
    }
    thx_contours_destroy(&c);
    thx_model *m = a->d.m;
    if (!s) thx_surface_create(a->ctx, name, thx_dig_surface_role(t->s, i), &s);
    if (s) {
        snprintf(s->name, sizeof s->name, "%s", name);
        s->role = thx_dig_surface_role(t->s, i);
        thx_surface_destroy(&m->surf[mi]);
        m->surf[mi] = s;
    }
    set_look(a, mi, ts->ok || !m->surf[mi]->n_tris);
    ts->build_ms = now_ms() - t0;
    /* each verdict on standard output too, for scripts (and the tests) */
    printf("trace: %s: %s (%.0f ms)\n", name, ts->verdict, ts->build_ms);
    fflush(stdout);
}

void view_trace_rebuild_now(view_app *a)
{
    view_tracing *t = a->trace;
    if (!t) return;
    if (t->rebuild_id) { g_source_remove(t->rebuild_id); t->rebuild_id = 0; }
    int any = 0;
    for (size_t i = 0; i < thx_dig_n_surfaces(t->s) && i < VIEW_TRACE_MAX; i++)
        if (!t->surf[i].built || t->surf[i].built_gen != thx_dig_surface_gen(t->s, i)) {
            build_one(a, i);
            any = 1;
        }
    if (!any) return;
    thx_picture_geometry_changed(&a->d);
    view_pick_prepare(a);
    view_redraw_all(a);
    view_slice_redraw(a);
}

static gboolean rebuild_idle(gpointer user)
{
    view_app *a = user;
    a->trace->rebuild_id = 0;
    view_trace_rebuild_now(a);
    return G_SOURCE_REMOVE;
}

/* The 3D view's scan plane on the traced plane. */
static void follow_plane(view_app *a)
{
    view_tracing *t = a->trace;
    if (!a->d.scan || a->d.n_scan_planes < 1) return;
    a->d.scan_axis[0] = 'z';
    a->d.scan_pos[0] = thx_dig_plane_z(t->s, thx_dig_current_plane(t->s));
    t->cursor[2] = a->d.scan_pos[0];
}

static void describe(view_app *a)
{
    view_tracing *t = a->trace;
    int cur = thx_dig_current_surface(t->s);
    long k = thx_dig_current_plane(t->s);
    static const char *tools[] = {"points", "livewire", "region"};
    view_set_info(a, "tracing %s on z=%.2f mm (plane %ld of %ld), %s%s%s", cur >= 0 ? thx_dig_surface_name(t->s, (size_t)cur) : "-",
                  thx_dig_plane_z(t->s, k), k + 1, thx_dig_n_planes(t->s), tools[t->tool],
                  cur >= 0 && t->surf[cur].built ? "; " : "", cur >= 0 && t->surf[cur].built ? t->surf[cur].verdict : "");
}

int view_trace_line(view_app *a, const char *line)
{
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace: not tracing (thorax view --image IMG, without a model or with --trace-surface)"); a->status = 1; return -1; }
    double t0 = now_ms();
    if (thx_dig_apply(a->ctx, t->s, line) != THX_OK) {
        view_set_info(a, "%s", thx_ctx_message(a->ctx));
        a->status = 1;
        return -1;
    }
    if (a->vo->verbose > 0) fprintf(stderr, "thorax view: trace %s (%.1f ms)\n", line, now_ms() - t0);
    for (size_t i = 0; i < thx_dig_n_surfaces(t->s) && i < VIEW_TRACE_MAX; i++) model_surface(a, i);
    free(t->preview);
    t->preview = NULL;
    t->n_preview = 0;
    double z_before = a->d.n_scan_planes ? a->d.scan_pos[0] : NAN;
    follow_plane(a);
    if (!t->rebuild_id) t->rebuild_id = g_idle_add(rebuild_idle, a);
    describe(a);
    /* the 3D view changes with the plane, or when a surface is built again (rebuild_idle draws it) */
    if (!(a->d.n_scan_planes && a->d.scan_pos[0] == z_before)) view_redraw_all(a);
    view_slice_redraw(a);
    return 0;
}

/* ---- outputs ---- */

/* dir/name into buf; -1 when it does not fit. */
static int join(char *buf, size_t size, const char *dir, const char *name)
{
    return snprintf(buf, size, "%s/%s", dir, name) < (int)size ? 0 : -1;
}

/* The session as a script of the viewer: the image and the window, the contour file it started from,
 * then every line of the log (`thorax view --script FILE` goes on from there). */
static thx_status write_session(view_app *a, const char *path)
{
    view_tracing *t = a->trace;
    static const char marker[] = "# thorax view: a tracing session";
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(a->ctx, path, marker, sizeof marker - 1, NULL, 0, &af));
    char img[PATH_MAX];
    const char *ip = a->vo->pic.image;
    if (!realpath(ip, img)) snprintf(img, sizeof img, "%s", ip);
    fprintf(af.f, "%s (resume: thorax view --script %s)\n", marker, path);
    fprintf(af.f, "--image %s\n--image-window %.9g\n--image-level %.9g\n--size %dx%d\n", img, a->d.window, a->d.level,
            a->vo->win_w, a->vo->win_h);
    for (int k = 0; k < t->n_names; k++) fprintf(af.f, "--trace-surface %s\n", t->names[k]);
    if (t->start[0]) fprintf(af.f, "--contours %s\n", t->start);
    const char *const *lines;
    size_t n = thx_dig_log(t->s, &lines);
    for (size_t i = 0; i < n; i++) fprintf(af.f, "action trace %s\n", lines[i]);
    return thx_atomic_commit(a->ctx, &af);
}

/* The label map of the model's surfaces on the image's grid (thx_voxelize: each voxel the innermost
 * surface holding its centre). */
static thx_status write_labels(view_app *a, const thx_model *m, const char *path)
{
    const thx_image *img = a->trace->img;
    thx_image lab;
    THX_CHECK(thx_image_alloc(a->ctx, img->n, &lab));
    memcpy(lab.spacing, img->spacing, sizeof lab.spacing);
    memcpy(lab.origin, img->origin, sizeof lab.origin);
    memcpy(lab.dir, img->dir, sizeof lab.dir);
    lab.integral = 1;
    thx_voxelize_opts vo;
    thx_voxelize_opts_default(&vo);
    vo.sub = 1;
    thx_status st = thx_voxelize(a->ctx, (const thx_surface *const *)m->surf, m->n_surfaces, &vo, &lab, NULL);
    if (st == THX_OK) st = thx_image_write(a->ctx, &lab, path, NULL);
    thx_image_free(&lab);
    return st;
}

static int save(view_app *a, const char *dir)
{
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace-save: not tracing"); a->status = 1; return -1; }
    if (!dir[0]) { view_set_info(a, "trace-save: give a directory"); a->status = 1; return -1; }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        view_set_info(a, "trace-save %s: %s", dir, strerror(errno));
        a->status = 1;
        return -1;
    }
    char p_contours[PATH_MAX], p_session[PATH_MAX], p_model[PATH_MAX], p_labels[PATH_MAX];
    if (join(p_contours, sizeof p_contours, dir, "contours.txt") || join(p_session, sizeof p_session, dir, "session.txt") ||
        join(p_model, sizeof p_model, dir, "model") || join(p_labels, sizeof p_labels, dir, "labels.nii.gz")) {
        view_set_info(a, "trace-save: the directory's name is too long");
        a->status = 1;
        return -1;
    }
    thx_contours *c = NULL;
    size_t skipped = 0;
    thx_status st = thx_dig_contours(a->ctx, t->s, -1, &c, &skipped);
    /* the image by its absolute path: the same file whichever directory the session ran in */
    char img[PATH_MAX], comment[PATH_MAX + 64];
    if (!realpath(a->vo->pic.image, img)) snprintf(img, sizeof img, "%s", a->vo->pic.image);
    snprintf(comment, sizeof comment, "traced by hand in thorax view on %s", img);
    if (st == THX_OK && strlen(img) < sizeof c->image) memcpy(c->image, img, strlen(img) + 1);
    if (st == THX_OK) st = thx_contours_write(a->ctx, c, p_contours, comment);
    if (st == THX_OK) st = write_session(a, p_session);
    if (st != THX_OK) {
        view_set_info(a, "trace-save %s: %s", dir, thx_ctx_message(a->ctx));
        a->status = 1;
        thx_contours_destroy(&c);
        return -1;
    }
    /* the model and its label map only when the model passes the check (a command never writes what
       its own check would fail) */
    thx_model *m = NULL;
    thx_surfaces_opts so;
    thx_surfaces_opts_default(&so);
    char why[512] = "";
    st = thx_surfaces_build(a->ctx, c, &so, &m, NULL, NULL);
    thx_model_report *rep = NULL;
    if (st == THX_OK) {
        thx_check_opts co;
        thx_check_opts_default(&co);
        st = thx_model_check(a->ctx, m, &co, &rep);
    }
    if (st != THX_OK) snprintf(why, sizeof why, "%s", thx_ctx_message(a->ctx));
    thx_model_report_destroy(&rep);
    if (st == THX_OK) st = thx_model_write(a->ctx, m, p_model);
    if (st == THX_OK) st = write_labels(a, m, p_labels);
    if (st != THX_OK && !why[0]) snprintf(why, sizeof why, "%s", thx_ctx_message(a->ctx));
    thx_model_destroy(&m);
    size_t ns = c->n_surfaces;
    thx_contours_destroy(&c);
    if (why[0]) {
        view_set_info(a, "trace-save %s: contours.txt and session.txt written; the model and label map not: %s", dir, why);
        fprintf(stdout, "trace-save %s: model not written: %s\n", dir, why);
    } else {
        view_set_info(a, "trace-save %s: contours.txt (%zu surfaces%s), model/, labels.nii.gz, session.txt", dir, ns,
                      skipped ? ", open loops left out" : "");
        fprintf(stdout, "trace-save %s: contours.txt, model/, labels.nii.gz, session.txt\n", dir);
    }
    fflush(stdout);
    return 0;
}

/* ---- actions ---- */

static void do_trace(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_trace_line(user, g_variant_get_string(v, NULL));
}

static void do_save(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    save(user, g_variant_get_string(v, NULL));
}

static void do_pane_png(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_app *a = user;
    const char *path = g_variant_get_string(v, NULL);
    if (!a->trace) { view_set_info(a, "trace-screenshot: not tracing"); a->status = 1; return; }
    view_trace_rebuild_now(a);
    if (!*path || view_slice_png(a, path)) { view_set_info(a, "trace-screenshot '%s': not written", path); a->status = 1; return; }
    view_set_info(a, "saved the slice pane as %s", path);
}

static int by_value(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Benchmarks (bench/digitize.sh): N plane steps, each followed by the pane drawn (offscreen, its size):
 * the plane sampled, its grey levels, the loops; or N edits of the current surface's first point
 * (1 mm along x and back), each followed by that surface built again and checked. Medians printed. */
static void do_bench(GSimpleAction *act, GVariant *v, gpointer user)
{
    view_app *a = user;
    view_tracing *t = a->trace;
    const char *name = g_action_get_name(G_ACTION(act));
    int n = g_variant_get_int32(v);
    if (!t || n < 1 || n > 100000) { view_set_info(a, "%s: tracing, and 1 to 100000 steps", name); a->status = 1; return; }
    double *ms = calloc((size_t)n, sizeof *ms);
    if (!ms) return;
    int edit = !strcmp(name, "bench-trace-edit"), dir = 1, done = 0;
    for (int i = 0; i < n; i++) {
        double t0 = now_ms();
        char line[160];
        if (edit) {
            int cur = thx_dig_current_surface(t->s);
            const thx_dig_loop *l;
            if (cur < 0 || !thx_dig_loops(t->s, (size_t)cur, thx_dig_current_plane(t->s), &l)) {
                view_set_info(a, "%s: no loop of the current surface on this plane", name);
                a->status = 1;
                break;
            }
            snprintf(line, sizeof line, "move 1 1 %.2f %.2f", l[0].p[0].x + (i % 2 ? -1.0 : 1.0), l[0].p[0].y);
            if (view_trace_line(a, line)) break;
            view_trace_rebuild_now(a);
        } else {
            if (thx_dig_current_plane(t->s) + dir < 0 || thx_dig_current_plane(t->s) + dir >= thx_dig_n_planes(t->s)) dir = -dir;
            snprintf(line, sizeof line, "plane %+d", dir);
            if (view_trace_line(a, line)) break;
            if (t->area) {
                int W = gtk_widget_get_width(t->area), H = gtk_widget_get_height(t->area);
                cairo_surface_t *cs = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W > 0 ? W : 560, H > 0 ? H : 480);
                cairo_t *cr = cairo_create(cs);
                view_slice_draw(a, cr, W > 0 ? W : 560, H > 0 ? H : 480);
                cairo_destroy(cr);
                cairo_surface_destroy(cs);
            }
        }
        ms[done++] = now_ms() - t0;
    }
    if (done) {
        qsort(ms, (size_t)done, sizeof *ms, by_value);
        int cur = thx_dig_current_surface(t->s);
        const thx_image_slice *sl = thx_dig_slice(a->ctx, t->s);
        printf("%s %d steps: median %.2f ms, min %.2f, max %.2f (%s; plane %zux%zu)\n", name, done, ms[done / 2], ms[0],
               ms[done - 1], edit && cur >= 0 ? t->surf[cur].verdict : "plane stepped, pane drawn", sl ? sl->w : 0, sl ? sl->h : 0);
        fflush(stdout);
    }
    free(ms);
}

static void do_tool(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace-tool: not tracing"); a->status = 1; return; }
    const char *s = g_variant_get_string(v, NULL);
    view_trace_tool want = !strcmp(s, "points") ? VIEW_TOOL_POINTS : !strcmp(s, "livewire") ? VIEW_TOOL_LIVEWIRE
                         : !strcmp(s, "region") ? VIEW_TOOL_REGION : !strcmp(s, "next") ? (view_trace_tool)((t->tool + 1) % 3)
                         : (view_trace_tool)-1;
    if ((int)want < 0) { view_set_info(a, "trace-tool '%s': points, livewire, region or next", s); a->status = 1; return; }
    t->tool = want;
    /* the session's own tool joins points (the region tool leaves it as it is) */
    if (want != VIEW_TOOL_REGION) view_trace_line(a, want == VIEW_TOOL_LIVEWIRE ? "tool livewire" : "tool points");
    describe(a);
    view_slice_redraw(a);
}

static void do_surface_next(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    (void)v;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (!t || !t->n_names) { view_set_info(a, "trace-surface-next: not tracing"); a->status = 1; return; }
    int cur = thx_dig_current_surface(t->s), next = 0;
    if (cur >= 0) {
        const char *name = thx_dig_surface_name(t->s, (size_t)cur);
        for (int k = 0; k < t->n_names; k++) {
            size_t len = strcspn(t->names[k], ":");
            if (strlen(name) == len && !strncmp(t->names[k], name, len)) next = (k + 1) % t->n_names;
        }
    }
    char line[128];
    snprintf(line, sizeof line, "surface %s", t->names[next]);
    view_trace_line(a, line);
}

/* Backspace: the open loop's last point removed. */
static void do_backspace(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    (void)v;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace-backspace: not tracing"); a->status = 1; return; }
    int cur = thx_dig_current_surface(t->s);
    const thx_dig_loop *l;
    size_t n = cur >= 0 ? thx_dig_loops(t->s, (size_t)cur, thx_dig_current_plane(t->s), &l) : 0;
    for (size_t i = 0; i < n; i++)
        if (!l[i].closed) {
            char line[64];
            snprintf(line, sizeof line, "delete %zu %zu", i + 1, l[i].n);
            view_trace_line(a, line);
            return;
        }
    view_set_info(a, "trace-backspace: no open loop on this plane");
}

static void do_threshold(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace-threshold: not tracing"); a->status = 1; return; }
    const char *s = g_variant_get_string(v, NULL);
    double lo, hi;
    int used = 0;
    if (!*s) {
        t->have_thr = 0;
    } else if (sscanf(s, "%lf:%lf%n", &lo, &hi, &used) == 2 && !s[used] && lo <= hi && isfinite(lo) && isfinite(hi)) {
        t->thr_lo = lo;
        t->thr_hi = hi;
        t->have_thr = 1;
    } else {
        view_set_info(a, "trace-threshold '%s': LO:HI (LO <= HI), or empty for the grey window shown", s);
        a->status = 1;
        return;
    }
    view_set_info(a, "region tool: values from %g to %g", t->have_thr ? t->thr_lo : a->d.level - 0.5 * a->d.window,
                  t->have_thr ? t->thr_hi : a->d.level + 0.5 * a->d.window);
}

static void do_orient(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_app *a = user;
    view_tracing *t = a->trace;
    if (!t) { view_set_info(a, "trace-view: not tracing"); a->status = 1; return; }
    const char *s = g_variant_get_string(v, NULL);
    char o = !strcmp(s, "axial") ? 'z' : !strcmp(s, "coronal") ? 'y' : !strcmp(s, "sagittal") ? 'x' : 0;
    if (!o) { view_set_info(a, "trace-view '%s': axial, coronal or sagittal", s); a->status = 1; return; }
    t->orient = o;
    t->zoom = 1;
    t->pan[0] = t->pan[1] = 0;
    view_set_info(a, "the slice pane shows %s planes%s", s, o == 'z' ? "" : " (loops are traced on axial planes: a click picks the axial plane)");
    view_slice_redraw(a);
}

/* Window and level presets (CT in Hounsfield units; MR from the image's histogram). */
static void do_preset(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)act;
    view_app *a = user;
    const char *s = g_variant_get_string(v, NULL);
    if (!a->d.scan) { view_set_info(a, "image-preset: no image (--image IMG)"); a->status = 1; return; }
    if (!strcmp(s, "soft")) { a->d.window = 400; a->d.level = 40; }
    else if (!strcmp(s, "lung")) { a->d.window = 1500; a->d.level = -600; }
    else if (!strcmp(s, "bone")) { a->d.window = 2000; a->d.level = 500; }
    else if (!strcmp(s, "auto")) {
        const thx_image *img = thx_picture_scan_image(&a->d);
        thx_image_window_default(img, &a->d.window, &a->d.level);
    } else { view_set_info(a, "image-preset '%s': soft, lung, bone (CT) or auto (the histogram's 1st-99th percentile)", s); a->status = 1; return; }
    view_set_info(a, "window %g, level %g (%s)", a->d.window, a->d.level, s);
    view_redraw_all(a);
    view_slice_redraw(a);
}

typedef struct {
    const char *name, *param;
    GCallback fn;
    const char *keys[3];
    const char *target;
    const char *help;
} trace_action;

static const trace_action TRACE_ACTIONS[] = {
    {"trace", "s", G_CALLBACK(do_trace), {"Return", "KP_Enter"}, "'close'",
     "a tracing line (surface, plane, tool, point, close, move, insert, delete, region, copy, interpolate, undo, redo); "
     "Return closes the loop"},
    {"trace-copy-up", NULL, NULL, {"j"}, NULL, "copy the surface's loops to the next plane up and snap them to its edges"},
    {"trace-copy-down", NULL, NULL, {"<Shift>j"}, NULL, "the same one plane down"},
    {"trace-interpolate", NULL, NULL, {"h"}, NULL, "fill the planes between traced planes (shape-based interpolation)"},
    {"trace-tool", "s", G_CALLBACK(do_tool), {"l"}, "'next'", "the tool: points, livewire, region (l: the next)"},
    {"trace-surface-next", NULL, G_CALLBACK(do_surface_next), {"Tab"}, NULL, "trace the next surface (torso, fat, ...)"},
    {"trace-backspace", NULL, G_CALLBACK(do_backspace), {"BackSpace"}, NULL, "remove the open loop's last point"},
    {"trace-threshold", "s", G_CALLBACK(do_threshold), {NULL}, NULL, "the region tool's values LO:HI (empty: the grey window shown)"},
    {"trace-view", "s", G_CALLBACK(do_orient), {"F2"}, "'axial'", "the slice pane's planes: axial (F2), coronal (F3), sagittal (F4)"},
    {"trace-view-coronal", NULL, NULL, {"F3"}, NULL, "coronal planes in the slice pane"},
    {"trace-view-sagittal", NULL, NULL, {"F4"}, NULL, "sagittal planes in the slice pane"},
    {"image-preset", "s", G_CALLBACK(do_preset), {"F5"}, "'soft'", "window and level: soft (F5), lung (F6), bone (F7), auto (F8)"},
    {"image-preset-lung", NULL, NULL, {"F6"}, NULL, "lung window (1500 / -600)"},
    {"image-preset-bone", NULL, NULL, {"F7"}, NULL, "bone window (2000 / 500)"},
    {"image-preset-auto", NULL, NULL, {"F8"}, NULL, "the image's 1st to 99th percentile"},
    {"trace-save", "s", G_CALLBACK(do_save), {NULL}, NULL, "write DIR/contours.txt, model/, labels.nii.gz and session.txt"},
    {"trace-screenshot", "s", G_CALLBACK(do_pane_png), {NULL}, NULL, "save the slice pane as PNG"},
    {"bench-trace-scroll", "i", G_CALLBACK(do_bench), {NULL}, NULL, "benchmark: N plane steps, the pane drawn after each"},
    {"bench-trace-edit", "i", G_CALLBACK(do_bench), {NULL}, NULL, "benchmark: N moves of a point, the surface built and checked after each"},
};

static const struct {
    const char *alias, *action, *target;
} TRACE_ALIASES[] = {
    {"trace-copy-up", "trace", "'copy 1'"},          {"trace-copy-down", "trace", "'copy -1'"},
    {"trace-interpolate", "trace", "'interpolate'"}, {"trace-view-coronal", "trace-view", "'coronal'"},
    {"trace-view-sagittal", "trace-view", "'sagittal'"}, {"image-preset-lung", "image-preset", "'lung'"},
    {"image-preset-bone", "image-preset", "'bone'"}, {"image-preset-auto", "image-preset", "'auto'"},
};

static void on_alias(GSimpleAction *act, GVariant *v, gpointer user)
{
    (void)v;
    view_app *a = user;
    const char *name = g_action_get_name(G_ACTION(act));
    for (size_t k = 0; k < sizeof TRACE_ALIASES / sizeof TRACE_ALIASES[0]; k++)
        if (!strcmp(TRACE_ALIASES[k].alias, name)) {
            GVariant *t = g_variant_parse(NULL, TRACE_ALIASES[k].target, NULL, NULL, NULL);
            g_action_group_activate_action(G_ACTION_GROUP(a->gapp), TRACE_ALIASES[k].action, t);
        }
}

void view_trace_install(view_app *a)
{
    for (size_t k = 0; k < sizeof TRACE_ACTIONS / sizeof TRACE_ACTIONS[0]; k++) {
        const trace_action *d = &TRACE_ACTIONS[k];
        GSimpleAction *act = g_simple_action_new(d->name, d->param ? G_VARIANT_TYPE(d->param) : NULL);
        g_signal_connect(act, "activate", d->fn ? d->fn : G_CALLBACK(on_alias), a);
        g_action_map_add_action(G_ACTION_MAP(a->gapp), G_ACTION(act));
        g_object_unref(act);
        /* the keys only while tracing: Return, Tab, h, j, l mean nothing to the viewer otherwise */
        if (a->trace && d->keys[0]) {
            char detailed[128];
            if (d->target) snprintf(detailed, sizeof detailed, "app.%s(%s)", d->name, d->target);
            else snprintf(detailed, sizeof detailed, "app.%s", d->name);
            gtk_application_set_accels_for_action(a->gapp, detailed, d->keys);
        }
    }
}

size_t view_trace_help(const char *(*rows)[3], size_t max)
{
    size_t n = 0;
    for (size_t k = 0; k < sizeof TRACE_ACTIONS / sizeof TRACE_ACTIONS[0] && n < max; k++, n++) {
        rows[n][0] = TRACE_ACTIONS[k].keys[0] ? TRACE_ACTIONS[k].keys[0] : "";
        rows[n][1] = TRACE_ACTIONS[k].fn ? TRACE_ACTIONS[k].name : "";
        rows[n][2] = TRACE_ACTIONS[k].help;
    }
    return n;
}

/* ---- open and close ---- */

int view_trace_open(view_app *a)
{
    const thx_view_opts *vo = a->vo;
    if (!vo->trace_on) return 0;
    const thx_image *img = thx_picture_scan_image(&a->d);
    if (!img) { fprintf(stderr, "thorax view: tracing needs --image IMG\n"); return -1; }
    view_tracing *t = calloc(1, sizeof *t);
    if (!t) return -1;
    a->trace = t;
    t->img = img;
    t->orient = 'z';
    t->zoom = 1;
    for (int k = 0; k < VIEW_TRACE_MAX; k++) t->surf[k].model_index = -1;
    if (thx_dig_session_create(a->ctx, img, &t->s) != THX_OK) {
        fprintf(stderr, "thorax view: %s\n", thx_ctx_message(a->ctx));
        return -1;
    }
    for (int k = 0; k < vo->n_trace_names && k < 16; k++) snprintf(t->names[t->n_names++], sizeof t->names[0], "%s", vo->trace_names[k]);
    if (!t->n_names)
        for (size_t k = 0; k < sizeof default_names / sizeof default_names[0]; k++)
            snprintf(t->names[t->n_names++], sizeof t->names[0], "%s", default_names[k]);
    if (vo->trace_contours) {
        thx_contours *c = NULL;
        thx_status st = thx_contours_read_raw(a->ctx, vo->trace_contours, &c);
        if (st == THX_OK) st = thx_dig_load(a->ctx, t->s, c);
        thx_contours_destroy(&c);
        if (st != THX_OK) { fprintf(stderr, "thorax view: --contours %s: %s\n", vo->trace_contours, thx_ctx_message(a->ctx)); return -1; }
        if (!realpath(vo->trace_contours, t->start)) snprintf(t->start, sizeof t->start, "%s", vo->trace_contours);
    }
    for (size_t i = 0; i < thx_dig_n_surfaces(t->s) && i < VIEW_TRACE_MAX; i++) model_surface(a, i);
    a->d.bounds_from_scan = 1;
    double lo[3], hi[3];
    thx_picture_bounds(&a->d, lo, hi);
    for (int k = 0; k < 3; k++) t->cursor[k] = 0.5 * (lo[k] + hi[k]);
    if (a->d.n_scan_planes < 1) a->d.n_scan_planes = 1;
    follow_plane(a);
    view_trace_rebuild_now(a);
    return 0;
}

void view_trace_close(view_app *a)
{
    view_tracing *t = a->trace;
    if (!t) return;
    if (t->rebuild_id) g_source_remove(t->rebuild_id);
    thx_dig_session_destroy(&t->s);
    if (t->have_other) thx_image_slice_free(&t->other);
    if (t->grey) cairo_surface_destroy(t->grey);
    free(t->preview);
    free(t);
    a->trace = NULL;
}
