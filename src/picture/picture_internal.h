/* What the picture module's files share (thorax/picture/picture.h). */
#ifndef THORAX_PICTURE_INTERNAL_H
#define THORAX_PICTURE_INTERNAL_H
#include "thorax/picture/picture.h"

/* Node labels and extrema marks over img (marks.c), for a single-panel picture drawn at img's size. */
thx_status picture_marks(thx_ctx *ctx, const thx_picture_opts *o, thx_picture_data *d, thx_font *font, int frame,
                         thx_image *img);
#endif
