/* What thorax render (cmd_render.c) and thorax animate (cmd_animate.c) share: the options of a
 * picture, the data bound to the surfaces, one frame drawn. */
#ifndef THORAX_CLI_RENDER_H
#define THORAX_CLI_RENDER_H
#include <stddef.h>

#include "cli/options.h"
#include "thorax/render/image.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/render/render.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
enum { SCOPE_FRAME, SCOPE_SERIES, SCOPE_ALL, SCOPE_FIXED };

typedef struct {
    const char *model_dir, *solution, *data, *data_surface, *out, *font, *trace, *arrows;
    const char *files[16];  /* surface files drawn without a model (any format thorax import reads) */
    const char *channels;   /* map3d .channels: node i of the data surface takes recording channel c */
    int n_files;
    int w, h, frame, first, last, fps;
    int view;               /* a thx_view */
    int have_camera;
    thx_camera cam;
    /* the anatomical frame: canonical axis k (0 the subject's right, 1 anterior, 2 cranial) is
       sg[k] times model axis ax[k] (default x, y, z; --up and --front change it) */
    int ax[3];
    double sg[3];
    const char *up_spec, *front_spec;
    int mode;               /* a thx_draw_mode */
    int style;              /* a thx_data_style */
    int levels;
    int cmap;               /* a thx_colormap */
    int model;              /* a thx_scale_model */
    int scope, symmetric;
    double lo, hi;
    char clip[64];
    int colorbar, label, panels;
    const char *only[16];
    int n_only;
    const char *whole[16];  /* --no-clip NAME: left whole by the clip plane */
    int n_whole;
    struct surf_look {      /* --surface NAME=MODE[:OPACITY[:#RRGGBB]] */
        char name[64];
        thx_draw_mode mode;
        float opacity;      /* < 0: the default */
        int have_color;
        float color[3];
    } look[16];
    int n_look;
    double arrow_spacing, arrow_scale;
    int arrow_max, arrow_unit;
    double arrow_gap;          /* minimum distance between arrows (mm), 0: none */
    int have_box;
    double box[6];             /* arrows only inside x0 y0 z0 x1 y1 z1 */
    const char *arrow_region;  /* arrows only at nodes of this tissue region */
    int verbose;
    const char *cmd;           /* "render" or "animate" (usage errors) */
} ropts;

/* ---- data bound to surfaces ---- */
typedef struct {
    thx_model *m;
    thx_series *series[64];   /* per surface, or NULL */
    thx_series *ecg;          /* 12-lead (trace) */
    thx_series *currents;     /* currents_node, for arrows */
    thx_series *volume;       /* volume potentials (unused for now) */
    char ecg_names[12][8];
    double smin[64], smax[64]; /* finite range of each surface's whole series (computed once) */
    unsigned char sranged[64];
    const thx_series *trace;  /* the series --trace draws from (not owned), its row and label */
    size_t trace_row;
    char trace_label[96];
} rdata;

/* The options' defaults (800x800, anterior, gouraud, ecg, ...); o->cmd is left NULL. */
void render_opts_default(ropts *o);
/* The options render and animate share (what is drawn, and how), into t[N_RENDER_OPTS], their values
 * into o; returns their count. Their callbacks and render_positional take o as the user pointer. */
#define N_RENDER_OPTS 36
size_t render_options(cli_opt *t, ropts *o);
/* cli_command.positional: the model directory, or a surface file (at most 16). */
int render_positional(void *user, const char *a);
/* Reads the data (d, zeroed first), settles the views' frame, creates the renderer, the image and
 * (for annotations) the font. */
thx_status render_setup(thx_ctx *ctx, ropts *o, rdata *d, thx_renderer **rr, thx_font **font, thx_image **img);
/* Draws frame (0-based) into img; *nan_total counts the values that are not numbers. */
thx_status render_frame(thx_ctx *ctx, const ropts *o, rdata *d, thx_renderer *rr, thx_font *font, int frame,
                        thx_image *img, size_t *nan_total);
/* The column of the solution's currents_node at the time of frame, or -1. */
long render_currents_column(const rdata *d, int frame);
void render_data_free(rdata *d);
#endif
