/*
 * RaySpray's tracer (thorax/raytrace/raytrace.h): the Embree device, the geometry cache (a surface's
 * BVH is built once and kept while its nodes and triangles stay the same), the scene assembled per
 * call from the cached geometries, and the image traced tile by tile (OpenMP; every pixel
 * independent, every random number a hash, so the picture does not depend on the thread count).
 */
#include <math.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "raytrace/rt_impl.h"

#define TILE 16
#define CACHE_MAX 256

struct thx_tracer {
    RTCDevice dev;
    rt_vmesh vm;
    rt_geom cache[CACHE_MAX];
    size_t n_cache;
    unsigned long call;
    char info[64];
};

static double wall(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

double rt_rand(uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    /* a 32-bit mix (lowbias32) over the keys in turn */
    uint32_t h = 0x9e3779b9u;
    uint32_t k[4] = {a, b, c, d};
    for (int i = 0; i < 4; i++) {
        h ^= k[i] + 0x7f4a7c15u + (h << 6) + (h >> 2);
        h ^= h >> 16;
        h *= 0x7feb352du;
        h ^= h >> 15;
        h *= 0x846ca68bu;
        h ^= h >> 16;
    }
    return (double)h / 4294967296.0;
}

void thx_raytrace_opts_default(thx_raytrace_opts *o)
{
    memset(o, 0, sizeof *o);
    o->samples = 2;
    o->max_depth = 6;
    o->ambient = 0.25;
    o->ao_distance = 30;
    for (int k = 0; k < THX_RAYTRACE_MAX_SURFACES; k++) {
        o->material[k].ior = 1;
        o->material[k].texture_mm = 10;
    }
}

static void on_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    fprintf(stderr, "thorax: Embree error %d: %s\n", (int)code, str ? str : "");
}

thx_status thx_tracer_create(thx_ctx *ctx, thx_tracer **out)
{
    *out = NULL;
    thx_tracer *t = thx_calloc(ctx, 1, sizeof *t);
    if (!t) return THX_ENOMEM;
    t->dev = rtcNewDevice("verbose=0");
    if (!t->dev) {
        free(t);
        return thx_error(ctx, THX_EIO, "Embree: no device (%d)", (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceErrorFunction(t->dev, on_error, NULL);
    snprintf(t->info, sizeof t->info, "Embree %d.%d.%d", (int)rtcGetDeviceProperty(t->dev, RTC_DEVICE_PROPERTY_VERSION_MAJOR),
             (int)rtcGetDeviceProperty(t->dev, RTC_DEVICE_PROPERTY_VERSION_MINOR),
             (int)rtcGetDeviceProperty(t->dev, RTC_DEVICE_PROPERTY_VERSION_PATCH));
    *out = t;
    return THX_OK;
}

static void geom_free(rt_geom *g)
{
    if (g->geom) rtcReleaseGeometry(g->geom);
    free(g->nrm);
    memset(g, 0, sizeof *g);
}

void thx_tracer_destroy(thx_tracer **tp)
{
    thx_tracer *t = tp ? *tp : NULL;
    if (!t) return;
    for (size_t i = 0; i < t->n_cache; i++) geom_free(&t->cache[i]);
    rt_vmesh_free(&t->vm);
    rtcReleaseDevice(t->dev);
    free(t);
    *tp = NULL;
}

const char *thx_tracer_info(const thx_tracer *t) { return t->info; }

thx_status rt_tracer_vmesh(thx_ctx *ctx, thx_tracer *t, const thx_raytrace_volume *v)
{
    if (!v->xyz || !v->tet || !v->n_tets || (!v->point_values && !v->cell_values))
        return thx_error(ctx, THX_EINPUT, "volume rendering: a mesh (nodes, tetrahedra) and its values are needed");
    if (!(v->density >= 0) || !isfinite(v->density)) return thx_error(ctx, THX_EINPUT, "volume rendering: density %g", v->density);
    return rt_vmesh_build(ctx, t->dev, v, &t->vm);
}

rt_vmesh *rt_tracer_vmesh_get(thx_tracer *t) { return &t->vm; }

/* The cached geometry of surface s, built when new or changed. */
static thx_status geom_of(thx_ctx *ctx, thx_tracer *t, const thx_surface *s, const rt_geom **out, size_t *builds)
{
    for (size_t i = 0; i < t->n_cache; i++) {
        rt_geom *g = &t->cache[i];
        if (g->surf == s && g->xyz == s->xyz && g->tri == s->tri && g->n_nodes == s->n_nodes && g->n_tris == s->n_tris) {
            g->used = t->call;
            *out = g;
            return THX_OK;
        }
    }
    /* a slot: a free one, else the least recently used */
    size_t slot = t->n_cache;
    if (slot == CACHE_MAX) {
        slot = 0;
        for (size_t i = 1; i < t->n_cache; i++)
            if (t->cache[i].used < t->cache[slot].used) slot = i;
        if (t->cache[slot].used == t->call) return thx_error(ctx, THX_EINPUT, "ray tracer: more than %d surfaces", CACHE_MAX);
        geom_free(&t->cache[slot]);
    } else {
        t->n_cache++;
    }
    rt_geom *g = &t->cache[slot];
    memset(g, 0, sizeof *g);
    g->geom = rtcNewGeometry(t->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       s->n_nodes ? s->n_nodes : 1);
    unsigned *ix = rtcSetNewGeometryBuffer(g->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                           s->n_tris ? s->n_tris : 1);
    g->nrm = thx_calloc(ctx, 3 * (s->n_nodes ? s->n_nodes : 1), sizeof *g->nrm);
    if (!v || !ix || !g->nrm) { geom_free(g); t->n_cache -= slot == t->n_cache - 1; return THX_ENOMEM; }
    for (size_t i = 0; i < 3 * s->n_nodes; i++) v[i] = (float)s->xyz[i];
    double *acc = thx_calloc(ctx, 3 * (s->n_nodes ? s->n_nodes : 1), sizeof *acc);
    if (!acc) { geom_free(g); return THX_ENOMEM; }
    for (size_t k = 0; k < 3 * s->n_tris; k++) ix[k] = (unsigned)s->tri[k];
    thx_surface_normal_sums(s, acc); /* area-weighted */
    for (size_t i = 0; i < s->n_nodes; i++) {
        double l = sqrt(acc[3 * i] * acc[3 * i] + acc[3 * i + 1] * acc[3 * i + 1] + acc[3 * i + 2] * acc[3 * i + 2]);
        for (int q = 0; q < 3; q++) g->nrm[3 * i + q] = l > 0 ? (float)(acc[3 * i + q] / l) : 0.0f;
    }
    free(acc);
    rtcCommitGeometry(g->geom);
    g->surf = s;
    g->xyz = s->xyz;
    g->tri = s->tri;
    g->n_nodes = s->n_nodes;
    g->n_tris = s->n_tris;
    g->used = t->call;
    (*builds)++;
    *out = g;
    return THX_OK;
}

void rt_ray_once(RTCScene sc, const double org[3], const double dir[3], double tnear, double tfar, struct RTCRayHit *rh)
{
    struct RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    memset(rh, 0, sizeof *rh);
    rh->ray.org_x = (float)org[0];
    rh->ray.org_y = (float)org[1];
    rh->ray.org_z = (float)org[2];
    rh->ray.dir_x = (float)dir[0];
    rh->ray.dir_y = (float)dir[1];
    rh->ray.dir_z = (float)dir[2];
    rh->ray.tnear = (float)tnear;
    rh->ray.tfar = (float)tfar;
    rh->ray.mask = 0xffffffffu;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(sc, &c, rh);
}

/* The surfaces and arrows: the nearest hit the clip planes keep (surfaces with no_clip are kept
 * whole; arrows are cut as the OpenGL renderer cuts them). */
static int hit_solid(const rt_frame *f, const double org[3], const double dir[3], double tnear, double tfar,
                     struct RTCRayHit *rh, size_t *rays)
{
    for (int pass = 0; pass < 256; pass++) {
        rt_ray_once(f->scene, org, dir, tnear, tfar, rh);
        (*rays)++;
        if (rh->hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
        size_t k;
        int kind = rt_kind(f, rh->hit.geomID, &k);
        if (!f->any_clip || (kind == RT_SURFACE && f->s[k].no_clip)) return 1;
        double t = rh->ray.tfar, p[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
        int kept = 1;
        for (int c = 0; c < f->sc->n_clip; c++) {
            const thx_clip_plane *cp = &f->sc->clip[c];
            if (cp->n[0] * p[0] + cp->n[1] * p[1] + cp->n[2] * p[2] + cp->d < 0) kept = 0;
        }
        if (kept) return 1;
        tnear = nextafterf((float)t, INFINITY); /* clipped away: on along the ray */
    }
    return 0;
}

/* Orthographic: how far behind the eye's plane the scene's box (f->box_lo..box_hi, the image planes
 * in it) reaches, where eye rays start. */
static void frame_back(rt_frame *f)
{
    f->back = 0;
    if (f->ortho)
        for (int q = 0; q < 8 && f->box_lo[0] <= f->box_hi[0]; q++) {
            double corner[3] = {q & 1 ? f->box_hi[0] : f->box_lo[0], q & 2 ? f->box_hi[1] : f->box_lo[1],
                                q & 4 ? f->box_hi[2] : f->box_lo[2]};
            double d = 0;
            for (int k = 0; k < 3; k++) d -= (corner[k] - f->eye[k]) * f->view[k];
            f->back = fmax(f->back, d + 1);
        }
}

/* The camera's frame in f (f->cam, eye, view, right, up; the view's half extents at f->aspect and a
 * pixel's size for f->vp_h rows; the
 * lights given in the camera's axes turned into the model's; how far behind the eye's plane an
 * orthographic ray starts, from f's box): 0, or 1 eye at the centre, 2 up along the line of sight, 3
 * orthographic with no height. */
static int frame_camera(rt_frame *f, const thx_camera *c)
{
    const thx_raytrace_opts *o = f->o;
    f->cam = *c;
    double v[3] = {c->center[0] - c->eye[0], c->center[1] - c->eye[1], c->center[2] - c->eye[2]};
    double lv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(lv > 0)) return 1;
    for (int k = 0; k < 3; k++) { f->view[k] = v[k] / lv; f->eye[k] = c->eye[k]; }
    double r[3] = {f->view[1] * c->up[2] - f->view[2] * c->up[1], f->view[2] * c->up[0] - f->view[0] * c->up[2],
                   f->view[0] * c->up[1] - f->view[1] * c->up[0]};
    double lr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(lr > 0)) return 2;
    for (int k = 0; k < 3; k++) f->right[k] = r[k] / lr;
    f->up[0] = f->right[1] * f->view[2] - f->right[2] * f->view[1];
    f->up[1] = f->right[2] * f->view[0] - f->right[0] * f->view[2];
    f->up[2] = f->right[0] * f->view[1] - f->right[1] * f->view[0];
    for (int i = 0; i < o->n_lights && i < THX_RAYTRACE_MAX_LIGHTS; i++) {
        thx_light *L = &f->lights[i];
        *L = o->lights[i];
        if (L->in_camera)
            for (int k = 0; k < 3; k++) L->dir[k] = o->lights[i].dir[0] * f->right[k] + o->lights[i].dir[1] * f->up[k] + o->lights[i].dir[2] * f->view[k];
    }
    f->ortho = !(c->fov_deg > 0);
    f->half_h = f->ortho ? 0.5 * c->height : tan(0.5 * c->fov_deg * M_PI / 180);
    f->half_w = f->half_h * f->aspect;
    f->pixel_mm = 2 * f->half_h / f->vp_h;
    if (f->ortho && !(f->half_h > 0)) return 3;
    frame_back(f);
    return 0;
}

int rt_intersect(const rt_frame *f, const double org[3], const double dir[3], double tnear, double tfar,
                 struct RTCRayHit *rh, size_t *rays)
{
    int hit = hit_solid(f, org, dir, tnear, tfar, rh, rays);
    if (!f->planes) return hit;
    /* the image planes (never clipped), in front of the solid hit by more than a hair: a surface in a
       plane's own plane wins (the OpenGL renderer's polygon offset behind it); transparent texels let
       the ray on */
    double lim = tfar;
    if (hit) lim = rh->ray.tfar - 1e-4 * fmax(1, fabs(rh->ray.tfar));
    struct RTCRayHit ph;
    for (int pass = 0; pass < 64 && tnear < lim; pass++) {
        rt_ray_once(f->planes, org, dir, tnear, lim, &ph);
        (*rays)++;
        if (ph.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
        double t = ph.ray.tfar, p[3] = {org[0] + t * dir[0], org[1] + t * dir[1], org[2] + t * dir[2]};
        size_t k;
        rt_kind(f, ph.hit.geomID, &k);
        if (rt_plane_texel(&f->pl[k], p, NULL)) {
            *rh = ph;
            return 1;
        }
        tnear = nextafterf((float)t, INFINITY);
    }
    return hit;
}

/* The call's frame for a viewport vp_w x vp_h pixels: the camera's frame, the scene surfaces'
 * geometries (built when needed) and their per-node t, the image planes and the arrows' glyphs
 * (built per call). */
static thx_status frame_build(thx_ctx *ctx, thx_tracer *t, const thx_scene *sc, const thx_raytrace_opts *o, int vp_w, int vp_h,
                              rt_frame *f, size_t *builds)
{
    memset(f, 0, sizeof *f);
    f->sc = sc;
    f->o = o;
    f->vp_h = vp_h;
    f->aspect = (double)vp_w / vp_h;
    if ((sc->n_surfaces && !sc->surfaces) || (sc->n_arrows && !sc->arrows) || (sc->n_planes && !sc->planes))
        return thx_error(ctx, THX_EINPUT, "ray tracer: the scene's surface, arrow or plane array is NULL");
    /* the camera's frame (the scene's box, where orthographic rays start, after the build) */
    static const char *why[] = {"", "eye at the centre", "up along the line of sight", "orthographic with no height"};
    f->box_lo[0] = 1;
    f->box_hi[0] = 0;
    int bad = frame_camera(f, &sc->camera);
    if (bad) return thx_error(ctx, THX_EINPUT, "ray tracer: degenerate camera (%s)", why[bad]);
    f->s = thx_calloc(ctx, sc->n_surfaces ? sc->n_surfaces : 1, sizeof *f->s);
    if (!f->s) return THX_ENOMEM;
    f->n_s = sc->n_surfaces;
    if (o->next && o->shutter > 0) { /* motion blur: the next frame's scene, the same surfaces */
        if (o->next->n_surfaces != sc->n_surfaces)
            return thx_error(ctx, THX_EINPUT, "motion blur: the next frame's scene has %zu surfaces, this frame's %zu (the same "
                             "surfaces in the same order)", o->next->n_surfaces, sc->n_surfaces);
        for (size_t i = 0; i < sc->n_surfaces; i++) {
            const thx_surface *a = sc->surfaces[i].surf, *b = o->next->surfaces[i].surf;
            if ((a == NULL) != (b == NULL) || (a && a->n_nodes != b->n_nodes))
                return thx_error(ctx, THX_EINPUT, "motion blur: surface %zu of the next frame's scene is not this frame's (%zu "
                                 "nodes, %zu)", i, b ? b->n_nodes : 0, a ? a->n_nodes : 0);
        }
        rt_frame probe = {.o = o, .aspect = f->aspect, .vp_h = vp_h};
        int bad_next = frame_camera(&probe, &o->next->camera);
        if (bad_next)
            return thx_error(ctx, THX_EINPUT, "motion blur: the next frame's camera is degenerate (%s)", why[bad_next]);
        f->next = o->next;
        f->shutter = fmin(o->shutter, 1);
    }
    f->scene = rtcNewScene(t->dev);
    rtcSetSceneFlags(f->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(f->scene, RTC_BUILD_QUALITY_HIGH);
    static const float grey[4] = {0.85f, 0.85f, 0.85f, 1}, nan_default[4] = {0.7f, 0.45f, 0.7f, 1};
    for (size_t i = 0; i < sc->n_surfaces; i++) {
        const thx_render_surface *rs = &sc->surfaces[i];
        rt_surf *s = &f->s[i];
        s->rs = rs;
        if (rs->mode == THX_DRAW_HIDDEN || !rs->surf || !rs->surf->n_tris) continue;
        THX_CHECK(geom_of(ctx, t, rs->surf, &s->g, builds));
        int zero = rs->color[0] == 0 && rs->color[1] == 0 && rs->color[2] == 0 && rs->color[3] == 0;
        memcpy(s->color, zero ? grey : rs->color, sizeof s->color);
        s->mat = i < THX_RAYTRACE_MAX_SURFACES ? o->material[i] : o->material[0];
        if (!(s->mat.ior > 0)) s->mat.ior = 1;
        s->transmit = s->mat.transmit > 0 ? s->mat.transmit : s->color[3] < 1 ? 1 - s->color[3] : 0;
        s->no_clip = rs->no_clip;
        if (rs->values) {
            s->t = thx_malloc(ctx, rs->surf->n_nodes * sizeof *s->t);
            if (!s->t) return THX_ENOMEM;
            thx_scale_apply_n(&rs->scale, rs->values, rs->surf->n_nodes, s->t);
            const thx_render_surface *nx = f->next ? &f->next->surfaces[i] : NULL;
            if (nx && nx->values && (nx->values != rs->values || memcmp(&nx->scale, &rs->scale, sizeof rs->scale))) {
                /* the next frame's values, on its own scale (the same as this frame's: none) */
                s->t_next = thx_malloc(ctx, rs->surf->n_nodes * sizeof *s->t_next);
                if (!s->t_next) return THX_ENOMEM;
                thx_scale_apply_n(&nx->scale, nx->values, rs->surf->n_nodes, s->t_next);
            }
        }
        rtcAttachGeometryByID(f->scene, s->g->geom, (unsigned)i);
    }
    THX_CHECK(rt_planes_build(ctx, t->dev, f));
    THX_CHECK(rt_arrows_build(ctx, t->dev, f));
    rtcCommitScene(f->scene);
    int zero_nan = sc->nan_color[0] == 0 && sc->nan_color[1] == 0 && sc->nan_color[2] == 0 && sc->nan_color[3] == 0;
    memcpy(f->nan_color, zero_nan ? nan_default : sc->nan_color, sizeof f->nan_color);
    memcpy(f->bg, sc->background, sizeof f->bg);
    f->any_clip = sc->n_clip > 0;
    /* the scene's box (its image planes too): where orthographic eye rays start */
    for (int q = 0; q < 2; q++) {
        struct RTCBounds b;
        if (q == 1 && !f->planes) break;
        rtcGetSceneBounds(q ? f->planes : f->scene, &b);
        if (!(b.lower_x <= b.upper_x)) continue;
        double lo[3] = {b.lower_x, b.lower_y, b.lower_z}, hi[3] = {b.upper_x, b.upper_y, b.upper_z};
        int empty = !(f->box_lo[0] <= f->box_hi[0]);
        for (int k = 0; k < 3; k++) {
            f->box_lo[k] = empty ? lo[k] : fmin(f->box_lo[k], lo[k]);
            f->box_hi[k] = empty ? hi[k] : fmax(f->box_hi[k], hi[k]);
        }
    }
    frame_back(f);
    return THX_OK;
}

static void frame_free(rt_frame *f)
{
    rt_glyphs_free(f);
    for (size_t i = 0; i < f->n_s; i++) {
        free(f->s[i].t);
        free(f->s[i].t_next);
    }
    free(f->s);
    if (f->scene) rtcReleaseScene(f->scene);
    memset(f, 0, sizeof *f);
}

/* The eye ray through viewport point (x, y) of a w x h viewport: thx_camera_ray's ray, from the
 * camera's frame made once (f->right, up, view, half_w, half_h) rather than per pixel; an
 * orthographic ray starts behind everything traced (thx_camera_ray puts its origin on the eye's
 * plane, which may cut the model). */
static inline void primary_ray(const rt_frame *f, int w, int h, double x, double y, double org[3], double dir[3])
{
    double nx = 2 * x / w - 1, ny = 1 - 2 * y / h;
    if (!f->ortho) {
        double a = nx * f->half_w, b = ny * f->half_h, n = 0;
        for (int k = 0; k < 3; k++) {
            org[k] = f->eye[k];
            dir[k] = f->view[k] + a * f->right[k] + b * f->up[k];
            n += dir[k] * dir[k];
        }
        n = 1 / sqrt(n);
        for (int k = 0; k < 3; k++) dir[k] *= n;
    } else {
        double a = nx * f->half_w, b = ny * f->half_h;
        for (int k = 0; k < 3; k++) {
            dir[k] = f->view[k];
            org[k] = f->eye[k] + a * f->right[k] + b * f->up[k] - f->back * dir[k];
        }
    }
}

/* Ray i of an eye-ray packet: from o along d (float, as Embree takes them), from 0 to infinity, no
 * hit yet. */
static inline void packet_rayf(struct RTCRayHit16 *pk, int i, const float o[3], const float d[3])
{
    pk->ray.org_x[i] = o[0], pk->ray.org_y[i] = o[1], pk->ray.org_z[i] = o[2];
    pk->ray.dir_x[i] = d[0], pk->ray.dir_y[i] = d[1], pk->ray.dir_z[i] = d[2];
    pk->ray.tnear[i] = 0;
    pk->ray.tfar[i] = INFINITY;
    pk->ray.time[i] = 0;
    pk->ray.mask[i] = 0xffffffffu;
    pk->ray.id[i] = (unsigned)i;
    pk->ray.flags[i] = 0;
    pk->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
    pk->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

/* The same from a ray in double. */
static inline void packet_ray(struct RTCRayHit16 *pk, int i, const double org[3], const double dir[3])
{
    float o[3] = {(float)org[0], (float)org[1], (float)org[2]}, d[3] = {(float)dir[0], (float)dir[1], (float)dir[2]};
    packet_rayf(pk, i, o, d);
}

/* The id image's eye rays for the pixels x0 .. x0 + n - 1 of row y (n at most TILE), through their
 * centres, as a packet: in float, the directions not normalized (what a ray meets first does not
 * depend on its direction's length), the others not valid. */
static void packet_ids_row(const rt_frame *f, int w, int h, int x0, int n, int y, struct RTCRayHit16 *pk, int *valid)
{
    float ny = (float)(1 - 2 * (y + 0.5) / h), b = ny * (float)f->half_h;
    float e[3], v[3], r[3], u[3];
    for (int k = 0; k < 3; k++) e[k] = (float)f->eye[k], v[k] = (float)f->view[k], r[k] = (float)f->right[k], u[k] = (float)f->up[k];
    for (int i = 0; i < TILE; i++) {
        float a = (float)((2 * (x0 + i + 0.5) / w - 1) * f->half_w), o[3], d[3];
        for (int k = 0; k < 3; k++) {
            if (f->ortho) {
                d[k] = v[k];
                o[k] = e[k] + a * r[k] + b * u[k] - (float)f->back * v[k];
            } else {
                d[k] = v[k] + a * r[k] + b * u[k];
                o[k] = e[k];
            }
        }
        valid[i] = i < n ? -1 : 0;
        packet_rayf(pk, i, o, d);
    }
}

/* The packet's rays (those valid) through the scene together: Embree's SIMD traversal of coherent
 * rays (a row of a tile's eye rays). */
static inline void packet_trace(RTCScene scene, const int *valid, struct RTCRayHit16 *pk)
{
    struct RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    c.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect16(valid, scene, &c, pk);
}

/* primary_ray for the TILE eye rays of a packet at (xs[i], ys[i]), the same rays to the last bit: the
 * perspective directions' lengths taken two at a time in SSE2's lanes (one square root and one
 * division a ray, one at a time, were a tenth of a primary-ray frame). */
static void primary_row(const rt_frame *f, int w, int h, const double *xs, const double *ys, double (*org)[3], double (*dir)[3])
{
#ifdef __SSE2__
    if (!f->ortho) {
        _Alignas(16) double n2[TILE];
        for (int i = 0; i < TILE; i++) {
            double a = (2 * xs[i] / w - 1) * f->half_w, b = (1 - 2 * ys[i] / h) * f->half_h;
            n2[i] = 0;
            for (int k = 0; k < 3; k++) {
                org[i][k] = f->eye[k];
                dir[i][k] = f->view[k] + a * f->right[k] + b * f->up[k];
                n2[i] += dir[i][k] * dir[i][k];
            }
        }
        for (int i = 0; i < TILE; i += 2)
            _mm_store_pd(n2 + i, _mm_div_pd(_mm_set1_pd(1), _mm_sqrt_pd(_mm_load_pd(n2 + i))));
        for (int i = 0; i < TILE; i++)
            for (int k = 0; k < 3; k++) dir[i][k] *= n2[i];
        return;
    }
#endif
    for (int i = 0; i < TILE; i++) primary_ray(f, w, h, xs[i], ys[i], org[i], dir[i]);
}

/* The camera at time tau of the frame interval: eye, centre, up, field of view and height linear
 * between this frame's (a) and the next's (b); tau = 0 gives a exactly. */
static void camera_lerp(const thx_camera *a, const thx_camera *b, double tau, thx_camera *c)
{
    for (int k = 0; k < 3; k++) {
        c->eye[k] = a->eye[k] + tau * (b->eye[k] - a->eye[k]);
        c->center[k] = a->center[k] + tau * (b->center[k] - a->center[k]);
        c->up[k] = a->up[k] + tau * (b->up[k] - a->up[k]);
    }
    c->fov_deg = a->fov_deg + tau * (b->fov_deg - a->fov_deg);
    c->height = a->height + tau * (b->height - a->height);
}

/* A colour component in [0, 1] (clamped) as a byte, rounded. */
static inline unsigned char byte01(double c) { return (unsigned char)((c > 1 ? 1 : c > 0 ? c : 0) * 255 + 0.5); }

static int gcd(int a, int b) { return b ? gcd(b, a % b) : a; }

/* A pixel's premultiplied colour (r, g, b) of coverage a over the background (bg, clear) or over the
 * pixel's own colour (not clear), into its bytes. */
static void pixel_over(unsigned char *p, double r, double g, double b, double a, int clear, const float bgc[4])
{
    double c[3] = {r, g, b}, bga = clear ? bgc[3] : p[3] / 255.0;
    for (int k = 0; k < 3; k++) {
        double bg = clear ? bgc[k] : p[k] / 255.0;
        p[k] = byte01(c[k] + (1 - a) * bg); /* the samples' colours over the background */
    }
    p[3] = byte01(a + (1 - a) * bga);
}

static void viewport_of(const thx_scene *sc, const thx_raster *img, int vp[4]);

void thx_raytrace_layer_finish(const thx_scene *sc, int samples, const float *layer, thx_raster *img)
{
    int vp[4];
    viewport_of(sc, img, vp);
    size_t n = (size_t)samples * (size_t)samples;
    for (int y = vp[1]; y < vp[1] + vp[3] && y < img->h; y++)
        for (int x = vp[0]; x < vp[0] + vp[2] && x < img->w; x++) {
            size_t at = (size_t)y * (size_t)img->w + (size_t)x;
            double acc[4] = {0, 0, 0, 0};
            for (size_t s = 0; s < n; s++) /* the samples in the order thx_raytrace_scene sums them */
                for (int k = 0; k < 4; k++) acc[k] += layer[4 * (at * n + s) + (size_t)k];
            pixel_over(img->rgba + 4 * at, acc[0] / (double)n, acc[1] / (double)n, acc[2] / (double)n, acc[3] / (double)n,
                       sc->clear, sc->background);
        }
}

static void viewport_of(const thx_scene *sc, const thx_raster *img, int vp[4])
{
    if (sc->viewport[2] > 0) memcpy(vp, sc->viewport, sizeof(int) * 4);
    else { vp[0] = vp[1] = 0; vp[2] = img->w; vp[3] = img->h; }
}

thx_status thx_raytrace_scene(thx_ctx *ctx, thx_tracer *t, const thx_scene *sc, const thx_raytrace_opts *o_in, thx_raster *img,
                           thx_raytrace_stats *stats)
{
    double t0 = wall();
    thx_raytrace_opts od;
    if (!o_in) thx_raytrace_opts_default(&od);
    const thx_raytrace_opts *o = o_in ? o_in : &od;
    int vp[4];
    viewport_of(sc, img, vp);
    if (vp[2] < 1 || vp[3] < 1 || vp[0] < 0 || vp[1] < 0 || vp[0] + vp[2] > img->w || vp[1] + vp[3] > img->h)
        return thx_error(ctx, THX_EINPUT, "ray tracer: viewport %d,%d %dx%d outside the %dx%d image", vp[0], vp[1], vp[2], vp[3],
                         img->w, img->h);
    if (o->samples < 1 || o->samples > 64) return thx_error(ctx, THX_EINPUT, "ray tracer: %d samples a side (1 to 64)", o->samples);
    if (!(o->shutter >= 0 && o->shutter <= 1))
        return thx_error(ctx, THX_EINPUT, "motion blur: shutter %g (0 to 1 of the frame interval)", o->shutter);
    t->call++;
    size_t builds = 0;
    rt_frame f;
    thx_status st = frame_build(ctx, t, sc, o, vp[2], vp[3], &f, &builds);
    double t1 = wall();
    if (st != THX_OK) { frame_free(&f); return st; }
    f.n_samples = o->samples * o->samples;
    for (f.tau_stride = (int)(0.618 * f.n_samples); f.tau_stride > 1 && gcd(f.tau_stride, f.n_samples) != 1; f.tau_stride--) {}
    if (f.tau_stride < 1) f.tau_stride = 1;
    rt_tf *tf = NULL;
    if (o->volume) { /* the field inside its mesh: the mesh's faces kept across calls, the values new */
        size_t before = t->vm.builds;
        st = rt_tracer_vmesh(ctx, t, o->volume);
        tf = st == THX_OK ? thx_malloc(ctx, sizeof *tf) : NULL;
        if (st != THX_OK || !tf) { frame_free(&f); return st != THX_OK ? st : THX_ENOMEM; }
        rt_tf_build(o->volume, tf);
        f.vm = &t->vm;
        f.tf = tf;
        f.fld = rt_volume_field(ctx, &t->vm, o->volume);
        if (!f.fld) { free(tf); frame_free(&f); return THX_ENOMEM; }
        builds += t->vm.builds - before;
    }
    int tw = (vp[2] + TILE - 1) / TILE, th = (vp[3] + TILE - 1) / TILE, n_tiles = tw * th, done = 0;
    /* sort-first: this rank's tiles alone (tile k to rank k mod size) */
    int share = o->share_size > 1 ? o->share_size : 1, mine = o->share_size > 1 ? o->share_rank : 0;
    if (mine < 0 || mine >= share) {
        frame_free(&f);
        free(tf);
        return thx_error(ctx, THX_EINPUT, "ray tracer: share %d of %d", o->share_rank, o->share_size);
    }
    int n_mine = n_tiles / share + (mine < n_tiles % share);
    size_t rays = 0, primary = 0;
    int ns = o->samples;
    /* eye rays in packets of a tile's row (Embree's SIMD traversal of coherent rays), where the frame
       has no motion blur (one camera) and no image planes (looked for after the solid hit) */
    int packets = !f.next && !f.planes;
#pragma omp parallel for schedule(dynamic) reduction(+ : rays, primary)
    for (int tile = 0; tile < n_tiles; tile++) {
        if (tile % share != mine) continue;
        int x0 = (tile % tw) * TILE, y0 = (tile / tw) * TILE, x1 = x0 + TILE < vp[2] ? x0 + TILE : vp[2];
        for (int y = y0; y < y0 + TILE && y < vp[3]; y++) {
            double acc[TILE][3], cov[TILE];
            for (int i = 0; i < TILE; i++) acc[i][0] = acc[i][1] = acc[i][2] = cov[i] = 0;
            /* the samples in the same order for each pixel as one pixel at a time (the same sums) */
            for (int sy = 0; sy < ns; sy++)
                for (int sx = 0; sx < ns; sx++) {
                    uint32_t sample = (uint32_t)(sy * ns + sx);
                    double org[TILE][3], dir[TILE][3], jx[TILE], jy[TILE]; /* jx, jy: the sample's place in its pixel */
                    struct RTCRayHit16 pk;
                    _Alignas(64) int valid[TILE]; /* (Embree reads it as one vector) */
                    double xs[TILE], ys[TILE];
                    for (int x = x0; x < x0 + TILE; x++) {
                        int i = x - x0;
                        uint32_t px = (uint32_t)(y * vp[2] + x);
                        valid[i] = x < x1 ? -1 : 0;
                        jx[i] = ns == 1 || !valid[i] ? 0.5 : (sx + rt_rand(px, sample, 0, 1)) / ns;
                        jy[i] = ns == 1 || !valid[i] ? 0.5 : (sy + rt_rand(px, sample, 0, 2)) / ns;
                        xs[i] = x + jx[i];
                        ys[i] = y + jy[i];
                    }
                    primary_row(&f, vp[2], vp[3], xs, ys, org, dir);
                    if (packets)
                        for (int i = 0; i < x1 - x0; i++) packet_ray(&pk, i, org[i], dir[i]);
                    if (packets) packet_trace(f.scene, valid, &pk);
                    double rgb[TILE][3], alpha[TILE], thit[TILE];
                    int drawn[TILE];
                    for (int x = x0; x < x1; x++) {
                        int i = x - x0;
                        uint32_t px = (uint32_t)(y * vp[2] + x);
                        const rt_frame *fp = &f;
                        drawn[i] = 0;
                        rt_frame fs;
                        if (f.next) { /* motion blur: the camera at the sample's time */
                            thx_camera cm;
                            camera_lerp(&sc->camera, &f.next->camera, rt_tau(&f, px, sample), &cm);
                            fs = f;
                            if (frame_camera(&fs, &cm)) continue;
                            fp = &fs;
                            primary_ray(fp, vp[2], vp[3], x + jx[i], y + jy[i], org[i], dir[i]);
                        }
                        if (packets) {
                            struct RTCRayHit h;
                            h.ray.tfar = pk.ray.tfar[i];
                            h.hit.geomID = pk.hit.geomID[i];
                            h.hit.primID = pk.hit.primID[i];
                            h.hit.u = pk.hit.u[i];
                            h.hit.v = pk.hit.v[i];
                            h.hit.Ng_x = pk.hit.Ng_x[i];
                            h.hit.Ng_y = pk.hit.Ng_y[i];
                            h.hit.Ng_z = pk.hit.Ng_z[i];
                            rt_shade_first(fp, org[i], dir[i], &h, px, sample, rgb[i], &alpha[i], &thit[i], &rays);
                        } else {
                            rt_shade(fp, org[i], dir[i], 0, 1.0, px, sample, rgb[i], &alpha[i], &thit[i], &rays);
                        }
                        drawn[i] = 1;
                    }
                    if (f.vm) { /* the field in front of each surface hit (or of the background), the row's rays together */
                        double vo[TILE][3], vd[TILE][3], vt[TILE], vc[TILE][3], T[TILE];
                        int n = 0;
                        for (int i = 0; i < x1 - x0; i++)
                            if (drawn[i]) {
                                memcpy(vo[n], org[i], sizeof vo[n]);
                                memcpy(vd[n], dir[i], sizeof vd[n]);
                                vt[n++] = thit[i];
                            }
                        rt_volume_march_n(f.vm, o->volume, f.tf, f.fld, n, (const double(*)[3])vo, (const double(*)[3])vd, vt, vc, T, &rays);
                        n = 0;
                        for (int i = 0; i < x1 - x0; i++) {
                            if (!drawn[i]) continue;
                            /* premultiplied: the volume's emission, then the surface behind it through
                               what the volume lets pass; the coverage likewise */
                            double vcov = (1 - T[n]) + T[n] * alpha[i];
                            for (int k = 0; k < 3; k++) rgb[i][k] = vcov > 0 ? (vc[n][k] + T[n] * alpha[i] * rgb[i][k]) / vcov : 0;
                            alpha[i] = vcov;
                            n++;
                        }
                    }
                    for (int i = 0; i < x1 - x0; i++) {
                        if (o->layer) { /* sort-last: each sample premultiplied, composited before they are averaged */
                            float *L = o->layer + 4 * (((size_t)(vp[1] + y) * (size_t)img->w + (size_t)(vp[0] + x0 + i)) *
                                                           (size_t)(ns * ns) + sample);
                            for (int k = 0; k < 4; k++) L[k] = !drawn[i] ? 0.0f : (float)(k < 3 ? rgb[i][k] * alpha[i] : alpha[i]);
                        }
                        if (!drawn[i]) continue;
                        for (int k = 0; k < 3; k++) acc[i][k] += rgb[i][k] * alpha[i];
                        cov[i] += alpha[i];
                    }
                }
            for (int x = x0; x < x1; x++) {
                int i = x - x0;
                double n = (double)(ns * ns);
                size_t at = (size_t)(vp[1] + y) * (size_t)img->w + (size_t)(vp[0] + x);
                if (!o->layer) pixel_over(img->rgba + 4 * at, acc[i][0] / n, acc[i][1] / n, acc[i][2] / n, cov[i] / n, sc->clear, f.bg);
                if (o->own) o->own[at] = 1;
            }
            primary += (size_t)(x1 - x0) * (size_t)(ns * ns);
        }
        if (o->progress) {
#pragma omp critical
            {
                done++;
                if (done % 16 == 0 || done == n_mine) {
                    int bar = 40 * done / n_mine;
                    fprintf(stderr, "\rtracing [%.*s%*s] %3d%%", bar, "########################################", 40 - bar, "",
                            100 * done / n_mine);
                    if (done == n_mine) fputc('\n', stderr);
                }
            }
        }
    }
    frame_free(&f);
    free(tf);
    if (stats) {
        stats->seconds = wall() - t0;
        stats->build_seconds = t1 - t0;
        stats->primary_rays = primary;
        stats->rays = rays;
        stats->builds = builds;
    }
    return THX_OK;
}

thx_status thx_raytrace_ids(thx_ctx *ctx, thx_tracer *t, const thx_scene *sc, int w, int h, int32_t *surface, int32_t *tri)
{
    thx_raytrace_opts o;
    thx_raytrace_opts_default(&o);
    t->call++;
    size_t builds = 0;
    rt_frame f;
    if (w < 1 || h < 1) return thx_error(ctx, THX_EINPUT, "ray tracer: id image %d x %d", w, h);
    thx_status st = frame_build(ctx, t, sc, &o, w, h, &f, &builds);
    if (st != THX_OK) { frame_free(&f); return st; }
    size_t rays = 0;
    /* eye rays in packets of 16 along a row where no image plane or clip plane asks for a second look */
    int packets = !f.planes && !f.any_clip;
#pragma omp parallel for schedule(dynamic) reduction(+ : rays)
    for (int y = 0; y < h; y++)
        for (int x0 = 0; x0 < w; x0 += TILE) {
            int x1 = x0 + TILE < w ? x0 + TILE : w;
            double org[TILE][3], dir[TILE][3];
            struct RTCRayHit16 pk;
            _Alignas(64) int valid[TILE]; /* (Embree reads it as one vector) */
            if (packets) {
                packet_ids_row(&f, w, h, x0, x1 - x0, y, &pk, valid);
                packet_trace(f.scene, valid, &pk);
                rays += (size_t)(x1 - x0);
            } else {
                for (int x = x0; x < x1; x++) primary_ray(&f, w, h, x + 0.5, y + 0.5, org[x - x0], dir[x - x0]);
            }
            for (int x = x0; x < x1; x++) {
                int i = x - x0;
                size_t px = (size_t)y * (size_t)w + (size_t)x;
                struct RTCRayHit rh;
                surface[px] = -1;
                tri[px] = -1;
                if (packets) {
                    if (pk.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
                    rh.hit.geomID = pk.hit.geomID[i];
                    rh.hit.primID = pk.hit.primID[i];
                    rh.hit.u = pk.hit.u[i];
                    rh.hit.v = pk.hit.v[i];
                } else if (!rt_intersect(&f, org[i], dir[i], 0, INFINITY, &rh, &rays)) {
                    continue;
                }
                size_t k;
                int kind = rt_kind(&f, rh.hit.geomID, &k);
                if (kind == RT_SURFACE) {
                    surface[px] = (int32_t)k;
                    tri[px] = (int32_t)rh.hit.primID;
                } else if (kind == RT_PLANE) {
                    surface[px] = THX_RAYTRACE_ID_PLANE;
                    tri[px] = (int32_t)k;
                } else {
                    double n[3], col[4];
                    surface[px] = THX_RAYTRACE_ID_ARROW;
                    rt_arrow_hit(&f.ar[k], rh.hit.primID, rh.hit.u, rh.hit.v, n, col, &tri[px]);
                }
            }
        }
    frame_free(&f);
    return THX_OK;
}
