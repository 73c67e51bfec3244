/*
 * Program control (paper 4.2): a script file holds the viewer's command-line options, one per
 * line, the way the paper's users kept theirs; the options at its head are read with the command
 * line (the CLI does that), and the lines after them run once the windows are up, each after the
 * previous one's drawing is done:
 *     action NAME [VALUE]   a GAction, as a key or menu would run it (`?` lists them)
 *     --option [VALUE]      an option of the command line, applied to every window now
 *     wait MS               let MS milliseconds pass (while playing, say)
 *     quit                  the same as `action quit`
 * A line that fails stops the script and the viewer with exit status 1, naming FILE:LINE.
 * "Save session" writes such a script: the data options, then every setting that makes the
 * picture (the camera made explicit), so the script reopens the session and `thorax render`
 * given the same options draws the same picture.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "thorax/core/fileio.h"
#include "thorax/picture/movie.h"
#include "view/view_internal.h"

/* Drawing queued or under way in some window (or a window not drawn yet). */
static int busy(view_app *a)
{
    for (int k = 0; k < a->n_win; k++) {
        view_win *w = a->win[k];
        if (w->gl_failed) continue;
        if (!gtk_widget_get_realized(w->gl) || w->drawn == 0 || w->pending || w->shot_path) return 1;
    }
    return 0;
}

static void script_fail(view_app *a, int line, const char *fmt, const char *what)
{
    fprintf(stderr, "thorax view: %s:%d: ", a->vo->script ? a->vo->script : "script", line);
    fprintf(stderr, fmt, what);
    fprintf(stderr, "\n");
    a->status = 1;
    g_application_quit(G_APPLICATION(a->gapp));
}

/* Runs one line; 0 on success, -1 after reporting a failure. *wait_ms: a pause asked for. */
static int run_line(view_app *a, const char *text, int line, int *wait_ms)
{
    while (*text == ' ' || *text == '\t') text++;
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", text);
    size_t len = strlen(buf);
    while (len && (buf[len - 1] == '\n' || buf[len - 1] == '\r' || buf[len - 1] == ' ' || buf[len - 1] == '\t')) buf[--len] = '\0';
    if (!buf[0] || buf[0] == '#') return 0;
    if (!strcmp(buf, "quit")) snprintf(buf, sizeof buf, "action quit");
    if (!strncmp(buf, "wait ", 5)) {
        char *end;
        long ms = strtol(buf + 5, &end, 10);
        if (*end || ms < 0 || ms > 600000) { script_fail(a, line, "wait '%s': milliseconds, 0 to 600000", buf + 5); return -1; }
        *wait_ms = (int)ms;
        return 0;
    }
    if (buf[0] == '-') {
        if (!a->vo->option_fn) { script_fail(a, line, "'%s': options are not taken here", buf); return -1; }
        for (int k = 0; k < a->n_win; k++) {
            thx_picture_opts o = a->win[k]->o;
            if (a->vo->option_fn(a->vo->option_user, &o, buf)) { script_fail(a, line, "'%s': see the message above", buf); return -1; }
            /* the volume potentials are read at the start only when a cut is asked for there: now, else */
            if ((o.isosurface || o.n_slices || o.n_streamlines) && thx_picture_volume_load(a->ctx, &o, &a->d, buf) != THX_OK) {
                script_fail(a, line, "%s", thx_ctx_message(a->ctx));
                return -1;
            }
            if (o.clip[0] && thx_picture_clip_check(a->ctx, &o, &a->d) != THX_OK) {
                script_fail(a, line, "%s", thx_ctx_message(a->ctx));
                return -1;
            }
            /* a cut that cannot be made is this line's error, not a failed drawing's */
            if (thx_picture_cuts_check(a->ctx, &o, &a->d) != THX_OK) {
                script_fail(a, line, "%s", thx_ctx_message(a->ctx));
                return -1;
            }
            a->win[k]->o = o;
        }
        view_redraw_all(a);
        view_panel_refresh(a);
        return 0;
    }
    if (strncmp(buf, "action ", 7)) {
        script_fail(a, line, "'%s': a line is an option (--name value), action NAME [VALUE], wait MS, quit or a # comment", buf);
        return -1;
    }
    char *name = buf + 7;
    while (*name == ' ') name++;
    char *value = name + strcspn(name, " \t");
    if (*value) { *value++ = '\0'; while (*value == ' ' || *value == '\t') value++; }
    if (!strncmp(name, "app.", 4)) name += 4;
    GActionGroup *g = G_ACTION_GROUP(a->gapp);
    if (!g_action_group_has_action(g, name)) { script_fail(a, line, "no action '%s' (the `?` key lists them)", name); return -1; }
    const GVariantType *pt = g_action_group_get_action_parameter_type(g, name);
    GVariant *param = NULL;
    if (!pt) {
        if (*value) { script_fail(a, line, "action %s takes no value", name); return -1; }
    } else if (g_variant_type_equal(pt, G_VARIANT_TYPE_STRING)) {
        param = g_variant_new_string(value);
    } else if (g_variant_type_equal(pt, G_VARIANT_TYPE_INT32)) {
        char *end;
        long v = strtol(value, &end, 10);
        if (!*value || *end || v < INT32_MIN || v > INT32_MAX) { script_fail(a, line, "action %s: give an integer", name); return -1; }
        param = g_variant_new_int32((gint32)v);
    } else {
        char *end;
        double v = strtod(value, &end);
        if (!*value || *end || !isfinite(v)) { script_fail(a, line, "action %s: give a number", name); return -1; }
        param = g_variant_new_double(v);
    }
    int before = a->status;
    a->status = 0;
    g_action_group_activate_action(g, name, param);
    if (a->status) { script_fail(a, line, "%s", a->info); return -1; }
    a->status = before;
    return 0;
}

/* Every 5 ms: the next lines, as long as they queue no drawing; then wait for it. */
static gboolean script_tick(gpointer user)
{
    view_app *a = user;
    if (busy(a) || a->sweep_id || a->bench_id || g_get_monotonic_time() < a->wait_until) return G_SOURCE_CONTINUE;
    while (a->line < a->vo->n_lines) {
        int wait_ms = 0, k = a->line++;
        if (run_line(a, a->vo->lines[k], a->vo->script_line0 + k, &wait_ms)) {
            a->script_id = 0;
            return G_SOURCE_REMOVE;
        }
        if (wait_ms > 0) {
            a->wait_until = g_get_monotonic_time() + 1000 * (gint64)wait_ms;
            return G_SOURCE_CONTINUE;
        }
        if (busy(a) || a->sweep_id || a->bench_id) return G_SOURCE_CONTINUE;
    }
    a->script_id = 0;
    return G_SOURCE_REMOVE;
}

void view_script_start(view_app *a)
{
    if (a->vo->n_lines == 0) return;
    a->line = 0;
    a->script_id = g_timeout_add(5, script_tick, a);
}

/* ---- save session ---- */

/* The words of render's --mode and --style (thx_draw_mode, thx_data_style order). */
static const char *const modes[] = {"hidden", "points", "wire", "flat", "gouraud", "phong", "orientation"};
static const char *const styles[] = {"continuous", "bands", "contours", "bands+contours", "continuous+contours"};

static void write_look(FILE *f, const thx_picture_look *l)
{
    fprintf(f, "--surface %s=%s", l->name, l->style >= 0 ? styles[l->style] : modes[l->mode]);
    if (l->opacity >= 0 || l->have_color) fprintf(f, ":%.3g", l->opacity >= 0 ? l->opacity : 1.0);
    if (l->have_color)
        fprintf(f, ":#%02x%02x%02x", (int)lround(l->color[0] * 255), (int)lround(l->color[1] * 255), (int)lround(l->color[2] * 255));
    fprintf(f, "\n");
}

/* The options of a window's picture as it is drawn now (what `thorax render` takes). */
static void write_picture(FILE *f, view_win *w)
{
    static const char *scopes[] = {"frame", "series", "all", "fixed", "surfaces"};
    int scale = gtk_widget_get_scale_factor(w->gl);
    int fb_w = gtk_widget_get_width(w->gl) * scale, fb_h = gtk_widget_get_height(w->gl) * scale;
    thx_picture_opts pic;
    view_picture(w, fb_w, fb_h, &pic);
    const thx_picture_opts *o = &pic;
    const thx_camera cam = pic.cam;
    fprintf(f, "--size %dx%d\n", fb_w, fb_h);
    fprintf(f, "--camera %.17g,%.17g,%.17g:%.17g,%.17g,%.17g:%.17g,%.17g,%.17g:%.17g:%.17g\n", cam.eye[0], cam.eye[1],
            cam.eye[2], cam.center[0], cam.center[1], cam.center[2], cam.up[0], cam.up[1], cam.up[2], cam.fov_deg, cam.height);
    if (o->up_spec) fprintf(f, "--up %s\n", o->up_spec);
    if (o->front_spec) fprintf(f, "--front %s\n", o->front_spec);
    fprintf(f, "--mode %s\n", modes[o->mode]);
    for (int k = 0; k < o->n_look; k++) write_look(f, &o->look[k]);
    for (int k = 0; k < o->n_only; k++) fprintf(f, "--only %s\n", o->only[k]);
    for (int k = 0; k < o->n_whole; k++) fprintf(f, "--no-clip %s\n", o->whole[k]);
    fprintf(f, "--style %s\n--levels %d\n--cmap %s\n--scale %s\n", styles[o->style], o->levels,
            thx_colormap_name((thx_colormap)o->cmap), thx_scale_model_name((thx_scale_model)o->model));
    if (o->scope == THX_SCOPE_FIXED) fprintf(f, "--scope fixed:%.17g:%.17g\n", o->lo, o->hi);
    else fprintf(f, "--scope %s\n", scopes[o->scope]);
    fprintf(f, "--mapping %s\n", thx_scale_mapping_name((thx_scale_mapping)o->mapping));
    for (int k = 0; k < o->n_groups; k++) fprintf(f, "--scale-group %s\n", o->groups[k]);
    for (int k = 0; k < o->n_slaves; k++) fprintf(f, "--slave %s\n", o->slaves[k]);
    if (o->invert) fprintf(f, "--invert\n");
    if (o->colorbar) fprintf(f, "--colorbar\n");
    if (o->label) fprintf(f, "--label\n");
    if (o->panels) fprintf(f, "--panels\n");
    if (o->trace) fprintf(f, "--trace %s\n", o->trace);
    for (int k = 0; k < o->n_labels; k++) fprintf(f, "--node-labels %s\n", o->labels[k]);
    if (o->extrema) fprintf(f, "--extrema\n");
    if (o->font) fprintf(f, "--font %s\n", o->font);
    if (o->clip[0]) fprintf(f, "--clip %s\n", o->clip);
    /* the volume's cuts as they are now (the panel, its gestures and script lines change them) */
    if (o->isosurface) fprintf(f, "--isosurface %s\n", o->isosurface);
    for (int k = 0; k < o->n_slices; k++) fprintf(f, "--slice %s\n", o->slices[k]);
    if (o->slice_current) fprintf(f, "--slice-current\n");
    for (int k = 0; k < o->n_streamlines; k++) fprintf(f, "--streamlines %s\n", o->streamlines[k]);
    if (o->stream_radius > 0) fprintf(f, "--stream-radius %.17g\n", o->stream_radius);
    if (o->stream_potential) fprintf(f, "--stream-potential\n");
    if (o->arrows) {
        fprintf(f, "--arrows\n--arrow-spacing %.17g\n--arrow-length %.17g\n--arrow-max %d\n", o->arrow_spacing,
                o->arrow_scale, o->arrow_max);
        if (o->arrow_gap > 0) fprintf(f, "--arrow-gap %.17g\n", o->arrow_gap);
        if (o->arrow_unit) fprintf(f, "--arrow-unit\n");
        if (o->arrow_region) fprintf(f, "--arrow-region %s\n", o->arrow_region);
    }
}

thx_status view_save_session(view_app *a, const char *path)
{
    static const char marker[] = "# thorax view session";
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(a->ctx, path, marker, sizeof marker - 1, NULL, 0, &af));
    FILE *f = af.f;
    const thx_picture_opts *o = &a->vo->pic;
    time_t now = time(NULL);
    char when[64];
    strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S", localtime(&now));
    fprintf(f, "%s, saved %s\n", marker, when);
    fprintf(f, "# reopen: thorax view --script %s\n", path);
    fprintf(f, "# draw the same offscreen: thorax render with these options (less the viewer's own, after the mark below)\n");
    if (a->vo->command_line) fprintf(f, "# from: %s\n", a->vo->command_line);
    if (o->model_dir) fprintf(f, "%s\n", o->model_dir);
    for (int k = 0; k < o->n_files; k++) fprintf(f, "%s\n", o->files[k]);
    if (o->solution) fprintf(f, "--solution %s\n", o->solution);
    for (int k = 0; k < o->n_data; k++) { /* each data set with the channels that follow it */
        fprintf(f, "--data %s\n", o->data[k]);
        if (o->n_channels && o->data_channels[k]) fprintf(f, "--channels %s\n", o->data_channels[k]);
    }
    for (int k = 0; k < o->n_data_surface; k++) fprintf(f, "--data-surface %s\n", o->data_surface[k]);
    if (!o->n_channels && o->channels) fprintf(f, "--channels %s\n", o->channels);
    for (int k = 0; k < o->n_landmarks; k++) fprintf(f, "--landmarks %s\n", o->landmarks[k]);
    for (int k = 0; k < o->n_electrodes; k++) fprintf(f, "--electrodes %s\n", o->electrodes[k]);
    if (o->tetrahedra) fprintf(f, "--tetrahedra\n");
    if (o->image) { /* the scan: its planes where they are now, the window and level in use */
        fprintf(f, "--image %s\n", o->image);
        for (int k = 0; k < a->d.n_scan_planes; k++) fprintf(f, "--image-plane %c=%.17g\n", a->d.scan_axis[k], a->d.scan_pos[k]);
        fprintf(f, "--image-window %.17g\n--image-level %.17g\n", a->d.window, a->d.level);
        if (o->image_labels) fprintf(f, "--image-labels\n");
        if (o->contours) fprintf(f, "--contours %s\n", o->contours);
    }
    /* the maps shown: those asked for at the start, and those made since */
    for (size_t s = 0; s < a->d.m->n_surfaces && s < THX_PICTURE_SURFACES; s++) {
        if (!a->d.series[s] || !a->d.map[s][a->d.active[s]]) continue;
        int rec = a->d.map[s][a->d.active[s]] == 2;
        const char *spec = rec ? a->rec_spec[s] : a->act_spec[s];
        const char *const *given = rec ? o->recovery : o->activation;
        size_t nl = strlen(a->d.m->surf[s]->name);
        for (int k = 0; k < (rec ? o->n_recovery : o->n_activation); k++) /* the start's own spec for this surface */
            if (!strncmp(given[k], a->d.m->surf[s]->name, nl) && (given[k][nl] == ':' || !given[k][nl]) && !spec[0])
                spec = given[k] + nl + (given[k][nl] == ':');
        fprintf(f, "--%s %s%s%s\n", rec ? "recovery" : "activation", a->d.m->surf[s]->name, spec[0] ? ":" : "", spec);
    }
    view_win *w = a->win[0];
    write_picture(f, w);
    fprintf(f, "--frame %d\n", view_frame_of(w) + 1);
    fprintf(f, "# the viewer's own\n");
    fprintf(f, "--rate %.17g\n--step %d\n%s\n", a->rate, a->step, a->loop ? "--loop" : "--no-loop");
    if (a->n_win > 1)
        for (int k = 0; k < a->n_win; k++) {
            GString *names = g_string_new("");
            for (int j = 0; j < a->win[k]->o.n_only; j++) g_string_append_printf(names, "%s%s", j ? "," : "", a->win[k]->o.only[j]);
            fprintf(f, "--window %s\n", names->str);
            g_string_free(names, TRUE);
        }
    return thx_atomic_commit(a->ctx, &af);
}

thx_status view_movie(view_app *a, const char *path)
{
    thx_atomic_file af;
    THX_CHECK(thx_movie_claim(a->ctx, path, &af));
    int fps = (int)lround(a->rate);
    return thx_movie_make(a->ctx, &af, a->rec_dir, a->rec_first, a->rec_count, fps < 1 ? 1 : fps > 240 ? 240 : fps);
}

/* ---- record every frame, unattended ---- */

static gboolean sweep_tick(gpointer user)
{
    view_app *a = user;
    if (busy(a)) return G_SOURCE_CONTINUE;
    if (a->sweep_next < a->n_frames && a->recording) {
        g_action_group_activate_action(G_ACTION_GROUP(a->gapp), "frame", g_variant_new_int32(a->sweep_next + 1));
        a->sweep_next++;
        return G_SOURCE_CONTINUE;
    }
    a->sweep_id = 0;
    if (!a->recording) return G_SOURCE_REMOVE;
    a->recording = 0;
    char movie[1100];
    snprintf(movie, sizeof movie, "%s/animation.mp4", a->rec_dir);
    if (view_movie(a, movie) != THX_OK) {
        view_report(a, "movie");
        a->status = 1;
    } else {
        view_set_info(a, "recorded %d frames and %s", a->rec_count, movie);
    }
    return G_SOURCE_REMOVE;
}

void view_record_all(view_app *a, const char *dir)
{
    if (g_mkdir_with_parents(dir, 0777) != 0) {
        view_set_info(a, "record-all: cannot create %s: %s", dir, g_strerror(errno));
        a->status = 1;
        return;
    }
    snprintf(a->rec_dir, sizeof a->rec_dir, "%s", dir);
    a->recording = 1;
    a->rec_count = 0;
    a->sweep_next = 0;
    a->sweep_id = g_timeout_add(5, sweep_tick, a);
}

/* ---- a key-framed flight ---- */

static gboolean fly_tick(gpointer user)
{
    view_app *a = user;
    if (busy(a)) return G_SOURCE_CONTINUE;
    if (a->flight && a->fly_next <= thx_camera_path_last(a->flight)) {
        thx_camera cam;
        thx_camera_path_camera(a->flight, a->fly_next, &cam);
        for (int k = 0; k < a->n_win; k++) { /* the window's camera is the flight's: no turn, zoom or pan on it */
            view_win *w = a->win[k];
            w->o.have_camera = 1;
            w->o.cam = cam;
            w->q[0] = 1, w->q[1] = w->q[2] = w->q[3] = 0;
            w->zoom = 1;
            w->pan[0] = w->pan[1] = 0;
        }
        int df = thx_camera_path_data_frame(a->flight, a->fly_next);
        if (!df) df = a->fly_next;
        if (a->n_frames > 0) g_action_group_activate_action(G_ACTION_GROUP(a->gapp), "frame", g_variant_new_int32(df));
        view_redraw_all(a);
        a->fly_next++;
        return G_SOURCE_CONTINUE;
    }
    view_set_info(a, "flew %d frames", a->flight ? thx_camera_path_last(a->flight) : 0);
    thx_camera_path_destroy(&a->flight);
    a->sweep_id = 0;
    return G_SOURCE_REMOVE;
}

void view_fly(view_app *a, const char *path)
{
    if (a->sweep_id) { view_set_info(a, "fly: a sweep is under way"); a->status = 1; return; }
    view_win *w = a->win[0];
    thx_camera_keys keys;
    thx_camera views[6];
    for (int v = 0; v < 6; v++) thx_picture_view_camera(&w->o, &a->d, v, (double)w->o.w / w->o.h, &views[v]);
    thx_status st = thx_camera_keys_read(a->ctx, path, &keys);
    if (st == THX_OK) st = thx_camera_keys_resolve(a->ctx, &keys, views);
    if (st == THX_OK) st = thx_camera_path_create(a->ctx, &keys, &a->flight);
    thx_camera_keys_free(&keys);
    for (int f = 1; st == THX_OK && a->n_frames > 0 && f <= thx_camera_path_last(a->flight); f++) {
        int df = thx_camera_path_data_frame(a->flight, f);
        if ((df ? df : f) > a->n_frames)
            st = thx_error(a->ctx, THX_EINPUT, "%s: movie frame %d shows data frame %d: the data has %d frames%s", path, f,
                           df ? df : f, a->n_frames, df ? "" : " (give the data frame of some keys: data N)");
    }
    if (st != THX_OK) {
        thx_camera_path_destroy(&a->flight);
        snprintf(a->info, sizeof a->info, "fly: %s", thx_ctx_message(a->ctx));
        a->status = 1;
        return;
    }
    a->fly_next = 1;
    a->sweep_id = g_timeout_add(5, fly_tick, a);
}

/* ---- benchmarks ---- */

static int cmp_ms(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Peak resident memory of the process, MB (VmHWM). */
static double peak_mb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    double kb = 0;
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, "VmHWM:", 6)) kb = atof(line + 6);
    if (f) fclose(f);
    return kb / 1024;
}

static gboolean bench_tick(gpointer user)
{
    view_app *a = user;
    if (busy(a)) return G_SOURCE_CONTINUE;
    gint64 now = g_get_monotonic_time();
    if (a->bench_i > 0 && a->bench_kind != 3) a->bench_ms[a->bench_i - 1] = (double)(now - a->bench_last) / 1000.0;
    a->bench_last = now;
    view_win *w = a->win[0];
    if (a->bench_i < a->bench_n) {
        if (a->bench_kind == 1) {
            view_rotate_screen(w, 0, 1, 1.0);
            view_copy_transform(a, w);
            view_redraw_all(a);
        } else if (a->bench_kind == 2) {
            a->frame = (a->frame + 1) % (a->n_frames > 0 ? a->n_frames : 1);
            for (int k = 0; k < a->n_win; k++) a->win[k]->frame = a->frame;
            view_redraw_all(a);
        } else {
            /* picks over a grid of the window, each timed alone */
            int gw = gtk_widget_get_width(w->gl), gh = gtk_widget_get_height(w->gl), side = (int)ceil(sqrt(a->bench_n));
            double x = (a->bench_i % side + 0.5) * gw / side, y = (a->bench_i / side + 0.5) * gh / side;
            gint64 t0 = g_get_monotonic_time();
            view_pick_quiet(w, x, y);
            a->bench_ms[a->bench_i] = (double)(g_get_monotonic_time() - t0) / 1000.0;
        }
        a->bench_i++;
        return G_SOURCE_CONTINUE;
    }
    int n = a->bench_n;
    double total = (double)(now - a->bench_t0) / 1e6;
    qsort(a->bench_ms, (size_t)n, sizeof *a->bench_ms, cmp_ms);
    double draw = 0;
    int nd = 0;
    for (int k = 0; k < a->n_win; k++) { draw += a->win[k]->ms_sum; nd += a->win[k]->ms_n; }
    static const char *kinds[] = {"", "rotate", "frame-step", "pick"};
    int scale = gtk_widget_get_scale_factor(w->gl);
    if (a->bench_kind == 3)
        printf("view bench: pick %d picks, median %.2f ms, max %.2f ms, window %dx%d, peak %.0f MB\n", n, a->bench_ms[n / 2],
               a->bench_ms[n - 1], gtk_widget_get_width(w->gl) * scale, gtk_widget_get_height(w->gl) * scale, peak_mb());
    else
        printf("view bench: %s %d steps in %.2f s: %.1f per second; median %.1f ms a step (slowest %.1f); drawing %.1f ms "
               "on average; window %dx%d; peak %.0f MB\n", kinds[a->bench_kind], n, total, n / total, a->bench_ms[n / 2],
               a->bench_ms[n - 1], nd ? draw / nd : 0, gtk_widget_get_width(w->gl) * scale, gtk_widget_get_height(w->gl) * scale,
               peak_mb());
    if (a->bench_kind != 3 && nd) {
        double ph[4] = {0};
        for (int k = 0; k < a->n_win; k++)
            for (int j = 0; j < 4; j++) ph[j] += a->win[k]->phase_ms[j];
        printf("view bench: %s phases: scene %.1f ms, readback %.1f ms, annotations %.1f ms, their upload %.1f ms (a draw, "
               "each finished)\n", kinds[a->bench_kind], ph[0] / nd, ph[1] / nd, ph[2] / nd, ph[3] / nd);
    }
    fflush(stdout);
    free(a->bench_ms);
    a->bench_ms = NULL;
    a->bench_id = 0;
    return G_SOURCE_REMOVE;
}

void view_bench(view_app *a, int kind, int n)
{
    a->bench_ms = calloc((size_t)n, sizeof *a->bench_ms);
    if (!a->bench_ms) { view_set_info(a, "bench: out of memory"); a->status = 1; return; }
    for (int k = 0; k < a->n_win; k++) {
        a->win[k]->ms_sum = 0;
        a->win[k]->ms_n = 0;
        a->win[k]->bench = 1;
        memset(a->win[k]->phase_ms, 0, sizeof a->win[k]->phase_ms);
    }
    a->bench_kind = kind;
    a->bench_n = n;
    a->bench_i = 0;
    a->bench_t0 = a->bench_last = g_get_monotonic_time();
    a->bench_id = g_idle_add(bench_tick, a);
}
