/*
 * The volume walk in eight lanes (rt_volume_march_n): eight rays walk the tetrahedra at once, a
 * step each per round, in AVX2's eight float lanes, where the one-ray walk (rt_volume.c) tests one
 * tetrahedron's four faces in SSE's four lanes and does the rest of the step in scalar code.
 *
 * Each lane holds one ray's walk (rt_walk's fields, lane by lane). A round loads the eight
 * tetrahedra's planes and fields (two rows a load, transposed: rows4), finds each exit face and the
 * field at each exit, and integrates each lane's segment as segment() and piece() do: the first
 * piece for every lane, then one more iteration for each table entry the most crossing lane
 * crosses; thin pieces by the same polynomials, thick ones with a vector e^x. What stays lane by
 * lane, through the one-ray walk's own code (lane_event): a ray's entry into the mesh and its
 * re-entry after leaving it (Embree), the end of a ray short of the mesh's far side, a grazing ray.
 * A lane whose ray is done takes the batch's next ray, so that the lanes stay full until the last
 * rays.
 *
 * The lanes need AVX2 and FMA (compiled for them here, chosen at run time); elsewhere, and with
 * THORAX_VOLUME_LANES=0 in the environment, the rays walk one at a time. The two walks give the
 * same integrals to float's rounding (tests/test_raytrace.c compares them; docs/design/raytrace.md,
 * "The volume walk in eight lanes").
 */
#include <stdlib.h>
#include <string.h>

#include "raytrace/rt_impl.h"
#include "raytrace/rt_walk.h"

/* a transmittance below this ends a ray, as in the one-ray walk */
#define T_MIN 1e-4

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define RT_LANES 1
#endif

#ifdef RT_LANES
#define AVX2 __attribute__((target("avx2,fma")))

typedef float v8f __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));

/* Four channels (r, g, b, tau) in eight lanes: the transfer function's values, a colour gathered. */
typedef struct {
    v8f r, g, b, t;
} v8c;

/* The eight walks, lane by lane: rt_walk's fields; the colour and the transmittance gathered so far. */
typedef struct {
    v8f ex, ey, ez, dx, dy, dz, s, send, xa;
    v8c va;                         /* the transfer function at xa */
    v8c acc;                        /* r, g, b gathered (t unused) */
    v8f T;
    v8i tt, in, steps;
    /* scalar, per lane */
    int ray[8];                     /* the ray in the lane (-1: none) */
    int entries[8];
    double t[8], tin[8];
} lanes;

/* The batch: its rays and what they give. */
typedef struct {
    const rt_vmesh *m;
    const thx_raytrace_volume *v;
    const rt_tf *tf;
    const float *fld;
    int n, next;
    const double (*o)[3], (*d)[3];
    const double *tfar;
    double (*rgb)[3];
    double *T;
    size_t *rays;
} batch;

AVX2 static inline v8f splat(float x) { return (v8f)_mm256_set1_ps(x); }
AVX2 static inline v8i splati(int32_t x) { return (v8i)_mm256_set1_epi32(x); }
AVX2 static inline v8f self(v8i m, v8f a, v8f b) { return (v8f)_mm256_blendv_ps((__m256)b, (__m256)a, (__m256)m); }
AVX2 static inline v8i seli(v8i m, v8i a, v8i b) { return (m & a) | (~m & b); }
AVX2 static inline v8f vmin(v8f a, v8f b) { return (v8f)_mm256_min_ps((__m256)a, (__m256)b); }
AVX2 static inline v8f vmax(v8f a, v8f b) { return (v8f)_mm256_max_ps((__m256)a, (__m256)b); }
/* a clamped to [lo, hi] */
AVX2 static inline v8i clampi(v8i a, int32_t lo, int32_t hi)
{
    return (v8i)_mm256_max_epi32(_mm256_min_epi32((__m256i)a, _mm256_set1_epi32(hi)), _mm256_set1_epi32(lo));
}
AVX2 static inline v8f gatherf(const float *base, v8i idx) { return (v8f)_mm256_i32gather_ps(base, (__m256i)idx, 4); }
AVX2 static inline unsigned bits(v8i m) { return (unsigned)_mm256_movemask_ps((__m256)m); }
AVX2 static inline v8c csel(v8i m, v8c a, v8c b) { return (v8c){self(m, a.r, b.r), self(m, a.g, b.g), self(m, a.b, b.b), self(m, a.t, b.t)}; }
/* v + u d, channel by channel */
AVX2 static inline v8c clerp(v8c v, v8c d, v8f u) { return (v8c){v.r + u * d.r, v.g + u * d.g, v.b + u * d.b, v.t + u * d.t}; }

/* e^x for x <= 0, in float (to e^-87, about 1e-38; 0 below): x = n ln 2 + r with |r| <= ln 2 / 2
 * (ln 2 in two parts, so that r keeps no error of ln 2's rounding), e^r by its Taylor polynomial to
 * r^7 (the next term under 6e-9 of it), times 2^n built in the exponent's bits. */
AVX2 static inline v8f vexp_neg(v8f x)
{
    v8i under = x < -87.0f;
    x = vmax(x, splat(-87.0f));
    v8f n = (v8f)_mm256_round_ps((__m256)(x * 1.44269504088896341f), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    v8f r = (x - n * 0.693359375f) + n * 2.12194440e-4f;
    v8f p = 1 + r * (1 + r * (0.5f + r * (1.0f / 6 + r * (1.0f / 24 + r * (1.0f / 120 + r * (1.0f / 720 + r * (1.0f / 5040)))))));
    v8i e = (__builtin_convertvector(n, v8i) + 127) << 23;
    return (v8f)((v8i)(p * (v8f)e) & ~under);
}

/* piece() in the lanes of m: the sub-piece of length len from p0 to p1 (colour and extinction linear
 * along it) added to *acc under *T, and *T reduced. A thin piece as piece() takes it (the same
 * polynomials, in float); a thick one (optical depth x at least THIN; rare on a fine mesh), in
 * float: a = 1 - e^-x, b in closed form where tau is constant (1 - a / x), else by 4-point
 * Gauss-Legendre on the smooth 1 - e^-D (as piece() does in double). */
AVX2 static inline __attribute__((always_inline)) void vpiece(v8i m, v8c p0, v8c p1, v8f len, v8c *acc, v8f *T)
{
    v8f x = 0.5f * (p0.t + p1.t) * len;
    v8f a = x * (1 - x * (0.5f - x * (1.0f / 6 - x * (1.0f / 24 - x * (1.0f / 120)))));
    v8f u = p0.t * len, v = 0.5f * (p1.t - p0.t) * len;
    v8f b = RT_THIN_B(u, v);
    v8i thick = m & (x >= (float)THIN);
    if (bits(thick)) {
        v8f at = 1 - vexp_neg(-x);
#define NODE(g) (GL_W[g] * (1 - vexp_neg(-((u + v * GL_S[g]) * GL_S[g]))))
        v8f bt = self(p0.t == p1.t, 1 - at / x, (NODE(0) + NODE(2)) + (NODE(1) + NODE(3)));
#undef NODE
        a = self(thick, at, a);
        b = self(thick, bt, b);
    }
    v8f ab = a - b; /* piece()'s b and a - b */
    acc->r = self(m, acc->r + *T * (p0.r * b + p1.r * ab), acc->r);
    acc->g = self(m, acc->g + *T * (p0.g * b + p1.g * ab), acc->g);
    acc->b = self(m, acc->b + *T * (p0.b * b + p1.b * ab), acc->b);
    *T = self(m, *T * (1 - a), *T);
}

/* Lane l's walk and sums as the one-ray walk holds them. */
AVX2 static void lane_get(const lanes *L, int l, rt_walk *w, rt_v4f *acc, double *T)
{
    w->e = (rt_v4f){L->ex[l], L->ey[l], L->ez[l], 1};
    w->df = (rt_v4f){L->dx[l], L->dy[l], L->dz[l], 0};
    w->va = (rt_v4f){L->va.r[l], L->va.g[l], L->va.b[l], L->va.t[l]};
    w->s = L->s[l];
    w->send = L->send[l];
    w->xa = L->xa[l];
    w->tt = (size_t)L->tt[l];
    w->in = L->in[l];
    w->tin = L->tin[l];
    *acc = (rt_v4f){L->acc.r[l], L->acc.g[l], L->acc.b[l], 0};
    *T = L->T[l];
}

/* Lane l's walk and sums from the one-ray walk's. */
AVX2 static void lane_set(lanes *L, int l, const rt_walk *w, rt_v4f acc, double T)
{
    L->ex[l] = w->e[0], L->ey[l] = w->e[1], L->ez[l] = w->e[2];
    L->dx[l] = w->df[0], L->dy[l] = w->df[1], L->dz[l] = w->df[2];
    L->va.r[l] = w->va[0], L->va.g[l] = w->va[1], L->va.b[l] = w->va[2], L->va.t[l] = w->va[3];
    L->s[l] = w->s;
    L->send[l] = w->send;
    L->xa[l] = w->xa;
    L->tt[l] = (int32_t)w->tt;
    L->in[l] = w->in;
    L->tin[l] = w->tin;
    L->acc.r[l] = acc[0], L->acc.g[l] = acc[1], L->acc.b[l] = acc[2];
    L->T[l] = (float)T;
}

/* Lane l's ray is done: its colour and transmittance written out. */
AVX2 static void lane_finish(const lanes *L, batch *b, int l)
{
    int r = L->ray[l];
    b->rgb[r][0] = L->acc.r[l];
    b->rgb[r][1] = L->acc.g[l];
    b->rgb[r][2] = L->acc.b[l];
    b->T[r] = L->T[l];
}

/* Lane l's ray looks for where it enters the mesh (from L->t[l]), as the one-ray walk's loop does:
 * 1 and the lane's walk set where it enters; 0 where it is done. */
AVX2 static int lane_enter(lanes *L, batch *b, int l)
{
    int r = L->ray[l];
    while (L->entries[l] < 64 && L->T[l] > T_MIN && L->t[l] < b->tfar[r]) {
        L->entries[l]++;
        rt_walk w;
        int in = rt_walk_enter(b->m, b->v, b->tf, b->fld, b->o[r], b->d[r], &L->t[l], b->tfar[r], &w, b->rays);
        if (in == 0) return 0;
        if (in > 0) {
            rt_v4f acc = {L->acc.r[l], L->acc.g[l], L->acc.b[l], 0};
            lane_set(L, l, &w, acc, L->T[l]);
            L->steps[l] = 0;
            return 1;
        }
    }
    return 0;
}

/* Lane l takes the batch's next rays until one enters the mesh (the others are done with nothing
 * gathered): 1; 0 when the batch has none left (the lane idles). */
AVX2 static int lane_fill(lanes *L, batch *b, int l)
{
    while (b->next < b->n) {
        int r = b->next++;
        L->ray[l] = r;
        L->entries[l] = 0;
        L->t[l] = 0;
        L->acc.r[l] = L->acc.g[l] = L->acc.b[l] = 0;
        L->T[l] = 1;
        if (lane_enter(L, b, l)) return 1;
        lane_finish(L, b, l);
    }
    L->ray[l] = -1;
    L->tt[l] = 0; /* a valid tetrahedron for the round's loads; what they read is not used */
    return 0;
}

/* Lane l's walk ended at the mesh's boundary (or a grazing ray): the ray enters again further on, or
 * is done and the lane takes the next ray. Returns whether the lane is walking. */
AVX2 static int lane_reenter(lanes *L, batch *b, int l)
{
    L->t[l] = nextafterf((float)(L->tin[l] + L->s[l]), INFINITY);
    if (lane_enter(L, b, l)) return 1;
    lane_finish(L, b, l);
    return lane_fill(L, b, l);
}

/* Eight rows of four floats, base + ix[l] * stride for lane l, as four vectors:
 * o[k] lane l = row l's float k. Two rows a load (lanes l and l + 4), then a 4 x 4 transposition in
 * each half: cheaper than four gathers. */
AVX2 static inline void rows4(const float *base, const int32_t ix[8], size_t stride, v8f o[4])
{
#define ROW(l) _mm_loadu_ps(base + (size_t)ix[l] * stride)
#define PAIR(l) _mm256_insertf128_ps(_mm256_castps128_ps256(ROW(l)), ROW(l + 4), 1)
    __m256 a = PAIR(0), b = PAIR(1), c = PAIR(2), d = PAIR(3);
#undef PAIR
#undef ROW
    __m256 t0 = _mm256_unpacklo_ps(a, b), t1 = _mm256_unpackhi_ps(a, b), t2 = _mm256_unpacklo_ps(c, d), t3 = _mm256_unpackhi_ps(c, d);
    o[0] = (v8f)_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
    o[1] = (v8f)_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    o[2] = (v8f)_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
    o[3] = (v8f)_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* The rows of a table of (r, g, b, tau) vectors (the transfer function's) at idx, channel by channel. */
AVX2 static inline v8c trow(const rt_v4f *tab, v8i idx)
{
    _Alignas(32) int32_t ix[8];
    *(v8i *)ix = idx;
    v8f c[4];
    rows4((const float *)tab, ix, 4, c);
    return (v8c){c[0], c[1], c[2], c[3]};
}

/* The largest of eight non-negative integers. */
AVX2 static inline int hmax(v8i x)
{
    __m128i m = _mm_max_epi32(_mm256_castsi256_si128((__m256i)x), _mm256_extracti128_si256((__m256i)x, 1));
    m = _mm_max_epi32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm_max_epi32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtsi128_si32(m);
}

/* What happens to lane l after a round, lane by lane (out of the round's loop: rare): its ray done
 * (the next taken), its walk out of the mesh (Embree finds where it enters again), or its step not
 * the common one (the one-ray walk's step, from the lane's state). Returns whether it walks on. */
__attribute__((noinline)) AVX2 static int lane_event(lanes *L, batch *b, int l, int done, int leave, int32_t max_steps)
{
    if (done) {
        lane_finish(L, b, l);
        return lane_fill(L, b, l);
    }
    if (leave) return lane_reenter(L, b, l);
    rt_walk w;
    rt_v4f acc;
    double T;
    lane_get(L, l, &w, &acc, &T);
    w.sbeg = -INFINITY; /* (the lanes march rays without a box: rt_volume_march_n) */
    int r = L->steps[l] > max_steps ? -1 : walk_step(b->m, b->v, b->tf, b->fld, &w, &acc, &T);
    lane_set(L, l, &w, acc, T);
    if (r > 0 && T > T_MIN) return 1;
    if (r == 0 || T <= T_MIN) {
        lane_finish(L, b, l);
        return lane_fill(L, b, l);
    }
    return lane_reenter(L, b, l);
}

AVX2 static void march_lanes(batch *b)
{
    const rt_vmesh *m = b->m;
    const rt_tf *tf = b->tf;
    const float *planes = (const float *)m->tets, *fld = b->fld;
    const int cell = !b->v->point_values;
    const int32_t max_steps = (int32_t)(4 * m->n_tets + 16 < INT32_MAX ? 4 * m->n_tets + 16 : INT32_MAX);
    lanes L;
    memset(&L, 0, sizeof L);
    unsigned act = 0;
    for (int l = 0; l < 8; l++)
        if (lane_fill(&L, b, l)) act |= 1u << l;
    const v8f inf = splat(INFINITY), zero = splat(0), one = splat(1);
    const v8i lane_bit = {1, 2, 4, 8, 16, 32, 64, 128};
    while (act) {
        v8i on = (splati((int32_t)act) & lane_bit) != 0;
        /* the eight tetrahedra: their planes (q[j] lane k: plane k's coefficient j) and neighbours
           (the fourth lanes), and their fields */
        _Alignas(32) int32_t tt[8];
        *(v8i *)tt = L.tt;
        v8f q0[4], q1[4], q2[4], q3[4], g[4];
        rows4(planes, tt, 16, q0);
        rows4(planes + 4, tt, 16, q1);
        rows4(planes + 8, tt, 16, q2);
        rows4(planes + 12, tt, 16, q3);
        rows4(fld, tt, 4, g);
        /* the exit face, as exit_face finds it */
        v8f f0 = -(q0[0] * L.dx + q1[0] * L.dy + q2[0] * L.dz), f1 = -(q0[1] * L.dx + q1[1] * L.dy + q2[1] * L.dz);
        v8f f2 = -(q0[2] * L.dx + q1[2] * L.dy + q2[2] * L.dz), f3 = -((f0 + f2) + f1);
        v8f w0 = q0[0] * L.ex + q1[0] * L.ey + q2[0] * L.ez + q3[0], w1 = q0[1] * L.ex + q1[1] * L.ey + q2[1] * L.ez + q3[1];
        v8f w2 = q0[2] * L.ex + q1[2] * L.ey + q2[2] * L.ez + q3[2], w3 = 1 - ((w0 + w2) + w1);
        v8f s0 = self((f0 > 0) & (L.in != 0), w0 / f0, inf), s1 = self((f1 > 0) & (L.in != 1), w1 / f1, inf);
        v8f s2 = self((f2 > 0) & (L.in != 2), w2 / f2, inf), s3 = self((f3 > 0) & (L.in != 3), w3 / f3, inf);
        v8f least = vmin(vmin(s0, s1), vmin(s2, s3));
        v8i is0 = s0 == least, is1 = s1 == least, is2 = s2 == least;
        v8i nb = (v8i)self(is0, q0[3], self(is1, q1[3], self(is2, q2[3], q3[3])));
        v8f stop = vmin(vmax(least, L.s), L.send);
        /* the field at the exit, its place in the table, the transfer function there (the table's
           row of its interval; the clamp keeps an idle lane's index in the table) */
        v8f px = L.ex + stop * L.dx, py = L.ey + stop * L.dy, pz = L.ez + stop * L.dz;
        v8f xb = vmin(vmax((g[0] * px + g[2] * pz) + (g[1] * py + g[3]), zero), one) * (TF_N - 1);
        v8i ia = __builtin_convertvector(L.xa, v8i), ib = __builtin_convertvector(xb, v8i);
        v8i cross = on & (ia != ib);
        unsigned any_cross = bits(cross);
        v8i ic = clampi(ib, 0, TF_N - 2);
        v8c vb = clerp(trow(tf->v, ic), trow(tf->d, ic), xb - __builtin_convertvector(ic, v8f));
        v8f len = stop - L.s;
        /* the common step: an exit short of the ray's end; the others take the one-ray step */
        v8i common = on & (least < inf) & (stop < L.send) & (L.steps < max_steps);
        /* the segment's pieces, as segment() splits it: the table's entries strictly between xa and
           xb in the ray's order (count of them, from k0 by dir), then the piece to xb */
        if (!any_cross) {
            vpiece(common, L.va, vb, len, &L.acc, &L.T);
        } else {
            v8i up = xb > L.xa, dir = (up & splati(1)) | (~up & splati(-1));
            v8i cxa = __builtin_convertvector((v8f)_mm256_ceil_ps((__m256)L.xa), v8i);
            v8i cxb = __builtin_convertvector((v8f)_mm256_ceil_ps((__m256)xb), v8i);
            v8i k0 = seli(up, ia + 1, cxa - 1), count = common & cross & seli(up, cxb - k0, k0 - ib);
            v8f inv = 1 / (xb - L.xa), done_s = zero;
            v8c vcur = L.va;
            int most = hmax(count);
            v8i alive = common; /* segment() stops where the transmittance falls below T_MIN */
            for (int j = 0; j <= most; j++) {
                v8i mid = alive & (splati(j) < count), last = alive & (splati(j) == count);
                v8i k = k0 + splati(j) * dir;
                v8c ve = csel(mid, trow(tf->v, clampi(k, 0, TF_N - 1)), vb);
                v8f upto = self(mid, (__builtin_convertvector(k, v8f) - L.xa) * inv, one); /* of the segment */
                vpiece(mid | last, vcur, ve, (upto - done_s) * len, &L.acc, &L.T);
                vcur = csel(mid, ve, vcur);
                done_s = upto;
                alive &= L.T > (float)T_MIN;
            }
        }
        L.va = csel(common, vb, L.va);
        L.xa = self(common, xb, L.xa);
        L.s = self(common, stop, L.s);
        L.steps += on & splati(1);
        /* into the next tetrahedron, where the walk goes on */
        v8i go = common & (L.T > (float)T_MIN);
        v8i move = go & (nb >= 0);
        L.tt = seli(move, nb >> 2, L.tt);
        L.in = seli(move, nb & 3, L.in);
        if (cell) { /* cell data: the field jumps at the face */
            v8f xc = vmin(vmax(gatherf(fld + 3, L.tt * 4), zero), one) * (TF_N - 1);
            v8i jc = clampi(__builtin_convertvector(xc, v8i), 0, TF_N - 2);
            L.xa = self(move, xc, L.xa);
            L.va = csel(move, clerp(trow(tf->v, jc), trow(tf->d, jc), xc - __builtin_convertvector(jc, v8f)), L.va);
        }
        /* the lanes whose step was not the common one, whose ray is done or whose walk left the
           mesh, lane by lane */
        unsigned scalar = bits(on & ~common), done = bits(common & ~go), leave = bits(go & ~move);
        for (unsigned k = scalar | done | leave; k; k &= k - 1) {
            int l = __builtin_ctz(k);
            if (!lane_event(&L, b, l, done >> l & 1, leave >> l & 1, max_steps)) act &= ~(1u << l);
        }
    }
}

/* Whether this processor has the lanes' instructions (THORAX_VOLUME_LANES=0: as if it had not). */
static int lanes_cpu(void)
{
    static int cpu = -1; /* the tile threads may ask at once: each finds the same answer */
    int c = __atomic_load_n(&cpu, __ATOMIC_RELAXED);
    if (c < 0) {
        __builtin_cpu_init();
        const char *e = getenv("THORAX_VOLUME_LANES");
        c = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && !(e && strcmp(e, "0") == 0);
        __atomic_store_n(&cpu, c, __ATOMIC_RELAXED);
    }
    return c;
}
#endif

void rt_volume_march_n(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, int n,
                       const double (*o)[3], const double (*d)[3], const double *tfar, double (*rgb)[3], double *T, size_t *rays)
{
#ifdef RT_LANES
    if (n > 1 && lanes_cpu() && m->n_tets < (size_t)INT32_MAX / 16 && !v->have_box) { /* (a box: one ray at a time) */
        batch b = {m, v, tf, fld, n, 0, o, d, tfar, rgb, T, rays};
        march_lanes(&b);
        return;
    }
#endif
    for (int i = 0; i < n; i++) rt_volume_march(m, v, tf, fld, o[i], d[i], 0, tfar[i], rgb[i], &T[i], rays);
}

int thx_raytrace_volume_lanes(void)
{
#ifdef RT_LANES
    return lanes_cpu() ? 8 : 1;
#else
    return 1;
#endif
}
