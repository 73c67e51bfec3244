/* The anatomical frame of a model (see thorax/model/frame.h). */
#include "thorax/model/frame.h"
#include <string.h>

int thx_axis_parse(const char *s, thx_axis *a)
{
    int sign = 1;
    if (*s == '+' || *s == '-') sign = *s++ == '-' ? -1 : 1;
    if ((*s == 'x' || *s == 'y' || *s == 'z') && !s[1]) {
        a->axis = *s - 'x';
        a->sign = sign;
        return 0;
    }
    return -1;
}

const char *thx_axis_name(thx_axis a, char buf[3])
{
    buf[0] = a.sign < 0 ? '-' : '+';
    buf[1] = (char)('x' + a.axis);
    buf[2] = '\0';
    return buf;
}

thx_status thx_frame_from_names(thx_ctx *ctx, const char *up, const char *front, const char *what, thx_frame *f)
{
    thx_frame r = {0};
    if (!up || thx_axis_parse(up, &r.up))
        return thx_error(ctx, THX_EINPUT, "%s: superior axis \"%s\" is not one of +x -x +y -y +z -z", what, up ? up : "");
    if (!front || thx_axis_parse(front, &r.front))
        return thx_error(ctx, THX_EINPUT, "%s: anterior axis \"%s\" is not one of +x -x +y -y +z -z", what,
                         front ? front : "");
    if (r.up.axis == r.front.axis)
        return thx_error(ctx, THX_EINPUT, "%s: the superior (%s) and anterior (%s) axes must be different axes", what, up,
                         front);
    r.set = 1;
    *f = r;
    return THX_OK;
}

void thx_frame_vectors(const thx_frame *f, double up[3], double front[3], double left[3])
{
    memset(up, 0, 3 * sizeof *up);
    memset(front, 0, 3 * sizeof *front);
    up[f->up.axis] = f->up.sign;
    front[f->front.axis] = f->front.sign;
    left[0] = up[1] * front[2] - up[2] * front[1];
    left[1] = up[2] * front[0] - up[0] * front[2];
    left[2] = up[0] * front[1] - up[1] * front[0];
}

thx_frame thx_frame_ras(void)
{
    thx_frame f = {1, {2, 1}, {1, 1}};
    return f;
}

thx_axis thx_frame_left(const thx_frame *f)
{
    double u[3], a[3], l[3];
    thx_frame_vectors(f, u, a, l);
    thx_axis r = {0, 1};
    for (int k = 0; k < 3; k++)
        if (l[k] != 0) {
            r.axis = k;
            r.sign = l[k] > 0 ? 1 : -1;
        }
    return r;
}

int thx_frame_valid(const thx_frame *f)
{
    return f && f->set && f->up.axis >= 0 && f->up.axis <= 2 && f->front.axis >= 0 && f->front.axis <= 2 &&
           (f->up.sign == 1 || f->up.sign == -1) && (f->front.sign == 1 || f->front.sign == -1) &&
           f->up.axis != f->front.axis;
}

void thx_frame_to_ras(const thx_frame *f, const double p[3], double q[3])
{
    double u[3], a[3], l[3];
    thx_frame_vectors(f, u, a, l);
    double r0 = -(l[0] * p[0] + l[1] * p[1] + l[2] * p[2]);
    double r1 = a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
    double r2 = u[0] * p[0] + u[1] * p[1] + u[2] * p[2];
    q[0] = r0;
    q[1] = r1;
    q[2] = r2;
}

void thx_frame_from_ras(const thx_frame *f, const double q[3], double p[3])
{
    double u[3], a[3], l[3];
    thx_frame_vectors(f, u, a, l);
    double r[3];
    for (int k = 0; k < 3; k++) r[k] = -l[k] * q[0] + a[k] * q[1] + u[k] * q[2];
    memcpy(p, r, sizeof r);
}

thx_status thx_frame_require(thx_ctx *ctx, const thx_frame *f, const char *model, const char *needs)
{
    if (f && f->set) return THX_OK;
    return thx_error(ctx, THX_EINPUT,
                     "%s has no anatomical frame (which axes point superior and anterior; %s depend on it): give "
                     "--up and --front to thorax import (e.g. --up +z --front +y), or a 'frame UP FRONT' line in the "
                     "contours given to thorax surfaces",
                     model, needs);
}
