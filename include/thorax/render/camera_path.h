/*
 * thorax/render/camera_path.h — key-framed camera flights (paper 4.3, "Animation methods"): camera
 * keys at movie frames, read from a key file (docs/formats.md, "Camera key files"), and the C2 path
 * through them.
 *
 * Positions (the eye and the target), the field of view and the orthographic height follow
 * interpolating cubic B-splines with their knots at the keys' frames (non-uniform, clamped), each key
 * reached exactly at its frame; the orientation follows Kim, Kim and Shin's cumulative B-spline curve
 * on unit quaternions (SIGGRAPH 1995) over the same knots, its control quaternions found by Newton's
 * method so that it passes through every key's orientation. Both are C2: position, velocity and
 * acceleration, and orientation, angular velocity and angular acceleration, are continuous.
 * docs/decisions.md, "Key-framed camera flights (issue 16)", says why.
 */
#ifndef THORAX_RENDER_CAMERA_PATH_H
#define THORAX_RENDER_CAMERA_PATH_H

#include "thorax/render/render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The conditions at the first and the last key (the two equations an interpolating cubic spline
 * leaves free). */
typedef enum {
    THX_CAMERA_ENDS_NATURAL = 0, /* zero acceleration (and angular acceleration) at the ends */
    THX_CAMERA_ENDS_REST,        /* zero velocity (and angular velocity): the camera starts and stops */
    THX_CAMERA_ENDS_CLOSED       /* a closed flight (the last key repeats the first): velocity and acceleration
                                    the same at both ends, so the loop is C2 all round (at most 100 keys) */
} thx_camera_ends;

/* What the orientation curve decides. */
typedef enum {
    THX_CAMERA_LOOK_TARGET = 0,  /* the camera looks at the interpolated target; the quaternion curve
                                    gives the roll (the up direction, made square to the view) */
    THX_CAMERA_LOOK_ORIENTATION  /* the quaternion curve gives the whole orientation; the target's
                                    spline only the distance to the point looked at */
} thx_camera_look;

/* Which fields a key's line gave (thx_camera_key.given). */
enum {
    THX_KEY_EYE = 1, THX_KEY_TARGET = 2, THX_KEY_UP = 4, THX_KEY_FOV = 8, THX_KEY_HEIGHT = 16,
    THX_KEY_DISTANCE = 32
};

typedef struct {
    int line;            /* in the key file, 1-based (0: not from a file) */
    int frame;           /* the movie frame, 1-based */
    int data_frame;      /* the data frame shown at that movie frame, 1-based; 0: not given */
    int view;            /* -1: the eye is given; else a thx_view, placed by thx_camera_keys_resolve */
    double distance;     /* a named view: from the target to the eye, mm (THX_KEY_DISTANCE) */
    unsigned given;      /* THX_KEY_* */
    thx_camera cam;      /* the fields given (all of them after thx_camera_keys_resolve) */
} thx_camera_key;

typedef struct {
    char *path;          /* the file's name, for messages (owned) */
    thx_camera_key *keys;
    size_t n;
    thx_camera_ends ends;
    thx_camera_look look;
} thx_camera_keys;

/* Reads a key file (docs/formats.md). Errors name the file, the line and the field: a frame that is
 * not above the previous key's, a number that is not finite, an unknown view or word, a key with
 * neither eye nor view, fewer than two keys. *out is zeroed first; free it with thx_camera_keys_free. */
thx_status thx_camera_keys_read(thx_ctx *ctx, const char *path, thx_camera_keys *out);
/* The same from text in memory, `name` standing for the file in messages. */
thx_status thx_camera_keys_parse(thx_ctx *ctx, const char *name, const char *text, thx_camera_keys *out);
void thx_camera_keys_free(thx_camera_keys *k);
/* Completes every key: fields a line does not give are the previous key's (target, up, fov,
 * height); a named view v places the eye at its distance (else the previous key's eye-to-target
 * distance, else the standard view's) from the target
 * (else the previous key's, else the standard view's centre) on the side of views[v], with views[v]'s
 * up unless the line gives one, and views[v]'s height for an orthographic key without one. views:
 * the six standard cameras (thx_view order) of the picture, or NULL when there are none (a named view
 * is then refused). Errors name the file and line: no target, up or fov for the first key, the eye on
 * the target, the up along the view direction, perspective and orthographic keys mixed. */
thx_status thx_camera_keys_resolve(thx_ctx *ctx, thx_camera_keys *k, const thx_camera views[6]);

typedef struct thx_camera_path thx_camera_path;

/* The path through resolved keys (thx_camera_keys_resolve). Refuses a path whose interpolated field
 * of view leaves (0, 180) degrees or height turns non-positive, whose eye meets its target, or whose
 * up turns along the view (the frame and the keys around it named), orientations of successive keys
 * 180 degrees or more apart, or an orientation curve that does not converge. */
thx_status thx_camera_path_create(thx_ctx *ctx, const thx_camera_keys *k, thx_camera_path **out);
void thx_camera_path_destroy(thx_camera_path **p);
/* The first and the last key's movie frames. */
int thx_camera_path_first(const thx_camera_path *p);
int thx_camera_path_last(const thx_camera_path *p);
/* The camera at a movie frame (fractional frames allowed; before the first key and after the last,
 * the end keys' cameras). */
void thx_camera_path_camera(const thx_camera_path *p, double frame, thx_camera *cam);
/* The data frame (1-based) shown at movie frame `frame`: linear in the movie frame between the keys
 * that give one, rounded to the nearest frame (halves up), the end ones' before and after them; 0
 * when no key gives one. */
int thx_camera_path_data_frame(const thx_camera_path *p, int frame);

/* The curves and their analytic first and second derivatives with respect to the movie frame, at
 * `frame`; at a key's frame, side < 0 takes the piece before it and side > 0 the piece after it
 * (they agree: the curves are C2). q is the orientation quaternion (w, x, y, z), the rotation whose
 * columns are the camera's right, up and back (eye minus target) directions. */
typedef struct {
    double eye[3][3], target[3][3], q[3][4], fov[3], height[3]; /* [derivative order][component] */
} thx_camera_path_state;
void thx_camera_path_state_at(const thx_camera_path *p, double frame, int side, thx_camera_path_state *s);

/* The unit quaternion (w, x, y, z) of a camera's look-at frame (columns right, up, back); -1 for a
 * degenerate camera (eye on the target, up along the view). */
int thx_camera_quaternion(const thx_camera *cam, double q[4]);

#ifdef __cplusplus
}
#endif
#endif
