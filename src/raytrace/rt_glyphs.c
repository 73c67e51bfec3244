/*
 * RaySpray's image planes and arrows (thorax/raytrace/raytrace.h): the scene's textured rectangles
 * and vector glyphs as Embree geometry, built per call (a plane is one quad, an arrow 5 N triangles),
 * and what a hit on them shows.
 *
 * Planes (thx_render_plane) go into a scene of their own (rt_frame.planes), so that rt_intersect
 * can give a surface lying in a plane's own plane the precedence the OpenGL renderer's polygon
 * offset gives it (contours drawn on a scan stay in front). A plane hit shows its texel, unlit, with
 * the OpenGL renderer's addressing: texel (a, b)'s centre at origin + (a + 0.5) / w u + (b + 0.5) / h
 * v, nearest or bilinear (clamped to the edge) as the plane asks; a texel of alpha below 128 (below
 * 1/2 after the bilinear mix) is transparent.
 *
 * Arrows (thx_render_arrows) are 3D glyphs in the surfaces' scene: a cylinder shaft and a cone head,
 * closed by disks. The OpenGL renderer draws them in pixels (the shaft w pixels wide, w the arrow
 * width at least 1; the head hl = min(0.4 len, 4 w + 6) pixels long and 2 max(0.4 hl, w) wide); here
 * the same measures in millimetres at the pixel size where the arrow's middle lies (orthographic:
 * the camera's height over the viewport's; perspective: the pixel's footprint at that distance), with
 * the arrow's 3D length in place of its projected one. Coloured as the OpenGL renderer colours them,
 * lit by the tracer's lights.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "raytrace/rt_impl.h"

/* segments around an arrow's axis */
#define SEG 12
#define ARROW_VERTS (6 * SEG + 2)

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

thx_status rt_planes_build(thx_ctx *ctx, RTCDevice dev, rt_frame *f)
{
    const thx_scene *sc = f->sc;
    if (!sc->n_planes) return THX_OK;
    f->pl = thx_calloc(ctx, sc->n_planes, sizeof *f->pl);
    if (!f->pl) return THX_ENOMEM;
    f->n_pl = sc->n_planes;
    f->planes = rtcNewScene(dev);
    rtcSetSceneFlags(f->planes, RTC_SCENE_FLAG_ROBUST);
    for (size_t i = 0; i < sc->n_planes; i++) {
        const thx_render_plane *pl = &sc->planes[i];
        rt_plane *p = &f->pl[i];
        p->pl = pl;
        if (pl->w < 1 || pl->h < 1 || !pl->rgba)
            return thx_error(ctx, THX_EINPUT, "ray tracer: image plane %zu: %d x %d texels%s", i + 1, pl->w, pl->h,
                             pl->rgba ? "" : ", no texels");
        double g11 = dot3(pl->u, pl->u), g12 = dot3(pl->u, pl->v), g22 = dot3(pl->v, pl->v), det = g11 * g22 - g12 * g12;
        if (!(det > 1e-12 * g11 * g22) || !isfinite(det))
            return thx_error(ctx, THX_EINPUT, "ray tracer: image plane %zu: its edges u and v are parallel or zero", i + 1);
        p->gi[0] = g22 / det;
        p->gi[1] = -g12 / det;
        p->gi[2] = g11 / det;
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_QUAD);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4);
        unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), 1);
        if (!v || !ix) { rtcReleaseGeometry(g); return thx_error(ctx, THX_ENOMEM, "ray tracer: out of memory (image plane)"); }
        for (int c = 0; c < 4; c++) { /* o, o + u, o + u + v, o + v */
            double a = (c == 1 || c == 2) ? 1 : 0, b = c >= 2 ? 1 : 0;
            for (int k = 0; k < 3; k++) v[3 * c + k] = (float)(pl->origin[k] + a * pl->u[k] + b * pl->v[k]);
            ix[c] = (unsigned)c;
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(f->planes, g, (unsigned)(f->n_s + i));
        rtcReleaseGeometry(g); /* the scene holds it */
    }
    rtcCommitScene(f->planes);
    return THX_OK;
}

int rt_plane_texel(const rt_plane *p, const double pt[3], double rgb[3])
{
    const thx_render_plane *pl = p->pl;
    double d[3] = {pt[0] - pl->origin[0], pt[1] - pl->origin[1], pt[2] - pl->origin[2]};
    double du = dot3(d, pl->u), dv = dot3(d, pl->v);
    double s = fmin(fmax(p->gi[0] * du + p->gi[1] * dv, 0), 1), t = fmin(fmax(p->gi[1] * du + p->gi[2] * dv, 0), 1);
    double c[4] = {0, 0, 0, 0};
    if (pl->nearest) {
        int a = (int)floor(s * pl->w), b = (int)floor(t * pl->h);
        a = a < 0 ? 0 : a >= pl->w ? pl->w - 1 : a;
        b = b < 0 ? 0 : b >= pl->h ? pl->h - 1 : b;
        const unsigned char *q = pl->rgba + 4 * ((size_t)b * (size_t)pl->w + (size_t)a);
        for (int k = 0; k < 4; k++) c[k] = q[k] / 255.0;
    } else { /* between the four nearest texel centres, clamped to the edge */
        double x = s * pl->w - 0.5, y = t * pl->h - 0.5;
        int x0 = (int)floor(x), y0 = (int)floor(y);
        double fx = x - x0, fy = y - y0;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                int a = x0 + i, b = y0 + j;
                a = a < 0 ? 0 : a >= pl->w ? pl->w - 1 : a;
                b = b < 0 ? 0 : b >= pl->h ? pl->h - 1 : b;
                double w = (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
                const unsigned char *q = pl->rgba + 4 * ((size_t)b * (size_t)pl->w + (size_t)a);
                for (int k = 0; k < 4; k++) c[k] += w * q[k] / 255.0;
            }
    }
    if (rgb)
        for (int k = 0; k < 3; k++) rgb[k] = c[k];
    return c[3] >= 0.5;
}

/* Two unit vectors perpendicular to d and to each other (e1 x e2 = d). */
static void frame_of(const double d[3], double e1[3], double e2[3])
{
    double a[3] = {fabs(d[0]) < 0.9 ? 1 : 0, fabs(d[0]) < 0.9 ? 0 : 1, 0};
    e1[0] = a[1] * d[2] - a[2] * d[1];
    e1[1] = a[2] * d[0] - a[0] * d[2];
    e1[2] = a[0] * d[1] - a[1] * d[0];
    double l = sqrt(dot3(e1, e1));
    for (int k = 0; k < 3; k++) e1[k] /= l;
    e2[0] = d[1] * e1[2] - d[2] * e1[1];
    e2[1] = d[2] * e1[0] - d[0] * e1[2];
    e2[2] = d[0] * e1[1] - d[1] * e1[0];
}

/* One arrow's vertices (ARROW_VERTS, with their normals) and triangles (5 SEG, indices from base):
 * tail disk, shaft, the head's back disk, the cone. */
static void arrow_mesh(const double tail[3], const double d[3], double len, double r_shaft, double head_len, double r_head,
                       float *v, float *nrm, unsigned *ix, unsigned base)
{
    double e1[3], e2[3], b[3], tip[3];
    frame_of(d, e1, e2);
    for (int k = 0; k < 3; k++) {
        b[k] = tail[k] + (len - head_len) * d[k];
        tip[k] = tail[k] + len * d[k];
    }
    double hyp = sqrt(head_len * head_len + r_head * r_head);
    size_t q = 0;
#define PUT(P, N0, N1, N2)                                                                              \
    do {                                                                                                \
        for (int k_ = 0; k_ < 3; k_++) v[3 * q + k_] = (float)(P)[k_];                                  \
        nrm[3 * q] = (float)(N0);                                                                       \
        nrm[3 * q + 1] = (float)(N1);                                                                   \
        nrm[3 * q + 2] = (float)(N2);                                                                   \
        q++;                                                                                            \
    } while (0)
    PUT(tail, -d[0], -d[1], -d[2]); /* 0: the tail disk's centre */
    for (int pass = 0; pass < 4; pass++)
        for (int i = 0; i < SEG; i++) {
            double ph = 2 * M_PI * i / SEG, c = cos(ph), s = sin(ph), rad[3], p[3];
            for (int k = 0; k < 3; k++) rad[k] = c * e1[k] + s * e2[k];
            if (pass == 0 || pass == 1) { /* the tail disk's ring, the shaft's ring at the tail */
                for (int k = 0; k < 3; k++) p[k] = tail[k] + r_shaft * rad[k];
                if (pass == 0) PUT(p, -d[0], -d[1], -d[2]);
                else PUT(p, rad[0], rad[1], rad[2]);
            } else if (pass == 2) { /* the shaft's ring at the head */
                for (int k = 0; k < 3; k++) p[k] = b[k] + r_shaft * rad[k];
                PUT(p, rad[0], rad[1], rad[2]);
            } else { /* the head's back disk: centre first, then its ring */
                if (i == 0) PUT(b, -d[0], -d[1], -d[2]);
                for (int k = 0; k < 3; k++) p[k] = b[k] + r_head * rad[k];
                PUT(p, -d[0], -d[1], -d[2]);
            }
        }
    /* the cone's base ring (normals at the ring's own angles) and its tips (at the segments' middles) */
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < SEG; i++) {
            double ph = 2 * M_PI * (i + 0.5 * pass) / SEG, c = cos(ph), s = sin(ph), rad[3], p[3], nc[3];
            for (int k = 0; k < 3; k++) {
                rad[k] = c * e1[k] + s * e2[k];
                nc[k] = (head_len * rad[k] + r_head * d[k]) / hyp;
                p[k] = pass ? tip[k] : b[k] + r_head * rad[k];
            }
            PUT(p, nc[0], nc[1], nc[2]);
        }
#undef PUT
    /* vertex numbers: 0 tail centre; 1.. tail ring; 1+SEG.. shaft at the tail; 1+2SEG.. shaft at the head;
       1+3SEG head centre; 2+3SEG.. head ring; 2+4SEG.. cone ring; 2+5SEG.. tips */
    unsigned *t = ix;
    for (unsigned i = 0; i < SEG; i++) {
        unsigned j = (i + 1) % SEG;
        /* outward: seen from outside, counterclockwise (the axis d points out of the tip) */
        *t++ = base; *t++ = base + 1 + j; *t++ = base + 1 + i;
        *t++ = base + 1 + SEG + i; *t++ = base + 1 + SEG + j; *t++ = base + 1 + 2 * SEG + j;
        *t++ = base + 1 + SEG + i; *t++ = base + 1 + 2 * SEG + j; *t++ = base + 1 + 2 * SEG + i;
        *t++ = base + 1 + 3 * SEG; *t++ = base + 2 + 3 * SEG + j; *t++ = base + 2 + 3 * SEG + i;
        *t++ = base + 2 + 4 * SEG + i; *t++ = base + 2 + 4 * SEG + j; *t++ = base + 2 + 5 * SEG + i;
    }
}

thx_status rt_arrows_build(thx_ctx *ctx, RTCDevice dev, rt_frame *f)
{
    const thx_scene *sc = f->sc;
    if (!sc->n_arrows) return THX_OK;
    f->ar = thx_calloc(ctx, sc->n_arrows, sizeof *f->ar);
    if (!f->ar) return THX_ENOMEM;
    f->n_ar = sc->n_arrows;
    for (size_t i = 0; i < sc->n_arrows; i++) {
        const thx_render_arrows *a = &sc->arrows[i];
        rt_arrows *r = &f->ar[i];
        r->a = a;
        if (!a->n) continue;
        if (!a->pos || !a->vec) return thx_error(ctx, THX_EINPUT, "ray tracer: arrows without positions or vectors");
        /* the arrows drawn: finite, nonzero, and at least half a pixel long (as the OpenGL renderer's) */
        r->index = thx_malloc(ctx, a->n * sizeof *r->index);
        r->color = thx_malloc(ctx, a->n * sizeof *r->color);
        double *geo = thx_malloc(ctx, 8 * a->n * sizeof *geo); /* tail, unit direction, length, pixel mm */
        if (!r->index || !r->color || !geo) { free(geo); return THX_ENOMEM; }
        int zero = a->color[0] == 0 && a->color[1] == 0 && a->color[2] == 0 && a->color[3] == 0;
        float fixed[4] = {0, 0, 0, 1};
        if (!zero) memcpy(fixed, a->color, sizeof fixed);
        for (size_t j = 0; j < a->n; j++) {
            const double *p = a->pos + 3 * j, *v = a->vec + 3 * j;
            double mag = sqrt(dot3(v, v));
            if (!(mag > 0) || !isfinite(mag) || !isfinite(p[0] + p[1] + p[2])) continue;
            double len = a->unit_length ? a->scale : a->scale * mag, mid[3];
            if (!(len > 0) || !isfinite(len)) continue;
            for (int k = 0; k < 3; k++) mid[k] = p[k] + 0.5 * len * v[k] / mag - f->eye[k];
            double depth = dot3(mid, f->view), px = f->ortho ? f->pixel_mm : f->pixel_mm * depth;
            if (!(px > 0) || len < 0.5 * px) continue;
            double *g = geo + 8 * r->n;
            for (int k = 0; k < 3; k++) { g[k] = p[k]; g[3 + k] = v[k] / mag; }
            g[6] = len;
            g[7] = px;
            memcpy(r->color[r->n], fixed, sizeof fixed);
            if (a->unit_length) { /* coloured by |v| */
                unsigned char c8[3];
                thx_colormap_eval(a->cmap, fmin(fmax(thx_scale_apply(&a->mag_scale, mag), 0), 1), c8);
                for (int k = 0; k < 3; k++) r->color[r->n][k] = c8[k] / 255.0f;
            }
            r->index[r->n++] = (int32_t)j;
        }
        if (!r->n) { free(geo); continue; }
        RTCGeometry gm = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = rtcSetNewGeometryBuffer(gm, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), ARROW_VERTS * r->n);
        unsigned *ib = rtcSetNewGeometryBuffer(gm, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), RT_ARROW_TRIS * r->n);
        r->nrm = thx_malloc(ctx, 3 * ARROW_VERTS * r->n * sizeof *r->nrm);
        if (!vb || !ib || !r->nrm) { rtcReleaseGeometry(gm); free(geo); return THX_ENOMEM; }
        double w = a->width > 0 ? a->width : 1.5;
        if (w < 1) w = 1;
        for (size_t j = 0; j < r->n; j++) {
            const double *g = geo + 8 * j;
            double len = g[6], px = g[7];
            double head = fmin(0.4 * len, (4 * w + 6) * px), r_head = fmax(0.4 * head, w * px);
            arrow_mesh(g, g + 3, len, 0.5 * w * px, head, r_head, vb + 3 * ARROW_VERTS * j, r->nrm + 3 * ARROW_VERTS * j,
                       ib + 3 * RT_ARROW_TRIS * j, (unsigned)(ARROW_VERTS * j));
        }
        free(geo);
        r->ib = ib; /* Embree's buffer, alive while the frame's scene holds the geometry */
        rtcCommitGeometry(gm);
        rtcAttachGeometryByID(f->scene, gm, (unsigned)(f->n_s + f->n_pl + i));
        rtcReleaseGeometry(gm);
    }
    return THX_OK;
}

void rt_arrow_hit(const rt_arrows *r, unsigned prim, double u, double v, double n[3], double color[4], int32_t *index)
{
    size_t j = prim / RT_ARROW_TRIS;
    const unsigned *c = r->ib + 3 * (size_t)prim; /* the triangle's corners (numbered over the whole set) */
    const float *nb = r->nrm;
    double w = 1 - u - v;
    for (int k = 0; k < 3; k++) n[k] = w * nb[3 * c[0] + k] + u * nb[3 * c[1] + k] + v * nb[3 * c[2] + k];
    double l = sqrt(dot3(n, n));
    if (l > 0)
        for (int k = 0; k < 3; k++) n[k] /= l;
    for (int k = 0; k < 4; k++) color[k] = r->color[j][k];
    if (index) *index = r->index[j];
}

void rt_glyphs_free(rt_frame *f)
{
    for (size_t i = 0; i < f->n_ar; i++) {
        free(f->ar[i].nrm);
        free(f->ar[i].color);
        free(f->ar[i].index);
    }
    free(f->ar);
    free(f->pl);
    if (f->planes) rtcReleaseScene(f->planes);
    f->ar = NULL;
    f->pl = NULL;
    f->planes = NULL;
    f->n_ar = f->n_pl = 0;
}
