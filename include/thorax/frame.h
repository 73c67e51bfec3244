/*
 * The anatomical frame of a model: which of the model's axes point superior
 * (toward the head), anterior (toward the front) and to the subject's left.
 *
 * thorax's own models (the phantom) use RAS: +x the subject's right, +y
 * anterior, +z superior, so left is -x. Data made elsewhere often is not
 * (the Dalhousie torso's long axis is y). The frame is recorded in the
 * contours file ("frame UP FRONT") and in model.json ("frame"), given on
 * import (--up, --front), and read by every command that needs anatomy;
 * a model without one stops such a command with a message naming the
 * option (see docs/formats.md).
 */
#ifndef THORAX_FRAME_H
#define THORAX_FRAME_H

#include "thorax/core.h"

/* A signed axis: axis 0, 1, 2 (x, y, z) and sign +1 or -1. */
typedef struct {
    int axis;
    int sign;
} thx_axis;

typedef struct {
    int set;          /* 0: no frame recorded (the fields below are meaningless) */
    thx_axis up;      /* superior */
    thx_axis front;   /* anterior */
} thx_frame;

/* Parses "+z", "-y", "x" (sign optional, '+' by default) into *a; -1 if not such a name. */
int thx_axis_parse(const char *s, thx_axis *a);
/* Writes "+z" etc. into buf (at least 3 bytes); returns buf. */
const char *thx_axis_name(thx_axis a, char buf[3]);
/* Sets *f from the two names; THX_EINPUT naming `what` (e.g. "--up/--front" or "file:line")
 * when a name is bad or the two axes are not perpendicular. */
thx_status thx_frame_from_names(thx_ctx *ctx, const char *up, const char *front, const char *what, thx_frame *f);
/* The unit vectors of the frame in model coordinates: superior, anterior and the subject's
 * left = superior x anterior (in RAS: z x y = -x; a right-handed body). f->set required. */
void thx_frame_vectors(const thx_frame *f, double up[3], double front[3], double left[3]);
/* The RAS frame of thorax's own models (+z up, +y front). */
thx_frame thx_frame_ras(void);

#endif
