/*
 * RaySpray's shading (thorax/raytrace/raytrace.h): at a hit, the surface's colour as the OpenGL
 * renderer computes it (the value's t interpolated, banded, looked up; contour lines of the same
 * pixel width), lit by the headlight or the scene's lights (Blinn-Phong; shadows by rays, soft from
 * an area light), ambient occlusion, a texture, then mirror reflection and refraction (Snell's law,
 * Schlick's Fresnel) traced on, up to the depth limit. An image plane shows its texel, unlit; an
 * arrow is lit as a surface of its own colour.
 */
#include <math.h>
#include <string.h>

#include "raytrace/rt_impl.h"

/* The OpenGL renderer's lighting constants (src/render/render_shaders.c) */
#define KD 0.75
#define KS 0.2

/* x^40 (the OpenGL renderer's shininess, 40) by squaring: x^8 x^32, six products where pow takes a logarithm */
static inline double shine(double x)
{
    double x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8;
    return x8 * x16 * x16;
}

#define EPS 1e-3

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void norm3(double a[3])
{
    double l = sqrt(dot3(a, a));
    if (l > 0) { a[0] /= l; a[1] /= l; a[2] /= l; }
}

/* A node's t at time tau of the frame interval (motion blur: between this frame's and the next's). */
static double node_t(const rt_surf *s, int32_t i, double tau)
{
    return s->t_next && tau > 0 ? (1 - tau) * s->t[i] + tau * s->t_next[i] : s->t[i];
}

/* The surface's colour at the hit (before lighting) at the sample's time tau: rgb and the contour
 * line's cover. */
static void base_color(const rt_frame *f, const rt_surf *s, unsigned prim, double u, double v, const double p[3],
                       const double n[3], double tau, double rgb[3])
{
    const thx_render_surface *rs = s->rs;
    for (int k = 0; k < 3; k++) rgb[k] = s->color[k];
    if (rs->mode == THX_DRAW_ORIENTATION) return;
    if (s->t) {
        const int32_t *c = rs->surf->tri + 3 * (size_t)prim;
        double t0 = node_t(s, c[0], tau), t1 = node_t(s, c[1], tau), t2 = node_t(s, c[2], tau), w = 1 - u - v;
        double t = w * t0 + u * t1 + v * t2;
        if (!isfinite(t) || fabs(t) > 2) {
            for (int k = 0; k < 3; k++) rgb[k] = f->nan_color[k];
            return;
        }
        int nl = thx_scale_bands(&rs->scale, rs->n_levels > 0 ? rs->n_levels : 1);
        double n_lev = nl > 0 ? nl : 1, tc = fmin(fmax(t, 0), 1);
        if (rs->style == THX_DATA_BANDS || rs->style == THX_DATA_BANDS_CONTOURS) tc = (fmin(floor(tc * n_lev), n_lev - 1) + 0.5) / n_lev;
        if (rs->style != THX_DATA_CONTOURS) {
            unsigned char c8[3];
            thx_colormap_eval(rs->cmap, tc, c8);
            for (int k = 0; k < 3; k++) rgb[k] = c8[k] / 255.0;
        }
        if (rs->style == THX_DATA_CONTOURS || rs->style == THX_DATA_BANDS_CONTOURS || rs->style == THX_DATA_CONTINUOUS_CONTOURS) {
            /* the line's half width in f = t n: the change of f across a pixel (the shader's fwidth) from
               t's gradient on the triangle and the pixel's footprint on it */
            const double *a = rs->surf->xyz + 3 * c[0], *b = rs->surf->xyz + 3 * c[1], *d = rs->surf->xyz + 3 * c[2];
            double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
            double g11 = dot3(e1, e1), g12 = dot3(e1, e2), g22 = dot3(e2, e2), det = g11 * g22 - g12 * g12;
            double fw = 0;
            if (det > 0) {
                double d1 = (t1 - t0) * n_lev, d2 = (t2 - t0) * n_lev;
                double al = (g22 * d1 - g12 * d2) / det, be = (g11 * d2 - g12 * d1) / det, g[3];
                for (int k = 0; k < 3; k++) g[k] = al * e1[k] + be * e2[k];
                double dist = f->ortho ? 1 : sqrt((p[0] - f->eye[0]) * (p[0] - f->eye[0]) + (p[1] - f->eye[1]) * (p[1] - f->eye[1]) +
                                                  (p[2] - f->eye[2]) * (p[2] - f->eye[2]));
                double px = f->pixel_mm * dist, nv = dot3(n, f->view);
                for (int axis = 0; axis < 2; axis++) {
                    const double *sdir = axis ? f->up : f->right;
                    double ns = dot3(n, sdir), step[3];
                    for (int k = 0; k < 3; k++) step[k] = px * (sdir[k] - (fabs(nv) > 1e-6 ? f->view[k] * ns / nv : 0));
                    fw += fabs(dot3(g, step));
                }
            }
            double ff = t * n_lev, kk = floor(ff + 0.5), lw = rs->line_width > 0 ? rs->line_width : 1.5;
            if (kk >= 1 && kk <= n_lev - 1 && fw > 0) {
                double line = fmin(fmax(0.5 * lw - fabs(ff - kk) / fw + 0.5, 0), 1);
                const float *cc = rs->contour_color;
                int zero = cc[0] == 0 && cc[1] == 0 && cc[2] == 0 && cc[3] == 0;
                double ca = zero ? 1 : cc[3];
                for (int k = 0; k < 3; k++) rgb[k] = rgb[k] + (zero ? 0 - rgb[k] : cc[k] - rgb[k]) * line * ca;
            }
        }
    }
    if (s->mat.texture && s->mat.texture_mm > 0) { /* a grid or a checkerboard in model millimetres */
        double q = s->mat.texture_mm;
        if (s->mat.texture == 1) {
            double w = 0.06 * q, dmin = INFINITY;
            for (int k = 0; k < 3; k++) {
                if (fabs(n[k]) > 0.9) continue; /* lines across the surface, not along its normal */
                double r = fabs(p[k] / q - floor(p[k] / q + 0.5)) * q;
                dmin = fmin(dmin, r);
            }
            if (dmin < w) for (int k = 0; k < 3; k++) rgb[k] *= 0.25;
        } else {
            long par = (long)floor(p[0] / q) + (long)floor(p[1] / q) + (long)floor(p[2] / q);
            if (par & 1) for (int k = 0; k < 3; k++) rgb[k] *= 0.2;
        }
    }
}

/* How much light passes from p to a point `dist` along l (1: none blocked; transparent surfaces let
 * their transmitted part through). */
static double visibility(const rt_frame *f, const double p[3], const double l[3], double dist, size_t *rays)
{
    double vis = 1, tnear = EPS;
    for (int k = 0; k < 32 && vis > 1e-3; k++) {
        struct RTCRayHit rh;
        if (!rt_intersect(f, p, l, tnear, dist - EPS, &rh, rays)) return vis;
        size_t ix;
        int kind = rt_kind(f, rh.hit.geomID, &ix);
        if (kind == RT_PLANE) return 0; /* an opaque texel */
        if (kind == RT_SURFACE) vis *= f->s[ix].transmit;
        else {
            double n[3], c[4];
            rt_arrow_hit(&f->ar[ix], rh.hit.primID, rh.hit.u, rh.hit.v, n, c, NULL);
            vis *= 1 - c[3];
        }
        tnear = nextafterf(rh.ray.tfar, INFINITY);
    }
    return vis;
}

/* A unit vector in the cosine-weighted hemisphere about n, from two random numbers. */
static void hemisphere(const double n[3], double r1, double r2, double out[3])
{
    double a[3] = {fabs(n[0]) < 0.9 ? 1 : 0, fabs(n[0]) < 0.9 ? 0 : 1, 0}, t[3], b[3];
    t[0] = n[1] * a[2] - n[2] * a[1];
    t[1] = n[2] * a[0] - n[0] * a[2];
    t[2] = n[0] * a[1] - n[1] * a[0];
    norm3(t);
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
    double phi = 2 * M_PI * r1, sr = sqrt(r2), z = sqrt(1 - r2);
    for (int k = 0; k < 3; k++) out[k] = sr * cos(phi) * t[k] + sr * sin(phi) * b[k] + z * n[k];
}

void rt_environment(const rt_frame *f, const double dir[3], double rgb[3])
{
    const thx_raytrace_opts *o = f->o;
    double l = sqrt(dot3(dir, dir)), z = l > 0 ? dir[2] / l : 0;
    if (o->environment && o->environment->w > 0 && o->environment->h > 0) {
        const thx_raster *e = o->environment;
        double u = (atan2(dir[1], dir[0]) / (2 * M_PI) + 0.5) * e->w - 0.5, v = acos(fmin(fmax(z, -1), 1)) / M_PI * e->h - 0.5;
        int x0 = (int)floor(u), y0 = (int)floor(v);
        double fu = u - x0, fv = v - y0;
        for (int k = 0; k < 3; k++) rgb[k] = 0;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                int x = ((x0 + i) % e->w + e->w) % e->w, y = y0 + j < 0 ? 0 : y0 + j >= e->h ? e->h - 1 : y0 + j;
                double w = (i ? fu : 1 - fu) * (j ? fv : 1 - fv);
                const unsigned char *p = e->rgba + 4 * ((size_t)y * (size_t)e->w + (size_t)x);
                for (int k = 0; k < 3; k++) rgb[k] += w * p[k] / 255.0;
            }
        return;
    }
    if (o->sky) { /* a ground below the horizon, a sky paling towards it */
        static const double zen[3] = {0.22, 0.38, 0.70}, hor[3] = {0.80, 0.85, 0.92}, gnd[3] = {0.30, 0.28, 0.26};
        double a = fabs(z);
        for (int k = 0; k < 3; k++) rgb[k] = z >= 0 ? hor[k] + (zen[k] - hor[k]) * pow(a, 0.6) : hor[k] + (gnd[k] - hor[k]) * pow(a, 0.3);
        return;
    }
    for (int k = 0; k < 3; k++) rgb[k] = f->bg[k];
}

static void shade(const rt_frame *f, const double org[3], const double dir[3], int depth, double weight, uint32_t px,
                  uint32_t sample, const struct RTCRayHit *first, double rgb[3], double *alpha, double *thit, size_t *rays)
{
    struct RTCRayHit rh;
    *thit = INFINITY;
    int hit;
    if (first) {
        rh = *first;
        (*rays)++;
        hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        if (hit && f->any_clip) hit = rt_intersect(f, org, dir, 0, INFINITY, &rh, rays); /* maybe clipped away */
    } else {
        hit = rt_intersect(f, org, dir, depth ? EPS : 0, INFINITY, &rh, rays);
    }
    if (!hit) {
        rt_environment(f, dir, rgb);
        *alpha = f->o->environment || f->o->sky ? 1 : 0; /* the environment covers what it is seen in */
        return;
    }
    *thit = rh.ray.tfar;
    double t = rh.ray.tfar, p[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
    double ps[3] = {p[0], p[1], p[2]}; /* where shadow and occlusion rays start */
    size_t idx;
    int kind = rt_kind(f, rh.hit.geomID, &idx);
    if (kind == RT_PLANE) { /* an image plane: its texel, unlit */
        rt_plane_texel(&f->pl[idx], p, rgb);
        *alpha = 1;
        return;
    }
    double u = rh.hit.u, v = rh.hit.v, w = 1 - u - v;
    double ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    norm3(ng);
    int outside = dot3(ng, dir) < 0; /* the ray meets the surface's outward side (surfaces are outward) */
    double n[3], base[3], reflect = 0, transmit, ior = 1;
    if (kind == RT_ARROWS) { /* an arrow's glyph: its colour, its smooth normal, translucent as its alpha */
        double c[4];
        rt_arrow_hit(&f->ar[idx], rh.hit.primID, u, v, n, c, NULL);
        if (dot3(n, n) == 0) memcpy(n, ng, sizeof n);
        if (dot3(n, dir) > 0) for (int k = 0; k < 3; k++) n[k] = -n[k];
        for (int k = 0; k < 3; k++) base[k] = c[k];
        transmit = 1 - c[3];
    } else {
        const rt_surf *s = &f->s[idx];
        const thx_render_surface *rs = s->rs;
        if (rs->mode == THX_DRAW_FLAT || rs->mode == THX_DRAW_ORIENTATION) {
            memcpy(n, ng, sizeof n);
        } else {
            const int32_t *c = rs->surf->tri + 3 * (size_t)rh.hit.primID;
            const float *n0 = s->g->nrm + 3 * c[0], *n1 = s->g->nrm + 3 * c[1], *n2 = s->g->nrm + 3 * c[2];
            for (int k = 0; k < 3; k++) n[k] = w * n0[k] + u * n1[k] + v * n2[k];
            norm3(n);
            if (dot3(n, n) == 0) memcpy(n, ng, sizeof n);
            /* the shadow terminator: on a coarse smooth-shaded surface, a point the smooth normal turns
               to the light may sit below its neighbour triangles, which then shadow it in bands. The
               shadow and occlusion rays start instead from the point lifted onto the corners' tangent
               planes (each corner's lift where the point lies below its plane, mixed by the
               barycentric weights), on the side the ray sees (Hanika, Ray Tracing Gems II, ch. 4) */
            double side = dot3(n, dir) > 0 ? -1 : 1, bw[3] = {w, u, v};
            const float *nc[3] = {n0, n1, n2};
            for (int j = 0; j < 3; j++) {
                const double *x = rs->surf->xyz + 3 * (size_t)c[j];
                double below = side * ((p[0] - x[0]) * nc[j][0] + (p[1] - x[1]) * nc[j][1] + (p[2] - x[2]) * nc[j][2]);
                if (below < 0)
                    for (int k = 0; k < 3; k++) ps[k] -= bw[j] * below * side * nc[j][k];
            }
        }
        if (dot3(n, dir) > 0) for (int k = 0; k < 3; k++) n[k] = -n[k]; /* facing the ray: two-sided */
        base_color(f, s, rh.hit.primID, u, v, p, n, rt_tau(f, px, sample), base);
        if (rs->mode == THX_DRAW_ORIENTATION && !outside) { /* the inward side: the back colour */
            const float *bc = rs->back_color;
            int zero = bc[0] == 0 && bc[1] == 0 && bc[2] == 0 && bc[3] == 0;
            for (int k = 0; k < 3; k++) base[k] = zero ? 1 : bc[k];
        }
        reflect = s->mat.reflect;
        transmit = s->transmit;
        ior = s->mat.ior;
    }
    /* lighting: what the surface shows of itself counts for (1 - reflect - transmit) of the ray */
    const thx_raytrace_opts *o = f->o;
    double amb = o->ambient, own = weight * (1 - reflect - transmit);
    if (o->ao_samples > 0 && own > 0.2) { /* the ambient term scaled by the unoccluded fraction (where it shows) */
        int free_ = 0;
        for (int k = 0; k < o->ao_samples; k++) {
            double d[3];
            hemisphere(n, rt_rand(px, sample, (uint32_t)depth, 100 + 2 * (uint32_t)k),
                       rt_rand(px, sample, (uint32_t)depth, 101 + 2 * (uint32_t)k), d);
            free_ += visibility(f, ps, d, o->ao_distance, rays) > 0.5;
        }
        amb *= (double)free_ / o->ao_samples;
    }
    double local[3] = {base[0] * amb, base[1] * amb, base[2] * amb}, toeye[3] = {-dir[0], -dir[1], -dir[2]};
    int n_lights = own < 1.0 / 256 ? 0 : o->n_lights > 0 ? o->n_lights : 1; /* nothing of its own to light */
    for (int li = 0; li < n_lights; li++) {
        thx_light head = {.kind = THX_LIGHT_HEAD, .intensity = 1};
        const thx_light *L = o->n_lights > 0 ? &f->lights[li] : &head;
        double l[3], dist = INFINITY, inten = L->intensity > 0 ? L->intensity : 1;
        if (L->kind == THX_LIGHT_HEAD) {
            if (f->ortho) for (int k = 0; k < 3; k++) l[k] = -f->view[k];
            else for (int k = 0; k < 3; k++) l[k] = f->eye[k] - p[k];
            norm3(l);
            double d = fabs(dot3(n, l)); /* the OpenGL renderer's two-sided headlight */
            for (int k = 0; k < 3; k++) local[k] += inten * (KD * d * base[k] + KS * shine(d));
            continue;
        }
        if (L->kind == THX_LIGHT_DIRECTIONAL) {
            for (int k = 0; k < 3; k++) l[k] = -L->dir[k];
            norm3(l);
        } else {
            double q[3];
            memcpy(q, L->pos, sizeof q);
            if (L->kind == THX_LIGHT_AREA) { /* a point of the rectangle, stratified by the pixel's samples */
                double r1 = rt_rand(px, sample, (uint32_t)depth, 10 + (uint32_t)li), r2 = rt_rand(px, sample, (uint32_t)depth, 20 + (uint32_t)li);
                for (int k = 0; k < 3; k++) q[k] += r1 * L->u[k] + r2 * L->v[k];
            }
            for (int k = 0; k < 3; k++) l[k] = q[k] - p[k];
            dist = sqrt(dot3(l, l));
            norm3(l);
        }
        double d = dot3(n, l);
        if (d <= 0) continue;
        double vis = L->shadows ? visibility(f, ps, l, dist, rays) : 1;
        if (vis <= 0) continue;
        double h[3] = {l[0] + toeye[0], l[1] + toeye[1], l[2] + toeye[2]};
        norm3(h);
        double sp = shine(fmax(dot3(n, h), 0));
        for (int k = 0; k < 3; k++) local[k] += vis * inten * (KD * d * base[k] + KS * sp);
    }
    double refl = reflect, trans = transmit;
    if (depth >= o->max_depth) refl = trans = 0;
    const double cut = 1.0 / 256; /* a branch that adds less than a grey level is not traced */
    double out[3];
    for (int k = 0; k < 3; k++) out[k] = (1 - refl - trans) * local[k];
    if (trans > 0) {
        /* refraction: Snell's law into (outside) or out of the surface, Schlick's Fresnel; total
           internal reflection reflects */
        double eta = outside ? 1 / ior : ior, cosi = -dot3(n, dir);
        double k2 = 1 - eta * eta * (1 - cosi * cosi), tdir[3], fr = 0;
        if (ior != 1) {
            double r0 = (1 - ior) / (1 + ior);
            r0 *= r0;
            fr = r0 + (1 - r0) * pow(1 - cosi, 5);
        }
        if (k2 < 0) { fr = 1; }
        else for (int k = 0; k < 3; k++) tdir[k] = eta * dir[k] + (eta * cosi - sqrt(k2)) * n[k];
        if (fr < 1 && weight * trans * (1 - fr) >= cut) {
            double c[3], a, th;
            shade(f, p, tdir, depth + 1, weight * trans * (1 - fr), px, sample, NULL, c, &a, &th, rays);
            for (int k = 0; k < 3; k++) out[k] += trans * (1 - fr) * (a > 0 ? c[k] : f->bg[k]);
        }
        refl += trans * fr;
    }
    if (refl > 0 && weight * refl >= cut) {
        double r[3], c[3], a, th;
        double dn = dot3(dir, n);
        for (int k = 0; k < 3; k++) r[k] = dir[k] - 2 * dn * n[k];
        shade(f, p, r, depth + 1, weight * refl, px, sample, NULL, c, &a, &th, rays);
        for (int k = 0; k < 3; k++) out[k] += refl * (a > 0 ? c[k] : f->bg[k]);
    }
    for (int k = 0; k < 3; k++) rgb[k] = fmin(fmax(out[k], 0), 1);
    *alpha = 1;
}

void rt_shade(const rt_frame *f, const double org[3], const double dir[3], int depth, double weight, uint32_t px,
              uint32_t sample, double rgb[3], double *alpha, double *thit, size_t *rays)
{
    shade(f, org, dir, depth, weight, px, sample, NULL, rgb, alpha, thit, rays);
}

void rt_shade_first(const rt_frame *f, const double org[3], const double dir[3], const struct RTCRayHit *first, uint32_t px,
                    uint32_t sample, double rgb[3], double *alpha, double *thit, size_t *rays)
{
    shade(f, org, dir, 0, 1.0, px, sample, first, rgb, alpha, thit, rays);
}
