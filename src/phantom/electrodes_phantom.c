/*
 * The phantom's electrodes (thorax/phantom/phantom.h): the standard 12-lead
 * positions and a body-surface-mapping array on the model's outer surface.
 *
 * Landmarks are computed from the model itself, so they follow the phantom's
 * shape and any other torso (an imported one such as the Dalhousie torso):
 * the torso's cross-sections across its superior axis (thx_surface_slice: the
 * largest loop of the outer surface on a plane of constant height), its
 * extent along that axis, and the heart's. The model's anatomical frame
 * (thorax/model/frame.h) says which axes are superior and anterior: the outer and
 * heart surfaces are first carried into RAS (+x the subject's right, +y
 * anterior, +z superior; a rotation, so orientation and distances are kept),
 * the landmarks are found there, and each electrode is the outer-surface node
 * nearest its landmark, reported with the node's own model coordinates. Below,
 * x, y, z are those RAS coordinates: the subject's left is -x, anterior +y.
 *
 *  - Heights. V1 and V2 (4th intercostal space) at the middle of the heart's
 *    z extent; V4, V5, V6 (5th space) a quarter of the heart's height lower,
 *    which puts V4 over the apex as on a real chest; V3 halfway between.
 *  - Across. On each section: the midline x_m (centre of its x extent), the
 *    half-widths to the right and the left, the centre y_c of its y extent.
 *    V1 and V2: the anterior surface at x_m +- 0.15 half-width (beside the
 *    sternum, about 25 mm from the midline on the phantom); V4: at
 *    x_m - 0.55 half-width (the mid-clavicular line, about 90 mm left); V6:
 *    the leftmost point of the section on y = y_c (mid-axillary line); V5:
 *    halfway along the section between V4 and V6 (the AHA rule when the
 *    anterior axillary line is not evident); V3: the anterior surface at the
 *    mean x of V2 and V4, halfway between their heights.
 *  - Limb leads, Mason-Likar: RA and LA on the front of the shoulders
 *    (8% of the torso's height below its top, at +-0.7 half-width; on a
 *    torso that goes on into the neck, lower: at the first height where the
 *    section is at least 75% as wide as the widest), LL on the front at the
 *    left lower end (8% above the bottom, 0.6 half-width left).
 *  - The array: rings at heights zmin + (k + 1/2) H / rings (k = 0 bottom to
 *    top, H the torso's height, so no ring is on a cap), each ring's
 *    electrodes evenly spaced in arc length along the section, starting at
 *    the anterior midline and running counterclockwise seen from above
 *    (anterior, the subject's left, posterior, right). n = 192 gives 12
 *    rings of 16; in general rings = round(sqrt(3 n / 4)), the electrodes
 *    shared as evenly as possible (lower rings take the remainder). Names
 *    A001, A002, ... in that order. Array electrodes are distinct nodes:
 *    each takes the nearest node not taken by an earlier one.
 * Everything is deterministic (no randomness, fixed order).
 */
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/slice.h"
/* A cross-section: one closed loop, counterclockwise seen from above, with
 * cumulative arc lengths and its bounding box. */
typedef struct {
    thx_vec2 *p;
    size_t n;
    double *s; /* n + 1 cumulative lengths, s[n] = perimeter */
    double x0, x1, y0, y1;
    double z;
} section;

static void section_free(section *c)
{
    free(c->p);
    free(c->s);
    memset(c, 0, sizeof *c);
}

static thx_status section_at(thx_ctx *ctx, const thx_surface *s, double z, section *out)
{
    memset(out, 0, sizeof *out);
    thx_loop *loops = NULL;
    size_t nl = 0;
    THX_CHECK(thx_surface_slice(ctx, s, z, &loops, &nl));
    /* the loop enclosing the largest area */
    size_t best = nl;
    double best_a = 0;
    for (size_t l = 0; l < nl; l++) {
        double a = 0;
        for (size_t i = 0, j = loops[l].n - 1; i < loops[l].n; j = i++)
            a += loops[l].p[j].x * loops[l].p[i].y - loops[l].p[i].x * loops[l].p[j].y;
        if (loops[l].n >= 3 && fabs(a) > fabs(best_a)) {
            best = l;
            best_a = a;
        }
    }
    if (best == nl) {
        thx_slice_free(&loops, nl);
        return thx_error(ctx, THX_EGEOM, "surface \"%s\" has no cross-section at z = %g mm", s->name, z);
    }
    size_t n = loops[best].n;
    out->p = thx_malloc(ctx, n * sizeof *out->p);
    out->s = thx_malloc(ctx, (n + 1) * sizeof *out->s);
    if (!out->p || !out->s) {
        thx_slice_free(&loops, nl);
        section_free(out);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) out->p[i] = loops[best].p[best_a > 0 ? i : n - 1 - i];
    thx_slice_free(&loops, nl);
    out->n = n;
    out->z = z;
    out->x0 = out->y0 = INFINITY;
    out->x1 = out->y1 = -INFINITY;
    out->s[0] = 0;
    for (size_t i = 0; i < n; i++) {
        thx_vec2 a = out->p[i], b = out->p[(i + 1) % n];
        out->s[i + 1] = out->s[i] + hypot(b.x - a.x, b.y - a.y);
        out->x0 = fmin(out->x0, a.x);
        out->x1 = fmax(out->x1, a.x);
        out->y0 = fmin(out->y0, a.y);
        out->y1 = fmax(out->y1, a.y);
    }
    return THX_OK;
}

static double sec_mid_x(const section *c) { return 0.5 * (c->x0 + c->x1); }
static double sec_mid_y(const section *c) { return 0.5 * (c->y0 + c->y1); }
/* Half-widths toward the subject's right (+x) and left (-x) from the midline. */
static double sec_hw_right(const section *c) { return c->x1 - sec_mid_x(c); }
static double sec_hw_left(const section *c) { return sec_mid_x(c) - c->x0; }

/* Where the line {coordinate `axis` (0 = x, 1 = y) == value} crosses the
 * loop, the crossing with the largest (sign > 0) or smallest other
 * coordinate; its arc length in *arc. Returns 0 if the line misses the loop. */
static int sec_line(const section *c, int axis, double value, int sign, thx_vec2 *hit, double *arc)
{
    int found = 0;
    double best = 0;
    for (size_t i = 0; i < c->n; i++) {
        thx_vec2 a = c->p[i], b = c->p[(i + 1) % c->n];
        double ua = axis == 0 ? a.x : a.y, ub = axis == 0 ? b.x : b.y;
        if ((ua >= value) == (ub >= value)) continue;
        double t = (value - ua) / (ub - ua);
        thx_vec2 q = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        double other = axis == 0 ? q.y : q.x;
        if (!found || (sign > 0 ? other > best : other < best)) {
            found = 1;
            best = other;
            *hit = q;
            *arc = c->s[i] + t * (c->s[i + 1] - c->s[i]);
        }
    }
    return found;
}

/* The point at arc length t (wrapped) along the loop. */
static thx_vec2 sec_at(const section *c, double t)
{
    double L = c->s[c->n];
    t = fmod(t, L);
    if (t < 0) t += L;
    size_t lo = 0, hi = c->n;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (c->s[mid] <= t) lo = mid;
        else hi = mid;
    }
    thx_vec2 a = c->p[lo], b = c->p[(lo + 1) % c->n];
    double seg = c->s[lo + 1] - c->s[lo];
    double u = seg > 0 ? (t - c->s[lo]) / seg : 0;
    thx_vec2 r = {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
    return r;
}

/* The anterior surface point of the section at x (the crossing of x = const
 * with the largest y); x is clamped into the section's extent. */
static thx_status anterior_at(thx_ctx *ctx, const section *c, double x, const char *what, double out[3])
{
    double lo = c->x0 + 1e-6 * (c->x1 - c->x0), hi = c->x1 - 1e-6 * (c->x1 - c->x0);
    x = x < lo ? lo : x > hi ? hi : x;
    thx_vec2 q;
    double arc;
    if (!sec_line(c, 0, x, +1, &q, &arc))
        return thx_error(ctx, THX_EINTERNAL, "electrodes: landmark %s: x = %g misses the section at z = %g", what, x,
                         c->z);
    out[0] = q.x;
    out[1] = q.y;
    out[2] = c->z;
    return THX_OK;
}

static const thx_surface *find_role(const thx_model *m, thx_role role)
{
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == role) return m->surf[s];
    return NULL;
}

/* The node of s nearest p, skipping nodes marked in `used` (may be NULL);
 * ties go to the lower node number. */
static size_t nearest_node(const thx_surface *s, const double p[3], const unsigned char *used)
{
    size_t best = s->n_nodes;
    double bd = INFINITY;
    for (size_t i = 0; i < s->n_nodes; i++) {
        if (used && used[i]) continue;
        const double *x = s->xyz + 3 * i;
        double d = (x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

static void set_electrode(thx_electrodes *e, size_t i, const char *name, const thx_surface *s, size_t node)
{
    snprintf(e->name[i], sizeof e->name[i], "%s", name);
    e->node[i] = (int32_t)node;
    memcpy(e->xyz + 3 * i, s->xyz + 3 * node, 3 * sizeof(double));
}

#define SHOULDER_WIDTH 0.75

static thx_status twelve_lead(thx_ctx *ctx, const thx_surface *outer, const thx_surface *heart, double zmin,
                              double zmax, thx_electrodes **out)
{
    double hz0 = INFINITY, hz1 = -INFINITY;
    for (size_t i = 0; i < heart->n_nodes; i++) {
        hz0 = fmin(hz0, heart->xyz[3 * i + 2]);
        hz1 = fmax(hz1, heart->xyz[3 * i + 2]);
    }
    double H = zmax - zmin, Hh = hz1 - hz0;
    double z12 = 0.5 * (hz0 + hz1), z46 = z12 - 0.25 * Hh, z3 = 0.5 * (z12 + z46);
    double zarm = zmax - 0.08 * H, zleg = zmin + 0.08 * H;
    double lm[9][3]; /* RA LA LL V1..V6 */
    section c12, c3, c46, carm, cleg;
    thx_status st = THX_OK;
    memset(&c12, 0, sizeof c12);
    c3 = c46 = carm = cleg = c12;
    THX_TRY(section_at(ctx, outer, z12, &c12));
    THX_TRY(section_at(ctx, outer, z3, &c3));
    THX_TRY(section_at(ctx, outer, z46, &c46));
    {
        /* The shoulders. A torso cut at the shoulders (the phantom) has them at its top;
         * one that goes on into the neck (the Dalhousie torso) is much narrower there:
         * then the arm electrodes go down to the first height where the torso is at
         * least SHOULDER_WIDTH of its widest section (sampled at 48 heights), never
         * below the V1/V2 level. */
        double wmax = 0;
        for (int k = 0; k < 48; k++) {
            section t;
            double z = zmin + (0.04 + 0.92 * k / 47.0) * H;
            if (section_at(ctx, outer, z, &t) != THX_OK) continue;
            wmax = fmax(wmax, t.x1 - t.x0);
            section_free(&t);
        }
        THX_TRY(section_at(ctx, outer, zarm, &carm));
        while (carm.x1 - carm.x0 < SHOULDER_WIDTH * wmax && zarm - 0.01 * H > z12) {
            section_free(&carm);
            zarm -= 0.01 * H;
            THX_TRY(section_at(ctx, outer, zarm, &carm));
        }
    }
    THX_TRY(section_at(ctx, outer, zleg, &cleg));
    THX_TRY(anterior_at(ctx, &carm, sec_mid_x(&carm) + 0.7 * sec_hw_right(&carm), "RA", lm[0]));
    THX_TRY(anterior_at(ctx, &carm, sec_mid_x(&carm) - 0.7 * sec_hw_left(&carm), "LA", lm[1]));
    THX_TRY(anterior_at(ctx, &cleg, sec_mid_x(&cleg) - 0.6 * sec_hw_left(&cleg), "LL", lm[2]));
    THX_TRY(anterior_at(ctx, &c12, sec_mid_x(&c12) + 0.15 * sec_hw_right(&c12), "V1", lm[3]));
    THX_TRY(anterior_at(ctx, &c12, sec_mid_x(&c12) - 0.15 * sec_hw_left(&c12), "V2", lm[4]));
    THX_TRY(anterior_at(ctx, &c46, sec_mid_x(&c46) - 0.55 * sec_hw_left(&c46), "V4", lm[6]));
    THX_TRY(anterior_at(ctx, &c3, 0.5 * (lm[4][0] + lm[6][0]), "V3", lm[5]));
    {
        /* V5 and V6 at the height of V4's node (not of its landmark), so that on a
         * coarse model the three lie on one layer */
        double zn = outer->xyz[3 * nearest_node(outer, lm[6], NULL) + 2];
        if (zn != z46) {
            section_free(&c46);
            z46 = zn;
            THX_TRY(section_at(ctx, outer, z46, &c46));
            THX_TRY(anterior_at(ctx, &c46, lm[6][0], "V4", lm[6]));
        }
    }
    {
        /* V6: leftmost crossing of y = y_c; V5: halfway along the section from V4 to V6 */
        thx_vec2 q6, q4;
        double s6, s4;
        if (!sec_line(&c46, 1, sec_mid_y(&c46), -1, &q6, &s6) || !sec_line(&c46, 0, lm[6][0], +1, &q4, &s4)) {
            st = thx_error(ctx, THX_EINTERNAL, "electrodes: V4/V6 landmarks miss the section at z = %g", z46);
            goto done;
        }
        double L = c46.s[c46.n], d = fmod(s6 - s4, L);
        if (d > 0.5 * L) d -= L;
        if (d < -0.5 * L) d += L;
        thx_vec2 q5 = sec_at(&c46, s4 + 0.5 * d);
        lm[8][0] = q6.x, lm[8][1] = q6.y, lm[8][2] = z46;
        lm[7][0] = q5.x, lm[7][1] = q5.y, lm[7][2] = z46;
    }
    {
        static const char *const names[9] = {"RA", "LA", "LL", "V1", "V2", "V3", "V4", "V5", "V6"};
        thx_electrodes *e = NULL;
        THX_TRY(thx_electrodes_create(ctx, 9, &e));
        snprintf(e->surface, sizeof e->surface, "%s", outer->name);
        for (size_t i = 0; i < 9; i++) set_electrode(e, i, names[i], outer, nearest_node(outer, lm[i], NULL));
        *out = e;
    }
done:
    section_free(&c12);
    section_free(&c3);
    section_free(&c46);
    section_free(&carm);
    section_free(&cleg);
    return st;
}

static thx_status body_array(thx_ctx *ctx, const thx_surface *outer, double zmin, double zmax, size_t n,
                             thx_electrodes **out)
{
    if (n > outer->n_nodes)
        return thx_error(ctx, THX_EINPUT, "electrodes: an array of %zu electrodes on distinct nodes needs more than the "
                                          "%zu nodes of surface \"%s\"",
                         n, outer->n_nodes, outer->name);
    size_t rings = (size_t)lround(sqrt(0.75 * (double)n));
    rings = rings < 1 ? 1 : rings > n ? n : rings;
    unsigned char *used = thx_calloc(ctx, outer->n_nodes, 1);
    if (!used) return THX_ENOMEM;
    thx_electrodes *e = NULL;
    thx_status st = thx_electrodes_create(ctx, n, &e);
    if (st != THX_OK) {
        free(used);
        return st;
    }
    snprintf(e->surface, sizeof e->surface, "%s", outer->name);
    size_t i = 0, moved = 0;
    for (size_t k = 0; k < rings && st == THX_OK; k++) {
        size_t count = n / rings + (k < n % rings ? 1 : 0);
        double z = zmin + ((double)k + 0.5) * (zmax - zmin) / (double)rings;
        section c;
        if ((st = section_at(ctx, outer, z, &c)) != THX_OK) break;
        thx_vec2 q0;
        double s0;
        if (!sec_line(&c, 0, sec_mid_x(&c), +1, &q0, &s0)) {
            st = thx_error(ctx, THX_EINTERNAL, "electrodes: the midline misses the section at z = %g", z);
            section_free(&c);
            break;
        }
        double L = c.s[c.n];
        for (size_t j = 0; j < count; j++, i++) {
            thx_vec2 q = sec_at(&c, s0 + L * (double)j / (double)count);
            double p[3] = {q.x, q.y, z};
            size_t node = nearest_node(outer, p, used);
            if (node != nearest_node(outer, p, NULL)) moved++;
            used[node] = 1;
            char name[32];
            snprintf(name, sizeof name, "A%03zu", i + 1);
            set_electrode(e, i, name, outer, node);
        }
        section_free(&c);
    }
    free(used);
    if (st != THX_OK) {
        thx_electrodes_destroy(&e);
        return st;
    }
    if (moved)
        thx_log(ctx, THX_LOG_INFO, "electrodes: %zu array electrodes took the nearest free node (their nearest was taken)",
                moved);
    *out = e;
    return THX_OK;
}

/* A copy of s in the RAS coordinates of frame f (same node and triangle numbers). */
static thx_status ras_copy(thx_ctx *ctx, const thx_surface *s, const thx_frame *f, thx_surface **out)
{
    *out = NULL;
    thx_surface *c = NULL;
    THX_CHECK(thx_surface_create(ctx, s->name, s->role, &c));
    c->xyz = thx_malloc(ctx, (s->n_nodes ? s->n_nodes : 1) * 3 * sizeof *c->xyz);
    c->tri = thx_malloc(ctx, (s->n_tris ? s->n_tris : 1) * 3 * sizeof *c->tri);
    if (!c->xyz || !c->tri) {
        thx_surface_destroy(&c);
        return THX_ENOMEM;
    }
    c->n_nodes = s->n_nodes;
    c->n_tris = s->n_tris;
    for (size_t i = 0; i < s->n_nodes; i++) thx_frame_to_ras(f, s->xyz + 3 * i, c->xyz + 3 * i);
    if (s->n_tris) memcpy(c->tri, s->tri, 3 * s->n_tris * sizeof *c->tri);
    *out = c;
    return THX_OK;
}

/* Each electrode's position back in the model's coordinates: its node's. */
static void to_model(thx_electrodes *e, const thx_surface *outer)
{
    for (size_t i = 0; e && i < e->n; i++) memcpy(e->xyz + 3 * i, outer->xyz + 3 * (size_t)e->node[i], 3 * sizeof(double));
}

thx_status thx_phantom_electrodes(thx_ctx *ctx, const thx_model *m, thx_electrodes **leads12, size_t n_array,
                                  thx_electrodes **array)
{
    thx_frame ras = thx_frame_ras();
    return thx_torso_electrodes(ctx, m, m && m->frame.set ? &m->frame : &ras, leads12, n_array, array);
}

static thx_status place(thx_ctx *ctx, const thx_surface *outer, const thx_surface *heart, thx_electrodes **leads12,
                        size_t n_array, thx_electrodes **array);

thx_status thx_torso_electrodes(thx_ctx *ctx, const thx_model *m, const thx_frame *frame, thx_electrodes **leads12,
                                size_t n_array, thx_electrodes **array)
{
    if (leads12) *leads12 = NULL;
    if (array) *array = NULL;
    if (!m) return thx_error(ctx, THX_EINPUT, "electrodes: no model");
    if (!frame) frame = &m->frame;
    THX_CHECK(thx_frame_require(ctx, frame, "the model", "the electrode landmarks"));
    if (!thx_frame_valid(frame)) return thx_error(ctx, THX_EINPUT, "electrodes: the model's frame is not valid");
    const thx_surface *mo = find_role(m, THX_ROLE_OUTER), *mh = find_role(m, THX_ROLE_HEART);
    if (!mo || mo->n_nodes == 0 || mo->n_tris == 0)
        return thx_error(ctx, THX_EINPUT, "electrodes: the model has no outer surface (role \"outer\") to place them on");
    if (!mh || mh->n_nodes == 0)
        return thx_error(ctx, THX_EINPUT,
                         "electrodes: the model has no heart surface (role \"heart\"): the precordial landmarks "
                         "follow the heart's height");
    thx_surface *o = NULL, *h = NULL;
    thx_status st = ras_copy(ctx, mo, frame, &o);
    if (st == THX_OK) st = ras_copy(ctx, mh, frame, &h);
    if (st == THX_OK) st = place(ctx, o, h, leads12, n_array, array);
    if (st == THX_OK) {
        if (leads12) to_model(*leads12, mo);
        if (array) to_model(*array, mo);
    }
    thx_surface_destroy(&o);
    thx_surface_destroy(&h);
    return st;
}

static thx_status place(thx_ctx *ctx, const thx_surface *outer, const thx_surface *heart, thx_electrodes **leads12,
                        size_t n_array, thx_electrodes **array)
{
    if (!outer || outer->n_nodes == 0 || outer->n_tris == 0)
        return thx_error(ctx, THX_EINPUT, "electrodes: the model has no outer surface (role \"outer\") to place them on");
    if (!heart || heart->n_nodes == 0)
        return thx_error(ctx, THX_EINPUT,
                         "electrodes: the model has no heart surface (role \"heart\"): the precordial landmarks "
                         "follow the heart's height");
    double zmin = INFINITY, zmax = -INFINITY;
    for (size_t i = 0; i < outer->n_nodes; i++) {
        zmin = fmin(zmin, outer->xyz[3 * i + 2]);
        zmax = fmax(zmax, outer->xyz[3 * i + 2]);
    }
    if (!(zmax > zmin))
        return thx_error(ctx, THX_EGEOM, "electrodes: the outer surface \"%s\" is flat along its superior axis", outer->name);
    thx_electrodes *e12 = NULL, *ea = NULL;
    if (leads12) THX_CHECK(twelve_lead(ctx, outer, heart, zmin, zmax, &e12));
    if (array && n_array > 0) {
        thx_status st = body_array(ctx, outer, zmin, zmax, n_array, &ea);
        if (st != THX_OK) {
            thx_electrodes_destroy(&e12);
            return st;
        }
    }
    if (leads12) *leads12 = e12;
    if (array) *array = ea;
    return THX_OK;
}
