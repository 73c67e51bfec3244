/*
 * thorax/picture/picture.h — a picture of a model and its data (paper 4.2): which surfaces, how
 * each is drawn, the data bound to them and the scale of each, the camera and clip plane in the
 * model's anatomical frame, and the annotations (colour bar, time label, a signal trace).
 *
 * One code for every picture thorax makes: `thorax render` and `thorax animate` draw it offscreen
 * (thx_picture_draw), `thorax view` draws the same scene into its window (thx_picture_draw_gl, then
 * thx_picture_annotate over the pixels), so a window shows what `thorax render` writes from the
 * same settings.
 */
#ifndef THORAX_PICTURE_H
#define THORAX_PICTURE_H
#include <stddef.h>

#include "thorax/model/model.h"
#include "thorax/model/electrodes.h"
#include "thorax/model/contours.h"
#include "thorax/geom/landmark_mesh.h"
#include "thorax/model/series.h"
#include "thorax/render/image.h"
#include "thorax/render/render.h"
#include "thorax/raytrace/raytrace.h"
#include "thorax/field/streamline.h"
#ifdef __cplusplus
extern "C" {
#endif

/* The range a surface's colours span (paper 4.2: "based on the current data frame or in some
 * larger context, or even set directly by the user"). */
typedef enum {
    THX_SCOPE_FRAME = 0, /* this frame of this surface */
    THX_SCOPE_SERIES,    /* all frames of this surface */
    THX_SCOPE_ALL,       /* all frames of all surfaces with data */
    THX_SCOPE_FIXED,     /* lo..hi as given */
    THX_SCOPE_SURFACES   /* this frame of all surfaces with data */
} thx_scope;

/* One surface's look (--surface NAME=MODE[:OPACITY[:#RRGGBB]]; MODE also a data style: bands,
 * contours, ... draw the surface's data so, shaded). */
typedef struct {
    char name[64];
    thx_draw_mode mode;
    int style;          /* a thx_data_style for this surface's data, or -1: the picture's */
    float opacity;      /* < 0: the default */
    int have_color;
    float color[3];
} thx_picture_look;

#define THX_PICTURE_MAX 16 /* files, --only, --surface, --no-clip entries */
#define THX_PICTURE_BARS 4 /* colour bars beside a picture, at most */

/* The settings of a picture: what `thorax render` takes on its command line (docs/cli.md), which
 * the viewer changes as it runs. Plain data; thx_picture_opts_default fills the defaults. Strings
 * are not owned. */
typedef struct {
    const char *model_dir, *solution, *font, *trace, *arrows;
    /* data sets: each series given (rows = a surface's nodes) goes to data_surface[k] when given,
       else to the one surface with that many nodes; a surface may hold several, the last shown */
    const char *data[THX_PICTURE_MAX];
    int n_data;
    const char *data_surface[THX_PICTURE_MAX];
    int n_data_surface;
    const char *files[THX_PICTURE_MAX]; /* surface files drawn without a model (any format thorax import reads) */
    const char *channels;   /* map3d .channels: node i of the data surface takes recording channel c (the first
                               given; with n_channels == 0, every data set's) */
    /* the channels file of each data set (data_channels[k] for data[k], NULL: its rows are the
       surface's nodes): a --channels belongs to the --data it follows, as --data-surface does */
    const char *data_channels[THX_PICTURE_MAX];
    int n_channels;
    const char *bad_leads;  /* a bad-lead list or "auto": the --data's bad channels filled on their surface
                               (thorax/leads/bad_leads.h) */
    int n_files;
    int w, h;               /* picture size, pixels */
    int view;               /* a thx_view */
    int have_camera;
    thx_camera cam;
    /* the anatomical frame: canonical axis k (0 the subject's right, 1 anterior, 2 cranial) is
       sg[k] times model axis ax[k] (default x, y, z; up_spec and front_spec change it) */
    int ax[3];
    double sg[3];
    const char *up_spec, *front_spec;
    int mode;               /* a thx_draw_mode */
    int style;              /* a thx_data_style */
    int levels;
    int cmap;               /* a thx_colormap */
    int model;              /* a thx_scale_model */
    int scope;              /* a thx_scope */
    int mapping;            /* a thx_scale_mapping: true, symmetric (the default), midpoint, separate */
    double lo, hi;          /* THX_SCOPE_FIXED */
    int invert;             /* the colour map reversed (high values in the low colour) */
    /* scale groups: each a comma-separated list of surfaces whose scope spans them together
       (frame and series scopes); slaves: "NAME=MASTER", NAME drawn with MASTER's scale */
    const char *groups[THX_PICTURE_MAX];
    int n_groups;
    const char *slaves[THX_PICTURE_MAX];
    int n_slaves;
    char clip[64];          /* SIDE[:F] or nx,ny,nz,d; "" none */
    int colorbar, label, panels;
    const char *only[THX_PICTURE_MAX];
    int n_only;
    const char *whole[THX_PICTURE_MAX]; /* left whole by the clip plane */
    int n_whole;
    thx_picture_look look[THX_PICTURE_MAX];
    int n_look;
    double arrow_spacing, arrow_scale;
    int arrow_max, arrow_unit;
    double arrow_gap;       /* minimum distance between arrows (mm), 0: none */
    int have_box;
    double box[6];          /* arrows only inside x0 y0 z0 x1 y1 z1 */
    const char *arrow_region; /* arrows only at nodes of this tissue region */
    /* marks (single-panel pictures): node labels "SURFACE=index|channel|value" (the nodes seen
       from the camera, decluttered), and the extrema of each surface's data at the frame */
    const char *labels[THX_PICTURE_MAX];
    int n_labels;
    /* picked nodes (the viewer's traces; single-panel pictures): a ring at each node and its
       number (1-based) beside it, in the colour given (its trace's); a ring left open and the
       number dimmed when the node is behind the surfaces or clipped away */
    struct {
        int surface;
        size_t node;
        unsigned char rgba[4];
    } pins[8];
    int n_pins;
    /* map3d landmark files (.lmarks): arteries as tubes, sites as spheres, drawn with the surfaces
       in their own colours, never clipped (markers of where things are) */
    const char *landmarks[THX_PICTURE_MAX];
    int n_landmarks;
    /* electrode files (thorax/model/electrodes.h): each electrode a sphere at its position, with its
       name beside it, never clipped (where the ECG is measured) */
    const char *electrodes[THX_PICTURE_MAX];
    int n_electrodes;
    /* the volume mesh drawn: the tetrahedra wholly on the kept side of the clip plane (all of them
       without one), their visible faces coloured by tissue region with their edges; made at load */
    int tetrahedra;
    /* activation-time maps: "SURFACE[:T0:T1]": the surface's data replaced by the time of each
       node's steepest downstroke (between T0 and T1, the series' time unit), drawn over its true
       range, isochrones with a contour style (thorax/leads/activation.h) */
    const char *activation[THX_PICTURE_MAX];
    int n_activation;
    /* recovery-time maps, "SURFACE[:T0:T1]": each node's steepest T-wave upstroke after its
       activation, T0:T1 the T wave's window (without it the record's rec fiducials, else the chosen
       beat's T wave: thx_picture_add_map) */
    const char *recovery[THX_PICTURE_MAX];
    int n_recovery;
    int extrema;
    /* colour bars: the k-th bar's title and unit (given once: every bar's), in place of what is
       shown ("potential", "activation", "|J|") and the data's unit */
    const char *bar_title[THX_PICTURE_BARS];
    int n_bar_title;
    const char *bar_unit[THX_PICTURE_BARS];
    int n_bar_unit;
    /* orientation letters (A/P, L/R, S/I of the anatomical frame) at the middle of each edge of
       every panel, for the camera of that panel (thx_picture_orientation) */
    int orientation;
    /* inside the volume (paper 4.3; thorax/field/field.h), from the solution's volume potentials
       (thorax forward --volume): equipotential surfaces at the values of `isosurface` (a list, a
       count or percentages of the range of the colour scale's scope: thx_field_values_parse),
       drawn as one surface named "equipotentials", translucent, each in its value's colour; slices
       by the planes `slices` (thx_field_plane_parse), named "slices", coloured by potential (with
       the picture's data style: bands, contour lines) or, with slice_current, by |J| per
       tetrahedron under a scale of its own. Both are clipped like the model unless named in
       `whole`, and take --surface looks by those names. */
    const char *isosurface;
    const char *slices[8];
    int n_slices;
    int slice_current;
    /* current streamlines (thorax/field/streamline.h) from the volume potentials' J = -sigma grad
       phi averaged to the nodes: one seed specification each (point:, line:, sphere:, region:,
       density:), traced both ways with RK2, drawn as tubes of stream_radius mm (0: 0.4% of the
       model's diagonal) named "streamlines", coloured by |J| (viridis, a bar of their own) or, with
       stream_potential, by the potential under the equipotentials' scale */
    const char *streamlines[4];
    int n_streamlines;
    double stream_radius;
    int stream_potential;
    /* the scan under the model (issue 25): the image `image` (any format thx_image_read takes, in the
       model's coordinates: RAS mm for a model built from it) cut by the planes `image_planes` ("z=MM",
       "y=MM", "x=MM" or the image's own "k=N", "j=N", "i=N"; none given: the axial plane through the
       image's middle), each drawn as a textured rectangle with the surfaces (depth-tested: an opaque
       surface in front hides it, a translucent one shows it through). Grey levels under `window` and
       `level` (window 0 / have_level 0: the image's defaults, thorax/image/sample.h); image_labels: a
       colour per label value instead. `contours`: a contour file whose layer nearest each axial plane
       is drawn on it, a colour per contour surface (picture/scan_layer.c). */
    const char *image;
    const char *image_planes[4];
    int n_image_planes;
    double window, level;
    int have_level;
    int image_labels;
    const char *contours;
    /* the renderer (issue 27): 0 OpenGL (the paper's HiPPR), 1 the ray tracer (RaySpray,
       thorax/raytrace/raytrace.h): the same scene, traced with rt's lights, samples, ambient
       occlusion and depth, and the materials rt_mat[] give surfaces by name (the viewer draws with
       OpenGL) */
    int renderer;
    thx_raytrace_opts rt;
    struct {
        char name[64];
        thx_raytrace_material m;
    } rt_mat[THX_PICTURE_MAX];
    int n_rt_mat;
    int rt_key;             /* add a key light (directional, shadows) from above the viewer's right shoulder */
    const char *environment; /* the ray tracer's environment: an equirectangular PNG, or "sky" */
    /* motion blur (the ray tracer, rt.shutter > 0): each frame blurred towards the next one, whose
       data frame is next_frame (0-based; -1: the frame after the one drawn, the series' last its own
       next) and whose camera is next_cam when have_next_cam (a camera flight's at the next movie
       frame), else the frame's own camera. The surfaces of the model take the next frame's values
       and scales; the field's (slices, isosurfaces) and the volume stay this frame's. */
    int next_frame;
    int have_next_cam;
    thx_camera next_cam;
    /* volume rendering (the ray tracer; needs --solution with volume potentials): "potential" (linear
       in each tetrahedron) or "current" (|J| = |sigma grad phi| per tetrahedron), in the solution's
       domain; opacity control points (t, opacity) over the field's colour scale (none: clear at the
       middle, opaque at both ends) and the extinction per mm at opacity 1 */
    const char *volume_render;
    double volume_opacity[THX_RAYTRACE_MAX_OPACITY][2];
    int n_volume_opacity;
    double volume_density;
    int check_frame;        /* thx_picture_load: refuse when `frame` is past a surface's data */
    int frame;              /* 0-based, for that check */
} thx_picture_opts;

#define THX_PICTURE_SURFACES 64

#define THX_PICTURE_SETS 8

/* The data a picture draws, read once (thx_picture_load) and owned here. */
typedef struct {
    thx_model *m;
    thx_series *sets[THX_PICTURE_SURFACES][THX_PICTURE_SETS]; /* each surface's data sets (owned) */
    int n_sets[THX_PICTURE_SURFACES];
    int active[THX_PICTURE_SURFACES];
    thx_series *series[THX_PICTURE_SURFACES]; /* the set shown per surface (sets[s][active[s]]), or NULL */
    int *channel[THX_PICTURE_SURFACES]; /* the recording channel of each node (1-based; 0 none), from --channels */
    unsigned char map[THX_PICTURE_SURFACES][THX_PICTURE_SETS]; /* a map of times, not potentials: drawn over
                                                                  its true range whatever the mapping
                                                                  (1 activation, 2 recovery) */
    signed char map_src[THX_PICTURE_SURFACES][THX_PICTURE_SETS]; /* a map's potentials (their set), -1 none */
    unsigned char map_auto[THX_PICTURE_SURFACES][THX_PICTURE_SETS]; /* a map whose window was chosen (not given) */
    struct thx_pick_index *pick; /* for the marks' visibility, built at the first use (thorax/geom/pick.h) */
    thx_landmark_meshes *marks[THX_PICTURE_MAX]; /* the meshes of o->landmarks[k] */
    char model_dir[4096];     /* the model directory read ("" for surface files) */
    int n_marks;
    thx_electrodes *elec[THX_PICTURE_MAX];        /* o->electrodes[k], read (thx_electrodes; owned) */
    int n_elec;
    thx_surface *tets[THX_PICTURE_MAX];  /* o->tetrahedra: the visible faces of each region's kept tetrahedra (owned) */
    int tets_region[THX_PICTURE_MAX];    /* ... and the region each one is */
    int n_tets;
    thx_series *ecg;          /* 12-lead (trace) */
    thx_series *currents;     /* currents_node, for arrows */
    thx_series *volume;       /* the solution's volume potentials (isosurface, slices), or NULL */
    double vmin, vmax;        /* their finite range over the series */
    struct thx_field_mesh *field[2]; /* equipotential surfaces, slices: of frame field_frame (owned) */
    thx_stream_tubes *tubes;         /* streamlines as tubes, of frame field_frame (owned) */
    size_t n_stream_lines;           /* the lines traced for them */
    thx_surface field_surf[3];       /* the three as surfaces to draw (arrays borrowed or field_own) */
    double *field_values[3];         /* the value drawn at each vertex */
    double *field_own[2];            /* slices by |J|: their own vertices, 3 per triangle (owned) */
    int32_t *field_own_tri;          /* ... and triangles */
    double field_lo[3], field_hi[3]; /* the range their scale covers at field_frame */
    unsigned char field_current[3];  /* 1: drawn by |J| (a bar of its own), 0: by potential */
    unsigned char *field_use;        /* per volume region: in the solution's domain (thx_solution_domain) */
    int field_frame;                 /* -1: none built */
    char field_key[1024];            /* the options they were built with (a script may change them) */
    int field_warned;                /* a frame without equipotentials was told (once per field_key) */
    double smin[THX_PICTURE_SURFACES], smax[THX_PICTURE_SURFACES]; /* finite range of each surface's series */
    unsigned char sranged[THX_PICTURE_SURFACES];
    /* the scan (o->image; picture/scan_layer.c) */
    struct pic_scan *scan;           /* the image read, or NULL */
    int n_scan_planes;
    char scan_axis[4];               /* the planes shown: axis ('x'..'z', 'i'..'k') and position (the viewer moves them) */
    double scan_pos[4];
    double window, level;            /* the grey levels in use */
    thx_render_plane scan_plane[4];  /* the planes as drawn (their texels in scan_rgba) */
    unsigned char *scan_rgba[4];
    double scan_key[4][4];           /* what each was built for: position, window, level, labels */
    int scan_built[4];
    int bounds_from_scan;            /* frame the scan's box, not the surfaces' (tracing: they grow as traced) */
    thx_tracer *tracer;              /* the ray tracer (o->renderer 1), made at the first traced draw (owned) */
    int32_t *vr_tet;                 /* volume rendering: the tetrahedra in the solution's domain (owned) */
    size_t vr_n_tets;
    double *vr_cell;                 /* ... and |J| per tetrahedron of the frame drawn (owned) */
    thx_raytrace_stats rt_stats;     /* ... and what its last draw took */
    thx_raster *rt_env;              /* o->environment read (owned) */
    thx_contours *contours;          /* o->contours, or NULL */
    thx_surface *contour_lines[64];  /* the loops on the planes: a wire surface per plane and contour surface */
    float contour_rgba[64][4];
    int n_contour_lines;
    double contour_z[4];             /* the layer drawn on each plane (NaN: none near it) */
    const thx_series *trace;  /* the series the trace draws from (not owned), its row and label */
    size_t trace_row;
    char trace_label[96];
    /* sort-last (picture/picture_parts.c): this rank's part of a partitioned solution, when
       part_size > 1; m->volume and volume are then the part's (its own tetrahedra and ghosts) */
    int part_rank, part_size;
    unsigned char *part_own;         /* per tetrahedron of the part: 1 own, 0 ghost (owned) */
    int32_t *part_node, *part_tet_id, *part_owner; /* the part's nodes' and tetrahedra's numbers in the whole, owners */
    double part_span[8][2];          /* the slices' planes' spans over the whole volume (every rank's) */
    double part_slice_scale;         /* the slices' snapping scale over the whole volume (thx_field_slice_scaled) */
    double part_lo, part_hi;         /* the frame part_frame's range over the whole volume */
    int part_frame;
    char part_unit[32];              /* the parts' values' unit (their manifest's) */
    void *part_cuts;                 /* the parts' boxes (thx_fem_cut[ranks - 1]; owned): the blending order */
    double part_jmax;                /* volume rendering by |J|: the largest over the ranks (NaN: none yet) */
    double vr_local_hi;              /* ... this rank's, from its own tetrahedra */
    double *field_normals[3];        /* the cuts' normal sums at their vertices, the ghosts' triangles in (owned) */
    int32_t *field_part_tri[3];      /* the cuts' own triangles (owned) */
} thx_picture_data;

/* The colour scales of a picture: one colour bar each (paper 4.2: "a colour bar per distinct
 * scale"). The first is the body surface's (else the first surface's with data); the others are
 * the other surfaces' scales that differ from every one before (in range, model, mapping, colour
 * map, quantity or unit), then the arrows' |J| when they are coloured by magnitude. At most
 * THX_PICTURE_BARS fit beside a picture; up to THX_PICTURE_SCALES distinct ones are counted, so
 * that a picture with more can be refused (thx_picture_draw) instead of showing a bar that does
 * not belong to a surface's colours. */
#define THX_PICTURE_SCALES 16
typedef struct {
    int n;                                /* distinct scales shown (up to THX_PICTURE_SCALES) */
    int more;                             /* 1: more than THX_PICTURE_SCALES */
    thx_scale scale[THX_PICTURE_SCALES];
    int cmap[THX_PICTURE_SCALES];         /* a thx_colormap */
    char names[THX_PICTURE_SCALES][96];   /* the surfaces drawn with each ("currents" for arrows) */
    char unit[THX_PICTURE_SCALES][16];    /* the data's unit ("mV", "ms", ...) */
    char title[THX_PICTURE_SCALES][16];   /* what is shown: "potential", "activation", "|J|" */
} thx_picture_bars;

/* The defaults (800x800, anterior, gouraud, ecg, linear, series scope, symmetric, ...). */
void thx_picture_opts_default(thx_picture_opts *o);
/* "hidden", "points", "wire", "flat", "gouraud", "phong", "orientation"; -1 if unknown. */
int thx_picture_mode_parse(const char *s, thx_draw_mode *out);
/* "+y", "-z", "x" -> axis index and sign; -1 if not an axis. */
int thx_picture_axis_parse(const char *s, int *axis, double *sign);

/* Reads the model (or the surface files), the solution's or the given data, the trace and the
 * currents, checks every name the options give, and settles the anatomical frame of the views
 * (o->ax, o->sg). d is zeroed first; free it with thx_picture_data_free even on failure. */
thx_status thx_picture_load(thx_ctx *ctx, thx_picture_opts *o, thx_picture_data *d);
void thx_picture_data_free(thx_picture_data *d);

/* The picture of frame (0-based) into img (o->w x o->h), offscreen with r (made with that size).
 * *nan_total (may be NULL) counts the values that are not numbers. font may be NULL (no text). */
thx_status thx_picture_draw(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                            thx_font *font, int frame, thx_raster *img, size_t *nan_total);

/* Sort-last (thorax/parallel/parallel.h), collective: the end of thx_picture_load under mpirun. st is
 * this rank's load; the ranks agree on it, and when each reads its part of a partitioned solution
 * (d->part_size > 1) the volume's range and the slices' spans become the whole's, and the cuts are
 * checked against them. Without mpirun, st itself. */
thx_status thx_picture_parts_settle(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_status st);

/* Sort-last, collective (d->part_size > 1): each rank draws its part of the volume's cuts (rank 0 the
 * model's surfaces too) as a layer with depth, the layers are composited by IceT (the nearest
 * fragment of each pixel) and finished on rank 0, into img there (the 3D part: thx_picture_annotate
 * draws the rest). The colour scales drawn are left in *bars on rank 0. Every surface drawn must be
 * opaque. Equal, byte for byte, to the picture one process draws from the whole solution. */
thx_status thx_picture_draw_part(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r, thx_font *font,
                                 int frame, thx_raster *img, thx_picture_bars *bars, size_t *nan_total);

/* Sort-first (thorax/parallel/parallel.h): the 3D part of the same picture, only rank's share of
 * its pixels among size ranks, into img filled with the background first: the ray tracer's tiles of
 * 16 x 16 pixels of each viewport, tile k for rank k mod size; OpenGL's rows [h * rank / size,
 * h * (rank + 1) / size) from the top. own (a byte a pixel of img, zeroed first) is set to 1 where
 * this rank wrote. The colour scales drawn are left in *bars, checked as thx_picture_draw checks
 * them. Once rank 0 holds every rank's pixels (thx_par_gather_pixels), thx_picture_annotate there
 * gives the picture thx_picture_draw gives, byte for byte. */
thx_status thx_picture_draw_share(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                                  thx_font *font, int frame, int rank, int size, thx_raster *img, unsigned char *own,
                                  thx_picture_bars *bars, size_t *nan_total);

/* The same picture's 3D part, into the framebuffer bound in the caller's current OpenGL 3.3
 * context (fb_w x fb_h pixels; r made with w = h = 0), the whole framebuffer cleared to the
 * picture's background first. The colour scales drawn are left in *bars for thx_picture_annotate.
 * The camera used is o->cam when o->have_camera, else the standard view. */
thx_status thx_picture_draw_gl(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_renderer *r,
                               thx_font *font, int frame, int fb_w, int fb_h, thx_picture_bars *bars, size_t *nan_total);
/* The annotations (surface names of panels, colour bar, time label, trace) over img, which holds
 * the 3D part drawn by thx_picture_draw_gl at img's size. */
thx_status thx_picture_annotate(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font,
                                int frame, const thx_picture_bars *bars, thx_raster *img);

/* Where the colour bars of a picture of w x h pixels go: the strip of bar k (x, y from the top
 * left, w, h) in box[k], for n bars stacked beside the 3D part (o->colorbar). Returns how many of
 * the n fit (at least 16 pixels of strip each, room for three title lines above), at most
 * THX_PICTURE_BARS. */
int thx_picture_bar_layout(const thx_picture_opts *o, thx_font *font, int w, int h, int n, int box[][4]);
/* The titles of bar k: what is shown ("potential", "activation", "|J|", or o->bar_title's) and
 * the unit (o->bar_unit's, or the data's). With more than one bar, a line above them names the
 * surfaces the bar serves (bars->names[k]). */
void thx_picture_bar_title(const thx_picture_opts *o, const thx_picture_bars *bars, int k, char *head, size_t head_size,
                           char *unit, size_t unit_size);
/* Whether the colour bars a picture asks for can be drawn truthfully: THX_EINPUT, naming the
 * scales and how to share them, when there are more distinct scales than fit beside a picture of
 * w x h pixels, or more --bar-title/--bar-unit than bars. Called by thx_picture_draw; the viewer
 * draws the bars that fit. */
thx_status thx_picture_bars_check(thx_ctx *ctx, const thx_picture_opts *o, thx_font *font, int w, int h,
                                  const thx_picture_bars *bars);

/* An orientation letter of a picture: text (1 to 3 of A P L R S I, the strongest direction
 * first) drawn with its baseline's left end at (x, y) (pixels from the top left). */
typedef struct {
    char text[4];
    int x, y;
} thx_picture_letter;
/*
 * The anatomical directions along the screen under camera cam, in the frame o->ax/o->sg (the
 * model's frame or --up/--front): for the screen's left, right, top and bottom (out[0..3]), the
 * letters of the anatomical axes making an angle of at most about 70 degrees with that screen
 * direction (|cos| >= 0.35), the nearest first: 'R'/'L' (the subject's right/left), 'A'/'P',
 * 'S'/'I'. A standard anterior view of a RAS model gives R, L, S, I; an oblique camera gives
 * e.g. "LA". out[k].x, y are 0.
 */
void thx_picture_orientation_text(const thx_picture_opts *o, const thx_camera *cam, thx_picture_letter out[4]);
/* The orientation letters of every panel of a picture of w x h pixels, placed 6 pixels inside the
 * middle of each edge of the panel's viewport; up to max (4 per panel). Returns the count. */
int thx_picture_orientation(const thx_picture_opts *o, const thx_picture_data *d, thx_font *font, int w, int h,
                            thx_picture_letter *out, int max);

/* The 3D part's viewport (x, y from the top left, w, h) of a picture of w x h pixels: the picture
 * less the label strip above, the colour bar beside and the trace below, as o asks for them. */
void thx_picture_viewport(const thx_picture_opts *o, thx_font *font, int w, int h, int vp[4]);
/* The camera of the standard view o->view for a viewport of aspect w/h, in the model's axes,
 * framing the surfaces drawn (o->only when given, else all). */
/* How each of the model's surfaces is drawn at frame (0-based), as thx_picture_draw draws it: its
 * mode, colour and opacity, the values of that frame, the data style, colour map and scale; the
 * surfaces shown only (o->only), in the model's order (out[k].surf is the model's surface), no GL.
 * Returns how many were written (at most max; 0 also when out of memory). The web page's exporter
 * takes its looks from here, so that the page colours as `thorax render` does. */
/* What thx_picture_draw adds to the model's surfaces at frame (0-based), made for that frame: the
 * volume's cuts (surfaces named "equipotentials", "slices", "streamlines", with their values, scales
 * and colour maps) and the scan's contour lines, up to max into out (*n of them), and the scan's
 * planes (*planes: d's, *n_planes of them). Valid until the next draw or layers call. */
thx_status thx_picture_layers(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, int frame,
                              thx_render_surface *out, size_t max, size_t *n, const thx_render_plane **planes,
                              size_t *n_planes);
/* The pictures' background and the colour of values that are not numbers (RGBA, 0..1). */
void thx_picture_colors(float background[4], float nan_color[4]);
size_t thx_picture_surface_looks(const thx_picture_opts *o, thx_picture_data *d, int frame, thx_render_surface *out,
                                 size_t max);
void thx_picture_camera(const thx_picture_opts *o, const thx_picture_data *d, double aspect, thx_camera *cam);
/* The camera of standard view `view` (a thx_view) whatever o->have_camera says (the named views of
 * a camera key file, thorax/render/camera_path.h). */
void thx_picture_view_camera(const thx_picture_opts *o, const thx_picture_data *d, int view, double aspect, thx_camera *cam);
/* The model's bounding box (all surfaces). */
void thx_picture_bounds(const thx_picture_data *d, double lo[3], double hi[3]);
/* The clip plane o->clip asks for, in the model's axes; 0 none, 1 one (in *p), -1 a bad spec (message in ctx). */
int thx_picture_clip(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d, thx_clip_plane *p);
/* o->clip checked against the model: a bad spec, or a plane that removes every node of the
 * surfaces drawn (none left whole by --no-clip), is THX_EINPUT saying so (a blank picture is never
 * drawn without a word). thx_picture_load calls it; the viewer again for a script's --clip. */
thx_status thx_picture_clip_check(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d);

/* The solution's volume potentials read now, when thx_picture_load did not read them (no cut was
 * asked for then): a viewer's first cut. Nothing when they are read; THX_EINPUT naming `what` (the
 * option or action asking) when o has no solution, or a solution without them (thorax forward
 * --volume makes them). */
thx_status thx_picture_volume_load(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, const char *what);
/* The cuts o asks for (isosurface, slices, streamlines) checked against the volume potentials read
 * at load, as thx_picture_load checks them: a bad specification, a slice that misses the volume or
 * a value outside every frame's potentials is THX_EINPUT naming the option; cuts without the volume
 * potentials likewise. The viewer calls it before a changed cut is drawn. */
thx_status thx_picture_cuts_check(thx_ctx *ctx, const thx_picture_opts *o, const thx_picture_data *d);
/* Shows data set k (0-based) of surface s; -1 when there is no such set. */
int thx_picture_set_active(thx_picture_data *d, int s, int k);
/* Removes data set k of surface s, a map (a viewer's map replaced by one of another window): the sets
 * after it move down one, and the potentials it was made from are shown. -1 when k is not a map. */
int thx_picture_drop_set(thx_picture_data *d, int s, int k);
/* Adds the activation-time map of surface s's shown data (steepest downstroke between t0 and t1;
 * NaN: the window a map3d user expects, thx_activation_window_choose) as its next data set, and
 * shows it. Same as thx_picture_add_map(ctx, d, s, 1, t0, t1). */
thx_status thx_picture_add_activation(thx_ctx *ctx, thx_picture_data *d, int s, double t0, double t1);
/* A map of surface s's shown potentials as its next data set, shown: kind 1 activation, 2 recovery.
 * With t0, t1 NaN: the record's own per-lead fiducials (act, rec) when it has them, else the
 * window thx_activation_window_choose finds (the label of the map says which); given, t0..t1 is
 * the activation window (kind 1) or the T wave's (kind 2). */
thx_status thx_picture_add_map(thx_ctx *ctx, thx_picture_data *d, int s, int kind, double t0, double t1);
/* After the model's surfaces changed (an edit): forget what was computed from their geometry. */
void thx_picture_geometry_changed(thx_picture_data *d);

/* The scan's plane k (o->image) moved by n of the image's planes along its axis (a RAS plane to the
 * plane of voxel centres n steps on, an index plane to index + n), kept inside the image. Returns
 * 1 when it moved, 0 when already at the image's end (or no such plane). */
int thx_picture_scan_move(thx_picture_data *d, int k, int n);
/* The image of o->image as read (NULL without one): the digitizer traces on it (thorax/digitizer/
 * session.h) without a second copy in memory. */
struct thx_image;
const struct thx_image *thx_picture_scan_image(const thx_picture_data *d);
/* What the scan shows, for a status line: "image plane z=1 mm, window 900 level 550". */
void thx_picture_scan_describe(const thx_picture_data *d, char *buf, size_t size);

/* The column of the solution's currents_node at the time of frame, or -1. */
long thx_picture_currents_column(const thx_picture_data *d, int frame);
/* The number of frames of the data shown (the body surface's, else the first surface's with data;
 * 0 without data). */
size_t thx_picture_n_frames(const thx_picture_data *d);

#ifdef __cplusplus
}
#endif
#endif
