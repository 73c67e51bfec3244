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
    free(m->nbr);
    free(m->nbr_face);
    free(m->bface);
    free(m->plane);
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
    m->nbr = thx_malloc(ctx, (nf ? nf : 1) * sizeof *m->nbr);
    m->nbr_face = thx_malloc(ctx, (nf ? nf : 1) * sizeof *m->nbr_face);
    if (!f || !m->nbr || !m->nbr_face) { free(f); rt_vmesh_free(m); return THX_ENOMEM; }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            face_rec *r = &f[4 * t + (size_t)k];
            int32_t a[3], n = 0;
            for (int j = 0; j < 4; j++)
                if (j != k) a[n++] = v->tet[4 * t + (size_t)j];
            /* sorted corners: the key both tetrahedra of a face share */
            if (a[0] > a[1]) { int32_t x = a[0]; a[0] = a[1]; a[1] = x; }
            if (a[1] > a[2]) { int32_t x = a[1]; a[1] = a[2]; a[2] = x; }
            if (a[0] > a[1]) { int32_t x = a[0]; a[0] = a[1]; a[1] = x; }
            memcpy(r->key, a, sizeof a);
            r->slot = (int32_t)(4 * t + (size_t)k);
            m->nbr[4 * t + (size_t)k] = -1;
            m->nbr_face[4 * t + (size_t)k] = -1;
        }
    qsort(f, nf, sizeof *f, face_cmp);
    size_t nb = 0;
    for (size_t i = 0; i < nf;) {
        size_t j = i + 1;
        while (j < nf && !memcmp(f[j].key, f[i].key, sizeof f[i].key)) j++;
        if (j - i == 2) {
            int32_t a = f[i].slot, b = f[i + 1].slot;
            m->nbr[a] = b / 4;
            m->nbr_face[a] = b % 4;
            m->nbr[b] = a / 4;
            m->nbr_face[b] = a % 4;
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
    m->plane = thx_malloc(ctx, 16 * (nt ? nt : 1) * sizeof *m->plane);
    if (!m->plane) { rt_vmesh_free(m); return THX_ENOMEM; }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            const int32_t *c = v->tet + 4 * t;
            const double *p0 = v->xyz + 3 * c[(k + 1) % 4], *p1 = v->xyz + 3 * c[(k + 2) % 4], *p2 = v->xyz + 3 * c[(k + 3) % 4];
            const double *vk = v->xyz + 3 * c[k];
            double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            double sk = n[0] * (vk[0] - p0[0]) + n[1] * (vk[1] - p0[1]) + n[2] * (vk[2] - p0[2]);
            double *pl = m->plane + 16 * t + 4 * (size_t)k;
            if (sk == 0) { pl[0] = pl[1] = pl[2] = 0; pl[3] = 0.25; continue; } /* a flat tetrahedron: never crossed */
            for (int q = 0; q < 3; q++) pl[q] = n[q] / sk;
            pl[3] = -(pl[0] * p0[0] + pl[1] * p0[1] + pl[2] * p0[2]);
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
        if (m->nbr[s] >= 0) continue;
        size_t t = s / 4, n = 0;
        int k = (int)(s % 4);
        for (int j = 0; j < 4; j++)
            if (j != k) ib[3 * q + n++] = (unsigned)v->tet[4 * t + (size_t)j];
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

static inline double clamp01(double t) { return t < 0 ? 0 : t > 1 ? 1 : t; }

/* The transfer function at t (linear between entries; t clamped to [0, 1]). */
static void tf_at(const rt_tf *tf, double t, double c[3], double *tau)
{
    double x = clamp01(t) * (TF_N - 1);
    int i = (int)floor(x);
    if (i >= TF_N - 1) i = TF_N - 2;
    double w = x - i;
    for (int k = 0; k < 3; k++) c[k] = (1 - w) * tf->c[i][k] + w * tf->c[i + 1][k];
    *tau = (1 - w) * tf->tau[i] + w * tf->tau[i + 1];
}

/* One sub-piece of length L with C and tau linear from (c0, tau0) to (c1, tau1): its emission added
 * to rgb under the transmittance *T, and *T reduced. */
/* e^(-x) for x >= 0: a Taylor polynomial where x is small (most pieces of a fine mesh: the error
 * under 1e-13 for x < 0.01), exp elsewhere. */
static double exp_neg(double x)
{
    if (x < 0.01) return 1 - x * (1 - x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x / 120))));
    return exp(-x);
}

static void piece(const double c0[3], double tau0, const double c1[3], double tau1, double L, double rgb[3], double *T)
{
    if (!(L > 0) || (tau0 == 0 && tau1 == 0)) return; /* clear: nothing emitted or absorbed */
    double depth = 0.5 * (tau0 + tau1) * L;
    if (fabs(tau1 - tau0) <= 1e-12 * (fabs(tau0) + fabs(tau1)) || tau0 == tau1) {
        double tau = 0.5 * (tau0 + tau1), x = tau * L, a, b;
        /* exact: int_0^L (c0 + s z) tau e^(-tau z) dz = c0 a + s b, s = (c1 - c0) / L, with
           a = 1 - e^(-x) and b = (1 - e^(-x) (1 + x)) / tau (series where x is small) */
        if (x < 0.01) {
            a = x * (1 - x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x / 120))));
            b = x * x * (0.5 - x * (1.0 / 3 - x * (0.125 - x / 30))) / tau;
        } else {
            double e = exp(-x);
            a = 1 - e;
            b = (1 - e * (1 + x)) / tau;
        }
        for (int k = 0; k < 3; k++) rgb[k] += *T * (c0[k] * a + (c1[k] - c0[k]) / L * b);
        *T *= 1 - a;
        return;
    } else {
        /* 3-point Gauss-Legendre; the optical depth D(x) = tau0 x + (tau1 - tau0) x^2 / (2 L) exact */
        static const double gx[3] = {-0.7745966692414834, 0, 0.7745966692414834}, gw[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
        for (int g = 0; g < 3; g++) {
            double x = 0.5 * L * (gx[g] + 1), w = x / L, D = tau0 * x + (tau1 - tau0) * x * x / (2 * L);
            double tau = tau0 + w * (tau1 - tau0), f = 0.5 * L * gw[g] * tau * exp_neg(D);
            for (int k = 0; k < 3; k++) rgb[k] += *T * f * (c0[k] + w * (c1[k] - c0[k]));
        }
    }
    *T *= exp_neg(depth);
}

/* A segment of length L along which t goes linearly from ta to tb: split where t crosses a table
 * entry, each sub-piece integrated. */
static void segment(const rt_tf *tf, double ta, double tb, double L, double rgb[3], double *T)
{
    ta = clamp01(ta);
    tb = clamp01(tb);
    double xa = ta * (TF_N - 1), xb = tb * (TF_N - 1);
    double c0[3], tau0, c1[3], tau1;
    tf_at(tf, ta, c0, &tau0);
    if (fabs(xb - xa) < 1e-12) {
        piece(c0, tau0, c0, tau0, L, rgb, T);
        return;
    }
    int dir = xb > xa ? 1 : -1;
    double x = xa, s = 0; /* s: the fraction of L done */
    while (*T > 1e-4) {
        double next = dir > 0 ? floor(x) + 1 : ceil(x) - 1;
        if ((dir > 0 && next >= xb) || (dir < 0 && next <= xb)) next = xb;
        double s1 = (next - xa) / (xb - xa);
        tf_at(tf, next / (TF_N - 1), c1, &tau1);
        piece(c0, tau0, c1, tau1, (s1 - s) * L, rgb, T);
        memcpy(c0, c1, sizeof c0);
        tau0 = tau1;
        s = s1;
        x = next;
        if (next == xb) break;
    }
}

/* The field's t at point p in tetrahedron tt: the corners' t (tnode, the scale applied per node,
 * interpolated as the OpenGL renderer interpolates a surface's t) mixed by the barycentric
 * coordinates; cell data: the tetrahedron's. */
static double field_t(const rt_vmesh *m, const thx_raytrace_volume *v, const double *tnode, size_t tt, const double p[3])
{
    if (!v->point_values) return thx_scale_apply(&v->scale, v->cell_values[tt]);
    const int32_t *c = v->tet + 4 * tt;
    const double *pl = m->plane + 16 * tt;
    double t = 0;
    for (int k = 0; k < 4; k++) t += (pl[4 * k] * p[0] + pl[4 * k + 1] * p[1] + pl[4 * k + 2] * p[2] + pl[4 * k + 3]) * tnode[c[k]];
    return t;
}

double *rt_volume_tnode(thx_ctx *ctx, const thx_raytrace_volume *v)
{
    if (!v->point_values) return NULL;
    double *t = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *t);
    if (t)
        for (size_t i = 0; i < v->n_nodes; i++) t[i] = thx_scale_apply(&v->scale, v->point_values[i]);
    return t;
}

/* Where the ray leaves tetrahedron tt entered through face `in` (-1: unknown): the face whose
 * barycentric coordinate falls to 0 first, and the distance; -1 when none falls (a ray grazing). */
static int exit_face(const rt_vmesh *m, size_t tt, int in, const double o[3], const double d[3], double tmin, double *texit)
{
    const double *pl = m->plane + 16 * tt;
    int best = -1;
    double bt = INFINITY;
    for (int k = 0; k < 4; k++) {
        if (k == in) continue;
        const double *a = pl + 4 * k;
        double rate = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
        if (!(rate < 0)) continue; /* the coordinate does not fall: the ray does not leave by this face */
        double t = -(a[0] * o[0] + a[1] * o[1] + a[2] * o[2] + a[3]) / rate;
        if (t < bt) { bt = t; best = k; }
    }
    if (best < 0) return -1;
    *texit = bt > tmin ? bt : tmin;
    return best;
}

void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const double *tnode, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays)
{
    rgb[0] = rgb[1] = rgb[2] = 0;
    *T = 1;
    double t = tnear;
    for (int entries = 0; entries < 64 && *T > 1e-4 && t < tfar; entries++) {
        struct RTCIntersectContext c;
        rtcInitIntersectContext(&c);
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        rh.ray.org_x = (float)o[0];
        rh.ray.org_y = (float)o[1];
        rh.ray.org_z = (float)o[2];
        rh.ray.dir_x = (float)d[0];
        rh.ray.dir_y = (float)d[1];
        rh.ray.dir_z = (float)d[2];
        rh.ray.tnear = (float)t;
        rh.ray.tfar = (float)tfar;
        rh.ray.mask = 0xffffffffu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m->scene, &c, &rh);
        (*rays)++;
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
        int32_t slot = m->bface[rh.hit.primID];
        double tin = rh.ray.tfar;
        /* entering only: a ray that meets a boundary face from inside (leaving) goes on past it */
        size_t tt = (size_t)slot / 4;
        int in = slot % 4;
        {
            const int32_t *cc = v->tet + 4 * tt;
            const double *opp = v->xyz + 3 * cc[in], *p0 = v->xyz + 3 * cc[(in + 1) % 4];
            double ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
            double toopp = ng[0] * (opp[0] - p0[0]) + ng[1] * (opp[1] - p0[1]) + ng[2] * (opp[2] - p0[2]);
            double along = ng[0] * d[0] + ng[1] * d[1] + ng[2] * d[2];
            if ((toopp > 0) != (along > 0)) { t = nextafterf((float)tin, INFINITY); continue; }
        }
        double pt = tin;
        double p[3] = {o[0] + pt * d[0], o[1] + pt * d[1], o[2] + pt * d[2]}, ta = field_t(m, v, tnode, tt, p);
        for (size_t steps = 0; steps < 4 * v->n_tets + 16 && *T > 1e-4; steps++) {
            double tx;
            int out = exit_face(m, tt, in, o, d, pt, &tx);
            if (out < 0) { tx = pt; break; }
            double stop = tx < tfar ? tx : tfar;
            double q[3] = {o[0] + stop * d[0], o[1] + stop * d[1], o[2] + stop * d[2]}, tb = field_t(m, v, tnode, tt, q);
            segment(tf, ta, tb, stop - pt, rgb, T);
            pt = stop;
            if (stop >= tfar) return;
            int32_t nb = m->nbr[4 * tt + (size_t)out];
            if (nb < 0) break; /* out of the mesh: Embree finds where it enters again */
            in = m->nbr_face[4 * tt + (size_t)out];
            tt = (size_t)nb;
            ta = field_t(m, v, tnode, tt, q);
        }
        t = nextafterf((float)pt, INFINITY);
    }
}

thx_status thx_raytrace_volume_ray(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, const double org[3],
                                   const double dir[3], double tnear, double tfar, double rgb[3], double *transmittance)
{
    THX_CHECK(rt_tracer_vmesh(ctx, t, v));
    rt_tf tf;
    rt_tf_build(v, &tf);
    size_t rays = 0;
    double *tnode = rt_volume_tnode(ctx, v);
    if (v->point_values && !tnode) return THX_ENOMEM;
    rt_volume_march(rt_tracer_vmesh_get(t), v, &tf, tnode, org, dir, tnear, tfar, rgb, transmittance, &rays);
    free(tnode);
    return THX_OK;
}
