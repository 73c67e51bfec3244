/*
 * The scan under the model (issue 25; picture/scan.c): the image of --image read once, and its
 * planes made into textures (grey levels under a window and level, or a colour per label).
 *
 * Internal to src/picture. The volume (thorax/image/image.h's thx_image) stays behind pic_scan, so
 * that a picture's settings and the renderer's RGBA raster (thx_raster, thorax/render/image.h) need
 * not know the image module.
 */
#ifndef THORAX_PICTURE_SCAN_H
#define THORAX_PICTURE_SCAN_H

#include "thorax/core/core.h"

typedef struct pic_scan pic_scan;

/* A plane's texture: w x h texels (RGBA; alpha 0 outside the image), the rectangle they cover
 * (origin: the outer corner of texel (0, 0); u, v: the whole edges, RAS mm) and its unit normal. */
typedef struct {
    int w, h;
    unsigned char *rgba;
    double origin[3], u[3], v[3], normal[3];
    int nearest;   /* sampled at the nearest voxel (a label map): texels drawn as blocks */
} pic_scan_tex;

/* Reads the image (any format thx_image_read takes) and settles its default window. */
thx_status pic_scan_open(thx_ctx *ctx, const char *path, pic_scan **out);
void pic_scan_close(pic_scan **s);
/* The image read (thx_picture_scan_image). */
struct thx_image;
const struct thx_image *pic_scan_image(const pic_scan *s);
/* The default window and level, and why ("label map, full range", ...). */
void pic_scan_window(const pic_scan *s, double *window, double *level, const char **why);
/* Whether the image looks like a label map (integral, >= 0, at most 256 distinct values). */
int pic_scan_is_labels(const pic_scan *s);
/* "x".."z" or "i".."k" plane of spec text ("z=12.5"): 0, or -1 when not a plane. */
int pic_scan_parse(const char *spec, char *axis, double *pos);
/* The positions a plane along axis may take in the image and the step to the next image plane. */
void pic_scan_range(const pic_scan *s, char axis, double *lo, double *hi, double *step);
/* The plane's texture (out->rgba malloc'd; free it). labels: a colour per label value (the
 * categorical table, label 0 black) and nearest sampling; otherwise grey levels
 * grey = (value - (level - window / 2)) / window clamped to [0, 1], nearest sampling for a label
 * map and trilinear for a scan. THX_EINPUT when the plane lies outside the image. */
thx_status pic_scan_texture(thx_ctx *ctx, const pic_scan *s, char axis, double pos, int labels, double window,
                            double level, pic_scan_tex *out);
/* The colour of label value k in the categorical table (k = 0: black). */
void pic_scan_label_color(long k, unsigned char rgb[3]);

#endif
