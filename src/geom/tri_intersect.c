/*
 * Exact triangle-triangle intersection (thorax/geom/tri_intersect.h): used by the lacing's own
 * test for crossing triangles (build.c) and by the surface checker (src/check/check.c).
 */
#include "thorax/geom/tri_intersect.h"

#include <math.h>
#include <stddef.h>

#include "thorax/geom/predicates.h"

/* Exact geometric tests. Every decision below is a sign of thx_orient3d or
 * thx_orient2d, so it is exact for the given doubles. Triangles passed here
 * are non-degenerate (not collinear), which the callers guarantee. */

static int sgn(double x) { return (x > 0) - (x < 0); }

static double o3(const double *a, const double *b, const double *c, const double *d)
{
    return thx_orient3d(a, b, c, d);
}

/* Coordinates of p in the plane that drops axis `ax`. */
static void proj(const double *p, int ax, double out[2])
{
    out[0] = p[(ax + 1) % 3];
    out[1] = p[(ax + 2) % 3];
}

/* An axis along which the projection of the (non-degenerate) triangle a, b, c
 * keeps a non-zero area (exact), preferring the largest: projecting a
 * coplanar configuration along it is an affine bijection of the plane, so
 * every orient2d sign of projected points is that of the configuration. */
static int plane_axis(const double *a, const double *b, const double *c)
{
    int best = -1;
    double bestv = 0.0;
    for (int ax = 0; ax < 3; ax++) {
        double pa[2], pb[2], pc[2];
        proj(a, ax, pa);
        proj(b, ax, pb);
        proj(c, ax, pc);
        double v = fabs(thx_orient2d(pa, pb, pc));
        if (v > bestv) {
            bestv = v;
            best = ax;
        }
    }
    return best; /* -1 only for a collinear triangle */
}

int thx_collinear3(const double *a, const double *b, const double *c) { return plane_axis(a, b, c) < 0; }

/* p on the closed segment a-b, given that p, a, b are collinear. */
static int on_segment2(const double *p, const double *a, const double *b)
{
    return fmin(a[0], b[0]) <= p[0] && p[0] <= fmax(a[0], b[0]) && fmin(a[1], b[1]) <= p[1] &&
           p[1] <= fmax(a[1], b[1]);
}

/* Closed segments a-b and c-d meet (2D). */
static int seg_seg2(const double *a, const double *b, const double *c, const double *d)
{
    int o1 = sgn(thx_orient2d(a, b, c)), o2 = sgn(thx_orient2d(a, b, d));
    int o3_ = sgn(thx_orient2d(c, d, a)), o4 = sgn(thx_orient2d(c, d, b));
    if (o1 * o2 < 0 && o3_ * o4 < 0) return 1;
    if (o1 == 0 && on_segment2(c, a, b)) return 1;
    if (o2 == 0 && on_segment2(d, a, b)) return 1;
    if (o3_ == 0 && on_segment2(a, c, d)) return 1;
    if (o4 == 0 && on_segment2(b, c, d)) return 1;
    return 0;
}

/* p in the closed triangle a, b, c (2D, non-degenerate, either orientation). */
static int point_in_tri2(const double *p, const double *a, const double *b, const double *c)
{
    int s1 = sgn(thx_orient2d(a, b, p)), s2 = sgn(thx_orient2d(b, c, p)), s3 = sgn(thx_orient2d(c, a, p));
    return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

/* Closed segment e0-e1 meets closed triangle t (2D). */
static int seg_tri2(const double *e0, const double *e1, double t[3][2])
{
    if (point_in_tri2(e0, t[0], t[1], t[2]) || point_in_tri2(e1, t[0], t[1], t[2])) return 1;
    for (int k = 0; k < 3; k++)
        if (seg_seg2(e0, e1, t[k], t[(k + 1) % 3])) return 1;
    return 0;
}

/* Closed segment e0-e1 meets closed triangle a, b, c (3D). */
int thx_segment_triangle3(const double *e0, const double *e1, const double *a, const double *b, const double *c)
{
    int s0 = sgn(o3(a, b, c, e0)), s1 = sgn(o3(a, b, c, e1));
    if (s0 == s1 && s0 != 0) return 0;
    if (s0 == 0 && s1 == 0) { /* segment in the triangle's plane */
        int ax = plane_axis(a, b, c);
        double t[3][2], p0[2], p1[2];
        proj(a, ax, t[0]);
        proj(b, ax, t[1]);
        proj(c, ax, t[2]);
        proj(e0, ax, p0);
        proj(e1, ax, p1);
        return seg_tri2(p0, p1, t);
    }
    /* The segment crosses (or ends on) the plane at one point X; the signs
     * below are those of X's barycentric coordinates (up to a common sign). */
    int w1 = sgn(o3(e0, e1, a, b)), w2 = sgn(o3(e0, e1, b, c)), w3 = sgn(o3(e0, e1, c, a));
    return (w1 >= 0 && w2 >= 0 && w3 >= 0) || (w1 <= 0 && w2 <= 0 && w3 <= 0);
}

/* Closed triangles p and q meet (3D, both non-degenerate, no shared nodes). */
static int tri_tri3(const double *const p[3], const double *const q[3])
{
    int dq[3], dp[3];
    for (int k = 0; k < 3; k++) dq[k] = sgn(o3(p[0], p[1], p[2], q[k]));
    if ((dq[0] > 0 && dq[1] > 0 && dq[2] > 0) || (dq[0] < 0 && dq[1] < 0 && dq[2] < 0)) return 0;
    for (int k = 0; k < 3; k++) dp[k] = sgn(o3(q[0], q[1], q[2], p[k]));
    if ((dp[0] > 0 && dp[1] > 0 && dp[2] > 0) || (dp[0] < 0 && dp[1] < 0 && dp[2] < 0)) return 0;
    if (dq[0] == 0 && dq[1] == 0 && dq[2] == 0) { /* coplanar */
        int ax = plane_axis(p[0], p[1], p[2]);
        double tp[3][2], tq[3][2];
        for (int k = 0; k < 3; k++) {
            proj(p[k], ax, tp[k]);
            proj(q[k], ax, tq[k]);
        }
        for (int k = 0; k < 3; k++)
            if (seg_tri2(tq[k], tq[(k + 1) % 3], tp)) return 1;
        /* q's edges miss p: they meet only if p lies inside q */
        return point_in_tri2(tp[0], tq[0], tq[1], tq[2]);
    }
    /* Not coplanar: the intersection lies on the line L of the two planes;
     * T1 ∩ L and T2 ∩ L are segments whose ends lie on the triangles' edges,
     * so if they overlap, an end of one lies in the other triangle: some edge
     * of one triangle meets the other triangle. */
    for (int k = 0; k < 3; k++) {
        if (thx_segment_triangle3(p[k], p[(k + 1) % 3], q[0], q[1], q[2])) return 1;
        if (thx_segment_triangle3(q[k], q[(k + 1) % 3], p[0], p[1], p[2])) return 1;
    }
    return 0;
}

int thx_triangles_intersect(const double *xyz, const int32_t ta[3], const int32_t tb[3])
{
    int shared_a[3] = {-1, -1, -1}; /* shared_a[i] = k if ta[i] == tb[k] */
    int n_shared = 0;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            if (ta[i] == tb[k]) {
                shared_a[i] = k;
                n_shared++;
            }
#define PT(v) (xyz + 3 * (size_t)(v))
    if (n_shared == 0) {
        const double *p[3] = {PT(ta[0]), PT(ta[1]), PT(ta[2])};
        const double *q[3] = {PT(tb[0]), PT(tb[1]), PT(tb[2])};
        return tri_tri3(p, q);
    }
    if (n_shared == 1) {
        /* shared node v; (a, b) = ta's opposite edge, (c, d) = tb's. The two
         * meet beyond v iff ab meets tb or cd meets ta (on the line through v
         * common to both planes, or on a common ray from v in their common
         * plane, the nearer far end lies in both triangles, and it lies on
         * an opposite edge). */
        int ia = 0;
        while (shared_a[ia] < 0) ia++;
        int kb = shared_a[ia];
        const double *a = PT(ta[(ia + 1) % 3]), *b = PT(ta[(ia + 2) % 3]);
        const double *c = PT(tb[(kb + 1) % 3]), *d = PT(tb[(kb + 2) % 3]);
        return thx_segment_triangle3(a, b, PT(tb[0]), PT(tb[1]), PT(tb[2])) || thx_segment_triangle3(c, d, PT(ta[0]), PT(ta[1]), PT(ta[2]));
    }
    if (n_shared == 2) {
        /* shared edge (a, b); c, d the opposite nodes. Non-coplanar: the
         * intersection is exactly the edge. Coplanar: they overlap iff c and d
         * are on the same side of ab (a fold), else they are flat neighbours. */
        int ic = 0, kd = 0;
        while (shared_a[ic] >= 0) ic++;
        int used[3] = {0, 0, 0};
        for (int i = 0; i < 3; i++)
            if (shared_a[i] >= 0) used[shared_a[i]] = 1;
        while (used[kd]) kd++;
        const double *a = PT(ta[(ic + 1) % 3]), *b = PT(ta[(ic + 2) % 3]);
        const double *c = PT(ta[ic]), *d = PT(tb[kd]);
        if (o3(a, b, c, d) != 0.0) return 0;
        int ax = plane_axis(a, b, c);
        double pa[2], pb[2], pc[2], pd[2];
        proj(a, ax, pa);
        proj(b, ax, pb);
        proj(c, ax, pc);
        proj(d, ax, pd);
        return sgn(thx_orient2d(pa, pb, pc)) == sgn(thx_orient2d(pa, pb, pd));
    }
#undef PT
    return 0; /* same three nodes: a duplicate, reported as such */
}

