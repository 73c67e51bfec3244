/*
 * Inside/outside tests by angle sums (paper 3.2, "Inside/Outside algorithm"):
 * planar angles about a point for a closed loop, solid angles for a closed
 * triangle surface. See thorax/geom/inside.h for conventions and tolerances.
 */
#include "thorax/geom/inside.h"
#include "thorax/geom/predicates.h"
#include <math.h>

#define TWO_PI 6.283185307179586476925286766559
#define FOUR_PI 12.566370614359172953850573533118

/* ---------------------------------------------------------------------------
 * 2D
 * ------------------------------------------------------------------------- */

double thx_loop_angle_sum(const thx_vec2 *pts, size_t n, thx_vec2 p)
{
    double sum = 0.0;
    if (n < 2) return 0.0;
    const double pp[2] = {p.x, p.y};
    for (size_t i = 0; i < n; i++) {
        const thx_vec2 a = pts[i], b = pts[(i + 1) % n];
        /* Angle from (a - p) to (b - p) in (-pi, pi]: atan2(cross, dot) is
         * accurate for every angle (acos of a normalized dot is not near 0
         * and pi). The cross product comes from the exact orient2d so that its
         * sign is right even for p extremely close to the edge, where the
         * angle is near +-pi and a wrong sign would change the sum by 2 pi. */
        const double aa[2] = {a.x, a.y}, bb[2] = {b.x, b.y};
        double cross = thx_orient2d(pp, aa, bb);
        double dot = (a.x - p.x) * (b.x - p.x) + (a.y - p.y) * (b.y - p.y);
        sum += atan2(cross, dot);
    }
    return sum;
}

double thx_loop_area(const thx_vec2 *pts, size_t n)
{
    if (n < 3) return 0.0;
    /* Shoelace formula relative to pts[0] (smaller cancellation far from the origin). */
    double s = 0.0, ox = pts[0].x, oy = pts[0].y;
    for (size_t i = 1; i + 1 < n; i++)
        s += (pts[i].x - ox) * (pts[i + 1].y - oy) - (pts[i + 1].x - ox) * (pts[i].y - oy);
    return 0.5 * s;
}

static double seg_dist2(thx_vec2 a, thx_vec2 b, thx_vec2 p)
{
    double ex = b.x - a.x, ey = b.y - a.y, px = p.x - a.x, py = p.y - a.y;
    double l2 = ex * ex + ey * ey, t = 0.0;
    if (l2 > 0.0) {
        t = (px * ex + py * ey) / l2;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    }
    double dx = px - t * ex, dy = py - t * ey;
    return dx * dx + dy * dy;
}

/* Exact test: p on the closed segment [a, b]. */
static int on_segment(thx_vec2 a, thx_vec2 b, thx_vec2 p)
{
    const double aa[2] = {a.x, a.y}, bb[2] = {b.x, b.y}, pp[2] = {p.x, p.y};
    if (thx_orient2d(aa, bb, pp) != 0.0) return 0;
    return p.x >= fmin(a.x, b.x) && p.x <= fmax(a.x, b.x) && p.y >= fmin(a.y, b.y) && p.y <= fmax(a.y, b.y);
}

double thx_loop_distance(const thx_vec2 *pts, size_t n, thx_vec2 p)
{
    if (n == 0) return INFINITY;
    double best = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double d = seg_dist2(pts[i], pts[(i + 1) % n], p);
        if (d < best) best = d;
    }
    return sqrt(best);
}

thx_inside thx_loop_classify(const thx_vec2 *pts, size_t n, thx_vec2 p, double tol, int *winding, double *residual)
{
    if (winding) *winding = 0;
    if (residual) *residual = 0.0;
    if (n == 0) return THX_OUTSIDE;
    for (size_t i = 0; i < n; i++)
        if (on_segment(pts[i], pts[(i + 1) % n], p)) return THX_ON_BOUNDARY;
    if (tol > 0.0 && thx_loop_distance(pts, n, p) < tol) return THX_ON_BOUNDARY;
    double sum = thx_loop_angle_sum(pts, n, p);
    double k = nearbyint(sum / TWO_PI);
    if (winding) *winding = (int)k;
    if (residual) *residual = fabs(sum - k * TWO_PI);
    return k != 0.0 ? THX_INSIDE : THX_OUTSIDE;
}

thx_inside thx_loop_inside(const thx_vec2 *pts, size_t n, thx_vec2 p, double tol)
{
    return thx_loop_classify(pts, n, p, tol, NULL, NULL);
}

/* ---------------------------------------------------------------------------
 * 3D
 * ------------------------------------------------------------------------- */

double thx_triangle_solid_angle(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p)
{
    /* Van Oosterom & Strackee (1983): tan(Omega / 2) = N / D with
     * N = R1 . (R2 x R3), D = r1 r2 r3 + (R1.R2) r3 + (R1.R3) r2 + (R2.R3) r1.
     * atan2 keeps the quadrant, so Omega covers (-2 pi, 2 pi]. N > 0 when p is
     * on the side opposite to the normal (b - a) x (c - a). */
    thx_vec3 r1 = thx_v3_sub(a, p), r2 = thx_v3_sub(b, p), r3 = thx_v3_sub(c, p);
    double l1 = thx_v3_norm(r1), l2 = thx_v3_norm(r2), l3 = thx_v3_norm(r3);
    double num = thx_v3_dot(r1, thx_v3_cross(r2, r3));
    double den = l1 * l2 * l3 + thx_v3_dot(r1, r2) * l3 + thx_v3_dot(r1, r3) * l2 + thx_v3_dot(r2, r3) * l1;
    return 2.0 * atan2(num, den);
}

/* Fixed chunk size for the deterministic parallel sum: the chunks and the
 * order in which their partial sums are added depend only on n_tris. */
#define SA_CHUNK 2048
#define SA_MAX_CHUNKS 256

static double solid_angle_range(const thx_surface *s, thx_vec3 p, size_t t0, size_t t1)
{
    double sum = 0.0;
    for (size_t t = t0; t < t1; t++) {
        const int32_t *v = s->tri + 3 * t;
        sum += thx_triangle_solid_angle(thx_surface_node(s, (size_t)v[0]), thx_surface_node(s, (size_t)v[1]),
                                        thx_surface_node(s, (size_t)v[2]), p);
    }
    return sum;
}

double thx_surface_solid_angle(const thx_surface *s, thx_vec3 p)
{
    size_t n = s->n_tris;
    if (n <= SA_CHUNK) return solid_angle_range(s, p, 0, n);
    size_t chunk = SA_CHUNK;
    if ((n + chunk - 1) / chunk > SA_MAX_CHUNKS) chunk = (n + SA_MAX_CHUNKS - 1) / SA_MAX_CHUNKS;
    long nc = (long)((n + chunk - 1) / chunk);
    double part[SA_MAX_CHUNKS];
#pragma omp parallel for schedule(static) if (n > 16384)
    for (long c = 0; c < nc; c++) {
        size_t t0 = (size_t)c * chunk, t1 = t0 + chunk < n ? t0 + chunk : n;
        part[c] = solid_angle_range(s, p, t0, t1);
    }
    double sum = 0.0;
    for (long c = 0; c < nc; c++) sum += part[c];
    return sum;
}

static double seg3_dist2(thx_vec3 a, thx_vec3 b, thx_vec3 p)
{
    thx_vec3 e = thx_v3_sub(b, a), d = thx_v3_sub(p, a);
    double l2 = thx_v3_dot(e, e), t = 0.0;
    if (l2 > 0.0) {
        t = thx_v3_dot(d, e) / l2;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    }
    thx_vec3 r = thx_v3_sub(d, thx_v3_scale(e, t));
    return thx_v3_dot(r, r);
}

/* Closest distance from p to triangle a, b, c (squared). Regions of the
 * triangle's plane: the vertex, edge and face regions are tested by the
 * barycentric signs of the projection of p. */
static double tri_dist2(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p)
{
    thx_vec3 ab = thx_v3_sub(b, a), ac = thx_v3_sub(c, a), ap = thx_v3_sub(p, a);
    double d1 = thx_v3_dot(ab, ap), d2 = thx_v3_dot(ac, ap);
    thx_vec3 q;
    if (d1 <= 0.0 && d2 <= 0.0) {
        q = a;
    } else {
        thx_vec3 bp = thx_v3_sub(p, b);
        double d3 = thx_v3_dot(ab, bp), d4 = thx_v3_dot(ac, bp);
        thx_vec3 cp = thx_v3_sub(p, c);
        double d5 = thx_v3_dot(ab, cp), d6 = thx_v3_dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) {
            q = b;
        } else if (d6 >= 0.0 && d5 <= d6) {
            q = c;
        } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            q = thx_v3_add(a, thx_v3_scale(ab, d1 / (d1 - d3)));
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            q = thx_v3_add(a, thx_v3_scale(ac, d2 / (d2 - d6)));
        } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
            double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            q = thx_v3_add(b, thx_v3_scale(thx_v3_sub(c, b), w));
        } else {
            double den = va + vb + vc;
            if (den == 0.0) /* degenerate (collinear) triangle: nearest of its edges */
                return fmin(seg3_dist2(a, b, p), fmin(seg3_dist2(b, c, p), seg3_dist2(c, a, p)));
            double v = vb / den, w = vc / den;
            q = thx_v3_add(a, thx_v3_add(thx_v3_scale(ab, v), thx_v3_scale(ac, w)));
        }
    }
    thx_vec3 d = thx_v3_sub(p, q);
    return thx_v3_dot(d, d);
}

double thx_triangle_distance(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p)
{
    return sqrt(tri_dist2(a, b, c, p));
}

double thx_triangle_distance2(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p) { return tri_dist2(a, b, c, p); }

/* Exact test: p lies on the closed triangle a, b, c (coplanar and inside or
 * on its boundary). Projects along the dominant axis of the normal, which is
 * an affine bijection of the plane when p is coplanar. */
static int on_triangle(thx_vec3 a, thx_vec3 b, thx_vec3 c, thx_vec3 p)
{
    const double A[3] = {a.x, a.y, a.z}, B[3] = {b.x, b.y, b.z}, C[3] = {c.x, c.y, c.z}, P[3] = {p.x, p.y, p.z};
    if (thx_orient3d(A, B, C, P) != 0.0) return 0;
    thx_vec3 nrm = thx_v3_cross(thx_v3_sub(b, a), thx_v3_sub(c, a));
    double nx = fabs(nrm.x), ny = fabs(nrm.y), nz = fabs(nrm.z);
    int i0, i1; /* kept coordinates */
    if (nz >= nx && nz >= ny) { i0 = 0; i1 = 1; }
    else if (ny >= nx) { i0 = 2; i1 = 0; }
    else { i0 = 1; i1 = 2; }
    double a2[2] = {A[i0], A[i1]}, b2[2] = {B[i0], B[i1]}, c2[2] = {C[i0], C[i1]}, p2[2] = {P[i0], P[i1]};
    double o = thx_orient2d(a2, b2, c2);
    if (o == 0.0) { /* degenerate triangle: on one of its edges? */
        thx_vec2 u = {a2[0], a2[1]}, v = {b2[0], b2[1]}, w = {c2[0], c2[1]}, q = {p2[0], p2[1]};
        return on_segment(u, v, q) || on_segment(v, w, q) || on_segment(w, u, q);
    }
    double o1 = thx_orient2d(a2, b2, p2), o2 = thx_orient2d(b2, c2, p2), o3 = thx_orient2d(c2, a2, p2);
    if (o < 0) { o1 = -o1; o2 = -o2; o3 = -o3; }
    return o1 >= 0.0 && o2 >= 0.0 && o3 >= 0.0;
}

thx_inside thx_surface_classify(const thx_surface *s, thx_vec3 p, double tol, int *winding, double *residual)
{
    if (winding) *winding = 0;
    if (residual) *residual = 0.0;
    double tol2 = tol * tol;
    for (size_t t = 0; t < s->n_tris; t++) {
        const int32_t *v = s->tri + 3 * t;
        thx_vec3 a = thx_surface_node(s, (size_t)v[0]), b = thx_surface_node(s, (size_t)v[1]),
                 c = thx_surface_node(s, (size_t)v[2]);
        if (tol > 0.0 && tri_dist2(a, b, c, p) < tol2) return THX_ON_BOUNDARY;
        if (on_triangle(a, b, c, p)) return THX_ON_BOUNDARY;
    }
    double sum = thx_surface_solid_angle(s, p);
    double k = nearbyint(sum / FOUR_PI);
    if (winding) *winding = (int)k;
    if (residual) *residual = fabs(sum - k * FOUR_PI);
    return k != 0.0 ? THX_INSIDE : THX_OUTSIDE;
}

thx_inside thx_surface_inside(const thx_surface *s, thx_vec3 p, double tol)
{
    return thx_surface_classify(s, p, tol, NULL, NULL);
}
