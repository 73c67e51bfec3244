/*
 * The viewer's drawing: each window's GtkGLArea draws its picture with the picture module
 * (thx_picture_draw_gl: the same scene `thorax render` draws), then, when the picture has
 * annotations, reads the pixels back, lets thx_picture_annotate draw them over, and shows the
 * result as one texture — so the window holds the very pixels `thorax render` writes. Screenshots
 * and recorded frames are those pixels.
 */
#include <epoxy/gl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "view/view_internal.h"

static const char *VS = "#version 330 core\n"
                        "layout(location = 0) in vec2 p;\n"
                        "out vec2 uv;\n"
                        "void main() { uv = vec2((p.x + 1.0) * 0.5, (1.0 - p.y) * 0.5); gl_Position = vec4(p, 0.0, 1.0); }\n";
static const char *FS = "#version 330 core\n"
                        "in vec2 uv;\n"
                        "uniform sampler2D tex;\n"
                        "out vec4 color;\n"
                        "void main() { color = texture(tex, uv); }\n";

static unsigned compile(GLenum type, const char *src)
{
    unsigned s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    int ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) { glDeleteShader(s); return 0; }
    return s;
}

static int overlay_init(view_win *w)
{
    unsigned vs = compile(GL_VERTEX_SHADER, VS), fs = compile(GL_FRAGMENT_SHADER, FS);
    if (!vs || !fs) return -1;
    w->prog = glCreateProgram();
    glAttachShader(w->prog, vs);
    glAttachShader(w->prog, fs);
    glLinkProgram(w->prog);
    glDeleteShader(vs);
    glDeleteShader(fs);
    int ok = 0;
    glGetProgramiv(w->prog, GL_LINK_STATUS, &ok);
    if (!ok) return -1;
    static const float quad[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glGenVertexArrays(1, &w->vao);
    glBindVertexArray(w->vao);
    glGenBuffers(1, &w->vbo);
    glBindBuffer(GL_ARRAY_BUFFER, w->vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindVertexArray(0);
    glGenTextures(1, &w->tex);
    return 0;
}

static void on_realize(GtkGLArea *area, gpointer user)
{
    view_win *w = user;
    gtk_gl_area_make_current(area);
    if (gtk_gl_area_get_error(area)) {
        w->gl_failed = 1;
        view_set_info(w->app, "OpenGL: %s", gtk_gl_area_get_error(area)->message);
        return;
    }
    if (thx_renderer_create(w->app->ctx, 0, 0, &w->r) != THX_OK || overlay_init(w)) {
        w->gl_failed = 1;
        view_report(w->app, "OpenGL");
    }
}

static void on_unrealize(GtkGLArea *area, gpointer user)
{
    view_win *w = user;
    gtk_gl_area_make_current(area);
    if (gtk_gl_area_get_error(area)) return;
    thx_renderer_destroy(&w->r);
    if (w->tex) glDeleteTextures(1, &w->tex);
    if (w->vbo) glDeleteBuffers(1, &w->vbo);
    if (w->vao) glDeleteVertexArrays(1, &w->vao);
    if (w->prog) glDeleteProgram(w->prog);
    w->tex = w->vbo = w->vao = w->prog = 0;
}

void view_camera(const view_win *w, double aspect, thx_camera *cam)
{
    thx_camera base;
    thx_picture_camera(&w->o, &w->app->d, aspect, &base);
    double c[3], e0[3], e[3], u[3];
    for (int k = 0; k < 3; k++) { c[k] = base.center[k]; e0[k] = base.eye[k] - c[k]; }
    view_quat_rotate(w->q, e0, e);
    view_quat_rotate(w->q, base.up, u);
    double f[3] = {-e[0], -e[1], -e[2]};
    double r[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
    double rn = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]), un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    double zoom = w->zoom > 0 ? w->zoom : 1;
    *cam = base;
    for (int k = 0; k < 3; k++) {
        double t = (rn > 0 ? r[k] / rn : 0) * w->pan[0] + (un > 0 ? u[k] / un : 0) * w->pan[1];
        cam->center[k] = c[k] + t;
        cam->eye[k] = c[k] + t + (base.fov_deg > 0 ? e[k] / zoom : e[k]);
        cam->up[k] = u[k];
    }
    cam->height = base.height / zoom;
}

void view_scene_viewport(const view_win *w, int fb_w, int fb_h, int vp[4])
{
    thx_picture_viewport(&w->o, w->font, fb_w, fb_h, vp);
}

/* The window's picture with its camera and clip plane made explicit: what `thorax render` would be
 * given to draw the same (the session's options), and what picking and the marks see. A clip plane
 * facing the viewer (clip_view) follows the camera: through the model's centre, moved by the
 * offset, removing the near (front) or far (back) part. */
void view_picture(const view_win *w, int fb_w, int fb_h, thx_picture_opts *o)
{
    *o = w->o;
    /* the picked nodes of the traces, each marked in its trace's colour */
    const view_app *a = w->app;
    o->n_pins = 0;
    for (int t = 0; t < a->n_traces && o->n_pins < (int)(sizeof o->pins / sizeof o->pins[0]); t++) {
        o->pins[o->n_pins].surface = a->traces[t].surface;
        o->pins[o->n_pins].node = a->traces[t].node;
        memcpy(o->pins[o->n_pins].rgba, view_trace_colors[t % VIEW_MAX_TRACES], 4);
        o->n_pins++;
    }
    int vp[4];
    thx_picture_viewport(&w->o, w->font, fb_w, fb_h, vp);
    view_camera(w, vp[3] > 0 ? (double)vp[2] / vp[3] : 1, &o->cam);
    o->have_camera = 1;
    if (w->clip_view) {
        double lo[3], hi[3], c[3], b[3], bn = 0;
        thx_picture_bounds(&w->app->d, lo, hi);
        for (int k = 0; k < 3; k++) {
            c[k] = 0.5 * (lo[k] + hi[k]);
            b[k] = o->cam.eye[k] - o->cam.center[k];
            bn += b[k] * b[k];
        }
        bn = sqrt(bn);
        if (bn > 0) {
            /* front: keep (x - c) . b <= offset, i.e. -b . x + (b . c + offset) >= 0; back: the other side */
            double sgn = w->clip_view == 1 ? -1 : 1, bc = 0;
            for (int k = 0; k < 3; k++) { b[k] /= bn; bc += b[k] * c[k]; }
            snprintf(o->clip, sizeof o->clip, "%.9g,%.9g,%.9g,%.9g", sgn * b[0], sgn * b[1], sgn * b[2],
                     -sgn * bc + w->clip_offset);
        }
    } else if (o->clip[0] && w->clip_offset != 0) {
        thx_clip_plane p;
        if (thx_picture_clip(w->app->ctx, &w->o, &w->app->d, &p) == 1) {
            double n = sqrt(p.n[0] * p.n[0] + p.n[1] * p.n[1] + p.n[2] * p.n[2]);
            snprintf(o->clip, sizeof o->clip, "%.9g,%.9g,%.9g,%.9g", p.n[0], p.n[1], p.n[2], p.d - w->clip_offset * n);
        }
    }
}

static int font_for(view_win *w, int fb_h)
{
    int px = fb_h / 40 > 11 ? fb_h / 40 : 11;
    int want = w->o.colorbar || w->o.label || w->o.trace || w->o.panels || w->o.n_labels || w->o.extrema || w->app->n_traces;
    if (!want) { thx_font_close(&w->font); w->font_px = 0; return 0; }
    if (w->font && w->font_px == px) return 0;
    thx_font_close(&w->font);
    if (thx_font_open(w->app->ctx, w->o.font, px, &w->font) != THX_OK) return -1;
    w->font_px = px;
    return 0;
}

static void read_back(thx_raster *img)
{
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, img->w, img->h, GL_RGBA, GL_UNSIGNED_BYTE, img->rgba);
    size_t row = 4 * (size_t)img->w;
    unsigned char *tmp = malloc(row);
    if (!tmp) return;
    for (int y = 0; y < img->h / 2; y++) {
        unsigned char *a = img->rgba + (size_t)y * row, *b = img->rgba + (size_t)(img->h - 1 - y) * row;
        memcpy(tmp, a, row);
        memcpy(a, b, row);
        memcpy(b, tmp, row);
    }
    free(tmp);
    for (size_t i = 3; i < row * (size_t)img->h; i += 4) img->rgba[i] = 255;
}

static void show_image(view_win *w, const thx_raster *img)
{
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glViewport(0, 0, img->w, img->h);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, w->tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (w->tex_w != img->w || w->tex_h != img->h) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, img->w, img->h, 0, GL_RGBA, GL_UNSIGNED_BYTE, img->rgba);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        w->tex_w = img->w;
        w->tex_h = img->h;
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, img->w, img->h, GL_RGBA, GL_UNSIGNED_BYTE, img->rgba);
    }
    glUseProgram(w->prog);
    glUniform1i(glGetUniformLocation(w->prog, "tex"), 0);
    glBindVertexArray(w->vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glBindVertexArray(0);
    glUseProgram(0);
}

/*
 * Only what the annotations changed, over the scene already in the framebuffer: for each band of
 * 32 rows, the columns where img differs from the scene read back (w->scene) are uploaded into the
 * texture and drawn through a scissor. A colour bar and a label line are a tenth of a 1280x800
 * picture: uploading and drawing the whole frame cost 12.3 ms of a 92 ms rotation step under load
 * (bench/view.sh's phases); measured after: 21 rectangles, 5.7% of the pixels, 4.6 ms. The first draw at a size uploads it all.
 */
static void show_changes(view_win *w, const thx_raster *img)
{
    if (w->tex_w != img->w || w->tex_h != img->h || !w->scene) { show_image(w, img); return; }
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glViewport(0, 0, img->w, img->h);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, w->tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, img->w);
    glUseProgram(w->prog);
    glUniform1i(glGetUniformLocation(w->prog, "tex"), 0);
    glBindVertexArray(w->vao);
    const size_t row = 4 * (size_t)img->w;
    enum { BAND = 32, MAXR = 256 };
    int rect[MAXR][4], nr = 0;
    /* every changed rectangle uploaded first, then drawn: an upload into a texture a pending draw
       reads would make the driver wait for that draw */
    for (int y0 = 0; y0 < img->h && nr < MAXR; y0 += BAND) {
        int y1 = y0 + BAND < img->h ? y0 + BAND : img->h, x0 = img->w, x1 = -1;
        for (int y = y0; y < y1; y++) {
            const uint32_t *a = (const uint32_t *)(img->rgba + (size_t)y * row), *b = (const uint32_t *)(w->scene + (size_t)y * row);
            int l = 0, r = img->w - 1;
            while (l < x0 && a[l] == b[l]) l++;
            while (r > x1 && r >= l && a[r] == b[r]) r--;
            if (l < x0 && a[l] != b[l]) x0 = l;
            if (r > x1 && a[r] != b[r]) x1 = r;
        }
        if (x1 < x0) continue;
        glPixelStorei(GL_UNPACK_SKIP_PIXELS, x0);
        glPixelStorei(GL_UNPACK_SKIP_ROWS, y0);
        glTexSubImage2D(GL_TEXTURE_2D, 0, x0, y0, x1 - x0 + 1, y1 - y0, GL_RGBA, GL_UNSIGNED_BYTE, img->rgba);
        rect[nr][0] = x0;
        rect[nr][1] = img->h - y1; /* GL's rows from the bottom */
        rect[nr][2] = x1 - x0 + 1;
        rect[nr][3] = y1 - y0;
        nr++;
    }
    glEnable(GL_SCISSOR_TEST);
    for (int k = 0; k < nr; k++) {
        glScissor(rect[k][0], rect[k][1], rect[k][2], rect[k][3]);
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    }
    glDisable(GL_SCISSOR_TEST);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
    glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
    glBindVertexArray(0);
    glUseProgram(0);
}

static void record_frame(view_win *w, const thx_raster *img)
{
    view_app *a = w->app;
    /* numbered in the order drawn, from 1, so the movie's frames are consecutive */
    char path[1100];
    snprintf(path, sizeof path, "%s/frame_%05d.png", a->rec_dir, a->rec_count + 1);
    if (thx_raster_write_png(a->ctx, img, path) != THX_OK) {
        view_report(a, "recording");
        a->recording = 0;
        return;
    }
    a->rec_first = 1;
    a->rec_count++;
}

/* A picture that cannot be drawn. At the start, or while a script runs, it stops the viewer with
 * exit status 1 and the message thorax render gives for the same options (a blank window waiting
 * for a draw that never comes was the alternative: the script waits for each line's drawing). Later,
 * from a key or menu, the status line says why and the window stays up; either way the draw counts
 * as done, so nothing waits for it. */
static void draw_failed(view_win *w)
{
    view_app *a = w->app;
    int fatal = w->drawn == 0 || a->script_id || a->sweep_id || a->bench_id;
    w->drawn++;
    if (!fatal) { view_report(a, "drawing"); return; }
    if (w->drawn > 1 && a->script_id && a->line > 0) /* after a script line: name it */
        fprintf(stderr, "thorax view: %s:%d: %s\n", a->vo->script ? a->vo->script : "script", a->vo->script_line0 + a->line - 1,
                thx_ctx_message(a->ctx));
    else
        fprintf(stderr, "thorax view: %s\n", thx_ctx_message(a->ctx));
    snprintf(a->info, sizeof a->info, "%s", thx_ctx_message(a->ctx));
    a->status = 1;
    g_application_quit(G_APPLICATION(a->gapp));
}

static gboolean on_render(GtkGLArea *area, GdkGLContext *context, gpointer user)
{
    view_win *w = user;
    view_app *a = w->app;
    w->pending = 0;
    if (w->gl_failed || !w->r) return TRUE;
    int scale = gtk_widget_get_scale_factor(GTK_WIDGET(area));
    int fb_w = gtk_widget_get_width(GTK_WIDGET(area)) * scale, fb_h = gtk_widget_get_height(GTK_WIDGET(area)) * scale;
    if (fb_w < 1 || fb_h < 1) return TRUE;
    gint64 t0 = g_get_monotonic_time();
    if (font_for(w, fb_h)) { view_report(a, "font"); return TRUE; }
    thx_picture_opts o;
    view_picture(w, fb_w, fb_h, &o);
    thx_picture_bars bars;
    int frame = view_frame_of(w);
    thx_status st = thx_picture_draw_gl(a->ctx, &o, &a->d, w->r, w->font, frame, fb_w, fb_h, &bars, NULL);
    if (st != THX_OK) { draw_failed(w); return TRUE; }
    w->bars = bars; /* where the colour bars are, for their gestures (view_panel.c) */
    w->fb_w = fb_w;
    w->fb_h = fb_h;
    gint64 tp = t0, tn;
#define PHASE(k) /* a benchmark's phases, each finished */                                            \
    if (w->bench) {                                                                                     \
        glFinish();                                                                                     \
        tn = g_get_monotonic_time();                                                                    \
        w->phase_ms[k] += (double)(tn - tp) / 1000.0;                                                   \
        tp = tn;                                                                                        \
    }
    PHASE(0)
    int annotated = w->font != NULL;
    int need_pixels = annotated || w->shot_path || (a->recording && w->id == 1);
    if (need_pixels) {
        if (!w->img || w->img->w != fb_w || w->img->h != fb_h) {
            thx_raster_destroy(&w->img);
            if (thx_raster_create(a->ctx, fb_w, fb_h, &w->img) != THX_OK) { view_report(a, "image"); return TRUE; }
        }
        read_back(w->img);
        PHASE(1)
        if (annotated) {
            size_t nb = (size_t)fb_w * (size_t)fb_h * 4;
            if (!w->scene || w->tex_w != fb_w || w->tex_h != fb_h) {
                free(w->scene);
                w->scene = malloc(nb);
            }
            if (w->scene) memcpy(w->scene, w->img->rgba, nb);
            st = thx_picture_annotate(a->ctx, &o, &a->d, w->font, frame, &bars, w->img);
            if (st != THX_OK) { view_report(a, "annotations"); return TRUE; }
            view_panel_marks(w, &o, w->img); /* the equipotentials' values on their colour bar */
            PHASE(2)
            show_changes(w, w->img);
            PHASE(3)
        }
        if (w->shot_path) {
            if (thx_raster_write_png(a->ctx, w->img, w->shot_path) == THX_OK) view_set_info(a, "saved %s (%dx%d)", w->shot_path, fb_w, fb_h);
            else { view_report(a, "screenshot"); a->status = 1; }
            g_free(w->shot_path);
            w->shot_path = NULL;
        }
        if (a->recording && w->id == 1) record_frame(w, w->img);
    }
#undef PHASE
    if (w->bench) glFinish(); /* the drawing's whole time, not its queueing */
    else glFlush();
    w->draw_ms = (double)(g_get_monotonic_time() - t0) / 1000.0;
    w->ms_sum += w->draw_ms;
    w->ms_n++;
    w->drawn++;
    if (w->drawn == 1) {
        view_pick_prepare(a);
        /* the state a test waits for (instead of sleeping): this window is up and drawn */
        graphene_point_t at = GRAPHENE_POINT_INIT(0, 0), in;
        if (!gtk_widget_compute_point(GTK_WIDGET(area), w->window, &at, &in)) in = at;
        if (a->vo->verbose > 0)
            fprintf(stderr, "thorax view: window %d drawn (%dx%d pixels, at %.0f,%.0f in the window)\n", w->id, fb_w, fb_h, in.x, in.y);
    }
    return TRUE;
}

void view_gl_attach(view_win *w)
{
    GtkGLArea *area = GTK_GL_AREA(w->gl);
    gtk_gl_area_set_required_version(area, 3, 3);
    gtk_gl_area_set_has_depth_buffer(area, TRUE);
    gtk_gl_area_set_auto_render(area, FALSE);
    g_signal_connect(area, "realize", G_CALLBACK(on_realize), w);
    g_signal_connect(area, "unrealize", G_CALLBACK(on_unrealize), w);
    g_signal_connect(area, "render", G_CALLBACK(on_render), w);
}
