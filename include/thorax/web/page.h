/*
 * thorax/web/page.h — results as one self-contained HTML page (issue 29; docs/design/web.md).
 *
 * The page is the viewer (web/, bundled into the binary at build time) and its data inline: a JSON
 * description and binary blobs, each deflated and base64-encoded in a script element of its own.
 * This module writes the blobs and the file; what goes into the description is the caller's
 * (src/cli/cmd_export_page.c builds it from a picture, so the page shows what `thorax render` draws).
 *
 * Potentials are quantized to 16 bits per surface and series: value = origin + code * step with
 * code 0..65534 over the series' finite range and 65535 for a value that is not a number, so no
 * decoded value is further than step / 2 from the original. Frames are stored one after the other,
 * each as differences from the previous frame's codes (mod 65536), which deflate compresses well
 * since a beat changes little from one millisecond to the next.
 */
#ifndef THORAX_WEB_PAGE_H
#define THORAX_WEB_PAGE_H
#include <stddef.h>
#include <stdint.h>

#include "thorax/core/core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define THX_WEB_NAN_CODE 65535u

/* A series quantized: codes[f * n_rows + i] for row i of frame f. */
typedef struct {
    uint16_t *codes;
    size_t n_rows, n_frames;
    double origin, step; /* value = origin + code * step */
    double min, max;     /* the finite range (min > max: no finite value) */
    size_t n_nan;        /* values that are not numbers */
} thx_web_quant;

/* Quantizes v[f * n_rows + i] (frame-major, n_frames frames). */
thx_status thx_web_quantize(thx_ctx *ctx, const double *v, size_t n_rows, size_t n_frames, thx_web_quant *q);
void thx_web_quant_free(thx_web_quant *q);
/* The value of a code (NaN for THX_WEB_NAN_CODE). */
double thx_web_dequantize(const thx_web_quant *q, uint16_t code);
/* The largest |decoded - original| over the finite values (NaN must stay NaN: else +inf). */
double thx_web_quant_error(const thx_web_quant *q, const double *v);
/* Each frame after the first replaced by its difference from the previous one, mod 65536, and back. */
void thx_web_delta_encode(uint16_t *codes, size_t n_rows, size_t n_frames);
void thx_web_delta_decode(uint16_t *codes, size_t n_rows, size_t n_frames);

/* Raw deflate (RFC 1951, no zlib header: the browser's DecompressionStream("deflate-raw")), level 9.
 * *out is malloc'd. */
thx_status thx_web_deflate(thx_ctx *ctx, const void *in, size_t n, unsigned char **out, size_t *out_n);
/* And back, for the tests: exactly want bytes or an error. */
thx_status thx_web_inflate(thx_ctx *ctx, const unsigned char *in, size_t n, size_t want, unsigned char **out);
/* Standard base64 (RFC 4648, padded) of in[0..n) into out (4 * ((n + 2) / 3) bytes, no NUL). */
size_t thx_web_base64(const unsigned char *in, size_t n, char *out);

/* The page being written. */
typedef struct thx_web_page thx_web_page;
thx_status thx_web_page_create(thx_ctx *ctx, thx_web_page **p);
void thx_web_page_free(thx_web_page **p);
/* Adds a blob of count elements of type ("float32", "float64", "uint32", "uint16", "uint8"; elem_size
 * bytes each, little-endian as this machine is), deflated when compress; its index in *index. */
thx_status thx_web_page_blob(thx_ctx *ctx, thx_web_page *p, const char *type, const void *data, size_t count,
                             size_t elem_size, int compress, int *index);
size_t thx_web_page_blobs(const thx_web_page *p);
/* The blob's type and element count (for the description's "blobs" list), its stored bytes. */
const char *thx_web_page_blob_type(const thx_web_page *p, size_t k, size_t *count, size_t *stored);
/* Writes the page to path (atomically; an existing file is replaced only if it is a page thorax
 * wrote, and never when it is one of inputs): title, the description (JSON text; every "</" is
 * written "<\/"), the blobs, then the viewer's script. *bytes (may be NULL): the file's size. */
thx_status thx_web_page_write(thx_ctx *ctx, const thx_web_page *p, const char *path, const char *title,
                              const char *meta_json, const char *viewer, size_t viewer_len,
                              const char *const *inputs, size_t n_inputs, size_t *bytes);

/* The viewer bundled at build time (web/, scripts/web.sh), and its length; NULL and 0 when this
 * thorax was built without it (node and npm missing). */
const char *thx_web_viewer(size_t *len);

#ifdef __cplusplus
}
#endif
#endif
