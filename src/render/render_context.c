/*
 * The renderer's OpenGL context (see render.c): an EGL display and an OpenGL 3.3 core context of
 * the renderer's own, made current for a frame and the caller's given back after; and the
 * offscreen framebuffers it draws into.
 */
#include "render_internal.h"

#include <stdio.h>
#include <string.h>

#define MAX_SAMPLES 4

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
thx_status rn_egl_open(thx_ctx *ctx, thx_renderer *r)
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

/* ---------------------------------------------------------------- switching */

/* Makes the renderer's context current, remembering the caller's (egl_current:
 * render_internal.h). */
thx_status rn_make_current(thx_ctx *ctx, thx_renderer *r, egl_current *prev)
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
void rn_restore_current(const thx_renderer *r, const egl_current *prev)
{
    if (prev->ctx != EGL_NO_CONTEXT && prev->ctx != r->egl)
        eglMakeCurrent(prev->dpy, prev->draw, prev->read, prev->ctx);
}

/* ------------------------------------------------------------- framebuffers */

void rn_free_framebuffers(thx_renderer *r)
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
thx_status rn_make_framebuffers(thx_ctx *ctx, thx_renderer *r)
{
    GLint max_samples = 0, max_rb = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
    if (r->w > max_rb || r->h > max_rb)
        return thx_error(ctx, THX_EINPUT, "renderer: %d x %d pixels exceed the driver's limit of %d", r->w, r->h,
                         max_rb);
    int want = r->samples_asked ? r->samples_asked : r->software ? 1 : MAX_SAMPLES;
    r->samples = want > 1 && max_samples >= MAX_SAMPLES ? MAX_SAMPLES : 1;
    rn_free_framebuffers(r);
    if (r->samples > 1) THX_CHECK(make_fbo(ctx, r->w, r->h, 1, 0, &r->fbo_out, &r->rb_out, NULL));
    THX_CHECK(make_fbo(ctx, r->w, r->h, r->samples, 1, &r->fbo_draw, &r->rb_color, &r->rb_depth));
    return rn_gl_check(ctx, "creating the framebuffers");
}
