/*
 * A frame's drawing (see render.c): the scene's checks, the values mapped to t and uploaded, the
 * surfaces in their modes (points, wire, flat, Gouraud, Phong, orientation), the clip planes and
 * the surfaces exempt from them, the arrows, and the passes: opaque surfaces, arrows, then the
 * translucent surfaces far to near.
 */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    THX_CHECK(rn_grow(ctx, (void **)&r->tbuf, &r->tbuf_cap, nn + 1, sizeof *r->tbuf));
    size_t nan = 0;
    thx_scale_apply_n(&rs->scale, rs->values, nn, r->tbuf); /* t in [0, 1]; a lab scale's levels found once */
    for (size_t i = 0; i < nn; i++)
        if (isnan(rs->values[i])) {
            r->tbuf[i] = NAN_T;
            nan++;
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
    THX_CHECK(rn_grow(ctx, (void **)&r->flags, &r->flags_cap, nn + 1, 1));
    THX_CHECK(rn_grow(ctx, (void **)&r->idx, &r->idx_cap, nn + 1, sizeof *r->idx));
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
    THX_CHECK(rn_surface_program(ctx, r, v, &p));
    set_common(p, fs);
    glUniform4fv(p->color, 1, color);
    if (v.data) {
        GLuint tex;
        THX_CHECK(rn_cmap_texture(ctx, r, rs->cmap, &tex));
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_1D, tex);
        glUniform1i(p->nlev, thx_scale_bands(&rs->scale, rs->n_levels)); /* a lab scale's own count */
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
        THX_CHECK(rn_entry_edges(ctx, e, s));
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
    THX_CHECK(rn_cmap_texture(ctx, r, a->unit_length ? a->cmap : THX_CMAP_ECG, &tex));
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
    THX_CHECK(rn_grow(ctx, (void **)&r->tbuf, &r->tbuf_cap, 7 * a->n, sizeof *r->tbuf));
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

/* An image plane (thx_render_plane): its texels into the renderer's one plane texture, its corners
 * into the quad, drawn unlit with a polygon offset behind what lies in its plane (contour lines). */
static thx_status draw_plane(thx_ctx *ctx, thx_renderer *r, const thx_render_plane *pl, const frame_state *fs)
{
    const double *o = pl->origin, *u = pl->u, *v = pl->v;
    float quad[4][5];
    for (int c = 0; c < 4; c++) {
        double a = (c == 1 || c == 2) ? 1 : 0, b = c >= 2 ? 1 : 0;
        for (int k = 0; k < 3; k++) quad[c][k] = (float)(o[k] + a * u[k] + b * v[k]);
        quad[c][3] = (float)a;
        quad[c][4] = (float)b;
    }
    glUseProgram(r->p_plane.id);
    glUniformMatrix4fv(r->p_plane.view, 1, GL_FALSE, fs->view);
    glUniformMatrix4fv(r->p_plane.proj, 1, GL_FALSE, fs->proj);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r->plane_tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, pl->w, pl->h, 0, GL_RGBA, GL_UNSIGNED_BYTE, pl->rgba);
    GLint filter = pl->nearest ? GL_NEAREST : GL_LINEAR;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindVertexArray(r->vao_plane);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo_plane);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)sizeof quad, quad);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
    glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindVertexArray(0);
    glBindTexture(GL_TEXTURE_2D, 0);
    (void)ctx;
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
thx_status rn_viewport_rect(thx_ctx *ctx, const thx_scene *sc, int fb_w, int fb_h, int rect[4])
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
thx_status rn_draw_scene(thx_ctx *ctx, thx_renderer *r, const thx_scene *sc, int fb_w, int fb_h, size_t *n_nan)
{
    size_t nan = 0;
    thx_status st = THX_OK;
    if (n_nan) *n_nan = 0;
    if (!sc) return thx_error(ctx, THX_EINPUT, "renderer: no scene");
    if (sc->n_clip < 0 || sc->n_clip > 4)
        return thx_error(ctx, THX_EINPUT, "renderer: %d clip planes (at most 4)", sc->n_clip);
    if ((sc->n_surfaces && !sc->surfaces) || (sc->n_arrows && !sc->arrows) || (sc->n_planes && !sc->planes))
        return thx_error(ctx, THX_EINPUT, "renderer: the scene's surface, arrow or plane array is NULL");
    for (size_t i = 0; i < sc->n_planes; i++) {
        const thx_render_plane *pl = &sc->planes[i];
        double q = 0;
        for (int k = 0; k < 3; k++) q += pl->origin[k] + pl->u[k] + pl->v[k];
        if (pl->w < 1 || pl->h < 1 || pl->w > 16384 || pl->h > 16384 || !pl->rgba || !isfinite(q))
            return thx_error(ctx, THX_EINPUT, "renderer: image plane %zu: %d x %d texels%s", i + 1, pl->w, pl->h,
                             !pl->rgba ? " without texels" : !isfinite(q) ? " at a non-finite place" : " (1 to 16384 each)");
    }
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
        if (rs->values && has_data_mode(rs->mode) && rs->style != THX_DATA_CONTINUOUS &&
            thx_scale_bands(&rs->scale, rs->n_levels) < 1)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": bands and contours need n_levels >= 1, got %d",
                             rs->surf->name, rs->n_levels);
        if ((int)rs->style < 0 || (int)rs->style > THX_DATA_CONTINUOUS_CONTOURS)
            return thx_error(ctx, THX_EINPUT, "renderer: surface \"%s\": unknown data style %d", rs->surf->name,
                             (int)rs->style);
    }
    int rect[4];
    THX_CHECK(rn_viewport_rect(ctx, sc, fb_w, fb_h, rect));
    THX_CHECK(rn_gl_init(ctx, r));
    r->frame++;

    glViewport(rect[0], rect[1], rect[2], rect[3]);
    glEnable(GL_SCISSOR_TEST);
    if (r->scissor[2] > 0) /* sort-first: this rank's band and the rows FXAA reads around it */
        glScissor(r->scissor[0], r->scissor[1], r->scissor[2], r->scissor[3]);
    else
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
    THX_TRY(rn_grow(ctx, (void **)&r->ents, &r->ents_cap, sc->n_surfaces + 1, sizeof *r->ents));
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        r->ents[i] = NULL;
        if (rs->mode == THX_DRAW_HIDDEN || !rs->surf || !rs->surf->n_nodes) continue;
        THX_TRY(rn_cache_get(ctx, r, rs->surf, rs->normals, &r->ents[i]));
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
    for (size_t i = 0; i < sc->n_planes; i++) /* the planes' corners */
        for (int c = 0; c < 4; c++)
            for (int k = 0; k < 3; k++) {
                const thx_render_plane *pl = &sc->planes[i];
                double x = pl->origin[k] + (c & 1 ? pl->u[k] : 0) + (c & 2 ? pl->v[k] : 0);
                lo[k] = fmin(lo[k], x);
                hi[k] = fmax(hi[k], x);
            }
    if (!(lo[0] <= hi[0])) goto done; /* nothing to draw */
    if (sc->have_box) /* one depth scale for every part of a scene (sort-last) */
        for (int k = 0; k < 3; k++) lo[k] = sc->box[0][k], hi[k] = sc->box[1][k];

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
    /* The image planes: with the opaque things (depth written), before the translucent surfaces. */
    for (size_t i = 0; i < sc->n_planes; i++) THX_TRY(draw_plane(ctx, r, &sc->planes[i], &fs));
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
    st = rn_gl_check(ctx, "drawing the scene");
done:
    restore_state(sc->n_clip);
    rn_cache_trim(r);
    if (n_nan) *n_nan = nan;
    return st;
}
