/*
 * thorax/render/render.h — the 3D renderer (paper 4.2): surfaces as points, wire
 * meshes, flat, Gouraud or Phong shading, the orientation check, clipping
 * planes, potentials coloured per pixel (value interpolated, then looked up:
 * exact bands and contour lines), and arrows for current density.
 *
 * OpenGL 3.3 core profile through libepoxy. thx_renderer_create makes an
 * offscreen context with EGL (the GPU's driver where there is one, Mesa's
 * llvmpipe where there is none) and renders into a framebuffer object; the
 * drawing code (thx_render_scene_gl) only needs a current 3.3 context, so
 * the interactive viewer can call it in its own window.
 */
#ifndef THORAX_RENDER_H
#define THORAX_RENDER_H

#include "thorax/model/surface.h"
#include "thorax/render/image.h"
/* The colour scales (thx_scale, thx_scale_from_range and the rest) are in thorax/render/image.h. */

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    THX_DRAW_HIDDEN = 0,
    THX_DRAW_POINTS,      /* nodes as round points */
    THX_DRAW_WIRE,        /* triangle edges */
    THX_DRAW_FLAT,        /* one normal per triangle */
    THX_DRAW_GOURAUD,     /* lighting per vertex, interpolated */
    THX_DRAW_PHONG,       /* normals interpolated, lighting per pixel */
    THX_DRAW_ORIENTATION  /* the paper's check: triangles drawn only where their outward side faces the
                             viewer (front colour), nodes behind drawn as points (back colour) */
} thx_draw_mode;

typedef enum {
    THX_DATA_CONTINUOUS = 0, /* the colour map, continuously */
    THX_DATA_BANDS,          /* n_levels discrete shades */
    THX_DATA_CONTOURS,       /* n_levels - 1 contour lines at the band boundaries over the surface colour */
    THX_DATA_BANDS_CONTOURS, /* shades with the lines between them */
    THX_DATA_CONTINUOUS_CONTOURS
} thx_data_style;

typedef struct {
    const thx_surface *surf;
    thx_draw_mode mode;
    float color[4];          /* surface colour; alpha < 1: translucent (drawn after the opaque ones);
                                all zero: light grey */
    float back_color[4];     /* orientation mode: colour of the points behind; all zero: white */
    float point_size;        /* pixels (points and orientation modes); 0: 4 */
    float line_width;        /* pixels (wire mode, contour lines); 0: 1 (wire), 1.5 (contours) */
    /* data: one value per node (NULL = none). Values are mapped by `scale` to t in [0, 1], t is
       interpolated across each triangle per pixel and looked up in `cmap` (thorax/render/image.h). NaN
       values are drawn in the scene's nan_color. */
    const double *values;
    thx_data_style style;
    int n_levels;            /* bands asked for; a lab scale draws its own number (thx_scale_bands) */
    thx_colormap cmap;
    thx_scale scale;
    float contour_color[4];  /* all zero: black */
    int no_clip;             /* 1: the scene's clip planes leave this surface whole (the heart
                                seen entire through a torso opened by a clip plane) */
    /* per node its normal, any length but not zero (the renderer normalizes it), or NULL: the sum of
       the node's triangles' area-weighted normals. A part of a larger surface (sort-last's ranks)
       gives the whole's sums, so that its nodes on the part's edge are lit as the whole's are. */
    const double *normals;
} thx_render_surface;

/* Arrows, e.g. current density (paper 4.2, "Displaying vector fields"). */
typedef struct {
    const double *pos;   /* 3 n: tails */
    const double *vec;   /* 3 n */
    size_t n;
    int unit_length;     /* 0: length = |v| * scale (mm); 1: every arrow `scale` mm long, coloured by |v| */
    double scale;
    thx_colormap cmap;   /* colour by |v| under mag_scale (unit_length), else `color` */
    thx_scale mag_scale;
    float color[4];      /* all zero: black */
    float width;         /* shaft width, pixels; 0: 1.5 */
} thx_render_arrows;

/*
 * Arrows from a vector field given at points (e.g. current density at the volume mesh's nodes),
 * with the paper's clutter controls: the points where in[i] is nonzero (in NULL: all) are averaged
 * over the cells of a grid of `spacing` (mm; each arrow at the mean position of its cell's points,
 * with their mean vector) or, with spacing 0, taken one by one; zero and non-finite vectors are
 * dropped; then, strongest first, an arrow is kept when no kept arrow's tail lies within `gap` mm
 * of its own (0: no limit), until `max_n` are kept.
 * Output: *pos and *vec (3 n each, malloc'd, strongest first), *n, and *vmax the largest
 * magnitude among all candidates (the scale of the whole field, kept or not).
 */
thx_status thx_arrows_select(thx_ctx *ctx, const double *xyz, const double *vec, size_t n_points,
                             const unsigned char *in, double spacing, double gap, size_t max_n,
                             double **pos_out, double **vec_out, size_t *n_out, double *vmax);

typedef struct {
    double eye[3], center[3], up[3];
    double fov_deg;      /* perspective vertical field of view; 0 = orthographic */
    double height;       /* orthographic: the visible height, mm */
} thx_camera;

typedef enum { THX_VIEW_ANTERIOR = 0, THX_VIEW_POSTERIOR, THX_VIEW_LEFT, THX_VIEW_RIGHT, THX_VIEW_SUPERIOR, THX_VIEW_INFERIOR } thx_view;

/* "anterior", "posterior", "left", "right", "superior", "inferior"; -1 if unknown. */
int thx_view_parse(const char *name, thx_view *out);
/* A standard anatomical view of the box lo..hi (the model's axes: +x the subject's right, +y
 * anterior, +z cranial): looking at the subject from that side, head up (superior/inferior:
 * anterior up), orthographic, the box filling the view with a margin for the given aspect w/h. */
void thx_camera_view(thx_camera *cam, thx_view view, const double lo[3], const double hi[3], double aspect);
/* Where point p lands in a viewport of w x h pixels under cam (the renderer's projection): *x, *y
 * in pixels from the viewport's top left (fractional; outside 0..w, 0..h when off the picture),
 * *depth the distance in front of the eye along the line of sight (mm). 0, or -1 when p is not in
 * front of the eye (perspective) or the camera is degenerate. */
int thx_camera_project(const thx_camera *cam, int w, int h, const double p[3], double *x, double *y, double *depth);
/* The ray under viewport pixel (x, y) (from the top left, fractional): origin and unit direction.
 * Orthographic: the origin on the plane through the eye facing the view. 0, or -1 for a
 * degenerate camera. The inverse of thx_camera_project: a point on the ray projects to (x, y). */
int thx_camera_ray(const thx_camera *cam, int w, int h, double x, double y, double origin[3], double dir[3]);

/* An image plane (a scan's axial, coronal or sagittal plane, issue 25): a textured rectangle at
 * its place in 3D, depth-tested with the surfaces (an opaque surface in front hides it, a
 * translucent one shows it through), unlit, not cut by the clip planes. Texel (0, 0) is first
 * in rgba, rows run along u: texel (a, b)'s centre is origin + (a + 0.5) / w u + (b + 0.5) / h v.
 * Texels of alpha below 128 (outside the image) are not drawn. The plane is drawn after the
 * opaque surfaces with a polygon offset (1, 1) behind them, so lines lying in it (a wire surface
 * of contours drawn on it) stay in front. */
typedef struct {
    int w, h;                   /* texels */
    const unsigned char *rgba;  /* 4 w h bytes */
    double origin[3];           /* the outer corner of texel (0, 0), model mm */
    double u[3], v[3];          /* the rectangle's whole edges: w texels along u, h along v */
    int nearest;                /* 1: each texel a block (a label map); 0: bilinear between texels */
} thx_render_plane;

/* Keeps the half space n . x + d >= 0. */
typedef struct {
    double n[3], d;
} thx_clip_plane;

typedef struct {
    const thx_render_surface *surfaces;
    size_t n_surfaces;
    const thx_render_arrows *arrows;
    size_t n_arrows;
    thx_camera camera;
    thx_clip_plane clip[4];
    int n_clip;
    float background[4];
    float nan_color[4];  /* default magenta-grey if all zero */
    int viewport[4];     /* x, y (from the top left), w, h within the image; w = 0: the whole image */
    int clear;           /* clear the viewport to the background first (else draw over its pixels) */
    const thx_render_plane *planes; /* image planes drawn with the surfaces (may be NULL) */
    size_t n_planes;
    /* the box the depth range is fitted to (have_box): in place of the box around what is drawn, so
       that pictures of parts of one scene (sort-last's ranks) share one depth scale */
    int have_box;
    double box[2][3];
} thx_scene;

typedef struct thx_renderer thx_renderer;

/* An offscreen EGL context with OpenGL 3.3 core and a w x h framebuffer (4x multisampled). Errors
 * name what is missing ("no EGL display", "OpenGL 3.3 core not available: got 2.1 Mesa ...").
 * w = h = 0: no context of its own, for thx_render_scene_gl in the caller's current 3.3 context
 * (the viewer); its GL objects are made there at the first draw, and it must be destroyed with
 * that context current. */
thx_status thx_renderer_create(thx_ctx *ctx, int w, int h, thx_renderer **out);
void thx_renderer_destroy(thx_renderer **r);
/* "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)" */
const char *thx_renderer_info(const thx_renderer *r);
/* Antialiasing of the offscreen framebuffer: 4 = 4x multisampling; 1 = one sample per pixel,
 * smoothed by FXAA; 0 = automatic, the default: 4 on a GPU, 1 on a software rasterizer (llvmpipe),
 * where multisampling triples the time of a large mesh (docs/decisions.md, "Renderer"). */
thx_status thx_renderer_set_samples(thx_ctx *ctx, thx_renderer *r, int samples);
/* The samples per pixel in use (4 or 1; 0 for a renderer without its own framebuffer). */
int thx_renderer_samples(const thx_renderer *r);

/* Sort-first rendering (thorax/parallel/parallel.h): thx_render then draws only this rank's band of
 * the image's rows, [h * rank / size, h * (rank + 1) / size) from the top, leaves the other rows as
 * they were in img, and sets to 1 in own (a byte per pixel of the image, when not NULL) the pixels it
 * wrote. Each band's pixels are those of the whole picture, byte for byte: the drawing is scissored
 * to the band and to the rows FXAA reads around it (one sample: 26 rows on each side), whose
 * fragments are the same with or without the scissor. size 0 or 1: the whole image, as before.
 * Only scenes that clear their viewport (a blended one would need its neighbours' rows). */
thx_status thx_renderer_set_share(thx_ctx *ctx, thx_renderer *r, int rank, int size, unsigned char *own);

/* Sort-last (docs/design/parallel.md): the scene drawn as thx_render draws it, read back raw: the
 * viewport's premultiplied RGBA into rgba and its window depth into depth (0 near .. 1 far; 1 where
 * nothing was drawn), a value a pixel of the whole image, rows from the top; the pixels outside the
 * viewport left as they are. One sample a pixel only (thx_renderer_set_samples 1, llvmpipe's
 * default): a layer's pixel is one fragment. Layers of parts of one scene, drawn with the same
 * camera and box (thx_scene.have_box), composited by depth (the nearer fragment) and finished by
 * thx_render_layer_finish, give thx_render's picture of the whole scene. */
thx_status thx_render_layer(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, unsigned char *rgba, float *depth,
                            size_t *n_nan);
/* The end of thx_render over a layer (a composited one): FXAA over the scene's viewport, then
 * divided by alpha into img (w x h of the renderer; the other pixels left as they are). */
thx_status thx_render_layer_finish(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, const unsigned char *rgba,
                                   thx_raster *img);

/* Draws the scene into the renderer's framebuffer and reads it back into img (w x h of the
 * renderer), leaving the pixels outside the viewport as they were in img. n_nan (may be NULL):
 * the number of NaN values met in the data of the surfaces drawn with it. */
thx_status thx_render(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, thx_raster *img, size_t *n_nan);

/* The drawing alone, into whatever framebuffer (with a depth buffer) is bound in the current 3.3
 * context (for the interactive viewer; the renderer made with w = h = 0). */
thx_status thx_render_scene_gl(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, int fb_w, int fb_h, size_t *n_nan);

#ifdef __cplusplus
}
#endif
#endif
