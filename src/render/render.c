/*
 * The 3D renderer (paper 4.2): OpenGL 3.3 core through libepoxy, offscreen
 * with EGL, or in the caller's context (the viewer).
 *
 * Pipeline of thx_render: make the renderer's EGL context current, draw the
 * scene into the framebuffer object's viewport, then either resolve the 4x
 * multisampled drawing (on a GPU) or smooth the single-sampled one with FXAA
 * on the CPU (on llvmpipe, where multisampling triples the time: see
 * docs/decisions.md, "Renderer"), read it back and flip it into the image
 * (GL's rows run bottom to top, thx_image's top to bottom).
 *
 * Invariants and conventions:
 *  - Colours are premultiplied by alpha inside the framebuffer (blending
 *    ONE, ONE_MINUS_SRC_ALPHA, for translucent surfaces only) and divided out
 *    at readback, so translucent surfaces over a transparent background come
 *    out right in the PNG.
 *  - Data are mapped to t = thx_scale_apply(scale, value) on the CPU (the
 *    exact function of thorax/image.h, in double); t is interpolated per
 *    pixel and looked up in a 1D texture of the colour map. A NaN value is
 *    sent as t = NAN_T, so that |t| > 2 anywhere inside a triangle touching
 *    it: those pixels take the NaN colour.
 *  - Band and contour arithmetic happens per pixel: the band is floor(t n)
 *    (thx_scale_band), the contour lines sit where t n crosses 1 .. n - 1,
 *    with a constant width in pixels from fwidth(t n).
 *  - Geometry is uploaded once per surface and kept in a cache keyed by the
 *    surface's address, its counts and array addresses, and a hash of its
 *    coordinates and triangles, so a redrawn mesh with new values only
 *    uploads one float per node; a freed surface whose address is reused, or
 *    a surface edited in place, is uploaded again.
 *  - Lighting is two-sided; a closed, consistently oriented, opaque surface
 *    seen from outside and not clipped draws only the side that can be seen.
 *  - Every GL object of a renderer belongs to one context: its own EGL
 *    context, or (w = h = 0) the context current at its first draw.
 *  - Clip planes are gl_ClipDistance 0 .. n_clip - 1, evaluated in model
 *    coordinates, so they cut surfaces and arrows alike.
 */
#include "render_internal.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SAMPLES 4
#define CMAP_N 1024     /* texels of a colour map's 1D texture */
#define CACHE_KEEP 32   /* surfaces kept uploaded beyond those of the current frame */

/* ------------------------------------------------------------------ shaders */

#define GLSL_VERSION "#version 330 core\n"

/* The headlight: a light at the eye (along the line of sight when orthographic), two-sided
 * (|n . l|), plus ambient; flat shading has no highlight. */
static const char *const GLSL_LIGHT =
    "const float KA = 0.25, KD = 0.75, KS = 0.2, SHINE = 40.0;\n"
    "uniform int u_ortho;\n"
    "vec2 headlight(vec3 n, vec3 eye) {\n"
    "    vec3 l = u_ortho == 1 ? vec3(0.0, 0.0, 1.0) : normalize(-eye);\n"
    "    float ln = length(n);\n"
    "    float d = ln > 0.0 ? abs(dot(n / ln, l)) : 1.0;\n"
    "    return vec2(d, pow(d, SHINE));\n"
    "}\n";

/*
 * The surface shaders come in variants, chosen by #defines, because llvmpipe runs both sides of
 * every branch and a shader that may discard loses the early depth test:
 *   PRIM   0 triangles, 1 round points, 2 lines (widened by the geometry shader)
 *   LIGHT  0 none, 1 flat (the face normal from screen derivatives), 2 Gouraud, 3 Phong
 *   DATA   1: colour by t per pixel; STYLE: thx_data_style
 *   SHRINK 1: points foreshortened by |n . view| (the orientation mode's back nodes)
 *   A2C    1: opaque round points through alpha to coverage
 *   CLIP   1: clip planes in use
 * The lighting inputs are interpolated at the centroid of the covered samples, so that multisampled
 * edge pixels never extrapolate the normal beyond the triangle (a highlight at a silhouette); t is
 * not, as the contour lines need its screen derivatives continuous across triangles.
 * t arrives per node; a NaN value is sent as NAN_T, so that |t| > 2 inside every triangle touching
 * it (the flag interpolates to a large value everywhere but on the opposite edge).
 */
#define GLSL_VOUT                     \
    "VOUT {\n"                        \
    "    float t;\n"                  \
    "#if LIGHT == 1 || LIGHT == 3\n"  \
    "    centroid vec3 eye;\n"        \
    "#endif\n"                        \
    "#if LIGHT == 3\n"                \
    "    centroid vec3 nrm;\n"        \
    "#endif\n"                        \
    "#if LIGHT == 2\n"                \
    "    centroid vec2 lit;\n"        \
    "#endif\n"                        \
    "#if SHRINK\n"                    \
    "    float ps;\n"                 \
    "#endif\n"                        \
    "#if PRIM == 2 && CLIP\n"         \
    "    vec4 clip;\n"                \
    "#endif\n"                        \
    "}"

#define NAN_T 1.0e6f

static const char *const VS_SURF =
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec3 a_nrm;\n"
    "layout(location = 2) in float a_t;\n"
    "uniform mat4 u_view, u_proj;\n"
    "uniform vec4 u_clip[4];\n"
    "uniform float u_point_size;\n"
    "out " GLSL_VOUT " vo;\n"
    "void main() {\n"
    "    vec4 e = u_view * vec4(a_pos, 1.0);\n"
    "    vec3 n = mat3(u_view) * a_nrm;\n"
    "    vo.t = a_t;\n"
    "#if LIGHT == 1 || LIGHT == 3\n"
    "    vo.eye = e.xyz;\n"
    "#endif\n"
    "#if LIGHT == 3\n"
    "    vo.nrm = n;\n"
    "#endif\n"
    "#if LIGHT == 2\n"
    "    vo.lit = headlight(n, e.xyz);\n"
    "#endif\n"
    "    gl_Position = u_proj * e;\n"
    "#if PRIM == 1\n"
    "    float ps = u_point_size;\n"
    "#if SHRINK\n"
    "    vec3 l = u_ortho == 1 ? vec3(0.0, 0.0, 1.0) : normalize(-e.xyz);\n"
    "    float ln = length(n);\n"
    "    ps *= ln > 0.0 ? abs(dot(n / ln, l)) : 1.0;\n"
    "    vo.ps = ps;\n"
    "    if (ps < 1.0) gl_Position = vec4(0.0, 0.0, -2.0, 1.0); /* outside: not drawn */\n"
    "#endif\n"
    "    gl_PointSize = max(ps, 1.0);\n"
    "#endif\n"
    "#if CLIP\n"
    "    vec4 c;\n"
    "    for (int i = 0; i < 4; i++) c[i] = dot(u_clip[i].xyz, a_pos) + u_clip[i].w;\n"
    "#if PRIM == 2\n"
    "    vo.clip = c;\n"
    "#else\n"
    "    gl_ClipDistance[0] = c.x; gl_ClipDistance[1] = c.y; gl_ClipDistance[2] = c.z; gl_ClipDistance[3] = c.w;\n"
    "#endif\n"
    "#endif\n"
    "}\n";

/* Lines of constant pixel width: each segment becomes a screen-aligned quad, extended by half the
 * width at both ends so that the edges of a mesh join. */
static const char *const GS_LINES =
    "layout(lines) in;\n"
    "layout(triangle_strip, max_vertices = 4) out;\n"
    "in " GLSL_VOUT " gi[];\n"
    "out " GLSL_VOUT " go;\n"
    "uniform vec2 u_vp;\n"
    "uniform float u_lw;\n"
    "void put(int i, vec2 off) {\n"
    "    go.t = gi[i].t;\n"
    "    vec4 p = gl_in[i].gl_Position;\n"
    "    gl_Position = vec4(p.xy + off * p.w, p.zw);\n"
    "#if CLIP\n"
    "    go.clip = gi[i].clip;\n"
    "    gl_ClipDistance[0] = gi[i].clip.x; gl_ClipDistance[1] = gi[i].clip.y;\n"
    "    gl_ClipDistance[2] = gi[i].clip.z; gl_ClipDistance[3] = gi[i].clip.w;\n"
    "#endif\n"
    "    EmitVertex();\n"
    "}\n"
    "void main() {\n"
    "    vec4 p0 = gl_in[0].gl_Position, p1 = gl_in[1].gl_Position;\n"
    "    if (p0.w <= 0.0 || p1.w <= 0.0) return;\n"
    "    vec2 d = (p1.xy / p1.w - p0.xy / p0.w) * 0.5 * u_vp;\n"
    "    float len = length(d);\n"
    "    vec2 dir = len > 1e-4 ? d / len : vec2(1.0, 0.0);\n"
    "    vec2 nrm = vec2(-dir.y, dir.x);\n"
    "    float hw = 0.5 * u_lw;\n"
    "    vec2 px = 2.0 / u_vp;\n"
    "    put(0, (-dir + nrm) * hw * px);\n"
    "    put(0, (-dir - nrm) * hw * px);\n"
    "    put(1, (dir + nrm) * hw * px);\n"
    "    put(1, (dir - nrm) * hw * px);\n"
    "    EndPrimitive();\n"
    "}\n";

static const char *const FS_SURF =
    "#define CONTOURS (PRIM == 0 && DATA && STYLE >= 2)\n"
    "in " GLSL_VOUT " fi;\n"
    "uniform int u_nlev;\n"
    "uniform float u_lw, u_point_size, u_cmap_n;\n"
    "uniform vec4 u_color, u_nan_color, u_contour_color;\n"
    "uniform sampler1D u_cmap;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    float n = float(max(u_nlev, 1));\n"
    "#if CONTOURS\n"
    "    float f = fi.t * n;\n"
    "    float fw = fwidth(f);\n"
    "#endif\n"
    "#if LIGHT == 1\n"
    "    vec3 fn = cross(dFdx(fi.eye), dFdy(fi.eye));\n"
    "#endif\n"
    "    float cov = 1.0;\n"
    "#if PRIM == 1\n"
    "    float r = length(gl_PointCoord * 2.0 - 1.0);\n"
    "#if SHRINK\n"
    "    float ps = fi.ps;\n"
    "#else\n"
    "    float ps = u_point_size;\n"
    "#endif\n"
    "    cov = clamp((1.0 - r) * 0.5 * ps + 0.5, 0.0, 1.0);\n"
    "    if (cov <= 0.0) discard;\n"
    "#endif\n"
    "    vec4 base = u_color;\n"
    "    float line = 0.0;\n"
    "#if DATA\n"
    "    if (abs(fi.t) > 2.0) base = u_nan_color;\n"
    "    else {\n"
    "        float t = clamp(fi.t, 0.0, 1.0);\n"
    "#if STYLE == 1 || STYLE == 3\n"
    "        t = (min(floor(t * n), n - 1.0) + 0.5) / n;\n"
    "#endif\n"
    "#if STYLE != 2\n"
    "        base.rgb = texture(u_cmap, (t * (u_cmap_n - 1.0) + 0.5) / u_cmap_n).rgb;\n"
    "#endif\n"
    "#if CONTOURS\n"
    "        float k = floor(f + 0.5);\n"
    "        if (k >= 1.0 && k <= n - 1.0 && fw > 0.0) line = clamp(0.5 * u_lw - abs(f - k) / fw + 0.5, 0.0, 1.0);\n"
    "#endif\n"
    "    }\n"
    "#endif\n"
    "    vec3 rgb = base.rgb;\n"
    "#if LIGHT == 1\n"
    "    rgb *= KA + KD * headlight(fn, fi.eye).x;\n"
    "#elif LIGHT == 2\n"
    "    rgb = rgb * (KA + KD * fi.lit.x) + KS * fi.lit.y;\n"
    "#elif LIGHT == 3\n"
    "    vec2 l = headlight(fi.nrm, fi.eye);\n"
    "    rgb = rgb * (KA + KD * l.x) + KS * l.y;\n"
    "#endif\n"
    "#if CONTOURS\n"
    "    rgb = mix(rgb, u_contour_color.rgb, line * u_contour_color.a);\n"
    "#endif\n"
    "    rgb = clamp(rgb, 0.0, 1.0);\n"
    "#if A2C\n"
    "    o_color = vec4(rgb, cov);\n"
    "#else\n"
    "    o_color = vec4(rgb * base.a * cov, base.a * cov);\n"
    "#endif\n"
    "}\n";

/* Arrows: one vertex per arrow (tail, displacement to the tip, t or -1); the geometry shader
 * builds a shaft of the given pixel width and a head in screen space, at the arrow's depth. */
static const char *const VS_ARROW =
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec3 a_vec;\n"
    "layout(location = 2) in float a_t;\n"
    "uniform mat4 u_view, u_proj;\n"
    "uniform vec4 u_clip[4];\n"
    "out AOUT { vec4 tip; vec4 c0; vec4 c1; float t; } ao;\n"
    "vec4 clipd(vec3 p) {\n"
    "    vec4 c;\n"
    "    for (int i = 0; i < 4; i++) c[i] = dot(u_clip[i].xyz, p) + u_clip[i].w;\n"
    "    return c;\n"
    "}\n"
    "void main() {\n"
    "    vec3 q = a_pos + a_vec;\n"
    "    gl_Position = u_proj * u_view * vec4(a_pos, 1.0);\n"
    "    ao.tip = u_proj * u_view * vec4(q, 1.0);\n"
    "    ao.c0 = clipd(a_pos);\n"
    "    ao.c1 = clipd(q);\n"
    "    ao.t = a_t;\n"
    "}\n";

static const char *const GS_ARROW =
    "layout(points) in;\n"
    "layout(triangle_strip, max_vertices = 7) out;\n"
    "in AOUT { vec4 tip; vec4 c0; vec4 c1; float t; } ai[];\n"
    "out AF { float t; } af;\n"
    "uniform vec2 u_vp;\n"
    "uniform float u_lw;\n"
    "vec4 P0, P1, C0, C1;\n"
    "void put(vec2 s, float f) {\n"
    "    vec4 p = mix(P0, P1, f);\n"
    "    gl_Position = vec4(s / (0.5 * u_vp) * p.w, p.z, p.w);\n"
    "    vec4 c = mix(C0, C1, f);\n"
    "    gl_ClipDistance[0] = c.x; gl_ClipDistance[1] = c.y; gl_ClipDistance[2] = c.z; gl_ClipDistance[3] = c.w;\n"
    "    af.t = ai[0].t;\n"
    "    EmitVertex();\n"
    "}\n"
    "void main() {\n"
    "    P0 = gl_in[0].gl_Position; P1 = ai[0].tip; C0 = ai[0].c0; C1 = ai[0].c1;\n"
    "    if (P0.w <= 0.0 || P1.w <= 0.0) return;\n"
    "    vec2 s0 = P0.xy / P0.w * 0.5 * u_vp, s1 = P1.xy / P1.w * 0.5 * u_vp;\n"
    "    vec2 d = s1 - s0;\n"
    "    float len = length(d);\n"
    "    if (len < 0.5) return;\n"
    "    vec2 dir = d / len, nrm = vec2(-dir.y, dir.x);\n"
    "    float w = max(u_lw, 1.0);\n"
    "    float hl = min(0.4 * len, 4.0 * w + 6.0);\n"
    "    float hw = max(0.4 * hl, w);\n"
    "    float fb = 1.0 - hl / len;\n"
    "    vec2 sb = s1 - dir * hl;\n"
    "    put(s0 + nrm * 0.5 * w, 0.0);\n"
    "    put(s0 - nrm * 0.5 * w, 0.0);\n"
    "    put(sb + nrm * 0.5 * w, fb);\n"
    "    put(sb - nrm * 0.5 * w, fb);\n"
    "    EndPrimitive();\n"
    "    put(sb + nrm * hw, fb);\n"
    "    put(sb - nrm * hw, fb);\n"
    "    put(s1, 1.0);\n"
    "    EndPrimitive();\n"
    "}\n";

static const char *const FS_ARROW =
    "in AF { float t; } fi;\n"
    "uniform vec4 u_color;\n"
    "uniform sampler1D u_cmap;\n"
    "uniform float u_cmap_n;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    vec3 rgb = fi.t >= 0.0 ? texture(u_cmap, (clamp(fi.t, 0.0, 1.0) * (u_cmap_n - 1.0) + 0.5) / u_cmap_n).rgb\n"
    "                           : u_color.rgb;\n"
    "    o_color = vec4(rgb * u_color.a, u_color.a);\n"
    "}\n";

/* The image's pixels under a viewport that is not cleared (thx_render with clear = 0). */
static const char *const VS_BLIT =
    "void main() {\n"
    "    gl_Position = vec4(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0, 0.0, 1.0);\n"
    "}\n";

static const char *const FS_BLIT =
    "uniform sampler2D u_tex;\n"
    "uniform ivec4 u_rect;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    ivec2 q = ivec2(gl_FragCoord.xy) - u_rect.xy;\n"
    "    o_color = texelFetch(u_tex, ivec2(q.x, u_rect.w - 1 - q.y), 0);\n"
    "}\n";

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
    program p_arrow, p_blit;
    variant_prog *variants;   /* compiled at their first use */
    size_t n_variants, cap_variants;
    GLuint cmap_tex[6];
    GLuint vao_empty, vao_arrow, vbo_arrow, blit_tex;
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
};

/* ---------------------------------------------------------------------- EGL */

static const char *egl_error_name(EGLint e)
{
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    }
    return "unknown EGL error";
}

static const char *gl_error_name(GLenum e)
{
    switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    }
    return "unknown GL error";
}

/* Whether the space-separated extension list has the word ext. */
static int has_ext(const char *list, const char *ext)
{
    size_t n = strlen(ext);
    for (const char *p = list; p && (p = strstr(p, ext)) != NULL; p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return 1;
    return 0;
}

/*
 * EGL displays are process-wide: eglInitialize on an initialized display does nothing, and
 * eglTerminate would end the contexts of every other renderer on it. So a renderer initializes its
 * display and never terminates it; Mesa finalizes its displays at exit. (Terminating after the last
 * renderer would need a process-wide reference count, and unloading the driver then leaves
 * allocations that LeakSanitizer reports against an unknown module.)
 */
/* The OpenGL version a display offers without asking for any (for the error message). */
static void probe_default_version(EGLDisplay dpy, EGLConfig cfg, int surfaceless, char *out, size_t n)
{
    snprintf(out, n, "no OpenGL context at all (%s)", egl_error_name(eglGetError()));
    EGLContext c = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, NULL);
    if (c == EGL_NO_CONTEXT) return;
    EGLSurface s = EGL_NO_SURFACE;
    if (!surfaceless) {
        const EGLint pa[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
        s = eglCreatePbufferSurface(dpy, cfg, pa);
    }
    if (eglMakeCurrent(dpy, s, s, c)) {
        const char *v = (const char *)glGetString(GL_VERSION), *rn = (const char *)glGetString(GL_RENDERER);
        snprintf(out, n, "got %s, %s", v ? v : "?", rn ? rn : "?");
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    if (s != EGL_NO_SURFACE) eglDestroySurface(dpy, s);
    eglDestroyContext(dpy, c);
}

/* Tries to make an OpenGL 3.3 core context on dpy; 0 on success (r->dpy, egl, pbuf set and the
 * context current), else -1 with the reason in why. no_display: set when the display could not even
 * be initialized. */
static int try_display(thx_renderer *r, EGLDisplay dpy, const char *platform, char *why, size_t nwhy, int *no_display)
{
    EGLint major = 0, minor = 0;
    *no_display = 0;
    if (dpy == EGL_NO_DISPLAY) {
        snprintf(why, nwhy, "%s: no display (%s)", platform, egl_error_name(eglGetError()));
        *no_display = 1;
        return -1;
    }
    if (!eglInitialize(dpy, &major, &minor)) {
        snprintf(why, nwhy, "%s: eglInitialize failed (%s)", platform, egl_error_name(eglGetError()));
        *no_display = 1;
        return -1;
    }
    const char *exts = eglQueryString(dpy, EGL_EXTENSIONS);
    int surfaceless = has_ext(exts, "EGL_KHR_surfaceless_context");
    int create_ctx = (major > 1 || minor >= 5) || has_ext(exts, "EGL_KHR_create_context");
    if (!eglBindAPI(EGL_OPENGL_API)) {
        snprintf(why, nwhy, "%s (EGL %d.%d): no desktop OpenGL API (%s)", platform, major, minor,
                 egl_error_name(eglGetError()));
        return -1;
    }
    const EGLint ca[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, surfaceless ? 0 : EGL_PBUFFER_BIT,
                         EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
    EGLConfig cfg;
    EGLint n_cfg = 0;
    if (!eglChooseConfig(dpy, ca, &cfg, 1, &n_cfg) || n_cfg < 1) {
        snprintf(why, nwhy, "%s (EGL %d.%d): no RGB8 OpenGL config (%s)", platform, major, minor,
                 egl_error_name(eglGetError()));
        return -1;
    }
    if (!create_ctx) {
        snprintf(why, nwhy, "%s (EGL %d.%d): cannot ask for a version (no EGL_KHR_create_context)", platform, major,
                 minor);
        return -1;
    }
    const EGLint xa[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                         EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext c = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, xa);
    if (c == EGL_NO_CONTEXT) {
        char got[160];
        probe_default_version(dpy, cfg, surfaceless, got, sizeof got);
        snprintf(why, nwhy, "%s: %s", platform, got);
        return -1;
    }
    EGLSurface s = EGL_NO_SURFACE;
    if (!surfaceless) {
        const EGLint pa[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
        s = eglCreatePbufferSurface(dpy, cfg, pa);
        if (s == EGL_NO_SURFACE) {
            snprintf(why, nwhy, "%s: no pbuffer surface (%s)", platform, egl_error_name(eglGetError()));
            eglDestroyContext(dpy, c);
            return -1;
        }
    }
    if (!eglMakeCurrent(dpy, s, s, c)) {
        snprintf(why, nwhy, "%s: eglMakeCurrent failed (%s)", platform, egl_error_name(eglGetError()));
        if (s != EGL_NO_SURFACE) eglDestroySurface(dpy, s);
        eglDestroyContext(dpy, c);
        return -1;
    }
    if (epoxy_gl_version() < 33 || !epoxy_is_desktop_gl()) {
        const char *v = (const char *)glGetString(GL_VERSION);
        snprintf(why, nwhy, "%s: got %s", platform, v ? v : "?");
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (s != EGL_NO_SURFACE) eglDestroySurface(dpy, s);
        eglDestroyContext(dpy, c);
        return -1;
    }
    r->dpy = dpy;
    r->egl = c;
    r->pbuf = s;
    return 0;
}

/* Finds a display with OpenGL 3.3 core: Mesa's surfaceless platform (a GPU's render node, else
 * llvmpipe), then each EGL device (NVIDIA's driver has no surfaceless platform), then the default
 * display. The context is left current. */
static thx_status egl_open(thx_ctx *ctx, thx_renderer *r)
{
    char why[3][320] = {"", "", ""};
    int n_why = 0, displays = 0, nd;
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS); /* NULL without client extensions */
    int platform_base = has_ext(client, "EGL_EXT_platform_base");
    if (platform_base && has_ext(client, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        if (try_display(r, d, "surfaceless", why[n_why], sizeof why[0], &nd) == 0) return THX_OK;
        displays += !nd;
        n_why++;
    }
    if (platform_base && has_ext(client, "EGL_EXT_platform_device") && has_ext(client, "EGL_EXT_device_enumeration")) {
        EGLDeviceEXT dev[8];
        EGLint n_dev = 0;
        if (eglQueryDevicesEXT(8, dev, &n_dev))
            for (EGLint i = 0; i < n_dev; i++) {
                EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev[i], NULL);
                char platform[32];
                snprintf(platform, sizeof platform, "device %d", (int)i);
                if (try_display(r, d, platform, why[n_why], sizeof why[0], &nd) == 0) return THX_OK;
                displays += !nd;
            }
        if (why[n_why][0]) n_why++;
    }
    if (try_display(r, eglGetDisplay(EGL_DEFAULT_DISPLAY), "default display", why[n_why], sizeof why[0], &nd) == 0)
        return THX_OK;
    displays += !nd;
    n_why++;
    char all[1024] = "";
    for (int i = 0; i < n_why; i++) {
        size_t l = strlen(all);
        snprintf(all + l, sizeof all - l, "%s%s", i ? "; " : "", why[i]);
    }
    if (!displays) return thx_error(ctx, THX_EIO, "renderer: no EGL display (is Mesa's libEGL installed?): %s", all);
    return thx_error(ctx, THX_EIO, "renderer: OpenGL 3.3 core not available: %s", all);
}

/* ------------------------------------------------------------ GL resources */

static thx_status gl_check(thx_ctx *ctx, const char *where)
{
    GLenum e = glGetError(), first = e;
    if (e == GL_NO_ERROR) return THX_OK;
    while (e != GL_NO_ERROR) e = glGetError();
    return thx_error(ctx, THX_EINTERNAL, "renderer: OpenGL error %s (0x%x) %s", gl_error_name(first), first, where);
}

static thx_status compile(thx_ctx *ctx, GLenum type, const char *name, const char *defs, const char *body, GLuint *out)
{
    const char *src[4] = {GLSL_VERSION, defs, GLSL_LIGHT, body};
    GLuint s = glCreateShader(type);
    glShaderSource(s, 4, src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        glDeleteShader(s);
        return thx_error(ctx, THX_EINTERNAL, "renderer: the %s shader does not compile: %s", name, log);
    }
    *out = s;
    return THX_OK;
}

/* A program from a vertex, an optional geometry and a fragment shader. */
static thx_status make_program(thx_ctx *ctx, const char *name, const char *defs, const char *vs, const char *gs,
                               const char *fs, program *p)
{
    GLuint sh[3] = {0, 0, 0};
    thx_status st = THX_OK;
    char what[64];
    snprintf(what, sizeof what, "%s vertex", name);
    THX_TRY(compile(ctx, GL_VERTEX_SHADER, what, defs, vs, &sh[0]));
    if (gs) {
        snprintf(what, sizeof what, "%s geometry", name);
        THX_TRY(compile(ctx, GL_GEOMETRY_SHADER, what, defs, gs, &sh[1]));
    }
    snprintf(what, sizeof what, "%s fragment", name);
    THX_TRY(compile(ctx, GL_FRAGMENT_SHADER, what, defs, fs, &sh[2]));
    GLuint id = glCreateProgram();
    for (int i = 0; i < 3; i++)
        if (sh[i]) glAttachShader(id, sh[i]);
    glLinkProgram(id);
    GLint ok = 0;
    glGetProgramiv(id, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = "";
        glGetProgramInfoLog(id, sizeof log, NULL, log);
        glDeleteProgram(id);
        st = thx_error(ctx, THX_EINTERNAL, "renderer: the %s shaders do not link: %s", name, log);
        goto done;
    }
    memset(p, 0, sizeof *p);
    p->id = id;
#define LOC(f, n) p->f = glGetUniformLocation(id, n)
    LOC(view, "u_view"); LOC(proj, "u_proj"); LOC(clip, "u_clip"); LOC(ortho, "u_ortho"); LOC(vp, "u_vp");
    LOC(point_size, "u_point_size"); LOC(nlev, "u_nlev"); LOC(lw, "u_lw"); LOC(cmap, "u_cmap");
    LOC(cmap_n, "u_cmap_n"); LOC(color, "u_color"); LOC(nan_color, "u_nan_color");
    LOC(contour_color, "u_contour_color"); LOC(tex, "u_tex"); LOC(rect, "u_rect");
#undef LOC
    glUseProgram(id);
    if (p->cmap >= 0) glUniform1i(p->cmap, 0);
    if (p->cmap_n >= 0) glUniform1f(p->cmap_n, (float)CMAP_N);
    if (p->tex >= 0) glUniform1i(p->tex, 0);
    glUseProgram(0);
done:
    for (int i = 0; i < 3; i++)
        if (sh[i]) glDeleteShader(sh[i]);
    return st;
}

/* The surface program of a variant, compiled at its first use. */
static thx_status surface_program(thx_ctx *ctx, thx_renderer *r, variant v, const program **out)
{
    for (size_t i = 0; i < r->n_variants; i++)
        if (memcmp(&r->variants[i].key, &v, sizeof v) == 0) {
            *out = &r->variants[i].prog;
            return THX_OK;
        }
    THX_CHECK(thx_grow(ctx, (void **)&r->variants, &r->cap_variants, r->n_variants + 1, sizeof *r->variants));
    char defs[256], name[64];
    snprintf(defs, sizeof defs,
             "#define PRIM %d\n#define LIGHT %d\n#define DATA %d\n#define STYLE %d\n#define SHRINK %d\n"
             "#define A2C %d\n#define CLIP %d\n",
             v.prim, v.light, v.data, v.style, v.shrink, v.a2c, v.clip);
    snprintf(name, sizeof name, "%s", v.prim == 0 ? "triangle" : v.prim == 1 ? "point" : "line");
    variant_prog *vp = &r->variants[r->n_variants];
    THX_CHECK(make_program(ctx, name, defs, VS_SURF, v.prim == 2 ? GS_LINES : NULL, FS_SURF, &vp->prog));
    vp->key = v;
    r->n_variants++;
    *out = &vp->prog;
    return THX_OK;
}

/* Programs and shared objects, in the current context (once per renderer). */
static thx_status gl_init(thx_ctx *ctx, thx_renderer *r)
{
    if (r->gl_ready) return THX_OK;
    if (epoxy_gl_version() < 33 || !epoxy_is_desktop_gl()) {
        const char *v = (const char *)glGetString(GL_VERSION);
        return thx_error(ctx, THX_EIO, "renderer: OpenGL 3.3 core not available: got %s", v ? v : "?");
    }
    const char *v = (const char *)glGetString(GL_VERSION), *rn = (const char *)glGetString(GL_RENDERER);
    snprintf(r->info, sizeof r->info, "OpenGL %s, %s", v ? v : "?", rn ? rn : "?");
    const variant first = {0, 3, 1, THX_DATA_CONTINUOUS, 0, 0, 0};
    const program *unused;
    THX_CHECK(surface_program(ctx, r, first, &unused)); /* a compile error shows at once */
    THX_CHECK(make_program(ctx, "arrow", "", VS_ARROW, GS_ARROW, FS_ARROW, &r->p_arrow));
    THX_CHECK(make_program(ctx, "blit", "", VS_BLIT, NULL, FS_BLIT, &r->p_blit));
    glGenVertexArrays(1, &r->vao_empty);
    glGenVertexArrays(1, &r->vao_arrow);
    glGenBuffers(1, &r->vbo_arrow);
    glBindVertexArray(r->vao_arrow);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_arrow);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), (void *)(3 * sizeof(float)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, 7 * sizeof(float), (void *)(6 * sizeof(float)));
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    THX_CHECK(gl_check(ctx, "setting up the shaders"));
    r->gl_ready = 1;
    return THX_OK;
}

/* The colour map as a 1D texture (made at its first use). */
static thx_status cmap_texture(thx_ctx *ctx, thx_renderer *r, thx_colormap c, GLuint *out)
{
    if ((int)c < 0 || (int)c >= 6) return thx_error(ctx, THX_EINPUT, "renderer: unknown colour map %d", (int)c);
    if (!r->cmap_tex[c]) {
        unsigned char rgb[3 * CMAP_N];
        thx_colormap_table(c, CMAP_N, rgb);
        glGenTextures(1, &r->cmap_tex[c]);
        glBindTexture(GL_TEXTURE_1D, r->cmap_tex[c]);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage1D(GL_TEXTURE_1D, 0, GL_RGB8, CMAP_N, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_1D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    }
    *out = r->cmap_tex[c];
    return THX_OK;
}

static void free_framebuffers(thx_renderer *r)
{
    GLuint fb[2] = {r->fbo_draw, r->fbo_out}, rb[3] = {r->rb_color, r->rb_depth, r->rb_out};
    glDeleteFramebuffers(2, fb);
    glDeleteRenderbuffers(3, rb);
    r->fbo_draw = r->fbo_out = r->rb_color = r->rb_depth = r->rb_out = 0;
}

/* A framebuffer of RGBA8 colour (and depth when with_depth) with the given samples (1: plain). */
static thx_status make_fbo(thx_ctx *ctx, int w, int h, int samples, int with_depth, GLuint *fbo, GLuint *color,
                           GLuint *depth)
{
    glGenFramebuffers(1, fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
    glGenRenderbuffers(1, color);
    glBindRenderbuffer(GL_RENDERBUFFER, *color);
    if (samples > 1) glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
    else glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, *color);
    if (with_depth) {
        glGenRenderbuffers(1, depth);
        glBindRenderbuffer(GL_RENDERBUFFER, *depth);
        if (samples > 1) glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
        else glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *depth);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    GLenum fs = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (fs != GL_FRAMEBUFFER_COMPLETE)
        return thx_error(ctx, THX_EINTERNAL, "renderer: the %d-sample framebuffer is incomplete (0x%x)", samples, fs);
    return THX_OK;
}

/* The offscreen framebuffers for r->samples_asked: the one drawn into (4x multisampled, or single
 * sampled), and for multisampling the one it is resolved into. */
static thx_status make_framebuffers(thx_ctx *ctx, thx_renderer *r)
{
    GLint max_samples = 0, max_rb = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
    if (r->w > max_rb || r->h > max_rb)
        return thx_error(ctx, THX_EINPUT, "renderer: %d x %d pixels exceed the driver's limit of %d", r->w, r->h,
                         max_rb);
    int want = r->samples_asked ? r->samples_asked : r->software ? 1 : MAX_SAMPLES;
    r->samples = want > 1 && max_samples >= MAX_SAMPLES ? MAX_SAMPLES : 1;
    free_framebuffers(r);
    if (r->samples > 1) THX_CHECK(make_fbo(ctx, r->w, r->h, 1, 0, &r->fbo_out, &r->rb_out, NULL));
    THX_CHECK(make_fbo(ctx, r->w, r->h, r->samples, 1, &r->fbo_draw, &r->rb_color, &r->rb_depth));
    return gl_check(ctx, "creating the framebuffers");
}

static thx_status grow(thx_ctx *ctx, void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return THX_OK;
    return thx_grow(ctx, p, cap, need, elem);
}

/* ---------------------------------------------------------- surface cache */

static uint64_t hash_bytes(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = data;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, b + i, 8);
        h = (h ^ w) * 0x100000001b3ULL;
        h ^= h >> 29;
    }
    for (; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
    return h;
}

static uint64_t surface_hash(const thx_surface *s)
{
    uint64_t h = 0xcbf29ce484222325ULL;
    if (s->xyz) h = hash_bytes(h, s->xyz, 3 * s->n_nodes * sizeof *s->xyz);
    if (s->tri) h = hash_bytes(h, s->tri, 3 * s->n_tris * sizeof *s->tri);
    return h;
}

static void entry_free_gl(surf_entry *e)
{
    GLuint b[5] = {e->vbo_geo, e->vbo_t, e->ebo_tri, e->ebo_edge, e->ebo_pts};
    glDeleteBuffers(5, b);
    glDeleteVertexArrays(1, &e->vao);
}

/* Whether the triangles form a closed, consistently oriented surface: every edge used exactly twice,
 * once in each direction. The directed edges are bucketed by their lower node and each bucket sorted:
 * O(edges). Returns 1 when closed and consistent, 0 when not, -1 when out of memory. */
static int closed_consistent(const thx_surface *s)
{
    size_t nn = s->n_nodes, nt = s->n_tris;
    if (!nt) return 0;
    size_t *start = calloc(nn + 2, sizeof *start);
    uint64_t *other = malloc(3 * nt * sizeof *other);
    int ok = 1;
    if (!start || !other) {
        ok = -1;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            start[(a < b ? a : b) + 2]++;
        }
    for (size_t i = 2; i < nn + 2; i++) start[i] += start[i - 1];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            /* the upper node, and the direction in the lowest bit */
            other[start[(a < b ? a : b) + 1]++] = 2 * (uint64_t)(a < b ? b : a) + (a > b);
        }
    for (size_t i = 0; i < nn && ok; i++) {
        size_t b0 = start[i], b1 = start[i + 1];
        for (size_t j = b0 + 1; j < b1; j++) {
            uint64_t x = other[j];
            size_t k = j;
            for (; k > b0 && other[k - 1] > x; k--) other[k] = other[k - 1];
            other[k] = x;
        }
        if ((b1 - b0) % 2) ok = 0;
        for (size_t j = b0; j + 1 < b1 && ok; j += 2) /* pairs (2 u, 2 u + 1), each upper node once */
            if (other[j] % 2 || other[j + 1] != other[j] + 1 || (j + 2 < b1 && other[j + 2] / 2 == other[j] / 2))
                ok = 0;
    }
done:
    free(start);
    free(other);
    return ok;
}

/* Uploads the geometry of s into e: positions and area-weighted vertex normals (floats,
 * interleaved), a per-node value buffer, and the triangles. */
static thx_status entry_upload(thx_ctx *ctx, surf_entry *e, const thx_surface *s, uint64_t hash)
{
    size_t nn = s->n_nodes, nt = s->n_tris;
    if (nn > UINT32_MAX || nt > (size_t)INT_MAX / 3 || (nn && !s->xyz) || (nt && !s->tri))
        return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": %zu nodes and %zu triangles cannot be drawn",
                         s->name, nn, nt);
    for (size_t i = 0; i < 3 * nt; i++)
        if (s->tri[i] < 0 || (size_t)s->tri[i] >= nn)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": triangle %zu has node %d of %zu", s->name,
                             i / 3, (int)s->tri[i], nn);
    for (size_t i = 0; i < 3 * nn; i++)
        if (!isfinite(s->xyz[i]))
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": node %zu has a non-finite coordinate",
                             s->name, i / 3);
    double *acc = thx_calloc(ctx, 3 * nn + 1, sizeof *acc);
    float *geo = thx_malloc(ctx, (6 * nn + 1) * sizeof *geo);
    if (!acc || !geo) {
        free(acc);
        free(geo);
        return THX_ENOMEM;
    }
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = s->tri + 3 * t;
        const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) acc[3 * (size_t)v[k] + j] += n[j];
    }
    for (int k = 0; k < 3; k++) e->lo[k] = INFINITY, e->hi[k] = -INFINITY;
    for (size_t i = 0; i < nn; i++) {
        double *n = acc + 3 * i, l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) {
            double x = s->xyz[3 * i + k];
            geo[6 * i + k] = (float)x;
            geo[6 * i + 3 + k] = l > 0 ? (float)(n[k] / l) : (k == 2 ? 1.0f : 0.0f);
            e->lo[k] = fmin(e->lo[k], x);
            e->hi[k] = fmax(e->hi[k], x);
        }
    }
    free(acc);
    if (!e->vao) {
        glGenVertexArrays(1, &e->vao);
        glGenBuffers(1, &e->vbo_geo);
        glGenBuffers(1, &e->vbo_t);
        glGenBuffers(1, &e->ebo_tri);
    }
    glBindVertexArray(e->vao);
    glBindBuffer(GL_ARRAY_BUFFER, e->vbo_geo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(6 * nn * sizeof(float)), geo, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)(3 * sizeof(float)));
    glBindBuffer(GL_ARRAY_BUFFER, e->vbo_t);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nn * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(float), (void *)0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_tri);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(3 * nt * sizeof(uint32_t)), s->tri, GL_STATIC_DRAW);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    free(geo);
    e->surf = s;
    e->n_nodes = nn;
    e->n_tris = nt;
    e->xyz = s->xyz;
    e->tri = s->tri;
    e->hash = hash;
    e->edges_ok = 0;
    e->n_edges = 0;
    int closed = closed_consistent(s);
    if (closed < 0) return thx_error(ctx, THX_ENOMEM, "renderer: out of memory checking surface \"%s\"", s->name);
    e->cull = closed ? (thx_surface_volume(s) > 0 ? GL_BACK : GL_FRONT) : 0;
    return gl_check(ctx, "uploading a surface");
}

/* The cache entry of s, uploading it when it is new or has changed. */
static thx_status cache_get(thx_ctx *ctx, thx_renderer *r, const thx_surface *s, surf_entry **out)
{
    uint64_t h = surface_hash(s);
    surf_entry *same_ptr = NULL;
    for (size_t i = 0; i < r->n_cache; i++) {
        surf_entry *e = r->cache[i];
        if (e->surf != s) continue;
        if (e->n_nodes == s->n_nodes && e->n_tris == s->n_tris && e->xyz == s->xyz && e->tri == s->tri &&
            e->hash == h) {
            e->last_used = r->frame;
            *out = e;
            return THX_OK;
        }
        same_ptr = e;
    }
    surf_entry *e = same_ptr;
    if (!e) {
        THX_CHECK(grow(ctx, (void **)&r->cache, &r->cap_cache, r->n_cache + 1, sizeof *r->cache));
        e = thx_calloc(ctx, 1, sizeof *e);
        if (!e) return THX_ENOMEM;
        r->cache[r->n_cache++] = e;
    }
    e->last_used = r->frame;
    thx_status st = entry_upload(ctx, e, s, h);
    if (st != THX_OK) e->surf = NULL; /* never matches until uploaded again */
    *out = e;
    return st;
}

/* Drops the least recently used entries beyond CACHE_KEEP that the current frame did not use. */
static void cache_trim(thx_renderer *r)
{
    while (r->n_cache > CACHE_KEEP) {
        size_t oldest = SIZE_MAX;
        for (size_t i = 0; i < r->n_cache; i++)
            if (r->cache[i]->last_used != r->frame &&
                (oldest == SIZE_MAX || r->cache[i]->last_used < r->cache[oldest]->last_used))
                oldest = i;
        if (oldest == SIZE_MAX) return;
        entry_free_gl(r->cache[oldest]);
        free(r->cache[oldest]);
        r->cache[oldest] = r->cache[--r->n_cache];
    }
}

/* The unique edges of the triangles, for the wire mode (built at its first use): the edges are
 * bucketed by their lower node, each bucket sorted and deduplicated, in O(edges). */
static thx_status entry_edges(thx_ctx *ctx, surf_entry *e, const thx_surface *s)
{
    if (e->edges_ok) return THX_OK;
    size_t nn = s->n_nodes, nt = s->n_tris;
    size_t *start = thx_calloc(ctx, nn + 2, sizeof *start);
    uint32_t *other = thx_malloc(ctx, (3 * nt + 1) * sizeof *other);
    uint32_t *pairs = thx_malloc(ctx, (6 * nt + 1) * sizeof *pairs);
    thx_status st = THX_OK;
    if (!start || !other || !pairs) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            start[(a < b ? a : b) + 2]++;
        }
    for (size_t i = 2; i < nn + 2; i++) start[i] += start[i - 1];
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = (uint32_t)s->tri[3 * t + k], b = (uint32_t)s->tri[3 * t + (k + 1) % 3];
            other[start[(a < b ? a : b) + 1]++] = a < b ? b : a;
        }
    size_t ne = 0;
    for (size_t i = 0; i < nn; i++) {
        size_t b0 = start[i], b1 = start[i + 1];
        for (size_t j = b0 + 1; j < b1; j++) { /* insertion sort: buckets hold a handful */
            uint32_t x = other[j];
            size_t k = j;
            for (; k > b0 && other[k - 1] > x; k--) other[k] = other[k - 1];
            other[k] = x;
        }
        for (size_t j = b0; j < b1; j++)
            if (j == b0 || other[j] != other[j - 1]) {
                pairs[2 * ne] = (uint32_t)i;
                pairs[2 * ne + 1] = other[j];
                ne++;
            }
    }
    if (!e->ebo_edge) glGenBuffers(1, &e->ebo_edge);
    glBindVertexArray(e->vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_edge);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(2 * ne * sizeof(uint32_t)), pairs, GL_STATIC_DRAW);
    glBindVertexArray(0);
    e->n_edges = ne;
    e->edges_ok = 1;
done:
    free(start);
    free(other);
    free(pairs);
    return st;
}

/* ------------------------------------------------------------------ drawing */

static const float DEFAULT_COLOR[4] = {0.85f, 0.85f, 0.85f, 1};
static const float DEFAULT_BACK[4] = {1, 1, 1, 1};
static const float DEFAULT_CONTOUR[4] = {0, 0, 0, 1};
static const float DEFAULT_NAN[4] = {0.7f, 0.45f, 0.7f, 1};
static const float DEFAULT_ARROW[4] = {0, 0, 0, 1};

/* A colour, or the default when all four components are zero. */
static const float *or_default(const float c[4], const float def[4])
{
    return c[0] == 0 && c[1] == 0 && c[2] == 0 && c[3] == 0 ? def : c;
}

static int has_data_mode(thx_draw_mode m)
{
    return m == THX_DRAW_POINTS || m == THX_DRAW_WIRE || m == THX_DRAW_FLAT || m == THX_DRAW_GOURAUD ||
           m == THX_DRAW_PHONG;
}

/* Per-frame state shared by the passes. */
typedef struct {
    float view[16], proj[16], clip[16];
    double eye[3], back[3];
    int ortho, n_clip;
    float vp[2];
    const float *nan_color;
} frame_state;

static void set_common(const program *p, const frame_state *fs)
{
    glUseProgram(p->id);
    glUniformMatrix4fv(p->view, 1, GL_FALSE, fs->view);
    glUniformMatrix4fv(p->proj, 1, GL_FALSE, fs->proj);
    glUniform4fv(p->clip, 4, fs->clip);
    glUniform1i(p->ortho, fs->ortho);
    glUniform2fv(p->vp, 1, fs->vp);
    glUniform4fv(p->nan_color, 1, fs->nan_color);
}

/* Uploads t per node (NaN: NAN_T) and counts the NaN values. */
static thx_status upload_values(thx_ctx *ctx, thx_renderer *r, const surf_entry *e, const thx_render_surface *rs,
                                size_t *n_nan)
{
    size_t nn = e->n_nodes;
    THX_CHECK(grow(ctx, (void **)&r->tbuf, &r->tbuf_cap, nn + 1, sizeof *r->tbuf));
    size_t nan = 0;
    for (size_t i = 0; i < nn; i++) {
        double v = rs->values[i];
        if (isnan(v)) {
            r->tbuf[i] = NAN_T;
            nan++;
            continue;
        }
        double t = thx_scale_apply(&rs->scale, v);
        r->tbuf[i] = t >= 0 && t <= 1 ? (float)t : t > 1 ? 1.0f : 0.0f;
    }
    *n_nan += nan;
    glBindBuffer(GL_ARRAY_BUFFER, e->vbo_t);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(nn * sizeof(float)), r->tbuf);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    return THX_OK;
}

/* Orientation mode: the nodes whose triangles all face away from the eye (a node shared with a
 * front-facing triangle lies on the visible surface or its silhouette and is not drawn). Returns the
 * count, the indices in the entry's point buffer. */
static thx_status back_nodes(thx_ctx *ctx, thx_renderer *r, surf_entry *e, const thx_surface *s,
                             const frame_state *fs, size_t *count)
{
    size_t nn = s->n_nodes, nt = s->n_tris, n = 0;
    THX_CHECK(grow(ctx, (void **)&r->flags, &r->flags_cap, nn + 1, 1));
    THX_CHECK(grow(ctx, (void **)&r->idx, &r->idx_cap, nn + 1, sizeof *r->idx));
    memset(r->flags, 0, nn);
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = s->tri + 3 * t;
        const double *a = s->xyz + 3 * v[0], *b = s->xyz + 3 * v[1], *c = s->xyz + 3 * v[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double d;
        if (fs->ortho) d = nrm[0] * fs->back[0] + nrm[1] * fs->back[1] + nrm[2] * fs->back[2];
        else d = nrm[0] * (fs->eye[0] - a[0]) + nrm[1] * (fs->eye[1] - a[1]) + nrm[2] * (fs->eye[2] - a[2]);
        unsigned char f = d > 0 ? 1 : 2;
        r->flags[v[0]] |= f;
        r->flags[v[1]] |= f;
        r->flags[v[2]] |= f;
    }
    for (size_t i = 0; i < nn; i++)
        if (r->flags[i] == 2) r->idx[n++] = (uint32_t)i;
    if (!e->ebo_pts) glGenBuffers(1, &e->ebo_pts);
    glBindVertexArray(e->vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_pts);
    if (n > e->pts_cap) {
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(nn * sizeof(uint32_t)), NULL, GL_DYNAMIC_DRAW);
        e->pts_cap = nn;
    }
    if (n) glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, (GLsizeiptr)(n * sizeof(uint32_t)), r->idx);
    *count = n;
    return THX_OK;
}

/* The style shown by points and lines, which cannot carry contour lines: the fill underneath. */
static int fill_style(int style)
{
    return style == THX_DATA_CONTOURS || style == THX_DATA_CONTINUOUS_CONTOURS ? THX_DATA_CONTINUOUS
           : style == THX_DATA_BANDS_CONTOURS                                 ? THX_DATA_BANDS
                                                                                : style;
}

/* Selects the variant's program and sets the frame's and the surface's uniforms (the colour map
 * when it shows data). */
static thx_status use_program(thx_ctx *ctx, thx_renderer *r, variant v, const frame_state *fs,
                              const thx_render_surface *rs, const float color[4], const program **out)
{
    if (!v.data) v.style = 0;
    if (v.prim != 0) v.style = fill_style(v.style);
    v.clip = fs->n_clip > 0;
    const program *p;
    THX_CHECK(surface_program(ctx, r, v, &p));
    set_common(p, fs);
    glUniform4fv(p->color, 1, color);
    if (v.data) {
        GLuint tex;
        THX_CHECK(cmap_texture(ctx, r, rs->cmap, &tex));
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_1D, tex);
        glUniform1i(p->nlev, rs->n_levels);
        glUniform4fv(p->contour_color, 1, or_default(rs->contour_color, DEFAULT_CONTOUR));
    }
    *out = p;
    return THX_OK;
}

/* Round points of the given pixel size (the program chosen); opaque ones through alpha to
 * coverage. */
static void draw_points(const program *p, float size, int opaque, GLsizei count, int indexed)
{
    glUniform1f(p->point_size, size);
    if (opaque) {
        glEnable(GL_SAMPLE_ALPHA_TO_COVERAGE);
        glEnable(GL_SAMPLE_ALPHA_TO_ONE);
    }
    if (indexed) glDrawElements(GL_POINTS, count, GL_UNSIGNED_INT, (void *)0);
    else glDrawArrays(GL_POINTS, 0, count);
    glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    glDisable(GL_SAMPLE_ALPHA_TO_ONE);
}

/* One surface in one of the passes. */
static thx_status draw_surface_clipped(thx_ctx *ctx, thx_renderer *r, surf_entry *e, const thx_render_surface *rs,
                               const frame_state *fs, int has_values, int translucent, int outside)
{
    const thx_surface *s = rs->surf;
    const float *color = or_default(rs->color, DEFAULT_COLOR);
    float point_size = rs->point_size > 0 ? rs->point_size : 4.0f;
    float line_width = rs->line_width > 0 ? rs->line_width : 1.0f;
    int style = (int)rs->style;
    const program *p;
    glBindVertexArray(e->vao);
    switch (rs->mode) {
    case THX_DRAW_HIDDEN: break;
    case THX_DRAW_POINTS: {
        variant v = {1, 0, has_values, style, 0, !translucent, 0};
        THX_CHECK(use_program(ctx, r, v, fs, rs, color, &p));
        draw_points(p, point_size, !translucent, (GLsizei)e->n_nodes, 0);
        break;
    }
    case THX_DRAW_WIRE: {
        THX_CHECK(entry_edges(ctx, e, s));
        variant v = {2, 0, has_values, style, 0, 0, 0};
        THX_CHECK(use_program(ctx, r, v, fs, rs, color, &p));
        glUniform1f(p->lw, line_width);
        glBindVertexArray(e->vao);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_edge);
        glDrawElements(GL_LINES, (GLsizei)(2 * e->n_edges), GL_UNSIGNED_INT, (void *)0);
        break;
    }
    case THX_DRAW_FLAT:
    case THX_DRAW_GOURAUD:
    case THX_DRAW_PHONG: {
        int light = rs->mode == THX_DRAW_FLAT ? 1 : rs->mode == THX_DRAW_GOURAUD ? 2 : 3;
        variant v = {0, light, has_values, style, 0, 0, 0};
        THX_CHECK(use_program(ctx, r, v, fs, rs, color, &p));
        glUniform1f(p->lw, rs->line_width > 0 ? rs->line_width : 1.5f);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_tri);
        GLsizei n = (GLsizei)(3 * e->n_tris);
        if (translucent) { /* the far side first, then the near side: exact for convex closed surfaces */
            glEnable(GL_CULL_FACE);
            glCullFace(GL_FRONT);
            glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT, (void *)0);
            glCullFace(GL_BACK);
            glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT, (void *)0);
            glDisable(GL_CULL_FACE);
        } else if (e->cull && outside && (!fs->n_clip || rs->no_clip)) {
            /* A closed surface seen from outside, uncut: its inward-facing side is never visible
             * (half the triangles rejected at setup). */
            glEnable(GL_CULL_FACE);
            glCullFace(e->cull);
            glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT, (void *)0);
            glDisable(GL_CULL_FACE);
        } else {
            glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT, (void *)0);
        }
        break;
    }
    case THX_DRAW_ORIENTATION: {
        /* The paper's check: only triangles whose outward side faces the viewer are drawn (their
         * stored counterclockwise order is front-facing); the nodes of the parts facing away show
         * as points, wherever no front-facing triangle hides them. */
        variant v = {0, 3, 0, 0, 0, 0, 0};
        THX_CHECK(use_program(ctx, r, v, fs, rs, color, &p));
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, e->ebo_tri);
        glDrawElements(GL_TRIANGLES, (GLsizei)(3 * e->n_tris), GL_UNSIGNED_INT, (void *)0);
        glDisable(GL_CULL_FACE);
        size_t n_back = 0;
        THX_CHECK(back_nodes(ctx, r, e, s, fs, &n_back));
        if (n_back) {
            const float *back = or_default(rs->back_color, DEFAULT_BACK);
            int opaque = !translucent && back[3] >= 1;
            variant pv = {1, 0, 0, 0, 1, opaque, 0};
            THX_CHECK(use_program(ctx, r, pv, fs, rs, back, &p));
            draw_points(p, point_size, opaque, (GLsizei)n_back, 1);
        }
        break;
    }
    default:
        glBindVertexArray(0);
        return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": unknown draw mode %d", s->name, (int)rs->mode);
    }
    glBindVertexArray(0);
    return THX_OK;
}

/* A surface exempt from the clip planes is drawn with planes that keep everything (0 x + 1 >= 0):
 * the same program and the same enabled distances, so no state changes between surfaces (disabling
 * GL_CLIP_DISTANCEi around one draw was not honoured by Mesa 22.3 llvmpipe: the heart stayed cut). */
static thx_status draw_surface(thx_ctx *ctx, thx_renderer *r, surf_entry *e, const thx_render_surface *rs,
                               const frame_state *fs, int has_values, int translucent, int outside)
{
    if (!rs->no_clip || fs->n_clip == 0) return draw_surface_clipped(ctx, r, e, rs, fs, has_values, translucent, outside);
    frame_state whole = *fs;
    for (int i = 0; i < 4; i++) {
        whole.clip[4 * i + 0] = whole.clip[4 * i + 1] = whole.clip[4 * i + 2] = 0;
        whole.clip[4 * i + 3] = 1;
    }
    return draw_surface_clipped(ctx, r, e, rs, &whole, has_values, translucent, outside);
}

/* Arrows: positions, displacements and t packed per arrow; NaN or zero vectors are skipped. */
static thx_status draw_arrows(thx_ctx *ctx, thx_renderer *r, const thx_render_arrows *a, const frame_state *fs,
                              size_t n_valid, const float *packed)
{
    if (!n_valid) return THX_OK;
    const program *p = &r->p_arrow;
    set_common(p, fs);
    GLuint tex;
    THX_CHECK(cmap_texture(ctx, r, a->unit_length ? a->cmap : THX_CMAP_ECG, &tex));
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_1D, tex);
    glUniform1f(p->lw, a->width > 0 ? (float)a->width : 1.5f);
    glUniform4fv(p->color, 1, or_default(a->color, DEFAULT_ARROW));
    glBindVertexArray(r->vao_arrow);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_arrow);
    size_t bytes = 7 * n_valid * sizeof(float);
    if (bytes > r->arrow_cap) {
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)bytes, NULL, GL_DYNAMIC_DRAW);
        r->arrow_cap = bytes;
    }
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)bytes, packed);
    glDrawArrays(GL_POINTS, 0, (GLsizei)n_valid);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindVertexArray(0);
    return THX_OK;
}

/* Packs the arrows of a into r->tbuf (7 floats each) and grows the box lo..hi around them. */
static thx_status pack_arrows(thx_ctx *ctx, thx_renderer *r, const thx_render_arrows *a, size_t *n_valid,
                              double lo[3], double hi[3])
{
    *n_valid = 0;
    if (!a->n) return THX_OK;
    if (!a->pos || !a->vec) return thx_error(ctx, THX_EINPUT, "renderer: arrows without positions or vectors");
    THX_CHECK(grow(ctx, (void **)&r->tbuf, &r->tbuf_cap, 7 * a->n, sizeof *r->tbuf));
    size_t m = 0;
    for (size_t i = 0; i < a->n; i++) {
        const double *p = a->pos + 3 * i, *v = a->vec + 3 * i;
        double mag = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(mag > 0) || !isfinite(mag) || !isfinite(p[0] + p[1] + p[2])) continue;
        double f = a->unit_length ? a->scale / mag : a->scale;
        float *q = r->tbuf + 7 * m;
        for (int k = 0; k < 3; k++) {
            double tip = p[k] + f * v[k];
            q[k] = (float)p[k];
            q[3 + k] = (float)(f * v[k]);
            lo[k] = fmin(lo[k], fmin(p[k], tip));
            hi[k] = fmax(hi[k], fmax(p[k], tip));
        }
        q[6] = a->unit_length ? (float)fmin(fmax(thx_scale_apply(&a->mag_scale, mag), 0), 1) : -1.0f;
        m++;
    }
    *n_valid = m;
    return THX_OK;
}

typedef struct {
    size_t index;
    double depth;
} sort_item;

static int by_depth_desc(const void *x, const void *y)
{
    const sort_item *a = x, *b = y;
    return a->depth < b->depth ? 1 : a->depth > b->depth ? -1 : (a->index > b->index) - (a->index < b->index);
}

/* Whether the surface's box lies wholly beyond the near plane (depth > znear): then the eye is
 * outside the surface and nothing of it is cut away by the near plane. Orthographic views place the
 * near plane before the whole scene. */
static int box_in_front(const frame_state *fs, const surf_entry *e, double znear)
{
    if (fs->ortho) return 1;
    for (int i = 0; i < 8; i++) {
        double p[3] = {i & 1 ? e->hi[0] : e->lo[0], i & 2 ? e->hi[1] : e->lo[1], i & 4 ? e->hi[2] : e->lo[2]};
        double d = -((p[0] - fs->eye[0]) * fs->back[0] + (p[1] - fs->eye[1]) * fs->back[1] +
                     (p[2] - fs->eye[2]) * fs->back[2]);
        if (!(d > znear)) return 0;
    }
    return 1;
}

/* The viewport rectangle in GL's coordinates (origin bottom left). */
static thx_status viewport_rect(thx_ctx *ctx, const thx_scene *sc, int fb_w, int fb_h, int rect[4])
{
    if (sc->viewport[2] == 0) {
        rect[0] = 0, rect[1] = 0, rect[2] = fb_w, rect[3] = fb_h;
        return THX_OK;
    }
    const int *v = sc->viewport;
    if (v[0] < 0 || v[1] < 0 || v[2] <= 0 || v[3] <= 0 || v[0] > fb_w - v[2] || v[1] > fb_h - v[3])
        return thx_error(ctx, THX_EINPUT, "renderer: viewport %d,%d %dx%d is not inside the %dx%d image", v[0], v[1],
                         v[2], v[3], fb_w, fb_h);
    rect[0] = v[0], rect[1] = fb_h - v[1] - v[3], rect[2] = v[2], rect[3] = v[3];
    return THX_OK;
}

static void restore_state(int n_clip)
{
    for (int i = 0; i < n_clip; i++) glDisable(GL_CLIP_DISTANCE0 + i);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDisable(GL_PROGRAM_POINT_SIZE);
    glDepthMask(GL_TRUE);
    glBindVertexArray(0);
    glUseProgram(0);
}

/* Draws the scene into the bound framebuffer's viewport (the heart of thx_render and
 * thx_render_scene_gl). */
static thx_status draw_scene(thx_ctx *ctx, thx_renderer *r, const thx_scene *sc, int fb_w, int fb_h, size_t *n_nan)
{
    size_t nan = 0;
    thx_status st = THX_OK;
    if (n_nan) *n_nan = 0;
    if (!sc) return thx_error(ctx, THX_EINPUT, "renderer: no scene");
    if (sc->n_clip < 0 || sc->n_clip > 4)
        return thx_error(ctx, THX_EINPUT, "renderer: %d clip planes (at most 4)", sc->n_clip);
    if ((sc->n_surfaces && !sc->surfaces) || (sc->n_arrows && !sc->arrows))
        return thx_error(ctx, THX_EINPUT, "renderer: the scene's surface or arrow array is NULL");
    frame_state fs;
    memset(&fs, 0, sizeof fs);
    double right[3], up[3];
    if (cam_frame(&sc->camera, right, up, fs.back) != 0)
        return thx_error(ctx, THX_EINPUT,
                         "renderer: degenerate camera (eye at the centre, or up along the line of sight)");
    if (!(sc->camera.fov_deg > 0) && !(sc->camera.height > 0))
        return thx_error(ctx, THX_EINPUT, "renderer: orthographic camera with height %g (must be > 0)",
                         sc->camera.height);
    if (sc->camera.fov_deg >= 180)
        return thx_error(ctx, THX_EINPUT, "renderer: field of view %g degrees (must be < 180)", sc->camera.fov_deg);
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        if (rs->mode == THX_DRAW_HIDDEN || !rs->surf) continue;
        if (rs->values && has_data_mode(rs->mode) && rs->style != THX_DATA_CONTINUOUS && rs->n_levels < 1)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": bands and contours need n_levels >= 1, got %d",
                             rs->surf->name, rs->n_levels);
        if ((int)rs->style < 0 || (int)rs->style > THX_DATA_CONTINUOUS_CONTOURS)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": unknown data style %d", rs->surf->name,
                             (int)rs->style);
    }
    int rect[4];
    THX_CHECK(viewport_rect(ctx, sc, fb_w, fb_h, rect));
    THX_CHECK(gl_init(ctx, r));
    r->frame++;

    glViewport(rect[0], rect[1], rect[2], rect[3]);
    glEnable(GL_SCISSOR_TEST);
    glScissor(rect[0], rect[1], rect[2], rect[3]);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    if (sc->clear) {
        const float *b = sc->background;
        glClearColor(b[0] * b[3], b[1] * b[3], b[2] * b[3], b[3]);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    } else {
        glClear(GL_DEPTH_BUFFER_BIT);
    }

    /* Upload what changed, the values, and the box around everything drawn. */
    THX_TRY(grow(ctx, (void **)&r->ents, &r->ents_cap, sc->n_surfaces + 1, sizeof *r->ents));
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        r->ents[i] = NULL;
        if (rs->mode == THX_DRAW_HIDDEN || !rs->surf || !rs->surf->n_nodes) continue;
        THX_TRY(cache_get(ctx, r, rs->surf, &r->ents[i]));
        if (rs->values && has_data_mode(rs->mode)) THX_TRY(upload_values(ctx, r, r->ents[i], rs, &nan));
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], r->ents[i]->lo[k]);
            hi[k] = fmax(hi[k], r->ents[i]->hi[k]);
        }
    }
    /* Arrows are packed once to size the box; they are packed again when drawn (tbuf is shared). */
    for (size_t i = 0; i < sc->n_arrows; i++) {
        size_t m;
        THX_TRY(pack_arrows(ctx, r, &sc->arrows[i], &m, lo, hi));
    }
    if (!(lo[0] <= hi[0])) goto done; /* nothing to draw */

    double zn, zf, view[16], proj[16];
    cam_depth_range(&sc->camera, lo, hi, &zn, &zf);
    cam_view_matrix(&sc->camera, view);
    cam_proj_matrix(&sc->camera, (double)rect[2] / rect[3], zn, zf, proj);
    for (int k = 0; k < 16; k++) fs.view[k] = (float)view[k], fs.proj[k] = (float)proj[k];
    for (int i = 0; i < 4; i++) {
        const double *n = i < sc->n_clip ? sc->clip[i].n : NULL;
        fs.clip[4 * i + 0] = n ? (float)n[0] : 0;
        fs.clip[4 * i + 1] = n ? (float)n[1] : 0;
        fs.clip[4 * i + 2] = n ? (float)n[2] : 0;
        fs.clip[4 * i + 3] = n ? (float)sc->clip[i].d : 1;
    }
    for (int k = 0; k < 3; k++) fs.eye[k] = sc->camera.eye[k];
    fs.ortho = !(sc->camera.fov_deg > 0);
    fs.n_clip = sc->n_clip;
    fs.vp[0] = (float)rect[2], fs.vp[1] = (float)rect[3];
    fs.nan_color = or_default(sc->nan_color, DEFAULT_NAN);

    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND); /* opaque: no read of the framebuffer */
    glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glFrontFace(GL_CCW);
    for (int i = 0; i < sc->n_clip; i++) glEnable(GL_CLIP_DISTANCE0 + i);

    /* Opaque surfaces, then the arrows, then the translucent surfaces far to near without writing
     * depth. */
    size_t n_trans = 0;
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        if (!r->ents[i]) continue;
        if (or_default(rs->color, DEFAULT_COLOR)[3] < 1) {
            n_trans++;
            continue;
        }
        THX_TRY(draw_surface(ctx, r, r->ents[i], rs, &fs, rs->values != NULL, 0, box_in_front(&fs, r->ents[i], zn)));
    }
    for (size_t i = 0; i < sc->n_arrows; i++) {
        size_t m;
        double alo[3] = {0, 0, 0}, ahi[3] = {0, 0, 0};
        THX_TRY(pack_arrows(ctx, r, &sc->arrows[i], &m, alo, ahi));
        int trans = or_default(sc->arrows[i].color, DEFAULT_ARROW)[3] < 1;
        if (trans) glDepthMask(GL_FALSE), glEnable(GL_BLEND);
        THX_TRY(draw_arrows(ctx, r, &sc->arrows[i], &fs, m, r->tbuf));
        glDepthMask(GL_TRUE);
        glDisable(GL_BLEND);
    }
    if (n_trans) {
        sort_item *order = thx_malloc(ctx, n_trans * sizeof *order);
        if (!order) {
            st = THX_ENOMEM;
            goto done;
        }
        size_t m = 0;
        for (size_t i = 0; i < sc->n_surfaces; i++) {
            const thx_render_surface *rs = &sc->surfaces[i];
            if (!r->ents[i] || or_default(rs->color, DEFAULT_COLOR)[3] >= 1) continue;
            const surf_entry *e = r->ents[i];
            double d = 0;
            for (int k = 0; k < 3; k++) d -= (0.5 * (e->lo[k] + e->hi[k]) - fs.eye[k]) * fs.back[k];
            order[m].index = i;
            order[m].depth = d;
            m++;
        }
        qsort(order, m, sizeof *order, by_depth_desc);
        glDepthMask(GL_FALSE);
        glEnable(GL_BLEND);
        for (size_t j = 0; j < m && st == THX_OK; j++) {
            size_t i = order[j].index;
            st = draw_surface(ctx, r, r->ents[i], &sc->surfaces[i], &fs, sc->surfaces[i].values != NULL, 1, 0);
        }
        glDepthMask(GL_TRUE);
        free(order);
        if (st != THX_OK) goto done;
    }
    st = gl_check(ctx, "drawing the scene");
done:
    restore_state(sc->n_clip);
    cache_trim(r);
    if (n_nan) *n_nan = nan;
    return st;
}

/* ------------------------------------------------------------- public API */

/* Makes the renderer's context current, remembering the caller's. */
typedef struct {
    EGLDisplay dpy;
    EGLContext ctx;
    EGLSurface draw, read;
} egl_current;

static thx_status make_current(thx_ctx *ctx, thx_renderer *r, egl_current *prev)
{
    prev->ctx = eglGetCurrentContext();
    prev->dpy = eglGetCurrentDisplay();
    prev->draw = eglGetCurrentSurface(EGL_DRAW);
    prev->read = eglGetCurrentSurface(EGL_READ);
    if (prev->ctx == r->egl) return THX_OK;
    if (!eglMakeCurrent(r->dpy, r->pbuf, r->pbuf, r->egl))
        return thx_error(ctx, THX_EINTERNAL, "renderer: eglMakeCurrent failed (%s)", egl_error_name(eglGetError()));
    return THX_OK;
}

/* Gives the caller's context back (ours stays current when there was none, saving a switch per
 * frame). */
static void restore_current(const thx_renderer *r, const egl_current *prev)
{
    if (prev->ctx != EGL_NO_CONTEXT && prev->ctx != r->egl)
        eglMakeCurrent(prev->dpy, prev->draw, prev->read, prev->ctx);
}

static void free_gl_objects(thx_renderer *r)
{
    for (size_t i = 0; i < r->n_cache; i++) {
        entry_free_gl(r->cache[i]);
        free(r->cache[i]);
    }
    r->n_cache = 0;
    if (!r->gl_ready && !r->fbo_out) return;
    for (size_t i = 0; i < r->n_variants; i++) glDeleteProgram(r->variants[i].prog.id);
    r->n_variants = 0;
    if (r->p_arrow.id) glDeleteProgram(r->p_arrow.id);
    if (r->p_blit.id) glDeleteProgram(r->p_blit.id);
    glDeleteTextures(6, r->cmap_tex);
    glDeleteTextures(1, &r->blit_tex);
    glDeleteVertexArrays(1, &r->vao_empty);
    glDeleteVertexArrays(1, &r->vao_arrow);
    glDeleteBuffers(1, &r->vbo_arrow);
    free_framebuffers(r);
}

thx_status thx_renderer_create(thx_ctx *ctx, int w, int h, thx_renderer **out)
{
    *out = NULL;
    if (w < 0 || h < 0 || (w == 0) != (h == 0))
        return thx_error(ctx, THX_EINPUT, "renderer: bad framebuffer size %d x %d", w, h);
    thx_renderer *r = thx_calloc(ctx, 1, sizeof *r);
    if (!r) return THX_ENOMEM;
    r->w = w;
    r->h = h;
    if (w == 0) { /* the caller's context, at the first draw */
        snprintf(r->info, sizeof r->info, "OpenGL (the caller's context, not yet used)");
        *out = r;
        return THX_OK;
    }
    egl_current prev = {eglGetCurrentDisplay(), eglGetCurrentContext(), eglGetCurrentSurface(EGL_DRAW),
                        eglGetCurrentSurface(EGL_READ)};
    thx_status st = egl_open(ctx, r);
    if (st != THX_OK) {
        free(r);
        return st;
    }
    r->own = 1;
    const char *rn = (const char *)glGetString(GL_RENDERER);
    r->software = rn && (strstr(rn, "llvmpipe") || strstr(rn, "softpipe") || strstr(rn, "SWR") ||
                         strstr(rn, "Software Rasterizer"));
    st = make_framebuffers(ctx, r);
    if (st == THX_OK) st = gl_init(ctx, r);
    if (st != THX_OK) {
        restore_current(r, &prev);
        thx_renderer_destroy(&r);
        return st;
    }
    restore_current(r, &prev);
    *out = r;
    return THX_OK;
}

void thx_renderer_destroy(thx_renderer **rp)
{
    if (!rp || !*rp) return;
    thx_renderer *r = *rp;
    if (r->own) {
        EGLContext cur = eglGetCurrentContext();
        EGLDisplay cur_dpy = eglGetCurrentDisplay();
        EGLSurface cur_draw = eglGetCurrentSurface(EGL_DRAW), cur_read = eglGetCurrentSurface(EGL_READ);
        if (eglMakeCurrent(r->dpy, r->pbuf, r->pbuf, r->egl)) free_gl_objects(r);
        if (cur != EGL_NO_CONTEXT && cur != r->egl) eglMakeCurrent(cur_dpy, cur_draw, cur_read, cur);
        else eglMakeCurrent(r->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (r->pbuf != EGL_NO_SURFACE) eglDestroySurface(r->dpy, r->pbuf);
        eglDestroyContext(r->dpy, r->egl);
    } else if (r->gl_ready) {
        free_gl_objects(r); /* in the caller's context, which must be current */
    }
    for (size_t i = 0; i < r->n_cache; i++) free(r->cache[i]);
    free(r->cache);
    free(r->tbuf);
    free(r->flags);
    free(r->idx);
    free(r->pix);
    free(r->pix2);
    free(r->luma);
    free(r->ents);
    free(r->variants);
    free(r);
    *rp = NULL;
}

const char *thx_renderer_info(const thx_renderer *r) { return r ? r->info : ""; }

thx_status thx_renderer_set_samples(thx_ctx *ctx, thx_renderer *r, int samples)
{
    if (!r || !r->own)
        return thx_error(ctx, THX_EINPUT, "thx_renderer_set_samples: the renderer has no offscreen framebuffer");
    if (samples != 0 && samples != 1 && samples != 4)
        return thx_error(ctx, THX_EINPUT, "thx_renderer_set_samples: %d samples (0, 1 or 4)", samples);
    r->samples_asked = samples;
    egl_current prev;
    THX_CHECK(make_current(ctx, r, &prev));
    thx_status st = make_framebuffers(ctx, r);
    restore_current(r, &prev);
    return st;
}

int thx_renderer_samples(const thx_renderer *r) { return r && r->own ? r->samples : 0; }

/* The image's pixels under the viewport into the framebuffer, premultiplied (clear = 0). */
static thx_status blit_image(thx_ctx *ctx, thx_renderer *r, const thx_image *img, const int rect[4])
{
    int x0 = rect[0], w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    THX_CHECK(grow(ctx, (void **)&r->pix, &r->pix_cap, (size_t)4 * w * h, 1));
    for (int y = 0; y < h; y++) {
        const unsigned char *src = img->rgba + 4 * ((size_t)(y_top + y) * img->w + x0);
        unsigned char *dst = r->pix + (size_t)4 * w * y;
        for (int x = 0; x < w; x++) {
            unsigned a = src[4 * x + 3];
            for (int k = 0; k < 3; k++) dst[4 * x + k] = (unsigned char)((src[4 * x + k] * a + 127) / 255);
            dst[4 * x + 3] = (unsigned char)a;
        }
    }
    if (!r->blit_tex) glGenTextures(1, &r->blit_tex);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r->blit_tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, r->pix);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glViewport(rect[0], rect[1], w, h);
    glEnable(GL_SCISSOR_TEST);
    glScissor(rect[0], rect[1], w, h);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glUseProgram(r->p_blit.id);
    glUniform4i(r->p_blit.rect, rect[0], rect[1], w, h);
    glBindVertexArray(r->vao_empty);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
    glDisable(GL_SCISSOR_TEST);
    return gl_check(ctx, "copying the image under the viewport");
}

/*
 * FXAA (after Lottes' FXAA 3.11, "quality"), on the CPU over the read-back viewport: a pixel whose
 * luma contrast with its four neighbours is small is kept (most pixels stop there, which is why
 * this runs on the CPU: llvmpipe would run every instruction for every pixel); on an edge, the
 * edge's orientation comes from the 3 x 3 lumas, its two ends are searched along it, and the pixel
 * is blended with its neighbour across the edge by how near it is to the nearer end, or by the
 * sub-pixel contrast when larger. src and dst: w x h premultiplied RGBA (any row order); alpha
 * counts in the luma so that edges against a transparent background are smoothed too. Each output
 * pixel depends on the input only: the result does not depend on the thread count.
 */
/* Inline min/max (fmaxf and fminf are library calls unless NaNs are ruled out). */
#define MAXF(a, b) ((a) > (b) ? (a) : (b))
#define MINF(a, b) ((a) < (b) ? (a) : (b))
#define ABSF(a) ((a) < 0 ? -(a) : (a))
static void fxaa(const unsigned char *src, unsigned char *dst, float *luma, int w, int h)
{
    size_t n = (size_t)w * h;
#pragma omp parallel for schedule(static) if (n > 65536)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            const unsigned char *c = src + 4 * i;
            luma[i] = (0.299f * c[0] + 0.587f * c[1] + 0.114f * c[2] + 0.5f * (255 - c[3])) * (1.0f / 255);
        }
#define CLAMP(v_, n_) ((v_) < 0 ? 0 : (v_) >= (n_) ? (n_) - 1 : (v_))
#define L(x_, y_) luma[(size_t)CLAMP(y_, h) * w + CLAMP(x_, w)]
#pragma omp parallel for schedule(static) if (n > 65536)
    for (int y = 0; y < h; y++) {
        const float *row = luma + (size_t)y * w, *up = luma + (size_t)(y + 1 < h ? y + 1 : y) * w,
                    *dn = luma + (size_t)(y > 0 ? y - 1 : 0) * w;
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            int xl = x > 0 ? x - 1 : 0, xr = x + 1 < w ? x + 1 : x;
            float lm = row[x], ln = up[x], ls = dn[x], le = row[xr], lw = row[xl];
            float lmax = MAXF(lm, MAXF(MAXF(ln, ls), MAXF(le, lw)));
            float lmin = MINF(lm, MINF(MINF(ln, ls), MINF(le, lw)));
            float range = lmax - lmin;
            if (range < MAXF(0.0312f, 0.125f * lmax)) {
                memcpy(dst + 4 * i, src + 4 * i, 4);
                continue;
            }
            float lne = up[xr], lnw = up[xl], lse = dn[xr], lsw = dn[xl];
            float avg = (2 * (ln + ls + le + lw) + lne + lnw + lse + lsw) / 12;
            float sub = MINF(ABSF(avg - lm) / range, 1);
            sub = sub * sub * (3 - 2 * sub);
            sub = 0.75f * sub * sub;
            float eh = ABSF(lsw + lnw - 2 * lw) + 2 * ABSF(ls + ln - 2 * lm) + ABSF(lse + lne - 2 * le);
            float ev = ABSF(lnw + lne - 2 * ln) + 2 * ABSF(lw + le - 2 * lm) + ABSF(lsw + lse - 2 * ls);
            int horz = eh >= ev; /* the edge runs along x; its sides differ along y */
            float l1 = horz ? ls : lw, l2 = horz ? ln : le;
            float g1 = ABSF(l1 - lm), g2 = ABSF(l2 - lm);
            int step = g1 >= g2 ? -1 : 1; /* toward the side of the steeper gradient */
            float grad = 0.25f * MAXF(g1, g2);
            float llocal = 0.5f * ((step < 0 ? l1 : l2) + lm);
            /* the luma on the edge (between this row and the next across it), k pixels along */
#define EDGE(k) (horz ? 0.5f * (L(x + (k), y) + L(x + (k), y + step)) : 0.5f * (L(x, y + (k)) + L(x + step, y + (k))))
            static const int STEPS[10] = {1, 1, 1, 1, 1, 2, 2, 2, 4, 8};
            int k1 = -1, k2 = 1;
            float d1 = EDGE(k1) - llocal, d2 = EDGE(k2) - llocal;
            int r1 = ABSF(d1) >= grad, r2 = ABSF(d2) >= grad;
            for (int s = 0; s < 10 && !(r1 && r2); s++) {
                if (!r1) {
                    k1 -= STEPS[s];
                    d1 = EDGE(k1) - llocal;
                    r1 = ABSF(d1) >= grad;
                }
                if (!r2) {
                    k2 += STEPS[s];
                    d2 = EDGE(k2) - llocal;
                    r2 = ABSF(d2) >= grad;
                }
            }
#undef EDGE
            float dist1 = (float)-k1, dist2 = (float)k2;
            int first = dist1 < dist2;
            float off = 0.5f - MINF(dist1, dist2) / (dist1 + dist2);
            int good = ((first ? d1 : d2) < 0) != (lm < llocal);
            off = MAXF(good ? off : 0, sub);
            int xo = horz ? x : x + step, yo = horz ? y + step : y;
            xo = xo < 0 ? 0 : xo >= w ? w - 1 : xo;
            yo = yo < 0 ? 0 : yo >= h ? h - 1 : yo;
            const unsigned char *a = src + 4 * i, *b = src + 4 * ((size_t)yo * w + xo);
            for (int k = 0; k < 4; k++) dst[4 * i + k] = (unsigned char)(a[k] + off * (b[k] - a[k]) + 0.5f);
        }
    }
#undef L
#undef CLAMP
}
#undef MAXF
#undef MINF
#undef ABSF

/* Resolves the viewport (multisampled) or smooths it (FXAA), reads it back, flips it into img and
 * divides out alpha. */
static thx_status read_back(thx_ctx *ctx, thx_renderer *r, thx_image *img, const int rect[4])
{
    int w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    size_t n = (size_t)w * h;
    if (r->samples > 1) {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo_draw);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, r->fbo_out);
        glBlitFramebuffer(rect[0], rect[1], rect[0] + w, rect[1] + h, rect[0], rect[1], rect[0] + w, rect[1] + h,
                          GL_COLOR_BUFFER_BIT, GL_NEAREST);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo_out);
    } else {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo_draw);
    }
    THX_CHECK(grow(ctx, (void **)&r->pix, &r->pix_cap, 4 * n, 1));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(rect[0], rect[1], w, h, GL_RGBA, GL_UNSIGNED_BYTE, r->pix);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    THX_CHECK(gl_check(ctx, "reading the image back"));
    const unsigned char *pix = r->pix;
    if (r->samples == 1) {
        THX_CHECK(grow(ctx, (void **)&r->pix2, &r->pix2_cap, 4 * n, 1));
        THX_CHECK(grow(ctx, (void **)&r->luma, &r->luma_cap, n, sizeof *r->luma));
        fxaa(r->pix, r->pix2, r->luma, w, h);
        pix = r->pix2;
    }
    for (int y = 0; y < h; y++) {
        const unsigned char *src = pix + (size_t)4 * w * (h - 1 - y);
        unsigned char *dst = img->rgba + 4 * ((size_t)(y_top + y) * img->w + rect[0]);
        for (int x = 0; x < w; x++) {
            unsigned a = src[4 * x + 3];
            if (a == 255) {
                memcpy(dst + 4 * x, src + 4 * x, 4);
                continue;
            }
            for (int k = 0; k < 3; k++) {
                unsigned c = a ? (src[4 * x + k] * 255u + a / 2) / a : 0;
                dst[4 * x + k] = (unsigned char)(c > 255 ? 255 : c);
            }
            dst[4 * x + 3] = (unsigned char)a;
        }
    }
    return THX_OK;
}

thx_status thx_render(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, thx_image *img, size_t *n_nan)
{
    if (n_nan) *n_nan = 0;
    if (!r || !r->own)
        return thx_error(ctx, THX_EINPUT, "thx_render: the renderer has no offscreen context (made with 0 x 0: use "
                         "thx_render_scene_gl)");
    if (!img || img->w != r->w || img->h != r->h)
        return thx_error(ctx, THX_EINPUT, "thx_render: the image is %d x %d, the renderer %d x %d", img ? img->w : 0,
                         img ? img->h : 0, r->w, r->h);
    if (!scene) return thx_error(ctx, THX_EINPUT, "thx_render: no scene");
    int rect[4];
    THX_CHECK(viewport_rect(ctx, scene, r->w, r->h, rect));
    egl_current prev;
    THX_CHECK(make_current(ctx, r, &prev));
    thx_status st = THX_OK;
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    if (!scene->clear) THX_TRY(blit_image(ctx, r, img, rect));
    THX_TRY(draw_scene(ctx, r, scene, r->w, r->h, n_nan));
    THX_TRY(read_back(ctx, r, img, rect));
done:
    restore_current(r, &prev);
    return st;
}

thx_status thx_render_scene_gl(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, int fb_w, int fb_h,
                               size_t *n_nan)
{
    if (n_nan) *n_nan = 0;
    if (!r) return thx_error(ctx, THX_EINPUT, "thx_render_scene_gl: no renderer");
    if (fb_w <= 0 || fb_h <= 0)
        return thx_error(ctx, THX_EINPUT, "thx_render_scene_gl: bad framebuffer size %d x %d", fb_w, fb_h);
    if (!r->own) return draw_scene(ctx, r, scene, fb_w, fb_h, n_nan);
    egl_current prev;
    THX_CHECK(make_current(ctx, r, &prev));
    thx_status st = draw_scene(ctx, r, scene, fb_w, fb_h, n_nan);
    restore_current(r, &prev);
    return st;
}
