/*
 * The renderer's shaders (see render.c): the GLSL sources, compiled into programs in the current
 * context (the surface variants at their first use), the GL objects every frame shares, the
 * colour maps as 1D textures, and the check of GL's error flag.
 */
#include "render_internal.h"

#include <stdio.h>
#include <string.h>

#define CMAP_N 1024     /* texels of a colour map's 1D texture */

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

/* An image plane: a textured quad, unlit; texels outside the image (alpha < 0.5) are not drawn. */
static const char *const VS_PLANE =
    "layout(location = 0) in vec3 a_pos;\n"
    "layout(location = 1) in vec2 a_tc;\n"
    "uniform mat4 u_view, u_proj;\n"
    "out vec2 v_tc;\n"
    "out float gl_ClipDistance[4];\n"
    "void main() {\n"
    "    v_tc = a_tc;\n"
    "    for (int i = 0; i < 4; i++) gl_ClipDistance[i] = 1.0; /* never cut by the clip planes */\n"
    "    gl_Position = u_proj * u_view * vec4(a_pos, 1.0);\n"
    "}\n";

static const char *const FS_PLANE =
    "uniform sampler2D u_tex;\n"
    "in vec2 v_tc;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    vec4 c = texture(u_tex, v_tc);\n"
    "    if (c.a < 0.5) discard;\n"
    "    o_color = vec4(c.rgb, 1.0);\n"
    "}\n";

/* ------------------------------------------------------------ GL resources */

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

thx_status rn_gl_check(thx_ctx *ctx, const char *where)
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
thx_status rn_surface_program(thx_ctx *ctx, thx_renderer *r, variant v, const program **out)
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
thx_status rn_gl_init(thx_ctx *ctx, thx_renderer *r)
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
    THX_CHECK(rn_surface_program(ctx, r, first, &unused)); /* a compile error shows at once */
    THX_CHECK(make_program(ctx, "arrow", "", VS_ARROW, GS_ARROW, FS_ARROW, &r->p_arrow));
    THX_CHECK(make_program(ctx, "blit", "", VS_BLIT, NULL, FS_BLIT, &r->p_blit));
    THX_CHECK(make_program(ctx, "image plane", "", VS_PLANE, NULL, FS_PLANE, &r->p_plane));
    glGenVertexArrays(1, &r->vao_plane);
    glGenBuffers(1, &r->vbo_plane);
    glBindVertexArray(r->vao_plane);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_plane);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(4 * 5 * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)(3 * sizeof(float)));
    glGenTextures(1, &r->plane_tex);
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
    THX_CHECK(rn_gl_check(ctx, "setting up the shaders"));
    r->gl_ready = 1;
    return THX_OK;
}

/* The colour map as a 1D texture (made at its first use). */
thx_status rn_cmap_texture(thx_ctx *ctx, thx_renderer *r, thx_colormap c, GLuint *out)
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
