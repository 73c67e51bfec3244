/*
 * RaySpray's volume renderer (thorax/raytrace/raytrace.h, thx_raytrace_volume): emission and
 * absorption along each ray through a tetrahedral mesh.
 *
 * The mesh. Its boundary faces (a face of one tetrahedron only) go into an Embree scene of their own,
 * and each tetrahedron's four face neighbours (the tetrahedron across the face opposite vertex k, and
 * that face's number there) into a table; both are built once per mesh and kept.
 *
 * The walk. A ray enters at the nearest boundary face Embree finds, in that face's tetrahedron. Each
 * tetrahedron keeps its four barycentric coordinates as affine functions (built with the mesh), so
 * along the ray each is linear: in a tetrahedron entered through face `in`, the ray leaves through
 * the face among the other three whose coordinate falls to 0 first, and the field there is the
 * coordinates' mix of the corner values; the neighbour across that face is entered through the same
 * face (its number there from the table), so no face is tested twice and a ray is never lost
 * between two tetrahedra. At a boundary face the ray leaves the mesh and Embree finds where it
 * enters again (a concave mesh).
 *
 * The integral. Along a piece the field is linear (point data) or constant (cell data), so t =
 * scale(value) is linear in the distance. The transfer function is a table of 256 entries over t,
 * linear between entries; the piece is split where t crosses an entry, and on each sub-piece the
 * colour C and the extinction tau are linear in the distance; each sub-piece's emission and
 * absorption by `piece` (by parts, in two numbers; a thin piece in float by its series, a thick one
 * in double, in closed form where tau is constant). Front to back: colour += T E, T *= exp(-depth).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raytrace/rt_impl.h"

#ifdef __SSE2__
#include <immintrin.h>
#endif

#define TF_N 256

typedef struct {
    int32_t key[3];
    int32_t slot;   /* tet * 4 + k */
} face_rec;

typedef struct {
    uint64_t key;
    int32_t tet;
} morton_rec;

static int morton_cmp(const void *a, const void *b)
{
    const morton_rec *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->tet > y->tet) - (x->tet < y->tet);
}

/* 21 bits spread to every third place. */
static uint64_t spread3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

/* The tetrahedra in the Morton order of their centres (malloc'd; NULL when out of memory). */
static int32_t *morton_order(thx_ctx *ctx, const thx_raytrace_volume *v)
{
    size_t nt = v->n_tets;
    morton_rec *r = thx_malloc(ctx, (nt ? nt : 1) * sizeof *r);
    int32_t *order = thx_malloc(ctx, (nt ? nt : 1) * sizeof *order);
    if (!r || !order) { free(r); free(order); return NULL; }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < v->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], v->xyz[3 * i + (size_t)k]);
            hi[k] = fmax(hi[k], v->xyz[3 * i + (size_t)k]);
        }
    double span = fmax(fmax(hi[0] - lo[0], hi[1] - lo[1]), hi[2] - lo[2]), q = span > 0 ? 2097151.0 / span : 0;
    for (size_t t = 0; t < nt; t++) {
        uint64_t key = 0;
        for (int k = 0; k < 3; k++) {
            double c = 0;
            for (int j = 0; j < 4; j++) c += 0.25 * v->xyz[3 * (size_t)v->tet[4 * t + (size_t)j] + (size_t)k];
            key |= spread3((uint64_t)fmin(fmax((c - lo[k]) * q, 0), 2097151)) << k;
        }
        r[t].key = key;
        r[t].tet = (int32_t)t;
    }
    qsort(r, nt, sizeof *r, morton_cmp);
    for (size_t t = 0; t < nt; t++) order[t] = r[t].tet;
    free(r);
    return order;
}

static int face_cmp(const void *a, const void *b)
{
    const face_rec *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->key[k] != y->key[k]) return x->key[k] < y->key[k] ? -1 : 1;
    return (x->slot > y->slot) - (x->slot < y->slot);
}

void rt_vmesh_free(rt_vmesh *m)
{
    if (m->scene) rtcReleaseScene(m->scene);
    free(m->tets);
    free(m->order);
    free(m->bface);
    memset(m, 0, sizeof *m);
}

thx_status rt_vmesh_build(thx_ctx *ctx, RTCDevice dev, const thx_raytrace_volume *v, rt_vmesh *m)
{
    if (m->xyz == v->xyz && m->tet == v->tet && m->n_nodes == v->n_nodes && m->n_tets == v->n_tets && m->scene) return THX_OK;
    rt_vmesh_free(m);
    size_t nt = v->n_tets, nf = 4 * nt;
    for (size_t i = 0; i < 4 * nt; i++)
        if (v->tet[i] < 0 || (size_t)v->tet[i] >= v->n_nodes)
            return thx_error(ctx, THX_EINPUT, "volume rendering: tetrahedron %zu names node %d of %zu", i / 4 + 1, v->tet[i] + 1, v->n_nodes);
    face_rec *f = thx_malloc(ctx, (nf ? nf : 1) * sizeof *f);
    m->order = morton_order(ctx, v);
    if (posix_memalign((void **)&m->tets, 64, (nt ? nt : 1) * sizeof *m->tets)) {
        m->tets = NULL;
        thx_error(ctx, THX_ENOMEM, "out of memory (%zu tetrahedra to walk)", nt);
    }
    if (!f || !m->tets || !m->order) { free(f); rt_vmesh_free(m); return THX_ENOMEM; }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            face_rec *r = &f[4 * t + (size_t)k];
            int32_t a[3], n = 0;
            for (int j = 0; j < 4; j++)
                if (j != k) a[n++] = v->tet[4 * (size_t)m->order[t] + (size_t)j];
            /* sorted corners: the key both tetrahedra of a face share */
            if (a[0] > a[1]) { int32_t x = a[0]; a[0] = a[1]; a[1] = x; }
            if (a[1] > a[2]) { int32_t x = a[1]; a[1] = a[2]; a[2] = x; }
            if (a[0] > a[1]) { int32_t x = a[0]; a[0] = a[1]; a[1] = x; }
            memcpy(r->key, a, sizeof a);
            r->slot = (int32_t)(4 * t + (size_t)k);
            RT_TET_NB(&m->tets[t], k) = -1;
        }
    qsort(f, nf, sizeof *f, face_cmp);
    size_t nb = 0;
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && !memcmp(f[j].key, f[i].key, sizeof f[i].key)) j++;
        if (j - i == 2) {
            int32_t a = f[i].slot, b = f[i + 1].slot;
            RT_TET_NB(&m->tets[a / 4], a % 4) = b;
            RT_TET_NB(&m->tets[b / 4], b % 4) = a;
        } else if (j - i == 1) {
            nb++;
        } else {
            free(f);
            rt_vmesh_free(m);
            return thx_error(ctx, THX_EINPUT, "volume rendering: a face in %zu tetrahedra (a mesh needs each face in 1 or 2)", j - i);
        }
        i = j;
    }
    free(f);
    /* each tetrahedron's barycentric coordinates as affine functions: lambda_k(p) = a_k . p + b_k, 1 at
       vertex k and 0 on the face opposite it (what the walk and the field's interpolation read) */
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            const int32_t *c = v->tet + 4 * (size_t)m->order[t];
            const double *p0 = v->xyz + 3 * c[(k + 1) % 4], *p1 = v->xyz + 3 * c[(k + 2) % 4], *p2 = v->xyz + 3 * c[(k + 3) % 4];
            const double *vk = v->xyz + 3 * c[k];
            double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            double sk = n[0] * (vk[0] - p0[0]) + n[1] * (vk[1] - p0[1]) + n[2] * (vk[2] - p0[2]);
            float *pl = m->tets[t].f + k; /* lane k of the four vectors */
            if (sk == 0) { pl[0] = pl[4] = pl[8] = 0; pl[12] = 0.25f; continue; } /* a flat tetrahedron: never crossed */
            double a[3] = {n[0] / sk, n[1] / sk, n[2] / sk};
            for (int q = 0; q < 3; q++) pl[4 * q] = (float)a[q];
            pl[12] = (float)-(a[0] * p0[0] + a[1] * p0[1] + a[2] * p0[2]);
        }
    /* the boundary faces, as Embree triangles (each face's tetrahedron slot kept) */
    m->bface = thx_malloc(ctx, (nb ? nb : 1) * sizeof *m->bface);
    if (!m->bface) { rt_vmesh_free(m); return THX_ENOMEM; }
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), v->n_nodes ? v->n_nodes : 1);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nb ? nb : 1);
    if (!vb || !ib) { rtcReleaseGeometry(g); rt_vmesh_free(m); return THX_ENOMEM; }
    for (size_t i = 0; i < 3 * v->n_nodes; i++) vb[i] = (float)v->xyz[i];
    size_t q = 0;
    for (size_t s = 0; s < nf; s++) {
        if (RT_TET_NB(&m->tets[s / 4], s % 4) >= 0) continue;
        size_t t = s / 4, n = 0;
        int k = (int)(s % 4);
        for (int j = 0; j < 4; j++)
            if (j != k) ib[3 * q + n++] = (unsigned)v->tet[4 * (size_t)m->order[t] + (size_t)j];
        m->bface[q++] = (int32_t)s;
    }
    rtcCommitGeometry(g);
    m->scene = rtcNewScene(dev);
    rtcSetSceneFlags(m->scene, RTC_SCENE_FLAG_ROBUST);
    rtcAttachGeometry(m->scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(m->scene);
    m->xyz = v->xyz;
    m->tet = v->tet;
    m->n_nodes = v->n_nodes;
    m->n_tets = nt;
    m->n_bface = nb;
    m->builds++;
    return THX_OK;
}

void rt_tf_build(const thx_raytrace_volume *v, rt_tf *tf)
{
    for (int i = 0; i < TF_N; i++) {
        double t = (double)i / (TF_N - 1), op;
        unsigned char c[3];
        thx_colormap_eval(v->cmap, t, c);
        if (v->n_opacity <= 0) {
            op = fabs(t - 0.5) * 2;
        } else if (t <= v->opacity[0][0]) {
            op = v->opacity[0][1];
        } else if (t >= v->opacity[v->n_opacity - 1][0]) {
            op = v->opacity[v->n_opacity - 1][1];
        } else {
            int j = 0;
            while (j + 1 < v->n_opacity && v->opacity[j + 1][0] < t) j++;
            double t0 = v->opacity[j][0], t1 = v->opacity[j + 1][0];
            double w = t1 > t0 ? (t - t0) / (t1 - t0) : 0;
            op = v->opacity[j][1] + w * (v->opacity[j + 1][1] - v->opacity[j][1]);
        }
        tf->v[i] = (rt_v4f){c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, (float)(fmax(op, 0) * v->density)};
    }
    for (int i = 0; i < TF_N; i++) tf->d[i] = i + 1 < TF_N ? tf->v[i + 1] - tf->v[i] : (rt_v4f){0, 0, 0, 0};
}

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
 *   its Taylor polynomial (the next term under x^6 / 720, 2e-11), b by 4-point Gauss-Legendre over
 *   the piece of 1 - e^(-D) by its Taylor polynomial to D^4 (the next term under x^5 / 120, 3e-9;
 *   the quadrature exact for the polynomial to D^3, the D^4 term's error under 1e-11): each 1e-7
 *   of itself, float's own precision, and no cancellation (a and b are both small).
 * - Else, in double: a = -expm1(-x), b exact in closed form where tau is constant (b = 1 - a / x),
 *   else by 3-point Gauss-Legendre on the smooth 1 - e^(-D). */
static inline __attribute__((always_inline)) void piece(rt_v4f p0, rt_v4f p1, float L, rt_v4f *acc, double *T)
{
    float tau0 = p0[3], tau1 = p1[3], x = 0.5f * (tau0 + tau1) * L, a, b;
    if (x < THIN) {
        a = x * (1 - x * (0.5f - x * (1.0f / 6 - x * (1.0f / 24 - x * (1.0f / 120)))));
        float u = tau0 * L, v = 0.5f * (tau1 - tau0) * L;
        rt_v4f D = (u + v * GL_S) * GL_S;
        b = hsum4(GL_W * (D * (1 - D * (0.5f - D * (1.0f / 6 - D * (1.0f / 24))))));
    } else {
        double xd = x, ad = -expm1(-xd), bd;
        if (tau0 == tau1) {
            bd = 1 - ad / xd;
        } else {
            /* D(z) = tau0 z + (tau1 - tau0) z^2 / (2 L) at the nodes z = L (1 + g) / 2 */
            static const double gx[3] = {-0.7745966692414834, 0, 0.7745966692414834}, gw[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
            bd = 0;
            for (int g = 0; g < 3; g++) {
                double z = 0.5 * L * (gx[g] + 1);
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

float *rt_volume_field(thx_ctx *ctx, const rt_vmesh *m, const thx_raytrace_volume *v)
{
    size_t nt = v->n_tets;
    float *fld = thx_malloc(ctx, 4 * (nt ? nt : 1) * sizeof *fld);
    double *tn = v->point_values ? thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *tn) : NULL;
    if (!fld || (v->point_values && !tn)) { free(fld); free(tn); return NULL; }
    if (tn)
        for (size_t i = 0; i < v->n_nodes; i++) tn[i] = thx_scale_apply(&v->scale, v->point_values[i]);
#pragma omp parallel for schedule(static)
    for (size_t t = 0; t < nt; t++) {
        float *g = fld + 4 * t;
        if (!tn) {
            g[0] = g[1] = g[2] = 0;
            g[3] = (float)thx_scale_apply(&v->scale, v->cell_values[m->order[t]]);
            continue;
        }
        /* t(p) = sum_k lambda_k(p) t_k: the coordinates' affine functions mixed by the corner values */
        double acc[4] = {0, 0, 0, 0};
        const float *pl = m->tets[t].f;
        const int32_t *c = v->tet + 4 * (size_t)m->order[t];
        double t3 = tn[c[3]]; /* lambda_3 = 1 - the others */
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 4; q++) acc[q] += (double)pl[4 * q + k] * (tn[c[k]] - t3);
        acc[3] += t3;
        for (int q = 0; q < 4; q++) g[q] = (float)acc[q];
    }
    free(tn);
    return fld;
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

void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays)
{
    rt_v4f acc = {0, 0, 0, 0}; /* r, g, b (and a lane unused), in a register while the walk runs */
    double acc_T = 1;
    double t = tnear;
    for (int entries = 0; entries < 64 && acc_T > 1e-4 && t < tfar; entries++) {
        struct RTCRayHit rh;
        rt_ray_once(m->scene, o, d, t, tfar, &rh);
        (*rays)++;
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
        int32_t slot = m->bface[rh.hit.primID];
        double tin = rh.ray.tfar;
        /* entering only: a ray that meets a boundary face from inside (leaving) goes on past it */
        size_t tt = (size_t)slot / 4;
        int in = slot % 4;
        {
            const int32_t *cc = v->tet + 4 * (size_t)m->order[tt];
            const double *opp = v->xyz + 3 * cc[in], *p0 = v->xyz + 3 * cc[(in + 1) % 4];
            double ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
            double toopp = ng[0] * (opp[0] - p0[0]) + ng[1] * (opp[1] - p0[1]) + ng[2] * (opp[2] - p0[2]);
            double along = ng[0] * d[0] + ng[1] * d[1] + ng[2] * d[2];
            if ((toopp > 0) != (along > 0)) { t = nextafterf((float)tin, INFINITY); continue; }
        }
        /* the walk measures s from the entry point (a perspective eye may be a metre and a half away);
           a point as (x, y, z, 1), so that the field there is one product with its (g, c) */
        rt_v4f e = {(float)(o[0] + tin * d[0]), (float)(o[1] + tin * d[1]), (float)(o[2] + tin * d[2]), 1};
        rt_v4f df = {(float)d[0], (float)d[1], (float)d[2], 0};
        float send = (float)(tfar - tin), s = 0;
        const rt_v4f *fv = (const rt_v4f *)fld;
        float xa = tf_pos(hsum4(fv[tt] * e));
        rt_v4f va = tf_at(tf, xa);
        for (size_t steps = 0; steps < 4 * v->n_tets + 16 && acc_T > 1e-4; steps++) {
            const rt_tet *X = m->tets + tt;
            float sx;
            int out = exit_face(X, in, e, df, s, &sx);
            if (out < 0) break;
            float stop = sx < send ? sx : send;
            float xb = tf_pos(hsum4(fv[tt] * (e + stop * df)));
            va = segment(tf, xa, xb, stop - s, va, &acc, &acc_T);
            xa = xb;
            s = stop;
            if (stop >= send) goto done;
            int32_t nb = RT_TET_NB(X, out);
            if (nb < 0) break; /* out of the mesh: Embree finds where it enters again */
            tt = (size_t)nb / 4;
            in = nb % 4;
            /* point data: the field continuous across the face (the same value there); cell data jumps */
            if (!v->point_values) {
                xa = tf_pos(fv[tt][3]);
                va = tf_at(tf, xa);
            }
        }
        t = nextafterf((float)(tin + s), INFINITY);
    }
done:
    for (int k = 0; k < 3; k++) rgb[k] = acc[k];
    *T = acc_T;
}

thx_status thx_raytrace_volume_ray(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, const double org[3],
                                   const double dir[3], double tnear, double tfar, double rgb[3], double *transmittance)
{
    THX_CHECK(rt_tracer_vmesh(ctx, t, v));
    rt_tf tf;
    rt_tf_build(v, &tf);
    size_t rays = 0;
    const rt_vmesh *m = rt_tracer_vmesh_get(t);
    float *fld = rt_volume_field(ctx, m, v);
    if (!fld) return THX_ENOMEM;
    rt_volume_march(m, v, &tf, fld, org, dir, tnear, tfar, rgb, transmittance, &rays);
    free(fld);
    return THX_OK;
}
