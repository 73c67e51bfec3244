/*
 * Landmark sets (thorax/model/landmarks.h): the types, create/destroy, and their invariants.
 *
 *  - The type names are map3d's (its writer's "Artery", "PaceNeedle", ... in lower case); the
 *    aliases are words the real files and map3d's reader use ("coronary" in both files we have,
 *    "stitch" map3d's own name for a closure, "catheter"). map3d matches a prefix of the
 *    upper-cased word ("OCC" is an occlusion, "STI" a stimulus); thorax takes whole words only,
 *    each of which map3d reads as the same type, so a file thorax accepts means the same to both.
 */
#include "thorax/model/landmarks.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ------------------------------------------------------------ types */

static const char *const type_name[THX_LANDMARK_TYPE_COUNT] = {
    "artery", "occlusion", "closure", "stimulus", "lead", "plane",
    "rod", "paceneedle", "cath", "fiber", "recneedle", "cannula",
};

static const struct {
    const char *name;
    thx_landmark_type t;
} aliases[] = {{"coronary", THX_LANDMARK_ARTERY}, {"stitch", THX_LANDMARK_CLOSURE}, {"catheter", THX_LANDMARK_CATH}};

const char *thx_landmark_type_name(thx_landmark_type t)
{
    return (unsigned)t < THX_LANDMARK_TYPE_COUNT ? type_name[t] : "?";
}

int thx_landmark_type_parse(const char *s, thx_landmark_type *out)
{
    for (int i = 0; i < THX_LANDMARK_TYPE_COUNT; i++)
        if (!strcasecmp(s, type_name[i])) {
            *out = (thx_landmark_type)i;
            return 0;
        }
    for (size_t i = 0; i < sizeof aliases / sizeof aliases[0]; i++)
        if (!strcasecmp(s, aliases[i].name)) {
            *out = aliases[i].t;
            return 0;
        }
    return -1;
}

const char *thx_landmark_type_names(void)
{
    return "artery (or coronary), occlusion, closure (or stitch), stimulus, lead, plane, rod, paceneedle, "
           "cath (or catheter), fiber, recneedle, cannula";
}

thx_landmark_shape thx_landmark_type_shape(thx_landmark_type t)
{
    switch (t) {
    case THX_LANDMARK_ARTERY:
    case THX_LANDMARK_CATH:
    case THX_LANDMARK_CANNULA: return THX_LANDMARK_SHAPE_TUBE;
    case THX_LANDMARK_PLANE: return THX_LANDMARK_SHAPE_DISC;
    case THX_LANDMARK_ROD: return THX_LANDMARK_SHAPE_ROD;
    case THX_LANDMARK_FIBER: return THX_LANDMARK_SHAPE_ARROW;
    default: return THX_LANDMARK_SHAPE_SPHERES;
    }
}

size_t thx_landmark_type_min_points(thx_landmark_type t)
{
    switch (thx_landmark_type_shape(t)) {
    case THX_LANDMARK_SHAPE_SPHERES: return 1;
    case THX_LANDMARK_SHAPE_DISC: return 3;
    default: return 2;
    }
}

/* ------------------------------------------------------------ the object */

thx_status thx_landmarks_create(thx_ctx *ctx, thx_landmarks **out)
{
    *out = thx_calloc(ctx, 1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

void thx_landmarks_destroy(thx_landmarks **lm)
{
    if (!lm || !*lm) return;
    for (size_t k = 0; k < (*lm)->n; k++) free((*lm)->seg[k].pt);
    free((*lm)->seg);
    free(*lm);
    *lm = NULL;
}

thx_status thx_landmarks_add_segment(thx_ctx *ctx, thx_landmarks *lm, thx_landmark_type t,
                                     const thx_landmark_point *pts, size_t n, thx_landmark_segment **out)
{
    if (out) *out = NULL;
    if (n == 0) return thx_error(ctx, THX_EINPUT, "landmarks: a segment needs at least one point");
    if (n > SIZE_MAX / sizeof(thx_landmark_point))
        return thx_error(ctx, THX_EINPUT, "landmarks: %zu points are too many", n);
    thx_landmark_point *p = thx_calloc(ctx, n, sizeof *p);
    if (!p) return THX_ENOMEM;
    if (pts) memcpy(p, pts, n * sizeof *p);
    /* grow by one each time: a set holds tens of segments; realloc amortizes well enough */
    thx_landmark_segment *s = thx_realloc(ctx, lm->seg, (lm->n + 1) * sizeof *s);
    if (!s) {
        free(p);
        return THX_ENOMEM;
    }
    lm->seg = s;
    thx_landmark_segment *g = &lm->seg[lm->n++];
    memset(g, 0, sizeof *g);
    g->type = t;
    g->n = n;
    g->pt = p;
    if (out) *out = g;
    return THX_OK;
}

/* ------------------------------------------------------------ validation */

int thx_landmark_points_coincide(const double a[3], const double b[3])
{
    double m = 0, d = 0;
    for (int k = 0; k < 3; k++) {
        m = fmax(m, fmax(fabs(a[k]), fabs(b[k])));
        d = fmax(d, fabs(a[k] - b[k]));
    }
    return d <= 1e-9 * (1.0 + m);
}

const char *thx_landmark_label_why(const char *s)
{
    size_t n = strnlen(s, THX_LANDMARK_LABEL_MAX + 1);
    if (n > THX_LANDMARK_LABEL_MAX) return "is longer than 39 characters (map3d reads 39)";
    for (const char *c = s; *c; c++) {
        if (*c == '#') return "holds '#' (a comment in the file)";
        if (*c <= ' ' || *c > '~') return "holds a blank or a character outside printable ASCII";
    }
    return NULL;
}

/* Message prefix for segment k: `where` when given, else "path:line: " when known. */
static void seg_prefix(char *buf, size_t cap, const char *where, const char *path, int line)
{
    if (where && where[0]) snprintf(buf, cap, "%s", where);
    else if (path && path[0] && line > 0) snprintf(buf, cap, "%s:%d: ", path, line);
    else buf[0] = '\0';
}

static thx_status segment_check(thx_ctx *ctx, const thx_landmark_segment *s, size_t k, const char *pre)
{
    if ((unsigned)s->type >= THX_LANDMARK_TYPE_COUNT)
        return thx_error(ctx, THX_EINPUT, "%ssegment %zu: type %d is not a landmark type (%s)", pre, k + 1,
                         (int)s->type, thx_landmark_type_names());
    const char *tn = thx_landmark_type_name(s->type);
    thx_landmark_shape shape = thx_landmark_type_shape(s->type);
    size_t need = thx_landmark_type_min_points(s->type);
    if (s->n < need || !s->pt)
        return thx_error(ctx, THX_EINPUT, "%ssegment %zu (%s): %zu point%s; a%s %s needs %s%zu", pre, k + 1, tn, s->n,
                         s->n == 1 ? "" : "s", tn[0] == 'a' || tn[0] == 'o' ? "n" : "", tn,
                         shape == THX_LANDMARK_SHAPE_DISC ? "exactly " : "at least ", need);
    if (shape == THX_LANDMARK_SHAPE_DISC && s->n != 3)
        return thx_error(ctx, THX_EINPUT, "%ssegment %zu (plane): %zu points; a plane needs exactly 3", pre, k + 1,
                         s->n);
    if (s->has_index && s->index < 0)
        return thx_error(ctx, THX_EINPUT, "%ssegment %zu (%s): index %ld is negative", pre, k + 1, tn, s->index);
    for (size_t i = 0; i < s->n; i++) {
        const thx_landmark_point *p = &s->pt[i];
        for (int c = 0; c < 3; c++)
            if (!isfinite(p->xyz[c]) || fabs(p->xyz[c]) > THX_LANDMARK_MAX_COORD)
                return thx_error(ctx, THX_EINPUT, "%ssegment %zu point %zu: %c = %g is not a finite number within "
                                 "+-%g mm", pre, k + 1, i + 1, "xyz"[c], p->xyz[c], THX_LANDMARK_MAX_COORD);
        if (!isfinite(p->radius) || p->radius < 0 || p->radius > THX_LANDMARK_MAX_COORD)
            return thx_error(ctx, THX_EINPUT, "%ssegment %zu point %zu: radius %g is not a finite number in "
                             "0..%g mm", pre, k + 1, i + 1, p->radius, THX_LANDMARK_MAX_COORD);
        if (!memchr(p->label, '\0', sizeof p->label))
            return thx_error(ctx, THX_EINPUT, "%ssegment %zu point %zu: label is not terminated", pre, k + 1, i + 1);
        const char *why = thx_landmark_label_why(p->label);
        if (why)
            return thx_error(ctx, THX_EINPUT, "%ssegment %zu point %zu: label \"%s\" %s", pre, k + 1, i + 1,
                             p->label, why);
    }
    if (shape == THX_LANDMARK_SHAPE_TUBE || shape == THX_LANDMARK_SHAPE_ROD || shape == THX_LANDMARK_SHAPE_ARROW) {
        size_t i = 1;
        while (i < s->n && thx_landmark_points_coincide(s->pt[0].xyz, s->pt[i].xyz)) i++;
        if (i == s->n)
            return thx_error(ctx, THX_EINPUT, "%ssegment %zu (%s): all %zu points are at one place (%g, %g, %g); a%s %s "
                             "needs a length", pre, k + 1, tn, s->n, s->pt[0].xyz[0], s->pt[0].xyz[1], s->pt[0].xyz[2],
                             tn[0] == 'a' ? "n" : "", tn);
    }
    if (shape == THX_LANDMARK_SHAPE_DISC) {
        const double *a = s->pt[0].xyz, *b = s->pt[1].xyz, *c = s->pt[2].xyz;
        double u[3], v[3];
        for (int d = 0; d < 3; d++) u[d] = b[d] - a[d], v[d] = c[d] - a[d];
        double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), nv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        double nw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        /* sine of the angle at point 1 below 1e-9, or a side of no length: no plane */
        if (thx_landmark_points_coincide(a, b) || thx_landmark_points_coincide(a, c) ||
            thx_landmark_points_coincide(b, c) || !(nw > 1e-9 * nu * nv))
            return thx_error(ctx, THX_EINPUT, "%ssegment %zu (plane): the 3 points are collinear or coincide; they "
                             "must span the plane", pre, k + 1);
    }
    return THX_OK;
}

thx_status thx_landmark_segment_validate(thx_ctx *ctx, const thx_landmark_segment *s, size_t k, const char *where)
{
    return segment_check(ctx, s, k, where ? where : "");
}

thx_status thx_landmarks_validate(thx_ctx *ctx, const thx_landmarks *lm, const char *where)
{
    if (!lm) return thx_error(ctx, THX_EINPUT, "%slandmarks: no set", where ? where : "");
    if (lm->n && !lm->seg) return thx_error(ctx, THX_EINPUT, "%slandmarks: %zu segments and no array", where ? where : "", lm->n);
    for (size_t k = 0; k < lm->n; k++) {
        char pre[700];
        seg_prefix(pre, sizeof pre, where, lm->path, lm->seg[k].line);
        THX_CHECK(segment_check(ctx, &lm->seg[k], k, pre));
    }
    return THX_OK;
}
