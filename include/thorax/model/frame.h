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

#include "thorax/core/core.h"
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
/* The axis toward the subject's left (superior x anterior). f->set required. */
thx_axis thx_frame_left(const thx_frame *f);
/* Whether f is a valid frame (set, axes 0..2, signs +-1, up and front on different axes). */
int thx_frame_valid(const thx_frame *f);
/* A point or vector between model coordinates p and the RAS coordinates q of the frame
 * (q[0] toward the subject's right, q[1] anterior, q[2] superior). The map is a rotation
 * (det +1): orientations, distances and handedness are kept. f->set required. */
void thx_frame_to_ras(const thx_frame *f, const double p[3], double q[3]);
void thx_frame_from_ras(const thx_frame *f, const double q[3], double p[3]);
/* THX_EINPUT when f is not set, with the message every command that needs anatomy gives:
 * "MODEL has no anatomical frame (which axes point superior and anterior; NEEDS depend on
 * it): give --up and --front to thorax import ..., or a 'frame UP FRONT' line in the
 * contours"; `needs` says what needed it ("the 12-lead landmarks"). THX_OK when set. */
thx_status thx_frame_require(thx_ctx *ctx, const thx_frame *f, const char *model, const char *needs);

#endif
