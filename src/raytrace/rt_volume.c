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
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raytrace/rt_impl.h"
#include "raytrace/rt_walk.h"


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
    free(m->fld);
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
    if (posix_memalign((void **)&m->tets, 64, (nt ? nt : 1) * sizeof *m->tets)) m->tets = NULL;
    if (posix_memalign((void **)&m->fld, 64, 4 * (nt ? nt : 1) * sizeof *m->fld)) m->fld = NULL;
    if (!m->tets || !m->fld) thx_error(ctx, THX_ENOMEM, "out of memory (%zu tetrahedra to walk)", nt);
    if (!f || !m->tets || !m->fld || !m->order) { free(f); rt_vmesh_free(m); return THX_ENOMEM; }
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

float *rt_volume_field(thx_ctx *ctx, rt_vmesh *m, const thx_raytrace_volume *v)
{
    size_t nt = v->n_tets;
    float *fld = m->fld;
    double *tn = v->point_values ? thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *tn) : NULL;
    if (v->point_values && !tn) return NULL;
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

void rt_volume_march(const rt_vmesh *m, const thx_raytrace_volume *v, const rt_tf *tf, const float *fld, const double o[3],
                     const double d[3], double tnear, double tfar, double rgb[3], double *T, size_t *rays)
{
    rt_v4f acc = {0, 0, 0, 0}; /* r, g, b (and a lane unused), in a register while the walk runs */
    double acc_T = 1;
    double t = tnear;
    if (v->have_box) { /* sort-last: the ray ends where it leaves the box */
        double t0, t1;
        rt_box_span(v, o, d, &t0, &t1);
        if (t1 < tfar) tfar = t1;
        if (t0 > t1) tfar = tnear; /* the ray misses the box */
    }
    for (int entries = 0; entries < 64 && acc_T > 1e-4 && t < tfar; entries++) {
        rt_walk w;
        int in = rt_walk_enter(m, v, tf, fld, o, d, &t, tfar, &w, rays);
        if (in == 0) break;
        if (in < 0) continue;
        int r = 1;
        for (size_t steps = 0; steps < 4 * v->n_tets + 16 && acc_T > 1e-4 && r > 0; steps++) r = walk_step(m, v, tf, fld, &w, &acc, &acc_T);
        if (r == 0) break;
        t = nextafterf((float)(w.tin + w.s), INFINITY);
    }
    for (int k = 0; k < 3; k++) rgb[k] = acc[k];
    *T = acc_T;
}

/* What a call of the volume API needs: the tracer's mesh for v (built when new), the transfer
 * function, the field. */
static thx_status volume_call(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, rt_tf *tf, rt_vmesh **m,
                              const float **fld)
{
    THX_CHECK(rt_tracer_vmesh(ctx, t, v));
    rt_tf_build(v, tf);
    *m = rt_tracer_vmesh_get(t);
    *fld = rt_volume_field(ctx, *m, v);
    return *fld ? THX_OK : THX_ENOMEM;
}

thx_status thx_raytrace_volume_ray(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, const double org[3],
                                   const double dir[3], double tnear, double tfar, double rgb[3], double *transmittance)
{
    rt_tf tf;
    rt_vmesh *m;
    const float *fld;
    THX_CHECK(volume_call(ctx, t, v, &tf, &m, &fld));
    size_t rays = 0;
    rt_volume_march(m, v, &tf, fld, org, dir, tnear, tfar, rgb, transmittance, &rays);
    return THX_OK;
}

thx_status thx_raytrace_volume_rays(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v, size_t n, const double (*org)[3],
                                    const double (*dir)[3], const double *tfar, double (*rgb)[3], double *transmittance)
{
    if (n > INT_MAX) return thx_error(ctx, THX_EINPUT, "volume rendering: %zu rays in one call (at most %d)", n, INT_MAX);
    rt_tf tf;
    rt_vmesh *m;
    const float *fld;
    THX_CHECK(volume_call(ctx, t, v, &tf, &m, &fld));
    size_t rays = 0;
    rt_volume_march_n(m, v, &tf, fld, (int)n, org, dir, tfar, rgb, transmittance, &rays);
    return THX_OK;
}
