/*
 * The pixels between the image and the framebuffer (see render.c): the image under a viewport
 * that is not cleared, copied in before drawing; after it, the drawing resolved (multisampled) or
 * smoothed by FXAA on the CPU (one sample), read back, flipped into the image and divided by alpha.
 */
#include "render_internal.h"

#include <stdlib.h>
#include <string.h>

/* The image's pixels under the viewport into the framebuffer, premultiplied (clear = 0). */
thx_status rn_blit_image(thx_ctx *ctx, thx_renderer *r, const thx_raster *img, const int rect[4])
{
    int x0 = rect[0], w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    THX_CHECK(rn_grow(ctx, (void **)&r->pix, &r->pix_cap, (size_t)4 * w * h, 1));
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
    return rn_gl_check(ctx, "copying the image under the viewport");
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
            /* the farthest a search reaches is 1 + 23 = 24 rows or columns away: RN_FXAA_REACH (26) must
               stay above it, or sort-first's bands would differ from the whole picture near their edges */
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

/* Resolves rect (multisampled) or smooths it (FXAA), reads it back, flips its rows keep into img and
 * divides out alpha. */
thx_status rn_read_back(thx_ctx *ctx, thx_renderer *r, thx_raster *img, const int rect[4], const int keep[4], unsigned char *own)
{
    THX_CHECK(rn_read_pixels(ctx, r, rect));
    return rn_finish(ctx, r, img, rect, keep, own);
}

/* rect's pixels (resolved when multisampled) into r->pix, GL's rows (from the bottom), premultiplied. */
thx_status rn_read_pixels(thx_ctx *ctx, thx_renderer *r, const int rect[4])
{
    int w = rect[2], h = rect[3];
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
    THX_CHECK(rn_grow(ctx, (void **)&r->pix, &r->pix_cap, 4 * n, 1));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(rect[0], rect[1], w, h, GL_RGBA, GL_UNSIGNED_BYTE, r->pix);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo_draw);
    return rn_gl_check(ctx, "reading the image back");
}

/* r->pix (rect's pixels, as rn_read_pixels leaves them) smoothed by FXAA (one sample), its rows keep
 * flipped into img and divided by alpha; own (may be NULL): those pixels set to 1. */
thx_status rn_finish(thx_ctx *ctx, thx_renderer *r, thx_raster *img, const int rect[4], const int keep[4], unsigned char *own)
{
    int w = rect[2], h = rect[3], y_top = r->h - rect[1] - h;
    size_t n = (size_t)w * h;
    const unsigned char *pix = r->pix;
    if (r->samples == 1) {
        THX_CHECK(rn_grow(ctx, (void **)&r->pix2, &r->pix2_cap, 4 * n, 1));
        THX_CHECK(rn_grow(ctx, (void **)&r->luma, &r->luma_cap, n, sizeof *r->luma));
        fxaa(r->pix, r->pix2, r->luma, w, h);
        pix = r->pix2;
    }
    for (int y = 0; y < h; y++) {
        int gl_row = rect[1] + h - 1 - y; /* this image row's in GL's order */
        if (gl_row < keep[1] || gl_row >= keep[1] + keep[3]) continue;
        const unsigned char *src = pix + (size_t)4 * w * (h - 1 - y);
        unsigned char *dst = img->rgba + 4 * ((size_t)(y_top + y) * img->w + rect[0]);
        if (own) memset(own + (size_t)(y_top + y) * img->w + rect[0], 1, (size_t)w);
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
