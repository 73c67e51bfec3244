/*
 * Images (thorax/image.h): RGBA buffers and PNG files.
 *
 * PNG goes through libpng's simplified API (png_image_*), which catches
 * libpng's internal longjmp itself: no setjmp in thorax. Files are written
 * through a temporary file renamed into place (thorax/fileio.h), so a failed
 * write leaves nothing behind. An image whose every alpha is 255 is written as
 * 8-bit RGB (a quarter smaller, and what most viewers expect of a picture);
 * otherwise 8-bit RGBA. Reading converts any PNG (grey, palette, 16-bit,
 * interlaced) to 8-bit RGBA, not premultiplied. 8-bit files come through
 * unchanged; 16-bit files without colour-space chunks are taken as linear
 * light, as the simplified API's rule is, and encoded to sRGB (0.5 becomes
 * 186, not 128): other viewers may show such files darker.
 */
#include "thorax/render/image.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>
#include <zlib.h>

#include "thorax/core/fileio.h"
/* Largest side accepted: keeps 4 w h far from overflow and refuses absurd PNG headers before
   allocating (32768^2 RGBA is 4 GiB). */
#define THX_IMAGE_MAX_SIDE 32768

thx_status thx_raster_create(thx_ctx *ctx, int w, int h, thx_raster **out)
{
    *out = NULL;
    if (w <= 0 || h <= 0 || w > THX_IMAGE_MAX_SIDE || h > THX_IMAGE_MAX_SIDE)
        return thx_error(ctx, THX_EINPUT, "image size %d x %d: each side must be 1 to %d pixels", w, h,
                         THX_IMAGE_MAX_SIDE);
    thx_raster *img = thx_calloc(ctx, 1, sizeof *img);
    if (!img) return THX_ENOMEM;
    img->rgba = thx_calloc(ctx, (size_t)w * (size_t)h, 4);
    if (!img->rgba) {
        free(img);
        return THX_ENOMEM;
    }
    img->w = w;
    img->h = h;
    *out = img;
    return THX_OK;
}

void thx_raster_destroy(thx_raster **img)
{
    if (!img || !*img) return;
    free((*img)->rgba);
    free(*img);
    *img = NULL;
}

void thx_raster_fill(thx_raster *img, const unsigned char rgba[4])
{
    size_t n = (size_t)img->w * (size_t)img->h;
    for (size_t i = 0; i < n; i++) memcpy(img->rgba + 4 * i, rgba, 4);
}

static int all_opaque(const thx_raster *img)
{
    size_t n = (size_t)img->w * (size_t)img->h;
    for (size_t i = 0; i < n; i++)
        if (img->rgba[4 * i + 3] != 255) return 0;
    return 1;
}

thx_status thx_raster_write_png(thx_ctx *ctx, const thx_raster *img, const char *path)
{
    if (!img || !img->rgba || img->w <= 0 || img->h <= 0)
        return thx_error(ctx, THX_EINPUT, "%s: no image to write", path);
    int opaque = all_opaque(img);
    unsigned char *rgb = NULL;
    const unsigned char *pixels = img->rgba;
    if (opaque) {
        size_t n = (size_t)img->w * (size_t)img->h;
        rgb = thx_malloc(ctx, 3 * n);
        if (!rgb) return THX_ENOMEM;
        for (size_t i = 0; i < n; i++) memcpy(rgb + 3 * i, img->rgba + 4 * i, 3);
        pixels = rgb;
    }

    /* Encoded in memory, then written with a tEXt chunk "Software: thorax" after the header: the
     * signature by which a later run knows the file as its own (thorax/fileio.h). */
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    pi.width = (png_uint_32)img->w;
    pi.height = (png_uint_32)img->h;
    pi.format = opaque ? PNG_FORMAT_RGB : PNG_FORMAT_RGBA;
    pi.flags = PNG_IMAGE_FLAG_FAST; /* zlib's fast setting and fewer filters: 3x faster, ~20% larger */
    png_alloc_size_t size = 0;
    unsigned char *png = NULL;
    int ok = png_image_write_to_memory(&pi, NULL, &size, 0, pixels, 0, NULL);
    if (ok && size > 33) {
        png = thx_malloc(ctx, size);
        ok = png && png_image_write_to_memory(&pi, png, &size, 0, pixels, 0, NULL);
    }
    free(rgb);
    if (!ok || size <= 33) {
        thx_status st = png ? thx_error(ctx, THX_EIO, "%s: PNG encoding failed: %s", path, pi.message) : THX_ENOMEM;
        png_image_free(&pi);
        free(png);
        return st;
    }
    png_image_free(&pi);
    thx_atomic_file af;
    thx_status st = thx_atomic_open_output(ctx, path, THX_PNG_MARKER, sizeof THX_PNG_MARKER - 1, NULL, 0, &af);
    if (st != THX_OK) {
        free(png);
        return st;
    }
    /* signature (8) and IHDR (4 length + 4 type + 13 data + 4 CRC) come first in every PNG */
    static const unsigned char text[] = "tEXt" THX_PNG_MARKER;
    const size_t n_text = sizeof text - 1; /* type + data */
    unsigned char len[4] = {0, 0, 0, (unsigned char)(n_text - 4)}, crc[4];
    uLong c = crc32(crc32(0L, Z_NULL, 0), text, (uInt)n_text);
    for (int k = 0; k < 4; k++) crc[k] = (unsigned char)(c >> (24 - 8 * k));
    fwrite(png, 1, 33, af.f);
    fwrite(len, 1, 4, af.f);
    fwrite(text, 1, n_text, af.f);
    fwrite(crc, 1, 4, af.f);
    fwrite(png + 33, 1, size - 33, af.f);
    free(png);
    return thx_atomic_commit(ctx, &af);
}

thx_status thx_raster_read_png(thx_ctx *ctx, const char *path, thx_raster **out)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    unsigned char sig[8];
    size_t got = fread(sig, 1, sizeof sig, f);
    if (got != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        fclose(f);
        return thx_error(ctx, THX_EINPUT, "%s: not a PNG file (no PNG signature)", path);
    }
    rewind(f);

    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    thx_raster *img = NULL;
    thx_status st = THX_OK;
    if (!png_image_begin_read_from_stdio(&pi, f)) {
        st = thx_error(ctx, THX_EINPUT, "%s: unreadable PNG: %s", path, pi.message);
        goto done;
    }
    if (pi.width == 0 || pi.height == 0 || pi.width > THX_IMAGE_MAX_SIDE || pi.height > THX_IMAGE_MAX_SIDE) {
        st = thx_error(ctx, THX_EINPUT, "%s: PNG of %u x %u pixels: each side must be 1 to %d", path,
                       (unsigned)pi.width, (unsigned)pi.height, THX_IMAGE_MAX_SIDE);
        goto done;
    }
    /* 8-bit sRGB RGBA, not premultiplied; a file without colour-space chunks is taken as sRGB,
       so 8-bit files come through unchanged. */
    pi.format = PNG_FORMAT_RGBA;
    st = thx_raster_create(ctx, (int)pi.width, (int)pi.height, &img);
    if (st != THX_OK) goto done;
    if (!png_image_finish_read(&pi, NULL, img->rgba, 0, NULL)) {
        st = thx_error(ctx, THX_EINPUT, "%s: unreadable PNG: %s", path, pi.message);
        thx_raster_destroy(&img);
        goto done;
    }
    *out = img;
done:
    png_image_free(&pi);
    fclose(f);
    return st;
}
