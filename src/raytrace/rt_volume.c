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
 * colour C and the extinction tau are linear in the distance. Where tau is constant there (a
 * constant field, or a flat opacity) the emission integral of C tau exp(-tau x) is taken in closed
 * form, exact for C linear; elsewhere by 3-point Gauss-Legendre with the optical depth exact
 * (quadratic). Front to back: colour += T E, T *= exp(-depth).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raytrace/rt_impl.h"

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
            m->tets[t].nb[k] = -1;
        }
    qsort(f, nf, sizeof *f, face_cmp);
    size_t nb = 0;
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && !memcmp(f[j].key, f[i].key, sizeof f[i].key)) j++;
        if (j - i == 2) {
            int32_t a = f[i].slot, b = f[i + 1].slot;
            m->tets[a / 4].nb[a % 4] = b;
            m->tets[b / 4].nb[b % 4] = a;
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
            float *pl = m->tets[t].pl + 4 * k;
            if (sk == 0) { pl[0] = pl[1] = pl[2] = 0; pl[3] = 0.25f; continue; } /* a flat tetrahedron: never crossed */
            double a[3] = {n[0] / sk, n[1] / sk, n[2] / sk};
            for (int q = 0; q < 3; q++) pl[q] = (float)a[q];
            pl[3] = (float)-(a[0] * p0[0] + a[1] * p0[1] + a[2] * p0[2]);
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
        if (m->tets[s / 4].nb[s % 4] >= 0) continue;
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
        for (int k = 0; k < 3; k++) tf->c[i][k] = c[k] / 255.0;
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
        tf->tau[i] = fmax(op, 0) * v->density;
    }
}

/* The transfer function at table position x in [0, TF_N - 1] (linear between entries). */
typedef struct {
    double c[3], tau;
} tf_val;

static inline void tf_at(const rt_tf *tf, double x, tf_val *v)
{
    int i = (int)x;
    if (i > TF_N - 2) i = TF_N - 2;
    double w = x - i;
    for (int k = 0; k < 3; k++) v->c[k] = tf->c[i][k] + w * (tf->c[i + 1][k] - tf->c[i][k]);
    v->tau = tf->tau[i] + w * (tf->tau[i + 1] - tf->tau[i]);
}

/* t = scale(value) as a table position (t clamped to [0, 1]). */
static inline double tf_pos(double t) { return (t < 0 ? 0 : t > 1 ? 1 : t) * (TF_N - 1); }

/* Below this optical depth a piece is integrated by series (most pieces of a fine mesh). */
#define THIN 0.05

/* 1 - e^(-x) for x >= 0, without the cancellation where x is small (a Taylor polynomial below THIN:
 * the next term under x^7 / 5040, 2e-13). */
static inline double absorbed(double x)
{
    if (x < THIN) return x * (1 - x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x * (1.0 / 120 - x / 720)))));
    return -expm1(-x);
}

/* One sub-piece of length L along which the colour C and the extinction tau are linear, from (c0,
 * tau0) to (c1, tau1): its emission added to rgb under the transmittance *T, and *T reduced.
 *
 * With the optical depth D(z) = int_0^z tau, and tau e^(-D) = d/dz (-e^(-D)), integration by parts
 * gives the emission int_0^L C tau e^(-D) dz = c0 b + c1 (a - b), where a = 1 - e^(-D(L)) (what the
 * piece absorbs) and b = (1 / L) int_0^L (1 - e^(-D(z))) dz: exact for C linear, in two numbers
 * shared by the three channels. b is exact in closed form where tau is constant (b = 1 - a / x, x =
 * tau L; its series where x is small); elsewhere its series to the fifth power of D where the piece is
 * thin (x < THIN), else 3-point Gauss-Legendre on a smooth integrand (D quadratic). No cancellation: a
 * and b are both small where the piece is thin. */
static inline __attribute__((always_inline)) void piece(const double c0[3], double tau0, const double c1[3], double tau1, double L,
                                                        double rgb[3], double *T)
{
    if (!(L > 0) || (tau0 == 0 && tau1 == 0)) return; /* clear: nothing emitted or absorbed */
    double x = 0.5 * (tau0 + tau1) * L, a = absorbed(x), b;
    if (tau0 == tau1) {
        b = x < THIN ? x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x * (1.0 / 120 - x / 720)))) : 1 - a / x;
    } else if (x < THIN) {
        /* D(z) = u z / L + v z^2 / L^2 (u = tau0 L, v = (tau1 - tau0) L / 2, D <= x): b is the mean of
           D - D^2 / 2 + D^3 / 6 - D^4 / 24 + D^5 / 120 over the piece, each power's mean exact (the
           mean of (u s + v s^2)^n over s in [0, 1] is sum_j C(n, j) u^(n-j) v^j / (n + j + 1)); the
           next term under x^6 / 720, 2e-11 */
        double u = tau0 * L, v = 0.5 * (tau1 - tau0) * L, u2 = u * u, v2 = v * v, u3 = u2 * u, v3 = v2 * v;
        double m1 = u / 2 + v / 3, m2 = u2 / 3 + u * v / 2 + v2 / 5;
        double m3 = u3 / 4 + 0.6 * u2 * v + u * v2 / 2 + v3 / 7;
        double m4 = u2 * u2 / 5 + 2.0 / 3 * u3 * v + 6.0 / 7 * u2 * v2 + u * v3 / 2 + v2 * v2 / 9;
        double m5 = u3 * u2 / 6 + 5.0 / 7 * u2 * u2 * v + 1.25 * u3 * v2 + 10.0 / 9 * u2 * v3 + 0.5 * u * v2 * v2 + v3 * v2 / 11;
        b = m1 - m2 / 2 + m3 / 6 - m4 / 24 + m5 / 120;
    } else {
        /* D(z) = tau0 z + (tau1 - tau0) z^2 / (2 L) at the nodes z = L (1 + g) / 2 */
        static const double gx[3] = {-0.7745966692414834, 0, 0.7745966692414834}, gw[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
        b = 0;
        for (int g = 0; g < 3; g++) {
            double z = 0.5 * L * (gx[g] + 1);
            b += gw[g] * absorbed(tau0 * z + (tau1 - tau0) * z * z / (2 * L));
        }
    }
    double w = *T;
    for (int k = 0; k < 3; k++) rgb[k] += w * (c0[k] * b + c1[k] * (a - b));
    *T = w * (1 - a);
}

/* A segment of length L along which the table position goes linearly from xa (where the transfer
 * function is *v) to xb: split where it crosses a table entry, each sub-piece integrated; *v becomes
 * the transfer function at xb. */
static void segment(const rt_tf *tf, double xa, double xb, double L, tf_val *v, double rgb[3], double *T)
{
    tf_val e;
    if (xb == xa) {
        piece(v->c, v->tau, v->c, v->tau, L, rgb, T);
        return;
    }
    int ia = (int)xa, ib = (int)xb;
    if (ia == ib && (double)ia != xa && (double)ib != xb) { /* within one entry's interval: one piece (most steps) */
        tf_at(tf, xb, &e);
        piece(v->c, v->tau, e.c, e.tau, L, rgb, T);
        *v = e;
        return;
    }
    /* the entries strictly between xa and xb, in the ray's order */
    int up = xb > xa, k = up ? (int)xa + 1 : (int)ceil(xa) - 1, kend = up ? (int)ceil(xb) : (int)xb;
    double s = 0, inv = 1 / (xb - xa); /* s: the fraction of L done */
    for (; up ? k < kend : k > kend; k += up ? 1 : -1) {
        double s1 = (k - xa) * inv;
        tf_at(tf, k, &e);
        piece(v->c, v->tau, e.c, e.tau, (s1 - s) * L, rgb, T);
        *v = e;
        s = s1;
        if (*T <= 1e-4) return;
    }
    tf_at(tf, xb, &e);
    piece(v->c, v->tau, e.c, e.tau, (1 - s) * L, rgb, T);
    *v = e;
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
        const float *pl = m->tets[t].pl;
        const int32_t *c = v->tet + 4 * (size_t)m->order[t];
        double t3 = tn[c[3]]; /* lambda_3 = 1 - the others */
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 4; q++) acc[q] += (double)pl[4 * k + q] * (tn[c[k]] - t3);
        acc[3] += t3;
        for (int q = 0; q < 4; q++) g[q] = (float)acc[q];
    }
    free(tn);
    return fld;
}

/* Where the ray o + s d leaves tetrahedron T entered through face `in` (-1: unknown): the face among
 * the others whose barycentric coordinate falls to 0 first, *sexit its distance (at least smin); -1
 * when none falls (a ray grazing). The candidates are compared by cross-multiplication, one division
 * for the winner. */
static inline int exit_face(const rt_tet *T, int in, const float o[3], const float d[3], float smin, float *sexit)
{
    const float *a = T->pl;
    float fall[4], val[4];
    for (int k = 0; k < 3; k++) {
        fall[k] = -(a[4 * k] * d[0] + a[4 * k + 1] * d[1] + a[4 * k + 2] * d[2]);
        val[k] = a[4 * k] * o[0] + a[4 * k + 1] * o[1] + a[4 * k + 2] * o[2] + a[4 * k + 3];
    }
    fall[3] = -(fall[0] + fall[1] + fall[2]);
    val[3] = 1 - (val[0] + val[1] + val[2]);
    int best = -1;
    float bnum = 0, bden = 1; /* the best distance as bnum / bden, bden > 0 */
    for (int k = 0; k < 4; k++) {
        if (k == in || !(fall[k] > 0)) continue; /* the coordinate does not fall: the ray does not leave by this face */
        if (best < 0 || val[k] * bden < bnum * fall[k]) { best = k; bnum = val[k]; bden = fall[k]; }
    }
    if (best < 0) return -1;
    float s = bnum / bden;
    *sexit = s > smin ? s : smin;
    return best;
}

void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays)
{
    rgb[0] = rgb[1] = rgb[2] = 0;
    *T = 1;
    double t = tnear;
    for (int entries = 0; entries < 64 && *T > 1e-4 && t < tfar; entries++) {
        struct RTCRayHit rh;
        rt_ray_once(m->scene, o, d, t, tfar, &rh);
        (*rays)++;
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
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
        /* the walk measures s from the entry point (a perspective eye may be a metre and a half away) */
        float e[3] = {(float)(o[0] + tin * d[0]), (float)(o[1] + tin * d[1]), (float)(o[2] + tin * d[2])};
        float df[3] = {(float)d[0], (float)d[1], (float)d[2]}, send = (float)(tfar - tin), s = 0;
        const float *g = fld + 4 * tt;
        double xa = tf_pos(g[0] * e[0] + g[1] * e[1] + g[2] * e[2] + g[3]);
        tf_val va;
        tf_at(tf, xa, &va);
        for (size_t steps = 0; steps < 4 * v->n_tets + 16 && *T > 1e-4; steps++) {
            const rt_tet *X = m->tets + tt;
            /* the ray's next tetrahedron is one of three: their lines asked for now, while this one's
               exit is found and its piece integrated (the walk is bound by memory latency) */
            for (int k = 0; k < 4; k++)
                if (k != in && X->nb[k] >= 0) {
                    __builtin_prefetch(m->tets + X->nb[k] / 4);
                    __builtin_prefetch(fld + 4 * (X->nb[k] / 4));
                }
            float sx;
            int out = exit_face(X, in, e, df, s, &sx);
            if (out < 0) break;
            float stop = sx < send ? sx : send;
            g = fld + 4 * tt;
            double xb = tf_pos(g[0] * (e[0] + stop * df[0]) + g[1] * (e[1] + stop * df[1]) + g[2] * (e[2] + stop * df[2]) + g[3]);
            segment(tf, xa, xb, (double)stop - s, &va, rgb, T);
            xa = xb;
            s = stop;
            if (stop >= send) return;
            int32_t nb = X->nb[out];
            if (nb < 0) break; /* out of the mesh: Embree finds where it enters again */
            tt = (size_t)nb / 4;
            in = nb % 4;
            /* point data: the field continuous across the face (the same value there); cell data jumps */
            if (!v->point_values) {
                xa = tf_pos(fld[4 * tt + 3]);
                tf_at(tf, xa, &va);
            }
        }
        t = nextafterf((float)(tin + s), INFINITY);
    }
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
