/*
 * thorax/view/view.h — the interactive viewer (`thorax view`; paper 4.2 "Interactive Viewing of
 * the Results", 3.2 "Manual editing", 3.4): windows of linked surfaces drawn by the picture module
 * (thorax/picture/picture.h) in GTK 4 (GtkGLArea), frames stepped in step across surfaces and
 * windows, real-time rotation, zoom and clipping, picking with the node's time signal, and every
 * action a GAction that menus, keys and script lines call alike.
 *
 * The only module that links a toolkit (GTK 4): a library of its own (CMake target thorax_view).
 */
#ifndef THORAX_VIEW_H
#define THORAX_VIEW_H
#include <string.h>

#include "thorax/picture/picture.h"
#ifdef __cplusplus
extern "C" {
#endif

#define THX_VIEW_MAX_WINDOWS 16

/* Applies one option line of a script to a picture's settings (the caller's option table, so a
 * script holds the very options of the command line): 0, or nonzero after reporting the error. */
typedef int (*thx_view_option_fn)(void *user, thx_picture_opts *o, const char *line);

typedef struct {
    thx_picture_opts pic;   /* the settings every window starts from (data already named there) */
    int frame;              /* the first frame shown, 0-based */
    /* windows: each a comma-separated list of surface names (NULL entries: none given, one window
       with every surface); separate: one window per surface */
    const char *windows[THX_VIEW_MAX_WINDOWS];
    int n_windows;
    int separate;
    int win_w, win_h;       /* the drawing area of each window, pixels (before GDK_SCALE) */
    double rate;            /* frames per second when playing */
    int loop;               /* playing wraps around */
    int step;               /* frames per step of the arrow keys */
    int play;               /* start playing */
    const char **lines;     /* the script lines run once the windows are up (after its leading options; the
                               caller's array) */
    int n_lines;
    /* tracing (issue 26; thorax/digitizer/session.h): with `image` and no model, or trace_on, a slice
       pane beside the 3D view where loops are traced on the image's axial planes; trace_names: the
       surfaces offered (NAME[:ROLE]; none: torso, fat, muscle, lungs, heart); trace_contours: a contour
       file traced on this image to go on with */
    int trace_on;
    const char *trace_names[16];
    int n_trace_names;
    const char *trace_contours;
    const char *script;     /* the script's path (messages) */
    int script_line0;       /* the line number of lines[0] in it */
    thx_view_option_fn option_fn; /* applies a script's option line; NULL: option lines refused */
    void *option_user;
    const char *command_line; /* for "save session" (provenance comment) */
    int verbose;
} thx_view_opts;

/* The defaults: the picture's, 800x800, 25 frames a second, looping, one frame a step. */
static inline void thx_view_opts_default(thx_view_opts *o)
{
    memset(o, 0, sizeof *o);
    thx_picture_opts_default(&o->pic);
    o->win_w = 800;
    o->win_h = 800;
    o->rate = 25;
    o->loop = 1;
    o->step = 1;
}

/* Loads the data (thx_picture_load), opens the windows and runs until the last window closes or a
 * `quit` action. Returns the process exit status: 0, or 1 after an error (reported through ctx's
 * log and message), e.g. no display, or a script line that fails. */
int thx_view_run(thx_ctx *ctx, thx_view_opts *o);

#ifdef __cplusplus
}
#endif
#endif
