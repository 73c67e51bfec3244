/*
 * Triangle meshes of landmarks (thorax/geom/landmark_mesh.h states the shapes).
 *
 * Everything but the spheres is built by one routine, `tube`, from a list of stations (a centre
 * and a radius each):
 *  - consecutive stations are at distinct places, or at one place with different radii (a flat
 *    step: the arrow's head, a repeated point with a new radius); interior radii are > 0, an end
 *    radius may be 0 (the tube closes to that point);
 *  - each station gets a unit tangent t (at an end the direction of its piece; inside, the
 *    bisector of the incoming and outgoing directions) and a frame (u, v = t x u) carried from
 *    the previous station by the rotation taking the previous tangent to this one (parallel
 *    transport: the rings do not twist about the axis);
 *  - ring vertex j of a station is c + R (cos(2 pi j/n) u + sin(2 pi j/n) v), stretched along the
 *    bend direction by 1/cos(half the bend angle) (a mitre: the ring is where both pieces'
 *    cylinders cut the bisecting plane; the stretch is capped at 3, i.e. bends above ~141 degrees
 *    are not fully stretched), with R = r sqrt(2 pi / (n sin(2 pi / n))) so that the polygon's
 *    area is pi r^2;
 *  - side triangles (a_j, a_j+1, b_j+1), (a_j, b_j+1, b_j) between consecutive rings a and b face
 *    out (their normal at j = 0 is (v x t) = u, outward); a cap fan at the start (C, a_j+1, a_j)
 *    faces -t, at the end (C, a_j, a_j+1) faces +t; an end of radius 0 is one vertex, and the
 *    side triangles that would repeat it are dropped.
 * So every edge is shared by exactly two triangles in opposite directions, and no triangle has
 * zero area (rings have R > 0 and distinct stations or distinct radii).
 */
#include "thorax/geom/landmark_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/verify.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MITRE_MAX 3.0 /* largest stretch of a ring at a bend */
#define ARROW_HEAD_RADIUS 2.5
#define ARROW_HEAD_RADII 6.0
#define ARROW_HEAD_FRACTION 0.4

void thx_landmark_mesh_opts_default(thx_landmark_mesh_opts *o)
{
    o->sides = 12;
    o->disc_sides = 48;
    o->sphere_level = 2;
    o->min_radius = 0.5;
}

/* ------------------------------------------------------------ colours */

void thx_landmark_type_color(thx_landmark_type t, float rgba[4])
{
    static const float tab[THX_LANDMARK_TYPE_COUNT][4] = {
        [THX_LANDMARK_ARTERY] = {1, 0, 0, 1},     [THX_LANDMARK_OCCLUSION] = {0, 1, 1, 1},
        [THX_LANDMARK_CLOSURE] = {0, 0, 1, 1},    [THX_LANDMARK_STIMULUS] = {1, 1, 0, 1},
        [THX_LANDMARK_LEAD] = {0, 0, 1, 1},       [THX_LANDMARK_PLANE] = {1, 0, 1, 0.5f},
        [THX_LANDMARK_ROD] = {0, 1, 0, 1},        [THX_LANDMARK_PACENEEDLE] = {0, 1, 0, 1},
        [THX_LANDMARK_CATH] = {0, 1, 1, 1},       [THX_LANDMARK_FIBER] = {0, 1, 0, 1},
        [THX_LANDMARK_RECNEEDLE] = {0, 1, 0, 1},  [THX_LANDMARK_CANNULA] = {1, 0, 0, 1},
    };
    static const float grey[4] = {0.5f, 0.5f, 0.5f, 1};
    memcpy(rgba, (unsigned)t < THX_LANDMARK_TYPE_COUNT ? tab[t] : grey, 4 * sizeof(float));
}

void thx_landmark_color(const thx_landmark_segment *s, float rgba[4])
{
    thx_landmark_type_color(s->type, rgba);
    if (s->has_color)
        for (int c = 0; c < 3; c++) rgba[c] = (float)s->rgb[c] / 255.0f;
}

/* ------------------------------------------------------------ a growing mesh */

typedef struct {
    thx_ctx *ctx;
    double *xyz;
    size_t nv, cap_v;
    int32_t *tri;
    size_t nt, cap_t;
} mesh;

static thx_status add_vertex(mesh *m, thx_vec3 p, int32_t *idx)
{
    if (m->nv >= (size_t)INT32_MAX) return thx_error(m->ctx, THX_EINPUT, "landmark mesh: too many nodes");
    THX_CHECK(thx_grow(m->ctx, (void **)&m->xyz, &m->cap_v, m->nv + 1, 3 * sizeof *m->xyz));
    m->xyz[3 * m->nv] = p.x;
    m->xyz[3 * m->nv + 1] = p.y;
    m->xyz[3 * m->nv + 2] = p.z;
    *idx = (int32_t)m->nv++;
    return THX_OK;
}

static thx_status add_tri(mesh *m, int32_t a, int32_t b, int32_t c)
{
    THX_CHECK(thx_grow(m->ctx, (void **)&m->tri, &m->cap_t, m->nt + 1, 3 * sizeof *m->tri));
    m->tri[3 * m->nt] = a;
    m->tri[3 * m->nt + 1] = b;
    m->tri[3 * m->nt + 2] = c;
    m->nt++;
    return THX_OK;
}

static thx_vec3 unit(thx_vec3 a)
{
    double n = thx_v3_norm(a);
    return n > 0 ? thx_v3_scale(a, 1.0 / n) : a;
}

static thx_vec3 p3(const double *x) { return thx_v3(x[0], x[1], x[2]); }

static int same(thx_vec3 a, thx_vec3 b)
{
    double x[3] = {a.x, a.y, a.z}, y[3] = {b.x, b.y, b.z};
    return thx_landmark_points_coincide(x, y);
}

/* A radius as drawn at centre c: radii within the tolerance at which two points coincide
 * (thx_landmark_points_coincide, 1e-9 of the coordinates) are 0 (they would give rings of
 * coincident nodes); then `zero` stands for it (min_radius, or 0 for an end that closes). */
static double drawn_radius(double r, thx_vec3 c, double zero)
{
    double m = fmax(fabs(c.x), fmax(fabs(c.y), fabs(c.z)));
    return r > 1e-9 * (1.0 + m) ? r : zero;
}

/* A unit vector perpendicular to unit t. */
static thx_vec3 any_perpendicular(thx_vec3 t)
{
    double ax = fabs(t.x), ay = fabs(t.y), az = fabs(t.z);
    thx_vec3 e = ax <= ay && ax <= az ? thx_v3(1, 0, 0) : ay <= az ? thx_v3(0, 1, 0) : thx_v3(0, 0, 1);
    return unit(thx_v3_cross(t, e));
}

/* u carried from tangent t0 to t1 by the rotation about t0 x t1 taking t0 to t1 (Rodrigues),
 * then made exactly perpendicular to t1. */
static thx_vec3 transport(thx_vec3 u, thx_vec3 t0, thx_vec3 t1)
{
    thx_vec3 k = thx_v3_cross(t0, t1);
    double s = thx_v3_norm(k), c = thx_v3_dot(t0, t1);
    thx_vec3 r = u;
    if (s > 1e-12) {
        k = thx_v3_scale(k, 1.0 / s);
        /* r = u cos + (k x u) sin + k (k.u)(1 - cos) */
        r = thx_v3_add(thx_v3_add(thx_v3_scale(u, c), thx_v3_scale(thx_v3_cross(k, u), s)),
                       thx_v3_scale(k, thx_v3_dot(k, u) * (1 - c)));
    }
    r = thx_v3_sub(r, thx_v3_scale(t1, thx_v3_dot(r, t1)));
    double n = thx_v3_norm(r);
    return n > 1e-6 ? thx_v3_scale(r, 1.0 / n) : any_perpendicular(t1);
}

/* The tube through m stations c[i] with radii r[i] (the invariants in the header comment),
 * n sides, appended to the mesh. */
static thx_status tube(mesh *me, const thx_vec3 *c, const double *r, size_t m, int n)
{
    if (m < 2) return thx_error(me->ctx, THX_EINTERNAL, "landmark tube: %zu stations", m);
    const double area_scale = sqrt(2 * M_PI / (n * sin(2 * M_PI / n)));
    thx_vec3 u = {0, 0, 0}, t_prev = {0, 0, 0};
    int32_t prev_first = -1; /* first ring vertex of the previous station; -2: the previous was a point */
    int32_t prev_point = -1;
    for (size_t i = 0; i < m; i++) {
        /* the nearest stations at other places before and after */
        size_t ip = i, in = i;
        while (ip > 0 && same(c[ip], c[i])) ip--;
        while (in + 1 < m && same(c[in], c[i])) in++;
        int has_in = !same(c[ip], c[i]), has_out = !same(c[in], c[i]);
        thx_vec3 din = has_in ? unit(thx_v3_sub(c[i], c[ip])) : thx_v3(0, 0, 0);
        thx_vec3 dout = has_out ? unit(thx_v3_sub(c[in], c[i])) : thx_v3(0, 0, 0);
        thx_vec3 t, b = {0, 0, 0};
        double stretch = 1;
        if (has_in && has_out) {
            thx_vec3 sum = thx_v3_add(din, dout);
            double ns = thx_v3_norm(sum);
            if (ns > 1e-6) {
                t = thx_v3_scale(sum, 1.0 / ns);
                double ch = thx_v3_dot(t, din); /* cos of half the bend */
                stretch = ch > 1.0 / MITRE_MAX ? 1.0 / ch : MITRE_MAX;
                thx_vec3 d = thx_v3_sub(dout, din);
                double nd = thx_v3_norm(d);
                if (nd > 1e-9) b = thx_v3_scale(d, 1.0 / nd);
                else stretch = 1;
            } else {
                t = din; /* a hairpin: the ring across the incoming piece */
            }
        } else {
            t = has_in ? din : dout;
        }
        if (i == 0) u = any_perpendicular(t);
        else u = transport(u, t_prev, t);
        t_prev = t;
        thx_vec3 v = thx_v3_cross(t, u);
        int is_end = i == 0 || i + 1 == m;
        if (r[i] <= 0) { /* an end closed to a point */
            if (!is_end || (i > 0 && prev_first < 0))
                return thx_error(me->ctx, THX_EINTERNAL, "landmark tube: radius 0 inside, or at both ends of one piece");
            int32_t pt;
            THX_CHECK(add_vertex(me, c[i], &pt));
            if (i > 0) /* the cone from the previous ring to this point */
                for (int j = 0; j < n; j++)
                    THX_CHECK(add_tri(me, prev_first + j, prev_first + (j + 1) % n, pt));
            prev_point = pt;
            prev_first = -2;
            continue;
        }
        double R = r[i] * area_scale;
        int32_t first = (int32_t)me->nv, dummy;
        for (int j = 0; j < n; j++) {
            double a = 2 * M_PI * j / n;
            thx_vec3 o = thx_v3_add(thx_v3_scale(u, R * cos(a)), thx_v3_scale(v, R * sin(a)));
            if (stretch != 1) o = thx_v3_add(o, thx_v3_scale(b, (stretch - 1) * thx_v3_dot(o, b)));
            THX_CHECK(add_vertex(me, thx_v3_add(c[i], o), &dummy));
        }
        if (i == 0) { /* the start cap, facing -t */
            int32_t ctr;
            THX_CHECK(add_vertex(me, c[i], &ctr));
            for (int j = 0; j < n; j++) THX_CHECK(add_tri(me, ctr, first + (j + 1) % n, first + j));
        } else if (prev_first == -2) { /* from the start point to this ring */
            for (int j = 0; j < n; j++) THX_CHECK(add_tri(me, prev_point, first + (j + 1) % n, first + j));
        } else { /* the side between the previous ring and this one */
            for (int j = 0; j < n; j++) {
                int32_t a0 = prev_first + j, a1 = prev_first + (j + 1) % n, b0 = first + j, b1 = first + (j + 1) % n;
                THX_CHECK(add_tri(me, a0, a1, b1));
                THX_CHECK(add_tri(me, a0, b1, b0));
            }
        }
        if (i + 1 == m) { /* the end cap, facing +t */
            int32_t ctr;
            THX_CHECK(add_vertex(me, c[i], &ctr));
            for (int j = 0; j < n; j++) THX_CHECK(add_tri(me, ctr, first + j, first + (j + 1) % n));
        }
        prev_first = first;
    }
    return THX_OK;
}

/* ------------------------------------------------------------ stations */

typedef struct {
    thx_vec3 *c;
    double *r;
    size_t m, cap;
} stations;

static thx_status st_push(thx_ctx *ctx, stations *s, thx_vec3 c, double r)
{
    if (s->m + 1 > s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 16;
        thx_vec3 *nc = thx_realloc(ctx, s->c, cap * sizeof *nc);
        if (!nc) return THX_ENOMEM;
        s->c = nc;
        double *nr = thx_realloc(ctx, s->r, cap * sizeof *nr);
        if (!nr) return THX_ENOMEM;
        s->r = nr;
        s->cap = cap;
    }
    s->c[s->m] = c;
    s->r[s->m] = r;
    s->m++;
    return THX_OK;
}

/* Stations from the points of a run at one place: only the first and last of each run are kept
 * (a flat step between their radii), and they only if their radii differ. */
static void squeeze(stations *s)
{
    size_t w = 0;
    for (size_t i = 0; i < s->m;) {
        size_t j = i;
        while (j + 1 < s->m && same(s->c[j + 1], s->c[i])) j++;
        s->c[w] = s->c[i];
        s->r[w++] = s->r[i];
        if (j > i && s->r[j] != s->r[i]) {
            s->c[w] = s->c[j];
            s->r[w++] = s->r[j];
        }
        i = j + 1;
    }
    s->m = w;
}

/* The stations of a tube-type segment (artery, cath, cannula): radii as in the file, an interior
 * or every 0 made min_radius, ends of 0 kept (points). */
static thx_status tube_stations(thx_ctx *ctx, const thx_landmark_segment *g, double rmin, stations *s)
{
    int all_zero = 1;
    for (size_t i = 0; i < g->n; i++) all_zero &= drawn_radius(g->pt[i].radius, p3(g->pt[i].xyz), 0) == 0;
    for (size_t i = 0; i < g->n; i++) {
        double r = drawn_radius(g->pt[i].radius, p3(g->pt[i].xyz), 0);
        int end = i == 0 || i + 1 == g->n;
        if (r == 0 && (all_zero || !end)) r = rmin;
        THX_CHECK(st_push(ctx, s, p3(g->pt[i].xyz), r));
    }
    squeeze(s);
    /* an end of 0 at the place of its neighbour is that neighbour's flat cap; a start or end
       station of radius 0 next to another of radius 0 cannot occur (interior zeros are rmin) */
    if (s->m >= 2 && s->r[0] == 0 && same(s->c[0], s->c[1])) {
        memmove(s->c, s->c + 1, (s->m - 1) * sizeof *s->c);
        memmove(s->r, s->r + 1, (s->m - 1) * sizeof *s->r);
        s->m--;
    }
    if (s->m >= 2 && s->r[s->m - 1] == 0 && same(s->c[s->m - 1], s->c[s->m - 2])) s->m--;
    /* a tube of two stations, both points, cannot occur either: not all radii are 0 then */
    return THX_OK;
}

/* ------------------------------------------------------------ shapes */

static thx_status spheres(mesh *me, const thx_landmark_segment *g, const thx_landmark_mesh_opts *o)
{
    for (size_t i = 0; i < g->n; i++) {
        double r = drawn_radius(g->pt[i].radius, p3(g->pt[i].xyz), o->min_radius);
        thx_surface *s = NULL;
        THX_CHECK(thx_icosphere(me->ctx, o->sphere_level, r, "site", THX_ROLE_OTHER, &s));
        int32_t base = (int32_t)me->nv, dummy;
        thx_status st = THX_OK;
        for (size_t v = 0; v < s->n_nodes && st == THX_OK; v++)
            st = add_vertex(me, thx_v3_add(p3(g->pt[i].xyz), thx_surface_node(s, v)), &dummy);
        for (size_t t = 0; t < s->n_tris && st == THX_OK; t++)
            st = add_tri(me, base + s->tri[3 * t], base + s->tri[3 * t + 1], base + s->tri[3 * t + 2]);
        thx_surface_destroy(&s);
        THX_CHECK(st);
    }
    return THX_OK;
}

static thx_status disc(mesh *me, const thx_landmark_segment *g, const thx_landmark_mesh_opts *o)
{
    thx_vec3 a = p3(g->pt[0].xyz), b = p3(g->pt[1].xyz), c = p3(g->pt[2].xyz);
    thx_vec3 ctr = thx_v3_scale(thx_v3_add(thx_v3_add(a, b), c), 1.0 / 3);
    thx_vec3 nrm = unit(thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a)));
    double R = drawn_radius(g->pt[0].radius, ctr, o->min_radius);
    double T = drawn_radius(g->pt[1].radius, ctr, o->min_radius);
    if (T > 2 * R) T = 2 * R;
    /* far from the origin a thin disc's faces would coincide (thx_landmark_points_coincide): at
       least 4e-9 of the coordinates apart, which they do not (|d| >= T / sqrt 3 > the tolerance) */
    double m = fmax(fabs(ctr.x), fmax(fabs(ctr.y), fabs(ctr.z)));
    T = fmax(T, 4e-9 * (1.0 + m));
    thx_vec3 cs[2] = {thx_v3_sub(ctr, thx_v3_scale(nrm, T / 2)), thx_v3_add(ctr, thx_v3_scale(nrm, T / 2))};
    double rs[2] = {R, R};
    if (same(cs[0], cs[1]))
        return thx_error(me->ctx, THX_EGEOM, "plane: thickness %g mm is too thin to draw at (%g, %g, %g)", T, ctr.x,
                         ctr.y, ctr.z);
    return tube(me, cs, rs, 2, o->disc_sides);
}

static thx_status segment_mesh(mesh *me, const thx_landmark_segment *g, const thx_landmark_mesh_opts *o)
{
    thx_landmark_shape shape = thx_landmark_type_shape(g->type);
    if (shape == THX_LANDMARK_SHAPE_SPHERES) return spheres(me, g, o);
    if (shape == THX_LANDMARK_SHAPE_DISC) return disc(me, g, o);
    stations s = {0};
    thx_status st = THX_OK;
    if (shape == THX_LANDMARK_SHAPE_TUBE) {
        THX_TRY(tube_stations(me->ctx, g, o->min_radius, &s));
    } else {
        double r = drawn_radius(g->pt[0].radius, p3(g->pt[0].xyz), o->min_radius);
        for (size_t i = 0; i < g->n; i++) THX_TRY(st_push(me->ctx, &s, p3(g->pt[i].xyz), r));
        squeeze(&s); /* equal radii: one station per place */
        if (shape == THX_LANDMARK_SHAPE_ARROW && s.m >= 2) {
            /* the head: on the last piece, a step out to 2.5 r, then the tip */
            thx_vec3 tip = s.c[s.m - 1], from = s.c[s.m - 2];
            double len = thx_v3_norm(thx_v3_sub(tip, from));
            double hl = fmin(ARROW_HEAD_RADII * r, ARROW_HEAD_FRACTION * len);
            thx_vec3 base = thx_v3_sub(tip, thx_v3_scale(unit(thx_v3_sub(tip, from)), hl));
            s.m--;
            if (!same(base, from)) THX_TRY(st_push(me->ctx, &s, base, r));
            THX_TRY(st_push(me->ctx, &s, base, ARROW_HEAD_RADIUS * r));
            THX_TRY(st_push(me->ctx, &s, tip, 0));
        }
    }
    if (s.m < 2) {
        st = thx_error(me->ctx, THX_EGEOM, "%zu distinct point%s: nothing to draw a tube along", s.m, s.m == 1 ? "" : "s");
        goto done;
    }
    st = tube(me, s.c, s.r, s.m, o->sides);
done:
    free(s.c);
    free(s.r);
    return st;
}

static thx_status check_opts(thx_ctx *ctx, const thx_landmark_mesh_opts *o)
{
    if (o->sides < 3 || o->sides > 256)
        return thx_error(ctx, THX_EINPUT, "landmark meshes: sides %d out of range 3..256", o->sides);
    if (o->disc_sides < 3 || o->disc_sides > 1024)
        return thx_error(ctx, THX_EINPUT, "landmark meshes: disc sides %d out of range 3..1024", o->disc_sides);
    if (o->sphere_level < 0 || o->sphere_level > 5)
        return thx_error(ctx, THX_EINPUT, "landmark meshes: sphere level %d out of range 0..5", o->sphere_level);
    if (!(o->min_radius >= 1e-3) || !(o->min_radius <= THX_LANDMARK_MAX_COORD))
        return thx_error(ctx, THX_EINPUT, "landmark meshes: minimum radius %g mm is not in [0.001, %g]", o->min_radius,
                         THX_LANDMARK_MAX_COORD);
    return THX_OK;
}

thx_status thx_landmark_segment_mesh(thx_ctx *ctx, const thx_landmark_segment *s, size_t k,
                                     const thx_landmark_mesh_opts *o, thx_surface **out)
{
    *out = NULL;
    thx_landmark_mesh_opts def;
    if (!o) {
        thx_landmark_mesh_opts_default(&def);
        o = &def;
    }
    THX_CHECK(check_opts(ctx, o));
    THX_CHECK(thx_landmark_segment_validate(ctx, s, k, ""));
    char name[64];
    snprintf(name, sizeof name, "landmark_%zu_%s", k + 1, thx_landmark_type_name(s->type));
    mesh me = {.ctx = ctx};
    thx_surface *surf = NULL;
    thx_status st = segment_mesh(&me, s, o);
    if (st != THX_OK) {
        /* name the segment: the shape's own message lacks it */
        char m[800];
        snprintf(m, sizeof m, "%s", thx_ctx_message(ctx));
        if (strncmp(m, "segment", 7) != 0)
            st = thx_error(ctx, st, "segment %zu (%s): %s", k + 1, thx_landmark_type_name(s->type), m);
        goto done;
    }
    THX_TRY(thx_surface_create(ctx, name, THX_ROLE_OTHER, &surf));
    surf->xyz = me.xyz;
    surf->n_nodes = me.nv;
    surf->tri = me.tri;
    surf->n_tris = me.nt;
    me.xyz = NULL;
    me.tri = NULL;
    *out = surf;
done:
    free(me.xyz);
    free(me.tri);
    return st;
}

thx_status thx_landmarks_mesh(thx_ctx *ctx, const thx_landmarks *lm, const thx_landmark_mesh_opts *o,
                              thx_landmark_meshes **out)
{
    *out = NULL;
    THX_CHECK(thx_landmarks_validate(ctx, lm, NULL));
    thx_landmark_meshes *m = thx_calloc(ctx, 1, sizeof *m);
    if (!m) return THX_ENOMEM;
    thx_status st = THX_OK;
    if (lm->n) {
        m->surf = thx_calloc(ctx, lm->n, sizeof *m->surf);
        m->rgba = thx_calloc(ctx, lm->n, sizeof *m->rgba);
        if (!m->surf || !m->rgba) {
            st = THX_ENOMEM;
            goto done;
        }
    }
    for (size_t k = 0; k < lm->n; k++) {
        st = thx_landmark_segment_mesh(ctx, &lm->seg[k], k, o, &m->surf[k]);
        if (st != THX_OK) {
            if (lm->path[0] && lm->seg[k].line > 0) {
                char msg[900];
                snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
                st = thx_error(ctx, st, "%s:%d: %s", lm->path, lm->seg[k].line, msg);
            }
            goto done;
        }
        m->n = k + 1;
        thx_landmark_color(&lm->seg[k], m->rgba[k]);
    }
    *out = m;
    m = NULL;
done:
    thx_landmark_meshes_destroy(&m);
    return st;
}

void thx_landmark_meshes_destroy(thx_landmark_meshes **m)
{
    if (!m || !*m) return;
    for (size_t k = 0; k < (*m)->n; k++) thx_surface_destroy(&(*m)->surf[k]);
    free((*m)->surf);
    free((*m)->rgba);
    free(*m);
    *m = NULL;
}
