/*
 * src/raytrace/rt_walk.h — the volume walk's step, shared by the one-ray walk (rt_volume.c) and the
 * walk in eight lanes (rt_volume_lanes.c): the transfer function's table, a piece's emission and
 * absorption, a segment split at the table's entries, the exit face of a tetrahedron, and a ray's
 * entry into the mesh. Private to src/raytrace.
 */
#ifndef THORAX_RT_WALK_H
#define THORAX_RT_WALK_H

#include <math.h>

#include "raytrace/rt_impl.h"

#ifdef __SSE2__
#include <immintrin.h>
#endif

#define TF_N 256

/* The transfer function (r, g, b, tau) at table position x in [0, TF_N - 1], linear between entries. */
static inline rt_v4f tf_at(const rt_tf *tf, float x)
{
    int i = (int)x;
    if (i > TF_N - 2) i = TF_N - 2;
    return tf->v[i] + (x - (float)i) * tf->d[i];
}

/* t = scale(value) as a table position (t clamped to [0, 1]). */
static inline float tf_pos(float t) { return (t < 0 ? 0 : t > 1 ? 1 : t) * (TF_N - 1); }

/* Below this optical depth a piece is integrated by series (most pieces of a fine mesh). */
#define THIN 0.05

/* The sum of a vector's four lanes. */
static inline float hsum4(rt_v4f x)
{
    x += __builtin_shufflevector(x, x, 2, 3, 0, 1);
    return x[0] + x[1];
}

/* 4-point Gauss-Legendre on [0, 1] (exact for polynomials to degree 7): nodes and weights. */
static const rt_v4f GL_S = {0.0694318442f, 0.3300094782f, 0.6699905218f, 0.9305681558f};
static const rt_v4f GL_W = {0.1739274226f, 0.3260725774f, 0.3260725774f, 0.1739274226f};

/* b of a thin piece (below): the mean over s in [0, 1] of D - D^2 / 2 + D^3 / 6 - D^4 / 24 with D =
 * u s + v s^2, the means of D^n being sum_k C(n, k) u^(n-k) v^k / (n + k + 1); by Horner in u, each
 * coefficient by Horner in v (14 multiply-adds). For a float or a vector of floats alike. */
#define RT_THIN_B(u, v)                                                                                                    \
    ((v) * (1.0f / 3 + (v) * (-1.0f / 10 + (v) * (1.0f / 42 - (v) * (1.0f / 216)))) +                                    \
     (u) * ((0.5f + (v) * (-0.25f + (v) * (1.0f / 12 - (v) * (1.0f / 48)))) +                                            \
            (u) * ((-1.0f / 6 + (v) * (0.1f - (v) * (1.0f / 28))) + (u) * ((1.0f / 24 - (v) * (1.0f / 36)) - (u) * (1.0f / 120)))))

/* One sub-piece of length L along which the colour C and the extinction tau are linear, from p0 =
 * (c0, tau0) to p1 = (c1, tau1): its emission added to acc (r, g, b in its first three lanes) under
 * the transmittance *T, and *T reduced.
 *
 * With the optical depth D(z) = int_0^z tau, and tau e^(-D) = d/dz (-e^(-D)), integration by parts
 * gives the emission int_0^L C tau e^(-D) dz = c0 b + c1 (a - b), where a = 1 - e^(-D(L)) (what the
 * piece absorbs) and b = (1 / L) int_0^L (1 - e^(-D(z))) dz: exact for C linear, in two numbers
 * shared by the three channels, the channels then one vector operation. D is quadratic along the
 * piece (tau linear): D(sL) = u s + v s^2, u = tau0 L, v = (tau1 - tau0) L / 2, and D <= x = (tau0 +
 * tau1) L / 2.
 * - Where the piece is thin (x < THIN, most pieces of a fine mesh; and an empty or clear piece, which
 *   gives a = b = 0, so the usual step has no branch the processor cannot foresee), in float: a by
 *   its Taylor polynomial (the next term under x^6 / 720, 2e-11), b as the mean over the piece of
 *   1 - e^(-D) by its Taylor polynomial to D^4 (the next term under x^5 / 120, 3e-9), which is a
 *   polynomial in u and v, exactly (RT_THIN_B): each 1e-7 of itself, float's own precision, and no
 *   cancellation (a and b are both small).
 * - Else, in double: a = -expm1(-x), b exact in closed form where tau is constant (b = 1 - a / x),
 *   else by 4-point Gauss-Legendre on the smooth 1 - e^(-D). */
static inline __attribute__((always_inline)) void piece(rt_v4f p0, rt_v4f p1, float L, rt_v4f *acc, double *T)
{
    float tau0 = p0[3], tau1 = p1[3], x = 0.5f * (tau0 + tau1) * L, a, b;
    if (x < THIN) {
        a = x * (1 - x * (0.5f - x * (1.0f / 6 - x * (1.0f / 24 - x * (1.0f / 120)))));
        float u = tau0 * L, v = 0.5f * (tau1 - tau0) * L;
        b = RT_THIN_B(u, v);
    } else {
        double xd = x, ad = -expm1(-xd), bd;
        if (tau0 == tau1) {
            bd = 1 - ad / xd;
        } else {
            /* D(z) = tau0 z + (tau1 - tau0) z^2 / (2 L) at the nodes z = L s, s the 4 Gauss-Legendre
               nodes on [0, 1] */
            static const double gs[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
            static const double gw[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};
            bd = 0;
            for (int g = 0; g < 4; g++) {
                double z = L * gs[g];
                bd += gw[g] * -expm1(-((double)tau0 * z + ((double)tau1 - tau0) * z * z / (2.0 * L)));
            }
        }
        a = (float)ad;
        b = (float)bd;
    }
    *acc += (float)*T * (p0 * b + p1 * (a - b));
    *T *= 1 - (double)a;
}

/* A segment of length L along which the table position goes linearly from xa (where the transfer
 * function is va) to xb: split where it crosses a table entry, each sub-piece integrated; returns
 * the transfer function at xb. */
static inline __attribute__((always_inline)) rt_v4f segment(const rt_tf *tf, float xa, float xb, float L, rt_v4f va,
                                                            rt_v4f *acc, double *T)
{
    int ia = (int)xa, ib = (int)xb; /* the table intervals [i, i + 1) of the two ends (x >= 0) */
    if (ia == ib) { /* within one interval, where the function is linear: one piece (most steps) */
        rt_v4f vb = tf_at(tf, xb);
        piece(va, vb, L, acc, T);
        return vb;
    }
    /* the entries strictly between xa and xb, in the ray's order */
    int up = xb > xa, k = up ? ia + 1 : (int)ceilf(xa) - 1, kend = up ? (int)ceilf(xb) : ib;
    double s = 0, inv = 1 / ((double)xb - xa); /* s: the fraction of L done */
    for (; up ? k < kend : k > kend; k += up ? 1 : -1) {
        double s1 = (k - (double)xa) * inv;
        rt_v4f e = tf_at(tf, (float)k);
        piece(va, e, (float)((s1 - s) * L), acc, T);
        va = e;
        s = s1;
        if (*T <= 1e-4) return va;
    }
    rt_v4f e = tf_at(tf, xb);
    piece(va, e, (float)((1 - s) * L), acc, T);
    return e;
}

/* Where the ray o + s d leaves tetrahedron T entered through face `in` (-1: unknown): the face among
 * the others whose barycentric coordinate falls to 0 first, *sexit its distance (at least smin); -1
 * when none falls (a ray grazing). The four faces at once and without a branch (which face wins is
 * the data's whim, and a mispredicted branch a step cost more than the division): each coordinate's
 * value at o and its fall along d from the planes' lanes, the fourth face's as 1 - and 0 - the
 * others', the distances val / fall where the coordinate falls (+inf elsewhere), the least. Ties go
 * to the lower face, the same way for every ray. */
static inline int exit_face(const rt_tet *T, int in, rt_v4f o, rt_v4f d, float smin, float *sexit)
{
    const rt_v4i planes = {-1, -1, -1, 0}, lane = {0, 1, 2, 3};
    rt_v4f x = (rt_v4f)((rt_v4i)T->q[0] & planes), y = (rt_v4f)((rt_v4i)T->q[1] & planes);
    rt_v4f z = (rt_v4f)((rt_v4i)T->q[2] & planes), c = (rt_v4f)((rt_v4i)T->q[3] & planes);
    rt_v4f fall = -(x * d[0] + y * d[1] + z * d[2]), val = x * o[0] + y * o[1] + z * o[2] + c;
    float f3 = -hsum4(fall), v3 = 1 - hsum4(val);
    fall[3] = f3;
    val[3] = v3;
    rt_v4i ok = (fall > 0) & (lane != in);
    const rt_v4f inf = {INFINITY, INFINITY, INFINITY, INFINITY};
    rt_v4f s = (rt_v4f)((ok & (rt_v4i)(val / fall)) | (~ok & (rt_v4i)inf));
#ifdef __SSE2__
    __m128 m = _mm_min_ps((__m128)s, _mm_shuffle_ps((__m128)s, (__m128)s, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1))); /* the least in every lane */
    float least = _mm_cvtss_f32(m);
    if (!(least < INFINITY)) return -1;
    int out = __builtin_ctz((unsigned)_mm_movemask_ps(_mm_cmpeq_ps((__m128)s, m)));
#else
    int out = 0;
    for (int k = 1; k < 4; k++)
        if (s[k] < s[out]) out = k;
    float least = s[out];
    if (!(least < INFINITY)) return -1;
#endif
    *sexit = least > smin ? least : smin;
    return out;
}

/* A ray's walk through the tetrahedra between two boundary faces: the entry point e = (x, y, z, 1)
 * (the walk measures s from it), the direction (dx, dy, dz, 0) in float, the distance send left to
 * the ray's end, the tetrahedron tt entered through face in, the table position xa at s and the
 * transfer function va there, tin the entry's distance along the ray. */
typedef struct {
    rt_v4f e, df, va;
    float s, send, xa;
    float sbeg; /* the pieces before it skipped (a volume's box, sort-last), else -inf */
    size_t tt;
    int in;
    double tin;
} rt_walk;

/* The span [*t0, *t1] of the ray o + t d inside the volume's box (have_box; else all of it): the
 * slabs of the box's sides, each box [lo, hi) as the parts' cuts make them (a ray in a side's plane
 * is in the box above it alone). Empty when *t0 > *t1. */
static inline void rt_box_span(const thx_raytrace_volume *v, const double o[3], const double d[3], double *t0, double *t1)
{
    *t0 = -INFINITY;
    *t1 = INFINITY;
    if (!v->have_box) return;
    for (int k = 0; k < 3; k++) {
        double lo = v->box[0][k], hi = v->box[1][k];
        if (d[k] == 0) {
            if (o[k] < lo || o[k] >= hi) *t0 = INFINITY, *t1 = -INFINITY; /* [lo, hi): as the parts' cuts are */
            continue;
        }
        double a = (lo - o[k]) / d[k], b = (hi - o[k]) / d[k]; /* (an infinite side: +-inf) */
        if (a > b) { double c = a; a = b; b = c; }
        if (a > *t0) *t0 = a;
        if (b < *t1) *t1 = b;
    }
}

/* One look for where the ray o + t d (from *t to tfar) enters the mesh: 1 and the walk set in *w
 * where it enters; -1 where the face met is one the ray leaves through (*t moved past it: look
 * again); 0 where it meets no face (the ray is done). */
static inline int rt_walk_enter(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld,
                                const double o[3], const double d[3], double *t, double tfar, rt_walk *w, size_t *rays)
{
    struct RTCRayHit rh;
    rt_ray_once(m->scene, o, d, *t, tfar, &rh);
    (*rays)++;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    int32_t slot = m->bface[rh.hit.primID];
    double tin = rh.ray.tfar;
    /* entering only: a ray that meets a boundary face from inside (leaving) goes on past it */
    size_t tt = (size_t)slot / 4;
    int in = slot % 4;
    const int32_t *cc = v->tet + 4 * (size_t)m->order[tt];
    const double *opp = v->xyz + 3 * cc[in], *p0 = v->xyz + 3 * cc[(in + 1) % 4];
    double ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    double toopp = ng[0] * (opp[0] - p0[0]) + ng[1] * (opp[1] - p0[1]) + ng[2] * (opp[2] - p0[2]);
    double along = ng[0] * d[0] + ng[1] * d[1] + ng[2] * d[2];
    if ((toopp > 0) != (along > 0)) { *t = nextafterf((float)tin, INFINITY); return -1; }
    /* the walk measures s from the entry point (a perspective eye may be a metre and a half away);
       a point as (x, y, z, 1), so that the field there is one product with its (g, c) */
    w->e = (rt_v4f){(float)(o[0] + tin * d[0]), (float)(o[1] + tin * d[1]), (float)(o[2] + tin * d[2]), 1};
    w->df = (rt_v4f){(float)d[0], (float)d[1], (float)d[2], 0};
    w->send = (float)(tfar - tin);
    w->s = 0;
    w->sbeg = -INFINITY;
    if (v->have_box) { /* sort-last: the pieces before the box skipped (its end is tfar's) */
        double t0, t1;
        rt_box_span(v, o, d, &t0, &t1);
        if (t0 > tin) w->sbeg = (float)(t0 - tin);
    }
    w->tt = tt;
    w->in = in;
    w->tin = tin;
    w->xa = tf_pos(hsum4(((const rt_v4f *)fld)[tt] * w->e));
    w->va = tf_at(tf, w->xa);
    return 1;
}

/* One step of a walk: the exit from w's tetrahedron, the segment's integral into acc and *T, and
 * the walk moved into the next tetrahedron. 1: go on; 0: the ray is done (its end reached); -1: the
 * walk ends here (the mesh's boundary, or a ray grazing a face), and the ray looks for where it
 * enters again. */
static inline __attribute__((always_inline)) int walk_step(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, rt_walk *w,
                            rt_v4f *acc, double *T)
{
    const rt_v4f *fv = (const rt_v4f *)fld;
    const rt_tet *X = m->tets + w->tt;
    float sx;
    int out = exit_face(X, w->in, w->e, w->df, w->s, &sx);
    if (out < 0) return -1;
    float stop = sx < w->send ? sx : w->send;
    float xb = tf_pos(hsum4(fv[w->tt] * (w->e + stop * w->df)));
    if (__builtin_expect(w->s < w->sbeg, 0)) { /* sort-last: a piece before the box begins */
        if (stop <= w->sbeg) {
            w->va = tf_at(tf, xb);
        } else { /* the piece from the box's side on */
            w->xa = tf_pos(hsum4(fv[w->tt] * (w->e + w->sbeg * w->df)));
            w->va = segment(tf, w->xa, xb, stop - w->sbeg, tf_at(tf, w->xa), acc, T);
        }
    } else {
        w->va = segment(tf, w->xa, xb, stop - w->s, w->va, acc, T);
    }
    w->xa = xb;
    w->s = stop;
    if (stop >= w->send) return 0;
    int32_t nb = RT_TET_NB(X, out);
    if (nb < 0) return -1; /* out of the mesh: Embree finds where it enters again */
    w->tt = (size_t)nb / 4;
    w->in = nb % 4;
    /* point data: the field continuous across the face (the same value there); cell data jumps */
    if (!v->point_values) {
        w->xa = tf_pos(fv[w->tt][3]);
        w->va = tf_at(tf, w->xa);
    }
    return 1;
}

#endif
