/*
 * The edit operations (thorax/edit/edit.h): each applies one edit to the model (and, for a layer
 * edit, to the contours, then laces the surface again) and keeps what it replaced, so that undo
 * puts the model back byte for byte. No edit changes anything until everything it needs (memory,
 * the new surface) is in hand: a failed edit leaves the state as it was.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "edit/edit_impl.h"
#include "thorax/model/volume.h"

static const char *const KIND_NAMES[THX_EDIT_KIND_COUNT] = {
    "node_move", "tri_delete", "tri_add", "tri_flip", "layer_move", "layer_rotate", "layer_smooth"};

const char *thx_edit_kind_name(thx_edit_kind k)
{
    return k >= 0 && k < THX_EDIT_KIND_COUNT ? KIND_NAMES[k] : "?";
}

int thx_edit_kind_parse(const char *word, thx_edit_kind *out)
{
    for (int k = 0; k < THX_EDIT_KIND_COUNT; k++)
        if (strcmp(word, KIND_NAMES[k]) == 0) {
            *out = (thx_edit_kind)k;
            return 0;
        }
    return -1;
}

int thx_edit_kind_is_layer(thx_edit_kind k)
{
    return k == THX_EDIT_LAYER_MOVE || k == THX_EDIT_LAYER_ROTATE || k == THX_EDIT_LAYER_SMOOTH;
}

/* ---- constructors ------------------------------------------------------------------------------ */

static thx_edit edit_new(thx_edit_kind kind, const char *surface)
{
    thx_edit e;
    memset(&e, 0, sizeof e);
    e.kind = kind;
    snprintf(e.surface, sizeof e.surface, "%s", surface ? surface : "");
    return e;
}

thx_edit thx_edit_node_move(const char *surface, size_t node, thx_vec3 to)
{
    thx_edit e = edit_new(THX_EDIT_NODE_MOVE, surface);
    e.node = node;
    e.v[0] = to.x;
    e.v[1] = to.y;
    e.v[2] = to.z;
    return e;
}

thx_edit thx_edit_tri_delete(const char *surface, size_t tri)
{
    thx_edit e = edit_new(THX_EDIT_TRI_DELETE, surface);
    e.tri = tri;
    return e;
}

thx_edit thx_edit_tri_add(const char *surface, size_t a, size_t b, size_t c)
{
    thx_edit e = edit_new(THX_EDIT_TRI_ADD, surface);
    e.nodes[0] = a;
    e.nodes[1] = b;
    e.nodes[2] = c;
    return e;
}

thx_edit thx_edit_tri_flip(const char *surface, size_t tri)
{
    thx_edit e = edit_new(THX_EDIT_TRI_FLIP, surface);
    e.tri = tri;
    return e;
}

thx_edit thx_edit_layer_move(const char *surface, thx_edit_layer layer, double dx, double dy)
{
    thx_edit e = edit_new(THX_EDIT_LAYER_MOVE, surface);
    e.layer = layer;
    e.v[0] = dx;
    e.v[1] = dy;
    return e;
}

thx_edit thx_edit_layer_rotate(const char *surface, thx_edit_layer layer, double degrees)
{
    thx_edit e = edit_new(THX_EDIT_LAYER_ROTATE, surface);
    e.layer = layer;
    e.v[0] = degrees;
    return e;
}

thx_edit thx_edit_layer_smooth(const char *surface, thx_edit_layer layer, double bandwidth_mm)
{
    thx_edit e = edit_new(THX_EDIT_LAYER_SMOOTH, surface);
    e.layer = layer;
    e.v[0] = bandwidth_mm;
    return e;
}

thx_edit_layer thx_edit_layer_z(double z)
{
    thx_edit_layer l = {0, 0, z};
    return l;
}

thx_edit_layer thx_edit_layer_index(size_t index)
{
    thx_edit_layer l = {1, index, 0};
    return l;
}

/* ---- the log line of an edit ------------------------------------------------------------------- */

void edit_fmt_double(char *buf, size_t cap, double v)
{
    /* plain decimals where they are short (120, 0.25, -3.125), else the shortest %g (1e-05) */
    if (v == 0 || (fabs(v) >= 1e-4 && fabs(v) < 1e15))
        for (int d = 0; d <= 17; d++) {
            snprintf(buf, cap, "%.*f", d, v);
            if (strtod(buf, NULL) == v && strlen(buf) <= 24) return;
        }
    for (int p = 1; p <= 17; p++) {
        snprintf(buf, cap, "%.*g", p, v);
        if (strtod(buf, NULL) == v) return;
    }
    snprintf(buf, cap, "%.17g", v);
}

int thx_edit_format(const thx_edit *e, char *buf, size_t cap)
{
    char a[40], b[40], c[40], lay[48];
    const char *w = thx_edit_kind_name(e->kind);
    if (thx_edit_kind_is_layer(e->kind)) {
        if (e->layer.by_index) snprintf(lay, sizeof lay, "layer=%zu", e->layer.index + 1);
        else {
            edit_fmt_double(a, sizeof a, e->layer.z);
            snprintf(lay, sizeof lay, "z=%s", a);
        }
    }
    switch (e->kind) {
    case THX_EDIT_NODE_MOVE:
        edit_fmt_double(a, sizeof a, e->v[0]);
        edit_fmt_double(b, sizeof b, e->v[1]);
        edit_fmt_double(c, sizeof c, e->v[2]);
        return snprintf(buf, cap, "%s %s %zu %s %s %s", w, e->surface, e->node + 1, a, b, c);
    case THX_EDIT_TRI_DELETE:
    case THX_EDIT_TRI_FLIP:
        return snprintf(buf, cap, "%s %s %zu", w, e->surface, e->tri + 1);
    case THX_EDIT_TRI_ADD:
        return snprintf(buf, cap, "%s %s %zu %zu %zu", w, e->surface, e->nodes[0] + 1, e->nodes[1] + 1,
                        e->nodes[2] + 1);
    case THX_EDIT_LAYER_MOVE:
        edit_fmt_double(a, sizeof a, e->v[0]);
        edit_fmt_double(b, sizeof b, e->v[1]);
        return snprintf(buf, cap, "%s %s %s %s %s", w, e->surface, lay, a, b);
    case THX_EDIT_LAYER_ROTATE:
    case THX_EDIT_LAYER_SMOOTH:
        edit_fmt_double(a, sizeof a, e->v[0]);
        return snprintf(buf, cap, "%s %s %s %s", w, e->surface, lay, a);
    default:
        return snprintf(buf, cap, "? %s", e->surface);
    }
}

/* ---- lookups ----------------------------------------------------------------------------------- */

long edit_find_surface(const thx_model *m, const char *name)
{
    for (size_t k = 0; k < m->n_surfaces; k++)
        if (strcmp(m->surf[k]->name, name) == 0) return (long)k;
    return -1;
}

thx_status edit_layer_locate(thx_ctx *ctx, const thx_contours *c, const thx_edit *e, size_t *cs, size_t *layer)
{
    if (!c)
        return thx_error(ctx, THX_EINPUT,
                         "no contours: a layer edit changes the contours the model was built from and laces the "
                         "surface again, and this session has none");
    int k = thx_contours_find_surface(c, e->surface);
    if (k < 0) return thx_error(ctx, THX_EINPUT, "the contours have no surface \"%s\"", e->surface);
    const thx_contour_surface *S = &c->surf[k];
    if (e->layer.by_index) {
        if (e->layer.index >= S->n_layers)
            return thx_error(ctx, THX_EINPUT, "layer %zu out of range 1..%zu (surface \"%s\" has %zu layers)",
                             e->layer.index + 1, S->n_layers, S->name, S->n_layers);
        *cs = (size_t)k;
        *layer = e->layer.index;
        return THX_OK;
    }
    if (!isfinite(e->layer.z)) return thx_error(ctx, THX_EINPUT, "layer z is not finite");
    for (size_t l = 0; l < S->n_layers; l++)
        if (fabs(S->layers[l].z - e->layer.z) <= THX_EDIT_Z_TOL) {
            *cs = (size_t)k;
            *layer = l;
            return THX_OK;
        }
    char z[40];
    edit_fmt_double(z, sizeof z, e->layer.z);
    return thx_error(ctx, THX_EINPUT, "surface \"%s\" has no layer at z=%s (its layers run from z=%g to z=%g)", S->name,
                     z, S->layers[0].z, S->layers[S->n_layers - 1].z);
}

/* ---- the contours of a layer ------------------------------------------------------------------- */

void edit_loops_free(thx_loop *loops, size_t n)
{
    for (size_t i = 0; loops && i < n; i++) {
        free(loops[i].p);
        free(loops[i].lines);
    }
    free(loops);
}

void edit_loops_swap(thx_contours *c, size_t cs, size_t layer, thx_loop **loops, size_t *n)
{
    thx_contour_layer *L = &c->surf[cs].layers[layer];
    thx_loop *tl = L->loops;
    size_t tn = L->n_loops;
    L->loops = *loops;
    L->n_loops = *n;
    *loops = tl;
    *n = tn;
}

/* A deep copy of n loops. */
static thx_status loops_copy(thx_ctx *ctx, const thx_loop *src, size_t n, thx_loop **out)
{
    thx_loop *d = thx_calloc(ctx, n ? n : 1, sizeof *d);
    if (!d) return THX_ENOMEM;
    for (size_t i = 0; i < n; i++) {
        d[i].n = src[i].n;
        d[i].line = src[i].line;
        d[i].p = thx_malloc(ctx, (src[i].n ? src[i].n : 1) * sizeof *d[i].p);
        if (!d[i].p) goto nomem;
        memcpy(d[i].p, src[i].p, src[i].n * sizeof *d[i].p);
        if (src[i].lines) {
            d[i].lines = thx_malloc(ctx, (src[i].n ? src[i].n : 1) * sizeof *d[i].lines);
            if (!d[i].lines) goto nomem;
            memcpy(d[i].lines, src[i].lines, src[i].n * sizeof *d[i].lines);
        }
    }
    *out = d;
    return THX_OK;
nomem:
    edit_loops_free(d, n);
    return THX_ENOMEM;
}

/* The area centroid of a layer's loops (each loop weighted by its area, whatever its direction);
 * the mean of the points if the loops enclose no area. */
static thx_vec2 layer_centroid(const thx_contour_layer *L)
{
    double A = 0, cx = 0, cy = 0, mx = 0, my = 0;
    size_t np = 0;
    for (size_t i = 0; i < L->n_loops; i++) {
        const thx_loop *lp = &L->loops[i];
        double a = 0, sx = 0, sy = 0;
        /* about the loop's first point: less cancellation far from the origin */
        double ox = lp->p[0].x, oy = lp->p[0].y;
        for (size_t j = 0; j < lp->n; j++) {
            const thx_vec2 p = lp->p[j], q = lp->p[(j + 1) % lp->n];
            double px = p.x - ox, py = p.y - oy, qx = q.x - ox, qy = q.y - oy;
            double cr = px * qy - qx * py;
            a += cr;
            sx += (px + qx) * cr;
            sy += (py + qy) * cr;
            mx += p.x;
            my += p.y;
            np++;
        }
        if (a != 0) {
            double w = fabs(a / 2);
            cx += w * (ox + sx / (3 * a));
            cy += w * (oy + sy / (3 * a));
            A += w;
        }
    }
    thx_vec2 c;
    if (A > 0) {
        c.x = cx / A;
        c.y = cy / A;
    } else {
        c.x = np ? mx / (double)np : 0;
        c.y = np ? my / (double)np : 0;
    }
    return c;
}

thx_status edit_layer_transform(thx_ctx *ctx, thx_contours *c, size_t cs, size_t layer, const thx_edit *e,
                                thx_loop **old, size_t *n_old)
{
    thx_contour_layer *L = &c->surf[cs].layers[layer];
    for (int k = 0; k < 2; k++)
        if (!isfinite(e->v[k])) return thx_error(ctx, THX_EINPUT, "a value is not finite");
    if (e->kind == THX_EDIT_LAYER_SMOOTH && !(e->v[0] > 0))
        return thx_error(ctx, THX_EINPUT, "the smoothing bandwidth must be > 0 mm");
    thx_loop *work = NULL;
    THX_CHECK(loops_copy(ctx, L->loops, L->n_loops, &work));
    size_t n = L->n_loops;
    if (e->kind == THX_EDIT_LAYER_MOVE) {
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; j < work[i].n; j++) {
                work[i].p[j].x += e->v[0];
                work[i].p[j].y += e->v[1];
            }
    } else if (e->kind == THX_EDIT_LAYER_ROTATE) {
        thx_vec2 o = layer_centroid(L);
        double t = e->v[0] * (M_PI / 180.0), ct = cos(t), st = sin(t);
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; j < work[i].n; j++) {
                double x = work[i].p[j].x - o.x, y = work[i].p[j].y - o.y;
                work[i].p[j].x = o.x + (ct * x - st * y);
                work[i].p[j].y = o.y + (st * x + ct * y);
            }
    } else if (e->kind == THX_EDIT_LAYER_SMOOTH) {
        /* each loop refitted by the smoothing spline at its own point density (its perimeter over
           its number of points), starting nearest its first point */
        for (size_t i = 0; i < n; i++) {
            thx_loop *lp = &work[i];
            double per = 0;
            for (size_t j = 0; j < lp->n; j++) {
                thx_vec2 p = lp->p[j], q = lp->p[(j + 1) % lp->n];
                per += hypot(q.x - p.x, q.y - p.y);
            }
            thx_vec2 *np = NULL;
            size_t nn = 0;
            thx_status st = thx_loop_resample(ctx, lp->p, lp->n, per / (double)lp->n, e->v[0], lp->p[0], &np, &nn);
            if (st != THX_OK) {
                edit_loops_free(work, n);
                return st;
            }
            free(lp->p);
            free(lp->lines); /* the points are no longer the file's */
            lp->lines = NULL;
            lp->p = np;
            lp->n = nn;
        }
    } else {
        edit_loops_free(work, n);
        return thx_error(ctx, THX_EINTERNAL, "edit_layer_transform: not a layer edit");
    }
    *old = work;
    *n_old = n;
    edit_loops_swap(c, cs, layer, old, n_old); /* the layer now holds work; *old what it held */
    return THX_OK;
}

/* ---- mesh edits -------------------------------------------------------------------------------- */

static thx_status node_move(thx_ctx *ctx, thx_surface *s, const thx_edit *e, edit_undo *u)
{
    if (e->node >= s->n_nodes)
        return thx_error(ctx, THX_EINPUT, "node %zu out of range 1..%zu (surface \"%s\" has %zu nodes)", e->node + 1,
                         s->n_nodes, s->name, s->n_nodes);
    if (!isfinite(e->v[0]) || !isfinite(e->v[1]) || !isfinite(e->v[2]))
        return thx_error(ctx, THX_EINPUT, "coordinates are not finite");
    double *p = &s->xyz[3 * e->node];
    memcpy(u->old_xyz, p, sizeof u->old_xyz);
    p[0] = e->v[0];
    p[1] = e->v[1];
    p[2] = e->v[2];
    return THX_OK;
}

static thx_status tri_index_ok(thx_ctx *ctx, const thx_surface *s, size_t t)
{
    if (t >= s->n_tris)
        return thx_error(ctx, THX_EINPUT, "triangle %zu out of range 1..%zu (surface \"%s\" has %zu triangles)", t + 1,
                         s->n_tris, s->name, s->n_tris);
    return THX_OK;
}

static thx_status tri_delete(thx_ctx *ctx, thx_surface *s, const thx_edit *e, edit_undo *u, thx_edit_result *res)
{
    THX_CHECK(tri_index_ok(ctx, s, e->tri));
    int32_t *t = &s->tri[3 * e->tri];
    memcpy(u->old_tri, t, sizeof u->old_tri);
    memmove(t, t + 3, (s->n_tris - e->tri - 1) * 3 * sizeof *t);
    s->n_tris--;
    res->tri = e->tri;
    memcpy(res->tri_nodes, u->old_tri, sizeof res->tri_nodes);
    snprintf(res->note, sizeof res->note, "removed triangle %zu (%d %d %d); triangles after it moved down by one",
             e->tri + 1, u->old_tri[0] + 1, u->old_tri[1] + 1, u->old_tri[2] + 1);
    return THX_OK;
}

static thx_status tri_flip(thx_ctx *ctx, thx_surface *s, const thx_edit *e, thx_edit_result *res)
{
    THX_CHECK(tri_index_ok(ctx, s, e->tri));
    int32_t *t = &s->tri[3 * e->tri];
    int32_t x = t[1];
    t[1] = t[2];
    t[2] = x;
    res->tri = e->tri;
    memcpy(res->tri_nodes, t, sizeof res->tri_nodes);
    return THX_OK;
}

/* tri_add: the nodes distinct and in range, no triangle on the same three nodes; the order is the
 * one most of the triangles sharing an edge with it agree with (they must traverse a shared edge
 * the other way), the order given when none shares an edge or the votes tie. */
static thx_status tri_add(thx_ctx *ctx, thx_surface *s, const thx_edit *e, thx_edit_result *res)
{
    const size_t *n = e->nodes;
    for (int k = 0; k < 3; k++)
        if (n[k] >= s->n_nodes)
            return thx_error(ctx, THX_EINPUT, "node %zu out of range 1..%zu (surface \"%s\" has %zu nodes)", n[k] + 1,
                             s->n_nodes, s->name, s->n_nodes);
    if (n[0] == n[1] || n[1] == n[2] || n[0] == n[2])
        return thx_error(ctx, THX_EINPUT, "a triangle needs three different nodes (%zu %zu %zu)", n[0] + 1, n[1] + 1,
                         n[2] + 1);
    if (s->n_tris >= (size_t)INT32_MAX) return thx_error(ctx, THX_EINPUT, "surface \"%s\" has too many triangles", s->name);
    int32_t a = (int32_t)n[0], b = (int32_t)n[1], c = (int32_t)n[2];
    int keep = 0, flip = 0;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *q = &s->tri[3 * t];
        int same = 0;
        for (int i = 0; i < 3; i++) same += q[i] == a || q[i] == b || q[i] == c;
        if (same == 3 && q[0] != q[1] && q[1] != q[2] && q[0] != q[2])
            return thx_error(ctx, THX_EINPUT, "triangle %zu (%d %d %d) is already on these nodes", t + 1, q[0] + 1,
                             q[1] + 1, q[2] + 1);
        if (same < 2) continue;
        for (int i = 0; i < 3; i++) {
            int32_t u = q[i], v = q[(i + 1) % 3];
            /* directed edge u->v of t against the new triangle's a->b, b->c, c->a */
            if ((u == a && v == b) || (u == b && v == c) || (u == c && v == a)) flip++;
            else if ((u == b && v == a) || (u == c && v == b) || (u == a && v == c)) keep++;
        }
    }
    int32_t *nt = thx_realloc(ctx, s->tri, (s->n_tris + 1) * 3 * sizeof *nt);
    if (!nt) return THX_ENOMEM;
    s->tri = nt;
    int32_t *t = &s->tri[3 * s->n_tris];
    t[0] = a;
    t[1] = flip > keep ? c : b;
    t[2] = flip > keep ? b : c;
    res->tri = s->n_tris;
    memcpy(res->tri_nodes, t, sizeof res->tri_nodes);
    res->neighbours_agree = flip > keep ? flip : keep;
    res->neighbours_disagree = flip > keep ? keep : flip;
    s->n_tris++;
    if (!keep && !flip)
        snprintf(res->note, sizeof res->note, "triangle %zu added as given (it shares no edge with a triangle)",
                 res->tri + 1);
    else
        snprintf(res->note, sizeof res->note, "triangle %zu added as %d %d %d (%s, by %d shared edge%s%s)",
                 res->tri + 1, t[0] + 1, t[1] + 1, t[2] + 1, flip > keep ? "order reversed" : "order as given",
                 res->neighbours_agree, res->neighbours_agree == 1 ? "" : "s",
                 res->neighbours_disagree ? "; outvoting a neighbour of the other orientation" : "");
    return THX_OK;
}

/* ---- layer edits ------------------------------------------------------------------------------- */

static thx_status layer_edit(thx_ctx *ctx, thx_model *m, thx_contours *c, const thx_edit_recipe *r, const thx_edit *e,
                             edit_undo *u, thx_edit_result *res)
{
    size_t cs, layer;
    THX_CHECK(edit_layer_locate(ctx, c, e, &cs, &layer));
    if (!r) return thx_error(ctx, THX_EINPUT, "no recipe: the options the surfaces were built with are unknown");
    thx_loop *old = NULL;
    size_t n_old = 0;
    THX_CHECK(edit_layer_transform(ctx, c, cs, layer, e, &old, &n_old));
    thx_surface *ns = NULL;
    thx_vec3 interior;
    thx_status st = thx_surface_build(ctx, c, cs, &r->surfaces, &ns, &interior, NULL);
    if (st != THX_OK) {
        edit_loops_swap(c, cs, layer, &old, &n_old); /* the contours as they were */
        edit_loops_free(old, n_old);
        return st;
    }
    u->old_surface = m->surf[u->surf];
    u->old_has_interior = m->has_interior[u->surf];
    u->old_interior = m->interior[u->surf];
    u->cs = cs;
    u->layer = layer;
    u->old_loops = old;
    u->old_n_loops = n_old;
    ns->role = u->old_surface->role; /* the model's role stands (a model may say more than the contours) */
    m->surf[u->surf] = ns;
    m->has_interior[u->surf] = 1;
    m->interior[u->surf] = interior;
    res->relaced = 1;
    const thx_contour_surface *S = &c->surf[cs];
    snprintf(res->note, sizeof res->note, "layer %zu of %zu (z=%g) %s; \"%s\" laced again: %zu nodes, %zu triangles",
             layer + 1, S->n_layers, S->layers[layer].z,
             e->kind == THX_EDIT_LAYER_MOVE ? "moved" : e->kind == THX_EDIT_LAYER_ROTATE ? "rotated" : "smoothed",
             ns->name, ns->n_nodes, ns->n_tris);
    return THX_OK;
}

thx_status edit_op_apply(thx_ctx *ctx, thx_model *m, thx_contours *c, const thx_edit_recipe *recipe,
                         const thx_edit *e, edit_undo *u, thx_edit_result *res)
{
    memset(u, 0, sizeof *u);
    u->e = *e;
    if (e->kind < 0 || e->kind >= THX_EDIT_KIND_COUNT) return thx_error(ctx, THX_EINPUT, "unknown edit kind %d", (int)e->kind);
    long k = edit_find_surface(m, e->surface);
    if (k < 0) return thx_error(ctx, THX_EINPUT, "the model has no surface \"%s\"", e->surface);
    u->surf = (size_t)k;
    res->kind = e->kind;
    res->surface = (size_t)k;
    thx_surface *s = m->surf[k];
    switch (e->kind) {
    case THX_EDIT_NODE_MOVE: return node_move(ctx, s, e, u);
    case THX_EDIT_TRI_DELETE: return tri_delete(ctx, s, e, u, res);
    case THX_EDIT_TRI_ADD: return tri_add(ctx, s, e, res);
    case THX_EDIT_TRI_FLIP: return tri_flip(ctx, s, e, res);
    default: return layer_edit(ctx, m, c, recipe, e, u, res);
    }
}

void edit_op_undo(thx_model *m, thx_contours *c, edit_undo *u)
{
    thx_surface *s = m->surf[u->surf];
    const thx_edit *e = &u->e;
    switch (e->kind) {
    case THX_EDIT_NODE_MOVE: memcpy(&s->xyz[3 * e->node], u->old_xyz, sizeof u->old_xyz); break;
    case THX_EDIT_TRI_DELETE: {
        /* the array still has room: deleting never shrinks it */
        int32_t *t = &s->tri[3 * e->tri];
        memmove(t + 3, t, (s->n_tris - e->tri) * 3 * sizeof *t);
        memcpy(t, u->old_tri, sizeof u->old_tri);
        s->n_tris++;
        break;
    }
    case THX_EDIT_TRI_ADD: s->n_tris--; break;
    case THX_EDIT_TRI_FLIP: {
        int32_t *t = &s->tri[3 * e->tri];
        int32_t x = t[1];
        t[1] = t[2];
        t[2] = x;
        break;
    }
    default:
        thx_surface_destroy(&m->surf[u->surf]);
        m->surf[u->surf] = u->old_surface;
        u->old_surface = NULL;
        m->has_interior[u->surf] = u->old_has_interior;
        m->interior[u->surf] = u->old_interior;
        edit_loops_swap(c, u->cs, u->layer, &u->old_loops, &u->old_n_loops);
        break;
    }
    edit_undo_clear(u);
}

void edit_undo_clear(edit_undo *u)
{
    thx_surface_destroy(&u->old_surface);
    edit_loops_free(u->old_loops, u->old_n_loops);
    u->old_loops = NULL;
    u->old_n_loops = 0;
}
