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
#include "thorax/picture/picture.h"
/* The command line of render and animate: a picture's settings, and what the command does with it. */
typedef struct {
    thx_picture_opts p;
    const char *out;
    int frame, first, last, fps;
    int verbose;
    const char *cmd;           /* "render" or "animate" (usage errors) */
} ropts;

/* The options' defaults (800x800, anterior, gouraud, ecg, ...); o->cmd is left NULL. */
void render_opts_default(ropts *o);
/* The options render and animate share (what is drawn, and how), into t[N_RENDER_OPTS], their values
 * into o; returns their count. Their callbacks and render_positional take o as the user pointer. */
#define N_RENDER_OPTS 66
size_t render_options(cli_opt *t, ropts *o);
/* cli_command.positional: the model directory, or a surface file (at most 16). */
int render_positional(void *user, const char *a);
/* Reads the data (d, zeroed first), settles the views' frame, creates the renderer, the image and
 * (for annotations) the font. */
thx_status render_setup(thx_ctx *ctx, ropts *o, thx_picture_data *d, thx_renderer **rr, thx_font **font, thx_raster **img);
#endif
