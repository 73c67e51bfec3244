/*
 * thorax render: batch pictures of models and potentials (paper 4.2), headless; the options,
 * data and drawing it shares with thorax animate (cmd_animate.c, cli/render_cli.h).
 */
#include <assert.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "cli/render_cli.h"
#include "cli/cli_share.h"
#include "cli/cli_raytrace.h"
#include "cli/cli_bad_leads.h"
#include "thorax/core/fileio.h"
#include "thorax/render/image.h"
#include "thorax/import/import.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/render/render.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
#include "thorax/picture/picture.h"

/* ---- the options of render and animate ---- */

/* A positional argument: the model directory, or a surface file (a model of its own surfaces).
 * 0, or -1 for a second directory, a directory beside files, or too many files. */
static int positional(ropts *o, const char *a)
{
    struct stat sb;
    int dir = stat(a, &sb) == 0 && S_ISDIR(sb.st_mode);
    if (dir) {
        if (o->p.model_dir || o->p.n_files) return -1;
        o->p.model_dir = a;
        return 0;
    }
    if (o->p.model_dir || o->p.n_files >= 16) return -1;
    o->p.files[o->p.n_files++] = a;
    return 0;
}

void render_opts_default(ropts *o)
{
    memset(o, 0, sizeof *o);
    thx_picture_opts_default(&o->p);
    o->last = -1;
    o->fps = 25;
}

/* --surface NAME=MODE[:OPACITY[:#RRGGBB]]; 0, or 2 after printing the usage error */
static int parse_look(void *user, const cli_opt *opt, const char *spec)
{
    ropts *o = user;
    const char *cmd = o->cmd;
    if (o->p.n_look >= 16) { cli_usage_error(cmd, "--surface: at most 16"); return 2; }
    thx_picture_look *l = &o->p.look[o->p.n_look];
    memset(l, 0, sizeof *l);
    l->opacity = -1;
    char buf[160];
    snprintf(buf, sizeof buf, "%s", spec);
    char *eq = strchr(buf, '=');
    if (!eq || eq == buf || eq - buf >= (long)sizeof l->name) {
        cli_usage_error(cmd, "--surface '%s': give NAME=MODE[:OPACITY[:#RRGGBB]]", spec);
        return 2;
    }
    *eq = '\0';
    memcpy(l->name, buf, (size_t)(eq - buf) + 1);
    char *mode = eq + 1, *op = strchr(mode, ':'), *col = NULL;
    if (op) { *op++ = '\0'; col = strchr(op, ':'); if (col) *col++ = '\0'; }
    l->style = -1;
    static const char *styles_words[] = {"continuous", "bands", "contours", "bands+contours", "continuous+contours"};
    for (int k = 0; k < 5; k++)
        if (!strcmp(mode, styles_words[k])) { l->style = k; l->mode = THX_DRAW_GOURAUD; }
    if (l->style < 0 && thx_picture_mode_parse(mode, &l->mode)) {
        cli_usage_error(cmd, "--surface '%s': mode '%s' is not hidden, points, wire, flat, gouraud, phong, orientation, or a data style "
                                  "(continuous, bands, contours, bands+contours, continuous+contours)", spec, mode);
        return 2;
    }
    if (op && *op) {
        char *end;
        double a = strtod(op, &end);
        if (*end || !(a >= 0 && a <= 1)) { cli_usage_error(cmd, "--surface '%s': opacity '%s' is not a number in 0..1", spec, op); return 2; }
        l->opacity = (float)a;
    }
    if (col) {
        const char *h = col[0] == '#' ? col + 1 : col;
        unsigned rgb;
        int used = 0;
        if (strlen(h) != 6 || sscanf(h, "%6x%n", &rgb, &used) != 1 || used != 6) {
            cli_usage_error(cmd, "--surface '%s': colour '%s' is not #RRGGBB", spec, col);
            return 2;
        }
        l->color[0] = (float)((rgb >> 16) & 255) / 255.0f;
        l->color[1] = (float)((rgb >> 8) & 255) / 255.0f;
        l->color[2] = (float)(rgb & 255) / 255.0f;
        l->have_color = 1;
    }
    o->p.n_look++;
    return 0;
}

int render_positional(void *user, const char *a)
{
    ropts *o = user;
    if (positional(o, a)) return cli_usage_error(o->cmd, "'%s': give one model directory, or surface files (at most 16)", a);
    return 0;
}

static int parse_size(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    long w, h;
    if (cli_parse_pair(v, 'x', 16, 8192, &w, &h)) return cli_usage_error(o->cmd, "--size WxH (16..8192)");
    o->p.w = (int)w;
    o->p.h = (int)h;
    return 0;
}

static int parse_camera(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    thx_camera *c = &o->p.cam;
    c->height = 0;
    int got = sscanf(v, "%lf,%lf,%lf:%lf,%lf,%lf:%lf,%lf,%lf:%lf:%lf", &c->eye[0], &c->eye[1], &c->eye[2], &c->center[0],
                     &c->center[1], &c->center[2], &c->up[0], &c->up[1], &c->up[2], &c->fov_deg, &c->height);
    if (got < 10 || !(c->fov_deg >= 0 && c->fov_deg < 180) || (c->fov_deg == 0 && !(c->height > 0)))
        return cli_usage_error(o->cmd, "--camera EX,EY,EZ:CX,CY,CZ:UX,UY,UZ:FOV[:HEIGHT] (FOV in degrees, 0 for orthographic "
                                       "with the visible HEIGHT in mm)");
    o->p.have_camera = 1;
    return 0;
}

static int parse_scope(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    if (!strcmp(v, "frame")) o->p.scope = THX_SCOPE_FRAME;
    else if (!strcmp(v, "series")) o->p.scope = THX_SCOPE_SERIES;
    else if (!strcmp(v, "all")) o->p.scope = THX_SCOPE_ALL;
    else if (!strcmp(v, "surfaces")) o->p.scope = THX_SCOPE_SURFACES;
    else if (sscanf(v, "fixed:%lf:%lf", &o->p.lo, &o->p.hi) == 2 && o->p.lo < o->p.hi) o->p.scope = THX_SCOPE_FIXED;
    else return cli_usage_error(o->cmd, "--scope: frame, series, surfaces, all, or fixed:LO:HI");
    return 0;
}

static int parse_clip_option(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    snprintf(o->p.clip, sizeof o->p.clip, "%s", v);
    return 0;
}

static int parse_axis_option(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    int axis;
    double sign;
    if (!strcmp(opt->name, "--up")) o->p.up_spec = v;
    else o->p.front_spec = v;
    if (thx_picture_axis_parse(v, &axis, &sign)) return cli_usage_error(o->cmd, "%s: an axis: +x, -x, +y, -y, +z or -z", opt->name);
    return 0;
}

static int set_arrows(void *user, const cli_opt *opt, const char *v)
{
    ((ropts *)user)->p.arrows = "node";
    return 0;
}

static int parse_box(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    double *b = o->p.box;
    if (sscanf(v, "%lf:%lf:%lf:%lf:%lf:%lf", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) != 6 || b[0] >= b[3] ||
        b[1] >= b[4] || b[2] >= b[5])
        return cli_usage_error(o->cmd, "--arrow-box X0:Y0:Z0:X1:Y1:Z1 (mm, low corner then high)");
    o->p.have_box = 1;
    return 0;
}

/* --image-level L: the image's grey level centre (any finite value; given: not the image's default). */
static int parse_level(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    char *end = NULL;
    double x = strtod(v, &end);
    if (!end || end == v || *end || !isfinite(x))
        return cli_usage_error(o->cmd, "--image-level L: the grey level's centre, a number in the image's values");
    o->p.level = x;
    o->p.have_level = 1;
    return 0;
}

/* --channels FILE: the channels of the --data given last (before any --data: the first), one each. */
static int pair_channels(void *user, const cli_opt *opt, const char *v)
{
    ropts *o = user;
    int k = o->p.n_data ? o->p.n_data - 1 : 0;
    if (o->p.data_channels[k])
        return cli_usage_error(o->cmd, "--channels %s: data set %d (%s) has its channels already (%s); give each --data its "
                                       "--channels after it", v, k + 1, o->p.n_data ? o->p.data[k] : "the first --data",
                               o->p.data_channels[k]);
    o->p.data_channels[k] = v;
    o->p.n_channels++;
    if (!o->p.channels) o->p.channels = v;
    return 0;
}

static const cli_choice views[] = {{"anterior", THX_VIEW_ANTERIOR}, {"posterior", THX_VIEW_POSTERIOR},
                                   {"left", THX_VIEW_LEFT},         {"right", THX_VIEW_RIGHT},
                                   {"superior", THX_VIEW_SUPERIOR}, {"inferior", THX_VIEW_INFERIOR},
                                   {NULL, 0}};
static const cli_choice modes[] = {{"hidden", THX_DRAW_HIDDEN}, {"points", THX_DRAW_POINTS},   {"wire", THX_DRAW_WIRE},
                                   {"flat", THX_DRAW_FLAT},     {"gouraud", THX_DRAW_GOURAUD}, {"phong", THX_DRAW_PHONG},
                                   {"orientation", THX_DRAW_ORIENTATION}, {NULL, 0}};
static const cli_choice styles[] = {{"continuous", THX_DATA_CONTINUOUS}, {"bands", THX_DATA_BANDS},
                                    {"contours", THX_DATA_CONTOURS},     {"bands+contours", THX_DATA_BANDS_CONTOURS},
                                    {"continuous+contours", THX_DATA_CONTINUOUS_CONTOURS}, {NULL, 0}};
static const cli_choice cmaps[] = {{"ecg", THX_CMAP_ECG},         {"ecg-green", THX_CMAP_ECG_GREEN},
                                   {"coolwarm", THX_CMAP_COOLWARM}, {"viridis", THX_CMAP_VIRIDIS},
                                   {"gray", THX_CMAP_GRAY},       {"jet", THX_CMAP_JET}, {NULL, 0}};
static const cli_choice scales[] = {{"linear", THX_SCALE_LINEAR}, {"log", THX_SCALE_LOG}, {"exp", THX_SCALE_EXP},
                                    {"lab7", THX_SCALE_LAB7}, {"lab13", THX_SCALE_LAB13}, {NULL, 0}};
static const cli_choice mappings[] = {{"true", THX_MAPPING_TRUE}, {"symmetric", THX_MAPPING_SYMMETRIC},
                                      {"midpoint", THX_MAPPING_MIDPOINT}, {"separate", THX_MAPPING_SEPARATE}, {NULL, 0}};

size_t render_options(cli_opt *t, ropts *o)
{
    size_t n = 0;
    t[n++] = (cli_opt){.name = "--solution", .type = CLI_INPUT, .meta = "DIR", .s = &o->p.solution,
                       .help = "a thorax forward solution: its model, the torso potentials (and the heart's, when the "
                               "epicardial series is still where the solution says)"};
    t[n++] = (cli_opt){.name = "--data", .type = CLI_INPUT, .meta = "SERIES", .flags = CLI_REPEAT, .sv = o->p.data,
                       .count = &o->p.n_data, .max = THX_PICTURE_MAX,
                       .help = "per-node values of one surface (rows = its nodes), any series format; repeat for more data "
                               "sets (a surface shows the last given; the viewer steps through them)"};
    t[n++] = (cli_opt){.name = "--data-surface", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT,
                       .sv = o->p.data_surface, .count = &o->p.n_data_surface, .max = THX_PICTURE_MAX,
                       .help = "the surface the k-th --data belongs to (the k-th --data-surface), when several have that many "
                               "nodes"};
    t[n++] = (cli_opt){.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .flags = CLI_REPEAT, .fn = pair_channels,
                       .help = "map3d .channels of the --data it follows (before any --data: the first): that data "
                               "set's rows are recording channels, node i takes channel c; repeat for more data sets"};
    t[n++] = (cli_opt)CLI_BAD_LEADS_OPT(&o->p.bad_leads, "filled by Laplacian interpolation on the --data's surface");
    t[n++] = (cli_opt){.name = "--size", .type = CLI_STRING, .meta = "WxH", .fn = parse_size, .def = "800x800",
                       .unit = "pixels", .help = "image size, 16 to 8192 each"};
    t[n++] = (cli_opt){.name = "--view", .type = CLI_CHOICE, .meta = "V", .choices = views, .i = &o->p.view,
                       .help = "anterior, posterior, left, right, superior or inferior, in the model's frame"};
    t[n++] = (cli_opt){.name = "--up", .type = CLI_STRING, .meta = "AXIS", .fn = parse_axis_option,
                       .def = "the model's frame, model.json \"frame\"",
                       .help = "the model's cranial axis for the views and clip sides: +x, -x, +y, -y, +z or -z (a "
                               "model without a frame needs --up and --front for a named view or clip side; surface "
                               "files without them are drawn as +z and +y, with a warning)"};
    t[n++] = (cli_opt){.name = "--front", .type = CLI_STRING, .meta = "AXIS", .fn = parse_axis_option,
                       .def = "the model's frame", .help = "the model's anterior axis, as --up"};
    t[n++] = (cli_opt){.name = "--camera", .type = CLI_STRING, .meta = "E:C:U:FOV[:H]", .fn = parse_camera,
                       .help = "explicit camera: eye, centre, up (x,y,z each), field of view in degrees, or 0 and the "
                               "visible height H in mm for an orthographic view"};
    t[n++] = (cli_opt){.name = "--mode", .type = CLI_CHOICE, .meta = "M", .choices = modes, .i = &o->p.mode,
                       .help = "hidden, points, wire, flat, gouraud, phong, or orientation (the paper's check: "
                               "triangles only where their outward side faces the viewer, the nodes behind as points)"};
    t[n++] = (cli_opt){.name = "--surface", .type = CLI_STRING, .meta = "NAME=M[:OPACITY[:#RRGGBB]]",
                       .flags = CLI_REPEAT, .fn = parse_look,
                       .help = "one surface's mode (as --mode, or a data style as --style: the surface's data drawn so), "
                               "opacity and colour (a surface with data keeps the colour "
                               "map); at most 16"};
    t[n++] = (cli_opt){.name = "--only", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = o->p.only,
                       .count = &o->p.n_only, .max = 16, .help = "draw only these surfaces"};
    t[n++] = (cli_opt){.name = "--panels", .type = CLI_FLAG, .i = &o->p.panels, .help = "a grid of panels, one per surface"};
    t[n++] = (cli_opt){.name = "--style", .type = CLI_CHOICE, .meta = "S", .choices = styles, .i = &o->p.style,
                       .help = "continuous, bands, contours, bands+contours or continuous+contours"};
    t[n++] = (cli_opt){.name = "--levels", .type = CLI_INT, .meta = "N", .i = &o->p.levels, .rule = CLI_GE | CLI_LE,
                       .lo = 2, .hi = 64, .bad = "--levels: 2..64", .help = "shades / contour levels, 2 to 64"};
    t[n++] = (cli_opt){.name = "--cmap", .type = CLI_CHOICE, .meta = "C", .choices = cmaps, .i = &o->p.cmap,
                       .help = "ecg (red positive, blue negative, white zero), ecg-green, coolwarm (perceptually "
                               "uniform, diverging), viridis, gray or jet"};
    t[n++] = (cli_opt){.name = "--scale", .type = CLI_CHOICE, .choices = scales, .i = &o->p.model,
                       .help = "the scaling model from values to colours: linear, log, exp, or map3d's lab7 and lab13 "
                               "standards (levels 1, 1.5, 2.2, 3.3, 4.7, 6.8 or the 13-step series, times powers of ten; "
                               "they fix the number of bands)"};
    t[n++] = (cli_opt){.name = "--scope", .type = CLI_STRING, .meta = "S", .fn = parse_scope, .def = "series",
                       .help = "the range the colours span: frame (this frame), series (all frames of the surface), "
                               "surfaces (this frame of all surfaces), all (all frames of all surfaces), or fixed:LO:HI"};
    t[n++] = (cli_opt){.name = "--scale-group", .type = CLI_STRING, .meta = "A,B,...", .flags = CLI_REPEAT,
                       .sv = o->p.groups, .count = &o->p.n_groups, .max = THX_PICTURE_MAX,
                       .help = "these surfaces share one scale (the frame and series scopes span them together)"};
    t[n++] = (cli_opt){.name = "--slave", .type = CLI_STRING, .meta = "NAME=MASTER", .flags = CLI_REPEAT,
                       .sv = o->p.slaves, .count = &o->p.n_slaves, .max = THX_PICTURE_MAX,
                       .help = "surface NAME is drawn with surface MASTER's scale"};
    t[n++] = (cli_opt){.name = "--invert", .type = CLI_FLAG, .i = &o->p.invert,
                       .help = "the colour map reversed (high values in the low colours)"};
    t[n++] = (cli_opt){.name = "--mapping", .type = CLI_CHOICE, .choices = mappings, .i = &o->p.mapping,
                       .help = "how the range meets the colours: true (min..max), symmetric about zero, midpoint "
                               "(symmetric about the middle of min..max), separate (negative and positive values each "
                               "over their own half of the colours, zero always the middle colour)"};
    t[n++] = (cli_opt){.name = "--true-range", .type = CLI_SET, .i = &o->p.mapping, .ival = THX_MAPPING_TRUE,
                       .help = "the same as --mapping true"};
    t[n++] = (cli_opt){.name = "--symmetric", .type = CLI_SET, .i = &o->p.mapping, .ival = THX_MAPPING_SYMMETRIC,
                       .help = "the same as --mapping symmetric (the default)"};
    t[n++] = (cli_opt){.name = "--clip", .type = CLI_STRING, .meta = "SIDE[:F]|PLANE", .fn = parse_clip_option,
                       .help = "remove a side (anterior, posterior, left, right, superior, inferior) from fraction F of "
                               "the depth (default 0.5), or cut by a plane nx,ny,nz,d (keeps n.x + d >= 0)"};
    t[n++] = (cli_opt){.name = "--no-clip", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = o->p.whole,
                       .count = &o->p.n_whole, .max = 16,
                       .help = "this surface is left whole by the clip plane (e.g. the heart inside an opened chest)"};
    t[n++] = (cli_opt){.name = "--colorbar", .type = CLI_FLAG, .i = &o->p.colorbar,
                       .help = "a colour bar per distinct colour scale shown (at most 4; a picture with more is refused), "
                               "with its values, title and unit, and the surfaces it serves when there are several"};
    t[n++] = (cli_opt){.name = "--bar-title", .type = CLI_STRING, .meta = "TEXT", .flags = CLI_REPEAT,
                       .sv = o->p.bar_title, .count = &o->p.n_bar_title, .max = THX_PICTURE_BARS,
                       .def = "what is shown: potential, activation, |J|",
                       .help = "the colour bar's title; given once, every bar's; repeated, the k-th bar's (the body "
                               "surface's first)"};
    t[n++] = (cli_opt){.name = "--bar-unit", .type = CLI_STRING, .meta = "UNIT", .flags = CLI_REPEAT,
                       .sv = o->p.bar_unit, .count = &o->p.n_bar_unit, .max = THX_PICTURE_BARS, .def = "the data's",
                       .help = "the colour bar's unit, as --bar-title"};
    t[n++] = (cli_opt){.name = "--orientation", .type = CLI_FLAG, .i = &o->p.orientation,
                       .help = "orientation letters at the middle of each edge of every panel: the anatomical "
                               "directions (R/L the subject's right/left, A/P, S/I) toward that edge for the camera "
                               "and the model's frame (two or three letters for an oblique camera)"};
    t[n++] = (cli_opt){.name = "--label", .type = CLI_FLAG, .i = &o->p.label, .help = "the time and frame"};
    t[n++] = (cli_opt){.name = "--node-labels", .type = CLI_STRING, .meta = "SURFACE=index|channel|value",
                       .flags = CLI_REPEAT, .sv = o->p.labels, .count = &o->p.n_labels, .max = THX_PICTURE_MAX,
                       .help = "the surface's nodes seen from the camera labelled with their number (1-based), recording "
                               "channel (--channels) or value, where the labels do not overlap"};
    t[n++] = (cli_opt){.name = "--landmarks", .type = CLI_INPUT, .meta = "FILE.lmarks", .flags = CLI_REPEAT,
                       .sv = o->p.landmarks, .count = &o->p.n_landmarks, .max = THX_PICTURE_MAX,
                       .help = "map3d landmarks drawn with the surfaces: coronary arteries as tubes, sites and leads as "
                               "spheres, in their colours, never clipped"};
    t[n++] = (cli_opt){.name = "--electrodes", .type = CLI_INPUT, .meta = "FILE", .flags = CLI_REPEAT,
                       .sv = o->p.electrodes, .count = &o->p.n_electrodes, .max = THX_PICTURE_MAX,
                       .help = "an electrode file (thorax electrodes: MODEL/electrodes/12lead.txt, array.txt): each "
                               "electrode a green sphere with its name, never clipped"};
    t[n++] = (cli_opt){.name = "--tetrahedra", .type = CLI_FLAG, .i = &o->p.tetrahedra,
                       .help = "the volume mesh: the tetrahedra wholly on the kept side of --clip (all without it), "
                               "faces coloured by tissue region (1 tan, 2 blue, 3 red, 4 green, 5 violet, 6 yellow, "
                               "7 cyan, 8 grey, then again), edges dark"};
    t[n++] = (cli_opt){.name = "--activation", .type = CLI_STRING, .meta = "SURFACE[:T0:T1]", .flags = CLI_REPEAT,
                       .sv = o->p.activation, .count = &o->p.n_activation, .max = THX_PICTURE_MAX,
                       .help = "the surface's activation-time map (each node's steepest downstroke, between T0 and T1 "
                               "in the data's time unit) instead of its potentials; without T0:T1 the record's own "
                               "activation fiducials (act), else its QRS (qon..soff fiducials), else one beat found on "
                               "the RMS curve, as the label says; isochrones with --style contours"};
    t[n++] = (cli_opt){.name = "--recovery", .type = CLI_STRING, .meta = "SURFACE[:T0:T1]", .flags = CLI_REPEAT,
                       .sv = o->p.recovery, .count = &o->p.n_recovery, .max = THX_PICTURE_MAX,
                       .help = "the surface's recovery-time map (each node's steepest T-wave upstroke after its "
                               "activation; T0:T1 the T wave) instead of its potentials; without T0:T1 the record's "
                               "rec fiducials, else the T wave of the beat --activation would take"};
    t[n++] = (cli_opt){.name = "--extrema", .type = CLI_FLAG, .i = &o->p.extrema,
                       .help = "marks at the largest and smallest value of each surface's data (grey when behind)"};
    t[n++] = (cli_opt){.name = "--trace", .type = CLI_STRING, .meta = "T", .s = &o->p.trace,
                       .help = "a signal under the picture with a marker at the frame: an ECG lead (I..V6, from the "
                               "solution's ecg12), or SURFACE:NODE / NODE (1-based) of the data"};
    t[n++] = (cli_opt){.name = "--isosurface", .type = CLI_STRING, .meta = "VALUES", .s = &o->p.isosurface,
                       .help = "equipotential surfaces from --solution's volume potentials (thorax forward --volume): "
                               "values '-0.5,0,0.5' ('0' is the zero equipotential), a count 'count:5' (evenly inside the scale's range, "
                               "ends excluded), or percentages of the scale's range '25%,75%'; "
                               "drawn translucent as the surface 'equipotentials'"};
    t[n++] = (cli_opt){.name = "--slice", .type = CLI_STRING, .meta = "PLANE", .flags = CLI_REPEAT, .sv = o->p.slices,
                       .count = &o->p.n_slices, .max = 8,
                       .help = "a plane through the volume coloured by potential (with --style's bands or contour "
                               "lines): x=MM, y=MM, z=MM or PX,PY,PZ:NX,NY,NZ; the surface 'slices'; at most 8"};
    t[n++] = (cli_opt){.name = "--slice-current", .type = CLI_FLAG, .i = &o->p.slice_current,
                       .help = "colour the slices by |J| per tetrahedron (their own bar) instead of the potential"};
    t[n++] = (cli_opt){.name = "--streamlines", .type = CLI_STRING, .meta = "SEEDS", .flags = CLI_REPEAT,
                       .sv = o->p.streamlines, .count = &o->p.n_streamlines, .max = 4,
                       .help = "current streamlines from --solution's volume potentials, traced both ways from the seeds "
                               "point:X,Y,Z, line:X,Y,Z:X,Y,Z:N, sphere:X,Y,Z:R:N, region:NAME:N (on the heart's "
                               "surface for the heart) or density:N; tubes named 'streamlines', coloured by |J|; at most 4"};
    t[n++] = (cli_opt){.name = "--stream-radius", .type = CLI_REAL, .meta = "MM", .d = &o->p.stream_radius,
                       .unit = "mm", .rule = CLI_GT, .bad = "--stream-radius must be positive (mm)",
                       .def = "0.4% of the model's diagonal", .help = "the streamline tubes' radius"};
    t[n++] = (cli_opt){.name = "--stream-potential", .type = CLI_FLAG, .i = &o->p.stream_potential,
                       .help = "colour the streamlines by the potential (the equipotentials' scale) instead of |J|"};
    t[n++] = (cli_opt){.name = "--image", .type = CLI_INPUT, .meta = "IMG", .s = &o->p.image,
                       .help = "the scan under the model: an image (.nii, .nii.gz, and the formats thorax image reads) "
                               "in the model's coordinates (RAS mm, as a model built from it), its --image-plane drawn "
                               "with the surfaces in grey levels (an opaque surface in front hides it, a translucent one "
                               "shows it through)"};
    t[n++] = (cli_opt){.name = "--image-plane", .type = CLI_STRING, .meta = "AXIS=POS", .flags = CLI_REPEAT,
                       .sv = o->p.image_planes, .count = &o->p.n_image_planes, .max = 4,
                       .def = "the axial plane through the image's middle",
                       .help = "a plane of --image: z=MM (axial), y=MM (coronal), x=MM (sagittal) in RAS millimetres, or "
                               "the image's own plane k=N, j=N, i=N (0-based index); inside the image; at most 4"};
    t[n++] = (cli_opt){.name = "--image-window", .type = CLI_REAL, .meta = "W", .d = &o->p.window, .rule = CLI_GT,
                       .bad = "--image-window must be positive (in the image's values)",
                       .def = "a label map: its full range; Hounsfield units: 400; else the 1st to 99th percentile",
                       .help = "the width of the image's values spread from black to white"};
    t[n++] = (cli_opt){.name = "--image-level", .type = CLI_STRING, .meta = "L", .fn = parse_level,
                       .def = "as --image-window: the range's middle; Hounsfield units: 40",
                       .help = "the image value drawn mid-grey (grey = (value - L + W/2) / W, clamped to black..white)"};
    t[n++] = (cli_opt){.name = "--image-labels", .type = CLI_FLAG, .i = &o->p.image_labels,
                       .help = "--image is a label map: a colour per label value (0 black; 1 orange, 2 sky blue, 3 green, "
                               "4 yellow, 5 blue, 6 vermilion, 7 pink, 8 white, ... then again), nearest voxel"};
    t[n++] = (cli_opt){.name = "--contours", .type = CLI_INPUT, .meta = "FILE", .s = &o->p.contours,
                       .help = "a contour file drawn on the axial --image-plane: the loops of its layer nearest the plane "
                               "(within half the widest gap between layers), a line per loop, surface k of the file in "
                               "--image-labels' colour k"};
    t[n++] = (cli_opt){.name = "--arrows", .type = CLI_FLAG, .fn = set_arrows,
                       .help = "current density arrows (the solution's currents_node, for the frame shown)"};
    t[n++] = (cli_opt){.name = "--arrow-spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->p.arrow_spacing,
                       .rule = CLI_GE, .bad = "--arrow-spacing must be 0 (one arrow per node) or positive (mm)",
                       .note = "0: one arrow per node", .help = "arrows averaged on a grid of this spacing"};
    t[n++] = (cli_opt){.name = "--arrow-gap", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->p.arrow_gap,
                       .rule = CLI_GE, .bad = "--arrow-gap must be 0 or positive (mm)", .note = "0: none",
                       .help = "no arrow closer than this to a stronger one"};
    t[n++] = (cli_opt){.name = "--arrow-max", .type = CLI_INT, .meta = "N", .i = &o->p.arrow_max, .rule = CLI_GE, .lo = 1,
                       .bad = "--arrow-max must be at least 1", .help = "at most N arrows, the strongest"};
    t[n++] = (cli_opt){.name = "--arrow-length", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o->p.arrow_scale,
                       .rule = CLI_GT, .bad = "--arrow-length must be positive (mm)",
                       .help = "the longest arrow's length (lengths proportional to magnitude)"};
    t[n++] = (cli_opt){.name = "--arrow-unit", .type = CLI_FLAG, .i = &o->p.arrow_unit,
                       .help = "every arrow the same length, coloured by magnitude"};
    t[n++] = (cli_opt){.name = "--arrow-region", .type = CLI_STRING, .meta = "NAME", .s = &o->p.arrow_region,
                       .help = "arrows only at nodes of this tissue region"};
    t[n++] = (cli_opt){.name = "--arrow-box", .type = CLI_STRING, .meta = "X0:Y0:Z0:X1:Y1:Z1", .unit = "mm",
                       .fn = parse_box, .help = "arrows only inside this box, low corner then high"};
    t[n++] = (cli_opt){.name = "--font", .type = CLI_INPUT, .meta = "FILE", .s = &o->p.font,
                       .def = "sans-serif, through fontconfig", .help = "a TrueType font for the annotations"};
    t[n++] = (cli_opt){.name = "-v", .type = CLI_SET, .i = &o->verbose, .ival = 1, .flags = CLI_NOUSAGE,
                       .help = "more logging"};
    t[n++] = (cli_opt){.name = "-q", .type = CLI_SET, .i = &o->verbose, .ival = -1, .flags = CLI_NOUSAGE,
                       .help = "less logging"};
    assert(n <= N_RENDER_OPTS);
    return n;
}


thx_status render_setup(thx_ctx *ctx, ropts *o, thx_picture_data *d, thx_renderer **rr, thx_font **font, thx_raster **img)
{
    memset(d, 0, sizeof *d);
    o->p.frame = o->frame;
    o->p.check_frame = o->last < 0; /* animate checks its range of frames itself */
    if (cli_check_seed_counts(o->cmd, o->p.streamlines, o->p.n_streamlines))
        return thx_error(ctx, THX_EINPUT, "--streamlines: too many seeds for this machine's memory (above)");
    THX_CHECK(thx_picture_load(ctx, &o->p, d));
    THX_CHECK(thx_renderer_create(ctx, o->p.w, o->p.h, rr));
    THX_CHECK(thx_raster_create(ctx, o->p.w, o->p.h, img));
    if (o->p.colorbar || o->p.label || o->p.trace || o->p.panels || o->p.n_labels || o->p.extrema || o->p.orientation ||
        o->p.n_electrodes)
        THX_CHECK(thx_font_open(ctx, o->p.font, o->p.h / 40 > 11 ? o->p.h / 40 : 11, font));
    return THX_OK;
}

static int cmp_dbl(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* thorax render, and thorax trace (traced = 1: the ray tracer by default, with a key light casting
 * shadows and ambient occlusion unless lights are given). */
static int render_main(int argc, char **argv, int traced)
{
    ropts o;
    render_opts_default(&o);
    o.cmd = traced ? "trace" : "render";
    if (traced) {
        o.p.renderer = 1;
        o.p.rt_key = 1;
        o.p.rt.ao_samples = 8;
    }
    int repeat = 1, frame = 1;
    cli_opt own[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "IMAGE.png", .s = &o.out,
         .help = "the picture (PNG)"},
        {.name = "--frame", .type = CLI_INT, .meta = "K", .i = &frame, .rule = CLI_GE, .lo = 1, .bad = "--frame: 1, 2, ...",
         .help = "the frame, 1-based"},
        {.name = "--repeat", .type = CLI_INT, .meta = "N", .i = &repeat, .rule = CLI_GE | CLI_LE, .lo = 1, .hi = 10000,
         .bad = "--repeat: 1..10000", .help = "draw N times and print the median time a frame (benchmarks)"},
    };
    cli_opt common[N_RENDER_OPTS], rt[N_RAYTRACE_OPTS];
    cli_command cmd = {
        .name = traced ? "trace" : "render",
        .usage = "MODEL [--data [--data-surface]] [--frame] -o [options]\n"
                 "--solution [--frame] -o [options]\n"
                 "SURFACE_FILE... [--data [--channels]] [--bad-leads] [--frame] -o [options]",
        .about = traced ? "RaySpray (paper 4.3): the picture thorax render draws, ray traced with Embree:\n"
                          "the same scene, colours and annotations, with shadows (a key light above the\n"
                          "viewer's shoulder, unless --light gives others), ambient occlusion, mirror\n"
                          "reflection and refraction (--material torso=glass shows the heart through a glass\n"
                          "torso), anti-aliasing. Deterministic: the same picture for the same input on any\n"
                          "number of threads. thorax render --renderer trace is the same. Under mpirun -np N the\n"
                          "picture's tiles are dealt to the ranks and gathered by rank 0, which writes: the\n"
                          "same bytes as one process.\n"
                        : "Draws the model's surfaces, headless (EGL, OpenGL 3.3; Mesa's llvmpipe without a\n"
                          "GPU), with potentials coloured per pixel (the value interpolated, then the colour\n"
                          "looked up, so bands and contours are exact), following the field's display\n"
                          "conventions (paper 4.2). --renderer trace traces it instead (thorax trace). Under\n"
                          "mpirun -np N each rank draws a band of the picture's rows, gathered by rank 0, which\n"
                          "writes: the same bytes as one process. A --solution whose volume is in N parts\n"
                          "(thorax forward --volume on N ranks) is drawn sort-last: each rank reads and cuts its\n"
                          "part alone (slices, equipotentials, streamlines from point, line or sphere seeds;\n"
                          "opaque surfaces only), and IceT composites the\n"
                          "ranks' pictures by depth on rank 0: the same bytes as one process.\n",
        .group = {{NULL, own, sizeof own / sizeof own[0]}, {"what is drawn, and how", common, render_options(common, &o)},
                  {"ray tracing (--renderer trace)", rt, raytrace_options(rt, &o)}},
        .positional = render_positional,
        .user = &o,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    o.frame = frame - 1;
    if (o.p.volume_render && o.p.renderer != 1) return cli_usage_error(o.cmd, "--volume: volume rendering is the ray tracer's (--renderer trace, or thorax trace)");
    if (o.p.rt.shutter > 0 && o.p.renderer != 1)
        return cli_usage_error(o.cmd, "--motion-blur: motion blur is the ray tracer's (--renderer trace, or thorax trace)");
    if (!o.p.model_dir && !o.p.n_files && !o.p.solution) return cli_usage_error(o.cmd, "no model, surface file or --solution given");
    if (!o.out) return cli_usage_error(o.cmd, "no output image given (-o IMAGE.png)");
    /* under mpirun: the picture's pixels shared among the ranks (sort-first), rank 0 writes */
    int prc = cli_share_start(o.cmd, &o.verbose);
    if (prc) return prc;
    thx_ctx *ctx = cli_ctx(o.verbose);
    thx_picture_data d;
    thx_renderer *rr = NULL;
    thx_font *font = NULL;
    thx_raster *img = NULL;
    size_t nan = 0;
    double t0 = thx_wtime();
    thx_status st = render_setup(ctx, &o, &d, &rr, &font, &img);
    double *times = malloc((size_t)repeat * sizeof *times);
    if (!times) st = THX_ENOMEM;
    st = thx_picture_parts_settle(ctx, &o.p, &d, st); /* every rank draws, or none; sort-last's parts made one */
    for (int k = 0; k < repeat && st == THX_OK; k++) { /* --repeat: the same frame again, timed (benchmarks) */
        double t1 = thx_wtime();
        nan = 0;
        st = cli_share_picture(ctx, &o.p, &d, rr, font, o.frame, img, &nan);
        times[k] = thx_wtime() - t1;
    }
    int rank = thx_par_rank(), ranks = thx_par_size();
    long long rays = (long long)d.rt_stats.rays;
    if (st == THX_OK) st = thx_par_sum(ctx, &rays, 1); /* (every rank reaches it: st is agreed) */
    if (st == THX_OK && rank == 0) st = thx_raster_write_png(ctx, img, o.out);
    if (st == THX_OK && repeat > 1 && o.verbose >= 0) {
        qsort(times, (size_t)repeat, sizeof *times, cmp_dbl);
        printf("render: %d repetitions, median %.1f ms a frame (min %.1f, max %.1f), %.1f frames per second\n", repeat,
               1000 * times[repeat / 2], 1000 * times[0], 1000 * times[repeat - 1], 1.0 / times[repeat / 2]);
    }
    free(times);
    char by[48] = "";
    if (ranks > 1) snprintf(by, sizeof by, ", %d ranks", ranks);
    int rc = cli_share_end(ctx, o.cmd, st);
    if (!rc) {
        if (nan) thx_log(ctx, THX_LOG_WARN, "%zu values are not numbers (drawn in the NaN colour)", nan);
        if (o.verbose >= 0 && o.p.renderer == 1)
            printf("wrote %s (%dx%d, %.3f s%s; traced with %s: %lld rays, %.3f s)\n", o.out, o.p.w, o.p.h, thx_wtime() - t0, by,
                   thx_tracer_info(d.tracer), rays, d.rt_stats.seconds);
        else if (o.verbose >= 0)
            printf("wrote %s (%dx%d, %.3f s%s; %s)\n", o.out, o.p.w, o.p.h, thx_wtime() - t0, by, thx_renderer_info(rr));
    }
    thx_raster_destroy(&img);
    thx_font_close(&font);
    thx_renderer_destroy(&rr);
    thx_picture_data_free(&d);
    thx_ctx_destroy(&ctx);
    return rc;
}

int cmd_render(int argc, char **argv) { return render_main(argc, argv, 0); }
int cmd_trace(int argc, char **argv) { return render_main(argc, argv, 1); }
