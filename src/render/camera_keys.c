/*
 * Camera key files (thorax/render/camera_path.h; docs/formats.md, "Camera key files"): one key a
 * line, "FRAME [data N] (eye X,Y,Z | view NAME [distance D]) [target X,Y,Z] [up X,Y,Z] [fov DEG]
 * [height MM]", and the settings "ends natural|rest|closed" and "look target|orientation"; '#' starts a
 * comment. Then the keys completed: fields carried over from the previous key, named views placed.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/core/fileio.h"
#include "thorax/render/camera_path.h"

void thx_camera_keys_free(thx_camera_keys *k)
{
    if (!k) return;
    free(k->path);
    free(k->keys);
    memset(k, 0, sizeof *k);
}

/* A finite number filling the whole token. */
static int num(const char *s, double *v)
{
    char *end;
    *v = strtod(s, &end);
    return end != s && !*end && isfinite(*v) ? 0 : -1;
}

static int vec3(const char *s, double v[3])
{
    char buf[256];
    if (strlen(s) >= sizeof buf) return -1;
    strcpy(buf, s);
    char *a = buf, *b = strchr(a, ','), *c = b ? strchr(b + 1, ',') : NULL;
    if (!b || !c || strchr(c + 1, ',')) return -1;
    *b = *c = 0;
    return num(a, &v[0]) || num(b + 1, &v[1]) || num(c + 1, &v[2]) ? -1 : 0;
}

static int whole(const char *s, int *v)
{
    double d;
    if (num(s, &d) || d != floor(d) || d < 1 || d > 1e8) return -1;
    *v = (int)d;
    return 0;
}

/* One key line's words after the frame. */
static thx_status parse_key(thx_ctx *ctx, const char *name, int line, char **w, int nw, thx_camera_key *ky)
{
    static const char *const words[] = {"data", "eye", "view", "distance", "target", "up", "fov", "height"};
    unsigned seen = 0;
    ky->view = -1;
    for (int i = 0; i < nw; i += 2) {
        int f = -1;
        for (int k = 0; k < 8; k++)
            if (!strcmp(w[i], words[k])) f = k;
        if (f < 0)
            return thx_error(ctx, THX_EINPUT, "%s:%d: '%s': expected data, eye, view, distance, target, up, fov or height",
                             name, line, w[i]);
        if (seen & (1u << f)) return thx_error(ctx, THX_EINPUT, "%s:%d: %s given twice", name, line, words[f]);
        seen |= 1u << f;
        if (i + 1 >= nw) return thx_error(ctx, THX_EINPUT, "%s:%d: %s: no value", name, line, words[f]);
        const char *v = w[i + 1];
        int bad = 0;
        const char *want = "";
        switch (f) {
        case 0: bad = whole(v, &ky->data_frame), want = "a data frame, a whole number >= 1"; break;
        case 1: bad = vec3(v, ky->cam.eye), want = "three finite numbers X,Y,Z (mm)"; ky->given |= THX_KEY_EYE; break;
        case 2: {
            thx_view vw;
            bad = thx_view_parse(v, &vw);
            ky->view = bad ? -1 : (int)vw;
            want = "anterior, posterior, left, right, superior or inferior";
            break;
        }
        case 3:
            bad = num(v, &ky->distance) || !(ky->distance > 0), want = "a distance > 0 (mm)";
            ky->given |= THX_KEY_DISTANCE;
            break;
        case 4: bad = vec3(v, ky->cam.center), want = "three finite numbers X,Y,Z (mm)"; ky->given |= THX_KEY_TARGET; break;
        case 5: {
            bad = vec3(v, ky->cam.up), want = "three finite numbers X,Y,Z, not all zero";
            double *u = ky->cam.up;
            if (!bad && u[0] == 0 && u[1] == 0 && u[2] == 0) bad = 1;
            ky->given |= THX_KEY_UP;
            break;
        }
        case 6:
            bad = num(v, &ky->cam.fov_deg) || !(ky->cam.fov_deg >= 0 && ky->cam.fov_deg < 180);
            want = "degrees, 0 (orthographic) or between 0 and 180";
            ky->given |= THX_KEY_FOV;
            break;
        default:
            bad = num(v, &ky->cam.height) || !(ky->cam.height > 0), want = "the orthographic view's height > 0 (mm)";
            ky->given |= THX_KEY_HEIGHT;
            break;
        }
        if (bad) return thx_error(ctx, THX_EINPUT, "%s:%d: %s '%s': %s", name, line, words[f], v, want);
    }
    if ((ky->given & THX_KEY_EYE) && ky->view >= 0)
        return thx_error(ctx, THX_EINPUT, "%s:%d: eye and view both given: one of them", name, line);
    if (!(ky->given & THX_KEY_EYE) && ky->view < 0)
        return thx_error(ctx, THX_EINPUT, "%s:%d: frame %d: no eye X,Y,Z or view NAME", name, line, ky->frame);
    if ((ky->given & THX_KEY_DISTANCE) && ky->view < 0)
        return thx_error(ctx, THX_EINPUT, "%s:%d: distance is for a named view (view NAME distance D)", name, line);
    return THX_OK;
}

thx_status thx_camera_keys_parse(thx_ctx *ctx, const char *name, const char *text, thx_camera_keys *out)
{
    memset(out, 0, sizeof *out);
    out->path = strdup(name);
    char *buf = strdup(text);
    if (!out->path || !buf) {
        free(buf);
        thx_camera_keys_free(out);
        return thx_error(ctx, THX_ENOMEM, "%s: out of memory", name);
    }
    thx_status st = THX_OK;
    size_t cap = 0;
    int line = 0;
    char *save = NULL;
    for (char *ln = buf, *next; ln && st == THX_OK; ln = next) {
        line++;
        next = strchr(ln, '\n');
        if (next) *next++ = 0;
        char *hash = strchr(ln, '#');
        if (hash) *hash = 0;
        char *w[32];
        int nw = 0;
        for (char *tok = strtok_r(ln, " \t\r", &save); tok; tok = strtok_r(NULL, " \t\r", &save)) {
            if (nw == 32) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: more than 32 words", name, line);
                break;
            }
            w[nw++] = tok;
        }
        if (st != THX_OK || !nw) continue;
        if (!strcmp(w[0], "ends") || !strcmp(w[0], "look")) {
            int ends = !strcmp(w[0], "ends");
            if (out->n) st = thx_error(ctx, THX_EINPUT, "%s:%d: %s: settings come before the first key", name, line, w[0]);
            else if (nw != 2) st = thx_error(ctx, THX_EINPUT, "%s:%d: %s: one value", name, line, w[0]);
            else if (ends && !strcmp(w[1], "natural")) out->ends = THX_CAMERA_ENDS_NATURAL;
            else if (ends && !strcmp(w[1], "rest")) out->ends = THX_CAMERA_ENDS_REST;
            else if (ends && !strcmp(w[1], "closed")) out->ends = THX_CAMERA_ENDS_CLOSED;
            else if (!ends && !strcmp(w[1], "target")) out->look = THX_CAMERA_LOOK_TARGET;
            else if (!ends && !strcmp(w[1], "orientation")) out->look = THX_CAMERA_LOOK_ORIENTATION;
            else st = thx_error(ctx, THX_EINPUT, "%s:%d: %s '%s': %s", name, line, w[0], w[1],
                                ends ? "natural, rest or closed" : "target or orientation");
            continue;
        }
        thx_camera_key ky;
        memset(&ky, 0, sizeof ky);
        ky.line = line;
        if (whole(w[0], &ky.frame)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: frame '%s': a movie frame, a whole number >= 1 (or a setting: ends, look)",
                           name, line, w[0]);
            break;
        }
        if (out->n && ky.frame <= out->keys[out->n - 1].frame) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: frame %d: not after the previous key's frame %d (line %d)", name, line,
                           ky.frame, out->keys[out->n - 1].frame, out->keys[out->n - 1].line);
            break;
        }
        st = parse_key(ctx, name, line, w + 1, nw - 1, &ky);
        if (st != THX_OK) break;
        if (out->n == cap) {
            size_t nc = cap ? 2 * cap : 16;
            thx_camera_key *nk = realloc(out->keys, nc * sizeof *nk);
            if (!nk) {
                st = thx_error(ctx, THX_ENOMEM, "%s: out of memory", name);
                break;
            }
            out->keys = nk, cap = nc;
        }
        out->keys[out->n++] = ky;
    }
    free(buf);
    if (st == THX_OK && out->n < 2)
        st = thx_error(ctx, THX_EINPUT, "%s: %zu key%s: a camera flight needs at least 2 (lines FRAME eye X,Y,Z ...)", name,
                       out->n, out->n == 1 ? "" : "s");
    if (st != THX_OK) {
        char *p = out->path;
        out->path = NULL;
        thx_camera_keys_free(out);
        free(p);
    }
    return st;
}

thx_status thx_camera_keys_read(thx_ctx *ctx, const char *path, thx_camera_keys *out)
{
    memset(out, 0, sizeof *out);
    char *text = NULL;
    size_t len = 0;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    if (strlen(text) != len) {
        free(text);
        return thx_error(ctx, THX_EINPUT, "%s: a NUL byte: not a text key file", path);
    }
    thx_status st = thx_camera_keys_parse(ctx, path, text, out);
    free(text);
    return st;
}

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

thx_status thx_camera_keys_resolve(thx_ctx *ctx, thx_camera_keys *k, const thx_camera views[6])
{
    static const char *const vnames[] = {"anterior", "posterior", "left", "right", "superior", "inferior"};
    const char *name = k->path ? k->path : "camera keys";
    for (size_t j = 0; j < k->n; j++) {
        thx_camera_key *ky = &k->keys[j];
        const thx_camera *prev = j ? &k->keys[j - 1].cam : NULL, *vc = NULL;
        thx_camera *c = &ky->cam;
        if (ky->view >= 0) {
            if (!views)
                return thx_error(ctx, THX_EINPUT, "%s:%d: view %s: no model to place the named views on (give eye X,Y,Z)",
                                 name, ky->line, vnames[ky->view]);
            vc = &views[ky->view];
        }
        if (!(ky->given & THX_KEY_FOV)) {
            if (!prev)
                return thx_error(ctx, THX_EINPUT, "%s:%d: the first key gives no fov (fov DEG, or fov 0 and height MM for "
                                 "an orthographic view)", name, ky->line);
            c->fov_deg = prev->fov_deg;
        }
        if (!(ky->given & THX_KEY_TARGET)) {
            if (prev) memcpy(c->center, prev->center, sizeof c->center);
            else if (vc) memcpy(c->center, vc->center, sizeof c->center);
            else return thx_error(ctx, THX_EINPUT, "%s:%d: the first key gives no target X,Y,Z", name, ky->line);
        }
        if (!(ky->given & THX_KEY_UP)) {
            if (vc) memcpy(c->up, vc->up, sizeof c->up);
            else if (prev) memcpy(c->up, prev->up, sizeof c->up);
            else return thx_error(ctx, THX_EINPUT, "%s:%d: the first key gives no up X,Y,Z", name, ky->line);
        }
        if (!(ky->given & THX_KEY_HEIGHT)) {
            if (prev && prev->height > 0) c->height = prev->height;
            else if (vc) c->height = vc->height;
            else if (!(c->fov_deg > 0))
                return thx_error(ctx, THX_EINPUT, "%s:%d: fov 0 (orthographic) needs the view's height MM", name, ky->line);
        }
        if (vc) {
            double d = dist3(vc->eye, vc->center), dd = ky->given & THX_KEY_DISTANCE ? ky->distance : prev ? dist3(prev->eye, prev->center) : d;
            if (!(d > 0)) return thx_error(ctx, THX_EINTERNAL, "%s:%d: view %s: a degenerate standard view", name, ky->line, vnames[ky->view]);
            for (int e = 0; e < 3; e++) c->eye[e] = c->center[e] + dd * (vc->eye[e] - vc->center[e]) / d;
        }
        if (j && (c->fov_deg > 0) != (k->keys[0].cam.fov_deg > 0))
            return thx_error(ctx, THX_EINPUT, "%s:%d: fov %g: perspective and orthographic keys cannot be mixed (line %d has fov %g)",
                             name, ky->line, c->fov_deg, k->keys[0].line, k->keys[0].cam.fov_deg);
        double q[4];
        if (!(dist3(c->eye, c->center) > 0))
            return thx_error(ctx, THX_EINPUT, "%s:%d: the eye %g,%g,%g is on the target", name, ky->line, c->eye[0], c->eye[1], c->eye[2]);
        if (thx_camera_quaternion(c, q))
            return thx_error(ctx, THX_EINPUT, "%s:%d: up %g,%g,%g is along the view direction (eye %g,%g,%g to target %g,%g,%g)",
                             name, ky->line, c->up[0], c->up[1], c->up[2], c->eye[0], c->eye[1], c->eye[2], c->center[0],
                             c->center[1], c->center[2]);
    }
    return THX_OK;
}
