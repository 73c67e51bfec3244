/* What the viewer's files share (thorax/view/view.h): the application, its windows, and the
 * functions each file gives the others. GTK 4; OpenGL through libepoxy. */
#ifndef THORAX_VIEW_INTERNAL_H
#define THORAX_VIEW_INTERNAL_H
#include <gtk/gtk.h>

#include "thorax/edit/edit.h"
#include "thorax/picture/picture.h"
#include "thorax/render/camera_path.h"
#include "thorax/view/view.h"

typedef struct view_app view_app;
typedef struct view_tracing view_tracing; /* view_trace.h */

/* A pick kept for the edits: the surface, the triangle hit and its nearest node, where the node was. */
typedef struct {
    int surface;
    size_t tri, node;
    double start[3];
} view_pick;

/* A trace held in the plot pane: a node of a surface with data. */
typedef struct {
    int surface;
    size_t node;
} view_trace;

#define VIEW_MAX_TRACES 6
extern const unsigned char view_trace_colors[VIEW_MAX_TRACES][4];

/* What the side panel edits for every window (view_panel.c): the strings the pictures' cut options
 * point to, and the state of its tools. */
typedef struct {
    char iso[1024];            /* --isosurface's list */
    char slice[8][96];         /* --slice planes */
    char seed[4][256];         /* --streamlines seeds */
    int slice_sel;             /* the selected slice (0-based): slice-move and Ctrl+Shift+drag move it */
    int seed_tool;             /* 0 none, 1 a click seeds a point, 2 two clicks a rake */
    int rake_n;                /* seeds along a rake */
    int have_rake_a;           /* the rake's first end picked, at rake_a */
    double rake_a[3];
    int scope_auto;            /* the scope a fixed range replaced (range auto goes back to it) */
    int selecting;             /* a time window dragged on the trace pane, sel[0] to sel[1] */
    double sel[2];
} view_cuts;

typedef struct view_panel view_panel;

typedef struct view_win {
    view_app *app;
    int id;                    /* 1-based, in titles */
    GtkWidget *window, *gl, *status, *plot, *paned;
    GtkWidget *plot_scroll;    /* the trace pane: a fixed height, scrolled when the traces need more */
    thx_picture_opts o;        /* this window's picture; o.only[] = its surfaces (none: all) */
    char only_buf[THX_PICTURE_MAX][64];
    char label_buf[THX_PICTURE_MAX][80]; /* node-labels entries set by the action */
    char group_buf[THX_PICTURE_MAX][256]; /* scale-group and slave entries set by the actions */
    char slave_buf[THX_PICTURE_MAX][256];
    thx_renderer *r;           /* in the GL area's context */
    thx_font *font;
    int font_px;
    thx_font *plot_font;       /* the plot pane's */
    int frame;                 /* this window's frame when the frame lock is off */
    /* camera: the standard view at open, turned by q about its centre, zoomed and panned */
    int have_base;
    thx_camera base;
    double q[4];               /* unit quaternion (w, x, y, z) applied to the camera about the centre */
    double zoom;               /* > 1: closer */
    double pan[2];             /* mm, along the camera's right and up */
    double drag_q[4], drag_pan[2];
    double drag_x0, drag_y0;
    int drag_mode;             /* 0 none, 1 rotate, 2 pan, 3 clip */
    double drag_clip;
    /* clip plane: off, or the picture's o.clip; `offset` moves it along its normal (mm); locked:
       turns with the object (kept in model coordinates) instead of staying facing the viewer */
    double clip_offset;
    int clip_view;             /* 0: the picture's clip plane; 1, 2: a plane facing the viewer, cutting the near
                                  (front) or far (back) part, that follows the camera until locked */
    /* the overlay of annotations */
    unsigned tex, prog, vao, vbo;
    int tex_w, tex_h;
    thx_raster *img;
    unsigned char *scene;      /* the scene as read back, before the annotations (what changed is uploaded) */
    /* a screenshot wanted at the next draw (path owned), and its outcome */
    char *shot_path;
    int drawn;                 /* draws since open */
    int pending;               /* a draw is queued */
    double draw_ms;            /* the last draw's time */
    double ms_sum;
    int ms_n;
    int gl_failed;
    int bench;                 /* benchmarking: each draw finished (glFinish) before it is timed */
    double phase_ms[4];        /* ... and its phases summed: the scene (finished), the readback, the
                                  annotations, their upload and quad (finished) */
    view_panel *panel;         /* the side panel (view_panel.c) */
    thx_picture_bars bars;     /* the colour bars of the last draw, at fb_w x fb_h (the bar's gestures) */
    int fb_w, fb_h;
} view_win;

struct view_app {
    thx_ctx *ctx;
    thx_view_opts *vo;
    thx_picture_data d;
    GtkApplication *gapp;
    view_win *win[THX_VIEW_MAX_WINDOWS];
    int n_win;
    int n_frames;
    int frame;                 /* the shared frame (frame lock on) */
    int playing;
    guint play_id;
    double rate;
    int loop, step;
    int lock_frame, lock_transform, lock_scale;
    int current;               /* the surface commands act on (up/down arrows) */
    int status;                /* exit status */
    /* the script */
    int line;
    guint script_id;
    gint64 wait_until;         /* a `wait` line's end (monotonic microseconds) */
    /* recording: every new frame drawn in window 1 into rec_dir/frame_%05d.png */
    char rec_dir[1024];
    int recording, rec_count, rec_first;
    int sweep_next;            /* record-all: the next frame to draw (while sweep_id) */
    thx_camera_path *flight;   /* action fly: the key-framed flight under way (while sweep_id), its next movie frame */
    int fly_next;
    /* benchmarks (bench/view.sh): N steps of a kind, each drawn before the next, timed */
    int bench_kind, bench_n, bench_i;  /* 1 rotate 1 degree, 2 frame step, 3 pick */
    gint64 bench_t0, bench_last;
    double *bench_ms;          /* wall time between consecutive finished draws */
    guint bench_id;
    guint sweep_id;
    /* picking */
    view_trace traces[VIEW_MAX_TRACES];
    char act_spec[THX_PICTURE_SURFACES][40]; /* the window of each surface's activation map ("" whole series) */
    char rec_spec[THX_PICTURE_SURFACES][40]; /* ... and of its recovery map */
    double plot_zoom;
    thx_edit_session *edit;    /* opened at the first edit (view_edit.c) */
    view_pick picked[3];       /* the last three picks, oldest first */
    int n_picked;          /* the plot pane shows 1/plot_zoom of the frames, centred on the frame shown */
    int n_traces;
    char info[512];            /* the status line's pick/edit information */
    int shots;                 /* screenshots saved by the menu (numbering) */
    view_tracing *trace;       /* tracing a scan (view_trace.c), or NULL */
    view_cuts cuts;            /* the side panel's (view_panel.c) */
};

/* view_app.c */
view_win *view_active(view_app *a);
void view_redraw_all(view_app *a);
void view_update_titles(view_app *a);
int view_frame_of(const view_win *w);
void view_set_info(view_app *a, const char *fmt, ...) G_GNUC_PRINTF(2, 3);
void view_report(view_app *a, const char *what); /* the ctx's message into the status line and stderr */

/* view_gl.c */
void view_gl_attach(view_win *w);
void view_camera(const view_win *w, double aspect, thx_camera *cam);
void view_scene_viewport(const view_win *w, int fb_w, int fb_h, int vp[4]);
void view_picture(const view_win *w, int fb_w, int fb_h, thx_picture_opts *o);

/* view_input.c */
void view_input_attach(view_win *w);
void view_quat_identity(double q[4]);
void view_quat_mul(const double a[4], const double b[4], double out[4]);
void view_quat_axis_angle(const double axis[3], double deg, double q[4]);
void view_quat_rotate(const double q[4], const double v[3], double out[3]);
void view_rotate_screen(view_win *w, double ax, double ay, double deg); /* about an axis in screen space */
void view_copy_transform(view_app *a, const view_win *from);
void view_camera_basis(const view_win *w, double right[3], double up[3], double back[3]);
double view_mm_per_pixel(const view_win *w);

/* view_actions.c */
void view_actions_install(view_app *a);
thx_picture_look *view_look_of(view_win *w, const char *name); /* the window's look of a surface (made when new) */
GMenuModel *view_menu(void);

/* view_script.c */
void view_script_start(view_app *a);
thx_status view_save_session(view_app *a, const char *path);
thx_status view_movie(view_app *a, const char *path);
void view_record_all(view_app *a, const char *dir);
/* Flies every window's camera along a camera key file (thorax animate --keys), one movie frame drawn
 * after another, each at the flight's data frame; frames are recorded when recording is on. */
void view_fly(view_app *a, const char *keys);
void view_bench(view_app *a, int kind, int n);

/* view_edit.c */
int view_edit_apply(view_app *a, const thx_edit *e);
int view_edit_line(view_app *a, const char *text);
int view_edit_undo(view_app *a, int redo);
int view_edit_save(view_app *a, const char *dir);
int view_edit_picked(view_app *a, const char *what, double x);
void view_edit_drag(view_win *w, double dx, double dy, int done);

/* view_trace.c (tracing a scan; view_trace.h holds the rest) */
int view_trace_open(view_app *a);
void view_trace_close(view_app *a);
void view_trace_install(view_app *a);
int view_trace_line(view_app *a, const char *line);
/* The tracing actions' rows for the key list: key (GTK accelerator text, "" none), action, help. */
size_t view_trace_help(const char *(*rows)[3], size_t max);

/* view_plot.c */
void view_plot_attach(view_win *w);
void view_plot_update(view_app *a);
thx_status view_plot_export(view_app *a, const char *path);
int view_pick_at(view_win *w, double x, double y);
/* The point of the surfaces shown under (x, y) and the ray's direction; 1, or 0 when nothing is hit. */
int view_pick_point(view_win *w, double x, double y, double p[3], double dir[3]);
/* The time under x (the pane's pixels) on the traces' axis; 0, or -1 without traces. */
int view_plot_time_at(view_win *w, double x, double *t);
void view_pick_prepare(view_app *a);
void view_pick_quiet(view_win *w, double x, double y);

/* view_panel.c: the side panel (issue 26, item 4) at the right of the drawing area (F9, action
 * panel), its actions, and the gestures on the colour bar, of the selected slice and of the seed
 * tool. */
void view_panel_attach(view_win *w, GtkWidget *box);
void view_panel_refresh(view_app *a);
void view_panel_free(view_app *a);
void view_panel_action(view_app *a, GSimpleAction *act, GVariant *v);
void view_panel_marks(view_win *w, const thx_picture_opts *o, thx_raster *img);
int view_panel_drag_begin(view_win *w, double x, double y, GdkModifierType m, guint button);
void view_panel_drag_update(view_win *w, double dx, double dy);
void view_panel_drag_end(view_win *w, double dx, double dy);
int view_panel_click(view_win *w, double x, double y);
#endif
