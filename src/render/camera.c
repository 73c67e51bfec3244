/*
 * Cameras: the standard anatomical views and the view and projection
 * matrices (see render_internal.h for the conventions).
 *
 * The standard views look at the subject from one side with the head up
 * (superior and inferior views: anterior up). The image's right is then
 * right = (center - eye) x up: in the anterior view, looking along -y with +z
 * up, that is -x, so the subject's right (+x) is on the image's left, as a
 * viewer facing the patient sees it; the inferior view is the radiological
 * one (from the feet, anterior up, the subject's right on the image's left).
 */
#include "render_internal.h"

#include <math.h>
#include <string.h>

static const char *const VIEW_NAMES[] = {"anterior", "posterior", "left", "right", "superior", "inferior"};

int thx_view_parse(const char *name, thx_view *out)
{
    for (int i = 0; i < 6; i++)
        if (name && strcmp(name, VIEW_NAMES[i]) == 0) {
            *out = (thx_view)i;
            return 0;
        }
    return -1;
}

/* Direction from the centre toward the eye, and the image's up, per view. */
static void view_axes(thx_view view, double back[3], double up[3])
{
    static const double B[6][3] = {{0, 1, 0}, {0, -1, 0}, {-1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
    static const double U[6][3] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 1, 0}, {0, 1, 0}};
    int v = (int)view >= 0 && (int)view < 6 ? (int)view : 0;
    memcpy(back, B[v], sizeof B[v]);
    memcpy(up, U[v], sizeof U[v]);
}

void thx_camera_view(thx_camera *cam, thx_view view, const double lo[3], const double hi[3], double aspect)
{
    double back[3], up[3], right[3], c[3], ext[3], diag = 0;
    view_axes(view, back, up);
    right[0] = up[1] * back[2] - up[2] * back[1]; /* right = up x back */
    right[1] = up[2] * back[0] - up[0] * back[2];
    right[2] = up[0] * back[1] - up[1] * back[0];
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5 * (lo[k] + hi[k]);
        ext[k] = fabs(hi[k] - lo[k]);
        diag += ext[k] * ext[k];
    }
    diag = sqrt(diag);
    /* Axis-aligned frame: the extent across the image is the box's size along that axis. */
    double eh = fabs(right[0]) * ext[0] + fabs(right[1]) * ext[1] + fabs(right[2]) * ext[2];
    double ev = fabs(up[0]) * ext[0] + fabs(up[1]) * ext[1] + fabs(up[2]) * ext[2];
    if (!(aspect > 0) || !isfinite(aspect)) aspect = 1;
    double height = fmax(ev, eh / aspect) * 1.1; /* a 5% margin on each side */
    if (!(height > 0) || !isfinite(height)) height = 1;
    double dist = 2 * diag + height; /* in front of the box; only perspective and clipping care */
    memset(cam, 0, sizeof *cam);
    for (int k = 0; k < 3; k++) {
        cam->center[k] = c[k];
        cam->eye[k] = c[k] + dist * back[k];
        cam->up[k] = up[k];
    }
    cam->fov_deg = 0;
    cam->height = height;
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

int cam_frame(const thx_camera *cam, double right[3], double up[3], double back[3])
{
    for (int k = 0; k < 3; k++) back[k] = cam->eye[k] - cam->center[k];
    double lb = norm3(back);
    if (!(lb > 0) || !isfinite(lb)) return -1;
    for (int k = 0; k < 3; k++) back[k] /= lb;
    const double *u = cam->up;
    right[0] = u[1] * back[2] - u[2] * back[1];
    right[1] = u[2] * back[0] - u[0] * back[2];
    right[2] = u[0] * back[1] - u[1] * back[0];
    double lr = norm3(right), lu = norm3(u);
    if (!(lr > 1e-9 * lu) || !isfinite(lr)) return -1;
    for (int k = 0; k < 3; k++) right[k] /= lr;
    up[0] = back[1] * right[2] - back[2] * right[1]; /* up = back x right, unit */
    up[1] = back[2] * right[0] - back[0] * right[2];
    up[2] = back[0] * right[1] - back[1] * right[0];
    return 0;
}

void cam_view_matrix(const thx_camera *cam, double m[16])
{
    double r[3], u[3], b[3];
    memset(m, 0, 16 * sizeof *m);
    if (cam_frame(cam, r, u, b) != 0) {
        m[0] = m[5] = m[10] = m[15] = 1;
        return;
    }
    for (int k = 0; k < 3; k++) {
        m[k * 4 + 0] = r[k];
        m[k * 4 + 1] = u[k];
        m[k * 4 + 2] = b[k];
    }
    m[12] = -(r[0] * cam->eye[0] + r[1] * cam->eye[1] + r[2] * cam->eye[2]);
    m[13] = -(u[0] * cam->eye[0] + u[1] * cam->eye[1] + u[2] * cam->eye[2]);
    m[14] = -(b[0] * cam->eye[0] + b[1] * cam->eye[1] + b[2] * cam->eye[2]);
    m[15] = 1;
}

void cam_proj_matrix(const thx_camera *cam, double aspect, double znear, double zfar, double m[16])
{
    memset(m, 0, 16 * sizeof *m);
    double fn = zfar - znear;
    if (cam->fov_deg > 0) {
        double f = 1 / tan(0.5 * cam->fov_deg * M_PI / 180);
        m[0] = f / aspect;
        m[5] = f;
        m[10] = -(zfar + znear) / fn;
        m[11] = -1;
        m[14] = -2 * zfar * znear / fn;
    } else {
        double hh = 0.5 * cam->height, hw = hh * aspect;
        m[0] = 1 / hw;
        m[5] = 1 / hh;
        m[10] = -2 / fn;
        m[14] = -(zfar + znear) / fn;
        m[15] = 1;
    }
}

void cam_depth_range(const thx_camera *cam, const double lo[3], const double hi[3], double *znear, double *zfar)
{
    double r[3], u[3], b[3], dmin = INFINITY, dmax = -INFINITY, size = 0;
    if (cam_frame(cam, r, u, b) != 0) {
        *znear = 1, *zfar = 2;
        return;
    }
    for (int i = 0; i < 8; i++) {
        double p[3] = {i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]};
        double d = -((p[0] - cam->eye[0]) * b[0] + (p[1] - cam->eye[1]) * b[1] + (p[2] - cam->eye[2]) * b[2]);
        dmin = fmin(dmin, d);
        dmax = fmax(dmax, d);
    }
    for (int k = 0; k < 3; k++) size += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    double margin = 0.02 * (dmax - dmin) + 1e-3 * sqrt(size) + 1e-6 * (fabs(dmax) + 1);
    if (!isfinite(dmin) || !isfinite(dmax)) {
        *znear = 1, *zfar = 2;
        return;
    }
    double zn = dmin - margin, zf = dmax + margin;
    if (cam->fov_deg > 0) {
        if (zf <= 0) zf = 1;
        if (zn < zf / 2000) zn = zf / 2000;
    }
    *znear = zn;
    *zfar = zf;
}

int thx_camera_project(const thx_camera *cam, int w, int h, const double p[3], double *x, double *y, double *depth)
{
    double r[3], u[3], b[3];
    if (w <= 0 || h <= 0 || cam_frame(cam, r, u, b) != 0) return -1;
    double q[3] = {p[0] - cam->eye[0], p[1] - cam->eye[1], p[2] - cam->eye[2]};
    double xe = q[0] * r[0] + q[1] * r[1] + q[2] * r[2], ye = q[0] * u[0] + q[1] * u[1] + q[2] * u[2];
    double d = -(q[0] * b[0] + q[1] * b[1] + q[2] * b[2]);
    double aspect = (double)w / h, nx, ny;
    if (cam->fov_deg > 0) {
        if (!(d > 0)) return -1;
        double f = 1 / tan(0.5 * cam->fov_deg * M_PI / 180);
        nx = f / aspect * xe / d;
        ny = f * ye / d;
    } else {
        double hh = 0.5 * cam->height, hw = hh * aspect;
        if (!(hh > 0)) return -1;
        nx = xe / hw;
        ny = ye / hh;
    }
    *x = 0.5 * (nx + 1) * w;
    *y = 0.5 * (1 - ny) * h;
    *depth = d;
    return 0;
}

int thx_camera_ray(const thx_camera *cam, int w, int h, double x, double y, double origin[3], double dir[3])
{
    double r[3], u[3], b[3];
    if (w <= 0 || h <= 0 || cam_frame(cam, r, u, b) != 0) return -1;
    double aspect = (double)w / h, nx = 2 * x / w - 1, ny = 1 - 2 * y / h;
    if (cam->fov_deg > 0) {
        double ty = tan(0.5 * cam->fov_deg * M_PI / 180), tx = ty * aspect, n = 0;
        for (int k = 0; k < 3; k++) {
            origin[k] = cam->eye[k];
            dir[k] = -b[k] + nx * tx * r[k] + ny * ty * u[k];
            n += dir[k] * dir[k];
        }
        n = sqrt(n);
        for (int k = 0; k < 3; k++) dir[k] /= n;
    } else {
        double hh = 0.5 * cam->height, hw = hh * aspect;
        if (!(hh > 0)) return -1;
        for (int k = 0; k < 3; k++) {
            origin[k] = cam->eye[k] + nx * hw * r[k] + ny * hh * u[k];
            dir[k] = -b[k];
        }
    }
    return 0;
}
