/*
 * The synthetic thorax (include/thorax/phantom/phantom.h): smooth anatomy, then a
 * simulated hand digitization of it (paper 3.1).
 *
 * Construction, per layer k (z = 5 k):
 *  1. Smooth outlines, dense closed polylines (~1.5 mm edges), counterclockwise:
 *     - torso, fat, muscle: polar curves r(theta) about the origin; fat and
 *       muscle are the torso curve minus radial thicknesses (>= 9 mm), so
 *       they nest by construction, and the normal gap (radial gap times the
 *       cosine of the angle between radius and normal) stays above the
 *       minimum;
 *     - heart: the plane section of a tilted ellipsoid (exact ellipse);
 *     - lungs: the zero set of an implicit function, traced by marching
 *       squares: "inside the muscle by g_wall AND lateral of the mediastinum
 *       AND away from the heart by g_heart AND above the diaphragm dome AND
 *       below the apex dome", combined with a smooth maximum so the outline
 *       has rounded corners. The crescents of the lower lungs fall out of
 *       the heart and dome terms; they are not drawn by hand.
 *     Every layer is then checked: containment and a minimum distance between
 *     all pairs of outlines (THX_PHANTOM_MIN_GAP); a failure is THX_EINTERNAL.
 *  2. Digitization: points at random arc-length gaps (smaller where the outline
 *     bends), bounded jitter along the normal, random start and direction,
 *     then the layer's (x, y) shift. A loop that came out self-intersecting is
 *     redrawn (deterministically, from the same stream).
 */
#include "thorax/phantom/phantom.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/contours_valid.h"
#include "thorax/geom/predicates.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- layout ------------------------------------------------------------- */

#define LAYER_DZ 5.0    /* mm between layers of the high-resolution phantom (paper 3.1: scans 5 mm apart) */
/* Torso layers k = 0 .. K_TOP (z = 0, below the heart, to 270 mm, the
 * shoulders); even, so both resolutions end on it. Tuned with the torso size
 * so that the high model comes to ~42,000 nodes (thx_phantom_estimate). */
#define K_TOP 54
#define Z_TOP (LAYER_DZ * K_TOP)

enum { S_TORSO = 0, S_FAT, S_MUSCLE, S_LUNG_R, S_LUNG_L, S_HEART };

static const struct {
    const char *name;
    thx_role role;
    thx_cap_method cap;
} SURF[THX_PHANTOM_N_SURFACES] = {
    {"torso", THX_ROLE_OUTER, THX_CAP_GRID},   {"fat", THX_ROLE_FAT, THX_CAP_GRID},
    {"muscle", THX_ROLE_MUSCLE, THX_CAP_GRID}, {"lung_r", THX_ROLE_LUNG, THX_CAP_POLYGON},
    {"lung_l", THX_ROLE_LUNG, THX_CAP_POLYGON}, {"heart", THX_ROLE_HEART, THX_CAP_GRID},
};

/* ---- deterministic random numbers --------------------------------------- */

/* splitmix64 (Steele, Lea, Flood 2014): tiny, full period, good enough for
 * jitter, and identical everywhere (unlike rand()). */
static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

typedef struct { uint64_t s; } rng;

/* One independent stream per (seed, a, b): a loop's points do not depend on
 * how many numbers other loops drew, so the medium phantom (even layers only)
 * reproduces the high phantom's loops exactly. */
static void rng_init(rng *r, uint64_t seed, uint64_t a, uint64_t b)
{
    uint64_t s = seed;
    uint64_t x = splitmix64(&s);
    s = x ^ (a + 0x632BE59BD9B4E019ull);
    x = splitmix64(&s);
    s = x ^ (b + 0x8CB92BA72F3D8DD7ull);
    r->s = splitmix64(&s);
}

static double rng_uniform(rng *r) { return (double)(splitmix64(&r->s) >> 11) * 0x1.0p-53; }

/* Unit-variance bell curve (sum of four uniforms), clipped at +-clip. */
static double rng_bell(rng *r, double clip)
{
    double g = (rng_uniform(r) + rng_uniform(r) + rng_uniform(r) + rng_uniform(r) - 2.0) * 1.7320508075688772;
    return g > clip ? clip : g < -clip ? -clip : g;
}

/* ---- small numeric helpers ---------------------------------------------- */

static double clampd(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }

/* 0 below e0, 1 above e1, smooth in between. */
static double smoothstep(double e0, double e1, double x)
{
    double t = clampd((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

/* Smooth maximum with blending width k (>= max(a, b), so regions only shrink:
 * a clearance guaranteed by max() is kept). */
static double smax(double a, double b, double k)
{
    double h = fmax(k - fabs(a - b), 0.0) / k;
    return fmax(a, b) + h * h * k * 0.25;
}

/* Angle difference wrapped to (-pi, pi]. */
static double dangle(double a, double b)
{
    double d = fmod(a - b, 2.0 * M_PI);
    if (d > M_PI) d -= 2.0 * M_PI;
    if (d <= -M_PI) d += 2.0 * M_PI;
    return d;
}

/* ---- outlines ----------------------------------------------------------- */

/* A dense closed polyline, counterclockwise (positive area), no repeated point. */
typedef struct {
    thx_vec2 *p;
    size_t n;
    double *s;     /* cumulative arc length, n + 1 entries (s[n] = perimeter) */
} outline;

static void outline_free(outline *o)
{
    free(o->p);
    free(o->s);
    memset(o, 0, sizeof *o);
}

static double poly_area(const thx_vec2 *p, size_t n)
{
    double a = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++) a += p[j].x * p[i].y - p[i].x * p[j].y;
    return 0.5 * a;
}

/* Makes the outline counterclockwise and computes its arc lengths. */
static thx_status outline_finish(thx_ctx *ctx, outline *o)
{
    if (poly_area(o->p, o->n) < 0)
        for (size_t i = 0, j = o->n - 1; i < j; i++, j--) {
            thx_vec2 t = o->p[i];
            o->p[i] = o->p[j];
            o->p[j] = t;
        }
    o->s = thx_malloc(ctx, (o->n + 1) * sizeof *o->s);
    if (!o->s) return THX_ENOMEM;
    o->s[0] = 0;
    for (size_t i = 0; i < o->n; i++) {
        thx_vec2 a = o->p[i], b = o->p[(i + 1) % o->n];
        o->s[i + 1] = o->s[i] + hypot(b.x - a.x, b.y - a.y);
    }
    return THX_OK;
}

static double outline_length(const outline *o) { return o->s[o->n]; }

/* Point at arc length t (any real; wrapped). */
static thx_vec2 outline_at(const outline *o, double t)
{
    double L = outline_length(o);
    t = fmod(t, L);
    if (t < 0) t += L;
    size_t lo = 0, hi = o->n;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (o->s[mid] <= t) lo = mid; else hi = mid;
    }
    thx_vec2 a = o->p[lo], b = o->p[(lo + 1) % o->n];
    double seg = o->s[lo + 1] - o->s[lo];
    double u = seg > 0 ? (t - o->s[lo]) / seg : 0;
    thx_vec2 r = {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
    return r;
}

/* Outward unit normal at arc length t (the outline is counterclockwise, so the
 * outside is to the right of the direction of travel). */
static thx_vec2 outline_normal(const outline *o, double t)
{
    thx_vec2 a = outline_at(o, t - 1.0), b = outline_at(o, t + 1.0);
    double dx = b.x - a.x, dy = b.y - a.y, d = hypot(dx, dy);
    thx_vec2 nrm = {d > 0 ? dy / d : 0, d > 0 ? -dx / d : 0};
    return nrm;
}

/* Radius of curvature at arc length t: circumradius of the points at t - w, t, t + w. */
static double outline_radius(const outline *o, double t)
{
    double w = fmin(3.0, outline_length(o) / 8.0);
    thx_vec2 a = outline_at(o, t - w), b = outline_at(o, t), c = outline_at(o, t + w);
    double ab = hypot(b.x - a.x, b.y - a.y), bc = hypot(c.x - b.x, c.y - b.y), ca = hypot(a.x - c.x, a.y - c.y);
    double cr = fabs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
    if (cr < 1e-12) return 1e9;
    return ab * bc * ca / (2.0 * cr);
}

/* Even-odd point-in-polygon test (the outlines are simple; points tested are
 * never near an edge, the gap check below sees to that). */
static int point_in(const thx_vec2 *p, size_t n, thx_vec2 q)
{
    int in = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
        if ((p[i].y > q.y) != (p[j].y > q.y) &&
            q.x < p[j].x + (q.y - p[j].y) * (p[i].x - p[j].x) / (p[i].y - p[j].y))
            in = !in;
    return in;
}

/* Plain sqrt(x^2 + y^2): hypot() guards against overflow we cannot have (mm
 * coordinates) and is several times slower in the marching-squares loop. */
static double len2d(double x, double y) { return sqrt(x * x + y * y); }

static double seg_dist(thx_vec2 q, thx_vec2 a, thx_vec2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? clampd(((q.x - a.x) * dx + (q.y - a.y) * dy) / l2, 0, 1) : 0;
    return len2d(q.x - a.x - t * dx, q.y - a.y - t * dy);
}

/* Smallest distance from the vertices of a to the edges of b, capped at `cap`
 * (a bucket grid of cell size cap over b keeps this linear). With edges
 * shorter than the gaps that matter, min(gap(a,b), gap(b,a)) is the distance
 * between the two outlines, and a crossing would show up as a tiny gap. */
static double vertex_gap(const outline *a, const outline *b, double cap)
{
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (size_t i = 0; i < b->n; i++) {
        x0 = fmin(x0, b->p[i].x); y0 = fmin(y0, b->p[i].y);
        x1 = fmax(x1, b->p[i].x); y1 = fmax(y1, b->p[i].y);
    }
    int nx = (int)((x1 - x0) / cap) + 1, ny = (int)((y1 - y0) / cap) + 1;
    size_t nc = (size_t)nx * (size_t)ny;
    size_t *start = calloc(nc + 1, sizeof *start);
    size_t *items = NULL;
    double best = cap;
    if (!start) return -1;
    /* Two passes: count the edges per cell, then fill (edge i in the cell of its midpoint;
     * edges are short against the cell, so the 3x3 neighbourhood covers them). */
    for (int pass = 0; pass < 2; pass++) {
        size_t *fill = NULL;
        if (pass == 1) {
            for (size_t c = 0; c < nc; c++) start[c + 1] += start[c];
            items = malloc((start[nc] ? start[nc] : 1) * sizeof *items);
            fill = calloc(nc, sizeof *fill);
            if (!items || !fill) { free(fill); free(items); free(start); return -1; }
        }
        for (size_t i = 0; i < b->n; i++) {
            thx_vec2 p = b->p[i], q = b->p[(i + 1) % b->n];
            int cx = (int)((0.5 * (p.x + q.x) - x0) / cap), cy = (int)((0.5 * (p.y + q.y) - y0) / cap);
            cx = cx < 0 ? 0 : cx >= nx ? nx - 1 : cx;
            cy = cy < 0 ? 0 : cy >= ny ? ny - 1 : cy;
            size_t c = (size_t)cy * (size_t)nx + (size_t)cx;
            if (pass == 0) start[c + 1]++;
            else items[start[c] + fill[c]++] = i;
        }
        free(fill);
    }
    for (size_t k = 0; k < a->n; k++) {
        thx_vec2 q = a->p[k];
        int cx = (int)floor((q.x - x0) / cap), cy = (int)floor((q.y - y0) / cap);
        for (int j = cy - 1; j <= cy + 1; j++)
            for (int i = cx - 1; i <= cx + 1; i++) {
                if (i < 0 || j < 0 || i >= nx || j >= ny) continue;
                size_t c = (size_t)j * (size_t)nx + (size_t)i;
                for (size_t m = start[c]; m < start[c + 1]; m++) {
                    size_t e = items[m];
                    double d = seg_dist(q, b->p[e], b->p[(e + 1) % b->n]);
                    if (d < best) best = d;
                }
            }
    }
    free(items);
    free(start);
    return best;
}

/* ---- anatomy: torso, fat, muscle ---------------------------------------- */

/* Torso half-widths by height (mm): ar/al to the subject's right/left, bf/bb
 * to the front/back. Lower thorax near the diaphragm, widest and deepest at
 * mid-chest, shallower toward the shoulders. */
static const struct { double z, ar, al, bf, bb; } TORSO_KEYS[] = {
    {0, 146, 144, 100, 97},     {60, 156, 154, 107, 100},  {130, 165, 163, 112, 103},
    {200, 170, 168, 107, 100},  {260, 174, 172, 97, 95},   {320, 176, 174, 90, 92},
};
#define N_TORSO_KEYS (sizeof TORSO_KEYS / sizeof TORSO_KEYS[0])

typedef struct { double ar, al, bf, bb; } torso_par;

static torso_par torso_at(double z)
{
    size_t i = 0;
    while (i + 2 < N_TORSO_KEYS && z > TORSO_KEYS[i + 1].z) i++;
    double t = smoothstep(TORSO_KEYS[i].z, TORSO_KEYS[i + 1].z, z);
    torso_par p;
    p.ar = TORSO_KEYS[i].ar + t * (TORSO_KEYS[i + 1].ar - TORSO_KEYS[i].ar);
    p.al = TORSO_KEYS[i].al + t * (TORSO_KEYS[i + 1].al - TORSO_KEYS[i].al);
    p.bf = TORSO_KEYS[i].bf + t * (TORSO_KEYS[i + 1].bf - TORSO_KEYS[i].bf);
    p.bb = TORSO_KEYS[i].bb + t * (TORSO_KEYS[i + 1].bb - TORSO_KEYS[i].bb);
    return p;
}

/* Superellipse exponents: rounder chest (2.15), flattened back (2.9). */
#define TORSO_N_FRONT 2.15
#define TORSO_N_BACK 2.9
/* Spine groove: depth and half-width (mm) of the concave posterior midline. */
#define SPINE_DEPTH 10.0
#define SPINE_WIDTH 13.0

static double torso_r(const torso_par *p, double th)
{
    double c = cos(th), s = sin(th);
    double a = c >= 0 ? p->ar : p->al, b = s >= 0 ? p->bf : p->bb, n = s >= 0 ? TORSO_N_FRONT : TORSO_N_BACK;
    double r = pow(pow(fabs(c) / a, n) + pow(fabs(s) / b, n), -1.0 / n);
    double d = dangle(th, -0.5 * M_PI) * p->bb / SPINE_WIDTH;
    return r - SPINE_DEPTH * exp(-d * d);
}

/* Radial thickness of the subcutaneous fat: 9 mm in front, 13 mm at the back. */
static double fat_t(double th)
{
    double s = sin(th), c = cos(th), back = s < 0 ? -s : 0;
    return 9.0 + 4.0 * back + 1.5 * c * c;
}

/* Radial thickness of the skeletal muscle: 12 mm in front, 22 mm at the back
 * (paraspinal muscles), thicker toward the shoulders (pectorals, trapezius). */
static double muscle_t(double th, double z)
{
    double s = sin(th), c = cos(th), back = s < 0 ? -s : 0;
    return 12.0 + 10.0 * back * back + 3.0 * c * c + 8.0 * smoothstep(Z_TOP - 80, Z_TOP, z);
}

/* Radius of shell `which` (S_TORSO, S_FAT, S_MUSCLE) at angle th, height z. */
static double shell_r(int which, const torso_par *p, double th, double z)
{
    double r = torso_r(p, th);
    if (which >= S_FAT) r -= fat_t(th);
    if (which >= S_MUSCLE) r -= muscle_t(th, z);
    return r;
}

#define N_POLAR 720

static thx_status shell_outline(thx_ctx *ctx, int which, double z, outline *o)
{
    torso_par p = torso_at(z);
    o->p = thx_malloc(ctx, N_POLAR * sizeof *o->p);
    if (!o->p) return THX_ENOMEM;
    o->n = N_POLAR;
    for (int i = 0; i < N_POLAR; i++) {
        double th = 2.0 * M_PI * i / N_POLAR, r = shell_r(which, &p, th, z);
        o->p[i].x = r * cos(th);
        o->p[i].y = r * sin(th);
    }
    return outline_finish(ctx, o);
}

/* ---- anatomy: heart ----------------------------------------------------- */

/* Epicardium: an ellipsoid, long axis 2 * 62 mm from the base (posterior,
 * right, superior) toward the apex (anterior, left, inferior: -x, +y, -z in
 * RAS), centred left of the midline and anterior. Semi-axes: 62 along the long
 * axis, 60 horizontal across it, 50 in the remaining direction; its z extent
 * is about 106 mm, of which the layers z = 60..160 carry real loops. */
static const double HEART_C[3] = {-30.0, 12.0, 110.0};
static const double HEART_U[3] = {-0.70, 0.50, -0.50};
#define HEART_A 62.0
#define HEART_B 60.0
#define HEART_CC 50.0
/* Layers whose section is thinner than this (semi-axis, mm) are left out:
 * the end loops must be real loops, not slivers. */
#define HEART_MIN_SEMI 8.0

typedef struct {
    int ok;
    double cx, cy;       /* centre */
    double ra, rb;       /* semi-axes along e1 and its perpendicular */
    double e1x, e1y;     /* unit direction of the first axis */
} ellipse2;

/* The section z = const of the heart ellipsoid, exact: the ellipsoid is
 * d^T M d = 1 with M = sum e_i e_i^T / s_i^2; fixing dz leaves a 2x2 quadratic. */
static ellipse2 heart_section(double z)
{
    double u[3] = {HEART_U[0], HEART_U[1], HEART_U[2]};
    double nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; i++) u[i] /= nu;
    double w[3] = {u[1], -u[0], 0}; /* u x z_hat: horizontal, across the long axis */
    double nw = hypot(w[0], w[1]);
    w[0] /= nw; w[1] /= nw;
    double v[3] = {w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]};
    double M[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            M[i][j] = u[i] * u[j] / (HEART_A * HEART_A) + w[i] * w[j] / (HEART_B * HEART_B) +
                      v[i] * v[j] / (HEART_CC * HEART_CC);
    double dz = z - HEART_C[2];
    double a = M[0][0], b = M[0][1], d = M[1][1], det = a * d - b * b;
    double m0 = M[0][2], m1 = M[1][2];
    /* q0 = -dz M2^-1 m */
    double i00 = d / det, i01 = -b / det, i11 = a / det;
    double q0x = -dz * (i00 * m0 + i01 * m1), q0y = -dz * (i01 * m0 + i11 * m1);
    double rho = 1.0 - dz * dz * M[2][2] + dz * dz * (m0 * (i00 * m0 + i01 * m1) + m1 * (i01 * m0 + i11 * m1));
    ellipse2 e = {0, 0, 0, 0, 0, 1, 0};
    if (rho <= 0) return e;
    double tr = a + d, disc = sqrt(fmax(0.0, 0.25 * (a - d) * (a - d) + b * b));
    double l1 = 0.5 * tr - disc, l2 = 0.5 * tr + disc; /* l1 <= l2: e1 is the long axis */
    double ex = b, ey = l1 - a;
    if (fabs(ex) + fabs(ey) < 1e-15) { ex = l1 - d; ey = b; }
    if (fabs(ex) + fabs(ey) < 1e-15) { ex = 1; ey = 0; }
    double ne = hypot(ex, ey);
    e.ok = 1;
    e.cx = HEART_C[0] + q0x;
    e.cy = HEART_C[1] + q0y;
    e.ra = sqrt(rho / l1);
    e.rb = sqrt(rho / l2);
    e.e1x = ex / ne;
    e.e1y = ey / ne;
    return e;
}

static int heart_present(double z)
{
    ellipse2 e = heart_section(z);
    return e.ok && fmin(e.ra, e.rb) >= HEART_MIN_SEMI;
}

/* Approximate signed distance to an ellipse (negative inside): k0 (k0 - 1) / k1
 * (Quilez), accurate near the curve, which is where it is used (a clearance of
 * ~10 mm); the exact clearance is verified on the outlines afterwards. */
static double ellipse_dist(const ellipse2 *e, double x, double y)
{
    double dx = x - e->cx, dy = y - e->cy;
    double px = dx * e->e1x + dy * e->e1y, py = -dx * e->e1y + dy * e->e1x;
    double k0 = len2d(px / e->ra, py / e->rb), k1 = len2d(px / (e->ra * e->ra), py / (e->rb * e->rb));
    if (k1 < 1e-12) return -fmin(e->ra, e->rb);
    return k0 * (k0 - 1.0) / k1;
}

static thx_status heart_outline(thx_ctx *ctx, double z, outline *o)
{
    ellipse2 e = heart_section(z);
    int n = 360;
    o->p = thx_malloc(ctx, (size_t)n * sizeof *o->p);
    if (!o->p) return THX_ENOMEM;
    o->n = (size_t)n;
    for (int i = 0; i < n; i++) {
        double t = 2.0 * M_PI * i / n, a = e.ra * cos(t), b = e.rb * sin(t);
        o->p[i].x = e.cx + a * e.e1x - b * e.e1y;
        o->p[i].y = e.cy + a * e.e1y + b * e.e1x;
    }
    return outline_finish(ctx, o);
}

/* ---- anatomy: lungs ----------------------------------------------------- */

/* Per lung (index 0 right, +x; 1 left, -x):
 *  dome: the diaphragm under the lung, a paraboloid with its top at (dome_x,
 *        dome_y, dome_z) and radius of curvature dome_R; the lung lies above it,
 *        so low layers lose a growing anteromedial disc and end as posterior-
 *        lateral crescents (costophrenic recesses). The right dome is higher
 *        (liver).
 *  apex: a paraboloid cap with its top apex_dz below the top of the torso. */
static const struct {
    double dome_x, dome_y, dome_z, dome_R;
    double apex_x, apex_y, apex_dz, apex_R;
} LUNG[2] = {
    {22.0, 30.0, 85.0, 75.0, 58.0, -8.0, 28.0, 55.0},
    {-28.0, 25.0, 72.0, 75.0, -58.0, -8.0, 30.0, 55.0},
};
#define LUNG_GAP_WALL 9.5   /* radial clearance from the muscle (mm) */
#define LUNG_GAP_HEART 9.0  /* clearance from the heart (mm) */
#define LUNG_BLEND 6.0      /* smooth-maximum width: rounds the lung's corners */
#define LUNG_MIN_AREA 500.0 /* mm^2: smaller loops are specks between exclusion zones, not lung;
                               a lung's end layers are the outermost with a loop this large */
#define LUNG_GRID 1.25      /* marching-squares step (mm) */

/* Half-width of the mediastinum: 14 mm, 26 mm beside the spine and aorta. */
static double mediastinum_w(double y)
{
    double t = (y + 55.0) / 22.0;
    return 14.0 + 12.0 * exp(-t * t);
}

typedef struct {
    int side;            /* 0 right, 1 left */
    double z;
    double wall[N_POLAR + 1]; /* muscle radius minus clearance, sampled in theta */
    ellipse2 heart;
} lung_fn;

/* Terms are distance-like (slope about 1), so a point where one of them
 * exceeds this is outside, and so are its grid neighbours: its exact value
 * cannot move a crossing and the remaining terms are skipped. */
#define LUNG_EARLY_OUT 8.0

static double lung_f(const lung_fn *L, double x, double y)
{
    double sg = L->side == 0 ? 1.0 : -1.0;
    double f = mediastinum_w(y) - sg * x;
    if (f > LUNG_EARLY_OUT) return f;
    double r = len2d(x, y), th = atan2(y, x);
    if (th < 0) th += 2.0 * M_PI;
    double u = th / (2.0 * M_PI) * N_POLAR;
    int i = (int)u;
    if (i >= N_POLAR) i = N_POLAR - 1;
    double wr = L->wall[i] + (u - i) * (L->wall[i + 1] - L->wall[i]);
    f = smax(f, r - wr, LUNG_BLEND);
    if (f > LUNG_EARLY_OUT) return f;
    if (L->heart.ok) {
        /* The left lung also keeps out of the band in front of the heart (the
         * cardiac notch): the heart's section swept forward to the chest wall,
         * i.e. in front of its centre the distance is taken at the centre's y. */
        double yy = L->side == 1 && y > L->heart.cy ? L->heart.cy : y;
        f = smax(f, LUNG_GAP_HEART - ellipse_dist(&L->heart, x, yy), LUNG_BLEND);
    }
    double dz = LUNG[L->side].dome_z - L->z;
    if (dz > 0) {
        double rho = sqrt(2.0 * LUNG[L->side].dome_R * dz);
        f = smax(f, rho - len2d(x - LUNG[L->side].dome_x, y - LUNG[L->side].dome_y), LUNG_BLEND);
    }
    double az = Z_TOP - LUNG[L->side].apex_dz - L->z;
    double ra = az > 0 ? sqrt(2.0 * LUNG[L->side].apex_R * az) : 0.0;
    if (ra < 400.0) f = smax(f, len2d(x - LUNG[L->side].apex_x, y - LUNG[L->side].apex_y) - ra, LUNG_BLEND);
    return f;
}

/* Traces the region lung_f < 0 by marching squares. Returns the largest loop
 * in *o (o->n = 0 if the region is empty) and the number of loops of at least
 * LUNG_MIN_AREA in *n_loops; smaller loops are specks left between exclusion
 * zones and are dropped. More than one loop is a design error (a split lung
 * or a hole), reported by the caller. */
static thx_status lung_outline(thx_ctx *ctx, int side, double z, outline *o, int *n_loops)
{
    thx_status st = THX_OK;
    lung_fn *L = thx_malloc(ctx, sizeof *L);
    if (!L) return THX_ENOMEM;
    L->side = side;
    L->z = z;
    torso_par tp = torso_at(z);
    for (int i = 0; i <= N_POLAR; i++) {
        double th = 2.0 * M_PI * i / N_POLAR;
        L->wall[i] = shell_r(S_MUSCLE, &tp, th, z) - LUNG_GAP_WALL;
    }
    L->heart = heart_section(z);
    double h = LUNG_GRID, sg = side == 0 ? 1.0 : -1.0;
    double xa = sg * 8.0, xb = sg * (fmax(tp.ar, tp.al) + 4.0);
    double x0 = fmin(xa, xb), x1 = fmax(xa, xb), y0 = -tp.bb - 4.0, y1 = tp.bf + 4.0;
    int nx = (int)ceil((x1 - x0) / h) + 1, ny = (int)ceil((y1 - y0) / h) + 1;
    size_t nn = (size_t)nx * (size_t)ny, ne = 2 * nn;
    double *v = thx_malloc(ctx, nn * sizeof *v);
    int *nb = thx_malloc(ctx, 2 * ne * sizeof *nb);
    unsigned char *seen = thx_calloc(ctx, ne, 1);
    thx_vec2 *pts = NULL, *best = NULL;
    size_t npts = 0, cap = 0, nbest = 0;
    double best_area = 0;
    *n_loops = 0;
    memset(o, 0, sizeof *o);
    if (!v || !nb || !seen) { st = THX_ENOMEM; goto done; }
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            double f = lung_f(L, x0 + i * h, y0 + j * h);
            /* The frame is outside, so every contour closes; no value is exactly
             * zero, so every crossing lies strictly inside an edge. */
            if (i == 0 || j == 0 || i == nx - 1 || j == ny - 1) f = fmax(f, 1.0);
            if (f == 0) f = 1e-9;
            v[(size_t)j * nx + i] = f;
        }
    for (size_t e = 0; e < 2 * ne; e++) nb[e] = -1;
#define HE(i, j) ((int)((size_t)(j) * nx + (i)))
#define VE(i, j) ((int)(nn + (size_t)(j) * nx + (i)))
#define LINK(a, b) do { int a_ = (a), b_ = (b); nb[2 * a_ + (nb[2 * a_] >= 0)] = b_; nb[2 * b_ + (nb[2 * b_] >= 0)] = a_; } while (0)
    for (int j = 0; j + 1 < ny; j++)
        for (int i = 0; i + 1 < nx; i++) {
            double v00 = v[HE(i, j)], v10 = v[HE(i + 1, j)], v11 = v[HE(i + 1, j + 1)], v01 = v[HE(i, j + 1)];
            int c = (v00 < 0) | (v10 < 0) << 1 | (v11 < 0) << 2 | (v01 < 0) << 3;
            if (c == 0 || c == 15) continue;
            int eb = HE(i, j), er = VE(i + 1, j), et = HE(i, j + 1), el = VE(i, j);
            if (c == 5 || c == 10) {
                /* Saddle: the centre value decides which corners are joined. */
                double vc = 0.25 * (v00 + v10 + v11 + v01);
                if ((vc < 0) == (v00 < 0)) { LINK(eb, er); LINK(et, el); }
                else { LINK(el, eb); LINK(er, et); }
                continue;
            }
            int cross[4], k = 0;
            if ((v00 < 0) != (v10 < 0)) cross[k++] = eb;
            if ((v10 < 0) != (v11 < 0)) cross[k++] = er;
            if ((v11 < 0) != (v01 < 0)) cross[k++] = et;
            if ((v01 < 0) != (v00 < 0)) cross[k++] = el;
            if (k == 2) LINK(cross[0], cross[1]);
        }
    /* Walk the loops. */
    for (size_t e0 = 0; e0 < ne; e0++) {
        if (nb[2 * e0] < 0 || seen[e0]) continue;
        npts = 0;
        int prev = -1, cur = (int)e0;
        do {
            seen[cur] = 1;
            int vertical = (size_t)cur >= nn;
            size_t id = vertical ? (size_t)cur - nn : (size_t)cur;
            int i = (int)(id % (size_t)nx), j = (int)(id / (size_t)nx);
            double va = v[HE(i, j)], vb = vertical ? v[HE(i, j + 1)] : v[HE(i + 1, j)];
            double t = va / (va - vb);
            thx_vec2 q = {x0 + (i + (vertical ? 0 : t)) * h, y0 + (j + (vertical ? t : 0)) * h};
            if (npts + 1 > cap) {
                size_t ncap = cap ? 2 * cap : 1024;
                thx_vec2 *np = thx_realloc(ctx, pts, ncap * sizeof *np);
                if (!np) { st = THX_ENOMEM; goto done; }
                pts = np;
                cap = ncap;
            }
            /* Crossings that fall on one grid node coincide: keep one. */
            if (npts == 0 || hypot(q.x - pts[npts - 1].x, q.y - pts[npts - 1].y) > 1e-6) pts[npts++] = q;
            int nxt = nb[2 * cur] != prev ? nb[2 * cur] : nb[2 * cur + 1];
            prev = cur;
            cur = nxt;
        } while (cur != (int)e0 && cur >= 0);
        if (cur < 0) { st = thx_error(ctx, THX_EINTERNAL, "phantom: open lung contour"); goto done; }
        while (npts > 1 && hypot(pts[0].x - pts[npts - 1].x, pts[0].y - pts[npts - 1].y) <= 1e-6) npts--;
        if (npts < 3) continue;
        double a = fabs(poly_area(pts, npts));
        if (a < LUNG_MIN_AREA) continue; /* a speck between exclusion zones, not anatomy */
        (*n_loops)++;
        if (a > best_area) { /* keep this loop; the next one gets a fresh buffer */
            free(best);
            best = pts;
            nbest = npts;
            best_area = a;
            pts = NULL;
            cap = 0;
        }
    }
#undef HE
#undef VE
#undef LINK
    if (best) {
        o->p = best;
        o->n = nbest;
        best = NULL;
        st = outline_finish(ctx, o);
    }
done:
    free(best);
    free(pts);
    free(seen);
    free(nb);
    free(v);
    free(L);
    return st;
}

/* ---- the smooth phantom: one layer at a time ----------------------------- */

typedef struct {
    int first[THX_PHANTOM_N_SURFACES], last[THX_PHANTOM_N_SURFACES]; /* layer ranges, k */
} layer_plan;

/* Layer ranges. The shells nest by two layers (10 mm) so that their caps are
 * separate planes at both resolutions; heart and lungs occupy the even-ended
 * range of layers where their section is substantial, so that the medium
 * phantom (even layers) ends on the same layers. */
static thx_status make_plan(thx_ctx *ctx, layer_plan *pl)
{
    pl->first[S_TORSO] = 0;      pl->last[S_TORSO] = K_TOP;
    pl->first[S_FAT] = 2;        pl->last[S_FAT] = K_TOP - 2;
    pl->first[S_MUSCLE] = 4;     pl->last[S_MUSCLE] = K_TOP - 4;
    int lo = -1, hi = -1;
    for (int k = 0; k <= K_TOP; k++)
        if (heart_present(LAYER_DZ * k)) {
            if (lo < 0) lo = k;
            hi = k;
        }
    if (lo < 0) return thx_error(ctx, THX_EINTERNAL, "phantom: the heart has no layer");
    pl->first[S_HEART] = lo + (lo & 1);
    pl->last[S_HEART] = hi - (hi & 1);
    for (int side = 0; side < 2; side++) {
        /* Scan inward from both ends of the muscle (two layers inside it, for
         * separate caps); the layers in between are checked when built. */
        lo = hi = -1;
        for (int dir = 0; dir < 2; dir++) {
            int k0 = dir == 0 ? pl->first[S_MUSCLE] + 2 : pl->last[S_MUSCLE] - 2, dk = dir == 0 ? 1 : -1;
            for (int k = k0; k >= pl->first[S_MUSCLE] + 2 && k <= pl->last[S_MUSCLE] - 2; k += dk) {
                outline o;
                int nl;
                THX_CHECK(lung_outline(ctx, side, LAYER_DZ * k, &o, &nl));
                outline_free(&o);
                if (nl == 1) {
                    if (dir == 0) lo = k; else hi = k;
                    break;
                }
            }
        }
        if (lo < 0 || hi < lo + 4) return thx_error(ctx, THX_EINTERNAL, "phantom: lung %d has too few layers", side);
        pl->first[S_LUNG_R + side] = lo + (lo & 1);
        pl->last[S_LUNG_R + side] = hi - (hi & 1);
    }
    return THX_OK;
}

typedef struct {
    int present[THX_PHANTOM_N_SURFACES];
    outline o[THX_PHANTOM_N_SURFACES];
} smooth_layer;

static void smooth_layer_free(smooth_layer *L)
{
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) outline_free(&L->o[s]);
}

/* Pairs that must keep their distance: (outer, inner) nested, or disjoint. */
static const struct { int a, b, nested; } PAIRS[] = {
    {S_TORSO, S_FAT, 1},     {S_FAT, S_MUSCLE, 1},     {S_MUSCLE, S_LUNG_R, 1}, {S_MUSCLE, S_LUNG_L, 1},
    {S_MUSCLE, S_HEART, 1},  {S_LUNG_R, S_LUNG_L, 0},  {S_LUNG_R, S_HEART, 0},  {S_LUNG_L, S_HEART, 0},
};

/* Builds the smooth outlines of layer k and checks nesting and gaps; the
 * smallest gap found is folded into *min_gap. */
static thx_status smooth_layer_build(thx_ctx *ctx, const layer_plan *pl, int k, smooth_layer *L, double *min_gap)
{
    thx_status st = THX_OK;
    double z = LAYER_DZ * k;
    memset(L, 0, sizeof *L);
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) {
        if (k < pl->first[s] || k > pl->last[s]) continue;
        L->present[s] = 1;
        if (s <= S_MUSCLE) THX_TRY(shell_outline(ctx, s, z, &L->o[s]));
        else if (s == S_HEART) THX_TRY(heart_outline(ctx, z, &L->o[s]));
        else {
            int nl;
            THX_TRY(lung_outline(ctx, s - S_LUNG_R, z, &L->o[s], &nl));
            if (nl != 1) {
                st = thx_error(ctx, THX_EINTERNAL, "phantom: surface \"%s\" layer z=%g: %d loops (expected 1)",
                               SURF[s].name, z, nl);
                goto done;
            }
        }
    }
    for (size_t i = 0; i < sizeof PAIRS / sizeof PAIRS[0]; i++) {
        int a = PAIRS[i].a, b = PAIRS[i].b;
        if (!L->present[a] || !L->present[b]) continue;
        const outline *A = &L->o[a], *B = &L->o[b];
        int b_in_a = point_in(A->p, A->n, B->p[0]), a_in_b = point_in(B->p, B->n, A->p[0]);
        int ok = PAIRS[i].nested ? b_in_a : (!b_in_a && !a_in_b);
        double g1 = vertex_gap(A, B, 8.0), g2 = vertex_gap(B, A, 8.0);
        if (g1 < 0 || g2 < 0) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); goto done; }
        double g = fmin(g1, g2);
        if (g < *min_gap) *min_gap = g;
        if (!ok || g < THX_PHANTOM_MIN_GAP) {
            st = thx_error(ctx, THX_EINTERNAL, "phantom: layer z=%g: surfaces \"%s\" and \"%s\" %s (gap %.2f mm)", z,
                           SURF[a].name, SURF[b].name, ok ? "come too close" : "are not nested as designed", g);
            goto done;
        }
    }
done:
    if (st != THX_OK) smooth_layer_free(L);
    return st;
}

/* ---- digitization -------------------------------------------------------- */


/* Is the closed polygon simple (no two non-adjacent edges touching, no
 * repeated consecutive point, no fold-back)? O(n^2): loops have < 300 points. */
static int loop_simple(const thx_vec2 *p, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        thx_vec2 a = p[i], b = p[(i + 1) % n], c = p[(i + 2) % n];
        if (a.x == b.x && a.y == b.y) return 0;
        if (thx_orient2d(&a.x, &b.x, &c.x) == 0 && (a.x - b.x) * (c.x - b.x) + (a.y - b.y) * (c.y - b.y) > 0) return 0;
    }
    for (size_t i = 0; i < n; i++) {
        thx_vec2 a = p[i], b = p[(i + 1) % n];
        double x0 = fmin(a.x, b.x), x1 = fmax(a.x, b.x), y0 = fmin(a.y, b.y), y1 = fmax(a.y, b.y);
        for (size_t j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1) continue;
            thx_vec2 c = p[j], d = p[(j + 1) % n];
            /* Disjoint bounding boxes cannot touch: skips almost every pair. */
            if (fmax(c.x, d.x) < x0 || fmin(c.x, d.x) > x1 || fmax(c.y, d.y) < y0 || fmin(c.y, d.y) > y1) continue;
            if (thx_segments_touch(&a.x, &b.x, &c.x, &d.x)) return 0;
        }
    }
    return 1;
}

/* Largest jitter (mm): the outlines are THX_PHANTOM_MIN_GAP apart, each side
 * may move by this much, and the rest must stay a clear gap. */
#define JITTER_MAX 1.5
#define SHIFT_CLIP 2.5 /* shifts and jitter are clipped at 2.5 standard deviations */

/* Digitizes one outline: random start, random gaps along the arc (between
 * 35% and 100% of an upper bound of R/10 clamped to 2.5..8 mm, R the local
 * radius of curvature: a hand puts more points into bends and fewer along
 * straight stretches), jitter along the normal, then the layer's shift
 * (dx, dy), and a random direction. */
static thx_status digitize(thx_ctx *ctx, const outline *o, rng *r, double jitter, double dx, double dy,
                           thx_vec2 **out, size_t *n_out)
{
    double L = outline_length(o);
    size_t cap = (size_t)(L / 0.8) + 16;
    thx_vec2 *p = thx_malloc(ctx, cap * sizeof *p);
    if (!p) return THX_ENOMEM;
    for (int attempt = 0;; attempt++) {
        /* After a few failed draws the loop is drawn without jitter: the
         * smooth outline is simple, so this always ends. */
        double jit = attempt < 8 ? jitter : 0.0;
        double s0 = rng_uniform(r) * L, s = s0;
        size_t n = 0;
        for (;;) {
            double R = outline_radius(o, s);
            double gmax = fmin(clampd(0.1 * R, 2.5, 8.0), L / 10.0);
            double gap = gmax * (0.35 + 0.65 * rng_uniform(r));
            thx_vec2 q = outline_at(o, s), nrm = outline_normal(o, s);
            double j = jit * rng_bell(r, SHIFT_CLIP);
            double jmax = fmin(JITTER_MAX, 0.25 * R);
            j = clampd(j, -jmax, jmax);
            if (n >= cap) break; /* cannot happen: gaps are >= 0.875 mm or L / 30 */
            p[n].x = q.x + j * nrm.x + dx;
            p[n].y = q.y + j * nrm.y + dy;
            n++;
            /* Stop so that the closing edge is not much shorter than a gap. */
            if (s + gap > s0 + L - 0.4 * gap) break;
            s += gap;
        }
        int clockwise = rng_uniform(r) < 0.5;
        if (clockwise)
            for (size_t i = 0, k = n - 1; i < k; i++, k--) {
                thx_vec2 t = p[i];
                p[i] = p[k];
                p[k] = t;
            }
        if (n >= 3 && loop_simple(p, n)) {
            *out = p;
            *n_out = n;
            return THX_OK;
        }
        if (attempt > 8) break;
    }
    free(p);
    return thx_error(ctx, THX_EINTERNAL, "phantom: could not digitize a simple loop");
}

/* ---- public ------------------------------------------------------------- */

void thx_phantom_opts_default(thx_phantom_opts *o)
{
    memset(o, 0, sizeof *o);
    o->resolution = THX_PHANTOM_MEDIUM;
    o->seed = 1;
    o->jitter_mm = 0.6;
    o->shift_mm = 1.0;
}

double thx_phantom_spacing(int resolution) { return resolution == THX_PHANTOM_HIGH ? 5.0 : 11.0; }

static thx_status check_opts(thx_ctx *ctx, const thx_phantom_opts *o)
{
    if (o->resolution != THX_PHANTOM_HIGH && o->resolution != THX_PHANTOM_MEDIUM)
        return thx_error(ctx, THX_EINPUT, "phantom: unknown resolution %d", o->resolution);
    if (!(o->jitter_mm >= 0 && o->jitter_mm <= 5))
        return thx_error(ctx, THX_EINPUT, "phantom: jitter %g mm is outside 0..5", o->jitter_mm);
    if (!(o->shift_mm >= 0 && o->shift_mm <= 20))
        return thx_error(ctx, THX_EINPUT, "phantom: layer shift %g mm is outside 0..20", o->shift_mm);
    return THX_OK;
}

/* Layers of the resolution: all (high) or the even ones (medium). */
static int layer_step(int resolution) { return resolution == THX_PHANTOM_HIGH ? 1 : 2; }

thx_status thx_phantom_contours(thx_ctx *ctx, const thx_phantom_opts *o, thx_contours **out)
{
    thx_status st = THX_OK;
    thx_contours *c = NULL;
    layer_plan pl;
    thx_vec2 *pts = NULL;
    *out = NULL;
    THX_CHECK(check_opts(ctx, o));
    THX_CHECK(make_plan(ctx, &pl));
    THX_TRY(thx_contours_create(ctx, &c));
    c->spacing = thx_phantom_spacing(o->resolution);
    c->frame = thx_frame_ras(); /* the phantom is drawn in RAS: +z superior, +y anterior */
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++)
        THX_TRY(thx_contours_add_surface(ctx, c, SURF[s].name, SURF[s].role, SURF[s].cap, 0.0, NULL));
    double min_gap = 1e9;
    for (int k = 0; k <= K_TOP; k += layer_step(o->resolution)) {
        smooth_layer L;
        THX_TRY(smooth_layer_build(ctx, &pl, k, &L, &min_gap));
        rng shift_rng;
        rng_init(&shift_rng, o->seed, (uint64_t)k, 0xFFFF);
        double dx = o->shift_mm * rng_bell(&shift_rng, SHIFT_CLIP);
        double dy = o->shift_mm * rng_bell(&shift_rng, SHIFT_CLIP);
        for (int s = 0; s < THX_PHANTOM_N_SURFACES && st == THX_OK; s++) {
            if (!L.present[s]) continue;
            rng r;
            rng_init(&r, o->seed, (uint64_t)k, (uint64_t)s + 1);
            size_t n = 0;
            st = digitize(ctx, &L.o[s], &r, o->jitter_mm, dx, dy, &pts, &n);
            if (st == THX_OK) st = thx_contours_add_loop(ctx, c, (size_t)s, LAYER_DZ * k, pts, n);
            free(pts);
            pts = NULL;
        }
        smooth_layer_free(&L);
        if (st != THX_OK) goto done;
    }
    c->n_layers = (size_t)(K_TOP / layer_step(o->resolution) + 1);
    st = thx_contours_validate(ctx, c);
    if (st != THX_OK) {
        char msg[512];
        snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
        st = thx_error(ctx, THX_EINTERNAL, "phantom: generated contours are invalid: %s", msg);
    }
done:
    if (st != THX_OK) thx_contours_destroy(&c);
    *out = c;
    return st;
}

thx_status thx_phantom_estimate(thx_ctx *ctx, const thx_phantom_opts *o, thx_phantom_counts *out)
{
    layer_plan pl;
    memset(out, 0, sizeof *out);
    THX_CHECK(check_opts(ctx, o));
    THX_CHECK(make_plan(ctx, &pl));
    double S = thx_phantom_spacing(o->resolution);
    int step = layer_step(o->resolution);
    out->min_gap = 1e9;
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) {
        snprintf(out->surf[s].name, sizeof out->surf[s].name, "%s", SURF[s].name);
        out->surf[s].first_layer = pl.first[s];
        out->surf[s].last_layer = pl.last[s];
    }
    for (int k = 0; k <= K_TOP; k += step) {
        smooth_layer L;
        THX_CHECK(smooth_layer_build(ctx, &pl, k, &L, &out->min_gap));
        out->layers++;
        for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) {
            if (!L.present[s]) continue;
            thx_phantom_surface_count *sc = &out->surf[s];
            double len = outline_length(&L.o[s]);
            long nodes = lround(len / S);
            sc->layers++;
            sc->loop_nodes += (size_t)(nodes < 3 ? 3 : nodes);
            if (SURF[s].cap == THX_CAP_GRID && (k == pl.first[s] || k == pl.last[s]))
                sc->cap_nodes += (size_t)lround(poly_area(L.o[s].p, L.o[s].n) / (S * S));
            out->loops++;
        }
        smooth_layer_free(&L);
    }
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) {
        thx_phantom_surface_count *sc = &out->surf[s];
        sc->nodes = sc->loop_nodes + sc->cap_nodes;
        sc->triangles = 2 * sc->nodes - 4;
        out->loop_nodes += sc->loop_nodes;
        out->cap_nodes += sc->cap_nodes;
        out->nodes += sc->nodes;
        out->triangles += sc->triangles;
    }
    return THX_OK;
}

/* ---- the smooth anatomy as a point test (the phantom as a scan) --------- */

/* The solid of each surface, between its first and last layer (flat caps on those planes, as the
 * surfaces built from the contours have): torso, fat and muscle r < R(theta, z) of their polar
 * curves; the heart inside its ellipsoid; a lung where lung_f < 0 (the function whose zero set
 * lung_outline traces on the layers). A point's region is 0 outside the torso, else 1 + the
 * index of the innermost surface holding it. */
struct thx_phantom_field {
    layer_plan pl;
};

struct thx_phantom_plane {
    double z;
    int on[THX_PHANTOM_N_SURFACES]; /* z within the surface's slab */
    torso_par tp;
    ellipse2 heart;
    lung_fn lung[2];
    /* bounds on the plane (1 mm beyond the extremes of 720 samples in theta, which the curves
     * cannot pass between samples by more than ~0.01 mm): r >= r_out is outside the torso, r < r_in
     * inside the innermost shell present; between them the shells are evaluated */
    double r_in, r_out;
    int inner; /* that innermost shell */
};

thx_status thx_phantom_field_create(thx_ctx *ctx, thx_phantom_field **out)
{
    *out = NULL;
    thx_phantom_field *f = thx_calloc(ctx, 1, sizeof *f);
    if (!f) return THX_ENOMEM;
    thx_status st = make_plan(ctx, &f->pl);
    if (st != THX_OK) {
        free(f);
        return st;
    }
    *out = f;
    return THX_OK;
}

void thx_phantom_field_destroy(thx_phantom_field **f)
{
    if (!f || !*f) return;
    free(*f);
    *f = NULL;
}

void thx_phantom_slab(const thx_phantom_field *f, int surface, double *z0, double *z1)
{
    *z0 = LAYER_DZ * f->pl.first[surface];
    *z1 = LAYER_DZ * f->pl.last[surface];
}

void thx_phantom_bounds(const thx_phantom_field *f, double lo[3], double hi[3])
{
    /* The torso's half-widths are the largest at any height (the spine groove only takes away). */
    lo[0] = lo[1] = 1e300;
    hi[0] = hi[1] = -1e300;
    for (int k = 0; k <= 4 * K_TOP; k++) {
        torso_par p = torso_at(0.25 * LAYER_DZ * k);
        lo[0] = fmin(lo[0], -p.al);
        hi[0] = fmax(hi[0], p.ar);
        lo[1] = fmin(lo[1], -p.bb);
        hi[1] = fmax(hi[1], p.bf);
    }
    thx_phantom_slab(f, S_TORSO, &lo[2], &hi[2]);
}

thx_status thx_phantom_plane_create(thx_ctx *ctx, const thx_phantom_field *f, double z, thx_phantom_plane **out)
{
    thx_phantom_plane *P = thx_calloc(ctx, 1, sizeof *P);
    *out = P;
    if (!P) return THX_ENOMEM;
    thx_phantom_plane_set(f, z, P);
    return THX_OK;
}

void thx_phantom_plane_set(const thx_phantom_field *f, double z, thx_phantom_plane *P)
{
    P->z = z;
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++)
        P->on[s] = z >= LAYER_DZ * f->pl.first[s] && z <= LAYER_DZ * f->pl.last[s];
    P->tp = torso_at(z);
    P->inner = P->on[S_MUSCLE] ? S_MUSCLE : P->on[S_FAT] ? S_FAT : S_TORSO;
    P->heart = heart_section(z);
    if (!P->heart.ok) P->on[S_HEART] = 0;
    for (int side = 0; side < 2; side++) {
        P->lung[side].side = side;
        P->lung[side].z = z;
        P->lung[side].heart = P->heart;
    }
    P->r_in = P->r_out = 0;
    if (!P->on[S_TORSO]) return; /* the lungs and heart lie inside the torso's slab */
    /* the shells at the samples theta_i, each radius once (the same operations as shell_r, so the
       lungs' walls are the values lung_outline uses, bit for bit) */
    double mn = 1e300, mx = 0;
    for (int i = 0; i <= N_POLAR; i++) {
        double th = 2.0 * M_PI * i / N_POLAR, r[3];
        r[S_TORSO] = torso_r(&P->tp, th);
        r[S_FAT] = r[S_TORSO] - fat_t(th);
        r[S_MUSCLE] = r[S_FAT] - muscle_t(th, z);
        if (i < N_POLAR) {
            mx = fmax(mx, r[S_TORSO]);
            mn = fmin(mn, r[P->inner]);
        }
        for (int side = 0; side < 2; side++)
            if (P->on[S_LUNG_R + side]) P->lung[side].wall[i] = r[S_MUSCLE] - LUNG_GAP_WALL;
    }
    P->r_out = mx + 1.0;
    P->r_in = fmax(0.0, mn - 1.0);
}

void thx_phantom_plane_destroy(thx_phantom_plane **P)
{
    if (!P) return;
    free(*P);
    *P = NULL;
}

int thx_phantom_region(const thx_phantom_plane *P, double x, double y)
{
    if (P->on[S_HEART]) {
        const ellipse2 *e = &P->heart;
        double dx = x - e->cx, dy = y - e->cy;
        double px = (dx * e->e1x + dy * e->e1y) / e->ra, py = (-dx * e->e1y + dy * e->e1x) / e->rb;
        if (px * px + py * py < 1.0) return 1 + S_HEART;
    }
    for (int side = 0; side < 2; side++)
        if (P->on[S_LUNG_R + side] && lung_f(&P->lung[side], x, y) < 0) return 1 + S_LUNG_R + side;
    if (!P->on[S_TORSO]) return 0;
    double r = len2d(x, y);
    if (r >= P->r_out) return 0;
    if (r < P->r_in) return 1 + P->inner;
    double th = atan2(y, x);
    double R = torso_r(&P->tp, th);
    if (r >= R) return 0;
    if (!P->on[S_FAT]) return 1 + S_TORSO;
    R -= fat_t(th);
    if (r >= R) return 1 + S_TORSO;
    if (!P->on[S_MUSCLE]) return 1 + S_FAT;
    R -= muscle_t(th, P->z);
    return r >= R ? 1 + S_FAT : 1 + S_MUSCLE;
}

/* Area enclosed by surface s on the plane z: the shells by the trapezoid rule in theta (periodic and
 * smooth: the error falls fast with the number of samples), the heart's ellipse exactly, a lung the
 * polygon lung_outline traces (marching squares at LUNG_GRID: the contour model's own outline). */
static thx_status section_area(thx_ctx *ctx, int s, double z, double *area)
{
    *area = 0;
    if (s <= S_MUSCLE) {
        torso_par p = torso_at(z);
        const int n = 8192;
        double sum = 0;
        for (int i = 0; i < n; i++) {
            double r = shell_r(s, &p, 2.0 * M_PI * i / n, z);
            sum += r * r;
        }
        *area = 0.5 * sum * (2.0 * M_PI / n);
    } else if (s == S_HEART) {
        ellipse2 e = heart_section(z);
        if (e.ok) *area = M_PI * e.ra * e.rb;
    } else {
        outline o;
        int nl;
        THX_CHECK(lung_outline(ctx, s - S_LUNG_R, z, &o, &nl));
        if (o.n) *area = fabs(poly_area(o.p, o.n));
        outline_free(&o);
    }
    return THX_OK;
}

thx_status thx_phantom_volumes(thx_ctx *ctx, const thx_phantom_field *f, double dz, double vol[THX_PHANTOM_N_SURFACES])
{
    for (int s = 0; s < THX_PHANTOM_N_SURFACES; s++) {
        double z0 = LAYER_DZ * f->pl.first[s], z1 = LAYER_DZ * f->pl.last[s];
        long n = lround(ceil((z1 - z0) / dz / 2.0)) * 2; /* even: Simpson */
        double h = (z1 - z0) / (double)n, sum = 0;
        for (long i = 0; i <= n; i++) {
            double a;
            THX_CHECK(section_area(ctx, s, z0 + h * (double)i, &a));
            sum += a * (i == 0 || i == n ? 1.0 : i % 2 ? 4.0 : 2.0);
        }
        vol[s] = sum * h / 3.0;
    }
    return THX_OK;
}

thx_status thx_phantom_section(thx_ctx *ctx, const thx_phantom_field *f, int surface, double z, thx_vec2 **pts,
                               size_t *n)
{
    *pts = NULL;
    *n = 0;
    if (surface < 0 || surface >= THX_PHANTOM_N_SURFACES)
        return thx_error(ctx, THX_EINPUT, "phantom: no surface %d", surface);
    if (z < LAYER_DZ * f->pl.first[surface] || z > LAYER_DZ * f->pl.last[surface]) return THX_OK;
    outline o;
    memset(&o, 0, sizeof o);
    int nl = 0;
    thx_status st;
    if (surface <= S_MUSCLE) st = shell_outline(ctx, surface, z, &o);
    else if (surface == S_HEART) st = heart_section(z).ok ? heart_outline(ctx, z, &o) : THX_OK;
    else st = lung_outline(ctx, surface - S_LUNG_R, z, &o, &nl);
    if (st != THX_OK) {
        outline_free(&o);
        return st;
    }
    free(o.s);
    *pts = o.p;
    *n = o.n;
    return THX_OK;
}
