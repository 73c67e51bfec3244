/*
 * The 3D renderer (paper 4.2): OpenGL 3.3 core through libepoxy, offscreen
 * with EGL, or in the caller's context (the viewer).
 *
 * Pipeline of thx_render: make the renderer's EGL context current, draw the
 * scene into the framebuffer object's viewport, then either resolve the 4x
 * multisampled drawing (on a GPU) or smooth the single-sampled one with FXAA
 * on the CPU (on llvmpipe, where multisampling triples the time: see
 * docs/decisions.md, "Renderer"), read it back and flip it into the image
 * (GL's rows run bottom to top, thx_raster's top to bottom).
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
 *    with a constant width in pixels from fwidth(t n); n is
 *    thx_scale_bands(scale, n_levels), the lab scales' own count, whose
 *    levels sit exactly at t = j / n.
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
 *
 * Files (render_internal.h has what they share):
 *  - render.c: the renderer's life (create, destroy, samples) and the calls thx_render and
 *    thx_render_scene_gl that draw a frame; the scratch buffers.
 *  - render_context.c: the EGL display and context, switching to it and back, and the offscreen
 *    framebuffers.
 *  - render_shaders.c: the GLSL sources and their programs, the GL objects the frames share, the
 *    colour maps' textures, GL error checks.
 *  - render_cache.c: the geometry cache (surfaces uploaded once).
 *  - render_draw.c: a frame's drawing: surfaces in their modes, clip planes, arrows, viewport,
 *    the opaque and translucent passes.
 *  - render_readback.c: the image under an uncleared viewport, and the drawing read back (resolved,
 *    or smoothed by FXAA) into the image.
 *  - camera.c: the camera's matrices.
 */
#include "render_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A scratch buffer of the renderer (tbuf, flags, idx, pix, ...) grown to hold need elements. */
thx_status rn_grow(thx_ctx *ctx, void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return THX_OK;
    return thx_grow(ctx, p, cap, need, elem);
}

static void free_gl_objects(thx_renderer *r)
{
    for (size_t i = 0; i < r->n_cache; i++) {
        rn_entry_free_gl(r->cache[i]);
        free(r->cache[i]);
    }
    r->n_cache = 0;
    if (!r->gl_ready && !r->fbo_out) return;
    for (size_t i = 0; i < r->n_variants; i++) glDeleteProgram(r->variants[i].prog.id);
    r->n_variants = 0;
    if (r->p_arrow.id) glDeleteProgram(r->p_arrow.id);
    if (r->p_blit.id) glDeleteProgram(r->p_blit.id);
    if (r->p_plane.id) glDeleteProgram(r->p_plane.id);
    glDeleteTextures(1, &r->plane_tex);
    glDeleteVertexArrays(1, &r->vao_plane);
    glDeleteBuffers(1, &r->vbo_plane);
    glDeleteTextures(6, r->cmap_tex);
    glDeleteTextures(1, &r->blit_tex);
    glDeleteVertexArrays(1, &r->vao_empty);
    glDeleteVertexArrays(1, &r->vao_arrow);
    glDeleteBuffers(1, &r->vbo_arrow);
    rn_free_framebuffers(r);
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
    thx_status st = rn_egl_open(ctx, r);
    if (st != THX_OK) {
        free(r);
        return st;
    }
    r->own = 1;
    const char *rn = (const char *)glGetString(GL_RENDERER);
    r->software = rn && (strstr(rn, "llvmpipe") || strstr(rn, "softpipe") || strstr(rn, "SWR") ||
                         strstr(rn, "Software Rasterizer"));
    st = rn_make_framebuffers(ctx, r);
    if (st == THX_OK) st = rn_gl_init(ctx, r);
    if (st != THX_OK) {
        rn_restore_current(r, &prev);
        thx_renderer_destroy(&r);
        return st;
    }
    rn_restore_current(r, &prev);
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
    THX_CHECK(rn_make_current(ctx, r, &prev));
    thx_status st = rn_make_framebuffers(ctx, r);
    rn_restore_current(r, &prev);
    return st;
}

int thx_renderer_samples(const thx_renderer *r) { return r && r->own ? r->samples : 0; }

thx_status thx_render(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, thx_raster *img, size_t *n_nan)
{
    if (n_nan) *n_nan = 0;
    if (!r || !r->own)
        return thx_error(ctx, THX_EINPUT, "thx_render: the renderer has no offscreen context (made with 0 x 0: use "
                         "thx_render_scene_gl)");
    if (!img || img->w != r->w || img->h != r->h)
        return thx_error(ctx, THX_EINPUT, "thx_render: the image is %d x %d, the renderer %d x %d", img ? img->w : 0,
                         img ? img->h : 0, r->w, r->h);
    if (!scene) return thx_error(ctx, THX_EINPUT, "thx_render: no scene");
    int rect[4], draw[4], keep[4];
    THX_CHECK(rn_viewport_rect(ctx, scene, r->w, r->h, rect));
    memcpy(draw, rect, sizeof draw);
    memcpy(keep, rect, sizeof keep);
    if (r->share_size > 1) { /* sort-first: this rank's band of rows (GL's rows count from the bottom) */
        if (!scene->clear)
            return thx_error(ctx, THX_EINPUT, "thx_render: sort-first draws scenes that clear their viewport only");
        int g0 = r->h - (int)((long long)r->h * (r->share_rank + 1) / r->share_size);
        int g1 = r->h - (int)((long long)r->h * r->share_rank / r->share_size);
        int k0 = g0 > rect[1] ? g0 : rect[1], k1 = g1 < rect[1] + rect[3] ? g1 : rect[1] + rect[3];
        if (k1 <= k0) return THX_OK; /* none of the viewport's rows is this rank's */
        int m = r->samples == 1 ? RN_FXAA_REACH : 0;
        int d0 = k0 - m > rect[1] ? k0 - m : rect[1], d1 = k1 + m < rect[1] + rect[3] ? k1 + m : rect[1] + rect[3];
        keep[1] = k0, keep[3] = k1 - k0;
        draw[1] = d0, draw[3] = d1 - d0;
    }
    egl_current prev;
    THX_CHECK(rn_make_current(ctx, r, &prev));
    thx_status st = THX_OK;
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    if (!scene->clear) THX_TRY(rn_blit_image(ctx, r, img, rect));
    if (r->share_size > 1) memcpy(r->scissor, draw, sizeof draw);
    st = rn_draw_scene(ctx, r, scene, r->w, r->h, n_nan);
    memset(r->scissor, 0, sizeof r->scissor);
    if (st != THX_OK) goto done;
    THX_TRY(rn_read_back(ctx, r, img, draw, keep, r->share_own));
done:
    rn_restore_current(r, &prev);
    return st;
}

thx_status thx_render_layer(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, unsigned char *rgba, float *depth,
                            size_t *n_nan)
{
    if (n_nan) *n_nan = 0;
    if (!r || !r->own) return thx_error(ctx, THX_EINPUT, "thx_render_layer: the renderer has no offscreen framebuffer");
    if (r->samples != 1)
        return thx_error(ctx, THX_EINPUT, "thx_render_layer: %d samples a pixel; layers are composited by depth, one "
                         "sample a pixel (thx_renderer_set_samples 1)", r->samples);
    if (!scene || !scene->clear) return thx_error(ctx, THX_EINPUT, "thx_render_layer: a scene that clears its viewport");
    int rect[4];
    THX_CHECK(rn_viewport_rect(ctx, scene, r->w, r->h, rect));
    egl_current prev;
    THX_CHECK(rn_make_current(ctx, r, &prev));
    thx_status st = THX_OK;
    float *z = NULL;
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    THX_TRY(rn_draw_scene(ctx, r, scene, r->w, r->h, n_nan));
    THX_TRY(rn_read_pixels(ctx, r, rect));
    int w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    z = thx_malloc(ctx, (size_t)w * h * sizeof *z);
    if (!z) { st = THX_ENOMEM; goto done; }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r->fbo_draw);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(rect[0], rect[1], w, h, GL_DEPTH_COMPONENT, GL_FLOAT, z);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    THX_TRY(rn_gl_check(ctx, "reading the depth back"));
    for (int y = 0; y < h; y++) { /* GL's rows from the bottom: flipped */
        size_t src = (size_t)w * (h - 1 - y), dst = (size_t)(y_top + y) * r->w + rect[0];
        memcpy(rgba + 4 * dst, r->pix + 4 * src, 4 * (size_t)w);
        memcpy(depth + dst, z + src, (size_t)w * sizeof *z);
    }
done:
    free(z);
    rn_restore_current(r, &prev);
    return st;
}

thx_status thx_render_layer_finish(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, const unsigned char *rgba,
                                   thx_raster *img)
{
    if (!r || !r->own || !img || img->w != r->w || img->h != r->h)
        return thx_error(ctx, THX_EINPUT, "thx_render_layer_finish: no renderer of the image's size");
    int rect[4];
    THX_CHECK(rn_viewport_rect(ctx, scene, r->w, r->h, rect));
    int w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    THX_CHECK(rn_grow(ctx, (void **)&r->pix, &r->pix_cap, 4 * (size_t)w * h, 1));
    for (int y = 0; y < h; y++) /* back to GL's rows, as rn_read_pixels leaves them */
        memcpy(r->pix + 4 * (size_t)w * (h - 1 - y), rgba + 4 * ((size_t)(y_top + y) * r->w + rect[0]), 4 * (size_t)w);
    return rn_finish(ctx, r, img, rect, rect, NULL);
}

thx_status thx_renderer_set_share(thx_ctx *ctx, thx_renderer *r, int rank, int size, unsigned char *own)
{
    if (!r || !r->own) return thx_error(ctx, THX_EINPUT, "thx_renderer_set_share: the renderer has no offscreen framebuffer");
    if (size < 0 || rank < 0 || (size > 1 && rank >= size) || (size <= 1 && rank != 0))
        return thx_error(ctx, THX_EINPUT, "thx_renderer_set_share: rank %d of %d", rank, size);
    r->share_rank = rank;
    r->share_size = size;
    r->share_own = own;
    return THX_OK;
}

thx_status thx_render_scene_gl(thx_ctx *ctx, thx_renderer *r, const thx_scene *scene, int fb_w, int fb_h,
                               size_t *n_nan)
{
    if (n_nan) *n_nan = 0;
    if (!r) return thx_error(ctx, THX_EINPUT, "thx_render_scene_gl: no renderer");
    if (fb_w <= 0 || fb_h <= 0)
        return thx_error(ctx, THX_EINPUT, "thx_render_scene_gl: bad framebuffer size %d x %d", fb_w, fb_h);
    if (!r->own) return rn_draw_scene(ctx, r, scene, fb_w, fb_h, n_nan);
    egl_current prev;
    THX_CHECK(rn_make_current(ctx, r, &prev));
    thx_status st = rn_draw_scene(ctx, r, scene, fb_w, fb_h, n_nan);
    rn_restore_current(r, &prev);
    return st;
}
