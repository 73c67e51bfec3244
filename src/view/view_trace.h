/* The viewer's tracing (issue 26 items 1-3, 6): what view_trace.c (the session, its actions, the
 * model built while tracing, the outputs) and view_slice.c (the slice pane: drawing, mouse) share.
 * Private to src/view. */
#ifndef THORAX_VIEW_TRACE_H
#define THORAX_VIEW_TRACE_H
#include <gtk/gtk.h>

#include "thorax/digitizer/session.h"
#include "view/view_internal.h"

#define VIEW_TRACE_MAX 32

/* A traced surface as the 3D view shows it: its index in the picture's model, the loops it was
 * last built from (the session's generation), and the check's verdict. */
typedef struct {
    int model_index;        /* -1: not in the model yet */
    unsigned long built_gen;
    unsigned long long built_hash;  /* of the closed loops it was built from: an open loop's points change
                                       nothing built, and are not built again for */
    int built;              /* built at least once */
    int ok;                 /* built and passes thorax check */
    char verdict[256];      /* "passes: 12 planes, 1240 nodes", "open: ...", "one plane traced", ... */
    double build_ms;
} view_trace_surf;

typedef enum { VIEW_TOOL_POINTS = 0, VIEW_TOOL_LIVEWIRE, VIEW_TOOL_REGION } view_trace_tool;

struct view_tracing {
    thx_dig_session *s;
    const thx_image *img;           /* the picture's scan (thx_picture_scan_image) */
    char names[16][80];             /* the surfaces offered (NAME[:ROLE]), Tab cycles them */
    int n_names;
    char start[4096];               /* the contour file the session started from ("" none) */
    view_trace_surf surf[VIEW_TRACE_MAX];
    view_trace_tool tool;
    double thr_lo, thr_hi;          /* the region tool's window (have_thr 0: the grey window shown) */
    int have_thr;
    guint rebuild_id;
    /* the pane */
    GtkWidget *area;
    char orient;                    /* 'z' axial (traced on), 'y' coronal, 'x' sagittal */
    double zoom, pan[2];            /* zoom > 1 closer; pan in screen pixels */
    double cursor[3];               /* RAS: the coronal/sagittal planes pass through it */
    thx_image_slice other;          /* the coronal or sagittal plane shown */
    int have_other;
    double other_key[2];            /* its orientation and position */
    cairo_surface_t *grey;          /* the shown plane in grey levels, and what it was made for */
    double grey_key[5];
    const thx_image_slice *shown;   /* the plane drawn last (its geometry maps the mouse) */
    /* the mouse */
    double *preview;                /* the livewire's path to the pointer (RAS), drawn live */
    size_t n_preview;
    int drag_button;
    int drag_node;                  /* a node is being dragged: loop drag_loop, point drag_i */
    size_t drag_loop, drag_i;
    double drag_x0, drag_y0, drag_pan[2], drag_window, drag_level;
    double drag_at[2];              /* the dragged node's position now (RAS x, y) */
};

/* view_trace.c (also view_internal.h: open, close, install, line, help) */
/* The model's surfaces rebuilt from the loops that changed, at once. */
void view_trace_rebuild_now(view_app *a);

/* view_slice.c */
GtkWidget *view_slice_new(view_app *a);
void view_slice_redraw(view_app *a);
/* The pane drawn into cr (W x H: the pane's size, which its geometry takes). */
void view_slice_draw(view_app *a, cairo_t *cr, int W, int H);
/* The pane as drawn now, into a PNG (cairo); 0, or -1. */
int view_slice_png(view_app *a, const char *path);
#endif
