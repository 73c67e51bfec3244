/*
 * thorax/raytrace/raytrace.h — RaySpray (paper 4.3: "an integrated ray tracer/volume renderer"):
 * the scene of thorax/render/render.h traced with Embree 3 (its BVH: today's form of the paper's
 * "'voxel'-based method"), with shadows, reflection, refraction, ambient occlusion and
 * anti-aliasing. The same thx_scene as the OpenGL renderer, so the picture module draws either;
 * colours are the OpenGL renderer's (the same scale, bands and colour map per hit, the same
 * headlight by default). docs/design/raytrace.md.
 *
 * What is traced: surfaces in the flat, Gouraud, Phong and orientation modes (points and wire modes
 * are drawn as Phong surfaces; hidden ones not), with their colours, data and contour lines, and the
 * scene's clip planes; image planes (a quad each, its texels as the OpenGL renderer addresses and
 * filters them, unlit, not clipped, transparent where a texel's alpha is below 128; they cast
 * shadows, and a surface lying in a plane's own plane is seen in front of it, as the OpenGL
 * renderer's polygon offset has it); arrows as 3D glyphs (a cylinder shaft and a cone head, of the
 * OpenGL renderer's widths in pixels at the arrow's distance, its colours, lit and casting shadows,
 * cut by the clip planes); a field inside a tetrahedral mesh (thx_raytrace_volume).
 *
 * Motion blur across animation frames (the paper's RaySpray had it): with opts.next (the same scene
 * at the next frame) and opts.shutter > 0, each pixel sample has its time tau in [0, shutter) of the
 * frame interval (stratified over the pixel's samples, a hash of pixel and sample), and sees the
 * camera and the surfaces' values between the two frames: the camera's eye, centre, up, field of
 * view and height linear in tau, the value's t = scale(value) at each node (1 - tau) t_this +
 * tau t_next. The surfaces' geometry does not move (no BVH is built for a frame step); the volume
 * (opts.volume) is this frame's, unblurred.
 *
 * Deterministic: every random number is a hash of (pixel, sample, bounce, use), tiles are
 * independent, so the same input gives the same picture whatever the number of threads.
 */
#ifndef THORAX_RAYTRACE_H
#define THORAX_RAYTRACE_H

#include <stdint.h>

#include "thorax/render/render.h"

#ifdef __cplusplus
extern "C" {
#endif

#define THX_RAYTRACE_MAX_LIGHTS 8
#define THX_RAYTRACE_MAX_SURFACES 64

typedef enum {
    THX_LIGHT_HEAD = 0,   /* at the eye (the OpenGL renderer's headlight): two-sided, never shadowed */
    THX_LIGHT_POINT,      /* at pos */
    THX_LIGHT_DIRECTIONAL,/* from infinitely far along -dir (dir: where the light travels) */
    THX_LIGHT_AREA        /* a rectangle: corner pos, edges u and v (soft shadows) */
} thx_light_kind;

typedef struct {
    thx_light_kind kind;
    double pos[3], dir[3], u[3], v[3];
    int in_camera;        /* directional: dir given along the camera's right, up and line of sight
                             (a light that keeps its place over the viewer's shoulder whatever the view) */
    double intensity;     /* multiplies the diffuse and specular terms (1) */
    int shadows;          /* cast shadows (point, directional, area) */
} thx_light;

typedef struct thx_raytrace_material {
    double reflect;       /* mirror reflectance 0..1 */
    double transmit;      /* 0..1: the part that passes through (glass); 0 and the colour's alpha < 1:
                             1 - alpha, without refraction */
    double ior;           /* index of refraction inside the surface (1: none; glass 1.5) */
    int texture;          /* 0 none, 1 grid lines, 2 checkerboard (in model mm, every texture_mm) */
    double texture_mm;
} thx_raytrace_material;

/* A field inside a tetrahedral mesh, rendered by emission and absorption along each ray (the volume
 * renderer of paper 4.3's RaySpray): the ray enters the mesh where Embree finds a boundary face, walks
 * from tetrahedron to tetrahedron through their shared faces, and integrates each piece exactly for a
 * field linear in the tetrahedron (point data) or constant in it (cell data). Colour from cmap over
 * scale (the field's colour scale), extinction tau(t) = density * opacity(t) per mm with opacity
 * piecewise linear through the control points (t, opacity), t = scale(value) in [0, 1]; none: 0 at
 * t = 1/2 rising to 1 at both ends (a symmetric potential's zero clear, its extremes opaque). The
 * mesh's boundary faces and neighbours are built once per mesh (xyz, tet) and kept: a frame step
 * changes the values alone. */
#define THX_RAYTRACE_MAX_OPACITY 16
typedef struct {
    const double *xyz;       /* 3 n_nodes */
    size_t n_nodes;
    const int32_t *tet;      /* 4 n_tets, positively oriented */
    size_t n_tets;
    const double *point_values; /* per node (linear in each tetrahedron), or NULL */
    const double *cell_values;  /* per tetrahedron (constant), when point_values is NULL */
    thx_colormap cmap;
    thx_scale scale;
    double opacity[THX_RAYTRACE_MAX_OPACITY][2];
    int n_opacity;
    double density;          /* extinction per mm at opacity 1 */
    /* sort-last: only the rays' pieces inside this box count (a rank's part of a volume cut into boxes,
       whose mesh reaches beyond the box where tetrahedra straddle its sides); have_box 0: all. The
       layers of the boxes, blended in their order along the rays, give the whole's picture. */
    int have_box;
    double box[2][3];
} thx_raytrace_volume;

typedef struct thx_raytrace_opts {
    int samples;          /* per pixel side: samples^2 stratified, jittered samples (1: the centre) */
    int max_depth;        /* reflection and refraction bounces (6) */
    thx_light lights[THX_RAYTRACE_MAX_LIGHTS];
    int n_lights;         /* 0: the headlight alone */
    double ambient;       /* the ambient term (0.25, the OpenGL renderer's) */
    int ao_samples;       /* ambient occlusion: rays per hit (0: none); the ambient term scaled by the
                             unoccluded fraction within ao_distance mm */
    double ao_distance;
    thx_raytrace_material material[THX_RAYTRACE_MAX_SURFACES]; /* per scene surface (index in thx_scene) */
    int progress;         /* a progress bar on stderr */
    const thx_raytrace_volume *volume; /* a field rendered inside its mesh (NULL: none) */
    /* the environment: what rays that leave the scene see, the background included (reflections show
       it): an equirectangular image (longitude along its width, +z at its top row; the raster is the
       caller's), or sky = 1 for a sky gradient; neither: the scene's background colour */
    const thx_raster *environment;
    int sky;
    /* motion blur: the same scene at the next frame (the same surfaces in the same order, with the
       next frame's values, scales and camera; borrowed) and the shutter, the part of the frame
       interval the samples' times spread over (0 to 1; 0 or next NULL: no blur, the picture of this
       frame alone) */
    const thx_scene *next;
    double shutter;
    /* sort-first (thorax/parallel/parallel.h): of the viewport's tiles of 16 x 16 pixels, numbered
       row by row, only those whose number modulo share_size is share_rank are traced (share_size 0
       or 1: all); the others' pixels are left as they are. A pixel's colour does not depend on who
       traces it. own (when not NULL): a byte per pixel of the image, set to 1 where this call wrote */
    int share_rank, share_size;
    unsigned char *own;
    /* sort-last (thorax/parallel/parallel.h): when not NULL, each sample of each pixel of the viewport
       as premultiplied RGBA floats over nothing (4 floats a sample, samples^2 samples a pixel, pixels
       of the image row by row from the top), the background left out, and img not written;
       thx_raytrace_layer_finish puts such layers, composited sample by sample, over it. (Samples, not
       pixels: a pixel whose samples see two parts side by side is their sum, which blending two
       averaged pixels would not give.) */
    float *layer;
} thx_raytrace_opts;

void thx_raytrace_opts_default(thx_raytrace_opts *o);

typedef struct {
    double seconds, build_seconds;
    size_t primary_rays, rays;   /* primary (eye) rays, and all rays traced */
    size_t builds;               /* geometries built (BVH) during the call */
} thx_raytrace_stats;

typedef struct thx_tracer thx_tracer;

/* An Embree device (robust mode) and the geometry cache: a surface keeps its BVH across calls while
 * its nodes and triangles stay the same (a frame step only changes values). */
thx_status thx_tracer_create(thx_ctx *ctx, thx_tracer **out);
void thx_tracer_destroy(thx_tracer **t);
/* "Embree 3.13.5" */
const char *thx_tracer_info(const thx_tracer *t);

/* The viewport of img from a layer of samples x samples samples a pixel (thx_raytrace_opts.layer; the
 * layers of parts of a volume blended front to back): each pixel its samples' mean over sc's
 * background, as thx_raytrace_scene finishes the pixels it traces (sc->clear; else over img's own). */
void thx_raytrace_layer_finish(const thx_scene *sc, int samples, const float *layer, thx_raster *img);

/* Traces sc into img at sc->viewport (w = 0: the whole image; sc->clear fills it with the
 * background first, else the background is left where no surface is hit). stats may be NULL. */
thx_status thx_raytrace_scene(thx_ctx *ctx, thx_tracer *t, const thx_scene *sc, const thx_raytrace_opts *o, thx_raster *img,
                           thx_raytrace_stats *stats);

/* The volume integral along one ray from tnear to tfar (RAS mm; dir unit): the emitted colour
 * (premultiplied) and the transmittance left, as the tracer composites it (tests). */
thx_status thx_raytrace_volume_ray(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, const double org[3],
                                   const double dir[3], double tnear, double tfar, double rgb[3], double *transmittance);

/* The same for n rays from 0 to tfar[i] (org, dir, tfar, rgb and transmittance: n each), walked
 * together as thx_raytrace_scene walks a row's eye rays: eight at a time in AVX2's lanes where the
 * processor has them (the same integrals to float's rounding; elsewhere one at a time). */
thx_status thx_raytrace_volume_rays(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, size_t n, const double (*org)[3],
                                    const double (*dir)[3], const double *tfar, double (*rgb)[3], double *transmittance);
/* How many rays the volume walk takes at once on this processor: 8 (AVX2 and FMA), else 1. */
int thx_raytrace_volume_lanes(void);

/* What each pixel's centre sees in a w x h viewport: the index of the scene surface hit (-1 none) and
 * the triangle (the primary ray through the pixel centre, after the clip planes). An image plane's
 * texel: surface THX_RAYTRACE_ID_PLANE and tri the plane's index in sc->planes; an arrow: surface
 * THX_RAYTRACE_ID_ARROW and tri the arrow's index in its thx_render_arrows. */
#define THX_RAYTRACE_ID_PLANE (-2)
#define THX_RAYTRACE_ID_ARROW (-3)
thx_status thx_raytrace_ids(thx_ctx *ctx, thx_tracer *t, const thx_scene *sc, int w, int h, int32_t *surface,
                         int32_t *tri);

#ifdef __cplusplus
}
#endif
#endif
