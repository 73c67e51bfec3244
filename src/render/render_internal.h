/*
 * Internal to src/render: what the files of the 3D renderer share. render.c describes the
 * pipeline and its invariants and lists the files; camera.c makes the camera's matrices.
 *
 * Matrices are 4 x 4, column-major (m[col * 4 + row]) as OpenGL takes them,
 * in double until they are handed to a shader. Eye space is OpenGL's: the
 * camera at the origin looking along -z, +y up, +x to the right of the image.
 * The model matrix is the identity: surfaces are drawn in model coordinates
 * (millimetres, RAS).
 *
 * Functions shared between the renderer's files are named rn_ (camera.c's cam_); each is
 * described above its definition.
 */
#ifndef THORAX_RENDER_INTERNAL_H
#define THORAX_RENDER_INTERNAL_H

#include "thorax/render/render.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <stddef.h>
#include <stdint.h>

/* The t of a NaN value (see the surface shaders in render_shaders.c). */
#define NAN_T 1.0e6f

/* ------------------------------------------------------------------- types */

typedef struct {
    GLuint id;
    GLint view, proj, clip, ortho, vp, point_size, nlev, lw, cmap, cmap_n, color, nan_color, contour_color, tex, rect;
} program;

/* A surface shader variant (see the #defines above the shaders). */
typedef struct {
    int prim, light, data, style, shrink, a2c, clip;
} variant;

typedef struct {
    variant key;
    program prog;
} variant_prog;

/* One uploaded surface. */
typedef struct {
    const thx_surface *surf; /* the key: address, counts, array addresses, content hash */
    size_t n_nodes, n_tris;
    const double *xyz;
    const int32_t *tri;
    uint64_t hash;
    GLuint vao, vbo_geo, vbo_t, ebo_tri, ebo_edge, ebo_pts;
    size_t n_edges;  /* valid when edges_ok */
    int edges_ok;
    size_t pts_cap;  /* indices the orientation-mode point buffer holds */
    GLenum cull;     /* closed and consistently oriented: the faces never seen from outside (GL_BACK when
                        the triangles face outward, GL_FRONT when inward); 0 otherwise */
    double lo[3], hi[3];
    unsigned long last_used;
} surf_entry;

struct thx_renderer {
    int own;                  /* 1: our EGL context and framebuffers; 0: the caller's context */
    EGLDisplay dpy;
    EGLContext egl;
    EGLSurface pbuf;          /* EGL_NO_SURFACE when the display can make surfaceless contexts current */
    int w, h;
    int samples;              /* 4: multisampled, resolved by a blit; 1: one sample, smoothed by FXAA (CPU) */
    int samples_asked;        /* thx_renderer_set_samples: 0 automatic */
    int software;             /* the driver rasterizes on the CPU (llvmpipe) */
    GLuint fbo_draw, rb_color, rb_depth; /* drawn into (and read back from with one sample) */
    GLuint fbo_out, rb_out;              /* the multisampled drawing resolved, read back */
    int gl_ready;
    char info[256];
    program p_arrow, p_blit, p_plane;
    variant_prog *variants;   /* compiled at their first use */
    size_t n_variants, cap_variants;
    GLuint cmap_tex[6];
    GLuint vao_empty, vao_arrow, vbo_arrow, blit_tex;
    GLuint vao_plane, vbo_plane, plane_tex; /* image planes (render_draw.c): one quad, one texture, refilled per plane */
    size_t arrow_cap;
    surf_entry **cache;
    size_t n_cache, cap_cache;
    unsigned long frame;
    /* scratch, grown as needed */
    float *tbuf;
    size_t tbuf_cap;
    unsigned char *flags;
    size_t flags_cap;
    uint32_t *idx;
    size_t idx_cap;
    unsigned char *pix, *pix2;
    size_t pix_cap, pix2_cap;
    float *luma;
    size_t luma_cap;
    surf_entry **ents;
    size_t ents_cap;
    /* sort-first (thx_renderer_set_share), and the scissor rn_draw_scene uses while thx_render draws
       a band (GL's rows, from the bottom; scissor[2] == 0: the viewport's) */
    int share_rank, share_size;
    unsigned char *share_own;
    int scissor[4];
};

/* The caller's EGL context, display and surfaces, given back after a frame. */
typedef struct {
    EGLDisplay dpy;
    EGLContext ctx;
    EGLSurface draw, read;
} egl_current;

/* render.c: scratch buffers grown as needed (thx_grow when need exceeds cap). */
thx_status rn_grow(thx_ctx *ctx, void **p, size_t *cap, size_t need, size_t elem);

/* render_context.c: the EGL context and the offscreen framebuffers. */
thx_status rn_egl_open(thx_ctx *ctx, thx_renderer *r);
thx_status rn_make_current(thx_ctx *ctx, thx_renderer *r, egl_current *prev);
void rn_restore_current(const thx_renderer *r, const egl_current *prev);
void rn_free_framebuffers(thx_renderer *r);
thx_status rn_make_framebuffers(thx_ctx *ctx, thx_renderer *r);

/* render_shaders.c: programs, shared GL objects, colour map textures, GL errors. */
thx_status rn_gl_check(thx_ctx *ctx, const char *where);
thx_status rn_surface_program(thx_ctx *ctx, thx_renderer *r, variant v, const program **out);
thx_status rn_gl_init(thx_ctx *ctx, thx_renderer *r);
thx_status rn_cmap_texture(thx_ctx *ctx, thx_renderer *r, thx_colormap c, GLuint *out);

/* render_cache.c: the uploaded surfaces. */
void rn_entry_free_gl(surf_entry *e);
thx_status rn_cache_get(thx_ctx *ctx, thx_renderer *r, const thx_surface *s, const double *normals, surf_entry **out);
void rn_cache_trim(thx_renderer *r);
thx_status rn_entry_edges(thx_ctx *ctx, surf_entry *e, const thx_surface *s);

/* render_draw.c: the viewport's rectangle and the drawing of a scene into it. */
thx_status rn_viewport_rect(thx_ctx *ctx, const thx_scene *sc, int fb_w, int fb_h, int rect[4]);
thx_status rn_draw_scene(thx_ctx *ctx, thx_renderer *r, const thx_scene *sc, int fb_w, int fb_h, size_t *n_nan);

/* render_readback.c: the image into the framebuffer (clear = 0) and the drawing back out. */
thx_status rn_blit_image(thx_ctx *ctx, thx_renderer *r, const thx_raster *img, const int rect[4]);
/* The framebuffer's rect (resolved, or smoothed by FXAA over rect), its rows keep (within rect) into
 * img, divided by alpha; own (may be NULL): those pixels set to 1. */
thx_status rn_read_back(thx_ctx *ctx, thx_renderer *r, thx_raster *img, const int rect[4], const int keep[4], unsigned char *own);
/* rn_read_back's two halves: rect's pixels into r->pix (GL's rows), and r->pix smoothed, flipped and
 * divided by alpha into img's rows keep. */
thx_status rn_read_pixels(thx_ctx *ctx, thx_renderer *r, const int rect[4]);
thx_status rn_finish(thx_ctx *ctx, thx_renderer *r, thx_raster *img, const int rect[4], const int keep[4], unsigned char *own);
/* The rows FXAA reads above and below a pixel it smooths, and one more (render_readback.c). */
#define RN_FXAA_REACH 26

/* The camera's orthonormal frame: right, up and back (from the centre toward the eye). Returns -1
 * when the camera is degenerate (eye at the centre, up along the line of sight, non-finite). */
int cam_frame(const thx_camera *cam, double right[3], double up[3], double back[3]);
/* The view matrix (model to eye space); cam_frame must have succeeded. */
void cam_view_matrix(const thx_camera *cam, double m[16]);
/* The projection for a viewport of the given aspect (w / h) between the depths znear < zfar (eye
 * distances along the line of sight; znear > 0 in perspective, any sign when orthographic). */
void cam_proj_matrix(const thx_camera *cam, double aspect, double znear, double zfar, double m[16]);
/* Depths (distances in front of the eye along the line of sight) that enclose the box lo..hi with a
 * margin; in perspective znear is kept positive and at least zfar / 2000 (24-bit depth buffer). */
void cam_depth_range(const thx_camera *cam, const double lo[3], const double hi[3], double *znear, double *zfar);

#endif
